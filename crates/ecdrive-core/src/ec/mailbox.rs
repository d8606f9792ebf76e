//! Typed views over mailbox, CoE, SDO, SDO information and emergency messages
//! (ETG.1000.4 §5.6 mailbox header, ETG.1000.6 §5.6 CoE).
//!
//! Two layers, in the smoltcp style:
//!
//! - **Views** over byte buffers with checked constructors, field accessors and setters:
//!   [`Mailbox`] (6-byte header + data), [`Coe`] (2-byte CoE header + data), [`Sdo`] (SDO command
//!   byte, index, sub-index, data), [`SdoInfo`] (4-byte SDO information header + data).
//! - **Representations** that parse a whole message and emit one, with every length field
//!   computed: [`SdoRequest`], [`SdoResponse`], [`SdoInfoRequest`], [`SdoInfoFragment`],
//!   [`ObjectDescription`], [`EntryDescription`], [`OdList`], [`Emergency`],
//!   [`MailboxErrorReply`], and [`MailboxMessage::parse`] for any received mailbox.
//!
//! Every length field is validated against the buffer it claims to describe: a lying length is an
//! [`Error`], never a panic or an out-of-bounds slice. Accessors never panic either, whatever
//! the buffer holds (the checked constructors guarantee the fixed fields are present).
//!
//! ```text
//! mailbox  | length u16 | address u16 | chan:6 prio:2 | type:4 cnt:3 r:1 | data[length] |
//! CoE      | number:9 reserved:3 service:4 | ...                                          |
//! SDO      | cmd u8 | index u16 | sub u8 | data[4] | ...                                   |
//! segment  | cmd u8 | data[..]                                                            |
//! SDO info | opcode:7 incomplete:1 | reserved u8 | fragments_left u16 | ...               |
//! ```
//!
//! Abort codes and access flags are carried as raw integers here (`ec` depends on nothing);
//! [`crate::od::SdoAbortCode`] and [`crate::od::EntryAccess`] give them meaning.

use core::fmt;

/// Size of the mailbox header.
pub const MAILBOX_HEADER_LEN: usize = 6;
/// Size of the CoE header.
pub const COE_HEADER_LEN: usize = 2;
/// Size of the SDO part of every SDO message after the CoE header: command byte, index,
/// sub-index and 4 data bytes. SDO messages are never shorter (mailbox length ≥ 10).
pub const SDO_MIN_LEN: usize = 8;
/// Smallest mailbox `length` of an SDO message (CoE header + [`SDO_MIN_LEN`]).
pub const SDO_MIN_MAILBOX_LEN: usize = COE_HEADER_LEN + SDO_MIN_LEN;
/// Size of the SDO information header.
pub const SDO_INFO_HEADER_LEN: usize = 4;

/// How many data bytes a normal (non-expedited) initiate message carries at most in a mailbox
/// of `mailbox_size` bytes (the SyncManager length): `mailbox_size − 16`.
pub const fn normal_data_capacity(mailbox_size: usize) -> usize {
    mailbox_size.saturating_sub(MAILBOX_HEADER_LEN + COE_HEADER_LEN + SDO_MIN_LEN)
}

/// How many data bytes one SDO segment carries at most in a mailbox of `mailbox_size` bytes:
/// `mailbox_size − 9`.
pub const fn segment_data_capacity(mailbox_size: usize) -> usize {
    mailbox_size.saturating_sub(MAILBOX_HEADER_LEN + COE_HEADER_LEN + 1)
}

/// How many service-data bytes one SDO information fragment carries at most in a mailbox of
/// `mailbox_size` bytes: `mailbox_size − 12`.
pub const fn info_data_capacity(mailbox_size: usize) -> usize {
    mailbox_size.saturating_sub(MAILBOX_HEADER_LEN + COE_HEADER_LEN + SDO_INFO_HEADER_LEN)
}

/// Why a mailbox message could not be parsed or emitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Error {
    /// The buffer ends before a fixed part of the message.
    #[error("{what} is truncated: it needs {needed} bytes, {available} are there")]
    Truncated {
        /// Which part.
        what: &'static str,
        /// Bytes needed.
        needed: usize,
        /// Bytes available.
        available: usize,
    },
    /// The mailbox length field claims more data than the buffer holds.
    #[error(
        "mailbox length field claims {claimed} data bytes, but only {available} follow the header"
    )]
    BadLength {
        /// The length field.
        claimed: usize,
        /// Bytes after the header.
        available: usize,
    },
    /// A field holds a value this message kind does not allow.
    #[error("{what}: unexpected value 0x{value:X}")]
    Unexpected {
        /// Which field.
        what: &'static str,
        /// Its value.
        value: u32,
    },
    /// The output buffer is too small for the message.
    #[error("cannot emit {what}: it needs {needed} bytes, the buffer has {available}")]
    NoSpace {
        /// Which message.
        what: &'static str,
        /// Bytes needed.
        needed: usize,
        /// Bytes available.
        available: usize,
    },
}

// ---------------------------------------------------------------------------------------------
// Panic-free byte access. The checked constructors guarantee the fixed fields exist; these
// helpers make the accessors total anyway (out of range reads give 0, writes are dropped).

fn rd_u8(b: &[u8], at: usize) -> u8 {
    b.get(at).copied().unwrap_or(0)
}

fn rd_u16(b: &[u8], at: usize) -> u16 {
    b.get(at..at.saturating_add(2))
        .and_then(|s| <[u8; 2]>::try_from(s).ok())
        .map_or(0, u16::from_le_bytes)
}

fn rd_u32(b: &[u8], at: usize) -> u32 {
    b.get(at..at.saturating_add(4))
        .and_then(|s| <[u8; 4]>::try_from(s).ok())
        .map_or(0, u32::from_le_bytes)
}

fn wr(b: &mut [u8], at: usize, bytes: &[u8]) {
    if let Some(d) = b.get_mut(at..at.saturating_add(bytes.len())) {
        d.copy_from_slice(bytes);
    }
}

fn wr_u8(b: &mut [u8], at: usize, v: u8) {
    wr(b, at, &[v]);
}

fn wr_u16(b: &mut [u8], at: usize, v: u16) {
    wr(b, at, &v.to_le_bytes());
}

fn wr_u32(b: &mut [u8], at: usize, v: u32) {
    wr(b, at, &v.to_le_bytes());
}

fn tail(b: &[u8], from: usize) -> &[u8] {
    b.get(from..).unwrap_or(&[])
}

fn tail_mut(b: &mut [u8], from: usize) -> &mut [u8] {
    let from = from.min(b.len());
    b.get_mut(from..).unwrap_or_default()
}

fn need(what: &'static str, needed: usize, available: usize) -> Result<(), Error> {
    if available < needed {
        Err(Error::Truncated {
            what,
            needed,
            available,
        })
    } else {
        Ok(())
    }
}

fn space(what: &'static str, needed: usize, available: usize) -> Result<(), Error> {
    if available < needed {
        Err(Error::NoSpace {
            what,
            needed,
            available,
        })
    } else {
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Mailbox header.

/// The mailbox protocol in the header's type field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum MailboxType {
    /// Mailbox error reply (ERR).
    Error = 0,
    /// ADS over EtherCAT.
    Aoe = 1,
    /// Ethernet over EtherCAT.
    Eoe = 2,
    /// CAN application protocol over EtherCAT.
    Coe = 3,
    /// File access over EtherCAT.
    Foe = 4,
    /// Servo profile over EtherCAT.
    Soe = 5,
    /// Vendor specific.
    Voe = 15,
}

impl MailboxType {
    /// Decode the 4-bit type field. `None` for the reserved values 6–14.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        Some(match bits & 0x0F {
            0 => Self::Error,
            1 => Self::Aoe,
            2 => Self::Eoe,
            3 => Self::Coe,
            4 => Self::Foe,
            5 => Self::Soe,
            15 => Self::Voe,
            _ => return None,
        })
    }

    /// Short protocol name: `ERR`, `AoE`, `EoE`, `CoE`, `FoE`, `SoE`, `VoE`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Error => "ERR",
            Self::Aoe => "AoE",
            Self::Eoe => "EoE",
            Self::Coe => "CoE",
            Self::Foe => "FoE",
            Self::Soe => "SoE",
            Self::Voe => "VoE",
        }
    }
}

impl fmt::Display for MailboxType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A view over a mailbox: the 6-byte header followed by `length` data bytes (and, in a
/// SyncManager buffer, padding up to the SyncManager length, which the view ignores).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mailbox<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Mailbox<T> {
    /// Wrap a buffer, checking that it holds the header and the `length` data bytes the header
    /// announces.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let b = buffer.as_ref();
        need("mailbox header", MAILBOX_HEADER_LEN, b.len())?;
        let claimed = rd_u16(b, 0) as usize;
        let available = b.len() - MAILBOX_HEADER_LEN;
        if claimed > available {
            return Err(Error::BadLength { claimed, available });
        }
        Ok(Self { buffer })
    }

    /// Wrap a buffer for building a message: only checks that the header fits. The length field
    /// is not checked (a fresh buffer holds anything); set it with [`Mailbox::set_length`].
    pub fn new_for_emit(buffer: T) -> Result<Self, Error> {
        space("mailbox header", MAILBOX_HEADER_LEN, buffer.as_ref().len())?;
        Ok(Self { buffer })
    }

    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Number of data bytes after the header.
    pub fn length(&self) -> u16 {
        rd_u16(self.buffer.as_ref(), 0)
    }

    /// Station address field (0 in requests from the master and in replies).
    pub fn address(&self) -> u16 {
        rd_u16(self.buffer.as_ref(), 2)
    }

    /// Channel (bits 0–5 of byte 4).
    pub fn channel(&self) -> u8 {
        rd_u8(self.buffer.as_ref(), 4) & 0x3F
    }

    /// Priority (bits 6–7 of byte 4).
    pub fn priority(&self) -> u8 {
        rd_u8(self.buffer.as_ref(), 4) >> 6
    }

    /// The raw 4-bit type field.
    pub fn mailbox_type_raw(&self) -> u8 {
        rd_u8(self.buffer.as_ref(), 5) & 0x0F
    }

    /// The protocol, `None` for a reserved type.
    pub fn mailbox_type(&self) -> Option<MailboxType> {
        MailboxType::from_bits(self.mailbox_type_raw())
    }

    /// The counter (1..=7; 0 means "not used").
    pub fn counter(&self) -> u8 {
        (rd_u8(self.buffer.as_ref(), 5) >> 4) & 0x07
    }

    /// Header plus data: the bytes a message occupies.
    pub fn total_len(&self) -> usize {
        MAILBOX_HEADER_LEN + self.length() as usize
    }

    /// The `length` data bytes after the header (clipped to the buffer).
    pub fn payload(&self) -> &[u8] {
        let b = self.buffer.as_ref();
        let end = self.total_len().min(b.len());
        b.get(MAILBOX_HEADER_LEN..end).unwrap_or(&[])
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Mailbox<T> {
    /// Set the data length.
    pub fn set_length(&mut self, v: u16) {
        wr_u16(self.buffer.as_mut(), 0, v);
    }

    /// Set the address field.
    pub fn set_address(&mut self, v: u16) {
        wr_u16(self.buffer.as_mut(), 2, v);
    }

    /// Set the channel (6 bits) and priority (2 bits).
    pub fn set_channel_priority(&mut self, channel: u8, priority: u8) {
        wr_u8(
            self.buffer.as_mut(),
            4,
            (channel & 0x3F) | ((priority & 0x03) << 6),
        );
    }

    /// Set the type field.
    pub fn set_mailbox_type(&mut self, t: MailboxType) {
        let b = self.buffer.as_mut();
        let v = (rd_u8(b, 5) & 0xF0) | t as u8;
        wr_u8(b, 5, v);
    }

    /// Set the counter (masked to 3 bits); the reserved bit 7 is cleared.
    pub fn set_counter(&mut self, counter: u8) {
        let b = self.buffer.as_mut();
        let v = (rd_u8(b, 5) & 0x0F) | ((counter & 0x07) << 4);
        wr_u8(b, 5, v);
    }

    /// Everything after the header, up to the end of the buffer (for building the data).
    pub fn payload_mut(&mut self) -> &mut [u8] {
        tail_mut(self.buffer.as_mut(), MAILBOX_HEADER_LEN)
    }
}

/// Write a complete mailbox header into `buf`: `length` data bytes, address 0, channel 0,
/// priority 0, the type and the counter. Checks that `buf` has room for the header and data.
pub fn emit_header(
    buf: &mut [u8],
    length: usize,
    mailbox_type: MailboxType,
    counter: u8,
) -> Result<usize, Error> {
    let total = MAILBOX_HEADER_LEN + length;
    space(mailbox_type.name(), total, buf.len())?;
    let length = u16::try_from(length).map_err(|_| Error::NoSpace {
        what: "mailbox length field",
        needed: length,
        available: u16::MAX as usize,
    })?;
    let mut mbx = Mailbox::new_for_emit(&mut *buf)?;
    mbx.set_length(length);
    mbx.set_address(0);
    mbx.set_channel_priority(0, 0);
    mbx.set_mailbox_type(mailbox_type);
    mbx.set_counter(counter);
    Ok(total)
}

// ---------------------------------------------------------------------------------------------
// CoE header.

/// The CoE service in the CoE header (ETG.1000.6 Table 29).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum CoeService {
    /// Emergency.
    Emergency = 1,
    /// SDO request.
    SdoRequest = 2,
    /// SDO response.
    SdoResponse = 3,
    /// TxPDO.
    TxPdo = 4,
    /// RxPDO.
    RxPdo = 5,
    /// TxPDO remote request.
    TxPdoRtr = 6,
    /// RxPDO remote request.
    RxPdoRtr = 7,
    /// SDO information.
    SdoInfo = 8,
}

impl CoeService {
    /// Decode the 4-bit service field. `None` for 0 and 9–15.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        Some(match bits & 0x0F {
            1 => Self::Emergency,
            2 => Self::SdoRequest,
            3 => Self::SdoResponse,
            4 => Self::TxPdo,
            5 => Self::RxPdo,
            6 => Self::TxPdoRtr,
            7 => Self::RxPdoRtr,
            8 => Self::SdoInfo,
            _ => return None,
        })
    }
}

/// A view over CoE data (a mailbox payload): the 2-byte CoE header and the service data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Coe<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Coe<T> {
    /// Wrap a buffer, checking that it holds the CoE header.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        need("CoE header", COE_HEADER_LEN, buffer.as_ref().len())?;
        Ok(Self { buffer })
    }

    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The 9-bit number (0 for SDO; the PDO number for PDO services).
    pub fn number(&self) -> u16 {
        rd_u16(self.buffer.as_ref(), 0) & 0x01FF
    }

    /// The raw 4-bit service field.
    pub fn service_raw(&self) -> u8 {
        (rd_u16(self.buffer.as_ref(), 0) >> 12) as u8
    }

    /// The service, `None` for a reserved value.
    pub fn service(&self) -> Option<CoeService> {
        CoeService::from_bits(self.service_raw())
    }

    /// The service data after the CoE header.
    pub fn payload(&self) -> &[u8] {
        tail(self.buffer.as_ref(), COE_HEADER_LEN)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Coe<T> {
    /// Set the number (9 bits) and the service; the reserved bits are cleared.
    pub fn set_header(&mut self, number: u16, service: CoeService) {
        let v = (number & 0x01FF) | ((service as u16) << 12);
        wr_u16(self.buffer.as_mut(), 0, v);
    }

    /// The service data after the CoE header, mutable.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        tail_mut(self.buffer.as_mut(), COE_HEADER_LEN)
    }
}

/// Write a mailbox header and a CoE header for `service` with `body_len` bytes of service data
/// following; returns the total message length. The caller writes the service data at
/// `buf[8..]`.
fn emit_coe_headers(
    buf: &mut [u8],
    counter: u8,
    service: CoeService,
    body_len: usize,
) -> Result<usize, Error> {
    let total = emit_header(buf, COE_HEADER_LEN + body_len, MailboxType::Coe, counter)?;
    let mut coe = Coe::new_checked(tail_mut(buf, MAILBOX_HEADER_LEN))?;
    coe.set_header(0, service);
    Ok(total)
}

const COE_BODY: usize = MAILBOX_HEADER_LEN + COE_HEADER_LEN;

// ---------------------------------------------------------------------------------------------
// SDO.

/// SDO command specifiers (bits 5–7 of the command byte), by direction.
pub mod command {
    /// Client → server: download segment.
    pub const CCS_DOWNLOAD_SEGMENT: u8 = 0;
    /// Client → server: initiate download.
    pub const CCS_INITIATE_DOWNLOAD: u8 = 1;
    /// Client → server: initiate upload.
    pub const CCS_INITIATE_UPLOAD: u8 = 2;
    /// Client → server: upload segment.
    pub const CCS_UPLOAD_SEGMENT: u8 = 3;
    /// Either way: abort transfer.
    pub const ABORT: u8 = 4;
    /// Server → client: upload segment.
    pub const SCS_UPLOAD_SEGMENT: u8 = 0;
    /// Server → client: download segment.
    pub const SCS_DOWNLOAD_SEGMENT: u8 = 1;
    /// Server → client: initiate upload.
    pub const SCS_INITIATE_UPLOAD: u8 = 2;
    /// Server → client: initiate download.
    pub const SCS_INITIATE_DOWNLOAD: u8 = 3;
}

/// A view over the SDO part of an SDO message (after the CoE header): the command byte, then
/// for initiate and abort messages index, sub-index and data, for segments the segment data.
/// Every SDO message has at least [`SDO_MIN_LEN`] bytes here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sdo<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Sdo<T> {
    /// Wrap the SDO bytes (exactly the mailbox length minus the CoE header), checking the
    /// minimum size.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        need("SDO message", SDO_MIN_LEN, buffer.as_ref().len())?;
        Ok(Self { buffer })
    }

    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The command byte.
    pub fn command(&self) -> u8 {
        rd_u8(self.buffer.as_ref(), 0)
    }

    /// The command specifier (bits 5–7); see [`command`].
    pub fn specifier(&self) -> u8 {
        self.command() >> 5
    }

    /// Initiate messages: bit 0, size indicated.
    pub fn size_indicated(&self) -> bool {
        self.command() & 0x01 != 0
    }

    /// Initiate messages: bit 1, expedited transfer.
    pub fn expedited(&self) -> bool {
        self.command() & 0x02 != 0
    }

    /// Initiate messages: bits 2–3, the number of unused bytes of the 4 expedited data bytes.
    pub fn unused_bytes(&self) -> u8 {
        (self.command() >> 2) & 0x03
    }

    /// Initiate messages: bit 4, complete access.
    pub fn complete_access(&self) -> bool {
        self.command() & 0x10 != 0
    }

    /// Initiate and abort messages: the object index.
    pub fn index(&self) -> u16 {
        rd_u16(self.buffer.as_ref(), 1)
    }

    /// Initiate and abort messages: the sub-index.
    pub fn sub(&self) -> u8 {
        rd_u8(self.buffer.as_ref(), 3)
    }

    /// Expedited messages: the data bytes (4 − unused, or all 4 when no size is indicated).
    pub fn expedited_data(&self) -> &[u8] {
        let n = if self.size_indicated() {
            4 - self.unused_bytes() as usize
        } else {
            4
        };
        self.buffer.as_ref().get(4..4 + n).unwrap_or(&[])
    }

    /// Normal initiate messages: the complete size. Abort messages: the abort code.
    pub fn complete_size(&self) -> u32 {
        rd_u32(self.buffer.as_ref(), 4)
    }

    /// Abort messages: the abort code.
    pub fn abort_code(&self) -> u32 {
        rd_u32(self.buffer.as_ref(), 4)
    }

    /// Normal initiate messages: the data after the complete size.
    pub fn normal_data(&self) -> &[u8] {
        tail(self.buffer.as_ref(), SDO_MIN_LEN)
    }

    /// Segments: bit 4, the toggle bit.
    pub fn toggle(&self) -> bool {
        self.command() & 0x10 != 0
    }

    /// Segments: bits 1–3, the number of unused bytes of a 7-byte segment.
    pub fn segment_unused(&self) -> u8 {
        (self.command() >> 1) & 0x07
    }

    /// Segments: bit 0, no more segments follow.
    pub fn last_segment(&self) -> bool {
        self.command() & 0x01 != 0
    }

    /// Segments: the segment data. A segment of fewer than 7 bytes is sent padded to 7 with the
    /// number of unused bytes in bits 1–3; longer segments fill the message exactly.
    pub fn segment_data(&self) -> &[u8] {
        let data = tail(self.buffer.as_ref(), 1);
        let len = if data.len() == 7 {
            7 - self.segment_unused() as usize
        } else {
            data.len()
        };
        data.get(..len).unwrap_or(data)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Sdo<T> {
    /// Set the command byte.
    pub fn set_command(&mut self, v: u8) {
        wr_u8(self.buffer.as_mut(), 0, v);
    }

    /// Set the index.
    pub fn set_index(&mut self, v: u16) {
        wr_u16(self.buffer.as_mut(), 1, v);
    }

    /// Set the sub-index.
    pub fn set_sub(&mut self, v: u8) {
        wr_u8(self.buffer.as_mut(), 3, v);
    }

    /// Set bytes 4–7 as a u32 (complete size or abort code).
    pub fn set_u32(&mut self, v: u32) {
        wr_u32(self.buffer.as_mut(), 4, v);
    }

    /// Everything after the command byte (segment data), mutable.
    pub fn segment_data_mut(&mut self) -> &mut [u8] {
        tail_mut(self.buffer.as_mut(), 1)
    }

    /// Everything after the sub-index (expedited data, or size and normal data), mutable.
    pub fn data_mut(&mut self) -> &mut [u8] {
        tail_mut(self.buffer.as_mut(), 4)
    }
}

/// An SDO message from the client (the master): CoE service "SDO request".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoRequest<'a> {
    /// Initiate download with 1–4 bytes of data in the message. Without a size indication the
    /// data is all 4 bytes.
    DownloadExpedited {
        /// Object index.
        index: u16,
        /// Sub-index (0 or 1 with complete access).
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// The data.
        data: &'a [u8],
    },
    /// Initiate a normal download: the complete size and the first data bytes (all of them if
    /// they fit; otherwise download segments follow).
    DownloadNormal {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Total number of bytes of the transfer.
        complete_size: u32,
        /// The data bytes in this message.
        data: &'a [u8],
    },
    /// One download segment.
    DownloadSegment {
        /// Toggle bit, 0 for the first segment.
        toggle: bool,
        /// No more segments follow.
        last: bool,
        /// Segment data.
        data: &'a [u8],
    },
    /// Initiate upload.
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access.
        complete_access: bool,
    },
    /// Request the next upload segment.
    UploadSegment {
        /// Toggle bit, 0 for the first segment.
        toggle: bool,
    },
    /// Abort the transfer.
    Abort {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code (see [`crate::od::SdoAbortCode`]).
        code: u32,
    },
}

/// An SDO message from the server (the slave): CoE service "SDO response" (aborts are sent as
/// SDO requests, as ETG.1000.6 defines the abort service).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoResponse<'a> {
    /// Initiate download confirmed.
    Download {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// Download segment confirmed.
    DownloadSegment {
        /// The toggle bit of the confirmed segment.
        toggle: bool,
    },
    /// Upload answered with 1–4 bytes in the message.
    UploadExpedited {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// The data.
        data: &'a [u8],
    },
    /// Upload answered normally: complete size and the first data bytes. If fewer than
    /// `complete_size` bytes are here, the client requests upload segments.
    UploadNormal {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Total number of bytes.
        complete_size: u32,
        /// The data bytes in this message.
        data: &'a [u8],
    },
    /// One upload segment.
    UploadSegment {
        /// The toggle bit of the request.
        toggle: bool,
        /// No more segments follow.
        last: bool,
        /// Segment data.
        data: &'a [u8],
    },
    /// Transfer aborted.
    Abort {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code (see [`crate::od::SdoAbortCode`]).
        code: u32,
    },
}

fn initiate_cmd(specifier: u8, complete_access: bool, expedited_len: Option<usize>) -> u8 {
    let ca = if complete_access { 0x10 } else { 0 };
    let rest = match expedited_len {
        // e = 1, s = 1, n = 4 − len
        Some(len) => 0x03 | (((4 - len.min(4)) as u8) << 2),
        // normal: s = 1 (size indicated)
        None => 0x01,
    };
    (specifier << 5) | ca | rest
}

fn segment_cmd(specifier: u8, toggle: bool, last: bool, len: usize) -> u8 {
    let unused = if len < 7 { (7 - len) as u8 } else { 0 };
    (specifier << 5) | (u8::from(toggle) << 4) | (unused << 1) | u8::from(last)
}

/// Write an initiate/abort SDO body (8 bytes + `extra`) into `sdo`.
fn emit_initiate(
    sdo: &mut [u8],
    cmd: u8,
    index: u16,
    sub: u8,
    word: [u8; 4],
    extra: &[u8],
) -> Result<usize, Error> {
    let len = SDO_MIN_LEN + extra.len();
    space("SDO message", len, sdo.len())?;
    wr_u8(sdo, 0, cmd);
    wr_u16(sdo, 1, index);
    wr_u8(sdo, 3, sub);
    wr(sdo, 4, &word);
    wr(sdo, 8, extra);
    Ok(len)
}

/// Write a segment body (command byte + data, padded to 7 data bytes) into `sdo`.
fn emit_segment(sdo: &mut [u8], cmd: u8, data: &[u8]) -> Result<usize, Error> {
    let len = 1 + data.len().max(7);
    space("SDO segment", len, sdo.len())?;
    wr_u8(sdo, 0, cmd);
    if let Some(d) = sdo.get_mut(1..len) {
        d.fill(0);
    }
    wr(sdo, 1, data);
    Ok(len)
}

fn expedited_word(data: &[u8]) -> Result<[u8; 4], Error> {
    if data.is_empty() || data.len() > 4 {
        return Err(Error::Unexpected {
            what: "expedited data length (1..=4)",
            value: data.len() as u32,
        });
    }
    let mut w = [0u8; 4];
    wr(&mut w, 0, data);
    Ok(w)
}

impl<'a> SdoRequest<'a> {
    /// The request that starts downloading `data` through a mailbox (SM0) of `mailbox_size`
    /// bytes, and how many bytes of `data` it carries: expedited for 1–4 bytes, otherwise normal
    /// with as much as fits (`mailbox_size − 16`). Send the rest with
    /// [`SdoRequest::download_segment`], starting with toggle 0.
    pub fn initiate_download(
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &'a [u8],
        mailbox_size: usize,
    ) -> (Self, usize) {
        if (1..=4).contains(&data.len()) {
            return (
                Self::DownloadExpedited {
                    index,
                    sub,
                    complete_access,
                    data,
                },
                data.len(),
            );
        }
        let n = data.len().min(normal_data_capacity(mailbox_size));
        (
            Self::DownloadNormal {
                index,
                sub,
                complete_access,
                complete_size: u32::try_from(data.len()).unwrap_or(u32::MAX),
                data: data.get(..n).unwrap_or(&[]),
            },
            n,
        )
    }

    /// The next download segment for the `rest` of the data through a mailbox of
    /// `mailbox_size` bytes (at most `mailbox_size − 9` bytes per segment), and how many bytes
    /// of `rest` it carries. It is the last segment when that is all of `rest`.
    pub fn download_segment(rest: &'a [u8], toggle: bool, mailbox_size: usize) -> (Self, usize) {
        let n = rest.len().min(segment_data_capacity(mailbox_size).max(1));
        (
            Self::DownloadSegment {
                toggle,
                last: n == rest.len(),
                data: rest.get(..n).unwrap_or(&[]),
            },
            n,
        )
    }

    /// Parse the SDO bytes of a request (the CoE payload, exactly `length − 2` bytes).
    pub fn parse(sdo: &'a [u8]) -> Result<Self, Error> {
        let v = Sdo::new_checked(sdo)?;
        let (index, sub, complete_access) = (v.index(), v.sub(), v.complete_access());
        Ok(match v.specifier() {
            command::CCS_DOWNLOAD_SEGMENT => Self::DownloadSegment {
                toggle: v.toggle(),
                last: v.last_segment(),
                data: sdo_segment_data(sdo),
            },
            command::CCS_INITIATE_DOWNLOAD if v.expedited() => Self::DownloadExpedited {
                index,
                sub,
                complete_access,
                data: expedited_data(sdo),
            },
            command::CCS_INITIATE_DOWNLOAD => {
                if !v.size_indicated() {
                    return Err(Error::Unexpected {
                        what: "normal download without size indication (command)",
                        value: v.command() as u32,
                    });
                }
                Self::DownloadNormal {
                    index,
                    sub,
                    complete_access,
                    complete_size: v.complete_size(),
                    data: tail(sdo, SDO_MIN_LEN),
                }
            }
            command::CCS_INITIATE_UPLOAD => Self::Upload {
                index,
                sub,
                complete_access,
            },
            command::CCS_UPLOAD_SEGMENT => Self::UploadSegment { toggle: v.toggle() },
            command::ABORT => Self::Abort {
                index,
                sub,
                code: v.abort_code(),
            },
            _ => {
                return Err(Error::Unexpected {
                    what: "SDO client command specifier",
                    value: v.command() as u32,
                });
            }
        })
    }

    /// Write the SDO bytes (the CoE payload) into `sdo`; returns their number.
    pub fn emit(&self, sdo: &mut [u8]) -> Result<usize, Error> {
        use command::*;
        match *self {
            Self::DownloadExpedited {
                index,
                sub,
                complete_access,
                data,
            } => {
                let word = expedited_word(data)?;
                let cmd = initiate_cmd(CCS_INITIATE_DOWNLOAD, complete_access, Some(data.len()));
                emit_initiate(sdo, cmd, index, sub, word, &[])
            }
            Self::DownloadNormal {
                index,
                sub,
                complete_access,
                complete_size,
                data,
            } => {
                let cmd = initiate_cmd(CCS_INITIATE_DOWNLOAD, complete_access, None);
                emit_initiate(sdo, cmd, index, sub, complete_size.to_le_bytes(), data)
            }
            Self::DownloadSegment { toggle, last, data } => emit_segment(
                sdo,
                segment_cmd(CCS_DOWNLOAD_SEGMENT, toggle, last, data.len()),
                data,
            ),
            Self::Upload {
                index,
                sub,
                complete_access,
            } => {
                let cmd = (CCS_INITIATE_UPLOAD << 5) | if complete_access { 0x10 } else { 0 };
                emit_initiate(sdo, cmd, index, sub, [0; 4], &[])
            }
            Self::UploadSegment { toggle } => {
                let cmd = (CCS_UPLOAD_SEGMENT << 5) | (u8::from(toggle) << 4);
                emit_initiate(sdo, cmd, 0, 0, [0; 4], &[])
            }
            Self::Abort { index, sub, code } => {
                emit_initiate(sdo, ABORT << 5, index, sub, code.to_le_bytes(), &[])
            }
        }
    }

    /// Write the whole mailbox message (mailbox header, CoE header "SDO request", SDO bytes)
    /// into `buf`; returns the number of bytes to send (the rest of an SM0 buffer is padding).
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        let n = self.emit(tail_mut(buf, COE_BODY))?;
        emit_coe_headers(buf, counter, CoeService::SdoRequest, n)
    }
}

fn expedited_data(sdo: &[u8]) -> &[u8] {
    match Sdo::new_checked(sdo) {
        Ok(v) => {
            let n = if v.size_indicated() {
                4 - v.unused_bytes() as usize
            } else {
                4
            };
            sdo.get(4..4 + n).unwrap_or(&[])
        }
        Err(_) => &[],
    }
}

fn sdo_segment_data(sdo: &[u8]) -> &[u8] {
    let data = tail(sdo, 1);
    let unused = (rd_u8(sdo, 0) >> 1) & 0x07;
    let len = if data.len() == 7 {
        7 - unused as usize
    } else {
        data.len()
    };
    data.get(..len).unwrap_or(data)
}

impl<'a> SdoResponse<'a> {
    /// Parse the SDO bytes of a response (the CoE payload, exactly `length − 2` bytes).
    /// Aborts arrive with service "SDO request"; parse those with this function too.
    pub fn parse(sdo: &'a [u8]) -> Result<Self, Error> {
        let v = Sdo::new_checked(sdo)?;
        let (index, sub, complete_access) = (v.index(), v.sub(), v.complete_access());
        Ok(match v.specifier() {
            command::SCS_UPLOAD_SEGMENT => Self::UploadSegment {
                toggle: v.toggle(),
                last: v.last_segment(),
                data: sdo_segment_data(sdo),
            },
            command::SCS_DOWNLOAD_SEGMENT => Self::DownloadSegment { toggle: v.toggle() },
            command::SCS_INITIATE_UPLOAD if v.expedited() => Self::UploadExpedited {
                index,
                sub,
                complete_access,
                data: expedited_data(sdo),
            },
            command::SCS_INITIATE_UPLOAD => {
                let complete_size = v.complete_size();
                let data = tail(sdo, SDO_MIN_LEN);
                Self::UploadNormal {
                    index,
                    sub,
                    complete_access,
                    complete_size,
                    data: data.get(..complete_size as usize).unwrap_or(data),
                }
            }
            command::SCS_INITIATE_DOWNLOAD => Self::Download { index, sub },
            command::ABORT => Self::Abort {
                index,
                sub,
                code: v.abort_code(),
            },
            _ => {
                return Err(Error::Unexpected {
                    what: "SDO server command specifier",
                    value: v.command() as u32,
                });
            }
        })
    }

    /// Write the SDO bytes (the CoE payload) into `sdo`; returns their number.
    pub fn emit(&self, sdo: &mut [u8]) -> Result<usize, Error> {
        use command::*;
        match *self {
            Self::Download { index, sub } => {
                emit_initiate(sdo, SCS_INITIATE_DOWNLOAD << 5, index, sub, [0; 4], &[])
            }
            Self::DownloadSegment { toggle } => {
                let cmd = (SCS_DOWNLOAD_SEGMENT << 5) | (u8::from(toggle) << 4);
                emit_initiate(sdo, cmd, 0, 0, [0; 4], &[])
            }
            Self::UploadExpedited {
                index,
                sub,
                complete_access,
                data,
            } => {
                let word = expedited_word(data)?;
                let cmd = initiate_cmd(SCS_INITIATE_UPLOAD, complete_access, Some(data.len()));
                emit_initiate(sdo, cmd, index, sub, word, &[])
            }
            Self::UploadNormal {
                index,
                sub,
                complete_access,
                complete_size,
                data,
            } => {
                let cmd = initiate_cmd(SCS_INITIATE_UPLOAD, complete_access, None);
                emit_initiate(sdo, cmd, index, sub, complete_size.to_le_bytes(), data)
            }
            Self::UploadSegment { toggle, last, data } => emit_segment(
                sdo,
                segment_cmd(SCS_UPLOAD_SEGMENT, toggle, last, data.len()),
                data,
            ),
            Self::Abort { index, sub, code } => {
                emit_initiate(sdo, ABORT << 5, index, sub, code.to_le_bytes(), &[])
            }
        }
    }

    /// Write the whole mailbox message into `buf`; returns its length. Aborts go out with the
    /// CoE service "SDO request" (the abort service is a request in ETG.1000.6), everything
    /// else with "SDO response".
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        let n = self.emit(tail_mut(buf, COE_BODY))?;
        let service = match self {
            Self::Abort { .. } => CoeService::SdoRequest,
            _ => CoeService::SdoResponse,
        };
        emit_coe_headers(buf, counter, service, n)
    }
}

// ---------------------------------------------------------------------------------------------
// SDO information.

/// SDO information opcodes (ETG.1000.6 §5.6.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum SdoInfoOpcode {
    /// Get OD list request.
    OdListRequest = 1,
    /// Get OD list response.
    OdListResponse = 2,
    /// Get object description request.
    ObjectDescriptionRequest = 3,
    /// Get object description response.
    ObjectDescriptionResponse = 4,
    /// Get entry description request.
    EntryDescriptionRequest = 5,
    /// Get entry description response.
    EntryDescriptionResponse = 6,
    /// SDO information error (carries an abort code).
    Error = 7,
}

impl SdoInfoOpcode {
    /// Decode the 7-bit opcode. `None` for other values.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        Some(match bits & 0x7F {
            1 => Self::OdListRequest,
            2 => Self::OdListResponse,
            3 => Self::ObjectDescriptionRequest,
            4 => Self::ObjectDescriptionResponse,
            5 => Self::EntryDescriptionRequest,
            6 => Self::EntryDescriptionResponse,
            7 => Self::Error,
            _ => return None,
        })
    }
}

/// OD list types of the "get OD list" request.
pub mod list_type {
    /// The number of objects in each of the five lists (5 × u16).
    pub const QUANTITIES: u16 = 0;
    /// All objects.
    pub const ALL: u16 = 1;
    /// Objects with an entry mappable into an RxPDO.
    pub const RXPDO_MAPPABLE: u16 = 2;
    /// Objects with an entry mappable into a TxPDO.
    pub const TXPDO_MAPPABLE: u16 = 3;
    /// Objects stored for device replacement (backup).
    pub const BACKUP: u16 = 4;
    /// Objects usable as start-up parameters (settings).
    pub const STARTUP: u16 = 5;
}

/// Value-info flags of the "get entry description" request and response: which optional
/// fields follow the fixed part of the response, in this order.
pub mod value_info {
    /// Unit type (u16).
    pub const UNIT_TYPE: u8 = 0x08;
    /// Default value (entry size).
    pub const DEFAULT: u8 = 0x10;
    /// Minimum value (entry size).
    pub const MINIMUM: u8 = 0x20;
    /// Maximum value (entry size).
    pub const MAXIMUM: u8 = 0x40;
}

/// A view over SDO information data (a CoE payload): the 4-byte header and the service data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdoInfo<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> SdoInfo<T> {
    /// Wrap a buffer, checking that it holds the SDO information header.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        need(
            "SDO information header",
            SDO_INFO_HEADER_LEN,
            buffer.as_ref().len(),
        )?;
        Ok(Self { buffer })
    }

    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The raw 7-bit opcode.
    pub fn opcode_raw(&self) -> u8 {
        rd_u8(self.buffer.as_ref(), 0) & 0x7F
    }

    /// The opcode, `None` for an unknown value.
    pub fn opcode(&self) -> Option<SdoInfoOpcode> {
        SdoInfoOpcode::from_bits(self.opcode_raw())
    }

    /// More fragments follow.
    pub fn incomplete(&self) -> bool {
        rd_u8(self.buffer.as_ref(), 0) & 0x80 != 0
    }

    /// Number of fragments still to come after this one.
    pub fn fragments_left(&self) -> u16 {
        rd_u16(self.buffer.as_ref(), 2)
    }

    /// The service data after the header.
    pub fn data(&self) -> &[u8] {
        tail(self.buffer.as_ref(), SDO_INFO_HEADER_LEN)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SdoInfo<T> {
    /// Set the header: opcode, incomplete flag, fragments left; the reserved byte is cleared.
    pub fn set_header(&mut self, opcode: SdoInfoOpcode, incomplete: bool, fragments_left: u16) {
        let b = self.buffer.as_mut();
        wr_u8(b, 0, opcode as u8 | if incomplete { 0x80 } else { 0 });
        wr_u8(b, 1, 0);
        wr_u16(b, 2, fragments_left);
    }

    /// The service data after the header, mutable.
    pub fn data_mut(&mut self) -> &mut [u8] {
        tail_mut(self.buffer.as_mut(), SDO_INFO_HEADER_LEN)
    }
}

/// An SDO information request from the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoInfoRequest {
    /// Get OD list of one [`list_type`].
    OdList {
        /// The list type.
        list_type: u16,
    },
    /// Get object description.
    ObjectDescription {
        /// Object index.
        index: u16,
    },
    /// Get entry description.
    EntryDescription {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Requested optional fields ([`value_info`] flags).
        value_info: u8,
    },
}

impl SdoInfoRequest {
    /// Parse a request from a CoE payload with service "SDO information".
    pub fn parse(coe_payload: &[u8]) -> Result<Self, Error> {
        let v = SdoInfo::new_checked(coe_payload)?;
        let d = v.data();
        match v.opcode() {
            Some(SdoInfoOpcode::OdListRequest) => {
                need("get OD list request", 2, d.len())?;
                Ok(Self::OdList {
                    list_type: rd_u16(d, 0),
                })
            }
            Some(SdoInfoOpcode::ObjectDescriptionRequest) => {
                need("get object description request", 2, d.len())?;
                Ok(Self::ObjectDescription {
                    index: rd_u16(d, 0),
                })
            }
            Some(SdoInfoOpcode::EntryDescriptionRequest) => {
                need("get entry description request", 4, d.len())?;
                Ok(Self::EntryDescription {
                    index: rd_u16(d, 0),
                    sub: rd_u8(d, 2),
                    value_info: rd_u8(d, 3),
                })
            }
            _ => Err(Error::Unexpected {
                what: "SDO information request opcode",
                value: v.opcode_raw() as u32,
            }),
        }
    }

    /// Write the whole mailbox message into `buf`; returns its length.
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        let (opcode, data, n): (_, [u8; 4], usize) = match *self {
            Self::OdList { list_type } => {
                let b = list_type.to_le_bytes();
                (SdoInfoOpcode::OdListRequest, [b[0], b[1], 0, 0], 2)
            }
            Self::ObjectDescription { index } => {
                let b = index.to_le_bytes();
                (
                    SdoInfoOpcode::ObjectDescriptionRequest,
                    [b[0], b[1], 0, 0],
                    2,
                )
            }
            Self::EntryDescription {
                index,
                sub,
                value_info,
            } => {
                let b = index.to_le_bytes();
                (
                    SdoInfoOpcode::EntryDescriptionRequest,
                    [b[0], b[1], sub, value_info],
                    4,
                )
            }
        };
        SdoInfoFragment {
            opcode,
            incomplete: false,
            fragments_left: 0,
            data: data.get(..n).unwrap_or(&[]),
        }
        .emit_mailbox(counter, buf)
    }
}

/// One SDO information message: a request, one fragment of a response, or an error. A response
/// larger than the mailbox is split into fragments; the service data of all fragments, in
/// order, is the complete response ([`OdList`], [`ObjectDescription`], [`EntryDescription`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdoInfoFragment<'a> {
    /// The opcode.
    pub opcode: SdoInfoOpcode,
    /// More fragments follow.
    pub incomplete: bool,
    /// Number of fragments still to come after this one.
    pub fragments_left: u16,
    /// This fragment's service data.
    pub data: &'a [u8],
}

impl<'a> SdoInfoFragment<'a> {
    /// Parse from a CoE payload with service "SDO information".
    pub fn parse(coe_payload: &'a [u8]) -> Result<Self, Error> {
        let v = SdoInfo::new_checked(coe_payload)?;
        let opcode = v.opcode().ok_or(Error::Unexpected {
            what: "SDO information opcode",
            value: v.opcode_raw() as u32,
        })?;
        Ok(Self {
            opcode,
            incomplete: v.incomplete(),
            fragments_left: v.fragments_left(),
            data: tail(coe_payload, SDO_INFO_HEADER_LEN),
        })
    }

    /// For an [`SdoInfoOpcode::Error`] message: the abort code.
    pub fn error_code(&self) -> Option<u32> {
        (self.opcode == SdoInfoOpcode::Error && self.data.len() >= 4).then(|| rd_u32(self.data, 0))
    }

    /// Write the whole mailbox message into `buf`; returns its length.
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        let body = SDO_INFO_HEADER_LEN + self.data.len();
        space("SDO information message", COE_BODY + body, buf.len())?;
        let total = emit_coe_headers(buf, counter, CoeService::SdoInfo, body)?;
        let mut v = SdoInfo::new_checked(tail_mut(buf, COE_BODY))?;
        v.set_header(self.opcode, self.incomplete, self.fragments_left);
        wr(v.data_mut(), 0, self.data);
        Ok(total)
    }
}

/// The service data of a complete "get OD list" response: the list type, then the indices (or,
/// for list type 0, the five list lengths).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OdList<'a> {
    /// The list type.
    pub list_type: u16,
    /// The u16 values after the list type, little-endian.
    pub raw: &'a [u8],
}

impl<'a> OdList<'a> {
    /// Parse reassembled service data. An odd number of value bytes is an error.
    pub fn parse(data: &'a [u8]) -> Result<Self, Error> {
        need("OD list response", 2, data.len())?;
        let raw = tail(data, 2);
        if raw.len() % 2 != 0 {
            return Err(Error::Unexpected {
                what: "OD list length (must be even)",
                value: raw.len() as u32,
            });
        }
        Ok(Self {
            list_type: rd_u16(data, 0),
            raw,
        })
    }

    /// The indices (or quantities).
    pub fn values(&self) -> impl Iterator<Item = u16> + 'a {
        self.raw
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([rd_u8(c, 0), rd_u8(c, 1)]))
    }
}

/// The service data of a complete "get object description" response.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObjectDescription<'a> {
    /// Object index.
    pub index: u16,
    /// Data type index (for ARRAY the element type).
    pub data_type: u16,
    /// Highest sub-index.
    pub max_sub: u8,
    /// Object code: 7 VAR, 8 ARRAY, 9 RECORD.
    pub object_code: u8,
    /// The name (not NUL-terminated).
    pub name: &'a [u8],
}

impl<'a> ObjectDescription<'a> {
    /// Size of the fixed part before the name.
    pub const FIXED_LEN: usize = 6;

    /// Parse reassembled service data.
    pub fn parse(data: &'a [u8]) -> Result<Self, Error> {
        need("object description", Self::FIXED_LEN, data.len())?;
        Ok(Self {
            index: rd_u16(data, 0),
            data_type: rd_u16(data, 2),
            max_sub: rd_u8(data, 4),
            object_code: rd_u8(data, 5),
            name: tail(data, Self::FIXED_LEN),
        })
    }

    /// Bytes [`ObjectDescription::emit`] writes.
    pub fn len(&self) -> usize {
        Self::FIXED_LEN + self.name.len()
    }

    /// Whether it has no name (the fixed part is always there).
    pub fn is_empty(&self) -> bool {
        self.name.is_empty()
    }

    /// Write the service data into `out`; returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        space("object description", self.len(), out.len())?;
        wr_u16(out, 0, self.index);
        wr_u16(out, 2, self.data_type);
        wr_u8(out, 4, self.max_sub);
        wr_u8(out, 5, self.object_code);
        wr(out, Self::FIXED_LEN, self.name);
        Ok(self.len())
    }
}

/// The service data of a complete "get entry description" response.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryDescription<'a> {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Which optional fields follow ([`value_info`] flags).
    pub value_info: u8,
    /// Data type index.
    pub data_type: u16,
    /// Size in bits.
    pub bit_len: u16,
    /// Access rights (ObjAccess; see [`crate::od::EntryAccess`]).
    pub access: u16,
    /// The optional fields selected by `value_info`, then the name.
    pub data: &'a [u8],
}

/// The optional fields and the name of an [`EntryDescription`], split.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EntryValues<'a> {
    /// Unit type.
    pub unit_type: Option<u16>,
    /// Default value bytes.
    pub default: Option<&'a [u8]>,
    /// Minimum value bytes.
    pub minimum: Option<&'a [u8]>,
    /// Maximum value bytes.
    pub maximum: Option<&'a [u8]>,
    /// The name.
    pub name: &'a [u8],
}

impl<'a> EntryDescription<'a> {
    /// Size of the fixed part before the optional fields.
    pub const FIXED_LEN: usize = 10;

    /// Parse reassembled service data.
    pub fn parse(data: &'a [u8]) -> Result<Self, Error> {
        need("entry description", Self::FIXED_LEN, data.len())?;
        Ok(Self {
            index: rd_u16(data, 0),
            sub: rd_u8(data, 2),
            value_info: rd_u8(data, 3),
            data_type: rd_u16(data, 4),
            bit_len: rd_u16(data, 6),
            access: rd_u16(data, 8),
            data: tail(data, Self::FIXED_LEN),
        })
    }

    /// The byte size of each of the default, minimum and maximum fields: the entry size rounded
    /// up to whole bytes.
    pub fn value_len(&self) -> usize {
        (self.bit_len as usize).div_ceil(8)
    }

    /// Split `data` into the optional fields `value_info` announces and the name. A `data`
    /// shorter than the announced fields is an error.
    pub fn values(&self) -> Result<EntryValues<'a>, Error> {
        let mut rest = self.data;
        let mut out = EntryValues::default();
        let mut take = |n: usize, what: &'static str| -> Result<&'a [u8], Error> {
            need(what, n, rest.len())?;
            let (a, b) = rest.split_at(n);
            rest = b;
            Ok(a)
        };
        if self.value_info & value_info::UNIT_TYPE != 0 {
            out.unit_type = Some(rd_u16(take(2, "entry description unit type")?, 0));
        }
        let n = self.value_len();
        if self.value_info & value_info::DEFAULT != 0 {
            out.default = Some(take(n, "entry description default value")?);
        }
        if self.value_info & value_info::MINIMUM != 0 {
            out.minimum = Some(take(n, "entry description minimum value")?);
        }
        if self.value_info & value_info::MAXIMUM != 0 {
            out.maximum = Some(take(n, "entry description maximum value")?);
        }
        out.name = rest;
        Ok(out)
    }

    /// Bytes [`EntryDescription::emit`] writes.
    pub fn len(&self) -> usize {
        Self::FIXED_LEN + self.data.len()
    }

    /// Whether nothing follows the fixed part.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Write the service data into `out`; returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        space("entry description", self.len(), out.len())?;
        wr_u16(out, 0, self.index);
        wr_u8(out, 2, self.sub);
        wr_u8(out, 3, self.value_info);
        wr_u16(out, 4, self.data_type);
        wr_u16(out, 6, self.bit_len);
        wr_u16(out, 8, self.access);
        wr(out, Self::FIXED_LEN, self.data);
        Ok(self.len())
    }
}

// ---------------------------------------------------------------------------------------------
// Emergency and mailbox errors.

/// A CoE emergency message (CoE service 1): the one CiA 301 emergency type
/// ([`crate::od::Emergency`]) both buses use; this module adds its mailbox framing.
pub use crate::od::Emergency;

/// The CoE framing of an emergency.
impl Emergency {
    /// Parse from a CoE payload with service "Emergency" (at least 8 bytes; the rest is the
    /// mailbox's padding).
    pub fn parse_coe(coe_payload: &[u8]) -> Result<Self, Error> {
        need("emergency message", Self::LEN, coe_payload.len())?;
        let bytes = coe_payload.get(..Self::LEN).unwrap_or(coe_payload);
        Self::parse(bytes).map_err(|e| Error::Truncated {
            what: "emergency message",
            needed: Self::LEN,
            available: e.0,
        })
    }

    /// Write the whole mailbox message (length 10) into `buf`; returns its length.
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        space("emergency message", COE_BODY + Self::LEN, buf.len())?;
        let total = emit_coe_headers(buf, counter, CoeService::Emergency, Self::LEN)?;
        let body = tail_mut(buf, COE_BODY);
        wr_u16(body, 0, self.error_code);
        wr_u8(body, 2, self.error_register);
        wr(body, 3, &self.data);
        Ok(total)
    }
}

/// Detail codes of a mailbox error reply (mailbox type 0), ETG.1000.4.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u16)]
pub enum MailboxErrorDetail {
    /// Syntax of the 6-byte mailbox header is wrong.
    Syntax = 1,
    /// The mailbox protocol is not supported.
    UnsupportedProtocol = 2,
    /// The channel field is invalid.
    InvalidChannel = 3,
    /// The service in the mailbox protocol is not supported.
    ServiceNotSupported = 4,
    /// The protocol header of the mailbox data is wrong.
    InvalidHeader = 5,
    /// The mailbox data is too short.
    SizeTooShort = 6,
    /// The mailbox protocol cannot be processed for lack of resources.
    NoMemory = 7,
    /// The length of the data is inconsistent.
    InvalidSize = 8,
}

impl fmt::Display for MailboxErrorReply {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match MailboxErrorDetail::from_code(self.detail) {
            Some(MailboxErrorDetail::Syntax) => "syntax of the mailbox header",
            Some(MailboxErrorDetail::UnsupportedProtocol) => "mailbox protocol not supported",
            Some(MailboxErrorDetail::InvalidChannel) => "invalid channel",
            Some(MailboxErrorDetail::ServiceNotSupported) => "service not supported",
            Some(MailboxErrorDetail::InvalidHeader) => "invalid protocol header",
            Some(MailboxErrorDetail::SizeTooShort) => "mailbox data too short",
            Some(MailboxErrorDetail::NoMemory) => "no memory",
            Some(MailboxErrorDetail::InvalidSize) => "inconsistent data length",
            None => "unknown detail",
        };
        write!(f, "detail {} ({text})", self.detail)
    }
}

impl MailboxErrorDetail {
    /// Decode a detail code.
    pub const fn from_code(code: u16) -> Option<Self> {
        Some(match code {
            1 => Self::Syntax,
            2 => Self::UnsupportedProtocol,
            3 => Self::InvalidChannel,
            4 => Self::ServiceNotSupported,
            5 => Self::InvalidHeader,
            6 => Self::SizeTooShort,
            7 => Self::NoMemory,
            8 => Self::InvalidSize,
            _ => return None,
        })
    }

    /// The meaning in words.
    pub const fn text(self) -> &'static str {
        match self {
            Self::Syntax => "mailbox header syntax error",
            Self::UnsupportedProtocol => "mailbox protocol not supported",
            Self::InvalidChannel => "invalid mailbox channel",
            Self::ServiceNotSupported => "service not supported",
            Self::InvalidHeader => "invalid protocol header",
            Self::SizeTooShort => "mailbox data too short",
            Self::NoMemory => "no memory for the mailbox service",
            Self::InvalidSize => "inconsistent mailbox data length",
        }
    }
}

/// A mailbox error reply (mailbox type 0): `type u16 = 0x0001, detail u16`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MailboxErrorReply {
    /// The raw detail code (see [`MailboxErrorDetail`]).
    pub detail: u16,
}

impl MailboxErrorReply {
    /// The command value that marks a mailbox error reply.
    pub const COMMAND: u16 = 0x0001;
    /// Size of the data after the mailbox header.
    pub const LEN: usize = 4;

    /// A reply with a known detail.
    pub const fn new(detail: MailboxErrorDetail) -> Self {
        Self {
            detail: detail as u16,
        }
    }

    /// Parse from the payload of a type-0 mailbox.
    pub fn parse(payload: &[u8]) -> Result<Self, Error> {
        need("mailbox error reply", Self::LEN, payload.len())?;
        let cmd = rd_u16(payload, 0);
        if cmd != Self::COMMAND {
            return Err(Error::Unexpected {
                what: "mailbox error reply command",
                value: cmd as u32,
            });
        }
        Ok(Self {
            detail: rd_u16(payload, 2),
        })
    }

    /// Write the whole mailbox message into `buf`; returns its length.
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        let total = emit_header(buf, Self::LEN, MailboxType::Error, counter)?;
        let body = tail_mut(buf, MAILBOX_HEADER_LEN);
        wr_u16(body, 0, Self::COMMAND);
        wr_u16(body, 2, self.detail);
        Ok(total)
    }
}

// ---------------------------------------------------------------------------------------------
// Whole messages.

/// What a mailbox carries, decoded as far as this module knows the protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MailboxMessage<'a> {
    /// A mailbox error reply.
    Error(MailboxErrorReply),
    /// CoE "SDO request" (including aborts from either side).
    SdoRequest(SdoRequest<'a>),
    /// CoE "SDO response".
    SdoResponse(SdoResponse<'a>),
    /// CoE emergency.
    Emergency(Emergency),
    /// CoE SDO information (request, response fragment or error).
    SdoInfo(SdoInfoFragment<'a>),
    /// Another CoE service (PDO services), undecoded.
    OtherCoe {
        /// The raw service field.
        service: u8,
        /// The data after the CoE header.
        payload: &'a [u8],
    },
    /// Another mailbox protocol, undecoded.
    Other {
        /// The raw type field.
        mailbox_type: u8,
        /// The mailbox data.
        payload: &'a [u8],
    },
}

impl<'a> MailboxMessage<'a> {
    /// Parse a received mailbox (a whole SyncManager buffer: header, data, padding). Returns the
    /// counter and the message.
    pub fn parse(buf: &'a [u8]) -> Result<(u8, Self), Error> {
        let mbx = Mailbox::new_checked(buf)?;
        let counter = mbx.counter();
        let payload = payload_of(buf);
        let msg = match mbx.mailbox_type() {
            Some(MailboxType::Error) => Self::Error(MailboxErrorReply::parse(payload)?),
            Some(MailboxType::Coe) => {
                let coe = Coe::new_checked(payload)?;
                let data = tail(payload, COE_HEADER_LEN);
                match coe.service() {
                    Some(CoeService::SdoRequest) => Self::SdoRequest(SdoRequest::parse(data)?),
                    Some(CoeService::SdoResponse) => Self::SdoResponse(SdoResponse::parse(data)?),
                    Some(CoeService::Emergency) => Self::Emergency(Emergency::parse_coe(data)?),
                    Some(CoeService::SdoInfo) => Self::SdoInfo(SdoInfoFragment::parse(data)?),
                    _ => Self::OtherCoe {
                        service: coe.service_raw(),
                        payload: data,
                    },
                }
            }
            _ => Self::Other {
                mailbox_type: mbx.mailbox_type_raw(),
                payload,
            },
        };
        Ok((counter, msg))
    }
}

/// The `length` data bytes of a mailbox already checked with [`Mailbox::new_checked`], with
/// the buffer's lifetime.
fn payload_of(buf: &[u8]) -> &[u8] {
    let len = rd_u16(buf, 0) as usize;
    buf.get(MAILBOX_HEADER_LEN..MAILBOX_HEADER_LEN + len)
        .unwrap_or(&[])
}

/// The data bytes of a mailbox after checking its header: `length` bytes after the 6-byte
/// header, with the buffer's lifetime.
pub fn mailbox_payload(buf: &[u8]) -> Result<&[u8], Error> {
    Mailbox::new_checked(buf)?;
    Ok(payload_of(buf))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trip_and_lying_length() {
        let mut buf = [0u8; 16];
        let n = emit_header(&mut buf, 10, MailboxType::Coe, 3).unwrap();
        assert_eq!(n, 16);
        assert_eq!(buf[..6], [0x0A, 0x00, 0x00, 0x00, 0x00, 0x33]);
        let m = Mailbox::new_checked(&buf[..]).unwrap();
        assert_eq!(m.counter(), 3);
        assert_eq!(m.mailbox_type(), Some(MailboxType::Coe));
        assert_eq!(m.payload().len(), 10);
        assert_eq!(
            Mailbox::new_checked(&buf[..15]),
            Err(Error::BadLength {
                claimed: 10,
                available: 9
            })
        );
        assert!(matches!(
            Mailbox::new_checked(&buf[..5]),
            Err(Error::Truncated { .. })
        ));
        assert!(matches!(
            emit_header(&mut buf, 11, MailboxType::Coe, 1),
            Err(Error::NoSpace { .. })
        ));
    }

    #[test]
    fn expedited_download_bytes() {
        let mut buf = [0u8; 32];
        let req = SdoRequest::DownloadExpedited {
            index: 0x6040,
            sub: 0,
            complete_access: false,
            data: &[0x0F, 0x00],
        };
        let n = req.emit_mailbox(1, &mut buf).unwrap();
        assert_eq!(
            buf[..n],
            [
                0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20, 0x2B, 0x40, 0x60, 0x00, 0x0F, 0x00,
                0x00, 0x00
            ]
        );
        assert_eq!(
            MailboxMessage::parse(&buf).unwrap(),
            (1, MailboxMessage::SdoRequest(req))
        );
    }

    #[test]
    fn short_segment_is_padded_with_unused_count() {
        let mut buf = [0xEEu8; 32];
        let resp = SdoResponse::UploadSegment {
            toggle: true,
            last: true,
            data: b"abc",
        };
        let n = resp.emit_mailbox(2, &mut buf).unwrap();
        assert_eq!(n, 16);
        assert_eq!(buf[0], 10);
        // 0x00 | t<<4 | n<<1 | c, n = 7 − 3 = 4
        assert_eq!(buf[8], 0x10 | (4 << 1) | 1);
        assert_eq!(&buf[9..16], b"abc\0\0\0\0");
        assert_eq!(
            MailboxMessage::parse(&buf[..n]).unwrap().1,
            MailboxMessage::SdoResponse(resp)
        );
        // A long segment fills the message exactly.
        let data = [7u8; 20];
        let resp = SdoResponse::UploadSegment {
            toggle: false,
            last: false,
            data: &data,
        };
        let n = resp.emit_mailbox(3, &mut buf).unwrap();
        assert_eq!(n, 6 + 3 + 20);
        assert_eq!(buf[8], 0x00);
        assert_eq!(
            MailboxMessage::parse(&buf[..n]).unwrap().1,
            MailboxMessage::SdoResponse(resp)
        );
    }

    #[test]
    fn download_helpers_split_as_soem_does() {
        let data: Vec<u8> = (0..16).collect();
        // SM0 of 20 bytes: 4 bytes in the initiate, then segments of 11.
        let (init, n) = SdoRequest::initiate_download(0x2004, 0, false, &data, 20);
        assert_eq!(n, 4);
        let mut buf = [0u8; 20];
        assert_eq!(init.emit_mailbox(1, &mut buf).unwrap(), 20);
        assert_eq!(
            buf[..12],
            [14, 0, 0, 0, 0, 0x13, 0, 0x20, 0x21, 0x04, 0x20, 0]
        );
        assert_eq!(buf[12..16], [16, 0, 0, 0]);
        let (seg, k) = SdoRequest::download_segment(&data[n..], false, 20);
        assert_eq!(k, 11);
        assert!(matches!(
            seg,
            SdoRequest::DownloadSegment { last: false, .. }
        ));
        let (seg, k) = SdoRequest::download_segment(&data[n + 11..], true, 20);
        assert_eq!(k, 1);
        assert_eq!(seg.emit_mailbox(3, &mut buf).unwrap(), 16);
        // 0x00 | t<<4 | (7 − 1)<<1 | c
        assert_eq!(buf[8], 0x1D);
        // 1–4 bytes go expedited.
        let (init, n) = SdoRequest::initiate_download(0x6040, 0, false, &data[..2], 20);
        assert_eq!(n, 2);
        assert!(matches!(init, SdoRequest::DownloadExpedited { .. }));
    }

    #[test]
    fn entry_description_values_split() {
        let mut out = [0u8; 64];
        let mut data = vec![];
        data.extend_from_slice(&0x1234u16.to_le_bytes());
        data.extend_from_slice(&[1, 0, 2, 0, 3, 0]);
        data.extend_from_slice(b"Controlword");
        let e = EntryDescription {
            index: 0x6040,
            sub: 0,
            value_info: value_info::UNIT_TYPE
                | value_info::DEFAULT
                | value_info::MINIMUM
                | value_info::MAXIMUM,
            data_type: 6,
            bit_len: 16,
            access: 0x3F,
            data: &data,
        };
        let n = e.emit(&mut out).unwrap();
        let p = EntryDescription::parse(&out[..n]).unwrap();
        assert_eq!(p, e);
        let v = p.values().unwrap();
        assert_eq!(v.unit_type, Some(0x1234));
        assert_eq!(v.default, Some(&[1u8, 0][..]));
        assert_eq!(v.maximum, Some(&[3u8, 0][..]));
        assert_eq!(v.name, b"Controlword");
        let short = EntryDescription {
            data: &data[..3],
            ..e
        };
        assert!(short.values().is_err());
    }

    #[test]
    fn emergency_and_error_round_trip() {
        let mut buf = [0u8; 16];
        let e = Emergency {
            error_code: 0x2310,
            error_register: 0x03,
            data: [1, 2, 3, 4, 5],
        };
        let n = e.emit_mailbox(5, &mut buf).unwrap();
        assert_eq!(n, 16);
        assert_eq!(buf[6..8], [0x00, 0x10]);
        assert_eq!(
            MailboxMessage::parse(&buf).unwrap(),
            (5, MailboxMessage::Emergency(e))
        );
        let r = MailboxErrorReply::new(MailboxErrorDetail::UnsupportedProtocol);
        let n = r.emit_mailbox(1, &mut buf).unwrap();
        assert_eq!(buf[..n], [4, 0, 0, 0, 0, 0x10, 1, 0, 2, 0]);
        assert_eq!(
            MailboxMessage::parse(&buf[..n]).unwrap().1,
            MailboxMessage::Error(r)
        );
    }
}
