//! The SOEM baseline: a minimal C cyclic loop on SOEM (`benches/soem/soem_cycle.c`, built
//! by `benches/soem/build.sh` from the SOEM sources of the pysoem source distribution),
//! run as a separate process on the same interface, with the same drives, period, SYNC0
//! shift, priority, CPU and memory locking as the other runs.
//!
//! The harness tells the program what the drives need, as data taken from each drive's
//! profile, exactly as for the plain ethercrab loop ([`super::plain`]): the PRE-OP SDO writes
//! (`--sdo`), the output values that must not be zero (`--default`) and the cycle counter
//! (`--counter`). The program configures the segment with SOEM (`ec_config_init`,
//! `ec_config_map`, `ec_configdc`, SYNC0 on every DC device), cycles until every device is in
//! OP, then measures `--cycles` cycles, steering its wake-ups to the reference clock so that
//! each frame leaves at SYNC0 + shift. It writes every cycle's wake-up latency, period, round
//! trip and busy time to a file (little-endian `u32` quadruples, ns), which this module turns
//! into the same histograms as the other runs, and prints its counts and CPU figures as
//! `key=value` lines. SOEM moves frames from the loop thread itself: there is no TX/RX thread.
//!
//! Only over a network interface (SOEM opens a raw socket); the program is never built in CI's
//! critical path, and when it is missing the report says why there is no SOEM run.

use super::HarnessError;
use super::cpu::{CPU_METHOD, CpuReport, ThreadCpu, ThreadRole};
use super::report::{RunHistograms, RunReport, RunStructure};
use crate::drives::DriveProfile;
use crate::rt::{RtReport, RtSettings};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// What the SOEM run needs to know.
#[derive(Debug, Clone)]
pub struct SoemSettings {
    /// The `soem_cycle` program.
    pub program: PathBuf,
    /// The interface its far end serves the drives on.
    pub interface: String,
    /// Cycle time.
    pub cycle: Duration,
    /// Cycles in the measured window.
    pub cycles: u64,
    /// Real-time set-up of the loop.
    pub rt: RtSettings,
    /// The profile of each device, in line order.
    pub profiles: Vec<&'static DriveProfile>,
    /// How long the devices may take to reach OP.
    pub op_timeout: Duration,
    /// When the frame is sent after SYNC0.
    pub sync0_shift: Duration,
    /// Reply budget as a fraction of the cycle.
    pub reply_budget: f64,
}

fn err(what: impl Into<String>, reason: impl ToString) -> HarnessError {
    HarnessError::Run {
        run: "soem",
        what: what.into(),
        reason: reason.to_string(),
    }
}

/// Why the program at `path` cannot be used (`None`: it can).
pub fn unusable(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => None,
        Ok(_) => Some(format!("{} is not a file", path.display())),
        Err(e) => Some(format!(
            "{}: {e} (build it with benches/soem/build.sh)",
            path.display()
        )),
    }
}

/// The program's arguments for these settings.
pub fn arguments(s: &SoemSettings, samples: &Path) -> Result<Vec<String>, HarnessError> {
    let cycle_ns = u64::try_from(s.cycle.as_nanos()).unwrap_or(u64::MAX);
    let mut a: Vec<String> = vec![
        "--interface".into(),
        s.interface.clone(),
        "--expect".into(),
        s.profiles.len().to_string(),
        "--cycle-ns".into(),
        cycle_ns.to_string(),
        "--cycles".into(),
        s.cycles.to_string(),
        "--shift-ns".into(),
        s.sync0_shift.as_nanos().to_string(),
        "--samples".into(),
        samples.display().to_string(),
        "--op-timeout-ms".into(),
        s.op_timeout.as_millis().to_string(),
        "--budget".into(),
        format!("{}", s.reply_budget),
    ];
    if let Some(p) = s.rt.priority {
        a.extend(["--priority".into(), p.to_string()]);
    }
    if let Some(c) = s.rt.cpu {
        a.extend(["--cpu".into(), c.to_string()]);
    }
    if s.rt.lock_memory {
        a.push("--lock-memory".into());
    }
    let cycle32 = u32::try_from(cycle_ns).unwrap_or(u32::MAX);
    for (pos, p) in s.profiles.iter().enumerate() {
        let plan = super::plain::drive_plan(p, cycle32, pos)
            .map_err(|e| err(format!("drive {pos} ({})", p.name), e))?;
        for (addr, bytes, why) in &plan.writes {
            let value = match bytes.len() {
                1 | 2 | 4 => bytes
                    .iter()
                    .rev()
                    .fold(0u64, |v, b| (v << 8) | u64::from(*b)),
                n => {
                    return Err(err(
                        format!("drive {pos} ({}): SDO {addr} ({why})", p.name),
                        format!("{n} bytes: the SOEM loop downloads 1, 2 or 4 bytes"),
                    ));
                }
            };
            a.push("--sdo".into());
            a.push(format!(
                "{pos}:0x{:04X}:{}:{}:{value}",
                addr.index,
                addr.sub,
                bytes.len()
            ));
        }
        let byte_field = |f: &crate::pdo::Field, what: &str| {
            if f.bit_offset() != 0 || !matches!(f.bits(), 8 | 16 | 32) {
                Err(err(
                    format!("drive {pos} ({}): {what}", p.name),
                    format!(
                        "a {}-bit field at bit {}: the SOEM loop writes whole bytes",
                        f.bits(),
                        f.bit_offset()
                    ),
                ))
            } else {
                Ok((f.byte_offset(), f.bits() / 8))
            }
        };
        for (f, v) in &plan.defaults {
            let (byte, size) = byte_field(f, "output default")?;
            a.push("--default".into());
            a.push(format!("{pos}:{byte}:{size}:{v}"));
        }
        if let Some(f) = &plan.counter {
            let (byte, _) = byte_field(f, "cycle counter")?;
            a.push("--counter".into());
            a.push(format!("{pos}:{byte}"));
        }
    }
    Ok(a)
}

/// Parse the program's `key=value` output.
pub fn parse_output(stdout: &str) -> (HashMap<String, String>, Vec<String>) {
    let mut kv = HashMap::new();
    let mut warnings = Vec::new();
    for line in stdout.lines() {
        if let Some((k, v)) = line.split_once('=') {
            if k == "warning" {
                warnings.push(v.to_string());
            } else {
                kv.insert(k.trim().to_string(), v.trim().to_string());
            }
        }
    }
    (kv, warnings)
}

/// The histograms of a samples file (`u32` quadruples: wake latency, period, exchange, busy).
pub fn histograms(bytes: &[u8]) -> RunHistograms {
    let mut h = RunHistograms::new(true);
    for q in bytes.chunks_exact(16) {
        let v = |i: usize| {
            q.get(i * 4..i * 4 + 4)
                .and_then(|b| <[u8; 4]>::try_from(b).ok())
                .map_or(0, |b| u64::from(u32::from_le_bytes(b)))
        };
        h.wake_latency.record(v(0));
        if v(1) > 0 {
            h.period.record(v(1));
        }
        if let Some(e) = h.exchange.as_mut() {
            e.record(v(2));
        }
        h.busy.record(v(3));
    }
    h
}

/// Run the SOEM loop; its report (without drive figures).
pub fn run(s: &SoemSettings) -> Result<RunReport, HarnessError> {
    let cycle_ns = u64::try_from(s.cycle.as_nanos()).unwrap_or(u64::MAX);
    let samples = std::env::temp_dir().join(format!(
        "ecdrive-jitter-soem-{}-{}.bin",
        std::process::id(),
        crate::rt::monotonic_ns()
    ));
    let args = arguments(s, &samples)?;
    let out = Command::new(&s.program)
        .args(&args)
        .output()
        .map_err(|e| err(format!("starting {}", s.program.display()), e))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let bytes = std::fs::read(&samples);
    let _ = std::fs::remove_file(&samples);
    if !out.status.success() {
        let why = stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no message");
        return Err(err("running", format!("{} ({})", why.trim(), out.status)));
    }
    let bytes = bytes.map_err(|e| err("reading its samples", e))?;
    let (kv, warnings) = parse_output(&stdout);
    let num = |k: &str| kv.get(k).and_then(|v| v.parse::<f64>().ok());
    let count = |k: &str| kv.get(k).and_then(|v| v.parse::<u64>().ok());
    let h = histograms(&bytes);
    let cycles = h.wake_latency.len().max(1) as f64;
    let per = |v: Option<f64>| v.map(|v| v / cycles);
    let thread_ns = per(num("thread_cpu_ns"));
    let process_ns = per(num("process_cpu_ns"));
    let voluntary = per(num("voluntary_switches"));
    let involuntary = per(num("involuntary_switches"));
    let cpu = CpuReport {
        method: CPU_METHOD,
        cycles: h.wake_latency.len(),
        window_s: h.wake_latency.len() as f64 * s.cycle.as_secs_f64(),
        cycle_thread_ns: thread_ns,
        io_thread_ns: None,
        // One process, one thread: the whole process is the master.
        master_ns: process_ns,
        process_ns,
        voluntary_switches: voluntary,
        involuntary_switches: involuntary,
        syscalls: None,
        threads: vec![ThreadCpu {
            name: "soem_cycle".into(),
            role: ThreadRole::Master,
            cpu_ns: thread_ns.unwrap_or(0.0),
            voluntary: voluntary.unwrap_or(0.0),
            involuntary: involuntary.unwrap_or(0.0),
        }],
    };
    let granted = count("priority_granted").and_then(|p| u8::try_from(p).ok());
    let rt = RtReport {
        priority_granted: granted.filter(|p| *p > 0),
        cpu_pinned: s.rt.cpu.filter(|_| count("cpu_pinned") == Some(1)),
        memory_locked: count("memory_locked") == Some(1),
        warnings,
    };
    let mut notes = Vec::new();
    if let Some(v) = kv.get("soem_version") {
        notes.push(format!("SOEM {v}"));
    }
    if let Some(n) = count("wkc_errors").filter(|n| *n > 0) {
        notes.push(format!("{n} cycles with a wrong working counter"));
    }
    let mut r = h.report(
        "soem",
        cycle_ns,
        rt,
        count("late").unwrap_or(0),
        count("missed"),
        cpu,
        Vec::new(),
        notes,
    );
    r.structure = RunStructure {
        link: "SOEM's raw socket, frames sent and received by the loop thread (its own process)"
            .into(),
        mailbox_poll_ms: None,
        master_threads: vec!["soem_cycle".into()],
        slaves: String::new(),
    };
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_and_output_are_read_back() {
        let mut b = Vec::new();
        for q in [[10u32, 0, 30, 40], [11, 1_000_000, 31, 41]] {
            for v in q {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        let h = histograms(&b);
        assert_eq!(h.wake_latency.len(), 2);
        assert_eq!(h.period.len(), 1);
        let (kv, w) = parse_output("cycles=2\nlate=0\nwarning=memory not locked\n");
        assert_eq!(kv["cycles"], "2");
        assert_eq!(w, ["memory not locked"]);
    }

    #[test]
    fn the_drives_needs_become_arguments() {
        let s = SoemSettings {
            program: PathBuf::from("soem_cycle"),
            interface: "veth0".into(),
            cycle: Duration::from_millis(1),
            cycles: 10,
            rt: RtSettings::default(),
            profiles: vec![crate::drives::by_key("mr-j4-tm").expect("a profile")],
            op_timeout: Duration::from_secs(1),
            sync0_shift: Duration::from_micros(500),
            reply_budget: 0.8,
        };
        let a = arguments(&s, Path::new("/tmp/x")).unwrap();
        let sdo: Vec<&String> = a.iter().skip_while(|x| *x != "--sdo").collect();
        assert!(sdo.len() > 2, "{a:?}");
        // The mapping, then DC synchronisation at this cycle time (0x1C32:01 = 2, :02 = 1 ms).
        assert!(a.iter().any(|x| x == "0:0x1C12:1:2:5632"), "{a:?}");
        assert_eq!(a.last().map(String::as_str), Some("0:0x1C32:2:4:1000000"));
        assert!(
            a.windows(2)
                .any(|w| w[0] == "--cycle-ns" && w[1] == "1000000")
        );
    }
}
