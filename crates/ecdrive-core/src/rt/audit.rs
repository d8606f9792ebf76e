//! Evidence that the cyclic path behaves: a per-thread **syscall counter** and an allocation
//! counter.
//!
//! [`SyscallCounter`] counts, for the calling thread only, every syscall entry and every entry of
//! a syscall *outside* an allowed set, using the kernel's `raw_syscalls:sys_enter` tracepoint
//! through `perf_event_open` (needs root or `perf_event_paranoid` ≤ 1, and tracefs; it mounts
//! tracefs itself when it can). The cycle tests allow only the sleep and the link's frame I/O
//! and assert the "outside" count is zero; the jitter harness reports syscalls per cycle.
//!
//! [`CountingAlloc`] wraps the system allocator; a test binary installs it as its
//! `#[global_allocator]` and opens a window on the cycle thread with [`alloc_window_begin`] /
//! [`alloc_window_end`]: allocations and frees made by that thread inside the window are counted.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::fs::File;
use std::io::Read;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};

/// Why the syscall counter is not available.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("syscall counting unavailable: {0}")]
pub struct AuditError(pub String);

const TRACEFS: &str = "/sys/kernel/tracing";

fn sys_enter_id() -> Result<u64, AuditError> {
    let path = format!("{TRACEFS}/events/raw_syscalls/sys_enter/id");
    if std::fs::metadata(&path).is_err() {
        // Try to mount tracefs (root only); ignore failure, the read below reports it.
        let _ = std::process::Command::new("mount")
            .args(["-t", "tracefs", "nodev", TRACEFS])
            .status();
    }
    let text = std::fs::read_to_string(&path).map_err(|e| {
        AuditError(format!(
            "cannot read {path}: {e} (tracefs not mounted, or not root)"
        ))
    })?;
    text.trim()
        .parse()
        .map_err(|_| AuditError(format!("{path} holds {text:?}, not a number")))
}

fn open_counter(id: u64, filter: Option<&str>) -> Result<OwnedFd, AuditError> {
    use perf_event_open_sys::{bindings, ioctls, perf_event_open};
    let mut attr = bindings::perf_event_attr {
        size: std::mem::size_of::<bindings::perf_event_attr>() as u32,
        type_: bindings::PERF_TYPE_TRACEPOINT,
        config: id,
        ..Default::default()
    };
    attr.set_disabled(1);
    attr.set_exclude_hv(1);
    // SAFETY: perf_event_open(2) with a fully initialised attr, pid 0 = calling thread, cpu -1 =
    // any CPU, no group, no flags. It returns a new fd or -1.
    let fd = unsafe { perf_event_open(&mut attr, 0, -1, -1, 0) };
    if fd < 0 {
        return Err(AuditError(format!(
            "perf_event_open: {}",
            std::io::Error::last_os_error()
        )));
    }
    // SAFETY: fd is a fresh descriptor that nothing else owns.
    let fd = unsafe { OwnedFd::from_raw_fd(fd) };
    if let Some(f) = filter {
        let c = std::ffi::CString::new(f).map_err(|_| AuditError("filter has a NUL".into()))?;
        // SAFETY: SET_FILTER reads a NUL-terminated string that outlives the call.
        let r = unsafe { ioctls::SET_FILTER(fd.as_raw_fd(), c.as_ptr() as *mut _) };
        if r < 0 {
            return Err(AuditError(format!(
                "setting the tracepoint filter {f:?}: {}",
                std::io::Error::last_os_error()
            )));
        }
    }
    Ok(fd)
}

#[derive(Clone, Copy)]
enum Ctl {
    Enable,
    Disable,
    Reset,
}

fn ctl(fd: &OwnedFd, op: Ctl) {
    use perf_event_open_sys::ioctls;
    // SAFETY: ENABLE/DISABLE/RESET take an integer flag argument (0 = this event only) on a
    // perf event fd we own.
    unsafe {
        match op {
            Ctl::Enable => ioctls::ENABLE(fd.as_raw_fd(), 0),
            Ctl::Disable => ioctls::DISABLE(fd.as_raw_fd(), 0),
            Ctl::Reset => ioctls::RESET(fd.as_raw_fd(), 0),
        };
    }
}

/// Counts the calling thread's syscalls: all of them, and those outside an allowed set.
pub struct SyscallCounter {
    all: OwnedFd,
    outside: OwnedFd,
}

/// Counts read from a [`SyscallCounter`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SyscallCounts {
    /// Every syscall entry.
    pub all: u64,
    /// Entries of syscalls outside the allowed set.
    pub outside: u64,
}

impl SyscallCounter {
    /// Counters for the **calling thread**, with `allowed` syscall numbers (e.g.
    /// `libc::SYS_clock_nanosleep`) excluded from the `outside` count. The counters start
    /// stopped.
    pub fn for_current_thread(allowed: &[libc::c_long]) -> Result<Self, AuditError> {
        let id = sys_enter_id()?;
        let all = open_counter(id, None)?;
        let filter = allowed
            .iter()
            .map(|n| format!("id != {n}"))
            .collect::<Vec<_>>()
            .join(" && ");
        let outside = open_counter(id, (!filter.is_empty()).then_some(filter.as_str()))?;
        Ok(Self { all, outside })
    }

    /// Start counting. Allocation-free.
    pub fn start(&self) {
        ctl(&self.all, Ctl::Enable);
        ctl(&self.outside, Ctl::Enable);
    }

    /// Stop counting. Allocation-free. The stop itself adds a constant (the `ioctl`s); measure
    /// it with an empty window ([`SyscallCounter::overhead`]).
    pub fn stop(&self) {
        ctl(&self.outside, Ctl::Disable);
        ctl(&self.all, Ctl::Disable);
    }

    /// Read the counts so far.
    pub fn read(&self) -> Result<SyscallCounts, AuditError> {
        let rd = |fd: &OwnedFd| -> Result<u64, AuditError> {
            let mut b = [0u8; 8];
            let mut f = File::from(fd.try_clone().map_err(|e| AuditError(e.to_string()))?);
            f.read_exact(&mut b)
                .map_err(|e| AuditError(e.to_string()))?;
            Ok(u64::from_ne_bytes(b))
        };
        Ok(SyscallCounts {
            all: rd(&self.all)?,
            outside: rd(&self.outside)?,
        })
    }

    /// Reset both counts to zero.
    pub fn reset(&self) {
        ctl(&self.all, Ctl::Reset);
        ctl(&self.outside, Ctl::Reset);
    }

    /// The counts an empty start/stop window produces (the stop `ioctl`s), to subtract.
    pub fn overhead(&self) -> Result<SyscallCounts, AuditError> {
        self.reset();
        self.start();
        self.stop();
        let c = self.read()?;
        self.reset();
        Ok(c)
    }
}

// ---- allocation counting ---------------------------------------------------------------------

// Each thread's own window and counts: tests running at the same time in one test binary, each
// auditing its own cycle thread, never see each other's allocations.
thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
    static FREES: Cell<u64> = const { Cell::new(0) };
}

/// A global allocator that counts the allocations and frees made by threads inside an open
/// window, each thread its own. Install it in a test binary with `#[global_allocator]`.
pub struct CountingAlloc;

fn counting() -> bool {
    COUNTING.try_with(Cell::get).unwrap_or(false)
}

fn count(counter: &'static std::thread::LocalKey<Cell<u64>>) {
    let _ = counter.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every method forwards to the system allocator unchanged; counting touches only
// const-initialised thread-locals, which never allocate.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if counting() {
            count(&ALLOCS);
        }
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if counting() {
            count(&FREES);
        }
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if counting() {
            count(&ALLOCS);
        }
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if counting() {
            count(&ALLOCS);
        }
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocation counts of a window.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct AllocCounts {
    /// Allocations and reallocations.
    pub allocs: u64,
    /// Frees.
    pub frees: u64,
}

/// Open an allocation-counting window on the calling thread (counts reset).
pub fn alloc_window_begin() {
    let _ = ALLOCS.try_with(|c| c.set(0));
    let _ = FREES.try_with(|c| c.set(0));
    let _ = COUNTING.try_with(|c| c.set(true));
}

/// Close the calling thread's window and return its counts. Only meaningful when
/// [`CountingAlloc`] is the global allocator.
pub fn alloc_window_end() -> AllocCounts {
    let _ = COUNTING.try_with(|c| c.set(false));
    AllocCounts {
        allocs: ALLOCS.try_with(Cell::get).unwrap_or(0),
        frees: FREES.try_with(Cell::get).unwrap_or(0),
    }
}

/// For tests that need privileges: print a loud skip line, or fail when `ECDRIVE_CI` is set
/// (CI runs as root and must run them).
pub fn skip_or_fail(why: &str) {
    if std::env::var_os("ECDRIVE_CI").is_some() {
        panic!("ECDRIVE_CI is set but this test cannot run: {why}");
    }
    announce_skip(&format!("SKIPPED: {why}"));
}

/// Print a test's skip line where the user sees it in a normal `cargo test` run: straight to
/// the process's stderr, which the test harness does not capture (it captures `eprintln!`,
/// and shows that only for failed tests).
pub fn announce_skip(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "\n*** {line} ***");
}

/// The seed of a test's generated cases: `ECDRIVE_SEED` (or `PROPTEST_RNG_SEED`) when set,
/// else a fresh one — written to stderr past the test harness's capture, so that every run,
/// passing or failing, says how to replay it (`ECDRIVE_SEED=N cargo test …`).
pub fn test_seed(test: &str) -> u64 {
    use std::hash::BuildHasher;
    use std::io::Write;
    let from_env = ["ECDRIVE_SEED", "PROPTEST_RNG_SEED"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.trim().parse::<u64>().ok());
    let seed = from_env.unwrap_or_else(|| {
        std::collections::hash_map::RandomState::new()
            .hash_one((std::process::id(), std::time::SystemTime::now()))
    });
    let _ = writeln!(
        std::io::stderr().lock(),
        "{test}: generated cases from seed {seed} (replay: ECDRIVE_SEED={seed})"
    );
    seed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_only_syscalls_outside_the_allowed_set() {
        let c = match SyscallCounter::for_current_thread(&[libc::SYS_clock_nanosleep]) {
            Ok(c) => c,
            Err(e) => {
                crate::rt::audit::skip_or_fail(&format!("syscall counter: {e}"));
                return;
            }
        };
        let base = c.overhead().unwrap();
        c.start();
        for _ in 0..50 {
            crate::rt::sleep_until_ns(0);
            crate::rt::sleep_until_ns(crate::rt::monotonic_ns() + 1000);
        }
        // SAFETY: getppid has no preconditions.
        unsafe { libc::getppid() };
        c.stop();
        let n = c.read().unwrap();
        assert_eq!(n.outside - base.outside, 1, "{n:?} base {base:?}");
        assert_eq!(n.all - base.all, 101, "{n:?} base {base:?}");
    }
}
