//! The machine around an emulated motor, one model for both buses: the limit switches, the home
//! switch (proximity dog), the encoder's index pulse (Z phase, once per revolution), the
//! touch-probe inputs, and where each CiA 402 homing method ends on them ([`homing_end`]).
//!
//! Positions are world positions in the drive's position units; the switches are placed in
//! revolutions. Every placement is **\[REC\]**: no manual describes a machine.

/// The switches and inputs around the motor. **\[REC\]** values, not from any manual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct World {
    /// Negative limit switch position, rev (active at and below).
    pub negative_limit_rev: f64,
    /// Positive limit switch position, rev (active at and above).
    pub positive_limit_rev: f64,
    /// Home switch edge, rev (active at and above); `None`: the machine has no home switch, so
    /// every method that looks for one runs into a limit switch and fails.
    pub home_switch_rev: Option<f64>,
    /// Touch-probe input 1 (MR-J4-TM TPR1, BDHDE the input given function 27): active while
    /// the motor is in `[from, to)` rev; `None`: never active.
    pub probe1_rev: Option<(f64, f64)>,
    /// Touch-probe input 2, likewise.
    pub probe2_rev: Option<(f64, f64)>,
}

impl Default for World {
    /// **\[REC\]** limits at ±10 rev, the home switch edge at +2.5 rev, index pulses at whole
    /// revolutions, probe input 1 active from 1.3 to 1.7 rev, probe input 2 from −1.6 to −1.2
    /// rev.
    fn default() -> Self {
        Self {
            negative_limit_rev: -10.0,
            positive_limit_rev: 10.0,
            home_switch_rev: Some(2.5),
            probe1_rev: Some((1.3, 1.7)),
            probe2_rev: Some((-1.6, -1.2)),
        }
    }
}

impl World {
    /// Digital inputs in 0x60FD's layout at world position `pos` (position units, `ppr` per
    /// revolution): bit 0 negative limit, bit 1 positive limit, bit 2 home switch.
    pub fn digital_inputs(&self, pos: f64, ppr: f64) -> u32 {
        let rev = pos / ppr;
        let mut d = 0;
        if rev <= self.negative_limit_rev {
            d |= 1;
        }
        if rev >= self.positive_limit_rev {
            d |= 2;
        }
        if self.home_switch_rev.is_some_and(|h| rev >= h) {
            d |= 4;
        }
        d
    }

    /// Whether touch-probe input `n` (1 or 2) is active at `pos`.
    pub fn probe_input(&self, n: u8, pos: f64, ppr: f64) -> bool {
        let r = if n == 1 {
            self.probe1_rev
        } else {
            self.probe2_rev
        };
        let rev = pos / ppr;
        r.is_some_and(|(from, to)| rev >= from && rev < to)
    }

    /// Where input `n` changes between `from` and `to` (world positions, one cycle's travel),
    /// if it does: the position of the edge and whether it is a rising one. The edge is where
    /// the motor crossed the input's boundary, so a latch taken there is exact whatever the
    /// cycle.
    pub fn probe_edge(&self, n: u8, from: f64, to: f64, ppr: f64) -> Option<(f64, bool)> {
        let r = if n == 1 {
            self.probe1_rev
        } else {
            self.probe2_rev
        }?;
        if from == to {
            return None;
        }
        let (lo, hi) = if from < to { (from, to) } else { (to, from) };
        // The boundaries in position units, in the order the motor meets them.
        let mut edges = [r.0 * ppr, r.1 * ppr];
        if from > to {
            edges.reverse();
        }
        edges.into_iter().find_map(|e| {
            let crossed = if from < to {
                e > lo && e <= hi
            } else {
                e >= lo && e < hi
            };
            crossed.then(|| {
                let rising = self.probe_input(n, e + (to - from).signum() * 1e-9 * ppr, ppr);
                (e, rising)
            })
        })
    }
}

/// Where a homing method ends on a [`World`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HomingEnd {
    /// At this world position (position units): the home.
    Reference(f64),
    /// The search runs into a limit switch at this world position without finding what it
    /// looks for: the drive reports its homing failure there.
    Fails {
        /// Where the search stops.
        at: f64,
    },
    /// The method is not one the model knows, or needs an index pulse the encoder has not.
    NotSupported,
}

/// Where `method` (0x6098) ends from world position `pos` (position units, `ppr` per
/// revolution). Index pulses sit at whole revolutions. The CiA 402 methods: 1/2 a limit switch
/// and the index pulse, 3–14 the home switch and the index pulse (7–14 reversing at a limit
/// switch), 17/18 a limit switch, 19–30 the home switch's edge, 33/34 the next index pulse
/// below/above, 35/37 the current position. A method that looks for a home switch the world
/// has not fails at the limit switch its search runs into.
pub fn homing_end(method: i8, world: &World, pos: f64, ppr: f64, index_pulse: bool) -> HomingEnd {
    let index_above = |x: f64| (x / ppr).floor() * ppr + ppr;
    let index_below = |x: f64| (x / ppr).ceil() * ppr - ppr;
    let needs_index = matches!(method, 1..=14 | 33 | 34);
    if needs_index && !index_pulse {
        return HomingEnd::NotSupported;
    }
    let neg = world.negative_limit_rev * ppr;
    let pos_limit = world.positive_limit_rev * ppr;
    let home = world.home_switch_rev.map(|h| h * ppr);
    // The methods on the home switch: where the search fails without one (the first limit in
    // the search direction; 7–14 and 23–30 reverse there and fail at the other).
    let fails_at = |m: i8| match m {
        3..=6 | 19..=22 => {
            if matches!(m, 3 | 4 | 19 | 20) {
                pos_limit
            } else {
                neg
            }
        }
        7..=10 | 23..=26 => neg,
        _ => pos_limit,
    };
    match method {
        1 => HomingEnd::Reference(index_above(neg)),
        2 => HomingEnd::Reference(index_below(pos_limit)),
        3..=14 | 19..=30 => match home {
            None => HomingEnd::Fails {
                at: fails_at(method),
            },
            Some(h) => HomingEnd::Reference(match method {
                // 3: back from the switch's edge to the first index pulse below it (MR-J4-TM
                // §5.4.9 (4): "move back away from the dog; home = first Z-phase"); 4: the
                // first index pulse after the edge ("dog cradle").
                3 => index_below(h),
                4 | 7..=10 => index_above(h),
                5 | 6 | 11..=14 => index_below(h),
                _ => h,
            }),
        },
        17 => HomingEnd::Reference(neg),
        18 => HomingEnd::Reference(pos_limit),
        33 => HomingEnd::Reference(index_below(pos + 1e-9)),
        34 => HomingEnd::Reference(index_above(pos - 1e-9)),
        35 | 37 => HomingEnd::Reference(pos),
        _ => HomingEnd::NotSupported,
    }
}

/// A drive's two touch probes as CiA 402 describes them (0x60B8 function, 0x60B9 status, the
/// latches 0x60BA–0x60BD), on the machine's probe inputs: one model for the emulated drives of
/// both buses.
///
/// 0x60B8 enables each probe (bit 0/8), chooses one or every edge (bit 1/9), the input or the
/// index pulse (bit 2/10, where the drive offers that), and which edges are sampled (bits 4/5,
/// 12/13); a sampled edge latches the position where the motor crossed the input's boundary and
/// sets its bit in 0x60B9 (1/2, 9/10; 0/8 mirror the enables). Clearing a sample bit clears its
/// stored bit, which re-arms a single-edge probe; so does enabling it again.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TouchProbes {
    /// 0x60B8 as last seen.
    function: u16,
    /// 0x60B9.
    status: u16,
}

/// What one step of [`TouchProbes::step`] latched: positions (reported units) for probe 1
/// rising, probe 1 falling, probe 2 rising, probe 2 falling (0x60BA–0x60BD).
pub type ProbeLatches = [Option<i64>; 4];

impl TouchProbes {
    /// 0x60B9.
    pub fn status(&self) -> u16 {
        self.status
    }

    /// One step's travel from `from` to `to` (world positions, `ppr` per revolution) with
    /// function `f` (0x60B8); `offset` turns a world position into a reported one;
    /// `index_pulse`: the drive offers its encoder's zero point as a trigger (bit 2/10).
    /// Returns the new status (0x60B9) and what was latched.
    pub fn step(
        &mut self,
        f: u16,
        world: &World,
        (from, to): (f64, f64),
        ppr: f64,
        offset: f64,
        index_pulse: bool,
    ) -> (u16, ProbeLatches) {
        let mut latched: ProbeLatches = [None; 4];
        if f == 0 && self.status == 0 {
            self.function = 0;
            return (0, latched);
        }
        let mut st = self.status;
        for (k, (n, base)) in [(1u8, 0u16), (2, 8)].into_iter().enumerate() {
            let bit = |b: u16| f >> (base + b) & 1 != 0;
            if !bit(0) {
                st &= !(0x0007 << base);
                continue;
            }
            let was_enabled = self.function >> base & 1 != 0;
            st |= 1 << base;
            if !was_enabled {
                st &= !(0x0006 << base);
            }
            for (sample, stored) in [(4u16, 1u16), (5, 2)] {
                if !bit(sample) {
                    st &= !(1 << (base + stored));
                }
            }
            let edge = if bit(2) {
                // The encoder's zero point (index pulse, whole revolutions): a rising edge each
                // time the motor passes one.
                index_pulse
                    .then(|| {
                        let (lo, hi) = if from < to { (from, to) } else { (to, from) };
                        let z = (hi / ppr).floor() * ppr;
                        (z > lo && z <= hi).then_some((z, true))
                    })
                    .flatten()
            } else {
                world.probe_edge(n, from, to, ppr)
            };
            let Some((at, rising)) = edge else {
                continue;
            };
            let (sample, stored, slot) = if rising { (4u16, 1u16, 0) } else { (5, 2, 1) };
            let continuous = bit(1);
            if bit(sample) && (continuous || st >> (base + stored) & 1 == 0) {
                if let Some(l) = latched.get_mut(2 * k + slot) {
                    *l = Some((at + offset).round() as i64);
                }
                st |= 1 << (base + stored);
            }
        }
        self.status = st;
        self.function = f;
        (st, latched)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PPR: f64 = 1000.0;

    #[test]
    fn methods_end_where_the_switches_and_index_pulses_are() {
        let w = World::default();
        let end = |m| homing_end(m, &w, 400.0, PPR, true);
        assert_eq!(end(19), HomingEnd::Reference(2500.0));
        assert_eq!(end(4), HomingEnd::Reference(3000.0));
        assert_eq!(end(3), HomingEnd::Reference(2000.0));
        assert_eq!(end(5), HomingEnd::Reference(2000.0));
        assert_eq!(end(33), HomingEnd::Reference(0.0));
        assert_eq!(end(34), HomingEnd::Reference(1000.0));
        assert_eq!(end(35), HomingEnd::Reference(400.0));
        assert_eq!(end(17), HomingEnd::Reference(-10_000.0));
        assert_eq!(end(0), HomingEnd::NotSupported);
        assert_eq!(
            homing_end(33, &w, 400.0, PPR, false),
            HomingEnd::NotSupported
        );
    }

    #[test]
    fn without_a_home_switch_the_search_fails_at_a_limit() {
        let w = World {
            home_switch_rev: None,
            ..World::default()
        };
        assert_eq!(
            homing_end(19, &w, 0.0, PPR, true),
            HomingEnd::Fails { at: 10_000.0 }
        );
        assert_eq!(
            homing_end(21, &w, 0.0, PPR, true),
            HomingEnd::Fails { at: -10_000.0 }
        );
        assert_eq!(
            homing_end(35, &w, 7.0, PPR, true),
            HomingEnd::Reference(7.0)
        );
    }

    #[test]
    fn probe_edges_are_found_where_the_motor_crossed_them() {
        let w = World::default();
        // Input 1 is active from 1300 to 1700.
        assert_eq!(w.probe_edge(1, 1250.0, 1350.0, PPR), Some((1300.0, true)));
        assert_eq!(w.probe_edge(1, 1650.0, 1750.0, PPR), Some((1700.0, false)));
        assert_eq!(w.probe_edge(1, 1750.0, 1650.0, PPR), Some((1700.0, true)));
        assert_eq!(w.probe_edge(1, 1350.0, 1250.0, PPR), Some((1300.0, false)));
        assert_eq!(w.probe_edge(1, 1400.0, 1500.0, PPR), None);
        assert!(w.probe_input(1, 1500.0, PPR));
        assert!(!w.probe_input(2, 1500.0, PPR));
    }
}
