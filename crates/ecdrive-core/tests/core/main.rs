//! The core layers' tests: CiA 402, PDOs, ESI and EDS files (the vendor corpora among them), the drive profiles.
//!
//! One test binary for the crate `ecdrive-core`: each module was a test file of its own.

mod support;

mod cia402_axis;
mod cia402_bits;
mod cia402_device;
mod cia402_error_code;
mod cia402_planner;
mod drives_profiles;
mod eds_corpus;
mod esi_drives;
mod esi_fuzz;
mod esi_vendor;
mod pdo_image;
mod pdo_layout;
mod pdo_limits;
mod pdo_remap;
