//! The cycle-jitter harness behind `ecdrive jitter`: ecdrive's cycle measured against the floor
//! of the machine, in one invocation.
//!
//! [`run`] measures three loops **one after the other** (never concurrently), each for the same
//! number of cycles at the same cycle time, with the same real-time set-up
//! ([`RtSettings`]: SCHED_FIFO priority, CPU, memory locking) and on the same emulated drives:
//!
//! 1. **`sleep`** — the bare sleep loop ([`sleep`]): absolute `clock_nanosleep` on a fixed grid,
//!    nothing else; the `cyclictest` floor of this machine.
//! 2. **`ethercrab`** — the plain ethercrab loop ([`plain`]): ethercrab alone, `tx_rx_dc` and an
//!    absolute sleep to the instant it asks for, with ethercrab's usual separate TX/RX thread.
//! 3. **`ecdrive`** — ecdrive's master ([`ecdrive`]): [`crate::master::session::Master`] and its
//!    cycle, axes enabled and holding position.
//!
//! Transports ([`Transport`]): in-process (the emulated slaves are a
//! [`crate::sim::transport::SegmentLink`] called by ecdrive's cycle thread, and an
//! [`EthercrabLink`](crate::sim::transport::EthercrabLink) thread for plain ethercrab); a veth
//! pair the harness creates, with the emulated slaves served on its far end inside a network
//! namespace by a thread of this process (root); or any interface, whose far end is not the
//! harness's (`ecdrive sim` elsewhere, or real drives).
//!
//! # How each figure is measured
//!
//! | figure | sleep | ethercrab | ecdrive |
//! |---|---|---|---|
//! | wake-up latency | woke − grid instant | woke − (exchange start + `next_cycle_wait`) | the cycle's `Timing::wake_latency` (same DC-aligned rule) |
//! | period | woke − previous woke | same | `Timing::period` |
//! | period error | \|period − cycle\|, derived from the period histogram (resolution 0.1 % of the period) | same | same |
//! | frame round trip | — | around `tx_rx_dc().await` (includes the hand-over to and from the TX/RX thread) | `Timing::exchange`: `tx_rx_dc` polled and pumped inline |
//! | busy | woke → ready to sleep | same | `Timing::busy` |
//! | late cycles | wake-up more than one cycle late | same | the cycle's overruns (same rule) |
//! | missed cycles | — | `tx_rx_dc` failed, or the reply came later than 0.8 cycle after the wake-up | cycles without a reply within the cycle's reply budget (0.8 cycle) |
//! | syscalls per cycle (opt-in) | the cycle thread's, `raw_syscalls:sys_enter` tracepoint ([`cpu::SyscallWindow`]) | the loop thread's (not the TX/RX thread's) | the cycle thread's |
//! | CPU per cycle | see [`cpu`]: thread CPU clocks read when the window opens and closes, ÷ cycles | loop thread + TX/RX thread (reported apart too) | cycle thread (frame I/O included), sampled by `CycleHooks` on the cycle thread |
//! | DC system-time difference | — | \|0x092C\| of each emulated ESC after every drift-compensation write in OP, read from the emulated ESC after the run ([`crate::sim::esc::TimingStats`]) | same |
//! | frame arrival after SYNC0 | — | at each emulated ESC, time from the latest SYNC0 to the frame completing its outputs, in OP; and SYNC0 pulses that found no fresh outputs | same |
//!
//! The steady-state window: plain ethercrab from the first cycle after every device reported
//! OP; ecdrive from the cycle after every drive reached OP to the stop request
//! ([`CycleSettings::steady_timing_only`](crate::master::cycle::CycleSettings)); the sleep loop
//! after 10 warm-up cycles. The drive figures (DC difference, SYNC0) come from the emulated
//! slaves and are empty when the far end is not the harness's (`--interface`); they cover the
//! whole time each drive was in OP from its first SYNC0 pulse on (both masters start SYNC0
//! 100 ms after the DC set-up, and an emulated drive may reach OP before that).
//!
//! Both masters configure the same DC SYNC0: 100 ms start delay, SYNC0 period = cycle, frames
//! sent [`JitterConfig::sync0_shift`] after SYNC0 (default half a cycle, ecdrive's default).
//!
//! Emulated drives: any sim device with a drive profile (`generic-coe`, the only one that runs
//! at 125 µs, and the emulated `mr-j4-tm` and `bdhde` from 250 µs).
//!
//! In-process, the emulated slaves run on ecdrive's cycle thread and on plain ethercrab's TX/RX
//! thread, so the master CPU figure (cycle thread + TX/RX thread) contains the same slave work
//! in both; over a veth pair it contains none.
//!
//! # JSON
//!
//! [`JitterReport`] serialises to one object (all times in ns, ratios are ecdrive ÷ baseline,
//! `null` where a figure does not exist or a denominator is 0):
//!
//! ```text
//! {
//!   "schema": "ecdrive-jitter/1", "version": "0.1.0",
//!   "host": { "kernel", "preempt_rt", "cpu_model", "cpus", "governor", "isolated_cpus",
//!             "sched_rt_runtime_us" },
//!   "settings": { "cycle_ns", "cycles", "transport", "interface", "priority", "cpu",
//!                 "lock_memory", "drives": [..], "profiles": [..], "ecdrive_axes",
//!                 "count_syscalls", "sync0_shift_ns" },
//!   "priority_granted": bool, "warnings": [..],
//!   "sleep" | "ethercrab" | "ecdrive": {
//!     "name", "rt": { "priority_granted", "cpu_pinned", "memory_locked", "warnings" },
//!     "cycles",
//!     "wake_latency" | "period" | "period_error" | "busy": SUMMARY,
//!     "exchange": SUMMARY | null,
//!     "late": n, "missed": n | null,
//!     "cpu": { "method", "cycles", "window_s", "cycle_thread_ns", "io_thread_ns",
//!              "master_ns", "process_ns", "voluntary_switches", "involuntary_switches",
//!              "syscalls" },
//!     "drives": [ { "position", "device", "dc_difference": SUMMARY | null,
//!                   "arrival_after_sync0": SUMMARY | null, "sync0_pulses",
//!                   "sync0_without_outputs" } ],
//!     "wake_latency_histogram": [ { "lo_ns", "hi_ns", "count" } ],
//!     "notes": [..]
//!   },
//!   "ratios": { "ecdrive_to_sleep" | "ecdrive_to_ethercrab": {
//!     "wake_latency" | "period_error" | "busy": RATIO, "exchange": RATIO | null,
//!     "late", "missed", "cpu_master", "cpu_cycle_thread", "cpu_process",
//!     "drives": [ { "position", "dc_difference": RATIO | null,
//!                   "arrival_after_sync0": RATIO | null } ] } },
//!   "command": "ecdrive jitter …"   (added by the CLI)
//! }
//! SUMMARY = { "count", "min", "p50", "p90", "p99", "p999", "max", "mean" }
//! RATIO   = { "p50", "p90", "p99", "p999", "max" }
//! ```

pub mod cpu;
pub mod ecdrive;
pub mod emulated;
pub mod far_end;
pub mod plain;
pub mod report;
pub mod sleep;
pub mod svg;

pub use emulated::EmulationError;
pub use report::{AllRatios, JitterReport, Ratios, RunReport};

use crate::link::netns::{NetnsError, VethPair, is_root};
use crate::link::{LinkError, RawSocket};
use crate::rt::RtSettings;
use crate::rt::host::HostInfo;
use crate::sim::Segment;
use crate::sim::transport::SegmentLink;
use report::{DriveTiming, SettingsReport, summary_of};
use std::time::Duration;

/// Where the masters' frames go.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Transport {
    /// In-process emulated slaves; no network, no root.
    InProcess,
    /// A veth pair the harness creates, the emulated slaves on its far end (root).
    Veth,
    /// An existing interface; its far end must already serve the drives (root or
    /// `CAP_NET_RAW`).
    Interface(String),
}

/// What to measure.
#[derive(Debug, Clone, PartialEq)]
pub struct JitterConfig {
    /// Cycle time.
    pub cycle: Duration,
    /// Cycles per run.
    pub cycles: u64,
    /// Transport.
    pub transport: Transport,
    /// Real-time set-up of every run's cycle thread.
    pub rt: RtSettings,
    /// The emulated drives (sim device names, see [`crate::sim::devices::DEVICE_NAMES`]), in
    /// line order. Empty with [`Transport::Interface`]: the drives on the far end are
    /// discovered (each must match a drive profile).
    pub drives: Vec<String>,
    /// How long the drives may take to reach OP.
    pub op_timeout: Duration,
    /// Also count each run's cycle-thread syscalls per cycle (root or `perf_event_paranoid`
    /// ≤ 1; the tracepoint adds a little to every syscall, so leave it off for CPU figures).
    pub count_syscalls: bool,
    /// When both masters send their frame after SYNC0; `None`: half a cycle (ecdrive's
    /// default, see [`crate::master::startup::DcSettings`]).
    pub sync0_shift: Option<Duration>,
}

impl JitterConfig {
    /// Defaults: in-process, two generic CoE drives, SCHED_FIFO 80 with memory locked, 10 s.
    pub fn new(cycle: Duration) -> Self {
        let cycles = (10_000_000_000 / cycle.as_nanos().max(1)) as u64;
        Self {
            cycle,
            cycles,
            transport: Transport::InProcess,
            rt: RtSettings {
                priority: Some(80),
                cpu: None,
                lock_memory: true,
            },
            drives: vec!["generic-coe".into(), "generic-coe".into()],
            op_timeout: Duration::from_secs(10),
            count_syscalls: false,
            sync0_shift: None,
        }
    }
}

/// Why a measurement failed.
#[derive(Debug, thiserror::Error)]
pub enum HarnessError {
    /// The settings cannot be measured.
    #[error("invalid settings: {0}")]
    Settings(String),
    /// The emulated drives cannot be built.
    #[error(transparent)]
    Emulation(#[from] EmulationError),
    /// One run failed.
    #[error("{run} run: {what}: {reason}")]
    Run {
        /// `sleep`, `ethercrab` or `ecdrive`.
        run: &'static str,
        /// What was being done.
        what: String,
        /// Why it failed.
        reason: String,
    },
    /// The veth pair could not be set up.
    #[error("veth pair: {0}")]
    Netns(#[from] NetnsError),
    /// The interface could not be opened.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The drives on the far end of the interface could not be discovered.
    #[error("discovering the drives on {interface}: {reason}")]
    Discovery {
        /// The interface.
        interface: String,
        /// Why.
        reason: String,
    },
}

/// The drives on the far end of `interface`, by discovery: each device's profile key (as
/// `drives` in the report) and its profile. Every device must be a drive with a profile.
fn discover_far_end(
    interface: &str,
) -> Result<(Vec<String>, Vec<&'static crate::drives::DriveProfile>), HarnessError> {
    use crate::app::ethercat::tools::{Target, session};
    let target = Target::Interface(interface.to_string());
    let devices = session(&target, |bus| {
        crate::master::startup::discover(bus).map(|(_, devices)| devices)
    })
    .map_err(|e| HarnessError::Discovery {
        interface: interface.to_string(),
        reason: e.to_string(),
    })?;
    let mut names = Vec::with_capacity(devices.len());
    let mut profiles = Vec::with_capacity(devices.len());
    for d in &devices {
        let p = emulated::profile_of_identity(d.vendor_id, d.product_code).ok_or_else(|| {
            HarnessError::Settings(format!(
                "device {} on {interface} ({}, vendor 0x{:08X}, product 0x{:08X}) matches no \
                 drive profile: the harness measures a line of drives (name them with --device \
                 to say what the far end serves)",
                d.position, d.name, d.vendor_id, d.product_code
            ))
        })?;
        names.push(p.key.to_string());
        profiles.push(p);
    }
    Ok((names, profiles))
}

fn drive_timings(segment: &Segment, names: &[String]) -> Vec<DriveTiming> {
    segment
        .slaves()
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            s.esc.timing_stats().map(|t| DriveTiming {
                position: i as u16,
                device: names.get(i).cloned().unwrap_or_default(),
                dc_difference: (!t.dc_difference.is_empty()).then(|| summary_of(&t.dc_difference)),
                arrival_after_sync0: (!t.arrival_after_sync0.is_empty())
                    .then(|| summary_of(&t.arrival_after_sync0)),
                sync0_pulses: t.sync0_pulses,
                sync0_without_outputs: t.sync0_without_outputs,
            })
        })
        .collect()
}

/// Run the three measurements. `progress` is told what starts (one line each).
pub fn run(cfg: &JitterConfig, progress: &dyn Fn(&str)) -> Result<JitterReport, HarnessError> {
    let cycle_ns = u64::try_from(cfg.cycle.as_nanos()).unwrap_or(u64::MAX);
    if !(50_000..=100_000_000).contains(&cycle_ns) {
        return Err(HarnessError::Settings(format!(
            "cycle time {} µs is outside 50 µs … 100 ms",
            cycle_ns / 1000
        )));
    }
    if cfg.cycles < 10 {
        return Err(HarnessError::Settings(format!(
            "{} cycles per run are too few (at least 10)",
            cfg.cycles
        )));
    }
    let (drives, profiles) = match &cfg.transport {
        Transport::Interface(i) if cfg.drives.is_empty() => {
            progress(&format!("discovering the drives on {i}"));
            discover_far_end(i)?
        }
        _ => (cfg.drives.clone(), emulated::profiles(&cfg.drives)?),
    };
    let sync0_shift = cfg.sync0_shift.unwrap_or(cfg.cycle / 2);
    if sync0_shift >= cfg.cycle {
        return Err(HarnessError::Settings(format!(
            "the SYNC0 shift ({} µs) must be shorter than the cycle",
            sync0_shift.as_micros()
        )));
    }
    let veth = match &cfg.transport {
        Transport::Veth if !is_root() => {
            return Err(HarnessError::Settings(
                "the veth transport needs root (network namespaces and raw sockets)".into(),
            ));
        }
        Transport::Veth => Some(VethPair::create()?),
        _ => None,
    };
    let interface = match (&cfg.transport, &veth) {
        (_, Some(v)) => Some(v.host().to_string()),
        (Transport::Interface(i), None) => Some(i.clone()),
        _ => None,
    };
    let far_end = |what: &'static str| -> Result<Option<far_end::FarEnd>, HarnessError> {
        match &veth {
            Some(v) => {
                let socket = v.open_peer_socket()?;
                let seg = emulated::segment(&cfg.drives)?;
                let rt = RtSettings {
                    priority: cfg.rt.priority,
                    cpu: None,
                    lock_memory: false,
                };
                far_end::FarEnd::spawn(socket, seg, rt)
                    .map(Some)
                    .map_err(|e| HarnessError::Run {
                        run: what,
                        what: "starting the emulated drives on the veth far end".into(),
                        reason: e.to_string(),
                    })
            }
            None => Ok(None),
        }
    };
    let stop_far_end = |f: Option<far_end::FarEnd>, run: &'static str| -> Option<Segment> {
        let f = f?;
        match f.stop() {
            Ok((seg, Ok(_))) => Some(seg),
            Ok((seg, Err(e))) => {
                tracing::warn!("{run} run: the veth far end reported: {e}");
                Some(seg)
            }
            Err(e) => {
                tracing::warn!("{run} run: {e}");
                None
            }
        }
    };

    // 1. The bare sleep loop.
    progress(&format!(
        "sleep: {} cycles of {} µs",
        cfg.cycles,
        cycle_ns / 1000
    ));
    let sleep = sleep::run(cfg.cycle, cfg.cycles, &cfg.rt, cfg.count_syscalls).map_err(|e| {
        HarnessError::Run {
            run: "sleep",
            what: "running".into(),
            reason: e.to_string(),
        }
    })?;

    // 2. Plain ethercrab.
    progress("ethercrab: start-up, then the measured cycles");
    let plain_settings = plain::PlainSettings {
        cycle: cfg.cycle,
        cycles: cfg.cycles,
        rt: cfg.rt.clone(),
        profiles: profiles.clone(),
        op_timeout: cfg.op_timeout,
        reply_budget: 0.8,
        count_syscalls: cfg.count_syscalls,
        sync0_shift,
    };
    let (mut ethercrab, seg) = match &cfg.transport {
        Transport::InProcess => plain::run(
            plain::PlainTransport::InProcess(emulated::segment(&cfg.drives)?),
            &plain_settings,
        )?,
        Transport::Veth | Transport::Interface(_) => {
            let fe = far_end("ethercrab")?;
            let iface = interface.clone().unwrap_or_default();
            let r = plain::run(plain::PlainTransport::Interface(iface), &plain_settings);
            let seg = stop_far_end(fe, "ethercrab");
            let (rep, _) = r?;
            (rep, seg)
        }
    };
    if let Some(seg) = &seg {
        ethercrab.drives = drive_timings(seg, &drives);
    }

    // 3. ecdrive.
    progress("ecdrive: start-up, then the measured cycles");
    let ec_settings = ecdrive::EcdriveSettings {
        cycle: cfg.cycle,
        cycles: cfg.cycles,
        rt: cfg.rt.clone(),
        profiles: profiles.clone(),
        op_timeout: cfg.op_timeout,
        count_syscalls: cfg.count_syscalls,
        sync0_shift,
    };
    let (mut ecd, seg) = match &cfg.transport {
        Transport::InProcess => {
            let link = SegmentLink::new(emulated::segment(&cfg.drives)?);
            let (rep, link) = ecdrive::run(link, &ec_settings)?;
            (rep, Some(link.into_segment()))
        }
        Transport::Veth | Transport::Interface(_) => {
            let fe = far_end("ecdrive")?;
            let iface = interface.clone().unwrap_or_default();
            let r = RawSocket::open(&iface)
                .map_err(HarnessError::from)
                .and_then(|s| ecdrive::run(s, &ec_settings));
            let seg = stop_far_end(fe, "ecdrive");
            let (rep, _) = r?;
            (rep, seg)
        }
    };
    if let Some(seg) = &seg {
        ecd.drives = drive_timings(seg, &drives);
    }
    if interface.is_some() && veth.is_none() {
        for r in [&mut ethercrab, &mut ecd] {
            r.notes
                .push("the far end is not the harness's: no DC difference or SYNC0 figures".into());
        }
    }

    let mut warnings: Vec<String> = Vec::new();
    for r in [&sleep, &ethercrab, &ecd] {
        for w in &r.rt.warnings {
            if !warnings.contains(w) {
                warnings.push(w.clone());
            }
        }
    }
    let priority_granted = cfg.rt.priority.is_some()
        && [&sleep, &ethercrab, &ecd]
            .iter()
            .all(|r| r.rt.priority_granted == cfg.rt.priority);
    let ratios = AllRatios {
        ecdrive_to_sleep: Ratios::of(&ecd, &sleep),
        ecdrive_to_ethercrab: Ratios::of(&ecd, &ethercrab),
    };
    Ok(JitterReport {
        schema: report::SCHEMA,
        version: env!("CARGO_PKG_VERSION"),
        host: HostInfo::read(),
        settings: SettingsReport {
            count_syscalls: cfg.count_syscalls,
            sync0_shift_ns: u64::try_from(sync0_shift.as_nanos()).unwrap_or(u64::MAX),
            cycle_ns,
            cycles: cfg.cycles,
            transport: match cfg.transport {
                Transport::InProcess => "in-process",
                Transport::Veth => "veth",
                Transport::Interface(_) => "interface",
            }
            .into(),
            interface,
            priority: cfg.rt.priority,
            cpu: cfg.rt.cpu,
            lock_memory: cfg.rt.lock_memory,
            drives,
            profiles: profiles.iter().map(|p| p.name.to_string()).collect(),
            ecdrive_axes: "enabled in csp once in OP, holding position".into(),
        },
        priority_granted,
        warnings,
        sleep,
        ethercrab,
        ecdrive: ecd,
        ratios,
    })
}
