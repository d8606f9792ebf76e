//! Profile position mode (pp, 6060h = 1): the new-set-point / set-point-acknowledge handshake,
//! single set-points and sets of set-points, absolute and relative targets.
//!
//! The handshake (CiA 402 §6.2.2, as the three CANopen drive manuals describe it: BLV-R §7.3.3–
//! 7.3.5, ASDA-A2 §4.4 6040h/6041h, Lexium §6.5):
//!
//! | step | master (controlword) | drive (statusword) |
//! |---|---|---|
//! | 1 | writes 607Ah, bit 5 (change set immediately), bit 6 (relative) | bit 12 = 0: ready for a set-point |
//! | 2 | bit 4 (new set-point) 0 → 1 | takes 607Ah, answers bit 12 = 1 (set-point acknowledge) |
//! | 3 | bit 4 → 0 | bit 12 → 0 once it can take the next set-point |
//! | 4 | | bit 10 = 1 when the last target is reached |
//!
//! Bit 5 = 1 ("single set-point"): a new set-point replaces the running move at once. Bit 5 = 0
//! ("set of set-points"): it is queued and starts when the running move reaches its target; a
//! drive with a one-deep buffer keeps bit 12 = 1 while the buffer is full. Bit 6 = 1: the
//! target is relative (BLV-R: to the previous target by default, 60F2h). Controlword bit 9
//! (change on set-point) stays 0: the BLV-R requires it (§7.3.3).
//!
//! [`ProfilePosition`] drives an [`Axis`] through its public API only: it writes the target with
//! [`Axis::set_position`] one cycle before it raises bit 4 (so a drive that maps 607Ah and 6040h
//! in different PDOs has the target before the edge), and sets bits 4, 5, 6 and 8 with
//! [`Axis::set_mode_bits`]. It holds a fixed-size queue: nothing allocates and nothing panics.
//! It never moves the axis on its own: when the axis stops streaming (fault, disable, quick
//! stop, mode change) the queue is dropped and [`PpStatus::aborted`] says so.

use super::axis::Axis;
use super::bits::{ControlWord, StatusWord};
use super::mode::OperationMode;

/// One pp set-point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SetPoint {
    /// 607Ah, in drive position units.
    pub target: i32,
    /// Controlword bit 6: relative target.
    pub relative: bool,
    /// Controlword bit 5: change set immediately (single set-point). `false`: queue it behind
    /// the running move (set of set-points).
    pub immediate: bool,
}

impl SetPoint {
    /// An absolute set-point that replaces the running move.
    pub const fn absolute(target: i32) -> Self {
        Self {
            target,
            relative: false,
            immediate: true,
        }
    }

    /// A relative set-point that replaces the running move.
    pub const fn relative(distance: i32) -> Self {
        Self {
            target: distance,
            relative: true,
            immediate: true,
        }
    }

    /// The same set-point queued behind the running move (bit 5 = 0).
    pub const fn queued(self) -> Self {
        Self {
            immediate: false,
            ..self
        }
    }

    /// The controlword bits 5 and 6 of this set-point.
    pub fn bits(self) -> ControlWord {
        let mut b = ControlWord::empty();
        b.set(ControlWord::CHANGE_SET_IMMEDIATELY, self.immediate);
        b.set(ControlWord::RELATIVE, self.relative);
        b
    }
}

/// Settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PpConfig {
    /// Cycles to wait for set-point acknowledge (bit 12 = 1) after raising bit 4 (≥ 1).
    pub handshake_timeout_cycles: u32,
}

impl Default for PpConfig {
    /// **\[REC\]** 500 cycles (0.5 s at 1 ms; a drive acknowledges within a few cycles).
    fn default() -> Self {
        Self {
            handshake_timeout_cycles: 500,
        }
    }
}

/// Where the handshake is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PpPhase {
    /// Nothing in flight.
    Idle,
    /// The target is written; bit 4 rises next cycle.
    Loading,
    /// Bit 4 = 1; waiting for bit 12 = 1.
    Presenting,
    /// Acknowledged, bit 4 = 0; waiting for bit 12 = 0 before the next set-point.
    Acknowledged,
}

/// A handshake failure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum PpError {
    /// The queue is full.
    #[error("pp set-point queue is full ({0} set-points)")]
    QueueFull(usize),
    /// The drive did not acknowledge.
    #[error(
        "the drive did not acknowledge the set-point (statusword bit 12 stayed 0 for {cycles} \
         cycles after controlword bit 4 rose)"
    )]
    NoAcknowledge {
        /// Cycles waited.
        cycles: u32,
    },
}

/// What [`ProfilePosition::step`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PpStatus {
    /// The handshake phase after this step.
    pub phase: PpPhase,
    /// Set-points waiting in the queue.
    pub queued: usize,
    /// Set-points acknowledged by the drive so far.
    pub acknowledged: u32,
    /// Statusword bit 10 with nothing queued or in flight: every given set-point is done.
    pub target_reached: bool,
    /// Statusword bit 13 (following error).
    pub following_error: bool,
    /// The queue was dropped in this step because the axis stopped streaming.
    pub aborted: bool,
    /// A handshake failure in this step (the set-point in flight is dropped).
    pub error: Option<PpError>,
}

/// Queue capacity.
pub const PP_QUEUE: usize = 8;

/// The pp handshake engine. See the [module documentation](self).
#[derive(Debug, Clone)]
pub struct ProfilePosition {
    config: PpConfig,
    queue: [Option<SetPoint>; PP_QUEUE],
    head: usize,
    len: usize,
    phase: PpPhase,
    current: Option<SetPoint>,
    cycles: u32,
    acknowledged: u32,
    halt: bool,
}

impl ProfilePosition {
    /// An idle engine.
    pub const fn new(config: PpConfig) -> Self {
        Self {
            config,
            queue: [None; PP_QUEUE],
            head: 0,
            len: 0,
            phase: PpPhase::Idle,
            current: None,
            cycles: 0,
            acknowledged: 0,
            halt: false,
        }
    }

    /// Queue a set-point. Set-points are handed to the drive in order, one handshake each.
    pub fn push(&mut self, sp: SetPoint) -> Result<(), PpError> {
        if self.len >= PP_QUEUE {
            return Err(PpError::QueueFull(PP_QUEUE));
        }
        let idx = (self.head + self.len) % PP_QUEUE;
        if let Some(slot) = self.queue.get_mut(idx) {
            *slot = Some(sp);
            self.len += 1;
        }
        Ok(())
    }

    /// Drop every queued set-point (the one in flight finishes its handshake).
    pub fn clear(&mut self) {
        self.queue = [None; PP_QUEUE];
        self.head = 0;
        self.len = 0;
    }

    /// Controlword bit 8 (halt): stop with the profile deceleration (605Dh) and keep the
    /// target. Clearing it resumes the move.
    pub fn set_halt(&mut self, halt: bool) {
        self.halt = halt;
    }

    /// The phase.
    pub const fn phase(&self) -> PpPhase {
        self.phase
    }

    /// Whether nothing is queued or in flight.
    pub const fn idle(&self) -> bool {
        self.len == 0 && matches!(self.phase, PpPhase::Idle)
    }

    fn pop(&mut self) -> Option<SetPoint> {
        if self.len == 0 {
            return None;
        }
        let sp = self.queue.get_mut(self.head).and_then(Option::take);
        self.head = (self.head + 1) % PP_QUEUE;
        self.len -= 1;
        sp
    }

    /// One cycle, before [`Axis::step`]: `sw` is the statusword of this cycle's feedback. Sets
    /// the axis' target position and mode bits.
    pub fn step(&mut self, axis: &mut Axis, sw: StatusWord) -> PpStatus {
        let st = axis.status();
        let streaming = st.streaming && st.active_mode == OperationMode::ProfilePosition;
        let ack = sw.contains(StatusWord::SET_POINT_ACKNOWLEDGE);
        let mut error = None;
        let mut aborted = false;

        if !streaming {
            if self.len > 0 || self.phase != PpPhase::Idle {
                aborted = true;
            }
            self.clear();
            self.phase = PpPhase::Idle;
            self.current = None;
            self.cycles = 0;
            return self.status(sw, aborted, None);
        }

        let timeout = self.config.handshake_timeout_cycles.max(1);
        match self.phase {
            PpPhase::Idle => {
                if !ack && let Some(sp) = self.pop() {
                    // Target first, the edge on bit 4 next cycle.
                    let _ = axis.set_position(sp.target);
                    self.current = Some(sp);
                    self.phase = PpPhase::Loading;
                    self.cycles = 0;
                }
            }
            PpPhase::Loading => {
                if let Some(sp) = self.current {
                    let _ = axis.set_position(sp.target);
                }
                self.phase = PpPhase::Presenting;
                self.cycles = 0;
            }
            PpPhase::Presenting => {
                if ack {
                    self.acknowledged = self.acknowledged.wrapping_add(1);
                    self.phase = PpPhase::Acknowledged;
                    self.cycles = 0;
                } else if self.cycles >= timeout {
                    error = Some(PpError::NoAcknowledge {
                        cycles: self.cycles,
                    });
                    self.phase = PpPhase::Idle;
                    self.current = None;
                } else {
                    self.cycles = self.cycles.saturating_add(1);
                }
            }
            PpPhase::Acknowledged => {
                if !ack {
                    self.phase = PpPhase::Idle;
                    self.current = None;
                    // Present the next one at once if there is one.
                    if let Some(sp) = self.pop() {
                        let _ = axis.set_position(sp.target);
                        self.current = Some(sp);
                        self.phase = PpPhase::Loading;
                    }
                    self.cycles = 0;
                }
                // Bit 12 may legitimately stay 1 for a whole move: a drive with a one-deep
                // buffer holding a queued set-point takes the next one only when the running
                // move ends. No timeout here.
            }
        }

        let mut bits = self.current.map(SetPoint::bits).unwrap_or_default();
        if self.phase == PpPhase::Presenting {
            bits |= ControlWord::NEW_SET_POINT;
        }
        if self.halt {
            bits |= ControlWord::HALT;
        }
        axis.set_mode_bits(bits);
        self.status(sw, aborted, error)
    }

    fn status(&self, sw: StatusWord, aborted: bool, error: Option<PpError>) -> PpStatus {
        PpStatus {
            phase: self.phase,
            queued: self.len,
            acknowledged: self.acknowledged,
            target_reached: self.len == 0
                && self.phase == PpPhase::Idle
                && sw.contains(StatusWord::TARGET_REACHED)
                && !sw.contains(StatusWord::SET_POINT_ACKNOWLEDGE),
            following_error: sw.contains(StatusWord::FOLLOWING_ERROR),
            aborted,
            error,
        }
    }
}

impl Default for ProfilePosition {
    fn default() -> Self {
        Self::new(PpConfig::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cia402::mode_test_support::Rig;

    /// A drive's pp side with a one-deep set-point buffer (CiA 402; BLV-R §7.3.5): the rising
    /// edge of bit 4 is taken while bit 12 = 0; bit 12 drops when bit 4 is 0 and the buffer is
    /// free; bit 10 when no move runs.
    struct PpDrive {
        last_bit4: bool,
        ack: bool,
        active: Option<(SetPoint, u32)>,
        buffer: Option<SetPoint>,
        taken: Vec<SetPoint>,
        move_cycles: u32,
        respond: bool,
    }

    impl PpDrive {
        fn new(move_cycles: u32) -> Self {
            Self {
                last_bit4: false,
                ack: false,
                active: None,
                buffer: None,
                taken: Vec::new(),
                move_cycles,
                respond: true,
            }
        }

        fn react(&mut self, rig: &mut Rig) {
            let out = rig.last.unwrap();
            let cw = out.controlword;
            let bit4 = cw.contains(ControlWord::NEW_SET_POINT);
            if let Some((sp, n)) = &mut self.active {
                let _ = sp;
                *n = n.saturating_sub(1);
                if *n == 0 {
                    self.active = self.buffer.take().map(|b| (b, self.move_cycles));
                }
            }
            if self.respond && bit4 && !self.last_bit4 && !self.ack {
                let sp = SetPoint {
                    target: out.target_position,
                    relative: cw.contains(ControlWord::RELATIVE),
                    immediate: cw.contains(ControlWord::CHANGE_SET_IMMEDIATELY),
                };
                self.taken.push(sp);
                if sp.immediate || self.active.is_none() {
                    self.active = Some((sp, self.move_cycles));
                } else {
                    self.buffer = Some(sp);
                }
                self.ack = true;
            } else if !bit4 && self.ack && self.buffer.is_none() {
                self.ack = false;
            }
            self.last_bit4 = bit4;
            let mut extra = StatusWord::empty();
            extra.set(StatusWord::SET_POINT_ACKNOWLEDGE, self.ack);
            extra.set(
                StatusWord::TARGET_REACHED,
                self.active.is_none() && !self.taken.is_empty(),
            );
            rig.extra = extra;
        }
    }

    fn run(
        rig: &mut Rig,
        pp: &mut ProfilePosition,
        drive: &mut PpDrive,
        n: usize,
    ) -> Vec<PpStatus> {
        let mut out = Vec::new();
        for _ in 0..n {
            let st = {
                let sw = rig.statusword();
                pp.step(&mut rig.axis, sw)
            };
            rig.cycle();
            drive.react(rig);
            out.push(st);
        }
        out
    }

    #[test]
    fn single_set_point_handshake_follows_the_manual() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut drive = PpDrive::new(5);
        let mut pp = ProfilePosition::default();
        pp.push(SetPoint::absolute(36_000)).unwrap();
        // Cycle 1: target written, bit 4 still 0.
        {
            let sw = rig.statusword();
            pp.step(&mut rig.axis, sw)
        };
        let o = rig.cycle();
        assert_eq!(o.target_position, 36_000);
        assert!(!o.controlword.contains(ControlWord::NEW_SET_POINT));
        assert!(o.controlword.contains(ControlWord::CHANGE_SET_IMMEDIATELY));
        assert!(!o.controlword.contains(ControlWord::RELATIVE));
        drive.react(&mut rig);
        // Cycle 2: bit 4 rises with the same target; the drive acknowledges.
        {
            let sw = rig.statusword();
            pp.step(&mut rig.axis, sw)
        };
        let o = rig.cycle();
        assert!(o.controlword.contains(ControlWord::NEW_SET_POINT));
        assert_eq!(o.target_position, 36_000);
        drive.react(&mut rig);
        assert!(rig.statusword().contains(StatusWord::SET_POINT_ACKNOWLEDGE));
        // Cycle 3: the master drops bit 4 on seeing bit 12.
        let st = {
            let sw = rig.statusword();
            pp.step(&mut rig.axis, sw)
        };
        assert_eq!(st.phase, PpPhase::Acknowledged);
        assert_eq!(st.acknowledged, 1);
        let o = rig.cycle();
        assert!(!o.controlword.contains(ControlWord::NEW_SET_POINT));
        drive.react(&mut rig);
        let sts = run(&mut rig, &mut pp, &mut drive, 10);
        assert!(sts.last().unwrap().target_reached);
        assert!(
            !sts.first().unwrap().target_reached,
            "not reached while moving"
        );
        assert_eq!(drive.taken, vec![SetPoint::absolute(36_000)]);
        // The drive never saw a second edge.
        assert!(!rig.cw().contains(ControlWord::NEW_SET_POINT));
    }

    #[test]
    fn relative_and_queued_bits() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut drive = PpDrive::new(3);
        let mut pp = ProfilePosition::default();
        pp.push(SetPoint::relative(-500).queued()).unwrap();
        run(&mut rig, &mut pp, &mut drive, 3);
        assert_eq!(
            drive.taken,
            vec![SetPoint {
                target: -500,
                relative: true,
                immediate: false
            }]
        );
    }

    #[test]
    fn set_of_set_points_waits_for_buffer_space() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut drive = PpDrive::new(20);
        let mut pp = ProfilePosition::default();
        for t in [1000, 2000, 3000] {
            pp.push(SetPoint::absolute(t).queued()).unwrap();
        }
        let sts = run(&mut rig, &mut pp, &mut drive, 15);
        // Two taken quickly (active + buffer), the third waits: bit 12 stays 1 meanwhile.
        assert_eq!(drive.taken.len(), 2);
        assert_eq!(sts.last().unwrap().queued, 1);
        assert!(sts.iter().all(|s| s.error.is_none()));
        let sts = run(&mut rig, &mut pp, &mut drive, 80);
        let targets: Vec<i32> = drive.taken.iter().map(|s| s.target).collect();
        assert_eq!(targets, vec![1000, 2000, 3000]);
        assert!(sts.last().unwrap().target_reached);
        assert_eq!(sts.last().unwrap().acknowledged, 3);
    }

    #[test]
    fn missing_acknowledge_is_an_error() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut drive = PpDrive::new(3);
        drive.respond = false;
        let mut pp = ProfilePosition::new(PpConfig {
            handshake_timeout_cycles: 10,
        });
        pp.push(SetPoint::absolute(5)).unwrap();
        let sts = run(&mut rig, &mut pp, &mut drive, 20);
        let err = sts.iter().find_map(|s| s.error).unwrap();
        assert_eq!(err, PpError::NoAcknowledge { cycles: 10 });
        assert!(!rig.cw().contains(ControlWord::NEW_SET_POINT));
        assert_eq!(pp.phase(), PpPhase::Idle);
    }

    #[test]
    fn queue_dropped_when_the_axis_stops_streaming() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut drive = PpDrive::new(3);
        let mut pp = ProfilePosition::default();
        pp.push(SetPoint::absolute(5)).unwrap();
        pp.push(SetPoint::absolute(6)).unwrap();
        rig.axis.request_disable();
        let sts = run(&mut rig, &mut pp, &mut drive, 5);
        assert!(sts.iter().any(|s| s.aborted));
        assert!(pp.idle());
        assert!(drive.taken.is_empty() || drive.taken.len() == 1);
        for _ in 0..PP_QUEUE {
            pp.push(SetPoint::absolute(1)).unwrap();
        }
        assert_eq!(
            pp.push(SetPoint::absolute(1)),
            Err(PpError::QueueFull(PP_QUEUE))
        );
    }

    #[test]
    fn halt_sets_bit_8() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut drive = PpDrive::new(3);
        let mut pp = ProfilePosition::default();
        pp.set_halt(true);
        run(&mut rig, &mut pp, &mut drive, 2);
        assert!(rig.cw().contains(ControlWord::HALT));
        pp.set_halt(false);
        run(&mut rig, &mut pp, &mut drive, 1);
        assert!(!rig.cw().contains(ControlWord::HALT));
    }
}
