//! The CANopen master (the crate `ecdrive-canopen`, re-exported): the same CiA 402 layer over
//! CANopen. The applications built on it (demo, tools) are in the package `ecdrive-cli`.

pub use ecdrive_canopen::*;
