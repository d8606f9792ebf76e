//! `ecdrive run FILE` for a CANopen run file ([`crate::app::config::canopen`]): the drives
//! configured and started by the CANopen master, then run by the motion runtime the EtherCAT
//! runs use ([`crate::canopen::MotionSession`]): enable, the programs, a controlled stop,
//! disable, NMT Stop. [`run`] returns a [`CanRunReport`]; the CLI prints it or its JSON.
//!
//! On `can-sim` the emulated drives run on simulated time (a run of seconds takes
//! milliseconds); on a `vbus:` hub or a SocketCAN interface the SYNC period is real time.

use crate::app::canopen::tools::open_bus;
use crate::app::config::canopen::{CanDriveConfig, CanRunConfig, CanTarget};
use crate::app::ethercat::tools::run::{Outcome, RecordSummary};
use crate::canopen::error::{CanError, CanErrorKind, NodeRef};
use crate::canopen::master::{DriveSetup, MasterConfig, MasterEvent};
use crate::canopen::motion::{MotionSession, SessionDrive, axis_setup};
use crate::canopen::transport::CanTransport;
use crate::cia402::State;
use crate::master::{Axes, Command, EventKind, StopKind, StopReason};
use crate::master::{CycleSample, SampleScale};
use crate::sim::canopen::{EmulatedNode, SimBus};
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// **\[REC\]** How long the drives may take to reach Operation enabled, and to be disabled at
/// the end.
pub const ENABLE_TIMEOUT: Duration = Duration::from_secs(5);

/// **\[REC\]** How long a controlled stop may take before the run disables regardless (the
/// runtime's own stop timeout is 2 s).
pub const STOP_WAIT: Duration = Duration::from_secs(5);

/// **\[REC\]** At least this many SYNC cycles for each of those waits: each state transition
/// takes an RPDO applied at one SYNC and a TPDO answering the next, so at a long period (a 1 s
/// SYNC) five seconds are not enough to walk the state machine.
pub const MIN_WAIT_CYCLES: u64 = 25;

/// **\[REC\]** A gap between two cycles longer than this (and ten SYNC periods) is a stall of
/// the master worth naming: the run's life guarding lets a drive wait 300 ms.
pub const STALL_US: u64 = 300_000;

/// What a run did, per drive.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CanDriveReport {
    /// Node-ID.
    pub node: u8,
    /// The drive's name.
    pub drive: &'static str,
    /// The program, as the file gives it.
    pub program: Vec<String>,
    /// Whether the program ran to its end.
    pub program_done: bool,
    /// The CiA 402 states it went through.
    pub states: Vec<String>,
    /// The modes it ran in.
    pub modes: Vec<String>,
    /// Its actual position at the end, counts.
    pub position: i64,
    /// The same in the file's user unit, when it gives one.
    pub position_user: Option<f64>,
    /// The user unit's name, or "counts".
    pub units: String,
    /// What went wrong on it (faults with the drive's alarm, refusals, a failed home step).
    pub errors: Vec<String>,
    /// Touch-probe latches, in order.
    pub probe_latches: Vec<CanProbeLatch>,
}

/// One touch-probe latch of a CANopen run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CanProbeLatch {
    /// Probe 1 or 2.
    pub probe: u8,
    /// `"rising"` or `"falling"`.
    pub edge: &'static str,
    /// The latched position, counts.
    pub counts: i64,
    /// The same in the file's user unit, when it gives one.
    pub value: Option<f64>,
}

/// What a CANopen run did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CanRunReport {
    /// The configuration file.
    pub config: String,
    /// The bus.
    pub bus: String,
    /// The SYNC period, µs.
    pub cycle_us: u64,
    /// How it ended.
    pub outcome: Outcome,
    /// Why, in words.
    pub reason: String,
    /// SYNC cycles run.
    pub cycles: u64,
    /// The bus's time the run took, from opening the bus to NMT Stop, µs (simulated on
    /// `can-sim`).
    pub bus_time_us: u64,
    /// Per drive, in file order.
    pub drives: Vec<CanDriveReport>,
    /// Every EMCY received, decoded with the drive's alarm table.
    pub emergencies: Vec<String>,
    /// The recording, if one was asked for.
    pub record: Option<RecordSummary>,
    /// What went wrong beside the drives (a recording that could not be written).
    pub warnings: Vec<String>,
    /// What the configuration check found questionable (an EDS file's oddities, an object
    /// the drive lacks), as `--check` and the start of the run say it.
    pub check_warnings: Vec<String>,
    /// The frame log, if one was asked for (`--candump`).
    pub candump: Option<super::candump::CandumpSummary>,
}

/// A CANopen run's recording: every cycle's sample of every axis with feedback, as the
/// EtherCAT runs write it ([`crate::master::CSV_HEADER`]; `ecdrive plot` draws it). The
/// position column holds the node-ID; latency, exchange time and working counter are 0 (a
/// CAN bus has none of them).
struct Recorder {
    out: std::io::BufWriter<std::fs::File>,
    path: std::path::PathBuf,
    t0_ns: Option<u64>,
    scales: Vec<SampleScale>,
    samples: u64,
}

impl Recorder {
    fn create(path: &std::path::Path, cfg: &CanRunConfig) -> std::io::Result<Self> {
        use std::io::Write;
        let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
        writeln!(out, "{}", crate::master::CSV_HEADER)?;
        let scales = cfg
            .drives
            .iter()
            .map(|d| {
                let u = &d.profile.units;
                SampleScale::of(u16::from(d.node), d.profile.name, d.units.as_ref(), u)
            })
            .collect();
        Ok(Self {
            out,
            path: path.to_path_buf(),
            t0_ns: None,
            scales,
            samples: 0,
        })
    }

    /// One line per axis with feedback.
    fn cycle<T: CanTransport>(&mut self, s: &MotionSession<T>, cycle: u64) -> std::io::Result<()> {
        let time_ns = s.master().now_us().saturating_mul(1000);
        let t0 = *self.t0_ns.get_or_insert(time_ns);
        for (i, scale) in self.scales.iter().enumerate() {
            let Some(t) = s.telemetry(i) else { continue };
            if t.state.is_none() {
                continue;
            }
            let judged = s.axis(i).is_some_and(|a| a.fe_judged());
            let sample = CycleSample::of_axis(cycle, time_ns, i as u16, t, judged);
            sample.write_csv(&mut self.out, t0, Some(scale))?;
            self.samples += 1;
        }
        Ok(())
    }

    fn finish(mut self) -> std::io::Result<RecordSummary> {
        use std::io::Write;
        self.out.flush()?;
        Ok(RecordSummary {
            file: self.path.display().to_string(),
            samples: self.samples,
            dropped: 0,
        })
    }
}

/// What can change how [`run`] runs a file.
#[derive(Debug, Clone, Default)]
pub struct CanRunOptions {
    /// Override the file's duration.
    pub duration: Option<Duration>,
    /// Record every cycle into this CSV file (`--record`).
    pub record: Option<std::path::PathBuf>,
    /// Log every CAN frame into this file, candump format (`--candump`).
    pub candump: Option<std::path::PathBuf>,
}

/// Run `cfg` as `opts` says. `stop` ends it early with a controlled stop (Ctrl-C). An error is
/// a bus or configuration failure before the drives moved, naming the node; what happens to a
/// drive afterwards is in the report.
pub fn run(
    cfg: &CanRunConfig,
    opts: &CanRunOptions,
    stop: &AtomicBool,
) -> Result<CanRunReport, CanError> {
    let bus_err = |e| {
        CanError::new(
            NodeRef { id: 0, drive: None },
            None,
            CanErrorKind::Transport(e),
        )
    };
    match &cfg.target {
        CanTarget::Sim => run_logged(emulated_bus(cfg)?, "can-sim", cfg, opts, stop),
        CanTarget::Bus(spec) => run_logged(
            open_bus(spec).map_err(bus_err)?,
            &spec.to_string(),
            cfg,
            opts,
            stop,
        ),
    }
}

/// [`run_on`], with every frame logged when `opts.candump` says so.
fn run_logged<T: CanTransport>(
    transport: T,
    iface: &str,
    cfg: &CanRunConfig,
    opts: &CanRunOptions,
    stop: &AtomicBool,
) -> Result<CanRunReport, CanError> {
    let Some(path) = &opts.candump else {
        return run_on(transport, cfg, opts.duration, opts.record.as_deref(), stop);
    };
    let (tap, log) = super::candump::CandumpTap::new(transport, path, iface).map_err(|e| {
        CanError::new(
            NodeRef { id: 0, drive: None },
            None,
            CanErrorKind::NotReady(format!("the candump log {}: {e}", path.display())),
        )
    })?;
    let mut report = run_on(tap, cfg, opts.duration, opts.record.as_deref(), stop)?;
    report.candump = Some(log.summary());
    Ok(report)
}

/// The run on an open bus.
pub fn run_on<T: CanTransport>(
    transport: T,
    cfg: &CanRunConfig,
    duration: Option<Duration>,
    record: Option<&std::path::Path>,
    stop: &AtomicBool,
) -> Result<CanRunReport, CanError> {
    let recorder = match record {
        Some(p) => Some(Recorder::create(p, cfg).map_err(|e| {
            CanError::new(
                NodeRef { id: 0, drive: None },
                None,
                CanErrorKind::NotReady(format!("recording to {}: {e}", p.display())),
            )
        })?),
        None => None,
    };
    let (mut s, started_us) = session(transport, cfg)?;
    let mut run = Run::new(cfg, duration.or(cfg.duration), started_us);
    run.recorder = recorder;
    let (outcome, reason) = run.drive(&mut s, stop)?;
    run.finish(s, outcome, reason)
}

/// The drives of `cfg` on an open bus, configured and started, on the motion runtime: each
/// node to Pre-operational (a node an earlier run left Stopped serves no SDO), configured
/// (identity, PDO plan, supervision, the program's and the file's start-up values), started,
/// and one motion axis per drive with its program, limits and mode. With the bus's time when
/// it began, µs. What a run then does is [`run_on`]'s; a test or an application may drive the
/// session itself.
pub fn session<T: CanTransport>(
    transport: T,
    cfg: &CanRunConfig,
) -> Result<(MotionSession<T>, u64), CanError> {
    let cycle_us = u64::try_from(cfg.cycle.as_micros()).unwrap_or(u64::MAX);
    let started_us = transport.now_us();
    let mut drives = Vec::with_capacity(cfg.drives.len());
    for d in &cfg.drives {
        let mut setup = DriveSetup::new(d.profile);
        setup.settings = d.settings.clone();
        // The touch probe's objects in the PDOs when the program arms one (the file's check
        // found room for them).
        let probes = crate::master::program::probes_used(&d.steps);
        setup.plan = crate::canopen::PdoPlan::with_probes(d.profile, &probes).map_err(|why| {
            let node = NodeRef {
                id: d.node,
                drive: Some(d.profile.name),
            };
            CanError::new(node, None, CanErrorKind::NotReady(why))
        })?;
        setup.initial_mode = d.mode.operation_mode();
        // Life guarding: the drive sees a master that dies (switched off at the run's end).
        setup.supervision = crate::canopen::master::Supervision::for_drive(d.profile);
        let mut axis = axis_setup(d.profile, d.steps.clone(), d.mode);
        axis.following_error_limit = d.following_error_limit;
        axis.limits = d.limits;
        drives.push(SessionDrive {
            node: d.node,
            setup,
            axis,
        });
    }
    let master = MasterConfig {
        cycle_us,
        ..MasterConfig::default()
    };
    Ok((MotionSession::start(transport, master, drives)?, started_us))
}

/// The emulated drives of a `can-sim` run: one per `[[drive]]`, at its node.
pub fn emulated_bus(cfg: &CanRunConfig) -> Result<SimBus, CanError> {
    let mut bus = SimBus::new();
    for d in &cfg.drives {
        let node = EmulatedNode::new(d.emulation, d.node).map_err(|e| {
            CanError::new(
                NodeRef {
                    id: d.node,
                    drive: Some(d.profile.name),
                },
                None,
                CanErrorKind::NotReady(format!("the emulated drive: {e}")),
            )
        })?;
        bus.add_node(node);
    }
    Ok(bus)
}

/// A run under way: its limits and what it saw.
struct Run<'a> {
    cfg: &'a CanRunConfig,
    cycles_per_s: f64,
    duration_cycles: Option<u64>,
    cycles: u64,
    errors: Vec<Vec<String>>,
    done: Vec<bool>,
    /// The bus's time when the run began, µs.
    started_us: u64,
    recorder: Option<Recorder>,
    /// Why the recording stopped, if it failed.
    record_error: Option<String>,
    /// The bus's time after the last cycle, and the longest gap between two cycles, µs: a
    /// master that did not run for a while (a stalled host, a stopped process) says so.
    last_cycle_us: Option<u64>,
    longest_gap_us: u64,
    /// Drives whose TPDOs stopped (each reported once).
    stale: Vec<bool>,
}

impl<'a> Run<'a> {
    fn new(cfg: &'a CanRunConfig, duration: Option<Duration>, started_us: u64) -> Self {
        let cycles_per_s = 1.0 / cfg.cycle.as_secs_f64();
        Self {
            cfg,
            cycles_per_s,
            duration_cycles: duration.map(|d| (d.as_secs_f64() * cycles_per_s).ceil() as u64),
            cycles: 0,
            errors: vec![Vec::new(); cfg.drives.len()],
            done: cfg.drives.iter().map(|d| d.steps.is_empty()).collect(),
            started_us,
            recorder: None,
            record_error: None,
            last_cycle_us: None,
            longest_gap_us: 0,
            stale: vec![false; cfg.drives.len()],
        }
    }

    /// The cycles `d` lasts, at least [`MIN_WAIT_CYCLES`] (all uses are waits for the drives).
    fn cycles_of(&self, d: Duration) -> u64 {
        ((d.as_secs_f64() * self.cycles_per_s).ceil() as u64).max(MIN_WAIT_CYCLES)
    }

    /// One cycle, its events sorted into the drives' errors and ends; `Some(reason)` when the
    /// axes were stopped for one.
    fn cycle<T: CanTransport>(
        &mut self,
        s: &mut MotionSession<T>,
    ) -> Result<Option<StopReason>, CanError> {
        s.cycle()?;
        self.cycles += 1;
        let now = s.master().now_us();
        if let Some(last) = self.last_cycle_us.replace(now) {
            self.longest_gap_us = self.longest_gap_us.max(now.saturating_sub(last));
        }
        if let Some(r) = self.recorder.as_mut()
            && let Err(e) = r.cycle(s, self.cycles)
        {
            self.record_error = Some(e.to_string());
            self.recorder = None;
        }
        let mut stopped = None;
        for e in s.take_events() {
            let axis = |a: u16| usize::from(a);
            match e.kind {
                EventKind::ProgramDone { axis: a } => {
                    if let Some(d) = self.done.get_mut(axis(a)) {
                        *d = true;
                    }
                }
                EventKind::CommandRefused { axis: a, why } => self.error(axis(a), why.to_string()),
                EventKind::HomingFailed { axis: a, .. } => {
                    self.error(axis(a), crate::master::telemetry::event_text(&e.kind));
                }
                EventKind::Axis {
                    axis: a,
                    event: crate::cia402::Event::Fault { .. },
                } => self.error(axis(a), "the drive faulted (its EMCY below)".into()),
                EventKind::FollowingError {
                    axis: a,
                    value,
                    limit,
                } => {
                    let text = self.following_error_text(axis(a), value, limit);
                    self.error(axis(a), text);
                }
                EventKind::Stopping { reason } => {
                    if let StopReason::ProbeNotLatched { axis: a, .. } = reason {
                        let text = self.stop_reason(reason);
                        self.error(axis(a), text);
                    }
                    stopped = stopped.or(Some(reason));
                }
                _ => {}
            }
        }
        while let Some(e) = s.master_mut().poll_event() {
            if let MasterEvent::HeartbeatLost { node, .. } | MasterEvent::GuardingLost { node, .. } =
                e
                && let Some(i) = self.cfg.drives.iter().position(|d| d.node == node.id)
            {
                self.error(i, e.to_string());
                stopped = stopped.or(Some(StopReason::DriveFault { axis: i as u16 }));
            }
            if let MasterEvent::RemoteOff { node } = e
                && let Some(i) = self.cfg.drives.iter().position(|d| d.node == node.id)
            {
                self.error(i, e.to_string());
            }
            // A drive that leaves Operational on its own (its reaction to a lost master, an
            // NMT command of another master) sends no more PDOs and takes none.
            if let MasterEvent::StateChanged { node, to, .. } = e
                && to != crate::canopen::nmt::NmtState::Operational
                && let Some(i) = self.cfg.drives.iter().position(|d| d.node == node)
                && self.cycles > 1
            {
                let d = &self.cfg.drives[i];
                let text = format!(
                    "node {} ({}) left NMT Operational on its own (now {to}): its PDOs stopped",
                    d.node, d.profile.name
                );
                self.error(i, text);
                stopped = stopped.or(Some(StopReason::DriveFault { axis: i as u16 }));
            }
        }
        // TPDOs that stopped coming: the drive's state is unknown from here on.
        for i in 0..self.cfg.drives.len() {
            if self.stale.get(i).copied().unwrap_or(true) || self.fresh(s, i) {
                continue;
            }
            if let Some(x) = self.stale.get_mut(i) {
                *x = true;
            }
            let d = &self.cfg.drives[i];
            let text = format!(
                "node {} ({}): no TPDO for more than {} ms: its state is unknown from here on",
                d.node,
                d.profile.name,
                self.stale_after_us() / 1000
            );
            self.error(i, text);
            stopped = stopped.or(Some(StopReason::DriveFault { axis: i as u16 }));
        }
        Ok(stopped)
    }

    /// Whether a drive that still sends TPDOs shows an energised state.
    fn any_energised<T: CanTransport>(&self, s: &MotionSession<T>) -> bool {
        (0..self.cfg.drives.len()).any(|i| {
            self.fresh(s, i)
                && s.telemetry(i)
                    .is_some_and(|t| t.state.is_some_and(State::is_energised))
        })
    }

    /// How long a drive may send no TPDO: ten SYNC periods, at least 100 ms **\[REC\]**.
    fn stale_after_us(&self) -> u64 {
        let cycle_us = u64::try_from(self.cfg.cycle.as_micros()).unwrap_or(u64::MAX);
        cycle_us.saturating_mul(10).max(100_000)
    }

    /// Whether drive `i` sent a TPDO recently (or has not started sending yet: before its
    /// first TPDO there is nothing to miss).
    fn fresh<T: CanTransport>(&self, s: &MotionSession<T>, i: usize) -> bool {
        let Some(d) = self
            .cfg
            .drives
            .get(i)
            .and_then(|d| s.master().drive(d.node))
        else {
            return false;
        };
        let newest = (0..d.tpdos().len()).filter_map(|k| d.tpdo_seen_us(k)).max();
        match newest {
            None => true,
            Some(t) => s.master().now_us().saturating_sub(t) <= self.stale_after_us(),
        }
    }

    /// A following error in counts, and in the file's unit where it has one.
    fn following_error_text(&self, i: usize, value: i64, limit: u32) -> String {
        let units = self.cfg.drives.get(i).and_then(|d| d.units.as_ref());
        match units {
            Some(u) => format!(
                "following error {value} counts ({:.4} {}) beyond the limit of {limit} counts \
                 ({:.4} {})",
                value as f64 / u.counts_per_unit,
                u.name,
                f64::from(limit) / u.counts_per_unit,
                u.name
            ),
            None => format!("following error {value} counts beyond the limit of {limit}"),
        }
    }

    fn error(&mut self, i: usize, text: String) {
        if let Some(v) = self.errors.get_mut(i)
            && !v.contains(&text)
        {
            v.push(text);
        }
    }

    /// Enable, run the programs (or the duration), stop: the outcome and why.
    fn drive<T: CanTransport>(
        &mut self,
        s: &mut MotionSession<T>,
        stop: &AtomicBool,
    ) -> Result<(Outcome, String), CanError> {
        if let Some(refused) = self.latched_faults(s)? {
            return Ok((Outcome::Refused, refused));
        }
        s.command(Command::Enable(Axes::All));
        let limit = self.cycles_of(ENABLE_TIMEOUT);
        let enabled = |s: &MotionSession<T>| {
            (0..self.cfg.drives.len()).all(|i| {
                s.telemetry(i)
                    .is_some_and(|t| t.state == Some(State::OperationEnabled))
            })
        };
        let mut n = 0;
        while !enabled(s) {
            if let Some(r) = self.cycle(s)? {
                return Ok((Outcome::DriveFault, self.stop_reason(r)));
            }
            n += 1;
            if n > limit || stop.load(Ordering::Relaxed) {
                let late: Vec<String> = (0..self.cfg.drives.len())
                    .filter(|i| {
                        s.telemetry(*i)
                            .is_none_or(|t| t.state != Some(State::OperationEnabled))
                    })
                    .map(|i| describe_not_enabled(s, &self.cfg.drives[i], i))
                    .collect();
                if stop.load(Ordering::Relaxed) {
                    return Ok((Outcome::Interrupted, "stopped while enabling".into()));
                }
                return Ok((
                    Outcome::Refused,
                    format!(
                        "not every drive reached Operation enabled within {} s: {}",
                        ENABLE_TIMEOUT.as_secs(),
                        late.join("; ")
                    ),
                ));
            }
        }
        for (i, d) in self.cfg.drives.iter().enumerate() {
            if !d.steps.is_empty() {
                s.command(Command::RunProgram(Axes::One(i as u16)));
            }
        }
        let start = self.cycles;
        loop {
            if let Some(r) = self.cycle(s)? {
                return Ok((Outcome::DriveFault, self.stop_reason(r)));
            }
            if stop.load(Ordering::Relaxed) {
                return Ok((Outcome::Interrupted, "stopped on request".into()));
            }
            let elapsed = self.cycles - start;
            match self.duration_cycles {
                Some(d) if elapsed >= d => {
                    return Ok((Outcome::Completed, "the duration passed".into()));
                }
                None if self.done.iter().all(|d| *d) => {
                    return Ok((Outcome::Completed, "every program finished".into()));
                }
                _ => {}
            }
            if let Some((i, e)) = self
                .errors
                .iter()
                .enumerate()
                .find_map(|(i, e)| e.first().map(|e| (i, e)))
            {
                let who = self.cfg.drives.get(i).map_or_else(String::new, |d| {
                    format!(" node {} ({})", d.node, d.profile.name)
                });
                return Ok((
                    Outcome::Refused,
                    format!("a program could not go on:{who}: {e}"),
                ));
            }
        }
    }

    /// Faults the drives show before the run (latched by an earlier one): reset when the file
    /// says `reset_faults = true`, else the run is refused naming each drive, its error code
    /// and its last EMCY. Waits for every drive's first feedback.
    fn latched_faults<T: CanTransport>(
        &mut self,
        s: &mut MotionSession<T>,
    ) -> Result<Option<String>, CanError> {
        let n = self.cfg.drives.len();
        let fed = |s: &MotionSession<T>| {
            (0..n).all(|i| s.telemetry(i).is_some_and(|t| t.state.is_some()))
        };
        for _ in 0..self.cycles_of(ENABLE_TIMEOUT) {
            if fed(s) {
                break;
            }
            self.cycle(s)?;
        }
        let faulted: Vec<usize> = (0..n)
            .filter(|i| {
                s.telemetry(*i)
                    .is_some_and(|t| t.state == Some(State::Fault))
            })
            .collect();
        if faulted.is_empty() {
            return Ok(None);
        }
        if !self.cfg.reset_faults {
            let named: Vec<String> = faulted
                .iter()
                .map(|&i| {
                    let d = &self.cfg.drives[i];
                    let code = s.telemetry(i).map_or(0, |t| t.error_code);
                    // Decoded with the drive's alarm table (an EMCY sent before the master
                    // knew the node came undecoded).
                    let emcy = s
                        .master()
                        .emergencies(d.node)
                        .last()
                        .map_or_else(String::new, |e| {
                            format!(": {}", d.profile.decode_emcy(&e.emergency))
                        });
                    format!(
                        "node {} ({}) is in Fault, error code 0x{code:04X}{emcy}",
                        d.node, d.profile.name
                    )
                })
                .collect();
            return Ok(Some(format!(
                "{}; clear it at the drive, or run with reset_faults = true",
                named.join("; ")
            )));
        }
        for &i in &faulted {
            s.command(Command::FaultReset(Axes::One(i as u16)));
        }
        for _ in 0..self.cycles_of(ENABLE_TIMEOUT) {
            self.cycle(s)?;
            if faulted.iter().all(|&i| {
                s.telemetry(i)
                    .is_some_and(|t| t.state != Some(State::Fault))
            }) {
                // The reset's own refusals and the fault's account are history, not this run's.
                for &i in &faulted {
                    if let Some(v) = self.errors.get_mut(i) {
                        v.clear();
                    }
                }
                return Ok(None);
            }
        }
        Ok(Some(
            "a fault reset did not clear every drive's fault".into(),
        ))
    }

    fn stop_reason(&self, r: StopReason) -> String {
        let name = |a: u16| {
            self.cfg.drives.get(usize::from(a)).map_or_else(
                || format!("axis {a}"),
                |d| format!("node {} ({})", d.node, d.profile.name),
            )
        };
        match r {
            StopReason::Requested => "requested".to_string(),
            StopReason::Restart => "re-start requested".to_string(),
            StopReason::DriveFault { axis } => format!("{} faulted", name(axis)),
            StopReason::FollowingError { axis } => format!("{}: following error", name(axis)),
            StopReason::HomingFailed { axis } => format!("{}: homing failed", name(axis)),
            StopReason::ProbeNotLatched { axis, probe } => format!(
                "{}: touch probe {probe} did not latch within its probe_wait",
                name(axis)
            ),
            // EtherCAT's reasons; a CANopen run does not stop for them.
            StopReason::FramesLost { cycles } => format!("{cycles} cycles without a reply"),
            StopReason::DriveLeftOp { device } => format!("device {device} left OP"),
            StopReason::WorkingCounter => "the working counter stayed wrong".to_string(),
        }
    }

    /// A controlled stop, disable, NMT Stop; the report.
    fn finish<T: CanTransport>(
        mut self,
        mut s: MotionSession<T>,
        outcome: Outcome,
        reason: String,
    ) -> Result<CanRunReport, CanError> {
        s.command(Command::Stop(StopKind::Ramp));
        let limit = self.cycles_of(STOP_WAIT);
        // A drive whose TPDOs stopped (it left Operational) is not waited for: its last
        // statusword says nothing, and its RPDOs are not taken either.
        for _ in 0..limit {
            self.cycle(&mut s)?;
            if !self.any_energised(&s) {
                break;
            }
        }
        s.command(Command::Disable(Axes::All));
        for _ in 0..self.cycles_of(ENABLE_TIMEOUT) {
            self.cycle(&mut s)?;
            if !self.any_energised(&s) {
                break;
            }
        }
        let drives: Vec<CanDriveReport> = self
            .cfg
            .drives
            .iter()
            .enumerate()
            .map(|(i, d)| self.drive_report(&s, d, i))
            .collect();
        let mut m = s.into_master();
        let mut emergencies = Vec::new();
        for d in &self.cfg.drives {
            emergencies.extend(m.emergencies(d.node).map(ToString::to_string));
            // Life guarding off before the master goes, on a drive it disabled (one still
            // energised keeps watching for its master).
            let energised = m
                .drive(d.node)
                .is_some_and(|x| x.statusword().state().is_some_and(State::is_energised));
            if !energised
                && let Err(e) = m.supervise(d.node, crate::canopen::master::Supervision::None)
            {
                emergencies.push(format!(
                    "switching life guarding off on node {}: {e}",
                    d.node
                ));
            }
            // NMT Stop is refused to a drive still energised (the master's safety rule): the
            // report says so.
            if let Err(e) = m.nmt(d.node, crate::canopen::nmt::NmtCommand::Stop) {
                emergencies.push(format!("NMT Stop of node {}: {e}", d.node));
            }
        }
        let record = match self.recorder.take().map(Recorder::finish).transpose() {
            Ok(r) => r,
            Err(e) => {
                self.record_error = Some(e.to_string());
                None
            }
        };
        let warnings = self
            .record_error
            .iter()
            .map(|e| format!("the recording stopped: {e}"))
            .collect();
        // A master that itself stood still longer than the drives' supervision allows (the
        // host stalled, the process was stopped): the drives' loss reports are its doing.
        let cycle_us = u64::try_from(self.cfg.cycle.as_micros()).unwrap_or(u64::MAX);
        let reason = if self.longest_gap_us > STALL_US.max(10 * cycle_us) {
            format!(
                "{reason}; the master itself did not run for {} ms at one point (the host \
                 stalled or the process was stopped), longer than the drives' supervision \
                 allows: what they reported then is the master's doing",
                self.longest_gap_us / 1000
            )
        } else {
            reason
        };
        Ok(CanRunReport {
            config: self.cfg.source.clone(),
            bus: self.cfg.target.to_string(),
            cycle_us,
            outcome,
            reason,
            cycles: self.cycles,
            bus_time_us: m.now_us().saturating_sub(self.started_us),
            drives,
            emergencies,
            record,
            warnings,
            check_warnings: self.cfg.warnings.clone(),
            candump: None,
        })
    }

    fn drive_report<T: CanTransport>(
        &self,
        s: &MotionSession<T>,
        d: &CanDriveConfig,
        i: usize,
    ) -> CanDriveReport {
        let t = s.telemetry(i).copied().unwrap_or_default();
        let a = s.axis(i);
        let k = d.units.as_ref().map(|u| u.counts_per_unit);
        CanDriveReport {
            node: d.node,
            drive: d.profile.name,
            program: d.described.clone(),
            program_done: self.done.get(i).copied().unwrap_or(false) && !d.steps.is_empty(),
            states: a.map_or_else(Vec::new, |a| {
                a.states().iter().map(ToString::to_string).collect()
            }),
            modes: a.map_or_else(Vec::new, |a| {
                crate::motion::mode_names(a.modes_run(), a.modes_omitted(), ToString::to_string)
            }),
            position: t.position_actual,
            position_user: k.map(|k| t.position_actual as f64 / k),
            units: d
                .units
                .as_ref()
                .map_or_else(|| "counts".to_string(), |u| u.name.clone()),
            errors: self.errors.get(i).cloned().unwrap_or_default(),
            probe_latches: a.map_or_else(Vec::new, |a| {
                a.latches()
                    .iter()
                    .map(|&(probe, edge, counts)| CanProbeLatch {
                        probe,
                        edge: edge.name(),
                        counts,
                        value: k.map(|k| counts as f64 / k),
                    })
                    .collect()
            }),
        }
    }
}

/// Why drive `i` is not enabled: its state and statusword.
fn describe_not_enabled<T: CanTransport>(
    s: &MotionSession<T>,
    d: &CanDriveConfig,
    i: usize,
) -> String {
    let t = s.telemetry(i).copied().unwrap_or_default();
    let remote = if s.master().remote_off(d.node) {
        ", statusword bit 9 (remote) is 0: the drive ignores the controlword"
    } else {
        ""
    };
    format!(
        "node {} ({}) is in {} (statusword 0x{:04X}){remote}",
        d.node,
        d.profile.name,
        t.state
            .map_or_else(|| "no state yet".to_string(), |s| s.to_string()),
        t.statusword
    )
}
