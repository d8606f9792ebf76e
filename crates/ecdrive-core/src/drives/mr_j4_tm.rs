//! Mitsubishi MELSERVO MR-J4-_TM_ servo amplifier with the EtherCAT network module
//! (HMS ABCC-M40-ECT).
//!
//! Source: *MR-J4-_TM_ Servo Amplifier Instruction Manual (EtherCAT)*, SH(NA)030208ENG rev. A–E;
//! `§x.y` below cite its sections. Values the manual does not state are labelled **MANUAL GAP**
//! or **\[REC\]** (our choice) where they are declared; **DISCREPANCY** marks places where the
//! manual contradicts itself, with the reading used.
//!
//! Sections of this file:
//! - PDO mapping: limits, the power-on contents of every mapping object, the default assignment,
//!   the recommended cyclic mapping, and the objects each mode needs;
//! - CiA 402 behaviour: state skipping, the quick-stop option, the mode rules, the alarm table;
//! - synchronisation and cycle times; units;
//! - start-up: what the master writes by SDO and into the first cycle's outputs;
//! - the object dictionary ([`DICTIONARY`], in `mr_j4_tm/dictionary.rs`);
//! - the profile ([`PROFILE`]);
//! - **values that are ours**: every MANUAL GAP and \[REC\] value of this file, and the reading
//!   taken where the manual contradicts itself (DISCREPANCY), in one section at the end.

use super::profile::{
    CycleCounter, CycleTimeObject, CycleTimes, DriveProfile, IdentityMatch, ModeGroup,
    ModeSelector, OutputDefault, StartupSdo, StatusFlag, SyncSpec, Units,
};
use crate::cia402::VelocityUnit;
use crate::cia402::{DriveCaps, ErrorEntry, QuickStopOption, SupportedModes, VendorModeBit};
use crate::drives::profile::EtherCat;
use crate::od::ObjectAddress;
use crate::pdo::{DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange, RequiredObjects};

mod dictionary;
pub use dictionary::DICTIONARY;

// ============================================================================================
// PDO mapping (§1.3, §3.3, §3.4, §3.5, §7.3.2, §7.3.3)
// ============================================================================================

/// Mapping objects of the RxPDOs: four tables 0x1600–0x1603, each up to 32 entries
/// (§3.4; §7.3.2 sub 0 range 00h–20h).
const RX_RANGES: &[PdoRange] = &[PdoRange::new(0x1600, 0x1603, 32)];

/// Mapping objects of the TxPDOs: four tables 0x1A00–0x1A03, each up to 32 entries.
const TX_RANGES: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A03, 32)];

/// The PDO rules of the MR-J4-TM.
///
/// - Per direction at most 32 mapped objects and 64 bytes (§1.3, §3.4).
/// - Mapping and assignment are writable in PRE-OP only (§3.4 POINT; for the assignment the
///   PRE-OP restriction is DERIVED, not stated) and are not stored: they are back at the
///   defaults after every power-up, so the master writes them at every start.
/// - At most **1** PDO per SyncManager. DISCREPANCY: §7.3.3 gives 0x1C12/0x1C13 sub 0 the range
///   0–4 with four assignment entries, while §3.4 shows a read-only one-entry array and §1.3
///   says "RxPDO: 1 channel, TxPDO: 1 channel". \[REC\] assign exactly one PDO per direction.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "MR-J4-TM",
    rx: DirectionLimits {
        pdos: RX_RANGES,
        max_assigned: 1,
        max_entries: 32,
        max_bytes: 64,
    },
    tx: DirectionLimits {
        pdos: TX_RANGES,
        max_assigned: 1,
        max_entries: 32,
        max_bytes: 64,
    },
    assignment_writable: true,
};

// --- Power-on contents of the mapping objects ------------------------------------------------
//
// §3.3 lists the objects of each default table; only the first entry value of 0x1600 and 0x1A00
// is printed (60600008h / 60610008h). The entry values below are DERIVED as
// index << 16 | sub << 8 | bits with sub 0 and the bit length of each object's type (§7.3).
//
// DISCREPANCY (default entry counts): §3.4 gives 0x1600 = 12, 0x1601 = 16, 0x1602 = 10,
// 0x1603 = 0, 0x1A00 = 14, 0x1A01 = 19, 0x1A02 = 0x1A03 = 0; §7.3.2 gives 0x1600 = 8,
// 0x1A00 = 9 and 0 for the rest. The §3 counts match the listed objects and the stated map
// sizes (29 and 41 bytes) and are used here.

/// 0x1600, 1st RxPDO map (assigned at power-on): csp/csv/cst/hm with speed limit (cst), torque
/// limits and touch probe. 12 entries, 29 bytes.
///
/// Beware (§3.3 notes 1–2): 0x2D20 = 0 limits the speed to 0 and 0x60E0/0x60E1 = 0 produce no
/// torque, so a master using this map must send sensible values from the first cycle.
pub const RX_PDO_1600: Pdo = Pdo::fixed(
    0x1600,
    &[
        PdoEntry::new(0x6060, 0, 8),  // Modes of operation, I8
        PdoEntry::new(0x6040, 0, 16), // Controlword, U16
        PdoEntry::new(0x2D01, 0, 16), // Control DI 1, U16
        PdoEntry::new(0x2D02, 0, 16), // Control DI 2, U16
        PdoEntry::new(0x2D03, 0, 16), // Control DI 3, U16
        PdoEntry::new(0x607A, 0, 32), // Target position, I32
        PdoEntry::new(0x60FF, 0, 32), // Target velocity, I32
        // Velocity limit value: U32 per §7.3.7, I32 per §5.4.5 (DISCREPANCY); 32 bits either way.
        PdoEntry::new(0x2D20, 0, 32),
        PdoEntry::new(0x6071, 0, 16), // Target torque, I16
        PdoEntry::new(0x60E0, 0, 16), // Positive torque limit value, U16
        PdoEntry::new(0x60E1, 0, 16), // Negative torque limit value, U16
        PdoEntry::new(0x60B8, 0, 16), // Touch probe function, U16
    ],
);

/// 0x1601, 2nd RxPDO map: pp/pv/tq/hm. 16 entries, 45 bytes.
pub const RX_PDO_1601: Pdo = Pdo::fixed(
    0x1601,
    &[
        PdoEntry::new(0x6060, 0, 8),  // Modes of operation
        PdoEntry::new(0x6040, 0, 16), // Controlword
        PdoEntry::new(0x2D01, 0, 16), // Control DI 1
        PdoEntry::new(0x2D02, 0, 16), // Control DI 2
        PdoEntry::new(0x2D03, 0, 16), // Control DI 3
        PdoEntry::new(0x607A, 0, 32), // Target position
        PdoEntry::new(0x60FF, 0, 32), // Target velocity
        PdoEntry::new(0x2D20, 0, 32), // Velocity limit value
        PdoEntry::new(0x6071, 0, 16), // Target torque
        PdoEntry::new(0x6081, 0, 32), // Profile velocity, U32
        PdoEntry::new(0x6083, 0, 32), // Profile acceleration, U32
        PdoEntry::new(0x6084, 0, 32), // Profile deceleration, U32
        PdoEntry::new(0x6087, 0, 32), // Torque slope, U32
        PdoEntry::new(0x60E0, 0, 16), // Positive torque limit value
        PdoEntry::new(0x60E1, 0, 16), // Negative torque limit value
        PdoEntry::new(0x60B8, 0, 16), // Touch probe function
    ],
);

/// 0x1602, 3rd RxPDO map: pt/idx/jg/hm (software version B2 or later). 10 entries, 25 bytes.
pub const RX_PDO_1602: Pdo = Pdo::fixed(
    0x1602,
    &[
        PdoEntry::new(0x6060, 0, 8),  // Modes of operation
        PdoEntry::new(0x6040, 0, 16), // Controlword
        PdoEntry::new(0x2D01, 0, 16), // Control DI 1
        PdoEntry::new(0x2D02, 0, 16), // Control DI 2
        PdoEntry::new(0x2D03, 0, 16), // Control DI 3
        PdoEntry::new(0x2D60, 0, 16), // Target point table, I16 [B2+]
        PdoEntry::new(0x6081, 0, 32), // Profile velocity
        PdoEntry::new(0x6083, 0, 32), // Profile acceleration
        PdoEntry::new(0x6084, 0, 32), // Profile deceleration
        PdoEntry::new(0x60B8, 0, 16), // Touch probe function
    ],
);

/// 0x1603, 4th RxPDO map: empty at power-on.
pub const RX_PDO_1603: Pdo = Pdo::fixed(0x1603, &[]);

/// 0x1A00, 1st TxPDO map (assigned at power-on): csp/csv/cst/hm and pp/pv/tq/hm with touch-probe
/// latches. 14 entries, 41 bytes.
pub const TX_PDO_1A00: Pdo = Pdo::fixed(
    0x1A00,
    &[
        PdoEntry::new(0x6061, 0, 8),  // Modes of operation display, I8
        PdoEntry::new(0x6041, 0, 16), // Statusword, U16
        PdoEntry::new(0x2D11, 0, 16), // Status DO 1, U16
        PdoEntry::new(0x2D12, 0, 16), // Status DO 2, U16
        PdoEntry::new(0x2D13, 0, 16), // Status DO 3, U16
        PdoEntry::new(0x6064, 0, 32), // Position actual value, I32
        PdoEntry::new(0x606C, 0, 32), // Velocity actual value, I32
        PdoEntry::new(0x60F4, 0, 32), // Following error actual value, I32
        // Torque actual value: I16 per §7.3.11, I32 per the §5 tables (DISCREPANCY); 16 bits
        // gives the stated 41-byte map size.
        PdoEntry::new(0x6077, 0, 16),
        PdoEntry::new(0x60B9, 0, 16), // Touch probe status, U16
        PdoEntry::new(0x60BA, 0, 32), // Touch probe pos1 pos value, I32
        PdoEntry::new(0x60BB, 0, 32), // Touch probe pos1 neg value, I32
        PdoEntry::new(0x60BC, 0, 32), // Touch probe pos2 pos value, I32
        PdoEntry::new(0x60BD, 0, 32), // Touch probe pos2 neg value, I32
    ],
);

/// 0x1A01, 2nd TxPDO map: pt/idx/jg/hm (B2 or later). 19 entries.
///
/// DISCREPANCY: §3.3 states a map size of 54 bytes; the listed objects with their §7 types add
/// up to 50 bytes, which is what this table gives. Verify on hardware.
pub const TX_PDO_1A01: Pdo = Pdo::fixed(
    0x1A01,
    &[
        PdoEntry::new(0x6061, 0, 8),  // Modes of operation display
        PdoEntry::new(0x6041, 0, 16), // Statusword
        PdoEntry::new(0x2D11, 0, 16), // Status DO 1
        PdoEntry::new(0x2D12, 0, 16), // Status DO 2
        PdoEntry::new(0x2D13, 0, 16), // Status DO 3
        PdoEntry::new(0x2D15, 0, 16), // Status DO 5, U16
        PdoEntry::new(0x2D17, 0, 16), // Status DO 7, U16
        PdoEntry::new(0x6064, 0, 32), // Position actual value
        PdoEntry::new(0x606C, 0, 32), // Velocity actual value
        PdoEntry::new(0x60F4, 0, 32), // Following error actual value
        PdoEntry::new(0x6077, 0, 16), // Torque actual value
        PdoEntry::new(0x2D68, 0, 16), // Point demand value, I16 [B2+]
        PdoEntry::new(0x2D69, 0, 16), // Point actual value, I16 [B2+]
        PdoEntry::new(0x2D6A, 0, 8),  // M code actual value, U8 [B2+]
        PdoEntry::new(0x60B9, 0, 16), // Touch probe status
        PdoEntry::new(0x60BA, 0, 32), // Touch probe pos1 pos value
        PdoEntry::new(0x60BB, 0, 32), // Touch probe pos1 neg value
        PdoEntry::new(0x60BC, 0, 32), // Touch probe pos2 pos value
        PdoEntry::new(0x60BD, 0, 32), // Touch probe pos2 neg value
    ],
);

/// 0x1A02, 3rd TxPDO map: empty at power-on.
pub const TX_PDO_1A02: Pdo = Pdo::fixed(0x1A02, &[]);

/// 0x1A03, 4th TxPDO map: empty at power-on.
pub const TX_PDO_1A03: Pdo = Pdo::fixed(0x1A03, &[]);

/// Power-on contents of every RxPDO mapping object, in index order (what an emulated drive
/// resets to).
pub const RX_PDOS: &[Pdo] = &[RX_PDO_1600, RX_PDO_1601, RX_PDO_1602, RX_PDO_1603];

/// Power-on contents of every TxPDO mapping object, in index order.
pub const TX_PDOS: &[Pdo] = &[TX_PDO_1A00, TX_PDO_1A01, TX_PDO_1A02, TX_PDO_1A03];

/// The power-on assignment: 0x1C12:01 = 0x1600 and 0x1C13:01 = 0x1A00, one PDO each
/// (§3.4, §7.3.3). Output image 29 bytes, input image 41 bytes.
pub const DEFAULT_MAPPING: Mapping = Mapping::fixed(DEFAULT_RX, DEFAULT_TX);
const DEFAULT_RX: &[Pdo] = &[RX_PDO_1600];
const DEFAULT_TX: &[Pdo] = &[TX_PDO_1A00];

/// \[REC\] Recommended mapping for cyclic synchronous operation (csp, csv, cst, switchable through
/// 0x6060), our choice, not the manual's. Output 13 bytes, input 19 bytes.
///
/// It carries what the cycle writes and reads every cycle, and nothing that is dangerous when
/// left at zero: unlike the default 0x1600 it leaves out the velocity limit 0x2D20 and the torque
/// limits 0x60E0/0x60E1 (0 in the process image means "speed 0" / "no torque", §3.3 notes); set
/// those by SDO in PRE-OP if needed (0x60E0/0x60E1 default to [Pr. PA11]/[Pr. PA12]). It adds
/// the error code 0x603F, which no default map carries. It keeps 32-bit fields on even byte
/// offsets. Not included, though §3.5 recommends them for csp/csv/cst: the watch-dog counters
/// 0x2D23/0x2D24 (mapping 0x2D23 arms [AL. 86.2] unless the master increments it every cycle),
/// Control DI 1/2, Status DO 1–3.
pub const CYCLIC_MAPPING: Mapping = Mapping::fixed(CYCLIC_RX, CYCLIC_TX);
const CYCLIC_RX: &[Pdo] = &[Pdo::fixed(
    0x1600,
    &[
        PdoEntry::new(0x6040, 0, 16), // Controlword, byte 0
        PdoEntry::new(0x607A, 0, 32), // Target position, byte 2
        PdoEntry::new(0x60FF, 0, 32), // Target velocity, byte 6
        PdoEntry::new(0x6071, 0, 16), // Target torque, byte 10
        PdoEntry::new(0x6060, 0, 8),  // Modes of operation, byte 12
    ],
)];
const CYCLIC_TX: &[Pdo] = &[Pdo::fixed(
    0x1A00,
    &[
        PdoEntry::new(0x6041, 0, 16), // Statusword, byte 0
        PdoEntry::new(0x6064, 0, 32), // Position actual value, byte 2
        PdoEntry::new(0x606C, 0, 32), // Velocity actual value, byte 6
        PdoEntry::new(0x6077, 0, 16), // Torque actual value, byte 10
        PdoEntry::new(0x60F4, 0, 32), // Following error actual value, byte 12
        PdoEntry::new(0x603F, 0, 16), // Error code, byte 16
        PdoEntry::new(0x6061, 0, 8),  // Modes of operation display, byte 18
        // [REC] Status DO 2: bit 3 S_ZSP is the drive's zero-speed signal, which the drive
        // requires before switching to or from a position mode (§5.4.2); the engine waits for
        // it rather than guessing from the velocity.
        PdoEntry::new(0x2D12, 0, 16), // byte 19
    ],
)];

const CONTROLWORD: ObjectAddress = ObjectAddress::new(0x6040, 0);
const STATUSWORD: ObjectAddress = ObjectAddress::new(0x6041, 0);
const SW_ONLY: &[ObjectAddress] = &[STATUSWORD];

/// Objects each mode of operation must have mapped: the "mapping required" (⊙) marks of §3.5.
/// Modes of operation (0x6060) is in no row: the mode can also be set by SDO. The touch-probe
/// function (0x60B8 Rx / 0x60B9 Tx, required when touch probe is used) is not a mode and is not
/// listed here. pt, jg and idx need software version B2 or later.
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
    RequiredObjects {
        mode: 1,
        mode_name: "pp",
        rx: &[CONTROLWORD, ObjectAddress::new(0x607A, 0)],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: 3,
        mode_name: "pv",
        rx: &[CONTROLWORD, ObjectAddress::new(0x60FF, 0)],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: 4,
        mode_name: "tq",
        rx: &[CONTROLWORD, ObjectAddress::new(0x6071, 0)],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: 6,
        mode_name: "hm",
        rx: &[CONTROLWORD],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: -101,
        mode_name: "pt",
        rx: &[CONTROLWORD, ObjectAddress::new(0x2D60, 0)],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: -100,
        mode_name: "jg",
        rx: &[CONTROLWORD],
        tx: SW_ONLY,
    },
    RequiredObjects {
        mode: -103,
        mode_name: "idx",
        rx: &[CONTROLWORD, ObjectAddress::new(0x2D60, 0)],
        tx: SW_ONLY,
    },
];

// ============================================================================================
// CiA 402 behaviour (§5.1, §5.4, §5.6, §7.3.1(3), §7.3.8)
// ============================================================================================

/// [Pr. PA01] (0x2001) selects the usable modes, read at power-on (§5.4.1 table: "usable
/// control modes are limited depending on the setting of [Pr. PA01]"). The low hex digit
/// selects: ___0 / ___1 the cyclic synchronous modes (and hm), ___2 the profile modes (and
/// hm), ___6 / ___8 the point-table and indexer methods (software version B2 or later).
pub const MODE_SELECTOR: ModeSelector = ModeSelector {
    object: ObjectAddress::new(0x2001, 0),
    name: "[Pr. PA01] Operation mode",
    mask: 0xF,
    groups: &[
        ModeGroup {
            value: 0,
            name: "___0: Automatic selection by each network",
            modes: &[6, 8, 9, 10],
        },
        ModeGroup {
            value: 1,
            name: "___1: Cyclic synchronous mode",
            modes: &[6, 8, 9, 10],
        },
        ModeGroup {
            value: 2,
            name: "___2: Profile mode",
            modes: &[1, 3, 4, 6],
        },
        ModeGroup {
            value: 6,
            name: "___6: Positioning mode (point table method)",
            modes: &[6, -100, -101],
        },
        ModeGroup {
            value: 8,
            name: "___8: Positioning mode (indexer method)",
            modes: &[6, -100, -103],
        },
    ],
    source: "MR-J4-TM manual §5.4.1",
};

/// 0x6502 vendor bits (§7.3.8(8)): bit 16 jg (−100), bit 17 pt (−101), bit 19 idx (−103).
pub const VENDOR_MODE_BITS: &[VendorModeBit] = &[
    VendorModeBit {
        bit: 16,
        mode: -100,
    },
    VendorModeBit {
        bit: 17,
        mode: -101,
    },
    VendorModeBit {
        bit: 19,
        mode: -103,
    },
];

/// The alarms this manual names, as 0x603F / 0x1003 / EMCY codes: 0xFF00 + the main alarm
/// number (software B2 and later; §7.3.1(3), §7.3.8(1)). Several details share one code
/// (AL.86.1 and AL.86.2 are both 0xFF86); 0x2A41 carries the detail. Two rows come from the
/// MELSERVO-J4 alarm numbering rather than from this manual (see [`REC_ALARMS`]). The last row
/// names any other alarm by its number.
pub const ERRORS: &[ErrorEntry] = &[
    ErrorEntry::exact(0xFF10, "AL.10", "Undervoltage"),
    ErrorEntry::exact(0xFF25, "AL.25", "Absolute position erased"),
    REC_ALARMS[0],
    ErrorEntry::exact(0xFF37, "AL.37", "Parameter error"),
    REC_ALARMS[1],
    ErrorEntry::exact(0xFF69, "AL.69", "Command error"),
    ErrorEntry::exact(0xFF86, "AL.86", "Network communication error"),
    // The warnings this manual names (statusword bit 7 "W", §5.3.1; S_BWNG for AL.92/AL.9F in
    // 0x2D11). MANUAL GAP: the manual gives the 0xFF00 + number rule for alarms and does not
    // say whether 0x603F carries a warning; should one come with that rule, it is named.
    ErrorEntry::exact(0xFF90, "AL.90", "Home position return incomplete warning"),
    ErrorEntry::exact(0xFF92, "AL.92", "Battery cable disconnection warning"),
    ErrorEntry::exact(0xFF98, "AL.98", "Software limit warning"),
    ErrorEntry::exact(0xFF9F, "AL.9F", "Battery warning"),
    ErrorEntry::exact(0xFFE3, "AL.E3", "Absolute position counter warning"),
    ErrorEntry::exact(0xFFF4, "AL.F4", "Positioning warning"),
    ErrorEntry {
        code: 0xFF00,
        mask: 0xFF00,
        name: "AL.xx",
        text: "MR-J4-TM alarm: the low byte is the alarm number",
    },
];

/// The device-control rules (§5.1, §5.4.2, §5.6, §7.3.8):
/// - **state skipping**: Switch on (0x0007) or Enable operation (0x000F) from Switch on
///   disabled, and Enable operation from Ready to switch on, jump straight there;
/// - quick-stop option code **2 only** (0x605A range 2–2): decelerate on 0x6085, then Switch on
///   disabled; no transition 16 (§5.1 table: "not supported");
/// - switching 0x6060 to or from a position mode needs zero speed (§5.4.2); pt and idx position
///   the axis, jg does not (our reading: §5.4.2 only says "position mode");
/// - 0x6502 = 0x000B03AD: pp, pv, tq, hm, csp, csv, cst plus jg, pt, idx (B2 and later);
/// - the alarm table [`ERRORS`].
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: true,
    transition_16: false,
    quick_stop_options: &[QuickStopOption::QUICK_STOP_RAMP],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: true,
    vendor_position_modes: &[-101, -103],
    remote_gates_controlword: false,
    supported_modes: SupportedModes::from_raw(0x000B_03AD).with_vendor_bits(VENDOR_MODE_BITS),
    error_table: ERRORS,
    csp_start_edge: false,
    // §5.4.9 (4): a stroke end during homing (methods 3–6, 19–22) gives [AL. 90 Home position
    // return incomplete warning], a warning (statusword bit 7, §5.3.1): the drive stays
    // enabled.
    homing_failure: "AL.90 Home position return incomplete warning",
    // §7.3.13 (1): "No value can be written because Home offset (607Ch) is set automatically.
    // Writing any value causes SDO Abort Code (0609 0030h …)".
    home_offset_set_by_drive: Some(
        "the MR-J4-TM sets its home offset 0x607C itself and refuses a written value (SDO abort \
         0x06090030, manual §7.3.13 (1)); its home position shift comes from its own parameters",
    ),
    // §4.2 SDO Abort Code: "0601 0006h Object mapped to RxPDO, SDO download blocked. SDO
    // Download is executed to an object mapped to RxPDO."
    sdo_refused_while_rx_mapped: Some(
        "the MR-J4-TM refuses an SDO download to an object mapped in its RxPDO (manual §4.2: \
         \"SDO Download is executed to an object mapped to RxPDO\"): write it through the PDO, \
         or remap in PRE-OP without it first",
    ),
    // §7.3.12 (1), Target position (607Ah): "Profile position mode (pp) … _ 0 _ _ (mm), _ 1 _ _
    // (inch), _ 3 _ _ (pulse): FFF0BDC1h to 000F423Fh (-999999 to 999999)" (degree: −360000 to
    // 360000, narrower still; the check takes the wider).
    pp_target_range: Some(crate::cia402::ValueRange {
        min: -999_999,
        max: 999_999,
        source: "the MR-J4-TM takes −999999 to 999999 pos units in 0x607A in pp (manual \
                 §7.3.12 (1)); a pos unit follows [Pr. PT01], [Pr. PT03] and the gear ratio 0x6091 \
                 (§7.3.14)",
    }),
};

// ============================================================================================
// Synchronisation (§1.1, §1.3, §7.3.3(4), (5))
// ============================================================================================

/// The PDO / SYNC0 cycle times the drive accepts in 0x1C32:02, ns (§1.3, §7.3.3(4)); any other
/// value is refused (abort 0x06090030).
pub const CYCLE_TIMES_NS: &[u32] = &[250_000, 500_000, 1_000_000, 2_000_000];

/// Free run (0x1C32:01 = 0; the cyclic modes need software B4 or later) or DC SYNC0
/// (0x1C32:01 = 2), with SYNC0 = the PDO cycle, no shift, SYNC1 unused (§1.1(3)); the master
/// writes 0x1C32:01 and 0x1C32:02 in PRE-OP (0x1C33:01/:02 follow). There is no 0x60C2.
pub const SYNC: SyncSpec = SyncSpec {
    free_run: true,
    dc_sync0: true,
    cycle_times: CycleTimes::List(CYCLE_TIMES_NS),
    assign_activate: ASSIGN_ACTIVATE,
    sync_type_object: Some(ObjectAddress::new(0x1C32, 1)),
    cycle_time_object: Some(CycleTimeObject::Nanoseconds(ObjectAddress::new(0x1C32, 2))),
};

// ============================================================================================
// Units (§5.4.3–§5.4.5, §7.3.14)
// ============================================================================================

/// Position command units per motor revolution in the cyclic modes: pulses, the encoder
/// resolution of the MR-J4 rotary motors (22 bits; 0x608F:01 reports it, e.g. 4 194 304).
pub const COUNTS_PER_REV: f64 = 4_194_304.0;

/// Position in pulses (4 194 304 per revolution), velocity in 0.01 r/min (0x60A9 = 0xFEB44700),
/// torque in 0.1 % of the rated torque (§5.4.3–§5.4.5). Ramps (0x6083/0x6084/0x6085) are time
/// constants in ms from 0 to the rated speed, not accelerations.
pub const UNITS: Units = Units {
    position_name: "pulse",
    position_per_rev: COUNTS_PER_REV,
    // 0.01 r/min (a velocity unit is COUNTS_PER_REV / 6000 pulses/s).
    velocity: VelocityUnit::RevPerMinute { scale: 0.01 },
    // 0.1 % of rated torque.
    torque_per_mille: 1.0,
    profile: Some(crate::cia402::ProfileUnits {
        // 6081h and 6099h:01/02: "Unit: [0.01 r/min]" (§7.3.12 (6), §7.3.13 (3)).
        profile_velocity: VelocityUnit::RevPerMinute { scale: 0.01 },
        homing_velocity: VelocityUnit::RevPerMinute { scale: 0.01 },
        // 6083h/6084h/6085h/609Ah: "a time for the servo motor to reach the rated speed", ms
        // (§7.3.12 (7)(8), §7.3.13 (4)); the rated speed is the motor's (MANUAL GAP:
        // REC_RATED_SPEED_RPM).
        acceleration: crate::cia402::AccelUnit::MillisecondsTo {
            rpm: REC_RATED_SPEED_RPM,
        },
        // 6087h: "Unit: 0.1%/s (rated torque of 100%)" (§5.4.8 (1)).
        torque_slope: crate::cia402::TorqueSlopeUnit::PerMillePerSecond,
    }),
};

/// **MANUAL GAP** \[REC\]: the rated speed the ramp time constants (6083h, 6084h, 6085h,
/// 609Ah) refer to is the motor's, which this manual does not give; 3000 r/min, the rated speed
/// of the HG-KR/HG-MR motors the MR-J4 rotary series is usually combined with (the emulated
/// motor's too).
pub const REC_RATED_SPEED_RPM: f64 = 3000.0;

// ============================================================================================
// Start-up (§1.4.2, §3.3 notes, §5.9, §6.2)
// ============================================================================================

/// SDOs for a safe start: none beyond the synchronisation set-up ([`SYNC`]: 0x1C32:01 and the
/// cycle in 0x1C32:02). The drive's power-on values are safe: quick stop on the 100 ms ramp,
/// following-error window 3 revolutions, torque limits at [Pr. PA11]/[Pr. PA12]. The values that
/// are unsafe at zero are outputs, not SDOs: see [`OUTPUT_DEFAULTS`].
pub const STARTUP: &[StartupSdo] = &[];

/// Outputs that must not start at zero when they are mapped (§3.3 notes 1–2, §5.4.5): 0 in the
/// velocity limit 0x2D20 stops the motor in cst/tq, 0 in the torque limits 0x60E0/0x60E1 means no
/// torque at all. The default 0x1600 maps all three.
pub const OUTPUT_DEFAULTS: &[OutputDefault] = &[
    OutputDefault {
        address: ObjectAddress::new(0x2D20, 0),
        value: 50_000,
        why: "velocity limit 500.00 r/min (the drive's default, [Pr. PT67]); 0 would hold the motor at zero speed in cst/tq",
    },
    OutputDefault {
        address: ObjectAddress::new(0x60E0, 0),
        value: 10_000,
        why: "positive torque limit 1000.0 % (the maximum; the motor's own limit applies); 0 would mean no torque",
    },
    OutputDefault {
        address: ObjectAddress::new(0x60E1, 0),
        value: 10_000,
        why: "negative torque limit 1000.0 % (the maximum; the motor's own limit applies); 0 would mean no torque",
    },
];

/// The incremental (watchdog) counter of §6.2 / §7.3.7(22), (23): when 0x2D23 is mapped the
/// master adds 1 (mod 256) every cycle, else [AL. 86.2]; the drive returns 0x2D24 = 0x2D23 + 1.
/// Checked in DC mode only.
pub const CYCLE_COUNTER: CycleCounter = CycleCounter {
    output: ObjectAddress::new(0x2D23, 0),
    echo: Some(ObjectAddress::new(0x2D24, 0)),
};

// ============================================================================================
// The profile
// ============================================================================================

/// Everything ecdrive knows about the MR-J4-TM.
pub static PROFILE: DriveProfile = DriveProfile {
    name: "MR-J4-TM",
    vendor: "Mitsubishi Electric",
    caps: CAPS,
    dictionary: DICTIONARY,
    units: UNITS,
    bus: EtherCat {
        key: "mr-j4-tm",
        identity: IdentityMatch {
            vendor_id: VENDOR_ID,
            product_code: PRODUCT_CODE,
        },
        revision: REVISION,
        pdo_limits: PDO_LIMITS,
        default_mapping: DEFAULT_MAPPING,
        cyclic_mapping: CYCLIC_MAPPING,
        mode_mappings: &[],
        required_objects: REQUIRED_OBJECTS,
        startup: STARTUP,
        init_cmds: &[],
        output_defaults: OUTPUT_DEFAULTS,
        cycle_counter: Some(CYCLE_COUNTER),
        sync: SYNC,
        // §4.1: "Complete Access: not supported".
        complete_access: false,
        esi: include_str!("../../../../esi/Mitsubishi_MR-J4-TM.xml"),
        zero_speed_flag: Some(StatusFlag {
            address: ObjectAddress::new(0x2D12, 0),
            bit: 3,
        }),
        mode_selector: Some(MODE_SELECTOR),
        ratings: RATINGS,
    },
};

/// What the manual documents independently of the motor: the torque limits 0x60E0/0x60E1
/// default to 10000 (1000.0 % of the rated torque) and 0x607F (max profile velocity) to
/// 2000000 × 0.01 r/min = 20000 r/min. The motor's own maxima are lower and motor-dependent
/// (0x6072, 0x6080 report them).
pub const RATINGS: crate::drives::Ratings = crate::drives::Ratings {
    max_torque: Some(crate::drives::Rating {
        value: 10000.0,
        source: "0x60E0/0x60E1 torque limit default 10000 = 1000.0 % of rated torque (§5.4 object tables)",
    }),
    max_speed_rev_s: Some(crate::drives::Rating {
        value: 20000.0 / 60.0,
        source: "0x607F max profile velocity default 2000000 × 0.01 r/min = 20000 r/min (§5.4.6 (1))",
    }),
};

/// Vendor ID (0x1018:01, §7.3.1(9); the manual prints the 7-digit "0000A1Eh").
pub const VENDOR_ID: u32 = 0x0000_0A1E;
/// Product code (0x1018:02, §7.3.1(9)).
pub const PRODUCT_CODE: u32 = 0x0000_0201;

// ============================================================================================
// Values that are ours (MANUAL GAP, [REC]) and readings of DISCREPANCIES
// ============================================================================================
//
// Declared here:
// - [`REVISION`] (MANUAL GAP), [`ASSIGN_ACTIVATE`] (MANUAL GAP), [`REC_ALARMS`] (\[REC\]).
//
// Declared with their section, and marked there:
// - PDO limits: one PDO per SyncManager (\[REC\], DISCREPANCY §3.4 vs §7.3.3); the assignment
//   writable in PRE-OP only (DERIVED);
// - default mapping-object contents: entry values DERIVED from the object types; sub-0 counts
//   12/16/10/0 and 14/19/0/0 (DISCREPANCY §3.4 vs §7.3.2, §3.4 used); 0x1A01 50 bytes
//   (DISCREPANCY: §3.3 says 54); 0x6077 INTEGER16 and 0x2D20 UNSIGNED32 (DISCREPANCIES with §5);
// - [`CYCLIC_MAPPING`] (\[REC\]);
// - [`CAPS`]: jg is not a position mode for the zero-speed rule, pt and idx are (our reading);
// - [`OUTPUT_DEFAULTS`]: the values 50 000 / 10 000 / 10 000 (the drive's defaults);
// - dictionary: 0x6060/0x6061 = 8 at power-on (DISCREPANCY §7.3.8(6) says 0, §5.4.1 says 8 for
//   [Pr. PA01] = ___0; §5.4.1 used, as in the ESI file); 0x1C33:02 writable (DISCREPANCY §3.2 vs
//   §7.3.3: §7.3.3 used, mirrored with 0x1C32:02); 0x2D20 default 50 000 (DISCREPANCY §5.4.8
//   says 5000); 0x6098 default 37, 0x6086 default −1, 0x606E default 10 (the §7 values).

/// \[REC\] / MANUAL GAP: the revision number 0x1018:03 and the SII revision. The manual gives
/// no value; 0x00020002 is what one public field report read from an MR-J4-20TM.
pub const REVISION: u32 = 0x0002_0002;

/// MANUAL GAP: the ESI AssignActivate word of the DC mode (0x0980/0x0981). The manual states only
/// "SYNC0 used, SYNC1 not used"; 0x0300 is the ETG convention for SYNC0-only operation.
pub const ASSIGN_ACTIVATE: u16 = 0x0300;

/// \[REC\] Alarm names that are not in this manual but in the MELSERVO-J4 alarm numbering (the
/// troubleshooting manual SH(NA)030109 is not available here). The emulated drive raises them:
/// AL.35 when a csp set-point step implies a speed above the permissible speed, AL.52 when the
/// droop exceeds the following-error window 0x6065 for longer than 0x6066.
pub const REC_ALARMS: [ErrorEntry; 2] = [
    ErrorEntry::exact(0xFF35, "AL.35", "Command frequency error"),
    ErrorEntry::exact(0xFF52, "AL.52", "Error excessive"),
];
