//! ecdrive's own CoE (CANopen over EtherCAT) client.
//!
//! ethercrab 0.7.1 downloads at most 4 bytes, has SDO information only for object lists, and
//! throws away (or, if one arrives as the reply, panics on) emergency messages. ecdrive speaks the
//! mailbox protocol itself over ethercrab's raw `Command` API: SM0/SM1 handshake with the repeat
//! request, SDO upload and download (expedited, normal, segmented, complete access), SDO
//! information (OD list, object and entry descriptions, fragmented), and every emergency that
//! arrives — before, between or instead of a reply — is decoded into an [`EmergencyRecord`] and
//! kept. Not used in the cycle: it runs on the supervisory side.

use super::error::DriveRef;
use crate::ec::mailbox::{
    self, Emergency, EntryDescription, MailboxMessage, ObjectDescription, OdList, SdoInfoFragment,
    SdoInfoOpcode, SdoInfoRequest, SdoRequest, SdoResponse,
};
use crate::ec::register;
use crate::od::{ObjectAddress, SdoAbortCode, SegmentError, Segmented};
use crate::rt::monotonic_ns;
use ethercrab::{Command, MainDevice};
use std::sync::{Arc, Mutex};
use std::time::Duration;

#[path = "foe.rs"]
mod foe;
pub use foe::FoeTransfer;

/// The mailbox SyncManagers of a drive, as configured in the ESC.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MailboxSms {
    /// SM0 (master → drive) start address.
    pub out_start: u16,
    /// SM0 length.
    pub out_len: u16,
    /// SM1 (drive → master) start address.
    pub in_start: u16,
    /// SM1 length.
    pub in_len: u16,
}

/// An emergency message as received, with when and from whom (the CANopen master's record of
/// the same message is `ecdrive_canopen::EmergencyRecord`: the node instead of the position).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct EmergencyRecord {
    /// `CLOCK_MONOTONIC` time of reception, ns.
    pub time_ns: u64,
    /// The drive's position on the segment.
    pub position: u16,
    /// The drive's name.
    pub drive: String,
    /// The message (its error code decoded with the drive profile's alarm table where shown).
    pub emergency: Emergency,
}

/// Where a client keeps the emergencies it receives. Shared by every client of a bus.
pub type EmergencyLog = Arc<Mutex<Vec<EmergencyRecord>>>;

/// What went wrong in a CoE exchange.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoeErrorKind {
    /// The drive aborted the transfer.
    #[error("SDO abort {0}")]
    Abort(SdoAbortCode),
    /// The drive answered with a mailbox error.
    #[error("mailbox error: {0}")]
    MailboxError(String),
    /// SDO information error.
    #[error("SDO information error {0}")]
    InfoError(SdoAbortCode),
    /// No reply in time.
    #[error("no reply within {0} ms")]
    Timeout(u64),
    /// The reply does not fit the request.
    #[error("protocol error: {0}")]
    Protocol(String),
    /// The drive has no mailbox (or it is not configured: the drive is in INIT).
    #[error("no mailbox: {0}")]
    NoMailbox(String),
    /// An EtherCAT access failed.
    #[error("bus error: {0}")]
    Bus(String),
    /// The device ended an FoE transfer with an error.
    #[error("FoE error {code}{}", if .text.is_empty() { String::new() } else { format!(": {}", .text) })]
    Foe {
        /// The code.
        code: crate::ec::mailbox::FoeErrorCode,
        /// The device's text.
        text: String,
    },
    /// The data does not fit a mailbox transfer.
    #[error("{0}")]
    TooLarge(String),
}

/// A CoE error, naming the drive and the object.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{drive}{}: {kind}", .address.map(|a| format!(" {a}")).unwrap_or_default())]
pub struct CoeError {
    /// The drive.
    pub drive: DriveRef,
    /// The object, if the exchange was about one.
    pub address: Option<ObjectAddress>,
    /// What went wrong.
    pub kind: CoeErrorKind,
}

impl CoeError {
    /// The abort code, if the drive aborted.
    pub fn abort_code(&self) -> Option<SdoAbortCode> {
        match self.kind {
            CoeErrorKind::Abort(c) | CoeErrorKind::InfoError(c) => Some(c),
            _ => None,
        }
    }
}

/// The mailbox counters of one device in a bus session, over every client that writes its
/// mailbox.
///
/// A device drops a request whose counter equals the previous request's as a repeat. ecdrive's
/// [`CoeClient`] and ethercrab's own SDO client (which reads 0x1C12/0x1C13 and the PDOs while
/// it builds the process image) both write the mailbox, each with its own counter; when the
/// last counter of one equalled the next of the other, the device ignored the request and the
/// start-up timed out (on the MR-J4-TM whenever the mapping had 10, 17 or 24 entries). The bus
/// keeps this record from every request that went out (see `Pump::set_mailbox_tap`), so that
/// ecdrive continues after the last counter on the wire and never sends the counter ethercrab
/// will send next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MailboxSequence {
    /// The counter of the last request sent to the device by anyone (0: none yet).
    pub last: u8,
    /// The counter ethercrab's client will put on its next request.
    pub ethercrab_next: u8,
}

impl Default for MailboxSequence {
    fn default() -> Self {
        Self {
            last: 0,
            // ethercrab 0.7.1 starts each SubDevice's counter at 1 (`SubDevice::mailbox_counter`
            // returns the value before incrementing) and counts 1..=7.
            ethercrab_next: 1,
        }
    }
}

impl MailboxSequence {
    /// A request with `counter` went out from ethercrab's client.
    pub fn sent_by_ethercrab(&mut self, counter: u8) {
        self.last = counter;
        self.ethercrab_next = counter % 7 + 1;
    }
}

/// The kind of a reply for a message, without its fields (`UploadExpedited`, `SdoInfo`).
fn kind_of(m: &impl core::fmt::Debug) -> String {
    let d = format!("{m:?}");
    d.split(['{', '(', ' '])
        .next()
        .unwrap_or_default()
        .trim()
        .to_string()
}

/// SM status bit 3: mailbox full.
const MBX_FULL: u8 = 0x08;

/// A CoE client for one drive.
pub struct CoeClient<'a> {
    md: &'a MainDevice<'a>,
    address: u16,
    drive: DriveRef,
    sms: MailboxSms,
    counter: u8,
    avoid: u8,
    /// The next request carries counter 0 (the start value, never taken for a repeat).
    zero_next: bool,
    complete_access: bool,
    timeout: Duration,
    log: EmergencyLog,
    buf: Vec<u8>,
    /// The last exchange of this client ended with its reply: the drive took the request out
    /// of SM0 before it answered, and nothing of an earlier exchange is left to come. The next
    /// request goes without a look at the SyncManagers first (what arrives meanwhile, an
    /// emergency, is read and recorded while waiting for the reply).
    settled: bool,
}

impl<'a> CoeClient<'a> {
    /// A client for the drive at configured station `address`. Reads the mailbox SyncManager
    /// configuration from the ESC (the drive must be in PRE-OP or above).
    pub async fn new(
        md: &'a MainDevice<'a>,
        address: u16,
        drive: DriveRef,
        log: EmergencyLog,
    ) -> Result<Self, CoeError> {
        let err = |kind| CoeError {
            drive: drive.clone(),
            address: None,
            kind,
        };
        let regs = Command::fprd(address, register::sm(0))
            .receive_slice(md, 16)
            .await
            .map_err(|e| err(CoeErrorKind::Bus(format!("reading SM0/SM1: {e}"))))?;
        let r = |i: usize| regs.get(i).copied().unwrap_or(0);
        let sms = MailboxSms {
            out_start: u16::from_le_bytes([r(0), r(1)]),
            out_len: u16::from_le_bytes([r(2), r(3)]),
            in_start: u16::from_le_bytes([r(8), r(9)]),
            in_len: u16::from_le_bytes([r(10), r(11)]),
        };
        let (sm0_on, sm1_on) = (r(6) & 1 != 0, r(14) & 1 != 0);
        if !sm0_on || !sm1_on || sms.out_len < 16 || sms.in_len < 16 {
            return Err(err(CoeErrorKind::NoMailbox(format!(
                "SM0 {} ({} bytes), SM1 {} ({} bytes)",
                if sm0_on { "on" } else { "off" },
                sms.out_len,
                if sm1_on { "on" } else { "off" },
                sms.in_len
            ))));
        }
        Ok(Self::with_sms(md, address, drive, log, sms))
    }

    /// A client for the drive at configured station `address` whose mailbox SyncManagers are
    /// known (from an earlier client's [`sms`](Self::sms) in the same session): no frame.
    pub fn with_sms(
        md: &'a MainDevice<'a>,
        address: u16,
        drive: DriveRef,
        log: EmergencyLog,
        sms: MailboxSms,
    ) -> Self {
        let n = sms.out_len.max(sms.in_len) as usize;
        Self {
            md,
            address,
            drive,
            sms,
            counter: 0,
            avoid: 0,
            zero_next: false,
            settled: false,
            complete_access: false,
            timeout: Duration::from_millis(1000),
            log,
            buf: vec![0; n],
        }
    }

    /// Allow complete access (only if the drive's SII/ESI says it supports it).
    pub fn with_complete_access(mut self, yes: bool) -> Self {
        self.complete_access = yes;
        self
    }

    /// Continue the mailbox counter sequence from `last` (the counter of the previous request
    /// to this drive). A drive drops a request whose counter equals the previous one as a
    /// repeat, so the sequence must continue across clients of one session.
    pub fn with_counter(mut self, last: u8) -> Self {
        self.counter = last % 8;
        self
    }

    /// Never use counter `c` (1–7; 0: no restriction): it is the counter another client of
    /// this drive (ethercrab's) will send next, so the request before it must not carry it.
    /// See [`MailboxSequence`].
    pub fn avoiding(mut self, c: u8) -> Self {
        self.avoid = c % 8;
        self
    }

    /// The counter of the last request sent.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// How long to wait for each reply (default 1 s).
    pub fn with_timeout(mut self, timeout: Duration) -> Self {
        self.timeout = timeout;
        self
    }

    /// How long it waits for each reply.
    pub fn timeout(&self) -> Duration {
        self.timeout
    }

    /// Change how long it waits for each reply, from the next request on.
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// The drive.
    pub fn drive(&self) -> &DriveRef {
        &self.drive
    }

    /// The mailbox SyncManagers.
    pub fn sms(&self) -> MailboxSms {
        self.sms
    }

    fn error(&self, address: Option<ObjectAddress>, kind: CoeErrorKind) -> CoeError {
        CoeError {
            drive: self.drive.clone(),
            address,
            kind,
        }
    }

    /// Start the counter sequence at 0, the mailbox counter's start value (ETG.1000.4), which a
    /// device never takes for a repeat: for a client that does not know what the device
    /// received last (a tool that addresses a device without a discovery of its own).
    pub fn with_unknown_history(mut self) -> Self {
        self.zero_next = true;
        self
    }

    fn next_counter(&mut self) -> u8 {
        if self.zero_next {
            self.zero_next = false;
            self.counter = 0;
            return 0;
        }
        // Counters run 1..=7; 0 is reserved.
        self.counter = self.counter % 7 + 1;
        if self.counter == self.avoid {
            self.counter = self.counter % 7 + 1;
        }
        self.counter
    }

    async fn sm_status(&self, sm: u8) -> Result<u8, ethercrab::error::Error> {
        Command::fprd(self.address, register::sm(sm) + register::SM_STATUS_OFFSET)
            .receive::<u8>(self.md)
            .await
    }

    /// Record an emergency.
    fn record(&self, e: Emergency) {
        let rec = EmergencyRecord {
            time_ns: monotonic_ns(),
            position: self.drive.position,
            drive: self.drive.name.clone(),
            emergency: e,
        };
        // 0x0000 is "error reset or no error" (CiA 301 §7.2.7.1): the drive says its fault
        // went away, which is news, not a warning.
        if e.error_code == 0 {
            tracing::info!(
                "{}: emergency 0x0000 (error reset or no error; error register 0x{:02X})",
                self.drive,
                e.error_register
            );
        } else {
            tracing::warn!(
                "{}: emergency 0x{:04X} (error register 0x{:02X})",
                self.drive,
                e.error_code,
                e.error_register
            );
        }
        if let Ok(mut log) = self.log.lock() {
            log.push(rec);
        }
    }

    /// Read SM1 if it is full. Returns the number of bytes read into `self.buf`, 0 if empty.
    async fn read_in(&mut self, addr: Option<ObjectAddress>) -> Result<usize, CoeError> {
        let status = self
            .sm_status(1)
            .await
            .map_err(|e| self.error(addr, CoeErrorKind::Bus(format!("reading SM1 status: {e}"))))?;
        if status & MBX_FULL == 0 {
            return Ok(0);
        }
        let len = self.sms.in_len;
        for attempt in 0..3 {
            match Command::fprd(self.address, self.sms.in_start)
                .receive_slice(self.md, len)
                .await
            {
                Ok(data) => {
                    let n = data.len().min(self.buf.len());
                    self.buf[..n].copy_from_slice(&data[..n]);
                    return Ok(n);
                }
                Err(ethercrab::error::Error::WorkingCounter { .. }) if attempt < 2 => {
                    // The read was lost: ask the drive to repost the last reply (repeat request:
                    // toggle SM1 activate bit 1, wait for the PDI's repeat ack).
                    self.repeat_request(addr).await?;
                }
                Err(e) => {
                    return Err(self.error(addr, CoeErrorKind::Bus(format!("reading SM1: {e}"))));
                }
            }
        }
        Err(self.error(
            addr,
            CoeErrorKind::Bus("reading SM1 failed after repeat requests".into()),
        ))
    }

    async fn repeat_request(&self, addr: Option<ObjectAddress>) -> Result<(), CoeError> {
        let act = register::sm(1) + register::SM_ACTIVATE_OFFSET;
        let bus = |e: ethercrab::error::Error| {
            self.error(addr, CoeErrorKind::Bus(format!("mailbox repeat: {e}")))
        };
        let cur: [u8; 2] = Command::fprd(self.address, act)
            .receive(self.md)
            .await
            .map_err(bus)?;
        let want = (cur[0] ^ 0x02) & 0x02;
        Command::fpwr(self.address, act)
            .send(self.md, [cur[0] ^ 0x02])
            .await
            .map_err(bus)?;
        let deadline = monotonic_ns() + self.timeout.as_nanos() as u64;
        loop {
            let ack: [u8; 2] = Command::fprd(self.address, act)
                .receive(self.md)
                .await
                .map_err(bus)?;
            if ack[1] & 0x02 == want {
                return Ok(());
            }
            if monotonic_ns() > deadline {
                return Err(
                    self.error(addr, CoeErrorKind::Timeout(self.timeout.as_millis() as u64))
                );
            }
        }
    }

    /// Read and record anything already waiting in SM1 (emergencies, stale replies). Returns the
    /// number of emergencies recorded.
    pub async fn drain(&mut self) -> Result<usize, CoeError> {
        let mut n = 0;
        for _ in 0..16 {
            let len = self.read_in(None).await?;
            if len == 0 {
                break;
            }
            if let Ok((_, MailboxMessage::Emergency(e))) = MailboxMessage::parse(&self.buf[..len]) {
                self.record(e);
                n += 1;
            }
        }
        Ok(n)
    }

    /// Before a request: both mailbox SyncManagers' status in one read (0x0805–0x080D). What
    /// waits in SM1 is read out ([`drain`](Self::drain): an emergency is recorded, a stale
    /// reply must not pass for the next one). Returns whether SM0 was seen free (the request
    /// can go without another look at it).
    async fn prepare(&mut self, addr: Option<ObjectAddress>) -> Result<bool, CoeError> {
        let st = Command::fprd(self.address, register::sm(0) + register::SM_STATUS_OFFSET)
            .receive::<[u8; 9]>(self.md)
            .await
            .map_err(|e| {
                self.error(
                    addr,
                    CoeErrorKind::Bus(format!("reading SM0/SM1 status: {e}")),
                )
            })?;
        if st[8] & MBX_FULL != 0 {
            self.drain().await?;
            return Ok(false);
        }
        Ok(st[0] & MBX_FULL == 0)
    }

    /// Write one request (already emitted into `req`) into SM0.
    async fn send(&mut self, req: &[u8], addr: Option<ObjectAddress>) -> Result<(), CoeError> {
        self.send_checked(req, addr, true).await
    }

    /// One look at SM0: whether it is free; an error once `deadline` has passed.
    async fn sm0_free(&self, addr: Option<ObjectAddress>, deadline: u64) -> Result<bool, CoeError> {
        let s = self
            .sm_status(0)
            .await
            .map_err(|e| self.error(addr, CoeErrorKind::Bus(format!("reading SM0 status: {e}"))))?;
        if s & MBX_FULL == 0 {
            return Ok(true);
        }
        if monotonic_ns() > deadline {
            return Err(self.error(
                addr,
                CoeErrorKind::Protocol("SM0 stays full: the drive does not take requests".into()),
            ));
        }
        Ok(false)
    }

    /// Write one request into SM0; with `check`, first wait until SM0 is free (the drive has
    /// taken the previous request).
    async fn send_checked(
        &mut self,
        req: &[u8],
        addr: Option<ObjectAddress>,
        check: bool,
    ) -> Result<(), CoeError> {
        // Settled again only by an exchange that ends with its reply (`sdo`).
        self.settled = false;
        let deadline = monotonic_ns() + self.timeout.as_nanos() as u64;
        // Wait until the drive has taken the previous request.
        while check && !self.sm0_free(addr, deadline).await? {}
        // The whole SM0 buffer is written (request + zero padding): the ESC marks the mailbox
        // full only when its last byte is written.
        let mut out = vec![0u8; self.sms.out_len as usize];
        let n = req.len().min(out.len());
        out[..n].copy_from_slice(&req[..n]);
        Command::fpwr(self.address, self.sms.out_start)
            .send_receive_slice(self.md, out.as_slice())
            .await
            .map_err(|e| self.error(addr, CoeErrorKind::Bus(format!("writing SM0: {e}"))))?;
        Ok(())
    }

    /// Wait for the reply to a request: returns the reply's bytes in `self.buf`. Emergencies that
    /// arrive meanwhile are recorded and waiting continues.
    async fn receive_reply(
        &mut self,
        addr: Option<ObjectAddress>,
        accept: impl Fn(&MailboxMessage<'_>) -> bool,
    ) -> Result<usize, CoeError> {
        let deadline = monotonic_ns() + self.timeout.as_nanos() as u64;
        loop {
            let len = self.read_in(addr).await?;
            if len > 0 {
                match MailboxMessage::parse(&self.buf[..len]) {
                    Ok((_, MailboxMessage::Emergency(e))) => self.record(e),
                    Ok((_, MailboxMessage::Error(e))) => {
                        return Err(self.error(addr, CoeErrorKind::MailboxError(e.to_string())));
                    }
                    Ok((_, m)) if accept(&m) => return Ok(len),
                    Ok((_, m)) => {
                        tracing::debug!("{}: ignoring unrelated mailbox message {m:?}", self.drive);
                    }
                    Err(e) => {
                        return Err(self.error(
                            addr,
                            CoeErrorKind::Protocol(format!("undecodable reply: {e}")),
                        ));
                    }
                }
            }
            if monotonic_ns() > deadline {
                return Err(
                    self.error(addr, CoeErrorKind::Timeout(self.timeout.as_millis() as u64))
                );
            }
        }
    }

    /// One SDO request/response exchange.
    async fn sdo(
        &mut self,
        req: SdoRequest<'_>,
        addr: ObjectAddress,
    ) -> Result<(Vec<u8>, usize), CoeError> {
        let sm0_free = std::mem::take(&mut self.settled) || self.prepare(Some(addr)).await?;
        let counter = self.next_counter();
        let mut out = vec![0u8; self.sms.out_len as usize];
        let n = req
            .emit_mailbox(counter, &mut out)
            .map_err(|e| self.error(Some(addr), CoeErrorKind::TooLarge(e.to_string())))?;
        self.send_checked(&out[..n], Some(addr), !sm0_free).await?;
        let len = self
            .receive_reply(Some(addr), |m| {
                matches!(
                    m,
                    MailboxMessage::SdoResponse(_)
                        | MailboxMessage::SdoRequest(SdoRequest::Abort { .. })
                )
            })
            .await?;
        self.settled = true;
        Ok((self.buf[..len].to_vec(), len))
    }

    fn parse_sdo<'b>(
        &self,
        reply: &'b [u8],
        addr: ObjectAddress,
    ) -> Result<SdoResponse<'b>, CoeError> {
        match MailboxMessage::parse(reply) {
            Ok((_, MailboxMessage::SdoResponse(r))) => match r {
                SdoResponse::Abort { code, .. } => {
                    Err(self.error(Some(addr), CoeErrorKind::Abort(SdoAbortCode(code))))
                }
                r => Ok(r),
            },
            Ok((_, MailboxMessage::SdoRequest(SdoRequest::Abort { code, .. }))) => {
                Err(self.error(Some(addr), CoeErrorKind::Abort(SdoAbortCode(code))))
            }
            Ok((_, m)) => Err(self.error(
                Some(addr),
                CoeErrorKind::Protocol(format!("unexpected reply: {}", kind_of(&m))),
            )),
            Err(e) => Err(self.error(Some(addr), CoeErrorKind::Protocol(e.to_string()))),
        }
    }

    /// Upload (read) an entry. With `complete_access`, reads the whole object starting at `sub`
    /// (0 or 1).
    pub async fn upload(
        &mut self,
        addr: ObjectAddress,
        complete_access: bool,
    ) -> Result<Vec<u8>, CoeError> {
        if complete_access && !self.complete_access {
            return Err(self.error(
                Some(addr),
                CoeErrorKind::Abort(SdoAbortCode::COMPLETE_ACCESS_UNSUPPORTED),
            ));
        }
        let (reply, _) = self
            .sdo(
                SdoRequest::Upload {
                    index: addr.index,
                    sub: addr.sub,
                    complete_access,
                },
                addr,
            )
            .await?;
        let (mut data, size) = match self.parse_sdo(&reply, addr)? {
            SdoResponse::UploadExpedited {
                index, sub, data, ..
            } => {
                self.check_echo(addr, index, sub, complete_access)?;
                return Ok(data.to_vec());
            }
            SdoResponse::UploadNormal {
                index,
                sub,
                complete_size,
                data,
                ..
            } => {
                self.check_echo(addr, index, sub, complete_access)?;
                let size = complete_size as usize;
                let mut v = Vec::with_capacity(size);
                v.extend_from_slice(&data[..data.len().min(size)]);
                if v.len() == size {
                    return Ok(v);
                }
                (v, size)
            }
            other => {
                return Err(self.error(
                    Some(addr),
                    CoeErrorKind::Protocol(format!(
                        "unexpected reply to an upload: {}",
                        kind_of(&other)
                    )),
                ));
            }
        };
        // Segmented upload for the rest (the initiate announced the size).
        let mut seg = Segmented::start(data.len(), Some(size));
        loop {
            let req = SdoRequest::UploadSegment {
                toggle: seg.toggle(),
            };
            let (reply, _) = self.sdo(req, addr).await?;
            match self.parse_sdo(&reply, addr)? {
                SdoResponse::UploadSegment {
                    toggle,
                    last,
                    data: part,
                } => match seg.next_in(toggle, part.len(), last, size) {
                    Ok(done) => {
                        data.extend_from_slice(part);
                        if done {
                            return Ok(data);
                        }
                    }
                    Err(e) => return Err(self.segment_error(addr, "upload", e)),
                },
                other => {
                    return Err(self.error(
                        Some(addr),
                        CoeErrorKind::Protocol(format!(
                            "unexpected reply to an upload segment: {}",
                            kind_of(&other)
                        )),
                    ));
                }
            }
        }
    }

    /// The error for a segment the transfer refused: a toggle bit out of turn is what an
    /// abort would say; a length off the announced size is a protocol error.
    fn segment_error(&self, addr: ObjectAddress, what: &str, e: SegmentError) -> CoeError {
        let kind = match e {
            SegmentError::Toggle => CoeErrorKind::Abort(SdoAbortCode::TOGGLE_BIT),
            e => CoeErrorKind::Protocol(format!("{what}: {e}")),
        };
        self.error(Some(addr), kind)
    }

    fn check_echo(
        &self,
        addr: ObjectAddress,
        index: u16,
        sub: u8,
        ca: bool,
    ) -> Result<(), CoeError> {
        // With complete access a drive may echo sub 0 or 1; only the index must match.
        if index != addr.index || (!ca && sub != addr.sub) {
            return Err(self.error(
                Some(addr),
                CoeErrorKind::Protocol(format!(
                    "reply is for 0x{index:04X}:{sub:02X}, not for the request"
                )),
            ));
        }
        Ok(())
    }

    /// Download (write) an entry; any length (segmented when it does not fit one mailbox).
    pub async fn download(
        &mut self,
        addr: ObjectAddress,
        data: &[u8],
        complete_access: bool,
    ) -> Result<(), CoeError> {
        if data.is_empty() {
            return Err(self.error(
                Some(addr),
                CoeErrorKind::TooLarge("nothing to write".into()),
            ));
        }
        if complete_access && !self.complete_access {
            return Err(self.error(
                Some(addr),
                CoeErrorKind::Abort(SdoAbortCode::COMPLETE_ACCESS_UNSUPPORTED),
            ));
        }
        let mbx = self.sms.out_len as usize;
        let (req, sent) =
            SdoRequest::initiate_download(addr.index, addr.sub, complete_access, data, mbx);
        let (reply, _) = self.sdo(req, addr).await?;
        match self.parse_sdo(&reply, addr)? {
            SdoResponse::Download { index, sub } => {
                self.check_echo(addr, index, sub, complete_access)?
            }
            other => {
                return Err(self.error(
                    Some(addr),
                    CoeErrorKind::Protocol(format!(
                        "unexpected reply to a download: {}",
                        kind_of(&other)
                    )),
                ));
            }
        }
        let mut seg = Segmented::start(sent, Some(data.len()));
        let capacity = mailbox::segment_data_capacity(mbx).max(1);
        while !seg.sent_all(data.len()) {
            let out = seg.next_out(data.len(), capacity);
            let req = SdoRequest::DownloadSegment {
                toggle: out.toggle,
                last: out.last,
                data: data.get(out.range).unwrap_or(&[]),
            };
            let (reply, _) = self.sdo(req, addr).await?;
            match self.parse_sdo(&reply, addr)? {
                SdoResponse::DownloadSegment { toggle } => {
                    if let Err(e) = seg.acknowledged(toggle) {
                        return Err(self.segment_error(addr, "download", e));
                    }
                }
                other => {
                    return Err(self.error(
                        Some(addr),
                        CoeErrorKind::Protocol(format!(
                            "unexpected reply to a download segment: {}",
                            kind_of(&other)
                        )),
                    ));
                }
            }
        }
        Ok(())
    }

    /// One SDO information exchange, reassembling fragments. Returns the service data.
    async fn info(
        &mut self,
        req: SdoInfoRequest,
        addr: Option<ObjectAddress>,
    ) -> Result<Vec<u8>, CoeError> {
        self.drain().await?;
        let counter = self.next_counter();
        let mut out = vec![0u8; self.sms.out_len as usize];
        let n = req
            .emit_mailbox(counter, &mut out)
            .map_err(|e| self.error(addr, CoeErrorKind::TooLarge(e.to_string())))?;
        self.send(&out[..n], addr).await?;
        let mut data = Vec::new();
        loop {
            let len = self
                .receive_reply(addr, |m| matches!(m, MailboxMessage::SdoInfo(_)))
                .await?;
            let (_, msg) = MailboxMessage::parse(&self.buf[..len])
                .map_err(|e| self.error(addr, CoeErrorKind::Protocol(e.to_string())))?;
            let MailboxMessage::SdoInfo(frag) = msg else {
                continue;
            };
            let frag: SdoInfoFragment<'_> = frag;
            if frag.opcode == SdoInfoOpcode::Error {
                let code = frag.error_code().unwrap_or(0);
                return Err(self.error(addr, CoeErrorKind::InfoError(SdoAbortCode(code))));
            }
            data.extend_from_slice(frag.data);
            if !frag.incomplete {
                return Ok(data);
            }
        }
    }

    /// The object indices of an OD list ([`mailbox::list_type`]: 1 = all objects).
    pub async fn od_list(&mut self, list_type: u16) -> Result<Vec<u16>, CoeError> {
        let data = self
            .info(SdoInfoRequest::OdList { list_type }, None)
            .await?;
        let list = OdList::parse(&data)
            .map_err(|e| self.error(None, CoeErrorKind::Protocol(e.to_string())))?;
        Ok(list.values().collect())
    }

    /// The description of one object.
    pub async fn object_description(&mut self, index: u16) -> Result<ObjectInfo, CoeError> {
        let addr = Some(ObjectAddress::new(index, 0));
        let data = self
            .info(SdoInfoRequest::ObjectDescription { index }, addr)
            .await?;
        let d = ObjectDescription::parse(&data)
            .map_err(|e| self.error(addr, CoeErrorKind::Protocol(e.to_string())))?;
        Ok(ObjectInfo {
            index: d.index,
            data_type: d.data_type,
            max_sub: d.max_sub,
            object_code: d.object_code,
            name: String::from_utf8_lossy(d.name)
                .trim_end_matches('\0')
                .to_string()
                .into(),
        })
    }

    /// The description of one entry (with default/minimum/maximum when the drive provides them).
    pub async fn entry_description(&mut self, addr: ObjectAddress) -> Result<EntryInfo, CoeError> {
        let data = self
            .info(
                SdoInfoRequest::EntryDescription {
                    index: addr.index,
                    sub: addr.sub,
                    value_info: mailbox::value_info::DEFAULT
                        | mailbox::value_info::MINIMUM
                        | mailbox::value_info::MAXIMUM,
                },
                Some(addr),
            )
            .await?;
        let d = EntryDescription::parse(&data)
            .map_err(|e| self.error(Some(addr), CoeErrorKind::Protocol(e.to_string())))?;
        Ok(EntryInfo {
            address: addr,
            data_type: d.data_type,
            bit_len: d.bit_len,
            access: crate::od::EntryAccess::from_bits_truncate(d.access),
            name: d
                .values()
                .map(|v| {
                    String::from_utf8_lossy(v.name)
                        .trim_end_matches('\0')
                        .to_string()
                })
                .unwrap_or_default(),
        })
    }
}

pub use crate::od::ObjectInfo;

/// An entry description read through SDO information.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EntryInfo {
    /// Address.
    pub address: ObjectAddress,
    /// Data type code.
    pub data_type: u16,
    /// Size in bits.
    pub bit_len: u16,
    /// Access rights and PDO mappability.
    pub access: crate::od::EntryAccess,
    /// Name.
    pub name: String,
}
