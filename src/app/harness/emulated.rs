//! The emulated drives a measurement runs against: sim devices by name, the drive profile the
//! master uses for each, and fresh segments with the ESC timing statistics switched on.

use crate::cia402::VelocityUnit;
use crate::cia402::{DriveCaps, SupportedModes};
use crate::drives::{
    self, CycleTimeObject, CycleTimes, DriveProfile, EtherCat, IdentityMatch, SyncSpec, Units,
};
use crate::od::ObjectAddress;
use crate::pdo::{DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange};
use crate::sim::Segment;
use crate::sim::devices::generic_coe::{GENERIC_COE_PRODUCT, OBJECTS};
use crate::sim::devices::{self, TEST_VENDOR_ID};

static RANGES_RX: &[PdoRange] = &[PdoRange::new(0x1600, 0x1601, 8)];
static RANGES_TX: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A01, 8)];
static RX: &[Pdo] = &[Pdo::fixed(
    0x1600,
    &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)],
)];
static TX: &[Pdo] = &[Pdo::fixed(
    0x1A00,
    &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6064, 0, 32)],
)];

/// The profile the harness runs the sim's generic CoE device (`generic-coe`) with: its default
/// mapping (controlword + target position, statusword + actual position, 6 bytes each way) as
/// the cyclic mapping, DC SYNC0 with 0x1C32:01/02, any cycle from 125 µs in 125 µs steps.
pub static GENERIC_COE_PROFILE: DriveProfile = DriveProfile {
    name: "generic CoE device (emulated)",
    vendor: "ecdrive",
    caps: DriveCaps {
        supported_modes: SupportedModes::ALL_STANDARD,
        ..DriveCaps::CIA402
    },
    dictionary: OBJECTS,
    units: Units {
        position_name: "increment",
        position_per_rev: 1.0,
        velocity: VelocityUnit::PositionPerSecond,
        torque_per_mille: 1.0,
        profile: None,
    },
    bus: EtherCat {
        key: "generic-coe",
        identity: IdentityMatch {
            vendor_id: TEST_VENDOR_ID,
            product_code: GENERIC_COE_PRODUCT,
        },
        revision: 1,
        pdo_limits: PdoLimits {
            drive: "generic CoE device",
            rx: DirectionLimits {
                pdos: RANGES_RX,
                max_assigned: 2,
                max_entries: 16,
                max_bytes: 64,
            },
            tx: DirectionLimits {
                pdos: RANGES_TX,
                max_assigned: 2,
                max_entries: 16,
                max_bytes: 64,
            },
            assignment_writable: true,
        },
        default_mapping: Mapping::fixed(RX, TX),
        cyclic_mapping: Mapping::fixed(RX, TX),
        mode_mappings: &[],
        required_objects: &[],
        startup: &[],
        init_cmds: &[],
        output_defaults: &[],
        cycle_counter: None,
        sync: SyncSpec {
            free_run: true,
            dc_sync0: true,
            cycle_times: CycleTimes::Range {
                min_ns: 125_000,
                max_ns: 10_000_000,
                step_ns: 125_000,
            },
            assign_activate: 0x0300,
            sync_type_object: Some(ObjectAddress::new(0x1C32, 1)),
            cycle_time_object: Some(CycleTimeObject::Nanoseconds(ObjectAddress::new(0x1C32, 2))),
        },
        complete_access: false,
        esi: "",
        zero_speed_flag: None,
        mode_selector: None,
        ratings: crate::drives::Ratings::NONE,
    },
};

/// Why the emulated line cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum EmulationError {
    /// The device name is unknown or the device cannot be built.
    #[error("emulated drive {position}: {source}")]
    Device {
        /// Position in the line.
        position: usize,
        /// Why.
        #[source]
        source: devices::DeviceError,
    },
    /// No profile matches the device.
    #[error(
        "emulated drive {position} ({name}): no drive profile matches vendor 0x{vendor:08X} \
         product 0x{product:08X}; the master cannot run it"
    )]
    NoProfile {
        /// Position.
        position: usize,
        /// Device name.
        name: String,
        /// Vendor ID.
        vendor: u32,
        /// Product code.
        product: u32,
    },
    /// The SII of a device cannot be built.
    #[error("emulated drive {position} ({name}): {reason}")]
    Sii {
        /// Position.
        position: usize,
        /// Device name.
        name: String,
        /// Why.
        reason: String,
    },
    /// No drive given.
    #[error("no drives to emulate")]
    Empty,
}

/// The profile the master uses for the sim device `name`: the harness's own for
/// `generic-coe`, otherwise the registered profile matching the device's identity.
pub fn profile_for(name: &str, position: usize) -> Result<&'static DriveProfile, EmulationError> {
    if name == "generic-coe" {
        return Ok(&GENERIC_COE_PROFILE);
    }
    let dev = devices::by_name(name, position)
        .map_err(|source| EmulationError::Device { position, source })?;
    let id = dev.description().identity;
    drives::by_identity(id.vendor_id, id.product_code).ok_or(EmulationError::NoProfile {
        position,
        name: name.to_string(),
        vendor: id.vendor_id,
        product: id.product_code,
    })
}

/// The profile the master uses for a device with this identity: the harness's own for the
/// sim's generic CoE device, otherwise the registered profile.
pub fn profile_of_identity(vendor_id: u32, product_code: u32) -> Option<&'static DriveProfile> {
    let g = &GENERIC_COE_PROFILE.identity;
    if vendor_id == g.vendor_id && product_code == g.product_code {
        return Some(&GENERIC_COE_PROFILE);
    }
    drives::by_identity(vendor_id, product_code)
}

/// Profiles for a line of sim devices, in order.
pub fn profiles(names: &[String]) -> Result<Vec<&'static DriveProfile>, EmulationError> {
    if names.is_empty() {
        return Err(EmulationError::Empty);
    }
    names
        .iter()
        .enumerate()
        .map(|(i, n)| profile_for(n, i))
        .collect()
}

/// A fresh segment of the named devices: the software slave's [`devices::line`] (every ESC
/// recording its timing statistics, each on its own oscillator, [`devices::DRIFT_PPB`]).
pub fn segment(names: &[String]) -> Result<Segment, EmulationError> {
    devices::line(names).map_err(|e| match e {
        devices::LineError::Empty => EmulationError::Empty,
        devices::LineError::Device { position, source } => {
            EmulationError::Device { position, source }
        }
        devices::LineError::Sii {
            position,
            name,
            reason,
        } => EmulationError::Sii {
            position,
            name,
            reason,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generic_devices_get_the_harness_profile_and_unknown_names_are_named() {
        let names = vec!["generic-coe".to_string(), "generic-coe".to_string()];
        let p = profiles(&names).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].key, "generic-coe");
        let seg = segment(&names).unwrap();
        assert_eq!(seg.len(), 2);
        assert!(seg.slave(1).unwrap().esc.timing_stats().is_some());
        let e = profiles(&["nope".to_string()]).unwrap_err();
        assert!(e.to_string().contains("unknown device \"nope\""), "{e}");
        // A device without a drive profile: named, with its identity.
        let e = profiles(&["generic-io".to_string()]).unwrap_err();
        assert!(e.to_string().contains("generic-io"), "{e}");
        assert!(matches!(profiles(&[]), Err(EmulationError::Empty)));
    }
}
