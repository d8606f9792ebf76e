//! The applications built on the library, behind the `ecdrive` command: the EtherCAT demo, soak,
//! recovery operator and commissioning tools ([`ethercat`]), the CANopen demo and tools
//! ([`canopen`]), the `ecdrive run` configuration file ([`config`]) and the cycle-jitter harness
//! ([`harness`]). They may use every layer; no layer uses them.

pub mod canopen;
pub mod capture;
pub mod config;
pub mod ethercat;
pub mod harness;
pub mod plot;
pub mod version;
