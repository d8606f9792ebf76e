//! The CiA 402 device states ("power drive system" finite state automaton).

use core::fmt;

/// A state of the CiA 402 device state machine, as encoded in statusword bits 0–3, 5, 6.
///
/// | state | bits 6 5 3 2 1 0 | mask / value |
/// |---|---|---|
/// | Not ready to switch on | `0 x 0 0 0 0` | `sw & 0x4F == 0x00` |
/// | Switch on disabled | `1 x 0 0 0 0` | `sw & 0x4F == 0x40` |
/// | Ready to switch on | `0 1 0 0 0 1` | `sw & 0x6F == 0x21` |
/// | Switched on | `0 1 0 0 1 1` | `sw & 0x6F == 0x23` |
/// | Operation enabled | `0 1 0 1 1 1` | `sw & 0x6F == 0x27` |
/// | Quick stop active | `0 0 0 1 1 1` | `sw & 0x6F == 0x07` |
/// | Fault reaction active | `0 x 1 1 1 1` | `sw & 0x4F == 0x0F` |
/// | Fault | `0 x 1 0 0 0` | `sw & 0x4F == 0x08` |
///
/// The table is the same in CiA 402, the MR-J4-TM manual (§5.3.1), the BDHDE manual (§5.4) and
/// the BLV-R manual (§6.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum State {
    /// Not ready to switch on: initialising after power-on (transition 0). The MR-J4-TM does
    /// not even send a statusword here.
    NotReadyToSwitchOn,
    /// Switch on disabled: initialised, power stage off.
    SwitchOnDisabled,
    /// Ready to switch on: power stage off, waiting for "switch on".
    ReadyToSwitchOn,
    /// Switched on: power stage ready (MR-J4: RA on), not energising the motor.
    SwitchedOn,
    /// Operation enabled: the motor is energised and follows set-points.
    OperationEnabled,
    /// Quick stop active: the quick-stop function runs or has run (energised).
    QuickStopActive,
    /// Fault reaction active: a fault was detected, the fault reaction runs.
    FaultReactionActive,
    /// Fault: power stage off until a fault reset.
    Fault,
}

impl State {
    /// All eight states.
    pub const ALL: [State; 8] = [
        State::NotReadyToSwitchOn,
        State::SwitchOnDisabled,
        State::ReadyToSwitchOn,
        State::SwitchedOn,
        State::OperationEnabled,
        State::QuickStopActive,
        State::FaultReactionActive,
        State::Fault,
    ];

    /// Decode a statusword with the CiA 402 masks (`0x4F` for the states whose bit 5 is "don't
    /// care", `0x6F` for the others). Returns `None` for the bit patterns the table does not
    /// define (e.g. `0x0001`, or `0x0021` with bit 6 set). Total over all 65 536 values.
    pub const fn from_statusword(sw: u16) -> Option<State> {
        match sw & 0x004F {
            0x0000 => return Some(State::NotReadyToSwitchOn),
            0x0040 => return Some(State::SwitchOnDisabled),
            0x000F => return Some(State::FaultReactionActive),
            0x0008 => return Some(State::Fault),
            _ => {}
        }
        match sw & 0x006F {
            0x0021 => Some(State::ReadyToSwitchOn),
            0x0023 => Some(State::SwitchedOn),
            0x0027 => Some(State::OperationEnabled),
            0x0007 => Some(State::QuickStopActive),
            _ => None,
        }
    }

    /// The canonical statusword bits 0–3, 5, 6 for this state; "don't care" bits are 0.
    /// `State::from_statusword(s.statusword_bits()) == Some(s)` for every state.
    pub const fn statusword_bits(self) -> u16 {
        match self {
            State::NotReadyToSwitchOn => 0x0000,
            State::SwitchOnDisabled => 0x0040,
            State::ReadyToSwitchOn => 0x0021,
            State::SwitchedOn => 0x0023,
            State::OperationEnabled => 0x0027,
            State::QuickStopActive => 0x0007,
            State::FaultReactionActive => 0x000F,
            State::Fault => 0x0008,
        }
    }

    /// The state's name as CiA 402 writes it.
    pub const fn name(self) -> &'static str {
        match self {
            State::NotReadyToSwitchOn => "Not ready to switch on",
            State::SwitchOnDisabled => "Switch on disabled",
            State::ReadyToSwitchOn => "Ready to switch on",
            State::SwitchedOn => "Switched on",
            State::OperationEnabled => "Operation enabled",
            State::QuickStopActive => "Quick stop active",
            State::FaultReactionActive => "Fault reaction active",
            State::Fault => "Fault",
        }
    }

    /// Fault reaction active or Fault.
    pub const fn is_fault(self) -> bool {
        matches!(self, State::FaultReactionActive | State::Fault)
    }

    /// The motor may be energised in this state: Operation enabled, Quick stop active, Fault
    /// reaction active.
    pub const fn is_energised(self) -> bool {
        matches!(
            self,
            State::OperationEnabled | State::QuickStopActive | State::FaultReactionActive
        )
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
