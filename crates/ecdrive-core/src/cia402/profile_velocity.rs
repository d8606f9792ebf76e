//! Profile velocity (pv, 6060h = 3) and profile torque (tq, 6060h = 4): set-point, halt and
//! the mode's status bits.
//!
//! pv (BLV-R §7.2.4, ASDA-A2 §4.4, Lexium §6.6): statusword bit 10 = target (speed) reached
//! (with halt = 1: the axis has stopped), bit 12 = speed is zero (all three drives; ASDA-A2
//! "zero speed", BLV-R "SPD"), bit 13 = max slippage error (Lexium). The drive ramps to 60FFh
//! with 6083h/6084h; a new 60FFh applies at once.
//!
//! tq (BLV-R §7.4, ASDA-A2 §3.5, Lexium §6.8): bit 10 = torque reached; the drive ramps to 6071h
//! with 6087h; halt = 1 ramps the torque to 0.
//!
//! Both helpers drive an [`Axis`] through [`Axis::set_velocity`] / [`Axis::set_torque`] and
//! [`Axis::set_mode_bits`] (bit 8). Bit 10 refers to the target the drive *has*: right after a
//! new target (or the start of streaming) the statusword still describes the old one, so the
//! helpers report "reached" only [`SETTLE_CYCLES`] cycles after the last change. The axis accepts set-points only while streaming, i.e. in
//! Operation enabled: this is what the ASDA-A2 needs, which clears 60FFh and 6071h when it
//! enables (§3.4.2, §3.5.2) — a value written before would be lost.

use super::axis::Axis;
use super::bits::{ControlWord, StatusWord};
use super::mode::OperationMode;

/// **\[REC\]** Cycles after a target change before bit 10 counts: the round trip of the new
/// target to the drive and of its statusword back (RPDO at one SYNC, TPDO at the next), plus
/// one.
pub const SETTLE_CYCLES: u32 = 3;

/// The pv status bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PvStatus {
    /// Bit 10: the velocity is within the window of the target (halt = 1: stopped).
    pub target_reached: bool,
    /// Bit 12: speed is zero (if the drive has the flag).
    pub zero_speed: Option<bool>,
    /// Bit 13: max slippage / following error.
    pub slippage_error: bool,
    /// Whether the axis accepted the set-point this cycle.
    pub streaming: bool,
}

/// Profile velocity helper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ProfileVelocity {
    zero_speed_bit: bool,
    target: i32,
    halt: bool,
    since_change: u32,
}

impl ProfileVelocity {
    /// A helper; `zero_speed_bit`: the drive reports zero speed in statusword bit 12.
    pub const fn new(zero_speed_bit: bool) -> Self {
        Self {
            zero_speed_bit,
            target: 0,
            halt: false,
            since_change: 0,
        }
    }

    /// The target velocity (60FFh, drive units), applied while the axis streams in pv.
    pub fn set_target(&mut self, velocity: i32) {
        if velocity != self.target {
            self.since_change = 0;
        }
        self.target = velocity;
    }

    /// The target.
    pub const fn target(&self) -> i32 {
        self.target
    }

    /// Halt (bit 8): decelerate per 605Dh and hold zero; clearing it resumes the target.
    pub fn set_halt(&mut self, halt: bool) {
        if halt != self.halt {
            self.since_change = 0;
        }
        self.halt = halt;
    }

    /// One cycle, before [`Axis::step`].
    pub fn step(&mut self, axis: &mut Axis, sw: StatusWord) -> PvStatus {
        let st = axis.status();
        let active = st.streaming && st.active_mode == OperationMode::ProfileVelocity;
        self.since_change = if active {
            self.since_change.saturating_add(1)
        } else {
            0
        };
        if active {
            let _ = axis.set_velocity(self.target);
            let bits = if self.halt {
                ControlWord::HALT
            } else {
                ControlWord::empty()
            };
            axis.set_mode_bits(bits);
        }
        PvStatus {
            target_reached: sw.contains(StatusWord::TARGET_REACHED)
                && self.since_change > SETTLE_CYCLES,
            zero_speed: self
                .zero_speed_bit
                .then(|| sw.contains(StatusWord::SPEED_ZERO)),
            slippage_error: sw.contains(StatusWord::FOLLOWING_ERROR),
            streaming: active,
        }
    }
}

/// The tq status bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TqStatus {
    /// Bit 10: the torque has reached the target.
    pub target_reached: bool,
    /// Whether the axis accepted the set-point this cycle.
    pub streaming: bool,
}

/// Profile torque helper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ProfileTorque {
    target: i16,
    halt: bool,
    since_change: u32,
}

impl ProfileTorque {
    /// A helper with target 0.
    pub const fn new() -> Self {
        Self {
            target: 0,
            halt: false,
            since_change: 0,
        }
    }

    /// The target torque (6071h, per mille of rated torque on the three CANopen drives).
    pub fn set_target(&mut self, torque: i16) {
        if torque != self.target {
            self.since_change = 0;
        }
        self.target = torque;
    }

    /// Halt (bit 8): ramp the torque to 0.
    pub fn set_halt(&mut self, halt: bool) {
        if halt != self.halt {
            self.since_change = 0;
        }
        self.halt = halt;
    }

    /// One cycle, before [`Axis::step`].
    pub fn step(&mut self, axis: &mut Axis, sw: StatusWord) -> TqStatus {
        let st = axis.status();
        let active = st.streaming && st.active_mode == OperationMode::ProfileTorque;
        self.since_change = if active {
            self.since_change.saturating_add(1)
        } else {
            0
        };
        if active {
            let _ = axis.set_torque(self.target);
            let bits = if self.halt {
                ControlWord::HALT
            } else {
                ControlWord::empty()
            };
            axis.set_mode_bits(bits);
        }
        TqStatus {
            target_reached: sw.contains(StatusWord::TARGET_REACHED)
                && self.since_change > SETTLE_CYCLES,
            streaming: active,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cia402::mode_test_support::Rig;

    #[test]
    fn pv_writes_the_target_and_reads_the_flags() {
        let mut rig = Rig::enabled(OperationMode::ProfileVelocity);
        let mut pv = ProfileVelocity::new(true);
        pv.set_target(1500);
        rig.extra = StatusWord::SPEED_ZERO;
        let s = rig.statusword();
        let st = pv.step(&mut rig.axis, s);
        assert_eq!(st.zero_speed, Some(true));
        assert!(st.streaming);
        let o = rig.cycle();
        assert_eq!(o.target_velocity, 1500);
        assert!(!o.controlword.contains(ControlWord::HALT));
        pv.set_halt(true);
        rig.extra = StatusWord::TARGET_REACHED;
        let s = rig.statusword();
        let st = pv.step(&mut rig.axis, s);
        assert!(!st.target_reached, "bit 10 still describes the old target");
        for _ in 0..SETTLE_CYCLES {
            let s = rig.statusword();
            pv.step(&mut rig.axis, s);
            rig.cycle();
        }
        let s = rig.statusword();
        let st = pv.step(&mut rig.axis, s);
        assert!(st.target_reached);
        assert_eq!(st.zero_speed, Some(false));
        assert!(rig.cycle().controlword.contains(ControlWord::HALT));
        let st = ProfileVelocity::new(false).step(&mut rig.axis, rig_sw());
        assert_eq!(st.zero_speed, None);
    }

    fn rig_sw() -> StatusWord {
        StatusWord::empty()
    }

    #[test]
    fn pv_target_held_back_until_enabled() {
        // ASDA-A2 clears 60FFh on enable: the target must only go out in Operation enabled.
        let mut rig = Rig::enabled(OperationMode::ProfileVelocity);
        rig.axis.request_disable();
        for _ in 0..10 {
            rig.cycle();
        }
        let mut pv = ProfileVelocity::new(true);
        pv.set_target(900);
        let s = rig.statusword();
        assert!(!pv.step(&mut rig.axis, s).streaming);
        assert_eq!(rig.cycle().target_velocity, 0);
        rig.axis.request_enable().unwrap();
        let mut seen = Vec::new();
        for _ in 0..20 {
            let s = rig.statusword();
            pv.step(&mut rig.axis, s);
            let o = rig.cycle();
            seen.push((rig.device.state(), o.target_velocity));
        }
        assert!(seen.iter().any(|(_, v)| *v == 900));
        // Never 900 before the device was in Operation enabled.
        let first = seen.iter().position(|(_, v)| *v == 900).unwrap();
        assert!(first > 0);
    }

    #[test]
    fn tq_writes_the_target() {
        let mut rig = Rig::enabled(OperationMode::ProfileTorque);
        let mut tq = ProfileTorque::new();
        tq.set_target(-250);
        rig.extra = StatusWord::TARGET_REACHED;
        for _ in 0..SETTLE_CYCLES {
            let s = rig.statusword();
            assert!(!tq.step(&mut rig.axis, s).target_reached);
            rig.cycle();
        }
        let s = rig.statusword();
        let st = tq.step(&mut rig.axis, s);
        assert!(st.target_reached && st.streaming);
        assert_eq!(rig.cycle().target_torque, -250);
        tq.set_halt(true);
        let s = rig.statusword();
        tq.step(&mut rig.axis, s);
        assert!(rig.cycle().controlword.contains(ControlWord::HALT));
    }
}
