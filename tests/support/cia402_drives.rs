//! Capability sets of the drives in /work/shared/manuals, written from the manuals, for the
//! cia402 tests. The drive profiles in `src/drives/` own the real ones; these are test data and
//! cite their sources.
#![allow(dead_code)]

use ecdrive::cia402::{
    DriveCaps, ErrorEntry, QuickStopEnd, QuickStopOption, StopRamp, SupportedModes, VendorModeBit,
};

/// MR-J4-TM 0x6502 vendor bits (§7.3.8(8)): bit 16 jg (−100), bit 17 pt (−101), bit 19 idx (−103).
pub const MR_J4_VENDOR_BITS: &[VendorModeBit] = &[
    VendorModeBit {
        bit: 16,
        mode: -100,
    },
    VendorModeBit {
        bit: 17,
        mode: -101,
    },
    VendorModeBit {
        bit: 19,
        mode: -103,
    },
];

/// MR-J4-TM alarms named in the EtherCAT manual (§10); 0x603F = 0xFF00 + alarm number (SW B2+).
pub const MR_J4_ERRORS: &[ErrorEntry] = &[
    ErrorEntry::exact(0xFF10, "AL.10", "Undervoltage"),
    ErrorEntry::exact(0xFF25, "AL.25", "Absolute position erased"),
    ErrorEntry::exact(0xFF37, "AL.37", "Parameter error"),
    ErrorEntry::exact(0xFF69, "AL.69", "Command error"),
    ErrorEntry::exact(0xFF86, "AL.86", "Network communication error"),
    ErrorEntry {
        code: 0xFF00,
        mask: 0xFF00,
        name: "AL.xx",
        text: "MR-J4-TM alarm: the low byte is the alarm number",
    },
];

/// MR-J4-TM (§5.1, §5.4.2, §5.6, §7.3.8): state skipping, quick-stop code 2 only, no transition
/// 16, zero speed needed to switch to/from position modes, 0x6502 = 0x000B03AD (with B2 modes).
pub const MR_J4_TM: DriveCaps = DriveCaps {
    state_skipping: true,
    transition_16: false,
    quick_stop_options: &[QuickStopOption::QUICK_STOP_RAMP],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: true,
    // pt (point table) and idx (indexer) position the axis; jg (jog) does not. Our reading:
    // §5.4.2 only says "position mode".
    vendor_position_modes: &[-101, -103],
    remote_gates_controlword: false,
    supported_modes: SupportedModes::from_raw(0x000B_03AD).with_vendor_bits(MR_J4_VENDOR_BITS),
    error_table: MR_J4_ERRORS,
};

/// BDHDE fault codes (§10.2 Table 10-4) that are not standard CiA codes or whose vendor name
/// differs.
pub const BDHDE_ERRORS: &[ErrorEntry] = &[
    ErrorEntry::exact(0x2310, "F2 (FLT 17)", "Motor Foldback"),
    ErrorEntry::exact(0x818D, "Fb8 (FLT 91)", "EtherCAT Packet Loss"),
    ErrorEntry::exact(0x8689, "J3 (FLT 87)", "Excessive PE Value"),
    ErrorEntry::exact(0xF080, "Fb9 (FLT 92)", "CAN/EtherCAT State Not Operational"),
    ErrorEntry::exact(0xFF04, "- (FLT 89)", "Realtime Overload Fault"),
];

/// BDHDE (§5.4, §5.5, §9 605Ah, §12): no skipping, transition 16 (with 0x605A = 6), quick-stop
/// codes 0, 2, 6 (default 0), commands need COMMmode = 1 (remote bit), 0x6502 = 0x3AD.
pub const BDHDE: DriveCaps = DriveCaps {
    state_skipping: false,
    transition_16: true,
    quick_stop_options: &[
        QuickStopOption::DISABLE_DRIVE,
        QuickStopOption::QUICK_STOP_RAMP,
        QuickStopOption::QUICK_STOP_RAMP_STAY,
    ],
    default_quick_stop_option: QuickStopOption::DISABLE_DRIVE,
    position_mode_switch_needs_zero_speed: false,
    vendor_position_modes: &[],
    remote_gates_controlword: true,
    supported_modes: SupportedModes::from_raw(0x0000_03AD),
    error_table: BDHDE_ERRORS,
};

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
};
