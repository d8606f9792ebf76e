//! A small executor that runs ethercrab futures while pumping their frames.
//!
//! [`run`] is for start-up and supervisory work: it polls the future, sends what ethercrab
//! queued, waits for replies (or for a wake-up from ethercrab's internal timers), retransmits and
//! finally gives up on lost frames, and enforces an overall deadline by dropping the future.
//! [`exchange`] is the cycle's allocation-free variant: it polls a future with a no-op waker and
//! pumps inline until the future completes or the cycle's deadline passes.

use super::error::{DriveRef, ErrorKind, MasterError};
use super::io::{FrameLink, LinkError, Pump};
use crate::rt::monotonic_ns;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::task::{Context, Poll, Wake, Waker};
use std::thread::Thread;
use std::time::Duration;

/// Why a future run by the executor did not complete.
#[derive(Debug, thiserror::Error)]
pub enum ExecError {
    /// The overall deadline passed.
    #[error("{what}: no result within {timeout_ms} ms")]
    Timeout {
        /// What was being done.
        what: String,
        /// The deadline that passed, in ms.
        timeout_ms: u64,
    },
    /// A frame got no reply after all retransmissions: the segment did not answer.
    #[error("{what}: the segment did not answer ({lost} frame(s) lost after retries)")]
    FrameLost {
        /// What was being done.
        what: String,
        /// Frames lost.
        lost: usize,
    },
    /// The link failed.
    #[error("{what}: {source}")]
    Link {
        /// What was being done.
        what: String,
        /// The link error.
        source: LinkError,
    },
}

struct ThreadWaker {
    thread: Thread,
    notified: AtomicBool,
}

impl Wake for ThreadWaker {
    fn wake(self: Arc<Self>) {
        self.wake_by_ref();
    }

    fn wake_by_ref(self: &Arc<Self>) {
        self.notified.store(true, Ordering::Release);
        self.thread.unpark();
    }
}

/// How long the executor parks while waiting for something that is not a frame (ethercrab's
/// internal poll loops).
const PARK_SLICE_NS: u64 = 200_000;

/// Run every future of `futs` to completion, polling each that is not done whenever the
/// joined future is polled; the outputs in the order of `futs`. For start-up work over several
/// devices at once (their mailboxes), not for the cycle.
pub async fn join_all<'a, T>(futs: Vec<std::pin::Pin<Box<dyn Future<Output = T> + 'a>>>) -> Vec<T> {
    let mut pending: Vec<Option<std::pin::Pin<Box<dyn Future<Output = T> + 'a>>>> =
        futs.into_iter().map(Some).collect();
    let mut out: Vec<Option<T>> = pending.iter().map(|_| None).collect();
    std::future::poll_fn(|cx| {
        let mut all = true;
        for (slot, done) in pending.iter_mut().zip(out.iter_mut()) {
            if let Some(f) = slot {
                match f.as_mut().poll(cx) {
                    Poll::Ready(v) => {
                        *done = Some(v);
                        *slot = None;
                    }
                    Poll::Pending => all = false,
                }
            }
        }
        if all { Poll::Ready(()) } else { Poll::Pending }
    })
    .await;
    out.into_iter().flatten().collect()
}

/// Run `fut` to completion while pumping its frames, within `timeout`. `what` names the step for
/// error messages ("reading the SII of drive 1 (MR-J4-TM)").
pub fn run<L: FrameLink, F: Future>(
    pump: &mut Pump<'_, L>,
    what: &dyn Fn() -> String,
    timeout: Duration,
    fut: F,
) -> Result<F::Output, ExecError> {
    let deadline = monotonic_ns().saturating_add(timeout.as_nanos() as u64);
    let tw = Arc::new(ThreadWaker {
        thread: std::thread::current(),
        notified: AtomicBool::new(false),
    });
    let waker = Waker::from(tw.clone());
    let mut cx = Context::from_waker(&waker);
    pump.register_waker(&waker);
    // The future lives in this block: leaving it drops the future (releasing, if it did not
    // complete, its frames in ethercrab) before the pump forgets them below. It is boxed:
    // start-up futures hold ethercrab's group (tens of KiB), and this is not the cyclic path.
    let result = {
        let mut fut = Box::pin(fut);
        loop {
            tw.notified.store(false, Ordering::Release);
            if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
                break Ok(v);
            }
            let link_err = |source| ExecError::Link {
                what: what(),
                source,
            };
            if let Err(e) = pump.send_pending() {
                break Err(link_err(e));
            }
            let now = monotonic_ns();
            if now >= deadline {
                break Err(ExecError::Timeout {
                    what: what(),
                    timeout_ms: timeout.as_millis() as u64,
                });
            }
            if pump.outstanding() > 0 {
                let until = deadline.min(now + pump.policy().frame_timeout_ns / 4 + 1);
                if let Err(e) = pump.receive_until(until) {
                    break Err(link_err(e));
                }
                match pump.check_timeouts() {
                    Ok(0) => {}
                    Ok(lost) => {
                        break Err(ExecError::FrameLost { what: what(), lost });
                    }
                    Err(e) => break Err(link_err(e)),
                }
            } else if !tw.notified.load(Ordering::Acquire) {
                let slice = PARK_SLICE_NS.min(deadline.saturating_sub(now));
                std::thread::park_timeout(Duration::from_nanos(slice));
            }
        }
    };
    // Forget the dropped future's frames so late replies count as stale and are not handed to a
    // reused slot.
    if result.is_err() {
        pump.clear_all();
    } else {
        pump.clear_lost();
    }
    pump.register_waker(Waker::noop());
    result
}

/// Run `fut` on the calling thread while **another** thread pumps the frames (the cycle
/// thread, during OP): poll, park until woken or a short slice passes, repeat, within
/// `timeout`. For supervisory work during the cycle (mailbox polling for emergencies, SDOs).
pub fn run_remote<F: Future>(
    what: &dyn Fn() -> String,
    timeout: Duration,
    fut: F,
) -> Result<F::Output, ExecError> {
    run_remote_unless(what, timeout, fut, &|| false)
}

/// [`run_remote`], given up (as a timeout) as soon as `abort` says so: the pumping thread has
/// ended, say, and no reply can come.
pub fn run_remote_unless<F: Future>(
    what: &dyn Fn() -> String,
    timeout: Duration,
    fut: F,
    abort: &dyn Fn() -> bool,
) -> Result<F::Output, ExecError> {
    let deadline = monotonic_ns().saturating_add(timeout.as_nanos() as u64);
    let tw = Arc::new(ThreadWaker {
        thread: std::thread::current(),
        notified: AtomicBool::new(false),
    });
    let waker = Waker::from(tw.clone());
    let mut cx = Context::from_waker(&waker);
    let mut fut = Box::pin(fut);
    loop {
        tw.notified.store(false, Ordering::Release);
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return Ok(v);
        }
        let now = monotonic_ns();
        if now >= deadline || abort() {
            return Err(ExecError::Timeout {
                what: what(),
                timeout_ms: timeout.as_millis() as u64,
            });
        }
        if !tw.notified.load(Ordering::Acquire) {
            std::thread::park_timeout(Duration::from_nanos(
                (1_000_000u64).min(deadline.saturating_sub(now)),
            ));
        }
    }
}

/// How one cyclic exchange ended, when it did not complete.
#[derive(Debug, thiserror::Error)]
pub enum ExchangeError {
    /// The reply did not arrive before the cycle's deadline. The future was dropped and its
    /// frame released; a reply arriving later is discarded as stale.
    #[error("no reply before the cycle deadline")]
    Late,
    /// The link failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

/// Complete one cyclic exchange: poll `fut` (e.g. `group.tx_rx_dc(&md)`), send its frame,
/// receive the reply, poll again, until the deadline. Allocation-free; the only syscalls are the
/// link's.
pub fn exchange<L: FrameLink, F: Future>(
    pump: &mut Pump<'_, L>,
    mut fut: Pin<&mut F>,
    deadline_ns: u64,
) -> Result<F::Output, ExchangeError> {
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return Ok(v);
        }
        pump.send_pending()?;
        if pump.outstanding() > 0 {
            pump.receive_until(deadline_ns)?;
        }
        if monotonic_ns() >= deadline_ns {
            // One last poll: the reply may have arrived exactly at the deadline.
            if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
                return Ok(v);
            }
            pump.clear_all();
            return Err(ExchangeError::Late);
        }
    }
}

/// Start one cyclic exchange without waiting for it: poll `fut` once (it queues its frame)
/// and send what is queued. `Some` when the future completed at once (it could not queue its
/// frame); otherwise finish it later with [`exchange`]. Allocation-free.
pub fn start<L: FrameLink, F: Future>(
    pump: &mut Pump<'_, L>,
    fut: Pin<&mut F>,
) -> Result<Option<F::Output>, ExchangeError> {
    let mut cx = Context::from_waker(Waker::noop());
    if let Poll::Ready(v) = fut.poll(&mut cx) {
        return Ok(Some(v));
    }
    pump.send_pending()?;
    Ok(None)
}

/// Convert an executor error, with the drive it concerned.
pub fn exec_error(drive: Option<&DriveRef>, e: ExecError) -> MasterError {
    let (step, kind, reason) = match e {
        ExecError::Timeout { what, timeout_ms } => (
            what,
            ErrorKind::Timeout,
            format!("no result within {timeout_ms} ms"),
        ),
        ExecError::FrameLost { what, lost } => (
            what,
            ErrorKind::Timeout,
            format!("the segment did not answer ({lost} frame(s) lost after retries)"),
        ),
        ExecError::Link { what, source } => (what, ErrorKind::Link, source.to_string()),
    };
    MasterError::new(drive, step, kind, reason)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{LossPolicy, MAX_FRAME};
    use ethercrab::{Command, MainDevice, MainDeviceConfig, PduStorage, Timeouts};
    use std::collections::VecDeque;
    use std::pin::pin;

    /// A poll whose answer can no longer come (the pumping thread ended) is given up at once,
    /// whatever its timeout: the session must not wait for it.
    #[test]
    fn run_remote_unless_gives_up_when_told() {
        let r = run_remote_unless(
            &|| "polling".into(),
            Duration::from_secs(3600),
            std::future::pending::<()>(),
            &|| true,
        );
        assert!(matches!(r, Err(ExecError::Timeout { .. })), "{r:?}");
    }

    /// A link whose "segment" is two slaves that answer every BRD by OR-ing 0x11 into the data
    /// and adding 2 to the working counter. It can swallow frames to simulate loss.
    struct FakeLink {
        replies: VecDeque<Vec<u8>>,
        swallow: usize,
        held: Option<Vec<u8>>,
        hold_next: bool,
    }

    impl FakeLink {
        fn new() -> Self {
            Self {
                replies: VecDeque::new(),
                swallow: 0,
                held: None,
                hold_next: false,
            }
        }
    }

    impl FrameLink for FakeLink {
        fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
            if self.swallow > 0 {
                self.swallow -= 1;
                return Ok(());
            }
            let mut f = frame.to_vec();
            f[6] |= 0x02; // locally administered source MAC, as a real ESC sets it
            // First datagram: header at 16, data at 26.
            let len = (u16::from_le_bytes([f[22], f[23]]) & 0x07FF) as usize;
            if f[16] == 7 {
                f[26] |= 0x11;
                let w = 26 + len;
                let wkc = u16::from_le_bytes([f[w], f[w + 1]]) + 2;
                f[w..w + 2].copy_from_slice(&wkc.to_le_bytes());
            }
            if self.hold_next {
                self.hold_next = false;
                self.held = Some(f);
            } else {
                self.replies.push_back(f);
            }
            Ok(())
        }

        fn recv(
            &mut self,
            buf: &mut [u8],
            timeout: Option<Duration>,
        ) -> Result<Option<usize>, LinkError> {
            match self.replies.pop_front() {
                Some(f) => {
                    buf[..f.len()].copy_from_slice(&f);
                    Ok(Some(f.len()))
                }
                None => {
                    let wait = timeout
                        .unwrap_or(Duration::from_millis(1))
                        .min(Duration::from_micros(100));
                    std::thread::sleep(wait);
                    Ok(None)
                }
            }
        }
    }

    type Storage = PduStorage<8, { PduStorage::element_size(MAX_FRAME) }>;

    fn timeouts() -> Timeouts {
        Timeouts {
            pdu: Duration::MAX,
            ..Timeouts::default()
        }
    }

    const POLICY: LossPolicy = LossPolicy {
        frame_timeout_ns: 2_000_000,
        retries: 2,
    };

    #[test]
    fn run_completes_a_read_through_the_pump() {
        let storage = Box::new(Storage::new());
        let (tx, rx, pl) = storage.try_split().unwrap();
        let md = MainDevice::new(pl, timeouts(), MainDeviceConfig::default());
        let mut pump = Pump::new(tx, rx, FakeLink::new(), POLICY);
        let v: u8 = run(&mut pump, &|| "BRD".into(), Duration::from_secs(1), async {
            Command::brd(0).with_wkc(2).receive::<u8>(&md).await
        })
        .unwrap()
        .unwrap();
        assert_eq!(v, 0x11);
        assert_eq!(pump.stats().sent, 1);
        assert_eq!(pump.stats().received, 1);
    }

    #[test]
    fn a_swallowed_frame_is_retransmitted() {
        let storage = Box::new(Storage::new());
        let (tx, rx, pl) = storage.try_split().unwrap();
        let md = MainDevice::new(pl, timeouts(), MainDeviceConfig::default());
        let mut link = FakeLink::new();
        link.swallow = 1;
        let mut pump = Pump::new(tx, rx, link, POLICY);
        let v: u8 = run(&mut pump, &|| "BRD".into(), Duration::from_secs(2), async {
            Command::brd(0).with_wkc(2).receive::<u8>(&md).await
        })
        .unwrap()
        .unwrap();
        assert_eq!(v, 0x11);
        assert_eq!(pump.stats().retransmitted, 1);
        assert_eq!(pump.stats().lost, 0);
    }

    #[test]
    fn a_dead_segment_is_reported_as_lost_and_the_slot_is_reusable() {
        let storage = Box::new(Storage::new());
        let (tx, rx, pl) = storage.try_split().unwrap();
        let md = MainDevice::new(pl, timeouts(), MainDeviceConfig::default());
        let mut link = FakeLink::new();
        link.swallow = 3; // first transmission + 2 retries
        let mut pump = Pump::new(tx, rx, link, POLICY);
        let err = run(
            &mut pump,
            &|| "counting slaves".into(),
            Duration::from_secs(2),
            async { Command::brd(0).with_wkc(2).receive::<u8>(&md).await },
        )
        .unwrap_err();
        assert!(matches!(err, ExecError::FrameLost { lost: 1, .. }), "{err}");
        assert!(
            err.to_string()
                .starts_with("counting slaves: the segment did not answer")
        );
        // Every storage slot is free again: more reads than slots succeed.
        for _ in 0..20 {
            let v: u8 = run(&mut pump, &|| "BRD".into(), Duration::from_secs(1), async {
                Command::brd(0).with_wkc(2).receive::<u8>(&md).await
            })
            .unwrap()
            .unwrap();
            assert_eq!(v, 0x11);
        }
    }

    #[test]
    fn a_late_cycle_reply_is_discarded_as_stale() {
        let storage = Box::new(Storage::new());
        let (tx, rx, pl) = storage.try_split().unwrap();
        let md = MainDevice::new(pl, timeouts(), MainDeviceConfig::default());
        let mut link = FakeLink::new();
        link.hold_next = true;
        let mut pump = Pump::new(tx, rx, link, POLICY);
        {
            let fut = pin!(Command::brd(0).with_wkc(2).receive::<u8>(&md));
            let r = exchange(&mut pump, fut, monotonic_ns() + 1_000_000);
            assert!(matches!(r.unwrap_err(), ExchangeError::Late));
        }
        // The held reply now arrives, after the future was dropped.
        let held = pump.link_mut().held.take().unwrap();
        pump.link_mut().replies.push_back(held);
        let fut = pin!(Command::brd(0).with_wkc(2).receive::<u8>(&md));
        let v = exchange(&mut pump, fut, monotonic_ns() + 1_000_000_000)
            .unwrap()
            .unwrap();
        assert_eq!(v, 0x11);
        assert_eq!(pump.stats().stale, 1);
    }
}
