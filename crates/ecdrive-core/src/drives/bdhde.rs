//! Servotronix BDHDE servo drive, EtherCAT (EB models).
//!
//! Source: *EtherCAT Reference Manual — BDHDE Servo Drive — EB Models*, rev. 0.0.2 (2020-03),
//! firmware 2.0.6; `§x.y` cite its sections and "chapter 7/9" its object tables. Values the
//! manual does not state are labelled **MANUAL GAP** or **\[REC\]** (our choice) where they are
//! declared.
//!
//! Sections of this file:
//! - PDO mapping: limits, the power-on contents of every mapping object, the default assignment,
//!   the recommended cyclic mapping, and the objects each mode needs;
//! - CiA 402 behaviour: no state skipping, quick-stop option codes 0/2/6 with transition 16, the
//!   remote bit, the fault table;
//! - synchronisation (0x60C2 in 250 µs units) and cycle times; units (the factor group);
//! - start-up: the SDOs a safe start needs;
//! - the object dictionary ([`DICTIONARY`], in `bdhde/dictionary.rs`);
//! - the profile ([`PROFILE`]);
//! - **values that are ours**: every MANUAL GAP and \[REC\] value of this file, and the reading
//!   taken where the manual contradicts itself (DISCREPANCY), in one section at the end.

use super::profile::{
    CycleTimeObject, CycleTimes, DriveProfile, IdentityMatch, StartupSdo, StartupWhen, SyncSpec,
    Units,
};
use crate::cia402::VelocityUnit;
use crate::cia402::{DriveCaps, ErrorEntry, QuickStopOption, SupportedModes};
use crate::drives::profile::EtherCat;
use crate::od::{ConstValue, ObjectAddress};
use crate::pdo::{DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange, RequiredObjects};

mod dictionary;
pub use dictionary::DICTIONARY;

// ============================================================================================
// PDO mapping (§5.2.2, chapter 7 objects 1600h–1603h, 1A00h–1A03h, 1C12h, 1C13h)
// ============================================================================================

/// RxPDO mapping objects: 0x1600 holds up to 8 entries, 0x1601–0x1603 up to 2 (the sub-index 0
/// ranges "0 to 8" and "0 to 2" in chapter 7).
const RX_RANGES: &[PdoRange] = &[
    PdoRange::single(0x1600, 8),
    PdoRange::new(0x1601, 0x1603, 2),
];

/// TxPDO mapping objects: 0x1A00 up to 8 entries, 0x1A01–0x1A03 up to 2.
const TX_RANGES: &[PdoRange] = &[
    PdoRange::single(0x1A00, 8),
    PdoRange::new(0x1A01, 0x1A03, 2),
];

/// The PDO rules of the BDHDE.
///
/// - Entries per mapping object: 8 in 0x1600/0x1A00, 2 in 0x1601–0x1603/0x1A01–0x1A03
///   (chapter 7). The mapping objects are read/write ("variable PDO mapping", §5.2.2).
/// - PDOs per SyncManager: **1**. The manual documents 0x1C12/0x1C13 as single UNSIGNED16
///   variables (one PDO index each, ranges 0x1600–0x17FF / 0x1A00–0x1BFF), not as ETG arrays;
///   \[REC\] treat that as one assignable PDO per direction, written in the standard array form
///   (sub 0 count, sub 1 index), which is what ethercrab reads back.
/// - MANUAL GAP: no maximum entry count or byte size per direction. \[REC\] 8 entries and
///   32 bytes, DERIVED from one assigned PDO of at most 8 entries of at most 32 bits.
/// - Changing the mapping needs sub 0 = 0 first (abort 0x06010003) and PRE-OP
///   (abort 0x08000022); the mapping is not stored.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "BDHDE",
    rx: DirectionLimits {
        pdos: RX_RANGES,
        max_assigned: 1,
        max_entries: 8,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: TX_RANGES,
        max_assigned: 1,
        max_entries: 8,
        max_bytes: 32,
    },
    assignment_writable: true,
};

// --- Power-on contents of the mapping objects ------------------------------------------------
//
// Chapter 7 prints every default entry value in decimal; the hex values below are those numbers
// (e.g. 1618608160 = 0x607A0020). §5.2.2 lists the same objects with their bit lengths.

/// 0x1600 "Receive PDO Mapping Parameter 1" (assigned at power-on). 8 entries, 23 bytes, with
/// 16- and 32-bit fields at odd byte offsets.
pub const RX_PDO_1600: Pdo = Pdo::fixed(
    0x1600,
    &[
        PdoEntry::new(0x607A, 0, 32), // Target position, I32 (1618608160)
        PdoEntry::new(0x60FF, 0, 32), // Target velocity, I32 (1627324448)
        PdoEntry::new(0x6060, 0, 8),  // Modes of operation, I8 (1616904200)
        PdoEntry::new(0x6040, 0, 16), // Controlword, U16 (1614807056)
        PdoEntry::new(0x6081, 0, 32), // Profile velocity, U32 (1619066912)
        PdoEntry::new(0x60B8, 0, 16), // Touch probe function, U16 (1622671376)
        PdoEntry::new(0x6071, 0, 16), // Target torque, I16 (1618018320)
        PdoEntry::new(0x6083, 0, 32), // Profile acceleration, U32 (1619197984)
    ],
);

/// 0x1601 "Receive PDO Mapping Parameter 2": controlword + target position, 6 bytes.
pub const RX_PDO_1601: Pdo = Pdo::fixed(
    0x1601,
    &[
        PdoEntry::new(0x6040, 0, 16), // Controlword
        PdoEntry::new(0x607A, 0, 32), // Target position
    ],
);

/// 0x1602 "Receive PDO Mapping Parameter 3": controlword + target velocity, 6 bytes.
pub const RX_PDO_1602: Pdo = Pdo::fixed(
    0x1602,
    &[
        PdoEntry::new(0x6040, 0, 16), // Controlword
        PdoEntry::new(0x60FF, 0, 32), // Target velocity
    ],
);

/// 0x1603 "Receive PDO Mapping Parameter 4": controlword + target torque, 4 bytes.
pub const RX_PDO_1603: Pdo = Pdo::fixed(
    0x1603,
    &[
        PdoEntry::new(0x6040, 0, 16), // Controlword
        PdoEntry::new(0x6071, 0, 16), // Target torque
    ],
);

/// 0x1A00 "Transmit PDO Mapping Parameter 1" (assigned at power-on). 8 entries, 23 bytes.
pub const TX_PDO_1A00: Pdo = Pdo::fixed(
    0x1A00,
    &[
        PdoEntry::new(0x6041, 0, 16), // Statusword, U16 (1614872592)
        PdoEntry::new(0x6064, 0, 32), // Position actual value, I32 (1617166368)
        PdoEntry::new(0x606C, 0, 32), // Velocity actual value, I32 (1617690656)
        PdoEntry::new(0x6077, 0, 16), // Torque actual value, I16 (1618411536)
        PdoEntry::new(0x6061, 0, 8),  // Modes of operation display, I8 (1616969736)
        PdoEntry::new(0x60F4, 0, 32), // Following error actual value, I32 (1626603552)
        PdoEntry::new(0x60B9, 0, 16), // Touch probe status, U16 (1622736912)
        PdoEntry::new(0x60BA, 0, 32), // Touch probe 1 positive value, I32 (1622802464)
    ],
);

/// 0x1A01 "Transmit PDO Mapping Parameter 2": statusword + position actual value, 6 bytes.
pub const TX_PDO_1A01: Pdo = Pdo::fixed(
    0x1A01,
    &[
        PdoEntry::new(0x6041, 0, 16), // Statusword
        PdoEntry::new(0x6064, 0, 32), // Position actual value
    ],
);

/// 0x1A02 "Transmit PDO Mapping Parameter 3": statusword + velocity actual value, 6 bytes.
pub const TX_PDO_1A02: Pdo = Pdo::fixed(
    0x1A02,
    &[
        PdoEntry::new(0x6041, 0, 16), // Statusword
        PdoEntry::new(0x606C, 0, 32), // Velocity actual value
    ],
);

/// 0x1A03 (the manual heads it "Transmit PDO Mapping Parameter 3" with index "1A02", both
/// typos): statusword + torque actual value, 4 bytes.
pub const TX_PDO_1A03: Pdo = Pdo::fixed(
    0x1A03,
    &[
        PdoEntry::new(0x6041, 0, 16), // Statusword
        PdoEntry::new(0x6077, 0, 16), // Torque actual value
    ],
);

/// Power-on contents of every RxPDO mapping object, in index order.
pub const RX_PDOS: &[Pdo] = &[RX_PDO_1600, RX_PDO_1601, RX_PDO_1602, RX_PDO_1603];

/// Power-on contents of every TxPDO mapping object, in index order.
pub const TX_PDOS: &[Pdo] = &[TX_PDO_1A00, TX_PDO_1A01, TX_PDO_1A02, TX_PDO_1A03];

/// The power-on assignment: 0x1C12 = 0x1600, 0x1C13 = 0x1A00 (chapter 7 defaults 5632 and
/// 6656). Both images 23 bytes.
pub const DEFAULT_MAPPING: Mapping = Mapping::fixed(DEFAULT_RX, DEFAULT_TX);
const DEFAULT_RX: &[Pdo] = &[RX_PDO_1600];
const DEFAULT_TX: &[Pdo] = &[TX_PDO_1A00];

/// \[REC\] Recommended mapping for cyclic synchronous operation (csp, csv, cst, switchable through
/// 0x6060), our choice, not the manual's: the same objects and order as the MR-J4-TM's
/// [`CYCLIC_MAPPING`](super::mr_j4_tm::CYCLIC_MAPPING), so one cycle serves both drives.
/// Output 13 bytes (5 entries), input 19 bytes (7 entries), within the 8-entry limit of
/// 0x1600/0x1A00. Compared with the default it drops the profile and touch-probe objects and
/// adds the error code 0x603F. The velocity and torque offsets 0x60B1/0x60B2 and the digital
/// inputs 0x60FD are mappable too, if an application needs them.
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
    ],
)];

const CONTROLWORD: ObjectAddress = ObjectAddress::new(0x6040, 0);
const STATUSWORD: ObjectAddress = ObjectAddress::new(0x6041, 0);
const SW_ONLY: &[ObjectAddress] = &[STATUSWORD];

/// \[REC\] Objects each mode needs in the process data. MANUAL GAP: the manual has no such table
/// (its chapter 5 "associated objects" lists disagree with the chapter 9 mapping flags); these
/// are the CiA 402 minimum — controlword and statusword plus the mode's set-point.
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
];

// ============================================================================================
// CiA 402 behaviour (§5.4, §5.5, §9 605Ah–605Eh, §10.2)
// ============================================================================================

/// The fault codes of §10.2 Table 10-4, as 0x603F and EMCY codes, with the 7-segment code and
/// FLT number as the name. Several faults share one code (0x6320 covers twelve); such rows name
/// all of them, since the code alone cannot tell them apart. Codes that are also standard CiA
/// codes are named here with the drive's own wording, which is looked up first.
pub const ERRORS: &[ErrorEntry] = &[
    ErrorEntry::exact(
        0x2214,
        "F24 (FLT 146) / P (FLT 3)",
        "Hardware over-current / Over-Current",
    ),
    ErrorEntry::exact(0x2250, "F20 (FLT 166)", "IPM Bottom Leg Short Circuit"),
    ErrorEntry::exact(0x2310, "F2 (FLT 17)", "Motor Foldback"),
    ErrorEntry::exact(0x2311, "F1 (FLT 16)", "Drive Foldback"),
    ErrorEntry::exact(0x2330, "F21 (FLT 167)", "UVW to Ground Short Circuit"),
    ErrorEntry::exact(
        0x2380,
        "e109 (FLT 43) / F23 (FLT 155)",
        "Current-Sensors Offset Invalid / Current Sensor boot strap error",
    ),
    ErrorEntry::exact(0x2382, "o9 (FLT 105)", "Digital Output Over-Current Fault"),
    ErrorEntry::exact(0x3110, "o (FLT 9)", "Over-Voltage"),
    ErrorEntry::exact(0x3120, "u (FLT 11)", "Under-Voltage"),
    ErrorEntry::exact(0x3183, "o7 (FLT 78)", "Bus AC Supply Line Disconnect"),
    ErrorEntry::exact(
        0x3199,
        "F4 (FLT 148) / o8 (FLT 83)",
        "Regeneration fault / Regen Resistor Overload",
    ),
    ErrorEntry::exact(
        0x4080,
        "t2 (FLT 39)",
        "Integrated Power Module Over-Temperature",
    ),
    ErrorEntry::exact(0x4310, "t1 (FLT 10)", "Power Stage Over-Temperature"),
    ErrorEntry::exact(
        0x5530,
        "e107 (FLT 7) / F13 (FLT 159)",
        "Power EEPROM Fault / Failure Writing to Power EEPROM",
    ),
    ErrorEntry::exact(
        0x5581,
        "e106 (FLT 6) / F11 (FLT 157) / F14 (FLT 160)",
        "Control EEPROM Fault / Parameter EEPROM Fault / Failure Writing to Control EEPROM",
    ),
    ErrorEntry::exact(
        0x5585,
        "e (FLT 2) / F0 (FLT 154) / F12 (FLT 158) / F15 (FLT 161) / F9 (FLT 153)",
        "Parameter Memory Checksum Failure / Eeprom version error / Control EEPROM Checksum \
         Failure / Control Board and Power Board Mismatch / Power EEPROM Checksum Failure",
    ),
    ErrorEntry::exact(0x5586, "E (FLT 12)", "Failure Writing to Flash Memory"),
    ErrorEntry::exact(0x6100, "HE (FLT 174)", "Homing Error"),
    ErrorEntry::exact(
        0x6320,
        "F10/F16/F17/F18/F25/F7/F8/H1-H5 (FLT 156/162/163/164/147/151/152/169-173)",
        "Power On Time Out / No Signal for Touch Probe / Electrical Gear Calculate Overflow / \
         Electrical Gear Over Range / Regeneration resistance less than 40 Ohm / Drive parameter \
         initialize fail / Motor parameter initialize fail / HDM 1-5",
    ),
    ErrorEntry::exact(0x6381, "-1 (FLT 12)", "Not Configured"),
    ErrorEntry::exact(0x6581, "e101 (FLT 5)", "FPGA Config Failed"),
    ErrorEntry::exact(0x7090, "e120 (FLT 47)", "FPGA Version Mismatch"),
    ErrorEntry::exact(0x7091, "n3 (FLT 57)", "Emergency Stop Issued"),
    ErrorEntry::exact(0x7121, "F3 (FLT 59)", "Stall Fault"),
    ErrorEntry::exact(
        0x7305,
        "F22 (FLT 168)",
        "Encoder Multi-turn Counter Overflow",
    ),
    ErrorEntry::exact(0x7380, "r20 (FLT 34)", "Feedback Communication Error"),
    ErrorEntry::exact(
        0x7382,
        "F19 (FLT 165) / r24 (FLT 42)",
        "SenseAR Init Failed / Tamagawa Init Failed",
    ),
    ErrorEntry::exact(
        0x7385,
        "r29 (FLT 56)",
        "Absolute Multi-turn Encoder Battery Low Voltage Fault",
    ),
    ErrorEntry::exact(0x7388, "r26 (FLT 49)", "Tamagawa Abs Operational Fault"),
    ErrorEntry::exact(0x738D, "r40 (FLT 82)", "SensAR Encoder Fault"),
    ErrorEntry::exact(0x7580, "Fb3 (FLT 65)", "Fieldbus Cable Disconnected"),
    ErrorEntry::exact(0x818D, "Fb8 (FLT 91)", "EtherCAT Packet Loss"),
    ErrorEntry::exact(0x8481, "J (FLT 14)", "Velocity Over-Speed Exceeded"),
    ErrorEntry::exact(0x8482, "J2 (FLT 67)", "Exceeded Maximum Velocity Error"),
    ErrorEntry::exact(0x8689, "J3 (FLT 87)", "Excessive PE Value"),
    ErrorEntry::exact(0xF080, "Fb9 (FLT 92)", "CAN/EtherCAT State Not Operational"),
    ErrorEntry::exact(0xFF02, "e123 (FLT 85)", "Motor Plate Read Failed"),
    ErrorEntry::exact(0xFF04, "- (FLT 89)", "Realtime Overload Fault"),
    ErrorEntry::exact(
        0xFF14,
        "e131 (FLT 108)",
        "MOTORNAME and MTP data are not compatible",
    ),
];

/// The device-control rules (§5.4, §5.5, §9 605Ah, §2.3):
/// - no state skipping: Shutdown → Switch on → Enable operation;
/// - quick-stop option codes 0 (disable the drive, the motor coasts; **the default**), 2 (ramp on
///   0x6085, then Switch on disabled) and 6 (ramp on 0x6085 and stay; transition 16 on Enable
///   operation). The manual words 6 as "remain in Operation Enabled"; CiA 402 and this model
///   read it as staying in Quick stop active;
/// - commands act only with statusword bit 9 (remote, COMMmode 1, the factory setting);
/// - 0x6502 = 941 (0x3AD): pp, pv, tq, hm, csp, csv, cst; no vendor modes;
/// - the fault table [`ERRORS`].
pub const CAPS: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: true,
    quick_stop_options: &[
        QuickStopOption::DISABLE_DRIVE,
        QuickStopOption::QUICK_STOP_RAMP,
        QuickStopOption::QUICK_STOP_RAMP_STAY,
    ],
    default_quick_stop_option: QuickStopOption::DISABLE_DRIVE,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: true,
    supported_modes: SupportedModes::from_raw(0x0000_03AD),
    error_table: ERRORS,
    // BDHDE manual, CSP example ("Starting the Operating Mode … Bit 4: New Target Value 0 » 1
    // Starts a movement to a target position"): read as written, the drive follows the target
    // only after the edge. ecdrive's choice: give the edge (harmless where bit 4 is reserved).
    csp_start_edge: true,
    // Table 10-4: fault 0x6100 "Homing Error" (display HE, FLT 174); §10.2: the drive enters
    // Fault.
    homing_failure: "fault 0x6100 Homing Error (HE, FLT 174)",
    home_offset_set_by_drive: None,
    sdo_refused_while_rx_mapped: None,
    pp_target_range: None,
};

// ============================================================================================
// Synchronisation (§2.4, §4.4.1, §9 60C2h)
// ============================================================================================

/// The time unit of 0x60C2:01 (FBITPRD): 250 µs; 0x60C2:02 (FBITIDX) is fixed at −4 and
/// read-only (§2.4).
pub const INTERPOLATION_UNIT_NS: u32 = 250_000;

/// DC SYNC0 ("DC-Synchronous", §4.4.1 step 8) with the cycle told to the drive in 0x60C2:01 as a
/// multiple of 250 µs, 1 to 64 (250 µs to 16 ms; DISCREPANCY, see the end of this file). The
/// drive has no 0x1C32/0x1C33 and no documented free run.
pub const SYNC: SyncSpec = SyncSpec {
    free_run: false,
    dc_sync0: true,
    cycle_times: CycleTimes::Range {
        min_ns: INTERPOLATION_UNIT_NS * FBITPRD_MIN,
        max_ns: INTERPOLATION_UNIT_NS * 64,
        step_ns: INTERPOLATION_UNIT_NS,
    },
    assign_activate: ASSIGN_ACTIVATE,
    sync_type_object: None,
    cycle_time_object: Some(CycleTimeObject::InterpolationFixedIndex {
        unit_ns: INTERPOLATION_UNIT_NS,
        index: -4,
    }),
};

// ============================================================================================
// Units (§6, §9 6091h/6092h, 6071h–6078h)
// ============================================================================================

/// Position units per motor revolution once [`STARTUP`] has set the factor group:
/// (0x6091:01 / 0x6091:02) × (0x6092:01 / 0x6092:02) = 1 048 576 / 1 × 1 / 1 (§6.2–§6.4, the
/// manual's own example). With the drive's defaults (all 1) one unit is one revolution.
pub const COUNTS_PER_REV: u32 = 1 << 20;

/// Position in user units (2^20 per revolution after [`STARTUP`]), velocity in user units per
/// second, acceleration in user units per s² (§6.2–§6.4), torque in per mille of the motor's
/// rated torque 0x6076 (§6.6).
pub const UNITS: Units = Units {
    // Counts: 2^20 per revolution, set at start-up.
    position_name: "count",
    position_per_rev: COUNTS_PER_REV as f64,
    velocity: VelocityUnit::PositionPerSecond,
    // 0.1 % of rated torque (0x6076).
    torque_per_mille: 1.0,
    profile: Some(crate::cia402::ProfileUnits {
        // 6081h, 6099h:01/02: "CAN user velocity units" (p.193, p.201), position units/s
        // (§6.3).
        profile_velocity: VelocityUnit::PositionPerSecond,
        homing_velocity: VelocityUnit::PositionPerSecond,
        // 6083h/6084h/609Ah: "CAN user acceleration/deceleration units" (p.194, p.203),
        // position units/s² (§6.4).
        acceleration: crate::cia402::AccelUnit::PositionPerSecond2,
        // 6087h: per mille of 6076h per second by §6.6; its object page says mN·m/s (the
        // manual contradicts itself; tq is not run by ecdrive on this drive yet).
        torque_slope: crate::cia402::TorqueSlopeUnit::PerMillePerSecond,
    }),
};

// ============================================================================================
// Start-up (§6.2, §9 6065h/6066h/605Ah/607Fh/6085h; reference 12 items 5 and 10)
// ============================================================================================

/// SDOs for a safe start, written in PRE-OP in this order. The drive's documented defaults are
/// unusable: one user unit per revolution, a following-error window of 1 unit with no time-out,
/// a maximum profile velocity of 1 unit/s, a quick stop that coasts (0x605A = 0) and a quick-stop
/// deceleration of 1 unit/s². The values are ours (\[REC\]), see [`REC_STARTUP`].
pub const STARTUP: &[StartupSdo] = REC_STARTUP;

// ============================================================================================
// The profile
// ============================================================================================

/// Everything ecdrive knows about the BDHDE.
pub static PROFILE: DriveProfile = DriveProfile {
    name: "BDHDE",
    vendor: "Servotronix",
    caps: CAPS,
    dictionary: DICTIONARY,
    units: UNITS,
    bus: EtherCat {
        key: "bdhde",
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
        output_defaults: &[],
        cycle_counter: None,
        sync: SYNC,
        // MANUAL GAP: complete access is not described; the abort list names 0x06010004
        // "cannot be accessed via complete access". Off, as in the ESI file.
        complete_access: false,
        esi: include_str!("../../../../esi/Servotronix_BDHDE.xml"),
        zero_speed_flag: None,
        mode_selector: None,
        ratings: RATINGS,
    },
};

/// What the manual documents independently of the motor: 0x6072 (max torque) takes 0 to 5000
/// (object 6072h, p. 184), read as per mille of the rated torque (\[REC\]: the manual gives no
/// unit). No speed independent of the motor (0x6080 is the motor's, default 0: MANUAL GAP).
pub const RATINGS: crate::drives::Ratings = crate::drives::Ratings {
    max_torque: Some(crate::drives::Rating {
        value: 5000.0,
        source: "0x6072 max torque, range 0–5000 (object 6072h, p. 184; per mille [REC])",
    }),
    max_speed_rev_s: None,
};

/// Vendor ID (0x1018:01, §7 1018h).
pub const VENDOR_ID: u32 = 0x0000_02E1;
/// Product code (0x1018:02, §7 1018h).
pub const PRODUCT_CODE: u32 = 0x000B_E2EB;
/// Revision number (0x1018:03 default 0, §7 1018h).
pub const REVISION: u32 = 0;

// ============================================================================================
// Values that are ours (MANUAL GAP, [REC]) and readings of DISCREPANCIES
// ============================================================================================
//
// Declared here: [`ASSIGN_ACTIVATE`], [`FBITPRD_MIN`] (DISCREPANCY), [`REC_STARTUP`].
//
// Declared with their section, and marked there:
// - PDO limits: one PDO per SyncManager (\[REC\]: 0x1C12/0x1C13 documented as single U16
//   variables, served in the ETG array form), 8 entries / 32 bytes per direction (MANUAL GAP,
//   DERIVED from the largest mapping object);
// - [`CYCLIC_MAPPING`] and [`REQUIRED_OBJECTS`] (\[REC\]);
// - [`CAPS`]: quick-stop code 6 read as CiA "stay in Quick stop active" (DISCREPANCY with the
//   manual's wording "remain in Operation Enabled");
// - [`UNITS`]: the 2^20 units per revolution follow from [`REC_STARTUP`];
// - complete access off (MANUAL GAP);
// - dictionary: 0x60C2:02 INTEGER8 (the manual prints UNSIGNED8 for −4); 0x1C12/0x1C13 as ETG
//   arrays (\[REC\]); 0x60C2:01 range 1–64 (DISCREPANCY, [`FBITPRD_MIN`]);
// - [`RATINGS`]: 0x6072 in per mille of the rated torque (\[REC\]: the manual gives its units
//   as "not applicable"); no speed rating (MANUAL GAP).

/// MANUAL GAP: the ESI AssignActivate word of the DC mode; 0x0300 (SYNC0 only) is the usual
/// "DC-Synchronous" value.
pub const ASSIGN_ACTIVATE: u16 = 0x0300;

/// DISCREPANCY: the smallest 0x60C2:01 (FBITPRD). §2.4, the description of the parameter itself,
/// says "the setting range of FBITPRD is from 1 to 64" (250 µs to 16 ms); the 0x60C2 object
/// table prints 4 to 64 (1 ms to 16 ms). The parameter's own description is followed, so the
/// drive runs at 500 µs and 250 µs too; the ESI file and the emulated drive agree.
pub const FBITPRD_MIN: u32 = 1;

/// \[REC\] The start-up SDOs (see [`STARTUP`]): the factor group first, then the windows and
/// limits in the resulting units.
pub const REC_STARTUP: &[StartupSdo] = &[
    StartupSdo {
        address: ObjectAddress::new(0x6091, 1),
        value: ConstValue::Uint(COUNTS_PER_REV as u64),
        why: "gear ratio motor revolutions: 2^20 position units per motor revolution (§6.2 example)",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x6091, 2),
        value: ConstValue::Uint(1),
        why: "gear ratio shaft revolutions: 1",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x6092, 1),
        value: ConstValue::Uint(1),
        why: "feed constant numerator: 1",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x6092, 2),
        value: ConstValue::Uint(1),
        why: "feed constant denominator: 1",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x6065, 0),
        value: ConstValue::Uint(3 * COUNTS_PER_REV as u64),
        why: "following-error window 3 revolutions (the drive's default is 1 unit)",
        when: StartupWhen::IfNotMapped,
    },
    StartupSdo {
        address: ObjectAddress::new(0x6066, 0),
        value: ConstValue::Uint(10),
        why: "following-error time-out 10 ms (the drive's default is 0)",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x607F, 0),
        value: ConstValue::Uint(100 * COUNTS_PER_REV as u64),
        why: "maximum profile velocity 100 rev/s = 6000 r/min (the drive's default is 1 unit/s)",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x6085, 0),
        value: ConstValue::Uint(1000 * COUNTS_PER_REV as u64),
        why: "quick-stop deceleration 1000 rev/s² (6000 r/min to 0 in 0.1 s; default 1 unit/s²)",
        when: StartupWhen::Always,
    },
    StartupSdo {
        address: ObjectAddress::new(0x605A, 0),
        value: ConstValue::Int(2),
        why: "quick stop on the 0x6085 ramp, then Switch on disabled (the default 0 lets the motor coast)",
        when: StartupWhen::Always,
    },
];
