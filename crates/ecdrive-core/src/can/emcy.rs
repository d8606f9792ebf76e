//! Emergency messages (CiA 301 §7.2.7): COB-ID 080h + node, 8 bytes: bytes 0–1 the error code
//! (little endian), byte 2 the error register (1001h), bytes 3–7 manufacturer-specific.
//!
//! What bytes 3–7 carry differs per drive (see [`EmcyFormat`](super::profile::EmcyFormat)): the
//! BLV-R sends zeros (§4.5), the ASDA-A2 the panel alarm number in bytes 3–4 (§5.1), the Lexium
//! the PDO number in byte 5 and a vendor code in bytes 6–7 (§3.5). An error code of 0000h means
//! "error reset / no error".

use super::frame::{CanFrame, cob};

/// A checked view over the data bytes of an EMCY frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmcyFrame<T: AsRef<[u8]>> {
    buffer: T,
}

/// An EMCY frame without exactly 8 data bytes (the one CiA 301 error, under its CAN name).
pub use crate::od::EmergencyLengthError as EmcyLengthError;

impl<T: AsRef<[u8]>> EmcyFrame<T> {
    /// The view, if `buffer` holds 8 bytes.
    pub fn new_checked(buffer: T) -> Result<Self, EmcyLengthError> {
        let len = buffer.as_ref().len();
        if len != 8 {
            return Err(EmcyLengthError(len));
        }
        Ok(Self { buffer })
    }

    fn byte(&self, i: usize) -> u8 {
        self.buffer.as_ref().get(i).copied().unwrap_or(0)
    }

    /// Bytes 0–1: the error code.
    pub fn error_code(&self) -> u16 {
        u16::from_le_bytes([self.byte(0), self.byte(1)])
    }

    /// Byte 2: the error register (1001h).
    pub fn error_register(&self) -> u8 {
        self.byte(2)
    }

    /// Bytes 3–7: manufacturer-specific.
    pub fn vendor(&self) -> [u8; 5] {
        [
            self.byte(3),
            self.byte(4),
            self.byte(5),
            self.byte(6),
            self.byte(7),
        ]
    }
}

/// An emergency message's content: the one CiA 301 type ([`crate::od::Emergency`]) both buses
/// use; this module adds its CAN framing.
pub use crate::od::Emergency;

/// The CAN framing of an emergency.
impl Emergency {
    /// The frame on COB-ID `cob_id` (080h + node unless 1014h moved it).
    pub fn frame(&self, cob_id: u16) -> CanFrame {
        CanFrame::from_parts(cob_id, self.to_bytes(), 8)
    }

    /// The frame on the default COB-ID of `node`.
    pub fn default_frame(&self, node: u8) -> CanFrame {
        self.frame(cob::emcy(node))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let e = Emergency {
            error_code: 0x7305,
            error_register: 0x81,
            data: [0x11, 0x00, 0, 0, 0],
        };
        let f = e.default_frame(0x7F);
        assert_eq!(f.id(), 0xFF);
        assert_eq!(f.data(), &[0x05, 0x73, 0x81, 0x11, 0, 0, 0, 0]);
        assert_eq!(Emergency::parse(f.data()).unwrap(), e);
        assert!(Emergency::parse(&[0; 7]).is_err());
    }
}
