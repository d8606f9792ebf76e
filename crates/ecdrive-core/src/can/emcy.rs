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

/// An EMCY frame with fewer than 8 data bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
#[error("EMCY message has {0} data bytes, expected 8")]
pub struct EmcyLengthError(pub usize);

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

/// An emergency message's content.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Emergency {
    /// Error code (0000h = error reset).
    pub code: u16,
    /// Error register.
    pub register: u8,
    /// Bytes 3–7.
    pub vendor: [u8; 5],
}

impl Emergency {
    /// Decode the data bytes of an EMCY frame.
    pub fn parse(data: &[u8]) -> Result<Self, EmcyLengthError> {
        let f = EmcyFrame::new_checked(data)?;
        Ok(Self {
            code: f.error_code(),
            register: f.error_register(),
            vendor: f.vendor(),
        })
    }

    /// The frame `node` sends (COB-ID 080h + node unless 1014h moved it: pass `cob_id`).
    pub fn frame(&self, cob_id: u16) -> CanFrame {
        let [c0, c1] = self.code.to_le_bytes();
        let v = self.vendor;
        CanFrame::from_parts(
            cob_id,
            [c0, c1, self.register, v[0], v[1], v[2], v[3], v[4]],
            8,
        )
    }

    /// The frame on the default COB-ID of `node`.
    pub fn default_frame(&self, node: u8) -> CanFrame {
        self.frame(cob::emcy(node))
    }

    /// Whether this is the "error reset / no error" message.
    pub const fn is_reset(&self) -> bool {
        self.code == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let e = Emergency {
            code: 0x7305,
            register: 0x81,
            vendor: [0x11, 0x00, 0, 0, 0],
        };
        let f = e.default_frame(0x7F);
        assert_eq!(f.id(), 0xFF);
        assert_eq!(f.data(), &[0x05, 0x73, 0x81, 0x11, 0, 0, 0, 0]);
        assert_eq!(Emergency::parse(f.data()).unwrap(), e);
        assert!(Emergency::parse(&[0; 7]).is_err());
    }
}
