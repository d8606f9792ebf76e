//! The cyclic path of the software slave allocates nothing and makes no syscalls: a 64-slave
//! segment (I/O and CoE devices, in OP with DC SYNC0) processes cyclic frames through
//! `Segment::process` and through the synchronous `SegmentLink`, with every frame delivering a
//! SYNC0 event to every device.

use ecdrive_core::ec::Command;
use ecdrive_core::ec::frame::{FrameBuilder, MAX_FRAME_LEN, physical_address};
use ecdrive_core::link::FrameLink;
use ecdrive_core::rt::audit::{SyscallCounter, alloc_window_begin, alloc_window_end, skip_or_fail};
use ecdrive_sim::devices::{GenericCoeDevice, IoDevice};
use ecdrive_sim::probe::{PROBE_MAC, Probe};
use ecdrive_sim::transport::SegmentLink;
use ecdrive_sim::{Clock, Device, EscConfig, HostClock, ManualClock, Segment};
use std::sync::Arc;

const N: u16 = 64;
const CYCLE: u64 = 1_000_000;

fn fmmu(log: u32, len: u16, phys: u16, ty: u8) -> [u8; 16] {
    let mut f = [0u8; 16];
    f[0..4].copy_from_slice(&log.to_le_bytes());
    f[4..6].copy_from_slice(&len.to_le_bytes());
    f[7] = 7;
    f[8..10].copy_from_slice(&phys.to_le_bytes());
    f[11] = ty;
    f[12] = 1;
    f
}

/// Even positions: I/O devices (2 out / 4 in); odd: CoE devices (6 out / 6 in, default
/// mapping). All in OP with SYNC0 every `CYCLE`. Returns the probe and the cyclic frames (as a
/// master splits them: FRMW + LRW, then the AL status reads).
fn segment_in_op(clock: Arc<dyn Clock>) -> (Probe, Vec<u8>, Vec<u8>) {
    let mut seg = Segment::new(clock);
    for i in 0..N {
        let dev: Box<dyn Device> = if i % 2 == 0 {
            Box::new(IoDevice::new(2, 4))
        } else {
            Box::new(GenericCoeDevice::new(u32::from(i)).unwrap())
        };
        seg.push(
            dev,
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    let mut p = Probe::new(seg);
    p.assign_addresses(0x1000).unwrap();
    let mut log = 0u32;
    for i in 0..N {
        let st = 0x1000 + i;
        let (out, inp, out_at, in_at, fo, fi) = if i % 2 == 0 {
            (2u16, 4u16, 0x1000u16, 0x1800u16, 0x0800u16, 0x0808u16)
        } else {
            let mbx = [
                0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
            ];
            assert_eq!(p.fpwr(st, 0x0800, &mbx).unwrap().wkc, 1);
            (6, 6, 0x1100, 0x1400, 0x0810, 0x0818)
        };
        let mut sm = [0u8; 8];
        sm[0..2].copy_from_slice(&out_at.to_le_bytes());
        sm[2..4].copy_from_slice(&out.to_le_bytes());
        sm[4] = 0x64;
        sm[6] = 1;
        p.fpwr(st, fo, &sm).unwrap();
        sm[0..2].copy_from_slice(&in_at.to_le_bytes());
        sm[2..4].copy_from_slice(&inp.to_le_bytes());
        sm[4] = 0x20;
        p.fpwr(st, fi, &sm).unwrap();
        p.fpwr(st, 0x0600, &fmmu(log, out, out_at, 2)).unwrap();
        p.fpwr(st, 0x0610, &fmmu(log + u32::from(out), inp, in_at, 1))
            .unwrap();
        log += u32::from(out + inp);
        assert_eq!(p.request_state(st, 0x0002).unwrap(), (0x0002, 0));
        let now = p.fprd(st, 0x0910, 8).unwrap().data;
        let start = u64::from_le_bytes(now[..8].try_into().unwrap()) + CYCLE;
        p.fpwr(st, 0x0990, &start.to_le_bytes()).unwrap();
        p.fpwr(st, 0x09A0, &CYCLE.to_le_bytes()).unwrap();
        p.fpwr(st, 0x0981, &[0x03]).unwrap();
        assert_eq!(p.request_state(st, 0x0004).unwrap(), (0x0004, 0));
        assert_eq!(p.request_state(st, 0x0008).unwrap(), (0x0008, 0));
    }
    let mut frame = vec![0u8; MAX_FRAME_LEN];
    let mut b = FrameBuilder::new(&mut frame, PROBE_MAC).unwrap();
    b.push(Command::Frmw, 0, physical_address(0x1000, 0x0910), &[0; 8])
        .unwrap();
    b.push(Command::Lrw, 1, 0, &vec![0u8; log as usize])
        .unwrap();
    let len = b.finish();
    frame.truncate(len);
    let mut states = vec![0u8; MAX_FRAME_LEN];
    let mut b = FrameBuilder::new(&mut states, PROBE_MAC).unwrap();
    for i in 0..N {
        b.push(
            Command::Fprd,
            2,
            physical_address(0x1000 + i, 0x0130),
            &[0; 2],
        )
        .unwrap();
    }
    let len = b.finish();
    states.truncate(len);
    (p, frame, states)
}

#[test]
fn cyclic_frames_allocate_nothing() {
    let clock = ManualClock::new(1_000_000_000);
    let (p, frame, states) = segment_in_op(Arc::new(clock.clone()));
    let mut seg = p.segment;
    let mut buf = frame.clone();
    let mut sbuf = states.clone();
    // Warm up: buffers that grow once (outputs latch, scratch) reach their size.
    for _ in 0..5 {
        clock.advance(CYCLE);
        buf.copy_from_slice(&frame);
        seg.process(&mut buf).unwrap();
        sbuf.copy_from_slice(&states);
        seg.process(&mut sbuf).unwrap();
    }
    alloc_window_begin();
    for _ in 0..200 {
        clock.advance(CYCLE);
        buf.copy_from_slice(&frame);
        seg.process(&mut buf).unwrap();
        sbuf.copy_from_slice(&states);
        seg.process(&mut sbuf).unwrap();
    }
    let counts = alloc_window_end();
    assert_eq!(counts.allocs, 0, "{counts:?}");
    assert_eq!(counts.frees, 0, "{counts:?}");
    // Every frame was a full cycle: one SYNC0 per device per frame, outputs fresh.
    let io = seg.device::<IoDevice>(0).unwrap();
    assert!(io.seen.sync0_events >= 200);
    let coe = seg.device::<GenericCoeDevice>(1).unwrap();
    assert!(coe.seen.sync0_events >= 200);
    assert_eq!(
        coe.seen.missed_in_op, 1,
        "only the first pulse, before any frame"
    );

    // The same through the synchronous in-process link.
    let mut link = SegmentLink::new(seg);
    let mut rx = vec![0u8; MAX_FRAME_LEN];
    clock.advance(CYCLE);
    link.send(&frame).unwrap();
    link.recv(&mut rx, None).unwrap();
    alloc_window_begin();
    for _ in 0..200 {
        clock.advance(CYCLE);
        link.send(&frame).unwrap();
        let n = link.recv(&mut rx, None).unwrap();
        assert_eq!(n, Some(frame.len()));
    }
    let counts = alloc_window_end();
    assert_eq!(counts.allocs, 0, "{counts:?}");
    // LRW working counter: 3 per device.
    let lrw_wkc_at = frame.len() - 2;
    assert_eq!(
        u16::from_le_bytes([rx[lrw_wkc_at], rx[lrw_wkc_at + 1]]),
        3 * N
    );
}

#[test]
fn cyclic_frames_make_no_syscalls() {
    let counter = match SyscallCounter::for_current_thread(&[]) {
        Ok(c) => c,
        Err(e) => {
            skip_or_fail(&format!("sim_cycle_audit: {e}"));
            return;
        }
    };
    // The host clock: reading CLOCK_MONOTONIC must go through the vDSO.
    let (p, frame, states) = segment_in_op(Arc::new(HostClock));
    let mut link = SegmentLink::new(p.segment);
    let mut rx = vec![0u8; MAX_FRAME_LEN];
    // Warm up over a few SYNC0 periods of host time (1 ms): the buffers that grow once, at
    // the first SYNC0 event (the devices' output latches), reach their size.
    let warm_until = std::time::Instant::now() + std::time::Duration::from_millis(5);
    while std::time::Instant::now() < warm_until {
        link.send(&frame).unwrap();
        link.send(&states).unwrap();
        link.recv(&mut rx, None).unwrap();
        link.recv(&mut rx, None).unwrap();
    }
    let overhead = counter.overhead().unwrap();
    counter.start();
    for _ in 0..200 {
        link.send(&frame).unwrap();
        link.send(&states).unwrap();
        link.recv(&mut rx, None).unwrap();
        link.recv(&mut rx, None).unwrap();
    }
    counter.stop();
    let c = counter.read().unwrap();
    assert!(
        c.all <= overhead.all,
        "{} syscalls in 200 cycles (overhead {})",
        c.all,
        overhead.all
    );
}
