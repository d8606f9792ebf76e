//! The master's error/event history: every entry is counted by kind for the whole run, and the
//! latest [`HistoryLog::DEFAULT_CAPACITY`] (or a configured number of) entries are kept. A long
//! run with a bad cable does not grow the memory without bound, and a reader that polls takes
//! only what is new ([`HistorySlice`]), so that polling costs the same after a week as after a
//! minute.
//!
//! Entries are typed ([`HistoryEvent`]: the cycle's own [`EventKind`], or what the session
//! noted around it) and carry what their words need, resolved when they were recorded
//! ([`Resolved`]: names, the drive's alarm text, user units). They are put in words only at
//! the edge, by [`HistoryEntry::text`] (`render`), for the command line and the JSON.

mod render;

use super::error::DriveRef;
use super::startup::UserUnits;
use crate::cia402::{self, ErrorDescription};
use crate::telemetry::EventKind;
use std::collections::{BTreeMap, VecDeque};

/// An entry of the error/event history.
#[derive(Debug, Clone, PartialEq)]
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
    /// What happened, typed.
    pub event: HistoryEvent,
    /// What putting the event in words needs beyond the event, resolved when it was recorded.
    pub resolved: Resolved,
}

impl HistoryEntry {
    /// An entry of `event`, its kind and whether it is an error taken from the event.
    pub fn new(
        time_ns: u64,
        cycle: Option<u64>,
        drive: Option<DriveRef>,
        event: HistoryEvent,
        resolved: Resolved,
    ) -> Self {
        Self {
            time_ns,
            cycle,
            drive,
            error: event.is_error(),
            kind: event.kind(),
            event,
            resolved,
        }
    }

    /// What happened, in words (the drive concerned is [`HistoryEntry::drive`], not repeated).
    pub fn text(&self) -> String {
        render::text(&self.event, &self.resolved)
    }

    /// The cycle's event, if the entry is one.
    pub fn cycle_event(&self) -> Option<&EventKind> {
        match &self.event {
            HistoryEvent::Cycle(e) => Some(e),
            _ => None,
        }
    }

    /// The CiA 402 engine's event of an axis, if the entry is one.
    pub fn axis_event(&self) -> Option<cia402::Event> {
        match self.event {
            HistoryEvent::Cycle(EventKind::Axis { event, .. }) => Some(event),
            _ => None,
        }
    }
}

impl std::fmt::Display for HistoryEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text())
    }
}

/// As JSON: the entry's fields, the typed event, and its words (`text`).
impl serde::Serialize for HistoryEntry {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("HistoryEntry", 7)?;
        st.serialize_field("time_ns", &self.time_ns)?;
        st.serialize_field("cycle", &self.cycle)?;
        st.serialize_field("drive", &self.drive)?;
        st.serialize_field("error", &self.error)?;
        st.serialize_field("kind", &self.kind)?;
        st.serialize_field("event", &self.event)?;
        st.serialize_field("text", &self.text())?;
        st.end()
    }
}

/// What an entry of the history records.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HistoryEvent {
    /// An event of the cycle, as the cycle reported it (axes and devices by index; the entry's
    /// [`HistoryEntry::drive`] names the one concerned).
    Cycle(EventKind),
    /// An emergency message (CoE EMCY) from a drive.
    Emergency {
        /// Error code (0x603F's code space; 0x0000: error reset or no error).
        error_code: u16,
        /// Error register (0x1001).
        error_register: u8,
    },
    /// A warning of start-up or of the real-time set-up, as its stage wrote it.
    Warning(String),
    /// Re-start progress.
    Restart(RestartNote),
    /// A command came while no cycle ran and was not carried out.
    NoCycle {
        /// The command, as it reads.
        command: String,
    },
    /// The cycle thread could not be started.
    CycleThreadFailed(String),
}

impl HistoryEvent {
    /// Whether the event is a fault or error (as opposed to information).
    pub fn is_error(&self) -> bool {
        match self {
            Self::Cycle(e) => cycle_error(e),
            Self::Emergency { error_code, .. } => *error_code != 0,
            Self::Warning(_) => false,
            Self::Restart(n) => matches!(
                n,
                RestartNote::AttemptFailed { .. } | RestartNote::GivingUp { .. }
            ),
            Self::NoCycle { .. } | Self::CycleThreadFailed(_) => true,
        }
    }

    /// The event's category.
    pub fn kind(&self) -> HistoryKind {
        match self {
            Self::Cycle(e) => cycle_kind(e),
            Self::Emergency { .. } => HistoryKind::Emergency,
            Self::Warning(_) => HistoryKind::Warning,
            Self::Restart(_) => HistoryKind::Restart,
            Self::NoCycle { .. } => HistoryKind::NoCycle,
            Self::CycleThreadFailed(_) => HistoryKind::Session,
        }
    }
}

/// Re-start progress (see `MasterConfig::restart`).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RestartNote {
    /// A re-start was requested while the cycle ran.
    Requested,
    /// The cycle ended; the session waits for `Master::restart`.
    WaitingForRequest,
    /// The cycle ended; the session re-starts by itself, trying every `retry_every_ms`.
    Automatic {
        /// Milliseconds between attempts.
        retry_every_ms: u64,
    },
    /// An attempt failed.
    AttemptFailed {
        /// Attempts failed so far.
        attempt: u32,
        /// Why, as start-up said it.
        error: String,
    },
    /// Automatic attempts were given up; a request can still re-start.
    GivingUp {
        /// Attempts failed.
        failures: u32,
    },
    /// The segment answers with the same drives; they are being taken to OP.
    SameDrives {
        /// How many.
        drives: usize,
    },
    /// Every drive is back in OP.
    BackInOp {
        /// The re-start's number (1 = the first).
        restart: u32,
    },
}

/// What putting an event in words needs beyond the event, resolved by the session when it
/// recorded it (the event itself names axes and devices by index).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Resolved {
    /// Every drive of the segment, for the events that concern all of them (a lost frame,
    /// a silent segment).
    pub drives: Vec<DriveRef>,
    /// A fault or emergency code in the drive's own words (its alarm table).
    pub fault: Option<ErrorDescription>,
    /// The axis's user units, for positions and following errors.
    pub units: Option<UserUnits>,
    /// The drive or device a stop reason names.
    pub subject: Option<DriveRef>,
}

/// Whether an event of the cycle is an error.
fn cycle_error(e: &EventKind) -> bool {
    match *e {
        EventKind::Axis { event, .. } => matches!(
            event,
            cia402::Event::Fault { .. }
                | cia402::Event::PlannerFailed(_)
                | cia402::Event::ModeSwitchFailed(_)
                | cia402::Event::ModeDisplayMismatch { .. }
        ),
        EventKind::OutputsNotTaken { io, .. } => !io,
        // A state with the error indication bit (0x10), except the bootstrap state (8).
        EventKind::AlState { state, .. } => state != 8 && state & 0x10 != 0,
        EventKind::OpTimeout { .. }
        | EventKind::WorkingCounter { .. }
        | EventKind::FrameLost { .. }
        | EventKind::SegmentGone { .. }
        | EventKind::LeftOp { .. }
        | EventKind::SegmentLost { .. }
        | EventKind::FollowingError { .. }
        | EventKind::CommandRefused { .. }
        | EventKind::HomingFailed { .. }
        | EventKind::ProbeNotLatched { .. }
        | EventKind::SetpointLimit { .. } => true,
        EventKind::AllOp
        | EventKind::FramesResumed { .. }
        | EventKind::DriveFollowingErrorStuck { .. }
        | EventKind::ProgramStep { .. }
        | EventKind::ProgramDone { .. }
        | EventKind::ProbeLatched { .. }
        | EventKind::StreamUnderrun { .. }
        | EventKind::Stopping { .. }
        | EventKind::Stopped => false,
    }
}

/// The history category of an event of the cycle.
fn cycle_kind(kind: &EventKind) -> HistoryKind {
    match *kind {
        EventKind::AllOp
        | EventKind::AlState { .. }
        | EventKind::ProgramStep { .. }
        | EventKind::ProgramDone { .. } => HistoryKind::Info,
        EventKind::OpTimeout { .. } | EventKind::LeftOp { .. } => HistoryKind::AlState,
        EventKind::Axis { event, .. } => match event {
            cia402::Event::Fault { .. } => HistoryKind::DriveFault,
            cia402::Event::PlannerFailed(_)
            | cia402::Event::ModeSwitchFailed(_)
            | cia402::Event::ModeDisplayMismatch { .. } => HistoryKind::StateMachine,
            cia402::Event::WarningChanged(_) => HistoryKind::Warning,
            _ => HistoryKind::Info,
        },
        EventKind::WorkingCounter { .. } | EventKind::OutputsNotTaken { .. } => {
            HistoryKind::WorkingCounter
        }
        EventKind::FrameLost { .. } | EventKind::FramesResumed { .. } => HistoryKind::FrameLost,
        EventKind::SegmentLost { .. } | EventKind::SegmentGone { .. } => HistoryKind::SegmentLost,
        EventKind::FollowingError { .. } => HistoryKind::FollowingError,
        EventKind::DriveFollowingErrorStuck { .. } => HistoryKind::Warning,
        EventKind::CommandRefused { .. } => HistoryKind::CommandRefused,
        EventKind::HomingFailed { .. } => HistoryKind::Homing,
        EventKind::ProbeLatched { .. } | EventKind::ProbeNotLatched { .. } => HistoryKind::Probe,
        EventKind::SetpointLimit { .. } => HistoryKind::CommandRefused,
        EventKind::StreamUnderrun { .. } => HistoryKind::Warning,
        EventKind::Stopping { .. } | EventKind::Stopped => HistoryKind::Stopping,
    }
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

    /// An entry of `kind` whose text is `text` (a warning, or a cycle event of the kind).
    fn entry(kind: HistoryKind, text: &str) -> HistoryEntry {
        let mut e = HistoryEntry::new(
            0,
            None,
            None,
            HistoryEvent::Warning(text.into()),
            Resolved::default(),
        );
        e.kind = kind;
        e
    }

    #[test]
    fn keeps_the_latest_and_counts_all() {
        let mut h = HistoryLog::new(3);
        for i in 0..5 {
            h.push(entry(HistoryKind::FrameLost, &i.to_string()));
        }
        h.push(entry(HistoryKind::DriveFault, "5"));
        let texts: Vec<String> = h.entries().into_iter().map(|e| e.text()).collect();
        assert_eq!(texts, ["warning: 3", "warning: 4", "warning: 5"]);
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
        assert_eq!(s.entries[0].text(), "warning: 4");
        // Asking beyond the end gives nothing and misses nothing.
        let s = h.since(100);
        assert!(s.entries.is_empty());
        assert_eq!((s.first, s.next, s.missed), (7, 7, 0));
    }
}
