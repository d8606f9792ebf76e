//! `Master`, `Drive` and `Device`: a running master, EtherCAT or CANopen, as Python objects.
//!
//! The Rust master runs the cycle in its own thread ([`ecdrive::Master`], or the CANopen
//! master's `CycleThread`, behind [`Backend`]); these objects only send it commands, read its
//! telemetry and history, and ask the EtherCAT session thread for SDOs. Every call
//! that waits releases the GIL, and holds the master's lock only for a look at a time, so other
//! Python threads (and other calls on the same master) go on meanwhile.

use crate::backend::{Backend, EtherCat};
use crate::devices::{Device, FoundDrive};
use crate::errors::{Class, Failure};
use crate::record::Recorder;
use crate::values;
use ecdrive::cia402::{self, OperationMode, State};
use ecdrive::master::bus::run_session;
use ecdrive::master::cycle::audit::SteadyAudit as Audit;
use ecdrive::master::session::IoSummary;
use ecdrive::master::{DriveSummary, cycle::al_state_name};
use ecdrive::od::{DataType, Dictionary, ObjectAddress};
use ecdrive::{
    Axes, Command, DriveRef, EventKind, HistoryEntry, HistoryEvent, MasterConfig, RunMode,
    StopKind, Telemetry,
};
use ecdrive_cli::app::config::canopen::CanRunConfig;
use ecdrive_cli::app::config::{self, Config};
use ecdrive_cli::app::ethercat::tools::{self, SimSettings, Target, ToolLink};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

type EcMaster = ecdrive::Master<ToolLink>;

/// Which master, configured how.
enum Bus {
    /// EtherCAT: the master's configuration (start-up, cycle, drives).
    EtherCat(Box<MasterConfig>),
    /// CANopen: the run file's drives, cycle and bus (boxed: the two differ in size).
    CanOpen(Box<CanRunConfig>),
}

/// Where the segment is, and how the master runs on it.
struct Setup {
    target: String,
    bus: Bus,
    op_timeout: Duration,
    record: bool,
    audit: bool,
}

impl Setup {
    fn cycle(&self) -> Duration {
        match &self.bus {
            Bus::EtherCat(c) => c.cycle.cycle,
            Bus::CanOpen(c) => c.cycle,
        }
    }
}

/// A master run: the master and its recording.
struct Running {
    bus: Box<dyn Backend>,
    recorder: Option<Recorder>,
    audit: Option<Arc<Audit>>,
}

enum Session {
    /// No cycle: the EtherCAT link, on which the commissioning reads run (a CANopen master
    /// opens its bus when it starts).
    Idle(Option<ToolLink>),
    /// The cycle runs.
    Running(Box<Running>),
    /// Closed (or the link was lost with a failed start).
    Closed,
}

/// The drives and I/O devices as the last start found them.
#[derive(Default, Clone)]
struct Found {
    drives: Vec<FoundDrive>,
    io: Vec<Device>,
}

pub(crate) struct Inner {
    setup: Setup,
    session: Mutex<Session>,
    found: Mutex<Found>,
    /// The last run's end, as `stop()` returned it.
    report: Mutex<Option<serde_json::Value>>,
}

fn locked<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn not_running(what: &str) -> Failure {
    Failure::new(
        Class::Bus,
        None,
        what,
        "the master's cycle does not run (start() it; it ends with stop(), close(), a fault \
         that took a drive out of OP, or a lost segment)",
    )
}

impl Inner {
    /// `f` on the running master, under the lock (a look, not a wait).
    fn running<R>(
        &self,
        what: &str,
        f: impl FnOnce(&mut Running) -> Result<R, Failure>,
    ) -> Result<R, Failure> {
        match &mut *locked(&self.session) {
            Session::Running(r) => f(r),
            _ => Err(not_running(what)),
        }
    }

    /// Send `c`; the telemetry's cycle and the history's next sequence number as of then.
    fn command(&self, what: &str, c: Command) -> Result<(u64, u64), Failure> {
        self.running(what, |r| {
            let seq = r.bus.history_since(u64::MAX).next;
            let cycle = r.bus.telemetry().cycle.cycle;
            if !r.bus.is_running() {
                return Err(not_running(what));
            }
            r.bus.command(c)?;
            Ok((cycle, seq))
        })
    }

    /// Wait (the caller has released the GIL) until `until` says so for axis `axis`,
    /// watching the history from `from.1` for the command's refusal, a fault, a following
    /// error or the cycle's end. A telemetry condition counts from three cycles after `from.0`
    /// on (the command has been taken by then).
    fn wait(
        &self,
        what: &str,
        drive: &DriveRef,
        axis: usize,
        from: (u64, u64),
        timeout: Duration,
        until: Until<'_>,
    ) -> Result<(), Failure> {
        let deadline = Instant::now() + timeout;
        let mut seq = from.1;
        let mut seen = false;
        // A failure that stops the axes is raised once they are stopped and disabled (the
        // cycle ends after that), within the stop's own time and a margin.
        let mut failed: Option<(Failure, Instant)> = None;
        loop {
            let outcome = self.running(what, |r| {
                let slice = r.bus.history_since(seq);
                seq = slice.next;
                for e in &slice.entries {
                    if failed.is_none()
                        && let Some(f) = stops_the_wait(e, axis, drive, what)
                    {
                        let f = another_drives_fault(&mut *r.bus, e, drive, what).unwrap_or(f);
                        failed = Some((f, Instant::now() + STOP_MARGIN));
                    }
                    if let (Until::Event(f), HistoryEvent::Cycle(k)) = (&until, &e.event) {
                        seen |= f(k);
                    }
                }
                let t = r.bus.telemetry();
                let all_off = t
                    .axes
                    .iter()
                    .all(|a| a.state != Some(State::OperationEnabled));
                if let Some((f, by)) = &failed {
                    if !r.bus.is_running() || all_off || Instant::now() > *by {
                        return Err(f.clone());
                    }
                    return Ok(false);
                }
                if seen {
                    return Ok(true);
                }
                if !r.bus.is_running() {
                    return Err(Failure::new(
                        Class::Bus,
                        Some(drive),
                        what,
                        "the cycle ended",
                    ));
                }
                let t = r.bus.telemetry();
                if let Until::Telemetry(done) = &until
                    && t.cycle.cycle >= from.0 + 3
                    && done(t)
                {
                    return Ok(true);
                }
                if Instant::now() > deadline {
                    return Err(timed_out(what, drive, t.axes.get(axis), timeout));
                }
                Ok(false)
            })?;
            if outcome {
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Start the master on the idle link and wait for OP.
    fn start(&self) -> Result<(), Failure> {
        let mut s = locked(&self.session);
        let link = match std::mem::replace(&mut *s, Session::Closed) {
            Session::Idle(l) => l,
            Session::Running(r) if r.bus.is_running() => {
                *s = Session::Running(r);
                return Ok(());
            }
            // Ended by itself (a drive left OP, the segment was lost): its link, afresh.
            Session::Running(r) => r.bus.stop(StopKind::QuickStop).1,
            Session::Closed => {
                return Err(Failure::new(
                    Class::Bus,
                    None,
                    "starting the master",
                    "the master is closed",
                ));
            }
        };
        match &self.setup.bus {
            Bus::EtherCat(cfg) => {
                let Some(link) = link else {
                    return Err(Failure::new(
                        Class::Bus,
                        None,
                        "starting the master",
                        "the link is gone",
                    ));
                };
                self.start_ethercat(s, (**cfg).clone(), link)
            }
            Bus::CanOpen(cfg) => {
                let (mut bus, (drives, io)) = crate::canopen::start(cfg)?;
                *locked(&self.found) = Found { drives, io };
                // The drives are Operational; their telemetry means something once the cycle
                // has had their first feedback.
                let deadline = Instant::now() + self.setup.op_timeout;
                while bus.is_running()
                    && bus.telemetry().cycle.cycle < 3
                    && Instant::now() < deadline
                {
                    std::thread::sleep(Duration::from_millis(1));
                }
                *s = Session::Running(Box::new(Running {
                    bus,
                    recorder: None,
                    audit: None,
                }));
                Ok(())
            }
        }
    }

    fn start_ethercat(
        &self,
        mut s: MutexGuard<'_, Session>,
        mut cfg: MasterConfig,
        link: ToolLink,
    ) -> Result<(), Failure> {
        let (tx, recorder) = Recorder::start(self.setup.record).map_err(|e| {
            Failure::new(
                Class::Bus,
                None,
                "starting the recording thread",
                e.to_string(),
            )
        })?;
        cfg.record = Some(tx);
        let audit = self.setup.audit.then(|| Arc::new(crate::audit::hooks()));
        if let Some(a) = &audit {
            cfg.hooks = Some(a.clone());
        }
        let mut m = match EcMaster::start(link, cfg) {
            Ok(m) => m,
            Err(f) => {
                *s = Session::Idle(Some(f.link));
                return Err(f.error.into());
            }
        };
        *locked(&self.found) = found_on_ethercat(m.drives(), m.io());
        recorder.set_velocity_scales(
            m.drives()
                .iter()
                .map(|d| d.units.velocity_position_per_s())
                .collect(),
        );
        let op = m.wait_until("OP", self.setup.op_timeout, |t| t.cycle.all_op);
        *s = Session::Running(Box::new(Running {
            bus: Box::new(EtherCat { m }),
            recorder: Some(recorder),
            audit,
        }));
        drop(s);
        if let Err(e) = op {
            let _ = self.stop(StopKind::QuickStop);
            return Err(e.into());
        }
        Ok(())
    }

    /// Stop the cycle (every axis stopped and disabled, the devices to INIT); the link is kept
    /// for another start or the commissioning reads.
    fn stop(&self, kind: StopKind) -> Result<serde_json::Value, Failure> {
        let mut s = locked(&self.session);
        if !matches!(&*s, Session::Running(_)) {
            return Ok(locked(&self.report)
                .clone()
                .unwrap_or(serde_json::Value::Null));
        }
        let Session::Running(r) = std::mem::replace(&mut *s, Session::Closed) else {
            unreachable!("matched as running above, under the same lock")
        };
        let Running {
            bus,
            recorder,
            audit,
        } = *r;
        let (mut summary, link) = bus.stop(kind);
        *s = match link {
            Some(l) => Session::Idle(Some(l)),
            None if matches!(self.setup.bus, Bus::CanOpen(_)) => Session::Idle(None),
            None => Session::Closed,
        };
        if let Some(o) = summary.as_object_mut() {
            if let Some(r) = recorder {
                o.insert("max_wake_latency_ns".into(), r.max_wake_latency_ns().into());
            }
            if let Some(a) = audit {
                o.insert(
                    "audit".into(),
                    serde_json::to_value(crate::audit::result(&a)).unwrap_or_default(),
                );
            }
        }
        *locked(&self.report) = Some(summary.clone());
        Ok(summary)
    }
}

/// How long a wait that ended in a stop waits for the axes to be disabled: the cycle's stop
/// timeout (3 s) and a margin.
const STOP_MARGIN: Duration = Duration::from_secs(5);

/// What a wait waits for.
enum Until<'a> {
    /// A condition on the telemetry.
    Telemetry(&'a (dyn Fn(&Telemetry) -> bool + Sync)),
    /// An event of the cycle's.
    Event(&'a (dyn Fn(&EventKind) -> bool + Sync)),
}

/// A wait that ran out of time, with where the axis stands.
fn timed_out(
    what: &str,
    drive: &DriveRef,
    a: Option<&ecdrive::AxisTelemetry>,
    timeout: Duration,
) -> Failure {
    Failure::new(
        Class::Refused,
        Some(drive),
        what,
        format!(
            "not done within {:.1} s (state {}, statusword 0x{:04X}, mode display {}, error \
             code 0x{:04X})",
            timeout.as_secs_f64(),
            a.and_then(|a| a.state).map_or("none", State::name),
            a.map_or(0, |a| a.statusword),
            a.map_or(0, |a| a.mode_display),
            a.map_or(0, |a| a.error_code),
        ),
    )
}

/// The history entry that ends a wait on axis `axis`, as the failure to raise.
fn stops_the_wait(e: &HistoryEntry, axis: usize, drive: &DriveRef, what: &str) -> Option<Failure> {
    let HistoryEvent::Cycle(kind) = &e.event else {
        return None;
    };
    let mine = |a: u16| usize::from(a) == axis;
    let class = match *kind {
        EventKind::CommandRefused { axis: a, why } if mine(a) => {
            return Some(Failure::new(Class::Refused, Some(drive), what, why));
        }
        EventKind::Axis {
            axis: a,
            event: cia402::Event::Fault { .. },
        } if mine(a) => Class::Fault,
        EventKind::FollowingError { axis: a, .. } if mine(a) => Class::Fault,
        EventKind::HomingFailed { axis: a, .. } if mine(a) => Class::Refused,
        EventKind::LeftOp { device, .. } if device == drive.position => Class::Bus,
        EventKind::SegmentLost { .. } => Class::Bus,
        EventKind::Stopping { .. } => Class::Bus,
        _ => return None,
    };
    let class = match (class, kind) {
        (
            _,
            EventKind::Stopping {
                reason:
                    ecdrive::StopReason::DriveFault { .. } | ecdrive::StopReason::FollowingError { .. },
            },
        ) => Class::Fault,
        (c, _) => c,
    };
    Some(Failure::new(class, Some(drive), what, e.text()))
}

/// The wait of `drive` ended because another drive faulted (every axis is being stopped):
/// that drive's fault, in the words of its alarm table, with what was waiting.
fn another_drives_fault(
    bus: &mut dyn Backend,
    e: &HistoryEntry,
    drive: &DriveRef,
    what: &str,
) -> Option<Failure> {
    let HistoryEvent::Cycle(EventKind::Stopping {
        reason: ecdrive::StopReason::DriveFault { axis },
    }) = e.event
    else {
        return None;
    };
    let faulted = bus.drive_ref(usize::from(axis))?;
    let said = last_fault(&bus.history_since(0).entries, usize::from(axis)).map(|e| e.text());
    Some(Failure::new(
        Class::Fault,
        Some(&faulted),
        format!("while {drive} was {what}"),
        format!(
            "the drive faulted{}; every axis is stopped and disabled",
            said.map(|s| format!(": {s}")).unwrap_or_default()
        ),
    ))
}

/// The last fault of axis `axis` in `history`.
fn last_fault(history: &[HistoryEntry], axis: usize) -> Option<&HistoryEntry> {
    history.iter().rev().find(|e| {
        matches!(e.event, HistoryEvent::Cycle(EventKind::Axis {
            axis: a,
            event: cia402::Event::Fault { .. },
        }) if usize::from(a) == axis)
    })
}

/// The target (none for a CANopen run: its bus is opened at the start), the master's
/// configuration and the emulated devices' settings.
fn setup_of(
    target: &str,
    cycle_us: Option<u32>,
    sim_loss_detection: bool,
) -> Result<(Option<Target>, Bus, SimSettings), Failure> {
    let cycle = |us: u32| Duration::from_micros(u64::from(us));
    let is_file = target.ends_with(".toml") || std::path::Path::new(target).is_file();
    if !is_file {
        let t: Target = target.parse().map_err(Failure::from)?;
        let sim = SimSettings {
            loss_detection: sim_loss_detection,
            ..SimSettings::default()
        };
        let cfg = MasterConfig::new(cycle(cycle_us.unwrap_or(1000)));
        return Ok((Some(t), Bus::EtherCat(Box::new(cfg)), sim));
    }
    match config::load_any(std::path::Path::new(target)) {
        Ok(Config::EtherCat(c)) => {
            let mut master = c.master;
            if let Some(us) = cycle_us {
                master.startup.cycle = cycle(us);
                master.cycle.cycle = cycle(us);
            }
            Ok((Some(c.target), Bus::EtherCat(Box::new(master)), c.sim))
        }
        Ok(Config::CanOpen(mut c)) => {
            if let Some(us) = cycle_us {
                c.cycle = cycle(us);
            }
            Ok((None, Bus::CanOpen(Box::new(c)), SimSettings::default()))
        }
        Err(e) => Err(Failure::config(format!("reading {target}"), e)),
    }
}

/// `ecdrive.run`: the run file to its end, its JSON summary.
pub fn run_file(
    path: &std::path::Path,
    interface: Option<&str>,
    duration: Option<Duration>,
) -> Result<serde_json::Value, Failure> {
    let json = |what: &str, v: Result<serde_json::Value, serde_json::Error>| {
        v.map_err(|e| Failure::config(format!("converting {what}"), e))
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    match config::load_any(path) {
        Ok(Config::EtherCat(mut c)) => {
            if let Some(i) = interface {
                c.target = i.parse().map_err(Failure::from)?;
            }
            let opts = tools::run::RunOptions {
                duration,
                ..tools::run::RunOptions::default()
            };
            let r = tools::run::run(&c, &opts, &stop, &mut |_| {}).map_err(Failure::from)?;
            json("the run's report", serde_json::to_value(&r))
        }
        Ok(Config::CanOpen(mut c)) => {
            use ecdrive_cli::app::canopen::run::{CanRunOptions, run};
            use ecdrive_cli::app::config::canopen::CanTarget;
            if let Some(i) = interface {
                c.target =
                    if i == "can-sim" {
                        CanTarget::Sim
                    } else {
                        CanTarget::Bus(i.parse().map_err(|e| {
                            Failure::config(format!("reading the interface {i:?}"), e)
                        })?)
                    };
            }
            let opts = CanRunOptions {
                duration,
                record: None,
                candump: None,
            };
            let r = run(&c, &opts, &stop)
                .map_err(|e| Failure::new(e.class(), None, "the CANopen run", e.to_string()))?;
            json("the run's report", serde_json::to_value(&r))
        }
        Err(e) => Err(Failure::config(format!("reading {}", path.display()), e)),
    }
}

/// An EtherCAT master: start-up to OP, the cycle in Rust, the drives as [`Drive`]s.
///
/// `Master(target, cycle_us=1000, *, start=True, record=True, op_timeout=15.0,
/// sim_loss_detection=True, audit=False, priority=None)`.
///
/// - `target`: `"sim:mr-j4-tm,bdhde"` (emulated drives in-process, no root), a network
///   interface (`"eth1"`, raw socket: root or CAP_NET_RAW), or a run file (`.toml`: its
///   target, `[sim]`, drives, mappings, limits and cycle; `cycle_us` overrides its cycle).
/// - `start=False`: the cycle waits for `start()`; meanwhile the commissioning reads
///   (`slaves`, `pdos`, `sdos`, `states`) run on the link.
/// - `record`: keep every cycle's samples for `record()`.
/// - `sim_loss_detection=False`: the emulated drives do not fault when the cycle stalls (as an
///   MR-J4-TM with [Pr. PN06] set so), for a host that cannot keep the cycle.
/// - `audit=True`: count the cycle thread's allocations and syscalls from OP to the stop
///   (the summary `stop()` returns has them).
/// - `priority`: SCHED_FIFO priority of the cycle thread (1–99; needs root or CAP_SYS_NICE,
///   else a warning in the history).
#[pyclass(frozen, subclass, module = "ecdrive._ecdrive")]
pub struct Master {
    inner: Arc<Inner>,
}

#[pymethods]
impl Master {
    #[new]
    #[pyo3(signature = (target, cycle_us=None, *, start=true, record=true, op_timeout=15.0, sim_loss_detection=true, audit=false, priority=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        target: String,
        cycle_us: Option<u32>,
        start: bool,
        record: bool,
        op_timeout: f64,
        sim_loss_detection: bool,
        audit: bool,
        priority: Option<u8>,
    ) -> PyResult<Self> {
        let op_timeout = values::seconds(op_timeout)?;
        let inner = py.detach(move || -> Result<Arc<Inner>, Failure> {
            let (t, mut bus, sim) = setup_of(&target, cycle_us, sim_loss_detection)?;
            if let (Some(p), Bus::EtherCat(cfg)) = (priority, &mut bus) {
                cfg.cycle.rt.priority = Some(p);
            }
            let link = t
                .map(|t| t.open_with(&sim).map_err(Failure::from))
                .transpose()?;
            let inner = Arc::new(Inner {
                setup: Setup {
                    target,
                    bus,
                    op_timeout,
                    record,
                    audit,
                },
                session: Mutex::new(Session::Idle(link)),
                found: Mutex::new(Found::default()),
                report: Mutex::new(None),
            });
            if start {
                inner.start()?;
            }
            Ok(inner)
        })?;
        Ok(Self { inner })
    }

    /// Start the cycle (start-up to OP); nothing if it runs.
    fn start(&self, py: Python<'_>) -> PyResult<()> {
        let inner = self.inner.clone();
        Ok(py.detach(move || inner.start())?)
    }

    /// Stop the cycle: every axis ramped down (or quick stopped with `quick=True`) and
    /// disabled, the devices to INIT. Returns the run's summary (its cycle figures, wake-up
    /// latency, history totals, each drive's largest following error). The master can be
    /// started again.
    #[pyo3(signature = (*, quick=false))]
    fn stop(&self, py: Python<'_>, quick: bool) -> PyResult<Py<PyAny>> {
        let inner = self.inner.clone();
        let kind = if quick {
            StopKind::QuickStop
        } else {
            StopKind::Ramp
        };
        let summary = py.detach(move || inner.stop(kind))?;
        values::json_to_py(py, &summary)
    }

    /// Stop (as `stop()`) and release the link; the master cannot be used afterwards.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        let inner = self.inner.clone();
        py.detach(move || -> Result<(), Failure> {
            inner.stop(StopKind::Ramp)?;
            *locked(&inner.session) = Session::Closed;
            Ok(())
        })?;
        Ok(())
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    /// Whether the cycle runs.
    #[getter]
    fn running(&self) -> bool {
        matches!(&*locked(&self.inner.session), Session::Running(r) if r.bus.is_running())
    }

    /// The target as given.
    #[getter]
    fn target(&self) -> String {
        self.inner.setup.target.clone()
    }

    /// The cycle time, µs.
    #[getter]
    fn cycle_us(&self) -> u64 {
        self.inner.setup.cycle().as_micros() as u64
    }

    /// Every device of the segment as the last start found it, in segment order, with its AL
    /// state now.
    #[getter]
    fn devices(&self) -> Vec<Device> {
        let found = locked(&self.inner.found).clone();
        let can = matches!(self.inner.setup.bus, Bus::CanOpen(_));
        let live = self
            .inner
            .running("reading the states", |r| {
                let running = r.bus.is_running();
                let t = r.bus.telemetry();
                Ok((
                    running,
                    t.axes.iter().map(|a| a.al_state).collect::<Vec<_>>(),
                    t.io.iter()
                        .map(|i| (i.position, i.al_state))
                        .collect::<Vec<_>>(),
                ))
            })
            .ok();
        let mut out: Vec<Device> = Vec::new();
        for (i, d) in found.drives.iter().enumerate() {
            let mut dev = d.device.clone();
            dev.state = match (&live, can) {
                (Some((true, _, _)), true) => "OPERATIONAL".to_string(),
                (_, true) => "STOPPED".to_string(),
                (Some((_, axes, _)), false) => state_name(axes.get(i).copied()),
                (None, false) => "INIT".to_string(),
            };
            out.push(dev);
        }
        for d in &found.io {
            let mut dev = d.clone();
            dev.state = match &live {
                Some((_, _, io)) => {
                    state_name(io.iter().find(|(p, _)| *p == d.position).map(|(_, s)| *s))
                }
                None => "INIT".to_string(),
            };
            out.push(dev);
        }
        out.sort_by_key(|d| d.position);
        out
    }

    /// The drives, in segment order.
    #[getter]
    fn drives(&self) -> Vec<Drive> {
        let found = locked(&self.inner.found).clone();
        (0..found.drives.len())
            .filter_map(|i| self.drive_at(&found, i))
            .collect()
    }

    /// The drive at segment position `which` (an int), or by name (`"BDHDE"`; the first of
    /// that name).
    fn drive(&self, which: &Bound<'_, PyAny>) -> PyResult<Drive> {
        let found = locked(&self.inner.found).clone();
        let axis = if let Ok(p) = which.extract::<u16>() {
            found.drives.iter().position(|d| d.drive.position == p)
        } else if let Ok(n) = which.extract::<String>() {
            found
                .drives
                .iter()
                .position(|d| d.drive.name.eq_ignore_ascii_case(&n))
        } else {
            None
        };
        let names: Vec<String> = found.drives.iter().map(|d| d.drive.to_string()).collect();
        axis.and_then(|a| self.drive_at(&found, a)).ok_or_else(|| {
            Failure::config(
                format!("selecting the drive {which}"),
                format!(
                    "no such drive (the drives: {})",
                    if names.is_empty() {
                        "none; the master has not started".to_string()
                    } else {
                        names.join(", ")
                    }
                ),
            )
            .into()
        })
    }

    /// The cycle's figures now: cycle number, working counter (and the expected one), lost
    /// cycles, overruns, the last cycle's wake-up latency and exchange time, whether every
    /// device is in OP, the session's phase.
    #[getter]
    fn cycle(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let c = self
            .inner
            .running("reading the cycle", |r| Ok(r.bus.telemetry().cycle))?;
        values::to_py(py, "the cycle's figures", &c)
    }

    /// The largest wake-up latency of any cycle since the master started, µs.
    #[getter]
    fn max_wake_latency_us(&self) -> PyResult<f64> {
        let ns = self.inner.running("reading the latency", |r| {
            r.recorder
                .as_ref()
                .map(Recorder::max_wake_latency_ns)
                .ok_or_else(not_recorded)
        })?;
        Ok(ns as f64 / 1000.0)
    }

    /// Every cycle's samples since the last call, one row per axis and cycle with a reply, as
    /// columns: a dict of lists (the package turns them into numpy arrays when numpy is
    /// installed). Columns: cycle, time_ns, axis, wake_latency_ns, exchange_ns, wkc, mode,
    /// statusword, position_demand, position, velocity_demand, velocity, torque_demand,
    /// torque, following_error (positions in counts, velocities in counts/s, torques in the
    /// drive's unit; None where not mapped).
    fn record(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let cols = self.inner.running("reading the recording", |r| {
            r.recorder
                .as_ref()
                .map(Recorder::take)
                .ok_or_else(not_recorded)
        })?;
        cols.into_py(py)
    }

    /// The history (errors, warnings, events), oldest first, each entry as `ecdrive run
    /// --json` gives it (its event and its text). With `since` (a sequence number), only the
    /// entries from it on.
    #[pyo3(signature = (since=0))]
    fn history(&self, py: Python<'_>, since: u64) -> PyResult<Py<PyAny>> {
        let entries = self.inner.running("reading the history", |r| {
            Ok(r.bus.history_since(since).entries)
        })?;
        values::to_py(py, "the history", &entries)
    }

    /// `ecdrive slaves --json`: every device as discovery finds it. Discovers the segment
    /// afresh (every device to INIT, then PRE-OP), so only while the cycle does not run.
    #[pyo3(signature = (*, verbose=false))]
    fn slaves(&self, py: Python<'_>, verbose: bool) -> PyResult<Py<PyAny>> {
        let r = self.tool(py, "slaves", move |b| tools::slaves(b, verbose))?;
        values::to_py(py, "the devices", &r)
    }

    /// `ecdrive pdos -p POSITION --json`: the device's SyncManagers, PDO assignment and
    /// mapping as it reports them (only while the cycle does not run).
    fn pdos(&self, py: Python<'_>, position: u16) -> PyResult<Py<PyAny>> {
        let r = self.tool(py, "pdos", move |b| tools::pdos(b, position))?;
        values::to_py(py, "the PDO configuration", &r)
    }

    /// `ecdrive sdos -p POSITION --json`: the device's object dictionary from its SDO
    /// information, with the values when `values=True` (only while the cycle does not run).
    #[pyo3(signature = (position, *, values=false))]
    fn sdos(&self, py: Python<'_>, position: u16, values: bool) -> PyResult<Py<PyAny>> {
        let r = self.tool(py, "sdos", move |b| {
            tools::sdos(b, position, values, &mut |_, _| {})
        })?;
        values::to_py(py, "the object dictionary", &r)
    }

    /// `ecdrive states -p POSITION STATE --json`: take the device (every device with
    /// `position=None`) to INIT, PREOP, SAFEOP, OP or BOOT (only while the cycle does not
    /// run: `start()` takes the drives to OP and runs them).
    #[pyo3(signature = (position, state))]
    fn states(&self, py: Python<'_>, position: Option<u16>, state: &str) -> PyResult<Py<PyAny>> {
        let target = ecdrive::ec::AlState::parse(state).ok_or_else(|| {
            Failure::config(
                format!("reading the state {state:?}"),
                "use INIT, PREOP, SAFEOP, OP or BOOT",
            )
        })?;
        let mut opts = tools::StatesOptions::new(target);
        opts.position = position;
        opts.cycle = self.inner.setup.cycle();
        let r = self.tool(py, "states", move |b| tools::states_timed(b, &opts))?;
        values::to_py(py, "the state changes", &r)
    }

    fn __repr__(&self) -> String {
        let state = match &*locked(&self.inner.session) {
            Session::Idle(_) => "idle",
            Session::Running(_) => "running",
            Session::Closed => "closed",
        };
        format!(
            "ecdrive.Master({:?}, cycle_us={}) [{state}]",
            self.inner.setup.target,
            self.cycle_us()
        )
    }
}

impl Master {
    fn drive_at(&self, found: &Found, axis: usize) -> Option<Drive> {
        let d = found.drives.get(axis)?;
        Some(Drive {
            inner: self.inner.clone(),
            velocity_scale: d.velocity_scale,
            pending: Mutex::new(None),
            axis,
            drive: d.drive.clone(),
            dictionary: d.dictionary,
        })
    }

    /// A commissioning tool on the idle link, as the CLI runs it.
    fn tool<R: Send + 'static>(
        &self,
        py: Python<'_>,
        what: &str,
        f: impl FnOnce(&mut ecdrive::master::bus::Bus<'_, ToolLink>) -> Result<R, ecdrive::MasterError>
        + Send
        + 'static,
    ) -> PyResult<R> {
        let inner = self.inner.clone();
        let what = what.to_string();
        Ok(py.detach(move || -> Result<R, Failure> {
            let mut s = locked(&inner.session);
            let link = match std::mem::replace(&mut *s, Session::Closed) {
                Session::Idle(Some(l)) => l,
                other if matches!(inner.setup.bus, Bus::CanOpen(_)) => {
                    *s = other;
                    return Err(Failure::new(
                        Class::Input,
                        None,
                        what.as_str(),
                        "the commissioning reads are EtherCAT's: for CANopen drives, `ecdrive \
                         scan`, `upload` and `download` with `--can`",
                    ));
                }
                other => {
                    *s = other;
                    return Err(Failure::new(
                        Class::Bus,
                        None,
                        what.as_str(),
                        "the cycle runs: the commissioning reads discover the segment afresh \
                         (every device to INIT), as the `ecdrive` commands do; stop() first, \
                         or use devices, Drive.sdo_read and Drive.sdo_write while it runs",
                    ));
                }
            };
            // The link comes back whatever the tool's outcome.
            let (r, link) = match run_session(link, tools::tool_bus_options(), f) {
                Ok((r, link)) => (r.map_err(Failure::from), link),
                Err((e, link)) => (
                    Err(Failure::new(
                        Class::Bus,
                        None,
                        "opening the bus",
                        e.to_string(),
                    )),
                    link,
                ),
            };
            *s = Session::Idle(Some(link));
            r
        })?)
    }
}

/// What a CANopen master cannot give.
fn not_recorded() -> Failure {
    Failure::new(
        Class::Input,
        None,
        "reading the recording",
        "a CANopen master's cycles are recorded by `ecdrive run --record` (its run file); \
         record() and max_wake_latency_us are the EtherCAT master's",
    )
}

/// The drives and I/O devices of an EtherCAT start.
fn found_on_ethercat(drives: &[DriveSummary], io: &[IoSummary]) -> Found {
    let device =
        |d: &DriveRef, info: &ecdrive::master::startup::DeviceInfo, profile, drive| Device {
            position: d.position,
            name: d.name.clone(),
            vendor_id: info.vendor_id,
            product_code: info.product_code,
            revision: info.revision,
            serial: info.serial,
            alias: info.alias,
            profile,
            state: String::new(),
            is_drive: drive,
        };
    Found {
        drives: drives
            .iter()
            .map(|d| FoundDrive {
                drive: d.drive.clone(),
                device: device(&d.drive, &d.info, Some(d.profile.to_string()), true),
                dictionary: ecdrive::drives::by_identity(d.info.vendor_id, d.info.product_code)
                    .map(|p| p.dictionary),
                velocity_scale: d.units.velocity_position_per_s(),
            })
            .collect(),
        io: io
            .iter()
            .map(|d| {
                device(
                    &d.device,
                    &d.info,
                    d.info.profile.map(str::to_string),
                    false,
                )
            })
            .collect(),
    }
}

fn state_name(al: Option<u8>) -> String {
    al.map_or_else(|| "unknown".to_string(), al_state_name)
}

/// A move or program under way: what it is, where the cycle and the history stood when it
/// was sent, and whether the drive runs it (pp).
type Pending = (String, (u64, u64), bool);

/// One drive of a running master: its telemetry as properties, its commands as methods that
/// wait for their outcome (releasing the GIL meanwhile).
#[pyclass(frozen, module = "ecdrive._ecdrive")]
pub struct Drive {
    inner: Arc<Inner>,
    /// Counts per second in one unit of the drive's velocity objects (0x606C, 0x60FF).
    velocity_scale: f64,
    /// The move or program started without waiting: what it is, where the cycle and the
    /// history stood when it was sent, and whether the drive runs it (pp).
    pending: Mutex<Option<Pending>>,
    axis: usize,
    drive: DriveRef,
    dictionary: Option<&'static [ecdrive::od::ObjectDesc]>,
}

impl Drive {
    /// A look at this axis's telemetry.
    fn look<R>(&self, f: impl FnOnce(&ecdrive::AxisTelemetry) -> R) -> PyResult<R> {
        Ok(self.inner.running("reading the drive", |r| {
            r.bus
                .telemetry()
                .axes
                .get(self.axis)
                .map(f)
                .ok_or_else(|| not_running("reading the drive"))
        })?)
    }

    /// Send `c`, then wait until `done` (GIL released).
    fn command_and_wait(
        &self,
        py: Python<'_>,
        what: String,
        c: Command,
        timeout: f64,
        done: impl Fn(&ecdrive::AxisTelemetry) -> bool + Send + Sync,
    ) -> PyResult<()> {
        let timeout = values::seconds(timeout)?;
        let axis = self.axis;
        Ok(py.detach(|| -> Result<(), Failure> {
            let from = self
                .inner
                .command(&what, c)
                .map_err(|f| with_drive(f, &self.drive))?;
            let done = |t: &Telemetry| t.axes.get(axis).is_some_and(&done);
            self.inner.wait(
                &what,
                &self.drive,
                axis,
                from,
                timeout,
                Until::Telemetry(&done),
            )
        })?)
    }

    fn data_type(&self, address: ObjectAddress, given: Option<&str>) -> PyResult<Option<DataType>> {
        match given {
            Some(t) => values::data_type(t).map(Some),
            None => Ok(self
                .dictionary
                .and_then(|d| Dictionary::new(d).data_type(address))),
        }
    }

    fn setpoint(&self, what: &str, needs: &[RunMode], v: f64) -> PyResult<()> {
        let mode = self.look(|a| RunMode::of(OperationMode::from_i8(a.mode)))?;
        if !mode.is_some_and(|m| needs.contains(&m)) {
            let names: Vec<&str> = needs.iter().map(|m| m.name()).collect();
            return Err(Failure::new(
                Class::Refused,
                Some(&self.drive),
                what,
                format!(
                    "needs the axis in {} (it runs {}): set `mode` first",
                    names.join(" or "),
                    mode.map_or("no mode ecdrive runs", RunMode::name)
                ),
            )
            .into());
        }
        self.inner
            .command(what, Command::Setpoint(self.axis as u16, v))
            .map_err(|f| with_drive(f, &self.drive))?;
        Ok(())
    }
}

fn with_drive(mut f: Failure, d: &DriveRef) -> Failure {
    if f.drive.is_none() {
        f.drive = Some((d.position, d.name.clone()));
        f.message = format!("{d}: {}", f.message);
    }
    f
}

#[pymethods]
impl Drive {
    /// The drive's position on the segment.
    #[getter]
    fn slave_position(&self) -> u16 {
        self.drive.position
    }

    /// The drive's name (its profile's).
    #[getter]
    fn name(&self) -> String {
        self.drive.name.clone()
    }

    /// Its axis index (0 = the first drive).
    #[getter]
    fn axis(&self) -> usize {
        self.axis
    }

    /// Actual position (0x6064, unwrapped), counts.
    #[getter]
    fn position(&self) -> PyResult<i64> {
        self.look(|a| a.position_actual)
    }

    /// Actual velocity (0x606C), counts/s (from the drive's unit).
    #[getter]
    fn velocity(&self) -> PyResult<f64> {
        self.look(|a| f64::from(a.velocity_actual) * self.velocity_scale)
    }

    /// Actual torque (0x6077), the drive's units (‰ of rated torque for most drives).
    #[getter]
    fn torque(&self) -> PyResult<i16> {
        self.look(|a| a.torque_actual)
    }

    /// Statusword (0x6041) as received.
    #[getter]
    fn statusword(&self) -> PyResult<u16> {
        self.look(|a| a.statusword)
    }

    /// Controlword (0x6040) as sent.
    #[getter]
    fn controlword(&self) -> PyResult<u16> {
        self.look(|a| a.controlword)
    }

    /// CiA 402 state ("Operation enabled", "Switch on disabled", "Fault", …), None when the
    /// statusword decodes to no state (below OP).
    #[getter]
    fn state(&self) -> PyResult<Option<&'static str>> {
        self.look(|a| a.state.map(State::name))
    }

    /// Following error as the master computes it (the demand the drive took − the actual
    /// position), counts.
    #[getter]
    fn following_error(&self) -> PyResult<i64> {
        self.look(|a| a.following_error)
    }

    /// Largest |following error| while energised in csp, counts.
    #[getter]
    fn max_following_error(&self) -> PyResult<i64> {
        self.look(|a| a.max_following_error)
    }

    /// Error code (0x603F), 0 if none or not mapped.
    #[getter]
    fn error_code(&self) -> PyResult<u16> {
        self.look(|a| a.error_code)
    }

    /// Position demand (unwrapped), counts.
    #[getter]
    fn target_position(&self) -> PyResult<i64> {
        self.look(|a| a.position_demand)
    }

    /// Stream a position set-point (csp, ip): the cycle takes it at its next turn.
    #[setter]
    fn set_target_position(&self, v: f64) -> PyResult<()> {
        self.setpoint("setting target_position", &[RunMode::Csp, RunMode::Ip], v)
    }

    /// Velocity demand, counts/s (from the drive's unit).
    #[getter]
    fn target_velocity(&self) -> PyResult<f64> {
        self.look(|a| f64::from(a.velocity_demand) * self.velocity_scale)
    }

    /// Stream a velocity set-point (csv), counts/s: the cycle takes it at its next turn.
    #[setter]
    fn set_target_velocity(&self, v: f64) -> PyResult<()> {
        self.setpoint("setting target_velocity", &[RunMode::Csv], v)
    }

    /// Torque demand, the drive's units.
    #[getter]
    fn target_torque(&self) -> PyResult<i16> {
        self.look(|a| a.torque_demand)
    }

    /// Stream a torque set-point (cst), the drive's units: the cycle takes it at its next
    /// turn.
    #[setter]
    fn set_target_torque(&self, v: f64) -> PyResult<()> {
        self.setpoint("setting target_torque", &[RunMode::Cst], v)
    }

    /// The mode the axis runs ("csp", "csv", "cst", "pp", "pv", "tq", "ip", "hm" while
    /// homing), as sent in 0x6060.
    #[getter]
    fn mode(&self) -> PyResult<String> {
        self.look(|a| {
            let m = OperationMode::from_i8(a.mode);
            match (RunMode::of(m), m) {
                (Some(r), _) => r.name().to_string(),
                (None, OperationMode::NoMode) => "none".to_string(),
                (None, OperationMode::Homing) => "hm".to_string(),
                (None, m) => format!("{m:?}"),
            }
        })
    }

    /// Switch the mode while enabled, without a jump (the new mode starts from the actual
    /// values); waits until the drive shows it (0x6061), at most 2 s.
    #[setter]
    fn set_mode(&self, py: Python<'_>, mode: &str) -> PyResult<()> {
        let m: RunMode = mode
            .parse()
            .map_err(|e| Failure::config(format!("reading the mode {mode:?}"), e))?;
        let code = m.operation_mode().as_i8();
        self.command_and_wait(
            py,
            format!("switching to {}", m.name()),
            Command::Mode(Axes::One(self.axis as u16), m),
            2.0,
            move |a| a.mode == code && (a.mode_display == code || a.mode_display == 0),
        )
    }

    /// Enable (Operation enabled); waits for it. A drive in Fault raises DriveFault with its
    /// fault (reset it first with `fault_reset()`).
    #[pyo3(signature = (timeout=5.0))]
    fn enable(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        if let Some(f) = self.fault_now()? {
            return Err(f.into());
        }
        self.command_and_wait(
            py,
            "enabling".into(),
            Command::Enable(Axes::One(self.axis as u16)),
            timeout,
            |a| a.state == Some(State::OperationEnabled),
        )
    }

    /// Disable (Switch on disabled, without a ramp); waits for it.
    #[pyo3(signature = (timeout=5.0))]
    fn disable(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        self.command_and_wait(
            py,
            "disabling".into(),
            Command::Disable(Axes::One(self.axis as u16)),
            timeout,
            |a| {
                matches!(
                    a.state,
                    Some(State::SwitchOnDisabled | State::ReadyToSwitchOn)
                )
            },
        )
    }

    /// Quick stop (the drive's quick-stop ramp); waits until it is done.
    #[pyo3(signature = (timeout=5.0))]
    fn quick_stop(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        self.command_and_wait(
            py,
            "quick stop".into(),
            Command::QuickStop(Axes::One(self.axis as u16)),
            timeout,
            |a| a.state != Some(State::OperationEnabled),
        )
    }

    /// Reset a fault (a rising edge on controlword bit 7); waits until the drive leaves
    /// Fault.
    #[pyo3(signature = (timeout=5.0))]
    fn fault_reset(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        self.command_and_wait(
            py,
            "resetting the fault".into(),
            Command::FaultReset(Axes::One(self.axis as u16)),
            timeout,
            |a| !matches!(a.state, Some(State::Fault | State::FaultReactionActive)),
        )
    }

    /// Home with `method` (written to 0x6098 first; None: the method the drive holds), in
    /// homing mode, then back to the axis's mode; waits until homed. The axis must be
    /// enabled. A failed homing raises DriveRefused (the axes are stopped).
    #[pyo3(signature = (method=None, timeout=30.0))]
    fn home(&self, py: Python<'_>, method: Option<i8>, timeout: f64) -> PyResult<()> {
        let method = match method {
            Some(m) => {
                let a = ObjectAddress::new(0x6098, 0);
                self.download(py, a, m.to_le_bytes().to_vec())?;
                m
            }
            None => {
                let b = self.upload(py, ObjectAddress::new(0x6098, 0))?;
                b.first().map_or(0, |b| *b as i8)
            }
        };
        self.command_and_wait(
            py,
            format!("homing (method {method})"),
            Command::Home(Axes::One(self.axis as u16), method),
            timeout,
            move |a| matches!(a.task, ecdrive::master::DriveTask::Homed { method: m } if m == method),
        )
    }

    /// Move to `target` (counts). In csp (and any mode but pp) the cycle plans it
    /// (trapezoidal: at most `velocity` counts/s and `acceleration` counts/s², both needed);
    /// the axis switches to csp first. In pp the drive runs it with its own profile values
    /// (0x6081, 0x6083: `sdo_write` them, or the run file's start-up values), handed over with
    /// the new-set-point handshake; `velocity` and `acceleration` are then not given. Waits
    /// until the target is reached, or with `wait=False` returns at once (then `wait()`
    /// waits for it, so several drives move together).
    #[pyo3(signature = (target, velocity=None, acceleration=None, timeout=10.0, *, wait=true))]
    fn move_to(
        &self,
        py: Python<'_>,
        target: f64,
        velocity: Option<f64>,
        acceleration: Option<f64>,
        timeout: f64,
        wait: bool,
    ) -> PyResult<()> {
        let pp = self.look(|a| RunMode::of(OperationMode::from_i8(a.mode)))? == Some(RunMode::Pp);
        let what = format!("moving to {target}");
        let c = match (pp, velocity, acceleration) {
            (true, None, None) => Command::Pp {
                axis: self.axis as u16,
                target,
                relative: false,
                immediate: true,
            },
            (true, _, _) => {
                return Err(Failure::new(
                    Class::Input,
                    Some(&self.drive),
                    what,
                    "the axis runs pp: the drive moves with its own profile velocity and \
                     acceleration (0x6081, 0x6083; sdo_write them, or set them in the run \
                     file): leave velocity and acceleration out",
                )
                .into());
            }
            (false, Some(velocity), Some(acceleration)) => Command::Move {
                axis: self.axis as u16,
                to: target,
                velocity,
                acceleration,
            },
            (false, _, _) => {
                return Err(Failure::new(
                    Class::Input,
                    Some(&self.drive),
                    what,
                    "a csp move needs velocity= and acceleration= (counts/s, counts/s²)",
                )
                .into());
            }
        };
        let from = py.detach(|| {
            self.inner
                .command(&what, c)
                .map_err(|f| with_drive(f, &self.drive))
        })?;
        *locked(&self.pending) = Some((what, from, pp));
        if wait { self.wait(py, timeout) } else { Ok(()) }
    }

    /// Run the axis's program (the run file's `program`) from its first step; waits until it
    /// is done, or with `wait=False` returns at once (then `wait()`).
    #[pyo3(signature = (timeout=60.0, *, wait=true))]
    fn run_program(&self, py: Python<'_>, timeout: f64, wait: bool) -> PyResult<()> {
        let what = "running its program".to_string();
        let c = Command::RunProgram(Axes::One(self.axis as u16));
        let from = py.detach(|| {
            self.inner
                .command(&what, c)
                .map_err(|f| with_drive(f, &self.drive))
        })?;
        *locked(&self.pending) = Some((what, from, false));
        if wait { self.wait(py, timeout) } else { Ok(()) }
    }

    /// Wait until the move `move_to(..., wait=False)` started has arrived (nothing to wait
    /// for when none was started).
    #[pyo3(signature = (timeout=10.0))]
    fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        let timeout = values::seconds(timeout)?;
        let Some((what, from, pp)) = locked(&self.pending).take() else {
            return Ok(());
        };
        let axis = self.axis;
        // Done when the cycle says the program (a csp move runs as a one-step program) is
        // done; a pp move when the drive reports the target reached.
        let done = |k: &EventKind| matches!(*k, EventKind::ProgramDone { axis: a } if usize::from(a) == axis);
        let reached = |t: &Telemetry| {
            t.axes
                .get(axis)
                .is_some_and(|a| a.task == ecdrive::master::DriveTask::TargetReached)
        };
        let until = if pp {
            Until::Telemetry(&reached)
        } else {
            Until::Event(&done)
        };
        Ok(py.detach(|| {
            self.inner
                .wait(&what, &self.drive, axis, from, timeout, until)
        })?)
    }

    /// Move by `distance` (counts) from the position demand, as `move_to`.
    #[pyo3(signature = (distance, velocity=None, acceleration=None, timeout=10.0, *, wait=true))]
    fn move_by(
        &self,
        py: Python<'_>,
        distance: f64,
        velocity: Option<f64>,
        acceleration: Option<f64>,
        timeout: f64,
        wait: bool,
    ) -> PyResult<()> {
        let from = self.look(|a| a.position_demand)? as f64;
        self.move_to(py, from + distance, velocity, acceleration, timeout, wait)
    }

    /// Read object `index`:`sub` over CoE while the cycle runs: an int, float or str as the
    /// drive's dictionary types it (or as `type` says: "u32", "i16", "string", …), bytes when
    /// the type is not known.
    #[pyo3(signature = (index, sub=0, r#type=None))]
    fn sdo_read(
        &self,
        py: Python<'_>,
        index: u16,
        sub: u8,
        r#type: Option<&str>,
    ) -> PyResult<Py<PyAny>> {
        let a = ObjectAddress::new(index, sub);
        let dt = self.data_type(a, r#type)?;
        let bytes = self.upload(py, a)?;
        values::sdo_to_py(py, dt, &bytes)
    }

    /// Write `value` to object `index`:`sub` over CoE while the cycle runs, encoded as the
    /// drive's dictionary types it (or as `type` says); bytes are written as they are.
    #[pyo3(signature = (index, sub, value, r#type=None))]
    fn sdo_write(
        &self,
        py: Python<'_>,
        index: u16,
        sub: u8,
        value: &Bound<'_, PyAny>,
        r#type: Option<&str>,
    ) -> PyResult<()> {
        let a = ObjectAddress::new(index, sub);
        let dt = self.data_type(a, r#type)?;
        let data = values::py_to_sdo(value, dt)?;
        self.download(py, a, data)
    }

    /// Everything the telemetry says of the axis, as a dict.
    fn telemetry(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let t = self.look(|a| *a)?;
        let d = values::to_py(py, "the telemetry", &t)?;
        let state = t.state.map(State::name);
        d.bind(py).cast::<PyDict>()?.set_item("state", state)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Drive(axis={}, slave_position={}, name={:?})",
            self.axis, self.drive.position, self.drive.name
        )
    }
}

impl Drive {
    /// The drive's fault, if it is in Fault: the history's words for it (the drive's own
    /// alarm name), or its error code.
    fn fault_now(&self) -> PyResult<Option<Failure>> {
        let (state, code) = self.look(|a| (a.state, a.error_code))?;
        if !matches!(state, Some(State::Fault | State::FaultReactionActive)) {
            return Ok(None);
        }
        let axis = self.axis;
        let said = self
            .inner
            .running("reading the history", |r| {
                Ok(last_fault(&r.bus.history_since(0).entries, axis).map(HistoryEntry::text))
            })?
            .unwrap_or_else(|| format!("error code 0x{code:04X}"));
        Ok(Some(Failure::new(
            Class::Fault,
            Some(&self.drive),
            "enabling",
            format!("the drive is in Fault: {said}; reset it first (fault_reset())"),
        )))
    }

    fn upload(&self, py: Python<'_>, a: ObjectAddress) -> PyResult<Vec<u8>> {
        let inner = self.inner.clone();
        let position = self.drive.position;
        Ok(py.detach(move || -> Result<Vec<u8>, Failure> {
            let req = inner.running("reading an object", |r| r.bus.sdo_requester())?;
            req.upload(position, a).map_err(Failure::from)
        })?)
    }

    fn download(&self, py: Python<'_>, a: ObjectAddress, data: Vec<u8>) -> PyResult<()> {
        let inner = self.inner.clone();
        let position = self.drive.position;
        Ok(py.detach(move || -> Result<(), Failure> {
            let req = inner.running("writing an object", |r| r.bus.sdo_requester())?;
            req.download(position, a, &data).map_err(Failure::from)
        })?)
    }
}
