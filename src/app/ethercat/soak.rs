//! `ecdrive soak`: the demo's two emulated drives (MR-J4-TM and BDHDE, in-process) running
//! their programs over and over for a long time while the software slave drops a fraction of
//! the frames at random, and a count of what happened.
//!
//! The master runs as an application would run it: automatic re-start
//! ([`RestartPolicy::Auto`]); after a controlled stop (too many lost frames in a row, a drive
//! fault) the [`Operator`] resets faults, enables the axes again and restarts the programs.
//! Every history entry is counted by [`HistoryKind`]. An error is *handled* when the master
//! reacted as documented (lost cycles held the set-point; a controlled stop; a decoded fault; a
//! re-start) and the operator could bring the axes back to motion. It is *unhandled* when the
//! session ended by itself, a command or a recovery failed, an axis stayed enabled while a
//! fault was shown, history entries were discarded unread, or an entry of a kind that lost
//! frames must not cause ([`recovery::unhandled_kind`]: a refused command, a session error)
//! appeared.

use super::demo;
use super::recovery::{self, Operator, POLL};
use crate::drives;
use crate::master::cycle::CycleSettings;
use crate::master::error::{ErrorKind, MasterError};
use crate::master::session::{HistoryKind, Master, MasterConfig, RestartPolicy};
use crate::master::startup::{DriveSetup, Selector};
use crate::master::telemetry::{StopKind, Telemetry};
use crate::rt::{RtSettings, Summary};
use crate::sim::faults::{Fault, LinkFault};
use crate::sim::transport::SegmentLink;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Options of a soak run.
#[derive(Debug, Clone)]
pub struct SoakOptions {
    /// How long to run.
    pub duration: Duration,
    /// End after this many cycles instead of after [`SoakOptions::duration`] (tests count
    /// cycles, not seconds).
    pub cycles: Option<u64>,
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
    /// Set (e.g. by Ctrl-C) to end the soak early, in a controlled way, with its report.
    pub stop: Option<Arc<AtomicBool>>,
}

impl Default for SoakOptions {
    fn default() -> Self {
        Self {
            duration: Duration::from_secs(3600),
            cycles: None,
            cycle: Duration::from_millis(1),
            drop: 0.01,
            seed: 1,
            rt: demo::DemoOptions::default().rt,
            progress: None,
            stop: None,
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
    /// Whether the soak was ended early ([`SoakOptions::stop`], Ctrl-C).
    pub interrupted: bool,
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
    let (mut m, steps) = start(opts)?;
    let start = Instant::now();
    let mut counts = SoakCounts::default();
    let mut next_seq = 0u64;
    let mut next_progress = Duration::from_secs(1);
    let mut op = Operator::new(steps);
    let mut restarts = Restarts::default();
    let mut interrupted = false;
    while match opts.cycles {
        Some(n) => counts.cycles < n,
        None => start.elapsed() < opts.duration,
    } {
        std::thread::sleep(POLL);
        if opts
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Acquire))
        {
            interrupted = true;
            break;
        }
        if !m.is_running() {
            unhandled(&mut counts, start, "the session ended by itself".into());
            break;
        }
        next_seq = read_history(&m, next_seq, &mut counts, start);
        let t: Telemetry = m.telemetry().clone();
        restarts.count(&t, &mut counts);
        if start.elapsed() >= next_progress {
            next_progress += Duration::from_secs(1);
            if let Some(p) = opts.progress {
                p(start.elapsed(), &counts);
            }
        }
        for what in op.step(&mut m, &t)? {
            unhandled(&mut counts, start, what);
        }
        counts.programs_completed = op.programs_completed;
        counts.recoveries = op.recoveries;
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
        counts.cycles = counts.cycles.max(restarts.cycles_before + c.cycles);
        counts.lost_cycles = counts.lost_cycles.max(restarts.lost_before + c.lost);
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
        interrupted,
        shutdown_ok: report.shutdown_ok,
        ok,
    })
}

/// The demo's drives started with the demo's programs, a master that re-starts the session by
/// itself, in OP, and then the frame drops switched on (start-up has its own retries). Returns
/// the master and each drive's step count.
fn start(opts: &SoakOptions) -> Result<(Master<SegmentLink>, Vec<usize>), MasterError> {
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
    Ok((m, steps))
}

/// What went unhandled, `start` being when the soak began.
fn unhandled(counts: &mut SoakCounts, start: Instant, what: String) {
    counts
        .unhandled
        .push(format!("{:.3} s: {what}", start.elapsed().as_secs_f64()));
}

/// The history since `next_seq`, only what is new: counted by kind, and judged for what lost
/// frames must not cause. Returns the next sequence number to read from.
fn read_history(
    m: &Master<SegmentLink>,
    next_seq: u64,
    counts: &mut SoakCounts,
    start: Instant,
) -> u64 {
    let h = m.history_since(next_seq);
    if h.missed > 0 {
        unhandled(
            counts,
            start,
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
        let text = format!(
            "{:.3} s: {drive}{}",
            start.elapsed().as_secs_f64(),
            e.text()
        );
        // A command that crossed the end of a cycle (sent on the last `Cycling` snapshot)
        // is not carried out while the session re-starts (`NoCycle`): handled.
        if recovery::unhandled_kind(e.kind) {
            counts.unhandled.push(text.clone());
        }
        if counts.errors.len() < MAX_ERRORS {
            counts.errors.push(text);
        }
    }
    h.next
}

/// The cycle's counters across the session's re-starts (each begins them again): what the
/// sessions before the current one counted, and the current one's so far.
#[derive(Default)]
struct Restarts {
    seen: u32,
    cycles_before: u64,
    last_cycle: u64,
    lost_before: u64,
    last_lost: u64,
    overruns_before: u64,
}

impl Restarts {
    /// The soak's cycles, lost cycles, late wake-ups and re-starts, with the telemetry `t`.
    fn count(&mut self, t: &Telemetry, counts: &mut SoakCounts) {
        if t.cycle.restarts != self.seen {
            // A re-start: the cycle counter began again.
            self.seen = t.cycle.restarts;
            self.cycles_before += self.last_cycle;
            self.last_cycle = 0;
            self.lost_before += self.last_lost;
            self.last_lost = 0;
            self.overruns_before = counts.late_wakeups;
        }
        self.last_cycle = self.last_cycle.max(t.cycle.cycle);
        self.last_lost = self.last_lost.max(t.cycle.lost);
        counts.cycles = self.cycles_before + self.last_cycle;
        counts.lost_cycles = self.lost_before + self.last_lost;
        counts.late_wakeups = counts
            .late_wakeups
            .max(self.overruns_before + t.cycle.overruns);
        counts.restarts = t.cycle.restarts;
    }
}

fn kind_counts(totals: &BTreeMap<HistoryKind, u64>) -> BTreeMap<String, u64> {
    totals.iter().map(|(k, n)| (format!("{k:?}"), *n)).collect()
}
