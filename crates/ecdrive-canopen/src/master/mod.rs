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

    /// **\[REC\]** Node guarding every 100 ms, life time factor 3: the master sees a silent
    /// drive, and the drive a silent master, within 300 ms. With a heartbeat the drive produces,
    /// only the master watches; a master that dies leaves the drives running.
    pub const LIFE_GUARDING: Self = Self::Guarding {
        guard_ms: 100,
        life_factor: 3,
    };

    /// What a drive of `profile` gets by default: [`Supervision::LIFE_GUARDING`] where it has
    /// node guarding (each of the three manuals: the ASDA-A2 raises AL170 with the servo on,
    /// the Lexium MDrive goes to Fault on life-time expiry, the BLV-R sends EMCY 8130h — its
    /// manual names no motor reaction), else [`Supervision::DEFAULT`] where it produces a
    /// heartbeat (1017h), else [`Supervision::None`] (a drive whose EDS file has neither).
    pub fn for_drive(profile: &CanDriveProfile) -> Self {
        if profile.comm.guarding {
            Self::LIFE_GUARDING
        } else if Dictionary::new(profile.dictionary).object(0x1017).is_some() {
            Self::DEFAULT
        } else {
            Self::None
        }
    }
}

/// An EMCY message as received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmergencyRecord {
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

impl fmt::Display for EmergencyRecord {
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
    Emergency(EmergencyRecord),
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
    emcy: VecDeque<EmergencyRecord>,
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
    /// Cycles whose RPDOs to a drive were held back: the last went out less than the drive's
    /// minimum RPDO gap before ([`CommSupport::rpdo_min_interval_us`](super::profile::CommSupport::rpdo_min_interval_us)).
    pub rpdos_deferred: u64,
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
    /// The standard setup: standard PDO plan, default supervision (a heartbeat the drive
    /// produces: set [`Supervision::for_drive`] for life guarding, so that the drive sees its
    /// master go, and switch it off before the master leaves), initial mode pp if the drive has
    /// it (else its first mode).
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
    pub fn emergencies(&self, node: u8) -> impl Iterator<Item = &EmergencyRecord> {
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
}

mod cycle;
mod drives;
mod frames;
mod nmt;
mod scan;
mod sdo;
mod supervision;
