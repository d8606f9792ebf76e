//! # ecdrive-cli
//!
//! The `ecdrive` command and the applications behind it, built on the library façade
//! [`ecdrive`]: the EtherCAT demo, soak, recovery operator and commissioning tools
//! ([`app::ethercat`]), the CANopen demo and tools ([`app::canopen`]), the `ecdrive run`
//! configuration file ([`app::config`]) and the cycle-jitter harness ([`app::harness`]).
//!
//! This package is not published: it is the application, not a library. Its library target
//! exists so that the binary and this package's tests (`tests/app/`) share the applications.
//! They may use every layer; no layer uses them.
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

// The library's layers under the paths the applications use (`crate::sim`, `crate::master`, …).
pub(crate) use ecdrive::*;

pub mod app;
