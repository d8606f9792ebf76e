//! The master's error/event history: every entry is counted by kind for the whole run, and the
//! latest [`HistoryLog::DEFAULT_CAPACITY`] (or a configured number of) entries are kept with
//! their text. A long run with a bad cable does not grow the memory without bound, and a
//! reader that polls takes only what is new ([`HistorySlice`]), so that polling costs the same
//! after a week as after a minute.

use super::error::DriveRef;
use std::collections::{BTreeMap, VecDeque};

/// An entry of the error/event history.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HistoryEntry {
    /// `CLOCK_MONOTONIC` time, ns.
    pub time_ns: u64,
    /// Cycle number, if it came from the cycle.
    pub cycle: Option<u64>,
    /// The drive, if it concerns one.
    pub drive: Option<DriveRef>,
    /// Whether it is a fault or error (as opposed to information).
    pub error: bool,
    /// What kind of entry it is, for programs that react to the history.
    pub kind: HistoryKind,
    /// What happened, readable.
    pub text: String,
}

/// The kind of a [`HistoryEntry`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum HistoryKind {
    /// Progress: AL and CiA 402 state changes, OP reached, program steps, mode switches.
    Info,
    /// A warning (real-time set-up, a drive's warning bit).
    Warning,
    /// A cycle without a reply (the axes held their set-points) or replies resuming.
    FrameLost,
    /// The segment stopped answering (cable pull detected) or stayed silent (cycle ended).
    SegmentLost,
    /// The working counter differed from the expected value.
    WorkingCounter,
    /// A drive left OP on its own (with its AL status code), or did not reach OP.
    AlState,
    /// A drive fault (CiA 402 Fault, decoded with the drive's alarm table).
    DriveFault,
    /// The master-side following-error monitor tripped.
    FollowingError,
    /// The CiA 402 state machine or a mode switch failed.
    StateMachine,
    /// A command was refused.
    CommandRefused,
    /// A program's home step failed (the drive's report named).
    Homing,
    /// A touch probe latched (the position, in the user's units where configured).
    Probe,
    /// A command came while no cycle ran (the cycle had ended, the session was waiting for or
    /// making a re-start) and was not carried out. A command sent on the last snapshot of a
    /// cycle that was ending lands here; send it again once the cycle runs.
    NoCycle,
    /// An emergency message from a drive.
    Emergency,
    /// The cycle began a controlled stop of the axes, or ended.
    Stopping,
    /// Re-start progress: requested, attempted, failed, back in OP.
    Restart,
    /// The session itself failed (a thread could not start).
    Session,
}

/// Entries of the history from a sequence number on (see [`HistoryLog::since`]).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct HistorySlice {
    /// The entries, oldest first.
    pub entries: Vec<HistoryEntry>,
    /// Sequence number of the first of `entries` (entries are numbered from 0 in the order
    /// they were recorded).
    pub first: u64,
    /// Sequence number the next entry will get: pass it to the next call.
    pub next: u64,
    /// Entries asked for that had already been discarded (the reader fell behind by more than
    /// the capacity). Their kinds are still in [`HistorySlice::totals`].
    pub missed: u64,
    /// Entries recorded per kind since the start, discarded ones included.
    pub totals: BTreeMap<HistoryKind, u64>,
}

/// The bounded history: the latest `capacity` entries, and totals per kind of all of them.
#[derive(Debug, Clone)]
pub struct HistoryLog {
    entries: VecDeque<HistoryEntry>,
    capacity: usize,
    /// Sequence number of `entries[0]`.
    first: u64,
    totals: BTreeMap<HistoryKind, u64>,
}

impl Default for HistoryLog {
    fn default() -> Self {
        Self::new(Self::DEFAULT_CAPACITY)
    }
}

impl HistoryLog {
    /// Entries kept by default: at 1 % frame loss and 1 ms cycles (about 20 entries a second)
    /// a good hour of history, a few tens of MB at most.
    pub const DEFAULT_CAPACITY: usize = 100_000;

    /// An empty history keeping the latest `capacity` entries (at least 1).
    pub fn new(capacity: usize) -> Self {
        Self {
            entries: VecDeque::new(),
            capacity: capacity.max(1),
            first: 0,
            totals: BTreeMap::new(),
        }
    }

    /// Record an entry; the oldest is discarded when the history is full.
    pub fn push(&mut self, e: HistoryEntry) {
        *self.totals.entry(e.kind).or_default() += 1;
        if self.entries.len() >= self.capacity {
            self.entries.pop_front();
            self.first += 1;
        }
        self.entries.push_back(e);
    }

    /// The entries kept, oldest first.
    pub fn entries(&self) -> Vec<HistoryEntry> {
        self.entries.iter().cloned().collect()
    }

    /// Entries recorded so far (kept or discarded).
    pub fn recorded(&self) -> u64 {
        self.first + self.entries.len() as u64
    }

    /// Entries discarded because the history was full.
    pub fn discarded(&self) -> u64 {
        self.first
    }

    /// Entries recorded per kind since the start.
    pub fn totals(&self) -> &BTreeMap<HistoryKind, u64> {
        &self.totals
    }

    /// The entries from sequence number `seq` on.
    pub fn since(&self, seq: u64) -> HistorySlice {
        let next = self.recorded();
        let from = seq.clamp(self.first, next);
        let skip = usize::try_from(from - self.first).unwrap_or(usize::MAX);
        HistorySlice {
            entries: self.entries.iter().skip(skip).cloned().collect(),
            first: from,
            next,
            missed: from.saturating_sub(seq.min(next)),
            totals: self.totals.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(kind: HistoryKind, text: &str) -> HistoryEntry {
        HistoryEntry {
            time_ns: 0,
            cycle: None,
            drive: None,
            error: false,
            kind,
            text: text.into(),
        }
    }

    #[test]
    fn keeps_the_latest_and_counts_all() {
        let mut h = HistoryLog::new(3);
        for i in 0..5 {
            h.push(entry(HistoryKind::FrameLost, &i.to_string()));
        }
        h.push(entry(HistoryKind::DriveFault, "5"));
        let texts: Vec<String> = h.entries().into_iter().map(|e| e.text).collect();
        assert_eq!(texts, ["3", "4", "5"]);
        assert_eq!(h.recorded(), 6);
        assert_eq!(h.discarded(), 3);
        assert_eq!(h.totals()[&HistoryKind::FrameLost], 5);
        assert_eq!(h.totals()[&HistoryKind::DriveFault], 1);
    }

    #[test]
    fn since_returns_only_what_is_new_and_says_what_was_missed() {
        let mut h = HistoryLog::new(3);
        for i in 0..2 {
            h.push(entry(HistoryKind::Info, &i.to_string()));
        }
        let s = h.since(0);
        assert_eq!((s.entries.len(), s.first, s.next, s.missed), (2, 0, 2, 0));
        let s = h.since(s.next);
        assert!(s.entries.is_empty());
        assert_eq!((s.first, s.next, s.missed), (2, 2, 0));
        for i in 2..7 {
            h.push(entry(HistoryKind::Info, &i.to_string()));
        }
        // Entries 2, 3 were discarded; 4, 5, 6 are kept.
        let s = h.since(2);
        assert_eq!(s.missed, 2);
        assert_eq!(s.first, 4);
        assert_eq!(s.next, 7);
        assert_eq!(s.entries[0].text, "4");
        // Asking beyond the end gives nothing and misses nothing.
        let s = h.since(100);
        assert!(s.entries.is_empty());
        assert_eq!((s.first, s.next, s.missed), (7, 7, 0));
    }
}
