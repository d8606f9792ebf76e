//! The emulated drives: the MR-J4-TM and the BDHDE as the software slave presents them, built
//! from their ESI files and the emulator's own model of each drive.
//!
//! One engine, [`EmulatedDrive`], runs every drive; what differs is data, a [`DriveSpec`]:
//! the ESI file (identity, dictionary, CoE details, synchronisation modes and cycle times, SII;
//! [`esi_model`]) plus the emulator's model (CiA 402 state machine, PDO rules, write rules,
//! alarms, loss-of-data detection, motor and load, monitors). Nothing is taken from the
//! master's drive profiles: the two are written separately from the manuals and checked
//! against them (`tests/manual_facts/`), so a wrong value on one side is a disagreement, not
//! a shared mistake. Each drive's spec is in its own file ([`mr_j4_tm`], [`bdhde`]) with the
//! values that are ours (\[REC\]) in one labelled section.
//!
//! - **SII**: built from the drive's ESI file ([`description`], through
//!   [`crate::sii::from_esi`]), so the EEPROM a master reads and the ESI a user reads
//!   cannot drift apart.
//! - **CoE**: the ESI file's dictionary in an [`crate::coe::OdStore`] with the drive's PDO
//!   limits and write rules; complete access and SDO information as the ESI file says.
//! - **Cycle**: at every SYNC0 (or, in free run, every process-data frame) the drive moves the
//!   motor over the cycle that ended, supervises it, reads the new outputs, steps the CiA 402
//!   state machine ([`crate::cia402::device`]) and plans the next cycle; see [`motor`].
//! - **Fault injection** (for the master's tests), on the device reached with
//!   `Segment::device_mut::<EmulatedDrive>(position)`:
//!   [`EmulatedDrive::raise_alarm`], [`EmulatedDrive::force_following_error`],
//!   [`EmulatedDrive::jam`], [`EmulatedDrive::drop_outputs`],
//!   [`EmulatedDrive::set_main_power`], [`EmulatedDrive::set_remote`],
//!   [`EmulatedDrive::set_loss_detection`]; set-up: [`EmulatedDrive::with_stored`] (a parameter
//!   stored in the drive, e.g. the MR-J4-TM's [Pr. PA01]), [`EmulatedDrive::power_cycle`];
//!   read-back: [`EmulatedDrive::state`], [`EmulatedDrive::statusword`],
//!   [`EmulatedDrive::mode`], [`EmulatedDrive::position`], [`EmulatedDrive::position_rev`],
//!   [`EmulatedDrive::speed_rev_s`], [`EmulatedDrive::following_error`],
//!   [`EmulatedDrive::alarm`], [`EmulatedDrive::last_emergency`],
//!   [`EmulatedDrive::sync_error_counter`], [`EmulatedDrive::stats`], [`EmulatedDrive::od`].
//!   Injected alarms act at the next process-data cycle.
//!
//! Not modelled: touch probes, software position limits and [AL. 98], the MR-J4-TM's point
//! table, jog and indexer motion (those modes hold the position), homing with switches (only
//! the "current position" methods home; others report a homing error), warnings (statusword
//! bit 7 stays 0), storing parameters (0x1010 / 0x2340 accept their command and keep nothing
//! beyond [`EmulatedDrive::with_stored`]).
//!
//! ```
//! use ecdrive_sim::drives::{EmulatedDrive, emulated};
//! use ecdrive_sim::{ManualClock, Segment};
//! use std::sync::Arc;
//!
//! let mut segment = Segment::new(Arc::new(ManualClock::new(0)));
//! for key in ["mr-j4-tm", "bdhde"] {
//!     segment.push_device(emulated(key, 1).unwrap()).unwrap();
//! }
//! let mr = segment.device_mut::<EmulatedDrive>(0).unwrap();
//! assert_eq!(mr.spec().name, "MR-J4-TM");
//! mr.raise_alarm("AL.86.1").unwrap();
//! assert!(mr.raise_alarm("AL.99").is_err());
//! ```

pub mod bdhde;
mod drive;
pub mod esi_model;
pub mod motor;
pub mod mr_j4_tm;
pub mod spec;

pub use drive::{DriveStats, EmulatedDrive, TargetSample, UnknownAlarm};
pub use esi_model::{EsiModel, EsiModelError};
pub use spec::{DriveSpec, HomingFailure, HomingSpec};

use super::device::Device;
use super::quirks::Quirks;
use super::sii::DeviceDescription;
use crate::device::DeviceError;

static SPECS: [&DriveSpec; 2] = [&mr_j4_tm::SPEC, &bdhde::SPEC];

/// Every emulated drive.
pub fn specs() -> &'static [&'static DriveSpec] {
    &SPECS
}

/// The emulated drive with `--device` name `key` (`"mr-j4-tm"`, `"bdhde"`), if there is one.
pub fn spec_for(key: &str) -> Option<&'static DriveSpec> {
    SPECS.iter().copied().find(|s| s.key == key)
}

/// Switch the loss-of-data supervision of every emulated drive on `segment` on or off
/// ([`EmulatedDrive::set_loss_detection`]); other devices are left as they are.
pub fn set_loss_detection(segment: &mut crate::Segment, on: bool) {
    for i in 0..segment.len() {
        if let Some(d) = segment.device_mut::<EmulatedDrive>(i) {
            d.set_loss_detection(on);
        }
    }
}

/// The emulated drive `key` with serial number `serial`, ready to push onto a
/// [`crate::Segment`].
pub fn emulated(key: &str, serial: u32) -> Result<Box<dyn Device>, DeviceError> {
    emulated_with(key, serial, Quirks::NONE)
}

/// [`emulated`], behaving like a device ecdrive did not write ([`crate::quirks`]; every
/// quirk applies to the emulated drives).
pub fn emulated_with(
    key: &str,
    serial: u32,
    quirks: Quirks,
) -> Result<Box<dyn Device>, DeviceError> {
    emulated_stored(key, serial, quirks, &[])
}

/// [`emulated_with`], with parameters stored in the drive's non-volatile memory, in effect
/// from power-on ([`EmulatedDrive::with_stored`]); an object the drive does not have is an
/// error naming it.
pub fn emulated_stored(
    key: &str,
    serial: u32,
    quirks: Quirks,
    stored: &[(crate::od::ObjectAddress, i64)],
) -> Result<Box<dyn Device>, DeviceError> {
    let spec = spec_for(key).ok_or_else(|| DeviceError::Build {
        name: key.to_string(),
        reason: format!("ecdrive has no emulation of {key:?}"),
    })?;
    quirks
        .check_for(spec.key, EmulatedDrive::CAPABILITIES)
        .map_err(|reason| DeviceError::Quirk {
            name: key.to_string(),
            reason,
        })?;
    let mut d = EmulatedDrive::new(spec, serial)
        .map_err(|e| DeviceError::Build {
            name: key.to_string(),
            reason: e.to_string(),
        })?
        .with_quirks(quirks);
    for &(address, value) in stored {
        if d.od().dict().int(address).is_none() && d.od().dict().uint(address).is_none() {
            return Err(DeviceError::Build {
                name: key.to_string(),
                reason: format!("the {} has no object {address} to store", spec.name),
            });
        }
        d = d.with_stored(address, value);
    }
    Ok(Box::new(d))
}

/// Why the SII description of an emulated drive cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DescriptionError {
    /// No emulated drive has this key.
    #[error("ecdrive has no emulation of {0:?}")]
    Unknown(String),
    /// The drive's ESI file cannot be read or described in the SII.
    #[error(transparent)]
    Esi(#[from] EsiModelError),
}

/// The SII description of the emulated drive `key`, built from its ESI file, with serial
/// number `serial`.
pub fn description(key: &str, serial: u32) -> Result<DeviceDescription, DescriptionError> {
    let spec = spec_for(key).ok_or_else(|| DescriptionError::Unknown(key.to_string()))?;
    Ok(spec.model()?.description(serial)?)
}
