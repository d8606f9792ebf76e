//! `ecdrive pdos`: SyncManagers, PDO assignment and mapping as the drive reports them.

use super::sii::{SiiInfo, read_categories};
use super::{discover, drive_ref};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{ErrorKind, MasterError};
use crate::od::{Dictionary, ObjectAddress};
use crate::pdo::{Direction, Mapping, PdoEntry};
use serde::Serialize;
use std::time::Duration;

const T_SDO: Duration = Duration::from_secs(10);

/// Where the mapping came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PdoSource {
    /// Read over CoE from 0x1C12/0x1C13 and the mapping objects: what the drive uses now.
    Coe,
    /// The SII's TxPDO/RxPDO categories (devices without CoE): the EEPROM defaults.
    Sii,
}

/// One mapped entry.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PdoEntryReport {
    /// `0xINDEX:SUB` (`0x0000:00` for padding).
    pub address: String,
    /// Object index (0: padding).
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Size in bits.
    pub bits: u8,
    /// Bit offset in the SyncManager's process image.
    pub bit_offset: u32,
    /// Name, from the drive profile, the SII or the drive's SDO information.
    pub name: Option<String>,
}

/// One assigned PDO.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ReportedPdo {
    /// `RxPDO` or `TxPDO`.
    pub direction: String,
    /// Mapping index.
    pub index: u16,
    /// Name, from the SII or the drive's SDO information.
    pub name: Option<String>,
    /// Size in bits.
    pub bits: u32,
    /// Entries in order.
    pub entries: Vec<PdoEntryReport>,
}

/// One SyncManager (from the SII SyncM category) with the PDOs assigned to it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SmReport {
    /// SyncManager number.
    pub index: u8,
    /// Physical start address.
    pub start: u16,
    /// Default size from the SII (mailboxes: their size; process data: the EEPROM default).
    pub default_size: u16,
    /// Control byte.
    pub control: u8,
    /// Enabled by default.
    pub enable: bool,
    /// `MBoxOut`, `MBoxIn`, `Outputs`, `Inputs`, `Unused`.
    pub kind: String,
    /// Process data SyncManagers: the size the assigned PDOs need, bytes.
    pub mapped_bytes: Option<usize>,
    /// The PDOs assigned (SM2: RxPDOs, SM3: TxPDOs).
    pub pdos: Vec<ReportedPdo>,
}

/// What `pdos` reports.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PdoReport {
    /// Position of the device.
    pub position: u16,
    /// The device (profile name, or the SII name).
    pub drive: String,
    /// Where the mapping came from.
    pub source: PdoSource,
    /// The SyncManagers.
    pub sync_managers: Vec<SmReport>,
}

/// The PDO configuration of the device at `position`: its SyncManagers from the SII, and the
/// assignment and mapping read over CoE (0x1C12/0x1C13, 0x16xx/0x1Axx), or the SII's PDO
/// categories for devices without CoE.
pub fn pdos<L: FrameLink>(bus: &mut Bus<'_, L>, position: u16) -> Result<PdoReport, MasterError> {
    let found = discover(bus)?;
    let d = found.device(position)?.clone();
    let drive = drive_ref(&d);
    let raw = read_categories(bus, &found.group, position, &drive)?;
    let sii = SiiInfo::decode(&raw)
        .map_err(|e| MasterError::new(Some(&drive), "decoding the SII", ErrorKind::Bus, e))?;
    let profile = crate::drives::by_identity(d.vendor_id, d.product_code);
    let coe = sii.protocol_bits & 0x0004 != 0 && sii.mailbox.is_some();
    let (mapping, source) = if coe {
        let addr = d.address;
        let m = crate::master::startup::read_mapping(bus, addr, &drive, "reading the PDO mapping")?;
        (m, PdoSource::Coe)
    } else {
        let pdo = |p: &super::sii::SiiPdo| {
            crate::pdo::Pdo::owned(
                p.index,
                p.entries
                    .iter()
                    .map(|e| PdoEntry::new(e.index, e.sub, e.bits))
                    .collect(),
            )
        };
        // Without CoE the assignment is the SII's: the PDOs with a default SyncManager.
        let rx = sii
            .rx_pdos
            .iter()
            .filter(|p| p.sm != 0xFF)
            .map(pdo)
            .collect();
        let tx = sii
            .tx_pdos
            .iter()
            .filter(|p| p.sm != 0xFF)
            .map(pdo)
            .collect();
        (Mapping::owned(rx, tx), PdoSource::Sii)
    };

    let dict = profile.map(|p| Dictionary::new(p.dictionary));
    // Names the profile and the SII do not give: ask the drive's SDO information, when it has
    // it (General category, CoE details bit 1). Failures only leave the name out.
    let sdo_info = coe
        && sii
            .general
            .as_ref()
            .is_some_and(|g| g.coe_details & 0x02 != 0);
    let mut info_names: std::collections::HashMap<ObjectAddress, String> =
        std::collections::HashMap::new();
    if sdo_info && profile.is_none() {
        let mut wanted: Vec<(ObjectAddress, bool)> = Vec::new();
        for dir in [Direction::Rx, Direction::Tx] {
            for p in mapping.pdos(dir) {
                if !sii
                    .rx_pdos
                    .iter()
                    .chain(&sii.tx_pdos)
                    .any(|s| s.index == p.index)
                {
                    wanted.push((ObjectAddress::new(p.index, 0), true));
                }
                for e in p.entries.iter().filter(|e| !e.is_padding()) {
                    wanted.push((e.address(), false));
                }
            }
        }
        wanted.sort();
        wanted.dedup();
        let addr = d.address;
        let names = bus.with_coe(addr, drive.clone(), false, T_SDO * 4, async |c| {
            let mut out = Vec::new();
            for (a, object) in &wanted {
                let name = if *object {
                    c.object_description(a.index)
                        .await
                        .map(|o| o.name.into_owned())
                } else {
                    c.entry_description(*a).await.map(|e| e.name)
                };
                if let Ok(n) = name
                    && !n.is_empty()
                {
                    out.push((*a, *object, n));
                }
            }
            Ok(out)
        });
        if let Ok(names) = names {
            for (a, object, n) in names {
                // PDO names are keyed by the mapping index with sub-index 0xFF (no entry
                // uses it for a name here).
                let key = if object {
                    ObjectAddress::new(a.index, 0xFF)
                } else {
                    a
                };
                info_names.insert(key, n);
            }
        }
    }
    let sii_entry_name = |a: ObjectAddress| {
        sii.rx_pdos
            .iter()
            .chain(sii.tx_pdos.iter())
            .flat_map(|p| p.entries.iter())
            .find(|e| e.index == a.index && e.sub == a.sub && !e.name.is_empty())
            .map(|e| e.name.clone())
    };
    let sii_pdo_name = |index: u16| {
        sii.rx_pdos
            .iter()
            .chain(sii.tx_pdos.iter())
            .find(|p| p.index == index && !p.name.is_empty())
            .map(|p| p.name.clone())
    };
    let report_dir = |dir: Direction| -> Vec<ReportedPdo> {
        let mut bit = 0u32;
        mapping
            .pdos(dir)
            .iter()
            .map(|p| {
                let entries = p
                    .entries
                    .iter()
                    .map(|e| {
                        let a = e.address();
                        let name = if e.is_padding() {
                            Some("padding".to_string())
                        } else {
                            dict.as_ref()
                                .and_then(|dict| dict.lookup(a))
                                .map(|(o, en)| {
                                    if o.entries.len() <= 1 || en.name.is_empty() {
                                        o.name.to_string()
                                    } else {
                                        en.name.to_string()
                                    }
                                })
                                .or_else(|| sii_entry_name(a))
                                .or_else(|| info_names.get(&a).cloned())
                        };
                        let r = PdoEntryReport {
                            address: a.to_string(),
                            index: e.index,
                            sub: e.sub,
                            bits: e.bits,
                            bit_offset: bit,
                            name,
                        };
                        bit += u32::from(e.bits);
                        r
                    })
                    .collect();
                ReportedPdo {
                    direction: dir.name().to_string(),
                    index: p.index,
                    name: sii_pdo_name(p.index)
                        .or_else(|| info_names.get(&ObjectAddress::new(p.index, 0xFF)).cloned()),
                    bits: p.bits(),
                    entries,
                }
            })
            .collect()
    };
    let rx = report_dir(Direction::Rx);
    let tx = report_dir(Direction::Tx);
    let mut rx = Some(rx);
    let mut tx = Some(tx);
    let mut sms = Vec::new();
    for (i, sm) in sii.sync_managers.iter().enumerate() {
        let (pdos, mapped) = match sm.kind.as_str() {
            "Outputs" => (
                rx.take().unwrap_or_default(),
                Some(mapping.bytes(Direction::Rx)),
            ),
            "Inputs" => (
                tx.take().unwrap_or_default(),
                Some(mapping.bytes(Direction::Tx)),
            ),
            _ => (Vec::new(), None),
        };
        sms.push(SmReport {
            index: u8::try_from(i).unwrap_or(u8::MAX),
            start: sm.start,
            default_size: sm.length,
            control: sm.control,
            enable: sm.enable & 1 != 0,
            kind: sm.kind.clone(),
            mapped_bytes: mapped,
            pdos,
        });
    }
    // A device whose SII lists no process-data SyncManager but maps PDOs: report them on the
    // standard SM2/SM3 anyway.
    for (dir, rest) in [(Direction::Rx, rx), (Direction::Tx, tx)] {
        if let Some(pdos) = rest.filter(|p| !p.is_empty()) {
            sms.push(SmReport {
                index: dir.sync_manager(),
                start: 0,
                default_size: 0,
                control: 0,
                enable: false,
                kind: if dir == Direction::Rx {
                    "Outputs".into()
                } else {
                    "Inputs".into()
                },
                mapped_bytes: Some(mapping.bytes(dir)),
                pdos,
            });
        }
    }
    Ok(PdoReport {
        position,
        drive: drive.name,
        source,
        sync_managers: sms,
    })
}
