//! The profile of a drive, whatever its bus: one type, [`Profile`], with the part every layer
//! reads the same way (name, vendor, CiA 402 capabilities with the alarm table, object
//! dictionary, units) and the bus's own part `B`: `drives::EtherCat` for an EtherCAT drive
//! (`drives::DriveProfile`), `can::profile::CanOpen` for a CANopen one
//! (`can::profile::CanDriveProfile`).

use super::{DriveCaps, Units};
use crate::od::ObjectDesc;
use core::ops::Deref;

/// A drive ecdrive knows (see the [module documentation](self)). Profiles are `static`s or
/// `const`s; use them by reference. The bus part's fields read through the profile
/// (`profile.pdo_limits` is `profile.bus.pdo_limits`), so code for one bus names them
/// directly.
#[derive(Debug, Clone, Copy)]
pub struct Profile<B: 'static> {
    /// Short name used in messages and on the command line (`"MR-J4-TM"`, `"BLV-R"`).
    pub name: &'static str,
    /// Vendor name.
    pub vendor: &'static str,
    /// CiA 402 behaviour: state skipping, quick-stop options, mode rules, alarm table.
    pub caps: DriveCaps,
    /// The object dictionary as the manual lists it.
    pub dictionary: &'static [ObjectDesc],
    /// Units of the position, velocity and torque objects.
    pub units: Units,
    /// What only the drive's bus has.
    pub bus: B,
}

impl<B> Deref for Profile<B> {
    type Target = B;

    fn deref(&self) -> &B {
        &self.bus
    }
}
