//! Schneider Electric Lexium MDrive (LMDOA42x/57x/85x integrated stepper), CANopen.
//!
//! Source: Schneider Electric Motion USA, *CANopen Fieldbus manual for Lexium MDrive*, V1.00
//! (09.2014); `§x.y` cite its sections. Condensed in
//! `../shared/reference/drive-lexium-mdrive.md`.
//!
//! ⚠ This manual is full of wrong headings and indices (6082h named "Polarity", 60F8h shown as
//! 60FFh, 6068h shown as 6066h, 2002h shown as 2003h, 2019h as 2018h, 1014h as "10142h", …).
//! Indices here follow the tables of §8.2–8.4 and the reference file's ⚠ notes; every such
//! reading is listed in the MANUAL GAP / DISCREPANCY section at the end.
//!
//! Behaviour a master must know (all of it data below):
//! - Defaults: node-ID **41h**, **1 Mbit/s**; node-ID and bit rate by LSS (7E5h/7E4h) or the
//!   vendor utility.
//! - Only **RPDO1 and TPDO1 are valid** at power-on; all PDOs type 255; 8 entries per PDO.
//! - **NMT Stop or Reset communication while the power stage is enabled → error class 2**:
//!   quick stop, then power stage off, state Fault (§3.6.1).
//! - Cannot produce SYNC; 1006h and 1016h are absent from the dictionary although the text
//!   mentions them (⚠); heartbeat producer and node guarding only. Life-guarding timeout →
//!   Fault.
//! - 6502h advertises pp, pv, hm only (0000 0025h); tq exists on **closed-loop** models
//!   ([`PROFILE_CLOSED_LOOP`]); csp is described but has no 6060h value.
//! - Units: microsteps, 51,200 per revolution; steps/s; steps/s² (true rates).
//! - EMCY byte 5 = PDO number, bytes 6–7 = vendor code.
//! - Statusword bit 4 (DC bus) must be 1 before Ready to switch on; bridge and brake settle
//!   times (2034h/2035h) delay Operation enabled. Home and limit inputs must be assigned
//!   (2002h) before homing.

use crate::can::profile::od::{
    I8, I16, I32, RO, RO_T, RW, RW_R, STR, U8, U16, U32, count, e, error_history, i, pdo_comm,
    pdo_map, store_record, u,
};
use crate::can::profile::{
    AccelUnit, Alarm, CanDriveProfile, CanOpen, CanPdoProfile, CommSupport, EmcyFormat,
    EnableConditions, EnabledNmtReaction, HomingSupport, Identity, PdoDefault, TorqueSlopeUnit,
    TransmissionTypes, Units, VelocityUnit,
};
use crate::cia402::{DriveCaps, ErrorEntry, ProfileUnits, QuickStopOption, SupportedModes};
use crate::od::{ConstValue, EntryDesc, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, PdoEntry, PdoLimits, PdoRange};

// ============================================================================================
// Identity (§8.5.1, §8.5.16, §5.2)
// ============================================================================================

/// Vendor ID, 1018h:01 (§8.5.16). ⚠ §5.6 gives 0800005Ah as the LSS vendor ID: read 1018h
/// before using LSS selective.
pub const VENDOR_ID: u32 = 0x0000_021B;
/// Product code, 1018h:02.
pub const PRODUCT: u32 = 0x0000_0000;
/// Revision, 1018h:03.
pub const REVISION: u32 = 0x0000_0507;
/// Device type 1000h: 0044 0192h (stepper motor, DSP402).
pub const DEVICE_TYPE: u32 = 0x0044_0192;
/// 1008h.
pub const DEVICE_NAME: &str = "CANopen Lexium MDrive Motion Control Node";

/// Identity (1018h sub-indices 1–4; the serial number is per device).
pub const IDENTITY: Identity = Identity {
    vendor_id: VENDOR_ID,
    products: &[(PRODUCT, "Lexium MDrive")],
    device_type: DEVICE_TYPE,
    other_device_types: &[],
    revision: Some(REVISION),
};

// ============================================================================================
// Alarms (§7, Table 7.2)
// ============================================================================================

/// Alarm numbers (EMCY bytes 6–7, the upper word of 1003h entries; CAN-side codes without
/// additional info use the code itself).
pub mod alarm {
    /// 8130h life guard or heartbeat error.
    pub const GUARDING: u16 = 0x8130;
    /// 4210h with additional info 8h: over-temperature fault.
    pub const OVER_TEMPERATURE: u16 = 0x0008;
    /// FF01h with additional info 1h: motor idle during a commanded move (stall).
    pub const STALL: u16 = 0x0001;
    /// **MANUAL GAP** → \[REC\] error class 2 after NMT Stop / Reset communication while the
    /// power stage is enabled: the manual names no code; 8100h ("communication") is used.
    pub const NMT_WHILE_ENABLED: u16 = 0x8100;
}

const fn al(number: u16, code: u16, register: u8, text: &'static str, fault: bool) -> Alarm {
    Alarm {
        number,
        code,
        register,
        name: "Lexium",
        text,
        fault,
    }
}

/// The error codes of Table 7.2 (with the temperature codes of 2018h/2019h).
pub const ALARMS: &[Alarm] = &[
    al(0x8110, 0x8110, 0x11, "CAN overrun", false),
    al(0x8120, 0x8120, 0x11, "CAN error passive", false),
    al(
        alarm::GUARDING,
        0x8130,
        0x11,
        "life guard or heartbeat error",
        true,
    ),
    al(0x8140, 0x8140, 0x11, "recovered from bus-off", false),
    al(0x8141, 0x8141, 0x11, "bus-off occurred", true),
    al(
        0x8210,
        0x8210,
        0x11,
        "PDO not processed, length error",
        false,
    ),
    al(
        alarm::OVER_TEMPERATURE,
        0x4210,
        0x09,
        "over-temperature error",
        true,
    ),
    al(
        0x0016,
        0x4210,
        0x09,
        "pending over-temperature warning",
        false,
    ),
    al(
        alarm::STALL,
        0xFF01,
        0x81,
        "motor idle during commanded move",
        true,
    ),
    al(
        0x0002,
        0xFF01,
        0x81,
        "motor should be idle (additional info 2h-8h)",
        true,
    ),
    al(0x0009, 0xFF01, 0x81, "undershot warning", false),
    al(
        alarm::NMT_WHILE_ENABLED,
        0x8100,
        0x11,
        "error class 2: NMT stop or reset communication while the power stage was enabled",
        true,
    ),
];

/// 603Fh names.
pub const ERROR_TABLE: &[ErrorEntry] = &[
    ErrorEntry::exact(0x8141, "bus-off", "bus-off occurred"),
    ErrorEntry::exact(0x4210, "temperature", "over-temperature (2018h/2019h)"),
    ErrorEntry::exact(
        0xFF01,
        "motion",
        "motor idle during move / should be idle / undershot",
    ),
];

// ============================================================================================
// CiA 402 capabilities (§6.1–6.4)
// ============================================================================================

/// 6502h = 0000 0025h: pp, pv, hm (§8.4).
pub const SUPPORTED_MODES: SupportedModes = SupportedModes::from_raw(0x0000_0025);
/// The closed-loop models also run tq (§6.8, §6.4 example) although 6502h does not say so:
/// pp, pv, tq, hm.
pub const SUPPORTED_MODES_CLOSED_LOOP: SupportedModes = SupportedModes::from_raw(0x0000_002D);

/// The capability set: no state skipping (Table 6.3); transition 16 as in CiA 402 ("enable
/// operation 4, 16"); quick-stop codes 0–6, default 2 (§6.3); statusword bit 9 = 0 means "does
/// not execute commands" (§6.2, remote gates); modes switch on the fly (§6.4).
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: true,
    quick_stop_options: &[
        QuickStopOption::DISABLE_DRIVE,
        QuickStopOption::SLOW_DOWN_RAMP,
        QuickStopOption::QUICK_STOP_RAMP,
        QuickStopOption::CURRENT_LIMIT,
        QuickStopOption::VOLTAGE_LIMIT,
        QuickStopOption::SLOW_DOWN_RAMP_STAY,
        QuickStopOption::QUICK_STOP_RAMP_STAY,
    ],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: true,
    supported_modes: SUPPORTED_MODES,
    error_table: ERROR_TABLE,
    csp_start_edge: false,
    homing_failure: "",
    home_offset_set_by_drive: None,
    sdo_refused_while_rx_mapped: None,
    pp_target_range: None,
};

/// The closed-loop capability set: as [`CAPS`] plus tq.
pub const CAPS_CLOSED_LOOP: DriveCaps = DriveCaps {
    supported_modes: SUPPORTED_MODES_CLOSED_LOOP,
    ..CAPS
};

// ============================================================================================
// PDOs (§3.3, §8.5.18–21)
// ============================================================================================

const RX_RANGES: &[PdoRange] = &[PdoRange::new(0x1600, 0x1603, 8)];
const TX_RANGES: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A03, 8)];

/// Four PDOs per direction, up to 8 entries each ("up to 8 bytes of 8 different objects"),
/// 8 bytes each.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "Lexium MDrive",
    rx: DirectionLimits {
        pdos: RX_RANGES,
        max_assigned: 4,
        max_entries: 32,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: TX_RANGES,
        max_assigned: 4,
        max_entries: 32,
        max_bytes: 32,
    },
    assignment_writable: true,
};

const CW: PdoEntry = PdoEntry::new(0x6040, 0, 16);
const SW: PdoEntry = PdoEntry::new(0x6041, 0, 16);

const fn pdo(
    number: u8,
    cob_id: u32,
    event_timer: u16,
    mapping: &'static [PdoEntry],
) -> PdoDefault {
    PdoDefault {
        number,
        cob_id,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer,
        mapping,
    }
}

/// Power-on RPDOs (§3.3.3, §8.5.19): only RPDO1 valid. ⚠ RPDO4 maps 6071h (INTEGER16) with
/// length 20h as the manual prints it; remap before use.
pub const DEFAULT_RPDOS: &[PdoDefault] = &[
    pdo(1, 0x200, 0, &[CW]),
    pdo(2, 0x8000_0300, 0, &[CW, PdoEntry::new(0x607A, 0, 32)]),
    pdo(3, 0x8000_0400, 0, &[CW, PdoEntry::new(0x60FF, 0, 32)]),
    pdo(4, 0x8000_0500, 0, &[CW, PdoEntry::new(0x6071, 0, 32)]),
];

/// Power-on TPDOs: only TPDO1 valid; TPDO2 and TPDO3 have a 100 ms event timer.
pub const DEFAULT_TPDOS: &[PdoDefault] = &[
    pdo(1, 0x180, 0, &[SW]),
    pdo(2, 0x8000_0280, 100, &[SW, PdoEntry::new(0x6064, 0, 32)]),
    pdo(3, 0x8000_0380, 100, &[SW, PdoEntry::new(0x606C, 0, 32)]),
    pdo(4, 0x8000_0480, 0, &[SW]),
];

/// RPDO types (Table 8.8): 0–240 applied at the next SYNC, 254/255 on reception.
pub const RPDO_TYPES: TransmissionTypes = TransmissionTypes {
    sync_acyclic: true,
    sync_cyclic: true,
    rtr_sync: false,
    rtr_event: false,
    event_manufacturer: true,
    event_profile: true,
};

/// The PDO profile.
pub const PDO: CanPdoProfile = CanPdoProfile {
    limits: PDO_LIMITS,
    max_pdo_bytes: 8,
    rpdo_types: RPDO_TYPES,
    tpdo_types: TransmissionTypes::ALL,
    rpdo_comm_subs: 5,
    default_rpdos: DEFAULT_RPDOS,
    default_tpdos: DEFAULT_TPDOS,
};

// ============================================================================================
// Object dictionary (§8.2–8.6)
// ============================================================================================

macro_rules! var {
    ($index:literal, $name:literal, $dt:expr, $acc:expr, $def:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[e(0, $name, $dt, $acc, $def)],
        }
    };
}

macro_rules! rec {
    ($index:literal, $name:literal, $code:expr, $entries:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: $code,
            entries: $entries,
        }
    };
}

const ARRAY: ObjectCode = ObjectCode::Array;
const RECORD: ObjectCode = ObjectCode::Record;

static ERRORS_1003: [EntryDesc; 5] = error_history::<5>();
static STORE_1010: [EntryDesc; 5] = store_record::<5>();
static RESTORE_1011: [EntryDesc; 5] = store_record::<5>();
static RPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x200, 255, 0, 0);
static RPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x8000_0300, 255, 0, 0);
static RPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x8000_0400, 255, 0, 0);
static RPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x8000_0500, 255, 0, 0);
static TPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x180, 255, 0, 0);
static TPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x8000_0280, 255, 0, 100);
static TPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x8000_0380, 255, 0, 100);
static TPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x8000_0480, 255, 0, 0);
static RPDO1_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6040_0010]);
static RPDO2_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6040_0010, 0x607A_0020]);
static RPDO3_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6040_0010, 0x60FF_0020]);
static RPDO4_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6040_0010, 0x6071_0020]);
static TPDO1_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6041_0010]);
static TPDO2_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6041_0010, 0x6064_0020]);
static TPDO3_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6041_0010, 0x606C_0020]);
static TPDO4_MAP: [EntryDesc; 9] = pdo_map::<9>(&[0x6041_0010]);

/// The object dictionary of §8.2–8.6 with the mapping flags of Table 3.9. Sorted by index.
pub static DICTIONARY: &[ObjectDesc] = &[
    var!(0x1000, "Device type", U32, RO, u(DEVICE_TYPE as u64)),
    var!(0x1001, "Error register", U8, RO, u(0)),
    rec!(0x1003, "Pre-defined error field", ARRAY, &ERRORS_1003),
    var!(0x1005, "COB-ID SYNC", U32, RW, u(0x80)),
    var!(0x1007, "Synchronous window length", U32, RW, u(0)),
    ObjectDesc {
        index: 0x1008,
        name: "Manufacturer device name",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer device name", STR, RO)
            .bits(41 * 8)
            .default(ConstValue::Str(DEVICE_NAME))],
    },
    ObjectDesc {
        index: 0x1009,
        name: "Manufacturer hardware version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer hardware version", STR, RO)
            .bits(5 * 8)
            .default(ConstValue::Str("V1.00"))],
    },
    ObjectDesc {
        index: 0x100A,
        name: "Manufacturer software version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer software version", STR, RO)
            .bits(5 * 8)
            .default(ConstValue::Str("V5.48"))],
    },
    var!(0x100C, "Guard time", U16, RW, u(0)),
    var!(0x100D, "Life time factor", U8, RW, u(0)),
    rec!(0x1010, "Store parameters", ARRAY, &STORE_1010),
    rec!(0x1011, "Restore default parameters", ARRAY, &RESTORE_1011),
    var!(0x1012, "COB-ID time stamp", U32, RW, u(0x100)),
    var!(0x1014, "COB-ID EMCY", U32, RW, u(0x80)),
    var!(0x1015, "Inhibit time EMCY", U16, RW, u(0)),
    var!(0x1017, "Producer heartbeat time", U16, RW, u(0)),
    rec!(
        0x1018,
        "Identity object",
        RECORD,
        &[
            count(4, RO),
            e(1, "Vendor ID", U32, RO, u(VENDOR_ID as u64)),
            e(2, "Product code", U32, RO, u(PRODUCT as u64)),
            e(3, "Revision number", U32, RO, u(REVISION as u64)),
            e(4, "Serial number", U32, RO, u(EMU_SERIAL as u64)),
        ]
    ),
    rec!(0x1400, "RPDO1 communication parameter", RECORD, &RPDO1_COMM),
    rec!(0x1401, "RPDO2 communication parameter", RECORD, &RPDO2_COMM),
    rec!(0x1402, "RPDO3 communication parameter", RECORD, &RPDO3_COMM),
    rec!(0x1403, "RPDO4 communication parameter", RECORD, &RPDO4_COMM),
    rec!(0x1600, "RPDO1 mapping parameter", RECORD, &RPDO1_MAP),
    rec!(0x1601, "RPDO2 mapping parameter", RECORD, &RPDO2_MAP),
    rec!(0x1602, "RPDO3 mapping parameter", RECORD, &RPDO3_MAP),
    rec!(0x1603, "RPDO4 mapping parameter", RECORD, &RPDO4_MAP),
    rec!(0x1800, "TPDO1 communication parameter", RECORD, &TPDO1_COMM),
    rec!(0x1801, "TPDO2 communication parameter", RECORD, &TPDO2_COMM),
    rec!(0x1802, "TPDO3 communication parameter", RECORD, &TPDO3_COMM),
    rec!(0x1803, "TPDO4 communication parameter", RECORD, &TPDO4_COMM),
    rec!(0x1A00, "TPDO1 mapping parameter", RECORD, &TPDO1_MAP),
    rec!(0x1A01, "TPDO2 mapping parameter", RECORD, &TPDO2_MAP),
    rec!(0x1A02, "TPDO3 mapping parameter", RECORD, &TPDO3_MAP),
    rec!(0x1A03, "TPDO4 mapping parameter", RECORD, &TPDO4_MAP),
    // --- 2000h group (§8.3, §8.6) ------------------------------------------------------------
    rec!(
        0x2002,
        "Configure input switches",
        ARRAY,
        &[
            count(4, RO),
            e(1, "Home switch mask", U8, RW, u(0)),
            e(2, "Positive limit mask", U8, RW, u(0)),
            e(3, "Negative limit mask", U8, RW, u(0)),
            e(4, "Inhibit switch mask", U8, RW, u(0)),
        ]
    ),
    rec!(
        0x2020,
        "Software limits as hardware",
        RECORD,
        &[
            count(2, RO),
            e(1, "Limit flags", U8, RO, u(0)),
            e(2, "Limit mask", U8, RW, u(0x03)),
        ]
    ),
    rec!(
        0x2022,
        "Actual position software limit",
        RECORD,
        &[
            count(2, RO),
            e(1, "Negative limit", I32, RW, i(i32::MIN as i64)),
            e(2, "Positive limit", I32, RW, i(i32::MAX as i64)),
        ]
    ),
    var!(0x2098, "Homing configuration", U8, RW, u(1)),
    var!(0x2204, "Run current", U8, RW, u(50)),
    var!(0x2205, "Hold current", U8, RW, u(5)),
    var!(0x2701, "hMTechnology enable", U8, RW, u(0)),
    var!(0x2704, "Torque speed", U8, RW, u(98)),
    var!(0x2740, "Clear locked rotor", U8, RW_R, u(0)),
    var!(0x2741, "hMT status", U8, RO_T, u(0x80)),
    // --- 6000h group (§6, §8.4) --------------------------------------------------------------
    // DISCREPANCY (mappable): see the end of this file.
    var!(0x6007, "Abort connection option code", I16, RW_R, i(0)),
    var!(0x603F, "Error code", U16, RO_T, u(0)),
    var!(0x6040, "Controlword", U16, RW_R, u(0)),
    var!(0x6041, "Statusword", U16, RO_T, u(0)),
    var!(0x605A, "Quick stop option code", I16, RW, i(2)),
    var!(0x605B, "Shutdown option code", I16, RW, i(0)),
    var!(0x605C, "Disable operation option code", I16, RW, i(0)),
    var!(0x605D, "Halt option code", I16, RW, i(2)),
    var!(0x605E, "Fault reaction option code", I16, RW, i(2)),
    var!(0x6060, "Modes of operation", I8, RW_R, i(1)),
    var!(0x6061, "Modes of operation display", I8, RO_T, i(1)),
    var!(0x6062, "Position demand value", I32, RO_T, i(0)),
    var!(0x6063, "Position actual value internal", I32, RO_T, i(0)),
    var!(0x6064, "Position actual value", I32, RO_T, i(0)),
    var!(0x6065, "Following error window", U32, RW, u(0x0000_0512)),
    var!(0x6066, "Following error timeout", U16, RW, u(0)),
    var!(0x6067, "Position window", U32, RW, u(0x0FFF_FFFF)),
    var!(0x6068, "Position window time", U16, RW, u(0)),
    var!(0x606C, "Velocity actual value", I32, RO_T, i(0)),
    var!(0x6071, "Target torque", I16, RW_R, i(0)),
    var!(0x6077, "Torque actual value", I16, RO_T, i(0)),
    var!(0x607A, "Target position", I32, RW_R, i(0)),
    var!(0x607C, "Homing offset", I32, RW, i(0)),
    var!(0x607E, "Polarity", U8, RW_R, u(0)),
    var!(0x6081, "Profile velocity", U32, RW_R, u(512_000)),
    var!(0x6082, "End velocity", U32, RW_R, u(51_200)),
    var!(0x6083, "Profile acceleration", U32, RW_R, u(100_000)),
    var!(0x6084, "Profile deceleration", U32, RW_R, u(100_000)),
    var!(0x6085, "Quick stop deceleration", U32, RW, u(200_000)),
    var!(0x6086, "Motion profile type", I16, RW_R, i(0)),
    var!(0x6087, "Torque slope", U32, RW, u(1_000)),
    rec!(
        0x608F,
        "Position encoder resolution",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Encoder increments", U32, RW, u(2048)),
            e(2, "Motor revolutions", U32, RW, u(1)),
        ]
    ),
    rec!(
        0x6092,
        "Feed constant",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Feed", U32, RW, u(51_200)),
            e(2, "Shaft revolutions", U32, RW, u(1)),
        ]
    ),
    var!(0x6098, "Homing method", I8, RW, i(0)),
    rec!(
        0x6099,
        "Homing speeds",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Fast homing speed", U32, RW, u(102_400)),
            e(2, "Slow homing speed", U32, RW, u(6_400)),
        ]
    ),
    rec!(
        0x60C2,
        "Interpolation time period",
        RECORD,
        &[
            count(2, RO),
            e(1, "Interpolation time period", U8, RW, u(1)),
            e(2, "Interpolation time index", I8, RW, i(-3)),
        ]
    ),
    var!(0x60F8, "Maximum slippage", I32, RW, i(512)),
    var!(0x60FD, "Digital inputs", U32, RO_T, u(0)),
    rec!(
        0x60FE,
        "Digital outputs",
        ARRAY,
        &[count(1, RO), e(1, "Digital outputs", U32, RW_R, u(0))]
    ),
    var!(0x60FF, "Target velocity", I32, RW_R, i(0)),
    var!(0x6402, "Motor type", U16, RO, u(9)),
    var!(0x6502, "Supported drive modes", U32, RO, u(0x0000_0025)),
];

// ============================================================================================
// Units, enable conditions, homing, communication
// ============================================================================================

/// Units (§6.5, §6.11): microsteps, 51,200 per motor revolution (6092h = 51200/1);
/// velocities in steps/s; accelerations in steps/s²; torque ‰ of rated, slope ‰/s.
pub const UNITS: Units = Units {
    position_name: "microstep",
    position_per_rev: 51_200.0,
    velocity: VelocityUnit::PositionPerSecond,
    torque_per_mille: 1.0,
    profile: Some(ProfileUnits {
        profile_velocity: VelocityUnit::PositionPerSecond,
        homing_velocity: VelocityUnit::PositionPerSecond,
        acceleration: AccelUnit::PositionPerSecond2,
        torque_slope: TorqueSlopeUnit::PerMillePerSecond,
    }),
};

/// Enable preconditions: statusword bit 4 (DC bus OK) must be 1 before Ready to switch on.
pub const ENABLE: EnableConditions = EnableConditions {
    remote_required: true,
    voltage_required: true,
    needs_operational: false,
    settings: &[],
    targets_cleared_on_enable: &[],
    notes: "bridge-on settle time 2034h and brake settle times 2035h delay Operation \
            enabled; home and limit inputs must be assigned in 2002h before homing or limits \
            act",
};

/// Homing (§6.7.5): 0 (none, default) and 1–35 except the reserved 15, 16, 31, 32. Index
/// methods need the encoder of closed-loop models.
pub const HOMING: HomingSupport = HomingSupport {
    methods: &[
        0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26,
        27, 28, 29, 30, 33, 34, 35,
    ],
    default_method: 0,
    index_pulse: false,
};

/// Communication: guarding and heartbeat producer, no 1016h, no SYNC production, no 1006h
/// (⚠), 4 error-history entries, store sub-indices 01h–04h. No rate limit stated.
pub const COMM: CommSupport = CommSupport {
    guarding: true,
    heartbeat_consumers: 0,
    sync_producer: false,
    has_cycle_period: false,
    cycle_period_granularity_us: 0,
    error_history: 4,
    store_subs: 4,
    sdo_min_interval_us: 0,
    rpdo_min_interval_us: 0,
};

/// The Lexium MDrive profile (open-loop models: pp, pv, hm; no index pulse).
pub const PROFILE: CanDriveProfile = CanDriveProfile {
    name: "Lexium MDrive",
    vendor: "Schneider Electric",
    caps: CAPS,
    dictionary: DICTIONARY,
    units: UNITS,
    bus: CanOpen {
        source: "Schneider Electric CANopen Fieldbus manual for Lexium MDrive, V1.00 (09.2014)",
        identity: IDENTITY,
        default_node_id: Some(0x41),
        default_bitrate_kbit: 1000,
        bitrates_kbit: &[1000, 800, 500, 250, 125, 100, 50, 20, 10],
        modes_note: "6502h = 0000 0025h (pp, pv, hm); 6060h range 1, 3, 6, default 1. tq (4) is \
                     described for closed-loop models only and csp (§6.9) has no 6060h value",
        pdo: PDO,
        enable: ENABLE,
        homing: HOMING,
        emcy: EmcyFormat::PdoAndVendorCode,
        alarms: ALARMS,
        vendor_abort_codes: &[],
        comm: COMM,
        nmt_stop_while_enabled: EnabledNmtReaction::QuickStopThenFault(alarm::NMT_WHILE_ENABLED),
        nmt_reset_while_enabled: EnabledNmtReaction::QuickStopThenFault(alarm::NMT_WHILE_ENABLED),
        // CiA 402: controlword bit 4 enables interpolation in ip.
        ip_needs_enable_bit: true,
        // Statusword bit 12 in pv: zero speed.
        pv_zero_speed_bit: true,
    },
};

/// The closed-loop models (encoder, hMTechnology): tq and the index-pulse homing methods too.
pub const PROFILE_CLOSED_LOOP: CanDriveProfile = CanDriveProfile {
    name: "Lexium MDrive (closed loop)",
    caps: CAPS_CLOSED_LOOP,
    bus: CanOpen {
        homing: HomingSupport {
            index_pulse: true,
            ..HOMING
        },
        ..PROFILE.bus
    },
    ..PROFILE
};

// ============================================================================================
// MANUAL GAP / [REC] / DISCREPANCY — every value above that is not vendor fact
// ============================================================================================
//
// - MANUAL GAP: the error code of the class-2 error after NMT Stop / Reset communication while
//   enabled: [REC] 8100h (`alarm::NMT_WHILE_ENABLED`). Reset node is treated the same way.
// - MANUAL GAP: 1803h event timer (not stated): 0.
// - MANUAL GAP: 1018h:04 serial number (per device): `EMU_SERIAL`.
// - DISCREPANCY: 6502h says pp/pv/hm while §6.8 documents tq on closed-loop models:
//   `PROFILE_CLOSED_LOOP` adds tq to the capability set; the emulated 6502h reads 25h as the
//   manual prints it.
// - DISCREPANCY: 1003h sub 00h range 0–4 (§8.5.3) vs 0–254 (§7.3.2): 4 entries used.
// - DISCREPANCY: 6060h PDO-mappable per §8.4/Table 3.9, "No" in §6.4.1: mappable.
// - DISCREPANCY: 606Ch ro (§8.4) vs rw (§6.6.4): ro. 603Fh ro (§8.4) vs rw (§6.3.2): ro.
// - DISCREPANCY: 607Ch INT32 (§8.4) vs UINT32 (§6.7.4): INT32.
// - DISCREPANCY: RPDO4 default maps 6071h with length 20h (6071h is INTEGER16): kept as
//   printed; the PDO is invalid at power-on and the master always remaps.
// - DISCREPANCY: "6 PDOs, 3 receive and 3 transmit" (§3.3.3 text) vs 4 + 4 in every table:
//   4 + 4 used.
// - DISCREPANCY: headings 60F8h shown as 60FFh, 6068h as 6066h, 2002h as 2003h: the table
//   indices of §8.2–8.4 used.
// - 6065h default `0000 0512h` is printed in hex (= 1298); kept as printed.
// - DISCREPANCY: 6007h PDO-mappable "Yes" in its own description (§6.3.1), no PDO entry in the
//   §8.4 table and not in Table 3.9: mappable (RxPDO), as the object's own description says.
// - DISCREPANCY: which PDOs are valid at power-on. The object tables (§8.2) give every COB-ID
//   as base + node-ID without the invalid bit, and §3.4 says all 4 + 4 PDOs run; §3.3.3 says
//   only R_PDO1 and T_PDO1 are active (example "8000 04xxh": R_PDO3 not activated). Used:
//   §3.3.3 (PDOs 2–4 invalid at power-on, bit 31 set); the master writes every PDO it uses.

/// **MANUAL GAP** → \[REC\] 1018h:04 serial number of the emulated node (the manual's example
/// serial 341070398 = 1454523Eh, §5.6).
pub const EMU_SERIAL: u32 = 0x1454_523E;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::od::Dictionary;

    #[test]
    fn dictionary_is_consistent_and_sorted() {
        let d = Dictionary::new(DICTIONARY);
        assert!(d.is_sorted());
        assert_eq!(d.check(), Ok(()));
    }

    #[test]
    fn only_pdo1_valid_at_power_on() {
        let valid = |p: &PdoDefault| p.cob_id & 0x8000_0000 == 0;
        assert_eq!(DEFAULT_RPDOS.iter().filter(|p| valid(p)).count(), 1);
        assert_eq!(DEFAULT_TPDOS.iter().filter(|p| valid(p)).count(), 1);
    }
}
