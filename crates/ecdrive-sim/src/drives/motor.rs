//! The motor and load model of the emulated drives, with the drive's control loops.
//!
//! One rigid inertia with viscous friction, driven by a torque that the drive limits. The drive
//! closes its loops once per cycle, from the actual state at the start of the cycle, and the
//! model integrates the cycle in [`SUBSTEPS`] equal steps. Nothing here reads a clock: the
//! result depends only on the commands and the cycle times given, so a test that streams the
//! same outputs gets the same motion every time.
//!
//! The loops know the inertia and the friction (as after an auto-tuning):
//! - **position** (csp, and pp/hm through their set-point generators): the reference moves
//!   linearly over the cycle from the previous set-point to the new one (the set-point's own
//!   speed is the velocity feed-forward), and a PD loop of [`POSITION_BANDWIDTH_HZ`] (critically
//!   damped) closes on it every integration step; between two set-points the remaining error
//!   decays within a fraction of a cycle, so a csp stream is followed with a following error far
//!   below one cycle of motion;
//! - **velocity** (csv, pv): a constant acceleration that reaches the target speed at the end of
//!   the cycle;
//! - **torque** (cst, tq): the commanded torque, with a speed limiter.
//!
//! Every loop is bounded by the torque limits and the speed limit, and then the following
//! error grows: that is what a too large set-point step does to a real drive.

use super::spec::{MotorSpec, PowerOff};
use core::f64::consts::TAU;

/// Integration steps per cycle, at least: more for long cycles, so that no step is longer than
/// [`MAX_STEP_NS`].
pub const SUBSTEPS: u32 = 8;

/// The longest integration step, ns.
pub const MAX_STEP_NS: u32 = 62_500;

/// \[REC\] Bandwidth of the position loop, Hz (critically damped): the emulated drive's tuning.
pub const POSITION_BANDWIDTH_HZ: f64 = 300.0;

/// What the drive asks of the motor for one cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drive {
    /// Power stage off: the motor coasts or is braked by the dynamic brake.
    Off,
    /// Follow a reference that moves linearly from `from_rev` (the previous set-point) to
    /// `to_rev` (this cycle's) over the cycle.
    Position {
        /// The previous set-point, revolutions.
        from_rev: f64,
        /// This cycle's set-point, revolutions.
        to_rev: f64,
    },
    /// Reach `target_rev_s` at the end of the cycle.
    Velocity {
        /// Speed set-point, rev/s.
        target_rev_s: f64,
    },
    /// Apply this torque.
    Torque {
        /// Torque set-point, N·m.
        torque_nm: f64,
    },
}

/// The limits of one cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Largest positive torque, N·m (≥ 0).
    pub positive_nm: f64,
    /// Largest negative torque magnitude, N·m (≥ 0).
    pub negative_nm: f64,
    /// Largest speed magnitude, rev/s.
    pub speed_rev_s: f64,
}

/// The motor and its load.
#[derive(Debug, Clone, PartialEq)]
pub struct Motor {
    spec: MotorSpec,
    position_rev: f64,
    speed_rev_s: f64,
    torque_nm: f64,
    torque_limited: bool,
    speed_limited: bool,
    jammed: bool,
}

impl Motor {
    /// A motor at rest at position 0.
    pub fn new(spec: MotorSpec) -> Self {
        Self {
            spec,
            position_rev: 0.0,
            speed_rev_s: 0.0,
            torque_nm: 0.0,
            torque_limited: false,
            speed_limited: false,
            jammed: false,
        }
    }

    /// The motor data.
    pub fn spec(&self) -> &MotorSpec {
        &self.spec
    }

    /// Position, revolutions.
    pub fn position_rev(&self) -> f64 {
        self.position_rev
    }

    /// Speed, rev/s.
    pub fn speed_rev_s(&self) -> f64 {
        self.speed_rev_s
    }

    /// The average torque of the last cycle, N·m.
    pub fn torque_nm(&self) -> f64 {
        self.torque_nm
    }

    /// A torque limit bounded the last cycle.
    pub fn torque_limited(&self) -> bool {
        self.torque_limited
    }

    /// The speed limit bounded the last cycle.
    pub fn speed_limited(&self) -> bool {
        self.speed_limited
    }

    /// Whether the motor is at zero speed.
    pub fn stopped(&self) -> bool {
        self.speed_rev_s.abs() <= self.spec.zero_speed_rev_s
    }

    /// Block the load (a jammed axis): the motor does not move whatever the torque.
    pub fn set_jammed(&mut self, jammed: bool) {
        self.jammed = jammed;
        if jammed {
            self.speed_rev_s = 0.0;
        }
    }

    /// Whether the load is blocked.
    pub fn jammed(&self) -> bool {
        self.jammed
    }

    fn inertia_rev(&self) -> f64 {
        // N·m per rev/s²: J in kg·m² times 2π rad/rev.
        self.spec.inertia_kg_m2.max(1e-9) * TAU
    }

    fn friction_nm(&self, speed_rev_s: f64) -> f64 {
        self.spec.viscous_nm_s_rad * speed_rev_s * TAU
    }

    /// Integrate one cycle of `dt_s` seconds.
    pub fn step(&mut self, drive: Drive, limits: Limits, dt_s: f64) {
        self.torque_limited = false;
        self.speed_limited = false;
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return;
        }
        let n = SUBSTEPS.max((dt_s * 1e9 / f64::from(MAX_STEP_NS)).ceil() as u32);
        let h = dt_s / f64::from(n);
        let wn = TAU * POSITION_BANDWIDTH_HZ;
        let (kp, kv) = (wn * wn, 2.0 * wn);
        let v0 = self.speed_rev_s;
        let accel = match drive {
            Drive::Velocity { target_rev_s } => (target_rev_s - v0) / dt_s,
            _ => 0.0,
        };
        let speed_limit = limits.speed_rev_s.max(0.0);
        let mut torque_sum = 0.0;
        for k in 0..n {
            let x = self.position_rev;
            let v = self.speed_rev_s;
            let friction = self.friction_nm(v);
            let mut torque = match drive {
                Drive::Off => match self.spec.power_off {
                    PowerOff::Coast => 0.0,
                    PowerOff::DynamicBrake => -self.spec.dynamic_brake_nm_s_rad * v * TAU,
                },
                Drive::Position { from_rev, to_rev } => {
                    let speed = (to_rev - from_rev) / dt_s;
                    let t = f64::from(k) * h;
                    let x_ref = from_rev + speed * t;
                    let a = kp * (x_ref - x) + kv * (speed - v);
                    self.inertia_rev() * a + friction
                }
                Drive::Velocity { .. } => self.inertia_rev() * accel + friction,
                Drive::Torque { torque_nm } => {
                    // Speed limiter: no torque that drives the speed beyond the limit.
                    let a = (torque_nm - friction) / self.inertia_rev();
                    let next = v + a * h;
                    if next.abs() > speed_limit {
                        self.speed_limited = true;
                        let target = speed_limit.copysign(next);
                        self.inertia_rev() * (target - v) / h + friction
                    } else {
                        torque_nm
                    }
                }
            };
            if drive != Drive::Off {
                let hi = limits.positive_nm.max(0.0);
                let lo = -limits.negative_nm.max(0.0);
                if torque > hi || torque < lo {
                    self.torque_limited = true;
                    torque = torque.clamp(lo, hi);
                }
            }
            let mut a = (torque - friction) / self.inertia_rev();
            if self.jammed {
                a = 0.0;
                self.speed_rev_s = 0.0;
            }
            let mut v_next = self.speed_rev_s + a * h;
            if drive != Drive::Off && v_next.abs() > speed_limit {
                self.speed_limited = true;
                v_next = speed_limit.copysign(v_next);
                a = (v_next - self.speed_rev_s) / h;
            }
            if !self.jammed {
                self.position_rev += self.speed_rev_s * h + 0.5 * a * h * h;
                self.speed_rev_s = v_next;
            }
            torque_sum += torque;
        }
        // A braked or coasting motor comes to rest instead of creeping forever.
        if drive == Drive::Off && self.speed_rev_s.abs() < 1e-6 {
            self.speed_rev_s = 0.0;
        }
        self.torque_nm = torque_sum / f64::from(n);
    }

    /// Move the position by `rev` without motion (homing re-references the position counter
    /// outside this model; this is for tests of the model).
    pub fn offset(&mut self, rev: f64) {
        self.position_rev += rev;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: MotorSpec = MotorSpec {
        rated_torque_nm: 0.32,
        peak_torque_permille: 3000.0,
        rated_speed_rev_s: 50.0,
        max_speed_rev_s: 100.0,
        inertia_kg_m2: 2.0e-5,
        viscous_nm_s_rad: 1.0e-5,
        dynamic_brake_nm_s_rad: 1.0e-3,
        power_off: PowerOff::DynamicBrake,
        zero_speed_rev_s: 0.01,
    };

    const LIMITS: Limits = Limits {
        positive_nm: 0.96,
        negative_nm: 0.96,
        speed_rev_s: 100.0,
    };

    #[test]
    fn position_loop_reaches_the_set_point() {
        let mut m = Motor::new(SPEC);
        let dt = 0.001;
        let mut prev = 0.0;
        let mut worst = 0.0f64;
        let mut max_step = 0.0f64;
        for k in 1..=1000 {
            let t = f64::from(k) * dt;
            // Starts at rest: 1 − cos.
            let target = 1.0 - (TAU * t).cos();
            m.step(
                Drive::Position {
                    from_rev: prev,
                    to_rev: target,
                },
                LIMITS,
                dt,
            );
            max_step = max_step.max((target - prev).abs());
            prev = target;
            worst = worst.max((m.position_rev() - target).abs());
            assert!(!m.torque_limited());
        }
        // The error at the end of a cycle is a small fraction of a cycle's motion.
        assert!(worst < 0.02 * max_step, "{worst} vs {max_step}");
    }

    #[test]
    fn limits_bound_a_large_step() {
        let mut m = Motor::new(SPEC);
        m.step(
            Drive::Position {
                from_rev: 0.0,
                to_rev: 10.0,
            },
            LIMITS,
            0.001,
        );
        assert!(m.torque_limited());
        assert!(m.position_rev() < 1.0);
        // Peak acceleration: 0.96 N·m / (2e-5 kg·m² · 2π) ≈ 7639 rev/s².
        assert!(
            m.speed_rev_s() > 7.0 && m.speed_rev_s() < 7.7,
            "{}",
            m.speed_rev_s()
        );
        // It gets there and settles: hold the set-point.
        for _ in 0..300 {
            m.step(
                Drive::Position {
                    from_rev: 10.0,
                    to_rev: 10.0,
                },
                LIMITS,
                0.001,
            );
        }
        assert!(
            (m.position_rev() - 10.0).abs() < 1e-6,
            "{}",
            m.position_rev()
        );
        assert!(m.speed_rev_s().abs() < 1e-3);
    }

    #[test]
    fn velocity_torque_and_off() {
        let mut m = Motor::new(SPEC);
        m.step(Drive::Velocity { target_rev_s: 5.0 }, LIMITS, 0.001);
        assert!((m.speed_rev_s() - 5.0).abs() < 1e-9);
        // Torque mode against the speed limit.
        let slow = Limits {
            speed_rev_s: 6.0,
            ..LIMITS
        };
        for _ in 0..10 {
            m.step(Drive::Torque { torque_nm: 0.5 }, slow, 0.001);
        }
        assert!((m.speed_rev_s() - 6.0).abs() < 1e-9);
        assert!(m.speed_limited());
        // The dynamic brake stops it.
        for _ in 0..2000 {
            m.step(Drive::Off, LIMITS, 0.001);
        }
        assert!(m.stopped());
        // A jammed load does not move.
        m.set_jammed(true);
        let p = m.position_rev();
        m.step(Drive::Velocity { target_rev_s: 5.0 }, LIMITS, 0.001);
        assert_eq!(m.position_rev(), p);
    }
}
