//! One emulated CANopen drive: NMT state machine with boot-up, heartbeat producer, node-guarding
//! responder and life guarding, heartbeat consumer, SDO server with the access rules and abort
//! codes the manuals list, PDO engine (RPDO/TPDO, transmission types 0–240, 252–255, inhibit time,
//! event timer, RTR), EMCY producer with the error history, store/restore, the device-side
//! CiA 402 state machine ([`crate::cia402::device`]) and the motion of [`super::motion`].
//!
//! The node is generic: every drive difference comes from its [`NodeSpec`] (dictionary,
//! PDO rules, alarms, EMCY format, quirks), the emulator's own data, never the master's. It does no I/O: frames go in through
//! [`EmulatedNode::receive`], time through [`EmulatedNode::tick`], and frames come out of
//! [`EmulatedNode::poll_transmit`].

use super::motion::{
    DEFAULT_SPEED_WINDOW_REV_S, DEFAULT_ZERO_SPEED_REV_S, FALLBACK_ACCEL_REV_S2,
    FALLBACK_PROFILE_VELOCITY_REV_S, Motion, Params, STEP_ACCEL_REV_S2, World,
};
use super::sdo_server::SdoServer;
use super::spec::NodeSpec;
use crate::can::emcy::Emergency;
use crate::can::frame::{CanFrame, cob};
use crate::can::nmt::{ErrorControl, NmtCommand, NmtState};
use crate::can::profile::{Alarm, EnabledNmtReaction, Transmission, od};
use crate::cia402::device::{Device, DeviceConfig, DeviceInputs, Reaction};
use crate::cia402::{AccelUnit, ProfileUnits, TorqueSlopeUnit, Units};
use crate::cia402::{ControlWord, OperationMode, State, StopRamp};
use crate::coe::ObjectStore;
use crate::coe::ValueStore;
use crate::ec::AlState;
use crate::od::{DataType, EntryAccess, EntryDesc, ObjectAddress, ObjectInfo, SdoAbortCode, Value};
use std::collections::VecDeque;

/// Why a node cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EmuError {
    /// Node-ID outside 1–127.
    #[error("node-ID {0} is outside 1–127")]
    NodeId(u8),
    /// The spec's dictionary cannot be served.
    #[error("the {drive} dictionary cannot be emulated: {reason}")]
    Dictionary {
        /// Drive.
        drive: &'static str,
        /// Why.
        reason: String,
    },
}

/// Counters of what a node did, for tests and the demo summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NodeStats {
    /// SDO requests served (answered or aborted).
    pub sdo_requests: u64,
    /// SDO requests dropped by the rate limit.
    pub sdo_overruns: u64,
    /// RPDOs applied.
    pub rpdos_applied: u64,
    /// RPDOs rejected (length, rate).
    pub rpdos_rejected: u64,
    /// TPDOs sent.
    pub tpdos_sent: u64,
    /// SYNCs seen.
    pub syncs: u64,
    /// EMCY messages sent.
    pub emcys_sent: u64,
    /// Heartbeats sent (boot-up included).
    pub heartbeats_sent: u64,
    /// Guarding requests answered.
    pub guard_replies: u64,
    /// Boot-ups.
    pub boot_ups: u64,
}

#[derive(Debug, Clone, Copy, Default)]
struct PdoRt {
    valid: bool,
    cob: u16,
    ttype: u8,
    rtr_allowed: bool,
    inhibit_us: u64,
    event_us: u64,
    entries: [(u16, u8, u8); 8],
    n: usize,
    len: usize,
    // TPDO state
    last_sent: Option<[u8; 8]>,
    last_sent_us: u64,
    sync_count: u8,
    sampled: Option<[u8; 8]>,
    // RPDO state
    pending: Option<[u8; 8]>,
    last_rx_us: Option<u64>,
}

/// **\[REC\]** Frames a node queues for transmission before it drops the oldest.
pub const OUTBOX_FRAMES: usize = 1024;

/// An emulated CANopen drive. See the [module documentation](self).
#[derive(Debug, Clone)]
pub struct EmulatedNode {
    id: u8,
    spec: &'static NodeSpec,
    /// What the node does beyond its dictionary (the emulator's own data).
    quirks: super::quirks::EmulationQuirks,
    /// The touch probes (60B8h–60BDh, 60D5h–60D8h) on the machine's probe inputs, and the
    /// world position of the last tick they saw.
    probes: crate::machine::TouchProbes,
    probe_from: f64,
    od: ValueStore,
    stored: ValueStore,
    restore_pending: [bool; 5],
    nmt: NmtState,
    sdo: SdoServer,
    guard_toggle: bool,
    last_guard_us: Option<u64>,
    guard_lost: bool,
    hb_next_us: Option<u64>,
    consumer_last_us: Option<u64>,
    consumer_lost: bool,
    rpdo: [PdoRt; 4],
    tpdo: [PdoRt; 4],
    device: Device,
    motion: Motion,
    alarm: Option<&'static Alarm>,
    alarm_cause: bool,
    warning: Option<&'static Alarm>,
    remote: bool,
    main_power: bool,
    out: VecDeque<CanFrame>,
    now_us: u64,
    /// When the frame being handled was on the bus: the gaps a drive judges between requests
    /// are the bus's (a frame that waited in a socket keeps its time).
    frame_us: u64,
    last_tick_us: Option<u64>,
    last_sdo_us: Option<u64>,
    sync_next_us: Option<u64>,
    last_sync_us: Option<u64>,
    stats: NodeStats,
    powered: bool,
}

fn adjust_node_ids(d: &mut ValueStore, id: u8) {
    let addrs: Vec<ObjectAddress> = d
        .objects()
        .flat_map(|o| {
            o.entries
                .iter()
                .map(move |e| ObjectAddress::new(o.index, e.sub))
        })
        .filter(|a| od::node_relative(*a))
        .collect();
    for a in addrs {
        if let Some(v) = d.uint(a) {
            let _ = d.set_uint(a, v.wrapping_add(u64::from(id)));
        }
    }
}

fn comm_range(sub: u8) -> (u16, u16) {
    match sub {
        2 => (0x1000, 0x1FFF),
        3 => (0x6000, 0x9FFF),
        4 => (0x2000, 0x5FFF),
        _ => (0x0000, 0xFFFF),
    }
}

const SAVE: u32 = 0x6576_6173;
const LOAD: u32 = 0x6461_6F6C;

impl EmulatedNode {
    /// A node of model `spec` with node-ID `id`, powered off. Call [`EmulatedNode::power_on`]
    /// (the [`SimBus`](super::SimBus) does) to boot it.
    pub fn new(spec: &'static NodeSpec, id: u8) -> Result<Self, EmuError> {
        Self::with_world(spec, id, World::default())
    }

    /// A node with a custom machine (limit and home switch positions).
    pub fn with_world(spec: &'static NodeSpec, id: u8, world: World) -> Result<Self, EmuError> {
        if !(1..=127).contains(&id) {
            return Err(EmuError::NodeId(id));
        }
        let mut od = ValueStore::new(spec.dictionary).map_err(|e| EmuError::Dictionary {
            drive: spec.name,
            reason: e.to_string(),
        })?;
        adjust_node_ids(&mut od, id);
        let stored = od.clone();
        let caps = spec.caps;
        let device = Device::new(DeviceConfig::from_caps(
            &caps,
            caps.default_quick_stop_option,
        ));
        Ok(Self {
            id,
            spec,
            quirks: spec.quirks,
            probes: crate::machine::TouchProbes::default(),
            probe_from: 0.0,
            od,
            stored,
            restore_pending: [false; 5],
            nmt: NmtState::BootUp,
            sdo: SdoServer::new(),
            guard_toggle: false,
            last_guard_us: None,
            guard_lost: false,
            hb_next_us: None,
            consumer_last_us: None,
            consumer_lost: false,
            rpdo: [PdoRt::default(); 4],
            tpdo: [PdoRt::default(); 4],
            device,
            motion: Motion::new(world, &spec.units),
            alarm: None,
            alarm_cause: false,
            warning: None,
            remote: true,
            main_power: true,
            out: VecDeque::with_capacity(64),
            now_us: 0,
            last_tick_us: None,
            frame_us: 0,
            last_sdo_us: None,
            sync_next_us: None,
            last_sync_us: None,
            stats: NodeStats::default(),
            powered: false,
        })
    }

    // ----- observation and test hooks ------------------------------------------------------

    /// The node-ID.
    pub const fn id(&self) -> u8 {
        self.id
    }

    /// The drive model the node emulates.
    pub const fn spec(&self) -> &'static NodeSpec {
        self.spec
    }

    /// The NMT state (boot-up until powered on).
    pub const fn nmt_state(&self) -> NmtState {
        self.nmt
    }

    /// The CiA 402 state.
    pub fn state(&self) -> State {
        self.device.state()
    }

    /// The reported position (6064h).
    pub fn position(&self) -> i32 {
        self.motion.reported_position()
    }

    /// Where the motor stands on the machine, revolutions (the world position, whatever a
    /// homing made the reported one).
    pub fn machine_rev(&self) -> f64 {
        self.motion.pos / self.motion.ppr()
    }

    /// Velocity in position units per second.
    pub fn velocity_units_per_s(&self) -> f64 {
        self.motion.vel
    }

    /// Torque, ‰.
    pub fn torque(&self) -> f64 {
        self.motion.torque
    }

    /// The value of an object, decoded.
    pub fn value(&self, addr: ObjectAddress) -> Option<Value> {
        self.od.value(addr)
    }

    /// An integer object's value.
    pub fn int(&self, addr: ObjectAddress) -> Option<i64> {
        self.od.int(addr)
    }

    /// The active fault alarm.
    pub fn alarm(&self) -> Option<&'static Alarm> {
        self.alarm
    }

    /// Counters.
    pub const fn stats(&self) -> NodeStats {
        self.stats
    }

    /// The remote input: BLV-R statusword bit 9 is 0 while the S-ON input is active; the
    /// controlword is then ignored except quick stop and fault reset.
    pub fn set_remote(&mut self, remote: bool) {
        self.remote = remote;
    }

    /// Main power (statusword bit 4).
    pub fn set_main_power(&mut self, on: bool) {
        self.main_power = on;
    }

    /// Inject a following error (statusword bit 13 in pp/ip).
    pub fn set_following_error(&mut self, on: bool) {
        self.motion.following_error = on;
    }

    /// Raise the alarm with vendor number `number` from the spec's table, as the drive does:
    /// EMCY, 603Fh, 1001h, 1003h, and Fault for a fault alarm. Returns `false` for an unknown
    /// number. The cause is gone at once unless [`EmulatedNode::set_alarm_cause`] says otherwise.
    pub fn inject_alarm(&mut self, number: u16) -> bool {
        match self.spec.alarm(number) {
            Some(a) => {
                self.raise(a);
                true
            }
            None => false,
        }
    }

    /// Whether the cause of the active alarm persists (a fault reset is then refused).
    pub fn set_alarm_cause(&mut self, present: bool) {
        self.alarm_cause = present;
    }

    // ----- power and NMT ---------------------------------------------------------------------

    /// Power on at `now_us`: initialisation, boot-up message, Pre-operational.
    pub fn power_on(&mut self, now_us: u64) {
        self.now_us = now_us;
        self.powered = true;
        self.last_tick_us = Some(now_us);
        self.reset_node();
    }

    fn boot(&mut self) {
        self.sdo.reset();
        self.guard_toggle = false;
        self.last_guard_us = None;
        self.guard_lost = false;
        self.consumer_last_us = None;
        self.consumer_lost = false;
        self.last_sdo_us = None;
        self.last_sync_us = None;
        self.nmt = NmtState::PreOperational;
        self.emit(ErrorControl::frame(self.id, NmtState::BootUp, false));
        self.stats.heartbeats_sent += 1;
        self.stats.boot_ups += 1;
        self.restart_heartbeat();
        self.restart_sync_producer();
        self.rebuild_pdos();
        // The status objects describe the device from the first moment, not the stored zeros.
        self.last_tick_us = Some(self.now_us);
        self.tick(self.now_us);
    }

    fn reload(&mut self, lo: u16, hi: u16) {
        for (i, pending) in self.restore_pending.iter_mut().enumerate() {
            if *pending {
                let (a, b) = comm_range(i as u8);
                if let Ok(mut fresh) = ValueStore::new(self.spec.dictionary) {
                    adjust_node_ids(&mut fresh, self.id);
                    copy_range(&fresh, &mut self.stored, a, b);
                }
                *pending = false;
            }
        }
        copy_range(&self.stored, &mut self.od, lo, hi);
    }

    fn reset_node(&mut self) {
        self.reload(0x0000, 0xFFFF);
        self.alarm = None;
        self.warning = None;
        self.alarm_cause = false;
        self.device = Device::new(self.device_config());
        self.motion.vel = 0.0;
        self.motion.torque = 0.0;
        self.boot();
    }

    fn reset_communication(&mut self) {
        self.reload(0x1000, 0x1FFF);
        self.boot();
    }

    fn nmt_command(&mut self, cmd: NmtCommand) {
        let energised = self.device.state().is_energised();
        let reaction = match cmd {
            NmtCommand::Stop if energised => Some(self.spec.nmt_stop_while_enabled),
            NmtCommand::ResetNode | NmtCommand::ResetCommunication if energised => {
                Some(self.spec.nmt_reset_while_enabled)
            }
            NmtCommand::EnterPreOperational if energised && self.quirks.operational_required => {
                Some(EnabledNmtReaction::Unspecified)
            }
            _ => None,
        };
        // Alarms are raised before Stopped (EMCY still goes out) and after a reset (so the
        // reset does not clear them).
        let before = matches!(cmd, NmtCommand::Stop | NmtCommand::EnterPreOperational);
        if before && let Some(r) = reaction {
            self.nmt_reaction(r);
        }
        match cmd {
            NmtCommand::Start => {
                self.nmt = NmtState::Operational;
                self.rebuild_pdos();
            }
            NmtCommand::Stop => self.nmt = NmtState::Stopped,
            NmtCommand::EnterPreOperational => self.nmt = NmtState::PreOperational,
            NmtCommand::ResetNode => self.reset_node(),
            NmtCommand::ResetCommunication => self.reset_communication(),
        }
        if !before && let Some(r) = reaction {
            self.nmt_reaction(r);
        }
        self.restart_heartbeat_if_needed();
    }

    fn nmt_reaction(&mut self, r: EnabledNmtReaction) {
        match r {
            EnabledNmtReaction::Unspecified => {
                // Power stage off (transition 9 / 12).
                self.device = Device::with_state(self.device_config(), State::SwitchOnDisabled);
            }
            EnabledNmtReaction::Alarm(n) | EnabledNmtReaction::QuickStopThenFault(n) => {
                self.inject_alarm(n);
            }
        }
    }

    // ----- frames ------------------------------------------------------------------------------

    fn emit(&mut self, f: CanFrame) {
        if self.out.len() >= OUTBOX_FRAMES {
            self.out.pop_front();
        }
        self.out.push_back(f);
    }

    /// The next frame the node transmits.
    pub fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.out.pop_front()
    }

    fn sync_cob(&self) -> u16 {
        (self.od.uint(ObjectAddress::new(0x1005, 0)).unwrap_or(0x80) & 0x7FF) as u16
    }

    /// A frame from the bus at `now_us`. Garbage of any kind is ignored.
    pub fn receive(&mut self, frame: &CanFrame, now_us: u64) {
        if !self.powered {
            return;
        }
        self.now_us = self.now_us.max(now_us);
        self.frame_us = now_us;
        let id = frame.id();
        if id == cob::NMT {
            if let Some((cmd, node)) = NmtCommand::parse(frame)
                && (node == 0 || node == self.id)
            {
                self.nmt_command(cmd);
            }
            return;
        }
        if id == self.sync_cob() && !frame.is_remote() {
            self.on_sync();
            return;
        }
        if id == cob::sdo_rx(self.id) && !frame.is_remote() {
            self.on_sdo(frame);
            return;
        }
        if id == cob::error_control(self.id) {
            if frame.is_remote() && self.spec.comm.guarding {
                self.on_guard_request();
            }
            return;
        }
        if (0x701..=0x77F).contains(&id) && !frame.is_remote() {
            self.on_heartbeat((id - 0x700) as u8);
            return;
        }
        if self.nmt != NmtState::Operational {
            return;
        }
        if frame.is_remote() {
            self.on_tpdo_rtr(id);
            return;
        }
        if let Some(k) = self.rpdo.iter().position(|p| p.valid && p.cob == id) {
            self.on_rpdo(k, frame.data());
        }
    }

    fn on_guard_request(&mut self) {
        if self.nmt == NmtState::BootUp {
            return;
        }
        let f = ErrorControl::frame(self.id, self.nmt, self.guard_toggle);
        self.guard_toggle = !self.guard_toggle;
        self.last_guard_us = Some(self.now_us);
        self.guard_lost = false;
        self.stats.guard_replies += 1;
        self.emit(f);
    }

    fn on_heartbeat(&mut self, producer: u8) {
        let cfg = self.od.uint(ObjectAddress::new(0x1016, 1)).unwrap_or(0);
        if cfg != 0 && ((cfg >> 16) & 0xFF) as u8 == producer {
            self.consumer_last_us = Some(self.now_us);
            self.consumer_lost = false;
        }
    }

    fn on_sdo(&mut self, frame: &CanFrame) {
        if !self.nmt.serves_sdo() || self.nmt == NmtState::BootUp {
            return;
        }
        let min = u64::from(self.spec.comm.sdo_min_interval_us);
        let too_soon = min > 0
            && self
                .last_sdo_us
                .is_some_and(|t| self.frame_us.saturating_sub(t) < min);
        self.last_sdo_us = Some(self.frame_us);
        if too_soon {
            // The drive's SDO receive buffer overruns: the request is lost (ASDA-A2 AL111).
            self.stats.sdo_overruns += 1;
            if let Some(n) = self.quirks.sdo_overrun_alarm {
                self.inject_alarm(n);
            }
            return;
        }
        self.stats.sdo_requests += 1;
        let mut server = core::mem::take(&mut self.sdo);
        // The entries' access flags are in EtherCAT terms: pre-operational is PRE-OP.
        let access = if self.nmt == NmtState::Operational {
            AlState::Op
        } else {
            AlState::PreOp
        };
        let resp = server.handle(frame.data(), access, self);
        self.sdo = server;
        if let Some(r) = resp {
            self.emit(CanFrame::from_parts(cob::sdo_tx(self.id), r, 8));
        }
    }

    fn on_rpdo(&mut self, k: usize, data: &[u8]) {
        let Some(p) = self.rpdo.get(k).copied() else {
            return;
        };
        let min = u64::from(self.spec.comm.rpdo_min_interval_us);
        let too_soon = min > 0
            && p.last_rx_us
                .is_some_and(|t| self.frame_us.saturating_sub(t) < min);
        if let Some(r) = self.rpdo.get_mut(k) {
            r.last_rx_us = Some(self.frame_us);
        }
        if too_soon {
            self.stats.rpdos_rejected += 1;
            if let Some(n) = self.quirks.rpdo_overrun_alarm {
                self.inject_alarm(n);
            }
            return;
        }
        if data.len() < p.len {
            self.stats.rpdos_rejected += 1;
            if let Some(n) = self.quirks.pdo_length_alarm {
                self.inject_alarm(n);
            }
            return;
        }
        let mut buf = [0u8; 8];
        if let (Some(d), Some(s)) = (buf.get_mut(..p.len), data.get(..p.len)) {
            d.copy_from_slice(s);
        }
        match Transmission::from_u8(p.ttype) {
            Transmission::SyncAcyclic | Transmission::SyncCyclic(_) => {
                if let Some(r) = self.rpdo.get_mut(k) {
                    r.pending = Some(buf);
                }
            }
            _ => self.apply_rpdo(&p, &buf),
        }
    }

    fn apply_rpdo(&mut self, p: &PdoRt, data: &[u8; 8]) {
        let mut pos = 0usize;
        for &(index, sub, bits) in p.entries.iter().take(p.n) {
            let n = usize::from(bits / 8);
            if let Some(bytes) = data.get(pos..pos + n)
                && index >= 0x1000
            {
                let _ = self.od.set_raw(ObjectAddress::new(index, sub), bytes);
            }
            pos += n;
        }
        self.stats.rpdos_applied += 1;
    }

    fn tpdo_data(&self, p: &PdoRt) -> [u8; 8] {
        let mut buf = [0u8; 8];
        let mut pos = 0usize;
        for &(index, sub, bits) in p.entries.iter().take(p.n) {
            let n = usize::from(bits / 8);
            if let (Some(raw), Some(dst)) = (
                self.od.raw(ObjectAddress::new(index, sub)),
                buf.get_mut(pos..pos + n),
            ) && let Some(src) = raw.get(..n)
            {
                dst.copy_from_slice(src);
            }
            pos += n;
        }
        buf
    }

    fn send_tpdo(&mut self, k: usize, data: [u8; 8]) {
        let Some(p) = self.tpdo.get_mut(k) else {
            return;
        };
        p.last_sent = Some(data);
        p.last_sent_us = self.now_us;
        let f = CanFrame::from_parts(p.cob, data, p.len as u8);
        self.stats.tpdos_sent += 1;
        self.emit(f);
    }

    fn on_tpdo_rtr(&mut self, id: u16) {
        let Some(k) = self
            .tpdo
            .iter()
            .position(|p| p.valid && p.cob == id && p.rtr_allowed)
        else {
            return;
        };
        let Some(p) = self.tpdo.get(k).copied() else {
            return;
        };
        match Transmission::from_u8(p.ttype) {
            Transmission::RtrSync => {
                if let Some(d) = p.sampled {
                    self.send_tpdo(k, d);
                }
            }
            Transmission::RtrEvent | Transmission::Event(_) => {
                let d = self.tpdo_data(&p);
                self.send_tpdo(k, d);
            }
            _ => {}
        }
    }

    fn on_sync(&mut self) {
        self.stats.syncs += 1;
        let now = self.now_us;
        let period_hint = self
            .last_sync_us
            .map(|t| now.saturating_sub(t))
            .unwrap_or_else(|| self.ip_period_us());
        self.last_sync_us = Some(now);
        if self.nmt == NmtState::Operational {
            // TPDOs first (sampled now), then the RPDOs received since the last SYNC
            // (Lexium §2.4: "sends its TPDOs first and then receives RPDOs").
            for k in 0..4 {
                let Some(p) = self.tpdo.get(k).copied() else {
                    continue;
                };
                if !p.valid || p.n == 0 {
                    continue;
                }
                let data = self.tpdo_data(&p);
                match Transmission::from_u8(p.ttype) {
                    Transmission::SyncAcyclic if p.last_sent != Some(data) => {
                        self.send_tpdo(k, data);
                    }
                    Transmission::SyncCyclic(n) => {
                        let c = p.sync_count.saturating_add(1);
                        if c >= n {
                            self.send_tpdo(k, data);
                            if let Some(q) = self.tpdo.get_mut(k) {
                                q.sync_count = 0;
                            }
                        } else if let Some(q) = self.tpdo.get_mut(k) {
                            q.sync_count = c;
                        }
                    }
                    Transmission::RtrSync => {
                        if let Some(q) = self.tpdo.get_mut(k) {
                            q.sampled = Some(data);
                        }
                    }
                    _ => {}
                }
            }
            for k in 0..4 {
                let Some(p) = self.rpdo.get_mut(k) else {
                    continue;
                };
                if let Some(d) = p.pending.take() {
                    let p = *p;
                    self.apply_rpdo(&p, &d);
                }
            }
        }
        let ip = self
            .od
            .int(ObjectAddress::new(0x60C1, 1))
            .and_then(|v| i32::try_from(v).ok())
            .unwrap_or(0);
        self.motion.on_sync(now, ip, period_hint);
    }

    fn ip_period_us(&self) -> u64 {
        let units = self.od.uint(ObjectAddress::new(0x60C2, 1)).unwrap_or(1);
        let index = self.od.int(ObjectAddress::new(0x60C2, 2)).unwrap_or(-3);
        let scale = match index {
            -3 => 1_000,
            -4 => 100,
            -5 => 10,
            -6 => 1,
            _ => 1_000,
        };
        units.max(1) * scale
    }

    // ----- PDO configuration ----------------------------------------------------------------

    fn rebuild_pdos(&mut self) {
        for k in 0..4u16 {
            let r = self.read_pdo(0x1400 + k, 0x1600 + k, false);
            let t = self.read_pdo(0x1800 + k, 0x1A00 + k, true);
            if let Some(slot) = self.rpdo.get_mut(usize::from(k)) {
                let keep = slot.last_rx_us;
                *slot = r;
                slot.last_rx_us = keep;
            }
            if let Some(slot) = self.tpdo.get_mut(usize::from(k)) {
                *slot = t;
            }
        }
    }

    fn read_pdo(&self, comm: u16, map: u16, tx: bool) -> PdoRt {
        let mut p = PdoRt::default();
        let Some(cob_id) = self.od.uint(ObjectAddress::new(comm, 1)) else {
            return p;
        };
        p.valid = cob_id & 0x8000_0000 == 0;
        p.rtr_allowed = tx && cob_id & 0x4000_0000 == 0;
        p.cob = (cob_id & 0x7FF) as u16;
        p.ttype = self.od.uint(ObjectAddress::new(comm, 2)).unwrap_or(255) as u8;
        p.inhibit_us = self.od.uint(ObjectAddress::new(comm, 3)).unwrap_or(0) * 100;
        p.event_us = self.od.uint(ObjectAddress::new(comm, 5)).unwrap_or(0) * 1000;
        let n = self.od.uint(ObjectAddress::new(map, 0)).unwrap_or(0) as usize;
        let mut bits = 0usize;
        for (i, slot) in p.entries.iter_mut().enumerate().take(n.min(8)) {
            let v = self
                .od
                .uint(ObjectAddress::new(map, (i + 1) as u8))
                .unwrap_or(0) as u32;
            *slot = ((v >> 16) as u16, (v >> 8) as u8, v as u8);
            bits += usize::from(v as u8);
        }
        p.n = n.min(8);
        p.len = bits.div_ceil(8).min(8);
        p
    }

    /// Check the mapping of `map` with `n` entries: existence, mappability, lengths, 64 bits.
    fn check_mapping(
        &self,
        map: u16,
        n: u8,
        values: Option<(u8, u32)>,
    ) -> Result<(), SdoAbortCode> {
        let rx = (0x1600..0x1800).contains(&map);
        let mut bits = 0u32;
        for s in 1..=n {
            let v = match values {
                Some((sub, v)) if sub == s => v,
                _ => self.od.uint(ObjectAddress::new(map, s)).unwrap_or(0) as u32,
            };
            self.check_entry(v, rx)?;
            bits += v & 0xFF;
        }
        if bits > u32::from(self.spec.pdo.max_pdo_bytes) * 8 {
            return Err(SdoAbortCode::PDO_TOO_LONG);
        }
        Ok(())
    }

    fn check_entry(&self, v: u32, rx: bool) -> Result<(), SdoAbortCode> {
        let index = (v >> 16) as u16;
        let sub = (v >> 8) as u8;
        let len = (v & 0xFF) as u16;
        if len == 0 || len % 8 != 0 {
            return Err(SdoAbortCode::NOT_MAPPABLE);
        }
        if rx && (1..=7).contains(&index) {
            // Dummy entries (data-type indices) in RPDOs.
            return match DataType::from_code(index).and_then(DataType::bit_len) {
                Some(b) if b == len => Ok(()),
                _ => Err(SdoAbortCode::NOT_MAPPABLE),
            };
        }
        let e = self
            .od
            .entry_desc(ObjectAddress::new(index, sub))
            .ok_or(SdoAbortCode::NO_OBJECT)?;
        let flag = if rx {
            EntryAccess::RXPDO
        } else {
            EntryAccess::TXPDO
        };
        if !e.access.contains(flag) || e.bit_len != len {
            return Err(SdoAbortCode::NOT_MAPPABLE);
        }
        Ok(())
    }

    // ----- the CiA 402 side --------------------------------------------------------------------

    fn quick_stop_option(&self) -> crate::cia402::QuickStopOption {
        let caps = &self.spec.caps;
        self.od
            .int(ObjectAddress::new(0x605A, 0))
            .and_then(|c| i16::try_from(c).ok())
            .and_then(|c| caps.quick_stop_option(c))
            .unwrap_or(caps.default_quick_stop_option)
    }

    fn bit3_mode(&self) -> bool {
        self.quirks.bit3_enable.is_some_and(|b| {
            self.od
                .int(b.addr)
                .is_some_and(|v| (v as u32) & b.mask == b.value)
        })
    }

    fn device_config(&self) -> DeviceConfig {
        let mut cfg = DeviceConfig::from_caps(&self.spec.caps, self.quick_stop_option());
        if self.bit3_mode() {
            cfg.state_skipping = true;
        }
        cfg
    }

    fn refresh_device(&mut self) {
        self.device = Device::with_state(self.device_config(), self.device.state());
    }

    fn raise(&mut self, a: &'static Alarm) {
        let e = Emergency {
            error_code: a.code,
            error_register: a.register,
            data: self.spec.emcy.vendor_bytes(a.number),
        };
        self.push_history(self.spec.emcy.history_entry(a.code, a.number));
        let _ = self
            .od
            .set_uint(ObjectAddress::new(0x603F, 0), u64::from(a.code));
        let _ = self
            .od
            .set_uint(ObjectAddress::new(0x1001, 0), u64::from(a.register));
        if a.fault {
            self.alarm = Some(a);
        } else {
            self.warning = Some(a);
        }
        self.send_emcy(e);
    }

    fn send_emcy(&mut self, e: Emergency) {
        let cob = self
            .od
            .uint(ObjectAddress::new(0x1014, 0))
            .unwrap_or(0x80 + u64::from(self.id));
        if cob & 0x8000_0000 != 0 {
            return;
        }
        self.stats.emcys_sent += 1;
        self.emit(e.frame((cob & 0x7FF) as u16));
    }

    fn push_history(&mut self, entry: u32) {
        let depth = self.spec.comm.error_history;
        if depth == 0 {
            return;
        }
        for s in (1..depth).rev() {
            if let Some(v) = self.od.uint(ObjectAddress::new(0x1003, s)) {
                let _ = self.od.set_uint(ObjectAddress::new(0x1003, s + 1), v);
            }
        }
        let _ = self
            .od
            .set_uint(ObjectAddress::new(0x1003, 1), u64::from(entry));
        let n = self.od.uint(ObjectAddress::new(0x1003, 0)).unwrap_or(0);
        let _ = self
            .od
            .set_uint(ObjectAddress::new(0x1003, 0), (n + 1).min(u64::from(depth)));
    }

    fn clear_alarm(&mut self) {
        self.alarm = None;
        self.warning = None;
        let _ = self.od.set_uint(ObjectAddress::new(0x603F, 0), 0);
        let _ = self.od.set_uint(ObjectAddress::new(0x1001, 0), 0);
        self.send_emcy(Emergency {
            error_code: 0,
            error_register: 0,
            data: [0; 5],
        });
    }

    fn params(&self) -> Params {
        let u = &self.spec.units;
        let ppr = u.position_per_rev;
        let int = |i: u16, s: u8| self.od.int(ObjectAddress::new(i, s));
        let f = |i: u16, s: u8| int(i, s).map(|v| v as f64);
        let vel = |unit, v: f64| u.to_rev_per_s(unit, v) * ppr;
        // \[REC\] A profile that describes no profile-mode units: the cyclic velocity unit,
        // accelerations in position units/s², torque slopes in ‰/s.
        let pu = u.profile.unwrap_or(ProfileUnits {
            profile_velocity: u.velocity,
            homing_velocity: u.velocity,
            acceleration: AccelUnit::PositionPerSecond2,
            torque_slope: TorqueSlopeUnit::PerMillePerSecond,
        });
        let units = Units {
            profile: Some(pu),
            ..*u
        };
        let acc = |a: Option<f64>| {
            let r = match a.and_then(|a| units.accel_to_rev_per_s2(a)) {
                Some(r) => r,
                None => FALLBACK_ACCEL_REV_S2,
            };
            let r = if !r.is_finite() {
                STEP_ACCEL_REV_S2
            } else if r <= 0.0 {
                FALLBACK_ACCEL_REV_S2
            } else {
                r.min(STEP_ACCEL_REV_S2)
            };
            r * ppr
        };
        let decel = acc(f(0x6084, 0));
        Params {
            target_position: int(0x607A, 0).unwrap_or(0) as i32,
            // A drive without 6081h (an EDS file that has none) moves at its maximum
            // profile velocity 607Fh, else at [REC] FALLBACK_PROFILE_VELOCITY_REV_S.
            profile_velocity: match f(0x6081, 0).or_else(|| f(0x607F, 0)) {
                Some(v) => vel(pu.profile_velocity, v),
                None => FALLBACK_PROFILE_VELOCITY_REV_S * ppr,
            },
            acceleration: acc(f(0x6083, 0)),
            deceleration: decel,
            quick_stop_deceleration: match f(0x6085, 0) {
                Some(v) => acc(Some(v)),
                None => decel,
            },
            target_velocity: vel(u.velocity, f(0x60FF, 0).unwrap_or(0.0)),
            target_torque: f(0x6071, 0).unwrap_or(0.0) * u.torque_per_mille,
            torque_slope: {
                let s = units.torque_slope_per_mille_per_s(f(0x6087, 0).unwrap_or(0.0));
                s.filter(|s| s.is_finite()).unwrap_or(1.0e9)
            },
            homing_method: int(0x6098, 0).unwrap_or(0) as i8,
            homing_fast: vel(pu.homing_velocity, f(0x6099, 1).unwrap_or(0.0)),
            homing_slow: vel(pu.homing_velocity, f(0x6099, 2).unwrap_or(0.0)),
            homing_acceleration: acc(f(0x609A, 0).or(f(0x6083, 0))),
            home_offset: int(0x607C, 0).unwrap_or(0) as i32,
            position_window: f(0x6067, 0).unwrap_or(0.5),
            velocity_window: match f(0x606D, 0) {
                Some(w) => vel(u.velocity, w),
                None => DEFAULT_SPEED_WINDOW_REV_S * ppr,
            },
            zero_speed_threshold: match f(0x606F, 0) {
                Some(w) => vel(u.velocity, w),
                None => DEFAULT_ZERO_SPEED_REV_S * ppr,
            },
            halt_option: int(0x605D, 0).unwrap_or(1) as i16,
            ip_position: int(0x60C1, 1).unwrap_or(0) as i32,
        }
    }

    fn clear_targets(&mut self) {
        for a in self.spec.targets_cleared_on_enable {
            let _ = self.od.set_int(*a, 0);
        }
    }

    /// The touch probes over this tick's travel, where the dictionary has 60B8h: status into
    /// 60B9h, latches into 60BAh–60BDh, each latch counted in 60D5h–60D8h (UINT16, wrapping).
    fn touch_probe(&mut self) {
        let to = self.motion.pos;
        let from = core::mem::replace(&mut self.probe_from, to);
        let a = |i: u16| ObjectAddress::new(i, 0);
        if self.od.entry_desc(a(0x60B8)).is_none() {
            return;
        }
        let f = self.od.uint(a(0x60B8)).unwrap_or(0) as u16;
        let (st, latched) = self.probes.step(
            f,
            self.motion.world(),
            (from, to),
            self.motion.ppr(),
            self.motion.offset,
            self.quirks.touch_probe_index_pulse,
        );
        let _ = self.od.set_uint(a(0x60B9), u64::from(st));
        for ((latch, counter), v) in [
            (0x60BA, 0x60D5),
            (0x60BB, 0x60D6),
            (0x60BC, 0x60D7),
            (0x60BD, 0x60D8),
        ]
        .into_iter()
        .zip(latched)
        {
            let Some(v) = v else { continue };
            let _ = self.od.set_int(a(latch), v);
            if self.od.entry_desc(a(counter)).is_some() {
                let n = self.od.uint(a(counter)).unwrap_or(0);
                let _ = self.od.set_uint(a(counter), (n + 1) & 0xFFFF);
            }
        }
    }

    /// Advance the node to `now_us`: timers, the device state machine, motion, event TPDOs.
    pub fn tick(&mut self, now_us: u64) {
        if !self.powered {
            return;
        }
        let now = now_us.max(self.now_us);
        self.now_us = now;
        let dt = self
            .last_tick_us
            .map(|t| now.saturating_sub(t) as f64 / 1e6)
            .unwrap_or(0.0);
        self.last_tick_us = Some(now);

        self.error_control_timers();
        self.sync_producer();

        // Device state machine.
        let raw_cw =
            ControlWord::from_raw(self.od.uint(ObjectAddress::new(0x6040, 0)).unwrap_or(0) as u16);
        let cw = if self.bit3_mode() && raw_cw.contains(ControlWord::ENABLE_OPERATION) {
            // ASDA-A2 P3-12 X = 0: servo on with bit 3 alone.
            raw_cw | ControlWord::from_raw(0x0007)
        } else {
            raw_cw
        };
        let before = self.device.state();
        let qs = self.quick_stop_option();
        let reaction = self.device.step(&DeviceInputs {
            controlword: cw,
            // In Fault, a reset edge clears the alarm once its cause is gone (transition 15
            // needs `fault` false); elsewhere an alarm drives transition 13.
            fault: self.alarm.is_some() && (self.alarm_cause || before != State::Fault),
            motion_stopped: self.motion.vel.abs() <= 1e-4 * self.spec.units.position_per_rev,
            main_power: self.main_power,
            remote: self.remote,
            warning: self.warning.is_some() || self.alarm.is_some(),
        });
        let after = self.device.state();
        if let Reaction::Transition(t) = reaction {
            if t.number == Some(15) {
                self.clear_alarm();
            }
            if (after == State::OperationEnabled) != (before == State::OperationEnabled) {
                self.clear_targets();
            }
        }

        // Mode.
        let requested =
            OperationMode::from_i8(self.od.int(ObjectAddress::new(0x6060, 0)).unwrap_or(0) as i8);
        let mode = if requested == OperationMode::NoMode
            || self.spec.caps.supported_modes.contains(requested)
        {
            requested
        } else {
            OperationMode::from_i8(self.od.int(ObjectAddress::new(0x6061, 0)).unwrap_or(0) as i8)
        };
        let _ = self
            .od
            .set_int(ObjectAddress::new(0x6061, 0), i64::from(mode.as_i8()));

        let p = self.params();
        let immediate = (matches!(qs.ramp, StopRamp::Immediate) && after == State::QuickStopActive)
            || (after == State::FaultReactionActive
                && self.od.int(ObjectAddress::new(0x605E, 0)) == Some(0));
        let (bits, _stopped) = self.motion.tick(
            now,
            dt,
            after,
            mode,
            cw,
            &p,
            self.spec,
            &self.quirks,
            immediate,
        );

        let sw = self.device.statusword() | bits;
        let u = &self.spec.units;
        let vel_units = u.from_rev_per_s(u.velocity, self.motion.vel / u.position_per_rev);
        let pos = i64::from(self.motion.reported_position());
        let set = |od: &mut ValueStore, i: u16, v: i64| {
            if od.entry_desc(ObjectAddress::new(i, 0)).is_some() {
                let _ = od.set_int(ObjectAddress::new(i, 0), v);
            }
        };
        set(&mut self.od, 0x6041, i64::from(sw.raw()));
        set(&mut self.od, 0x6064, pos);
        set(&mut self.od, 0x6062, pos);
        set(&mut self.od, 0x6063, pos);
        set(&mut self.od, 0x60FC, pos);
        set(&mut self.od, 0x606C, vel_units.round() as i64);
        set(&mut self.od, 0x606B, vel_units.round() as i64);
        set(&mut self.od, 0x6077, self.motion.torque.round() as i64);
        set(&mut self.od, 0x6074, self.motion.torque.round() as i64);
        set(
            &mut self.od,
            0x60FD,
            i64::from(self.motion.digital_inputs()),
        );
        self.touch_probe();

        // Event-driven TPDOs.
        if self.nmt == NmtState::Operational {
            for k in 0..4 {
                let Some(p) = self.tpdo.get(k).copied() else {
                    continue;
                };
                if !p.valid
                    || p.n == 0
                    || !matches!(Transmission::from_u8(p.ttype), Transmission::Event(_))
                {
                    continue;
                }
                let data = self.tpdo_data(&p);
                let since = now.saturating_sub(p.last_sent_us);
                let changed =
                    p.last_sent != Some(data) && (p.last_sent.is_none() || since >= p.inhibit_us);
                let timer = p.event_us > 0 && since >= p.event_us;
                if changed || timer {
                    self.send_tpdo(k, data);
                }
            }
        }
    }

    fn error_control_timers(&mut self) {
        let now = self.now_us;
        if let Some(next) = self.hb_next_us
            && now >= next
            && self.nmt != NmtState::BootUp
        {
            let period = self.od.uint(ObjectAddress::new(0x1017, 0)).unwrap_or(0) * 1000;
            self.emit(ErrorControl::frame(self.id, self.nmt, false));
            self.stats.heartbeats_sent += 1;
            self.hb_next_us = (period > 0).then(|| next.max(now.saturating_sub(period)) + period);
        }
        // Life guarding: starts with the first guarding request.
        let guard = self.od.uint(ObjectAddress::new(0x100C, 0)).unwrap_or(0);
        let factor = self.od.uint(ObjectAddress::new(0x100D, 0)).unwrap_or(0);
        if let Some(last) = self.last_guard_us
            && guard > 0
            && factor > 0
            && !self.guard_lost
            && now.saturating_sub(last) > guard * factor * 1000
        {
            self.guard_lost = true;
            self.comm_lost();
        }
        // Heartbeat consumer: starts with the first heartbeat of the producer.
        let cfg = self.od.uint(ObjectAddress::new(0x1016, 1)).unwrap_or(0);
        let t = (cfg & 0xFFFF) * 1000;
        if let Some(last) = self.consumer_last_us
            && t > 0
            && !self.consumer_lost
            && now.saturating_sub(last) > t
        {
            self.consumer_lost = true;
            self.comm_lost();
        }
    }

    fn comm_lost(&mut self) {
        match self.quirks.guarding_alarm {
            Some(n) => {
                self.inject_alarm(n);
            }
            None => self.send_emcy(Emergency {
                error_code: 0x8130,
                error_register: 0x11,
                data: [0; 5],
            }),
        }
        // 1029h:01 (ASDA-A2): 0 → Pre-operational if Operational, 2 → Stopped.
        match self.od.uint(ObjectAddress::new(0x1029, 1)) {
            Some(0) if self.nmt == NmtState::Operational => self.nmt = NmtState::PreOperational,
            Some(2) => self.nmt = NmtState::Stopped,
            _ => {}
        }
    }

    fn restart_heartbeat(&mut self) {
        let period = self.od.uint(ObjectAddress::new(0x1017, 0)).unwrap_or(0) * 1000;
        self.hb_next_us = (period > 0).then(|| self.now_us + period);
    }

    fn restart_heartbeat_if_needed(&mut self) {
        if self.hb_next_us.is_none() {
            self.restart_heartbeat();
        }
    }

    fn restart_sync_producer(&mut self) {
        let cob_id = self.od.uint(ObjectAddress::new(0x1005, 0)).unwrap_or(0x80);
        let period = self.od.uint(ObjectAddress::new(0x1006, 0)).unwrap_or(0);
        self.sync_next_us =
            (self.spec.comm.sync_producer && cob_id & 0x4000_0000 != 0 && period > 0)
                .then(|| self.now_us + period);
    }

    fn sync_producer(&mut self) {
        let Some(next) = self.sync_next_us else {
            return;
        };
        if self.now_us < next {
            return;
        }
        let period = self.od.uint(ObjectAddress::new(0x1006, 0)).unwrap_or(0);
        let cob = self.sync_cob();
        self.emit(CanFrame::from_parts(cob, [0; 8], 0));
        self.on_sync();
        self.sync_next_us = (period > 0).then(|| next + period);
    }

    /// Side effects of a master write to `addr`.
    fn after_write(&mut self, addr: ObjectAddress) {
        match addr.index {
            0x1005 | 0x1006 => self.restart_sync_producer(),
            0x1017 => self.restart_heartbeat(),
            // **\[REC\]** Life guarding (re)starts with the first guarding request after a new
            // guard time or life time factor, not from a request of an earlier configuration
            // (the manuals: it starts with the first request).
            0x100C | 0x100D => {
                self.last_guard_us = None;
                self.guard_lost = false;
            }
            0x1400..=0x1BFF => self.rebuild_pdos(),
            0x605A => self.refresh_device(),
            _ => {}
        }
        if self.quirks.bit3_enable.is_some_and(|b| b.addr == addr) {
            self.refresh_device();
        }
    }

    /// Device-specific write rules; `v` is the new value as an unsigned number where it is one.
    fn check_write(
        &self,
        addr: ObjectAddress,
        v: Option<u64>,
        sv: Option<i64>,
    ) -> Result<(), SdoAbortCode> {
        let i = addr.index;
        match (i, addr.sub) {
            (0x1003, 0) if v != Some(0) => return Err(SdoAbortCode::VALUE_RANGE),
            (0x1005, 0) => {
                let v = v.unwrap_or(0);
                if v & 0x4000_0000 != 0 && !self.spec.comm.sync_producer {
                    return Err(SdoAbortCode::VALUE_RANGE);
                }
            }
            (0x1006, 0) => {
                let g = u64::from(self.spec.comm.cycle_period_granularity_us);
                if g > 0 && v.unwrap_or(0) % g != 0 {
                    return Err(SdoAbortCode::VALUE_RANGE);
                }
            }
            (0x1400..=0x15FF | 0x1800..=0x19FF, 1) => {
                let v = v.unwrap_or(0);
                if v & 0x2000_0000 != 0 || v & 0x1FFF_F800 != 0 {
                    // 29-bit identifiers are not supported.
                    return Err(SdoAbortCode::VALUE_RANGE);
                }
                let old = self.od.uint(addr).unwrap_or(0);
                let was_valid = old & 0x8000_0000 == 0;
                let stays_valid = v & 0x8000_0000 == 0;
                if was_valid && stays_valid && (old & 0x7FF) != (v & 0x7FF) {
                    return Err(SdoAbortCode::VALUE_RANGE);
                }
            }
            (0x1400..=0x15FF, 2) if !self.spec.pdo.rpdo_types.allows(v.unwrap_or(0) as u8) => {
                return Err(SdoAbortCode::VALUE_RANGE);
            }
            (0x1800..=0x19FF, 2) if !self.spec.pdo.tpdo_types.allows(v.unwrap_or(0) as u8) => {
                return Err(SdoAbortCode::VALUE_RANGE);
            }
            (0x1800..=0x19FF, 3) => {
                let valid = self.od.uint(ObjectAddress::new(i, 1)).unwrap_or(0) & 0x8000_0000 == 0;
                if valid {
                    return Err(SdoAbortCode::DEVICE_STATE);
                }
            }
            (0x1600..=0x17FF | 0x1A00..=0x1BFF, s) => {
                let comm = i - 0x200;
                let valid =
                    self.od.uint(ObjectAddress::new(comm, 1)).unwrap_or(0) & 0x8000_0000 == 0;
                if valid {
                    return Err(SdoAbortCode::DEVICE_STATE);
                }
                let rx = i < 0x1800;
                if s == 0 {
                    self.check_mapping(i, v.unwrap_or(0) as u8, None)?;
                } else {
                    if self.od.uint(ObjectAddress::new(i, 0)).unwrap_or(0) != 0 {
                        return Err(SdoAbortCode::DEVICE_STATE);
                    }
                    self.check_entry(v.unwrap_or(0) as u32, rx)?;
                }
            }
            (0x6060, 0) => {
                let m = OperationMode::from_i8(sv.unwrap_or(0) as i8);
                if m != OperationMode::NoMode && !self.spec.caps.supported_modes.contains(m) {
                    return Err(SdoAbortCode::VALUE_RANGE);
                }
            }
            (0x6098, 0) if !self.spec.homing.supports(sv.unwrap_or(0) as i8) => {
                return Err(SdoAbortCode::VALUE_RANGE);
            }
            (0x605A, 0)
                if self
                    .spec
                    .caps
                    .quick_stop_option(sv.unwrap_or(0) as i16)
                    .is_none() =>
            {
                return Err(SdoAbortCode::VALUE_RANGE);
            }
            _ => {}
        }
        Ok(())
    }
}

fn copy_range(from: &ValueStore, to: &mut ValueStore, lo: u16, hi: u16) {
    let addrs: Vec<ObjectAddress> = from
        .objects()
        .filter(|o| (lo..=hi).contains(&o.index))
        .flat_map(|o| {
            o.entries
                .iter()
                .map(move |e| ObjectAddress::new(o.index, e.sub))
        })
        .collect();
    for a in addrs {
        if let Some(raw) = from.raw(a) {
            let raw = raw.to_vec();
            let _ = to.set_raw(a, &raw);
        }
    }
}

/// The node's dictionary as the SDO server serves it; CANopen access does not depend on the NMT
/// state here (every entry the manuals list is accessible in pre-operational and operational).
impl ObjectStore for EmulatedNode {
    fn object(&self, index: u16) -> Option<ObjectInfo> {
        self.od.object_desc(index).map(ObjectInfo::describe)
    }

    fn entry(&self, index: u16, sub: u8) -> Result<EntryDesc, SdoAbortCode> {
        self.entry_of(ObjectAddress::new(index, sub)).copied()
    }

    fn next_index(&self, after: Option<u16>) -> Option<u16> {
        self.od
            .objects()
            .map(|o| o.index)
            .filter(|i| after.is_none_or(|a| *i > a))
            .min()
    }

    fn read(
        &mut self,
        index: u16,
        sub: u8,
        _: AlState,
        buf: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        let addr = ObjectAddress::new(index, sub);
        let e = self.entry_of(addr)?;
        if !e.access.readable() {
            return Err(SdoAbortCode::WRITE_ONLY);
        }
        if addr.index == 0x1003 && addr.sub >= 1 {
            let n = self.od.uint(ObjectAddress::new(0x1003, 0)).unwrap_or(0);
            if u64::from(addr.sub) > n {
                return Err(SdoAbortCode::NO_DATA);
            }
        }
        let v = self.od.raw(addr).unwrap_or(&[]);
        buf.get_mut(..v.len())
            .ok_or(SdoAbortCode::OUT_OF_MEMORY)?
            .copy_from_slice(v);
        Ok(v.len())
    }

    fn write(&mut self, index: u16, sub: u8, _: AlState, data: &[u8]) -> Result<(), SdoAbortCode> {
        self.sdo_write(ObjectAddress::new(index, sub), data)
    }
}

impl EmulatedNode {
    fn entry_of(&self, addr: ObjectAddress) -> Result<&'static EntryDesc, SdoAbortCode> {
        self.od.entry_desc(addr).ok_or_else(|| {
            if self.od.object_desc(addr.index).is_some() {
                SdoAbortCode::NO_SUBINDEX
            } else {
                SdoAbortCode::NO_OBJECT
            }
        })
    }

    /// Write one entry from an SDO download: length and range checks, store/restore
    /// signatures, the node's side effects.
    fn sdo_write(&mut self, addr: ObjectAddress, data: &[u8]) -> Result<(), SdoAbortCode> {
        let e = self.entry_of(addr)?;
        if !e.access.writable() {
            return Err(SdoAbortCode::READ_ONLY);
        }
        // Store / restore with signatures.
        if (addr.index == 0x1010 || addr.index == 0x1011) && addr.sub >= 1 {
            let sig = data
                .get(..4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .ok_or(SdoAbortCode::LENGTH_TOO_LOW)?;
            if addr.index == 0x1010 {
                if sig != SAVE {
                    return Err(SdoAbortCode::CANNOT_STORE);
                }
                let (lo, hi) = comm_range(addr.sub);
                let od = self.od.clone();
                copy_range(&od, &mut self.stored, lo, hi);
            } else {
                if sig != LOAD {
                    return Err(SdoAbortCode::CANNOT_STORE);
                }
                if let Some(p) = self.restore_pending.get_mut(usize::from(addr.sub)) {
                    *p = true;
                }
            }
            return Ok(());
        }
        let need = usize::from(e.bit_len).div_ceil(8);
        let (too_long, too_short) = if self.quirks.length_abort_high_low {
            (SdoAbortCode::LENGTH_TOO_HIGH, SdoAbortCode::LENGTH_TOO_LOW)
        } else {
            (SdoAbortCode::LENGTH_MISMATCH, SdoAbortCode::LENGTH_MISMATCH)
        };
        let bytes: &[u8] = if e.data_type.is_string() {
            if data.len() > need && need > 0 {
                return Err(too_long);
            }
            data
        } else if data.len() == need {
            data
        } else if data.len() > need {
            return Err(too_long);
        } else {
            return Err(too_short);
        };
        let value = Value::decode(e.data_type, bytes).ok();
        let iv = value.as_ref().and_then(Value::as_i128);
        if let Some(x) = iv {
            if let Some(min) = e.min.as_i128()
                && x < min
            {
                return Err(if self.quirks.range_abort_high_low {
                    SdoAbortCode::VALUE_TOO_LOW
                } else {
                    SdoAbortCode::VALUE_RANGE
                });
            }
            if let Some(max) = e.max.as_i128()
                && x > max
            {
                return Err(if self.quirks.range_abort_high_low {
                    SdoAbortCode::VALUE_TOO_HIGH
                } else {
                    SdoAbortCode::VALUE_RANGE
                });
            }
        }
        let uv = iv.and_then(|x| u64::try_from(x).ok());
        let sv = iv.and_then(|x| i64::try_from(x).ok());
        self.check_write(addr, uv, sv)?;
        self.od.set_raw(addr, bytes)?;
        if addr.index == 0x1003 {
            for s in 1..=self.spec.comm.error_history {
                let _ = self.od.set_uint(ObjectAddress::new(0x1003, s), 0);
            }
        }
        self.after_write(addr);
        Ok(())
    }
}
