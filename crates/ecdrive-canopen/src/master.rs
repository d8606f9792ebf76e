//! The CANopen master (CiA 301 NMT master, SDO client, SYNC producer, EMCY consumer, heartbeat
//! consumer and node-guarding master) over any [`CanTransport`].
//!
//! Blocking operations (SDO transfers, boot-up waits, configuration) keep receiving while they
//! wait: every frame that arrives meanwhile — heartbeats, EMCYs, TPDOs — is handled, so nothing
//! is lost. Time comes from the transport ([`CanTransport::now_us`]), which lets the software slave's
//! in-process simulated bus run on simulated time.
//!
//! # Safety rules (behaviour, tested)
//!
//! - **NMT Stop, Reset node and Reset communication are refused to a drive whose power stage is
//!   enabled** (Operation enabled, Quick stop active, Fault reaction active): the ASDA-A2 answers
//!   them with AL401, the Lexium with an error-class-2 stop. [`Master::nmt`] reads the
//!   statusword (SDO, or the last TPDO if the node serves no SDO) first; disable through the
//!   controlword ([`Master::disable`]) or use [`Master::shutdown_node`].
//! - **SDO pacing**: requests to one node are at least the profile's
//!   [`CommSupport::sdo_min_interval_us`](super::profile::CommSupport::sdo_min_interval_us)
//!   apart (ASDA-A2: 1 ms, AL111), and [`MasterConfig::unknown_sdo_interval_us`] for
//!   unidentified nodes. Every segment counts.
//! - **Remote bit**: a drive whose profile needs statusword bit 9 reports
//!   [`MasterEvent::RemoteOff`] as soon as the axis wants it enabled and bit 9 is 0, and
//!   [`Master::enable`] fails with [`CanErrorKind::RemoteOff`] at once instead of timing out.
//! - **Targets after enable**: the axis writes set-points only in Operation enabled, every
//!   cycle, so the ASDA-A2's clearing of 60FFh/6071h on enable is harmless.

use super::drive::CanDrive;
use super::emcy::Emergency;
use super::error::{CanError, CanErrorKind, NodeRef};
use super::frame::{CanFrame, Service, cob};
use super::nmt::{ErrorControl, NmtCommand, NmtState};
use super::pdo_plan::PdoPlan;
use super::profile::{CanDriveProfile, DecodedEmcy};
use super::sdo::{ClientStep, ClientTransfer, SdoError, SdoRequest};
use super::transport::CanTransport;
use crate::cia402::{
    AxisConfig, Event, OperationMode, Phase, State, StatusWord, Target, axis::Axis,
};
use crate::od::{DataType, Dictionary, ObjectAddress, Value};
use core::fmt;
use core::time::Duration;
use std::collections::VecDeque;

/// Master settings. Defaults are **\[REC\]** (our choice).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MasterConfig {
    /// SDO response timeout per request, µs. \[REC\] 500 ms.
    pub sdo_timeout_us: u64,
    /// Gap between SDO requests to a node without a profile, µs. \[REC\] 1 ms: the strictest of
    /// the known drives (ASDA-A2).
    pub unknown_sdo_interval_us: u32,
    /// How long to wait for a boot-up message after a reset, µs. \[REC\] 2 s.
    pub boot_timeout_us: u64,
    /// The communication cycle (SYNC period), µs. \[REC\] 2 ms.
    pub cycle_us: u64,
    /// The master produces SYNC at the start of every cycle.
    pub sync_producer: bool,
    /// Events kept before the oldest are dropped.
    pub event_capacity: usize,
    /// EMCY records kept per node.
    pub emcy_log: usize,
}

impl Default for MasterConfig {
    fn default() -> Self {
        Self {
            sdo_timeout_us: 500_000,
            unknown_sdo_interval_us: 1000,
            boot_timeout_us: 2_000_000,
            cycle_us: 2_000,
            sync_producer: true,
            event_capacity: 256,
            emcy_log: 32,
        }
    }
}

/// How the master watches a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Supervision {
    /// The node produces heartbeats every `producer_ms` (1017h); the master reports a loss
    /// after `consumer_ms` of silence (must exceed the producer time).
    Heartbeat {
        /// 1017h, ms.
        producer_ms: u16,
        /// Consumer time, ms.
        consumer_ms: u32,
    },
    /// The master guards the node every `guard_ms` (100Ch) and reports a loss after
    /// `life_factor` (100Dh) unanswered requests.
    Guarding {
        /// 100Ch, ms.
        guard_ms: u16,
        /// 100Dh.
        life_factor: u8,
    },
    /// None (1017h = 0, 100Ch = 0).
    None,
}

impl Supervision {
    /// **\[REC\]** Heartbeat every 100 ms, loss after 350 ms (3.5 periods).
    pub const DEFAULT: Self = Self::Heartbeat {
        producer_ms: 100,
        consumer_ms: 350,
    };
}

/// An EMCY message as received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmcyRecord {
    /// Node.
    pub node: u8,
    /// Drive name, if identified.
    pub drive: Option<&'static str>,
    /// Transport time, µs.
    pub time_us: u64,
    /// The message.
    pub emergency: Emergency,
    /// Decoded with the drive's format and alarm table, if the node is identified.
    pub decoded: Option<DecodedEmcy>,
}

impl fmt::Display for EmcyRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let node = NodeRef {
            id: self.node,
            drive: self.drive,
        };
        match &self.decoded {
            Some(d) => write!(f, "{node}: {d}"),
            None => write!(
                f,
                "{node}: EMCY 0x{:04X}, error register 0x{:02X}, data {:02X?}",
                self.emergency.error_code, self.emergency.error_register, self.emergency.data
            ),
        }
    }
}

/// Something the master observed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MasterEvent {
    /// A node sent its boot-up message.
    BootUp {
        /// Node.
        node: u8,
    },
    /// A node's NMT state changed (heartbeat or guarding).
    StateChanged {
        /// Node.
        node: u8,
        /// Before.
        from: Option<NmtState>,
        /// After.
        to: NmtState,
    },
    /// No heartbeat within the consumer time.
    HeartbeatLost {
        /// Node.
        node: NodeRef,
        /// The state last reported.
        last_state: Option<NmtState>,
        /// Silence so far, µs.
        silent_us: u64,
    },
    /// Heartbeats came back.
    HeartbeatResumed {
        /// Node.
        node: u8,
    },
    /// Node guarding: `missed` requests unanswered (the life time expired).
    GuardingLost {
        /// Node.
        node: NodeRef,
        /// Unanswered requests.
        missed: u32,
    },
    /// A guarding reply with the toggle bit not alternated.
    GuardingToggle {
        /// Node.
        node: u8,
    },
    /// An EMCY message.
    Emergency(EmcyRecord),
    /// The drive ignores the controlword: statusword bit 9 (remote) is 0 while the axis wants it
    /// enabled.
    RemoteOff {
        /// Node.
        node: NodeRef,
    },
    /// Statusword bit 9 is 1 again.
    RemoteOn {
        /// Node.
        node: u8,
    },
}

impl fmt::Display for MasterEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MasterEvent::BootUp { node } => write!(f, "node {node}: boot-up"),
            MasterEvent::StateChanged { node, from, to } => match from {
                Some(s) => write!(f, "node {node}: NMT {s} -> {to}"),
                None => write!(f, "node {node}: NMT {to}"),
            },
            MasterEvent::HeartbeatLost {
                node,
                last_state,
                silent_us,
            } => write!(
                f,
                "{node}: heartbeat lost (no heartbeat for {} ms, last state {})",
                silent_us / 1000,
                last_state.map(NmtState::name).unwrap_or("unknown")
            ),
            MasterEvent::HeartbeatResumed { node } => write!(f, "node {node}: heartbeat resumed"),
            MasterEvent::GuardingLost { node, missed } => {
                write!(
                    f,
                    "{node}: node guarding lost ({missed} requests unanswered)"
                )
            }
            MasterEvent::GuardingToggle { node } => {
                write!(
                    f,
                    "node {node}: guarding reply with the toggle bit not alternated"
                )
            }
            MasterEvent::Emergency(e) => write!(f, "{e}"),
            MasterEvent::RemoteOff { node } => write!(
                f,
                "{node}: statusword bit 9 (remote) is 0: the drive ignores the controlword"
            ),
            MasterEvent::RemoteOn { node } => write!(f, "node {node}: remote (bit 9) is 1 again"),
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Guard {
    period_us: u64,
    life_factor: u32,
    next_us: u64,
    outstanding: u32,
    toggle: Option<bool>,
    lost: bool,
}

#[derive(Debug, Clone, Default)]
struct NodeSlot {
    seen: bool,
    profile: Option<&'static CanDriveProfile>,
    nmt: Option<NmtState>,
    last_seen_us: Option<u64>,
    boot_ups: u32,
    hb_timeout_us: Option<u64>,
    hb_lost: bool,
    guard: Option<Guard>,
    last_sdo_us: Option<u64>,
    sdo_interval_override: Option<u32>,
    emcy: VecDeque<EmcyRecord>,
    drive: Option<usize>,
    remote_off: bool,
}

/// Counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MasterStats {
    /// Frames received.
    pub frames_rx: u64,
    /// Frames sent.
    pub frames_tx: u64,
    /// SYNCs sent.
    pub syncs: u64,
    /// Cycles run.
    pub cycles: u64,
    /// Frames no service claimed.
    pub unhandled: u64,
    /// SDO responses that came too late or unasked.
    pub stray_sdo: u64,
}

/// What configuring a drive needs.
#[derive(Debug, Clone)]
pub struct DriveSetup {
    /// The drive profile.
    pub profile: &'static CanDriveProfile,
    /// The PDO plan ([`PdoPlan::standard`] by default).
    pub plan: PdoPlan,
    /// The mode written to 6060h at start.
    pub initial_mode: OperationMode,
    /// Error control.
    pub supervision: Supervision,
    /// 605Ah to write (only if the drive has the object).
    pub quick_stop_option: Option<i16>,
    /// Further SDO writes, in order (profile velocity, accelerations, homing method, …).
    pub settings: Vec<(ObjectAddress, Value)>,
    /// The axis settings; `None`: [`AxisConfig::for_cycle_time`] with the master's cycle.
    pub axis: Option<AxisConfig>,
}

impl DriveSetup {
    /// The standard setup: standard PDO plan, default supervision, initial mode pp if the drive
    /// has it (else its first mode).
    pub fn new(profile: &'static CanDriveProfile) -> Self {
        let initial_mode = if profile.supports(OperationMode::ProfilePosition) {
            OperationMode::ProfilePosition
        } else {
            profile
                .caps
                .supported_modes
                .iter()
                .next()
                .unwrap_or(OperationMode::ProfileVelocity)
        };
        Self {
            profile,
            plan: PdoPlan::standard(profile),
            initial_mode,
            supervision: Supervision::DEFAULT,
            quick_stop_option: None,
            settings: Vec::new(),
            axis: None,
        }
    }
}

/// The CANopen master. See the [module documentation](self).
pub struct Master<T: CanTransport> {
    t: T,
    cfg: MasterConfig,
    nodes: Vec<NodeSlot>,
    drives: Vec<CanDrive>,
    tpdo_route: Vec<Option<(u16, u8)>>,
    events: VecDeque<MasterEvent>,
    events_lost: u64,
    sdo_wait: Option<u8>,
    sdo_reply: Option<[u8; 8]>,
    scan_replies: Option<Vec<(u8, [u8; 8])>>,
    next_cycle_us: Option<u64>,
    stats: MasterStats,
}

impl<T: CanTransport> fmt::Debug for Master<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Master")
            .field("transport", &self.t.name())
            .field("config", &self.cfg)
            .field("drives", &self.drives.len())
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// **\[REC\]** Cycles after an enable request before a remote bit of 0 counts as the reason
/// for not enabling: the round trip of the request and of a fresh statusword, plus one.
pub const REMOTE_GRACE_CYCLES: u32 = 3;

/// Nodes 0–127 (0 unused).
const SLOTS: usize = 128;

impl<T: CanTransport> Master<T> {
    /// A master on `transport`.
    pub fn new(transport: T, cfg: MasterConfig) -> Self {
        Self {
            t: transport,
            cfg,
            nodes: vec![NodeSlot::default(); SLOTS],
            drives: Vec::new(),
            tpdo_route: vec![None; 0x800],
            events: VecDeque::with_capacity(cfg.event_capacity.max(1)),
            events_lost: 0,
            sdo_wait: None,
            sdo_reply: None,
            scan_replies: None,
            next_cycle_us: None,
            stats: MasterStats::default(),
        }
    }

    /// The configuration.
    pub const fn config(&self) -> &MasterConfig {
        &self.cfg
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.t
    }

    /// The transport, mutably (e.g. the nodes of the software slave's simulated bus in tests).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.t
    }

    /// The transport's time, µs.
    pub fn now_us(&self) -> u64 {
        self.t.now_us()
    }

    /// Counters.
    pub const fn stats(&self) -> MasterStats {
        self.stats
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<MasterEvent> {
        self.events.pop_front()
    }

    /// Events dropped because the queue was full.
    pub const fn events_lost(&self) -> u64 {
        self.events_lost
    }

    fn push_event(&mut self, e: MasterEvent) {
        if self.events.len() >= self.cfg.event_capacity.max(1) {
            self.events.pop_front();
            self.events_lost += 1;
        }
        self.events.push_back(e);
    }

    fn slot(&self, node: u8) -> Option<&NodeSlot> {
        self.nodes.get(usize::from(node))
    }

    fn slot_mut(&mut self, node: u8) -> Option<&mut NodeSlot> {
        self.nodes.get_mut(usize::from(node))
    }

    /// The node as messages name it.
    pub fn node_ref(&self, node: u8) -> NodeRef {
        NodeRef {
            id: node,
            drive: self.slot(node).and_then(|s| s.profile).map(|p| p.name),
        }
    }

    fn err(&self, node: u8, addr: Option<ObjectAddress>, kind: CanErrorKind) -> CanError {
        CanError::new(self.node_ref(node), addr, kind)
    }

    fn check_node(&self, node: u8) -> Result<(), CanError> {
        if (1..=127).contains(&node) {
            Ok(())
        } else {
            Err(self.err(
                node,
                None,
                CanErrorKind::Invalid(format!("node-ID {node} is outside 1–127")),
            ))
        }
    }

    /// The NMT state last seen from `node`.
    pub fn nmt_state(&self, node: u8) -> Option<NmtState> {
        self.slot(node).and_then(|s| s.nmt)
    }

    /// Boot-up messages seen from `node`.
    pub fn boot_ups(&self, node: u8) -> u32 {
        self.slot(node).map(|s| s.boot_ups).unwrap_or(0)
    }

    /// The profile the master uses for `node`.
    pub fn profile(&self, node: u8) -> Option<&'static CanDriveProfile> {
        self.slot(node).and_then(|s| s.profile)
    }

    /// Set the profile of `node` (scan and configuration set it from the identity).
    pub fn set_profile(&mut self, node: u8, profile: &'static CanDriveProfile) {
        if let Some(s) = self.slot_mut(node) {
            s.profile = Some(profile);
            s.seen = true;
        }
    }

    /// Override the SDO pacing for `node` (µs between requests; `None`: the profile's).
    pub fn set_sdo_interval(&mut self, node: u8, us: Option<u32>) {
        if let Some(s) = self.slot_mut(node) {
            s.sdo_interval_override = us;
        }
    }

    /// The EMCY messages received from `node`, oldest first (the last
    /// [`MasterConfig::emcy_log`]).
    pub fn emergencies(&self, node: u8) -> impl Iterator<Item = &EmcyRecord> {
        self.slot(node).into_iter().flat_map(|s| s.emcy.iter())
    }

    /// The configured drive on `node`.
    pub fn drive(&self, node: u8) -> Option<&CanDrive> {
        let i = self.slot(node)?.drive?;
        self.drives.get(i)
    }

    /// The configured drive on `node`, mutably.
    pub fn drive_mut(&mut self, node: u8) -> Option<&mut CanDrive> {
        let i = self.slot(node)?.drive?;
        self.drives.get_mut(i)
    }

    /// Every configured drive.
    pub fn drives_mut(&mut self) -> impl Iterator<Item = &mut CanDrive> {
        self.drives.iter_mut()
    }

    // ----- frames --------------------------------------------------------------------------

    fn send(&mut self, f: &CanFrame) -> Result<(), CanError> {
        self.stats.frames_tx += 1;
        self.t
            .send(f)
            .map_err(|e| CanError::new(NodeRef { id: 0, drive: None }, None, e.into()))
    }

    /// Receive and handle frames until `deadline_us` or until `done` holds; returns whether
    /// `done` held. Timers (heartbeat consumer, guarding) run meanwhile.
    fn pump_until(
        &mut self,
        deadline_us: u64,
        done: impl Fn(&Self) -> bool,
    ) -> Result<bool, CanError> {
        loop {
            if done(self) {
                return Ok(true);
            }
            let now = self.t.now_us();
            self.timers(now)?;
            if now >= deadline_us {
                return Ok(done(self));
            }
            // Wake for the next timer (heartbeat deadline, guarding request) at the latest.
            let until = deadline_us.min(self.next_timer_us().unwrap_or(u64::MAX));
            let wait = until.saturating_sub(now).max(1);
            let got = self.t.recv(wait).map_err(|e| {
                CanError::new(
                    NodeRef { id: 0, drive: None },
                    None,
                    CanErrorKind::Transport(e),
                )
            })?;
            if let Some(f) = got {
                self.dispatch(&f);
            }
        }
    }

    /// Receive and handle frames for `us` microseconds.
    pub fn pump(&mut self, us: u64) -> Result<(), CanError> {
        let deadline = self.t.now_us().saturating_add(us);
        self.pump_until(deadline, |_| false).map(|_| ())
    }

    fn next_timer_us(&self) -> Option<u64> {
        let mut next: Option<u64> = None;
        for s in &self.nodes {
            if let (Some(t), Some(last), false) = (s.hb_timeout_us, s.last_seen_us, s.hb_lost) {
                let d = last.saturating_add(t).saturating_add(1);
                next = Some(next.map_or(d, |n| n.min(d)));
            }
            if let Some(g) = s.guard
                && !g.lost
            {
                next = Some(next.map_or(g.next_us, |n| n.min(g.next_us)));
            }
        }
        next
    }

    /// Heartbeat deadlines and guarding requests. Allocation-free (it runs every cycle).
    fn timers(&mut self, now: u64) -> Result<(), CanError> {
        for id in 0..SLOTS {
            let mut event = None;
            let mut guard_request = false;
            if let Some(s) = self.nodes.get_mut(id) {
                let node = NodeRef {
                    id: id as u8,
                    drive: s.profile.map(|p| p.name),
                };
                if let (Some(t), Some(last)) = (s.hb_timeout_us, s.last_seen_us)
                    && !s.hb_lost
                    && now.saturating_sub(last) > t
                {
                    s.hb_lost = true;
                    event = Some(MasterEvent::HeartbeatLost {
                        node,
                        last_state: s.nmt,
                        silent_us: now.saturating_sub(last),
                    });
                }
                if let Some(g) = &mut s.guard
                    && !g.lost
                    && now >= g.next_us
                {
                    if g.outstanding >= g.life_factor.max(1) {
                        g.lost = true;
                        event = Some(MasterEvent::GuardingLost {
                            node,
                            missed: g.outstanding,
                        });
                    } else {
                        g.outstanding += 1;
                        g.next_us = now.saturating_add(g.period_us.max(1));
                        guard_request = true;
                    }
                }
            }
            if let Some(e) = event {
                self.push_event(e);
            }
            if guard_request {
                self.send(&ErrorControl::guard_request(id as u8))?;
            }
        }
        Ok(())
    }

    fn dispatch(&mut self, f: &CanFrame) {
        self.stats.frames_rx += 1;
        let now = self.t.now_us();
        if !f.is_remote()
            && let Some(Some((drive, slot))) = self.tpdo_route.get(usize::from(f.id()))
        {
            let (drive, slot) = (usize::from(*drive), usize::from(*slot));
            if let Some(d) = self.drives.get_mut(drive) {
                d.store_tpdo(slot, f.data(), now);
            }
            return;
        }
        match f.service() {
            Service::ErrorControl(node) if !f.is_remote() => self.on_error_control(node, f, now),
            Service::Emcy(node) if !f.is_remote() => self.on_emcy(node, f, now),
            Service::SdoTx(node) if !f.is_remote() => {
                let data = f.data8();
                if f.data().len() != 8 {
                    self.stats.stray_sdo += 1;
                } else if let Some(r) = &mut self.scan_replies {
                    r.push((node, data));
                } else if self.sdo_wait == Some(node) && self.sdo_reply.is_none() {
                    self.sdo_reply = Some(data);
                } else {
                    self.stats.stray_sdo += 1;
                }
                if let Some(s) = self.slot_mut(node) {
                    s.seen = true;
                    s.last_seen_us = s.last_seen_us.max(Some(now));
                }
            }
            _ => self.stats.unhandled += 1,
        }
    }

    fn on_error_control(&mut self, node: u8, f: &CanFrame, now: u64) {
        let Ok(ec) = ErrorControl::parse(f) else {
            self.stats.unhandled += 1;
            return;
        };
        let mut events: [Option<MasterEvent>; 4] = [None; 4];
        let mut n = 0usize;
        let mut push = |e: MasterEvent| {
            if let Some(slot) = events.get_mut(n) {
                *slot = Some(e);
                n += 1;
            }
        };
        let Some(s) = self.nodes.get_mut(usize::from(node)) else {
            return;
        };
        s.seen = true;
        s.last_seen_us = Some(now);
        if s.hb_lost {
            s.hb_lost = false;
            push(MasterEvent::HeartbeatResumed { node });
        }
        let state = if ec.state == NmtState::BootUp {
            s.boot_ups += 1;
            push(MasterEvent::BootUp { node });
            if let Some(g) = &mut s.guard {
                g.toggle = None;
            }
            NmtState::PreOperational
        } else {
            ec.state
        };
        if let Some(g) = &mut s.guard
            && ec.state != NmtState::BootUp
        {
            g.outstanding = 0;
            g.lost = false;
            if g.toggle.is_some_and(|t| t == ec.toggle) {
                push(MasterEvent::GuardingToggle { node });
            }
            g.toggle = Some(ec.toggle);
        }
        if s.nmt != Some(state) {
            push(MasterEvent::StateChanged {
                node,
                from: s.nmt,
                to: state,
            });
            s.nmt = Some(state);
        }
        for e in events.into_iter().flatten() {
            self.push_event(e);
        }
    }

    fn on_emcy(&mut self, node: u8, f: &CanFrame, now: u64) {
        let Ok(e) = Emergency::parse(f.data()) else {
            self.stats.unhandled += 1;
            return;
        };
        let cap = self.cfg.emcy_log.max(1);
        let Some(s) = self.nodes.get_mut(usize::from(node)) else {
            return;
        };
        s.seen = true;
        let rec = EmcyRecord {
            node,
            drive: s.profile.map(|p| p.name),
            time_us: now,
            emergency: e,
            decoded: s.profile.map(|p| p.decode_emcy(&e)),
        };
        if s.emcy.len() >= cap {
            s.emcy.pop_front();
        }
        s.emcy.push_back(rec);
        self.push_event(MasterEvent::Emergency(rec));
    }

    // ----- NMT --------------------------------------------------------------------------------

    /// Whether `node`'s power stage is enabled, from a fresh statusword (SDO) if the node
    /// serves SDO, else from the last TPDO. `None` if unknown.
    fn power_stage(&mut self, node: u8) -> Option<State> {
        let serves = self
            .slot(node)
            .and_then(|s| s.nmt)
            .is_some_and(NmtState::serves_sdo);
        if serves
            && let Ok(raw) = self.sdo_upload(node, ObjectAddress::new(0x6041, 0))
            && let [a, b, ..] = raw[..]
        {
            return StatusWord::from_raw(u16::from_le_bytes([a, b])).state();
        }
        self.drive(node).and_then(|d| d.statusword().state())
    }

    /// Send an NMT command to `node` (0 = every node). Stop and the resets are refused to a node
    /// whose drive is energised (see the [module documentation](self)); for node 0 every known
    /// node is checked.
    pub fn nmt(&mut self, node: u8, cmd: NmtCommand) -> Result<(), CanError> {
        if node > 127 {
            return self.check_node(node);
        }
        if cmd.disturbs_enabled_drive() {
            let targets: Vec<u8> = if node == 0 {
                (1..=127u8)
                    .filter(|n| self.slot(*n).is_some_and(|s| s.seen))
                    .collect()
            } else {
                vec![node]
            };
            for n in targets {
                if let Some(state) = self.power_stage(n)
                    && state.is_energised()
                {
                    return Err(self.err(n, None, CanErrorKind::NmtRefused { cmd, state }));
                }
            }
        }
        self.send(&cmd.frame(node))?;
        let expected = match cmd {
            NmtCommand::Start => Some(NmtState::Operational),
            NmtCommand::Stop => Some(NmtState::Stopped),
            NmtCommand::EnterPreOperational => Some(NmtState::PreOperational),
            _ => None,
        };
        let ids: Vec<u8> = if node == 0 {
            (1..=127).collect()
        } else {
            vec![node]
        };
        for n in ids {
            if let Some(s) = self.slot_mut(n)
                && s.seen
                && let Some(e) = expected
            {
                // The node does not confirm NMT commands; assume the state until the next
                // heartbeat says otherwise.
                s.nmt = Some(e);
            }
        }
        Ok(())
    }

    /// Wait until `node` sends a boot-up message counted after `after` boot-ups.
    fn wait_boot(&mut self, node: u8, after: u32) -> Result<(), CanError> {
        let deadline = self.t.now_us().saturating_add(self.cfg.boot_timeout_us);
        let ok = self.pump_until(deadline, |m| m.boot_ups(node) > after)?;
        if ok {
            Ok(())
        } else {
            Err(self.err(
                node,
                None,
                CanErrorKind::NoBootUp(self.cfg.boot_timeout_us / 1000),
            ))
        }
    }

    /// Reset communication of `node` (refused while its drive is energised) and wait for its
    /// boot-up message.
    pub fn reset_communication(&mut self, node: u8) -> Result<(), CanError> {
        self.check_node(node)?;
        let before = self.boot_ups(node);
        self.nmt(node, NmtCommand::ResetCommunication)?;
        self.wait_boot(node, before)
    }

    /// Reset `node` (application and communication; refused while its drive is energised) and
    /// wait for its boot-up message.
    pub fn reset_node(&mut self, node: u8) -> Result<(), CanError> {
        self.check_node(node)?;
        let before = self.boot_ups(node);
        self.nmt(node, NmtCommand::ResetNode)?;
        self.wait_boot(node, before)
    }

    // ----- SDO ----------------------------------------------------------------------------------

    fn sdo_interval(&self, node: u8) -> u64 {
        let s = self.slot(node);
        let v = s
            .and_then(|s| s.sdo_interval_override)
            .or_else(|| {
                s.and_then(|s| s.profile)
                    .map(|p| p.comm.sdo_min_interval_us)
            })
            .unwrap_or(self.cfg.unknown_sdo_interval_us);
        u64::from(v)
    }

    /// Send one SDO request to `node` at the earliest time its pacing allows.
    fn send_sdo(&mut self, node: u8, req: [u8; 8]) -> Result<(), CanError> {
        let min = self.sdo_interval(node);
        if let Some(last) = self.slot(node).and_then(|s| s.last_sdo_us) {
            let ready = last.saturating_add(min);
            if self.t.now_us() < ready {
                self.pump_until(ready, |_| false)?;
            }
        }
        let now = self.t.now_us();
        if let Some(s) = self.slot_mut(node) {
            s.last_sdo_us = Some(now);
        }
        self.send(&CanFrame::from_parts(cob::sdo_rx(node), req, 8))
    }

    fn sdo_exchange(&mut self, node: u8, req: [u8; 8]) -> Result<Option<[u8; 8]>, CanError> {
        self.send_sdo(node, req)?;
        self.sdo_wait = Some(node);
        self.sdo_reply = None;
        let deadline = self.t.now_us().saturating_add(self.cfg.sdo_timeout_us);
        let r = self.pump_until(deadline, |m| m.sdo_reply.is_some());
        self.sdo_wait = None;
        r?;
        Ok(self.sdo_reply.take())
    }

    fn run_transfer(
        &mut self,
        node: u8,
        mut t: ClientTransfer,
        first: [u8; 8],
    ) -> Result<Option<Vec<u8>>, CanError> {
        let addr = t.address();
        let mut req = first;
        loop {
            let Some(resp) = self.sdo_exchange(node, req)? else {
                let _ = self.send_sdo(node, t.abort());
                return Err(self.err(
                    node,
                    Some(addr),
                    CanErrorKind::Sdo(SdoError::Timeout(self.cfg.sdo_timeout_us / 1000)),
                ));
            };
            match t.on_response(&resp) {
                Ok(ClientStep::Send(next)) => req = next,
                Ok(ClientStep::Uploaded(v)) => return Ok(Some(v)),
                Ok(ClientStep::Downloaded) => return Ok(None),
                Err(SdoError::Abort(code)) => {
                    let text = match self.profile(node) {
                        Some(p) => p.abort_text(code),
                        None => super::sdo::abort_text(code, &[]),
                    };
                    return Err(self.err(node, Some(addr), CanErrorKind::Abort(text)));
                }
                Err(e) => {
                    if matches!(e, SdoError::Protocol { .. } | SdoError::TooLarge(_)) {
                        let _ = self.send_sdo(node, t.abort());
                    }
                    return Err(self.err(node, Some(addr), CanErrorKind::Sdo(e)));
                }
            }
        }
    }

    /// Upload (read) `addr` from `node`: the raw little-endian bytes.
    pub fn sdo_upload(&mut self, node: u8, addr: ObjectAddress) -> Result<Vec<u8>, CanError> {
        self.check_node(node)?;
        let (t, first) = ClientTransfer::upload(addr);
        Ok(self.run_transfer(node, t, first)?.unwrap_or_default())
    }

    /// Download (write) `data` to `addr` of `node`: expedited up to 4 bytes, segmented above.
    pub fn sdo_download(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        data: &[u8],
    ) -> Result<(), CanError> {
        self.check_node(node)?;
        let (t, first) = ClientTransfer::download(addr, data.to_vec())
            .map_err(|e| self.err(node, Some(addr), CanErrorKind::Sdo(e)))?;
        self.run_transfer(node, t, first).map(|_| ())
    }

    /// Download `data` to `addr` of `node` with the segmented protocol even if it would fit an
    /// expedited transfer.
    pub fn sdo_download_segmented(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        data: &[u8],
    ) -> Result<(), CanError> {
        self.check_node(node)?;
        let (t, first) = ClientTransfer::download_segmented(addr, data.to_vec())
            .map_err(|e| self.err(node, Some(addr), CanErrorKind::Sdo(e)))?;
        self.run_transfer(node, t, first).map(|_| ())
    }

    /// The data type of `addr` on `node` from its profile's dictionary, or `given`.
    pub fn data_type(
        &self,
        node: u8,
        addr: ObjectAddress,
        given: Option<DataType>,
    ) -> Result<DataType, CanError> {
        if let Some(dt) = given {
            return Ok(dt);
        }
        self.profile(node)
            .and_then(|p| Dictionary::new(p.dictionary).data_type(addr))
            .ok_or_else(|| self.err(node, Some(addr), CanErrorKind::UnknownType))
    }

    /// Upload `addr` and decode it as `data_type` (or the type in the node's profile).
    pub fn upload_value(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        data_type: Option<DataType>,
    ) -> Result<Value, CanError> {
        let dt = self.data_type(node, addr, data_type)?;
        let raw = self.sdo_upload(node, addr)?;
        Value::decode(dt, &raw).map_err(|e| self.err(node, Some(addr), CanErrorKind::Value(e)))
    }

    /// Encode `value` as `data_type` (or the profile's type) and download it to `addr`.
    pub fn download_value(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        value: &Value,
        data_type: Option<DataType>,
    ) -> Result<(), CanError> {
        let dt = self.data_type(node, addr, data_type)?;
        let bytes = value
            .encode(dt)
            .map_err(|e| self.err(node, Some(addr), CanErrorKind::Value(e)))?;
        self.sdo_download(node, addr, &bytes)
    }

    fn upload_u32(&mut self, node: u8, addr: ObjectAddress) -> Result<u32, CanError> {
        let raw = self.sdo_upload(node, addr)?;
        let mut b = [0u8; 4];
        let n = raw.len().min(4);
        if let (Some(d), Some(s)) = (b.get_mut(..n), raw.get(..n)) {
            d.copy_from_slice(s);
        }
        Ok(u32::from_le_bytes(b))
    }

    fn write_uint(
        &mut self,
        node: u8,
        addr: ObjectAddress,
        v: u64,
        dt: DataType,
    ) -> Result<(), CanError> {
        self.download_value(node, addr, &Value::Uint(v), Some(dt))
    }

    // ----- scan ------------------------------------------------------------------------------

    /// Ask every node in `ids` for 1000h at once and collect the answers for `window_us`:
    /// the nodes that answer (with a value or an abort) exist. Returns them with 1000h.
    pub fn probe(
        &mut self,
        ids: impl IntoIterator<Item = u8>,
        window_us: u64,
    ) -> Result<Vec<(u8, Option<u32>)>, CanError> {
        let ids: Vec<u8> = ids.into_iter().filter(|n| (1..=127).contains(n)).collect();
        self.scan_replies = Some(Vec::new());
        let req = SdoRequest::initiate_upload(ObjectAddress::new(0x1000, 0));
        for &n in &ids {
            if let Err(e) = self.send(&CanFrame::from_parts(cob::sdo_rx(n), req, 8)) {
                self.scan_replies = None;
                return Err(e);
            }
            let now = self.t.now_us();
            if let Some(s) = self.slot_mut(n) {
                s.last_sdo_us = Some(now);
            }
        }
        let deadline = self.t.now_us().saturating_add(window_us);
        let r = self.pump_until(deadline, |_| false);
        let replies = self.scan_replies.take().unwrap_or_default();
        r?;
        let mut out: Vec<(u8, Option<u32>)> = Vec::new();
        for (n, data) in replies {
            if !ids.contains(&n) || out.iter().any(|(m, _)| *m == n) {
                continue;
            }
            let dt = match super::sdo::SdoResponse::parse(&data) {
                Ok(super::sdo::SdoResponse::UploadInitiated {
                    expedited: Some((d, 4)),
                    ..
                }) => Some(u32::from_le_bytes(d)),
                _ => None,
            };
            if let Some(s) = self.slot_mut(n) {
                s.seen = true;
            }
            out.push((n, dt));
        }
        out.sort_by_key(|(n, _)| *n);
        Ok(out)
    }

    // ----- supervision -------------------------------------------------------------------------

    /// Set up error control of `node` (writes 1017h or 100Ch/100Dh) and start watching it.
    pub fn supervise(&mut self, node: u8, s: Supervision) -> Result<(), CanError> {
        self.check_node(node)?;
        let has = |m: &Self, i: u16| {
            m.profile(node)
                .is_none_or(|p| Dictionary::new(p.dictionary).object(i).is_some())
        };
        let now = self.t.now_us();
        match s {
            Supervision::Heartbeat {
                producer_ms,
                consumer_ms,
            } => {
                if u64::from(consumer_ms) <= u64::from(producer_ms) {
                    return Err(self.err(
                        node,
                        None,
                        CanErrorKind::Invalid(format!(
                            "heartbeat consumer time {consumer_ms} ms must exceed the producer \
                             time {producer_ms} ms"
                        )),
                    ));
                }
                if has(self, 0x100C) {
                    self.write_uint(node, ObjectAddress::new(0x100C, 0), 0, DataType::Unsigned16)?;
                }
                self.write_uint(
                    node,
                    ObjectAddress::new(0x1017, 0),
                    u64::from(producer_ms),
                    DataType::Unsigned16,
                )?;
                if let Some(sl) = self.slot_mut(node) {
                    sl.guard = None;
                    sl.hb_timeout_us = Some(u64::from(consumer_ms) * 1000);
                    sl.hb_lost = false;
                    sl.last_seen_us = Some(now);
                }
            }
            Supervision::Guarding {
                guard_ms,
                life_factor,
            } => {
                if self.profile(node).is_some_and(|p| !p.comm.guarding) {
                    return Err(self.err(
                        node,
                        None,
                        CanErrorKind::Invalid("the drive has no node guarding".into()),
                    ));
                }
                if guard_ms == 0 || life_factor == 0 {
                    return Err(self.err(
                        node,
                        None,
                        CanErrorKind::Invalid("guard time and life-time factor must be > 0".into()),
                    ));
                }
                self.write_uint(node, ObjectAddress::new(0x1017, 0), 0, DataType::Unsigned16)?;
                self.write_uint(
                    node,
                    ObjectAddress::new(0x100C, 0),
                    u64::from(guard_ms),
                    DataType::Unsigned16,
                )?;
                self.write_uint(
                    node,
                    ObjectAddress::new(0x100D, 0),
                    u64::from(life_factor),
                    DataType::Unsigned8,
                )?;
                if let Some(sl) = self.slot_mut(node) {
                    sl.hb_timeout_us = None;
                    sl.guard = Some(Guard {
                        period_us: u64::from(guard_ms) * 1000,
                        life_factor: u32::from(life_factor),
                        next_us: now,
                        outstanding: 0,
                        toggle: None,
                        lost: false,
                    });
                }
            }
            Supervision::None => {
                self.write_uint(node, ObjectAddress::new(0x1017, 0), 0, DataType::Unsigned16)?;
                if has(self, 0x100C) {
                    self.write_uint(node, ObjectAddress::new(0x100C, 0), 0, DataType::Unsigned16)?;
                }
                if let Some(sl) = self.slot_mut(node) {
                    sl.hb_timeout_us = None;
                    sl.guard = None;
                }
            }
        }
        Ok(())
    }

    // ----- drives ----------------------------------------------------------------------------

    /// Check that `node` is the drive of `profile` (1000h, 1018h:01, 1018h:02).
    pub fn check_identity(
        &mut self,
        node: u8,
        profile: &'static CanDriveProfile,
    ) -> Result<(), CanError> {
        let device_type = self.upload_u32(node, ObjectAddress::new(0x1000, 0))?;
        let vendor = self.upload_u32(node, ObjectAddress::new(0x1018, 1))?;
        let product = self.upload_u32(node, ObjectAddress::new(0x1018, 2)).ok();
        if profile.identity.matches(device_type, vendor, product) {
            Ok(())
        } else {
            Err(self.err(
                node,
                None,
                CanErrorKind::Identity(format!(
                    "the node reports device type 0x{device_type:08X}, vendor 0x{vendor:08X}, \
                     product {}; the {} profile expects device type 0x{:08X}, vendor 0x{:08X}",
                    product.map_or("?".to_string(), |p| format!("0x{p:08X}")),
                    profile.name,
                    profile.identity.device_type,
                    profile.identity.vendor_id
                )),
            ))
        }
    }

    /// Configure `node` as a drive (in Pre-operational): identity check, supervision, enable
    /// preconditions ([`EnableConditions::settings`](super::profile::EnableConditions)), the PDO
    /// plan, quick-stop option, initial mode, settings, cycle objects; then build its
    /// [`CanDrive`] with an [`Axis`]. Start it with [`Master::start`].
    pub fn configure_drive(&mut self, node: u8, setup: DriveSetup) -> Result<(), CanError> {
        self.check_node(node)?;
        let p = setup.profile;
        self.set_profile(node, p);
        self.check_identity(node, p)?;
        let caps = p.caps;
        let cycle = self.cfg.cycle_us;
        let min_pdo = u64::from(p.comm.rpdo_min_interval_us);
        if cycle < min_pdo {
            return Err(self.err(
                node,
                None,
                CanErrorKind::Invalid(format!(
                    "a {cycle} µs cycle sends each RPDO more often than the {} accepts (one \
                     frame per COB-ID per {min_pdo} µs)",
                    p.name
                )),
            ));
        }
        setup
            .plan
            .validate(p)
            .map_err(|e| self.err(node, None, CanErrorKind::Pdo(e)))?;
        self.nmt(node, NmtCommand::EnterPreOperational)?;
        self.supervise(node, setup.supervision)?;
        for s in p.enable.settings {
            let v = self.upload_u32(node, s.addr)?;
            if v & s.mask != s.value {
                if !s.writable {
                    return Err(self.err(
                        node,
                        Some(s.addr),
                        CanErrorKind::Precondition {
                            why: s.why,
                            addr_index: s.addr.index,
                            addr_sub: s.addr.sub,
                            value: u64::from(v),
                        },
                    ));
                }
                let nv = (v & !s.mask) | s.value;
                let dt = self.data_type(node, s.addr, None)?;
                let bytes = nv.to_le_bytes();
                let n = usize::from(dt.bit_len().unwrap_or(32) / 8).min(4);
                self.sdo_download(node, s.addr, bytes.get(..n).unwrap_or(&bytes))?;
            }
        }
        for w in setup.plan.writes(p, node) {
            self.sdo_download(node, w.addr, &w.bytes())?;
        }
        let dict = Dictionary::new(p.dictionary);
        if let Some(code) = setup.quick_stop_option
            && dict.object(0x605A).is_some()
        {
            self.download_value(
                node,
                ObjectAddress::new(0x605A, 0),
                &Value::Int(code.into()),
                None,
            )?;
        }
        self.download_value(
            node,
            ObjectAddress::new(0x6060, 0),
            &Value::Int(setup.initial_mode.as_i8().into()),
            None,
        )?;
        if self.cfg.sync_producer && p.comm.has_cycle_period {
            let g = u64::from(p.comm.cycle_period_granularity_us);
            if g == 0 || cycle % g == 0 {
                self.write_uint(
                    node,
                    ObjectAddress::new(0x1006, 0),
                    cycle,
                    DataType::Unsigned32,
                )?;
            }
        }
        if dict.object(0x60C2).is_some() && cycle % 1000 == 0 && (1000..=20_000).contains(&cycle) {
            // ip period in ms (ASDA-A2 60C2h:01, 1–20 ms).
            self.write_uint(
                node,
                ObjectAddress::new(0x60C2, 1),
                cycle / 1000,
                DataType::Unsigned8,
            )?;
        }
        for (addr, v) in &setup.settings {
            self.download_value(node, *addr, v, None)?;
        }
        let axis_cfg = match setup.axis {
            Some(c) => c,
            None => {
                AxisConfig::for_cycle_time(&caps, Duration::from_micros(cycle), setup.initial_mode)
            }
        };
        let axis =
            Axis::new(caps, axis_cfg).map_err(|e| self.err(node, None, CanErrorKind::Axis(e)))?;
        let drive = CanDrive::new(node, p, setup.plan, axis)
            .map_err(|e| self.err(node, None, CanErrorKind::Field(e)))?;
        // Replace a previous configuration of this node.
        if let Some(old) = self.slot(node).and_then(|s| s.drive) {
            for r in self.tpdo_route.iter_mut() {
                if r.is_some_and(|(d, _)| usize::from(d) == old) {
                    *r = None;
                }
            }
            if let Some(slot) = self.drives.get_mut(old) {
                *slot = drive;
            }
        } else {
            self.drives.push(drive);
            let idx = self.drives.len() - 1;
            if let Some(s) = self.slot_mut(node) {
                s.drive = Some(idx);
            }
        }
        let idx = self.slot(node).and_then(|s| s.drive).unwrap_or(0);
        let routes: Vec<(u16, u8)> = self
            .drives
            .get(idx)
            .map(|d| {
                d.tpdos()
                    .iter()
                    .enumerate()
                    .map(|(i, s)| (s.cob, i as u8))
                    .collect()
            })
            .unwrap_or_default();
        for (c, i) in routes {
            if let Some(r) = self.tpdo_route.get_mut(usize::from(c)) {
                *r = Some((idx as u16, i));
            }
        }
        Ok(())
    }

    /// NMT start of `node`: PDOs run from now on.
    pub fn start(&mut self, node: u8) -> Result<(), CanError> {
        self.check_node(node)?;
        self.nmt(node, NmtCommand::Start)
    }

    // ----- the cycle --------------------------------------------------------------------------

    /// One communication cycle: send every drive's RPDOs (the outputs of its last
    /// [`CanDrive::step`]) to Operational nodes, then SYNC, then receive until the next cycle
    /// starts (the TPDOs answering the SYNC arrive meanwhile). Finally checks each drive's
    /// remote bit.
    pub fn cycle(&mut self) -> Result<(), CanError> {
        let now = self.t.now_us();
        let start = match self.next_cycle_us {
            Some(t) if t >= now => {
                self.pump_until(t, |_| false)?;
                t
            }
            _ => now,
        };
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            let node = d.node();
            if d.last_output().is_none() || self.nmt_state(node) != Some(NmtState::Operational) {
                continue;
            }
            for k in 0..d.rpdos().len() {
                let frame = self
                    .drives
                    .get(i)
                    .and_then(|d| d.rpdo_bytes(k))
                    .and_then(|(c, b)| CanFrame::new(c, b).ok());
                if let Some(f) = frame {
                    self.send(&f)?;
                }
            }
        }
        if self.cfg.sync_producer {
            self.send(&CanFrame::from_parts(cob::SYNC, [0; 8], 0))?;
            self.stats.syncs += 1;
        }
        let next = start.saturating_add(self.cfg.cycle_us.max(1));
        self.next_cycle_us = Some(next);
        self.pump_until(next, |_| false)?;
        self.stats.cycles += 1;
        self.check_remote();
        Ok(())
    }

    /// Remote-bit events. Allocation-free (it runs every cycle).
    fn check_remote(&mut self) {
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            if !d.profile().enable.remote_required || !d.has_feedback() {
                continue;
            }
            let node = d.node();
            let wants = d.axis().status().target == Target::OperationEnabled;
            let off = !d.statusword().contains(StatusWord::REMOTE);
            let was = self.slot(node).is_some_and(|s| s.remote_off);
            let event = if off && wants && !was {
                Some(MasterEvent::RemoteOff {
                    node: self.node_ref(node),
                })
            } else if !off && was {
                Some(MasterEvent::RemoteOn { node })
            } else {
                None
            };
            if let Some(e) = event {
                if let Some(s) = self.slot_mut(node) {
                    s.remote_off = off;
                }
                self.push_event(e);
            }
        }
    }

    /// Whether `node`'s drive ignores the controlword because bit 9 is 0 (profiles that need it).
    pub fn remote_off(&self, node: u8) -> bool {
        self.slot(node).is_some_and(|s| s.remote_off)
    }

    /// One cycle ([`Master::cycle`]), then for each drive: `hook` (profile-mode helpers,
    /// set-points) and [`CanDrive::step`].
    pub fn cycle_step(&mut self, mut hook: impl FnMut(&mut CanDrive)) -> Result<(), CanError> {
        self.cycle()?;
        for d in &mut self.drives {
            hook(d);
            d.step();
        }
        Ok(())
    }

    fn run_axis_until(
        &mut self,
        node: u8,
        timeout_us: u64,
        what: &str,
        done: impl Fn(&CanDrive) -> bool,
        remote_matters: bool,
    ) -> Result<(), CanError> {
        let deadline = self.t.now_us().saturating_add(timeout_us);
        let mut cycles = 0u32;
        loop {
            self.cycle_step(|_| {})?;
            cycles = cycles.saturating_add(1);
            let Some(d) = self.drive_mut(node) else {
                return Err(self.err(
                    node,
                    None,
                    CanErrorKind::NotReady("not a configured drive".into()),
                ));
            };
            let mut failure = None;
            while let Some(e) = d.axis_mut().poll_event() {
                match e {
                    Event::PlannerFailed(p) => failure = Some(p.to_string()),
                    Event::Fault { error, .. } => {
                        failure = Some(match error {
                            Some(e) => format!("the drive faulted: {e}"),
                            None => "the drive faulted".to_string(),
                        })
                    }
                    _ => {}
                }
            }
            if done(d) {
                return Ok(());
            }
            // A statusword older than the request may still show the old remote bit.
            if remote_matters && cycles > REMOTE_GRACE_CYCLES && self.remote_off(node) {
                return Err(self.err(node, None, CanErrorKind::RemoteOff));
            }
            if let Some(f) = failure {
                return Err(self.err(node, None, CanErrorKind::Timeout(format!("{what}: {f}"))));
            }
            if self.t.now_us() >= deadline {
                let st = self.drive(node).map(|d| d.axis().status());
                return Err(self.err(
                    node,
                    None,
                    CanErrorKind::Timeout(format!(
                        "{what}: not done within {} ms (phase {}, statusword 0x{:04X})",
                        timeout_us / 1000,
                        st.map(|s| s.phase.to_string()).unwrap_or_default(),
                        st.map(|s| s.statusword.raw()).unwrap_or(0)
                    )),
                ));
            }
        }
    }

    /// Enable `node`'s drive: run cycles until Operation enabled. Like [`Master::disable`] and
    /// [`Master::switch_mode`] it consumes the axis' events (older ones are discarded first).
    /// Fails at once with
    /// [`CanErrorKind::RemoteOff`] if the drive needs the remote bit and it is 0, and on a
    /// fault or planner failure.
    pub fn enable(&mut self, node: u8, timeout_us: u64) -> Result<(), CanError> {
        let missing = self.err(
            node,
            None,
            CanErrorKind::NotReady("not a configured drive".into()),
        );
        let d = self.drive_mut(node).ok_or(missing)?;
        while d.axis_mut().poll_event().is_some() {}
        d.axis_mut().request_enable().map_err(|e| {
            CanError::new(
                NodeRef {
                    id: node,
                    drive: Some(d.profile().name),
                },
                None,
                CanErrorKind::Axis(e),
            )
        })?;
        self.run_axis_until(
            node,
            timeout_us,
            "enable",
            |d| d.axis().status().phase == Phase::Enabled && d.axis().status().streaming,
            true,
        )
    }

    /// Disable `node`'s drive: run cycles until Switch on disabled.
    pub fn disable(&mut self, node: u8, timeout_us: u64) -> Result<(), CanError> {
        let missing = self.err(
            node,
            None,
            CanErrorKind::NotReady("not a configured drive".into()),
        );
        let d = self.drive_mut(node).ok_or(missing)?;
        while d.axis_mut().poll_event().is_some() {}
        d.axis_mut().request_disable();
        self.run_axis_until(
            node,
            timeout_us,
            "disable",
            |d| {
                let s = d.axis().status();
                s.phase == Phase::Disabled || s.state.is_some_and(|st| !st.is_energised())
            },
            false,
        )
    }

    /// Switch to `mode` and run cycles until 0x6061 confirms it.
    pub fn switch_mode(
        &mut self,
        node: u8,
        mode: OperationMode,
        timeout_us: u64,
    ) -> Result<(), CanError> {
        let missing = self.err(
            node,
            None,
            CanErrorKind::NotReady("not a configured drive".into()),
        );
        let d = self.drive_mut(node).ok_or(missing)?;
        while d.axis_mut().poll_event().is_some() {}
        d.axis_mut().request_mode(mode).map_err(|e| {
            CanError::new(
                NodeRef {
                    id: node,
                    drive: Some(d.profile().name),
                },
                None,
                CanErrorKind::Axis(e),
            )
        })?;
        self.run_axis_until(
            node,
            timeout_us,
            "mode switch",
            move |d| {
                let s = d.axis().status();
                s.active_mode == mode && s.mode_switch == crate::cia402::ModeSwitchPhase::Idle
            },
            false,
        )
    }

    /// Take `node` off the bus safely: disable its drive through the controlword (if it is a
    /// configured drive), then NMT Stop.
    pub fn shutdown_node(&mut self, node: u8, timeout_us: u64) -> Result<(), CanError> {
        if self.drive(node).is_some() {
            self.disable(node, timeout_us)?;
        }
        self.nmt(node, NmtCommand::Stop)
    }
}
