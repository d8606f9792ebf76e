//! The EtherCAT master: ethercrab integration, start-up, PDO and DC configuration, the cyclic loop.

pub mod bus;
pub mod coe;
pub mod cycle;
pub mod demo;
pub mod error;
pub mod exec;
pub mod history;
pub mod io;
pub mod program;
pub mod recovery;
pub mod session;
pub mod setpoint;
pub mod soak;
pub mod startup;
pub mod telemetry;
pub mod tools;
