//! The classes of failure both masters' errors fall into: what the `ecdrive` command's exit
//! codes and the Python package's exceptions tell apart.

/// What kind of failure, for the user: input to fix, a bus to check, a drive that refused, a
/// drive that faulted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ErrorClass {
    /// Input that does not fit: a bad argument, configuration or ESI/EDS file, a position or
    /// value out of range, a device no profile matches (exit code 2, `ConfigError`).
    Input,
    /// The bus or link: nothing answers, a timeout, the interface is missing, the segment was
    /// lost (exit code 3, `BusError`).
    Bus,
    /// A drive refused: an SDO abort, an AL state change or NMT command refused, a setting it
    /// holds fixed, a state not reached (exit code 4, `DriveRefused`).
    Refused,
    /// A drive faulted: a fault, a following error (exit code 5, `DriveFault`).
    Fault,
}
