//! The cycle: one thread, absolute-time sleeps on the DC-aligned cycle, one process-data
//! exchange, one CiA 402 step per axis, every cycle.
//!
//! Per cycle: sleep until the instant (`clock_nanosleep`, absolute), exchange the process data
//! (`tx_rx_dc`, pumped inline by [`exec::exchange`]: the frame I/O is this thread's own), check
//! the working counter and every drive's AL state, read each drive's inputs through its
//! resolved fields, take commands, run the set-point program, step the [`cia402::Axis`], write
//! the outputs, publish telemetry and events. After start-up nothing here allocates, locks
//! anything another thread takes, or makes a syscall other than the frame I/O and the sleep —
//! `tests/cycle_audit.rs` proves it with a counting allocator and per-thread syscall counters.
//!
//! The cycle itself takes the drives from SAFE-OP to OP (after some cycles of valid outputs),
//! and stops them in a controlled way on request, on a fault, on lost frames or when a drive
//! leaves OP: ramp (or quick stop), then disable. Ending the cycle hands the bus back to the
//! session, which takes the drives to INIT.

use super::app::{AppAxis, AppCycle, CycleApp, SetpointLimits};
use super::exec::{self, ExchangeError};
use super::io::{FrameLink, Pump};
use super::program::{ProbeEdge, RunMode, Runner, Step, Tick};
use super::record::{CycleSample, RecordTx};
use super::setpoint::Sample;
use super::startup::{ConfiguredDrive, ConfiguredIo, DriveFields, Group};
use super::telemetry::{
    AxisTelemetry, Command, CycleTelemetry, DriveTask, Event, EventKind, IO_TELEMETRY_BYTES,
    IoTelemetry, Phase, ProbeState, StopKind, StopReason, Telemetry,
};
use super::wkc::{DatagramWkc, WkcPlan};
use crate::cia402::{
    self, Axis, AxisConfig, AxisStatus, Feedback, ModeSwitchPhase, OperationMode, Output, State,
    StatusWord,
};
use crate::ec::register;
use crate::pdo;
use crate::rt::{LatencyHistogram, RtReport, RtSettings, monotonic_ns, sleep_until_ns};
use ethercrab::subdevice_group::{HasDc, SafeOp};
use ethercrab::{Command as EcCommand, MainDevice, SubDeviceState};
use std::pin::pin;
use std::time::Duration;

/// How the master matches a position actual value with the demand it answers, by SYNC0 pulse.
/// SYNC0 fires at whole multiples of the cycle in DC system time (ethercrab rounds the first
/// pulse so), so the frame that passed the reference clock at DC time `t` came after pulse
/// `t / cycle`. The demand a frame carries is taken by the drives at the next pulse; the
/// position a frame reads was sampled at the last pulse and answers the demand taken at the
/// pulse before. So the position read by a frame after pulse `s` answers the demand carried by
/// the frame after pulse `s − 2`: on time, that is the demand computed three cycles earlier
/// (computed after the exchange of cycle k, carried by the frame of cycle k+1, taken at pulse
/// k+2, reported at pulse k+3). A frame late enough to cross a pulse changes that count by one;
/// matching by pulse keeps the error free of it. A drive whose position loop adds its own
/// delay shows it as a constant part of the error at constant speed.
pub const FEEDBACK_PULSES: u64 = 2;

/// Demands remembered per axis, with the pulse after which their frame passed.
const CARRIED: usize = 4;

/// Cycles of motion in csp (the position demand changed) with a master-side following error
/// other than 0, after which a 0x60F4 that never left 0 is flagged ([`EventKind::DriveFollowingErrorStuck`]).
pub const DRIVE_FE_STUCK_CYCLES: u32 = 500;

/// Settings of the cycle.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleSettings {
    /// The cycle time.
    pub cycle: Duration,
    /// Real-time thread settings.
    pub rt: RtSettings,
    /// Cycles of valid outputs in SAFE-OP, counted with SYNC0 running on every drive, before OP
    /// is requested (\[REC\] 10: the MR-J4-TM manual §1.4.2 (7) asks for DC synchronisation
    /// and valid command values before OP and gives no count).
    pub safeop_cycles: u32,
    /// How long the drives may take to reach OP.
    pub op_timeout: Duration,
    /// Consecutive cycles without a reply after which the axes are stopped in a controlled
    /// way (the ramp runs on the frames that get through; until then every axis holds its
    /// set-point).
    pub lost_before_stop: u32,
    /// Consecutive cycles without a reply after which the segment counts as lost (cable pull
    /// detected: an event, and the axes are stopped). Three by default.
    pub segment_lost_after: u32,
    /// How long the segment may stay silent before the cycle ends: the drives' own
    /// watchdogs have disabled them by then, and only a re-start brings them back.
    pub segment_gone_after: Duration,
    /// Consecutive cycles with a wrong working counter before the axes are stopped.
    pub wkc_errors_before_stop: u32,
    /// Time to ramp a moving axis to standstill in a controlled stop.
    pub stop_ramp: Duration,
    /// Longest a controlled stop may take before the drives are disabled regardless.
    pub stop_timeout: Duration,
    /// How late, as a fraction of the cycle, the reply may arrive before the cycle counts it
    /// as lost.
    pub reply_budget: f64,
    /// Record the [`Timing`] histograms and the report's lost/overrun counts in steady state
    /// only: from the cycle after every drive reached OP to the cycle that takes the stop
    /// request. The jitter harness measures steady state; start-up cycles (extra frames for
    /// the OP request) would blur it. Off by default: every cycle is recorded.
    pub steady_timing_only: bool,
    /// Distribute the reference clock's time to the other clocks every cycle (the FRMW of
    /// `tx_rx_dc`): the drift compensation that keeps the SYNC0 pulses of all drives together.
    /// On by default; off only to show what it does (the frame then reads the reference
    /// clock without writing the others, `tests/faults_master.rs`).
    pub drift_compensation: bool,
}

impl CycleSettings {
    /// Defaults for a cycle time.
    pub fn new(cycle: Duration) -> Self {
        Self {
            cycle,
            rt: RtSettings::default(),
            safeop_cycles: 10,
            op_timeout: Duration::from_secs(5),
            lost_before_stop: 3,
            segment_lost_after: 3,
            segment_gone_after: Duration::from_millis(200),
            wkc_errors_before_stop: 3,
            stop_ramp: Duration::from_millis(200),
            stop_timeout: Duration::from_secs(3),
            reply_budget: 0.8,
            steady_timing_only: false,
            drift_compensation: true,
        }
    }
}

/// Hooks the cycle thread calls, for instrumentation (the audit tests count allocations and
/// syscalls between them).
pub trait CycleHooks: Sync {
    /// Called on the cycle thread once every drive is in OP (steady state begins).
    fn steady_begin(&self) {}
    /// Called on the cycle thread when a stop command arrives or the cycle ends.
    fn steady_end(&self) {}
}

/// The cycle's ends of the lock-free channels.
pub struct CycleIo {
    /// Commands in.
    pub commands: rtrb::Consumer<Command>,
    /// Events out.
    pub events: rtrb::Producer<Event>,
    /// Telemetry out.
    pub telemetry: triple_buffer::Input<Telemetry>,
    /// Where the cycle reports what its real-time set-up got, before the loop starts.
    pub rt_report: Option<std::sync::mpsc::Sender<RtReport>>,
    /// Re-starts so far (published in the telemetry).
    pub restarts: u32,
    /// This run is a re-start: [`Self::restarts`] counts up once every drive is in OP.
    pub restarting: bool,
}

/// The supervisory ends of the channels.
pub struct SupervisorIo {
    /// Commands to the cycle.
    pub commands: rtrb::Producer<Command>,
    /// Events from the cycle.
    pub events: rtrb::Consumer<Event>,
    /// Telemetry from the cycle.
    pub telemetry: triple_buffer::Output<Telemetry>,
}

/// Create both ends for `axes` axes and `io` I/O devices.
pub fn channels(axes: usize, io: usize) -> (CycleIo, SupervisorIo) {
    let (ctx, crx) = rtrb::RingBuffer::new(256);
    let (etx, erx) = rtrb::RingBuffer::new(4096);
    let initial = Telemetry {
        cycle: CycleTelemetry::default(),
        axes: vec![AxisTelemetry::default(); axes],
        io: vec![IoTelemetry::default(); io],
    };
    let (tin, tout) = triple_buffer::TripleBuffer::new(&initial).split();
    (
        CycleIo {
            commands: crx,
            events: etx,
            telemetry: tin,
            rt_report: None,
            restarts: 0,
            restarting: false,
        },
        SupervisorIo {
            commands: ctx,
            events: erx,
            telemetry: tout,
        },
    )
}

/// How the cycle ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum CycleEnd {
    /// Stopped on request; every axis disabled.
    Stopped,
    /// The drives did not reach OP: this axis (its raw AL state).
    OpFailed {
        /// Position of the first device not in OP.
        device: u16,
        /// AL state register value.
        al_state: u8,
    },
    /// The segment stopped answering for longer than
    /// [`CycleSettings::segment_gone_after`].
    SegmentLost,
    /// The link failed.
    LinkFailed,
    /// A drive left OP on its own; every axis was stopped and disabled, the others taken to
    /// PRE-OP.
    DriveLeftOp {
        /// Position of the device (a drive or an I/O device).
        device: u16,
        /// Its AL status (0x0130) when seen.
        al_state: u8,
        /// Its AL status code (0x0134), if it could be read.
        code: Option<u16>,
    },
    /// A re-start was requested; every axis was stopped and disabled, the drives taken to
    /// PRE-OP.
    Restart,
}

/// Timing histograms of a cycle run.
#[derive(Debug, Clone, Default)]
pub struct Timing {
    /// Wake-up latency against the intended instant.
    pub wake_latency: LatencyHistogram,
    /// Period between wake-ups.
    pub period: LatencyHistogram,
    /// Frame round trip (send → reply handed to ethercrab).
    pub exchange: LatencyHistogram,
    /// Time the thread was awake per cycle (exchange + computation).
    pub busy: LatencyHistogram,
}

/// What a cycle run produced.
#[derive(Debug, Clone)]
pub struct CycleReport {
    /// How it ended.
    pub end: CycleEnd,
    /// Cycles run.
    pub cycles: u64,
    /// Cycles without a reply (in steady state only with
    /// [`CycleSettings::steady_timing_only`]).
    pub lost: u64,
    /// Cycles whose wake-up was more than one cycle late (in steady state only with
    /// [`CycleSettings::steady_timing_only`]).
    pub overruns: u64,
    /// The histograms.
    pub timing: Timing,
    /// What the RT set-up got.
    pub rt: RtReport,
    /// Why the axes were first stopped (the event that ended the run), if the cycle stopped
    /// them; `Requested` for a stop that was asked for.
    pub first_stop: Option<StopReason>,
    /// Per axis: the largest |following error| while enabled in csp, as the master computes it.
    pub max_following_error: Vec<i64>,
    /// Per axis: the largest |0x60F4| the drive reported meanwhile (`None`: not mapped).
    pub max_following_error_drive: Vec<Option<i64>>,
    /// Per axis: 0x60F4 stayed 0 while the axis moved ([`EventKind::DriveFollowingErrorStuck`]).
    pub following_error_drive_stuck: Vec<bool>,
    /// Per axis: the modes it ran in while enabled, in order (hm for a home step).
    pub modes_run: Vec<Vec<OperationMode>>,
    /// Per axis: the touch-probe latches, in order: (probe, edge, position in counts).
    pub probe_latches: Vec<Vec<(u8, ProbeEdge, i64)>>,
    /// Per axis: the largest change of the streamed set-point from one cycle to the next while
    /// the drive was enabled, for each kind (across mode switches too: a jump shows here).
    pub max_setpoint_step: Vec<SetpointSteps>,
    /// Per axis: the states it went through, in order (consecutive duplicates removed).
    pub states: Vec<Vec<State>>,
    /// The frames of the run (the IgH `master` command's figures).
    pub frames: FrameStats,
}

/// The frames of a run of the cycle, in total (divide by [`FrameStats::seconds`] for rates).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Frames sent (first transmissions: cyclic frames, AL requests, mailbox polls riding along).
    pub sent: u64,
    /// Replies received.
    pub answered: u64,
    /// Retransmissions of frames that got no reply in time.
    pub retransmitted: u64,
    /// Cycles whose frames got no reply at all.
    pub lost: u64,
    /// Cycles whose reply came after the cycle's budget (counted as lost cycles too).
    pub late: u64,
    /// Replies with a wrong working counter.
    pub wrong_wkc: u64,
    /// How long the run of the cycle lasted, s.
    pub seconds: f64,
}

/// Largest cycle-to-cycle changes of the set-points sent to one axis while it was enabled.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SetpointSteps {
    /// Target position (0x607A), position units, while in csp.
    pub position: i64,
    /// Target velocity (0x60FF), drive velocity units, while in csv.
    pub velocity: i64,
    /// Target torque (0x6071), drive torque units, while in cst.
    pub torque: i64,
    /// Cycle numbers at which each maximum happened (position, velocity, torque).
    pub at_cycle: [u64; 3],
}

/// Controlled-stop progress of one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stopping {
    No,
    /// Ramping the set-point to standstill from this sample, started at this good cycle
    /// (the ramp's clock, like the program's, runs on cycles with a reply) and at this cycle
    /// (for the timeout).
    Ramp {
        from: Sample,
        at: u64,
        since: u64,
    },
    /// Quick stop requested at this cycle.
    Quick {
        at: u64,
    },
    /// Disable requested.
    Disabling,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ProgramState {
    Idle,
    Pending,
    Running,
}

/// **\[REC\]** How long a program's home step may take before it counts as failed: two
/// minutes (a search over a long axis at creep speed), whatever the cycle time.
const HOMING_TIMEOUT: Duration = Duration::from_secs(120);

/// Where a program's `home` step is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HomeRun {
    /// No home step running.
    Idle,
    /// hm requested; waiting for the drive to confirm it.
    ToHm,
    /// Homing (controlword bit 4 through [`cia402::Homing`]).
    Running { method: i8 },
    /// Homed; back to the program's mode requested.
    Back,
}

/// A pp, pv or tq step the drive runs (the step is the runner's step `index`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DriveRun {
    /// None running.
    Idle,
    /// pp: `given` targets handed to the handshake engine; `settled` cycles with nothing in
    /// flight; `reached` the drive reported the targets given so far reached.
    Pp {
        index: usize,
        given: usize,
        settled: u32,
        reached: bool,
        since: u64,
    },
    /// pv or tq: the target went out at good cycle `since` (`None`: the axis is not yet
    /// taking it).
    Profile { index: usize, since: Option<u64> },
}

/// What the application's callback ([`AppAxis`]) asked of an axis in one cycle, with a
/// homing a command asked for.
#[derive(Debug, Clone, Copy, Default)]
struct Requests {
    setpoint: Option<f64>,
    mode: Option<RunMode>,
    home: Option<i8>,
    pp: Option<(f64, bool, bool)>,
    probe: Option<(u8, ProbeEdge)>,
}

impl Requests {
    /// The callback's requests of this cycle.
    fn of(app: &AppAxis) -> Self {
        Self {
            setpoint: app.setpoint,
            mode: app.mode_request,
            home: app.home_request,
            pp: app.pp_request,
            probe: app.probe_request,
        }
    }
}

/// One touch probe as the cycle drives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ProbeArm {
    /// Not armed.
    Off,
    /// The probe's function bits go 0 for one cycle (a drive latches again only after its
    /// sample bit was cleared), then it is armed.
    Rearm(ProbeEdge),
    /// Armed on `edge`; `clear` once the drive's stored bit was seen 0 since (a bit still
    /// set from an earlier latch is not this one).
    Armed { edge: ProbeEdge, clear: bool },
    /// Latched and reported; the drive keeps the value (first-event mode).
    Latched { edge: ProbeEdge, position: i64 },
}

impl ProbeArm {
    /// This probe's bits of 0x60B8 (`base` 0 for probe 1, 8 for probe 2): enable, first event,
    /// the probe input, the edge's sample bit.
    fn function_bits(self, base: u16) -> u16 {
        let edge = match self {
            Self::Off | Self::Rearm(_) => return 0,
            Self::Armed { edge, .. } | Self::Latched { edge, .. } => edge,
        };
        let sample = match edge {
            ProbeEdge::Rising => 1 << 4,
            ProbeEdge::Falling => 1 << 5,
        };
        (1 | sample) << base
    }
}

/// **\[REC\]** How long a pp step may take, and a pv step beyond its own time, before it
/// counts as failed (the drive never reported its target reached): two minutes, as a homing.
const DRIVE_STEP_TIMEOUT_S: f64 = 120.0;

/// **\[REC\]** The longest a tq step waits, beyond twice its ramp down, for the drive to
/// report the torque back near 0 (2 % of the step's torque).
const TQ_SETTLE_MAX_S: f64 = 1.0;

/// Touch-probe latches a run keeps per axis (more are still reported as events).
const PROBE_LATCHES: usize = 16;

/// **\[REC\]** Cycles with nothing in flight and statusword bit 10 set before a pp target
/// counts as reached: the round trip of the last handshake (as [`cia402::profile_velocity`]'s
/// settling).
const PP_SETTLE_CYCLES: u32 = 3;

/// Where the drives stand on the way to OP.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OpState {
    /// Valid outputs go out in SAFE-OP; OP not requested yet.
    SafeOp,
    /// OP requested at this cycle.
    Requested { at: u64 },
    /// Every device has been in OP.
    AllOp,
}

/// Where the run stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum RunPhase {
    /// Cycling: commands and programs drive the axes.
    Running,
    /// Stopping the axes; once every axis is disabled, PRE-OP is requested (at this cycle).
    Ending { preop_requested_at: Option<u64> },
}

/// Which cycles the timing histograms and the report's counts cover (see
/// [`CycleSettings::steady_timing_only`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Window {
    /// Not yet (steady state has not begun).
    NotYet,
    /// From the next cycle on.
    OpensNext,
    /// This cycle is recorded.
    Open,
    /// This cycle is recorded, the next ones not.
    ClosesAfter,
    /// No more.
    Closed,
}

impl Window {
    fn recording(self) -> bool {
        matches!(self, Self::Open | Self::ClosesAfter)
    }
}

/// Events out of the cycle, stamped with the cycle number; remembers why the axes were first
/// stopped.
struct Emitter<'a> {
    out: &'a mut rtrb::Producer<Event>,
    cycle: u64,
    first_stop: Option<StopReason>,
}

impl Emitter<'_> {
    fn emit(&mut self, kind: EventKind) {
        if let EventKind::Stopping { reason } = kind
            && self.first_stop.is_none()
        {
            self.first_stop = Some(reason);
        }
        let _ = self.out.push(Event {
            cycle: self.cycle,
            time_ns: monotonic_ns(),
            kind,
        });
    }
}

/// What every axis's step of one cycle shares.
#[derive(Debug, Clone, Copy)]
struct StepContext {
    /// The cycle number.
    cycle: u64,
    /// Cycles with a reply so far: the clock of the programs and the stop ramps.
    tick: u64,
    /// The cycle time in seconds.
    dt: f64,
    /// The SYNC0 pulse the frame of this cycle came after (see [`FEEDBACK_PULSES`]).
    pulse: u64,
    /// The run is stopping.
    ending: bool,
    /// Whether any axis was energised or running a program as of the last cycle.
    any_energised_before: bool,
    stop_ramp_cycles: u64,
    stop_timeout_cycles: u64,
}

/// One axis in the cycle: its engine, its place in the process image, its program and what
/// the cycle remembers of it.
struct AxisRt {
    /// Position on the segment (index in the group).
    sub: usize,
    axis: Axis,
    fields: DriveFields,
    velocity_unit: f64,
    runner: Runner,
    program: ProgramState,
    /// The home step's homing engine and where the step is.
    homing: cia402::Homing,
    home: HomeRun,
    /// How the drive's manual names a failed homing ([`cia402::DriveCaps::homing_failure`]).
    homing_failure: &'static str,
    /// The pp/pv/tq step the drive runs, and the engines of those modes.
    drive_run: DriveRun,
    pp: cia402::ProfilePosition,
    pv: cia402::ProfileVelocity,
    tq: cia402::ProfileTorque,
    /// The homing the application started (its method), what it asked stands as, and pp
    /// targets of the application in flight (with cycles settled, as a pp step counts them).
    home_by_app: Option<i8>,
    app_task: DriveTask,
    app_pp: Option<u32>,
    /// A homing a command ([`Command::Home`]) asked for since the last cycle: taken as the
    /// application's request is (pp targets and probes of commands are taken at once).
    home_commanded: Option<i8>,
    /// Touch probes 1 and 2.
    probes: [ProbeArm; 2],
    /// 0x60B9 and 0x60BA–0x60BD as read this cycle (0 where not mapped).
    probe_status: u16,
    probe_positions: [i32; 4],
    /// 0x60B8 to write (once a probe was armed).
    probe_function: Option<u16>,
    /// Set-point held when no program runs (position/velocity/torque by mode).
    hold: Sample,
    mode: RunMode,
    requested_mode: Option<RunMode>,
    fe_limit: Option<u32>,
    /// 0x60F4 was seen other than 0 while the axis moved in csp.
    fe_drive_alive: bool,
    /// The master judged the following error in this cycle's step (energised in csp): the
    /// recording shows it only then. Cleared once recorded.
    fe_judged: bool,
    /// Cycles of motion in csp with 0x60F4 at 0 while it was never seen otherwise.
    fe_drive_zero_cycles: u32,
    stopping: Stopping,
    pos_raw: i32,
    pos: i64,
    pos_valid: bool,
    /// (pulse, demand carried) of the last frames with a reply, see [`FEEDBACK_PULSES`].
    carried: [(u64, i64); CARRIED],
    carried_next: usize,
    /// The demand computed in the last cycle: the next frame carries it.
    last_demand: Option<i64>,
    counter: u8,
    al_state: u8,
    tel: AxisTelemetry,
    last_state: Option<State>,
    states: Vec<State>,
    modes_run: Vec<OperationMode>,
    /// The touch-probe latches of the run (at most [`PROBE_LATCHES`] kept).
    latches: Vec<(u8, ProbeEdge, i64)>,
    steps: SetpointSteps,
    last_out: Option<(i32, i32, i16)>,
    /// This cycle's inputs, read before the application runs.
    fb: Option<Feedback>,
    /// What the application's set-points must keep.
    limits: SetpointLimits,
}

impl AxisRt {
    /// The axis of drive `d` (set-up: allocations allowed), or `None` if its engine cannot be
    /// built.
    fn new(d: &ConfiguredDrive, cycle: Duration) -> Option<Self> {
        let caps = d.profile.caps;
        let initial = OperationMode::from_i8(d.setup.mode.code());
        let axis = Axis::new(caps, AxisConfig::for_cycle_time(&caps, cycle, initial))
            .or_else(|_| {
                let csp = OperationMode::CyclicSyncPosition;
                Axis::new(caps, AxisConfig::for_cycle_time(&caps, cycle, csp))
            })
            .ok()?;
        Some(Self {
            sub: usize::from(d.info.position),
            axis,
            fields: d.fields.clone(),
            velocity_unit: d.profile.units.velocity_position_per_s(),
            runner: Runner::new(d.setup.program.clone(), d.setup.mode),
            program: ProgramState::Idle,
            homing: cia402::Homing::new(cia402::HomingConfig {
                timeout_cycles: u32::try_from(HOMING_TIMEOUT.as_nanos() / cycle.as_nanos().max(1))
                    .unwrap_or(u32::MAX),
                ..cia402::HomingConfig::default()
            }),
            home: HomeRun::Idle,
            homing_failure: caps.homing_failure,
            drive_run: DriveRun::Idle,
            pp: cia402::ProfilePosition::default(),
            pv: cia402::ProfileVelocity::new(false),
            tq: cia402::ProfileTorque::new(),
            home_by_app: None,
            app_task: DriveTask::Idle,
            home_commanded: None,
            app_pp: None,
            probes: [ProbeArm::Off; 2],
            probe_status: 0,
            probe_positions: [0; 4],
            probe_function: None,
            hold: Sample::default(),
            mode: d.setup.mode,
            requested_mode: None,
            fe_limit: d.setup.following_error_limit,
            fe_drive_alive: false,
            fe_judged: false,
            fe_drive_zero_cycles: 0,
            stopping: Stopping::No,
            pos_raw: 0,
            pos: 0,
            pos_valid: false,
            carried: [(u64::MAX, 0); CARRIED],
            carried_next: 0,
            last_demand: None,
            counter: 0,
            al_state: 0,
            tel: AxisTelemetry::default(),
            last_state: None,
            states: Vec::with_capacity(64),
            modes_run: Vec::with_capacity(8),
            latches: Vec::with_capacity(PROBE_LATCHES),
            steps: SetpointSteps::default(),
            last_out: None,
            fb: None,
            limits: d.setup.limits,
        })
    }

    /// Outputs that carry fixed values from the first cycle on, and Disable voltage.
    fn initial_outputs(&self, out: &mut [u8]) {
        for (f, v) in &self.fields.held_outputs {
            let _ = f.write_raw(out, *v);
        }
        for (f, v) in &self.fields.output_defaults {
            pdo::axis::write(Some(*f), out, *v);
        }
        self.fields.axis.write_disable_voltage(out);
    }

    /// Advance the drive's cycle counter (if mapped) in `out`: one per cycle, as the drive
    /// expects, also on a cycle whose outputs are otherwise unchanged.
    fn count(&mut self, out: &mut [u8]) {
        if let Some((c, _)) = &self.fields.counter {
            self.counter = self.counter.wrapping_add(1);
            pdo::axis::write(Some(*c), out, i64::from(self.counter));
        }
    }

    /// Below OP nothing of the drive is judged: a slave may serve stale inputs until OP (a mode
    /// display of 0, a statusword of 0), and it should not act on the outputs. They stay safe
    /// all the same, for a slave that does: Disable voltage.
    fn below_op(&mut self, out: &mut [u8]) {
        self.fields.axis.write_disable_voltage(out);
        self.count(out);
        self.tel.state = None;
        self.tel.al_state = self.al_state;
    }

    /// Read this cycle's inputs (the frame just exchanged carried the demand of the last
    /// cycle): the feedback for the engine, the unwrapped position and the telemetry.
    fn read_inputs(&mut self, inputs: &[u8], pulse: u64) -> Feedback {
        if let Some(d) = self.last_demand {
            self.carried[self.carried_next] = (pulse, d);
            self.carried_next = (self.carried_next + 1) % CARRIED;
        }
        let pf = &self.fields.probe;
        self.probe_status = pdo::axis::read(pf.status, inputs).unwrap_or(0) as u16;
        for (v, f) in self.probe_positions.iter_mut().zip(pf.positions) {
            *v = pdo::axis::read(f, inputs).unwrap_or(0) as i32;
        }
        let b = &self.fields.axis;
        let fb = b.feedback(inputs);
        if let Some(p) = fb.position {
            if self.pos_valid {
                self.pos += i64::from(p.wrapping_sub(self.pos_raw));
            } else {
                self.pos = i64::from(p);
                self.pos_valid = true;
            }
            self.pos_raw = p;
        }
        let t = &mut self.tel;
        t.statusword = fb.statusword.raw();
        t.position_actual = self.pos;
        t.velocity_actual = fb.velocity.unwrap_or(0);
        t.torque_actual = fb.torque.unwrap_or(0);
        t.mode_display = fb.mode_display.map_or(0, OperationMode::as_i8);
        t.error_code = fb.error_code.map_or(0, |e| e.0);
        t.following_error_drive = b.following_error(inputs);
        fb
    }

    /// The actual values as a set-point sample.
    fn actual(&self) -> Sample {
        Sample {
            pos: self.pos as f64,
            vel: self.tel.velocity_actual as f64 * self.velocity_unit,
            acc: 0.0,
            torque: f64::from(self.tel.torque_actual),
            done: false,
        }
    }

    /// One cycle with a reply in OP: inputs → program and stop ramp → engine → outputs, with
    /// the engine's events, the set-point statistics, the following error and the telemetry.
    fn step(
        &mut self,
        i: usize,
        fb: Feedback,
        ctx: &StepContext,
        ev: &mut Emitter,
        app: Option<&AppAxis>,
    ) -> Output {
        let actual = self.actual();
        let st = self.axis.status();
        let enabled = st.state == Some(State::OperationEnabled) && st.streaming;
        if self.program == ProgramState::Pending && enabled {
            self.runner.seed(actual);
            self.program = ProgramState::Running;
            ev.emit(EventKind::ProgramStep {
                axis: i as u16,
                step: self.runner.step_index() as u16,
            });
        }
        let mut sp = self.stop_setpoint(&st, enabled, ctx);
        if self.stopping == Stopping::No && self.program == ProgramState::Running && enabled {
            if let Some(s) = self.program_setpoint(i, &st, actual, ctx, ev) {
                sp = s;
            }
        }
        let mut req = app.map(Requests::of).unwrap_or_default();
        req.home = req.home.or(self.home_commanded.take());
        if let Some(s) = self.app_requests(i, &req, &st, enabled, ctx, ev) {
            sp = s;
        }
        if let Some((probe, edge)) = req.probe
            && let Err(why) = self.arm_probe(probe, edge)
        {
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why,
            });
        }
        if enabled {
            self.command(sp, &st);
            let m = st.active_mode;
            if self.modes_run.last() != Some(&m) && self.modes_run.len() < self.modes_run.capacity()
            {
                self.modes_run.push(m);
            }
        } else if self.stopping == Stopping::No {
            // Not enabled: track the actual values so enabling starts without a jump.
            self.hold = actual;
        }
        if matches!(self.home, HomeRun::Running { .. }) {
            self.homing.step(&mut self.axis, fb.statusword);
        }
        self.profile_mode(i, fb.statusword, actual, ctx, ev);
        self.probe(i, ev);
        self.tel.task = self.app_task;
        for (t, p) in self.tel.probes.iter_mut().zip(self.probes) {
            *t = match p {
                ProbeArm::Off => ProbeState::Off,
                ProbeArm::Rearm(edge) | ProbeArm::Armed { edge, .. } => ProbeState::Armed(edge),
                ProbeArm::Latched { edge, position } => ProbeState::Latched { edge, position },
            };
        }
        let out = self.axis.step(&fb);
        self.engine_events(i, actual, ctx, ev);
        self.record_steps(&out, enabled, ctx.cycle);
        self.follow(i, &out, ctx, ev);
        out
    }

    /// What the application asked of the axis this cycle: a mode switch (through the engine),
    /// and a set-point, taken in Operation enabled with no program running and within the
    /// limits; a set-point beyond them stops the axis with a ramp and names the limit.
    fn app_requests(
        &mut self,
        i: usize,
        app: &Requests,
        st: &AxisStatus,
        enabled: bool,
        ctx: &StepContext,
        ev: &mut Emitter,
    ) -> Option<Sample> {
        if let Some(m) = app.mode
            && st.active_mode.as_i8() != m.code()
            && st.mode_switch == ModeSwitchPhase::Idle
            && self
                .axis
                .request_mode(OperationMode::from_i8(m.code()))
                .is_err()
        {
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why: "the application's mode switch was refused",
            });
        }
        if let Some(sp) = self.app_home(i, app.home, st, enabled, ctx, ev) {
            return Some(sp);
        }
        let free =
            enabled && self.stopping == Stopping::No && self.program != ProgramState::Running;
        let mode = RunMode::from_code(st.active_mode.as_i8()).unwrap_or(self.mode);
        if let Some((target, relative, immediate)) = app.pp
            && let Err((report, why)) = self.take_pp(target, relative, immediate)
            && report
        {
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why,
            });
        }
        let v = app.setpoint?;
        if !free {
            return None;
        }
        match self
            .limits
            .check(mode, v, (self.hold.pos, self.hold.vel), ctx.dt)
        {
            Ok((vel, acc)) => {
                let sp = match mode {
                    RunMode::Csp => Sample {
                        pos: v,
                        vel,
                        acc,
                        ..self.hold
                    },
                    RunMode::Csv => Sample {
                        pos: self.hold.pos + v * ctx.dt,
                        vel: v,
                        acc,
                        ..self.hold
                    },
                    RunMode::Cst => Sample {
                        torque: v,
                        ..self.hold
                    },
                    // The drive generates the motion in the profile modes: pv and tq take the
                    // target and ramp to it; pp targets come through `request_pp`.
                    RunMode::Pv => {
                        self.pv.set_target(self.drive_velocity(v));
                        return None;
                    }
                    RunMode::Tq => {
                        self.tq.set_target(drive_torque(v));
                        return None;
                    }
                    RunMode::Pp => return None,
                };
                self.hold = sp;
                Some(sp)
            }
            Err((limit, value, max)) => {
                ev.emit(EventKind::SetpointLimit {
                    axis: i as u16,
                    limit,
                    value,
                    max,
                });
                self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                None
            }
        }
    }

    /// A pp target of the application or a command, handed to the handshake engine: taken in
    /// pp, in Operation enabled with no program, stop or pp step running. `Err((report, why))`
    /// when not taken; `report` is false for "not now" (the callback may ask every cycle).
    fn take_pp(
        &mut self,
        target: f64,
        relative: bool,
        immediate: bool,
    ) -> Result<(), (bool, &'static str)> {
        let st = self.axis.status();
        let enabled = st.state == Some(State::OperationEnabled) && st.streaming;
        let mode = RunMode::from_code(st.active_mode.as_i8()).unwrap_or(self.mode);
        if !enabled || self.stopping != Stopping::No {
            return Err((false, "pp target refused: the axis is not enabled"));
        }
        if self.program == ProgramState::Running || self.drive_run != DriveRun::Idle {
            return Err((false, "pp target refused: a program runs on the axis"));
        }
        if mode != RunMode::Pp {
            return Err((false, "pp target refused: the axis is not in pp"));
        }
        if !(target.is_finite() && target.abs() <= f64::from(i32::MAX)) {
            return Err((
                true,
                "pp target refused: not a finite position within ±2^31 counts",
            ));
        }
        if let Some(range) = self.axis.caps().pp_target_range
            && !range.contains(target.round() as i64)
        {
            return Err((
                true,
                "pp target refused: beyond the range the drive's manual gives for 0x607A in pp",
            ));
        }
        self.pp.set_halt(false);
        let sp = cia402::SetPoint {
            target: target.round() as i32,
            relative,
            immediate,
        };
        if self.pp.push(sp).is_err() {
            return Err((true, "pp target refused: the queue of targets is full"));
        }
        self.app_pp = Some(0);
        self.app_task = DriveTask::Positioning { queued: 1 };
        Ok(())
    }

    /// The homing the application asked for ([`AppAxis::request_home`]): started in
    /// Operation enabled with no program or homing running, then run as a program's home step
    /// is ([`AxisRt::home_step`]); while it runs the held set-point follows the actual one
    /// (returned). Its end, or a stop that cut it short, is what [`AppAxis::task`] says.
    fn app_home(
        &mut self,
        i: usize,
        request: Option<i8>,
        st: &AxisStatus,
        enabled: bool,
        ctx: &StepContext,
        ev: &mut Emitter,
    ) -> Option<Sample> {
        let actual = self.actual();
        let method = match (self.home_by_app, request) {
            (Some(m), _) if self.home == HomeRun::Idle => {
                // Cut short (a stop, a disable, a fault) since the last cycle.
                self.home_by_app = None;
                self.app_task = DriveTask::HomingFailed { method: m };
                return None;
            }
            (Some(m), _) => m,
            (None, Some(m))
                if enabled
                    && self.stopping == Stopping::No
                    && self.program != ProgramState::Running
                    && self.home == HomeRun::Idle =>
            {
                self.home_by_app = Some(m);
                self.app_task = DriveTask::Homing { method: m };
                m
            }
            _ => return None,
        };
        let was_back = self.home == HomeRun::Back;
        self.home_step(i, method, st, actual, ctx, ev);
        if self.home == HomeRun::Idle {
            self.home_by_app = None;
            self.app_task = if was_back {
                DriveTask::Homed { method }
            } else {
                DriveTask::HomingFailed { method }
            };
        }
        self.hold = actual;
        Some(actual)
    }

    /// The set-point of a controlled stop (ramp to standstill, or waiting out a quick stop),
    /// or the one held.
    fn stop_setpoint(&mut self, st: &AxisStatus, enabled: bool, ctx: &StepContext) -> Sample {
        match self.stopping {
            Stopping::Ramp { from, at, since } => {
                let k = ctx.tick.saturating_sub(at) as f64 / ctx.stop_ramp_cycles as f64;
                // In pp and pv the drive brakes on its own deceleration (halt, target 0),
                // which may take longer than the master's ramp: disable once it stands still
                // (`supervise_stop` still disables at the stop timeout).
                let drive_brakes = RunMode::from_code(st.active_mode.as_i8())
                    .is_some_and(|m| matches!(m, RunMode::Pp | RunMode::Pv));
                let braking = enabled
                    && drive_brakes
                    && !st.standstill
                    && ctx.cycle.saturating_sub(since) <= ctx.stop_timeout_cycles;
                let sp = if (k >= 1.0 && !braking) || !enabled {
                    self.axis.request_disable();
                    self.stopping = Stopping::Disabling;
                    Sample {
                        vel: 0.0,
                        torque: 0.0,
                        ..from
                    }
                } else {
                    // Linear velocity (and torque) ramp to zero; position integrates.
                    let t = ctx.tick.saturating_sub(at) as f64 * ctx.dt;
                    let total = ctx.stop_ramp_cycles as f64 * ctx.dt;
                    Sample {
                        pos: from.pos + from.vel * (t - t * t / (2.0 * total)),
                        vel: from.vel * (1.0 - k),
                        acc: 0.0,
                        torque: from.torque * (1.0 - k),
                        done: false,
                    }
                };
                self.hold = sp;
                sp
            }
            Stopping::Quick { at } => {
                // Disable once the quick stop has run: the drive left Quick stop active
                // (option codes ending in Switch on disabled), or stands still in it.
                let in_qs = st.state == Some(State::QuickStopActive);
                let done = ctx.cycle - at > 2 && (!in_qs || st.standstill);
                if done || ctx.cycle - at > ctx.stop_timeout_cycles {
                    self.axis.request_disable();
                    self.stopping = Stopping::Disabling;
                }
                self.hold
            }
            Stopping::Disabling | Stopping::No => self.hold,
        }
    }

    /// One tick of the running program: its set-point (`None`: hold), a mode switch it asks
    /// for, or its end.
    fn program_setpoint(
        &mut self,
        i: usize,
        st: &AxisStatus,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut Emitter,
    ) -> Option<Sample> {
        let mut sp = None;
        match self.runner.tick(ctx.tick as f64 * ctx.dt) {
            Tick::Setpoint(s) => {
                sp = Some(s);
                self.hold = s;
            }
            Tick::SwitchMode(m) => {
                let idle = st.mode_switch == ModeSwitchPhase::Idle;
                if idle && st.active_mode.as_i8() == m.code() {
                    // Already in that mode (a run begins by asking for its start mode): no
                    // switch, no event; go on at once.
                    self.requested_mode = None;
                    self.runner.mode_switched(actual);
                } else if idle {
                    // Nothing under way (also when an earlier request of this run was cut
                    // short): ask for it.
                    self.requested_mode = Some(m);
                    if self
                        .axis
                        .request_mode(OperationMode::from_i8(m.code()))
                        .is_err()
                    {
                        self.requested_mode = None;
                        ev.emit(EventKind::CommandRefused {
                            axis: i as u16,
                            why: "the program's mode switch was refused",
                        });
                        self.program = ProgramState::Idle;
                    }
                }
                // Else a switch is under way: its ModeSwitched event (or the next look at the
                // active mode) lets the program go on.
            }
            Tick::Finished(s) => {
                sp = Some(s);
                self.hold = s;
                self.program = ProgramState::Idle;
                ev.emit(EventKind::ProgramDone { axis: i as u16 });
            }
            Tick::Drive { index } => {
                if self.drive_run == DriveRun::Idle {
                    self.drive_run = match self.runner.steps().get(index) {
                        Some(Step::Pp { .. }) => {
                            self.pp.set_halt(false);
                            DriveRun::Pp {
                                index,
                                given: 0,
                                settled: 0,
                                reached: false,
                                since: ctx.tick,
                            }
                        }
                        _ => DriveRun::Profile { index, since: None },
                    };
                }
                self.hold = actual;
                sp = Some(actual);
            }
            Tick::Probe { probe, edge, hold } => {
                if let Some(p) = self.probes.get_mut(usize::from(probe).saturating_sub(1)) {
                    *p = ProbeArm::Rearm(edge);
                }
                sp = Some(hold);
                self.hold = hold;
            }
            Tick::ProbeWait {
                probe,
                setpoint,
                expired,
            } => {
                sp = Some(setpoint);
                self.hold = setpoint;
                let latched = matches!(
                    self.probes.get(usize::from(probe).saturating_sub(1)),
                    Some(ProbeArm::Latched { .. })
                );
                if latched {
                    self.runner.probe_latched();
                } else if expired {
                    self.program = ProgramState::Idle;
                    let seconds = match self.runner.steps().get(self.runner.step_index()) {
                        Some(&Step::ProbeWait { seconds, .. }) => seconds,
                        _ => 0.0,
                    };
                    ev.emit(EventKind::ProbeNotLatched {
                        axis: i as u16,
                        probe,
                        seconds,
                    });
                    ev.emit(EventKind::Stopping {
                        reason: StopReason::ProbeNotLatched {
                            axis: i as u16,
                            probe,
                        },
                    });
                    // This axis stops; the run then stops the others.
                    self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                }
            }
            Tick::Home { method } => {
                // Homing moves the drive on its own and redefines its position: the held
                // set-point follows the actual one, so nothing from before the home is ever
                // commanded after it.
                self.home_step(i, method, st, actual, ctx, ev);
                self.hold = actual;
                sp = Some(actual);
            }
        }
        let idx = self.runner.step_index() as u16;
        if idx != self.tel.program_step {
            ev.emit(EventKind::ProgramStep {
                axis: i as u16,
                step: idx,
            });
        }
        sp
    }

    /// One cycle of a `home` step: hm requested (the engine handles the zero-speed rule), the
    /// homing run once the drive is in hm, then back to the program's mode; the program goes on
    /// from the position homing defined. A homing error (or a run that times out or is cut
    /// short) stops the axes, naming the drive's own report.
    fn home_step(
        &mut self,
        i: usize,
        method: i8,
        st: &AxisStatus,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut Emitter,
    ) {
        let idle = st.mode_switch == ModeSwitchPhase::Idle;
        match self.home {
            HomeRun::Idle => {
                self.home = HomeRun::ToHm;
                if let Err(e) = self.axis.request_mode(OperationMode::Homing) {
                    self.home = HomeRun::Idle;
                    self.program = ProgramState::Idle;
                    ev.emit(EventKind::CommandRefused {
                        axis: i as u16,
                        why: match e {
                            cia402::AxisError::ModeNotSupported { .. } => {
                                "the program's home step was refused: the drive has no homing mode"
                            }
                            cia402::AxisError::ModeSwitchInProgress { .. } => {
                                "the program's home step was refused: another mode switch was under way"
                            }
                            _ => "the program's home step was refused by the axis",
                        },
                    });
                    self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                }
            }
            HomeRun::ToHm => {
                if idle && st.active_mode == OperationMode::Homing && st.streaming {
                    self.homing.start();
                    self.home = HomeRun::Running { method };
                }
            }
            HomeRun::Running { method } => match self.homing.outcome() {
                None => {}
                Some(cia402::HomingOutcome::Completed) => {
                    self.home = HomeRun::Back;
                    self.requested_mode = None;
                    if self
                        .axis
                        .request_mode(OperationMode::from_i8(self.mode.code()))
                        .is_err()
                    {
                        self.home = HomeRun::Idle;
                        self.program = ProgramState::Idle;
                        ev.emit(EventKind::CommandRefused {
                            axis: i as u16,
                            why: "the program stopped: the switch back from homing failed",
                        });
                        self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                    }
                }
                Some(outcome) => {
                    self.home = HomeRun::Idle;
                    self.program = ProgramState::Idle;
                    ev.emit(EventKind::HomingFailed {
                        axis: i as u16,
                        method,
                        outcome,
                        drive_says: self.homing_failure,
                    });
                    ev.emit(EventKind::Stopping {
                        reason: StopReason::HomingFailed { axis: i as u16 },
                    });
                    // This axis stops; the run then stops the others.
                    self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                }
            },
            HomeRun::Back => {
                if idle && st.active_mode.as_i8() == self.mode.code() {
                    self.home = HomeRun::Idle;
                    if self.home_by_app.is_none() {
                        self.runner.drive_done(actual);
                    }
                    self.hold = actual;
                }
            }
        }
    }

    /// Leave a home step: controlword bit 4 drops (homing interrupted), nothing stays armed
    /// for a later run of the program.
    fn abort_home(&mut self) {
        if self.home != HomeRun::Idle {
            self.homing.stop();
            self.axis.set_mode_bits(cia402::ControlWord::empty());
            self.home = HomeRun::Idle;
        }
        self.abort_drive_run();
    }

    /// Leave a pp/pv/tq step: the queue of pp targets is dropped and the move halted
    /// (controlword bit 8, the drive's own deceleration); pv and tq go to target 0.
    fn abort_drive_run(&mut self) {
        if self.drive_run != DriveRun::Idle {
            self.pp.clear();
            self.pp.set_halt(true);
            self.pv.set_target(0);
            self.tq.set_target(0);
            self.drive_run = DriveRun::Idle;
        }
    }

    /// One cycle in a profile mode (pp, pv, tq): the running step's targets through the mode's
    /// engine (the new-set-point handshake in pp), the step's end, and, with no step running,
    /// what the axis holds (pp: the last target; pv: velocity 0; tq: torque 0).
    fn profile_mode(
        &mut self,
        i: usize,
        sw: StatusWord,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut Emitter,
    ) {
        let st = self.axis.status();
        let Some(mode) = RunMode::from_code(st.active_mode.as_i8()).filter(|m| !m.is_cyclic())
        else {
            // Outside the profile modes their targets are 0: entering one starts from rest.
            self.pv.set_target(0);
            self.tq.set_target(0);
            return;
        };
        let stopping = self.stopping != Stopping::No;
        let enabled = st.state == Some(State::OperationEnabled) && st.streaming;
        if !enabled {
            // Nothing set before a disable, a quick stop or a fault comes back when the axis
            // is enabled again.
            self.pv.set_target(0);
            self.tq.set_target(0);
        }
        if stopping {
            self.abort_drive_run();
            self.pv.set_target(0);
            self.tq.set_target(0);
            if self.app_pp.take().is_some() {
                self.pp.clear();
                self.pp.set_halt(true);
            }
        }
        match (mode, self.drive_run) {
            (RunMode::Pp, DriveRun::Pp { .. }) => self.pp_step(i, sw, actual, ctx, ev),
            (RunMode::Pp, _) => {
                if stopping {
                    self.pp.set_halt(true);
                }
                let s = self.pp.step(&mut self.axis, sw);
                if s.aborted && self.app_pp.take().is_some() {
                    self.app_task = DriveTask::Idle;
                }
                if let Some(settled) = self.app_pp {
                    let settled = if s.queued == 0 && s.phase == cia402::PpPhase::Idle {
                        settled.saturating_add(1)
                    } else {
                        0
                    };
                    self.app_pp = Some(settled);
                    self.app_task = if s.target_reached && settled >= PP_SETTLE_CYCLES {
                        self.app_pp = None;
                        DriveTask::TargetReached
                    } else {
                        DriveTask::Positioning {
                            queued: u8::try_from(s.queued).unwrap_or(u8::MAX),
                        }
                    };
                }
            }
            (RunMode::Pv | RunMode::Tq, DriveRun::Profile { index, since }) => {
                let since = since.or(st.streaming.then_some(ctx.tick));
                self.drive_run = DriveRun::Profile { index, since };
                let t = since.map_or(0.0, |s| ctx.tick.saturating_sub(s) as f64 * ctx.dt);
                let done = match self.runner.steps().get(index) {
                    Some(&Step::Pv { velocity, seconds }) if mode == RunMode::Pv => {
                        let on = since.is_none() || t < seconds;
                        let v = self.drive_velocity(velocity);
                        self.pv.set_target(if on { v } else { 0 });
                        let s = self.pv.step(&mut self.axis, sw);
                        if t > seconds + DRIVE_STEP_TIMEOUT_S {
                            self.abort_drive_run();
                            self.program = ProgramState::Idle;
                            ev.emit(EventKind::CommandRefused {
                                axis: i as u16,
                                why: "the program stopped: the drive did not report velocity 0 \
                                      reached within 2 minutes of the pv step's end",
                            });
                            self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                            return;
                        }
                        !on && s.streaming && s.target_reached
                    }
                    Some(&Step::Tq {
                        torque,
                        seconds,
                        ramp,
                    }) if mode == RunMode::Tq => {
                        let on = since.is_none() || t < ramp + seconds;
                        self.tq
                            .set_target(if on { drive_torque(torque) } else { 0 });
                        let s = self.tq.step(&mut self.axis, sw);
                        // Done once the ramp down has had its time and the drive reports the
                        // torque back near 0 (a drive whose slope unit differs from its
                        // profile's takes longer), or, without that, after twice the time.
                        let settle = f64::from(cia402::profile_velocity::SETTLE_CYCLES) * ctx.dt;
                        let down = t >= 2.0 * ramp + seconds + settle;
                        let near_zero = f64::from(self.tel.torque_actual).abs()
                            <= (torque.abs() / 50.0).max(1.0);
                        !on && s.streaming
                            && down
                            && (near_zero || t >= 4.0 * ramp + seconds + TQ_SETTLE_MAX_S)
                    }
                    _ => {
                        // Not this mode's step (a mode switch under way): hold.
                        self.hold_profile(mode, sw);
                        false
                    }
                };
                if done {
                    self.drive_run = DriveRun::Idle;
                    self.runner.drive_done(actual);
                    self.hold = actual;
                }
            }
            _ => self.hold_profile(mode, sw),
        }
    }

    /// In pv or tq with no step running: the target the application set, else 0.
    fn hold_profile(&mut self, mode: RunMode, sw: StatusWord) {
        match mode {
            RunMode::Pv => {
                let _ = self.pv.step(&mut self.axis, sw);
            }
            RunMode::Tq => {
                let _ = self.tq.step(&mut self.axis, sw);
            }
            _ => {}
        }
    }

    /// One cycle of a pp step: targets into the handshake engine (a set of set-points: as the
    /// engine's queue takes them; single set-points: each once the last is reached), the
    /// handshake, and the step's end once the drive reports the last target reached.
    fn pp_step(
        &mut self,
        i: usize,
        sw: StatusWord,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut Emitter,
    ) {
        let DriveRun::Pp {
            index,
            mut given,
            mut settled,
            reached,
            since,
        } = self.drive_run
        else {
            return;
        };
        let Some(Step::Pp {
            targets,
            relative,
            immediate,
        }) = self.runner.steps().get(index)
        else {
            self.drive_run = DriveRun::Idle;
            return;
        };
        let (relative, immediate, n) = (*relative, *immediate, targets.len());
        if let Some(&t) = targets.get(given)
            && (!immediate || given == 0 || reached)
        {
            let sp = cia402::SetPoint {
                target: t.round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32,
                relative,
                immediate,
            };
            if self.pp.push(sp).is_ok() {
                given += 1;
            }
        }
        let s = self.pp.step(&mut self.axis, sw);
        let timed_out = ctx.tick.saturating_sub(since) as f64 * ctx.dt > DRIVE_STEP_TIMEOUT_S;
        if timed_out {
            self.abort_drive_run();
            self.program = ProgramState::Idle;
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why: "the program stopped: the drive did not report its pp targets reached \
                      within 2 minutes",
            });
            self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
            return;
        }
        if s.error.is_some() {
            self.abort_drive_run();
            self.program = ProgramState::Idle;
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why: "the program stopped: the drive did not acknowledge a pp target \
                      (statusword bit 12 stayed 0 after controlword bit 4 rose)",
            });
            self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
            return;
        }
        settled = if s.queued == 0 && s.phase == cia402::PpPhase::Idle {
            settled.saturating_add(1)
        } else {
            0
        };
        let reached = s.target_reached && settled >= PP_SETTLE_CYCLES;
        if given == n && reached {
            self.drive_run = DriveRun::Idle;
            self.runner.drive_done(actual);
            self.hold = actual;
            return;
        }
        self.drive_run = DriveRun::Pp {
            index,
            given,
            settled,
            reached,
            since,
        };
    }

    /// The application or a command arms a probe: taken with no program running and the
    /// probe's objects mapped.
    fn arm_probe(&mut self, probe: u8, edge: ProbeEdge) -> Result<(), &'static str> {
        let pf = &self.fields.probe;
        let slot =
            (usize::from(probe.clamp(1, 2)) - 1) * 2 + usize::from(edge == ProbeEdge::Falling);
        let mapped = pf.function.is_some()
            && pf.status.is_some()
            && pf.positions.get(slot).is_some_and(Option::is_some);
        if !matches!(probe, 1 | 2) {
            Err("touch probe refused: probes are 1 and 2")
        } else if !mapped {
            Err(
                "touch probe refused: the mapping does not carry 0x60B8, 0x60B9 and the probe's \
                 position object (map them with the drive's `probes`)",
            )
        } else if self.program == ProgramState::Running {
            Err("touch probe refused: a program runs on the axis")
        } else {
            if let Some(p) = self.probes.get_mut(usize::from(probe) - 1) {
                *p = ProbeArm::Rearm(edge);
            }
            Ok(())
        }
    }

    /// The touch probes: 0x60B8 from what is armed, and a latch in 0x60B9 reported with the
    /// position the drive latched (0x60BA–0x60BD), unwrapped like the actual position.
    fn probe(&mut self, i: usize, ev: &mut Emitter) {
        let status = self.probe_status;
        let mut function = 0u16;
        for (k, base) in [(0usize, 0u16), (1, 8)] {
            let Some(arm) = self.probes.get(k).copied() else {
                continue;
            };
            let next = match arm {
                ProbeArm::Rearm(edge) => ProbeArm::Armed { edge, clear: false },
                ProbeArm::Armed { edge, clear } => {
                    let stored = base
                        + match edge {
                            ProbeEdge::Rising => 1,
                            ProbeEdge::Falling => 2,
                        };
                    let enabled = status >> base & 1 != 0;
                    let set = status >> stored & 1 != 0;
                    if enabled && !set {
                        ProbeArm::Armed { edge, clear: true }
                    } else if enabled && set && clear {
                        let probe = k as u8 + 1;
                        let slot = usize::from(k as u8 * 2 + u8::from(edge == ProbeEdge::Falling));
                        let raw = self.probe_positions.get(slot).copied().unwrap_or(0);
                        let position = self.pos + i64::from(raw.wrapping_sub(self.pos_raw));
                        if self.latches.len() < self.latches.capacity() {
                            self.latches.push((probe, edge, position));
                        }
                        ev.emit(EventKind::ProbeLatched {
                            axis: i as u16,
                            probe,
                            edge,
                            position,
                        });
                        ProbeArm::Latched { edge, position }
                    } else {
                        arm
                    }
                }
                other => other,
            };
            if let Some(p) = self.probes.get_mut(k) {
                *p = next;
            }
            // A probe being re-armed has its bits 0 for this cycle (the drive clears what it
            // stored), then set from the next.
            if !matches!(arm, ProbeArm::Rearm(_)) {
                function |= next.function_bits(base);
            }
        }
        if self.probes != [ProbeArm::Off; 2] {
            self.probe_function = Some(function);
        }
    }

    /// A velocity in position units per second as the drive's velocity value (0x60FF),
    /// rounded and held to its range.
    fn drive_velocity(&self, v: f64) -> i32 {
        (v / self.velocity_unit)
            .round()
            .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }

    /// The set-point into the engine, in the active mode.
    fn command(&mut self, sp: Sample, st: &AxisStatus) {
        let mode = RunMode::from_code(st.active_mode.as_i8()).unwrap_or(self.mode);
        self.mode = mode;
        let _ = match mode {
            // The drive generates the motion; `profile_mode` gives it its targets.
            RunMode::Pp | RunMode::Pv | RunMode::Tq => Ok(()),
            RunMode::Csp => self.axis.set_position((sp.pos.round() as i64) as i32),
            RunMode::Csv => self.axis.set_velocity(self.drive_velocity(sp.vel)),
            RunMode::Cst => self.axis.set_torque(drive_torque(sp.torque)),
        };
    }

    /// The engine's events of this step: mode switches the program waits for, faults.
    fn engine_events(&mut self, i: usize, actual: Sample, ctx: &StepContext, ev: &mut Emitter) {
        while let Some(e) = self.axis.poll_event() {
            match e {
                cia402::Event::ModeSwitched { to, .. } => {
                    if let Some(m) = RunMode::from_code(to.as_i8()) {
                        self.mode = m;
                        if self.requested_mode == Some(m) {
                            self.requested_mode = None;
                            self.runner.mode_switched(actual);
                        }
                    }
                }
                cia402::Event::ModeSwitchFailed(f)
                    if matches!(self.home, HomeRun::ToHm | HomeRun::Back) =>
                {
                    // The switch into or out of hm failed: the home step cannot go on.
                    self.home = HomeRun::Idle;
                    self.program = ProgramState::Idle;
                    if f.reason != cia402::ModeSwitchFailure::Fault {
                        ev.emit(EventKind::CommandRefused {
                            axis: i as u16,
                            why: "the program stopped: the switch into or out of homing mode failed",
                        });
                        self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                    }
                }
                cia402::Event::ModeSwitchFailed(f)
                    if self.program == ProgramState::Pending
                        && f.reason != cia402::ModeSwitchFailure::Fault =>
                {
                    // The drive never took the mode the program starts in: the program cannot
                    // start, and the axis does not stay enabled waiting for it.
                    self.program = ProgramState::Idle;
                    ev.emit(EventKind::CommandRefused {
                        axis: i as u16,
                        why: "the program could not start: the drive did not take its start mode",
                    });
                    self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                }
                cia402::Event::ModeSwitchFailed(f) if self.requested_mode.is_some() => {
                    // The program asked for this switch and cannot go on without it. A fault
                    // cut it short: the fault itself is what gets reported.
                    self.requested_mode = None;
                    self.program = ProgramState::Idle;
                    if f.reason != cia402::ModeSwitchFailure::Fault {
                        ev.emit(EventKind::CommandRefused {
                            axis: i as u16,
                            why: "the program stopped: its mode switch failed",
                        });
                        // The axis does not stay enabled in the mode it was leaving (turning,
                        // perhaps, with nobody to stop it): a controlled stop, as for a program
                        // that cannot start.
                        self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
                    }
                }
                cia402::Event::Fault { .. } if !ctx.ending => {
                    self.program = ProgramState::Idle;
                    if let HomeRun::Running { method } = self.home {
                        // A drive that faults on a homing error (the BDHDE's 0x6100): the home
                        // step's account first, the fault after it.
                        ev.emit(EventKind::HomingFailed {
                            axis: i as u16,
                            method,
                            outcome: self
                                .homing
                                .outcome()
                                .unwrap_or(cia402::HomingOutcome::Aborted),
                            drive_says: self.homing_failure,
                        });
                    }
                    self.abort_home();
                    ev.emit(EventKind::Axis {
                        axis: i as u16,
                        event: e,
                    });
                    // The other axes are stopped after the per-axis steps. A fault while
                    // nothing was energised (latched before the run) stops nothing.
                    if ctx.any_energised_before {
                        ev.emit(EventKind::Stopping {
                            reason: StopReason::DriveFault { axis: i as u16 },
                        });
                    }
                    continue;
                }
                _ => {}
            }
            ev.emit(EventKind::Axis {
                axis: i as u16,
                event: e,
            });
        }
    }

    /// The engine's outputs into the process image, and the cycle counter.
    fn write_outputs(&mut self, out: &Output, image: &mut [u8]) {
        self.fields.axis.write(out, image);
        if let Some(f) = self.probe_function {
            pdo::axis::write(self.fields.probe.function, image, i64::from(f));
        }
        self.count(image);
    }

    /// Set-point steps while enabled, in the mode the drive runs (confirmed by 0x6061): the
    /// other targets only track the actual values.
    fn record_steps(&mut self, out: &Output, enabled: bool, cycle: u64) {
        let running = self.axis.status();
        if !(enabled && running.streaming) {
            self.last_out = None;
            return;
        }
        if let Some((p, v, t)) = self.last_out {
            let s = &mut self.steps;
            let step = match RunMode::from_code(running.active_mode.as_i8()) {
                Some(RunMode::Csp) => Some((
                    i64::from(out.target_position.wrapping_sub(p)).abs(),
                    &mut s.position,
                    0,
                )),
                Some(RunMode::Csv) => Some((
                    (i64::from(out.target_velocity) - i64::from(v)).abs(),
                    &mut s.velocity,
                    1,
                )),
                Some(RunMode::Cst) => Some((
                    (i64::from(out.target_torque) - i64::from(t)).abs(),
                    &mut s.torque,
                    2,
                )),
                _ => None,
            };
            if let Some((d, max, at)) = step
                && d > *max
            {
                *max = d;
                s.at_cycle[at] = cycle;
            }
        }
        self.last_out = Some((out.target_position, out.target_velocity, out.target_torque));
    }

    /// The master's following error (the actual value of this exchange against the demand it
    /// answers, [`FEEDBACK_PULSES`]), the drive's 0x60F4 judged against it, the following
    /// error limit, and the rest of the telemetry.
    fn follow(&mut self, i: usize, out: &Output, ctx: &StepContext, ev: &mut Emitter) {
        let demand = if self.pos_valid {
            self.pos + i64::from(out.target_position.wrapping_sub(self.pos_raw))
        } else {
            i64::from(out.target_position)
        };
        let state = StatusWord::from_raw(self.tel.statusword).state();
        let energised = state.is_some_and(State::is_energised);
        // In hm, pp, pv and tq the drive moves on its own (and in hm its position jumps at the
        // home): there is no demand to follow, and none from before may be judged against the
        // positions after.
        let homing = !RunMode::from_code(out.mode.as_i8()).is_some_and(RunMode::is_cyclic);
        if homing {
            self.carried = [(u64::MAX, 0); CARRIED];
            self.tel.following_error = 0;
        }
        // Without the demand (lost frames just before) the last value stands. The newest
        // demand whose frame passed by pulse s − 2 (two frames after one pulse: the later
        // one's demand is what the drive took).
        if let Some(s) = ctx.pulse.checked_sub(FEEDBACK_PULSES).filter(|_| !homing) {
            let newest_first = (1..=CARRIED).map(|k| (self.carried_next + CARRIED - k) % CARRIED);
            for k in newest_first {
                if let Some(&(p, d)) = self.carried.get(k)
                    && p != u64::MAX
                    && p <= s
                {
                    self.tel.following_error = d - self.pos;
                    break;
                }
            }
        }
        let moving = self.last_demand.is_some_and(|l| l != demand);
        self.last_demand = (!homing).then_some(demand);
        // The master's following error only while csp runs (in hm the drive moves on its own).
        self.fe_judged =
            energised && self.mode == RunMode::Csp && out.mode.as_i8() == RunMode::Csp.code();
        if self.fe_judged {
            self.judge_following_error(i, moving, ctx.cycle, ev);
        }
        let t = &mut self.tel;
        t.controlword = out.controlword.raw();
        t.mode = out.mode.as_i8();
        t.position_demand = demand;
        t.velocity_demand = out.target_velocity;
        t.torque_demand = out.target_torque;
        t.state = state;
        t.al_state = self.al_state;
        t.program_step = self.runner.step_index() as u16;
        t.program_running = self.program == ProgramState::Running;
        if state != self.last_state {
            self.last_state = state;
            if let Some(s) = state
                && self.states.last() != Some(&s)
                && self.states.len() < self.states.capacity()
            {
                self.states.push(s);
            }
        }
    }

    /// Energised in csp: the largest following errors, a 0x60F4 that never leaves 0, and the
    /// following error limit (a quick stop).
    fn judge_following_error(&mut self, i: usize, moving: bool, cycle: u64, ev: &mut Emitter) {
        let fe = self.tel.following_error.abs();
        if fe > self.tel.max_following_error {
            self.tel.max_following_error = fe;
        }
        if let Some(d) = self.tel.following_error_drive {
            self.tel.max_following_error_drive = self.tel.max_following_error_drive.max(d.abs());
            // 0x60F4 that never leaves 0 while the axis follows a moving set-point is not
            // computed by the drive: flag it once, never trust it.
            if d != 0 {
                self.fe_drive_alive = true;
            } else if moving
                && fe > 0
                && !self.fe_drive_alive
                && !self.tel.following_error_drive_stuck
            {
                self.fe_drive_zero_cycles += 1;
                if self.fe_drive_zero_cycles >= DRIVE_FE_STUCK_CYCLES {
                    self.tel.following_error_drive_stuck = true;
                    ev.emit(EventKind::DriveFollowingErrorStuck {
                        axis: i as u16,
                        cycles: self.fe_drive_zero_cycles,
                        master: self.tel.max_following_error,
                    });
                }
            }
        }
        if let Some(limit) = self.fe_limit
            && fe > i64::from(limit)
            && self.stopping == Stopping::No
        {
            ev.emit(EventKind::FollowingError {
                axis: i as u16,
                value: fe,
                limit,
            });
            ev.emit(EventKind::Stopping {
                reason: StopReason::FollowingError { axis: i as u16 },
            });
            self.stopping = Stopping::Quick { at: cycle };
            self.axis.request_quick_stop();
        }
    }

    /// Begin a controlled stop at good cycle `tick` (the ramp's clock) and cycle `cycle` (the
    /// timeout's).
    fn begin_stop(&mut self, kind: StopKind, tick: u64, cycle: u64) {
        self.program = ProgramState::Idle;
        self.abort_home();
        let st = self.axis.status();
        if !st.state.is_some_and(State::is_energised) {
            self.axis.request_disable();
            self.stopping = Stopping::Disabling;
            return;
        }
        self.stopping = match kind {
            StopKind::Ramp => Stopping::Ramp {
                from: self.hold,
                at: tick,
                since: cycle,
            },
            StopKind::QuickStop => {
                self.axis.request_quick_stop();
                Stopping::Quick { at: cycle }
            }
        };
    }

    /// A controlled stop that takes too long: disable regardless. A disabled axis is no longer
    /// stopping (unless the run ends).
    fn supervise_stop(&mut self, cycle: u64, stop_timeout_cycles: u64, ending: bool) {
        if let Stopping::Ramp { since: at, .. } | Stopping::Quick { at } = self.stopping
            && cycle - at > stop_timeout_cycles
        {
            self.axis.request_disable();
            self.stopping = Stopping::Disabling;
        }
        if self.stopping == Stopping::Disabling
            && !self.axis.status().state.is_some_and(State::is_energised)
            && !ending
        {
            self.stopping = Stopping::No;
        }
    }

    /// Apply a command to this axis (number `i`); `Some(reason)` if it was refused.
    fn apply(&mut self, cmd: &Command, i: usize) -> Option<&'static str> {
        match *cmd {
            Command::Enable(ax) if ax.includes(i) => {
                self.stopping = Stopping::No;
                self.axis
                    .request_enable()
                    .err()
                    .map(|_| "enable refused (fault present?)")
            }
            Command::Disable(ax) if ax.includes(i) => {
                self.program = ProgramState::Idle;
                self.abort_home();
                self.axis.request_disable();
                None
            }
            Command::QuickStop(ax) if ax.includes(i) => {
                self.program = ProgramState::Idle;
                self.abort_home();
                self.axis.request_quick_stop();
                None
            }
            Command::FaultReset(ax) if ax.includes(i) => {
                if self.axis.request_fault_reset() {
                    None
                } else {
                    Some("fault reset ignored: the drive shows no fault")
                }
            }
            Command::Mode(ax, m) if ax.includes(i) => self
                .axis
                .request_mode(OperationMode::from_i8(m.code()))
                .err()
                .map(|_| "mode switch refused"),
            Command::RunProgram(ax) if ax.includes(i) => {
                if self.runner.steps().is_empty() {
                    return Some("the axis has no program");
                }
                self.runner.restart();
                self.requested_mode = None;
                self.abort_home();
                if self.probes != [ProbeArm::Off; 2] {
                    self.probes = [ProbeArm::Off; 2];
                }
                self.program = ProgramState::Pending;
                None
            }
            Command::HoldProgram(ax) if ax.includes(i) => {
                self.program = ProgramState::Idle;
                self.abort_home();
                None
            }
            Command::Home(ax, method) if ax.includes(i) => {
                let st = self.axis.status();
                if st.state != Some(State::OperationEnabled) || self.stopping != Stopping::No {
                    Some("home refused: the axis is not enabled")
                } else if self.program == ProgramState::Running || self.home != HomeRun::Idle {
                    Some("home refused: a program or a homing runs on the axis")
                } else {
                    self.home_commanded = Some(method);
                    None
                }
            }
            Command::Pp {
                axis,
                target,
                relative,
                immediate,
            } if axis as usize == i => self.take_pp(target, relative, immediate).err().map(|e| e.1),
            Command::ArmProbe { axis, probe, edge } if axis as usize == i => {
                self.arm_probe(probe, edge).err()
            }
            Command::Setpoint(axis, v) if axis as usize == i => {
                match self.mode {
                    RunMode::Csp => self.hold.pos = v,
                    RunMode::Csv => self.hold.vel = v,
                    RunMode::Cst => self.hold.torque = v,
                    RunMode::Pp | RunMode::Pv | RunMode::Tq => {
                        return Some("a set-point command needs csp, csv or cst");
                    }
                }
                None
            }
            _ => None,
        }
    }
}

/// A torque in the drive's unit as its torque value (0x6071), rounded and held to its range.
fn drive_torque(t: f64) -> i16 {
    t.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
}

/// The raw AL state (0x0130 low byte) ethercrab read for a device.
fn raw_al_state(st: &SubDeviceState) -> u8 {
    match st {
        SubDeviceState::None => 0,
        SubDeviceState::Init => 1,
        SubDeviceState::PreOp => 2,
        SubDeviceState::Bootstrap => 3,
        SubDeviceState::SafeOp => 4,
        SubDeviceState::Op => 8,
        SubDeviceState::Other(v) => *v,
    }
}

/// How the exchange of one cycle went.
enum Exchanged {
    /// A reply came.
    Reply,
    /// No reply in time.
    Lost,
}

/// The constants of one run, derived from the settings and the drives.
struct Constants {
    cycle_ns: u64,
    dt: f64,
    /// The working counter a reply whose image went out in one LRW shows.
    wkc_whole: u16,
    segment_gone_cycles: u64,
    stop_ramp_cycles: u64,
    stop_timeout_cycles: u64,
    /// The DC system time from which OP may be requested: [`CycleSettings::safeop_cycles`]
    /// SYNC0 cycles after the last drive's first SYNC0 (0 without DC).
    op_not_before_dc: u64,
}

/// The clock of the run and the timing of the current cycle.
#[derive(Default)]
struct Clock {
    /// Cycles so far.
    cycle: u64,
    /// Cycles with a reply so far: the clock of the programs and the stop ramps (a lost cycle
    /// holds the set-point, so the motion resumes where it stood).
    tick: u64,
    last_wake: u64,
    next_wake: u64,
    woke: u64,
    latency: u64,
    t_ex: u64,
    t_ex_done: u64,
    /// The wait to the next DC-aligned instant, when the reference clock answered.
    next_wait: Option<u64>,
    dc_time: u64,
}

/// Counts of lost frames, wrong working counters and overruns.
#[derive(Default)]
struct Counts {
    lost_total: u64,
    consecutive_lost: u32,
    segment_lost: bool,
    wkc_errors: u32,
    last_wkc: u16,
    /// What the last reply's working counter should have been (the sum over its datagrams).
    last_wkc_expected: u16,
    overruns: u64,
    recorded_lost: u64,
    recorded_overruns: u64,
    /// Replies that came after the cycle's budget (counted among the lost cycles too).
    late_total: u64,
    /// Replies with a wrong working counter.
    wkc_wrong_total: u64,
    /// In SAFE-OP, before OP is requested: consecutive replies with the right working counter
    /// (OP is requested after enough of them) and with a wrong one (start-up fails after
    /// [`CycleSettings::wkc_errors_before_stop`]).
    safeop_wkc_good: u32,
    safeop_wkc_bad: u32,
    /// The last wrong SAFE-OP reply: (got, expected, its first wrong datagram).
    safeop_wkc_last: Option<(u16, u16, Option<DatagramWkc>)>,
    /// An I/O device takes its outputs in OP only: SAFE-OP's working counter is not judged
    /// further.
    safeop_wkc_tolerated: bool,
    /// The pump's counters when the run began.
    pump_at_start: crate::io::PumpStats,
}

/// One run of the cycle: what it drives, where it stands and what it has seen. See the
/// [module documentation](self).
struct Cycle<'a, 'p, L: FrameLink> {
    md: &'a MainDevice<'a>,
    pump: &'a mut Pump<'p, L>,
    group: &'a Group<SafeOp, HasDc>,
    others: &'a [ConfiguredIo],
    settings: &'a CycleSettings,
    hooks: Option<&'a dyn CycleHooks>,
    /// The application's code, called once per cycle, and its view of each axis (same order
    /// as `axes`).
    app: Option<&'a mut (dyn CycleApp + 'static)>,
    app_axes: Vec<AppAxis>,
    /// Where every cycle is recorded, if it is.
    record: Option<&'a mut RecordTx>,
    commands: &'a mut rtrb::Consumer<Command>,
    telemetry: &'a mut triple_buffer::Input<Telemetry>,
    restarts: &'a mut u32,
    restarting: &'a mut bool,
    ev: Emitter<'a>,
    k: Constants,
    /// The expected working counter of each logical datagram, from the FMMU configuration the
    /// master sent (`None`: not recorded; the whole-image value is checked instead).
    wkc_plan: Option<WkcPlan>,
    axes: Vec<AxisRt>,
    /// Every device by position: its station address and last AL state.
    addresses: Vec<u16>,
    al_states: Vec<u8>,
    /// The I/O devices as last seen (a lost cycle keeps the inputs of the last reply).
    io_last: Vec<IoTelemetry>,
    clock: Clock,
    counts: Counts,
    timing: Timing,
    window: Window,
    op: OpState,
    phase: RunPhase,
    /// The hooks were told steady state began (and not yet that it ended).
    steady: bool,
    end_reason: Option<CycleEnd>,
    last_telemetry: CycleTelemetry,
}

/// Run the cycle until it ends. Call on the thread that is to be the cycle thread (the
/// settings' RT priority, CPU and memory locking are applied to it).
#[allow(clippy::too_many_arguments)]
pub fn run<L: FrameLink>(
    md: &MainDevice<'_>,
    pump: &mut Pump<'_, L>,
    group: &Group<SafeOp, HasDc>,
    drives: &[ConfiguredDrive],
    others: &[ConfiguredIo],
    settings: &CycleSettings,
    io: &mut CycleIo,
    hooks: Option<&dyn CycleHooks>,
    app: Option<&mut (dyn CycleApp + 'static)>,
    record: Option<&mut RecordTx>,
) -> CycleReport {
    let rt = settings.rt.apply_to_current_thread();
    if let Some(tx) = io.rt_report.take() {
        let _ = tx.send(rt.clone());
    }
    let mut c = Cycle::new(md, pump, group, drives, others, settings, io, hooks, app);
    c.record = record;
    let end = loop {
        if let Some(end) = c.turn() {
            break end;
        }
    };
    c.finish(end, rt)
}

impl<'a, 'p, L: FrameLink> Cycle<'a, 'p, L> {
    /// Set up a run (allocations allowed): the axes, the initial outputs, the constants.
    #[allow(clippy::too_many_arguments)]
    fn new(
        md: &'a MainDevice<'a>,
        pump: &'a mut Pump<'p, L>,
        group: &'a Group<SafeOp, HasDc>,
        drives: &[ConfiguredDrive],
        others: &'a [ConfiguredIo],
        settings: &'a CycleSettings,
        io: &'a mut CycleIo,
        hooks: Option<&'a dyn CycleHooks>,
        app: Option<&'a mut (dyn CycleApp + 'static)>,
    ) -> Self {
        let cycle_ns = (settings.cycle.as_nanos() as u64).max(1);
        let axes: Vec<AxisRt> = drives
            .iter()
            .filter_map(|d| AxisRt::new(d, settings.cycle))
            .collect();
        let app_axes: Vec<AppAxis> = drives
            .iter()
            .filter(|d| axes.iter().any(|a| a.sub == usize::from(d.info.position)))
            .map(app_view)
            .collect();
        for a in &axes {
            if let Ok(sd) = group.subdevice(md, a.sub) {
                a.initial_outputs(sd.io_raw_mut().outputs());
            }
        }
        let CycleIo {
            commands,
            events,
            telemetry,
            restarts,
            restarting,
            ..
        } = io;
        {
            let t = telemetry.input_buffer_mut();
            t.axes.resize(axes.len(), AxisTelemetry::default());
            t.io.resize(others.len(), IoTelemetry::default());
        }
        // Every device counts: an LRW adds 2 for each device with outputs, 1 for each with
        // inputs.
        let wkc =
            |outputs: usize, inputs: usize| u16::from(outputs > 0) * 2 + u16::from(inputs > 0);
        let wkc_whole: u16 = drives
            .iter()
            .map(|d| {
                wkc(
                    d.layout.bytes(crate::pdo::Direction::Rx),
                    d.layout.bytes(crate::pdo::Direction::Tx),
                )
            })
            .chain(others.iter().map(|o| wkc(o.outputs, o.inputs)))
            .sum();
        let n_devices = group.len();
        let mut addresses = vec![0u16; n_devices];
        let placed = drives
            .iter()
            .map(|d| (d.info.position, d.info.address))
            .chain(others.iter().map(|o| (o.info.position, o.info.address)));
        for (position, address) in placed {
            if let Some(a) = addresses.get_mut(usize::from(position)) {
                *a = address;
            }
        }
        let plan = WkcPlan::from_fmmus(
            addresses.iter().enumerate().map(|(p, &a)| (p as u16, a)),
            pump.fmmu_configs(),
        );
        // The plan must account for every device the layout has: otherwise the tap missed a
        // configuration, and the whole-image value is the better check.
        let wkc_plan = (!plan.is_empty() && plan.whole() == wkc_whole).then_some(plan);
        pump.record_logical(wkc_plan.is_some());
        pump.set_drift_compensation(settings.drift_compensation);
        let cycles = |d: Duration| d.as_nanos() as u64 / cycle_ns;
        let pump_at_start = pump.stats();
        Self {
            md,
            pump,
            group,
            others,
            settings,
            hooks,
            app,
            app_axes,
            record: None,
            commands,
            telemetry,
            restarts,
            restarting,
            ev: Emitter {
                out: events,
                cycle: 0,
                first_stop: None,
            },
            wkc_plan,
            k: Constants {
                cycle_ns,
                dt: settings.cycle.as_secs_f64(),
                wkc_whole,
                segment_gone_cycles: cycles(settings.segment_gone_after)
                    .max(u64::from(settings.segment_lost_after)),
                stop_ramp_cycles: cycles(settings.stop_ramp).max(1),
                stop_timeout_cycles: cycles(settings.stop_timeout).max(1),
                op_not_before_dc: super::startup::op_not_before_dc(
                    drives,
                    settings.safeop_cycles,
                    cycle_ns,
                ),
            },
            axes,
            addresses,
            al_states: vec![0u8; n_devices],
            io_last: vec![IoTelemetry::default(); others.len()],
            clock: Clock {
                next_wake: monotonic_ns() + cycle_ns,
                ..Clock::default()
            },
            counts: Counts {
                pump_at_start,
                ..Counts::default()
            },
            timing: Timing::default(),
            window: if settings.steady_timing_only {
                Window::NotYet
            } else {
                Window::Open
            },
            op: OpState::SafeOp,
            phase: RunPhase::Running,
            steady: false,
            end_reason: None,
            last_telemetry: CycleTelemetry::default(),
        }
    }

    fn ending(&self) -> bool {
        matches!(self.phase, RunPhase::Ending { .. })
    }

    fn all_op(&self) -> bool {
        self.op == OpState::AllOp
    }

    /// One cycle; `Some` when the run ends. No allocation from here on.
    fn turn(&mut self) -> Option<CycleEnd> {
        if self.window == Window::OpensNext {
            self.window = Window::Open;
        }
        self.wake();
        let good = match self.exchange() {
            Ok(Exchanged::Reply) => true,
            Ok(Exchanged::Lost) => {
                if let Some(end) = self.on_lost() {
                    return Some(end);
                }
                false
            }
            Err(end) => return Some(end),
        };
        if let Some(end) = self.request_op() {
            return Some(end);
        }
        self.apply_commands();
        self.step_axes(good);
        self.supervise_axes();
        self.publish(good);
        if good {
            self.record_samples();
        }
        if let Some(end) = self.leave_op() {
            return Some(end);
        }
        if self.window.recording() {
            self.timing.busy.record(monotonic_ns() - self.clock.woke);
        }
        if self.window == Window::ClosesAfter {
            self.window = Window::Closed;
        }
        self.schedule_next();
        None
    }

    /// Sleep until the instant; record the wake-up.
    fn wake(&mut self) {
        let c = &mut self.clock;
        sleep_until_ns(c.next_wake);
        c.woke = monotonic_ns();
        c.latency = c.woke.saturating_sub(c.next_wake);
        let recording = self.window.recording();
        if recording {
            self.timing.wake_latency.record(c.latency);
            if c.last_wake != 0 {
                self.timing.period.record(c.woke - c.last_wake);
            }
        }
        if c.latency > self.k.cycle_ns {
            self.counts.overruns += 1;
            if recording {
                self.counts.recorded_overruns += 1;
            }
        }
        c.last_wake = c.woke;
        c.cycle += 1;
        self.ev.cycle = c.cycle;
    }

    /// Exchange the process data (the AL states ride along with the LRW) and look at what came
    /// back; `Err` when the link failed.
    fn exchange(&mut self) -> Result<Exchanged, CycleEnd> {
        let deadline =
            self.clock.woke + (self.k.cycle_ns as f64 * self.settings.reply_budget) as u64;
        self.clock.t_ex = monotonic_ns();
        let group = self.group;
        self.pump.clear_logical();
        let result = {
            let fut = pin!(group.tx_rx_dc(self.md));
            exec::exchange(self.pump, fut, deadline)
        };
        self.clock.t_ex_done = monotonic_ns();
        self.clock.next_wait = None;
        match result {
            Ok(Ok(resp)) => {
                self.clock.tick += 1;
                if self.window.recording() {
                    let took = self.clock.t_ex_done - self.clock.t_ex;
                    self.timing.exchange.record(took);
                }
                if self.counts.consecutive_lost > 0 {
                    self.ev.emit(EventKind::FramesResumed {
                        lost: self.counts.consecutive_lost,
                    });
                }
                self.counts.consecutive_lost = 0;
                self.counts.segment_lost = false;
                self.clock.dc_time = resp.extra.dc_system_time;
                self.counts.last_wkc = resp.working_counter;
                self.clock.next_wait = Some(resp.extra.next_cycle_wait.as_nanos() as u64);
                let mut scan = StateScan::default();
                for (i, st) in resp.subdevice_states.iter().enumerate() {
                    self.on_al_state(i, raw_al_state(st), &mut scan);
                }
                self.supervise_bus(scan, resp.working_counter);
                Ok(Exchanged::Reply)
            }
            Err(ExchangeError::Late) => {
                self.counts.late_total += 1;
                Ok(Exchanged::Lost)
            }
            Ok(Err(_)) => Ok(Exchanged::Lost),
            Err(ExchangeError::Link(_)) => Err(CycleEnd::LinkFailed),
        }
    }

    /// Device `i` is in AL state `raw`: note it, and a device that left OP on its own.
    fn on_al_state(&mut self, i: usize, raw: u8, scan: &mut StateScan) {
        if raw == 0 && scan.missing.is_none() {
            scan.missing = Some(i as u16);
        }
        if raw != 8 {
            scan.every_op = false;
        }
        if let Some(a) = self.axes.iter_mut().find(|a| a.sub == i) {
            a.al_state = raw;
        }
        let Some(prev) = self.al_states.get_mut(i) else {
            return;
        };
        if *prev == raw {
            return;
        }
        let was_op = *prev == 8;
        *prev = raw;
        self.ev.emit(EventKind::AlState {
            device: i as u16,
            state: raw,
        });
        if was_op && raw != 8 && !self.ending() {
            // A device left OP on its own: decode why, stop every axis, end.
            let code = self.al_status_code(i);
            self.ev.emit(EventKind::LeftOp {
                device: i as u16,
                state: raw,
                code,
            });
            if scan.left_op.is_none() {
                scan.left_op = Some(i as u16);
                self.end_reason = Some(CycleEnd::DriveLeftOp {
                    device: i as u16,
                    al_state: raw,
                    code,
                });
            }
        }
    }

    /// Device `i`'s AL status code (0x0134), if it answers within a quarter cycle.
    fn al_status_code(&mut self, i: usize) -> Option<u16> {
        let addr = self.addresses.get(i).copied().unwrap_or(0);
        let fut = pin!(EcCommand::fprd(addr, register::AL_STATUS_CODE).receive::<u16>(self.md));
        match exec::exchange(self.pump, fut, monotonic_ns() + self.k.cycle_ns / 4) {
            Ok(Ok(c)) => Some(c),
            _ => None,
        }
    }

    /// After a reply: a device that left OP stops every axis; every device in OP begins steady
    /// state; in OP, the working counter is checked.
    fn supervise_bus(&mut self, scan: StateScan, wkc: u16) {
        let (tick, cycle) = (self.clock.tick, self.clock.cycle);
        if let Some(device) = scan.left_op {
            self.ev.emit(EventKind::Stopping {
                reason: StopReason::DriveLeftOp { device },
            });
            self.begin_ending();
            for a in self.axes.iter_mut() {
                a.begin_stop(StopKind::Ramp, tick, cycle);
            }
        }
        if !self.all_op() && scan.every_op && !self.al_states.is_empty() {
            self.op = OpState::AllOp;
            if *self.restarting {
                *self.restarting = false;
                *self.restarts += 1;
            }
            self.ev.emit(EventKind::AllOp);
            if self.settings.steady_timing_only && self.window == Window::NotYet {
                self.window = Window::OpensNext;
            }
            if let Some(h) = self.hooks {
                h.steady_begin();
                self.steady = true;
            }
        }
        let (expected, datagram) = self.expected_wkc();
        self.counts.last_wkc_expected = expected;
        if self.op == OpState::SafeOp && !self.ending() {
            // SAFE-OP before OP: slave stacks take outputs from SAFE-OP on (ETG.1020), so the
            // working counter must be whole here too: a device whose outputs (or inputs) are
            // not taken is named before OP is requested.
            let c = &mut self.counts;
            if (wkc == expected && datagram.is_none()) || c.safeop_wkc_tolerated {
                c.safeop_wkc_good = c.safeop_wkc_good.saturating_add(1);
                c.safeop_wkc_bad = 0;
            } else {
                c.safeop_wkc_good = 0;
                c.safeop_wkc_bad = c.safeop_wkc_bad.saturating_add(1);
                c.safeop_wkc_last = Some((wkc, expected, datagram));
                c.wkc_wrong_total += 1;
            }
            return;
        }
        if !self.all_op() || self.ending() {
            return;
        }
        if wkc == expected && datagram.is_none() {
            self.counts.wkc_errors = 0;
            return;
        }
        self.counts.wkc_errors += 1;
        self.counts.wkc_wrong_total += 1;
        self.ev.emit(EventKind::WorkingCounter {
            got: wkc,
            expected,
            missing: scan.missing,
            datagram,
        });
        if self.counts.wkc_errors == self.settings.wkc_errors_before_stop {
            self.ev.emit(EventKind::Stopping {
                reason: StopReason::WorkingCounter,
            });
            for a in self.axes.iter_mut() {
                a.begin_stop(StopKind::Ramp, tick, cycle);
            }
        }
    }

    /// The working counter the last reply should show, and its first logical datagram that
    /// came back wrong: per datagram from the plan when the reply's datagrams were recorded,
    /// else the whole-image value. No allocation.
    fn expected_wkc(&self) -> (u16, Option<DatagramWkc>) {
        let (seen, overflow) = self.pump.logical_seen();
        match &self.wkc_plan {
            Some(plan) if !seen.is_empty() && !overflow => {
                plan.check(seen.iter().map(|d| (d.address, d.len, d.wkc)))
            }
            _ => (self.k.wkc_whole, None),
        }
    }

    /// No reply this cycle: count it, stop the moving axes after a few, end when the segment
    /// has been silent too long.
    fn on_lost(&mut self) -> Option<CycleEnd> {
        let s = self.settings;
        let c = &mut self.counts;
        c.lost_total += 1;
        if self.window.recording() {
            c.recorded_lost += 1;
        }
        c.consecutive_lost += 1;
        let lost = c.consecutive_lost;
        // Each lost cycle up to the stop and the detection; after that the segment counts as
        // lost, and the count comes with `FramesResumed` or `SegmentGone`.
        if lost <= s.lost_before_stop.max(s.segment_lost_after) {
            self.ev.emit(EventKind::FrameLost { consecutive: lost });
        }
        let (tick, cycle) = (self.clock.tick, self.clock.cycle);
        if lost == s.lost_before_stop && !self.ending() {
            self.ev.emit(EventKind::Stopping {
                reason: StopReason::FramesLost { cycles: lost },
            });
            self.stop_moving_axes(tick, cycle);
        }
        if lost == s.segment_lost_after && !self.counts.segment_lost {
            self.counts.segment_lost = true;
            self.ev.emit(EventKind::SegmentLost { cycles: lost });
            self.stop_moving_axes(tick, cycle);
        }
        if u64::from(lost) >= self.k.segment_gone_cycles {
            self.ev.emit(EventKind::SegmentGone { cycles: lost });
            return Some(CycleEnd::SegmentLost);
        }
        None
    }

    /// Begin a ramp stop of every axis not already stopping.
    fn stop_moving_axes(&mut self, tick: u64, cycle: u64) {
        for a in self.axes.iter_mut().filter(|a| a.stopping == Stopping::No) {
            a.begin_stop(StopKind::Ramp, tick, cycle);
        }
    }

    fn begin_ending(&mut self) {
        if !self.ending() {
            self.phase = RunPhase::Ending {
                preop_requested_at: None,
            };
        }
    }

    /// OP: request it once the drives have had [`CycleSettings::safeop_cycles`] cycles of
    /// valid outputs with SYNC0 running (by the reference clock's time; or, should it never
    /// answer, after the OP timeout, and the drives decide), each of the last of them with the
    /// whole working counter, then wait for it. A working counter wrong in SAFE-OP for
    /// [`CycleSettings::wkc_errors_before_stop`] cycles in a row ends the start-up, naming the
    /// device whose outputs are not taken.
    fn request_op(&mut self) -> Option<CycleEnd> {
        let cycle = self.clock.cycle;
        let synchronised = self.clock.dc_time >= self.k.op_not_before_dc
            || cycle * self.k.cycle_ns > self.settings.op_timeout.as_nanos() as u64;
        if self.op == OpState::SafeOp
            && self.counts.safeop_wkc_bad >= self.settings.wkc_errors_before_stop.max(1)
            && let Some((got, expected, datagram)) = self.counts.safeop_wkc_last
        {
            let (lo, hi) = datagram
                .and_then(|d| d.devices)
                .unwrap_or((0, self.addresses.len().saturating_sub(1) as u16));
            let device = (lo..=hi)
                .find(|&p| self.outputs_deactivated(p))
                .unwrap_or(lo);
            let al_state = self
                .al_states
                .get(usize::from(device))
                .copied()
                .unwrap_or(4);
            // An I/O device may enable its outputs in OP only by design (an ESI's OpOnly
            // SyncManager or FMMU): said, and OP requested; a drive must take them.
            let io = self.others.iter().any(|o| o.info.position == device);
            self.ev.emit(EventKind::OutputsNotTaken {
                device,
                got,
                expected,
                datagram,
                io,
            });
            if !io {
                return Some(CycleEnd::OpFailed { device, al_state });
            }
            self.counts.safeop_wkc_tolerated = true;
            self.counts.safeop_wkc_bad = 0;
        }
        match self.op {
            OpState::SafeOp
                if cycle >= u64::from(self.settings.safeop_cycles)
                    && self.counts.safeop_wkc_good >= self.settings.safeop_cycles
                    && synchronised =>
            {
                self.request_al_state(0x0008);
                self.op = OpState::Requested { at: cycle };
            }
            OpState::Requested { at }
                if (cycle - at) * self.k.cycle_ns > self.settings.op_timeout.as_nanos() as u64 =>
            {
                let (device, al_state) = self
                    .al_states
                    .iter()
                    .enumerate()
                    .find(|(_, s)| **s != 8)
                    .map(|(i, s)| (i as u16, *s))
                    .unwrap_or((0, 0));
                self.ev.emit(EventKind::OpTimeout { device, al_state });
                return Some(CycleEnd::OpFailed { device, al_state });
            }
            _ => {}
        }
        None
    }

    /// Whether the device at `position` has an output SyncManager its PDI keeps deactivated
    /// (0x0807 bit 0 of a buffered SM the master writes, with a length): the device that does
    /// not take its outputs. Read once, when start-up fails on it (not in the steady cycle).
    fn outputs_deactivated(&mut self, position: u16) -> bool {
        let Some(&addr) = self.addresses.get(usize::from(position)) else {
            return false;
        };
        let fut = pin!(EcCommand::fprd(addr, 0x0800).receive::<[u8; 64]>(self.md));
        let Ok(Ok(regs)) = exec::exchange(self.pump, fut, monotonic_ns() + self.k.cycle_ns) else {
            return false;
        };
        super::startup::process_data_sms(&regs).any(|(_, sm)| {
            (sm.control >> 2) & 0x03 == 0x01 && sm.activation & 1 != 0 && sm.pdi_control & 1 != 0
        })
    }

    /// Write `state` to every device's AL control register, each within half a cycle.
    fn request_al_state(&mut self, state: u16) {
        for &addr in &self.addresses {
            let fut = pin!(EcCommand::fpwr(addr, register::AL_CONTROL).send(self.md, state));
            let _ = exec::exchange(self.pump, fut, monotonic_ns() + self.k.cycle_ns / 2);
        }
    }

    /// Take the commands that came in.
    fn apply_commands(&mut self) {
        while let Ok(cmd) = self.commands.pop() {
            match cmd {
                Command::Stop(kind) => self.stop(kind, false),
                Command::Restart => self.stop(StopKind::Ramp, true),
                other => {
                    for (i, a) in self.axes.iter_mut().enumerate() {
                        if let Some(why) = a.apply(&other, i) {
                            self.ev.emit(EventKind::CommandRefused {
                                axis: i as u16,
                                why,
                            });
                        }
                    }
                }
            }
        }
    }

    /// A stop (or re-start) was asked for: steady state ends, every axis stops.
    fn stop(&mut self, kind: StopKind, restart: bool) {
        if self.settings.steady_timing_only {
            self.window = match self.window {
                Window::Open | Window::ClosesAfter => Window::ClosesAfter,
                Window::NotYet | Window::OpensNext | Window::Closed => Window::Closed,
            };
        }
        if let Some(h) = self.hooks
            && self.steady
        {
            h.steady_end();
            self.steady = false;
        }
        let cycle = self.clock.cycle;
        if self.ending() {
            if kind == StopKind::QuickStop {
                // Asked again to stop, in a hurry: the axes still on their ramp make a quick
                // stop instead (and are disabled after it, as always).
                for a in self.axes.iter_mut() {
                    if matches!(a.stopping, Stopping::Ramp { .. }) {
                        a.axis.request_quick_stop();
                        a.stopping = Stopping::Quick { at: cycle };
                    }
                }
            }
            return;
        }
        self.begin_ending();
        let (end, reason) = if restart {
            (CycleEnd::Restart, StopReason::Restart)
        } else {
            (CycleEnd::Stopped, StopReason::Requested)
        };
        self.end_reason = Some(end);
        self.ev.emit(EventKind::Stopping { reason });
        let tick = self.clock.tick;
        for a in self.axes.iter_mut() {
            a.begin_stop(kind, tick, cycle);
        }
    }

    /// Per axis: inputs → program → engine → outputs. On a lost cycle the inputs are stale:
    /// every axis holds its set-point (the outputs go out again unchanged), only the drive's
    /// cycle counter (if mapped) advances, as the drive expects one per cycle.
    fn step_axes(&mut self, good: bool) {
        let ctx = StepContext {
            cycle: self.clock.cycle,
            tick: self.clock.tick,
            dt: self.k.dt,
            pulse: self.clock.dc_time / self.k.cycle_ns,
            ending: self.ending(),
            any_energised_before: self.axes.iter().any(|a| {
                a.program != ProgramState::Idle || a.tel.state.is_some_and(State::is_energised)
            }),
            stop_ramp_cycles: self.k.stop_ramp_cycles,
            stop_timeout_cycles: self.k.stop_timeout_cycles,
        };
        let (md, group) = (self.md, self.group);
        let with_app = self.app.is_some();
        // Inputs first, for every axis (and the application's view of it, if there is an
        // application); then the application; then each axis's step.
        for (a, view) in self.axes.iter_mut().zip(self.app_axes.iter_mut()) {
            let Ok(sd) = group.subdevice(md, a.sub) else {
                continue;
            };
            let in_op = good && a.al_state & 0x0F == 8;
            let io = sd.io_raw();
            if in_op {
                a.fb = Some(a.read_inputs(io.inputs(), ctx.pulse));
            }
            if with_app {
                refresh_view(view, a, in_op, io.inputs(), io.outputs());
            }
        }
        if let Some(app) = self.app.as_deref_mut() {
            let ev = &mut self.ev;
            let mut emit = |k: EventKind| ev.emit(k);
            let mut c = AppCycle {
                cycle: ctx.cycle,
                dt: ctx.dt,
                dc_time_ns: self.clock.dc_time,
                axes: &mut self.app_axes,
                events: &mut emit,
            };
            app.cycle(&mut c);
        }
        for (i, (a, view)) in self.axes.iter_mut().zip(self.app_axes.iter()).enumerate() {
            let Ok(sd) = group.subdevice(md, a.sub) else {
                continue;
            };
            if !good {
                a.count(sd.io_raw_mut().outputs());
                continue;
            }
            if a.al_state & 0x0F != 8 {
                a.below_op(sd.io_raw_mut().outputs());
                continue;
            }
            let Some(fb) = a.fb.take() else { continue };
            let out = a.step(i, fb, &ctx, &mut self.ev, with_app.then_some(view));
            let mut io = sd.io_raw_mut();
            a.write_outputs(&out, io.outputs());
            for &(f, raw) in &view.writes {
                let _ = f.write_raw(io.outputs(), raw);
            }
        }
    }

    /// After the steps: a drive that faulted stops every other axis (outside the per-axis
    /// steps, so each axis sees the same decision); stops that take too long end in disable.
    fn supervise_axes(&mut self) {
        let (tick, cycle) = (self.clock.tick, self.clock.cycle);
        let ending = self.ending();
        if !ending && self.axes.iter().any(|a| a.axis.status().fault) {
            for a in self.axes.iter_mut() {
                let st = a.axis.status();
                if !st.fault
                    && a.stopping == Stopping::No
                    && st.state == Some(State::OperationEnabled)
                {
                    a.begin_stop(StopKind::Ramp, tick, cycle);
                }
            }
        }
        for a in self.axes.iter_mut() {
            a.supervise_stop(cycle, self.k.stop_timeout_cycles, ending);
        }
    }

    /// Publish the telemetry: the cycle, every axis, every I/O device.
    /// One sample per axis into the recording, if there is one (a full ring drops and counts).
    fn record_samples(&mut self) {
        let Some(r) = self.record.as_deref_mut() else {
            return;
        };
        let c = &self.clock;
        let (latency, exchange) = (
            u32::try_from(c.latency).unwrap_or(u32::MAX),
            u32::try_from(c.t_ex_done.saturating_sub(c.t_ex)).unwrap_or(u32::MAX),
        );
        for (i, a) in self.axes.iter_mut().enumerate() {
            let t = &a.tel;
            r.push(
                CycleSample {
                    cycle: c.cycle,
                    time_ns: c.woke,
                    wake_latency_ns: latency,
                    exchange_ns: exchange,
                    wkc: self.counts.last_wkc,
                    axis: i as u16,
                    mode_sent: t.mode,
                    demand: Some(t.position_demand),
                    actual: t.position_actual,
                    velocity_demand: Some(t.velocity_demand),
                    velocity: t.velocity_actual,
                    torque_demand: Some(t.torque_demand),
                    torque: t.torque_actual,
                    following_error: a.fe_judged.then_some(t.following_error),
                    statusword: t.statusword,
                    mode: t.mode_display,
                    probes: t.probes,
                }
                .defined(),
            );
            a.fe_judged = false;
        }
    }

    fn publish(&mut self, good: bool) {
        let c = &self.clock;
        let t = self.telemetry.input_buffer_mut();
        t.cycle = CycleTelemetry {
            cycle: c.cycle,
            dc_time: c.dc_time,
            wkc: self.counts.last_wkc,
            wkc_expected: self.counts.last_wkc_expected,
            lost: self.counts.lost_total,
            overruns: self.counts.overruns,
            wake_latency_ns: c.latency,
            exchange_ns: c.t_ex_done - c.t_ex,
            busy_ns: monotonic_ns() - c.woke,
            all_op: self.op == OpState::AllOp,
            lost_in_a_row: self.counts.consecutive_lost,
            phase: if matches!(self.phase, RunPhase::Ending { .. }) {
                Phase::Stopping
            } else {
                Phase::Cycling
            },
            restarts: *self.restarts,
        };
        self.last_telemetry = t.cycle;
        for (slot, a) in t.axes.iter_mut().zip(self.axes.iter()) {
            *slot = a.tel;
        }
        // Every field of every slot each time: the triple buffer hands out three buffers in
        // turn.
        let slots =
            t.io.iter_mut()
                .zip(self.io_last.iter_mut())
                .zip(self.others);
        for ((slot, last), o) in slots {
            let pos = usize::from(o.info.position);
            last.position = o.info.position;
            last.al_state = self.al_states.get(pos).copied().unwrap_or(0);
            if good && let Ok(sd) = self.group.subdevice(self.md, pos) {
                let img = sd.io_raw();
                let inp = img.inputs();
                let n = inp.len().min(IO_TELEMETRY_BYTES);
                last.inputs[..n].copy_from_slice(&inp[..n]);
                last.input_len = n as u16;
            }
            *slot = *last;
        }
        self.telemetry.publish();
    }

    /// Ending and every axis disabled: leave OP while still exchanging process data (drives
    /// in OP with SYNC0 treat missing data as a communication fault): request PRE-OP, and end
    /// once no drive is in OP any more.
    fn leave_op(&mut self) -> Option<CycleEnd> {
        let RunPhase::Ending { preop_requested_at } = self.phase else {
            return None;
        };
        // Energised as last seen (on a lost cycle: as of the last reply). A drive below
        // SAFE-OP sends no valid inputs and takes no outputs (its own state machine has
        // disabled it): its last statusword says nothing, so it does not hold the end up.
        let any_energised = self.axes.iter().any(|a| {
            matches!(a.al_state & 0x0F, 4 | 8) && a.tel.state.is_some_and(State::is_energised)
        });
        let stopping = self
            .axes
            .iter()
            .any(|a| matches!(a.stopping, Stopping::Ramp { .. } | Stopping::Quick { .. }));
        if any_energised || stopping {
            return None;
        }
        let cycle = self.clock.cycle;
        match preop_requested_at {
            None => {
                self.request_al_state(0x0002);
                self.phase = RunPhase::Ending {
                    preop_requested_at: Some(cycle),
                };
            }
            Some(at) => {
                let out_of_op = self.al_states.iter().all(|s| s & 0x0F != 8);
                if out_of_op || (cycle - at) * self.k.cycle_ns > 1_000_000_000 {
                    self.ev.emit(EventKind::Stopped);
                    return Some(self.end_reason.unwrap_or(CycleEnd::Stopped));
                }
            }
        }
        None
    }

    /// The next instant: DC-aligned when the reference clock answered, else one cycle on.
    fn schedule_next(&mut self) {
        let c = &mut self.clock;
        c.next_wake = match c.next_wait {
            Some(w) => c.t_ex + w,
            None => c.next_wake + self.k.cycle_ns,
        };
        if c.next_wake <= monotonic_ns() {
            // Overrun: skip to the next instant rather than running back-to-back cycles.
            c.next_wake = monotonic_ns() + self.k.cycle_ns / 2;
        }
    }

    /// The run has ended: say so until the session publishes what comes next (a whole
    /// snapshot: the input buffer of the triple buffer holds an older one), and report.
    fn finish(self, end: CycleEnd, rt: RtReport) -> CycleReport {
        self.pump.record_logical(false);
        self.pump.set_drift_compensation(true);
        let t = self.telemetry.input_buffer_mut();
        t.cycle = CycleTelemetry {
            phase: Phase::Stopping,
            ..self.last_telemetry
        };
        for (slot, a) in t.axes.iter_mut().zip(self.axes.iter()) {
            *slot = a.tel;
        }
        self.telemetry.publish();
        if let Some(h) = self.hooks
            && self.steady
        {
            h.steady_end();
        }
        let axes = &self.axes;
        CycleReport {
            end,
            cycles: self.clock.cycle,
            lost: self.counts.recorded_lost,
            overruns: self.counts.recorded_overruns,
            timing: self.timing,
            rt,
            first_stop: self.ev.first_stop,
            max_following_error: axes.iter().map(|a| a.tel.max_following_error).collect(),
            max_following_error_drive: axes
                .iter()
                .map(|a| {
                    a.fields
                        .axis
                        .following_error
                        .map(|_| a.tel.max_following_error_drive)
                })
                .collect(),
            following_error_drive_stuck: axes
                .iter()
                .map(|a| a.tel.following_error_drive_stuck)
                .collect(),
            modes_run: axes.iter().map(|a| a.modes_run.clone()).collect(),
            probe_latches: axes.iter().map(|a| a.latches.clone()).collect(),
            max_setpoint_step: axes.iter().map(|a| a.steps).collect(),
            states: axes.iter().map(|a| a.states.clone()).collect(),
            frames: {
                let (now, then) = (self.pump.stats(), self.counts.pump_at_start);
                FrameStats {
                    sent: now.sent - then.sent,
                    answered: now.received - then.received,
                    retransmitted: now.retransmitted - then.retransmitted,
                    lost: self.counts.lost_total,
                    late: self.counts.late_total,
                    wrong_wkc: self.counts.wkc_wrong_total,
                    seconds: self.clock.cycle as f64 * self.k.dt,
                }
            },
        }
    }
}

/// What one reply's AL states showed.
/// Bring the application's view of axis `a` up to date with this cycle's inputs, and clear
/// last cycle's requests.
fn refresh_view(view: &mut AppAxis, a: &AxisRt, in_op: bool, inputs: &[u8], outputs: &[u8]) {
    view.clear_requests();
    view.in_op = in_op;
    if !in_op {
        view.enabled = false;
        return;
    }
    view.tel = a.tel;
    let st = a.axis.status();
    view.tel.state = st.state;
    view.enabled = st.state == Some(State::OperationEnabled) && st.streaming;
    view.program_running = a.program == ProgramState::Running;
    let n = view.inputs.len().min(inputs.len());
    view.inputs[..n].copy_from_slice(&inputs[..n]);
    let n = view.outputs.len().min(outputs.len());
    view.outputs[..n].copy_from_slice(&outputs[..n]);
}

/// The application's view of drive `d` (set-up): every mapped entry, the ones the engine
/// drives marked.
fn app_view(d: &ConfiguredDrive) -> AppAxis {
    let b = &d.fields.axis;
    let mut engine: Vec<usize> = [
        b.controlword,
        b.mode,
        b.target_position,
        b.target_velocity,
        b.target_torque,
        b.velocity_offset,
        b.torque_offset,
        b.ip_position,
    ]
    .into_iter()
    .flatten()
    .map(|f| f.bit_position())
    .collect();
    if let Some((c, _)) = &d.fields.counter {
        engine.push(c.bit_position());
    }
    let rx = d.layout.image(pdo::Direction::Rx);
    let is_engine =
        |a: crate::od::ObjectAddress| rx.find(a).is_some_and(|e| engine.contains(&e.bit_position));
    let dict = crate::od::Dictionary::new(d.profile.dictionary);
    let signed = |a: crate::od::ObjectAddress| dict.data_type(a).is_some_and(|t| t.is_signed());
    AppAxis::new(&d.layout, &is_engine, &signed)
}

struct StateScan {
    /// The first device that did not answer.
    missing: Option<u16>,
    /// Every device is in OP.
    every_op: bool,
    /// The first device that left OP on its own.
    left_op: Option<u16>,
}

impl Default for StateScan {
    fn default() -> Self {
        Self {
            missing: None,
            every_op: true,
            left_op: None,
        }
    }
}

/// Decode a drive's raw AL state for messages.
pub fn al_state_name(raw: u8) -> String {
    let s = crate::ec::AlStatus {
        raw: u16::from(raw),
    };
    s.to_string()
}
