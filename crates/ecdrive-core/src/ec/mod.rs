//! EtherCAT protocol definitions shared by the master and the software slave.
//!
//! Everything here describes the wire (ETG.1000): datagram commands, ESC register addresses, AL
//! states and status codes, and typed views over frames, datagrams and mailbox messages. Nothing
//! here does I/O.

pub mod al;
pub mod command;
pub mod frame;
pub mod mailbox;
pub mod register;
pub mod sii;
pub mod wkc;

pub use al::{AlState, AlStatus, AlStatusCode};
pub use command::Command;
pub use wkc::DatagramWkc;

/// The EtherType of EtherCAT frames.
pub const ETHERTYPE: u16 = 0x88A4;
