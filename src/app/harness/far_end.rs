//! The far end of a veth pair the harness creates: the emulated segment served on the peer
//! end (inside the pair's network namespace) by a thread of this process, so that the slave
//! side's timing statistics can be read after the run.

use crate::link::{LinkError, RawSocket};
use crate::rt::RtSettings;
use crate::sim::Segment;
use crate::sim::transport::{ServeStats, serve};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

type Served = (Segment, Result<ServeStats, LinkError>);

/// A segment served on a raw socket by a thread with a given real-time set-up.
pub struct FarEnd {
    stop: Arc<AtomicBool>,
    thread: JoinHandle<Served>,
}

impl FarEnd {
    /// Serve `segment` on `socket` from a new thread set up with `rt` (the emulated drives
    /// stand in for hardware that answers at once, so they get the master's priority).
    pub fn spawn(socket: RawSocket, segment: Segment, rt: RtSettings) -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let thread = std::thread::Builder::new()
            .name("jitter-far-end".into())
            .spawn(move || {
                let _ = rt.apply_to_current_thread();
                let m = Mutex::new(segment);
                let r = serve(&socket, &m, &s);
                (m.into_inner().unwrap_or_else(|e| e.into_inner()), r)
            })?;
        Ok(Self { stop, thread })
    }

    /// Stop serving; the segment back, with what serving reported.
    pub fn stop(self) -> Result<Served, String> {
        self.stop.store(true, Ordering::Release);
        self.thread
            .join()
            .map_err(|_| "the thread serving the emulated drives panicked".to_string())
    }
}
