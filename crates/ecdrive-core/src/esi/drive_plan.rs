//! What ecdrive would make of a CiA 402 drive from its ESI file alone, without a drive profile
//! written in Rust: identity, the supported cyclic modes, the PDO mapping for each cyclic mode
//! (chosen from the file's PDOs, or built within the limits it implies), the DC operation mode,
//! whether the cycle time object 0x1C32:02 is writable, and the `<InitCmd>`s with their
//! transitions. `ecdrive esi show` prints it.
//!
//! # Choosing a mapping
//!
//! A cyclic mode needs its set-point and the controlword in an RxPDO, the statusword (and for
//! csp the actual position, where the set-point starts from) in a TxPDO; several modes need
//! 0x6060 and 0x6061 as well. For the modes asked for, per direction, in this order:
//!
//! 1. the file's default assignment (the PDOs with an `Sm` attribute, and the mandatory ones),
//!    if it carries everything;
//! 2. else the smallest set of the file's PDOs (mandatory ones always in, file order among
//!    equals) that carries everything, where no PDO excludes another (`<Exclude>`);
//! 3. else, if the file allows PDO configuration (`<CoE PdoConfig>`) and the direction has a
//!    PDO that is not `Fixed`: that PDO (the default-assigned one first) with its entries and
//!    the missing objects appended, if the dictionary has them mappable in that direction and
//!    the mapping object has sub-indices enough (its `<Object>` in the dictionary gives the
//!    limit: a 0x1600 with sub-indices 1–10 takes 10 entries);
//! 4. else the modes cannot be carried: the reason names each missing object.

use super::model::{Device, EsiFile, InitCmd, Transition};
use crate::od::{EntryAccess, ObjectAddress};
use crate::pdo::{Direction, Mapping, Pdo, PdoEntry};
use std::borrow::Cow;
use std::fmt::Write as _;

/// A cyclic mode, by its 0x6060 value and short name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CyclicModeRef {
    /// The 0x6060 value.
    pub code: i8,
    /// `csp`, `csv` or `cst`.
    pub name: &'static str,
}

/// csp, csv and cst.
pub const CYCLIC_MODES: [CyclicModeRef; 3] = [
    CyclicModeRef {
        code: 8,
        name: "csp",
    },
    CyclicModeRef {
        code: 9,
        name: "csv",
    },
    CyclicModeRef {
        code: 10,
        name: "cst",
    },
];

const CONTROLWORD: ObjectAddress = ObjectAddress::new(0x6040, 0);
const STATUSWORD: ObjectAddress = ObjectAddress::new(0x6041, 0);
const MODE: ObjectAddress = ObjectAddress::new(0x6060, 0);
const MODE_DISPLAY: ObjectAddress = ObjectAddress::new(0x6061, 0);

/// The objects `modes` need mapped, per direction.
pub fn required_objects(modes: &[CyclicModeRef]) -> (Vec<ObjectAddress>, Vec<ObjectAddress>) {
    let mut rx = vec![CONTROLWORD];
    let mut tx = vec![STATUSWORD];
    for m in modes {
        let (set_point, feedback) = match m.code {
            8 => (0x607A, Some(0x6064)),
            9 => (0x60FF, None),
            _ => (0x6071, None),
        };
        let sp = ObjectAddress::new(set_point, 0);
        if !rx.contains(&sp) {
            rx.push(sp);
        }
        if let Some(f) = feedback.map(|f| ObjectAddress::new(f, 0))
            && !tx.contains(&f)
        {
            tx.push(f);
        }
    }
    if modes.len() > 1 {
        rx.push(MODE);
        tx.push(MODE_DISPLAY);
    }
    (rx, tx)
}

/// How a mapping was arrived at.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MappingSource {
    /// The file's default assignment.
    Default,
    /// These PDOs of the file, as they are.
    Chosen,
    /// A configurable PDO with objects appended.
    Built,
}

/// One direction's part of a mapping decision.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct DirectionChoice {
    /// How.
    pub source: MappingSource,
    /// The PDOs assigned.
    pub pdos: Vec<u16>,
}

/// The mapping for a set of modes, or why there is none.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ModeMapping {
    /// The modes.
    pub modes: Vec<&'static str>,
    /// The RxPDO side.
    pub rx: Result<DirectionChoice, String>,
    /// The TxPDO side.
    pub tx: Result<DirectionChoice, String>,
    /// The mapping, when both sides have one.
    #[serde(skip)]
    pub mapping: Option<Mapping>,
}

impl ModeMapping {
    /// Whether the modes can be carried.
    pub fn ok(&self) -> bool {
        self.mapping.is_some()
    }
}

/// One `<InitCmd>` as ecdrive would send it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct InitCmdPlan {
    /// Line of the element in the file.
    pub line: u32,
    /// The transitions (`PS`, `SO`, …).
    pub transitions: Vec<&'static str>,
    /// `0xIIII:SS`.
    pub object: String,
    /// The data, hex.
    pub data: String,
    /// The file's comment.
    pub comment: String,
    /// Complete access.
    pub complete_access: bool,
    /// `Fixed`: a configuration value for the same object is refused.
    pub fixed: bool,
    /// `<Timeout>`, ms (None: the master's SDO timeout).
    pub timeout_ms: Option<u32>,
    /// `<Retries>`.
    pub retries: u8,
    /// `<Disabled>`: not sent.
    pub disabled: bool,
}

/// The DC operation mode ecdrive would use.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct DcPlan {
    /// The `<OpMode>` name.
    pub name: String,
    /// AssignActivate (0x0980).
    pub assign_activate: u16,
    /// SYNC0 cycle = factor × the cycle (when the file gives a factor; else 1).
    pub sync0_factor: i16,
    /// SYNC0 shift, ns, as written.
    pub shift_ns: i32,
}

/// What ecdrive would make of one device of an ESI file.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DrivePlan {
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision, if the file gives one.
    pub revision: Option<u32>,
    /// The device's name.
    pub name: String,
    /// The cyclic modes the drive supports (0x6502 default in the dictionary, bits 7–9); all
    /// three when the file does not say.
    pub modes: Vec<&'static str>,
    /// Whether the modes come from 0x6502 (else assumed).
    pub modes_from_0x6502: bool,
    /// Per supported cyclic mode, and for all of them together: the mapping.
    pub mappings: Vec<ModeMapping>,
    /// The DC operation mode with SYNC0 (None: the file offers none; free run).
    pub dc: Option<DcPlan>,
    /// Whether 0x1C32:02 (cycle time) is writable; when it is not, the InitCmds or the drive
    /// set the cycle.
    pub cycle_time_writable: Option<bool>,
    /// The `<InitCmd>`s in file order.
    pub init_cmds: Vec<InitCmdPlan>,
    /// Why the device is no CiA 402 drive ecdrive can run from this file, if it is not: no
    /// 0x6040 and 0x6041 in its dictionary or PDOs (an I/O device, a coupler), or PDOs that
    /// name their own mapping object.
    pub not_a_drive: Option<String>,
}

fn transition_name(t: Transition) -> &'static str {
    t.name()
}

fn hex(b: &[u8]) -> String {
    b.iter().fold(String::new(), |mut s, x| {
        let _ = write!(s, "{x:02X}");
        s
    })
}

fn objects_of(pdos: &[&super::model::EsiPdo]) -> Vec<ObjectAddress> {
    pdos.iter()
        .flat_map(|p| p.entries.iter())
        .filter(|e| !e.is_padding())
        .map(|e| ObjectAddress::new(e.index, e.sub))
        .collect()
}

fn name_of(dev: &Device, a: ObjectAddress) -> String {
    let n = dev
        .dictionary()
        .and_then(|d| d.object(a.index))
        .map(|o| o.name.clone())
        .unwrap_or_default();
    if n.is_empty() {
        format!("0x{:04X}:{:02X}", a.index, a.sub)
    } else {
        format!("0x{:04X}:{:02X} ({n})", a.index, a.sub)
    }
}

/// The choice for one direction.
fn choose(
    dev: &Device,
    dir: Direction,
    need: &[ObjectAddress],
) -> Result<(DirectionChoice, Vec<Pdo>), String> {
    let all: Vec<&super::model::EsiPdo> = dev.pdos(dir).iter().filter(|p| !p.virtual_).collect();
    let carries = |set: &[&super::model::EsiPdo]| {
        let have = objects_of(set);
        need.iter().all(|a| have.contains(a))
    };
    let to_pdos = |set: &[&super::model::EsiPdo]| -> Result<Vec<Pdo>, String> {
        set.iter()
            .map(|p| p.to_pdo(dir).map_err(|e| e.to_string()))
            .collect()
    };
    // 1. The default assignment.
    let default: Vec<&super::model::EsiPdo> =
        all.iter().copied().filter(|p| p.is_default()).collect();
    if !default.is_empty() && carries(&default) {
        return Ok((
            DirectionChoice {
                source: MappingSource::Default,
                pdos: default.iter().map(|p| p.index).collect(),
            },
            to_pdos(&default)?,
        ));
    }
    // 2. The smallest set of PDOs without exclusions (mandatory ones always in).
    let mandatory: Vec<&super::model::EsiPdo> =
        all.iter().copied().filter(|p| p.mandatory).collect();
    let optional: Vec<&super::model::EsiPdo> =
        all.iter().copied().filter(|p| !p.mandatory).collect();
    let n = optional.len().min(16);
    let mut best: Option<Vec<&super::model::EsiPdo>> = None;
    for mask in 0u32..(1u32 << n) {
        if best
            .as_ref()
            .is_some_and(|b| b.len() - mandatory.len() <= mask.count_ones() as usize)
        {
            continue;
        }
        let mut set = mandatory.clone();
        set.extend(
            optional
                .iter()
                .take(n)
                .enumerate()
                .filter(|(i, _)| mask & (1 << i) != 0)
                .map(|(_, p)| *p),
        );
        set.sort_by_key(|p| p.position.line);
        let excluded = set
            .iter()
            .any(|p| set.iter().any(|q| p.excludes.contains(&q.index)));
        if !excluded && !set.is_empty() && carries(&set) {
            best = Some(set);
        }
    }
    if let Some(set) = best {
        return Ok((
            DirectionChoice {
                source: MappingSource::Chosen,
                pdos: set.iter().map(|p| p.index).collect(),
            },
            to_pdos(&set)?,
        ));
    }
    // 3. A configurable PDO with the missing objects appended.
    let configurable = dev
        .mailbox
        .as_ref()
        .and_then(|m| m.coe.as_ref())
        .is_some_and(|c| c.pdo_config);
    let base = all
        .iter()
        .copied()
        .filter(|p| !p.fixed)
        .min_by_key(|p| (!p.is_default(), p.position.line));
    let missing: Vec<ObjectAddress> = {
        let have = objects_of(&default);
        need.iter().copied().filter(|a| !have.contains(a)).collect()
    };
    let names: Vec<String> = missing.iter().map(|a| name_of(dev, *a)).collect();
    let Some(base) = base.filter(|_| configurable) else {
        return Err(format!(
            "no {} of the file carries {} with the rest, and its PDOs cannot be configured",
            dir.name(),
            names.join(", ")
        ));
    };
    let dict = dev.dictionary();
    let mut pdo = base.to_pdo(dir).map_err(|e| e.to_string())?;
    let mut entries: Vec<PdoEntry> = pdo.entries.to_vec();
    for a in &need
        .iter()
        .copied()
        .filter(|a| !objects_of(&[base]).contains(a))
        .collect::<Vec<_>>()
    {
        let entry = dict
            .and_then(|d| d.resolve(a.index))
            .and_then(Result::ok)
            .and_then(|o| o.entry(a.sub).cloned());
        let Some(e) = entry else {
            return Err(format!(
                "{} is not in the file's dictionary",
                name_of(dev, *a)
            ));
        };
        let flag = match dir {
            Direction::Rx => EntryAccess::RXPDO,
            Direction::Tx => EntryAccess::TXPDO,
        };
        if !e.access.contains(flag) {
            return Err(format!(
                "{} cannot be mapped into an {} (its PdoMapping flag)",
                name_of(dev, *a),
                dir.name()
            ));
        }
        let bits = u8::try_from(e.bit_len)
            .map_err(|_| format!("{} is too long to map", name_of(dev, *a)))?;
        entries.push(PdoEntry::new(a.index, a.sub, bits));
    }
    let limit = dict
        .and_then(|d| d.resolve(base.index))
        .and_then(Result::ok)
        .map(|o| o.entries.iter().filter(|e| e.sub > 0).count());
    if let Some(limit) = limit
        && entries.len() > limit
    {
        return Err(format!(
            "{} 0x{:04X} would need {} entries; the file's dictionary gives it {limit}",
            dir.name(),
            base.index,
            entries.len()
        ));
    }
    pdo.entries = Cow::Owned(entries);
    Ok((
        DirectionChoice {
            source: MappingSource::Built,
            pdos: vec![base.index],
        },
        vec![pdo],
    ))
}

/// The mapping for `modes` (see the module documentation).
pub fn mapping_for(dev: &Device, modes: &[CyclicModeRef]) -> ModeMapping {
    let (rx_need, tx_need) = required_objects(modes);
    let rx = choose(dev, Direction::Rx, &rx_need);
    let tx = choose(dev, Direction::Tx, &tx_need);
    let mapping = match (&rx, &tx) {
        (Ok((_, r)), Ok((_, t))) => Some(Mapping {
            rx: Cow::Owned(r.clone()),
            tx: Cow::Owned(t.clone()),
        }),
        _ => None,
    };
    ModeMapping {
        modes: modes.iter().map(|m| m.name).collect(),
        rx: rx.map(|(c, _)| c),
        tx: tx.map(|(c, _)| c),
        mapping,
    }
}

impl DrivePlan {
    /// The plan for `dev` of `file`.
    pub fn new(file: &EsiFile, dev: &Device) -> Self {
        let dict = dev.dictionary();
        let supported = dict
            .and_then(|d| d.resolve(0x6502))
            .and_then(Result::ok)
            .and_then(|o| o.entry(0).and_then(|e| e.default.clone()))
            .and_then(|v| v.as_i128())
            .and_then(|v| u64::try_from(v).ok())
            // A default of 0 is a placeholder (Inovance's IS620N file: the firmware fills the
            // object in; its sister SV660N file has 0x3AD): no mode is known from it, as
            // without a default.
            .filter(|&v| v != 0);
        let modes: Vec<CyclicModeRef> = match supported {
            Some(bits) => CYCLIC_MODES
                .iter()
                .copied()
                .filter(|m| bits & (1 << (m.code - 1)) != 0)
                .collect(),
            None => CYCLIC_MODES.to_vec(),
        };
        let mut mappings: Vec<ModeMapping> =
            modes.iter().map(|m| mapping_for(dev, &[*m])).collect();
        if modes.len() > 1 {
            mappings.push(mapping_for(dev, &modes));
        }
        let dc = dev
            .dc
            .iter()
            .find(|m| m.mode.assign_activate & 0x0300 == 0x0300)
            .map(|m| DcPlan {
                name: m.mode.name.clone(),
                assign_activate: m.mode.assign_activate,
                sync0_factor: if m.mode.sync0_cycle_factor == 0 {
                    1
                } else {
                    m.mode.sync0_cycle_factor
                },
                shift_ns: m.mode.shift_time0,
            });
        let cycle_time_writable = dict
            .and_then(|d| d.resolve(0x1C32))
            .and_then(Result::ok)
            .and_then(|o| {
                o.entry(2)
                    .map(|e| e.access.contains(EntryAccess::WRITE_PREOP))
            });
        let init_cmds = dev
            .mailbox
            .as_ref()
            .map(|m| m.init_cmds.iter().map(init_cmd_plan).collect())
            .unwrap_or_default();
        let in_pdos = |index: u16| {
            dev.rx_pdos
                .iter()
                .chain(dev.tx_pdos.iter())
                .any(|p| p.entries.iter().any(|e| e.index == index))
        };
        let in_dict = |index: u16| dict.is_some_and(|d| d.object(index).is_some());
        let self_mapped = dev.rx_pdos.iter().chain(dev.tx_pdos.iter()).find_map(|p| {
            p.entries
                .iter()
                .find(|e| e.index == p.index)
                .map(|e| (p, e))
        });
        let not_a_drive = if let Some((p, e)) = self_mapped {
            Some(format!(
                "PDO 0x{:04X} maps its own mapping object (0x{:04X}:{:02X} {:?}): the file does \
                 not say which objects the device maps",
                p.index, e.index, e.sub, e.name
            ))
        } else if !(in_dict(0x6040) || in_pdos(0x6040)) || !(in_dict(0x6041) || in_pdos(0x6041)) {
            Some(
                "no 0x6040 (controlword) and 0x6041 (statusword) in its dictionary or PDOs: \
                 not a CiA 402 drive (an I/O device runs with its process data)"
                    .to_string(),
            )
        } else if dict.is_none() {
            Some(
                "the file has no object dictionary (<Profile><Dictionary>): a drive is run from \
                 its file's dictionary (types, access, modes)"
                    .to_string(),
            )
        } else if !(in_dict(0x6060) || in_pdos(0x6060)) {
            // A firmware loader (Elmo's "GCON Boot" devices have nine objects, 0x6040 and
            // 0x6041 among them) is no drive to run; neither is a device whose mode cannot be
            // set.
            Some(
                "no 0x6060 (modes of operation) in its dictionary or PDOs: the mode of operation \
                 cannot be set, so ecdrive does not run it as a drive (an I/O device runs with its \
                 process data)"
                    .to_string(),
            )
        } else {
            None
        };
        Self {
            not_a_drive,
            vendor_id: file.vendor.id,
            product_code: dev.type_.product_code,
            revision: dev.type_.revision_no,
            name: dev.name.clone(),
            modes: modes.iter().map(|m| m.name).collect(),
            modes_from_0x6502: supported.is_some(),
            mappings,
            dc,
            cycle_time_writable,
            init_cmds,
        }
    }
}

fn init_cmd_plan(c: &InitCmd) -> InitCmdPlan {
    InitCmdPlan {
        line: c.position.line,
        transitions: c.transitions.iter().map(|t| transition_name(*t)).collect(),
        object: format!("0x{:04X}:{:02X}", c.index, c.sub),
        data: hex(&c.data),
        comment: c.comment.clone(),
        complete_access: c.complete_access,
        fixed: c.fixed,
        timeout_ms: c.timeout_ms,
        retries: c.retries,
        disabled: c.disabled,
    }
}
