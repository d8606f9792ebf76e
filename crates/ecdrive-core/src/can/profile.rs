//! The CANopen drive profile: everything the master and the emulated nodes need to know about
//! one drive model, as data. The three CANopen drives declare one [`CanDriveProfile`] each in
//! `drives/` ([`crate::drives::blv_r`], [`crate::drives::asda_a2`],
//! [`crate::drives::lexium_mdrive`]); generic code reads these fields and never asks which
//! vendor it talks to.
//!
//! What a profile holds (see `../shared/reference/canopen-common.md` §3):
//! identity ([`Identity`]); the CiA 402 capability set ([`DriveCaps`](crate::cia402::DriveCaps), shared with the EtherCAT
//! drives); the object dictionary; the PDO rules including the CAN-only ones ([`CanPdoProfile`]);
//! units and their conversions ([`Units`]); enable preconditions ([`EnableConditions`]); homing
//! methods ([`HomingSupport`]); how EMCY bytes 3–7 are laid out ([`EmcyFormat`]) and the alarm
//! table ([`Alarm`]); traffic limits; and the reaction to NMT commands while enabled
//! ([`EnabledNmtReaction`]). What only the emulated node needs lives in the software slave, not
//! here. A [`CanDriveProfile`] is the common [`Profile`] with the CANopen part [`CanOpen`].
//!
//! The module also has `const` builders for dictionary tables ([`od`]) so the profiles stay
//! short.

use crate::cia402::{ErrorCode, ErrorDescription, OperationMode};
use crate::od::ObjectAddress;
use crate::pdo::{PdoEntry, PdoLimits};
use core::fmt;

use super::emcy::Emergency;

/// Identity of a drive model: what 0x1000 and 0x1018 hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Identity {
    /// 0x1018:01 vendor ID.
    pub vendor_id: u32,
    /// 0x1018:02 product codes of the models this profile covers, with the model name.
    pub products: &'static [(u32, &'static str)],
    /// 0x1000 device type (the emulated node reports this one).
    pub device_type: u32,
    /// Other 0x1000 values of models this profile covers (e.g. the ASDA-A2 M series).
    pub other_device_types: &'static [u32],
    /// 0x1018:03 revision number, if the manual gives one.
    pub revision: Option<u32>,
}

impl Identity {
    /// Whether a node with these 0x1000 / 0x1018:01 / 0x1018:02 values is this model.
    pub fn matches(&self, device_type: u32, vendor_id: u32, product: Option<u32>) -> bool {
        let dt = device_type == self.device_type || self.other_device_types.contains(&device_type);
        let product_ok = product.is_none_or(|p| self.products.iter().any(|(c, _)| *c == p));
        dt && vendor_id == self.vendor_id && product_ok
    }

    /// The model name for a product code.
    pub fn model(&self, product: u32) -> Option<&'static str> {
        self.products
            .iter()
            .find(|(c, _)| *c == product)
            .map(|(_, n)| *n)
    }
}

/// Which transmission types (0x14xx/0x18xx sub 02h) a PDO direction accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TransmissionTypes {
    /// 0: synchronous, acyclic.
    pub sync_acyclic: bool,
    /// 1–240: synchronous, every n-th SYNC (RPDO: applied at the next SYNC).
    pub sync_cyclic: bool,
    /// 252: synchronous, RTR only (TPDO).
    pub rtr_sync: bool,
    /// 253: asynchronous, RTR only (TPDO).
    pub rtr_event: bool,
    /// 254: event-driven, manufacturer-specific.
    pub event_manufacturer: bool,
    /// 255: event-driven, device profile.
    pub event_profile: bool,
}

impl TransmissionTypes {
    /// Every CiA 301 type.
    pub const ALL: Self = Self {
        sync_acyclic: true,
        sync_cyclic: true,
        rtr_sync: true,
        rtr_event: true,
        event_manufacturer: true,
        event_profile: true,
    };

    /// Whether `t` is accepted.
    pub const fn allows(&self, t: u8) -> bool {
        match t {
            0 => self.sync_acyclic,
            1..=240 => self.sync_cyclic,
            252 => self.rtr_sync,
            253 => self.rtr_event,
            254 => self.event_manufacturer,
            255 => self.event_profile,
            _ => false,
        }
    }
}

/// A transmission type's meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Transmission {
    /// 0: at the next SYNC, if something changed (TPDO) / applied at the next SYNC (RPDO).
    SyncAcyclic,
    /// 1–240: every n-th SYNC.
    SyncCyclic(u8),
    /// 241–251: reserved.
    Reserved(u8),
    /// 252: sampled at SYNC, sent on RTR.
    RtrSync,
    /// 253: sent on RTR.
    RtrEvent,
    /// 254/255: event-driven (change of value, inhibit time, event timer).
    Event(u8),
}

impl Transmission {
    /// Decode a transmission type.
    pub const fn from_u8(t: u8) -> Self {
        match t {
            0 => Self::SyncAcyclic,
            1..=240 => Self::SyncCyclic(t),
            252 => Self::RtrSync,
            253 => Self::RtrEvent,
            254 | 255 => Self::Event(t),
            _ => Self::Reserved(t),
        }
    }

    /// Whether SYNC paces this PDO (types 0–240 and 252).
    pub const fn is_synchronous(self) -> bool {
        matches!(
            self,
            Self::SyncAcyclic | Self::SyncCyclic(_) | Self::RtrSync
        )
    }
}

/// A PDO's power-on configuration: communication record and mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoDefault {
    /// PDO number 1–4 (RPDO n: 0x1400 + n − 1 / 0x1600 + n − 1; TPDO n: 0x1800 / 0x1A00 …).
    pub number: u8,
    /// Sub 01h COB-ID **for node-ID 0**: the device adds its node-ID to the 11-bit part. Bit 31
    /// = PDO invalid, bit 30 = no RTR.
    pub cob_id: u32,
    /// Sub 02h transmission type.
    pub transmission_type: u8,
    /// Sub 03h inhibit time (× 100 µs), TPDOs.
    pub inhibit_time: u16,
    /// Sub 05h event timer (ms).
    pub event_timer: u16,
    /// The mapping.
    pub mapping: &'static [PdoEntry],
}

/// The PDO rules of a CANopen drive: the generic [`PdoLimits`] plus what only CAN has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanPdoProfile {
    /// Mapping objects and entries per PDO, as for the EtherCAT drives: 0x1600–0x1603 and
    /// 0x1A00–0x1A03, `max_assigned` = 4 (every PDO may be valid), `max_bytes` = 4 × 8.
    pub limits: PdoLimits,
    /// Bytes per PDO: 8 on classic CAN.
    pub max_pdo_bytes: u8,
    /// RPDO transmission types accepted (others: abort 0609 0030h).
    pub rpdo_types: TransmissionTypes,
    /// TPDO transmission types accepted.
    pub tpdo_types: TransmissionTypes,
    /// Highest sub-index of the RPDO communication records (BLV-R 2, others 5).
    pub rpdo_comm_subs: u8,
    /// Power-on RPDOs.
    pub default_rpdos: &'static [PdoDefault],
    /// Power-on TPDOs.
    pub default_tpdos: &'static [PdoDefault],
}

pub use crate::cia402::Profile;
pub use crate::cia402::units::{AccelUnit, TorqueSlopeUnit, Units, VelocityUnit};

/// A drive parameter the master must check or set before enabling: `(value & mask) == value`
/// after a read-modify-write of the bits in `mask`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamSetting {
    /// The object.
    pub addr: ObjectAddress,
    /// The bits that matter.
    pub mask: u32,
    /// Their required value.
    pub value: u32,
    /// Whether the master may write it (`false`: only check and report).
    pub writable: bool,
    /// Why, for messages.
    pub why: &'static str,
}

/// What must hold before a drive follows "enable operation".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EnableConditions {
    /// Statusword bit 9 (remote) must be 1; while it is 0 the drive ignores the controlword
    /// except quick stop, fault reset and halt (BLV-R §6.1).
    pub remote_required: bool,
    /// Statusword bit 4 (voltage enabled, DC bus) must be 1 (Lexium §6.1).
    pub voltage_required: bool,
    /// The drive excites the motor only in NMT Operational (BLV-R §5.1).
    pub needs_operational: bool,
    /// Parameters to check or write before enabling.
    pub settings: &'static [ParamSetting],
    /// Targets the drive clears when it enables (ASDA-A2 §3.4.2, §3.5.2: 60FFh, 6071h): write
    /// them only after Operation enabled.
    pub targets_cleared_on_enable: &'static [ObjectAddress],
    /// Other delays or conditions, for documentation.
    pub notes: &'static str,
}

/// Homing methods (0x6098) a drive accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HomingSupport {
    /// Accepted methods.
    pub methods: &'static [i8],
    /// The power-on value of 0x6098.
    pub default_method: i8,
    /// Methods that need an index pulse (encoder) this model has. `false`: index methods end in
    /// a homing error.
    pub index_pulse: bool,
}

impl HomingSupport {
    /// Whether `method` is accepted.
    pub fn supports(&self, method: i8) -> bool {
        self.methods.contains(&method)
    }
}

/// Where a drive puts its vendor alarm number in an EMCY message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EmcyFormat {
    /// Bytes 3–7 are zero; the alarm number is the low byte of a `FFxxh` code (BLV-R §4.5).
    AlarmInCodeLowByte,
    /// Bytes 3–4 hold the panel alarm number, little endian, e.g. `0x0011` for AL011 (ASDA-A2
    /// §5.1). 0x1003 entries carry it in the upper 16 bits.
    AlarmInBytes3To4,
    /// Byte 5 = PDO number, bytes 6–7 = vendor code (additional info), little endian (Lexium
    /// §3.5). 0x1003 entries carry the additional info in the upper 16 bits.
    PdoAndVendorCode,
}

impl EmcyFormat {
    /// The vendor alarm number / additional info an EMCY carries, if any.
    pub fn vendor_number(self, e: &Emergency) -> Option<u16> {
        match self {
            EmcyFormat::AlarmInCodeLowByte => {
                (e.error_code & 0xFF00 == 0xFF00).then_some(e.error_code & 0x00FF)
            }
            EmcyFormat::AlarmInBytes3To4 => {
                let n = u16::from_le_bytes([e.data[0], e.data[1]]);
                (n != 0).then_some(n)
            }
            EmcyFormat::PdoAndVendorCode => {
                let n = u16::from_le_bytes([e.data[3], e.data[4]]);
                (n != 0).then_some(n)
            }
        }
    }

    /// Bytes 3–7 for an alarm with vendor number `number`.
    pub fn vendor_bytes(self, number: u16) -> [u8; 5] {
        let [lo, hi] = number.to_le_bytes();
        match self {
            EmcyFormat::AlarmInCodeLowByte => [0; 5],
            EmcyFormat::AlarmInBytes3To4 => [lo, hi, 0, 0, 0],
            EmcyFormat::PdoAndVendorCode => [0, 0, 0, lo, hi],
        }
    }

    /// The 0x1003 entry for an alarm.
    pub fn history_entry(self, code: u16, number: u16) -> u32 {
        match self {
            EmcyFormat::AlarmInCodeLowByte => u32::from(code),
            EmcyFormat::AlarmInBytes3To4 | EmcyFormat::PdoAndVendorCode => {
                u32::from(number) << 16 | u32::from(code)
            }
        }
    }
}

/// One alarm of a drive's alarm table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Alarm {
    /// The vendor number as the EMCY carries it (see [`EmcyFormat`]): BLV-R alarm code (e.g.
    /// 0x30), ASDA-A2 panel number written as hex digits (AL011 → 0x0011), Lexium additional
    /// info.
    pub number: u16,
    /// The error code in EMCY bytes 0–1 and 0x603F.
    pub code: u16,
    /// The error register (0x1001) the drive reports with it.
    pub register: u8,
    /// The vendor's name, e.g. `"AL011"`.
    pub name: &'static str,
    /// What it means.
    pub text: &'static str,
    /// Whether the drive goes to Fault (`false`: a warning, statusword bit 7 only).
    pub fault: bool,
}

/// The reaction of a drive to NMT Stop / Reset while its power stage is enabled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EnabledNmtReaction {
    /// The manual says nothing; the emulation disables the power stage (transition 9).
    /// **MANUAL GAP**.
    Unspecified,
    /// The drive raises this alarm (vendor number) and faults (ASDA-A2 AL401).
    Alarm(u16),
    /// Error class 2: quick stop, then power stage off, state Fault (Lexium §3.6.1), with this
    /// alarm (vendor number).
    QuickStopThenFault(u16),
}

/// What the NMT error-control and SYNC services of a drive offer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CommSupport {
    /// Node guarding / life guarding (0x100C, 0x100D).
    pub guarding: bool,
    /// Entries of the consumer-heartbeat object 0x1016 (0: the object does not exist).
    pub heartbeat_consumers: u8,
    /// The drive can be the SYNC producer (0x1005 bit 30).
    pub sync_producer: bool,
    /// 0x1006 exists.
    pub has_cycle_period: bool,
    /// 0x1006 must be a multiple of this many µs (0 = any).
    pub cycle_period_granularity_us: u32,
    /// Entries of the error history 0x1003.
    pub error_history: u8,
    /// Highest sub-index of 0x1010/0x1011 (store/restore).
    pub store_subs: u8,
    /// Smallest gap between two SDO requests the drive tolerates, µs (0 = no limit). ASDA-A2:
    /// two requests within 1 ms raise AL111.
    pub sdo_min_interval_us: u32,
    /// Smallest gap between two frames on one RPDO COB-ID, µs (0 = no limit). ASDA-A2: AL112.
    pub rpdo_min_interval_us: u32,
}

impl CommSupport {
    /// What a drive's EDS file says of its error control and history: guarding where 100Ch
    /// and 100Dh exist, heartbeat consumers from 1016h's sub-indices, 1006h, the depth of
    /// 1003h and the store sub-indices of 1010h. A file cannot say whether the drive produces
    /// SYNC (1005h bit 30) nor which gaps it tolerates: **\[REC\]** no, and none.
    pub fn from_eds(f: &crate::eds::EdsFile) -> Self {
        let has = |i: u16| f.objects.contains_key(&i);
        Self {
            guarding: has(0x100C) && has(0x100D),
            heartbeat_consumers: f.highest_sub(0x1016),
            sync_producer: false,
            has_cycle_period: has(0x1006),
            cycle_period_granularity_us: 0,
            error_history: f.highest_sub(0x1003),
            store_subs: f.highest_sub(0x1010),
            sdo_min_interval_us: 0,
            rpdo_min_interval_us: 0,
        }
    }
}

/// A CANopen drive's profile: the common part and [`CanOpen`] (see [`Profile`]).
pub type CanDriveProfile = Profile<CanOpen>;

/// What only a CANopen drive's profile has.
#[derive(Debug, Clone, Copy)]
pub struct CanOpen {
    /// The manual the data comes from.
    pub source: &'static str,
    /// Identity.
    pub identity: Identity,
    /// Factory node-ID, if the manual states one.
    pub default_node_id: Option<u8>,
    /// Factory bit rate, kbit/s.
    pub default_bitrate_kbit: u16,
    /// Bit rates the drive offers, kbit/s.
    pub bitrates_kbit: &'static [u16],
    /// Where the manuals disagree about the supported modes.
    pub modes_note: &'static str,
    /// PDO rules and defaults.
    pub pdo: CanPdoProfile,
    /// Enable preconditions.
    pub enable: EnableConditions,
    /// Homing methods.
    pub homing: HomingSupport,
    /// EMCY bytes 3–7.
    pub emcy: EmcyFormat,
    /// The alarm table.
    pub alarms: &'static [Alarm],
    /// Vendor SDO abort codes and their texts.
    pub vendor_abort_codes: &'static [(u32, &'static str)],
    /// Error control, SYNC, error history, store, rate limits.
    pub comm: CommSupport,
    /// Reaction to NMT Stop while enabled.
    pub nmt_stop_while_enabled: EnabledNmtReaction,
    /// Reaction to NMT Reset node / Reset communication while enabled.
    pub nmt_reset_while_enabled: EnabledNmtReaction,
    /// In ip, controlword bit 4 enables interpolation (CiA); `false`: interpolation runs
    /// whenever mode 7 is active (ASDA-A2 §5.2).
    pub ip_needs_enable_bit: bool,
    /// Statusword bit 12 in pv is the zero-speed flag.
    pub pv_zero_speed_bit: bool,
}

impl CanDriveProfile {
    /// The alarm with vendor number `number`.
    pub fn alarm(&self, number: u16) -> Option<&'static Alarm> {
        let alarms: &'static [Alarm] = self.alarms;
        alarms.iter().find(|a| a.number == number)
    }

    /// Decode an EMCY message with this drive's format and alarm table.
    pub fn decode_emcy(&self, e: &Emergency) -> DecodedEmcy {
        let number = self.emcy.vendor_number(e);
        let alarms: &'static [Alarm] = self.alarms;
        let alarm = number
            .and_then(|n| {
                alarms
                    .iter()
                    .find(|a| a.number == n && a.code == e.error_code)
            })
            .or_else(|| number.and_then(|n| alarms.iter().find(|a| a.number == n)))
            .or_else(|| {
                // Only the code: unambiguous if exactly one alarm has it.
                let mut it = alarms.iter().filter(|a| a.code == e.error_code);
                match (it.next(), it.next()) {
                    (Some(a), None) => Some(a),
                    _ => None,
                }
            });
        DecodedEmcy {
            emergency: *e,
            vendor_number: number,
            alarm,
            description: ErrorCode(e.error_code).describe(self.caps.error_table),
        }
    }

    /// Whether the drive supports `mode` by its capability set.
    pub fn supports(&self, mode: OperationMode) -> bool {
        self.caps.supported_modes.contains(mode)
    }

    /// The text of an abort code, with this drive's vendor codes.
    pub fn abort_text(&self, code: crate::od::SdoAbortCode) -> super::sdo::AbortText {
        super::sdo::abort_text(code, self.vendor_abort_codes)
    }
}

/// An EMCY message decoded with a drive profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DecodedEmcy {
    /// The raw message.
    pub emergency: Emergency,
    /// The vendor number the format yields.
    pub vendor_number: Option<u16>,
    /// The alarm-table row, if found.
    pub alarm: Option<&'static Alarm>,
    /// The error code decoded with the drive's error table and the CiA tables.
    pub description: ErrorDescription,
}

impl fmt::Display for DecodedEmcy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = &self.emergency;
        if e.is_reset() {
            return write!(f, "error reset (register 0x{:02X})", e.error_register);
        }
        write!(f, "EMCY 0x{:04X}", e.error_code)?;
        match self.alarm {
            Some(a) => write!(f, " {} {}", a.name, a.text)?,
            None => write!(f, " {}", self.description)?,
        }
        write!(f, ", error register 0x{:02X}", e.error_register)?;
        if let (None, Some(n)) = (self.alarm, self.vendor_number) {
            write!(f, ", vendor number 0x{n:04X}")?;
        }
        Ok(())
    }
}

/// `const` builders for dictionary tables of CANopen drives.
///
/// Access flags: CANopen has no SAFE-OP; [`EntryAccess::RW`](crate::od::EntryAccess::RW) means
/// writable in Pre-operational and Operational, `RO` readable in both. Communication objects
/// whose default depends on the node-ID hold the value for node-ID 0 (as EDS files write
/// `$NODEID+0x180`); the node adds its ID ([`od::node_relative`]).
pub mod od {
    use crate::od::{ConstValue, DataType, EntryAccess, EntryDesc, ObjectAddress};

    /// Read-only.
    pub const RO: EntryAccess = EntryAccess::RO;
    /// Read-write.
    pub const RW: EntryAccess = EntryAccess::RW;
    /// Read-write, RPDO-mappable.
    pub const RW_R: EntryAccess = EntryAccess::RW.union(EntryAccess::RXPDO);
    /// Read-only, TPDO-mappable.
    pub const RO_T: EntryAccess = EntryAccess::RO.union(EntryAccess::TXPDO);
    /// Read-write, mappable both ways (e.g. BLV-R "rww" objects, ASDA-A2 parameters).
    pub const RW_RT: EntryAccess = EntryAccess::RW
        .union(EntryAccess::RXPDO)
        .union(EntryAccess::TXPDO);

    /// UNSIGNED8.
    pub const U8: DataType = DataType::Unsigned8;
    /// UNSIGNED16.
    pub const U16: DataType = DataType::Unsigned16;
    /// UNSIGNED32.
    pub const U32: DataType = DataType::Unsigned32;
    /// INTEGER8.
    pub const I8: DataType = DataType::Integer8;
    /// INTEGER16.
    pub const I16: DataType = DataType::Integer16;
    /// INTEGER32.
    pub const I32: DataType = DataType::Integer32;
    /// VISIBLE_STRING.
    pub const STR: DataType = DataType::VisibleString;

    /// Unsigned constant.
    pub const fn u(v: u64) -> ConstValue {
        ConstValue::Uint(v)
    }

    /// Signed constant.
    pub const fn i(v: i64) -> ConstValue {
        ConstValue::Int(v)
    }

    /// An entry.
    pub const fn e(
        sub: u8,
        name: &'static str,
        dt: DataType,
        access: EntryAccess,
        default: ConstValue,
    ) -> EntryDesc {
        EntryDesc::new(sub, name, dt, access).default(default)
    }

    /// The "number of entries" sub-index 0.
    pub const fn count(n: u8, access: EntryAccess) -> EntryDesc {
        EntryDesc::new(0, "Number of entries", U8, access).default(ConstValue::Uint(n as u64))
    }

    /// A PDO communication record with subs 0–2 (BLV-R RPDOs) or 0–5 (sub 4 absent: accessing
    /// it aborts 0609 0011h on all three drives). `N` is 3 or 5.
    pub const fn pdo_comm<const N: usize>(
        cob_id: u32,
        transmission_type: u8,
        inhibit: u16,
        event_timer: u16,
    ) -> [EntryDesc; N] {
        let mut out = [count(0, RO); N];
        out[0] = count(if N == 3 { 2 } else { 5 }, RO);
        if N > 1 {
            out[1] = e(1, "COB-ID", U32, RW, u(cob_id as u64));
        }
        if N > 2 {
            out[2] = e(2, "Transmission type", U8, RW, u(transmission_type as u64));
        }
        if N > 3 {
            out[3] = e(3, "Inhibit time", U16, RW, u(inhibit as u64));
        }
        if N > 4 {
            out[4] = e(5, "Event timer", U16, RW, u(event_timer as u64));
        }
        out
    }

    /// A PDO mapping record with `N − 1` entries (`N` = 5 or 9), `defaults` in order.
    pub const fn pdo_map<const N: usize>(defaults: &[u32]) -> [EntryDesc; N] {
        let mut out = [count(0, RW); N];
        let mut n = defaults.len();
        if n > N - 1 {
            n = N - 1;
        }
        out[0] = EntryDesc::new(0, "Number of mapped objects", U8, RW)
            .default(ConstValue::Uint(n as u64))
            .range(ConstValue::Uint(0), ConstValue::Uint((N - 1) as u64));
        let mut k = 1;
        while k < N {
            let d = if k <= n { defaults[k - 1] } else { 0 };
            out[k] = e(k as u8, "Mapped object", U32, RW, u(d as u64));
            k += 1;
        }
        out
    }

    /// An error-history ARRAY (0x1003) with `N − 1` entries.
    pub const fn error_history<const N: usize>() -> [EntryDesc; N] {
        let mut out = [count(0, RW); N];
        let mut k = 1;
        while k < N {
            out[k] = e(k as u8, "Standard error field", U32, RO, u(0));
            k += 1;
        }
        out
    }

    /// A store (0x1010) or restore (0x1011) ARRAY with `N − 1` entries reading 1 ("on
    /// command").
    pub const fn store_record<const N: usize>() -> [EntryDesc; N] {
        let mut out = [count((N - 1) as u8, RO); N];
        let mut k = 1;
        while k < N {
            out[k] = e(k as u8, "Signature", U32, RW, u(1));
            k += 1;
        }
        out
    }

    /// Whether the default of `addr` is written for node-ID 0 and the node adds its ID: 0x1014,
    /// 0x1200:01/02, PDO COB-IDs 0x1400–0x15FF:01 and 0x1800–0x19FF:01.
    pub const fn node_relative(addr: ObjectAddress) -> bool {
        match addr.index {
            0x1014 => addr.sub == 0,
            0x1200 => addr.sub == 1 || addr.sub == 2,
            0x1400..=0x15FF | 0x1800..=0x19FF => addr.sub == 1,
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emcy_formats() {
        let e = Emergency {
            error_code: 0xFF30,
            error_register: 0x81,
            data: [0; 5],
        };
        assert_eq!(EmcyFormat::AlarmInCodeLowByte.vendor_number(&e), Some(0x30));
        let d = Emergency {
            error_code: 0x7305,
            error_register: 0x01,
            data: EmcyFormat::AlarmInBytes3To4.vendor_bytes(0x0011),
        };
        assert_eq!(d.data, [0x11, 0, 0, 0, 0]);
        assert_eq!(EmcyFormat::AlarmInBytes3To4.vendor_number(&d), Some(0x0011));
        assert_eq!(
            EmcyFormat::AlarmInBytes3To4.history_entry(0x7305, 0x0011),
            0x0011_7305
        );
        let l = Emergency {
            error_code: 0x4210,
            error_register: 0x09,
            data: EmcyFormat::PdoAndVendorCode.vendor_bytes(0x08),
        };
        assert_eq!(EmcyFormat::PdoAndVendorCode.vendor_number(&l), Some(0x08));
        assert!(TransmissionTypes::ALL.allows(240));
        assert!(!TransmissionTypes::ALL.allows(241));
        assert!(Transmission::from_u8(1).is_synchronous());
        assert!(!Transmission::from_u8(255).is_synchronous());
    }
}
