//! The EtherCAT applications: the demo, the soak, the recovery operator they share, and the
//! tools behind the CLI's commissioning commands.

pub mod demo;
pub mod recovery;
pub mod soak;
pub mod tools;
