//! Ready-made emulated devices for tests, benchmarks and `ecdrive sim`.
//!
//! - [`IoDevice`]: a digital-I/O-like device without mailbox. Its PDOs come from the SII
//!   (TxPDO/RxPDO categories), SyncManagers and FMMUs from the SII too: the path ethercrab and
//!   SOEM take for EEPROM-only devices. Inputs echo the outputs behind a cycle counter, so a test
//!   can see the process data round trip.
//! - [`EchoMailbox`]: a device with a standard mailbox whose firmware returns every request
//!   unchanged; it exercises the SyncManager mailbox handshake without any protocol.
//!
//! - [`GenericCoeDevice`]: a CiA 402-style servo with a CoE mailbox (SDO, SDO information,
//!   complete access, emergencies), variable PDO mapping and DC synchronisation.
//!
//! [`by_name`] creates devices from the names `ecdrive sim --device` accepts ([`device_names`]):
//! the emulated drives of the registry ([`super::drives`]) and the test devices here.

mod echo;
pub mod esi_dictionary;
pub mod generic_coe;
mod io;
mod line;

pub use echo::EchoMailbox;
pub use generic_coe::{CoeObservations, GenericCoeDevice};
pub use io::{IoDevice, IoObservations, TEST_VENDOR_ID};
pub use line::{DRIFT_PPB, LineError, line};

use super::device::Device;
use super::quirks::{split_name, stored_params};

pub use crate::device::DeviceError;

/// The test devices [`by_name`] accepts, with a one-line description each. The emulated drives
/// come on top, from the drive registry: see [`device_names`].
pub const DEVICE_NAMES: &[(&str, &str)] = &[
    (
        "generic-coe",
        "CiA 402-style servo with CoE mailbox, variable PDO mapping (0x1600/0x1601, 0x1A00/0x1A01) and DC SYNC0",
    ),
    (
        "generic-io",
        "digital I/O without mailbox: 2 output bytes, 4 input bytes (counter + echo), DC capable",
    ),
    (
        "echo-mailbox",
        "mailbox device that returns every mailbox request unchanged (no process data)",
    ),
];

/// Every name [`by_name`] accepts, with a one-line description: each emulated drive
/// ([`super::drives::specs`], by its `--device` key, identity from its ESI file), then the test
/// devices.
pub fn device_names() -> Vec<(&'static str, String)> {
    let drives = super::drives::specs().iter().map(|s| {
        let text = match s.model() {
            Ok(m) => format!(
                "emulated {} {} (vendor 0x{:08X}, product 0x{:08X}), SII from its ESI file",
                m.vendor_name, s.name, m.vendor_id, m.product_code
            ),
            Err(e) => format!("emulated {} (unusable: {e})", s.name),
        };
        (s.key, text)
    });
    drives
        .chain(DEVICE_NAMES.iter().map(|(n, d)| (*n, (*d).to_string())))
        .collect()
}

/// The names [`by_name`] accepts, comma-separated (for error messages).
pub fn known_names() -> String {
    device_names()
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Check a device name without building the device (cheap: no ESI parse, no dictionary):
/// the error [`by_name`] would give for an unknown name or quirk.
pub fn check_name(name: &str) -> Result<(), DeviceError> {
    let (base, _) = split_name(name).map_err(|reason| DeviceError::Quirk {
        name: name.into(),
        reason,
    })?;
    let stored = stored_params(name).map_err(|reason| DeviceError::Quirk {
        name: name.into(),
        reason,
    })?;
    let is_drive = super::drives::specs().iter().any(|s| s.key == base);
    if !stored.is_empty() && !is_drive {
        return Err(DeviceError::Quirk {
            name: name.into(),
            reason: "only the emulated drives keep stored parameters (`@OBJECT=VALUE`)".into(),
        });
    }
    let known =
        is_drive || DEVICE_NAMES.iter().any(|(n, _)| *n == base) || base.starts_with("esi:");
    if known {
        Ok(())
    } else {
        Err(DeviceError::Unknown {
            name: base.into(),
            known: known_names(),
        })
    }
}

/// Create a device by name (see [`device_names`]), with the quirks named after `+`
/// (`bdhde+no-state-skipping`, see [`crate::quirks`]) and, for an emulated drive, the
/// parameters stored in it after `@` (`mr-j4-tm@0x2001=2`, [`stored_params`]). `position` makes serial numbers
/// unique. `esi:PATH` is the generic CoE servo behind the one device of the ESI file at PATH
/// ([`GenericCoeDevice::from_esi`]).
pub fn by_name(name: &str, position: usize) -> Result<Box<dyn Device>, DeviceError> {
    check_name(name)?;
    let serial = u32::try_from(position).unwrap_or(u32::MAX);
    let stored = stored_params(name).map_err(|reason| DeviceError::Quirk {
        name: name.into(),
        reason,
    })?;
    let (base, quirks) = split_name(name).map_err(|reason| DeviceError::Quirk {
        name: name.into(),
        reason,
    })?;
    let quirk_error = |reason: String| DeviceError::Quirk {
        name: name.into(),
        reason,
    };
    if let Some(path) = base.strip_prefix("esi:") {
        let build = |reason: String| DeviceError::Build {
            name: name.into(),
            reason,
        };
        // `esi:PATH@0xPRODUCT[:0xREVISION]` chooses a device of a file that has several.
        let (path, choice) = match name.rsplit_once('@') {
            Some((_, sel)) if sel.starts_with("0x") || sel.starts_with("0X") => {
                let path = path.rsplit_once('@').map_or(path, |(p, _)| p);
                (path, crate::esi::DeviceChoice::parse(sel))
            }
            _ => (path, crate::esi::DeviceChoice::Only),
        };
        let file = crate::esi::EsiFile::from_path(path).map_err(|e| build(e.to_string()))?;
        let dev = file
            .choose(&choice)
            .map_err(|e| {
                build(
                    if choice == crate::esi::DeviceChoice::Only && file.devices.len() > 1 {
                        format!(
                            "the file describes {} devices ({}): say which with \
                         esi:FILE@0xPRODUCT[:0xREVISION]",
                            file.devices.len(),
                            file.device_list()
                        )
                    } else {
                        e
                    },
                )
            })
            .and_then(|i| {
                file.devices
                    .get(i)
                    .ok_or_else(|| build("device index out of range".into()))
            })?;
        return GenericCoeDevice::from_esi(&file, dev, serial)
            .map_err(build)?
            .with_quirks(quirks)
            .map(|d| Box::new(d) as Box<dyn Device>)
            .map_err(quirk_error);
    }
    match base {
        "generic-coe" => GenericCoeDevice::new(serial)
            .map_err(|e| DeviceError::Build {
                name: name.into(),
                reason: e.to_string(),
            })?
            .with_quirks(quirks)
            .map(|d| Box::new(d) as Box<dyn Device>)
            .map_err(quirk_error),
        "generic-io" => IoDevice::new(2, 4)
            .with_serial(serial)
            .with_quirks(quirks)
            .map(|d| Box::new(d) as Box<dyn Device>)
            .map_err(quirk_error),
        "echo-mailbox" if quirks.is_empty() => Ok(Box::new(EchoMailbox::new().with_serial(serial))),
        "echo-mailbox" => Err(quirk_error(
            "the echo-mailbox device takes no quirks".into(),
        )),
        _ => match super::drives::spec_for(base) {
            Some(spec) => super::drives::emulated_stored(spec.key, serial, quirks, &stored),
            None => Err(DeviceError::Unknown {
                name: base.into(),
                known: known_names(),
            }),
        },
    }
}

#[cfg(test)]
mod name_tests {
    use super::*;

    #[test]
    fn check_name_accepts_exactly_what_by_name_builds() {
        for (name, _) in device_names() {
            assert!(check_name(name).is_ok(), "{name}");
            assert!(by_name(name, 0).is_ok(), "{name}");
        }
        for bad in ["", "mr-j4", "MR-J4-TM ", "nonsense"] {
            assert!(check_name(bad).is_err(), "{bad:?}");
            assert!(by_name(bad, 0).is_err(), "{bad:?}");
            assert_eq!(
                check_name(bad).err().map(|e| e.to_string()),
                by_name(bad, 0).err().map(|e| e.to_string())
            );
        }
    }
}
