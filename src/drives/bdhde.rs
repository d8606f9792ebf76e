//! Servotronix BDHDE servo drive, EtherCAT (EB models).
//!
//! Source: *EtherCAT Reference Manual — BDHDE Servo Drive — EB Models*, rev. 0.0.2 (2020-03),
//! firmware 2.0.6; `§x.y` cite its sections and "chapter 7/9" its object tables. Values the
//! manual does not state are labelled **MANUAL GAP** or **\[REC\]** (our choice) where they are
//! declared.
//!
//! Sections of this file:
//! - PDO mapping: limits, the power-on contents of every mapping object, the default assignment,
//!   the recommended cyclic mapping, and the objects each mode needs.

use crate::od::ObjectAddress;
use crate::pdo::{DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange, RequiredObjects};

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
