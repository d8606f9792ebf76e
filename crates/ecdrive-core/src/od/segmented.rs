//! The segmented SDO transfer, once for both buses and both roles.
//!
//! CiA 301 §7.2.4.3.4–7 splits a value that does not fit the initiate message into segments;
//! ETG.1000.6 §5.6.2.3 and §5.6.2.6 carry the same protocol inside CoE, with longer segments. In
//! both, the toggle bit of the first segment is 0 and alternates; the side that sends the
//! data (a client downloading, a server answering an upload request) marks the last segment;
//! the side that receives it checks the toggle, the length against the size the initiate
//! announced, and its own limit.
//!
//! [`Segmented`] is that state, without I/O and without a buffer (the caller keeps the value,
//! so a server can reuse one allocation): the CANopen client and server (`can::sdo`), the CoE
//! client (the EtherCAT master) and the CoE server (the software slave) all step it. Only the
//! bytes differ per bus: 8-byte CAN frames with up to 7 data bytes, CoE mailboxes with as many
//! as the mailbox holds.

use core::ops::Range;

/// Why a segment was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SegmentError {
    /// The toggle bit did not alternate.
    #[error("toggle bit not alternated")]
    Toggle,
    /// More data than the initiate announced.
    #[error("more than the {announced} bytes announced")]
    LongerThanAnnounced {
        /// The announced size.
        announced: usize,
    },
    /// The last segment came before the announced size was reached.
    #[error("{got} bytes where {announced} were announced")]
    ShorterThanAnnounced {
        /// The announced size.
        announced: usize,
        /// Bytes received.
        got: usize,
    },
    /// More data than the receiver takes.
    #[error("more than {limit} bytes")]
    OverLimit {
        /// The receiver's limit.
        limit: usize,
    },
}

/// One segment to send: its toggle bit, the bytes of the value it carries and whether it is
/// the last.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Segment {
    /// Toggle bit.
    pub toggle: bool,
    /// The bytes of the value it carries.
    pub range: Range<usize>,
    /// Whether it is the last segment.
    pub last: bool,
}

/// Where a segmented transfer stands. It is stepped by the side that sends a value ([`next_out`](Self::next_out)) and by the side that receives it ([`next_in`](Self::next_in)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segmented {
    toggle: bool,
    pos: usize,
    size: Option<usize>,
}

impl Segmented {
    /// A transfer whose segments start at byte `pos` of the value (after what the initiate
    /// carried: nothing on CAN, the first part of a CoE normal transfer), with the size the
    /// initiate announced, if any.
    pub const fn start(pos: usize, size: Option<usize>) -> Self {
        Self {
            toggle: false,
            pos,
            size,
        }
    }

    /// The toggle bit the next segment (or segment request) carries.
    pub const fn toggle(&self) -> bool {
        self.toggle
    }

    /// Bytes of the value sent or received so far.
    pub const fn position(&self) -> usize {
        self.pos
    }

    /// The size the initiate announced.
    pub const fn size(&self) -> Option<usize> {
        self.size
    }

    /// Check the toggle bit of a request or acknowledgement for the segment at hand: an upload
    /// segment request (server) must carry [`toggle`](Self::toggle).
    pub fn expect(&self, toggle: bool) -> Result<(), SegmentError> {
        if toggle == self.toggle {
            Ok(())
        } else {
            Err(SegmentError::Toggle)
        }
    }

    /// Check the toggle bit of the acknowledgement of the segment [`next_out`](Self::next_out)
    /// gave last (a download segment response, at the client).
    pub fn acknowledged(&self, toggle: bool) -> Result<(), SegmentError> {
        self.expect(!toggle)
    }

    /// Whether every byte of a value of `len` bytes has been given out.
    pub const fn sent_all(&self, len: usize) -> bool {
        self.pos >= len
    }

    /// The sending side: the next segment of a value of `len` bytes, at most `capacity` bytes
    /// long; moves on (the toggle alternates).
    pub fn next_out(&mut self, len: usize, capacity: usize) -> Segment {
        let start = self.pos.min(len);
        let end = len.min(start.saturating_add(capacity));
        let s = Segment {
            toggle: self.toggle,
            range: start..end,
            last: end >= len,
        };
        self.pos = end;
        self.toggle = !self.toggle;
        s
    }

    /// The receiving side: a segment of `n` bytes arrived with `toggle` and `last`. Checks the
    /// toggle, the announced size and `limit`, and moves on; `Ok(true)` when it was the last
    /// (the value is complete). The caller appends the bytes only on `Ok`.
    pub fn next_in(
        &mut self,
        toggle: bool,
        n: usize,
        last: bool,
        limit: usize,
    ) -> Result<bool, SegmentError> {
        self.expect(toggle)?;
        let got = self.pos.saturating_add(n);
        if let Some(announced) = self.size
            && got > announced
        {
            return Err(SegmentError::LongerThanAnnounced { announced });
        }
        if got > limit {
            return Err(SegmentError::OverLimit { limit });
        }
        if last
            && let Some(announced) = self.size
            && got != announced
        {
            return Err(SegmentError::ShorterThanAnnounced { announced, got });
        }
        self.pos = got;
        self.toggle = !self.toggle;
        Ok(last)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn toggle_starts_at_zero_and_alternates() {
        let mut s = Segmented::start(0, Some(10));
        assert!(!s.toggle());
        assert_eq!(s.next_in(false, 7, false, 100), Ok(false));
        assert_eq!(s.next_in(false, 3, true, 100), Err(SegmentError::Toggle));
        assert_eq!(s.next_in(true, 3, true, 100), Ok(true));
        assert_eq!(s.position(), 10);
    }

    #[test]
    fn the_announced_size_and_the_limit_hold() {
        let mut s = Segmented::start(0, Some(10));
        assert_eq!(
            s.next_in(false, 11, false, 100),
            Err(SegmentError::LongerThanAnnounced { announced: 10 })
        );
        assert_eq!(
            s.next_in(false, 9, true, 100),
            Err(SegmentError::ShorterThanAnnounced {
                announced: 10,
                got: 9
            })
        );
        let mut s = Segmented::start(0, None);
        assert_eq!(
            s.next_in(false, 5, false, 4),
            Err(SegmentError::OverLimit { limit: 4 })
        );
        // Nothing moved on an error.
        assert_eq!((s.position(), s.toggle()), (0, false));
    }

    #[test]
    fn an_empty_value_is_one_empty_last_segment() {
        let mut out = Segmented::start(0, Some(0));
        let seg = out.next_out(0, 7);
        assert_eq!(seg.range, 0..0);
        assert!(seg.last && !seg.toggle);
        let mut inn = Segmented::start(0, Some(0));
        assert_eq!(inn.next_in(false, 0, true, 10), Ok(true));
    }

    proptest! {
        #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(crate::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
        /// Whatever the value's length, the first part and the capacity: the sender's segments,
        /// fed to a receiver, rebuild the value, the last flag on exactly the final one, each
        /// acknowledgement accepted and a repeated one refused.
        #[test]
        fn sender_and_receiver_agree(
            value in proptest::collection::vec(any::<u8>(), 0..200),
            first in 0usize..20,
            capacity in 1usize..40,
        ) {
            let first = first.min(value.len());
            let mut tx = Segmented::start(first, Some(value.len()));
            let mut rx = Segmented::start(first, Some(value.len()));
            let mut got = value[..first].to_vec();
            loop {
                let seg = tx.next_out(value.len(), capacity);
                prop_assert!(seg.range.len() <= capacity);
                prop_assert!(tx.acknowledged(seg.toggle).is_ok());
                prop_assert!(tx.acknowledged(!seg.toggle).is_err());
                let done = rx.next_in(seg.toggle, seg.range.len(), seg.last, 1000).unwrap();
                got.extend_from_slice(&value[seg.range.clone()]);
                prop_assert_eq!(done, seg.last);
                prop_assert_eq!(seg.last, tx.sent_all(value.len()));
                if done {
                    break;
                }
            }
            prop_assert_eq!(got, value);
        }
    }
}
