//! The cycle's settings, its channels to the supervisory side, and what a run of it reports.

use super::*;

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
    /// as lost (from the wake-up: with [`ReplyWait::NextWake`] the frame went out a cycle
    /// before).
    pub reply_budget: f64,
    /// Record the [`Timing`] histograms and the report's lost/overrun counts in steady state
    /// only: from the cycle after every drive reached OP to the cycle that takes the stop
    /// request. The jitter harness measures steady state; start-up cycles (extra frames for
    /// the OP request) would blur it. Off by default: every cycle is recorded.
    pub steady_timing_only: bool,
    /// Distribute the reference clock's time to the other clocks every cycle (the FRMW of
    /// `tx_rx_dc`): the drift compensation that keeps the SYNC0 pulses of all drives together.
    /// On by default; off only to show what it does (the frame then reads the reference
    /// clock without writing the others, `crates/ecdrive-ethercat/tests/ethercat/faults_master.rs`).
    pub drift_compensation: bool,
    /// When the cycle's frame goes out and when its reply is read. [`ReplyWait::NextWake`]
    /// by default.
    pub reply_wait: ReplyWait,
    /// Carry the process image in frames ecdrive builds itself, learnt from the frames
    /// ethercrab's `tx_rx_dc` sends in the first cycle (the same datagrams on the wire, without
    /// ethercrab's PDU machinery in the cycle; `cycle::frames`). On by default; off: ethercrab's
    /// `tx_rx_dc` every cycle. See [`CycleReport::frames_by`].
    pub own_frames: bool,
}

/// Whose frames carried the process image in a run (see [`CycleSettings::own_frames`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FramesBy {
    /// ecdrive's own, learnt from ethercrab's first.
    Ecdrive,
    /// ethercrab's `tx_rx_dc`, and why.
    Ethercrab {
        /// Why not ecdrive's.
        why: &'static str,
    },
}

/// When the cycle's frame goes out and when its reply is read (see
/// [`CycleSettings::reply_wait`]).
///
/// Both give the drives outputs computed from the inputs of the frame before, so the data is
/// equally fresh; they differ in where the frame's flight falls and what it costs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReplyWait {
    /// Receive, process, send, sleep (the order of IgH's cyclic task): at the wake-up the
    /// reply of the frame sent at the end of the cycle before is read without waiting; the
    /// steps compute the outputs; the frame with them goes out; the thread sleeps. The frame
    /// flies while the thread sleeps: one wake-up per cycle. A reply not there at the wake-up
    /// is waited for up to [`CycleSettings::reply_budget`], and so are the further frames of a
    /// process image too large for one. The exchange time recorded is the reading of the reply
    /// at the wake-up (the flight during the sleep is not measured).
    #[default]
    NextWake,
    /// Send, wait, process, sleep (the order of SOEM's examples): the frame goes out at the
    /// wake-up with the outputs the steps computed in the cycle before, and the thread waits
    /// for its reply, up to [`CycleSettings::reply_budget`] of the cycle. Two wake-ups per
    /// cycle (the sleep and the reply); the exchange time recorded is the frame's round trip.
    InCycle,
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
            reply_wait: ReplyWait::NextWake,
            own_frames: true,
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
    /// What the cycle last saw of the devices' mailboxes (shared with the session thread,
    /// which reads them only when one may hold something).
    pub mail: std::sync::Arc<super::frames::MailWatch>,
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
            mail: Default::default(),
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
    /// Where the awake time went, summed over the recorded cycles.
    pub parts: CycleParts,
}

/// The cycle thread's awake time by part, summed over the cycles the histograms cover (ns,
/// wall time on the cycle thread; at a real-time priority nothing else runs there, so it is
/// the thread's CPU time in those parts). What a cycle costs besides these parts is the sleep
/// and the wake-up: the thread's CPU time per cycle minus their sum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CycleParts {
    /// Cycles summed.
    pub cycles: u64,
    /// Reading the reply of the frame: the link's receive, ethercrab's handling of the frame
    /// (its PDU bookkeeping, the process image), the working counter and AL-state checks.
    pub receive_ns: u64,
    /// Of `receive_ns`: inside the link's receive (the syscall).
    pub receive_link_ns: u64,
    /// The CiA 402 engine and motion runtime: every axis's inputs read, step, outputs written
    /// (and the application's cycle code, if any).
    pub engine_ns: u64,
    /// Supervision: commands taken, OP requested, faults spread to the other axes, stop
    /// timeouts, devices leaving OP.
    pub supervision_ns: u64,
    /// Telemetry: the snapshot published and the recording's samples pushed.
    pub telemetry_ns: u64,
    /// Sending the next frame: ethercrab builds it (its PDU bookkeeping), the link sends it.
    pub send_ns: u64,
    /// Of `send_ns`: inside the link's send (the syscall).
    pub send_link_ns: u64,
}

impl CycleParts {
    /// Per cycle, ns: (receive, receive's link, engine, supervision, telemetry, send, send's
    /// link); zeros before any cycle was summed.
    pub fn per_cycle(&self) -> [f64; 7] {
        let n = self.cycles.max(1) as f64;
        [
            self.receive_ns,
            self.receive_link_ns,
            self.engine_ns,
            self.supervision_ns,
            self.telemetry_ns,
            self.send_ns,
            self.send_link_ns,
        ]
        .map(|v| if self.cycles == 0 { 0.0 } else { v as f64 / n })
    }
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
    /// Per axis: mode changes beyond what `modes_run` keeps.
    pub modes_omitted: Vec<u32>,
    /// Per axis: the touch-probe latches, in order: (probe, edge, position in counts).
    pub probe_latches: Vec<Vec<(u8, ProbeEdge, i64)>>,
    /// Per axis: the largest change of the streamed set-point from one cycle to the next while
    /// the drive was enabled, for each kind (across mode switches too: a jump shows here).
    pub max_setpoint_step: Vec<SetpointSteps>,
    /// Per axis: the states it went through, in order (consecutive duplicates removed).
    pub states: Vec<Vec<State>>,
    /// Whose frames carried the process image.
    pub frames_by: FramesBy,
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
