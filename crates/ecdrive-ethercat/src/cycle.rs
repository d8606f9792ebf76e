//! The cycle: one thread, absolute-time sleeps on the DC-aligned cycle, one process-data
//! exchange, one CiA 402 step per axis, every cycle.
//!
//! Per cycle: sleep until the instant (`clock_nanosleep`, absolute), exchange the process data
//! (`tx_rx_dc`, pumped inline by [`exec::exchange`]: the frame I/O is this thread's own), check
//! the working counter and every drive's AL state, read each drive's inputs through its
//! resolved fields, take commands, step each axis of the motion runtime
//! ([`ecdrive_motion::MotionAxis`]: the program, homing, the profile modes, the probes, the
//! stops and the CiA 402 engine), write the outputs, publish telemetry and events. After start-up nothing here allocates, locks
//! anything another thread takes, or makes a syscall other than the frame I/O and the sleep —
//! `tests/cycle_audit.rs` proves it with a counting allocator and per-thread syscall counters.
//!
//! The cycle itself takes the drives from SAFE-OP to OP (after some cycles of valid outputs),
//! and stops them in a controlled way on request, on a fault, on lost frames or when a drive
//! leaves OP: ramp (or quick stop), then disable. Ending the cycle hands the bus back to the
//! session, which takes the drives to INIT.

use super::app::{AppAxis, AppCycle, CycleApp};
use super::exec::{self, ExchangeError};
use super::io::{FrameLink, Pump};
use super::program::ProbeEdge;
use super::record::{CycleSample, RecordTx};
use super::startup::{ConfiguredDrive, ConfiguredIo, DriveFields, Group};
use super::telemetry::{
    AxisTelemetry, Command, CycleTelemetry, Event, EventKind, IO_TELEMETRY_BYTES, IoTelemetry,
    Phase, StopKind, StopReason, Telemetry,
};
use super::wkc::{DatagramWkc, WkcPlan};
use crate::cia402::{Feedback, OperationMode, Output, State};
use crate::ec::register;
use crate::pdo;
use crate::rt::{LatencyHistogram, RtReport, RtSettings, monotonic_ns, sleep_until_ns};
use ecdrive_motion::{
    AxisSetup, EventSink, Inputs, MotionAxis, ProbeObjects, Requests, StepContext,
};
pub use ecdrive_motion::{DRIVE_FE_STUCK_CYCLES, FEEDBACK_PULSES, SetpointSteps};
use ethercrab::subdevice_group::{HasDc, SafeOp};
use ethercrab::{Command as EcCommand, MainDevice, SubDeviceState};
use std::pin::pin;
use std::time::Duration;

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

impl EventSink for Emitter<'_> {
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

/// One drive on the segment: its place in the process image, what the bus side remembers of
/// it, and its axis of the motion runtime.
struct AxisRt {
    /// Position on the segment (index in the group).
    sub: usize,
    fields: DriveFields,
    counter: u8,
    al_state: u8,
    /// This cycle's inputs, read before the application runs.
    fb: Option<Feedback>,
    m: MotionAxis,
}

impl AxisRt {
    /// The axis of drive `d` (set-up: allocations allowed), or `None` if its engine cannot be
    /// built.
    fn new(d: &ConfiguredDrive, cycle: Duration) -> Option<Self> {
        let pf = &d.fields.probe;
        let setup = AxisSetup {
            caps: d.profile.caps,
            velocity_unit: d.profile.units.velocity_position_per_s(),
            program: d.setup.program.clone(),
            mode: d.setup.mode,
            following_error_limit: d.setup.following_error_limit,
            limits: d.setup.limits,
            probe_objects: ProbeObjects {
                function: pf.function.is_some(),
                status: pf.status.is_some(),
                positions: pf.positions.map(|p| p.is_some()),
            },
        };
        Some(Self {
            sub: usize::from(d.info.position),
            fields: d.fields.clone(),
            counter: 0,
            al_state: 0,
            fb: None,
            m: MotionAxis::new(&setup, cycle)?,
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
        self.m.below_op();
        self.m.telemetry_mut().al_state = self.al_state;
    }

    /// Read this cycle's inputs from the process image into the motion axis.
    fn read_inputs(&mut self, inputs: &[u8], pulse: u64) -> Feedback {
        let pf = &self.fields.probe;
        let b = &self.fields.axis;
        let read = Inputs {
            feedback: b.feedback(inputs),
            probe_status: pdo::axis::read(pf.status, inputs).unwrap_or(0) as u16,
            probe_positions: pf
                .positions
                .map(|f| pdo::axis::read(f, inputs).unwrap_or(0) as i32),
            following_error_drive: b.following_error(inputs),
        };
        self.m.read(&read, pulse)
    }

    /// The engine's outputs into the process image, and the cycle counter.
    fn write_outputs(&mut self, out: &Output, image: &mut [u8]) {
        self.fields.axis.write(out, image);
        if let Some(f) = self.m.probe_function() {
            pdo::axis::write(self.fields.probe.function, image, i64::from(f));
        }
        self.count(image);
        self.m.telemetry_mut().al_state = self.al_state;
    }
}

/// What the application's callback ([`AppAxis`]) asked of an axis in one cycle.
fn requests_of(app: &AppAxis) -> Requests {
    Requests {
        setpoint: app.setpoint,
        mode: app.mode_request,
        home: app.home_request,
        pp: app.pp_request,
        probe: app.probe_request,
    }
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
                a.m.begin_stop(StopKind::Ramp, tick, cycle);
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
                a.m.begin_stop(StopKind::Ramp, tick, cycle);
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
        for a in self.axes.iter_mut().filter(|a| !a.m.stopping()) {
            a.m.begin_stop(StopKind::Ramp, tick, cycle);
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
                        if let Some(why) = a.m.apply(&other, i) {
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
                    a.m.hurry_stop(cycle);
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
            a.m.begin_stop(kind, tick, cycle);
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
            any_energised_before: self.axes.iter().any(|a| a.m.busy()),
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
            let req = if with_app {
                requests_of(view)
            } else {
                Requests::default()
            };
            let out = a.m.step(i, fb, &ctx, &mut self.ev, req);
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
        if !ending && self.axes.iter().any(|a| a.m.status().fault) {
            for a in self.axes.iter_mut() {
                let st = a.m.status();
                if !st.fault && !a.m.stopping() && st.state == Some(State::OperationEnabled) {
                    a.m.begin_stop(StopKind::Ramp, tick, cycle);
                }
            }
        }
        for a in self.axes.iter_mut() {
            a.m.supervise_stop(cycle, self.k.stop_timeout_cycles, ending);
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
            let judged = a.m.take_fe_judged();
            let t = a.m.telemetry();
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
                    following_error: judged.then_some(t.following_error),
                    statusword: t.statusword,
                    mode: t.mode_display,
                    probes: t.probes,
                }
                .defined(),
            );
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
            *slot = *a.m.telemetry();
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
            matches!(a.al_state & 0x0F, 4 | 8)
                && a.m.telemetry().state.is_some_and(State::is_energised)
        });
        let stopping = self.axes.iter().any(|a| a.m.braking());
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
            *slot = *a.m.telemetry();
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
            max_following_error: axes
                .iter()
                .map(|a| a.m.telemetry().max_following_error)
                .collect(),
            max_following_error_drive: axes
                .iter()
                .map(|a| {
                    a.fields
                        .axis
                        .following_error
                        .map(|_| a.m.telemetry().max_following_error_drive)
                })
                .collect(),
            following_error_drive_stuck: axes
                .iter()
                .map(|a| a.m.telemetry().following_error_drive_stuck)
                .collect(),
            modes_run: axes.iter().map(|a| a.m.modes_run().to_vec()).collect(),
            probe_latches: axes.iter().map(|a| a.m.latches().to_vec()).collect(),
            max_setpoint_step: axes.iter().map(|a| a.m.setpoint_steps()).collect(),
            states: axes.iter().map(|a| a.m.states().to_vec()).collect(),
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
    view.tel = *a.m.telemetry();
    let st = a.m.status();
    view.tel.state = st.state;
    view.enabled = st.state == Some(State::OperationEnabled) && st.streaming;
    view.program_running = a.m.program_running();
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
