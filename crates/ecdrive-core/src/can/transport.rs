//! The CAN transport trait and the in-process virtual bus.
//!
//! A [`CanTransport`] sends and receives classic CAN frames and tells the time. Time belongs to
//! the transport so that a simulated bus can run on simulated time: the master never reads a
//! clock of its own, which makes every SYNC, heartbeat, guarding and SDO-rate rule testable
//! without sleeping (the software slave's simulated CAN bus advances its clock while the master
//! waits). Real transports (the CANopen master's SocketCAN and Unix-socket transports, and
//! [`VirtualPort`]) use `CLOCK_MONOTONIC`.
//!
//! The bus model: every frame a port sends reaches every *other* port, in order (a CAN bus has
//! no addressing, only identifiers). [`Hub`] is that model with one bounded receive queue per
//! port and no locks or threads; [`VirtualBus`] shares a hub between threads.

use super::frame::CanFrame;
use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::time::Duration;

/// What a transport can fail with.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// An operating-system error on the interface.
    #[error("{interface}: {op}: {source}")]
    Io {
        /// The interface or socket.
        interface: String,
        /// What was being done.
        op: &'static str,
        /// The error.
        source: std::io::Error,
    },
    /// The other end is gone (virtual bus dropped, hub stopped).
    #[error("{0}: the bus is closed")]
    Closed(String),
    /// The transport cannot carry this frame.
    #[error("{interface}: {what}")]
    Unsupported {
        /// The interface.
        interface: String,
        /// What.
        what: String,
    },
}

/// A CAN interface: send, receive with a timeout, and the time.
pub trait CanTransport {
    /// The interface name for messages (`can0`, `virtual`, …).
    fn name(&self) -> &str;
    /// Monotonic time of this transport, in microseconds.
    fn now_us(&self) -> u64;
    /// Queue one frame for transmission.
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError>;
    /// Wait at most `timeout_us` for a frame (0 = do not wait). `Ok(None)` on timeout.
    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError>;
    /// As [`CanTransport::recv`], with the time the frame was on the bus (this transport's
    /// clock): a transport that knows when it was sent says so (a frame that waited in a
    /// socket keeps its time, as on a CAN bus, where frames cannot bunch); by default the time
    /// it is received.
    fn recv_stamped(&mut self, timeout_us: u64) -> Result<Option<(CanFrame, u64)>, TransportError> {
        Ok(self.recv(timeout_us)?.map(|f| (f, self.now_us())))
    }
}

impl<T: CanTransport + ?Sized> CanTransport for Box<T> {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn now_us(&self) -> u64 {
        (**self).now_us()
    }
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        (**self).send(frame)
    }
    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        (**self).recv(timeout_us)
    }
    fn recv_stamped(&mut self, timeout_us: u64) -> Result<Option<(CanFrame, u64)>, TransportError> {
        (**self).recv_stamped(timeout_us)
    }
}

impl<T: CanTransport + ?Sized> CanTransport for &mut T {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn now_us(&self) -> u64 {
        (**self).now_us()
    }
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        (**self).send(frame)
    }
    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        (**self).recv(timeout_us)
    }
    fn recv_stamped(&mut self, timeout_us: u64) -> Result<Option<(CanFrame, u64)>, TransportError> {
        (**self).recv_stamped(timeout_us)
    }
}

/// `CLOCK_MONOTONIC` in microseconds: the clock of the real transports.
pub fn monotonic_us() -> u64 {
    crate::rt::monotonic_ns() / 1000
}

/// **\[REC\]** Frames a virtual port queues before it drops (like a CAN controller's receive
/// FIFO overrunning). Large enough for a second of traffic at 1 Mbit/s from a few nodes.
pub const DEFAULT_QUEUE_FRAMES: usize = 4096;

/// Identifies a port of a [`Hub`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PortId(pub usize);

/// The bus model: one bounded receive queue per port; a frame sent by one port is appended to
/// every other port's queue. Deterministic, no locks, no threads.
#[derive(Debug, Clone)]
pub struct Hub {
    queues: Vec<Option<VecDeque<CanFrame>>>,
    capacity: usize,
    dropped: Vec<u64>,
    sent: u64,
}

impl Default for Hub {
    fn default() -> Self {
        Self::new(DEFAULT_QUEUE_FRAMES)
    }
}

impl Hub {
    /// A hub whose ports queue at most `capacity` frames (at least 1).
    pub fn new(capacity: usize) -> Self {
        Self {
            queues: Vec::new(),
            capacity: capacity.max(1),
            dropped: Vec::new(),
            sent: 0,
        }
    }

    /// Attach a new port.
    pub fn attach(&mut self) -> PortId {
        let id = PortId(self.queues.len());
        self.queues.push(Some(VecDeque::with_capacity(64)));
        self.dropped.push(0);
        id
    }

    /// Detach a port: it receives nothing more and its queue is dropped.
    pub fn detach(&mut self, port: PortId) {
        if let Some(q) = self.queues.get_mut(port.0) {
            *q = None;
        }
    }

    /// Put `frame` on the bus from `from`: every other attached port receives it.
    pub fn send(&mut self, from: PortId, frame: &CanFrame) {
        self.sent = self.sent.wrapping_add(1);
        for (i, q) in self.queues.iter_mut().enumerate() {
            if i == from.0 {
                continue;
            }
            if let Some(q) = q {
                if q.len() >= self.capacity {
                    if let Some(d) = self.dropped.get_mut(i) {
                        *d = d.saturating_add(1);
                    }
                } else {
                    q.push_back(*frame);
                }
            }
        }
    }

    /// The next frame for `port`.
    pub fn recv(&mut self, port: PortId) -> Option<CanFrame> {
        self.queues.get_mut(port.0)?.as_mut()?.pop_front()
    }

    /// Whether `port` has a frame waiting.
    pub fn pending(&self, port: PortId) -> bool {
        self.queues
            .get(port.0)
            .and_then(Option::as_ref)
            .is_some_and(|q| !q.is_empty())
    }

    /// Frames dropped at `port` because its queue was full.
    pub fn dropped(&self, port: PortId) -> u64 {
        self.dropped.get(port.0).copied().unwrap_or(0)
    }

    /// Frames sent on the bus so far.
    pub fn frames_sent(&self) -> u64 {
        self.sent
    }
}

#[derive(Debug)]
struct Shared {
    hub: Mutex<Hub>,
    arrived: Condvar,
}

/// A [`Hub`] shared between threads: each thread holds a [`VirtualPort`]. Uses real time.
#[derive(Debug, Clone)]
pub struct VirtualBus {
    shared: Arc<Shared>,
}

impl Default for VirtualBus {
    fn default() -> Self {
        Self::new()
    }
}

impl VirtualBus {
    /// A bus with [`DEFAULT_QUEUE_FRAMES`] per port.
    pub fn new() -> Self {
        Self {
            shared: Arc::new(Shared {
                hub: Mutex::new(Hub::default()),
                arrived: Condvar::new(),
            }),
        }
    }

    /// Attach a port named `name` (for messages).
    pub fn port(&self, name: &str) -> VirtualPort {
        let id = self
            .shared
            .hub
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .attach();
        VirtualPort {
            shared: Arc::clone(&self.shared),
            id,
            name: name.to_string(),
        }
    }
}

/// One thread's connection to a [`VirtualBus`].
#[derive(Debug)]
pub struct VirtualPort {
    shared: Arc<Shared>,
    id: PortId,
    name: String,
}

impl Drop for VirtualPort {
    fn drop(&mut self) {
        self.shared
            .hub
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .detach(self.id);
    }
}

impl CanTransport for VirtualPort {
    fn name(&self) -> &str {
        &self.name
    }

    fn now_us(&self) -> u64 {
        monotonic_us()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        self.shared
            .hub
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .send(self.id, frame);
        self.shared.arrived.notify_all();
        Ok(())
    }

    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        let deadline = monotonic_us().saturating_add(timeout_us);
        let mut hub = self
            .shared
            .hub
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        loop {
            if let Some(f) = hub.recv(self.id) {
                return Ok(Some(f));
            }
            let now = monotonic_us();
            if now >= deadline {
                return Ok(None);
            }
            let wait = Duration::from_micros(deadline - now);
            hub = self
                .shared
                .arrived
                .wait_timeout(hub, wait)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hub_broadcasts_to_others_only() {
        let mut h = Hub::new(2);
        let a = h.attach();
        let b = h.attach();
        let c = h.attach();
        let f = CanFrame::new(0x181, &[1]).unwrap();
        h.send(a, &f);
        assert_eq!(h.recv(a), None);
        assert_eq!(h.recv(b), Some(f));
        assert!(h.pending(c));
        h.send(a, &f);
        h.send(a, &f);
        assert_eq!(h.dropped(c), 1);
        h.detach(b);
        h.send(a, &f);
        assert_eq!(h.recv(b), None);
    }

    #[test]
    fn threads_exchange_frames() {
        let bus = VirtualBus::new();
        let mut a = bus.port("a");
        let mut b = bus.port("b");
        let t = std::thread::spawn(move || {
            // Echo one frame with id + 1; a missing frame fails the test through the join.
            let f = b.recv(5_000_000).unwrap().unwrap();
            b.send(&CanFrame::new(f.id() + 1, f.data()).unwrap())
                .unwrap();
        });
        a.send(&CanFrame::new(0x600, &[9]).unwrap()).unwrap();
        let r = a.recv(5_000_000).unwrap().unwrap();
        assert_eq!((r.id(), r.data()), (0x601, &[9u8][..]));
        t.join().unwrap();
        assert_eq!(a.recv(0).unwrap(), None);
    }
}
