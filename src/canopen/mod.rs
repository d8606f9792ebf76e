//! CANopen (CiA 301) master and the CANopen drives, through the same [`crate::cia402`] layer.
//!
//! Work in progress (issue 9).

pub mod can_socket;
pub mod demo;
pub mod drive;
pub mod emcy;
pub mod emu;
pub mod error;
pub mod frame;
pub mod master;
pub mod nmt;
pub mod pdo_plan;
pub mod profile;
pub mod sdo;
pub mod tools;
pub mod transport;
pub mod unix_bus;

pub use frame::{CanFrame, FrameError, NodeId, Service};
pub use transport::{CanTransport, Hub, PortId, TransportError, VirtualBus, VirtualPort};
