//! The EtherCAT master (the crate `ecdrive-ethercat`, re-exported): start-up, the cycle,
//! supervision. The applications built on it (demo, soak, tools) are in the package `ecdrive-cli`.

pub use ecdrive_ethercat::*;
