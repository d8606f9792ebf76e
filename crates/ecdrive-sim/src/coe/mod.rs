//! The CoE mailbox server of the software slave (ETG.1000.6 §5.6).
//!
//! The ESC (SyncManager handshake, mailbox full flags, repeat) hands [`CoeServer::handle`]
//! each complete request the master wrote into SM0 and copies the reply into SM1. The server
//! speaks:
//!
//! - SDO download and upload: expedited, normal and segmented, with the toggle bit checked, and
//!   complete access where [`CoeConfig::complete_access`] allows it;
//! - SDO information: OD list (all five list types and the quantities), object and entry
//!   descriptions, split into fragments when larger than the mailbox;
//! - aborts with the codes the [`ObjectStore`] gives, mailbox error replies (type 0) for
//!   unsupported protocols and services and for malformed mailboxes;
//! - emergencies, queued and delivered by [`CoeServer::poll_unsolicited`] only, never as the
//!   answer to a request (ethercrab panics when an SDO request is answered by an emergency),
//!   unless a test injects exactly that ([`CoeServer::emergency_during_next_sdo`]);
//! - injected faults: an SDO abort instead of the answer ([`CoeServer::abort_next_sdo`]);
//! - the duplicate counter: a request whose counter equals the previous one is a repeat and is
//!   not executed again.
//!
//! The object dictionary is behind the dyn-compatible [`ObjectStore`] trait; [`OdStore`] is the
//! generic implementation built from static descriptor tables, with [`OdHooks`] for
//! device-specific behaviour (ready-made ones in [`hooks`]).

pub mod fixture;
pub mod hooks;
mod od_store;
mod store;

pub use crate::ec::mailbox::Emergency;
pub use od_store::{NoHooks, OdError, OdHooks, OdStore, ValueStore};
pub use store::{ListType, ObjectInfo, ObjectStore};

use crate::ec::AlState;
use crate::ec::mailbox::{
    self, Coe, CoeService, EntryDescription, Mailbox, MailboxErrorDetail, MailboxErrorReply,
    MailboxType, ObjectDescription, SDO_MIN_LEN, Sdo, SdoInfoFragment, SdoInfoOpcode,
    SdoInfoRequest, SdoRequest, SdoResponse, list_type, value_info,
};
use crate::od::{ConstValue, EntryDesc, SdoAbortCode, SegmentError, Segmented};
use crate::quirks::{self, Quirk, Quirks};
use std::collections::VecDeque;

// ---------------------------------------------------------------------------------------------
// Our choices where neither the standards nor the manuals give a value (\[REC\]), in one place.

/// \[REC\] Data type index reported in SDO information for RECORD objects, which have no
/// structure type in our descriptor tables. ETG.1000.6 wants the index of the record's structure
/// definition; 0 says "none defined" (SOEM and ethercrab only print it).
pub const RECORD_DATA_TYPE: u16 = 0x0000;

/// \[REC\] Largest string a string entry declared without a size (`bit_len` 0) accepts, unless
/// its default is longer.
pub const MAX_UNSIZED_STRING: usize = 255;

/// \[REC\] Default [`CoeConfig::max_object_size`]: larger than any object of the emulated
/// drives (the MR-J4-TM manual states 1486 bytes of SDO data at most).
pub const DEFAULT_MAX_OBJECT_SIZE: usize = 4096;

/// \[REC\] Default [`CoeConfig::emergency_queue_len`].
pub const DEFAULT_EMERGENCY_QUEUE_LEN: usize = 16;

// ---------------------------------------------------------------------------------------------

/// What the emulated device supports, and the server's bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoeConfig {
    /// SDO complete access (SII General "CoE details" bit 5). Without it a complete-access
    /// request is aborted with 0x06010000 ("unsupported access to an object"), as slave stacks
    /// without complete access answer; 0x06010004 is for a device that has complete access,
    /// asked for an object of variable length.
    pub complete_access: bool,
    /// The abort code of a complete-access request to a device without complete access
    /// (0x06010000 by default; a device's manual may name another).
    pub complete_access_refusal: SdoAbortCode,
    /// SDO information service. Without it SDO information requests get the mailbox error
    /// "service not supported".
    pub sdo_info: bool,
    /// Emergencies waiting for delivery at most; further ones are dropped and counted.
    pub emergency_queue_len: usize,
    /// Largest object value or complete-access image transferred, in bytes. A longer segmented
    /// download is refused at its start (0x06070012).
    pub max_object_size: usize,
    /// Foreign-device behaviour (see [`crate::quirks`]); the server applies
    /// [`Quirk::NoSdoInfo`], [`Quirk::NoCompleteAccess`], [`Quirk::SdoInfoBadEntry`],
    /// [`Quirk::SdoInfoShortEntry`] and [`Quirk::OddAbort`].
    pub quirks: Quirks,
}

impl Default for CoeConfig {
    /// Complete access and SDO information on, [`DEFAULT_EMERGENCY_QUEUE_LEN`] queued
    /// emergencies, objects up to [`DEFAULT_MAX_OBJECT_SIZE`] bytes.
    fn default() -> Self {
        Self {
            complete_access: true,
            complete_access_refusal: SdoAbortCode::UNSUPPORTED_ACCESS,
            sdo_info: true,
            emergency_queue_len: DEFAULT_EMERGENCY_QUEUE_LEN,
            max_object_size: DEFAULT_MAX_OBJECT_SIZE,
            quirks: Quirks::NONE,
        }
    }
}

/// A segmented transfer in progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Transfer {
    Idle,
    /// Upload: the value is in `data[..len]`; `seg` says where the next segment starts.
    Upload {
        index: u16,
        sub: u8,
        len: usize,
        seg: Segmented,
    },
    /// Download: the size announced in `seg`, received so far in `data`.
    Download {
        index: u16,
        sub: u8,
        complete_access: bool,
        seg: Segmented,
    },
}

/// SDO information fragments still to be sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PendingInfo {
    opcode: SdoInfoOpcode,
    offset: usize,
}

/// Counters for diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CoeStats {
    /// Requests ignored as repeats (same counter as the previous request).
    pub repeats_ignored: u64,
    /// Emergencies dropped because the queue was full.
    pub emergencies_dropped: u64,
    /// SDO aborts sent.
    pub aborts_sent: u64,
    /// Mailbox error replies sent.
    pub mailbox_errors_sent: u64,
    /// Replies or unsolicited messages that did not fit the reply buffer and were not sent.
    pub replies_too_large: u64,
    /// SDO downloads the object store accepted (every write that changed the dictionary).
    pub downloads_accepted: u64,
}

/// The CoE server of one emulated slave. See the [module documentation](self).
///
/// It allocates its buffers once (at construction or on first use) and reuses them.
#[derive(Debug, Clone)]
pub struct CoeServer {
    config: CoeConfig,
    /// Counter of the previous request, `None` after a reset.
    last_counter: Option<u8>,
    /// Counter of the last message sent (0 = none yet); replies count 1..=7.
    reply_counter: u8,
    transfer: Transfer,
    /// Value of the upload in progress, or bytes of the download in progress.
    data: Vec<u8>,
    /// Service data of the SDO information response in progress.
    info: Vec<u8>,
    pending_info: Option<PendingInfo>,
    emergencies: VecDeque<Emergency>,
    stats: CoeStats,
    /// Injected: abort the next initiate to (index, subindex or any) with this code.
    abort_next: Option<(u16, Option<u8>, u32)>,
    /// Injected: answer the next segment request with this emergency.
    emcy_during_sdo: Option<Emergency>,
    /// The reply held back behind an injected emergency (`held[..held_len]`).
    held: Vec<u8>,
    held_len: usize,
}

impl CoeServer {
    /// A server for a device with `config`.
    pub fn new(config: CoeConfig) -> Self {
        Self {
            config,
            last_counter: None,
            reply_counter: 0,
            transfer: Transfer::Idle,
            data: Vec::with_capacity(config.max_object_size),
            info: Vec::new(),
            pending_info: None,
            emergencies: VecDeque::with_capacity(config.emergency_queue_len),
            stats: CoeStats::default(),
            abort_next: None,
            emcy_during_sdo: None,
            held: Vec::new(),
            held_len: 0,
        }
    }

    /// Fault injection: answer the next SDO upload or download initiate to `index:sub` (`sub`
    /// `None`: any subindex) with an abort carrying `code` instead of serving it. One shot;
    /// replaces a previous one. Allocation-free.
    pub fn abort_next_sdo(&mut self, index: u16, sub: Option<u8>, code: u32) {
        self.abort_next = Some((index, sub, code));
    }

    /// Fault injection: answer the first segment request of the next segmented SDO transfer
    /// with `emcy`, and send the segment response as the next mailbox message (as soon as SM1
    /// is free again). One shot; replaces a previous one. Arming allocates nothing; when it
    /// fires the first time, the buffer for the held-back response is sized to the mailbox.
    pub fn emergency_during_next_sdo(&mut self, emcy: Emergency) {
        self.emcy_during_sdo = Some(emcy);
    }

    /// The configuration.
    pub fn config(&self) -> &CoeConfig {
        &self.config
    }

    /// Diagnostic counters.
    pub fn stats(&self) -> CoeStats {
        self.stats
    }

    /// Whether a segmented SDO transfer is in progress.
    pub fn transfer_in_progress(&self) -> bool {
        self.transfer != Transfer::Idle
    }

    /// Whether [`CoeServer::poll_unsolicited`] has something to send (SDO information
    /// fragments or emergencies).
    pub fn has_unsolicited(&self) -> bool {
        self.held_len > 0 || self.pending_info.is_some() || !self.emergencies.is_empty()
    }

    /// Mailbox (re)configured or INIT: forget the duplicate counter and the reply counter,
    /// abort segmented transfers and pending SDO information fragments, and drop queued
    /// emergencies (a device loses its mailbox content with the mailbox).
    pub fn reset(&mut self) {
        self.last_counter = None;
        self.reply_counter = 0;
        self.transfer = Transfer::Idle;
        self.data.clear();
        self.info.clear();
        self.pending_info = None;
        self.emergencies.clear();
        self.held_len = 0;
    }

    /// Queue an emergency; delivered by [`CoeServer::poll_unsolicited`] when SM1 is free. When
    /// the queue is full the new emergency is dropped (the first ones are kept: they name the
    /// original fault) and counted in [`CoeStats::emergencies_dropped`].
    pub fn push_emergency(&mut self, emcy: Emergency) {
        if self.emergencies.len() >= self.config.emergency_queue_len {
            self.stats.emergencies_dropped += 1;
            tracing::debug!(
                error_code = emcy.error_code,
                "emergency queue full, emergency dropped"
            );
            return;
        }
        self.emergencies.push_back(emcy);
    }

    /// Something to send without a request, for the ESC to call when SM1 is empty: the next
    /// fragment of an SDO information response first, then one queued emergency. Writes the
    /// mailbox into `reply` (sized as SM1) and returns its length.
    ///
    /// The ESC must not call this between receiving a request and posting its reply: a master
    /// waiting for an SDO response must get that response first.
    pub fn poll_unsolicited(&mut self, reply: &mut [u8]) -> Option<usize> {
        if self.held_len > 0 {
            // The reply held back behind an injected emergency comes first.
            let n = self.held_len;
            let src = self.held.get(..n)?;
            let dst = reply.get_mut(..n)?;
            dst.copy_from_slice(src);
            self.held_len = 0;
            return Some(n);
        }
        if let Some(p) = self.pending_info {
            return self.next_info_fragment(p, reply);
        }
        let emcy = *self.emergencies.front()?;
        let n = self.emit(reply, |c, b| emcy.emit_mailbox(c, b))?;
        self.emergencies.pop_front();
        Some(n)
    }

    /// The master wrote a complete mailbox into SM0; `request` is the whole SM0 buffer (header +
    /// data + padding). If a reply is due, write the whole reply mailbox (6-byte header + data)
    /// into `reply` (sized as SM1) and return its length.
    ///
    /// No reply is due for a repeated request (same counter as the previous one), for an SDO
    /// abort from the master, or when `reply` is too small for the reply (counted in
    /// [`CoeStats::replies_too_large`]).
    pub fn handle(
        &mut self,
        request: &[u8],
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        self.handle_with_foe(request, state, od, None, reply)
    }

    /// [`CoeServer::handle`] for a device that also serves FoE: type-4 mailboxes go to `foe`
    /// (one counter sequence, one repeat check for both protocols, as the mailbox is one).
    /// Without `foe` they get the mailbox error "protocol not supported".
    pub fn handle_with_foe(
        &mut self,
        request: &[u8],
        state: AlState,
        od: &mut dyn ObjectStore,
        foe: Option<&mut crate::foe::FoeServer>,
        reply: &mut [u8],
    ) -> Option<usize> {
        let mbx = match Mailbox::new_checked(request) {
            Ok(m) => m,
            Err(mailbox::Error::BadLength { .. }) => {
                return self.mailbox_error(MailboxErrorDetail::InvalidSize, reply);
            }
            Err(_) => return self.mailbox_error(MailboxErrorDetail::SizeTooShort, reply),
        };
        let counter = mbx.counter();
        if counter != 0 && self.last_counter == Some(counter) {
            self.stats.repeats_ignored += 1;
            tracing::trace!(counter, "repeated mailbox request ignored");
            return None;
        }
        self.last_counter = Some(counter);
        // A new request from the master ends an SDO information response still being sent.
        self.pending_info = None;
        let payload = mbx.payload();
        match (mbx.mailbox_type(), foe) {
            (Some(MailboxType::Coe), _) => {}
            (Some(MailboxType::Foe), Some(foe)) => {
                let size = reply.len();
                let r = foe.handle(payload, state, size)?;
                return self.emit(reply, |c, b| r.message().emit_mailbox(c, b));
            }
            _ => return self.mailbox_error(MailboxErrorDetail::UnsupportedProtocol, reply),
        }
        let Ok(coe) = Coe::new_checked(payload) else {
            return self.mailbox_error(MailboxErrorDetail::SizeTooShort, reply);
        };
        match coe.service() {
            Some(CoeService::SdoRequest) => self.handle_sdo(coe.payload(), state, od, reply),
            Some(CoeService::SdoInfo)
                if self.config.sdo_info && !self.config.quirks.has(Quirk::NoSdoInfo) =>
            {
                self.handle_info(coe.payload(), od, reply)
            }
            _ => self.mailbox_error(MailboxErrorDetail::ServiceNotSupported, reply),
        }
    }

    fn complete_access(&self) -> bool {
        self.config.complete_access && !self.config.quirks.has(Quirk::NoCompleteAccess)
    }

    // -----------------------------------------------------------------------------------------
    // Output.

    /// Emit a message with the next reply counter; the counter advances only if it was sent.
    fn emit(
        &mut self,
        reply: &mut [u8],
        f: impl FnOnce(u8, &mut [u8]) -> Result<usize, mailbox::Error>,
    ) -> Option<usize> {
        let next = self.reply_counter % 7 + 1;
        match f(next, reply) {
            Ok(n) => {
                self.reply_counter = next;
                Some(n)
            }
            Err(e) => {
                self.stats.replies_too_large += 1;
                tracing::debug!(error = %e, "mailbox reply not sent");
                None
            }
        }
    }

    fn mailbox_error(&mut self, detail: MailboxErrorDetail, reply: &mut [u8]) -> Option<usize> {
        tracing::debug!(detail = detail.text(), "mailbox error reply");
        let n = self.emit(reply, |c, b| {
            MailboxErrorReply::new(detail).emit_mailbox(c, b)
        })?;
        self.stats.mailbox_errors_sent += 1;
        Some(n)
    }

    fn respond(&mut self, r: SdoResponse<'_>, reply: &mut [u8]) -> Option<usize> {
        self.emit(reply, |c, b| r.emit_mailbox(c, b))
    }

    fn abort(
        &mut self,
        index: u16,
        sub: u8,
        code: SdoAbortCode,
        reply: &mut [u8],
    ) -> Option<usize> {
        self.transfer = Transfer::Idle;
        tracing::debug!(index, sub, code = %code, "SDO abort");
        let n = self.respond(
            SdoResponse::Abort {
                index,
                sub,
                code: code.0,
            },
            reply,
        )?;
        if self.config.quirks.has(Quirk::OddAbort) {
            // CoE header bytes 6–7 (service in bits 12–15), SDO command byte 8.
            if let Some(h) = reply.get_mut(7) {
                *h = (*h & 0x0F) | ((CoeService::SdoRequest as u8) << 4);
            }
            if let Some(c) = reply.get_mut(8) {
                *c = quirks::ODD_ABORT_COMMAND;
            }
        }
        self.stats.aborts_sent += 1;
        Some(n)
    }

    // -----------------------------------------------------------------------------------------
    // SDO.

    fn handle_sdo(
        &mut self,
        sdo: &[u8],
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        if sdo.len() < SDO_MIN_LEN {
            return self.mailbox_error(MailboxErrorDetail::SizeTooShort, reply);
        }
        let req = match SdoRequest::parse(sdo) {
            Ok(r) => r,
            Err(_) => {
                let (index, sub) = Sdo::new_checked(sdo).map_or((0, 0), |v| (v.index(), v.sub()));
                return self.abort(index, sub, SdoAbortCode::INVALID_COMMAND, reply);
            }
        };
        if let Some((ai, asub, code)) = self.abort_next {
            let target = match req {
                SdoRequest::Upload { index, sub, .. }
                | SdoRequest::DownloadExpedited { index, sub, .. }
                | SdoRequest::DownloadNormal { index, sub, .. } => Some((index, sub)),
                _ => None,
            };
            if let Some((index, sub)) = target
                && index == ai
                && asub.is_none_or(|s| s == sub)
            {
                self.abort_next = None;
                tracing::debug!(index, sub, code, "injected SDO abort");
                return self.abort(index, sub, SdoAbortCode(code), reply);
            }
        }
        let segment = matches!(
            req,
            SdoRequest::UploadSegment { .. } | SdoRequest::DownloadSegment { .. }
        );
        if segment && self.transfer != Transfer::Idle {
            if let Some(emcy) = self.emcy_during_sdo.take() {
                return self.emergency_then(emcy, req, state, od, reply);
            }
        }
        self.serve_sdo(req, state, od, reply)
    }

    /// Answer with `emcy` now and hold the response to `req` back until SM1 is free again.
    fn emergency_then(
        &mut self,
        emcy: Emergency,
        req: SdoRequest<'_>,
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        let Some(n) = self.emit(reply, |c, b| emcy.emit_mailbox(c, b)) else {
            return self.serve_sdo(req, state, od, reply);
        };
        tracing::debug!(
            error_code = emcy.error_code,
            "injected emergency in the middle of an SDO transfer"
        );
        if self.held.len() < reply.len() {
            // Sized to the mailbox once, when the fault first fires.
            self.held.resize(reply.len(), 0);
        }
        let mut held = std::mem::take(&mut self.held);
        let r = match held.get_mut(..reply.len()) {
            Some(h) => {
                h.fill(0);
                self.serve_sdo(req, state, od, h)
            }
            None => None,
        };
        self.held = held;
        self.held_len = r.unwrap_or(0);
        Some(n)
    }

    fn serve_sdo(
        &mut self,
        req: SdoRequest<'_>,
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        match req {
            SdoRequest::Upload {
                index,
                sub,
                complete_access,
            } => self.upload(index, sub, complete_access, state, od, reply),
            SdoRequest::UploadSegment { toggle } => self.upload_segment(toggle, reply),
            SdoRequest::DownloadExpedited {
                index,
                sub,
                complete_access,
                data,
            } => {
                self.transfer = Transfer::Idle;
                self.download(index, sub, complete_access, data, state, od, reply)
            }
            SdoRequest::DownloadNormal {
                index,
                sub,
                complete_access,
                complete_size,
                data,
            } => self.download_normal(
                index,
                sub,
                complete_access,
                complete_size,
                data,
                state,
                od,
                reply,
            ),
            SdoRequest::DownloadSegment { toggle, last, data } => {
                self.download_segment(toggle, last, data, state, od, reply)
            }
            SdoRequest::Abort { index, sub, code } => {
                tracing::debug!(index, sub, code, "SDO transfer aborted by the master");
                self.transfer = Transfer::Idle;
                None
            }
        }
    }

    fn upload(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        // A new initiate ends any transfer in progress, as on a device with one SDO channel.
        self.transfer = Transfer::Idle;
        if complete_access && !self.complete_access() {
            return self.abort(index, sub, self.config.complete_access_refusal, reply);
        }
        self.data.clear();
        self.data.resize(self.config.max_object_size, 0);
        let read = if complete_access {
            od.read_complete(index, sub, state, &mut self.data)
        } else {
            od.read(index, sub, state, &mut self.data)
        };
        let len = match read {
            Ok(n) => n.min(self.data.len()),
            Err(code) => return self.abort(index, sub, code, reply),
        };
        self.data.truncate(len);
        let value = std::mem::take(&mut self.data);
        let out = if (1..=4).contains(&len) {
            // Objects of up to 4 bytes always go expedited: ethercrab reads PDO configuration
            // expedited only and fails on a normal response.
            self.respond(
                SdoResponse::UploadExpedited {
                    index,
                    sub,
                    complete_access,
                    data: &value,
                },
                reply,
            )
        } else if len <= mailbox::normal_data_capacity(reply.len()) {
            self.respond(
                SdoResponse::UploadNormal {
                    index,
                    sub,
                    complete_access,
                    complete_size: len as u32,
                    data: &value,
                },
                reply,
            )
        } else {
            // Segmented: the initiate response carries only the size (ethercrab ignores data
            // here, SOEM accepts an empty first part); all data follows in segments.
            let r = self.respond(
                SdoResponse::UploadNormal {
                    index,
                    sub,
                    complete_access,
                    complete_size: len as u32,
                    data: &[],
                },
                reply,
            );
            if r.is_some() {
                self.transfer = Transfer::Upload {
                    index,
                    sub,
                    len,
                    seg: Segmented::start(0, Some(len)),
                };
            }
            r
        };
        self.data = value;
        out
    }

    fn upload_segment(&mut self, toggle: bool, reply: &mut [u8]) -> Option<usize> {
        let Transfer::Upload {
            index,
            sub,
            len,
            mut seg,
        } = self.transfer
        else {
            return self.abort(0, 0, SdoAbortCode::INVALID_COMMAND, reply);
        };
        if seg.expect(toggle).is_err() {
            return self.abort(index, sub, SdoAbortCode::TOGGLE_BIT, reply);
        }
        let out = seg.next_out(len, mailbox::segment_data_capacity(reply.len()));
        let data = std::mem::take(&mut self.data);
        let r = self.respond(
            SdoResponse::UploadSegment {
                toggle: out.toggle,
                last: out.last,
                data: data.get(out.range).unwrap_or(&[]),
            },
            reply,
        );
        self.data = data;
        if r.is_some() {
            self.transfer = if out.last {
                Transfer::Idle
            } else {
                Transfer::Upload {
                    index,
                    sub,
                    len,
                    seg,
                }
            };
        }
        r
    }

    /// Write a complete value and answer with the initiate-download response or an abort.
    #[allow(clippy::too_many_arguments)]
    fn download(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        if complete_access && !self.complete_access() {
            return self.abort(index, sub, self.config.complete_access_refusal, reply);
        }
        let written = if complete_access {
            od.write_complete(index, sub, state, data)
        } else {
            od.write(index, sub, state, data)
        };
        match written {
            Ok(()) => {
                self.stats.downloads_accepted += 1;
                self.respond(SdoResponse::Download { index, sub }, reply)
            }
            Err(code) => self.abort(index, sub, code, reply),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn download_normal(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        complete_size: u32,
        data: &[u8],
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        self.transfer = Transfer::Idle;
        let size = complete_size as usize;
        if data.len() >= size {
            return self.download(
                index,
                sub,
                complete_access,
                data.get(..size).unwrap_or(data),
                state,
                od,
                reply,
            );
        }
        // Segmented: refuse early what cannot succeed.
        if complete_access && !self.complete_access() {
            return self.abort(index, sub, self.config.complete_access_refusal, reply);
        }
        let exists = if complete_access {
            od.object(index).map(|_| ()).ok_or(SdoAbortCode::NO_OBJECT)
        } else {
            od.entry(index, sub).map(|_| ())
        };
        if let Err(code) = exists {
            return self.abort(index, sub, code, reply);
        }
        if size > self.config.max_object_size {
            return self.abort(index, sub, SdoAbortCode::LENGTH_TOO_HIGH, reply);
        }
        self.data.clear();
        self.data.extend_from_slice(data);
        let r = self.respond(SdoResponse::Download { index, sub }, reply);
        if r.is_some() {
            self.transfer = Transfer::Download {
                index,
                sub,
                complete_access,
                seg: Segmented::start(data.len(), Some(size)),
            };
        }
        r
    }

    fn download_segment(
        &mut self,
        toggle: bool,
        last: bool,
        data: &[u8],
        state: AlState,
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        let Transfer::Download {
            index,
            sub,
            complete_access,
            mut seg,
        } = self.transfer
        else {
            return self.abort(0, 0, SdoAbortCode::INVALID_COMMAND, reply);
        };
        let done = match seg.next_in(toggle, data.len(), last, self.config.max_object_size) {
            Ok(done) => done,
            Err(SegmentError::Toggle) => {
                return self.abort(index, sub, SdoAbortCode::TOGGLE_BIT, reply);
            }
            // More or less than the initiate announced.
            Err(_) => return self.abort(index, sub, SdoAbortCode::LENGTH_MISMATCH, reply),
        };
        self.data.extend_from_slice(data);
        if !done {
            let r = self.respond(SdoResponse::DownloadSegment { toggle }, reply);
            if r.is_some() {
                self.transfer = Transfer::Download {
                    index,
                    sub,
                    complete_access,
                    seg,
                };
            }
            return r;
        }
        self.transfer = Transfer::Idle;
        let value = std::mem::take(&mut self.data);
        let written = if complete_access {
            od.write_complete(index, sub, state, &value)
        } else {
            od.write(index, sub, state, &value)
        };
        self.data = value;
        match written {
            Ok(()) => {
                self.stats.downloads_accepted += 1;
                self.respond(SdoResponse::DownloadSegment { toggle }, reply)
            }
            Err(code) => self.abort(index, sub, code, reply),
        }
    }

    // -----------------------------------------------------------------------------------------
    // SDO information.

    fn handle_info(
        &mut self,
        payload: &[u8],
        od: &mut dyn ObjectStore,
        reply: &mut [u8],
    ) -> Option<usize> {
        let req = match SdoInfoRequest::parse(payload) {
            Ok(r) => r,
            Err(mailbox::Error::Truncated { .. }) => {
                return self.mailbox_error(MailboxErrorDetail::SizeTooShort, reply);
            }
            Err(_) => return self.info_error(SdoAbortCode::INVALID_COMMAND, reply),
        };
        let mut info = std::mem::take(&mut self.info);
        info.clear();
        let built = match req {
            SdoInfoRequest::OdList { list_type } => {
                od_list(od, list_type, &mut info).map(|()| SdoInfoOpcode::OdListResponse)
            }
            SdoInfoRequest::ObjectDescription { index } => object_description(od, index, &mut info)
                .map(|()| SdoInfoOpcode::ObjectDescriptionResponse),
            SdoInfoRequest::EntryDescription { index, sub, .. }
                if self.config.quirks.has(Quirk::SdoInfoBadEntry)
                    && (index, sub) == quirks::BAD_INFO_ENTRY =>
            {
                Err(SdoAbortCode(0))
            }
            SdoInfoRequest::EntryDescription {
                index,
                sub,
                value_info,
            } => entry_description(od, index, sub, value_info, &mut info).map(|()| {
                if self.config.quirks.has(Quirk::SdoInfoShortEntry)
                    && (index, sub) == quirks::SHORT_INFO_ENTRY
                {
                    // Index, sub-index and value info only.
                    info.truncate(4);
                }
                SdoInfoOpcode::EntryDescriptionResponse
            }),
        };
        self.info = info;
        match built {
            Ok(opcode) => self.next_info_fragment(PendingInfo { opcode, offset: 0 }, reply),
            Err(code) => self.info_error(code, reply),
        }
    }

    fn info_error(&mut self, code: SdoAbortCode, reply: &mut [u8]) -> Option<usize> {
        tracing::debug!(code = %code, "SDO information error");
        let bytes = code.0.to_le_bytes();
        self.emit(reply, |c, b| {
            SdoInfoFragment {
                opcode: SdoInfoOpcode::Error,
                incomplete: false,
                fragments_left: 0,
                data: &bytes,
            }
            .emit_mailbox(c, b)
        })
    }

    /// Send the fragment of `self.info` starting at `p.offset`.
    fn next_info_fragment(&mut self, p: PendingInfo, reply: &mut [u8]) -> Option<usize> {
        let cap = mailbox::info_data_capacity(reply.len());
        if cap == 0 {
            self.pending_info = None;
            self.stats.replies_too_large += 1;
            return None;
        }
        let total = self.info.len();
        let end = total.min(p.offset.saturating_add(cap));
        let rest = total - end;
        let fragments_left = u16::try_from(rest.div_ceil(cap)).unwrap_or(u16::MAX);
        let info = std::mem::take(&mut self.info);
        let chunk = info.get(p.offset..end).unwrap_or(&[]);
        let r = self.emit(reply, |c, b| {
            SdoInfoFragment {
                opcode: p.opcode,
                incomplete: rest > 0,
                fragments_left,
                data: chunk,
            }
            .emit_mailbox(c, b)
        });
        self.info = info;
        self.pending_info = match r {
            Some(_) if rest > 0 => Some(PendingInfo {
                opcode: p.opcode,
                offset: end,
            }),
            _ => None,
        };
        r
    }
}

fn push_u16(out: &mut Vec<u8>, v: u16) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// Indices of `list` in ascending order.
fn for_each_in_list(od: &dyn ObjectStore, list: ListType, mut f: impl FnMut(u16)) {
    let mut at = od.next_index(None);
    while let Some(i) = at {
        if od.in_list(i, list) {
            f(i);
        }
        at = od.next_index(Some(i));
    }
}

fn od_list(od: &dyn ObjectStore, lt: u16, out: &mut Vec<u8>) -> Result<(), SdoAbortCode> {
    push_u16(out, lt);
    if lt == list_type::QUANTITIES {
        for list in ListType::ALL_TYPES {
            let mut n = 0u32;
            for_each_in_list(od, list, |_| n += 1);
            push_u16(out, u16::try_from(n).unwrap_or(u16::MAX));
        }
        return Ok(());
    }
    // **Choice**: an unknown list type is "unsupported access" (as SOES answers it).
    let list = ListType::from_code(lt).ok_or(SdoAbortCode::UNSUPPORTED_ACCESS)?;
    for_each_in_list(od, list, |i| push_u16(out, i));
    Ok(())
}

fn object_description(
    od: &dyn ObjectStore,
    index: u16,
    out: &mut Vec<u8>,
) -> Result<(), SdoAbortCode> {
    let o = od.object(index).ok_or(SdoAbortCode::NO_OBJECT)?;
    let d = ObjectDescription {
        index,
        data_type: o.data_type,
        max_sub: o.max_sub,
        object_code: o.object_code,
        name: o.name.as_bytes(),
    };
    out.resize(d.len(), 0);
    d.emit(out).map_err(|_| SdoAbortCode::GENERAL)?;
    Ok(())
}

/// Encode a descriptor value (default, minimum, maximum) in the entry's size; `None` when there
/// is none or it does not fit the type.
fn encode_const(e: &EntryDesc, v: ConstValue, len: usize, out: &mut Vec<u8>) -> bool {
    let Some(value) = v.to_value() else {
        return false;
    };
    let start = out.len();
    out.resize(start + len, 0);
    let ok = out
        .get_mut(start..)
        .is_some_and(|dst| value.encode_into(e.data_type, dst).is_ok());
    if !ok {
        out.truncate(start);
    }
    ok
}

fn entry_description(
    od: &dyn ObjectStore,
    index: u16,
    sub: u8,
    requested: u8,
    out: &mut Vec<u8>,
) -> Result<(), SdoAbortCode> {
    let e = od.entry(index, sub)?;
    // Fixed part first, the value-info byte is patched once we know what we include.
    let fixed = EntryDescription {
        index,
        sub,
        value_info: 0,
        data_type: e.data_type.code(),
        bit_len: e.bit_len,
        access: e.access.bits(),
        data: &[],
    };
    out.resize(EntryDescription::FIXED_LEN, 0);
    fixed.emit(out).map_err(|_| SdoAbortCode::GENERAL)?;
    // Our descriptors have no unit; default, minimum and maximum where the table gives them.
    let len = (e.bit_len as usize).div_ceil(8);
    let mut given = 0u8;
    for (flag, v) in [
        (value_info::DEFAULT, e.default),
        (value_info::MINIMUM, e.min),
        (value_info::MAXIMUM, e.max),
    ] {
        if requested & flag != 0 && encode_const(&e, v, len, out) {
            given |= flag;
        }
    }
    if let Some(b) = out.get_mut(3) {
        *b = given;
    }
    out.extend_from_slice(e.name.as_bytes());
    Ok(())
}

#[cfg(test)]
mod tests;
