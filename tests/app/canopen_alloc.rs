//! The cyclic path allocates nothing: after warm-up, master cycles (RPDOs, SYNC, TPDO
//! reception, heartbeat and guarding timers, remote checks), the drive's Axis step and the pp
//! helper run without a single allocation on the calling thread — counted with the crate's
//! allocation counter. (The simulated bus runs on the same thread and is included.)

use crate::canopen_util;

use canopen_util::{T, ready};
use ecdrive::cia402::{ProfilePosition, SetPoint};
use ecdrive::drives::blv_r;
use ecdrive::rt::audit::{alloc_window_begin, alloc_window_end};

#[test]
fn master_cycle_allocates_nothing() {
    let mut m = ready(&blv_r::PROFILE, 3);
    m.switch_mode(3, ecdrive::cia402::OperationMode::ProfilePosition, T)
        .unwrap();
    let mut pp = ProfilePosition::default();
    // Warm-up: queues reach their steady capacity.
    for k in 0..4 {
        pp.push(SetPoint::absolute(9_000 * (k + 1))).unwrap();
    }
    for _ in 0..300 {
        m.cycle_step(|d| {
            let sw = d.statusword();
            pp.step(d.axis_mut(), sw);
        })
        .unwrap();
    }
    for k in 0..4 {
        pp.push(SetPoint::relative(-9_000 * (k + 1)).queued())
            .unwrap();
    }
    while m.poll_event().is_some() {}
    alloc_window_begin();
    for _ in 0..500 {
        m.cycle_step(|d| {
            let sw = d.statusword();
            pp.step(d.axis_mut(), sw);
        })
        .unwrap();
    }
    let counts = alloc_window_end();
    assert_eq!(counts.allocs, 0, "{counts:?}");
    assert!(pp.idle(), "the moves ran meanwhile");
}
