//! Serve a segment to an ethercrab `MainDevice` in the same process, through its `PduTx` /
//! `PduRx` halves: no network, no root.

use super::held::HeldReplies;
use super::lock;
use crate::clock::Clock;
use crate::segment::{Segment, SegmentError};
use ethercrab::{PduRx, PduTx};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::task::{Wake, Waker};
use std::thread::{self, JoinHandle, Thread};
use std::time::Duration;

/// Longest the pump thread sleeps without a wake-up (it still delivers SYNC0 events and notices
/// watchdog expiry while the master is silent).
const IDLE_PARK: Duration = Duration::from_millis(5);

struct Shared {
    segment: Mutex<Segment>,
    stop: AtomicBool,
    frames: AtomicU64,
    dropped: AtomicU64,
    lost: AtomicU64,
}

/// When the pump thread wakes up other than for a frame from the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wakeups {
    /// At each of the segment's deadlines (SYNC0 pulses, watchdog expiry) as well: the
    /// slaves' time-driven work happens on time even while the master is silent.
    #[default]
    Deadlines,
    /// Only for frames (and replies held back by an injected delay): the slaves' time-driven
    /// work is done when the next frame arrives, as [`super::SegmentLink`] does it on the
    /// master's own thread. An idle master is still noticed every 5 ms. The jitter harness
    /// uses this, so that the in-process baseline wakes no more often than ecdrive's cycle.
    FramesOnly,
}

struct Unpark(Thread);

impl Wake for Unpark {
    fn wake(self: Arc<Self>) {
        self.0.unpark();
    }

    fn wake_by_ref(self: &Arc<Self>) {
        self.0.unpark();
    }
}

/// A thread moving frames between ethercrab's `PduTx`/`PduRx` and a [`Segment`]. The thread
/// sleeps until ethercrab queues a frame (it registers itself as the TX waker), processes every
/// sendable frame through the segment and hands the replies to `PduRx`.
///
/// ```no_run
/// # use ecdrive_sim::{Segment, HostClock, devices::IoDevice, transport::EthercrabLink};
/// # use std::sync::Arc;
/// use ethercrab::PduStorage;
/// static STORAGE: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();
/// let (tx, rx, pdu_loop) = STORAGE.try_split().unwrap();
/// let mut segment = Segment::new(Arc::new(HostClock));
/// segment.push_device(Box::new(IoDevice::new(2, 4))).unwrap();
/// let link = EthercrabLink::spawn(segment, tx, rx).unwrap();
/// // … MainDevice::new(pdu_loop, …), init, OP, tx_rx …
/// let segment = link.stop();
/// ```
pub struct EthercrabLink {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl core::fmt::Debug for EthercrabLink {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EthercrabLink")
            .field("frames", &self.frames())
            .finish_non_exhaustive()
    }
}

impl EthercrabLink {
    /// Start serving `segment` to the master owning `tx`/`rx`.
    pub fn spawn(
        segment: Segment,
        tx: PduTx<'static>,
        rx: PduRx<'static>,
    ) -> std::io::Result<Self> {
        Self::spawn_with(segment, tx, rx, || {})
    }

    /// Like [`spawn`](Self::spawn), running `on_start` first on the new thread (e.g. to give
    /// it a real-time priority, or to note its CPU clock for measurements).
    pub fn spawn_with(
        segment: Segment,
        tx: PduTx<'static>,
        rx: PduRx<'static>,
        on_start: impl FnOnce() + Send + 'static,
    ) -> std::io::Result<Self> {
        Self::spawn_configured(segment, tx, rx, Wakeups::Deadlines, on_start)
    }

    /// Like [`spawn_with`](Self::spawn_with), waking as `wakeups` says.
    pub fn spawn_configured(
        segment: Segment,
        tx: PduTx<'static>,
        rx: PduRx<'static>,
        wakeups: Wakeups,
        on_start: impl FnOnce() + Send + 'static,
    ) -> std::io::Result<Self> {
        let shared = Arc::new(Shared {
            segment: Mutex::new(segment),
            stop: AtomicBool::new(false),
            frames: AtomicU64::new(0),
            dropped: AtomicU64::new(0),
            lost: AtomicU64::new(0),
        });
        let s = shared.clone();
        let thread = thread::Builder::new()
            .name("ecdrive-sim-ethercrab".into())
            .spawn(move || {
                on_start();
                pump(&s, tx, rx, wakeups)
            })?;
        Ok(Self {
            shared,
            thread: Some(thread),
        })
    }

    /// Lock the segment (e.g. to inspect a device). Frames wait while the guard is held.
    pub fn segment(&self) -> MutexGuard<'_, Segment> {
        lock(&self.shared.segment)
    }

    /// Frames answered so far (including late ones).
    pub fn frames(&self) -> u64 {
        self.shared.frames.load(Ordering::Relaxed)
    }

    /// Frames the segment dropped (malformed) or ethercrab refused (e.g. after a timeout).
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }

    /// Frames not answered because of an injected link fault (dropped, cable pulled).
    pub fn lost(&self) -> u64 {
        self.shared.lost.load(Ordering::Relaxed)
    }

    /// Stop the thread and give the segment back.
    pub fn stop(mut self) -> Segment {
        self.halt();
        let shared = Arc::clone(&self.shared);
        drop(self);
        match Arc::try_unwrap(shared) {
            Ok(s) => s.segment.into_inner().unwrap_or_else(|e| e.into_inner()),
            // The thread has exited, so this cannot happen; keep an empty segment rather
            // than panicking.
            Err(s) => {
                let clock = lock(&s.segment).clock().clone();
                Segment::new(clock)
            }
        }
    }

    fn halt(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

impl Drop for EthercrabLink {
    fn drop(&mut self) {
        self.halt();
    }
}

/// Delayed replies held at once at most.
const HELD: usize = 32;

fn pump(shared: &Shared, mut tx: PduTx<'static>, mut rx: PduRx<'static>, wakeups: Wakeups) {
    let waker = Waker::from(Arc::new(Unpark(thread::current())));
    let mut buf: Vec<u8> = vec![0; 2048];
    let mut held = HeldReplies::new(HELD);
    let clock = lock(&shared.segment).clock().clone();
    loop {
        if shared.stop.load(Ordering::Acquire) || tx.should_exit() {
            break;
        }
        tx.replace_waker(&waker);
        // Delayed replies whose time has come (a stale one is refused by ethercrab and counted
        // as dropped).
        while let Some(f) = held.pop_due(clock.now_ns()) {
            if rx.receive_frame(f).is_ok() {
                shared.frames.fetch_add(1, Ordering::Relaxed);
            } else {
                shared.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
        let mut any = false;
        while let Some(frame) = tx.next_sendable_frame() {
            any = true;
            let mut len = 0;
            let sent = frame.send_blocking(|bytes| {
                if bytes.len() > buf.len() {
                    // Grows once to the largest frame ethercrab's storage can produce.
                    buf.resize(bytes.len(), 0);
                }
                if let Some(dst) = buf.get_mut(..bytes.len()) {
                    dst.copy_from_slice(bytes);
                }
                len = bytes.len();
                Ok(bytes.len())
            });
            if sent.is_err() {
                shared.dropped.fetch_add(1, Ordering::Relaxed);
                continue;
            }
            let Some(frame) = buf.get_mut(..len) else {
                continue;
            };
            let reply = lock(&shared.segment).process_frame(frame);
            match reply {
                Ok(r) if r.delay_ns > 0 => {
                    let ok = buf.get(..r.len).is_some_and(|f| held.push(f, r.due_ns));
                    if !ok {
                        shared.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Ok(r) => {
                    shared.frames.fetch_add(1, Ordering::Relaxed);
                    let ok = buf
                        .get(..r.len)
                        .map(|f| rx.receive_frame(f).is_ok())
                        .unwrap_or(false);
                    if !ok {
                        shared.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Err(SegmentError::Lost { .. } | SegmentError::Disconnected) => {
                    shared.lost.fetch_add(1, Ordering::Relaxed);
                }
                Err(_) => {
                    shared.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
        if !any {
            let timeout = {
                let mut seg = lock(&shared.segment);
                seg.poll();
                let now = seg.clock().now_ns();
                let deadline = match wakeups {
                    Wakeups::Deadlines => seg.next_deadline(),
                    Wakeups::FramesOnly => None,
                };
                let next = match (deadline, held.next_due()) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
                next.map(|d| Duration::from_nanos(d.saturating_sub(now)).min(IDLE_PARK))
                    .unwrap_or(IDLE_PARK)
            };
            thread::park_timeout(timeout);
        }
    }
}
