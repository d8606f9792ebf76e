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
    /// UNSIGNED64.
    Unsigned64 = 0x001B,
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
}

impl DataType {
    /// Decode a data-type index as carried in SDO information and the SII. `None` for types this
    /// crate does not model (structured and vendor types).
    pub const fn from_code(code: u16) -> Option<Self> {
        Some(match code {
            0x0001 => Self::Boolean,
            0x0002 => Self::Integer8,
            0x0003 => Self::Integer16,
            0x0004 => Self::Integer32,
            0x0005 => Self::Unsigned8,
            0x0006 => Self::Unsigned16,
            0x0007 => Self::Unsigned32,
            0x0008 => Self::Real32,
            0x0009 => Self::VisibleString,
            0x000A => Self::OctetString,
            0x000B => Self::UnicodeString,
            0x000C => Self::TimeOfDay,
            0x000D => Self::TimeDifference,
            0x000F => Self::Domain,
            0x0010 => Self::Integer24,
            0x0011 => Self::Real64,
            0x0015 => Self::Integer64,
            0x0016 => Self::Unsigned24,
            0x001B => Self::Unsigned64,
            0x0030 => Self::Bit1,
            0x0031 => Self::Bit2,
            0x0032 => Self::Bit3,
            0x0033 => Self::Bit4,
            0x0034 => Self::Bit5,
            0x0035 => Self::Bit6,
            0x0036 => Self::Bit7,
            0x0037 => Self::Bit8,
            _ => return None,
        })
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
            Self::Bit8 | Self::Integer8 | Self::Unsigned8 => 8,
            Self::Integer16 | Self::Unsigned16 => 16,
            Self::Integer24 | Self::Unsigned24 => 24,
            Self::Integer32 | Self::Unsigned32 | Self::Real32 => 32,
            Self::TimeOfDay | Self::TimeDifference => 48,
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
            Self::Integer8 | Self::Integer16 | Self::Integer24 | Self::Integer32 | Self::Integer64
        )
    }

    /// Whether values of this type are unsigned integers, booleans or bit fields.
    pub const fn is_unsigned(self) -> bool {
        matches!(
            self,
            Self::Boolean
                | Self::Unsigned8
                | Self::Unsigned16
                | Self::Unsigned24
                | Self::Unsigned32
                | Self::Unsigned64
                | Self::Bit1
                | Self::Bit2
                | Self::Bit3
                | Self::Bit4
                | Self::Bit5
                | Self::Bit6
                | Self::Bit7
                | Self::Bit8
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

    /// The CiA 301 name, e.g. `UNSIGNED16`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Boolean => "BOOLEAN",
            Self::Integer8 => "INTEGER8",
            Self::Integer16 => "INTEGER16",
            Self::Integer24 => "INTEGER24",
            Self::Integer32 => "INTEGER32",
            Self::Integer64 => "INTEGER64",
            Self::Unsigned8 => "UNSIGNED8",
            Self::Unsigned16 => "UNSIGNED16",
            Self::Unsigned24 => "UNSIGNED24",
            Self::Unsigned32 => "UNSIGNED32",
            Self::Unsigned64 => "UNSIGNED64",
            Self::Real32 => "REAL32",
            Self::Real64 => "REAL64",
            Self::VisibleString => "VISIBLE_STRING",
            Self::OctetString => "OCTET_STRING",
            Self::UnicodeString => "UNICODE_STRING",
            Self::TimeOfDay => "TIME_OF_DAY",
            Self::TimeDifference => "TIME_DIFFERENCE",
            Self::Domain => "DOMAIN",
            Self::Bit1 => "BIT1",
            Self::Bit2 => "BIT2",
            Self::Bit3 => "BIT3",
            Self::Bit4 => "BIT4",
            Self::Bit5 => "BIT5",
            Self::Bit6 => "BIT6",
            Self::Bit7 => "BIT7",
            Self::Bit8 => "BIT8",
        }
    }

    /// The IEC 61131 name ESI files use, e.g. `UINT`. Strings are written `STRING(n)` in ESI;
    /// this returns the bare `STRING`.
    pub const fn esi_name(self) -> &'static str {
        match self {
            Self::Boolean => "BOOL",
            Self::Integer8 => "SINT",
            Self::Integer16 => "INT",
            Self::Integer24 => "INT24",
            Self::Integer32 => "DINT",
            Self::Integer64 => "LINT",
            Self::Unsigned8 => "USINT",
            Self::Unsigned16 => "UINT",
            Self::Unsigned24 => "UINT24",
            Self::Unsigned32 => "UDINT",
            Self::Unsigned64 => "ULINT",
            Self::Real32 => "REAL",
            Self::Real64 => "LREAL",
            Self::VisibleString => "STRING",
            Self::OctetString => "OCTET_STRING",
            Self::UnicodeString => "UNICODE_STRING",
            Self::TimeOfDay => "TIME_OF_DAY",
            Self::TimeDifference => "TIME_DIFFERENCE",
            Self::Domain => "DOMAIN",
            Self::Bit1 => "BIT1",
            Self::Bit2 => "BIT2",
            Self::Bit3 => "BIT3",
            Self::Bit4 => "BIT4",
            Self::Bit5 => "BIT5",
            Self::Bit6 => "BIT6",
            Self::Bit7 => "BIT7",
            Self::Bit8 => "BIT8",
        }
    }

    /// Parse a type name as ESI files, the CLI (`--type`) and CiA 301 write it: IEC names
    /// (`UINT`, `DINT`, `STRING(20)`, `BYTE`, `WORD`, `DWORD`), CiA names (`UNSIGNED16`) and
    /// the short forms `u8`…`u64`, `i8`…`i64`, `f32`, `f64`, `bool`, `string`.
    /// Case-insensitive.
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_uppercase();
        let base = match n.find('(') {
            Some(p) => &n[..p],
            None => n.as_str(),
        };
        Some(match base {
            "BOOL" | "BOOLEAN" => Self::Boolean,
            "SINT" | "INTEGER8" | "I8" => Self::Integer8,
            "INT" | "INTEGER16" | "I16" => Self::Integer16,
            "INT24" | "INTEGER24" => Self::Integer24,
            "DINT" | "INTEGER32" | "I32" => Self::Integer32,
            "LINT" | "INTEGER64" | "I64" => Self::Integer64,
            "USINT" | "BYTE" | "UNSIGNED8" | "U8" => Self::Unsigned8,
            "UINT" | "WORD" | "UNSIGNED16" | "U16" => Self::Unsigned16,
            "UINT24" | "UNSIGNED24" => Self::Unsigned24,
            "UDINT" | "DWORD" | "UNSIGNED32" | "U32" => Self::Unsigned32,
            "ULINT" | "LWORD" | "UNSIGNED64" | "U64" => Self::Unsigned64,
            "REAL" | "REAL32" | "F32" => Self::Real32,
            "LREAL" | "REAL64" | "F64" => Self::Real64,
            "STRING" | "VISIBLE_STRING" => Self::VisibleString,
            "OCTET_STRING" | "OCTETS" | "BYTES" => Self::OctetString,
            "UNICODE_STRING" => Self::UnicodeString,
            "TIME_OF_DAY" => Self::TimeOfDay,
            "TIME_DIFFERENCE" => Self::TimeDifference,
            "DOMAIN" => Self::Domain,
            "BIT1" => Self::Bit1,
            "BIT2" => Self::Bit2,
            "BIT3" => Self::Bit3,
            "BIT4" => Self::Bit4,
            "BIT5" => Self::Bit5,
            "BIT6" => Self::Bit6,
            "BIT7" => Self::Bit7,
            "BIT8" | "BITARR8" => Self::Bit8,
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
        for code in 0..=0x40u16 {
            if let Some(t) = DataType::from_code(code) {
                assert_eq!(t.code(), code);
                assert_eq!(DataType::parse(t.name()), Some(t), "{t}");
                assert_eq!(DataType::parse(t.esi_name()), Some(t), "{t}");
            }
        }
        assert_eq!(DataType::parse("STRING(20)"), Some(DataType::VisibleString));
        assert_eq!(DataType::parse("u16"), Some(DataType::Unsigned16));
        assert_eq!(DataType::parse("nonsense"), None);
    }
}
