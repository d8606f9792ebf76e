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

/// One thread of this process at one instant, from `/proc/self/task/TID/`: CPU time in ns
/// (`schedstat`, first field: time on a CPU) and context switches (`status`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ThreadTime {
    /// Kernel thread ID.
    pub tid: u32,
    /// Thread name (`comm`).
    pub name: String,
    /// CPU time so far, ns.
    pub cpu_ns: u64,
    /// Voluntary context switches so far (the thread slept: one wake-up each).
    pub voluntary: u64,
    /// Involuntary context switches so far (the thread was preempted).
    pub involuntary: u64,
}

/// Every thread of this process now (empty if `/proc` cannot be read). Reads a few files per
/// thread: for the edges of a window only.
pub fn threads_now() -> Vec<ThreadTime> {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for e in dir.flatten() {
        let Some(tid) = e.file_name().to_str().and_then(|t| t.parse::<u32>().ok()) else {
            continue;
        };
        let path = e.path();
        let read = |f: &str| std::fs::read_to_string(path.join(f)).unwrap_or_default();
        let Some(cpu_ns) = read("schedstat")
            .split_whitespace()
            .next()
            .and_then(|v| v.parse().ok())
        else {
            continue;
        };
        let status = read("status");
        let field = |k: &str| {
            status
                .lines()
                .find_map(|l| l.strip_prefix(k))
                .and_then(|v| v.trim().parse().ok())
                .unwrap_or(0)
        };
        out.push(ThreadTime {
            tid,
            name: read("comm").trim().to_string(),
            cpu_ns,
            voluntary: field("voluntary_ctxt_switches:"),
            involuntary: field("nonvoluntary_ctxt_switches:"),
        });
    }
    out.sort_by_key(|t| t.tid);
    out
}

/// The kernel thread ID of the calling thread.
pub fn current_tid() -> u32 {
    // `/proc/thread-self` links to `PID/task/TID`.
    std::fs::read_link("/proc/thread-self")
        .ok()
        .and_then(|p| p.file_name()?.to_str()?.parse().ok())
        .unwrap_or(0)
}

static BEFORE_RUN: std::sync::Mutex<Vec<u32>> = std::sync::Mutex::new(Vec::new());

/// Note the threads that exist before a run starts: they are not the run's master (the
/// harness itself, a test harness's other threads). Call before each run.
pub fn begin_run() {
    let tids: Vec<u32> = threads_now().iter().map(|t| t.tid).collect();
    if let Ok(mut b) = BEFORE_RUN.lock() {
        *b = tids;
    }
}

/// Thread name prefix of the emulated slaves served on a veth far end (not the master's).
pub const FAR_END_THREAD: &str = "jitter-far-end";
/// The `async-io` crate's reactor thread, which serves ethercrab's timers.
pub const ASYNC_IO_THREAD: &str = "async-io";
/// Thread name prefix of the `--stress` load threads (not the master's).
pub const STRESS_THREAD: &str = "jitter-stress";

/// What a thread of the harness's process is, for the CPU figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ThreadRole {
    /// Part of the master being measured (cycle, TX/RX, session threads; in-process also the
    /// emulated slaves, which run on a master thread in both masters).
    Master,
    /// The emulated slaves on a veth far end: charged to no master.
    Segment,
    /// The `--stress` load.
    Load,
    /// Not the run's: the harness itself, and every thread that existed before the run
    /// started ([`begin_run`]).
    Harness,
}

impl ThreadRole {
    /// The name the JSON uses.
    pub fn name(self) -> &'static str {
        match self {
            Self::Master => "master",
            Self::Segment => "segment",
            Self::Load => "load",
            Self::Harness => "harness",
        }
    }
}

/// The role of a thread: by its name, else whether the run started it. Names are the kernel's
/// (`comm`, at most 15 characters: `ecdrive-sim-ethercrab` reads `ecdrive-sim-eth`).
pub fn role_of(t: &ThreadTime) -> ThreadRole {
    let before = BEFORE_RUN
        .lock()
        .map(|b| b.contains(&t.tid))
        .unwrap_or(false);
    if t.name.starts_with(FAR_END_THREAD) {
        ThreadRole::Segment
    } else if t.name.starts_with(STRESS_THREAD) {
        ThreadRole::Load
    } else if t.name == ASYNC_IO_THREAD {
        // Started once per process by the first ethercrab timer and shared by every later
        // run: its work during a run is that run's master's.
        ThreadRole::Master
    } else if before || t.tid == std::process::id() {
        ThreadRole::Harness
    } else {
        ThreadRole::Master
    }
}

/// CPU figures at one instant, taken on the thread whose time is measured.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
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
    /// Every thread of the process.
    pub threads: Vec<ThreadTime>,
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
            threads: threads_now(),
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
pub const CPU_METHOD: &str = "per-window: every thread's CPU time (/proc/self/task/*/schedstat), \
    CLOCK_THREAD_CPUTIME_ID of the cycle thread (and pthread_getcpuclockid of a TX/RX thread) \
    and CLOCK_PROCESS_CPUTIME_ID read when the measured window opens and closes, the \
    difference divided by the cycles in the window; context switches from \
    getrusage(RUSAGE_THREAD) and /proc/self/task/*/status. master_ns is the sum over the \
    master's threads (the emulated slaves of a veth far end, the --stress load and the \
    harness's own threads excluded). Nothing is read per cycle.";

/// One thread's share of a window, per cycle.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ThreadCpu {
    /// Thread name.
    pub name: String,
    /// What it is.
    pub role: ThreadRole,
    /// CPU time per cycle, ns.
    pub cpu_ns: f64,
    /// Voluntary context switches per cycle (wake-ups after sleeping).
    pub voluntary: f64,
    /// Involuntary context switches per cycle.
    pub involuntary: f64,
}

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
    /// Every thread of the master per cycle, ns ([`ThreadRole::Master`]: the cycle thread, a
    /// TX/RX thread, ecdrive's session thread; in-process also the emulated slaves, which run
    /// on a master thread in both masters). The figure the masters are compared by.
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
    /// Every thread of the process that ran in the window, per cycle.
    pub threads: Vec<ThreadCpu>,
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
        let threads: Vec<ThreadCpu> = end
            .threads
            .iter()
            .map(|e| {
                let b = begin.threads.iter().find(|b| b.tid == e.tid);
                let d = |f: fn(&ThreadTime) -> u64| f(e).saturating_sub(b.map_or(0, f)) as f64 / n;
                ThreadCpu {
                    name: e.name.clone(),
                    role: role_of(e),
                    cpu_ns: d(|t| t.cpu_ns),
                    voluntary: d(|t| t.voluntary),
                    involuntary: d(|t| t.involuntary),
                }
            })
            .collect();
        let from_threads = threads
            .iter()
            .filter(|t| t.role == ThreadRole::Master)
            .map(|t| t.cpu_ns)
            .sum::<f64>();
        // Without /proc, the threads the run knows about.
        let master_ns = if threads.is_empty() {
            match (cycle_thread_ns, io_thread_ns) {
                (Some(c), Some(i)) => Some(c + i),
                (Some(c), None) => Some(c),
                _ => None,
            }
        } else {
            Some(from_threads)
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
            threads,
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
            threads: Vec::new(),
        };
        let b = CpuSample {
            at_ns: 1_000_000_000,
            thread_ns: Some(11_000),
            helper_ns: Some(5_500),
            process_ns: Some(40_000),
            voluntary: Some(13),
            involuntary: Some(1),
            threads: Vec::new(),
        };
        let r = CpuReport::between(&a, &b, 10);
        assert_eq!(r.cycle_thread_ns, Some(1_000.0));
        assert_eq!(r.io_thread_ns, Some(500.0));
        assert_eq!(r.master_ns, Some(1_500.0));
        assert_eq!(r.process_ns, Some(3_000.0));
        assert_eq!(r.voluntary_switches, Some(1.0));
        assert_eq!(r.window_s, 1.0);
    }

    #[test]
    fn the_master_figure_sums_the_masters_threads_only() {
        let t = |tid, name: &str, cpu_ns| ThreadTime {
            tid,
            name: name.into(),
            cpu_ns,
            voluntary: 0,
            involuntary: 0,
        };
        let a = CpuSample {
            threads: vec![t(1_000_001, "cycle", 0), t(1_000_002, FAR_END_THREAD, 0)],
            ..CpuSample::default()
        };
        let b = CpuSample {
            at_ns: 1,
            threads: vec![
                t(1_000_001, "cycle", 100),
                t(1_000_002, FAR_END_THREAD, 1_000),
                t(1_000_003, "jitter-stress-0", 5_000),
            ],
            ..CpuSample::default()
        };
        let r = CpuReport::between(&a, &b, 10);
        assert_eq!(r.master_ns, Some(10.0));
        assert_eq!(r.threads.len(), 3);
        assert_eq!(r.threads[1].role, ThreadRole::Segment);
        assert_eq!(r.threads[2].role, ThreadRole::Load);
        // This process's own threads are readable.
        assert!(!threads_now().is_empty());
    }
}
