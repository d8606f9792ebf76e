//! Conversions from ESI PDO descriptions into the crate's [`Pdo`] / [`Mapping`].

use super::model::{Device, EsiPdo};
use crate::pdo::{Direction, Mapping, Pdo, PdoEntry};
use std::borrow::Cow;

/// Why ESI PDOs could not be turned into a [`Mapping`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EsiConvertError {
    /// An entry is longer than a PDO mapping entry can describe (255 bits).
    #[error(
        "{dir} 0x{pdo:04X}: entry 0x{index:04X}:{sub:02X} has BitLen {bits}, more than the 255 \
         bits a mapping entry can hold"
    )]
    EntryTooLong {
        /// The PDO's direction (`RxPDO`/`TxPDO`).
        dir: &'static str,
        /// PDO index.
        pdo: u16,
        /// Entry index.
        index: u16,
        /// Entry sub-index.
        sub: u8,
        /// Its bit length.
        bits: u16,
    },
    /// A requested PDO is not in the ESI.
    #[error("the device offers no {dir} 0x{index:04X}")]
    UnknownPdo {
        /// `RxPDO`/`TxPDO`.
        dir: &'static str,
        /// The requested index.
        index: u16,
    },
    /// A PDO is requested twice.
    #[error("{dir} 0x{index:04X} is assigned twice")]
    Duplicate {
        /// `RxPDO`/`TxPDO`.
        dir: &'static str,
        /// The index.
        index: u16,
    },
    /// Two selected PDOs exclude each other (`<Exclude>`).
    #[error("{dir} 0x{a:04X} excludes 0x{b:04X}: they cannot be assigned together")]
    Excluded {
        /// `RxPDO`/`TxPDO`.
        dir: &'static str,
        /// The PDO carrying the `<Exclude>`.
        a: u16,
        /// The excluded PDO.
        b: u16,
    },
    /// A mandatory PDO is not selected.
    #[error("{dir} 0x{index:04X} is mandatory and must be assigned")]
    MissingMandatory {
        /// `RxPDO`/`TxPDO`.
        dir: &'static str,
        /// The index.
        index: u16,
    },
}

impl EsiPdo {
    /// This PDO as the crate's [`Pdo`]: index and entries (gaps become padding entries).
    /// `dir` only names the PDO in errors.
    pub fn to_pdo(&self, dir: Direction) -> Result<Pdo, EsiConvertError> {
        let entries = self
            .entries
            .iter()
            .map(|e| {
                let bits = u8::try_from(e.bit_len).map_err(|_| EsiConvertError::EntryTooLong {
                    dir: dir.name(),
                    pdo: self.index,
                    index: e.index,
                    sub: e.sub,
                    bits: e.bit_len,
                })?;
                Ok(if e.is_padding() {
                    PdoEntry::padding(bits)
                } else {
                    PdoEntry::new(e.index, e.sub, bits)
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Pdo::owned(self.index, entries))
    }
}

impl Device {
    /// The default PDO assignment as a [`Mapping`].
    ///
    /// Rule (ETG.2000): a PDO is assigned by default when it has an `Sm` attribute; a
    /// `Mandatory` PDO is always assigned, with or without one. PDOs keep their file order.
    /// Exclusions are not checked here (a vendor file may be inconsistent; see
    /// [`Device::check`]).
    pub fn default_mapping(&self) -> Result<Mapping, EsiConvertError> {
        let pick = |dir: Direction| -> Result<Vec<Pdo>, EsiConvertError> {
            self.pdos(dir)
                .iter()
                .filter(|p| p.is_default())
                .map(|p| p.to_pdo(dir))
                .collect()
        };
        Ok(Mapping {
            rx: Cow::Owned(pick(Direction::Rx)?),
            tx: Cow::Owned(pick(Direction::Tx)?),
        })
    }

    /// A [`Mapping`] of the chosen PDOs (by index, in the order given), with their ESI
    /// entries. Checks that each exists, none is chosen twice, no two chosen PDOs exclude each
    /// other, and every mandatory PDO is chosen.
    pub fn mapping(&self, rx: &[u16], tx: &[u16]) -> Result<Mapping, EsiConvertError> {
        let pick = |dir: Direction, chosen: &[u16]| -> Result<Vec<Pdo>, EsiConvertError> {
            let d = dir.name();
            let mut out = Vec::with_capacity(chosen.len());
            for (i, &index) in chosen.iter().enumerate() {
                if chosen.get(..i).unwrap_or_default().contains(&index) {
                    return Err(EsiConvertError::Duplicate { dir: d, index });
                }
                let p = self
                    .pdo(dir, index)
                    .ok_or(EsiConvertError::UnknownPdo { dir: d, index })?;
                if let Some(&b) = p.excludes.iter().find(|x| chosen.contains(x)) {
                    return Err(EsiConvertError::Excluded {
                        dir: d,
                        a: index,
                        b,
                    });
                }
                out.push(p.to_pdo(dir)?);
            }
            if let Some(m) = self
                .pdos(dir)
                .iter()
                .find(|p| p.mandatory && !chosen.contains(&p.index))
            {
                return Err(EsiConvertError::MissingMandatory {
                    dir: d,
                    index: m.index,
                });
            }
            Ok(out)
        };
        Ok(Mapping {
            rx: Cow::Owned(pick(Direction::Rx, rx)?),
            tx: Cow::Owned(pick(Direction::Tx, tx)?),
        })
    }
}

fn leak_str(s: &str) -> &'static str {
    String::leak(s.to_owned())
}

fn constant(v: &Option<crate::od::Value>) -> crate::od::ConstValue {
    use crate::od::{ConstValue, Value};
    match v {
        None => ConstValue::None,
        Some(Value::Int(i)) => ConstValue::Int(*i),
        Some(Value::Uint(u)) => ConstValue::Uint(*u),
        Some(Value::Real(r)) => ConstValue::Real(*r),
        Some(Value::Str(s)) => ConstValue::Str(leak_str(s)),
        Some(Value::Bytes(b)) => ConstValue::Bytes(Vec::leak(b.clone())),
    }
}

/// The device's object dictionary as `'static` object descriptions, sorted by index: what a
/// drive profile built from the file and an emulated device built from it both use. The
/// descriptions are leaked: build them once per file and process (at start-up, never in a
/// cycle). Objects that cannot be resolved and entries of a type ecdrive does not know are
/// left out (`esi check` names each): a run that needs one finds it missing and says so.
/// Only a device without any dictionary is an error.
pub fn static_dictionary(dev: &Device) -> Result<&'static [crate::od::ObjectDesc], String> {
    use crate::od::{EntryDesc, ObjectDesc};
    let dict = dev
        .dictionary()
        .ok_or_else(|| "the device has no object dictionary".to_string())?;
    let mut objects = Vec::with_capacity(dict.objects.len());
    for o in dict
        .objects
        .iter()
        .filter_map(|o| dict.resolve_object(o).ok())
    {
        if objects.iter().any(|x: &ObjectDesc| x.index == o.index) {
            continue;
        }
        let mut entries: Vec<EntryDesc> = Vec::with_capacity(o.entries.len());
        for e in &o.entries {
            // A sub-index described twice (an array whose elements start at 0 collides with
            // its count): the first description holds.
            if entries.iter().any(|x| x.sub == e.sub) {
                continue;
            }
            let (Some(data_type), Ok(mut bit_len)) = (e.data_type, u16::try_from(e.bit_len)) else {
                continue;
            };
            // A string's default may be longer than its BitSize says: strings have the
            // length of their value.
            if data_type.is_string() {
                let n = match &e.default {
                    Some(crate::od::Value::Str(s)) => s.len(),
                    Some(crate::od::Value::Bytes(b)) => b.len(),
                    _ => 0,
                };
                bit_len = bit_len.max(u16::try_from(n * 8).unwrap_or(u16::MAX));
            }
            // What the file's own PDOs map is mappable in their direction, whatever the
            // entry's flags say (a file that marks nothing mappable maps 0x6040 in 0x1600).
            let mut access = e.access;
            for (dir, flag) in [
                (Direction::Rx, crate::od::EntryAccess::RXPDO),
                (Direction::Tx, crate::od::EntryAccess::TXPDO),
            ] {
                let mapped = dev.pdos(dir).iter().any(|p| {
                    p.entries
                        .iter()
                        .any(|x| x.index == o.index && x.sub == e.sub && x.index != p.index)
                });
                if mapped {
                    access |= flag;
                }
            }
            entries.push(EntryDesc {
                sub: e.sub,
                name: leak_str(&e.name),
                data_type,
                bit_len,
                access,
                default: constant(&e.default),
                min: constant(&e.min),
                max: constant(&e.max),
            });
        }
        // An ARRAY or RECORD counts its entries in an UNSIGNED8 at sub-index 0; one that
        // does not cannot be served (left out, as `esi check` says).
        let counted = o.code == crate::od::ObjectCode::Var
            || entries
                .iter()
                .find(|e| e.sub == 0)
                .is_some_and(|e| e.data_type == crate::od::DataType::Unsigned8);
        if entries.is_empty() || !counted {
            continue;
        }
        objects.push(ObjectDesc {
            index: o.index,
            name: leak_str(&o.name),
            code: o.code,
            entries: Vec::leak(entries),
        });
    }
    add_pdo_mapped(dev, &mut objects);
    objects.sort_by_key(|o| o.index);
    Ok(Vec::leak(objects))
}

/// The data type of a PDO entry: its `<DataType>` where ecdrive knows it and it has the
/// entry's size, else an unsigned integer (or a byte string) of the entry's size.
pub fn pdo_entry_type(name: Option<crate::od::DataType>, bits: u16) -> crate::od::DataType {
    use crate::od::DataType;
    match name {
        Some(t) if t.bit_len() == Some(bits) => t,
        _ => match bits {
            1 => DataType::Boolean,
            8 => DataType::Unsigned8,
            16 => DataType::Unsigned16,
            24 => DataType::Unsigned24,
            32 => DataType::Unsigned32,
            64 => DataType::Unsigned64,
            b if b < 8 => DataType::Unsigned8,
            _ => DataType::OctetString,
        },
    }
}

/// Objects the file's own PDOs map that its dictionary lacks (an Elmo boot device maps 0x60FD
/// in a fixed TxPDO that its nine-object dictionary does not describe): the PDO entry is the
/// file's description of them, so they are added with its data type and size, mappable in the
/// PDO's direction (`esi check` names each). The device has them, or its fixed PDO would not
/// work.
fn add_pdo_mapped(dev: &Device, objects: &mut Vec<crate::od::ObjectDesc>) {
    use crate::od::{EntryAccess, EntryDesc, ObjectCode, ObjectDesc};
    for (dir, flag, access) in [
        (Direction::Rx, EntryAccess::RXPDO, EntryAccess::RW),
        (Direction::Tx, EntryAccess::TXPDO, EntryAccess::RO),
    ] {
        for p in dev.pdos(dir).iter().filter(|p| !p.virtual_) {
            for e in p
                .entries
                .iter()
                .filter(|e| !e.is_padding() && e.index != p.index)
            {
                let entry = EntryDesc {
                    sub: e.sub,
                    name: leak_str(&e.name),
                    data_type: pdo_entry_type(e.data_type(), e.bit_len),
                    bit_len: e.bit_len,
                    access: access.union(flag),
                    default: crate::od::ConstValue::None,
                    min: crate::od::ConstValue::None,
                    max: crate::od::ConstValue::None,
                };
                match objects.iter_mut().find(|o| o.index == e.index) {
                    Some(o) if o.entries.iter().any(|x| x.sub == e.sub) => {}
                    // A variable mapped by sub-index: the variable holds.
                    Some(o) if o.code == ObjectCode::Var => {}
                    Some(o) => {
                        let mut entries = o.entries.to_vec();
                        entries.push(entry);
                        entries.sort_by_key(|x| x.sub);
                        o.entries = Vec::leak(entries);
                    }
                    None => {
                        let (code, entries) = if e.sub == 0 {
                            (ObjectCode::Var, vec![entry])
                        } else {
                            let count = EntryDesc::new(
                                0,
                                "Number of entries",
                                crate::od::DataType::Unsigned8,
                                EntryAccess::RO,
                            )
                            .default(crate::od::ConstValue::Uint(u64::from(e.sub)));
                            (ObjectCode::Record, vec![count, entry])
                        };
                        objects.push(ObjectDesc {
                            index: e.index,
                            name: entry.name,
                            code,
                            entries: Vec::leak(entries),
                        });
                    }
                }
            }
        }
    }
}
