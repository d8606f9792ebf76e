//! The cycle audit with Python attached (`Master(..., audit=True)`): the allocations the cycle
//! thread makes and the syscalls it makes outside the sleep and the frame I/O, counted from the
//! moment every drive is in OP to the stop, as the Rust audit tests count them
//! (`crates/ecdrive-ethercat/tests/ethercat/cycle_audit.rs`). The extension's global
//! allocator is the counting one: every allocation of Rust code in the extension, the cycle's
//! included, passes through it (Python's own allocations do not, and need not: the cycle
//! never calls Python).

use ecdrive::master::cycle::CycleHooks;
use ecdrive::rt::audit::{self, AllocCounts, SyscallCounter, SyscallCounts};
use std::sync::Mutex;

/// What the audit found, for the stop's summary.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct AuditResult {
    /// Allocations and frees by the cycle thread in steady state.
    pub allocs: u64,
    pub frees: u64,
    /// Its syscalls in steady state, all of them and those outside the allowed set (the
    /// counter's own overhead taken off); None when they could not be counted.
    pub syscalls: Option<u64>,
    pub syscalls_outside: Option<u64>,
    /// The syscalls allowed: the sleep, the futex that hands a mailbox reply to the session
    /// thread, and a raw socket's frame I/O.
    pub allowed: Vec<&'static str>,
    /// Why the syscalls could not be counted (not root, no tracefs).
    pub error: Option<String>,
    /// Whether the window opened and closed (every drive reached OP, then the stop came).
    pub complete: bool,
}

const ALLOWED: [libc::c_long; 6] = [
    libc::SYS_clock_nanosleep,
    libc::SYS_futex,
    libc::SYS_sendto,
    libc::SYS_recvfrom,
    libc::SYS_poll,
    libc::SYS_ppoll,
];
const ALLOWED_NAMES: [&str; 6] = [
    "clock_nanosleep",
    "futex",
    "sendto",
    "recvfrom",
    "poll",
    "ppoll",
];

/// The hooks the cycle thread calls.
#[derive(Default)]
pub struct Audit {
    counter: Mutex<Option<SyscallCounter>>,
    base: Mutex<SyscallCounts>,
    result: Mutex<Option<(AllocCounts, Option<SyscallCounts>)>>,
    error: Mutex<Option<String>>,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl CycleHooks for Audit {
    fn steady_begin(&self) {
        // Nothing is allocated here that would be freed inside the window (a list of the
        // allowed syscalls built here would be, when this function returns).
        match SyscallCounter::for_current_thread(&ALLOWED) {
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
        let counts = lock(&self.counter).as_ref().map(|c| {
            c.stop();
            c.read().unwrap_or_default()
        });
        let allocs = audit::alloc_window_end();
        *lock(&self.result) = Some((allocs, counts));
    }
}

impl Audit {
    /// What the window counted (after the cycle stopped).
    pub fn result(&self) -> AuditResult {
        let base = *lock(&self.base);
        let mut r = AuditResult {
            allowed: ALLOWED_NAMES.to_vec(),
            error: lock(&self.error).clone(),
            ..AuditResult::default()
        };
        if let Some((allocs, sys)) = *lock(&self.result) {
            r.complete = true;
            r.allocs = allocs.allocs;
            r.frees = allocs.frees;
            if let Some(s) = sys {
                r.syscalls = Some(s.all.saturating_sub(base.all));
                r.syscalls_outside = Some(s.outside.saturating_sub(base.outside));
            }
        }
        r
    }
}
