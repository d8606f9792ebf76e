//! The BDHDE object dictionary as data: the table the emulated drive's object store is built
//! from and what the master and the CLI use for types and mapping checks.
//!
//! Transcribed from the drive's ESI file in `esi/` (itself written from the manual, with the
//! section of every value cited there) and checked against the manual's object tables; where the
//! two forms must agree, `crates/ecdrive-sim/tests/sim/drives_dictionary.rs` compares them entry by entry (type, length,
//! access, PDO mapping, default, range) and every object read over CoE from the emulated drive.
//! Values the manual leaves open are listed in the parent module's "Values that are ours"
//! section.

use crate::drives::od_table::*;
use crate::od::{ConstValue, EntryDesc, ObjectCode, ObjectDesc};

/// Every object, sorted by index.
pub static DICTIONARY: &[ObjectDesc] = &[
    ObjectDesc {
        index: 0x1000,
        name: "Device Type",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Device Type", U32, RO).default(u(0x192))],
    },
    ObjectDesc {
        index: 0x1001,
        name: "Error Register",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Error Register", U8, RO).default(u(0))],
    },
    ObjectDesc {
        index: 0x1008,
        name: "Manufacturer Device Name",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer Device Name", VSTR, RO)
            .bits(40)
            .default(ConstValue::Str("BDHDE"))],
    },
    ObjectDesc {
        index: 0x1009,
        name: "Manufacturer Hardware Version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer Hardware Version", VSTR, RO).bits(64)],
    },
    ObjectDesc {
        index: 0x100A,
        name: "Manufacturer Software Version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Manufacturer Software Version", VSTR, RO).bits(64)],
    },
    ObjectDesc {
        index: 0x1018,
        name: "Identity Object",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO)
                .default(u(4))
                .range(u(1), u(4)),
            EntryDesc::new(1, "Vendor ID", U32, RO).default(u(0x2E1)),
            EntryDesc::new(2, "Product code", U32, RO).default(u(0xBE2EB)),
            EntryDesc::new(3, "Revision number", U32, RO).default(u(0)),
            EntryDesc::new(4, "Serial number", U32, RO).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x1600,
        name: "Receive PDO Mapping Parameter 1",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(8))
                .range(u(0), u(8)),
            EntryDesc::new(1, "Mapping target position", U32, RW).default(u(0x607A0020)),
            EntryDesc::new(2, "Mapping target velocity", U32, RW).default(u(0x60FF0020)),
            EntryDesc::new(3, "Mapping modes of operation", U32, RW).default(u(0x60600008)),
            EntryDesc::new(4, "Mapping controlword", U32, RW).default(u(0x60400010)),
            EntryDesc::new(5, "Mapping profile velocity", U32, RW).default(u(0x60810020)),
            EntryDesc::new(6, "Mapping touch probe function", U32, RW).default(u(0x60B80010)),
            EntryDesc::new(7, "Mapping target torque", U32, RW).default(u(0x60710010)),
            EntryDesc::new(8, "Mapping profile acceleration", U32, RW).default(u(0x60830020)),
        ],
    },
    ObjectDesc {
        index: 0x1601,
        name: "Receive PDO Mapping Parameter 2",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(2))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Mapping controlword", U32, RW).default(u(0x60400010)),
            EntryDesc::new(2, "Mapping target position", U32, RW).default(u(0x607A0020)),
        ],
    },
    ObjectDesc {
        index: 0x1602,
        name: "Receive PDO Mapping Parameter 3",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(2))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Mapping controlword", U32, RW).default(u(0x60400010)),
            EntryDesc::new(2, "Mapping target velocity", U32, RW).default(u(0x60FF0020)),
        ],
    },
    ObjectDesc {
        index: 0x1603,
        name: "Receive PDO Mapping Parameter 4",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(2))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Mapping controlword", U32, RW).default(u(0x60400010)),
            EntryDesc::new(2, "Mapping target torque", U32, RW).default(u(0x60710010)),
        ],
    },
    ObjectDesc {
        index: 0x1A00,
        name: "Transmit PDO Mapping Parameter 1",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(8))
                .range(u(0), u(8)),
            EntryDesc::new(1, "Mapping status word", U32, RW).default(u(0x60410010)),
            EntryDesc::new(2, "Mapping actual position", U32, RW).default(u(0x60640020)),
            EntryDesc::new(3, "Mapping actual velocity", U32, RW).default(u(0x606C0020)),
            EntryDesc::new(4, "Mapping actual torque", U32, RW).default(u(0x60770010)),
            EntryDesc::new(5, "Mapping modes of operation display", U32, RW).default(u(0x60610008)),
            EntryDesc::new(6, "Mapping following error", U32, RW).default(u(0x60F40020)),
            EntryDesc::new(7, "Mapping touch probe status", U32, RW).default(u(0x60B90010)),
            EntryDesc::new(8, "Mapping touch probe value", U32, RW).default(u(0x60BA0020)),
        ],
    },
    ObjectDesc {
        index: 0x1A01,
        name: "Transmit PDO Mapping Parameter 2",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(2))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Mapping status word", U32, RW).default(u(0x60410010)),
            EntryDesc::new(2, "Mapping actual position", U32, RW).default(u(0x60640020)),
        ],
    },
    ObjectDesc {
        index: 0x1A02,
        name: "Transmit PDO Mapping Parameter 3",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(2))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Mapping status word", U32, RW).default(u(0x60410010)),
            EntryDesc::new(2, "Mapping actual velocity", U32, RW).default(u(0x606C0020)),
        ],
    },
    ObjectDesc {
        index: 0x1A03,
        name: "Transmit PDO Mapping Parameter 4",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RW)
                .default(u(2))
                .range(u(0), u(2)),
            EntryDesc::new(1, "Mapping status word", U32, RW).default(u(0x60410010)),
            EntryDesc::new(2, "Mapping actual torque", U32, RW).default(u(0x60770010)),
        ],
    },
    ObjectDesc {
        index: 0x1C00,
        name: "Sync Manager Communication Type",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(4))
                .range(u(0), u(4)),
            EntryDesc::new(1, "SubIndex 001", U8, RO)
                .default(u(1))
                .range(u(0), u(4)),
            EntryDesc::new(2, "SubIndex 002", U8, RO)
                .default(u(2))
                .range(u(0), u(4)),
            EntryDesc::new(3, "SubIndex 003", U8, RO)
                .default(u(3))
                .range(u(0), u(4)),
            EntryDesc::new(4, "SubIndex 004", U8, RO)
                .default(u(4))
                .range(u(0), u(4)),
        ],
    },
    ObjectDesc {
        index: 0x1C12,
        name: "Sync Manager 2 PDO Assignment",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RW)
                .default(u(1))
                .range(u(0), u(1)),
            EntryDesc::new(1, "SubIndex 001", U16, RW)
                .default(u(0x1600))
                .range(u(0x1600), u(0x17FF)),
        ],
    },
    ObjectDesc {
        index: 0x1C13,
        name: "Sync Manager 3 PDO Assignment",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RW)
                .default(u(1))
                .range(u(0), u(1)),
            EntryDesc::new(1, "SubIndex 001", U16, RW)
                .default(u(0x1A00))
                .range(u(0x1A00), u(0x1BFF)),
        ],
    },
    ObjectDesc {
        index: 0x2011,
        name: "Warning Bits",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO)
                .default(u(3))
                .range(u(3), u(3)),
            EntryDesc::new(1, "Lower 32 bits of warning word", U32, RO).default(u(0)),
            EntryDesc::new(2, "Middle 32 bits of warning word", U32, RO).default(u(0)),
            EntryDesc::new(3, "Upper 32 bits of warning word", U32, RO).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x2036,
        name: "Motor Peak Current",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Motor Peak Current", U32, RO)
            .default(u(11879))
            .range(u(100), u(300000))],
    },
    ObjectDesc {
        index: 0x2039,
        name: "Torque Constant",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Torque Constant", U32, RO)
            .default(u(321))
            .range(u(1), u(3000))],
    },
    ObjectDesc {
        index: 0x2046,
        name: "Disabling Mode",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Disabling Mode", U16, RW)
            .default(u(0))
            .range(u(0), u(5))],
    },
    ObjectDesc {
        index: 0x204A,
        name: "Active Disabling Speed Threshold",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Active Disabling Speed Threshold", U32, RW)
                .default(u(10000))
                .range(u(0), u(200000)),
        ],
    },
    ObjectDesc {
        index: 0x204B,
        name: "Active Disabling Time",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Active Disabling Time", U32, RW)
            .default(u(10))
            .range(u(0), u(6500))],
    },
    ObjectDesc {
        index: 0x2066,
        name: "Current D Axis",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Current D Axis", I32, RO_TX)
            .default(i(0))
            .range(i(-100000), i(100000))],
    },
    ObjectDesc {
        index: 0x2067,
        name: "Current Q Axis",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Current Q Axis", I32, RO)
            .default(i(0))
            .range(i(-100000), i(100000))],
    },
    ObjectDesc {
        index: 0x2078,
        name: "Negative Limit Switch Status",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Negative Limit Switch Status", U16, RO)
            .default(u(0))
            .range(u(0), u(1))],
    },
    ObjectDesc {
        index: 0x2079,
        name: "Positive Limit Switch Status",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Positive Limit Switch Status", U16, RO)
            .default(u(0))
            .range(u(0), u(1))],
    },
    ObjectDesc {
        index: 0x207B,
        name: "Drive Peak Current",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Drive Peak Current", U32, RO)
            .default(u(11879))
            .range(u(0), u(100000))],
    },
    ObjectDesc {
        index: 0x207C,
        name: "Drive Continuous Current",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Drive Continuous Current", U32, RO)
            .default(u(3959))
            .range(u(0), u(100000))],
    },
    ObjectDesc {
        index: 0x2090,
        name: "Home Status",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Home Status", U16, RO).range(u(0), u(20))],
    },
    ObjectDesc {
        index: 0x20A2,
        name: "Software Enable Status",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Software Enable Status", U16, RO)
            .default(u(0))
            .range(u(0), u(1))],
    },
    ObjectDesc {
        index: 0x20B5,
        name: "Position Error in Position Flag",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Position Error in Position Flag", U16, RO)
                .default(u(0))
                .range(u(0), u(1)),
        ],
    },
    ObjectDesc {
        index: 0x20EE,
        name: "Drive and Motor Maximum Velocity",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Drive and Motor Maximum Velocity", I32, RO)
                .default(i(10))
                .range(i(10), i(9000)),
        ],
    },
    ObjectDesc {
        index: 0x20F0,
        name: "Drive and Motor Maximum Current",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Drive and Motor Maximum Current", I32, RO)
                .default(i(11879))
                .range(i(0), i(100000)),
        ],
    },
    ObjectDesc {
        index: 0x2103,
        name: "Homing Command",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Homing Command", U16, RW)
            .default(u(0))
            .range(u(0), u(255))],
    },
    ObjectDesc {
        index: 0x2113,
        name: "Drive Ready",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Drive Ready", U16, RO)
            .default(u(0))
            .range(u(0), u(1))],
    },
    ObjectDesc {
        index: 0x2340,
        name: "Save Parameters",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Save Parameters", U16, RW)],
    },
    ObjectDesc {
        index: 0x603F,
        name: "Error Code",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Error Code", U16, RO_TX).default(u(0))],
    },
    ObjectDesc {
        index: 0x6040,
        name: "Controlword",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Controlword", U16, RW_RX).default(u(0))],
    },
    ObjectDesc {
        index: 0x6041,
        name: "Statusword",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Statusword", U16, RO_TX).default(u(0))],
    },
    ObjectDesc {
        index: 0x605A,
        name: "Quick Stop Option Code",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Quick Stop Option Code", I16, RW).default(i(0))],
    },
    ObjectDesc {
        index: 0x605B,
        name: "Shutdown Option Code",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Shutdown Option Code", I16, RW)
            .default(i(-1))
            .range(i(-1), i(1))],
    },
    ObjectDesc {
        index: 0x605C,
        name: "Disable Operation Option Code",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Disable Operation Option Code", I16, RW)
            .default(i(-1))
            .range(i(-1), i(1))],
    },
    ObjectDesc {
        index: 0x605D,
        name: "Halt Option Code",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Halt Option Code", I16, RW)
            .default(i(1))
            .range(i(1), i(3))],
    },
    ObjectDesc {
        index: 0x605E,
        name: "Fault Reaction Option Code",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Fault Reaction Option Code", I16, RW)
            .default(i(-1))
            .range(i(-1), i(1))],
    },
    ObjectDesc {
        index: 0x6060,
        name: "Modes of Operation",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Modes of Operation", I8, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6061,
        name: "Modes of Operation Display",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Modes of Operation Display", I8, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6062,
        name: "Position Demand Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Demand Value", I32, RO).default(i(0))],
    },
    ObjectDesc {
        index: 0x6063,
        name: "Position Actual Internal Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Actual Internal Value", I32, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6064,
        name: "Position Actual Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Actual Value", I32, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6065,
        name: "Following Error Window",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Following Error Window", U32, RW_RX).default(u(1))],
    },
    ObjectDesc {
        index: 0x6066,
        name: "Following Error Time Out",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Following Error Time Out", U16, RW).default(u(0))],
    },
    ObjectDesc {
        index: 0x6067,
        name: "Position Window",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Window", U32, RW_RX).default(u(0))],
    },
    ObjectDesc {
        index: 0x6068,
        name: "Position Window Time",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Window Time", U16, RW).default(u(5))],
    },
    ObjectDesc {
        index: 0x606B,
        name: "Velocity Demand Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Demand Value", I32, RO).default(i(0))],
    },
    ObjectDesc {
        index: 0x606C,
        name: "Velocity Actual Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Actual Value", I32, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x606D,
        name: "Velocity Window",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Window", U16, RW).default(u(0))],
    },
    ObjectDesc {
        index: 0x606E,
        name: "Velocity Window Time",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Window Time", U16, RW).default(u(0))],
    },
    ObjectDesc {
        index: 0x606F,
        name: "Velocity Threshold",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Threshold", U16, RW).default(u(0))],
    },
    ObjectDesc {
        index: 0x6070,
        name: "Velocity Threshold Time",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Threshold Time", U16, RW).default(u(0))],
    },
    ObjectDesc {
        index: 0x6071,
        name: "Target Torque",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Target Torque", I16, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6072,
        name: "Max Torque",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Max Torque", U16, RW_RX)
            .default(u(5000))
            .range(u(0), u(5000))],
    },
    ObjectDesc {
        index: 0x6073,
        name: "Maximum Current",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Maximum Current", U16, RW_RX).default(u(0))],
    },
    ObjectDesc {
        index: 0x6074,
        name: "Torque Demand Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Torque Demand Value", I16, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6075,
        name: "Motor Rated Current",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Motor Rated Current", U32, RO).default(u(0))],
    },
    ObjectDesc {
        index: 0x6076,
        name: "Motor Rated Torque",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Motor Rated Torque", U32, RO).default(u(0))],
    },
    ObjectDesc {
        index: 0x6077,
        name: "Torque Actual Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Torque Actual Value", I16, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6078,
        name: "Current Actual Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Current Actual Value", I16, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6079,
        name: "DC Link Circuit Voltage",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "DC Link Circuit Voltage", U32, RO_TX).default(u(0))],
    },
    ObjectDesc {
        index: 0x607A,
        name: "Target Position",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Target Position", I32, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x607C,
        name: "Home Offset",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Home Offset", I32, RW).default(i(0))],
    },
    ObjectDesc {
        index: 0x607D,
        name: "Software Position Limit",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            EntryDesc::new(1, "SubIndex 001", I32, RW).default(i(0)),
            EntryDesc::new(2, "SubIndex 002", I32, RW).default(i(0)),
        ],
    },
    ObjectDesc {
        index: 0x607E,
        name: "Polarity",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Polarity", U8, RW)
            .default(u(0))
            .range(u(0), u(192))],
    },
    ObjectDesc {
        index: 0x607F,
        name: "Maximum Profile Velocity",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Maximum Profile Velocity", U32, RW)
            .default(u(1))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x6080,
        name: "Motor Maximum Speed",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Motor Maximum Speed", U32, RW).default(u(0))],
    },
    ObjectDesc {
        index: 0x6081,
        name: "Profile Velocity",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Profile Velocity", U32, RW_RX).default(u(0))],
    },
    ObjectDesc {
        index: 0x6083,
        name: "Profile Acceleration",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Profile Acceleration", U32, RW_RX)
            .default(u(1000))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x6084,
        name: "Profile Deceleration",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Profile Deceleration", U32, RW_RX)
            .default(u(1000))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x6085,
        name: "Quick Stop Deceleration",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Quick Stop Deceleration", U32, RW)
            .default(u(1))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x6087,
        name: "Torque Slope",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Torque Slope", U32, RW_RX)
            .default(u(0))
            .range(u(0), u(30000000))],
    },
    ObjectDesc {
        index: 0x608F,
        name: "Position Encoder Resolution",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            EntryDesc::new(1, "SubIndex 001", U32, RO)
                .default(u(2048))
                .range(u(16), u(10000000)),
            EntryDesc::new(2, "SubIndex 002", U32, RO)
                .default(u(1))
                .range(u(1), u(1)),
        ],
    },
    ObjectDesc {
        index: 0x6091,
        name: "Gear Ratio",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            EntryDesc::new(1, "SubIndex 001", U32, RW)
                .default(u(1))
                .range(u(1), u(4294967295)),
            EntryDesc::new(2, "SubIndex 002", U32, RW)
                .default(u(1))
                .range(u(1), u(4294967295)),
        ],
    },
    ObjectDesc {
        index: 0x6092,
        name: "Feed Constant",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            EntryDesc::new(1, "SubIndex 001", U32, RW)
                .default(u(1))
                .range(u(1), u(4294967295)),
            EntryDesc::new(2, "SubIndex 002", U32, RW)
                .default(u(1))
                .range(u(1), u(4294967295)),
        ],
    },
    ObjectDesc {
        index: 0x6098,
        name: "Homing Method",
        code: ObjectCode::Var,
        // Range "-192 to 35" (manual line 6265; §5.8: "1 to 35"): the maximum all readings
        // share; no lower bound (Integer8 cannot hold -192, manual_facts obj.6098).
        entries: &[EntryDesc::new(0, "Homing Method", I8, RW)
            .default(i(1))
            .range(ConstValue::None, i(35))],
    },
    ObjectDesc {
        index: 0x6099,
        name: "Homing Speeds",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            EntryDesc::new(1, "SubIndex 001", U32, RW)
                .default(u(1))
                .range(u(1), u(4294967295)),
            EntryDesc::new(2, "SubIndex 002", U32, RW)
                .default(u(1))
                .range(u(1), u(4294967295)),
        ],
    },
    ObjectDesc {
        index: 0x609A,
        name: "Homing Acceleration",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Homing Acceleration", U32, RW)
            .default(u(1))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x60B0,
        name: "Position Offset",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Offset", I32, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x60B1,
        name: "Velocity Offset",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Velocity Offset", I32, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x60B2,
        name: "Torque Offset",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Torque Offset", I16, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x60B8,
        name: "Touch Probe Function",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Touch Probe Function", U16, RW_RX).default(u(0))],
    },
    ObjectDesc {
        index: 0x60B9,
        name: "Touch Probe Status",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Touch Probe Status", U16, RO_TX).default(u(0))],
    },
    ObjectDesc {
        index: 0x60BA,
        name: "Touch Probe 1 Position Positive Value",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch Probe 1 Position Positive Value", I32, RO_TX).default(i(0)),
        ],
    },
    ObjectDesc {
        index: 0x60BB,
        name: "Touch Probe 1 Position Negative Value",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch Probe 1 Position Negative Value", I32, RO_TX).default(i(0)),
        ],
    },
    ObjectDesc {
        index: 0x60BC,
        name: "Touch Probe 2 Position Positive Value",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch Probe 2 Position Positive Value", I32, RO_TX).default(i(0)),
        ],
    },
    ObjectDesc {
        index: 0x60BD,
        name: "Touch Probe 2 Position Negative Value",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch Probe 2 Position Negative Value", I32, RO_TX).default(i(0)),
        ],
    },
    ObjectDesc {
        index: 0x60C2,
        name: "Interpolation Time Period",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            // DISCREPANCY: the object table gives :01 4–64 in 250 µs units and :02 read-only
            // −4; the drive's own set-up example (Beckhoff) writes :01 = 1 and :02 = −3 for
            // 1 ms, the standard form. ecdrive takes the set-up's reading: :02 writable, :01
            // any UNSIGNED8 (the cycle they tell must still be 250 µs–16 ms in 250 µs steps).
            EntryDesc::new(1, "Interpolation time period value", U8, RW)
                .default(u(4))
                .range(u(1), u(255)),
            EntryDesc::new(2, "Interpolation time index", I8, RW)
                .default(i(-4))
                .range(i(-9), i(-3)),
        ],
    },
    ObjectDesc {
        index: 0x60C5,
        name: "Max Acceleration",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Max Acceleration", U32, RW)
            .default(u(4294967295))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x60C6,
        name: "Max Deceleration",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Max Deceleration", U32, RW)
            .default(u(4294967295))
            .range(u(1), u(4294967295))],
    },
    ObjectDesc {
        index: 0x60D5,
        name: "Touch probe 1 positive edge counter",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch probe 1 positive edge counter", U16, RO_TX).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x60D6,
        name: "Touch probe 1 negative edge counter",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch probe 1 negative edge counter", U16, RO_TX).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x60D7,
        name: "Touch probe 2 positive edge counter",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch probe 2 positive edge counter", U16, RO_TX).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x60D8,
        name: "Touch probe 2 negative edge counter",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Touch probe 2 negative edge counter", U16, RO_TX).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x60F4,
        name: "Following Error Actual Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Following Error Actual Value", I32, RO_TX).default(i(0))],
    },
    ObjectDesc {
        index: 0x60FC,
        name: "Position Demand Internal Value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Position Demand Internal Value", I32, RO).default(i(0))],
    },
    ObjectDesc {
        index: 0x60FD,
        name: "Digital Inputs",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Digital Inputs", U32, RO_TX).default(u(0))],
    },
    ObjectDesc {
        index: 0x60FE,
        name: "Digital Outputs",
        code: ObjectCode::Array,
        entries: &[
            EntryDesc::new(0, "SubIndex 000", U8, RO)
                .default(u(2))
                .range(u(2), u(2)),
            EntryDesc::new(1, "SubIndex 001", U32, RW_RX).default(u(0)),
            EntryDesc::new(2, "SubIndex 002", U32, RW_RX).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x60FF,
        name: "Target Velocity",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Target Velocity", I32, RW_RX).default(i(0))],
    },
    ObjectDesc {
        index: 0x6502,
        name: "Supported Drive Modes",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Supported Drive Modes", U32, RO)
            .default(u(0x3AD))
            .range(u(0x3AD), u(0x3AD))],
    },
];
