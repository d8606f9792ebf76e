//! The emulated BDHDE: its ESI file (`esi/Servotronix_BDHDE.xml`: identity, dictionary, CoE
//! details, synchronisation modes and cycle times, SII) plus the emulator's model of the
//! drive, written from the manual independently of the master's profile.
//!
//! What it does, with the manual sections (EtherCAT Reference Manual rev. 0.0.2):
//! - the object dictionary of the profile with its documented defaults, including the unusable
//!   ones a master must replace (one unit per revolution, 0x6065 = 1, 0x607F = 1; §6, §9);
//!   0x605A accepts 0, 2 and 6, 0x6060 the modes of 0x6502 (§9); remapping only in PRE-OP with
//!   sub-index 0 cleared first (abort 0x06010003); 0x60C2:02 −4 at power-on (§2.4), writable
//!   for the standard form its set-up example writes;
//! - the CiA 402 state machine without state skipping; quick-stop codes 0 (disable at once),
//!   2 (ramp, then Switch on disabled) and 6 (ramp and stay, transition 16 on Enable operation);
//!   halt in csp/csv slows down on the profile deceleration (605Dh = 1); the controlword acts
//!   only with statusword bit 9 (COMMmode 1);
//! - the cycle told by 0x60C2: :01 × 250 µs while :02 is −4, :01 × 10^(:02) s otherwise;
//!   SAFE-OP → OP needs SYNC0 with that cycle;
//! - the factor group: units per revolution = (0x6091:01/:02) × (0x6092:01/:02), velocity in
//!   units/s, acceleration in units/s² (§6.2–§6.4); torque in ‰ of 0x6076 (§6.6);
//! - faults latch 0x603F with the codes of Table 10-4 and send one EMCY each (§10.2); a fault
//!   reset clears them; the following error beyond 0x6065 for longer than 0x6066 raises J3
//!   0x8689 "Excessive PE Value".
//!
//! The emulator's own choices are in the section "Values that are ours" below.

use super::spec::{
    AlarmDef, CommandCheck, Condition, CycleSource, DriveSpec, EmcyData, ErrorReporting,
    FollowingErrorSpec, HomingFailure, HomingSpec, LossDetection, LossLimit, ModeRules, Monitor,
    MotorSpec, PowerOff, PowerOnData, PowerOnValue, Quantity, Scaling, StateMachineSpec, StatusBit,
    SyncObjects, TorqueLimits, TorqueSlopeUnit, WriteRule,
};
use crate::cia402::QuickStopOption;
use crate::ec::AlStatusCode;
use crate::od::{ObjectAddress, SdoAbortCode};
use crate::pdo::{DirectionLimits, PdoLimits, PdoRange};
use std::sync::OnceLock;

/// The state machine (§3, §9 605Ah): no state skipping; 0x605A accepts 0 (disable drive at
/// once, the power-on value), 2 (ramp, then Switch on disabled) and 6 (ramp and stay, so
/// transition 16 exists); the controlword acts only with statusword bit 9 set (COMMmode 1).
pub const STATE_MACHINE: StateMachineSpec = StateMachineSpec {
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
};

/// PDO rules (chapter 7 objects 1600h–1603h, 1A00h–1A03h; §5.2.2): 0x1600/0x1A00 up to 8
/// entries, 0x1601–0x1603/0x1A01–0x1A03 up to 2; one PDO per direction (0x1C12/0x1C13 are
/// single variables in the manual). \[REC\] at most 8 entries and 32 bytes per direction
/// (MANUAL GAP: no budget is stated; 8 entries of at most 32 bits).
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "BDHDE",
    rx: DirectionLimits {
        pdos: &[
            PdoRange::single(0x1600, 8),
            PdoRange::new(0x1601, 0x1603, 2),
        ],
        max_assigned: 1,
        max_entries: 8,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: &[
            PdoRange::single(0x1A00, 8),
            PdoRange::new(0x1A01, 0x1A03, 2),
        ],
        max_assigned: 1,
        max_entries: 8,
        max_bytes: 32,
    },
    assignment_writable: true,
};

/// The unit of 0x60C2:01 while 0x60C2:02 holds −4 (FBITPRD × 250 µs, §2.4).
pub const INTERPOLATION_UNIT_NS: u32 = 250_000;

const fn a(index: u16, sub: u8) -> ObjectAddress {
    ObjectAddress::new(index, sub)
}

const fn fault(id: &'static str, text: &'static str, code: u16, reg: u8, flt: u32) -> AlarmDef {
    AlarmDef {
        id,
        text,
        error_code: code,
        error_register: reg,
        detail: flt,
        resettable: true,
    }
}

/// The faults the emulated BDHDE raises (Table 10-4; the id is the 7-segment code, the detail
/// the FLT number). The 0x1001 bits are ours, see [`REC_ERROR_REGISTER`].
pub const ALARMS: &[AlarmDef] = &[
    fault(
        "J3",
        "Excessive PE Value",
        0x8689,
        REC_ERROR_REGISTER.monitoring,
        87,
    ),
    fault(
        "Fb8",
        "EtherCAT Packet Loss",
        0x818D,
        REC_ERROR_REGISTER.monitoring,
        91,
    ),
    fault(
        "Fb9",
        "CAN/EtherCAT State Not Operational",
        0xF080,
        REC_ERROR_REGISTER.monitoring,
        92,
    ),
    fault(
        "Fb3",
        "Fieldbus Cable Disconnected",
        0x7580,
        REC_ERROR_REGISTER.monitoring,
        65,
    ),
    fault(
        "J",
        "Velocity Over-Speed Exceeded",
        0x8481,
        REC_ERROR_REGISTER.monitoring,
        14,
    ),
    fault(
        "J2",
        "Exceeded Maximum Velocity Error",
        0x8482,
        REC_ERROR_REGISTER.monitoring,
        67,
    ),
    fault(
        "F2",
        "Motor Foldback",
        0x2310,
        REC_ERROR_REGISTER.current,
        17,
    ),
    fault("o", "Over-Voltage", 0x3110, REC_ERROR_REGISTER.voltage, 9),
    fault("u", "Under-Voltage", 0x3120, REC_ERROR_REGISTER.voltage, 11),
    fault(
        "t1",
        "Power Stage Over-Temperature",
        0x4310,
        REC_ERROR_REGISTER.temperature,
        10,
    ),
    fault(
        "n3",
        "Emergency Stop Issued",
        0x7091,
        REC_ERROR_REGISTER.generic,
        57,
    ),
    fault("F3", "Stall Fault", 0x7121, REC_ERROR_REGISTER.generic, 59),
    fault(
        "HE",
        "Homing Error",
        0x6100,
        REC_ERROR_REGISTER.generic,
        174,
    ),
];

/// The drive's write rules.
pub const WRITE_RULES: &[WriteRule] = &[
    WriteRule::Allowed {
        address: a(0x605A, 0),
        values: &[0, 2, 6],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x6060, 0),
        values: &[0, 1, 3, 4, 6, 8, 9, 10],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x607E, 0),
        values: &[0],
        code: SdoAbortCode::VALUE_RANGE,
    },
    // 0x60C2:01: at most 64 in either reading of the manual (object table 4–64, §2.4 FBITPRD
    // 1–64; the set-up example's standard form 1 × 10^−3 s is taken): above it "Value of
    // parameter written too high"; 0 passes this rule to the dictionary's minimum of 1
    // ("too low").
    WriteRule::Allowed {
        address: a(0x60C2, 1),
        values: &INTERPOLATION_PERIODS,
        code: SdoAbortCode::VALUE_TOO_HIGH,
    },
];

/// 0x60C2:01 values this rule lets through to the dictionary's range: 0 to 64.
const INTERPOLATION_PERIODS: [u64; 65] = {
    let mut v = [0u64; 65];
    let mut i = 0;
    while i < 65 {
        v[i] = i as u64;
        i += 1;
    }
    v
};

/// The emulated BDHDE.
pub static SPEC: DriveSpec = DriveSpec {
    key: "bdhde",
    name: "BDHDE",
    esi: include_str!("../../../../esi/Servotronix_BDHDE.xml"),
    product_code: 0x000B_E2EB,
    model: OnceLock::new(),
    state_machine: STATE_MACHINE,
    pdo_limits: PDO_LIMITS,
    // No 0x1C32/0x1C33 (§4.4.1: DC-Synchronous only); the cycle is told in 0x60C2.
    sync: SyncObjects {
        sync_type: None,
        cycle: Some(CycleSource::Interpolation {
            vendor: Some((-4, INTERPOLATION_UNIT_NS)),
        }),
    },
    cycle_counter: None,
    alarms: ALARMS,
    alarm_detail_prefix: Some("FLT"),
    reporting: ErrorReporting {
        current_alarm: None,
        history_newest: None,
        error_history: false,
        clear_error_code_on_reset: true,
        emcy_data: EmcyData::Zero,
        emcy_on_reset: REC_EMCY_ON_RESET,
    },
    write_rules: WRITE_RULES,
    power_on: REC_POWER_ON,
    motor: REC_MOTOR,
    scaling: Scaling::FactorProduct {
        gear: 0x6091,
        feed: 0x6092,
    },
    loss: REC_LOSS,
    counter_alarm: None,
    leave_op_alarm: REC_LEAVE_OP_ALARM,
    following_error: FollowingErrorSpec {
        window: a(0x6065, 0),
        timeout_ms: a(0x6066, 0),
        disabled: 0xFFFF_FFFF,
        alarm: Some("J3"),
    },
    command: CommandCheck {
        speed_factor: 1.0,
        speed_alarm: None,
        overflow_alarm: None,
    },
    torque_limits: TorqueLimits {
        positive: None,
        negative: None,
        max: Some(a(0x6072, 0)),
        speed_limit: None,
    },
    torque_slope: TorqueSlopeUnit::MilliNewtonMetrePerSecond,
    torque_mode_quick_stop_immediate: false,
    halt_in_cyclic_modes: true,
    pp_ack_while_moving: false,
    // CSP example, "Starting the Operating Mode": "The movement is started via the
    // Controlword. … Bit 4: New Target Value 0 » 1 Starts a movement to a target position."
    csp_start_edge: true,
    modes: ModeRules {
        selector: None,
        groups: &[],
        modes: &[1, 3, 4, 6, 8, 9, 10],
        initial: 0,
    },
    monitors: &[
        Monitor {
            address: a(0x6078, 0),
            quantity: Quantity::CurrentPermille,
        },
        Monitor {
            address: a(0x6079, 0),
            quantity: Quantity::DcLinkMillivolt,
        },
    ],
    status_bits: &[
        StatusBit {
            address: a(0x20B5, 0),
            bit: 0,
            condition: Condition::InPosition,
        },
        StatusBit {
            address: a(0x20A2, 0),
            bit: 0,
            condition: Condition::PowerStageOn,
        },
    ],
    homing: HomingSpec {
        methods: REC_HOMING_METHODS,
        index_pulse: true,
        // Table 10-4: fault 0x6100 "Homing Error" (HE, FLT 174); §10.2: a non-zero 0x603F is a
        // fault and the state machine enters Fault.
        failure: HomingFailure::Fault { alarm: "HE" },
    },
    // §5.10: "Bit 10 = Target reached 0 = Target torque not reached 1 = Target torque reached".
    tq_target_reached: true,
    // 60B8h bit 2: "trigger with zero pulse signal or position encoder (not support)".
    touch_probe_index_pulse: false,
    sync_cycle_mismatch: AlStatusCode::DC_INVALID_CYCLE_TIME,
    abort_codes: REC_ABORT_CODES,
    // The manual names a BOOT state (LED "very fast flashing") but no file access.
    foe: None,
    // Table 10-2 lists "0601 0004h The object cannot be accessed via complete access" (and
    // 0601 0000h "Unsupported access to an object"): the first is the one that names complete
    // access.
    complete_access_refusal: SdoAbortCode::COMPLETE_ACCESS_UNSUPPORTED,
};

// ============================================================================================
// Values that are ours ([REC]): what the manual leaves open, chosen for the emulation
// ============================================================================================

/// \[REC\] 0x1001 bits per fault class (the manual lists the bits, not which fault sets which):
/// bit 0 always, plus bit 1 current, bit 2 voltage, bit 3 temperature, bit 4 communication /
/// monitoring.
pub struct ErrorRegisterBits {
    /// Generic.
    pub generic: u8,
    /// Current.
    pub current: u8,
    /// Voltage.
    pub voltage: u8,
    /// Temperature.
    pub temperature: u8,
    /// Communication and monitoring.
    pub monitoring: u8,
}

/// \[REC\] See [`ErrorRegisterBits`].
pub const REC_ERROR_REGISTER: ErrorRegisterBits = ErrorRegisterBits {
    generic: 0x01,
    current: 0x03,
    voltage: 0x05,
    temperature: 0x09,
    monitoring: 0x11,
};

/// \[REC\] The emulated motor: the 400 W motor the dictionary's defaults describe (torque
/// constant 0x2039 = 321 mN·m/A, drive continuous current 0x207C = 3959 mA, so a rated torque
/// of 1.271 N·m; peak current 0x2036 = 11 879 mA = 300 %), 3000 r/min rated, 6000 r/min
/// maximum, total inertia 7.4 × 10⁻⁵ kg·m² (rotor and an equal load). With the power stage
/// off it coasts (0x605E = −1, DISMODE 0, read as "disable at once"). Zero speed below
/// 30 r/min.
pub const REC_MOTOR: MotorSpec = MotorSpec {
    rated_torque_nm: 1.271,
    peak_torque_permille: 3000.0,
    rated_speed_rev_s: 50.0,
    max_speed_rev_s: 100.0,
    inertia_kg_m2: 7.4e-5,
    viscous_nm_s_rad: 4.0e-5,
    dynamic_brake_nm_s_rad: 0.0,
    power_off: PowerOff::Coast,
    zero_speed_rev_s: 0.5,
};

/// \[REC\] Power-on values the manual leaves to the hardware: motor rated current 0x6075 =
/// 3959 mA and torque 0x6076 = 1271 mN·m (the manual prints 0, "motor-dependent"), motor
/// maximum speed 0x6080 and 0x20EE = 6000 r/min, the firmware version the manual is written for
/// in 0x100A, and the serial number.
pub const REC_POWER_ON: &[PowerOnValue] = &[
    PowerOnValue {
        address: a(0x1009, 0),
        value: PowerOnData::Text("emulated"),
    },
    PowerOnValue {
        address: a(0x100A, 0),
        value: PowerOnData::Text("2.0.6"),
    },
    PowerOnValue {
        address: a(0x1018, 4),
        value: PowerOnData::Serial,
    },
    PowerOnValue {
        address: a(0x6075, 0),
        value: PowerOnData::Int(3959),
    },
    PowerOnValue {
        address: a(0x6076, 0),
        value: PowerOnData::Int(1271),
    },
    PowerOnValue {
        address: a(0x6080, 0),
        value: PowerOnData::Int(6000),
    },
    PowerOnValue {
        address: a(0x20EE, 0),
        value: PowerOnData::Int(6000),
    },
];

/// \[REC\] Loss of cyclic data (MANUAL GAP: the manual names the fault, not the rule): the
/// ETG.1020 error counter, +3 per SYNC0 without data, −1 per cycle with data; 0x818D "EtherCAT
/// Packet Loss" after 7 ms of consecutive misses, the MR-J4-TM's automatic threshold; the
/// counter stands still while a fault is present and a fault reset starts it at 0.
pub const REC_LOSS: LossDetection = LossDetection {
    increment: 3,
    decrement: 1,
    limit: LossLimit::Milliseconds(7),
    alarm: "Fb8",
    restart_on_reset: true,
};

/// \[REC\] Leaving OP with the motor energised raises 0xF080 "CAN/EtherCAT State Not
/// Operational".
pub const REC_LEAVE_OP_ALARM: Option<&str> = Some("Fb9");

/// \[REC\] An EMCY with code 0x0000 when a fault is reset (the manual does not say).
pub const REC_EMCY_ON_RESET: bool = true;

/// \[REC\] Homing methods: the manual gives 0x6098 "the value range is 1 to 35" (§5.8) and
/// refers to CiA 402 for the methods, with no list and no 0x60E3; the emulated drive runs the
/// CiA 402 methods in that range the machine model knows (1–14, 17–30, 33–35).
pub const REC_HOMING_METHODS: &[i8] = &[
    1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28,
    29, 30, 33, 34, 35,
];

/// \[REC\] The BDHDE's SDO abort codes (Table 10-2) have no "object cannot be mapped", no
/// "PDO length exceeded" (0x06040041/0x06040042) and no length refinements (0x06070012/13);
/// the emulated drive answers a wrong length with the listed 0x06070010 and a mapping entry
/// naming an object that cannot be mapped with the listed "Invalid value for parameter"
/// 0x06090030, and a mapping or assignment beyond the PDO budget with "Value of parameter
/// written too high" 0x06090031.
pub const REC_ABORT_CODES: &[(SdoAbortCode, SdoAbortCode)] = &[
    (SdoAbortCode::NOT_MAPPABLE, SdoAbortCode::VALUE_RANGE),
    (SdoAbortCode::PDO_TOO_LONG, SdoAbortCode::VALUE_TOO_HIGH),
    // Table 10-2 lists only "Data type does not match, length of service parameter does not
    // match" 0x06070010 for a wrong length, not the "too high"/"too low" refinements.
    (SdoAbortCode::LENGTH_TOO_HIGH, SdoAbortCode::LENGTH_MISMATCH),
    (SdoAbortCode::LENGTH_TOO_LOW, SdoAbortCode::LENGTH_MISMATCH),
];
