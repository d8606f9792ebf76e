//! Homing mode (hm, 6060h = 6): start, progress, attained, error.
//!
//! Controlword bit 4 = homing operation start: a 0 → 1 edge starts, 1 keeps it running, 1 → 0
//! interrupts (Lexium §6.2; BLV-R §7.5.3 "1 = start/continue"; ASDA-A2 "rising edge"). The
//! statusword bits 13 (homing error), 12 (homing attained) and 10 (target reached) decode as
//! BLV-R §7.5.4 tabulates (the CiA 402 table):
//!
//! | b13 | b12 | b10 | meaning |
//! |---|---|---|---|
//! | 0 | 0 | 0 | homing in progress |
//! | 0 | 0 | 1 | interrupted or not started |
//! | 0 | 1 | 0 | homed, motion still in progress |
//! | 0 | 1 | 1 | completed successfully |
//! | 1 | 0 | 0 | error, velocity ≠ 0 |
//! | 1 | 0 | 1 | error, velocity = 0 |
//! | 1 | 1 | x | reserved |
//!
//! [`Homing`] drives an [`Axis`] through [`Axis::set_mode_bits`]: bit 4 low for one cycle, then
//! high until the drive reports completion or an error, then low again. A statusword that shows
//! "completed" right after the start may still describe the previous homing run, so completion
//! (and an error) counts only after the drive has shown a running state (bit 10 = 0: in
//! progress, or attained and still moving) once, or after [`HomingConfig::settle_cycles`]
//! (methods 35/37 finish within one drive cycle without moving).

use super::axis::Axis;
use super::bits::{ControlWord, StatusWord};
use super::mode::OperationMode;

/// The homing status bits decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HomingState {
    /// 0 0 0: in progress.
    InProgress,
    /// 0 0 1: interrupted or not started.
    Interrupted,
    /// 0 1 0: homed, motion still in progress.
    AttainedMoving,
    /// 0 1 1: completed successfully.
    Completed,
    /// 1 0 0: error, velocity ≠ 0.
    ErrorMoving,
    /// 1 0 1: error, velocity = 0.
    ErrorStopped,
    /// 1 1 x: reserved.
    Reserved,
}

impl HomingState {
    /// Decode bits 13, 12, 10 of a statusword.
    pub const fn decode(sw: StatusWord) -> Self {
        let e = sw.bits() & StatusWord::HOMING_ERROR.bits() != 0;
        let a = sw.bits() & StatusWord::HOMING_ATTAINED.bits() != 0;
        let t = sw.bits() & StatusWord::TARGET_REACHED.bits() != 0;
        match (e, a, t) {
            (false, false, false) => Self::InProgress,
            (false, false, true) => Self::Interrupted,
            (false, true, false) => Self::AttainedMoving,
            (false, true, true) => Self::Completed,
            (true, false, false) => Self::ErrorMoving,
            (true, false, true) => Self::ErrorStopped,
            (true, true, _) => Self::Reserved,
        }
    }

    /// The state name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::InProgress => "homing in progress",
            Self::Interrupted => "homing interrupted or not started",
            Self::AttainedMoving => "homed, motion still in progress",
            Self::Completed => "homing completed",
            Self::ErrorMoving => "homing error, motor moving",
            Self::ErrorStopped => "homing error, motor stopped",
            Self::Reserved => "reserved homing status (bits 13 and 12 both set)",
        }
    }
}

/// Settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct HomingConfig {
    /// Cycles the whole homing run may take before [`HomingOutcome::Timeout`] (≥ 1).
    pub timeout_cycles: u32,
    /// Cycles after the start edge after which "completed" or an error counts even if no
    /// running state was seen (≥ 1): the drive's round trip plus margin.
    pub settle_cycles: u32,
}

impl Default for HomingConfig {
    /// **\[REC\]** 60 000 cycles (a minute at 1 ms), settle 20 cycles.
    fn default() -> Self {
        Self {
            timeout_cycles: 60_000,
            settle_cycles: 20,
        }
    }
}

/// How a homing run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HomingOutcome {
    /// Completed successfully (bits 12 and 10).
    Completed,
    /// The drive reported a homing error (bit 13).
    Error {
        /// Whether the motor was still moving.
        moving: bool,
    },
    /// The axis stopped streaming (fault, disable, quick stop, mode change); bit 4 dropped.
    Aborted,
    /// No result within [`HomingConfig::timeout_cycles`]; bit 4 dropped (interrupts homing).
    Timeout,
    /// [`Homing::start`] while the axis was not streaming in hm.
    NotReady,
}

/// Where a run is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HomingPhase {
    /// Not started, or finished (see [`Homing::outcome`]).
    Idle,
    /// Start requested: bit 4 low for one cycle.
    Arming,
    /// Bit 4 high.
    Running,
}

/// The homing engine. See the [module documentation](self).
#[derive(Debug, Clone)]
pub struct Homing {
    config: HomingConfig,
    phase: HomingPhase,
    cycles: u32,
    seen_running: bool,
    outcome: Option<HomingOutcome>,
}

impl Homing {
    /// An idle engine.
    pub const fn new(config: HomingConfig) -> Self {
        Self {
            config,
            phase: HomingPhase::Idle,
            cycles: 0,
            seen_running: false,
            outcome: None,
        }
    }

    /// Request a homing run (the method, speeds and offset are objects 6098h, 6099h, 607Ch,
    /// written beforehand). Restarts a running one.
    pub fn start(&mut self) {
        self.phase = HomingPhase::Arming;
        self.cycles = 0;
        self.seen_running = false;
        self.outcome = None;
    }

    /// Interrupt: bit 4 drops at the next step.
    pub fn stop(&mut self) {
        if self.phase != HomingPhase::Idle {
            self.phase = HomingPhase::Idle;
            self.outcome = Some(HomingOutcome::Aborted);
        }
    }

    /// The phase.
    pub const fn phase(&self) -> HomingPhase {
        self.phase
    }

    /// The result of the last run, once it ended.
    pub const fn outcome(&self) -> Option<HomingOutcome> {
        self.outcome
    }

    /// One cycle, before [`Axis::step`]; `sw` is this cycle's statusword. Returns the decoded
    /// homing state; the run's result is in [`Homing::outcome`].
    pub fn step(&mut self, axis: &mut Axis, sw: StatusWord) -> HomingState {
        let st = axis.status();
        let streaming = st.streaming && st.active_mode == OperationMode::Homing;
        let state = HomingState::decode(sw);
        let was = self.phase;
        match self.phase {
            HomingPhase::Idle => {}
            HomingPhase::Arming => {
                if streaming {
                    self.phase = HomingPhase::Running;
                } else {
                    self.phase = HomingPhase::Idle;
                    self.outcome = Some(HomingOutcome::NotReady);
                }
            }
            HomingPhase::Running => {
                self.cycles = self.cycles.saturating_add(1);
                if !streaming {
                    self.finish(HomingOutcome::Aborted);
                } else {
                    if matches!(state, HomingState::InProgress | HomingState::AttainedMoving) {
                        self.seen_running = true;
                    }
                    let settled =
                        self.seen_running || self.cycles >= self.config.settle_cycles.max(1);
                    match state {
                        HomingState::Completed if settled => self.finish(HomingOutcome::Completed),
                        HomingState::ErrorMoving if settled => {
                            self.finish(HomingOutcome::Error { moving: true })
                        }
                        HomingState::ErrorStopped if settled => {
                            self.finish(HomingOutcome::Error { moving: false })
                        }
                        _ if self.cycles >= self.config.timeout_cycles.max(1) => {
                            self.finish(HomingOutcome::Timeout)
                        }
                        _ => {}
                    }
                }
            }
        }
        // Arming → Running keeps bit 4 low for this cycle, so the next one is an edge.
        let bits = if self.phase == HomingPhase::Running && was == HomingPhase::Running {
            ControlWord::HOMING_START
        } else {
            ControlWord::empty()
        };
        axis.set_mode_bits(bits);
        state
    }

    fn finish(&mut self, outcome: HomingOutcome) {
        self.phase = HomingPhase::Idle;
        self.outcome = Some(outcome);
    }
}

impl Default for Homing {
    fn default() -> Self {
        Self::new(HomingConfig::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cia402::mode_test_support::Rig;

    fn sw(bits: u16) -> StatusWord {
        StatusWord::from_raw(bits)
    }

    #[test]
    fn decode_follows_the_blv_r_table() {
        // b13 b12 b10 (BLV-R §7.5.4).
        assert_eq!(HomingState::decode(sw(0)), HomingState::InProgress);
        assert_eq!(HomingState::decode(sw(1 << 10)), HomingState::Interrupted);
        assert_eq!(
            HomingState::decode(sw(1 << 12)),
            HomingState::AttainedMoving
        );
        assert_eq!(
            HomingState::decode(sw(1 << 12 | 1 << 10)),
            HomingState::Completed
        );
        assert_eq!(HomingState::decode(sw(1 << 13)), HomingState::ErrorMoving);
        assert_eq!(
            HomingState::decode(sw(1 << 13 | 1 << 10)),
            HomingState::ErrorStopped
        );
        assert_eq!(
            HomingState::decode(sw(1 << 13 | 1 << 12)),
            HomingState::Reserved
        );
    }

    /// Drive side: on the rising edge of bit 4 homing runs for `n` cycles (bit 10 = 0), then
    /// attained + reached, or an error.
    fn drive(rig: &mut Rig, last4: &mut bool, left: &mut Option<u32>, fail: bool) {
        let bit4 = rig.cw().contains(ControlWord::HOMING_START);
        if bit4 && !*last4 {
            *left = Some(5);
        }
        if !bit4 && left.is_some_and(|n| n > 0) {
            *left = None; // interrupted
            rig.extra = sw(1 << 10);
        }
        *last4 = bit4;
        match left {
            Some(0) => {
                rig.extra = if fail {
                    sw(1 << 13 | 1 << 10)
                } else {
                    sw(1 << 12 | 1 << 10)
                }
            }
            Some(n) => {
                rig.extra = sw(0);
                *n -= 1;
            }
            None => {}
        }
    }

    fn run(rig: &mut Rig, h: &mut Homing, fail: bool, cycles: usize) -> Vec<ControlWord> {
        let (mut last4, mut left) = (false, None);
        let mut cws = Vec::new();
        for _ in 0..cycles {
            let s = rig.statusword();
            h.step(&mut rig.axis, s);
            rig.cycle();
            cws.push(rig.cw());
            drive(rig, &mut last4, &mut left, fail);
        }
        cws
    }

    #[test]
    fn start_edge_hold_and_completion() {
        let mut rig = Rig::enabled(OperationMode::Homing);
        // A stale "completed" from an earlier run must not end the new one at once.
        rig.extra = sw(1 << 12 | 1 << 10);
        let mut h = Homing::default();
        h.start();
        let cws = run(&mut rig, &mut h, false, 30);
        assert!(!cws[0].contains(ControlWord::HOMING_START), "low first");
        assert!(cws[1].contains(ControlWord::HOMING_START), "then the edge");
        assert_eq!(h.outcome(), Some(HomingOutcome::Completed));
        assert!(!cws.last().unwrap().contains(ControlWord::HOMING_START));
        // Bit 4 stayed high for the whole run (1→0 would interrupt it).
        let high = cws
            .iter()
            .filter(|c| c.contains(ControlWord::HOMING_START))
            .count();
        assert!(high >= 6, "{high}");
    }

    #[test]
    fn homing_error_is_reported() {
        let mut rig = Rig::enabled(OperationMode::Homing);
        let mut h = Homing::default();
        h.start();
        run(&mut rig, &mut h, true, 30);
        assert_eq!(h.outcome(), Some(HomingOutcome::Error { moving: false }));
    }

    #[test]
    fn not_ready_outside_homing_mode() {
        let mut rig = Rig::enabled(OperationMode::ProfilePosition);
        let mut h = Homing::default();
        h.start();
        run(&mut rig, &mut h, false, 3);
        assert_eq!(h.outcome(), Some(HomingOutcome::NotReady));
        assert!(!rig.cw().contains(ControlWord::HOMING_START));
    }

    #[test]
    fn timeout_and_stop_drop_bit_4() {
        let mut rig = Rig::enabled(OperationMode::Homing);
        let mut h = Homing::new(HomingConfig {
            timeout_cycles: 3,
            settle_cycles: 1,
        });
        h.start();
        for _ in 0..6 {
            let s = rig.statusword();
            h.step(&mut rig.axis, s);
            rig.cycle();
            rig.extra = sw(0); // in progress forever
        }
        assert_eq!(h.outcome(), Some(HomingOutcome::Timeout));
        assert!(!rig.cw().contains(ControlWord::HOMING_START));
        h.start();
        let s = rig.statusword();
        h.step(&mut rig.axis, s);
        h.stop();
        let s = rig.statusword();
        h.step(&mut rig.axis, s);
        rig.cycle();
        assert_eq!(h.outcome(), Some(HomingOutcome::Aborted));
        assert!(!rig.cw().contains(ControlWord::HOMING_START));
    }
}
