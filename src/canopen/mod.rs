//! The CANopen master (the crate `ecdrive-canopen`, re-exported): the same CiA 402 layer over
//! CANopen. The applications built on it (demo, tools) are in the application layer, `app`.

pub use ecdrive_canopen::*;
