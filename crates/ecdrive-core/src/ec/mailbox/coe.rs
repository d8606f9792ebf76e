//! The CoE header (ETG.1000.6 §5.6): [`CoeService`], the [`Coe`] view.

use super::*;

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
pub(super) fn emit_coe_headers(
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

pub(super) const COE_BODY: usize = MAILBOX_HEADER_LEN + COE_HEADER_LEN;
