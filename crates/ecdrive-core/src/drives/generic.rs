//! The generic CiA 402 profile: what ecdrive assumes about a drive it has no profile for.
//!
//! A device with an unknown identity is reported with its vendor ID, product code and revision
//! ([`super::identify`]); it runs with this profile only when the user asks for it. Everything
//! here is the plain CiA 402 / ETG.1020 standard, nothing vendor-specific:
//! - device control without state skipping, every standard quick-stop code, transition 16;
//! - PDO mapping objects 0x1600–0x17FF / 0x1A00–0x1BFF with no limits beyond the standard ones
//!   (the drive refuses what it does not accept, and the master reports that abort);
//! - the recommended cyclic mapping of the known drives (controlword, target position, velocity
//!   and torque, mode; statusword, actual position, velocity and torque, following error, error
//!   code, mode display) on 0x1600 / 0x1A00;
//! - synchronisation through 0x1C32:01 / 0x1C32:02 (ETG.1020), DC SYNC0 or free run, any cycle
//!   from 125 µs to 100 ms in 1 µs steps;
//! - the standard objects with their CiA 301 / CiA 402 types, for type inference only: an
//!   unknown device need not have them;
//! - no start-up SDOs, no output defaults, no cycle counter, no complete access, no ESI file.

use super::od_table::*;
use super::profile::{CycleTimeObject, CycleTimes, DriveProfile, IdentityMatch, SyncSpec, Units};
use crate::cia402::DriveCaps;
use crate::cia402::VelocityUnit;
use crate::drives::profile::EtherCat;
use crate::od::{EntryDesc, ObjectAddress, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange, RequiredObjects};

const RX_RANGES: &[PdoRange] = &[PdoRange::new(0x1600, 0x17FF, 255)];
const TX_RANGES: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1BFF, 255)];

/// The standard ranges and no further limits (the SyncManager length is the only bound the
/// ESC gives: 1024 bytes here, beyond any CiA 402 drive's process data).
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "generic CiA 402 drive",
    rx: DirectionLimits {
        pdos: RX_RANGES,
        max_assigned: 255,
        max_entries: 1024,
        max_bytes: 1024,
    },
    tx: DirectionLimits {
        pdos: TX_RANGES,
        max_assigned: 255,
        max_entries: 1024,
        max_bytes: 1024,
    },
    assignment_writable: true,
};

/// The recommended cyclic mapping (the same as the known drives'): output 13 bytes, input 19.
pub const CYCLIC_MAPPING: Mapping = Mapping::fixed(CYCLIC_RX, CYCLIC_TX);
const CYCLIC_RX: &[Pdo] = &[Pdo::fixed(
    0x1600,
    &[
        PdoEntry::new(0x6040, 0, 16),
        PdoEntry::new(0x607A, 0, 32),
        PdoEntry::new(0x60FF, 0, 32),
        PdoEntry::new(0x6071, 0, 16),
        PdoEntry::new(0x6060, 0, 8),
    ],
)];
const CYCLIC_TX: &[Pdo] = &[Pdo::fixed(
    0x1A00,
    &[
        PdoEntry::new(0x6041, 0, 16),
        PdoEntry::new(0x6064, 0, 32),
        PdoEntry::new(0x606C, 0, 32),
        PdoEntry::new(0x6077, 0, 16),
        PdoEntry::new(0x60F4, 0, 32),
        PdoEntry::new(0x603F, 0, 16),
        PdoEntry::new(0x6061, 0, 8),
    ],
)];

/// The power-on mapping of an unknown drive is unknown: empty (the master reads it back).
pub const DEFAULT_MAPPING: Mapping = Mapping::fixed(&[], &[]);

const CONTROLWORD: ObjectAddress = ObjectAddress::new(0x6040, 0);
const SW_ONLY: &[ObjectAddress] = &[ObjectAddress::new(0x6041, 0)];

/// The CiA 402 minimum per mode: controlword and statusword plus the mode's set-point.
pub const REQUIRED_OBJECTS: &[RequiredObjects] = &[
    RequiredObjects {
        mode: 8,
        mode_name: "csp",
        rx: &[CONTROLWORD, ObjectAddress::new(0x607A, 0)],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: 9,
        mode_name: "csv",
        rx: &[CONTROLWORD, ObjectAddress::new(0x60FF, 0)],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: 10,
        mode_name: "cst",
        rx: &[CONTROLWORD, ObjectAddress::new(0x6071, 0)],
        tx: SW_ONLY,
    },
];

macro_rules! var {
    ($index:literal, $name:literal, $ty:expr, $acc:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[EntryDesc::new(0, $name, $ty, $acc)],
        }
    };
}

/// The standard objects with their CiA 301 / CiA 402 types and access, for type inference.
pub static DICTIONARY: &[ObjectDesc] = &[
    var!(0x1000, "Device type", U32, RO),
    var!(0x1001, "Error register", U8, RO),
    ObjectDesc {
        index: 0x1018,
        name: "Identity object",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Vendor ID", U32, RO),
            EntryDesc::new(2, "Product code", U32, RO),
            EntryDesc::new(3, "Revision number", U32, RO),
            EntryDesc::new(4, "Serial number", U32, RO),
        ],
    },
    ObjectDesc {
        index: 0x1C32,
        name: "SM output parameter",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Synchronization type", U16, RW_PREOP),
            EntryDesc::new(2, "Cycle time", U32, RW_PREOP),
        ],
    },
    var!(0x603F, "Error code", U16, RO_TX),
    var!(0x6040, "Controlword", U16, RW_RX),
    var!(0x6041, "Statusword", U16, RO_TX),
    var!(0x605A, "Quick stop option code", I16, RW),
    var!(0x605B, "Shutdown option code", I16, RW),
    var!(0x605C, "Disable operation option code", I16, RW),
    var!(0x605D, "Halt option code", I16, RW),
    var!(0x605E, "Fault reaction option code", I16, RW),
    var!(0x6060, "Modes of operation", I8, RW_RX),
    var!(0x6061, "Modes of operation display", I8, RO_TX),
    var!(0x6064, "Position actual value", I32, RO_TX),
    var!(0x6065, "Following error window", U32, RW),
    var!(0x6066, "Following error time out", U16, RW),
    var!(0x606C, "Velocity actual value", I32, RO_TX),
    var!(0x6071, "Target torque", I16, RW_RX),
    var!(0x6077, "Torque actual value", I16, RO_TX),
    var!(0x607A, "Target position", I32, RW_RX),
    var!(0x607F, "Max profile velocity", U32, RW),
    var!(0x6085, "Quick stop deceleration", U32, RW),
    var!(0x60B1, "Velocity offset", I32, RW_RX),
    var!(0x60B2, "Torque offset", I16, RW_RX),
    ObjectDesc {
        index: 0x60C2,
        name: "Interpolation time period",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Interpolation time period value", U8, RW),
            EntryDesc::new(2, "Interpolation time index", I8, RW),
        ],
    },
    var!(0x60F4, "Following error actual value", I32, RO_TX),
    var!(0x60FF, "Target velocity", I32, RW_RX),
    var!(0x6502, "Supported drive modes", U32, RO),
];

/// The other standard CiA 402 objects a drive may have, with their types and PDO mapping as
/// CiA 402-2 (IEC 61800-7-201) defines them: where a vendor file's dictionary leaves one out
/// (files are often partial: "this profile section is optional"), a profile built from it takes
/// the standard description ([`standard_object`]), and the drive itself says at start-up if it
/// does not have the object (an SDO abort naming it).
pub static STANDARD_EXTRA: &[ObjectDesc] = &[
    var!(0x6062, "Position demand value", I32, RO_TX),
    var!(0x6063, "Position actual internal value", I32, RO_TX),
    var!(0x6067, "Position window", U32, RW),
    var!(0x6068, "Position window time", U16, RW),
    var!(0x606B, "Velocity demand value", I32, RO_TX),
    var!(0x606D, "Velocity window", U16, RW),
    var!(0x606E, "Velocity window time", U16, RW),
    var!(0x606F, "Velocity threshold", U16, RW),
    var!(0x6070, "Velocity threshold time", U16, RW),
    var!(0x6072, "Max torque", U16, RW_RX),
    var!(0x6073, "Max current", U16, RW),
    var!(0x6074, "Torque demand", I16, RO_TX),
    var!(0x6075, "Motor rated current", U32, RW),
    var!(0x6076, "Motor rated torque", U32, RW),
    var!(0x6078, "Current actual value", I16, RO_TX),
    var!(0x6079, "DC link circuit voltage", U32, RO_TX),
    var!(0x607C, "Home offset", I32, RW),
    ObjectDesc {
        index: 0x607D,
        name: "Software position limit",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Min position limit", I32, RW),
            EntryDesc::new(2, "Max position limit", I32, RW),
        ],
    },
    var!(0x6080, "Max motor speed", U32, RW_RX),
    var!(0x6081, "Profile velocity", U32, RW_RX),
    var!(0x6083, "Profile acceleration", U32, RW_RX),
    var!(0x6084, "Profile deceleration", U32, RW_RX),
    var!(0x6086, "Motion profile type", I16, RW),
    var!(0x6087, "Torque slope", U32, RW_RX),
    var!(0x6098, "Homing method", I8, RW_RX),
    ObjectDesc {
        index: 0x6099,
        name: "Homing speeds",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Speed during search for switch", U32, RW_RX),
            EntryDesc::new(2, "Speed during search for zero", U32, RW_RX),
        ],
    },
    var!(0x609A, "Homing acceleration", U32, RW_RX),
    var!(0x60B0, "Position offset", I32, RW_RX),
    var!(0x60B8, "Touch probe function", U16, RW_RX),
    var!(0x60B9, "Touch probe status", U16, RO_TX),
    var!(0x60BA, "Touch probe 1 positive edge", I32, RO_TX),
    var!(0x60BB, "Touch probe 1 negative edge", I32, RO_TX),
    var!(0x60BC, "Touch probe 2 positive edge", I32, RO_TX),
    var!(0x60BD, "Touch probe 2 negative edge", I32, RO_TX),
    ObjectDesc {
        index: 0x60C2,
        name: "Interpolation time period",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Interpolation time period value", U8, RW),
            EntryDesc::new(2, "Interpolation time index", I8, RW),
        ],
    },
    var!(0x60E0, "Positive torque limit value", U16, RW_RX),
    var!(0x60E1, "Negative torque limit value", U16, RW_RX),
    var!(0x60FC, "Position demand internal value", I32, RO_TX),
    var!(0x60FD, "Digital inputs", U32, RO_TX),
    ObjectDesc {
        index: 0x60FE,
        name: "Digital outputs",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO),
            EntryDesc::new(1, "Physical outputs", U32, RW_RX),
            EntryDesc::new(2, "Bit mask", U32, RW),
        ],
    },
];

/// The standard description of a CiA 402 (or CiA 301) object: [`DICTIONARY`], then
/// [`STANDARD_EXTRA`].
pub fn standard_object(index: u16) -> Option<&'static ObjectDesc> {
    DICTIONARY
        .iter()
        .chain(STANDARD_EXTRA.iter())
        .find(|o| o.index == index)
}

/// ETG.1020 synchronisation: 0x1C32:01 (2 = DC SYNC0, 0 = free run) and the cycle in 0x1C32:02.
pub const SYNC: SyncSpec = SyncSpec {
    free_run: true,
    dc_sync0: true,
    cycle_times: CycleTimes::Range {
        min_ns: 125_000,
        max_ns: 100_000_000,
        step_ns: 1_000,
    },
    assign_activate: 0x0300,
    sync_type_object: Some(ObjectAddress::new(0x1C32, 1)),
    cycle_time_object: Some(CycleTimeObject::Nanoseconds(ObjectAddress::new(0x1C32, 2))),
};

/// Units are the drive's own: increments, increments per second, per mille of rated torque.
pub const UNITS: Units = Units {
    position_name: "increment (drive-defined)",
    position_per_rev: 1.0,
    velocity: VelocityUnit::PositionPerSecond,
    // 0.1 % of rated torque (0x6076).
    torque_per_mille: 1.0,
    profile: None,
};

/// The generic CiA 402 profile (see the [module documentation](self)). Its identity matches no
/// device: it is chosen by [`super::identify`] with `allow_generic`, or by its key.
pub static GENERIC_CIA402: DriveProfile = DriveProfile {
    name: "generic CiA 402 drive",
    vendor: "any",
    caps: DriveCaps::CIA402,
    dictionary: DICTIONARY,
    units: UNITS,
    bus: EtherCat {
        key: "generic-cia402",
        identity: IdentityMatch {
            vendor_id: 0,
            product_code: 0,
        },
        revision: 0,
        pdo_limits: PDO_LIMITS,
        default_mapping: DEFAULT_MAPPING,
        cyclic_mapping: CYCLIC_MAPPING,
        mode_mappings: &[],
        required_objects: REQUIRED_OBJECTS,
        startup: &[],
        init_cmds: &[],
        output_defaults: &[],
        cycle_counter: None,
        sync: SYNC,
        complete_access: false,
        esi: "",
        zero_speed_flag: None,
        mode_selector: None,
        ratings: crate::drives::Ratings::NONE,
    },
};
