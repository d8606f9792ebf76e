//! Proof that the cycle, once the drives are in OP, allocates nothing and makes no syscall but
//! the sleep (in-process link: the frame I/O is a function call).
//!
//! A counting global allocator counts allocations made by the cycle thread inside a window; a
//! per-thread perf counter on the `raw_syscalls:sys_enter` tracepoint counts the cycle
//! thread's syscalls, and those outside the allowed set. The window opens when every drive is
//! in OP and closes when the stop command arrives; the hooks run on the cycle thread.

mod support {
    pub mod generic;
}
use ecdrive::master::cycle::CycleHooks;
use ecdrive::master::session::{Master, MasterConfig};
use ecdrive::master::startup::{DriveSetup, Selector};
use ecdrive::master::telemetry::StopKind;
use ecdrive::rt::audit::{
    self, AllocCounts, CountingAlloc, SyscallCounter, SyscallCounts, skip_or_fail,
};
use ecdrive::sim::transport::SegmentLink;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use support::generic::{GENERIC_TEST, generic_segment};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

#[derive(Default)]
struct Audit {
    counter: Mutex<Option<SyscallCounter>>,
    base: Mutex<SyscallCounts>,
    result: Mutex<Option<(AllocCounts, SyscallCounts)>>,
    error: Mutex<Option<String>>,
}

impl CycleHooks for Audit {
    fn steady_begin(&self) {
        match SyscallCounter::for_current_thread(&[libc::SYS_clock_nanosleep]) {
            Ok(c) => {
                if let Ok(b) = c.overhead() {
                    *self.base.lock().unwrap() = b;
                }
                audit::alloc_window_begin();
                c.start();
                *self.counter.lock().unwrap() = Some(c);
            }
            Err(e) => {
                *self.error.lock().unwrap() = Some(e.to_string());
                audit::alloc_window_begin();
            }
        }
    }

    fn steady_end(&self) {
        let guard = self.counter.lock().unwrap();
        let counts = match guard.as_ref() {
            Some(c) => {
                c.stop();
                c.read().unwrap_or_default()
            }
            None => SyscallCounts::default(),
        };
        let allocs = audit::alloc_window_end();
        *self.result.lock().unwrap() = Some((allocs, counts));
    }
}

#[test]
fn steady_cycle_allocates_nothing_and_only_sleeps() {
    let audit = Arc::new(Audit::default());
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    // No supervisory mailbox traffic during the window: its replies wake another thread.
    cfg.emergency_poll = None;
    cfg.hooks = Some(audit.clone());
    for p in 0..2 {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            ..DriveSetup::new(Selector::Position(p))
        });
    }
    let mut m = Master::start(SegmentLink::new(generic_segment(2)), cfg).unwrap();
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let c0 = m.telemetry().cycle.cycle;
    m.wait_until("300 cycles in OP", Duration::from_secs(20), |t| {
        t.cycle.cycle > c0 + 300
    })
    .unwrap();
    let (report, _) = m.stop(StopKind::Ramp);
    assert!(report.unwrap().shutdown_ok);

    let (allocs, sys) = audit
        .result
        .lock()
        .unwrap()
        .take()
        .expect("the window closed");
    assert_eq!(
        allocs,
        AllocCounts::default(),
        "the cycle allocated in steady state"
    );
    if let Some(e) = audit.error.lock().unwrap().take() {
        skip_or_fail(&format!("syscall audit of the cycle: {e}"));
        return;
    }
    let base = *audit.base.lock().unwrap();
    let outside = sys.outside - base.outside;
    let all = sys.all - base.all;
    assert_eq!(
        outside, 0,
        "syscalls other than clock_nanosleep: {sys:?} (base {base:?})"
    );
    // One sleep per cycle: at least the 300 cycles we waited for.
    assert!(all >= 300, "{sys:?}");
}
