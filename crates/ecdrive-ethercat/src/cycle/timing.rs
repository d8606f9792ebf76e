//! The cycle's own timing: the values folded into the histograms in batches, and the
//! stopwatch of each cycle's parts.

use super::settings::Timing;
use crate::rt::{LatencyHistogram, monotonic_ns};

/// The timing values of the last cycles, folded into the [`Timing`] histograms a batch at a
/// time: recording a value into a histogram touches its counts far apart (and, after the
/// sleep, cold), a batch's values sit together: one cycle's four values side by side, in one
/// cache line.
#[derive(Clone, Copy)]
pub(super) struct TimingBatch {
    /// By slot, then wake latency, period, exchange, busy.
    values: [[u64; 4]; TIMING_BATCH],
    n: [usize; 4],
}

const TIMING_BATCH: usize = 64;

impl Default for TimingBatch {
    fn default() -> Self {
        Self {
            values: [[0; 4]; TIMING_BATCH],
            n: [0; 4],
        }
    }
}

impl TimingBatch {
    pub(super) const WAKE: usize = 0;
    pub(super) const PERIOD: usize = 1;
    pub(super) const EXCHANGE: usize = 2;
    pub(super) const BUSY: usize = 3;

    fn histogram(t: &mut Timing, which: usize) -> &mut LatencyHistogram {
        match which {
            Self::WAKE => &mut t.wake_latency,
            Self::PERIOD => &mut t.period,
            Self::EXCHANGE => &mut t.exchange,
            _ => &mut t.busy,
        }
    }

    // Out of line (as `Lap::lap`): one copy of the code for the cycle's several calls, which
    // run cold from memory after each sleep.
    #[inline(never)]
    pub(super) fn record(&mut self, t: &mut Timing, which: usize, ns: u64) {
        let n = self.n[which];
        self.values[n][which] = ns;
        self.n[which] = n + 1;
        if n + 1 == TIMING_BATCH {
            self.flush(t, which);
        }
    }

    fn flush(&mut self, t: &mut Timing, which: usize) {
        let h = Self::histogram(t, which);
        for v in &self.values[..self.n[which]] {
            h.record(v[which]);
        }
        self.n[which] = 0;
    }

    pub(super) fn flush_all(&mut self, t: &mut Timing) {
        for which in 0..4 {
            self.flush(t, which);
        }
    }
}

/// The cycle's stopwatch: the time since the last lap, and the pump's counters when the cycle
/// woke.
pub(super) struct Lap {
    last: u64,
    pub(super) stats: crate::io::PumpStats,
}

impl Lap {
    pub(super) fn new(woke: u64, stats: crate::io::PumpStats) -> Self {
        Self { last: woke, stats }
    }

    #[inline(never)]
    pub(super) fn lap(&mut self) -> u64 {
        let now = monotonic_ns();
        let d = now.saturating_sub(self.last);
        self.last = now;
        d
    }
}
