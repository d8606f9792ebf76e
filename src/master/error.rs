//! Errors of the master, each naming the drive, the object or register, and the reason.

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
