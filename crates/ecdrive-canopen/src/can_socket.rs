//! SocketCAN transport for real CAN adapters on Linux, through the `socketcan` crate.
//!
//! Classic frames with 11-bit identifiers only (what CANopen's pre-defined connection set
//! uses): extended, FD and error frames are skipped on reception. Time is `CLOCK_MONOTONIC`.
//! [`can_interfaces`] lists the interfaces of type CAN (`/sys/class/net/*/type` = 280), which is
//! how the tests decide whether a SocketCAN test can run here.

use super::frame::CanFrame;
use super::transport::{CanTransport, TransportError, monotonic_us};
use socketcan::{CanSocket, EmbeddedFrame, Id, Socket, SocketOptions, StandardId};
use std::io::ErrorKind;
use std::os::fd::AsFd;

/// ARPHRD_CAN: the `type` of a CAN network interface in sysfs.
pub const ARPHRD_CAN: u32 = 280;

/// The network interfaces of type CAN on this machine (`can0`, `vcan0`, …), sorted.
pub fn can_interfaces() -> Vec<String> {
    let Ok(dir) = std::fs::read_dir("/sys/class/net") else {
        return Vec::new();
    };
    let mut out: Vec<String> = dir
        .filter_map(Result::ok)
        .filter(|e| {
            std::fs::read_to_string(e.path().join("type"))
                .ok()
                .and_then(|t| t.trim().parse::<u32>().ok())
                == Some(ARPHRD_CAN)
        })
        .filter_map(|e| e.file_name().into_string().ok())
        .collect();
    out.sort();
    out
}

/// Whether `ifname` is a virtual CAN interface (no backing device in sysfs): traffic on it
/// reaches no real bus.
pub fn is_virtual(ifname: &str) -> bool {
    !std::path::Path::new("/sys/class/net")
        .join(ifname)
        .join("device")
        .exists()
}

/// A SocketCAN raw socket bound to one interface.
#[derive(Debug)]
pub struct SocketCanTransport {
    sock: CanSocket,
    name: String,
}

fn io(interface: &str, op: &'static str, source: std::io::Error) -> TransportError {
    TransportError::Io {
        interface: interface.to_string(),
        op,
        source,
    }
}

impl SocketCanTransport {
    /// Open `ifname` (e.g. `can0`). Error frames are not delivered.
    pub fn open(ifname: &str) -> Result<Self, TransportError> {
        let sock = CanSocket::open(ifname).map_err(|e| io(ifname, "open", e))?;
        sock.set_error_filter_drop_all()
            .map_err(|e| io(ifname, "set error filter", e))?;
        sock.set_nonblocking(true)
            .map_err(|e| io(ifname, "set non-blocking", e))?;
        Ok(Self {
            sock,
            name: ifname.to_string(),
        })
    }

    /// Also receive the frames this socket sends (loopback tests on a virtual interface).
    pub fn set_receive_own(&self, on: bool) -> Result<(), TransportError> {
        self.sock
            .set_recv_own_msgs(on)
            .map_err(|e| io(&self.name, "set receive-own", e))
    }

    fn convert(f: &socketcan::CanFrame) -> Option<CanFrame> {
        let Id::Standard(id) = f.id() else {
            return None;
        };
        match f {
            socketcan::CanFrame::Data(d) => CanFrame::new(id.as_raw(), d.data()).ok(),
            socketcan::CanFrame::Remote(r) => CanFrame::remote(id.as_raw(), r.dlc() as u8).ok(),
            socketcan::CanFrame::Error(_) => None,
        }
    }
}

impl CanTransport for SocketCanTransport {
    fn name(&self) -> &str {
        &self.name
    }

    fn now_us(&self) -> u64 {
        monotonic_us()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let id = StandardId::new(frame.id()).ok_or_else(|| TransportError::Unsupported {
            interface: self.name.clone(),
            what: format!("identifier 0x{:X} is not 11-bit", frame.id()),
        })?;
        let f = if frame.is_remote() {
            socketcan::CanFrame::new_remote(id, usize::from(frame.dlc()))
        } else {
            socketcan::CanFrame::new(id, frame.data())
        }
        .ok_or_else(|| TransportError::Unsupported {
            interface: self.name.clone(),
            what: format!("cannot build frame {frame}"),
        })?;
        let mut r = self.sock.write_frame(&f);
        // Non-blocking: a full transmit queue waits (up to 100 ms) as a blocking write did.
        if matches!(&r, Err(e) if e.kind() == ErrorKind::WouldBlock) {
            ecdrive_core::rt::wait_writable(self.sock.as_fd(), 100_000)
                .map_err(|e| io(&self.name, "wait to write", e))?;
            r = self.sock.write_frame(&f);
        }
        r.map_err(|e| io(&self.name, "write", e))
    }

    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        let deadline = monotonic_us().saturating_add(timeout_us);
        loop {
            // The socket is non-blocking (set at open): a read, and when nothing is there a
            // wait for the rest of the time (one ppoll), then the read again.
            let mut r = self.sock.read_frame();
            let left = deadline.saturating_sub(monotonic_us());
            if left > 0 && matches!(&r, Err(e) if e.kind() == ErrorKind::WouldBlock) {
                ecdrive_core::rt::wait_readable(self.sock.as_fd(), left)
                    .map_err(|e| io(&self.name, "wait", e))?;
                r = self.sock.read_frame();
            }
            match r {
                Ok(f) => {
                    if let Some(f) = Self::convert(&f) {
                        return Ok(Some(f));
                    }
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                    ) =>
                {
                    if monotonic_us() >= deadline {
                        return Ok(None);
                    }
                }
                Err(e) => return Err(io(&self.name, "read", e)),
            }
            if left == 0 {
                return Ok(None);
            }
        }
    }
}
