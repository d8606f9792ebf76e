//! Datagrams per second through an emulated segment: 2 and 64 I/O slaves in OP with DC SYNC0,
//! processing the cyclic frame ethercrab sends (FRMW of the reference clock, one LRW over the
//! process image, one FPRD of AL status per slave), with the clock advancing one 1 ms cycle per
//! frame so that every frame also delivers a SYNC0 event to every device.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ecdrive::ec::Command;
use ecdrive::ec::frame::{FrameBuilder, MAX_FRAME_LEN, physical_address};
use ecdrive::sim::devices::IoDevice;
use ecdrive::sim::probe::{PROBE_MAC, Probe};
use ecdrive::sim::{EscConfig, ManualClock, Segment};
use std::hint::black_box;
use std::sync::Arc;

const OUT: u16 = 2;
const IN: u16 = 4;
const CYCLE: u64 = 1_000_000;

fn segment_in_op(n: u16) -> (Segment, ManualClock, Vec<u8>, usize) {
    let clock = ManualClock::new(1_000_000_000);
    let mut seg = Segment::new(Arc::new(clock.clone()));
    for _ in 0..n {
        seg.push(
            Box::new(IoDevice::new(OUT.into(), IN.into())),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .expect("slave");
    }
    let mut p = Probe::new(seg);
    p.assign_addresses(0x1000).expect("addresses");
    // Image: all inputs first, then all outputs (as ethercrab lays it out).
    let inputs = u32::from(n) * u32::from(IN);
    for i in 0..n {
        let st = 0x1000 + i;
        p.fpwr(st, 0x0800, &[0x00, 0x10, OUT as u8, 0, 0x64, 0, 1, 0])
            .expect("SM0");
        p.fpwr(st, 0x0808, &[0x00, 0x18, IN as u8, 0, 0x20, 0, 1, 0])
            .expect("SM1");
        let fmmu = |log: u32, len: u16, phys: u16, ty: u8| {
            let mut f = [0u8; 16];
            f[0..4].copy_from_slice(&log.to_le_bytes());
            f[4..6].copy_from_slice(&len.to_le_bytes());
            f[7] = 7;
            f[8..10].copy_from_slice(&phys.to_le_bytes());
            f[11] = ty;
            f[12] = 1;
            f
        };
        let out_log = inputs + u32::from(i) * u32::from(OUT);
        p.fpwr(st, 0x0600, &fmmu(out_log, OUT, 0x1000, 2))
            .expect("FMMU0");
        p.fpwr(
            st,
            0x0610,
            &fmmu(u32::from(i) * u32::from(IN), IN, 0x1800, 1),
        )
        .expect("FMMU1");
        p.fpwr(st, 0x0120, &[0x02, 0]).expect("PREOP");
        let now = p.fprd(st, 0x0910, 8).expect("time").data;
        let start = u64::from_le_bytes(now[..8].try_into().unwrap_or([0; 8])) + CYCLE;
        p.fpwr(st, 0x0990, &start.to_le_bytes()).expect("start");
        p.fpwr(st, 0x09A0, &CYCLE.to_le_bytes()).expect("cycle");
        p.fpwr(st, 0x0981, &[0x03]).expect("activate");
        p.fpwr(st, 0x0120, &[0x04, 0]).expect("SAFEOP");
        p.fpwr(st, 0x0120, &[0x08, 0]).expect("OP");
    }
    let r = p.brd(0x0130, 2).expect("state");
    assert_eq!(r.data, vec![0x08, 0], "all in OP");

    let mut frame = vec![0u8; MAX_FRAME_LEN];
    let image = vec![0u8; (u32::from(n) * u32::from(IN + OUT)) as usize];
    let mut b = FrameBuilder::new(&mut frame, PROBE_MAC).expect("frame");
    b.push(Command::Frmw, 0, physical_address(0x1000, 0x0910), &[0; 8])
        .expect("FRMW");
    b.push(Command::Lrw, 1, 0, &image).expect("LRW");
    for i in 0..n {
        b.push(
            Command::Fprd,
            2,
            physical_address(0x1000 + i, 0x0130),
            &[0; 2],
        )
        .expect("FPRD");
    }
    let len = b.finish();
    let datagrams = 2 + usize::from(n);
    (p.segment, clock, frame[..len].to_vec(), datagrams)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("sim_cyclic_frame");
    for n in [2u16, 64] {
        let (mut seg, clock, frame, datagrams) = segment_in_op(n);
        let mut buf = frame.clone();
        // Check once that the frame does what it should: WKC of the LRW = 3 per slave.
        buf.copy_from_slice(&frame);
        seg.process(&mut buf).expect("cyclic frame");
        let lrw_wkc_at = 14 + 2 + (10 + 8 + 2) + 10 + usize::from(n) * usize::from(IN + OUT);
        assert_eq!(
            u16::from_le_bytes([buf[lrw_wkc_at], buf[lrw_wkc_at + 1]]),
            3 * n,
            "LRW working counter"
        );
        g.throughput(Throughput::Elements(datagrams as u64));
        g.bench_function(format!("{n}_slaves"), |b| {
            b.iter(|| {
                clock.advance(CYCLE);
                buf.copy_from_slice(&frame);
                black_box(seg.process(black_box(&mut buf)).expect("processed"));
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
