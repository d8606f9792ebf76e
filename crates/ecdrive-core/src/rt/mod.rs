//! Real-time support: thread set-up, absolute-time sleeping, cycle statistics and host facts.
//!
//! The cyclic thread sleeps to absolute instants of `CLOCK_MONOTONIC` with `clock_nanosleep`
//! (never a relative sleep, never a tokio timer), so a late wake-up does not shift the following
//! cycles.

pub mod audit;
pub mod clock;
pub mod host;
pub mod stats;
pub mod thread;

pub use clock::{monotonic_ns, sleep_until_ns, wait_readable, wait_writable};
pub use stats::{LatencyHistogram, Summary};
pub use thread::{RtReport, RtSettings};
