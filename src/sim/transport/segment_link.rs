//! The synchronous in-process link.

use crate::ec::frame::MAX_FRAME_LEN;
use crate::link::{FrameLink, LinkError};
use crate::sim::segment::Segment;
use std::time::Duration;

/// Frames that can be in flight at once (sent, reply not yet received).
pub const IN_FLIGHT: usize = 32;

/// A [`FrameLink`] whose other end is a [`Segment`] in the same thread: `send` processes the
/// frame immediately, `recv` hands out the replies in order. Dropped frames (malformed, or no
/// slaves) produce no reply, as on a wire. Buffers are allocated once at construction.
#[derive(Debug)]
pub struct SegmentLink {
    segment: Segment,
    slots: Vec<[u8; MAX_FRAME_LEN]>,
    lens: [usize; IN_FLIGHT],
    head: usize,
    count: usize,
}

impl SegmentLink {
    /// A link to `segment`.
    pub fn new(segment: Segment) -> Self {
        Self {
            segment,
            slots: vec![[0u8; MAX_FRAME_LEN]; IN_FLIGHT],
            lens: [0; IN_FLIGHT],
            head: 0,
            count: 0,
        }
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

    /// Replies waiting to be received.
    pub fn pending_replies(&self) -> usize {
        self.count
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
        if self.count >= IN_FLIGHT {
            return Err(LinkError::Peer(format!(
                "in-process segment: {IN_FLIGHT} replies are waiting to be received; receive before sending more"
            )));
        }
        let idx = (self.head + self.count) % IN_FLIGHT;
        let (Some(slot), Some(len)) = (self.slots.get_mut(idx), self.lens.get_mut(idx)) else {
            return Err(LinkError::Peer(
                "in-process segment: slot out of range".into(),
            ));
        };
        let Some(buf) = slot.get_mut(..frame.len()) else {
            return Err(LinkError::Peer("in-process segment: slot too small".into()));
        };
        buf.copy_from_slice(frame);
        if let Ok(n) = self.segment.process(buf) {
            *len = n;
            self.count += 1;
        }
        Ok(())
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        _timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        if self.count == 0 {
            // Nothing in flight: let time-driven work (SYNC0, watchdogs) happen, then report a
            // timeout at once (nothing can arrive while we wait in the same thread).
            self.segment.poll();
            return Ok(None);
        }
        let idx = self.head;
        let n = self.lens.get(idx).copied().unwrap_or(0);
        let src = self
            .slots
            .get(idx)
            .and_then(|s| s.get(..n))
            .ok_or_else(|| LinkError::Peer("in-process segment: bad slot".into()))?;
        let capacity = buf.len();
        let dst = buf.get_mut(..n).ok_or_else(|| LinkError::Truncated {
            interface: "in-process segment".into(),
            len: n,
            capacity,
        })?;
        dst.copy_from_slice(src);
        self.head = (self.head + 1) % IN_FLIGHT;
        self.count -= 1;
        Ok(Some(n))
    }
}
