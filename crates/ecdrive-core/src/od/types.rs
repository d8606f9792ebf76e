use core::fmt;

/// A CANopen / CoE basic data type (CiA 301 table 44, ETG.1000.6 table 64 for the BITn types).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u16)]
pub enum DataType {
    /// BOOLEAN (1 bit in PDOs, 1 byte over SDO).
    Boolean = 0x0001,
    /// INTEGER8.
    Integer8 = 0x0002,
    /// INTEGER16.
    Integer16 = 0x0003,
    /// INTEGER32.
    Integer32 = 0x0004,
    /// UNSIGNED8.
    Unsigned8 = 0x0005,
    /// UNSIGNED16.
    Unsigned16 = 0x0006,
    /// UNSIGNED32.
    Unsigned32 = 0x0007,
    /// REAL32.
    Real32 = 0x0008,
    /// VISIBLE_STRING.
    VisibleString = 0x0009,
    /// OCTET_STRING.
    OctetString = 0x000A,
    /// UNICODE_STRING.
    UnicodeString = 0x000B,
    /// TIME_OF_DAY.
    TimeOfDay = 0x000C,
    /// TIME_DIFFERENCE.
    TimeDifference = 0x000D,
    /// DOMAIN.
    Domain = 0x000F,
    /// INTEGER24.
    Integer24 = 0x0010,
    /// REAL64.
    Real64 = 0x0011,
    /// INTEGER64.
    Integer64 = 0x0015,
    /// UNSIGNED24.
    Unsigned24 = 0x0016,
    /// INTEGER40.
    Integer40 = 0x0012,
    /// INTEGER48.
    Integer48 = 0x0013,
    /// INTEGER56.
    Integer56 = 0x0014,
    /// UNSIGNED40.
    Unsigned40 = 0x0018,
    /// UNSIGNED48.
    Unsigned48 = 0x0019,
    /// UNSIGNED56.
    Unsigned56 = 0x001A,
    /// UNSIGNED64.
    Unsigned64 = 0x001B,
    /// BYTE (EtherCAT, 8-bit bit string).
    Byte = 0x001E,
    /// WORD (EtherCAT, 16-bit bit string).
    Word = 0x001F,
    /// DWORD (EtherCAT, 32-bit bit string).
    Dword = 0x0020,
    /// BITARR8 (EtherCAT).
    BitArr8 = 0x002D,
    /// BITARR16 (EtherCAT).
    BitArr16 = 0x002E,
    /// BITARR32 (EtherCAT).
    BitArr32 = 0x002F,
    /// BIT1 (EtherCAT).
    Bit1 = 0x0030,
    /// BIT2 (EtherCAT).
    Bit2 = 0x0031,
    /// BIT3 (EtherCAT).
    Bit3 = 0x0032,
    /// BIT4 (EtherCAT).
    Bit4 = 0x0033,
    /// BIT5 (EtherCAT).
    Bit5 = 0x0034,
    /// BIT6 (EtherCAT).
    Bit6 = 0x0035,
    /// BIT7 (EtherCAT).
    Bit7 = 0x0036,
    /// BIT8 (EtherCAT).
    Bit8 = 0x0037,
    /// BIT9 (EtherCAT).
    Bit9 = 0x0038,
    /// BIT10 (EtherCAT).
    Bit10 = 0x0039,
    /// BIT11 (EtherCAT).
    Bit11 = 0x003A,
    /// BIT12 (EtherCAT).
    Bit12 = 0x003B,
    /// BIT13 (EtherCAT).
    Bit13 = 0x003C,
    /// BIT14 (EtherCAT).
    Bit14 = 0x003D,
    /// BIT15 (EtherCAT).
    Bit15 = 0x003E,
    /// BIT16 (EtherCAT).
    Bit16 = 0x003F,
}

impl DataType {
    /// Every data type this crate models, in code order.
    pub const ALL: &'static [DataType] = &[
        Self::Boolean,
        Self::Integer8,
        Self::Integer16,
        Self::Integer32,
        Self::Unsigned8,
        Self::Unsigned16,
        Self::Unsigned32,
        Self::Real32,
        Self::VisibleString,
        Self::OctetString,
        Self::UnicodeString,
        Self::TimeOfDay,
        Self::TimeDifference,
        Self::Domain,
        Self::Integer24,
        Self::Real64,
        Self::Integer40,
        Self::Integer48,
        Self::Integer56,
        Self::Integer64,
        Self::Unsigned24,
        Self::Unsigned40,
        Self::Unsigned48,
        Self::Unsigned56,
        Self::Unsigned64,
        Self::Byte,
        Self::Word,
        Self::Dword,
        Self::BitArr8,
        Self::BitArr16,
        Self::BitArr32,
        Self::Bit1,
        Self::Bit2,
        Self::Bit3,
        Self::Bit4,
        Self::Bit5,
        Self::Bit6,
        Self::Bit7,
        Self::Bit8,
        Self::Bit9,
        Self::Bit10,
        Self::Bit11,
        Self::Bit12,
        Self::Bit13,
        Self::Bit14,
        Self::Bit15,
        Self::Bit16,
    ];

    /// Decode a data-type index as carried in SDO information and the SII. `None` for types this
    /// crate does not model (structured and vendor types).
    pub const fn from_code(code: u16) -> Option<Self> {
        let mut i = 0;
        while i < Self::ALL.len() {
            if Self::ALL[i] as u16 == code {
                return Some(Self::ALL[i]);
            }
            i += 1;
        }
        None
    }

    /// The numeric code.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// Size in bits of a fixed-size type; `None` for strings and domains, whose size is the
    /// entry's.
    pub const fn bit_len(self) -> Option<u16> {
        Some(match self {
            Self::Boolean | Self::Bit1 => 1,
            Self::Bit2 => 2,
            Self::Bit3 => 3,
            Self::Bit4 => 4,
            Self::Bit5 => 5,
            Self::Bit6 => 6,
            Self::Bit7 => 7,
            Self::Bit8 | Self::Integer8 | Self::Unsigned8 | Self::Byte | Self::BitArr8 => 8,
            Self::Bit9 => 9,
            Self::Bit10 => 10,
            Self::Bit11 => 11,
            Self::Bit12 => 12,
            Self::Bit13 => 13,
            Self::Bit14 => 14,
            Self::Bit15 => 15,
            Self::Bit16 | Self::Integer16 | Self::Unsigned16 | Self::Word | Self::BitArr16 => 16,
            Self::Integer24 | Self::Unsigned24 => 24,
            Self::Integer32 | Self::Unsigned32 | Self::Real32 | Self::Dword | Self::BitArr32 => 32,
            Self::Integer40 | Self::Unsigned40 => 40,
            Self::Integer48 | Self::Unsigned48 | Self::TimeOfDay | Self::TimeDifference => 48,
            Self::Integer56 | Self::Unsigned56 => 56,
            Self::Integer64 | Self::Unsigned64 | Self::Real64 => 64,
            Self::VisibleString | Self::OctetString | Self::UnicodeString | Self::Domain => {
                return None;
            }
        })
    }

    /// Whether values of this type are signed integers.
    pub const fn is_signed(self) -> bool {
        matches!(
            self,
            Self::Integer8
                | Self::Integer16
                | Self::Integer24
                | Self::Integer32
                | Self::Integer40
                | Self::Integer48
                | Self::Integer56
                | Self::Integer64
        )
    }

    /// Whether values of this type are unsigned integers, booleans or bit strings.
    pub const fn is_unsigned(self) -> bool {
        matches!(
            self,
            Self::Boolean
                | Self::Unsigned8
                | Self::Unsigned16
                | Self::Unsigned24
                | Self::Unsigned32
                | Self::Unsigned40
                | Self::Unsigned48
                | Self::Unsigned56
                | Self::Unsigned64
                | Self::Byte
                | Self::Word
                | Self::Dword
                | Self::BitArr8
                | Self::BitArr16
                | Self::BitArr32
                | Self::Bit1
                | Self::Bit2
                | Self::Bit3
                | Self::Bit4
                | Self::Bit5
                | Self::Bit6
                | Self::Bit7
                | Self::Bit8
                | Self::Bit9
                | Self::Bit10
                | Self::Bit11
                | Self::Bit12
                | Self::Bit13
                | Self::Bit14
                | Self::Bit15
                | Self::Bit16
        )
    }

    /// Whether values are IEEE floats.
    pub const fn is_real(self) -> bool {
        matches!(self, Self::Real32 | Self::Real64)
    }

    /// Whether values are byte strings of entry-defined length.
    pub const fn is_string(self) -> bool {
        matches!(
            self,
            Self::VisibleString | Self::OctetString | Self::UnicodeString | Self::Domain
        )
    }

    /// The CiA 301 / ETG.1000.6 name, e.g. `UNSIGNED16`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Boolean => "BOOLEAN",
            Self::Integer8 => "INTEGER8",
            Self::Integer16 => "INTEGER16",
            Self::Integer24 => "INTEGER24",
            Self::Integer32 => "INTEGER32",
            Self::Integer40 => "INTEGER40",
            Self::Integer48 => "INTEGER48",
            Self::Integer56 => "INTEGER56",
            Self::Integer64 => "INTEGER64",
            Self::Unsigned8 => "UNSIGNED8",
            Self::Unsigned16 => "UNSIGNED16",
            Self::Unsigned24 => "UNSIGNED24",
            Self::Unsigned32 => "UNSIGNED32",
            Self::Unsigned40 => "UNSIGNED40",
            Self::Unsigned48 => "UNSIGNED48",
            Self::Unsigned56 => "UNSIGNED56",
            Self::Unsigned64 => "UNSIGNED64",
            Self::Real32 => "REAL32",
            Self::Real64 => "REAL64",
            Self::VisibleString => "VISIBLE_STRING",
            Self::OctetString => "OCTET_STRING",
            Self::UnicodeString => "UNICODE_STRING",
            Self::TimeOfDay => "TIME_OF_DAY",
            Self::TimeDifference => "TIME_DIFFERENCE",
            Self::Domain => "DOMAIN",
            Self::Byte => "BYTE",
            Self::Word => "WORD",
            Self::Dword => "DWORD",
            Self::BitArr8 => "BITARR8",
            Self::BitArr16 => "BITARR16",
            Self::BitArr32 => "BITARR32",
            Self::Bit1 => "BIT1",
            Self::Bit2 => "BIT2",
            Self::Bit3 => "BIT3",
            Self::Bit4 => "BIT4",
            Self::Bit5 => "BIT5",
            Self::Bit6 => "BIT6",
            Self::Bit7 => "BIT7",
            Self::Bit8 => "BIT8",
            Self::Bit9 => "BIT9",
            Self::Bit10 => "BIT10",
            Self::Bit11 => "BIT11",
            Self::Bit12 => "BIT12",
            Self::Bit13 => "BIT13",
            Self::Bit14 => "BIT14",
            Self::Bit15 => "BIT15",
            Self::Bit16 => "BIT16",
        }
    }

    /// The name ESI files use (IEC 61131 where one exists), e.g. `UINT`. Strings are written
    /// `STRING(n)` in ESI; this returns the bare `STRING`.
    pub const fn esi_name(self) -> &'static str {
        match self {
            Self::Boolean => "BOOL",
            Self::Integer8 => "SINT",
            Self::Integer16 => "INT",
            Self::Integer24 => "INT24",
            Self::Integer32 => "DINT",
            Self::Integer40 => "INT40",
            Self::Integer48 => "INT48",
            Self::Integer56 => "INT56",
            Self::Integer64 => "LINT",
            Self::Unsigned8 => "USINT",
            Self::Unsigned16 => "UINT",
            Self::Unsigned24 => "UINT24",
            Self::Unsigned32 => "UDINT",
            Self::Unsigned40 => "UINT40",
            Self::Unsigned48 => "UINT48",
            Self::Unsigned56 => "UINT56",
            Self::Unsigned64 => "ULINT",
            Self::Real32 => "REAL",
            Self::Real64 => "LREAL",
            Self::VisibleString => "STRING",
            Self::OctetString => "OCTET_STRING",
            Self::UnicodeString => "UNICODE_STRING",
            Self::TimeOfDay => "TIME_OF_DAY",
            Self::TimeDifference => "TIME_DIFFERENCE",
            Self::Domain => "DOMAIN",
            // The remaining EtherCAT bit-string types are spelled the same in ESI.
            other => other.name(),
        }
    }

    /// Parse a type name as ESI files, the CLI (`--type`) and CiA 301 write it: IEC names
    /// (`UINT`, `DINT`, `STRING(20)`), EtherCAT names (`BYTE`, `WORD`, `DWORD`, `BITARR8`,
    /// `BIT3`), CiA names (`UNSIGNED16`) and the short forms `u8`…`u64`, `i8`…`i64`, `f32`,
    /// `f64`, `bool`, `string`. Case-insensitive.
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_uppercase();
        let base = match n.find('(') {
            Some(p) => n.get(..p).unwrap_or_default(),
            None => n.as_str(),
        };
        Some(match base {
            "BOOL" | "BOOLEAN" => Self::Boolean,
            "SINT" | "INTEGER8" | "I8" => Self::Integer8,
            "INT" | "INTEGER16" | "I16" => Self::Integer16,
            "INT24" | "INTEGER24" => Self::Integer24,
            "DINT" | "INTEGER32" | "I32" => Self::Integer32,
            "INT40" | "INTEGER40" => Self::Integer40,
            "INT48" | "INTEGER48" => Self::Integer48,
            "INT56" | "INTEGER56" => Self::Integer56,
            "LINT" | "INTEGER64" | "I64" => Self::Integer64,
            "USINT" | "UNSIGNED8" | "U8" => Self::Unsigned8,
            "UINT" | "UNSIGNED16" | "U16" => Self::Unsigned16,
            "UINT24" | "UNSIGNED24" => Self::Unsigned24,
            "UDINT" | "UNSIGNED32" | "U32" => Self::Unsigned32,
            "UINT40" | "UNSIGNED40" => Self::Unsigned40,
            "UINT48" | "UNSIGNED48" => Self::Unsigned48,
            "UINT56" | "UNSIGNED56" => Self::Unsigned56,
            "ULINT" | "LWORD" | "UNSIGNED64" | "U64" => Self::Unsigned64,
            "REAL" | "REAL32" | "F32" => Self::Real32,
            "LREAL" | "REAL64" | "F64" => Self::Real64,
            "STRING" | "VISIBLE_STRING" => Self::VisibleString,
            "OCTET_STRING" | "OCTETS" | "BYTES" => Self::OctetString,
            "UNICODE_STRING" => Self::UnicodeString,
            "TIME_OF_DAY" => Self::TimeOfDay,
            "TIME_DIFFERENCE" => Self::TimeDifference,
            "DOMAIN" => Self::Domain,
            "BYTE" => Self::Byte,
            "WORD" => Self::Word,
            "DWORD" => Self::Dword,
            "BITARR8" => Self::BitArr8,
            "BITARR16" => Self::BitArr16,
            "BITARR32" => Self::BitArr32,
            "BIT1" => Self::Bit1,
            "BIT2" => Self::Bit2,
            "BIT3" => Self::Bit3,
            "BIT4" => Self::Bit4,
            "BIT5" => Self::Bit5,
            "BIT6" => Self::Bit6,
            "BIT7" => Self::Bit7,
            "BIT8" => Self::Bit8,
            "BIT9" => Self::Bit9,
            "BIT10" => Self::Bit10,
            "BIT11" => Self::Bit11,
            "BIT12" => Self::Bit12,
            "BIT13" => Self::Bit13,
            "BIT14" => Self::Bit14,
            "BIT15" => Self::Bit15,
            "BIT16" => Self::Bit16,
            _ => return None,
        })
    }
}

impl fmt::Display for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip() {
        let mut seen = 0;
        for code in 0..=0x100u16 {
            if let Some(t) = DataType::from_code(code) {
                seen += 1;
                assert_eq!(t.code(), code);
                assert_eq!(DataType::parse(t.name()), Some(t), "{t}");
                assert_eq!(DataType::parse(t.esi_name()), Some(t), "{t}");
                assert!(
                    t.is_signed() as u8
                        + t.is_unsigned() as u8
                        + t.is_real() as u8
                        + t.is_string() as u8
                        <= 1,
                    "{t} has one kind at most"
                );
            }
        }
        assert_eq!(seen, DataType::ALL.len());
        for w in DataType::ALL.windows(2) {
            assert!(w[0].code() < w[1].code(), "{} before {}", w[0], w[1]);
        }
        assert_eq!(DataType::parse("STRING(20)"), Some(DataType::VisibleString));
        assert_eq!(DataType::parse("u16"), Some(DataType::Unsigned16));
        assert_eq!(DataType::parse("nonsense"), None);
    }

    #[test]
    fn ethercat_bit_string_types_keep_their_own_codes() {
        // ETG.1000.6: BYTE 0x1E, WORD 0x1F, DWORD 0x20, BITARR8..32 0x2D..0x2F, BIT9..16 0x38..0x3F.
        assert_eq!(DataType::parse("BYTE").map(DataType::code), Some(0x1E));
        assert_eq!(DataType::parse("DWORD").map(DataType::code), Some(0x20));
        assert_eq!(DataType::parse("BITARR8").map(DataType::code), Some(0x2D));
        assert_eq!(DataType::parse("BIT16").map(DataType::code), Some(0x3F));
        assert_eq!(DataType::BitArr16.bit_len(), Some(16));
        assert_eq!(DataType::Bit11.bit_len(), Some(11));
        assert_eq!(DataType::Unsigned40.bit_len(), Some(40));
        assert!(DataType::Integer56.is_signed());
    }
}
