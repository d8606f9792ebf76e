//! CPU time of threads and of the process, sampled at the edges of a measurement window.
//!
//! Reading a CPU-time clock is a syscall on most kernels (`clock_gettime` of a CPU clock is not
//! served by the vDSO), so nothing here is read per cycle: a [`CpuSample`] is taken when the
//! window opens and when it closes, and the difference is divided by the cycles in between.
//!
//! - the calling thread: `CLOCK_THREAD_CPUTIME_ID` (nanoseconds) and `getrusage(RUSAGE_THREAD)`
//!   for its voluntary and involuntary context switches;
//! - another thread: its CPU clock from `pthread_getcpuclockid`, noted by that thread itself
//!   ([`ThreadCpuClock::current`]) and read from anywhere while it runs;
//! - the whole process: `CLOCK_PROCESS_CPUTIME_ID`.

use crate::rt::audit::{AuditError, SyscallCounter, SyscallCounts};
use nix::time::{ClockId, clock_gettime};

fn read_ns(id: ClockId) -> Option<u64> {
    clock_gettime(id).ok().map(|ts| {
        (ts.tv_sec() as u64)
            .saturating_mul(1_000_000_000)
            .saturating_add(ts.tv_nsec() as u64)
    })
}

/// CPU time of the calling thread, ns.
pub fn thread_cpu_ns() -> Option<u64> {
    read_ns(ClockId::CLOCK_THREAD_CPUTIME_ID)
}

/// CPU time of the whole process (all threads), ns.
pub fn process_cpu_ns() -> Option<u64> {
    read_ns(ClockId::CLOCK_PROCESS_CPUTIME_ID)
}

/// Voluntary and involuntary context switches of the calling thread so far.
pub fn thread_switches() -> Option<(u64, u64)> {
    use nix::sys::resource::{UsageWho, getrusage};
    getrusage(UsageWho::RUSAGE_THREAD).ok().map(|u| {
        (
            u.voluntary_context_switches() as u64,
            u.involuntary_context_switches() as u64,
        )
    })
}

/// The CPU-time clock of one thread, readable from any thread of the process while that thread
/// runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThreadCpuClock(libc::clockid_t);

impl ThreadCpuClock {
    /// The calling thread's clock.
    pub fn current() -> Option<Self> {
        let mut id: libc::clockid_t = 0;
        // SAFETY: pthread_self() is always valid for the calling thread; `id` is a valid
        // out-pointer for the duration of the call.
        let r = unsafe { libc::pthread_getcpuclockid(libc::pthread_self(), &mut id) };
        (r == 0).then_some(Self(id))
    }

    /// CPU time of the thread so far, ns (`None` once the thread has ended).
    pub fn now_ns(&self) -> Option<u64> {
        read_ns(ClockId::from_raw(self.0))
    }
}

/// CPU figures at one instant, taken on the thread whose time is measured.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CpuSample {
    /// `CLOCK_MONOTONIC`, ns.
    pub at_ns: u64,
    /// CPU time of the calling thread, ns.
    pub thread_ns: Option<u64>,
    /// CPU time of a helper thread (e.g. a TX/RX thread), ns.
    pub helper_ns: Option<u64>,
    /// CPU time of the process, ns.
    pub process_ns: Option<u64>,
    /// Voluntary context switches of the calling thread.
    pub voluntary: Option<u64>,
    /// Involuntary context switches of the calling thread.
    pub involuntary: Option<u64>,
}

impl CpuSample {
    /// Take a sample on the calling thread, with `helper`'s clock if given.
    pub fn take(helper: Option<&ThreadCpuClock>) -> Self {
        let sw = thread_switches();
        Self {
            at_ns: crate::rt::monotonic_ns(),
            thread_ns: thread_cpu_ns(),
            helper_ns: helper.and_then(ThreadCpuClock::now_ns),
            process_ns: process_cpu_ns(),
            voluntary: sw.map(|s| s.0),
            involuntary: sw.map(|s| s.1),
        }
    }
}

/// Counts the calling thread's syscalls over a window (opt-in: the kernel's
/// `raw_syscalls:sys_enter` tracepoint adds a little to every syscall, so the CPU figures of a
/// run that counts are slightly pessimistic). Needs root or `perf_event_paranoid` ≤ 1.
pub struct SyscallWindow {
    counter: SyscallCounter,
    base: SyscallCounts,
}

impl SyscallWindow {
    /// Open the window on the calling thread and start counting.
    pub fn start() -> Result<Self, AuditError> {
        let counter = SyscallCounter::for_current_thread(&[])?;
        let base = counter.overhead()?;
        counter.start();
        Ok(Self { counter, base })
    }

    /// Stop counting; the syscalls made inside the window (the counter's own stop excluded).
    pub fn stop(self) -> Result<u64, AuditError> {
        self.counter.stop();
        let n = self.counter.read()?;
        Ok(n.all.saturating_sub(self.base.all))
    }
}

/// How the CPU time per cycle is measured (also in the JSON).
pub const CPU_METHOD: &str = "per-window: CLOCK_THREAD_CPUTIME_ID of the cycle thread (and \
    pthread_getcpuclockid of the TX/RX thread) and CLOCK_PROCESS_CPUTIME_ID read when the \
    measured window opens and closes, the difference divided by the cycles in the window; \
    context switches from getrusage(RUSAGE_THREAD). Nothing is read per cycle.";

/// CPU time per cycle over a window.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct CpuReport {
    /// How it was measured.
    pub method: &'static str,
    /// Cycles in the window.
    pub cycles: u64,
    /// Wall time of the window, s.
    pub window_s: f64,
    /// CPU time of the cycle thread per cycle, ns (ecdrive: the cycle thread, frame I/O
    /// included; plain ethercrab: the loop thread; sleep: the sleeping thread).
    pub cycle_thread_ns: Option<f64>,
    /// CPU time of the separate TX/RX thread per cycle, ns (plain ethercrab only; in-process
    /// it also runs the emulated slaves).
    pub io_thread_ns: Option<f64>,
    /// Cycle thread + TX/RX thread per cycle, ns: what the master needs per cycle. The 10 %
    /// comparison uses this figure.
    pub master_ns: Option<f64>,
    /// CPU time of the whole process per cycle, ns (every thread: the harness itself, a
    /// session/supervisor thread, in-process slaves).
    pub process_ns: Option<f64>,
    /// Voluntary context switches of the cycle thread per cycle.
    pub voluntary_switches: Option<f64>,
    /// Involuntary context switches of the cycle thread per cycle.
    pub involuntary_switches: Option<f64>,
    /// Syscalls of the cycle thread per cycle (only when counting was asked for and possible;
    /// see [`SyscallWindow`]).
    pub syscalls: Option<f64>,
}

impl CpuReport {
    /// The figures between two samples over `cycles` cycles.
    pub fn between(begin: &CpuSample, end: &CpuSample, cycles: u64) -> Self {
        let n = cycles.max(1) as f64;
        let per = |a: Option<u64>, b: Option<u64>| match (a, b) {
            (Some(a), Some(b)) => Some(b.saturating_sub(a) as f64 / n),
            _ => None,
        };
        let cycle_thread_ns = per(begin.thread_ns, end.thread_ns);
        let io_thread_ns = per(begin.helper_ns, end.helper_ns);
        let master_ns = match (cycle_thread_ns, io_thread_ns) {
            (Some(c), Some(i)) => Some(c + i),
            (Some(c), None) => Some(c),
            _ => None,
        };
        Self {
            method: CPU_METHOD,
            cycles,
            window_s: end.at_ns.saturating_sub(begin.at_ns) as f64 / 1e9,
            cycle_thread_ns,
            io_thread_ns,
            master_ns,
            process_ns: per(begin.process_ns, end.process_ns),
            voluntary_switches: per(begin.voluntary, end.voluntary),
            involuntary_switches: per(begin.involuntary, end.involuntary),
            syscalls: None,
        }
    }

    /// Add the syscall count of the window (`count` syscalls over `self.cycles` cycles).
    pub fn with_syscalls(mut self, count: u64) -> Self {
        self.syscalls = Some(count as f64 / self.cycles.max(1) as f64);
        self
    }
}

/// Start counting syscalls if asked to; a note when it is not possible.
pub fn start_syscalls(wanted: bool, notes: &mut Vec<String>) -> Option<SyscallWindow> {
    if !wanted {
        return None;
    }
    match SyscallWindow::start() {
        Ok(w) => Some(w),
        Err(e) => {
            notes.push(format!("syscalls not counted: {e}"));
            None
        }
    }
}

/// Add a syscall count (from [`SyscallWindow::stop`], if counting ran) to `cpu`; a note if
/// reading failed.
pub fn apply_syscalls(
    count: Option<Result<u64, AuditError>>,
    cpu: CpuReport,
    notes: &mut Vec<String>,
) -> CpuReport {
    match count {
        Some(Ok(n)) => cpu.with_syscalls(n),
        Some(Err(e)) => {
            notes.push(format!("syscalls not counted: {e}"));
            cpu
        }
        None => cpu,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_thread_accumulates_cpu_time_and_its_clock_is_readable_elsewhere() {
        let (tx, rx) = std::sync::mpsc::channel();
        let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
        let h = std::thread::spawn(move || {
            let clock = ThreadCpuClock::current().expect("a CPU clock for this thread");
            let t0 = clock.now_ns().unwrap();
            let mut x = 0u64;
            while clock.now_ns().unwrap() < t0 + 2_000_000 {
                x = std::hint::black_box(x.wrapping_add(1));
            }
            tx.send(clock).unwrap();
            done_rx.recv().unwrap();
            x
        });
        let clock = rx.recv().unwrap();
        // Read from this thread while the other one still runs: at least the 2 ms it spun.
        assert!(clock.now_ns().unwrap() >= 2_000_000);
        done_tx.send(()).unwrap();
        h.join().unwrap();
    }

    #[test]
    fn report_divides_by_cycles_and_adds_the_helper() {
        let a = CpuSample {
            at_ns: 0,
            thread_ns: Some(1_000),
            helper_ns: Some(500),
            process_ns: Some(10_000),
            voluntary: Some(3),
            involuntary: Some(0),
        };
        let b = CpuSample {
            at_ns: 1_000_000_000,
            thread_ns: Some(11_000),
            helper_ns: Some(5_500),
            process_ns: Some(40_000),
            voluntary: Some(13),
            involuntary: Some(1),
        };
        let r = CpuReport::between(&a, &b, 10);
        assert_eq!(r.cycle_thread_ns, Some(1_000.0));
        assert_eq!(r.io_thread_ns, Some(500.0));
        assert_eq!(r.master_ns, Some(1_500.0));
        assert_eq!(r.process_ns, Some(3_000.0));
        assert_eq!(r.voluntary_switches, Some(1.0));
        assert_eq!(r.window_s, 1.0);
    }
}
