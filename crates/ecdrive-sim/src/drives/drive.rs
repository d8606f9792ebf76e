//! The emulated drive: one engine for every [`DriveSpec`].

use super::motor::{Drive, Limits, Motor};
use super::spec::{
    AlarmDef, Condition, CycleSource, DriveSpec, EmcyData, PowerOnData, Quantity, Scaling,
    TorqueSlopeUnit, WriteRule,
};
use crate::cia402::device::{Device as Fsa, DeviceConfig, DeviceInputs, Reaction};
use crate::cia402::{ControlWord, OperationMode, QuickStopOption, State, StatusWord, StopRamp};
use crate::coe::hooks::{AllowedValues, Chain, Mirror, RefuseMappedWrites, RefuseWrites};
use crate::coe::{CoeConfig, CoeServer, OdError, OdStore};
use crate::device::{Device, ProcessDataSizes, StateRequest, SyncEvent, SyncKind};
use crate::ec::mailbox::Emergency;
use crate::ec::{AlState, AlStatusCode};
use crate::od::ObjectAddress;
use crate::pdo::Direction;
use crate::quirks::{Quirk, Quirks};
use crate::sii::DeviceDescription;

/// Object addresses the engine reads and writes.
mod obj {
    use crate::od::ObjectAddress;
    const fn a(index: u16) -> ObjectAddress {
        ObjectAddress::new(index, 0)
    }
    pub const ERROR_REGISTER: ObjectAddress = a(0x1001);
    pub const SERIAL: ObjectAddress = ObjectAddress::new(0x1018, 4);
    pub const ERROR_CODE: ObjectAddress = a(0x603F);
    pub const CONTROLWORD: ObjectAddress = a(0x6040);
    pub const STATUSWORD: ObjectAddress = a(0x6041);
    pub const QUICK_STOP_OPTION: ObjectAddress = a(0x605A);
    pub const MODES: ObjectAddress = a(0x6060);
    pub const MODES_DISPLAY: ObjectAddress = a(0x6061);
    pub const POSITION_DEMAND: ObjectAddress = a(0x6062);
    pub const POSITION_INTERNAL: ObjectAddress = a(0x6063);
    pub const POSITION_ACTUAL: ObjectAddress = a(0x6064);
    pub const POSITION_WINDOW: ObjectAddress = a(0x6067);
    pub const POSITION_WINDOW_TIME: ObjectAddress = a(0x6068);
    pub const VELOCITY_DEMAND: ObjectAddress = a(0x606B);
    pub const VELOCITY_ACTUAL: ObjectAddress = a(0x606C);
    pub const VELOCITY_WINDOW: ObjectAddress = a(0x606D);
    pub const VELOCITY_WINDOW_TIME: ObjectAddress = a(0x606E);
    pub const VELOCITY_THRESHOLD: ObjectAddress = a(0x606F);
    pub const VELOCITY_THRESHOLD_TIME: ObjectAddress = a(0x6070);
    pub const TARGET_TORQUE: ObjectAddress = a(0x6071);
    pub const TORQUE_DEMAND: ObjectAddress = a(0x6074);
    pub const TORQUE_ACTUAL: ObjectAddress = a(0x6077);
    pub const TARGET_POSITION: ObjectAddress = a(0x607A);
    pub const HOME_OFFSET: ObjectAddress = a(0x607C);
    pub const MAX_PROFILE_VELOCITY: ObjectAddress = a(0x607F);
    pub const PROFILE_VELOCITY: ObjectAddress = a(0x6081);
    pub const PROFILE_ACCELERATION: ObjectAddress = a(0x6083);
    pub const PROFILE_DECELERATION: ObjectAddress = a(0x6084);
    pub const QUICK_STOP_DECELERATION: ObjectAddress = a(0x6085);
    pub const TORQUE_SLOPE: ObjectAddress = a(0x6087);
    pub const HOMING_METHOD: ObjectAddress = a(0x6098);
    pub const HOMING_SPEED_SWITCH: ObjectAddress = ObjectAddress::new(0x6099, 1);
    pub const HOMING_SPEED_ZERO: ObjectAddress = ObjectAddress::new(0x6099, 2);
    pub const HOMING_ACCELERATION: ObjectAddress = a(0x609A);
    pub const TOUCH_PROBE_FUNCTION: ObjectAddress = a(0x60B8);
    pub const TOUCH_PROBE_STATUS: ObjectAddress = a(0x60B9);
    pub const TOUCH_PROBE_1_RISING: ObjectAddress = a(0x60BA);
    pub const TOUCH_PROBE_1_FALLING: ObjectAddress = a(0x60BB);
    pub const TOUCH_PROBE_2_RISING: ObjectAddress = a(0x60BC);
    pub const TOUCH_PROBE_2_FALLING: ObjectAddress = a(0x60BD);
    pub const DIGITAL_INPUTS: ObjectAddress = a(0x60FD);
    pub const POSITION_OFFSET: ObjectAddress = a(0x60B0);
    pub const VELOCITY_OFFSET: ObjectAddress = a(0x60B1);
    pub const TORQUE_OFFSET: ObjectAddress = a(0x60B2);
    pub const INTERPOLATION_PERIOD: ObjectAddress = ObjectAddress::new(0x60C2, 1);
    pub const FOLLOWING_ERROR: ObjectAddress = a(0x60F4);
    pub const CONTROL_EFFORT: ObjectAddress = a(0x60FA);
    pub const POSITION_DEMAND_INTERNAL: ObjectAddress = a(0x60FC);
    pub const TARGET_VELOCITY: ObjectAddress = a(0x60FF);
}

/// A mapped entry in a process image.
#[derive(Debug, Clone, Copy)]
struct Slot {
    addr: ObjectAddress,
    bit: usize,
    bits: usize,
}

/// Copy `bits` bits from `src` at bit `from` to `dst` at bit `to` (LSB first).
fn copy_bits(src: &[u8], from: usize, dst: &mut [u8], to: usize, bits: usize) {
    if from % 8 == 0 && to % 8 == 0 && bits % 8 == 0 {
        let n = bits / 8;
        if let (Some(s), Some(d)) = (
            src.get(from / 8..from / 8 + n),
            dst.get_mut(to / 8..to / 8 + n),
        ) {
            d.copy_from_slice(s);
        }
        return;
    }
    for k in 0..bits {
        let (sb, db) = (from + k, to + k);
        let v = src.get(sb / 8).is_some_and(|b| b >> (sb % 8) & 1 != 0);
        if let Some(d) = dst.get_mut(db / 8) {
            let m = 1u8 << (db % 8);
            *d = if v { *d | m } else { *d & !m };
        }
    }
}

fn layout(mapping: &crate::pdo::Mapping, dir: Direction) -> Vec<Slot> {
    let mut out = Vec::new();
    let mut bit = 0usize;
    for pdo in mapping.pdos(dir) {
        for e in pdo.entries.iter() {
            if !e.is_padding() {
                out.push(Slot {
                    addr: e.address(),
                    bit,
                    bits: usize::from(e.bits),
                });
            }
            bit += usize::from(e.bits);
        }
    }
    out
}

/// Profile-position state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct ProfilePosition {
    /// The move in progress: target in position units.
    target: Option<f64>,
    /// A set-point waiting for the move in progress (change set immediately = 0).
    pending: Option<f64>,
    /// Demand speed, units/s.
    speed: f64,
    /// Set-point acknowledge (statusword bit 12).
    ack: bool,
    /// The last target, for "target reached" after the move.
    last_target: f64,
}

/// Homing state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
enum Homing {
    /// Not started (or interrupted).
    #[default]
    Idle,
    /// Moving to the home (`failing`: to the limit switch where the search fails), reported
    /// units, at `speed` units/s now.
    Running {
        target: f64,
        failing: bool,
        speed: f64,
    },
    /// Interrupted (bit 4 dropped, or halt): decelerating at 0x609A from `speed` units/s;
    /// then Idle.
    Stopping { speed: f64 },
    /// Homing attained: the reference reads as the home position.
    Attained,
    /// Homing failed.
    Error,
}

/// **\[REC\]** Homing: distance before the reference at which the slow speed (0x6099:02)
/// takes over from the switch-search speed (0x6099:01), rev (the machine model's creep
/// distance).
const HOMING_CREEP_REV: f64 = 0.05;

/// What the emulated drive has done, for tests and the master's fault-injection tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DriveStats {
    /// Process-data cycles (SYNC0 or frame events).
    pub cycles: u64,
    /// Cycles in OP without fresh outputs (including injected ones).
    pub missed_outputs: u64,
    /// Emergencies queued.
    pub emergencies: u64,
    /// Alarms raised.
    pub alarms: u64,
    /// Fault resets that cleared an alarm.
    pub resets: u64,
}

/// Why [`EmulatedDrive::raise_alarm`] could not raise an alarm.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the emulated {drive} has no alarm {id:?}; it has {known}")]
pub struct UnknownAlarm {
    /// Drive name.
    pub drive: &'static str,
    /// The id asked for.
    pub id: String,
    /// The known ids.
    pub known: String,
}

/// One cycle of a drive in OP as [`EmulatedDrive::record_targets`] keeps it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TargetSample {
    /// The SYNC0 (or frame) cycle.
    pub cycle: u64,
    /// Fresh outputs arrived for this cycle.
    pub fresh: bool,
    /// The target position (0x607A) the drive acts on.
    pub target: i32,
}

/// An emulated drive. See the [module documentation](super).
pub struct EmulatedDrive {
    spec: &'static DriveSpec,
    serial: u32,
    stored: Vec<(ObjectAddress, i64)>,
    coe: CoeServer,
    /// File access, if the drive has it; its files live in flash (kept over a power cycle).
    foe: Option<crate::foe::FoeServer>,
    /// The firmware image in force since an update over FoE (its revision and version).
    firmware: Option<crate::foe::FirmwareImage>,
    od: OdStore,
    rx: Vec<Slot>,
    tx: Vec<Slot>,
    al: AlState,
    fsa: Fsa,
    qs_code: i16,
    qs_immediate: bool,
    motor: Motor,
    plan: Drive,
    limits: Limits,
    // Mode and set-points (position units).
    mode: i8,
    allowed_modes: &'static [i8],
    demand: f64,
    demand_prev: f64,
    offset_units: f64,
    last_target: Option<i32>,
    command_unwrapped: i64,
    velocity_demand: f64,
    torque_demand_permille: f64,
    pp: ProfilePosition,
    homing: Homing,
    /// The machine around the motor: switches, index pulse, probe inputs.
    world: crate::machine::World,
    /// A warning the drive shows (statusword bit 7): its id and text.
    warning: Option<(&'static str, &'static str)>,
    /// The touch probes (0x60B8/0x60B9), on the machine's probe inputs.
    probes: crate::machine::TouchProbes,
    prev_cw: u16,
    /// csp motion started by bit 4's edge ([`DriveSpec::csp_start_edge`]).
    csp_started: bool,
    /// Time inside the position window / velocity window / velocity threshold so far (0:
    /// outside).
    in_window_ns: u64,
    speed_window_ns: u64,
    speed_zero_ns: u64,
    // Supervision.
    fe_over_ns: u64,
    fe_flag: bool,
    loss_counter: u32,
    counter_last: Option<u8>,
    counter_missed: u8,
    alarm: Option<&'static AlarmDef>,
    pending: Option<&'static AlarmDef>,
    // Fault injection and environment.
    drop_outputs: u32,
    loss_detection: bool,
    forced_fe: Option<i32>,
    main_power: bool,
    remote: bool,
    last_emcy: Option<Emergency>,
    last_dt_ns: u32,
    stats: DriveStats,
    /// The target position of each cycle in OP, when recording (see [`Self::record_targets`]).
    targets: Option<Vec<TargetSample>>,
    quirks: Quirks,
}

impl core::fmt::Debug for EmulatedDrive {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EmulatedDrive")
            .field("drive", &self.spec.name)
            .field("serial", &self.serial)
            .field("al", &self.al)
            .field("state", &self.fsa.state())
            .field("mode", &self.mode)
            .field("alarm", &self.alarm.map(|a| a.id))
            .finish_non_exhaustive()
    }
}

fn build_store(spec: &'static DriveSpec) -> Result<OdStore, OdError> {
    let mut chain = Chain::new();
    for rule in spec.write_rules {
        chain = match *rule {
            WriteRule::RefuseMappedRx(code) => chain.with(RefuseMappedWrites {
                direction: Direction::Rx,
                code,
            }),
            WriteRule::Allowed {
                address,
                values,
                code,
            } => chain.with(AllowedValues {
                address,
                values,
                code,
            }),
            WriteRule::Refuse {
                objects,
                entries,
                code,
            } => chain.with(RefuseWrites {
                objects,
                entries,
                code,
            }),
            WriteRule::Mirror(a, b) => chain.with(Mirror { a, b }),
        };
    }
    let model = spec.model().map_err(|e| OdError {
        at: "ESI".into(),
        reason: e.to_string(),
    })?;
    Ok(OdStore::new(model.dictionary)?
        .with_limits(spec.pdo_limits)
        .with_abort_codes(spec.abort_codes)
        .with_hooks(chain))
}

impl EmulatedDrive {
    /// A drive as `spec` describes it, with serial number `serial` (SII and 0x1018:04), just
    /// powered on. Fails only if the spec's dictionary is inconsistent.
    pub fn new(spec: &'static DriveSpec, serial: u32) -> Result<Self, OdError> {
        let od = build_store(spec)?;
        let coe = CoeServer::new(CoeConfig {
            complete_access: spec.model().is_ok_and(|m| m.complete_access),
            complete_access_refusal: spec.complete_access_refusal,
            sdo_info: esi_sdo_info(spec),
            ..CoeConfig::default()
        });
        let qs = spec.state_machine.default_quick_stop_option;
        let mut d = Self {
            spec,
            serial,
            stored: Vec::new(),
            coe,
            foe: spec.foe.map(crate::foe::FoeServer::new),
            firmware: None,
            od,
            rx: Vec::new(),
            tx: Vec::new(),
            al: AlState::Init,
            fsa: Fsa::new(spec.state_machine.device_config(qs)),
            qs_code: qs.code,
            qs_immediate: false,
            motor: Motor::new(spec.motor),
            plan: Drive::Off,
            limits: Limits {
                positive_nm: 0.0,
                negative_nm: 0.0,
                speed_rev_s: 0.0,
            },
            mode: 0,
            allowed_modes: &[],
            demand: 0.0,
            demand_prev: 0.0,
            offset_units: 0.0,
            last_target: None,
            command_unwrapped: 0,
            velocity_demand: 0.0,
            torque_demand_permille: 0.0,
            pp: ProfilePosition::default(),
            homing: Homing::default(),
            world: crate::machine::World::default(),
            warning: None,
            probes: crate::machine::TouchProbes::default(),
            prev_cw: 0,
            csp_started: false,
            in_window_ns: 0,
            speed_window_ns: 0,
            speed_zero_ns: 0,
            fe_over_ns: 0,
            fe_flag: false,
            loss_counter: 0,
            counter_last: None,
            counter_missed: 0,
            alarm: None,
            pending: None,
            drop_outputs: 0,
            loss_detection: true,
            forced_fe: None,
            main_power: true,
            remote: true,
            last_emcy: None,
            last_dt_ns: 1_000_000,
            stats: DriveStats::default(),
            targets: None,
            quirks: Quirks::NONE,
        };
        d.power_on();
        Ok(d)
    }

    /// The same drive on another machine ([`crate::machine::World`]: switches, probe inputs).
    pub fn with_world(mut self, world: crate::machine::World) -> Self {
        self.world = world;
        self
    }

    /// The machine around the motor.
    pub fn world(&self) -> &crate::machine::World {
        &self.world
    }

    /// The warning the drive shows (statusword bit 7), by its id and text.
    pub fn warning(&self) -> Option<(&'static str, &'static str)> {
        self.warning
    }

    /// The same drive with a parameter stored in its non-volatile memory, in effect from power-on
    /// (e.g. the MR-J4-TM's [Pr. PA01] = 2 for the profile modes).
    pub fn with_stored(mut self, address: ObjectAddress, value: i64) -> Self {
        self.stored.push((address, value));
        self.power_on();
        self
    }

    /// Switch the drive off and on: dictionary back to its defaults (plus stored parameters),
    /// motor at rest at position 0, alarms cleared, CiA 402 state machine re-initialised.
    pub fn power_cycle(&mut self) {
        self.od.dict_mut().restore_defaults();
        self.motor = Motor::new(self.spec.motor);
        self.alarm = None;
        self.pending = None;
        self.coe.reset();
        self.power_on();
    }

    /// 0x1018:03 and 0x100A from the firmware in force (after an update over FoE).
    fn apply_firmware(&mut self) {
        let Some(fw) = &self.firmware else { return };
        let (revision, version) = (u64::from(fw.revision), fw.version.clone());
        let d = self.od.dict_mut();
        let r = d
            .set_uint(ObjectAddress::new(0x1018, 3), revision)
            .and_then(|()| d.set_raw(ObjectAddress::new(0x100A, 0), version.as_bytes()));
        if let Err(code) = r {
            tracing::warn!(drive = self.spec.name, %code, "firmware identity not accepted");
        }
    }

    /// The firmware image in force since an update over FoE, if any.
    pub fn firmware(&self) -> Option<&crate::foe::FirmwareImage> {
        self.firmware.as_ref()
    }

    /// The FoE server's counters, if the drive has file access.
    pub fn foe_stats(&self) -> Option<crate::foe::FoeStats> {
        self.foe.as_ref().map(|f| f.stats())
    }

    fn power_on(&mut self) {
        let spec = self.spec;
        for p in spec.power_on {
            let r = match p.value {
                PowerOnData::Int(v) => self.od.dict_mut().set_int(p.address, v),
                PowerOnData::Serial => self
                    .od
                    .dict_mut()
                    .set_uint(p.address, u64::from(self.serial)),
                PowerOnData::Text(t) => self.od.dict_mut().set_raw(p.address, t.as_bytes()),
            };
            if let Err(code) = r {
                tracing::warn!(drive = spec.name, address = %p.address, %code, "power-on value not accepted");
            }
        }
        let _ = self
            .od
            .dict_mut()
            .set_uint(obj::SERIAL, u64::from(self.serial));
        for &(a, v) in &self.stored {
            if let Err(code) = self.od.dict_mut().set_int(a, v) {
                tracing::warn!(drive = spec.name, address = %a, %code, "stored value not accepted");
            }
        }
        self.apply_firmware();
        let rules = spec.modes;
        let (modes, initial) = match rules.selector {
            Some(sel) => {
                let v = self.od.dict().int(sel).unwrap_or(0) & 0xF;
                rules
                    .groups
                    .iter()
                    .find(|g| g.group.value == v)
                    .map_or((&[][..], 0), |g| (g.group.modes, g.initial))
            }
            None => (rules.modes, rules.initial),
        };
        self.allowed_modes = modes;
        self.mode = initial;
        let _ = self.od.dict_mut().set_int(obj::MODES, i64::from(initial));
        let _ = self
            .od
            .dict_mut()
            .set_int(obj::MODES_DISPLAY, i64::from(initial));
        self.qs_code = self.spec.state_machine.default_quick_stop_option.code;
        self.fsa = Fsa::new(self.fsa_config());
        self.plan = Drive::Off;
        self.offset_units = 0.0;
        self.reset_motion_state();
        self.loss_counter = 0;
        self.counter_last = None;
        self.write_feedback(0);
    }

    // -----------------------------------------------------------------------------------------
    // Read-back.

    /// The spec.
    pub fn spec(&self) -> &'static DriveSpec {
        self.spec
    }

    /// The CiA 402 state.
    pub fn state(&self) -> State {
        self.fsa.state()
    }

    /// The statusword as last reported.
    pub fn statusword(&self) -> u16 {
        self.od.dict().uint(obj::STATUSWORD).unwrap_or(0) as u16
    }

    /// The mode of operation in effect (0x6061).
    pub fn mode(&self) -> i8 {
        self.mode
    }

    /// The actual position in position units (0x6064) as last reported.
    pub fn position(&self) -> i32 {
        self.od.dict().int(obj::POSITION_ACTUAL).unwrap_or(0) as i32
    }

    /// The motor position, revolutions.
    pub fn position_rev(&self) -> f64 {
        self.motor.position_rev()
    }

    /// The motor speed, rev/s.
    pub fn speed_rev_s(&self) -> f64 {
        self.motor.speed_rev_s()
    }

    /// The following error (0x60F4) as last reported, position units.
    pub fn following_error(&self) -> i32 {
        self.od.dict().int(obj::FOLLOWING_ERROR).unwrap_or(0) as i32
    }

    /// The alarm present, if any.
    pub fn alarm(&self) -> Option<&'static AlarmDef> {
        self.alarm
    }

    /// The last emergency queued for the master.
    pub fn last_emergency(&self) -> Option<Emergency> {
        self.last_emcy
    }

    /// The loss-of-data error counter (MR-J4-TM: +3 per missed cycle).
    pub fn sync_error_counter(&self) -> u32 {
        self.loss_counter
    }

    /// Counters.
    pub fn stats(&self) -> DriveStats {
        self.stats
    }

    /// Record the target position (0x607A) the drive acts on in each cycle in OP, up to
    /// `capacity` cycles (the buffer is allocated here, once): what reached the drive, cycle by
    /// cycle, for tests that check delivery at the drive's side.
    pub fn record_targets(&mut self, capacity: usize) {
        self.targets = Some(Vec::with_capacity(capacity));
    }

    /// The cycles recorded since [`Self::record_targets`].
    pub fn recorded_targets(&self) -> &[TargetSample] {
        self.targets.as_deref().unwrap_or(&[])
    }

    /// The CoE server's counters (SDO downloads accepted, aborts sent, …).
    pub fn coe_stats(&self) -> crate::coe::CoeStats {
        self.coe.stats()
    }

    /// The object dictionary (device view).
    pub fn od(&self) -> &OdStore {
        &self.od
    }

    /// The object dictionary, mutable (device-side changes by a test).
    pub fn od_mut(&mut self) -> &mut OdStore {
        &mut self.od
    }

    /// The AL state the drive last saw.
    pub fn al_state(&self) -> AlState {
        self.al
    }

    // -----------------------------------------------------------------------------------------
    // Fault injection.

    /// Raise the alarm named `id` (see [`DriveSpec::alarms`]) at the next cycle.
    pub fn raise_alarm(&mut self, id: &str) -> Result<(), UnknownAlarm> {
        let a = self.spec.alarm(id).ok_or_else(|| UnknownAlarm {
            drive: self.spec.name,
            id: id.to_string(),
            known: self
                .spec
                .alarms
                .iter()
                .map(|a| a.id)
                .collect::<Vec<_>>()
                .join(", "),
        })?;
        self.pending = Some(a);
        Ok(())
    }

    /// Report this following error (0x60F4) instead of the measured one, and supervise it, until
    /// `None` (a stuck load as the drive sees it).
    pub fn force_following_error(&mut self, value: Option<i32>) {
        self.forced_fe = value;
    }

    /// Block the load: the motor does not move (the following error then grows with the
    /// set-points).
    pub fn jam(&mut self, jammed: bool) {
        self.motor.set_jammed(jammed);
    }

    /// The outputs of the next `cycles` process-data cycles do not arrive: the drive keeps the
    /// previous outputs and counts them as missing.
    pub fn drop_outputs(&mut self, cycles: u32) {
        self.drop_outputs = self.drop_outputs.saturating_add(cycles);
    }

    /// Switch the loss-of-data supervision ([`DriveSpec::loss`]) and the cycle-counter check on
    /// or off (on at power-on). Off is what the MR-J4-TM does with [Pr. PN06] = 1___ and
    /// [Pr. PN02] = 0; tests with a master that is not real-time use it.
    pub fn set_loss_detection(&mut self, on: bool) {
        self.loss_detection = on;
        self.loss_counter = 0;
    }

    /// The same drive with the loss-of-data supervision off (see
    /// [`EmulatedDrive::set_loss_detection`]).
    pub fn without_loss_detection(mut self) -> Self {
        self.set_loss_detection(false);
        self
    }

    /// Main-circuit (DC bus) power present (statusword bit 4; losing it in Operation enabled is
    /// transition 8).
    pub fn set_main_power(&mut self, on: bool) {
        self.main_power = on;
    }

    /// The drive follows the fieldbus (statusword bit 9; BDHDE COMMmode).
    pub fn set_remote(&mut self, on: bool) {
        self.remote = on;
    }

    // -----------------------------------------------------------------------------------------
    // Units.

    fn units_per_rev(&self) -> f64 {
        match self.spec.scaling {
            Scaling::Fixed {
                position_per_rev, ..
            } => position_per_rev,
            Scaling::FactorProduct { gear, feed } => {
                let r = |i: u16, s: u8| {
                    self.od
                        .dict()
                        .uint(ObjectAddress::new(i, s))
                        .unwrap_or(1)
                        .max(1) as f64
                };
                (r(gear, 1) / r(gear, 2)) * (r(feed, 1) / r(feed, 2))
            }
        }
    }

    fn velocity_per_rev_s(&self) -> f64 {
        match self.spec.scaling {
            Scaling::Fixed {
                velocity_per_rev_s, ..
            } => velocity_per_rev_s,
            Scaling::FactorProduct { .. } => self.units_per_rev(),
        }
    }

    /// A ramp object's value as rev/s²: a time constant in ms from 0 to the rated speed
    /// (fixed scaling; `zero_as_ms` replaces 0) or an acceleration in units/s².
    fn ramp_rev_s2(&self, addr: ObjectAddress, zero_as_ms: Option<u64>) -> f64 {
        let v = self.od.dict().uint(addr).unwrap_or(0);
        match self.spec.scaling {
            Scaling::Fixed { .. } => {
                let ms = match (v, zero_as_ms) {
                    (0, Some(z)) => z,
                    (0, None) => return f64::INFINITY,
                    (v, _) => v,
                };
                self.spec.motor.rated_speed_rev_s / (ms as f64 / 1000.0)
            }
            Scaling::FactorProduct { .. } => (v.max(1) as f64) / self.units_per_rev(),
        }
    }

    fn permille_to_nm(&self, permille: f64) -> f64 {
        permille / 1000.0 * self.spec.motor.rated_torque_nm
    }

    fn int(&self, a: ObjectAddress) -> i64 {
        self.od.dict().int(a).unwrap_or(0)
    }

    fn actual_units(&self) -> f64 {
        self.motor.position_rev() * self.units_per_rev() + self.offset_units
    }

    // -----------------------------------------------------------------------------------------
    // The cycle.

    fn fsa_config(&self) -> DeviceConfig {
        let sm = &self.spec.state_machine;
        let mut qs = sm
            .quick_stop_option(self.qs_code)
            .unwrap_or(sm.default_quick_stop_option);
        if self.qs_immediate {
            qs = QuickStopOption::vendor(qs.code, StopRamp::Immediate, qs.end);
        }
        let mut c = sm.device_config(qs);
        if self.quirks.has(Quirk::NoStateSkipping) {
            c.state_skipping = false;
        }
        c
    }

    /// What an emulated drive has, for [`Quirks::check_for`]: everything.
    pub const CAPABILITIES: crate::quirks::Capabilities = crate::quirks::Capabilities {
        coe: true,
        cia402: true,
        following_error: true,
    };

    /// The same drive behaving like a device ecdrive did not write ([`crate::quirks`]):
    /// every quirk applies (the drive has a CoE mailbox and CiA 402 device control).
    pub fn with_quirks(mut self, quirks: Quirks) -> Self {
        self.quirks = quirks;
        self.coe = CoeServer::new(CoeConfig {
            complete_access: self.spec.model().is_ok_and(|m| m.complete_access),
            complete_access_refusal: self.spec.complete_access_refusal,
            sdo_info: esi_sdo_info(self.spec),
            quirks,
            ..CoeConfig::default()
        });
        self.od.set_quirks(quirks);
        self.fsa = Fsa::with_state(self.fsa_config(), self.fsa.state());
        if quirks.has(Quirk::NoHomeSwitch) {
            self.world.home_switch_rev = None;
        }
        self
    }

    /// Rebuild the state machine when the quick-stop behaviour changed (0x605A, or the
    /// torque-mode rule).
    fn refresh_fsa_config(&mut self) {
        let code = self.int(obj::QUICK_STOP_OPTION) as i16;
        let code = if self.spec.state_machine.quick_stop_option(code).is_some() {
            code
        } else {
            self.qs_code
        };
        let torque_mode = matches!(self.mode, 4 | 10);
        let immediate = self.spec.torque_mode_quick_stop_immediate && torque_mode;
        if code != self.qs_code || immediate != self.qs_immediate {
            self.qs_code = code;
            self.qs_immediate = immediate;
            self.fsa = Fsa::with_state(self.fsa_config(), self.fsa.state());
        }
    }

    fn reset_motion_state(&mut self) {
        let actual = self.actual_units();
        self.demand = actual;
        self.demand_prev = actual;
        self.last_target = None;
        self.csp_started = false;
        self.velocity_demand = self.motor.speed_rev_s();
        self.torque_demand_permille = 0.0;
        // The drive counts whole position units: a relative target adds to the position it
        // stands at, not to the motor model's fraction of a count (a target 0.4 counts off
        // never comes within a position window of 0).
        self.pp = ProfilePosition {
            last_target: actual.round(),
            ..ProfilePosition::default()
        };
    }

    fn raise(&mut self, a: &'static AlarmDef) {
        if self.alarm.is_some() {
            return;
        }
        self.alarm = Some(a);
        self.stats.alarms += 1;
        let rep = self.spec.reporting;
        let d = self.od.dict_mut();
        let _ = d.set_uint(obj::ERROR_CODE, u64::from(a.error_code));
        let _ = d.set_uint(obj::ERROR_REGISTER, u64::from(a.error_register));
        if let Some(c) = rep.current_alarm {
            let _ = d.set_uint(c, u64::from(a.detail));
        }
        if let Some(h) = rep.history_newest {
            let _ = d.set_uint(h, u64::from(a.detail));
        }
        if rep.error_history {
            push_error_history(self.od.dict_mut(), a.error_code);
        }
        let data = match rep.emcy_data {
            EmcyData::Zero => [0; 5],
            EmcyData::DetailLe => {
                let b = a.detail.to_le_bytes();
                [b[0], b[1], b[2], b[3], 0]
            }
        };
        self.emit(Emergency {
            error_code: a.error_code,
            error_register: a.error_register,
            data,
        });
        self.loss_counter = 0;
        tracing::debug!(drive = self.spec.name, alarm = a.id, "alarm");
    }

    fn emit(&mut self, e: Emergency) {
        self.coe.push_emergency(e);
        self.last_emcy = Some(e);
        self.stats.emergencies += 1;
    }

    fn clear_alarm(&mut self) {
        self.alarm = None;
        self.stats.resets += 1;
        if self.spec.loss.restart_on_reset {
            self.loss_counter = 0;
        }
        let rep = self.spec.reporting;
        let d = self.od.dict_mut();
        let _ = d.set_uint(obj::ERROR_REGISTER, 0);
        if rep.clear_error_code_on_reset {
            let _ = d.set_uint(obj::ERROR_CODE, 0);
        }
        if let Some(c) = rep.current_alarm {
            let _ = d.set_uint(c, 0);
        }
        if rep.emcy_on_reset {
            self.emit(Emergency {
                error_code: 0,
                error_register: 0,
                data: [0; 5],
            });
        }
    }

    fn alarm_by_id(&self, id: Option<&'static str>) -> Option<&'static AlarmDef> {
        id.and_then(|i| self.spec.alarm(i))
    }

    fn free_run_cycle_ns(&self) -> u32 {
        let ns = self.configured_cycle_ns().unwrap_or(0);
        match u32::try_from(ns) {
            Ok(n) if n > 0 => n,
            _ => 1_000_000,
        }
    }

    /// The cycle 0x60C2 tells: `:01` in the drive's unit while `:02` holds its own index, the
    /// standard `:01 × 10^(:02)` s otherwise (the form its set-up example writes).
    fn interpolation_ns(&self, vendor: Option<(i8, u32)>) -> Option<u64> {
        let d = self.od.dict();
        let value = d.uint(obj::INTERPOLATION_PERIOD)?;
        let power = d.int(ObjectAddress::new(0x60C2, 2))?;
        crate::cia402::interpolated::interpolation_cycle_ns(
            value,
            i8::try_from(power).ok()?,
            vendor,
        )
    }

    /// The cycle the drive is configured for (SYNC0 must match it).
    fn configured_cycle_ns(&self) -> Option<u64> {
        match self.spec.sync.cycle? {
            CycleSource::Nanoseconds(a) => self.od.dict().uint(a),
            CycleSource::Interpolation { vendor } => self.interpolation_ns(vendor),
        }
    }

    /// Loss-of-data and cycle-counter supervision of one DC cycle.
    fn supervise_cycle(&mut self, fresh: bool, cycle_ns: u32) {
        let loss = self.spec.loss;
        // While an alarm is present the counter may stand still (see
        // `LossDetection::restart_on_reset`).
        let counting = !(loss.restart_on_reset && self.alarm.is_some());
        if counting && fresh {
            self.loss_counter = self.loss_counter.saturating_sub(loss.decrement);
        } else if counting {
            self.loss_counter = self.loss_counter.saturating_add(loss.increment);
            if self.loss_counter >= loss.threshold(cycle_ns) && self.pending.is_none() {
                self.pending = self.alarm_by_id(Some(loss.alarm));
            }
        }
        // The incremental counter: +1 per cycle, checked when it arrives.
        let (Some(cc), Some(alarm)) = (self.spec.cycle_counter, self.spec.counter_alarm) else {
            return;
        };
        if !self.od.dict().is_mapped(Direction::Rx, cc.output) {
            self.counter_last = None;
            return;
        }
        if !fresh {
            self.counter_missed = self.counter_missed.wrapping_add(1);
            return;
        }
        let dl = self.od.dict().uint(cc.output).unwrap_or(0) as u8;
        if let Some(last) = self.counter_last {
            let expected = last.wrapping_add(self.counter_missed).wrapping_add(1);
            if dl != expected && self.pending.is_none() {
                self.pending = self.alarm_by_id(Some(alarm));
            }
        }
        self.counter_last = Some(dl);
        self.counter_missed = 0;
        if let Some(echo) = cc.echo {
            let _ = self
                .od
                .dict_mut()
                .set_uint(echo, u64::from(dl.wrapping_add(1)));
        }
    }

    /// Follow the motion the plan of the previous cycle asked for, then supervise.
    fn integrate(&mut self, dt_ns: u32) {
        let dt = f64::from(dt_ns) / 1e9;
        self.motor.step(self.plan, self.limits, dt);
        // Following error: only while the position loop runs.
        let position_loop = matches!(self.plan, Drive::Position { .. });
        let measured = if position_loop {
            self.demand - self.actual_units()
        } else {
            0.0
        };
        let fe = match self.forced_fe {
            Some(v) => f64::from(v),
            None => measured,
        };
        let spec = self.spec.following_error;
        let window = self.od.dict().uint(spec.window).unwrap_or(u64::MAX);
        let timeout_ns = self.od.dict().uint(spec.timeout_ms).unwrap_or(0) * 1_000_000;
        let supervised = window != spec.disabled
            && (position_loop || self.forced_fe.is_some())
            && self.fsa.state() == State::OperationEnabled;
        if supervised && fe.abs() > window as f64 {
            self.fe_over_ns = self.fe_over_ns.saturating_add(u64::from(dt_ns));
            if self.fe_over_ns > timeout_ns {
                self.fe_flag = true;
                if self.pending.is_none() && self.alarm.is_none() {
                    self.pending = self.alarm_by_id(spec.alarm);
                }
            }
        } else {
            self.fe_over_ns = 0;
            self.fe_flag = false;
        }
        let fe_i = (fe.round() as i64).clamp(i64::from(i32::MIN), i64::from(i32::MAX));
        let shown = if self.quirks.has(Quirk::FollowingErrorZero) {
            0
        } else {
            fe_i
        };
        let _ = self.od.dict_mut().set_int(obj::FOLLOWING_ERROR, shown);
    }

    /// Torque and speed limits of the next cycle.
    fn compute_limits(&mut self) {
        let t = self.spec.torque_limits;
        let peak = self.spec.motor.peak_torque_permille;
        let obj_limit =
            |a: Option<ObjectAddress>| a.and_then(|a| self.od.dict().uint(a)).map(|v| v as f64);
        let max = obj_limit(t.max).unwrap_or(peak).min(peak);
        let pos = obj_limit(t.positive).unwrap_or(peak).min(max);
        let neg = obj_limit(t.negative).unwrap_or(peak).min(max);
        let mut speed = self.spec.motor.max_speed_rev_s;
        if matches!(self.mode, 4 | 10)
            && let Some(a) = t.speed_limit
        {
            let v = self.od.dict().int(a).unwrap_or(0).unsigned_abs() as f64;
            speed = speed.min(v / self.velocity_per_rev_s());
        }
        self.limits = Limits {
            positive_nm: self.permille_to_nm(pos),
            negative_nm: self.permille_to_nm(neg),
            speed_rev_s: speed,
        };
    }

    /// Mode switching (0x6060 → 0x6061), with the zero-speed rule.
    fn switch_mode(&mut self) {
        let requested = self.int(obj::MODES) as i8;
        if requested == self.mode || requested == 0 || !self.allowed_modes.contains(&requested) {
            return;
        }
        if self.quirks.has(Quirk::ModesOnlyWhenDisabled)
            && self.fsa.state() == State::OperationEnabled
        {
            return;
        }
        let sm = &self.spec.state_machine;
        let pos = |m: i8| sm.is_position_mode(OperationMode::from_i8(m));
        if sm.position_mode_switch_needs_zero_speed
            && (pos(requested) || pos(self.mode))
            && !self.motor.stopped()
        {
            return;
        }
        self.mode = requested;
        self.reset_motion_state();
        // A completed homing stays reported when hm is entered again (MR-J4-TM §5.4.9 (3)
        // POINT); one in progress is interrupted.
        if self.homing != Homing::Attained {
            self.homing = Homing::default();
        }
    }

    /// The plan of the next cycle in Operation enabled, by the mode of operation.
    fn operate(&mut self, cw: ControlWord, dt_ns: u32) {
        let dt = f64::from(dt_ns) / 1e9;
        let m = Motion {
            cw,
            dt,
            halt: cw.contains(ControlWord::HALT),
            edge4: cw.contains(ControlWord::NEW_SET_POINT)
                && self.prev_cw & ControlWord::NEW_SET_POINT.bits() == 0,
            accel: self.ramp_rev_s2(obj::PROFILE_ACCELERATION, None),
            decel: self.ramp_rev_s2(obj::PROFILE_DECELERATION, None),
        };
        self.demand_prev = self.demand;
        match self.mode {
            8 => self.operate_csp(&m),
            9 => self.operate_csv(&m),
            10 => self.operate_cst(),
            3 => self.operate_pv(&m),
            4 => self.operate_tq(&m),
            1 => self.operate_pp(&m),
            6 => self.operate_hm(&m),
            // A mode the emulator does not run: hold the position.
            _ => self.plan_position(dt),
        }
    }

    /// Cyclic synchronous position.
    fn operate_csp(&mut self, m: &Motion) {
        let (halt, edge4, decel, dt) = (m.halt, m.edge4, m.decel, m.dt);
        let upr = self.units_per_rev();
        if halt && self.spec.halt_in_cyclic_modes {
            self.ramp_to_stop(decel, dt);
            return;
        }
        if self.spec.csp_start_edge && !self.csp_started {
            if !edge4 {
                // Not started: hold where the axis is.
                self.plan_position(dt);
                return;
            }
            self.csp_started = true;
        }
        let target = self.int(obj::TARGET_POSITION) as i32;
        let base = self.last_target.unwrap_or_else(|| {
            (self.demand.round() as i64).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
        });
        let delta = i64::from(target.wrapping_sub(base));
        if self.last_target.is_none() {
            self.command_unwrapped = i64::from(base);
        }
        self.command_unwrapped = self.command_unwrapped.saturating_add(delta);
        self.last_target = Some(target);
        let c = self.spec.command;
        if self.command_unwrapped < i64::from(i32::MIN)
            || self.command_unwrapped > i64::from(i32::MAX)
        {
            if let Some(a) = self.alarm_by_id(c.overflow_alarm) {
                self.pending = Some(a);
            }
        }
        let speed = delta.unsigned_abs() as f64 / upr / dt.max(1e-9);
        if speed > c.speed_factor * self.spec.motor.max_speed_rev_s
            && let Some(a) = self.alarm_by_id(c.speed_alarm)
        {
            self.pending = Some(a);
        }
        // The demand follows the unwrapped command (across the 32-bit wrap of 0x607A),
        // plus the position offset where the drive has one (0x60B0).
        let offset = self.int(obj::POSITION_OFFSET) as f64;
        self.demand = self.command_unwrapped as f64 + offset;
        self.plan_position(dt);
    }

    /// Cyclic synchronous velocity.
    fn operate_csv(&mut self, m: &Motion) {
        let (halt, decel, dt) = (m.halt, m.decel, m.dt);
        let vpr = self.velocity_per_rev_s();
        let v = (self.int(obj::TARGET_VELOCITY) + self.int(obj::VELOCITY_OFFSET)) as f64 / vpr;
        if halt && self.spec.halt_in_cyclic_modes {
            self.ramp_to_stop(decel, dt);
            return;
        }
        self.velocity_demand = v.clamp(-self.limits.speed_rev_s, self.limits.speed_rev_s);
        self.demand = self.actual_units();
        self.plan = Drive::Velocity {
            target_rev_s: self.velocity_demand,
        };
    }

    /// Cyclic synchronous torque.
    fn operate_cst(&mut self) {
        let t = (self.int(obj::TARGET_TORQUE) + self.int(obj::TORQUE_OFFSET)) as f64;
        self.torque_demand_permille = t;
        self.demand = self.actual_units();
        self.plan = Drive::Torque {
            torque_nm: self.permille_to_nm(t),
        };
    }

    /// Profile velocity.
    fn operate_pv(&mut self, m: &Motion) {
        let (halt, accel, decel, dt) = (m.halt, m.accel, m.decel, m.dt);
        let vpr = self.velocity_per_rev_s();
        let target = if halt {
            0.0
        } else {
            self.int(obj::TARGET_VELOCITY) as f64 / vpr
        };
        let target = target.clamp(-self.limits.speed_rev_s, self.limits.speed_rev_s);
        let v = self.velocity_demand;
        let rate = if target.abs() > v.abs() && target.signum() == v.signum() || v == 0.0 {
            accel
        } else {
            decel
        };
        self.velocity_demand = approach(v, target, rate * dt);
        self.demand = self.actual_units();
        self.plan = Drive::Velocity {
            target_rev_s: self.velocity_demand,
        };
    }

    /// Profile torque.
    fn operate_tq(&mut self, m: &Motion) {
        let (halt, dt) = (m.halt, m.dt);
        let target = if halt {
            0.0
        } else {
            self.int(obj::TARGET_TORQUE) as f64
        };
        let slope = self.od.dict().uint(obj::TORQUE_SLOPE).unwrap_or(0) as f64;
        // As ‰ of the rated torque per second.
        let slope = match self.spec.torque_slope {
            TorqueSlopeUnit::PerMillePerSecond => slope,
            TorqueSlopeUnit::MilliNewtonMetrePerSecond => {
                slope / (self.spec.motor.rated_torque_nm * 1000.0) * 1000.0
            }
            // 0 → 100 % of rated in that many ms.
            TorqueSlopeUnit::MillisecondsToRated if slope > 0.0 => 1000.0 / slope * 1000.0,
            TorqueSlopeUnit::MillisecondsToRated => 0.0,
        };
        self.torque_demand_permille = if slope == 0.0 {
            target
        } else {
            approach(self.torque_demand_permille, target, slope * dt)
        };
        self.demand = self.actual_units();
        self.plan = Drive::Torque {
            torque_nm: self.permille_to_nm(self.torque_demand_permille),
        };
    }

    /// Profile position.
    fn operate_pp(&mut self, m: &Motion) {
        let (cw, halt, edge4, accel, decel, dt) = (m.cw, m.halt, m.edge4, m.accel, m.decel, m.dt);
        let (upr, vpr) = (self.units_per_rev(), self.velocity_per_rev_s());
        if edge4 {
            let t = self.int(obj::TARGET_POSITION) as f64;
            let target = if cw.contains(ControlWord::RELATIVE) {
                self.pp.last_target + t
            } else {
                t
            };
            if self.pp.target.is_some() && !cw.contains(ControlWord::CHANGE_SET_IMMEDIATELY) {
                if self.pp.pending.is_none() {
                    self.pp.pending = Some(target);
                    self.pp.ack = true;
                }
            } else {
                self.pp.target = Some(target);
                self.pp.last_target = target;
                self.pp.ack = true;
            }
        }
        if !cw.contains(ControlWord::NEW_SET_POINT) {
            self.pp.ack = false;
        }
        let vmax = (self.od.dict().uint(obj::PROFILE_VELOCITY).unwrap_or(0) as f64).min(
            self.od
                .dict()
                .uint(obj::MAX_PROFILE_VELOCITY)
                .map_or(f64::INFINITY, |v| v as f64),
        ) / vpr
            * upr;
        let vmax = vmax.min(self.limits.speed_rev_s * upr);
        let (acc, dec) = (accel * upr, decel * upr);
        self.profile_step(halt, vmax, acc, dec, dt);
        self.plan_position(dt);
    }

    /// Homing: on bit 4's edge the method's end on the machine ([`crate::machine::homing_end`]);
    /// the demand moves there at 0x6099:01, the last [`HOMING_CREEP_REV`] at 0x6099:02, with
    /// 0x609A; there the reference reads as 0x607C. A search that runs into a limit switch, a
    /// method the drive does not run, or one the model does not know fails as the drive's spec
    /// says. Bit 4 falling stops the run (interrupted).
    fn operate_hm(&mut self, m: &Motion) {
        let (edge4, dt) = (m.edge4, m.dt);
        let bit4 = m.cw.contains(ControlWord::HOMING_START);
        let upr = self.units_per_rev();
        if edge4 {
            self.warning = None;
            let method = self.int(obj::HOMING_METHOD) as i8;
            let world_pos = self.motor.position_rev() * upr;
            let h = self.spec.homing;
            let end = if h.methods.contains(&method) {
                crate::machine::homing_end(method, &self.world, world_pos, upr, h.index_pulse)
            } else {
                crate::machine::HomingEnd::NotSupported
            };
            self.homing = match end {
                crate::machine::HomingEnd::Reference(r) => Homing::Running {
                    target: r + self.offset_units,
                    failing: false,
                    speed: 0.0,
                },
                crate::machine::HomingEnd::Fails { at } => Homing::Running {
                    target: at + self.offset_units,
                    failing: true,
                    speed: 0.0,
                },
                crate::machine::HomingEnd::NotSupported => {
                    self.homing_failed();
                    Homing::Error
                }
            };
        }
        if let Homing::Running {
            target,
            failing,
            speed,
        } = self.homing
        {
            if !bit4 || m.halt {
                self.homing = Homing::Stopping { speed };
            } else {
                let vpr = self.velocity_per_rev_s();
                let fast = self.od.dict().uint(obj::HOMING_SPEED_SWITCH).unwrap_or(0) as f64;
                let slow = self.od.dict().uint(obj::HOMING_SPEED_ZERO).unwrap_or(0) as f64;
                let near = (target - self.demand).abs() <= HOMING_CREEP_REV * upr;
                let vmax = (if near { slow } else { fast }) / vpr * upr;
                let vmax = vmax.min(self.limits.speed_rev_s * upr);
                let acc = self.ramp_rev_s2(obj::HOMING_ACCELERATION, None) * upr;
                let acc = if acc.is_finite() { acc } else { f64::MAX / 4.0 };
                let (arrived, v) = step_toward(&mut self.demand, target, speed, vmax, acc, dt);
                self.homing = Homing::Running {
                    target,
                    failing,
                    speed: v,
                };
                if arrived && failing {
                    self.homing_failed();
                    self.homing = Homing::Error;
                } else if arrived {
                    let home = self.int(obj::HOME_OFFSET) as f64;
                    self.offset_units += home - target;
                    self.demand = home;
                    self.demand_prev = home;
                    self.homing = Homing::Attained;
                    self.plan_position(dt);
                    return;
                }
            }
        }
        if let Homing::Stopping { speed } = self.homing {
            // An interrupted homing decelerates on the homing acceleration (MR-J4-TM §5.7:
            // "hm: The servo motor decelerates to a stop with Homing acceleration (609Ah)").
            let acc = self.ramp_rev_s2(obj::HOMING_ACCELERATION, None) * upr;
            let step = if acc.is_finite() { acc * dt } else { f64::MAX };
            let v = approach(speed, 0.0, step);
            self.demand += v * dt;
            self.homing = if v == 0.0 {
                Homing::Idle
            } else {
                Homing::Stopping { speed: v }
            };
        }
        self.plan_position(dt);
    }

    /// The touch probe over one cycle's travel from `from_rev` to `to_rev` (motor revolutions),
    /// as [`crate::machine::TouchProbes`] describes it; the latches into 0x60BA–0x60BD.
    fn touch_probe(&mut self, from_rev: f64, to_rev: f64) {
        let f = self.od.dict().uint(obj::TOUCH_PROBE_FUNCTION).unwrap_or(0) as u16;
        let upr = self.units_per_rev();
        let (st, latched) = self.probes.step(
            f,
            &self.world,
            (from_rev * upr, to_rev * upr),
            upr,
            self.offset_units,
            self.spec.touch_probe_index_pulse,
        );
        let objects = [
            obj::TOUCH_PROBE_1_RISING,
            obj::TOUCH_PROBE_1_FALLING,
            obj::TOUCH_PROBE_2_RISING,
            obj::TOUCH_PROBE_2_FALLING,
        ];
        for (o, v) in objects.into_iter().zip(latched) {
            if let Some(v) = v {
                let _ = self.od.dict_mut().set_int(o, v);
            }
        }
        let _ = self
            .od
            .dict_mut()
            .set_uint(obj::TOUCH_PROBE_STATUS, u64::from(st));
    }

    /// Report a failed homing as the drive's spec says.
    fn homing_failed(&mut self) {
        match self.spec.homing.failure {
            super::spec::HomingFailure::Warning { id, text } => {
                self.warning = Some((id, text));
            }
            super::spec::HomingFailure::Fault { alarm } => {
                if let Some(a) = self.alarm_by_id(Some(alarm)) {
                    self.pending = Some(a);
                }
            }
        }
    }

    fn plan_position(&mut self, _dt: f64) {
        let upr = self.units_per_rev();
        self.plan = Drive::Position {
            from_rev: (self.demand_prev - self.offset_units) / upr,
            to_rev: (self.demand - self.offset_units) / upr,
        };
    }

    /// Decelerate the demand to a stop at `decel` rev/s² (halt, quick stop).
    fn ramp_to_stop(&mut self, decel: f64, dt: f64) {
        let v = approach(self.motor.speed_rev_s(), 0.0, decel * dt);
        self.velocity_demand = v;
        self.demand = self.actual_units();
        self.last_target = None;
        self.plan = Drive::Velocity { target_rev_s: v };
    }

    /// One cycle of the profile-position set-point generator.
    fn profile_step(&mut self, halt: bool, vmax: f64, acc: f64, dec: f64, dt: f64) {
        let Some(target) = self.pp.target else {
            self.pp.speed = 0.0;
            return;
        };
        let s = target - self.demand;
        let v = self.pp.speed;
        let dec = if dec.is_finite() { dec } else { f64::MAX / 4.0 };
        let acc = if acc.is_finite() { acc } else { f64::MAX / 4.0 };
        let braking = v * v / (2.0 * dec);
        let braking_now = s.abs() <= braking + v.abs() * dt && s.signum() == v.signum();
        let wanted = if halt || braking_now {
            0.0
        } else {
            vmax.copysign(s)
        };
        let rate = if wanted.abs() > v.abs() && (v == 0.0 || wanted.signum() == v.signum()) {
            acc
        } else {
            dec
        };
        let mut nv = approach(v, wanted, rate * dt);
        // Never pass the target.
        let step = nv * dt;
        if !halt && (step.abs() >= s.abs() || (s.abs() < 1e-9 && nv.abs() <= dec * dt)) {
            self.demand = target;
            nv = 0.0;
            self.pp.target = self.pp.pending.take();
            if let Some(t) = self.pp.target {
                self.pp.last_target = t;
            }
        } else {
            self.demand += step;
        }
        self.pp.speed = nv;
    }

    /// Statusword bits 10–13 of the current mode, and the time windows behind them.
    fn mode_bits(&mut self, dt_ns: u32, enabled: bool) -> u16 {
        let mut sw = 0u16;
        let actual = self.actual_units();
        let vpr = self.velocity_per_rev_s();
        let v_units = self.motor.speed_rev_s() * vpr;
        let ms = |a: ObjectAddress, d: &Self| d.od.dict().uint(a).unwrap_or(0) * 1_000_000;
        match self.mode {
            8..=10 => {
                if enabled {
                    sw |= StatusWord::DRIVE_FOLLOWS_COMMAND.bits();
                }
                if self.mode == 8 && self.fe_flag {
                    sw |= StatusWord::FOLLOWING_ERROR.bits();
                }
            }
            1 => {
                let window = self.od.dict().uint(obj::POSITION_WINDOW).unwrap_or(0);
                let within = window == u64::from(u32::MAX)
                    || (self.pp.last_target - actual.round()).abs() <= window as f64;
                if within && self.pp.target.is_none() {
                    self.in_window_ns = self.in_window_ns.saturating_add(u64::from(dt_ns));
                } else {
                    self.in_window_ns = 0;
                }
                let halted = self.prev_cw & ControlWord::HALT.bits() != 0 && self.motor.stopped();
                if halted
                    || self.in_window_ns > 0
                        && self.in_window_ns >= ms(obj::POSITION_WINDOW_TIME, self)
                {
                    sw |= StatusWord::TARGET_REACHED.bits();
                }
                let held = if self.spec.pp_ack_while_moving {
                    self.pp.target.is_some()
                } else {
                    self.pp.pending.is_some()
                };
                if self.pp.ack || held {
                    sw |= StatusWord::SET_POINT_ACKNOWLEDGE.bits();
                }
                if self.fe_flag {
                    sw |= StatusWord::FOLLOWING_ERROR.bits();
                }
            }
            3 => {
                let target = self.int(obj::TARGET_VELOCITY) as f64;
                let window = self.od.dict().uint(obj::VELOCITY_WINDOW).unwrap_or(0) as f64;
                if (v_units - target).abs() <= window {
                    self.speed_window_ns = self.speed_window_ns.saturating_add(u64::from(dt_ns));
                } else {
                    self.speed_window_ns = 0;
                }
                if self.speed_window_ns > 0
                    && self.speed_window_ns >= ms(obj::VELOCITY_WINDOW_TIME, self)
                {
                    sw |= StatusWord::TARGET_REACHED.bits();
                }
                let threshold = self.od.dict().uint(obj::VELOCITY_THRESHOLD).unwrap_or(0) as f64;
                if v_units.abs() <= threshold {
                    self.speed_zero_ns = self.speed_zero_ns.saturating_add(u64::from(dt_ns));
                } else {
                    self.speed_zero_ns = 0;
                }
                if self.speed_zero_ns > 0
                    && self.speed_zero_ns >= ms(obj::VELOCITY_THRESHOLD_TIME, self)
                {
                    sw |= StatusWord::SPEED_ZERO.bits();
                }
            }
            4 => {
                let target = self.int(obj::TARGET_TORQUE) as f64;
                if self.spec.tq_target_reached && (self.torque_demand_permille - target).abs() < 0.5
                {
                    sw |= StatusWord::TARGET_REACHED.bits();
                }
            }
            // The manual's table (MR-J4-TM §5.4.9 (3)): 000 in progress, 001 interrupted or not
            // started, 011 completed, 10x error (velocity not 0 / 0).
            6 => match self.homing {
                Homing::Idle => sw |= StatusWord::TARGET_REACHED.bits(),
                Homing::Running { .. } | Homing::Stopping { .. } => {}
                Homing::Attained => {
                    sw |= StatusWord::HOMING_ATTAINED.bits();
                    if self.motor.stopped() {
                        sw |= StatusWord::TARGET_REACHED.bits();
                    }
                }
                Homing::Error => {
                    sw |= StatusWord::HOMING_ERROR.bits();
                    if self.motor.stopped() {
                        sw |= StatusWord::TARGET_REACHED.bits();
                    }
                }
            },
            _ => {}
        }
        sw
    }

    /// Write the feedback objects of this cycle.
    fn write_feedback(&mut self, mode_bits: u16) {
        let vpr = self.velocity_per_rev_s();
        let actual = self.actual_units();
        let clamp_i32 = |v: f64| -> i64 {
            let r = v.round();
            if r.is_nan() {
                0
            } else {
                // Position counters wrap like a 32-bit register.
                (r.rem_euclid(4_294_967_296.0) as i64) as i32 as i64
            }
        };
        let sat = |v: f64, lo: i64, hi: i64| -> i64 {
            if v.is_nan() {
                0
            } else {
                (v.round() as i64).clamp(lo, hi)
            }
        };
        let speed = self.motor.speed_rev_s();
        let torque_permille = self.motor.torque_nm() / self.spec.motor.rated_torque_nm * 1000.0;
        let powered = self.plan != Drive::Off;
        let sw = self.fsa.statusword().bits() | mode_bits;
        let upr = self.units_per_rev();
        let switches = self
            .world
            .digital_inputs(self.motor.position_rev() * upr, upr);
        let d = self.od.dict_mut();
        // 0x60FD bits 0–2: negative and positive limit switch, home switch (the machine's).
        let inputs = d.uint(obj::DIGITAL_INPUTS).unwrap_or(0) & !0x7;
        let _ = d.set_uint(obj::DIGITAL_INPUTS, inputs | u64::from(switches));
        let _ = d.set_uint(obj::STATUSWORD, u64::from(sw));
        let _ = d.set_int(obj::MODES_DISPLAY, i64::from(self.mode));
        let _ = d.set_int(obj::POSITION_ACTUAL, clamp_i32(actual));
        let _ = d.set_int(obj::POSITION_INTERNAL, clamp_i32(actual));
        let _ = d.set_int(obj::POSITION_DEMAND, clamp_i32(self.demand));
        let _ = d.set_int(obj::POSITION_DEMAND_INTERNAL, clamp_i32(self.demand));
        let i32r = (i64::from(i32::MIN), i64::from(i32::MAX));
        let i16r = (i64::from(i16::MIN), i64::from(i16::MAX));
        let _ = d.set_int(obj::VELOCITY_ACTUAL, sat(speed * vpr, i32r.0, i32r.1));
        let dt = f64::from(self.last_dt_ns.max(1)) / 1e9;
        let vd = match self.plan {
            Drive::Velocity { target_rev_s } => target_rev_s,
            Drive::Position { from_rev, to_rev } => (to_rev - from_rev) / dt,
            _ => 0.0,
        };
        let _ = d.set_int(obj::VELOCITY_DEMAND, sat(vd * vpr, i32r.0, i32r.1));
        let _ = d.set_int(obj::CONTROL_EFFORT, sat(vd * vpr, i32r.0, i32r.1));
        let _ = d.set_int(obj::TORQUE_ACTUAL, sat(torque_permille, i16r.0, i16r.1));
        let td = if powered {
            match self.plan {
                Drive::Torque { torque_nm } => torque_nm / self.spec.motor.rated_torque_nm * 1000.0,
                _ => torque_permille,
            }
        } else {
            0.0
        };
        let _ = d.set_int(obj::TORQUE_DEMAND, sat(td, i16r.0, i16r.1));
        for m in self.spec.monitors {
            let v = match m.quantity {
                Quantity::SpeedRpm => speed * 60.0,
                Quantity::TorquePercent => torque_permille / 10.0,
                Quantity::CurrentPermille => torque_permille,
                Quantity::Position => actual,
                Quantity::DcLinkMillivolt => 320_000.0,
            };
            let _ = d.set_int(m.address, sat(v, i32r.0, i32r.1));
        }
        for b in self.spec.status_bits {
            let on = match b.condition {
                Condition::ZeroSpeed => self.motor.stopped(),
                Condition::InPosition => {
                    let w = d.uint(obj::POSITION_WINDOW).unwrap_or(0) as f64;
                    (self.demand - actual).abs() <= w
                }
                Condition::TorqueLimited => powered && self.motor.torque_limited(),
                Condition::SpeedLimited => powered && self.motor.speed_limited(),
                Condition::PowerStageOn => powered,
            };
            let cur = d.uint(b.address).unwrap_or(0);
            let mask = 1u64 << b.bit;
            let _ = d.set_uint(b.address, if on { cur | mask } else { cur & !mask });
        }
    }

    /// One process-data cycle.
    fn cycle(&mut self, event: &SyncEvent, outputs: &[u8]) {
        self.stats.cycles += 1;
        let dc = event.kind == SyncKind::Sync0;
        let dt_ns = if dc && event.cycle_time_ns > 0 {
            event.cycle_time_ns
        } else {
            self.free_run_cycle_ns()
        };
        // 1. The motion of the cycle that just ended, and the touch probe on it.
        self.last_dt_ns = dt_ns;
        let before = self.motor.position_rev();
        self.integrate(dt_ns);
        self.touch_probe(before, self.motor.position_rev());
        // 2. The outputs of this cycle.
        let op = event.outputs_enabled && self.al == AlState::Op;
        let mut fresh = !dc || event.outputs_fresh();
        if self.drop_outputs > 0 {
            self.drop_outputs -= 1;
            fresh = false;
        }
        if op && fresh {
            for s in &self.rx {
                let n = s.bits.div_ceil(8).min(8);
                let mut buf = [0u8; 8];
                copy_bits(outputs, s.bit, &mut buf, 0, s.bits);
                if let Some(b) = buf.get(..n) {
                    let _ = self.od.dict_mut().set_raw(s.addr, b);
                }
            }
        }
        if op && !fresh {
            self.stats.missed_outputs += 1;
        }
        if op && self.targets.is_some() {
            let target = self.int(obj::TARGET_POSITION) as i32;
            if let Some(t) = self.targets.as_mut()
                && t.len() < t.capacity()
            {
                t.push(TargetSample {
                    cycle: event.cycle,
                    fresh,
                    target,
                });
            }
        }
        if op && dc && self.loss_detection {
            self.supervise_cycle(fresh, dt_ns);
        }
        if let Some(a) = self.pending.take() {
            self.raise(a);
        }
        // 3. The state machine: commands act only in OP.
        let cw = if op {
            ControlWord::from_raw(self.od.dict().uint(obj::CONTROLWORD).unwrap_or(0) as u16)
        } else {
            ControlWord::from_raw(0)
        };
        let reset_edge = cw.contains(ControlWord::FAULT_RESET) && self.prev_cw & 0x0080 == 0 && op;
        if reset_edge
            && self.fsa.state() == State::Fault
            && let Some(a) = self.alarm
            && a.resettable
        {
            self.clear_alarm();
        }
        self.refresh_fsa_config();
        let before = self.fsa.state();
        let stopped = match before {
            State::QuickStopActive => self.motor.stopped() || self.qs_immediate,
            // The fault reaction switches the power stage off at once.
            _ => true,
        };
        let reaction = self.fsa.step(&DeviceInputs {
            controlword: cw,
            fault: self.alarm.is_some(),
            motion_stopped: stopped,
            main_power: self.main_power,
            remote: self.remote,
            warning: self.warning.is_some(),
        });
        let state = self.fsa.state();
        if let Reaction::Transition(t) = reaction
            && t.to == State::OperationEnabled
        {
            // Entering Operation enabled: the demand starts at the actual position.
            self.reset_motion_state();
        }
        // 4. Mode and the plan of the next cycle.
        self.switch_mode();
        self.refresh_fsa_config();
        self.compute_limits();
        match state {
            State::OperationEnabled => self.operate(cw, dt_ns),
            State::QuickStopActive if !self.qs_immediate => {
                let qs = self.spec.state_machine.quick_stop_option(self.qs_code);
                let addr = match qs.map(|q| q.ramp) {
                    Some(StopRamp::SlowDown) => obj::PROFILE_DECELERATION,
                    _ => obj::QUICK_STOP_DECELERATION,
                };
                let zero_ms = (addr == obj::QUICK_STOP_DECELERATION).then_some(100);
                let decel = self.ramp_rev_s2(addr, zero_ms);
                if matches!(qs.map(|q| q.ramp), Some(StopRamp::Immediate)) {
                    self.plan = Drive::Off;
                } else {
                    self.ramp_to_stop(decel, f64::from(dt_ns) / 1e9);
                }
            }
            _ => {
                self.plan = Drive::Off;
                self.reset_motion_state();
            }
        }
        let enabled = state == State::OperationEnabled;
        let bits = self.mode_bits(dt_ns, enabled);
        self.prev_cw = cw.bits();
        self.write_feedback(bits);
    }
}

/// Move `from` towards `to` by at most `step` (≥ 0).
/// One cycle of a trapezoidal move of `pos` to `target` from speed `v` (units/s) within `vmax`
/// and `acc`; returns whether it arrived (then at the target, stopped) and the new speed.
fn step_toward(pos: &mut f64, target: f64, v: f64, vmax: f64, acc: f64, dt: f64) -> (bool, f64) {
    let d = target - *pos;
    let brake = (2.0 * acc * d.abs()).sqrt();
    let wanted = d.signum() * vmax.abs().min(brake);
    let nv = approach(v, wanted, acc * dt);
    let step = nv * dt;
    if d.abs() < 0.5 || (step != 0.0 && step.abs() >= d.abs() && step.signum() == d.signum()) {
        *pos = target;
        return (true, 0.0);
    }
    *pos += step;
    (false, nv)
}

fn approach(from: f64, to: f64, step: f64) -> f64 {
    let step = if step.is_finite() {
        step.abs()
    } else {
        f64::MAX
    };
    if (to - from).abs() <= step {
        to
    } else {
        from + step.copysign(to - from)
    }
}

/// Push `code` into 0x1003 (newest in sub 1), if the object exists.
fn push_error_history(d: &mut crate::coe::ValueStore, code: u16) {
    let Some(o) = d.object_desc(0x1003) else {
        return;
    };
    let max = o.entries.iter().map(|e| e.sub).max().unwrap_or(0);
    let n = d.uint(ObjectAddress::new(0x1003, 0)).unwrap_or(0) as u8;
    let mut k = max;
    while k > 1 {
        let prev = d.uint(ObjectAddress::new(0x1003, k - 1)).unwrap_or(0);
        let _ = d.set_uint(ObjectAddress::new(0x1003, k), prev);
        k -= 1;
    }
    let _ = d.set_uint(ObjectAddress::new(0x1003, 1), u64::from(code));
    let _ = d.set_uint(
        ObjectAddress::new(0x1003, 0),
        u64::from(n.saturating_add(1).min(max)),
    );
}

fn esi_sdo_info(spec: &DriveSpec) -> bool {
    spec.model().map_or(true, |m| m.sdo_info)
}

impl Device for EmulatedDrive {
    fn power_cycle(&mut self) {
        EmulatedDrive::power_cycle(self);
    }

    fn quirks(&self) -> Quirks {
        self.quirks
    }

    fn description(&self) -> DeviceDescription {
        match self.spec.model().and_then(|m| m.description(self.serial)) {
            Ok(mut d) => {
                if self.quirks.has(Quirk::NoSdoInfo) {
                    d.coe_details.remove(crate::sii::CoeDetails::SDO_INFO);
                }
                d
            }
            Err(e) => {
                // The drive's ESI is part of the build and checked by the tests; an error here
                // is a programming error, reported and answered with an empty device.
                tracing::error!(drive = self.spec.name, error = %e, "ESI cannot be turned into an SII");
                DeviceDescription::default()
            }
        }
    }

    fn process_data_sizes(&self) -> ProcessDataSizes {
        match self.od.mapping() {
            Ok(m) => ProcessDataSizes {
                outputs: m.bytes(Direction::Rx),
                inputs: m.bytes(Direction::Tx),
            },
            Err(_) => ProcessDataSizes::default(),
        }
    }

    fn request_state(&mut self, r: &StateRequest) -> Result<(), AlStatusCode> {
        match (r.from, r.to) {
            (AlState::PreOp, AlState::SafeOp) => {
                let m = self
                    .od
                    .mapping()
                    .map_err(|_| AlStatusCode::INVALID_OUTPUT_MAPPING)?;
                self.spec
                    .pdo_limits
                    .validate(&m, None)
                    .map_err(|_| AlStatusCode::INVALID_OUTPUT_MAPPING)?;
                Ok(())
            }
            (AlState::SafeOp, AlState::Op) => {
                let model = self
                    .spec
                    .model()
                    .map_err(|_| AlStatusCode::INVALID_DC_SYNC_CONFIG)?;
                let dc = match self.spec.sync.sync_type {
                    Some(a) => self.od.dict().uint(a).unwrap_or(0) == 2,
                    None => r.dc.sync0_active,
                };
                if dc {
                    if !r.dc.sync0_active || model.dc_sync0.is_none() {
                        return Err(AlStatusCode::INVALID_DC_SYNC_CONFIG);
                    }
                    let cycle = r.dc.sync0_cycle_ns;
                    if !model.accepts_cycle(true, cycle) {
                        return Err(self.spec.sync_cycle_mismatch);
                    }
                    if let Some(want) = self.configured_cycle_ns()
                        && want != u64::from(cycle)
                    {
                        return Err(self.spec.sync_cycle_mismatch);
                    }
                } else if model.free_run.is_none() {
                    return Err(AlStatusCode::INVALID_DC_SYNC_CONFIG);
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    fn state_changed(&mut self, from: AlState, to: AlState, _error: Option<AlStatusCode>) {
        self.al = to;
        if from == AlState::Bootstrap && to == AlState::Init {
            // The device restarts with the firmware written in BOOT, if any.
            if let Some(fw) = self.foe.as_mut().and_then(|f| f.take_firmware()) {
                tracing::info!(
                    drive = self.spec.name,
                    revision = fw.revision,
                    version = %fw.version,
                    "firmware updated"
                );
                self.firmware = Some(fw);
                self.apply_firmware();
            }
        }
        if from == AlState::PreOp && to == AlState::SafeOp {
            if let Ok(m) = self.od.mapping() {
                self.rx = layout(&m, Direction::Rx);
                self.tx = layout(&m, Direction::Tx);
            }
            self.loss_counter = 0;
            self.counter_last = None;
        }
        if from == AlState::Op && to != AlState::Op {
            // Leaving OP re-initialises the drive's control: the power stage goes off. With the
            // motor energised that is a fault of its own on some drives.
            let energised = matches!(
                self.fsa.state(),
                State::OperationEnabled | State::QuickStopActive
            );
            if energised && let Some(a) = self.alarm_by_id(self.spec.leave_op_alarm) {
                self.raise(a);
                self.fsa.step(&DeviceInputs {
                    controlword: ControlWord::from_raw(0),
                    fault: true,
                    motion_stopped: true,
                    main_power: self.main_power,
                    remote: self.remote,
                    warning: false,
                });
            }
            if !self.fsa.state().is_fault() {
                self.fsa = Fsa::with_state(self.fsa_config(), State::SwitchOnDisabled);
            }
            self.plan = Drive::Off;
            self.reset_motion_state();
            self.write_feedback(0);
        }
        if matches!(to, AlState::Init | AlState::PreOp) {
            self.rx.clear();
            self.tx.clear();
        }
    }

    fn mailbox_request(
        &mut self,
        state: AlState,
        request: &[u8],
        reply: &mut [u8],
    ) -> Option<usize> {
        self.coe
            .handle_with_foe(request, state, &mut self.od, self.foe.as_mut(), reply)
    }

    fn mailbox_poll(&mut self, reply: &mut [u8]) -> Option<usize> {
        self.coe.poll_unsolicited(reply)
    }

    fn mailbox_reset(&mut self) {
        self.coe.reset();
        if let Some(f) = self.foe.as_mut() {
            f.reset();
        }
    }

    fn inject(&mut self, fault: &crate::faults::DeviceFault) -> bool {
        use crate::faults::DeviceFault;
        match *fault {
            DeviceFault::RaiseAlarm(id) => match self.spec.alarm(id) {
                // Looked up first: an unknown name must not build an error (allocation).
                Some(a) => {
                    self.pending = Some(a);
                    true
                }
                None => false,
            },
            DeviceFault::ForceFollowingError(v) => {
                self.force_following_error(v);
                true
            }
            DeviceFault::Emergency {
                error_code,
                error_register,
                data,
            } => {
                self.coe.push_emergency(crate::coe::Emergency {
                    error_code,
                    error_register,
                    data,
                });
                true
            }
            DeviceFault::AbortSdo {
                index,
                subindex,
                code,
            } => {
                self.coe.abort_next_sdo(index, subindex, code);
                true
            }
            DeviceFault::EmergencyDuringSdo {
                error_code,
                error_register,
                data,
            } => {
                self.coe.emergency_during_next_sdo(crate::coe::Emergency {
                    error_code,
                    error_register,
                    data,
                });
                true
            }
        }
    }

    fn sync(
        &mut self,
        event: &SyncEvent,
        outputs: &[u8],
        inputs: &mut [u8],
    ) -> Result<(), AlStatusCode> {
        if self.quirks.has(Quirk::CycleTimeReadOnly) {
            self.od.dict_mut().show_sync0_cycle(event);
        }
        self.cycle(event, outputs);
        for s in &self.tx {
            if let Some(v) = self.od.dict().raw(s.addr) {
                copy_bits(v, 0, inputs, s.bit, s.bits);
            }
        }
        Ok(())
    }
}

/// What one cycle in Operation enabled starts from: the controlword and its edges, the cycle
/// time and the profile ramps.
struct Motion {
    cw: ControlWord,
    dt: f64,
    halt: bool,
    /// Bit 4 (new set-point) rose.
    edge4: bool,
    /// Profile acceleration and deceleration, rev/s².
    accel: f64,
    decel: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn approach_moves_by_at_most_the_step() {
        assert_eq!(approach(0.0, 10.0, 3.0), 3.0);
        assert_eq!(approach(0.0, -10.0, 3.0), -3.0);
        assert_eq!(approach(9.0, 10.0, 3.0), 10.0);
        assert_eq!(approach(1.0, 2.0, f64::INFINITY), 2.0);
    }

    #[test]
    fn bit_copy() {
        let src = [0b1010_1100u8, 0xFF];
        let mut dst = [0u8; 2];
        copy_bits(&src, 2, &mut dst, 5, 6);
        assert_eq!(dst, [0b0110_0000, 0b0000_0101]);
    }
}
