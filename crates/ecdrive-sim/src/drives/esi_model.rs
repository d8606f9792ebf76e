//! What an emulated drive takes from its ESI file: identity, object dictionary, CoE details,
//! synchronisation modes and allowed cycle times, and the SII EEPROM.
//!
//! The emulation never reads the master's drive profiles: the ESI file is the vendor-format
//! description of the device (here written from the manual, see `esi/README.md`), and the
//! drive's behaviour beyond it is in the emulator's own tables ([`super::mr_j4_tm`],
//! [`super::bdhde`]). The tests in `tests/manual_facts/` check both the master's profiles and
//! the emulated drives, over the bus, against the manuals.
//!
//! The dictionary is built once per drive type and process, on first use, and kept for the
//! life of the process (the object store holds `'static` descriptions).

use crate::esi::{self, EsiFile};
use crate::od::ObjectDesc;
use crate::sii::DeviceDescription;

/// The parts of a drive's ESI file the emulation is built from.
#[derive(Debug)]
pub struct EsiModel {
    /// The drive's name, for errors.
    drive: &'static str,
    /// The parsed file.
    file: EsiFile,
    /// Which device of the file.
    device: usize,
    /// Vendor ID (`<Vendor><Id>`).
    pub vendor_id: u32,
    /// Vendor name.
    pub vendor_name: String,
    /// Product code (`<Type ProductCode>`).
    pub product_code: u32,
    /// Revision (`<Type RevisionNo>`).
    pub revision: u32,
    /// The object dictionary (`<Profile><Dictionary>`), resolved.
    pub dictionary: &'static [ObjectDesc],
    /// `<CoE CompleteAccess>`.
    pub complete_access: bool,
    /// `<CoE SdoInfo>`.
    pub sdo_info: bool,
    /// Free run is offered (an `<OpMode>` with AssignActivate 0), with its allowed cycle times.
    pub free_run: Option<Option<esi::CycleTimes>>,
    /// DC SYNC0 is offered (an `<OpMode>` activating SYNC0), with its allowed cycle times.
    pub dc_sync0: Option<Option<esi::CycleTimes>>,
}

/// Why an ESI file cannot be an emulated drive.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the {drive} ESI file: {reason}")]
pub struct EsiModelError {
    /// The drive.
    pub drive: &'static str,
    /// What is wrong.
    pub reason: String,
}

impl EsiModel {
    /// The model of device `product_code` in the ESI text `xml`, for the drive named `drive`
    /// (in errors).
    pub fn build(drive: &'static str, xml: &str, product_code: u32) -> Result<Self, EsiModelError> {
        let err = |reason: String| EsiModelError { drive, reason };
        let file = EsiFile::parse(xml).map_err(|e| err(e.to_string()))?;
        let device = file
            .devices
            .iter()
            .position(|d| d.type_.product_code == product_code)
            .ok_or_else(|| err(format!("no device with product code 0x{product_code:08X}")))?;
        let dev = file
            .devices
            .get(device)
            .ok_or_else(|| err("device index out of range".into()))?;
        let dictionary = esi::static_dictionary(dev).map_err(err)?;
        let coe = dev.mailbox.as_ref().and_then(|m| m.coe.as_ref());
        let mode = |sync0: bool| {
            dev.dc
                .iter()
                .find(|m| {
                    if sync0 {
                        m.mode.sync0()
                    } else {
                        m.mode.assign_activate == 0
                    }
                })
                .map(|m| m.allowed_cycle_times.clone())
        };
        // Without a <Dc> element the device runs free (SM-synchronous or free run).
        let free_run = if dev.dc.is_empty() {
            Some(None)
        } else {
            mode(false)
        };
        Ok(Self {
            vendor_id: file.vendor.id,
            vendor_name: file.vendor.name.clone(),
            product_code: dev.type_.product_code,
            revision: dev.type_.revision_no.unwrap_or(0),
            dictionary,
            complete_access: coe.is_some_and(|c| c.complete_access),
            sdo_info: coe.is_none_or(|c| c.sdo_info),
            free_run,
            dc_sync0: mode(true),
            device,
            file,
            drive,
        })
    }

    /// The SII EEPROM contents with serial number `serial`.
    pub fn description(&self, serial: u32) -> Result<DeviceDescription, EsiModelError> {
        let dev = self.file.devices.get(self.device).ok_or(EsiModelError {
            drive: self.drive,
            reason: "device index out of range".into(),
        })?;
        crate::sii::from_esi(self.vendor_id, dev, serial).map_err(|e| EsiModelError {
            drive: self.drive,
            reason: e.to_string(),
        })
    }

    /// Whether the drive accepts a SYNC0 (`dc`) or free-run cycle of `ns` as its ESI states
    /// it; a mode without a stated list accepts any cycle.
    pub fn accepts_cycle(&self, dc: bool, ns: u32) -> bool {
        let mode = if dc { &self.dc_sync0 } else { &self.free_run };
        match mode {
            None => false,
            Some(None) => true,
            Some(Some(times)) => times.contains(ns),
        }
    }
}
