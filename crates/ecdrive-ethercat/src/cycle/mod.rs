//! The cycle: one thread, absolute-time sleeps on the DC-aligned cycle, one process-data
//! exchange, one CiA 402 step per axis, every cycle.
//!
//! Per cycle: sleep until the instant (`clock_nanosleep`, absolute), read the reply of the frame
//! sent at the end of the cycle before (the cycle's own frames, learnt from ethercrab's
//! `tx_rx_dc` in the first cycle, `cycle/frames.rs`; or `tx_rx_dc` itself, pumped inline by
//! [`exec::exchange`]: either way the frame I/O is this thread's own), check the working
//! counter and every drive's AL state, read
//! each drive's inputs through its resolved fields, take commands, step each axis of the motion
//! runtime ([`ecdrive_motion::MotionAxis`]: the program, homing, the profile modes, the probes,
//! the stops and the CiA 402 engine), write the outputs, publish telemetry and events, send the
//! frame with the new outputs, sleep: the frame flies while the thread sleeps,
//! one wake-up per cycle ([`ReplyWait::NextWake`]; [`ReplyWait::InCycle`] sends at the wake-up
//! and waits for the reply instead). After start-up nothing here allocates, locks
//! anything another thread takes, or makes a syscall other than the frame I/O and the sleep —
//! `crates/ecdrive-ethercat/tests/ethercat/cycle_audit.rs` proves it with a counting allocator and per-thread syscall counters.
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
use ethercrab::subdevice_group::CycleInfo;
use ethercrab::subdevice_group::{HasDc, SafeOp};
use ethercrab::{Command as EcCommand, MainDevice, SubDeviceState};
use std::future::Future;
use std::pin::{Pin, pin};
use std::time::Duration;

pub mod audit;
mod axes;
mod bus;
mod frames;
mod own;
mod publish;
mod schedule;
mod settings;
mod timing;

use axes::{CycleDrive, app_view};
pub use bus::al_state_name;
use bus::{StateScan, raw_al_state};
pub use frames::MailWatch;
use frames::{Image, OwnOutcome};
use own::OwnPath;
pub use settings::{
    CycleEnd, CycleHooks, CycleIo, CycleParts, CycleReport, CycleSettings, FrameStats, FramesBy,
    ReplyWait, SupervisorIo, Timing, channels,
};
use timing::{Lap, TimingBatch};

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
enum TimingWindow {
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

impl TimingWindow {
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

/// How the exchange of one cycle's frame went.
enum FrameOutcome {
    /// A reply came.
    Answered,
    /// No reply in time.
    Lost,
}

/// The constants of one run, derived from the settings and the drives.
struct RunConstants {
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
    /// The SYNC0 shift, as ethercrab's first reply shows it (for the own frames' wait to the
    /// next instant).
    sync0_shift_ns: u64,
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
    /// When the frame in flight went out.
    t_sent: u64,
    /// The exchange as recorded: from the send to the reply ([`ReplyWait::InCycle`]), or the
    /// reading of the reply at the wake-up ([`ReplyWait::NextWake`]).
    t_ex: u64,
    t_ex_done: u64,
    /// A point of the SYNC0 grid (SYNC0 plus the shift) from the reply that came, when the
    /// reference clock answered: the phase [`schedule`] keeps the cycle on.
    next_at: Option<u64>,
    /// The last frame could not be sent (no frame slot): its cycle counts as lost.
    unsent: bool,
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
    /// What the last reply said of the devices' mailboxes, for the session thread, and what
    /// it was last told (it is written only when that changes: the cycle does not touch the
    /// shared byte every cycle).
    mail: &'a frames::MailWatch,
    mail_told: Option<bool>,
    ev: Emitter<'a>,
    consts: RunConstants,
    /// The expected working counter of each logical datagram, from the FMMU configuration the
    /// master sent (`None`: not recorded; the whole-image value is checked instead).
    wkc_plan: Option<WkcPlan>,
    axes: Vec<CycleDrive>,
    /// Every device by position: its station address and last AL state.
    addresses: Vec<u16>,
    al_states: Vec<u8>,
    /// The I/O devices as last seen (a lost cycle keeps the inputs of the last reply).
    io_last: Vec<IoTelemetry>,
    clock: Clock,
    counts: Counts,
    timing: Timing,
    /// The timing values not yet in `timing`.
    batch: TimingBatch,
    window: TimingWindow,
    op: OpState,
    phase: RunPhase,
    /// The hooks were told steady state began (and not yet that it ended).
    steady: bool,
    end_reason: Option<CycleEnd>,
    /// A device that left OP whose AL status code is still to be read: (device, AL state,
    /// tries so far).
    left_op_code: Option<(usize, u8, u8)>,
    last_telemetry: CycleTelemetry,
    /// Every device's inputs and outputs: what the steps read and write.
    image: Image,
    /// Whose frames carry the image.
    own: OwnPath,
    /// The FMMU blocks the master configured (station address, block), for learning.
    fmmus: Vec<(u16, crate::ec::register::FmmuConfig)>,
    /// The AL state of each device from the last reply, by position (its first `states_n`).
    states: Vec<u8>,
    states_n: usize,
    /// Why the own frames were not taken up, when they were not.
    not_learnt: Option<&'static str>,
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
    // The exchange in flight: ethercrab's future for the cycle's frame, kept here (its type
    // has no name) and handed to each cycle.
    let make = || group.tx_rx_dc(md);
    let mut flight = pin!(None);
    let end = loop {
        if let Some(end) = c.next_cycle(flight.as_mut(), &make) {
            break end;
        }
    };
    // The session no longer hears from the cycle: it looks at the mailboxes itself.
    c.mail.set(None);
    // A frame still in flight is given up (its reply, should it come, is stale).
    if flight.is_some() {
        flight.set(None);
        c.pump.clear_all();
    }
    c.finish(end, rt)
}

/// The cycle's process image at the start of a run: what ethercrab's copy holds, then every
/// axis's initial outputs.
fn first_image(md: &MainDevice<'_>, group: &Group<SafeOp, HasDc>, axes: &[CycleDrive]) -> Image {
    let n = group.len();
    let sizes: Vec<(usize, usize)> = (0..n)
        .map(|p| {
            group.subdevice(md, p).map_or((0, 0), |sd| {
                let io = sd.io_raw();
                (io.inputs().len(), io.outputs().len())
            })
        })
        .collect();
    let mut image = Image::new(&sizes);
    for p in 0..n {
        if let Ok(sd) = group.subdevice(md, p) {
            let io = sd.io_raw();
            image.set_inputs(p, io.inputs());
            let (_, out) = image.io_mut(p);
            if out.len() == io.outputs().len() {
                out.copy_from_slice(io.outputs());
            }
        }
    }
    for a in axes {
        a.initial_outputs(image.io_mut(a.sub).1);
    }
    image
}

/// The reply of one cycle's frame, as ethercrab gives it.
type Reply = Result<
    ethercrab::subdevice_group::TxRxResponse<{ crate::bus::MAX_SUBDEVICES }, CycleInfo>,
    ethercrab::error::Error,
>;

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
        let axes: Vec<CycleDrive> = drives
            .iter()
            .filter_map(|d| CycleDrive::new(d, settings.cycle))
            .collect();
        let app_axes: Vec<AppAxis> = drives
            .iter()
            .filter(|d| axes.iter().any(|a| a.sub == usize::from(d.info.position)))
            .map(app_view)
            .collect();
        let n_devices = group.len();
        let image = first_image(md, group, &axes);
        let CycleIo {
            commands,
            events,
            telemetry,
            restarts,
            restarting,
            mail,
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
        let fmmus: Vec<(u16, crate::ec::register::FmmuConfig)> =
            pump.fmmu_configs().map(|(st, _, c)| (st, c)).collect();
        pump.record_logical(wkc_plan.is_some());
        // ethercrab's frames of the shape the last run's own had go out again (learning).
        pump.own_frames(&[]);
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
            mail,
            mail_told: None,
            ev: Emitter {
                out: events,
                cycle: 0,
                first_stop: None,
            },
            wkc_plan,
            consts: RunConstants {
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
                sync0_shift_ns: cycle_ns / 2,
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
            batch: TimingBatch::default(),
            window: if settings.steady_timing_only {
                TimingWindow::NotYet
            } else {
                TimingWindow::Open
            },
            op: OpState::SafeOp,
            phase: RunPhase::Running,
            steady: false,
            end_reason: None,
            left_op_code: None,
            last_telemetry: CycleTelemetry::default(),
            image,
            own: OwnPath::new(settings.own_frames),
            fmmus,
            states: vec![0; n_devices],
            states_n: 0,
            not_learnt: None,
        }
    }

    fn ending(&self) -> bool {
        matches!(self.phase, RunPhase::Ending { .. })
    }

    fn all_op(&self) -> bool {
        self.op == OpState::AllOp
    }

    /// One cycle; `Some` when the run ends. No allocation from here on. `flight` holds the
    /// exchange in flight between cycles ([`ReplyWait::NextWake`]); `make` makes one.
    fn next_cycle<F: Future<Output = Reply>>(
        &mut self,
        mut flight: Pin<&mut Option<F>>,
        make: &impl Fn() -> F,
    ) -> Option<CycleEnd> {
        if self.window == TimingWindow::OpensNext {
            self.window = TimingWindow::Open;
        }
        self.wake();
        let next_wake = self.settings.reply_wait == ReplyWait::NextWake;
        let mut lap = Lap::new(self.clock.woke, self.pump.stats());
        // In-cycle, and the first cycle of NextWake (no frame before it): send now, wait.
        let first = flight.is_none() && !self.own_in_flight() && !self.clock.unsent;
        if (!next_wake || first)
            && let Err(end) = self.send_frame(flight.as_mut(), make)
        {
            return Some(end);
        }
        let sent_now = lap.lap();
        let good = match self.exchange(flight.as_mut()) {
            Ok(FrameOutcome::Answered) => true,
            Ok(FrameOutcome::Lost) => {
                if let Some(end) = self.on_lost() {
                    return Some(end);
                }
                false
            }
            Err(end) => return Some(end),
        };
        let receive = lap.lap();
        if let Some(end) = self.request_op() {
            return Some(end);
        }
        self.apply_commands();
        let mut supervision = lap.lap();
        self.step_axes(good);
        let engine = lap.lap();
        self.supervise_axes();
        supervision += lap.lap();
        self.publish(good);
        if good {
            self.record_samples();
        }
        let telemetry = lap.lap();
        if let Some(end) = self.leave_op() {
            return Some(end);
        }
        supervision += lap.lap();
        let recording = self.window.recording();
        if recording {
            let busy = monotonic_ns() - self.clock.woke;
            self.batch.record(&mut self.timing, TimingBatch::BUSY, busy);
        }
        if self.window == TimingWindow::ClosesAfter {
            self.window = TimingWindow::Closed;
        }
        if next_wake && let Err(end) = self.send_frame(flight, make) {
            return Some(end);
        }
        let sent_late = lap.lap();
        if recording {
            let (link, p) = (self.pump.stats(), &mut self.timing.parts);
            p.cycles += 1;
            p.receive_ns += receive;
            p.engine_ns += engine;
            p.supervision_ns += supervision;
            p.telemetry_ns += telemetry;
            p.send_ns += sent_now + sent_late;
            p.receive_link_ns += link.link_recv_ns - lap.stats.link_recv_ns;
            p.send_link_ns += link.link_send_ns - lap.stats.link_send_ns;
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
            let t = &mut self.timing;
            self.batch.record(t, TimingBatch::WAKE, c.latency);
            if c.last_wake != 0 {
                self.batch
                    .record(t, TimingBatch::PERIOD, c.woke - c.last_wake);
            }
        }
        if c.latency > self.consts.cycle_ns {
            self.counts.overruns += 1;
            if recording {
                self.counts.recorded_overruns += 1;
            }
        }
        c.last_wake = c.woke;
        c.cycle += 1;
        self.ev.cycle = c.cycle;
    }

    /// Send the cycle's frame: the process image's outputs as the steps left them, the
    /// reference clock's time, every device's AL state (ethercrab's `tx_rx_dc`). Its reply is
    /// read by [`exchange`](Self::exchange).
    fn send_frame<F: Future<Output = Reply>>(
        &mut self,
        mut flight: Pin<&mut Option<F>>,
        make: &impl Fn() -> F,
    ) -> Result<(), CycleEnd> {
        self.pump.clear_logical();
        self.clock.t_sent = monotonic_ns();
        if let OwnPath::On(own) = &mut self.own {
            return own
                .send(self.pump, &self.image)
                .map_err(|_| CycleEnd::LinkFailed);
        }
        // ethercrab's frame: the outputs into its copy of the image.
        self.outputs_to_ethercrab();
        self.pump
            .capture(matches!(self.own, OwnPath::Learning { .. }));
        flight.set(Some(make()));
        let Some(fut) = flight.as_mut().as_pin_mut() else {
            return Ok(());
        };
        match exec::start(self.pump, fut) {
            Ok(None) => Ok(()),
            // No frame could be had: nothing in flight, the cycle counts as lost.
            Ok(Some(_)) => {
                flight.set(None);
                self.clock.unsent = true;
                Ok(())
            }
            Err(_) => {
                flight.set(None);
                Err(CycleEnd::LinkFailed)
            }
        }
    }

    /// Read the reply of the frame in flight and look at what came back (the AL states ride
    /// along with the LRW); `Err` when the link failed. It waits up to the reply budget (with
    /// [`ReplyWait::NextWake`] the reply normally came during the sleep).
    fn exchange<F: Future<Output = Reply>>(
        &mut self,
        mut flight: Pin<&mut Option<F>>,
    ) -> Result<FrameOutcome, CycleEnd> {
        // With NextWake the reply is normally there at once; an image too large for one frame
        // goes on in further frames, exchanged now, within the same budget.
        let deadline =
            self.clock.woke + (self.consts.cycle_ns as f64 * self.settings.reply_budget) as u64;
        // A frame sent in this cycle: its round trip; one sent in the cycle before: the
        // reading of its reply.
        let now = monotonic_ns();
        self.clock.t_ex = if self.clock.t_sent >= self.clock.woke {
            self.clock.t_sent
        } else {
            now
        };
        if let OwnPath::On(own) = &mut self.own
            && own.in_flight()
        {
            let result = own.receive(self.pump, &mut self.image, deadline);
            self.clock.t_ex_done = monotonic_ns();
            self.clock.next_at = None;
            return match result {
                Ok(OwnOutcome::Answered(r)) => {
                    let n = own.states().len().min(self.states.len());
                    self.states[..n].copy_from_slice(&own.states()[..n]);
                    self.states_n = n;
                    self.tell_mail(r.mail);
                    let (period, shift) = (self.consts.cycle_ns, self.consts.sync0_shift_ns);
                    let wait = (period - r.dc_time % period) + shift;
                    self.answered(r.wkc, r.dc_time, wait);
                    Ok(FrameOutcome::Answered)
                }
                Ok(OwnOutcome::Late) => {
                    self.counts.late_total += 1;
                    self.tell_mail(None);
                    Ok(FrameOutcome::Lost)
                }
                Err(_) => Err(CycleEnd::LinkFailed),
            };
        }
        let Some(fut) = flight.as_mut().as_pin_mut() else {
            // No frame could be sent.
            self.clock.t_ex_done = now;
            self.clock.next_at = None;
            self.clock.unsent = false;
            return Ok(FrameOutcome::Lost);
        };
        let result = exec::exchange(self.pump, fut, deadline);
        flight.set(None);
        self.clock.t_ex_done = monotonic_ns();
        self.clock.next_at = None;
        match result {
            Ok(Ok(resp)) => {
                let n = resp.subdevice_states.len().min(self.states.len());
                for (d, st) in self.states.iter_mut().zip(resp.subdevice_states.iter()) {
                    *d = raw_al_state(st);
                }
                self.states_n = n;
                for p in 0..self.states.len() {
                    if let Ok(sd) = self.group.subdevice(self.md, p) {
                        self.image.set_inputs(p, sd.io_raw().inputs());
                    }
                }
                let wait = resp.extra.next_cycle_wait.as_nanos() as u64;
                let dc = resp.extra.dc_system_time;
                self.learn(dc, wait);
                self.answered(resp.working_counter, dc, wait);
                Ok(FrameOutcome::Answered)
            }
            Err(ExchangeError::Late) => {
                self.counts.late_total += 1;
                Ok(FrameOutcome::Lost)
            }
            Ok(Err(_)) => Ok(FrameOutcome::Lost),
            Err(ExchangeError::Link(_)) => Err(CycleEnd::LinkFailed),
        }
    }

    /// A reply came: its working counter, the reference clock's time, the wait from the send
    /// to the next DC-aligned instant; the AL states are in `states`.
    fn answered(&mut self, wkc: u16, dc_time: u64, next_wait_ns: u64) {
        self.clock.tick += 1;
        if self.window.recording() {
            let took = self.clock.t_ex_done - self.clock.t_ex;
            self.batch
                .record(&mut self.timing, TimingBatch::EXCHANGE, took);
        }
        if self.counts.consecutive_lost > 0 {
            self.ev.emit(EventKind::FramesResumed {
                lost: self.counts.consecutive_lost,
            });
        }
        self.counts.consecutive_lost = 0;
        self.counts.segment_lost = false;
        self.clock.dc_time = dc_time;
        self.counts.last_wkc = wkc;
        self.clock.next_at = Some(self.clock.t_sent + next_wait_ns);
        // A code still owed from an earlier cycle first (not twice in one cycle).
        self.retry_left_op_code(false);
        let mut scan = StateScan::default();
        for i in 0..self.states_n {
            let st = self.states[i];
            self.on_al_state(i, st, &mut scan);
        }
        self.supervise_bus(scan, wkc);
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
                TimingWindow::Open | TimingWindow::ClosesAfter => TimingWindow::ClosesAfter,
                TimingWindow::NotYet | TimingWindow::OpensNext | TimingWindow::Closed => {
                    TimingWindow::Closed
                }
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
            dt: self.consts.dt,
            pulse: self.clock.dc_time / self.consts.cycle_ns,
            ending: self.ending(),
            any_energised_before: self.axes.iter().any(|a| a.m.busy()),
            stop_ramp_cycles: self.consts.stop_ramp_cycles,
            stop_timeout_cycles: self.consts.stop_timeout_cycles,
        };
        let with_app = self.app.is_some();
        // Inputs first, for every axis (and the application's view of it, if there is an
        // application); then the application; then each axis's step.
        for (a, view) in self.axes.iter_mut().zip(self.app_axes.iter_mut()) {
            let in_op = good && a.al_state & 0x0F == 8;
            let (inputs, outputs) = (self.image.inputs(a.sub), self.image.outputs(a.sub));
            if in_op {
                a.fb = Some(a.read_inputs(inputs, ctx.pulse));
            }
            if with_app {
                view.refresh(&a.m, in_op, inputs, outputs);
            }
        }
        if let Some(app) = self.app.as_deref_mut() {
            let ev = &mut self.ev;
            let mut emit = |k: EventKind| ev.emit(k);
            let mut c = AppCycle::new(
                ctx.cycle,
                ctx.dt,
                self.clock.dc_time,
                &mut self.app_axes,
                &mut emit,
            );
            app.cycle(&mut c);
        }
        for (i, (a, view)) in self.axes.iter_mut().zip(self.app_axes.iter()).enumerate() {
            let outputs = self.image.io_mut(a.sub).1;
            if !good {
                a.count(outputs);
                continue;
            }
            if a.al_state & 0x0F != 8 {
                a.below_op(outputs);
                continue;
            }
            let Some(fb) = a.fb.take() else { continue };
            let req = if with_app {
                view.requests()
            } else {
                Requests::default()
            };
            let out = a.m.step(i, fb, &ctx, &mut self.ev, req);
            let outputs = self.image.io_mut(a.sub).1;
            a.write_outputs(&out, outputs);
            for &(f, raw) in view.writes() {
                let _ = f.write_raw(outputs, raw);
            }
        }
    }

    /// After the steps: a drive that faulted stops every other axis (outside the per-axis
    /// steps, so each axis sees the same decision); stops that take too long end in disable.
    fn supervise_axes(&mut self) {
        let (tick, cycle) = (self.clock.tick, self.clock.cycle);
        let ending = self.ending();
        if !ending && self.axes.iter().any(|a| a.m.faulted()) {
            for a in self.axes.iter_mut() {
                if !a.m.faulted() && !a.m.stopping() && a.m.state() == Some(State::OperationEnabled)
                {
                    a.m.begin_stop(StopKind::Ramp, tick, cycle);
                }
            }
        }
        for a in self.axes.iter_mut() {
            a.m.supervise_stop(cycle, self.consts.stop_timeout_cycles, ending);
        }
    }

    /// The next instant: one after this cycle's on the SYNC0 grid when the reference clock
    /// answered, else one cycle on; missed instants are skipped ([`schedule`]).
    fn schedule_next(&mut self) {
        let c = &mut self.clock;
        c.next_wake =
            schedule::next_instant(c.next_wake, c.next_at, self.consts.cycle_ns, monotonic_ns());
    }
}
