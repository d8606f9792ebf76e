//! Per-drive rules of the CiA 402 layer, as data.
//!
//! The generic code (planner, device model, axis engine) reads a [`DriveCaps`] and never asks
//! which vendor it talks to. Drive profiles in `drives/` hold one `DriveCaps` each as a `const`.

use core::fmt;

use super::error_code::ErrorEntry;
use super::mode::{OperationMode, SupportedModes};

/// How the drive brakes during a quick stop (or another stop reaction).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StopRamp {
    /// Disable the drive function at once: the motor coasts (or a dynamic brake acts).
    Immediate,
    /// Decelerate on the slow-down ramp (the deceleration of the active mode).
    SlowDown,
    /// Decelerate on the quick-stop ramp, 0x6085.
    QuickStopRamp,
    /// Decelerate at the current limit.
    CurrentLimit,
    /// Decelerate at the voltage limit.
    VoltageLimit,
    /// A manufacturer-specific deceleration (e.g. BLV-R −3/−2: custom stopping time/rate).
    Vendor,
}

/// Where the state machine goes after a quick stop has stopped the motor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum QuickStopEnd {
    /// Transition 12 happens automatically: Quick stop active → Switch on disabled (codes 0–4).
    SwitchOnDisabled,
    /// The drive stays in Quick stop active (codes 5–8) until "enable operation" (transition 16,
    /// if supported) or "disable voltage" (transition 12).
    StayInQuickStopActive,
}

/// One value of the quick-stop option code, object 0x605A (INTEGER16), and what it does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct QuickStopOption {
    /// The 0x605A value.
    pub code: i16,
    /// How the motor is stopped.
    pub ramp: StopRamp,
    /// Where the state machine ends.
    pub end: QuickStopEnd,
}

impl QuickStopOption {
    /// 0: disable drive function (→ Switch on disabled).
    pub const DISABLE_DRIVE: Self = Self::standard_const(0, StopRamp::Immediate);
    /// 1: slow-down ramp, then Switch on disabled.
    pub const SLOW_DOWN_RAMP: Self = Self::standard_const(1, StopRamp::SlowDown);
    /// 2: quick-stop ramp, then Switch on disabled.
    pub const QUICK_STOP_RAMP: Self = Self::standard_const(2, StopRamp::QuickStopRamp);
    /// 3: current limit, then Switch on disabled.
    pub const CURRENT_LIMIT: Self = Self::standard_const(3, StopRamp::CurrentLimit);
    /// 4: voltage limit, then Switch on disabled.
    pub const VOLTAGE_LIMIT: Self = Self::standard_const(4, StopRamp::VoltageLimit);
    /// 5: slow-down ramp, stay in Quick stop active.
    pub const SLOW_DOWN_RAMP_STAY: Self = Self::standard_const(5, StopRamp::SlowDown);
    /// 6: quick-stop ramp, stay in Quick stop active.
    pub const QUICK_STOP_RAMP_STAY: Self = Self::standard_const(6, StopRamp::QuickStopRamp);
    /// 7: current limit, stay in Quick stop active.
    pub const CURRENT_LIMIT_STAY: Self = Self::standard_const(7, StopRamp::CurrentLimit);
    /// 8: voltage limit, stay in Quick stop active.
    pub const VOLTAGE_LIMIT_STAY: Self = Self::standard_const(8, StopRamp::VoltageLimit);

    /// The nine CiA 402 codes 0–8.
    pub const STANDARD: [QuickStopOption; 9] = [
        Self::DISABLE_DRIVE,
        Self::SLOW_DOWN_RAMP,
        Self::QUICK_STOP_RAMP,
        Self::CURRENT_LIMIT,
        Self::VOLTAGE_LIMIT,
        Self::SLOW_DOWN_RAMP_STAY,
        Self::QUICK_STOP_RAMP_STAY,
        Self::CURRENT_LIMIT_STAY,
        Self::VOLTAGE_LIMIT_STAY,
    ];

    const fn standard_const(code: i16, ramp: StopRamp) -> Self {
        Self {
            code,
            ramp,
            end: if code >= 5 {
                QuickStopEnd::StayInQuickStopActive
            } else {
                QuickStopEnd::SwitchOnDisabled
            },
        }
    }

    /// The CiA 402 meaning of `code` (0–8), `None` otherwise.
    pub const fn standard(code: i16) -> Option<Self> {
        match code {
            0 => Some(Self::DISABLE_DRIVE),
            1 => Some(Self::SLOW_DOWN_RAMP),
            2 => Some(Self::QUICK_STOP_RAMP),
            3 => Some(Self::CURRENT_LIMIT),
            4 => Some(Self::VOLTAGE_LIMIT),
            5 => Some(Self::SLOW_DOWN_RAMP_STAY),
            6 => Some(Self::QUICK_STOP_RAMP_STAY),
            7 => Some(Self::CURRENT_LIMIT_STAY),
            8 => Some(Self::VOLTAGE_LIMIT_STAY),
            _ => None,
        }
    }

    /// A manufacturer-specific code (negative values, e.g. BLV-R −3…−1).
    pub const fn vendor(code: i16, ramp: StopRamp, end: QuickStopEnd) -> Self {
        Self { code, ramp, end }
    }
}

impl fmt::Display for QuickStopOption {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let end = match self.end {
            QuickStopEnd::SwitchOnDisabled => "then Switch on disabled",
            QuickStopEnd::StayInQuickStopActive => "stay in Quick stop active",
        };
        write!(f, "0x605A = {} ({:?}, {end})", self.code, self.ramp)
    }
}

/// What differs between drives in device control and mode handling.
///
/// Const-constructible: a drive profile writes `pub const CAPS: DriveCaps = DriveCaps { … };`.
/// [`DriveCaps::CIA402`] is the plain standard behaviour to start from with struct-update syntax.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DriveCaps {
    /// The drive accepts the direct jumps Switch on disabled → Switched on ("switch on"),
    /// Switch on disabled → Operation enabled and Ready to switch on → Operation enabled ("enable
    /// operation"). MR-J4-TM §5.1: yes. Describes the drive (the emulation accepts the jumps);
    /// ecdrive's planner never relies on them and walks the standard transitions.
    pub state_skipping: bool,
    /// Transition 16 (Quick stop active → Operation enabled on "enable operation", quick-stop
    /// codes 5–8) exists. MR-J4-TM: no (§5.1 note); BLV-R: no; BDHDE: yes (with 0x605A = 6).
    pub transition_16: bool,
    /// The quick-stop option codes the drive accepts in 0x605A. An empty slice means the object
    /// does not exist (e.g. ASDA-A2); then [`DriveCaps::default_quick_stop_option`] describes the
    /// drive's fixed behaviour.
    pub quick_stop_options: &'static [QuickStopOption],
    /// The 0x605A value the drive has unless the master writes another one (MR-J4-TM 2, BDHDE 0,
    /// BLV-R 2).
    pub default_quick_stop_option: QuickStopOption,
    /// Switching 0x6060 to or from a position mode (pp, hm, ip, csp) only works at zero speed;
    /// otherwise the drive ignores the request (MR-J4-TM §5.4.2).
    pub position_mode_switch_needs_zero_speed: bool,
    /// Vendor modes (negative 0x6060 values) that count as position modes for
    /// [`DriveCaps::position_mode_switch_needs_zero_speed`] (the standard ones are pp, hm, ip,
    /// csp; see [`OperationMode::is_position_mode`]).
    pub vendor_position_modes: &'static [i8],
    /// While statusword bit 9 (remote) is 0 the drive ignores every controlword command except
    /// quick stop, fault reset and halt (BLV-R §6.1). Used to report *why* a transition stalls.
    pub remote_gates_controlword: bool,
    /// The modes 0x6502 advertises, with the drive's vendor-bit mapping.
    pub supported_modes: SupportedModes,
    /// The drive's own error-code names, looked up before the standard table.
    pub error_table: &'static [ErrorEntry],
    /// In csp the drive follows the target only after a 0→1 edge of controlword bit 4 ("new
    /// target value"), which CiA 402 leaves reserved in csp (BDHDE manual, CSP example: "Bit
    /// 4: New Target Value 0 » 1 Starts a movement to a target position"). The axis then
    /// raises bit 4 when csp starts streaming and keeps it set; drives without the rule
    /// ignore the bit.
    pub csp_start_edge: bool,
    /// How the drive's manual names a failed homing besides statusword bit 13 (a warning or an
    /// alarm), for messages; empty when it names none.
    pub homing_failure: &'static str,
    /// The drive sets the home offset 0x607C itself and refuses a value written to it: why,
    /// in the manual's words (`None`: 0x607C is the CiA 402 home offset the master writes).
    pub home_offset_set_by_drive: Option<&'static str>,
    /// The drive refuses an SDO download to an object mapped in its RxPDO (abort 0x06010006):
    /// the manual's words, for the message (`None`: the manual does not say so).
    pub sdo_refused_while_rx_mapped: Option<&'static str>,
    /// The range of the target position 0x607A in pp where it is narrower than the object's
    /// type (MR-J4-TM: ±999 999 pos units, §7.3.12 (1)); `None`: the type's range. A pp target
    /// beyond it is refused before it reaches the drive.
    pub pp_target_range: Option<ValueRange>,
}

/// The values a drive takes in an object, and where its manual says so.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ValueRange {
    /// Smallest value.
    pub min: i64,
    /// Largest value.
    pub max: i64,
    /// What the manual says, and where (for messages).
    pub source: &'static str,
}

impl ValueRange {
    /// Whether `v` is within the range.
    pub const fn contains(&self, v: i64) -> bool {
        self.min <= v && v <= self.max
    }
}

impl DriveCaps {
    /// Plain CiA 402: no state skipping, transition 16 supported, every standard quick-stop code
    /// with default 2, no zero-speed rule, remote bit not gating, every standard mode, no vendor
    /// error table.
    pub const CIA402: DriveCaps = DriveCaps {
        state_skipping: false,
        transition_16: true,
        quick_stop_options: &QuickStopOption::STANDARD,
        default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
        position_mode_switch_needs_zero_speed: false,
        vendor_position_modes: &[],
        remote_gates_controlword: false,
        supported_modes: SupportedModes::ALL_STANDARD,
        error_table: &[],
        csp_start_edge: false,
        homing_failure: "",
        home_offset_set_by_drive: None,
        sdo_refused_while_rx_mapped: None,
        pp_target_range: None,
    };

    /// The range a pp target of `target` counts is beyond, where the drive narrows 0x607A in
    /// pp ([`DriveCaps::pp_target_range`]) and the target, rounded as it is written, is outside
    /// it; `None` when the drive takes it. The one check of the run file's steps, start-up's
    /// and the axis's targets.
    pub fn pp_target_outside(&self, target: f64) -> Option<ValueRange> {
        self.pp_target_range
            .filter(|r| !r.contains(target.round() as i64))
    }

    /// Whether `mode` is a position mode on this drive: the standard ones, plus the listed
    /// vendor modes.
    pub fn is_position_mode(&self, mode: OperationMode) -> bool {
        match mode {
            OperationMode::Vendor(v) => self.vendor_position_modes.contains(&v),
            m => m.is_position_mode(),
        }
    }

    /// The option with 0x605A value `code`, if the drive accepts it. When the drive has no
    /// 0x605A (empty list), only the default's code is accepted.
    pub fn quick_stop_option(&self, code: i16) -> Option<QuickStopOption> {
        if self.quick_stop_options.is_empty() {
            return (self.default_quick_stop_option.code == code)
                .then_some(self.default_quick_stop_option);
        }
        self.quick_stop_options
            .iter()
            .copied()
            .find(|o| o.code == code)
    }
}
