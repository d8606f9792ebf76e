//! Opt-in timing statistics of one ESC, for measurements (the jitter harness): what the slave
//! saw of the master's timing while in OP.
//!
//! - **DC system-time difference**: the magnitude of register 0x092C after every
//!   drift-compensation write to 0x0910 (what a master polling 0x092C would read);
//! - **frame arrival after SYNC0**: when a frame completes the output buffer, the time since the
//!   latest SYNC0 pulse (system time, so the master's jitter as the drive sees it);
//! - **SYNC0 pulses without fresh outputs**: pulses in OP that found no new output buffer since
//!   the previous pulse (the frame came late or not at all).
//!
//! Off by default: [`Esc::enable_timing_stats`](super::Esc::enable_timing_stats) allocates the
//! histograms once; recording into them never allocates.

use hdrhistogram::Histogram;

/// Largest value recorded exactly (about 4.3 s); larger values are clamped and counted.
const MAX_NS: u64 = u32::MAX as u64;

/// Timing statistics of one ESC in OP. See the module documentation.
#[derive(Debug, Clone)]
pub struct TimingStats {
    /// |0x092C| in ns after each drift-compensation write in OP.
    pub dc_difference: Histogram<u64>,
    /// Time from the latest SYNC0 pulse to the completion of the output buffer, ns, in OP.
    pub arrival_after_sync0: Histogram<u64>,
    /// SYNC0 pulses delivered in OP.
    pub sync0_pulses: u64,
    /// SYNC0 pulses in OP that found no fresh outputs.
    pub sync0_without_outputs: u64,
    /// Values above the histograms' bound (clamped).
    pub clamped: u64,
}

impl TimingStats {
    /// Empty statistics (two histograms of 1 ns … 4.3 s at 2 significant digits).
    pub fn new() -> Self {
        Self {
            dc_difference: hist(),
            arrival_after_sync0: hist(),
            sync0_pulses: 0,
            sync0_without_outputs: 0,
            clamped: 0,
        }
    }

    pub(super) fn record_dc_difference(&mut self, diff_ns: i64) {
        let v = diff_ns.unsigned_abs();
        record(&mut self.dc_difference, &mut self.clamped, v);
    }

    pub(super) fn record_arrival(&mut self, since_sync0_ns: u64) {
        record(
            &mut self.arrival_after_sync0,
            &mut self.clamped,
            since_sync0_ns,
        );
    }

    /// Forget everything recorded so far.
    pub fn reset(&mut self) {
        self.dc_difference.reset();
        self.arrival_after_sync0.reset();
        self.sync0_pulses = 0;
        self.sync0_without_outputs = 0;
        self.clamped = 0;
    }
}

impl Default for TimingStats {
    fn default() -> Self {
        Self::new()
    }
}

fn hist() -> Histogram<u64> {
    // Constant bounds and precision that `new_with_bounds` always accepts (not runtime data).
    Histogram::new_with_bounds(1, MAX_NS, 2).expect("constant histogram bounds are valid")
}

fn record(h: &mut Histogram<u64>, clamped: &mut u64, v: u64) {
    let v = if v > MAX_NS {
        *clamped += 1;
        MAX_NS
    } else {
        v.max(1)
    };
    h.saturating_record(v);
}
