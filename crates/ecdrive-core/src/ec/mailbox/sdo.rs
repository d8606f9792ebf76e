//! SDO (CoE service 2/3): the command byte, the [`Sdo`] view, [`SdoRequest`] and [`SdoResponse`].

use super::*;

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

pub(super) fn initiate_cmd(
    specifier: u8,
    complete_access: bool,
    expedited_len: Option<usize>,
) -> u8 {
    let ca = if complete_access { 0x10 } else { 0 };
    let rest = match expedited_len {
        // e = 1, s = 1, n = 4 − len
        Some(len) => 0x03 | (((4 - len.min(4)) as u8) << 2),
        // normal: s = 1 (size indicated)
        None => 0x01,
    };
    (specifier << 5) | ca | rest
}

pub(super) fn segment_cmd(specifier: u8, toggle: bool, last: bool, len: usize) -> u8 {
    let unused = if len < 7 { (7 - len) as u8 } else { 0 };
    (specifier << 5) | (u8::from(toggle) << 4) | (unused << 1) | u8::from(last)
}

/// Write an initiate/abort SDO body (8 bytes + `extra`) into `sdo`.
pub(super) fn emit_initiate(
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
pub(super) fn emit_segment(sdo: &mut [u8], cmd: u8, data: &[u8]) -> Result<usize, Error> {
    let len = 1 + data.len().max(7);
    space("SDO segment", len, sdo.len())?;
    wr_u8(sdo, 0, cmd);
    if let Some(d) = sdo.get_mut(1..len) {
        d.fill(0);
    }
    wr(sdo, 1, data);
    Ok(len)
}

pub(super) fn expedited_word(data: &[u8]) -> Result<[u8; 4], Error> {
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

pub(super) fn expedited_data(sdo: &[u8]) -> &[u8] {
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

pub(super) fn sdo_segment_data(sdo: &[u8]) -> &[u8] {
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
