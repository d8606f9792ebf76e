//! Device-control commands encoded in controlword bits 0–3 and 7.

use core::fmt;

use super::bits::ControlWord;

/// A device-control command (CiA 402 controlword bits 7, 3, 2, 1, 0).
///
/// | command | b7 | b3 | b2 | b1 | b0 | value | transitions |
/// |---|---|---|---|---|---|---|---|
/// | Shutdown | 0 | x | 1 | 1 | 0 | `0x0006` | 2, 6, 8 |
/// | Switch on | 0 | 0 | 1 | 1 | 1 | `0x0007` | 3 |
/// | Enable operation | 0 | 1 | 1 | 1 | 1 | `0x000F` | 4, 16 (and 3 + 4, see below) |
/// | Disable voltage | 0 | x | x | 0 | x | `0x0000` | 7, 9, 10, 12 |
/// | Quick stop | 0 | x | 0 | 1 | x | `0x0002` | 7, 10, 11 |
/// | Disable operation | 0 | 0 | 1 | 1 | 1 | `0x0007` | 5 |
/// | Fault reset | 0→1 | x | x | x | x | `0x0080` | 15 |
///
/// "x" bits are encoded as 0. The values are those of the MR-J4-TM (§5.1), BDHDE (§5.5) and
/// BLV-R (§6) tables. "Switch on" and "Disable operation" have the same bits; the state decides
/// which transition they cause. Fault reset acts on the 0 → 1 edge of bit 7; a planner produces
/// the edge by sending [`Command::DisableVoltage`] and then [`Command::FaultReset`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Command {
    /// Shutdown: to Ready to switch on (transitions 2, 6, 8).
    Shutdown,
    /// Switch on: Ready to switch on → Switched on (transition 3).
    SwitchOn,
    /// Enable operation: Switched on → Operation enabled (4), Quick stop active → Operation
    /// enabled (16, where supported). In Ready to switch on CiA 402 calls the same bits "switch on
    /// + enable operation" (3 then 4).
    EnableOperation,
    /// Disable voltage: to Switch on disabled (transitions 7, 9, 10, 12).
    DisableVoltage,
    /// Quick stop: Operation enabled → Quick stop active (11); Ready to switch on / Switched on
    /// → Switch on disabled (7, 10).
    QuickStop,
    /// Disable operation: Operation enabled → Switched on (transition 5). Same bits as
    /// [`Command::SwitchOn`].
    DisableOperation,
    /// Fault reset: bit 7 high. The reset happens on the rising edge (transition 15).
    FaultReset,
}

impl Command {
    /// Every command.
    pub const ALL: [Command; 7] = [
        Command::Shutdown,
        Command::SwitchOn,
        Command::EnableOperation,
        Command::DisableVoltage,
        Command::QuickStop,
        Command::DisableOperation,
        Command::FaultReset,
    ];

    /// The command's bits 0–3 and 7 (don't-care bits 0).
    pub const fn bits(self) -> u16 {
        match self {
            Command::Shutdown => 0x0006,
            Command::SwitchOn | Command::DisableOperation => 0x0007,
            Command::EnableOperation => 0x000F,
            Command::DisableVoltage => 0x0000,
            Command::QuickStop => 0x0002,
            Command::FaultReset => 0x0080,
        }
    }

    /// Write this command into `cw`: bits 0–3 and 7 are replaced, every other bit (mode-specific
    /// bits 4–6, halt, 9, reserved and manufacturer bits) is kept.
    pub const fn apply(self, cw: ControlWord) -> ControlWord {
        ControlWord::from_bits_retain((cw.bits() & !ControlWord::COMMAND_MASK) | self.bits())
    }

    /// The controlword with only this command's bits set.
    pub const fn controlword(self) -> ControlWord {
        ControlWord::from_bits_retain(self.bits())
    }

    /// Which command a controlword carries, by the CiA 402 table. Every value decodes: bit 7
    /// set → [`Command::FaultReset`] (whether it is an edge is the receiver's business); else bit
    /// 1 clear → disable voltage; else bit 2 clear → quick stop; else bit 0 clear → shutdown;
    /// else bit 3 clear → switch on (never [`Command::DisableOperation`], which has the same
    /// bits); else enable operation.
    pub const fn decode(cw: ControlWord) -> Command {
        let b = cw.bits();
        if b & 0x0080 != 0 {
            Command::FaultReset
        } else if b & 0x0002 == 0 {
            Command::DisableVoltage
        } else if b & 0x0004 == 0 {
            Command::QuickStop
        } else if b & 0x0001 == 0 {
            Command::Shutdown
        } else if b & 0x0008 == 0 {
            Command::SwitchOn
        } else {
            Command::EnableOperation
        }
    }

    /// The CiA 402 transition numbers this command triggers.
    pub const fn transitions(self) -> &'static [u8] {
        match self {
            Command::Shutdown => &[2, 6, 8],
            Command::SwitchOn => &[3],
            Command::EnableOperation => &[4, 16],
            Command::DisableVoltage => &[7, 9, 10, 12],
            Command::QuickStop => &[7, 10, 11],
            Command::DisableOperation => &[5],
            Command::FaultReset => &[15],
        }
    }

    /// The command's name as CiA 402 writes it.
    pub const fn name(self) -> &'static str {
        match self {
            Command::Shutdown => "Shutdown",
            Command::SwitchOn => "Switch on",
            Command::EnableOperation => "Enable operation",
            Command::DisableVoltage => "Disable voltage",
            Command::QuickStop => "Quick stop",
            Command::DisableOperation => "Disable operation",
            Command::FaultReset => "Fault reset",
        }
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
