//! The emulated MR-J4-TM: its ESI file (`esi/Mitsubishi_MR-J4-TM.xml`: identity, dictionary,
//! CoE details, synchronisation modes and cycle times, SII) plus the emulator's model of the
//! drive, written from the manual independently of the master's profile.
//!
//! What it does, with the manual sections (SH(NA)030208ENG):
//! - the object dictionary of the profile, with the drive's write rules: SDO downloads to an
//!   object mapped in the RxPDO are refused with 0x06010006 (§4.2); 0x1C32:02 accepts only 250,
//!   500, 1000 and 2000 µs and 0x1C32:01 only 0 and 2 (§7.3.3(4)), each mirrored into 0x1C33;
//!   the objects the drive sets itself refuse writes with 0x06090030 (0x1C32:03, 0x1C33:03,
//!   0x607B, 0x607C, 0x608F, 0x6092, 0x60A8, 0x60A9); 0x10F1:02 refuses writes in the automatic
//!   threshold mode with 0x08000021 (B4 and later, §7.3.1(10)); remapping only in PRE-OP; no
//!   complete access (§4.1);
//! - the CiA 402 state machine with state skipping and quick-stop option 2 only; in cst (and tq)
//!   a quick stop switches the power stage off at once with the dynamic brake (§5.6); the state
//!   machine acts only in OP and leaving OP re-initialises it (§1.4.2, §5.1);
//! - [Pr. PA01] (0x2001) selects the cyclic modes (csp, csv, cst, hm; the factory setting) or the
//!   profile modes (pp, pv, tq, hm) at power-on (§5.4.1); switching to or from a position mode
//!   needs zero speed (§5.4.2);
//! - loss of cyclic data in DC mode: the error counter goes up by 3 per cycle without data and
//!   [AL. 86.1] is raised after 7 ms of them (§7.3.1(10), automatic threshold); the incremental
//!   counter 0x2D23 raises [AL. 86.2] when it is not advanced by 1 per cycle, and 0x2D24 echoes
//!   it + 1 (§6.2);
//! - 0x603F = 0xFF00 + alarm number, kept after a reset ("latest error since power-on"),
//!   0x2A41 = alarm << 16 | detail, 0x1003 history, 0x1001 bit 0 (§7.3.1(2), (3), §7.3.5, §7.3.8(1));
//! - a csp command outside the 32-bit range raises [AL. 69] (§5.8);
//! - statusword bit 13 when the droop exceeds 0x6065 for longer than 0x6066 (§5.4.3).
//!
//! The emulator's own choices are in the section "Values that are ours" below.

use super::spec::{
    AlarmDef, CommandCheck, Condition, CycleCounterSpec, CycleSource, DriveSpec, EmcyData,
    ErrorReporting, FollowingErrorSpec, GroupAtPowerOn, HomingFailure, HomingSpec, LossDetection,
    LossLimit, ModeGroup, ModeRules, Monitor, MotorSpec, PowerOff, PowerOnData, PowerOnValue,
    Quantity, Scaling, StateMachineSpec, StatusBit, SyncObjects, TorqueLimits, TorqueSlopeUnit,
    WriteRule,
};
use crate::cia402::QuickStopOption;
use crate::ec::AlStatusCode;
use crate::od::{ObjectAddress, SdoAbortCode};
use crate::pdo::{DirectionLimits, PdoLimits, PdoRange};
use std::sync::OnceLock;

/// Position units per motor revolution in the cyclic modes: encoder pulses of the MR-J4 rotary
/// motors, 22 bits (§5.4.3; 0x608F:01 reports the resolution).
pub const PULSES_PER_REV: f64 = 4_194_304.0;

/// 0x1C32:02 accepts these cycles only, ns (§1.3, §7.3.3(4)).
const CYCLES: [u64; 4] = [250_000, 500_000, 1_000_000, 2_000_000];

/// The state machine (§5.1, §5.2): Switch on (0x0007) or Enable operation (0x000F) from Switch
/// on disabled, and Enable operation from Ready to switch on, jump straight there; 0x605A
/// has the one code 2 (range 2–2, §7.3.8); transition 16 "not supported" (§5.1 table);
/// switching to or from a position mode needs zero speed (§5.4.2), the point table (−101) and
/// indexer (−103) modes position the axis.
pub const STATE_MACHINE: StateMachineSpec = StateMachineSpec {
    state_skipping: true,
    transition_16: false,
    quick_stop_options: &[QuickStopOption::QUICK_STOP_RAMP],
    default_quick_stop_option: QuickStopOption::QUICK_STOP_RAMP,
    position_mode_switch_needs_zero_speed: true,
    vendor_position_modes: &[-101, -103],
    remote_gates_controlword: false,
};

/// PDO rules (§1.3 "RxPDO: 1 channel, TxPDO: 1 channel", §3.4, §7.3.2): mapping tables
/// 0x1600–0x1603 and 0x1A00–0x1A03 of up to 32 entries, at most 64 bytes per direction, one
/// PDO assigned per SyncManager.
pub const PDO_LIMITS: PdoLimits = PdoLimits {
    drive: "MR-J4-TM",
    rx: DirectionLimits {
        pdos: &[PdoRange::new(0x1600, 0x1603, 32)],
        max_assigned: 1,
        max_entries: 32,
        max_bytes: 64,
    },
    tx: DirectionLimits {
        pdos: &[PdoRange::new(0x1A00, 0x1A03, 32)],
        max_assigned: 1,
        max_entries: 32,
        max_bytes: 64,
    },
    assignment_writable: true,
};

const fn a(index: u16, sub: u8) -> ObjectAddress {
    ObjectAddress::new(index, sub)
}

const fn alarm(id: &'static str, text: &'static str, number: u16, detail: u16) -> AlarmDef {
    AlarmDef {
        id,
        text,
        error_code: 0xFF00 | number,
        error_register: 0x01,
        detail: (number as u32) << 16 | detail as u32,
        resettable: true,
    }
}

/// The alarms the emulated MR-J4-TM raises. Names from the manual, except AL.35 and AL.52
/// (\[REC\]: from the MELSERVO-J4 alarm numbering; this manual does not list them).
pub const ALARMS: &[AlarmDef] = &[
    alarm("AL.10", "Undervoltage", 0x10, 1),
    AlarmDef {
        resettable: false,
        ..alarm("AL.25", "Absolute position erased", 0x25, 1)
    },
    alarm("AL.35", "Command frequency error", 0x35, 1),
    AlarmDef {
        resettable: false,
        ..alarm("AL.37", "Parameter error", 0x37, 1)
    },
    alarm("AL.52", "Error excessive", 0x52, 1),
    alarm("AL.69", "Command error", 0x69, 1),
    alarm("AL.86.1", "Network communication error 1", 0x86, 1),
    alarm("AL.86.2", "Network communication error 2", 0x86, 2),
];

/// 0x6060 values of 0x6502 (§7.3.8(6)): 0, pp, pv, tq, hm, csp, csv, cst, jg, pt, idx (the
/// negative ones as their INTEGER8 bit patterns).
static MODE_VALUES: &[u64] = &[0, 1, 3, 4, 6, 8, 9, 10, 0x9C, 0x9B, 0x99];

/// The drive's write rules (see the module documentation).
pub const WRITE_RULES: &[WriteRule] = &[
    // §4.2 SDO Abort Code: "0601 0006h Object mapped to RxPDO, SDO download blocked. SDO
    // Download is executed to an object mapped to RxPDO." (KickCAT's DS402 sequence writes
    // 0x6060 by SDO in PRE-OP: refused while 0x6060 is mapped, as the manual says.)
    WriteRule::RefuseMappedRx(SdoAbortCode::MAPPED_TO_RXPDO),
    WriteRule::Allowed {
        address: a(0x1C32, 1),
        values: &[0, 2],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x1C33, 1),
        values: &[0, 2],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x1C32, 2),
        values: &CYCLES,
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x1C33, 2),
        values: &CYCLES,
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Mirror(a(0x1C32, 1), a(0x1C33, 1)),
    WriteRule::Mirror(a(0x1C32, 2), a(0x1C33, 2)),
    WriteRule::Refuse {
        objects: &[0x607C, 0x608F, 0x6092, 0x60A8, 0x60A9],
        entries: &[a(0x1C32, 3), a(0x1C33, 3), a(0x607B, 1), a(0x607B, 2)],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Refuse {
        objects: &[],
        entries: &[a(0x10F1, 2)],
        code: SdoAbortCode::LOCAL_CONTROL,
    },
    WriteRule::Allowed {
        address: a(0x6060, 0),
        values: MODE_VALUES,
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x607E, 0),
        values: &[0x00, 0xC0, 0xE0],
        code: SdoAbortCode::VALUE_RANGE,
    },
    // The magic values of §7.1, §7.3.1(8) (1011h "load"), §7.3.5(3) (2A40h 1EA5h), §6.5.2.
    WriteRule::Allowed {
        address: a(0x1010, 1),
        values: &[0x6576_6173],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x1011, 1),
        values: &[0x6461_6F6C],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x2A40, 0),
        values: &[0x1EA5],
        code: SdoAbortCode::VALUE_RANGE,
    },
    WriteRule::Allowed {
        address: a(0x2D34, 0),
        values: &[0x1EA5],
        code: SdoAbortCode::VALUE_RANGE,
    },
];

/// The emulated MR-J4-TM.
pub static SPEC: DriveSpec = DriveSpec {
    key: "mr-j4-tm",
    name: "MR-J4-TM",
    esi: include_str!("../../../../esi/Mitsubishi_MR-J4-TM.xml"),
    product_code: 0x0000_0201,
    model: OnceLock::new(),
    state_machine: STATE_MACHINE,
    pdo_limits: PDO_LIMITS,
    // §7.3.3(4): 0x1C32:01 0 = free run, 2 = DC SYNC0; 0x1C32:02 the cycle in ns.
    sync: SyncObjects {
        sync_type: Some(a(0x1C32, 1)),
        cycle: Some(CycleSource::Nanoseconds(a(0x1C32, 2))),
    },
    // §6.2, §7.3.7(22), (23): 0x2D23 advanced by 1 every cycle, else [AL. 86.2]; 0x2D24 echoes
    // it + 1.
    cycle_counter: Some(CycleCounterSpec {
        output: a(0x2D23, 0),
        echo: Some(a(0x2D24, 0)),
    }),
    alarms: ALARMS,
    alarm_detail_prefix: None,
    reporting: ErrorReporting {
        current_alarm: Some(a(0x2A41, 0)),
        history_newest: Some(a(0x2A00, 1)),
        error_history: true,
        clear_error_code_on_reset: false,
        emcy_data: REC_EMCY_DATA,
        emcy_on_reset: REC_EMCY_ON_RESET,
    },
    write_rules: WRITE_RULES,
    power_on: REC_POWER_ON,
    motor: REC_MOTOR,
    scaling: Scaling::Fixed {
        position_per_rev: PULSES_PER_REV,
        velocity_per_rev_s: 6000.0,
    },
    loss: LossDetection {
        increment: 3,
        decrement: REC_LOSS_DECREMENT,
        limit: LossLimit::Milliseconds(7),
        alarm: "AL.86.1",
        restart_on_reset: REC_LOSS_RESTART_ON_RESET,
    },
    counter_alarm: Some("AL.86.2"),
    leave_op_alarm: REC_LEAVE_OP_ALARM,
    following_error: FollowingErrorSpec {
        window: a(0x6065, 0),
        timeout_ms: a(0x6066, 0),
        disabled: 0xFFFF_FFFF,
        alarm: REC_FOLLOWING_ERROR_ALARM,
    },
    command: CommandCheck {
        speed_factor: REC_COMMAND_SPEED_FACTOR,
        speed_alarm: Some("AL.35"),
        overflow_alarm: Some("AL.69"),
    },
    torque_limits: TorqueLimits {
        positive: Some(a(0x60E0, 0)),
        negative: Some(a(0x60E1, 0)),
        max: None,
        speed_limit: Some(a(0x2D20, 0)),
    },
    torque_slope: TorqueSlopeUnit::PerMillePerSecond,
    torque_mode_quick_stop_immediate: true,
    halt_in_cyclic_modes: false,
    pp_ack_while_moving: true,
    csp_start_edge: false,
    modes: ModeRules {
        selector: Some(a(0x2001, 0)),
        groups: &[
            GroupAtPowerOn {
                group: ModeGroup {
                    value: 0,
                    name: "___0: automatic selection by each network",
                    modes: &[6, 8, 9, 10],
                },
                initial: 8,
            },
            GroupAtPowerOn {
                group: ModeGroup {
                    value: 1,
                    name: "___1: cyclic synchronous mode",
                    modes: &[6, 8, 9, 10],
                },
                initial: 8,
            },
            GroupAtPowerOn {
                group: ModeGroup {
                    value: 2,
                    name: "___2: profile mode",
                    modes: &[1, 3, 4, 6],
                },
                initial: 1,
            },
            GroupAtPowerOn {
                group: ModeGroup {
                    value: 6,
                    name: "___6: positioning mode (point table method)",
                    modes: &[6, -100, -101],
                },
                initial: -101,
            },
            GroupAtPowerOn {
                group: ModeGroup {
                    value: 8,
                    name: "___8: positioning mode (indexer method)",
                    modes: &[6, -100, -103],
                },
                initial: -103,
            },
        ],
        modes: &[],
        initial: 8,
    },
    monitors: &[
        Monitor {
            address: a(0x2B02, 0),
            quantity: Quantity::SpeedRpm,
        },
        Monitor {
            address: a(0x2B0B, 0),
            quantity: Quantity::TorquePercent,
        },
    ],
    status_bits: &[
        StatusBit {
            address: a(0x2D11, 0),
            bit: 12,
            condition: Condition::InPosition,
        },
        StatusBit {
            address: a(0x2D11, 0),
            bit: 13,
            condition: Condition::TorqueLimited,
        },
        StatusBit {
            address: a(0x2D12, 0),
            bit: 3,
            condition: Condition::ZeroSpeed,
        },
        StatusBit {
            address: a(0x2D12, 0),
            bit: 4,
            condition: Condition::SpeedLimited,
        },
    ],
    homing: HomingSpec {
        // 0x60E3's CiA 402 methods (§7.3.13 (5)(a): 37, 35, 34, 33, 28, 27, 24, 23, 22, 21,
        // 20, 19, 12, 11, 8, 7, 6, 5, 4, 3); its vendor methods −1 … −43 are not modelled.
        methods: &[
            37, 35, 34, 33, 28, 27, 24, 23, 22, 21, 20, 19, 12, 11, 8, 7, 6, 5, 4, 3,
        ],
        // The encoder's Z phase (§5.4.9 (4): methods 3–12 and 33/34 end on it).
        index_pulse: true,
        // §5.4.9 (4): a stroke end during methods 3–6 and 19–22 gives [AL. 90 Home position
        // return incomplete warning]; a warning (statusword bit 7, §5.3.1).
        failure: HomingFailure::Warning {
            id: "AL.90",
            text: "Home position return incomplete warning",
        },
    },
    // §5.4.8 (3): in tq, "Bit 10 Target reached (not supported)".
    tq_target_reached: false,
    // §5.5: "encoder zero point" as a trigger with 60B8h bit 2/10 = 1 [SW B2+].
    touch_probe_index_pulse: true,
    sync_cycle_mismatch: REC_SYNC_CYCLE_MISMATCH,
    abort_codes: REC_ABORT_CODES,
    foe: Some(REC_FOE),
    // §4.1: no complete access; the manual lists no abort codes: what a slave stack without
    // complete access answers, "unsupported access to an object".
    complete_access_refusal: SdoAbortCode::UNSUPPORTED_ACCESS,
};

// ============================================================================================
// Values that are ours ([REC]): what the manual leaves open, chosen for the emulation
// ============================================================================================

/// \[REC\] The emulated motor: a 100 W, 3000 r/min motor of the HG-KR13 class with a load of
/// the rotor's inertia. Values of that class, not a datasheet: rated torque 0.32 N·m, peak 300 %,
/// 6000 r/min, total inertia 1.6 × 10⁻⁵ kg·m²; the dynamic brake stops it with a 50 ms time
/// constant; zero speed below 50 r/min ([Pr. PC07]).
pub const REC_MOTOR: MotorSpec = MotorSpec {
    rated_torque_nm: 0.32,
    peak_torque_permille: 3000.0,
    rated_speed_rev_s: 50.0,
    max_speed_rev_s: 100.0,
    inertia_kg_m2: 1.6e-5,
    viscous_nm_s_rad: 1.0e-5,
    dynamic_brake_nm_s_rad: 3.2e-4,
    power_off: PowerOff::DynamicBrake,
    zero_speed_rev_s: 50.0 / 60.0,
};

/// \[REC\] What the hardware reports at power-on: the motor's data (0x6072 300 %, 0x6080
/// 6000 r/min, 0x608F:01 and 0x6092:01 4 194 304 pulses, 0x2D28 3000 r/min), the SI velocity
/// unit 0.01 r/min (0x60A9 = 0xFEB44700, §7.3.14(6)), the position range ±2³¹ (0x607B), the versions
/// and names of the emulated module and amplifier, and the serial number.
pub const REC_POWER_ON: &[PowerOnValue] = &[
    PowerOnValue {
        address: a(0x1009, 0),
        value: PowerOnData::Text("emulated"),
    },
    PowerOnValue {
        address: a(0x100A, 0),
        value: PowerOnData::Text(concat!("ecdrive ", env!("CARGO_PKG_VERSION"))),
    },
    PowerOnValue {
        address: a(0x1018, 4),
        value: PowerOnData::Serial,
    },
    PowerOnValue {
        address: a(0x2D28, 0),
        value: PowerOnData::Int(3000),
    },
    PowerOnValue {
        address: a(0x2D30, 0),
        value: PowerOnData::Text("MR-J4-10TM"),
    },
    PowerOnValue {
        address: a(0x2D31, 0),
        value: PowerOnData::Text("emulated"),
    },
    PowerOnValue {
        address: a(0x2D32, 0),
        value: PowerOnData::Text("B4"),
    },
    PowerOnValue {
        address: a(0x2D33, 0),
        value: PowerOnData::Text("ECDRIVE"),
    },
    PowerOnValue {
        address: a(0x6072, 0),
        value: PowerOnData::Int(3000),
    },
    PowerOnValue {
        address: a(0x607B, 1),
        value: PowerOnData::Int(i32::MIN as i64),
    },
    PowerOnValue {
        address: a(0x607B, 2),
        value: PowerOnData::Int(i32::MAX as i64),
    },
    PowerOnValue {
        address: a(0x6080, 0),
        value: PowerOnData::Int(6000),
    },
    PowerOnValue {
        address: a(0x608F, 1),
        value: PowerOnData::Int(4_194_304),
    },
    PowerOnValue {
        address: a(0x6092, 1),
        value: PowerOnData::Int(4_194_304),
    },
    PowerOnValue {
        address: a(0x60A9, 0),
        value: PowerOnData::Int(0xFEB4_4700),
    },
];

/// \[REC\] The error counter goes down by 1 per cycle with data (the ETG.1020 convention; the
/// manual states only the +3).
pub const REC_LOSS_DECREMENT: u32 = 1;

/// \[REC\] MANUAL GAP (§7.3.1(10) gives the +3 and the threshold, not what an alarm reset does
/// to the counter): the error counter stands still while an alarm is present and an alarm reset
/// starts it at 0, so that [AL. 86.1] can be reset once the data arrives again.
pub const REC_LOSS_RESTART_ON_RESET: bool = true;

/// \[REC\] Leaving OP while the motor is energised raises [AL. 86.1] (§1.4.4: disconnecting
/// without stopping, Shutdown and PRE-OP "may" raise it).
pub const REC_LEAVE_OP_ALARM: Option<&str> = Some("AL.86.1");

/// \[REC\] The following error beyond 0x6065 for longer than 0x6066 raises [AL. 52 Error
/// excessive] as well as statusword bit 13. The manual names only the bit; the drive's own
/// error-excessive level ([Pr. PC01], general manual) defaults to the same 3 revolutions as
/// 0x6065.
pub const REC_FOLLOWING_ERROR_ALARM: Option<&str> = Some("AL.52");

/// \[REC\] A csp set-point step implying more than 1.2 × the permissible speed raises
/// [AL. 35 Command frequency error].
pub const REC_COMMAND_SPEED_FACTOR: f64 = 1.2;

/// \[REC\] EMCY manufacturer bytes: the 0x2A41 value (alarm << 16 | detail), little-endian.
pub const REC_EMCY_DATA: EmcyData = EmcyData::DetailLe;

/// \[REC\] An EMCY with code 0x0000 when an alarm is reset.
pub const REC_EMCY_ON_RESET: bool = true;

/// \[REC\] The MR-J4-TM's abort code list (§4.2 SDO Abort Code) has no specific code for the
/// standard remap refusals (an entry written while sub 0 is not 0, an object that cannot be
/// mapped, a PDO too long, a bit length that does not match the object); the emulated drive
/// answers them with the listed "General parameter incompatibility reason" 0x06040043.
pub const REC_ABORT_CODES: &[(SdoAbortCode, SdoAbortCode)] = &[
    (
        SdoAbortCode::SUBINDEX0_NOT_ZERO,
        SdoAbortCode::PARAMETER_INCOMPATIBLE,
    ),
    (
        SdoAbortCode::NOT_MAPPABLE,
        SdoAbortCode::PARAMETER_INCOMPATIBLE,
    ),
    (
        SdoAbortCode::PDO_TOO_LONG,
        SdoAbortCode::PARAMETER_INCOMPATIBLE,
    ),
    (
        SdoAbortCode::LENGTH_MISMATCH,
        SdoAbortCode::PARAMETER_INCOMPATIBLE,
    ),
];

/// \[REC\] SAFE-OP → OP with a SYNC0 cycle that differs from 0x1C32:02 (or that the drive does
/// not support) is refused with AL status 0x0035 "invalid sync cycle time".
pub const REC_SYNC_CYCLE_MISMATCH: AlStatusCode = AlStatusCode::DC_INVALID_CYCLE_TIME;

/// FoE on the MR-J4-TM: the manual says the drive supports FoE (software B3 or later, §1.2) and
/// that in the Bootstrap state "the mailbox communication with the FoE protocol can be
/// performed. Firmware can be updated through EtherCAT in this state" (§1.4.1); for details it
/// refers to the sales office. Everything else is \[REC\] (MANUAL GAP): files only in BOOT
/// (error 0x8009 elsewhere); the password 0x4D524A34 ("MRJ4"; error 0x800A when wrong); files
/// up to 4 MiB; a written file must be a firmware image for vendor 0xA1E, product 0x201 in the
/// emulation's own format ([`crate::foe::FirmwareImage`]; error 0x8004 otherwise); it is
/// applied at the next BOOT → INIT: 0x1018:03 and 0x100A (the network module's revision and
/// software version, §7.3.1(6), (9)) then report the image's.
pub const REC_FOE: crate::foe::FoeSpec = crate::foe::FoeSpec {
    password: 0x4D52_4A34,
    boot_only: true,
    max_file_bytes: 4 << 20,
    firmware_for: Some((0x0000_0A1E, 0x0000_0201)),
};
