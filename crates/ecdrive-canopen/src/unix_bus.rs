//! The virtual CAN bus across processes on this machine: a hub on a Unix-domain datagram
//! socket, and ports that connect to it. No kernel CAN support (vcan) is needed.
//!
//! Protocol, one datagram each: a client sends `H` (hello) from its own bound socket to
//! register, `B` (bye) to leave, and frames as the 16-byte Linux `struct can_frame` record
//! ([`CanFrame::to_record`]) followed by the sender's `CLOCK_MONOTONIC` time in µs (8 bytes,
//! little-endian): a frame keeps the time it was sent at, as on a CAN bus, however long it
//! waited in a socket for a process the scheduler kept from running (a drive that judges the
//! gap between two requests judges the bus's, not the scheduler's; a record without the time
//! is taken at its arrival). The hub forwards every frame to every other registered client —
//! the broadcast of a CAN bus — and forgets clients whose socket is gone. Malformed datagrams
//! are dropped. Only filesystem sockets of this machine are involved.

use super::frame::CanFrame;
use super::transport::{CanTransport, TransportError, monotonic_us};
use std::io::ErrorKind;
use std::os::fd::AsFd;
use std::os::unix::net::UnixDatagram;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

const HELLO: &[u8] = b"H";
/// Bytes of a `struct can_frame` record.
const RECORD: usize = 16;
const BYE: &[u8] = b"B";

fn io(path: &Path, op: &'static str, source: std::io::Error) -> TransportError {
    TransportError::Io {
        interface: path.display().to_string(),
        op,
        source,
    }
}

/// The hub of a cross-process virtual bus.
#[derive(Debug)]
pub struct UnixBusHub {
    sock: UnixDatagram,
    path: PathBuf,
    clients: Vec<PathBuf>,
}

impl UnixBusHub {
    /// Bind the hub at `path`. A stale socket file (no hub answering) is replaced; a live hub
    /// there is an error.
    pub fn bind(path: &Path) -> Result<Self, TransportError> {
        if path.exists() {
            let probe = UnixDatagram::unbound().map_err(|e| io(path, "socket", e))?;
            if probe.connect(path).is_ok() {
                return Err(io(
                    path,
                    "bind",
                    std::io::Error::new(ErrorKind::AddrInUse, "a hub is already running there"),
                ));
            }
            std::fs::remove_file(path).map_err(|e| io(path, "remove stale socket", e))?;
        }
        let sock = UnixDatagram::bind(path).map_err(|e| io(path, "bind", e))?;
        sock.set_read_timeout(Some(Duration::from_millis(50)))
            .map_err(|e| io(path, "set timeout", e))?;
        Ok(Self {
            sock,
            path: path.to_path_buf(),
            clients: Vec::new(),
        })
    }

    /// Registered clients.
    pub fn clients(&self) -> usize {
        self.clients.len()
    }

    /// Handle datagrams until `stop` is set.
    pub fn run(&mut self, stop: &AtomicBool) -> Result<(), TransportError> {
        let mut buf = [0u8; 64];
        while !stop.load(Ordering::Relaxed) {
            let (n, from) = match self.sock.recv_from(&mut buf) {
                Ok(x) => x,
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                    ) =>
                {
                    continue;
                }
                Err(e) => return Err(io(&self.path, "receive", e)),
            };
            let Some(from) = from.as_pathname().map(Path::to_path_buf) else {
                continue;
            };
            let msg = buf.get(..n).unwrap_or(&[]);
            if msg == HELLO {
                if !self.clients.contains(&from) {
                    self.clients.push(from);
                }
                continue;
            }
            if msg == BYE {
                self.clients.retain(|c| *c != from);
                continue;
            }
            if CanFrame::from_record(msg.get(..RECORD).unwrap_or(msg)).is_err() {
                continue;
            }
            let mut gone = Vec::new();
            for c in &self.clients {
                if *c == from {
                    continue;
                }
                if let Err(e) = self.sock.send_to(msg, c)
                    && matches!(e.kind(), ErrorKind::NotFound | ErrorKind::ConnectionRefused)
                {
                    gone.push(c.clone());
                }
            }
            self.clients.retain(|c| !gone.contains(c));
        }
        Ok(())
    }

    /// Run a hub at `path` on its own thread until the handle is dropped.
    pub fn spawn(path: &Path) -> Result<HubHandle, TransportError> {
        let mut hub = Self::bind(path)?;
        let stop = Arc::new(AtomicBool::new(false));
        let s = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("canopen-hub".into())
            .spawn(move || {
                let _ = hub.run(&s);
            })
            .map_err(|e| io(path, "spawn hub thread", e))?;
        Ok(HubHandle {
            stop,
            thread: Some(thread),
            path: path.to_path_buf(),
        })
    }
}

impl Drop for UnixBusHub {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// A hub running on a thread; dropping it stops the hub and removes its socket.
#[derive(Debug)]
pub struct HubHandle {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    path: PathBuf,
}

impl HubHandle {
    /// The hub's socket path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for HubHandle {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

static PORTS: AtomicU64 = AtomicU64::new(0);

/// A process's connection to a [`UnixBusHub`]. Real time (`CLOCK_MONOTONIC`).
#[derive(Debug)]
pub struct UnixBusPort {
    sock: UnixDatagram,
    own: PathBuf,
    name: String,
}

impl UnixBusPort {
    /// Connect to the hub at `hub`: bind a socket next to it and say hello.
    pub fn connect(hub: &Path) -> Result<Self, TransportError> {
        let n = PORTS.fetch_add(1, Ordering::Relaxed);
        let mut own = hub.as_os_str().to_owned();
        own.push(format!(".{}.{n}", std::process::id()));
        let own = PathBuf::from(own);
        let _ = std::fs::remove_file(&own);
        let sock = UnixDatagram::bind(&own).map_err(|e| io(&own, "bind", e))?;
        // A hub that is not there leaves no socket file of ours behind.
        let undo = |e: TransportError| {
            let _ = std::fs::remove_file(&own);
            e
        };
        sock.connect(hub).map_err(|e| undo(io(hub, "connect", e)))?;
        sock.send(HELLO).map_err(|e| undo(io(hub, "hello", e)))?;
        sock.set_nonblocking(true)
            .map_err(|e| io(&own, "set non-blocking", e))?;
        Ok(Self {
            sock,
            own,
            name: format!("vbus:{}", hub.display()),
        })
    }
}

impl Drop for UnixBusPort {
    fn drop(&mut self) {
        let _ = self.sock.send(BYE);
        let _ = std::fs::remove_file(&self.own);
    }
}

impl CanTransport for UnixBusPort {
    fn name(&self) -> &str {
        &self.name
    }

    fn now_us(&self) -> u64 {
        monotonic_us()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let mut msg = [0u8; RECORD + 8];
        msg[..RECORD].copy_from_slice(&frame.to_record());
        msg[RECORD..].copy_from_slice(&monotonic_us().to_le_bytes());
        let mut r = self.sock.send(&msg);
        // Non-blocking: a full queue at the hub waits (up to 100 ms) as a blocking send did.
        // A datagram socket may poll writable while the hub's queue is still full (Linux
        // wakes on its own buffer): wait again until the hub took the frame or the time is up.
        let deadline = monotonic_us() + 100_000;
        while matches!(&r, Err(e) if e.kind() == ErrorKind::WouldBlock) {
            let left = deadline.saturating_sub(monotonic_us());
            if left == 0 {
                break;
            }
            let ready = ecdrive_core::rt::wait_writable(self.sock.as_fd(), left.min(1_000))
                .map_err(|e| io(&self.own, "wait to send", e))?;
            r = self.sock.send(&msg);
            if ready && matches!(&r, Err(e) if e.kind() == ErrorKind::WouldBlock) {
                std::thread::sleep(std::time::Duration::from_micros(100));
            }
        }
        match r {
            Ok(_) => Ok(()),
            Err(e) if matches!(e.kind(), ErrorKind::NotFound | ErrorKind::ConnectionRefused) => {
                Err(TransportError::Closed(self.name.clone()))
            }
            Err(e) => Err(io(&self.own, "send", e)),
        }
    }

    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        Ok(self.recv_stamped(timeout_us)?.map(|(f, _)| f))
    }

    fn recv_stamped(&mut self, timeout_us: u64) -> Result<Option<(CanFrame, u64)>, TransportError> {
        let deadline = monotonic_us().saturating_add(timeout_us);
        let mut buf = [0u8; 64];
        loop {
            // The socket is non-blocking (set at connect): a receive, and when nothing is
            // there a wait for the rest of the time (one ppoll), then the receive again.
            let mut r = self.sock.recv(&mut buf);
            let left = deadline.saturating_sub(monotonic_us());
            if left > 0 && matches!(&r, Err(e) if e.kind() == ErrorKind::WouldBlock) {
                ecdrive_core::rt::wait_readable(self.sock.as_fd(), left)
                    .map_err(|e| io(&self.own, "wait", e))?;
                r = self.sock.recv(&mut buf);
            }
            match r {
                Ok(n) => {
                    let msg = buf.get(..n).unwrap_or(&[]);
                    if let Ok(f) = CanFrame::from_record(msg.get(..RECORD).unwrap_or(msg)) {
                        let now = monotonic_us();
                        let sent = msg
                            .get(RECORD..RECORD + 8)
                            .and_then(|b| <[u8; 8]>::try_from(b).ok())
                            .map_or(now, |b| u64::from_le_bytes(b).min(now));
                        return Ok(Some((f, sent)));
                    }
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(io(&self.own, "receive", e)),
            }
            if left == 0 || monotonic_us() >= deadline {
                return Ok(None);
            }
        }
    }
}
