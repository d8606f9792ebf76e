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

use super::clock::Clock;
use super::device::Device;
use super::esc::{Esc, EscConfig, Hop};
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SegmentStats {
    /// Frames processed and returned.
    pub frames: u64,
    /// Datagrams processed.
    pub datagrams: u64,
    /// Frames dropped as malformed.
    pub invalid_frames: u64,
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
    stats: SegmentStats,
    faults: Option<rtrb::Consumer<super::faults::Fault>>,
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
            stats: SegmentStats::default(),
            faults: None,
        }
    }

    /// A handle to inject faults from another thread (see [`super::faults`]). A new handle
    /// replaces the previous one.
    pub fn fault_handle(&mut self) -> super::faults::FaultHandle {
        let (tx, rx) = rtrb::RingBuffer::new(super::faults::QUEUE);
        self.faults = Some(rx);
        super::faults::FaultHandle { tx }
    }

    /// Apply the queued faults (allocation-free).
    fn apply_faults(&mut self) {
        let Some(rx) = self.faults.as_mut() else {
            return;
        };
        while let Ok(f) = rx.pop() {
            match f {
                super::faults::Fault::Device { position, fault } => {
                    if let Some(s) = self.slaves.get_mut(usize::from(position)) {
                        s.device.inject(&fault);
                    }
                }
            }
        }
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
        self.stats
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
    pub fn poll(&mut self) {
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
    pub fn process(&mut self, frame: &mut [u8]) -> Result<usize, SegmentError> {
        if self.slaves.is_empty() {
            return Err(SegmentError::Empty);
        }
        let now = self.clock.now_ns();
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
        self.apply_faults();
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
        self.stats.frames += 1;
        Ok(len)
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
