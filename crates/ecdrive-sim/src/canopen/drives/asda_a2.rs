//! The emulated Delta ASDA-A2 servo drive in CANopen mode, as data: its [`NodeSpec`], written
//! from Delta's manual *CANopen for ASDA-A2* (manual number CANopen for
//! ASDA-A2_M_EN_20120920, second edition V2.01, 2012/09/20) independently of the master's
//! profile. "§x.y" cites a section of that manual; the manual refers to CiA DS 301 V4.02 and
//! CiA DSP 402 V2.0 (§6).
//!
//! What the manual gives and this table holds:
//! - identity: vendor 1DDh, product 6000h (A2) / 6030h (M), device type 04020192h / 06020192h,
//!   1018h:00 = 3 with no serial number (§4.4); node-ID P3-00 (default 7Fh) and bit rate P3-01
//!   (default 500 kbit/s) (§2.2.1, §2.2.2);
//! - CANopen mode is P1-01 = 0x0B ("half", simple) or 0x0C ("full", standard DS402) (§2.2.1);
//!   **the emulation models P1-01 = 0x0C**: controlword default 0x0004, 60C1h = 32-bit position
//!   plus optional 16-bit difference, 60C2h as the ip period, homing speeds in 0.1 rpm (§3.2.2,
//!   §4.4);
//! - the CiA 402 state machine stepped 0x0006 → 0x0007 → 0x000F (§4.4 6040h note), except that
//!   with P3-12 X = 0 (the default) "enable operation" alone switches the servo on (§2.2.2,
//!   emulated by [`QUIRKS`]); no 605Ah (the object list §4.3 has none);
//! - modes pp, pv, tq, hm, ip (6502h = 6Dh, §4.4); no touch probe, no 60E3h;
//! - the object dictionary of §4.2 (1000h group), §4.3 (6000h group) and the Delta parameters
//!   2xxxh that the CANopen chapters name (§2.2.2, §4.4 "Object 2xxxh");
//! - 4 RPDOs and 4 TPDOs of up to 8 objects, transmission type 0 and no mapping by default
//!   (§4.4 1400h–1A03h);
//! - the EMCY layout with the panel alarm code in bytes 3–4 (§5.1) and the alarm list (§5.1,
//!   §5.2); the SDO abort codes (§5.3);
//! - the rate limits (AL111 for two SDOs within 1 ms, AL112 for two PDOs on one COB-ID within
//!   1 ms, §5.1) and AL401 for NMT Stop / Reset while enabled (§5.1);
//! - 60FFh and 6071h cleared on servo-on (§3.4.2, §3.5.2).
//!
//! Values the manual does not give are labelled **MANUAL GAP** or **\[REC\]** (the emulator's
//! choice); the list, and the places where the manual contradicts itself, are at the end of
//! the file.

use super::super::quirks::{Bit3Enable, EmulationQuirks};
use super::super::spec::NodeSpec;
use crate::can::profile::od::{I8, I16, I32, RO, RO_T, RW, RW_RT, U8, U16, U32, e, i, pdo_map, u};
use crate::can::profile::{
    Alarm, CanPdoProfile, CommSupport, EmcyFormat, EnabledNmtReaction, HomingSupport, PdoDefault,
    TransmissionTypes,
};
use crate::cia402::units::{AccelUnit, TorqueSlopeUnit, Units, VelocityUnit};
use crate::cia402::{DriveCaps, ErrorEntry, ProfileUnits, QuickStopOption, SupportedModes};
use crate::od::{EntryDesc, ObjectAddress, ObjectCode, ObjectDesc};
use crate::pdo::{DirectionLimits, PdoLimits, PdoRange};

// ================================================================================================
// Identity and commissioning (§2.2, §4.4)
// ================================================================================================

/// Model name.
pub const NAME: &str = "ASDA-A2";
/// Vendor name.
pub const VENDOR: &str = "Delta Electronics";
/// The manual the values come from.
pub const SOURCE: &str = "Delta, CANopen for ASDA-A2 (manual CANopen for \
                          ASDA-A2_M_EN_20120920, second edition V2.01, 2012/09/20)";

/// 1018h:01 vendor ID (§4.4).
pub const VENDOR_ID: u32 = 0x0000_01DD;
/// 1018h:02 product code of the A2 series (§4.4); the emulated node reports this one.
pub const PRODUCT_CODE_A2: u32 = 0x0000_6000;
/// 1018h:02 product code of the M series (§4.4).
pub const PRODUCT_CODE_M: u32 = 0x0000_6030;
/// 1000h device type of the A2 series (§4.4): profile 0192h = 402; the emulated node reports
/// this one.
pub const DEVICE_TYPE_A2: u32 = 0x0402_0192;
/// 1000h device type of the M series (§4.4).
pub const DEVICE_TYPE_M: u32 = 0x0602_0192;
/// 1018h:03 revision number. **MANUAL GAP**: §4.4 gives "N/A" as its default; \[REC\] 0.
pub const REVISION: u32 = 0;

/// Factory node-ID, P3-00 = 7Fh (§2.2.2; range 01h–7Fh).
pub const DEFAULT_NODE_ID: u8 = 0x7F;
/// Factory bit rate, kbit/s: P3-01 = 0x0203, digit Z = 2 (§1.2, §2.2.2).
pub const DEFAULT_BITRATE_KBIT: u16 = 500;
/// Bit rates by P3-01 digit Z = 0…4, kbit/s (§2.2.1, §2.2.2).
pub const BITRATES_KBIT: [u16; 5] = [125, 250, 500, 750, 1000];
/// Longest bus per bit rate, m (§1.2).
pub const BUS_LENGTH_M: [(u16, u16); 5] =
    [(1000, 25), (750, 50), (500, 100), (250, 250), (125, 500)];

/// P1-01 value "CANopen mode (half)": simple mode, not the complete protocol (§2.2.1).
pub const P1_01_CANOPEN_HALF: u16 = 0x000B;
/// P1-01 value "CANopen mode (full)": the standard protocol, recommended (§2.2.1). The
/// emulation models this mode.
pub const P1_01_CANOPEN_FULL: u16 = 0x000C;

/// Index of drive parameter P`group`-`number` (§4.4 "Object 2xxxh": P3-00 → 2300h, P1-44 →
/// 212Ch, i.e. 2000h + group × 100h + number, the number taken as a binary value).
pub const fn param(group: u16, number: u16) -> u16 {
    0x2000 + group * 0x100 + number
}

/// P1-01 control mode (§2.2.2).
pub const P1_01: u16 = param(1, 1);
/// P1-32 stop mode; digit Y ↔ 605Bh (§2.2.2 P3-12 table).
pub const P1_32: u16 = param(1, 32);
/// P1-34 acceleration time ↔ 6083h, 6084h, 6087h (§2.2.2 P3-12 table).
pub const P1_34: u16 = param(1, 34);
/// P1-38 zero-speed range ↔ 606Fh (§2.2.2 P3-12 table).
pub const P1_38: u16 = param(1, 38);
/// P1-44 electronic gear numerator ↔ 6093h:01 (§2.2.2, §4.4 example 2: 212Ch).
pub const P1_44: u16 = param(1, 44);
/// P1-45 electronic gear denominator ↔ 6093h:02 (§2.2.2 P3-12 table, §4.4 6093h).
pub const P1_45: u16 = param(1, 45);
/// P1-47 speed reached range ↔ 606Dh (§2.2.2 P3-12 table).
pub const P1_47: u16 = param(1, 47);
/// P1-49 ↔ 606Eh velocity window time (§2.2.2 P3-12 table).
pub const P1_49: u16 = param(1, 49);
/// P1-55 maximum speed; 607Fh = P1-55 × 10, 6080h = P1-55 (§4.4).
pub const P1_55: u16 = param(1, 55);
/// P2-08 special function: 10 (or 30, then 28 after a firmware upgrade) clears AL201 (§5.1).
pub const P2_08: u16 = param(2, 8);
/// P2-35 excessive deviation ↔ 6065h (§2.2.2 P3-12 table).
pub const P2_35: u16 = param(2, 35);
/// P3-00 node-ID (§2.2.2, §4.4 example 1: 2300h).
pub const P3_00: u16 = param(3, 0);
/// P3-01 bit rate (§2.2.2).
pub const P3_01: u16 = param(3, 1);
/// P3-09 SYNC clock correction (§2.2.2).
pub const P3_09: u16 = param(3, 9);
/// P3-10 DS402 protocol version / reaction to CAN bus errors (§2.2.2).
pub const P3_10: u16 = param(3, 10);
/// P3-11 EEPROM saving of PDO writes (§2.2.2).
pub const P3_11: u16 = param(3, 11);
/// P3-12 quick stop / servo-on / reload settings (§2.2.2).
pub const P3_12: u16 = param(3, 12);

/// P3-01 factory value: CAN 500 kbit/s (Z = 2), RS-232/485 38400 bit/s (X = 3) (§2.2.2).
pub const P3_01_DEFAULT: u16 = 0x0203;
/// P3-09 factory value: E = 5, T = 0, D = 5, M = 5 (§2.2.1 ④, §2.2.2).
pub const P3_09_DEFAULT: u16 = 0x5055;
/// P3-09 digit T: target SYNC arrival time = 300 + 10 × T µs (§2.2.2).
pub const SYNC_TARGET_BASE_US: u32 = 300;
/// "The standard value of SYNC signal reach time is 500 usec" (§2.2.2).
pub const SYNC_STANDARD_ARRIVAL_US: u32 = 500;

/// 1010h:01 signature "save" (§4.4).
pub const STORE_SIGNATURE: u32 = 0x6576_6173;
/// 1011h:01 signature "load" (§4.4).
pub const RESTORE_SIGNATURE: u32 = 0x6461_6F6C;

/// The ip period 60C2h:01 accepts with index −3, ms (§3.2.2, P1-01 = 0x0C).
pub const IP_PERIOD_MS: (u8, u8) = (1, 20);

/// 1008h–100Ah (device name, hardware and software version): **not in the object list**
/// (§4.2), so the node has none and there are no example strings to hold.
pub const HAS_NAME_AND_VERSION_STRINGS: bool = false;

/// The SDO abort codes the drive uses (§5.3), with the manual's texts; the 0800 00Axh ones are
/// Delta's.
pub const ABORT_CODES: &[(u32, &str)] = &[
    (
        0x0504_0001,
        "Client/server command specifier not valid or unknown",
    ),
    (0x0601_0002, "Attempt to write a read only object"),
    (
        0x0602_0000,
        "Object does not exist in the object dictionary",
    ),
    (0x0604_0041, "Object cannot be mapped to the PDO"),
    (
        0x0604_0042,
        "The number and length of the objects to be mapped would exceed PDO length",
    ),
    (
        0x0606_0000,
        "Access failed due to an hardware error (store or restore error)",
    ),
    (
        0x0607_0010,
        "Data type does not match, length of service parameter does not match",
    ),
    (0x0609_0011, "Sub-index does not exist"),
    (
        0x0609_0030,
        "Value range of parameter exceeded (only for write access)",
    ),
    (0x0800_0000, "General error"),
    (0x0800_00A1, "Object error when reading from EEPROM"),
    (0x0800_00A2, "Object error when writing to EEPROM"),
    (0x0800_00A3, "Invalid Range when accessing EEPROM"),
    (0x0800_00A4, "Checksum error when accessing EEPROM"),
    (0x0800_00A5, "Password error when writing encryption zone"),
    (
        0x0800_0020,
        "Data cannot be transferred or stored to the application (store or restore signature \
         error)",
    ),
    (
        0x0800_0021,
        "Data cannot be transferred or stored to the application because of the local control \
         (store or restore while wrong state)",
    ),
    (0x0800_0022, "Object is on the fly"),
];

// ================================================================================================
// CiA 402 capabilities (§2.2.2 P3-12, §3, §4.4 6040h/6041h/6060h/6502h)
// ================================================================================================

/// 6502h = 6Dh: pp (bit 0), pv (bit 2), tq (bit 3), hm (bit 5), ip (bit 6) (§4.4).
pub const SUPPORTED_MODES: u32 = 0x0000_006D;

/// The drive's own names of the error codes it reports (§5.2). Several alarms share a code;
/// the panel alarm number in EMCY bytes 3–4 tells them apart (see [`ALARMS`]).
pub const ERROR_TABLE: &[ErrorEntry] = &[
    ErrorEntry::exact(0x2310, "AL001", "Overcurrent"),
    ErrorEntry::exact(0x3110, "AL002", "Overvoltage"),
    ErrorEntry::exact(0x3120, "AL003", "Undervoltage"),
    ErrorEntry::exact(0x3130, "AL022", "Input power phase loss"),
    ErrorEntry::exact(0x3210, "AL005", "Regeneration error"),
    ErrorEntry::exact(0x3230, "AL006", "Overload"),
    ErrorEntry::exact(0x3231, "AL023", "Pre-overload warning"),
    ErrorEntry::exact(0x3300, "AL031", "U,V,W wiring error"),
    ErrorEntry::exact(0x4210, "AL016", "IGBT temperature error"),
    ErrorEntry::exact(0x5330, "AL017", "Memory error"),
    ErrorEntry::exact(0x5441, "AL013", "Emergency stop activated"),
    ErrorEntry::exact(0x5442, "AL015", "Forward limit switch error"),
    ErrorEntry::exact(0x5443, "AL014", "Reverse limit switch error"),
    ErrorEntry::exact(0x5444, "AL283", "Forward software limit"),
    ErrorEntry::exact(0x5445, "AL285", "Reverse software limit"),
    ErrorEntry::exact(0x5500, "AL099", "DSP firmware upgrade"),
    ErrorEntry::exact(
        0x6200,
        "AL301-AL305/AL3E1-AL3E5",
        "CANopen SYNC / IP command / SYNC period error",
    ),
    ErrorEntry::exact(
        0x6310,
        "AL201",
        "CANopen load/save 1010/1011 error (data initial error)",
    ),
    ErrorEntry::exact(0x6320, "AL012", "Adjustment error"),
    ErrorEntry::exact(0x7121, "AL030", "Motor protection error"),
    ErrorEntry::exact(0x7122, "AL004", "Motor error"),
    ErrorEntry::exact(0x7305, "AL011/AL024-AL027", "Encoder error"),
    ErrorEntry::exact(0x7306, "AL018", "Encoder output error"),
    ErrorEntry::exact(0x7510, "AL019", "Serial communication error"),
    ErrorEntry::exact(0x7520, "AL020", "Serial communication time out"),
    ErrorEntry::exact(
        0x8100,
        "AL186/AL401",
        "CANbus error (bus-off) / CANopen state error",
    ),
    ErrorEntry::exact(
        0x8110,
        "AL111/AL112",
        "CANopen SDO/PDO receive buffer overrun",
    ),
    ErrorEntry::exact(0x8120, "AL185", "CANbus error (warning)"),
    ErrorEntry::exact(0x8130, "AL170/AL180", "Node guarding or heartbeat error"),
    ErrorEntry::exact(0x8200, "AL121-AL132", "CANopen PDO object access error"),
    ErrorEntry::exact(0x8400, "AL007", "Overspeed"),
    ErrorEntry::exact(0x8600, "AL008", "Abnormal pulse control command"),
    ErrorEntry::exact(0x8610, "AL040", "Full closed-loop excessive deviation"),
    ErrorEntry::exact(0x8611, "AL009", "Excessive deviation"),
];

/// The state machine and modes.
///
/// - `state_skipping: false`: with P1-01 = 0x0C the master "need[s] to set 6040h to
///   0x0006->0x0007->0x000F for Servo On step by step" (§4.4 6040h note). The P3-12 X = 0
///   shortcut (bit 3 alone switches on, the factory setting, §2.2.2) is the quirk
///   [`QUIRKS`]`.bit3_enable`, read from 230Ch at run time.
/// - No 605Ah (§4.3), so `quick_stop_options` is empty and the default describes the fixed
///   behaviour: **MANUAL GAP** — the manual gives the quick-stop ramp 6085h (§4.4) and 605Eh
///   default 2 "slow down on quick stop ramp", but not the end state of a quick stop; \[REC\]
///   code 2 (6085h ramp, then Switch on disabled), the CiA 402 default.
/// - Transition 16: not mentioned; without codes 5–8 it cannot occur (\[REC\] `false`).
/// - Statusword bit 9 "Remote" exists (§4.4 6041h) but nothing gates the controlword on it.
/// - Homing: only statusword bit 13 "Homing error" (§4.4 6041h); no alarm is named.
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: false,
    quick_stop_options: &[],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: false,
    supported_modes: SupportedModes::from_raw(SUPPORTED_MODES),
    error_table: ERROR_TABLE,
    csp_start_edge: false,
    homing_failure: "",
    home_offset_set_by_drive: None,
    sdo_refused_while_rx_mapped: None,
    pp_target_range: None,
};

// ================================================================================================
// Alarms (§5.1 fault messages, §5.2 error code table)
// ================================================================================================

/// Error register 1001h reported with an alarm. **MANUAL GAP**: the manual gives 1001h only as
/// "error register" (§4.4, §5.1 byte 2). \[REC\] the CiA 301 bits by the code's class: bit 0
/// (generic) always, plus bit 1 current (2xxxh), bit 2 voltage (3xxxh), bit 3 temperature
/// (4xxxh), bit 4 communication (81xxh, 82xxh).
const fn register_for(code: u16) -> u8 {
    match code >> 12 {
        0x2 => 0x03,
        0x3 => 0x05,
        0x4 => 0x09,
        0x8 if code < 0x8300 => 0x11,
        _ => 0x01,
    }
}

/// An alarm that puts the drive into Fault.
const fn fault(number: u16, code: u16, name: &'static str, text: &'static str) -> Alarm {
    Alarm {
        number,
        code,
        register: register_for(code),
        name,
        text,
        fault: true,
    }
}

/// An alarm the manual calls a warning (statusword bit 7, "drive still servo on", §4.4
/// 6041h).
const fn warning(number: u16, code: u16, name: &'static str, text: &'static str) -> Alarm {
    Alarm {
        fault: false,
        ..fault(number, code, name, text)
    }
}

/// Every alarm the manual lists (§5.1, §5.2), with the panel number written as hex digits
/// (AL011 → 0x0011, AL3E1 → 0x03E1) as EMCY bytes 3–4 carry it (§5.1) and the code of §5.2.
/// Fault or warning: only AL023 ("Pre-overload warning") and AL185 ("CANbus error
/// (Warning)") are named warnings; **MANUAL GAP** for the rest, \[REC\] faults (each is cleared
/// by "NMT-ResetNode or 6040h fault reset", §5.1). AL010 and AL021 ("Reserved", §5.2) are not
/// alarms and are left out.
pub static ALARMS: &[Alarm] = &[
    // §5.2: drive alarms.
    fault(0x0001, 0x2310, "AL001", "Overcurrent"),
    fault(0x0002, 0x3110, "AL002", "Overvoltage"),
    fault(0x0003, 0x3120, "AL003", "Undervoltage"),
    fault(0x0004, 0x7122, "AL004", "Motor error"),
    fault(0x0005, 0x3210, "AL005", "Regeneration error"),
    fault(0x0006, 0x3230, "AL006", "Overload"),
    fault(0x0007, 0x8400, "AL007", "Overspeed"),
    fault(0x0008, 0x8600, "AL008", "Abnormal pulse control command"),
    fault(0x0009, 0x8611, "AL009", "Excessive deviation"),
    fault(0x0011, 0x7305, "AL011", "Encoder error"),
    fault(0x0012, 0x6320, "AL012", "Adjustment error"),
    fault(0x0013, 0x5441, "AL013", "Emergency stop activated"),
    fault(0x0014, 0x5443, "AL014", "Reverse limit switch error"),
    fault(0x0015, 0x5442, "AL015", "Forward limit switch error"),
    fault(0x0016, 0x4210, "AL016", "IGBT temperature error"),
    fault(0x0017, 0x5330, "AL017", "Memory error"),
    fault(0x0018, 0x7306, "AL018", "Encoder output error"),
    fault(0x0019, 0x7510, "AL019", "Serial communication error"),
    fault(0x0020, 0x7520, "AL020", "Serial communication time out"),
    fault(0x0022, 0x3130, "AL022", "Input power phase loss"),
    warning(0x0023, 0x3231, "AL023", "Pre-overload warning"),
    fault(
        0x0024,
        0x7305,
        "AL024",
        "Encoder initial magnetic field error",
    ),
    fault(0x0025, 0x7305, "AL025", "Encoder internal error"),
    fault(0x0026, 0x7305, "AL026", "Encoder internal error"),
    fault(0x0027, 0x7305, "AL027", "Encoder data error"),
    fault(0x0030, 0x7121, "AL030", "Motor protection error"),
    fault(0x0031, 0x3300, "AL031", "U,V,W wiring error"),
    fault(
        0x0040,
        0x8610,
        "AL040",
        "Full closed-loop excessive deviation",
    ),
    fault(0x0099, 0x5500, "AL099", "DSP firmware upgrade"),
    // §5.1 / §5.2: CANopen alarms.
    fault(
        0x0111,
        0x8110,
        "AL111",
        "CANopen SDO receive buffer overrun (two or more SDO packets in 1 ms)",
    ),
    fault(
        0x0112,
        0x8110,
        "AL112",
        "CANopen PDO receive buffer overrun (two or more PDO packets with the same COB-ID in \
         1 ms)",
    ),
    fault(
        0x0121,
        0x8200,
        "AL121",
        "Index error when accessing CANopen PDO object: the index does not exist",
    ),
    fault(
        0x0122,
        0x8200,
        "AL122",
        "Sub-index error when accessing CANopen PDO object: the sub-index does not exist",
    ),
    fault(
        0x0123,
        0x8200,
        "AL123",
        "Data type (size) error when accessing CANopen PDO object: the data length does not \
         match the object",
    ),
    fault(
        0x0124,
        0x8200,
        "AL124",
        "Data range error when accessing CANopen PDO object: the data exceeds the object's range",
    ),
    fault(
        0x0125,
        0x8200,
        "AL125",
        "CANopen PDO object is read-only and write-protected",
    ),
    fault(
        0x0126,
        0x8200,
        "AL126",
        "CANopen PDO object does not support PDO",
    ),
    fault(
        0x0127,
        0x8200,
        "AL127",
        "CANopen PDO object is write-protected when Servo On",
    ),
    fault(
        0x0128,
        0x8200,
        "AL128",
        "Error reading CANopen objects from EEPROM at start-up; all objects return to their \
         defaults",
    ),
    fault(
        0x0129,
        0x8200,
        "AL129",
        "Error writing CANopen objects into EEPROM",
    ),
    fault(
        0x0130,
        0x8200,
        "AL130",
        "EEPROM invalid address range (e.g. data of an older firmware version)",
    ),
    fault(
        0x0131,
        0x8200,
        "AL131",
        "EEPROM checksum error; all CANopen objects return to their defaults",
    ),
    fault(
        0x0132,
        0x8200,
        "AL132",
        "Password error / EEPROM zone error: the parameter is password protected",
    ),
    fault(
        0x0170,
        0x8130,
        "AL170",
        "Node guarding or heartbeat error (Servo On)",
    ),
    fault(
        0x0180,
        0x8130,
        "AL180",
        "Node guarding or heartbeat error (Servo Off)",
    ),
    warning(
        0x0185,
        0x8120,
        "AL185",
        "CANbus error (Warning): bus off or Tx error counter exceeds 128",
    ),
    fault(
        0x0186,
        0x8100,
        "AL186",
        "CANbus error (Bus-Off): Tx error counter exceeds 255",
    ),
    fault(
        0x0201,
        0x6310,
        "AL201",
        "CANopen load/save 1010/1011 error (CANopen data initial error); clear with P2-08 = 10",
    ),
    fault(0x0283, 0x5444, "AL283", "Forward software limit"),
    fault(0x0285, 0x5445, "AL285", "Reverse software limit"),
    fault(0x0301, 0x6200, "AL301", "CANopen SYNC failed (Servo On)"),
    fault(
        0x0302,
        0x6200,
        "AL302",
        "CANopen SYNC signal error (Servo On): SYNC received too early",
    ),
    fault(0x0303, 0x6200, "AL303", "CANopen SYNC time out (Servo On)"),
    fault(
        0x0304,
        0x6200,
        "AL304",
        "CANopen IP command failed (Servo On)",
    ),
    fault(
        0x0305,
        0x6200,
        "AL305",
        "SYNC period error (Servo On): 1006h value invalid",
    ),
    fault(0x03E1, 0x6200, "AL3E1", "CANopen SYNC failed (Servo Off)"),
    fault(
        0x03E2,
        0x6200,
        "AL3E2",
        "CANopen SYNC signal error (Servo Off): SYNC received too early",
    ),
    fault(0x03E3, 0x6200, "AL3E3", "CANopen SYNC time out (Servo Off)"),
    fault(
        0x03E4,
        0x6200,
        "AL3E4",
        "CANopen IP command failed (Servo Off)",
    ),
    fault(
        0x03E5,
        0x6200,
        "AL3E5",
        "SYNC period error (Servo Off): 1006h value invalid",
    ),
    fault(
        0x0401,
        0x8100,
        "AL401",
        "CANopen state error: NMT reset or NMT stop received while the drive is enabled",
    ),
];

// ================================================================================================
// PDO rules (§2.1.1, §3.2.2, §4.4 1400h–1A03h)
// ================================================================================================

/// Mapping objects 1600h–1603h / 1A00h–1A03h, "1~8: activated" entries each (§4.4); every PDO
/// may be valid at once; 8 bytes per PDO. CANopen has no 1C12h/1C13h: a PDO is switched on by
/// its COB-ID bit 31, so there is no assignment object to write.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: NAME,
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
    assignment_writable: false,
};

/// Transmission types: "time-trigger, event-trigger, sync cyclic and sync acyclic" (§2.1.1),
/// the sub-index 02h value range is UNSIGNED8 (§4.4). **MANUAL GAP**: RTR types 252/253 are
/// not mentioned; \[REC\] refused.
pub const TRANSMISSION_TYPES: TransmissionTypes = TransmissionTypes {
    sync_acyclic: true,
    sync_cyclic: true,
    rtr_sync: false,
    rtr_event: false,
    event_manufacturer: true,
    event_profile: true,
};

const fn pdo_default(number: u8, cob_id: u32) -> PdoDefault {
    PdoDefault {
        number,
        cob_id,
        transmission_type: 0,
        inhibit_time: 0,
        event_timer: 0,
        mapping: &[],
    }
}

/// Power-on RPDOs (§4.4 1400h–1403h, 1600h–1603h): COB-ID 200h/300h/400h/500h + node-ID with
/// bit 31 = 0, reception type 0, no mapping (sub 00h = 0, "deactivated").
pub const DEFAULT_RPDOS: &[PdoDefault] = &[
    pdo_default(1, 0x200),
    pdo_default(2, 0x300),
    pdo_default(3, 0x400),
    pdo_default(4, 0x500),
];

/// Power-on TPDOs (§4.4 1800h–1803h, 1A00h–1A03h): COB-ID 180h/280h/380h/480h + node-ID,
/// transmission type 0, inhibit time 0, event timer 0, no mapping.
pub const DEFAULT_TPDOS: &[PdoDefault] = &[
    pdo_default(1, 0x180),
    pdo_default(2, 0x280),
    pdo_default(3, 0x380),
    pdo_default(4, 0x480),
];

/// The PDO rules: sub-indices 00h–05h in both communication records (sub 04h "compatibility
/// entry" / "reserved" exists on this drive, §4.4).
pub const PDO: CanPdoProfile = CanPdoProfile {
    limits: PDO_LIMITS,
    max_pdo_bytes: 8,
    rpdo_types: TRANSMISSION_TYPES,
    tpdo_types: TRANSMISSION_TYPES,
    rpdo_comm_subs: 5,
    default_rpdos: DEFAULT_RPDOS,
    default_tpdos: DEFAULT_TPDOS,
};

// ================================================================================================
// The object dictionary (§4.2, §4.3, §4.4, §2.2.2)
// ================================================================================================

/// A VAR object, optionally with the range the manual states.
macro_rules! var {
    ($index:expr, $name:literal, $dt:expr, $acc:expr, $def:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[e(0, $name, $dt, $acc, $def)],
        }
    };
    ($index:expr, $name:literal, $dt:expr, $acc:expr, $def:expr, $min:expr, $max:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[e(0, $name, $dt, $acc, $def).range($min, $max)],
        }
    };
}

/// 1003h (§4.4): sub 00h "number of errors" rw, 0–5 (writing 0 clears); subs 01h–05h ro.
static ERROR_FIELD: [EntryDesc; 6] = [
    e(0, "number of errors", U8, RW, u(0)).range(u(0), u(5)),
    e(1, "standard error field", U32, RO, u(0)),
    e(2, "standard error field", U32, RO, u(0)),
    e(3, "standard error field", U32, RO, u(0)),
    e(4, "standard error field", U32, RO, u(0)),
    e(5, "standard error field", U32, RO, u(0)),
];

/// 1010h (§4.4): one sub-index, "save all", reads 1; write [`STORE_SIGNATURE`].
static STORE: [EntryDesc; 2] = [
    e(0, "largest sub-index supported", U8, RO, u(1)),
    e(1, "save all default parameters", U32, RW, u(1)),
];

/// 1011h (§4.4): one sub-index, "restore all", reads 1; write [`RESTORE_SIGNATURE`].
static RESTORE: [EntryDesc; 2] = [
    e(0, "largest sub-index supported", U8, RO, u(1)),
    e(1, "restore all default parameters", U32, RW, u(1)),
];

/// 1016h (§4.4): one consumer, bits 0–15 time (ms), 16–23 node-ID, 24–31 00h.
static CONSUMER_HEARTBEAT: [EntryDesc; 2] = [
    e(0, "number entries", U8, RO, u(1)),
    e(1, "Consumer Heartbeat Time", U32, RW, u(0)),
];

/// 1018h (§4.4): three entries, no serial number.
static IDENTITY: [EntryDesc; 4] = [
    e(0, "number of entries", U8, RO, u(3)),
    e(1, "Vendor ID", U32, RO, u(VENDOR_ID as u64)),
    e(2, "Product code", U32, RO, u(PRODUCT_CODE_A2 as u64)),
    e(3, "Revision number", U32, RO, u(REVISION as u64)),
];

/// 1029h (§4.4): communication error → 0 Pre-operational (only from Operational), 1 no state
/// change, 2 Stopped.
static ERROR_BEHAVIOR: [EntryDesc; 2] = [
    e(0, "No. of Error Classes", U8, RO, u(1)),
    e(1, "Communication Error", U8, RW, u(0)),
];

/// 1200h (§4.4): both COB-IDs read-only, written for node-ID 0.
static SERVER_SDO: [EntryDesc; 3] = [
    e(0, "number of entries", U8, RO, u(2)),
    e(1, "COB-ID Client->Server (rx)", U32, RO, u(0x600)),
    e(2, "COB-ID Server->Client (tx)", U32, RO, u(0x580)),
];

/// An RPDO communication record (§4.4 1400h–1403h): subs 00h–05h, all defaults 0 except the
/// COB-ID; 03h and 05h exist but are "not used for RPDO".
const fn rpdo_comm(cob_id: u32) -> [EntryDesc; 6] {
    [
        e(0, "largest sub-index supported", U8, RO, u(5)),
        e(1, "COB-ID used by PDO", U32, RW, u(cob_id as u64)),
        e(2, "Reception type", U8, RW, u(0)),
        e(3, "inhibit time (not used for RPDO)", U16, RW, u(0)),
        e(4, "compatibility entry", U8, RW, u(0)),
        e(5, "event timer (not used for RPDO)", U16, RW, u(0)),
    ]
}

/// A TPDO communication record (§4.4 1800h–1803h): subs 00h–05h, 04h reserved.
const fn tpdo_comm(cob_id: u32) -> [EntryDesc; 6] {
    [
        e(0, "largest sub-index supported", U8, RO, u(5)),
        e(1, "COB-ID used by PDO", U32, RW, u(cob_id as u64)),
        e(2, "Transmission type", U8, RW, u(0)),
        e(3, "inhibit time", U16, RW, u(0)),
        e(4, "reserved", U8, RW, u(0)),
        e(5, "event timer", U16, RW, u(0)),
    ]
}

static RPDO1_COMM: [EntryDesc; 6] = rpdo_comm(0x200);
static RPDO2_COMM: [EntryDesc; 6] = rpdo_comm(0x300);
static RPDO3_COMM: [EntryDesc; 6] = rpdo_comm(0x400);
static RPDO4_COMM: [EntryDesc; 6] = rpdo_comm(0x500);
static TPDO1_COMM: [EntryDesc; 6] = tpdo_comm(0x180);
static TPDO2_COMM: [EntryDesc; 6] = tpdo_comm(0x280);
static TPDO3_COMM: [EntryDesc; 6] = tpdo_comm(0x380);
static TPDO4_COMM: [EntryDesc; 6] = tpdo_comm(0x480);

/// A mapping record (§4.4 1600h–1603h, 1A00h–1A03h): sub 00h 0–8 (default 0), subs 01h–08h
/// default 0.
static PDO_MAP_EMPTY: [EntryDesc; 9] = pdo_map::<9>(&[]);

/// 607Dh software position limit (§4.3: ARRAY, INTEGER32, rw, mappable). **MANUAL GAP**: no
/// detail page; \[REC\] the CiA 402 layout (01h min, 02h max) with the type's extremes (no
/// limit).
static SOFTWARE_POSITION_LIMIT: [EntryDesc; 3] = [
    e(0, "Number of entries", U8, RO, u(2)),
    e(1, "Min position limit", I32, RW_RT, i(i32::MIN as i64)),
    e(2, "Max position limit", I32, RW_RT, i(i32::MAX as i64)),
];

/// 6093h (§4.4): numerator (= P1-44) / feed constant (= P1-45), 1:1 at power-on (P3-12 Z = 0
/// reloads it, §2.2.2).
static POSITION_FACTOR: [EntryDesc; 3] = [
    e(0, "Number of entries", U8, RO, u(2)),
    e(1, "Numerator", U32, RW_RT, u(1)),
    e(2, "Feed_constant", U32, RW_RT, u(1)),
];

/// 6099h (§4.4): with P1-01 = 0x0C in 0.1 rpm; the manual's ranges 1–2000 rpm and 1–500 rpm
/// as 0.1 rpm values (see DISCREPANCY).
static HOMING_SPEEDS: [EntryDesc; 3] = [
    e(0, "Number of entries", U8, RO, u(2)),
    e(1, "Speed during search for switch", U32, RW_RT, u(100)).range(u(10), u(20_000)),
    e(2, "Speed during search for zero", U32, RW_RT, u(20)).range(u(10), u(5_000)),
];

/// 60C1h with P1-01 = 0x0C (§4.4): 01h 32-bit position command (PUU), 02h symmetrical
/// difference ΔXi = (Xi+1 − Xi−1)/2 (PUU), needed only for 60C0h = −1.
static INTERPOLATION_DATA: [EntryDesc; 3] = [
    e(0, "Number of entries", U8, RO, u(2)),
    e(1, "Pos_Cmd", I32, RW_RT, i(0)),
    e(2, "Velocity - Pos_Cmd difference", I16, RW_RT, i(0)),
];

/// 60C2h (§4.4, §3.2.2): units 1–20 (ms with index −3), index always −3.
static INTERPOLATION_PERIOD: [EntryDesc; 3] = [
    e(0, "Number of entries", U8, RO, u(2)),
    e(1, "Interpolation time units", U8, RW_RT, u(1)).range(u(1), u(20)),
    e(2, "Interpolation time index", I8, RW_RT, i(-3)).range(i(-128), i(63)),
];

/// \[REC\] P1-55 maximum speed, rpm (**MANUAL GAP**: the manual uses P1-55 as the default of
/// 607Fh/6080h without giving its value).
pub const MAX_SPEED_RPM: u32 = 3000;

/// The object dictionary at power-on, sorted by index. Access: "RW" + mappable → `RW_RT`,
/// "RO" + mappable → `RO_T` (the manual does not restrict the direction). Objects whose value
/// is measured have no default in the manual; they start at 0 (\[REC\]).
pub static DICTIONARY: &[ObjectDesc] = &[
    // ---- 1000h group (§4.2, §4.4); "only 1001h could be mapped to PDO" (§4.2).
    var!(0x1000, "device type", U32, RO, u(DEVICE_TYPE_A2 as u64)),
    var!(0x1001, "error register", U8, RO_T, u(0)),
    ObjectDesc {
        index: 0x1003,
        name: "pre-defined error field",
        code: ObjectCode::Array,
        entries: &ERROR_FIELD,
    },
    var!(0x1005, "COB-ID SYNC message", U32, RW, u(0x80)),
    var!(0x1006, "communication cycle period", U32, RW, u(0)),
    var!(0x100C, "guard time", U16, RW, u(0)),
    var!(0x100D, "life time factor", U8, RW, u(0)),
    ObjectDesc {
        index: 0x1010,
        name: "store parameters",
        code: ObjectCode::Array,
        entries: &STORE,
    },
    ObjectDesc {
        index: 0x1011,
        name: "restore default parameters",
        code: ObjectCode::Array,
        entries: &RESTORE,
    },
    // Written for node-ID 0: the node adds its ID (80h + node-ID, §4.4).
    var!(0x1014, "COB-ID Emergency message", U32, RO, u(0x80)),
    ObjectDesc {
        index: 0x1016,
        name: "Consumer Heartbeat Time",
        code: ObjectCode::Array,
        entries: &CONSUMER_HEARTBEAT,
    },
    var!(0x1017, "Producer Heartbeat Time", U16, RW, u(0)),
    ObjectDesc {
        index: 0x1018,
        name: "Identity Object",
        code: ObjectCode::Record,
        entries: &IDENTITY,
    },
    ObjectDesc {
        index: 0x1029,
        name: "Error Behavior",
        code: ObjectCode::Array,
        entries: &ERROR_BEHAVIOR,
    },
    ObjectDesc {
        index: 0x1200,
        name: "Server SDO parameter",
        code: ObjectCode::Record,
        entries: &SERVER_SDO,
    },
    ObjectDesc {
        index: 0x1400,
        name: "Receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO1_COMM,
    },
    ObjectDesc {
        index: 0x1401,
        name: "Receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO2_COMM,
    },
    ObjectDesc {
        index: 0x1402,
        name: "Receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO3_COMM,
    },
    ObjectDesc {
        index: 0x1403,
        name: "Receive PDO parameter",
        code: ObjectCode::Record,
        entries: &RPDO4_COMM,
    },
    ObjectDesc {
        index: 0x1600,
        name: "Receive PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1601,
        name: "Receive PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1602,
        name: "Receive PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1603,
        name: "Receive PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1800,
        name: "transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO1_COMM,
    },
    ObjectDesc {
        index: 0x1801,
        name: "transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO2_COMM,
    },
    ObjectDesc {
        index: 0x1802,
        name: "transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO3_COMM,
    },
    ObjectDesc {
        index: 0x1803,
        name: "transmit PDO parameter",
        code: ObjectCode::Record,
        entries: &TPDO4_COMM,
    },
    ObjectDesc {
        index: 0x1A00,
        name: "Transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1A01,
        name: "Transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1A02,
        name: "Transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    ObjectDesc {
        index: 0x1A03,
        name: "Transmit PDO mapping",
        code: ObjectCode::Record,
        entries: &PDO_MAP_EMPTY,
    },
    // ---- Delta parameters 2xxxh (§4.4 "Object 2xxxh": VAR, INTEGER16/INTEGER32, RW, PDO
    // mappable, default = the parameter's). Sizes: "Data Size: 16-bit" where §2.2.2 says so,
    // P1-44 INTEGER32 (§4.4 example 2); the others are a MANUAL GAP (see the end).
    // P1-01 "Control Mode and Output Direction", range 00–110F (§2.2.2). Factory default 0;
    // [REC] 0x000C here: a node that talks CANopen has P1-01 = 0x0B or 0x0C, and the emulator
    // models 0x0C ("full", recommended, §2.2.1).
    var!(
        P1_01,
        "Control Mode and Output Direction",
        I16,
        RW_RT,
        i(P1_01_CANOPEN_FULL as i64),
        i(0x0000),
        i(0x110F)
    ),
    // P1-32 stop mode: Y = 0 dynamic brake (605Bh = −1), Y = 1 no dynamic brake (605Bh = 0)
    // (§2.2.2 P3-12 table). MANUAL GAP default: [REC] 0x0010 to agree with 605Bh = 0.
    var!(P1_32, "Motor stop mode (605Bh)", I16, RW_RT, i(0x0010)),
    // P1-34, P1-38, P1-47, P1-49: defaults from the P3-12 table (§2.2.2).
    var!(
        P1_34,
        "Acceleration time (6083h/6084h/6087h)",
        I16,
        RW_RT,
        i(200)
    ),
    var!(P1_38, "Zero speed range (606Fh)", I16, RW_RT, i(100)),
    // P1-44 / P1-45: factory 128:10 (§2.2.2 P3-12 table); 6093h is 1:1 at power-on.
    var!(P1_44, "Electronic Gear", I32, RW_RT, i(128)),
    var!(
        P1_45,
        "Electronic gear denominator (6093h:02)",
        I32,
        RW_RT,
        i(10)
    ),
    var!(P1_47, "Speed reached range (606Dh), rpm", I16, RW_RT, i(10)),
    var!(P1_49, "Velocity window time (606Eh)", I16, RW_RT, i(0)),
    var!(
        P1_55,
        "Maximum speed limit (607Fh/6080h), rpm",
        I16,
        RW_RT,
        i(MAX_SPEED_RPM as i64)
    ),
    // P2-08: 10 (or 30 and 28 after a firmware upgrade) clears AL201 (§5.1); [REC] default 0.
    var!(
        P2_08,
        "Special parameter write (clears AL201)",
        I16,
        RW_RT,
        i(0)
    ),
    // P2-35: 3840000 (§2.2.2 P3-12 table) does not fit 16 bits: INTEGER32.
    var!(
        P2_35,
        "Excessive deviation (6065h)",
        I32,
        RW_RT,
        i(3_840_000)
    ),
    var!(P3_00, "Node-ID", I16, RW_RT, i(0x7F), i(0x01), i(0x7F)),
    var!(
        P3_01,
        "Transmission Speed",
        I16,
        RW_RT,
        i(P3_01_DEFAULT as i64),
        i(0x0000),
        i(0x0405)
    ),
    // P3-09 digits E T D M (E 1–9, T 0–9, D 0–F, M 1–F); no numeric range given.
    var!(
        P3_09,
        "CANopen Synchronization Setting",
        I16,
        RW_RT,
        i(P3_09_DEFAULT as i64)
    ),
    // P3-10: X DS402 version (0 partial, 1 complete), Y CAN bus error → 0 free run, 1 servo off.
    var!(P3_10, "CANopen Protocol Setting", I16, RW_RT, i(0)),
    // P3-11: X = 1 saves parameters written by PDO in EEPROM (A2-M/-F only).
    var!(P3_11, "CANopen saving options", I16, RW_RT, i(0)),
    // P3-12: X servo-on rule, Y quick stop on auto protection, Z reload of CANopen objects at
    // power-on; "0x0000 ~ 0x0111" (given in the Unit row).
    var!(
        P3_12,
        "CANopen Quick Stop Settings",
        I16,
        RW_RT,
        i(0),
        i(0x0000),
        i(0x0111)
    ),
    // ---- 6000h group (§4.3, §4.4).
    var!(0x603F, "Error code", U16, RO_T, u(0)),
    // Default 0x0004 with P1-01 = 0x0C (0x0000 with 0x0B).
    var!(0x6040, "Controlword", U16, RW_RT, u(0x0004)),
    var!(0x6041, "Statusword", U16, RO_T, u(0)),
    // 0 disable drive function, −1 dynamic brake enable; not mappable (§4.3).
    var!(0x605B, "Shutdown option code", I16, RW, i(0)),
    // 0 disable drive (free), 1 slow-down ramp, 2 quick-stop ramp; not mappable (§4.3).
    var!(0x605E, "Fault reaction option code", I16, RW, i(2)),
    // 0 reserved, 1 pp, 3 pv, 4 tq, 6 hm, 7 ip.
    var!(0x6060, "Modes of operation", I8, RW_RT, i(0)),
    var!(0x6061, "Modes of operation display", I8, RO_T, i(0)),
    var!(0x6062, "Position demand value", I32, RO_T, i(0)),
    var!(0x6063, "Position actual value*", I32, RO_T, i(0)),
    var!(0x6064, "Position actual value", I32, RO_T, i(0)),
    var!(0x6065, "Following error window", U32, RW_RT, u(3_840_000)),
    var!(0x6067, "Position window", U32, RW_RT, u(100)),
    var!(0x6068, "Position window time", U16, RW_RT, u(0)),
    var!(0x606B, "Velocity demand value", I32, RO_T, i(0)),
    var!(0x606C, "Velocity actual value", I32, RO_T, i(0)),
    var!(0x606D, "Velocity window", U16, RW_RT, u(100), u(0), u(3000)),
    var!(0x606E, "Velocity window time", U16, RW_RT, u(0)),
    var!(
        0x606F,
        "Velocity threshold",
        U16,
        RW_RT,
        u(100),
        u(0),
        u(2000)
    ),
    var!(0x6071, "Target torque", I16, RW_RT, i(0), i(-3000), i(3000)),
    var!(0x6074, "Torque demand value", I16, RO_T, i(0)),
    // MANUAL GAP: motor data; [REC] a 400 W class motor, 2.6 A.
    var!(0x6075, "Motor rated current", U32, RO_T, u(2600)),
    // Unit "per thousand of rate torque" (§4.4): the rated torque is 1000 of it ([REC]).
    var!(0x6076, "Motor rated torque", U32, RO_T, u(1000)),
    var!(0x6077, "Torque actual value", I16, RO_T, i(0)),
    var!(0x6078, "Current actual value", I16, RO_T, i(0)),
    var!(0x607A, "Target position", I32, RW_RT, i(0)),
    var!(0x607C, "Home offset", I32, RW_RT, i(0)),
    ObjectDesc {
        index: 0x607D,
        name: "Software position limit",
        code: ObjectCode::Array,
        entries: &SOFTWARE_POSITION_LIMIT,
    },
    // P1-55 (rpm) × 10, in 0.1 rpm.
    var!(
        0x607F,
        "Max profile velocity",
        U32,
        RW_RT,
        u(MAX_SPEED_RPM as u64 * 10)
    ),
    var!(
        0x6080,
        "Max motor speed",
        U32,
        RW_RT,
        u(MAX_SPEED_RPM as u64)
    ),
    // PUU/s.
    var!(0x6081, "Profile velocity", U32, RW_RT, u(10_000)),
    // ms from 0 to 3000 rpm, 1–UNSIGNED32.
    var!(
        0x6083,
        "Profile acceleration",
        U32,
        RW_RT,
        u(200),
        u(1),
        u(u32::MAX as u64)
    ),
    var!(
        0x6084,
        "Profile deceleration",
        U32,
        RW_RT,
        u(200),
        u(1),
        u(u32::MAX as u64)
    ),
    var!(0x6085, "Quick stop deceleration", U32, RW_RT, u(0)),
    var!(0x6086, "Motion profile type", I16, RW_RT, i(0)),
    // ms from 0 to 100 % rated torque; default 0 per §4.4 (the P3-12 table says 200).
    var!(0x6087, "Torque slope", U32, RW_RT, u(0)),
    ObjectDesc {
        index: 0x6093,
        name: "Position factor",
        code: ObjectCode::Array,
        entries: &POSITION_FACTOR,
    },
    var!(0x6098, "Homing method", I8, RW_RT, i(0), i(0), i(35)),
    ObjectDesc {
        index: 0x6099,
        name: "Homing speeds",
        code: ObjectCode::Array,
        entries: &HOMING_SPEEDS,
    },
    // ms from 0 to 3000 rpm.
    var!(0x609A, "Homing acceleration", U32, RW_RT, u(100)),
    // 60B0h–60B2h: "Not implement yet." (§4.4).
    var!(0x60B0, "Position offset", I32, RW_RT, i(0)),
    var!(0x60B1, "Velocity offset", I32, RW_RT, i(0)),
    var!(0x60B2, "Torque offset", I16, RW_RT, i(0)),
    // P1-01 = 0x0C: 0 linear (no difference), −1 Delta definition (difference in 60C1h:02).
    var!(0x60C0, "Interpolation sub mode select", I16, RW_RT, i(0)),
    ObjectDesc {
        index: 0x60C1,
        name: "Interpolation data record",
        code: ObjectCode::Array,
        entries: &INTERPOLATION_DATA,
    },
    ObjectDesc {
        index: 0x60C2,
        name: "Interpolation time period",
        code: ObjectCode::Record,
        entries: &INTERPOLATION_PERIOD,
    },
    var!(0x60C5, "Max acceleration", U32, RW_RT, u(200)),
    var!(0x60C6, "Max deceleration", U32, RW_RT, u(200)),
    var!(0x60F2, "Positioning option code", U16, RW_RT, u(0)),
    var!(0x60F4, "Following error actual value", I32, RO_T, i(0)),
    var!(0x60FC, "Position demand value*", I32, RO_T, i(0)),
    var!(0x60FD, "Digital inputs", U32, RO_T, u(0)),
    // 0.1 rpm; no default given ([REC] 0).
    var!(0x60FF, "Target velocity", I32, RW_RT, i(0)),
    var!(
        0x6502,
        "Supported drive modes",
        U32,
        RO_T,
        u(SUPPORTED_MODES as u64)
    ),
];

// ================================================================================================
// Units of the motor model (§3.1.1, §3.1.2, §3.3.2, §3.4.2, §3.5.2, §4.4)
// ================================================================================================

/// Position in PUU: PUU/rev = 1 280 000 × 6093h:02 / 6093h:01 (§3.1.1), 1 280 000 with the
/// power-on 6093h = 1:1 (§2.2.2, §4.4). Velocity 60FFh/606Ch in 0.1 rpm, 6081h in PUU/s;
/// torque in ‰ of rated torque; 6083h/6084h/6085h/609Ah as ms from 0 to 3000 rpm; 6087h as
/// ms from 0 to 100 % rated torque; 6099h in 0.1 rpm with P1-01 = 0x0C.
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

// ================================================================================================
// Homing (§3.3, §4.4 6098h)
// ================================================================================================

/// 6098h value range 0–35 (§4.4); 15, 16, 31, 32 are "Reserved" and left out; 0 (the
/// default, no homing) is accepted.
pub const HOMING_METHODS: &[i8] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27,
    28, 29, 30, 33, 34, 35,
];

/// Homing: methods 1–14 and 33–34 use the encoder's index pulse, which a servo motor has.
pub const HOMING: HomingSupport = HomingSupport {
    methods: HOMING_METHODS,
    default_method: 0,
    index_pulse: true,
};

// ================================================================================================
// EMCY, communication, NMT (§2.1, §4.4, §5.1)
// ================================================================================================

/// EMCY: bytes 0–1 error code, byte 2 1001h, bytes 3–4 the panel alarm code, 5–7 unused
/// (§5.1); 1003h entries = alarm << 16 | code (§4.4 1003h example).
pub const EMCY: EmcyFormat = EmcyFormat::AlarmInBytes3To4;

/// Error control and rate limits: node guarding and heartbeat (§2.1.1, 100Ch/100Dh, 1016h
/// with one entry, 1017h); SYNC consumer only (the host sends SYNC, §3.2.1; **MANUAL GAP**
/// whether 1005h bit 30 is accepted, \[REC\] no); 1006h exists, "recommended" a multiple of
/// 1000 µs (§3.2.2, not enforced: \[REC\] 0); 1003h depth 5; 1010h/1011h sub 01h only; two SDOs
/// or two PDOs on one COB-ID within 1 ms raise AL111/AL112 (§5.1).
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

/// AL401 "NMT reset or NMT stop is received when drive is enabled" (§5.1).
pub const NMT_WHILE_ENABLED: EnabledNmtReaction = EnabledNmtReaction::Alarm(0x0401);

/// "After drive switch to servo-on, internal velocity command will be reset and OD-60FFh will
/// be cleared" (§3.4.2); likewise 6071h (§3.5.2).
pub static TARGETS_CLEARED_ON_ENABLE: [ObjectAddress; 2] =
    [ObjectAddress::new(0x60FF, 0), ObjectAddress::new(0x6071, 0)];

// ================================================================================================
// Quirks (the emulator's own table, copied from `quirks.rs`)
// ================================================================================================

/// What the node does beyond CiA 301/402.
pub const QUIRKS: EmulationQuirks = EmulationQuirks {
    // §5.3 lists 0609 0030h as the range code, not CiA 301's 0031h/0032h.
    range_abort_high_low: false,
    // §5.3 lists 0607 0010h for a wrong length, not 0607 0012h/0013h.
    length_abort_high_low: false,
    // P3-12 (230Ch) digit X = 0: "enable operation" alone switches on (§2.2.2).
    bit3_enable: Some(Bit3Enable {
        addr: ObjectAddress::new(P3_12, 0),
        mask: 0x000F,
        value: 0,
    }),
    // AL111: SDO requests too close together; AL112: RPDO frames too close together; AL123:
    // RPDO length error; AL170: guarding/heartbeat lost while servo on (§5.1).
    sdo_overrun_alarm: Some(0x0111),
    rpdo_overrun_alarm: Some(0x0112),
    pdo_length_alarm: Some(0x0123),
    guarding_alarm: Some(0x0170),
    // §3.2, §4.4 6040h (bit 4 "N/A" in IP): interpolation runs whenever mode 7 is active.
    ip_needs_enable_bit: false,
    ..EmulationQuirks::NONE
};

// ================================================================================================
// The spec
// ================================================================================================

/// The emulated ASDA-A2 (A2 series identity, P1-01 = 0x0C).
pub const SPEC: NodeSpec = NodeSpec {
    name: NAME,
    vendor: VENDOR,
    source: SOURCE,
    dictionary: DICTIONARY,
    caps: CAPS,
    units: UNITS,
    pdo: PDO,
    homing: HOMING,
    emcy: EMCY,
    alarms: ALARMS,
    comm: COMM,
    nmt_stop_while_enabled: NMT_WHILE_ENABLED,
    nmt_reset_while_enabled: NMT_WHILE_ENABLED,
    targets_cleared_on_enable: &TARGETS_CLEARED_ON_ENABLE,
    quirks: QUIRKS,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dictionary_is_sorted_and_unique() {
        for w in DICTIONARY.windows(2) {
            assert!(
                w[0].index < w[1].index,
                "0x{:04X} before 0x{:04X}",
                w[0].index,
                w[1].index
            );
        }
    }

    #[test]
    fn alarm_numbers_are_unique() {
        for (k, a) in ALARMS.iter().enumerate() {
            assert!(
                ALARMS[k + 1..].iter().all(|b| b.number != a.number),
                "{}",
                a.name
            );
        }
    }

    #[test]
    fn parameter_indices() {
        assert_eq!(P3_00, 0x2300);
        assert_eq!(P1_44, 0x212C);
        assert_eq!(P3_12, 0x230C);
    }
}

// ================================================================================================
// MANUAL GAP / [REC] / DISCREPANCY
// ================================================================================================
//
// MANUAL GAP — values the manual does not state, with the emulator's choice ([REC]):
// - 1018h:03 revision number: "N/A" (§4.4); [REC] 0.
// - P1-01 power-on value: the factory default is 0 (§2.2.2), which is not a CANopen mode; a
//   node on the bus has 0x0B or 0x0C. [REC] 0x000C, the recommended "full" mode (§2.2.1), and
//   everything mode-dependent follows it: 6040h default 0x0004, 60C1h layout (sub 00h = 2,
//   01h INTEGER32, 02h INTEGER16), 60C2h as the ip period, 6099h in 0.1 rpm. The 0x0B variants
//   (60C1h 01h/02h as UNSIGNED16 words + 03h difference, 1006h as the ip period, 60C0h −2,
//   6099h in rpm, 0x000F switching on at once) are not modelled.
// - P1-32 default: not given; [REC] 0x0010 (Y = 1, no dynamic brake) so that it agrees with
//   605Bh = 0 (§2.2.2 P3-12 table links P1-32.Y and 605Bh).
// - P1-55 default (source of 607Fh = P1-55 × 10 and 6080h = P1-55): not given; [REC] 3000 rpm.
// - Data sizes of P1-32, P1-34, P1-38, P1-47, P1-49, P1-55, P2-08: not given; [REC]
//   INTEGER16. P1-45: [REC] INTEGER32 like its partner P1-44. P2-35: INTEGER32 (its default
//   3 840 000 needs it).
// - P2-08 default and range: not given; [REC] 0, no range. P3-09, P3-10, P3-11: ranges given
//   only per digit; no numeric range set.
// - Other parameters named in passing are left out: P2-10…P2-22 (digital I/O, reset by P1-01
//   digit C; no defaults given).
// - 6075h motor rated current, 6076h motor rated torque: motor data, not given; [REC] 2600 mA
//   and 1000 (the manual's unit is "per thousand of rated torque").
// - 607Dh software position limit: ARRAY in §4.3 without a detail page; [REC] CiA 402 layout
//   01h min / 02h max, defaults i32::MIN / i32::MAX (no limit).
// - Defaults of 606Bh, 606Ch, 6074h, 6077h, 6078h, 60F4h, 60FCh, 60FDh, 60FFh: not given;
//   [REC] 0.
// - Units of 60C5h/60C6h max acceleration/deceleration: not given (default 200 is in the
//   manual; presumably ms 0→3000 rpm like 6083h).
// - Quick stop (no 605Ah): the ramp is 6085h (§4.4) but the state after the stop is not
//   stated; [REC] code 2 behaviour (6085h ramp, then Switch on disabled); transition 16 [REC]
//   not supported. 6085h default 0 ms makes the quick stop immediate.
// - Error register per alarm: not given; [REC] by code class (see `register_for`).
// - Fault vs warning: only AL023 and AL185 are called warnings; [REC] all others faults.
// - Reserved alarms AL010 (0000-0010h) and AL021 ("Reserved") are left out of the table: a
//   code of 0000h would read as "error reset".
// - RPDO/TPDO RTR transmission types 252/253: not mentioned (§2.1.1 lists time-trigger,
//   event-trigger, sync cyclic, sync acyclic); [REC] refused.
// - 1005h bit 30 (SYNC producer): not mentioned, the host produces SYNC (§3.2.1); [REC] no.
// - 1006h granularity: "recommended ... a multiple of 1000 microsecond" (§3.2.2), not a rule;
//   [REC] any value accepted. What makes 1006h "invalid" for AL305 is not stated.
// - 1017h unit: not stated (CiA 301: ms). Boot-up message: not described (CiA 301 assumed).
// - Homing: whether writing the reserved methods 15, 16, 31, 32 to 6098h is refused is not
//   stated; [REC] refused (they are outside `HOMING_METHODS`).
// - 1008h–100Ah (name / version strings): not in the object list (§4.2), so no 1009h/100Ah
//   contents or examples exist to hold.
// - P3-01 "via CANopen only Z can be changed" (§2.2.2) and P1-01 "●" (effective after power
//   cycle) are not modelled as write rules.
//
// DISCREPANCY — where the manual contradicts itself, and the reading used:
// - 6061h access: RO in §4.3 and in §3.1.4/§3.2.3/§3.3.3/§3.4.4/§3.5.4, RW in §4.4. Used RO
//   (a display object; four tables against one).
// - 606Dh: UNSIGNED16 RW in §4.3 and §3.4.4, INTEGER16 RO in §4.4 (range 0–3000, default 100
//   agree). Used UNSIGNED16 RW (§3.4.3 tells the host to "Set" it).
// - 6077h type: UNSIGNED16 in §4.3, INTEGER16 in §4.4 and §3.5.4. Used INTEGER16 (a signed
//   torque).
// - 605Bh / 605Eh PDO mapping: "N" in §4.3, "Yes" in §4.4. Used not mappable (§4.3, the table
//   that lists mappability as such; CiA 402 does not map them either).
// - 6087h default: 0 in §4.4, 200 in the P3-12 table (§2.2.2, linked to P1-34). Used 0 (the
//   object's own page); every other object of the P3-12 table agrees with its §4.4 page.
// - 6093h default 1:1 (§4.4 and P3-12 table) vs "Same as P1-44 / P1-45" whose factory values
//   are 128:10 (P3-12 table). Used 6093h = 1:1 (P3-12 Z = 0, the default, reloads it at power
//   on) and 212Ch/212Dh = 128/10 (their own stated defaults); the emulator does not link them.
//   Position units per revolution follow 6093h: 1 280 000.
// - 605Bh default 0 = "disable drive function" vs P1-32.Y = 0 ↔ 605Bh = −1 (P3-12 table).
//   Used 605Bh = 0 and P1-32 = 0x0010 (see MANUAL GAP).
// - 6099h ranges "1~2000rpm" / "1~500rpm" and §3.3.2 "(unit: rpm)" vs the 6099h comment
//   "P1-01 = 0x0C, Unit: 0.1rpm". Used 0.1 rpm (the modelled mode) with the ranges converted
//   to 10–20 000 and 10–5 000 (the rpm the manual names); defaults 100 and 20 kept as raw
//   values (10 rpm and 2 rpm). tests/manual_facts/open.toml lists the disagreement with the
//   facts, which keep the printed numbers.
// - Homing method range: "1~35" in §3.3.2, "0~35" in §4.4 6098h (default 0). Used 0–35.
// - P3-09 example: "300 + 10 x 5 = 450" (§2.2.2) — the formula gives 350. Used the formula
//   (SYNC_TARGET_BASE_US + 10 × T).
// - P3-12 digit X = 1: "When OD-6040 Bit2 (Quick Stop) = 1, then servo drive will go to Quick
//   Stop mode" (§2.2.2) vs 6040h bit 2 "Quick Stop (B-contact)", i.e. active low (§4.4). Used
//   the CiA 402 reading (bit 2 = 0 commands a quick stop).
// - P3-12 X = 1 "When all OD-6040 Bit0, Bit1, and Bit3 = 1, then execute servo on" (reads as
//   0x000F switching on from any state) vs the 6040h note for P1-01 = 0x0C "need to set 6040h
//   to 0x0006->0x0007->0x000F ... step by step". Used the step-by-step rule
//   (`state_skipping: false`).
// - P3-12 value range printed in the "Unit" row ("0x0000 ~ 0x0111"). Used as the range.
// - P3-00: digits Y 0–7 and X 0–F would allow 0x00, the range says 0x01–0x7F. Used 0x01–0x7F.
// - 1014h is RO, yet its page describes bit 31 as switching EMCY on and off. Used RO (EMCY
//   cannot be disabled or moved).
// - 1200h page names it "Server PDO parameter"; the object list says "1st Server SDO
//   parameter". Used "Server SDO parameter".
// - 6063h page heading "Position demand value", name "Position actual value*" (increments);
//   §3.1.2 step ⑦ calls 6064h "Statusword". Used the names (6063h actual value in increments,
//   6064h position actual value).
// - 6085h: object list "Quick stop deceleration", page "Quick stop acceleration". Used
//   deceleration.
// - 6099h sub 00h "PDO Mapping: Yes". Used RO, not mappable (a count).
// - 60C1h is an "ARRAY" whose entries have different types (INTEGER32 + INTEGER16 with
//   P1-01 = 0x0C; its header says UNSIGNED32 in the 0x0B variant and "UNSIGNED16/32" in
//   §4.3). Kept ObjectCode::Array with each entry's own type.
// - 60C2h: RECORD "SIGNED8" (§4.3) / "UNSIGNED8" (§4.4 header) with sub 01h UNSIGNED8 and
//   sub 02h INTEGER8. Used the per-entry types.
// - 60C2h:01 value range "UNSIGNED8" (§4.4) vs "The range is from 1ms to 20ms" (§3.2.2). Used
//   1–20.
// - AL132: "Password error" (§5.1) vs "EEPROM zone error" (§5.2). Text holds both.
// - AL201: "CANopen Data Initial Error" and "CANopen load/save 1010/1011 error" (§5.2 lists
//   AL201 twice, same code 6310-0201h). One alarm, text holds both.
// - 6076h unit "per thousand of rate torque" (CiA 402: mN·m). Kept the manual's unit.
// - 6083h/6084h comments say "For Profile position mode" but §3.4.2 uses them in pv too. Used
//   in both.
// - The 1016h bit table types the 16-bit heartbeat time and the node-ID as "UNSIGNED8". The
//   layout (bits 0–15 time, 16–23 node-ID) is used.
