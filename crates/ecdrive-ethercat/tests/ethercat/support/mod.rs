//! Helpers of this test binary; those shared with other crates' tests are `ecdrive-testkit`'s.

pub use ecdrive_testkit::generic;

/// An entry a test expects in the history: what it is, in words for the failure message, and
/// how to know its event.
pub type Expected<'a> = (&'a str, &'a dyn Fn(&ecdrive_ethercat::HistoryEvent) -> bool);
