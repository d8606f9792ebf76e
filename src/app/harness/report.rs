//! What a jitter measurement produces: per run the summaries, counts, CPU time and per-drive
//! figures; the ratios of ecdrive to both baselines; the host conditions. Serialises to the JSON
//! documented in [the module documentation](super).

use super::cpu::CpuReport;
use crate::rt::host::HostInfo;
use crate::rt::{LatencyHistogram, RtReport, Summary};
use hdrhistogram::Histogram;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Version tag of the JSON layout.
pub const SCHEMA: &str = "ecdrive-jitter/2";

/// The percentile summary of an hdrhistogram (ns).
pub fn summary_of(h: &Histogram<u64>) -> Summary {
    if h.is_empty() {
        return Summary::default();
    }
    Summary {
        count: h.len(),
        min: h.min(),
        p50: h.value_at_quantile(0.50),
        p90: h.value_at_quantile(0.90),
        p99: h.value_at_quantile(0.99),
        p999: h.value_at_quantile(0.999),
        max: h.max(),
        mean: h.mean(),
    }
}

/// One bin of a log-spaced histogram: values in `[lo_ns, hi_ns)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Bucket {
    /// Lower bound, ns.
    pub lo_ns: u64,
    /// Upper bound (exclusive), ns.
    pub hi_ns: u64,
    /// Samples in the bin.
    pub count: u64,
}

/// Bins per decade of [`buckets`].
pub const BINS_PER_DECADE: u32 = 20;

/// The non-empty bins of `h` on a log scale ([`BINS_PER_DECADE`] per decade, from 1 ns).
pub fn buckets(h: &Histogram<u64>) -> Vec<Bucket> {
    let mut out: Vec<Bucket> = Vec::new();
    let edge = |k: u32| -> u64 {
        10f64
            .powf(f64::from(k) / f64::from(BINS_PER_DECADE))
            .round() as u64
    };
    for v in h.iter_recorded() {
        let value = v.value_iterated_to().max(1);
        let count = v.count_at_value();
        let k = ((value as f64).log10() * f64::from(BINS_PER_DECADE))
            .floor()
            .max(0.0) as u32;
        let (lo, hi) = (edge(k), edge(k + 1).max(edge(k) + 1));
        match out.last_mut() {
            Some(b) if b.lo_ns == lo => b.count += count,
            _ => out.push(Bucket {
                lo_ns: lo,
                hi_ns: hi,
                count,
            }),
        }
    }
    out
}

/// What the emulated slave saw of one run at one drive (from its ESC's timing statistics, see
/// [`crate::sim::esc::TimingStats`]), over the whole time the drive was in OP (the measured
/// window and the few cycles before and after it). Only available when the harness runs the
/// emulated segment itself (in-process, or over the veth pair it creates).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DriveTiming {
    /// Position on the segment.
    pub position: u16,
    /// Emulated device.
    pub device: String,
    /// |DC system-time difference| (0x092C) after each drift-compensation write in OP, ns;
    /// `None` for the reference clock (it is the time the others are compared with).
    pub dc_difference: Option<Summary>,
    /// Time from the latest SYNC0 to the frame completing the outputs, in OP, ns; `None` if no
    /// frame arrived in OP.
    pub arrival_after_sync0: Option<Summary>,
    /// SYNC0 pulses in OP.
    pub sync0_pulses: u64,
    /// SYNC0 pulses in OP that found no fresh outputs (the frame came late or not at all).
    pub sync0_without_outputs: u64,
}

/// What a run consists of, so that a reader (and a test) can check that each run is what it
/// says: how frames reach the slaves, which threads the master has, whether it polls
/// mailboxes, and where the emulated slaves' work is charged.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RunStructure {
    /// How the frames reach the emulated slaves.
    pub link: String,
    /// Mailbox (emergency) polling during the window: its period, ms; `None`: no polling.
    pub mailbox_poll_ms: Option<u64>,
    /// The master's threads that ran during the window (kernel names, at most 15
    /// characters).
    pub master_threads: Vec<String>,
    /// Where the emulated slaves ran, and whose CPU figure holds their work.
    pub slaves: String,
}

/// One measured run: the bare sleep loop, the plain ethercrab loop, the SOEM loop or ecdrive.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    /// `sleep`, `ethercrab`, `soem` or `ecdrive`.
    pub name: &'static str,
    /// What the run consists of.
    pub structure: RunStructure,
    /// What the real-time set-up of the cycle thread got.
    pub rt: RtReport,
    /// Cycles in the measured window.
    pub cycles: u64,
    /// Wake-up latency against the intended instant, ns.
    pub wake_latency: Summary,
    /// Time between consecutive wake-ups, ns.
    pub period: Summary,
    /// |period − cycle time|, ns (derived from the period histogram: resolution 0.1 % of
    /// the period).
    pub period_error: Summary,
    /// Frame round trip (exchange start → reply processed), ns; `None` for the sleep loop.
    pub exchange: Option<Summary>,
    /// Time awake per cycle (wake-up → ready to sleep), ns.
    pub busy: Summary,
    /// Cycles whose wake-up came more than one cycle late.
    pub late: u64,
    /// Cycles whose exchange did not complete within the reply budget (0.8 cycle after the
    /// wake-up) or failed; `None` for the sleep loop.
    pub missed: Option<u64>,
    /// CPU time per cycle.
    pub cpu: CpuReport,
    /// Per drive, what the emulated slave saw; empty when the far end is not the harness's.
    pub drives: Vec<DriveTiming>,
    /// The wake-up latency histogram in log-spaced bins (for plots).
    pub wake_latency_histogram: Vec<Bucket>,
    /// Where ecdrive's cycle thread spends a cycle, by part; `None` for the other runs.
    pub parts: Option<CycleBreakdown>,
    /// Remarks (e.g. figures not available and why).
    pub notes: Vec<String>,
}

/// ecdrive's cycle thread per cycle by part, ns, averaged over the measured cycles (wall time
/// on the real-time cycle thread, see `ecdrive_ethercat::cycle::CycleParts`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CycleBreakdown {
    /// Reading the frame's reply: the link's receive, ethercrab's PDU handling and process
    /// image, the working counter and AL-state checks.
    pub receive_ns: f64,
    /// Of `receive_ns`: the link's receive call.
    pub receive_link_ns: f64,
    /// The CiA 402 engine and motion runtime of every axis, inputs to outputs.
    pub engine_ns: f64,
    /// Supervision: commands, OP, fault spreading, stop timeouts, devices leaving OP.
    pub supervision_ns: f64,
    /// Telemetry published (and the recording, if any).
    pub telemetry_ns: f64,
    /// The next frame: ethercrab builds it, the link sends it.
    pub send_ns: f64,
    /// Of `send_ns`: the link's send call.
    pub send_link_ns: f64,
    /// The cycle thread's CPU time per cycle minus the parts above: the sleep and the
    /// wake-up, in the kernel (`None` without the thread's CPU figure).
    pub sleep_and_wake_ns: Option<f64>,
}

impl CycleBreakdown {
    /// The breakdown of `parts`, the rest taken from the cycle thread's CPU time per cycle.
    pub fn new(per_cycle: [f64; 7], cycle_thread_ns: Option<f64>) -> Self {
        let [
            receive,
            receive_link,
            engine,
            supervision,
            telemetry,
            send,
            send_link,
        ] = per_cycle;
        let awake = receive + engine + supervision + telemetry + send;
        Self {
            receive_ns: receive,
            receive_link_ns: receive_link,
            engine_ns: engine,
            supervision_ns: supervision,
            telemetry_ns: telemetry,
            send_ns: send,
            send_link_ns: send_link,
            sleep_and_wake_ns: cycle_thread_ns.map(|c| (c - awake).max(0.0)),
        }
    }

    /// The figures, named as in the summary across repetitions.
    pub fn figures(&self) -> [(&'static str, Option<f64>); 8] {
        [
            ("part_receive_ns", Some(self.receive_ns)),
            ("part_receive_link_ns", Some(self.receive_link_ns)),
            ("part_engine_ns", Some(self.engine_ns)),
            ("part_supervision_ns", Some(self.supervision_ns)),
            ("part_telemetry_ns", Some(self.telemetry_ns)),
            ("part_send_ns", Some(self.send_ns)),
            ("part_send_link_ns", Some(self.send_link_ns)),
            ("part_sleep_and_wake_ns", self.sleep_and_wake_ns),
        ]
    }
}

/// Histograms a run records; turned into a [`RunReport`] by [`RunHistograms::report`].
#[derive(Debug, Clone, Default)]
pub struct RunHistograms {
    /// Wake-up latency.
    pub wake_latency: LatencyHistogram,
    /// Period.
    pub period: LatencyHistogram,
    /// Exchange (none for the sleep loop).
    pub exchange: Option<LatencyHistogram>,
    /// Busy time.
    pub busy: LatencyHistogram,
}

/// |period − cycle| from a period histogram. Derived rather than recorded, so that every run
/// (ecdrive's cycle keeps a period histogram only) gets it the same way; its resolution is the
/// period histogram's, 0.1 % of the period (1 µs at 1 ms).
pub fn period_error(period: &Histogram<u64>, cycle_ns: u64) -> Summary {
    let mut e = LatencyHistogram::new();
    for v in period.iter_recorded() {
        let x = period
            .median_equivalent(v.value_iterated_to())
            .abs_diff(cycle_ns);
        for _ in 0..v.count_at_value() {
            e.record(x);
        }
    }
    e.summary()
}

impl RunHistograms {
    /// Empty histograms (allocated here, recording never allocates).
    pub fn new(with_exchange: bool) -> Self {
        Self {
            wake_latency: LatencyHistogram::new(),
            period: LatencyHistogram::new(),
            exchange: with_exchange.then(LatencyHistogram::new),
            busy: LatencyHistogram::new(),
        }
    }

    /// The report of a run with these histograms at `cycle_ns`.
    #[allow(clippy::too_many_arguments)]
    pub fn report(
        &self,
        name: &'static str,
        cycle_ns: u64,
        rt: RtReport,
        late: u64,
        missed: Option<u64>,
        cpu: CpuReport,
        drives: Vec<DriveTiming>,
        notes: Vec<String>,
    ) -> RunReport {
        let master_threads = cpu
            .threads
            .iter()
            .filter(|t| t.role == super::cpu::ThreadRole::Master && t.cpu_ns > 0.0)
            .map(|t| t.name.clone())
            .collect();
        RunReport {
            name,
            structure: RunStructure {
                master_threads,
                ..RunStructure::default()
            },
            rt,
            cycles: self.wake_latency.len(),
            wake_latency: self.wake_latency.summary(),
            period: self.period.summary(),
            period_error: period_error(self.period.histogram(), cycle_ns),
            exchange: self.exchange.as_ref().map(LatencyHistogram::summary),
            busy: self.busy.summary(),
            late,
            missed,
            cpu,
            drives,
            wake_latency_histogram: buckets(self.wake_latency.histogram()),
            parts: None,
            notes,
        }
    }
}

/// Ratios of two summaries (`None` where the denominator is 0).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SummaryRatio {
    /// Median.
    pub p50: Option<f64>,
    /// 90th percentile.
    pub p90: Option<f64>,
    /// 99th percentile.
    pub p99: Option<f64>,
    /// 99.9th percentile.
    pub p999: Option<f64>,
    /// Maximum.
    pub max: Option<f64>,
}

fn ratio(a: f64, b: f64) -> Option<f64> {
    (b > 0.0 && a.is_finite() && b.is_finite()).then(|| a / b)
}

impl SummaryRatio {
    /// `a / b` per percentile.
    pub fn of(a: &Summary, b: &Summary) -> Self {
        let r = |x: u64, y: u64| ratio(x as f64, y as f64);
        Self {
            p50: r(a.p50, b.p50),
            p90: r(a.p90, b.p90),
            p99: r(a.p99, b.p99),
            p999: r(a.p999, b.p999),
            max: r(a.max, b.max),
        }
    }
}

/// Ratios of one drive's slave-side figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DriveRatio {
    /// Position.
    pub position: u16,
    /// DC system-time difference (`None` for the reference clock).
    pub dc_difference: Option<SummaryRatio>,
    /// Frame arrival after SYNC0.
    pub arrival_after_sync0: Option<SummaryRatio>,
}

/// Every ecdrive figure as a ratio to one baseline.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ratios {
    /// Wake-up latency.
    pub wake_latency: SummaryRatio,
    /// Period error.
    pub period_error: SummaryRatio,
    /// Frame round trip (`None` against the sleep loop, which has none).
    pub exchange: Option<SummaryRatio>,
    /// Busy time.
    pub busy: SummaryRatio,
    /// Late cycles (`None` when the baseline had none).
    pub late: Option<f64>,
    /// Missed exchanges (`None` against the sleep loop or when the baseline had none).
    pub missed: Option<f64>,
    /// CPU per cycle of the master (cycle thread + TX/RX thread).
    pub cpu_master: Option<f64>,
    /// CPU per cycle of the cycle thread alone.
    pub cpu_cycle_thread: Option<f64>,
    /// CPU per cycle of the whole process.
    pub cpu_process: Option<f64>,
    /// Per drive (only against the plain ethercrab loop, with the harness's own far end).
    pub drives: Vec<DriveRatio>,
}

impl Ratios {
    /// `ecdrive / base` for every figure.
    pub fn of(ecdrive: &RunReport, base: &RunReport) -> Self {
        let opt = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => ratio(a, b),
            _ => None,
        };
        let drives = ecdrive
            .drives
            .iter()
            .filter_map(|d| {
                base.drives
                    .iter()
                    .find(|b| b.position == d.position)
                    .map(|b| {
                        let both = |x: &Option<Summary>, y: &Option<Summary>| match (x, y) {
                            (Some(x), Some(y)) => Some(SummaryRatio::of(x, y)),
                            _ => None,
                        };
                        DriveRatio {
                            position: d.position,
                            dc_difference: both(&d.dc_difference, &b.dc_difference),
                            arrival_after_sync0: both(
                                &d.arrival_after_sync0,
                                &b.arrival_after_sync0,
                            ),
                        }
                    })
            })
            .collect();
        Self {
            wake_latency: SummaryRatio::of(&ecdrive.wake_latency, &base.wake_latency),
            period_error: SummaryRatio::of(&ecdrive.period_error, &base.period_error),
            exchange: match (&ecdrive.exchange, &base.exchange) {
                (Some(a), Some(b)) => Some(SummaryRatio::of(a, b)),
                _ => None,
            },
            busy: SummaryRatio::of(&ecdrive.busy, &base.busy),
            late: ratio(ecdrive.late as f64, base.late as f64),
            missed: match (ecdrive.missed, base.missed) {
                (Some(a), Some(b)) => ratio(a as f64, b as f64),
                _ => None,
            },
            cpu_master: opt(ecdrive.cpu.master_ns, base.cpu.master_ns),
            cpu_cycle_thread: opt(ecdrive.cpu.cycle_thread_ns, base.cpu.cycle_thread_ns),
            cpu_process: opt(ecdrive.cpu.process_ns, base.cpu.process_ns),
            drives,
        }
    }
}

/// The ratios of ecdrive to the baselines.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AllRatios {
    /// ecdrive / bare sleep loop.
    pub ecdrive_to_sleep: Ratios,
    /// ecdrive / plain ethercrab loop.
    pub ecdrive_to_ethercrab: Ratios,
    /// ecdrive / SOEM loop (`None` when SOEM did not run).
    pub ecdrive_to_soem: Option<Ratios>,
}

/// One repetition: every run once, in the order sleep, ethercrab, SOEM, ecdrive.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repetition {
    /// 1-based.
    pub index: usize,
    /// The bare sleep loop.
    pub sleep: RunReport,
    /// The plain ethercrab `tx_rx_dc` loop.
    pub ethercrab: RunReport,
    /// The SOEM loop (`None`: see [`JitterReport::soem_absent`]).
    pub soem: Option<RunReport>,
    /// ecdrive's cycle.
    pub ecdrive: RunReport,
    /// ecdrive's figures as ratios to the baselines of this repetition.
    pub ratios: AllRatios,
}

impl Repetition {
    /// The runs in the order they ran.
    pub fn runs(&self) -> Vec<&RunReport> {
        let mut v = vec![&self.sleep, &self.ethercrab];
        v.extend(self.soem.as_ref());
        v.push(&self.ecdrive);
        v
    }
}

/// One figure across repetitions.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spread {
    /// Median of the repetitions' values (the mean of the middle two for an even count).
    pub median: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// Each repetition's value, in order.
    pub values: Vec<f64>,
}

impl Spread {
    /// The spread of `values` (`None` if there are none).
    pub fn of(values: Vec<f64>) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.clone();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        };
        Some(Self {
            median,
            min: v[0],
            max: v[n - 1],
            values,
        })
    }
}

/// The figures of a run that are summarised across repetitions (ns, or counts), in table
/// order.
pub fn run_figures(r: &RunReport) -> Vec<(&'static str, Option<f64>)> {
    let f = |v: u64| Some(v as f64);
    let ex = r.exchange.as_ref();
    let mut v = vec![
        ("wake_latency_p50", f(r.wake_latency.p50)),
        ("wake_latency_p99", f(r.wake_latency.p99)),
        ("wake_latency_p999", f(r.wake_latency.p999)),
        ("wake_latency_max", f(r.wake_latency.max)),
        ("period_error_p50", f(r.period_error.p50)),
        ("period_error_max", f(r.period_error.max)),
        ("exchange_p50", ex.map(|e| e.p50 as f64)),
        ("exchange_p99", ex.map(|e| e.p99 as f64)),
        ("exchange_max", ex.map(|e| e.max as f64)),
        ("busy_p50", f(r.busy.p50)),
        ("busy_max", f(r.busy.max)),
        ("cpu_master_ns", r.cpu.master_ns),
        ("cpu_process_ns", r.cpu.process_ns),
        ("late", f(r.late)),
        ("missed", r.missed.map(|m| m as f64)),
    ];
    if let Some(p) = &r.parts {
        v.extend(p.figures());
    }
    v
}

/// The ratios summarised across repetitions, in table order.
pub fn ratio_figures(q: &Ratios) -> Vec<(&'static str, Option<f64>)> {
    let ex = q.exchange.as_ref();
    vec![
        ("wake_latency_p50", q.wake_latency.p50),
        ("wake_latency_p99", q.wake_latency.p99),
        ("wake_latency_max", q.wake_latency.max),
        ("period_error_p50", q.period_error.p50),
        ("exchange_p50", ex.and_then(|e| e.p50)),
        ("exchange_p99", ex.and_then(|e| e.p99)),
        ("busy_p50", q.busy.p50),
        ("cpu_master", q.cpu_master),
        ("cpu_process", q.cpu_process),
        ("missed", q.missed),
    ]
}

/// Every figure across the repetitions: per run name (and per ratio name) per figure.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct AcrossRepetitions {
    /// `sleep` | `ethercrab` | `soem` | `ecdrive` → figure → spread.
    pub runs: BTreeMap<String, BTreeMap<String, Spread>>,
    /// `ecdrive_to_sleep` | `ecdrive_to_ethercrab` | `ecdrive_to_soem` → figure → spread of
    /// the per-repetition ratios.
    pub ratios: BTreeMap<String, BTreeMap<String, Spread>>,
}

impl AcrossRepetitions {
    /// Summarise `reps`.
    pub fn of(reps: &[Repetition]) -> Self {
        let mut out = Self::default();
        let collect = |into: &mut BTreeMap<String, BTreeMap<String, Spread>>,
                       name: &str,
                       rows: Vec<Vec<(&'static str, Option<f64>)>>| {
            let Some(first) = rows.first() else {
                return;
            };
            let mut m = BTreeMap::new();
            for (i, (key, _)) in first.iter().enumerate() {
                let vals: Vec<f64> = rows.iter().filter_map(|r| r.get(i)?.1).collect();
                if let Some(sp) = Spread::of(vals) {
                    m.insert((*key).to_string(), sp);
                }
            }
            into.insert(name.to_string(), m);
        };
        for name in ["sleep", "ethercrab", "soem", "ecdrive"] {
            let rows: Vec<_> = reps
                .iter()
                .filter_map(|r| r.runs().into_iter().find(|x| x.name == name))
                .map(run_figures)
                .collect();
            if !rows.is_empty() {
                collect(&mut out.runs, name, rows);
            }
        }
        type Pick = fn(&AllRatios) -> Option<&Ratios>;
        let picks: [(&str, Pick); 3] = [
            ("ecdrive_to_sleep", |a| Some(&a.ecdrive_to_sleep)),
            ("ecdrive_to_ethercrab", |a| Some(&a.ecdrive_to_ethercrab)),
            ("ecdrive_to_soem", |a| a.ecdrive_to_soem.as_ref()),
        ];
        for (name, pick) in picks {
            let rows: Vec<_> = reps
                .iter()
                .filter_map(|r| pick(&r.ratios))
                .map(ratio_figures)
                .collect();
            if !rows.is_empty() {
                collect(&mut out.ratios, name, rows);
            }
        }
        out
    }
}

/// The background load during the runs.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LoadReport {
    /// `/proc/loadavg` (1, 5, 15 min) before the first run.
    pub loadavg_before: Option<[f64; 3]>,
    /// `/proc/loadavg` after the last run.
    pub loadavg_after: Option<[f64; 3]>,
    /// The `--stress` load, if any: what it does.
    pub stress: Option<String>,
    /// CPUs the stress threads were pinned to.
    pub stress_cpus: Vec<usize>,
}

/// The load averages from `/proc/loadavg`.
pub fn loadavg() -> Option<[f64; 3]> {
    let s = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = s.split_whitespace().map(|v| v.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// The settings a measurement ran with.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SettingsReport {
    /// Cycle time, ns.
    pub cycle_ns: u64,
    /// Cycles measured per run.
    pub cycles: u64,
    /// `in-process`, `veth` or `interface`.
    pub transport: String,
    /// The interface the masters used (veth host end or the given interface).
    pub interface: Option<String>,
    /// SCHED_FIFO priority requested.
    pub priority: Option<u8>,
    /// CPU requested.
    pub cpu: Option<usize>,
    /// Whether memory locking was requested.
    pub lock_memory: bool,
    /// The emulated drives, in line order.
    pub drives: Vec<String>,
    /// The drive profile the master used for each.
    pub profiles: Vec<String>,
    /// What ecdrive's axes did during the window.
    pub ecdrive_axes: String,
    /// Whether syscalls were counted (which costs a little on every syscall).
    pub count_syscalls: bool,
    /// When every master sends its frame after SYNC0, ns.
    pub sync0_shift_ns: u64,
    /// Repetitions (each runs sleep, ethercrab, SOEM, ecdrive once, in that order).
    pub repeat: usize,
    /// The SOEM loop's program, if one was found.
    pub soem_program: Option<String>,
}

/// The whole measurement. See [the module documentation](super) for the JSON layout.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JitterReport {
    /// [`SCHEMA`].
    pub schema: &'static str,
    /// ecdrive's version.
    pub version: &'static str,
    /// The commit the binary was built from (`ecdrive version`).
    pub commit: &'static str,
    /// Host conditions.
    pub host: HostInfo,
    /// Settings.
    pub settings: SettingsReport,
    /// The load on the machine.
    pub load: LoadReport,
    /// Whether every run got the real-time priority requested (`false` also when none was
    /// requested).
    pub priority_granted: bool,
    /// Warnings (priority not granted, memory not locked, …), each once.
    pub warnings: Vec<String>,
    /// Why there is no SOEM run (`None` when SOEM ran).
    pub soem_absent: Option<String>,
    /// Every repetition.
    pub repetitions: Vec<Repetition>,
    /// Every figure and ratio across the repetitions.
    pub summary: AcrossRepetitions,
}

fn us(ns: u64) -> String {
    format!("{:.1}", ns as f64 / 1000.0)
}

fn opt_us(v: Option<f64>) -> String {
    v.map_or("-".into(), |ns| format!("{:.2}", ns / 1000.0))
}

fn x(v: Option<f64>) -> String {
    v.map_or("-".into(), |r| format!("{r:.2}"))
}

fn across(s: Option<&Spread>, f: impl Fn(f64) -> String) -> String {
    s.map_or("-".into(), |s| {
        if s.values.len() == 1 {
            f(s.median)
        } else {
            format!("{} [{}–{}]", f(s.median), f(s.min), f(s.max))
        }
    })
}

impl JitterReport {
    /// A plain-text report for a terminal: the settings, each repetition's table, the figures
    /// across repetitions, the first repetition's CPU threads and drive figures, notes.
    pub fn text(&self) -> String {
        let mut s = String::new();
        self.header(&mut s);
        for rep in &self.repetitions {
            let _ = writeln!(s);
            if self.repetitions.len() > 1 {
                let _ = writeln!(s, "repetition {} of {}", rep.index, self.repetitions.len());
            }
            rep_table(&mut s, rep);
        }
        if self.repetitions.len() > 1 {
            let _ = writeln!(s);
            self.across_table(&mut s);
        }
        if let Some(rep) = self.repetitions.first() {
            let _ = writeln!(s);
            threads_table(&mut s, rep);
            drives_table(&mut s, rep);
        }
        if let Some(why) = &self.soem_absent {
            let _ = writeln!(s);
            let _ = writeln!(s, "soem: not run: {why}");
        }
        let mut notes: Vec<String> = Vec::new();
        for rep in &self.repetitions {
            for r in rep.runs() {
                for n in &r.notes {
                    let n = format!("{}: {n}", r.name);
                    if !notes.contains(&n) {
                        notes.push(n);
                    }
                }
            }
        }
        if !notes.is_empty() {
            let _ = writeln!(s);
            for n in notes {
                let _ = writeln!(s, "note: {n}");
            }
        }
        s
    }

    fn header(&self, s: &mut String) {
        let st = &self.settings;
        let h = &self.host;
        let _ = writeln!(s, "ecdrive {} (commit {})", self.version, self.commit);
        let _ = writeln!(
            s,
            "cycle {} µs, {} cycles per run, {} repetition(s), {}{}, drives: {}",
            st.cycle_ns / 1000,
            st.cycles,
            st.repeat,
            st.transport,
            st.interface
                .as_deref()
                .map_or(String::new(), |i| format!(" ({i})")),
            st.drives.join(", ")
        );
        let _ = writeln!(
            s,
            "host: {} | PREEMPT_RT {} | {} ({} CPUs) | governor {} | isolated CPUs {} | \
             sched_rt_runtime_us {}",
            h.kernel,
            if h.preempt_rt { "yes" } else { "no" },
            h.cpu_model,
            h.cpus,
            h.governor.as_deref().unwrap_or("n/a"),
            if h.isolated_cpus.is_empty() {
                "none"
            } else {
                &h.isolated_cpus
            },
            h.sched_rt_runtime_us
                .map_or("n/a".into(), |v| v.to_string())
        );
        let la = |l: Option<[f64; 3]>| {
            l.map_or("n/a".into(), |l| {
                format!("{:.2} {:.2} {:.2}", l[0], l[1], l[2])
            })
        };
        let _ = writeln!(
            s,
            "load: {}; load average before {}, after {}",
            self.load.stress.as_deref().unwrap_or("no --stress"),
            la(self.load.loadavg_before),
            la(self.load.loadavg_after)
        );
        let _ = writeln!(
            s,
            "priority: {} ({}), CPU {}, memory lock {}",
            st.priority
                .map_or("none requested".into(), |p| format!("SCHED_FIFO {p}")),
            if self.priority_granted {
                "granted"
            } else {
                "NOT granted"
            },
            st.cpu.map_or("any".into(), |c| c.to_string()),
            if st.lock_memory { "requested" } else { "off" }
        );
    }

    fn across_table(&self, s: &mut String) {
        let n = self.repetitions.len();
        let _ = writeln!(
            s,
            "across {n} repetitions: median [min–max] of each repetition's figure (µs)"
        );
        let _ = writeln!(
            s,
            "{:<10} {:>22} {:>22} {:>22} {:>22} {:>22} {:>16}",
            "",
            "wake-up p50",
            "wake-up p99",
            "wake-up max",
            "exchange p50",
            "CPU/cycle (master)",
            "missed"
        );
        let u = |v: f64| format!("{:.1}", v / 1000.0);
        let c = |v: f64| format!("{v:.0}");
        for (name, f) in &self.summary.runs {
            let g = |k: &str| f.get(k);
            let _ = writeln!(
                s,
                "{:<10} {:>22} {:>22} {:>22} {:>22} {:>22} {:>16}",
                name,
                across(g("wake_latency_p50"), u),
                across(g("wake_latency_p99"), u),
                across(g("wake_latency_max"), u),
                across(g("exchange_p50"), u),
                across(g("cpu_master_ns"), u),
                across(g("missed"), c),
            );
        }
        let r = |v: f64| format!("{v:.2}");
        for (name, f) in &self.summary.ratios {
            let g = |k: &str| f.get(k);
            let _ = writeln!(
                s,
                "{:<10} {:>22} {:>22} {:>22} {:>22} {:>22}",
                name.replace("ecdrive_to_", "÷ "),
                across(g("wake_latency_p50"), r),
                across(g("wake_latency_p99"), r),
                across(g("wake_latency_max"), r),
                across(g("exchange_p50"), r),
                across(g("cpu_master"), r),
            );
        }
    }
}

fn rep_table(s: &mut String, rep: &Repetition) {
    let _ = writeln!(
        s,
        "{:<10} {:>33} {:>20} {:>20} {:>20} {:>14} {:>6} {:>6}",
        "all µs",
        "wake-up latency p50/p99/p99.9/max",
        "period err p50/max",
        "exchange p50/max",
        "busy p50/max",
        "CPU/cycle",
        "late",
        "missed"
    );
    for r in rep.runs() {
        let w = &r.wake_latency;
        let _ = writeln!(
            s,
            "{:<10} {:>33} {:>20} {:>20} {:>20} {:>14} {:>6} {:>6}",
            r.name,
            format!(
                "{} / {} / {} / {}",
                us(w.p50),
                us(w.p99),
                us(w.p999),
                us(w.max)
            ),
            format!("{} / {}", us(r.period_error.p50), us(r.period_error.max)),
            r.exchange
                .as_ref()
                .map_or("-".into(), |e| format!("{} / {}", us(e.p50), us(e.max))),
            format!("{} / {}", us(r.busy.p50), us(r.busy.max)),
            opt_us(r.cpu.master_ns),
            r.late,
            r.missed.map_or("-".into(), |m| m.to_string()),
        );
    }
    let mut ratios = vec![
        ("÷ sleep", &rep.ratios.ecdrive_to_sleep),
        ("÷ ethercrab", &rep.ratios.ecdrive_to_ethercrab),
    ];
    if let Some(q) = &rep.ratios.ecdrive_to_soem {
        ratios.push(("÷ soem", q));
    }
    for (name, q) in ratios {
        let w = &q.wake_latency;
        let _ = writeln!(
            s,
            "{:<10} {:>33} {:>20} {:>20} {:>20} {:>14}",
            name,
            format!("{} / {} / {} / {}", x(w.p50), x(w.p99), x(w.p999), x(w.max)),
            format!("{} / {}", x(q.period_error.p50), x(q.period_error.max)),
            q.exchange
                .as_ref()
                .map_or("-".into(), |e| format!("{} / {}", x(e.p50), x(e.max))),
            format!("{} / {}", x(q.busy.p50), x(q.busy.max)),
            x(q.cpu_master),
        );
    }
}

fn threads_table(s: &mut String, rep: &Repetition) {
    let _ = writeln!(
        s,
        "CPU per cycle, repetition {} (µs; wake-ups = voluntary context switches per cycle):",
        rep.index
    );
    for r in rep.runs() {
        let c = &r.cpu;
        let threads: Vec<String> = c
            .threads
            .iter()
            .filter(|t| t.cpu_ns > 0.0 || t.voluntary > 0.0)
            .map(|t| {
                format!(
                    "{} [{}] {:.2} µs, {:.2} wake-ups",
                    t.name,
                    t.role.name(),
                    t.cpu_ns / 1000.0,
                    t.voluntary
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "  {:<10} master {} | process {} | syscalls {} | {}",
            r.name,
            opt_us(c.master_ns),
            opt_us(c.process_ns),
            c.syscalls.map_or("-".into(), |v| format!("{v:.2}")),
            if threads.is_empty() {
                "no per-thread figures".to_string()
            } else {
                threads.join("; ")
            }
        );
        let st = &r.structure;
        if !st.link.is_empty() {
            let _ = writeln!(
                s,
                "  {:<10} link: {}; mailbox polling {}; slaves: {}",
                "",
                st.link,
                st.mailbox_poll_ms
                    .map_or("off".into(), |m| format!("every {m} ms")),
                st.slaves
            );
        }
        if let Some(p) = &r.parts {
            let _ = writeln!(
                s,
                "  {:<10} cycle thread by part: receive {:.2} (link {:.2}), engine {:.2}, \
                 supervision {:.2}, telemetry {:.2}, send {:.2} (link {:.2}), sleep and \
                 wake-up {}",
                "",
                p.receive_ns / 1000.0,
                p.receive_link_ns / 1000.0,
                p.engine_ns / 1000.0,
                p.supervision_ns / 1000.0,
                p.telemetry_ns / 1000.0,
                p.send_ns / 1000.0,
                p.send_link_ns / 1000.0,
                p.sleep_and_wake_ns
                    .map_or("-".into(), |v| format!("{:.2}", v / 1000.0)),
            );
        }
    }
}

fn drives_table(s: &mut String, rep: &Repetition) {
    if rep.runs().iter().all(|r| r.drives.is_empty()) {
        return;
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "at the drives (µs)  {:<10} {:>5} {:>24} {:>26} {:>10}",
        "", "drive", "|DC diff| ns p50/p99/max", "arrival after SYNC0 p50/max", "no outputs"
    );
    for r in rep.runs() {
        for d in &r.drives {
            let _ = writeln!(
                s,
                "                    {:<10} {:>5} {:>24} {:>26} {:>10}",
                r.name,
                d.position,
                d.dc_difference
                    .map_or("-".into(), |v| format!("{} / {} / {}", v.p50, v.p99, v.max)),
                d.arrival_after_sync0.map_or("-".into(), |v| format!(
                    "{} / {}",
                    us(v.p50),
                    us(v.max)
                )),
                format!("{}/{}", d.sync0_without_outputs, d.sync0_pulses),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_cover_every_sample_once() {
        let mut h = LatencyHistogram::new();
        for v in [900u64, 1_000, 1_100, 5_000, 5_000, 1_000_000] {
            h.record(v);
        }
        let b = buckets(h.histogram());
        assert_eq!(b.iter().map(|b| b.count).sum::<u64>(), 6);
        for w in b.windows(2) {
            assert!(w[0].hi_ns <= w[1].lo_ns, "{b:?}");
        }
        for bin in &b {
            assert!(bin.lo_ns < bin.hi_ns);
        }
    }

    #[test]
    fn period_error_is_the_distance_from_the_cycle() {
        let mut p = LatencyHistogram::new();
        for v in [1_000_000u64, 1_000_000, 1_010_000, 990_000] {
            p.record(v);
        }
        let e = period_error(p.histogram(), 1_000_000);
        assert_eq!(e.count, 4);
        assert!(e.p50 < 1_000, "{e:?}");
        assert!((9_000..=11_000).contains(&e.max), "{e:?}");
    }

    #[test]
    fn ratios_are_none_on_a_zero_denominator() {
        let a = Summary {
            p50: 10,
            max: 20,
            ..Summary::default()
        };
        let b = Summary {
            p50: 5,
            ..Summary::default()
        };
        let r = SummaryRatio::of(&a, &b);
        assert_eq!(r.p50, Some(2.0));
        assert_eq!(r.max, None);
    }

    #[test]
    fn a_spread_has_the_median_and_the_extremes_in_run_order() {
        let sp = Spread::of(vec![3.0, 1.0, 2.0, 10.0]).unwrap();
        assert_eq!((sp.median, sp.min, sp.max), (2.5, 1.0, 10.0));
        assert_eq!(sp.values, [3.0, 1.0, 2.0, 10.0]);
        assert_eq!(Spread::of(vec![4.0]).unwrap().median, 4.0);
        assert!(Spread::of(Vec::new()).is_none());
    }
}
