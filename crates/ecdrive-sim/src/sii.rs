//! The SII EEPROM image of an emulated slave, built from a [`DeviceDescription`] (ETG.2010).
//!
//! A [`DeviceDescription`] holds what an ESI file (or a hand-written device) says about the
//! device in the terms the SII uses: identity, names, mailbox, SyncManagers, FMMU usage, PDOs,
//! DC operation modes, CoE details and flags. [`build`] turns it into the EEPROM byte image the
//! ESC serves through registers 0x0500–0x050F; [`SiiImage`] reads an image back (tests, tools).
//!
//! Layout (word addresses): 0–6 ESC configuration area, 7 CRC-8 of words 0–6, 8–15 identity,
//! 0x14–0x17 bootstrap mailbox, 0x18–0x1B standard mailbox, 0x1C mailbox protocols, 0x3E size,
//! 0x3F version, 0x40+ categories (Strings, General, FMMU, SyncM, TxPDO, RxPDO, DC, End).

use bitflags::bitflags;

/// Default EEPROM size in bytes (16 Kbit, the size of the common 24C16).
pub const DEFAULT_EEPROM_BYTES: usize = 2048;

pub use crate::ec::sii::{FIRST_CATEGORY_WORD, category};

pub use crate::ec::sii::SII_CRC;

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
    /// SyncManager status (mailbox polling).
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

/// One distributed-clock operation mode (DC category).
#[derive(Debug, Clone, PartialEq, Eq)]
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
    /// SYNC0 cycle factor.
    pub sync0_cycle_factor: i16,
    /// SYNC1 cycle factor.
    pub sync1_cycle_factor: i16,
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
}

/// Why an ESI device cannot be described in SII terms.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FromEsiError {
    /// A PDO entry is longer than an SII PDO entry's bit length byte can hold.
    #[error(
        "PDO 0x{pdo:04X} entry 0x{index:04X}:{sub:02X}: BitLen {bits} does not fit the SII (at most 255)"
    )]
    EntryTooLong {
        /// PDO index.
        pdo: u16,
        /// Entry index.
        index: u16,
        /// Entry sub-index.
        sub: u8,
        /// Its bit length.
        bits: u16,
    },
    /// A DC cycle factor does not fit the SII's 16-bit field.
    #[error("DC operation mode {mode:?}: cycle factor {factor} out of range")]
    FactorOutOfRange {
        /// The mode.
        mode: String,
        /// The factor.
        factor: i32,
    },
}

/// The PDOs of an ESI list in SII terms.
fn esi_pdos(list: &[crate::esi::EsiPdo]) -> Result<Vec<PdoDesc>, FromEsiError> {
    list.iter()
        .map(|p| {
            let entries = p
                .entries
                .iter()
                .map(|e| {
                    Ok(PdoEntryDesc {
                        index: e.index,
                        sub: e.sub,
                        name: e.name.clone(),
                        data_type: e.data_type().map(|t| t.code() as u8).unwrap_or(0),
                        bits: u8::try_from(e.bit_len).map_err(|_| FromEsiError::EntryTooLong {
                            pdo: p.index,
                            index: e.index,
                            sub: e.sub,
                            bits: e.bit_len,
                        })?,
                        flags: 0,
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            // ETG.2010 PDO flags: bit 0 mandatory, bit 1 default, bit 4 fixed content,
            // bit 5 virtual content.
            let flags = u16::from(p.mandatory)
                | u16::from(p.is_default()) << 1
                | u16::from(p.fixed) << 4
                | u16::from(p.virtual_) << 5;
            Ok(PdoDesc {
                index: p.index,
                sm: p.sm.unwrap_or(0xFF),
                dc_sync: 0,
                name: p.name.clone(),
                flags,
                entries,
            })
        })
        .collect()
}

/// The DC operation modes of an ESI device in SII terms.
fn esi_dc_modes(device: &crate::esi::Device) -> Result<Vec<DcOpMode>, FromEsiError> {
    let factor = |mode: &str, f: Option<i32>| -> Result<i16, FromEsiError> {
        let f = f.unwrap_or(0);
        i16::try_from(f).map_err(|_| FromEsiError::FactorOutOfRange {
            mode: mode.to_owned(),
            factor: f,
        })
    };
    device
        .dc
        .iter()
        .map(|m| {
            Ok(DcOpMode {
                name: m.name.clone(),
                description: m.desc.clone(),
                assign_activate: m.assign_activate,
                cycle_time0: m.cycle_time_sync0,
                shift_time0: m.shift_time_sync0,
                shift_time1: m.shift_time_sync1,
                sync0_cycle_factor: factor(&m.name, m.cycle_time_sync0_factor)?,
                sync1_cycle_factor: factor(&m.name, m.cycle_time_sync1_factor)?,
            })
        })
        .collect::<Result<Vec<_>, FromEsiError>>()
}

/// Describe an ESI device in SII terms, as a configuration tool would write its EEPROM:
/// identity (vendor from the file, serial given), names, the configuration area from
/// `<Eeprom><ConfigData>`, the mailbox from the `MBoxOut`/`MBoxIn` SyncManagers and `<Mailbox>`,
/// the bootstrap mailbox from `<Eeprom><BootStrap>`, CoE details, SyncManagers, FMMUs, all
/// PDOs (with the default SM assignment) and DC operation modes. The EEPROM size is
/// `<Eeprom><ByteSize>` if given, else [`DEFAULT_EEPROM_BYTES`]; \[REC\] when the image does
/// not fit that size (small ESCs carry a 1 Kbit EEPROM that real tools fill only partly), the
/// smallest power of two that holds it.
pub fn from_esi(
    vendor_id: u32,
    device: &crate::esi::Device,
    serial: u32,
) -> Result<DeviceDescription, FromEsiError> {
    use crate::esi::{FmmuUsage as EF, SmKind};
    let eeprom = device.eeprom.as_ref();
    let cfg = |word: usize| -> Option<u16> {
        let b = eeprom?.config_data.get(word * 2..word * 2 + 2)?;
        Some(u16::from_le_bytes([b[0], b[1]]))
    };
    let mailbox = match (
        device.sync_manager(SmKind::MBoxOut),
        device.sync_manager(SmKind::MBoxIn),
        device.mailbox.as_ref(),
    ) {
        (Some(out), Some(inp), Some(m)) => Some(MailboxDesc {
            rx_offset: out.start_address,
            rx_size: out.default_size.unwrap_or(0),
            tx_offset: inp.start_address,
            tx_size: inp.default_size.unwrap_or(0),
            protocols: MailboxProtocols::from_bits_truncate(m.protocols.bits()),
            bootstrap: eeprom.and_then(|e| {
                let w = |i: usize| {
                    e.boot_strap
                        .get(i * 2..i * 2 + 2)
                        .map(|b| u16::from_le_bytes([b[0], b[1]]))
                };
                Some([w(0)?, w(1)?, w(2)?, w(3)?])
            }),
        }),
        _ => None,
    };
    let coe_details = device
        .mailbox
        .as_ref()
        .and_then(|m| m.coe.as_ref())
        .map(|c| CoeDetails::from_bits_truncate(c.sii_byte()))
        .unwrap_or_default();
    let sync_managers = device
        .sync_managers
        .iter()
        .map(|s| SmDesc {
            start: s.start_address,
            length: s.default_size.unwrap_or(0),
            control: s.control_byte,
            enable: SmEnable::from_bits_truncate(s.sii_enable()),
            kind: match s.kind {
                SmKind::MBoxOut => SmType::MailboxOut,
                SmKind::MBoxIn => SmType::MailboxIn,
                SmKind::Outputs => SmType::Outputs,
                SmKind::Inputs => SmType::Inputs,
                SmKind::Unused => SmType::Unused,
            },
        })
        .collect();
    let fmmus = device
        .fmmus
        .iter()
        .map(|f| match f.usage {
            EF::Outputs => FmmuUsage::Outputs,
            EF::Inputs => FmmuUsage::Inputs,
            EF::MBoxState => FmmuUsage::SmStatus,
            EF::Unused => FmmuUsage::Unused,
        })
        .collect();
    let dc_modes = esi_dc_modes(device)?;
    let eeprom_bytes = eeprom
        .and_then(|e| e.byte_size)
        .map(|b| (b as usize).div_ceil(128).max(1) * 128)
        .unwrap_or(DEFAULT_EEPROM_BYTES);
    let mut desc = DeviceDescription {
        identity: Identity {
            vendor_id,
            product_code: device.type_.product_code,
            revision: device.type_.revision_no.unwrap_or(0),
            serial,
        },
        order: device.type_.name_text.clone(),
        name: device.name.clone(),
        group: device.group_type.clone().unwrap_or_default(),
        image: None,
        pdi_control: cfg(0).unwrap_or(0x0080),
        pdi_config: cfg(1).unwrap_or(0),
        sync_impulse_len: cfg(2).unwrap_or(0),
        pdi_config2: cfg(3).unwrap_or(0),
        alias: cfg(4).unwrap_or(0),
        mailbox,
        coe_details,
        ds402_channels: u8::from(device.profiles.iter().any(|p| p.profile_no == Some(402))),
        sync_managers,
        fmmus,
        tx_pdos: esi_pdos(&device.tx_pdos)?,
        rx_pdos: esi_pdos(&device.rx_pdos)?,
        dc_modes,
        eeprom_bytes,
        ..Default::default()
    };
    if let Err(SiiError::ImageTooLarge { needed, .. }) = build(&desc) {
        desc.eeprom_bytes = needed.next_power_of_two().max(eeprom_bytes);
    }
    Ok(desc)
}
