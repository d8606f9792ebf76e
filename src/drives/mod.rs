//! Drive profiles: one file per drive, identity, defaults, quirks and alarm tables as data, and
//! the registry that finds a profile by identity or by name.
//!
//! Each profile is data plus rustdoc, no logic: the generic layers (`pdo`, `cia402`, `master`,
//! `sim`) read these constants. Every value a manual does not state is labelled **MANUAL GAP**
//! or **\[REC\]** where it is declared, and **DISCREPANCY** marks where a manual contradicts
//! itself, with the reading used; each drive file collects them in a section "Values that are
//! ours" at its end.
//!
//! - [`mr_j4_tm`]: Mitsubishi MR-J4-_TM_ (EtherCAT), [`mr_j4_tm::PROFILE`].
//! - [`bdhde`]: Servotronix BDHDE (EtherCAT, EB models), [`bdhde::PROFILE`].
//! - [`generic`]: plain CiA 402 ([`generic::GENERIC_CIA402`]), for devices ecdrive does not
//!   know, used only when the user asks for it.
//!
//! ```
//! use ecdrive::drives;
//!
//! let p = drives::by_identity(0x0000_0A1E, 0x0000_0201).unwrap();
//! assert_eq!(p.key, "mr-j4-tm");
//! assert_eq!(drives::by_key("bdhde").unwrap().name, "BDHDE");
//! let unknown = drives::identify(0x1234, 0x5678, 1, false).unwrap_err();
//! assert!(unknown.to_string().contains("vendor 0x00001234, product 0x00005678"));
//! // Only on request: the generic profile.
//! assert_eq!(drives::identify(0x1234, 0x5678, 1, true).unwrap().key, "generic-cia402");
//! ```

pub mod bdhde;
pub mod generic;
pub mod mr_j4_tm;
pub(crate) mod od_table;
pub mod profile;

pub use profile::{
    CycleCounter, CycleTimeError, CycleTimeObject, CycleTimes, DriveProfile, IdentityMatch,
    OutputDefault, StartupSdo, StartupWhen, SyncSpec, SyncWrite, Units,
};

static ALL: [&DriveProfile; 2] = [&mr_j4_tm::PROFILE, &bdhde::PROFILE];

/// Every drive profile ecdrive knows (the generic one is not among them).
pub fn all() -> &'static [&'static DriveProfile] {
    &ALL
}

/// The profile of the drive with this vendor ID and product code (any revision).
pub fn by_identity(vendor_id: u32, product_code: u32) -> Option<&'static DriveProfile> {
    ALL.iter()
        .copied()
        .find(|p| p.matches(vendor_id, product_code))
}

/// The profile with this `--device` key (`mr-j4-tm`, `bdhde`, `generic-cia402`), ignoring ASCII
/// case.
pub fn by_key(key: &str) -> Option<&'static DriveProfile> {
    let key = key.trim();
    ALL.iter()
        .copied()
        .chain(core::iter::once(&generic::GENERIC_CIA402))
        .find(|p| p.key.eq_ignore_ascii_case(key))
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
        known: ALL
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
