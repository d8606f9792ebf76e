use super::DataType;
use core::fmt;

/// A value as static data states it: a default, a minimum or a maximum in a descriptor table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConstValue {
    /// No value given.
    None,
    /// A signed integer.
    Int(i64),
    /// An unsigned integer, boolean or bit field.
    Uint(u64),
    /// A float.
    Real(f64),
    /// A visible string.
    Str(&'static str),
    /// An octet string or domain.
    Bytes(&'static [u8]),
}

impl ConstValue {
    /// The owned runtime value, or `None` for [`ConstValue::None`].
    pub fn to_value(self) -> Option<Value> {
        Some(match self {
            Self::None => return None,
            Self::Int(v) => Value::Int(v),
            Self::Uint(v) => Value::Uint(v),
            Self::Real(v) => Value::Real(v),
            Self::Str(s) => Value::Str(s.to_string()),
            Self::Bytes(b) => Value::Bytes(b.to_vec()),
        })
    }

    /// The value as an `i128`, for range comparisons of integers of any signedness.
    pub fn as_i128(self) -> Option<i128> {
        match self {
            Self::Int(v) => Some(v as i128),
            Self::Uint(v) => Some(v as i128),
            _ => None,
        }
    }
}

/// A runtime object value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A signed integer.
    Int(i64),
    /// An unsigned integer, boolean or bit field.
    Uint(u64),
    /// A float.
    Real(f64),
    /// A visible or unicode string.
    Str(String),
    /// An octet string or domain.
    Bytes(Vec<u8>),
}

/// Why a value could not be parsed, encoded or decoded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValueError {
    /// The number does not fit the data type.
    #[error("value {value} is out of range for {data_type} ({min}..={max})")]
    OutOfRange {
        /// The value as given.
        value: String,
        /// The data type it was meant for.
        data_type: DataType,
        /// Smallest allowed value.
        min: i128,
        /// Largest allowed value.
        max: i128,
    },
    /// The text is not a number of the required kind.
    #[error("{text:?} is not a valid {data_type} value (use decimal or 0x hex)")]
    NotANumber {
        /// The text given.
        text: String,
        /// The data type it was meant for.
        data_type: DataType,
    },
    /// The text is not a sequence of hex bytes (for an OCTET STRING or DOMAIN).
    #[error(
        "{text:?} is not hex bytes for {data_type} (two hex digits per byte, in order: \"34 12\" or 0x3412)"
    )]
    NotHexBytes {
        /// The text given.
        text: String,
        /// The data type it was meant for.
        data_type: DataType,
    },
    /// The byte length does not match the data type.
    #[error("{data_type} needs {expected} bytes, got {got}")]
    WrongLength {
        /// The data type.
        data_type: DataType,
        /// Bytes the type needs.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// The value kind does not fit the data type (e.g. a string for an integer object).
    #[error("a {kind} value cannot be stored in a {data_type} object")]
    KindMismatch {
        /// What the value is.
        kind: &'static str,
        /// The data type.
        data_type: DataType,
    },
}

/// Inclusive integer range of a fixed-size integer type, or `None` for non-integers.
pub(crate) fn int_range(dt: DataType) -> Option<(i128, i128)> {
    let bits = dt.bit_len()? as u32;
    if dt.is_signed() {
        Some((-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1))
    } else if dt.is_unsigned() || matches!(dt, DataType::TimeOfDay | DataType::TimeDifference) {
        // TIME_OF_DAY / TIME_DIFFERENCE are handled as their raw 48-bit little-endian value.
        Some((0, (1i128 << bits) - 1))
    } else {
        None
    }
}

/// Byte length of a fixed-size type over SDO (bit types take whole bytes).
pub(crate) fn byte_len(dt: DataType) -> Option<usize> {
    dt.bit_len().map(|b| (b as usize).div_ceil(8))
}

impl Value {
    /// The value as an `i128`, if it is an integer.
    pub fn as_i128(&self) -> Option<i128> {
        match self {
            Self::Int(v) => Some(*v as i128),
            Self::Uint(v) => Some(*v as i128),
            _ => None,
        }
    }

    fn kind(&self) -> &'static str {
        match self {
            Self::Int(_) | Self::Uint(_) => "integer",
            Self::Real(_) => "real",
            Self::Str(_) => "string",
            Self::Bytes(_) => "byte-string",
        }
    }

    /// Decode the little-endian bytes of an SDO transfer as `dt`. Too few bytes are an error;
    /// bytes beyond the type's size are ignored (a segmented upload may pad), so a server that
    /// must reject over-long downloads checks the length itself.
    pub fn decode(dt: DataType, bytes: &[u8]) -> Result<Self, ValueError> {
        if dt.is_string() {
            return Ok(match dt {
                DataType::VisibleString => {
                    // Strings may be NUL-padded to their object size.
                    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
                    Self::Str(String::from_utf8_lossy(&bytes[..end]).into_owned())
                }
                _ => Self::Bytes(bytes.to_vec()),
            });
        }
        let n = byte_len(dt).unwrap_or(0);
        if bytes.len() < n {
            return Err(ValueError::WrongLength {
                data_type: dt,
                expected: n,
                got: bytes.len(),
            });
        }
        let mut raw = [0u8; 8];
        raw[..n.min(8)].copy_from_slice(&bytes[..n.min(8)]);
        let u = u64::from_le_bytes(raw);
        Ok(match dt {
            DataType::Real32 => Self::Real(f32::from_bits(u as u32) as f64),
            DataType::Real64 => Self::Real(f64::from_bits(u)),
            _ if dt.is_signed() => {
                let bits = dt.bit_len().unwrap_or(64) as u32;
                let shift = 64 - bits;
                Self::Int(((u << shift) as i64) >> shift)
            }
            _ => {
                let mask = match dt.bit_len() {
                    Some(b) if b < 64 => (1u64 << b) - 1,
                    _ => u64::MAX,
                };
                Self::Uint(u & mask)
            }
        })
    }

    /// Encode as little-endian bytes of `dt` into `out`, checking that the value fits. Returns
    /// the number of bytes written. Strings are written as given (no padding).
    pub fn encode_into(&self, dt: DataType, out: &mut [u8]) -> Result<usize, ValueError> {
        let bytes_needed = |n: usize, out: &mut [u8]| {
            if out.len() < n {
                Err(ValueError::WrongLength {
                    data_type: dt,
                    expected: n,
                    got: out.len(),
                })
            } else {
                Ok(())
            }
        };
        match (self, dt) {
            (Self::Str(s), DataType::VisibleString | DataType::UnicodeString) => {
                bytes_needed(s.len(), out)?;
                out[..s.len()].copy_from_slice(s.as_bytes());
                Ok(s.len())
            }
            (Self::Bytes(b), d) if d.is_string() => {
                bytes_needed(b.len(), out)?;
                out[..b.len()].copy_from_slice(b);
                Ok(b.len())
            }
            (Self::Str(s), DataType::OctetString | DataType::Domain) => {
                bytes_needed(s.len(), out)?;
                out[..s.len()].copy_from_slice(s.as_bytes());
                Ok(s.len())
            }
            (Self::Real(v), DataType::Real32) => {
                bytes_needed(4, out)?;
                out[..4].copy_from_slice(&(*v as f32).to_le_bytes());
                Ok(4)
            }
            (Self::Real(v), DataType::Real64) => {
                bytes_needed(8, out)?;
                out[..8].copy_from_slice(&v.to_le_bytes());
                Ok(8)
            }
            (Self::Int(_) | Self::Uint(_), d) if int_range(d).is_some() => {
                let v = self.as_i128().unwrap_or_default();
                let (min, max) = int_range(d).unwrap_or((0, 0));
                if v < min || v > max {
                    return Err(ValueError::OutOfRange {
                        value: v.to_string(),
                        data_type: d,
                        min,
                        max,
                    });
                }
                let n = byte_len(d).unwrap_or(0);
                bytes_needed(n, out)?;
                out[..n].copy_from_slice(&(v as i64).to_le_bytes()[..n]);
                Ok(n)
            }
            (v, d) => Err(ValueError::KindMismatch {
                kind: v.kind(),
                data_type: d,
            }),
        }
    }

    /// Encode into a new vector (for non-cyclic use).
    pub fn encode(&self, dt: DataType) -> Result<Vec<u8>, ValueError> {
        let len = match self {
            Self::Str(s) => s.len(),
            Self::Bytes(b) => b.len(),
            _ => byte_len(dt).unwrap_or(8),
        };
        let mut v = vec![0; len];
        let n = self.encode_into(dt, &mut v)?;
        v.truncate(n);
        Ok(v)
    }

    /// Parse a value as a user types it for an object of type `dt`: decimal or `0x` hex for
    /// integers (a leading `-` for signed ones), `true`/`false` for booleans, a decimal for
    /// reals, the text itself for strings, and hex digits (`0x0102…` or `01 02 …`) for octet
    /// strings. The value must fit the type.
    pub fn parse(text: &str, dt: DataType) -> Result<Self, ValueError> {
        let t = text.trim();
        let nan = || ValueError::NotANumber {
            text: text.to_string(),
            data_type: dt,
        };
        match dt {
            DataType::VisibleString | DataType::UnicodeString => Ok(Self::Str(text.to_string())),
            DataType::OctetString | DataType::Domain => {
                let nan = || ValueError::NotHexBytes {
                    text: text.to_string(),
                    data_type: dt,
                };
                let digits = t
                    .strip_prefix("0x")
                    .or_else(|| t.strip_prefix("0X"))
                    .unwrap_or(t);
                let hex: Vec<u8> = digits
                    .bytes()
                    .filter(|c| !c.is_ascii_whitespace())
                    .collect();
                if hex.len() % 2 != 0 {
                    return Err(nan());
                }
                hex.chunks_exact(2)
                    .map(|pair| match pair {
                        [hi, lo] => {
                            let hi = (*hi as char).to_digit(16).ok_or_else(nan)?;
                            let lo = (*lo as char).to_digit(16).ok_or_else(nan)?;
                            Ok((hi * 16 + lo) as u8)
                        }
                        _ => Err(nan()),
                    })
                    .collect::<Result<Vec<_>, _>>()
                    .map(Self::Bytes)
            }
            DataType::Real32 | DataType::Real64 => t.parse().map(Self::Real).map_err(|_| nan()),
            _ => {
                let lower = t.to_ascii_lowercase();
                let v: i128 = match lower.as_str() {
                    "true" if dt == DataType::Boolean => 1,
                    "false" if dt == DataType::Boolean => 0,
                    _ => {
                        let (neg, mag) = match lower.strip_prefix('-') {
                            Some(m) => (true, m),
                            None => (false, lower.strip_prefix('+').unwrap_or(&lower)),
                        };
                        let (radix, digits) = match mag.strip_prefix("0x") {
                            Some(h) => (16, h),
                            None => (10, mag),
                        };
                        // Digits only: `from_str_radix` would also accept a second sign.
                        if digits.is_empty() || !digits.chars().all(|c| c.is_digit(radix)) {
                            return Err(nan());
                        }
                        let mag = i128::from_str_radix(digits, radix).map_err(|_| nan())?;
                        if neg { -mag } else { mag }
                    }
                };
                let (min, max) = int_range(dt).ok_or_else(nan)?;
                if v < min || v > max {
                    return Err(ValueError::OutOfRange {
                        value: t.to_string(),
                        data_type: dt,
                        min,
                        max,
                    });
                }
                Ok(if dt.is_signed() {
                    Self::Int(v as i64)
                } else {
                    Self::Uint(v as u64)
                })
            }
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Int(v) => write!(f, "{v}"),
            Self::Uint(v) => write!(f, "{v}"),
            Self::Real(v) => write!(f, "{v}"),
            Self::Str(s) => write!(f, "{s:?}"),
            Self::Bytes(b) => {
                f.write_str("0x")?;
                for x in b {
                    write!(f, "{x:02x}")?;
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_decode_round_trip_signed() {
        let v = Value::parse("-100000", DataType::Integer32).unwrap();
        let b = v.encode(DataType::Integer32).unwrap();
        assert_eq!(b, (-100000i32).to_le_bytes());
        assert_eq!(Value::decode(DataType::Integer32, &b).unwrap(), v);
    }

    #[test]
    fn parse_rejects_out_of_range_and_garbage() {
        assert!(matches!(
            Value::parse("256", DataType::Unsigned8),
            Err(ValueError::OutOfRange { .. })
        ));
        assert!(matches!(
            Value::parse("-1", DataType::Unsigned16),
            Err(ValueError::OutOfRange { .. })
        ));
        assert!(matches!(
            Value::parse("12abc", DataType::Unsigned16),
            Err(ValueError::NotANumber { .. })
        ));
        assert_eq!(
            Value::parse("0xFF", DataType::Unsigned8).unwrap(),
            Value::Uint(255)
        );
        assert_eq!(
            Value::parse("-128", DataType::Integer8).unwrap(),
            Value::Int(-128)
        );
        for bad in ["--5", "-+5", "0x-5", "+-5", "", "-", "0x"] {
            assert!(
                matches!(
                    Value::parse(bad, DataType::Integer32),
                    Err(ValueError::NotANumber { .. })
                ),
                "{bad:?}"
            );
        }
        assert_eq!(
            Value::parse("+7", DataType::Integer8).unwrap(),
            Value::Int(7)
        );
    }

    #[test]
    fn octet_strings_parse_hex_and_reject_other_text_without_panicking() {
        assert_eq!(
            Value::parse("0x0102ff", DataType::OctetString).unwrap(),
            Value::Bytes(vec![1, 2, 0xff])
        );
        assert_eq!(
            Value::parse("01 02 FF", DataType::OctetString).unwrap(),
            Value::Bytes(vec![1, 2, 0xff])
        );
        // Multi-byte characters must not split a char boundary.
        for bad in ["a\u{e9}b", "\u{e9}\u{e9}", "0g", "123"] {
            assert!(
                matches!(
                    Value::parse(bad, DataType::OctetString),
                    Err(ValueError::NotHexBytes { .. })
                ),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn wide_types_encode_and_decode() {
        let v = Value::Int(-(1i64 << 39));
        let b = v.encode(DataType::Integer40).unwrap();
        assert_eq!(b.len(), 5);
        assert_eq!(Value::decode(DataType::Integer40, &b).unwrap(), v);
        assert!(Value::Uint(1 << 48).encode(DataType::Unsigned48).is_err());
        // What decode produces for a TIME_OF_DAY, encode accepts back.
        let raw = [1, 2, 3, 4, 5, 6];
        let t = Value::decode(DataType::TimeOfDay, &raw).unwrap();
        assert_eq!(t.encode(DataType::TimeOfDay).unwrap(), raw);
    }

    #[test]
    fn decode_short_input_is_an_error() {
        assert!(matches!(
            Value::decode(DataType::Unsigned32, &[1, 2]),
            Err(ValueError::WrongLength { .. })
        ));
    }

    #[test]
    fn strings_stop_at_nul() {
        assert_eq!(
            Value::decode(DataType::VisibleString, b"MR-J4\0\0").unwrap(),
            Value::Str("MR-J4".into())
        );
    }
}
