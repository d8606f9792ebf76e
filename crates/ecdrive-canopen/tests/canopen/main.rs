//! The CANopen master's tests that need nothing of the application.
//!
//! One test binary for the crate `ecdrive-canopen`: each module was a test file of its own.

mod canopen_socketcan;
