//! Delta ASDA-A2 servo drive, CANopen.
//!
//! Source: Delta, *CANopen for ASDA-A2*, `CANopen for ASDA-A2_M_EN_20120920`, V2.01; `§x.y` cite
//! its sections. Condensed in `../shared/reference/drive-asda-a2.md`. Standards: CiA DS 301
//! V4.02, DSP 402 V2.0.
//!
//! Behaviour a master must know (all of it data below):
//! - **P1-01 = 0x0C** ("CANopen full", standard DS402) is assumed; 0x0B ("half") changes the
//!   enable sequence, homing units and the ip data layout ([`ENABLE`] checks it).
//! - **P3-12 X = 0 by default**: servo on as soon as controlword bit 3 = 1, not the DS402
//!   sequence; [`ENABLE`] writes X = 1 before enabling.
//! - **At most one SDO per millisecond** (two within 1 ms → AL111) and one frame per RPDO
//!   COB-ID per millisecond (AL112) ([`COMM`]).
//! - **NMT Stop / Reset while servo on → AL401** ([`PROFILE`] `nmt_*_while_enabled`).
//! - **60FFh and 6071h are cleared on servo on**, mode change, servo off and quick stop
//!   (§3.4.2, §3.5.2): write them after Operation enabled.
//! - No default PDO mappings, transmission type 0 everywhere; 8 entries per PDO.
//! - Units: PUU (1,280,000 × 6093h:02 / 6093h:01 per revolution), 0.1 r/min, but 6081h in
//!   PUU/s, accelerations as a **time** in ms for 0 → 3000 r/min, torque slope as ms to 100 %.
//! - ip (mode 7) is Delta's: no enable bit 4, statusword bit 12 = ip active, bit 14 = SYNC OK.
//! - EMCY bytes 3–4 carry the panel alarm number; 1014h is read-only; 605Ah does not exist.
//!
//! Every value the manual does not give is in the **MANUAL GAP / \[REC\]** section at the end.

use crate::can::profile::od::{
    I8, I16, I32, RO, RO_T, RW, RW_R, RW_RT, U8, U16, U32, count, e, error_history, i, pdo_comm,
    pdo_map, store_record, u,
};
use crate::can::profile::{
    AccelUnit, Alarm, CanDriveProfile, CanOpen, CanPdoProfile, CommSupport, EmcyFormat,
    EnableConditions, EnabledNmtReaction, HomingSupport, Identity, ParamSetting, PdoDefault,
    TorqueSlopeUnit, TransmissionTypes, Units, VelocityUnit,
};
use crate::cia402::{DriveCaps, ErrorEntry, ProfileUnits, QuickStopOption, SupportedModes};
use crate::od::{EntryDesc, ObjectAddress, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, PdoLimits, PdoRange};

// ============================================================================================
// Identity (§4.4)
// ============================================================================================

/// Vendor ID, 1018h:01.
pub const VENDOR_ID: u32 = 0x0000_01DD;
/// Product code of the A2 series, 1018h:02.
pub const PRODUCT_A2: u32 = 0x0000_6000;
/// Product code of the M series.
pub const PRODUCT_M: u32 = 0x0000_6030;
/// Device type 1000h of the A2 series.
pub const DEVICE_TYPE_A2: u32 = 0x0402_0192;
/// Device type 1000h of the M series.
pub const DEVICE_TYPE_M: u32 = 0x0602_0192;

/// Identity (1018h has sub-indices 1–3; the revision is "N/A").
pub const IDENTITY: Identity = Identity {
    vendor_id: VENDOR_ID,
    products: &[(PRODUCT_A2, "ASDA-A2"), (PRODUCT_M, "ASDA-A2-M")],
    device_type: DEVICE_TYPE_A2,
    other_device_types: &[DEVICE_TYPE_M],
    revision: None,
};

// ============================================================================================
// Alarms (§5.1, §5.2)
// ============================================================================================

/// Alarm numbers as the EMCY carries them (the panel number written as hex digits).
pub mod alarm {
    /// AL111 SDO receive buffer overrun (two SDO requests within 1 ms).
    pub const SDO_OVERRUN: u16 = 0x0111;
    /// AL112 PDO receive buffer overrun (two PDOs on one COB-ID within 1 ms).
    pub const PDO_OVERRUN: u16 = 0x0112;
    /// AL123 PDO data length mismatch.
    pub const PDO_LENGTH: u16 = 0x0123;
    /// AL170 node guarding or heartbeat error, servo on.
    pub const GUARDING_SERVO_ON: u16 = 0x0170;
    /// AL401 NMT reset or stop received while enabled.
    pub const NMT_WHILE_ENABLED: u16 = 0x0401;
}

const fn al(number: u16, code: u16, name: &'static str, text: &'static str) -> Alarm {
    Alarm {
        number,
        code,
        register: 0x01,
        name,
        text,
        fault: true,
    }
}

const fn warn(number: u16, code: u16, name: &'static str, text: &'static str) -> Alarm {
    Alarm {
        number,
        code,
        register: 0x01,
        name,
        text,
        fault: false,
    }
}

/// The alarm table of §5.1/§5.2: code = EMCY bytes 0–1 / 603Fh, number = EMCY bytes 3–4 and
/// the upper word of 1003h entries. Alarms not listed in this manual are in the drive's user
/// manual.
pub const ALARMS: &[Alarm] = &[
    al(0x0001, 0x2310, "AL001", "overcurrent"),
    al(0x0002, 0x3110, "AL002", "overvoltage"),
    al(0x0003, 0x3120, "AL003", "undervoltage"),
    al(0x0004, 0x7122, "AL004", "motor error"),
    al(0x0005, 0x3210, "AL005", "regeneration error"),
    al(0x0006, 0x3230, "AL006", "overload"),
    al(0x0007, 0x8400, "AL007", "overspeed"),
    al(0x0008, 0x8600, "AL008", "abnormal pulse control command"),
    al(0x0009, 0x8611, "AL009", "excessive deviation"),
    al(0x0011, 0x7305, "AL011", "encoder error"),
    al(0x0012, 0x6320, "AL012", "adjustment error"),
    al(0x0013, 0x5441, "AL013", "emergency stop activated"),
    al(0x0014, 0x5443, "AL014", "reverse limit switch error"),
    al(0x0015, 0x5442, "AL015", "forward limit switch error"),
    al(0x0016, 0x4210, "AL016", "IGBT temperature error"),
    al(0x0017, 0x5330, "AL017", "memory error"),
    al(0x0018, 0x7306, "AL018", "encoder output error"),
    al(0x0019, 0x7510, "AL019", "serial communication error"),
    al(0x0020, 0x7520, "AL020", "serial communication time out"),
    al(0x0022, 0x3130, "AL022", "input power phase loss"),
    warn(0x0023, 0x3231, "AL023", "pre-overload warning"),
    al(
        0x0024,
        0x7305,
        "AL024",
        "encoder initial magnetic field error",
    ),
    al(0x0025, 0x7305, "AL025", "encoder internal error"),
    al(0x0026, 0x7305, "AL026", "encoder internal error"),
    al(0x0027, 0x7305, "AL027", "encoder data error"),
    al(0x0030, 0x7121, "AL030", "motor protection error"),
    al(0x0031, 0x3300, "AL031", "U,V,W wiring error"),
    al(
        0x0040,
        0x8610,
        "AL040",
        "full closed-loop excessive deviation",
    ),
    al(0x0099, 0x5500, "AL099", "DSP firmware upgrade"),
    al(
        0x0111,
        0x8110,
        "AL111",
        "CANopen SDO receive buffer overrun (two SDOs within 1 ms)",
    ),
    al(
        0x0112,
        0x8110,
        "AL112",
        "CANopen PDO receive buffer overrun (two PDOs on one COB-ID within 1 ms)",
    ),
    al(0x0121, 0x8200, "AL121", "PDO object index does not exist"),
    al(
        0x0122,
        0x8200,
        "AL122",
        "PDO object sub-index does not exist",
    ),
    al(0x0123, 0x8200, "AL123", "PDO data type (size) error"),
    al(0x0124, 0x8200, "AL124", "PDO data range error"),
    al(0x0125, 0x8200, "AL125", "PDO object is read-only"),
    al(0x0126, 0x8200, "AL126", "object does not support PDO"),
    al(
        0x0127,
        0x8200,
        "AL127",
        "PDO object is write-protected while servo on",
    ),
    al(
        0x0128,
        0x8200,
        "AL128",
        "error reading CANopen objects from EEPROM",
    ),
    al(
        0x0129,
        0x8200,
        "AL129",
        "error writing CANopen objects to EEPROM",
    ),
    al(0x0130, 0x8200, "AL130", "EEPROM invalid address range"),
    al(0x0131, 0x8200, "AL131", "EEPROM checksum error"),
    al(0x0132, 0x8200, "AL132", "password / EEPROM zone error"),
    al(
        0x0170,
        0x8130,
        "AL170",
        "node guarding or heartbeat error (servo on)",
    ),
    al(
        0x0180,
        0x8130,
        "AL180",
        "node guarding or heartbeat error (servo off)",
    ),
    warn(
        0x0185,
        0x8120,
        "AL185",
        "CAN bus error (warning: Tx error counter > 128)",
    ),
    al(0x0186, 0x8100, "AL186", "CAN bus-off"),
    al(
        0x0201,
        0x6310,
        "AL201",
        "CANopen data initial error / 1010h-1011h load-save error",
    ),
    al(0x0283, 0x5444, "AL283", "forward software limit"),
    al(0x0285, 0x5445, "AL285", "reverse software limit"),
    al(0x0301, 0x6200, "AL301", "CANopen SYNC failed (servo on)"),
    al(
        0x0302,
        0x6200,
        "AL302",
        "CANopen SYNC received too early (servo on)",
    ),
    al(0x0303, 0x6200, "AL303", "CANopen SYNC time out (servo on)"),
    al(
        0x0304,
        0x6200,
        "AL304",
        "CANopen ip command failed (servo on)",
    ),
    al(
        0x0305,
        0x6200,
        "AL305",
        "SYNC period 1006h invalid (servo on)",
    ),
    al(0x03E1, 0x6200, "AL3E1", "CANopen SYNC failed (servo off)"),
    al(
        0x03E2,
        0x6200,
        "AL3E2",
        "CANopen SYNC received too early (servo off)",
    ),
    al(0x03E3, 0x6200, "AL3E3", "CANopen SYNC time out (servo off)"),
    al(
        0x03E4,
        0x6200,
        "AL3E4",
        "CANopen ip command failed (servo off)",
    ),
    al(
        0x03E5,
        0x6200,
        "AL3E5",
        "SYNC period 1006h invalid (servo off)",
    ),
    al(
        0x0401,
        0x8100,
        "AL401",
        "CANopen state error: NMT reset or stop received while enabled",
    ),
];

/// 603Fh names. 603Fh holds only the CiA code, which several alarms share (7305h = AL011,
/// AL024–AL027): the EMCY's bytes 3–4 tell them apart ([`ALARMS`]).
pub const ERROR_TABLE: &[ErrorEntry] = &[
    ErrorEntry::exact(0x7305, "AL011/AL024-AL027", "encoder error"),
    ErrorEntry::exact(
        0x8110,
        "AL111/AL112",
        "CANopen SDO or PDO receive buffer overrun",
    ),
    ErrorEntry::exact(0x8130, "AL170/AL180", "node guarding or heartbeat error"),
    ErrorEntry::exact(
        0x8100,
        "AL186/AL401",
        "CAN bus-off or NMT stop/reset while enabled",
    ),
    ErrorEntry::exact(0x8200, "AL121-AL132", "CANopen PDO object or EEPROM error"),
    ErrorEntry::exact(0x6200, "AL301-AL3E5", "CANopen SYNC or ip error"),
    ErrorEntry::exact(0x6310, "AL201", "CANopen data initial / load-save error"),
    ErrorEntry::exact(0x5444, "AL283", "forward software limit"),
    ErrorEntry::exact(0x5445, "AL285", "reverse software limit"),
    ErrorEntry::exact(0x5441, "AL013", "emergency stop activated"),
    ErrorEntry::exact(0x5442, "AL015", "forward limit switch error"),
    ErrorEntry::exact(0x5443, "AL014", "reverse limit switch error"),
];

// ============================================================================================
// CiA 402 capabilities (§2.2.2 P3-12, §4.4 6040h/6060h/6502h)
// ============================================================================================

/// 6502h = 0000 006Dh: pp, pv, tq, hm, ip.
pub const SUPPORTED_MODES: SupportedModes = SupportedModes::from_raw(0x0000_006D);

/// The capability set. With P3-12 X = 1 (written by the master, see [`ENABLE`]) the drive
/// follows 0006h → 0007h → 000Fh step by step: no state skipping. 605Ah does not exist (empty
/// list); the fixed quick-stop behaviour is **MANUAL GAP** → \[REC\] code 2 (quick-stop ramp,
/// then Switch on disabled), and transition 16 is assumed absent. No zero-speed rule stated.
/// The remote bit is not described as a gate.
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: false,
    quick_stop_options: &[],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: false,
    supported_modes: SUPPORTED_MODES,
    error_table: ERROR_TABLE,
    csp_start_edge: false,
    homing_failure: "",
    home_offset_set_by_drive: None,
    sdo_refused_while_rx_mapped: None,
    pp_target_range: None,
};

// ============================================================================================
// PDOs (§4.4 1400h–1A03h)
// ============================================================================================

const RX_RANGES: &[PdoRange] = &[PdoRange::new(0x1600, 0x1603, 8)];
const TX_RANGES: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A03, 8)];

/// Four PDOs per direction, up to **8 entries** each, 8 bytes each.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "ASDA-A2",
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

const fn empty(number: u8, cob_id: u32) -> PdoDefault {
    PdoDefault {
        number,
        cob_id,
        transmission_type: 0,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[],
    }
}

/// Power-on RPDOs: COB-IDs 200h…500h + node, transmission type **0**, **no mapping**.
pub const DEFAULT_RPDOS: &[PdoDefault] = &[
    empty(1, 0x200),
    empty(2, 0x300),
    empty(3, 0x400),
    empty(4, 0x500),
];

/// Power-on TPDOs: COB-IDs 180h…480h + node, transmission type **0**, **no mapping**.
pub const DEFAULT_TPDOS: &[PdoDefault] = &[
    empty(1, 0x180),
    empty(2, 0x280),
    empty(3, 0x380),
    empty(4, 0x480),
];

/// RPDO types: sync acyclic (0), sync cyclic (1–240; the ip example uses 1) and event-driven.
/// TPDO types: the same; RTR types are not mentioned (§2.1.1), so not offered.
pub const TYPES: TransmissionTypes = TransmissionTypes {
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
    rpdo_types: TYPES,
    tpdo_types: TYPES,
    rpdo_comm_subs: 5,
    default_rpdos: DEFAULT_RPDOS,
    default_tpdos: DEFAULT_TPDOS,
};

// ============================================================================================
// Object dictionary (§4.2–§4.4)
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

static ERRORS_1003: [EntryDesc; 6] = error_history::<6>();
static STORE_1010: [EntryDesc; 2] = store_record::<2>();
static RESTORE_1011: [EntryDesc; 2] = store_record::<2>();
static RPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x200, 0, 0, 0);
static RPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x300, 0, 0, 0);
static RPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x400, 0, 0, 0);
static RPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x500, 0, 0, 0);
static TPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x180, 0, 0, 0);
static TPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x280, 0, 0, 0);
static TPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x380, 0, 0, 0);
static TPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x480, 0, 0, 0);
static MAP_EMPTY: [EntryDesc; 9] = pdo_map::<9>(&[]);

/// The object dictionary of §4.2–§4.4 (P1-01 = 0x0C layouts), with the drive parameters the
/// master and the emulation use (P1-01, P1-44, P1-45, P3-00, P3-01, P3-09, P3-10, P3-11,
/// P3-12; index = 2000h + group × 100h + number). Every 6000h object marked "Y" in §4.3 is
/// mappable (RW → RPDO, RO → TPDO); 2xxxh parameters both ways; 1001h TPDO-mappable. Sorted.
pub static DICTIONARY: &[ObjectDesc] = &[
    var!(0x1000, "Device type", U32, RO, u(DEVICE_TYPE_A2 as u64)),
    var!(0x1001, "Error register", U8, RO_T, u(0)),
    rec!(0x1003, "Pre-defined error field", ARRAY, &ERRORS_1003),
    var!(0x1005, "COB-ID SYNC", U32, RW, u(0x80)),
    var!(0x1006, "Communication cycle period", U32, RW, u(0)),
    var!(0x100C, "Guard time", U16, RW, u(0)),
    var!(0x100D, "Life time factor", U8, RW, u(0)),
    rec!(0x1010, "Store parameters", ARRAY, &STORE_1010),
    rec!(0x1011, "Restore default parameters", ARRAY, &RESTORE_1011),
    var!(0x1014, "COB-ID EMCY", U32, RO, u(0x80)),
    rec!(
        0x1016,
        "Consumer heartbeat time",
        ARRAY,
        &[count(1, RO), e(1, "Consumer heartbeat time", U32, RW, u(0)),]
    ),
    var!(0x1017, "Producer heartbeat time", U16, RW, u(0)),
    rec!(
        0x1018,
        "Identity object",
        RECORD,
        &[
            count(3, RO),
            e(1, "Vendor ID", U32, RO, u(VENDOR_ID as u64)),
            e(2, "Product code", U32, RO, u(PRODUCT_A2 as u64)),
            e(3, "Revision number", U32, RO, u(EMU_REVISION as u64)),
        ]
    ),
    rec!(
        0x1029,
        "Error behaviour",
        ARRAY,
        &[count(1, RO), e(1, "Communication error", U8, RW, u(0))]
    ),
    rec!(
        0x1200,
        "Server SDO parameter",
        RECORD,
        &[
            count(2, RO),
            e(1, "COB-ID client to server", U32, RO, u(0x600)),
            e(2, "COB-ID server to client", U32, RO, u(0x580)),
        ]
    ),
    rec!(0x1400, "Receive PDO parameter 1", RECORD, &RPDO1_COMM),
    rec!(0x1401, "Receive PDO parameter 2", RECORD, &RPDO2_COMM),
    rec!(0x1402, "Receive PDO parameter 3", RECORD, &RPDO3_COMM),
    rec!(0x1403, "Receive PDO parameter 4", RECORD, &RPDO4_COMM),
    rec!(0x1600, "Receive PDO mapping 1", RECORD, &MAP_EMPTY),
    rec!(0x1601, "Receive PDO mapping 2", RECORD, &MAP_EMPTY),
    rec!(0x1602, "Receive PDO mapping 3", RECORD, &MAP_EMPTY),
    rec!(0x1603, "Receive PDO mapping 4", RECORD, &MAP_EMPTY),
    rec!(0x1800, "Transmit PDO parameter 1", RECORD, &TPDO1_COMM),
    rec!(0x1801, "Transmit PDO parameter 2", RECORD, &TPDO2_COMM),
    rec!(0x1802, "Transmit PDO parameter 3", RECORD, &TPDO3_COMM),
    rec!(0x1803, "Transmit PDO parameter 4", RECORD, &TPDO4_COMM),
    rec!(0x1A00, "Transmit PDO mapping 1", RECORD, &MAP_EMPTY),
    rec!(0x1A01, "Transmit PDO mapping 2", RECORD, &MAP_EMPTY),
    rec!(0x1A02, "Transmit PDO mapping 3", RECORD, &MAP_EMPTY),
    rec!(0x1A03, "Transmit PDO mapping 4", RECORD, &MAP_EMPTY),
    // --- drive parameters (§2.2, §4.4: every Px-yy is an object 2xxxh) -----------------------
    var!(
        0x2101,
        "P1-01 Control mode",
        I16,
        RW_RT,
        i(EMU_P1_01 as i64)
    ),
    var!(
        0x212C,
        "P1-44 Electronic gear numerator",
        I32,
        RW_RT,
        i(128)
    ),
    var!(
        0x212D,
        "P1-45 Electronic gear denominator",
        I32,
        RW_RT,
        i(10)
    ),
    var!(0x2300, "P3-00 Node ID", I16, RW_RT, i(0x7F)),
    var!(0x2301, "P3-01 Bit rate", I16, RW_RT, i(0x0203)),
    var!(0x2309, "P3-09 SYNC correction", I16, RW_RT, i(0x5055)),
    var!(0x230A, "P3-10 CANopen protocol setting", I16, RW_RT, i(0)),
    var!(0x230B, "P3-11 CANopen saving options", I16, RW_RT, i(0)),
    var!(
        0x230C,
        "P3-12 CANopen quick stop settings",
        I16,
        RW_RT,
        i(0)
    ),
    // --- 6000h group -------------------------------------------------------------------------
    var!(0x603F, "Error code", U16, RO_T, u(0)),
    var!(0x6040, "Controlword", U16, RW_R, u(0x0004)),
    var!(0x6041, "Statusword", U16, RO_T, u(0)),
    var!(0x605B, "Shutdown option code", I16, RW, i(0)),
    var!(0x605E, "Fault reaction option code", I16, RW, i(2)),
    var!(0x6060, "Modes of operation", I8, RW_R, i(0)),
    var!(0x6061, "Modes of operation display", I8, RO_T, i(0)),
    var!(0x6062, "Position demand value", I32, RO_T, i(0)),
    var!(
        0x6063,
        "Position actual value (increments)",
        I32,
        RO_T,
        i(0)
    ),
    var!(0x6064, "Position actual value", I32, RO_T, i(0)),
    var!(0x6065, "Following error window", U32, RW_R, u(3_840_000)),
    var!(0x6067, "Position window", U32, RW_R, u(100)),
    var!(0x6068, "Position window time", U16, RW_R, u(0)),
    var!(0x606B, "Velocity demand value", I32, RO_T, i(0)),
    var!(0x606C, "Velocity actual value", I32, RO_T, i(0)),
    var!(0x606D, "Velocity window", U16, RW_R, u(100)),
    var!(0x606E, "Velocity window time", U16, RW_R, u(0)),
    var!(0x606F, "Velocity threshold", U16, RW_R, u(100)),
    var!(0x6071, "Target torque", I16, RW_R, i(0)),
    var!(0x6074, "Torque demand value", I16, RO_T, i(0)),
    var!(
        0x6075,
        "Motor rated current",
        U32,
        RO_T,
        u(EMU_RATED_CURRENT_MA as u64)
    ),
    var!(
        0x6076,
        "Motor rated torque",
        U32,
        RO_T,
        u(EMU_RATED_TORQUE as u64)
    ),
    var!(0x6077, "Torque actual value", I16, RO_T, i(0)),
    var!(0x6078, "Current actual value", I16, RO_T, i(0)),
    var!(0x607A, "Target position", I32, RW_R, i(0)),
    var!(0x607C, "Home offset", I32, RW_R, i(0)),
    rec!(
        0x607D,
        "Software position limit",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Min position limit", I32, RW_R, i(i32::MIN as i64)),
            e(2, "Max position limit", I32, RW_R, i(i32::MAX as i64)),
        ]
    ),
    var!(
        0x607F,
        "Max profile velocity",
        U32,
        RW_R,
        u(EMU_MAX_SPEED_RPM as u64 * 10)
    ),
    var!(
        0x6080,
        "Max motor speed",
        U32,
        RW_R,
        u(EMU_MAX_SPEED_RPM as u64)
    ),
    var!(0x6081, "Profile velocity", U32, RW_R, u(10_000)),
    var!(0x6083, "Profile acceleration", U32, RW_R, u(200)),
    var!(0x6084, "Profile deceleration", U32, RW_R, u(200)),
    var!(0x6085, "Quick stop deceleration", U32, RW_R, u(0)),
    var!(0x6086, "Motion profile type", I16, RW_R, i(0)),
    var!(0x6087, "Torque slope", U32, RW_R, u(0)),
    rec!(
        0x6093,
        "Position factor",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Numerator", U32, RW_R, u(1)),
            e(2, "Feed constant", U32, RW_R, u(1)),
        ]
    ),
    var!(0x6098, "Homing method", I8, RW_R, i(0)),
    rec!(
        0x6099,
        "Homing speeds",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Speed during search for switch", U32, RW_R, u(100)),
            e(2, "Speed during search for zero", U32, RW_R, u(20)),
        ]
    ),
    var!(0x609A, "Homing acceleration", U32, RW_R, u(100)),
    var!(0x60B0, "Position offset", I32, RW_R, i(0)),
    var!(0x60B1, "Velocity offset", I32, RW_R, i(0)),
    var!(0x60B2, "Torque offset", I16, RW_R, i(0)),
    var!(0x60C0, "Interpolation sub mode select", I16, RW_R, i(0)),
    rec!(
        0x60C1,
        "Interpolation data record",
        ARRAY,
        &[
            count(2, RO),
            e(1, "Position command", I32, RW_R, i(0)),
            e(2, "Position difference", I16, RW_R, i(0)),
        ]
    ),
    rec!(
        0x60C2,
        "Interpolation time period",
        RECORD,
        &[
            count(2, RO),
            EntryDesc::new(1, "Interpolation time units", U8, RW_R)
                .default(u(1))
                .range(u(1), u(20)),
            e(2, "Interpolation time index", I8, RW_R, i(-3)),
        ]
    ),
    var!(0x60C5, "Max acceleration", U32, RW_R, u(200)),
    var!(0x60C6, "Max deceleration", U32, RW_R, u(200)),
    var!(0x60F2, "Positioning option code", U16, RW_R, u(0)),
    var!(0x60F4, "Following error actual value", I32, RO_T, i(0)),
    var!(
        0x60FC,
        "Position demand value (increments)",
        I32,
        RO_T,
        i(0)
    ),
    var!(0x60FD, "Digital inputs", U32, RO_T, u(0)),
    var!(0x60FF, "Target velocity", I32, RW_R, i(0)),
    var!(0x6502, "Supported drive modes", U32, RO_T, u(0x0000_006D)),
];

// ============================================================================================
// Units, enable conditions, homing, communication
// ============================================================================================

/// Units (§6 of the reference): PUU, 1,280,000 per revolution with 6093h = 1:1; 60FFh/606Ch in
/// 0.1 r/min; 6081h in PUU/s; homing speeds 0.1 r/min (P1-01 = 0x0C); accelerations as the
/// time in ms from 0 to 3000 r/min; torque slope as ms from 0 to 100 % rated torque; torque ‰.
pub const UNITS: Units = Units {
    position_name: "PUU",
    position_per_rev: 1_280_000.0,
    velocity: VelocityUnit::RevPerMinute { scale: 0.1 },
    torque_per_mille: 1.0,
    profile: Some(ProfileUnits {
        profile_velocity: VelocityUnit::PositionPerSecond,
        homing_velocity: VelocityUnit::RevPerMinute { scale: 0.1 },
        acceleration: AccelUnit::MillisecondsTo { rpm: 3000.0 },
        torque_slope: TorqueSlopeUnit::MillisecondsToRated,
    }),
};

/// P1-01 (2101h): control mode 0x0C = CANopen full (standard DS402). Checked, not written (a
/// mode change needs a restart).
pub const P1_01: ObjectAddress = ObjectAddress::new(0x2101, 0);
/// P3-12 (230Ch): digit X (bits 0–3) = 1 → servo on only with bits 0, 1 and 3 (DS402).
pub const P3_12: ObjectAddress = ObjectAddress::new(0x230C, 0);

/// Enable preconditions: P1-01 = 0x0C, P3-12 X = 1; 60FFh and 6071h are cleared when the drive
/// enables (write them afterwards).
pub const ENABLE: EnableConditions = EnableConditions {
    remote_required: false,
    voltage_required: false,
    needs_operational: false,
    settings: &[
        ParamSetting {
            addr: P1_01,
            mask: 0x00FF,
            value: 0x0C,
            writable: false,
            why: "P1-01 must be 0x0C (CANopen full, DS402); 0x0B is Delta's simplified mode",
        },
        ParamSetting {
            addr: P3_12,
            mask: 0x000F,
            value: 0x0001,
            writable: true,
            why: "P3-12 X = 1: servo on only by the DS402 sequence (X = 0 switches on with \
                  controlword bit 3 alone)",
        },
    ],
    targets_cleared_on_enable: &[ObjectAddress::new(0x60FF, 0), ObjectAddress::new(0x6071, 0)],
    notes: "60FFh/6071h are also cleared on mode change, servo off and quick stop",
};

/// Homing (§4.4 6098h): methods 0 (none, default) and 1–35 except the reserved 15, 16, 31, 32.
pub const HOMING: HomingSupport = HomingSupport {
    methods: &[
        0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26,
        27, 28, 29, 30, 33, 34, 35,
    ],
    default_method: 0,
    index_pulse: true,
};

/// Delta's SDO abort codes beyond CiA 301 (§5.3).
pub const VENDOR_ABORT_CODES: &[(u32, &str)] = &[
    (0x0800_00A1, "Object error when reading from EEPROM"),
    (0x0800_00A2, "Object error when writing to EEPROM"),
    (0x0800_00A3, "Invalid range when accessing EEPROM"),
    (0x0800_00A4, "Checksum error when accessing EEPROM"),
    (
        0x0800_00A5,
        "Password error when writing the encrypted zone",
    ),
];

/// Communication: guarding and heartbeat (1016h one entry), SYNC consumer only, 1006h, 5
/// error-history entries, store sub 01h only, **≤ 1 SDO per ms** (AL111) and **≤ 1 PDO per
/// COB-ID per ms** (AL112).
pub const COMM: CommSupport = CommSupport {
    guarding: true,
    heartbeat_consumers: 1,
    sync_producer: false,
    has_cycle_period: true,
    cycle_period_granularity_us: 0,
    error_history: 5,
    store_subs: 1,
    sdo_min_interval_us: 1000,
    rpdo_min_interval_us: 1000,
};

/// The ASDA-A2 profile.
pub const PROFILE: CanDriveProfile = CanDriveProfile {
    name: "ASDA-A2",
    vendor: "Delta Electronics",
    caps: CAPS,
    dictionary: DICTIONARY,
    units: UNITS,
    bus: CanOpen {
        source: "Delta CANopen for ASDA-A2, V2.01 (2012-09-20)",
        identity: IDENTITY,
        default_node_id: Some(0x7F),
        default_bitrate_kbit: 500,
        bitrates_kbit: &[1000, 750, 500, 250, 125],
        modes_note: "6502h = 0000 006Dh (pp, pv, tq, hm, ip); 6060h 0 is reserved (default)",
        pdo: PDO,
        enable: ENABLE,
        homing: HOMING,
        emcy: EmcyFormat::AlarmInBytes3To4,
        alarms: ALARMS,
        vendor_abort_codes: VENDOR_ABORT_CODES,
        comm: COMM,
        nmt_stop_while_enabled: EnabledNmtReaction::Alarm(alarm::NMT_WHILE_ENABLED),
        nmt_reset_while_enabled: EnabledNmtReaction::Alarm(alarm::NMT_WHILE_ENABLED),
        // §5.2: interpolation runs whenever mode 7 is active.
        ip_needs_enable_bit: false,
        // Statusword bit 12 in pv: zero speed.
        pv_zero_speed_bit: true,
    },
};

// ============================================================================================
// MANUAL GAP / [REC] / DISCREPANCY — every value above that is not vendor fact
// ============================================================================================
//
// - MANUAL GAP: the fixed quick-stop behaviour (605Ah absent): [REC] quick-stop ramp, then
//   Switch on disabled; transition 16 assumed absent.
// - MANUAL GAP: 1018h:03 revision ("N/A"): `EMU_REVISION`.
// - MANUAL GAP: 607Fh/6080h defaults come from P1-55, whose value is in the user manual:
//   `EMU_MAX_SPEED_RPM`. 6075h/6076h values: `EMU_RATED_CURRENT_MA`, `EMU_RATED_TORQUE`.
// - MANUAL GAP: P1-01's factory value is not in this manual; the emulation runs in CANopen
//   full mode (`EMU_P1_01`).
// - DISCREPANCY: 6061h ro (§4.3) vs RW (§4.4); 606Dh UINT16 rw vs INT16 ro; 6077h INT16 vs
//   UINT16: §4.3 types used where they agree with CiA 402 (ro, UINT16, INT16).
// - DISCREPANCY: 6087h default 0 (§4.4) vs 200 (P3-12 table): 0 used (object default).
// - DISCREPANCY: 6093h default 1:1 vs P1-44/P1-45 factory 128:10: 1:1 used (object default;
//   P3-12 Z decides which survives a reset).
// - DISCREPANCY: P3-12 text "bit 2 = 1 → quick stop" vs the 6040h table "B-contact": the CiA
//   reading (quick stop when bit 2 = 0) is used.

/// **MANUAL GAP** → \[REC\] 1018h:03 of the emulated node.
pub const EMU_REVISION: u32 = 0x0000_0001;
/// **MANUAL GAP** → \[REC\] P1-55 maximum speed, r/min (for 6080h, 607Fh and the motor model).
pub const EMU_MAX_SPEED_RPM: u32 = 5000;
/// **MANUAL GAP** → \[REC\] 6075h of the emulated node, mA.
pub const EMU_RATED_CURRENT_MA: u32 = 2_600;
/// **MANUAL GAP** → \[REC\] 6076h of the emulated node.
pub const EMU_RATED_TORQUE: u32 = 1_000;
/// **MANUAL GAP** → \[REC\] P1-01 of the emulated node: 0x0C (CANopen full).
pub const EMU_P1_01: i16 = 0x0C;

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
