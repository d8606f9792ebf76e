//! Typed views over EtherCAT frames and datagrams (ETG.1000.4 §5).
//!
//! An EtherCAT frame on the wire is an Ethernet II frame with EtherType 0x88A4 (optionally behind
//! one 802.1Q VLAN tag), a 2-byte EtherCAT header, and one or more datagrams:
//!
//! ```text
//! dst(6) src(6) type(2)=0x88A4 | ecat header u16: len(11) res(1) type(4)
//!   | datagram: cmd u8, idx u8, address u32, len u16 (len 11, res 3, C 1, M 1), irq u16, data[len], wkc u16
//!   | datagram …
//! ```
//!
//! The views here follow the smoltcp style: a `View<T: AsRef<[u8]>>` wraps a buffer, a checked
//! constructor verifies that every accessor is in bounds, and the accessors never panic.
//! [`EthercatFrame::check`] walks the whole datagram chain once so that a frame that passes it
//! can be processed without further length errors. [`FrameBuilder`] writes frames (master side,
//! tests, fuzzers and benchmarks).

use super::{Command, ETHERTYPE};
use core::fmt;

/// Length of an Ethernet II header without VLAN tag.
pub const ETHERNET_HEADER_LEN: usize = 14;
/// Length of an 802.1Q VLAN tag.
pub const VLAN_TAG_LEN: usize = 4;
/// The 802.1Q VLAN EtherType.
pub const ETHERTYPE_VLAN: u16 = 0x8100;
/// Length of the EtherCAT frame header.
pub const ECAT_HEADER_LEN: usize = 2;
/// Length of a datagram header (cmd, idx, address, len, irq).
pub const DATAGRAM_HEADER_LEN: usize = 10;
/// Length of the working counter that ends each datagram.
pub const WKC_LEN: usize = 2;
/// Largest datagram data length the 11-bit length field can express.
pub const MAX_DATAGRAM_DATA: usize = 0x07FF;
/// EtherCAT header type for DLPDU (command) frames, the only type a slave processes.
pub const ECAT_TYPE_DLPDU: u8 = 1;
/// The locally-administered (U/L) bit in the first byte of a MAC address. Every ESC sets it in
/// the source address of frames it forwards, which is how masters tell replies from their own
/// transmissions.
pub const MAC_LOCAL_BIT: u8 = 0x02;
/// Largest Ethernet frame without FCS that a standard (1500-byte MTU) link carries, with one
/// VLAN tag.
pub const MAX_FRAME_LEN: usize = 1518;

/// Why a buffer is not a well-formed EtherCAT frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// Shorter than an Ethernet header.
    #[error("frame is {len} bytes, shorter than an Ethernet header ({ETHERNET_HEADER_LEN} bytes)")]
    TooShortForEthernet {
        /// Frame length.
        len: usize,
    },
    /// The EtherType is not EtherCAT.
    #[error("EtherType 0x{ethertype:04X} is not EtherCAT (0x88A4)")]
    NotEthercat {
        /// The EtherType found.
        ethertype: u16,
    },
    /// The frame ends inside the EtherCAT header.
    #[error("frame ends inside the EtherCAT header")]
    TooShortForHeader,
    /// The EtherCAT header type is not 1 (DLPDU).
    #[error("EtherCAT header type {frame_type} is not 1 (DLPDU commands)")]
    UnsupportedType {
        /// The type found.
        frame_type: u8,
    },
    /// The reserved bit 11 of the EtherCAT header is set.
    #[error("EtherCAT header reserved bit 11 is set")]
    ReservedBitSet,
    /// The header announces more datagram bytes than the frame holds.
    #[error("EtherCAT header announces {declared} bytes of datagrams but only {available} follow")]
    LengthExceedsFrame {
        /// Length from the header.
        declared: usize,
        /// Bytes present after the header.
        available: usize,
    },
    /// The header announces no datagrams at all.
    #[error("EtherCAT header announces no datagrams")]
    Empty,
    /// A datagram header does not fit into the datagram area.
    #[error("datagram {index} at byte {offset}: its 10-byte header runs past the datagram area")]
    DatagramHeaderTruncated {
        /// Position of the datagram in the frame (0-based).
        index: usize,
        /// Byte offset of the datagram in the datagram area.
        offset: usize,
    },
    /// A datagram's data and working counter do not fit into the datagram area.
    #[error(
        "datagram {index} at byte {offset}: {len} data bytes plus working counter run past the datagram area"
    )]
    DatagramTruncated {
        /// Position of the datagram in the frame (0-based).
        index: usize,
        /// Byte offset of the datagram in the datagram area.
        offset: usize,
        /// Data length from the datagram header.
        len: usize,
    },
    /// A buffer is too small for what a builder was asked to write.
    #[error("buffer of {capacity} bytes is too small: {needed} bytes needed")]
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes available.
        capacity: usize,
    },
    /// A datagram's data is longer than the 11-bit length field allows.
    #[error("datagram data of {len} bytes exceeds the maximum of {MAX_DATAGRAM_DATA}")]
    DataTooLong {
        /// Requested length.
        len: usize,
    },
}

fn get_u16(buf: &[u8], at: usize) -> u16 {
    match buf.get(at..at + 2) {
        Some(b) => u16::from_le_bytes([b[0], b[1]]),
        None => 0,
    }
}

fn set_u16(buf: &mut [u8], at: usize, v: u16) {
    if let Some(b) = buf.get_mut(at..at + 2) {
        b.copy_from_slice(&v.to_le_bytes());
    }
}

fn get_u32(buf: &[u8], at: usize) -> u32 {
    match buf.get(at..at + 4) {
        Some(b) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        None => 0,
    }
}

/// A MAC address.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct MacAddress(pub [u8; 6]);

impl MacAddress {
    /// The broadcast address `ff:ff:ff:ff:ff:ff`.
    pub const BROADCAST: Self = Self([0xFF; 6]);

    /// The address with the locally-administered bit set, as an ESC returns it.
    pub const fn with_local_bit(self) -> Self {
        let mut a = self.0;
        a[0] |= MAC_LOCAL_BIT;
        Self(a)
    }
}

impl fmt::Debug for MacAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl fmt::Display for MacAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0;
        write!(
            f,
            "{:02x}:{:02x}:{:02x}:{:02x}:{:02x}:{:02x}",
            a[0], a[1], a[2], a[3], a[4], a[5]
        )
    }
}

/// A view of an Ethernet II frame carrying EtherCAT, with an optional single VLAN tag.
#[derive(Debug, Clone, Copy)]
pub struct EthernetFrame<T: AsRef<[u8]>> {
    buf: T,
    /// Offset of the EtherCAT header (14, or 18 with a VLAN tag).
    payload_offset: usize,
}

impl<T: AsRef<[u8]>> EthernetFrame<T> {
    /// Wrap a buffer holding a whole Ethernet frame (without FCS). Checks that the Ethernet
    /// header is complete and that the EtherType (after at most one VLAN tag) is EtherCAT.
    pub fn new_checked(buf: T) -> Result<Self, FrameError> {
        let b = buf.as_ref();
        if b.len() < ETHERNET_HEADER_LEN {
            return Err(FrameError::TooShortForEthernet { len: b.len() });
        }
        let mut ethertype = u16::from_be_bytes([b[12], b[13]]);
        let mut payload_offset = ETHERNET_HEADER_LEN;
        if ethertype == ETHERTYPE_VLAN {
            if b.len() < ETHERNET_HEADER_LEN + VLAN_TAG_LEN {
                return Err(FrameError::TooShortForEthernet { len: b.len() });
            }
            ethertype = u16::from_be_bytes([b[16], b[17]]);
            payload_offset += VLAN_TAG_LEN;
        }
        if ethertype != ETHERTYPE {
            return Err(FrameError::NotEthercat { ethertype });
        }
        Ok(Self {
            buf,
            payload_offset,
        })
    }

    /// Destination MAC address.
    pub fn dst(&self) -> MacAddress {
        let mut a = [0; 6];
        a.copy_from_slice(&self.buf.as_ref()[0..6]);
        MacAddress(a)
    }

    /// Source MAC address.
    pub fn src(&self) -> MacAddress {
        let mut a = [0; 6];
        a.copy_from_slice(&self.buf.as_ref()[6..12]);
        MacAddress(a)
    }

    /// Whether the frame carries an 802.1Q VLAN tag.
    pub fn has_vlan_tag(&self) -> bool {
        self.payload_offset != ETHERNET_HEADER_LEN
    }

    /// Offset of the EtherCAT header within the frame.
    pub fn payload_offset(&self) -> usize {
        self.payload_offset
    }

    /// Everything after the Ethernet header (and VLAN tag): the EtherCAT frame.
    pub fn payload(&self) -> &[u8] {
        self.buf.as_ref().get(self.payload_offset..).unwrap_or(&[])
    }

    /// The whole buffer.
    pub fn into_inner(self) -> T {
        self.buf
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EthernetFrame<T> {
    /// Set the source MAC address.
    pub fn set_src(&mut self, mac: MacAddress) {
        self.buf.as_mut()[6..12].copy_from_slice(&mac.0);
    }

    /// Set the destination MAC address.
    pub fn set_dst(&mut self, mac: MacAddress) {
        self.buf.as_mut()[0..6].copy_from_slice(&mac.0);
    }

    /// Set the locally-administered bit in the source address, as every ESC does to the frames
    /// it forwards.
    pub fn mark_forwarded(&mut self) {
        self.buf.as_mut()[6] |= MAC_LOCAL_BIT;
    }

    /// The EtherCAT frame, mutable.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        let off = self.payload_offset;
        self.buf.as_mut().get_mut(off..).unwrap_or(&mut [])
    }
}

/// A view of an EtherCAT frame: the 2-byte EtherCAT header followed by the datagram area.
#[derive(Debug, Clone, Copy)]
pub struct EthercatFrame<T: AsRef<[u8]>> {
    buf: T,
}

/// Summary of a validated EtherCAT frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameSummary {
    /// Number of datagrams (following the M bits).
    pub datagrams: usize,
    /// Bytes of the datagram area actually used by those datagrams.
    pub used_len: usize,
}

impl<T: AsRef<[u8]>> EthercatFrame<T> {
    /// Wrap a buffer starting at the EtherCAT header. Checks the header only; use
    /// [`check`](Self::check) to validate the datagram chain.
    pub fn new_checked(buf: T) -> Result<Self, FrameError> {
        let b = buf.as_ref();
        if b.len() < ECAT_HEADER_LEN {
            return Err(FrameError::TooShortForHeader);
        }
        let f = Self { buf };
        if f.frame_type() != ECAT_TYPE_DLPDU {
            return Err(FrameError::UnsupportedType {
                frame_type: f.frame_type(),
            });
        }
        if f.reserved_bit() {
            return Err(FrameError::ReservedBitSet);
        }
        let declared = f.length();
        let available = f.buf.as_ref().len() - ECAT_HEADER_LEN;
        if declared > available {
            return Err(FrameError::LengthExceedsFrame {
                declared,
                available,
            });
        }
        if declared == 0 {
            return Err(FrameError::Empty);
        }
        Ok(f)
    }

    fn header(&self) -> u16 {
        get_u16(self.buf.as_ref(), 0)
    }

    /// Length of the datagram area from the header (bits 0–10).
    pub fn length(&self) -> usize {
        (self.header() & 0x07FF) as usize
    }

    /// Header reserved bit 11.
    pub fn reserved_bit(&self) -> bool {
        self.header() & 0x0800 != 0
    }

    /// Frame type (bits 12–15); 1 = DLPDU.
    pub fn frame_type(&self) -> u8 {
        (self.header() >> 12) as u8
    }

    /// The datagram area as declared by the header.
    pub fn datagram_area(&self) -> &[u8] {
        let len = self.length();
        self.buf
            .as_ref()
            .get(ECAT_HEADER_LEN..ECAT_HEADER_LEN + len)
            .unwrap_or(&[])
    }

    /// Walk the datagram chain and verify that every datagram (following the M bits) lies
    /// completely inside the datagram area. After this succeeds, [`datagrams`](Self::datagrams)
    /// yields every datagram without error.
    pub fn check(&self) -> Result<FrameSummary, FrameError> {
        check_datagram_area(self.datagram_area())
    }

    /// Iterate over the datagrams. Stops after the datagram without the M bit, or at the first
    /// malformed one (yielding its error).
    pub fn datagrams(&self) -> Datagrams<'_> {
        Datagrams {
            rest: self.datagram_area(),
            offset: 0,
            index: 0,
            done: false,
        }
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EthercatFrame<T> {
    /// Iterate over the datagrams, mutably.
    pub fn datagrams_mut(&mut self) -> DatagramsMut<'_> {
        let len = self.length();
        let area = self
            .buf
            .as_mut()
            .get_mut(ECAT_HEADER_LEN..ECAT_HEADER_LEN + len)
            .unwrap_or(&mut []);
        DatagramsMut {
            rest: area,
            offset: 0,
            index: 0,
            done: false,
        }
    }
}

/// Validate a datagram area (the bytes after the EtherCAT header, as long as the header says).
pub fn check_datagram_area(area: &[u8]) -> Result<FrameSummary, FrameError> {
    let mut offset = 0usize;
    let mut index = 0usize;
    loop {
        let rest = area.get(offset..).unwrap_or(&[]);
        if rest.len() < DATAGRAM_HEADER_LEN {
            return Err(FrameError::DatagramHeaderTruncated { index, offset });
        }
        let lenf = get_u16(rest, 6);
        let len = (lenf & 0x07FF) as usize;
        let total = DATAGRAM_HEADER_LEN + len + WKC_LEN;
        if rest.len() < total {
            return Err(FrameError::DatagramTruncated { index, offset, len });
        }
        offset += total;
        index += 1;
        if lenf & 0x8000 == 0 {
            return Ok(FrameSummary {
                datagrams: index,
                used_len: offset,
            });
        }
    }
}

/// Iterator over the datagrams of a frame.
#[derive(Debug, Clone)]
pub struct Datagrams<'a> {
    rest: &'a [u8],
    offset: usize,
    index: usize,
    done: bool,
}

impl<'a> Iterator for Datagrams<'a> {
    type Item = Result<Datagram<&'a [u8]>, FrameError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match Datagram::new_checked(self.rest) {
            Ok(d) => {
                let total = d.total_len();
                let (this, rest) = self.rest.split_at(total);
                self.rest = rest;
                self.offset += total;
                self.index += 1;
                let d = Datagram { buf: this };
                if !d.more() {
                    self.done = true;
                }
                Some(Ok(d))
            }
            Err(e) => {
                self.done = true;
                Some(Err(with_position(e, self.index, self.offset)))
            }
        }
    }
}

/// Mutable iterator over the datagrams of a frame.
#[derive(Debug)]
pub struct DatagramsMut<'a> {
    rest: &'a mut [u8],
    offset: usize,
    index: usize,
    done: bool,
}

impl<'a> Iterator for DatagramsMut<'a> {
    type Item = Result<Datagram<&'a mut [u8]>, FrameError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let rest = core::mem::take(&mut self.rest);
        let total = match Datagram::new_checked(&*rest) {
            Ok(d) => d.total_len(),
            Err(e) => {
                self.done = true;
                return Some(Err(with_position(e, self.index, self.offset)));
            }
        };
        let (this, rest) = rest.split_at_mut(total);
        self.rest = rest;
        self.offset += total;
        self.index += 1;
        let d = Datagram { buf: this };
        if !d.more() {
            self.done = true;
        }
        Some(Ok(d))
    }
}

fn with_position(e: FrameError, index: usize, offset: usize) -> FrameError {
    match e {
        FrameError::DatagramHeaderTruncated { .. } => {
            FrameError::DatagramHeaderTruncated { index, offset }
        }
        FrameError::DatagramTruncated { len, .. } => {
            FrameError::DatagramTruncated { index, offset, len }
        }
        other => other,
    }
}

/// A view of one datagram: header, data and working counter.
#[derive(Debug, Clone, Copy)]
pub struct Datagram<T: AsRef<[u8]>> {
    buf: T,
}

impl<T: AsRef<[u8]>> Datagram<T> {
    /// Wrap a buffer starting at a datagram header. The buffer may extend past the datagram;
    /// the check is that header, data and working counter fit.
    pub fn new_checked(buf: T) -> Result<Self, FrameError> {
        let b = buf.as_ref();
        if b.len() < DATAGRAM_HEADER_LEN {
            return Err(FrameError::DatagramHeaderTruncated {
                index: 0,
                offset: 0,
            });
        }
        let len = (get_u16(b, 6) & 0x07FF) as usize;
        if b.len() < DATAGRAM_HEADER_LEN + len + WKC_LEN {
            return Err(FrameError::DatagramTruncated {
                index: 0,
                offset: 0,
                len,
            });
        }
        Ok(Self { buf })
    }

    /// The raw command byte.
    pub fn command_raw(&self) -> u8 {
        self.buf.as_ref()[0]
    }

    /// The command, or `None` for reserved codes.
    pub fn command(&self) -> Option<Command> {
        Command::from_u8(self.command_raw())
    }

    /// The datagram index (set by the master, never changed by slaves).
    pub fn index(&self) -> u8 {
        self.buf.as_ref()[1]
    }

    /// The position/station address word (ADP) of physical and broadcast commands.
    pub fn adp(&self) -> u16 {
        get_u16(self.buf.as_ref(), 2)
    }

    /// The register offset word (ADO) of physical and broadcast commands.
    pub fn ado(&self) -> u16 {
        get_u16(self.buf.as_ref(), 4)
    }

    /// The 32-bit logical address of LRD/LWR/LRW.
    pub fn logical_address(&self) -> u32 {
        get_u32(self.buf.as_ref(), 2)
    }

    fn len_field(&self) -> u16 {
        get_u16(self.buf.as_ref(), 6)
    }

    /// Data length in bytes.
    pub fn data_len(&self) -> usize {
        (self.len_field() & 0x07FF) as usize
    }

    /// The circulating-frame bit (C).
    pub fn circulating(&self) -> bool {
        self.len_field() & 0x4000 != 0
    }

    /// The more-datagrams-follow bit (M).
    pub fn more(&self) -> bool {
        self.len_field() & 0x8000 != 0
    }

    /// The IRQ field.
    pub fn irq(&self) -> u16 {
        get_u16(self.buf.as_ref(), 8)
    }

    /// The data.
    pub fn data(&self) -> &[u8] {
        let len = self.data_len();
        &self.buf.as_ref()[DATAGRAM_HEADER_LEN..DATAGRAM_HEADER_LEN + len]
    }

    /// The working counter.
    pub fn wkc(&self) -> u16 {
        get_u16(self.buf.as_ref(), DATAGRAM_HEADER_LEN + self.data_len())
    }

    /// Total length of this datagram on the wire: header, data and working counter.
    pub fn total_len(&self) -> usize {
        DATAGRAM_HEADER_LEN + self.data_len() + WKC_LEN
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Datagram<T> {
    /// Set the ADP word.
    pub fn set_adp(&mut self, v: u16) {
        set_u16(self.buf.as_mut(), 2, v);
    }

    /// Set the IRQ field.
    pub fn set_irq(&mut self, v: u16) {
        set_u16(self.buf.as_mut(), 8, v);
    }

    /// Set or clear the circulating bit.
    pub fn set_circulating(&mut self, on: bool) {
        let f = self.len_field();
        let f = if on { f | 0x4000 } else { f & !0x4000 };
        set_u16(self.buf.as_mut(), 6, f);
    }

    /// The data, mutable.
    pub fn data_mut(&mut self) -> &mut [u8] {
        let len = self.data_len();
        &mut self.buf.as_mut()[DATAGRAM_HEADER_LEN..DATAGRAM_HEADER_LEN + len]
    }

    /// Set the working counter.
    pub fn set_wkc(&mut self, v: u16) {
        let at = DATAGRAM_HEADER_LEN + self.data_len();
        set_u16(self.buf.as_mut(), at, v);
    }

    /// The header fields and data, both mutable at once, plus the working counter slot:
    /// `(adp, data, wkc)` as raw byte slices for in-place processing.
    pub fn split_mut(&mut self) -> DatagramParts<'_> {
        let len = self.data_len();
        let b = self.buf.as_mut();
        let (head, rest) = b.split_at_mut(DATAGRAM_HEADER_LEN);
        let (data, rest) = rest.split_at_mut(len);
        let wkc = &mut rest[..WKC_LEN];
        DatagramParts {
            command: head[0],
            address: &mut head[2..6],
            data,
            wkc,
        }
    }
}

/// The mutable parts of a datagram, from [`Datagram::split_mut`].
#[derive(Debug)]
pub struct DatagramParts<'a> {
    /// Raw command byte.
    pub command: u8,
    /// Address field (ADP, ADO little-endian, or the logical address).
    pub address: &'a mut [u8],
    /// Data.
    pub data: &'a mut [u8],
    /// Working counter (2 bytes, little-endian).
    pub wkc: &'a mut [u8],
}

/// Writes an EtherCAT frame datagram by datagram into a caller-provided buffer.
///
/// ```
/// use ecdrive_core::ec::{Command, frame::{FrameBuilder, MacAddress}};
/// let mut buf = [0u8; 64];
/// let mut b = FrameBuilder::new(&mut buf, MacAddress([0x10; 6])).unwrap();
/// b.push(Command::Brd, 0, 0x0000_0000, &[0]).unwrap();
/// let len = b.finish();
/// assert_eq!(len, 14 + 2 + 10 + 1 + 2);
/// ```
#[derive(Debug)]
pub struct FrameBuilder<'a> {
    buf: &'a mut [u8],
    len: usize,
    last: Option<usize>,
}

impl<'a> FrameBuilder<'a> {
    /// Start a frame to broadcast from `src`.
    pub fn new(buf: &'a mut [u8], src: MacAddress) -> Result<Self, FrameError> {
        let needed = ETHERNET_HEADER_LEN + ECAT_HEADER_LEN;
        if buf.len() < needed {
            return Err(FrameError::BufferTooSmall {
                needed,
                capacity: buf.len(),
            });
        }
        buf[0..6].copy_from_slice(&MacAddress::BROADCAST.0);
        buf[6..12].copy_from_slice(&src.0);
        buf[12..14].copy_from_slice(&ETHERTYPE.to_be_bytes());
        buf[14..16].copy_from_slice(&(u16::from(ECAT_TYPE_DLPDU) << 12).to_le_bytes());
        Ok(Self {
            buf,
            len: needed,
            last: None,
        })
    }

    /// Go on with a frame already in `buf`, whose first `len` bytes are a valid EtherCAT
    /// frame: further datagrams go after its last one (whatever follows it, such as padding, is
    /// overwritten).
    pub fn resume(buf: &'a mut [u8], len: usize) -> Result<Self, FrameError> {
        let payload = buf
            .get(ETHERNET_HEADER_LEN..len)
            .ok_or(FrameError::TooShortForHeader)?;
        let summary = EthercatFrame::new_checked(payload)?.check()?;
        let mut at = ETHERNET_HEADER_LEN + ECAT_HEADER_LEN;
        let mut last = None;
        for _ in 0..summary.datagrams {
            last = Some(at);
            let lf = usize::from(get_u16(buf, at + 6) & 0x07FF);
            at += DATAGRAM_HEADER_LEN + lf + WKC_LEN;
        }
        Ok(Self { buf, len: at, last })
    }

    /// Append a datagram with the given raw command code, index, address (ADP | ADO << 16, or
    /// a logical address) and data, with working counter 0. Returns the byte offset of its
    /// data in the frame.
    pub fn push_raw(
        &mut self,
        command: u8,
        index: u8,
        address: u32,
        data: &[u8],
    ) -> Result<usize, FrameError> {
        if data.len() > MAX_DATAGRAM_DATA {
            return Err(FrameError::DataTooLong { len: data.len() });
        }
        let total = DATAGRAM_HEADER_LEN + data.len() + WKC_LEN;
        let needed = self.len + total;
        let area = needed - ETHERNET_HEADER_LEN - ECAT_HEADER_LEN;
        if needed > self.buf.len() || area > MAX_DATAGRAM_DATA {
            return Err(FrameError::BufferTooSmall {
                needed,
                capacity: self
                    .buf
                    .len()
                    .min(ETHERNET_HEADER_LEN + ECAT_HEADER_LEN + MAX_DATAGRAM_DATA),
            });
        }
        if let Some(prev) = self.last {
            let f = get_u16(self.buf, prev + 6) | 0x8000;
            set_u16(self.buf, prev + 6, f);
        }
        let at = self.len;
        let d = &mut self.buf[at..at + total];
        d[0] = command;
        d[1] = index;
        d[2..6].copy_from_slice(&address.to_le_bytes());
        d[6..8].copy_from_slice(&(data.len() as u16).to_le_bytes());
        d[8..10].copy_from_slice(&[0, 0]);
        d[10..10 + data.len()].copy_from_slice(data);
        d[10 + data.len()..].copy_from_slice(&[0, 0]);
        self.last = Some(at);
        self.len = needed;
        let header = (u16::from(ECAT_TYPE_DLPDU) << 12) | area as u16;
        set_u16(self.buf, ETHERNET_HEADER_LEN, header);
        Ok(at + DATAGRAM_HEADER_LEN)
    }

    /// Append a datagram; see [`push_raw`](Self::push_raw).
    pub fn push(
        &mut self,
        command: Command,
        index: u8,
        address: u32,
        data: &[u8],
    ) -> Result<usize, FrameError> {
        self.push_raw(command as u8, index, address, data)
    }

    /// Finish the frame; returns its length in bytes.
    pub fn finish(self) -> usize {
        self.len
    }
}

/// Build a physical/broadcast address field from ADP and ADO.
pub const fn physical_address(adp: u16, ado: u16) -> u32 {
    adp as u32 | (ado as u32) << 16
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ([u8; 128], usize) {
        let mut buf = [0u8; 128];
        let mut b = FrameBuilder::new(&mut buf, MacAddress([0x10; 6])).unwrap();
        b.push(Command::Brd, 7, physical_address(0, 0x0130), &[0, 0])
            .unwrap();
        b.push(Command::Lrw, 8, 0x0001_0000, &[1, 2, 3, 4]).unwrap();
        let len = b.finish();
        (buf, len)
    }

    #[test]
    fn a_resumed_frame_is_the_frame_built_at_once() {
        let (mut buf, len) = sample();
        // Padding after the last datagram is overwritten.
        buf[len..len + 8].fill(0xAA);
        let mut b = FrameBuilder::resume(&mut buf, len + 8).unwrap();
        let data = b
            .push(Command::Brd, 9, physical_address(0, 0x080D), &[5])
            .unwrap();
        let resumed = b.finish();
        let mut once = [0u8; 128];
        let mut b = FrameBuilder::new(&mut once, MacAddress([0x10; 6])).unwrap();
        b.push(Command::Brd, 7, physical_address(0, 0x0130), &[0, 0])
            .unwrap();
        b.push(Command::Lrw, 8, 0x0001_0000, &[1, 2, 3, 4]).unwrap();
        assert_eq!(
            b.push(Command::Brd, 9, physical_address(0, 0x080D), &[5]),
            Ok(data)
        );
        let n = b.finish();
        assert_eq!(resumed, n);
        assert_eq!(buf[..n], once[..n]);
        // Not a frame: an error, not a builder.
        let mut short = [0u8; 10];
        assert!(FrameBuilder::resume(&mut short, 10).is_err());
    }

    #[test]
    fn build_and_parse() {
        let (buf, len) = sample();
        assert_eq!(len, 14 + 2 + (10 + 2 + 2) + (10 + 4 + 2));
        let eth = EthernetFrame::new_checked(&buf[..len]).unwrap();
        assert_eq!(eth.src(), MacAddress([0x10; 6]));
        assert_eq!(eth.dst(), MacAddress::BROADCAST);
        let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
        assert_eq!(ec.length(), 30);
        assert_eq!(
            ec.check().unwrap(),
            FrameSummary {
                datagrams: 2,
                used_len: 30
            }
        );
        let dgs: Vec<_> = ec.datagrams().map(Result::unwrap).collect();
        assert_eq!(dgs.len(), 2);
        assert_eq!(dgs[0].command(), Some(Command::Brd));
        assert_eq!(dgs[0].index(), 7);
        assert_eq!(dgs[0].ado(), 0x0130);
        assert!(dgs[0].more());
        assert!(!dgs[1].more());
        assert_eq!(dgs[1].logical_address(), 0x0001_0000);
        assert_eq!(dgs[1].data(), &[1, 2, 3, 4]);
        assert_eq!(dgs[1].wkc(), 0);
    }

    #[test]
    fn mutate_in_place() {
        let (mut buf, len) = sample();
        {
            let mut eth = EthernetFrame::new_checked(&mut buf[..len]).unwrap();
            eth.mark_forwarded();
            let mut ec = EthercatFrame::new_checked(eth.payload_mut()).unwrap();
            for d in ec.datagrams_mut() {
                let mut d = d.unwrap();
                d.set_wkc(3);
                d.set_adp(d.adp().wrapping_add(1));
                d.data_mut()[0] = 0xAA;
            }
        }
        let eth = EthernetFrame::new_checked(&buf[..len]).unwrap();
        assert_eq!(eth.src().0[0], 0x12);
        let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
        for d in ec.datagrams() {
            let d = d.unwrap();
            assert_eq!(d.wkc(), 3);
            assert_eq!(d.data()[0], 0xAA);
        }
    }

    #[test]
    fn rejects_garbage() {
        assert!(matches!(
            EthernetFrame::new_checked(&[0u8; 5][..]),
            Err(FrameError::TooShortForEthernet { len: 5 })
        ));
        let mut f = [0u8; 20];
        f[12] = 0x08;
        assert!(matches!(
            EthernetFrame::new_checked(&f[..]),
            Err(FrameError::NotEthercat { ethertype: 0x0800 })
        ));
        let (buf, len) = sample();
        // Truncate the second datagram.
        let cut = &buf[..len - 3];
        let eth = EthernetFrame::new_checked(cut).unwrap();
        assert!(matches!(
            EthercatFrame::new_checked(eth.payload()),
            Err(FrameError::LengthExceedsFrame { .. })
        ));
        // Header length shortened so the second datagram no longer fits.
        let mut b2 = buf;
        set_u16(&mut b2, 14, 0x1000 | 20);
        let eth = EthernetFrame::new_checked(&b2[..len]).unwrap();
        let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
        assert!(matches!(
            ec.check(),
            Err(FrameError::DatagramHeaderTruncated {
                index: 1,
                offset: 14
            })
        ));
        let errs: Vec<_> = ec.datagrams().collect();
        assert_eq!(errs.len(), 2);
        assert!(errs[1].is_err());
    }

    #[test]
    fn vlan_tag_is_skipped() {
        let (buf, len) = sample();
        let mut v = Vec::new();
        v.extend_from_slice(&buf[..12]);
        v.extend_from_slice(&[0x81, 0x00, 0x00, 0x05]);
        v.extend_from_slice(&buf[12..len]);
        let eth = EthernetFrame::new_checked(&v[..]).unwrap();
        assert!(eth.has_vlan_tag());
        let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
        assert_eq!(ec.check().unwrap().datagrams, 2);
    }
}
