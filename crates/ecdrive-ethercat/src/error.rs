//! Errors of the master, each naming the drive, the object or register, and the reason.

use crate::ec::AlStatusCode;
use crate::od::SdoAbortCode;
use core::fmt;

/// A drive as error messages name it: its position on the segment and its name.
#[derive(Debug, Clone, PartialEq, Eq, Hash, serde::Serialize)]
pub struct DriveRef {
    /// Position on the segment (0 = first).
    pub position: u16,
    /// Name (profile name, or the SII name for unknown devices).
    pub name: String,
}

impl fmt::Display for DriveRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "drive {} ({})", self.position, self.name)
    }
}

/// What kind of failure, for callers that react differently (exit codes, retries).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ErrorKind {
    /// Nothing answered, or the segment does not look as configured.
    Discovery,
    /// A device no profile matches (and the generic profile was not allowed).
    UnknownDevice,
    /// The configuration is invalid (mapping over a limit, cycle time not allowed, …); found
    /// before anything was written.
    Config,
    /// The drive aborted an SDO.
    Sdo(SdoAbortCode),
    /// The drive refused an EtherCAT state change.
    AlState(AlStatusCode),
    /// Distributed clocks did not settle.
    DcSettle,
    /// A setting the drive holds fixed (a read-only synchronisation object, say) does not fit
    /// the configuration.
    Incompatible,
    /// The device refused a request outside SDO and the state machine: it ended a file
    /// access with an FoE error, or its EEPROM did not acknowledge a write.
    Refused,
    /// The bus did not answer in time.
    Timeout,
    /// The link (interface, socket) failed.
    Link,
    /// The drive reported a fault.
    DriveFault,
    /// Anything else ethercrab reported.
    Bus,
}

impl ErrorKind {
    /// The class of failure (the `ecdrive` command's exit code, the Python exception).
    pub fn class(&self) -> ecdrive_core::ErrorClass {
        use ecdrive_core::ErrorClass;
        match self {
            ErrorKind::Config | ErrorKind::UnknownDevice => ErrorClass::Input,
            ErrorKind::Discovery | ErrorKind::Timeout | ErrorKind::Link | ErrorKind::Bus => {
                ErrorClass::Bus
            }
            ErrorKind::Sdo(_)
            | ErrorKind::AlState(_)
            | ErrorKind::DcSettle
            | ErrorKind::Incompatible
            | ErrorKind::Refused => ErrorClass::Refused,
            ErrorKind::DriveFault => ErrorClass::Fault,
        }
    }
}

/// A failed step of the master.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{step}: {reason}", .drive.as_ref().map(|d| format!("{d}: ")).unwrap_or_default())]
pub struct MasterError {
    /// The drive, if the step concerned one.
    pub drive: Option<DriveRef>,
    /// What was being done, naming the object or register ("writing 0x1C32:02 (cycle time)").
    pub step: String,
    /// Why it failed.
    pub reason: String,
    /// The kind of failure.
    pub kind: ErrorKind,
}

impl MasterError {
    /// An error.
    pub fn new(
        drive: Option<&DriveRef>,
        step: impl Into<String>,
        kind: ErrorKind,
        reason: impl fmt::Display,
    ) -> Self {
        Self {
            drive: drive.cloned(),
            step: step.into(),
            reason: reason.to_string(),
            kind,
        }
    }
}

/// Convert an ethercrab error from a step.
pub fn bus_error(
    drive: Option<&DriveRef>,
    step: impl Into<String>,
    e: ethercrab::error::Error,
) -> MasterError {
    MasterError::new(drive, step, ErrorKind::Bus, e)
}
