//! The units of a drive's CiA 402 objects, for every bus: position units per revolution, the
//! velocity unit of 0x60FF/0x606C, the torque unit of 0x6071/0x6077, and — where the drive's
//! manual describes them — the units of the profile-mode objects (0x6081, 0x6083–0x6085,
//! 0x6087, 0x6099, 0x609A). Conversions go through revolutions and seconds.

/// How a velocity value is expressed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VelocityUnit {
    /// Revolutions per minute times `scale` (BLV-R: 1.0; ASDA-A2 60FFh: 0.1; MR-J4-TM: 0.01).
    RevPerMinute {
        /// One unit in r/min.
        scale: f64,
    },
    /// Position units per second (BDHDE counts/s, ASDA-A2 6081h PUU/s, Lexium steps/s).
    PositionPerSecond,
}

/// How accelerations are expressed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AccelUnit {
    /// A rate in (r/min)/s (BLV-R).
    RpmPerSecond,
    /// A **time**: milliseconds to go from 0 to `rpm` (ASDA-A2: 0 → 3000 r/min).
    MillisecondsTo {
        /// The speed the time refers to, r/min.
        rpm: f64,
    },
    /// A rate in position units per second² (Lexium steps/s²).
    PositionPerSecond2,
}

/// How the torque slope 0x6087 is expressed. One type for the masters' drive profiles and the
/// software slave's own tables (each side states its drive's unit on its own).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TorqueSlopeUnit {
    /// Per mille of rated torque per second (MR-J4-TM, BLV-R 0.1 %/s, Lexium ‰/s).
    PerMillePerSecond,
    /// Milliseconds from 0 to 100 % rated torque (ASDA-A2).
    MillisecondsToRated,
    /// mN·m per second (the BDHDE's 6087h object page), converted with the rated torque.
    MilliNewtonMetrePerSecond,
}

/// The units of the profile-mode objects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileUnits {
    /// Unit of 0x6081 profile velocity (and 0x6082).
    pub profile_velocity: VelocityUnit,
    /// Unit of the homing speeds 0x6099.
    pub homing_velocity: VelocityUnit,
    /// Unit of 0x6083, 0x6084, 0x6085, 0x609A.
    pub acceleration: AccelUnit,
    /// Unit of 0x6087.
    pub torque_slope: TorqueSlopeUnit,
}

/// The units of a drive and conversions to revolutions and seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Units {
    /// Name of the position unit ("pulse", "count", "PUU", "microstep").
    pub position_name: &'static str,
    /// Position units per motor revolution with the default scaling.
    pub position_per_rev: f64,
    /// Unit of 0x60FF, 0x606C, 0x606B.
    pub velocity: VelocityUnit,
    /// Torque (0x6071, 0x6077): one unit is this many per mille of the rated torque.
    pub torque_per_mille: f64,
    /// The profile-mode units, where the profile describes them (`None`: the drive's profile
    /// does not run the profile modes).
    pub profile: Option<ProfileUnits>,
}

impl Units {
    /// CiA 402's own units with `position_per_rev` position units per revolution: velocities
    /// in position units/s, accelerations in units/s², torque in ‰ of rated, its slope in ‰/s
    /// — what a drive known only from its EDS file is taken to use.
    pub const fn cia402(position_per_rev: f64) -> Self {
        Self {
            position_name: "position unit",
            position_per_rev,
            velocity: VelocityUnit::PositionPerSecond,
            torque_per_mille: 1.0,
            profile: Some(ProfileUnits {
                profile_velocity: VelocityUnit::PositionPerSecond,
                homing_velocity: VelocityUnit::PositionPerSecond,
                acceleration: AccelUnit::PositionPerSecond2,
                torque_slope: TorqueSlopeUnit::PerMillePerSecond,
            }),
        }
    }

    /// A velocity value in `unit` as revolutions per second.
    pub fn to_rev_per_s(&self, unit: VelocityUnit, v: f64) -> f64 {
        match unit {
            VelocityUnit::RevPerMinute { scale } => v * scale / 60.0,
            VelocityUnit::PositionPerSecond => v / self.position_per_rev,
        }
    }

    /// Revolutions per second as a value in `unit`.
    pub fn from_rev_per_s(&self, unit: VelocityUnit, rps: f64) -> f64 {
        match unit {
            VelocityUnit::RevPerMinute { scale } => {
                if scale == 0.0 {
                    0.0
                } else {
                    rps * 60.0 / scale
                }
            }
            VelocityUnit::PositionPerSecond => rps * self.position_per_rev,
        }
    }

    /// One unit of 0x60FF/0x606C in position units per second.
    pub fn velocity_position_per_s(&self) -> f64 {
        self.to_rev_per_s(self.velocity, 1.0) * self.position_per_rev
    }

    /// A velocity in position units per second as 0x60FF units (rounded, saturating).
    pub fn velocity_to_drive(&self, position_per_s: f64) -> i32 {
        let k = self.velocity_position_per_s();
        let v = if k == 0.0 {
            0.0
        } else {
            (position_per_s / k).round()
        };
        v.clamp(i32::MIN as f64, i32::MAX as f64) as i32
    }

    /// A 0x606C value as position units per second.
    pub fn velocity_from_drive(&self, v: i32) -> f64 {
        f64::from(v) * self.velocity_position_per_s()
    }

    /// The name of the velocity unit ("0.01 r/min", "count/s").
    pub fn velocity_name(&self) -> String {
        match self.velocity {
            VelocityUnit::RevPerMinute { scale } => format!("{scale} r/min"),
            VelocityUnit::PositionPerSecond => format!("{}/s", self.position_name),
        }
    }

    /// The name of the torque unit ("0.1 % of rated torque").
    pub fn torque_name(&self) -> String {
        format!("{} % of rated torque", self.torque_per_mille / 10.0)
    }

    /// Position units as revolutions.
    pub fn to_revs(&self, p: f64) -> f64 {
        p / self.position_per_rev
    }

    /// Revolutions as position units.
    pub fn from_revs(&self, revs: f64) -> f64 {
        revs * self.position_per_rev
    }

    /// An acceleration value (0x6083 …) as revolutions per second² (`None`: the profile does
    /// not describe the unit). A time of 0 ms counts as "as fast as possible" and gives
    /// `f64::INFINITY`.
    pub fn accel_to_rev_per_s2(&self, a: f64) -> Option<f64> {
        Some(match self.profile?.acceleration {
            AccelUnit::RpmPerSecond => a / 60.0,
            AccelUnit::MillisecondsTo { rpm } => {
                if a <= 0.0 {
                    f64::INFINITY
                } else {
                    (rpm / 60.0) / (a / 1000.0)
                }
            }
            AccelUnit::PositionPerSecond2 => a / self.position_per_rev,
        })
    }

    /// Revolutions per second² as a value of 0x6083 … (`None`: the unit is not described).
    pub fn accel_from_rev_per_s2(&self, rps2: f64) -> Option<f64> {
        Some(match self.profile?.acceleration {
            AccelUnit::RpmPerSecond => rps2 * 60.0,
            AccelUnit::MillisecondsTo { rpm } => {
                if rps2 <= 0.0 {
                    f64::INFINITY
                } else {
                    (rpm / 60.0) / rps2 * 1000.0
                }
            }
            AccelUnit::PositionPerSecond2 => rps2 * self.position_per_rev,
        })
    }

    /// A torque-slope value (0x6087) in per mille of rated torque per second (`None`: the
    /// unit is not described, or is mN·m/s, which needs the motor's rated torque). A time of 0
    /// gives `f64::INFINITY` (a step).
    pub fn torque_slope_per_mille_per_s(&self, v: f64) -> Option<f64> {
        let step = v <= 0.0;
        Some(match self.profile?.torque_slope {
            TorqueSlopeUnit::PerMillePerSecond if step => f64::INFINITY,
            TorqueSlopeUnit::PerMillePerSecond => v,
            TorqueSlopeUnit::MillisecondsToRated if step => f64::INFINITY,
            TorqueSlopeUnit::MillisecondsToRated => 1000.0 / (v / 1000.0),
            TorqueSlopeUnit::MilliNewtonMetrePerSecond => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_conversions() {
        let delta = Units {
            position_name: "PUU",
            position_per_rev: 1_280_000.0,
            velocity: VelocityUnit::RevPerMinute { scale: 0.1 },
            torque_per_mille: 1.0,
            profile: Some(ProfileUnits {
                profile_velocity: VelocityUnit::PositionPerSecond,
                homing_velocity: VelocityUnit::RevPerMinute { scale: 0.1 },
                acceleration: AccelUnit::MillisecondsTo { rpm: 3000.0 },
                torque_slope: TorqueSlopeUnit::MillisecondsToRated,
            }),
        };
        let p = delta.profile.expect("set above");
        // 600.0 r/min = 6000 × 0.1 r/min = 10 rev/s.
        assert!((delta.to_rev_per_s(delta.velocity, 6000.0) - 10.0).abs() < 1e-9);
        assert!((delta.to_rev_per_s(p.profile_velocity, 1_280_000.0) - 1.0).abs() < 1e-9);
        // 200 ms for 0 → 3000 r/min = 50 rev/s in 0.2 s = 250 rev/s².
        assert!((delta.accel_to_rev_per_s2(200.0).expect("described") - 250.0).abs() < 1e-9);
        assert!((delta.accel_from_rev_per_s2(250.0).expect("described") - 200.0).abs() < 1e-9);
        let slope = delta
            .torque_slope_per_mille_per_s(200.0)
            .expect("described");
        assert!((slope - 5000.0).abs() < 1e-9);
        assert!(delta.accel_to_rev_per_s2(0.0).is_some_and(f64::is_infinite));
        assert_eq!(delta.velocity_name(), "0.1 r/min");
        assert_eq!(delta.torque_name(), "0.1 % of rated torque");
        let cyclic_only = Units {
            profile: None,
            ..delta
        };
        assert_eq!(cyclic_only.accel_to_rev_per_s2(1.0), None);
    }

    #[test]
    fn velocity_to_and_from_the_drive() {
        // MR-J4-TM: 0.01 r/min, 4 194 304 pulses per revolution.
        let mr = Units {
            position_name: "pulse",
            position_per_rev: 4_194_304.0,
            velocity: VelocityUnit::RevPerMinute { scale: 0.01 },
            torque_per_mille: 1.0,
            profile: None,
        };
        assert_eq!(mr.velocity_to_drive(50.0 * 4_194_304.0), 300_000);
        assert!((mr.velocity_from_drive(300_000) - 50.0 * 4_194_304.0).abs() < 1e-6);
        let counts = Units {
            position_name: "count",
            position_per_rev: 1_048_576.0,
            velocity: VelocityUnit::PositionPerSecond,
            ..mr
        };
        assert_eq!(counts.velocity_to_drive(1_048_576.0), 1_048_576);
        assert_eq!(counts.velocity_name(), "count/s");
    }
}
