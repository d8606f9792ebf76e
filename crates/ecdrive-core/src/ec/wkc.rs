//! The working counter of a logical datagram, as a master reports it when it is wrong.

/// A logical datagram whose working counter is wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct DatagramWkc {
    /// Its number in the reply, from 1.
    pub index: u8,
    /// How many logical datagrams the reply had.
    pub of: u8,
    /// Logical start address.
    pub address: u32,
    /// Length in bytes.
    pub len: u16,
    /// Working counter received.
    pub got: u16,
    /// Working counter expected.
    pub expected: u16,
    /// Lowest and highest position of the devices it covers.
    pub devices: Option<(u16, u16)>,
}
