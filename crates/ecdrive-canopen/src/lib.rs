//! # ecdrive-canopen
//!
//! The CANopen (CiA 301) master: NMT, paced SDO client, SYNC producer, heartbeat consumer,
//! node guarding, EMCY consumer, drive configuration with PDO plans, the cycle, and the
//! SocketCAN and Unix-socket transports, through the same CiA 402 layer as the EtherCAT drives.
//! Built on `ecdrive-core` (the protocols are its `can` module, re-exported here); it
//! does not depend on the software slave (`ecdrive-sim`); the tests that run it against the
//! emulated nodes live in the root package.
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

// The core layers this crate builds on, under the paths the modules use.
#[cfg(test)]
pub(crate) use ecdrive_core::drives;
pub(crate) use ecdrive_core::{cia402, od, pdo};

pub mod can_socket;
pub mod drive;
pub mod error;
pub mod master;
pub mod motion;
pub mod pdo_plan;
pub mod unix_bus;

pub use ecdrive_core::can::{emcy, frame, nmt, profile, sdo, transport};

pub use drive::CanDrive;
pub use error::{CanError, CanErrorKind, NodeRef};
pub use frame::{CanFrame, FrameError, NodeId, Service};
pub use master::{DriveSetup, Master, MasterConfig, MasterEvent, Supervision};
pub use motion::{CycleThread, MotionSession};
pub use pdo_plan::PdoPlan;
pub use transport::{CanTransport, Hub, PortId, TransportError, VirtualBus, VirtualPort};
