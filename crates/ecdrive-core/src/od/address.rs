use core::fmt;
use core::str::FromStr;

/// The address of one object-dictionary entry: index and sub-index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectAddress {
    /// Object index, e.g. `0x6040`.
    pub index: u16,
    /// Sub-index, `0` for VAR objects.
    pub sub: u8,
}

impl ObjectAddress {
    /// An address.
    pub const fn new(index: u16, sub: u8) -> Self {
        Self { index, sub }
    }
}

impl fmt::Display for ObjectAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "0x{:04X}:{:02X}", self.index, self.sub)
    }
}

/// Why an `INDEX:SUB` text could not be parsed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("malformed object address {text:?}: {reason} (expected INDEX:SUB, e.g. 0x6040:00)")]
pub struct AddressParseError {
    /// The text given.
    pub text: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

/// Parse a number as users write object addresses: `0x` prefix or `h` suffix for hex, otherwise
/// decimal.
fn parse_num(s: &str) -> Option<u64> {
    let s = s.trim();
    if let Some(h) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        u64::from_str_radix(h, 16).ok()
    } else if let Some(h) = s.strip_suffix('h').or_else(|| s.strip_suffix('H')) {
        u64::from_str_radix(h, 16).ok()
    } else {
        s.parse().ok()
    }
}

impl FromStr for ObjectAddress {
    type Err = AddressParseError;

    /// Parse `INDEX:SUB`. Each part is decimal, `0x`-prefixed hex or `h`-suffixed hex:
    /// `0x6040:0`, `0x1C32:0x02`, `6040h:00h`, `24640:0`. A bare index (`0x6041`) means sub 0.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let err = |reason| AddressParseError {
            text: text.to_string(),
            reason,
        };
        let (idx, sub) = match text.split_once(':') {
            Some((i, s)) => (i, Some(s)),
            None => (text, None),
        };
        if idx.trim().is_empty() {
            return Err(err("the index is empty"));
        }
        let index = parse_num(idx).ok_or_else(|| err("the index is not a number"))?;
        let index = u16::try_from(index).map_err(|_| err("the index is larger than 0xFFFF"))?;
        let sub = match sub {
            None => 0,
            Some(s) if s.trim().is_empty() => return Err(err("the sub-index is empty")),
            Some(s) => {
                let v = parse_num(s).ok_or_else(|| err("the sub-index is not a number"))?;
                u8::try_from(v).map_err(|_| err("the sub-index is larger than 0xFF"))?
            }
        };
        Ok(Self { index, sub })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_common_spellings() {
        let a = ObjectAddress::new(0x6040, 0);
        assert_eq!("0x6040:0".parse(), Ok(a));
        assert_eq!("0x6040:0x00".parse(), Ok(a));
        assert_eq!("6040h:00h".parse(), Ok(a));
        assert_eq!("24640:0".parse(), Ok(a));
        assert_eq!("0x6040".parse(), Ok(a));
        assert_eq!(a.to_string(), "0x6040:00");
    }

    #[test]
    fn rejects_bad_input_with_reason() {
        for (t, why) in [
            ("", "the index is empty"),
            ("0x10000:0", "the index is larger than 0xFFFF"),
            ("0x6040:0x100", "the sub-index is larger than 0xFF"),
            ("zz:0", "the index is not a number"),
            ("0x6040:", "the sub-index is empty"),
        ] {
            let e = t.parse::<ObjectAddress>().unwrap_err();
            assert_eq!(e.reason, why, "{t}");
        }
    }
}
