//! Drive profiles: one file per drive, identity, defaults, quirks and alarm tables as data.
//!
//! Each profile is data plus rustdoc, no logic: the generic layers (`pdo`, `cia402`, `master`,
//! `sim`) read these constants. Every value a manual does not state is labelled **MANUAL GAP**
//! or **\[REC\]** where it is declared, and **DISCREPANCY** marks where a manual contradicts
//! itself, with the reading used.
//!
//! - [`mr_j4_tm`]: Mitsubishi MR-J4-_TM_ (EtherCAT).
//! - [`bdhde`]: Servotronix BDHDE (EtherCAT, EB models).
//! - [`blv_r`]: Oriental Motor BLV series R type (CANopen).
//! - [`asda_a2`]: Delta ASDA-A2 (CANopen).
//! - [`lexium_mdrive`]: Schneider Electric Lexium MDrive (CANopen).

pub mod asda_a2;
pub mod bdhde;
pub mod blv_r;
pub mod lexium_mdrive;
pub mod mr_j4_tm;
pub mod profile;
mod registry;

pub use registry::{all, by_identity, by_key};

pub use profile::{
    CycleCounter, CycleTimeObject, CycleTimes, DriveProfile, IdentityMatch, OutputDefault,
    StartupSdo, StartupWhen, SyncSpec, Units,
};
