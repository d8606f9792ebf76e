//! Facts about the host that decide what timing it can deliver, reported next to every
//! measurement.

use serde::Serialize;
use std::fs;

/// Host conditions relevant to cycle timing.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct HostInfo {
    /// Kernel release and version (`uname -r -v`).
    pub kernel: String,
    /// Whether the kernel is PREEMPT_RT.
    pub preempt_rt: bool,
    /// CPU model name.
    pub cpu_model: String,
    /// Number of online CPUs.
    pub cpus: usize,
    /// cpufreq governor of CPU 0, if cpufreq is present.
    pub governor: Option<String>,
    /// Isolated CPUs (`isolcpus=`), as the kernel lists them; empty if none.
    pub isolated_cpus: String,
    /// `/proc/sys/kernel/sched_rt_runtime_us` (-1 = RT throttling off).
    pub sched_rt_runtime_us: Option<i64>,
}

fn read_trim(path: &str) -> Option<String> {
    fs::read_to_string(path).ok().map(|s| s.trim().to_string())
}

impl HostInfo {
    /// Read the facts from `/proc` and `/sys`. Missing files give empty fields, never an error.
    pub fn read() -> Self {
        let release = read_trim("/proc/sys/kernel/osrelease").unwrap_or_default();
        let version = read_trim("/proc/sys/kernel/version").unwrap_or_default();
        let preempt_rt = read_trim("/sys/kernel/realtime").as_deref() == Some("1")
            || version.contains("PREEMPT_RT");
        let cpu_model = fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Self {
            kernel: format!("{release} {version}").trim().to_string(),
            preempt_rt,
            cpu_model,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            governor: read_trim("/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor"),
            isolated_cpus: read_trim("/sys/devices/system/cpu/isolated").unwrap_or_default(),
            sched_rt_runtime_us: read_trim("/proc/sys/kernel/sched_rt_runtime_us")
                .and_then(|s| s.parse().ok()),
        }
    }
}
