//! Errors of the CANopen master. Each names the node (and its drive, if known), the object, and
//! the reason.

use super::nmt::NmtCommand;
use super::pdo_plan::PdoPlanError;
use super::sdo::{AbortText, SdoError};
use super::transport::TransportError;
use crate::cia402::{AxisError, State};
use crate::od::{ObjectAddress, ValueError};
use crate::pdo::FieldError;
use core::fmt;

/// A node as messages name it: `node 3 (BLV-R)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct NodeRef {
    /// Node-ID (0 = broadcast).
    pub id: u8,
    /// Drive name, if the node is identified.
    pub drive: Option<&'static str>,
}

impl fmt::Display for NodeRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.id == 0 {
            return f.write_str("all nodes");
        }
        write!(f, "node {} (0x{:02X}", self.id, self.id)?;
        if let Some(d) = self.drive {
            write!(f, ", {d}")?;
        }
        f.write_str(")")
    }
}

/// What went wrong.
#[derive(Debug, thiserror::Error)]
pub enum CanErrorKind {
    /// The node aborted an SDO transfer.
    #[error("SDO abort {0}")]
    Abort(AbortText),
    /// Another SDO failure (timeout, protocol).
    #[error(transparent)]
    Sdo(SdoError),
    /// The bus failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// An NMT command refused because the drive's power stage is enabled.
    #[error(
        "{cmd} refused: the drive is in {state} (power stage enabled); disable it through the \
         controlword first (ASDA-A2: AL401, Lexium: error class 2)"
    )]
    NmtRefused {
        /// The command.
        cmd: NmtCommand,
        /// The state the drive reported.
        state: State,
    },
    /// No boot-up message.
    #[error("no boot-up message within {0} ms")]
    NoBootUp(u64),
    /// The node is not known to the master (never seen, or not configured as a drive).
    #[error("{0}")]
    NotReady(String),
    /// The node's identity does not match the profile.
    #[error("identity mismatch: {0}")]
    Identity(String),
    /// A drive parameter does not allow enabling and cannot be written.
    #[error("{why} (0x{addr_index:04X}:{addr_sub:02X} = 0x{value:X})")]
    Precondition {
        /// Why it matters.
        why: &'static str,
        /// Object index.
        addr_index: u16,
        /// Sub-index.
        addr_sub: u8,
        /// The value read.
        value: u64,
    },
    /// The PDO plan breaks the drive's rules.
    #[error(transparent)]
    Pdo(#[from] PdoPlanError),
    /// A value does not fit the object's type.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// The object's data type is unknown (not in the profile's dictionary and none given).
    #[error("data type unknown: the object is not in the drive's dictionary; give the type")]
    UnknownType,
    /// The axis engine refused a request.
    #[error(transparent)]
    Axis(#[from] AxisError),
    /// A mapped CiA 402 object cannot be read as its type.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// The drive does not follow the controlword because statusword bit 9 (remote) is 0.
    #[error(
        "statusword bit 9 (remote) is 0: the drive ignores the controlword except quick stop, \
         fault reset and halt (BLV-R: S-ON input active or the support software operates the \
         drive)"
    )]
    RemoteOff,
    /// A wait ran out.
    #[error("{0}")]
    Timeout(String),
    /// An invalid argument.
    #[error("{0}")]
    Invalid(String),
}

/// A CANopen error with its node and object.
#[derive(Debug, thiserror::Error)]
#[error("{node}{}: {kind}", .address.map(|a| format!(" {a}")).unwrap_or_default())]
pub struct CanError {
    /// The node.
    pub node: NodeRef,
    /// The object, if the error is about one.
    pub address: Option<ObjectAddress>,
    /// What went wrong.
    pub kind: CanErrorKind,
}

impl CanError {
    /// The class of failure (the `ecdrive` command's exit code, the Python exception): a
    /// drive's refusal (an SDO abort, an NMT command refused), input to fix (a value that does
    /// not fit, an identity that is not the profile's: the configuration names another drive),
    /// else the bus.
    pub fn class(&self) -> ecdrive_core::ErrorClass {
        use ecdrive_core::ErrorClass;
        match &self.kind {
            CanErrorKind::Abort(_) | CanErrorKind::NmtRefused { .. } => ErrorClass::Refused,
            CanErrorKind::Identity(_) => ErrorClass::Input,
            CanErrorKind::Sdo(s) if s.abort_code().is_some() => ErrorClass::Refused,
            CanErrorKind::Value(_) | CanErrorKind::UnknownType | CanErrorKind::Invalid(_) => {
                ErrorClass::Input
            }
            _ => ErrorClass::Bus,
        }
    }

    /// An error of `node` about `address`.
    pub fn new(node: NodeRef, address: Option<ObjectAddress>, kind: CanErrorKind) -> Self {
        Self {
            node,
            address,
            kind,
        }
    }

    /// The abort code, if the node aborted an SDO.
    pub fn abort_code(&self) -> Option<crate::od::SdoAbortCode> {
        match &self.kind {
            CanErrorKind::Abort(t) => Some(t.code),
            CanErrorKind::Sdo(e) => e.abort_code(),
            _ => None,
        }
    }
}
