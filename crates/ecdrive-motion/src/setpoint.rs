//! Set-point sources for the cyclic modes: point-to-point moves with a trapezoidal or a
//! jerk-limited (double-S) velocity profile, sines, velocity ramps, jogs and torque profiles.
//!
//! Everything is in drive units (position counts, velocity units per second, …) and seconds;
//! the drive profile converts user units. Sampling is allocation-free: a profile is planned once
//! (when a program step starts) and then evaluated per cycle.

use serde::Serialize;

/// One sample of a set-point source.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Sample {
    /// Position.
    pub pos: f64,
    /// Velocity (position units per second).
    pub vel: f64,
    /// Acceleration (position units per second²).
    pub acc: f64,
    /// Torque (torque units; only torque sources set it).
    pub torque: f64,
    /// Whether the source has finished (the sample is its final value).
    pub done: bool,
}

/// A motion shape that cannot be planned (a limit or a value out of range).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A limit is zero, negative or not a number.
    #[error("{name} must be a positive finite number, got {value}")]
    BadLimit {
        /// Which limit.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A position or duration is not finite.
    #[error("{name} must be finite, got {value}")]
    NotFinite {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A duration is negative (or not finite).
    #[error("{name} must be 0 or more (a finite number), got {value}")]
    Negative {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: f64,
    },
}

fn positive(name: &'static str, value: f64) -> Result<f64, ShapeError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ShapeError::BadLimit { name, value })
    }
}

fn finite(name: &'static str, value: f64) -> Result<f64, ShapeError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ShapeError::NotFinite { name, value })
    }
}

/// A piece of a motion profile with constant jerk, starting from a known state.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Segment {
    t0: f64,
    dur: f64,
    p0: f64,
    v0: f64,
    a0: f64,
    jerk: f64,
}

impl Segment {
    fn eval(&self, t: f64) -> (f64, f64, f64) {
        let d = t;
        let j = self.jerk;
        (
            self.p0 + self.v0 * d + self.a0 * d * d / 2.0 + j * d * d * d / 6.0,
            self.v0 + self.a0 * d + j * d * d / 2.0,
            self.a0 + j * d,
        )
    }
}

/// A planned point-to-point move (rest to rest): trapezoidal or double-S.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    start: f64,
    end: f64,
    segs: [Segment; 7],
    n: usize,
    duration: f64,
    peak_vel: f64,
}

impl Move {
    /// A move from `start` to `end` with a trapezoidal velocity profile: constant acceleration
    /// `acc` up to at most `vel`, cruise, constant deceleration. Short moves never reach `vel`
    /// (triangular profile).
    pub fn trapezoid(start: f64, end: f64, vel: f64, acc: f64) -> Result<Self, ShapeError> {
        let (start, end) = (finite("start", start)?, finite("end", end)?);
        let (vmax, amax) = (positive("velocity", vel)?, positive("acceleration", acc)?);
        let h = (end - start).abs();
        let s = if end >= start { 1.0 } else { -1.0 };
        // Time to reach vmax and the distance it takes; triangular if the move is too short.
        let (ta, vpeak) = if h >= vmax * vmax / amax {
            (vmax / amax, vmax)
        } else {
            let v = (h * amax).sqrt();
            (v / amax, v)
        };
        let tv = if vpeak > 0.0 {
            (h - vpeak * ta) / vpeak
        } else {
            0.0
        };
        let plan = [
            (ta, 0.0, s * amax),
            (tv.max(0.0), 0.0, 0.0),
            (ta, 0.0, -s * amax),
        ];
        Ok(Self::build(start, end, &plan, vpeak))
    }

    /// A jerk-limited move from `start` to `end` (double-S, seven phases): jerk `jerk`,
    /// acceleration at most `acc`, velocity at most `vel`. Limits that the distance does not
    /// allow to reach are reduced as needed.
    pub fn double_s(
        start: f64,
        end: f64,
        vel: f64,
        acc: f64,
        jerk: f64,
    ) -> Result<Self, ShapeError> {
        let (start, end) = (finite("start", start)?, finite("end", end)?);
        let vmax = positive("velocity", vel)?;
        let amax = positive("acceleration", acc)?;
        let jmax = positive("jerk", jerk)?;
        let h = (end - start).abs();
        let s = if end >= start { 1.0 } else { -1.0 };

        // Acceleration phase that reaches vmax (rest to rest, symmetric).
        let (mut tj, mut ta) = if vmax * jmax >= amax * amax {
            (amax / jmax, amax / jmax + vmax / amax)
        } else {
            let tj = (vmax / jmax).sqrt();
            (tj, 2.0 * tj)
        };
        let mut tv = h / vmax - ta;
        if tv < 0.0 {
            // vmax is not reached: no cruise phase.
            tv = 0.0;
            if h >= 2.0 * amax * amax * amax / (jmax * jmax) {
                // amax is still reached.
                tj = amax / jmax;
                let delta = amax.powi(4) / (jmax * jmax) + 4.0 * h * amax;
                ta = (amax * amax / jmax + delta.sqrt()) / (2.0 * amax);
            } else {
                // Neither vmax nor amax: triangular acceleration.
                tj = (h / (2.0 * jmax)).cbrt();
                ta = 2.0 * tj;
            }
        }
        let tconst = (ta - 2.0 * tj).max(0.0);
        let j = s * jmax;
        let plan = [
            (tj, j, 0.0),
            (tconst, 0.0, f64::NAN),
            (tj, -j, f64::NAN),
            (tv, 0.0, 0.0),
            (tj, -j, 0.0),
            (tconst, 0.0, f64::NAN),
            (tj, j, f64::NAN),
        ];
        let vpeak = jmax * tj * (ta - tj);
        Ok(Self::build(
            start,
            end,
            &plan,
            if h > 0.0 { vpeak } else { 0.0 },
        ))
    }

    /// Chain segments `(duration, jerk, start acceleration or NaN = continue)`.
    fn build(start: f64, end: f64, plan: &[(f64, f64, f64)], peak_vel: f64) -> Self {
        let mut segs = [Segment::default(); 7];
        let (mut t, mut p, mut v, mut a) = (0.0, start, 0.0, 0.0);
        let mut n = 0;
        for &(dur, jerk, a_start) in plan {
            if dur.is_nan() || dur <= 0.0 {
                continue;
            }
            if !a_start.is_nan() {
                a = a_start;
            }
            let seg = Segment {
                t0: t,
                dur,
                p0: p,
                v0: v,
                a0: a,
                jerk,
            };
            (p, v, a) = seg.eval(dur);
            t += dur;
            if let Some(slot) = segs.get_mut(n) {
                *slot = seg;
                n += 1;
            }
        }
        Self {
            start,
            end,
            segs,
            n,
            duration: t,
            peak_vel,
        }
    }

    /// Total duration in seconds.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Highest speed the move reaches.
    pub fn peak_velocity(&self) -> f64 {
        self.peak_vel
    }

    /// The set-point `t` seconds after the start. Before 0 it is the start; from the end on it is
    /// exactly the end position at rest.
    pub fn sample(&self, t: f64) -> Sample {
        if t >= self.duration || self.n == 0 {
            return Sample {
                pos: self.end,
                done: true,
                ..Sample::default()
            };
        }
        if t <= 0.0 {
            return Sample {
                pos: self.start,
                ..Sample::default()
            };
        }
        let seg = self.segs[..self.n]
            .iter()
            .rev()
            .find(|s| s.t0 <= t)
            .copied()
            .unwrap_or_default();
        let (pos, vel, acc) = seg.eval(t - seg.t0);
        Sample {
            pos,
            vel,
            acc,
            torque: 0.0,
            done: false,
        }
    }
}

/// A sine around a centre: `centre + amplitude · sin(2π f t)` for a number of periods. It starts
/// at the centre, so starting it at the actual position does not jump the position (it does
/// start with velocity `2π f · amplitude`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sine {
    centre: f64,
    amplitude: f64,
    freq: f64,
    duration: f64,
}

impl Sine {
    /// A sine of `periods` periods (fractional allowed).
    pub fn new(
        centre: f64,
        amplitude: f64,
        freq_hz: f64,
        periods: f64,
    ) -> Result<Self, ShapeError> {
        Ok(Self {
            centre: finite("centre", centre)?,
            amplitude: finite("amplitude", amplitude)?,
            freq: positive("frequency", freq_hz)?,
            duration: positive("periods", periods)? / freq_hz,
        })
    }

    /// Duration in seconds.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The set-point at `t` seconds.
    pub fn sample(&self, t: f64) -> Sample {
        let done = t >= self.duration;
        let t = t.clamp(0.0, self.duration);
        let w = 2.0 * std::f64::consts::PI * self.freq;
        Sample {
            pos: self.centre + self.amplitude * (w * t).sin(),
            vel: if done {
                0.0
            } else {
                self.amplitude * w * (w * t).cos()
            },
            acc: if done {
                0.0
            } else {
                -self.amplitude * w * w * (w * t).sin()
            },
            torque: 0.0,
            done,
        }
    }
}

/// A velocity ramp from `from` to `to` at constant acceleration, then held for `hold` seconds;
/// the position integrates from `start_pos`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityRamp {
    start_pos: f64,
    from: f64,
    to: f64,
    ramp: f64,
    hold: f64,
}

impl VelocityRamp {
    /// A ramp with acceleration magnitude `acc`.
    pub fn new(
        start_pos: f64,
        from: f64,
        to: f64,
        acc: f64,
        hold: f64,
    ) -> Result<Self, ShapeError> {
        let acc = positive("acceleration", acc)?;
        let (from, to) = (finite("from", from)?, finite("to", to)?);
        if !(hold.is_finite() && hold >= 0.0) {
            return Err(ShapeError::Negative {
                name: "hold",
                value: hold,
            });
        }
        Ok(Self {
            start_pos: finite("start position", start_pos)?,
            from,
            to,
            ramp: (to - from).abs() / acc,
            hold,
        })
    }

    /// Duration in seconds (ramp + hold).
    pub fn duration(&self) -> f64 {
        self.ramp + self.hold
    }

    /// The set-point at `t` seconds.
    pub fn sample(&self, t: f64) -> Sample {
        let t = t.max(0.0);
        let done = t >= self.duration();
        let t = t.min(self.duration());
        let a = if self.ramp > 0.0 {
            (self.to - self.from) / self.ramp
        } else {
            0.0
        };
        let (pos, vel, acc) = if t < self.ramp {
            (
                self.start_pos + self.from * t + a * t * t / 2.0,
                self.from + a * t,
                a,
            )
        } else {
            let p_ramp = self.start_pos + (self.from + self.to) / 2.0 * self.ramp;
            (p_ramp + self.to * (t - self.ramp), self.to, 0.0)
        };
        Sample {
            pos,
            vel,
            acc,
            torque: 0.0,
            done,
        }
    }
}

/// A jog: the velocity follows a target, changing at most `acc` per second; the position
/// integrates. Stateful, advanced once per cycle; the target can change at any time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jog {
    pos: f64,
    vel: f64,
    target: f64,
    acc: f64,
}

impl Jog {
    /// A jog starting at rest at `pos`.
    pub fn new(pos: f64, acc: f64) -> Result<Self, ShapeError> {
        Ok(Self {
            pos: finite("position", pos)?,
            vel: 0.0,
            target: 0.0,
            acc: positive("acceleration", acc)?,
        })
    }

    /// Set the target velocity (0 to stop).
    pub fn set_target(&mut self, vel: f64) {
        if vel.is_finite() {
            self.target = vel;
        }
    }

    /// Advance by `dt` seconds and return the new set-point. `done` is true when stopped with a
    /// zero target.
    pub fn advance(&mut self, dt: f64) -> Sample {
        let dt = if dt.is_finite() { dt.max(0.0) } else { 0.0 };
        let dv = (self.target - self.vel).clamp(-self.acc * dt, self.acc * dt);
        let v0 = self.vel;
        self.vel += dv;
        self.pos += (v0 + self.vel) / 2.0 * dt;
        Sample {
            pos: self.pos,
            vel: self.vel,
            acc: if dt > 0.0 { dv / dt } else { 0.0 },
            torque: 0.0,
            done: self.target == 0.0 && self.vel == 0.0,
        }
    }
}

/// A torque profile: ramp from `from` to `level` at `slope` per second, hold for `hold` seconds,
/// ramp back to zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorqueStep {
    from: f64,
    level: f64,
    slope: f64,
    hold: f64,
}

impl TorqueStep {
    /// A torque step. `slope` = `f64::INFINITY` gives a true step.
    pub fn new(from: f64, level: f64, slope: f64, hold: f64) -> Result<Self, ShapeError> {
        let slope = if slope == f64::INFINITY {
            slope
        } else {
            positive("torque slope", slope)?
        };
        if !(hold.is_finite() && hold >= 0.0) {
            return Err(ShapeError::Negative {
                name: "hold",
                value: hold,
            });
        }
        Ok(Self {
            from: finite("from", from)?,
            level: finite("level", level)?,
            slope,
            hold,
        })
    }

    fn t_up(&self) -> f64 {
        (self.level - self.from).abs() / self.slope
    }

    fn t_down(&self) -> f64 {
        self.level.abs() / self.slope
    }

    /// Duration in seconds.
    pub fn duration(&self) -> f64 {
        self.t_up() + self.hold + self.t_down()
    }

    /// The torque at `t` seconds.
    pub fn sample(&self, t: f64) -> Sample {
        let t = t.max(0.0);
        let (up, down) = (self.t_up(), self.t_down());
        let torque = if t < up {
            self.from + (self.level - self.from) * t / up
        } else if t < up + self.hold {
            self.level
        } else if t < up + self.hold + down {
            self.level * (1.0 - (t - up - self.hold) / down)
        } else {
            0.0
        };
        Sample {
            torque,
            done: t >= self.duration(),
            ..Sample::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check_move(m: &Move, start: f64, end: f64, vmax: f64, amax: f64, jmax: Option<f64>) {
        let dt = m.duration() / 2000.0;
        let mut prev = m.sample(0.0);
        assert_eq!(prev.pos, start);
        let tol = 1e-6 * (1.0 + (end - start).abs());
        for i in 1..=2100 {
            let s = m.sample(i as f64 * dt);
            assert!(
                s.vel.abs() <= vmax * (1.0 + 1e-9) + 1e-9,
                "v {} > {vmax}",
                s.vel
            );
            assert!(
                s.acc.abs() <= amax * (1.0 + 1e-9) + 1e-9,
                "a {} > {amax}",
                s.acc
            );
            // Monotonic towards the end, never overshooting it.
            if end >= start {
                assert!(s.pos + tol >= prev.pos && s.pos <= end + tol);
            } else {
                assert!(s.pos <= prev.pos + tol && s.pos + tol >= end);
            }
            // Continuity of position and velocity between samples.
            assert!((s.pos - prev.pos).abs() <= vmax * dt * 1.01 + tol);
            if let Some(j) = jmax {
                assert!((s.acc - prev.acc).abs() <= j * dt * 1.01 + 1e-9, "jerk");
            }
            prev = s;
        }
        let last = m.sample(m.duration());
        assert_eq!(last.pos, end);
        assert!(last.done);
        // Just before the end the profile has nearly arrived (no jump at the end).
        let almost = m.sample(m.duration() * (1.0 - 1e-9));
        assert!((almost.pos - end).abs() <= tol + vmax * m.duration() * 1e-8);
    }

    #[test]
    fn trapezoid_reaches_vmax_on_long_moves() {
        let m = Move::trapezoid(0.0, 100_000.0, 10_000.0, 50_000.0).unwrap();
        // 0.2 s ramp each way, 10 000 counts per ramp pair: cruise 9 s.
        assert!((m.duration() - 10.2).abs() < 1e-9);
        assert_eq!(m.peak_velocity(), 10_000.0);
        check_move(&m, 0.0, 100_000.0, 10_000.0, 50_000.0, None);
    }

    #[test]
    fn trapezoid_is_triangular_on_short_moves() {
        let m = Move::trapezoid(500.0, 400.0, 10_000.0, 10_000.0).unwrap();
        assert!(m.peak_velocity() < 10_000.0);
        assert!((m.duration() - 2.0 * (100.0f64 / 10_000.0).sqrt()).abs() < 1e-9);
        check_move(&m, 500.0, 400.0, 10_000.0, 10_000.0, None);
    }

    #[test]
    fn double_s_limits_jerk_and_handles_all_cases() {
        for &(h, v, a, j) in &[
            (100_000.0, 10_000.0, 50_000.0, 1_000_000.0), // reaches v and a
            (3_000.0, 10_000.0, 50_000.0, 1_000_000.0),   // reaches a, not v
            (10.0, 10_000.0, 50_000.0, 1_000_000.0),      // reaches neither
            (100_000.0, 100.0, 50_000.0, 1_000_000.0),    // v reached before a
        ] {
            let m = Move::double_s(0.0, h, v, a, j).unwrap();
            check_move(&m, 0.0, h, v, a, Some(j));
            let m = Move::double_s(h, 0.0, v, a, j).unwrap();
            check_move(&m, h, 0.0, v, a, Some(j));
        }
    }

    #[test]
    fn zero_length_move_is_done_at_once() {
        let m = Move::double_s(7.0, 7.0, 1.0, 1.0, 1.0).unwrap();
        assert_eq!(m.duration(), 0.0);
        let s = m.sample(0.0);
        assert!(s.done);
        assert_eq!(s.pos, 7.0);
    }

    #[test]
    fn bad_limits_are_refused_with_their_name() {
        let e = Move::trapezoid(0.0, 1.0, 0.0, 1.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "velocity must be a positive finite number, got 0"
        );
        assert!(Move::double_s(0.0, f64::NAN, 1.0, 1.0, 1.0).is_err());
        assert!(Sine::new(0.0, 1.0, -1.0, 1.0).is_err());
    }

    #[test]
    fn sine_starts_at_centre_and_ends_done() {
        let s = Sine::new(1000.0, 500.0, 2.0, 3.0).unwrap();
        assert_eq!(s.sample(0.0).pos, 1000.0);
        assert!((s.duration() - 1.5).abs() < 1e-12);
        assert!((s.sample(0.125).pos - 1500.0).abs() < 1e-9);
        assert!(s.sample(1.5).done);
    }

    #[test]
    fn velocity_ramp_integrates_position() {
        let r = VelocityRamp::new(0.0, 0.0, 1000.0, 2000.0, 1.0).unwrap();
        let s = r.sample(0.5);
        assert!((s.vel - 1000.0).abs() < 1e-9);
        assert!((s.pos - 250.0).abs() < 1e-9);
        let e = r.sample(10.0);
        assert!(e.done);
        assert!((e.pos - 1250.0).abs() < 1e-9);
    }

    #[test]
    fn jog_respects_acceleration_and_stops() {
        let mut j = Jog::new(0.0, 1000.0).unwrap();
        j.set_target(500.0);
        let s = j.advance(0.1);
        assert!((s.vel - 100.0).abs() < 1e-9);
        for _ in 0..10 {
            j.advance(0.1);
        }
        j.set_target(0.0);
        let mut last = j.advance(0.1);
        for _ in 0..10 {
            last = j.advance(0.1);
        }
        assert!(last.done);
        assert_eq!(last.vel, 0.0);
    }

    #[test]
    fn torque_step_ramps_holds_and_returns_to_zero() {
        let t = TorqueStep::new(0.0, 100.0, 1000.0, 0.5).unwrap();
        assert!((t.sample(0.05).torque - 50.0).abs() < 1e-9);
        assert_eq!(t.sample(0.3).torque, 100.0);
        assert_eq!(t.sample(10.0).torque, 0.0);
        assert!(t.sample(t.duration()).done);
    }

    proptest! {
        #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
        #[test]
        fn random_double_s_moves_respect_limits(
            start in -1e6f64..1e6, dist in -1e6f64..1e6,
            v in 1.0f64..1e5, a in 1.0f64..1e6, j in 1.0f64..1e8,
        ) {
            let m = Move::double_s(start, start + dist, v, a, j).unwrap();
            check_move(&m, start, start + dist, v, a, Some(j));
        }

        #[test]
        fn random_trapezoids_respect_limits(
            start in -1e6f64..1e6, dist in -1e6f64..1e6, v in 1.0f64..1e5, a in 1.0f64..1e6,
        ) {
            let m = Move::trapezoid(start, start + dist, v, a).unwrap();
            check_move(&m, start, start + dist, v, a, None);
        }
    }
}
