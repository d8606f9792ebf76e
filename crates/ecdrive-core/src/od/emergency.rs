//! The CiA 301 emergency message, one type for both buses: 8 bytes, bytes 0–1 the error code
//! (little endian; 0x0000 = error reset / no error), byte 2 the error register (0x1001),
//! bytes 3–7 manufacturer-specific. CANopen sends them as an EMCY frame
//! ([`crate::can::emcy`]), EtherCAT as a CoE emergency in the mailbox ([`crate::ec::mailbox`]);
//! each bus adds only its framing.

/// Emergency data of the wrong length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
#[error("emergency message has {0} data bytes, expected 8")]
pub struct EmergencyLengthError(pub usize);

/// A CiA 301 emergency message: error code, error register and five manufacturer bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
pub struct Emergency {
    /// Error code (CiA 301 / CiA 402, e.g. 0x2310 over-current; 0x0000 = error reset).
    pub error_code: u16,
    /// Error register (object 0x1001).
    pub error_register: u8,
    /// Manufacturer-specific bytes 3–7.
    pub data: [u8; 5],
}

impl Emergency {
    /// Size of the message.
    pub const LEN: usize = 8;

    /// Decode the 8 bytes of a message.
    pub fn parse(bytes: &[u8]) -> Result<Self, EmergencyLengthError> {
        let b: &[u8; 8] = bytes
            .try_into()
            .map_err(|_| EmergencyLengthError(bytes.len()))?;
        let [c0, c1, register, d0, d1, d2, d3, d4] = *b;
        Ok(Self {
            error_code: u16::from_le_bytes([c0, c1]),
            error_register: register,
            data: [d0, d1, d2, d3, d4],
        })
    }

    /// The 8 bytes of the message.
    pub const fn to_bytes(&self) -> [u8; 8] {
        let [c0, c1] = self.error_code.to_le_bytes();
        let d = self.data;
        [c0, c1, self.error_register, d[0], d[1], d[2], d[3], d[4]]
    }

    /// Whether this is the "error reset / no error" message.
    pub const fn is_reset(&self) -> bool {
        self.error_code == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_round_trip_and_length_is_checked() {
        let e = Emergency {
            error_code: 0x7305,
            error_register: 0x81,
            data: [0x11, 0, 0, 0, 0x22],
        };
        assert_eq!(e.to_bytes(), [0x05, 0x73, 0x81, 0x11, 0, 0, 0, 0x22]);
        assert_eq!(Emergency::parse(&e.to_bytes()), Ok(e));
        assert_eq!(Emergency::parse(&[0; 7]), Err(EmergencyLengthError(7)));
        assert_eq!(Emergency::parse(&[0; 9]), Err(EmergencyLengthError(9)));
        assert!(Emergency::default().is_reset());
    }
}
