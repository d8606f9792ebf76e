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

mod coe;
mod errors;
mod foe;
mod header;
mod message;
mod sdo;
mod sdo_info;
#[cfg(test)]
mod tests;

pub use coe::*;
pub use errors::*;
pub use foe::*;
pub use header::*;
pub use message::*;
pub use sdo::*;
pub use sdo_info::*;
