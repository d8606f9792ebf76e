//! When the cycle wakes up next: on the grid of instants the SYNC0 pulses and the shift
//! define, one instant after the one it woke for.
//!
//! ethercrab's `tx_rx_dc` gives, with a reply, the time from the frame's send to the instant
//! after the *next* SYNC0 (SYNC0 + shift), from the reference clock's time in the reply. That
//! is a point of the grid, but which one depends on when the frame went out: with the reply
//! read a cycle later ([`ReplyWait::NextWake`](super::ReplyWait::NextWake)), or a frame sent
//! between a SYNC0 and its shifted instant, it is one point later than the instant after the
//! wake-up. So the point only gives the grid's phase (the drift between the host's clock and
//! the reference clock); the next wake-up is the grid's point nearest one cycle after the
//! instant this one woke for, and when that has already passed (an overrun), the grid's first
//! point after now: missed instants are skipped, never caught up back to back, and the cycle
//! stays on the grid.

/// The next wake-up, ns of the monotonic clock. `target`: the instant this cycle woke for;
/// `grid`: a point of the SYNC0 grid from the reply this cycle read (None: no reply, or no
/// reference clock: one cycle on); `now`: the time the cycle is done.
pub(super) fn next_instant(target: u64, grid: Option<u64>, cycle_ns: u64, now: u64) -> u64 {
    let p = i128::from(cycle_ns.max(1));
    let want = i128::from(target) + p;
    let next = match grid {
        Some(at) => {
            let at = i128::from(at);
            // The grid's point nearest `want`.
            at + (want - at + p / 2).div_euclid(p) * p
        }
        None => want,
    };
    let now = i128::from(now);
    let next = if next > now {
        next
    } else {
        next + ((now - next) / p + 1) * p
    };
    u64::try_from(next).unwrap_or(u64::MAX)
}

#[cfg(test)]
mod tests {
    use super::next_instant;

    const P: u64 = 1_000_000;
    /// The reference clock's time = the host's + this (any offset: only the phase counts).
    const DC_OFFSET: u64 = 7_654_321_987;

    /// ethercrab 0.7.1's `next_cycle_wait` for a frame that passes the reference clock at host
    /// time `t`: to the next SYNC0 (at multiples of `P` in DC time), plus the shift.
    fn next_at(t: u64, shift: u64) -> u64 {
        let dc = t + DC_OFFSET;
        t + (P - dc % P) + shift
    }

    /// The instants k·P + shift in host time: the grid.
    fn on_grid(t: u64, shift: u64) -> bool {
        (t + DC_OFFSET) % P == shift % P
    }

    /// A run of `cycles` cycles reading each reply at the next wake-up (the frame sent at the
    /// end of the cycle, `busy` after the wake-up; the first cycle also sends at once and
    /// reads that reply in the cycle), waking `late(k)` after the instant. The wake-up targets.
    fn run(
        shift: u64,
        busy: u64,
        first: u64,
        late: impl Fn(usize) -> u64,
        cycles: usize,
    ) -> Vec<u64> {
        let mut target = first;
        let mut targets = vec![];
        let mut in_flight: Option<u64> = None;
        for k in 0..cycles {
            targets.push(target);
            let woke = target + late(k);
            let grid = match in_flight.take() {
                Some(sent) => next_at(sent, shift),
                // The first cycle: its frame goes out at the wake-up, its reply read at once.
                None => next_at(woke, shift),
            };
            let done = woke + busy;
            in_flight = Some(done);
            target = next_instant(target, Some(grid), P, done);
        }
        targets
    }

    #[test]
    fn every_shift_settles_on_consecutive_instants_after_the_first_cycle() {
        for shift in [0, P / 10, P / 4, P / 2 - 1, P / 2, 3 * P / 4, 9 * P / 10] {
            for busy in [1_000, 40_000, 200_000] {
                for first in [123_456_789, 123_456_789 + P / 3, 123_456_789 + 2 * P / 3] {
                    let t = run(shift, busy, first, |_| 20_000, 50);
                    for w in t[1..].windows(2) {
                        assert!(on_grid(w[0], shift), "shift {shift} busy {busy}: {t:?}");
                        assert_eq!(w[1] - w[0], P, "shift {shift} busy {busy}: {t:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn an_overrun_skips_the_missed_instants_and_stays_on_the_grid() {
        for shift in [0, P / 10, P / 2, 9 * P / 10] {
            // Cycle 10 wakes 2.3 cycles late: the instants it missed are skipped.
            let t = run(
                shift,
                30_000,
                5 * P + 17,
                |k| if k == 10 { 2_300_000 } else { 10_000 },
                30,
            );
            for w in t[1..].windows(2) {
                assert!(on_grid(w[1], shift), "shift {shift}: {t:?}");
            }
            let steps: Vec<u64> = t[1..].windows(2).map(|w| (w[1] - w[0]) / P).collect();
            assert_eq!(steps.iter().filter(|&&s| s != 1).count(), 1, "{steps:?}");
            assert_eq!(steps[9], 3, "{steps:?}");
        }
    }

    #[test]
    fn without_a_reply_the_cycle_goes_one_cycle_on() {
        assert_eq!(next_instant(10 * P, None, P, 10 * P + 5), 11 * P);
        // Already past: the first instant of the same phase after now.
        assert_eq!(next_instant(10 * P, None, P, 13 * P + 5), 14 * P);
    }
}
