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

use super::exec::{self, ExchangeError};
use super::io::{FrameLink, Pump};
use super::program::{CyclicMode, Runner, Tick};
use super::setpoint::Sample;
use super::startup::{ConfiguredDrive, ConfiguredIo, DriveFields, Group};
use super::telemetry::{
    AxisTelemetry, Command, CycleTelemetry, Event, EventKind, IO_TELEMETRY_BYTES, IoTelemetry,
    Phase, StopKind, StopReason, Telemetry,
};
use crate::cia402::{
    self, Axis, AxisConfig, ErrorCode, Feedback, ModeSwitchPhase, OperationMode, State, StatusWord,
};
use crate::ec::register;
use crate::pdo::Field;
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
    /// Cycles of valid outputs in SAFE-OP before OP is requested.
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
}

impl CycleSettings {
    /// Defaults for a cycle time.
    pub fn new(cycle: Duration) -> Self {
        Self {
            cycle,
            rt: RtSettings::default(),
            safeop_cycles: 20,
            op_timeout: Duration::from_secs(5),
            lost_before_stop: 3,
            segment_lost_after: 3,
            segment_gone_after: Duration::from_millis(200),
            wkc_errors_before_stop: 3,
            stop_ramp: Duration::from_millis(200),
            stop_timeout: Duration::from_secs(3),
            reply_budget: 0.8,
            steady_timing_only: false,
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
    /// Per axis: the modes it ran set-points in.
    pub modes_run: Vec<Vec<CyclicMode>>,
    /// Per axis: the largest change of the streamed set-point from one cycle to the next while
    /// the drive was enabled, for each kind (across mode switches too: a jump shows here).
    pub max_setpoint_step: Vec<SetpointSteps>,
    /// Per axis: the states it went through, in order (consecutive duplicates removed).
    pub states: Vec<Vec<State>>,
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

struct AxisRt {
    /// Position on the segment (index in the group).
    sub: usize,
    axis: Axis,
    fields: DriveFields,
    velocity_unit: f64,
    runner: Runner,
    program: ProgramState,
    /// Set-point held when no program runs (position/velocity/torque by mode).
    hold: Sample,
    mode: CyclicMode,
    requested_mode: Option<CyclicMode>,
    fe_limit: Option<u32>,
    /// 0x60F4 was seen other than 0 while the axis moved in csp.
    fe_drive_alive: bool,
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
    modes_run: Vec<CyclicMode>,
    steps: SetpointSteps,
    last_out: Option<(i32, i32, i16)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ProgramState {
    Idle,
    Pending,
    Running,
}

fn read_u(f: &Field, buf: &[u8]) -> u64 {
    f.read_raw(buf).unwrap_or(0)
}

fn read_i(f: &Field, buf: &[u8]) -> i64 {
    f.read_int(buf).map(|v| v as i64).unwrap_or(0)
}

fn write_i(f: &Field, buf: &mut [u8], v: i64) {
    let _ = f.write_int(buf, v as i128);
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
) -> CycleReport {
    let rt = settings.rt.apply_to_current_thread();
    if let Some(tx) = io.rt_report.take() {
        let _ = tx.send(rt.clone());
    }
    let cycle_ns = settings.cycle.as_nanos() as u64;
    let dt = settings.cycle.as_secs_f64();
    let n = drives.len();

    // ---- set-up (allocations allowed) ----------------------------------------------------
    let mut axes: Vec<AxisRt> = Vec::with_capacity(n);
    for d in drives {
        let initial = OperationMode::from_i8(d.setup.mode.code());
        let cfg = AxisConfig::for_cycle_time(&d.profile.caps, settings.cycle, initial);
        let axis = match Axis::new(d.profile.caps, cfg) {
            Ok(a) => a,
            Err(_) => match Axis::new(
                d.profile.caps,
                AxisConfig::for_cycle_time(
                    &d.profile.caps,
                    settings.cycle,
                    OperationMode::CyclicSyncPosition,
                ),
            ) {
                Ok(a) => a,
                Err(_) => continue,
            },
        };
        axes.push(AxisRt {
            sub: usize::from(d.info.position),
            axis,
            fields: d.fields.clone(),
            velocity_unit: d.profile.units.velocity_unit_counts_per_s,
            runner: Runner::new(d.setup.program.clone(), d.setup.mode),
            program: ProgramState::Idle,
            hold: Sample::default(),
            mode: d.setup.mode,
            requested_mode: None,
            fe_limit: d.setup.following_error_limit,
            fe_drive_alive: false,
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
            steps: SetpointSteps::default(),
            last_out: None,
        });
    }
    // Outputs that carry fixed values from the first cycle on.
    for a in axes.iter() {
        if let Ok(sd) = group.subdevice(md, a.sub) {
            let mut io = sd.io_raw_mut();
            let out = io.outputs();
            for (f, v) in &a.fields.held_outputs {
                let _ = f.write_raw(out, *v);
            }
            for (f, v) in &a.fields.output_defaults {
                write_i(f, out, *v);
            }
            write_i(&a.fields.controlword, out, 0);
        }
    }
    {
        let t = io.telemetry.input_buffer_mut();
        t.axes.resize(axes.len(), AxisTelemetry::default());
        t.io.resize(others.len(), IoTelemetry::default());
    }
    let mut timing = Timing::default();
    // Every device counts: an LRW adds 2 for each device with outputs, 1 for each with inputs.
    let wkc = |outputs: usize, inputs: usize| u16::from(outputs > 0) * 2 + u16::from(inputs > 0);
    let wkc_expected: u16 = drives
        .iter()
        .map(|d| {
            wkc(
                d.layout.bytes(crate::pdo::Direction::Rx),
                d.layout.bytes(crate::pdo::Direction::Tx),
            )
        })
        .chain(others.iter().map(|o| wkc(o.outputs, o.inputs)))
        .sum();
    // Every device by position: its station address and last AL state.
    let n_devices = group.len();
    let mut addresses = vec![0u16; n_devices];
    for d in drives {
        if let Some(a) = addresses.get_mut(usize::from(d.info.position)) {
            *a = d.info.address;
        }
    }
    for o in others {
        if let Some(a) = addresses.get_mut(usize::from(o.info.position)) {
            *a = o.info.address;
        }
    }
    let mut al_states = vec![0u8; n_devices];
    // The I/O devices as last seen (a lost cycle keeps the inputs of the last reply).
    let mut io_last = vec![IoTelemetry::default(); others.len()];

    // ---- the loop (no allocation from here on) -------------------------------------------
    let mut cycle: u64 = 0;
    // Cycles with a reply: the clock of the programs and the stop ramps (a lost cycle holds
    // the set-point, so the motion resumes where it stood).
    let mut tick: u64 = 0;
    let mut end_reason: Option<CycleEnd> = None;
    let mut segment_lost = false;
    let segment_gone_cycles = (settings.segment_gone_after.as_nanos() as u64 / cycle_ns.max(1))
        .max(u64::from(settings.segment_lost_after));
    let mut lost_total: u64 = 0;
    let mut consecutive_lost: u32 = 0;
    let mut wkc_errors: u32 = 0;
    let mut overruns: u64 = 0;
    // What the timing histograms and the report's counts cover (see `steady_timing_only`).
    let mut recording = !settings.steady_timing_only;
    let mut recording_from_next = false;
    let mut recording_ends = false;
    let mut recorded_lost: u64 = 0;
    let mut recorded_overruns: u64 = 0;
    let mut all_op = false;
    let mut op_requested_at: Option<u64> = None;
    let mut preop_requested_at: Option<u64> = None;
    let mut ending = false;
    // Why the axes were first stopped (what ended the run), if they were.
    let mut first_stop: Option<StopReason> = None;
    let mut last_telemetry = CycleTelemetry::default();
    let mut steady = false;
    let end;
    let mut last_wake: u64 = 0;
    let mut next_wake = monotonic_ns() + cycle_ns;
    let mut dc_time: u64 = 0;
    let mut last_wkc: u16 = 0;
    let stop_ramp_cycles = (settings.stop_ramp.as_nanos() as u64 / cycle_ns.max(1)).max(1);
    let stop_timeout_cycles = (settings.stop_timeout.as_nanos() as u64 / cycle_ns.max(1)).max(1);

    macro_rules! emit {
        ($kind:expr) => {{
            let kind = $kind;
            if let EventKind::Stopping { reason } = kind
                && first_stop.is_none()
            {
                first_stop = Some(reason);
            }
            let _ = io.events.push(Event {
                cycle,
                time_ns: monotonic_ns(),
                kind,
            });
        }};
    }

    loop {
        if recording_from_next {
            recording_from_next = false;
            recording = true;
        }
        sleep_until_ns(next_wake);
        let woke = monotonic_ns();
        let latency = woke.saturating_sub(next_wake);
        if recording {
            timing.wake_latency.record(latency);
            if last_wake != 0 {
                timing.period.record(woke - last_wake);
            }
        }
        if latency > cycle_ns {
            overruns += 1;
            if recording {
                recorded_overruns += 1;
            }
        }
        last_wake = woke;
        cycle += 1;

        // 1. Exchange the process data.
        let deadline = woke + (cycle_ns as f64 * settings.reply_budget) as u64;
        let t_ex = monotonic_ns();
        let result = {
            let fut = pin!(group.tx_rx_dc(md));
            exec::exchange(pump, fut, deadline)
        };
        let t_ex_done = monotonic_ns();
        let mut next_wait: Option<u64> = None;
        let mut good = false;
        match result {
            Ok(Ok(resp)) => {
                good = true;
                tick += 1;
                if recording {
                    timing.exchange.record(t_ex_done - t_ex);
                }
                if consecutive_lost > 0 {
                    emit!(EventKind::FramesResumed {
                        lost: consecutive_lost
                    });
                }
                consecutive_lost = 0;
                segment_lost = false;
                dc_time = resp.extra.dc_system_time;
                last_wkc = resp.working_counter;
                next_wait = Some(resp.extra.next_cycle_wait.as_nanos() as u64);
                // AL states (state checks ride along with the LRW).
                let mut missing: Option<u16> = None;
                let mut every_op = true;
                let mut left_op: Option<(u16, u8)> = None;
                for (i, st) in resp.subdevice_states.iter().enumerate() {
                    let raw: u8 = match st {
                        SubDeviceState::None => 0,
                        SubDeviceState::Init => 1,
                        SubDeviceState::PreOp => 2,
                        SubDeviceState::Bootstrap => 3,
                        SubDeviceState::SafeOp => 4,
                        SubDeviceState::Op => 8,
                        SubDeviceState::Other(v) => *v,
                    };
                    if raw == 0 && missing.is_none() {
                        missing = Some(i as u16);
                    }
                    if raw != 8 {
                        every_op = false;
                    }
                    if let Some(a) = axes.iter_mut().find(|a| a.sub == i) {
                        a.al_state = raw;
                    }
                    if let Some(prev) = al_states.get_mut(i)
                        && *prev != raw
                    {
                        let was_op = *prev == 8;
                        *prev = raw;
                        emit!(EventKind::AlState {
                            device: i as u16,
                            state: raw
                        });
                        if was_op && raw != 8 && !ending {
                            // A device left OP on its own: decode why, stop every axis, end.
                            let addr = addresses.get(i).copied().unwrap_or(0);
                            let code = {
                                let fut = pin!(
                                    EcCommand::fprd(addr, register::AL_STATUS_CODE)
                                        .receive::<u16>(md)
                                );
                                match exec::exchange(pump, fut, monotonic_ns() + cycle_ns / 4) {
                                    Ok(Ok(c)) => Some(c),
                                    _ => None,
                                }
                            };
                            emit!(EventKind::LeftOp {
                                device: i as u16,
                                state: raw,
                                code
                            });
                            if left_op.is_none() {
                                left_op = Some((i as u16, raw));
                                end_reason = Some(CycleEnd::DriveLeftOp {
                                    device: i as u16,
                                    al_state: raw,
                                    code,
                                });
                            }
                        }
                    }
                }
                if let Some((device, _)) = left_op {
                    emit!(EventKind::Stopping {
                        reason: StopReason::DriveLeftOp { device }
                    });
                    ending = true;
                    for a in axes.iter_mut() {
                        begin_stop(a, StopKind::Ramp, tick, cycle);
                    }
                }
                if !all_op && every_op && n_devices > 0 {
                    all_op = true;
                    if io.restarting {
                        io.restarting = false;
                        io.restarts += 1;
                    }
                    emit!(EventKind::AllOp);
                    if settings.steady_timing_only {
                        recording_from_next = true;
                    }
                    if let Some(h) = hooks {
                        h.steady_begin();
                        steady = true;
                    }
                }
                if all_op && !ending {
                    if resp.working_counter != wkc_expected {
                        wkc_errors += 1;
                        emit!(EventKind::WorkingCounter {
                            got: resp.working_counter,
                            expected: wkc_expected,
                            missing
                        });
                        if wkc_errors == settings.wkc_errors_before_stop && !ending {
                            emit!(EventKind::Stopping {
                                reason: StopReason::WorkingCounter
                            });
                            for a in axes.iter_mut() {
                                begin_stop(a, StopKind::Ramp, tick, cycle);
                            }
                        }
                    } else {
                        wkc_errors = 0;
                    }
                }
            }
            Ok(Err(_)) | Err(ExchangeError::Late) => {
                lost_total += 1;
                if recording {
                    recorded_lost += 1;
                }
                consecutive_lost += 1;
                // Each lost cycle up to the stop and the detection; after that the segment
                // counts as lost, and the count comes with `FramesResumed` or `SegmentGone`.
                if consecutive_lost <= settings.lost_before_stop.max(settings.segment_lost_after) {
                    emit!(EventKind::FrameLost {
                        consecutive: consecutive_lost
                    });
                }
                if consecutive_lost == settings.lost_before_stop && !ending {
                    emit!(EventKind::Stopping {
                        reason: StopReason::FramesLost {
                            cycles: consecutive_lost
                        }
                    });
                    stop_moving_axes(&mut axes, tick, cycle);
                }
                if consecutive_lost == settings.segment_lost_after && !segment_lost {
                    segment_lost = true;
                    emit!(EventKind::SegmentLost {
                        cycles: consecutive_lost
                    });
                    stop_moving_axes(&mut axes, tick, cycle);
                }
                if u64::from(consecutive_lost) >= segment_gone_cycles {
                    emit!(EventKind::SegmentGone {
                        cycles: consecutive_lost
                    });
                    end = CycleEnd::SegmentLost;
                    break;
                }
            }
            Err(ExchangeError::Link(_)) => {
                end = CycleEnd::LinkFailed;
                break;
            }
        }

        // 2. OP: request it after some cycles of valid outputs, then wait for it.
        if !all_op {
            match op_requested_at {
                None if cycle >= u64::from(settings.safeop_cycles) => {
                    for &addr in &addresses {
                        let fut =
                            pin!(EcCommand::fpwr(addr, register::AL_CONTROL).send(md, 0x0008u16));
                        let _ = exec::exchange(pump, fut, monotonic_ns() + cycle_ns / 2);
                    }
                    op_requested_at = Some(cycle);
                }
                Some(at) if (cycle - at) * cycle_ns > settings.op_timeout.as_nanos() as u64 => {
                    let (device, al_state) = al_states
                        .iter()
                        .enumerate()
                        .find(|(_, s)| **s != 8)
                        .map(|(i, s)| (i as u16, *s))
                        .unwrap_or((0, 0));
                    emit!(EventKind::OpTimeout { device, al_state });
                    end = CycleEnd::OpFailed { device, al_state };
                    break;
                }
                _ => {}
            }
        }

        // 3. Commands.
        while let Ok(cmd) = io.commands.pop() {
            match cmd {
                Command::Stop(_) | Command::Restart => {
                    let kind = match cmd {
                        Command::Stop(k) => k,
                        _ => StopKind::Ramp,
                    };
                    if settings.steady_timing_only {
                        recording_ends = true;
                    }
                    if let Some(h) = hooks
                        && steady
                    {
                        h.steady_end();
                        steady = false;
                    }
                    if ending && kind == StopKind::QuickStop {
                        // Asked again to stop, in a hurry: the axes still on their ramp make a
                        // quick stop instead (and are disabled after it, as always).
                        for a in axes.iter_mut() {
                            if matches!(a.stopping, Stopping::Ramp { .. }) {
                                a.axis.request_quick_stop();
                                a.stopping = Stopping::Quick { at: cycle };
                            }
                        }
                    }
                    if !ending {
                        ending = true;
                        let restart = cmd == Command::Restart;
                        end_reason = Some(if restart {
                            CycleEnd::Restart
                        } else {
                            CycleEnd::Stopped
                        });
                        emit!(EventKind::Stopping {
                            reason: if restart {
                                StopReason::Restart
                            } else {
                                StopReason::Requested
                            }
                        });
                        for a in axes.iter_mut() {
                            begin_stop(a, kind, tick, cycle);
                        }
                    }
                }
                other => {
                    for (i, a) in axes.iter_mut().enumerate() {
                        if let Some(why) = apply(a, &other, i) {
                            emit!(EventKind::CommandRefused {
                                axis: i as u16,
                                why
                            });
                        }
                    }
                }
            }
        }

        // 4. Per axis: inputs → program → engine → outputs. On a lost cycle the inputs are
        // stale: every axis holds its set-point (the outputs go out again unchanged), only the
        // drive's cycle counter (if mapped) advances, as the drive expects one per cycle.
        let now_s = tick as f64 * dt;
        // The SYNC0 pulse the frame of this cycle came after (see FEEDBACK_PULSES).
        let pulse = dc_time / cycle_ns.max(1);
        // Whether any axis was energised or running a program as of the last cycle.
        let any_energised_before = axes.iter().any(|a| {
            a.program != ProgramState::Idle || a.tel.state.is_some_and(State::is_energised)
        });
        for (i, a) in axes.iter_mut().enumerate() {
            let Ok(sd) = group.subdevice(md, a.sub) else {
                continue;
            };
            if !good {
                if let Some((c, _)) = &a.fields.counter {
                    a.counter = a.counter.wrapping_add(1);
                    let mut io_w = sd.io_raw_mut();
                    write_i(c, io_w.outputs(), i64::from(a.counter));
                }
                continue;
            }
            if a.al_state & 0x0F != 8 {
                // Below OP nothing of the drive is judged: a slave may serve stale inputs until
                // OP (a mode display of 0, a statusword of 0), and it should not act on the
                // outputs. They stay safe all the same, for a slave that does: Disable voltage.
                let mut io_w = sd.io_raw_mut();
                let o = io_w.outputs();
                write_i(&a.fields.controlword, o, 0);
                if let Some((c, _)) = &a.fields.counter {
                    a.counter = a.counter.wrapping_add(1);
                    write_i(c, o, i64::from(a.counter));
                }
                a.tel.state = None;
                a.tel.al_state = a.al_state;
                continue;
            }
            // The frame just exchanged carried the demand of the last cycle.
            if let Some(d) = a.last_demand {
                a.carried[a.carried_next] = (pulse, d);
                a.carried_next = (a.carried_next + 1) % CARRIED;
            }
            // Inputs.
            let fb = {
                let io_r = sd.io_raw();
                let inp = io_r.inputs();
                let f = &a.fields;
                let sw = read_u(&f.statusword, inp) as u16;
                let pos = f.position.as_ref().map(|p| read_i(p, inp) as i32);
                if let Some(p) = pos {
                    if a.pos_valid {
                        a.pos += i64::from(p.wrapping_sub(a.pos_raw));
                    } else {
                        a.pos = i64::from(p);
                        a.pos_valid = true;
                    }
                    a.pos_raw = p;
                }
                a.tel.statusword = sw;
                a.tel.position_actual = a.pos;
                a.tel.velocity_actual = f.velocity.as_ref().map_or(0, |v| read_i(v, inp) as i32);
                a.tel.torque_actual = f.torque.as_ref().map_or(0, |v| read_i(v, inp) as i16);
                a.tel.mode_display = f.mode_display.as_ref().map_or(0, |v| read_i(v, inp) as i8);
                a.tel.error_code = f.error_code.as_ref().map_or(0, |v| read_u(v, inp) as u16);
                a.tel.following_error_drive = f.following_error.as_ref().map(|fe| read_i(fe, inp));
                Feedback {
                    statusword: StatusWord::from_raw(sw),
                    mode_display: f
                        .mode_display
                        .as_ref()
                        .map(|_| OperationMode::from_i8(a.tel.mode_display)),
                    position: pos,
                    velocity: f.velocity.as_ref().map(|_| a.tel.velocity_actual),
                    torque: f.torque.as_ref().map(|_| a.tel.torque_actual),
                    error_code: f.error_code.as_ref().map(|_| ErrorCode(a.tel.error_code)),
                    zero_speed: f
                        .zero_speed
                        .as_ref()
                        .map(|(z, bit)| read_u(z, inp) >> bit & 1 == 1),
                }
            };

            // Program and stop ramps → set-points.
            let actual = Sample {
                pos: a.pos as f64,
                vel: a.tel.velocity_actual as f64 * a.velocity_unit,
                acc: 0.0,
                torque: f64::from(a.tel.torque_actual),
                done: false,
            };
            let st = a.axis.status();
            let enabled = st.state == Some(State::OperationEnabled) && st.streaming;
            if a.program == ProgramState::Pending && enabled {
                a.runner.seed(actual);
                a.program = ProgramState::Running;
                emit!(EventKind::ProgramStep {
                    axis: i as u16,
                    step: a.runner.step_index() as u16
                });
            }
            let mut sp = a.hold;
            match a.stopping {
                Stopping::Ramp { from, at, .. } => {
                    let k = tick.saturating_sub(at) as f64 / stop_ramp_cycles as f64;
                    if k >= 1.0 || !enabled {
                        a.axis.request_disable();
                        a.stopping = Stopping::Disabling;
                        sp = Sample {
                            vel: 0.0,
                            torque: 0.0,
                            ..from
                        };
                    } else {
                        // Linear velocity (and torque) ramp to zero; position integrates.
                        let t = tick.saturating_sub(at) as f64 * dt;
                        let total = stop_ramp_cycles as f64 * dt;
                        sp = Sample {
                            pos: from.pos + from.vel * (t - t * t / (2.0 * total)),
                            vel: from.vel * (1.0 - k),
                            acc: 0.0,
                            torque: from.torque * (1.0 - k),
                            done: false,
                        };
                    }
                    a.hold = sp;
                }
                Stopping::Quick { at } => {
                    // Disable once the quick stop has run: the drive left Quick stop active
                    // (option codes ending in Switch on disabled), or stands still in it.
                    let in_qs = st.state == Some(State::QuickStopActive);
                    let done = cycle - at > 2 && (!in_qs || st.standstill);
                    if done || cycle - at > stop_timeout_cycles {
                        a.axis.request_disable();
                        a.stopping = Stopping::Disabling;
                    }
                }
                Stopping::Disabling | Stopping::No => {}
            }
            if a.stopping == Stopping::No && a.program == ProgramState::Running && enabled {
                match a.runner.tick(now_s) {
                    Tick::Setpoint(s) => {
                        sp = s;
                        a.hold = s;
                    }
                    Tick::SwitchMode(m) => {
                        let idle = st.mode_switch == ModeSwitchPhase::Idle;
                        if idle && st.active_mode.as_i8() == m.code() {
                            // Already in that mode (a run begins by asking for its start
                            // mode): no switch, no event; go on at once.
                            a.requested_mode = None;
                            a.runner.mode_switched(actual);
                        } else if idle {
                            // Nothing under way (also when an earlier request of this run was
                            // cut short): ask for it.
                            a.requested_mode = Some(m);
                            if a.axis
                                .request_mode(OperationMode::from_i8(m.code()))
                                .is_err()
                            {
                                a.requested_mode = None;
                                emit!(EventKind::CommandRefused {
                                    axis: i as u16,
                                    why: "the program's mode switch was refused"
                                });
                                a.program = ProgramState::Idle;
                            }
                        }
                        // Else a switch is under way: its ModeSwitched event (or the next
                        // look at the active mode) lets the program go on.
                    }
                    Tick::Finished(s) => {
                        sp = s;
                        a.hold = s;
                        a.program = ProgramState::Idle;
                        emit!(EventKind::ProgramDone { axis: i as u16 });
                    }
                }
                let idx = a.runner.step_index() as u16;
                if idx != a.tel.program_step {
                    emit!(EventKind::ProgramStep {
                        axis: i as u16,
                        step: idx
                    });
                }
            }
            // Set-point into the engine, in the active mode.
            if enabled {
                let mode = CyclicMode::from_code(st.active_mode.as_i8()).unwrap_or(a.mode);
                a.mode = mode;
                let _ = match mode {
                    CyclicMode::Csp => a.axis.set_position((sp.pos.round() as i64) as i32),
                    CyclicMode::Csv => a.axis.set_velocity(
                        (sp.vel / a.velocity_unit)
                            .round()
                            .clamp(i32::MIN as f64, i32::MAX as f64) as i32,
                    ),
                    CyclicMode::Cst => a.axis.set_torque(
                        sp.torque.round().clamp(i16::MIN as f64, i16::MAX as f64) as i16,
                    ),
                };
                if a.modes_run.last() != Some(&mode) && a.modes_run.len() < a.modes_run.capacity() {
                    a.modes_run.push(mode);
                }
            } else if a.stopping == Stopping::No {
                // Not enabled: track the actual values so enabling starts without a jump.
                a.hold = actual;
            }

            let out = a.axis.step(&fb);

            // Engine events.
            while let Some(ev) = a.axis.poll_event() {
                match ev {
                    cia402::Event::ModeSwitched { to, .. } => {
                        if let Some(m) = CyclicMode::from_code(to.as_i8()) {
                            a.mode = m;
                            if a.requested_mode == Some(m) {
                                a.requested_mode = None;
                                a.runner.mode_switched(actual);
                            }
                        }
                    }
                    cia402::Event::ModeSwitchFailed(e) if a.requested_mode.is_some() => {
                        // The program asked for this switch and cannot go on without it. A
                        // fault cut it short: the fault itself is what gets reported.
                        a.requested_mode = None;
                        a.program = ProgramState::Idle;
                        if e.reason != cia402::ModeSwitchFailure::Fault {
                            emit!(EventKind::CommandRefused {
                                axis: i as u16,
                                why: "the program stopped: its mode switch failed"
                            });
                        }
                    }
                    cia402::Event::Fault { .. } if !ending => {
                        a.program = ProgramState::Idle;
                        emit!(EventKind::Axis {
                            axis: i as u16,
                            event: ev
                        });
                        // The other axes are stopped after this loop. A fault while nothing
                        // was energised (latched before the run) stops nothing.
                        if any_energised_before {
                            emit!(EventKind::Stopping {
                                reason: StopReason::DriveFault { axis: i as u16 }
                            });
                        }
                        continue;
                    }
                    _ => {}
                }
                emit!(EventKind::Axis {
                    axis: i as u16,
                    event: ev
                });
            }

            // Outputs.
            {
                let mut io_w = sd.io_raw_mut();
                let o = io_w.outputs();
                let f = &a.fields;
                write_i(&f.controlword, o, i64::from(out.controlword.raw()));
                if let Some(m) = &f.mode {
                    write_i(m, o, i64::from(out.mode.as_i8()));
                }
                if let Some(p) = &f.target_position {
                    write_i(p, o, i64::from(out.target_position));
                }
                if let Some(v) = &f.target_velocity {
                    write_i(v, o, i64::from(out.target_velocity));
                }
                if let Some(t) = &f.target_torque {
                    write_i(t, o, i64::from(out.target_torque));
                }
                if let Some((c, _)) = &f.counter {
                    a.counter = a.counter.wrapping_add(1);
                    write_i(c, o, i64::from(a.counter));
                }
            }

            // Set-point steps while enabled, in the mode the drive runs (confirmed by 0x6061):
            // the other targets only track the actual values.
            let running = a.axis.status();
            if enabled && running.streaming {
                if let Some((p, v, t)) = a.last_out {
                    match CyclicMode::from_code(running.active_mode.as_i8()) {
                        Some(CyclicMode::Csp) => {
                            let d = i64::from(out.target_position.wrapping_sub(p)).abs();
                            if d > a.steps.position {
                                a.steps.position = d;
                                a.steps.at_cycle[0] = cycle;
                            }
                        }
                        Some(CyclicMode::Csv) => {
                            let d = (i64::from(out.target_velocity) - i64::from(v)).abs();
                            if d > a.steps.velocity {
                                a.steps.velocity = d;
                                a.steps.at_cycle[1] = cycle;
                            }
                        }
                        Some(CyclicMode::Cst) => {
                            let d = (i64::from(out.target_torque) - i64::from(t)).abs();
                            if d > a.steps.torque {
                                a.steps.torque = d;
                                a.steps.at_cycle[2] = cycle;
                            }
                        }
                        None => {}
                    }
                }
                a.last_out = Some((out.target_position, out.target_velocity, out.target_torque));
            } else {
                a.last_out = None;
            }

            // Following error and telemetry.
            let demand = if a.pos_valid {
                a.pos + i64::from(out.target_position.wrapping_sub(a.pos_raw))
            } else {
                i64::from(out.target_position)
            };
            let state = StatusWord::from_raw(a.tel.statusword).state();
            let energised = state.is_some_and(State::is_energised);
            // The master's own following error, whatever the drive reports in 0x60F4: the
            // actual value of this exchange against the demand it answers (FEEDBACK_PULSES).
            // Without that demand (lost frames just before) the last value stands.
            // The newest demand whose frame passed by pulse s − 2 (two frames after one pulse:
            // the later one's demand is what the drive took).
            if let Some(s) = pulse.checked_sub(FEEDBACK_PULSES) {
                let newest_first = (1..=CARRIED).map(|k| (a.carried_next + CARRIED - k) % CARRIED);
                for k in newest_first {
                    if let Some(&(p, d)) = a.carried.get(k)
                        && p != u64::MAX
                        && p <= s
                    {
                        a.tel.following_error = d - a.pos;
                        break;
                    }
                }
            }
            let moving = a.last_demand.is_some_and(|l| l != demand);
            a.last_demand = Some(demand);
            if energised && a.mode == CyclicMode::Csp {
                let fe = a.tel.following_error.abs();
                if fe > a.tel.max_following_error {
                    a.tel.max_following_error = fe;
                }
                if let Some(d) = a.tel.following_error_drive {
                    a.tel.max_following_error_drive = a.tel.max_following_error_drive.max(d.abs());
                    // 0x60F4 that never leaves 0 while the axis follows a moving set-point is
                    // not computed by the drive: flag it once, never trust it.
                    if d != 0 {
                        a.fe_drive_alive = true;
                    } else if moving
                        && fe > 0
                        && !a.fe_drive_alive
                        && !a.tel.following_error_drive_stuck
                    {
                        a.fe_drive_zero_cycles += 1;
                        if a.fe_drive_zero_cycles >= DRIVE_FE_STUCK_CYCLES {
                            a.tel.following_error_drive_stuck = true;
                            emit!(EventKind::DriveFollowingErrorStuck {
                                axis: i as u16,
                                cycles: a.fe_drive_zero_cycles,
                                master: a.tel.max_following_error
                            });
                        }
                    }
                }
                if let Some(limit) = a.fe_limit
                    && fe > i64::from(limit)
                    && a.stopping == Stopping::No
                {
                    emit!(EventKind::FollowingError {
                        axis: i as u16,
                        value: fe,
                        limit
                    });
                    emit!(EventKind::Stopping {
                        reason: StopReason::FollowingError { axis: i as u16 }
                    });
                    a.stopping = Stopping::Quick { at: cycle };
                    a.axis.request_quick_stop();
                }
            }
            a.tel.controlword = out.controlword.raw();
            a.tel.mode = out.mode.as_i8();
            a.tel.position_demand = demand;
            a.tel.velocity_demand = out.target_velocity;
            a.tel.torque_demand = out.target_torque;
            a.tel.state = state;
            a.tel.al_state = a.al_state;
            a.tel.program_step = a.runner.step_index() as u16;
            a.tel.program_running = a.program == ProgramState::Running;
            if state != a.last_state {
                a.last_state = state;
                if let Some(s) = state
                    && a.states.last() != Some(&s)
                    && a.states.len() < a.states.capacity()
                {
                    a.states.push(s);
                }
            }
        }

        // A drive that faulted: stop every other axis (outside the per-axis loop, so each
        // axis sees the same decision).
        if !ending {
            let faulted = axes.iter().any(|a| a.axis.status().fault);
            if faulted {
                for a in axes.iter_mut() {
                    if !a.axis.status().fault && a.stopping == Stopping::No {
                        let st = a.axis.status();
                        if st.state == Some(State::OperationEnabled) {
                            begin_stop(a, StopKind::Ramp, tick, cycle);
                        }
                    }
                }
            }
        }
        // A controlled stop that takes too long: disable regardless.
        for a in axes.iter_mut() {
            if let Stopping::Ramp { since: at, .. } | Stopping::Quick { at } = a.stopping
                && cycle - at > stop_timeout_cycles
            {
                a.axis.request_disable();
                a.stopping = Stopping::Disabling;
            }
            if a.stopping == Stopping::Disabling
                && !a.axis.status().state.is_some_and(State::is_energised)
                && !ending
            {
                a.stopping = Stopping::No;
            }
        }

        // 5. Telemetry.
        {
            let t = io.telemetry.input_buffer_mut();
            t.cycle = CycleTelemetry {
                cycle,
                dc_time,
                wkc: last_wkc,
                wkc_expected,
                lost: lost_total,
                overruns,
                wake_latency_ns: latency,
                exchange_ns: t_ex_done - t_ex,
                busy_ns: monotonic_ns() - woke,
                all_op,
                lost_in_a_row: consecutive_lost,
                phase: if ending {
                    Phase::Stopping
                } else {
                    Phase::Cycling
                },
                restarts: io.restarts,
            };
            last_telemetry = t.cycle;
            for (slot, a) in t.axes.iter_mut().zip(axes.iter()) {
                *slot = a.tel;
            }
            // Every field of every slot each time: the triple buffer hands out three buffers in
            // turn.
            for ((slot, last), o) in t.io.iter_mut().zip(io_last.iter_mut()).zip(others) {
                let pos = usize::from(o.info.position);
                last.position = o.info.position;
                last.al_state = al_states.get(pos).copied().unwrap_or(0);
                if good && let Ok(sd) = group.subdevice(md, pos) {
                    let img = sd.io_raw();
                    let inp = img.inputs();
                    let n = inp.len().min(IO_TELEMETRY_BYTES);
                    last.inputs[..n].copy_from_slice(&inp[..n]);
                    last.input_len = n as u16;
                }
                *slot = *last;
            }
            io.telemetry.publish();
        }

        // Energised as last seen (on a lost cycle: as of the last reply). A drive below
        // SAFE-OP sends no valid inputs and takes no outputs (its own state machine has
        // disabled it): its last statusword says nothing, so it does not hold the end up.
        let any_energised = axes.iter().any(|a| {
            matches!(a.al_state & 0x0F, 4 | 8) && a.tel.state.is_some_and(State::is_energised)
        });
        if ending
            && !any_energised
            && axes
                .iter()
                .all(|a| !matches!(a.stopping, Stopping::Ramp { .. } | Stopping::Quick { .. }))
        {
            // Every axis is disabled. Leave OP while still exchanging process data (drives
            // in OP with SYNC0 treat missing data as a communication fault): request PRE-OP,
            // and end once no drive is in OP any more.
            match preop_requested_at {
                None => {
                    for &addr in &addresses {
                        let fut =
                            pin!(EcCommand::fpwr(addr, register::AL_CONTROL).send(md, 0x0002u16));
                        let _ = exec::exchange(pump, fut, monotonic_ns() + cycle_ns / 2);
                    }
                    preop_requested_at = Some(cycle);
                }
                Some(at) => {
                    let out_of_op = al_states.iter().all(|s| s & 0x0F != 8);
                    if out_of_op || (cycle - at) * cycle_ns > 1_000_000_000 {
                        emit!(EventKind::Stopped);
                        end = end_reason.unwrap_or(CycleEnd::Stopped);
                        break;
                    }
                }
            }
        }

        if recording {
            timing.busy.record(monotonic_ns() - woke);
        }
        if recording_ends {
            recording = false;
        }
        // 6. Next instant: DC-aligned when the reference clock answered, else one cycle on.
        next_wake = match next_wait {
            Some(w) => t_ex + w,
            None => next_wake + cycle_ns,
        };
        if next_wake <= monotonic_ns() {
            // Overrun: skip to the next instant rather than running back-to-back cycles.
            next_wake = monotonic_ns() + cycle_ns / 2;
        }
    }
    // The cycle has ended: say so until the session publishes what comes next (a whole
    // snapshot: the input buffer of the triple buffer holds an older one).
    {
        let t = io.telemetry.input_buffer_mut();
        t.cycle = CycleTelemetry {
            phase: Phase::Stopping,
            ..last_telemetry
        };
        for (slot, a) in t.axes.iter_mut().zip(axes.iter()) {
            *slot = a.tel;
        }
        io.telemetry.publish();
    }
    if let Some(h) = hooks
        && steady
    {
        h.steady_end();
    }
    CycleReport {
        end,
        cycles: cycle,
        lost: recorded_lost,
        overruns: recorded_overruns,
        timing,
        rt,
        first_stop,
        max_following_error: axes.iter().map(|a| a.tel.max_following_error).collect(),
        max_following_error_drive: axes
            .iter()
            .map(|a| {
                a.fields
                    .following_error
                    .as_ref()
                    .map(|_| a.tel.max_following_error_drive)
            })
            .collect(),
        following_error_drive_stuck: axes
            .iter()
            .map(|a| a.tel.following_error_drive_stuck)
            .collect(),
        modes_run: axes.iter().map(|a| a.modes_run.clone()).collect(),
        max_setpoint_step: axes.iter().map(|a| a.steps).collect(),
        states: axes.iter().map(|a| a.states.clone()).collect(),
    }
}

/// Begin a ramp stop of every axis not already stopping.
fn stop_moving_axes(axes: &mut [AxisRt], tick: u64, cycle: u64) {
    for a in axes.iter_mut().filter(|a| a.stopping == Stopping::No) {
        begin_stop(a, StopKind::Ramp, tick, cycle);
    }
}

/// Begin a controlled stop of one axis at good cycle `tick` (the ramp's clock) and cycle
/// `cycle` (the timeout's).
fn begin_stop(a: &mut AxisRt, kind: StopKind, tick: u64, cycle: u64) {
    a.program = ProgramState::Idle;
    let st = a.axis.status();
    if !st.state.is_some_and(State::is_energised) {
        a.axis.request_disable();
        a.stopping = Stopping::Disabling;
        return;
    }
    a.stopping = match kind {
        StopKind::Ramp => Stopping::Ramp {
            from: a.hold,
            at: tick,
            since: cycle,
        },
        StopKind::QuickStop => {
            a.axis.request_quick_stop();
            Stopping::Quick { at: cycle }
        }
    };
}

/// Apply a command to one axis; `Some(reason)` if it was refused.
fn apply(a: &mut AxisRt, cmd: &Command, i: usize) -> Option<&'static str> {
    match *cmd {
        Command::Enable(ax) if ax.includes(i) => {
            a.stopping = Stopping::No;
            a.axis
                .request_enable()
                .err()
                .map(|_| "enable refused (fault present?)")
        }
        Command::Disable(ax) if ax.includes(i) => {
            a.program = ProgramState::Idle;
            a.axis.request_disable();
            None
        }
        Command::QuickStop(ax) if ax.includes(i) => {
            a.program = ProgramState::Idle;
            a.axis.request_quick_stop();
            None
        }
        Command::FaultReset(ax) if ax.includes(i) => {
            if a.axis.request_fault_reset() {
                None
            } else {
                Some("fault reset ignored: the drive shows no fault")
            }
        }
        Command::Mode(ax, m) if ax.includes(i) => a
            .axis
            .request_mode(OperationMode::from_i8(m.code()))
            .err()
            .map(|_| "mode switch refused"),
        Command::RunProgram(ax) if ax.includes(i) => {
            if a.runner.steps().is_empty() {
                return Some("the axis has no program");
            }
            a.runner.restart();
            a.requested_mode = None;
            a.program = ProgramState::Pending;
            None
        }
        Command::HoldProgram(ax) if ax.includes(i) => {
            a.program = ProgramState::Idle;
            None
        }
        Command::Setpoint(axis, v) if axis as usize == i => {
            match a.mode {
                CyclicMode::Csp => a.hold.pos = v,
                CyclicMode::Csv => a.hold.vel = v,
                CyclicMode::Cst => a.hold.torque = v,
            }
            None
        }
        _ => None,
    }
}

/// Decode a drive's raw AL state for messages.
pub fn al_state_name(raw: u8) -> String {
    let s = crate::ec::AlStatus {
        raw: u16::from(raw),
    };
    s.to_string()
}
