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

/// Wait up to `timeout_us` µs for `fd` to become readable (`ppoll`, one syscall); `Ok(false)`
/// on timeout or a signal. The receive paths of the transports use it with a non-blocking
/// socket, so a cycle's wait costs one `ppoll` and one receive, no socket option per call.
pub fn wait_readable(fd: std::os::fd::BorrowedFd<'_>, timeout_us: u64) -> std::io::Result<bool> {
    wait_fd(fd, nix::poll::PollFlags::POLLIN, timeout_us)
}

/// Wait up to `timeout_us` µs for `fd` to take a write (`ppoll`): a non-blocking socket whose
/// peer's queue is full.
pub fn wait_writable(fd: std::os::fd::BorrowedFd<'_>, timeout_us: u64) -> std::io::Result<bool> {
    wait_fd(fd, nix::poll::PollFlags::POLLOUT, timeout_us)
}

fn wait_fd(
    fd: std::os::fd::BorrowedFd<'_>,
    events: nix::poll::PollFlags,
    timeout_us: u64,
) -> std::io::Result<bool> {
    use nix::poll::{PollFd, ppoll};
    let mut fds = [PollFd::new(fd, events)];
    let ts = TimeSpec::from_duration(std::time::Duration::from_micros(timeout_us));
    match ppoll(&mut fds, Some(ts), None) {
        Ok(n) => Ok(n > 0),
        Err(nix::errno::Errno::EINTR) => Ok(false),
        Err(e) => Err(std::io::Error::from_raw_os_error(e as i32)),
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
