//! An EDS/DCF file's objects as a dictionary table ([`ObjectDesc`]): what the master's SDO
//! client and the software slave's object store both work from. The conversion is the file's,
//! not a drive model's: each side decides its behaviour on its own.
//!
//! | file | table |
//! |---|---|
//! | `ObjectType` 7 / 8 / 9 | VAR (sub-index 0) / ARRAY / RECORD; other object types (DOMAIN, DEFTYPE, DEFSTRUCT, NULL) are left out |
//! | `DataType` | the type; an entry of a type without a fixed size (other than strings) is left out |
//! | `AccessType` + `PDOMapping` | read/write; `PDOMapping=1` adds RPDO mapping when writable, TPDO when readable (`rww`: RPDO only, `rwr`: TPDO only) |
//! | `ParameterValue` (DCF), else `DefaultValue` | the default; signed values written as their unsigned pattern (`0xFFFFFFFF` for −1) are read back as signed |
//! | `$NODEID+x` | `x`: node-relative objects hold the value for node-ID 0 and the node adds its own; a literal COB-ID of the predefined connection set (`0x181`) is taken back to its base |
//! | `LowLimit`/`HighLimit` | the range, when both are numbers of the type |
//! | an ARRAY/RECORD without sub-index 0 | sub-index 0 added, the highest sub-index |
//!
//! Tables built this way live for the rest of the process (the table type holds `'static`
//! data): a configuration builds each once, at start-up, never in the cycle.

use super::{Access, EdsEntry, EdsFile, EdsValue, ObjectKind};
use crate::od::{ConstValue, DataType, EntryAccess, EntryDesc, ObjectCode, ObjectDesc};

fn leak(s: &str) -> &'static str {
    String::leak(s.to_owned())
}

/// A file's objects as a dictionary table, and what was left out.
#[derive(Debug, Clone)]
pub struct EdsDictionary {
    /// The objects, sorted by index.
    pub objects: &'static [ObjectDesc],
    /// What was left out or changed, one line each (`2FFFh: DOMAIN object left out`).
    pub notes: Vec<String>,
}

/// Whether a COB-ID in `addr` is node-relative (the node adds its ID to the value for node 0).
const fn node_relative(index: u16, sub: u8) -> bool {
    match index {
        0x1014 => sub == 0,
        0x1200 => sub == 1 || sub == 2,
        0x1400..=0x15FF | 0x1800..=0x19FF => sub == 1,
        _ => false,
    }
}

/// A literal COB-ID of the predefined connection set (`0x181`: TPDO1 of node 1) taken back to
/// its base (`0x180`); `node`: a DCF's node-ID, subtracted when it fits.
fn cob_base(v: i128, node: Option<u8>) -> i128 {
    let cob = v & 0x7FF;
    let low = match node {
        Some(n) if cob & 0x7F == i128::from(n) => i128::from(n),
        _ => cob & 0x7F,
    };
    let base = cob - low;
    let predefined = matches!(
        base,
        0x080 | 0x180 | 0x200 | 0x280 | 0x300 | 0x380 | 0x400 | 0x480 | 0x500 | 0x580 | 0x600
    );
    if low != 0 && predefined { v - low } else { v }
}

/// `v` as a value of `dt`: unsigned patterns of signed types read back as signed, negative
/// values of unsigned types as their pattern; `None` when it does not fit.
fn fit(dt: DataType, v: i128) -> Option<ConstValue> {
    let bits = i128::from(dt.bit_len()?);
    if bits == 0 || bits > 64 {
        return None;
    }
    let span = 1i128 << bits;
    if dt.is_signed() {
        let half = span / 2;
        let v = if v >= half && v < span { v - span } else { v };
        (-half..half)
            .contains(&v)
            .then_some(ConstValue::Int(v as i64))
    } else if dt.is_real() {
        Some(ConstValue::Real(v as f64))
    } else {
        let v = if v < 0 && v >= -span / 2 { v + span } else { v };
        (0..span).contains(&v).then_some(ConstValue::Uint(v as u64))
    }
}

fn const_value(dt: DataType, v: &EdsValue, relative: bool, node: Option<u8>) -> Option<ConstValue> {
    match v {
        EdsValue::None => None,
        EdsValue::Int(n) if relative => fit(dt, cob_base(*n, node)),
        EdsValue::Int(n) => fit(dt, *n),
        EdsValue::NodeId { offset } if relative => fit(dt, *offset),
        // A formula outside the node-relative objects: the value for the DCF's node, else for
        // node 0.
        EdsValue::NodeId { offset } => fit(dt, offset + i128::from(node.unwrap_or(0))),
        EdsValue::Real(f) if dt.is_real() => Some(ConstValue::Real(*f)),
        EdsValue::Real(_) => None,
        EdsValue::Text(t) if dt.is_string() => Some(ConstValue::Str(leak(t))),
        EdsValue::Text(_) => None,
    }
}

fn access_of(e: &EdsEntry) -> EntryAccess {
    let base = match e.access {
        Some(Access::Wo) => EntryAccess::WO,
        Some(Access::Rw | Access::Rwr | Access::Rww) => EntryAccess::RW,
        Some(Access::Ro | Access::Const) | None => EntryAccess::RO,
    };
    if !e.pdo_mapping {
        return base;
    }
    match e.access {
        Some(Access::Rww) => base.union(EntryAccess::RXPDO),
        Some(Access::Rwr) => base.union(EntryAccess::TXPDO),
        Some(Access::Rw) => base.union(EntryAccess::RXPDO).union(EntryAccess::TXPDO),
        Some(Access::Wo) => base.union(EntryAccess::RXPDO),
        _ => base.union(EntryAccess::TXPDO),
    }
}

/// The table entry of `e` in object `index`; `None` (with a note) for a type without a size.
fn entry(index: u16, e: &EdsEntry, node: Option<u8>, notes: &mut Vec<String>) -> Option<EntryDesc> {
    let Some(dt) = e
        .data_type
        .filter(|d| d.bit_len().is_some() || d.is_string())
    else {
        notes.push(format!(
            "{index:04X}h:{:02X} ({}): data type {} left out",
            e.sub,
            e.name,
            e.data_type_code
                .map_or_else(|| "unknown".to_string(), |c| format!("0x{c:04X}"))
        ));
        return None;
    };
    let relative = node_relative(index, e.sub);
    let value = if e.parameter_value.is_none() {
        &e.default
    } else {
        &e.parameter_value
    };
    let mut d = EntryDesc::new(e.sub, leak(&e.name), dt, access_of(e));
    match const_value(dt, value, relative, node) {
        Some(v) => d = d.default(v),
        None if !value.is_none() => notes.push(format!(
            "{index:04X}h:{:02X} ({}): value {value:?} does not fit {dt}: 0 at power-on",
            e.sub, e.name
        )),
        None => {}
    }
    if let (Some(lo), Some(hi)) = (
        const_value(dt, &e.low, false, node),
        const_value(dt, &e.high, false, node),
    ) && !dt.is_string()
    {
        d = d.range(lo, hi);
    }
    if dt.is_string() {
        let len = match d.default {
            ConstValue::Str(s) => s.len(),
            _ => 0,
        };
        d = d.bits(u16::try_from(len.max(1) * 8).unwrap_or(u16::MAX));
    }
    Some(d)
}

/// **\[REC\]** Position units per motor revolution of a file whose factor group says nothing
/// usable (no 6092h feed, no 608Fh encoder resolution above 1).
pub const FALLBACK_POSITION_PER_REV: f64 = 10_000.0;

impl EdsFile {
    /// The highest sub-index object `index` has in the file (0: no such object, or a VAR).
    pub fn highest_sub(&self, index: u16) -> u8 {
        self.objects
            .get(&index)
            .and_then(|o| o.entries.keys().copied().max())
            .unwrap_or(0)
    }

    /// The PDO mapping objects of one direction the file has (`base` 1600h or 1A00h, at most
    /// four: CiA 301's predefined connection set), each with as many entries as its
    /// sub-indices and fixed where the file makes its count (sub-index 0) read-only; 8 bytes
    /// per PDO.
    pub fn pdo_limits(&self, base: u16) -> crate::pdo::DirectionLimits {
        let mut pdos = Vec::new();
        let mut most = 1u8;
        for index in (base..base + 4).filter(|i| self.objects.contains_key(i)) {
            let subs = self.highest_sub(index).clamp(1, 64);
            most = most.max(subs);
            let writable = self
                .entry(index, 0)
                .and_then(|e| e.access)
                .is_some_and(Access::writable);
            let r = crate::pdo::PdoRange::single(index, subs);
            pdos.push(if writable { r } else { r.fixed() });
        }
        let n = pdos.len().max(1) as u8;
        crate::pdo::DirectionLimits {
            pdos: Vec::leak(pdos),
            max_assigned: n,
            max_entries: u16::from(most) * u16::from(n),
            max_bytes: 8 * u16::from(n),
        }
    }

    /// An entry's value as a number: a DCF's `ParameterValue`, else `DefaultValue` (formulas
    /// for the DCF's node-ID, else node 0).
    pub fn number(&self, index: u16, sub: u8) -> Option<i128> {
        let e = self.entry(index, sub)?;
        let node = self.node_id.unwrap_or(0);
        e.parameter_value
            .resolve(node)
            .or_else(|| e.default.resolve(node))
    }

    /// Position units per motor revolution at power-on, from the factor group (CiA 402: feed
    /// constant 6092h over gear ratio 6091h, else the encoder resolution 608Fh), with where it
    /// came from. A quotient below 2 (a file that leaves 6092h at 1/1 while its positions are
    /// increments, as many do) is not taken; without either,
    /// [`FALLBACK_POSITION_PER_REV`].
    pub fn position_per_rev(&self) -> (f64, &'static str) {
        let ratio = |i: u16| match (self.number(i, 1), self.number(i, 2)) {
            (Some(a), Some(b)) if a > 0 && b > 0 => Some(a as f64 / b as f64),
            _ => None,
        };
        let gear = ratio(0x6091).unwrap_or(1.0);
        if let Some(feed) = ratio(0x6092)
            && feed / gear >= 2.0
        {
            return (feed / gear, "6092h feed constant / 6091h gear ratio");
        }
        match ratio(0x608F) {
            Some(r) if r >= 2.0 => (r, "608Fh position encoder resolution"),
            _ => (
                FALLBACK_POSITION_PER_REV,
                "[REC] 10000 (the file's factor group gives none)",
            ),
        }
    }

    /// The homing methods 60E3h lists (its sub-indices' values), if the file has the object.
    pub fn homing_methods(&self) -> Option<Vec<i8>> {
        let o = self.objects.get(&0x60E3)?;
        let node = self.node_id.unwrap_or(0);
        let mut m: Vec<i8> = o
            .entries
            .values()
            .filter(|e| e.sub > 0)
            .filter_map(|e| {
                e.parameter_value
                    .resolve(node)
                    .or_else(|| e.default.resolve(node))
            })
            .filter_map(|v| i8::try_from(if v > 127 && v < 256 { v - 256 } else { v }).ok())
            .filter(|v| *v != 0)
            .collect();
        m.sort_unstable();
        m.dedup();
        (!m.is_empty()).then_some(m)
    }

    /// The file's objects as a dictionary table (see the [module documentation](self)).
    pub fn dictionary(&self) -> EdsDictionary {
        let mut notes = Vec::new();
        let mut objects = Vec::with_capacity(self.objects.len());
        for o in self.objects.values() {
            let code = match o.kind {
                ObjectKind::Var => ObjectCode::Var,
                ObjectKind::Array => ObjectCode::Array,
                ObjectKind::Record => ObjectCode::Record,
                other => {
                    notes.push(format!(
                        "{:04X}h ({}): {other:?} object left out",
                        o.index, o.name
                    ));
                    continue;
                }
            };
            let mut entries: Vec<EntryDesc> = Vec::with_capacity(o.entries.len() + 1);
            if code == ObjectCode::Var {
                match o.entries.get(&0).or_else(|| o.entries.values().next()) {
                    Some(e) => {
                        let mut e = e.clone();
                        e.sub = 0;
                        entries.extend(entry(o.index, &e, self.node_id, &mut notes));
                    }
                    None => {
                        notes.push(format!("{:04X}h ({}): no value: left out", o.index, o.name));
                    }
                }
                if entries.is_empty() {
                    continue;
                }
            } else {
                let highest = o
                    .entries
                    .keys()
                    .copied()
                    .filter(|s| *s > 0)
                    .max()
                    .unwrap_or(0);
                for e in o.entries.values() {
                    if e.sub == 0 {
                        // Sub-index 0 is the UNSIGNED8 count, whatever type the file wrote.
                        let mut c = e.clone();
                        c.data_type = Some(DataType::Unsigned8);
                        entries.extend(entry(o.index, &c, self.node_id, &mut notes));
                    } else {
                        entries.extend(entry(o.index, e, self.node_id, &mut notes));
                    }
                }
                if entries.first().is_none_or(|e| e.sub != 0) {
                    entries.insert(
                        0,
                        EntryDesc::new(
                            0,
                            "Highest sub-index supported",
                            DataType::Unsigned8,
                            EntryAccess::RO,
                        )
                        .default(ConstValue::Uint(u64::from(highest))),
                    );
                }
            }
            objects.push(ObjectDesc {
                index: o.index,
                name: leak(&o.name),
                code,
                entries: Vec::leak(entries),
            });
        }
        EdsDictionary {
            objects: Vec::leak(objects),
            notes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_patterns_cob_ids_and_missing_counts() {
        let text = "[DeviceInfo]\nVendorNumber=1\n\
            [1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n\
            [1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x40000181\n\
            [1400]\nParameterName=RPDO1\nObjectType=0x9\n\
            [1400sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x200\n\
            [607D]\nParameterName=Limits\nObjectType=0x8\nSubNumber=3\n\
            [607Dsub0]\nParameterName=n\nDataType=0x0007\nAccessType=ro\nDefaultValue=2\n\
            [607Dsub1]\nParameterName=min\nDataType=0x0004\nAccessType=rw\nDefaultValue=#\n\
            [607Dsub2]\nParameterName=max\nDataType=0x0004\nAccessType=rw\nDefaultValue=0x80000000\n\
            [6040]\nParameterName=Controlword\nObjectType=0x7\nDataType=0x0006\nAccessType=rww\nPDOMapping=1\nDefaultValue=0\n";
        let f = EdsFile::parse(text.as_bytes()).unwrap();
        let d = f.dictionary();
        let get = |i: u16, s: u8| {
            d.objects
                .iter()
                .find(|o| o.index == i)
                .and_then(|o| o.entries.iter().find(|e| e.sub == s))
                .copied()
        };
        assert_eq!(
            get(0x1800, 1).map(|e| e.default),
            Some(ConstValue::Uint(0x4000_0180))
        );
        assert_eq!(get(0x1800, 0).map(|e| e.default), Some(ConstValue::Uint(1)));
        assert_eq!(
            get(0x1400, 1).map(|e| e.default),
            Some(ConstValue::Uint(0x200))
        );
        assert_eq!(
            get(0x607D, 0).map(|e| e.data_type),
            Some(DataType::Unsigned8)
        );
        assert_eq!(
            get(0x607D, 2).map(|e| e.default),
            Some(ConstValue::Int(i64::from(i32::MIN)))
        );
        assert_eq!(get(0x607D, 1).map(|e| e.default), Some(ConstValue::None));
        let cw = get(0x6040, 0).unwrap();
        assert!(cw.access.contains(EntryAccess::RXPDO) && !cw.access.contains(EntryAccess::TXPDO));
        assert!(
            d.notes.iter().any(|n| n.contains("607Dh:01")),
            "{:?}",
            d.notes
        );
    }
}
