//! The per-cycle axis engine.
//!
//! An [`Axis`] sits between the process image and the application. Once per cycle the master
//! calls [`Axis::step`] with the drive's [`Feedback`] and writes the returned [`Output`] into the
//! outputs. Between steps the application makes requests (enable, disable, quick stop, fault
//! reset, mode change) and gives set-points. `step` never blocks, allocates or panics, whatever
//! the feedback holds.
//!
//! # Enabling, disabling, faults
//!
//! Requests set the [`Planner`] target (enable → Operation enabled, disable → Switch on disabled,
//! quick stop → Quick stop). A fault — statusword bit 3, or the state Fault reaction active /
//! Fault — **drops the enable request at once**: the engine reports [`Event::Fault`] with the
//! decoded 0x603F, sends Disable voltage, and never enables again on its own. Enabling again takes
//! [`Axis::request_fault_reset`], then (once [`Event::FaultCleared`] came)
//! [`Axis::request_enable`]; `request_enable` is refused while the fault is present. Likewise a
//! drive that leaves Operation enabled on its own (e.g. a quick-stop input) drops the enable
//! request ([`Event::PlannerFailed`] with [`PlannerError::LeftTarget`]).
//!
//! # Set-points
//!
//! The engine keeps one commanded value per target object (0x607A position, 0x60FF velocity,
//! 0x6071 torque) and writes all three every cycle:
//! * the field of the active mode carries the application's set-point while the axis is
//!   *streaming* (Operation enabled, no mode switch pending, 0x6061 equal to the active mode if
//!   mapped, no fault); without a new set-point the last one is held;
//! * every other field, and every field while not in Operation enabled, **tracks the actual
//!   value**: position = actual position, velocity = actual velocity if its magnitude exceeds the
//!   standstill threshold else 0, torque = actual torque in Operation enabled (0 if not
//!   mapped) and 0 in every other state (the torque a drive reports in Quick stop active or
//!   Fault reaction active is its own braking, not a value to go on with). So enabling, and
//!   starting a new mode, begins exactly where the axis is: no jump.
//!
//! Set-points given when they cannot apply are refused with an [`AxisError`] (not streaming, or a
//! set-point kind the active mode does not use).
//!
//! # Mode switching
//!
//! [`Axis::request_mode`] checks the mode against [`DriveCaps::supported_modes`] (0x6502). Then:
//! 1. If the new mode is a position mode ([`DriveCaps::is_position_mode`]), the old one is not
//!    and the axis turns (a position mode starts from the actual position: entered at speed it
//!    would stop the axis within a cycle, at whatever torque the drive has), or if
//!    [`DriveCaps::position_mode_switch_needs_zero_speed`] and the old or the new mode is a
//!    position mode, the engine first **brings the axis to standstill** (phase
//!    [`ModeSwitchPhase::Stopping`]): in csp it ramps the per-cycle position increment down to 0,
//!    in csv it ramps the target velocity to 0, in cst/cstca the target torque to 0, each in
//!    [`StopRampConfig::cycles`] cycles (linear), in pv the target velocity likewise (the drive
//!    follows by its own deceleration); in every other mode it sets Halt (bit 8) so the
//!    drive stops by 0x605D. It waits for standstill (the drive's zero-speed flag if given,
//!    together with the velocity threshold where the velocity is known, since a drive may call
//!    tens of r/min zero; else the velocity or position-change threshold; for
//!    [`StandstillConfig::cycles`] cycles). Only then does it write 0x6060. The phase fails after
//!    [`AxisConfig::mode_switch_timeout_cycles`] without progress: while the actual speed keeps
//!    falling (a drive braking by its own deceleration in pv) the axis is on its way.
//!
//!    A torque set-point of 0 only lets the motor coast, so an axis that turns in a torque
//!    mode (cst, cstca, tq) is first switched to a velocity mode the drive supports (csv where it
//!    has it, the master setting the deceleration; else pv; no zero-speed rule applies between
//!    those) and ramped to 0 there.
//!    The phase reads [`ModeSwitchPhase::Stopping`] throughout, and the switch's `from` is that
//!    velocity mode from then on. A drive with no such mode gets the torque ramp and coasts.
//! 2. It writes the new mode to 0x6060 ([`ModeSwitchPhase::Requested`]). Until 0x6061 shows the
//!    new mode it **holds the old mode's last set-point** and the new mode's field keeps tracking
//!    the actual value, so both modes' command values are valid whichever the drive uses (MR-J4-TM
//!    §5.4.2). Mode-specific controlword bits are 0 meanwhile (the drive ignores them anyway).
//! 3. When 0x6061 confirms, the new mode's set-point starts from the tracked actual value and the
//!    application may stream again ([`Event::ModeSwitched`]). Without 0x6061 in the feedback the
//!    switch counts as confirmed at the next step (map 0x6061 for drives that switch slowly).
//!
//! If either phase takes longer than [`AxisConfig::mode_switch_timeout_cycles`] the switch is
//! abandoned ([`Event::ModeSwitchFailed`]): 0x6060 goes back to the old mode, whose held
//! set-point stays in force.

use core::fmt;
use core::time::Duration;

use super::bits::{ControlWord, StatusWord};
use super::caps::DriveCaps;
use super::error_code::{ErrorCode, ErrorDescription};
use super::mode::{OperationMode, SetPointKind};
use super::planner::{
    Planner, PlannerConfig, PlannerConfigError, PlannerError, Progress, Target, cycles_for,
};
use super::state::State;

/// What the drive reported this cycle. Fields the process image does not map are `None`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Feedback {
    /// 0x6041 Statusword.
    pub statusword: StatusWord,
    /// 0x6061 Modes of operation display, if mapped.
    pub mode_display: Option<OperationMode>,
    /// 0x6064 Position actual value.
    pub position: Option<i32>,
    /// 0x606C Velocity actual value.
    pub velocity: Option<i32>,
    /// 0x6077 Torque actual value.
    pub torque: Option<i16>,
    /// 0x603F Error code.
    pub error_code: Option<ErrorCode>,
    /// A drive-reported zero-speed flag (e.g. MR-J4-TM 0x2D12 bit 3 S_ZSP), if mapped.
    pub zero_speed: Option<bool>,
}

impl Feedback {
    /// Only a statusword; every optional field `None`.
    pub const fn new(statusword: StatusWord) -> Self {
        Self {
            statusword,
            mode_display: None,
            position: None,
            velocity: None,
            torque: None,
            error_code: None,
            zero_speed: None,
        }
    }
}

/// What to write to the drive this cycle. The master writes the fields its PDO mapping contains.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Output {
    /// 0x6040 Controlword.
    pub controlword: ControlWord,
    /// 0x6060 Modes of operation.
    pub mode: OperationMode,
    /// 0x607A Target position.
    pub target_position: i32,
    /// 0x60FF Target velocity.
    pub target_velocity: i32,
    /// 0x6071 Target torque.
    pub target_torque: i16,
    /// 0x60B1 Velocity offset (0 unless streaming).
    pub velocity_offset: i32,
    /// 0x60B2 Torque offset (0 unless streaming).
    pub torque_offset: i16,
}

/// How standstill is detected. Sources in order of preference: the drive's zero-speed flag
/// (with the velocity threshold too where the velocity actual value is known: the flag may mean
/// "below tens of r/min", the MR-J4-TM's S_ZSP below [Pr. PC07] = 50 r/min), the velocity
/// actual value, the change of the actual position per cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StandstillConfig {
    /// |velocity actual| at or below this counts as stopped (drive velocity units).
    pub velocity: u32,
    /// |position change per cycle| at or below this counts as stopped (position units); used
    /// only without velocity feedback.
    pub position_delta: u32,
    /// Consecutive cycles the condition must hold (at least 1 is used).
    pub cycles: u32,
}

/// The engine's own stop ramp before a zero-speed mode switch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StopRampConfig {
    /// Length of the linear ramp to zero, in cycles (at least 1 is used).
    pub cycles: u32,
}

/// Axis settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AxisConfig {
    /// The planner's settings.
    pub planner: PlannerConfig,
    /// The mode written to 0x6060 from the first cycle.
    pub initial_mode: OperationMode,
    /// Cycles each mode-switch phase (stopping, waiting for 0x6061) may take (≥ 1).
    pub mode_switch_timeout_cycles: u32,
    /// Standstill detection.
    pub standstill: StandstillConfig,
    /// Stop ramp before a zero-speed mode switch.
    pub stop_ramp: StopRampConfig,
}

/// Time-based defaults of [`AxisConfig::for_cycle_time`]. **\[REC\]**: our choice, not vendor data.
pub mod axis_defaults {
    use core::time::Duration;

    /// **\[REC\]** Stop ramp before a zero-speed mode switch.
    pub const STOP_RAMP: Duration = Duration::from_millis(200);
    /// **\[REC\]** Time allowed for each mode-switch phase.
    pub const MODE_SWITCH_TIMEOUT: Duration = Duration::from_secs(2);
    /// **\[REC\]** How long the standstill condition must hold.
    pub const STANDSTILL_TIME: Duration = Duration::from_millis(3);
}

impl AxisConfig {
    /// Defaults for a cycle of length `cycle`: [`PlannerConfig::for_cycle_time`] and
    /// [`axis_defaults`]; standstill thresholds 0 (exactly zero velocity / no position change —
    /// set them to the drive's noise level, or map a zero-speed flag).
    pub fn for_cycle_time(caps: &DriveCaps, cycle: Duration, initial_mode: OperationMode) -> Self {
        Self {
            planner: PlannerConfig::for_cycle_time(caps, cycle),
            initial_mode,
            mode_switch_timeout_cycles: cycles_for(axis_defaults::MODE_SWITCH_TIMEOUT, cycle),
            standstill: StandstillConfig {
                velocity: 0,
                position_delta: 0,
                cycles: cycles_for(axis_defaults::STANDSTILL_TIME, cycle),
            },
            stop_ramp: StopRampConfig {
                cycles: cycles_for(axis_defaults::STOP_RAMP, cycle),
            },
        }
    }
}

/// The axis phase, for status displays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Phase {
    /// Switch on disabled / switched on as requested.
    Disabled,
    /// On the way to Operation enabled.
    Enabling,
    /// Operation enabled.
    Enabled,
    /// On the way to a disabled state.
    Disabling,
    /// Quick stop commanded, not yet in Quick stop active / done.
    QuickStopping,
    /// Quick stop done.
    QuickStopped,
    /// The drive has a fault; no reset requested.
    Faulted,
    /// Fault reset in progress.
    ResettingFault,
    /// The planner failed (see [`AxisStatus::planner_error`]).
    Failed,
}

impl fmt::Display for Phase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Phase::Disabled => "disabled",
            Phase::Enabling => "enabling",
            Phase::Enabled => "enabled",
            Phase::Disabling => "disabling",
            Phase::QuickStopping => "quick stopping",
            Phase::QuickStopped => "quick stopped",
            Phase::Faulted => "faulted",
            Phase::ResettingFault => "resetting fault",
            Phase::Failed => "failed",
        })
    }
}

/// Where a mode switch is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModeSwitchPhase {
    /// No switch pending.
    Idle,
    /// Bringing the axis to standstill before writing 0x6060.
    Stopping {
        /// The requested mode.
        to: OperationMode,
    },
    /// 0x6060 written; waiting for 0x6061.
    Requested {
        /// The requested mode.
        to: OperationMode,
    },
}

/// Why a mode switch was abandoned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ModeSwitchFailure {
    /// The axis did not reach standstill.
    NoStandstill,
    /// 0x6061 did not show the new mode.
    NotConfirmed {
        /// What 0x6061 showed last.
        displayed: Option<OperationMode>,
    },
    /// A fault occurred while stopping.
    Fault,
}

/// A failed mode switch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error, serde::Serialize)]
#[error("mode switch {from} -> {to} abandoned after {cycles} cycles: {}", failure_text(.reason))]
pub struct ModeSwitchError {
    /// The mode before.
    pub from: OperationMode,
    /// The requested mode.
    pub to: OperationMode,
    /// Why.
    pub reason: ModeSwitchFailure,
    /// Cycles spent.
    pub cycles: u32,
}

fn failure_text(r: &ModeSwitchFailure) -> &'static str {
    match r {
        ModeSwitchFailure::NoStandstill => {
            "the axis did not reach zero speed, which a switch into a position mode needs (and \
             some drives require to switch to or from one)"
        }
        ModeSwitchFailure::NotConfirmed { .. } => {
            "0x6061 (modes of operation display) never showed the requested mode"
        }
        ModeSwitchFailure::Fault => "a fault occurred while stopping",
    }
}

/// Something that happened in a step. Read with [`Axis::poll_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Event {
    /// The decoded state changed (`None` = statusword matches no state).
    StateChanged {
        /// Before.
        from: Option<State>,
        /// After.
        to: Option<State>,
    },
    /// The planner reached its target.
    TargetReached(Target),
    /// The planner failed (timeout, unreachable, fault, drop-out).
    PlannerFailed(PlannerError),
    /// A fault appeared; the enable request was dropped.
    Fault {
        /// The state (Fault reaction active / Fault, or `None` if only bit 3 says so).
        state: Option<State>,
        /// 0x603F decoded, if the feedback carries it.
        error: Option<ErrorDescription>,
    },
    /// The fault is gone (after a reset, or the drive cleared it).
    FaultCleared,
    /// Statusword bit 7 changed.
    WarningChanged(bool),
    /// 0x6061 confirmed a new mode; set-points may stream.
    ModeSwitched {
        /// Before.
        from: OperationMode,
        /// After.
        to: OperationMode,
    },
    /// A mode switch was abandoned.
    ModeSwitchFailed(ModeSwitchError),
    /// 0x6061 shows another mode than the active one outside a switch; streaming paused.
    ModeDisplayMismatch {
        /// The active mode.
        expected: OperationMode,
        /// What 0x6061 shows.
        displayed: OperationMode,
    },
}

/// A request the engine refuses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum AxisError {
    /// Mode not in 0x6502.
    #[error("mode {mode} is not supported by the drive (0x6502 = 0x{supported:08X})")]
    ModeNotSupported {
        /// The mode.
        mode: OperationMode,
        /// The raw 0x6502 value.
        supported: u32,
    },
    /// Another mode switch is pending.
    #[error("a switch to mode {to} is still in progress")]
    ModeSwitchInProgress {
        /// The pending mode.
        to: OperationMode,
    },
    /// The drive has a fault; reset it first.
    #[error("the drive has a fault (0x603F = {}); request a fault reset first", code_text(*.error_code))]
    Faulted {
        /// 0x603F, if known.
        error_code: Option<ErrorCode>,
    },
    /// A set-point while the axis is not streaming.
    #[error("set-point refused: the axis is {phase} (state {}), not streaming", state_text(*.state))]
    NotStreaming {
        /// The state.
        state: Option<State>,
        /// The phase.
        phase: Phase,
    },
    /// A set-point the active mode does not use.
    #[error("a {kind} set-point does not apply in mode {mode}")]
    WrongSetPoint {
        /// The set-point given.
        kind: SetPointKind,
        /// The active mode.
        mode: OperationMode,
    },
    /// The planner configuration does not fit the drive.
    #[error(transparent)]
    PlannerConfig(#[from] PlannerConfigError),
    /// Another configuration value is invalid.
    #[error("invalid axis configuration: {what}")]
    InvalidConfig {
        /// What.
        what: &'static str,
    },
}

fn code_text(c: Option<ErrorCode>) -> ErrorCodeText {
    ErrorCodeText(c)
}

struct ErrorCodeText(Option<ErrorCode>);

impl fmt::Display for ErrorCodeText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(c) => write!(f, "{c}"),
            None => f.write_str("unknown"),
        }
    }
}

fn state_text(s: Option<State>) -> &'static str {
    match s {
        Some(s) => s.name(),
        None => "undecodable",
    }
}

/// A snapshot of the axis, cheap to copy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AxisStatus {
    /// Steps done.
    pub cycle: u64,
    /// The last statusword.
    pub statusword: StatusWord,
    /// Its decoded state.
    pub state: Option<State>,
    /// The phase.
    pub phase: Phase,
    /// The planner target.
    pub target: Target,
    /// The mode set-points are streamed for (confirmed by 0x6061).
    pub active_mode: OperationMode,
    /// The value written to 0x6060.
    pub commanded_mode: OperationMode,
    /// The last 0x6061, if mapped.
    pub displayed_mode: Option<OperationMode>,
    /// Mode-switch progress.
    pub mode_switch: ModeSwitchPhase,
    /// Set-points are accepted now.
    pub streaming: bool,
    /// At standstill by the configured rule.
    pub standstill: bool,
    /// A fault is present.
    pub fault: bool,
    /// The decoded 0x603F of the present or last fault.
    pub error: Option<ErrorDescription>,
    /// Statusword bit 7.
    pub warning: bool,
    /// The planner's current failure.
    pub planner_error: Option<PlannerError>,
    /// The last abandoned mode switch.
    pub mode_switch_error: Option<ModeSwitchError>,
    /// Events dropped because the queue was full.
    pub events_lost: u32,
}

const EVENT_CAPACITY: usize = 32;

#[derive(Debug, Clone)]
struct EventQueue {
    buf: [Option<Event>; EVENT_CAPACITY],
    head: usize,
    len: usize,
    lost: u32,
}

impl EventQueue {
    const fn new() -> Self {
        Self {
            buf: [None; EVENT_CAPACITY],
            head: 0,
            len: 0,
            lost: 0,
        }
    }

    // Events are rare (a state change, a fault): out of line, so the steady cycle's code stays
    // compact (it runs cold from the cache after each sleep).
    #[cold]
    #[inline(never)]
    fn push(&mut self, e: Event) {
        if self.len == EVENT_CAPACITY {
            // Drop the oldest.
            self.head = (self.head + 1) % EVENT_CAPACITY;
            self.len -= 1;
            self.lost = self.lost.saturating_add(1);
        }
        let idx = (self.head + self.len) % EVENT_CAPACITY;
        if let Some(slot) = self.buf.get_mut(idx) {
            *slot = Some(e);
            self.len += 1;
        }
    }

    fn pop(&mut self) -> Option<Event> {
        if self.len == 0 {
            return None;
        }
        let e = self.buf.get_mut(self.head).and_then(Option::take);
        self.head = (self.head + 1) % EVENT_CAPACITY;
        self.len -= 1;
        e
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ModeSwitch {
    Idle,
    /// A turning torque-mode axis on its way to a position mode: 0x6060 = `via` (a velocity
    /// mode) first, so the axis can be ramped to zero speed.
    Braking {
        via: OperationMode,
        to: OperationMode,
        cycles: u32,
    },
    Stopping {
        to: OperationMode,
        /// Cycles since the phase began or the axis last slowed down (the phase's timeout
        /// counts cycles without progress).
        cycles: u32,
        /// The lowest |velocity actual| seen in the phase (`u32::MAX` before any).
        slowest: u32,
        position_step: u32,
        velocity_step: u32,
        torque_step: u32,
    },
    Requested {
        from: OperationMode,
        to: OperationMode,
        cycles: u32,
    },
}

/// The per-cycle CiA 402 axis engine. See the [module documentation](self).
#[derive(Debug, Clone)]
pub struct Axis {
    caps: DriveCaps,
    config: AxisConfig,
    planner: Planner,
    cycle: u64,
    statusword: StatusWord,
    state: Option<State>,
    displayed_mode: Option<OperationMode>,
    still_cycles: u32,
    standstill: bool,
    last_actual_position: Option<i32>,
    fault: bool,
    error: Option<ErrorDescription>,
    warning: bool,
    active_mode: OperationMode,
    commanded_mode: OperationMode,
    switch: ModeSwitch,
    mismatch_reported: bool,
    position: i32,
    last_position_out: i32,
    position_delta: i32,
    velocity: i32,
    torque: i16,
    velocity_offset: i32,
    torque_offset: i16,
    mode_bits: ControlWord,
    progress: Option<Progress>,
    planner_error: Option<PlannerError>,
    mode_switch_error: Option<ModeSwitchError>,
    events: EventQueue,
}

impl Axis {
    /// An axis for a drive with `caps`. Starts with target Switch on disabled and writes
    /// `config.initial_mode` to 0x6060 (waiting for 0x6061 like any mode switch).
    pub fn new(caps: DriveCaps, config: AxisConfig) -> Result<Self, AxisError> {
        let planner = Planner::new(&caps, config.planner)?;
        if config.mode_switch_timeout_cycles == 0 {
            return Err(AxisError::InvalidConfig {
                what: "mode_switch_timeout_cycles must be at least 1",
            });
        }
        if !caps.supported_modes.contains(config.initial_mode) {
            return Err(AxisError::ModeNotSupported {
                mode: config.initial_mode,
                supported: caps.supported_modes.raw(),
            });
        }
        Ok(Self {
            caps,
            config,
            planner,
            cycle: 0,
            statusword: StatusWord::empty(),
            state: None,
            displayed_mode: None,
            still_cycles: 0,
            standstill: false,
            last_actual_position: None,
            fault: false,
            error: None,
            warning: false,
            active_mode: OperationMode::NoMode,
            commanded_mode: config.initial_mode,
            switch: ModeSwitch::Requested {
                from: OperationMode::NoMode,
                to: config.initial_mode,
                cycles: 0,
            },
            mismatch_reported: false,
            position: 0,
            last_position_out: 0,
            position_delta: 0,
            velocity: 0,
            torque: 0,
            velocity_offset: 0,
            torque_offset: 0,
            mode_bits: ControlWord::empty(),
            progress: None,
            planner_error: None,
            mode_switch_error: None,
            events: EventQueue::new(),
        })
    }

    /// The drive capabilities.
    pub const fn caps(&self) -> &DriveCaps {
        &self.caps
    }

    /// The configuration.
    pub const fn config(&self) -> &AxisConfig {
        &self.config
    }

    // ----- requests -------------------------------------------------------------------------

    /// Enable: target Operation enabled. Refused while a fault is present (reset it first).
    pub fn request_enable(&mut self) -> Result<(), AxisError> {
        self.request_target(Target::OperationEnabled)
    }

    /// Disable: target Switch on disabled (transitions 7, 9, 10; a running quick stop is let
    /// finish).
    pub fn request_disable(&mut self) {
        self.set_target(Target::SwitchOnDisabled);
    }

    /// Quick stop: target Quick stop. From a disabled drive the planner reports
    /// [`PlannerError::Unreachable`].
    pub fn request_quick_stop(&mut self) {
        self.set_target(Target::QuickStop);
    }

    /// Any planner target. Operation enabled and Switched on are refused while a fault is
    /// present.
    pub fn request_target(&mut self, target: Target) -> Result<(), AxisError> {
        if self.fault && matches!(target, Target::OperationEnabled | Target::SwitchedOn) {
            return Err(AxisError::Faulted {
                error_code: self.error.map(|e| e.code),
            });
        }
        self.set_target(target);
        Ok(())
    }

    /// Reset the fault: rising edges on bit 7 while the drive is in Fault (see [`Planner`]).
    /// The target becomes Switch on disabled; enabling again needs [`Axis::request_enable`]
    /// after [`Event::FaultCleared`]. Ignored (returns `false`) unless the last step saw a fault:
    /// a reset must answer a fault the application has seen, never one that comes later.
    pub fn request_fault_reset(&mut self) -> bool {
        if !self.fault {
            return false;
        }
        if self.planner.target() != Target::SwitchOnDisabled {
            self.set_target(Target::SwitchOnDisabled);
        }
        self.planner.request_fault_reset()
    }

    /// Change the mode of operation (see the module documentation for the procedure).
    pub fn request_mode(&mut self, mode: OperationMode) -> Result<(), AxisError> {
        if !self.caps.supported_modes.contains(mode) {
            return Err(AxisError::ModeNotSupported {
                mode,
                supported: self.caps.supported_modes.raw(),
            });
        }
        match self.switch {
            ModeSwitch::Idle => {}
            ModeSwitch::Braking { to, .. }
            | ModeSwitch::Stopping { to, .. }
            | ModeSwitch::Requested { to, .. } => {
                return if to == mode {
                    Ok(())
                } else {
                    Err(AxisError::ModeSwitchInProgress { to })
                };
            }
        }
        if mode == self.active_mode {
            return Ok(());
        }
        // A position mode starts from the actual position: entered while the axis turns, it
        // would stop the axis within a cycle at whatever torque the drive has. So every drive,
        // not only one that requires zero speed for the switch, is brought to standstill first,
        // also from csp (a csp move's demand ends while the axis still follows it).
        let turning_into_position = self.caps.is_position_mode(mode)
            && self.state == Some(State::OperationEnabled)
            && !self.fault
            && !self.standstill;
        let needs_stop = turning_into_position
            || (self.caps.position_mode_switch_needs_zero_speed
                && (self.caps.is_position_mode(mode)
                    || self.caps.is_position_mode(self.active_mode)));
        if needs_stop {
            if let Some(via) = self.braking_mode(mode) {
                self.commanded_mode = via;
                self.switch = ModeSwitch::Braking {
                    via,
                    to: mode,
                    cycles: 0,
                };
            } else {
                self.switch = self.stopping(mode);
            }
        } else {
            self.commanded_mode = mode;
            self.switch = ModeSwitch::Requested {
                from: self.active_mode,
                to: mode,
                cycles: 0,
            };
        }
        Ok(())
    }

    /// The Stopping phase toward `to`, with ramps from the present commanded values.
    fn stopping(&self, to: OperationMode) -> ModeSwitch {
        let n = self.config.stop_ramp.cycles.max(1);
        ModeSwitch::Stopping {
            to,
            cycles: 0,
            slowest: u32::MAX,
            position_step: step_size(self.position_delta.unsigned_abs(), n),
            velocity_step: step_size(self.velocity.unsigned_abs(), n),
            torque_step: step_size(u32::from(self.torque.unsigned_abs()), n),
        }
    }

    /// The velocity mode to brake in when the axis turns in a torque mode and must reach zero
    /// speed before `to`: a torque set-point of 0 only lets the motor coast, so the engine
    /// switches to a velocity mode and ramps the velocity to 0 there: csv where the drive has it
    /// (the master sets the deceleration cycle by cycle), else pv (the drive follows the ramped
    /// target by its own deceleration, 0x6084). A drive whose setting excludes the cyclic modes
    /// now (the MR-J4-TM's [Pr. PA01] in profile mode) has its [`DriveCaps::supported_modes`]
    /// restricted by the master, so it brakes in pv. `None` when the axis is not turning, not
    /// enabled, or the drive has neither.
    fn braking_mode(&self, _to: OperationMode) -> Option<OperationMode> {
        if self.active_mode.set_point_kind() != Some(SetPointKind::Torque)
            || self.standstill
            || self.state != Some(State::OperationEnabled)
            || self.fault
        {
            return None;
        }
        [
            OperationMode::CyclicSyncVelocity,
            OperationMode::ProfileVelocity,
        ]
        .into_iter()
        .find(|&via| self.caps.supported_modes.contains(via) && !self.caps.is_position_mode(via))
    }

    /// The commanded position is where the motion ends (a program's motion step that reached its
    /// target at rest): a stopping phase before a mode switch then holds it instead of carrying
    /// on the last cycle's increment (the last step of a move may be a large one, and the ramp
    /// down from it ran past the target).
    pub fn hold(&mut self) {
        self.position_delta = 0;
        self.last_position_out = self.position;
    }

    /// Target position (0x607A) for pp, ip, csp.
    pub fn set_position(&mut self, position: i32) -> Result<(), AxisError> {
        self.accept(SetPointKind::Position)?;
        self.position = position;
        Ok(())
    }

    /// Target velocity (0x60FF) for vl, pv, csv.
    pub fn set_velocity(&mut self, velocity: i32) -> Result<(), AxisError> {
        self.accept(SetPointKind::Velocity)?;
        self.velocity = velocity;
        Ok(())
    }

    /// Target torque (0x6071) for tq, cst, cstca.
    pub fn set_torque(&mut self, torque: i16) -> Result<(), AxisError> {
        self.accept(SetPointKind::Torque)?;
        self.torque = torque;
        Ok(())
    }

    /// Velocity offset (0x60B1) and torque offset (0x60B2), written while streaming.
    pub fn set_offsets(
        &mut self,
        velocity_offset: i32,
        torque_offset: i16,
    ) -> Result<(), AxisError> {
        self.check_streaming()?;
        self.velocity_offset = velocity_offset;
        self.torque_offset = torque_offset;
        Ok(())
    }

    /// Mode-specific controlword bits (4, 5, 6, 8, 9: new set-point, change set immediately,
    /// abs/rel, halt, change on set-point, homing start). Other bits are ignored. Applied while
    /// streaming; cleared when a mode switch completes.
    pub fn set_mode_bits(&mut self, bits: ControlWord) {
        self.mode_bits = bits.mode_specific();
    }

    // ----- observation ----------------------------------------------------------------------

    /// The next queued event.
    pub fn poll_event(&mut self) -> Option<Event> {
        self.events.pop()
    }

    /// Events are queued ([`Axis::poll_event`] returns one).
    pub fn has_events(&self) -> bool {
        self.events.len > 0
    }

    /// A snapshot.
    /// The decoded state (as [`status`](Self::status) has it, without building the rest).
    pub fn state(&self) -> Option<State> {
        self.state
    }

    /// A fault is present (as [`status`](Self::status) has it).
    pub fn fault(&self) -> bool {
        self.fault
    }

    /// Set-points are accepted now (as [`status`](Self::status) has it).
    pub fn is_streaming(&self) -> bool {
        self.streaming()
    }

    /// The mode set-points are streamed for (as [`status`](Self::status) has it).
    pub fn active_mode(&self) -> OperationMode {
        self.active_mode
    }

    /// At standstill by the configured rule (as [`status`](Self::status) has it).
    pub fn standstill(&self) -> bool {
        self.standstill
    }

    /// The whole status. The cycle's hot paths use the single accessors above instead.
    pub fn status(&self) -> AxisStatus {
        AxisStatus {
            cycle: self.cycle,
            statusword: self.statusword,
            state: self.state,
            phase: self.phase(),
            target: self.planner.target(),
            active_mode: self.active_mode,
            commanded_mode: self.commanded_mode,
            displayed_mode: self.displayed_mode,
            mode_switch: match self.switch {
                ModeSwitch::Idle => ModeSwitchPhase::Idle,
                ModeSwitch::Braking { to, .. } | ModeSwitch::Stopping { to, .. } => {
                    ModeSwitchPhase::Stopping { to }
                }
                ModeSwitch::Requested { to, .. } => ModeSwitchPhase::Requested { to },
            },
            streaming: self.streaming(),
            standstill: self.standstill,
            fault: self.fault,
            error: self.error,
            warning: self.warning,
            planner_error: self.planner_error,
            mode_switch_error: self.mode_switch_error,
            events_lost: self.events.lost,
        }
    }

    // ----- the cycle ------------------------------------------------------------------------

    /// One cycle: consume the feedback, produce the outputs.
    pub fn step(&mut self, fb: &Feedback) -> Output {
        self.cycle = self.cycle.wrapping_add(1);
        let sw = fb.statusword;
        let state = sw.state();
        if state != self.state {
            self.events.push(Event::StateChanged {
                from: self.state,
                to: state,
            });
            self.state = state;
        }
        self.statusword = sw;
        self.displayed_mode = fb.mode_display;
        let warning = sw.contains(StatusWord::WARNING);
        if warning != self.warning {
            self.warning = warning;
            self.events.push(Event::WarningChanged(warning));
        }
        self.update_standstill(fb);
        self.observe_fault(fb, state);
        self.run_mode_switch(fb);

        let step = self.planner.next(sw, self.standstill);
        if self.progress != Some(step.progress) {
            match step.progress {
                Progress::Reached => {
                    self.planner_error = None;
                    self.events
                        .push(Event::TargetReached(self.planner.target()));
                }
                Progress::Failed(e) => {
                    self.planner_error = Some(e);
                    self.events.push(Event::PlannerFailed(e));
                }
                Progress::InProgress => self.planner_error = None,
            }
            self.progress = Some(step.progress);
        }

        // Entering a cyclic position mode (csp, or ip: the binding copies 0x607A into
        // 0x60C1:01) from another one: the drive follows the position from the first frame that
        // names the mode, so every frame until the switch is confirmed carries the actual
        // position, not what the other mode left there (a pp target, which may be relative:
        // taken as absolute it is a jump).
        if self.commanded_mode != self.active_mode
            && (self.commanded_mode.is_cyclic()
                || self.commanded_mode == OperationMode::InterpolatedPosition)
            && self.commanded_mode.set_point_kind() == Some(SetPointKind::Position)
            && let Some(p) = fb.position
        {
            self.position = p;
        }
        self.update_set_points(fb);
        let streaming = self.streaming();
        let oms = if streaming {
            // A drive that starts csp motion on bit 4's edge gets it now and keeps it.
            if self.caps.csp_start_edge && self.active_mode == OperationMode::CyclicSyncPosition {
                self.mode_bits | ControlWord::NEW_SET_POINT
            } else {
                self.mode_bits
            }
        } else if self.halting() {
            ControlWord::HALT
        } else {
            ControlWord::empty()
        };
        let (velocity_offset, torque_offset) = if streaming {
            (self.velocity_offset, self.torque_offset)
        } else {
            (0, 0)
        };
        Output {
            controlword: step.command.apply(oms),
            mode: self.commanded_mode,
            target_position: self.position,
            target_velocity: self.velocity,
            target_torque: self.torque,
            velocity_offset,
            torque_offset,
        }
    }

    fn set_target(&mut self, target: Target) {
        self.planner.set_target(target);
        self.progress = None;
    }

    fn phase(&self) -> Phase {
        if self.fault {
            return if self.planner.fault_reset_pending() {
                Phase::ResettingFault
            } else {
                Phase::Faulted
            };
        }
        let progress = self.progress.unwrap_or(Progress::InProgress);
        match (self.planner.target(), progress) {
            (_, Progress::Failed(_)) => Phase::Failed,
            (Target::OperationEnabled, Progress::Reached) => Phase::Enabled,
            (Target::OperationEnabled, Progress::InProgress) => Phase::Enabling,
            (Target::SwitchedOn | Target::SwitchOnDisabled, Progress::Reached) => Phase::Disabled,
            (Target::SwitchedOn | Target::SwitchOnDisabled, Progress::InProgress) => {
                Phase::Disabling
            }
            (Target::QuickStop, Progress::Reached) => Phase::QuickStopped,
            (Target::QuickStop, Progress::InProgress) => Phase::QuickStopping,
        }
    }

    fn streaming(&self) -> bool {
        self.state == Some(State::OperationEnabled)
            && !self.fault
            && self.planner.target() == Target::OperationEnabled
            && self.switch == ModeSwitch::Idle
            && self.active_mode != OperationMode::NoMode
            && self.displayed_mode.is_none_or(|d| d == self.active_mode)
    }

    fn check_streaming(&self) -> Result<(), AxisError> {
        if self.fault {
            return Err(AxisError::Faulted {
                error_code: self.error.map(|e| e.code),
            });
        }
        if self.state != Some(State::OperationEnabled)
            || self.planner.target() != Target::OperationEnabled
        {
            return Err(AxisError::NotStreaming {
                state: self.state,
                phase: self.phase(),
            });
        }
        if let ModeSwitch::Braking { to, .. }
        | ModeSwitch::Stopping { to, .. }
        | ModeSwitch::Requested { to, .. } = self.switch
        {
            return Err(AxisError::ModeSwitchInProgress { to });
        }
        if !self.streaming() {
            return Err(AxisError::NotStreaming {
                state: self.state,
                phase: self.phase(),
            });
        }
        Ok(())
    }

    fn accept(&self, kind: SetPointKind) -> Result<(), AxisError> {
        self.check_streaming()?;
        if self.active_mode.set_point_kind() != Some(kind) {
            return Err(AxisError::WrongSetPoint {
                kind,
                mode: self.active_mode,
            });
        }
        Ok(())
    }

    /// Halt (bit 8) while stopping for a switch, in a profile mode other than pv: in pv the
    /// engine ramps the target velocity to 0 and the drive follows it by its own deceleration,
    /// where a halt would stop it by 0x605D (the MR-J4-TM at its torque limit, −261 %).
    fn halting(&self) -> bool {
        matches!(self.switch, ModeSwitch::Stopping { .. })
            && self.state == Some(State::OperationEnabled)
            && !self.active_mode.is_cyclic()
            && self.active_mode.set_point_kind() != Some(SetPointKind::Velocity)
    }

    fn update_standstill(&mut self, fb: &Feedback) {
        let cfg = self.config.standstill;
        let still = if let Some(z) = fb.zero_speed {
            z && fb.velocity.is_none_or(|v| v.unsigned_abs() <= cfg.velocity)
        } else if let Some(v) = fb.velocity {
            v.unsigned_abs() <= cfg.velocity
        } else if let (Some(p), Some(lp)) = (fb.position, self.last_actual_position) {
            p.wrapping_sub(lp).unsigned_abs() <= cfg.position_delta
        } else {
            false
        };
        self.last_actual_position = fb.position;
        self.still_cycles = if still {
            self.still_cycles.saturating_add(1)
        } else {
            0
        };
        self.standstill = self.still_cycles >= cfg.cycles.max(1);
    }

    #[inline]
    fn observe_fault(&mut self, fb: &Feedback, state: Option<State>) {
        let faulted =
            fb.statusword.contains(StatusWord::FAULT) || state.is_some_and(State::is_fault);
        if faulted || self.fault {
            self.fault_changes(fb, state, faulted);
        }
    }

    /// [`Axis::observe_fault`] with a fault present or just gone (rare: out of line).
    #[cold]
    #[inline(never)]
    fn fault_changes(&mut self, fb: &Feedback, state: Option<State>, faulted: bool) {
        if faulted {
            if let Some(code) = fb.error_code.filter(|c| !c.is_none()) {
                self.error = Some(code.describe(self.caps.error_table));
            }
            if !self.fault {
                self.fault = true;
                if matches!(
                    self.planner.target(),
                    Target::OperationEnabled | Target::SwitchedOn
                ) {
                    self.set_target(Target::SwitchOnDisabled);
                }
                if let ModeSwitch::Braking { to, cycles, .. }
                | ModeSwitch::Stopping { to, cycles, .. } = self.switch
                {
                    self.abandon_switch(to, ModeSwitchFailure::Fault, cycles);
                }
                self.events.push(Event::Fault {
                    state,
                    error: self.error,
                });
            }
        } else if self.fault && state.is_some() {
            self.fault = false;
            self.events.push(Event::FaultCleared);
        }
    }

    fn abandon_switch(&mut self, to: OperationMode, reason: ModeSwitchFailure, cycles: u32) {
        let err = ModeSwitchError {
            from: self.active_mode,
            to,
            reason,
            cycles,
        };
        if self.active_mode != OperationMode::NoMode {
            self.commanded_mode = self.active_mode;
        }
        self.switch = ModeSwitch::Idle;
        self.mode_switch_error = Some(err);
        self.events.push(Event::ModeSwitchFailed(err));
    }

    #[inline]
    fn run_mode_switch(&mut self, fb: &Feedback) {
        // The steady case: no switch, the display agreeing.
        if self.switch == ModeSwitch::Idle && fb.mode_display.is_none_or(|d| d == self.active_mode)
        {
            self.mismatch_reported = false;
            return;
        }
        self.mode_switch_progress(fb);
    }

    /// [`Axis::run_mode_switch`] with a switch under way or the display disagreeing (rare: out
    /// of line).
    #[cold]
    #[inline(never)]
    fn mode_switch_progress(&mut self, fb: &Feedback) {
        let timeout = self.config.mode_switch_timeout_cycles;
        match self.switch {
            ModeSwitch::Idle => match fb.mode_display {
                Some(d) if d != self.active_mode => {
                    if !self.mismatch_reported {
                        self.mismatch_reported = true;
                        self.events.push(Event::ModeDisplayMismatch {
                            expected: self.active_mode,
                            displayed: d,
                        });
                    }
                }
                _ => self.mismatch_reported = false,
            },
            ModeSwitch::Braking { via, to, cycles } => {
                if fb.mode_display.is_none_or(|d| d == via) {
                    // Now in the velocity mode, silently: the application asked for `to`.
                    self.active_mode = via;
                    self.mode_bits = ControlWord::empty();
                    self.switch = self.stopping(to);
                } else if cycles >= timeout {
                    self.abandon_switch(
                        to,
                        ModeSwitchFailure::NotConfirmed {
                            displayed: fb.mode_display,
                        },
                        cycles,
                    );
                } else if let ModeSwitch::Braking { cycles: c, .. } = &mut self.switch {
                    *c = cycles.saturating_add(1);
                }
            }
            ModeSwitch::Stopping {
                to,
                cycles,
                slowest,
                ..
            } => {
                // Progress: the actual speed reached a new low (by more than 1 %, or 1 unit).
                let progress = fb.velocity.map(i32::unsigned_abs).filter(|&v| {
                    slowest == u32::MAX || v < slowest.saturating_sub((slowest / 100).max(1))
                });
                // The engine's own ramp must have ended too: a drive's zero-speed flag may
                // already show at a speed it calls zero (the MR-J4-TM's S_ZSP below
                // [Pr. PC07], 50 r/min by default) while the set-point still brakes, and a
                // position mode entered then stops the rest within a cycle.
                if self.standstill && self.ramp_done() {
                    self.commanded_mode = to;
                    self.switch = ModeSwitch::Requested {
                        from: self.active_mode,
                        to,
                        cycles: 0,
                    };
                } else if cycles >= timeout {
                    self.abandon_switch(to, ModeSwitchFailure::NoStandstill, cycles);
                } else if let ModeSwitch::Stopping {
                    cycles: c,
                    slowest: low,
                    ..
                } = &mut self.switch
                {
                    match progress {
                        Some(v) => {
                            *low = v;
                            *c = 0;
                        }
                        None => *c = cycles.saturating_add(1),
                    }
                }
            }
            ModeSwitch::Requested { from, to, cycles } => {
                let confirmed = fb.mode_display.is_none_or(|d| d == to);
                if confirmed {
                    self.active_mode = to;
                    self.switch = ModeSwitch::Idle;
                    self.mismatch_reported = false;
                    self.mode_bits = ControlWord::empty();
                    self.events.push(Event::ModeSwitched { from, to });
                } else if cycles >= timeout {
                    self.abandon_switch(
                        to,
                        ModeSwitchFailure::NotConfirmed {
                            displayed: fb.mode_display,
                        },
                        cycles,
                    );
                } else if let ModeSwitch::Requested { cycles: c, .. } = &mut self.switch {
                    *c = cycles.saturating_add(1);
                }
            }
        }
    }

    /// Whether the Stopping phase's ramp has brought the commanded value of the active mode
    /// to zero.
    fn ramp_done(&self) -> bool {
        match self.active_mode.set_point_kind() {
            Some(SetPointKind::Velocity) => self.velocity == 0,
            Some(SetPointKind::Torque) => self.torque == 0,
            Some(SetPointKind::Position) => self.position_delta == 0,
            None => true,
        }
    }

    /// Update the three commanded values (see the module documentation).
    fn update_set_points(&mut self, fb: &Feedback) {
        let enabled = self.state == Some(State::OperationEnabled) && !self.fault;
        let active = if enabled {
            self.active_mode.set_point_kind()
        } else {
            None
        };
        let threshold = self.config.standstill.velocity;

        if active == Some(SetPointKind::Position) {
            if let ModeSwitch::Stopping { position_step, .. } = self.switch {
                let d = toward_zero(i64::from(self.position_delta), u64::from(position_step));
                let d = i32::try_from(d).unwrap_or(0);
                self.position = self.position.wrapping_add(d);
            }
        } else if let Some(p) = fb.position {
            self.position = p;
        }

        if active == Some(SetPointKind::Velocity) {
            if let ModeSwitch::Stopping { velocity_step, .. } = self.switch {
                let v = toward_zero(i64::from(self.velocity), u64::from(velocity_step));
                self.velocity = i32::try_from(v).unwrap_or(0);
            }
        } else {
            self.velocity = fb
                .velocity
                .filter(|v| v.unsigned_abs() > threshold)
                .unwrap_or(0);
        }

        if active == Some(SetPointKind::Torque) {
            if let ModeSwitch::Stopping { torque_step, .. } = self.switch {
                let t = toward_zero(i64::from(self.torque), u64::from(torque_step));
                self.torque = i16::try_from(t).unwrap_or(0);
            }
        } else if enabled {
            self.torque = fb.torque.unwrap_or(0);
        } else {
            // Outside Operation enabled the torque the drive reports is its own (the braking
            // of a quick stop or a fault reaction): a set-point taken from it would drive the
            // motor on the way back to Operation enabled (transition 16 leaves Quick stop
            // active straight into it). A de-energised motor has none, so 0 is what enabling
            // starts from.
            self.torque = 0;
        }

        self.position_delta = self.position.wrapping_sub(self.last_position_out);
        self.last_position_out = self.position;
    }
}

/// `ceil(magnitude / cycles)`, at least 1.
fn step_size(magnitude: u32, cycles: u32) -> u32 {
    magnitude.div_ceil(cycles.max(1)).max(1)
}

/// `v` moved toward 0 by `step`, never past it.
fn toward_zero(v: i64, step: u64) -> i64 {
    let step = i64::try_from(step).unwrap_or(i64::MAX);
    if v > 0 {
        (v - step).max(0)
    } else {
        (v + step).min(0)
    }
}
