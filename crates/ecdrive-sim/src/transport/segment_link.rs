//! The synchronous in-process link.

use super::held::HeldReplies;
use crate::clock::Clock;
use crate::ec::frame::MAX_FRAME_LEN;
use crate::link::{FrameLink, LinkError};
use crate::segment::Segment;
use std::time::Duration;

/// Replies that can wait to be received at once; one more `send` is refused.
pub const IN_FLIGHT: usize = 32;

/// Replies held at once, delayed ones included (see [`SegmentLink`]).
const HELD: usize = 4 * IN_FLIGHT;

/// A [`FrameLink`] whose other end is a [`Segment`] in the same thread: `send` processes the
/// frame immediately, `recv` hands out the replies. Dropped frames (malformed, no slaves, or
/// lost by an injected fault) produce no reply, as on a wire. Buffers are allocated once at
/// construction.
///
/// A reply delayed by an injected [`LinkFault::Delay`](crate::faults::LinkFault::Delay)
/// is handed out once the segment's clock reaches its due time; replies come out earliest due
/// first (a delayed reply can be overtaken by a later frame's). While a delayed reply is held,
/// `recv` waits for it as a socket would: until it is due or the timeout passes, whichever
/// comes first (a real sleep; with a [`ManualClock`](crate::ManualClock) the caller moves
/// the time instead and passes a zero timeout). With nothing in flight it returns `None` at
/// once.
///
/// Sending is refused (a [`LinkError::Peer`]) when [`IN_FLIGHT`] replies are due but not
/// received: the caller forgot to receive. Delayed replies not yet due do not count; should so
/// many be held that no buffer is free (128), a new frame is still processed but its reply is
/// lost, counted in [`SegmentLink::replies_lost`].
#[derive(Debug)]
pub struct SegmentLink {
    segment: Segment,
    held: HeldReplies,
    scratch: Box<[u8; MAX_FRAME_LEN]>,
    lost: u64,
}

impl SegmentLink {
    /// A link to `segment`.
    pub fn new(segment: Segment) -> Self {
        Self {
            segment,
            held: HeldReplies::new(HELD),
            scratch: Box::new([0u8; MAX_FRAME_LEN]),
            lost: 0,
        }
    }

    /// Replies lost because every buffer held a delayed reply.
    pub fn replies_lost(&self) -> u64 {
        self.lost
    }

    /// The segment.
    pub fn segment(&self) -> &Segment {
        &self.segment
    }

    /// The segment, mutable.
    pub fn segment_mut(&mut self) -> &mut Segment {
        &mut self.segment
    }

    /// Give the segment back.
    pub fn into_segment(self) -> Segment {
        self.segment
    }

    /// Replies waiting to be received (including delayed ones not yet due).
    pub fn pending_replies(&self) -> usize {
        self.held.len()
    }

    fn take_due(&mut self, buf: &mut [u8]) -> Result<Option<usize>, LinkError> {
        let now = self.segment.clock().now_ns();
        let Some(src) = self.held.pop_due(now) else {
            return Ok(None);
        };
        let n = src.len();
        let capacity = buf.len();
        let dst = buf.get_mut(..n).ok_or_else(|| LinkError::Truncated {
            interface: "in-process segment".into(),
            len: n,
            capacity,
        })?;
        dst.copy_from_slice(src);
        Ok(Some(n))
    }
}

impl FrameLink for SegmentLink {
    fn describe(&self) -> String {
        format!("the in-process segment of {} device(s)", self.segment.len())
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        if frame.len() > MAX_FRAME_LEN {
            return Err(LinkError::FrameTooLarge {
                interface: "in-process segment".into(),
                len: frame.len(),
                max: MAX_FRAME_LEN,
            });
        }
        if self.held.len() >= IN_FLIGHT
            && self.held.due_count(self.segment.clock().now_ns()) >= IN_FLIGHT
        {
            return Err(LinkError::Peer(format!(
                "in-process segment: {IN_FLIGHT} replies are waiting to be received; receive before sending more"
            )));
        }
        let Some((i, slot)) = self.held.free_slot() else {
            // Every buffer holds a delayed reply: the frame still reaches the slaves, its reply
            // is lost.
            if let Some(buf) = self.scratch.get_mut(..frame.len()) {
                buf.copy_from_slice(frame);
                if self.segment.process_frame(buf).is_ok() {
                    self.lost += 1;
                }
            }
            return Ok(());
        };
        let Some(buf) = slot.get_mut(..frame.len()) else {
            return Err(LinkError::Peer("in-process segment: slot too small".into()));
        };
        buf.copy_from_slice(frame);
        if let Ok(r) = self.segment.process_frame(buf) {
            self.held.commit(i, r.len, r.due_ns, r.delay_ns > 0);
        }
        Ok(())
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        if let Some(n) = self.take_due(buf)? {
            return Ok(Some(n));
        }
        // Nothing due: let time-driven work (SYNC0, watchdogs, queued faults) happen.
        self.segment.poll();
        let Some(due) = self.held.next_due() else {
            // Nothing in flight: report a timeout at once (nothing can arrive while we wait in
            // the same thread).
            return Ok(None);
        };
        // A delayed reply is on its way: wait for it, at most `timeout`, as a socket would.
        let wait = Duration::from_nanos(due.saturating_sub(self.segment.clock().now_ns()));
        let wait = timeout.map_or(wait, |t| wait.min(t));
        if !wait.is_zero() {
            std::thread::sleep(wait);
            self.segment.poll();
        }
        self.take_due(buf)
    }
}
