//! The CoE framing of an emergency (CoE service 1) and the mailbox error reply.

use super::*;
use core::fmt;

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
