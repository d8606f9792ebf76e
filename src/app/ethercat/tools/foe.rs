//! `ecdrive foe read|write`: files over FoE (File access over EtherCAT), firmware above all.
//!
//! Like `diag` and `alias` it does no discovery: it talks to the device at a position as it
//! finds it, so that a device put into BOOT by `ecdrive states -p POS BOOT` (where firmware is
//! written) is still in BOOT. The device must have a mailbox, i.e. be in PRE-OP or above, or in
//! BOOT (the bootstrap mailbox); in INIT it has none and the command says so. Its station
//! address is the one the last discovery gave it (0x0010).
//!
//! The device's name comes from its SII identity (a built-in profile's name, else the vendor
//! and product code). A refusal is the device's FoE error code and text, with the drive named:
//! `drive 0 (MR-J4-TM) mailbox: FoE error 0x8009 (not in Bootstrap): file access in BOOT only`.

use super::diag::aprd;
use crate::ec::{AlState, AlStatus};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::coe::FoeTransfer;
use crate::master::error::{DriveRef, ErrorKind, MasterError};
use serde::Serialize;
use std::time::Duration;

/// The largest file `foe read` accepts (\[REC\]: firmware files are a few MiB).
pub const MAX_READ_BYTES: usize = 64 << 20;

/// What a transfer did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FoeReport {
    /// Position of the device.
    pub position: u16,
    /// The device.
    pub drive: String,
    /// Its AL state.
    pub al_state: String,
    /// `read` or `write`.
    pub direction: &'static str,
    /// The file name on the device.
    pub name: String,
    /// Bytes, packets and BUSY replies.
    #[serde(flatten)]
    pub transfer: FoeTransfer,
}

/// The device at `position` as FoE finds it: its name, AL status and station address.
fn device<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
) -> Result<(DriveRef, AlStatus, u16), MasterError> {
    let step = format!("device {position}: FoE");
    let r = aprd(bus, position, 0x0010, 0x0132 - 0x0010).map_err(|e| {
        if e.reason.contains("working counter") {
            MasterError::new(
                None,
                step.clone(),
                ErrorKind::Config,
                "there is no device at this position",
            )
        } else {
            e
        }
    })?;
    let u16_at = |i: usize| {
        u16::from_le_bytes([
            r.get(i).copied().unwrap_or(0),
            r.get(i + 1).copied().unwrap_or(0),
        ])
    };
    let address = u16_at(0);
    let status = AlStatus {
        raw: u16_at(0x0130 - 0x0010),
    };
    let vendor = super::eeprom::read_u32(bus, position, 0x0008)?;
    let product = super::eeprom::read_u32(bus, position, 0x000A)?;
    let name = crate::drives::by_identity(vendor, product)
        .map(|p| p.name.to_string())
        .unwrap_or_else(|| format!("vendor 0x{vendor:08X} product 0x{product:08X}"));
    let drive = DriveRef { position, name };
    if status.state() == Some(AlState::Init) || status.state().is_none() {
        return Err(MasterError::new(
            Some(&drive),
            "FoE",
            ErrorKind::Config,
            format!(
                "the device is in {status}, which has no mailbox: request BOOT for firmware \
                 (`ecdrive states -p {position} BOOT`) or PRE-OP first"
            ),
        ));
    }
    if address == 0 {
        return Err(MasterError::new(
            Some(&drive),
            "FoE",
            ErrorKind::Config,
            "the device has no station address (0x0010 = 0): run a command that discovers the \
             segment first (`ecdrive states -p POS BOOT`)",
        ));
    }
    Ok((drive, status, address))
}

/// A session error as a [`MasterError`] whose step names the transfer.
fn step(e: crate::master::bus::SessionError, what: String) -> MasterError {
    let mut m = MasterError::from(e);
    m.step = what;
    m
}

/// Time for a whole transfer of `bytes`: 10 s plus 50 ms per KiB.
fn budget(bytes: usize) -> Duration {
    Duration::from_secs(10) + Duration::from_millis(50 * (bytes as u64 / 1024 + 1))
}

/// Write `data` as file `name` to the device at `position`, with `password` (0: none).
pub fn foe_write<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    name: &str,
    password: u32,
    data: &[u8],
    progress: &mut (dyn FnMut(usize, usize) + Send),
) -> Result<FoeReport, MasterError> {
    let (drive, status, address) = device(bus, position)?;
    let t = bus
        .with_mailbox_as_found(address, drive.clone(), budget(data.len()), async |c| {
            c.foe_write(name, password, data, progress).await
        })
        .map_err(|e| step(e, format!("FoE write of {name:?}")))?;
    Ok(FoeReport {
        position,
        drive: drive.name,
        al_state: status.to_string(),
        direction: "write",
        name: name.to_string(),
        transfer: t,
    })
}

/// Read file `name` from the device at `position`, with `password` (0: none).
pub fn foe_read<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    name: &str,
    password: u32,
    progress: &mut (dyn FnMut(usize) + Send),
) -> Result<(Vec<u8>, FoeReport), MasterError> {
    let (drive, status, address) = device(bus, position)?;
    let (data, t) = bus
        .with_mailbox_as_found(
            address,
            drive.clone(),
            budget(MAX_READ_BYTES / 64),
            async |c| c.foe_read(name, password, MAX_READ_BYTES, progress).await,
        )
        .map_err(|e| step(e, format!("FoE read of {name:?}")))?;
    Ok((
        data,
        FoeReport {
            position,
            drive: drive.name,
            al_state: status.to_string(),
            direction: "read",
            name: name.to_string(),
            transfer: t,
        },
    ))
}
