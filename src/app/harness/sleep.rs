//! The bare sleep loop: the floor of this machine (what `cyclictest` measures). One thread with
//! the same real-time set-up as the master's cycle thread sleeps to absolute instants on a
//! fixed grid with `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)` and records how late it
//! woke. Nothing else.

use super::cpu::{CpuReport, CpuSample, apply_syscalls, start_syscalls};
use super::report::{RunHistograms, RunReport};
use crate::rt::{RtSettings, monotonic_ns, sleep_until_ns};
use std::time::Duration;

/// Cycles run before the window opens (first-touch page faults, cache warm-up).
const WARM_UP: u64 = 10;

/// Run the sleep loop for `cycles` cycles of `cycle` on a new thread set up with `rt`.
/// With `count_syscalls`, the thread's syscalls are counted too ([`super::cpu::SyscallWindow`]).
pub fn run(
    cycle: Duration,
    cycles: u64,
    rt: &RtSettings,
    count_syscalls: bool,
) -> std::io::Result<RunReport> {
    let rt = rt.clone();
    let h = std::thread::Builder::new()
        .name("jitter-sleep".into())
        .spawn(move || measure(cycle, cycles, &rt, count_syscalls))?;
    h.join()
        .map_err(|_| std::io::Error::other("the sleep-loop thread panicked"))
}

fn measure(cycle: Duration, cycles: u64, rt: &RtSettings, count_syscalls: bool) -> RunReport {
    let report = rt.apply_to_current_thread();
    let cycle_ns = cycle.as_nanos() as u64;
    let mut h = RunHistograms::new(false);
    let mut late = 0u64;
    let mut next = monotonic_ns() + cycle_ns;
    let mut last_wake = 0u64;
    let mut begin = CpuSample::default();
    let mut notes = Vec::new();
    let mut sys = None;
    for i in 0..WARM_UP + cycles {
        if i == WARM_UP {
            begin = CpuSample::take(None);
            sys = start_syscalls(count_syscalls, &mut notes);
        }
        sleep_until_ns(next);
        let woke = monotonic_ns();
        if i >= WARM_UP {
            let latency = woke.saturating_sub(next);
            h.wake_latency.record(latency);
            if last_wake != 0 {
                h.period.record(woke - last_wake);
            }
            if latency > cycle_ns {
                late += 1;
            }
        }
        last_wake = woke;
        next += cycle_ns;
        // Fell behind by whole cycles: skip the instants already past (they count as late).
        while next <= woke {
            next += cycle_ns;
        }
        if i >= WARM_UP {
            h.busy.record(monotonic_ns() - woke);
        }
    }
    let sys_end = sys.map(|w| w.stop());
    let end = CpuSample::take(None);
    let cpu = apply_syscalls(
        sys_end,
        CpuReport::between(&begin, &end, cycles),
        &mut notes,
    );
    h.report(
        "sleep",
        cycle_ns,
        report,
        late,
        None,
        cpu,
        Vec::new(),
        notes,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cycle_is_recorded() {
        let r = run(
            Duration::from_micros(500),
            50,
            &RtSettings::default(),
            false,
        )
        .unwrap();
        assert_eq!(r.cycles, 50);
        // The first measured wake-up has a predecessor in the warm-up.
        assert_eq!(r.period.count, 50);
        assert_eq!(r.busy.count, 50);
        assert!(r.exchange.is_none() && r.missed.is_none());
        assert!(r.cpu.cycle_thread_ns.is_some());
        assert_eq!(r.cpu.cycles, 50);
    }
}
