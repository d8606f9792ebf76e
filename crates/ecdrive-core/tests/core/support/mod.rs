//! Helpers of this test binary; those shared with other crates' tests are `ecdrive-testkit`'s.

pub mod cia402_drives;
pub mod cia402_servo;
pub mod cia402_sim;
pub use ecdrive_testkit::corpus;
