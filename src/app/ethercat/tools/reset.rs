//! `ecdrive reset`: clear the faults a drive has latched.
//!
//! A drive in Fault stays there until the master gives it a rising edge on controlword bit 7,
//! and that needs process data: a short cyclic session. [`reset`] starts a master on the
//! segment (every drive it has a profile for, and with `allow_generic` the other CiA 402
//! devices), waits for OP and for each drive's statusword, and for every drive in Fault (or
//! Fault reaction active) records what it latched (0x603F decoded with the drive's alarm
//! table, as the history names it), sends the reset edge and waits until it leaves Fault.
//! Then it takes the drives down again (disabled, INIT). A fault that does not clear (its cause
//! is still there, or the drive needs a power cycle) is reported as such.
//!
//! [`clear_faults`] is the same step inside a running [`Master`] (`ecdrive run` with
//! `reset_faults = true`).

use crate::cia402::State;
use crate::link::FrameLink;
use crate::master::HistoryKind;
use crate::master::error::{ErrorKind, MasterError};
use crate::master::session::{Master, MasterConfig};
use crate::master::telemetry::{Axes, Command, StopKind};
use serde::Serialize;
use std::time::Duration;

/// How [`reset`] runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ResetOptions {
    /// Only the drive at this position (default: every drive).
    pub position: Option<u16>,
    /// The cycle of the short session.
    pub cycle: Duration,
    /// Run devices that declare CiA 402 but have no profile with the generic profile.
    pub allow_generic: bool,
    /// How long a drive may take to leave Fault after the reset edge.
    pub timeout: Duration,
}

impl Default for ResetOptions {
    fn default() -> Self {
        Self {
            position: None,
            cycle: Duration::from_millis(1),
            allow_generic: true,
            timeout: Duration::from_secs(2),
        }
    }
}

/// One drive after [`reset`] or [`clear_faults`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DriveReset {
    /// Position on the segment.
    pub position: u16,
    /// The drive (profile name).
    pub drive: String,
    /// Its CiA 402 state before.
    pub before: String,
    /// What it had latched (the fault as the history decodes it), if it was in Fault.
    pub fault: Option<String>,
    /// Whether it left Fault after the reset edge (`None`: it was not in Fault).
    pub cleared: Option<bool>,
    /// Its CiA 402 state after.
    pub after: String,
}

/// What [`reset`] did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ResetReport {
    /// The drives looked at, in segment order.
    pub drives: Vec<DriveReset>,
    /// Whether no drive is left in Fault.
    pub all_clear: bool,
}

fn state_name(s: Option<State>) -> String {
    s.map_or_else(|| "unknown".to_string(), |s| s.to_string())
}

fn is_fault(s: Option<State>) -> bool {
    matches!(s, Some(State::Fault | State::FaultReactionActive))
}

/// What axis `i` has latched: 0x603F decoded with the drive's alarm table (when 0x603F is
/// mapped), else the history's account of the fault.
pub fn latched<L: FrameLink + Send + 'static>(m: &mut Master<L>, i: usize) -> String {
    let Some(d) = m.drives().get(i).cloned() else {
        return "a fault".into();
    };
    let code = m.telemetry().axes.get(i).map_or(0, |a| a.error_code);
    if code != 0 {
        let table = crate::drives::all()
            .iter()
            .find(|p| p.name == d.profile)
            .map_or(&[][..], |p| p.caps.error_table);
        return crate::cia402::ErrorCode(code).describe(table).to_string();
    }
    m.history()
        .iter()
        .rev()
        .find(|h| {
            h.kind == HistoryKind::DriveFault
                && h.drive
                    .as_ref()
                    .is_some_and(|x| x.position == d.info.position)
        })
        .map_or_else(|| "a fault (0x603F not mapped)".to_string(), |h| h.text())
}

/// In a running master whose drives are in OP: give every drive (of `axes`) that is in Fault
/// the reset edge and wait until it leaves Fault, at most `timeout` per drive.
pub fn clear_faults<L: FrameLink + Send + 'static>(
    m: &mut Master<L>,
    only: Option<u16>,
    timeout: Duration,
) -> Result<Vec<DriveReset>, MasterError> {
    // Every drive's statusword has come in once (a drive is judged only in OP).
    m.wait_until("every drive's state", Duration::from_secs(5), |t| {
        t.axes.iter().all(|a| a.state.is_some())
    })?;
    let drives = m.drives().to_vec();
    let mut out = Vec::new();
    for (i, d) in drives.iter().enumerate() {
        if only.is_some_and(|p| p != d.info.position) {
            continue;
        }
        let before = m.telemetry().axes.get(i).and_then(|a| a.state);
        let mut r = DriveReset {
            position: d.info.position,
            drive: d.drive.name.clone(),
            before: state_name(before),
            fault: None,
            cleared: None,
            after: state_name(before),
        };
        if is_fault(before) {
            r.fault = Some(latched(m, i));
            m.command(Command::FaultReset(Axes::One(i as u16)))?;
            let cleared = m
                .wait_until("the fault reset", timeout, |t| {
                    t.axes.get(i).is_some_and(|a| !is_fault(a.state))
                })
                .is_ok();
            r.cleared = Some(cleared);
            r.after = state_name(m.telemetry().axes.get(i).and_then(|a| a.state));
        }
        out.push(r);
    }
    Ok(out)
}

/// Clear the latched faults on `link`: a short cyclic session (see the module documentation).
pub fn reset<L: FrameLink + Send + 'static>(
    link: L,
    opts: &ResetOptions,
) -> Result<ResetReport, MasterError> {
    let mut cfg = MasterConfig::new(opts.cycle);
    cfg.startup.allow_generic = opts.allow_generic;
    let mut m = Master::start(link, cfg).map_err(|f| f.error)?;
    if let Some(p) = opts.position
        && !m.drives().iter().any(|d| d.info.position == p)
    {
        let _ = m.stop(StopKind::Ramp);
        return Err(MasterError::new(
            None,
            format!("resetting the drive at position {p}"),
            ErrorKind::Config,
            "there is no drive at that position (an I/O device has no CiA 402 faults)",
        ));
    }
    let r = m
        .wait_until("OP", Duration::from_secs(15), |t| t.cycle.all_op)
        .and_then(|()| clear_faults(&mut m, opts.position, opts.timeout));
    let (report, _) = m.stop(StopKind::Ramp);
    let drives = r?;
    if !report.is_some_and(|r| r.shutdown_ok) {
        return Err(MasterError::new(
            None,
            "taking the drives down after the reset",
            ErrorKind::Bus,
            "not every drive reached INIT",
        ));
    }
    Ok(ResetReport {
        all_clear: drives.iter().all(|d| d.cleared != Some(false)),
        drives,
    })
}
