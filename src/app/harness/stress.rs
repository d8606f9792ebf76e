//! `ecdrive jitter --stress`: a documented background load on the machine while every run is
//! measured, so that the tables can show an idle and a loaded machine, as published
//! multi-master comparisons do.
//!
//! The load ([`WHAT`]): one normal-priority (SCHED_OTHER) thread per CPU other than the
//! measured one, or per CPU when no CPU is chosen with `--cpu`, each pinned to its CPU. Each
//! writes every cache line of its own 16 MiB buffer over and over (memory bandwidth, and the
//! caches the masters share with it) and yields after each MiB (a syscall, so the kernel's
//! entry and exit paths are busy too). The real-time threads preempt it; what it costs them
//! is what a busy machine costs a real-time thread: cache and memory contention, and the
//! scheduler's latency. The threads are named `jitter-stress-N` and are charged to no master.

use super::cpu::STRESS_THREAD;
use crate::rt::RtSettings;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;

/// What the load does (also in the JSON).
pub const WHAT: &str = "--stress: one SCHED_OTHER thread pinned to each CPU other than the \
    measured one (each CPU when --cpu is not given), writing every cache line of its own \
    16 MiB buffer in a loop and calling sched_yield after each MiB";

const BUFFER: usize = 16 << 20;
const LINE: usize = 64;

/// The running load.
pub struct Stress {
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
    /// The CPUs loaded.
    pub cpus: Vec<usize>,
}

impl Stress {
    /// Start the load on every CPU but `measured` (every CPU if `None`).
    pub fn start(measured: Option<usize>) -> std::io::Result<Self> {
        let n = std::thread::available_parallelism().map_or(1, |n| n.get());
        let cpus: Vec<usize> = (0..n).filter(|c| Some(*c) != measured).collect();
        let stop = Arc::new(AtomicBool::new(false));
        let mut threads = Vec::with_capacity(cpus.len());
        for &cpu in &cpus {
            let stop = stop.clone();
            threads.push(
                std::thread::Builder::new()
                    .name(format!("{STRESS_THREAD}-{cpu}"))
                    .spawn(move || load(cpu, &stop))?,
            );
        }
        Ok(Self {
            stop,
            threads,
            cpus,
        })
    }

    /// Stop the load and wait for its threads.
    pub fn stop(self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads {
            let _ = t.join();
        }
    }
}

fn load(cpu: usize, stop: &AtomicBool) {
    let _ = RtSettings {
        priority: None,
        cpu: Some(cpu),
        lock_memory: false,
    }
    .apply_to_current_thread();
    let mut buf = vec![0u8; BUFFER];
    let mut round: u8 = 0;
    while !stop.load(Ordering::Relaxed) {
        round = round.wrapping_add(1);
        for (i, chunk) in buf.chunks_mut(1 << 20).enumerate() {
            for line in chunk.iter_mut().step_by(LINE) {
                *line = line.wrapping_add(round);
            }
            std::hint::black_box(&chunk);
            if i % 4 == 0 && stop.load(Ordering::Relaxed) {
                return;
            }
            std::thread::yield_now();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_load_starts_on_the_other_cpus_and_stops() {
        let s = Stress::start(Some(0)).unwrap();
        assert!(!s.cpus.contains(&0));
        std::thread::sleep(std::time::Duration::from_millis(20));
        s.stop();
    }
}
