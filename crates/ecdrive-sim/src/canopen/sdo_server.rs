//! The SDO server of an emulated CANopen node (CiA 301 §7.2.4): expedited and segmented upload
//! and download, toggle checking and aborts, over the same [`ObjectStore`] the CoE server
//! serves. The frames are `can::sdo`'s; the segmented transfer is the one both buses share
//! ([`Segmented`]).
//!
//! CANopen has no AL state: the node passes the access state its NMT state stands for
//! (pre-operational → PRE-OP, operational → OP, the `EntryAccess` flags' terms).

use crate::can::sdo::{MAX_TRANSFER, SdoRequest, SdoResponse, abort_frame};
use crate::coe::ObjectStore;
use crate::ec::AlState;
use crate::od::{ObjectAddress, SdoAbortCode, SegmentError, Segmented};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ServerState {
    Idle,
    Downloading { addr: ObjectAddress, seg: Segmented },
    Uploading { addr: ObjectAddress, seg: Segmented },
}

/// The server side of SDO for one node.
#[derive(Debug, Clone)]
pub struct SdoServer {
    state: ServerState,
    /// The value being transferred: received segments, or the value read for an upload.
    buf: Vec<u8>,
}

impl Default for SdoServer {
    fn default() -> Self {
        Self::new()
    }
}

/// The abort a server sends for a refused download segment (CiA 301 §7.2.4.3.17).
fn segment_abort(e: SegmentError) -> SdoAbortCode {
    match e {
        SegmentError::Toggle => SdoAbortCode::TOGGLE_BIT,
        SegmentError::LongerThanAnnounced { .. } | SegmentError::OverLimit { .. } => {
            SdoAbortCode::LENGTH_TOO_HIGH
        }
        SegmentError::ShorterThanAnnounced { .. } => SdoAbortCode::LENGTH_TOO_LOW,
    }
}

impl SdoServer {
    /// An idle server.
    pub fn new() -> Self {
        Self {
            state: ServerState::Idle,
            buf: Vec::new(),
        }
    }

    /// Whether a segmented transfer is in progress.
    pub fn busy(&self) -> bool {
        self.state != ServerState::Idle
    }

    /// Drop any transfer (NMT reset).
    pub fn reset(&mut self) {
        self.state = ServerState::Idle;
        self.buf.clear();
    }

    fn abort(&mut self, addr: ObjectAddress, code: SdoAbortCode) -> Option<[u8; 8]> {
        self.reset();
        Some(abort_frame(addr, code))
    }

    /// Handle one request (the 8 data bytes from 600h + node) in access state `state`; returns
    /// the response, if any. A request that is not 8 bytes long is ignored (no response); an
    /// abort from the client ends the transfer without response.
    pub fn handle(
        &mut self,
        bytes: &[u8],
        state: AlState,
        objects: &mut dyn ObjectStore,
    ) -> Option<[u8; 8]> {
        let req = SdoRequest::parse(bytes).ok()?;
        match req {
            SdoRequest::Abort { .. } => {
                self.reset();
                None
            }
            SdoRequest::Unsupported { addr, .. } => self.abort(addr, SdoAbortCode::INVALID_COMMAND),
            SdoRequest::InitiateDownload {
                addr,
                expedited: Some((data, len)),
                size,
            } => {
                self.reset();
                let mut d = data.get(..len).unwrap_or(&data);
                if size.is_none() {
                    // No size indicated: the client sent 4 bytes, the object takes its own size.
                    match objects.entry(addr.index, addr.sub) {
                        Ok(e) if !e.data_type.is_string() => {
                            let need = usize::from(e.bit_len).div_ceil(8);
                            if need > 0 && need < d.len() {
                                d = d.get(..need).unwrap_or(d);
                            }
                        }
                        Ok(_) => {}
                        Err(code) => return self.abort(addr, code),
                    }
                }
                match objects.write(addr.index, addr.sub, state, d) {
                    Ok(()) => Some(SdoResponse::download_initiated(addr)),
                    Err(code) => self.abort(addr, code),
                }
            }
            SdoRequest::InitiateDownload {
                addr,
                expedited: None,
                size,
            } => {
                self.reset();
                if let Err(code) = Self::writable(objects, addr, size) {
                    return self.abort(addr, code);
                }
                self.state = ServerState::Downloading {
                    addr,
                    seg: Segmented::start(0, size.map(|s| s as usize)),
                };
                Some(SdoResponse::download_initiated(addr))
            }
            SdoRequest::DownloadSegment {
                toggle,
                data,
                len,
                last,
            } => {
                self.download_segment(toggle, data.get(..len).unwrap_or(&[]), last, state, objects)
            }
            SdoRequest::InitiateUpload { addr } => self.initiate_upload(addr, state, objects),
            SdoRequest::UploadSegment { toggle } => self.upload_segment(toggle),
        }
    }

    /// Whether a segmented download of `size` bytes (if indicated) to `addr` can start: refused
    /// at the initiate, before any segment moves, when the entry is missing or read-only or the
    /// size exceeds it or the server's limit.
    fn writable(
        objects: &dyn ObjectStore,
        addr: ObjectAddress,
        size: Option<u32>,
    ) -> Result<(), SdoAbortCode> {
        let e = objects.entry(addr.index, addr.sub)?;
        if !e.access.writable() {
            return Err(SdoAbortCode::READ_ONLY);
        }
        let cap = usize::from(e.bit_len).div_ceil(8);
        match size.map(|s| s as usize) {
            Some(s) if s > MAX_TRANSFER || (cap > 0 && s > cap) => {
                Err(SdoAbortCode::LENGTH_TOO_HIGH)
            }
            _ => Ok(()),
        }
    }

    fn download_segment(
        &mut self,
        toggle: bool,
        data: &[u8],
        last: bool,
        state: AlState,
        objects: &mut dyn ObjectStore,
    ) -> Option<[u8; 8]> {
        let ServerState::Downloading { addr, mut seg } = self.state else {
            return self.abort(ObjectAddress::new(0, 0), SdoAbortCode::INVALID_COMMAND);
        };
        let done = match seg.next_in(toggle, data.len(), last, MAX_TRANSFER) {
            Ok(done) => done,
            Err(e) => return self.abort(addr, segment_abort(e)),
        };
        self.buf.extend_from_slice(data);
        if !done {
            self.state = ServerState::Downloading { addr, seg };
            return Some(SdoResponse::download_segment(toggle));
        }
        let value = core::mem::take(&mut self.buf);
        let r = objects.write(addr.index, addr.sub, state, &value);
        self.buf = value;
        self.reset();
        match r {
            Ok(()) => Some(SdoResponse::download_segment(toggle)),
            Err(code) => self.abort(addr, code),
        }
    }

    fn initiate_upload(
        &mut self,
        addr: ObjectAddress,
        state: AlState,
        objects: &mut dyn ObjectStore,
    ) -> Option<[u8; 8]> {
        self.reset();
        self.buf.resize(MAX_TRANSFER, 0);
        let len = match objects.read(addr.index, addr.sub, state, &mut self.buf) {
            Ok(n) => n.min(MAX_TRANSFER),
            Err(code) => return self.abort(addr, code),
        };
        self.buf.truncate(len);
        if len > 0
            && let Some(f) = SdoResponse::expedited_upload(addr, &self.buf)
        {
            self.buf.clear();
            return Some(f);
        }
        // Segmented; an empty string is a segmented upload of size 0 with one empty last
        // segment.
        self.state = ServerState::Uploading {
            addr,
            seg: Segmented::start(0, Some(len)),
        };
        Some(SdoResponse::segmented_upload(addr, len as u32))
    }

    fn upload_segment(&mut self, toggle: bool) -> Option<[u8; 8]> {
        let ServerState::Uploading { addr, mut seg } = self.state else {
            return self.abort(ObjectAddress::new(0, 0), SdoAbortCode::INVALID_COMMAND);
        };
        if seg.expect(toggle).is_err() {
            return self.abort(addr, SdoAbortCode::TOGGLE_BIT);
        }
        let out = seg.next_out(self.buf.len(), 7);
        let frame = SdoResponse::upload_segment(
            out.toggle,
            self.buf.get(out.range).unwrap_or(&[]),
            out.last,
        );
        if out.last {
            self.reset();
        } else {
            self.state = ServerState::Uploading { addr, seg };
        }
        Some(frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::sdo::{ClientStep, ClientTransfer, SdoError};
    use crate::od::{DataType, EntryAccess, EntryDesc, ObjectInfo};
    use std::collections::BTreeMap;

    /// Domain entries 0x2000:n of any length; 0x1000:00 read-only.
    #[derive(Default)]
    struct Store(BTreeMap<ObjectAddress, Vec<u8>>);

    impl ObjectStore for Store {
        fn object(&self, index: u16) -> Option<ObjectInfo> {
            (index == 0x1000 || index == 0x2000).then(|| ObjectInfo {
                index,
                data_type: 0,
                max_sub: 255,
                object_code: 9,
                name: "test".into(),
            })
        }
        fn entry(&self, index: u16, sub: u8) -> Result<EntryDesc, SdoAbortCode> {
            match index {
                0x1000 => Ok(EntryDesc::new(
                    sub,
                    "ro",
                    DataType::Unsigned32,
                    EntryAccess::RO,
                )),
                0x2000 => Ok(EntryDesc::new(sub, "d", DataType::Domain, EntryAccess::RW)),
                _ => Err(SdoAbortCode::NO_OBJECT),
            }
        }
        fn next_index(&self, _: Option<u16>) -> Option<u16> {
            None
        }
        fn read(
            &mut self,
            i: u16,
            s: u8,
            _: AlState,
            buf: &mut [u8],
        ) -> Result<usize, SdoAbortCode> {
            let v = self
                .0
                .get(&ObjectAddress::new(i, s))
                .ok_or(SdoAbortCode::NO_OBJECT)?;
            buf.get_mut(..v.len())
                .ok_or(SdoAbortCode::OUT_OF_MEMORY)?
                .copy_from_slice(v);
            Ok(v.len())
        }
        fn write(&mut self, i: u16, s: u8, _: AlState, d: &[u8]) -> Result<(), SdoAbortCode> {
            if i == 0x1000 {
                return Err(SdoAbortCode::READ_ONLY);
            }
            self.0.insert(ObjectAddress::new(i, s), d.to_vec());
            Ok(())
        }
    }

    fn run(
        server: &mut SdoServer,
        store: &mut Store,
        mut t: ClientTransfer,
        first: [u8; 8],
    ) -> Result<ClientStep, SdoError> {
        let mut req = first;
        for _ in 0..10_000 {
            let resp = server
                .handle(&req, AlState::PreOp, store)
                .expect("response");
            match t.on_response(&resp)? {
                ClientStep::Send(next) => req = next,
                done => return Ok(done),
            }
        }
        panic!("transfer did not end");
    }

    #[test]
    fn expedited_and_segmented_round_trips() {
        let mut s = SdoServer::new();
        let mut st = Store::default();
        for len in [1usize, 2, 3, 4, 5, 7, 8, 13, 14, 15, 100] {
            let a = ObjectAddress::new(0x2000, len as u8);
            let data: Vec<u8> = (0..len as u8).map(|b| b.wrapping_mul(7)).collect();
            let (t, f) = ClientTransfer::download(a, data.clone()).unwrap();
            assert_eq!(run(&mut s, &mut st, t, f), Ok(ClientStep::Downloaded));
            let (t, f) = ClientTransfer::upload(a);
            assert_eq!(run(&mut s, &mut st, t, f), Ok(ClientStep::Uploaded(data)));
            assert!(!s.busy());
        }
    }

    #[test]
    fn aborts_and_toggle_errors() {
        let mut s = SdoServer::new();
        let mut st = Store::default();
        let (t, f) = ClientTransfer::upload(ObjectAddress::new(0x1234, 0));
        assert_eq!(
            run(&mut s, &mut st, t, f),
            Err(SdoError::Abort(SdoAbortCode::NO_OBJECT))
        );
        let (t, f) = ClientTransfer::download(ObjectAddress::new(0x1000, 0), vec![1]).unwrap();
        assert_eq!(
            run(&mut s, &mut st, t, f),
            Err(SdoError::Abort(SdoAbortCode::READ_ONLY))
        );
        // A segmented download to a read-only entry is refused at the initiate.
        let (t, f) =
            ClientTransfer::download_segmented(ObjectAddress::new(0x1000, 0), vec![1; 9]).unwrap();
        assert_eq!(
            run(&mut s, &mut st, t, f),
            Err(SdoError::Abort(SdoAbortCode::READ_ONLY))
        );
        // A segment with the wrong toggle bit is aborted with 0503 0000h.
        let a = ObjectAddress::new(0x2000, 9);
        let pre = AlState::PreOp;
        s.handle(&SdoRequest::segmented_download(a, 10), pre, &mut st)
            .unwrap();
        let r = s
            .handle(
                &SdoRequest::download_segment(true, &[0; 7], false),
                pre,
                &mut st,
            )
            .unwrap();
        assert_eq!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::Abort {
                addr: a,
                code: SdoAbortCode::TOGGLE_BIT
            }
        );
        // Block transfer is not served.
        let r = s
            .handle(&[0xC0, 0, 0x20, 0, 0, 0, 0, 0], pre, &mut st)
            .unwrap();
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::Abort {
                code: SdoAbortCode::INVALID_COMMAND,
                ..
            }
        ));
        // Short frames get no answer.
        assert_eq!(s.handle(&[0x40, 0, 0x10], pre, &mut st), None);
    }
}
