//! `CLOCK_MONOTONIC` in nanoseconds, and absolute-time sleeping.

use nix::sys::time::TimeSpec;
use nix::time::{ClockId, ClockNanosleepFlags, clock_gettime, clock_nanosleep};

/// The current `CLOCK_MONOTONIC` time in nanoseconds. Read through the vDSO: no syscall on
/// common clock sources.
pub fn monotonic_ns() -> u64 {
    match clock_gettime(ClockId::CLOCK_MONOTONIC) {
        Ok(ts) => ts.tv_sec() as u64 * 1_000_000_000 + ts.tv_nsec() as u64,
        // CLOCK_MONOTONIC cannot fail on Linux; fall back to std's monotonic clock anyway.
        Err(_) => {
            static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
            START
                .get_or_init(std::time::Instant::now)
                .elapsed()
                .as_nanos() as u64
        }
    }
}

/// Sleep until the absolute `CLOCK_MONOTONIC` instant `deadline_ns`. Returns at once if it has
/// passed. Restarts after signals (EINTR) with the same absolute deadline, so it never returns
/// early.
pub fn sleep_until_ns(deadline_ns: u64) {
    let ts = TimeSpec::new(
        (deadline_ns / 1_000_000_000) as libc::time_t,
        (deadline_ns % 1_000_000_000) as libc::c_long,
    );
    loop {
        match clock_nanosleep(
            ClockId::CLOCK_MONOTONIC,
            ClockNanosleepFlags::TIMER_ABSTIME,
            &ts,
        ) {
            Err(nix::errno::Errno::EINTR) => continue,
            _ => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleep_until_never_returns_early() {
        let t0 = monotonic_ns();
        let deadline = t0 + 2_000_000;
        sleep_until_ns(deadline);
        assert!(monotonic_ns() >= deadline);
        // A deadline in the past returns at once (no assertion on how fast: machines are noisy).
        sleep_until_ns(t0);
    }
}
