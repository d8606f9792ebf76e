//! `ecdrive soak`: the demo's two emulated drives (MR-J4-TM and BDHDE, in-process) running
//! their programs over and over for a long time while the software slave drops a fraction of
//! the frames at random, and a count of what happened.
//!
//! The master runs as an application would run it: automatic re-start
//! ([`RestartPolicy::Auto`]); after a controlled stop (too many lost frames in a row, a drive
//! fault) the soak resets faults, enables the axes again and restarts the programs. Every
//! history entry is counted by [`HistoryKind`]. An error is *handled* when the master reacted
//! as documented (lost cycles held the set-point; a controlled stop; a decoded fault; a
//! re-start) and the soak could bring the axes back to motion. It is *unhandled* when the
//! session ended by itself, a command or a recovery failed, an axis stayed enabled while a
//! fault was shown, or an entry of a kind that lost frames must not cause (state-machine
//! failures, refused commands, a session error) appeared.

use super::cycle::CycleSettings;
use super::demo;
use super::error::{ErrorKind, MasterError};
use super::session::{HistoryKind, Master, MasterConfig, RestartPolicy};
use super::startup::{DriveSetup, Selector};
use super::telemetry::{Axes, Command, Phase, StopKind, Telemetry};
use crate::cia402::State;
use crate::drives;
use crate::rt::{RtSettings, Summary};
use crate::sim::faults::{Fault, LinkFault};
use crate::sim::transport::SegmentLink;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// Options of a soak run.
#[derive(Debug, Clone)]
pub struct SoakOptions {
    /// How long to run.
    pub duration: Duration,
    /// Cycle time.
    pub cycle: Duration,
    /// Fraction of frames the software slave drops at random (0.01 = 1 %).
    pub drop: f32,
    /// Seed of the drop pattern.
    pub seed: u64,
    /// Real-time settings of the cycle thread.
    pub rt: RtSettings,
    /// Progress callback, called about once a second with the elapsed time and the counts.
    pub progress: Option<fn(Duration, &SoakCounts)>,
}

impl Default for SoakOptions {
    fn default() -> Self {
        Self {
            duration: Duration::from_secs(3600),
            cycle: Duration::from_millis(1),
            drop: 0.01,
            seed: 1,
            rt: demo::DemoOptions::default().rt,
            progress: None,
        }
    }
}

/// Running counts of a soak.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SoakCounts {
    /// Cycles run (over every re-start).
    pub cycles: u64,
    /// Cycles without a reply, as the master counted them.
    pub lost_cycles: u64,
    /// Cycles whose wake-up came more than a whole cycle late (a stall of the machine; long
    /// ones make the drives' own loss supervision trip, which the master then handles).
    pub late_wakeups: u64,
    /// Programs run to their end (both axes together count once).
    pub programs_completed: u64,
    /// Times the soak brought the axes back to motion after a controlled stop.
    pub recoveries: u64,
    /// Re-starts of the segment.
    pub restarts: u32,
    /// History entries per kind (errors and information alike).
    pub history: BTreeMap<String, u64>,
    /// Unhandled errors, each with what and when.
    pub unhandled: Vec<String>,
    /// The first error entries of the history other than lost frames (at most
    /// [`MAX_ERRORS`]), each with when, for the reader.
    pub errors: Vec<String>,
}

/// At most this many error texts are kept in [`SoakCounts::errors`].
pub const MAX_ERRORS: usize = 200;

/// The result of a soak run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SoakReport {
    /// Seconds run.
    pub seconds: f64,
    /// Cycle time, µs.
    pub cycle_us: u64,
    /// The drop fraction asked for.
    pub drop: f32,
    /// Frames the software slave answered.
    pub frames: u64,
    /// Frames it dropped (on either leg).
    pub frames_dropped: u64,
    /// The counts.
    pub counts: SoakCounts,
    /// Wake-up latency of the cycle thread, ns, over the cycles since the last re-start (the
    /// whole run when there was none): stalls of the machine show in its maximum.
    pub wake_latency_ns: Summary,
    /// Whether the drives were taken to INIT at the end.
    pub shutdown_ok: bool,
    /// No unhandled error, the session ran to the end, and the drives were shut down.
    pub ok: bool,
}

fn soak_error(reason: impl std::fmt::Display) -> MasterError {
    MasterError::new(None, "the soak", ErrorKind::Bus, reason)
}

/// Run a soak. Errors only when it cannot start at all; everything after that is counted in
/// the report.
pub fn run(opts: &SoakOptions) -> Result<SoakReport, MasterError> {
    if !(0.0..=1.0).contains(&opts.drop) {
        return Err(MasterError::new(
            None,
            "the soak",
            ErrorKind::Config,
            format!("drop fraction {} is not between 0 and 1", opts.drop),
        ));
    }
    let profiles = [&drives::mr_j4_tm::PROFILE, &drives::bdhde::PROFILE];
    let mut cfg = MasterConfig::new(opts.cycle);
    cfg.cycle = CycleSettings {
        rt: opts.rt.clone(),
        ..CycleSettings::new(opts.cycle)
    };
    cfg.restart = RestartPolicy::Auto {
        retry_every: Duration::from_millis(500),
        max_attempts: None,
    };
    for (i, p) in profiles.iter().enumerate() {
        cfg.startup.drives.push(DriveSetup {
            program: demo::program(p),
            ..DriveSetup::new(Selector::Position(i as u16))
        });
    }
    let steps: Vec<usize> = profiles.iter().map(|p| demo::program(p).len()).collect();
    let mut seg = demo::segment()?;
    let mut faults = seg.fault_handle();
    let mut m = Master::start(SegmentLink::new(seg), cfg).map_err(|f| f.error)?;
    // The drops start once the drives are in OP: start-up has its own retries.
    m.wait_until("every drive in OP", Duration::from_secs(10), |t| {
        t.cycle.all_op
    })?;
    for f in [
        LinkFault::Seed(opts.seed),
        LinkFault::DropFraction(opts.drop),
    ] {
        faults
            .inject(Fault::Link(f))
            .map_err(|e| soak_error(format!("injecting {f:?}: {e}")))?;
    }

    let start = Instant::now();
    let mut counts = SoakCounts::default();
    let mut next_seq = 0u64;
    let mut next_progress = Duration::from_secs(1);
    let mut running_program = false;
    let mut rec = Recovery::default();
    let mut last_restarts = 0u32;
    let mut cycles_before: u64 = 0;
    let mut last_cycle: u64 = 0;
    let mut lost_before: u64 = 0;
    let mut last_lost: u64 = 0;
    let mut overruns_before: u64 = 0;
    let unhandled = |counts: &mut SoakCounts, what: String| {
        counts
            .unhandled
            .push(format!("{:.3} s: {what}", start.elapsed().as_secs_f64()));
    };

    while start.elapsed() < opts.duration {
        std::thread::sleep(POLL);
        if !m.is_running() {
            unhandled(&mut counts, "the session ended by itself".into());
            break;
        }
        // History: only what is new; count by kind, judge what lost frames must not cause.
        let h = m.history_since(next_seq);
        next_seq = h.next;
        if h.missed > 0 {
            unhandled(
                &mut counts,
                format!(
                    "{} history entries were discarded before the soak read them",
                    h.missed
                ),
            );
        }
        counts.history = kind_counts(&h.totals);
        for e in &h.entries {
            if !e.error || e.kind == HistoryKind::FrameLost {
                continue;
            }
            let drive = e.drive.as_ref().map_or(String::new(), |d| format!("{d}: "));
            let text = format!("{:.3} s: {drive}{}", start.elapsed().as_secs_f64(), e.text);
            // A command that crossed the end of a cycle (sent on the last `Cycling` snapshot)
            // is not carried out while the session re-starts (`NoCycle`): handled.
            if matches!(e.kind, HistoryKind::CommandRefused | HistoryKind::Session) {
                counts.unhandled.push(text.clone());
            }
            if counts.errors.len() < MAX_ERRORS {
                counts.errors.push(text);
            }
        }

        let t: Telemetry = m.telemetry().clone();
        if t.cycle.restarts != last_restarts {
            // A re-start: the cycle counter began again.
            last_restarts = t.cycle.restarts;
            cycles_before += last_cycle;
            last_cycle = 0;
            lost_before += last_lost;
            last_lost = 0;
            overruns_before = counts.late_wakeups;
        }
        last_cycle = last_cycle.max(t.cycle.cycle);
        last_lost = last_lost.max(t.cycle.lost);
        counts.cycles = cycles_before + last_cycle;
        counts.lost_cycles = lost_before + last_lost;
        counts.late_wakeups = counts.late_wakeups.max(overruns_before + t.cycle.overruns);
        counts.restarts = t.cycle.restarts;
        if start.elapsed() >= next_progress {
            next_progress += Duration::from_secs(1);
            if let Some(p) = opts.progress {
                p(start.elapsed(), &counts);
            }
        }
        if t.cycle.phase != Phase::Cycling || !t.cycle.all_op {
            // Stopped, re-starting: the recovery begins again once the drives are in OP.
            rec = Recovery::default();
            continue;
        }
        // A fault must never leave an axis enabled.
        for (i, a) in t.axes.iter().enumerate() {
            if a.statusword & FAULT_BIT != 0 && a.state == Some(State::OperationEnabled) {
                unhandled(&mut counts, format!("axis {i} enabled with a fault shown"));
            }
        }
        let done = t
            .axes
            .iter()
            .zip(&steps)
            .all(|(a, n)| !a.program_running && a.program_step as usize >= *n);
        let all_enabled = t
            .axes
            .iter()
            .all(|a| a.state == Some(State::OperationEnabled));
        let any_running = t.axes.iter().any(|a| a.program_running);
        if running_program && done && all_enabled {
            counts.programs_completed += 1;
            running_program = false;
        }
        match rec.next(&t, all_enabled) {
            Action::None => {}
            Action::RunProgram => {
                if !any_running && !running_program {
                    m.command(Command::RunProgram(Axes::All))?;
                    running_program = true;
                }
            }
            Action::FaultReset(axes) => {
                running_program = false;
                for i in axes {
                    m.command(Command::FaultReset(Axes::One(i)))?;
                }
            }
            Action::Enable => {
                m.command(Command::Enable(Axes::All))?;
                counts.recoveries += 1;
                running_program = false;
            }
            Action::Unhandled(what, reset) => {
                unhandled(&mut counts, what);
                for i in reset {
                    m.command(Command::FaultReset(Axes::One(i)))?;
                }
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let (report, link) = m.stop(StopKind::Ramp);
    let report = report.ok_or_else(|| soak_error("the session ended without a report"))?;
    counts.history = kind_counts(&report.history_totals);
    let wake_latency_ns = report
        .cycle
        .as_ref()
        .map(|c| c.timing.wake_latency.summary())
        .unwrap_or_default();
    if let Some(c) = &report.cycle {
        counts.cycles = counts.cycles.max(cycles_before + c.cycles);
        counts.lost_cycles = counts.lost_cycles.max(lost_before + c.lost);
    }
    counts.restarts = report.restarts;
    let stats = link.segment().stats();
    let ok = counts.unhandled.is_empty() && report.shutdown_ok;
    Ok(SoakReport {
        seconds,
        cycle_us: opts.cycle.as_micros() as u64,
        drop: opts.drop,
        frames: stats.frames,
        frames_dropped: stats.dropped,
        counts,
        wake_latency_ns,
        shutdown_ok: report.shutdown_ok,
        ok,
    })
}

fn any_energised(t: &Telemetry) -> bool {
    t.axes
        .iter()
        .any(|a| a.state.is_some_and(State::is_energised))
}

fn kind_counts(totals: &BTreeMap<HistoryKind, u64>) -> BTreeMap<String, u64> {
    totals.iter().map(|(k, n)| (format!("{k:?}"), *n)).collect()
}

/// How often the soak looks at the telemetry and the history.
const POLL: Duration = Duration::from_millis(10);
/// Statusword bit 3, Fault.
const FAULT_BIT: u16 = 0x0008;
/// How long the axes stay disabled (no fault) before the soak enables them again.
const SETTLE: Duration = Duration::from_millis(50);
/// How long a fault may stay shown after the reset was requested (the master's planner pulses
/// bit 7 until the drive leaves Fault); longer is an unhandled error.
const FAULT_CLEAR_LIMIT: Duration = Duration::from_secs(5);
/// A fault still (or again) shown this long after the last reset request gets another.
const RESET_RETRY: Duration = Duration::from_secs(1);
/// How long the axes may take to reach Operation enabled after the request (no fault meanwhile).
const ENABLE_LIMIT: Duration = Duration::from_secs(5);

/// What the application does next, as the soak's operator would.
#[derive(Debug, PartialEq)]
enum Action {
    None,
    RunProgram,
    /// Reset the fault of these axes.
    FaultReset(Vec<u16>),
    Enable,
    /// An unhandled error, and the axes whose reset is requested again.
    Unhandled(String, Vec<u16>),
}

/// The soak's recovery after a controlled stop, as an application would do it: while a fault
/// is shown, request a reset of the faulted axis (the master then pulses bit 7 until the drive
/// leaves Fault), and again every [`RESET_RETRY`] while it is still or again shown; once no
/// axis shows a fault and none is energised, wait a moment and enable them all; once all are
/// enabled, run the programs.
///
/// A fault that appears while the enable is under way cancels it (the master refuses to
/// energise a faulted drive); the reset and the enable then start again. It is an unhandled
/// error when a fault stays shown [`FAULT_CLEAR_LIMIT`] after its first reset request, or the
/// axes are not enabled [`ENABLE_LIMIT`] after the request without a fault meanwhile.
#[derive(Debug)]
struct Recovery {
    /// How long the axes stay idle before the enable ([`SETTLE`]).
    settle: Duration,
    /// [`FAULT_CLEAR_LIMIT`].
    fault_clear_limit: Duration,
    /// [`ENABLE_LIMIT`].
    enable_limit: Duration,
    /// [`RESET_RETRY`].
    reset_retry: Duration,
    /// Per axis, in this fault episode: when the first and the last reset were requested.
    reset_at: Vec<Option<(Instant, Instant)>>,
    /// Since when no axis has been energised nor faulted.
    idle_since: Option<Instant>,
    /// When the enable was requested.
    enable_at: Option<Instant>,
}

impl Default for Recovery {
    fn default() -> Self {
        Self {
            settle: SETTLE,
            fault_clear_limit: FAULT_CLEAR_LIMIT,
            enable_limit: ENABLE_LIMIT,
            reset_retry: RESET_RETRY,
            reset_at: Vec::new(),
            idle_since: None,
            enable_at: None,
        }
    }
}

impl Recovery {
    fn next(&mut self, t: &Telemetry, all_enabled: bool) -> Action {
        self.reset_at.resize(t.axes.len(), None);
        let now = Instant::now();
        let mut reset = Vec::new();
        let mut unhandled = None;
        for (i, a) in t.axes.iter().enumerate() {
            let Some(slot) = self.reset_at.get_mut(i) else {
                continue;
            };
            if a.statusword & FAULT_BIT == 0 {
                // No fault (any more): the next fault is a new episode.
                *slot = None;
                continue;
            }
            match *slot {
                None => {
                    *slot = Some((now, now));
                    reset.push(i as u16);
                }
                Some((first, _)) if now.duration_since(first) > self.fault_clear_limit => {
                    *slot = Some((now, now));
                    reset.push(i as u16);
                    unhandled = Some(format!(
                        "axis {i}: fault (0x603F = 0x{:04X}, state {:?}, statusword 0x{:04X}, \
                         controlword 0x{:04X}) still shown {:?} after its reset was requested",
                        a.error_code, a.state, a.statusword, a.controlword, self.fault_clear_limit
                    ));
                }
                Some((first, last)) if now.duration_since(last) > self.reset_retry => {
                    // Shown again (a new fault right after the reset, between two looks) or
                    // still: ask again, as an application would.
                    *slot = Some((first, now));
                    reset.push(i as u16);
                }
                Some(_) => {}
            }
        }
        if let Some(what) = unhandled {
            return Action::Unhandled(what, reset);
        }
        let faulted = self.reset_at.iter().any(Option::is_some);
        if faulted {
            // A fault cancels an enable under way; it starts again after the reset.
            self.enable_at = None;
            self.idle_since = None;
            return if reset.is_empty() {
                Action::None
            } else {
                Action::FaultReset(reset)
            };
        }
        if all_enabled {
            self.enable_at = None;
            self.idle_since = None;
            return Action::RunProgram;
        }
        if let Some(at) = self.enable_at {
            if now.duration_since(at) > self.enable_limit {
                self.enable_at = None;
                return Action::Unhandled(
                    format!(
                        "the axes are not enabled {:?} after the request (states {:?})",
                        self.enable_limit,
                        t.axes.iter().map(|a| a.state).collect::<Vec<_>>()
                    ),
                    Vec::new(),
                );
            }
            return Action::None;
        }
        if any_energised(t) {
            // Still stopping (a ramp, a quick stop): wait.
            self.idle_since = None;
            return Action::None;
        }
        let since = *self.idle_since.get_or_insert(now);
        if now.duration_since(since) < self.settle {
            return Action::None;
        }
        self.idle_since = None;
        self.enable_at = Some(now);
        Action::Enable
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::master::telemetry::AxisTelemetry;

    fn telemetry(states: &[(State, bool)]) -> Telemetry {
        Telemetry {
            axes: states
                .iter()
                .map(|&(state, fault)| AxisTelemetry {
                    state: Some(state),
                    statusword: if fault { FAULT_BIT } else { 0 },
                    error_code: if fault { 0xFF86 } else { 0 },
                    ..AxisTelemetry::default()
                })
                .collect(),
            ..Telemetry::default()
        }
    }

    fn quick() -> Recovery {
        Recovery {
            settle: Duration::ZERO,
            reset_retry: Duration::from_millis(15),
            fault_clear_limit: Duration::from_millis(30),
            enable_limit: Duration::from_millis(30),
            ..Recovery::default()
        }
    }

    const SOD: State = State::SwitchOnDisabled;
    const OE: State = State::OperationEnabled;

    #[test]
    fn one_reset_per_faulted_axis_and_episode_then_enable_then_run() {
        let mut r = quick();
        let faulted = telemetry(&[(State::Fault, true), (SOD, false)]);
        assert_eq!(r.next(&faulted, false), Action::FaultReset(vec![0]));
        // Still in Fault within the retry time: the master pulses bit 7; no second request.
        assert_eq!(r.next(&faulted, false), Action::None);
        let idle = telemetry(&[(SOD, false), (SOD, false)]);
        assert_eq!(r.next(&idle, false), Action::Enable);
        assert_eq!(r.next(&idle, false), Action::None);
        let enabled = telemetry(&[(OE, false), (OE, false)]);
        assert_eq!(r.next(&enabled, true), Action::RunProgram);
        // A new fault is a new episode: a new reset.
        let both = telemetry(&[(State::Fault, true), (State::Fault, true)]);
        assert_eq!(r.next(&both, false), Action::FaultReset(vec![0, 1]));
    }

    #[test]
    fn a_fault_during_the_enable_cancels_it_and_recovery_starts_again() {
        let mut r = quick();
        let idle = telemetry(&[(SOD, false), (SOD, false)]);
        assert_eq!(r.next(&idle, false), Action::Enable);
        let faulted = telemetry(&[(State::Fault, true), (State::Fault, true)]);
        assert_eq!(r.next(&faulted, false), Action::FaultReset(vec![0, 1]));
        std::thread::sleep(Duration::from_millis(10));
        assert_eq!(r.next(&idle, false), Action::Enable);
    }

    #[test]
    fn a_fault_that_stays_and_an_enable_that_never_comes_are_unhandled() {
        let mut r = quick();
        let faulted = telemetry(&[(State::Fault, true), (SOD, false)]);
        assert_eq!(r.next(&faulted, false), Action::FaultReset(vec![0]));
        std::thread::sleep(Duration::from_millis(20));
        // Still shown after the retry time: asked again.
        assert_eq!(r.next(&faulted, false), Action::FaultReset(vec![0]));
        std::thread::sleep(Duration::from_millis(20));
        let Action::Unhandled(what, again) = r.next(&faulted, false) else {
            panic!("a fault that stays must be reported");
        };
        assert!(what.contains("axis 0") && what.contains("0xFF86"), "{what}");
        assert_eq!(again, vec![0]);

        let mut r = quick();
        let idle = telemetry(&[(SOD, false), (SOD, false)]);
        assert_eq!(r.next(&idle, false), Action::Enable);
        std::thread::sleep(Duration::from_millis(40));
        let Action::Unhandled(what, _) = r.next(&idle, false) else {
            panic!("an enable that never comes must be reported");
        };
        assert!(what.contains("not enabled"), "{what}");
    }

    #[test]
    fn energised_axes_are_left_to_stop_first() {
        let mut r = quick();
        let stopping = telemetry(&[(State::QuickStopActive, false), (SOD, false)]);
        assert_eq!(r.next(&stopping, false), Action::None);
    }
}
