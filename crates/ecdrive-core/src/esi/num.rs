//! The number, boolean and hex-binary formats ESI files use.

use std::num::IntErrorKind;

/// Why a number could not be read. The text says why, for the error message.
pub(crate) type NumResult<T> = Result<T, String>;

/// The digits after a hex prefix (`#x`, `#X`, `0x`, `0X`).
fn hex(t: &str) -> Option<&str> {
    t.strip_prefix("#x")
        .or_else(|| t.strip_prefix("#X"))
        .or_else(|| t.strip_prefix("0x"))
        .or_else(|| t.strip_prefix("0X"))
}

/// Parse an ESI number (ETG.2000 `HexDecValue`): decimal with an optional sign, `#x` hex, and
/// (tolerated, not in the schema) `0x` hex. Surrounding white space is ignored.
pub(crate) fn parse_int(text: &str) -> NumResult<i128> {
    let t = text.trim();
    if t.is_empty() {
        return Err("empty, expected a number".into());
    }
    let (neg, rest) = match t.as_bytes().first() {
        Some(b'-') => (true, &t[1..]),
        Some(b'+') => (false, &t[1..]),
        _ => (false, t),
    };
    // `#x0x6041` (both prefixes, as one generator writes them) is the same hex number.
    let (radix, digits) = if let Some(h) = hex(rest).map(|h| hex(h).unwrap_or(h)) {
        (16, h)
    } else {
        (10, rest)
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(if radix == 16 {
            "not a hex number".into()
        } else {
            "not a number".into()
        });
    }
    let mag = u128::from_str_radix(digits, radix).map_err(|e| match e.kind() {
        IntErrorKind::PosOverflow => "too large".to_string(),
        _ => "not a number".to_string(),
    })?;
    let mag = i128::try_from(mag).map_err(|_| "too large".to_string())?;
    Ok(if neg { -mag } else { mag })
}

/// An integer type a field is stored in, with its range for messages.
pub(crate) trait EsiInt: Sized + Copy {
    /// Smallest value.
    const MIN: i128;
    /// Largest value.
    const MAX: i128;
    /// Name for messages (`UINT16`…).
    const NAME: &'static str;
    /// Convert an in-range value.
    fn from_i128(v: i128) -> Self;
}

macro_rules! esi_int {
    ($t:ty, $name:literal) => {
        impl EsiInt for $t {
            const MIN: i128 = <$t>::MIN as i128;
            const MAX: i128 = <$t>::MAX as i128;
            const NAME: &'static str = $name;
            fn from_i128(v: i128) -> Self {
                v as $t
            }
        }
    };
}

esi_int!(u8, "an 8-bit unsigned number");
esi_int!(u16, "a 16-bit unsigned number");
esi_int!(i16, "a 16-bit signed number");
esi_int!(u32, "a 32-bit unsigned number");
esi_int!(i32, "a 32-bit signed number");
esi_int!(u64, "a 64-bit unsigned number");

/// Parse a number into `T`, checking the range.
pub(crate) fn parse_num<T: EsiInt>(text: &str) -> NumResult<T> {
    let v = parse_int(text)?;
    if v < T::MIN || v > T::MAX {
        return Err(format!(
            "out of range, expected {} ({}..={})",
            T::NAME,
            T::MIN,
            T::MAX
        ));
    }
    Ok(T::from_i128(v))
}

/// Parse a 32-bit identity value (vendor ID, product code, revision). Besides the unsigned
/// range, a negative decimal in the `i32` range is accepted as its two's complement: some
/// vendors write product codes with the top bit set that way, and the schema type allows it.
pub(crate) fn parse_u32_wrapping(text: &str) -> NumResult<u32> {
    let v = parse_int(text)?;
    if (0..=u32::MAX as i128).contains(&v) {
        Ok(v as u32)
    } else if (i32::MIN as i128..0).contains(&v) {
        Ok(v as i32 as u32)
    } else {
        Err("out of range, expected a 32-bit number".into())
    }
}

/// Parse an ESI boolean: `1`, `0`, `true`, `false` (case-insensitive).
pub(crate) fn parse_bool(text: &str) -> NumResult<bool> {
    let t = text.trim();
    if t == "1" || t.eq_ignore_ascii_case("true") {
        Ok(true)
    } else if t == "0" || t.eq_ignore_ascii_case("false") {
        Ok(false)
    } else {
        Err("not a boolean (expected 1, 0, true or false)".into())
    }
}

/// Parse `xs:hexBinary` bytes (`0A1E0000`). White space between digits is tolerated.
pub(crate) fn parse_hex_bytes(text: &str) -> NumResult<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 2);
    let mut high: Option<u8> = None;
    for c in text.chars() {
        if c.is_whitespace() {
            continue;
        }
        let d = c
            .to_digit(16)
            .ok_or_else(|| format!("not hex data ({c:?} is not a hex digit)"))?
            as u8;
        match high.take() {
            Some(h) => out.push(h << 4 | d),
            None => high = Some(d),
        }
    }
    if high.is_some() {
        return Err("not hex data (odd number of hex digits)".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(parse_int("#x0A1E"), Ok(0xA1E));
        assert_eq!(parse_int(" #X1c12 "), Ok(0x1C12));
        assert_eq!(parse_int("0x1600"), Ok(0x1600));
        assert_eq!(parse_int("#x0x6041"), Ok(0x6041));
        assert_eq!(parse_int("-5"), Ok(-5));
        assert_eq!(parse_int("+5"), Ok(5));
        assert_eq!(parse_int("250000"), Ok(250_000));
        assert!(parse_int("").is_err());
        assert!(parse_int("#x").is_err());
        assert!(parse_int("12a").is_err());
        assert!(parse_int("--1").is_err());
        assert!(parse_int("-+1").is_err());
        assert_eq!(
            parse_int("#x1234567890123456789012345678901234"),
            Err("too large".into())
        );
        assert_eq!(parse_num::<u8>("255"), Ok(255));
        assert!(parse_num::<u8>("256").unwrap_err().contains("out of range"));
        assert!(parse_num::<u16>("-1").is_err());
        assert_eq!(parse_num::<i32>("-1"), Ok(-1));
        assert_eq!(parse_u32_wrapping("-1"), Ok(0xFFFF_FFFF));
        assert_eq!(parse_u32_wrapping("#xFFFFFFFF"), Ok(0xFFFF_FFFF));
        assert!(parse_u32_wrapping("#x100000000").is_err());
        assert!(parse_u32_wrapping("-2147483649").is_err());
    }

    #[test]
    fn booleans_and_hex() {
        assert_eq!(parse_bool("1"), Ok(true));
        assert_eq!(parse_bool("False"), Ok(false));
        assert!(parse_bool("yes").is_err());
        assert_eq!(parse_hex_bytes("0A1E0000"), Ok(vec![0x0A, 0x1E, 0, 0]));
        assert_eq!(parse_hex_bytes("0a 1e"), Ok(vec![0x0A, 0x1E]));
        assert_eq!(parse_hex_bytes(""), Ok(vec![]));
        assert!(parse_hex_bytes("0A1").is_err());
        assert!(parse_hex_bytes("zz").is_err());
        assert!(parse_hex_bytes("aéa").is_err());
    }
}
