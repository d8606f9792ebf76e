//! Replies held by a transport until they are due (injected link delay), in buffers allocated
//! once.

use crate::ec::frame::MAX_FRAME_LEN;

/// A fixed set of reply buffers, each with the time it is due. Replies come out earliest due
/// first, in the order they went in among equal times. Replies without an injected delay (the
/// common case) go through a FIFO in O(1); only delayed ones are searched.
#[derive(Debug)]
pub(crate) struct HeldReplies {
    slots: Vec<[u8; MAX_FRAME_LEN]>,
    lens: Vec<usize>,
    due: Vec<u64>,
    seq: Vec<u64>,
    /// Free slot indices (a stack).
    free: Vec<usize>,
    /// Undelayed replies in order (a ring of slot indices).
    fifo: Vec<usize>,
    fifo_head: usize,
    fifo_len: usize,
    /// Delayed replies (slot indices, unordered).
    delayed: Vec<usize>,
    next_seq: u64,
}

impl HeldReplies {
    /// Room for `capacity` replies.
    pub(crate) fn new(capacity: usize) -> Self {
        Self {
            slots: vec![[0u8; MAX_FRAME_LEN]; capacity],
            lens: vec![0; capacity],
            due: vec![0; capacity],
            seq: vec![0; capacity],
            free: (0..capacity).rev().collect(),
            fifo: vec![0; capacity],
            fifo_head: 0,
            fifo_len: 0,
            delayed: Vec::with_capacity(capacity),
            next_seq: 0,
        }
    }

    /// Replies held.
    pub(crate) fn len(&self) -> usize {
        self.fifo_len + self.delayed.len()
    }

    /// A free buffer, to fill and then [`commit`](Self::commit).
    pub(crate) fn free_slot(&mut self) -> Option<(usize, &mut [u8; MAX_FRAME_LEN])> {
        let i = *self.free.last()?;
        self.slots.get_mut(i).map(|s| (i, s))
    }

    /// Hold the first `len` bytes of slot `i` (from [`free_slot`](Self::free_slot)) until
    /// `due`; `delayed`: the reply carries an injected delay (undelayed replies must be
    /// committed in the order of their due times).
    pub(crate) fn commit(&mut self, i: usize, len: usize, due: u64, delayed: bool) {
        if self.free.last() != Some(&i) {
            return;
        }
        let (Some(l), Some(d), Some(s)) = (
            self.lens.get_mut(i),
            self.due.get_mut(i),
            self.seq.get_mut(i),
        ) else {
            return;
        };
        self.free.pop();
        *l = len;
        *d = due;
        *s = self.next_seq;
        self.next_seq += 1;
        if delayed {
            self.delayed.push(i);
        } else {
            let cap = self.fifo.len().max(1);
            if let Some(slot) = self.fifo.get_mut((self.fifo_head + self.fifo_len) % cap) {
                *slot = i;
                self.fifo_len += 1;
            }
        }
    }

    /// Copy `frame` in and hold it until `due` (a delayed reply); `false` if every buffer is
    /// taken or the frame is too large.
    pub(crate) fn push(&mut self, frame: &[u8], due: u64) -> bool {
        let Some((i, slot)) = self.free_slot() else {
            return false;
        };
        let Some(dst) = slot.get_mut(..frame.len()) else {
            return false;
        };
        dst.copy_from_slice(frame);
        self.commit(i, frame.len(), due, true);
        true
    }

    fn key(&self, i: usize) -> (u64, u64) {
        (
            self.due.get(i).copied().unwrap_or(u64::MAX),
            self.seq.get(i).copied().unwrap_or(u64::MAX),
        )
    }

    fn fifo_front(&self) -> Option<usize> {
        if self.fifo_len == 0 {
            return None;
        }
        self.fifo.get(self.fifo_head).copied()
    }

    /// Position in `delayed` of the earliest delayed reply.
    fn earliest_delayed(&self) -> Option<usize> {
        (0..self.delayed.len()).min_by_key(|&k| {
            self.delayed
                .get(k)
                .map_or((u64::MAX, u64::MAX), |&i| self.key(i))
        })
    }

    /// The earliest due time held.
    pub(crate) fn next_due(&self) -> Option<u64> {
        let a = self.fifo_front().map(|i| self.key(i).0);
        let b = self
            .earliest_delayed()
            .and_then(|k| self.delayed.get(k))
            .map(|&i| self.key(i).0);
        match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Replies held that are due at `now`.
    pub(crate) fn due_count(&self, now: u64) -> usize {
        let cap = self.fifo.len().max(1);
        let fifo = (0..self.fifo_len)
            .filter_map(|k| self.fifo.get((self.fifo_head + k) % cap))
            .filter(|&&i| self.key(i).0 <= now)
            .count();
        fifo + self
            .delayed
            .iter()
            .filter(|&&i| self.key(i).0 <= now)
            .count()
    }

    /// Take the reply due first if it is due at `now`: the buffer stays valid until the next
    /// [`free_slot`](Self::free_slot) / [`push`](Self::push).
    pub(crate) fn pop_due(&mut self, now: u64) -> Option<&[u8]> {
        let front = self.fifo_front().filter(|&i| self.key(i).0 <= now);
        let delayed = if self.delayed.is_empty() {
            None
        } else {
            self.earliest_delayed()
                .filter(|&k| self.delayed.get(k).is_some_and(|&i| self.key(i).0 <= now))
        };
        let i = match (front, delayed) {
            (None, None) => return None,
            (Some(f), Some(k))
                if self
                    .delayed
                    .get(k)
                    .is_some_and(|&d| self.key(d) < self.key(f)) =>
            {
                self.delayed.swap_remove(k)
            }
            (Some(f), _) => {
                self.fifo_head = (self.fifo_head + 1) % self.fifo.len().max(1);
                self.fifo_len -= 1;
                f
            }
            (None, Some(k)) => self.delayed.swap_remove(k),
        };
        self.free.push(i);
        let n = self.lens.get(i).copied().unwrap_or(0);
        self.slots.get(i).and_then(|s| s.get(..n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn earliest_due_first_then_in_order() {
        let mut h = HeldReplies::new(3);
        assert!(h.push(&[1], 50));
        assert!(h.push(&[2], 10));
        assert!(h.push(&[3], 10));
        assert!(!h.push(&[4], 0), "full");
        assert_eq!(h.next_due(), Some(10));
        assert!(h.pop_due(9).is_none());
        assert_eq!(h.pop_due(10), Some(&[2u8][..]));
        assert_eq!(h.pop_due(10), Some(&[3u8][..]));
        assert!(h.pop_due(49).is_none());
        assert_eq!(h.pop_due(100), Some(&[1u8][..]));
        assert_eq!(h.len(), 0);
        assert_eq!(h.next_due(), None);
    }

    #[test]
    fn undelayed_and_delayed_interleave_by_due_time() {
        let mut h = HeldReplies::new(4);
        let put = |h: &mut HeldReplies, b: u8, due: u64, delayed: bool| {
            let (i, s) = h.free_slot().unwrap();
            s[0] = b;
            h.commit(i, 1, due, delayed);
        };
        put(&mut h, 1, 100, true); // sent at 0, due at 100
        put(&mut h, 2, 10, false);
        put(&mut h, 3, 20, false);
        put(&mut h, 4, 15, true);
        assert_eq!(h.due_count(20), 3);
        assert_eq!(h.pop_due(200), Some(&[2u8][..]));
        assert_eq!(h.pop_due(200), Some(&[4u8][..]));
        assert_eq!(h.pop_due(200), Some(&[3u8][..]));
        assert_eq!(h.pop_due(200), Some(&[1u8][..]));
        assert_eq!(h.pop_due(200), None);
        // Buffers are reused.
        for b in 0..4 {
            put(&mut h, b, 300, false);
        }
        assert!(h.free_slot().is_none());
        assert_eq!(h.len(), 4);
    }
}
