//! The EtherCAT master (the crate `ecdrive-ethercat`, re-exported): start-up, the cycle,
//! supervision. The applications built on it (demo, soak, tools) are in the application layer, `app`.

pub use ecdrive_ethercat::*;
