//! `--candump FILE`: every CAN frame of a CANopen run, both directions, in the log format of
//! can-utils' `candump -l` (`(seconds.micros) IFACE ID#DATA`, `ID#R` for a remote frame), which
//! `canplayer`, `log2asc` and Wireshark's candump import read. Times are the bus's clock (the
//! transport's: `CLOCK_MONOTONIC` on a real or `vbus:` bus, simulated time on `can-sim`); a
//! received frame is logged at the time it was on the bus ([`CanTransport::recv_stamped`]).

use crate::canopen::frame::CanFrame;
use crate::canopen::transport::{CanTransport, TransportError};
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// What a capture wrote.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct CandumpSummary {
    /// The log file.
    pub file: String,
    /// Frames written (sent and received).
    pub frames: u64,
}

/// A transport that logs every frame through it. A write error stops the logging (the
/// summary says so), never the bus. Dropping it flushes the log.
pub struct CandumpTap<T> {
    inner: T,
    out: Option<std::io::BufWriter<std::fs::File>>,
    iface: String,
    count: Arc<AtomicU64>,
}

/// The caller's view of a [`CandumpTap`]'s log, valid after the tap is gone.
#[derive(Debug, Clone)]
pub struct CandumpLog {
    file: String,
    count: Arc<AtomicU64>,
}

impl CandumpLog {
    /// What was written.
    pub fn summary(&self) -> CandumpSummary {
        CandumpSummary {
            file: self.file.clone(),
            frames: self.count.load(Ordering::Relaxed),
        }
    }
}

impl<T: CanTransport> CandumpTap<T> {
    /// Log `inner`'s frames to `path` (created), under the interface name `iface`.
    pub fn new(
        inner: T,
        path: &std::path::Path,
        iface: &str,
    ) -> std::io::Result<(Self, CandumpLog)> {
        let out = std::io::BufWriter::new(std::fs::File::create(path)?);
        // candump names an interface with no spaces and no '#'.
        let iface = iface
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let count = Arc::new(AtomicU64::new(0));
        Ok((
            Self {
                inner,
                out: Some(out),
                iface,
                count: count.clone(),
            },
            CandumpLog {
                file: path.display().to_string(),
                count,
            },
        ))
    }

    fn log(&mut self, f: &CanFrame, at_us: u64) {
        let Some(out) = self.out.as_mut() else {
            return;
        };
        let data = if f.is_remote() {
            "R".to_string()
        } else {
            f.data().iter().map(|b| format!("{b:02X}")).collect()
        };
        let line = writeln!(
            out,
            "({}.{:06}) {} {:03X}#{data}",
            at_us / 1_000_000,
            at_us % 1_000_000,
            self.iface,
            f.id()
        );
        if line.is_ok() {
            self.count.fetch_add(1, Ordering::Relaxed);
        } else {
            self.out = None;
        }
    }
}

impl<T: CanTransport> CanTransport for CandumpTap<T> {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn now_us(&self) -> u64 {
        self.inner.now_us()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let at = self.inner.now_us();
        self.inner.send(frame)?;
        self.log(frame, at);
        Ok(())
    }

    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        Ok(self.recv_stamped(timeout_us)?.map(|(f, _)| f))
    }

    fn recv_stamped(&mut self, timeout_us: u64) -> Result<Option<(CanFrame, u64)>, TransportError> {
        let got = self.inner.recv_stamped(timeout_us)?;
        if let Some((f, at)) = &got {
            self.log(f, *at);
        }
        Ok(got)
    }
}

impl<T> Drop for CandumpTap<T> {
    fn drop(&mut self) {
        if let Some(o) = self.out.as_mut() {
            let _ = o.flush();
        }
    }
}
