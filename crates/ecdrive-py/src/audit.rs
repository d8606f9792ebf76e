//! The cycle audit with Python attached (`Master(..., audit=True)`): the allocations the cycle
//! thread makes and the syscalls it makes outside the sleep and the frame I/O, counted from the
//! moment every drive is in OP to the stop, as the Rust audit tests count them
//! (`crates/ecdrive-ethercat/tests/ethercat/cycle_audit.rs`). The extension's global
//! allocator is the counting one: every allocation of Rust code in the extension, the cycle's
//! included, passes through it (Python's own allocations do not, and need not: the cycle
//! never calls Python).

use ecdrive::master::cycle::audit::SteadyAudit;

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

/// The hooks the cycle thread calls: the master's steady-state audit with the syscalls above.
pub fn hooks() -> SteadyAudit {
    SteadyAudit::new(&ALLOWED)
}

/// What the window counted (after the cycle stopped).
pub fn result(a: &SteadyAudit) -> AuditResult {
    let mut r = AuditResult {
        allowed: ALLOWED_NAMES.to_vec(),
        error: a.error(),
        ..AuditResult::default()
    };
    if let Some(c) = a.counts() {
        r.complete = true;
        r.allocs = c.allocs.allocs;
        r.frees = c.allocs.frees;
        if let Some(s) = c.syscalls {
            r.syscalls = Some(s.all);
            r.syscalls_outside = Some(s.outside);
        }
    }
    r
}
