//! The mailbox header (ETG.1000.4 §5.6): [`MailboxType`], the [`Mailbox`] view, [`emit_header`].

use super::*;
use core::fmt;

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
