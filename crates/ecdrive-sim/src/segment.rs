//! A line of emulated slaves in one process: every frame passes through each slave in order and
//! comes back, as on a real EtherCAT line.
//!
//! [`Segment::process`] takes one Ethernet frame in place, runs every datagram through the
//! slaves, sets the locally-administered bit in the source MAC (as the first real ESC does) and
//! returns the reply length. It allocates nothing per frame and makes no syscalls beyond reading
//! the [`Clock`], so a master's cycle thread can call it directly.
//!
//! Processing is datagram-major (each datagram through all slaves, then the next), which gives
//! the same result as a real line because slaves share no state. Addressing is by lookup where
//! possible: auto-increment commands go straight to position `-ADP`, configured-address
//! commands through a sorted station-address index, so a 128-slave segment does not scan every
//! slave for every FPRD.
//!
//! Timing: the frame reaches slave `k` of `N` at `t + k·d` and passes its port 1 on the way back
//! at `t + (2N−1−k)·d` (`d` = [`SegmentConfig::hop_delay_ns`]), which is what the DC receive
//! time latches see. SYNC0 pulses and watchdogs are processed lazily and exactly: before a frame
//! is processed (and in [`Segment::poll`]), every SYNC0 instant that has passed at each slave is
//! delivered to its device in order.
//!
//! Injected faults ([`super::faults`]) are applied at the start of every frame and every
//! [`Segment::poll`]. Link faults act here, in front of the first slave, so that every
//! transport honours them: [`Segment::process_frame`] says whether a frame was lost (before
//! or after the slaves processed it) and when its reply is due; a corrupted reply is changed
//! in place after the slaves processed the frame.

use super::clock::Clock;
use super::device::Device;
use super::esc::{Esc, EscConfig, Hop};
use super::faults::{Corruption, Fate, Fault, LinkFault, LinkState, SlaveFault};
use super::sii::SiiError;
use crate::ec::Command;
use crate::ec::frame::{Datagram, EthercatFrame, EthernetFrame, FrameError};
use std::sync::Arc;

/// Settings of a segment.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SegmentConfig {
    /// Forwarding delay per slave in ns (port to port), used for DC receive times.
    pub hop_delay_ns: u32,
}

impl Default for SegmentConfig {
    fn default() -> Self {
        Self {
            hop_delay_ns: super::rec::HOP_DELAY_NS,
        }
    }
}

/// Why a frame produced no reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SegmentError {
    /// The frame is not a well-formed EtherCAT frame. Real slaves drop such frames and count
    /// them in the RX error counter of port 0 (0x0300), which the first slave does here too.
    #[error("frame dropped: {0}")]
    Frame(#[from] FrameError),
    /// The segment has no slaves, so nothing comes back.
    #[error("no slaves on the segment: the frame does not come back")]
    Empty,
    /// The frame was lost by an injected fault ([`LinkFault::DropFraction`] or
    /// [`LinkFault::DropNext`](super::faults::LinkFault::DropNext)).
    ///
    /// [`LinkFault::DropFraction`]: super::faults::LinkFault::DropFraction
    #[error("frame lost by an injected fault (the slaves processed it: {reached_slaves})")]
    Lost {
        /// Whether the slaves processed the frame before its reply was lost.
        reached_slaves: bool,
    },
    /// The cable is pulled ([`LinkFault::Disconnect`](super::faults::LinkFault::Disconnect)):
    /// the frame never reached the slaves.
    #[error("frame lost: the cable is pulled (injected fault)")]
    Disconnected,
}

/// A processed frame's reply, from [`Segment::process_frame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SegmentReply {
    /// Length of the reply (always the length of the frame).
    pub len: usize,
    /// Time on the segment's clock at which the reply reaches the master: the time the frame
    /// was processed, plus the delay of an injected [`LinkFault::Delay`]. A transport holds the
    /// reply until then.
    ///
    /// [`LinkFault::Delay`]: super::faults::LinkFault::Delay
    pub due_ns: u64,
    /// The injected delay (0: none).
    pub delay_ns: u64,
}

/// One slave: the ESC and the device application behind it.
pub struct Slave {
    /// The slave controller.
    pub esc: Esc,
    /// The device application.
    pub device: Box<dyn Device>,
}

impl core::fmt::Debug for Slave {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Slave")
            .field("station_address", &self.esc.station_address())
            .field("state", &self.esc.al_state())
            .finish_non_exhaustive()
    }
}

/// Counters of a segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct SegmentStats {
    /// Frames processed and returned (including delayed and corrupted ones).
    pub frames: u64,
    /// Datagrams processed.
    pub datagrams: u64,
    /// Frames dropped as malformed.
    pub invalid_frames: u64,
    /// Frames lost to an injected bit error on a cable
    /// ([`LinkFault::CrcErrorAt`](super::faults::LinkFault::CrcErrorAt)).
    pub crc_errors: u64,
    /// Frames lost by an injected drop ([`LinkFault::DropFraction`],
    /// [`LinkFault::DropNext`]), on either leg.
    ///
    /// [`LinkFault::DropFraction`]: super::faults::LinkFault::DropFraction
    /// [`LinkFault::DropNext`]: super::faults::LinkFault::DropNext
    pub dropped: u64,
    /// Of [`dropped`](Self::dropped), the frames lost on the way back (the slaves processed
    /// them).
    pub dropped_replies: u64,
    /// Replies delayed by an injected [`LinkFault::Delay`](super::faults::LinkFault::Delay).
    pub delayed: u64,
    /// Replies corrupted by an injected
    /// [`LinkFault::CorruptNext`](super::faults::LinkFault::CorruptNext).
    pub corrupted: u64,
    /// Frames that arrived while the cable was pulled
    /// ([`LinkFault::Disconnect`](super::faults::LinkFault::Disconnect)).
    pub lost_disconnected: u64,
    /// Faults applied.
    pub faults_applied: u64,
    /// Faults ignored: position out of range, or a device fault the device does not support
    /// (e.g. an alarm name the drive does not have, a CoE fault for a device without CoE).
    pub faults_ignored: u64,
}

/// A line of emulated slaves.
pub struct Segment {
    clock: Arc<dyn Clock>,
    cfg: SegmentConfig,
    slaves: Vec<Slave>,
    /// (station address, position), sorted.
    index: Vec<(u16, u16)>,
    index_dirty: bool,
    any_alias: bool,
    dirty: Vec<u16>,
    dirty_mark: Vec<bool>,
    scratch: Vec<u8>,
    earliest: Option<u64>,
    /// Boxed: keeps `Segment` small enough to move around by value.
    stats: Box<SegmentStats>,
    faults: Box<FaultState>,
}

/// Injected-fault state of a segment.
#[derive(Default)]
struct FaultState {
    rx: Option<rtrb::Consumer<Fault>>,
    link: LinkState,
}

impl core::fmt::Debug for Segment {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Segment")
            .field("slaves", &self.slaves)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Access {
    Read,
    Write,
    ReadWrite,
}

impl Segment {
    /// An empty segment on `clock`.
    pub fn new(clock: Arc<dyn Clock>) -> Self {
        Self::with_config(clock, SegmentConfig::default())
    }

    /// An empty segment with explicit settings.
    pub fn with_config(clock: Arc<dyn Clock>, cfg: SegmentConfig) -> Self {
        Self {
            clock,
            cfg,
            slaves: Vec::new(),
            index: Vec::new(),
            index_dirty: true,
            any_alias: false,
            dirty: Vec::new(),
            dirty_mark: Vec::new(),
            scratch: vec![0; crate::ec::frame::MAX_DATAGRAM_DATA],
            earliest: None,
            stats: Box::default(),
            faults: Box::default(),
        }
    }

    /// A handle to inject faults from another thread (see [`super::faults`]). A new handle
    /// replaces the previous one.
    pub fn fault_handle(&mut self) -> super::faults::FaultHandle {
        let (tx, rx) = rtrb::RingBuffer::new(super::faults::QUEUE);
        self.faults.rx = Some(rx);
        super::faults::FaultHandle { tx }
    }

    /// Apply the queued faults (allocation-free).
    fn apply_faults(&mut self) {
        while let Some(f) = self.faults.rx.as_mut().and_then(|rx| rx.pop().ok()) {
            self.apply(&f);
        }
    }

    /// Apply a fault now (see [`super::faults`]); the owner of the segment can call this
    /// directly instead of going through a [`FaultHandle`](super::faults::FaultHandle).
    /// Returns whether it was applied: `false` for a position out of range or a device fault
    /// the device does not support (counted in [`SegmentStats::faults_ignored`]).
    /// Allocation-free.
    pub fn apply(&mut self, fault: &Fault) -> bool {
        let now = self.clock.now_ns();
        let ok = match *fault {
            Fault::Device { position, fault } => self
                .slaves
                .get_mut(usize::from(position))
                .is_some_and(|s| s.device.inject(&fault)),
            Fault::Slave { position, fault } => match self.slaves.get_mut(usize::from(position)) {
                None => false,
                Some(s) => {
                    match fault {
                        SlaveFault::ResetToInit => {
                            // Time-driven work up to now happens before the reset.
                            s.esc.run_due(now, s.device.as_mut());
                            s.esc.local_reset(s.device.as_mut());
                        }
                        SlaveFault::ClockDrift(ppb) => {
                            s.esc.set_clock_drift(now, i64::from(ppb));
                            self.earliest = Some(now);
                        }
                    }
                    true
                }
            },
            Fault::Link(l) => {
                // A pulled cable is a lost link at the first device's port 0 (0x0310).
                if matches!(l, LinkFault::Disconnect) && !self.faults.link.disconnected() {
                    if let Some(s) = self.slaves.first_mut() {
                        s.esc.count_lost_link(0);
                    }
                }
                self.faults.link.apply(l);
                true
            }
        };
        if ok {
            self.stats.faults_applied += 1;
        } else {
            self.stats.faults_ignored += 1;
        }
        ok
    }

    /// Whether the cable is pulled ([`LinkFault::Disconnect`](super::faults::LinkFault)).
    pub fn is_disconnected(&self) -> bool {
        self.faults.link.disconnected()
    }

    /// Append a slave fronting `device` with the given ESC hardware at the end of the line.
    /// Returns its position.
    pub fn push(&mut self, device: Box<dyn Device>, cfg: EscConfig) -> Result<usize, SiiError> {
        let desc = device.description();
        let esc = Esc::new(&desc, cfg)?;
        Ok(self.push_slave(Slave { esc, device }))
    }

    /// Append a slave with default ESC hardware (DC, 8 FMMUs, 8 SMs, 8 KiB RAM, SM watchdog at
    /// its reset value of 100 ms).
    pub fn push_device(&mut self, device: Box<dyn Device>) -> Result<usize, SiiError> {
        self.push(device, EscConfig::default())
    }

    /// Append an already built slave.
    pub fn push_slave(&mut self, mut slave: Slave) -> usize {
        if let Some(prev) = self.slaves.last_mut() {
            prev.esc.set_topology(true);
        }
        slave.esc.set_topology(false);
        self.slaves.push(slave);
        self.dirty_mark.push(false);
        self.dirty.reserve(1);
        self.index.reserve(1);
        self.index_dirty = true;
        self.slaves.len() - 1
    }

    /// Number of slaves.
    pub fn len(&self) -> usize {
        self.slaves.len()
    }

    /// Whether the segment has no slaves.
    pub fn is_empty(&self) -> bool {
        self.slaves.is_empty()
    }

    /// The slave at `position`.
    pub fn slave(&self, position: usize) -> Option<&Slave> {
        self.slaves.get(position)
    }

    /// The slave at `position`, mutable.
    pub fn slave_mut(&mut self, position: usize) -> Option<&mut Slave> {
        self.slaves.get_mut(position)
    }

    /// Switch the slave at `position` off and on ([`Esc::power_cycle`]): its EEPROM keeps
    /// what was written to it. `false` if there is no such slave.
    pub fn power_cycle(&mut self, position: usize) -> bool {
        match self.slaves.get_mut(position) {
            Some(s) => {
                s.esc.power_cycle(s.device.as_mut());
                true
            }
            None => false,
        }
    }

    /// All slaves in line order.
    pub fn slaves(&self) -> &[Slave] {
        &self.slaves
    }

    /// The device at `position` as its concrete type.
    pub fn device<T: Device>(&self, position: usize) -> Option<&T> {
        self.slaves
            .get(position)
            .and_then(|s| s.device.as_any().downcast_ref::<T>())
    }

    /// The device at `position` as its concrete type, mutable.
    pub fn device_mut<T: Device>(&mut self, position: usize) -> Option<&mut T> {
        self.slaves
            .get_mut(position)
            .and_then(|s| s.device.as_any_mut().downcast_mut::<T>())
    }

    /// The clock.
    pub fn clock(&self) -> &Arc<dyn Clock> {
        &self.clock
    }

    /// Counters.
    pub fn stats(&self) -> SegmentStats {
        *self.stats
    }

    /// Host time at which [`poll`](Self::poll) has work (a SYNC0 pulse or a watchdog expiry),
    /// if any. Transports use it as their receive timeout.
    pub fn next_deadline(&self) -> Option<u64> {
        self.earliest
    }

    fn hop(&self, k: usize, t: u64) -> Hop {
        let n = self.slaves.len() as u64;
        let k = k as u64;
        let d = u64::from(self.cfg.hop_delay_ns);
        Hop {
            forward_ns: t.saturating_add(k * d),
            return_ns: if k + 1 < n {
                Some(t.saturating_add((2 * n - 1 - k) * d))
            } else {
                None
            },
        }
    }

    /// Deliver due SYNC0 pulses and apply expired watchdogs, without a frame (e.g. on a
    /// receive timeout, so that a pulled cable is noticed).
    ///
    /// Applies queued faults first, so that faults (e.g. a reconnect) take effect while no
    /// frames arrive.
    pub fn poll(&mut self) {
        self.apply_faults();
        let now = self.clock.now_ns();
        self.run_due(now, false);
    }

    fn run_due(&mut self, t: u64, frame: bool) {
        let n = self.slaves.len();
        let last = if frame && n > 0 {
            self.hop(n - 1, t).forward_ns
        } else {
            t
        };
        match self.earliest {
            Some(e) if last >= e => {}
            _ => return,
        }
        let mut earliest: Option<u64> = None;
        for k in 0..n {
            let hop = if frame { self.hop(k, t) } else { Hop::at(t) };
            let Some(s) = self.slaves.get_mut(k) else {
                break;
            };
            s.esc.run_due(hop.forward_ns, s.device.as_mut());
            if s.esc.has_pending() {
                s.esc.end_of_frame(hop, s.device.as_mut());
            }
            if let Some(d) = s.esc.next_deadline(hop.forward_ns) {
                earliest = Some(earliest.map_or(d, |e: u64| e.min(d)));
            }
        }
        self.earliest = earliest;
    }

    fn rebuild_index(&mut self) {
        self.index.clear();
        self.any_alias = false;
        for (k, s) in self.slaves.iter().enumerate() {
            self.index.push((s.esc.station_address(), k as u16));
            self.any_alias |= s.esc.alias_enabled();
        }
        self.index.sort_unstable();
        self.index_dirty = false;
    }

    /// Process one Ethernet frame in place and return the length of the reply (always the
    /// length of the frame: slaves never change a frame's size).
    ///
    /// Injected link faults apply (a lost frame is an error, a corrupted one is returned
    /// corrupted), except [`LinkFault::Delay`](super::faults::LinkFault::Delay): the reply is
    /// returned at once. Transports use [`process_frame`](Self::process_frame), which reports
    /// the delay.
    pub fn process(&mut self, frame: &mut [u8]) -> Result<usize, SegmentError> {
        self.process_frame(frame).map(|r| r.len)
    }

    /// Process one Ethernet frame in place, with injected link faults: returns the reply's
    /// length and when it reaches the master, or why no reply comes back
    /// ([`SegmentError::Lost`], [`SegmentError::Disconnected`] for injected faults).
    pub fn process_frame(&mut self, frame: &mut [u8]) -> Result<SegmentReply, SegmentError> {
        if self.slaves.is_empty() {
            return Err(SegmentError::Empty);
        }
        self.apply_faults();
        let now = self.clock.now_ns();
        let (delay_ns, corrupt, lose_reply) = match self.faults.link.fate() {
            Fate::Pass { delay_ns, corrupt } => (delay_ns, corrupt, false),
            Fate::LostReturn => (0, None, true),
            Fate::LostOutbound => {
                self.stats.dropped += 1;
                self.run_due(now, false);
                return Err(SegmentError::Lost {
                    reached_slaves: false,
                });
            }
            Fate::Disconnected => {
                self.stats.lost_disconnected += 1;
                self.run_due(now, false);
                return Err(SegmentError::Disconnected);
            }
            Fate::CrcError(at) => {
                self.run_due(now, false);
                let at = usize::from(at);
                if at >= self.slaves.len() {
                    return self.process_frame(frame);
                }
                self.stats.crc_errors += 1;
                for (k, s) in self.slaves.iter_mut().enumerate() {
                    if k == at {
                        s.esc.count_rx_error(0);
                    } else if k > at {
                        s.esc.count_forwarded_error(0);
                    }
                    if s.esc.port1_open() {
                        s.esc.count_forwarded_error(1);
                    }
                }
                return Err(SegmentError::Lost {
                    reached_slaves: false,
                });
            }
        };
        let len = frame.len();
        let mut eth = EthernetFrame::new_checked(&mut *frame)?;
        let valid = EthercatFrame::new_checked(eth.payload_mut()).and_then(|f| f.check());
        if let Err(e) = valid {
            self.stats.invalid_frames += 1;
            if let Some(s) = self.slaves.first_mut() {
                s.esc.count_invalid_frame();
            }
            return Err(e.into());
        }
        self.run_due(now, true);
        {
            let mut ec = EthercatFrame::new_checked(eth.payload_mut())?;
            for d in ec.datagrams_mut() {
                let mut d = d?;
                self.datagram(&mut d, now);
                self.stats.datagrams += 1;
            }
        }
        // The PDI reacts after the frame has passed.
        for i in 0..self.dirty.len() {
            let Some(&k) = self.dirty.get(i) else { break };
            let k = usize::from(k);
            let hop = self.hop(k, now);
            if let Some(s) = self.slaves.get_mut(k) {
                if s.esc.end_of_frame(hop, s.device.as_mut()) {
                    if let Some(d) = s.esc.next_deadline(hop.forward_ns) {
                        self.earliest = Some(self.earliest.map_or(d, |e| e.min(d)));
                    }
                }
            }
            if let Some(m) = self.dirty_mark.get_mut(k) {
                *m = false;
            }
        }
        self.dirty.clear();
        eth.mark_forwarded();
        if lose_reply {
            self.stats.dropped += 1;
            self.stats.dropped_replies += 1;
            return Err(SegmentError::Lost {
                reached_slaves: true,
            });
        }
        if let Some(c) = corrupt {
            if corrupt_first_datagram(eth.payload_mut(), c) {
                self.stats.corrupted += 1;
            }
        }
        if delay_ns > 0 {
            self.stats.delayed += 1;
        }
        self.stats.frames += 1;
        Ok(SegmentReply {
            len,
            due_ns: now.saturating_add(delay_ns),
            delay_ns,
        })
    }

    fn touched(&mut self, k: usize) {
        let Some(s) = self.slaves.get_mut(k) else {
            return;
        };
        if s.esc.take_address_changed() {
            self.index_dirty = true;
        }
        if s.esc.has_pending() {
            if let Some(m) = self.dirty_mark.get_mut(k) {
                if !*m {
                    *m = true;
                    self.dirty.push(k as u16);
                }
            }
        }
    }

    /// A physical access at slave `k`; returns the working counter increment.
    fn physical(
        &mut self,
        k: usize,
        access: Access,
        or: bool,
        ado: u16,
        data: &mut [u8],
        t: u64,
    ) -> u16 {
        let hop = self.hop(k, t);
        let Some(s) = self.slaves.get_mut(k) else {
            return 0;
        };
        let inc = match access {
            Access::Read => u16::from(s.esc.ecat_read(ado, data, or, hop)),
            Access::Write => u16::from(s.esc.ecat_write(ado, data, hop, s.device.as_mut())),
            Access::ReadWrite => {
                let Some(tmp) = self.scratch.get_mut(..data.len()) else {
                    return 0;
                };
                tmp.copy_from_slice(data);
                let r = s.esc.ecat_read(ado, data, or, hop);
                let w = s.esc.ecat_write(ado, tmp, hop, s.device.as_mut());
                u16::from(r) + 2 * u16::from(w)
            }
        };
        self.touched(k);
        inc
    }

    fn fp_match(&self, k: usize, addr: u16) -> bool {
        self.slaves.get(k).is_some_and(|s| {
            s.esc.station_address() == addr
                || (s.esc.alias_enabled() && s.esc.station_alias() == addr)
        })
    }

    fn datagram(&mut self, d: &mut Datagram<&mut [u8]>, t: u64) {
        let Some(cmd) = d.command() else {
            // Reserved command codes pass unprocessed.
            return;
        };
        let n = self.slaves.len();
        let mut wkc = d.wkc();
        let adp = d.adp();
        let ado = d.ado();
        let laddr = d.logical_address();
        let data = d.data_mut();
        match cmd {
            Command::Nop => {}
            Command::Aprd | Command::Apwr | Command::Aprw => {
                let k = usize::from(0u16.wrapping_sub(adp));
                if k < n {
                    let access = match cmd {
                        Command::Aprd => Access::Read,
                        Command::Apwr => Access::Write,
                        _ => Access::ReadWrite,
                    };
                    wkc = wkc.wrapping_add(self.physical(k, access, false, ado, data, t));
                }
            }
            Command::Armw => {
                let target = usize::from(0u16.wrapping_sub(adp));
                for k in 0..n {
                    let access = if k == target {
                        Access::Read
                    } else {
                        Access::Write
                    };
                    wkc = wkc.wrapping_add(self.physical(k, access, false, ado, data, t));
                }
            }
            Command::Fprd | Command::Fpwr | Command::Fprw => {
                let access = match cmd {
                    Command::Fprd => Access::Read,
                    Command::Fpwr => Access::Write,
                    _ => Access::ReadWrite,
                };
                if self.index_dirty {
                    self.rebuild_index();
                }
                if self.any_alias {
                    for k in 0..n {
                        if self.fp_match(k, adp) {
                            wkc = wkc.wrapping_add(self.physical(k, access, false, ado, data, t));
                        }
                    }
                } else {
                    let first = self.index.partition_point(|&(a, _)| a < adp);
                    let mut i = first;
                    while let Some(&(a, k)) = self.index.get(i) {
                        if a != adp {
                            break;
                        }
                        wkc = wkc.wrapping_add(self.physical(
                            usize::from(k),
                            access,
                            false,
                            ado,
                            data,
                            t,
                        ));
                        i += 1;
                        if self.index_dirty {
                            // The access changed a station address; finish with a fresh index.
                            break;
                        }
                    }
                }
            }
            Command::Frmw => {
                for k in 0..n {
                    let access = if self.fp_match(k, adp) {
                        Access::Read
                    } else {
                        Access::Write
                    };
                    wkc = wkc.wrapping_add(self.physical(k, access, false, ado, data, t));
                }
            }
            Command::Brd | Command::Bwr | Command::Brw => {
                let (access, or) = match cmd {
                    Command::Brd => (Access::Read, true),
                    Command::Bwr => (Access::Write, false),
                    _ => (Access::ReadWrite, true),
                };
                for k in 0..n {
                    wkc = wkc.wrapping_add(self.physical(k, access, or, ado, data, t));
                }
            }
            Command::Lrd | Command::Lwr | Command::Lrw => {
                for k in 0..n {
                    let hop = self.hop(k, t);
                    let Some(s) = self.slaves.get_mut(k) else {
                        break;
                    };
                    wkc = wkc.wrapping_add(s.esc.logical(cmd, laddr, data, hop, s.device.as_mut()));
                    if s.esc.take_address_changed() {
                        self.index_dirty = true;
                    }
                    if s.esc.has_pending() {
                        self.touched(k);
                    }
                }
            }
        }
        if cmd.increments_adp() {
            d.set_adp(adp.wrapping_add(n as u16));
        }
        d.set_wkc(wkc);
    }
}

/// Corrupt the first datagram of an EtherCAT frame payload (see [`Corruption`]). Returns
/// whether something was changed.
fn corrupt_first_datagram(payload: &mut [u8], c: Corruption) -> bool {
    use crate::ec::frame::{DATAGRAM_HEADER_LEN, ECAT_HEADER_LEN};
    let Some(d) = payload.get_mut(ECAT_HEADER_LEN..) else {
        return false;
    };
    let data_len = match (d.get(6), d.get(7)) {
        (Some(&lo), Some(&hi)) => usize::from(u16::from_le_bytes([lo, hi]) & 0x07FF),
        _ => return false,
    };
    let xor = |b: Option<&mut u8>, m: u8| match b {
        Some(b) => {
            *b ^= m;
            true
        }
        None => false,
    };
    match c {
        Corruption::WorkingCounter => xor(d.get_mut(DATAGRAM_HEADER_LEN + data_len + 1), 0x80),
        Corruption::Index => xor(d.get_mut(1), 0x80),
        Corruption::Command => xor(d.get_mut(0), 0x80),
        Corruption::Length => match d.get_mut(6..8) {
            Some([lo, hi]) => {
                *lo = 0xFF;
                *hi |= 0x07;
                true
            }
            _ => false,
        },
        Corruption::Data => match d.get_mut(DATAGRAM_HEADER_LEN..DATAGRAM_HEADER_LEN + data_len) {
            Some(data) if !data.is_empty() => {
                data.iter_mut().for_each(|b| *b ^= 0xFF);
                true
            }
            _ => false,
        },
    }
}
