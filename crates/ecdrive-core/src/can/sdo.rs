//! The SDO protocol over CAN (CiA 301 §7.2.4): expedited and segmented upload and download,
//! and abort. Block transfer is not offered by any of the three drives (BLV-R §4.6, ASDA-A2
//! §5.3, Lexium §3.2), so it is neither requested nor served; a block request is aborted with
//! `0504 0001h`.
//!
//! - [`SdoFrame`]: a checked view over the 8 data bytes of a request or response.
//! - [`ClientTransfer`]: the client side of one transfer as a pure state machine: it produces the
//!   next request from each response and never does I/O (the master sends and times out).
//!
//! The server side serves the emulated nodes and lives with them in the software slave
//! (`sim::canopen::sdo_server`, over the same object store as its CoE server); the segmented
//! transfer itself is [`crate::od::Segmented`], shared with CoE.
//!
//! Command byte layout (byte 0), `ccs`/`scs` in bits 7–5:
//!
//! | frame | byte 0 |
//! |---|---|
//! | initiate download request | `001x nnes` (n = bytes without data, e = expedited, s = size given) |
//! | initiate download response | `0110 0000` (60h) |
//! | download segment request | `000t nnnc` (t = toggle, n = bytes without data, c = last) |
//! | download segment response | `001t 0000` |
//! | initiate upload request | `0100 0000` (40h) |
//! | initiate upload response | `010x nnes` |
//! | upload segment request | `011t 0000` |
//! | upload segment response | `000t nnnc` |
//! | abort | `1000 0000` (80h), bytes 4–7 the abort code |
//!
//! ⚠ The Lexium manual's Table 3.4 swaps the upload request (40h) and response (4xh) bytes; its
//! example frames are CiA-conformant and so is this module.

use crate::od::{ObjectAddress, SdoAbortCode, SegmentError, Segmented};
use core::fmt;

/// Largest value this module transfers, in bytes (client uploads and server downloads).
/// **\[REC\]**: far above every object of the three drives (their longest is the Lexium device
/// name, 41 bytes); it bounds memory if a peer announces a huge size.
pub const MAX_TRANSFER: usize = 4096;

/// A frame that is not a well-formed SDO message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum SdoFrameError {
    /// SDO frames are 8 bytes (CiA 301 §7.2.4.3).
    #[error("SDO frame has {0} data bytes, expected 8")]
    Length(usize),
}

/// A checked view over the 8 data bytes of an SDO frame (smoltcp style).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdoFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> SdoFrame<T> {
    /// The view, if `buffer` holds exactly 8 bytes.
    pub fn new_checked(buffer: T) -> Result<Self, SdoFrameError> {
        let len = buffer.as_ref().len();
        if len != 8 {
            return Err(SdoFrameError::Length(len));
        }
        Ok(Self { buffer })
    }

    fn byte(&self, i: usize) -> u8 {
        self.buffer.as_ref().get(i).copied().unwrap_or(0)
    }

    /// Byte 0, the command byte.
    pub fn command(&self) -> u8 {
        self.byte(0)
    }

    /// The command specifier, bits 7–5 of byte 0.
    pub fn specifier(&self) -> u8 {
        self.command() >> 5
    }

    /// Bytes 1–2 and 3 of an initiate or abort frame: the object address.
    pub fn address(&self) -> ObjectAddress {
        ObjectAddress::new(
            u16::from_le_bytes([self.byte(1), self.byte(2)]),
            self.byte(3),
        )
    }

    /// Initiate: e (bit 1), expedited transfer.
    pub fn expedited(&self) -> bool {
        self.command() & 0x02 != 0
    }

    /// Initiate: s (bit 0), size indicated.
    pub fn size_indicated(&self) -> bool {
        self.command() & 0x01 != 0
    }

    /// Initiate, expedited with size: data bytes in 4–7 (`4 - n`, n in bits 3–2).
    pub fn expedited_len(&self) -> usize {
        4 - usize::from((self.command() >> 2) & 0x03)
    }

    /// Bytes 4–7 as a little-endian number: the size of a segmented transfer or an abort code.
    pub fn u32_at_4(&self) -> u32 {
        u32::from_le_bytes([self.byte(4), self.byte(5), self.byte(6), self.byte(7)])
    }

    /// Bytes 4–7.
    pub fn data4(&self) -> [u8; 4] {
        [self.byte(4), self.byte(5), self.byte(6), self.byte(7)]
    }

    /// Segment: t (bit 4), the toggle bit.
    pub fn toggle(&self) -> bool {
        self.command() & 0x10 != 0
    }

    /// Segment: c (bit 0), no more segments.
    pub fn last(&self) -> bool {
        self.command() & 0x01 != 0
    }

    /// Segment: data bytes in 1–7 (`7 - n`, n in bits 3–1).
    pub fn segment_len(&self) -> usize {
        7 - usize::from((self.command() >> 1) & 0x07)
    }

    /// Bytes 1–7.
    pub fn data7(&self) -> [u8; 7] {
        [
            self.byte(1),
            self.byte(2),
            self.byte(3),
            self.byte(4),
            self.byte(5),
            self.byte(6),
            self.byte(7),
        ]
    }
}

fn initiate(cmd: u8, addr: ObjectAddress, data: [u8; 4]) -> [u8; 8] {
    let [i0, i1] = addr.index.to_le_bytes();
    [cmd, i0, i1, addr.sub, data[0], data[1], data[2], data[3]]
}

/// An abort frame for `addr` with `code`.
pub fn abort_frame(addr: ObjectAddress, code: SdoAbortCode) -> [u8; 8] {
    initiate(0x80, addr, code.0.to_le_bytes())
}

/// A decoded SDO request (client → server).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoRequest {
    /// Initiate download. `data` holds the expedited bytes (`len` of them) or, for a segmented
    /// transfer, nothing; `size` is the indicated size, if any.
    InitiateDownload {
        /// Object.
        addr: ObjectAddress,
        /// Expedited data (first `len` bytes valid), `None` for a segmented transfer.
        expedited: Option<([u8; 4], usize)>,
        /// Size indicated by the client (s = 1).
        size: Option<u32>,
    },
    /// One download segment.
    DownloadSegment {
        /// Toggle bit.
        toggle: bool,
        /// Data (first `len` bytes valid).
        data: [u8; 7],
        /// Data bytes.
        len: usize,
        /// Last segment.
        last: bool,
    },
    /// Initiate upload.
    InitiateUpload {
        /// Object.
        addr: ObjectAddress,
    },
    /// Request the next upload segment.
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
    },
    /// The client aborts.
    Abort {
        /// Object.
        addr: ObjectAddress,
        /// Code.
        code: SdoAbortCode,
    },
    /// A specifier this implementation does not serve (block transfer 5/6, 7).
    Unsupported {
        /// Object, as bytes 1–3 give it.
        addr: ObjectAddress,
        /// The command byte.
        command: u8,
    },
}

impl SdoRequest {
    /// Decode 8 request bytes.
    pub fn parse(bytes: &[u8]) -> Result<Self, SdoFrameError> {
        let f = SdoFrame::new_checked(bytes)?;
        Ok(match f.specifier() {
            1 => {
                let expedited = f.expedited().then(|| {
                    let len = if f.size_indicated() {
                        f.expedited_len()
                    } else {
                        4
                    };
                    (f.data4(), len)
                });
                let size = if f.size_indicated() {
                    Some(match expedited {
                        Some((_, len)) => len as u32,
                        None => f.u32_at_4(),
                    })
                } else {
                    None
                };
                SdoRequest::InitiateDownload {
                    addr: f.address(),
                    expedited,
                    size,
                }
            }
            0 => SdoRequest::DownloadSegment {
                toggle: f.toggle(),
                data: f.data7(),
                len: f.segment_len(),
                last: f.last(),
            },
            2 => SdoRequest::InitiateUpload { addr: f.address() },
            3 => SdoRequest::UploadSegment { toggle: f.toggle() },
            4 => SdoRequest::Abort {
                addr: f.address(),
                code: SdoAbortCode(f.u32_at_4()),
            },
            _ => SdoRequest::Unsupported {
                addr: f.address(),
                command: f.command(),
            },
        })
    }

    /// The 8 bytes of an initiate-upload request.
    pub fn initiate_upload(addr: ObjectAddress) -> [u8; 8] {
        initiate(0x40, addr, [0; 4])
    }

    /// The 8 bytes of an expedited download of 1–4 bytes (size indicated). `None` if `data` is
    /// empty or longer than 4 bytes.
    pub fn expedited_download(addr: ObjectAddress, data: &[u8]) -> Option<[u8; 8]> {
        if data.is_empty() || data.len() > 4 {
            return None;
        }
        let n = (4 - data.len()) as u8;
        let mut d = [0u8; 4];
        d.get_mut(..data.len())?.copy_from_slice(data);
        Some(initiate(0x23 | (n << 2), addr, d))
    }

    /// The 8 bytes of the initiate request of a segmented download of `size` bytes.
    pub fn segmented_download(addr: ObjectAddress, size: u32) -> [u8; 8] {
        initiate(0x21, addr, size.to_le_bytes())
    }

    /// The 8 bytes of a download segment with up to 7 bytes of `data` (more are ignored).
    pub fn download_segment(toggle: bool, data: &[u8], last: bool) -> [u8; 8] {
        let len = data.len().min(7);
        let n = (7 - len) as u8;
        let mut out = [0u8; 8];
        out[0] = (u8::from(toggle) << 4) | (n << 1) | u8::from(last);
        if let (Some(dst), Some(src)) = (out.get_mut(1..1 + len), data.get(..len)) {
            dst.copy_from_slice(src);
        }
        out
    }

    /// The 8 bytes of an upload-segment request.
    pub fn upload_segment(toggle: bool) -> [u8; 8] {
        [0x60 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0]
    }
}

/// A decoded SDO response (server → client).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoResponse {
    /// Initiate-download confirmed.
    DownloadInitiated {
        /// Object.
        addr: ObjectAddress,
    },
    /// Download segment confirmed.
    DownloadSegment {
        /// Toggle bit.
        toggle: bool,
    },
    /// Initiate-upload answer: expedited data, or the start of a segmented upload.
    UploadInitiated {
        /// Object.
        addr: ObjectAddress,
        /// Expedited data (first `len` bytes valid), `None` for a segmented upload.
        expedited: Option<([u8; 4], usize)>,
        /// Indicated size, if any.
        size: Option<u32>,
    },
    /// One upload segment.
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
        /// Data (first `len` bytes valid).
        data: [u8; 7],
        /// Data bytes.
        len: usize,
        /// Last segment.
        last: bool,
    },
    /// The server aborts.
    Abort {
        /// Object.
        addr: ObjectAddress,
        /// Code.
        code: SdoAbortCode,
    },
    /// A specifier a server does not send to a client doing expedited/segmented transfers.
    Unexpected {
        /// The command byte.
        command: u8,
    },
}

impl SdoResponse {
    /// Decode 8 response bytes.
    pub fn parse(bytes: &[u8]) -> Result<Self, SdoFrameError> {
        let f = SdoFrame::new_checked(bytes)?;
        Ok(match f.specifier() {
            3 => SdoResponse::DownloadInitiated { addr: f.address() },
            1 => SdoResponse::DownloadSegment { toggle: f.toggle() },
            2 => {
                let expedited = f.expedited().then(|| {
                    let len = if f.size_indicated() {
                        f.expedited_len()
                    } else {
                        4
                    };
                    (f.data4(), len)
                });
                let size = match (f.size_indicated(), expedited) {
                    (false, _) => None,
                    (true, Some((_, len))) => Some(len as u32),
                    (true, None) => Some(f.u32_at_4()),
                };
                SdoResponse::UploadInitiated {
                    addr: f.address(),
                    expedited,
                    size,
                }
            }
            0 => SdoResponse::UploadSegment {
                toggle: f.toggle(),
                data: f.data7(),
                len: f.segment_len(),
                last: f.last(),
            },
            4 => SdoResponse::Abort {
                addr: f.address(),
                code: SdoAbortCode(f.u32_at_4()),
            },
            _ => SdoResponse::Unexpected {
                command: f.command(),
            },
        })
    }

    /// Initiate-download confirmation bytes.
    pub fn download_initiated(addr: ObjectAddress) -> [u8; 8] {
        initiate(0x60, addr, [0; 4])
    }

    /// Download-segment confirmation bytes.
    pub fn download_segment(toggle: bool) -> [u8; 8] {
        [0x20 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0]
    }

    /// Expedited upload answer with 1–4 bytes (size indicated). `None` if `data` is empty or
    /// longer than 4 bytes.
    pub fn expedited_upload(addr: ObjectAddress, data: &[u8]) -> Option<[u8; 8]> {
        if data.is_empty() || data.len() > 4 {
            return None;
        }
        let n = (4 - data.len()) as u8;
        let mut d = [0u8; 4];
        d.get_mut(..data.len())?.copy_from_slice(data);
        Some(initiate(0x43 | (n << 2), addr, d))
    }

    /// Answer that starts a segmented upload of `size` bytes.
    pub fn segmented_upload(addr: ObjectAddress, size: u32) -> [u8; 8] {
        initiate(0x41, addr, size.to_le_bytes())
    }

    /// One upload segment with up to 7 bytes of `data`.
    pub fn upload_segment(toggle: bool, data: &[u8], last: bool) -> [u8; 8] {
        // Same layout as a download segment request.
        SdoRequest::download_segment(toggle, data, last)
    }
}

// ---------------------------------------------------------------------------------------------
// Client

/// Why a client transfer failed (the master adds the node and the object).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SdoError {
    /// The server aborted.
    #[error("SDO abort {0}")]
    Abort(SdoAbortCode),
    /// No response in time.
    #[error("no SDO response within {0} ms")]
    Timeout(u64),
    /// The response broke the protocol; the client aborts the transfer with `code`.
    #[error("SDO protocol error: {what} (transfer aborted with {code})")]
    Protocol {
        /// What was wrong.
        what: &'static str,
        /// The abort code sent to the server.
        code: SdoAbortCode,
    },
    /// A value of more than [`MAX_TRANSFER`] bytes.
    #[error("SDO transfer of {0} bytes exceeds the limit of {MAX_TRANSFER} bytes")]
    TooLarge(usize),
    /// Download of nothing.
    #[error("SDO download of zero bytes")]
    Empty,
}

impl SdoError {
    /// The abort code, if the server aborted.
    pub fn abort_code(&self) -> Option<SdoAbortCode> {
        match self {
            SdoError::Abort(c) => Some(*c),
            _ => None,
        }
    }
}

/// What the client does next.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientStep {
    /// Send these 8 bytes and wait for the response.
    Send([u8; 8]),
    /// Upload finished with this value.
    Uploaded(Vec<u8>),
    /// Download finished.
    Downloaded,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum ClientState {
    UploadInit,
    UploadSegments(Segmented),
    DownloadInit { segmented: bool },
    DownloadSegments(Segmented),
    Done,
}

/// One client transfer as a state machine. Start it with [`ClientTransfer::upload`] or
/// [`ClientTransfer::download`] (which return the first request), then feed every response to
/// [`ClientTransfer::on_response`] until it returns a result. On
/// [`SdoError::Protocol`] send [`ClientTransfer::abort`] to the server.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClientTransfer {
    addr: ObjectAddress,
    state: ClientState,
    buf: Vec<u8>,
    abort_code: Option<SdoAbortCode>,
}

impl ClientTransfer {
    /// Start an upload of `addr`.
    pub fn upload(addr: ObjectAddress) -> (Self, [u8; 8]) {
        (
            Self {
                addr,
                state: ClientState::UploadInit,
                buf: Vec::new(),
                abort_code: None,
            },
            SdoRequest::initiate_upload(addr),
        )
    }

    /// Start a download of `data` to `addr`: expedited for 1–4 bytes, segmented above.
    pub fn download(addr: ObjectAddress, data: Vec<u8>) -> Result<(Self, [u8; 8]), SdoError> {
        if data.is_empty() {
            return Err(SdoError::Empty);
        }
        if data.len() > MAX_TRANSFER {
            return Err(SdoError::TooLarge(data.len()));
        }
        let first = match SdoRequest::expedited_download(addr, &data) {
            Some(f) => (f, false),
            None => (
                SdoRequest::segmented_download(addr, data.len() as u32),
                true,
            ),
        };
        Ok((
            Self {
                addr,
                state: ClientState::DownloadInit { segmented: first.1 },
                buf: data,
                abort_code: None,
            },
            first.0,
        ))
    }

    /// Start a segmented download of `data` even if it would fit an expedited one (for servers
    /// that need it, and for tests of the segmented protocol).
    pub fn download_segmented(
        addr: ObjectAddress,
        data: Vec<u8>,
    ) -> Result<(Self, [u8; 8]), SdoError> {
        if data.is_empty() {
            return Err(SdoError::Empty);
        }
        if data.len() > MAX_TRANSFER {
            return Err(SdoError::TooLarge(data.len()));
        }
        let first = SdoRequest::segmented_download(addr, data.len() as u32);
        Ok((
            Self {
                addr,
                state: ClientState::DownloadInit { segmented: true },
                buf: data,
                abort_code: None,
            },
            first,
        ))
    }

    /// The object being transferred.
    pub const fn address(&self) -> ObjectAddress {
        self.addr
    }

    /// The abort frame to send after a protocol error (or to cancel at a timeout).
    pub fn abort(&self) -> [u8; 8] {
        abort_frame(self.addr, self.abort_code.unwrap_or(SdoAbortCode::TIMEOUT))
    }

    fn fail(&mut self, what: &'static str, code: SdoAbortCode) -> SdoError {
        self.state = ClientState::Done;
        self.abort_code = Some(code);
        SdoError::Protocol { what, code }
    }

    /// Feed one response (the 8 data bytes from 580h + node).
    pub fn on_response(&mut self, bytes: &[u8]) -> Result<ClientStep, SdoError> {
        let resp = match SdoResponse::parse(bytes) {
            Ok(r) => r,
            Err(_) => {
                return Err(self.fail(
                    "SDO response is not 8 bytes long",
                    SdoAbortCode::INVALID_COMMAND,
                ));
            }
        };
        if let SdoResponse::Abort { code, .. } = resp {
            self.state = ClientState::Done;
            return Err(SdoError::Abort(code));
        }
        match self.state.clone() {
            ClientState::Done => Err(self.fail(
                "response after the transfer ended",
                SdoAbortCode::INVALID_COMMAND,
            )),
            ClientState::UploadInit => match resp {
                SdoResponse::UploadInitiated {
                    addr,
                    expedited,
                    size,
                } => {
                    if addr != self.addr {
                        return Err(self.fail(
                            "the response names another object",
                            SdoAbortCode::INVALID_COMMAND,
                        ));
                    }
                    if let Some((data, len)) = expedited {
                        self.state = ClientState::Done;
                        return Ok(ClientStep::Uploaded(
                            data.get(..len).unwrap_or(&data).to_vec(),
                        ));
                    }
                    if let Some(s) = size
                        && s as usize > MAX_TRANSFER
                    {
                        self.fail("announced size too large", SdoAbortCode::OUT_OF_MEMORY);
                        return Err(SdoError::TooLarge(s as usize));
                    }
                    let seg = Segmented::start(0, size.map(|s| s as usize));
                    self.state = ClientState::UploadSegments(seg);
                    Ok(ClientStep::Send(SdoRequest::upload_segment(seg.toggle())))
                }
                _ => Err(self.fail(
                    "expected an initiate-upload response",
                    SdoAbortCode::INVALID_COMMAND,
                )),
            },
            ClientState::UploadSegments(mut seg) => match resp {
                SdoResponse::UploadSegment {
                    toggle,
                    data,
                    len,
                    last,
                } => {
                    let data = data.get(..len).unwrap_or(&[]);
                    match seg.next_in(toggle, data.len(), last, MAX_TRANSFER) {
                        Ok(done) => {
                            self.buf.extend_from_slice(data);
                            if done {
                                self.state = ClientState::Done;
                                return Ok(ClientStep::Uploaded(core::mem::take(&mut self.buf)));
                            }
                            self.state = ClientState::UploadSegments(seg);
                            Ok(ClientStep::Send(SdoRequest::upload_segment(seg.toggle())))
                        }
                        Err(SegmentError::Toggle) => {
                            Err(self.fail("toggle bit not alternated", SdoAbortCode::TOGGLE_BIT))
                        }
                        Err(SegmentError::OverLimit { .. }) => {
                            let n = seg.position() + data.len();
                            self.fail("upload too large", SdoAbortCode::OUT_OF_MEMORY);
                            Err(SdoError::TooLarge(n))
                        }
                        Err(_) => Err(self.fail(
                            "uploaded length differs from the indicated size",
                            SdoAbortCode::LENGTH_MISMATCH,
                        )),
                    }
                }
                _ => Err(self.fail("expected an upload segment", SdoAbortCode::INVALID_COMMAND)),
            },
            ClientState::DownloadInit { segmented } => match resp {
                SdoResponse::DownloadInitiated { addr } if addr == self.addr => {
                    if !segmented {
                        self.state = ClientState::Done;
                        return Ok(ClientStep::Downloaded);
                    }
                    Ok(self.next_segment(Segmented::start(0, Some(self.buf.len()))))
                }
                SdoResponse::DownloadInitiated { .. } => Err(self.fail(
                    "the response names another object",
                    SdoAbortCode::INVALID_COMMAND,
                )),
                _ => Err(self.fail(
                    "expected an initiate-download response",
                    SdoAbortCode::INVALID_COMMAND,
                )),
            },
            ClientState::DownloadSegments(seg) => match resp {
                SdoResponse::DownloadSegment { toggle } => {
                    if seg.acknowledged(toggle).is_err() {
                        return Err(
                            self.fail("toggle bit not alternated", SdoAbortCode::TOGGLE_BIT)
                        );
                    }
                    if seg.sent_all(self.buf.len()) {
                        self.state = ClientState::Done;
                        return Ok(ClientStep::Downloaded);
                    }
                    Ok(self.next_segment(seg))
                }
                _ => Err(self.fail(
                    "expected a download-segment response",
                    SdoAbortCode::INVALID_COMMAND,
                )),
            },
        }
    }

    fn next_segment(&mut self, mut seg: Segmented) -> ClientStep {
        let out = seg.next_out(self.buf.len(), 7);
        let chunk = self.buf.get(out.range).unwrap_or(&[]);
        let frame = SdoRequest::download_segment(out.toggle, chunk, out.last);
        self.state = ClientState::DownloadSegments(seg);
        ClientStep::Send(frame)
    }
}

/// The text of an abort code: the standard CiA 301 text, else a vendor text from `vendor` (a
/// drive profile's list, e.g. the ASDA-A2's EEPROM codes `0800 00A1h`–`00A5h`), else "unknown".
pub fn abort_text(code: SdoAbortCode, vendor: &[(u32, &'static str)]) -> AbortText {
    let text = code
        .text()
        .or_else(|| vendor.iter().find(|(c, _)| *c == code.0).map(|(_, t)| *t));
    AbortText { code, text }
}

/// An abort code with its text, for messages: `0x06020000 (Object does not exist …)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AbortText {
    /// The code.
    pub code: SdoAbortCode,
    /// Its text, if known.
    pub text: Option<&'static str>,
}

impl fmt::Display for AbortText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.text {
            Some(t) => write!(f, "0x{:08X} ({t})", self.code.0),
            None => write!(f, "0x{:08X} (unknown abort code)", self.code.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn frame_bytes_match_cia_301() {
        let a = ObjectAddress::new(0x6040, 0);
        assert_eq!(
            SdoRequest::expedited_download(a, &[0x0F, 0]).unwrap(),
            [0x2B, 0x40, 0x60, 0, 0x0F, 0, 0, 0]
        );
        assert_eq!(
            SdoRequest::expedited_download(a, &[1, 2, 3, 4]).unwrap()[0],
            0x23
        );
        assert_eq!(SdoRequest::expedited_download(a, &[1]).unwrap()[0], 0x2F);
        assert_eq!(
            SdoRequest::initiate_upload(a),
            [0x40, 0x40, 0x60, 0, 0, 0, 0, 0]
        );
        assert_eq!(SdoRequest::upload_segment(true)[0], 0x70);
        assert_eq!(
            SdoRequest::download_segment(false, &[1, 2, 3], true)[0],
            0x09
        );
        assert_eq!(
            abort_frame(a, SdoAbortCode::NO_OBJECT),
            [0x80, 0x40, 0x60, 0, 0, 0, 0x02, 0x06]
        );
        // Lexium §3.2 example: a 41-byte string starts with 41h and the size.
        assert_eq!(
            SdoResponse::segmented_upload(ObjectAddress::new(0x1008, 0), 41)[..5],
            [0x41, 0x08, 0x10, 0, 41]
        );
    }

    #[test]
    fn a_client_that_sees_a_bad_toggle_aborts() {
        let a = ObjectAddress::new(0x2000, 9);
        // A client that sees a bad toggle aborts with 0503 0000h.
        let (mut t, _) = ClientTransfer::upload(a);
        t.on_response(&SdoResponse::segmented_upload(a, 10))
            .unwrap();
        let e = t
            .on_response(&SdoResponse::upload_segment(true, &[0; 7], false))
            .unwrap_err();
        assert!(matches!(
            e,
            SdoError::Protocol {
                code: SdoAbortCode::TOGGLE_BIT,
                ..
            }
        ));
        assert_eq!(t.abort()[4..], 0x0503_0000u32.to_le_bytes());
    }

    #[test]
    fn abort_texts() {
        assert_eq!(
            abort_text(SdoAbortCode(0x0800_00A1), &[(0x0800_00A1, "EEPROM read")]).to_string(),
            "0x080000A1 (EEPROM read)"
        );
        assert!(
            abort_text(SdoAbortCode::NO_OBJECT, &[])
                .to_string()
                .contains("does not exist")
        );
        assert!(
            abort_text(SdoAbortCode(0x1234_5678), &[])
                .to_string()
                .contains("unknown")
        );
    }
}
