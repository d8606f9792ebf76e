//! The distributed-clock unit: local clock, system time with offset and delay, the drift
//! control loop, and the SYNC0 generator.
//!
//! Model:
//! - **local time** = host clock + configured offset + configured drift (parts per billion of
//!   the host time), i.e. each slave's own oscillator;
//! - **system time** = local time + offset register (0x0920) + trim, where the trim is what the
//!   control loop has corrected so far (a step part and a rate part);
//! - a write to 0x0910 (FRMW/ARMW from the reference clock, or a BWR) is a **control-loop
//!   input**: `e = own system time − (received + delay 0x0928)`; 0x092C shows `e` filtered
//!   (filter depth 0x0934) in sign-magnitude; the loop removes `e` with a proportional step of
//!   at most 1000 ppm of the elapsed time and integrates the rate error in small, bounded
//!   steps (gains in [`crate::rec`]);
//! - a write to 0x0930 or 0x0934 resets the loop (trim, rate and filter);
//! - **SYNC0**: when 0x0981 bits 0 and 1 are set, pulses start at the start time (0x0990) and
//!   repeat every 0x09A0 ns of system time (0 = a single pulse). A start time in the past
//!   starts nothing (64 bits) or waits for the 32-bit wrap, unless the start-time plausibility
//!   check (0x0981 bit 5) asks for a pulse at once; 0x0984 bit 2 says it was past.

use crate::rec::{
    DC_KI_DIV as KI_DIV, DC_KI_MIN_INTERVAL_NS as KI_MIN_INTERVAL_NS, DC_KP_SHIFT as KP_SHIFT,
    DC_MAX_RATE_PPB as MAX_RATE_PPB, DC_MAX_RATE_STEP_PPB as MAX_RATE_STEP_PPB,
    DC_MIN_STEP_NS as MIN_STEP_NS,
};

/// Fixed-point shift for rates: a rate in ppb is kept as `ppb · 2^40 / 10^9`, so applying it is
/// a multiplication and a shift instead of a 128-bit division.
const Q: u32 = 40;

fn ppb_to_q(ppb: i64) -> i64 {
    match ppb.checked_shl(Q).filter(|v| v >> Q == ppb) {
        Some(v) => v / 1_000_000_000,
        None => ((i128::from(ppb) << Q) / 1_000_000_000)
            .clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64,
    }
}

/// `x · q / 2^Q`, rounded to nearest.
fn apply_q(x: u64, q: i64) -> i128 {
    if q == 0 {
        return 0;
    }
    (i128::from(x) * i128::from(q) + (1i128 << (Q - 1))) >> Q
}

/// The DC unit state of one ESC.
#[derive(Debug, Clone)]
pub struct DcUnit {
    /// Local clock offset from the host clock.
    pub offset_ns: i64,
    drift_ppb: i64,
    drift_q: i64,
    trim_ns: i64,
    rate_ppb: i64,
    rate_q: i64,
    anchor_local: u64,
    last_input_local: Option<u64>,
    filtered: i64,
    /// SYNC0 generation.
    pub sync: SyncGen,
}

/// The SYNC0 generator.
#[derive(Debug, Clone, Copy, Default)]
pub struct SyncGen {
    /// Cyclic operation with SYNC0 is running.
    pub active: bool,
    /// System time of the next SYNC0 pulse.
    pub next: u64,
    /// SYNC0 cycle in ns (0: single shot).
    pub cycle: u32,
    /// Pulses delivered since activation.
    pub count: u64,
    /// The start time had passed at activation and nothing starts the pulses before the
    /// 64-bit system time reaches it again: none comes (see `Esc::start_sync`).
    pub waiting: bool,
}

impl DcUnit {
    /// A DC unit with the given local clock offset and drift.
    pub fn new(offset_ns: i64, drift_ppb: i64) -> Self {
        Self {
            offset_ns,
            drift_ppb,
            drift_q: ppb_to_q(drift_ppb),
            trim_ns: 0,
            rate_ppb: 0,
            rate_q: 0,
            anchor_local: 0,
            last_input_local: None,
            filtered: 0,
            sync: SyncGen::default(),
        }
    }

    /// Local clock drift against the host clock in ppb.
    pub fn drift_ppb(&self) -> i64 {
        self.drift_ppb
    }

    /// Change the drift from host time `host_ns` on, keeping the local time continuous there
    /// (the offset absorbs the difference).
    pub fn set_drift(&mut self, host_ns: u64, drift_ppb: i64) {
        let before = i128::from(self.local(host_ns));
        let q = ppb_to_q(drift_ppb);
        let offset = before - i128::from(host_ns) - apply_q(host_ns, q);
        self.offset_ns = offset.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64;
        self.drift_ppb = drift_ppb;
        self.drift_q = q;
    }

    /// Local time at host time `host_ns`.
    pub fn local(&self, host_ns: u64) -> u64 {
        let v = i128::from(host_ns) + i128::from(self.offset_ns) + apply_q(host_ns, self.drift_q);
        v.clamp(0, i128::from(u64::MAX)) as u64
    }

    fn trim_at(&self, local: u64) -> i64 {
        let rate = apply_q(local.saturating_sub(self.anchor_local), self.rate_q);
        (i128::from(self.trim_ns) + rate).clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
    }

    /// System time at host time `host_ns`, given the offset register value.
    pub fn system(&self, host_ns: u64, offset_reg: u64) -> u64 {
        let local = self.local(host_ns);
        local
            .wrapping_add(offset_reg)
            .wrapping_add(self.trim_at(local) as u64)
    }

    /// Reset the control loop (write to 0x0930 or 0x0934).
    pub fn reset_loop(&mut self) {
        self.trim_ns = 0;
        self.rate_ppb = 0;
        self.rate_q = 0;
        self.anchor_local = 0;
        self.last_input_local = None;
        self.filtered = 0;
    }

    /// A control-loop input at host time `host_ns`: `e` = own system time − delay − received
    /// (positive: this clock is ahead). `filter_depth` is 0x0934 bits 0–3. Returns the filtered
    /// difference for 0x092C.
    pub fn loop_input(&mut self, host_ns: u64, e: i64, filter_depth: u8) -> i64 {
        let local = self.local(host_ns);
        // Fold the rate part accumulated so far into the step part, re-anchoring at `local`.
        self.trim_ns = self.trim_at(local);
        self.anchor_local = local;
        let dt = self
            .last_input_local
            .map(|l| local.saturating_sub(l))
            .unwrap_or(0);
        self.last_input_local = Some(local);

        let limit = ((dt / 1000) as i64).max(MIN_STEP_NS);
        let step = (e >> KP_SHIFT).clamp(-limit, limit);
        // A tiny error still gets corrected by at least one nanosecond.
        let step = if step == 0 { e.signum() } else { step };
        self.trim_ns = self.trim_ns.saturating_sub(step);
        if dt >= KI_MIN_INTERVAL_NS && e != 0 {
            let dt = i64::try_from(dt).unwrap_or(i64::MAX);
            let observed_ppb = match e.checked_mul(1_000_000_000) {
                Some(x) => x / dt,
                None => (i128::from(e) * 1_000_000_000 / i128::from(dt))
                    .clamp(i128::from(i64::MIN), i128::from(i64::MAX))
                    as i64,
            };
            let adj = (observed_ppb / KI_DIV).clamp(-MAX_RATE_STEP_PPB, MAX_RATE_STEP_PPB);
            self.rate_ppb = (self.rate_ppb - adj).clamp(-MAX_RATE_PPB, MAX_RATE_PPB);
            self.rate_q = ppb_to_q(self.rate_ppb);
        }
        let depth = u32::from(filter_depth & 0x0F);
        self.filtered = if depth == 0 || self.filtered == 0 {
            e
        } else {
            // Saturating: a master may write any 64-bit value to 0x0910.
            self.filtered
                .saturating_add(e.saturating_sub(self.filtered) >> depth)
        };
        self.filtered
    }

    /// Encode a difference as register 0x092C: bit 31 set when the local copy is greater than
    /// or equal to the received time, bits 0–30 the magnitude (saturated).
    pub fn encode_difference(e: i64) -> u32 {
        let mag = e.unsigned_abs().min(0x7FFF_FFFF) as u32;
        if e >= 0 { mag | 0x8000_0000 } else { mag }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_time_offset_and_drift() {
        let dc = DcUnit::new(1_000, 50_000); // +1 µs, +50 ppm
        assert_eq!(dc.local(0), 1_000);
        assert_eq!(dc.local(1_000_000_000), 1_000_000_000 + 1_000 + 50_000);
    }

    #[test]
    fn loop_converges_on_drift() {
        // A slave running 80 ppm fast against a reference, compared every millisecond.
        let mut dc = DcUnit::new(0, 80_000);
        let reference = DcUnit::new(0, 0);
        let offset = 0u64;
        let mut t = 1_000_000_000u64;
        let mut last = 0i64;
        for _ in 0..3000 {
            t += 1_000_000;
            let own = dc.system(t, offset) as i64;
            let received = reference.system(t, offset) as i64;
            last = dc.loop_input(t, own - received, 0);
        }
        assert!(last.abs() < 20, "residual difference {last} ns");
    }

    #[test]
    fn loop_removes_initial_offset_back_to_back() {
        let mut dc = DcUnit::new(0, 0);
        let mut t = 5_000_000u64;
        // 600 ns behind the reference, 100 comparisons 30 µs apart.
        let base = dc.system(t, 0) as i64 + 600;
        let mut e = 0;
        for i in 0..100u64 {
            t += 30_000;
            let own = dc.system(t, 0) as i64;
            let received = base + (30_000 * (i + 1)) as i64;
            e = dc.loop_input(t, own - received, 0);
        }
        assert!(e.abs() <= 1, "residual {e}");
    }

    #[test]
    fn difference_encoding() {
        assert_eq!(DcUnit::encode_difference(5), 0x8000_0005);
        assert_eq!(DcUnit::encode_difference(0), 0x8000_0000);
        assert_eq!(DcUnit::encode_difference(-5), 5);
        assert_eq!(DcUnit::encode_difference(i64::MIN), 0x7FFF_FFFF);
    }
}

#[cfg(test)]
mod irregular {
    use super::*;

    /// Updates at irregular intervals (back-to-back bursts, 0.05–5 ms, occasional 100 ms
    /// gaps), 150 ppm relative drift: the loop stays stable and the difference ends small.
    #[test]
    fn loop_is_stable_with_irregular_updates() {
        let mut dc = DcUnit::new(0, 150_000);
        let reference = DcUnit::new(0, 0);
        let mut t = 1_000_000_000u64;
        // A simple deterministic sequence of intervals.
        let mut x = 12345u64;
        let mut last = 0i64;
        for i in 0..6000 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let r = (x >> 33) % 1000;
            let dt = if i < 100 {
                20_000 + r * 200
            } else if r < 980 {
                50_000 + r * 5_000
            } else {
                100_000_000
            };
            t += dt;
            let own = dc.system(t, 0) as i64;
            let received = reference.system(t, 0) as i64;
            last = dc.loop_input(t, own - received, 0);
        }
        assert!(last.abs() < 1_000, "residual {last} ns");
    }
}
