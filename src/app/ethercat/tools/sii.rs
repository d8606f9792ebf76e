//! `ecdrive sii`: reading a device's SII EEPROM, decoding it (ETG.2010), and rendering it as an
//! ESI skeleton (what the IgH tool's `xml` command does).
//!
//! [`SiiInfo::decode`] reads the header words and the categories (Strings, General, FMMU, SyncM,
//! TxPDO, RxPDO, DC) from raw EEPROM bytes; it never panics, and a category that runs past the
//! end of the data or is shorter than its records is an [`SiiDecodeError`] naming the category
//! and its word address. [`esi_skeleton`] writes what the SII knows as an `<EtherCATInfo>`
//! document that [`crate::esi::EsiFile`] reads back: identity, names, SyncManagers, FMMUs, PDOs
//! with entries, mailbox protocols, DC operation modes and the EEPROM configuration data. The
//! object dictionary is not in the SII, so the skeleton has none.

use super::slaves::protocol_names;
use super::{T_STEP, discover, drive_ref};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{MasterError, bus_error};
use crate::master::exec::exec_error;
use crate::od::DataType;
use serde::Serialize;
use std::fmt::Write as _;

pub use crate::ec::sii::{FIRST_CATEGORY_WORD, category};

pub use crate::ec::sii::SiiDecodeError;

/// The standard mailbox (words 0x18–0x1B) or the bootstrap mailbox (0x14–0x17).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SiiMailbox {
    /// Master → device mailbox start.
    pub rx_offset: u16,
    /// Its size.
    pub rx_size: u16,
    /// Device → master mailbox start.
    pub tx_offset: u16,
    /// Its size.
    pub tx_size: u16,
}

/// The General category.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiGeneral {
    /// Group name.
    pub group: String,
    /// Image name.
    pub image: String,
    /// Order code (ethercrab's `SubDevice::name`).
    pub order: String,
    /// Device name.
    pub name: String,
    /// CoE details byte (SDO, SDO info, PDO assign, PDO config, upload at start-up, complete
    /// access).
    pub coe_details: u8,
    /// FoE details byte.
    pub foe_details: u8,
    /// EoE details byte.
    pub eoe_details: u8,
    /// SoE channels.
    pub soe_channels: u8,
    /// DS402 channels.
    pub ds402_channels: u8,
    /// Flags (enable SAFE-OP, not LRW, mailbox DLL, identification).
    pub flags: u8,
    /// E-bus current, mA.
    pub ebus_current_ma: i16,
    /// Physical port types, one nibble per port.
    pub port_types: u16,
}

/// One SyncManager of the SyncM category.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiSm {
    /// Physical start address.
    pub start: u16,
    /// Default length.
    pub length: u16,
    /// Control byte.
    pub control: u8,
    /// Enable byte.
    pub enable: u8,
    /// `MBoxOut`, `MBoxIn`, `Outputs`, `Inputs` or `Unused` (the ESI names).
    pub kind: String,
}

/// One PDO entry of a TxPDO/RxPDO category.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiPdoEntry {
    /// Object index (0: padding).
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Name.
    pub name: String,
    /// CoE data type code.
    pub data_type: u8,
    /// Size in bits.
    pub bits: u8,
}

/// One PDO of a TxPDO/RxPDO category.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiPdo {
    /// Mapping index.
    pub index: u16,
    /// Default SyncManager (0xFF: none).
    pub sm: u8,
    /// DC sync mode.
    pub dc_sync: u8,
    /// Name.
    pub name: String,
    /// Flags.
    pub flags: u16,
    /// Entries.
    pub entries: Vec<SiiPdoEntry>,
}

/// One category as it sits in the EEPROM.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiCategory {
    /// Category type.
    pub kind: u16,
    /// Its name.
    pub name: String,
    /// Word address of its data.
    pub word: u32,
    /// Its length in words.
    pub words: u16,
}

/// A decoded SII EEPROM.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiInfo {
    /// PDI control (word 0).
    pub pdi_control: u16,
    /// PDI configuration (word 1).
    pub pdi_config: u16,
    /// SYNC impulse length, 10 ns units (word 2).
    pub sync_impulse_len: u16,
    /// Extended PDI configuration (word 3).
    pub pdi_config2: u16,
    /// Configured station alias (word 4).
    pub alias: u16,
    /// Whether the CRC in word 7 matches words 0–6.
    pub checksum_ok: bool,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// Bootstrap mailbox, if set.
    pub bootstrap_mailbox: Option<SiiMailbox>,
    /// Standard mailbox, if set.
    pub mailbox: Option<SiiMailbox>,
    /// Mailbox protocol bits (word 0x1C).
    pub protocol_bits: u16,
    /// Mailbox protocols by name.
    pub protocols: Vec<String>,
    /// EEPROM size in bytes (word 0x3E).
    pub size_bytes: usize,
    /// SII version (word 0x3F).
    pub version: u16,
    /// The categories in EEPROM order.
    pub categories: Vec<SiiCategory>,
    /// Strings (1-based in the SII; index 0 here is string 1).
    pub strings: Vec<String>,
    /// The General category.
    pub general: Option<SiiGeneral>,
    /// FMMU usage names (`Outputs`, `Inputs`, `MBoxState`, `Unused`).
    pub fmmus: Vec<String>,
    /// SyncManagers.
    pub sync_managers: Vec<SiiSm>,
    /// TxPDOs.
    pub tx_pdos: Vec<SiiPdo>,
    /// RxPDOs.
    pub rx_pdos: Vec<SiiPdo>,
    /// DC operation modes.
    pub dc_modes: Vec<crate::ec::sii::DcOpMode>,
}

impl SiiInfo {
    /// The string with SII index `i` (1-based; 0 and unknown indices give `""`).
    pub fn string(&self, i: u8) -> &str {
        match usize::from(i).checked_sub(1) {
            Some(k) => self.strings.get(k).map_or("", String::as_str),
            None => "",
        }
    }

    /// Decode raw EEPROM bytes (a dump, or the part up to the end category) with the core's
    /// [`parse`](crate::ec::sii::parse), into what the tools print.
    pub fn decode(bytes: &[u8]) -> Result<Self, SiiDecodeError> {
        let p = crate::ec::sii::parse(bytes)?;
        let d = &p.description;
        let mbx = |m: [u16; 4]| SiiMailbox {
            rx_offset: m[0],
            rx_size: m[1],
            tx_offset: m[2],
            tx_size: m[3],
        };
        let pdos = |list: &[crate::ec::sii::PdoDesc]| -> Vec<SiiPdo> {
            list.iter()
                .map(|p| SiiPdo {
                    index: p.index,
                    sm: p.sm,
                    dc_sync: p.dc_sync,
                    name: p.name.clone(),
                    flags: p.flags,
                    entries: p
                        .entries
                        .iter()
                        .map(|e| SiiPdoEntry {
                            index: e.index,
                            sub: e.sub,
                            name: e.name.clone(),
                            data_type: e.data_type,
                            bits: e.bits,
                        })
                        .collect(),
                })
                .collect()
        };
        Ok(SiiInfo {
            pdi_control: d.pdi_control,
            pdi_config: d.pdi_config,
            sync_impulse_len: d.sync_impulse_len,
            pdi_config2: d.pdi_config2,
            alias: d.alias,
            checksum_ok: p.checksum_ok,
            vendor_id: d.identity.vendor_id,
            product_code: d.identity.product_code,
            revision: d.identity.revision,
            serial: d.identity.serial,
            bootstrap_mailbox: d.mailbox.as_ref().and_then(|m| m.bootstrap).map(mbx),
            mailbox: d
                .mailbox
                .as_ref()
                .map(|m| mbx([m.rx_offset, m.rx_size, m.tx_offset, m.tx_size])),
            protocol_bits: p.protocol_bits,
            protocols: protocol_names(p.protocol_bits),
            size_bytes: d.eeprom_bytes,
            version: p.version,
            categories: p
                .categories
                .iter()
                .map(|c| SiiCategory {
                    kind: c.kind,
                    name: category::name(c.kind).to_string(),
                    word: c.word,
                    words: c.words,
                })
                .collect(),
            strings: p.strings.clone(),
            general: p.has_general.then(|| SiiGeneral {
                group: d.group.clone(),
                image: d.image.clone().unwrap_or_default(),
                order: d.order.clone(),
                name: d.name.clone(),
                coe_details: d.coe_details.bits(),
                foe_details: d.foe_details,
                eoe_details: d.eoe_details,
                soe_channels: d.soe_channels,
                ds402_channels: d.ds402_channels,
                flags: d.flags.bits(),
                ebus_current_ma: d.ebus_current_ma,
                port_types: d.port_types,
            }),
            fmmus: d.fmmus.iter().map(|f| f.esi_name().to_string()).collect(),
            sync_managers: d
                .sync_managers
                .iter()
                .map(|s| SiiSm {
                    start: s.start,
                    length: s.length,
                    control: s.control,
                    enable: s.enable.bits(),
                    kind: s.kind.esi_name().to_string(),
                })
                .collect(),
            tx_pdos: pdos(&d.tx_pdos),
            rx_pdos: pdos(&d.rx_pdos),
            dc_modes: d.dc_modes.clone(),
        })
    }
}

fn xml_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => {}
            c => o.push(c),
        }
    }
    o
}

fn esi_type_name(code: u8, bits: u8) -> String {
    match DataType::from_code(u16::from(code)) {
        Some(t) if t.bit_len().is_some() => t.esi_name().to_string(),
        Some(DataType::VisibleString) => format!("STRING({})", bits / 8),
        Some(t) => t.esi_name().to_string(),
        None => match bits {
            1 => "BOOL".into(),
            8 => "USINT".into(),
            16 => "UINT".into(),
            32 => "UDINT".into(),
            n => format!("BIT{n}"),
        },
    }
}

/// Render a decoded SII as an ESI skeleton (ETG.2000 `<EtherCATInfo>` with one device). The
/// `raw` bytes give the `<ConfigData>` (words 0–6).
pub fn esi_skeleton(info: &SiiInfo, raw: &[u8]) -> String {
    let g = info.general.clone().unwrap_or(SiiGeneral {
        group: String::new(),
        image: String::new(),
        order: String::new(),
        name: String::new(),
        coe_details: 0,
        foe_details: 0,
        eoe_details: 0,
        soe_channels: 0,
        ds402_channels: 0,
        flags: 0,
        ebus_current_ma: 0,
        port_types: 0,
    });
    let order = if g.order.is_empty() {
        format!("0x{:08X}", info.product_code)
    } else {
        g.order.clone()
    };
    let name = if g.name.is_empty() { &order } else { &g.name };
    let group = if g.group.is_empty() {
        "Unknown".to_string()
    } else {
        g.group.clone()
    };
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        "<!-- ESI skeleton generated by ecdrive from the SII EEPROM of {}: identity, SyncManagers, \
         FMMUs, PDOs, mailbox and DC as the SII states them. The object dictionary is not in the \
         SII. -->",
        xml_escape(&order)
    );
    let _ = writeln!(x, r#"<EtherCATInfo Version="1.6">"#);
    let _ = writeln!(x, "  <Vendor>");
    let _ = writeln!(x, "    <Id>#x{:08X}</Id>", info.vendor_id);
    let _ = writeln!(
        x,
        "    <Name LcId=\"1033\">Vendor 0x{:08X}</Name>",
        info.vendor_id
    );
    let _ = writeln!(x, "  </Vendor>");
    let _ = writeln!(x, "  <Descriptions>");
    let _ = writeln!(x, "    <Groups>");
    let _ = writeln!(x, "      <Group>");
    let _ = writeln!(x, "        <Type>{}</Type>", xml_escape(&group));
    let _ = writeln!(
        x,
        "        <Name LcId=\"1033\">{}</Name>",
        xml_escape(&group)
    );
    let _ = writeln!(x, "      </Group>");
    let _ = writeln!(x, "    </Groups>");
    let _ = writeln!(x, "    <Devices>");
    let _ = writeln!(x, "      <Device>");
    let _ = writeln!(
        x,
        "        <Type ProductCode=\"#x{:08X}\" RevisionNo=\"#x{:08X}\">{}</Type>",
        info.product_code,
        info.revision,
        xml_escape(&order)
    );
    let _ = writeln!(x, "        <Name LcId=\"1033\">{}</Name>", xml_escape(name));
    let _ = writeln!(x, "        <GroupType>{}</GroupType>", xml_escape(&group));
    for f in &info.fmmus {
        let _ = writeln!(x, "        <Fmmu>{f}</Fmmu>");
    }
    for sm in &info.sync_managers {
        let _ = writeln!(
            x,
            "        <Sm DefaultSize=\"{}\" StartAddress=\"#x{:04X}\" ControlByte=\"#x{:02X}\" \
             Enable=\"{}\">{}</Sm>",
            sm.length,
            sm.start,
            sm.control,
            sm.enable & 1,
            sm.kind
        );
    }
    skeleton_pdos(&mut x, info);
    skeleton_mailbox(&mut x, info, g.coe_details);
    skeleton_dc(&mut x, info);
    skeleton_eeprom(&mut x, info, raw);
    let _ = writeln!(x, "      </Device>");
    let _ = writeln!(x, "    </Devices>");
    let _ = writeln!(x, "  </Descriptions>");
    let _ = writeln!(x, "</EtherCATInfo>");
    x
}

/// The device's RxPDOs and TxPDOs, with their entries.
fn skeleton_pdos(x: &mut String, info: &SiiInfo) {
    for (tag, pdos) in [("RxPdo", &info.rx_pdos), ("TxPdo", &info.tx_pdos)] {
        for p in pdos {
            let sm = if p.sm == 0xFF {
                String::new()
            } else {
                format!(" Sm=\"{}\"", p.sm)
            };
            // PDO flags bit 4 (0x0010): fixed content.
            let fixed = if p.flags & 0x0010 != 0 {
                " Fixed=\"1\""
            } else {
                ""
            };
            let _ = writeln!(x, "        <{tag}{sm}{fixed}>");
            let _ = writeln!(x, "          <Index>#x{:04X}</Index>", p.index);
            let _ = writeln!(x, "          <Name>{}</Name>", xml_escape(&p.name));
            for e in &p.entries {
                let _ = writeln!(x, "          <Entry>");
                let _ = writeln!(x, "            <Index>#x{:04X}</Index>", e.index);
                if e.index != 0 {
                    let _ = writeln!(x, "            <SubIndex>{}</SubIndex>", e.sub);
                }
                let _ = writeln!(x, "            <BitLen>{}</BitLen>", e.bits);
                if e.index != 0 {
                    let _ = writeln!(x, "            <Name>{}</Name>", xml_escape(&e.name));
                    let _ = writeln!(
                        x,
                        "            <DataType>{}</DataType>",
                        esi_type_name(e.data_type, e.bits)
                    );
                }
                let _ = writeln!(x, "          </Entry>");
            }
            let _ = writeln!(x, "        </{tag}>");
        }
    }
}

/// The device's mailbox protocols (CoE with its details, `coe_details` of the General
/// category).
fn skeleton_mailbox(x: &mut String, info: &SiiInfo, coe_details: u8) {
    if info.mailbox.is_some() && info.protocol_bits != 0 {
        let _ = writeln!(x, "        <Mailbox>");
        if info.protocol_bits & 0x0001 != 0 {
            let _ = writeln!(x, "          <AoE/>");
        }
        if info.protocol_bits & 0x0002 != 0 {
            let _ = writeln!(x, "          <EoE/>");
        }
        if info.protocol_bits & 0x0004 != 0 {
            let c = coe_details;
            let b = |bit: u8| if c & bit != 0 { "true" } else { "false" };
            let _ = writeln!(
                x,
                "          <CoE SdoInfo=\"{}\" PdoAssign=\"{}\" PdoConfig=\"{}\" PdoUpload=\"{}\" \
                 CompleteAccess=\"{}\"/>",
                b(0x02),
                b(0x04),
                b(0x08),
                b(0x10),
                b(0x20)
            );
        }
        if info.protocol_bits & 0x0008 != 0 {
            let _ = writeln!(x, "          <FoE/>");
        }
        if info.protocol_bits & 0x0010 != 0 {
            let _ = writeln!(x, "          <SoE/>");
        }
        if info.protocol_bits & 0x0020 != 0 {
            let _ = writeln!(x, "          <VoE/>");
        }
        let _ = writeln!(x, "        </Mailbox>");
    }
}

/// The device's DC operation modes.
fn skeleton_dc(x: &mut String, info: &SiiInfo) {
    if !info.dc_modes.is_empty() {
        let _ = writeln!(x, "        <Dc>");
        for m in &info.dc_modes {
            let _ = writeln!(x, "          <OpMode>");
            let _ = writeln!(x, "            <Name>{}</Name>", xml_escape(&m.name));
            let _ = writeln!(x, "            <Desc>{}</Desc>", xml_escape(&m.description));
            let _ = writeln!(
                x,
                "            <AssignActivate>#x{:04X}</AssignActivate>",
                m.assign_activate
            );
            let _ = writeln!(
                x,
                "            <CycleTimeSync0 Factor=\"{}\">{}</CycleTimeSync0>",
                m.sync0_cycle_factor, m.cycle_time0
            );
            let _ = writeln!(
                x,
                "            <ShiftTimeSync0>{}</ShiftTimeSync0>",
                m.shift_time0
            );
            let _ = writeln!(
                x,
                "            <ShiftTimeSync1>{}</ShiftTimeSync1>",
                m.shift_time1
            );
            let _ = writeln!(x, "          </OpMode>");
        }
        let _ = writeln!(x, "        </Dc>");
    }
}

/// The EEPROM's size, its configuration words (the first 14 bytes of `raw`) and the
/// bootstrap mailbox.
fn skeleton_eeprom(x: &mut String, info: &SiiInfo, raw: &[u8]) {
    let _ = writeln!(x, "        <Eeprom>");
    let _ = writeln!(x, "          <ByteSize>{}</ByteSize>", info.size_bytes);
    let config: String = raw.iter().take(14).map(|b| format!("{b:02X}")).collect();
    let _ = writeln!(x, "          <ConfigData>{config}</ConfigData>");
    if let Some(b) = info.bootstrap_mailbox {
        let words = [b.rx_offset, b.rx_size, b.tx_offset, b.tx_size];
        let hex: String = words
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .map(|b| format!("{b:02X}"))
            .collect();
        let _ = writeln!(x, "          <BootStrap>{hex}</BootStrap>");
    }
    let _ = writeln!(x, "        </Eeprom>");
}

/// A device's EEPROM as read.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiDump {
    /// Position of the device.
    pub position: u16,
    /// The device (profile name, or the SII name).
    pub drive: String,
    /// The bytes.
    #[serde(serialize_with = "hex_string")]
    pub bytes: Vec<u8>,
}

fn hex_string<S: serde::Serializer>(b: &[u8], s: S) -> Result<S::Ok, S::Error> {
    let h: String = b.iter().map(|x| format!("{x:02x}")).collect();
    s.serialize_str(&h)
}

/// Bytes per EEPROM read request (progress granularity).
const CHUNK: usize = 128;

/// Read `len` bytes of a device's EEPROM from word `start`, calling `progress(done, total)`
/// after each chunk.
pub(crate) fn read_eeprom<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: &crate::master::startup::Group<ethercrab::subdevice_group::PreOp>,
    position: u16,
    drive: &crate::master::error::DriveRef,
    start_word: u16,
    len: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<u8>, MasterError> {
    let mut out = vec![0u8; len];
    let mut done = 0;
    while done < len {
        let n = (len - done).min(CHUNK);
        let word = u16::try_from(usize::from(start_word) + done / 2).map_err(|_| {
            MasterError::new(
                Some(drive),
                "reading the EEPROM",
                crate::master::error::ErrorKind::Config,
                "the EEPROM address is beyond 0xFFFF words",
            )
        })?;
        let chunk = out.get_mut(done..done + n).unwrap_or_default();
        let what = format!("reading EEPROM words 0x{word:04X}…");
        let read = bus
            .block_on(&|| format!("{drive}: {what}"), T_STEP, |md| async move {
                let sd = group.subdevice(md, usize::from(position))?;
                sd.eeprom_read_raw(md, word, chunk).await
            })
            .map_err(|e| exec_error(Some(drive), e))?
            .map_err(|e| bus_error(Some(drive), format!("reading EEPROM word 0x{word:04X}"), e))?;
        if read == 0 {
            out.truncate(done);
            break;
        }
        done += read.min(n);
        progress(done, len);
    }
    Ok(out)
}

/// Read the SII header and the categories up to the end marker (not the whole EEPROM).
pub(crate) fn read_categories<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: &crate::master::startup::Group<ethercrab::subdevice_group::PreOp>,
    position: u16,
    drive: &crate::master::error::DriveRef,
) -> Result<Vec<u8>, MasterError> {
    let none = &mut |_: usize, _: usize| {};
    let mut bytes = read_eeprom(
        bus,
        group,
        position,
        drive,
        0,
        usize::from(FIRST_CATEGORY_WORD) * 2,
        none,
    )?;
    let limit = (usize::from(u16::from_le_bytes([
        bytes.get(0x7C).copied().unwrap_or(0),
        bytes.get(0x7D).copied().unwrap_or(0),
    ])) + 1)
        * 128;
    loop {
        let at = bytes.len();
        if at + 4 > limit {
            break;
        }
        let hdr = read_eeprom(bus, group, position, drive, (at / 2) as u16, 4, none)?;
        let kind = u16::from_le_bytes([
            hdr.first().copied().unwrap_or(0xFF),
            hdr.get(1).copied().unwrap_or(0xFF),
        ]);
        let len = usize::from(u16::from_le_bytes([
            hdr.get(2).copied().unwrap_or(0),
            hdr.get(3).copied().unwrap_or(0),
        ])) * 2;
        bytes.extend_from_slice(&hdr);
        if kind == category::END || hdr.len() < 4 || at + 4 + len > limit {
            break;
        }
        let data = read_eeprom(
            bus,
            group,
            position,
            drive,
            ((at + 4) / 2) as u16,
            len,
            none,
        )?;
        bytes.extend_from_slice(&data);
    }
    Ok(bytes)
}

/// Read the whole EEPROM of the device at `position` (its size from SII word 0x3E), calling
/// `progress(done, total)` as it goes.
pub fn sii_read<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<SiiDump, MasterError> {
    let found = discover(bus)?;
    let d = found.device(position)?.clone();
    let drive = drive_ref(&d);
    let group = &found.group;
    let size = bus
        .block_on(
            &|| format!("{drive}: reading the EEPROM size"),
            T_STEP,
            |md| async move {
                let sd = group.subdevice(md, usize::from(position))?;
                sd.eeprom_size(md).await
            },
        )
        .map_err(|e| exec_error(Some(&drive), e))?
        .map_err(|e| bus_error(Some(&drive), "reading the EEPROM size (SII word 0x3E)", e))?;
    let bytes = read_eeprom(bus, &found.group, position, &drive, 0, size, progress)?;
    Ok(SiiDump {
        position,
        drive: drive.name,
        bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_is_the_sii_crc_and_needs_the_whole_header() {
        // The CRC-8 check value for this polynomial and seed: "123456789" → 0xFB.
        assert_eq!(crate::ec::sii::SII_CRC.checksum(b"123456789"), 0xFB);
        assert_eq!(crate::ec::sii::header_checksum(&[0; 4]), None);
    }

    #[test]
    fn garbage_never_panics() {
        for len in [0usize, 1, 13, 15, 128, 129, 200] {
            for fill in [0u8, 0xFF, 0x0A, 0x32] {
                let v = vec![fill; len];
                let _ = SiiInfo::decode(&v);
            }
        }
    }

    #[test]
    fn a_category_past_the_end_is_named() {
        let mut v = vec![0u8; 128 + 8];
        v[128..130].copy_from_slice(&category::GENERAL.to_le_bytes());
        v[130..132].copy_from_slice(&100u16.to_le_bytes());
        let e = SiiInfo::decode(&v).unwrap_err();
        assert!(e.to_string().contains("General"), "{e}");
        assert_eq!(e.word, 0x40);
    }
}
