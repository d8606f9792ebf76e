//! Helpers of this test binary; those shared with other crates' tests are `ecdrive-testkit`'s.

pub use ecdrive_testkit::{corpus, oracle, python_master, source_scan, wire};
