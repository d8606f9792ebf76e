//! The cycle audit's hooks: from the moment every drive is in OP to the stop request, the
//! allocations the cycle thread makes (with [`CountingAlloc`](crate::rt::audit::CountingAlloc)
//! as the program's global allocator) and its syscalls, all of them and those outside an
//! allowed set (a per-thread perf counter; root or `perf_event_paranoid` ≤ 1). The audit
//! tests install it, and so does an application that wants the evidence
//! (`Master(..., audit=True)` in Python).

use super::CycleHooks;
use crate::rt::audit::{self, AllocCounts, SyscallCounter, SyscallCounts};
use std::sync::{Mutex, MutexGuard};

/// What a window counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SteadyCounts {
    /// Allocations and frees by the cycle thread.
    pub allocs: AllocCounts,
    /// Its syscalls, the counter's own overhead taken off; `None` when they could not be
    /// counted (see [`SteadyAudit::error`]).
    pub syscalls: Option<SyscallCounts>,
}

/// [`CycleHooks`] that count what the cycle thread does in steady state.
pub struct SteadyAudit {
    allowed: &'static [std::ffi::c_long],
    counter: Mutex<Option<SyscallCounter>>,
    base: Mutex<SyscallCounts>,
    counts: Mutex<Option<SteadyCounts>>,
    error: Mutex<Option<String>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl SteadyAudit {
    /// An audit that allows the syscalls `allowed` (syscall numbers, e.g. `libc::SYS_clock_nanosleep`). The
    /// list is static: nothing the hooks allocate is freed inside the window.
    pub fn new(allowed: &'static [std::ffi::c_long]) -> Self {
        Self {
            allowed,
            counter: Mutex::new(None),
            base: Mutex::new(SyscallCounts::default()),
            counts: Mutex::new(None),
            error: Mutex::new(None),
        }
    }

    /// What the window counted, once it closed (`None` before: the drives never all reached
    /// OP, or the stop has not come).
    pub fn counts(&self) -> Option<SteadyCounts> {
        *lock(&self.counts)
    }

    /// Why the syscalls could not be counted (not root, no tracefs), if they could not.
    pub fn error(&self) -> Option<String> {
        lock(&self.error).clone()
    }
}

impl CycleHooks for SteadyAudit {
    fn steady_begin(&self) {
        match SyscallCounter::for_current_thread(self.allowed) {
            Ok(c) => {
                if let Ok(b) = c.overhead() {
                    *lock(&self.base) = b;
                }
                audit::alloc_window_begin();
                c.start();
                *lock(&self.counter) = Some(c);
            }
            Err(e) => {
                *lock(&self.error) = Some(e.to_string());
                audit::alloc_window_begin();
            }
        }
    }

    fn steady_end(&self) {
        let sys = lock(&self.counter).as_ref().map(|c| {
            c.stop();
            c.read().unwrap_or_default()
        });
        let allocs = audit::alloc_window_end();
        let base = *lock(&self.base);
        let syscalls = sys.map(|s| SyscallCounts {
            all: s.all.saturating_sub(base.all),
            outside: s.outside.saturating_sub(base.outside),
        });
        *lock(&self.counts) = Some(SteadyCounts { allocs, syscalls });
    }
}
