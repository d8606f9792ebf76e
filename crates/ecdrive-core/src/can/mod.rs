//! CANopen (CiA 301) wire vocabulary and protocols, without I/O policy: the counterpart of
//! [`crate::ec`] for the CAN bus. Both the CANopen master and the emulated CANopen drives of
//! the software slave are built on it, so neither depends on the other.
//!
//! | module | what |
//! |---|---|
//! | [`frame`] | classic CAN frames, the pre-defined connection set, node-IDs |
//! | [`nmt`], [`sdo`], [`emcy`] | the protocols as typed views and pure state machines (SDO client and server) |
//! | [`transport`] | [`CanTransport`] (send, receive with timeout, time) and the in-process virtual bus [`Hub`] / [`VirtualBus`] |
//! | [`profile`] | the CANopen drive-profile type and `const` dictionary builders |

pub mod emcy;
pub mod frame;
pub mod nmt;
pub mod profile;
pub mod sdo;
pub mod transport;

pub use frame::{CanFrame, FrameError, NodeId, Service};
pub use transport::{CanTransport, Hub, PortId, TransportError, VirtualBus, VirtualPort};
