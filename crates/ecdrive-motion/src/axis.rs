//! One axis of the motion runtime: the I/O-free step the masters call once per cycle.
//!
//! Per cycle a master reads its bus into [`Inputs`] ([`MotionAxis::read`]), lets the
//! application run, and calls [`MotionAxis::step`] with the application's [`Requests`] and the
//! cycle's [`StepContext`]; the step runs the program (or the stop ramp, or the application's
//! set-point), homing, the profile modes' handshakes, the touch probes and the following-error
//! supervision, then the CiA 402 engine, and returns the engine's [`Output`] for the bus.
//! Events go to the master's [`EventSink`]. Nothing here allocates or blocks after
//! [`MotionAxis::new`].

use crate::cia402::{
    self, Axis, AxisConfig, AxisStatus, Feedback, ModeSwitchPhase, OperationMode, Output, State,
    StatusWord,
};
use crate::limits::SetpointLimits;
use crate::program::{self, ProbeEdge, RunMode, Runner, Step, Tick};
use crate::setpoint::Sample;
use crate::telemetry::{
    AxisTelemetry, Command, DriveTask, EventKind, ProbeState, StopKind, StopReason,
};
use std::time::Duration;

/// Where the events of an axis's step go (the master stamps them with the cycle and time).
pub trait EventSink {
    /// One event of this cycle.
    fn emit(&mut self, kind: EventKind);
}

/// Which touch-probe objects the drive's process data carry.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ProbeObjects {
    /// 0x60B8 touch probe function (an output).
    pub function: bool,
    /// 0x60B9 touch probe status (an input).
    pub status: bool,
    /// 0x60BA–0x60BD: probe 1 rising, falling; probe 2 rising, falling.
    pub positions: [bool; 4],
}

/// What the runtime needs to know of a drive and its run, from the master's start-up.
#[derive(Debug, Clone)]
pub struct AxisSetup {
    /// The drive's CiA 402 capabilities (modes, state machine, stop codes).
    pub caps: cia402::DriveCaps,
    /// Position units per second of one unit of the drive's velocity objects.
    pub velocity_unit: f64,
    /// Position units per revolution of the motor shaft (for the standstill threshold).
    pub position_per_rev: f64,
    /// The program to run (may be empty).
    pub program: Vec<Step>,
    /// The mode the run starts in.
    pub mode: RunMode,
    /// The master's following-error limit in csp, position units (`None`: not supervised).
    pub following_error_limit: Option<u32>,
    /// What the application's set-points must keep.
    pub limits: SetpointLimits,
    /// The touch-probe objects the process data carry.
    pub probe_objects: ProbeObjects,
    /// In ip the drive interpolates only with controlword bit 4 set (CiA 402; not the
    /// ASDA-A2, which takes 60C1h:01 at each SYNC).
    pub ip_enable_bit: bool,
}

/// **\[REC\]** The speed at or below which an axis counts as standing still for a switch into a
/// position mode, in revolutions of the motor shaft per second (0.6 r/min): entered at that
/// speed, a position mode stops the rest within a few counts. A drive's own zero-speed flag may
/// mean far more (the MR-J4-TM's S_ZSP: below [Pr. PC07], 50 r/min by default), and a real
/// drive's velocity at standstill is never exactly 0.
pub const STANDSTILL_REV_S: f64 = 0.01;

/// [`STANDSTILL_REV_S`] in the drive's velocity units (at least 1).
fn standstill_velocity(setup: &AxisSetup) -> u32 {
    let v = STANDSTILL_REV_S * setup.position_per_rev / setup.velocity_unit;
    if v.is_finite() && v >= 1.0 {
        // In range: checked above, and u32::MAX saturates.
        v.min(f64::from(u32::MAX)) as u32
    } else {
        1
    }
}

/// One cycle's inputs of an axis, as the master read them from the bus.
#[derive(Debug, Clone, Copy)]
pub struct Inputs {
    /// The CiA 402 feedback (statusword, mode display, actual values, error code).
    pub feedback: Feedback,
    /// 0x60B9 (0 where not carried).
    pub probe_status: u16,
    /// 0x60BA–0x60BD (0 where not carried).
    pub probe_positions: [i32; 4],
    /// 0x60F4, the drive's following error, where carried.
    pub following_error_drive: Option<i64>,
}

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
        /// Cycles the axis has stood still with every target given and none reported reached.
        still: u32,
    },
    /// pv or tq: the target went out at good cycle `since` (`None`: the axis is not yet
    /// taking it).
    Profile { index: usize, since: Option<u64> },
}

/// What the application asked of an axis in one cycle (the master fills it from its callback's
/// view of the axis; `Default` when there is no application).
#[derive(Debug, Clone, Copy, Default)]
pub struct Requests {
    /// A set-point in the active mode (csp: position, csv/pv: velocity, cst/tq: torque).
    pub setpoint: Option<f64>,
    /// A mode to switch to.
    pub mode: Option<RunMode>,
    /// A homing, with the method that names it.
    pub home: Option<i8>,
    /// A pp target: (target, relative, immediate).
    pub pp: Option<(f64, bool, bool)>,
    /// A touch probe to arm, on an edge.
    pub probe: Option<(u8, ProbeEdge)>,
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

/// Mode changes an axis keeps for its report (kept without allocating in the cycle); beyond
/// them the last entry follows the newest mode and the rest are counted.
pub const MODES_KEPT: usize = 64;

/// The modes run as a report prints them, each by `name`: `omitted` changes beyond
/// [`MODES_KEPT`] shown as `… (N more)` before the last.
pub fn mode_names(
    modes: &[OperationMode],
    omitted: u32,
    name: fn(&OperationMode) -> String,
) -> Vec<String> {
    let mut names: Vec<String> = modes.iter().map(name).collect();
    if omitted > 0 && !names.is_empty() {
        let at = names.len() - 1;
        names.insert(at, format!("… ({omitted} more)"));
    }
    names
}

/// **\[REC\]** How long an axis may stand still in pp, every target given, without the drive
/// reporting the target reached, before the step counts as failed: a drive whose position window
/// (0x6067/0x6068) is tighter than it settles would otherwise hold the program until
/// [`DRIVE_STEP_TIMEOUT_S`].
const PP_STALL_S: f64 = 5.0;

/// Why a pp step has failed, if it has: no target reached within [`DRIVE_STEP_TIMEOUT_S`], a
/// target not acknowledged, or the axis standing still for [`PP_STALL_S`] (`still` cycles)
/// without the drive reporting the target reached.
fn pp_failure(
    s: &cia402::PpStatus,
    ctx: &StepContext,
    since: u64,
    still: u32,
) -> Option<&'static str> {
    if ctx.tick.saturating_sub(since) as f64 * ctx.dt > DRIVE_STEP_TIMEOUT_S {
        Some(
            "the program stopped: the drive did not report its pp targets reached within 2 \
             minutes",
        )
    } else if s.error.is_some() {
        Some(
            "the program stopped: the drive did not acknowledge a pp target (statusword bit 12 \
             stayed 0 after controlword bit 4 rose)",
        )
    } else if f64::from(still) * ctx.dt > PP_STALL_S {
        Some(
            "the program stopped: the axis has stood still for 5 s with every pp target given, \
             and the drive does not report the target reached (statusword bit 10): is its \
             position window (0x6067, 0x6068) tighter than the axis settles?",
        )
    } else {
        None
    }
}

/// What every axis's step of one cycle shares.
#[derive(Debug, Clone, Copy)]
pub struct StepContext {
    /// The cycle number.
    pub cycle: u64,
    /// Cycles with a reply so far: the clock of the programs and the stop ramps.
    pub tick: u64,
    /// The cycle time in seconds.
    pub dt: f64,
    /// The SYNC0 pulse the frame of this cycle came after (see [`FEEDBACK_PULSES`]).
    pub pulse: u64,
    /// The run is stopping.
    pub ending: bool,
    /// Whether any axis was energised or running a program as of the last cycle.
    pub any_energised_before: bool,
    /// Cycles of a controlled stop's ramp.
    pub stop_ramp_cycles: u64,
    /// Cycles after which a controlled stop disables regardless.
    pub stop_timeout_cycles: u64,
}

/// One axis of the motion runtime: its CiA 402 engine, its program, the profile modes' engines,
/// its probes and stop, and what the run remembers of it. The master reads the bus into
/// [`MotionAxis::read`], calls [`MotionAxis::step`] and writes the [`Output`] to the bus.
pub struct MotionAxis {
    axis: Axis,
    probe_objects: ProbeObjects,
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
    /// Controlword bit 4 in ip ([`AxisSetup::ip_enable_bit`]).
    ip_enable_bit: bool,
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
    tel: AxisTelemetry,
    last_state: Option<State>,
    states: Vec<State>,
    modes_run: Vec<OperationMode>,
    /// Mode changes left out of `modes_run` once it held [`MODES_KEPT`] (the last entry is
    /// always the mode the axis ran in last).
    modes_omitted: u32,
    /// The touch-probe latches of the run (at most [`PROBE_LATCHES`] kept).
    latches: Vec<(u8, ProbeEdge, i64)>,
    steps: SetpointSteps,
    last_out: Option<(i32, i32, i16)>,
    /// What the application's set-points must keep.
    limits: SetpointLimits,
}

impl MotionAxis {
    /// The axis of a drive as `setup` describes it, for cycles of `cycle` (set-up: allocations
    /// allowed), or `None` if its engine cannot be built.
    pub fn new(setup: &AxisSetup, cycle: Duration) -> Option<Self> {
        let caps = setup.caps;
        let initial = setup.mode.operation_mode();
        let config = |mode| {
            let mut c = AxisConfig::for_cycle_time(&caps, cycle, mode);
            c.standstill.velocity = standstill_velocity(setup);
            c
        };
        let axis = Axis::new(caps, config(initial))
            .or_else(|_| Axis::new(caps, config(OperationMode::CyclicSyncPosition)))
            .ok()?;
        Some(Self {
            axis,
            probe_objects: setup.probe_objects,
            velocity_unit: setup.velocity_unit,
            runner: Runner::new(setup.program.clone(), setup.mode),
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
            mode: setup.mode,
            requested_mode: None,
            fe_limit: setup.following_error_limit,
            ip_enable_bit: setup.ip_enable_bit,
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
            tel: AxisTelemetry::default(),
            last_state: None,
            states: Vec::with_capacity(64),
            modes_run: Vec::with_capacity(MODES_KEPT),
            modes_omitted: 0,
            latches: Vec::with_capacity(PROBE_LATCHES),
            steps: SetpointSteps::default(),
            last_out: None,
            limits: setup.limits,
        })
    }

    /// Below the bus's operational state nothing of the drive is judged (a slave may serve
    /// stale inputs until then): the telemetry shows no CiA 402 state.
    pub fn below_op(&mut self) {
        self.tel.state = None;
    }

    /// Take this cycle's inputs (the frame just exchanged carried the demand of the last
    /// cycle; `pulse` is the sync pulse it came after, see [`FEEDBACK_PULSES`]): the unwrapped
    /// position, the probes and the telemetry. Returns the engine's feedback.
    pub fn read(&mut self, inputs: &Inputs, pulse: u64) -> Feedback {
        if let Some(d) = self.last_demand {
            self.carried[self.carried_next] = (pulse, d);
            self.carried_next = (self.carried_next + 1) % CARRIED;
        }
        self.probe_status = inputs.probe_status;
        self.probe_positions = inputs.probe_positions;
        let fb = inputs.feedback;
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
        t.following_error_drive = inputs.following_error_drive;
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
    pub fn step(
        &mut self,
        i: usize,
        fb: Feedback,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
        requests: Requests,
    ) -> Output {
        let actual = self.actual();
        let active = self.axis.active_mode();
        let enabled =
            self.axis.state() == Some(State::OperationEnabled) && self.axis.is_streaming();
        let mut req = requests;
        if self.home_commanded.is_some() {
            req.home = req.home.or(self.home_commanded.take());
        }
        // The steady cycle (no program, stop, homing or request: the axis holds) runs inline,
        // everything else out of line, so the code every cycle runs stays compact: it comes
        // cold from memory after each sleep.
        let quiet = self.program == ProgramState::Idle
            && self.stopping == Stopping::No
            && self.home_by_app.is_none()
            && req.mode.is_none()
            && req.home.is_none()
            && req.pp.is_none()
            && req.setpoint.is_none();
        let sp = if quiet {
            self.hold
        } else {
            self.setpoint(i, actual, enabled, &req, ctx, ev)
        };
        if let Some((probe, edge)) = req.probe {
            self.command_probe(i, probe, edge, ev);
        }
        if enabled {
            self.command(sp, active);
            if self.modes_run.last() != Some(&active) {
                self.mode_ran(active);
            }
        } else if self.stopping == Stopping::No {
            // Not enabled: track the actual values so enabling starts without a jump.
            self.hold = actual;
        }
        if matches!(self.home, HomeRun::Running { .. }) {
            self.homing_step(fb.statusword);
        }
        if RunMode::of(self.axis.active_mode()).is_some_and(RunMode::is_cyclic) {
            // Outside the profile modes their targets are 0: entering one starts from rest.
            self.pv.set_target(0);
            self.tq.set_target(0);
        } else {
            self.profile_mode(i, fb.statusword, actual, ctx, ev);
        }
        if self.probes != [ProbeArm::Off; 2] {
            self.probe(i, ev);
        }
        self.tel.task = self.app_task;
        for (t, p) in self.tel.probes.iter_mut().zip(self.probes) {
            *t = match p {
                ProbeArm::Off => ProbeState::Off,
                ProbeArm::Rearm(edge) | ProbeArm::Armed { edge, .. } => ProbeState::Armed(edge),
                ProbeArm::Latched { edge, position } => ProbeState::Latched { edge, position },
            };
        }
        let out = self.axis.step(&fb);
        if self.axis.has_events() {
            self.engine_events(i, actual, ctx, ev);
        }
        self.record_steps(&out, enabled, ctx.cycle);
        self.follow(i, &out, ctx, ev);
        out
    }

    /// This cycle's set-point with a program, a stop, a homing of the application's or a
    /// request of the application's (out of line; the steady cycle holds): the program's start
    /// and tick, the stop's ramp, the application's requests.
    #[inline(never)]
    fn setpoint(
        &mut self,
        i: usize,
        actual: Sample,
        enabled: bool,
        req: &Requests,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) -> Sample {
        let st = self.axis.status();
        if self.program == ProgramState::Pending && enabled {
            self.runner.seed(actual);
            self.program = ProgramState::Running;
            ev.emit(EventKind::ProgramStep {
                axis: i as u16,
                step: self.runner.step_index() as u16,
            });
        }
        let mut sp = self.stop_setpoint(&st, enabled, ctx);
        if self.stopping == Stopping::No
            && self.program == ProgramState::Running
            && enabled
            && let Some(s) = self.program_setpoint(i, &st, actual, ctx, ev)
        {
            sp = s;
        }
        if let Some(s) = self.app_requests(i, req, &st, enabled, ctx, ev) {
            sp = s;
        }
        sp
    }

    /// A probe the application asked to arm on `edge` (out of line: rare).
    #[cold]
    #[inline(never)]
    fn command_probe(&mut self, i: usize, probe: u8, edge: ProbeEdge, ev: &mut dyn EventSink) {
        if let Err(why) = self.arm_probe(probe, edge) {
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why,
            });
        }
    }

    /// The axis runs in mode `m`, another than the last of [`MotionAxis::modes_run`] (out of
    /// line: rare).
    #[cold]
    #[inline(never)]
    fn mode_ran(&mut self, m: OperationMode) {
        if self.modes_run.len() < MODES_KEPT {
            self.modes_run.push(m);
        } else if let Some(last) = self.modes_run.last_mut() {
            *last = m;
            self.modes_omitted = self.modes_omitted.saturating_add(1);
        }
    }

    /// One cycle of the homing engine (out of line: only while a home step runs).
    #[inline(never)]
    fn homing_step(&mut self, sw: StatusWord) {
        self.homing.step(&mut self.axis, sw);
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
        ev: &mut dyn EventSink,
    ) -> Option<Sample> {
        // Not while a program runs (it owns the mode): not now, as for a pp target.
        if let Some(m) = app.mode
            && self.program == ProgramState::Idle
            && st.active_mode != m.operation_mode()
            && st.mode_switch == ModeSwitchPhase::Idle
            && self.axis.request_mode(m.operation_mode()).is_err()
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
        let mode = RunMode::of(st.active_mode).unwrap_or(self.mode);
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
        self.app_setpoint(i, mode, v, ctx, ev)
    }

    /// The application's set-point `v` in `mode`, checked against its limits: the sample to
    /// command (`None` in the profile modes, where the drive takes the target), or a ramp stop
    /// naming the limit it broke.
    fn app_setpoint(
        &mut self,
        i: usize,
        mode: RunMode,
        v: f64,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) -> Option<Sample> {
        match self
            .limits
            .check(mode, v, (self.hold.pos, self.hold.vel), ctx.dt)
        {
            Ok((vel, acc)) => {
                let sp = match mode {
                    RunMode::Csp | RunMode::Ip => Sample {
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
        let mode = RunMode::of(st.active_mode).unwrap_or(self.mode);
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
        if self.axis.caps().pp_target_outside(target).is_some() {
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

    /// The homing the application asked for (`AppAxis::request_home`): started in
    /// Operation enabled with no program or homing running, then run as a program's home step
    /// is ([`AxisRt::home_step`]); while it runs the held set-point follows the actual one
    /// (returned). Its end, or a stop that cut it short, is what `AppAxis::task` says.
    fn app_home(
        &mut self,
        i: usize,
        request: Option<i8>,
        st: &AxisStatus,
        enabled: bool,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
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
                let drive_brakes = RunMode::of(st.active_mode)
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
    #[inline(never)]
    fn program_setpoint(
        &mut self,
        i: usize,
        st: &AxisStatus,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) -> Option<Sample> {
        let mut sp = None;
        match self.runner.tick(ctx.tick as f64 * ctx.dt) {
            Tick::Setpoint(s) => {
                sp = Some(s);
                self.hold = s;
            }
            Tick::SwitchMode(m) => self.program_mode_switch(i, m, st, actual, ev),
            Tick::Finished(s) => {
                sp = Some(s);
                self.hold = s;
                self.program = ProgramState::Idle;
                ev.emit(EventKind::ProgramDone { axis: i as u16 });
            }
            Tick::Drive { index } => {
                if self.drive_run == DriveRun::Idle {
                    self.start_drive_run(index, ctx.tick);
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
                self.probe_wait(i, probe, expired, ctx, ev);
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

    /// A program's mode switch: none if the axis is in that mode, asked for if no switch is
    /// under way (its ModeSwitched event, or the next look at the active mode, lets the program
    /// go on), refused (the program stops) if the engine will not take it.
    fn program_mode_switch(
        &mut self,
        i: usize,
        m: RunMode,
        st: &AxisStatus,
        actual: Sample,
        ev: &mut dyn EventSink,
    ) {
        let idle = st.mode_switch == ModeSwitchPhase::Idle;
        if idle && st.active_mode == m.operation_mode() {
            // Already in that mode (a run begins by asking for its start mode): no switch, no
            // event; go on at once.
            self.requested_mode = None;
            self.runner.mode_switched(actual);
        } else if idle {
            // Nothing under way (also when an earlier request of this run was cut short): ask
            // for it, from the demand the program left (at rest: held where it is).
            self.requested_mode = Some(m);
            if self.runner.at_rest() {
                self.axis.hold();
            }
            if self.axis.request_mode(m.operation_mode()).is_err() {
                self.requested_mode = None;
                ev.emit(EventKind::CommandRefused {
                    axis: i as u16,
                    why: "the program's mode switch was refused",
                });
                self.program = ProgramState::Idle;
            }
        }
    }

    /// The program's step `index` hands the motion to the drive (pp, pv, tq) at good cycle
    /// `tick`.
    fn start_drive_run(&mut self, index: usize, tick: u64) {
        self.drive_run = match self.runner.steps().get(index) {
            Some(Step::Pp { .. }) => {
                self.pp.set_halt(false);
                DriveRun::Pp {
                    index,
                    given: 0,
                    settled: 0,
                    reached: false,
                    since: tick,
                    still: 0,
                }
            }
            _ => DriveRun::Profile { index, since: None },
        };
    }

    /// A program's wait for touch probe `probe`: it goes on once the probe latched; when the
    /// wait expired first, the program stops and so does the axis (the run then stops the
    /// others).
    fn probe_wait(
        &mut self,
        i: usize,
        probe: u8,
        expired: bool,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) {
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
            self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
        }
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
        ev: &mut dyn EventSink,
    ) {
        let idle = st.mode_switch == ModeSwitchPhase::Idle;
        match self.home {
            HomeRun::Idle => self.request_hm(i, ctx, ev),
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
                    if self.axis.request_mode(self.mode.operation_mode()).is_err() {
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
                if idle && st.active_mode == self.mode.operation_mode() {
                    self.home = HomeRun::Idle;
                    if self.home_by_app.is_none() {
                        self.runner.drive_done(actual);
                    }
                    self.hold = actual;
                }
            }
        }
    }

    /// A home step begins: hm requested (the engine handles the zero-speed rule); a refusal
    /// stops the program and the axis.
    fn request_hm(&mut self, i: usize, ctx: &StepContext, ev: &mut dyn EventSink) {
        self.home = HomeRun::ToHm;
        if self.runner.at_rest() {
            self.axis.hold();
        }
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
    #[inline(never)]
    fn profile_mode(
        &mut self,
        i: usize,
        sw: StatusWord,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) {
        let Some(mode) = RunMode::of(self.axis.active_mode()).filter(|m| !m.is_cyclic()) else {
            // Outside the profile modes their targets are 0: entering one starts from rest.
            self.pv.set_target(0);
            self.tq.set_target(0);
            return;
        };
        let stopping = self.stopping != Stopping::No;
        let streaming = self.axis.is_streaming();
        let enabled = self.axis.state() == Some(State::OperationEnabled) && streaming;
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
            (RunMode::Pp, _) => self.app_pp_step(sw, stopping),
            (RunMode::Pv | RunMode::Tq, DriveRun::Profile { index, since }) => {
                let since = since.or(streaming.then_some(ctx.tick));
                self.profile_step(i, mode, (index, since), sw, actual, ctx, ev);
            }
            _ => self.hold_profile(mode, sw),
        }
    }

    /// One cycle of program step `index` in pv or tq, the drive's target switched since good
    /// cycle `since` (`None`: not yet streaming): the step's target until its time is up, then
    /// 0, and the step's end once the drive is back at rest.
    #[allow(clippy::too_many_arguments)]
    fn profile_step(
        &mut self,
        i: usize,
        mode: RunMode,
        (index, since): (usize, Option<u64>),
        sw: StatusWord,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) {
        self.drive_run = DriveRun::Profile { index, since };
        let t = since.map_or(0.0, |s| ctx.tick.saturating_sub(s) as f64 * ctx.dt);
        let done = match self.runner.steps().get(index) {
            Some(&Step::Pv {
                velocity, seconds, ..
            }) if mode == RunMode::Pv => {
                let on = since.is_none() || t < seconds;
                let v = self.drive_velocity(velocity);
                self.pv.set_target(if on { v } else { 0 });
                let s = self.pv.step(&mut self.axis, sw);
                if t > seconds + DRIVE_STEP_TIMEOUT_S {
                    let why = "the program stopped: the drive did not report velocity 0 \
                               reached within 2 minutes of the pv step's end";
                    return self.drive_step_failed(i, why, ctx, ev);
                }
                !on && s.streaming && s.target_reached
            }
            Some(&Step::Tq {
                torque,
                slope,
                seconds,
            }) if mode == RunMode::Tq => {
                let ramp = program::tq_ramp(torque, slope);
                let on = since.is_none() || t < ramp + seconds;
                self.tq
                    .set_target(if on { drive_torque(torque) } else { 0 });
                let s = self.tq.step(&mut self.axis, sw);
                !on && s.streaming && self.tq_settled(t, torque, seconds, ramp, ctx.dt)
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

    /// pp with no program step: the handshake of the application's targets (halted while the
    /// axis stops), and what [`DriveTask`] says of them.
    fn app_pp_step(&mut self, sw: StatusWord, stopping: bool) {
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

    /// A pp, pv or tq step that cannot end as it should: the step is left, the program stops
    /// (naming `why`) and so does the axis.
    fn drive_step_failed(
        &mut self,
        i: usize,
        why: &'static str,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) {
        self.abort_drive_run();
        self.program = ProgramState::Idle;
        ev.emit(EventKind::CommandRefused {
            axis: i as u16,
            why,
        });
        self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
    }

    /// A tq step of `torque` for `seconds` with ramps of `ramp`, `t` seconds after it began:
    /// done once the ramp down has had its time and the drive reports the torque back near 0
    /// (a drive whose slope unit differs from its profile's takes longer), or, without that,
    /// after twice the time.
    fn tq_settled(&self, t: f64, torque: f64, seconds: f64, ramp: f64, dt: f64) -> bool {
        let settle = f64::from(cia402::profile_velocity::SETTLE_CYCLES) * dt;
        let down = t >= 2.0 * ramp + seconds + settle;
        let near_zero = f64::from(self.tel.torque_actual).abs() <= (torque.abs() / 50.0).max(1.0);
        down && (near_zero || t >= 4.0 * ramp + seconds + TQ_SETTLE_MAX_S)
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
        ev: &mut dyn EventSink,
    ) {
        let DriveRun::Pp {
            index,
            mut given,
            mut settled,
            reached,
            since,
            still,
        } = self.drive_run
        else {
            return;
        };
        let Some(Step::Pp {
            targets,
            relative,
            immediate,
            ..
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
        let still = if given == n && s.queued == 0 && !s.target_reached && self.axis.standstill() {
            still.saturating_add(1)
        } else {
            0
        };
        if let Some(why) = pp_failure(&s, ctx, since, still) {
            return self.drive_step_failed(i, why, ctx, ev);
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
            still,
        };
    }

    /// The application or a command arms a probe: taken with no program running and the
    /// probe's objects mapped.
    fn arm_probe(&mut self, probe: u8, edge: ProbeEdge) -> Result<(), &'static str> {
        let pf = &self.probe_objects;
        let slot =
            (usize::from(probe.clamp(1, 2)) - 1) * 2 + usize::from(edge == ProbeEdge::Falling);
        let mapped = pf.function && pf.status && pf.positions.get(slot).copied().unwrap_or(false);
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
    #[inline(never)]
    fn probe(&mut self, i: usize, ev: &mut dyn EventSink) {
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

    /// The set-point into the engine, in the active mode (`active`, as the step began).
    fn command(&mut self, sp: Sample, active: OperationMode) {
        let mode = RunMode::of(active).unwrap_or(self.mode);
        self.mode = mode;
        let _ = match mode {
            // The drive generates the motion; `profile_mode` gives it its targets.
            RunMode::Pp | RunMode::Pv | RunMode::Tq => Ok(()),
            RunMode::Csp => self.axis.set_position(round_i64(sp.pos) as i32),
            RunMode::Ip => {
                let bits = if self.ip_enable_bit {
                    cia402::interpolated::ENABLE_IP
                } else {
                    cia402::ControlWord::empty()
                };
                self.axis.set_mode_bits(bits);
                self.axis.set_position(round_i64(sp.pos) as i32)
            }
            RunMode::Csv => self.axis.set_velocity(self.drive_velocity(sp.vel)),
            RunMode::Cst => self.axis.set_torque(drive_torque(sp.torque)),
        };
    }

    /// The engine's events of this step: mode switches the program waits for, faults (out of
    /// line: rare).
    #[cold]
    #[inline(never)]
    fn engine_events(
        &mut self,
        i: usize,
        actual: Sample,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) {
        while let Some(e) = self.axis.poll_event() {
            match e {
                cia402::Event::ModeSwitched { to, .. } => {
                    if let Some(m) = RunMode::of(to) {
                        self.mode = m;
                        if self.requested_mode == Some(m) {
                            self.requested_mode = None;
                            self.runner.mode_switched(actual);
                        }
                    }
                }
                cia402::Event::ModeSwitchFailed(f) => self.mode_switch_failed(i, f, ctx, ev),
                cia402::Event::Fault { .. } if !ctx.ending => {
                    self.fault(i, e, ctx, ev);
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

    /// A mode switch the engine gave up: a home step, a program waiting for its start mode or
    /// a program's switch cannot go on (the program stops, and the axis does not stay enabled
    /// in the mode it was leaving). A fault that cut it short is reported as the fault.
    fn mode_switch_failed(
        &mut self,
        i: usize,
        f: cia402::ModeSwitchError,
        ctx: &StepContext,
        ev: &mut dyn EventSink,
    ) {
        let by_fault = f.reason == cia402::ModeSwitchFailure::Fault;
        let why = if matches!(self.home, HomeRun::ToHm | HomeRun::Back) {
            // The switch into or out of hm failed: the home step cannot go on.
            self.home = HomeRun::Idle;
            "the program stopped: the switch into or out of homing mode failed"
        } else if self.program == ProgramState::Pending && !by_fault {
            // The drive never took the mode the program starts in: the program cannot start.
            "the program could not start: the drive did not take its start mode"
        } else if self.requested_mode.is_some() {
            // The program asked for this switch and cannot go on without it.
            self.requested_mode = None;
            "the program stopped: its mode switch failed"
        } else {
            return;
        };
        self.program = ProgramState::Idle;
        if !by_fault {
            ev.emit(EventKind::CommandRefused {
                axis: i as u16,
                why,
            });
            self.begin_stop(StopKind::Ramp, ctx.tick, ctx.cycle);
        }
    }

    /// The drive faulted (outside the run's end): the program stops, a home step gives its
    /// account first, the fault is reported; the other axes are stopped after the per-axis
    /// steps (a fault while nothing was energised, latched before the run, stops nothing).
    fn fault(&mut self, i: usize, e: cia402::Event, ctx: &StepContext, ev: &mut dyn EventSink) {
        self.program = ProgramState::Idle;
        if let HomeRun::Running { method } = self.home {
            // A drive that faults on a homing error (the BDHDE's 0x6100).
            ev.emit(EventKind::HomingFailed {
                axis: i as u16,
                method,
                outcome: self
                    .homing
                    .outcome()
                    .unwrap_or(cia402::HomingOutcome::Aborted),
                // The fault itself is reported with its own code (a loss-of-data alarm during
                // homing is not the drive's homing error): no guess at its name here.
                drive_says: "",
            });
        }
        self.abort_home();
        ev.emit(EventKind::Axis {
            axis: i as u16,
            event: e,
        });
        if ctx.any_energised_before {
            ev.emit(EventKind::Stopping {
                reason: StopReason::DriveFault { axis: i as u16 },
            });
        }
    }

    /// Set-point steps while enabled, in the mode the drive runs (confirmed by 0x6061): the
    /// other targets only track the actual values.
    fn record_steps(&mut self, out: &Output, enabled: bool, cycle: u64) {
        if !(enabled && self.axis.is_streaming()) {
            self.last_out = None;
            return;
        }
        if let Some((p, v, t)) = self.last_out {
            let s = &mut self.steps;
            let step = match RunMode::of(self.axis.active_mode()) {
                Some(RunMode::Csp | RunMode::Ip) => Some((
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
    fn follow(&mut self, i: usize, out: &Output, ctx: &StepContext, ev: &mut dyn EventSink) {
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
        let homing = !RunMode::of(out.mode).is_some_and(RunMode::is_cyclic);
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
        // The master's following error only while csp or ip runs (in hm the drive moves on its
        // own).
        self.fe_judged =
            energised && self.mode.streams_position() && out.mode == self.mode.operation_mode();
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
    fn judge_following_error(
        &mut self,
        i: usize,
        moving: bool,
        cycle: u64,
        ev: &mut dyn EventSink,
    ) {
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
                    self.drive_fe_stuck(i, ev);
                }
            }
        }
        if let Some(limit) = self.fe_limit
            && fe > i64::from(limit)
            && self.stopping == Stopping::No
        {
            self.following_error_exceeded(i, fe, limit, cycle, ev);
        }
    }

    /// 0x60F4 stayed 0 for [`DRIVE_FE_STUCK_CYCLES`] cycles of motion: flagged once (out of
    /// line: rare).
    #[cold]
    #[inline(never)]
    fn drive_fe_stuck(&mut self, i: usize, ev: &mut dyn EventSink) {
        self.tel.following_error_drive_stuck = true;
        ev.emit(EventKind::DriveFollowingErrorStuck {
            axis: i as u16,
            cycles: self.fe_drive_zero_cycles,
            master: self.tel.max_following_error,
        });
    }

    /// The following error `fe` went beyond `limit`: a quick stop (out of line: rare).
    #[cold]
    #[inline(never)]
    fn following_error_exceeded(
        &mut self,
        i: usize,
        fe: i64,
        limit: u32,
        cycle: u64,
        ev: &mut dyn EventSink,
    ) {
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

    /// Begin a controlled stop at good cycle `tick` (the ramp's clock) and cycle `cycle` (the
    /// timeout's).
    pub fn begin_stop(&mut self, kind: StopKind, tick: u64, cycle: u64) {
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
    pub fn supervise_stop(&mut self, cycle: u64, stop_timeout_cycles: u64, ending: bool) {
        if let Stopping::Ramp { since: at, .. } | Stopping::Quick { at } = self.stopping
            && cycle - at > stop_timeout_cycles
        {
            self.axis.request_disable();
            self.stopping = Stopping::Disabling;
        }
        if self.stopping == Stopping::Disabling
            && !self.axis.state().is_some_and(State::is_energised)
            && !ending
        {
            self.stopping = Stopping::No;
        }
    }

    /// Apply a command to this axis (number `i`); `Some(reason)` if it was refused.
    pub fn apply(&mut self, cmd: &Command, i: usize) -> Option<&'static str> {
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
            // A running program owns the axis's mode (it would take its own back at its next
            // step): refused, as a pp target or a set-point is.
            Command::Mode(ax, _) if ax.includes(i) && self.program != ProgramState::Idle => {
                Some("mode switch refused: a program runs on the axis")
            }
            Command::Mode(ax, m) if ax.includes(i) => self
                .axis
                .request_mode(m.operation_mode())
                .err()
                .map(|_| "mode switch refused"),
            Command::RunProgram(ax) if ax.includes(i) => self.run_program(),
            Command::HoldProgram(ax) if ax.includes(i) => {
                self.program = ProgramState::Idle;
                self.abort_home();
                None
            }
            Command::Home(ax, method) if ax.includes(i) => self.command_home(method),
            Command::Pp {
                axis,
                target,
                relative,
                immediate,
            } if axis as usize == i => self.take_pp(target, relative, immediate).err().map(|e| e.1),
            Command::ArmProbe { axis, probe, edge } if axis as usize == i => {
                self.arm_probe(probe, edge).err()
            }
            Command::Setpoint(axis, v) if axis as usize == i => self.command_setpoint(v),
            Command::Move {
                axis,
                to,
                velocity,
                acceleration,
            } if axis as usize == i => self.command_move(to, velocity, acceleration),
            _ => None,
        }
    }

    /// [`Command::RunProgram`]: the program from its start, once the axis is enabled.
    fn run_program(&mut self) -> Option<&'static str> {
        self.runner.use_program();
        if self.runner.steps().is_empty() {
            return Some("the axis has no program");
        }
        self.runner.restart();
        self.requested_mode = None;
        self.abort_home();
        self.probes = [ProbeArm::Off; 2];
        self.program = ProgramState::Pending;
        None
    }

    /// [`Command::Home`]: taken (as the application's request is, next step) in Operation
    /// enabled with no program or homing running.
    fn command_home(&mut self, method: i8) -> Option<&'static str> {
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

    /// [`Command::Move`]: a csp move run as a one-step program in the program's place. Its
    /// limits must be positive, finite and within the axis's set-point limits.
    fn command_move(&mut self, to: f64, velocity: f64, acceleration: f64) -> Option<&'static str> {
        let st = self.axis.status();
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let within = |v: f64, max: Option<f64>| max.is_none_or(|m| v <= m);
        if st.state != Some(State::OperationEnabled) || self.stopping != Stopping::No {
            Some("move refused: the axis is not enabled")
        } else if self.program == ProgramState::Running
            || self.home != HomeRun::Idle
            || self.home_commanded.is_some()
            || self.drive_run != DriveRun::Idle
        {
            Some("move refused: a program, homing or pp move runs on the axis")
        } else if !to.is_finite() || !positive(velocity) || !positive(acceleration) {
            Some("move refused: the target must be finite, the velocity and acceleration positive")
        } else if !within(velocity, self.limits.max_velocity)
            || !within(acceleration, self.limits.max_acceleration)
        {
            Some("move refused: its velocity or acceleration is over the axis's set-point limits")
        } else {
            let step = Step::Move {
                target: program::Target::To(to),
                velocity,
                acceleration,
                jerk: None,
            };
            self.runner.run_single(step, RunMode::Csp);
            self.requested_mode = None;
            self.program = ProgramState::Pending;
            None
        }
    }

    /// [`Command::Setpoint`]: the held set-point of the cyclic mode the axis runs.
    fn command_setpoint(&mut self, v: f64) -> Option<&'static str> {
        match self.mode {
            RunMode::Csp | RunMode::Ip => self.hold.pos = v,
            RunMode::Csv => self.hold.vel = v,
            RunMode::Cst => self.hold.torque = v,
            RunMode::Pp | RunMode::Pv | RunMode::Tq => {
                return Some("a set-point command needs csp, csv, cst or ip");
            }
        }
        None
    }
}

/// What the master reads of an axis between steps.
impl MotionAxis {
    /// The engine's status.
    pub fn status(&self) -> AxisStatus {
        self.axis.status()
    }

    /// The CiA 402 state (as [`status`](Self::status) has it, without building the rest).
    pub fn state(&self) -> Option<State> {
        self.axis.state()
    }

    /// A fault is present (as [`status`](Self::status) has it).
    pub fn faulted(&self) -> bool {
        self.axis.fault()
    }

    /// The axis's telemetry as of its last step.
    pub fn telemetry(&self) -> &AxisTelemetry {
        &self.tel
    }

    /// The telemetry, for the bus's own fields (the AL state of an EtherCAT device).
    pub fn telemetry_mut(&mut self) -> &mut AxisTelemetry {
        &mut self.tel
    }

    /// Whether a program runs or waits to start, or the drive is energised.
    pub fn busy(&self) -> bool {
        self.program != ProgramState::Idle || self.tel.state.is_some_and(State::is_energised)
    }

    /// Whether a program runs on the axis.
    pub fn program_running(&self) -> bool {
        self.program == ProgramState::Running
    }

    /// Whether a controlled stop is under way (ramp, quick stop or disable).
    pub fn stopping(&self) -> bool {
        self.stopping != Stopping::No
    }

    /// Whether the axis is still braking (ramp or quick stop), not yet disabling.
    pub fn braking(&self) -> bool {
        matches!(
            self.stopping,
            Stopping::Ramp { .. } | Stopping::Quick { .. }
        )
    }

    /// Asked again to stop, in a hurry: an axis still on its ramp makes a quick stop instead
    /// (and is disabled after it, as always).
    pub fn hurry_stop(&mut self, cycle: u64) {
        if matches!(self.stopping, Stopping::Ramp { .. }) {
            self.axis.request_quick_stop();
            self.stopping = Stopping::Quick { at: cycle };
        }
    }

    /// Whether the last step judged the following error (energised in csp), cleared by the
    /// call: the recording shows the following error only in those cycles.
    pub fn take_fe_judged(&mut self) -> bool {
        core::mem::take(&mut self.fe_judged)
    }

    /// Whether the last step judged the master's following error (csp or ip, energised), for
    /// a recording that reads it without taking it.
    pub fn fe_judged(&self) -> bool {
        self.fe_judged
    }

    /// 0x60B8 to write, once a probe was armed.
    pub fn probe_function(&self) -> Option<u16> {
        self.probe_function
    }

    /// The CiA 402 states the axis went through (at most 64).
    pub fn states(&self) -> &[State] {
        &self.states
    }

    /// The modes the axis ran in, in order (at most 8 changes).
    /// Mode changes beyond [`MODES_KEPT`] not in [`Self::modes_run`].
    pub fn modes_omitted(&self) -> u32 {
        self.modes_omitted
    }

    /// The modes the axis ran in while enabled, in order (at most [`MODES_KEPT`]; see
    /// [`Self::modes_omitted`]).
    pub fn modes_run(&self) -> &[OperationMode] {
        &self.modes_run
    }

    /// The touch-probe latches of the run: (probe, edge, position).
    pub fn latches(&self) -> &[(u8, ProbeEdge, i64)] {
        &self.latches
    }

    /// The largest set-point steps while enabled.
    pub fn setpoint_steps(&self) -> SetpointSteps {
        self.steps
    }
}

/// A torque in the drive's unit as its torque value (0x6071), rounded and held to its range.
/// `x.round() as i64` (half away from zero, saturating, NaN as 0) without the library call
/// that `f64::round` is on a CPU without SSE4.1: the csp set-point of every cycle.
fn round_i64(x: f64) -> i64 {
    let r = x as i64;
    let frac = x - r as f64;
    if frac >= 0.5 {
        r.saturating_add(1)
    } else if frac <= -0.5 {
        r.saturating_sub(1)
    } else {
        r
    }
}

fn drive_torque(t: f64) -> i16 {
    t.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `round_i64` is `f64::round` then `as i64`, halves, signs, large values, infinities and
    /// NaN included.
    #[test]
    fn round_i64_is_round_then_as() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            4503599627370497.0,
            9.2e18,
            -9.2e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
        ];
        // And a deterministic spread of ordinary set-points.
        let mut v = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..10_000 {
            v ^= v << 13;
            v ^= v >> 7;
            v ^= v << 17;
            xs.push((v as i64 as f64) / 4096.0);
        }
        for x in xs {
            assert_eq!(round_i64(x), x.round() as i64, "{x}");
        }
    }

    fn ctx(tick: u64) -> StepContext {
        StepContext {
            cycle: tick,
            tick,
            dt: 0.001,
            pulse: tick,
            ending: false,
            any_energised_before: true,
            stop_ramp_cycles: 200,
            stop_timeout_cycles: 2000,
        }
    }

    fn status() -> cia402::PpStatus {
        cia402::PpStatus {
            phase: cia402::PpPhase::Idle,
            queued: 0,
            acknowledged: 1,
            target_reached: false,
            following_error: false,
            aborted: false,
            error: None,
        }
    }

    /// An axis that stands at its pp target without the drive reporting it reached (a
    /// position window tighter than it settles) fails the step after 5 s, naming the window,
    /// instead of holding the program for two minutes.
    #[test]
    fn a_pp_step_standing_still_without_target_reached_fails_after_5_s() {
        let s = status();
        assert_eq!(pp_failure(&s, &ctx(3000), 0, 5000), None);
        let why = pp_failure(&s, &ctx(6000), 0, 5001).expect("stalled");
        assert!(why.contains("0x6067"), "{why}");
        // Still turning (the counter restarts whenever it moves): two minutes at most.
        assert_eq!(pp_failure(&s, &ctx(119_000), 0, 10), None);
        assert!(pp_failure(&s, &ctx(120_001), 0, 10).is_some_and(|w| w.contains("2 minutes")));
    }
}
