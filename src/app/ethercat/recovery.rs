//! An operator for the emulated jobs (`ecdrive demo`, `ecdrive soak`): it does what an
//! application does around the master — enable the axes, run their programs, and after a
//! controlled stop (a drive fault, lost frames, a re-start) reset the faults, enable again and
//! run the programs again — and it judges what it sees: an error is *unhandled* when the
//! master did not react as documented or the axes could not be brought back to motion.
//!
//! [`Recovery`] is the decision (pure: a telemetry snapshot and the time in, an [`Action`]
//! out); [`Operator`] applies it to a running [`Master`] and counts completed programs and
//! recoveries.

use crate::cia402::State;
use crate::link::FrameLink;
use crate::master::error::MasterError;
use crate::master::session::{HistoryKind, Master};
use crate::master::telemetry::{Axes, Command, Phase, Telemetry};
use std::time::{Duration, Instant};

fn any_energised(t: &Telemetry) -> bool {
    t.axes
        .iter()
        .any(|a| a.state.is_some_and(State::is_energised))
}

/// Whether a history entry of this kind is an unhandled error wherever it appears in an
/// emulated job: a command the master refused, or the session itself failing. (Faults, lost
/// frames, stops and re-starts are the master's documented reactions; a command that came
/// while no cycle ran, [`HistoryKind::NoCycle`], is one that crossed a re-start.)
pub fn unhandled_kind(kind: HistoryKind) -> bool {
    matches!(kind, HistoryKind::CommandRefused | HistoryKind::Session)
}

/// Statusword bit 3, Fault.
const FAULT_BIT: u16 = 0x0008;
/// How long the axes stay disabled (no fault) before the operator enables them again.
const SETTLE: Duration = Duration::from_millis(50);
/// How long a fault may stay shown after the reset was requested (the master's planner pulses
/// bit 7 until the drive leaves Fault); longer is an unhandled error.
const FAULT_CLEAR_LIMIT: Duration = Duration::from_secs(5);
/// A fault still (or again) shown this long after the last reset request gets another.
const RESET_RETRY: Duration = Duration::from_secs(1);
/// How long the axes may take to reach Operation enabled after the request (no fault meanwhile).
const ENABLE_LIMIT: Duration = Duration::from_secs(5);

/// What the application does next.
#[derive(Debug, PartialEq)]
pub enum Action {
    /// Nothing now.
    None,
    /// Every axis is enabled: run the programs (if they do not run yet).
    RunProgram,
    /// Reset the fault of these axes.
    FaultReset(Vec<u16>),
    /// No axis is faulted or energised: enable them all.
    Enable,
    /// An unhandled error, and the axes whose reset is requested again.
    Unhandled(String, Vec<u16>),
}

/// The recovery after a controlled stop, as an application would do it: while a fault
/// is shown, request a reset of the faulted axis (the master then pulses bit 7 until the drive
/// leaves Fault), and again every `RESET_RETRY` while it is still or again shown; once no
/// axis shows a fault and none is energised, wait a moment and enable them all; once all are
/// enabled, run the programs.
///
/// A fault that appears while the enable is under way cancels it (the master refuses to
/// energise a faulted drive); the reset and the enable then start again. It is an unhandled
/// error when a fault stays shown `FAULT_CLEAR_LIMIT` after its first reset request, or the
/// axes are not enabled `ENABLE_LIMIT` after the request without a fault meanwhile.
#[derive(Debug)]
pub struct Recovery {
    /// How long the axes stay idle before the enable ([`SETTLE`]).
    settle: Duration,
    /// [`FAULT_CLEAR_LIMIT`].
    fault_clear_limit: Duration,
    /// [`ENABLE_LIMIT`].
    enable_limit: Duration,
    /// [`RESET_RETRY`].
    reset_retry: Duration,
    /// Per axis, in this fault episode: when the first and the last reset were requested.
    reset_at: Vec<Option<(Instant, Instant)>>,
    /// Since when no axis has been energised nor faulted.
    idle_since: Option<Instant>,
    /// When the enable was requested.
    enable_at: Option<Instant>,
}

impl Default for Recovery {
    fn default() -> Self {
        Self {
            settle: SETTLE,
            fault_clear_limit: FAULT_CLEAR_LIMIT,
            enable_limit: ENABLE_LIMIT,
            reset_retry: RESET_RETRY,
            reset_at: Vec::new(),
            idle_since: None,
            enable_at: None,
        }
    }
}

impl Recovery {
    /// What to do now, given the latest telemetry of a cycle that runs in OP and whether
    /// every axis is in Operation enabled.
    pub fn next(&mut self, t: &Telemetry, all_enabled: bool) -> Action {
        self.next_at(Instant::now(), t, all_enabled)
    }

    /// [`Recovery::next`] at the instant `now` (the tests' clock).
    fn next_at(&mut self, now: Instant, t: &Telemetry, all_enabled: bool) -> Action {
        self.reset_at.resize(t.axes.len(), None);
        let mut reset = Vec::new();
        let mut unhandled = None;
        for (i, a) in t.axes.iter().enumerate() {
            let Some(slot) = self.reset_at.get_mut(i) else {
                continue;
            };
            if a.statusword & FAULT_BIT == 0 {
                // No fault (any more): the next fault is a new episode.
                *slot = None;
                continue;
            }
            match *slot {
                None => {
                    *slot = Some((now, now));
                    reset.push(i as u16);
                }
                Some((first, _)) if now.duration_since(first) > self.fault_clear_limit => {
                    *slot = Some((now, now));
                    reset.push(i as u16);
                    unhandled = Some(format!(
                        "axis {i}: fault (0x603F = 0x{:04X}, state {:?}, statusword 0x{:04X}, \
                         controlword 0x{:04X}) still shown {:?} after its reset was requested",
                        a.error_code, a.state, a.statusword, a.controlword, self.fault_clear_limit
                    ));
                }
                Some((first, last)) if now.duration_since(last) > self.reset_retry => {
                    // Shown again (a new fault right after the reset, between two looks) or
                    // still: ask again, as an application would.
                    *slot = Some((first, now));
                    reset.push(i as u16);
                }
                Some(_) => {}
            }
        }
        if let Some(what) = unhandled {
            return Action::Unhandled(what, reset);
        }
        let faulted = self.reset_at.iter().any(Option::is_some);
        if faulted {
            // A fault cancels an enable under way; it starts again after the reset.
            self.enable_at = None;
            self.idle_since = None;
            return if reset.is_empty() {
                Action::None
            } else {
                Action::FaultReset(reset)
            };
        }
        if all_enabled {
            self.enable_at = None;
            self.idle_since = None;
            return Action::RunProgram;
        }
        if let Some(at) = self.enable_at {
            if now.duration_since(at) > self.enable_limit {
                self.enable_at = None;
                return Action::Unhandled(
                    format!(
                        "the axes are not enabled {:?} after the request (states {:?})",
                        self.enable_limit,
                        t.axes.iter().map(|a| a.state).collect::<Vec<_>>()
                    ),
                    Vec::new(),
                );
            }
            return Action::None;
        }
        if any_energised(t) {
            // Still stopping (a ramp, a quick stop): wait.
            self.idle_since = None;
            return Action::None;
        }
        let since = *self.idle_since.get_or_insert(now);
        if now.duration_since(since) < self.settle {
            return Action::None;
        }
        self.idle_since = None;
        self.enable_at = Some(now);
        Action::Enable
    }
}

/// How often an [`Operator`]'s owner should call [`Operator::step`].
pub const POLL: Duration = Duration::from_millis(10);

/// Applies [`Recovery`] to a running [`Master`]: enables, runs the programs, recovers after a
/// controlled stop, and counts.
#[derive(Debug)]
pub struct Operator {
    rec: Recovery,
    /// Steps of each axis's program.
    steps: Vec<usize>,
    /// The programs were asked to run and have not yet completed.
    running_program: bool,
    /// The axes were enabled at least once.
    enabled_once: bool,
    /// Programs run to their end (every axis together counts once).
    pub programs_completed: u64,
    /// Times the axes were brought back to motion after a controlled stop (the first enable
    /// is not one).
    pub recoveries: u64,
}

impl Operator {
    /// An operator for axes whose programs have these numbers of steps.
    pub fn new(steps: Vec<usize>) -> Self {
        Self {
            rec: Recovery::default(),
            steps,
            running_program: false,
            enabled_once: false,
            programs_completed: 0,
            recoveries: 0,
        }
    }

    /// Look at the latest telemetry `t` of `m` and act on it. Returns the unhandled errors
    /// found now (each saying what), or the master's error if a command could not be queued.
    pub fn step<L: FrameLink + Send + 'static>(
        &mut self,
        m: &mut Master<L>,
        t: &Telemetry,
    ) -> Result<Vec<String>, MasterError> {
        let mut unhandled = Vec::new();
        if t.cycle.phase != Phase::Cycling || !t.cycle.all_op {
            // Stopped, re-starting: the recovery begins again once the drives are in OP.
            self.rec = Recovery::default();
            return Ok(unhandled);
        }
        // A fault must never leave an axis enabled.
        for (i, a) in t.axes.iter().enumerate() {
            if a.statusword & FAULT_BIT != 0 && a.state == Some(State::OperationEnabled) {
                unhandled.push(format!("axis {i} enabled with a fault shown"));
            }
        }
        let done = t
            .axes
            .iter()
            .zip(&self.steps)
            .all(|(a, n)| !a.program_running && a.program_step as usize >= *n);
        let all_enabled = t
            .axes
            .iter()
            .all(|a| a.state == Some(State::OperationEnabled));
        let any_running = t.axes.iter().any(|a| a.program_running);
        if self.running_program && done && all_enabled {
            self.programs_completed += 1;
            self.running_program = false;
        }
        match self.rec.next(t, all_enabled) {
            Action::None => {}
            Action::RunProgram => {
                if !any_running && !self.running_program {
                    m.command(Command::RunProgram(Axes::All))?;
                    self.running_program = true;
                }
            }
            Action::FaultReset(axes) => {
                self.running_program = false;
                for i in axes {
                    m.command(Command::FaultReset(Axes::One(i)))?;
                }
            }
            Action::Enable => {
                m.command(Command::Enable(Axes::All))?;
                if self.enabled_once {
                    self.recoveries += 1;
                }
                self.enabled_once = true;
                self.running_program = false;
            }
            Action::Unhandled(what, reset) => {
                unhandled.push(what);
                for i in reset {
                    m.command(Command::FaultReset(Axes::One(i)))?;
                }
            }
        }
        Ok(unhandled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::master::telemetry::AxisTelemetry;

    fn telemetry(states: &[(State, bool)]) -> Telemetry {
        Telemetry {
            axes: states
                .iter()
                .map(|&(state, fault)| AxisTelemetry {
                    state: Some(state),
                    statusword: if fault { FAULT_BIT } else { 0 },
                    error_code: if fault { 0xFF86 } else { 0 },
                    ..AxisTelemetry::default()
                })
                .collect(),
            ..Telemetry::default()
        }
    }

    /// The tests' clock: time passes only when a test says so.
    struct Clock {
        now: Instant,
    }

    impl Clock {
        fn new() -> Self {
            Self {
                now: Instant::now(),
            }
        }
        fn advance(&mut self, ms: u64) {
            self.now += Duration::from_millis(ms);
        }
    }

    fn quick() -> Recovery {
        Recovery {
            settle: Duration::ZERO,
            reset_retry: Duration::from_millis(15),
            fault_clear_limit: Duration::from_millis(30),
            enable_limit: Duration::from_millis(30),
            ..Recovery::default()
        }
    }

    const SOD: State = State::SwitchOnDisabled;
    const OE: State = State::OperationEnabled;

    #[test]
    fn one_reset_per_faulted_axis_and_episode_then_enable_then_run() {
        let c = Clock::new();
        let mut r = quick();
        let faulted = telemetry(&[(State::Fault, true), (SOD, false)]);
        assert_eq!(
            r.next_at(c.now, &faulted, false),
            Action::FaultReset(vec![0])
        );
        // Still in Fault within the retry time: the master pulses bit 7; no second request.
        assert_eq!(r.next_at(c.now, &faulted, false), Action::None);
        let idle = telemetry(&[(SOD, false), (SOD, false)]);
        assert_eq!(r.next_at(c.now, &idle, false), Action::Enable);
        assert_eq!(r.next_at(c.now, &idle, false), Action::None);
        let enabled = telemetry(&[(OE, false), (OE, false)]);
        assert_eq!(r.next_at(c.now, &enabled, true), Action::RunProgram);
        // A new fault is a new episode: a new reset.
        let both = telemetry(&[(State::Fault, true), (State::Fault, true)]);
        assert_eq!(
            r.next_at(c.now, &both, false),
            Action::FaultReset(vec![0, 1])
        );
    }

    #[test]
    fn a_fault_during_the_enable_cancels_it_and_recovery_starts_again() {
        let mut c = Clock::new();
        let mut r = quick();
        let idle = telemetry(&[(SOD, false), (SOD, false)]);
        assert_eq!(r.next_at(c.now, &idle, false), Action::Enable);
        let faulted = telemetry(&[(State::Fault, true), (State::Fault, true)]);
        assert_eq!(
            r.next_at(c.now, &faulted, false),
            Action::FaultReset(vec![0, 1])
        );
        c.advance(10);
        assert_eq!(r.next_at(c.now, &idle, false), Action::Enable);
    }

    #[test]
    fn a_fault_that_stays_and_an_enable_that_never_comes_are_unhandled() {
        let mut c = Clock::new();
        let mut r = quick();
        let faulted = telemetry(&[(State::Fault, true), (SOD, false)]);
        assert_eq!(
            r.next_at(c.now, &faulted, false),
            Action::FaultReset(vec![0])
        );
        c.advance(20);
        // Still shown after the retry time: asked again.
        assert_eq!(
            r.next_at(c.now, &faulted, false),
            Action::FaultReset(vec![0])
        );
        c.advance(20);
        let Action::Unhandled(what, again) = r.next_at(c.now, &faulted, false) else {
            panic!("a fault that stays must be reported");
        };
        assert!(what.contains("axis 0") && what.contains("0xFF86"), "{what}");
        assert_eq!(again, vec![0]);

        let mut r = quick();
        let idle = telemetry(&[(SOD, false), (SOD, false)]);
        assert_eq!(r.next_at(c.now, &idle, false), Action::Enable);
        c.advance(40);
        let Action::Unhandled(what, _) = r.next_at(c.now, &idle, false) else {
            panic!("an enable that never comes must be reported");
        };
        assert!(what.contains("not enabled"), "{what}");
    }

    #[test]
    fn energised_axes_are_left_to_stop_first() {
        let c = Clock::new();
        let mut r = quick();
        let stopping = telemetry(&[(State::QuickStopActive, false), (SOD, false)]);
        assert_eq!(r.next_at(c.now, &stopping, false), Action::None);
    }
}
