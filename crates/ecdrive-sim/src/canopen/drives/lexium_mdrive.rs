//! The emulated Schneider Electric Lexium MDrive (CANopen): the emulator's own [`NodeSpec`],
//! written from the drive's manual independently of the master's profile.
//!
//! Source: Schneider Electric Motion USA, *CANopen Fieldbus manual for Lexium MDrive*, V1.00,
//! 09.2014 (LMDOA42x, LMDOA57x, LMDOA85x). "§x.y" cites a section of that manual. The model
//! emulated is the **open-loop** integrated stepper (no encoder, no hMTechnology): 6502h
//! advertises pp, pv and hm only (§6.4.3), index-pulse homing fails, profile torque (closed
//! loop only, §6.8) is not offered although its objects are in the dictionary (§8.4).
//!
//! What the node does, with the manual sections:
//! - identity 1000h = `0044 0192h` (stepper, DSP402; §8.5.1), 1018h vendor `0000 021Bh`,
//!   product 0, revision `0000 0507h` (§8.5.16); node-ID 41h at 1 Mbit/s (§5.2);
//! - the CiA 402 state machine of §6.1/§6.2 (Table 6.3 lists transition 16 for "enable
//!   operation"); 605Ah 0–6, default 2 (§6.3.3); 605Dh 1/2 (§6.3.6); 605Eh 0–2 (§6.3.7);
//! - EMCY: bytes 0–1 error code, byte 2 error register, bytes 3–4 reserved, byte 5 PDO number,
//!   bytes 6–7 vendor-specific code (§3.5.1); the codes of Table 7.2 (§7.3.2);
//! - NMT Stop / Reset communication while the power stage is enabled: error class 2, quick
//!   stop then power stage off (§3.6.1 Table 3.10); life time expiry → Fault (§8.5.10);
//! - PDOs: four RPDOs and four TPDOs, dynamic mapping of up to 8 entries / 8 bytes (§3.3.4,
//!   §8.2), only RPDO1/TPDO1 valid at power-on (§3.3.3), all asynchronous (255), TPDO2/TPDO3
//!   with a 100 ms event timer (§8.5.20); the default mappings of §8.5.19/§8.5.21;
//! - the device is a SYNC consumer only (§8.5.4); guarding (100Ch/100Dh) and the producer
//!   heartbeat (1017h); no 1006h, no 1016h in the object tables (§8.2);
//! - units: microsteps, 51 200 per revolution (6092h = 51200/1, §6.11.2; 607Ah §6.5.5),
//!   velocities in steps/s (§6.5.7, §6.6.6), accelerations in steps/s² (§6.5.9), torque in ‰
//!   of rated torque (§6.8.3), torque slope ‰/s (§6.8.5);
//! - homing methods 1–14, 17–30, 33–35 and 0 = no homing (§6.7.5).
//!
//! Values the manual does not state, and the manual's self-contradictions, are listed at the
//! end of the file (`MANUAL GAP / [REC] / DISCREPANCY`).

use super::super::quirks::EmulationQuirks;
use super::super::spec::NodeSpec;
use crate::can::profile::od::{
    I8, I16, I32, RO, RO_T, RW, RW_R, STR, U8, U16, U32, count, e, error_history, i, pdo_comm,
    pdo_map, store_record, u,
};
use crate::can::profile::{
    Alarm, CanPdoProfile, CommSupport, EmcyFormat, EnabledNmtReaction, HomingSupport, PdoDefault,
    TransmissionTypes,
};
use crate::cia402::units::{AccelUnit, ProfileUnits, TorqueSlopeUnit, Units, VelocityUnit};
use crate::cia402::{DriveCaps, ErrorEntry, QuickStopOption, SupportedModes};
use crate::od::{ConstValue, EntryDesc, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, PdoEntry, PdoLimits, PdoRange};

// ===== identity =================================================================================

/// 1000h device type: bits 31–16 = 0044h (stepper motor), bits 15–0 = 0192h (DSP402) (§8.5.1).
pub const DEVICE_TYPE: u32 = 0x0044_0192;
/// 1018h:01 vendor ID, "Default value 0000 021Bh" (§8.5.16).
pub const VENDOR_ID: u32 = 0x0000_021B;
/// The vendor ID §5.6 gives for the LSS switch-mode-selective signature ("VendorID =
/// 0800005Ah"); it contradicts 1018h:01 (see DISCREPANCY at the end). Kept for reference only:
/// the node reports [`VENDOR_ID`].
pub const LSS_VENDOR_ID: u32 = 0x0800_005A;
/// 1018h:02 product code (§8.5.16; §5.6 "Product code = 00").
pub const PRODUCT_CODE: u32 = 0x0000_0000;
/// 1018h:03 revision number (§8.5.16; §5.6 "Revision number = 507h").
pub const REVISION: u32 = 0x0000_0507;
/// 1018h:04 serial number. **\[REC\]** The manual gives no default (device-specific, §8.5.16);
/// this is §5.6's worked example "341070398 = 1454523E".
pub const SERIAL_NUMBER: u32 = 0x1454_523E;
/// 1008h manufacturer device name (§8.5.6).
pub const DEVICE_NAME: &str = "CANopen Lexium MDrive Motion Control Node";
/// 1009h manufacturer hardware version, the manual's default value (§8.5.7). The manual gives
/// one value for every unit; a real device may report another.
pub const HW_VERSION: &str = "V1.00";
/// 100Ah manufacturer software version, the manual's default value (§8.5.8); as for
/// [`HW_VERSION`], the firmware of a real device may differ.
pub const SW_VERSION: &str = "V5.48";
/// 6402h motor type: 9 = stepper motor (§8.4).
pub const MOTOR_TYPE: u16 = 9;
/// Factory node-ID 41h (§5.2, §7.1).
pub const DEFAULT_NODE_ID: u8 = 0x41;
/// Factory bit rate, kbit/s: "1 Mbaud (1000 kbps)" (§5.2).
pub const DEFAULT_BITRATE_KBIT: u16 = 1000;
/// Bit rates of the LSS bit-timing table, indices 00h–08h (§5.5; 800 kbit/s not with the
/// MD-CC500-000 converter).
pub const BITRATES_KBIT: &[u16] = &[1000, 800, 500, 250, 125, 100, 50, 20, 10];
/// LSS COB-IDs: master → slave 7E5h, slave → master 7E4h (§3.1.3 Table 3.2, §5.4).
pub const LSS_COB_IDS: (u16, u16) = (0x7E5, 0x7E4);
/// 6502h supported drive modes: "Default value 00000025h" = pp (bit 0), pv (bit 2), hm (bit 5)
/// (§6.4.3; 6060h accepts 1, 3, 6, §6.4.1).
pub const SUPPORTED_MODES_RAW: u32 = 0x0000_0025;

// ===== CiA 402 capabilities =====================================================================

/// 605Ah values 0–6 (§6.3.3 Table 6.7): 0 disable drive function; 1–4 slow down on the
/// slow-down ramp / quick-stop ramp / current limit / voltage limit, then Switch on disabled;
/// 5–6 slow-down ramp / quick-stop ramp and stay in Quick stop active.
const QUICK_STOP_OPTIONS: [QuickStopOption; 7] = [
    QuickStopOption::DISABLE_DRIVE,
    QuickStopOption::SLOW_DOWN_RAMP,
    QuickStopOption::QUICK_STOP_RAMP,
    QuickStopOption::CURRENT_LIMIT,
    QuickStopOption::VOLTAGE_LIMIT,
    QuickStopOption::SLOW_DOWN_RAMP_STAY,
    QuickStopOption::QUICK_STOP_RAMP_STAY,
];

/// The error codes of Table 7.2 (§7.3.2), looked up before the CiA tables. The additional
/// information (EMCY bytes 6–7, 1003h high word) tells 4210h and FF01h apart; see [`ALARMS`].
pub const ERROR_TABLE: &[ErrorEntry] = &[
    ErrorEntry::exact(0x8110, "8110h", "CAN overrun"),
    ErrorEntry::exact(0x8120, "8120h", "CAN in error passive mode"),
    ErrorEntry::exact(0x8130, "8130h", "Lifeguard or heartbeat error"),
    ErrorEntry::exact(0x8140, "8140h", "Recovered from \"bus off\" state"),
    ErrorEntry::exact(0x8141, "8141h", "Bus off state occurred"),
    ErrorEntry::exact(0x8210, "8210h", "PDO not processed - length error"),
    ErrorEntry::exact(
        0x4210,
        "4210h",
        "Over temperature error (additional info 8h) or pending over temperature warning \
         (additional info 16h)",
    ),
    ErrorEntry::exact(
        0xFF01,
        "FF01h",
        "Motor idle during commanded move (1h), motor should be idle (2h-8h) or undershot \
         warning (9h)",
    ),
];

/// The state machine and modes (§6.1–§6.4).
///
/// - `state_skipping: false`: Table 6.3 has only the CiA 402 commands; "Switch on + enable
///   operation" is transitions 3 + 4 in sequence, and no jump from Switch on disabled is named.
/// - `transition_16: true`: Table 6.3 "Enable operation … 4, 16"; 605Ah 5 and 6 stay in Quick
///   stop active (§6.3.3).
/// - 605Ah 0–6, default 2 (§6.3.3).
/// - `position_mode_switch_needs_zero_speed: false`: "The product allows the user to switch
///   dynamically from operation mode to operation mode" (§6.4).
/// - `remote_gates_controlword: false`: §6.2.2 bit 9 restates CiA 402's "remote" wording and
///   names no condition under which the drive clears it (MANUAL GAP below).
/// - 6502h = 0025h (§6.4.3).
/// - homing failure: only statusword bit 13 "homing error" (§6.7.3); no alarm is named.
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: true,
    quick_stop_options: &QUICK_STOP_OPTIONS,
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: false,
    supported_modes: SupportedModes::from_raw(SUPPORTED_MODES_RAW),
    error_table: ERROR_TABLE,
    csp_start_edge: false,
    homing_failure: "",
    home_offset_set_by_drive: None,
    sdo_refused_while_rx_mapped: None,
    pp_target_range: None,
};

// ===== alarms ===================================================================================

/// 1001h: generic error (bit 0) + communication (bit 4) (§7.3.1). **\[REC\]** the manual does
/// not say which bits each error sets.
const REG_COMM: u8 = 0x11;
/// 1001h: generic error (bit 0) + temperature (bit 3) (§7.3.1, §8.5.2). **\[REC\]**.
const REG_TEMP: u8 = 0x09;
/// 1001h: generic error (bit 0) + manufacturer specific (bit 7) (§7.3.1, §8.5.2). **\[REC\]**.
const REG_MFR: u8 = 0x81;

/// **\[REC\]** Vendor number (lookup key) of the alarm the node raises for NMT Stop / Reset
/// while the power stage is enabled (§3.6.1: "an error of error class 2 is triggered"); the
/// manual names no error code for it (MANUAL GAP). Code 8100h = CiA 301 "communication".
pub const NMT_WHILE_ENABLED_ALARM: u16 = 0x8100;

/// The alarm table: Table 7.2 (§7.3.2), plus the error-class-2 event of §3.6.1.
///
/// `number` is what the node puts in EMCY bytes 6–7 (and the 1003h high word): the manual's
/// "additional info" for 4210h and FF01h. For the communication errors, whose additional info
/// is 0h, **\[REC\]** the number is the error code itself, so that each has a distinct key
/// (the quirks name 8210h and 8130h); see DISCREPANCY at the end.
///
/// Fault or warning: "If an internal device error occurs, the device switches to the operating
/// state 9 Fault" (§3.5.1); "warning" rows are warnings; life-time expiry → Fault (§8.5.10).
/// The CAN-controller events are warnings: 6007h (default 0 = no action) governs bus-off
/// (§6.3.1). The PDO length error is a warning **\[REC\]**.
pub static ALARMS: &[Alarm] = &[
    Alarm {
        number: 0x8110,
        code: 0x8110,
        register: REG_COMM,
        name: "8110h",
        text: "CAN overrun",
        fault: false,
    },
    Alarm {
        number: 0x8120,
        code: 0x8120,
        register: REG_COMM,
        name: "8120h",
        text: "CAN in error passive mode",
        fault: false,
    },
    Alarm {
        number: 0x8130,
        code: 0x8130,
        register: REG_COMM,
        name: "8130h",
        text: "Lifeguard or heartbeat error",
        fault: true,
    },
    Alarm {
        number: 0x8140,
        code: 0x8140,
        register: REG_COMM,
        name: "8140h",
        text: "Recovered from \"bus off\" state",
        fault: false,
    },
    Alarm {
        number: 0x8141,
        code: 0x8141,
        register: REG_COMM,
        name: "8141h",
        text: "Bus off state occurred",
        fault: false,
    },
    Alarm {
        number: 0x8210,
        code: 0x8210,
        register: REG_COMM,
        name: "8210h",
        text: "PDO not processed - length error",
        fault: false,
    },
    Alarm {
        number: NMT_WHILE_ENABLED_ALARM,
        code: 0x8100,
        register: REG_COMM,
        name: "error class 2",
        text: "NMT Stop or Reset communication while the power stage is enabled: error class 2 \
               (quick stop, then power stage disabled)",
        fault: true,
    },
    // 4210h/08h before FF01h/08h: both have additional info 8h; `NodeSpec::alarm(8)` finds
    // the over-temperature fault.
    Alarm {
        number: 0x0008,
        code: 0x4210,
        register: REG_TEMP,
        name: "4210h/08h",
        text: "Over temperature error (2018h/2019h:03 fault threshold, default 85 \u{b0}C)",
        fault: true,
    },
    Alarm {
        number: 0x0016,
        code: 0x4210,
        register: REG_TEMP,
        name: "4210h/16h",
        text: "Pending over temperature warning (2018h/2019h:02 threshold, default 80 \u{b0}C)",
        fault: false,
    },
    Alarm {
        number: 0x0001,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/01h",
        text: "Motor idle during commanded move",
        fault: true,
    },
    Alarm {
        number: 0x0002,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/02h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0003,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/03h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0004,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/04h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0005,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/05h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0006,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/06h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0007,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/07h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0008,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/08h",
        text: "Motor should be idle",
        fault: true,
    },
    Alarm {
        number: 0x0009,
        code: 0xFF01,
        register: REG_MFR,
        name: "FF01h/09h",
        text: "Undershot warning",
        fault: false,
    },
];

// ===== PDO rules ================================================================================

/// A mapping entry as stored in 16xxh/1Axxh: index(16) · sub(8) · length in bits(8) (§8.5.19).
const fn m(index: u16, sub: u8, bits: u8) -> u32 {
    ((index as u32) << 16) | ((sub as u32) << 8) | (bits as u32)
}

/// COB-ID bit 31: PDO does not exist / is not valid (§8.5.18 Table 8.7).
const INVALID: u32 = 0x8000_0000;

/// Mapping objects 1600h–1603h / 1A00h–1A03h, dynamic, sub-indices 01h–08h (§3.3.4 Table 3.7,
/// §8.2); every PDO may be valid at once; 8 bytes each (§3.3.4).
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "Lexium MDrive",
    rx: DirectionLimits {
        pdos: &[PdoRange::new(0x1600, 0x1603, 8)],
        max_assigned: 4,
        max_entries: 32,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: &[PdoRange::new(0x1A00, 0x1A03, 8)],
        max_assigned: 4,
        max_entries: 32,
        max_bytes: 32,
    },
    // CANopen has no 1C12h/1C13h: a PDO is assigned by its COB-ID valid bit.
    assignment_writable: false,
};

/// Power-on RPDOs (§3.3.3, §8.5.18, §8.5.19): RPDO1 controlword (valid); RPDO2 controlword +
/// 607Ah; RPDO3 controlword + 60FFh; RPDO4 controlword + 6071h **with the manual's 32-bit
/// length** (DISCREPANCY). RPDO2–4 are not valid until activated (§3.3.3). Type 255.
pub const DEFAULT_RPDOS: &[PdoDefault] = &[
    PdoDefault {
        number: 1,
        cob_id: 0x200,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[PdoEntry::new(0x6040, 0, 16)],
    },
    PdoDefault {
        number: 2,
        cob_id: INVALID | 0x300,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)],
    },
    PdoDefault {
        number: 3,
        cob_id: INVALID | 0x400,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x60FF, 0, 32)],
    },
    PdoDefault {
        number: 4,
        cob_id: INVALID | 0x500,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x6071, 0, 32)],
    },
];

/// Power-on TPDOs (§3.3.3, §8.5.20, §8.5.21): TPDO1 statusword (valid); TPDO2 statusword +
/// 6064h, event timer 100 ms; TPDO3 statusword + 606Ch, event timer 100 ms; TPDO4 statusword.
/// Type 255; TPDO2–4 not valid until activated (§3.3.3).
pub const DEFAULT_TPDOS: &[PdoDefault] = &[
    PdoDefault {
        number: 1,
        cob_id: 0x180,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[PdoEntry::new(0x6041, 0, 16)],
    },
    PdoDefault {
        number: 2,
        cob_id: INVALID | 0x280,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 100,
        mapping: &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6064, 0, 32)],
    },
    PdoDefault {
        number: 3,
        cob_id: INVALID | 0x380,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 100,
        mapping: &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x606C, 0, 32)],
    },
    PdoDefault {
        number: 4,
        cob_id: INVALID | 0x480,
        transmission_type: 255,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[PdoEntry::new(0x6041, 0, 16)],
    },
];

/// PDO rules. Transmission types (§8.5.18 Table 8.8): 0, 1–240, 254, 255 for both directions;
/// 252 and 253 "are only possible for T_PDOs". Communication records have subs 0–3 and 5
/// (sub 4 reserved, abort 0609 0011h) (§8.2, §8.5.18).
pub const PDO: CanPdoProfile = CanPdoProfile {
    limits: PDO_LIMITS,
    max_pdo_bytes: 8,
    rpdo_types: TransmissionTypes {
        sync_acyclic: true,
        sync_cyclic: true,
        rtr_sync: false,
        rtr_event: false,
        event_manufacturer: true,
        event_profile: true,
    },
    tpdo_types: TransmissionTypes::ALL,
    rpdo_comm_subs: 5,
    default_rpdos: DEFAULT_RPDOS,
    default_tpdos: DEFAULT_TPDOS,
};

// ===== object dictionary ========================================================================

macro_rules! var {
    ($index:literal, $name:literal, $dt:expr, $acc:expr, $def:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[e(0, $name, $dt, $acc, $def)],
        }
    };
    ($index:literal, $name:literal, $dt:expr, $acc:expr, $def:expr, $min:expr, $max:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[e(0, $name, $dt, $acc, $def).range($min, $max)],
        }
    };
}

// --- 1000h group (§8.2, §8.5); none is PDO-mappable ---

static ERROR_FIELD_1003: [EntryDesc; 5] = error_history::<5>();
static STORE_1010: [EntryDesc; 5] = store_record::<5>();
static RESTORE_1011: [EntryDesc; 5] = store_record::<5>();
static IDENTITY_1018: [EntryDesc; 5] = [
    count(4, RO),
    e(1, "Vendor ID", U32, RO, u(VENDOR_ID as u64)),
    e(2, "Product code", U32, RO, u(PRODUCT_CODE as u64)),
    e(3, "Revision number", U32, RO, u(REVISION as u64)),
    e(4, "Serial number", U32, RO, u(SERIAL_NUMBER as u64)),
];

static RPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x200, 255, 0, 0);
static RPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(INVALID | 0x300, 255, 0, 0);
static RPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(INVALID | 0x400, 255, 0, 0);
static RPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(INVALID | 0x500, 255, 0, 0);
static RPDO1_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6040, 0, 16)]);
static RPDO2_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6040, 0, 16), m(0x607A, 0, 32)]);
static RPDO3_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6040, 0, 16), m(0x60FF, 0, 32)]);
// §8.5.19: "1603h = 6071 0020h" although 6071h is INTEGER16 (DISCREPANCY).
static RPDO4_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6040, 0, 16), m(0x6071, 0, 32)]);
static TPDO1_COMM: [EntryDesc; 5] = pdo_comm::<5>(0x180, 255, 0, 0);
static TPDO2_COMM: [EntryDesc; 5] = pdo_comm::<5>(INVALID | 0x280, 255, 0, 100);
static TPDO3_COMM: [EntryDesc; 5] = pdo_comm::<5>(INVALID | 0x380, 255, 0, 100);
static TPDO4_COMM: [EntryDesc; 5] = pdo_comm::<5>(INVALID | 0x480, 255, 0, 0);
static TPDO1_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6041, 0, 16)]);
static TPDO2_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6041, 0, 16), m(0x6064, 0, 32)]);
static TPDO3_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6041, 0, 16), m(0x606C, 0, 32)]);
static TPDO4_MAP: [EntryDesc; 9] = pdo_map::<9>(&[m(0x6041, 0, 16)]);

// --- 2000h group, manufacturer objects (§8.3, §8.6) ---

static IO_CONFIG_2000: [EntryDesc; 6] = [
    count(5, RO),
    e(1, "Reserved (I/O direction)", U8, RW, u(0)),
    e(2, "Reserved (sourcing/sinking)", U8, RW, u(0)),
    e(3, "Reserved (sink/source or source only)", U8, RW, u(0)),
    e(4, "Configure as polarity in", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(5, "Configure as polarity out", U8, RW, u(0)).range(u(0), u(0xFF)),
];
static INPUT_SWITCHES_2002: [EntryDesc; 5] = [
    count(4, RO),
    e(1, "Configure input as home", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(2, "Configure input as positive limit", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(3, "Configure input as negative limit", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(4, "Configure inhibit switch", U8, RW, u(0)).range(u(0), u(0xFF)),
];
static INPUT_MASK_2004: [EntryDesc; 9] = [
    count(8, RO),
    e(1, "Configure mask for Input 1", U8, RW, u(0x01)).range(u(0), u(0xFF)),
    e(2, "Configure mask for Input 2", U8, RW, u(0x02)).range(u(0), u(0xFF)),
    e(3, "Configure mask for Input 3", U8, RW, u(0x04)).range(u(0), u(0xFF)),
    e(4, "Configure mask for Input 4", U8, RW, u(0x08)).range(u(0), u(0xFF)),
    e(5, "Reserved", U8, RW, u(0)),
    e(6, "Reserved", U8, RW, u(0)),
    e(7, "Reserved", U8, RW, u(0)),
    e(8, "Reserved", U8, RW, u(0)),
];
static INPUT_FILTER_2006: [EntryDesc; 9] = [
    count(8, RO),
    e(1, "Configure filter for Input 1", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(2, "Configure filter for Input 2", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(3, "Configure filter for Input 3", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(4, "Configure filter for Input 4", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(5, "Configure filter for Input 9", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(6, "Configure filter for Input 10", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(7, "Configure filter for Input 11", U8, RW, u(0)).range(u(0), u(0xFF)),
    e(8, "Configure filter for Input 12", U8, RW, u(0)).range(u(0), u(0xFF)),
];
static INHIBIT_2007: [EntryDesc; 2] = [
    count(1, RO),
    e(1, "Inhibit switch reaction", U8, RW, u(12)).range(u(0), u(12)),
];
static OUTPUTS_2008: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Brake output defined", U8, RW, u(0)),
    e(2, "Target reached output defined", U8, RW, u(0)),
];
static OUTPUT_FAULT_2009: [EntryDesc; 2] = [
    count(1, RO),
    e(1, "Read value of output fault", U8, RO_T, u(0)),
];
static ANALOG_2010: [EntryDesc; 4] = [
    count(3, RO),
    e(1, "Analog input reading", U16, RO_T, u(0)).range(u(0), u(4095)),
    e(2, "Analog input configuration", U8, RW, u(0)).range(u(0), u(0x08)),
    e(3, "Analog filter level", U8, RW, u(0)).range(u(0), u(0x31)),
];
static AUX_POWER_2014: [EntryDesc; 4] = [
    count(3, RO),
    e(1, "Aux-power input reading", U16, RO_T, u(0)).range(u(0), u(280)),
    e(2, "Aux-power input low-level warning", U16, RW, u(0)).range(u(0), u(280)),
    e(3, "Aux-power input high-level warning", U16, RW, u(280)).range(u(0), u(280)),
];
static VDC_2015: [EntryDesc; 4] = [
    count(3, RO),
    e(1, "+VDC input monitoring", U16, RO_T, u(0)).range(u(0), u(800)),
    e(2, "+VDC input low-level warning", U16, RW, u(100)).range(u(0), u(800)),
    e(3, "+VDC input high-level warning", U16, RW, u(580)).range(u(0), u(800)),
];
static PCB_TEMP_2018: [EntryDesc; 4] = [
    count(3, RO),
    e(1, "PCB temperature reading", I8, RO_T, i(0)),
    e(2, "PCB temperature warning threshold", I8, RW, i(80)).range(i(-50), i(120)),
    e(3, "PCB temperature fault", I8, RW, i(85)).range(i(-50), i(120)),
];
static BRIDGE_TEMP_2019: [EntryDesc; 4] = [
    count(3, RO),
    e(1, "Bridge temperature reading", I8, RO_T, i(0)),
    e(2, "Bridge temperature warning threshold", I8, RW, i(80)).range(i(-50), i(120)),
    e(3, "Bridge temperature fault", I8, RW, i(85)).range(i(-50), i(120)),
];
static SW_LIMITS_AS_HW_2020: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Limit reached flag", U8, RW, u(0)).range(u(0), u(0x0F)),
    e(2, "Limit reached mask", U8, RW, u(0x03)).range(u(0), u(0x0F)),
];
static SW_LIMIT_2022: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Actual negative limit", I32, RW, i(i32::MIN as i64)),
    e(2, "Actual positive limit", I32, RW, i(i32::MAX as i64)),
];
static CAPTURE_2033: [EntryDesc; 5] = [
    count(4, RO),
    e(1, "Capture input enable", U8, RW, u(0)).range(u(0), u(1)),
    // "0/1 … Write all ones to clear the flag" (§8.6.18): no range, so FFh is accepted.
    e(2, "Position captured flag", U8, RW, u(0)),
    e(3, "Capture input filter time", U8, RW, u(0)).range(u(0), u(9)),
    e(4, "Captured position", I32, RO_T, i(0)),
];
static BRIDGE_SETTLE_2034: [EntryDesc; 2] = [
    count(1, RO),
    e(1, "Bridge on settle time", U16, RW, u(0)).range(u(0), u(1000)),
];
static BRAKE_SETTLE_2035: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Brake on settle time", U16, RW, u(0)).range(u(0), u(2000)),
    e(2, "Brake off settle time", U16, RW, u(0)).range(u(0), u(1000)),
];
static TRIP_2038: [EntryDesc; 4] = [
    count(3, RO),
    e(1, "Trip output control", U16, RW, u(0)),
    e(2, "First trip point", I32, RW, i(0)),
    e(3, "Multiple trip point spacing", I32, RW, i(5120)),
];
static FOLLOWING_ERROR_2221: [EntryDesc; 2] = [
    count(1, RO),
    e(1, "Following error reaction code", U8, RW, u(0)).range(u(0), u(2)),
];
static FACTORY_5002: [EntryDesc; 2] = [
    count(1, RO),
    e(1, "Serial number", U32, RO, u(SERIAL_NUMBER as u64)),
];

// --- 6000h group, device profile (§6, §8.4) ---

static ENCODER_RES_608F: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Resolution numerator", U32, RW, u(2048)).range(u(1), u(65535)),
    e(2, "Resolution denominator", U32, RW, u(1)).range(u(1), u(65535)),
];
static FEED_6092: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Feed user units numerator", U32, RW, u(51200)),
    e(2, "Shaft revolutions denominator", U32, RW, u(1)),
];
static HOMING_SPEEDS_6099: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Homing speed fast", U32, RW, u(102_400)).range(u(0), u(0x7FFF_FFFF)),
    e(2, "Homing speed slow", U32, RW, u(6400)).range(u(0), u(0x7FFF_FFFF)),
];
static INTERPOLATION_60C2: [EntryDesc; 3] = [
    count(2, RO),
    e(1, "Interpolation period", U8, RW, u(1)),
    e(2, "Interpolation factor", I8, RW, i(-3)),
];
static DIGITAL_OUTPUTS_60FE: [EntryDesc; 2] =
    [count(1, RO), e(1, "Digital outputs", U32, RW_R, u(0))];

/// The object dictionary at power-on, sorted by index: every object of the tables in §8.2
/// (1000h group), §8.3 (2000h group), §8.4 (6000h group), plus 2009h (Table 3.9 only) and
/// 5002h:01 (serial number, §5.6). Access and PDO flags follow the §8.2–§8.4 tables where the
/// detail sections differ (see DISCREPANCY).
pub static DICTIONARY: &[ObjectDesc] = &[
    // ----- 1000h group -----
    var!(0x1000, "Device type", U32, RO, u(DEVICE_TYPE as u64)),
    var!(0x1001, "Error register", U8, RO, u(0)),
    ObjectDesc {
        index: 0x1003,
        name: "Pre-defined error field",
        code: ObjectCode::Array,
        entries: &ERROR_FIELD_1003,
    },
    var!(0x1005, "COB-ID SYNC", U32, RW, u(0x0000_0080)),
    var!(0x1007, "Sync window length", U32, RW, u(0)),
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
    var!(0x100C, "Guard time", U16, RW, u(0), u(0), u(65535)),
    var!(0x100D, "Life time factor", U8, RW, u(0), u(0), u(255)),
    ObjectDesc {
        index: 0x1010,
        name: "Store parameters",
        code: ObjectCode::Array,
        entries: &STORE_1010,
    },
    ObjectDesc {
        index: 0x1011,
        name: "Restore default parameters",
        code: ObjectCode::Array,
        entries: &RESTORE_1011,
    },
    var!(0x1012, "COB-ID time stamp message", U32, RW, u(0x0000_0100)),
    // 80h + node-ID (node-relative).
    var!(0x1014, "COB-ID emergency message", U32, RW, u(0x0000_0080)),
    var!(0x1015, "Inhibit time EMCY", U16, RW, u(0)),
    var!(0x1017, "Producer heartbeat time", U16, RW, u(0)),
    ObjectDesc {
        index: 0x1018,
        name: "Identity object",
        code: ObjectCode::Record,
        entries: &IDENTITY_1018,
    },
    ObjectDesc {
        index: 0x1400,
        name: "1st receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO1_COMM,
    },
    ObjectDesc {
        index: 0x1401,
        name: "2nd receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO2_COMM,
    },
    ObjectDesc {
        index: 0x1402,
        name: "3rd receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO3_COMM,
    },
    ObjectDesc {
        index: 0x1403,
        name: "4th receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO4_COMM,
    },
    ObjectDesc {
        index: 0x1600,
        name: "1st receive PDO mapping",
        code: ObjectCode::Record,
        entries: &RPDO1_MAP,
    },
    ObjectDesc {
        index: 0x1601,
        name: "2nd receive PDO mapping",
        code: ObjectCode::Record,
        entries: &RPDO2_MAP,
    },
    ObjectDesc {
        index: 0x1602,
        name: "3rd receive PDO mapping",
        code: ObjectCode::Record,
        entries: &RPDO3_MAP,
    },
    ObjectDesc {
        index: 0x1603,
        name: "4th receive PDO mapping",
        code: ObjectCode::Record,
        entries: &RPDO4_MAP,
    },
    ObjectDesc {
        index: 0x1800,
        name: "1st transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO1_COMM,
    },
    ObjectDesc {
        index: 0x1801,
        name: "2nd transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO2_COMM,
    },
    ObjectDesc {
        index: 0x1802,
        name: "3rd transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO3_COMM,
    },
    ObjectDesc {
        index: 0x1803,
        name: "4th transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO4_COMM,
    },
    ObjectDesc {
        index: 0x1A00,
        name: "1st transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &TPDO1_MAP,
    },
    ObjectDesc {
        index: 0x1A01,
        name: "2nd transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &TPDO2_MAP,
    },
    ObjectDesc {
        index: 0x1A02,
        name: "3rd transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &TPDO3_MAP,
    },
    ObjectDesc {
        index: 0x1A03,
        name: "4th transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &TPDO4_MAP,
    },
    // ----- 2000h group -----
    ObjectDesc {
        index: 0x2000,
        name: "I/O configuration",
        code: ObjectCode::Array,
        entries: &IO_CONFIG_2000,
    },
    ObjectDesc {
        index: 0x2002,
        name: "Configure input switches",
        code: ObjectCode::Array,
        entries: &INPUT_SWITCHES_2002,
    },
    ObjectDesc {
        index: 0x2004,
        name: "Configure input mask",
        code: ObjectCode::Array,
        entries: &INPUT_MASK_2004,
    },
    ObjectDesc {
        index: 0x2006,
        name: "Configure input filter",
        code: ObjectCode::Array,
        entries: &INPUT_FILTER_2006,
    },
    ObjectDesc {
        index: 0x2007,
        name: "Inhibit switch reaction",
        code: ObjectCode::Array,
        entries: &INHIBIT_2007,
    },
    ObjectDesc {
        index: 0x2008,
        name: "Output definition",
        code: ObjectCode::Array,
        entries: &OUTPUTS_2008,
    },
    ObjectDesc {
        index: 0x2009,
        name: "Output fault",
        code: ObjectCode::Array,
        entries: &OUTPUT_FAULT_2009,
    },
    ObjectDesc {
        index: 0x2010,
        name: "Analog input configuration",
        code: ObjectCode::Array,
        entries: &ANALOG_2010,
    },
    ObjectDesc {
        index: 0x2014,
        name: "Auxiliary power input monitoring",
        code: ObjectCode::Array,
        entries: &AUX_POWER_2014,
    },
    ObjectDesc {
        index: 0x2015,
        name: "+VDC input monitoring",
        code: ObjectCode::Array,
        entries: &VDC_2015,
    },
    ObjectDesc {
        index: 0x2018,
        name: "PCB temperature options",
        code: ObjectCode::Array,
        entries: &PCB_TEMP_2018,
    },
    ObjectDesc {
        index: 0x2019,
        name: "Bridge temperature options",
        code: ObjectCode::Array,
        entries: &BRIDGE_TEMP_2019,
    },
    ObjectDesc {
        index: 0x2020,
        name: "Software limits as hardware",
        code: ObjectCode::Array,
        entries: &SW_LIMITS_AS_HW_2020,
    },
    ObjectDesc {
        index: 0x2022,
        name: "Actual position software limit",
        code: ObjectCode::Array,
        entries: &SW_LIMIT_2022,
    },
    var!(
        0x2030,
        "Output bridge polarity",
        I8,
        RW,
        i(0),
        i(-128),
        i(127)
    ),
    var!(0x2031, "Unit options", U8, RW, u(0)),
    ObjectDesc {
        index: 0x2033,
        name: "Capture input parameters",
        code: ObjectCode::Record,
        entries: &CAPTURE_2033,
    },
    ObjectDesc {
        index: 0x2034,
        name: "Bridge on settle time",
        code: ObjectCode::Array,
        entries: &BRIDGE_SETTLE_2034,
    },
    ObjectDesc {
        index: 0x2035,
        name: "Brake settle allow time",
        code: ObjectCode::Array,
        entries: &BRAKE_SETTLE_2035,
    },
    // "0 (off) or 2 to 65535 ms" (§8.6.21).
    var!(
        0x2036,
        "Hold current delay time",
        U16,
        RW,
        u(500),
        u(0),
        u(65535)
    ),
    var!(
        0x2037,
        "Bridge on to encoder settle time",
        U16,
        RW,
        u(300),
        u(0),
        u(3000)
    ),
    ObjectDesc {
        index: 0x2038,
        name: "Trip output configuration",
        code: ObjectCode::Record,
        entries: &TRIP_2038,
    },
    var!(0x2098, "Homing configuration", U8, RW, u(1), u(0), u(1)),
    var!(0x2204, "Run current", U8, RW, u(50), u(1), u(100)),
    var!(0x2205, "Hold current", U8, RW, u(5), u(0), u(100)),
    var!(0x2211, "Position present point target", I32, RO, i(0)),
    var!(0x2212, "Position final point target", I32, RO, i(0)),
    ObjectDesc {
        index: 0x2221,
        name: "Following error",
        code: ObjectCode::Array,
        entries: &FOLLOWING_ERROR_2221,
    },
    var!(
        0x2401,
        "General purpose user variable",
        U8,
        RW,
        u(0),
        u(0),
        u(0xFF)
    ),
    var!(0x2504, "SEM options", U8, RW, u(0), u(0), u(0xFF)),
    var!(0x2701, "hMTechnology enable", U8, RW, u(0), u(0), u(0x80)),
    var!(0x2702, "hMTechnology configuration", U8, RW, u(0xA2)),
    var!(0x2703, "Make-up velocity", U32, RW, u(1998)),
    var!(0x2704, "Torque speed", U8, RW, u(98)),
    var!(0x2710, "Locked rotor timeout", U8, RW, u(0)),
    var!(0x2740, "hMTechnology control", U8, RW_R, u(0)),
    var!(0x2741, "hMTechnology status (filtered)", U8, RO_T, u(0x80)),
    var!(0x2742, "hMTechnology status (unfiltered)", U8, RO, u(0x80)),
    var!(0x2743, "hMTechnology status filter", U8, RW, u(0xEF)),
    // ----- 5000h group (factory; only 5002h:01 is named, §5.6) -----
    ObjectDesc {
        index: 0x5002,
        name: "Factory configuration",
        code: ObjectCode::Record,
        entries: &FACTORY_5002,
    },
    // ----- 6000h group -----
    var!(
        0x6007,
        "Abort connection option code",
        I16,
        RW,
        i(0),
        i(0),
        i(3)
    ),
    var!(0x603F, "Error code", U16, RO_T, u(0)),
    var!(0x6040, "Controlword", U16, RW_R, u(0)),
    var!(0x6041, "Statusword", U16, RO_T, u(0)),
    var!(0x605A, "Quick stop option code", I16, RW, i(2), i(0), i(6)),
    var!(0x605B, "Shutdown option code", I16, RW, i(0), i(0), i(1)),
    var!(
        0x605C,
        "Disable operation option code",
        I16,
        RW,
        i(0),
        i(0),
        i(1)
    ),
    var!(0x605D, "Halt option code", I16, RW, i(2), i(1), i(2)),
    var!(
        0x605E,
        "Fault reaction option code",
        I16,
        RW,
        i(2),
        i(0),
        i(2)
    ),
    var!(0x6060, "Modes of operation", I8, RW_R, i(1), i(1), i(6)),
    var!(0x6061, "Modes of operation display", I8, RO_T, i(1)),
    var!(0x6062, "Position demand value", I32, RO_T, i(0)),
    var!(0x6063, "Position actual value internal", I32, RO_T, i(0)),
    var!(0x6064, "Position actual value", I32, RO_T, i(0)),
    // "0000 0512h" as printed (§6.10.5).
    var!(0x6065, "Following error window", U32, RW, u(0x0000_0512)),
    var!(0x6066, "Following error timeout", U16, RW, u(0)),
    var!(0x6067, "Position window", U32, RW, u(0x0FFF_FFFF)),
    var!(0x6068, "Position window time", U16, RW, u(0)),
    var!(0x606C, "Velocity actual value", I32, RO_T, i(0)),
    var!(0x6071, "Target torque", I16, RW_R, i(0), i(-1000), i(1000)),
    var!(
        0x6077,
        "Torque actual value",
        I16,
        RO_T,
        i(0),
        i(-1000),
        i(1000)
    ),
    var!(0x607A, "Target position", I32, RW_R, i(0)),
    var!(0x607C, "Homing offset", I32, RW, i(0)),
    var!(0x607E, "Polarity", U8, RW_R, u(0)),
    var!(0x6081, "Profile velocity", U32, RW_R, u(512_000)),
    var!(0x6082, "End velocity", U32, RW_R, u(51_200)),
    var!(0x6083, "Profile acceleration", U32, RW_R, u(100_000)),
    var!(0x6084, "Profile deceleration", U32, RW_R, u(100_000)),
    var!(0x6085, "Quick stop deceleration", U32, RW, u(200_000)),
    var!(0x6086, "Motion profile type", I16, RW_R, i(0), i(0), i(0)),
    var!(0x6087, "Torque slope", U32, RW, u(1000)),
    ObjectDesc {
        index: 0x608F,
        name: "Position encoder resolution",
        code: ObjectCode::Array,
        entries: &ENCODER_RES_608F,
    },
    ObjectDesc {
        index: 0x6092,
        name: "Feed and drive shaft resolution",
        code: ObjectCode::Array,
        entries: &FEED_6092,
    },
    var!(0x6098, "Homing method", I8, RW, i(0), i(0), i(35)),
    ObjectDesc {
        index: 0x6099,
        name: "Homing speeds",
        code: ObjectCode::Array,
        entries: &HOMING_SPEEDS_6099,
    },
    ObjectDesc {
        index: 0x60C2,
        name: "Interpolation time period",
        code: ObjectCode::Record,
        entries: &INTERPOLATION_60C2,
    },
    var!(0x60F8, "Maximum slippage", I32, RW, i(512)),
    var!(0x60FD, "Digital inputs", U32, RO_T, u(0)),
    ObjectDesc {
        index: 0x60FE,
        name: "Digital outputs",
        code: ObjectCode::Array,
        entries: &DIGITAL_OUTPUTS_60FE,
    },
    var!(0x60FF, "Target velocity", I32, RW_R, i(0)),
    var!(0x6402, "Motor type", U16, RO, u(MOTOR_TYPE as u64)),
    var!(
        0x6502,
        "Supported drive modes",
        U32,
        RO,
        u(SUPPORTED_MODES_RAW as u64)
    ),
];

// ===== units ====================================================================================

/// Units of the motor model: microsteps, 51 200 per revolution with the default 6092h
/// (§6.5.5, §6.11.2); 60FFh/606Ch and 6081h/6082h/6099h in (micro)steps per second (§6.5.7,
/// §6.6.4, §6.6.6); 6083h–6085h in steps/s² (§6.5.9–§6.5.11); 6071h/6077h in ‰ of rated
/// torque (§6.8.3, §6.8.4); 6087h in ‰ of rated torque per second (§6.8.5).
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

// ===== homing ===================================================================================

/// 6098h values (§6.7.5): 0 = no homing; 1–14 (limit/home switch with index pulse); 17–30
/// (the same without index pulse); 33/34 (index pulse only); 35 (current position). 15, 16, 31,
/// 32 are "reserved" and refused **\[REC\]** (the object's range is 0–35).
const HOMING_METHODS: [i8; 32] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27,
    28, 29, 30, 33, 34, 35,
];

/// Homing: default 6098h = 0 (§6.7.5). The index pulse comes from the encoder of the closed-loop
/// models (2031h bit 3, §8.6.17); the emulated open-loop model has none, so the index methods
/// (1–14, 33, 34) end in a homing error.
pub const HOMING: HomingSupport = HomingSupport {
    methods: &HOMING_METHODS,
    default_method: 0,
    index_pulse: false,
};

// ===== communication ============================================================================

/// Error control and SYNC (§3.6.2, §8.2, §8.5):
/// - node/life guarding 100Ch/100Dh: yes (§8.5.9, §8.5.10);
/// - consumer heartbeat 1016h: not in the object tables (§8.2) → 0 entries (DISCREPANCY);
/// - SYNC producer: no, "The device can only receive SYNC messages" (§8.5.4);
/// - 1006h: not in the object tables (§8.2) (DISCREPANCY);
/// - 1003h: 4 entries (§8.5.3 "0 … 4", §8.2 "01h – 04h");
/// - 1010h/1011h: sub-indices 1–4 (§8.5.10, §8.5.11);
/// - no SDO or RPDO rate limit is stated (MANUAL GAP → 0).
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

// ===== the node =================================================================================

/// The emulated Lexium MDrive (open loop). See the [module documentation](self).
pub const SPEC: NodeSpec = NodeSpec {
    name: "Lexium MDrive",
    vendor: "Schneider Electric",
    source: "CANopen Fieldbus manual for Lexium MDrive, V1.00, 09.2014 (Schneider Electric \
             Motion USA)",
    dictionary: DICTIONARY,
    caps: CAPS,
    units: UNITS,
    pdo: PDO,
    homing: HOMING,
    emcy: EmcyFormat::PdoAndVendorCode,
    alarms: ALARMS,
    comm: COMM,
    // §3.6.1 Table 3.10: Stop remote node (B) and Reset communication (E) with the power stage
    // enabled trigger an error of error class 2: quick stop, then power stage disabled.
    nmt_stop_while_enabled: EnabledNmtReaction::QuickStopThenFault(NMT_WHILE_ENABLED_ALARM),
    nmt_reset_while_enabled: EnabledNmtReaction::QuickStopThenFault(NMT_WHILE_ENABLED_ALARM),
    // The manual names no target the drive clears when it enables (MANUAL GAP).
    targets_cleared_on_enable: &[],
    // quirks.rs LEXIUM_MDRIVE: an RPDO shorter than its mapping: EMCY 8210h (Table 7.2);
    // guarding/heartbeat lost: EMCY 8130h (Table 7.2, §8.5.10).
    quirks: EmulationQuirks {
        pdo_length_alarm: Some(0x8210),
        guarding_alarm: Some(0x8130),
        // The one range code the manual names (§7.3.2 1003h, §8.5 1012h/1014h/14xxh): 0609
        // 0030h; it lists no 0609 0031h/0032h.
        range_abort_high_low: false,
        ..EmulationQuirks::NONE
    },
};

// ===== MANUAL GAP / [REC] / DISCREPANCY ========================================================
//
// MANUAL GAP / [REC] (values the manual does not state; our choice):
// - 1018h:04 serial number: device-specific, no default (§8.5.16). [REC] 1454523Eh, §5.6's
//   example (341070398); 5002h:01 holds the same value (5000h group "not for end use", §8.7;
//   only 5002h:01 is named, §5.6; type UNSIGNED32 and access ro are [REC]).
// - Error register bits per alarm (§7.3.1 gives only the bit meanings): [REC] 11h for the
//   communication errors, 09h for 4210h, 81h for FF01h.
// - Fault or warning per Table 7.2 row: [REC] 8110h/8120h/8140h/8141h warnings (6007h, default
//   "no action", governs bus-off); 8210h warning; FF01h/01h–08h faults (errors, §3.5.1);
//   FF01h/09h and 4210h/16h warnings (named so); 4210h/08h and 8130h faults (§8.6.12, §8.5.10).
// - Vendor number of the 81xxh/8210h alarms: the manual's additional info is 0h for all of
//   them; [REC] the number is the error code itself (distinct keys; the quirks name 8210h and
//   8130h). The node therefore puts e.g. 8130h in EMCY bytes 6–7 where the drive sends 0000h.
// - The alarm raised for NMT Stop / Reset while enabled ("error of error class 2", §3.6.1):
//   no error code is named. [REC] code and number 8100h (CiA 301 communication), fault.
//   §3.6.1 names the error class only for Stop (B) and Reset communication (E); Reset node (D)
//   passes through Reset communication, so the same reaction is used for both resets.
// - 1801h/1802h event timer 100 ms, 1800h 0 (§8.5.20); 1803h:05 not stated: [REC] 0.
// - PDO COB-ID bit 30 (RTR not allowed) at power-on: not stated; [REC] 0 (RTR allowed).
// - 2009h (Table 3.9 only, "Read value of output fault", T_PDO, UINT8 at sub 1): object code,
//   sub 0 and default not stated. [REC] ARRAY, 1 entry, default 0.
// - 2000h:01–03 "Reserved" (access "—" in §8.6.1, rw in §8.3): [REC] U8 rw, default 0.
// - 2004h:05–08, 2006h:05–08: reserved / "Input 9–12"; [REC] U8 rw, default 0.
// - 2008h:01/02, 2031h, 2038h:01, 2702h, 2703h, 2704h, 2743h: no range; none given.
// - 2010h:01, 2014h:01, 2015h:01, 2018h:01, 2019h:01 readings, 2710h, 2740h: no default;
//   [REC] 0.
// - 2221h:01 following-error reaction: the "Default value" field holds the range "0 - 2";
//   [REC] default 0 (no action), range 0–2.
// - 6040h default "device and operation mode specific" (§6.2.1): [REC] 0.
// - 60C2h:01/:02 defaults not stated (§8.4): [REC] 1 and −3 (CiA 402: 1 ms); csp is not in
//   6502h anyway.
// - 6060h range: values 1, 3, 6 (§6.4.1); the entry range is [REC] 1–6 and the node refuses
//   modes not in 6502h.
// - 6098h: 15, 16, 31, 32 are "reserved" inside the stated range 0–35: [REC] refused.
// - 1003h: manual gives the history depth (4) but no example entry values.
// - 1009h/100Ah: the manual gives "V1.00" / "V5.48" as the default values (§8.5.7, §8.5.8);
//   kept as HW_VERSION / SW_VERSION (a unit with other firmware reports others).
// - State skipping: Table 6.3 lists only CiA 402 commands ("Switch on + enable operation" =
//   transitions 3 + 4); no jump is documented → false.
// - Statusword bit 9 (remote): §6.2.2 restates CiA 402 and names no condition that clears it;
//   [REC] remote_gates_controlword = false (the node keeps bit 9 set).
// - Targets cleared on enable: none named → empty.
// - SDO / RPDO minimum intervals: none stated → 0.
// - The emulated model is the open-loop one (no encoder): index_pulse = false; 6071h, 6077h,
//   6087h, 2701h–2743h stay in the dictionary (listed in §8.3/§8.4) but tq is not in 6502h.
//
// DISCREPANCY (the manual contradicts itself; the reading used and why):
// - Vendor ID: 1018h:01 = 0000 021Bh (§8.5.16) vs LSS signature "VendorID = 0800005Ah" (§5.6).
//   Used 021Bh (the object's documented default; the quirk table is keyed by it);
//   LSS_VENDOR_ID records the other.
// - "The device uses 6 PDOs, 3 receive PDOs and 3 transmit PDOs" (§3.3.3) vs four RPDOs and
//   four TPDOs everywhere else (Table 3.6, Table 3.7, §8.2). Used four each.
// - PDO validity at power-on: §8.5.18/§8.5.20 give the COB-IDs as "0300h + node ID" etc.
//   without bit 31, but §3.3.3 says "With the default PDO settings, R_PDO1 and T_PDO1 are
//   activated. The other PDOs must be activated first". Used bit 31 set for PDOs 2–4.
// - 1603h:02 default "6071 0020h" (§8.5.19): 6071h is INTEGER16 (§6.8.3, §8.4), so the length
//   should be 10h. Kept the manual's 20h (RPDO4 is invalid at power-on; a master must remap).
// - Mapping entries per PDO: "Each communication object … provides 4 subindex entries"
//   (§3.3.4) vs "Up to 8 bytes of 8 different objects" (§3.3.4) and sub-indices 01h–08h
//   (§8.2, §8.5.19). Used 8. Sub 00h range "1 – 64" (§8.2, §8.5.19) vs 8 entries: used 0–8.
// - Table 3.8 gives length 20h = "30 bits": used 32 bits.
// - 1A0xh:02 defaults are labelled "1800h … 1803h" (§8.5.21): read as 1A00h–1A03h.
// - 1001h bits: §7.3.1 bits 1 current, 2 voltage, 5 device profile; §8.5.2 bits 1, 2, 5, 6
//   reserved. Used §7.3.1's meanings only for bits 0, 3, 4, 7, which both agree on.
// - 1003h:00 range 0–254 with entries 02h–FEh (§7.3.2) vs 0…4 with entries 01h–04h (§8.5.3,
//   §8.2). Used 4. §8.5.3 says the high 16 bits are "not assigned in the device", but Table
//   7.2 and §8.6.12 give additional info (0016 4210h / 0008 4210h). Used Table 7.2.
// - 1006h (communication cycle period) and 1016h (consumer heartbeat): used in §3.4, §3.6.2.2
//   and the LED table (§7.4) but absent from the object tables (§8.2, "No objects … 1000h").
//   Used the tables: neither object exists (heartbeat_consumers 0, has_cycle_period false).
// - Life time expiry → Fault (§8.5.10) vs 6007h default 0 "no action" for life guarding
//   (§6.3.1). Used §8.5.10 (fault), matching the quirk's guarding alarm.
// - 6007h PDO mapping "Yes" (§6.3.1) vs none (§8.4, not in Table 3.9). Used §8.4: rw, not
//   mappable.
// - 603Fh access rw (§6.3.2) vs ro (§8.4). Used ro, TPDO-mappable (§8.4, Table 3.9).
// - 6060h PDO mapping "No" (§6.4.1) vs R_PDO (§8.4, Table 3.9). Used RPDO-mappable.
// - 606Ch access rw (§6.6.4) vs ro (§8.4). Used ro, TPDO-mappable.
// - 607Ch: UNSIGNED32 with PDO mapping "Yes" (§6.7.4) vs INTEGER32, no PDO (§8.4); negative
//   offsets are described ("Negative values shall indicate the opposite direction"). Used
//   INTEGER32, rw, not mappable.
// - 6085h, 6087h, 6098h PDO mapping "Yes" (§6.5.11, §6.8.5, §6.7.5) vs not mappable (§8.4,
//   not in Table 3.9). Used §8.4.
// - 60F8h shown as "Index 60FFh" (§6.6.5), 6068h as "6066h" (§6.10.8), 6099h as "6098h"
//   (§6.7.5), 6082h named "Polarity" (§6.5.8), 605Eh named "Halt" (§6.3.7), 1014h as
//   "10142h" (§8.5.13), 2019h as "2018h" (§8.6.13), 2002h heading "2003h" (§8.6.2). Used the
//   indices of the §8.2–§8.4 tables.
// - 6065h default "0000 0512h" (hexadecimal = 1298) next to 60F8h's "512d": kept 0512h as
//   printed.
// - Supported modes: §6.4 lists pp, hm, pv; 6502h = 0025h (§6.4.3) and 6060h 1/3/6 (§6.4.1),
//   but §6.8 documents profile torque (closed loop only) with 6060h = 4 in its example, and
//   §6.9 describes csp. Used 0025h (the open-loop model).
// - 2002h: §8.3 lists subs 01h–03h with "Number of entries = 04h"; §8.6.2 lists 01h–04h
//   (04h inhibit switch). Used 4 entries.
// - 2006h: §8.6.4 labels two entries "05h" (Input 4 and Input 9). Read as 04h = Input 4,
//   05h–08h = Inputs 9–12.
// - 2007h:01 range "1 – 12" but the value table includes 0 = "No action" (§8.6.7). Used 0–12.
// - 2014h/2015h subs 01–03: UNSIGNED8, all ro (§8.3) vs UNSIGNED16 (ranges up to 280/800),
//   :02/:03 rw (§8.6.10, §8.6.11). Used §8.6 (280 and 800 do not fit 8 bits).
// - 2019h:01 UINT16 (Table 3.9) vs INTEGER8 (§8.3, §8.6.13). Used INTEGER8.
// - 2020h: §8.3 heading row "Set temperature fault VAR Integer8" vs §8.6.14 ARRAY of UNSIGNED8
//   (flag, mask). Used §8.6.14.
// - 2034h:01, 2035h:01/02: UNSIGNED8 (§8.3) vs ranges 0–1000 / 0–2000 ms (§8.6.19, §8.6.20;
//   2034h "Data type Unsigned16"). Used UNSIGNED16.
// - 2038h: §8.6.23's text lists four sub-indices (03h "capture input filter time", 04h
//   spacing) but its table has three (03h spacing, count 03h). Used the table.
// - 2098h value 0: "the position or encoder counter will clear following a home" and, in the
//   next sentence, "will NOT be assigned" (§8.6.24). Only stored here; default 1.
// - 2221h: ARRAY with rw :01 (§8.3) vs "VAR Integer32", :01 read-only (§8.6.29). Used §8.3.
// - 2401h, 2504h: UNSIGNED8 (§8.3) vs Integer32 with range 00–FFh (§8.6.30, §8.6.31). Used
//   UNSIGNED8.
// - Homing example (§6.7.6): "home method 18" but writes 13h = 19; "Stop homing" writes
//   controlword 0000h. No effect on the table.
// - Table 3.4 SDO read request/response command bytes are swapped relative to CiA 301; the
//   node follows CiA 301 (the manual's example frames do too).
