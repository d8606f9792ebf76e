//! The generic CoE test device: a small CiA 402-style servo with a real CoE mailbox, variable
//! PDO mapping and DC synchronisation, built on the CoE server ([`crate::coe`]).
//!
//! It is what `ecdrive sim` serves until the emulated drives exist, and what the plain-ethercrab
//! and SOEM acceptance tests remap in PRE-OP. Its application is deliberately simple but
//! honest: the CiA 402 power state machine on the controlword, position following the target in
//! csp, integrating the target velocity in csv, the missed-SYNC0 counter in 0x1C32:0B, and the
//! synchronisation checks a drive makes at SAFE-OP→OP.

use crate::coe::hooks::{AllowedValues, Chain, Mirror};
use crate::coe::{CoeConfig, CoeServer, Emergency, OdError, OdStore};
use crate::device::{Device, ProcessDataSizes, StateRequest, SyncEvent, SyncKind};
use crate::ec::{AlState, AlStatusCode};
use crate::od::{
    ConstValue, DataType, EntryAccess, EntryDesc, ObjectAddress, ObjectCode, ObjectDesc,
    SdoAbortCode,
};
use crate::pdo::{Direction, Mapping};
use crate::quirks::{Capabilities, Quirk, Quirks};
use crate::sii::{
    CoeDetails, DcOpMode, DeviceDescription, FmmuUsage, Identity, MailboxDesc, MailboxProtocols,
    SmDesc, SmEnable, SmType,
};

use super::io::TEST_VENDOR_ID;

/// Product code of the generic CoE device.
pub const GENERIC_COE_PRODUCT: u32 = 0x0000_0402;
/// Order code (ethercrab's `SubDevice::name()`).
pub const GENERIC_COE_ORDER: &str = "ECD-COE402";
/// Device name (SII and 0x1008).
pub const GENERIC_COE_NAME: &str = "ecdrive generic CoE device";
/// Mailbox size of each direction.
pub const GENERIC_COE_MBX: u16 = 128;

const RO: EntryAccess = EntryAccess::RO;
const RW: EntryAccess = EntryAccess::RW;
const RW_PREOP: EntryAccess = EntryAccess::RW_PREOP;
const RW_RX: EntryAccess = EntryAccess::RW.union(EntryAccess::RXPDO);
const RO_TX: EntryAccess = EntryAccess::RO.union(EntryAccess::TXPDO);

const U8: DataType = DataType::Unsigned8;
const U16: DataType = DataType::Unsigned16;
const U32: DataType = DataType::Unsigned32;
const I8: DataType = DataType::Integer8;
const I32: DataType = DataType::Integer32;

const fn u(v: u64) -> ConstValue {
    ConstValue::Uint(v)
}

const fn i(v: i64) -> ConstValue {
    ConstValue::Int(v)
}

macro_rules! var {
    ($index:literal, $name:literal, $ty:expr, $acc:expr, $def:expr) => {
        ObjectDesc {
            index: $index,
            name: $name,
            code: ObjectCode::Var,
            entries: &[EntryDesc::new(0, $name, $ty, $acc).default($def)],
        }
    };
}

const fn map_entries(defaults: [u64; 8], n: u64) -> [EntryDesc; 9] {
    let mut out = [EntryDesc::new(0, "Number of mapped objects", U8, RW_PREOP); 9];
    out[0] = out[0].default(u(n)).range(u(0), u(8));
    let mut k = 1;
    while k < 9 {
        out[k] =
            EntryDesc::new(k as u8, "Mapped object", U32, RW_PREOP).default(u(defaults[k - 1]));
        k += 1;
    }
    out
}

static RXPDO1: [EntryDesc; 9] = map_entries([0x6040_0010, 0x607A_0020, 0, 0, 0, 0, 0, 0], 2);
static RXPDO2: [EntryDesc; 9] =
    map_entries([0x6040_0010, 0x60FF_0020, 0x6060_0008, 0, 0, 0, 0, 0], 3);
static TXPDO1: [EntryDesc; 9] = map_entries([0x6041_0010, 0x6064_0020, 0, 0, 0, 0, 0, 0], 2);
static TXPDO2: [EntryDesc; 9] = map_entries(
    [
        0x6041_0010,
        0x6064_0020,
        0x606C_0020,
        0x6061_0008,
        0,
        0,
        0,
        0,
    ],
    4,
);

const fn sync_params() -> [EntryDesc; 10] {
    [
        EntryDesc::new(0, "Number of entries", U8, RO).default(u(0x20)),
        EntryDesc::new(1, "Synchronization type", U16, RW_PREOP).default(u(0)),
        EntryDesc::new(2, "Cycle time", U32, RW_PREOP).default(u(0)),
        EntryDesc::new(3, "Shift time", U32, RO).default(u(0)),
        // bit 0 free run, bit 1 SM-synchronous, bits 2–3 = 01 DC SYNC0.
        EntryDesc::new(4, "Synchronization types supported", U16, RO).default(u(0x0007)),
        EntryDesc::new(5, "Minimum cycle time", U32, RO).default(u(MIN_CYCLE_NS as u64)),
        EntryDesc::new(6, "Calc and copy time", U32, RO).default(u(10_000)),
        EntryDesc::new(11, "SM event missed counter", U16, RO).default(u(0)),
        EntryDesc::new(12, "Cycle time too small counter", U16, RO).default(u(0)),
        EntryDesc::new(32, "Sync error", DataType::Boolean, RO).default(u(0)),
    ]
}

static SYNC_OUT: [EntryDesc; 10] = sync_params();
static SYNC_IN: [EntryDesc; 10] = sync_params();

/// Smallest SYNC0 cycle the generic device accepts (0x1C32:05), in ns.
pub const MIN_CYCLE_NS: u32 = crate::rec::GENERIC_COE_MIN_CYCLE_NS;

/// The object dictionary of the generic CoE device.
pub static OBJECTS: &[ObjectDesc] = &[
    // Device type: CiA 402 (0x0192), servo (0x0002).
    var!(0x1000, "Device type", U32, RO, u(0x0002_0192)),
    var!(0x1001, "Error register", U8, RO, u(0)),
    ObjectDesc {
        index: 0x1008,
        name: "Manufacturer device name",
        code: ObjectCode::Var,
        entries: &[
            EntryDesc::new(0, "Manufacturer device name", DataType::VisibleString, RO)
                .default(ConstValue::Str(GENERIC_COE_NAME)),
        ],
    },
    ObjectDesc {
        index: 0x1009,
        name: "Manufacturer hardware version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(
            0,
            "Manufacturer hardware version",
            DataType::VisibleString,
            RO,
        )
        .default(ConstValue::Str("emulated"))],
    },
    ObjectDesc {
        index: 0x100A,
        name: "Manufacturer software version",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(
            0,
            "Manufacturer software version",
            DataType::VisibleString,
            RO,
        )
        .default(ConstValue::Str(concat!(
            "ecdrive ",
            env!("CARGO_PKG_VERSION")
        )))],
    },
    ObjectDesc {
        index: 0x1018,
        name: "Identity",
        code: ObjectCode::Record,
        entries: &[
            EntryDesc::new(0, "Number of entries", U8, RO).default(u(4)),
            EntryDesc::new(1, "Vendor ID", U32, RO).default(u(TEST_VENDOR_ID as u64)),
            EntryDesc::new(2, "Product code", U32, RO).default(u(GENERIC_COE_PRODUCT as u64)),
            EntryDesc::new(3, "Revision number", U32, RO).default(u(0x0001_0000)),
            EntryDesc::new(4, "Serial number", U32, RO).default(u(0)),
        ],
    },
    ObjectDesc {
        index: 0x1600,
        name: "RxPDO 1 (csp)",
        code: ObjectCode::Array,
        entries: &RXPDO1,
    },
    ObjectDesc {
        index: 0x1601,
        name: "RxPDO 2 (csv)",
        code: ObjectCode::Array,
        entries: &RXPDO2,
    },
    ObjectDesc {
        index: 0x1A00,
        name: "TxPDO 1",
        code: ObjectCode::Array,
        entries: &TXPDO1,
    },
    ObjectDesc {
        index: 0x1A01,
        name: "TxPDO 2",
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
        entries: &SYNC_OUT,
    },
    ObjectDesc {
        index: 0x1C33,
        name: "SM input parameter",
        code: ObjectCode::Record,
        entries: &SYNC_IN,
    },
    var!(0x6040, "Controlword", U16, RW_RX, u(0)),
    var!(0x6041, "Statusword", U16, RO_TX, u(0x0250)),
    var!(0x6060, "Modes of operation", I8, RW_RX, i(8)),
    var!(0x6061, "Modes of operation display", I8, RO_TX, i(8)),
    var!(0x6064, "Position actual value", I32, RO_TX, i(0)),
    var!(0x606C, "Velocity actual value", I32, RO_TX, i(0)),
    var!(0x607A, "Target position", I32, RW_RX, i(0)),
    var!(0x60FF, "Target velocity", I32, RW_RX, i(0)),
    // Supported drive modes: csp (bit 7), csv (bit 8).
    var!(0x6502, "Supported drive modes", U32, RO, u(0x0000_0180)),
    var!(0x2000, "User parameter", U32, RW, u(0)),
    ObjectDesc {
        index: 0x2001,
        name: "User text",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "User text", DataType::VisibleString, RW)
            .bits(USER_TEXT_LEN as u16 * 8)
            .default(ConstValue::Str(""))],
    },
];

/// Size of the writable string 0x2001 in bytes: larger than one mailbox, so that transfers of
/// it are segmented in both directions.
pub const USER_TEXT_LEN: usize = 300;

const CONTROLWORD: ObjectAddress = ObjectAddress::new(0x6040, 0);
const STATUSWORD: ObjectAddress = ObjectAddress::new(0x6041, 0);
const MODE: ObjectAddress = ObjectAddress::new(0x6060, 0);
const MODE_DISPLAY: ObjectAddress = ObjectAddress::new(0x6061, 0);
const POSITION: ObjectAddress = ObjectAddress::new(0x6064, 0);
const VELOCITY: ObjectAddress = ObjectAddress::new(0x606C, 0);
const TARGET_POSITION: ObjectAddress = ObjectAddress::new(0x607A, 0);
const TARGET_VELOCITY: ObjectAddress = ObjectAddress::new(0x60FF, 0);
const TARGET_TORQUE: ObjectAddress = ObjectAddress::new(0x6071, 0);
const TORQUE: ObjectAddress = ObjectAddress::new(0x6077, 0);
/// The generic servo's load in cst: rated torque (1000 ‰) accelerates it by this many
/// counts/s² (a made-up load, not a drive fact: the emulation of a file's drive follows its
/// torque set-point so that a master sees cst work).
const CST_COUNTS_PER_S2_AT_RATED: i64 = 1_000_000;
const SYNC_TYPE: ObjectAddress = ObjectAddress::new(0x1C32, 1);
const CYCLE_TIME: ObjectAddress = ObjectAddress::new(0x1C32, 2);
const MISSED: ObjectAddress = ObjectAddress::new(0x1C32, 11);

/// CiA 402 power states (the subset the generic device runs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PowerState {
    /// Switch on disabled.
    SwitchOnDisabled,
    /// Ready to switch on.
    ReadyToSwitchOn,
    /// Switched on.
    SwitchedOn,
    /// Operation enabled.
    OperationEnabled,
    /// Fault.
    Fault,
}

impl PowerState {
    fn statusword(self) -> u16 {
        // Bit 9 remote, bit 4 voltage enabled where powered.
        let s = match self {
            Self::SwitchOnDisabled => 0x0040,
            Self::ReadyToSwitchOn => 0x0031,
            Self::SwitchedOn => 0x0033,
            Self::OperationEnabled => 0x0037,
            Self::Fault => 0x0008,
        };
        s | 0x0200
    }

    /// The next state for a controlword (CiA 402 device control commands).
    fn next(self, cw: u16, prev_cw: u16) -> Self {
        use PowerState::*;
        let fault_reset = cw & 0x0080 != 0 && prev_cw & 0x0080 == 0;
        if self == Fault {
            return if fault_reset { SwitchOnDisabled } else { Fault };
        }
        let disable_voltage = cw & 0x0002 == 0;
        let quick_stop = cw & 0x0006 == 0x0002;
        let shutdown = cw & 0x0087 == 0x0006;
        let switch_on = cw & 0x008F == 0x0007;
        let enable = cw & 0x008F == 0x000F;
        if disable_voltage || quick_stop {
            return SwitchOnDisabled;
        }
        match self {
            SwitchOnDisabled if shutdown => ReadyToSwitchOn,
            ReadyToSwitchOn if switch_on => SwitchedOn,
            ReadyToSwitchOn if enable => OperationEnabled,
            SwitchedOn if enable => OperationEnabled,
            SwitchedOn | OperationEnabled if shutdown => ReadyToSwitchOn,
            OperationEnabled if switch_on => SwitchedOn,
            s => s,
        }
    }
}

/// What the generic device has seen, for tests.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CoeObservations {
    /// `sync` calls.
    pub cycles: u64,
    /// SYNC0 events.
    pub sync0_events: u64,
    /// SYNC0 events in OP without fresh outputs.
    pub missed_in_op: u64,
    /// SYNC0 cycle time of the last SYNC0 event.
    pub sync0_cycle_ns: u32,
    /// State changes `(from, to, error)`.
    pub transitions: Vec<(AlState, AlState, Option<AlStatusCode>)>,
}

/// One mapped entry in a process image.
#[derive(Debug, Clone, Copy)]
struct Slot {
    addr: ObjectAddress,
    bit: usize,
    bits: usize,
}

/// The generic CoE test device. See the [module documentation](self).
pub struct GenericCoeDevice {
    serial: u32,
    coe: CoeServer,
    od: OdStore,
    rx: Vec<Slot>,
    tx: Vec<Slot>,
    power: PowerState,
    prev_cw: u16,
    quirks: Quirks,
    /// The SII description and order code, when the device was built from an ESI file.
    esi: Option<(Box<DeviceDescription>, &'static str)>,
    /// Whether the device runs CiA 402 device control (0x6040/0x6041); without it, an I/O
    /// device whose inputs echo its outputs.
    cia402: bool,
    /// The process data of a device whose file describes it in a way no assignment object
    /// can hold (PDO entries naming their own mapping object): the file's default PDOs,
    /// fixed.
    fixed: Option<Mapping>,
    /// The file's default PDOs, for a device whose mapping objects do not read as one.
    file_default: Option<Mapping>,
    /// What the device has seen.
    pub seen: CoeObservations,
}

impl core::fmt::Debug for GenericCoeDevice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("GenericCoeDevice")
            .field("serial", &self.serial)
            .field("power", &self.power)
            .finish_non_exhaustive()
    }
}

fn build_store(serial: u32) -> Result<OdStore, OdError> {
    let mut od = OdStore::new(OBJECTS)?;
    od.dict_mut()
        .set_uint(ObjectAddress::new(0x1018, 4), u64::from(serial))
        .map_err(|code| OdError {
            at: "0x1018:04".into(),
            reason: format!("serial number not accepted: {code}"),
        })?;
    Ok(od.with_hooks(
        Chain::new()
            .with(AllowedValues {
                address: SYNC_TYPE,
                values: &[0, 1, 2],
                code: SdoAbortCode::VALUE_RANGE,
            })
            .with(Mirror {
                a: SYNC_TYPE,
                b: ObjectAddress::new(0x1C33, 1),
            })
            .with(Mirror {
                a: CYCLE_TIME,
                b: ObjectAddress::new(0x1C33, 2),
            }),
    ))
}

impl GenericCoeDevice {
    /// A device with a serial number (in the SII and 0x1018:04). Fails only if the built-in
    /// dictionary table is inconsistent.
    pub fn new(serial: u32) -> Result<Self, OdError> {
        Ok(Self {
            serial,
            coe: CoeServer::new(CoeConfig::default()),
            od: build_store(serial)?,
            rx: Vec::new(),
            tx: Vec::new(),
            power: PowerState::SwitchOnDisabled,
            prev_cw: 0,
            quirks: Quirks::NONE,
            esi: None,
            cia402: true,
            fixed: None,
            file_default: None,
            seen: CoeObservations::default(),
        })
    }

    /// The same application behind a device described by an ESI file: the file's identity,
    /// SII (SyncManagers, PDOs, DC modes, mailbox) and object dictionary with its defaults, so
    /// that a master sees the vendor's device; the behaviour is this generic servo's (CiA 402
    /// device control, csp/csv following, the synchronisation checks at SAFE-OP → OP against
    /// 0x1C32). For drives ecdrive has no emulation of: a master configured from the same file
    /// meets what the file promises. The device must have 0x6040 and 0x6041.
    pub fn from_esi(
        file: &crate::esi::EsiFile,
        dev: &crate::esi::Device,
        serial: u32,
    ) -> Result<Self, String> {
        let dictionary = super::esi_dictionary::emulated_dictionary(dev);
        let has = |a: u16| dictionary.iter().any(|o| o.index == a);
        let cia402 = has(0x6040) && has(0x6041);
        let fixed = if has(0x1C12) || has(0x1C13) {
            None
        } else {
            Some(dev.default_mapping().map_err(|e| e.to_string())?)
        };
        let mut od = OdStore::new(dictionary).map_err(|e| e.to_string())?;
        let _ = od
            .dict_mut()
            .set_uint(ObjectAddress::new(0x1018, 4), u64::from(serial));
        let writable = |a: ObjectAddress| {
            dictionary
                .iter()
                .find(|o| o.index == a.index)
                .and_then(|o| o.entries.iter().find(|e| e.sub == a.sub))
                .is_some_and(|e| e.access.contains(EntryAccess::WRITE_PREOP))
        };
        let mut hooks = Chain::new();
        for (a, b) in [
            (SYNC_TYPE, ObjectAddress::new(0x1C33, 1)),
            (CYCLE_TIME, ObjectAddress::new(0x1C33, 2)),
        ] {
            if writable(a) && writable(b) {
                hooks = hooks.with(Mirror { a, b });
            }
        }
        let od = od.with_hooks(hooks);
        let description =
            crate::sii::from_esi(file.vendor.id, dev, serial).map_err(|e| e.to_string())?;
        let coe = dev.mailbox.as_ref().and_then(|m| m.coe.as_ref());
        Ok(Self {
            serial,
            coe: CoeServer::new(CoeConfig {
                complete_access: coe.is_some_and(|c| c.complete_access),
                sdo_info: coe.is_none_or(|c| c.sdo_info),
                ..CoeConfig::default()
            }),
            od,
            rx: Vec::new(),
            tx: Vec::new(),
            power: PowerState::SwitchOnDisabled,
            prev_cw: 0,
            quirks: Quirks::NONE,
            esi: Some((
                Box::new(description),
                String::leak(dev.type_.name_text.clone()),
            )),
            seen: CoeObservations::default(),
            cia402,
            fixed,
            file_default: dev.default_mapping().ok(),
        })
    }

    /// The process data mapping in force: the assignment and mapping objects, or the file's
    /// fixed default PDOs.
    fn mapping(&self) -> Result<Mapping, ()> {
        match &self.fixed {
            Some(m) => Ok(m.clone()),
            None => self.od.mapping().map_err(|_| ()),
        }
        .or_else(|()| {
            // A file whose PDOs sit outside CiA 301's index ranges (TxPDOs at 0x1700): the
            // objects cannot be read as a mapping, the firmware still has its PDOs.
            self.file_default.clone().ok_or(())
        })
    }

    /// What the device has, for [`Quirks::check_for`]: a CoE mailbox and CiA 402 device
    /// control, but no 0x60F4.
    pub const CAPABILITIES: Capabilities = Capabilities {
        coe: true,
        cia402: true,
        following_error: false,
    };

    /// The same device behaving like one ecdrive did not write ([`crate::quirks`]).
    /// [`Quirk::FollowingErrorZero`] does not apply (it has no 0x60F4).
    pub fn with_quirks(mut self, quirks: Quirks) -> Result<Self, String> {
        let order = self.esi.as_ref().map_or(GENERIC_COE_ORDER, |(_, o)| *o);
        quirks.check_for(order, Self::CAPABILITIES)?;
        self.quirks = quirks;
        self.coe = CoeServer::new(CoeConfig {
            quirks,
            ..*self.coe.config()
        });
        self.od.set_quirks(quirks);
        Ok(self)
    }

    /// The CoE server's counters (SDO downloads accepted, aborts sent, …).
    pub fn coe_stats(&self) -> crate::coe::CoeStats {
        self.coe.stats()
    }

    /// The object dictionary (device view).
    pub fn od(&self) -> &OdStore {
        &self.od
    }

    /// The object dictionary, mutable.
    pub fn od_mut(&mut self) -> &mut OdStore {
        &mut self.od
    }

    /// The CoE server (e.g. to queue an emergency).
    pub fn coe_mut(&mut self) -> &mut CoeServer {
        &mut self.coe
    }

    /// Queue a CoE emergency for the master.
    pub fn push_emergency(&mut self, emcy: Emergency) {
        self.coe.push_emergency(emcy);
    }

    /// The CiA 402 power state.
    pub fn power_state(&self) -> PowerState {
        self.power
    }

    fn layout(mapping: &Mapping, dir: Direction) -> Vec<Slot> {
        let mut out = Vec::new();
        let mut bit = 0usize;
        for pdo in mapping.pdos(dir) {
            for e in pdo.entries.iter() {
                if !e.is_padding() {
                    out.push(Slot {
                        addr: e.address(),
                        bit,
                        bits: usize::from(e.bits),
                    });
                }
                bit += usize::from(e.bits);
            }
        }
        out
    }

    fn i32(&self, a: ObjectAddress) -> i32 {
        self.od
            .dict()
            .int(a)
            .and_then(|v| i32::try_from(v).ok())
            .unwrap_or(0)
    }

    fn application(&mut self, event: &SyncEvent) {
        let cw = self.od.dict().uint(CONTROLWORD).unwrap_or(0) as u16;
        let mut power = if event.outputs_enabled {
            let p = self.power.next(cw, self.prev_cw);
            if self.quirks.has(Quirk::NoStateSkipping)
                && self.power == PowerState::ReadyToSwitchOn
                && p == PowerState::OperationEnabled
            {
                // Switch on and enable operation at once (3 + 4) is not taken.
                self.power
            } else {
                p
            }
        } else if self.power == PowerState::OperationEnabled || self.power == PowerState::SwitchedOn
        {
            // Outputs invalid (SAFE-OP): a drive drops its power stage.
            PowerState::SwitchOnDisabled
        } else {
            self.power
        };
        if event.outputs_enabled && event.kind == SyncKind::Sync0 && !event.outputs_fresh() {
            let missed = self.od.dict().uint(MISSED).unwrap_or(0);
            let _ = self
                .od
                .dict_mut()
                .set_uint(MISSED, (missed + 1).min(0xFFFF));
        }
        self.prev_cw = cw;
        let mode = self.i32(MODE);
        let _ = self.od.dict_mut().set_int(MODE_DISPLAY, i64::from(mode));
        if power == PowerState::OperationEnabled {
            match mode {
                8 => {
                    let t = self.i32(TARGET_POSITION);
                    let p = self.i32(POSITION);
                    let _ = self.od.dict_mut().set_int(POSITION, i64::from(t));
                    let dt = event.cycle_time_ns.max(1) as i64;
                    let v = (i64::from(t) - i64::from(p)) * 1_000_000_000 / dt;
                    let _ = self
                        .od
                        .dict_mut()
                        .set_int(VELOCITY, v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)));
                }
                9 => {
                    let v = self.i32(TARGET_VELOCITY);
                    let dt = if event.cycle_time_ns > 0 {
                        i64::from(event.cycle_time_ns)
                    } else {
                        1_000_000
                    };
                    let p = i64::from(self.i32(POSITION)) + i64::from(v) * dt / 1_000_000_000;
                    let _ = self.od.dict_mut().set_int(POSITION, i64::from(p as i32));
                    let _ = self.od.dict_mut().set_int(VELOCITY, i64::from(v));
                }
                10 => {
                    let t = i64::from(self.i32(TARGET_TORQUE).clamp(-32768, 32767));
                    let dt = if event.cycle_time_ns > 0 {
                        i64::from(event.cycle_time_ns)
                    } else {
                        1_000_000
                    };
                    let v0 = i64::from(self.i32(VELOCITY));
                    let v = (v0 + t * CST_COUNTS_PER_S2_AT_RATED / 1000 * dt / 1_000_000_000)
                        .clamp(i64::from(i32::MIN), i64::from(i32::MAX));
                    let p = i64::from(self.i32(POSITION)) + v * dt / 1_000_000_000;
                    let _ = self.od.dict_mut().set_int(POSITION, i64::from(p as i32));
                    let _ = self.od.dict_mut().set_int(VELOCITY, v);
                    let _ = self.od.dict_mut().set_int(TORQUE, t);
                }
                _ => {
                    // Unsupported mode: a real drive faults.
                    power = PowerState::Fault;
                }
            }
        } else {
            let _ = self.od.dict_mut().set_int(VELOCITY, 0);
            let _ = self.od.dict_mut().set_int(TORQUE, 0);
        }
        self.power = power;
        let _ = self
            .od
            .dict_mut()
            .set_uint(STATUSWORD, u64::from(power.statusword()));
    }
}

/// Copy `bits` bits from `src` at bit `from` to `dst` at bit `to` (LSB first).
fn copy_bits(src: &[u8], from: usize, dst: &mut [u8], to: usize, bits: usize) {
    if from % 8 == 0 && to % 8 == 0 && bits % 8 == 0 {
        let n = bits / 8;
        if let (Some(s), Some(d)) = (
            src.get(from / 8..from / 8 + n),
            dst.get_mut(to / 8..to / 8 + n),
        ) {
            d.copy_from_slice(s);
        }
        return;
    }
    for k in 0..bits {
        let (sb, db) = (from + k, to + k);
        let v = src.get(sb / 8).is_some_and(|b| b >> (sb % 8) & 1 != 0);
        if let Some(d) = dst.get_mut(db / 8) {
            let m = 1u8 << (db % 8);
            *d = if v { *d | m } else { *d & !m };
        }
    }
}

impl Device for GenericCoeDevice {
    fn quirks(&self) -> Quirks {
        self.quirks
    }

    fn description(&self) -> DeviceDescription {
        if let Some((d, _)) = &self.esi {
            return (**d).clone();
        }
        DeviceDescription {
            identity: Identity {
                vendor_id: TEST_VENDOR_ID,
                product_code: GENERIC_COE_PRODUCT,
                revision: 0x0001_0000,
                serial: self.serial,
            },
            order: GENERIC_COE_ORDER.into(),
            name: GENERIC_COE_NAME.into(),
            group: "ecdrive test devices".into(),
            mailbox: Some(MailboxDesc {
                rx_offset: 0x1000,
                rx_size: GENERIC_COE_MBX,
                tx_offset: 0x1080,
                tx_size: GENERIC_COE_MBX,
                protocols: MailboxProtocols::COE,
                bootstrap: None,
            }),
            coe_details: if self.quirks.has(Quirk::NoSdoInfo) {
                CoeDetails::empty()
            } else {
                CoeDetails::SDO_INFO
            } | CoeDetails::SDO
                | CoeDetails::PDO_ASSIGN
                | CoeDetails::PDO_CONFIG
                | CoeDetails::COMPLETE_ACCESS,
            ds402_channels: 1,
            sync_managers: vec![
                SmDesc {
                    start: 0x1000,
                    length: GENERIC_COE_MBX,
                    control: 0x26,
                    enable: SmEnable::ENABLE,
                    kind: SmType::MailboxOut,
                },
                SmDesc {
                    start: 0x1080,
                    length: GENERIC_COE_MBX,
                    control: 0x22,
                    enable: SmEnable::ENABLE,
                    kind: SmType::MailboxIn,
                },
                SmDesc {
                    start: 0x1100,
                    length: 0,
                    control: 0x64,
                    enable: SmEnable::ENABLE,
                    kind: SmType::Outputs,
                },
                SmDesc {
                    start: 0x1400,
                    length: 0,
                    control: 0x20,
                    enable: SmEnable::ENABLE,
                    kind: SmType::Inputs,
                },
            ],
            fmmus: vec![FmmuUsage::Outputs, FmmuUsage::Inputs, FmmuUsage::SmStatus],
            dc_modes: vec![
                DcOpMode {
                    name: "FreeRun".into(),
                    description: "Free run / SM-synchronous".into(),
                    assign_activate: 0x0000,
                    cycle_time0: 0,
                    shift_time0: 0,
                    shift_time1: 0,
                    sync0_cycle_factor: 0,
                    sync1_cycle_factor: 0,
                },
                DcOpMode {
                    name: "DC".into(),
                    description: "DC SYNC0".into(),
                    assign_activate: 0x0300,
                    cycle_time0: 0,
                    shift_time0: 0,
                    shift_time1: 0,
                    sync0_cycle_factor: 1,
                    sync1_cycle_factor: 0,
                },
            ],
            ..Default::default()
        }
    }

    fn process_data_sizes(&self) -> ProcessDataSizes {
        match self.mapping() {
            Ok(m) => ProcessDataSizes {
                outputs: m.bytes(Direction::Rx),
                inputs: m.bytes(Direction::Tx),
            },
            Err(_) => ProcessDataSizes::default(),
        }
    }

    fn request_state(&mut self, r: &StateRequest) -> Result<(), AlStatusCode> {
        match (r.from, r.to) {
            (AlState::PreOp, AlState::SafeOp) => {
                self.mapping()
                    .map_err(|_| AlStatusCode::INVALID_OUTPUT_MAPPING)?;
                Ok(())
            }
            (AlState::SafeOp, AlState::Op) => {
                let sync = self.od.dict().uint(SYNC_TYPE).unwrap_or(0);
                if sync == 2 {
                    if !r.dc.sync0_active {
                        return Err(AlStatusCode::INVALID_DC_SYNC_CONFIG);
                    }
                    if r.dc.sync0_cycle_ns < MIN_CYCLE_NS {
                        return Err(AlStatusCode::DC_INVALID_CYCLE_TIME);
                    }
                    let want = self.od.dict().uint(CYCLE_TIME).unwrap_or(0);
                    if want != 0 && want != u64::from(r.dc.sync0_cycle_ns) {
                        return Err(AlStatusCode::DC_SYNC0_CYCLE_TIME);
                    }
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    fn state_changed(&mut self, from: AlState, to: AlState, error: Option<AlStatusCode>) {
        self.seen.transitions.push((from, to, error));
        if to == AlState::SafeOp && from == AlState::PreOp {
            if let Ok(m) = self.mapping() {
                self.rx = Self::layout(&m, Direction::Rx);
                self.tx = Self::layout(&m, Direction::Tx);
            }
        }
        if matches!(to, AlState::Init | AlState::PreOp) {
            self.power = PowerState::SwitchOnDisabled;
            let _ = self
                .od
                .dict_mut()
                .set_uint(STATUSWORD, u64::from(self.power.statusword()));
        }
    }

    fn mailbox_request(
        &mut self,
        state: AlState,
        request: &[u8],
        reply: &mut [u8],
    ) -> Option<usize> {
        self.coe.handle(request, state, &mut self.od, reply)
    }

    fn mailbox_poll(&mut self, reply: &mut [u8]) -> Option<usize> {
        self.coe.poll_unsolicited(reply)
    }

    fn mailbox_reset(&mut self) {
        self.coe.reset();
    }

    fn inject(&mut self, fault: &crate::faults::DeviceFault) -> bool {
        match *fault {
            crate::faults::DeviceFault::Emergency {
                error_code,
                error_register,
                data,
            } => {
                self.coe.push_emergency(Emergency {
                    error_code,
                    error_register,
                    data,
                });
                true
            }
            crate::faults::DeviceFault::AbortSdo {
                index,
                subindex,
                code,
            } => {
                self.coe.abort_next_sdo(index, subindex, code);
                true
            }
            crate::faults::DeviceFault::EmergencyDuringSdo {
                error_code,
                error_register,
                data,
            } => {
                self.coe.emergency_during_next_sdo(Emergency {
                    error_code,
                    error_register,
                    data,
                });
                true
            }
            _ => false,
        }
    }

    fn sync(
        &mut self,
        event: &SyncEvent,
        outputs: &[u8],
        inputs: &mut [u8],
    ) -> Result<(), AlStatusCode> {
        self.seen.cycles += 1;
        if self.quirks.has(Quirk::CycleTimeReadOnly) {
            self.od.dict_mut().show_sync0_cycle(event);
        }
        if event.kind == SyncKind::Sync0 {
            self.seen.sync0_events += 1;
            self.seen.sync0_cycle_ns = event.cycle_time_ns;
            if event.outputs_enabled && !event.outputs_fresh() {
                self.seen.missed_in_op += 1;
            }
        }
        if !self.cia402 {
            // An I/O device: its inputs echo its outputs (the first bytes of each), and count
            // the cycles where it has no outputs, so that a master sees its data move.
            if outputs.is_empty() {
                if let Some(b) = inputs.first_mut() {
                    *b = (self.seen.cycles & 0xFF) as u8;
                }
            } else if event.outputs_enabled {
                for (i, o) in inputs.iter_mut().zip(outputs.iter()) {
                    *i = *o;
                }
            }
            return Ok(());
        }
        if event.outputs_enabled {
            for s in &self.rx {
                let n = s.bits.div_ceil(8).min(8);
                let mut buf = [0u8; 8];
                copy_bits(outputs, s.bit, &mut buf, 0, s.bits);
                if let Some(b) = buf.get(..n) {
                    let _ = self.od.dict_mut().set_raw(s.addr, b);
                }
            }
        }
        self.application(event);
        for s in &self.tx {
            if let Some(v) = self.od.dict().raw(s.addr) {
                copy_bits(v, 0, inputs, s.bit, s.bits);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dictionary_builds_and_maps() {
        OdStore::new(OBJECTS).expect("generic dictionary is valid");
        let d = GenericCoeDevice::new(7).unwrap();
        assert_eq!(d.od().dict().uint(ObjectAddress::new(0x1018, 4)), Some(7));
        let s = d.process_data_sizes();
        assert_eq!((s.outputs, s.inputs), (6, 6));
    }

    #[test]
    fn power_state_machine() {
        use PowerState::*;
        assert_eq!(SwitchOnDisabled.next(0x0006, 0), ReadyToSwitchOn);
        assert_eq!(ReadyToSwitchOn.next(0x0007, 6), SwitchedOn);
        assert_eq!(SwitchedOn.next(0x000F, 7), OperationEnabled);
        assert_eq!(OperationEnabled.next(0x0000, 0xF), SwitchOnDisabled);
        assert_eq!(Fault.next(0x0080, 0), SwitchOnDisabled);
        assert_eq!(Fault.next(0x0080, 0x80), Fault);
    }

    #[test]
    fn bit_copy() {
        let src = [0b1010_1100u8, 0xFF];
        let mut dst = [0u8; 2];
        copy_bits(&src, 2, &mut dst, 5, 6);
        assert_eq!(dst, [0b0110_0000, 0b0000_0101]);
    }
}
