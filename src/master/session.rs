//! [`Master`]: a running master — start-up, the cycle thread, and the supervisory side.
//!
//! `Master::start` opens a session on a link on its own thread, runs the start-up
//! ([`super::startup`]) and returns once the cycle runs (or with the start-up error). While the
//! cycle runs, the session thread supervises: it drains the cycle's events into a readable
//! history (faults decoded with each drive's alarm table), and polls the drives' mailboxes for
//! emergencies — its frames ride along in the cycle thread's exchanges. `stop` ends the cycle
//! in a controlled way, takes the drives to INIT, and returns the report and the link.

use super::bus::{BusOptions, SESSION_STACK, with_bus};
use super::coe::{CoeClient, EmergencyRecord};
use super::cycle::{self, CycleEnd, CycleHooks, CycleReport, CycleSettings};
use super::error::{DriveRef, ErrorKind, MasterError};
use super::exec;
use super::io::FrameLink;
use super::startup::{self, DeviceInfo, StartupConfig};
use super::telemetry::{Command, Event, EventKind, StopKind, Telemetry};
use crate::cia402::{self, ErrorCode, ErrorEntry};
use crate::ec::register;
use crate::pdo::Direction;
use crate::rt::{RtReport, monotonic_ns};
use ethercrab::Command as EcCommand;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// Everything a master run needs.
#[derive(Clone)]
pub struct MasterConfig {
    /// Start-up: cycle time, DC, drives.
    pub startup: StartupConfig,
    /// The cycle.
    pub cycle: CycleSettings,
    /// Bus timing.
    pub bus: BusOptions,
    /// Poll every drive's mailbox for emergencies this often while the cycle runs (`None`:
    /// never).
    pub emergency_poll: Option<Duration>,
    /// Instrumentation hooks on the cycle thread.
    pub hooks: Option<Arc<dyn CycleHooks + Send>>,
}

impl MasterConfig {
    /// Defaults for a cycle time.
    pub fn new(cycle: Duration) -> Self {
        Self {
            startup: StartupConfig::new(cycle),
            cycle: CycleSettings::new(cycle),
            bus: BusOptions::default(),
            emergency_poll: Some(Duration::from_millis(50)),
            hooks: None,
        }
    }
}

/// One drive of a running master.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct DriveSummary {
    /// How messages name it.
    pub drive: DriveRef,
    /// What discovery learned.
    pub info: DeviceInfo,
    /// Profile name.
    pub profile: &'static str,
    /// Output and input image sizes.
    pub image_bytes: (usize, usize),
    /// Start mode.
    pub mode: &'static str,
}

/// An entry of the error/event history.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HistoryEntry {
    /// `CLOCK_MONOTONIC` time, ns.
    pub time_ns: u64,
    /// Cycle number, if it came from the cycle.
    pub cycle: Option<u64>,
    /// The drive, if it concerns one.
    pub drive: Option<DriveRef>,
    /// Whether it is a fault or error (as opposed to information).
    pub error: bool,
    /// What happened, readable.
    pub text: String,
}

/// What a master run did.
#[derive(Debug, Clone)]
pub struct SessionReport {
    /// The drives.
    pub drives: Vec<DriveSummary>,
    /// The cycle's report.
    pub cycle: Option<CycleReport>,
    /// The history.
    pub history: Vec<HistoryEntry>,
    /// Every emergency received.
    pub emergencies: Vec<EmergencyRecord>,
    /// Whether the drives reached INIT at the end.
    pub shutdown_ok: bool,
}

/// A failed start: the error, and the link back.
pub struct StartFailure<L> {
    /// What went wrong.
    pub error: MasterError,
    /// The link, to try again.
    pub link: L,
}

impl<L> std::fmt::Debug for StartFailure<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "StartFailure({})", self.error)
    }
}

impl<L> std::fmt::Display for StartFailure<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.error.fmt(f)
    }
}

struct Shared {
    history: Mutex<Vec<HistoryEntry>>,
    rt: Mutex<Option<RtReport>>,
}

/// A running master. See the module documentation.
pub struct Master<L: FrameLink + Send + 'static> {
    commands: rtrb::Producer<Command>,
    telemetry: triple_buffer::Output<Telemetry>,
    shared: Arc<Shared>,
    drives: Vec<DriveSummary>,
    thread: Option<JoinHandle<SessionOutcome<L>>>,
}

/// What the session thread returns: its report (none if start-up failed) and the link; `None`
/// if the thread never received the link.
type SessionOutcome<L> = Option<(Option<SessionReport>, L)>;

/// Names and alarm tables of the drives, for decoding events outside the cycle.
struct Decoder {
    drives: Vec<(DriveRef, &'static [ErrorEntry])>,
}

impl Decoder {
    fn drive(&self, axis: u16) -> Option<DriveRef> {
        self.drives.get(axis as usize).map(|(d, _)| d.clone())
    }

    fn table(&self, axis: u16) -> &'static [ErrorEntry] {
        self.drives.get(axis as usize).map_or(&[], |(_, t)| t)
    }

    fn entry(&self, e: &Event) -> Option<HistoryEntry> {
        let (drive, error, text) = match e.kind {
            EventKind::AllOp => (None, false, "every drive is in OP".to_string()),
            EventKind::OpTimeout { axis, al_state } => (
                self.drive(axis),
                true,
                format!(
                    "did not reach OP (AL status {})",
                    cycle::al_state_name(al_state)
                ),
            ),
            EventKind::Axis { axis, event } => {
                let (error, text) = match event {
                    cia402::Event::Fault { state, error } => (
                        true,
                        match error {
                            Some(d) => {
                                // Re-describe with the drive's table (names like "AL.86").
                                let d = d.code.describe(self.table(axis));
                                format!(
                                    "fault ({}): {d}",
                                    state.map_or("?".into(), |s| s.to_string())
                                )
                            }
                            None => {
                                format!("fault ({})", state.map_or("?".into(), |s| s.to_string()))
                            }
                        },
                    ),
                    cia402::Event::PlannerFailed(p) => (true, format!("state machine: {p}")),
                    cia402::Event::ModeSwitchFailed(m) => {
                        (true, format!("mode switch failed: {m}"))
                    }
                    cia402::Event::StateChanged { from, to } => {
                        let name = |s: Option<cia402::State>| {
                            s.map_or("(no state)".to_string(), |s| s.to_string())
                        };
                        (false, format!("state {} → {}", name(from), name(to)))
                    }
                    cia402::Event::TargetReached(t) => (false, format!("reached {t:?}")),
                    cia402::Event::FaultCleared => (false, "fault cleared".into()),
                    cia402::Event::WarningChanged(w) => (
                        false,
                        if w { "warning set" } else { "warning cleared" }.into(),
                    ),
                    cia402::Event::ModeSwitched { from, to } => {
                        (false, format!("mode {from} → {to}"))
                    }
                    cia402::Event::ModeDisplayMismatch {
                        expected,
                        displayed,
                    } => (
                        true,
                        format!(
                            "0x6061 shows {displayed} instead of {expected}; set-points paused"
                        ),
                    ),
                };
                (self.drive(axis), error, text)
            }
            EventKind::WorkingCounter {
                got,
                expected,
                missing,
            } => (
                missing.and_then(|m| self.drive(m)),
                true,
                format!(
                    "working counter {got}, expected {expected}{}",
                    if missing.is_some() {
                        " (this drive did not answer)"
                    } else {
                        ""
                    }
                ),
            ),
            EventKind::AlState { axis, state } => (
                self.drive(axis),
                state != 8 && state & 0x10 != 0,
                format!("AL state {}", cycle::al_state_name(state)),
            ),
            EventKind::FrameLost { consecutive } => (
                None,
                true,
                format!("no reply in this cycle ({consecutive} in a row)"),
            ),
            EventKind::FramesResumed { lost } => (
                None,
                false,
                format!("replies resumed after {lost} lost cycle(s)"),
            ),
            EventKind::SegmentLost { cycles } => (
                None,
                true,
                format!(
                    "the segment stopped answering ({cycles} cycles without a reply); drives: {}",
                    self.drives
                        .iter()
                        .map(|(d, _)| d.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ),
            EventKind::FollowingError { axis, value, limit } => (
                self.drive(axis),
                true,
                format!("master-side following error {value} exceeds {limit}"),
            ),
            EventKind::ProgramStep { axis, step } => {
                (self.drive(axis), false, format!("program step {step}"))
            }
            EventKind::ProgramDone { axis } => (self.drive(axis), false, "program done".into()),
            EventKind::CommandRefused { axis, why } => (self.drive(axis), true, why.to_string()),
            EventKind::Stopping { reason } => {
                (None, false, format!("stopping the axes: {reason:?}"))
            }
            EventKind::Stopped => (None, false, "every axis disabled; cycle ended".into()),
        };
        Some(HistoryEntry {
            time_ns: e.time_ns,
            cycle: Some(e.cycle),
            drive,
            error,
            text,
        })
    }
}

impl<L: FrameLink + Send + 'static> Master<L> {
    /// Start a master on `link`: start-up, then the cycle. Returns once the cycle runs (the
    /// drives then go to OP by themselves), or with the start-up error and the link.
    pub fn start(link: L, cfg: MasterConfig) -> Result<Self, StartFailure<L>> {
        let n_hint = cfg.startup.drives.len().max(8);
        let (cycle_io, sup) = cycle::channels(n_hint);
        let shared = Arc::new(Shared {
            history: Mutex::new(Vec::new()),
            rt: Mutex::new(None),
        });
        let (tx, rx) = mpsc::channel::<Result<Vec<DriveSummary>, MasterError>>();
        let shared2 = shared.clone();
        let cfg2 = cfg.clone();
        let mut events = sup.events;
        // The link goes to the session thread only once it runs, so that a failed spawn can
        // give it back.
        let (link_tx, link_rx) = mpsc::channel::<L>();
        let thread = std::thread::Builder::new()
            .name("ecdrive-session".into())
            .stack_size(SESSION_STACK)
            .spawn(move || {
                let Ok(link) = link_rx.recv() else {
                    return None;
                };
                let tx_err = tx.clone();
                let r = with_bus(link, cfg2.bus, move |bus| {
                    session(bus, &cfg2, cycle_io, &mut events, &shared2, &tx)
                });
                Some(match r {
                    Ok((report, link)) => (report, link),
                    Err((e, link)) => {
                        let _ = tx_err.send(Err(MasterError::new(
                            None,
                            "opening the bus",
                            ErrorKind::Bus,
                            e,
                        )));
                        (None, link)
                    }
                })
            });
        let thread = match thread {
            Ok(t) => t,
            Err(e) => {
                return Err(StartFailure {
                    error: MasterError::new(None, "starting the session thread", ErrorKind::Bus, e),
                    link,
                });
            }
        };
        if let Err(mpsc::SendError(link)) = link_tx.send(link) {
            return Err(StartFailure {
                error: MasterError::new(
                    None,
                    "starting the session thread",
                    ErrorKind::Bus,
                    "it ended at once",
                ),
                link,
            });
        }
        match rx.recv() {
            Ok(Ok(drives)) => Ok(Self {
                commands: sup.commands,
                telemetry: sup.telemetry,
                shared,
                drives,
                thread: Some(thread),
            }),
            Ok(Err(error)) => match thread.join() {
                Ok(Some((_, link))) => Err(StartFailure { error, link }),
                Ok(None) => unreachable!("the session thread received the link"),
                Err(p) => std::panic::resume_unwind(p),
            },
            Err(_) => match thread.join() {
                Ok(Some((_, link))) => Err(StartFailure {
                    error: MasterError::new(
                        None,
                        "start-up",
                        ErrorKind::Bus,
                        "the session ended without a result",
                    ),
                    link,
                }),
                Ok(None) => unreachable!("the session thread received the link"),
                Err(p) => std::panic::resume_unwind(p),
            },
        }
    }

    /// The drives.
    pub fn drives(&self) -> &[DriveSummary] {
        &self.drives
    }

    /// Send a command to the cycle.
    pub fn command(&mut self, c: Command) -> Result<(), MasterError> {
        self.commands.push(c).map_err(|_| {
            MasterError::new(
                None,
                "sending a command to the cycle",
                ErrorKind::Bus,
                "the command queue is full",
            )
        })
    }

    /// The latest telemetry snapshot.
    pub fn telemetry(&mut self) -> &Telemetry {
        self.telemetry.read()
    }

    /// The history so far.
    pub fn history(&self) -> Vec<HistoryEntry> {
        self.shared
            .history
            .lock()
            .map(|h| h.clone())
            .unwrap_or_default()
    }

    /// What the cycle thread's real-time set-up got (priority, CPU, locked memory, warnings),
    /// once the cycle has started.
    pub fn rt_report(&self) -> Option<RtReport> {
        self.shared.rt.lock().ok().and_then(|r| r.clone())
    }

    /// Whether the session (and its cycle) still runs.
    pub fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Wait until `pred` holds for the telemetry, checking every millisecond; an error naming
    /// `what` after `timeout`, or when the session ended.
    pub fn wait_until(
        &mut self,
        what: &str,
        timeout: Duration,
        mut pred: impl FnMut(&Telemetry) -> bool,
    ) -> Result<(), MasterError> {
        let deadline = monotonic_ns() + timeout.as_nanos() as u64;
        loop {
            if pred(self.telemetry.read()) {
                return Ok(());
            }
            if !self.is_running() {
                return Err(MasterError::new(
                    None,
                    format!("waiting for {what}"),
                    ErrorKind::Bus,
                    "the cycle ended",
                ));
            }
            if monotonic_ns() > deadline {
                return Err(MasterError::new(
                    None,
                    format!("waiting for {what}"),
                    ErrorKind::Timeout,
                    format!("not reached within {} ms", timeout.as_millis()),
                ));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Stop every axis in a controlled way, end the cycle, take the drives to INIT. Returns the
    /// report and the link.
    pub fn stop(mut self, kind: StopKind) -> (Option<SessionReport>, L) {
        let _ = self.commands.push(Command::Stop(kind));
        self.join()
    }

    /// Wait for the session to end by itself (segment lost, OP failed) and return its report
    /// and the link.
    pub fn join(mut self) -> (Option<SessionReport>, L) {
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Some(r))) => r,
            Some(Ok(None)) => unreachable!("the session thread received the link in start"),
            Some(Err(p)) => std::panic::resume_unwind(p),
            None => unreachable!("join consumes the master; the thread is joined once"),
        }
    }
}

impl<L: FrameLink + Send + 'static> Drop for Master<L> {
    fn drop(&mut self) {
        if self.thread.is_some() {
            let _ = self.commands.push(Command::Stop(StopKind::Ramp));
            if let Some(t) = self.thread.take() {
                let _ = t.join();
            }
        }
    }
}

/// The session: start-up, cycle, supervision, shutdown. Runs on the session thread.
fn session<L: FrameLink + Send>(
    bus: &mut super::bus::Bus<'_, L>,
    cfg: &MasterConfig,
    mut cycle_io: cycle::CycleIo,
    events: &mut rtrb::Consumer<Event>,
    shared: &Shared,
    started_tx: &mpsc::Sender<Result<Vec<DriveSummary>, MasterError>>,
) -> Option<SessionReport> {
    let started = match (|| {
        let (group, devices) = startup::discover(bus)?;
        let plan = startup::plan(&devices, &cfg.startup)?;
        startup::configure(bus, group, devices, plan, &cfg.startup)
    })() {
        Ok(s) => s,
        Err(e) => {
            let _ = started_tx.send(Err(e));
            return None;
        }
    };
    let summaries: Vec<DriveSummary> = started
        .drives
        .iter()
        .map(|d| DriveSummary {
            drive: d.drive.clone(),
            info: d.info.clone(),
            profile: d.profile.name,
            image_bytes: (d.layout.bytes(Direction::Rx), d.layout.bytes(Direction::Tx)),
            mode: d.setup.mode.name(),
        })
        .collect();
    let decoder = Decoder {
        drives: started
            .drives
            .iter()
            .map(|d| (d.drive.clone(), d.profile.caps.error_table))
            .collect(),
    };
    let _ = started_tx.send(Ok(summaries.clone()));

    let push_history = |e: HistoryEntry| {
        if let Ok(mut h) = shared.history.lock() {
            h.push(e);
        }
    };
    let log = bus.emergencies().clone();
    let mut seen_emcy = 0usize;
    let drain_emcy = |seen: &mut usize| {
        if let Ok(l) = log.lock() {
            for r in l.iter().skip(*seen) {
                let table = decoder
                    .drives
                    .get(r.position as usize)
                    .map_or(&[][..], |(_, t)| *t);
                let d = ErrorCode(r.error_code).describe(table);
                push_history(HistoryEntry {
                    time_ns: r.time_ns,
                    cycle: None,
                    drive: decoder.drive(r.position),
                    error: r.error_code != 0,
                    text: format!("emergency: {d} (error register 0x{:02X})", r.error_register),
                });
            }
            *seen = l.len();
        }
    };

    let (rt_tx, rt_rx) = mpsc::channel();
    cycle_io.rt_report = Some(rt_tx);
    let hooks = cfg.hooks.clone();
    let drives = &started.drives;
    let group = &started.group;
    let mbx_timeout = cfg.bus.mailbox_timeout;
    let addrs: Vec<(u16, DriveRef, bool)> = drives
        .iter()
        .map(|d| (d.info.address, d.drive.clone(), d.profile.complete_access))
        .collect();
    let (md, pump) = bus.split();
    let report = std::thread::scope(|s| {
        let h = std::thread::Builder::new()
            .name("ecdrive-cycle".into())
            .stack_size(8 * 1024 * 1024)
            .spawn_scoped(s, move || {
                let hooks_ref = hooks.as_deref().map(|h| h as &dyn CycleHooks);
                cycle::run(md, pump, group, drives, &cfg.cycle, cycle_io, hooks_ref)
            });
        let h = match h {
            Ok(h) => h,
            Err(e) => {
                push_history(HistoryEntry {
                    time_ns: monotonic_ns(),
                    cycle: None,
                    drive: None,
                    error: true,
                    text: format!("cannot start the cycle thread: {e}"),
                });
                return None;
            }
        };
        let mut next_poll = monotonic_ns();
        let mut counters = vec![0u8; addrs.len()];
        if let Ok(rt) = rt_rx.recv_timeout(Duration::from_secs(5)) {
            for w in &rt.warnings {
                tracing::warn!("{w}");
                push_history(HistoryEntry {
                    time_ns: monotonic_ns(),
                    cycle: None,
                    drive: None,
                    error: false,
                    text: format!("warning: {w}"),
                });
            }
            if let Ok(mut r) = shared.rt.lock() {
                *r = Some(rt);
            }
        }
        while !h.is_finished() {
            while let Ok(e) = events.pop() {
                if let Some(entry) = decoder.entry(&e) {
                    push_history(entry);
                }
            }
            if let Some(every) = cfg.emergency_poll
                && monotonic_ns() >= next_poll
            {
                next_poll = monotonic_ns() + every.as_nanos() as u64;
                for ((addr, drive, ca), counter) in addrs.iter().zip(counters.iter_mut()) {
                    let log = log.clone();
                    let last = *counter;
                    let r = exec::run_remote(
                        &|| format!("{drive}: polling the mailbox"),
                        mbx_timeout,
                        async {
                            let mut c = CoeClient::new(md, *addr, drive.clone(), log)
                                .await?
                                .with_complete_access(*ca)
                                .with_counter(last);
                            c.drain().await?;
                            Ok::<_, super::coe::CoeError>(c.counter())
                        },
                    );
                    if let Ok(Ok(c)) = r {
                        *counter = c;
                    }
                }
                drain_emcy(&mut seen_emcy);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        while let Ok(e) = events.pop() {
            if let Some(entry) = decoder.entry(&e) {
                push_history(entry);
            }
        }
        h.join().ok()
    });

    // Shutdown: every drive to INIT (the cycle has disabled the axes).
    let mut shutdown_ok = true;
    if !matches!(
        report.as_ref().map(|r| r.end),
        Some(CycleEnd::SegmentLost | CycleEnd::LinkFailed)
    ) {
        for d in drives {
            let addr = d.info.address;
            let r = bus.block_on(
                &|| format!("{}: requesting INIT", d.drive),
                Duration::from_secs(2),
                |md| async move {
                    EcCommand::fpwr(addr, register::AL_CONTROL)
                        .send(md, 0x0011u16)
                        .await
                },
            );
            if !matches!(r, Ok(Ok(()))) {
                shutdown_ok = false;
            }
        }
    } else {
        shutdown_ok = false;
    }
    drain_emcy(&mut seen_emcy);
    let history = shared.history.lock().map(|h| h.clone()).unwrap_or_default();
    let emergencies = log.lock().map(|l| l.clone()).unwrap_or_default();
    Some(SessionReport {
        drives: summaries,
        cycle: report,
        history,
        emergencies,
        shutdown_ok,
    })
}
