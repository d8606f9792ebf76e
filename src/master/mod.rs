//! The EtherCAT master ([`ecdrive_ethercat`], re-exported here under the same paths) and the
//! applications built on it: the demo, the soak run, recovery and the tools behind the CLI
//! commands.

pub use ecdrive_ethercat::*;

pub mod demo;
pub mod recovery;
pub mod soak;
pub mod tools;
