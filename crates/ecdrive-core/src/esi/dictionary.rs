//! `<Profile><Dictionary>`: the object dictionary an ESI file describes, as written, and
//! resolved into per-entry descriptions comparable with [`crate::od::ObjectDesc`].

use super::error::{EsiError, EsiErrorKind, Position};
use super::num;
use crate::od::{DataType, EntryAccess, ObjectCode, ObjectDesc, Value};
use core::fmt;

/// `<Dictionary>`: data types and objects as written.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Dictionary {
    /// `<DataTypes><DataType>`s.
    pub data_types: Vec<EsiDataType>,
    /// `<Objects><Object>`s.
    pub objects: Vec<EsiObject>,
}

/// `<DataType>`: a base type (`UINT`, 16 bits), an array type (`BaseType` + `ArrayInfo`) or a
/// structured type (`SubItem`s).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiDataType {
    /// Where the element starts.
    pub position: Position,
    /// `<Name>`, referenced by objects and sub-items (`DT1018`, `UDINT`, …).
    pub name: String,
    /// `<BaseType>` (arrays).
    pub base_type: Option<String>,
    /// `<BitSize>`.
    pub bit_size: u32,
    /// `<ArrayInfo>`.
    pub array: Option<ArrayInfo>,
    /// `<SubItem>`s.
    pub sub_items: Vec<EsiSubItem>,
}

/// `<ArrayInfo>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArrayInfo {
    /// `<LBound>`: the sub-index of the first element (usually 1).
    pub lbound: u32,
    /// `<Elements>`.
    pub elements: u32,
}

/// `<SubItem>` of a structured `<DataType>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiSubItem {
    /// `<SubIdx>`. Absent for the element list of an array type.
    pub sub_idx: Option<u8>,
    /// `<Name>`.
    pub name: String,
    /// `<Type>`.
    pub type_name: String,
    /// `<BitSize>`.
    pub bit_size: u32,
    /// `<BitOffs>`.
    pub bit_offs: u32,
    /// `<Flags>`.
    pub flags: Option<Flags>,
}

/// `<Object>`.
#[derive(Debug, Clone, PartialEq)]
pub struct EsiObject {
    /// Where the element starts.
    pub position: Position,
    /// `<Index>`.
    pub index: u16,
    /// The preferred `<Name>`.
    pub name: String,
    /// `<Type>`: a base type name or a `<DataType>` name.
    pub type_name: String,
    /// `<BitSize>`.
    pub bit_size: u32,
    /// `<Info>`: defaults and limits.
    pub info: ObjectInfo,
    /// `<Flags>`.
    pub flags: Option<Flags>,
}

/// `<Info>` of an object or of one of its sub-items.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ObjectInfo {
    /// `<DefaultData>`, `<DefaultValue>` or `<DefaultString>`.
    pub default: Option<EsiValue>,
    /// `<MinData>` or `<MinValue>`.
    pub min: Option<EsiValue>,
    /// `<MaxData>` or `<MaxValue>`.
    pub max: Option<EsiValue>,
    /// `<Unit>`, if given as text.
    pub unit: Option<String>,
    /// `<SubItem>`s: per-entry info, matched to entries by name (then by position).
    pub sub_items: Vec<(String, ObjectInfo)>,
}

/// A value as an ESI file writes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EsiValue {
    /// `…Data`: little-endian bytes.
    Data(Vec<u8>),
    /// `…Value`: a number as text (`#x0025`, `250000`, `-1`).
    Value(String),
    /// `DefaultString`: text.
    String(String),
}

/// `<Category>` in `<Flags>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Category {
    /// `m`: mandatory.
    Mandatory,
    /// `o`: optional.
    Optional,
    /// `c`: conditional.
    Conditional,
}

/// `<Flags>` of an object or sub-item.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Flags {
    /// `<Access>` with its `ReadRestrictions`/`WriteRestrictions`, as read/write bits per
    /// state; `None` if the element is absent.
    pub access: Option<EntryAccess>,
    /// `<PdoMapping>` as [`EntryAccess::RXPDO`] / [`EntryAccess::TXPDO`] bits.
    pub pdo_mapping: EntryAccess,
    /// `<Category>`.
    pub category: Option<Category>,
    /// `<Backup>` ≠ 0.
    pub backup: bool,
    /// `<Setting>` ≠ 0.
    pub setting: bool,
}

impl Default for Flags {
    fn default() -> Self {
        Self {
            access: None,
            pdo_mapping: EntryAccess::empty(),
            category: None,
            backup: false,
            setting: false,
        }
    }
}

impl Flags {
    /// All flags as one [`EntryAccess`]: read/write per state, PDO mappability, backup and
    /// settings. An absent `<Access>` counts as read-only.
    pub fn entry_access(&self) -> EntryAccess {
        let mut a = self.access.unwrap_or(EntryAccess::RO) | self.pdo_mapping;
        a.set(EntryAccess::BACKUP, self.backup);
        a.set(EntryAccess::SETTINGS, self.setting);
        a
    }
}

impl Dictionary {
    /// The object with index `index`.
    pub fn object(&self, index: u16) -> Option<&EsiObject> {
        self.objects.iter().find(|o| o.index == index)
    }

    /// The data type definition named `name` (exact match, then case-insensitive).
    pub fn data_type(&self, name: &str) -> Option<&EsiDataType> {
        self.data_types.iter().find(|d| d.name == name).or_else(|| {
            self.data_types
                .iter()
                .find(|d| d.name.eq_ignore_ascii_case(name))
        })
    }

    /// Whether the data type named `name` is a byte (8-bit element) array: `ARRAY [0..n] OF
    /// BYTE` and its kin, which ESI files use for byte strings of any length.
    fn is_byte_array(&self, dt: &EsiDataType) -> bool {
        dt.array.is_some()
            && dt.sub_items.is_empty()
            && dt.base_type.as_deref().is_some_and(|b| {
                matches!(
                    DataType::parse(b),
                    Some(DataType::Byte | DataType::Unsigned8 | DataType::Integer8)
                ) || self
                    .data_type(b)
                    .is_some_and(|t| t.bit_size == 8 && t.sub_items.is_empty())
            })
    }

    /// The type name an entry is decoded with: the name itself when it is a base type, else
    /// the `<BaseType>` of the file's `<DataType>` of that name (enumerations and aliases
    /// such as `DT0800EN03` or `DINT_ALIAS`), followed up to a few levels.
    pub fn base_type_name(&self, name: &str) -> String {
        let mut n = name.to_string();
        for _ in 0..8 {
            if DataType::parse(&n).is_some() {
                break;
            }
            match self
                .data_type(&n)
                .filter(|t| t.array.is_none() && t.sub_items.is_empty())
                .and_then(|t| t.base_type.clone())
            {
                Some(b) => n = b,
                None => break,
            }
        }
        n
    }

    /// Resolve the object `index` into entries with types, access and values.
    pub fn resolve(&self, index: u16) -> Option<Result<ResolvedObject, EsiError>> {
        self.object(index).map(|o| self.resolve_object(o))
    }

    /// Resolve every object, in file order. Stops at the first object that cannot be
    /// resolved (values that do not decode are not such a stop: see
    /// [`ResolvedObject::problems`]).
    pub fn resolve_all(&self) -> Result<Vec<ResolvedObject>, EsiError> {
        self.objects
            .iter()
            .map(|o| self.resolve_object(o))
            .collect()
    }

    /// Resolve one object: expand its data type into sub-indices, attach the per-entry info
    /// and flags, and decode defaults and limits with the entry's data type.
    ///
    /// Rules: a type with `<SubItem>`s is a RECORD, or an ARRAY when its non-zero entries
    /// all come from one array-typed sub-item (elements numbered from `LBound`); sub-items
    /// without `<SubIdx>` that are not arrays are alignment gaps and are skipped. Any other
    /// type is a VAR with one entry, sub-index 0. Entry flags are the sub-item's, else the
    /// object's. Info sub-items are matched by name, else by position.
    pub fn resolve_object(&self, obj: &EsiObject) -> Result<ResolvedObject, EsiError> {
        let err = |msg: String| {
            EsiError::new(
                EsiErrorKind::Invalid,
                obj.position,
                format!("<Object> 0x{:04X}: {msg}", obj.index),
            )
        };
        let obj_flags = obj.flags.unwrap_or_default();
        let (code, mut entries) = match self.data_type(&obj.type_name) {
            Some(dt) if !dt.sub_items.is_empty() => self.record_entries(dt, obj_flags, &err)?,
            Some(dt) if self.is_byte_array(dt) => (
                ObjectCode::Var,
                vec![RawEntry {
                    // An object typed with a byte array is one byte string.
                    sub: 0,
                    name: obj.name.clone(),
                    type_name: "OCTET_STRING".into(),
                    bit_len: if obj.bit_size > 0 {
                        obj.bit_size
                    } else {
                        dt.bit_size
                    },
                    flags: obj_flags,
                }],
            ),
            Some(dt) if dt.array.is_some() => {
                (ObjectCode::Array, self.array_entries(dt, obj_flags, &err)?)
            }
            _ => (
                ObjectCode::Var,
                vec![RawEntry {
                    sub: 0,
                    name: obj.name.clone(),
                    type_name: obj.type_name.clone(),
                    bit_len: obj.bit_size,
                    flags: obj_flags,
                }],
            ),
        };
        for e in &mut entries {
            e.type_name = self.base_type_name(&e.type_name);
        }
        let (entries, problems) = resolved_entries(obj, code, entries, &err);
        Ok(ResolvedObject {
            index: obj.index,
            name: obj.name.clone(),
            code,
            entries,
            problems,
        })
    }

    /// The entries of an object whose type has `<SubItem>`s: a RECORD, or an ARRAY when its
    /// non-zero entries all come from one array-typed sub-item.
    fn record_entries(
        &self,
        dt: &EsiDataType,
        obj_flags: Flags,
        err: &dyn Fn(String) -> EsiError,
    ) -> Result<(ObjectCode, Vec<RawEntry>), EsiError> {
        let mut entries = Vec::new();
        let mut array_elems = 0usize;
        let mut other = 0usize;
        for si in &dt.sub_items {
            let flags = si.flags.unwrap_or(obj_flags);
            let array = self
                .data_type(&si.type_name)
                .and_then(|t| t.array.map(|a| (t, a)));
            // A byte array is one entry (a byte string) where it has a sub-index of
            // its own, or where its elements would not fit sub-indices.
            let byte_string = array.and_then(|(arr, info)| {
                let sub = si.sub_idx.or_else(|| {
                    (info.elements > 255)
                        .then(|| u8::try_from(info.lbound.max(1)).ok())
                        .flatten()
                })?;
                self.is_byte_array(arr).then_some(sub)
            });
            if let Some(sub) = byte_string {
                other += usize::from(sub != 0);
                entries.push(RawEntry {
                    sub,
                    name: si.name.clone(),
                    type_name: "OCTET_STRING".into(),
                    bit_len: si.bit_size,
                    flags,
                });
                continue;
            }
            match array {
                Some((arr, info)) => {
                    array_elems += self.sub_item_elements(arr, info, flags, err, &mut entries)?;
                }
                None => {
                    let Some(sub) = si.sub_idx else { continue };
                    if sub != 0 {
                        other += 1;
                    }
                    entries.push(RawEntry {
                        sub,
                        name: si.name.clone(),
                        type_name: si.type_name.clone(),
                        bit_len: si.bit_size,
                        flags,
                    });
                }
            }
        }
        let code = if array_elems > 0 && other == 0 {
            ObjectCode::Array
        } else {
            ObjectCode::Record
        };
        Ok((code, entries))
    }

    /// The elements of an array-typed sub-item (`arr`), numbered from its `LBound`, into
    /// `entries`; returns how many.
    fn sub_item_elements(
        &self,
        arr: &EsiDataType,
        info: ArrayInfo,
        flags: Flags,
        err: &dyn Fn(String) -> EsiError,
        entries: &mut Vec<RawEntry>,
    ) -> Result<usize, EsiError> {
        let base = arr.base_type.as_deref().unwrap_or("");
        let elem_bits = match self.data_type(base) {
            Some(b) if b.sub_items.is_empty() && b.array.is_none() => b.bit_size,
            Some(_) => {
                return Err(err(format!(
                    "array type {:?} has structured base type {base:?}",
                    arr.name
                )));
            }
            None => arr.bit_size.checked_div(info.elements).unwrap_or(0),
        };
        if info.elements > 255 {
            return Err(err(format!(
                "array type {:?} has {} elements (at most 255 fit in sub-indices)",
                arr.name, info.elements
            )));
        }
        for i in 0..info.elements {
            let sub = info
                .lbound
                .checked_add(i)
                .and_then(|s| u8::try_from(s).ok())
                .ok_or_else(|| {
                    err(format!(
                        "array type {:?} elements run past sub-index 255",
                        arr.name
                    ))
                })?;
            entries.push(RawEntry {
                sub,
                name: format!("SubIndex {sub:03}"),
                type_name: base.to_string(),
                bit_len: elem_bits,
                flags,
            });
        }
        Ok(info.elements as usize)
    }

    /// The entries of an object typed directly with an array type: elements plus a
    /// synthesised sub-index 0 holding the count.
    fn array_entries(
        &self,
        dt: &EsiDataType,
        obj_flags: Flags,
        err: &dyn Fn(String) -> EsiError,
    ) -> Result<Vec<RawEntry>, EsiError> {
        let info = dt.array.unwrap_or(ArrayInfo {
            lbound: 1,
            elements: 0,
        });
        let base = dt.base_type.clone().unwrap_or_default();
        let elem_bits = self
            .data_type(&base)
            .map(|b| b.bit_size)
            .unwrap_or(dt.bit_size.checked_div(info.elements).unwrap_or(0));
        let mut entries = vec![RawEntry {
            sub: 0,
            name: "SubIndex 000".into(),
            type_name: "USINT".into(),
            bit_len: 8,
            flags: Flags {
                access: Some(EntryAccess::RO),
                ..obj_flags
            },
        }];
        for i in 0..info.elements.min(255) {
            let Some(sub) = info
                .lbound
                .checked_add(i)
                .and_then(|s| u8::try_from(s).ok())
            else {
                return Err(err("array elements run past sub-index 255".into()));
            };
            entries.push(RawEntry {
                sub,
                name: format!("SubIndex {sub:03}"),
                type_name: base.clone(),
                bit_len: elem_bits,
                flags: obj_flags,
            });
        }
        Ok(entries)
    }
}

/// Each entry with the object's info attached (the sub-item info by name, else by position)
/// and its default and limits decoded with its data type: a value that does not decode is left
/// out and noted; one taken by a tolerance rule (short data, a `#x` pattern) is kept and
/// noted. Returns the entries and the notes.
fn resolved_entries(
    obj: &EsiObject,
    code: ObjectCode,
    entries: Vec<RawEntry>,
    err: &dyn Fn(String) -> EsiError,
) -> (Vec<ResolvedEntry>, Vec<EsiError>) {
    let mut out = Vec::with_capacity(entries.len());
    let mut problems = Vec::new();
    let n_entries = entries.len();
    for (pos, e) in entries.into_iter().enumerate() {
        let info: Option<(&str, &ObjectInfo)> = if code == ObjectCode::Var {
            Some((e.name.as_str(), &obj.info))
        } else {
            let subs = &obj.info.sub_items;
            subs.iter()
                .find(|(n, _)| *n == e.name)
                .or_else(|| {
                    if subs.len() == n_entries {
                        subs.get(pos)
                    } else {
                        None
                    }
                })
                .map(|(n, i)| (n.as_str(), i))
        };
        let data_type = DataType::parse(&e.type_name);
        // A value that does not decode is left out and noted; one taken by a tolerance
        // rule (short data, a `#x` pattern) is kept and noted.
        let mut decode = |v: &Option<EsiValue>, what: &str| -> Option<Value> {
            let (v, dt) = (v.as_ref()?, data_type?);
            let at = |m: String| err(format!("{what} of sub-index {} ({}): {m}", e.sub, e.name));
            match decode_value(v, dt) {
                Ok((value, None)) => Some(value),
                Ok((value, Some(note))) => {
                    problems.push(at(note));
                    Some(value)
                }
                Err(m) => {
                    problems.push(at(format!("{m} (left out)")));
                    None
                }
            }
        };
        let (name, default, min, max) = match info {
            Some((n, i)) => (
                if code == ObjectCode::Array && e.sub != 0 {
                    n.to_string()
                } else {
                    e.name.clone()
                },
                decode(&i.default, "default"),
                decode(&i.min, "minimum"),
                decode(&i.max, "maximum"),
            ),
            None => (e.name.clone(), None, None, None),
        };
        out.push(ResolvedEntry {
            sub: e.sub,
            name,
            type_name: e.type_name,
            data_type,
            bit_len: e.bit_len,
            access: e.flags.entry_access(),
            default,
            min,
            max,
        });
    }
    (out, problems)
}

struct RawEntry {
    sub: u8,
    name: String,
    type_name: String,
    bit_len: u32,
    flags: Flags,
}

/// Decode an ESI value for an entry of type `dt`, as the masters people use
/// read vendor files: `#x…` text as the bit pattern of the type (`#x80000000` is an INTEGER32's
/// minimum), data shorter than the type as its low bytes (zero-extended), data longer than the
/// type when the bytes past it are zero. The note says which rule was used.
fn decode_value(v: &EsiValue, dt: DataType) -> Result<(Value, Option<String>), String> {
    match v {
        EsiValue::Data(bytes) => {
            let want = dt.bit_len().map(|b| usize::from(b).div_ceil(8));
            match want {
                Some(n) if !dt.is_string() && bytes.len() < n && !bytes.is_empty() => {
                    let mut padded = bytes.clone();
                    padded.resize(n, 0);
                    let value = Value::decode(dt, &padded).map_err(|e| e.to_string())?;
                    Ok((
                        value,
                        Some(format!(
                            "{dt} needs {n} bytes, got {}: read as {} zero-extended",
                            bytes.len(),
                            if bytes.len() == 1 {
                                "that byte"
                            } else {
                                "those bytes"
                            }
                        )),
                    ))
                }
                Some(n) if !dt.is_string() && bytes.len() > n => {
                    if bytes
                        .get(n..)
                        .is_some_and(|rest| rest.iter().all(|&b| b == 0))
                    {
                        let value = Value::decode(dt, bytes.get(..n).unwrap_or_default())
                            .map_err(|e| e.to_string())?;
                        Ok((
                            value,
                            Some(format!(
                                "{dt} needs {n} bytes, got {}: the zero bytes past it dropped",
                                bytes.len()
                            )),
                        ))
                    } else {
                        Err(format!("{dt} needs {n} bytes, got {}", bytes.len()))
                    }
                }
                _ => Ok((Value::decode(dt, bytes).map_err(|e| e.to_string())?, None)),
            }
        }
        EsiValue::String(s) => Ok(match dt {
            DataType::OctetString | DataType::Domain => (Value::Bytes(s.as_bytes().to_vec()), None),
            _ if dt.is_string() => (Value::Str(s.clone()), None),
            _ => return decode_value(&EsiValue::Value(s.clone()), dt),
        }),
        EsiValue::Value(s) => {
            if dt.is_string() {
                return Ok(match dt {
                    DataType::OctetString | DataType::Domain => {
                        (Value::Bytes(num::parse_hex_bytes(s)?), None)
                    }
                    _ => (Value::Str(s.clone()), None),
                });
            }
            if dt.is_real() {
                return s
                    .trim()
                    .parse::<f64>()
                    .map(|r| (Value::Real(r), None))
                    .or_else(|_| num::parse_int(s).map(|i| (Value::Real(i as f64), None)))
                    .map_err(|_| format!("{s:?} is not a number"));
            }
            let i = num::parse_int(s).map_err(|m| format!("{s:?}: {m}"))?;
            let bits = u32::from(dt.bit_len().unwrap_or(64).min(64));
            let full = if bits >= 64 {
                u128::from(u64::MAX)
            } else {
                (1u128 << bits) - 1
            };
            let hex = {
                let t = s.trim();
                t.starts_with("#x")
                    || t.starts_with("#X")
                    || t.starts_with("0x")
                    || t.starts_with("0X")
            };
            if dt.is_signed() {
                let (min, max) = (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1);
                if (min..=max).contains(&i) {
                    return Ok((Value::Int(i as i64), None));
                }
                // `#x80000000` for an INTEGER32: the bit pattern of the type.
                if hex && i > max && (i as u128) <= full {
                    let shift = 128 - bits;
                    let v = ((i as u128) << shift) as i128 >> shift;
                    return Ok((Value::Int(v as i64), None));
                }
                Err(format!("{s:?} is out of range for {dt}"))
            } else {
                // Unsigned values may be written as the negative two's complement (-1 for
                // 0xFFFF); accept that within the type's width.
                let i = if i < 0 && i >= -(1i128 << (bits - 1)) {
                    i + (1i128 << bits)
                } else {
                    i
                };
                if i < 0 || i as u128 > full {
                    return Err(format!("{s:?} is out of range for {dt}"));
                }
                Ok((Value::Uint(i as u64), None))
            }
        }
    }
}

/// An object with its entries resolved: comparable with [`ObjectDesc`].
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedObject {
    /// Index.
    pub index: u16,
    /// Name.
    pub name: String,
    /// VAR, ARRAY or RECORD (see [`Dictionary::resolve_object`] for the rule).
    pub code: ObjectCode,
    /// Entries in sub-index order as the data type lists them.
    pub entries: Vec<ResolvedEntry>,
    /// Values that were left out or read by a tolerance rule, each naming the entry.
    pub problems: Vec<EsiError>,
}

/// One entry of a [`ResolvedObject`].
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedEntry {
    /// Sub-index.
    pub sub: u8,
    /// Name (the sub-item's, the info sub-item's for array elements, the object's for a VAR).
    pub name: String,
    /// The type name as written.
    pub type_name: String,
    /// The data type, if the name is one [`DataType::parse`] knows.
    pub data_type: Option<DataType>,
    /// Size in bits.
    pub bit_len: u32,
    /// Access, PDO mappability, backup and settings flags.
    pub access: EntryAccess,
    /// Default value, if given.
    pub default: Option<Value>,
    /// Minimum, if given.
    pub min: Option<Value>,
    /// Maximum, if given.
    pub max: Option<Value>,
}

/// One difference between an ESI object and a profile's [`ObjectDesc`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjectDiff {
    /// Object index.
    pub index: u16,
    /// Sub-index, `None` for object-level differences.
    pub sub: Option<u8>,
    /// What differs: `code`, `entry`, `data type`, `bit length`, `access`, `default`, `min`,
    /// `max`.
    pub field: &'static str,
    /// The ESI's value, as text.
    pub esi: String,
    /// The profile's value, as text.
    pub profile: String,
}

impl fmt::Display for ObjectDiff {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.sub {
            Some(s) => write!(f, "0x{:04X}:{s:02X}", self.index)?,
            None => write!(f, "0x{:04X}", self.index)?,
        }
        write!(
            f,
            " {}: ESI {}, profile {}",
            self.field, self.esi, self.profile
        )
    }
}

/// The read/write and PDO bits of an access value (backup and settings are not compared).
fn comparable_access(a: EntryAccess) -> EntryAccess {
    a & (EntryAccess::R | EntryAccess::W | EntryAccess::RXPDO | EntryAccess::TXPDO)
}

fn access_text(a: EntryAccess) -> String {
    let mut s = String::new();
    for (state, r, w) in [
        ("P", EntryAccess::READ_PREOP, EntryAccess::WRITE_PREOP),
        ("S", EntryAccess::READ_SAFEOP, EntryAccess::WRITE_SAFEOP),
        ("O", EntryAccess::READ_OP, EntryAccess::WRITE_OP),
    ] {
        s.push_str(state);
        s.push(if a.contains(r) { 'r' } else { '-' });
        s.push(if a.contains(w) { 'w' } else { '-' });
        s.push(' ');
    }
    s.push_str(
        match (
            a.contains(EntryAccess::RXPDO),
            a.contains(EntryAccess::TXPDO),
        ) {
            (true, true) => "RT",
            (true, false) => "R",
            (false, true) => "T",
            (false, false) => "-",
        },
    );
    s
}

fn value_text(v: &Option<Value>) -> String {
    match v {
        Some(v) => v.to_string(),
        None => "none".into(),
    }
}

fn values_equal(a: &Value, b: &Value) -> bool {
    match (a.as_i128(), b.as_i128()) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

impl ResolvedObject {
    /// The entry with sub-index `sub`.
    pub fn entry(&self, sub: u8) -> Option<&ResolvedEntry> {
        self.entries.iter().find(|e| e.sub == sub)
    }

    /// Compare with a profile's description: object code, the set of sub-indices, and per
    /// entry the data type, bit length, access (read/write per state and PDO mappability) and
    /// the default, minimum and maximum where **both** sides state one. Names are not compared
    /// (manuals and ESI files word them differently).
    pub fn compare(&self, desc: &ObjectDesc) -> Vec<ObjectDiff> {
        let mut out = Vec::new();
        let diff = |sub, field, esi: String, profile: String| ObjectDiff {
            index: self.index,
            sub,
            field,
            esi,
            profile,
        };
        if self.code != desc.code {
            out.push(diff(
                None,
                "code",
                format!("{:?}", self.code),
                format!("{:?}", desc.code),
            ));
        }
        for e in &self.entries {
            let Some(d) = desc.entry(e.sub) else {
                out.push(diff(Some(e.sub), "entry", e.name.clone(), "missing".into()));
                continue;
            };
            if e.data_type != Some(d.data_type) {
                out.push(diff(
                    Some(e.sub),
                    "data type",
                    e.type_name.clone(),
                    d.data_type.to_string(),
                ));
            }
            if e.bit_len != u32::from(d.bit_len) {
                out.push(diff(
                    Some(e.sub),
                    "bit length",
                    e.bit_len.to_string(),
                    d.bit_len.to_string(),
                ));
            }
            if comparable_access(e.access) != comparable_access(d.access) {
                out.push(diff(
                    Some(e.sub),
                    "access",
                    access_text(e.access),
                    access_text(d.access),
                ));
            }
            for (field, ev, dv) in [
                ("default", &e.default, d.default.to_value()),
                ("min", &e.min, d.min.to_value()),
                ("max", &e.max, d.max.to_value()),
            ] {
                if let (Some(a), Some(b)) = (ev, &dv) {
                    if !values_equal(a, b) {
                        out.push(diff(Some(e.sub), field, value_text(ev), value_text(&dv)));
                    }
                }
            }
        }
        for d in desc.entries {
            if self.entry(d.sub).is_none() {
                out.push(diff(
                    Some(d.sub),
                    "entry",
                    "missing".into(),
                    d.name.to_string(),
                ));
            }
        }
        out
    }
}
