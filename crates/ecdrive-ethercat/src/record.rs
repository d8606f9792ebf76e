//! Every cycle recorded: the cycle pushes one [`CycleSample`] per axis and cycle with a reply into
//! a lock-free ring ([`RecordTx`]); a thread that is not real-time drains it ([`Recording`]).
//! A full ring never blocks the cycle: the sample is dropped and counted.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// One axis in one cycle. Columns that have no meaning in the cycle's mode are `None` (empty in
/// the CSV): the position demand outside csp, the velocity demand outside csv and pv,
/// the torque demand outside cst and tq, the following error wherever the master does not judge
/// it (anything but csp while energised) — so the CSV's largest |following error| is the run
/// summary's in every mode.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct CycleSample {
    /// The cycle number.
    pub cycle: u64,
    /// When the cycle woke (`CLOCK_MONOTONIC`, ns).
    pub time_ns: u64,
    /// How late the cycle woke, ns.
    pub wake_latency_ns: u32,
    /// How long the exchange of the frame took, ns.
    pub exchange_ns: u32,
    /// The working counter of the reply.
    pub wkc: u16,
    /// The axis (configuration order).
    pub axis: u16,
    /// The mode of operation the master sent (0x6060).
    pub mode_sent: i8,
    /// Position demand, counts (csp).
    pub demand: Option<i64>,
    /// Actual position, counts (unwrapped).
    pub actual: i64,
    /// Velocity demand (0x60FF), the drive's unit (csv, pv).
    pub velocity_demand: Option<i32>,
    /// Actual velocity, the drive's unit (0x606C).
    pub velocity: i32,
    /// Torque demand (0x6071), the drive's unit (cst, tq).
    pub torque_demand: Option<i16>,
    /// Actual torque, the drive's unit (0x6077).
    pub torque: i16,
    /// Following error as the master computes it (demand − actual, matched by SYNC0 pulse),
    /// counts, in the cycles it judges it.
    pub following_error: Option<i64>,
    /// Statusword.
    pub statusword: u16,
    /// Mode of operation display (0x6061).
    pub mode: i8,
    /// Touch probes 1 and 2.
    pub probes: [crate::telemetry::ProbeState; 2],
}

impl CycleSample {
    /// Axis `axis`'s sample of cycle `cycle` (at `time_ns`) from its telemetry; the following
    /// error only when the master `judged` it this cycle. The bus's own columns (wake-up
    /// latency, exchange time, working counter) are 0 for the caller to fill. Every column
    /// with a meaning in the mode sent ([`CycleSample::defined`]).
    pub fn of_axis(
        cycle: u64,
        time_ns: u64,
        axis: u16,
        t: &crate::telemetry::AxisTelemetry,
        judged: bool,
    ) -> Self {
        Self {
            cycle,
            time_ns,
            wake_latency_ns: 0,
            exchange_ns: 0,
            wkc: 0,
            axis,
            mode_sent: t.mode,
            demand: Some(t.position_demand),
            actual: t.position_actual,
            velocity_demand: Some(t.velocity_demand),
            velocity: t.velocity_actual,
            torque_demand: Some(t.torque_demand),
            torque: t.torque_actual,
            following_error: judged.then_some(t.following_error),
            statusword: t.statusword,
            mode: t.mode_display,
            probes: t.probes,
        }
        .defined()
    }

    /// Whether the mode sent is one of `codes`.
    fn sent_in(&self, codes: &[i8]) -> bool {
        codes.contains(&self.mode_sent)
    }

    /// The columns that have a meaning in the mode sent, the others `None` (the cycle fills
    /// every field; this is the one place that decides which are shown).
    pub fn defined(mut self) -> Self {
        // 0x6060 codes: pp 1, pv 3, tq 4, ip 7, csp 8, csv 9, cst 10. In pp 0x607A is a
        // target (relative, with controlword bit 6), not a demand the axis follows.
        if !self.sent_in(&[7, 8]) {
            self.demand = None;
        }
        if !self.sent_in(&[3, 9]) {
            self.velocity_demand = None;
        }
        if !self.sent_in(&[4, 10]) {
            self.torque_demand = None;
        }
        self
    }
}

/// How one axis's samples are written in physical units: where it sits, which drive it is, its
/// user units (if the run has them) and the drive's units of velocity and torque.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleScale {
    /// Position on the segment.
    pub position: u16,
    /// The drive's name (profile name).
    pub drive: String,
    /// The position unit the converted columns are in ("count", "deg", "mm").
    pub unit: String,
    /// Counts per such unit.
    pub counts_per_unit: f64,
    /// One unit of 0x60FF/0x606C, counts per second.
    pub velocity_counts_per_s: f64,
    /// One unit of 0x6071/0x6077, per mille of rated torque.
    pub torque_per_mille: f64,
}

impl SampleScale {
    /// The scale of the drive `drive` at `position` (a segment position, or a CANopen node-ID),
    /// with its units and the run's user units, if any.
    pub fn of(
        position: u16,
        drive: &str,
        user_units: Option<&crate::startup::UserUnits>,
        units: &ecdrive_core::cia402::Units,
    ) -> Self {
        let (unit, counts_per_unit) = match user_units {
            Some(u) if u.counts_per_unit > 0.0 => (u.name.clone(), u.counts_per_unit),
            _ => ("count".to_string(), 1.0),
        };
        Self {
            position,
            drive: drive.replace(',', ";"),
            unit,
            counts_per_unit,
            velocity_counts_per_s: units.velocity_position_per_s(),
            torque_per_mille: units.torque_per_mille,
        }
    }

    /// The scales of a running master's drives, by axis.
    pub fn of_drives(drives: &[crate::DriveSummary]) -> Vec<Self> {
        drives
            .iter()
            .map(|d| {
                Self::of(
                    d.drive.position,
                    &d.drive.name,
                    d.user_units.as_ref(),
                    &d.units,
                )
            })
            .collect()
    }
}

/// The cycle's end of a recording.
pub struct RecordTx {
    tx: rtrb::Producer<CycleSample>,
    dropped: Arc<AtomicU64>,
}

impl RecordTx {
    /// Push a sample; a full ring drops it and counts.
    pub(crate) fn push(&mut self, s: CycleSample) {
        if self.tx.push(s).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// The reader's end of a recording.
pub struct Recording {
    rx: rtrb::Consumer<CycleSample>,
    dropped: Arc<AtomicU64>,
}

impl Recording {
    /// Hand every sample waiting to `f`, oldest first; how many.
    pub fn drain(&mut self, mut f: impl FnMut(&CycleSample)) -> usize {
        let mut n = 0;
        while let Ok(s) = self.rx.pop() {
            f(&s);
            n += 1;
        }
        n
    }
    /// Samples the cycle had to drop because the ring was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
}

/// A recording of `capacity` samples in flight (one per axis and cycle: at 4 kHz with 8 axes,
/// 32 000 a second); the cycle's end goes to [`crate::MasterConfig::record`].
pub fn recording(capacity: usize) -> (RecordTx, Recording) {
    let (tx, rx) = rtrb::RingBuffer::new(capacity.max(1));
    let dropped = Arc::new(AtomicU64::new(0));
    (
        RecordTx {
            tx,
            dropped: dropped.clone(),
        },
        Recording { rx, dropped },
    )
}

/// The CSV header of [`CsvWriter`]: every column with its unit. Raw values first (counts and
/// the drive's units, as on the wire), then the same in physical units: position, demand and
/// following error in `unit` (the run's user unit, else counts), velocities in `unit`/s,
/// torques in % of the rated torque. A column without meaning in the cycle's mode is empty
/// ([`CycleSample`]); `probe1`/`probe2` (in `unit`) and `probe1_counts`/`probe2_counts` hold a
/// touch probe's latched position from the cycle it latched until it is armed again.
pub const CSV_HEADER: &str = "cycle,time_s,axis,position,drive,mode,mode_sent,statusword_hex,\
demand_counts,actual_counts,following_error_counts,velocity_demand_drive_units,\
velocity_drive_units,torque_demand_drive_units,torque_drive_units,unit,demand,actual,\
following_error,velocity_demand_per_s,velocity_per_s,torque_demand_percent,torque_percent,\
probe1,probe2,probe1_counts,probe2_counts,wake_latency_us,exchange_us,wkc";

/// `Some(v)` as the value, `None` as nothing.
struct Cell<T>(Option<T>);

impl<T: std::fmt::Display> std::fmt::Display for Cell<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.0 {
            Some(v) => v.fmt(f),
            None => Ok(()),
        }
    }
}

/// A value in physical units with enough digits for a count ("12.5", "0.000123").
struct Phys(Option<f64>);

impl std::fmt::Display for Phys {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(v) if v.is_finite() => write!(f, "{}", (v * 1e6).round() / 1e6),
            _ => Ok(()),
        }
    }
}

impl CycleSample {
    /// Write this sample as one CSV line ([`CSV_HEADER`]'s columns), `t0_ns` the time of the
    /// recording's first cycle, `scale` the axis's units (`None`: the physical columns empty).
    pub fn write_csv(
        &self,
        out: &mut dyn std::io::Write,
        t0_ns: u64,
        scale: Option<&SampleScale>,
    ) -> std::io::Result<()> {
        use crate::telemetry::ProbeState;
        let pos = |c: Option<i64>| Phys(scale.zip(c).map(|(s, c)| c as f64 / s.counts_per_unit));
        let vel = |v: Option<i32>| {
            Phys(
                scale
                    .zip(v)
                    .map(|(s, v)| f64::from(v) * s.velocity_counts_per_s / s.counts_per_unit),
            )
        };
        let tq = |t: Option<i16>| {
            Phys(
                scale
                    .zip(t)
                    .map(|(s, t)| f64::from(t) * s.torque_per_mille / 10.0),
            )
        };
        let probe = |p: &ProbeState| match p {
            ProbeState::Latched { position, .. } => Some(*position),
            _ => None,
        };
        writeln!(
            out,
            "{},{:.6},{},{},{},{},{},{:04X},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.1},{:.1},{}",
            self.cycle,
            self.time_ns.saturating_sub(t0_ns) as f64 / 1e9,
            self.axis,
            Cell(scale.map(|s| s.position)),
            Cell(scale.map(|s| s.drive.as_str())),
            self.mode,
            self.mode_sent,
            self.statusword,
            Cell(self.demand),
            self.actual,
            Cell(self.following_error),
            Cell(self.velocity_demand),
            self.velocity,
            Cell(self.torque_demand),
            self.torque,
            Cell(scale.map(|s| s.unit.as_str())),
            pos(self.demand),
            pos(Some(self.actual)),
            pos(self.following_error),
            vel(self.velocity_demand),
            vel(Some(self.velocity)),
            tq(self.torque_demand),
            tq(Some(self.torque)),
            pos(probe(&self.probes[0])),
            pos(probe(&self.probes[1])),
            Cell(probe(&self.probes[0])),
            Cell(probe(&self.probes[1])),
            f64::from(self.wake_latency_ns) / 1e3,
            f64::from(self.exchange_ns) / 1e3,
            self.wkc
        )
    }
}

/// Writes a [`Recording`] as CSV ([`CSV_HEADER`]) from a thread that is not real-time. The
/// physical columns need the drives' units, known once the master has started
/// ([`CsvWriter::set_drives`]); samples drained before that wait in memory.
pub struct CsvWriter<W: std::io::Write> {
    out: W,
    t0: Option<u64>,
    scales: Option<Vec<SampleScale>>,
    pending: Vec<CycleSample>,
    lines: u64,
}

impl<W: std::io::Write> CsvWriter<W> {
    /// Write the header to `out`.
    pub fn new(mut out: W) -> std::io::Result<Self> {
        writeln!(out, "{CSV_HEADER}")?;
        Ok(Self {
            out,
            t0: None,
            scales: None,
            pending: Vec::new(),
            lines: 0,
        })
    }

    /// The drives' units, by axis ([`SampleScale::of_drives`]); what waited is written.
    pub fn set_drives(&mut self, scales: Vec<SampleScale>) -> std::io::Result<()> {
        self.scales = Some(scales);
        let pending = std::mem::take(&mut self.pending);
        for s in &pending {
            self.line(s)?;
        }
        Ok(())
    }

    fn line(&mut self, s: &CycleSample) -> std::io::Result<()> {
        let t0 = *self.t0.get_or_insert(s.time_ns);
        let scale = self
            .scales
            .as_ref()
            .and_then(|v| v.get(usize::from(s.axis)));
        s.write_csv(&mut self.out, t0, scale)?;
        self.lines += 1;
        Ok(())
    }

    /// Drain every sample waiting in `rec` (written, or held until the drives are known).
    pub fn drain(&mut self, rec: &mut Recording) -> std::io::Result<()> {
        while let Ok(s) = rec.rx.pop() {
            if self.scales.is_some() {
                self.line(&s)?;
            } else {
                self.pending.push(s);
            }
        }
        Ok(())
    }

    /// Write what is held (without physical units if the drives never became known), flush;
    /// the output and the lines written.
    pub fn finish(mut self) -> std::io::Result<(W, u64)> {
        let pending = std::mem::take(&mut self.pending);
        for s in &pending {
            self.line(s)?;
        }
        self.out.flush()?;
        Ok((self.out, self.lines))
    }
}
