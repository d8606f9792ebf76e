//! The one registry of the drive profiles ecdrive knows, on both buses: the EtherCAT ones
//! looked up by identity or by name (and the report of a device none of them matches), the
//! CANopen ones by their identity objects.

use super::{DriveProfile, asda_a2, bdhde, blv_r, generic, lexium_mdrive, mr_j4_tm};
use crate::can::profile::CanDriveProfile;

/// Every known EtherCAT profile, in the order `ecdrive` lists them (the generic one is not
/// among them).
pub static PROFILES: &[&DriveProfile] = &[&mr_j4_tm::PROFILE, &bdhde::PROFILE];

/// Every known EtherCAT drive profile (the generic one is not among them).
pub fn all() -> &'static [&'static DriveProfile] {
    PROFILES
}

/// The profile of a device with this vendor ID and product code (any revision).
pub fn by_identity(vendor_id: u32, product_code: u32) -> Option<&'static DriveProfile> {
    PROFILES
        .iter()
        .copied()
        .find(|p| p.identity.matches(vendor_id, product_code))
}

/// The profile with this `--device` key or name (`mr-j4-tm`, `MR-J4-TM`, `bdhde`,
/// `generic-cia402`), ignoring ASCII case and surrounding blanks.
pub fn by_key(key: &str) -> Option<&'static DriveProfile> {
    let key = key.trim();
    PROFILES
        .iter()
        .copied()
        .chain(core::iter::once(&generic::GENERIC_CIA402))
        .find(|p| p.key.eq_ignore_ascii_case(key) || p.name.eq_ignore_ascii_case(key))
}

/// A device no profile matches.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown device: vendor 0x{vendor_id:08X}, product 0x{product_code:08X}, revision \
     0x{revision:08X}; ecdrive knows {known}; run it with the generic CiA 402 profile only if \
     you are sure it is a CiA 402 drive"
)]
pub struct UnknownDevice {
    /// Vendor ID read from the device.
    pub vendor_id: u32,
    /// Product code read from the device.
    pub product_code: u32,
    /// Revision read from the device.
    pub revision: u32,
    /// The known drives, as text.
    pub known: String,
}

/// The profile for a device: its own one, or, if there is none and `allow_generic` is set (the
/// user asked for it), [`generic::GENERIC_CIA402`]. Otherwise an error that names the identity.
pub fn identify(
    vendor_id: u32,
    product_code: u32,
    revision: u32,
    allow_generic: bool,
) -> Result<&'static DriveProfile, UnknownDevice> {
    if let Some(p) = by_identity(vendor_id, product_code) {
        return Ok(p);
    }
    if allow_generic {
        return Ok(&generic::GENERIC_CIA402);
    }
    Err(UnknownDevice {
        vendor_id,
        product_code,
        revision,
        known: PROFILES
            .iter()
            .map(|p| {
                format!(
                    "{} {} (vendor 0x{:08X}, product 0x{:08X})",
                    p.vendor, p.name, p.identity.vendor_id, p.identity.product_code
                )
            })
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// Every known CANopen profile, in the order the tools list them. The Lexium open- and
/// closed-loop models share their identity: only the open-loop profile is here (configure a
/// closed-loop drive with [`lexium_mdrive::PROFILE_CLOSED_LOOP`] explicitly).
pub static CANOPEN_PROFILES: &[&CanDriveProfile] =
    &[&blv_r::PROFILE, &asda_a2::PROFILE, &lexium_mdrive::PROFILE];

/// Which CANopen profile a node with these identity values matches (device type 1000h, vendor
/// 1018h:01, product 1018h:02).
pub fn canopen_by_identity(
    device_type: u32,
    vendor_id: u32,
    product: Option<u32>,
) -> Option<&'static CanDriveProfile> {
    CANOPEN_PROFILES
        .iter()
        .copied()
        .find(|p| p.identity.matches(device_type, vendor_id, product))
}
