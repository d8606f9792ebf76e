//! A read-only view over a static object-dictionary table, with lookup by index and by address,
//! and a consistency check for the tables the drive profiles declare.

use super::value::int_range;
use super::{ConstValue, DataType, EntryDesc, ObjectAddress, ObjectCode, ObjectDesc};

/// A view over a table of object descriptions: a drive profile's dictionary, served by the
/// emulated drive and used by the master and the CLI to infer types and check PDO mappings.
///
/// Lookups use a binary search when the table is sorted by index (checked once, in
/// [`Dictionary::new`]) and a linear scan otherwise. Nothing allocates.
#[derive(Debug, Clone, Copy)]
pub struct Dictionary<'a> {
    objects: &'a [ObjectDesc],
    sorted: bool,
}

impl<'a> Dictionary<'a> {
    /// A view over `objects`. Usable in `const` items.
    pub const fn new(objects: &'a [ObjectDesc]) -> Self {
        let mut sorted = true;
        let mut i = 1;
        while i < objects.len() {
            if objects[i - 1].index >= objects[i].index {
                sorted = false;
            }
            i += 1;
        }
        Self { objects, sorted }
    }

    /// The underlying table.
    pub const fn objects(&self) -> &'a [ObjectDesc] {
        self.objects
    }

    /// Number of objects.
    pub const fn len(&self) -> usize {
        self.objects.len()
    }

    /// Whether the table has no objects.
    pub const fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    /// Whether the table is strictly sorted by index (lookups are then binary searches).
    pub const fn is_sorted(&self) -> bool {
        self.sorted
    }

    /// The object at `index`.
    pub fn object(&self, index: u16) -> Option<&'a ObjectDesc> {
        if self.sorted {
            let pos = self
                .objects
                .binary_search_by_key(&index, |o| o.index)
                .ok()?;
            self.objects.get(pos)
        } else {
            self.objects.iter().find(|o| o.index == index)
        }
    }

    /// The entry at `addr`.
    pub fn entry(&self, addr: ObjectAddress) -> Option<&'static EntryDesc> {
        self.object(addr.index)?.entry(addr.sub)
    }

    /// The object and entry at `addr`.
    pub fn lookup(&self, addr: ObjectAddress) -> Option<(&'a ObjectDesc, &'static EntryDesc)> {
        let object = self.object(addr.index)?;
        Some((object, object.entry(addr.sub)?))
    }

    /// The data type of the entry at `addr` (what the CLI uses when no `--type` is given).
    pub fn data_type(&self, addr: ObjectAddress) -> Option<DataType> {
        self.entry(addr).map(|e| e.data_type)
    }

    /// The first object whose name equals `name`, ignoring ASCII case.
    pub fn find_by_name(&self, name: &str) -> Option<&'a ObjectDesc> {
        self.objects
            .iter()
            .find(|o| o.name.eq_ignore_ascii_case(name.trim()))
    }

    /// The objects, in table order.
    pub fn iter(&self) -> core::slice::Iter<'a, ObjectDesc> {
        self.objects.iter()
    }

    /// Every entry with its address, in table order.
    pub fn entries(&self) -> impl Iterator<Item = (ObjectAddress, &'static EntryDesc)> + 'a {
        self.objects.iter().flat_map(|o| {
            let entries: &'static [EntryDesc] = o.entries;
            let index = o.index;
            entries
                .iter()
                .map(move |e| (ObjectAddress::new(index, e.sub), e))
        })
    }

    /// Check the table for mistakes a profile author can make: duplicate objects or
    /// sub-indices, a VAR that is not exactly sub-index 0, an ARRAY/RECORD without its
    /// UNSIGNED8 sub-index 0, a bit length that disagrees with the data type, and a default,
    /// minimum or maximum that does not fit the type or the stated range.
    pub fn check(&self) -> Result<(), DictionaryError> {
        match self.problems().into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Every problem [`Dictionary::check`] looks for, in table order.
    pub fn problems(&self) -> Vec<DictionaryError> {
        let mut out = Vec::new();
        let mut indices: Vec<u16> = self.objects.iter().map(|o| o.index).collect();
        indices.sort_unstable();
        for w in indices.windows(2) {
            if let [a, b] = w {
                if a == b && out.last() != Some(&DictionaryError::DuplicateObject { index: *a }) {
                    out.push(DictionaryError::DuplicateObject { index: *a });
                }
            }
        }
        for o in self.objects {
            check_object(o, &mut out);
        }
        out
    }
}

impl<'a> From<&'a [ObjectDesc]> for Dictionary<'a> {
    fn from(objects: &'a [ObjectDesc]) -> Self {
        Self::new(objects)
    }
}

impl<'a> IntoIterator for &Dictionary<'a> {
    type Item = &'a ObjectDesc;
    type IntoIter = core::slice::Iter<'a, ObjectDesc>;

    fn into_iter(self) -> Self::IntoIter {
        self.objects.iter()
    }
}

fn check_object(o: &ObjectDesc, out: &mut Vec<DictionaryError>) {
    for (i, e) in o.entries.iter().enumerate() {
        if o.entries.iter().take(i).any(|p| p.sub == e.sub) {
            out.push(DictionaryError::DuplicateEntry { addr: o.at(e.sub) });
        }
    }
    match o.code {
        ObjectCode::Var => {
            if o.entries.len() != 1 || o.entry(0).is_none() {
                out.push(DictionaryError::VarShape {
                    index: o.index,
                    entries: o.entries.len(),
                });
            }
        }
        ObjectCode::Array | ObjectCode::Record => match o.entry(0) {
            Some(e) if e.data_type == DataType::Unsigned8 => {}
            _ => out.push(DictionaryError::MissingCount {
                index: o.index,
                code: o.code,
            }),
        },
    }
    for e in o.entries {
        check_entry(o.at(e.sub), e, out);
    }
}

fn check_entry(addr: ObjectAddress, e: &EntryDesc, out: &mut Vec<DictionaryError>) {
    let dt = e.data_type;
    if let Some(bits) = dt.bit_len() {
        if bits != e.bit_len {
            out.push(DictionaryError::BitLength {
                addr,
                data_type: dt,
                bit_len: e.bit_len,
            });
        }
    }
    for (which, v) in [
        ("default", e.default),
        ("minimum", e.min),
        ("maximum", e.max),
    ] {
        let fits_kind = match v {
            ConstValue::None => true,
            ConstValue::Int(_) | ConstValue::Uint(_) => int_range(dt).is_some(),
            ConstValue::Real(_) => dt.is_real(),
            ConstValue::Str(_) => dt.is_string(),
            ConstValue::Bytes(_) => matches!(dt, DataType::OctetString | DataType::Domain),
        };
        if !fits_kind {
            out.push(DictionaryError::ValueKind {
                addr,
                which,
                data_type: dt,
            });
            continue;
        }
        if let (Some(value), Some((min, max))) = (v.as_i128(), int_range(dt)) {
            if value < min || value > max {
                out.push(DictionaryError::OutOfRange {
                    addr,
                    which,
                    value,
                    min,
                    max,
                    bound: dt.name(),
                });
            }
        }
    }
    let (min, max) = (e.min.as_i128(), e.max.as_i128());
    if let (Some(min), Some(max)) = (min, max) {
        if min > max {
            out.push(DictionaryError::EmptyRange { addr, min, max });
        }
    }
    if let Some(d) = e.default.as_i128() {
        let below = min.is_some_and(|m| d < m);
        let above = max.is_some_and(|m| d > m);
        if below || above {
            out.push(DictionaryError::OutOfRange {
                addr,
                which: "default",
                value: d,
                min: min.unwrap_or(i128::MIN),
                max: max.unwrap_or(i128::MAX),
                bound: "the entry's stated range",
            });
        }
    }
}

/// A mistake in a dictionary table, found by [`Dictionary::check`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DictionaryError {
    /// Two objects share an index.
    #[error("object 0x{index:04X} is declared more than once")]
    DuplicateObject {
        /// The index.
        index: u16,
    },
    /// Two entries of one object share a sub-index.
    #[error("entry {addr} is declared more than once")]
    DuplicateEntry {
        /// The address.
        addr: ObjectAddress,
    },
    /// A VAR object must have exactly one entry, sub-index 0.
    #[error(
        "object 0x{index:04X} is a VAR but has {entries} entries (it needs exactly sub-index 0)"
    )]
    VarShape {
        /// The index.
        index: u16,
        /// How many entries it has.
        entries: usize,
    },
    /// An ARRAY or RECORD needs sub-index 0 of type UNSIGNED8.
    #[error("object 0x{index:04X} is {} but has no UNSIGNED8 sub-index 0", code.name())]
    MissingCount {
        /// The index.
        index: u16,
        /// Its object code.
        code: ObjectCode,
    },
    /// The declared bit length disagrees with the data type.
    #[error("entry {addr} is {data_type} ({} bits) but declares {bit_len} bits", data_type.bit_len().unwrap_or(0))]
    BitLength {
        /// The address.
        addr: ObjectAddress,
        /// Its data type.
        data_type: DataType,
        /// The declared length.
        bit_len: u16,
    },
    /// A default, minimum or maximum of the wrong kind (e.g. a string for an integer).
    #[error("the {which} of {addr} is not a {data_type} value")]
    ValueKind {
        /// The address.
        addr: ObjectAddress,
        /// `default`, `minimum` or `maximum`.
        which: &'static str,
        /// The entry's data type.
        data_type: DataType,
    },
    /// A value outside its type's range or outside the entry's stated range.
    #[error("the {which} of {addr} is {value}, outside {bound} ({min}..={max})")]
    OutOfRange {
        /// The address.
        addr: ObjectAddress,
        /// `default`, `minimum` or `maximum`.
        which: &'static str,
        /// The value.
        value: i128,
        /// Lower bound.
        min: i128,
        /// Upper bound.
        max: i128,
        /// What the bounds are: a data-type name or "the entry's stated range".
        bound: &'static str,
    },
    /// The stated minimum is above the stated maximum.
    #[error("entry {addr} has minimum {min} above maximum {max}")]
    EmptyRange {
        /// The address.
        addr: ObjectAddress,
        /// Stated minimum.
        min: i128,
        /// Stated maximum.
        max: i128,
    },
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::od::EntryAccess;

    const CW: &[EntryDesc] = &[EntryDesc::new(
        0,
        "Controlword",
        DataType::Unsigned16,
        EntryAccess::RW.union(EntryAccess::RXPDO),
    )];
    const SW: &[EntryDesc] = &[EntryDesc::new(
        0,
        "Statusword",
        DataType::Unsigned16,
        EntryAccess::RO.union(EntryAccess::TXPDO),
    )];
    const MAP: &[EntryDesc] = &[
        EntryDesc::new(
            0,
            "Number of entries",
            DataType::Unsigned8,
            EntryAccess::RW_PREOP,
        )
        .range(ConstValue::Uint(0), ConstValue::Uint(8)),
        EntryDesc::new(1, "Entry 1", DataType::Unsigned32, EntryAccess::RW_PREOP),
    ];
    const OBJECTS: &[ObjectDesc] = &[
        ObjectDesc {
            index: 0x1600,
            name: "RxPDO mapping 1",
            code: ObjectCode::Record,
            entries: MAP,
        },
        ObjectDesc {
            index: 0x6040,
            name: "Controlword",
            code: ObjectCode::Var,
            entries: CW,
        },
        ObjectDesc {
            index: 0x6041,
            name: "Statusword",
            code: ObjectCode::Var,
            entries: SW,
        },
    ];
    const DICT: Dictionary<'static> = Dictionary::new(OBJECTS);

    #[test]
    fn lookup_by_index_address_and_name() {
        assert!(DICT.is_sorted());
        assert_eq!(DICT.len(), 3);
        assert_eq!(DICT.object(0x6041).map(|o| o.name), Some("Statusword"));
        assert!(DICT.object(0x6042).is_none());
        assert_eq!(
            DICT.data_type(ObjectAddress::new(0x1600, 1)),
            Some(DataType::Unsigned32)
        );
        assert!(DICT.entry(ObjectAddress::new(0x1600, 2)).is_none());
        assert!(DICT.entry(ObjectAddress::new(0x6040, 1)).is_none());
        assert_eq!(
            DICT.find_by_name("controlword").map(|o| o.index),
            Some(0x6040)
        );
        assert_eq!(DICT.entries().count(), 4);
        DICT.check().unwrap();
    }

    #[test]
    fn unsorted_tables_still_look_up() {
        let reversed = [OBJECTS[2], OBJECTS[1], OBJECTS[0]];
        let d = Dictionary::new(&reversed);
        assert!(!d.is_sorted());
        assert_eq!(d.object(0x1600).map(|o| o.index), Some(0x1600));
        assert_eq!(d.object(0x6040).map(|o| o.index), Some(0x6040));
        d.check().unwrap();
    }

    #[test]
    fn check_names_each_mistake() {
        const BAD_BITS: &[EntryDesc] =
            &[EntryDesc::new(0, "x", DataType::Unsigned16, EntryAccess::RO).bits(8)];
        const BAD_DEFAULT: &[EntryDesc] =
            &[EntryDesc::new(0, "x", DataType::Unsigned8, EntryAccess::RO)
                .default(ConstValue::Uint(300))];
        const OUTSIDE: &[EntryDesc] =
            &[EntryDesc::new(0, "x", DataType::Integer16, EntryAccess::RW)
                .default(ConstValue::Int(-5))
                .range(ConstValue::Int(0), ConstValue::Int(10))];
        const WRONG_KIND: &[EntryDesc] =
            &[EntryDesc::new(0, "x", DataType::Unsigned8, EntryAccess::RO)
                .default(ConstValue::Str("no"))];
        let var = |index, entries| ObjectDesc {
            index,
            name: "x",
            code: ObjectCode::Var,
            entries,
        };
        let objects = [
            var(0x2000, BAD_BITS),
            var(0x2001, BAD_DEFAULT),
            var(0x2002, OUTSIDE),
            var(0x2003, WRONG_KIND),
            var(0x2003, CW),
            var(0x2004, MAP),
            ObjectDesc {
                index: 0x2005,
                name: "x",
                code: ObjectCode::Array,
                entries: CW,
            },
        ];
        let problems = Dictionary::new(&objects).problems();
        let text: Vec<String> = problems.iter().map(ToString::to_string).collect();
        let expect = [
            "object 0x2003 is declared more than once",
            "entry 0x2000:00 is UNSIGNED16 (16 bits) but declares 8 bits",
            "the default of 0x2001:00 is 300, outside UNSIGNED8 (0..=255)",
            "the default of 0x2002:00 is -5, outside the entry's stated range (0..=10)",
            "the default of 0x2003:00 is not a UNSIGNED8 value",
            "object 0x2004 is a VAR but has 2 entries (it needs exactly sub-index 0)",
            "object 0x2005 is ARRAY but has no UNSIGNED8 sub-index 0",
        ];
        for e in expect {
            assert!(text.iter().any(|t| t == e), "missing {e:?} in {text:#?}");
        }
        assert_eq!(text.len(), expect.len(), "{text:#?}");
    }
}
