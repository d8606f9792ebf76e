//! `ecdrive reset --can BUS`: clear the faults CANopen drives have latched, as `ecdrive reset`
//! does for the EtherCAT drives.
//!
//! A drive in Fault leaves it on a rising edge of controlword bit 7. [`reset`] takes every node
//! (or the one asked for) to NMT Pre-operational — a node an earlier run left Stopped serves no
//! SDO — finds the drives (the nodes with a profile), configures and starts them as a run does, and runs a
//! short session on the motion runtime: it waits for each drive's statusword, records what a
//! drive in Fault latched (603Fh, decoded with the drive's alarm table — from the EMCY the
//! drive sent, when it sent one while the master listened), gives it the reset edge
//! ([`Command::FaultReset`]) and waits until it leaves Fault. Then it disables the drives and
//! takes them back to Pre-operational (no PDOs). A fault that does not clear is reported as
//! such.

use super::tools::{self, SCAN_WINDOW_US};
use crate::canopen::error::{CanError, CanErrorKind, NodeRef};
use crate::canopen::master::{DriveSetup, Master, MasterConfig};
use crate::canopen::motion::{MotionSession, axis_setup};
use crate::canopen::nmt::NmtCommand;
use crate::canopen::profile::CanDriveProfile;
use crate::canopen::transport::CanTransport;
use crate::cia402::State;
use crate::master::RunMode;
use crate::master::telemetry::{Axes, Command};
use crate::od::Emergency;
use serde::Serialize;
use std::time::Duration;

/// How [`reset`] runs.
#[derive(Debug, Clone)]
pub struct CanResetOptions {
    /// Only this node (default: every node with a drive profile).
    pub node: Option<u8>,
    /// The SYNC period of the short session.
    pub cycle: Duration,
    /// How long a drive may take to report its state, and to leave Fault after the edge.
    pub timeout: Duration,
    /// A drive ecdrive has no profile for: the profile built from its EDS file
    /// (`drives::eds_can::from_eds`); a node that matches no built-in profile but this one's
    /// identity is reset as this drive.
    pub eds: Option<&'static CanDriveProfile>,
}

impl Default for CanResetOptions {
    fn default() -> Self {
        Self {
            node: None,
            cycle: Duration::from_millis(4),
            timeout: Duration::from_secs(2),
            eds: None,
        }
    }
}

/// One drive after [`reset`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CanDriveReset {
    /// Node-ID.
    pub node: u8,
    /// The drive (profile name).
    pub drive: String,
    /// Its CiA 402 state before.
    pub before: String,
    /// What it had latched (603Fh and the alarm it names), if it was in Fault.
    pub fault: Option<String>,
    /// Whether it left Fault after the reset edge (`None`: it was not in Fault).
    pub cleared: Option<bool>,
    /// Its CiA 402 state after.
    pub after: String,
}

/// What [`reset`] did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CanResetReport {
    /// The bus.
    pub bus: String,
    /// The drives looked at, in node order.
    pub drives: Vec<CanDriveReset>,
    /// Whether no drive is left in Fault.
    pub all_clear: bool,
}

fn state_name(s: Option<State>) -> String {
    s.map_or_else(|| "unknown".to_string(), |s| s.to_string())
}

fn is_fault(s: Option<State>) -> bool {
    matches!(s, Some(State::Fault | State::FaultReactionActive))
}

fn not_ready(node: NodeRef, why: String) -> CanError {
    CanError::new(node, None, CanErrorKind::NotReady(why))
}

/// Clear the latched faults of the drives on `transport` (`bus` names it in the report). An
/// error is a bus failure, or no drive where one was asked for; a drive whose fault stays is
/// in the report (`cleared: Some(false)`).
pub fn reset<T: CanTransport>(
    transport: T,
    bus: &str,
    opts: &CanResetOptions,
) -> Result<CanResetReport, CanError> {
    let cycle_us = u64::try_from(opts.cycle.as_micros()).unwrap_or(u64::MAX);
    let mut m = Master::new(
        transport,
        MasterConfig {
            cycle_us,
            ..MasterConfig::default()
        },
    );
    m.pump(50_000)?;
    // A node an earlier run left in NMT Stopped answers no SDO, so not the scan either: first
    // every node (or the one asked for) to Pre-operational.
    m.nmt(opts.node.unwrap_or(0), NmtCommand::EnterPreOperational)?;
    m.pump(20_000)?;
    let drives = find_drives(&mut m, opts.node, opts.eds)?;
    for (node, p) in &drives {
        m.configure_drive(*node, DriveSetup::new(p))?;
        m.start(*node)?;
    }
    let axes: Vec<_> = drives
        .iter()
        .map(|(node, p)| (*node, axis_setup(p, Vec::new(), RunMode::Pp)))
        .collect();
    let mut s = MotionSession::new(m, &axes)?;
    let limit = (opts.timeout.as_micros() as u64)
        .div_ceil(cycle_us.max(1))
        .max(1);
    let state = |s: &MotionSession<T>, i: usize| s.telemetry(i).and_then(|t| t.state);
    let n = drives.len();
    for _ in 0..limit {
        if (0..n).all(|i| state(&s, i).is_some()) {
            break;
        }
        s.cycle()?;
    }
    let before: Vec<Option<State>> = (0..n).map(|i| state(&s, i)).collect();
    let mut faults: Vec<Option<String>> = vec![None; n];
    for (i, (node, p)) in drives.iter().enumerate() {
        if is_fault(before[i]) {
            faults[i] = Some(latched(&s, i, *node, p));
            s.command(Command::FaultReset(Axes::One(i as u16)));
        }
    }
    for _ in 0..limit {
        s.cycle()?;
        let waiting = (0..n).any(|i| faults[i].is_some() && is_fault(state(&s, i)));
        if !waiting {
            break;
        }
    }
    let after: Vec<Option<State>> = (0..n).map(|i| state(&s, i)).collect();
    take_down(&mut s, limit)?;
    let report: Vec<CanDriveReset> = drives
        .iter()
        .enumerate()
        .map(|(i, (node, p))| CanDriveReset {
            node: *node,
            drive: p.name.to_string(),
            before: state_name(before[i]),
            cleared: faults[i].as_ref().map(|_| !is_fault(after[i])),
            fault: faults[i].clone(),
            after: state_name(after[i]),
        })
        .collect();
    Ok(CanResetReport {
        bus: bus.to_string(),
        all_clear: report.iter().all(|d| d.cleared != Some(false)),
        drives: report,
    })
}

/// The drives to look at: every node with a profile, or `only` (an error when it does not
/// answer or is no drive this master knows).
fn find_drives<T: CanTransport>(
    m: &mut Master<T>,
    only: Option<u8>,
    eds: Option<&'static CanDriveProfile>,
) -> Result<Vec<(u8, &'static CanDriveProfile)>, CanError> {
    let ids = only.map_or(1..=127, |n| n..=n);
    let mut found = tools::scan(m, ids)?;
    // A node no built-in profile knows, which is the drive of the EDS file given.
    if let Some(p) = eds {
        for i in found.iter_mut().filter(|i| i.profile.is_none()) {
            if let (Some(dt), Some(v)) = (i.device_type, i.vendor_id)
                && p.identity.matches(dt, v, i.product_code)
            {
                i.profile = Some(p);
            }
        }
    }
    if let Some(node) = only {
        let at = NodeRef {
            id: node,
            drive: None,
        };
        let Some(info) = found.iter().find(|i| i.node == node) else {
            return Err(not_ready(
                at,
                format!(
                    "does not answer: no reply to an SDO upload of 0x1000 within {} ms, after \
                     NMT Enter Pre-operational (is it powered, on this bus, at this node-ID?)",
                    SCAN_WINDOW_US / 1000
                ),
            ));
        };
        if info.profile.is_none() {
            return Err(CanError::new(
                at,
                None,
                CanErrorKind::Identity(format!(
                    "no drive profile matches its identity (vendor {}, product {}){}: give \
                     the drive's EDS file with --eds FILE (reset knows the BLV-R, the ASDA-A2 \
                     and the Lexium MDrive without one)",
                    info.vendor_id.map_or("-".into(), |v| format!("0x{v:08X}")),
                    info.product_code
                        .map_or("-".into(), |v| format!("0x{v:08X}")),
                    eds.map_or_else(String::new, |p| format!(
                        ", nor the {} of the EDS file given",
                        p.name
                    )),
                )),
            ));
        }
    }
    Ok(found
        .iter()
        .filter_map(|i| Some((i.node, i.profile?)))
        .collect())
}

/// What axis `i` latched: 603Fh and the alarm it names, decoded with the drive's table (the
/// EMCY the drive sent, when the master received one, else 603Fh alone).
fn latched<T: CanTransport>(
    s: &MotionSession<T>,
    i: usize,
    node: u8,
    p: &CanDriveProfile,
) -> String {
    let code = s.telemetry(i).map_or(0, |t| t.error_code);
    // The drive's EMCY for this error code (a later one, such as a guarding error after an
    // earlier master left, names something else).
    let emcy = s
        .master()
        .emergencies(node)
        .filter(|e| e.emergency.error_code == code)
        .last();
    let decoded = match emcy {
        Some(e) => p.decode_emcy(&e.emergency),
        None => p.decode_emcy(&Emergency {
            error_code: code,
            error_register: 0,
            data: [0; 5],
        }),
    };
    format!("error code 0x{code:04X}: {decoded}")
}

/// Disable every drive, then back to Pre-operational: no PDOs, SDO still served.
fn take_down<T: CanTransport>(s: &mut MotionSession<T>, limit: u64) -> Result<(), CanError> {
    s.command(Command::Disable(Axes::All));
    for _ in 0..limit {
        s.cycle()?;
        if !s.any_busy() {
            break;
        }
    }
    let nodes: Vec<u8> = (0..s.len())
        .filter_map(|i| s.node(i))
        .map(|n| n.id)
        .collect();
    for node in nodes {
        s.master_mut().nmt(node, NmtCommand::EnterPreOperational)?;
    }
    Ok(())
}
