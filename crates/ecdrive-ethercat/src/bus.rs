//! One bus session: the ethercrab `MainDevice`, its PDU storage, and the [`Pump`] that moves its
//! frames over a link.
//!
//! A session owns its storage: [`with_bus`] creates it, lends the [`Bus`] to a closure, and
//! frees everything when the closure returns. A new session (after a cable pull, say) gets fresh
//! storage; nothing is leaked and nothing needs `unsafe` re-use of ethercrab's storage.

use super::coe::{CoeClient, CoeError, EmergencyLog, MailboxSequence};
use super::error::{DriveRef, ErrorKind, MasterError};
use super::exec::{self, ExecError};
use super::io::{FrameLink, LossPolicy, MAX_FRAME, Pump};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, RetryBehaviour, Timeouts};
use std::collections::HashMap;
use std::future::Future;
use std::time::Duration;

/// What discovery took: time and frames, in all and on the SII (EEPROM).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Discovery {
    /// From the first frame to every device's identity, ms.
    pub ms: f64,
    /// From the first to the last frame with an SII access, ms.
    pub sii_ms: f64,
    /// Frames sent.
    pub frames: u64,
    /// Of them, frames with an SII access.
    pub sii_frames: u64,
    /// ethercrab's frames answered from the SII read at once (not sent).
    pub answered: u64,
}

/// Frames ethercrab may have in flight at once.
pub const MAX_FRAMES: usize = 64;
/// Largest number of devices on one segment.
pub const MAX_SUBDEVICES: usize = 256;
/// Largest process image (inputs + outputs of every device), bytes.
pub const MAX_PDI: usize = 16384;

/// The PDU storage of one session. An ethercrab frame buffer holds the whole Ethernet frame:
/// `element_size` adds ethercrab's 28 bytes of headers (`element_size(0)`) to the PDU data, so
/// the data may be `MAX_FRAME − 28` for every frame to fit an Ethernet frame. (With
/// `element_size(MAX_FRAME)` ethercrab packs frames of up to 1542 bytes when there is much to
/// send, e.g. the DC set-up of 64 drives, and a NIC or the in-process segment refuses them.)
pub type Storage =
    PduStorage<MAX_FRAMES, { PduStorage::element_size(MAX_FRAME - PduStorage::element_size(0)) }>;

const _: () = assert!(
    PduStorage::element_size(MAX_FRAME - PduStorage::element_size(0)) == MAX_FRAME,
    "ethercrab frames must fit an Ethernet frame"
);

/// Timing of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusOptions {
    /// Lost-frame policy during start-up and supervisory work.
    pub loss: LossPolicy,
    /// How long one mailbox reply may take.
    pub mailbox_timeout: Duration,
    /// ethercrab's state-transition timeout.
    pub state_transition: Duration,
    /// ethercrab's EEPROM timeout.
    pub eeprom: Duration,
    /// ethercrab's static drift compensation at init: frames sent whatever the clocks do
    /// (ethercrab's default is 10 000). 0 by default: start-up compensates drift itself until
    /// every drive's clock is measured to be within the threshold
    /// ([`DcSettings`](crate::startup::DcSettings)), however many frames that takes.
    pub dc_static_sync_iterations: u32,
    /// Answer ethercrab's re-reads during start-up from what ecdrive read or wrote: every
    /// device's SII read at once before ethercrab's initialisation, the PDO configuration a
    /// drive acknowledged by SDO while ethercrab builds the process image
    /// ([`crate::answers`]). On by default; off, every read goes to the wire one frame at a
    /// time as ethercrab sends it (the two paths compared: docs/guide/startup-time.md).
    pub answer_rereads: bool,
}

impl Default for BusOptions {
    fn default() -> Self {
        Self {
            loss: LossPolicy {
                frame_timeout_ns: 50_000_000,
                retries: 3,
            },
            mailbox_timeout: Duration::from_millis(2000),
            state_transition: Duration::from_secs(10),
            eeprom: Duration::from_millis(500),
            dc_static_sync_iterations: 0,
            answer_rereads: true,
        }
    }
}

impl BusOptions {
    fn timeouts(&self) -> Timeouts {
        Timeouts {
            // Never: ecdrive's pump detects lost frames itself (see `master::io`).
            pdu: Duration::MAX,
            state_transition: self.state_transition,
            eeprom: self.eeprom,
            mailbox_echo: self.mailbox_timeout,
            mailbox_response: self.mailbox_timeout,
            wait_loop_delay: Duration::ZERO,
        }
    }
}

/// Why a session could not start.
#[derive(Debug, thiserror::Error)]
pub enum BusError {
    /// The PDU storage could not be split (an internal error).
    #[error("internal error: the PDU storage could not be split")]
    Storage,
    /// The session thread could not be started.
    #[error("cannot start the session thread: {0}")]
    Thread(String),
}

/// A live bus session. See [`with_bus`].
pub struct Bus<'sto, L: FrameLink> {
    md: MainDevice<'sto>,
    pump: Pump<'sto, L>,
    emergencies: EmergencyLog,
    opts: BusOptions,
    /// Mailbox counters per configured address, over ecdrive's and ethercrab's clients.
    counters: HashMap<u16, MailboxSequence>,
    /// The device ethercrab's client wrote a mailbox request to last (to name it when
    /// ethercrab's step fails).
    last_ethercrab_mailbox: Option<u16>,
    /// The last discovery's duration and its SII span, in ms (start-up's time report).
    discovery: Option<Discovery>,
    /// The answers to ethercrab's re-reads between discovery and the process image.
    answers: Option<crate::answers::Answers>,
}

/// How many devices' mailboxes [`Bus::with_coe_each`] works on at once: each has at most one
/// frame in flight, and ethercrab's storage holds [`MAX_FRAMES`]; three quarters of it stay
/// free for the rest, and a link need not hold more than this many replies waiting (\[REC\]:
/// 16, the in-process segment holds 32).
pub const MAILBOXES_AT_ONCE: usize = MAX_FRAMES / 4;

/// What one device's mailbox work gave: the result, the last mailbox counter, its SM0 start.
type CoeRun<T> = (Result<T, CoeError>, u8, Option<u16>);

/// Open a session on `link` and run `f` with it. The storage and the link live as long as the
/// call; the link is returned with `f`'s result (or with the error).
pub fn with_bus<L: FrameLink, R>(
    link: L,
    opts: BusOptions,
    f: impl FnOnce(&mut Bus<'_, L>) -> R,
) -> Result<(R, L), (BusError, L)> {
    let storage = Box::new(Storage::new());
    let Ok((tx, rx, pdu_loop)) = storage.try_split() else {
        return Err((BusError::Storage, link));
    };
    let md = MainDevice::new(
        pdu_loop,
        opts.timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: opts.dc_static_sync_iterations,
            retry_behaviour: RetryBehaviour::None,
        },
    );
    let mut bus = Bus {
        md,
        pump: Pump::new(tx, rx, link, opts.loss),
        emergencies: EmergencyLog::default(),
        opts,
        counters: HashMap::new(),
        last_ethercrab_mailbox: None,
        discovery: None,
        answers: None,
    };
    let r = f(&mut bus);
    let (_, _, link) = bus.pump.into_parts();
    Ok((r, link))
}

/// Stack size of session threads: ethercrab's group is held inline in futures.
pub const SESSION_STACK: usize = 16 * 1024 * 1024;

/// Like [`with_bus`], on a dedicated thread with a stack large enough for ethercrab's group
/// (see [`SESSION_STACK`]). Returns when `f` does.
pub fn run_session<L, R, F>(link: L, opts: BusOptions, f: F) -> Result<(R, L), (BusError, L)>
where
    L: FrameLink + Send + 'static,
    R: Send + 'static,
    F: FnOnce(&mut Bus<'_, L>) -> R + Send + 'static,
{
    // The link goes to the thread only once it runs, so a failed spawn can give it back.
    let (link_tx, link_rx) = std::sync::mpsc::channel::<L>();
    let h = std::thread::Builder::new()
        .name("ecdrive-session".into())
        .stack_size(SESSION_STACK)
        .spawn(move || {
            let link = link_rx
                .recv()
                .map_err(|_| BusError::Thread("no link".into()));
            link.map(|l| with_bus(l, opts, f))
        });
    let h = match h {
        Ok(h) => h,
        Err(e) => return Err((BusError::Thread(e.to_string()), link)),
    };
    if let Err(std::sync::mpsc::SendError(link)) = link_tx.send(link) {
        return Err((
            BusError::Thread("the session thread ended at once".into()),
            link,
        ));
    }
    match h.join() {
        Ok(Ok(r)) => r,
        // The thread received the link; it cannot fail to receive it.
        Ok(Err(_)) => unreachable!("the link was sent before joining"),
        Err(p) => std::panic::resume_unwind(p),
    }
}

impl<'sto, L: FrameLink> Bus<'sto, L> {
    /// The ethercrab main device.
    pub fn md(&self) -> &MainDevice<'sto> {
        &self.md
    }

    /// The pump (statistics, the link).
    pub fn pump(&self) -> &Pump<'sto, L> {
        &self.pump
    }

    /// The pump, mutably.
    pub fn pump_mut(&mut self) -> &mut Pump<'sto, L> {
        &mut self.pump
    }

    /// Both halves at once: the main device to build futures on, the pump to run them.
    pub fn split(&mut self) -> (&MainDevice<'sto>, &mut Pump<'sto, L>) {
        (&self.md, &mut self.pump)
    }

    /// The session options.
    pub fn options(&self) -> &BusOptions {
        &self.opts
    }

    /// Every emergency received so far by any CoE client of this session.
    pub fn emergencies(&self) -> &EmergencyLog {
        &self.emergencies
    }

    /// Run the future `f` builds on the main device, pumping its frames, within `timeout`.
    /// `what` names the step for the error message.
    pub fn block_on<'a, F>(
        &'a mut self,
        what: &dyn Fn() -> String,
        timeout: Duration,
        f: impl FnOnce(&'a MainDevice<'sto>) -> F,
    ) -> Result<F::Output, ExecError>
    where
        F: Future,
    {
        let fut = f(&self.md);
        // ethercrab may write mailboxes itself (it reads the PDO assignment while it builds
        // the process image): record its counters.
        self.pump.set_mailbox_tap(true);
        let r = exec::run(&mut self.pump, what, timeout, fut);
        self.pump.set_mailbox_tap(false);
        for (station, c) in self.pump.take_mailbox_counters() {
            self.last_ethercrab_mailbox = Some(station);
            self.counters
                .entry(station)
                .or_default()
                .sent_by_ethercrab(c);
        }
        r
    }

    /// Run `op` for every item, [`MAILBOXES_AT_ONCE`] items at a time with their frames in
    /// flight together (register reads of many devices, EEPROM reads): one result per item, in
    /// the order of `items`. `Err` when the frames as a whole failed (the link, the segment,
    /// `timeout` per group of items).
    pub fn block_on_each<I, T>(
        &mut self,
        what: &dyn Fn() -> String,
        timeout: Duration,
        items: Vec<I>,
        op: impl AsyncFn(&MainDevice<'sto>, I) -> T,
    ) -> Result<Vec<T>, ExecError> {
        let mut out = Vec::with_capacity(items.len());
        let mut items = items.into_iter().peekable();
        let op = &op;
        while items.peek().is_some() {
            let md = &self.md;
            let futs: Vec<std::pin::Pin<Box<dyn Future<Output = T> + '_>>> = items
                .by_ref()
                .take(MAILBOXES_AT_ONCE)
                .map(|x| Box::pin(op(md, x)) as std::pin::Pin<Box<dyn Future<Output = T> + '_>>)
                .collect();
            self.pump.set_mailbox_tap(true);
            let r = exec::run(&mut self.pump, what, timeout, exec::join_all(futs));
            self.pump.set_mailbox_tap(false);
            out.extend(r?);
        }
        Ok(out)
    }

    /// Note what the last discovery took.
    pub fn set_discovery(&mut self, d: Discovery) {
        self.discovery = Some(d);
    }

    /// What the last discovery took.
    pub fn discovery(&self) -> Option<Discovery> {
        self.discovery
    }

    /// Keep the answers to ethercrab's re-reads for later (discovery leaves them here).
    pub fn stash_answers(&mut self, a: Option<crate::answers::Answers>) {
        self.answers = a;
    }

    /// The answers discovery left, if any.
    pub fn take_answers(&mut self) -> Option<crate::answers::Answers> {
        self.answers.take()
    }

    /// The configured address of the device to which ethercrab sent its last mailbox request
    /// (in a [`block_on`](Self::block_on) step), if it sent any.
    pub fn last_ethercrab_mailbox(&self) -> Option<u16> {
        self.last_ethercrab_mailbox
    }

    /// The mailbox counters of the device at configured `address`.
    pub fn mailbox_sequence(&self, address: u16) -> MailboxSequence {
        self.counters.get(&address).copied().unwrap_or_default()
    }

    /// Run `op` on the mailbox of every device of `jobs` (address, drive, complete access, the
    /// job's data), [`MAILBOXES_AT_ONCE`] devices at a time: their requests in flight together,
    /// each device's own exchange in order. One result per job, in the order of `jobs`; each
    /// device's mailbox counter continues as with [`with_coe`](Self::with_coe). `Err` when the
    /// exchanges as a whole failed (the link, the segment, `timeout` per group of devices).
    #[allow(clippy::type_complexity)]
    pub fn with_coe_each<X, T>(
        &mut self,
        jobs: Vec<(u16, DriveRef, bool, X)>,
        timeout: Duration,
        op: impl AsyncFn(&mut CoeClient<'_>, X) -> Result<T, CoeError>,
    ) -> Result<Vec<Result<T, CoeError>>, SessionError> {
        let mut results = Vec::with_capacity(jobs.len());
        let mut jobs = jobs.into_iter().peekable();
        while jobs.peek().is_some() {
            let chunk: Vec<(u16, DriveRef, bool, X)> =
                jobs.by_ref().take(MAILBOXES_AT_ONCE).collect();
            let addresses: Vec<u16> = chunk.iter().map(|j| j.0).collect();
            let names: Vec<String> = chunk.iter().map(|j| j.1.to_string()).collect();
            let what = || format!("{}: mailbox exchanges", names.join(", "));
            let (md, log, mbx_timeout) = (&self.md, &self.emergencies, self.opts.mailbox_timeout);
            let op = &op;
            let futs: Vec<std::pin::Pin<Box<dyn Future<Output = CoeRun<T>> + '_>>> = chunk
                .into_iter()
                .map(|(address, drive, complete_access, x)| {
                    let seq = self.mailbox_sequence(address);
                    let log = log.clone();
                    Box::pin(async move {
                        let c = CoeClient::new(md, address, drive, log).await;
                        let mut c = match c {
                            Ok(c) => c
                                .with_complete_access(complete_access)
                                .with_timeout(mbx_timeout)
                                .with_counter(seq.last)
                                .avoiding(seq.ethercrab_next),
                            Err(e) => return (Err(e), seq.last, None),
                        };
                        let sm0 = c.sms().out_start;
                        let r = op(&mut c, x).await;
                        (r, c.counter(), Some(sm0))
                    })
                        as std::pin::Pin<Box<dyn Future<Output = CoeRun<T>> + '_>>
                })
                .collect();
            let runs = exec::run(&mut self.pump, &what, timeout, exec::join_all(futs))
                .map_err(SessionError::Exec)?;
            for (address, (r, counter, sm0)) in addresses.into_iter().zip(runs) {
                if let Some(start) = sm0 {
                    self.pump.learn_mailbox(address, start);
                }
                self.counters.entry(address).or_default().last = counter;
                results.push(r);
            }
        }
        Ok(results)
    }

    /// Run `op` with a CoE client for the device at configured `address`. The client is
    /// created for the call (it reads the mailbox configuration) and records emergencies into
    /// the session's log.
    pub fn with_coe<T>(
        &mut self,
        address: u16,
        drive: DriveRef,
        complete_access: bool,
        timeout: Duration,
        op: impl AsyncFnOnce(&mut CoeClient<'_>) -> Result<T, CoeError>,
    ) -> Result<T, SessionError> {
        self.mailbox(address, drive, complete_access, false, timeout, op)
    }

    /// [`with_coe`](Self::with_coe) for a device this session did not discover (a tool that
    /// addresses a device as another session left it, in BOOT for instance): its mailbox's
    /// history is unknown, so the first request carries counter 0, which a device never takes
    /// for a repeat ([`CoeClient::with_unknown_history`]).
    pub fn with_mailbox_as_found<T>(
        &mut self,
        address: u16,
        drive: DriveRef,
        timeout: Duration,
        op: impl AsyncFnOnce(&mut CoeClient<'_>) -> Result<T, CoeError>,
    ) -> Result<T, SessionError> {
        self.mailbox(address, drive, false, true, timeout, op)
    }

    fn mailbox<T>(
        &mut self,
        address: u16,
        drive: DriveRef,
        complete_access: bool,
        unknown_history: bool,
        timeout: Duration,
        op: impl AsyncFnOnce(&mut CoeClient<'_>) -> Result<T, CoeError>,
    ) -> Result<T, SessionError> {
        let log = self.emergencies.clone();
        let mbx_timeout = self.opts.mailbox_timeout;
        let d = drive.clone();
        let what = || format!("{d}: mailbox exchange");
        let md = &self.md;
        let seq = self.mailbox_sequence(address);
        let mut counter = seq.last;
        let mut sm0 = None;
        let (counter_out, sm0_out) = (&mut counter, &mut sm0);
        let fut = async move {
            let mut c = CoeClient::new(md, address, drive, log)
                .await?
                .with_complete_access(complete_access)
                .with_timeout(mbx_timeout)
                .with_counter(seq.last)
                .avoiding(seq.ethercrab_next);
            if unknown_history {
                c = c.with_unknown_history();
            }
            *sm0_out = Some(c.sms().out_start);
            let r = op(&mut c).await;
            *counter_out = c.counter();
            r
        };
        let r = exec::run(&mut self.pump, &what, timeout, fut);
        if let Some(start) = sm0 {
            self.pump.learn_mailbox(address, start);
        }
        self.counters.entry(address).or_default().last = counter;
        match r {
            Ok(Ok(v)) => Ok(v),
            Ok(Err(e)) => Err(SessionError::Coe(e)),
            Err(e) => Err(SessionError::Exec(e)),
        }
    }
}

/// A failure of a supervisory operation.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The CoE exchange failed (names drive, object and reason).
    #[error(transparent)]
    Coe(#[from] CoeError),
    /// The bus did not answer in time, or the link failed.
    #[error(transparent)]
    Exec(#[from] ExecError),
}

impl From<SessionError> for MasterError {
    fn from(e: SessionError) -> Self {
        match e {
            SessionError::Coe(c) => {
                let kind = match c.abort_code() {
                    Some(code) => ErrorKind::Sdo(code),
                    None => match c.kind {
                        super::coe::CoeErrorKind::Timeout(_) => ErrorKind::Timeout,
                        super::coe::CoeErrorKind::Foe { .. } => ErrorKind::Refused,
                        _ => ErrorKind::Bus,
                    },
                };
                MasterError {
                    drive: Some(c.drive.clone()),
                    step: match c.address {
                        Some(a) => format!("{a}"),
                        None => "mailbox".into(),
                    },
                    reason: c.kind.to_string(),
                    kind,
                }
            }
            SessionError::Exec(x) => exec::exec_error(None, x),
        }
    }
}
