//! Capability sets of the drives for the cia402 tests: the EtherCAT drives' come from their
//! profiles in `src/drives/`; the CANopen BLV-R, which has no profile yet, is test data written
//! from its manual here.
#![allow(dead_code)]

use ecdrive_core::cia402::{
    DriveCaps, ErrorEntry, QuickStopEnd, QuickStopOption, StopRamp, SupportedModes, VendorModeBit,
};

/// The MR-J4-TM profile's 0x6502 vendor bits (§7.3.8(8)).
pub const MR_J4_VENDOR_BITS: &[VendorModeBit] = ecdrive_core::drives::mr_j4_tm::VENDOR_MODE_BITS;

/// The MR-J4-TM profile's alarm table (§10; 0x603F = 0xFF00 + alarm number).
pub const MR_J4_ERRORS: &[ErrorEntry] = ecdrive_core::drives::mr_j4_tm::ERRORS;

/// The MR-J4-TM profile's capabilities (§5.1, §5.4.2, §5.6, §7.3.8).
pub const MR_J4_TM: DriveCaps = ecdrive_core::drives::mr_j4_tm::CAPS;

/// The BDHDE profile's fault table (§10.2 Table 10-4).
pub const BDHDE_ERRORS: &[ErrorEntry] = ecdrive_core::drives::bdhde::ERRORS;

/// The BDHDE profile's capabilities (§5.4, §5.5, §9 605Ah, §12).
pub const BDHDE: DriveCaps = ecdrive_core::drives::bdhde::CAPS;

/// BLV-R alarms (§4.5 EMCY table): 0x603F = 0xFF00 + alarm code.
pub const BLV_R_ERRORS: &[ErrorEntry] = &[
    ErrorEntry::exact(0xFF10, "alarm 10h", "position deviation"),
    ErrorEntry::exact(0xFF20, "alarm 20h", "overcurrent"),
    ErrorEntry::exact(0xFF22, "alarm 22h", "overvoltage"),
    ErrorEntry::exact(0xFF30, "alarm 30h", "overload"),
    ErrorEntry::exact(0xFF31, "alarm 31h", "overspeed"),
    ErrorEntry::exact(0xFF67, "alarm 67h", "software overtravel"),
];

/// BLV-R (§6, §6.2, §8.3 605Ah): no skipping, no transition 16, quick-stop codes −3…−1, 0, 1,
/// 2, 5, 6 (default 2), remote bit gates the controlword, 0x6502 = 0x2D (pp, pv, tq, hm).
pub const BLV_R: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: false,
    quick_stop_options: &[
        QuickStopOption::vendor(-3, StopRamp::Vendor, QuickStopEnd::StayInQuickStopActive),
        QuickStopOption::vendor(-2, StopRamp::Vendor, QuickStopEnd::StayInQuickStopActive),
        QuickStopOption::vendor(-1, StopRamp::Immediate, QuickStopEnd::StayInQuickStopActive),
        QuickStopOption::DISABLE_DRIVE,
        QuickStopOption::SLOW_DOWN_RAMP,
        QuickStopOption::QUICK_STOP_RAMP,
        QuickStopOption::SLOW_DOWN_RAMP_STAY,
        QuickStopOption::QUICK_STOP_RAMP_STAY,
    ],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: true,
    supported_modes: SupportedModes::from_raw(0x0000_002D),
    error_table: BLV_R_ERRORS,
    csp_start_edge: false,
    homing_failure: "",
    home_offset_set_by_drive: None,
    sdo_refused_while_rx_mapped: None,
    pp_target_range: None,
};
