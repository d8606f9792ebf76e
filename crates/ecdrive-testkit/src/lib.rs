//! # ecdrive-testkit
//!
//! What the test binaries of ecdrive's crates share (a development dependency only; nothing
//! ships with it):
//!
//! - [`corpus`]: the real vendor ESI and EDS files beside the checkout;
//! - [`oracle`]: the manuals' facts (`tests/manual_facts/`), never the emulation's constants;
//! - [`wire`]: a small synchronous master on the wire of an in-process segment;
//! - [`generic`]: the master's profile for the software slave's generic CoE device;
//! - [`links`]: links around a link that watch or alter what a master sends;
//! - [`python_master`]: SOEM (pysoem) and KickCAT as independent masters over veth;
//! - [`source_scan`]: reading the sources for the layering checks.
#![allow(missing_docs)]

pub mod corpus;
pub mod generic;
pub mod links;
pub mod oracle;
pub mod python_master;
pub mod source_scan;
pub mod wire;

/// The repository's root (the workspace): where `tests/manual_facts/` and the corpora beside
/// the checkout are found from any crate's tests.
pub fn repo() -> &'static std::path::Path {
    std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}
