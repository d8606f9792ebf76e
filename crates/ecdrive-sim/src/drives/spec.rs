//! What an emulated drive is, as data: its ESI file (identity, dictionary, CoE details,
//! synchronisation modes, SII) plus the emulator's own model of the drive's behaviour (state
//! machine, PDO rules, write rules, alarms, loss-of-data detection, motor, monitors).
//!
//! The engine ([`super::EmulatedDrive`]) reads a [`DriveSpec`] and never asks which vendor it
//! emulates. Nothing here comes from the master's drive profiles: the emulation is a model of
//! the drive as its manual describes it, written separately, so that a wrong value on either
//! side shows up as a disagreement in the tests (`tests/manual_facts/` checks both against the
//! manuals). Each drive's spec file keeps its \[REC\] values in one labelled section.

use super::esi_model::{EsiModel, EsiModelError};
use crate::cia402::device::DeviceConfig;
use crate::cia402::{OperationMode, QuickStopOption};
use crate::od::{ObjectAddress, ObjectDesc, SdoAbortCode};
use crate::pdo::PdoLimits;
use std::sync::OnceLock;

/// The CiA 402 state machine as the drive implements it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateMachineSpec {
    /// The direct jumps Switch on disabled → Switched on / Operation enabled and Ready to
    /// switch on → Operation enabled are accepted.
    pub state_skipping: bool,
    /// Transition 16 (Quick stop active → Operation enabled) exists.
    pub transition_16: bool,
    /// The quick-stop option codes 0x605A accepts.
    pub quick_stop_options: &'static [QuickStopOption],
    /// 0x605A at power-on.
    pub default_quick_stop_option: QuickStopOption,
    /// Switching 0x6060 to or from a position mode needs zero speed; otherwise the request is
    /// ignored.
    pub position_mode_switch_needs_zero_speed: bool,
    /// Vendor modes (negative 0x6060 values) that count as position modes for that rule.
    pub vendor_position_modes: &'static [i8],
    /// While statusword bit 9 (remote) is 0 only quick stop, fault reset and halt act.
    pub remote_gates_controlword: bool,
}

impl StateMachineSpec {
    /// The quick-stop option with 0x605A value `code`, if the drive accepts it.
    pub fn quick_stop_option(&self, code: i16) -> Option<QuickStopOption> {
        self.quick_stop_options
            .iter()
            .copied()
            .find(|o| o.code == code)
    }

    /// Whether `mode` is a position mode on this drive.
    pub fn is_position_mode(&self, mode: OperationMode) -> bool {
        match mode {
            OperationMode::Vendor(v) => self.vendor_position_modes.contains(&v),
            m => m.is_position_mode(),
        }
    }

    /// The device model's configuration with quick-stop option `quick_stop` in effect.
    pub const fn device_config(&self, quick_stop: QuickStopOption) -> DeviceConfig {
        DeviceConfig {
            state_skipping: self.state_skipping,
            transition_16: self.transition_16,
            quick_stop,
            remote_gates_controlword: self.remote_gates_controlword,
            init_cycles: 0,
        }
    }
}

/// How the drive learns its cycle over CoE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CycleSource {
    /// The cycle in ns is written into this object (0x1C32:02).
    Nanoseconds(ObjectAddress),
    /// 0x60C2 interpolation time period, `:01 × 10^(:02)` s; with `vendor = Some((index,
    /// unit_ns))` the drive reads `:01` in `unit_ns` while `:02` holds `index`.
    Interpolation {
        /// The drive's own reading of one index.
        vendor: Option<(i8, u32)>,
    },
}

/// The synchronisation objects of the drive. Which modes it offers (free run, DC SYNC0) and
/// the cycle times each allows come from its ESI file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncObjects {
    /// Where the master writes the synchronisation type (0x1C32:01: 0 free run, 2 DC SYNC0);
    /// without it the drive runs DC whenever SYNC0 is active.
    pub sync_type: Option<ObjectAddress>,
    /// How the drive learns its cycle, if at all.
    pub cycle: Option<CycleSource>,
}

/// A counter the master advances by one every cycle, and the drive's echo of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CycleCounterSpec {
    /// The master's counter (RxPDO).
    pub output: ObjectAddress,
    /// The drive's echo (TxPDO), `output + 1`, if any.
    pub echo: Option<ObjectAddress>,
}

/// One alarm (fault) the emulated drive can raise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AlarmDef {
    /// The drive's own name, e.g. `"AL.86.1"` or `"J3"`; [`super::EmulatedDrive::raise_alarm`]
    /// takes it.
    pub id: &'static str,
    /// What it means.
    pub text: &'static str,
    /// The 0x603F value and the EMCY error code.
    pub error_code: u16,
    /// The bits set in 0x1001 while the alarm is present.
    pub error_register: u8,
    /// The drive's detail value: MR-J4-TM 0x2A41 (`alarm << 16 | detail`), BDHDE FLT number.
    pub detail: u32,
    /// Whether a fault reset (controlword bit 7 edge) clears it.
    pub resettable: bool,
}

/// How the five manufacturer-specific bytes of an EMCY are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EmcyData {
    /// All zero.
    Zero,
    /// The alarm's [`AlarmDef::detail`] as 4 bytes little-endian, then 0.
    DetailLe,
}

/// Where and how alarms are reported besides the statusword.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ErrorReporting {
    /// The current-alarm object (MR-J4-TM 0x2A41), set to [`AlarmDef::detail`] while present.
    pub current_alarm: Option<ObjectAddress>,
    /// The newest alarm-history entry (MR-J4-TM 0x2A00:01), set to the detail of each alarm.
    pub history_newest: Option<ObjectAddress>,
    /// The pre-defined error field 0x1003 (count in sub 0, newest in sub 1): each alarm's
    /// error code is pushed in, if the object exists.
    pub error_history: bool,
    /// Whether 0x603F goes back to 0 on a successful fault reset. The MR-J4-TM reports "the
    /// latest error since power-on" (§7.3.8(1)) and keeps it.
    pub clear_error_code_on_reset: bool,
    /// The manufacturer bytes of EMCYs.
    pub emcy_data: EmcyData,
    /// Whether an EMCY with code 0x0000 is sent when a fault is reset.
    pub emcy_on_reset: bool,
}

/// What happens to the motor when the power stage switches off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PowerOff {
    /// The motor coasts (friction only).
    Coast,
    /// A dynamic brake shorts the windings: a braking torque proportional to speed.
    DynamicBrake,
}

/// The emulated motor and load, in SI units. Deterministic: the model integrates the drive's
/// outputs with the drive's cycle time, never with host time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorSpec {
    /// Rated torque, N·m (1000 ‰ in the torque objects).
    pub rated_torque_nm: f64,
    /// Largest torque the drive can make, ‰ of rated.
    pub peak_torque_permille: f64,
    /// Rated speed, rev/s (the reference of the MR-J4-TM's time-constant ramps).
    pub rated_speed_rev_s: f64,
    /// Largest speed, rev/s (the permissible speed; 0x6080).
    pub max_speed_rev_s: f64,
    /// Rotor plus load inertia, kg·m².
    pub inertia_kg_m2: f64,
    /// Viscous friction, N·m·s/rad.
    pub viscous_nm_s_rad: f64,
    /// Braking coefficient of the dynamic brake, N·m·s/rad (used with [`PowerOff::DynamicBrake`]).
    pub dynamic_brake_nm_s_rad: f64,
    /// What the motor does with the power stage off.
    pub power_off: PowerOff,
    /// Below this speed the motor counts as stopped (zero-speed signal, quick-stop end), rev/s.
    pub zero_speed_rev_s: f64,
}

/// How the drive's position, velocity and ramp units relate to motor revolutions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scaling {
    /// Fixed units: `position_per_rev` position units per revolution, `velocity_per_rev_s`
    /// velocity units per rev/s; ramps (profile acceleration, quick stop) are time constants in
    /// ms from 0 to the rated speed (MR-J4-TM).
    Fixed {
        /// Position units per revolution.
        position_per_rev: f64,
        /// Velocity units per rev/s.
        velocity_per_rev_s: f64,
    },
    /// Units per revolution = (gear:01 / gear:02) × (feed:01 / feed:02); velocity in units/s,
    /// acceleration in units/s² (BDHDE §6).
    FactorProduct {
        /// The gear-ratio object (0x6091).
        gear: u16,
        /// The feed-constant object (0x6092).
        feed: u16,
    },
}

/// How the drive notices that cyclic outputs stop arriving (DC mode: a SYNC0 without fresh
/// outputs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LossDetection {
    /// Added to the error counter per SYNC0 without fresh outputs.
    pub increment: u32,
    /// Subtracted per SYNC0 with fresh outputs (not below 0).
    pub decrement: u32,
    /// When the alarm is raised.
    pub limit: LossLimit,
    /// The alarm.
    pub alarm: &'static str,
    /// `true`: while an alarm is present the counter stands still, and resetting the alarm
    /// starts it again at 0 (the supervision begins afresh). `false`: it keeps counting the
    /// SYNC0s without data in Fault, so that after a long gap a reset is followed by the same
    /// alarm at the next missed frame. Neither manual says; each drive's value is marked
    /// \[REC\].
    pub restart_on_reset: bool,
}

/// The error-counter limit of a [`LossDetection`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LossLimit {
    /// Alarm when the counter reaches this value.
    Counter(u32),
    /// Alarm when the counter reaches `increment` × the number of cycles in this many ms
    /// (rounded up): consecutive misses for that long raise it (MR-J4-TM automatic mode, 7 ms).
    Milliseconds(u32),
}

impl LossDetection {
    /// The counter value that raises the alarm at a cycle of `cycle_ns`.
    pub fn threshold(&self, cycle_ns: u32) -> u32 {
        match self.limit {
            LossLimit::Counter(n) => n.max(1),
            LossLimit::Milliseconds(ms) => {
                let cycles = (u64::from(ms) * 1_000_000).div_ceil(u64::from(cycle_ns.max(1)));
                let n = u32::try_from(cycles).unwrap_or(u32::MAX).max(1);
                n.saturating_mul(self.increment.max(1))
            }
        }
    }
}

/// The following-error supervision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FollowingErrorSpec {
    /// The window (0x6065), position units; [`FollowingErrorSpec::disabled`] switches it off.
    pub window: ObjectAddress,
    /// The time-out (0x6066), ms: the error must stay above the window longer than this.
    pub timeout_ms: ObjectAddress,
    /// The window value that disables the supervision.
    pub disabled: u64,
    /// The alarm raised (besides statusword bit 13), if any.
    pub alarm: Option<&'static str>,
}

/// A check of the csp set-point stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandCheck {
    /// Raise `speed_alarm` when a set-point step implies a speed above this factor times the
    /// permissible speed.
    pub speed_factor: f64,
    /// The alarm for a too fast set-point.
    pub speed_alarm: Option<&'static str>,
    /// Raise this alarm when the unwrapped command position leaves the 32-bit range.
    pub overflow_alarm: Option<&'static str>,
}

/// Where torque limits come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TorqueLimits {
    /// Positive limit object, ‰ (MR-J4-TM 0x60E0).
    pub positive: Option<ObjectAddress>,
    /// Negative limit object, ‰ (MR-J4-TM 0x60E1).
    pub negative: Option<ObjectAddress>,
    /// Symmetric limit object, ‰ (0x6072).
    pub max: Option<ObjectAddress>,
    /// The speed limit in the torque modes, velocity units (MR-J4-TM 0x2D20); without it the
    /// permissible speed applies.
    pub speed_limit: Option<ObjectAddress>,
}

/// The unit of the torque slope 0x6087: the core's type, this emulation's own value per drive.
pub use crate::cia402::TorqueSlopeUnit;

/// Which physical quantity an object shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Motor speed in r/min.
    SpeedRpm,
    /// Torque in % of rated.
    TorquePercent,
    /// Motor current in ‰ of rated (torque / torque constant).
    CurrentPermille,
    /// Position in position units.
    Position,
    /// DC-link voltage, mV.
    DcLinkMillivolt,
}

/// An object the emulator keeps up to date every cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Monitor {
    /// The object.
    pub address: ObjectAddress,
    /// What it shows.
    pub quantity: Quantity,
}

/// A condition a status bit shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Condition {
    /// The motor is at zero speed.
    ZeroSpeed,
    /// The following error is within the position window 0x6067.
    InPosition,
    /// The torque is at a limit.
    TorqueLimited,
    /// The speed is at the speed limit in a torque mode.
    SpeedLimited,
    /// The power stage is on (servo on).
    PowerStageOn,
}

/// One manufacturer status bit (MR-J4-TM Status DO objects).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StatusBit {
    /// The object.
    pub address: ObjectAddress,
    /// The bit.
    pub bit: u8,
    /// What it shows.
    pub condition: Condition,
}

/// A value the emulated hardware reports at power-on (motor data and the like), which the
/// manual leaves to the hardware.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerOnValue {
    /// The object.
    pub address: ObjectAddress,
    /// The value.
    pub value: PowerOnData,
}

/// The value of a [`PowerOnValue`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PowerOnData {
    /// An integer.
    Int(i64),
    /// A text.
    Text(&'static str),
    /// The serial number the drive was built with.
    Serial,
}

/// A write rule of the object store beyond types, access and ranges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriteRule {
    /// Refuse SDO downloads to objects mapped in the RxPDO.
    RefuseMappedRx(SdoAbortCode),
    /// Only these values.
    Allowed {
        /// The entry.
        address: ObjectAddress,
        /// Accepted values, as the raw unsigned value of the entry (two's complement for
        /// signed types, in the entry's width).
        values: &'static [u64],
        /// The abort for others.
        code: SdoAbortCode,
    },
    /// Refuse every write.
    Refuse {
        /// Whole objects.
        objects: &'static [u16],
        /// Single entries.
        entries: &'static [ObjectAddress],
        /// The abort.
        code: SdoAbortCode,
    },
    /// Keep two entries equal.
    Mirror(ObjectAddress, ObjectAddress),
}

/// A group of modes selectable together, keyed by a parameter read at power-on (the core's
/// type, this emulation's own values).
pub use crate::cia402::ModeGroup;

/// A group of modes and the mode the emulated drive shows in it at power-on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GroupAtPowerOn {
    /// The group.
    pub group: ModeGroup,
    /// 0x6060/0x6061 at power-on.
    pub initial: i8,
}

/// The mode rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeRules {
    /// The parameter that selects the group, and the groups; without one every mode the engine
    /// emulates is usable.
    pub selector: Option<ObjectAddress>,
    /// The groups (selector = parameter value & 0xF).
    pub groups: &'static [GroupAtPowerOn],
    /// Modes usable without a selector.
    pub modes: &'static [i8],
    /// 0x6060/0x6061 at power-on without a selector.
    pub initial: i8,
}

/// The emulated drive: its ESI file and the emulator's model of it.
#[derive(Debug)]
pub struct DriveSpec {
    /// The `--device` name of `ecdrive sim` (`"mr-j4-tm"`).
    pub key: &'static str,
    /// The drive's name in messages (`"MR-J4-TM"`).
    pub name: &'static str,
    /// The drive's ESI file (XML text): identity, dictionary, CoE details, synchronisation
    /// modes and cycle times, SII.
    pub esi: &'static str,
    /// The product code of the device the file describes (a file may hold several).
    pub product_code: u32,
    /// The ESI model, built on first use ([`DriveSpec::model`]).
    pub(super) model: OnceLock<Result<EsiModel, EsiModelError>>,
    /// The CiA 402 state machine.
    pub state_machine: StateMachineSpec,
    /// PDO rules enforced on the master's mapping writes and at PRE-OP → SAFE-OP.
    pub pdo_limits: PdoLimits,
    /// Synchronisation objects.
    pub sync: SyncObjects,
    /// A counter to advance every cycle when mapped, checked with [`DriveSpec::counter_alarm`].
    pub cycle_counter: Option<CycleCounterSpec>,
    /// The alarms the emulator can raise.
    pub alarms: &'static [AlarmDef],
    /// The name the manual also gives an alarm by its detail value, as "`PREFIX` detail"
    /// (BDHDE: "FLT 87" for J3), which [`DriveSpec::alarm`] accepts too.
    pub alarm_detail_prefix: Option<&'static str>,
    /// How alarms are reported.
    pub reporting: ErrorReporting,
    /// Write rules of the object store.
    pub write_rules: &'static [WriteRule],
    /// Values set at power-on.
    pub power_on: &'static [PowerOnValue],
    /// The motor and load.
    pub motor: MotorSpec,
    /// Units.
    pub scaling: Scaling,
    /// Loss of cyclic data in DC mode.
    pub loss: LossDetection,
    /// The alarm when 0x2D23-style cycle counter updates are wrong (with
    /// [`DriveSpec::cycle_counter`]); checked in DC mode only.
    pub counter_alarm: Option<&'static str>,
    /// The alarm when OP is left (by the master or the SM watchdog) while the motor is
    /// energised.
    pub leave_op_alarm: Option<&'static str>,
    /// Following-error supervision.
    pub following_error: FollowingErrorSpec,
    /// csp set-point checks.
    pub command: CommandCheck,
    /// Torque and speed limits.
    pub torque_limits: TorqueLimits,
    /// The unit of 0x6087.
    pub torque_slope: TorqueSlopeUnit,
    /// In cst/tq the quick stop switches the power stage off at once (MR-J4-TM §5.6: dynamic
    /// brake) instead of ramping.
    pub torque_mode_quick_stop_immediate: bool,
    /// Halt (controlword bit 8) acts in the cyclic modes.
    pub halt_in_cyclic_modes: bool,
    /// In pp, statusword bit 12 stays 1 for as long as a positioning runs (MR-J4-TM
    /// §5.4.6(3): "1: Positioning being executed"); otherwise it is the CiA 402 acknowledge,
    /// 1 while the drive holds a set-point it has not started (BDHDE §5.7 "0 = New position
    /// possible 1 = New target position accepted").
    pub pp_ack_while_moving: bool,
    /// In csp the drive holds its position until controlword bit 4 goes 0→1 in Operation
    /// enabled, then follows the target (until it leaves Operation enabled or the mode).
    pub csp_start_edge: bool,
    /// Mode rules.
    pub modes: ModeRules,
    /// Monitors kept up to date.
    pub monitors: &'static [Monitor],
    /// Manufacturer status bits.
    pub status_bits: &'static [StatusBit],
    /// Homing: the methods the drive runs on the emulated machine ([`crate::machine`]) and how
    /// it reports a homing that fails.
    pub homing: HomingSpec,
    /// In tq, statusword bit 10 says the target torque is reached (false: the drive does not
    /// support it and leaves the bit 0).
    pub tq_target_reached: bool,
    /// The touch probe can trigger on the encoder's zero point (0x60B8 bit 2/10 = 1); without
    /// it those settings never latch.
    pub touch_probe_index_pulse: bool,
    /// SAFE-OP → OP refusal when the SYNC0 cycle does not match the drive's cycle object.
    pub sync_cycle_mismatch: crate::ec::AlStatusCode,
    /// The drive's own abort codes for refusals the store reports with the standard ones
    /// (ETG.1000.6 / CiA 301): `(standard, this drive's)`. A drive whose manual lists fewer codes
    /// answers with those it lists.
    pub abort_codes: &'static [(SdoAbortCode, SdoAbortCode)],
    /// File access over EtherCAT, if the drive has it: what its FoE server allows. A firmware
    /// image written completely takes effect at the next BOOT → INIT (revision 0x1018:03 and
    /// software version 0x100A).
    pub foe: Option<crate::foe::FoeSpec>,
    /// The abort code of a complete-access request (the drive has none).
    pub complete_access_refusal: SdoAbortCode,
}

/// How a drive reports a homing that fails: a search that runs into a limit switch without
/// finding what it looks for, or a method it does not run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HomingFailure {
    /// Statusword bit 13 (homing error) and bit 7 (warning); the drive stays in Operation
    /// enabled and names the warning only on its display.
    Warning {
        /// The drive's name for it.
        id: &'static str,
        /// What it means.
        text: &'static str,
    },
    /// Statusword bit 13 and a fault: the alarm with this id (0x603F, EMCY).
    Fault {
        /// The alarm's id in the drive's alarm table.
        alarm: &'static str,
    },
}

/// A drive's homing (hm, 0x6060 = 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HomingSpec {
    /// The 0x6098 values the emulated drive runs. Methods the drive lists but the model does
    /// not know end in a homing failure.
    pub methods: &'static [i8],
    /// The encoder has an index pulse (Z phase) once per revolution.
    pub index_pulse: bool,
    /// How a failure is reported.
    pub failure: HomingFailure,
}

impl DriveSpec {
    /// What the drive takes from its ESI file (parsed once per process).
    pub fn model(&self) -> Result<&EsiModel, EsiModelError> {
        self.model
            .get_or_init(|| EsiModel::build(self.name, self.esi, self.product_code))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The object dictionary (from the ESI file); empty if the file cannot be read.
    pub fn dictionary(&self) -> &'static [ObjectDesc] {
        self.model().map(|m| m.dictionary).unwrap_or(&[])
    }

    /// The alarm with this id.
    pub fn alarm(&self, id: &str) -> Option<&'static AlarmDef> {
        let by_detail = self.alarm_detail_prefix.and_then(|p| {
            let n: u32 = id.strip_prefix(p)?.trim().parse().ok()?;
            self.alarms.iter().find(|a| a.detail == n)
        });
        by_detail.or_else(|| self.alarms.iter().find(|a| a.id.eq_ignore_ascii_case(id)))
    }
}

impl DriveSpec {
    /// The entries the emulator keeps up to date or sets at power-on, whose value therefore is
    /// not the dictionary default: the CiA 402 feedback objects, the error reporting objects,
    /// the monitors and status bits, the cycle-counter echo, the power-on values and the serial
    /// number. (Only entries the dictionary has.)
    pub fn runtime_objects(&self) -> Vec<ObjectAddress> {
        const FEEDBACK: &[u16] = &[
            0x1001, 0x603F, 0x6041, 0x6061, 0x6062, 0x6063, 0x6064, 0x606B, 0x606C, 0x6074, 0x6077,
            0x60F4, 0x60FA, 0x60FC,
        ];
        let mut out: Vec<ObjectAddress> =
            FEEDBACK.iter().map(|&i| ObjectAddress::new(i, 0)).collect();
        out.push(ObjectAddress::new(0x1018, 4));
        out.extend(self.reporting.current_alarm);
        out.extend(self.reporting.history_newest);
        if self.reporting.error_history {
            out.extend((0..=u8::MAX).map(|s| ObjectAddress::new(0x1003, s)));
        }
        out.extend(self.monitors.iter().map(|m| m.address));
        out.extend(self.status_bits.iter().map(|b| b.address));
        out.extend(self.power_on.iter().map(|p| p.address));
        if let Some(c) = self.cycle_counter {
            out.extend(c.echo);
        }
        let od = crate::od::Dictionary::new(self.dictionary());
        out.retain(|a| od.entry(*a).is_some());
        out.sort_unstable_by_key(|a| (a.index, a.sub));
        out.dedup();
        out
    }
}
