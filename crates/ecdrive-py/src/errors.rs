//! The exceptions: one class per kind of failure, as the `ecdrive` command's exit codes class
//! them (2 input, 3 bus, 4 a drive refused, 5 a drive faulted), each carrying what the Rust
//! error carries.

use ecdrive::{ErrorKind, MasterError};
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::{PyErr, create_exception};

create_exception!(
    ecdrive,
    Error,
    PyException,
    "Any ecdrive failure. Attributes: `drive` (the drive's name, or None), `position` (its \
     segment position, or None), `step` (what was being done, naming the object or register), \
     `reason`, `kind` (the Rust ErrorKind's name), `abort_code` (an SDO abort code, or None), \
     `al_status_code` (an AL status code, or None)."
);
create_exception!(
    ecdrive,
    ConfigError,
    Error,
    "Input that does not fit: a bad target, run file or value, a position out of range, a \
     configuration the drive cannot take (exit code 2 of the `ecdrive` command)."
);
create_exception!(
    ecdrive,
    BusError,
    Error,
    "The bus or link failed: nothing answers, a timeout, the segment was lost, the session \
     ended (exit code 3)."
);
create_exception!(
    ecdrive,
    DriveRefused,
    Error,
    "A drive refused: an SDO abort, an AL state change refused, a command the axis did not \
     take, a state not reached in time (exit code 4)."
);
create_exception!(
    ecdrive,
    DriveFault,
    Error,
    "A drive faulted: a fault, a following error; the axes were stopped and disabled (exit \
     code 5)."
);

/// The classes, as the command's exit codes class failures.
pub(crate) use ecdrive::ErrorClass as Class;

/// A failure to raise (boxed: it travels in `Result`s through every wait).
#[derive(Debug, Clone)]
pub struct Failure(Box<Details>);

impl std::ops::Deref for Failure {
    type Target = Details;
    fn deref(&self) -> &Details {
        &self.0
    }
}

impl std::ops::DerefMut for Failure {
    fn deref_mut(&mut self) -> &mut Details {
        &mut self.0
    }
}

/// A failure's class, message and attributes.
#[derive(Debug, Clone)]
pub struct Details {
    pub class: Class,
    pub message: String,
    pub drive: Option<(u16, String)>,
    pub step: String,
    pub reason: String,
    pub kind: String,
    pub abort_code: Option<u32>,
    pub al_status_code: Option<u16>,
}

impl Failure {
    /// A failure of `class` outside the master's own errors (a wait, a refused command).
    pub fn new(
        class: Class,
        drive: Option<&ecdrive::DriveRef>,
        step: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        let (step, reason) = (step.into(), reason.into());
        let drive = drive.map(|d| (d.position, d.name.clone()));
        let message = match &drive {
            Some((p, n)) => format!("drive {p} ({n}): {step}: {reason}"),
            None => format!("{step}: {reason}"),
        };
        Self(Box::new(Details {
            class,
            message,
            drive,
            step,
            reason,
            kind: format!("{class:?}"),
            abort_code: None,
            al_status_code: None,
        }))
    }

    /// A configuration error without a drive.
    pub fn config(step: impl Into<String>, reason: impl std::fmt::Display) -> Self {
        Self::new(Class::Input, None, step, reason.to_string())
    }
}

impl From<MasterError> for Failure {
    fn from(e: MasterError) -> Self {
        let (abort_code, al_status_code) = match e.kind {
            ErrorKind::Sdo(c) => (Some(c.0), None),
            ErrorKind::AlState(c) => (None, Some(c.0)),
            _ => (None, None),
        };
        Self(Box::new(Details {
            class: e.kind.class(),
            message: e.to_string(),
            drive: e.drive.as_ref().map(|d| (d.position, d.name.clone())),
            step: e.step.clone(),
            reason: e.reason.clone(),
            kind: match e.kind {
                ErrorKind::Sdo(_) => "Sdo".to_string(),
                ErrorKind::AlState(_) => "AlState".to_string(),
                k => format!("{k:?}"),
            },
            abort_code,
            al_status_code,
        }))
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> Self {
        let f = *f.0;
        let err = match f.class {
            Class::Input => ConfigError::new_err(f.message.clone()),
            Class::Bus => BusError::new_err(f.message.clone()),
            Class::Refused => DriveRefused::new_err(f.message.clone()),
            Class::Fault => DriveFault::new_err(f.message.clone()),
        };
        Python::attach(|py| {
            let v = err.value(py);
            let _ = v.setattr("drive", f.drive.as_ref().map(|d| d.1.clone()));
            let _ = v.setattr("position", f.drive.as_ref().map(|d| d.0));
            let _ = v.setattr("step", f.step);
            let _ = v.setattr("reason", f.reason);
            let _ = v.setattr("kind", f.kind);
            let _ = v.setattr("abort_code", f.abort_code);
            let _ = v.setattr("al_status_code", f.al_status_code);
        });
        err
    }
}
