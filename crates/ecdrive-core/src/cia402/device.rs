//! The CiA 402 state machine as a **drive** implements it: a pure, reusable model.
//!
//! [`Device::step`] takes the controlword the drive received this cycle plus a few facts about
//! the drive (fault present, motion stopped, main power, remote) and performs at most one
//! transition. The emulated drives of the software slave run it, and the property tests use it as
//! the reference the master-side [`Planner`](super::Planner) is checked against. The planner
//! decides which controlword to send; this model decides how a drive reacts to it.
//!
//! Model rules (CiA 402 transitions 0–16, with the per-drive choices of [`DeviceConfig`]):
//!
//! | from | command / event | to | no. |
//! |---|---|---|---|
//! | any but Fault reaction active / Fault | `fault` input | Fault reaction active | 13 |
//! | Not ready to switch on | after `init_cycles` steps | Switch on disabled | 1 |
//! | Switch on disabled | Shutdown | Ready to switch on | 2 |
//! | Ready to switch on | Switch on | Switched on | 3 |
//! | Ready to switch on | Enable operation | Switched on (3, then 4 on the next step) | 3 |
//! | Switched on | Enable operation | Operation enabled | 4 |
//! | Operation enabled | Disable operation | Switched on | 5 |
//! | Switched on | Shutdown | Ready to switch on | 6 |
//! | Ready to switch on | Disable voltage, Quick stop | Switch on disabled | 7 |
//! | Operation enabled | Shutdown, or main power lost | Ready to switch on | 8 |
//! | Operation enabled | Disable voltage | Switch on disabled | 9 |
//! | Switched on | Disable voltage, Quick stop | Switch on disabled | 10 |
//! | Operation enabled | Quick stop | Quick stop active | 11 |
//! | Quick stop active | Disable voltage; or automatically once stopped (codes ending in Switch on disabled; at once for [`StopRamp::Immediate`]) | Switch on disabled | 12 |
//! | Fault reaction active | `motion_stopped` (the fault reaction has finished) | Fault | 14 |
//! | Fault | rising edge of bit 7 while `fault` is false | Switch on disabled | 15 |
//! | Quick stop active | Enable operation, with `transition_16` and a code that stays in Quick stop active | Operation enabled | 16 |
//! | Switch on disabled | Switch on / Enable operation, with `state_skipping` | Switched on / Operation enabled | – |
//! | Ready to switch on | Enable operation, with `state_skipping` | Operation enabled | – |
//!
//! Further model choices (not vendor facts; an emulator may layer its own on top):
//! * While bit 7 is 1 outside Fault, the other command bits are not acted on (strict CiA reading
//!   of the table, where every other command has bit 7 = 0).
//! * Energising transitions (2, 3, 4, 16 and the skips) need `main_power`; without it the
//!   command is [`Block::NoMainPower`]. Losing main power in Operation enabled is transition 8
//!   (MR-J4-TM Table 5.1, 8(b)).
//! * With `remote_gates_controlword` and `remote` false, only quick stop and fault reset act
//!   (BLV-R §6.1); other commands are [`Block::NotRemote`].
//! * The statusword carries the canonical state bits, bit 4 = `main_power`, bit 7 = `warning`,
//!   bit 9 = `remote`; mode-specific bits are the emulator's business.

use super::bits::{ControlWord, StatusWord};
use super::caps::{DriveCaps, QuickStopEnd, QuickStopOption, StopRamp};
use super::command::Command;
use super::state::State;

/// The per-drive behaviour of the device model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DeviceConfig {
    /// Accept the state-skipping jumps (see [`DriveCaps::state_skipping`]).
    pub state_skipping: bool,
    /// Transition 16 exists.
    pub transition_16: bool,
    /// The quick-stop option code in effect (0x605A).
    pub quick_stop: QuickStopOption,
    /// Only quick stop and fault reset act while `remote` is false.
    pub remote_gates_controlword: bool,
    /// Steps spent in Not ready to switch on before transition 1.
    pub init_cycles: u32,
}

impl DeviceConfig {
    /// The model of a drive with `caps`, running quick-stop option `quick_stop`, that leaves Not
    /// ready to switch on at its first step.
    pub const fn from_caps(caps: &DriveCaps, quick_stop: QuickStopOption) -> Self {
        Self {
            state_skipping: caps.state_skipping,
            transition_16: caps.transition_16,
            quick_stop,
            remote_gates_controlword: caps.remote_gates_controlword,
            init_cycles: 0,
        }
    }
}

/// What the drive sees and knows in one cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DeviceInputs {
    /// The controlword received this cycle.
    pub controlword: ControlWord,
    /// A fault (alarm) is present. Triggers transition 13; blocks transition 15 while true.
    pub fault: bool,
    /// The motor has stopped (quick-stop ramp or fault reaction finished).
    pub motion_stopped: bool,
    /// Main circuit / DC-bus power is present (statusword bit 4).
    pub main_power: bool,
    /// The drive is under fieldbus control (statusword bit 9).
    pub remote: bool,
    /// A warning is present (statusword bit 7).
    pub warning: bool,
}

impl DeviceInputs {
    /// `controlword` with no fault, motor stopped, main power on, remote, no warning.
    pub const fn new(controlword: ControlWord) -> Self {
        Self {
            controlword,
            fault: false,
            motion_stopped: true,
            main_power: true,
            remote: true,
            warning: false,
        }
    }
}

/// A state change, with its CiA 402 number (`None` for a state-skipping jump).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Transition {
    /// State before.
    pub from: State,
    /// State after.
    pub to: State,
    /// CiA 402 transition number 1–16, `None` for a skip.
    pub number: Option<u8>,
}

/// Why a command that the state would accept did not act.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Block {
    /// Remote (bit 9) is 0 and the drive gates the controlword on it.
    NotRemote,
    /// No main power for an energising transition.
    NoMainPower,
    /// Fault reset edge while the fault is still present.
    FaultPresent,
}

/// How the drive reacted to one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reaction {
    /// The state changed.
    Transition(Transition),
    /// The command is the one that keeps this state (e.g. Shutdown in Ready to switch on, bit 7
    /// held high, or any controlword in Fault without a reset edge).
    Hold,
    /// An automatic state (initialisation, a running quick-stop ramp, fault reaction): the
    /// controlword does not matter now.
    Waiting,
    /// The command has no transition from this state (e.g. Switch on in Switch on disabled
    /// without state skipping, Enable operation in Quick stop active without transition 16).
    Ignored,
    /// The command would act but a condition prevents it.
    Blocked(Block),
}

/// The device-side state machine.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Device {
    config: DeviceConfig,
    state: State,
    init_left: u32,
    last_bit7: bool,
    main_power: bool,
    remote: bool,
    warning: bool,
}

impl Device {
    /// A drive just powered on (transition 0 done): Not ready to switch on.
    pub const fn new(config: DeviceConfig) -> Self {
        Self::with_state(config, State::NotReadyToSwitchOn)
    }

    /// A drive in `state` (for tests and emulator resets). Bit 7 is assumed low so far.
    pub const fn with_state(config: DeviceConfig, state: State) -> Self {
        Self {
            config,
            state,
            init_left: config.init_cycles,
            last_bit7: false,
            main_power: true,
            remote: true,
            warning: false,
        }
    }

    /// The configuration.
    pub const fn config(&self) -> &DeviceConfig {
        &self.config
    }

    /// The current state.
    pub const fn state(&self) -> State {
        self.state
    }

    /// The statusword for the current state: canonical state bits, bit 4 main power, bit 7
    /// warning, bit 9 remote (as given to the last [`Device::step`]; all on before the first).
    pub fn statusword(&self) -> StatusWord {
        let mut sw = StatusWord::from_raw(self.state.statusword_bits());
        sw.set(StatusWord::VOLTAGE_ENABLED, self.main_power);
        sw.set(StatusWord::REMOTE, self.remote);
        sw.set(StatusWord::WARNING, self.warning);
        sw
    }

    /// Process one cycle: at most one transition.
    pub fn step(&mut self, inputs: &DeviceInputs) -> Reaction {
        self.main_power = inputs.main_power;
        self.remote = inputs.remote;
        self.warning = inputs.warning;
        let bit7 = inputs.controlword.contains(ControlWord::FAULT_RESET);
        let edge = bit7 && !self.last_bit7;
        self.last_bit7 = bit7;

        let from = self.state;
        if inputs.fault && !from.is_fault() {
            return self.go(State::FaultReactionActive, Some(13));
        }
        let cmd = Command::decode(inputs.controlword);
        match from {
            State::NotReadyToSwitchOn => {
                if self.init_left > 0 {
                    self.init_left -= 1;
                    Reaction::Waiting
                } else {
                    self.go(State::SwitchOnDisabled, Some(1))
                }
            }
            State::FaultReactionActive => {
                if inputs.motion_stopped {
                    self.go(State::Fault, Some(14))
                } else {
                    Reaction::Waiting
                }
            }
            State::Fault => {
                if !edge {
                    Reaction::Hold
                } else if inputs.fault {
                    Reaction::Blocked(Block::FaultPresent)
                } else {
                    self.go(State::SwitchOnDisabled, Some(15))
                }
            }
            State::QuickStopActive => self.quick_stop_active(inputs, cmd),
            State::SwitchOnDisabled
            | State::ReadyToSwitchOn
            | State::SwitchedOn
            | State::OperationEnabled => self.operational(inputs, cmd),
        }
    }

    fn go(&mut self, to: State, number: Option<u8>) -> Reaction {
        let from = self.state;
        self.state = to;
        Reaction::Transition(Transition { from, to, number })
    }

    fn gated(&self, inputs: &DeviceInputs, cmd: Command) -> bool {
        self.config.remote_gates_controlword && !inputs.remote && cmd != Command::QuickStop
    }

    fn energise(&mut self, inputs: &DeviceInputs, to: State, number: Option<u8>) -> Reaction {
        if inputs.main_power {
            self.go(to, number)
        } else {
            Reaction::Blocked(Block::NoMainPower)
        }
    }

    fn operational(&mut self, inputs: &DeviceInputs, cmd: Command) -> Reaction {
        use State::*;
        let from = self.state;
        if from == OperationEnabled && !inputs.main_power {
            return self.go(ReadyToSwitchOn, Some(8));
        }
        if cmd == Command::FaultReset {
            return Reaction::Hold;
        }
        if self.gated(inputs, cmd) {
            return Reaction::Blocked(Block::NotRemote);
        }
        let skip = self.config.state_skipping;
        match (from, cmd) {
            (SwitchOnDisabled, Command::Shutdown) => {
                self.energise(inputs, ReadyToSwitchOn, Some(2))
            }
            (SwitchOnDisabled, Command::SwitchOn | Command::DisableOperation) if skip => {
                self.energise(inputs, SwitchedOn, None)
            }
            (SwitchOnDisabled, Command::EnableOperation) if skip => {
                self.energise(inputs, OperationEnabled, None)
            }
            (SwitchOnDisabled, Command::DisableVoltage | Command::QuickStop) => Reaction::Hold,
            (ReadyToSwitchOn, Command::Shutdown) => Reaction::Hold,
            (ReadyToSwitchOn, Command::SwitchOn | Command::DisableOperation) => {
                self.energise(inputs, SwitchedOn, Some(3))
            }
            (ReadyToSwitchOn, Command::EnableOperation) => {
                if skip {
                    self.energise(inputs, OperationEnabled, None)
                } else {
                    self.energise(inputs, SwitchedOn, Some(3))
                }
            }
            (ReadyToSwitchOn, Command::DisableVoltage | Command::QuickStop) => {
                self.go(SwitchOnDisabled, Some(7))
            }
            (SwitchedOn, Command::Shutdown) => self.go(ReadyToSwitchOn, Some(6)),
            (SwitchedOn, Command::SwitchOn | Command::DisableOperation) => Reaction::Hold,
            (SwitchedOn, Command::EnableOperation) => {
                self.energise(inputs, OperationEnabled, Some(4))
            }
            (SwitchedOn, Command::DisableVoltage | Command::QuickStop) => {
                self.go(SwitchOnDisabled, Some(10))
            }
            (OperationEnabled, Command::Shutdown) => self.go(ReadyToSwitchOn, Some(8)),
            (OperationEnabled, Command::SwitchOn | Command::DisableOperation) => {
                self.go(SwitchedOn, Some(5))
            }
            (OperationEnabled, Command::EnableOperation) => Reaction::Hold,
            (OperationEnabled, Command::DisableVoltage) => self.go(SwitchOnDisabled, Some(9)),
            (OperationEnabled, Command::QuickStop) => self.go(QuickStopActive, Some(11)),
            _ => Reaction::Ignored,
        }
    }

    fn quick_stop_active(&mut self, inputs: &DeviceInputs, cmd: Command) -> Reaction {
        let qs = self.config.quick_stop;
        if cmd == Command::DisableVoltage && !self.gated(inputs, cmd) {
            return self.go(State::SwitchOnDisabled, Some(12));
        }
        match qs.end {
            QuickStopEnd::SwitchOnDisabled => {
                if qs.ramp == StopRamp::Immediate || inputs.motion_stopped {
                    self.go(State::SwitchOnDisabled, Some(12))
                } else {
                    Reaction::Waiting
                }
            }
            QuickStopEnd::StayInQuickStopActive => match cmd {
                Command::QuickStop | Command::FaultReset => Reaction::Hold,
                _ if self.gated(inputs, cmd) => Reaction::Blocked(Block::NotRemote),
                Command::EnableOperation if self.config.transition_16 => {
                    self.energise(inputs, State::OperationEnabled, Some(16))
                }
                _ => Reaction::Ignored,
            },
        }
    }
}
