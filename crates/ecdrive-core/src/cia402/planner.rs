//! The master-side transition planner: from the observed state to a requested [`Target`], one
//! controlword per cycle.
//!
//! Call [`Planner::next`] once per cycle with the statusword just received. It returns the
//! command to send and the progress. The planner never blocks and keeps no clock: every limit
//! is a number of cycles.
//!
//! # Paths
//!
//! | target | path |
//! |---|---|
//! | Operation enabled | Switch on disabled → Shutdown (2) → Switch on (3) → Enable operation (4) |
//! | Switched on | … → Shutdown (2) → Switch on (3); from Operation enabled: Disable operation (5) |
//! | Switch on disabled | Disable voltage (7, 9, 10) |
//! | Quick stop | Operation enabled → Quick stop (11); Ready to switch on / Switched on → Quick stop (7, 10), which ends in Switch on disabled |
//!
//! The planner walks only the standard transitions. Some drives also accept state-skipping
//! jumps ([`DriveCaps::state_skipping`], e.g. the MR-J4-TM takes Enable operation straight from
//! Switch on disabled), but that is optional behaviour, and a drive that implements only the
//! standard transitions must enable too: skipping would save two cycles and is never used.
//!
//! # Rules
//!
//! * **Not ready to switch on** and **Fault reaction active** are waited out (sending Disable
//!   voltage); the cycles count toward the timeout.
//! * **Quick stop active** is never cut short. With an option code that ends in Switch on
//!   disabled the planner keeps sending Quick stop until the drive makes transition 12 by itself.
//!   With a code that stays in Quick stop active it waits until the caller reports standstill and
//!   then leaves by transition 16 (Enable operation) where the drive has it, else by transition 12
//!   (Disable voltage), e.g. on the MR-J4-TM and BLV-R.
//! * **Faults** are never reset implicitly. In Fault the planner sends Disable voltage and reports
//!   [`PlannerError::Faulted`] until [`Planner::request_fault_reset`] is called; then it makes a
//!   rising edge on bit 7 (one cycle low, `fault_reset_hold_cycles` high, the same number low)
//!   and repeats it while the drive stays in Fault, until the timeout.
//! * **A fault cancels an energising target.** A fault seen while the target is Operation enabled
//!   or Switched on latches [`PlannerError::Faulted`] and replaces the target by Switch on
//!   disabled. After the reset the drive stays in Switch on disabled until the next
//!   [`Planner::set_target`].
//! * **Timeout**: if the observed state does not change for `timeout_cycles` cycles while the
//!   target is not reached, the planner fails with [`PlannerError::Timeout`], naming the state it
//!   is stuck in, the transition it did not take (the command sent), the statusword and the
//!   likely cause ([`StallCause`]).
//! * **Dropping out**: once Operation enabled or Switched on was reached, a later change to
//!   another (non-fault) state that the planner did not command, e.g. a quick stop from a drive
//!   input, latches [`PlannerError::LeftTarget`] and replaces the target by Quick stop (if the
//!   drive is in Quick stop active) or Switch on disabled: the planner does not re-enable on its
//!   own.
//! * **Latched failures** (timeout, invalid statusword, fault during enable, dropping out) are
//!   reported as [`Progress::Failed`] until [`Planner::set_target`] (timeouts also until
//!   [`Planner::request_fault_reset`], which starts a new attempt). While latched the planner
//!   still sends safe commands: what the target asks for if that does not energise the drive
//!   further (e.g. Disable voltage, Quick stop), else the command that keeps the current state;
//!   fault-reset edges only while a reset is requested.
//! * A statusword that decodes to no state makes the planner send Disable voltage if the fault
//!   bit is set, else repeat the last command (a transient glitch must not disable a running
//!   axis); it fails with [`PlannerError::InvalidStatusWord`] after `timeout_cycles`.
//!
//! # Cycle bound
//!
//! Take a drive that reacts to each command in the cycle it receives it and whose statusword
//! reaches the master `L` cycles later, that spends `init` cycles initialising and at most `ramp`
//! cycles in a quick-stop ramp or fault reaction, and that resets a cleared fault on the first
//! edge. Then every target is reached, or reported unreachable, within
//! `init + ramp + 5 × (L + 1) + 4` cycles. The longest paths have 5 observed transitions, e.g.
//! Fault reaction active → Fault → Switch on disabled → Ready to switch on → Switched on →
//! Operation enabled. (From a fault the caller first asks for Switch on disabled with a fault
//! reset and then for its target; the bound covers both together.) Each further reset edge a
//! drive needs costs `2 × fault_reset_hold_cycles` cycles. The property tests check the bound
//! against the [`device`](super::device) model for every start state, target, quick-stop code,
//! on drives with and without state skipping and transition 16, and `L` up to 3.

use core::fmt;
use core::time::Duration;

use super::bits::{ControlWord, StatusWord};
use super::caps::{DriveCaps, QuickStopEnd};
use super::command::Command;
use super::state::State;

/// The state the planner drives towards.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Target {
    /// Operation enabled (motor energised, following set-points).
    OperationEnabled,
    /// Switched on (power stage ready, motor not energised).
    SwitchedOn,
    /// Switch on disabled (power stage off). From Fault this needs a fault reset.
    SwitchOnDisabled,
    /// Quick stop: Quick stop active, or Switch on disabled once a quick stop has run.
    QuickStop,
}

impl Target {
    /// The target's name.
    pub const fn name(self) -> &'static str {
        match self {
            Target::OperationEnabled => "Operation enabled",
            Target::SwitchedOn => "Switched on",
            Target::SwitchOnDisabled => "Switch on disabled",
            Target::QuickStop => "Quick stop",
        }
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The likely reason a drive does not move on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum StallCause {
    /// The drive did not react to the command (no further clue in the statusword).
    NoResponse,
    /// The drive stays in Not ready to switch on: it has not finished its own initialisation
    /// (transition 1 is the drive's, not the master's).
    Initialising,
    /// Statusword bit 9 (remote) is 0 and the drive ignores the controlword then.
    RemoteOff,
    /// Statusword bit 4 (voltage enabled) is 0: no main/DC-bus power.
    NoMainVoltage,
    /// Fault reset edges were sent but the drive stays in Fault: the cause is still present or
    /// the fault cannot be reset.
    FaultPersists,
    /// Waiting for standstill before leaving Quick stop active; the caller never reported it.
    NotAtStandstill,
    /// The drive stays in Quick stop active although the configured option code ends in Switch
    /// on disabled: check 0x605A, or the quick-stop ramp is longer than the timeout.
    QuickStopHeld,
}

impl fmt::Display for StallCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StallCause::NoResponse => {
                "the drive does not react to the controlword; usual causes: a safety or enable \
                 input open (STO, forced stop), the drive under local or test-mode control, or \
                 the controlword not reaching it (check its RxPDO mapping)"
            }
            StallCause::Initialising => {
                "the drive has not finished its own initialisation (look at its display or alarm \
                 for a hardware or parameter fault)"
            }
            StallCause::RemoteOff => {
                "statusword bit 9 (remote) is 0, so the drive ignores the controlword"
            }
            StallCause::NoMainVoltage => {
                "statusword bit 4 (voltage enabled) is 0: main circuit (DC-bus) power may be off; \
                 some drives keep bit 4 at 0 until Switched on, so check the safety and enable \
                 inputs (STO, forced stop) too"
            }
            StallCause::FaultPersists => {
                "fault reset was sent but the fault is still present or cannot be reset"
            }
            StallCause::NotAtStandstill => {
                "waiting for standstill before leaving Quick stop active"
            }
            StallCause::QuickStopHeld => {
                "the drive stays in Quick stop active; check that 0x605A matches the configured \
                 option code and that the quick-stop ramp is shorter than the timeout"
            }
        })
    }
}

/// Why the planner cannot reach its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error, serde::Serialize)]
pub enum PlannerError {
    /// The drive stayed in one state too long.
    #[error(
        "drive stuck in {stuck_in} for {cycles} cycles on the way to {target}: it did not take \
         {}, statusword 0x{statusword:04X}; {cause}",
        transition_name(*stuck_in, *command)
    )]
    Timeout {
        /// The state it is stuck in.
        stuck_in: State,
        /// The target.
        target: Target,
        /// Cycles spent in that state.
        cycles: u32,
        /// The command the planner kept sending (the transition the drive did not make).
        command: Command,
        /// The last statusword (0x6041).
        statusword: u16,
        /// The likely cause.
        cause: StallCause,
    },
    /// The statusword matched no CiA 402 state for too long.
    #[error("statusword 0x{statusword:04X} (0x6041) matches no CiA 402 state for {cycles} cycles")]
    InvalidStatusWord {
        /// The last statusword.
        statusword: u16,
        /// Cycles it has been undecodable.
        cycles: u32,
    },
    /// The target makes no sense from this state.
    #[error("{target} cannot be reached from {from}: {why}")]
    Unreachable {
        /// Current state.
        from: State,
        /// The target.
        target: Target,
        /// Why.
        why: &'static str,
    },
    /// The drive is in Fault reaction active or Fault.
    #[error("drive is in {state} while heading for {target}; a fault reset is required")]
    Faulted {
        /// Fault reaction active or Fault.
        state: State,
        /// The target at the time.
        target: Target,
    },
    /// The drive left the reached target state without being told to.
    #[error("drive left {target} on its own and is now in {now}; not re-enabling automatically")]
    LeftTarget {
        /// The target that had been reached.
        target: Target,
        /// Where the drive went.
        now: State,
    },
}

/// How far the planner got.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Progress {
    /// Still on the way.
    InProgress,
    /// The drive is in the target state.
    Reached,
    /// The target cannot be reached (see the error).
    Failed(PlannerError),
}

/// One cycle's result: the command to send and the progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Step {
    /// Command for controlword bits 0–3 and 7. Merge it into a controlword with
    /// [`Command::apply`] to keep the mode-specific bits.
    pub command: Command,
    /// Progress towards the target.
    pub progress: Progress,
}

impl Step {
    /// The command as a controlword (mode-specific bits 0).
    pub const fn controlword(&self) -> ControlWord {
        self.command.controlword()
    }
}

/// Defaults of [`PlannerConfig::for_cycle_time`], in time units. **\[REC\]**: recommendations,
/// not vendor data, except where noted.
pub mod defaults {
    use core::time::Duration;

    /// How long bit 7 is held high for a fault reset: MR-J4-TM §5.1 note, "hold bit 7 = 1 for at
    /// least 10 ms" on an unreliable link (vendor fact).
    pub const FAULT_RESET_HOLD: Duration = Duration::from_millis(10);
    /// **\[REC\]** How long a drive may stay in one state before the planner gives up. Must cover
    /// the longest quick-stop ramp and fault reaction (MR-J4-TM 0x6085 allows up to 20 s; its
    /// default is 100 ms).
    pub const STALL_TIMEOUT: Duration = Duration::from_secs(5);
}

/// Planner settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PlannerConfig {
    /// Cycles the observed state may stay unchanged before [`PlannerError::Timeout`] (≥ 1).
    pub timeout_cycles: u32,
    /// Cycles bit 7 is held high per fault-reset edge, and held low between edges (≥ 1).
    pub fault_reset_hold_cycles: u32,
    /// The quick-stop option code (0x605A) the drive runs with; must be one the caps list.
    pub quick_stop_option: i16,
}

impl PlannerConfig {
    /// The [`defaults`] converted to cycles of length `cycle` (rounded up, at least 1), with the
    /// drive's default quick-stop option.
    pub fn for_cycle_time(caps: &DriveCaps, cycle: Duration) -> Self {
        Self {
            timeout_cycles: cycles_for(defaults::STALL_TIMEOUT, cycle),
            fault_reset_hold_cycles: cycles_for(defaults::FAULT_RESET_HOLD, cycle),
            quick_stop_option: caps.default_quick_stop_option.code,
        }
    }
}

/// `span / cycle`, rounded up, clamped to `1..=u32::MAX`; a zero cycle gives 1.
pub fn cycles_for(span: Duration, cycle: Duration) -> u32 {
    let c = cycle.as_nanos();
    if c == 0 {
        return 1;
    }
    let n = span.as_nanos().div_ceil(c);
    u32::try_from(n).unwrap_or(u32::MAX).max(1)
}

/// A [`PlannerConfig`] that does not fit the drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum PlannerConfigError {
    /// 0x605A value not in the drive's list.
    #[error("quick stop option code {code} (0x605A) is not supported by this drive")]
    UnsupportedQuickStopOption {
        /// The value given.
        code: i16,
    },
    /// A cycle count of 0.
    #[error("{what} must be at least 1 cycle")]
    ZeroCycles {
        /// Which setting.
        what: &'static str,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Pulse {
    /// No reset pulse running; the next one starts with one low cycle.
    Idle,
    /// Bit 7 high for this many more cycles.
    High(u32),
    /// Bit 7 low for this many more cycles, then high again.
    Low(u32),
}

/// The transition planner. See the [module documentation](self) for the rules.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Planner {
    transition_16: bool,
    quick_stop_end: QuickStopEnd,
    remote_gates: bool,
    timeout: u32,
    hold: u32,
    target: Target,
    reached: bool,
    reset_requested: bool,
    seen_fault: bool,
    pulse: Pulse,
    edges_sent: u32,
    observed: Option<Option<State>>,
    stall: u32,
    quick_stop_commanded: bool,
    latched: Option<PlannerError>,
    last_command: Command,
}

impl Planner {
    /// A planner for a drive with `caps`. Starts with target Switch on disabled.
    pub fn new(caps: &DriveCaps, config: PlannerConfig) -> Result<Self, PlannerConfigError> {
        let qs = caps.quick_stop_option(config.quick_stop_option).ok_or(
            PlannerConfigError::UnsupportedQuickStopOption {
                code: config.quick_stop_option,
            },
        )?;
        if config.timeout_cycles == 0 {
            return Err(PlannerConfigError::ZeroCycles {
                what: "timeout_cycles",
            });
        }
        if config.fault_reset_hold_cycles == 0 {
            return Err(PlannerConfigError::ZeroCycles {
                what: "fault_reset_hold_cycles",
            });
        }
        Ok(Self {
            transition_16: caps.transition_16,
            quick_stop_end: qs.end,
            remote_gates: caps.remote_gates_controlword,
            timeout: config.timeout_cycles,
            hold: config.fault_reset_hold_cycles,
            target: Target::SwitchOnDisabled,
            reached: false,
            reset_requested: false,
            seen_fault: false,
            pulse: Pulse::Idle,
            edges_sent: 0,
            observed: None,
            stall: 0,
            quick_stop_commanded: false,
            latched: None,
            last_command: Command::DisableVoltage,
        })
    }

    /// Set a new target. Clears a latched failure and restarts the timeout.
    pub fn set_target(&mut self, target: Target) {
        self.target = target;
        self.reached = false;
        self.latched = None;
        self.stall = 0;
        self.quick_stop_commanded = false;
    }

    /// The current target.
    pub const fn target(&self) -> Target {
        self.target
    }

    /// The latched failure, if any.
    pub const fn latched_error(&self) -> Option<PlannerError> {
        self.latched
    }

    /// Allow a fault reset: while the drive is in Fault the planner sends rising edges on bit 7.
    /// The request ends when the drive leaves Fault (or at a timeout). Restarts the timeout and
    /// clears a latched timeout or invalid-statusword failure (a new attempt), but not a latched
    /// [`PlannerError::Faulted`] or [`PlannerError::LeftTarget`]: those need
    /// [`Planner::set_target`].
    ///
    /// The request is **ignored** unless the last statusword given to [`Planner::next`] showed a
    /// fault (bit 3, Fault reaction active or Fault): a reset asked for without a visible fault
    /// must not clear a fault that appears later. Returns whether the request was taken.
    pub fn request_fault_reset(&mut self) -> bool {
        if !self.seen_fault {
            return false;
        }
        self.reset_requested = true;
        self.pulse = Pulse::Idle;
        self.edges_sent = 0;
        self.stall = 0;
        if matches!(
            self.latched,
            Some(PlannerError::Timeout { .. } | PlannerError::InvalidStatusWord { .. })
        ) {
            self.latched = None;
        }
        true
    }

    /// A fault reset has been requested and the drive has not left Fault yet.
    pub const fn fault_reset_pending(&self) -> bool {
        self.reset_requested
    }

    /// One cycle: the statusword just received and whether the axis is at standstill (used only
    /// to leave Quick stop active with a code that stays there).
    pub fn next(&mut self, statusword: StatusWord, standstill: bool) -> Step {
        let state = statusword.state();
        if self.observed == Some(state) {
            self.stall = self.stall.saturating_add(1);
        } else {
            self.observed = Some(state);
            self.stall = 0;
        }
        let faulted = state.is_some_and(State::is_fault);
        self.seen_fault = faulted || statusword.contains(StatusWord::FAULT);

        if let Some(s) = state {
            if !s.is_fault() && self.reset_requested {
                self.reset_requested = false;
                self.pulse = Pulse::Idle;
                self.edges_sent = 0;
            }
            if faulted && matches!(self.target, Target::OperationEnabled | Target::SwitchedOn) {
                // A fault cancels the intent to energise; it never comes back on its own.
                self.latched = Some(PlannerError::Faulted {
                    state: s,
                    target: self.target,
                });
                self.target = Target::SwitchOnDisabled;
                self.reached = false;
            } else if self.reached && !faulted && !self.in_target(s) {
                self.latched = Some(PlannerError::LeftTarget {
                    target: self.target,
                    now: s,
                });
                self.target = if s == State::QuickStopActive {
                    Target::QuickStop
                } else {
                    Target::SwitchOnDisabled
                };
                self.reached = false;
            }
        }

        let (command, progress) = match self.latched {
            Some(_) => self.latched_step(state, statusword, standstill),
            None => self.normal(state, statusword, standstill),
        };
        if command == Command::QuickStop {
            self.quick_stop_commanded = true;
        }
        if progress == Progress::Reached {
            self.reached = true;
        }
        self.last_command = command;
        Step { command, progress }
    }

    fn in_target(&self, s: State) -> bool {
        match self.target {
            Target::OperationEnabled => s == State::OperationEnabled,
            Target::SwitchedOn => s == State::SwitchedOn,
            // Leaving these is never dangerous; the planner just drives back.
            Target::SwitchOnDisabled | Target::QuickStop => true,
        }
    }

    fn normal(
        &mut self,
        state: Option<State>,
        sw: StatusWord,
        standstill: bool,
    ) -> (Command, Progress) {
        let Some(s) = state else {
            let cmd = if sw.contains(StatusWord::FAULT) {
                Command::DisableVoltage
            } else {
                self.last_command
            };
            if self.stall >= self.timeout {
                let err = PlannerError::InvalidStatusWord {
                    statusword: sw.raw(),
                    cycles: self.stall,
                };
                self.latched = Some(err);
                return (cmd, Progress::Failed(err));
            }
            return (cmd, Progress::InProgress);
        };
        let (cmd, progress, cause) = match s {
            State::FaultReactionActive => {
                if self.reset_requested {
                    (
                        Command::DisableVoltage,
                        Progress::InProgress,
                        StallCause::NoResponse,
                    )
                } else {
                    (
                        Command::DisableVoltage,
                        self.faulted(s),
                        StallCause::NoResponse,
                    )
                }
            }
            State::Fault => {
                if self.reset_requested {
                    let cause = if self.edges_sent > 0 {
                        StallCause::FaultPersists
                    } else {
                        StallCause::NoResponse
                    };
                    (self.pulse_command(), Progress::InProgress, cause)
                } else {
                    (
                        Command::DisableVoltage,
                        self.faulted(s),
                        StallCause::NoResponse,
                    )
                }
            }
            _ => self.next_command(s, sw, standstill),
        };
        if progress == Progress::InProgress && self.stall >= self.timeout {
            let err = PlannerError::Timeout {
                stuck_in: s,
                target: self.target,
                cycles: self.stall,
                command: if s == State::Fault {
                    Command::FaultReset
                } else {
                    cmd
                },
                statusword: sw.raw(),
                cause,
            };
            self.latched = Some(err);
            if s == State::Fault {
                // Stop pulsing; a new request_fault_reset() starts a new attempt.
                self.reset_requested = false;
                self.pulse = Pulse::Idle;
            }
            let cmd = self.latched_command(state, sw, standstill);
            return (cmd, Progress::Failed(err));
        }
        (cmd, progress)
    }

    fn latched_step(
        &mut self,
        state: Option<State>,
        sw: StatusWord,
        standstill: bool,
    ) -> (Command, Progress) {
        if state == Some(State::Fault) && self.reset_requested && self.stall >= self.timeout {
            self.latched = Some(PlannerError::Timeout {
                stuck_in: State::Fault,
                target: self.target,
                cycles: self.stall,
                command: Command::FaultReset,
                statusword: sw.raw(),
                cause: if self.edges_sent > 0 {
                    StallCause::FaultPersists
                } else {
                    StallCause::NoResponse
                },
            });
            self.reset_requested = false;
            self.pulse = Pulse::Idle;
        }
        let cmd = self.latched_command(state, sw, standstill);
        match self.latched {
            Some(err) => (cmd, Progress::Failed(err)),
            None => (cmd, Progress::InProgress),
        }
    }

    fn faulted(&self, s: State) -> Progress {
        Progress::Failed(PlannerError::Faulted {
            state: s,
            target: self.target,
        })
    }

    /// The command while a failure is latched: never energise further.
    fn latched_command(
        &mut self,
        state: Option<State>,
        sw: StatusWord,
        standstill: bool,
    ) -> Command {
        match state {
            None => {
                if sw.contains(StatusWord::FAULT) {
                    Command::DisableVoltage
                } else {
                    self.last_command
                }
            }
            Some(State::Fault) if self.reset_requested => self.pulse_command(),
            Some(s) if s.is_fault() || s == State::NotReadyToSwitchOn => Command::DisableVoltage,
            Some(s) => {
                let (cmd, _, _) = self.next_command(s, sw, standstill);
                if raises(s, cmd) { hold_command(s) } else { cmd }
            }
        }
    }

    fn pulse_command(&mut self) -> Command {
        match self.pulse {
            Pulse::Idle => {
                self.pulse = Pulse::High(self.hold);
                Command::DisableVoltage
            }
            Pulse::High(n) => {
                if n == self.hold {
                    self.edges_sent = self.edges_sent.saturating_add(1);
                }
                self.pulse = if n <= 1 {
                    Pulse::Low(self.hold)
                } else {
                    Pulse::High(n - 1)
                };
                Command::FaultReset
            }
            Pulse::Low(n) => {
                self.pulse = if n <= 1 {
                    Pulse::High(self.hold)
                } else {
                    Pulse::Low(n - 1)
                };
                Command::DisableVoltage
            }
        }
    }

    /// The next command from a non-fault state.
    fn next_command(
        &self,
        s: State,
        sw: StatusWord,
        standstill: bool,
    ) -> (Command, Progress, StallCause) {
        use Command as C;
        use Progress::{InProgress, Reached};
        use State::*;
        let remote_off = self.remote_gates && !sw.contains(StatusWord::REMOTE);
        let gate = if remote_off {
            StallCause::RemoteOff
        } else {
            StallCause::NoResponse
        };
        // Without main power (statusword bit 4 clear) a drive refuses the transitions towards
        // Operation enabled (the BDHDE already transition 2, "bus voltage must be switched on").
        let up = if remote_off {
            StallCause::RemoteOff
        } else if !sw.contains(StatusWord::VOLTAGE_ENABLED) {
            StallCause::NoMainVoltage
        } else {
            StallCause::NoResponse
        };
        let wait = (C::DisableVoltage, InProgress, StallCause::NoResponse);
        let init = (C::DisableVoltage, InProgress, StallCause::Initialising);
        match self.target {
            Target::OperationEnabled => match s {
                NotReadyToSwitchOn => init,
                SwitchOnDisabled => (C::Shutdown, InProgress, up),
                ReadyToSwitchOn => (C::SwitchOn, InProgress, up),
                SwitchedOn => (C::EnableOperation, InProgress, up),
                OperationEnabled => (C::EnableOperation, Reached, StallCause::NoResponse),
                QuickStopActive => self.leave_quick_stop(standstill, gate),
                FaultReactionActive | Fault => wait,
            },
            Target::SwitchedOn => match s {
                NotReadyToSwitchOn => init,
                SwitchOnDisabled => (C::Shutdown, InProgress, up),
                ReadyToSwitchOn => (C::SwitchOn, InProgress, up),
                SwitchedOn => (C::SwitchOn, Reached, StallCause::NoResponse),
                OperationEnabled => (C::DisableOperation, InProgress, gate),
                QuickStopActive => self.leave_quick_stop(standstill, gate),
                FaultReactionActive | Fault => wait,
            },
            Target::SwitchOnDisabled => match s {
                SwitchOnDisabled => (C::DisableVoltage, Reached, StallCause::NoResponse),
                ReadyToSwitchOn | SwitchedOn | OperationEnabled => {
                    (C::DisableVoltage, InProgress, gate)
                }
                QuickStopActive => match self.quick_stop_end {
                    QuickStopEnd::SwitchOnDisabled => {
                        (C::QuickStop, InProgress, StallCause::QuickStopHeld)
                    }
                    QuickStopEnd::StayInQuickStopActive if !standstill => {
                        (C::QuickStop, InProgress, StallCause::NotAtStandstill)
                    }
                    QuickStopEnd::StayInQuickStopActive => (C::DisableVoltage, InProgress, gate),
                },
                NotReadyToSwitchOn | FaultReactionActive | Fault => wait,
            },
            Target::QuickStop => match s {
                NotReadyToSwitchOn => wait,
                SwitchOnDisabled if self.quick_stop_commanded => {
                    (C::QuickStop, Reached, StallCause::NoResponse)
                }
                SwitchOnDisabled => (
                    C::DisableVoltage,
                    Progress::Failed(PlannerError::Unreachable {
                        from: s,
                        target: self.target,
                        why: "the drive is disabled: there is no motion to stop",
                    }),
                    StallCause::NoResponse,
                ),
                // Quick stop acts even with remote = 0 (BLV-R §6.1).
                ReadyToSwitchOn | SwitchedOn => (C::QuickStop, InProgress, StallCause::NoResponse),
                OperationEnabled => (C::QuickStop, InProgress, StallCause::NoResponse),
                QuickStopActive => (C::QuickStop, Reached, StallCause::NoResponse),
                FaultReactionActive | Fault => wait,
            },
        }
    }

    fn leave_quick_stop(
        &self,
        standstill: bool,
        gate: StallCause,
    ) -> (Command, Progress, StallCause) {
        match self.quick_stop_end {
            QuickStopEnd::SwitchOnDisabled => (
                Command::QuickStop,
                Progress::InProgress,
                StallCause::QuickStopHeld,
            ),
            QuickStopEnd::StayInQuickStopActive if !standstill => (
                Command::QuickStop,
                Progress::InProgress,
                StallCause::NotAtStandstill,
            ),
            QuickStopEnd::StayInQuickStopActive if self.transition_16 => {
                (Command::EnableOperation, Progress::InProgress, gate)
            }
            QuickStopEnd::StayInQuickStopActive => {
                (Command::DisableVoltage, Progress::InProgress, gate)
            }
        }
    }
}

/// The transition `cmd` asks of a drive in `s`, in words: `transition 2 (Shutdown, controlword
/// 0x0006)`.
fn transition_name(s: State, cmd: Command) -> String {
    use Command as C;
    use State::*;
    if s == NotReadyToSwitchOn {
        return format!(
            "transition 1, the drive's own initialisation (the master waits, sending controlword \
             0x{:04X})",
            cmd.bits()
        );
    }
    let number = match (s, cmd) {
        (SwitchOnDisabled, C::Shutdown) => Some(2),
        (ReadyToSwitchOn, C::SwitchOn) => Some(3),
        (SwitchedOn, C::EnableOperation) => Some(4),
        (OperationEnabled, C::DisableOperation) => Some(5),
        (SwitchedOn | OperationEnabled, C::Shutdown) => Some(if s == SwitchedOn { 6 } else { 8 }),
        (ReadyToSwitchOn, C::DisableVoltage | C::QuickStop) => Some(7),
        (OperationEnabled, C::DisableVoltage) => Some(9),
        (SwitchedOn, C::DisableVoltage | C::QuickStop) => Some(10),
        (OperationEnabled, C::QuickStop) => Some(11),
        (QuickStopActive, C::DisableVoltage) => Some(12),
        (Fault, C::FaultReset) => Some(15),
        (QuickStopActive, C::EnableOperation) => Some(16),
        _ => None,
    };
    let name = match cmd {
        C::Shutdown => "Shutdown",
        C::SwitchOn => "Switch on",
        C::EnableOperation => "Enable operation",
        C::DisableVoltage => "Disable voltage",
        C::QuickStop => "Quick stop",
        C::DisableOperation => "Disable operation",
        C::FaultReset => "Fault reset",
    };
    match number {
        Some(n) => format!("transition {n} ({name}, controlword 0x{:04X})", cmd.bits()),
        None => format!("{name} (controlword 0x{:04X})", cmd.bits()),
    }
}

/// Whether `cmd` would move the drive from `s` towards a more energised state.
fn raises(s: State, cmd: Command) -> bool {
    use Command as C;
    match s {
        State::SwitchOnDisabled => {
            matches!(
                cmd,
                C::Shutdown | C::SwitchOn | C::DisableOperation | C::EnableOperation
            )
        }
        State::ReadyToSwitchOn => {
            matches!(cmd, C::SwitchOn | C::DisableOperation | C::EnableOperation)
        }
        State::SwitchedOn | State::QuickStopActive => cmd == C::EnableOperation,
        _ => false,
    }
}

/// The command that keeps the drive in `s`.
fn hold_command(s: State) -> Command {
    match s {
        State::ReadyToSwitchOn => Command::Shutdown,
        State::SwitchedOn => Command::SwitchOn,
        State::OperationEnabled => Command::EnableOperation,
        State::QuickStopActive => Command::QuickStop,
        State::NotReadyToSwitchOn
        | State::SwitchOnDisabled
        | State::FaultReactionActive
        | State::Fault => Command::DisableVoltage,
    }
}
