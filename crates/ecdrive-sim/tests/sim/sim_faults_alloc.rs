//! Injecting faults allocates nothing on the frame path: two emulated drives in OP with DC,
//! cyclic frames through the synchronous `SegmentLink` (as on a master's cycle thread) while
//! every kind of fault is pushed through the lock-free handle and applied by the segment.

use crate::support::wire;

use ecdrive_core::drives::{bdhde, mr_j4_tm};
use ecdrive_core::ec::Command;
use ecdrive_core::ec::frame::{FrameBuilder, MAX_FRAME_LEN};
use ecdrive_core::link::FrameLink;
use ecdrive_core::rt::audit::{alloc_window_begin, alloc_window_end};
use ecdrive_sim::faults::{Corruption, DeviceFault, DropLeg, Fault, LinkFault, SlaveFault};
use ecdrive_sim::probe::PROBE_MAC;
use ecdrive_sim::transport::SegmentLink;
use std::time::Duration;
use wire::Wire;

#[test]
fn applying_faults_allocates_nothing() {
    let w = Wire::op_cyclic(&[&mr_j4_tm::PROFILE, &bdhde::PROFILE], 1_000_000);
    let clock = w.clock.clone();
    let mut frame = vec![0u8; MAX_FRAME_LEN];
    let mut b = FrameBuilder::new(&mut frame, PROBE_MAC).unwrap();
    b.push(Command::Lrw, 1, 0, &w.image).unwrap();
    let len = b.finish();
    frame.truncate(len);
    let mut seg = w.p.segment;
    let mut h = seg.fault_handle();
    let mut link = SegmentLink::new(seg);
    let mut rx = vec![0u8; MAX_FRAME_LEN];
    // Warm up.
    for _ in 0..5 {
        link.send(&frame).unwrap();
        link.recv(&mut rx, Some(Duration::ZERO)).unwrap();
        clock.advance(1_000_000);
    }
    let dev = |position, fault| Fault::Device { position, fault };
    let faults = [
        Fault::Link(LinkFault::Seed(9)),
        Fault::Link(LinkFault::DropFraction(0.2)),
        Fault::Link(LinkFault::DropOn(DropLeg::Return)),
        Fault::Link(LinkFault::DropNext(2)),
        Fault::Link(LinkFault::Delay {
            fraction: 0.3,
            delay_ns: 300_000,
        }),
        Fault::Link(LinkFault::CorruptWith(Corruption::Index)),
        Fault::Link(LinkFault::CorruptNext(3)),
        Fault::Link(LinkFault::Disconnect),
        Fault::Link(LinkFault::Reconnect),
        Fault::Slave {
            position: 1,
            fault: SlaveFault::ClockDrift(30_000),
        },
        dev(0, DeviceFault::ForceFollowingError(Some(100_000))),
        dev(0, DeviceFault::ForceFollowingError(None)),
        dev(
            1,
            DeviceFault::Emergency {
                error_code: 0xFF00,
                error_register: 0x81,
                data: [0; 5],
            },
        ),
        dev(
            0,
            DeviceFault::AbortSdo {
                index: 0x6060,
                subindex: None,
                code: 0x0800_0022,
            },
        ),
        dev(
            1,
            DeviceFault::EmergencyDuringSdo {
                error_code: 0xFF01,
                error_register: 0x81,
                data: [0; 5],
            },
        ),
        dev(0, DeviceFault::RaiseAlarm("AL.52")),
        dev(1, DeviceFault::RaiseAlarm("AL.NOPE")),
        Fault::Slave {
            position: 1,
            fault: SlaveFault::ResetToInit,
        },
        Fault::Link(LinkFault::DropFraction(0.0)),
        Fault::Link(LinkFault::Delay {
            fraction: 0.0,
            delay_ns: 0,
        }),
    ];
    alloc_window_begin();
    let mut replies = 0u32;
    for (i, f) in faults.iter().cycle().take(200).enumerate() {
        h.inject(*f).unwrap();
        link.send(&frame).unwrap();
        while let Some(n) = link.recv(&mut rx, Some(Duration::ZERO)).unwrap() {
            replies += u32::from(n == frame.len());
        }
        clock.advance(if i % 7 == 0 { 400_000 } else { 1_000_000 });
    }
    let counts = alloc_window_end();
    assert_eq!(counts.allocs, 0, "{counts:?}");
    assert_eq!(counts.frees, 0, "{counts:?}");
    let s = link.segment().stats();
    // Every kind of link fault happened, and replies still came.
    assert!(s.dropped > 0 && s.dropped_replies > 0, "{s:?}");
    assert!(
        s.delayed > 0 && s.corrupted > 0 && s.lost_disconnected > 0,
        "{s:?}"
    );
    assert!(replies > 100, "{replies} replies");
    // 200 faults: the unknown alarm name ten times is the only one ignored.
    assert_eq!((s.faults_applied, s.faults_ignored), (190, 10), "{s:?}");
}
