//! # ecdrive-ethercat
//!
//! The EtherCAT master: ethercrab integration, start-up, PDO and DC configuration, the cyclic
//! loop, supervision. Built on `ecdrive-core`; the software slave is only a dev-dependency of
//! its tests, never a normal one.
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

// The core layers this crate builds on, under the paths the modules use.
pub(crate) use ecdrive_core::{cia402, drives, ec, link, od, pdo, rt};

pub mod bus;
pub mod coe;
pub mod cycle;
pub mod error;
pub mod exec;
pub mod history;
pub mod io;
pub mod program;
pub mod session;
pub mod setpoint;
pub mod startup;
pub mod telemetry;
