//! Typed access to entries of a process image, by resolved [`Field`] handle.
//!
//! EtherCAT packs PDO entries bit by bit with no implicit alignment, little-endian: an entry of
//! `n` bits that starts at bit `b` of the image occupies bits `b .. b + n`, where bit `b` is bit
//! `b % 8` of byte `b / 8` and carries the entry's least significant bit. The default mappings of
//! both drives put 16- and 32-bit entries at odd byte offsets, and 1-bit entries are common on
//! other devices, so every read and write here handles any bit position.
//!
//! This is the per-cycle path: nothing here allocates, locks or panics. A field that does not fit
//! the buffer, or a value that does not fit the field or the requested type, is an
//! [`ImageError`].

use core::fmt;

/// A resolved process-image entry: where it is and how to interpret it. `Copy`, so the cycle
/// resolves object addresses to fields once at start-up (see
/// [`Layout`](super::Layout)) and then reads and writes by handle.
///
/// Invariant (enforced by the constructors): `1 <= bits <= 64` and `bit_offset < 8`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Field {
    byte_offset: usize,
    bit_offset: u8,
    bits: u8,
    signed: bool,
}

impl Field {
    /// A field of `bits` bits (1–64) starting at bit `bit_position` of the image (counted from
    /// bit 0 of byte 0). `signed` fields are sign-extended on read and range-checked as two's
    /// complement on write.
    pub const fn new(bit_position: usize, bits: u8, signed: bool) -> Result<Self, ImageError> {
        if bits == 0 || bits > 64 {
            return Err(ImageError::InvalidWidth { bits });
        }
        Ok(Self {
            byte_offset: bit_position / 8,
            bit_offset: (bit_position % 8) as u8,
            bits,
            signed,
        })
    }

    /// An unsigned field (`UNSIGNEDn`, `BOOLEAN`, `BITn`, and raw access to anything else).
    pub const fn unsigned(bit_position: usize, bits: u8) -> Result<Self, ImageError> {
        Self::new(bit_position, bits, false)
    }

    /// A signed field (`INTEGERn`).
    pub const fn signed(bit_position: usize, bits: u8) -> Result<Self, ImageError> {
        Self::new(bit_position, bits, true)
    }

    /// The same position and width, with another signedness.
    pub const fn with_signed(self, signed: bool) -> Self {
        Self { signed, ..self }
    }

    /// Byte of the image holding the field's least significant bit.
    pub const fn byte_offset(&self) -> usize {
        self.byte_offset
    }

    /// Bit (0–7) within [`Field::byte_offset`] holding the field's least significant bit.
    pub const fn bit_offset(&self) -> u8 {
        self.bit_offset
    }

    /// Width in bits (1–64).
    pub const fn bits(&self) -> u8 {
        self.bits
    }

    /// Whether the field is read and written as a two's-complement signed integer.
    pub const fn is_signed(&self) -> bool {
        self.signed
    }

    /// Position of the least significant bit, counted from bit 0 of byte 0.
    pub const fn bit_position(&self) -> usize {
        self.byte_offset * 8 + self.bit_offset as usize
    }

    /// Whether the field starts on a byte boundary.
    pub const fn is_byte_aligned(&self) -> bool {
        self.bit_offset == 0
    }

    /// Number of bytes the field touches (1–9).
    pub const fn span(&self) -> usize {
        (self.bit_offset as usize + self.bits as usize).div_ceil(8)
    }

    /// Smallest image length, in bytes, that holds the field (`None` on overflow).
    pub const fn end(&self) -> Option<usize> {
        self.byte_offset.checked_add(self.span())
    }

    /// Inclusive value range of the field: `-(2^(bits-1)) ..= 2^(bits-1) - 1` when signed,
    /// `0 ..= 2^bits - 1` otherwise.
    pub const fn range(&self) -> (i128, i128) {
        let bits = self.bits as u32;
        if self.signed {
            (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
        } else {
            (0, (1i128 << bits) - 1)
        }
    }

    const fn mask(&self) -> u64 {
        if self.bits >= 64 {
            u64::MAX
        } else {
            (1u64 << self.bits) - 1
        }
    }

    fn out_of_bounds(&self, len: usize) -> ImageError {
        ImageError::OutOfBounds {
            byte_offset: self.byte_offset,
            bit_offset: self.bit_offset,
            bits: self.bits,
            needed: self.end().unwrap_or(usize::MAX),
            len,
        }
    }

    /// The field's bits, zero-extended, without interpretation.
    #[inline]
    pub fn read_raw(&self, image: &[u8]) -> Result<u64, ImageError> {
        let span = self.span();
        let bytes = self
            .end()
            .and_then(|end| image.get(self.byte_offset..end))
            .ok_or_else(|| self.out_of_bounds(image.len()))?;
        // Fast paths: byte-aligned whole-byte fields, the common case.
        if self.bit_offset == 0 {
            match *bytes {
                [a] if self.bits == 8 => return Ok(u64::from(a)),
                [a, b] if self.bits == 16 => return Ok(u64::from(u16::from_le_bytes([a, b]))),
                [a, b, c, d] if self.bits == 32 => {
                    return Ok(u64::from(u32::from_le_bytes([a, b, c, d])));
                }
                [a, b, c, d, e, f, g, h] if self.bits == 64 => {
                    return Ok(u64::from_le_bytes([a, b, c, d, e, f, g, h]));
                }
                _ => {}
            }
        }
        let mut le = [0u8; 16];
        if let Some(dst) = le.get_mut(..span) {
            dst.copy_from_slice(bytes);
        }
        let word = u128::from_le_bytes(le) >> self.bit_offset;
        Ok(word as u64 & self.mask())
    }

    /// Write the low [`Field::bits`] bits of `raw`, leaving every other bit of the image as it
    /// was. Higher bits of `raw` are ignored; use [`Field::write`] for a range-checked write.
    #[inline]
    pub fn write_raw(&self, image: &mut [u8], raw: u64) -> Result<(), ImageError> {
        let len = image.len();
        let span = self.span();
        let bytes = match self.end() {
            Some(end) => image.get_mut(self.byte_offset..end),
            None => None,
        }
        .ok_or_else(|| self.out_of_bounds(len))?;
        // Fast paths: byte-aligned whole-byte fields, the common case.
        if self.bit_offset == 0 {
            match (self.bits, &mut *bytes) {
                (8, [a]) => {
                    *a = raw as u8;
                    return Ok(());
                }
                (16, dst @ [_, _]) => {
                    dst.copy_from_slice(&(raw as u16).to_le_bytes());
                    return Ok(());
                }
                (32, dst @ [_, _, _, _]) => {
                    dst.copy_from_slice(&(raw as u32).to_le_bytes());
                    return Ok(());
                }
                (64, dst @ [_, _, _, _, _, _, _, _]) => {
                    dst.copy_from_slice(&raw.to_le_bytes());
                    return Ok(());
                }
                _ => {}
            }
        }
        let mut le = [0u8; 16];
        if let Some(src) = le.get_mut(..span) {
            src.copy_from_slice(bytes);
        }
        let shift = self.bit_offset;
        let mask = u128::from(self.mask()) << shift;
        let word = u128::from_le_bytes(le);
        let word = (word & !mask) | ((u128::from(raw) << shift) & mask);
        let le = word.to_le_bytes();
        if let Some(src) = le.get(..span) {
            bytes.copy_from_slice(src);
        }
        Ok(())
    }

    /// The field's value as an integer: sign-extended when the field is signed.
    #[inline]
    pub fn read_int(&self, image: &[u8]) -> Result<i128, ImageError> {
        let raw = self.read_raw(image)?;
        Ok(if self.signed {
            let shift = 64 - u32::from(self.bits);
            i128::from(((raw << shift) as i64) >> shift)
        } else {
            i128::from(raw)
        })
    }

    /// Write an integer, checking it fits the field (see [`Field::range`]).
    #[inline]
    pub fn write_int(&self, image: &mut [u8], value: i128) -> Result<(), ImageError> {
        let (min, max) = self.range();
        if value < min || value > max {
            return Err(ImageError::ValueOutOfRange {
                value,
                bits: self.bits,
                signed: self.signed,
            });
        }
        // Two's-complement truncation; the range check makes it exact.
        self.write_raw(image, value as u64)
    }

    /// Read the field as `T`. Errors if the field's value does not fit `T` (e.g. a 32-bit field
    /// holding 70000 read as `u16`, or a negative value read as an unsigned type).
    #[inline]
    pub fn read<T: FieldValue>(&self, image: &[u8]) -> Result<T, ImageError> {
        let v = self.read_int(image)?;
        T::from_i128(v).ok_or(ImageError::DoesNotFit {
            value: v,
            bits: self.bits,
            target: T::NAME,
        })
    }

    /// Write `value`, checking it fits the field.
    #[inline]
    pub fn write<T: FieldValue>(&self, image: &mut [u8], value: T) -> Result<(), ImageError> {
        self.write_int(image, value.to_i128())
    }

    /// Read a `REAL32` field (exactly 32 bits).
    pub fn read_f32(&self, image: &[u8]) -> Result<f32, ImageError> {
        self.expect_width(32, "f32")?;
        Ok(f32::from_bits(self.read_raw(image)? as u32))
    }

    /// Write a `REAL32` field (exactly 32 bits).
    pub fn write_f32(&self, image: &mut [u8], value: f32) -> Result<(), ImageError> {
        self.expect_width(32, "f32")?;
        self.write_raw(image, u64::from(value.to_bits()))
    }

    /// Read a `REAL64` field (exactly 64 bits).
    pub fn read_f64(&self, image: &[u8]) -> Result<f64, ImageError> {
        self.expect_width(64, "f64")?;
        Ok(f64::from_bits(self.read_raw(image)?))
    }

    /// Write a `REAL64` field (exactly 64 bits).
    pub fn write_f64(&self, image: &mut [u8], value: f64) -> Result<(), ImageError> {
        self.expect_width(64, "f64")?;
        self.write_raw(image, value.to_bits())
    }

    fn expect_width(&self, bits: u8, target: &'static str) -> Result<(), ImageError> {
        if self.bits == bits {
            Ok(())
        } else {
            Err(ImageError::WidthMismatch {
                bits: self.bits,
                target,
            })
        }
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {}-bit field at byte {} bit {}",
            if self.signed { "signed" } else { "unsigned" },
            self.bits,
            self.byte_offset,
            self.bit_offset
        )
    }
}

/// A typed view over one process image (smoltcp style): a buffer checked once against the
/// layout's size, then read and written by [`Field`] handle.
///
/// ```
/// use ecdrive_core::pdo::{Field, ImageView};
/// let statusword = Field::unsigned(8, 16).unwrap();
/// let mut view = ImageView::new_checked([0u8; 4], 3).unwrap();
/// view.write(statusword, 0x0237u16).unwrap();
/// assert_eq!(view.read::<u16>(statusword).unwrap(), 0x0237);
/// assert_eq!(view.as_bytes(), &[0x00, 0x37, 0x02, 0x00]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ImageView<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> ImageView<T> {
    /// Wrap `buffer` without a length check (every access is still bounds-checked).
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wrap `buffer`, checking it holds at least `len` bytes (the image size of a
    /// [`Layout`](super::Layout) direction).
    pub fn new_checked(buffer: T, len: usize) -> Result<Self, ImageError> {
        let have = buffer.as_ref().len();
        if have < len {
            return Err(ImageError::TooShort {
                len: have,
                needed: len,
            });
        }
        Ok(Self { buffer })
    }

    /// The buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The image bytes.
    pub fn as_bytes(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// Read `field` as `V`.
    #[inline]
    pub fn read<V: FieldValue>(&self, field: Field) -> Result<V, ImageError> {
        field.read(self.buffer.as_ref())
    }

    /// Read `field`'s raw bits.
    #[inline]
    pub fn read_raw(&self, field: Field) -> Result<u64, ImageError> {
        field.read_raw(self.buffer.as_ref())
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> ImageView<T> {
    /// Write `value` to `field`, range-checked.
    #[inline]
    pub fn write<V: FieldValue>(&mut self, field: Field, value: V) -> Result<(), ImageError> {
        field.write(self.buffer.as_mut(), value)
    }

    /// Write the low bits of `raw` to `field`.
    #[inline]
    pub fn write_raw(&mut self, field: Field, raw: u64) -> Result<(), ImageError> {
        field.write_raw(self.buffer.as_mut(), raw)
    }

    /// The image bytes, mutably.
    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        self.buffer.as_mut()
    }
}

/// A Rust type a [`Field`] can be read into and written from: the primitive integers and `bool`.
pub trait FieldValue: Copy + sealed::Sealed {
    /// Type name for error messages.
    const NAME: &'static str;
    /// The value as an `i128`.
    fn to_i128(self) -> i128;
    /// The `i128` as this type, if it fits.
    fn from_i128(v: i128) -> Option<Self>;
}

mod sealed {
    pub trait Sealed {}
}

macro_rules! field_value_int {
    ($($t:ty),*) => {$(
        impl sealed::Sealed for $t {}
        impl FieldValue for $t {
            const NAME: &'static str = stringify!($t);
            #[inline]
            fn to_i128(self) -> i128 {
                i128::from(self)
            }
            #[inline]
            fn from_i128(v: i128) -> Option<Self> {
                <$t>::try_from(v).ok()
            }
        }
    )*};
}

field_value_int!(u8, u16, u32, u64, i8, i16, i32, i64);

impl sealed::Sealed for bool {}
impl FieldValue for bool {
    const NAME: &'static str = "bool";
    #[inline]
    fn to_i128(self) -> i128 {
        i128::from(self)
    }
    #[inline]
    fn from_i128(v: i128) -> Option<Self> {
        match v {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        }
    }
}

/// Why a process-image access failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// A field must be 1 to 64 bits wide.
    #[error("a process-image field must be 1 to 64 bits wide, not {bits}")]
    InvalidWidth {
        /// The width asked for.
        bits: u8,
    },
    /// The field lies (partly) beyond the end of the image.
    #[error(
        "the {bits}-bit field at byte {byte_offset} bit {bit_offset} needs an image of {needed} bytes; this one has {len}"
    )]
    OutOfBounds {
        /// Byte of the field's first bit.
        byte_offset: usize,
        /// Bit within that byte.
        bit_offset: u8,
        /// Field width.
        bits: u8,
        /// Image length the field needs (`usize::MAX` on overflow).
        needed: usize,
        /// Actual image length.
        len: usize,
    },
    /// A buffer shorter than the image it should hold.
    #[error("the process image needs {needed} bytes; the buffer has {len}")]
    TooShort {
        /// Buffer length.
        len: usize,
        /// Image size.
        needed: usize,
    },
    /// A value written does not fit the field.
    #[error("{value} does not fit a {bits}-bit {} field", if *signed { "signed" } else { "unsigned" })]
    ValueOutOfRange {
        /// The value.
        value: i128,
        /// Field width.
        bits: u8,
        /// Field signedness.
        signed: bool,
    },
    /// The value a field holds does not fit the type it is read as.
    #[error("the {bits}-bit field holds {value}, which does not fit {target}")]
    DoesNotFit {
        /// The value read.
        value: i128,
        /// Field width.
        bits: u8,
        /// The requested type.
        target: &'static str,
    },
    /// A float access to a field of another width.
    #[error("a {bits}-bit field cannot be accessed as {target}")]
    WidthMismatch {
        /// Field width.
        bits: u8,
        /// The requested type.
        target: &'static str,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unaligned_little_endian_layout() {
        // A 16-bit value starting at bit 4: low nibble of 0xABCD goes to the high nibble of
        // byte 0, and so on.
        let f = Field::unsigned(4, 16).unwrap();
        let mut img = [0u8; 3];
        f.write(&mut img, 0xABCDu16).unwrap();
        assert_eq!(img, [0xD0, 0xBC, 0x0A]);
        assert_eq!(f.read::<u16>(&img).unwrap(), 0xABCD);
        assert_eq!(f.span(), 3);
    }

    #[test]
    fn neighbours_are_untouched() {
        let f = Field::signed(3, 5).unwrap();
        let mut img = [0xFFu8; 2];
        f.write(&mut img, 0i8).unwrap();
        assert_eq!(img, [0b0000_0111, 0xFF]);
        f.write(&mut img, -1i8).unwrap();
        assert_eq!(img, [0xFF, 0xFF]);
        assert_eq!(f.read::<i8>(&img).unwrap(), -1);
    }

    #[test]
    fn full_64_bit_fields_at_odd_positions() {
        let f = Field::signed(7, 64).unwrap();
        let mut img = [0u8; 9];
        f.write(&mut img, i64::MIN).unwrap();
        assert_eq!(f.read::<i64>(&img).unwrap(), i64::MIN);
        let u = f.with_signed(false);
        u.write(&mut img, u64::MAX).unwrap();
        assert_eq!(u.read::<u64>(&img).unwrap(), u64::MAX);
        assert_eq!(f.read::<i64>(&img).unwrap(), -1);
        assert_eq!(img[0], 0x80);
        assert_eq!(img[8], 0x7F);
    }

    #[test]
    fn errors_instead_of_panics() {
        assert_eq!(
            Field::unsigned(0, 0),
            Err(ImageError::InvalidWidth { bits: 0 })
        );
        assert_eq!(
            Field::unsigned(0, 65),
            Err(ImageError::InvalidWidth { bits: 65 })
        );
        let f = Field::unsigned(20, 8).unwrap();
        let mut img = [0u8; 3];
        assert!(matches!(
            f.read_raw(&img),
            Err(ImageError::OutOfBounds {
                needed: 4,
                len: 3,
                ..
            })
        ));
        assert!(f.write_raw(&mut img, 1).is_err());
        let far = Field::unsigned(usize::MAX, 64).unwrap();
        assert!(far.read_raw(&img).is_err());
        assert!(far.write_raw(&mut img, 0).is_err());

        let u8f = Field::unsigned(0, 8).unwrap();
        assert_eq!(
            u8f.write(&mut img, 256u16),
            Err(ImageError::ValueOutOfRange {
                value: 256,
                bits: 8,
                signed: false
            })
        );
        assert!(u8f.write(&mut img, -1i8).is_err());
        img[0] = 200;
        assert_eq!(
            u8f.read::<i8>(&img),
            Err(ImageError::DoesNotFit {
                value: 200,
                bits: 8,
                target: "i8"
            })
        );
        assert!(u8f.read::<bool>(&img).is_err());
        assert!(u8f.read_f32(&img).is_err());
    }

    #[test]
    fn views_check_their_length_once() {
        assert_eq!(
            ImageView::new_checked(&[0u8; 2][..], 3),
            Err(ImageError::TooShort { len: 2, needed: 3 })
        );
        let f = Field::signed(4, 12).unwrap();
        let mut v = ImageView::new_checked(vec![0u8; 2], 2).unwrap();
        v.write(f, -2048i16).unwrap();
        assert_eq!(v.read::<i16>(f).unwrap(), -2048);
        assert_eq!(v.read_raw(f).unwrap(), 0x800);
        assert_eq!(v.into_inner(), vec![0x00, 0x80]);
    }

    #[test]
    fn floats_round_trip() {
        let f = Field::unsigned(8, 32).unwrap();
        let mut img = [0u8; 5];
        f.write_f32(&mut img, -1.5).unwrap();
        assert_eq!(f.read_f32(&img).unwrap(), -1.5);
        let d = Field::unsigned(1, 64).unwrap();
        let mut img = [0u8; 9];
        d.write_f64(&mut img, 1e300).unwrap();
        assert_eq!(d.read_f64(&img).unwrap(), 1e300);
    }
}
