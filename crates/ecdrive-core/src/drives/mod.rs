//! Drive profiles: one file per drive, identity, defaults, quirks and alarm tables as data, and
//! the registry that finds a profile by identity or by name.
//!
//! Each profile is data plus rustdoc, no logic: the generic layers (`pdo`, `cia402`, `master`,
//! `sim`) read these constants. Every value a manual does not state is labelled **MANUAL GAP**
//! or **\[REC\]** where it is declared, and **DISCREPANCY** marks where a manual contradicts
//! itself, with the reading used; each drive file collects them in a section "Values that are
//! ours" at its end.
//!
//! EtherCAT drives, in the registry ([`all`], [`by_identity`], [`by_key`], [`identify`]):
//! - [`mr_j4_tm`]: Mitsubishi MR-J4-_TM_ (EtherCAT), [`mr_j4_tm::PROFILE`].
//! - [`bdhde`]: Servotronix BDHDE (EtherCAT, EB models), [`bdhde::PROFILE`].
//! - [`generic`]: plain CiA 402 ([`generic::GENERIC_CIA402`]), for devices ecdrive does not
//!   know, used only when the user asks for it.
//!
//! CANopen drives, in the same registry ([`CANOPEN_PROFILES`], [`canopen_by_identity`]):
//! - [`blv_r`]: Oriental Motor BLV series R type (CANopen).
//! - [`asda_a2`]: Delta ASDA-A2 (CANopen).
//! - [`lexium_mdrive`]: Schneider Electric Lexium MDrive (CANopen).
//! - [`eds_can`]: any CiA 402 drive from its EDS file, and a built-in profile refined by its
//!   vendor's file.
//!
//! ```
//! use ecdrive_core::drives;
//!
//! let p = drives::by_identity(0x0000_0A1E, 0x0000_0201).unwrap();
//! assert_eq!(p.key, "mr-j4-tm");
//! assert_eq!(drives::by_key("bdhde").unwrap().name, "BDHDE");
//! let unknown = drives::identify(0x1234, 0x5678, 1, false).unwrap_err();
//! assert!(unknown.to_string().contains("vendor 0x00001234, product 0x00005678"));
//! // Only on request: the generic profile.
//! assert_eq!(drives::identify(0x1234, 0x5678, 1, true).unwrap().key, "generic-cia402");
//! ```

pub mod asda_a2;
pub mod bdhde;
pub mod blv_r;
pub mod eds_can;
pub mod esi_profile;
pub mod generic;
pub mod lexium_mdrive;
pub mod mr_j4_tm;
pub(crate) mod od_table;
pub mod profile;
mod registry;

pub use registry::{
    CANOPEN_PROFILES, UnknownDevice, all, by_identity, by_key, canopen_by_identity, identify,
};

pub use profile::{
    CycleCounter, CycleTimeError, CycleTimeObject, CycleTimes, DriveProfile, EtherCat,
    IdentityMatch, InitCommand, ModeGroup, ModeSelector, OutputDefault, Rating, Ratings,
    StartupSdo, StartupWhen, StatusFlag, SyncSpec, SyncWrite, Units, interpolation_cycle_ns,
    interpolation_standard_form,
};
