//! Every cycle recorded: the cycle pushes one [`CycleSample`] per axis and cycle with a reply into
//! a lock-free ring ([`RecordTx`]); a thread that is not real-time drains it ([`Recording`]).
//! A full ring never blocks the cycle: the sample is dropped and counted.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// One axis in one cycle.
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
    /// Position demand, counts.
    pub demand: i64,
    /// Actual position, counts (unwrapped).
    pub actual: i64,
    /// Actual velocity, the drive's unit (0x606C).
    pub velocity: i32,
    /// Actual torque, the drive's unit (0x6077).
    pub torque: i16,
    /// Following error as the master computes it (demand − actual, matched by SYNC0 pulse),
    /// counts.
    pub following_error: i64,
    /// Statusword.
    pub statusword: u16,
    /// Mode of operation display (0x6061).
    pub mode: i8,
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
    /// Write every sample waiting to `out` as CSV lines; `t0_ns` is the time of the first
    /// sample ever written (set by the first call). Lines written.
    pub fn drain_csv(
        &mut self,
        out: &mut dyn std::io::Write,
        t0_ns: &mut Option<u64>,
    ) -> std::io::Result<u64> {
        let mut n = 0;
        while let Ok(s) = self.rx.pop() {
            let t0 = *t0_ns.get_or_insert(s.time_ns);
            s.write_csv(out, t0)?;
            n += 1;
        }
        Ok(n)
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

/// The CSV header of [`CycleSample::write_csv`]: every column with its unit.
pub const CSV_HEADER: &str = "cycle,time_s,axis,demand_counts,actual_counts,velocity_drive_units,torque_drive_units,following_error_counts,statusword_hex,mode,wake_latency_us,exchange_us,wkc";

impl CycleSample {
    /// Write this sample as one CSV line ([`CSV_HEADER`]'s columns), `t0_ns` the time of the
    /// recording's first cycle.
    pub fn write_csv(&self, out: &mut dyn std::io::Write, t0_ns: u64) -> std::io::Result<()> {
        writeln!(
            out,
            "{},{:.6},{},{},{},{},{},{},{:04X},{},{:.1},{:.1},{}",
            self.cycle,
            self.time_ns.saturating_sub(t0_ns) as f64 / 1e9,
            self.axis,
            self.demand,
            self.actual,
            self.velocity,
            self.torque,
            self.following_error,
            self.statusword,
            self.mode,
            f64::from(self.wake_latency_ns) / 1e3,
            f64::from(self.exchange_ns) / 1e3,
            self.wkc
        )
    }
}
