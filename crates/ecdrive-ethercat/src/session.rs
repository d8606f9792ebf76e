//! [`Master`]: a running master — start-up, the cycle thread, and the supervisory side.
//!
//! `Master::start` opens a session on a link on its own thread, runs the start-up
//! ([`super::startup`]) and returns once the cycle runs (or with the start-up error). While the
//! cycle runs, the session thread supervises: it drains the cycle's events into a readable
//! history (faults decoded with each drive's alarm table), and polls the drives' mailboxes for
//! emergencies — its frames ride along in the cycle thread's exchanges. `stop` ends the cycle
//! in a controlled way, takes the drives to INIT, and returns the report and the link.

use super::app::CycleApp;
use super::bus::{BusOptions, SESSION_STACK, with_bus};
use super::coe::{EmergencyLog, EmergencyRecord};
use super::cycle::{self, CycleEnd, CycleHooks, CycleReport, CycleSettings};
use super::error::{DriveRef, ErrorKind, MasterError};
pub use super::history::{
    HistoryEntry, HistoryEvent, HistoryKind, HistoryLog, HistorySlice, Resolved, RestartNote,
};
use super::io::FrameLink;
use super::record::RecordTx;
use super::startup::{self, DeviceInfo, StartupConfig};
use super::supervise::{MailboxDevice, MailboxRequest, Mailboxes};
use super::telemetry::{
    AxisTelemetry, Command, CycleTelemetry, Event, EventKind, Phase, StopKind, StopReason,
    Telemetry,
};
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
    /// never). With the cycle's own frames ([`CycleSettings::own_frames`]) a poll reads the
    /// mailboxes only when the cycle's broadcast read of SM1's status said that one holds
    /// something (or could not say); with ethercrab's, every time.
    pub emergency_poll: Option<Duration>,
    /// Instrumentation hooks on the cycle thread.
    pub hooks: Option<Arc<dyn CycleHooks + Send>>,
    /// The application's code in the cycle ([`CycleApp`]), called once per cycle. The cycle
    /// thread holds the lock for the whole run (so the caller's clone of the `Arc` can look
    /// at it once the master has stopped, or between runs).
    pub app: Option<Arc<Mutex<dyn CycleApp>>>,
    /// Every cycle recorded into this ring ([`crate::record::recording`]); the cycle thread
    /// holds the lock for the whole run, as with `app`.
    pub record: Option<Arc<Mutex<RecordTx>>>,
    /// What happens when the cycle ends by itself (segment lost, a drive fell out of OP).
    pub restart: RestartPolicy,
    /// History entries kept with their text (the latest; older ones are discarded but
    /// counted per kind): see [`HistoryLog`].
    pub history_capacity: usize,
}

/// What the session does when its cycle ends by itself: the segment stopped answering, or a
/// drive fell out of OP (every axis has then been stopped and disabled).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestartPolicy {
    /// The session ends; [`Master::join`] returns the report and the link (start a new
    /// [`Master`] on it to try again).
    Never,
    /// The session waits (no frames) for [`Master::restart`] or [`Master::stop`].
    OnRequest,
    /// The session re-starts the drives by itself: every `retry_every` it checks whether the
    /// segment answers with the same drives and takes them INIT → OP. After `max_attempts`
    /// failed attempts in a row (if set) it waits for a request as with `OnRequest`.
    Auto {
        /// Time between attempts.
        retry_every: Duration,
        /// Failed attempts in a row before falling back to waiting for a request.
        max_attempts: Option<u32>,
    },
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
            app: None,
            record: None,
            restart: RestartPolicy::Never,
            history_capacity: HistoryLog::DEFAULT_CAPACITY,
        }
    }
}

/// One drive of a running master.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DriveSummary {
    /// How messages name it.
    pub drive: DriveRef,
    /// What discovery learned.
    pub info: DeviceInfo,
    /// Profile name.
    pub profile: &'static str,
    /// Output and input image sizes.
    pub image_bytes: (usize, usize),
    /// The PDOs assigned (mapping object indices), RxPDOs and TxPDOs: the mapping start-up
    /// chose and wrote (or found fixed).
    pub pdos: (Vec<u16>, Vec<u16>),
    /// Start mode.
    pub mode: &'static str,
    /// The units of its CiA 402 objects (its profile's).
    #[serde(skip)]
    pub units: ecdrive_core::cia402::Units,
    /// The user's units, where the configuration gives them.
    pub user_units: Option<startup::UserUnits>,
}

/// One device of a running master that is not driven (an I/O device): in OP with its own PDO
/// configuration, its process data exchanged every cycle.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct IoSummary {
    /// How messages name it.
    pub device: DriveRef,
    /// What discovery learned.
    pub info: DeviceInfo,
    /// Output and input image sizes.
    pub image_bytes: (usize, usize),
    /// Why it is not driven.
    pub why: String,
}

/// What a master run did.
#[derive(Debug, Clone)]
pub struct SessionReport {
    /// The drives.
    pub drives: Vec<DriveSummary>,
    /// The devices that are not driven.
    pub io: Vec<IoSummary>,
    /// The cycle's report.
    pub cycle: Option<CycleReport>,
    /// The history: the latest [`MasterConfig::history_capacity`] entries.
    pub history: Vec<HistoryEntry>,
    /// Entries of the history discarded because it was full (the oldest).
    pub history_discarded: u64,
    /// History entries per kind over the whole run, discarded ones included.
    pub history_totals: std::collections::BTreeMap<HistoryKind, u64>,
    /// Every emergency received.
    pub emergencies: Vec<EmergencyRecord>,
    /// Where the first start-up's time went, to OP when every device got there.
    pub startup: Option<startup::StartupTimes>,
    /// Whether the drives reached INIT at the end.
    pub shutdown_ok: bool,
    /// Re-starts that brought the drives back to OP.
    pub restarts: u32,
}

/// One drive's part of a run, from the cycle's report (what the CLI's summary shows per drive):
/// [`SessionReport::drive_outcomes`].
#[derive(Debug, Clone, PartialEq)]
pub struct DriveOutcome {
    /// Which drive.
    pub drive: DriveRef,
    /// Largest |following error| while energised in csp, counts, as the master computes it
    /// (demand − actual with the cycle's transport delay); the limit uses it.
    pub max_following_error: i64,
    /// The same in the drive's user units, where the configuration gives them.
    pub max_following_error_units: Option<f64>,
    /// Largest |0x60F4| the drive reported meanwhile (`None`: not mapped).
    pub max_following_error_drive: Option<i64>,
    /// 0x60F4 stayed 0 while the axis moved: the drive does not compute it (not trusted).
    pub following_error_drive_stuck: bool,
    /// CiA 402 states it went through, in order.
    pub states: Vec<cia402::State>,
    /// Modes it ran set-points in, in order.
    pub modes_run: Vec<cia402::OperationMode>,
    /// Mode changes beyond what `modes_run` keeps (`ecdrive_motion::MODES_KEPT`).
    pub modes_omitted: u32,
    /// Touch-probe latches, in order: (probe, edge, position in counts).
    pub probe_latches: Vec<(u8, crate::program::ProbeEdge, i64)>,
}

impl SessionReport {
    /// Per drive (in the order of [`SessionReport::drives`]), what the run did: the largest
    /// following errors, the states and modes, the probe latches. Empty figures when the
    /// cycle never ran.
    pub fn drive_outcomes(&self) -> Vec<DriveOutcome> {
        let c = self.cycle.as_ref();
        self.drives
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let max_fe = c
                    .and_then(|c| c.max_following_error.get(i).copied())
                    .unwrap_or(0);
                DriveOutcome {
                    drive: d.drive.clone(),
                    max_following_error: max_fe,
                    max_following_error_units: d
                        .user_units
                        .as_ref()
                        .map(|u| max_fe as f64 / u.counts_per_unit),
                    max_following_error_drive: c
                        .and_then(|c| c.max_following_error_drive.get(i).copied())
                        .flatten(),
                    following_error_drive_stuck: c
                        .and_then(|c| c.following_error_drive_stuck.get(i).copied())
                        .unwrap_or(false),
                    states: c.and_then(|c| c.states.get(i).cloned()).unwrap_or_default(),
                    modes_run: c
                        .and_then(|c| c.modes_run.get(i).cloned())
                        .unwrap_or_default(),
                    modes_omitted: c.and_then(|c| c.modes_omitted.get(i).copied()).unwrap_or(0),
                    probe_latches: c
                        .and_then(|c| c.probe_latches.get(i).cloned())
                        .unwrap_or_default(),
                }
            })
            .collect()
    }
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
    history: Mutex<HistoryLog>,
    rt: Mutex<Option<RtReport>>,
    /// The application's SDO requests ([`Master::sdo_upload`]), served by the session thread.
    requests: Mutex<mpsc::Receiver<MailboxRequest>>,
    /// The session thread has ended (no request will be served).
    ended: std::sync::atomic::AtomicBool,
}

/// A running master. See the module documentation.
pub struct Master<L: FrameLink + Send + 'static> {
    commands: rtrb::Producer<Command>,
    requests: mpsc::Sender<MailboxRequest>,
    mailbox_timeout: Duration,
    telemetry: triple_buffer::Output<Telemetry>,
    shared: Arc<Shared>,
    drives: Vec<DriveSummary>,
    io: Vec<IoSummary>,
    thread: Option<JoinHandle<SessionOutcome<L>>>,
}

/// What a successful start-up hands to the [`Master`].
struct Started {
    drives: Vec<DriveSummary>,
    io: Vec<IoSummary>,
    commands: rtrb::Producer<Command>,
    telemetry: triple_buffer::Output<Telemetry>,
}

/// What the session thread returns: its report (none if start-up failed) and the link; `None`
/// if the thread never received the link.
type SessionOutcome<L> = Option<(Option<SessionReport>, L)>;

/// Names and alarm tables of the drives (by axis), and the names of every device (by position),
/// for decoding events outside the cycle.
struct Resolver {
    drives: Vec<(DriveRef, &'static [ErrorEntry])>,
    devices: Vec<DriveRef>,
    /// Per axis: the user's units, for following errors.
    units: Vec<Option<startup::UserUnits>>,
}

impl Resolver {
    fn device(&self, position: u16) -> Option<DriveRef> {
        self.devices.get(position as usize).cloned()
    }

    fn device_name(&self, position: u16) -> String {
        self.device(position)
            .map_or_else(|| format!("device {position}"), |d| d.to_string())
    }

    fn drive(&self, axis: u16) -> Option<DriveRef> {
        self.drives.get(axis as usize).map(|(d, _)| d.clone())
    }

    fn table(&self, axis: u16) -> &'static [ErrorEntry] {
        self.drives.get(axis as usize).map_or(&[], |(_, t)| t)
    }

    fn units(&self, axis: u16) -> Option<startup::UserUnits> {
        self.units.get(axis as usize).cloned().flatten()
    }

    /// The history entry of a cycle event: the drive it concerns, and what its words need
    /// (names, the drive's alarm text, user units), resolved now.
    fn entry(&self, e: &Event) -> HistoryEntry {
        let mut r = Resolved::default();
        let drive = match e.kind {
            EventKind::AllOp
            | EventKind::FramesResumed { .. }
            | EventKind::Stopped
            | EventKind::Stopping { .. } => None,
            EventKind::FrameLost { .. }
            | EventKind::SegmentGone { .. }
            | EventKind::SegmentLost { .. } => {
                r.drives = self.drives.iter().map(|(d, _)| d.clone()).collect();
                None
            }
            EventKind::OpTimeout { device, .. }
            | EventKind::OutputsNotTaken { device, .. }
            | EventKind::AlState { device, .. }
            | EventKind::LeftOp { device, .. } => self.device(device),
            EventKind::WorkingCounter { missing, .. } => missing.and_then(|m| self.device(m)),
            EventKind::Axis { axis, event } => {
                if let cia402::Event::Fault { error: Some(d), .. } = event {
                    // Re-described with the drive's table (names like "AL.86").
                    r.fault = Some(d.code.describe(self.table(axis)));
                }
                self.drive(axis)
            }
            EventKind::FollowingError { axis, .. } | EventKind::ProbeLatched { axis, .. } => {
                r.units = self.units(axis);
                self.drive(axis)
            }
            EventKind::DriveFollowingErrorStuck { .. }
            | EventKind::ProgramStep { .. }
            | EventKind::ProgramDone { .. }
            | EventKind::CommandRefused { .. }
            | EventKind::HomingFailed { .. }
            | EventKind::ProbeNotLatched { .. }
            | EventKind::SetpointLimit { .. }
            | EventKind::StreamUnderrun { .. } => e.kind.axis().and_then(|a| self.drive(a)),
        };
        if let EventKind::Stopping { reason } = e.kind {
            r.subject = match reason {
                StopReason::DriveLeftOp { device } => self.device(device),
                r => r.axis().and_then(|a| self.drive(a)),
            };
        }
        HistoryEntry::new(
            e.time_ns,
            Some(e.cycle),
            drive,
            HistoryEvent::Cycle(e.kind),
            r,
        )
    }
}

/// The application's code and the recording, locked for a run of the cycle.
#[allow(clippy::type_complexity)]
fn lock_app(
    cfg: &MasterConfig,
) -> (
    Option<std::sync::MutexGuard<'_, dyn CycleApp + 'static>>,
    Option<std::sync::MutexGuard<'_, RecordTx>>,
) {
    let app = cfg
        .app
        .as_ref()
        .map(|a| a.lock().unwrap_or_else(std::sync::PoisonError::into_inner));
    let record = cfg
        .record
        .as_ref()
        .map(|r| r.lock().unwrap_or_else(std::sync::PoisonError::into_inner));
    (app, record)
}

impl<L: FrameLink + Send + 'static> Master<L> {
    /// Start a master on `link`: start-up, then the cycle. Returns once the cycle runs (the
    /// drives then go to OP by themselves), or with the start-up error and the link.
    pub fn start(link: L, cfg: MasterConfig) -> Result<Self, StartFailure<L>> {
        let (requests, requests_rx) = mpsc::channel();
        let shared = Arc::new(Shared {
            history: Mutex::new(HistoryLog::new(cfg.history_capacity)),
            rt: Mutex::new(None),
            requests: Mutex::new(requests_rx),
            ended: std::sync::atomic::AtomicBool::new(false),
        });
        let mailbox_timeout = cfg.bus.mailbox_timeout;
        let (tx, rx) = mpsc::channel::<Result<Started, MasterError>>();
        let shared2 = shared.clone();
        let cfg2 = cfg.clone();
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
                let outcome = session(link, &cfg2, &shared2, &tx);
                shared2
                    .ended
                    .store(true, std::sync::atomic::Ordering::Release);
                Some(outcome)
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
            Ok(Ok(Started {
                drives,
                io,
                commands,
                telemetry,
            })) => Ok(Self {
                commands,
                requests,
                mailbox_timeout,
                telemetry,
                shared,
                drives,
                io,
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

    /// The devices that are not driven (I/O devices), in segment order.
    pub fn io(&self) -> &[IoSummary] {
        &self.io
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

    /// Read an object of the device at segment `position` over CoE while the cycle runs: the
    /// session thread sends the request with its mailbox polls (its frames ride along in the
    /// cycle's exchanges; the cycle is not held up). The bytes as the device sent them; an
    /// error names the device, the object and the reason (an SDO abort code, a timeout).
    pub fn sdo_upload(
        &self,
        position: u16,
        address: crate::od::ObjectAddress,
    ) -> Result<Vec<u8>, MasterError> {
        self.sdo_requester().upload(position, address)
    }

    /// Write an object of the device at segment `position` over CoE while the cycle runs, as
    /// [`Master::sdo_upload`] reads one.
    pub fn sdo_download(
        &self,
        position: u16,
        address: crate::od::ObjectAddress,
        data: &[u8],
    ) -> Result<(), MasterError> {
        self.sdo_requester().download(position, address, data)
    }

    /// A handle for [`Master::sdo_upload`] and [`Master::sdo_download`] that another thread
    /// may keep and use without the [`Master`] (a request waits up to the mailbox timeout).
    pub fn sdo_requester(&self) -> SdoRequester {
        SdoRequester {
            requests: self.requests.clone(),
            shared: self.shared.clone(),
            mailbox_timeout: self.mailbox_timeout,
        }
    }

    /// The latest telemetry snapshot.
    pub fn telemetry(&mut self) -> &Telemetry {
        self.telemetry.read()
    }

    /// The history so far: the latest [`MasterConfig::history_capacity`] entries, oldest
    /// first. A program that polls should use [`Master::history_since`], which copies only
    /// what is new.
    pub fn history(&self) -> Vec<HistoryEntry> {
        self.shared
            .history
            .lock()
            .map(|h| h.entries())
            .unwrap_or_default()
    }

    /// The history entries from sequence number `seq` on (0: from the start), with the number
    /// to pass next time, what was missed because it had been discarded, and the totals per
    /// kind.
    pub fn history_since(&self, seq: u64) -> HistorySlice {
        self.shared
            .history
            .lock()
            .map(|h| h.since(seq))
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
                    format!(
                        "not reached within {} ms ({})",
                        timeout.as_millis(),
                        where_things_stand(self.telemetry.read())
                    ),
                ));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Re-start the drives on the same link (see [`Command::Restart`]): while the cycle runs,
    /// every axis is stopped in a controlled way and the cycle ends first; while the session
    /// waits after the segment was lost or a drive fell out of OP, the drives are taken
    /// INIT → OP again. The history records each attempt and its outcome.
    pub fn restart(&mut self) -> Result<(), MasterError> {
        self.command(Command::Restart)
    }

    /// Stop every axis in a controlled way, end the cycle, take the drives to INIT. Returns the
    /// report and the link.
    pub fn stop(mut self, kind: StopKind) -> (Option<SessionReport>, L) {
        let _ = self.commands.push(Command::Stop(kind));
        self.join()
    }

    /// [`Master::stop`], watching `hurry` meanwhile: once it is set (a second stop request), the
    /// axes still ramping down are quick stopped instead. Every axis is disabled either way.
    pub fn stop_watching(
        mut self,
        kind: StopKind,
        hurry: Option<&std::sync::atomic::AtomicBool>,
    ) -> (Option<SessionReport>, L) {
        let _ = self.commands.push(Command::Stop(kind));
        let mut hurried = kind == StopKind::QuickStop;
        while self.thread.as_ref().is_some_and(|t| !t.is_finished()) {
            if !hurried && hurry.is_some_and(|h| h.load(std::sync::atomic::Ordering::Acquire)) {
                hurried = true;
                let _ = self.commands.push(Command::Stop(StopKind::QuickStop));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        self.join()
    }

    /// Wait for the session to end by itself and return its report and the link. With
    /// [`RestartPolicy::Never`] it ends when its cycle does (segment lost, a drive fell out of
    /// OP, OP not reached); with the other policies only on [`Master::stop`].
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

/// SDO requests to a running master's session ([`Master::sdo_requester`]).
#[derive(Clone)]
pub struct SdoRequester {
    requests: mpsc::Sender<MailboxRequest>,
    shared: Arc<Shared>,
    mailbox_timeout: Duration,
}

impl SdoRequester {
    /// [`Master::sdo_upload`].
    pub fn upload(
        &self,
        position: u16,
        address: crate::od::ObjectAddress,
    ) -> Result<Vec<u8>, MasterError> {
        let (reply, rx) = mpsc::channel();
        let what = format!("reading {address} of the device at position {position}");
        let r = MailboxRequest::Upload {
            position,
            address,
            reply,
        };
        self.request(r, rx, &what)
    }

    /// [`Master::sdo_download`].
    pub fn download(
        &self,
        position: u16,
        address: crate::od::ObjectAddress,
        data: &[u8],
    ) -> Result<(), MasterError> {
        let (reply, rx) = mpsc::channel();
        let what = format!("writing {address} of the device at position {position}");
        let r = MailboxRequest::Download {
            position,
            address,
            data: data.to_vec(),
            reply,
        };
        self.request(r, rx, &what)
    }

    /// Hand `r` to the session thread and wait for its answer: the mailbox timeout, plus the
    /// session's longest pause and a poll under way.
    fn request<T>(
        &self,
        r: MailboxRequest,
        rx: mpsc::Receiver<Result<T, MasterError>>,
        what: &str,
    ) -> Result<T, MasterError> {
        let ended = || MasterError::new(None, what, ErrorKind::Bus, "the session has ended");
        let over = || self.shared.ended.load(std::sync::atomic::Ordering::Acquire);
        if over() || self.requests.send(r).is_err() {
            return Err(ended());
        }
        let wait = self.mailbox_timeout + Duration::from_secs(1);
        let deadline = monotonic_ns() + wait.as_nanos() as u64;
        loop {
            match rx.recv_timeout(Duration::from_millis(50)) {
                Ok(r) => return r,
                Err(mpsc::RecvTimeoutError::Disconnected) => return Err(ended()),
                Err(mpsc::RecvTimeoutError::Timeout) if over() => return Err(ended()),
                Err(mpsc::RecvTimeoutError::Timeout) if monotonic_ns() > deadline => {
                    return Err(MasterError::new(
                        None,
                        what,
                        ErrorKind::Timeout,
                        format!(
                            "no answer within {} ms (the cycle is not running: starting, \
                             re-starting or stopping)",
                            wait.as_millis()
                        ),
                    ));
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
        }
    }
}

/// What one run on a bus (start-up, cycle, shutdown) came to.
enum RunEnd {
    /// The session is over: stopped on request, OP not reached at the first start, the link
    /// failed.
    Over,
    /// The cycle ended by itself: the segment was lost or a drive fell out of OP.
    Interrupted,
    /// A re-start was requested while the cycle ran.
    Restart,
    /// Start-up failed (at the first start: `start` returns the error; later: a failed
    /// re-start attempt).
    StartFailed(MasterError),
}

/// What lives across the runs of one session (the supervisory ends stay with the [`Master`]).
struct AcrossRuns {
    cycle_io: cycle::CycleIo,
    events: rtrb::Consumer<Event>,
    resolver: Resolver,
    summaries: Vec<DriveSummary>,
    io: Vec<IoSummary>,
    last_cycle: Option<CycleReport>,
    emergencies: Vec<EmergencyRecord>,
    restarts: u32,
    shutdown_ok: bool,
    startup: startup::StartupTimes,
}

impl AcrossRuns {
    /// What the first start of a session leaves for the runs after it: the summaries, the
    /// resolver, the channels (sized for exactly these drives and I/O devices: every telemetry
    /// buffer holds one entry each; they live as long as the session, across re-starts). The
    /// supervisory ends go to [`Master::start`] through `started_tx`.
    fn first(
        started: &startup::Started,
        started_tx: &mpsc::Sender<Result<Started, MasterError>>,
    ) -> Self {
        let summaries: Vec<DriveSummary> = started
            .drives
            .iter()
            .map(|d| DriveSummary {
                drive: d.drive.clone(),
                info: d.info.clone(),
                profile: d.profile.name,
                image_bytes: (d.layout.bytes(Direction::Rx), d.layout.bytes(Direction::Tx)),
                pdos: (
                    d.mapping.rx.iter().map(|p| p.index).collect(),
                    d.mapping.tx.iter().map(|p| p.index).collect(),
                ),
                mode: d.setup.mode.name(),
                units: d.profile.units,
                user_units: d.setup.units.clone(),
            })
            .collect();
        let io: Vec<IoSummary> = started
            .io
            .iter()
            .map(|o| IoSummary {
                device: o.info.drive_ref(),
                info: o.info.clone(),
                image_bytes: (o.outputs, o.inputs),
                why: o.why.clone(),
            })
            .collect();
        let resolver = Resolver {
            drives: started
                .drives
                .iter()
                .map(|d| (d.drive.clone(), d.profile.caps.error_table))
                .collect(),
            units: started
                .drives
                .iter()
                .map(|d| d.setup.units.clone())
                .collect(),
            devices: started
                .devices
                .iter()
                .map(|d| {
                    started
                        .drives
                        .iter()
                        .find(|x| x.info.position == d.position)
                        .map_or_else(|| d.drive_ref(), |x| x.drive.clone())
                })
                .collect(),
        };
        // The channels, sized for exactly these drives and I/O devices (every telemetry buffer
        // holds one entry each); they live as long as the session, across re-starts.
        let (cycle_io, sup) = cycle::channels(started.drives.len(), started.io.len());
        let _ = started_tx.send(Ok(Started {
            drives: summaries.clone(),
            io: io.clone(),
            commands: sup.commands,
            telemetry: sup.telemetry,
        }));
        AcrossRuns {
            cycle_io,
            events: sup.events,
            resolver,
            summaries,
            io,
            last_cycle: None,
            emergencies: Vec::new(),
            restarts: 0,
            shutdown_ok: false,
            startup: started.times,
        }
    }

    /// Publish a snapshot while no cycle runs: the phase and the re-start count. No drive is
    /// in SAFE-OP or OP then (taken to INIT, or out of reach), so no CiA 402 state is known:
    /// every axis shows `state: None`.
    fn publish_idle(&mut self, phase: Phase) {
        let n = self.summaries.len();
        let lost = self.last_cycle.as_ref().map_or(0, |r| r.lost);
        let t = self.cycle_io.telemetry.input_buffer_mut();
        t.cycle = CycleTelemetry {
            phase,
            restarts: self.restarts,
            lost,
            ..CycleTelemetry::default()
        };
        t.axes.clear();
        t.axes.resize(n, AxisTelemetry::default());
        for slot in t.io.iter_mut() {
            slot.al_state = 0;
            slot.input_len = 0;
        }
        self.cycle_io.telemetry.publish();
    }
}

fn push_history(shared: &Shared, e: HistoryEntry) {
    if let Ok(mut h) = shared.history.lock() {
        h.push(e);
    }
}

/// Record what the session itself notes (no cycle, no drive).
fn note(shared: &Shared, event: HistoryEvent) {
    push_history(
        shared,
        HistoryEntry::new(monotonic_ns(), None, None, event, Resolved::default()),
    );
}

/// The session: runs (start-up, cycle, shutdown) on fresh buses over the same link, re-started
/// as the [`RestartPolicy`] says. Runs on the session thread.
fn session<L: FrameLink + Send>(
    link: L,
    cfg: &MasterConfig,
    shared: &Shared,
    started_tx: &mpsc::Sender<Result<Started, MasterError>>,
) -> (Option<SessionReport>, L) {
    let mut link = link;
    let mut persist: Option<AcrossRuns> = None;
    let mut failures: u32 = 0;
    let mut restarting = false;
    loop {
        let r = with_bus(link, cfg.bus, |bus| {
            run(bus, cfg, shared, started_tx, &mut persist, restarting)
        });
        let end = match r {
            Ok((end, l)) => {
                link = l;
                end
            }
            Err((e, l)) => {
                link = l;
                RunEnd::StartFailed(MasterError::new(None, "opening the bus", ErrorKind::Bus, e))
            }
        };
        let Some(p) = persist.as_mut() else {
            // The first start failed: `start` returns the error.
            if let RunEnd::StartFailed(e) = end {
                let _ = started_tx.send(Err(e));
            }
            return (None, link);
        };
        match end {
            RunEnd::Over => break,
            RunEnd::Restart => {
                failures = 0;
                restarting = true;
                note(shared, HistoryEvent::Restart(RestartNote::Requested));
                continue;
            }
            RunEnd::Interrupted => {
                failures = 0;
                match cfg.restart {
                    RestartPolicy::Never => break,
                    RestartPolicy::OnRequest => note(
                        shared,
                        HistoryEvent::Restart(RestartNote::WaitingForRequest),
                    ),
                    RestartPolicy::Auto { retry_every, .. } => note(
                        shared,
                        HistoryEvent::Restart(RestartNote::Automatic {
                            retry_every_ms: u64::try_from(retry_every.as_millis())
                                .unwrap_or(u64::MAX),
                        }),
                    ),
                }
            }
            RunEnd::StartFailed(e) => {
                failures += 1;
                note(
                    shared,
                    HistoryEvent::Restart(RestartNote::AttemptFailed {
                        attempt: failures,
                        error: e.to_string(),
                    }),
                );
            }
        }
        let auto = match cfg.restart {
            RestartPolicy::Auto {
                retry_every,
                max_attempts,
            } => {
                if max_attempts.is_some_and(|m| failures >= m) {
                    if max_attempts == Some(failures) {
                        note(
                            shared,
                            HistoryEvent::Restart(RestartNote::GivingUp { failures }),
                        );
                    }
                    None
                } else {
                    Some(retry_every)
                }
            }
            _ => None,
        };
        if wait_for_restart(p, auto, shared) {
            restarting = true;
        } else {
            break;
        }
    }
    let Some(mut p) = persist else {
        return (None, link);
    };
    p.publish_idle(Phase::Ended);
    let (history, history_discarded, history_totals) = shared
        .history
        .lock()
        .map(|h| (h.entries(), h.discarded(), h.totals().clone()))
        .unwrap_or_default();
    (
        Some(SessionReport {
            drives: p.summaries,
            io: p.io,
            cycle: p.last_cycle,
            history,
            history_discarded,
            history_totals,
            emergencies: p.emergencies,
            shutdown_ok: p.shutdown_ok,
            restarts: p.restarts,
            startup: Some(p.startup),
        }),
        link,
    )
}

/// Between runs: wait for [`Command::Restart`] (true) or [`Command::Stop`] (false), or until
/// `auto` has passed (true). Other commands are refused in the history: no cycle runs.
fn wait_for_restart(p: &mut AcrossRuns, auto: Option<Duration>, shared: &Shared) -> bool {
    p.publish_idle(if auto.is_some() {
        Phase::Restarting
    } else {
        Phase::WaitingForRestart
    });
    let deadline = auto.map(|d| monotonic_ns() + d.as_nanos() as u64);
    loop {
        while let Ok(c) = p.cycle_io.commands.pop() {
            match c {
                Command::Restart => return true,
                Command::Stop(_) => return false,
                other => note(
                    shared,
                    HistoryEvent::NoCycle {
                        command: other.to_string(),
                    },
                ),
            }
        }
        if deadline.is_some_and(|d| monotonic_ns() >= d) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Whether the segment holds the drives the session started with (a re-start must find the
/// same drives at the same positions).
/// On a re-start the same devices must be drives and I/O devices as before (the channels, the
/// telemetry and the summaries are sized and named for them).
fn same_roles(
    summaries: &[DriveSummary],
    devices: &[DeviceInfo],
    plan: &[startup::Role],
) -> Result<(), MasterError> {
    for (d, r) in devices.iter().zip(plan) {
        let was_drive = summaries.iter().any(|s| s.info.position == d.position);
        let is_drive = r.drive().is_some();
        if was_drive != is_drive {
            return Err(MasterError::new(
                Some(&d.drive_ref()),
                "re-start",
                ErrorKind::Config,
                format!(
                    "it was {} and would now be {}: start the master afresh",
                    if was_drive {
                        "a drive"
                    } else {
                        "an I/O device"
                    },
                    if is_drive { "a drive" } else { "an I/O device" }
                ),
            ));
        }
    }
    Ok(())
}

/// A device as it was seen before a re-start.
struct Seen<'a> {
    drive: &'a DriveRef,
    info: &'a DeviceInfo,
}

fn same_drives(
    summaries: &[DriveSummary],
    io: &[IoSummary],
    devices: &[DeviceInfo],
) -> Result<(), MasterError> {
    // Fewer devices: the first missing one is named below.
    if devices.len() > summaries.len() + io.len() {
        return Err(MasterError::new(
            None,
            "re-start",
            ErrorKind::Config,
            format!(
                "the segment has {} device(s) now, it had {}: start the master afresh",
                devices.len(),
                summaries.len() + io.len()
            ),
        ));
    }
    let before = summaries
        .iter()
        .map(|s| (&s.drive, &s.info))
        .chain(io.iter().map(|s| (&s.device, &s.info)));
    for (drive, info) in before {
        let s = Seen { drive, info };
        let found = devices.iter().find(|d| d.position == s.info.position);
        match found {
            Some(d)
                if d.vendor_id == s.info.vendor_id
                    && d.product_code == s.info.product_code
                    && d.serial == s.info.serial => {}
            Some(d) => {
                return Err(MasterError::new(
                    Some(s.drive),
                    "re-start",
                    ErrorKind::Config,
                    format!(
                        "another device is at its position now: vendor 0x{:08X} product \
                         0x{:08X} serial {} (it was vendor 0x{:08X} product 0x{:08X} serial {})",
                        d.vendor_id,
                        d.product_code,
                        d.serial,
                        s.info.vendor_id,
                        s.info.product_code,
                        s.info.serial
                    ),
                ));
            }
            None => {
                return Err(MasterError::new(
                    Some(s.drive),
                    "re-start",
                    ErrorKind::Bus,
                    format!(
                        "the drive does not answer (the segment has {} device(s))",
                        devices.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Put the emergencies logged since `seen` into the history, each described with its drive's
/// alarm table (by segment position; an I/O device has none).
fn record_emergencies(log: &EmergencyLog, resolver: &Resolver, shared: &Shared, seen: &mut usize) {
    let Ok(l) = log.lock() else {
        return;
    };
    for r in l.iter().skip(*seen) {
        let table = resolver
            .drives
            .iter()
            .find(|(d, _)| d.position == r.position)
            .map_or(&[][..], |(_, t)| *t);
        let resolved = Resolved {
            fault: Some(ErrorCode(r.emergency.error_code).describe(table)),
            ..Resolved::default()
        };
        let event = HistoryEvent::Emergency {
            error_code: r.emergency.error_code,
            error_register: r.emergency.error_register,
        };
        push_history(
            shared,
            HistoryEntry::new(
                r.time_ns,
                None,
                resolver.device(r.position),
                event,
                resolved,
            ),
        );
    }
    *seen = l.len();
}

/// Every device to INIT after a run (the cycle has disabled the axes), unless the segment is
/// gone; whether every device took the request.
fn shutdown_to_init<L: FrameLink>(
    bus: &mut super::bus::Bus<'_, L>,
    devices: &[DeviceInfo],
    resolver: &Resolver,
    end: Option<CycleEnd>,
) -> bool {
    if matches!(end, Some(CycleEnd::SegmentLost | CycleEnd::LinkFailed)) {
        return false;
    }
    let mut ok = true;
    for d in devices {
        let addr = d.address;
        let name = resolver.device_name(d.position);
        let r = bus.block_on(
            &|| format!("{name}: requesting INIT"),
            Duration::from_secs(2),
            |md| async move {
                EcCommand::fpwr(addr, register::AL_CONTROL)
                    .send(md, 0x0011u16)
                    .await
            },
        );
        if !matches!(r, Ok(Ok(()))) {
            ok = false;
        }
    }
    ok
}

/// What follows a run that ended with `end`.
fn run_end(end: Option<CycleEnd>, restarting: bool, resolver: &Resolver) -> RunEnd {
    match end {
        None | Some(CycleEnd::Stopped | CycleEnd::LinkFailed) => RunEnd::Over,
        Some(CycleEnd::OpFailed { device, al_state }) if restarting => {
            RunEnd::StartFailed(MasterError::new(
                resolver.device(device).as_ref(),
                "re-start",
                ErrorKind::Timeout,
                format!(
                    "did not reach OP (AL status {})",
                    cycle::al_state_name(al_state)
                ),
            ))
        }
        Some(CycleEnd::OpFailed { .. }) => RunEnd::Over,
        Some(CycleEnd::SegmentLost | CycleEnd::DriveLeftOp { .. }) => RunEnd::Interrupted,
        Some(CycleEnd::Restart) => RunEnd::Restart,
    }
}

/// Start-up to SAFE-OP; on a re-start, the segment must show the same drives in the same
/// roles as at the first start.
fn start_up<L: FrameLink>(
    bus: &mut super::bus::Bus<'_, L>,
    cfg: &MasterConfig,
    persist: Option<&AcrossRuns>,
) -> Result<startup::Started, MasterError> {
    let (group, devices) = startup::discover(bus)?;
    if let Some(p) = persist {
        same_drives(&p.summaries, &p.io, &devices)?;
    }
    let plan = startup::assign_roles(&devices, &cfg.startup)?;
    if let Some(p) = persist {
        same_roles(&p.summaries, &devices, &plan)?;
    }
    startup::configure(bus, group, devices, plan, &cfg.startup)
}

/// Start-up's warnings into the history.
fn note_warnings(shared: &Shared, warnings: &[(DriveRef, String)]) {
    for (drive, w) in warnings {
        let event = HistoryEvent::Warning(w.clone());
        push_history(
            shared,
            HistoryEntry::new(
                monotonic_ns(),
                None,
                Some(drive.clone()),
                event,
                Resolved::default(),
            ),
        );
    }
}

/// One run: start-up, the cycle with its supervision, shutdown.
fn run<L: FrameLink + Send>(
    bus: &mut super::bus::Bus<'_, L>,
    cfg: &MasterConfig,
    shared: &Shared,
    started_tx: &mpsc::Sender<Result<Started, MasterError>>,
    persist: &mut Option<AcrossRuns>,
    restarting: bool,
) -> RunEnd {
    let started = match start_up(bus, cfg, persist.as_ref()) {
        Ok(s) => s,
        Err(e) => return RunEnd::StartFailed(e),
    };
    note_warnings(shared, &started.warnings);
    if persist.is_none() {
        *persist = Some(AcrossRuns::first(&started, started_tx));
    } else if restarting {
        note(
            shared,
            HistoryEvent::Restart(RestartNote::SameDrives {
                drives: started.drives.len(),
            }),
        );
    }
    let Some(p) = persist.as_mut() else {
        return RunEnd::Over;
    };
    let AcrossRuns {
        cycle_io,
        events,
        resolver,
        last_cycle,
        emergencies,
        restarts,
        shutdown_ok: shutdown_ok_out,
        startup: times,
        ..
    } = p;
    cycle_io.restarts = *restarts;
    cycle_io.restarting = restarting;

    let log = bus.emergencies().clone();
    let mut seen_emcy = 0usize;
    let drain_emcy = |seen: &mut usize| record_emergencies(&log, resolver, shared, seen);

    let (rt_tx, rt_rx) = mpsc::channel();
    cycle_io.rt_report = Some(rt_tx);
    let hooks = cfg.hooks.clone();
    let drives = &started.drives;
    let others = &started.io;
    let group = &started.group;
    let mut mailboxes = mailboxes_of(&started, resolver, log.clone(), cfg.bus.mailbox_timeout);
    let mail = cycle_io.mail.clone();
    let (md, pump) = bus.split();
    let report = std::thread::scope(|s| {
        let h = std::thread::Builder::new()
            .name("ecdrive-cycle".into())
            .stack_size(8 * 1024 * 1024)
            .spawn_scoped(s, || {
                let hooks_ref = hooks.as_deref().map(|h| h as &dyn CycleHooks);
                let (mut app, mut record) = lock_app(cfg);
                let (app, record) = (app.as_deref_mut(), record.as_deref_mut());
                let c = &cfg.cycle;
                cycle::run(
                    md, pump, group, drives, others, c, cycle_io, hooks_ref, app, record,
                )
            });
        let h = match h {
            Ok(h) => h,
            Err(e) => {
                note(shared, HistoryEvent::CycleThreadFailed(e.to_string()));
                return None;
            }
        };
        let mut next_poll = monotonic_ns();
        if let Ok(rt) = rt_rx.recv_timeout(Duration::from_secs(5)) {
            for w in &rt.warnings {
                tracing::warn!("{w}");
                note(shared, HistoryEvent::Warning(w.clone()));
            }
            if let Ok(mut r) = shared.rt.lock() {
                *r = Some(rt);
            }
        }
        let before = *restarts;
        let mut drain_events = || {
            let mut n = 0usize;
            while let Ok(e) = events.pop() {
                n += 1;
                push_history(shared, resolver.entry(&e));
                if matches!(e.kind, EventKind::AllOp) {
                    // When the cycle saw it, not when this thread got round to it.
                    times.reached_op(e.time_ns);
                    if restarting {
                        let restart = before + 1;
                        note(
                            shared,
                            HistoryEvent::Restart(RestartNote::BackInOp { restart }),
                        );
                    }
                }
            }
            n
        };
        let mut idle = SESSION_POLL_MIN;
        while !h.is_finished() {
            idle = next_idle(idle, drain_events(), cfg.emergency_poll);
            if let Some(every) = cfg.emergency_poll
                && monotonic_ns() >= next_poll
            {
                next_poll = monotonic_ns() + every.as_nanos() as u64;
                // Only when a mailbox may hold something: the cycle's own frames read every
                // device's SM1 status (issue 40: a poll of every drive costs the cycle
                // frames and the session wake-ups, every period).
                if mail.may_hold_mail() {
                    mailboxes.poll(md, &|| h.is_finished());
                    drain_emcy(&mut seen_emcy);
                }
            }
            // Sleeps until the next look, or until the application asks for an SDO.
            let pause = session_pause(idle, cfg.emergency_poll, next_poll);
            if let Some(r) = next_request(shared, pause) {
                mailboxes.serve(md, r, &|| h.is_finished());
                drain_emcy(&mut seen_emcy);
            }
        }
        drain_events();
        h.join().ok()
    });
    *restarts = cycle_io.restarts;

    let end = report.as_ref().map(|r| r.end);
    let shutdown_ok = shutdown_to_init(bus, &started.devices, resolver, end);
    drain_emcy(&mut seen_emcy);
    if let Ok(l) = log.lock() {
        emergencies.extend(l.iter().cloned());
    }
    *shutdown_ok_out = shutdown_ok;
    *last_cycle = report;
    run_end(end, restarting, resolver)
}

/// The session thread's shortest and longest sleep between looks at the cycle's events.
const SESSION_POLL_MIN: Duration = Duration::from_millis(2);
const SESSION_POLL_MAX: Duration = Duration::from_millis(16);

/// The session thread looks every 2 ms while events come and backs off to 16 ms while none do,
/// or to the emergency poll's period when that is longer (it wakes for the poll anyway, and
/// each wake-up costs a quiet cycle CPU time: issue 40): a quiet cycle costs it few wake-ups
/// (the event ring holds 4096).
fn next_idle(idle: Duration, events: usize, poll: Option<Duration>) -> Duration {
    if events > 0 {
        SESSION_POLL_MIN
    } else {
        (idle * 2).min(poll.map_or(SESSION_POLL_MAX, |p| p.max(SESSION_POLL_MAX)))
    }
}

/// The application's next SDO request, waiting for one at most `pause`.
fn next_request(shared: &Shared, pause: Duration) -> Option<MailboxRequest> {
    match shared.requests.lock() {
        Ok(rx) => rx.recv_timeout(pause).ok(),
        Err(_) => {
            std::thread::sleep(pause);
            None
        }
    }
}

/// Every device with a CoE mailbox, by position: the drives are polled for emergencies, the
/// others only answer the application's requests.
fn mailboxes_of(
    started: &startup::Started,
    resolver: &Resolver,
    log: EmergencyLog,
    timeout: Duration,
) -> Mailboxes {
    let devices = started
        .devices
        .iter()
        .filter(|d| d.coe)
        .map(|d| {
            let drive = started
                .drives
                .iter()
                .find(|s| s.info.position == d.position);
            MailboxDevice {
                position: d.position,
                address: d.address,
                drive: drive.map_or_else(
                    || DriveRef {
                        position: d.position,
                        name: resolver.device_name(d.position),
                    },
                    |s| s.drive.clone(),
                ),
                polled: drive.is_some(),
                complete_access: drive.is_some_and(|s| s.profile.complete_access),
            }
        })
        .collect();
    Mailboxes::new(devices, log, timeout)
}

/// How long the session thread sleeps: `idle`, but not past the next mailbox poll.
fn session_pause(idle: Duration, poll: Option<Duration>, next_poll_ns: u64) -> Duration {
    let to_poll = poll.map_or(idle, |_| {
        Duration::from_nanos(next_poll_ns.saturating_sub(monotonic_ns()))
    });
    idle.min(to_poll).max(SESSION_POLL_MIN)
}

/// ": LRW 2 of 2 (logical 0x000005BA, 118 bytes, devices 38–47) 18, expected 20" for a
/// working-counter event: which datagram of the reply was wrong and whom it covers.
/// What a working-counter event says: the count, the datagram, and what follows.
/// What a timed-out wait reports: the cycle's lost frames and every axis's state, with its
/// error code when it has one, so a wait that failed because a drive faulted says so.
fn where_things_stand(t: &Telemetry) -> String {
    let mut out = format!("cycle {}, {} lost", t.cycle.cycle, t.cycle.lost);
    for (i, a) in t.axes.iter().enumerate() {
        let state = a.state.map_or("no state", |s| s.name());
        out.push_str(&format!("; axis {i}: {state}"));
        if a.error_code != 0 {
            out.push_str(&format!(", error code 0x{:04X}", a.error_code));
        }
    }
    out
}
