//! FoE (File access over EtherCAT, ETG.1000.6 §5.8): mailbox type 4.
//!
//! ```text
//! FoE      | opcode u8 | reserved u8 | ...                                              |
//! RRQ/WRQ  | password u32 | file name[..]                                                |
//! DATA     | packet number u32 | data[..]   (a packet shorter than the most a mailbox    |
//!          |                               carries ends the file; 0 bytes if it fills)   |
//! ACK      | packet number u32               (0 answers a WRQ)                            |
//! ERR      | error code u32 | error text[..]                                              |
//! BUSY     | done u16 | entire u16 | text[..]                                             |
//! ```
//!
//! A write: WRQ → ACK 0, then DATA 1 → ACK 1, DATA 2 → ACK 2, …; a read: RRQ → DATA 1, ACK 1 →
//! DATA 2, …. Either side ends the transfer with ERR. A slave that needs time answers BUSY,
//! and the master sends the last packet again.

use super::*;
use core::fmt;

/// Size of the FoE header (opcode, reserved, the 32-bit field).
pub const FOE_HEADER_LEN: usize = 6;

/// How many data bytes one FoE DATA packet carries at most in a mailbox of `mailbox_size`
/// bytes: `mailbox_size − 12`.
pub const fn foe_data_capacity(mailbox_size: usize) -> usize {
    mailbox_size.saturating_sub(MAILBOX_HEADER_LEN + FOE_HEADER_LEN)
}

/// FoE opcodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FoeOpCode {
    /// Read request.
    Read = 1,
    /// Write request.
    Write = 2,
    /// A data packet.
    Data = 3,
    /// Acknowledge of a packet (or of a write request: packet 0).
    Ack = 4,
    /// Error: ends the transfer.
    Error = 5,
    /// The receiver is busy: send the last packet again.
    Busy = 6,
}

impl FoeOpCode {
    /// Decode.
    pub const fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            1 => Self::Read,
            2 => Self::Write,
            3 => Self::Data,
            4 => Self::Ack,
            5 => Self::Error,
            6 => Self::Busy,
            _ => return None,
        })
    }
}

/// An FoE error code (ETG.1000.6 Table 92), raw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub struct FoeErrorCode(pub u32);

impl FoeErrorCode {
    /// Not defined.
    pub const NOT_DEFINED: Self = Self(0x8000);
    /// File not found.
    pub const NOT_FOUND: Self = Self(0x8001);
    /// Access denied.
    pub const ACCESS_DENIED: Self = Self(0x8002);
    /// Disk full.
    pub const DISK_FULL: Self = Self(0x8003);
    /// Illegal.
    pub const ILLEGAL: Self = Self(0x8004);
    /// Packet number wrong.
    pub const PACKET_NUMBER: Self = Self(0x8005);
    /// File already exists.
    pub const ALREADY_EXISTS: Self = Self(0x8006);
    /// No user.
    pub const NO_USER: Self = Self(0x8007);
    /// Bootstrap only.
    pub const BOOTSTRAP_ONLY: Self = Self(0x8008);
    /// Not in Bootstrap.
    pub const NOT_IN_BOOTSTRAP: Self = Self(0x8009);
    /// No rights (a wrong password).
    pub const NO_RIGHTS: Self = Self(0x800A);
    /// Program error.
    pub const PROGRAM_ERROR: Self = Self(0x800B);

    /// The meaning in words, if the code is a standard one.
    pub const fn text(self) -> Option<&'static str> {
        Some(match self.0 {
            0x8000 => "not defined",
            0x8001 => "file not found",
            0x8002 => "access denied",
            0x8003 => "disk full",
            0x8004 => "illegal",
            0x8005 => "packet number wrong",
            0x8006 => "file already exists",
            0x8007 => "no user",
            0x8008 => "bootstrap only",
            0x8009 => "not in Bootstrap",
            0x800A => "no rights (wrong password)",
            0x800B => "program error",
            _ => return None,
        })
    }
}

impl fmt::Display for FoeErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.text() {
            Some(t) => write!(f, "0x{:04X} ({t})", self.0),
            None => write!(f, "0x{:04X}", self.0),
        }
    }
}

/// An FoE message. Names and texts are raw bytes (ETG.1000.6 does not fix an encoding; in
/// practice ASCII).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FoeMessage<'a> {
    /// Read request.
    Read {
        /// The password (0: none).
        password: u32,
        /// The file name.
        name: &'a [u8],
    },
    /// Write request.
    Write {
        /// The password (0: none).
        password: u32,
        /// The file name.
        name: &'a [u8],
    },
    /// A data packet.
    Data {
        /// Packet number, from 1.
        packet: u32,
        /// Its data.
        data: &'a [u8],
    },
    /// Acknowledge.
    Ack {
        /// The packet acknowledged (0: the write request).
        packet: u32,
    },
    /// Error.
    Error {
        /// The code.
        code: FoeErrorCode,
        /// The text the sender gave (may be empty).
        text: &'a [u8],
    },
    /// Busy.
    Busy {
        /// Progress: done …
        done: u16,
        /// … of entire.
        entire: u16,
    },
}

impl<'a> FoeMessage<'a> {
    /// Parse the data of a type-4 mailbox.
    pub fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        need("FoE header", FOE_HEADER_LEN, payload.len())?;
        let op = rd_u8(payload, 0);
        let field = rd_u32(payload, 2);
        let rest = tail(payload, FOE_HEADER_LEN);
        Ok(match FoeOpCode::from_u8(op) {
            Some(FoeOpCode::Read) => Self::Read {
                password: field,
                name: rest,
            },
            Some(FoeOpCode::Write) => Self::Write {
                password: field,
                name: rest,
            },
            Some(FoeOpCode::Data) => Self::Data {
                packet: field,
                data: rest,
            },
            Some(FoeOpCode::Ack) => Self::Ack { packet: field },
            Some(FoeOpCode::Error) => Self::Error {
                code: FoeErrorCode(field),
                text: rest,
            },
            Some(FoeOpCode::Busy) => Self::Busy {
                done: rd_u16(payload, 2),
                entire: rd_u16(payload, 4),
            },
            None => {
                return Err(Error::Unexpected {
                    what: "FoE opcode",
                    value: u32::from(op),
                });
            }
        })
    }

    /// The opcode.
    pub const fn opcode(&self) -> FoeOpCode {
        match self {
            Self::Read { .. } => FoeOpCode::Read,
            Self::Write { .. } => FoeOpCode::Write,
            Self::Data { .. } => FoeOpCode::Data,
            Self::Ack { .. } => FoeOpCode::Ack,
            Self::Error { .. } => FoeOpCode::Error,
            Self::Busy { .. } => FoeOpCode::Busy,
        }
    }

    /// Length of the FoE data (header and what follows it).
    pub fn len(&self) -> usize {
        FOE_HEADER_LEN
            + match self {
                Self::Read { name, .. } | Self::Write { name, .. } => name.len(),
                Self::Data { data, .. } => data.len(),
                Self::Error { text, .. } => text.len(),
                Self::Ack { .. } | Self::Busy { .. } => 0,
            }
    }

    /// Never empty: the header is always there.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Write the whole mailbox message (header, FoE header, data) into `buf`; returns its
    /// length.
    pub fn emit_mailbox(&self, counter: u8, buf: &mut [u8]) -> Result<usize, Error> {
        let len = self.len();
        let total = emit_header(buf, len, MailboxType::Foe, counter)?;
        let body = tail_mut(buf, MAILBOX_HEADER_LEN);
        wr_u8(body, 0, self.opcode() as u8);
        wr_u8(body, 1, 0);
        let (field, rest): (u32, &[u8]) = match *self {
            Self::Read { password, name } | Self::Write { password, name } => (password, name),
            Self::Data { packet, data } => (packet, data),
            Self::Ack { packet } => (packet, &[]),
            Self::Error { code, text } => (code.0, text),
            Self::Busy { done, entire } => (u32::from(done) | u32::from(entire) << 16, &[]),
        };
        wr_u32(body, 2, field);
        wr(body, FOE_HEADER_LEN, rest);
        Ok(total)
    }
}
