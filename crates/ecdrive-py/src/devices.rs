//! The devices of a segment (or the drives of a CANopen bus) as a start found them.

use ecdrive::DriveRef;
use pyo3::prelude::*;

/// One drive as the last start found it.
#[derive(Clone)]
pub(crate) struct FoundDrive {
    pub drive: DriveRef,
    pub device: Device,
    pub dictionary: Option<&'static [ecdrive::od::ObjectDesc]>,
    /// Counts per second in one unit of the drive's velocity objects.
    pub velocity_scale: f64,
}

/// The drives and the other devices of a start.
pub(crate) type FoundOf = (Vec<FoundDrive>, Vec<Device>);

/// A device of the segment, as start-up found it.
#[pyclass(frozen, get_all, module = "ecdrive._ecdrive")]
#[derive(Clone)]
pub struct Device {
    /// Position on the segment (0 = first); a CANopen drive's node-ID.
    pub(crate) position: u16,
    /// Name (the profile's, or the SII's for a device no profile matches).
    pub(crate) name: String,
    pub(crate) vendor_id: u32,
    pub(crate) product_code: u32,
    pub(crate) revision: u32,
    pub(crate) serial: u32,
    pub(crate) alias: u16,
    /// The drive profile ecdrive runs it with (None: not a drive).
    pub(crate) profile: Option<String>,
    /// AL state when the list was made: INIT, PRE-OP, SAFE-OP, OP (+ERR); a CANopen drive's
    /// NMT state (OPERATIONAL while the master runs).
    pub(crate) state: String,
    /// Whether ecdrive drives it (a CiA 402 axis).
    pub(crate) is_drive: bool,
}

#[pymethods]
impl Device {
    fn __repr__(&self) -> String {
        format!(
            "Device(position={}, name={:?}, vendor_id=0x{:08X}, product_code=0x{:08X}, \
             revision=0x{:08X}, state={:?})",
            self.position, self.name, self.vendor_id, self.product_code, self.revision, self.state
        )
    }
}
