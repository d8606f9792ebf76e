//! The SII EEPROM (ETG.1000.6 §5.4, ETG.2010), one representation for both directions: a
//! [`DeviceDescription`] says what a device's EEPROM holds (identity, names, mailbox,
//! SyncManagers, FMMU usage, PDOs, DC operation modes, CoE details and flags); [`build`] emits
//! the byte image (what the software slave serves), [`parse`] reads one back (what the
//! master's tools decode), and [`SiiImage`] is a byte view for single words and categories.
//!
//! Layout (word addresses): 0–6 ESC configuration area, 7 CRC-8 of words 0–6, 8–15 identity,
//! 0x14–0x17 bootstrap mailbox, 0x18–0x1B standard mailbox, 0x1C mailbox protocols, 0x3E size,
//! 0x3F version, 0x40+ categories (Strings, General, FMMU, SyncM, TxPDO, RxPDO, DC, End).

/// The SII checksum: CRC-8, polynomial 0x07, initial value 0xFF, no reflection, stored in the
/// low byte of word 7 over bytes 0..14 (words 0–6). One definition for the slave that writes
/// it and the master's tools that check it.
pub const SII_CRC: crc::Crc<u8> = crc::Crc::<u8>::new(&crc::Algorithm {
    width: 8,
    poly: 0x07,
    init: 0xFF,
    refin: false,
    refout: false,
    xorout: 0x00,
    check: 0xFB,
    residue: 0x00,
});

/// The checksum of an SII image's header (its first 14 bytes), or `None` if it is shorter.
pub fn header_checksum(image: &[u8]) -> Option<u8> {
    image.get(..14).map(|h| SII_CRC.checksum(h))
}

/// Word address of the first category.
pub const FIRST_CATEGORY_WORD: u16 = 0x0040;

/// SII category types (ETG.2010 table 6).
pub mod category {
    /// Strings.
    pub const STRINGS: u16 = 10;
    /// Data types.
    pub const DATA_TYPES: u16 = 20;
    /// General.
    pub const GENERAL: u16 = 30;
    /// FMMU usage.
    pub const FMMU: u16 = 40;
    /// SyncManagers.
    pub const SYNC_MANAGER: u16 = 41;
    /// FMMU extension (FMMU → SM assignment).
    pub const FMMU_EX: u16 = 42;
    /// TxPDOs (inputs).
    pub const TXPDO: u16 = 50;
    /// RxPDOs (outputs).
    pub const RXPDO: u16 = 51;
    /// Distributed clock operation modes.
    pub const DC: u16 = 60;
    /// End marker.
    pub const END: u16 = 0xFFFF;

    /// The category's name, as ESI and the IgH tool print it.
    pub fn name(kind: u16) -> &'static str {
        match kind {
            STRINGS => "Strings",
            DATA_TYPES => "DataTypes",
            GENERAL => "General",
            FMMU => "FMMU",
            SYNC_MANAGER => "SyncM",
            FMMU_EX => "FMMUX",
            TXPDO => "TxPDO",
            RXPDO => "RxPDO",
            DC => "DC",
            1..=9 => "NOP",
            0x0800..=0x0FFF => "vendor specific",
            _ => "unknown",
        }
    }
}

use bitflags::bitflags;

/// Default EEPROM size in bytes (16 Kbit, the size of the common 24C16).
pub const DEFAULT_EEPROM_BYTES: usize = 2048;

/// Vendor ID, product code, revision and serial number (SII words 8–15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Identity {
    /// Vendor ID (ETG-assigned).
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
}

bitflags! {
    /// Mailbox protocols (SII word 0x1C).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct MailboxProtocols: u16 {
        /// ADS over EtherCAT.
        const AOE = 0x0001;
        /// Ethernet over EtherCAT.
        const EOE = 0x0002;
        /// CANopen over EtherCAT.
        const COE = 0x0004;
        /// File access over EtherCAT.
        const FOE = 0x0008;
        /// Servo profile over EtherCAT.
        const SOE = 0x0010;
        /// Vendor-specific.
        const VOE = 0x0020;
    }

    /// CoE details (General category byte 5).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct CoeDetails: u8 {
        /// SDO supported.
        const SDO = 0x01;
        /// SDO information supported.
        const SDO_INFO = 0x02;
        /// PDO assignment configurable.
        const PDO_ASSIGN = 0x04;
        /// PDO mapping configurable.
        const PDO_CONFIG = 0x08;
        /// Upload at start-up.
        const STARTUP_UPLOAD = 0x10;
        /// SDO complete access supported.
        const COMPLETE_ACCESS = 0x20;
    }

    /// General category flags (byte 11).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct GeneralFlags: u8 {
        /// SAFE-OP may be entered without outputs.
        const ENABLE_SAFEOP = 0x01;
        /// The device does not support LRW (masters use LRD + LWR).
        const NOT_LRW = 0x02;
        /// Mailbox data link layer supported.
        const MBOX_DLL = 0x04;
        /// Identification via AL status code.
        const IDENT_AL_STATUS = 0x08;
        /// Identification via physical memory.
        const IDENT_PHY_MEMORY = 0x10;
    }

    /// SyncManager enable flags (SyncM category byte 6).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct SmEnable: u8 {
        /// Enabled by default.
        const ENABLE = 0x01;
        /// Fixed content (not configurable).
        const FIXED = 0x02;
        /// Virtual SyncManager (no hardware).
        const VIRTUAL = 0x04;
        /// Enabled in OP only.
        const OP_ONLY = 0x08;
    }
}

/// The role of a SyncManager (SyncM category byte 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum SmType {
    /// Not used.
    Unused = 0,
    /// Mailbox, master → slave (normally SM0).
    MailboxOut = 1,
    /// Mailbox, slave → master (normally SM1).
    MailboxIn = 2,
    /// Process data outputs, master → slave (normally SM2).
    Outputs = 3,
    /// Process data inputs, slave → master (normally SM3).
    Inputs = 4,
}

/// What an FMMU is meant for (FMMU category).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FmmuUsage {
    /// Not used.
    Unused = 0,
    /// Outputs.
    Outputs = 1,
    /// Inputs.
    Inputs = 2,
    /// SyncManager status (mailbox polling; ESI `MBoxState`).
    SmStatus = 3,
}

/// The standard mailbox of a device (SII words 0x18–0x1C), and the bootstrap one if any.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MailboxDesc {
    /// Start of the master → slave mailbox (SM0).
    pub rx_offset: u16,
    /// Size of the master → slave mailbox.
    pub rx_size: u16,
    /// Start of the slave → master mailbox (SM1).
    pub tx_offset: u16,
    /// Size of the slave → master mailbox.
    pub tx_size: u16,
    /// Supported protocols.
    pub protocols: MailboxProtocols,
    /// Bootstrap mailbox `(rx_offset, rx_size, tx_offset, tx_size)`, for devices with BOOT.
    pub bootstrap: Option<[u16; 4]>,
}

/// One SyncManager as the SII describes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SmDesc {
    /// Physical start address.
    pub start: u16,
    /// Default length in bytes (0 for process data sized from the PDO mapping).
    pub length: u16,
    /// Control byte: mode (bits 0–1: 0 buffered, 2 mailbox), direction (bits 2–3: 0 ECAT
    /// reads, 1 ECAT writes), interrupts and watchdog trigger.
    pub control: u8,
    /// Enable flags.
    pub enable: SmEnable,
    /// Role.
    pub kind: SmType,
}

/// One entry of a PDO in the SII (TxPDO/RxPDO categories).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoEntryDesc {
    /// Object index (0 for padding).
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Name.
    pub name: String,
    /// CoE data type code (low byte; 0 for padding).
    pub data_type: u8,
    /// Size in bits.
    pub bits: u8,
    /// Flags.
    pub flags: u16,
}

/// One PDO in the SII.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoDesc {
    /// Mapping object index (0x16xx / 0x1Axx).
    pub index: u16,
    /// The SyncManager it is assigned to by default (0xFF: not assigned).
    pub sm: u8,
    /// DC sync mode.
    pub dc_sync: u8,
    /// Name.
    pub name: String,
    /// PDO flags (ETG.2010: mandatory, default, fixed content, …).
    pub flags: u16,
    /// Entries.
    pub entries: Vec<PdoEntryDesc>,
}

impl PdoDesc {
    /// Total size in bits.
    pub fn bits(&self) -> u32 {
        self.entries.iter().map(|e| u32::from(e.bits)).sum()
    }
}

/// One distributed-clock operation mode (DC category): the one type for a DC mode, whether it
/// comes from the SII or from an ESI file's `<Dc><OpMode>` (see `esi::OpMode`).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct DcOpMode {
    /// Name, e.g. `"DC"` or `"SM-Synchron"`.
    pub name: String,
    /// Description.
    pub description: String,
    /// Value for register 0x0980/0x0981 (low byte 0x0980 cyclic unit control, high byte
    /// 0x0981 activation), e.g. 0x0300 for SYNC0.
    pub assign_activate: u16,
    /// SYNC0 cycle time in ns (0: master's cycle).
    pub cycle_time0: u32,
    /// SYNC0 shift in ns (may be negative, e.g. for input latching before SYNC0).
    pub shift_time0: i32,
    /// SYNC1 shift in ns.
    pub shift_time1: i32,
    /// SYNC0 cycle factor: SYNC0 cycle = factor × bus cycle (negative: bus cycle ÷ |factor|;
    /// 0: none given, see [`DcOpMode::sync0_cycle_ns`]).
    pub sync0_cycle_factor: i16,
    /// SYNC1 cycle factor: SYNC1 cycle = factor × SYNC0 cycle (0: none given).
    pub sync1_cycle_factor: i16,
}

impl DcOpMode {
    /// AssignActivate bit 8: the cyclic unit is activated.
    pub const fn cyclic(&self) -> bool {
        self.assign_activate & 0x0100 != 0
    }

    /// AssignActivate bit 9: SYNC0 is generated.
    pub const fn sync0(&self) -> bool {
        self.assign_activate & 0x0200 != 0
    }

    /// AssignActivate bit 10: SYNC1 is generated.
    pub const fn sync1(&self) -> bool {
        self.assign_activate & 0x0400 != 0
    }

    /// The SYNC0 cycle in ns for a bus (task) cycle of `bus_cycle_ns`: the factor applied to
    /// the bus cycle if one is given (negative: the bus cycle ÷ |factor|), else the fixed
    /// value, else (value 0) the bus cycle.
    pub fn sync0_cycle_ns(&self, bus_cycle_ns: u64) -> u64 {
        match self.sync0_cycle_factor {
            f if f > 0 => bus_cycle_ns.saturating_mul(f.unsigned_abs().into()),
            f if f < 0 => bus_cycle_ns / u64::from(f.unsigned_abs()),
            _ if self.cycle_time0 != 0 => u64::from(self.cycle_time0),
            _ => bus_cycle_ns,
        }
    }
}

/// What the SII of a device says, in SII terms. Build the image with [`build`].
///
/// This is the meeting point between ESI files (`esi/`), the emulated drives (`drives/`,
/// `sim::devices`) and the ESC: everything the ESC needs to know about the device it fronts
/// comes from here.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceDescription {
    /// Identity.
    pub identity: Identity,
    /// Order code / type name. ethercrab reports this as `SubDevice::name()`.
    pub order: String,
    /// Device name (long). SOEM reports the first string; ethercrab's `description()`.
    pub name: String,
    /// Group name.
    pub group: String,
    /// Image name, if any.
    pub image: Option<String>,
    /// SII word 0: PDI control (low byte → 0x0140) and ESC configuration (high byte → 0x0141).
    pub pdi_control: u16,
    /// SII word 1: PDI configuration (→ 0x0150).
    pub pdi_config: u16,
    /// SII word 2: SYNC impulse length in 10 ns units (→ 0x0982).
    pub sync_impulse_len: u16,
    /// SII word 3: extended PDI configuration (→ 0x0152).
    pub pdi_config2: u16,
    /// SII word 4: configured station alias (→ 0x0012).
    pub alias: u16,
    /// Mailbox, if the device has one.
    pub mailbox: Option<MailboxDesc>,
    /// CoE details (only meaningful with a CoE mailbox).
    pub coe_details: CoeDetails,
    /// FoE details byte.
    pub foe_details: u8,
    /// EoE details byte.
    pub eoe_details: u8,
    /// Number of SoE channels.
    pub soe_channels: u8,
    /// Number of DS402 channels.
    pub ds402_channels: u8,
    /// General flags.
    pub flags: GeneralFlags,
    /// Current drawn from E-bus in mA (negative: fed in).
    pub ebus_current_ma: i16,
    /// Physical port types, one nibble per port (0 unused, 1 MII, 3 EBUS, 4 fast hot connect).
    pub port_types: u16,
    /// Physical memory address for identification.
    pub physical_memory_address: u16,
    /// SyncManagers, in SM order.
    pub sync_managers: Vec<SmDesc>,
    /// FMMU usage, in FMMU order.
    pub fmmus: Vec<FmmuUsage>,
    /// TxPDOs (inputs). Written as category 50 if not empty.
    pub tx_pdos: Vec<PdoDesc>,
    /// RxPDOs (outputs). Written as category 51 if not empty.
    pub rx_pdos: Vec<PdoDesc>,
    /// DC operation modes. Written as category 60 if not empty.
    pub dc_modes: Vec<DcOpMode>,
    /// EEPROM size in bytes (a multiple of 128, at least the image size).
    pub eeprom_bytes: usize,
}

impl Default for DeviceDescription {
    fn default() -> Self {
        Self {
            identity: Identity::default(),
            order: String::new(),
            name: String::new(),
            group: String::new(),
            image: None,
            pdi_control: 0x0080,
            pdi_config: 0,
            sync_impulse_len: 0,
            pdi_config2: 0,
            alias: 0,
            mailbox: None,
            coe_details: CoeDetails::empty(),
            foe_details: 0,
            eoe_details: 0,
            soe_channels: 0,
            ds402_channels: 0,
            flags: GeneralFlags::empty(),
            ebus_current_ma: 0,
            port_types: 0x0011,
            physical_memory_address: 0,
            sync_managers: Vec::new(),
            fmmus: Vec::new(),
            tx_pdos: Vec::new(),
            rx_pdos: Vec::new(),
            dc_modes: Vec::new(),
            eeprom_bytes: DEFAULT_EEPROM_BYTES,
        }
    }
}

impl DeviceDescription {
    /// Index of the first SyncManager of the given role.
    pub fn sm_index(&self, kind: SmType) -> Option<u8> {
        self.sync_managers
            .iter()
            .position(|s| s.kind == kind)
            .and_then(|i| u8::try_from(i).ok())
    }

    /// Whether the device has a CoE mailbox.
    pub fn has_coe(&self) -> bool {
        self.mailbox
            .as_ref()
            .is_some_and(|m| m.protocols.contains(MailboxProtocols::COE) && m.tx_size > 0)
    }

    /// Process data size in bytes of SyncManager `sm` according to the SII PDO categories
    /// (the PDOs whose default SM is `sm`).
    pub fn sii_pdo_bytes(&self, sm: u8) -> usize {
        let bits: u32 = self
            .tx_pdos
            .iter()
            .chain(self.rx_pdos.iter())
            .filter(|p| p.sm == sm)
            .map(PdoDesc::bits)
            .sum();
        (bits as usize).div_ceil(8)
    }
}

/// Why an SII image cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SiiError {
    /// A string is longer than 255 bytes.
    #[error("SII string {text:?} is {len} bytes long; the SII allows at most 255")]
    StringTooLong {
        /// The string (truncated for display by the caller if needed).
        text: String,
        /// Its length.
        len: usize,
    },
    /// More than 255 distinct strings.
    #[error("the device needs {count} distinct SII strings; the SII allows at most 255")]
    TooManyStrings {
        /// Number of strings.
        count: usize,
    },
    /// More SyncManagers than the SII/ESC supports.
    #[error("the device describes {count} SyncManagers; at most 8 are supported")]
    TooManySyncManagers {
        /// Number described.
        count: usize,
    },
    /// An SM control byte that masters reject.
    #[error(
        "SM{sm}: control byte 0x{control:02X} has mode {mode} / direction {direction}; \
         only mode 0 (buffered) or 2 (mailbox) and direction 0 (ECAT read) or 1 (ECAT write) are valid"
    )]
    InvalidSmControl {
        /// SM index.
        sm: usize,
        /// The control byte.
        control: u8,
        /// Operation mode bits.
        mode: u8,
        /// Direction bits.
        direction: u8,
    },
    /// A PDO has more than 255 entries.
    #[error("PDO 0x{index:04X} has {count} entries; at most 255 fit the SII")]
    TooManyPdoEntries {
        /// PDO index.
        index: u16,
        /// Number of entries.
        count: usize,
    },
    /// A category does not fit its 16-bit word length.
    #[error("SII category {category} is {bytes} bytes long; too long for a category")]
    CategoryTooLong {
        /// Category type.
        category: u16,
        /// Its size.
        bytes: usize,
    },
    /// The EEPROM size is not a multiple of 128 bytes, or larger than 4 Mbit.
    #[error(
        "EEPROM size {bytes} bytes is not a multiple of 128 bytes between 128 bytes and 512 KiB"
    )]
    InvalidEepromSize {
        /// Requested size.
        bytes: usize,
    },
    /// The image does not fit the EEPROM.
    #[error("the SII image needs {needed} bytes but the EEPROM holds {capacity}")]
    ImageTooLarge {
        /// Bytes needed.
        needed: usize,
        /// EEPROM size.
        capacity: usize,
    },
}

struct Strings {
    list: Vec<String>,
}

impl Strings {
    fn index(&mut self, s: &str) -> Result<u8, SiiError> {
        if s.is_empty() {
            return Ok(0);
        }
        if s.len() > 255 {
            return Err(SiiError::StringTooLong {
                text: s.chars().take(40).collect(),
                len: s.len(),
            });
        }
        let pos = match self.list.iter().position(|x| x == s) {
            Some(p) => p,
            None => {
                self.list.push(s.to_owned());
                self.list.len() - 1
            }
        };
        u8::try_from(pos + 1).map_err(|_| SiiError::TooManyStrings {
            count: self.list.len(),
        })
    }
}

fn push_u16(v: &mut Vec<u8>, x: u16) {
    v.extend_from_slice(&x.to_le_bytes());
}

fn push_u32(v: &mut Vec<u8>, x: u32) {
    v.extend_from_slice(&x.to_le_bytes());
}

fn push_category(img: &mut Vec<u8>, kind: u16, mut data: Vec<u8>) -> Result<(), SiiError> {
    if data.len() % 2 == 1 {
        data.push(0);
    }
    let words = u16::try_from(data.len() / 2).map_err(|_| SiiError::CategoryTooLong {
        category: kind,
        bytes: data.len(),
    })?;
    push_u16(img, kind);
    push_u16(img, words);
    img.extend_from_slice(&data);
    Ok(())
}

/// Build the SII EEPROM image for a device. The result is exactly `desc.eeprom_bytes` long,
/// unused space filled with 0xFF as in an erased EEPROM.
pub fn build(desc: &DeviceDescription) -> Result<SiiImage, SiiError> {
    let size = desc.eeprom_bytes;
    if size < 128 || size % 128 != 0 || size > 512 * 1024 {
        return Err(SiiError::InvalidEepromSize { bytes: size });
    }
    check_sync_managers(desc)?;
    let mut strings = Strings { list: Vec::new() };
    // Order matters for SOEM, which names a device by string 1: the device name comes first.
    let name_idx = strings.index(&desc.name)?;
    let order_idx = strings.index(&desc.order)?;
    let group_idx = strings.index(&desc.group)?;
    let image_idx = strings.index(desc.image.as_deref().unwrap_or(""))?;
    let pdo_cats = pdo_categories(desc, &mut strings)?;
    let dc = dc_category(desc, &mut strings)?;
    let mut img = header_words(desc);

    // Strings.
    let mut s = Vec::new();
    s.push(strings.list.len() as u8);
    for x in &strings.list {
        s.push(x.len() as u8);
        s.extend_from_slice(x.as_bytes());
    }
    push_category(&mut img, category::STRINGS, s)?;

    // General.
    let mut g = vec![0u8; 32];
    g[0] = group_idx;
    g[1] = image_idx;
    g[2] = order_idx;
    g[3] = name_idx;
    g[5] = desc.coe_details.bits();
    g[6] = desc.foe_details;
    g[7] = desc.eoe_details;
    g[8] = desc.soe_channels;
    g[9] = desc.ds402_channels;
    g[11] = desc.flags.bits();
    g[12..14].copy_from_slice(&desc.ebus_current_ma.to_le_bytes());
    g[14..16].copy_from_slice(&desc.port_types.to_le_bytes());
    g[16..18].copy_from_slice(&desc.physical_memory_address.to_le_bytes());
    push_category(&mut img, category::GENERAL, g)?;

    if !desc.fmmus.is_empty() {
        let f = desc.fmmus.iter().map(|u| *u as u8).collect();
        push_category(&mut img, category::FMMU, f)?;
    }
    if !desc.sync_managers.is_empty() {
        let mut d = Vec::new();
        for sm in &desc.sync_managers {
            push_u16(&mut d, sm.start);
            push_u16(&mut d, sm.length);
            d.push(sm.control);
            d.push(0);
            d.push(sm.enable.bits());
            d.push(sm.kind as u8);
        }
        push_category(&mut img, category::SYNC_MANAGER, d)?;
    }
    for (kind, data) in pdo_cats {
        push_category(&mut img, kind, data)?;
    }
    if !dc.is_empty() {
        push_category(&mut img, category::DC, dc)?;
    }
    push_u16(&mut img, category::END);
    push_u16(&mut img, 0);

    if img.len() > size {
        return Err(SiiError::ImageTooLarge {
            needed: img.len(),
            capacity: size,
        });
    }
    img.resize(size, 0xFF);
    Ok(SiiImage { bytes: img })
}

/// At most eight SyncManagers, each with a mode and direction the SII can describe.
fn check_sync_managers(desc: &DeviceDescription) -> Result<(), SiiError> {
    if desc.sync_managers.len() > 8 {
        return Err(SiiError::TooManySyncManagers {
            count: desc.sync_managers.len(),
        });
    }
    for (sm, s) in desc.sync_managers.iter().enumerate() {
        let mode = s.control & 0x03;
        let direction = (s.control >> 2) & 0x03;
        if !(mode == 0 || mode == 2) || direction > 1 {
            return Err(SiiError::InvalidSmControl {
                sm,
                control: s.control,
                mode,
                direction,
            });
        }
    }

    Ok(())
}

/// The TxPDO and RxPDO categories (their names go into `strings`).
fn pdo_categories(
    desc: &DeviceDescription,
    strings: &mut Strings,
) -> Result<Vec<(u16, Vec<u8>)>, SiiError> {
    let mut pdo_cats = Vec::new();
    for (kind, pdos) in [
        (category::TXPDO, &desc.tx_pdos),
        (category::RXPDO, &desc.rx_pdos),
    ] {
        if pdos.is_empty() {
            continue;
        }
        let mut data = Vec::new();
        for p in pdos {
            let n = u8::try_from(p.entries.len()).map_err(|_| SiiError::TooManyPdoEntries {
                index: p.index,
                count: p.entries.len(),
            })?;
            push_u16(&mut data, p.index);
            data.push(n);
            data.push(p.sm);
            data.push(p.dc_sync);
            data.push(strings.index(&p.name)?);
            push_u16(&mut data, p.flags);
            for e in &p.entries {
                push_u16(&mut data, e.index);
                data.push(e.sub);
                data.push(strings.index(&e.name)?);
                data.push(e.data_type);
                data.push(e.bits);
                push_u16(&mut data, e.flags);
            }
        }
        pdo_cats.push((kind, data));
    }

    Ok(pdo_cats)
}

/// The DC category's data: one record per DC mode (its names go into `strings`).
fn dc_category(desc: &DeviceDescription, strings: &mut Strings) -> Result<Vec<u8>, SiiError> {
    let mut dc = Vec::new();
    for m in &desc.dc_modes {
        push_u32(&mut dc, m.cycle_time0);
        dc.extend_from_slice(&m.shift_time0.to_le_bytes());
        dc.extend_from_slice(&m.shift_time1.to_le_bytes());
        dc.extend_from_slice(&m.sync1_cycle_factor.to_le_bytes());
        push_u16(&mut dc, m.assign_activate);
        dc.extend_from_slice(&m.sync0_cycle_factor.to_le_bytes());
        dc.push(strings.index(&m.name)?);
        dc.push(strings.index(&m.description)?);
        dc.extend_from_slice(&[0; 4]);
    }

    Ok(dc)
}

/// The header words 0x00–0x3F: PDI control and configuration, alias, identity, mailbox, size,
/// version, and the checksum over words 0–6.
fn header_words(desc: &DeviceDescription) -> Vec<u8> {
    let size = desc.eeprom_bytes;
    let mut img = vec![0u8; usize::from(FIRST_CATEGORY_WORD) * 2];
    let mut w = |word: usize, v: u16| {
        img[word * 2..word * 2 + 2].copy_from_slice(&v.to_le_bytes());
    };
    w(0, desc.pdi_control);
    w(1, desc.pdi_config);
    w(2, desc.sync_impulse_len);
    w(3, desc.pdi_config2);
    w(4, desc.alias);
    let id = desc.identity;
    for (i, v) in [id.vendor_id, id.product_code, id.revision, id.serial]
        .into_iter()
        .enumerate()
    {
        w(8 + 2 * i, v as u16);
        w(9 + 2 * i, (v >> 16) as u16);
    }
    if let Some(m) = &desc.mailbox {
        if let Some(b) = m.bootstrap {
            for (i, v) in b.into_iter().enumerate() {
                w(0x14 + i, v);
            }
        }
        w(0x18, m.rx_offset);
        w(0x19, m.rx_size);
        w(0x1A, m.tx_offset);
        w(0x1B, m.tx_size);
        w(0x1C, m.protocols.bits());
    }
    w(0x3E, ((size * 8 / 1024) as u16).saturating_sub(1));
    w(0x3F, 1);
    let crc = SII_CRC.checksum(&img[0..14]);
    img[14] = crc;
    img[15] = 0;

    img
}

/// An SII EEPROM image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SiiImage {
    bytes: Vec<u8>,
}

/// One category of an SII image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Category<'a> {
    /// Category type.
    pub kind: u16,
    /// Word address of the category data.
    pub word: u16,
    /// The data.
    pub data: &'a [u8],
}

impl SiiImage {
    /// Wrap raw EEPROM content (e.g. a dump). Odd lengths are padded with 0xFF.
    pub fn from_bytes(mut bytes: Vec<u8>) -> Self {
        if bytes.len() % 2 == 1 {
            bytes.push(0xFF);
        }
        Self { bytes }
    }

    /// The raw bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The raw bytes, mutable (EEPROM writes).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes
    }

    /// The word at word address `addr`; 0xFFFF beyond the end (like an erased EEPROM).
    pub fn word(&self, addr: u32) -> u16 {
        let at = addr as usize * 2;
        match self.bytes.get(at..at + 2) {
            Some(b) => u16::from_le_bytes([b[0], b[1]]),
            None => 0xFFFF,
        }
    }

    /// Whether the CRC in word 7 matches words 0–6.
    pub fn checksum_ok(&self) -> bool {
        match self.bytes.get(0..15) {
            Some(b) => SII_CRC.checksum(&b[..14]) == b[14],
            None => false,
        }
    }

    /// The identity in words 8–15.
    pub fn identity(&self) -> Identity {
        let d = |w: u32| u32::from(self.word(w)) | u32::from(self.word(w + 1)) << 16;
        Identity {
            vendor_id: d(8),
            product_code: d(10),
            revision: d(12),
            serial: d(14),
        }
    }

    /// Iterate over the categories, up to the end marker or the end of the image.
    pub fn categories(&self) -> impl Iterator<Item = Category<'_>> + '_ {
        let mut word = u32::from(FIRST_CATEGORY_WORD);
        core::iter::from_fn(move || {
            let kind = self.word(word);
            if kind == category::END {
                return None;
            }
            let len = u32::from(self.word(word + 1));
            let start = (word + 2) as usize * 2;
            let end = start + len as usize * 2;
            let data = self.bytes.get(start..end)?;
            let cat = Category {
                kind,
                word: (word + 2) as u16,
                data,
            };
            word += 2 + len;
            Some(cat)
        })
    }

    /// The first category of a type.
    pub fn category(&self, kind: u16) -> Option<&[u8]> {
        self.categories().find(|c| c.kind == kind).map(|c| c.data)
    }

    /// String number `index` (1-based) from the Strings category.
    pub fn string(&self, index: u8) -> Option<&str> {
        if index == 0 {
            return None;
        }
        let data = self.category(category::STRINGS)?;
        let count = *data.first()?;
        if index > count {
            return None;
        }
        let mut at = 1usize;
        for i in 1..=count {
            let len = usize::from(*data.get(at)?);
            let s = data.get(at + 1..at + 1 + len)?;
            if i == index {
                return core::str::from_utf8(s).ok();
            }
            at += 1 + len;
        }
        None
    }
}

/// Why SII bytes could not be parsed: what was being read, its word address, what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("SII {what} at word 0x{word:04X}: {reason}")]
pub struct SiiDecodeError {
    /// What was being read.
    pub what: String,
    /// Its word address.
    pub word: u32,
    /// What is wrong.
    pub reason: String,
}

/// One category as it sits in an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CategoryInfo {
    /// Category type.
    pub kind: u16,
    /// Word address of its data.
    pub word: u32,
    /// Its length in words.
    pub words: u16,
}

/// What [`parse`] read from an image: the [`DeviceDescription`], and what of the image itself
/// a tool shows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParsedSii {
    /// The device as the image describes it.
    pub description: DeviceDescription,
    /// Whether the CRC in word 7 matches words 0–6.
    pub checksum_ok: bool,
    /// Mailbox protocol bits (word 0x1C), also without a mailbox.
    pub protocol_bits: u16,
    /// SII version (word 0x3F).
    pub version: u16,
    /// The categories in image order.
    pub categories: Vec<CategoryInfo>,
    /// The strings (index 0 here is SII string 1).
    pub strings: Vec<String>,
    /// Whether the image has a General category.
    pub has_general: bool,
}

impl ParsedSii {
    /// The string with SII index `i` (1-based; 0 and unknown indices give `""`).
    pub fn string(&self, i: u8) -> &str {
        string_at(&self.strings, i)
    }
}

fn string_at(strings: &[String], i: u8) -> &str {
    match usize::from(i).checked_sub(1) {
        Some(k) => strings.get(k).map_or("", String::as_str),
        None => "",
    }
}

/// Checked little-endian reads from SII data, errors naming the word.
struct Reader<'a> {
    data: &'a [u8],
    what: &'a str,
    word: u32,
}

impl Reader<'_> {
    fn err(&self, at: usize, reason: &str) -> SiiDecodeError {
        SiiDecodeError {
            what: self.what.to_string(),
            word: self.word + (at / 2) as u32,
            reason: reason.to_string(),
        }
    }

    fn u8(&self, at: usize) -> Result<u8, SiiDecodeError> {
        self.data
            .get(at)
            .copied()
            .ok_or_else(|| self.err(at, "the data ends early"))
    }

    fn u16(&self, at: usize) -> Result<u16, SiiDecodeError> {
        Ok(u16::from_le_bytes([self.u8(at)?, self.u8(at + 1)?]))
    }

    fn u32(&self, at: usize) -> Result<u32, SiiDecodeError> {
        Ok(u32::from(self.u16(at)?) | u32::from(self.u16(at + 2)?) << 16)
    }
}

/// Parse an SII image (a whole EEPROM, or a dump up to the end category): the inverse of
/// [`build`] for every description it accepts (a trailing unused FMMU aside, which the padding
/// of the FMMU category cannot tell from none).
pub fn parse(bytes: &[u8]) -> Result<ParsedSii, SiiDecodeError> {
    let head = Reader {
        data: bytes,
        what: "header",
        word: 0,
    };
    let w = |i: usize| head.u16(i * 2);
    let words4 = |base: usize| -> Result<[u16; 4], SiiDecodeError> {
        Ok([w(base)?, w(base + 1)?, w(base + 2)?, w(base + 3)?])
    };
    let valid = |m: [u16; 4]| m[1] != 0 && m[1] != 0xFFFF;
    let protocol_bits = w(0x1C)?;
    let (bootstrap, standard) = (words4(0x14)?, words4(0x18)?);
    let mailbox = valid(standard).then(|| MailboxDesc {
        rx_offset: standard[0],
        rx_size: standard[1],
        tx_offset: standard[2],
        tx_size: standard[3],
        protocols: MailboxProtocols::from_bits_retain(protocol_bits),
        bootstrap: valid(bootstrap).then_some(bootstrap),
    });
    let mut desc = DeviceDescription {
        identity: Identity {
            vendor_id: head.u32(16)?,
            product_code: head.u32(20)?,
            revision: head.u32(24)?,
            serial: head.u32(28)?,
        },
        pdi_control: w(0)?,
        pdi_config: w(1)?,
        sync_impulse_len: w(2)?,
        pdi_config2: w(3)?,
        alias: w(4)?,
        mailbox,
        eeprom_bytes: (usize::from(w(0x3E)?) + 1) * 128,
        ..DeviceDescription::default()
    };
    let cats = category_list(bytes)?;
    let strings = match cats.iter().find(|(c, _)| c.kind == category::STRINGS) {
        Some((c, data)) => parse_strings(c.word, data)?,
        None => Vec::new(),
    };
    let mut has_general = false;
    for (c, data) in &cats {
        let name = format!("{} category", category::name(c.kind));
        let r = Reader {
            data,
            what: &name,
            word: c.word,
        };
        match c.kind {
            category::GENERAL => {
                has_general = true;
                parse_general(&r, &strings, &mut desc)?;
            }
            category::FMMU => {
                desc.fmmus = data.iter().map(|b| FmmuUsage::from_byte(*b)).collect();
                // A padding byte makes the count even: drop a trailing unused one.
                if data.len() % 2 == 0 && data.last().is_some_and(|b| *b == 0 || *b == 0xFF) {
                    desc.fmmus.pop();
                }
            }
            category::SYNC_MANAGER => {
                for k in 0..data.len() / 8 {
                    let at = k * 8;
                    desc.sync_managers.push(SmDesc {
                        start: r.u16(at)?,
                        length: r.u16(at + 2)?,
                        control: r.u8(at + 4)?,
                        enable: SmEnable::from_bits_retain(r.u8(at + 6)?),
                        kind: SmType::from_byte(r.u8(at + 7)?),
                    });
                }
            }
            category::TXPDO => desc.tx_pdos.extend(parse_pdos(&r, &strings)?),
            category::RXPDO => desc.rx_pdos.extend(parse_pdos(&r, &strings)?),
            category::DC => {
                for k in 0..data.len() / 24 {
                    let at = k * 24;
                    desc.dc_modes.push(DcOpMode {
                        cycle_time0: r.u32(at)?,
                        shift_time0: r.u32(at + 4)? as i32,
                        shift_time1: r.u32(at + 8)? as i32,
                        sync1_cycle_factor: r.u16(at + 12)? as i16,
                        assign_activate: r.u16(at + 14)?,
                        sync0_cycle_factor: r.u16(at + 16)? as i16,
                        name: string_at(&strings, r.u8(at + 18)?).to_string(),
                        description: string_at(&strings, r.u8(at + 19)?).to_string(),
                    });
                }
            }
            _ => {}
        }
    }
    Ok(ParsedSii {
        description: desc,
        checksum_ok: header_checksum(bytes) == bytes.get(14).copied(),
        protocol_bits,
        version: w(0x3F)?,
        categories: cats.iter().map(|(c, _)| *c).collect(),
        strings,
        has_general,
    })
}

/// The categories from word 0x40 on, up to the end marker or the end of the data.
fn category_list(bytes: &[u8]) -> Result<Vec<(CategoryInfo, &[u8])>, SiiDecodeError> {
    let list = Reader {
        data: bytes,
        what: "category list",
        word: 0,
    };
    let mut cats = Vec::new();
    let mut word = u32::from(FIRST_CATEGORY_WORD);
    loop {
        let at = word as usize * 2;
        if at >= bytes.len() {
            // A dump cut short (or an erased EEPROM without end marker): stop.
            break;
        }
        let kind = list.u16(at)?;
        if kind == category::END {
            break;
        }
        let len = list.u16(at + 2)?;
        let start = at + 4;
        let end = start + usize::from(len) * 2;
        let data = bytes.get(start..end).ok_or_else(|| SiiDecodeError {
            what: format!("category {} ({kind})", category::name(kind)),
            word,
            reason: format!(
                "{len} words announced, the data ends at word 0x{:04X}",
                bytes.len() / 2
            ),
        })?;
        let info = CategoryInfo {
            kind,
            word: word + 2,
            words: len,
        };
        cats.push((info, data));
        word += 2 + u32::from(len);
    }
    Ok(cats)
}

/// The Strings category: a count, then length-prefixed strings.
fn parse_strings(word: u32, data: &[u8]) -> Result<Vec<String>, SiiDecodeError> {
    let r = Reader {
        data,
        what: "Strings category",
        word,
    };
    let n = r.u8(0)?;
    let mut at = 1;
    let mut out = Vec::with_capacity(usize::from(n));
    for _ in 0..n {
        let len = usize::from(r.u8(at)?);
        let s = data
            .get(at + 1..at + 1 + len)
            .ok_or_else(|| r.err(at, "a string runs past the category"))?;
        out.push(String::from_utf8_lossy(s).into_owned());
        at += 1 + len;
    }
    Ok(out)
}

/// The General category into `desc`.
fn parse_general(
    r: &Reader<'_>,
    strings: &[String],
    desc: &mut DeviceDescription,
) -> Result<(), SiiDecodeError> {
    let s = |i: u8| string_at(strings, i).to_string();
    desc.group = s(r.u8(0)?);
    let image = s(r.u8(1)?);
    desc.image = (!image.is_empty()).then_some(image);
    desc.order = s(r.u8(2)?);
    desc.name = s(r.u8(3)?);
    desc.coe_details = CoeDetails::from_bits_retain(r.u8(5)?);
    desc.foe_details = r.u8(6)?;
    desc.eoe_details = r.u8(7)?;
    desc.soe_channels = r.u8(8)?;
    desc.ds402_channels = r.u8(9)?;
    desc.flags = GeneralFlags::from_bits_retain(r.u8(11)?);
    desc.ebus_current_ma = r.u16(12)? as i16;
    desc.port_types = r.u16(14)?;
    desc.physical_memory_address = r.u16(16)?;
    Ok(())
}

/// The PDOs of a TxPDO or RxPDO category.
fn parse_pdos(r: &Reader<'_>, strings: &[String]) -> Result<Vec<PdoDesc>, SiiDecodeError> {
    let mut at = 0;
    let mut pdos = Vec::new();
    while at + 8 <= r.data.len() {
        let n = r.u8(at + 2)?;
        let mut pdo = PdoDesc {
            index: r.u16(at)?,
            sm: r.u8(at + 3)?,
            dc_sync: r.u8(at + 4)?,
            name: string_at(strings, r.u8(at + 5)?).to_string(),
            flags: r.u16(at + 6)?,
            entries: Vec::with_capacity(usize::from(n)),
        };
        at += 8;
        for _ in 0..n {
            pdo.entries.push(PdoEntryDesc {
                index: r.u16(at)?,
                sub: r.u8(at + 2)?,
                name: string_at(strings, r.u8(at + 3)?).to_string(),
                data_type: r.u8(at + 4)?,
                bits: r.u8(at + 5)?,
                flags: r.u16(at + 6)?,
            });
            at += 8;
        }
        pdos.push(pdo);
    }
    Ok(pdos)
}

impl SmType {
    /// The type of an SII SyncManager record's last byte (unknown values: unused).
    pub fn from_byte(b: u8) -> Self {
        match b {
            1 => Self::MailboxOut,
            2 => Self::MailboxIn,
            3 => Self::Outputs,
            4 => Self::Inputs,
            _ => Self::Unused,
        }
    }

    /// The ESI name (`MBoxOut`, `MBoxIn`, `Outputs`, `Inputs`, `Unused`).
    pub fn esi_name(self) -> &'static str {
        match self {
            Self::MailboxOut => "MBoxOut",
            Self::MailboxIn => "MBoxIn",
            Self::Outputs => "Outputs",
            Self::Inputs => "Inputs",
            Self::Unused => "Unused",
        }
    }
}

impl FmmuUsage {
    /// The usage of an SII FMMU byte (unknown values: unused).
    pub fn from_byte(b: u8) -> Self {
        match b {
            1 => Self::Outputs,
            2 => Self::Inputs,
            3 => Self::SmStatus,
            _ => Self::Unused,
        }
    }

    /// The ESI name (`Outputs`, `Inputs`, `MBoxState`, `Unused`).
    pub fn esi_name(self) -> &'static str {
        match self {
            Self::Outputs => "Outputs",
            Self::Inputs => "Inputs",
            Self::SmStatus => "MBoxState",
            Self::Unused => "Unused",
        }
    }

    /// The `<Fmmu>` element text of an ESI file (empty for unused).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Outputs => "Outputs",
            Self::Inputs => "Inputs",
            Self::SmStatus => "MBoxState",
            Self::Unused => "",
        }
    }

    /// The SII FMMU category byte: 1 outputs, 2 inputs, 3 SyncManager status (ESI
    /// `MBoxState`), 0 unused.
    pub const fn sii_code(self) -> u8 {
        self as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc() -> DeviceDescription {
        DeviceDescription {
            identity: Identity {
                vendor_id: 0x0000_0ECD,
                product_code: 0x1234_5678,
                revision: 0x0002_0001,
                serial: 42,
            },
            order: "TEST-IO".into(),
            name: "Test I/O device".into(),
            group: "Test".into(),
            sync_managers: vec![
                SmDesc {
                    start: 0x1000,
                    length: 2,
                    control: 0x64,
                    enable: SmEnable::ENABLE,
                    kind: SmType::Outputs,
                },
                SmDesc {
                    start: 0x1100,
                    length: 2,
                    control: 0x20,
                    enable: SmEnable::ENABLE,
                    kind: SmType::Inputs,
                },
            ],
            fmmus: vec![FmmuUsage::Outputs, FmmuUsage::Inputs],
            rx_pdos: vec![PdoDesc {
                index: 0x1600,
                sm: 0,
                dc_sync: 0,
                name: "Outputs".into(),
                flags: 0,
                entries: vec![PdoEntryDesc {
                    index: 0x7000,
                    sub: 1,
                    name: "Out".into(),
                    data_type: 6,
                    bits: 16,
                    flags: 0,
                }],
            }],
            ..Default::default()
        }
    }

    #[test]
    fn crc_matches_bitwise_definition() {
        // Independent bit-by-bit implementation of IEC 61158-6-12 §5.4: polynomial
        // x^8 + x^2 + x + 1, initial value 0xFF, MSB first.
        fn bitwise(data: &[u8]) -> u8 {
            let mut crc = 0xFFu8;
            for &b in data {
                crc ^= b;
                for _ in 0..8 {
                    crc = if crc & 0x80 != 0 {
                        (crc << 1) ^ 0x07
                    } else {
                        crc << 1
                    };
                }
            }
            crc
        }
        assert_eq!(bitwise(b"123456789"), 0xFB);
        assert_eq!(SII_CRC.checksum(b"123456789"), 0xFB);
        let header = [
            0x80, 0x0C, 0x00, 0xCC, 0x88, 0x13, 0xFF, 0x00, 0, 0, 0, 0, 0, 0,
        ];
        assert_eq!(SII_CRC.checksum(&header), bitwise(&header));
    }

    #[test]
    fn image_layout() {
        let img = build(&desc()).unwrap();
        assert_eq!(img.bytes().len(), 2048);
        assert!(img.checksum_ok());
        assert_eq!(img.identity(), desc().identity);
        assert_eq!(img.word(0x3E), 15);
        assert_eq!(img.word(0x3F), 1);
        assert_eq!(img.word(5000), 0xFFFF);
        let kinds: Vec<u16> = img.categories().map(|c| c.kind).collect();
        assert_eq!(
            kinds,
            vec![
                category::STRINGS,
                category::GENERAL,
                category::FMMU,
                category::SYNC_MANAGER,
                category::RXPDO
            ]
        );
        let g = img.category(category::GENERAL).unwrap();
        assert_eq!(img.string(g[3]), Some("Test I/O device"));
        assert_eq!(img.string(g[2]), Some("TEST-IO"));
        assert_eq!(img.string(1), Some("Test I/O device"));
        let sm = img.category(category::SYNC_MANAGER).unwrap();
        assert_eq!(&sm[0..8], &[0x00, 0x10, 2, 0, 0x64, 0, 1, 3]);
        let pdo = img.category(category::RXPDO).unwrap();
        assert_eq!(&pdo[0..4], &[0x00, 0x16, 1, 0]);
        assert_eq!(pdo[8 + 5], 16);
        // Corrupt word 4: the checksum no longer matches.
        let mut bad = img.clone();
        bad.bytes_mut()[8] ^= 1;
        assert!(!bad.checksum_ok());
    }

    #[test]
    fn rejects_bad_descriptions() {
        let mut d = desc();
        d.sync_managers[0].control = 0x03;
        assert!(matches!(
            build(&d),
            Err(SiiError::InvalidSmControl { sm: 0, .. })
        ));
        let mut d = desc();
        d.name = "x".repeat(300);
        assert!(matches!(
            build(&d),
            Err(SiiError::StringTooLong { len: 300, .. })
        ));
        let mut d = desc();
        d.eeprom_bytes = 100;
        assert!(matches!(build(&d), Err(SiiError::InvalidEepromSize { .. })));
        let mut d = desc();
        d.eeprom_bytes = 128;
        assert!(matches!(build(&d), Err(SiiError::ImageTooLarge { .. })));
    }

    #[test]
    fn parse_reads_what_build_wrote() {
        let mut d = desc();
        d.image = Some("img".into());
        d.physical_memory_address = 0x1234;
        d.dc_modes = vec![DcOpMode {
            name: "DC".into(),
            description: "SYNC0".into(),
            assign_activate: 0x0300,
            cycle_time0: 0,
            shift_time0: -5,
            shift_time1: 7,
            sync0_cycle_factor: 1,
            sync1_cycle_factor: -1,
        }];
        let img = build(&d).expect("valid");
        let p = parse(img.bytes()).expect("parses");
        assert_eq!(p.description, d);
        assert!(p.checksum_ok && p.has_general);
        assert_eq!(p.version, 1);
        assert_eq!(p.string(1), "Test I/O device");
        assert_eq!(
            p.categories.first().map(|c| c.kind),
            Some(category::STRINGS)
        );
    }

    #[test]
    fn a_category_past_the_end_is_named() {
        let img = build(&desc()).expect("valid");
        let cut = &img.bytes()[..usize::from(FIRST_CATEGORY_WORD) * 2 + 6];
        let e = parse(cut).expect_err("the Strings category runs past the end");
        assert!(e.to_string().contains("Strings"), "{e}");
        assert!(parse(&[0u8; 10]).is_err());
    }

    mod generated {
        use super::super::*;
        use proptest::prelude::*;

        fn text() -> impl Strategy<Value = String> {
            "[A-Za-z0-9 _-]{0,12}"
        }

        fn entry() -> impl Strategy<Value = PdoEntryDesc> {
            (
                any::<u16>(),
                any::<u8>(),
                text(),
                any::<u8>(),
                any::<u8>(),
                any::<u16>(),
            )
                .prop_map(|(index, sub, name, data_type, bits, flags)| PdoEntryDesc {
                    index,
                    sub,
                    name,
                    data_type,
                    bits,
                    flags,
                })
        }

        fn pdo() -> impl Strategy<Value = PdoDesc> {
            (
                any::<u16>(),
                any::<u8>(),
                any::<u8>(),
                text(),
                any::<u16>(),
                proptest::collection::vec(entry(), 0..4),
            )
                .prop_map(|(index, sm, dc_sync, name, flags, entries)| PdoDesc {
                    index,
                    sm,
                    dc_sync,
                    name,
                    flags,
                    entries,
                })
        }

        fn sm() -> impl Strategy<Value = SmDesc> {
            (
                any::<u16>(),
                any::<u16>(),
                prop_oneof![Just(0u8), Just(2u8)],
                0u8..2,
                0u8..16,
                any::<u8>(),
                0u8..5,
            )
                .prop_map(|(start, length, mode, dir, high, enable, kind)| SmDesc {
                    start,
                    length,
                    control: mode | dir << 2 | high << 4,
                    enable: SmEnable::from_bits_retain(enable),
                    kind: SmType::from_byte(kind),
                })
        }

        fn dc() -> impl Strategy<Value = DcOpMode> {
            (
                text(),
                text(),
                any::<u16>(),
                any::<u32>(),
                any::<i32>(),
                any::<i32>(),
                any::<i16>(),
                any::<i16>(),
            )
                .prop_map(|(name, description, aa, c0, s0, s1, f0, f1)| DcOpMode {
                    name,
                    description,
                    assign_activate: aa,
                    cycle_time0: c0,
                    shift_time0: s0,
                    shift_time1: s1,
                    sync0_cycle_factor: f0,
                    sync1_cycle_factor: f1,
                })
        }

        fn mailbox() -> impl Strategy<Value = Option<MailboxDesc>> {
            proptest::option::of(
                (
                    any::<u16>(),
                    1u16..0xFFFF,
                    any::<u16>(),
                    any::<u16>(),
                    any::<u16>(),
                    proptest::option::of((any::<u16>(), 1u16..0xFFFF, any::<u16>(), any::<u16>())),
                )
                    .prop_map(|(ro, rs, to, ts, p, b)| MailboxDesc {
                        rx_offset: ro,
                        rx_size: rs,
                        tx_offset: to,
                        tx_size: ts,
                        protocols: MailboxProtocols::from_bits_retain(p),
                        bootstrap: b.map(|(a, b, c, d)| [a, b, c, d]),
                    }),
            )
        }

        fn description() -> impl Strategy<Value = DeviceDescription> {
            let names = (text(), text(), text(), proptest::option::of("[a-z]{1,8}"));
            let header = (any::<[u32; 4]>(), any::<[u16; 5]>(), mailbox());
            let general = (any::<[u8; 8]>(), any::<i16>(), any::<[u16; 2]>());
            let lists = (
                proptest::collection::vec(sm(), 0..8),
                proptest::collection::vec(1u8..4, 0..4),
                proptest::collection::vec(pdo(), 0..3),
                proptest::collection::vec(pdo(), 0..3),
                proptest::collection::vec(dc(), 0..3),
            );
            (names, header, general, lists).prop_map(
                |((order, name, group, image), (id, pdi, mailbox), (g, ebus, ports), l)| {
                    DeviceDescription {
                        identity: Identity {
                            vendor_id: id[0],
                            product_code: id[1],
                            revision: id[2],
                            serial: id[3],
                        },
                        order,
                        name,
                        group,
                        image,
                        pdi_control: pdi[0],
                        pdi_config: pdi[1],
                        sync_impulse_len: pdi[2],
                        pdi_config2: pdi[3],
                        alias: pdi[4],
                        mailbox,
                        coe_details: CoeDetails::from_bits_retain(g[0]),
                        foe_details: g[1],
                        eoe_details: g[2],
                        soe_channels: g[3],
                        ds402_channels: g[4],
                        flags: GeneralFlags::from_bits_retain(g[5]),
                        ebus_current_ma: ebus,
                        port_types: ports[0],
                        physical_memory_address: ports[1],
                        sync_managers: l.0,
                        fmmus: l.1.into_iter().map(FmmuUsage::from_byte).collect(),
                        tx_pdos: l.2,
                        rx_pdos: l.3,
                        dc_modes: l.4,
                        eeprom_bytes: 8192,
                    }
                },
            )
        }

        proptest! {
            #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(crate::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
            /// Every description `build` accepts comes back from `parse` unchanged.
            #[test]
            fn parse_is_the_inverse_of_build(d in description()) {
                let img = build(&d);
                prop_assume!(img.is_ok());
                let img = img.expect("checked");
                let p = parse(img.bytes()).expect("a built image parses");
                prop_assert!(p.checksum_ok);
                prop_assert_eq!(p.description, d);
            }
        }
    }
}
