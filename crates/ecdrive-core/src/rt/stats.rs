//! Latency statistics on HDR histograms, allocation-free while recording.

use hdrhistogram::Histogram;
use serde::Serialize;

/// A histogram of nanosecond values with fixed bounds, so recording never allocates. Values above
/// the bound are clamped to it and counted in [`LatencyHistogram::clamped`].
#[derive(Debug, Clone)]
pub struct LatencyHistogram {
    hist: Histogram<u64>,
    clamped: u64,
}

/// The usual percentiles of a histogram, in nanoseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Summary {
    /// Number of samples.
    pub count: u64,
    /// Smallest sample.
    pub min: u64,
    /// Median.
    pub p50: u64,
    /// 90th percentile.
    pub p90: u64,
    /// 99th percentile.
    pub p99: u64,
    /// 99.9th percentile.
    pub p999: u64,
    /// Largest sample.
    pub max: u64,
    /// Mean.
    pub mean: f64,
}

impl LatencyHistogram {
    /// Largest value recorded exactly: 10 s.
    pub const MAX_NS: u64 = 10_000_000_000;

    /// An empty histogram (1 ns … 10 s, 3 significant digits).
    pub fn new() -> Self {
        // Constant bounds and precision that `new_with_bounds` always accepts.
        let hist = Histogram::new_with_bounds(1, Self::MAX_NS, 3)
            .expect("constant histogram bounds are valid");
        Self { hist, clamped: 0 }
    }

    /// Record one value. Never allocates.
    pub fn record(&mut self, ns: u64) {
        let v = if ns > Self::MAX_NS {
            self.clamped += 1;
            Self::MAX_NS
        } else {
            ns.max(1)
        };
        self.hist.saturating_record(v);
    }

    /// Values that exceeded [`Self::MAX_NS`].
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// Number of recorded values.
    pub fn len(&self) -> u64 {
        self.hist.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.hist.is_empty()
    }

    /// The percentile summary.
    pub fn summary(&self) -> Summary {
        if self.hist.is_empty() {
            return Summary::default();
        }
        Summary {
            count: self.hist.len(),
            min: self.hist.min(),
            p50: self.hist.value_at_quantile(0.50),
            p90: self.hist.value_at_quantile(0.90),
            p99: self.hist.value_at_quantile(0.99),
            p999: self.hist.value_at_quantile(0.999),
            max: self.hist.max(),
            mean: self.hist.mean(),
        }
    }

    /// The underlying histogram (for plotting).
    pub fn histogram(&self) -> &Histogram<u64> {
        &self.hist
    }

    /// Forget every value.
    pub fn reset(&mut self) {
        self.hist.reset();
        self.clamped = 0;
    }
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_known_values() {
        let mut h = LatencyHistogram::new();
        for v in 1..=1000u64 {
            h.record(v * 1000);
        }
        let s = h.summary();
        assert_eq!(s.count, 1000);
        // 3 significant digits: values are exact to 0.1 %.
        assert!((499_000..=501_000).contains(&s.p50), "{s:?}");
        assert!((989_000..=991_000).contains(&s.p99), "{s:?}");
        assert!((999_000..=1_001_000).contains(&s.max), "{s:?}");
    }

    #[test]
    fn huge_values_are_clamped_and_counted() {
        let mut h = LatencyHistogram::new();
        h.record(u64::MAX);
        assert_eq!(h.clamped(), 1);
        assert_eq!(h.len(), 1);
    }
}
