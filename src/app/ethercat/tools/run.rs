//! `ecdrive run`: a cyclic run from a configuration file.
//!
//! [`run`] starts a [`Master`] on the file's target, waits until every drive is in OP, enables
//! every axis, starts each axis's program, and watches until every program has finished, the
//! duration has passed, the caller asks to stop (Ctrl-C), or something stops the axes (a drive
//! fault, the following-error monitor, a drive leaving OP, the segment going silent). Then it
//! stops every axis with a ramp, takes the drives to INIT and reports what happened: per drive
//! the CiA 402 states it went through, the modes it ran, its largest following error and the
//! faults, and the cycle timing.

use super::Target;
use crate::app::config::{RunConfig, UserUnits};
use crate::cia402::State;
use crate::master::HistoryKind;
use crate::master::cycle::CycleEnd;
use crate::master::error::{ErrorKind, MasterError};
use crate::master::session::{DriveOutcome, DriveSummary, HistoryEntry, Master, SessionReport};
use crate::master::startup::{DeviceInfo, Selector};
use crate::master::telemetry::{Axes, Command, StopKind, StopReason, Telemetry};
use crate::rt::Summary;
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Every program finished (or the duration passed) and the axes stopped cleanly.
    Completed,
    /// Stopped on request (Ctrl-C).
    Interrupted,
    /// A drive faulted, or the master stopped the axes because of one (following error, a
    /// drive leaving OP).
    DriveFault,
    /// A drive did not reach OP or refused to be enabled.
    Refused,
    /// The segment stopped answering or the link failed.
    BusLost,
}

impl Outcome {
    /// In words: `completed`, `interrupted`, `drive fault`, `refused`, `bus lost`.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Completed => "completed",
            Self::Interrupted => "interrupted",
            Self::DriveFault => "drive fault",
            Self::Refused => "refused",
            Self::BusLost => "bus lost",
        }
    }
}

/// Where a run is, for progress displays.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunProgress {
    /// What is happening (`starting`, `waiting for OP`, `checking for faults`, `enabling`,
    /// `running`, `stopping`).
    pub phase: &'static str,
    /// Time since the programs started.
    pub elapsed: Duration,
    /// The duration limit, if any.
    pub duration: Option<Duration>,
    /// Program steps done over all axes.
    pub steps_done: usize,
    /// Program steps over all axes.
    pub steps_total: usize,
    /// Cycles run.
    pub cycles: u64,
}

/// Timing of the cycle, ns.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleSummary {
    /// Cycles run.
    pub cycles: u64,
    /// Cycles without a reply.
    pub lost: u64,
    /// Cycles whose wake-up came more than a cycle late.
    pub overruns: u64,
    /// Wake-up latency against the intended instant.
    pub wake_latency: Summary,
    /// Period between wake-ups.
    pub period: Summary,
    /// Frame round trip.
    pub exchange: Summary,
    /// SCHED_FIFO priority granted, if any.
    pub priority: Option<u8>,
    /// CPU pinned, if any.
    pub cpu: Option<usize>,
    /// What the real-time set-up could not get.
    pub rt_warnings: Vec<String>,
    /// The frames of the run: sent, answered, retransmitted, cycles lost and late, wrong
    /// working counters, in total over `frames.seconds`.
    pub frames: crate::master::cycle::FrameStats,
}

/// One drive after a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DriveRunReport {
    /// Position on the segment.
    pub position: u16,
    /// Profile name.
    pub name: String,
    /// Identity and SII name.
    pub device: DeviceInfo,
    /// Start mode.
    pub mode: String,
    /// The PDOs it ran with (RxPDOs, TxPDOs: mapping object indices) and the bytes of
    /// process data each way (outputs, inputs).
    pub pdos: (Vec<u16>, Vec<u16>),
    /// Output and input process data, bytes.
    pub image_bytes: (usize, usize),
    /// CiA 402 states it went through, in order.
    pub states: Vec<String>,
    /// Modes it ran set-points in, in order.
    pub modes_run: Vec<String>,
    /// Largest |following error| while energised in csp, position counts, as the master
    /// computes it (demand − actual with the cycle's transport delay); the limit uses it.
    pub max_following_error: i64,
    /// Largest |0x60F4| the drive reported meanwhile, if it is mapped.
    pub max_following_error_drive: Option<i64>,
    /// 0x60F4 stayed 0 while the axis moved: the drive does not compute it (not trusted).
    pub following_error_drive_stuck: bool,
    /// The same in user units, if the file gives units.
    pub max_following_error_units: Option<f64>,
    /// The user units.
    pub units: Option<UserUnits>,
    /// Program steps (as the file describes them).
    pub program: Vec<String>,
    /// Steps started (equals the program length when it finished).
    pub steps_done: usize,
    /// The touch-probe latches, in order.
    pub probe_latches: Vec<ProbeLatch>,
    /// Faults and errors the history records for this drive.
    pub errors: Vec<String>,
    /// Warnings the history records for this drive (what start-up accepted but the user should
    /// know: a read-only cycle time, a drive on the generic profile, a 0x60F4 not computed).
    pub warnings: Vec<String>,
}

/// A position a touch probe latched.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProbeLatch {
    /// Probe 1 or 2.
    pub probe: u8,
    /// `"rising"` or `"falling"`.
    pub edge: &'static str,
    /// The latched position, counts.
    pub counts: i64,
    /// The same in the user units, if the file gives units.
    pub value: Option<f64>,
}

/// One device that was not driven (an I/O device) after a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IoRunReport {
    /// Position on the segment.
    pub position: u16,
    /// Identity and SII name.
    pub device: DeviceInfo,
    /// Why it was not driven.
    pub why: String,
    /// Output bytes.
    pub outputs: usize,
    /// Input bytes.
    pub inputs: usize,
    /// The input bytes of the last cycle with a reply before the stop (at most
    /// [`crate::master::telemetry::IO_TELEMETRY_BYTES`]).
    pub last_inputs: Vec<u8>,
}

/// What a run did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    /// The configuration file.
    pub config: String,
    /// Where it ran.
    pub target: Target,
    /// How it ended.
    pub outcome: Outcome,
    /// Why, in words (the first error of the history, or what ended the run).
    pub reason: String,
    /// Cycle time, ns.
    pub cycle_ns: u64,
    /// Time from the programs' start to the stop request.
    pub run_seconds: f64,
    /// Per drive, in segment order.
    pub drives: Vec<DriveRunReport>,
    /// The devices that were not driven, in segment order: in OP with their own PDO
    /// configuration, their process data exchanged.
    pub io: Vec<IoRunReport>,
    /// The faults cleared before the run (`reset_faults = true`).
    pub resets: Vec<super::reset::DriveReset>,
    /// Cycle timing.
    pub cycle: Option<CycleSummary>,
    /// Whether every drive reached INIT at the end.
    pub shutdown_ok: bool,
    /// Where start-up's time went (discovery, SII, CoE configuration, process image, DC
    /// settle, SAFE-OP, OP), in ms.
    pub startup: Option<crate::master::StartupTimes>,
    /// The recording, if one was asked for.
    pub record: Option<RecordSummary>,
    /// The capture of the frames (`--pcap`), if one was asked for.
    pub capture: Option<crate::app::capture::CaptureSummary>,
    /// The whole event history.
    pub history: Vec<HistoryEntry>,
}

/// What `--record` wrote.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RecordSummary {
    /// The CSV file.
    pub file: String,
    /// Lines written (samples: one per axis and cycle with a reply).
    pub samples: u64,
    /// Samples the cycle dropped because the writer fell behind (never blocking the cycle).
    pub dropped: u64,
}

/// What can change how [`run`] runs a file.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Override the file's duration.
    pub duration: Option<Duration>,
    /// How long to wait for OP at least (the file's `supervision.op_timeout` plus 10 s when
    /// that is longer).
    pub op_timeout: Duration,
    /// How long the axes may take to be enabled.
    pub enable_timeout: Duration,
    /// Set while the run stops (a second Ctrl-C or SIGTERM): the axes still ramping are quick
    /// stopped instead; they are disabled all the same.
    pub hurry: Option<std::sync::Arc<AtomicBool>>,
    /// Record every cycle (one line per axis and cycle with a reply) into this CSV file.
    pub record: Option<std::path::PathBuf>,
    /// Write every frame, both directions, to this pcapng file (off the cycle thread).
    pub pcap: Option<std::path::PathBuf>,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            duration: None,
            op_timeout: Duration::from_secs(15),
            enable_timeout: Duration::from_secs(5),
            hurry: None,
            record: None,
            pcap: None,
        }
    }
}

fn selects(s: &Selector, d: &DeviceInfo) -> bool {
    match *s {
        Selector::Position(p) => d.position == p,
        Selector::Alias(a) => d.alias == a,
        Selector::Identity {
            vendor_id,
            product_code,
        } => d.vendor_id == vendor_id && d.product_code == product_code,
    }
}

fn is_fault(s: Option<State>) -> bool {
    matches!(s, Some(State::Fault | State::FaultReactionActive))
}

/// Run a configuration. Start-up failures (nothing answered, a device refused its
/// configuration, the configuration does not fit the segment) are errors; everything after
/// the cycle started ends in a [`RunReport`] whose [`Outcome`] says how it went.
/// `progress` is called about every 100 ms; setting `stop` ends the run early.
pub fn run(
    cfg: &RunConfig,
    opts: &RunOptions,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&RunProgress),
) -> Result<RunReport, MasterError> {
    let duration = opts.duration.or(cfg.duration);
    let mut watch = Watch {
        progress,
        duration,
        programs: Vec::new(),
        steps_total: 0,
    };
    let Started {
        mut m,
        writer,
        capture,
    } = start(cfg, opts, &mut watch)?;
    let entries = file_entries(cfg, &m);
    watch.programs = entries
        .iter()
        .map(|e| {
            e.and_then(|e| cfg.master.startup.drives.get(e))
                .map_or(0, |s| s.program.len())
        })
        .collect();
    watch.steps_total = watch.programs.iter().sum();
    let mut going = Going {
        outcome: Outcome::Completed,
        reason: String::new(),
        faulted_before: false,
    };
    wait_for_op(&mut m, cfg, opts, stop, &mut watch, &mut going);
    let mut resets = Vec::new();
    if going.ok() && watch.n_axes() > 0 {
        resets = faults_before(&mut m, cfg, &mut watch, &mut going)?;
    }
    if going.ok() {
        enable(&mut m, opts, stop, &mut watch, &mut going)?;
    }
    let started = if going.ok() {
        Some(run_programs(&mut m, stop, &mut watch, &mut going)?)
    } else {
        None
    };
    let run_seconds = started.map_or(0.0, |t| t.elapsed().as_secs_f64());
    let t = m.telemetry().clone();
    watch.tick(
        "stopping",
        &t,
        started.map_or(Duration::ZERO, |t| t.elapsed()),
    );
    let steps_done: Vec<usize> = t
        .axes
        .iter()
        .take(watch.n_axes())
        .map(|a| usize::from(a.program_step))
        .collect();
    let summaries = m.drives().to_vec();
    let io = io_reports(&m, &t);
    let (report, link) = m.stop_watching(StopKind::Ramp, opts.hurry.as_deref());
    drop(link);
    let capture = super::finish_capture(capture)?;
    let record = writer.map(RecordWriter::finish).transpose()?;
    let Some(report) = report else {
        return Err(MasterError::new(
            None,
            "stopping the run",
            ErrorKind::Bus,
            "the session ended without a report",
        ));
    };
    let ended_by = ended_by(&report, &summaries, &mut going);
    let finished = finished_reason(duration, watch.steps_total, run_seconds);
    going.reason = reason(&report, &going, ended_by, finished);
    let drives = drive_reports(
        cfg,
        &report,
        &summaries,
        &entries,
        &steps_done,
        &watch.programs,
    );
    Ok(RunReport {
        config: cfg.source.clone(),
        target: cfg.target.clone(),
        outcome: going.outcome,
        reason: going.reason,
        cycle_ns: cfg.master.cycle.cycle.as_nanos() as u64,
        run_seconds,
        drives,
        io,
        resets,
        cycle: report.cycle.as_ref().map(cycle_summary),
        shutdown_ok: report.shutdown_ok,
        startup: report.startup,
        record,
        capture,
        history: report.history,
    })
}

/// How the run is going: the outcome so far and why (empty until something is said), and
/// whether it was refused for faults from before it.
struct Going {
    outcome: Outcome,
    reason: String,
    faulted_before: bool,
}

impl Going {
    /// Nothing has ended the run yet.
    fn ok(&self) -> bool {
        self.outcome == Outcome::Completed
    }

    /// The run ends with `outcome`, for `reason`.
    fn end(&mut self, outcome: Outcome, reason: impl Into<String>) {
        self.outcome = outcome;
        self.reason = reason.into();
    }
}

/// The progress the run reports: the phase, the time, the program steps done of every
/// axis's program (`programs`: each axis's step count), the cycles.
struct Watch<'a> {
    progress: &'a mut dyn FnMut(&RunProgress),
    duration: Option<Duration>,
    programs: Vec<usize>,
    steps_total: usize,
}

impl Watch<'_> {
    /// The axes that are drives: the telemetry may carry more axis slots than drives (spare
    /// slots of the triple buffer); only the first ones are drives.
    fn n_axes(&self) -> usize {
        self.programs.len()
    }

    fn tick(&mut self, phase: &'static str, t: &Telemetry, elapsed: Duration) {
        let done = t
            .axes
            .iter()
            .take(self.n_axes())
            .zip(&self.programs)
            .map(|(a, n)| usize::from(a.program_step).min(*n))
            .sum();
        (self.progress)(&RunProgress {
            phase,
            elapsed,
            duration: self.duration,
            steps_done: done,
            steps_total: self.steps_total,
            cycles: t.cycle.cycle,
        });
    }
}

/// A started master, with the recording's writer and the capture, if asked for.
struct Started {
    m: Master<super::ToolLink>,
    writer: Option<RecordWriter>,
    capture: Option<crate::app::capture::CaptureFile>,
}

/// The link opened (captured with `--pcap`), the recording's writer started (`--record`), and
/// the master started: start-up, then the cycle.
fn start(
    cfg: &RunConfig,
    opts: &RunOptions,
    watch: &mut Watch<'_>,
) -> Result<Started, MasterError> {
    let link = cfg.target.open_with(&cfg.sim)?;
    let (link, capture) = super::capture_link(link, &cfg.target, opts.pcap.as_deref())?;
    (watch.progress)(&RunProgress {
        phase: "starting",
        elapsed: Duration::ZERO,
        duration: watch.duration,
        steps_done: 0,
        steps_total: 0,
        cycles: 0,
    });
    let mut master_cfg = cfg.master.clone();
    let writer = match &opts.record {
        Some(path) => Some(RecordWriter::start(
            path,
            &mut master_cfg,
            cfg.drives.len(),
        )?),
        None => None,
    };
    let m = match Master::start(link, master_cfg) {
        Ok(m) => m,
        Err(f) => {
            drop(f.link);
            let _ = super::finish_capture(capture);
            return Err(f.error);
        }
    };
    if let Some(w) = &writer {
        w.drives_known(m.drives());
    }
    Ok(Started { m, writer, capture })
}

/// Which file entry each axis is: the first entry not yet taken whose selector selects it.
fn file_entries(cfg: &RunConfig, m: &Master<super::ToolLink>) -> Vec<Option<usize>> {
    let mut used = vec![false; cfg.drives.len()];
    m.drives()
        .iter()
        .map(|d| {
            let i = cfg.drives.iter().enumerate().position(|(i, e)| {
                !used.get(i).copied().unwrap_or(true) && selects(&e.select, &d.info)
            });
            if let Some(i) = i {
                if let Some(u) = used.get_mut(i) {
                    *u = true;
                }
            }
            i
        })
        .collect()
}

/// Wait until every drive is in OP. The cycle itself gives up after its `op_timeout`; this
/// waits a little longer than that.
fn wait_for_op(
    m: &mut Master<super::ToolLink>,
    cfg: &RunConfig,
    opts: &RunOptions,
    stop: &AtomicBool,
    watch: &mut Watch<'_>,
    going: &mut Going,
) {
    let op_wait = opts
        .op_timeout
        .max(cfg.master.cycle.op_timeout + Duration::from_secs(10));
    let wait = Instant::now();
    loop {
        let t = m.telemetry().clone();
        watch.tick("waiting for OP", &t, Duration::ZERO);
        if t.cycle.all_op {
            return;
        }
        if !m.is_running() || wait.elapsed() > op_wait {
            let why = format!("the drives did not reach OP within {} s", op_wait.as_secs());
            return going.end(Outcome::Refused, why);
        }
        if stop.load(Ordering::Relaxed) {
            return going.end(Outcome::Interrupted, "interrupted");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Faults latched before this run (a loss alarm of the last one, say): cleared with
/// `reset_faults` (the resets returned), else the run is refused, saying how to clear them.
fn faults_before(
    m: &mut Master<super::ToolLink>,
    cfg: &RunConfig,
    watch: &mut Watch<'_>,
    going: &mut Going,
) -> Result<Vec<super::reset::DriveReset>, MasterError> {
    watch.tick(
        "checking for faults",
        &m.telemetry().clone(),
        Duration::ZERO,
    );
    if cfg.reset_faults {
        let resets = super::reset::clear_faults(m, None, Duration::from_secs(2))?;
        let stuck: Vec<String> = resets
            .iter()
            .filter(|d| d.cleared == Some(false))
            .map(|d| {
                format!(
                    "drive {} ({}): {}",
                    d.position,
                    d.drive,
                    d.fault.as_deref().unwrap_or("the fault")
                )
            })
            .collect();
        if !stuck.is_empty() {
            going.end(
                Outcome::Refused,
                format!(
                    "{} did not clear on reset: its cause is still present, or the drive needs \
                     a power cycle",
                    stuck.join("; ")
                ),
            );
        }
        return Ok(resets);
    }
    m.wait_until("every drive's state", Duration::from_secs(5), |t| {
        t.axes.iter().all(|a| a.state.is_some())
    })?;
    let t = m.telemetry().clone();
    // Every drive in Fault, each once (after a cable pull, several are).
    let faulted: Vec<usize> = t
        .axes
        .iter()
        .enumerate()
        .take(watch.n_axes())
        .filter(|(_, a)| is_fault(a.state))
        .map(|(i, _)| i)
        .collect();
    if faulted.is_empty() {
        return Ok(Vec::new());
    }
    let interface = match &cfg.target {
        Target::Interface(i) => i.clone(),
        Target::Sim(_) => cfg.target.to_string(),
    };
    let mut each = Vec::with_capacity(faulted.len());
    for &i in &faulted {
        let fault = super::reset::latched(m, i);
        let d = &m.drives()[i];
        each.push(format!("{} ({fault})", d.drive));
    }
    going.faulted_before = true;
    let why = if let [i] = faulted[..] {
        format!(
            "{} is in Fault from before this run; clear it with `ecdrive reset -i {interface} -p \
             {}`, or set reset_faults = true in the file",
            each.join(""),
            m.drives()[i].info.position
        )
    } else {
        format!(
            "{} drives are in Fault from before this run: {}; clear them with `ecdrive reset -i \
             {interface}`, or set reset_faults = true in the file",
            faulted.len(),
            each.join(", ")
        )
    };
    going.end(Outcome::Refused, why);
    Ok(Vec::new())
}

/// Enable every axis and wait until each is in Operation enabled; one that stays behind is
/// named with what it shows and what usually causes it.
fn enable(
    m: &mut Master<super::ToolLink>,
    opts: &RunOptions,
    stop: &AtomicBool,
    watch: &mut Watch<'_>,
    going: &mut Going,
) -> Result<(), MasterError> {
    m.command(Command::Enable(Axes::All))?;
    let n_axes = watch.n_axes();
    let wait = Instant::now();
    loop {
        let t = m.telemetry().clone();
        watch.tick("enabling", &t, Duration::ZERO);
        if t.axes
            .iter()
            .take(n_axes)
            .all(|a| a.state == Some(State::OperationEnabled))
        {
            return Ok(());
        }
        if t.axes.iter().take(n_axes).any(|a| is_fault(a.state)) {
            going.outcome = Outcome::DriveFault;
            return Ok(());
        }
        if !m.is_running() || wait.elapsed() > opts.enable_timeout {
            let why = format!(
                "not every axis reached Operation enabled within {} s: {}",
                opts.enable_timeout.as_secs(),
                not_enabled(m, &t, n_axes).join("; ")
            );
            going.end(Outcome::Refused, why);
            return Ok(());
        }
        if stop.load(Ordering::Relaxed) {
            going.end(Outcome::Interrupted, "interrupted");
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Which drive stays short of Operation enabled, with what it shows and what usually causes
/// it.
fn not_enabled(m: &Master<super::ToolLink>, t: &Telemetry, n_axes: usize) -> Vec<String> {
    t.axes
        .iter()
        .take(n_axes)
        .enumerate()
        .filter(|(_, a)| a.state != Some(State::OperationEnabled))
        .map(|(i, a)| {
            let drive = m
                .drives()
                .get(i)
                .map_or_else(|| format!("axis {i}"), |d| d.drive.to_string());
            let cause = if a.statusword & 0x0200 == 0 {
                crate::cia402::StallCause::RemoteOff
            } else if a.statusword & 0x0010 == 0 {
                crate::cia402::StallCause::NoMainVoltage
            } else {
                crate::cia402::StallCause::NoResponse
            };
            format!(
                "{drive} stays in {} (statusword 0x{:04X}, controlword 0x{:04X}): {cause}",
                a.state
                    .map_or("an unknown state".to_string(), |s| s.to_string()),
                a.statusword,
                a.controlword
            )
        })
        .collect()
}

/// Start every axis's program and watch until every program has finished and the duration
/// (if any) has passed, the duration has passed, the caller asks to stop, or something stops
/// an axis. Returns when the programs started.
fn run_programs(
    m: &mut Master<super::ToolLink>,
    stop: &AtomicBool,
    watch: &mut Watch<'_>,
    going: &mut Going,
) -> Result<Instant, MasterError> {
    for (i, n) in watch.programs.iter().enumerate() {
        if *n > 0 {
            m.command(Command::RunProgram(Axes::One(i as u16)))?;
        }
    }
    let n_axes = watch.n_axes();
    let t0 = Instant::now();
    // Give the cycle a moment to take the programs.
    std::thread::sleep(Duration::from_millis(20));
    loop {
        let elapsed = t0.elapsed();
        let t = m.telemetry().clone();
        watch.tick("running", &t, elapsed);
        if t.axes.iter().take(n_axes).any(|a| is_fault(a.state)) {
            going.outcome = Outcome::DriveFault;
            break;
        }
        if !m.is_running() {
            going.outcome = Outcome::BusLost;
            break;
        }
        if t.axes
            .iter()
            .take(n_axes)
            .any(|a| a.state != Some(State::OperationEnabled))
        {
            // The cycle stopped an axis on its own (following error, a drive left OP).
            going.outcome = Outcome::DriveFault;
            break;
        }
        if stop.load(Ordering::Relaxed) {
            going.end(Outcome::Interrupted, "interrupted");
            break;
        }
        let programs_done = watch.steps_total > 0
            && t.axes
                .iter()
                .take(n_axes)
                .zip(&watch.programs)
                .all(|(a, n)| *n == 0 || (!a.program_running && usize::from(a.program_step) >= *n));
        if programs_done && watch.duration.is_none_or(|d| elapsed >= d) {
            break;
        }
        if let Some(d) = watch.duration
            && elapsed >= d
        {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Ok(t0)
}

/// The devices that were not driven, with their last inputs.
fn io_reports(m: &Master<super::ToolLink>, t: &Telemetry) -> Vec<IoRunReport> {
    m.io()
        .iter()
        .map(|o| IoRunReport {
            position: o.info.position,
            device: o.info.clone(),
            why: o.why.clone(),
            outputs: o.image_bytes.0,
            inputs: o.image_bytes.1,
            last_inputs: t
                .io
                .iter()
                .find(|x| x.position == o.info.position)
                .map(|x| x.inputs().to_vec())
                .unwrap_or_default(),
        })
        .collect()
}

/// The first error of `kind` in the history (of the drive at `position`, if given), with the
/// drive it names.
fn first_of(report: &SessionReport, kind: HistoryKind, position: Option<u16>) -> Option<String> {
    report
        .history
        .iter()
        .find(|h| {
            h.kind == kind
                && h.error
                && position.is_none_or(|p| h.drive.as_ref().is_some_and(|d| d.position == p))
        })
        .map(|h| match &h.drive {
            Some(d) => format!("{d}: {}", h.text()),
            None => h.text(),
        })
}

/// The event that ended the run, in words, with the outcome it makes (set in `going`): the
/// first reason the cycle had to stop the axes, or how the cycle ended. Nothing for a run
/// refused for faults from before it, or one the cycle did not end.
fn ended_by(
    report: &SessionReport,
    summaries: &[DriveSummary],
    going: &mut Going,
) -> Option<String> {
    let c = report.cycle.as_ref().filter(|_| !going.faulted_before)?;
    let entry = |kind, position| first_of(report, kind, position);
    let drive_name = |axis: u16| {
        summaries
            .get(usize::from(axis))
            .map_or_else(|| format!("axis {axis}"), |s| s.drive.to_string())
    };
    let pos = |axis: u16| summaries.get(usize::from(axis)).map(|s| s.info.position);
    let (outcome, why) = match (c.end, c.first_stop) {
        (CycleEnd::SegmentLost | CycleEnd::LinkFailed, _) => (
            Outcome::BusLost,
            entry(HistoryKind::SegmentLost, None).or_else(|| Some("the link failed".to_string())),
        ),
        (_, Some(StopReason::FramesLost { cycles })) => (
            Outcome::BusLost,
            Some(format!(
                "{cycles} cycles in a row without a reply: the axes were stopped in a \
                 controlled way (a bus problem; a drive that supervises its cyclic data \
                 may have latched its loss-of-data fault meanwhile, which `ecdrive reset` \
                 clears)"
            )),
        ),
        (_, Some(StopReason::WorkingCounter)) => (
            Outcome::BusLost,
            Some(format!(
                "the working counter stayed wrong (a device does not exchange its process \
                 data): the axes were stopped in a controlled way{}",
                entry(HistoryKind::WorkingCounter, None)
                    .map_or(String::new(), |e| format!("; first: {e}"))
            )),
        ),
        (_, Some(StopReason::DriveFault { axis })) => (
            Outcome::DriveFault,
            entry(HistoryKind::DriveFault, pos(axis))
                .or_else(|| Some(format!("{} faulted", drive_name(axis)))),
        ),
        (_, Some(StopReason::FollowingError { axis })) => (
            Outcome::DriveFault,
            entry(HistoryKind::FollowingError, pos(axis)).or_else(|| {
                Some(format!(
                    "the following error of {} exceeded its limit",
                    drive_name(axis)
                ))
            }),
        ),
        (_, Some(StopReason::HomingFailed { axis })) => (
            Outcome::DriveFault,
            entry(HistoryKind::Homing, pos(axis))
                .or_else(|| Some(format!("homing of {} failed", drive_name(axis)))),
        ),
        (_, Some(StopReason::ProbeNotLatched { axis, probe })) => (
            Outcome::DriveFault,
            entry(HistoryKind::Probe, pos(axis)).or_else(|| {
                Some(format!(
                    "touch probe {probe} of {} did not latch",
                    drive_name(axis)
                ))
            }),
        ),
        (CycleEnd::DriveLeftOp { device, .. }, _)
        | (_, Some(StopReason::DriveLeftOp { device })) => (
            Outcome::DriveFault,
            entry(HistoryKind::AlState, Some(device)),
        ),
        // A working counter that stayed wrong in SAFE-OP says which device does not take its
        // process data; else the AL state that was not OP.
        (CycleEnd::OpFailed { device, .. }, _) => (
            Outcome::Refused,
            entry(HistoryKind::WorkingCounter, Some(device))
                .or_else(|| entry(HistoryKind::AlState, Some(device))),
        ),
        _ => return None,
    };
    going.outcome = outcome;
    why
}

/// Why the run ended as it did: on request, finished (`finished` says how), the event that
/// ended it, what the watching said, or the history's first error; a refusal to enable is
/// told with the state machine's own account.
fn reason(
    report: &SessionReport,
    going: &Going,
    ended_by: Option<String>,
    finished: String,
) -> String {
    let said = going.reason.clone();
    match (going.outcome, ended_by) {
        (Outcome::Interrupted, _) => "stopped on request (Ctrl-C or a signal)".into(),
        (Outcome::Completed, _) => finished,
        (_, Some(e)) => e,
        (outcome, None) if said.is_empty() => {
            let first_error = report
                .history
                .iter()
                .find(|h| h.error)
                .map(|h| match &h.drive {
                    Some(d) => format!("{d}: {}", h.text()),
                    None => h.text(),
                });
            first_error.unwrap_or_else(|| outcome.describe().to_string())
        }
        (Outcome::Refused, None) if !going.faulted_before => {
            // Why an axis was not enabled: the state machine's own account.
            match first_of(report, HistoryKind::StateMachine, None)
                .or_else(|| first_of(report, HistoryKind::CommandRefused, None))
            {
                Some(e) => format!("{said}: {e}"),
                None => said,
            }
        }
        _ => said,
    }
}

/// A completed run's reason: the time it ran, or that every program finished.
fn finished_reason(duration: Option<Duration>, steps_total: usize, run_seconds: f64) -> String {
    match duration {
        Some(d) if steps_total == 0 || run_seconds >= d.as_secs_f64() => {
            format!("ran for {} s", d.as_secs_f64())
        }
        _ => "every program finished".into(),
    }
}

/// Each drive's report: its device and process data, the states and modes it went through,
/// its following error and probe latches (in the file's units), its program and how far it
/// got, and its errors and warnings from the history, each once.
fn drive_reports(
    cfg: &RunConfig,
    report: &SessionReport,
    summaries: &[DriveSummary],
    entries: &[Option<usize>],
    steps_done: &[usize],
    programs: &[usize],
) -> Vec<DriveRunReport> {
    let outcomes = report.drive_outcomes();
    summaries
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let entry = entries
                .get(i)
                .copied()
                .flatten()
                .and_then(|e| cfg.drives.get(e));
            let units = entry.and_then(|e| e.units.clone());
            let o = outcomes.get(i);
            let max_fe = o.map_or(0, |o| o.max_following_error);
            DriveRunReport {
                position: s.info.position,
                name: s.profile.to_string(),
                device: s.info.clone(),
                mode: s.mode.to_string(),
                pdos: s.pdos.clone(),
                image_bytes: s.image_bytes,
                states: o
                    .map(|o| o.states.iter().map(|s| s.to_string()).collect())
                    .unwrap_or_default(),
                modes_run: o
                    .map(|o| {
                        crate::motion::mode_names(&o.modes_run, o.modes_omitted, |m| {
                            m.short_name().to_string()
                        })
                    })
                    .unwrap_or_default(),
                max_following_error: max_fe,
                max_following_error_drive: o.and_then(|o| o.max_following_error_drive),
                following_error_drive_stuck: o.is_some_and(|o| o.following_error_drive_stuck),
                max_following_error_units: units
                    .as_ref()
                    .map(|u| max_fe as f64 / u.counts_per_unit),
                probe_latches: o
                    .map(|o| probe_latches(o, units.as_ref()))
                    .unwrap_or_default(),
                units,
                program: entry.map(|e| e.steps.clone()).unwrap_or_default(),
                steps_done: steps_done
                    .get(i)
                    .copied()
                    .unwrap_or(0)
                    .min(programs.get(i).copied().unwrap_or(0)),
                errors: drive_errors(report, s.info.position),
                warnings: drive_warnings(report, s.info.position),
            }
        })
        .collect()
}

/// A drive's probe latches, in the file's units too.
fn probe_latches(o: &DriveOutcome, units: Option<&UserUnits>) -> Vec<ProbeLatch> {
    o.probe_latches
        .iter()
        .map(|&(probe, edge, counts)| ProbeLatch {
            probe,
            edge: edge.name(),
            counts,
            value: units.map(|u| counts as f64 / u.counts_per_unit),
        })
        .collect()
}

/// The errors of the history about the drive at `position`, each once.
fn drive_errors(report: &SessionReport, position: u16) -> Vec<String> {
    once_each(
        report
            .history
            .iter()
            .filter(|h| h.error && h.drive.as_ref().is_some_and(|d| d.position == position))
            .map(|h| h.text()),
    )
}

/// The warnings of the history about the drive at `position`, each once.
fn drive_warnings(report: &SessionReport, position: u16) -> Vec<String> {
    once_each(
        report
            .history
            .iter()
            .filter(|h| {
                h.kind == crate::master::HistoryKind::Warning
                    && !h.error
                    && h.drive.as_ref().is_some_and(|d| d.position == position)
            })
            .map(|h| h.text().trim_start_matches("warning: ").to_string()),
    )
}

/// The cycle's timing and frames, for the report.
fn cycle_summary(c: &crate::master::CycleReport) -> CycleSummary {
    CycleSummary {
        cycles: c.cycles,
        lost: c.lost,
        overruns: c.overruns,
        wake_latency: c.timing.wake_latency.summary(),
        period: c.timing.period.summary(),
        exchange: c.timing.exchange.summary(),
        priority: c.rt.priority_granted,
        cpu: c.rt.cpu_pinned,
        rt_warnings: c.rt.warnings.clone(),
        frames: c.frames,
    }
}

/// Each text once, in the order of its first appearance, with how often it came when more
/// than once ("… (3 times)"): a drive's report says every fault once (the history keeps each).
fn once_each(texts: impl Iterator<Item = String>) -> Vec<String> {
    let mut seen: Vec<(String, usize)> = Vec::new();
    for t in texts {
        match seen.iter_mut().find(|(s, _)| *s == t) {
            Some((_, n)) => *n += 1,
            None => seen.push((t, 1)),
        }
    }
    seen.into_iter()
        .map(|(t, n)| if n > 1 { format!("{t} ({n} times)") } else { t })
        .collect()
}

/// The thread that drains the cycle's recording into the CSV file.
struct RecordWriter {
    path: std::path::PathBuf,
    done: std::sync::Arc<AtomicBool>,
    /// The drives' units, sent once the master has started.
    drives: std::sync::mpsc::Sender<Vec<crate::master::SampleScale>>,
    thread: Option<std::thread::JoinHandle<std::io::Result<(u64, u64)>>>,
}

impl Drop for RecordWriter {
    /// A run that ends early (an error before the stop) still ends the writer: it drains
    /// what is there and closes the file.
    fn drop(&mut self) {
        self.done.store(true, std::sync::atomic::Ordering::Release);
    }
}

impl RecordWriter {
    /// Open `path`, give the cycle its end of a ring for `axes` axes (half a second of
    /// samples), start draining.
    fn start(
        path: &std::path::Path,
        cfg: &mut crate::master::MasterConfig,
        axes: usize,
    ) -> Result<Self, MasterError> {
        let fail = |e: std::io::Error| {
            MasterError::new(
                None,
                format!("recording to {}", path.display()),
                ErrorKind::Config,
                e,
            )
        };
        let file = std::fs::File::create(path).map_err(fail)?;
        let per_s = 1e9 / cfg.cycle.cycle.as_nanos().max(1) as f64;
        let capacity = ((per_s * axes.max(1) as f64 * 0.5) as usize).max(4096);
        let (tx, mut rx) = crate::master::recording(capacity);
        cfg.record = Some(std::sync::Arc::new(std::sync::Mutex::new(tx)));
        let done = std::sync::Arc::new(AtomicBool::new(false));
        let stop = done.clone();
        let (drives, drives_rx) = std::sync::mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("ecdrive-record".into())
            .spawn(move || {
                let mut w = crate::master::CsvWriter::new(std::io::BufWriter::new(file))?;
                loop {
                    let last = stop.load(std::sync::atomic::Ordering::Acquire);
                    if let Ok(scales) = drives_rx.try_recv() {
                        w.set_drives(scales)?;
                    }
                    w.drain(&mut rx)?;
                    if last {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(20));
                }
                let (_, lines) = w.finish()?;
                Ok((lines, rx.dropped()))
            })
            .map_err(fail)?;
        Ok(Self {
            path: path.to_path_buf(),
            done,
            drives,
            thread: Some(thread),
        })
    }

    /// The drives of the started master: their units for the CSV's physical columns.
    fn drives_known(&self, drives: &[crate::master::DriveSummary]) {
        // A writer that has ended (an I/O error) reports it when finished.
        let _ = self
            .drives
            .send(crate::master::SampleScale::of_drives(drives));
    }

    /// Drain what is left (the cycle has ended), close the file.
    fn finish(mut self) -> Result<RecordSummary, MasterError> {
        self.done.store(true, std::sync::atomic::Ordering::Release);
        let what = format!("recording to {}", self.path.display());
        let thread = self.thread.take().ok_or_else(|| {
            MasterError::new(None, &what, ErrorKind::Config, "the writer is gone")
        })?;
        let (samples, dropped) = thread
            .join()
            .map_err(|_| MasterError::new(None, &what, ErrorKind::Config, "the writer panicked"))?
            .map_err(|e| MasterError::new(None, &what, ErrorKind::Config, e))?;
        Ok(RecordSummary {
            file: self.path.display().to_string(),
            samples,
            dropped,
        })
    }
}
