//! The emulated Oriental Motor BLV series R type driver (BLVD-KRD / BLVD-KBRD) on CANopen: the
//! emulator's own [`NodeSpec`], written from the vendor's manual *Brushless Motor BLV series R
//! type Driver — CANopen communication profile*, independently of the master's drive profile.
//!
//! "§x.y" below is a section of that manual, "App." its object list (§9.1). The manual defers
//! user units, operation data, vendor homing and the I/O functions to the *BLV Series R Type
//! OPERATING MANUAL Function Edition* (HP-5142), which is not part of the emulator's sources.
//!
//! What the spec holds:
//! - identity (§8.1 1000h, 1008h, 1018h; §8.3 67FEh, 67FFh), emulating **driver version 4.00**:
//!   6502h = 0000 002Dh (tq supported, §7.1.1, §8.3 6502h);
//! - the CiA 402 state machine (§5.1, §6, §6.2): no transition 16, the remote bit (statusword
//!   bit 9) gates every command except quick stop, fault reset and halt (§7.2.3 note, §7.2.4),
//!   quick-stop codes −3…2, 5, 6 with default 2 (§8.3 605Ah);
//! - the alarm table (§4.5): EMCY codes FFxxh = FF00h + alarm code with error register 81h, the
//!   CAN-side codes 81xxh / 8210h with 11h; EMCY bytes 3–7 are 00h (§4.5);
//! - the PDO rules (§4.7, §8.1): 4 RPDOs + 4 TPDOs of at most 4 entries, RPDO transmission types
//!   00h, FEh, FFh only, RPDO communication records with sub-indices 0–2, TPDO records 0–3 and 5
//!   (sub 04h does not exist), the power-on mappings and COB-IDs (TPDO bit 30 set), 5 ms TPDO
//!   inhibit time, TPDO3/4 on every SYNC;
//! - the object dictionary: every object of §8.1–§8.3 / App.;
//! - units (§1.2, §8.3 608Fh): 36,000 steps per motor revolution, r/min, (r/min)/s, 0.1 % of
//!   rated torque, 0.1 %/s;
//! - homing (§7.5.5, §8.3 60E3h, 6098h): methods 37, 35, 1, 2, 8, 12, 17, 18, 24, 28, −1,
//!   default 37, index pulse = ZSG-N;
//! - NMT error control, SYNC producer, 1006h granularity, error history and store (§4.2–§4.5,
//!   §8.1).
//!
//! Values the manual does not state are marked **\[REC\]** (the emulator's choice) and listed,
//! with the places where the manual contradicts itself, at the end of the file.

use super::super::quirks::EmulationQuirks;
use super::super::spec::NodeSpec;
use crate::can::profile::od::{
    I8, I16, I32, RO, RO_T, RW, RW_R, RW_RT, STR, U8, U16, U32, count, e, error_history, i,
    pdo_comm, pdo_map, u,
};
use crate::can::profile::{
    Alarm, CanPdoProfile, CommSupport, EmcyFormat, EnabledNmtReaction, HomingSupport, PdoDefault,
    TransmissionTypes,
};
use crate::cia402::units::{AccelUnit, TorqueSlopeUnit, Units, VelocityUnit};
use crate::cia402::{
    DriveCaps, ErrorEntry, ProfileUnits, QuickStopEnd, QuickStopOption, StopRamp, SupportedModes,
};
use crate::od::{ConstValue, EntryDesc, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, PdoEntry, PdoLimits, PdoRange};

// =============================================================================================
// Identity
// =============================================================================================

/// The manual the values come from (its title page).
pub const SOURCE: &str =
    "Oriental Motor, Brushless Motor BLV series R type Driver — CANopen communication profile";

/// 1018h:01 vendor ID (§8.1).
pub const VENDOR_ID: u32 = 0x0000_02BE;

/// 1018h:02 product code of the BLVD-KRD (§8.1). The emulated model.
pub const PRODUCT_CODE_KRD: u32 = 0x0000_13F7;

/// 1018h:02 product code of the BLVD-KBRD (§8.1).
pub const PRODUCT_CODE_KBRD: u32 = 0x0000_1430;

/// The models the manual covers, with their product codes (§8.1 1008h, 1018h).
pub const PRODUCTS: &[(u32, &str)] = &[
    (PRODUCT_CODE_KRD, "BLVD-KRD"),
    (PRODUCT_CODE_KBRD, "BLVD-KBRD"),
];

/// 1000h device type (§8.1): additional information 2 (servo drive, "brushless motor driver"),
/// device profile 402 (0192h).
pub const DEVICE_TYPE: u32 = 0x0002_0192;

/// 67FFh single device type (§8.3): the same value as 1000h.
pub const SINGLE_DEVICE_TYPE: u32 = 0x0002_0192;

/// 67FEh version number (§8.3): major 4, minor 1, sub 0.
pub const VERSION_NUMBER: u32 = 0x0004_0100;

/// 1008h manufacturer device name of the emulated model (§8.1).
pub const DEVICE_NAME: &str = "BLVD-KRD";

/// 1009h manufacturer hardware version. **Example only**: §8.1 says "Rev.1.00" is shown for
/// version 1.00 and gives no actual value.
pub const HW_VERSION: &str = "Rev.1.00";

/// 100Ah manufacturer software version. **Example only**: §8.1 says "V.1.00" is shown for
/// version 1.00. It is not the driver (firmware) version of §4.7.2 / §7.1.1 (§4.7.2: "This
/// 'firmware version' does not mean 'software version object (100Ah)'").
pub const SW_VERSION: &str = "V.1.00";

/// 6502h with the torque mode: driver version 4.00 or later (§7.1.1, §8.3 6502h): pp, pv, tq,
/// hm. The emulated value.
pub const SUPPORTED_MODES_V4: u32 = 0x0000_002D;

/// 6502h before driver version 4.00 (§8.3 6502h, App.): pp, pv, hm.
pub const SUPPORTED_MODES_BEFORE_V4: u32 = 0x0000_0025;

/// Bit rates the support software offers, kbit/s (§2.3, §9.2).
pub const BITRATES_KBIT: &[u16] = &[1000, 800, 500, 250, 125, 50, 20, 10];

/// Factory bit rate, kbit/s (§2.3).
pub const DEFAULT_BITRATE_KBIT: u16 = 500;

/// Node-IDs the driver accepts (§2.3, §9.2). The factory node-ID is not stated (MANUAL GAP).
pub const NODE_IDS: core::ops::RangeInclusive<u8> = 1..=127;

// =============================================================================================
// CiA 402 capabilities
// =============================================================================================

/// The quick-stop option codes of 605Ah (§8.3): −3 custom stopping time (4736h), −2 custom
/// stopping rate (4735h), −1 immediate stop, each staying in Quick stop active; 0 immediate
/// stop, 1 slow-down ramp, 2 quick-stop ramp 6085h, each then Switch on disabled; 5 slow-down
/// ramp and 6 quick-stop ramp, staying. 3 and 4 are not listed.
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

/// The state machine and modes (§5.1, §6, §6.2, §7.1, §8.3).
pub const CAPS: DriveCaps = DriveCaps {
    // §6 lists "Switch ON + Enable Operation" (3 + 4, automatic) from Ready to switch on, which
    // is the CiA 402 table's own row; no jump from Switch on disabled is described. [REC]: no
    // vendor state skipping (see DISCREPANCY 1).
    state_skipping: false,
    // §6.2: "16 Not supported".
    transition_16: false,
    quick_stop_options: QUICK_STOP_OPTIONS,
    // §8.3 605Ah: default 2.
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    // MANUAL GAP: no rule on switching modes at speed; [REC] none.
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    // §7.2.3 / §7.3.3 / §7.5.3 notes, §7.2.4 footnote: remote (bit 9) = 0 while the S-ON input
    // is active or the support software operates the driver; then only quick stop, fault reset
    // and halt act.
    remote_gates_controlword: true,
    // Driver version 4.00 emulated: pp, pv, tq, hm (§8.3 6502h).
    supported_modes: SupportedModes::from_raw(SUPPORTED_MODES_V4),
    error_table: ERROR_TABLE,
    csp_start_edge: false,
    // §4.5: alarm 62h "Return-to-home operation error" (the manual does not tie it to
    // statusword bit 13 explicitly; §7.5.4 only defines bit 13).
    homing_failure: "alarm 62h return-to-home operation error (EMCY FF62h)",
    // §8.3 607Ch: rww, the master writes it.
    home_offset_set_by_drive: None,
    // MANUAL GAP: nothing about SDO writes to RPDO-mapped objects.
    sdo_refused_while_rx_mapped: None,
    // §8.3 607Ah: the full INT32 range.
    pp_target_range: None,
};

// =============================================================================================
// Alarm table (§4.5) and error-code names
// =============================================================================================

/// Builds the alarm table and the error-code table from one list.
macro_rules! blv_alarms {
    (
        comm: [$(($cc:literal, $cname:literal, $ctext:literal)),* $(,)?],
        alarms: [$(($n:literal, $name:literal, $text:literal)),* $(,)?] $(,)?
    ) => {
        /// Every EMCY error code of §4.5. The CAN-side codes (81xxh, 8210h, error register
        /// 11h) carry their code as vendor number; the driver alarms are FF00h + alarm code
        /// with error register 81h, and the vendor number is the alarm code (EMCY byte 0,
        /// [`EmcyFormat::AlarmInCodeLowByte`]). Every driver alarm is a fault (§5.1: a
        /// non-excitation alarm puts the driver in Fault); the CAN-side codes are reported
        /// without Fault (\[REC\], MANUAL GAP).
        pub static ALARMS: &[Alarm] = &[
            $(Alarm {
                number: $cc,
                code: $cc,
                register: 0x11,
                name: $cname,
                text: $ctext,
                fault: false,
            },)*
            $(Alarm {
                number: $n,
                code: 0xFF00 | $n,
                register: 0x81,
                name: $name,
                text: $text,
                fault: true,
            },)*
        ];

        /// The driver's error codes (603Fh = latest alarm + FF00h, §8.3 603Fh; EMCY §4.5),
        /// looked up before the CiA tables; the last row catches any other FFxxh.
        pub const ERROR_TABLE: &[ErrorEntry] = &[
            $(ErrorEntry::exact(0xFF00 | $n, $name, $text),)*
            ErrorEntry {
                code: 0xFF00,
                mask: 0xFF00,
                name: "Alarm",
                text: "BLV-R driver alarm (alarm code = error code − FF00h)",
            },
        ];
    };
}

blv_alarms! {
    comm: [
        (0x8110, "EMCY 8110h", "CAN overrun"),
        (0x8120, "EMCY 8120h", "CAN in error passive mode"),
        (0x8130, "EMCY 8130h", "Node guarding error or heartbeat error"),
        (0x8140, "EMCY 8140h", "Recover from Bus-Off state"),
        (0x8210, "EMCY 8210h", "PDO not processed due to length error"),
    ],
    alarms: [
        (0x10, "Alarm 10h", "Position deviation"),
        (0x20, "Alarm 20h", "Overcurrent"),
        (0x21, "Alarm 21h", "Main circuit overheat"),
        (0x22, "Alarm 22h", "Overvoltage"),
        (0x25, "Alarm 25h", "Undervoltage"),
        (0x26, "Alarm 26h", "Motor overheat"),
        (0x28, "Alarm 28h", "Encoder error"),
        (0x29, "Alarm 29h", "Internal circuit error"),
        (0x2A, "Alarm 2Ah", "Encoder communication error"),
        (0x30, "Alarm 30h", "Overload"),
        (0x31, "Alarm 31h", "Overspeed"),
        (0x41, "Alarm 41h", "EEPROM error"),
        (0x42, "Alarm 42h", "Initial encoder error"),
        (0x44, "Alarm 44h", "Encoder EEPROM error"),
        (0x45, "Alarm 45h", "Motor combination error"),
        (0x4A, "Alarm 4Ah", "Return-to-home incomplete"),
        (0x50, "Alarm 50h", "Electromagnetic brake overcurrent"),
        (0x53, "Alarm 53h", "HWTO input circuit error"),
        (0x55, "Alarm 55h", "Electromagnetic brake connection error"),
        (0x60, "Alarm 60h", "±LS both sides active"),
        (0x61, "Alarm 61h", "Reverse ±LS connection"),
        (0x62, "Alarm 62h", "Return-to-home operation error"),
        (0x63, "Alarm 63h", "No HOMES"),
        (0x64, "Alarm 64h", "Z, SLIT signal error"),
        (0x66, "Alarm 66h", "Hardware overtravel"),
        (0x67, "Alarm 67h", "Software overtravel"),
        (0x68, "Alarm 68h", "HWTO input detection"),
        (0x6A, "Alarm 6Ah", "Return-to-home additional operation error"),
        (0x70, "Alarm 70h", "Operation data error"),
        (0x71, "Alarm 71h", "Unit setting error"),
        (0x81, "Alarm 81h", "Network bus error"),
        (0x84, "Alarm 84h", "RS-485 communication error"),
        (0x85, "Alarm 85h", "RS-485 communication timeout"),
        (0x8C, "Alarm 8Ch", "Outside setting range"),
        (0xF0, "Alarm F0h", "CPU error"),
        (0xF3, "Alarm F3h", "CPU overload"),
    ],
}

/// EMCY bytes 3–7 are 00h; the alarm code is the low byte of the FFxxh error code (§4.5).
pub const EMCY: EmcyFormat = EmcyFormat::AlarmInCodeLowByte;

// =============================================================================================
// PDO rules (§4.7, §8.1)
// =============================================================================================

/// RPDO1 power-on mapping (§8.1 1600h): controlword.
pub const RPDO1_MAPPING: &[PdoEntry] = &[PdoEntry::new(0x6040, 0, 16)];
/// RPDO2 power-on mapping (§8.1 1601h): controlword, modes of operation.
pub const RPDO2_MAPPING: &[PdoEntry] = &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x6060, 0, 8)];
/// RPDO3 power-on mapping (§8.1 1602h): controlword, target position.
pub const RPDO3_MAPPING: &[PdoEntry] =
    &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)];
/// RPDO4 power-on mapping (§8.1 1603h): controlword, target velocity.
pub const RPDO4_MAPPING: &[PdoEntry] =
    &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x60FF, 0, 32)];
/// TPDO1 power-on mapping (§8.1 1A00h): statusword.
pub const TPDO1_MAPPING: &[PdoEntry] = &[PdoEntry::new(0x6041, 0, 16)];
/// TPDO2 power-on mapping (§8.1 1A01h): statusword, modes of operation display.
pub const TPDO2_MAPPING: &[PdoEntry] = &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6061, 0, 8)];
/// TPDO3 power-on mapping (§8.1 1A02h): statusword, position actual value.
pub const TPDO3_MAPPING: &[PdoEntry] =
    &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6064, 0, 32)];
/// TPDO4 power-on mapping (§8.1 1A03h): statusword, velocity actual value.
pub const TPDO4_MAPPING: &[PdoEntry] =
    &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x606C, 0, 32)];

/// TPDO inhibit time at power-on, × 100 µs (§8.1 1800h–1803h:03): 5 ms.
pub const TPDO_INHIBIT_DEFAULT: u16 = 50;

/// TPDO bit 30 "no RTR allowed", set in every power-on TPDO COB-ID (§8.1 1800h–1803h:01).
const NO_RTR: u32 = 0x4000_0000;

/// The power-on RPDOs (§8.1 1400h–1403h, 1600h–1603h): all valid, transmission type 255.
pub const DEFAULT_RPDOS: &[PdoDefault] = &[
    PdoDefault {
        number: 1,
        cob_id: 0x200,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: RPDO1_MAPPING,
    },
    PdoDefault {
        number: 2,
        cob_id: 0x300,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: RPDO2_MAPPING,
    },
    PdoDefault {
        number: 3,
        cob_id: 0x400,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: RPDO3_MAPPING,
    },
    PdoDefault {
        number: 4,
        cob_id: 0x500,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: RPDO4_MAPPING,
    },
];

/// The power-on TPDOs (§8.1 1800h–1803h, 1A00h–1A03h): all valid with bit 30 (no RTR) set,
/// TPDO1/2 event-driven (255), TPDO3/4 on every SYNC (1), inhibit 5 ms, no event timer.
pub const DEFAULT_TPDOS: &[PdoDefault] = &[
    PdoDefault {
        number: 1,
        cob_id: NO_RTR | 0x180,
        transmission_type: 255,
        inhibit_time: TPDO_INHIBIT_DEFAULT,
        event_timer: 0,
        mapping: TPDO1_MAPPING,
    },
    PdoDefault {
        number: 2,
        cob_id: NO_RTR | 0x280,
        transmission_type: 255,
        inhibit_time: TPDO_INHIBIT_DEFAULT,
        event_timer: 0,
        mapping: TPDO2_MAPPING,
    },
    PdoDefault {
        number: 3,
        cob_id: NO_RTR | 0x380,
        transmission_type: 1,
        inhibit_time: TPDO_INHIBIT_DEFAULT,
        event_timer: 0,
        mapping: TPDO3_MAPPING,
    },
    PdoDefault {
        number: 4,
        cob_id: NO_RTR | 0x480,
        transmission_type: 1,
        inhibit_time: TPDO_INHIBIT_DEFAULT,
        event_timer: 0,
        mapping: TPDO4_MAPPING,
    },
];

/// RPDO transmission types (§4.7.2, §8.1 1400h:02): 00h (applied at the next SYNC), FEh
/// (immediately; also triggers the paired TPDO and resets the node life time, firmware 2.02 or
/// later), FFh (immediately). 01h–F0h, FCh, FDh are refused with 0609 0030h.
pub const RPDO_TYPES: TransmissionTypes = TransmissionTypes {
    sync_acyclic: true,
    sync_cyclic: false,
    rtr_sync: false,
    rtr_event: false,
    event_manufacturer: true,
    event_profile: true,
};

/// TPDO transmission types (§4.7.2, §8.1 1800h:02): 00h, 01h–F0h, FCh, FDh, FEh, FFh (F1h–FBh
/// reserved).
pub const TPDO_TYPES: TransmissionTypes = TransmissionTypes::ALL;

/// Mapping objects and entries (§4.7, §8.1 1600h–1603h / 1A00h–1A03h sub 00h range 0–4, 8
/// bytes per CAN frame). Every PDO may be valid at once (§9.2: 4 RPDO, 4 TPDO).
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "BLV-R",
    rx: DirectionLimits {
        pdos: &[PdoRange::new(0x1600, 0x1603, 4)],
        max_assigned: 4,
        max_entries: 16,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: &[PdoRange::new(0x1A00, 0x1A03, 4)],
        max_assigned: 4,
        max_entries: 16,
        max_bytes: 32,
    },
    // [REC]: CANopen has no 1C12h/1C13h; a PDO is switched on and off with bit 31 of its
    // COB-ID (§4.7.1), which the master may write.
    assignment_writable: true,
};

/// The PDO rules.
pub const PDO: CanPdoProfile = CanPdoProfile {
    limits: PDO_LIMITS,
    max_pdo_bytes: 8,
    rpdo_types: RPDO_TYPES,
    tpdo_types: TPDO_TYPES,
    // §8.1 1400h–1403h:00 = 2 (COB-ID and transmission type only).
    rpdo_comm_subs: 2,
    default_rpdos: DEFAULT_RPDOS,
    default_tpdos: DEFAULT_TPDOS,
};

// =============================================================================================
// Object dictionary (§8.1, §8.2, §8.3, App.)
// =============================================================================================

/// No value given by the manual ("–"): the store starts at zero / empty.
const NONE: ConstValue = ConstValue::None;

/// A VAR object.
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

/// A VAR object with the range the manual gives.
macro_rules! var_r {
    ($index:literal, $name:literal, $dt:expr, $acc:expr, $def:expr, $min:expr, $max:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[e(0, $name, $dt, $acc, $def).range($min, $max)],
        }
    };
}

/// 1003h: 10 entries (§8.1); sub 00h rw (§8.1; App. says ro, DISCREPANCY 3), range 0–10
/// (App.).
static ERROR_FIELD: [EntryDesc; 11] = {
    let mut a = error_history::<11>();
    a[0] = EntryDesc::new(0, "Number of errors", U8, RW)
        .default(u(0))
        .range(u(0), u(10));
    a
};

static RPDO1_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x200, 255, 0, 0);
static RPDO2_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x300, 255, 0, 0);
static RPDO3_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x400, 255, 0, 0);
static RPDO4_COMM: [EntryDesc; 3] = pdo_comm::<3>(0x500, 255, 0, 0);

static RPDO1_MAP: [EntryDesc; 5] = pdo_map::<5>(&[RPDO1_MAPPING[0].to_u32()]);
static RPDO2_MAP: [EntryDesc; 5] =
    pdo_map::<5>(&[RPDO2_MAPPING[0].to_u32(), RPDO2_MAPPING[1].to_u32()]);
static RPDO3_MAP: [EntryDesc; 5] =
    pdo_map::<5>(&[RPDO3_MAPPING[0].to_u32(), RPDO3_MAPPING[1].to_u32()]);
static RPDO4_MAP: [EntryDesc; 5] =
    pdo_map::<5>(&[RPDO4_MAPPING[0].to_u32(), RPDO4_MAPPING[1].to_u32()]);

static TPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(NO_RTR | 0x180, 255, TPDO_INHIBIT_DEFAULT, 0);
static TPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(NO_RTR | 0x280, 255, TPDO_INHIBIT_DEFAULT, 0);
static TPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(NO_RTR | 0x380, 1, TPDO_INHIBIT_DEFAULT, 0);
static TPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(NO_RTR | 0x480, 1, TPDO_INHIBIT_DEFAULT, 0);

// 1A00h–1A03h sub 00h: rw (§8.1; App. says ro, DISCREPANCY 4).
static TPDO1_MAP: [EntryDesc; 5] = pdo_map::<5>(&[TPDO1_MAPPING[0].to_u32()]);
static TPDO2_MAP: [EntryDesc; 5] =
    pdo_map::<5>(&[TPDO2_MAPPING[0].to_u32(), TPDO2_MAPPING[1].to_u32()]);
static TPDO3_MAP: [EntryDesc; 5] =
    pdo_map::<5>(&[TPDO3_MAPPING[0].to_u32(), TPDO3_MAPPING[1].to_u32()]);
static TPDO4_MAP: [EntryDesc; 5] =
    pdo_map::<5>(&[TPDO4_MAPPING[0].to_u32(), TPDO4_MAPPING[1].to_u32()]);

/// The power-on object dictionary, sorted by index. COB-IDs of node-relative objects are
/// written for node-ID 0.
pub static DICTIONARY: &[ObjectDesc] = &[
    // ----- communication objects (§8.1) -----------------------------------------------------
    var!(0x1000, "Device type", U32, RO, u(DEVICE_TYPE as u64)),
    var!(0x1001, "Error register", U8, RO, NONE),
    ObjectDesc {
        index: 0x1003,
        name: "Pre-defined error field",
        code: ObjectCode::Array,
        entries: &ERROR_FIELD,
    },
    var_r!(
        0x1005,
        "COB-ID SYNC message",
        U32,
        RW,
        u(0x0000_0080),
        u(0),
        u(0xFFFF_FFFF)
    ),
    // Multiples of 250 µs only (§8.1 1006h; CommSupport::cycle_period_granularity_us).
    var_r!(
        0x1006,
        "Communication cycle period",
        U32,
        RW,
        u(0),
        u(0),
        u(1_000_000)
    ),
    var!(
        0x1008,
        "Manufacturer device name",
        STR,
        RO,
        ConstValue::Str(DEVICE_NAME)
    ),
    var!(
        0x1009,
        "Manufacturer hardware version",
        STR,
        RO,
        ConstValue::Str(HW_VERSION)
    ),
    var!(
        0x100A,
        "Manufacturer software version",
        STR,
        RO,
        ConstValue::Str(SW_VERSION)
    ),
    var_r!(0x100C, "Guard time", U16, RW, u(0), u(0), u(65_535)),
    var_r!(0x100D, "Life time factor", U8, RW, u(0), u(0), u(255)),
    // Reading a sub returns bit 0 = 1 (saves on command), bit 1 = 0 (§8.1 1010h).
    ObjectDesc {
        index: 0x1010,
        name: "Store parameters",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Save all parameters", U32, RW, u(1)),
            e(2, "Save communication parameters", U32, RW, u(1)),
        ],
    },
    // Reading a sub returns bit 0 = 1 (restores on command) (§8.1 1011h).
    ObjectDesc {
        index: 0x1011,
        name: "Restore default parameters",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Restore all default parameters", U32, RW, u(1)),
            e(2, "Restore communication default parameters", U32, RW, u(1)),
        ],
    },
    // 80h + node-ID (§8.1 1014h).
    var_r!(
        0x1014,
        "COB-ID EMCY",
        U32,
        RW,
        u(0x80),
        u(0),
        u(0xFFFF_FFFF)
    ),
    ObjectDesc {
        index: 0x1016,
        name: "Consumer heartbeat time",
        code: ObjectCode::Array,
        entries: &[
            count(1, RO),
            e(1, "Consumer heartbeat time", U32, RW, u(0)).range(u(0), u(0x00FF_FFFF)),
        ],
    },
    var_r!(
        0x1017,
        "Producer heartbeat time",
        U16,
        RW,
        u(0),
        u(0),
        u(65_535)
    ),
    ObjectDesc {
        index: 0x1018,
        name: "Identity object",
        code: ObjectCode::Record,
        entries: &[
            count(2, RO),
            e(1, "Vendor ID", U32, RO, u(VENDOR_ID as u64)),
            e(2, "Product code", U32, RO, u(PRODUCT_CODE_KRD as u64)),
        ],
    },
    // 600h / 580h + node-ID, read-only (§8.1 1200h).
    ObjectDesc {
        index: 0x1200,
        name: "SDO server parameter",
        code: ObjectCode::Record,
        entries: &[
            count(2, RO),
            e(1, "COB-ID client -> server (rx)", U32, RO, u(0x600)),
            e(2, "COB-ID server -> client (tx)", U32, RO, u(0x580)),
        ],
    },
    ObjectDesc {
        index: 0x1400,
        name: "1st RPDO communication parameter",
        code: ObjectCode::Record,
        entries: &RPDO1_COMM,
    },
    ObjectDesc {
        index: 0x1401,
        name: "2nd RPDO communication parameter",
        code: ObjectCode::Record,
        entries: &RPDO2_COMM,
    },
    ObjectDesc {
        index: 0x1402,
        name: "3rd RPDO communication parameter",
        code: ObjectCode::Record,
        entries: &RPDO3_COMM,
    },
    ObjectDesc {
        index: 0x1403,
        name: "4th RPDO communication parameter",
        code: ObjectCode::Record,
        entries: &RPDO4_COMM,
    },
    ObjectDesc {
        index: 0x1600,
        name: "1st RPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &RPDO1_MAP,
    },
    ObjectDesc {
        index: 0x1601,
        name: "2nd RPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &RPDO2_MAP,
    },
    ObjectDesc {
        index: 0x1602,
        name: "3rd RPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &RPDO3_MAP,
    },
    ObjectDesc {
        index: 0x1603,
        name: "4th RPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &RPDO4_MAP,
    },
    ObjectDesc {
        index: 0x1800,
        name: "1st TPDO communication parameter",
        code: ObjectCode::Record,
        entries: &TPDO1_COMM,
    },
    ObjectDesc {
        index: 0x1801,
        name: "2nd TPDO communication parameter",
        code: ObjectCode::Record,
        entries: &TPDO2_COMM,
    },
    ObjectDesc {
        index: 0x1802,
        name: "3rd TPDO communication parameter",
        code: ObjectCode::Record,
        entries: &TPDO3_COMM,
    },
    ObjectDesc {
        index: 0x1803,
        name: "4th TPDO communication parameter",
        code: ObjectCode::Record,
        entries: &TPDO4_COMM,
    },
    ObjectDesc {
        index: 0x1A00,
        name: "1st TPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &TPDO1_MAP,
    },
    ObjectDesc {
        index: 0x1A01,
        name: "2nd TPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &TPDO2_MAP,
    },
    ObjectDesc {
        index: 0x1A02,
        name: "3rd TPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &TPDO3_MAP,
    },
    ObjectDesc {
        index: 0x1A03,
        name: "4th TPDO mapping parameter",
        code: ObjectCode::Record,
        entries: &TPDO4_MAP,
    },
    // ----- manufacturer-specific objects (§8.2) ---------------------------------------------
    var_r!(
        0x402C,
        "Direct data operation operation data number",
        I16,
        RW_R,
        i(0),
        i(0),
        i(255)
    ),
    var_r!(
        0x402D,
        "Direct data operation operation type",
        U8,
        RW_R,
        u(0),
        u(0),
        u(255)
    ),
    var_r!(
        0x402E,
        "Direct data operation position",
        I32,
        RW_R,
        i(0),
        i(-2_147_483_648),
        i(2_147_483_647)
    ),
    var_r!(
        0x402F,
        "Direct data operation operating velocity",
        I32,
        RW_R,
        i(0),
        i(-4_000_000),
        i(4_000_000)
    ),
    var_r!(
        0x4030,
        "Direct data operation acceleration rate",
        I32,
        RW_R,
        i(1_000),
        i(1),
        i(1_000_000_000)
    ),
    var_r!(
        0x4031,
        "Direct data operation deceleration rate",
        I32,
        RW_R,
        i(1_000),
        i(1),
        i(1_000_000_000)
    ),
    var_r!(
        0x4032,
        "Direct data operation torque limiting value",
        I16,
        RW_R,
        i(10_000),
        i(0),
        i(10_000)
    ),
    var_r!(
        0x4033,
        "Direct data operation trigger",
        I32,
        RW_R,
        i(0),
        i(-7),
        i(2_147_418_131)
    ),
    var_r!(
        0x4034,
        "Direct data operation forwarding destination",
        U8,
        RW_R,
        u(0),
        u(0),
        u(1)
    ),
    var_r!(
        0x403A,
        "Driver input command (2nd)",
        U32,
        RW_R,
        u(0),
        u(0),
        u(0xFFFF_FFFF)
    ),
    // Bits turned ON here turn OFF again after 250 µs (§8.2 403Ch).
    var_r!(
        0x403C,
        "Driver input command (automatic OFF)",
        U32,
        RW_R,
        u(0),
        u(0),
        u(0xFFFF_FFFF)
    ),
    var_r!(
        0x403D,
        "NET selection data number",
        U32,
        RW_R,
        u(0),
        u(0),
        u(255)
    ),
    var_r!(
        0x403E,
        "Driver input command",
        U32,
        RW_R,
        u(0),
        u(0),
        u(0xFFFF_FFFF)
    ),
    var!(0x403F, "Driver output status", U32, RO_T, NONE),
    var!(
        0x404B,
        "Target position (User-defined position unit)",
        I32,
        RO_T,
        NONE
    ),
    var!(
        0x404C,
        "Demand position (User-defined position unit)",
        I32,
        RO_T,
        NONE
    ),
    var!(
        0x404D,
        "Actual position (User-defined position unit)",
        I32,
        RO_T,
        NONE
    ),
    var!(
        0x404E,
        "Target velocity (User-defined velocity unit)",
        I32,
        RO_T,
        NONE
    ),
    var!(
        0x404F,
        "Demand velocity (User-defined velocity unit)",
        I32,
        RO_T,
        NONE
    ),
    var!(
        0x4050,
        "Actual velocity (User-defined velocity unit)",
        I32,
        RO_T,
        NONE
    ),
    var!(0x4056, "Present communication error", U8, RO_T, NONE),
    var!(0x406B, "Torque monitor", I16, RO_T, NONE),
    var!(0x406C, "Load factor monitor", I32, RO_T, NONE),
    var!(0x406D, "Cumulative load monitor", U32, RO_T, NONE),
    var!(0x4070, "Next data number", I16, RO_T, NONE),
    var!(0x4071, "Loop origin data number", I16, RO_T, NONE),
    var!(0x4072, "Loop count", U32, RO_T, NONE),
    var!(0x4073, "Position deviation", I32, RO_T, NONE),
    var!(0x4075, "Speed deviation", I32, RO_T, NONE),
    var!(0x407A, "Tripmeter 1", I32, RO_T, NONE),
    var!(0x407B, "Information status 1", U32, RO_T, NONE),
    var!(0x407C, "Driver temperature", I16, RO_T, NONE),
    var!(0x407D, "Motor temperature", I16, RO_T, NONE),
    var!(0x407E, "Odometer", U32, RO_T, NONE),
    var!(0x407F, "Tripmeter 0", U32, RO_T, NONE),
    var!(0x409B, "Main power supply current", I32, RO_T, NONE),
    var!(0x409C, "Power consumption", U32, RO_T, NONE),
    var!(0x409D, "Energy consumption", U32, RO_T, NONE),
    var!(0x409E, "User energy consumption", U32, RO_T, NONE),
    var!(0x409F, "Total energy consumption", U32, RO_T, NONE),
    var!(0x40A1, "Total uptime", U32, RO_T, NONE),
    var!(0x40A2, "Number of boots", U32, RO_T, NONE),
    var!(0x40A3, "Inverter voltage", I16, RO_T, NONE),
    var!(0x40A4, "Main power supply voltage", I16, RO_T, NONE),
    var!(0x40A9, "Continuous uptime", U32, RO_T, NONE),
    var!(
        0x40AA,
        "RS-485 communication reception byte counter",
        U32,
        RO_T,
        NONE
    ),
    var!(
        0x40AB,
        "RS-485 communication transmission byte counter",
        U32,
        RO_T,
        NONE
    ),
    // One-shot maintenance commands: UINT8 rww, 0–2, default 0 (§8.2 40C0h–40D8h).
    var_r!(0x40C0, "Alarm reset", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40C2, "Clear alarm history", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40C5, "P-PRESET execution", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40C6, "Configuration", U8, RW_R, u(0), u(0), u(2)),
    var_r!(
        0x40CD,
        "Clear latch information",
        U8,
        RW_R,
        u(0),
        u(0),
        u(2)
    ),
    var_r!(0x40CE, "Clear sequence history", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40D0, "Clear ETO", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40D1, "ZSG-PRESET", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40D2, "Clear ZSG-PRESET", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40D3, "Clear information", U8, RW_R, u(0), u(0), u(2)),
    var_r!(
        0x40D6,
        "Clear user energy consumption",
        U8,
        RW_R,
        u(0),
        u(0),
        u(2)
    ),
    var_r!(0x40D7, "Clear tripmeter 0", U8, RW_R, u(0), u(0), u(2)),
    var_r!(0x40D8, "Clear tripmeter 1", U8, RW_R, u(0), u(0), u(2)),
    var_r!(
        0x4148,
        "Permission of absolute positioning without setting absolute coordinates",
        U8,
        RW_R,
        u(0),
        u(0),
        u(1)
    ),
    // UINT16 (§8.2, App.; §7.5.2 says UINT32, DISCREPANCY 10).
    var_r!(
        0x415F,
        "JOG/HOME Torque limit value",
        U16,
        RW_R,
        u(10_000),
        u(0),
        u(10_000)
    ),
    var_r!(0x4160, "(HOME) Homing mode", U8, RW_R, u(1), u(0), u(3)),
    var_r!(
        0x4163,
        "(HOME) Starting velocity",
        U32,
        RW_R,
        u(30),
        u(1),
        u(4_000_000)
    ),
    var_r!(
        0x4169,
        "(HOME) Backward steps in 2 sensor homeseeking",
        U32,
        RW_R,
        u(18_000),
        u(0),
        u(8_388_607)
    ),
    var_r!(
        0x4186,
        "Stopping timeout at alarm generation",
        U16,
        RW_R,
        u(3_000),
        u(0),
        u(10_000)
    ),
    var_r!(0x41CA, "WRAP setting", U8, RW_R, u(1), u(1), u(2)),
    var_r!(
        0x4735,
        "Custom stopping rate",
        U32,
        RW_R,
        u(1_000),
        u(1),
        u(1_000_000_000)
    ),
    var_r!(
        0x4736,
        "Custom stopping time",
        U32,
        RW_R,
        u(1_000),
        u(1),
        u(1_000_000_000)
    ),
    // ----- device profile objects (§8.3) ----------------------------------------------------
    // Latest alarm + FF00h.
    var!(0x603F, "Error code", U16, RO_T, NONE),
    var_r!(
        0x6040,
        "Controlword",
        U16,
        RW_R,
        u(0x0004),
        u(0x0000),
        u(0xFFFF)
    ),
    var!(0x6041, "Statusword", U16, RO_T, NONE),
    // Values −3…2, 5, 6 (see QUICK_STOP_OPTIONS; 3 and 4 are inside the range but not listed).
    var_r!(0x605A, "Quick stop option code", I16, RW, i(2), i(-3), i(6)),
    var_r!(0x605B, "Shutdown option code", I16, RW, i(0), i(0), i(1)),
    var_r!(
        0x605C,
        "Disable operation option code",
        I16,
        RW,
        i(1),
        i(0),
        i(1)
    ),
    // 0–1 (§8.3; App. says −3 to 2, DISCREPANCY 6); 0 is "reserved".
    var_r!(0x605D, "Halt option code", I16, RW, i(1), i(0), i(1)),
    var_r!(
        0x605E,
        "Fault reaction option code",
        I16,
        RW,
        i(2),
        i(0),
        i(2)
    ),
    // Default 3 = pv (§8.3 6060h); values 0, 1, 3, 4, 6.
    var_r!(0x6060, "Modes of operation", I8, RW_R, i(3), i(0), i(6)),
    var!(0x6061, "Modes of operation display", I8, RO_T, NONE),
    var!(0x6062, "Position demand value", I32, RO_T, NONE),
    var!(0x6064, "Position actual value", I32, RO_T, NONE),
    // 108,000 (§8.3; App. says 100,800, DISCREPANCY 7).
    var_r!(
        0x6065,
        "Following error window",
        U32,
        RW_R,
        u(108_000),
        u(0),
        u(10_000_000)
    ),
    var_r!(0x6067, "Position window", U32, RW_R, u(18), u(0), u(65_535)),
    var!(0x606B, "Velocity demand value", I32, RO_T, NONE),
    var!(0x606C, "Velocity actual value", I32, RO_T, NONE),
    var_r!(0x606D, "Velocity window", U16, RW_R, u(15), u(1), u(65_535)),
    var_r!(
        0x606F,
        "Velocity threshold",
        U16,
        RW_R,
        u(15),
        u(1),
        u(65_535)
    ),
    // Default 0, ±1,000 (§8.3; App. garbled, DISCREPANCY 8).
    var_r!(
        0x6071,
        "Target torque",
        I16,
        RW_R,
        i(0),
        i(-1_000),
        i(1_000)
    ),
    var_r!(0x6072, "Max torque", U16, RW_R, u(10_000), u(0), u(10_000)),
    var!(0x6074, "Torque demand", I16, RO_T, NONE),
    var!(0x6077, "Torque actual value", I16, RO_T, NONE),
    var_r!(
        0x607A,
        "Target position",
        I32,
        RW_R,
        i(0),
        i(-2_147_483_648),
        i(2_147_483_647)
    ),
    // Active only with 41CAh = 2 (§8.3 607Bh). Max upper limit 2,147,483,647 (App.; §8.3
    // prints 2,147,483,648, DISCREPANCY 9).
    ObjectDesc {
        index: 0x607B,
        name: "Position range limit",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Min position range limit", I32, RW_R, i(0)).range(i(-2_147_483_648), i(0)),
            e(2, "Max position range limit", I32, RW_R, i(0)).range(i(0), i(2_147_483_647)),
        ],
    },
    var_r!(
        0x607C,
        "Home offset",
        I32,
        RW_R,
        i(0),
        i(-2_147_483_648),
        i(2_147_483_647)
    ),
    // Active only after homing; disabled if min ≥ max or both 0 (§8.3 607Dh).
    ObjectDesc {
        index: 0x607D,
        name: "Software position limit",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Min position limit", I32, RW_R, i(0)).range(i(-2_147_483_648), i(2_147_483_647)),
            e(2, "Max position limit", I32, RW_R, i(0)).range(i(-2_147_483_648), i(2_147_483_647)),
        ],
    },
    var_r!(
        0x6081,
        "Profile velocity",
        U32,
        RW_R,
        u(1),
        u(1),
        u(4_000_000)
    ),
    var_r!(0x6082, "End velocity", U32, RW_R, u(0), u(0), u(4_000_000)),
    var_r!(
        0x6083,
        "Profile acceleration",
        U32,
        RW_R,
        u(1_000),
        u(1),
        u(1_000_000_000)
    ),
    var_r!(
        0x6084,
        "Profile deceleration",
        U32,
        RW_R,
        u(1_000),
        u(1),
        u(1_000_000_000)
    ),
    var_r!(
        0x6085,
        "Quick stop deceleration",
        U32,
        RW_R,
        u(1_000),
        u(1),
        u(1_000_000_000)
    ),
    var_r!(0x6087, "Torque slope", U32, RW_R, u(0), u(0), u(1_000_000)),
    ObjectDesc {
        index: 0x608F,
        name: "Position encoder resolution",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Encoder increments", U32, RW_R, u(36_000)).range(u(1), u(65_535)),
            e(2, "Motor revolutions", U32, RW_R, u(1)).range(u(1), u(65_535)),
        ],
    },
    ObjectDesc {
        index: 0x6091,
        name: "Gear ratio",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Motor revolutions", U32, RW, u(1)).range(u(1), u(1_000)),
            e(2, "Shaft revolutions", U32, RW, u(1)).range(u(1), u(1_000)),
        ],
    },
    var_r!(0x6098, "Homing method", I8, RW_R, i(37), i(-1), i(37)),
    // Sub-indices 01h/02h (§7.5.2, App.; §8.3 prints 00h/01h, DISCREPANCY 11).
    ObjectDesc {
        index: 0x6099,
        name: "Homing speeds",
        code: ObjectCode::Array,
        entries: &[
            count(2, RO),
            e(1, "Speed during search for switch", U32, RW_R, u(60)).range(u(1), u(4_000_000)),
            e(2, "Speed during search for zero", U32, RW_R, u(30)).range(u(1), u(4_000_000)),
        ],
    },
    // rww (§7.5.2, App.; §8.3 says rw, DISCREPANCY 12).
    var_r!(
        0x609A,
        "Homing acceleration",
        U32,
        RW_R,
        u(1_000),
        u(1),
        u(1_000_000_000)
    ),
    // rw, PDO-mappable; writes are not reflected (§8.3). Values [REC]: step; rev/min.
    var!(
        0x60A8,
        "SI unit position",
        U32,
        RW_RT,
        u(SI_UNIT_POSITION as u64)
    ),
    var!(
        0x60A9,
        "SI unit velocity",
        U32,
        RW_RT,
        u(SI_UNIT_VELOCITY as u64)
    ),
    // 3131h (§8.3; App. says 0000h, DISCREPANCY 13).
    var_r!(
        0x60B8,
        "Touch probe function",
        U16,
        RW_R,
        u(0x3131),
        u(0x0000),
        u(0xFFFF)
    ),
    var!(0x60B9, "Touch probe status", U16, RO_T, NONE),
    var!(0x60BA, "Touch probe 1 positive edge", I32, RO_T, NONE),
    var!(0x60BB, "Touch probe 1 negative edge", I32, RO_T, NONE),
    var!(0x60BC, "Touch probe 2 positive edge", I32, RO_T, NONE),
    var!(0x60BD, "Touch probe 2 negative edge", I32, RO_T, NONE),
    var!(
        0x60D5,
        "Touch probe 1 positive edge counter",
        U16,
        RO_T,
        NONE
    ),
    var!(
        0x60D6,
        "Touch probe 1 negative edge counter",
        U16,
        RO_T,
        NONE
    ),
    var!(
        0x60D7,
        "Touch probe 2 positive edge counter",
        U16,
        RO_T,
        NONE
    ),
    var!(
        0x60D8,
        "Touch probe 2 negative edge counter",
        U16,
        RO_T,
        NONE
    ),
    ObjectDesc {
        index: 0x60E3,
        name: "Supported homing methods",
        code: ObjectCode::Array,
        entries: &[
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
        ],
    },
    var_r!(
        0x60F2,
        "Positioning option code",
        U16,
        RW_R,
        u(0),
        u(0x0000),
        u(0xFFFF)
    ),
    var!(0x60F4, "Following error actual value", I32, RO_T, NONE),
    var!(0x60FD, "Digital inputs", U32, RO_T, NONE),
    ObjectDesc {
        index: 0x60FE,
        name: "Digital outputs",
        code: ObjectCode::Array,
        entries: &[
            count(1, RO),
            e(1, "Digital output - physical outputs", U32, RW_R, u(0)).range(u(0), u(0xFFFF_FFFF)),
        ],
    },
    var_r!(
        0x60FF,
        "Target velocity (pv)",
        I32,
        RW_R,
        i(0),
        i(-4_000_000),
        i(4_000_000)
    ),
    var!(
        0x6502,
        "Supported drive modes",
        U32,
        RO_T,
        u(SUPPORTED_MODES_V4 as u64)
    ),
    var!(0x67FE, "Version number", U32, RO, u(VERSION_NUMBER as u64)),
    var!(
        0x67FF,
        "Single device type",
        U32,
        RO,
        u(SINGLE_DEVICE_TYPE as u64)
    ),
];

/// 60A8h at power-on. **\[REC\]** (MANUAL GAP: §8.3 gives no value): prefix 10^0, unit B5h
/// "step / encoder increments", matching the default position unit "step" (§1.2).
pub const SI_UNIT_POSITION: u32 = 0x00B5_0000;

/// 60A9h at power-on. **\[REC\]** (MANUAL GAP): prefix 10^0, B4h "rev" per 47h "min", matching
/// the default velocity unit r/min (§1.2).
pub const SI_UNIT_VELOCITY: u32 = 0x00B4_4700;

// =============================================================================================
// Units of the motor model (§1.2, §8.3)
// =============================================================================================

/// Steps per motor revolution with the default scaling: 608Fh:01 / 608Fh:02 = 36,000 / 1, gear
/// 6091h = 1 / 1 (§8.3).
pub const STEPS_PER_REV: f64 = 36_000.0;

/// Units: position "step" (36,000 per revolution), velocity r/min, acceleration (r/min)/s,
/// torque 0.1 % of rated torque (= 1 ‰), torque slope 0.1 %/s (§1.2, §7.x.2, §8.3 6071h,
/// 6087h).
pub const UNITS: Units = Units {
    position_name: "step",
    position_per_rev: STEPS_PER_REV,
    velocity: VelocityUnit::RevPerMinute { scale: 1.0 },
    torque_per_mille: 1.0,
    profile: Some(ProfileUnits {
        // 6081h, 6082h: Vel. unit (§8.3).
        profile_velocity: VelocityUnit::RevPerMinute { scale: 1.0 },
        // 6099h: Vel. unit (§7.5.2, App.).
        homing_velocity: VelocityUnit::RevPerMinute { scale: 1.0 },
        // 6083h, 6084h, 6085h, 609Ah: Acc. unit = (r/min)/s (§1.2).
        acceleration: AccelUnit::RpmPerSecond,
        // 6087h: 0.1 %/s = 1 ‰/s.
        torque_slope: TorqueSlopeUnit::PerMillePerSecond,
    }),
};

// =============================================================================================
// Homing (§7.5.5, §8.3 6098h, 60E3h)
// =============================================================================================

/// Homing: the eleven methods of 60E3h, default 37 (current position), the index pulse is the
/// ZSG-N signal (§7.5.5 note).
pub const HOMING: HomingSupport = HomingSupport {
    methods: &[37, 35, 1, 2, 8, 12, 17, 18, 24, 28, -1],
    default_method: 37,
    index_pulse: true,
};

// =============================================================================================
// Communication services (§4.2–§4.5, §8.1)
// =============================================================================================

/// NMT error control, SYNC, error history, store.
pub const COMM: CommSupport = CommSupport {
    // §4.2: node guarding and heartbeat (not both at once).
    guarding: true,
    // §8.1 1016h: one consumer entry.
    heartbeat_consumers: 1,
    // §4.4, §8.1 1005h bit 30.
    sync_producer: true,
    has_cycle_period: true,
    // §8.1 1006h: only multiples of 250 µs.
    cycle_period_granularity_us: 250,
    // §8.1 1003h: up to ten entries.
    error_history: 10,
    // §8.1 1010h/1011h: 01h all, 02h communication.
    store_subs: 2,
    // MANUAL GAP: no SDO or RPDO rate limit is stated.
    sdo_min_interval_us: 0,
    rpdo_min_interval_us: 0,
};

/// NMT Stop while Operation enabled. MANUAL GAP: §5.1 ties excitation to NMT Operational (the
/// quirk `operational_required`), but names no alarm or state-machine reaction.
pub const NMT_STOP_WHILE_ENABLED: EnabledNmtReaction = EnabledNmtReaction::Unspecified;

/// NMT Reset node / Reset communication while Operation enabled. MANUAL GAP, as above.
pub const NMT_RESET_WHILE_ENABLED: EnabledNmtReaction = EnabledNmtReaction::Unspecified;

/// The quirks (the emulator's table for vendor 0000 02BEh): the motor is excited only in NMT
/// Operational (§5.1); an RPDO shorter than its mapping raises EMCY 8210h (§4.5); the touch
/// probe may trigger on the ZSG-N output (§7.6.1, 60B8h bits 2/10).
pub const QUIRKS: EmulationQuirks = EmulationQuirks {
    operational_required: true,
    pdo_length_alarm: Some(0x8210),
    touch_probe_index_pulse: true,
    ..EmulationQuirks::NONE
};

// =============================================================================================
// The spec
// =============================================================================================

/// The emulated BLVD-KRD (driver version 4.00).
pub const SPEC: NodeSpec = NodeSpec {
    name: "BLV-R",
    vendor: "Oriental Motor",
    source: SOURCE,
    dictionary: DICTIONARY,
    caps: CAPS,
    units: UNITS,
    pdo: PDO,
    homing: HOMING,
    emcy: EMCY,
    alarms: ALARMS,
    comm: COMM,
    nmt_stop_while_enabled: NMT_STOP_WHILE_ENABLED,
    nmt_reset_while_enabled: NMT_RESET_WHILE_ENABLED,
    // MANUAL GAP: the manual names no target the driver clears on enabling.
    targets_cleared_on_enable: &[],
    quirks: QUIRKS,
};

// =============================================================================================
// MANUAL GAP / [REC] / DISCREPANCY
// =============================================================================================
//
// MANUAL GAP — not stated by the manual; the emulator's choice [REC]:
// - Factory node-ID (§2.3 gives only the range 1–127 and the ways to set it).
// - 1009h / 100Ah contents: only the examples "Rev.1.00" / "V.1.00" (§8.1); HW_VERSION and
//   SW_VERSION are those examples.
// - 1008h / 1018h:02: the manual covers two models; the emulated one is the BLVD-KRD
//   (0000 13F7h).
// - 60A8h / 60A9h power-on values (§8.3 gives "–"): 00B5 0000h (step) / 00B4 4700h (rev/min).
//   Writes are "not reflected" by the drive (§8.3); the dictionary keeps them writable (rw).
// - Power-on values of every "–" object (monitors, 1001h, 603Fh, 6041h, 6061h, …): zero.
// - Whether the CAN-side EMCYs (8110h, 8120h, 8130h, 8140h, 8210h) put the driver in Fault:
//   not stated; they are reported without Fault (`fault: false`). Whether guarding/heartbeat
//   loss stops the motor: not stated (the quirk table has no guarding alarm).
// - Which alarms can be reset and which stop the motor with/without deceleration: the §4.5
//   table's annotation columns ("Possible", "Not possible", "Non-excitation", "Non-excitation
//   after deceleration") lost their row assignment in the source; not modelled. All FFxxh
//   alarms are faults (§5.1 "Fault: a non-excitation alarm (or non-excitation after slow down
//   alarm) is present").
// - Homing failure: §7.5.4 defines statusword bit 13; the text names alarm 62h because §4.5
//   lists "Return-to-home operation error" (also 63h No HOMES, 6Ah additional operation error,
//   4Ah return-to-home incomplete).
// - Reaction to NMT Stop / Reset while enabled: Unspecified (the node disables the power stage;
//   the quirk `operational_required` follows §5.1).
// - SDO / RPDO rate limits: none stated (0).
// - Targets cleared on enable: none stated.
// - Mode switching at speed: no rule stated (position_mode_switch_needs_zero_speed = false).
// - SDO refusal for RPDO-mapped objects: not stated (None).
// - PdoLimits::assignment_writable = true: CANopen has no assignment object; PDOs are
//   (in)validated with COB-ID bit 31 (§4.7.1).
// - Object codes (VAR/ARRAY/RECORD) are not given by the manual; CiA 301/402's are used
//   (1003h, 1010h, 1011h, 1016h, 607Bh, 607Dh, 608Fh, 6091h, 6099h, 60E3h, 60FEh ARRAY; 1018h,
//   1200h and the PDO parameters RECORD).
// - "rww" objects are taken as RPDO-mappable only (RW_R), "ro" + PDO Yes as TPDO-mappable only
//   (RO_T); "rw" + PDO Yes (60A8h, 60A9h) as mappable both ways (RW_RT).
//
// DISCREPANCY — the manual contradicts itself; the reading used:
//  1. §6 command table lists "Enable Operation → 4, 16" and "Switch ON + Enable Operation →
//     3 + 4 (automatic)"; §6.2 says transition 16 is "Not supported". Used: no transition 16
//     (§6.2, the dedicated table). The 3 + 4 row is the CiA 402 table's own row, not a
//     vendor state skip, so state_skipping = false.
//  2. 6502h: §8.3 gives 0000 0025h and 0000 002Dh (tq, driver version 4.00 or later), App.
//     only 0000 0025h. Used: 0000 002Dh (version 4.00 is emulated, §7.1.1, §9.2).
//  3. 1003h:00 access: rw (§8.1) vs ro (App.). Used: rw (§8.1, the object's own section; CiA
//     301 clears the history by writing 0). Range 0–10 from App.
//  4. 1A00h–1A03h:00 access: rw (§8.1) vs ro (App., also "Save No"). Used: rw (§8.1; the
//     remapping procedure §4.7.1 writes sub 00h; 1600h–1603h:00 are rw in both).
//  5. 1010h / 1011h sub 01h–02h: default "0000 0000h" in the tables, but a read returns bit 0
//     = 1 ("Always 1: the driver saves / restores parameters on command", §8.1). Used: 1.
//  6. 605Dh range: 0–1 (§8.3, value 0 "reserved", 1 slow-down ramp) vs −3 to 2 (App.). Used:
//     0–1 (§8.3, whose value table lists only 0 and 1).
//  7. 6065h default: 108,000 (§8.3) vs 100,800 (App.). Used: 108,000 (§8.3; = 3 revolutions
//     of 36,000 steps, the App. value looks like transposed digits).
//  8. 6071h: default 0, range −1,000 to 1,000 (§8.3) vs "default −1,000, lower 0, upper
//     1,000" (App., columns shifted). Used: §8.3.
//  9. 607Bh:02 upper limit: 2,147,483,648 (§8.3, outside INT32) vs 2,147,483,647 (App.).
//     Used: 2,147,483,647.
// 10. 415Fh data type: UINT32 (§7.5.2) vs UINT16 (§8.2, App.). Used: UINT16.
// 11. 6099h sub-indices: §8.3 prints "00h" twice (count and switch-search speed) and "01h"
//     for the zero-search speed, and no unit; §7.5.2 and App. give 01h / 02h in Vel. unit.
//     Used: 01h switch search (60), 02h zero search (30), Vel. unit.
// 12. 609Ah access: rw (§8.3) vs rww (§7.5.2, App.), PDO Yes everywhere. Used: rww (RW_R),
//     two places against one.
// 13. 60B8h default: 3131h (§8.3) vs 0000h (App.). Used: 3131h (the object's own section,
//     as for 6065h and 6071h).
// 14. 605Ah "Save": No (§8.3) vs Yes (App.). Not modelled (the dictionary has no save flag).
//     605Ah range −3 to 6 includes 3 and 4, which the value table does not list; the emulator
//     accepts only the listed codes (QUICK_STOP_OPTIONS).
// 15. 607Ah in pv: "always interpreted as an absolute value" (§8.3) vs §7.2.5 "treats the
//     absolute value of the target position as a relative movement distance" (controlword bit
//     12 = 1). Used: §7.2.5 (the mode's own section); this is motion behaviour, not data here.
// 16. Restricted COB-IDs (§3.3): "2020 (780h) to 2047 (7FFh)" — 780h is 1920. Used: 780h.
// 17. Statusword bit 8: "Drive profile operation ready (MS)" / DPRDY (§6.1, §7.x.4) vs "MS,
//     RDY" in the §8.3 bit map. Same bit, same meaning; no choice needed.
// 18. 4073h "Position deviation" text says "user-defined velocity units" while its unit column
//     says Pos. unit; 4050h "Actual velocity" is described as "present demand velocity".
//     Used: the table rows (names, Pos. unit / Vel. unit).
// 19. 6060h range 0–6 includes 2 and 5, which the value table does not list; the emulator's
//     modes come from 6502h (pp, pv, tq, hm).
