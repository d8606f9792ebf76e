//! The emulated ESC's opt-in timing statistics that `ecdrive jitter` reads after a run, checked
//! on a manual clock: frame arrival after SYNC0, SYNC0 pulses without fresh outputs, and the DC
//! system-time difference after each drift-compensation write, all in OP only.

use ecdrive_core::ec::Command;
use ecdrive_sim::devices::IoDevice;
use ecdrive_sim::probe::{Probe, Request};
use ecdrive_sim::{EscConfig, ManualClock, Segment};
use std::sync::Arc;

const OUT: u16 = 2;
const IN: u16 = 4;
const CYCLE: u64 = 1_000_000;
const N: u16 = 2;

/// Two I/O slaves in OP with SYNC0 every `CYCLE` from `start`; returns the probe, the clock and
/// the first SYNC0 instant.
fn in_op(stats: bool) -> (Probe, ManualClock, u64) {
    let clock = ManualClock::new(1_000_000_000);
    let mut seg = Segment::new(Arc::new(clock.clone()));
    for _ in 0..N {
        let at = seg
            .push(
                Box::new(IoDevice::new(OUT.into(), IN.into())),
                EscConfig {
                    sm_watchdog: 0,
                    ..Default::default()
                },
            )
            .unwrap();
        if stats {
            seg.slave_mut(at).unwrap().esc.enable_timing_stats();
        }
    }
    let mut p = Probe::new(seg);
    p.assign_addresses(0x1000).unwrap();
    let inputs = u32::from(N) * u32::from(IN);
    let mut start = 0;
    for i in 0..N {
        let st = 0x1000 + i;
        p.fpwr(st, 0x0800, &[0x00, 0x10, OUT as u8, 0, 0x64, 0, 1, 0])
            .unwrap();
        p.fpwr(st, 0x0808, &[0x00, 0x18, IN as u8, 0, 0x20, 0, 1, 0])
            .unwrap();
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
        p.fpwr(
            st,
            0x0600,
            &fmmu(inputs + u32::from(i * OUT), OUT, 0x1000, 2),
        )
        .unwrap();
        p.fpwr(st, 0x0610, &fmmu(u32::from(i * IN), IN, 0x1800, 1))
            .unwrap();
        p.fpwr(st, 0x0120, &[0x02, 0]).unwrap();
        let now = p.fprd(st, 0x0910, 8).unwrap().data;
        start = u64::from_le_bytes(now[..8].try_into().unwrap()) + CYCLE;
        p.fpwr(st, 0x0990, &start.to_le_bytes()).unwrap();
        p.fpwr(st, 0x09A0, &(CYCLE as u32).to_le_bytes()).unwrap();
        p.fpwr(st, 0x0981, &[0x03]).unwrap();
        p.fpwr(st, 0x0120, &[0x04, 0]).unwrap();
        p.fpwr(st, 0x0120, &[0x08, 0]).unwrap();
    }
    assert_eq!(p.brd(0x0130, 2).unwrap().data, vec![0x08, 0], "all in OP");
    (p, clock, start)
}

/// The cyclic frame: process data and the drift compensation from the reference clock.
/// Returns the LRW's working counter.
fn cyclic(p: &mut Probe) -> u16 {
    let image = vec![0u8; usize::from(N * (IN + OUT))];
    let r = p
        .frame(&[
            Request::logical(Command::Lrw, 0, &image),
            Request::physical(Command::Frmw, 0x1000, 0x0910, &[0; 8]),
        ])
        .unwrap();
    r[0].wkc
}

#[test]
fn arrival_after_sync0_missing_outputs_and_dc_difference_in_op() {
    let (mut p, clock, start) = in_op(true);
    // Ten cycles, the frame 40 µs after each SYNC0; no frame in cycle 5.
    for k in 0..10u64 {
        if k == 5 {
            continue;
        }
        assert!(clock.set(start + k * CYCLE + 40_000));
        assert_eq!(cyclic(&mut p), 3 * N, "LRW in OP");
    }
    for pos in 0..usize::from(N) {
        let t = p.segment.slave(pos).unwrap().esc.timing_stats().unwrap();
        // Nine frames, each 40 µs after its SYNC0 (plus the hop delays along the line).
        let a = &t.arrival_after_sync0;
        assert_eq!(a.len(), 9, "slave {pos}");
        assert!(
            (39_500..=41_000).contains(&a.min()) && (39_500..=41_000).contains(&a.max()),
            "slave {pos}: {} … {} ns",
            a.min(),
            a.max()
        );
        // Pulses 0…9 were delivered in OP; pulse 0 came before any outputs and pulse 6 after
        // the missing cycle.
        assert_eq!(t.sync0_pulses, 10, "slave {pos}");
        assert_eq!(t.sync0_without_outputs, 2, "slave {pos}");
    }
    // The reference clock compares with nobody; the second slave once per FRMW.
    let t0 = p.segment.slave(0).unwrap().esc.timing_stats().unwrap();
    let t1 = p.segment.slave(1).unwrap().esc.timing_stats().unwrap();
    assert!(t0.dc_difference.is_empty());
    assert_eq!(t1.dc_difference.len(), 9);
}

#[test]
fn nothing_is_recorded_outside_op_or_when_not_enabled() {
    let (mut p, clock, start) = in_op(false);
    assert!(clock.set(start + 40_000));
    cyclic(&mut p);
    assert!(p.segment.slave(0).unwrap().esc.timing_stats().is_none());

    let (mut p, clock, start) = in_op(true);
    // Back to SAFE-OP: frames and pulses there do not count.
    for st in [0x1000u16, 0x1001] {
        p.fpwr(st, 0x0120, &[0x04, 0]).unwrap();
    }
    for k in 0..3u64 {
        assert!(clock.set(start + k * CYCLE + 40_000));
        // SAFE-OP: inputs read and outputs written (slave stacks take them from SAFE-OP on,
        // ETG.1020), and still nothing recorded.
        assert_eq!(cyclic(&mut p), 3 * N, "LRW in SAFE-OP");
    }
    let t = p.segment.slave(1).unwrap().esc.timing_stats().unwrap();
    assert!(t.arrival_after_sync0.is_empty() && t.dc_difference.is_empty());
    assert_eq!((t.sync0_pulses, t.sync0_without_outputs), (0, 0));
    // Enabling again resets.
    p.segment.slave_mut(1).unwrap().esc.enable_timing_stats();
    assert_eq!(
        p.segment
            .slave(1)
            .unwrap()
            .esc
            .timing_stats()
            .unwrap()
            .sync0_pulses,
        0
    );
}
