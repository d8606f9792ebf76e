//! Real-time thread set-up: SCHED_FIFO priority, CPU pinning, locked memory.

use serde::Serialize;

/// What the cyclic thread asks for.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Deserialize, Serialize)]
pub struct RtSettings {
    /// SCHED_FIFO priority (1–99). `None` leaves the thread at normal priority.
    pub priority: Option<u8>,
    /// CPU to pin the thread to. `None` leaves the affinity alone.
    pub cpu: Option<usize>,
    /// Lock all current and future memory (`mlockall`) so page faults cannot stall the cycle.
    pub lock_memory: bool,
}

/// What was granted. Nothing here is fatal: without privileges the cycle still runs, with a
/// warning that says what was missing.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct RtReport {
    /// SCHED_FIFO priority actually set.
    pub priority_granted: Option<u8>,
    /// CPU the thread was pinned to.
    pub cpu_pinned: Option<usize>,
    /// Whether `mlockall` succeeded.
    pub memory_locked: bool,
    /// One line per request that was not granted, with the reason.
    pub warnings: Vec<String>,
}

impl RtSettings {
    /// Apply the settings to the **calling** thread.
    pub fn apply_to_current_thread(&self) -> RtReport {
        let mut report = RtReport::default();
        if let Some(prio) = self.priority {
            match set_fifo(prio) {
                Ok(()) => report.priority_granted = Some(prio),
                Err(e) => report.warnings.push(format!(
                    "real-time priority SCHED_FIFO {prio} not granted ({e}); the cycle runs at \
                     normal priority and its timing will suffer (run as root, or grant CAP_SYS_NICE \
                     / an rtprio limit)"
                )),
            }
        }
        if let Some(cpu) = self.cpu {
            let ids = core_affinity::get_core_ids().unwrap_or_default();
            match ids.into_iter().find(|c| c.id == cpu) {
                Some(id) if core_affinity::set_for_current(id) => report.cpu_pinned = Some(cpu),
                Some(_) => report
                    .warnings
                    .push(format!("could not pin the cycle thread to CPU {cpu}")),
                None => report.warnings.push(format!(
                    "CPU {cpu} does not exist or is not available to this process; not pinned"
                )),
            }
        }
        if self.lock_memory {
            use nix::sys::mman::{MlockAllFlags, mlockall};
            match mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE) {
                Ok(()) => report.memory_locked = true,
                Err(e) => report.warnings.push(format!(
                    "memory not locked ({e}); page faults may stall the cycle (needs \
                     CAP_IPC_LOCK or a memlock limit)"
                )),
            }
        }
        report
    }
}

fn set_fifo(prio: u8) -> Result<(), String> {
    use thread_priority::{
        RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
        set_thread_priority_and_policy, thread_native_id,
    };
    let value = ThreadPriorityValue::try_from(prio)
        .map_err(|_| format!("priority {prio} is not one of 1–99"))?;
    set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| match e {
        thread_priority::Error::OS(code) => std::io::Error::from_raw_os_error(code).to_string(),
        other => other.to_string(),
    })
}
