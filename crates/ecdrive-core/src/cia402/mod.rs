//! The pure CiA 402 layer: no I/O, no clocks.
//!
//! Everything here works on values: a statusword in, a controlword out, once per cycle. Time is
//! counted in cycles. Nothing blocks, allocates in the cyclic path, or panics on any input. The
//! layer depends only on [`crate::od`] (for object addresses).
//!
//! Per-drive behaviour enters only as data, a [`DriveCaps`] value. Values that are our choice
//! rather than vendor facts are marked \[REC\] and live in [`planner::defaults`] and
//! [`axis::axis_defaults`].
//!
//! | module | what |
//! |---|---|
//! | [`ControlWord`], [`StatusWord`] | 0x6040 / 0x6041 as bit sets, with the mode-specific aliases |
//! | [`State`] | the eight device states, decoded with the CiA masks 0x4F / 0x6F |
//! | [`Command`] | shutdown, switch on, enable operation, … encoded into bits 0–3 and 7 |
//! | [`OperationMode`], [`SupportedModes`] | 0x6060 / 0x6061 values (vendor values kept) and 0x6502 |
//! | [`DriveCaps`] | per-drive rules as data: state skipping, quick-stop codes, transition 16, zero-speed mode switching, remote gating, error table |
//! | [`planner`] ([`Planner`]) | master side: which controlword takes the drive to a [`Target`] |
//! | [`device`] | drive side: how a drive reacts to a controlword (reference model, emulator core) |
//! | [`axis`] ([`Axis`]) | the per-cycle engine: enable/disable, quick stop, fault reset, mode switching, set-points |
//! | [`profile_position`], [`homing`], [`profile_velocity`], [`interpolated`] | the profile modes pp (set-point handshake), hm, pv/tq and ip as per-cycle helpers that drive an [`Axis`] through its public API |
//! | [`ErrorCode`] | 0x603F decoding by CiA ranges plus per-drive tables |
//! | [`object`] | the object addresses this layer reads and writes |

pub mod axis;
mod bits;
mod caps;
mod command;
pub mod device;
pub mod drive_profile;
mod error_code;
pub mod homing;
pub mod interpolated;
mod mode;
#[cfg(test)]
mod mode_test_support;
pub mod planner;
pub mod profile_position;
pub mod profile_velocity;
mod state;
pub mod units;

pub use axis::{
    Axis, AxisConfig, AxisError, AxisStatus, Event, Feedback, ModeSwitchError, ModeSwitchFailure,
    ModeSwitchPhase, Output, Phase, StandstillConfig, StopRampConfig, axis_defaults,
};
pub use bits::{ControlWord, StatusWord};
pub use caps::{DriveCaps, QuickStopEnd, QuickStopOption, StopRamp, ValueRange};
pub use command::Command;
pub use drive_profile::Profile;
pub use error_code::{
    ErrorClass, ErrorCode, ErrorDescription, ErrorEntry, ErrorSource, STANDARD_CODES,
};
pub use homing::{Homing, HomingConfig, HomingOutcome, HomingPhase, HomingState};
pub use interpolated::{Interpolation, IpStatus};
pub use mode::{ModeGroup, OperationMode, SetPointKind, SupportedModes, VendorModeBit};
pub use planner::{
    Planner, PlannerConfig, PlannerConfigError, PlannerError, Progress, StallCause, Step, Target,
    cycles_for, defaults,
};
pub use profile_position::{PpConfig, PpError, PpPhase, PpStatus, ProfilePosition, SetPoint};
pub use profile_velocity::{ProfileTorque, ProfileVelocity, PvStatus, TqStatus};
pub use state::State;
pub use units::{AccelUnit, ProfileUnits, TorqueSlopeUnit, Units, VelocityUnit};

/// Object addresses of the CiA 402 objects this layer deals with.
pub mod object {
    use crate::od::ObjectAddress;

    /// 0x603F Error code (UNSIGNED16).
    pub const ERROR_CODE: ObjectAddress = ObjectAddress::new(0x603F, 0);
    /// 0x6040 Controlword (UNSIGNED16).
    pub const CONTROLWORD: ObjectAddress = ObjectAddress::new(0x6040, 0);
    /// 0x6041 Statusword (UNSIGNED16).
    pub const STATUSWORD: ObjectAddress = ObjectAddress::new(0x6041, 0);
    /// 0x605A Quick stop option code (INTEGER16).
    pub const QUICK_STOP_OPTION_CODE: ObjectAddress = ObjectAddress::new(0x605A, 0);
    /// 0x605B Shutdown option code (INTEGER16).
    pub const SHUTDOWN_OPTION_CODE: ObjectAddress = ObjectAddress::new(0x605B, 0);
    /// 0x605C Disable operation option code (INTEGER16).
    pub const DISABLE_OPERATION_OPTION_CODE: ObjectAddress = ObjectAddress::new(0x605C, 0);
    /// 0x605D Halt option code (INTEGER16).
    pub const HALT_OPTION_CODE: ObjectAddress = ObjectAddress::new(0x605D, 0);
    /// 0x605E Fault reaction option code (INTEGER16).
    pub const FAULT_REACTION_OPTION_CODE: ObjectAddress = ObjectAddress::new(0x605E, 0);
    /// 0x6060 Modes of operation (INTEGER8).
    pub const MODES_OF_OPERATION: ObjectAddress = ObjectAddress::new(0x6060, 0);
    /// 0x6061 Modes of operation display (INTEGER8).
    pub const MODES_OF_OPERATION_DISPLAY: ObjectAddress = ObjectAddress::new(0x6061, 0);
    /// 0x6064 Position actual value (INTEGER32).
    pub const POSITION_ACTUAL: ObjectAddress = ObjectAddress::new(0x6064, 0);
    /// 0x606C Velocity actual value (INTEGER32).
    pub const VELOCITY_ACTUAL: ObjectAddress = ObjectAddress::new(0x606C, 0);
    /// 0x6071 Target torque (INTEGER16).
    pub const TARGET_TORQUE: ObjectAddress = ObjectAddress::new(0x6071, 0);
    /// 0x6077 Torque actual value (INTEGER16).
    pub const TORQUE_ACTUAL: ObjectAddress = ObjectAddress::new(0x6077, 0);
    /// 0x607A Target position (INTEGER32).
    pub const TARGET_POSITION: ObjectAddress = ObjectAddress::new(0x607A, 0);
    /// 0x6085 Quick stop deceleration (UNSIGNED32).
    pub const QUICK_STOP_DECELERATION: ObjectAddress = ObjectAddress::new(0x6085, 0);
    /// 0x60B1 Velocity offset (INTEGER32).
    pub const VELOCITY_OFFSET: ObjectAddress = ObjectAddress::new(0x60B1, 0);
    /// 0x60B2 Torque offset (INTEGER16).
    pub const TORQUE_OFFSET: ObjectAddress = ObjectAddress::new(0x60B2, 0);
    /// 0x60FF Target velocity (INTEGER32).
    pub const TARGET_VELOCITY: ObjectAddress = ObjectAddress::new(0x60FF, 0);
    /// 0x6502 Supported drive modes (UNSIGNED32).
    pub const SUPPORTED_DRIVE_MODES: ObjectAddress = ObjectAddress::new(0x6502, 0);
}
