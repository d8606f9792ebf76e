//! The profiles ecdrive knows, looked up by identity or by name.

use super::DriveProfile;

/// Every known profile, in the order `ecdrive` lists them.
pub static PROFILES: &[&DriveProfile] = &[];

/// Every known profile.
pub fn all() -> &'static [&'static DriveProfile] {
    PROFILES
}

/// The profile of a device with this vendor ID and product code.
pub fn by_identity(vendor_id: u32, product_code: u32) -> Option<&'static DriveProfile> {
    PROFILES
        .iter()
        .copied()
        .find(|p| p.identity.matches(vendor_id, product_code))
}

/// The profile with this `--device` key or name (case-insensitive).
pub fn by_key(key: &str) -> Option<&'static DriveProfile> {
    PROFILES
        .iter()
        .copied()
        .find(|p| p.key.eq_ignore_ascii_case(key) || p.name.eq_ignore_ascii_case(key))
}
