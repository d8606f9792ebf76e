//! What the cycle tells the supervisory side, and what it takes from it — all lock-free.
//!
//! - [`Command`]s go in through a wait-free SPSC ring (`rtrb`); the cycle pops them without
//!   blocking.
//! - [`Event`]s come out through another SPSC ring: state changes, faults, working-counter
//!   mismatches, lost frames, program progress. Fixed-size values; the supervisory side turns
//!   them into the readable error history (with alarm names) outside the cycle.
//! - [`Telemetry`] is the latest snapshot, published each cycle through a triple buffer
//!   (`triple_buffer`): the cycle writes into a pre-allocated back buffer and publishes; readers
//!   always get a complete, recent snapshot, and neither side ever waits for the other.

use super::program::RunMode;
use crate::cia402;
use serde::Serialize;

/// Which axes a command addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Axes {
    /// Every axis.
    All,
    /// One axis, by its index (the drive's position among the configured drives).
    One(u16),
}

impl Axes {
    /// Whether axis `i` is addressed.
    pub fn includes(self, i: usize) -> bool {
        match self {
            Self::All => true,
            Self::One(n) => n as usize == i,
        }
    }
}

/// How to stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum StopKind {
    /// Ramp the set-point down at the configured deceleration, then disable.
    Ramp,
    /// The drive's quick stop (0x605A reaction), then disable.
    QuickStop,
}

/// A request to the cycle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Command {
    /// Enable (Operation enabled).
    Enable(Axes),
    /// Disable (Switch on disabled) at once, without a ramp.
    Disable(Axes),
    /// Quick stop.
    QuickStop(Axes),
    /// Reset a fault (rising edge on controlword bit 7).
    FaultReset(Axes),
    /// Switch the mode of operation while enabled (no jump).
    Mode(Axes, RunMode),
    /// Start (or restart) the axis's configured program once enabled.
    RunProgram(Axes),
    /// Stop the running program and hold the set-point.
    HoldProgram(Axes),
    /// Stream one set-point in the axis's mode (position counts, velocity counts/s, torque).
    Setpoint(u16, f64),
    /// Home with the method the drive holds in 0x6098 (start-up wrote it), then back to the
    /// axis's mode, as `AppAxis::request_home`; the method names it in reports.
    /// Taken in Operation enabled with no program or homing running; the axis's telemetry
    /// `task` says where it stands.
    Home(Axes, i8),
    /// Hand a pp target (counts) to the drive with the new-set-point handshake, as
    /// `AppAxis::request_pp`; taken in pp, in Operation enabled with no program
    /// running. The axis's telemetry `task` says where it stands.
    Pp {
        /// Axis index.
        axis: u16,
        /// Target (counts).
        target: f64,
        /// Controlword bit 6: relative to the last target.
        relative: bool,
        /// Controlword bit 5: replace the running move (else queued behind it).
        immediate: bool,
    },
    /// A move to an absolute position (counts) in csp, planned by the cycle as a program's
    /// `move` step is (trapezoidal, from where the axis stands, at most `velocity` counts/s
    /// and `acceleration` counts/s²), in place of the axis's program. Taken in Operation
    /// enabled with no program, homing or pp move running; the axis switches to csp first
    /// (without a jump). The axis's telemetry `program_running` says while it runs and
    /// `program_step` reaches 1 when it arrived.
    Move {
        /// Axis index.
        axis: u16,
        /// Destination (counts).
        to: f64,
        /// Velocity limit (counts/s).
        velocity: f64,
        /// Acceleration limit (counts/s²).
        acceleration: f64,
    },
    /// Arm a touch probe, as `AppAxis::arm_probe`; the axis's telemetry `probes`
    /// says whether it latched, and where.
    ArmProbe {
        /// Axis index.
        axis: u16,
        /// Probe 1 or 2.
        probe: u8,
        /// The edge.
        edge: crate::program::ProbeEdge,
    },
    /// Stop every axis in a controlled way, disable them, and end the cycle.
    Stop(StopKind),
    /// Re-start the segment: if the cycle runs, stop every axis in a controlled way and end
    /// it; then start the drives again (INIT → OP) on the same link, in the same process.
    /// After the segment was lost or a drive fell out of OP, this brings the drives back.
    Restart,
}

impl EventKind {
    /// The axis the event is about, if it is about one.
    pub fn axis(&self) -> Option<u16> {
        match *self {
            EventKind::Axis { axis, .. }
            | EventKind::FollowingError { axis, .. }
            | EventKind::ProbeLatched { axis, .. }
            | EventKind::DriveFollowingErrorStuck { axis, .. }
            | EventKind::ProgramStep { axis, .. }
            | EventKind::ProgramDone { axis }
            | EventKind::CommandRefused { axis, .. }
            | EventKind::HomingFailed { axis, .. }
            | EventKind::ProbeNotLatched { axis, .. }
            | EventKind::SetpointLimit { axis, .. }
            | EventKind::StreamUnderrun { axis, .. } => Some(axis),
            _ => None,
        }
    }
}

impl StopReason {
    /// The axis whose trouble stops the axes, if an axis's.
    pub fn axis(&self) -> Option<u16> {
        match *self {
            StopReason::DriveFault { axis }
            | StopReason::FollowingError { axis }
            | StopReason::HomingFailed { axis }
            | StopReason::ProbeNotLatched { axis, .. } => Some(axis),
            _ => None,
        }
    }
}

impl core::fmt::Display for Axes {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Axes::All => f.write_str("every axis"),
            Axes::One(a) => write!(f, "axis {a}"),
        }
    }
}

impl core::fmt::Display for Command {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Command::Enable(a) => write!(f, "enable {a}"),
            Command::Disable(a) => write!(f, "disable {a}"),
            Command::QuickStop(a) => write!(f, "quick stop {a}"),
            Command::FaultReset(a) => write!(f, "fault reset {a}"),
            Command::Mode(a, m) => write!(f, "switch {a} to {}", m.name()),
            Command::RunProgram(a) => write!(f, "run the program of {a}"),
            Command::HoldProgram(a) => write!(f, "hold the program of {a}"),
            Command::Setpoint(a, v) => write!(f, "set-point {v} for axis {a}"),
            Command::Home(a, m) => write!(f, "home {a} (method {m})"),
            Command::Pp {
                axis,
                target,
                relative,
                ..
            } => {
                let how = if *relative { "by" } else { "to" };
                write!(f, "pp {how} {target} for axis {axis}")
            }
            Command::Move { axis, to, .. } => write!(f, "move to {to} for axis {axis}"),
            Command::ArmProbe { axis, probe, edge } => write!(
                f,
                "arm touch probe {probe} ({} edge) of axis {axis}",
                edge.name()
            ),
            Command::Stop(StopKind::Ramp) => f.write_str("stop (ramp)"),
            Command::Stop(StopKind::QuickStop) => f.write_str("stop (quick stop)"),
            Command::Restart => f.write_str("re-start"),
        }
    }
}

/// Why the cycle stopped the axes on its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum StopReason {
    /// Requested.
    Requested,
    /// A drive faulted.
    DriveFault {
        /// Axis index.
        axis: u16,
    },
    /// The master-side following-error monitor tripped.
    FollowingError {
        /// Axis index.
        axis: u16,
    },
    /// Too many consecutive cycles without a reply.
    FramesLost {
        /// Consecutive lost cycles.
        cycles: u32,
    },
    /// A re-start was requested.
    Restart,
    /// A device (a drive or an I/O device) left OP.
    DriveLeftOp {
        /// Its position on the segment.
        device: u16,
    },
    /// The working counter stayed wrong.
    WorkingCounter,
    /// A program's home step failed.
    HomingFailed {
        /// Axis index.
        axis: u16,
    },
    /// A program's `ProbeWait` step saw no latch in its time.
    ProbeNotLatched {
        /// Axis index.
        axis: u16,
        /// Probe 1 or 2.
        probe: u8,
    },
}

/// Something the cycle observed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum EventKind {
    /// Every drive reached OP.
    AllOp,
    /// A device did not reach OP in time.
    OpTimeout {
        /// Its position on the segment.
        device: u16,
        /// Its AL state register value.
        al_state: u8,
    },
    /// An event of the CiA 402 engine.
    Axis {
        /// Axis index.
        axis: u16,
        /// The event.
        event: cia402::Event,
    },
    /// The working counter differs from the expected value.
    WorkingCounter {
        /// Received.
        got: u16,
        /// Expected.
        expected: u16,
        /// Position of the first device whose state check came back without an answer.
        missing: Option<u16>,
        /// The first logical datagram of the reply whose working counter was wrong, with the
        /// devices it covers (`None` when the reply's datagrams were not recorded).
        datagram: Option<ecdrive_core::ec::DatagramWkc>,
    },
    /// In SAFE-OP, before OP was requested, the working counter stayed wrong: a device does
    /// not take its outputs (or give its inputs); OP is not requested.
    OutputsNotTaken {
        /// Position of the first device of the first wrong datagram.
        device: u16,
        /// Received.
        got: u16,
        /// Expected.
        expected: u16,
        /// The first logical datagram that came back wrong, with the devices it covers.
        datagram: Option<ecdrive_core::ec::DatagramWkc>,
        /// The device is an I/O device (its outputs may be OP-only by design: a warning, OP
        /// is requested); else a drive, and start-up fails.
        io: bool,
    },
    /// A device's AL state changed.
    AlState {
        /// Its position on the segment.
        device: u16,
        /// The raw AL status value.
        state: u8,
    },
    /// A drive left OP without being asked: its AL status and AL status code (0x0134), read
    /// in the cycle it was seen.
    LeftOp {
        /// Its position on the segment.
        device: u16,
        /// The raw AL status value (0x0130).
        state: u8,
        /// The AL status code (0x0134); `None` if reading it failed.
        code: Option<u16>,
    },
    /// No reply within the cycle's budget (the master's `CycleSettings::reply_budget`; a
    /// reply that comes later is discarded): every axis held its set-point (the outputs were sent again
    /// unchanged, the program clock stood still).
    FrameLost {
        /// Consecutive lost cycles so far.
        consecutive: u32,
    },
    /// Replies resumed after lost cycles.
    FramesResumed {
        /// How many cycles were lost.
        lost: u32,
    },
    /// The segment stopped answering (cable pull, power loss): detected after
    /// the master's `CycleSettings::segment_lost_after` cycles without a reply.
    SegmentLost {
        /// Consecutive lost cycles.
        cycles: u32,
    },
    /// The segment stayed silent for the master's `CycleSettings::segment_gone_after`: the
    /// cycle ends (the drives' own watchdogs have disabled them); a re-start brings them back.
    SegmentGone {
        /// Consecutive lost cycles.
        cycles: u32,
    },
    /// 0x60F4 stayed 0 for `cycles` cycles of motion in csp while the master's own following
    /// error reached `master`: the drive does not compute it; it is flagged and not trusted.
    DriveFollowingErrorStuck {
        /// Axis index.
        axis: u16,
        /// Cycles of motion seen.
        cycles: u32,
        /// The master's largest |following error| so far, position units.
        master: i64,
    },
    /// The master-side following-error monitor tripped.
    FollowingError {
        /// Axis index.
        axis: u16,
        /// |demand − actual| in position units.
        value: i64,
        /// The limit.
        limit: u32,
    },
    /// A program step started.
    ProgramStep {
        /// Axis index.
        axis: u16,
        /// Step index.
        step: u16,
    },
    /// The program finished.
    ProgramDone {
        /// Axis index.
        axis: u16,
    },
    /// A program's home step failed: the drive reported a homing error (statusword bit 13),
    /// or the run timed out or was cut short.
    HomingFailed {
        /// Axis index.
        axis: u16,
        /// The homing method (0x6098).
        method: i8,
        /// How the run ended.
        #[serde(serialize_with = "homing_outcome_name")]
        outcome: crate::cia402::HomingOutcome,
        /// How the drive's manual names the failure (empty when it names none).
        drive_says: &'static str,
    },
    /// A touch probe latched: the position the drive latched at the probe's edge.
    ProbeLatched {
        /// Axis index.
        axis: u16,
        /// Probe 1 or 2.
        probe: u8,
        /// The edge.
        edge: crate::program::ProbeEdge,
        /// The latched position (counts, unwrapped like the actual position).
        position: i64,
    },
    /// A program's wait for a touch probe ended without the latch.
    ProbeNotLatched {
        /// Axis index.
        axis: u16,
        /// Probe 1 or 2.
        probe: u8,
        /// How long the program waited (s).
        seconds: f64,
    },
    /// A command could not be carried out.
    CommandRefused {
        /// Axis index.
        axis: u16,
        /// Why (a fixed text).
        why: &'static str,
    },
    /// A set-point from the application broke one of the axis's limits: the axis is stopped
    /// with a ramp.
    SetpointLimit {
        /// Axis index.
        axis: u16,
        /// The limit (`max_velocity`, `max_acceleration`, `max_torque`, or `a finite
        /// set-point`).
        limit: &'static str,
        /// The value the set-point implied (drive units).
        value: f64,
        /// The limit's value.
        max: f64,
    },
    /// A set-point stream ran empty while its axis took set-points: the last one is held.
    StreamUnderrun {
        /// Axis index.
        axis: u16,
        /// Cycles without a new set-point so far in this stream.
        total: u64,
    },
    /// The cycle started stopping the axes.
    Stopping {
        /// Why.
        reason: StopReason,
    },
    /// Every axis is disabled and the cycle ended.
    Stopped,
}

/// An event with when it happened.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Event {
    /// Cycle number.
    pub cycle: u64,
    /// `CLOCK_MONOTONIC` time, ns.
    pub time_ns: u64,
    /// What happened.
    pub kind: EventKind,
}

/// A touch probe of an axis as the cycle drives it (`AppAxis::arm_probe`, a program's
/// `TouchProbe` step).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum ProbeState {
    /// Not armed.
    #[default]
    Off,
    /// Armed on this edge, no latch yet.
    Armed(crate::program::ProbeEdge),
    /// Latched: the position the drive latched at the edge (counts, unwrapped like the
    /// actual position). The drive keeps it until the probe is armed again.
    Latched {
        /// The edge.
        edge: crate::program::ProbeEdge,
        /// The latched position (counts).
        position: i64,
    },
}

/// A homing or a pp move the application started on an axis (`AppAxis::request_home`,
/// `AppAxis::request_pp`), as it stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum DriveTask {
    /// Nothing started.
    #[default]
    Idle,
    /// Homing with this method runs (hm, then back to the mode the axis was in).
    Homing {
        /// The method (0x6098).
        method: i8,
    },
    /// The homing completed and the axis is back in its mode: its position is the home's.
    Homed {
        /// The method (0x6098).
        method: i8,
    },
    /// The homing failed or was cut short (a failure stops the axes and is in the history,
    /// as for a program's home step).
    HomingFailed {
        /// The method (0x6098).
        method: i8,
    },
    /// pp targets are in flight or queued.
    Positioning {
        /// Targets waiting behind the one in flight.
        queued: u8,
    },
    /// The drive reported the last pp target reached.
    TargetReached,
}

/// One axis in a snapshot.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct AxisTelemetry {
    /// Statusword as received.
    pub statusword: u16,
    /// Controlword as sent.
    pub controlword: u16,
    /// Decoded CiA 402 state (`None` when the statusword decodes to no state).
    #[serde(skip)]
    pub state: Option<cia402::State>,
    /// Mode of operation sent (0x6060).
    pub mode: i8,
    /// Mode display received (0x6061), if mapped.
    pub mode_display: i8,
    /// Position demand (unwrapped), position units.
    pub position_demand: i64,
    /// Position actual (unwrapped), position units.
    pub position_actual: i64,
    /// Velocity demand, drive units.
    pub velocity_demand: i32,
    /// Velocity actual, drive units.
    pub velocity_actual: i32,
    /// Torque demand, drive units.
    pub torque_demand: i16,
    /// Torque actual, drive units.
    pub torque_actual: i16,
    /// Following error as the master computes it: the position demand the drive took (the one
    /// whose frame passed two SYNC0 pulses before this feedback was latched) − the actual
    /// position. The master-side limit uses this value.
    pub following_error: i64,
    /// Largest |following error| (the master's) seen while energised in csp.
    pub max_following_error: i64,
    /// 0x60F4 as the drive reports it, if mapped (shown beside the master's value, never used
    /// for the limit).
    pub following_error_drive: Option<i64>,
    /// Largest |0x60F4| seen while energised in csp.
    pub max_following_error_drive: i64,
    /// 0x60F4 stayed 0 while the axis moved: the drive does not compute it.
    pub following_error_drive_stuck: bool,
    /// 0x603F, if mapped.
    pub error_code: u16,
    /// AL state register value.
    pub al_state: u8,
    /// Program step running (equals the step count when finished).
    pub program_step: u16,
    /// Whether a program is running.
    pub program_running: bool,
    /// The homing or pp move a command or the application started, as it stands.
    pub task: DriveTask,
    /// Touch probes 1 and 2.
    pub probes: [ProbeState; 2],
}

/// Bus and timing figures in a snapshot.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CycleTelemetry {
    /// Cycle number.
    pub cycle: u64,
    /// DC system time of the last exchange, ns.
    pub dc_time: u64,
    /// Working counter of the last exchange.
    pub wkc: u16,
    /// Expected working counter.
    pub wkc_expected: u16,
    /// Cycles without a reply, total.
    pub lost: u64,
    /// Cycles whose wake-up came later than a whole cycle.
    pub overruns: u64,
    /// Wake-up latency of the last cycle, ns.
    pub wake_latency_ns: u64,
    /// Frame round trip of the last cycle, ns.
    pub exchange_ns: u64,
    /// Time spent awake in the last cycle, ns.
    pub busy_ns: u64,
    /// Whether every drive is in OP.
    pub all_op: bool,
    /// Consecutive cycles without a reply (0 while the segment answers).
    pub lost_in_a_row: u32,
    /// Where the session is.
    pub phase: Phase,
    /// Re-starts so far (0 on the first start).
    pub restarts: u32,
}

/// Where a session is, for the supervisory side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub enum Phase {
    /// Starting the drives (INIT → SAFE-OP) or waiting for OP.
    #[default]
    Starting,
    /// The cycle runs.
    Cycling,
    /// The cycle is ending (a controlled stop after the segment was lost, a drive left OP, or
    /// a stop or re-start was requested); the session then takes the drives down. Commands
    /// other than stop and re-start may be refused from here on.
    Stopping,
    /// The cycle ended (segment lost, a drive left OP); waiting for a re-start request.
    WaitingForRestart,
    /// Re-starting the drives (waiting for the segment to answer, then INIT → OP).
    Restarting,
    /// The session ended.
    Ended,
}

/// Input bytes of an I/O device a snapshot carries at most.
pub const IO_TELEMETRY_BYTES: usize = 32;

/// One I/O device (not driven) in a snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct IoTelemetry {
    /// Position on the segment.
    pub position: u16,
    /// AL state register value.
    pub al_state: u8,
    /// The first [`IO_TELEMETRY_BYTES`] input bytes of the last exchange with a reply.
    #[serde(skip)]
    pub inputs: [u8; IO_TELEMETRY_BYTES],
    /// How many of them are valid.
    pub input_len: u16,
}

impl Default for IoTelemetry {
    fn default() -> Self {
        Self {
            position: 0,
            al_state: 0,
            inputs: [0; IO_TELEMETRY_BYTES],
            input_len: 0,
        }
    }
}

impl IoTelemetry {
    /// The valid input bytes.
    pub fn inputs(&self) -> &[u8] {
        &self.inputs[..usize::from(self.input_len).min(IO_TELEMETRY_BYTES)]
    }
}

/// The latest snapshot of the cycle.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Telemetry {
    /// Bus and timing.
    pub cycle: CycleTelemetry,
    /// One entry per axis.
    pub axes: Vec<AxisTelemetry>,
    /// One entry per I/O device (not driven), in segment order.
    pub io: Vec<IoTelemetry>,
}

fn homing_outcome_name<S: serde::Serializer>(
    o: &crate::cia402::HomingOutcome,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.serialize_str(homing_outcome_text(*o))
}

/// The text of an event that carries its own account (a failed home step); empty for others.
pub fn event_text(kind: &EventKind) -> String {
    match *kind {
        EventKind::HomingFailed {
            method,
            outcome,
            drive_says,
            ..
        } => homing_failure_text(method, outcome, drive_says),
        EventKind::ProbeNotLatched { probe, seconds, .. } => format!(
            "touch probe {probe} did not latch within the program's wait of {seconds} s: the \
             program stopped"
        ),
        _ => String::new(),
    }
}

/// A failed home step in words: the method, how the run ended, and the drive manual's name for
/// the failure when it gives one.
pub fn homing_failure_text(
    method: i8,
    outcome: crate::cia402::HomingOutcome,
    drive_says: &str,
) -> String {
    let named = if drive_says.is_empty() {
        String::new()
    } else {
        format!("; the drive's manual names it {drive_says}")
    };
    format!(
        "homing (method {method}) failed: {}{named}",
        homing_outcome_text(outcome)
    )
}

/// A homing run's end in words.
pub fn homing_outcome_text(o: crate::cia402::HomingOutcome) -> &'static str {
    use crate::cia402::HomingOutcome as H;
    match o {
        H::Completed => "completed",
        H::Error { moving: true } => {
            "the drive reported a homing error (statusword bit 13), the motor still moving"
        }
        H::Error { moving: false } => "the drive reported a homing error (statusword bit 13)",
        H::Aborted => "cut short (the axis stopped streaming in hm)",
        H::Timeout => "no result in time",
        H::NotReady => "the axis was not in hm",
    }
}
