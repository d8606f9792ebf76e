//! Replies held by a transport until they are due (injected link delay), in buffers allocated
//! once.

use crate::ec::frame::MAX_FRAME_LEN;

/// A fixed set of reply buffers, each with the time it is due. Replies come out earliest due
/// first, in the order they went in among equal times.
#[derive(Debug)]
pub(crate) struct HeldReplies {
    slots: Vec<[u8; MAX_FRAME_LEN]>,
    lens: Vec<usize>,
    due: Vec<u64>,
    seq: Vec<u64>,
    used: Vec<bool>,
    count: usize,
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
            used: vec![false; capacity],
            count: 0,
            next_seq: 0,
        }
    }

    /// Replies held.
    pub(crate) fn len(&self) -> usize {
        self.count
    }

    /// A free buffer, to fill and then [`commit`](Self::commit).
    pub(crate) fn free_slot(&mut self) -> Option<(usize, &mut [u8; MAX_FRAME_LEN])> {
        let i = self.used.iter().position(|u| !u)?;
        self.slots.get_mut(i).map(|s| (i, s))
    }

    /// Hold the first `len` bytes of slot `i` until `due`.
    pub(crate) fn commit(&mut self, i: usize, len: usize, due: u64) {
        if let (Some(u), Some(l), Some(d), Some(s)) = (
            self.used.get_mut(i),
            self.lens.get_mut(i),
            self.due.get_mut(i),
            self.seq.get_mut(i),
        ) {
            if !*u {
                *u = true;
                self.count += 1;
            }
            *l = len;
            *d = due;
            *s = self.next_seq;
            self.next_seq += 1;
        }
    }

    /// Copy `frame` in and hold it until `due`; `false` if every buffer is taken or the frame
    /// is too large.
    pub(crate) fn push(&mut self, frame: &[u8], due: u64) -> bool {
        let Some((i, slot)) = self.free_slot() else {
            return false;
        };
        let Some(dst) = slot.get_mut(..frame.len()) else {
            return false;
        };
        dst.copy_from_slice(frame);
        self.commit(i, frame.len(), due);
        true
    }

    /// Replies held that are due at `now`.
    pub(crate) fn due_count(&self, now: u64) -> usize {
        self.used
            .iter()
            .zip(&self.due)
            .filter(|&(&u, &d)| u && d <= now)
            .count()
    }

    /// The earliest due time held.
    pub(crate) fn next_due(&self) -> Option<u64> {
        (0..self.used.len())
            .filter(|&i| self.used.get(i).copied().unwrap_or(false))
            .filter_map(|i| self.due.get(i).copied())
            .min()
    }

    /// Take the reply due first if it is due at `now`: the buffer stays valid until the next
    /// [`free_slot`](Self::free_slot) / [`push`](Self::push).
    pub(crate) fn pop_due(&mut self, now: u64) -> Option<&[u8]> {
        let mut best: Option<(u64, u64, usize)> = None;
        for i in 0..self.used.len() {
            if !self.used.get(i).copied().unwrap_or(false) {
                continue;
            }
            let (Some(&d), Some(&s)) = (self.due.get(i), self.seq.get(i)) else {
                continue;
            };
            if d <= now && best.is_none_or(|(bd, bs, _)| (d, s) < (bd, bs)) {
                best = Some((d, s, i));
            }
        }
        let (_, _, i) = best?;
        if let Some(u) = self.used.get_mut(i) {
            *u = false;
        }
        self.count -= 1;
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
}
