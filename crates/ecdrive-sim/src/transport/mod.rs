//! Ways to put a [`Segment`](super::segment::Segment) on a wire.
//!
//! - [`SegmentLink`]: synchronous and in-process, implementing
//!   [`FrameLink`](crate::link::FrameLink): `send` processes the frame at once, `recv` returns
//!   the reply. No threads, no syscalls, no allocation per frame: for a master's own cycle
//!   thread.
//! - [`EthercrabLink`]: a thread that moves frames between ethercrab's `PduTx`/`PduRx` and a
//!   segment, for plain-ethercrab tests without root.
//! - [`RawServer`] / [`serve`]: answer frames on a raw socket (a veth end or a real NIC).
//!
//! All three honour the segment's injected link faults ([`crate::faults::LinkFault`]):
//! a lost frame gets no reply, a delayed reply is held until its time on the segment's clock,
//! and while the cable is pulled they keep polling the segment so that its SYNC0 pulses and
//! watchdogs run.

mod ethercrab_link;
mod held;
mod raw;
mod segment_link;

pub use ethercrab_link::{EthercrabLink, Wakeups};
pub use raw::{RawServer, ServeStats, serve};
pub use segment_link::{IN_FLIGHT, SegmentLink};

use std::sync::{Mutex, MutexGuard};

/// Lock a mutex, recovering the data if a holder panicked (the segment stays usable for
/// inspection after a failed test).
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}
