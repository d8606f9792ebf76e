use super::{ConstValue, DataType, ObjectAddress};

/// CANopen object code (CiA 301 table 42).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum ObjectCode {
    /// A single value.
    Var = 7,
    /// Several entries of one type; sub-index 0 holds the number of entries.
    Array = 8,
    /// Several entries of different types; sub-index 0 holds the highest sub-index.
    Record = 9,
}

impl ObjectCode {
    /// Decode an object code as carried in SDO information; `None` for codes this crate does not
    /// model (NULL, DOMAIN, DEFTYPE, DEFSTRUCT).
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            7 => Some(Self::Var),
            8 => Some(Self::Array),
            9 => Some(Self::Record),
            _ => None,
        }
    }

    /// The numeric code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// `VAR`, `ARRAY` or `RECORD`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Var => "VAR",
            Self::Array => "ARRAY",
            Self::Record => "RECORD",
        }
    }
}

bitflags::bitflags! {
    /// Entry access rights and flags, in the bit layout of the ETG.1000.6 SDO information
    /// "entry description" (ObjAccess): read and write per EtherCAT state, PDO mappability,
    /// backup and settings.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub struct EntryAccess: u16 {
        /// Readable in PRE-OP.
        const READ_PREOP = 0x0001;
        /// Readable in SAFE-OP.
        const READ_SAFEOP = 0x0002;
        /// Readable in OP.
        const READ_OP = 0x0004;
        /// Writable in PRE-OP.
        const WRITE_PREOP = 0x0008;
        /// Writable in SAFE-OP.
        const WRITE_SAFEOP = 0x0010;
        /// Writable in OP.
        const WRITE_OP = 0x0020;
        /// Mappable into an RxPDO (master → slave).
        const RXPDO = 0x0040;
        /// Mappable into a TxPDO (slave → master).
        const TXPDO = 0x0080;
        /// Included in a backup.
        const BACKUP = 0x0100;
        /// Used as a start-up setting.
        const SETTINGS = 0x0200;

        /// Readable in every state.
        const R = Self::READ_PREOP.bits() | Self::READ_SAFEOP.bits() | Self::READ_OP.bits();
        /// Writable in every state.
        const W = Self::WRITE_PREOP.bits() | Self::WRITE_SAFEOP.bits() | Self::WRITE_OP.bits();
        /// Read-only.
        const RO = Self::R.bits();
        /// Read-write in every state.
        const RW = Self::R.bits() | Self::W.bits();
        /// Readable always, writable only in PRE-OP.
        const RW_PREOP = Self::R.bits() | Self::WRITE_PREOP.bits();
        /// Write-only in every state.
        const WO = Self::W.bits();
    }
}

impl EntryAccess {
    /// Whether the entry can be read at all.
    pub const fn readable(self) -> bool {
        self.intersects(Self::R)
    }

    /// Whether the entry can be written in some state.
    pub const fn writable(self) -> bool {
        self.intersects(Self::W)
    }

    /// Short form as the IgH tool prints it per state: `rw`, `ro`, `wo`, or `--`.
    pub fn short(self) -> &'static str {
        match (self.readable(), self.writable()) {
            (true, true) => "rw",
            (true, false) => "ro",
            (false, true) => "wo",
            (false, false) => "--",
        }
    }
}

/// One entry (sub-index) of an object, as static data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EntryDesc {
    /// Sub-index.
    pub sub: u8,
    /// Name as the manual gives it.
    pub name: &'static str,
    /// Data type.
    pub data_type: DataType,
    /// Size in bits (strings: 8 × maximum length).
    pub bit_len: u16,
    /// Access rights and PDO mappability.
    pub access: EntryAccess,
    /// Default value.
    pub default: ConstValue,
    /// Smallest allowed value, if the manual states one.
    pub min: ConstValue,
    /// Largest allowed value, if the manual states one.
    pub max: ConstValue,
}

impl EntryDesc {
    /// An entry of a fixed-size type with no range and no default; refine it with the builder
    /// methods.
    pub const fn new(
        sub: u8,
        name: &'static str,
        data_type: DataType,
        access: EntryAccess,
    ) -> Self {
        let bit_len = match data_type.bit_len() {
            Some(b) => b,
            None => 0,
        };
        Self {
            sub,
            name,
            data_type,
            bit_len,
            access,
            default: ConstValue::None,
            min: ConstValue::None,
            max: ConstValue::None,
        }
    }

    /// With a default value.
    pub const fn default(mut self, v: ConstValue) -> Self {
        self.default = v;
        self
    }

    /// With an inclusive range.
    pub const fn range(mut self, min: ConstValue, max: ConstValue) -> Self {
        self.min = min;
        self.max = max;
        self
    }

    /// With an explicit size in bits (strings and domains).
    pub const fn bits(mut self, bit_len: u16) -> Self {
        self.bit_len = bit_len;
        self
    }
}

/// One object of a dictionary, as static data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectDesc {
    /// Index.
    pub index: u16,
    /// Name as the manual gives it.
    pub name: &'static str,
    /// VAR, ARRAY or RECORD.
    pub code: ObjectCode,
    /// The entries, in sub-index order. A VAR has exactly one entry, sub-index 0.
    pub entries: &'static [EntryDesc],
}

impl ObjectDesc {
    /// The entry with sub-index `sub`.
    pub fn entry(&self, sub: u8) -> Option<&'static EntryDesc> {
        let entries: &'static [EntryDesc] = self.entries;
        entries.iter().find(|e| e.sub == sub)
    }

    /// The address of one of its entries.
    pub const fn at(&self, sub: u8) -> ObjectAddress {
        ObjectAddress::new(self.index, sub)
    }
}

/// What SDO information tells about one object ("get object description", CiA 301 / ETG.1000.6
/// §5.6.3.5): one type for the slave that answers and the master that asks.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ObjectInfo {
    /// Index.
    pub index: u16,
    /// Data type index: the value type of a VAR, the element type of an ARRAY, the structure
    /// type of a RECORD (0 when none is defined).
    pub data_type: u16,
    /// Highest sub-index that exists (0 for a VAR).
    pub max_sub: u8,
    /// Object code as carried on the wire (7 VAR, 8 ARRAY, 9 RECORD; a device may report
    /// others).
    pub object_code: u8,
    /// Name.
    pub name: std::borrow::Cow<'static, str>,
}

impl ObjectInfo {
    /// The description of a static object: a VAR's value type, an ARRAY's element type (its
    /// first entry after sub-index 0), 0 for a RECORD (no structure type defined); the highest
    /// sub-index (0 for a VAR).
    pub fn describe(o: &ObjectDesc) -> Self {
        let max_sub = o.entries.iter().map(|e| e.sub).max().unwrap_or(0);
        let data_type = match o.code {
            ObjectCode::Var => o.entry(0).map_or(0, |e| e.data_type.code()),
            ObjectCode::Array => o
                .entries
                .iter()
                .find(|e| e.sub > 0)
                .map_or(0, |e| e.data_type.code()),
            ObjectCode::Record => 0,
        };
        Self {
            index: o.index,
            name: o.name.into(),
            object_code: o.code as u8,
            data_type,
            max_sub: if o.code == ObjectCode::Var {
                0
            } else {
                max_sub
            },
        }
    }

    /// The object code, if it is one this crate models.
    pub const fn code(&self) -> Option<ObjectCode> {
        ObjectCode::from_code(self.object_code)
    }
}
