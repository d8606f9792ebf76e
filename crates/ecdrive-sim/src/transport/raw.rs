//! Serve a segment on a raw socket.

use super::held::HeldReplies;
use super::lock;
use crate::ec::frame::MAX_FRAME_LEN;
use crate::link::{LinkError, RawSocket};
use crate::segment::{Segment, SegmentError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

/// Longest receive wait, so that `stop` is noticed and SYNC0 events and watchdogs run while
/// no frames arrive (a pulled cable).
const MAX_WAIT: Duration = Duration::from_millis(10);

/// Counters of [`serve`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct ServeStats {
    /// Frames answered (including late ones).
    pub frames: u64,
    /// Frames received but not answered (malformed, not EtherCAT, too large), and delayed
    /// replies that found no free buffer to wait in.
    pub dropped: u64,
    /// Frames not answered because of an injected link fault (dropped, cable pulled).
    pub lost: u64,
    /// Replies sent late because of an injected delay.
    pub delayed: u64,
    /// Times the interface went down (a real line keeps its slaves powered: they go on, see
    /// no frames, and answer again once it is back up).
    pub link_down: u64,
}

/// SCHED_FIFO priority of a [`RawServer`] thread (a master's cycle thread defaults to 80).
pub const SERVE_PRIORITY: u8 = 70;

/// Delayed replies held at once at most.
const HELD: usize = 64;

/// Answer EtherCAT frames arriving on `socket` with `segment` until `stop` is set. Between
/// frames (at most every 10 ms, or at the next SYNC0 deadline or delayed reply) it polls the
/// segment so that SYNC0 events, watchdogs and injected faults are processed while the master
/// is silent (or the cable is pulled). Replies delayed by an injected fault are held and sent
/// when due. The receive buffer and the buffers of delayed replies are allocated up front.
pub fn serve(
    socket: &RawSocket,
    segment: &Mutex<Segment>,
    stop: &AtomicBool,
) -> Result<ServeStats, LinkError> {
    let mut stats = ServeStats::default();
    let mut buf = vec![0u8; socket.max_frame_len().max(MAX_FRAME_LEN)];
    let mut held = HeldReplies::new(HELD);
    let mut down = false;
    // While the interface is down: no frames, the slaves run on their own clock.
    let link_down = |down: &mut bool, stats: &mut ServeStats, timeout: Duration| {
        if !*down {
            *down = true;
            stats.link_down += 1;
            tracing::warn!("the interface is down; serving again once it is up");
        }
        std::thread::sleep(timeout.min(Duration::from_millis(10)));
        lock(segment).poll();
    };
    while !stop.load(Ordering::Acquire) {
        let (now, deadline) = {
            let seg = lock(segment);
            (seg.clock().now_ns(), seg.next_deadline())
        };
        while let Some(f) = held.pop_due(now) {
            match socket.send(f) {
                Ok(()) => stats.frames += 1,
                Err(LinkError::InterfaceDown { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        let next = match (deadline, held.next_due()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let timeout = next
            .map(|d| Duration::from_nanos(d.saturating_sub(now)).min(MAX_WAIT))
            .unwrap_or(MAX_WAIT);
        match socket.recv(&mut buf, Some(timeout)) {
            Ok(Some(n)) => {
                down = false;
                let Some(frame) = buf.get_mut(..n) else {
                    continue;
                };
                let reply = lock(segment).process_frame(frame);
                match reply {
                    Ok(r) => {
                        let Some(f) = buf.get(..r.len) else {
                            continue;
                        };
                        if r.delay_ns == 0 {
                            match socket.send(f) {
                                Ok(()) => {
                                    down = false;
                                    stats.frames += 1;
                                }
                                Err(LinkError::InterfaceDown { .. }) => {
                                    link_down(&mut down, &mut stats, timeout)
                                }
                                Err(e) => return Err(e),
                            }
                        } else if held.push(f, r.due_ns) {
                            stats.delayed += 1;
                        } else {
                            stats.dropped += 1;
                        }
                    }
                    Err(SegmentError::Lost { .. } | SegmentError::Disconnected) => stats.lost += 1,
                    Err(_) => stats.dropped += 1,
                }
            }
            Ok(None) => lock(segment).poll(),
            Err(LinkError::Truncated { .. }) => stats.dropped += 1,
            Err(LinkError::InterfaceDown { .. }) => link_down(&mut down, &mut stats, timeout),
            Err(e) => return Err(e),
        }
    }
    Ok(stats)
}

struct Shared {
    segment: Mutex<Segment>,
    stop: AtomicBool,
}

/// A thread serving a segment on a raw socket ([`serve`]).
pub struct RawServer {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Result<ServeStats, LinkError>>>,
    interface: String,
}

impl core::fmt::Debug for RawServer {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RawServer")
            .field("interface", &self.interface)
            .finish_non_exhaustive()
    }
}

impl RawServer {
    /// Serve `segment` on `socket` from a new thread.
    pub fn spawn(socket: RawSocket, segment: Segment) -> std::io::Result<Self> {
        let shared = Arc::new(Shared {
            segment: Mutex::new(segment),
            stop: AtomicBool::new(false),
        });
        let interface = socket.interface().to_owned();
        let s = shared.clone();
        let thread = std::thread::Builder::new()
            .name(format!("ecdrive-sim {interface}"))
            .spawn(move || {
                // The emulated slave controller answers in hardware time on a real segment:
                // serve at real-time priority (just below a master's default cycle thread)
                // when the process may, so the scheduler does not turn a loaded machine into
                // lost frames. Without the privilege it serves at normal priority.
                let _ = crate::rt::RtSettings {
                    priority: Some(SERVE_PRIORITY),
                    cpu: None,
                    lock_memory: false,
                }
                .apply_to_current_thread();
                serve(&socket, &s.segment, &s.stop)
            })?;
        Ok(Self {
            shared,
            thread: Some(thread),
            interface,
        })
    }

    /// The interface served.
    pub fn interface(&self) -> &str {
        &self.interface
    }

    /// Lock the segment (e.g. to inspect a device). Frames wait while the guard is held.
    pub fn segment(&self) -> MutexGuard<'_, Segment> {
        lock(&self.shared.segment)
    }

    /// Whether the serving thread has ended (an I/O error).
    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().is_none_or(|t| t.is_finished())
    }

    /// Stop serving; returns the segment and what the thread reported.
    pub fn stop(mut self) -> (Segment, Result<ServeStats, LinkError>) {
        let result = self.halt();
        let shared = Arc::clone(&self.shared);
        drop(self);
        let segment = match Arc::try_unwrap(shared) {
            Ok(s) => s.segment.into_inner().unwrap_or_else(|e| e.into_inner()),
            Err(s) => {
                let clock = lock(&s.segment).clock().clone();
                Segment::new(clock)
            }
        };
        (segment, result)
    }

    fn halt(&mut self) -> Result<ServeStats, LinkError> {
        self.shared.stop.store(true, Ordering::Release);
        match self.thread.take() {
            Some(t) => t.join().unwrap_or_else(|_| {
                Err(LinkError::Peer(format!(
                    "the thread serving {} panicked",
                    self.interface
                )))
            }),
            None => Ok(ServeStats::default()),
        }
    }
}

impl Drop for RawServer {
    fn drop(&mut self) {
        let _ = self.halt();
    }
}
