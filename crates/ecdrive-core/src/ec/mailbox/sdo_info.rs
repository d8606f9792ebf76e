//! SDO information (CoE service 8): the [`SdoInfo`] view, requests, fragments, OD lists, object and entry descriptions.

use super::*;

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
