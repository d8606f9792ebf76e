//! NMT node control and NMT error control (CiA 301 §7.2.8): commands, states, and the one-byte
//! boot-up / heartbeat / node-guarding messages.
//!
//! Facts common to the three drives (BLV-R §4.1–4.3, ASDA-A2 §4.4, Lexium §3.6): the NMT frame
//! is COB-ID 000h with byte 0 = command specifier and byte 1 = node-ID (0 = all nodes); the error
//! control byte is 00h boot-up, 04h Stopped, 05h Operational, 7Fh Pre-operational, and node
//! guarding adds a toggle bit 7 that starts at 0 after reset communication.

use super::frame::{CanFrame, cob};
use core::fmt;

/// An NMT command specifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtCommand {
    /// 01h: start remote node → Operational.
    Start,
    /// 02h: stop remote node → Stopped.
    Stop,
    /// 80h: enter Pre-operational.
    EnterPreOperational,
    /// 81h: reset node (application and communication).
    ResetNode,
    /// 82h: reset communication.
    ResetCommunication,
}

impl NmtCommand {
    /// The command specifier byte.
    pub const fn cs(self) -> u8 {
        match self {
            Self::Start => 0x01,
            Self::Stop => 0x02,
            Self::EnterPreOperational => 0x80,
            Self::ResetNode => 0x81,
            Self::ResetCommunication => 0x82,
        }
    }

    /// The command for a specifier byte.
    pub const fn from_cs(cs: u8) -> Option<Self> {
        match cs {
            0x01 => Some(Self::Start),
            0x02 => Some(Self::Stop),
            0x80 => Some(Self::EnterPreOperational),
            0x81 => Some(Self::ResetNode),
            0x82 => Some(Self::ResetCommunication),
            _ => None,
        }
    }

    /// Stop and the two resets: the commands that take a drive out of Operational in a way that
    /// the ASDA-A2 (AL401) and the Lexium (error class 2) treat as a fault while the power stage
    /// is enabled. The master refuses them to an enabled drive.
    pub const fn disturbs_enabled_drive(self) -> bool {
        matches!(
            self,
            Self::Stop | Self::ResetNode | Self::ResetCommunication
        )
    }

    /// The command name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Start => "start remote node",
            Self::Stop => "stop remote node",
            Self::EnterPreOperational => "enter pre-operational",
            Self::ResetNode => "reset node",
            Self::ResetCommunication => "reset communication",
        }
    }

    /// The NMT frame addressed to `node` (0 = all nodes).
    pub fn frame(self, node: u8) -> CanFrame {
        CanFrame::from_parts(cob::NMT, [self.cs(), node & 0x7F, 0, 0, 0, 0, 0, 0], 2)
    }

    /// Decode an NMT frame: the command and the addressed node (0 = all). `None` for anything
    /// that is not a 2-byte data frame on COB-ID 0 with a known command.
    pub fn parse(frame: &CanFrame) -> Option<(Self, u8)> {
        if frame.id() != cob::NMT || frame.is_remote() {
            return None;
        }
        match frame.data() {
            [cs, node, ..] if *node <= 0x7F => Some((Self::from_cs(*cs)?, *node)),
            _ => None,
        }
    }
}

impl fmt::Display for NmtCommand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "NMT {} (0x{:02X})", self.name(), self.cs())
    }
}

/// The NMT state of a node, as its error-control messages report it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtState {
    /// 00h: the boot-up message (the node just entered Pre-operational after a reset).
    BootUp,
    /// 04h: Stopped.
    Stopped,
    /// 05h: Operational.
    Operational,
    /// 7Fh: Pre-operational.
    PreOperational,
}

impl NmtState {
    /// The state byte (bit 7, the guarding toggle, clear).
    pub const fn code(self) -> u8 {
        match self {
            Self::BootUp => 0x00,
            Self::Stopped => 0x04,
            Self::Operational => 0x05,
            Self::PreOperational => 0x7F,
        }
    }

    /// The state for bits 0–6 of an error-control byte.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code & 0x7F {
            0x00 => Some(Self::BootUp),
            0x04 => Some(Self::Stopped),
            0x05 => Some(Self::Operational),
            0x7F => Some(Self::PreOperational),
            _ => None,
        }
    }

    /// The state name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::BootUp => "boot-up",
            Self::Stopped => "Stopped",
            Self::Operational => "Operational",
            Self::PreOperational => "Pre-operational",
        }
    }

    /// SDO is served in this state (Pre-operational and Operational; a node that just sent its
    /// boot-up message is Pre-operational).
    pub const fn serves_sdo(self) -> bool {
        !matches!(self, Self::Stopped)
    }
}

impl fmt::Display for NmtState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A received NMT error-control message (COB-ID 700h + node, one data byte).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ErrorControl {
    /// The node.
    pub node: u8,
    /// The state.
    pub state: NmtState,
    /// Bit 7: the node-guarding toggle bit (always 0 in heartbeats and boot-up).
    pub toggle: bool,
}

/// Why an error-control frame cannot be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum ErrorControlError {
    /// Not 700h + node.
    #[error("COB-ID 0x{0:03X} is not an NMT error-control identifier (701h–77Fh)")]
    NotErrorControl(u16),
    /// A remote frame (a guarding request, not a reply).
    #[error("remote frame (a node-guarding request)")]
    Remote,
    /// Not exactly one data byte.
    #[error("error-control message of node {node} has {len} data bytes, expected 1")]
    Length {
        /// Node.
        node: u8,
        /// Data bytes.
        len: usize,
    },
    /// A state byte no CANopen state has.
    #[error("error-control message of node {node}: state byte 0x{byte:02X} is no NMT state")]
    UnknownState {
        /// Node.
        node: u8,
        /// The byte.
        byte: u8,
    },
}

impl ErrorControl {
    /// The frame a node sends: heartbeat/boot-up (toggle `false`) or a guarding reply.
    pub fn frame(node: u8, state: NmtState, toggle: bool) -> CanFrame {
        let byte = state.code() | if toggle { 0x80 } else { 0 };
        CanFrame::from_parts(cob::error_control(node), [byte, 0, 0, 0, 0, 0, 0, 0], 1)
    }

    /// The master's node-guarding request: a remote frame on 700h + node.
    pub fn guard_request(node: u8) -> CanFrame {
        CanFrame::remote(cob::error_control(node), 1).unwrap_or_default()
    }

    /// Decode an error-control data frame.
    pub fn parse(frame: &CanFrame) -> Result<Self, ErrorControlError> {
        let id = frame.id();
        if !(0x701..=0x77F).contains(&id) {
            return Err(ErrorControlError::NotErrorControl(id));
        }
        if frame.is_remote() {
            return Err(ErrorControlError::Remote);
        }
        let node = (id - 0x700) as u8;
        let [byte] = frame.data() else {
            return Err(ErrorControlError::Length {
                node,
                len: frame.data().len(),
            });
        };
        let state = NmtState::from_code(*byte)
            .ok_or(ErrorControlError::UnknownState { node, byte: *byte })?;
        Ok(Self {
            node,
            state,
            toggle: byte & 0x80 != 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_round_trip() {
        for c in [
            NmtCommand::Start,
            NmtCommand::Stop,
            NmtCommand::EnterPreOperational,
            NmtCommand::ResetNode,
            NmtCommand::ResetCommunication,
        ] {
            let f = c.frame(0x41);
            assert_eq!(f.id(), 0);
            assert_eq!(NmtCommand::parse(&f), Some((c, 0x41)));
        }
        assert_eq!(NmtCommand::Start.frame(0).data(), &[0x01, 0x00]);
        assert_eq!(
            NmtCommand::parse(&CanFrame::new(0, &[0x03, 1]).unwrap()),
            None
        );
        assert_eq!(NmtCommand::parse(&CanFrame::new(0, &[0x01]).unwrap()), None);
        assert!(NmtCommand::ResetCommunication.disturbs_enabled_drive());
        assert!(!NmtCommand::EnterPreOperational.disturbs_enabled_drive());
    }

    #[test]
    fn error_control_bytes() {
        let hb = ErrorControl::frame(5, NmtState::Operational, false);
        assert_eq!(hb.id(), 0x705);
        assert_eq!(hb.data(), &[0x05]);
        let g = ErrorControl::frame(5, NmtState::PreOperational, true);
        assert_eq!(g.data(), &[0xFF]);
        assert_eq!(
            ErrorControl::parse(&g).unwrap(),
            ErrorControl {
                node: 5,
                state: NmtState::PreOperational,
                toggle: true
            }
        );
        assert_eq!(
            ErrorControl::parse(&CanFrame::new(0x705, &[0x33]).unwrap()),
            Err(ErrorControlError::UnknownState {
                node: 5,
                byte: 0x33
            })
        );
        assert!(ErrorControl::parse(&ErrorControl::guard_request(5)).is_err());
        assert!(ErrorControl::parse(&CanFrame::new(0x705, &[]).unwrap()).is_err());
    }
}
