//! The two buses behind one `Master`: the EtherCAT master (`ecdrive::Master` on a tool link)
//! and the CANopen master's cycle thread (`canopen::motion::CycleThread`), both stepping their
//! drives with the same motion runtime, so both take the same commands and publish the same
//! telemetry and events. The Python objects see only [`Backend`].

use crate::errors::{Class, Failure};
use ecdrive::canopen::motion::{CycleThread, SessionView};
use ecdrive::canopen::transport::CanTransport;
use ecdrive::cia402::{self, ErrorCode, ErrorEntry};
use ecdrive::master::session::HistorySlice;
use ecdrive::master::{HistoryLog, Resolved, SdoRequester};
use ecdrive::{
    Command, CycleTelemetry, DriveRef, EventKind, HistoryEntry, HistoryEvent, StopKind, Telemetry,
};
use ecdrive_cli::app::ethercat::tools::ToolLink;

/// A running master, whichever the bus.
pub(crate) trait Backend: Send {
    /// Whether its cycle runs.
    fn is_running(&self) -> bool;
    /// Send a command to the cycle.
    fn command(&mut self, c: Command) -> Result<(), Failure>;
    /// The latest telemetry.
    fn telemetry(&mut self) -> &Telemetry;
    /// The history from sequence number `seq` on.
    fn history_since(&mut self, seq: u64) -> HistorySlice;
    /// The drive of axis `axis`.
    fn drive_ref(&self, axis: usize) -> Option<DriveRef>;
    /// SDOs while the cycle runs.
    fn sdo_requester(&self) -> Result<SdoRequester, Failure>;
    /// Stop every axis (a ramp or a quick stop), disable it, end the cycle; the summary, and
    /// the link when the bus can be started again on it.
    fn stop(self: Box<Self>, kind: StopKind) -> (serde_json::Value, Option<ToolLink>);
}

/// The EtherCAT master.
pub(crate) struct EtherCat {
    pub m: ecdrive::Master<ToolLink>,
}

impl Backend for EtherCat {
    fn is_running(&self) -> bool {
        self.m.is_running()
    }

    fn command(&mut self, c: Command) -> Result<(), Failure> {
        self.m.command(c).map_err(Failure::from)
    }

    fn telemetry(&mut self) -> &Telemetry {
        self.m.telemetry()
    }

    fn history_since(&mut self, seq: u64) -> HistorySlice {
        self.m.history_since(seq)
    }

    fn drive_ref(&self, axis: usize) -> Option<DriveRef> {
        self.m.drives().get(axis).map(|d| d.drive.clone())
    }

    fn sdo_requester(&self) -> Result<SdoRequester, Failure> {
        Ok(self.m.sdo_requester())
    }

    fn stop(self: Box<Self>, kind: StopKind) -> (serde_json::Value, Option<ToolLink>) {
        let (report, link) = self.m.stop(kind);
        (stop_summary(report.as_ref()), Some(link))
    }
}

/// One CANopen drive as the Python side names it.
pub(crate) struct CanAxis {
    pub drive: DriveRef,
    pub errors: &'static [ErrorEntry],
}

/// The CANopen master's cycle thread, with the history the EtherCAT session keeps made here
/// from its events (the same entries, the same words).
pub(crate) struct CanOpen<T: CanTransport + Send + 'static> {
    pub thread: Option<CycleThread<T>>,
    pub axes: Vec<CanAxis>,
    pub history: HistoryLog,
    pub telemetry: Telemetry,
}

impl<T: CanTransport + Send + 'static> CanOpen<T> {
    /// The thread's events since the last look into the history, its view into the telemetry.
    fn refresh(&mut self) {
        let Some(t) = self.thread.as_mut() else {
            return;
        };
        let events = t.events();
        let v: SessionView = t.view();
        for e in events {
            let entry = self.entry(e.time_ns, e.cycle, e.kind);
            self.history.push(entry);
        }
        self.telemetry.cycle = CycleTelemetry {
            cycle: v.cycle,
            overruns: v.late_cycles,
            all_op: !v.ended,
            ..CycleTelemetry::default()
        };
        self.telemetry.axes = v.axes;
    }

    /// A cycle event as a history entry: its drive, and a fault in the drive's alarm table.
    fn entry(&self, time_ns: u64, cycle: u64, kind: EventKind) -> HistoryEntry {
        let mut r = Resolved::default();
        if let EventKind::Axis {
            axis,
            event: cia402::Event::Fault { error: Some(d), .. },
        } = kind
            && let Some(a) = self.axes.get(usize::from(axis))
        {
            r.fault = Some(ErrorCode(d.code.0).describe(a.errors));
        }
        if let EventKind::Stopping { reason } = kind {
            r.subject = reason.axis().and_then(|a| self.drive_ref(usize::from(a)));
        }
        let axis = kind.axis();
        let drive = axis.and_then(|a| self.drive_ref(usize::from(a)));
        HistoryEntry::new(time_ns, Some(cycle), drive, HistoryEvent::Cycle(kind), r)
    }
}

impl<T: CanTransport + Send + 'static> Backend for CanOpen<T> {
    fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.view().ended)
    }

    fn command(&mut self, c: Command) -> Result<(), Failure> {
        let t = self.thread.as_mut().ok_or_else(|| {
            Failure::new(Class::Bus, None, "sending a command", "the cycle has ended")
        })?;
        t.command(c)
            .map_err(|e| Failure::new(e.class(), None, "sending a command", e.to_string()))
    }

    fn telemetry(&mut self) -> &Telemetry {
        self.refresh();
        &self.telemetry
    }

    fn history_since(&mut self, seq: u64) -> HistorySlice {
        self.refresh();
        self.history.since(seq)
    }

    fn drive_ref(&self, axis: usize) -> Option<DriveRef> {
        self.axes.get(axis).map(|a| a.drive.clone())
    }

    fn sdo_requester(&self) -> Result<SdoRequester, Failure> {
        Err(Failure::new(
            Class::Bus,
            None,
            "an SDO while the cycle runs",
            "the CANopen master's cycle thread owns the bus: SDOs go in the run file's \
             start-up values, or to `ecdrive upload`/`download` before the run",
        ))
    }

    fn stop(mut self: Box<Self>, kind: StopKind) -> (serde_json::Value, Option<ToolLink>) {
        self.refresh();
        let Some(t) = self.thread.take() else {
            return (serde_json::json!({ "shutdown_ok": false }), None);
        };
        let end = t.stop(kind);
        let (ok, view, notes) = match end {
            Ok(end) => {
                let view = end.view.clone();
                let mut notes = Vec::new();
                let mut m = end.session.into_master();
                for a in &self.axes {
                    let node = a.drive.position as u8;
                    // Life guarding off before the master goes (the drive is disabled), then
                    // NMT Stop, as `ecdrive run` ends.
                    if let Err(e) = m.supervise(node, ecdrive::canopen::master::Supervision::None) {
                        notes.push(format!("switching life guarding off on node {node}: {e}"));
                    }
                    if let Err(e) = m.nmt(node, ecdrive::canopen::nmt::NmtCommand::Stop) {
                        notes.push(format!("NMT Stop of node {node}: {e}"));
                    }
                }
                (end.error.is_none() && notes.is_empty(), view, notes)
            }
            Err(e) => (false, SessionView::default(), vec![e.to_string()]),
        };
        let summary = serde_json::json!({
            "shutdown_ok": ok,
            "cycle": { "cycles": view.cycle, "late": view.late_cycles },
            "notes": notes,
            "drives": self.axes.iter().zip(view.axes.iter()).map(|(a, t)| serde_json::json!({
                "position": a.drive.position,
                "name": a.drive.name,
                "max_following_error": t.max_following_error,
                "state": t.state.map(cia402::State::name),
            })).collect::<Vec<_>>(),
        });
        (summary, None)
    }
}

/// What `stop()` returns: how the run ended, its cycle figures, the history's totals.
pub(crate) fn stop_summary(report: Option<&ecdrive::SessionReport>) -> serde_json::Value {
    let Some(r) = report else {
        return serde_json::json!({ "shutdown_ok": false });
    };
    let cycle = r.cycle.as_ref().map(|c| {
        serde_json::json!({
            "end": format!("{:?}", c.end),
            "cycles": c.cycles,
            "lost": c.lost,
            "overruns": c.overruns,
            "wake_latency_ns": c.timing.wake_latency.summary(),
            "period_ns": c.timing.period.summary(),
            "busy_ns": c.timing.busy.summary(),
            "frames": c.frames,
        })
    });
    let totals: serde_json::Map<String, serde_json::Value> = r
        .history_totals
        .iter()
        .map(|(k, n)| (format!("{k:?}"), serde_json::Value::from(*n)))
        .collect();
    serde_json::json!({
        "shutdown_ok": r.shutdown_ok,
        "restarts": r.restarts,
        "cycle": cycle,
        "history_totals": totals,
        "emergencies": r.emergencies.len(),
        "drives": r.drive_outcomes().iter().map(|o| serde_json::json!({
            "position": o.drive.position,
            "name": o.drive.name,
            "max_following_error": o.max_following_error,
            "max_following_error_drive": o.max_following_error_drive,
            "states": o.states.iter().map(|s| s.name()).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}
