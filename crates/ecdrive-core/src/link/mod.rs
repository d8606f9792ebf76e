//! Ethernet frame I/O shared by the master and the software slave.
//!
//! - [`RawSocket`]: an `AF_PACKET` socket bound to one interface and EtherType 0x88A4, with
//!   preallocated buffers and timed receive; used by the slave to serve a segment and by the
//!   master as a client.
//! - [`FrameLink`]: the synchronous send/receive interface both the raw socket and the
//!   in-process link (`sim::transport::SegmentLink`) implement, so a master's cycle thread can
//!   run against either.
//! - [`netns`]: network namespaces and veth pairs for tests and the jitter harness, and the
//!   shared root check for tests that need them.

pub mod netns;
mod raw;
mod ring;

pub use raw::RawSocket;

use std::time::Duration;

/// Errors of frame I/O, each naming the interface and what went wrong.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The interface does not exist.
    #[error("interface {interface} does not exist")]
    NoSuchInterface {
        /// Interface name.
        interface: String,
    },
    /// The interface name is not valid.
    #[error("interface name {interface:?} is not valid (1–15 bytes, no '/', ':' or whitespace)")]
    InvalidName {
        /// Interface name.
        interface: String,
    },
    /// No permission for raw sockets.
    #[error("raw sockets need CAP_NET_RAW (run as root): opening {interface} failed")]
    PermissionDenied {
        /// Interface name.
        interface: String,
    },
    /// The interface is down.
    #[error("interface {interface} is down")]
    InterfaceDown {
        /// Interface name.
        interface: String,
    },
    /// A frame larger than the link can carry.
    #[error("frame of {len} bytes does not fit {interface} (at most {max} bytes)")]
    FrameTooLarge {
        /// Interface name.
        interface: String,
        /// Frame length.
        len: usize,
        /// Largest frame.
        max: usize,
    },
    /// A received frame was larger than the receive buffer and was dropped.
    #[error("received a {len}-byte frame on {interface}, larger than the {capacity}-byte buffer")]
    Truncated {
        /// Interface name.
        interface: String,
        /// Real frame length.
        len: usize,
        /// Buffer size.
        capacity: usize,
    },
    /// Another I/O error.
    #[error("{op} on {interface} failed: {source}")]
    Io {
        /// Interface name.
        interface: String,
        /// What was being done.
        op: &'static str,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The in-process peer is gone or cannot take the frame.
    #[error("{0}")]
    Peer(String),
}

/// Synchronous frame I/O: what a master's cycle thread needs from a link.
pub trait FrameLink {
    /// Send one Ethernet frame.
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError>;

    /// Receive one Ethernet frame into `buf`, waiting at most `timeout` (`None`: wait
    /// forever). Returns the frame length, or `None` on timeout.
    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError>;

    /// A short name for messages: the interface name, or "in-process segment".
    fn describe(&self) -> String {
        "link".into()
    }
}
