//! The limits an application's set-points must keep.

use crate::program::RunMode;

/// Limits a set-point from the application must keep (drive units; `None`: unchecked).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SetpointLimits {
    /// Largest |velocity|, position units per second: in csp the change of the position
    /// set-point per cycle, in csv the set-point itself.
    pub max_velocity: Option<f64>,
    /// Largest |acceleration|, position units per second²: the change of that velocity per
    /// cycle.
    pub max_acceleration: Option<f64>,
    /// Largest |torque| set-point in cst, in the drive's torque unit.
    pub max_torque: Option<f64>,
}

impl SetpointLimits {
    /// Check a set-point `v` in `mode` after `prev` (position, velocity) one cycle of `dt`
    /// seconds earlier: the velocity and acceleration it implies, or `Err((limit, value,
    /// max))` naming the limit it breaks.
    pub fn check(
        &self,
        mode: RunMode,
        v: f64,
        prev: (f64, f64),
        dt: f64,
    ) -> Result<(f64, f64), (&'static str, f64, f64)> {
        if !v.is_finite() {
            return Err(("a finite set-point", v, 0.0));
        }
        let (vel, acc) = match mode {
            RunMode::Csp | RunMode::Ip => {
                let vel = (v - prev.0) / dt;
                (vel, (vel - prev.1) / dt)
            }
            RunMode::Csv => (v, (v - prev.1) / dt),
            // The drive ramps to a pv target with its own 0x6083/0x6084.
            RunMode::Pv => (v, 0.0),
            // The drive generates the motion to a pp target.
            RunMode::Pp => return Ok((prev.1, 0.0)),
            RunMode::Cst | RunMode::Tq => {
                if let Some(m) = self.max_torque
                    && v.abs() > m
                {
                    return Err(("max_torque", v.abs(), m));
                }
                return Ok((prev.1, 0.0));
            }
        };
        if let Some(m) = self.max_velocity
            && vel.abs() > m
        {
            return Err(("max_velocity", vel.abs(), m));
        }
        if let Some(m) = self.max_acceleration
            && acc.abs() > m
        {
            return Err(("max_acceleration", acc.abs(), m));
        }
        Ok((vel, acc))
    }
}
