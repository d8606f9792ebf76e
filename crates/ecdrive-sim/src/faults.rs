//! Fault injection into a running segment, from another thread, without locks.
//!
//! [`Segment::fault_handle`](super::Segment::fault_handle) returns a [`FaultHandle`]; faults
//! pushed into it travel through a wait-free ring buffer and are applied by the segment at the
//! start of the next frame it processes or the next [`poll`](super::Segment::poll), on whatever
//! thread runs it (the master's cycle thread when the segment is in-process). The owner of the
//! segment can also apply a fault directly with [`Segment::apply`](super::Segment::apply).
//! Applying a fault and everything it does on the frame path allocates nothing, so the cycle
//! stays clean while a test injects faults.
//!
//! Three kinds of faults:
//!
//! - [`LinkFault`]: the wire between the master and the first slave. Applied by the
//!   [`Segment`](super::Segment) itself, so every transport honours them
//!   ([`SegmentLink`](super::transport::SegmentLink), [`RawServer`](super::transport::RawServer)
//!   / [`serve`](super::transport::serve), [`EthercrabLink`](super::transport::EthercrabLink)).
//!   What each does on the wire is documented on its variant; the counters are in
//!   [`SegmentStats`](super::segment::SegmentStats).
//! - [`SlaveFault`]: one slave controller (ESC): a local restart to INIT, a drifting clock.
//! - [`DeviceFault`]: the device application behind one ESC: drive alarms, following error,
//!   emergencies, SDO aborts.
//!
//! Random choices (which frames [`LinkFault::DropFraction`] and [`LinkFault::Delay`] hit) come
//! from a seeded generator ([`LinkFault::Seed`], default [`DEFAULT_SEED`]): the same seed and
//! the same frame sequence give the same faults.

/// A fault for one device application.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DeviceFault {
    /// Raise the drive's alarm with this identifier (the drive's own name, e.g. `"AL.52"` for the
    /// MR-J4-TM, `"J3"` for the BDHDE).
    RaiseAlarm(&'static str),
    /// Force the following error the drive's model sees to this value, in position units
    /// (`None`: back to the model's own).
    ForceFollowingError(Option<i32>),
    /// Post an emergency message in the device's mailbox (delivered when SM1 is free).
    Emergency {
        /// Error code.
        error_code: u16,
        /// Error register.
        error_register: u8,
        /// Manufacturer bytes.
        data: [u8; 5],
    },
    /// Answer the next SDO request (upload or download initiate) to `index:subindex`
    /// (`subindex` `None`: any subindex) with an SDO abort carrying `code`, instead of serving
    /// it. One shot: the request after it is served normally. Segment requests of a transfer
    /// already running are not affected (they carry no index).
    AbortSdo {
        /// Object index.
        index: u16,
        /// Subindex, or `None` for any.
        subindex: Option<u8>,
        /// The abort code sent (any value, e.g. 0x0800_0022 "data cannot be transferred
        /// because of the present device state").
        code: u32,
    },
    /// During the next segmented SDO transfer (upload or download), post this emergency in the
    /// middle: the first segment request after the initiate is answered with the emergency
    /// (CoE service 1) instead of the segment response, and the segment response follows as
    /// the next mailbox message, as soon as the master has read the emergency. The transfer
    /// then continues and completes normally. One shot.
    ///
    /// This is a legal mailbox sequence (an emergency may come at any time) that some masters
    /// do not expect: ethercrab 0.7.1 asserts that an SDO reply is not an emergency.
    EmergencyDuringSdo {
        /// Error code.
        error_code: u16,
        /// Error register.
        error_register: u8,
        /// Manufacturer bytes.
        data: [u8; 5],
    },
}

/// A fault of one slave controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlaveFault {
    /// The slave falls back to INIT on its own, as after a local reset of its application
    /// controller: AL status INIT with the error bit (0x0130 = 0x0011) and AL status code
    /// 0x0060 "Slave restarted locally" (ETG.1000.6), station address, SyncManager and FMMU
    /// registers kept (the ESC itself was not reset), the mailbox stopped (queued messages
    /// and transfers in progress are lost), the process data SyncManagers deactivated by the
    /// PDI. The device sees the state change as a local error (a drive leaving OP with its
    /// motor energised switches its power stage off and raises its leave-OP alarm). A master
    /// must acknowledge the error and start the slave again (INIT → PRE-OP → SAFE-OP → OP).
    ResetToInit,
    /// From now on the slave's local clock runs this many ppb faster (positive) or slower
    /// (negative) than the host clock, replacing its previous drift. The local time stays
    /// continuous (no step); only its rate changes. The DC drift loop, if the master runs it,
    /// has to follow. The emulated loop's rate correction is limited to ±1000 ppm; its
    /// proportional steps (up to 1000 ppm of the time between two updates, but at least 200 ns
    /// per update, [`crate::rec`]) come on top, so a master updating every cycle keeps
    /// larger drifts in check too (about 2000 ppm with an update every millisecond, more with
    /// the back-to-back updates of static drift compensation); a 10 % drift cannot be
    /// followed. `ecdrive sim --drift` accepts ±1000 ppm, the range real oscillators stay far
    /// inside. Beyond ±2000 ppm a transport may also notice SYNC0 pulses late, though each is
    /// still delivered with its exact time.
    ClockDrift(i32),
}

/// Where a dropped frame is lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DropLeg {
    /// On the way to the slaves: no slave sees the frame (nothing written, no working counter,
    /// no watchdog retriggered) and nothing comes back.
    #[default]
    Outbound,
    /// On the way back: every slave processed the frame (outputs written, registers changed,
    /// mailbox requests taken) but the reply never reaches the master.
    Return,
}

/// What [`LinkFault::CorruptNext`] changes in the first datagram of a frame. Corruption is
/// applied to the reply, after the slaves processed the frame, so the slaves saw a good frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Corruption {
    /// The working counter XOR 0x8000: never the count the slaves produced.
    #[default]
    WorkingCounter,
    /// The datagram index (header byte 1) XOR 0x80: the reply no longer matches the request the
    /// master sent.
    Index,
    /// The command byte (header byte 0) XOR 0x80: a reserved command code, not the command the
    /// master sent.
    Command,
    /// The length field (11 bits of header bytes 6–7) set to 2047, its maximum: the datagram
    /// claims more data than any frame holds, so the frame no longer parses.
    Length,
    /// Every data byte inverted (XOR 0xFF); header and working counter intact. Only a master
    /// that checks content (e.g. a register it wrote) notices.
    Data,
}

/// A fault of the link between the master and the first slave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinkFault {
    /// Drop each frame with this probability (0.0–1.0, clamped) from now on; 0.0 ends it. The
    /// leg where frames are lost is set with [`LinkFault::DropOn`] (default: on the way to the
    /// slaves). Counted in `SegmentStats::dropped`.
    DropFraction(f32),
    /// Drop exactly the next `n` frames (on the leg set with [`LinkFault::DropOn`]), in
    /// addition to [`LinkFault::DropFraction`]. Added to what a previous one has left.
    DropNext(u32),
    /// Where frames dropped by [`LinkFault::DropFraction`] and [`LinkFault::DropNext`] are
    /// lost.
    DropOn(DropLeg),
    /// Delay the reply of a fraction (0.0–1.0, clamped) of frames by `delay_ns` on the segment's
    /// clock: the slaves process the frame on time; only the reply reaches the master late
    /// (the transport holds it until then). A fraction of 0.0 ends it. A reply the master has
    /// given up on arrives anyway, as a stale frame. Counted in `SegmentStats::delayed`.
    Delay {
        /// Probability per frame.
        fraction: f32,
        /// Delay of the reply in ns.
        delay_ns: u64,
    },
    /// Corrupt the first datagram of each of the next `n` frames, as set with
    /// [`LinkFault::CorruptWith`] (default: the working counter). Replaces a previous count.
    /// Counted in `SegmentStats::corrupted`.
    CorruptNext(u32),
    /// What [`LinkFault::CorruptNext`] corrupts.
    CorruptWith(Corruption),
    /// Cable pull: from now on no frame reaches the slaves and nothing is answered. The slaves
    /// stay powered: their clocks keep running, SYNC0 keeps firing (as the transports keep
    /// polling the segment), the SM watchdog expires (OP → SAFE-OP with AL status code
    /// 0x001B), the emulated drives detect the loss of cyclic data as their manuals say.
    /// Frames lost this way are counted in `SegmentStats::lost_disconnected`.
    Disconnect,
    /// The cable is back: frames reach the slaves again.
    Reconnect,
    /// A bit error on the cable into the device at `position` (its port 0) for each of the
    /// next `frames` frames, as silicon sees it: that device counts an RX error on port 0
    /// (0x0301), marks the frame, and every device after it counts a forwarded RX error on
    /// port 0 (0x0308), every device with port 1 open another on port 1 (0x0309) as the frame
    /// comes back; the frame is processed by no device (the model keeps it simple: silicon
    /// would let the devices before `position` process it) and never answered. Counted in
    /// `SegmentStats::crc_errors`. A position past the last device is ignored when the frame
    /// comes.
    CrcErrorAt {
        /// Position of the device whose incoming cable flips a bit.
        position: u16,
        /// Frames affected.
        frames: u32,
    },
    /// Restart the random generator with this seed.
    Seed(u64),
}

/// A fault to inject.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fault {
    /// A fault for the device at `position`.
    Device {
        /// Position on the segment.
        position: u16,
        /// The fault.
        fault: DeviceFault,
    },
    /// A fault of the slave controller at `position`.
    Slave {
        /// Position on the segment.
        position: u16,
        /// The fault.
        fault: SlaveFault,
    },
    /// A fault of the link.
    Link(LinkFault),
}

/// The injecting side. Send it to the thread that injects; the segment applies what it sends.
pub struct FaultHandle {
    pub(super) tx: rtrb::Producer<Fault>,
}

/// The queue is full (the segment is not processing frames).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the fault queue is full: the segment is not processing frames")]
pub struct FaultQueueFull;

impl FaultHandle {
    /// Queue a fault for the next frame (or the next poll of the segment).
    pub fn inject(&mut self, fault: Fault) -> Result<(), FaultQueueFull> {
        self.tx.push(fault).map_err(|_| FaultQueueFull)
    }
}

impl core::fmt::Debug for FaultHandle {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FaultHandle").finish_non_exhaustive()
    }
}

/// Capacity of the fault queue.
pub(super) const QUEUE: usize = 64;

/// \[REC\] Seed of the link-fault generator until [`LinkFault::Seed`] sets another.
pub const DEFAULT_SEED: u64 = 0x0ECD_5EED_0000_0001;

/// What the link does with one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Fate {
    /// Processed and answered.
    Pass {
        /// Reply held until this long after the frame arrived.
        delay_ns: u64,
        /// Corrupt the reply.
        corrupt: Option<Corruption>,
    },
    /// Lost before the slaves.
    LostOutbound,
    /// Processed, reply lost.
    LostReturn,
    /// Cable pulled.
    Disconnected,
    /// A bit error on the cable into this device.
    CrcError(u16),
}

/// The link-fault state of a segment. Allocation-free.
#[derive(Debug, Clone)]
pub(super) struct LinkState {
    rng: u64,
    /// Drop probability as a threshold on 32 random bits (2^32 = always).
    drop_threshold: u64,
    drop_next: u32,
    drop_leg: DropLeg,
    delay_threshold: u64,
    delay_ns: u64,
    corrupt_next: u32,
    corruption: Corruption,
    disconnected: bool,
    crc_at: u16,
    crc_next: u32,
}

impl Default for LinkState {
    fn default() -> Self {
        Self {
            rng: DEFAULT_SEED,
            drop_threshold: 0,
            drop_next: 0,
            drop_leg: DropLeg::Outbound,
            delay_threshold: 0,
            delay_ns: 0,
            corrupt_next: 0,
            corruption: Corruption::WorkingCounter,
            disconnected: false,
            crc_at: 0,
            crc_next: 0,
        }
    }
}

/// A probability as a threshold on 32 random bits; NaN counts as 0.
fn threshold(p: f32) -> u64 {
    let p = if p.is_nan() { 0.0 } else { p.clamp(0.0, 1.0) };
    (f64::from(p) * 4_294_967_296.0).round() as u64
}

impl LinkState {
    pub(super) fn apply(&mut self, f: LinkFault) {
        match f {
            LinkFault::DropFraction(p) => self.drop_threshold = threshold(p),
            // Added to what is still to be dropped: two injections drop both counts.
            LinkFault::DropNext(n) => self.drop_next = self.drop_next.saturating_add(n),
            LinkFault::DropOn(leg) => self.drop_leg = leg,
            LinkFault::Delay { fraction, delay_ns } => {
                self.delay_threshold = threshold(fraction);
                self.delay_ns = delay_ns;
            }
            LinkFault::CorruptNext(n) => self.corrupt_next = n,
            LinkFault::CorruptWith(c) => self.corruption = c,
            LinkFault::Disconnect => self.disconnected = true,
            LinkFault::Reconnect => self.disconnected = false,
            LinkFault::CrcErrorAt { position, frames } => {
                self.crc_at = position;
                self.crc_next = frames;
            }
            LinkFault::Seed(s) => self.rng = s,
        }
    }

    pub(super) fn disconnected(&self) -> bool {
        self.disconnected
    }

    /// SplitMix64: small, fast, well distributed, and any seed (even 0) works.
    fn next_u32(&mut self) -> u64 {
        self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) >> 32
    }

    fn chance(&mut self, threshold: u64) -> bool {
        // No draw when the fault is off, so turning one fault on does not change which frames
        // another one hits.
        threshold != 0 && self.next_u32() < threshold
    }

    /// Decide the fate of the next frame.
    pub(super) fn fate(&mut self) -> Fate {
        if self.disconnected {
            return Fate::Disconnected;
        }
        if self.crc_next > 0 {
            self.crc_next -= 1;
            return Fate::CrcError(self.crc_at);
        }
        let mut drop = self.chance(self.drop_threshold);
        if self.drop_next > 0 {
            self.drop_next -= 1;
            drop = true;
        }
        if drop {
            return match self.drop_leg {
                DropLeg::Outbound => Fate::LostOutbound,
                DropLeg::Return => Fate::LostReturn,
            };
        }
        let delay_ns = if self.chance(self.delay_threshold) {
            self.delay_ns
        } else {
            0
        };
        let corrupt = if self.corrupt_next > 0 {
            self.corrupt_next -= 1;
            Some(self.corruption)
        } else {
            None
        };
        Fate::Pass { delay_ns, corrupt }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_cover_the_whole_range() {
        assert_eq!(threshold(0.0), 0);
        assert_eq!(threshold(1.0), 1 << 32);
        assert_eq!(threshold(2.0), 1 << 32);
        assert_eq!(threshold(-1.0), 0);
        assert_eq!(threshold(f32::NAN), 0);
        assert_eq!(threshold(0.5), 1 << 31);
    }

    #[test]
    fn always_and_never() {
        let mut s = LinkState::default();
        s.apply(LinkFault::DropFraction(1.0));
        assert!((0..1000).all(|_| s.fate() == Fate::LostOutbound));
        s.apply(LinkFault::DropFraction(0.0));
        assert!((0..1000).all(|_| matches!(s.fate(), Fate::Pass { delay_ns: 0, .. })));
    }

    #[test]
    fn same_seed_same_fates() {
        let run = |seed| {
            let mut s = LinkState::default();
            s.apply(LinkFault::Seed(seed));
            s.apply(LinkFault::DropFraction(0.3));
            (0..200).map(|_| s.fate()).collect::<Vec<_>>()
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
    }
}
