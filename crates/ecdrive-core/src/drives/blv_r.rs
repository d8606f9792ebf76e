//! Oriental Motor BLV series R type driver (BLVD-KRD / BLVD-KBRD), CANopen.
//!
//! Source: *Brushless Motor BLV series R type Driver — CANopen communication profile*; `§x.y`
//! cite its sections, "App." its appendix object list (§9.1). Condensed in
//! `../shared/reference/drive-blv-r.md`. Conformance claimed: CiA DS301 V4.2.0, DSP402 V4.0.0.
//!
//! Behaviour a master must know (all of it data below):
//! - **Remote bit gate** (§6.1 note, §7.3.4): statusword bit 9 = 0 while the S-ON input is
//!   active or the support software operates the drive; the controlword is then ignored except
//!   quick stop, fault reset and halt ([`CAPS`] `remote_gates_controlword`).
//! - No transition 16 (§6.2); quick-stop codes −3…−1, 0, 1, 2, 5, 6 (default 2).
//! - Default mode pv (6060h = 3, stored); tq only from driver version 4.00 (6502h 2Dh instead of
//!   25h).
//! - Only 4 entries per PDO; RPDO transmission types 00h, FEh, FFh only (others abort
//!   0609 0030h); TPDO3/4 default to type 1 and all TPDOs to a 5 ms inhibit time.
//! - 603Fh = alarm code + FF00h; EMCY bytes 3–7 are zero.
//! - Motor excitation is tied to NMT Operational (§5.1 table).
//!
//! Every value the manual does not give is in the **MANUAL GAP / \[REC\]** section at the end.

use crate::can::profile::od::{
    I8, I16, I32, RO, RO_T, RW, RW_R, STR, U8, U16, U32, count, e, error_history, i, pdo_comm,
    pdo_map, store_record, u,
};
use crate::can::profile::{
    AccelUnit, Alarm, CanDriveProfile, CanOpen, CanPdoProfile, CommSupport, EmcyFormat,
    EnableConditions, EnabledNmtReaction, HomingSupport, Identity, PdoDefault, TorqueSlopeUnit,
    TransmissionTypes, Units, VelocityUnit,
};
use crate::cia402::{
    DriveCaps, ErrorEntry, ProfileUnits, QuickStopEnd, QuickStopOption, StopRamp, SupportedModes,
};
use crate::od::{EntryDesc, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, PdoEntry, PdoLimits, PdoRange};

// ============================================================================================
// Identity (§8.1, §8.3)
// ============================================================================================

/// Vendor ID, 1018h:01 (§8.1).
pub const VENDOR_ID: u32 = 0x0000_02BE;
/// Product code of the BLVD-KRD, 1018h:02.
pub const PRODUCT_KRD: u32 = 0x0000_13F7;
/// Product code of the BLVD-KBRD, 1018h:02.
pub const PRODUCT_KBRD: u32 = 0x0000_1430;
/// Device type 1000h (and single device type 67FFh): 0002 0192h.
pub const DEVICE_TYPE: u32 = 0x0002_0192;

/// Identity. 1018h has sub-indices 1 and 2 only (no revision, no serial number).
pub const IDENTITY: Identity = Identity {
    vendor_id: VENDOR_ID,
    products: &[(PRODUCT_KRD, "BLVD-KRD"), (PRODUCT_KBRD, "BLVD-KBRD")],
    device_type: DEVICE_TYPE,
    other_device_types: &[],
    revision: None,
};

// ============================================================================================
// CiA 402 capabilities (§6, §6.2, §8.3)
// ============================================================================================

/// Alarms (§4.5 EMCY table; 603Fh = alarm code + FF00h, §8.3). The CAN-side codes (81xxh,
/// 8210h, error register 11h) carry no alarm number: their `number` is the code itself.
pub const ALARMS: &[Alarm] = &[
    alarm(0xFF10, "alarm 10h", "position deviation"),
    alarm(0xFF20, "alarm 20h", "overcurrent"),
    alarm(0xFF21, "alarm 21h", "main circuit overheat"),
    alarm(0xFF22, "alarm 22h", "overvoltage"),
    alarm(0xFF25, "alarm 25h", "undervoltage"),
    alarm(0xFF26, "alarm 26h", "motor overheat"),
    alarm(0xFF28, "alarm 28h", "encoder error"),
    alarm(0xFF29, "alarm 29h", "internal circuit error"),
    alarm(0xFF2A, "alarm 2Ah", "encoder communication error"),
    alarm(0xFF30, "alarm 30h", "overload"),
    alarm(0xFF31, "alarm 31h", "overspeed"),
    alarm(0xFF41, "alarm 41h", "EEPROM error"),
    alarm(0xFF42, "alarm 42h", "initial encoder error"),
    alarm(0xFF44, "alarm 44h", "encoder EEPROM error"),
    alarm(0xFF45, "alarm 45h", "motor combination error"),
    alarm(0xFF4A, "alarm 4Ah", "return-to-home incomplete"),
    alarm(0xFF50, "alarm 50h", "electromagnetic brake overcurrent"),
    alarm(0xFF53, "alarm 53h", "HWTO input circuit error"),
    alarm(
        0xFF55,
        "alarm 55h",
        "electromagnetic brake connection error",
    ),
    alarm(0xFF60, "alarm 60h", "±LS both sides active"),
    alarm(0xFF61, "alarm 61h", "reverse ±LS connection"),
    alarm(0xFF62, "alarm 62h", "return-to-home operation error"),
    alarm(0xFF63, "alarm 63h", "no HOMES"),
    alarm(0xFF64, "alarm 64h", "Z, SLIT signal error"),
    alarm(0xFF66, "alarm 66h", "hardware overtravel"),
    alarm(0xFF67, "alarm 67h", "software overtravel"),
    alarm(0xFF68, "alarm 68h", "HWTO input detection"),
    alarm(
        0xFF6A,
        "alarm 6Ah",
        "return-to-home additional operation error",
    ),
    alarm(0xFF70, "alarm 70h", "operation data error"),
    alarm(0xFF71, "alarm 71h", "unit setting error"),
    alarm(0xFF81, "alarm 81h", "network bus error"),
    alarm(0xFF84, "alarm 84h", "RS-485 communication error"),
    alarm(0xFF85, "alarm 85h", "RS-485 communication timeout"),
    alarm(0xFF8C, "alarm 8Ch", "outside setting range"),
    alarm(0xFFF0, "alarm F0h", "CPU error"),
    alarm(0xFFF3, "alarm F3h", "CPU overload"),
    comm(0x8110, "CAN overrun"),
    comm(0x8120, "CAN error passive"),
    comm(0x8130, "node guarding or heartbeat error"),
    comm(0x8140, "recovered from bus-off"),
    comm(0x8210, "PDO not processed (length error)"),
];

const fn alarm(code: u16, name: &'static str, text: &'static str) -> Alarm {
    Alarm {
        number: code & 0x00FF,
        code,
        register: 0x81,
        name,
        text,
        fault: true,
    }
}

const fn comm(code: u16, text: &'static str) -> Alarm {
    Alarm {
        number: code,
        code,
        register: 0x11,
        name: "CAN",
        text,
        fault: false,
    }
}

/// 603Fh names: each alarm's `FFxxh` code, then a catch-all for the FFxxh range.
pub const ERROR_TABLE: &[ErrorEntry] = &[
    ErrorEntry::exact(0xFF10, "alarm 10h", "position deviation"),
    ErrorEntry::exact(0xFF20, "alarm 20h", "overcurrent"),
    ErrorEntry::exact(0xFF21, "alarm 21h", "main circuit overheat"),
    ErrorEntry::exact(0xFF22, "alarm 22h", "overvoltage"),
    ErrorEntry::exact(0xFF25, "alarm 25h", "undervoltage"),
    ErrorEntry::exact(0xFF26, "alarm 26h", "motor overheat"),
    ErrorEntry::exact(0xFF28, "alarm 28h", "encoder error"),
    ErrorEntry::exact(0xFF30, "alarm 30h", "overload"),
    ErrorEntry::exact(0xFF31, "alarm 31h", "overspeed"),
    ErrorEntry::exact(0xFF62, "alarm 62h", "return-to-home operation error"),
    ErrorEntry::exact(0xFF66, "alarm 66h", "hardware overtravel"),
    ErrorEntry::exact(0xFF67, "alarm 67h", "software overtravel"),
    ErrorEntry::exact(0xFF81, "alarm 81h", "network bus error"),
    ErrorEntry {
        code: 0xFF00,
        mask: 0xFF00,
        name: "alarm xxh",
        text: "BLV-R alarm: the low byte is the alarm code (see the Function Edition)",
    },
];

/// Quick-stop option codes 605Ah (§8.3): −3 custom stopping time 4736h, −2 custom stopping
/// rate 4735h, −1 immediate stop (all three stay in Quick stop active), 0, 1, 2, 5, 6. Default 2.
pub const QUICK_STOP_OPTIONS: &[QuickStopOption] = &[
    QuickStopOption::vendor(-3, StopRamp::Vendor, QuickStopEnd::StayInQuickStopActive),
    QuickStopOption::vendor(-2, StopRamp::Vendor, QuickStopEnd::StayInQuickStopActive),
    QuickStopOption::vendor(-1, StopRamp::Immediate, QuickStopEnd::StayInQuickStopActive),
    QuickStopOption::DISABLE_DRIVE,
    QuickStopOption::SLOW_DOWN_RAMP,
    QuickStopOption::QUICK_STOP_RAMP,
    QuickStopOption::SLOW_DOWN_RAMP_STAY,
    QuickStopOption::QUICK_STOP_RAMP_STAY,
];

/// 6502h with tq: 0000 002Dh (pp, pv, tq, hm), driver version ≥ 4.00 (§8.3). Older drivers
/// report 0000 0025h (no tq): use [`SUPPORTED_MODES_BEFORE_V4`] for them.
pub const SUPPORTED_MODES: SupportedModes = SupportedModes::from_raw(0x0000_002D);
/// 6502h of drivers before version 4.00: pp, pv, hm.
pub const SUPPORTED_MODES_BEFORE_V4: SupportedModes = SupportedModes::from_raw(0x0000_0025);

/// The capability set (the one `crates/ecdrive-core/tests/core/support/cia402_drives.rs` wrote from §6, §6.2, §8.3): no
/// state skipping (the "switch on + enable operation" row is 3 then 4), no transition 16 (§6.2
/// "Not supported"), quick-stop codes above (default 2), the remote bit gates the controlword
/// (§6.1), no zero-speed rule for mode switching (none stated).
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: false,
    quick_stop_options: QUICK_STOP_OPTIONS,
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

// ============================================================================================
// PDOs (§4.7, §8.1)
// ============================================================================================

const RX_RANGES: &[PdoRange] = &[PdoRange::new(0x1600, 0x1603, 4)];
const TX_RANGES: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A03, 4)];

/// The generic PDO limits: four PDOs per direction, **4 entries each** (sub 00h range 0–4),
/// 8 bytes each.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "BLV-R",
    rx: DirectionLimits {
        pdos: RX_RANGES,
        max_assigned: 4,
        max_entries: 16,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: TX_RANGES,
        max_assigned: 4,
        max_entries: 16,
        max_bytes: 32,
    },
    assignment_writable: true,
};

const CW: PdoEntry = PdoEntry::new(0x6040, 0, 16);
const SW: PdoEntry = PdoEntry::new(0x6041, 0, 16);

/// Power-on RPDOs (§8.1): 1 CW; 2 CW + 6060h; 3 CW + 607Ah; 4 CW + 60FFh; type 255, valid.
pub const DEFAULT_RPDOS: &[PdoDefault] = &[
    rpdo(1, 0x200, &[CW]),
    rpdo(2, 0x300, &[CW, PdoEntry::new(0x6060, 0, 8)]),
    rpdo(3, 0x400, &[CW, PdoEntry::new(0x607A, 0, 32)]),
    rpdo(4, 0x500, &[CW, PdoEntry::new(0x60FF, 0, 32)]),
];

/// Power-on TPDOs (§8.1): 1 SW (255); 2 SW + 6061h (255); 3 SW + 6064h (**1**); 4 SW + 606Ch
/// (**1**); COB-IDs with bit 30 (no RTR) set; inhibit 50 × 100 µs = 5 ms; event timer 0.
pub const DEFAULT_TPDOS: &[PdoDefault] = &[
    tpdo(1, 0x4000_0180, 255, &[SW]),
    tpdo(2, 0x4000_0280, 255, &[SW, PdoEntry::new(0x6061, 0, 8)]),
    tpdo(3, 0x4000_0380, 1, &[SW, PdoEntry::new(0x6064, 0, 32)]),
    tpdo(4, 0x4000_0480, 1, &[SW, PdoEntry::new(0x606C, 0, 32)]),
];

const fn rpdo(number: u8, cob_id: u32, mapping: &'static [PdoEntry]) -> PdoDefault {
    PdoDefault {
        number,
        cob_id,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping,
    }
}

const fn tpdo(number: u8, cob_id: u32, tt: u8, mapping: &'static [PdoEntry]) -> PdoDefault {
    PdoDefault {
        number,
        cob_id,
        transmission_type: tt,
        inhibit_time: 50,
        event_timer: 0,
        mapping,
    }
}

/// RPDO transmission types (§4.7.2): 00h, FEh, FFh only. (FEh also triggers the paired TPDO
/// and resets the life time, firmware ≥ 2.02.)
pub const RPDO_TYPES: TransmissionTypes = TransmissionTypes {
    sync_acyclic: true,
    sync_cyclic: false,
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
    rpdo_comm_subs: 2,
    default_rpdos: DEFAULT_RPDOS,
    default_tpdos: DEFAULT_TPDOS,
};

// ============================================================================================
// Object dictionary (§8.1, §8.2, §8.3, App.)
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

static ERRORS_1003: [EntryDesc; 11] = error_history::<11>();
static STORE_1010: [EntryDesc; 3] = store_record::<3>();
static RESTORE_1011: [EntryDesc; 3] = store_record::<3>();
static RPDO1_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x200, 255, 0, 0);
static RPDO2_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x300, 255, 0, 0);
static RPDO3_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x400, 255, 0, 0);
static RPDO4_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x500, 255, 0, 0);
static RPDO1_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6040_0010]);
static RPDO2_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6040_0010, 0x6060_0008]);
static RPDO3_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6040_0010, 0x607A_0020]);
static RPDO4_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6040_0010, 0x60FF_0020]);
static TPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x4000_0180, 255, 50, 0);
static TPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x4000_0280, 255, 50, 0);
static TPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x4000_0380, 1, 50, 0);
static TPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x4000_0480, 1, 50, 0);
static TPDO1_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6041_0010]);
static TPDO2_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6041_0010, 0x6061_0008]);
static TPDO3_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6041_0010, 0x6064_0020]);
static TPDO4_MAP: [EntryDesc; 5] = pdo_map::<5>(&[0x6041_0010, 0x606C_0020]);

const ARRAY: ObjectCode = ObjectCode::Array;
const RECORD: ObjectCode = ObjectCode::Record;

/// The object dictionary: the communication objects of §8.1, the manufacturer objects of §8.2
/// a master uses (alarm reset, homing, stop timeout, wrap), and the device-profile objects of
/// §8.3. Access "rww" (writable, RPDO-mappable) is `RW` + RXPDO; "ro" with mapping "Yes" is
/// `RO` + TXPDO. Sorted by index.
pub static DICTIONARY: &[ObjectDesc] = &[
    var!(0x1000, "Device type", U32, RO, u(DEVICE_TYPE as u64)),
    var!(0x1001, "Error register", U8, RO, u(0)),
    rec!(0x1003, "Pre-defined error field", ARRAY, &ERRORS_1003),
    var!(0x1005, "COB-ID SYNC", U32, RW, u(0x80)),
    var!(0x1006, "Communication cycle period", U32, RW, u(0)),
    ObjectDesc {
        index: 0x1008,
        name: "Manufacturer device name",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer device name", STR, RO)
            .bits(16 * 8)
            .default(crate::od::ConstValue::Str("BLVD-KRD"))],
    },
    ObjectDesc {
        index: 0x1009,
        name: "Manufacturer hardware version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer hardware version", STR, RO)
            .bits(16 * 8)
            .default(crate::od::ConstValue::Str(EMU_HW_VERSION))],
    },
    ObjectDesc {
        index: 0x100A,
        name: "Manufacturer software version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer software version", STR, RO)
            .bits(16 * 8)
            .default(crate::od::ConstValue::Str(EMU_SW_VERSION))],
    },
    var!(0x100C, "Guard time", U16, RW, u(0)),
    var!(0x100D, "Life time factor", U8, RW, u(0)),
    rec!(0x1010, "Store parameters", ARRAY, &STORE_1010),
    rec!(0x1011, "Restore default parameters", ARRAY, &RESTORE_1011),
    var!(0x1014, "COB-ID EMCY", U32, RW, u(0x80)),
    rec!(
        0x1016,
        "Consumer heartbeat time",
        ARRAY,
        &[
            count(1, RO),
            EntryDesc::new(1, "Consumer heartbeat time", U32, RW)
                .default(u(0))
                .range(u(0), u(0x00FF_FFFF)),
        ]
    ),
    var!(0x1017, "Producer heartbeat time", U16, RW, u(0)),
    rec!(
        0x1018,
        "Identity object",
        RECORD,
        &[
            count(2, RO),
            e(1, "Vendor-ID", U32, RO, u(VENDOR_ID as u64)),
            e(2, "Product code", U32, RO, u(PRODUCT_KRD as u64)),
        ]
    ),
    rec!(
        0x1200,
        "SDO server parameter",
        RECORD,
        &[
            count(2, RO),
            e(1, "COB-ID client to server", U32, RO, u(0x600)),
            e(2, "COB-ID server to client", U32, RO, u(0x580)),
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
    // --- §8.2 manufacturer objects a master uses -------------------------------------------
    var!(0x403E, "Driver input command", U32, RW_R, u(0)),
    var!(0x403F, "Driver output status", U32, RO_T, u(0)),
    var!(0x40C0, "Alarm reset", U8, RW_R, u(0)),
    var!(0x40C2, "Clear alarm history", U8, RW_R, u(0)),
    var!(0x415F, "JOG/HOME torque limit", U16, RW_R, u(10_000)),
    var!(0x4160, "(HOME) Homing mode", U8, RW_R, u(1)),
    var!(0x4163, "(HOME) Starting velocity", U32, RW_R, u(30)),
    var!(
        0x4169,
        "(HOME) Backward steps in 2-sensor homing",
        U32,
        RW_R,
        u(18_000)
    ),
    var!(0x4186, "Stopping timeout at alarm", U16, RW_R, u(3_000)),
    var!(0x41CA, "WRAP setting", U8, RW_R, u(1)),
    // --- §8.3 device-profile objects --------------------------------------------------------
    var!(0x603F, "Error code", U16, RO_T, u(0)),
    var!(0x6040, "Controlword", U16, RW_R, u(0x0004)),
    var!(0x6041, "Statusword", U16, RO_T, u(0)),
    var!(0x605A, "Quick stop option code", I16, RW, i(2)),
    var!(0x605B, "Shutdown option code", I16, RW, i(0)),
    var!(0x605C, "Disable operation option code", I16, RW, i(1)),
    var!(0x605D, "Halt option code", I16, RW, i(1)),
    var!(0x605E, "Fault reaction option code", I16, RW, i(2)),
    var!(0x6060, "Modes of operation", I8, RW_R, i(3)),
    var!(0x6061, "Modes of operation display", I8, RO_T, i(3)),
    var!(0x6062, "Position demand value", I32, RO_T, i(0)),
    var!(0x6064, "Position actual value", I32, RO_T, i(0)),
    var!(0x6065, "Following error window", U32, RW_R, u(108_000)),
    var!(0x6067, "Position window", U32, RW_R, u(18)),
    var!(0x606B, "Velocity demand value", I32, RO_T, i(0)),
    var!(0x606C, "Velocity actual value", I32, RO_T, i(0)),
    var!(0x606D, "Velocity window", U16, RW_R, u(15)),
    var!(0x606F, "Velocity threshold", U16, RW_R, u(15)),
    var!(0x6071, "Target torque", I16, RW_R, i(0)),
    var!(0x6072, "Max torque", U16, RW_R, u(10_000)),
    var!(0x6074, "Torque demand", I16, RO_T, i(0)),
    var!(0x6077, "Torque actual value", I16, RO_T, i(0)),
    var!(0x607A, "Target position", I32, RW_R, i(0)),
    rec!(
        0x607B,
        "Position range limit",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Min position range limit", I32, RW_R, i(0)),
            e(2, "Max position range limit", I32, RW_R, i(0)),
        ]
    ),
    var!(0x607C, "Home offset", I32, RW_R, i(0)),
    rec!(
        0x607D,
        "Software position limit",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Min position limit", I32, RW_R, i(0)),
            e(2, "Max position limit", I32, RW_R, i(0)),
        ]
    ),
    var!(0x6081, "Profile velocity", U32, RW_R, u(1)),
    var!(0x6082, "End velocity", U32, RW_R, u(0)),
    var!(0x6083, "Profile acceleration", U32, RW_R, u(1_000)),
    var!(0x6084, "Profile deceleration", U32, RW_R, u(1_000)),
    var!(0x6085, "Quick stop deceleration", U32, RW_R, u(1_000)),
    var!(0x6087, "Torque slope", U32, RW_R, u(0)),
    rec!(
        0x608F,
        "Position encoder resolution",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Encoder increments", U32, RW_R, u(36_000)),
            e(2, "Motor revolutions", U32, RW_R, u(1)),
        ]
    ),
    rec!(
        0x6091,
        "Gear ratio",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Motor revolutions", U32, RW, u(1)),
            e(2, "Shaft revolutions", U32, RW, u(1)),
        ]
    ),
    var!(0x6098, "Homing method", I8, RW_R, i(37)),
    rec!(
        0x6099,
        "Homing speeds",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Speed during search for switch", U32, RW_R, u(60)),
            e(2, "Speed during search for zero", U32, RW_R, u(30)),
        ]
    ),
    var!(0x609A, "Homing acceleration", U32, RW_R, u(1_000)),
    var!(0x60B8, "Touch probe function", U16, RW_R, u(0x3131)),
    var!(0x60B9, "Touch probe status", U16, RO_T, u(0)),
    var!(0x60BA, "Touch probe 1 positive edge", I32, RO_T, i(0)),
    var!(0x60BB, "Touch probe 1 negative edge", I32, RO_T, i(0)),
    var!(0x60BC, "Touch probe 2 positive edge", I32, RO_T, i(0)),
    var!(0x60BD, "Touch probe 2 negative edge", I32, RO_T, i(0)),
    rec!(
        0x60E3,
        "Supported homing methods",
        ARRAY,
        &[
            count(11, RO),
            e(1, "1st supported homing method", I8, RO, i(37)),
            e(2, "2nd supported homing method", I8, RO, i(35)),
            e(3, "3rd supported homing method", I8, RO, i(1)),
            e(4, "4th supported homing method", I8, RO, i(2)),
            e(5, "5th supported homing method", I8, RO, i(8)),
            e(6, "6th supported homing method", I8, RO, i(12)),
            e(7, "7th supported homing method", I8, RO, i(17)),
            e(8, "8th supported homing method", I8, RO, i(18)),
            e(9, "9th supported homing method", I8, RO, i(24)),
            e(10, "10th supported homing method", I8, RO, i(28)),
            e(11, "11th supported homing method", I8, RO, i(-1)),
        ]
    ),
    var!(0x60F2, "Positioning option code", U16, RW_R, u(0)),
    var!(0x60F4, "Following error actual value", I32, RO_T, i(0)),
    var!(0x60FD, "Digital inputs", U32, RO_T, u(0)),
    rec!(
        0x60FE,
        "Digital outputs",
        ARRAY,
        &[count(1, RO), e(1, "Physical outputs", U32, RW_R, u(0))]
    ),
    var!(0x60FF, "Target velocity", I32, RW_R, i(0)),
    var!(0x6502, "Supported drive modes", U32, RO_T, u(0x0000_002D)),
    var!(0x67FE, "Version number", U32, RO, u(0x0004_0100)),
    var!(0x67FF, "Single device type", U32, RO, u(DEVICE_TYPE as u64)),
];

// ============================================================================================
// Units (§6 of the reference; §8.3 608Fh, object unit columns)
// ============================================================================================

/// Units: position in "steps", 36,000 per motor revolution by default (608Fh = 36,000 / 1);
/// velocities (60FFh, 6081h, 6099h) in r/min; accelerations (6083h–6085h, 609Ah) as a rate in
/// (r/min)/s; torque in 0.1 % of rated (per mille), torque slope 0.1 %/s. The unit configuration
/// itself is only reachable with the support software (60A8h/60A9h writes are ignored).
pub const UNITS: Units = Units {
    position_name: "step",
    position_per_rev: 36_000.0,
    velocity: VelocityUnit::RevPerMinute { scale: 1.0 },
    torque_per_mille: 1.0,
    profile: Some(ProfileUnits {
        profile_velocity: VelocityUnit::RevPerMinute { scale: 1.0 },
        homing_velocity: VelocityUnit::RevPerMinute { scale: 1.0 },
        acceleration: AccelUnit::RpmPerSecond,
        torque_slope: TorqueSlopeUnit::PerMillePerSecond,
    }),
};

/// Enable preconditions: remote bit 9 must be 1 (S-ON input off, support software not
/// operating the drive), and excitation needs NMT Operational (§5.1).
pub const ENABLE: EnableConditions = EnableConditions {
    remote_required: true,
    voltage_required: false,
    needs_operational: true,
    settings: &[],
    targets_cleared_on_enable: &[],
    notes: "statusword bit 9 (remote) is 0 while the S-ON input is active or the support \
            software operates the drive; the controlword is then ignored except quick stop, \
            fault reset and halt. Software limits 607Dh act only after homing.",
};

/// Homing (§7.5.5, 60E3h): 1, 2, 8, 12, 17, 18, 24, 28, 35, 37 and the vendor method −1;
/// default 37 (current position = home, allowed outside Operation enabled).
pub const HOMING: HomingSupport = HomingSupport {
    methods: &[1, 2, 8, 12, 17, 18, 24, 28, 35, 37, -1],
    default_method: 37,
    index_pulse: true,
};

/// Vendor SDO abort codes: none beyond CiA 301 (§4.6.5 lists only standard codes).
pub const VENDOR_ABORT_CODES: &[(u32, &str)] = &[];

/// Communication services (§4.2–4.4, §8.1): guarding and heartbeat (1016h with one entry), can
/// produce SYNC (1005h bit 30), 1006h in multiples of 250 µs, 10 error-history entries, store
/// sub-indices 01h and 02h. No SDO rate limit stated.
pub const COMM: CommSupport = CommSupport {
    guarding: true,
    heartbeat_consumers: 1,
    sync_producer: true,
    has_cycle_period: true,
    cycle_period_granularity_us: 250,
    error_history: 10,
    store_subs: 2,
    sdo_min_interval_us: 0,
    rpdo_min_interval_us: 0,
};

/// The BLV-R profile.
pub const PROFILE: CanDriveProfile = CanDriveProfile {
    name: "BLV-R",
    vendor: "Oriental Motor",
    caps: CAPS,
    dictionary: DICTIONARY,
    units: UNITS,
    bus: CanOpen {
        source: "Oriental Motor BLV series R type, CANopen communication profile",
        identity: IDENTITY,
        default_node_id: None,
        default_bitrate_kbit: 500,
        bitrates_kbit: &[1000, 800, 500, 250, 125, 50, 20, 10],
        modes_note: "6502h = 0000 002Dh (pp, pv, tq, hm) from driver version 4.00, 0000 0025h \
                     before (no tq); 6060h range 0–6, default 3 (pv)",
        pdo: PDO,
        enable: ENABLE,
        homing: HOMING,
        emcy: EmcyFormat::AlarmInCodeLowByte,
        alarms: ALARMS,
        vendor_abort_codes: VENDOR_ABORT_CODES,
        comm: COMM,
        nmt_stop_while_enabled: EnabledNmtReaction::Unspecified,
        nmt_reset_while_enabled: EnabledNmtReaction::Unspecified,
        // CiA 402: controlword bit 4 enables interpolation in ip.
        ip_needs_enable_bit: true,
        // Statusword bit 12 in pv: zero speed.
        pv_zero_speed_bit: true,
    },
};

// ============================================================================================
// MANUAL GAP / [REC] / DISCREPANCY — every value above that is not vendor fact
// ============================================================================================
//
// - MANUAL GAP: factory node-ID (`default_node_id: None`); the emulation and the demo use
//   `EMU_NODE_ID`.
// - MANUAL GAP: the reaction to NMT Stop / Reset while enabled (`Unspecified`); the emulation
//   disables the power stage because §5.1 ties excitation to Operational.
// - MANUAL GAP: whether guarding/heartbeat loss (EMCY 8130h) stops the motor (the software
//   slave's own quirk table: the emulation only sends the EMCY). The Function Edition is not
//   in our set.
// - MANUAL GAP: whether each alarm can be reset (the manual's "Possible/Not possible" column
//   lost its assignment); every FFxxh alarm is a fault here.
// - MANUAL GAP: 1009h/100Ah contents (the manual gives examples only): `EMU_HW_VERSION`,
//   `EMU_SW_VERSION`.
// - DISCREPANCY: 6065h default 108,000 (§8.3) vs 100,800 (App.): §8.3 used.
// - DISCREPANCY: 60B8h default 3131h (§8.3) vs 0000h (App.): §8.3 used.
// - DISCREPANCY: 1A00h–1A03h sub 00h rw (§8.1) vs ro (App.): rw, as the remap procedure of
//   §4.7.1 needs.
// - DISCREPANCY: 605Dh range 0–1 (§8.3) vs −3–2 (App.): only 1 is usable per §5.4.
// - DISCREPANCY: 6099h sub-indices both "00h" in §8.3: the appendix's 01h/02h used.

/// **MANUAL GAP** → \[REC\] node-ID of the emulated BLV-R and of the demo.
pub const EMU_NODE_ID: u8 = 0x01;
/// **MANUAL GAP** → \[REC\] 1009h of the emulated node (the manual's example value).
pub const EMU_HW_VERSION: &str = "Rev.1.00";
/// **MANUAL GAP** → \[REC\] 100Ah of the emulated node (the manual's example value).
pub const EMU_SW_VERSION: &str = "V.4.00";

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
    fn alarm_numbers_are_unique() {
        for (k, a) in ALARMS.iter().enumerate() {
            assert!(
                ALARMS.iter().skip(k + 1).all(|b| b.number != a.number),
                "{}",
                a.name
            );
        }
    }
}
