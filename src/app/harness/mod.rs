//! The cycle-jitter harness behind `ecdrive jitter`: ecdrive's cycle measured against the floor
//! of the machine and against two other masters, in one invocation.
//!
//! [`run`] measures up to four loops **one after the other** (never concurrently), each for the
//! same number of cycles at the same cycle time, with the same real-time set-up
//! ([`RtSettings`]: SCHED_FIFO priority, CPU, memory locking) and on the same emulated drives:
//!
//! 1. **`sleep`** — the bare sleep loop ([`sleep`]): absolute `clock_nanosleep` on a fixed grid,
//!    nothing else; the `cyclictest` floor of this machine.
//! 2. **`ethercrab`** — the plain ethercrab loop ([`plain`]): ethercrab alone, `tx_rx_dc` and an
//!    absolute sleep to the instant it asks for, with ethercrab's usual separate TX/RX thread.
//! 3. **`soem`** — a minimal C loop on SOEM ([`soem`]), a separate process, over a network
//!    interface only, when its program was built (`benches/soem/build.sh`); otherwise the
//!    report says why it is absent.
//! 4. **`ecdrive`** — ecdrive's master ([`ecdrive`]): [`crate::master::session::Master`] with
//!    its defaults (emergency polling on), axes enabled and holding position.
//!
//! With [`JitterConfig::repeat`] the four are repeated, interleaved (sleep, ethercrab, soem,
//! ecdrive, sleep, …); every figure and every ratio is kept per repetition and summarised as
//! median, min and max ([`report::AcrossRepetitions`]). With [`JitterConfig::stress`] a
//! documented background load ([`stress`]) runs during all of them.
//!
//! Transports ([`Transport`]): in-process (the emulated slaves are a
//! [`crate::sim::transport::SegmentLink`] called by ecdrive's cycle thread, and an
//! [`EthercrabLink`](crate::sim::transport::EthercrabLink) thread for plain ethercrab that, like
//! ecdrive's link, wakes for frames only); a veth pair the harness creates, with the emulated
//! slaves served on its far end inside a network namespace by a thread of this process (root);
//! or any interface, whose far end is not the harness's (`ecdrive sim` elsewhere, or real
//! drives).
//!
//! # Like for like
//!
//! - Both Rust masters see the same in-process link behaviour: the slaves' time-driven work
//!   (SYNC0 events) is done when the next frame arrives, on the thread that moves frames (the
//!   TX/RX thread for ethercrab, the cycle thread for ecdrive), so it is charged to both.
//! - Over veth the slaves run on a harness thread (`jitter-far-end`) charged to no master.
//! - CPU is compared as the whole master: the sum over every thread the run started (cycle,
//!   TX/RX, session, the async-io timer thread), from `/proc/self/task/*/schedstat` at the
//!   window's edges; SOEM's is its process's CPU time. Each run's [`report::RunStructure`]
//!   says which threads, which link and whether mailboxes are polled.
//!
//! # How each figure is measured
//!
//! | figure | sleep | ethercrab | soem | ecdrive |
//! |---|---|---|---|---|
//! | wake-up latency | woke − grid instant | woke − (exchange start + `next_cycle_wait`) | woke − intended instant (steered to the reference clock by the loop) | the cycle's `Timing::wake_latency` (same DC-aligned rule) |
//! | period | woke − previous woke | same | same | `Timing::period` |
//! | period error | \|period − cycle\|, derived from the period histogram (resolution 0.1 % of the period) | same | same | same |
//! | frame round trip | — | around `tx_rx_dc().await` (includes the hand-over to and from the TX/RX thread) | around `ec_send_processdata` + `ec_receive_processdata` | `Timing::exchange`: `tx_rx_dc` polled and pumped inline |
//! | busy | woke → ready to sleep | same | same | `Timing::busy` |
//! | late cycles | wake-up more than one cycle late | same | same | the cycle's overruns (same rule) |
//! | missed cycles | — | `tx_rx_dc` failed, or the reply came later than 0.8 cycle after the wake-up | no frame, wrong working counter, or later than 0.8 cycle | cycles without a reply within the cycle's reply budget (0.8 cycle) |
//! | syscalls per cycle (opt-in) | the cycle thread's, `raw_syscalls:sys_enter` tracepoint ([`cpu::SyscallWindow`]) | the loop thread's (not the TX/RX thread's) | — | the cycle thread's |
//! | CPU per cycle | see [`cpu`] | every master thread (loop, TX/RX, async-io) | its process | every master thread (cycle, session) |
//! | DC system-time difference | — | \|0x092C\| of each emulated ESC after every drift-compensation write in OP, read from the emulated ESC after the run ([`crate::sim::esc::TimingStats`]) | same | same |
//! | frame arrival after SYNC0 | — | at each emulated ESC, time from the latest SYNC0 to the frame completing its outputs, in OP; and SYNC0 pulses that found no fresh outputs | same | same |
//!
//! The steady-state window: plain ethercrab and SOEM from the first cycle after every device
//! reported OP; ecdrive from the cycle after every drive reached OP to the stop request
//! ([`CycleSettings::steady_timing_only`](crate::master::cycle::CycleSettings)); the sleep loop
//! after 10 warm-up cycles. The drive figures (DC difference, SYNC0) come from the emulated
//! slaves and are empty when the far end is not the harness's (`--interface`); they cover the
//! whole time each drive was in OP from its first SYNC0 pulse on.
//!
//! Every master configures the same DC SYNC0: SYNC0 period = cycle, frames sent
//! [`JitterConfig::sync0_shift`] after SYNC0 (default half a cycle, ecdrive's default).
//!
//! Emulated drives: any sim device with a drive profile (`generic-coe`, the only one that runs
//! at 125 µs, and the emulated `mr-j4-tm` and `bdhde` from 250 µs).
//!
//! # JSON
//!
//! [`JitterReport`] serialises to one object (all times in ns, ratios are ecdrive ÷ baseline,
//! `null` where a figure does not exist or a denominator is 0):
//!
//! ```text
//! {
//!   "schema": "ecdrive-jitter/2", "version": "0.1.0", "commit": "…",
//!   "host": { "kernel", "preempt_rt", "cpu_model", "cpus", "governor", "isolated_cpus",
//!             "sched_rt_runtime_us" },
//!   "settings": { "cycle_ns", "cycles", "transport", "interface", "priority", "cpu",
//!                 "lock_memory", "drives": [..], "profiles": [..], "ecdrive_axes",
//!                 "count_syscalls", "sync0_shift_ns", "repeat", "soem_program" },
//!   "load": { "loadavg_before", "loadavg_after", "stress", "stress_cpus" },
//!   "priority_granted": bool, "warnings": [..], "soem_absent": "why" | null,
//!   "repetitions": [ {
//!     "index",
//!     "sleep" | "ethercrab" | "soem" (or null) | "ecdrive": {
//!       "name", "structure": { "link", "mailbox_poll_ms", "master_threads", "slaves" },
//!       "rt": { "priority_granted", "cpu_pinned", "memory_locked", "warnings" },
//!       "cycles",
//!       "wake_latency" | "period" | "period_error" | "busy": SUMMARY,
//!       "exchange": SUMMARY | null,
//!       "late": n, "missed": n | null,
//!       "cpu": { "method", "cycles", "window_s", "cycle_thread_ns", "io_thread_ns",
//!                "master_ns", "process_ns", "voluntary_switches", "involuntary_switches",
//!                "syscalls", "threads": [ { "name", "role", "cpu_ns", "voluntary",
//!                "involuntary" } ] },
//!       "drives": [ { "position", "device", "dc_difference": SUMMARY | null,
//!                     "arrival_after_sync0": SUMMARY | null, "sync0_pulses",
//!                     "sync0_without_outputs" } ],
//!       "wake_latency_histogram": [ { "lo_ns", "hi_ns", "count" } ],
//!       "parts": null | { "receive_ns", "receive_link_ns", "engine_ns", "supervision_ns",
//!                "telemetry_ns", "send_ns", "send_link_ns", "sleep_and_wake_ns" }
//!                (ecdrive's cycle thread per cycle by part),
//!       "notes": [..]
//!     },
//!     "ratios": { "ecdrive_to_sleep" | "ecdrive_to_ethercrab" | "ecdrive_to_soem" (or null): {
//!       "wake_latency" | "period_error" | "busy": RATIO, "exchange": RATIO | null,
//!       "late", "missed", "cpu_master", "cpu_cycle_thread", "cpu_process",
//!       "drives": [ { "position", "dc_difference": RATIO | null,
//!                     "arrival_after_sync0": RATIO | null } ] } }
//!   } ],
//!   "summary": { "runs": { RUN: { FIGURE: SPREAD } }, "ratios": { RATIO_NAME: { FIGURE: SPREAD } } },
//!   "command": "ecdrive jitter …"   (added by the CLI)
//! }
//! SUMMARY = { "count", "min", "p50", "p90", "p99", "p999", "max", "mean" }
//! RATIO   = { "p50", "p90", "p99", "p999", "max" }
//! SPREAD  = { "median", "min", "max", "values": [one per repetition] }
//! FIGURE  = wake_latency_p50 | _p99 | _p999 | _max, period_error_p50 | _max, exchange_p50 |
//!           _p99 | _max, busy_p50 | _max, cpu_master_ns, cpu_process_ns, late, missed,
//!           and ecdrive's parts: part_receive_ns, part_receive_link_ns, part_engine_ns,
//!           part_supervision_ns, part_telemetry_ns, part_send_ns, part_send_link_ns,
//!           part_sleep_and_wake_ns
//!           (ratios: wake_latency_p50 | _p99 | _max, period_error_p50, exchange_p50 | _p99,
//!           busy_p50, cpu_master, cpu_process, missed)
//! ```

pub mod cpu;
pub mod ecdrive;
pub mod emulated;
pub mod far_end;
pub mod plain;
pub mod report;
pub mod sleep;
pub mod soem;
pub mod stress;
pub mod svg;

pub use emulated::EmulationError;
pub use report::{AllRatios, JitterReport, Ratios, Repetition, RunReport};

use cpu::FAR_END_THREAD;

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
    /// When every master sends its frame after SYNC0; `None`: half a cycle (ecdrive's
    /// default, see [`crate::master::startup::DcSettings`]).
    pub sync0_shift: Option<Duration>,
    /// Repetitions, interleaved: sleep, ethercrab, SOEM, ecdrive, sleep, … (1–100).
    pub repeat: usize,
    /// Run a background load during the measurements ([`stress`]).
    pub stress: bool,
    /// The SOEM loop program (`benches/soem/build.sh` builds it); `None`: no SOEM run.
    pub soem: Option<std::path::PathBuf>,
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
            repeat: 1,
            stress: false,
            soem: None,
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

/// Why there is no SOEM run with these settings and this program (`None`: it runs).
fn soem_absent(cfg: &JitterConfig) -> Option<String> {
    if cfg.transport == Transport::InProcess {
        return Some(
            "SOEM needs a network interface (--veth or --interface); this measurement is \
             in-process"
                .into(),
        );
    }
    match &cfg.soem {
        None => Some("no SOEM loop program was given (--soem, or --no-soem)".into()),
        Some(p) => soem::unusable(p),
    }
}

/// What every repetition shares.
struct Plan<'a> {
    cfg: &'a JitterConfig,
    cycle_ns: u64,
    drives: Vec<String>,
    profiles: Vec<&'static crate::drives::DriveProfile>,
    sync0_shift: Duration,
    veth: Option<VethPair>,
    interface: Option<String>,
    soem: Option<std::path::PathBuf>,
}

impl Plan<'_> {
    /// Serve the emulated drives on the veth far end (`None` without the harness's veth).
    fn far_end(&self, run: &'static str) -> Result<Option<far_end::FarEnd>, HarnessError> {
        let Some(v) = &self.veth else {
            return Ok(None);
        };
        let socket = v.open_peer_socket()?;
        let seg = emulated::segment(&self.cfg.drives)?;
        let rt = RtSettings {
            priority: self.cfg.rt.priority,
            cpu: None,
            lock_memory: false,
        };
        far_end::FarEnd::spawn(socket, seg, rt)
            .map(Some)
            .map_err(|e| HarnessError::Run {
                run,
                what: "starting the emulated drives on the veth far end".into(),
                reason: e.to_string(),
            })
    }

    /// The drives' figures of a run (from the segment it ran against, if the harness has it).
    fn drives_of(&self, seg: Option<Segment>, run: &mut RunReport) {
        if let Some(seg) = &seg {
            run.drives = drive_timings(seg, &self.drives);
        } else if self.interface.is_some() {
            run.notes
                .push("the far end is not the harness's: no DC difference or SYNC0 figures".into());
        }
    }

    fn slaves(&self, in_process_on: &str) -> String {
        match (&self.cfg.transport, &self.veth) {
            (Transport::InProcess, _) => format!(
                "in this process, on {in_process_on} (charged to the master, as in the other \
                 master's run)"
            ),
            (_, Some(_)) => format!(
                "a thread of the harness ({FAR_END_THREAD}) on the veth far end, in a network \
                 namespace (charged to no master)"
            ),
            _ => "on the far end of the interface (not this machine's figures)".into(),
        }
    }

    fn repetition(
        &self,
        index: usize,
        progress: &dyn Fn(&str),
    ) -> Result<Repetition, HarnessError> {
        let cfg = self.cfg;
        let tag = if cfg.repeat > 1 {
            format!("[{index}/{}] ", cfg.repeat)
        } else {
            String::new()
        };
        // 1. The bare sleep loop.
        cpu::begin_run();
        progress(&format!(
            "{tag}sleep: {} cycles of {} µs",
            cfg.cycles,
            self.cycle_ns / 1000
        ));
        let mut sleep =
            sleep::run(cfg.cycle, cfg.cycles, &cfg.rt, cfg.count_syscalls).map_err(|e| {
                HarnessError::Run {
                    run: "sleep",
                    what: "running".into(),
                    reason: e.to_string(),
                }
            })?;
        sleep.structure.link = "none (no frames)".into();
        sleep.structure.slaves = "none".into();

        // 2. Plain ethercrab.
        cpu::begin_run();
        progress(&format!(
            "{tag}ethercrab: start-up, then the measured cycles"
        ));
        let plain_settings = plain::PlainSettings {
            cycle: cfg.cycle,
            cycles: cfg.cycles,
            rt: cfg.rt.clone(),
            profiles: self.profiles.clone(),
            op_timeout: cfg.op_timeout,
            reply_budget: 0.8,
            count_syscalls: cfg.count_syscalls,
            sync0_shift: self.sync0_shift,
        };
        let (mut ethercrab, seg) = match &cfg.transport {
            Transport::InProcess => plain::run(
                plain::PlainTransport::InProcess(emulated::segment(&cfg.drives)?),
                &plain_settings,
            )?,
            Transport::Veth | Transport::Interface(_) => {
                let fe = self.far_end("ethercrab")?;
                let iface = self.interface.clone().unwrap_or_default();
                let r = plain::run(plain::PlainTransport::Interface(iface), &plain_settings);
                let seg = stop_far_end(fe, "ethercrab");
                let (rep, _) = r?;
                (rep, seg)
            }
        };
        self.drives_of(seg, &mut ethercrab);
        ethercrab.structure.link = match cfg.transport {
            Transport::InProcess => "ecdrive-sim's EthercrabLink thread as ethercrab's TX/RX \
                thread, woken by frames only (Wakeups::FramesOnly), like ecdrive's in-process \
                link"
                .into(),
            _ => "ethercrab::std::tx_rx_task on its own thread, raw socket".into(),
        };
        ethercrab.structure.slaves = self.slaves("the TX/RX thread");

        // 3. SOEM.
        cpu::begin_run();
        let soem_run = match &self.soem {
            Some(program) => {
                progress(&format!("{tag}soem: start-up, then the measured cycles"));
                let fe = self.far_end("soem")?;
                let r = soem::run(&soem::SoemSettings {
                    program: program.clone(),
                    interface: self.interface.clone().unwrap_or_default(),
                    cycle: cfg.cycle,
                    cycles: cfg.cycles,
                    rt: cfg.rt.clone(),
                    profiles: self.profiles.clone(),
                    op_timeout: cfg.op_timeout,
                    sync0_shift: self.sync0_shift,
                    reply_budget: 0.8,
                });
                let seg = stop_far_end(fe, "soem");
                let mut r = r?;
                self.drives_of(seg, &mut r);
                r.structure.slaves = self.slaves("-");
                Some(r)
            }
            None => None,
        };

        // 4. ecdrive.
        cpu::begin_run();
        progress(&format!("{tag}ecdrive: start-up, then the measured cycles"));
        let ec_settings = ecdrive::EcdriveSettings {
            cycle: cfg.cycle,
            cycles: cfg.cycles,
            rt: cfg.rt.clone(),
            profiles: self.profiles.clone(),
            op_timeout: cfg.op_timeout,
            count_syscalls: cfg.count_syscalls,
            sync0_shift: self.sync0_shift,
        };
        let (mut ecd, seg) = match &cfg.transport {
            Transport::InProcess => {
                let link = SegmentLink::new(emulated::segment(&cfg.drives)?);
                let (rep, link) = ecdrive::run(link, &ec_settings)?;
                (rep, Some(link.into_segment()))
            }
            Transport::Veth | Transport::Interface(_) => {
                let fe = self.far_end("ecdrive")?;
                let iface = self.interface.clone().unwrap_or_default();
                let r = RawSocket::open(&iface)
                    .map_err(HarnessError::from)
                    .and_then(|s| ecdrive::run(s, &ec_settings));
                let seg = stop_far_end(fe, "ecdrive");
                let (rep, _) = r?;
                (rep, seg)
            }
        };
        self.drives_of(seg, &mut ecd);
        ecd.structure.link = ecdrive_link(&cfg.transport);
        ecd.structure.slaves = self.slaves("the cycle thread");

        let ratios = AllRatios {
            ecdrive_to_sleep: Ratios::of(&ecd, &sleep),
            ecdrive_to_ethercrab: Ratios::of(&ecd, &ethercrab),
            ecdrive_to_soem: soem_run.as_ref().map(|s| Ratios::of(&ecd, s)),
        };
        Ok(Repetition {
            index,
            sleep,
            ethercrab,
            soem: soem_run,
            ecdrive: ecd,
            ratios,
        })
    }
}

fn stop_far_end(f: Option<far_end::FarEnd>, run: &'static str) -> Option<Segment> {
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
}

/// Run the measurements: `cfg.repeat` repetitions of sleep, ethercrab, SOEM (when it can run)
/// and ecdrive, interleaved. `progress` is told what starts (one line each).
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
    if !(1..=100).contains(&cfg.repeat) {
        return Err(HarnessError::Settings(format!(
            "{} repetitions: between 1 and 100",
            cfg.repeat
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
    let absent = soem_absent(cfg);
    let plan = Plan {
        cfg,
        cycle_ns,
        drives,
        profiles,
        sync0_shift,
        veth,
        interface,
        soem: if absent.is_none() {
            cfg.soem.clone()
        } else {
            None
        },
    };
    if let Some(why) = &absent {
        progress(&format!("soem: not run: {why}"));
    }
    let loadavg_before = report::loadavg();
    let stress = if cfg.stress {
        let s = stress::Stress::start(cfg.rt.cpu)
            .map_err(|e| HarnessError::Settings(format!("starting the --stress load: {e}")))?;
        progress(&format!("stress: load on CPU(s) {:?}", s.cpus));
        Some(s)
    } else {
        None
    };
    let mut repetitions = Vec::with_capacity(cfg.repeat);
    let mut failed = None;
    for index in 1..=cfg.repeat {
        match plan.repetition(index, progress) {
            Ok(r) => repetitions.push(r),
            Err(e) => {
                failed = Some(e);
                break;
            }
        }
    }
    let stress_cpus = stress.as_ref().map(|s| s.cpus.clone()).unwrap_or_default();
    if let Some(s) = stress {
        s.stop();
    }
    if let Some(e) = failed {
        return Err(e);
    }
    let loadavg_after = report::loadavg();

    let mut warnings: Vec<String> = Vec::new();
    let mut granted = cfg.rt.priority.is_some();
    for r in repetitions.iter().flat_map(Repetition::runs) {
        for w in &r.rt.warnings {
            if !warnings.contains(w) {
                warnings.push(w.clone());
            }
        }
        granted &= r.rt.priority_granted == cfg.rt.priority;
    }
    let summary = report::AcrossRepetitions::of(&repetitions);
    Ok(JitterReport {
        schema: report::SCHEMA,
        version: env!("CARGO_PKG_VERSION"),
        commit: env!("ECDRIVE_GIT_COMMIT"),
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
            interface: plan.interface.clone(),
            priority: cfg.rt.priority,
            cpu: cfg.rt.cpu,
            lock_memory: cfg.rt.lock_memory,
            drives: plan.drives.clone(),
            profiles: plan.profiles.iter().map(|p| p.name.to_string()).collect(),
            ecdrive_axes: "enabled in csp once in OP, holding position; ecdrive's defaults \
                (emergency polling on)"
                .into(),
            repeat: cfg.repeat,
            soem_program: plan.soem.as_ref().map(|p| p.display().to_string()),
        },
        load: report::LoadReport {
            loadavg_before,
            loadavg_after,
            stress: cfg.stress.then(|| stress::WHAT.to_string()),
            stress_cpus,
        },
        priority_granted: granted,
        warnings,
        soem_absent: absent,
        repetitions,
        summary,
    })
}

/// How ecdrive's run moves its frames, in words. Its default reply wait: the frame flies while
/// the cycle thread sleeps, so its exchange figure is the reading of the reply at the wake-up,
/// not the round trip.
fn ecdrive_link(transport: &Transport) -> String {
    let reply = "; the frame goes out at the end of the cycle and its reply is read at the next \
                 wake-up (exchange = that read, not the round trip); the frames are ecdrive's \
                 own, learnt from ethercrab's tx_rx_dc in the first cycle (a note says so when \
                 they were not)";
    match transport {
        Transport::InProcess => {
            format!(
                "ecdrive-sim's SegmentLink, called by the cycle thread (no TX/RX thread){reply}"
            )
        }
        _ => format!(
            "raw socket (frames received through its ring shared with the kernel), frames sent \
             and received by the cycle thread (no TX/RX thread){reply}"
        ),
    }
}
