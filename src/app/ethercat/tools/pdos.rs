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
        (sii_mapping(&sii), PdoSource::Sii)
    };
    // Names the profile and the SII do not give: ask the drive's SDO information, when it has
    // it (General category, CoE details bit 1). Failures only leave the name out.
    let sdo_info = coe
        && sii
            .general
            .as_ref()
            .is_some_and(|g| g.coe_details & 0x02 != 0);
    let info = if sdo_info && profile.is_none() {
        sdo_info_names(bus, &d, &drive, &mapping, &sii)
    } else {
        std::collections::HashMap::new()
    };
    let names = Names {
        dict: profile.map(|p| Dictionary::new(p.dictionary)),
        sii: &sii,
        info,
    };
    let rx = reported(&mapping, Direction::Rx, &names);
    let tx = reported(&mapping, Direction::Tx, &names);
    Ok(PdoReport {
        position,
        drive: drive.name,
        source,
        sync_managers: sync_managers(&sii, &mapping, rx, tx),
    })
}

/// Without CoE the assignment is the SII's: the PDOs with a default SyncManager.
fn sii_mapping(sii: &SiiInfo) -> Mapping {
    let pdo = |p: &super::sii::SiiPdo| {
        crate::pdo::Pdo::owned(
            p.index,
            p.entries
                .iter()
                .map(|e| PdoEntry::new(e.index, e.sub, e.bits))
                .collect(),
        )
    };
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
    Mapping::owned(rx, tx)
}

/// The names of the mapped PDOs the SII does not name and of every mapped entry, from the
/// drive's SDO information. PDO names are keyed by the mapping index with sub-index 0xFF (no
/// entry uses it for a name here). What cannot be read is left out.
fn sdo_info_names<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    d: &crate::master::startup::DeviceInfo,
    drive: &crate::master::error::DriveRef,
    mapping: &Mapping,
    sii: &SiiInfo,
) -> std::collections::HashMap<ObjectAddress, String> {
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
    let names = bus.with_coe(d.address, drive.clone(), false, T_SDO * 4, async |c| {
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
    let mut info_names = std::collections::HashMap::new();
    if let Ok(names) = names {
        for (a, object, n) in names {
            let key = if object {
                ObjectAddress::new(a.index, 0xFF)
            } else {
                a
            };
            info_names.insert(key, n);
        }
    }
    info_names
}

/// Where the report's names come from, in this order: the drive profile's dictionary, the
/// SII, the drive's SDO information ([`sdo_info_names`]).
struct Names<'a> {
    dict: Option<Dictionary<'a>>,
    sii: &'a SiiInfo,
    info: std::collections::HashMap<ObjectAddress, String>,
}

impl Names<'_> {
    fn entry(&self, e: &PdoEntry) -> Option<String> {
        let a = e.address();
        if e.is_padding() {
            return Some("padding".to_string());
        }
        self.dict
            .as_ref()
            .and_then(|dict| dict.lookup(a))
            .map(|(o, en)| {
                if o.entries.len() <= 1 || en.name.is_empty() {
                    o.name.to_string()
                } else {
                    en.name.to_string()
                }
            })
            .or_else(|| {
                self.sii
                    .rx_pdos
                    .iter()
                    .chain(self.sii.tx_pdos.iter())
                    .flat_map(|p| p.entries.iter())
                    .find(|e| e.index == a.index && e.sub == a.sub && !e.name.is_empty())
                    .map(|e| e.name.clone())
            })
            .or_else(|| self.info.get(&a).cloned())
    }

    fn pdo(&self, index: u16) -> Option<String> {
        self.sii
            .rx_pdos
            .iter()
            .chain(self.sii.tx_pdos.iter())
            .find(|p| p.index == index && !p.name.is_empty())
            .map(|p| p.name.clone())
            .or_else(|| self.info.get(&ObjectAddress::new(index, 0xFF)).cloned())
    }
}

/// The PDOs of one direction as reported: each entry with its bit offset in the process image
/// and its name.
fn reported(mapping: &Mapping, dir: Direction, names: &Names<'_>) -> Vec<ReportedPdo> {
    let mut bit = 0u32;
    mapping
        .pdos(dir)
        .iter()
        .map(|p| {
            let entries = p
                .entries
                .iter()
                .map(|e| {
                    let r = PdoEntryReport {
                        address: e.address().to_string(),
                        index: e.index,
                        sub: e.sub,
                        bits: e.bits,
                        bit_offset: bit,
                        name: names.entry(e),
                    };
                    bit += u32::from(e.bits);
                    r
                })
                .collect();
            ReportedPdo {
                direction: dir.name().to_string(),
                index: p.index,
                name: names.pdo(p.index),
                bits: p.bits(),
                entries,
            }
        })
        .collect()
}

/// The SyncManagers the SII lists, the process-data ones with the PDOs assigned to them; a
/// device whose SII lists no process-data SyncManager but maps PDOs has them reported on the
/// standard SM2/SM3 anyway.
fn sync_managers(
    sii: &SiiInfo,
    mapping: &Mapping,
    rx: Vec<ReportedPdo>,
    tx: Vec<ReportedPdo>,
) -> Vec<SmReport> {
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
    sms
}
