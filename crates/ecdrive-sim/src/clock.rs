//! Time sources for the software slave.
//!
//! Every emulated ESC derives its local DC time from one [`Clock`] shared by the whole segment
//! (plus a per-slave offset and drift), exactly as real slaves on one bus each count their own
//! oscillator. [`HostClock`] reads `CLOCK_MONOTONIC`; [`ManualClock`] is set by tests so that
//! SYNC0 events, watchdogs and DC arithmetic are deterministic.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// A monotonic nanosecond time source.
pub trait Clock: Send + Sync {
    /// The current time in nanoseconds. Must never go backwards.
    fn now_ns(&self) -> u64;
}

/// The host's `CLOCK_MONOTONIC`, in nanoseconds since boot.
#[derive(Debug, Clone, Copy, Default)]
pub struct HostClock;

impl Clock for HostClock {
    fn now_ns(&self) -> u64 {
        match nix::time::clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC) {
            Ok(ts) => (ts.tv_sec() as u64)
                .saturating_mul(1_000_000_000)
                .saturating_add(ts.tv_nsec() as u64),
            // CLOCK_MONOTONIC cannot fail on Linux; fall back to a value that keeps time
            // monotonic rather than panicking.
            Err(_) => 0,
        }
    }
}

/// A clock that only moves when told to. Clones share the same time.
#[derive(Debug, Clone, Default)]
pub struct ManualClock {
    now: Arc<AtomicU64>,
}

impl ManualClock {
    /// A clock starting at `start_ns`.
    pub fn new(start_ns: u64) -> Self {
        Self {
            now: Arc::new(AtomicU64::new(start_ns)),
        }
    }

    /// Move the clock forward by `ns` nanoseconds.
    pub fn advance(&self, ns: u64) {
        self.now.fetch_add(ns, Ordering::SeqCst);
    }

    /// Set the clock to `ns`, if that is not earlier than the current time (a clock never goes
    /// backwards). Returns whether the time was changed.
    pub fn set(&self, ns: u64) -> bool {
        self.now.fetch_max(ns, Ordering::SeqCst) <= ns
    }
}

impl Clock for ManualClock {
    fn now_ns(&self) -> u64 {
        self.now.load(Ordering::SeqCst)
    }
}

impl<C: Clock + ?Sized> Clock for Arc<C> {
    fn now_ns(&self) -> u64 {
        (**self).now_ns()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manual_clock_is_shared_and_monotonic() {
        let c = ManualClock::new(100);
        let c2 = c.clone();
        c.advance(50);
        assert_eq!(c2.now_ns(), 150);
        assert!(!c2.set(10));
        assert_eq!(c.now_ns(), 150);
        assert!(c2.set(1_000));
        assert_eq!(c.now_ns(), 1_000);
    }

    #[test]
    fn host_clock_advances() {
        let a = HostClock.now_ns();
        let b = HostClock.now_ns();
        assert!(a > 0);
        assert!(b >= a);
    }
}
