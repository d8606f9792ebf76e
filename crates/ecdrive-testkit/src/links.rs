//! Links around a link, for tests that watch or alter what a master sends.

use ecdrive_core::link::{FrameLink, LinkError};
use std::time::Duration;

/// A link that shows every frame the master sends to `tap`, which may change it, before the
/// frame goes out on `inner`; replies come back unchanged. Counting, recording and altering
/// what a master writes are each a closure over it.
pub struct SendTap<L, F> {
    /// The link the frames go out on.
    pub inner: L,
    tap: F,
    frame: Vec<u8>,
}

impl<L, F: FnMut(&mut [u8])> SendTap<L, F> {
    /// `inner`, with every frame sent shown to `tap` first.
    pub fn new(inner: L, tap: F) -> Self {
        Self {
            inner,
            tap,
            frame: Vec::new(),
        }
    }
}

impl<L: FrameLink, F: FnMut(&mut [u8])> FrameLink for SendTap<L, F> {
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        self.frame.clear();
        self.frame.extend_from_slice(frame);
        (self.tap)(&mut self.frame);
        self.inner.send(&self.frame)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        self.inner.recv(buf, timeout)
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}
