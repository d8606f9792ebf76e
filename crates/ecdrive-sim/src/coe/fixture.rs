//! A small CiA 402-style object dictionary for tests and examples of the software slave, with
//! one object of each shape the CoE server must handle: VARs of several types, a 60-byte
//! string, the identity RECORD, a RECORD with sub-index gaps (0x1C32), a RECORD with bit-packed
//! entries, PDO mapping and assignment objects, write-only, PRE-OP-only and range-limited
//! entries. It describes no real device.

use crate::od::{ConstValue, DataType, EntryAccess, EntryDesc, ObjectCode, ObjectDesc};

const RO: EntryAccess = EntryAccess::RO;
const RW: EntryAccess = EntryAccess::RW;
const RW_PREOP: EntryAccess = EntryAccess::RW_PREOP;
const RW_RX: EntryAccess = EntryAccess::RW.union(EntryAccess::RXPDO);
const RO_TX: EntryAccess = EntryAccess::RO.union(EntryAccess::TXPDO);
const RW_BACKUP: EntryAccess = EntryAccess::RW
    .union(EntryAccess::BACKUP)
    .union(EntryAccess::SETTINGS);

const U8: DataType = DataType::Unsigned8;
const U16: DataType = DataType::Unsigned16;
const U32: DataType = DataType::Unsigned32;
const I8: DataType = DataType::Integer8;
const I16: DataType = DataType::Integer16;
const I32: DataType = DataType::Integer32;

const fn u(v: u64) -> ConstValue {
    ConstValue::Uint(v)
}

const fn i(v: i64) -> ConstValue {
    ConstValue::Int(v)
}

/// Vendor ID in 0x1018:01.
pub const VENDOR_ID: u32 = 0x0000_0E0D;
/// Product code in 0x1018:02.
pub const PRODUCT_CODE: u32 = 0x0000_0402;
/// The device name in 0x1008, exactly 60 bytes (longer than a small mailbox can carry in one
/// message, so uploads of it are segmented).
pub const DEVICE_NAME: &str = "ecdrive fixture servo: CiA 402 test dictionary, 60 bytes ok.";

macro_rules! var {
    ($index:literal, $name:literal, $entry:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[$entry],
        }
    };
}

const fn mapping_entries(defaults: [u64; 8], n: u64) -> [EntryDesc; 9] {
    let mut out = [EntryDesc::new(0, "Number of entries", U8, RW_PREOP); 9];
    out[0] = out[0].default(u(n)).range(u(0), u(8));
    let mut k = 1;
    while k < 9 {
        out[k] =
            EntryDesc::new(k as u8, "Mapped object", U32, RW_PREOP).default(u(defaults[k - 1]));
        k += 1;
    }
    out
}

static RXPDO1: [EntryDesc; 9] = mapping_entries([0x6040_0010, 0x607A_0020, 0, 0, 0, 0, 0, 0], 2);
static RXPDO2: [EntryDesc; 9] = mapping_entries([0; 8], 0);
static TXPDO1: [EntryDesc; 9] = mapping_entries([0x6041_0010, 0x6064_0020, 0, 0, 0, 0, 0, 0], 2);
static TXPDO2: [EntryDesc; 9] = mapping_entries([0; 8], 0);

/// The fixture dictionary.
pub static OBJECTS: &[ObjectDesc] = &[
    var!(
        0x1000,
        "Device type",
        EntryDesc::new(0, "Device type", U32, RO).default(u(0x0002_0192))
    ),
    var!(
        0x1001,
        "Error register",
        EntryDesc::new(0, "Error register", U8, RO)
    ),
    var!(
        0x1008,
        "Manufacturer device name",
        EntryDesc::new(0, "Manufacturer device name", DataType::VisibleString, RO)
            .bits(60 * 8)
            .default(ConstValue::Str(DEVICE_NAME))
    ),
    ObjectDesc {
        index: 0x1018,
        name: "Identity",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO).default(u(4)),
            EntryDesc::new(1, "Vendor ID", U32, RO).default(u(VENDOR_ID as u64)),
            EntryDesc::new(2, "Product code", U32, RO).default(u(PRODUCT_CODE as u64)),
            EntryDesc::new(3, "Revision number", U32, RO).default(u(0x0001_0000)),
            EntryDesc::new(4, "Serial number", U32, RO).default(u(0x1234_5678)),
        ],
    },
    ObjectDesc {
        index: 0x1600,
        name: "RxPDO map 1",
        code: ObjectCode::Array,
        entries: &RXPDO1,
    },
    ObjectDesc {
        index: 0x1601,
        name: "RxPDO map 2",
        code: ObjectCode::Array,
        entries: &RXPDO2,
    },
    ObjectDesc {
        index: 0x1A00,
        name: "TxPDO map 1",
        code: ObjectCode::Array,
        entries: &TXPDO1,
    },
    ObjectDesc {
        index: 0x1A01,
        name: "TxPDO map 2",
        code: ObjectCode::Array,
        entries: &TXPDO2,
    },
    ObjectDesc {
        index: 0x1C00,
        name: "Sync manager communication type",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of used sync managers", U8, RO).default(u(4)),
            EntryDesc::new(1, "SM0", U8, RO).default(u(1)),
            EntryDesc::new(2, "SM1", U8, RO).default(u(2)),
            EntryDesc::new(3, "SM2", U8, RO).default(u(3)),
            EntryDesc::new(4, "SM3", U8, RO).default(u(4)),
        ],
    },
    ObjectDesc {
        index: 0x1C12,
        name: "RxPDO assign",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of assigned PDOs", U8, RW_PREOP)
                .default(u(1))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Assigned PDO 1", U16, RW_PREOP).default(u(0x1600)),
            EntryDesc::new(2, "Assigned PDO 2", U16, RW_PREOP),
        ],
    },
    ObjectDesc {
        index: 0x1C13,
        name: "TxPDO assign",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of assigned PDOs", U8, RW_PREOP)
                .default(u(1))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Assigned PDO 1", U16, RW_PREOP).default(u(0x1A00)),
            EntryDesc::new(2, "Assigned PDO 2", U16, RW_PREOP),
        ],
    },
    ObjectDesc {
        index: 0x1C32,
        name: "SM output parameter",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO).default(u(12)),
            EntryDesc::new(1, "Synchronization type", U16, RW_PREOP).default(u(0)),
            EntryDesc::new(2, "Cycle time", U32, RW_PREOP).default(u(1_000_000)),
            EntryDesc::new(3, "Shift time", U32, RW_PREOP).default(u(0)),
            EntryDesc::new(4, "Synchronization types supported", U16, RO).default(u(0x0005)),
            EntryDesc::new(5, "Minimum cycle time", U32, RO).default(u(250_000)),
            EntryDesc::new(6, "Calc and copy time", U32, RO).default(u(100_000)),
            EntryDesc::new(9, "Delay time", U32, RO),
            EntryDesc::new(12, "Cycle time too small", U16, RO),
        ],
    },
    ObjectDesc {
        index: 0x1C33,
        name: "SM input parameter",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO).default(u(12)),
            EntryDesc::new(1, "Synchronization type", U16, RW_PREOP).default(u(0)),
            EntryDesc::new(2, "Cycle time", U32, RW_PREOP).default(u(1_000_000)),
            EntryDesc::new(3, "Shift time", U32, RW_PREOP).default(u(0)),
            EntryDesc::new(4, "Synchronization types supported", U16, RO).default(u(0x0005)),
            EntryDesc::new(5, "Minimum cycle time", U32, RO).default(u(250_000)),
            EntryDesc::new(6, "Calc and copy time", U32, RO).default(u(100_000)),
            EntryDesc::new(9, "Delay time", U32, RO),
            EntryDesc::new(12, "Cycle time too small", U16, RO),
        ],
    },
    var!(
        0x2000,
        "Command (write-only)",
        EntryDesc::new(0, "Command", U16, EntryAccess::WO)
    ),
    ObjectDesc {
        index: 0x2001,
        name: "Packed flags",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO).default(u(4)),
            EntryDesc::new(1, "Enable", DataType::Boolean, RW).default(u(1)),
            EntryDesc::new(2, "Mode", DataType::Bit3, RW).default(u(5)),
            EntryDesc::new(3, "Level", DataType::Bit4, RW).default(u(0xA)),
            EntryDesc::new(4, "Gain", U16, RW).default(u(0x1234)),
        ],
    },
    var!(
        0x2002,
        "Limited value",
        EntryDesc::new(0, "Limited value", I16, RW_BACKUP)
            .default(i(0))
            .range(i(-100), i(100))
    ),
    var!(
        0x2003,
        "PRE-OP-only parameter",
        EntryDesc::new(0, "PRE-OP-only parameter", U32, RW_PREOP).default(u(7))
    ),
    var!(
        0x2004,
        "User text",
        EntryDesc::new(0, "User text", DataType::VisibleString, RW)
            .bits(16 * 8)
            .default(ConstValue::Str("hello"))
    ),
    var!(
        0x6040,
        "Controlword",
        EntryDesc::new(0, "Controlword", U16, RW_RX)
    ),
    var!(
        0x6041,
        "Statusword",
        EntryDesc::new(0, "Statusword", U16, RO_TX)
    ),
    var!(
        0x6060,
        "Modes of operation",
        EntryDesc::new(0, "Modes of operation", I8, RW_RX).default(i(8))
    ),
    var!(
        0x6061,
        "Modes of operation display",
        EntryDesc::new(0, "Modes of operation display", I8, RO_TX).default(i(8))
    ),
    var!(
        0x6064,
        "Position actual value",
        EntryDesc::new(0, "Position actual value", I32, RO_TX)
    ),
    var!(
        0x607A,
        "Target position",
        EntryDesc::new(0, "Target position", I32, RW_RX)
    ),
    ObjectDesc {
        index: 0x607D,
        name: "Software position limit",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO).default(u(2)),
            EntryDesc::new(1, "Min position limit", I32, RW_BACKUP).default(i(-1_000_000)),
            EntryDesc::new(2, "Max position limit", I32, RW_BACKUP).default(i(1_000_000)),
        ],
    },
    var!(
        0x60FF,
        "Target velocity",
        EntryDesc::new(0, "Target velocity", I32, RW_RX)
    ),
];
