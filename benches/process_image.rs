//! Per-cycle cost of packing and unpacking a process image by resolved field handles: the
//! MR-J4-TM default mapping (RxPDO 0x1600, 12 fields in 29 bytes; TxPDO 0x1A00, 14 fields in
//! 41 bytes; most fields at odd byte offsets).
//!
//! Run: `cargo bench --bench process_image`.

use criterion::{Criterion, criterion_group, criterion_main};
use ecdrive::drives::mr_j4_tm;
use ecdrive::od::{DataType, ObjectAddress};
use ecdrive::pdo::{Direction, Field, Layout};
use std::hint::black_box;

/// Resolve one object of the default mapping (types from the manual, §7.3).
fn field(layout: &Layout, dir: Direction, index: u16, t: DataType) -> Field {
    match layout.field(dir, ObjectAddress::new(index, 0), t) {
        Ok(f) => f,
        Err(e) => panic!("default mapping: {e}"),
    }
}

/// The outputs the cycle writes, resolved once at start-up.
struct Outputs {
    mode: Field,
    controlword: Field,
    control_di: [Field; 3],
    target_position: Field,
    target_velocity: Field,
    velocity_limit: Field,
    target_torque: Field,
    torque_limits: [Field; 2],
    touch_probe_function: Field,
}

/// The inputs the cycle reads.
struct Inputs {
    mode_display: Field,
    statusword: Field,
    status_do: [Field; 3],
    position: Field,
    velocity: Field,
    following_error: Field,
    torque: Field,
    touch_probe_status: Field,
    touch_probe_values: [Field; 4],
}

fn bench(c: &mut Criterion) {
    use DataType::{Integer8 as I8, Integer16 as I16, Integer32 as I32};
    use DataType::{Unsigned16 as U16, Unsigned32 as U32};
    let layout = Layout::new(&mr_j4_tm::DEFAULT_MAPPING);
    let rx = |i, t| field(&layout, Direction::Rx, i, t);
    let tx = |i, t| field(&layout, Direction::Tx, i, t);
    let out = Outputs {
        mode: rx(0x6060, I8),
        controlword: rx(0x6040, U16),
        control_di: [rx(0x2D01, U16), rx(0x2D02, U16), rx(0x2D03, U16)],
        target_position: rx(0x607A, I32),
        target_velocity: rx(0x60FF, I32),
        velocity_limit: rx(0x2D20, U32),
        target_torque: rx(0x6071, I16),
        torque_limits: [rx(0x60E0, U16), rx(0x60E1, U16)],
        touch_probe_function: rx(0x60B8, U16),
    };
    let inp = Inputs {
        mode_display: tx(0x6061, I8),
        statusword: tx(0x6041, U16),
        status_do: [tx(0x2D11, U16), tx(0x2D12, U16), tx(0x2D13, U16)],
        position: tx(0x6064, I32),
        velocity: tx(0x606C, I32),
        following_error: tx(0x60F4, I32),
        torque: tx(0x6077, I16),
        touch_probe_status: tx(0x60B9, U16),
        touch_probe_values: [
            tx(0x60BA, I32),
            tx(0x60BB, I32),
            tx(0x60BC, I32),
            tx(0x60BD, I32),
        ],
    };

    let mut outputs = vec![0u8; layout.bytes(Direction::Rx)];
    let mut position: i32 = -1_000_000;
    c.bench_function("pack MR-J4-TM default RxPDO (12 fields, 29 B)", |b| {
        b.iter(|| {
            position = position.wrapping_add(37);
            let o = &mut outputs[..];
            let p = black_box(position);
            let r = (|| {
                out.mode.write(o, 8i8)?;
                out.controlword.write(o, 0x000Fu16)?;
                for f in &out.control_di {
                    f.write(o, 0u16)?;
                }
                out.target_position.write(o, p)?;
                out.target_velocity.write(o, p / 4)?;
                out.velocity_limit.write(o, 50_000u32)?;
                out.target_torque.write(o, -(p % 1000) as i16)?;
                for f in &out.torque_limits {
                    f.write(o, 10_000u16)?;
                }
                out.touch_probe_function.write(o, 0u16)
            })();
            black_box(r).ok();
            black_box(&outputs);
        })
    });

    // An input image as the drive would send it.
    let mut inputs = vec![0u8; layout.bytes(Direction::Tx)];
    for (i, b) in inputs.iter_mut().enumerate() {
        *b = (i as u8).wrapping_mul(73).wrapping_add(11);
    }
    c.bench_function("unpack MR-J4-TM default TxPDO (14 fields, 41 B)", |b| {
        b.iter(|| {
            let img = black_box(&inputs[..]);
            let r = (|| -> Result<i64, ecdrive::pdo::ImageError> {
                let mut acc = i64::from(inp.mode_display.read::<i8>(img)?);
                acc += i64::from(inp.statusword.read::<u16>(img)?);
                for f in &inp.status_do {
                    acc += i64::from(f.read::<u16>(img)?);
                }
                acc += i64::from(inp.position.read::<i32>(img)?);
                acc += i64::from(inp.velocity.read::<i32>(img)?);
                acc += i64::from(inp.following_error.read::<i32>(img)?);
                acc += i64::from(inp.torque.read::<i16>(img)?);
                acc += i64::from(inp.touch_probe_status.read::<u16>(img)?);
                for f in &inp.touch_probe_values {
                    acc += i64::from(f.read::<i32>(img)?);
                }
                Ok(acc)
            })();
            black_box(r).ok();
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
