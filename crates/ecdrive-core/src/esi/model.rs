//! The parsed contents of an ESI file: vendor, groups and devices with their SyncManagers,
//! FMMUs, PDOs, mailbox, DC operation modes, EEPROM data and object dictionary.

use super::dictionary::Dictionary;
use super::error::Position;
use crate::od::DataType;
use crate::pdo::Direction;

/// The LCID of English (United States), the language preferred for [`LocalizedText`] choices.
pub const LCID_ENGLISH: u32 = 1033;

/// One `<Name>` (or `<Comment>`) in one language.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LocalizedText {
    /// The `LcId` attribute (1033 English, 1031 German, …), if given.
    pub lcid: Option<u32>,
    /// The text, trimmed.
    pub text: String,
}

/// Pick the preferred text of several languages: English (LcId 1033) if present, otherwise the
/// first one; empty if there is none.
pub fn preferred_text(texts: &[LocalizedText]) -> &str {
    texts
        .iter()
        .find(|t| t.lcid == Some(LCID_ENGLISH))
        .or_else(|| texts.first())
        .map(|t| t.text.as_str())
        .unwrap_or("")
}

/// A parsed ESI file (`<EtherCATInfo>`).
#[derive(Debug, Clone, PartialEq)]
pub struct EsiFile {
    /// The `Version` attribute of `<EtherCATInfo>` (schema version), if given.
    pub version: Option<String>,
    /// The vendor.
    pub vendor: Vendor,
    /// `<Descriptions><Groups>`, in file order.
    pub groups: Vec<Group>,
    /// `<Descriptions><Devices>`, in file order: those that could be read.
    pub devices: Vec<Device>,
    /// The devices that could not be read (a PDO entry, SyncManager or `<InitCmd>` the
    /// device's process data or start-up depends on does not read), with why.
    pub unreadable: Vec<UnreadableDevice>,
    /// Problems read past, in file order: a value left out (a default that is not hex data,
    /// an access keyword the schema does not have, an object whose index does not read, …)
    /// or taken as the tolerance rules say. They are warnings: what the run depends on is
    /// checked again where it is used.
    pub warnings: Vec<super::error::EsiError>,
}

/// A `<Device>` that could not be read: its identity as far as it reads, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnreadableDevice {
    /// Where the `<Device>` element starts.
    pub position: Position,
    /// The `<Type>` text.
    pub type_text: String,
    /// The preferred `<Name>`.
    pub name: String,
    /// `ProductCode`, if it reads.
    pub product_code: Option<u32>,
    /// `RevisionNo`, if it reads.
    pub revision_no: Option<u32>,
    /// Why the device could not be read.
    pub error: super::error::EsiError,
}

impl EsiFile {
    /// The devices with this product code, in file order (a file often holds several
    /// revisions of one product).
    pub fn devices_with_product(&self, product_code: u32) -> impl Iterator<Item = &Device> {
        self.devices
            .iter()
            .filter(move |d| d.type_.product_code == product_code)
    }

    /// The device matching an identity as a master reads it from the SII or 0x1018: the same
    /// product code and, if the device states one, the same revision. With `revision` `None`
    /// the last (usually newest) device with the product code is returned.
    pub fn device(&self, product_code: u32, revision: Option<u32>) -> Option<&Device> {
        match revision {
            Some(r) => self
                .devices_with_product(product_code)
                .find(|d| d.type_.revision_no == Some(r))
                .or_else(|| {
                    self.devices_with_product(product_code)
                        .find(|d| d.type_.revision_no.is_none())
                }),
            None => self.devices_with_product(product_code).last(),
        }
    }

    /// Choose one device ([`DeviceChoice`]), as an index into [`Self::devices`]. Never a
    /// silent first match: a choice that fits several devices is refused, listing them with
    /// the identity that tells them apart; a device that matches but could not be read says
    /// why.
    pub fn choose(&self, choice: &DeviceChoice) -> Result<usize, String> {
        let fits = |d: &Device| match choice {
            DeviceChoice::Only => true,
            DeviceChoice::Identity {
                product_code,
                revision,
            } => {
                d.type_.product_code == *product_code
                    && revision.is_none_or(|r| d.type_.revision_no == Some(r))
            }
            DeviceChoice::Name(n) => {
                d.type_.name_text.eq_ignore_ascii_case(n) || d.name.eq_ignore_ascii_case(n)
            }
        };
        let hits: Vec<usize> = (0..self.devices.len())
            .filter(|&i| self.devices.get(i).is_some_and(fits))
            .collect();
        let broken = self.unreadable.iter().find(|u| match choice {
            DeviceChoice::Only => true,
            DeviceChoice::Identity {
                product_code,
                revision,
            } => {
                u.product_code == Some(*product_code)
                    && revision.is_none_or(|r| u.revision_no == Some(r))
            }
            DeviceChoice::Name(n) => {
                u.type_text.eq_ignore_ascii_case(n) || u.name.eq_ignore_ascii_case(n)
            }
        });
        match (hits.as_slice(), broken) {
            ([i], None) => Ok(*i),
            ([], Some(u)) => Err(format!(
                "device {:?} of the file cannot be used: {}",
                if u.name.is_empty() {
                    &u.type_text
                } else {
                    &u.name
                },
                u.error
            )),
            ([], None) => Err(format!(
                "the file has no device {choice}; it has {}",
                self.device_list()
            )),
            _ => Err(format!(
                "{} devices of the file fit {choice}: {}; choose one by identity \
                 (0xPRODUCT:0xREVISION)",
                hits.len() + usize::from(broken.is_some()),
                self.device_list_of(&hits)
            )),
        }
    }

    /// Every device as `"name" 0xPRODUCT:0xREVISION`, comma-separated.
    pub fn device_list(&self) -> String {
        self.device_list_of(&(0..self.devices.len()).collect::<Vec<_>>())
    }

    fn device_list_of(&self, which: &[usize]) -> String {
        which
            .iter()
            .filter_map(|&i| self.devices.get(i))
            .map(|d| format!("{:?} {}", d.name, d.identity_text()))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The group with this `<Type>`.
    pub fn group(&self, type_: &str) -> Option<&Group> {
        self.groups.iter().find(|g| g.type_ == type_)
    }
}

/// `<Vendor>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Vendor {
    /// `<Id>`: the EtherCAT vendor ID (0x1018:01).
    pub id: u32,
    /// The preferred `<Name>`.
    pub name: String,
    /// All `<Name>`s.
    pub names: Vec<LocalizedText>,
}

/// `<Group>` in `<Descriptions><Groups>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Group {
    /// `<Type>`, referenced by a device's `<GroupType>`.
    pub type_: String,
    /// The preferred `<Name>`.
    pub name: String,
    /// All `<Name>`s.
    pub names: Vec<LocalizedText>,
}

/// `<Type>` of a device: its identity.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceType {
    /// `ProductCode` attribute (0x1018:02).
    pub product_code: u32,
    /// `RevisionNo` attribute (0x1018:03), if given.
    pub revision_no: Option<u32>,
    /// The element text: the order name, e.g. `EL2004`.
    pub name_text: String,
}

/// `<Device>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Device {
    /// Where the `<Device>` element starts.
    pub position: Position,
    /// Identity.
    pub type_: DeviceType,
    /// The preferred `<Name>` (English if present); the type text if there is no name.
    pub name: String,
    /// All `<Name>`s.
    pub names: Vec<LocalizedText>,
    /// `<GroupType>`.
    pub group_type: Option<String>,
    /// The `Physics` attribute (one letter per port: `Y` MII, `K` E-Bus, …).
    pub physics: Option<String>,
    /// `<Fmmu>`s in order (FMMU 0, 1, …).
    pub fmmus: Vec<Fmmu>,
    /// `<Sm>`s in order (SM 0, 1, …).
    pub sync_managers: Vec<SyncManager>,
    /// `<RxPdo>`s (outputs, master → device), in file order.
    pub rx_pdos: Vec<EsiPdo>,
    /// `<TxPdo>`s (inputs, device → master), in file order.
    pub tx_pdos: Vec<EsiPdo>,
    /// `<Mailbox>`.
    pub mailbox: Option<Mailbox>,
    /// `<Dc><OpMode>`s in file order (empty if the device has no `<Dc>`).
    pub dc: Vec<OpMode>,
    /// `<Eeprom>`.
    pub eeprom: Option<Eeprom>,
    /// `<Profile>`s (one per channel; drives usually have one).
    pub profiles: Vec<Profile>,
}

/// Which device of an ESI file: [`EsiFile::choose`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DeviceChoice {
    /// The file's only device.
    Only,
    /// By identity, as a master reads it (0x1018:02, :03).
    Identity {
        /// `ProductCode`.
        product_code: u32,
        /// `RevisionNo`; `None`: any revision (refused when several fit).
        revision: Option<u32>,
    },
    /// By `<Type>` text or `<Name>` (case-insensitive).
    Name(String),
}

impl DeviceChoice {
    /// Read `0xPRODUCT[:0xREVISION]` as an identity, anything else as a name.
    pub fn parse(text: &str) -> Self {
        let num = |t: &str| super::num::parse_u32_wrapping(t).ok();
        let hexy = |t: &str| t.starts_with("0x") || t.starts_with("0X") || t.starts_with("#x");
        let (p, r) = match text.split_once(':') {
            Some((p, r)) => (p, Some(r)),
            None => (text, None),
        };
        match (hexy(p).then(|| num(p)).flatten(), r.map(num)) {
            (Some(product_code), None) => Self::Identity {
                product_code,
                revision: None,
            },
            (Some(product_code), Some(Some(rev))) => Self::Identity {
                product_code,
                revision: Some(rev),
            },
            _ => Self::Name(text.to_string()),
        }
    }
}

impl core::fmt::Display for DeviceChoice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Only => f.write_str("(the only device)"),
            Self::Identity {
                product_code,
                revision: None,
            } => write!(f, "0x{product_code:08X}"),
            Self::Identity {
                product_code,
                revision: Some(r),
            } => write!(f, "0x{product_code:08X}:0x{r:08X}"),
            Self::Name(n) => write!(f, "{n:?}"),
        }
    }
}

impl Device {
    /// `0xPRODUCT:0xREVISION` (without the revision where the file gives none).
    pub fn identity_text(&self) -> String {
        match self.type_.revision_no {
            Some(r) => format!("0x{:08X}:0x{r:08X}", self.type_.product_code),
            None => format!("0x{:08X}", self.type_.product_code),
        }
    }

    /// The PDOs of one direction.
    pub fn pdos(&self, dir: Direction) -> &[EsiPdo] {
        match dir {
            Direction::Rx => &self.rx_pdos,
            Direction::Tx => &self.tx_pdos,
        }
    }

    /// The PDO with mapping index `index` in direction `dir`.
    pub fn pdo(&self, dir: Direction, index: u16) -> Option<&EsiPdo> {
        self.pdos(dir).iter().find(|p| p.index == index)
    }

    /// The first SyncManager of a kind.
    pub fn sync_manager(&self, kind: SmKind) -> Option<&SyncManager> {
        self.sync_managers.iter().find(|s| s.kind == kind)
    }

    /// The DC operation mode named `name` (case-insensitive).
    pub fn dc_op_mode(&self, name: &str) -> Option<&OpMode> {
        self.dc
            .iter()
            .find(|m| m.mode.name.eq_ignore_ascii_case(name))
    }

    /// The object dictionary of the first profile that has one.
    pub fn dictionary(&self) -> Option<&Dictionary> {
        self.profiles.iter().find_map(|p| p.dictionary.as_ref())
    }

    /// Whether the device has a mailbox with CoE.
    pub fn has_coe(&self) -> bool {
        self.mailbox
            .as_ref()
            .is_some_and(|m| m.protocols.contains(MailboxProtocols::COE))
    }
}

/// What a SyncManager is used for (the `<Sm>` element text).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SmKind {
    /// `MBoxOut`: mailbox master → device (SM0).
    MBoxOut,
    /// `MBoxIn`: mailbox device → master (SM1).
    MBoxIn,
    /// `Outputs`: process data master → device (RxPDOs).
    Outputs,
    /// `Inputs`: process data device → master (TxPDOs).
    Inputs,
    /// No text: the SyncManager exists but is not used.
    Unused,
}

impl SmKind {
    /// The ESI text.
    pub const fn name(self) -> &'static str {
        match self {
            Self::MBoxOut => "MBoxOut",
            Self::MBoxIn => "MBoxIn",
            Self::Outputs => "Outputs",
            Self::Inputs => "Inputs",
            Self::Unused => "",
        }
    }

    /// The SII SyncM category type byte: 0 unused, 1 mailbox out, 2 mailbox in, 3 outputs,
    /// 4 inputs (ETG.2010).
    pub const fn sii_type(self) -> u8 {
        match self {
            Self::Unused => 0,
            Self::MBoxOut => 1,
            Self::MBoxIn => 2,
            Self::Outputs => 3,
            Self::Inputs => 4,
        }
    }
}

/// `<Sm>`: one SyncManager.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SyncManager {
    /// Where the element starts.
    pub position: Position,
    /// The SyncManager number (its position among the device's `<Sm>`s).
    pub index: u8,
    /// What it is used for.
    pub kind: SmKind,
    /// `StartAddress`: physical start address in the ESC memory.
    pub start_address: u16,
    /// `DefaultSize` in bytes, if given.
    pub default_size: Option<u16>,
    /// `MinSize` in bytes, if given.
    pub min_size: Option<u16>,
    /// `MaxSize` in bytes, if given.
    pub max_size: Option<u16>,
    /// `ControlByte` (ESC register 0x0804 + 8n).
    pub control_byte: u8,
    /// `Enable` ≠ 0.
    pub enable: bool,
    /// `Virtual`.
    pub virtual_: bool,
    /// `OpOnly`: enabled only in OP.
    pub op_only: bool,
}

impl SyncManager {
    /// The SII SyncM category "enable" byte: bit 0 enable, bit 2 virtual, bit 3 OP only.
    pub const fn sii_enable(&self) -> u8 {
        (self.enable as u8) | (self.virtual_ as u8) << 2 | (self.op_only as u8) << 3
    }
}

pub use crate::ec::sii::DcOpMode;
pub use crate::ec::sii::FmmuUsage;

/// `<Fmmu>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fmmu {
    /// What it maps.
    pub usage: FmmuUsage,
    /// `Sm` attribute: the SyncManager it belongs to, if stated.
    pub sm: Option<u8>,
    /// `OpOnly`.
    pub op_only: bool,
}

/// `<RxPdo>` or `<TxPdo>`: one PDO a device offers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiPdo {
    /// Where the element starts.
    pub position: Position,
    /// `<Index>`: the mapping object (0x16xx / 0x1Axx).
    pub index: u16,
    /// The preferred `<Name>`.
    pub name: String,
    /// `Sm` attribute: the SyncManager this PDO is assigned to **by default**. A PDO without it
    /// is offered but not assigned.
    pub sm: Option<u8>,
    /// `Fixed`: the entries cannot be changed.
    pub fixed: bool,
    /// `Mandatory`: the PDO must always be assigned.
    pub mandatory: bool,
    /// `Virtual`.
    pub virtual_: bool,
    /// `<Exclude>`s: PDOs that cannot be assigned together with this one.
    pub excludes: Vec<u16>,
    /// `<Entry>`s in order.
    pub entries: Vec<EsiPdoEntry>,
}

impl EsiPdo {
    /// Total size in bits.
    pub fn bits(&self) -> u32 {
        self.entries.iter().map(|e| u32::from(e.bit_len)).sum()
    }

    /// Whether this PDO is in the default assignment: it has an `Sm` attribute or is
    /// mandatory. See [`Device::default_mapping`].
    pub fn is_default(&self) -> bool {
        self.sm.is_some() || self.mandatory
    }
}

/// `<Entry>` of a PDO.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiPdoEntry {
    /// Where the element starts.
    pub position: Position,
    /// `<Index>` of the mapped object (0 for a padding gap).
    pub index: u16,
    /// `<SubIndex>` (0 if absent, as for gaps).
    pub sub: u8,
    /// `<BitLen>`.
    pub bit_len: u16,
    /// The preferred `<Name>` (empty for gaps).
    pub name: String,
    /// `<DataType>` as written (`UINT`, `DINT`, `BOOL`, …), if given.
    pub data_type_name: Option<String>,
}

impl EsiPdoEntry {
    /// Whether this entry is a padding gap (index 0).
    pub fn is_padding(&self) -> bool {
        self.index == 0
    }

    /// The data type, if given and one this crate models ([`DataType::parse`]).
    pub fn data_type(&self) -> Option<DataType> {
        self.data_type_name.as_deref().and_then(DataType::parse)
    }
}

pub use crate::ec::sii::MailboxProtocols;

/// `<Mailbox>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mailbox {
    /// The protocols present as child elements (`<CoE>`, `<FoE>`, …).
    pub protocols: MailboxProtocols,
    /// `DataLinkLayer` attribute: the mailbox data-link layer (repeat/counter) is supported.
    pub data_link_layer: bool,
    /// The `<CoE>` attributes, if the device has CoE.
    pub coe: Option<CoeDetails>,
    /// `<CoE><InitCmd>`s in file order: the SDO downloads a configuration tool sends at the
    /// given transitions.
    pub init_cmds: Vec<InitCmd>,
}

/// The attributes of `<CoE>`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CoeDetails {
    /// `SdoInfo`: SDO information service supported.
    pub sdo_info: bool,
    /// `PdoAssign`: the PDO assignment (0x1C12/0x1C13) can be written.
    pub pdo_assign: bool,
    /// `PdoConfig`: the PDO mapping (0x16xx/0x1Axx) can be written.
    pub pdo_config: bool,
    /// `PdoUpload`: the master should read the PDO configuration at start-up.
    pub pdo_upload: bool,
    /// `CompleteAccess`: SDO complete access supported.
    pub complete_access: bool,
    /// `SegmentedSdo`: segmented SDO transfer supported (schema default true).
    pub segmented_sdo: bool,
    /// `DiagHistory`: diagnosis history object 0x10F3 supported.
    pub diag_history: bool,
    /// `EdsFile`, if given.
    pub eds_file: Option<String>,
}

impl CoeDetails {
    /// The SII General category "CoE details" byte: bit 0 SDO, bit 1 SDO info, bit 2 PDO
    /// assign, bit 3 PDO config, bit 4 PDO upload at start-up, bit 5 complete access.
    pub fn sii_byte(&self) -> u8 {
        1 | (self.sdo_info as u8) << 1
            | (self.pdo_assign as u8) << 2
            | (self.pdo_config as u8) << 3
            | (self.pdo_upload as u8) << 4
            | (self.complete_access as u8) << 5
    }
}

/// An ESM transition as written in `<InitCmd><Transition>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Transition {
    /// INIT → PRE-OP.
    IP,
    /// PRE-OP → INIT.
    PI,
    /// PRE-OP → SAFE-OP.
    PS,
    /// SAFE-OP → PRE-OP.
    SP,
    /// SAFE-OP → OP.
    SO,
    /// SAFE-OP → INIT.
    SI,
    /// OP → SAFE-OP.
    OS,
    /// OP → PRE-OP.
    OP,
    /// OP → INIT.
    OI,
    /// INIT → BOOT.
    IB,
    /// BOOT → INIT.
    BI,
    /// INIT → INIT (re-init).
    II,
}

impl Transition {
    const ALL: [Self; 12] = [
        Self::IP,
        Self::PI,
        Self::PS,
        Self::SP,
        Self::SO,
        Self::SI,
        Self::OS,
        Self::OP,
        Self::OI,
        Self::IB,
        Self::BI,
        Self::II,
    ];

    /// The ESI text, e.g. `PS`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::IP => "IP",
            Self::PI => "PI",
            Self::PS => "PS",
            Self::SP => "SP",
            Self::SO => "SO",
            Self::SI => "SI",
            Self::OS => "OS",
            Self::OP => "OP",
            Self::OI => "OI",
            Self::IB => "IB",
            Self::BI => "BI",
            Self::II => "II",
        }
    }

    /// Parse the ESI text (case-insensitive).
    pub fn parse(text: &str) -> Option<Self> {
        let t = text.trim();
        Self::ALL
            .into_iter()
            .find(|x| x.name().eq_ignore_ascii_case(t))
    }
}

/// `<InitCmd>` of `<CoE>`: an SDO download sent at state transitions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InitCmd {
    /// Where the element starts.
    pub position: Position,
    /// `<Transition>`s at which it is sent.
    pub transitions: Vec<Transition>,
    /// `<Index>`.
    pub index: u16,
    /// `<SubIndex>` (0 if absent).
    pub sub: u8,
    /// `<Data>`: the bytes to download, as written (little-endian for numbers).
    pub data: Vec<u8>,
    /// `<Comment>`.
    pub comment: String,
    /// `CompleteAccess` attribute.
    pub complete_access: bool,
    /// `Fixed` attribute: a configuration tool must not change it.
    pub fixed: bool,
    /// `<Timeout>` (ms; the element of the network description, ETG.2100, that vendor files
    /// carry too): how long the command may take. `None` when absent or 0: the master's SDO
    /// timeout.
    pub timeout_ms: Option<u32>,
    /// `<Retries>`: how often a command that timed out or was refused is sent again before the
    /// transition fails (0 when absent).
    pub retries: u8,
    /// `<Disabled>`: the command is listed but not sent.
    pub disabled: bool,
}

/// The allowed cycle times of a DC operation mode. ETG.2000 has no element for this; the
/// drive files of this project state it in `<VendorSpecific>` of the `<OpMode>` with the
/// namespace [`ECDRIVE_NAMESPACE`](super::ECDRIVE_NAMESPACE) (other tools ignore it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CycleTimes {
    /// Exactly these cycle times, in ns.
    List(Vec<u32>),
    /// `min`, `min + step`, … up to `max`, in ns.
    Range {
        /// Shortest cycle.
        min: u32,
        /// Longest cycle.
        max: u32,
        /// Step between allowed cycles (0: any value in the range).
        step: u32,
    },
}

impl CycleTimes {
    /// Whether `ns` is an allowed cycle time.
    pub fn contains(&self, ns: u32) -> bool {
        match self {
            Self::List(l) => l.contains(&ns),
            Self::Range { min, max, step } => {
                ns >= *min && ns <= *max && (*step == 0 || (ns - min) % step == 0)
            }
        }
    }

    /// The shortest allowed cycle.
    pub fn min(&self) -> Option<u32> {
        match self {
            Self::List(l) => l.iter().copied().min(),
            Self::Range { min, .. } => Some(*min),
        }
    }
}

/// `<Dc><OpMode>`: one synchronisation mode a configuration tool can choose. The part the
/// SII's DC category carries too is the one [`DcOpMode`] (name, description, AssignActivate,
/// SYNC0 cycle and its factor, shifts, SYNC1 factor); the rest only the ESI says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OpMode {
    /// Where the element starts.
    pub position: Position,
    /// The mode in SII terms: `<Name>`, `<Desc>`, `<AssignActivate>`, `<CycleTimeSync0>` and
    /// its `Factor`, `<ShiftTimeSync0>`, `<ShiftTimeSync1>` and the `Factor` of
    /// `<CycleTimeSync1>` (0 where the file gives none).
    pub mode: DcOpMode,
    /// `Factor` of `<ShiftTimeSync0>`.
    pub shift_time_sync0_factor: Option<i32>,
    /// `Input` of `<ShiftTimeSync0>`: the shift applies to inputs.
    pub shift_time_sync0_input: bool,
    /// `<CycleTimeSync1>` value in ns (0 if absent).
    pub cycle_time_sync1: u32,
    /// `<Sm>` children: per-SyncManager synchronisation settings for this mode.
    pub sms: Vec<DcSm>,
    /// Allowed cycle times (this project's vendor-specific extension), if stated.
    pub allowed_cycle_times: Option<CycleTimes>,
}

/// `<Sm>` inside a DC `<OpMode>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DcSm {
    /// `No` attribute: the SyncManager.
    pub no: u8,
    /// `<SyncType>` (the 0x1C32/0x1C33:01 value), if given.
    pub sync_type: Option<u16>,
    /// `<CycleTime>` in ns, if given.
    pub cycle_time: Option<u32>,
    /// `<ShiftTime>` in ns, if given.
    pub shift_time: Option<i32>,
    /// `<Pdo>`s: PDOs assigned in this mode.
    pub pdos: Vec<u16>,
}

/// `<Eeprom>`: what a configuration tool writes into the SII EEPROM.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Eeprom {
    /// `<ByteSize>`: EEPROM size in bytes.
    pub byte_size: Option<u32>,
    /// `<ConfigData>`: the first bytes of the EEPROM (PDI control, PDI configuration, SYNC
    /// impulse length, PDI configuration 2, station alias, …), without the checksum.
    pub config_data: Vec<u8>,
    /// `<BootStrap>`: bootstrap mailbox offsets and sizes (words 0x0014–0x0017).
    pub boot_strap: Vec<u8>,
    /// `<Data>`: a complete EEPROM image, if the vendor gives one.
    pub data: Vec<u8>,
    /// `<Category>`s: vendor categories (number and data).
    pub categories: Vec<EepromCategory>,
}

/// `<Category>` in `<Eeprom>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EepromCategory {
    /// `<CatNo>`.
    pub cat_no: u16,
    /// `<Data>`.
    pub data: Vec<u8>,
}

/// `<Profile>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// `<ProfileNo>` (402 for drives, 5001 for modular devices), if given.
    pub profile_no: Option<u32>,
    /// `<AddInfo>` (the high word of 0x1000), if given.
    pub add_info: Option<u32>,
    /// `Channel` attribute, if given.
    pub channel: Option<u32>,
    /// `<Dictionary>`, if given inline.
    pub dictionary: Option<Dictionary>,
}
