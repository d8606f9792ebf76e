//! Bit-level process-image access: round trips at arbitrary bit offsets and lengths, checked
//! against a bit-by-bit reference model; neighbours untouched; errors instead of panics.

use ecdrive_core::pdo::{Field, ImageError};
use proptest::prelude::*;

/// Reference model: bit `i` of the image is bit `i % 8` of byte `i / 8`; a field's bit `k` is
/// image bit `position + k` (little-endian, LSB first).
fn model_read(image: &[u8], position: usize, bits: u8) -> u64 {
    (0..bits as usize).fold(0u64, |acc, k| {
        let i = position + k;
        let bit = (image[i / 8] >> (i % 8)) & 1;
        acc | (u64::from(bit) << k)
    })
}

fn model_write(image: &mut [u8], position: usize, bits: u8, raw: u64) {
    for k in 0..bits as usize {
        let i = position + k;
        let bit = ((raw >> k) & 1) as u8;
        image[i / 8] = (image[i / 8] & !(1 << (i % 8))) | (bit << (i % 8));
    }
}

fn range(bits: u8, signed: bool) -> (i128, i128) {
    if signed {
        (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
    } else {
        (0, (1i128 << bits) - 1)
    }
}

/// A field that fits in an image, an image and a value in the field's range.
fn in_bounds_case() -> impl Strategy<Value = (Vec<u8>, usize, u8, bool, i128)> {
    (1u8..=64, any::<bool>(), 0usize..24)
        .prop_flat_map(|(bits, signed, extra)| {
            let min_len = (bits as usize).div_ceil(8);
            (
                proptest::collection::vec(any::<u8>(), min_len + extra..=min_len + extra + 9),
                Just(bits),
                Just(signed),
            )
        })
        .prop_flat_map(|(image, bits, signed)| {
            let max_pos = image.len() * 8 - bits as usize;
            let (lo, hi) = range(bits, signed);
            (Just(image), 0..=max_pos, Just(bits), Just(signed), lo..=hi)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    #[test]
    fn write_then_read_round_trips_and_leaves_neighbours(
        (image, pos, bits, signed, value) in in_bounds_case()
    ) {
        let field = Field::new(pos, bits, signed).unwrap();
        let mut img = image.clone();
        field.write_int(&mut img, value).unwrap();
        prop_assert_eq!(field.read_int(&img).unwrap(), value);

        // Same bytes as the bit-by-bit model writing the two's-complement pattern.
        let mut expected = image.clone();
        model_write(&mut expected, pos, bits, value as u64);
        prop_assert_eq!(&img, &expected);
        prop_assert_eq!(field.read_raw(&img).unwrap(), model_read(&img, pos, bits));
    }

    #[test]
    fn read_matches_the_model_on_any_content(
        (image, pos, bits, signed, _value) in in_bounds_case()
    ) {
        let field = Field::new(pos, bits, signed).unwrap();
        let raw = model_read(&image, pos, bits);
        prop_assert_eq!(field.read_raw(&image).unwrap(), raw);
        let expected = if signed && bits < 64 && raw >> (bits - 1) & 1 == 1 {
            raw as i128 - (1i128 << bits)
        } else if signed && bits == 64 {
            raw as i64 as i128
        } else {
            raw as i128
        };
        prop_assert_eq!(field.read_int(&image).unwrap(), expected);
    }

    #[test]
    fn typed_signed_values_round_trip_at_any_offset(
        pos in 0usize..64, v32 in any::<i32>(), v16 in any::<i16>(), v8 in any::<i8>(), v64 in any::<i64>()
    ) {
        let mut img = [0xA5u8; 24];
        let f32_ = Field::signed(pos, 32).unwrap();
        f32_.write(&mut img, v32).unwrap();
        prop_assert_eq!(f32_.read::<i32>(&img).unwrap(), v32);
        let f16 = Field::signed(pos, 16).unwrap();
        f16.write(&mut img, v16).unwrap();
        prop_assert_eq!(f16.read::<i16>(&img).unwrap(), v16);
        // A signed 16-bit field read into a wider type keeps its sign.
        prop_assert_eq!(f16.read::<i64>(&img).unwrap(), i64::from(v16));
        let f8 = Field::signed(pos, 8).unwrap();
        f8.write(&mut img, v8).unwrap();
        prop_assert_eq!(f8.read::<i8>(&img).unwrap(), v8);
        let f64_ = Field::signed(pos, 64).unwrap();
        f64_.write(&mut img, v64).unwrap();
        prop_assert_eq!(f64_.read::<i64>(&img).unwrap(), v64);
    }

    #[test]
    fn out_of_range_values_are_refused_and_change_nothing(
        (image, pos, bits, signed, _v) in in_bounds_case(), above in any::<bool>(), by in 1i128..1000
    ) {
        let field = Field::new(pos, bits, signed).unwrap();
        let (lo, hi) = range(bits, signed);
        let value = if above { hi + by } else { lo - by };
        let mut img = image.clone();
        prop_assert_eq!(
            field.write_int(&mut img, value),
            Err(ImageError::ValueOutOfRange { value, bits, signed })
        );
        prop_assert_eq!(img, image);
    }

    #[test]
    fn fields_beyond_the_image_are_errors_not_panics(
        len in 0usize..16, pos in 0usize..200, bits in 1u8..=64, raw in any::<u64>()
    ) {
        let field = Field::unsigned(pos, bits).unwrap();
        let fits = pos + bits as usize <= len * 8;
        let mut img = vec![0x5Au8; len];
        let read = field.read_raw(&img);
        let write = field.write_raw(&mut img, raw);
        prop_assert_eq!(read.is_ok(), fits);
        prop_assert_eq!(write.is_ok(), fits);
        if !fits {
            let is_oob = matches!(read, Err(ImageError::OutOfBounds { len: l, .. }) if l == len);
            prop_assert!(is_oob);
            prop_assert!(img.iter().all(|&b| b == 0x5A));
        }
    }
}

#[test]
fn mr_j4_tm_style_unaligned_fields_hold_negative_values() {
    // BDHDE default RxPDO: controlword at byte 9, profile velocity (U32) at byte 11; a target
    // torque (I16) at byte 17. A 5-bit field straddling a byte boundary.
    let mut img = [0u8; 23];
    let torque = Field::signed(17 * 8, 16).unwrap();
    torque.write(&mut img, -1234i16).unwrap();
    assert_eq!(&img[17..19], &(-1234i16).to_le_bytes());
    let odd = Field::signed(6, 5).unwrap();
    odd.write(&mut img, -3i8).unwrap();
    assert_eq!(odd.read::<i8>(&img).unwrap(), -3);
    assert_eq!(img[0], 0b0100_0000);
    assert_eq!(img[1], 0b0000_0111);
    assert_eq!(torque.read::<i16>(&img).unwrap(), -1234);
}

#[test]
fn booleans_and_bit_fields() {
    let mut img = [0u8; 1];
    let b = Field::unsigned(5, 1).unwrap();
    b.write(&mut img, true).unwrap();
    assert_eq!(img[0], 0b0010_0000);
    assert!(b.read::<bool>(&img).unwrap());
    assert_eq!(b.read::<u8>(&img).unwrap(), 1);
    b.write(&mut img, false).unwrap();
    assert_eq!(img[0], 0);
}
