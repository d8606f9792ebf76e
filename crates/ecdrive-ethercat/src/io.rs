//! Frame I/O for ethercrab, driven by ecdrive itself.
//!
//! ethercrab queues frames in its `PduStorage`; somebody must send them and hand the replies back
//! (`PduTx` / `PduRx`). ethercrab's own drivers do this on a separate thread or task, and time out
//! each frame with an `async_io::Timer`, which registers with async-io's reactor thread on every
//! poll (a syscall and a queue shared with a non-real-time thread). ecdrive instead runs ethercrab
//! with the PDU timeout set to "never" and moves the frames itself with a [`Pump`]: during start-up
//! the [`exec`](super::exec) executor pumps between polls; in the cycle the cycle thread pumps
//! inline, so frame I/O and the sleep are its only syscalls. Lost frames are detected here, by
//! age, retransmitted a bounded number of times, and finally reported so the caller drops the
//! waiting future (ethercrab releases the frame slot on drop).

use crate::answers::{Answers, Verdict};
use crate::ec::frame::{EthercatFrame, EthernetFrame, MAC_LOCAL_BIT};
use crate::ec::register::FmmuConfig;
use crate::ec::{command::Command, register};
use crate::rt::monotonic_ns;
use ethercrab::{PduRx, PduTx};
use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::task::{Wake, Waker};
use std::time::Duration;

pub use crate::link::{FrameLink, LinkError};

/// Largest Ethernet frame (without FCS) the pump handles.
pub const MAX_FRAME: usize = 1514;

/// Counters of everything the pump saw. Read by telemetry; plain integers, no allocation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct PumpStats {
    /// Frames sent (first transmissions).
    pub sent: u64,
    /// Replies handed to ethercrab.
    pub received: u64,
    /// Retransmissions after a frame got no reply in time.
    pub retransmitted: u64,
    /// Frames given up on after the last retransmission.
    pub lost: u64,
    /// Replies that matched no frame in flight (late replies to frames already given up on).
    pub stale: u64,
    /// Frames on the link that were not EtherCAT replies or that ethercrab rejected.
    pub rejected: u64,
    /// Our own frames coming back unprocessed (the source address without the bit every
    /// slave controller sets): a loopback or a reflecting switch, no EtherCAT device.
    pub echoes: u64,
    /// Frames of ethercrab's answered without the wire, from what ecdrive had read or
    /// written (start-up; see [`crate::answers`]). Not counted in `sent`.
    pub answered: u64,
    /// Time spent inside the link's send, ns (the syscall, for a raw socket).
    pub link_send_ns: u64,
    /// Time spent inside the link's receive, ns (the syscall, and the wait when nothing had
    /// arrived yet).
    pub link_recv_ns: u64,
}

#[derive(Clone, Copy)]
struct InFlight {
    /// Index of the first PDU: ethercrab maps a reply back to its frame by it.
    first_idx: u8,
    len: usize,
    sent_at: u64,
    retries: u8,
    lost: bool,
}

/// Timing policy for lost frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LossPolicy {
    /// A frame with no reply after this many nanoseconds is retransmitted (or given up on).
    pub frame_timeout_ns: u64,
    /// Retransmissions before a frame counts as lost.
    pub retries: u8,
}

impl Default for LossPolicy {
    fn default() -> Self {
        Self {
            frame_timeout_ns: 30_000_000,
            retries: 2,
        }
    }
}

/// Offset of the first PDU's index byte in an EtherCAT frame: Ethernet header (14), EtherCAT
/// header (2), command (1).
const FIRST_IDX_OFFSET: usize = 14 + 2 + 1;

/// Whether `frame`'s first datagram has the command and address in `first` (the command byte,
/// then the four address bytes; the index byte between them, a sequence number, is not
/// compared): how the cycle's own frames and their replies are told from ethercrab's.
pub(crate) fn first_datagram_is(frame: &[u8], first: &[u8; 5]) -> bool {
    frame.get(FIRST_IDX_OFFSET - 1) == first.first()
        && frame.get(FIRST_IDX_OFFSET + 1..FIRST_IDX_OFFSET + 5) == first.get(1..)
}

/// Watches the mailbox requests that go out on the wire.
///
/// A device drops a mailbox request whose counter equals the previous request's as a repeat
/// (ETG.1000.4 mailbox header `Cnt`; the slave stacks SOES and the SSC do). Two clients write the
/// mailboxes of one device in a session: ecdrive's CoE client and ethercrab's own (it reads the
/// PDO assignment while it builds the process image), each with its own counter. So that the
/// two sequences never collide, the bus must know every counter that went out, whoever sent it.
/// The tap learns where each device's SM0 (the write mailbox) starts from the SyncManager
/// writes it sees (FPWR to 0x0800) or from [`Pump::learn_mailbox`], and records the counter of
/// every FPWR to that address.
///
/// The same tap keeps the FMMU configuration every device was sent (FPWR to 0x0600–0x06FF):
/// where each device's inputs and outputs sit in the logical process image, as its ESC will
/// count them in the working counter (see [`Pump::fmmu_configs`]).
#[derive(Debug, Default)]
struct MailboxTap {
    on: bool,
    /// Station address → SM0 start.
    sm0: HashMap<u16, u16>,
    /// (station address, counter) of each mailbox request sent while the tap was on.
    seen: Vec<(u16, u8)>,
    /// (station address, FMMU number) → the block last written.
    fmmus: HashMap<(u16, u8), FmmuConfig>,
    /// Monotonic times of the first and the last frame with an SII (EEPROM) access, and how
    /// many such frames went out.
    sii: Option<(u64, u64, u64)>,
}

impl MailboxTap {
    fn observe(&mut self, frame: &[u8]) {
        let Ok(eth) = EthernetFrame::new_checked(frame) else {
            return;
        };
        let Ok(ecat) = EthercatFrame::new_checked(eth.payload()) else {
            return;
        };
        let mut sii = false;
        for d in ecat.datagrams() {
            let Ok(d) = d else { break };
            let logical = d.command().is_some_and(Command::is_logical);
            if !logical && (register::SII_CONTROL..=register::SII_DATA + 7).contains(&d.ado()) {
                sii = true;
            }
            if d.command() != Some(Command::Fpwr) {
                continue;
            }
            let (station, ado, data) = (d.adp(), d.ado(), d.data());
            if (register::FMMU_BASE..register::SM_BASE).contains(&ado) {
                let first = (ado - register::FMMU_BASE) / register::FMMU_SIZE;
                let blocks = data.chunks_exact(usize::from(register::FMMU_SIZE));
                for (k, b) in blocks.enumerate() {
                    if let (Some(c), Ok(n)) =
                        (FmmuConfig::parse(b), u8::try_from(usize::from(first) + k))
                    {
                        self.fmmus.insert((station, n), c);
                    }
                }
            } else if ado == register::sm(0) && data.len() >= 2 {
                let start = u16::from_le_bytes([data[0], data[1]]);
                self.sm0.insert(station, start);
            } else if self.sm0.get(&station) == Some(&ado) && data.len() >= 6 {
                // Mailbox header byte 5, bits 4–6: the counter.
                self.seen.push((station, (data[5] >> 4) & 0x07));
            }
        }
        if sii {
            let now = monotonic_ns();
            self.sii = Some(
                self.sii
                    .map_or((now, now, 1), |(first, _, n)| (first, now, n + 1)),
            );
        }
    }
}

/// One logical datagram (LRD/LWR/LRW) as it came back: where it addressed the process image and
/// the working counter the devices gave it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LogicalSeen {
    /// Logical start address.
    pub address: u32,
    /// Length in bytes.
    pub len: u16,
    /// Working counter.
    pub wkc: u16,
}

/// How many logical datagrams one cycle's record holds (ethercrab splits the process image
/// over as many frames as it needs; this covers images up to about 11 kB).
pub const LOGICAL_RECORD: usize = 8;

/// The logical datagrams of the replies received since the record was cleared: a fixed array,
/// written in the receive path without allocation.
#[derive(Debug, Clone, Copy, Default)]
struct LogicalRecord {
    on: bool,
    seen: [LogicalSeen; LOGICAL_RECORD],
    n: usize,
    overflow: bool,
}

impl LogicalRecord {
    fn observe(&mut self, frame: &[u8]) {
        let Ok(eth) = EthernetFrame::new_checked(frame) else {
            return;
        };
        let Ok(ecat) = EthercatFrame::new_checked(eth.payload()) else {
            return;
        };
        for d in ecat.datagrams() {
            let Ok(d) = d else { break };
            if !d.command().is_some_and(Command::is_logical) {
                continue;
            }
            self.note(LogicalSeen {
                address: d.logical_address(),
                len: u16::try_from(d.data_len()).unwrap_or(u16::MAX),
                wkc: d.wkc(),
            });
        }
    }

    fn note(&mut self, seen: LogicalSeen) {
        match self.seen.get_mut(self.n) {
            Some(slot) => {
                *slot = seen;
                self.n += 1;
            }
            None => self.overflow = true,
        }
    }
}

/// Moves frames between ethercrab and a [`FrameLink`]. See the module documentation.
pub struct Pump<'sto, L: FrameLink> {
    tx: PduTx<'sto>,
    rx: PduRx<'sto>,
    link: L,
    inflight: Vec<Option<InFlight>>,
    /// Copies of the frames in flight, for retransmission (one slot per storage frame).
    copies: Vec<[u8; MAX_FRAME]>,
    rx_buf: Box<[u8; MAX_FRAME + 4]>,
    stats: PumpStats,
    policy: LossPolicy,
    link_error: Option<String>,
    tap: MailboxTap,
    logical: LogicalRecord,
    /// `false`: the distribution of the reference clock's time (FRMW to 0x0910) is sent as a
    /// plain read of it (FPRD), so no other clock is corrected; the reply is handed back as
    /// the FRMW ethercrab sent ([`Pump::set_drift_compensation`]).
    drift_writes: bool,
    /// The frame as sent when the pump rewrites it.
    scratch: Box<[u8; MAX_FRAME]>,
    /// Answers to ethercrab's re-reads, during start-up (see [`crate::answers`]).
    answers: Option<Answers>,
    /// The reply an answer made.
    answer_buf: Box<[u8; MAX_FRAME]>,
    /// Copies of the frames ethercrab sent while capturing (see [`Pump::capture`]).
    capture: Capture,
    /// Set by ethercrab when it queues a frame, while watched (see [`Pump::watch_queue`]).
    queued: Option<Arc<QueuedFlag>>,
    /// The frames ecdrive builds itself, by length and first datagram (command and address):
    /// a late reply to one is dropped, never handed to ethercrab (see [`Pump::own_frames`]).
    own_shapes: Vec<(usize, [u8; 5])>,
}

/// ethercrab's sender waker, as a flag: ethercrab wakes it after it queued a frame.
struct QueuedFlag(AtomicBool);

impl Wake for QueuedFlag {
    fn wake(self: Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }

    fn wake_by_ref(self: &Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
}

/// Copies of the frames sent through ethercrab, as ethercrab made them, while on: buffers
/// allocated when capturing is first switched on, so capturing in the cycle allocates nothing.
#[derive(Default)]
struct Capture {
    on: bool,
    frames: Vec<[u8; MAX_FRAME]>,
    lens: Vec<usize>,
    /// More frames went out than it keeps.
    overflow: bool,
}

/// How many frames one capture keeps (the frames of one cycle's exchange, and the session's
/// that went out meanwhile).
const CAPTURE_FRAMES: usize = 32;

/// Datagram commands: FPRD (configured-address read) and FRMW (configured-address read,
/// multiple write), ETG.1000.4 table 14.
const FPRD: u8 = 4;
const FRMW: u8 = 14;
/// The system time register the reference clock's time is distributed to (ETG.1000.4).
const SYSTEM_TIME: u16 = 0x0910;

/// Rewrite, in the EtherCAT frame `frame` (Ethernet header included), every datagram with
/// command `from` to address `SYSTEM_TIME` into command `to`. Returns how many.
fn rewrite_system_time(frame: &mut [u8], from: u8, to: u8) -> usize {
    let mut at = 14 + 2;
    let mut n = 0;
    while let Some(h) = frame.get_mut(at..at + 10) {
        let len = usize::from(u16::from_le_bytes([h[6], h[7]]) & 0x07FF);
        let more = h[7] & 0x80 != 0;
        if h[0] == from && u16::from_le_bytes([h[4], h[5]]) == SYSTEM_TIME {
            h[0] = to;
            n += 1;
        }
        if !more {
            break;
        }
        at += 10 + len + 2;
    }
    n
}

impl<'sto, L: FrameLink> Pump<'sto, L> {
    /// A pump over ethercrab's TX/RX handles and a link. Allocates its buffers once, here.
    pub fn new(tx: PduTx<'sto>, rx: PduRx<'sto>, link: L, policy: LossPolicy) -> Self {
        let n = tx.capacity();
        Self {
            tx,
            rx,
            link,
            inflight: vec![None; n],
            copies: vec![[0u8; MAX_FRAME]; n],
            rx_buf: Box::new([0u8; MAX_FRAME + 4]),
            stats: PumpStats::default(),
            policy,
            link_error: None,
            tap: MailboxTap::default(),
            logical: LogicalRecord::default(),
            drift_writes: true,
            scratch: Box::new([0u8; MAX_FRAME]),
            answers: None,
            answer_buf: Box::new([0u8; MAX_FRAME]),
            capture: Capture::default(),
            queued: None,
            own_shapes: Vec::new(),
        }
    }

    /// The frames ecdrive builds itself from now on, each by its length and its first
    /// datagram's command and address (empty: none). A reply of that shape that reaches the
    /// pump outside [`receive_own`](Self::receive_own) — late, after its cycle gave it up, or
    /// after the cycle ended — is counted stale and dropped: its first index is ecdrive's
    /// sequence number, which ethercrab's own frames may use too, and ethercrab would take it
    /// for theirs. Kept until replaced (a new cycle clears it before ethercrab's frames of the
    /// same shape go out again).
    pub fn own_frames(&mut self, shapes: &[(usize, [u8; 5])]) {
        self.own_shapes.clear();
        self.own_shapes.extend_from_slice(shapes);
    }

    fn is_own_shape(&self, frame: &[u8]) -> bool {
        self.own_shapes
            .iter()
            .any(|(len, first)| frame.len() == *len && first_datagram_is(frame, first))
    }

    /// Have ethercrab say when it queues a frame (its sender waker sets a flag), so that
    /// [`send_queued`](Self::send_queued) looks through its frame slots only then. Allocates
    /// the flag once.
    pub fn watch_queue(&mut self) {
        let flag = self
            .queued
            .get_or_insert_with(|| Arc::new(QueuedFlag(AtomicBool::new(true))));
        // Something may have been queued before the waker was in place.
        flag.0.store(true, Ordering::Release);
        self.tx.replace_waker(&Waker::from(flag.clone()));
    }

    /// [`send_pending`](Self::send_pending), when ethercrab queued something since the last
    /// look (always, unless [`watch_queue`](Self::watch_queue) is on). ethercrab takes its
    /// waker when it wakes it: it is put back before the look, so a frame queued after the look
    /// sets the flag again. No allocation.
    pub fn send_queued(&mut self) -> Result<usize, LinkError> {
        if let Some(flag) = &self.queued {
            // A plain load first: the usual answer (nothing queued) without taking the line.
            if !flag.0.load(Ordering::Acquire) || !flag.0.swap(false, Ordering::AcqRel) {
                return Ok(0);
            }
            self.tx.replace_waker(&Waker::from(flag.clone()));
        }
        self.send_pending()
    }

    /// Keep a copy of every frame ethercrab sends from now on, as ethercrab made it (before a
    /// rewrite or an answer), up to 32; `false` stops and keeps what was taken. Switching
    /// it on clears what was taken (and allocates the buffers the first time).
    pub fn capture(&mut self, on: bool) {
        let c = &mut self.capture;
        if on {
            if c.frames.is_empty() {
                c.frames = vec![[0u8; MAX_FRAME]; CAPTURE_FRAMES];
                c.lens = Vec::with_capacity(CAPTURE_FRAMES);
            }
            c.lens.clear();
            c.overflow = false;
        }
        c.on = on;
    }

    /// The frames taken by [`capture`](Self::capture), in the order they went out, and
    /// whether more went out than it keeps.
    pub fn captured(&self) -> (impl Iterator<Item = &[u8]>, bool) {
        let c = &self.capture;
        (
            c.frames.iter().zip(&c.lens).map(|(f, &n)| &f[..n]),
            c.overflow,
        )
    }

    /// Send a frame ecdrive built itself (no slot of ethercrab's; see [`receive_own`]).
    ///
    /// [`receive_own`]: Self::receive_own
    pub fn send_own(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let t0 = monotonic_ns();
        let r = self.link.send(frame);
        self.stats.link_send_ns += monotonic_ns() - t0;
        if let Err(e) = r {
            self.link_error = Some(e.to_string());
            return Err(e);
        }
        self.stats.sent += 1;
        Ok(())
    }

    /// Wait until `deadline_ns` for the next frame `ours` says is a reply to a frame ecdrive
    /// built itself (`Some(true)`), dropping those it says are late replies to earlier ones of
    /// its own (`Some(false)`: counted stale, never handed to ethercrab, whose frames may use
    /// the same index) and handing every other frame that comes to ethercrab. The reply goes
    /// into `reply`; its length, or `None` when none came.
    pub fn receive_own(
        &mut self,
        reply: &mut [u8],
        deadline_ns: u64,
        ours: impl Fn(&[u8]) -> Option<bool>,
    ) -> Result<Option<usize>, LinkError> {
        loop {
            let Some(got) = self.recv_timed(deadline_ns)? else {
                return Ok(None);
            };
            let frame = self.rx_buf.get(..got).unwrap_or(&[]);
            match ours(frame) {
                Some(true) => {
                    if let Some(dst) = reply.get_mut(..got) {
                        dst.copy_from_slice(frame);
                        self.stats.received += 1;
                        return Ok(Some(got));
                    }
                    self.stats.rejected += 1;
                }
                Some(false) => self.stats.stale += 1,
                None => {
                    self.accept(got);
                }
            }
        }
    }

    /// Record a logical datagram of a reply to a frame of ecdrive's own, as those of the
    /// replies ethercrab takes are (see [`logical_seen`](Self::logical_seen)).
    pub fn note_logical(&mut self, seen: LogicalSeen) {
        if self.logical.on {
            self.logical.note(seen);
        }
    }

    /// Answer ethercrab's re-reads from `answers` from now on (`None`: every frame goes to
    /// the wire). See [`crate::answers`].
    pub fn set_answers(&mut self, answers: Option<Answers>) -> Option<Answers> {
        std::mem::replace(&mut self.answers, answers)
    }

    /// The answers in use, if any.
    pub fn answers_mut(&mut self) -> Option<&mut Answers> {
        self.answers.as_mut()
    }

    /// Send a frame ecdrive built itself (its first datagram's index [`crate::answers::RAW_INDEX`],
    /// outside ethercrab's) and wait until `deadline_ns` for its reply, handing any other
    /// frame that comes to ethercrab. The reply goes into `reply`; its length, or `None` when
    /// none came.
    pub fn exchange_raw(
        &mut self,
        frame: &[u8],
        reply: &mut [u8],
        deadline_ns: u64,
    ) -> Result<Option<usize>, LinkError> {
        if let Err(e) = self.link.send(frame) {
            self.link_error = Some(e.to_string());
            return Err(e);
        }
        self.stats.sent += 1;
        // Counted in the SII span whether or not the tap is on (nothing else in these frames).
        let on = std::mem::replace(&mut self.tap.on, true);
        self.tap.observe(frame);
        self.tap.on = on;
        self.receive_raw(reply, deadline_ns)
    }

    /// Wait until `deadline_ns` for the next reply to a frame of ecdrive's own (see
    /// [`exchange_raw`](Self::exchange_raw)): a later one, when the one that came was a late
    /// reply to an earlier frame.
    pub fn receive_raw(
        &mut self,
        reply: &mut [u8],
        deadline_ns: u64,
    ) -> Result<Option<usize>, LinkError> {
        self.receive_own(reply, deadline_ns, |f| {
            (f.get(FIRST_IDX_OFFSET) == Some(&crate::answers::RAW_INDEX)
                && f.get(6).is_some_and(|b| b & MAC_LOCAL_BIT != 0))
            .then_some(true)
        })
    }

    /// Whether the reference clock's time is distributed to the other clocks (on by
    /// default: that is the drift compensation of every cycle). Off, the FRMW ethercrab sends
    /// goes out as an FPRD of the same register, the clocks drift apart, and the reply is
    /// handed back as the FRMW — the switch that shows what compensation does
    /// ([`crate::CycleSettings::drift_compensation`]).
    pub fn set_drift_compensation(&mut self, on: bool) {
        self.drift_writes = on;
    }

    /// The FMMU blocks every device was sent while the tap was on, by (station address, FMMU
    /// number): the master's own record of the logical process image as the ESCs map it.
    pub fn fmmu_configs(&self) -> impl Iterator<Item = (u16, u8, FmmuConfig)> + '_ {
        self.tap.fmmus.iter().map(|(&(st, n), &c)| (st, n, c))
    }

    /// The monotonic times of the first and the last frame with an SII (EEPROM) access sent
    /// while the tap was on, since the last call, and the number of such frames.
    pub fn take_sii_span(&mut self) -> Option<(u64, u64, u64)> {
        self.tap.sii.take()
    }

    /// Record the logical datagrams (LRD/LWR/LRW) of the replies from now on, in a fixed
    /// array (allocation-free: the cycle keeps it on), and clear the record.
    pub fn record_logical(&mut self, on: bool) {
        self.logical = LogicalRecord {
            on,
            ..LogicalRecord::default()
        };
    }

    /// Clear the record of logical datagrams (keeps it on or off).
    pub fn clear_logical(&mut self) {
        self.logical.n = 0;
        self.logical.overflow = false;
    }

    /// The logical datagrams received since the record was cleared, in arrival order, and
    /// whether more arrived than the record holds ([`LOGICAL_RECORD`]).
    pub fn logical_seen(&self) -> (&[LogicalSeen], bool) {
        (
            self.logical.seen.get(..self.logical.n).unwrap_or(&[]),
            self.logical.overflow,
        )
    }

    /// Record the counters of mailbox requests sent from now on (off by default; never on in
    /// the cycle). See [`take_mailbox_counters`](Self::take_mailbox_counters).
    pub fn set_mailbox_tap(&mut self, on: bool) {
        self.tap.on = on;
    }

    /// Tell the tap where the write mailbox (SM0) of the device at `station` starts, when it
    /// was configured before the tap saw it.
    pub fn learn_mailbox(&mut self, station: u16, sm0_start: u16) {
        self.tap.sm0.insert(station, sm0_start);
    }

    /// The (station address, counter) of every mailbox request sent while the tap was on, in
    /// order, since the last call.
    pub fn take_mailbox_counters(&mut self) -> Vec<(u16, u8)> {
        std::mem::take(&mut self.tap.seen)
    }

    /// The link.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// The link's name for messages.
    pub fn link_name(&self) -> String {
        self.link.describe()
    }

    /// The link, mutably (e.g. to inject faults into an in-process segment).
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// The counters.
    pub fn stats(&self) -> PumpStats {
        self.stats
    }

    /// The loss policy in force.
    pub fn policy(&self) -> LossPolicy {
        self.policy
    }

    /// Change the loss policy (start-up tolerates slower replies than the cycle).
    pub fn set_policy(&mut self, policy: LossPolicy) {
        self.policy = policy;
    }

    /// Register the waker ethercrab wakes when it queues a frame.
    pub fn register_waker(&mut self, waker: &Waker) {
        self.queued = None;
        self.tx.replace_waker(waker);
    }

    /// Number of frames sent and neither answered nor given up on.
    pub fn outstanding(&self) -> usize {
        self.inflight
            .iter()
            .filter(|f| matches!(f, Some(f) if !f.lost))
            .count()
    }

    /// Send every frame ethercrab has queued. Returns how many were sent.
    pub fn send_pending(&mut self) -> Result<usize, LinkError> {
        let mut n = 0;
        while let Some(frame) = self.tx.next_sendable_frame() {
            let mut slot_free = None;
            for (i, f) in self.inflight.iter().enumerate() {
                if f.is_none() {
                    slot_free = Some(i);
                    break;
                }
            }
            let link = &mut self.link;
            let copies = &mut self.copies;
            let tap = &mut self.tap;
            let scratch = &mut self.scratch;
            let rewrite = !self.drift_writes;
            let mut record = None;
            let mut err = None;
            let mut answered = None;
            let answers = &mut self.answers;
            let answer_buf = &mut self.answer_buf;
            let send_ns = &mut self.stats.link_send_ns;
            let capture = &mut self.capture;
            let res = frame.send_blocking(|sent| {
                if capture.on {
                    match capture.frames.get_mut(capture.lens.len()) {
                        Some(slot) if capture.lens.len() < CAPTURE_FRAMES => {
                            if let Some(dst) = slot.get_mut(..sent.len()) {
                                dst.copy_from_slice(sent);
                                capture.lens.push(sent.len());
                            }
                        }
                        _ => capture.overflow = true,
                    }
                }
                let verdict = match answers.as_mut() {
                    Some(a) => a.answer(sent, &mut answer_buf[..]),
                    None => Verdict::Wire,
                };
                let sent: &[u8] = match verdict {
                    // A re-read answered from what ecdrive read: not sent.
                    Verdict::Answered(n) => {
                        answered = Some(n);
                        return Ok(sent.len());
                    }
                    Verdict::Rewritten(n) => answer_buf.get(..n).unwrap_or(sent),
                    Verdict::Wire => sent,
                };
                // Without drift compensation, the time distribution as a plain read.
                let bytes: &[u8] = match scratch.get_mut(..sent.len()) {
                    Some(buf) if rewrite => {
                        buf.copy_from_slice(sent);
                        rewrite_system_time(buf, FRMW, FPRD);
                        buf
                    }
                    _ => sent,
                };
                let t0 = monotonic_ns();
                let sent_ok = link.send(bytes);
                *send_ns += monotonic_ns() - t0;
                if let Err(e) = sent_ok {
                    err = Some(e);
                    return Err(ethercrab::error::Error::SendFrame);
                }
                if tap.on {
                    tap.observe(bytes);
                }
                if let (Some(i), Some(first)) = (slot_free, bytes.get(FIRST_IDX_OFFSET)) {
                    let len = bytes.len().min(MAX_FRAME);
                    if let Some(copy) = copies.get_mut(i) {
                        copy[..len].copy_from_slice(&bytes[..len]);
                    }
                    record = Some((i, *first, len));
                }
                Ok(bytes.len())
            });
            if let Some(e) = err {
                self.link_error = Some(e.to_string());
                return Err(e);
            }
            if let Some(len) = answered {
                if res.is_ok()
                    && let Some(reply) = self.answer_buf.get(..len)
                    && matches!(
                        self.rx.receive_frame(reply),
                        Ok(ethercrab::ReceiveAction::Processed)
                    )
                {
                    self.stats.answered += 1;
                } else {
                    self.stats.rejected += 1;
                }
                continue;
            }
            if res.is_ok() {
                n += 1;
                self.stats.sent += 1;
                if let Some((i, first_idx, len)) = record
                    && let Some(slot) = self.inflight.get_mut(i)
                {
                    *slot = Some(InFlight {
                        first_idx,
                        len,
                        sent_at: monotonic_ns(),
                        retries: 0,
                        lost: false,
                    });
                }
            }
        }
        Ok(n)
    }

    /// One frame from the link into `rx_buf`, waiting until `deadline_ns`; its length, or
    /// `None` when none came. The time inside the link is counted; a link error is kept.
    fn recv_timed(&mut self, deadline_ns: u64) -> Result<Option<usize>, LinkError> {
        let t0 = monotonic_ns();
        let timeout = Duration::from_nanos(deadline_ns.saturating_sub(t0));
        let got = self.link.recv(&mut self.rx_buf[..], Some(timeout));
        self.stats.link_recv_ns += monotonic_ns() - t0;
        got.inspect_err(|e| self.link_error = Some(e.to_string()))
    }

    /// Receive replies until nothing is outstanding or `deadline_ns` passes, handing each to
    /// ethercrab. Returns the number of replies handed over.
    pub fn receive_until(&mut self, deadline_ns: u64) -> Result<usize, LinkError> {
        let mut n = 0;
        while self.outstanding() > 0 {
            let Some(got) = self.recv_timed(deadline_ns)? else {
                break;
            };
            if self.accept(got) {
                n += 1;
            }
        }
        Ok(n)
    }

    /// Receive whatever has already arrived, without waiting.
    pub fn receive_ready(&mut self) -> Result<usize, LinkError> {
        self.receive_until(0)
    }

    fn accept(&mut self, len: usize) -> bool {
        if !self.drift_writes
            && let Some(f) = self.rx_buf.get_mut(..len)
        {
            // Handed back as the FRMW ethercrab sent.
            rewrite_system_time(f, FPRD, FRMW);
        }
        let Some(frame) = self.rx_buf.get(..len) else {
            self.stats.rejected += 1;
            return false;
        };
        let Some(&first) = frame.get(FIRST_IDX_OFFSET) else {
            self.stats.rejected += 1;
            return false;
        };
        if !self.own_shapes.is_empty() && self.is_own_shape(frame) {
            self.stats.stale += 1;
            return false;
        }
        let slot = self
            .inflight
            .iter()
            .position(|f| matches!(f, Some(f) if f.first_idx == first));
        let Some(slot) = slot else {
            self.stats.stale += 1;
            return false;
        };
        // A frame no slave controller forwarded keeps the source address we sent (each ESC
        // sets its locally-administered bit): an echo, not a reply. Left in flight, it times
        // out, and discovery says nothing answered, at once instead of after its timeout.
        if let (Some(sent), Some(got)) = (
            self.copies.get(slot).and_then(|c| c.get(6..12)),
            frame.get(6..12),
        ) && sent == got
        {
            self.stats.echoes += 1;
            return false;
        }
        let was_lost = matches!(self.inflight.get(slot), Some(Some(f)) if f.lost);
        if let Some(s) = self.inflight.get_mut(slot) {
            *s = None;
        }
        if was_lost {
            // The caller already gave up on this frame and dropped its future.
            self.stats.stale += 1;
            return false;
        }
        match self.rx.receive_frame(frame) {
            Ok(ethercrab::ReceiveAction::Processed) => {
                if self.logical.on {
                    self.logical.observe(frame);
                }
                self.stats.received += 1;
                true
            }
            _ => {
                self.stats.rejected += 1;
                false
            }
        }
    }

    /// Retransmit frames that got no reply within the policy's timeout; mark those out of
    /// retries as lost. Returns the number newly lost. The caller must drop the futures waiting
    /// for lost frames (ethercrab then frees their slots).
    pub fn check_timeouts(&mut self) -> Result<usize, LinkError> {
        let now = monotonic_ns();
        let mut lost = 0;
        for i in 0..self.inflight.len() {
            let Some(Some(f)) = self.inflight.get(i).copied() else {
                continue;
            };
            if f.lost || now.saturating_sub(f.sent_at) < self.policy.frame_timeout_ns {
                continue;
            }
            if f.retries < self.policy.retries {
                if let Some(copy) = self.copies.get(i)
                    && let Err(e) = self.link.send(&copy[..f.len])
                {
                    self.link_error = Some(e.to_string());
                    return Err(e);
                }
                self.stats.retransmitted += 1;
                if let Some(Some(s)) = self.inflight.get_mut(i) {
                    s.retries += 1;
                    s.sent_at = now;
                }
            } else {
                self.stats.lost += 1;
                lost += 1;
                if let Some(Some(s)) = self.inflight.get_mut(i) {
                    s.lost = true;
                }
            }
        }
        Ok(lost)
    }

    /// Forget frames marked lost, once their futures have been dropped.
    pub fn clear_lost(&mut self) {
        for f in self.inflight.iter_mut() {
            if matches!(f, Some(x) if x.lost) {
                *f = None;
            }
        }
    }

    /// Forget every frame in flight (after the futures waiting for them were dropped).
    pub fn clear_all(&mut self) {
        for f in self.inflight.iter_mut() {
            *f = None;
        }
    }

    /// The last link error, if the link failed.
    pub fn link_error(&self) -> Option<&str> {
        self.link_error.as_deref()
    }

    /// Take the TX/RX handles and the link back.
    pub fn into_parts(self) -> (PduTx<'sto>, PduRx<'sto>, L) {
        (self.tx, self.rx, self.link)
    }
}
