//! The per-cycle axis engine: enabling, set-points, mode switching rules, faults.

use crate::support::cia402_drives as drives;
use crate::support::cia402_servo as servo;

use ecdrive_core::cia402::{
    Axis, AxisConfig, AxisError, Command, ControlWord, DriveCaps, ErrorCode, Event, Feedback,
    ModeSwitchFailure, ModeSwitchPhase, OperationMode, Phase, PlannerConfig, PlannerError,
    SetPointKind, StandstillConfig, State, StatusWord, StopRampConfig, SupportedModes, Target,
};
use proptest::prelude::*;
use servo::SimServo;

const CSP: OperationMode = OperationMode::CyclicSyncPosition;
const CSV: OperationMode = OperationMode::CyclicSyncVelocity;
const CST: OperationMode = OperationMode::CyclicSyncTorque;

fn config(caps: &DriveCaps, mode: OperationMode) -> AxisConfig {
    AxisConfig {
        planner: PlannerConfig {
            timeout_cycles: 200,
            fault_reset_hold_cycles: 3,
            quick_stop_option: caps.default_quick_stop_option.code,
        },
        initial_mode: mode,
        mode_switch_timeout_cycles: 50,
        standstill: StandstillConfig {
            velocity: 0,
            position_delta: 0,
            cycles: 2,
        },
        stop_ramp: StopRampConfig { cycles: 10 },
    }
}

/// A generic drive with every cyclic mode and the plain CiA rules.
const GENERIC: DriveCaps = DriveCaps {
    supported_modes: SupportedModes::ALL_STANDARD,
    ..DriveCaps::CIA402
};

fn cycle(axis: &mut Axis, drive: &mut SimServo) -> ecdrive_core::cia402::Output {
    let out = axis.step(&drive.feedback());
    drive.apply(&out);
    out
}

fn events(axis: &mut Axis) -> Vec<Event> {
    std::iter::from_fn(|| axis.poll_event()).collect()
}

/// Enable and run until the axis streams; returns the number of cycles.
fn enable(axis: &mut Axis, drive: &mut SimServo) -> usize {
    axis.request_enable().expect("enable accepted");
    for n in 0..50 {
        cycle(axis, drive);
        if axis.status().streaming {
            return n;
        }
    }
    panic!("not streaming: {:?}", axis.status());
}

#[test]
fn enabling_starts_at_the_actual_position() {
    let mut drive = SimServo::new(drives::MR_J4_TM, State::SwitchOnDisabled, CSP);
    drive.position = 123_456;
    let mut axis = Axis::new(drives::MR_J4_TM, config(&drives::MR_J4_TM, CSP)).unwrap();
    assert!(matches!(
        axis.set_position(0),
        Err(AxisError::NotStreaming { .. })
    ));
    enable(&mut axis, &mut drive);
    // Every output on the way, and the first in Operation enabled, targets the actual position.
    assert!(drive.outputs.iter().all(|o| o.target_position == 123_456));
    assert!(drive.outputs.iter().all(|o| o.mode == CSP));
    // The standard transitions, also on the MR-J4-TM (which would accept 0x000F at once).
    let cws: Vec<u16> = drive.outputs.iter().map(|o| o.controlword.raw()).collect();
    assert_eq!(cws[..3], [0x0006, 0x0007, 0x000F], "{cws:04X?}");
    assert_eq!(drive.position, 123_456, "no jump");
    let st = axis.status();
    assert_eq!(
        (st.phase, st.state, st.active_mode),
        (Phase::Enabled, Some(State::OperationEnabled), CSP)
    );
    axis.set_position(123_500).unwrap();
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(out.target_position, 123_500);
    assert_eq!(drive.position, 123_500);
    // Without a new set-point the last one is held.
    assert_eq!(cycle(&mut axis, &mut drive).target_position, 123_500);
    assert_eq!(
        axis.set_velocity(5),
        Err(AxisError::WrongSetPoint {
            kind: SetPointKind::Velocity,
            mode: CSP
        })
    );
}

/// MR-J4-TM §5.4.2: switching from csp needs zero speed. The engine ramps the motion down,
/// writes 0x6060 only at standstill, holds the csp set-point until 0x6061 confirms, and starts
/// csv from the actual velocity (0).
#[test]
fn zero_speed_mode_switch() {
    let caps = drives::MR_J4_TM;
    let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CSP);
    drive.mode_lag = 3;
    let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
    enable(&mut axis, &mut drive);
    let mut p = drive.position;
    for _ in 0..20 {
        p += 50;
        axis.set_position(p).unwrap();
        cycle(&mut axis, &mut drive);
    }
    assert_eq!(drive.velocity, 50);
    events(&mut axis);
    axis.request_mode(CSV).unwrap();
    assert_eq!(
        axis.set_position(p + 50),
        Err(AxisError::ModeSwitchInProgress { to: CSV })
    );
    assert_eq!(
        axis.request_mode(CST),
        Err(AxisError::ModeSwitchInProgress { to: CSV })
    );

    // Phase 1: ramp down. The position increments shrink to 0; 0x6060 stays csp.
    let mut increments = Vec::new();
    let mut last = p;
    loop {
        let out = cycle(&mut axis, &mut drive);
        increments.push(out.target_position - last);
        last = out.target_position;
        if axis.status().mode_switch != (ModeSwitchPhase::Stopping { to: CSV }) {
            // Standstill detected in this step: 0x6060 goes out now.
            assert_eq!(out.mode, CSV);
            break;
        }
        assert_eq!(out.mode, CSP);
        assert!(increments.len() < 40, "stopping takes too long");
    }
    assert!(
        increments.windows(2).all(|w| w[1] <= w[0]),
        "{increments:?}"
    );
    assert_eq!(increments.first(), Some(&45));
    assert_eq!(*increments.last().unwrap(), 0);
    assert_eq!(drive.velocity, 0);
    let held = last;

    // Phase 2: 0x6060 = csv; csp's set-point held, csv's tracks the actual velocity (0).
    let mut waited = 0;
    while axis.status().mode_switch == (ModeSwitchPhase::Requested { to: CSV }) {
        let out = cycle(&mut axis, &mut drive);
        assert_eq!(out.mode, CSV);
        assert_eq!(out.target_position, held);
        assert_eq!(out.target_velocity, 0);
        if axis.status().mode_switch == ModeSwitchPhase::Idle {
            break;
        }
        assert_eq!(out.controlword.mode_specific(), ControlWord::empty());
        assert!(matches!(
            axis.set_velocity(10),
            Err(AxisError::ModeSwitchInProgress { .. })
        ));
        waited += 1;
        assert!(waited < 20);
    }
    assert!(waited >= 3, "0x6061 confirms after the drive's lag");
    assert_eq!(drive.refused_mode_writes, 0);
    assert_eq!(drive.switched_while_moving, 0);
    let evs = events(&mut axis);
    assert!(
        evs.contains(&Event::ModeSwitched { from: CSP, to: CSV }),
        "{evs:?}"
    );
    assert_eq!(axis.status().active_mode, CSV);

    // Phase 3: csv streams from 0; no jump.
    let out = cycle(&mut axis, &mut drive);
    assert_eq!((out.target_velocity, drive.velocity), (0, 0));
    axis.set_velocity(30).unwrap();
    assert_eq!(cycle(&mut axis, &mut drive).target_velocity, 30);
}

/// csv → csp on the MR-J4-TM: the target velocity ramps linearly to 0, then 0x6060 = csp, and
/// csp starts at the actual position.
#[test]
fn zero_speed_switch_from_csv_ramps_velocity() {
    let caps = drives::MR_J4_TM;
    let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CSV);
    let mut axis = Axis::new(caps, config(&caps, CSV)).unwrap();
    enable(&mut axis, &mut drive);
    axis.set_velocity(100).unwrap();
    for _ in 0..5 {
        cycle(&mut axis, &mut drive);
    }
    axis.request_mode(CSP).unwrap();
    let mut velocities = Vec::new();
    let mut position_when_written = None;
    for _ in 0..40 {
        let out = cycle(&mut axis, &mut drive);
        if out.mode == CSV {
            velocities.push(out.target_velocity);
        } else if position_when_written.is_none() {
            position_when_written = Some(drive.position);
        }
        if axis.status().mode_switch == ModeSwitchPhase::Idle {
            break;
        }
    }
    // 10-cycle linear ramp: 90, 80, …, 0, then held at 0 until standstill is confirmed.
    assert_eq!(&velocities[..10], &[90, 80, 70, 60, 50, 40, 30, 20, 10, 0]);
    assert!(velocities[10..].iter().all(|v| *v == 0));
    assert_eq!(drive.refused_mode_writes, 0);
    assert_eq!(axis.status().active_mode, CSP);
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(Some(out.target_position), position_when_written);
    assert_eq!(
        out.target_position, drive.position,
        "csp starts where the axis is"
    );
}

/// Without the zero-speed rule (BDHDE-like) a csv → cst switch starts at once; the csv
/// set-point is held and cst starts from the actual torque.
#[test]
fn mode_switch_without_zero_speed_rule() {
    let mut drive = SimServo::new(GENERIC, State::SwitchOnDisabled, CSV);
    drive.mode_lag = 2;
    let mut axis = Axis::new(GENERIC, config(&GENERIC, CSV)).unwrap();
    enable(&mut axis, &mut drive);
    axis.set_velocity(200).unwrap();
    cycle(&mut axis, &mut drive);
    drive.torque = 37; // a load
    axis.request_mode(CST).unwrap();
    assert_eq!(
        axis.status().mode_switch,
        ModeSwitchPhase::Requested { to: CST }
    );
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(out.mode, CST);
    assert_eq!(out.target_velocity, 200, "csv set-point held");
    assert_eq!(out.target_torque, 37, "cst starts from the actual torque");
    while axis.status().mode_switch != ModeSwitchPhase::Idle {
        let out = cycle(&mut axis, &mut drive);
        if axis.status().mode_switch != ModeSwitchPhase::Idle {
            assert_eq!(out.target_velocity, 200);
        }
    }
    assert_eq!(axis.status().active_mode, CST);
    let torque_at_switch = drive.torque;
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(out.target_torque, torque_at_switch);
    axis.set_torque(-5).unwrap();
    assert_eq!(cycle(&mut axis, &mut drive).target_torque, -5);
}

#[test]
fn unconfirmed_mode_switch_is_abandoned() {
    let mut drive = SimServo::new(GENERIC, State::SwitchOnDisabled, CSV);
    let mut axis = Axis::new(GENERIC, config(&GENERIC, CSV)).unwrap();
    enable(&mut axis, &mut drive);
    drive.mode_lag = u32::MAX;
    axis.set_velocity(20).unwrap();
    axis.request_mode(CST).unwrap();
    for _ in 0..60 {
        cycle(&mut axis, &mut drive);
    }
    let st = axis.status();
    assert_eq!(
        (st.mode_switch, st.commanded_mode, st.active_mode),
        (ModeSwitchPhase::Idle, CSV, CSV)
    );
    let err = st.mode_switch_error.expect("reported");
    assert_eq!(
        err.reason,
        ModeSwitchFailure::NotConfirmed {
            displayed: Some(CSV)
        }
    );
    assert!(err.to_string().contains("0x6061"));
    assert!(events(&mut axis).contains(&Event::ModeSwitchFailed(err)));
    // Streaming in the old mode again, from the held set-point.
    assert!(st.streaming);
    assert_eq!(cycle(&mut axis, &mut drive).target_velocity, 20);
}

/// A drive that never reports zero speed: the switch is abandoned and 0x6060 never changes.
#[test]
fn no_standstill_no_mode_write() {
    let caps = drives::MR_J4_TM;
    let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0237));
    fb.mode_display = Some(CSP);
    fb.position = Some(0);
    fb.zero_speed = Some(false);
    axis.request_enable().unwrap();
    for _ in 0..3 {
        axis.step(&fb);
    }
    assert!(axis.status().streaming);
    axis.request_mode(CSV).unwrap();
    for _ in 0..60 {
        let out = axis.step(&fb);
        assert_eq!(out.mode, CSP);
    }
    let err = axis.status().mode_switch_error.expect("reported");
    assert_eq!(err.reason, ModeSwitchFailure::NoStandstill);
}

/// Before a zero-speed switch, pp stops with Halt (bit 8); pv instead ramps its target
/// velocity to 0, which the drive follows by its own deceleration (a halt stops it by 0x605D:
/// the emulated MR-J4-TM at its torque limit, −261 %).
#[test]
fn profile_mode_switch_uses_halt() {
    let caps = drives::MR_J4_TM;
    let pp = OperationMode::ProfilePosition;
    let pv = OperationMode::ProfileVelocity;
    // pp → pv: Halt.
    let mut axis = Axis::new(caps, config(&caps, pp)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0237));
    fb.mode_display = Some(pp);
    fb.velocity = Some(100);
    axis.request_enable().unwrap();
    axis.step(&fb);
    axis.set_mode_bits(ControlWord::NEW_SET_POINT | ControlWord::SWITCH_ON);
    assert_eq!(axis.step(&fb).controlword.raw(), 0x001F);
    axis.request_mode(pv).unwrap();
    let out = axis.step(&fb);
    assert_eq!(out.controlword.raw(), 0x010F, "halt, no application bits");
    assert_eq!(out.mode, pp);
    fb.velocity = Some(0);
    axis.step(&fb);
    let out = axis.step(&fb);
    assert_eq!(out.mode, pv);
    assert_eq!(out.controlword.raw(), 0x000F);
    // pv → pp: no Halt; the target velocity ramps down from where the axis turns.
    let mut axis = Axis::new(caps, config(&caps, pv)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0237));
    fb.mode_display = Some(pv);
    fb.velocity = Some(1000);
    axis.request_enable().unwrap();
    axis.step(&fb);
    axis.set_velocity(1000).unwrap();
    axis.step(&fb);
    axis.request_mode(pp).unwrap();
    let first = axis.step(&fb);
    assert_eq!(first.controlword.raw(), 0x000F, "no halt in pv");
    assert_eq!(first.mode, pv);
    let second = axis.step(&fb);
    assert!(
        second.target_velocity < first.target_velocity && first.target_velocity < 1000,
        "{} then {}",
        first.target_velocity,
        second.target_velocity
    );
    fb.velocity = Some(0);
    for _ in 0..1000 {
        if axis.step(&fb).mode == pp {
            return;
        }
    }
    panic!("pp never requested");
}

#[test]
fn unsupported_modes_are_refused() {
    let blv = drives::BLV_R;
    assert!(matches!(
        Axis::new(blv, config(&blv, CSP)),
        Err(AxisError::ModeNotSupported { .. })
    ));
    let mut axis = Axis::new(blv, config(&blv, OperationMode::ProfileVelocity)).unwrap();
    let err = axis.request_mode(CSP).unwrap_err();
    assert_eq!(
        err.to_string(),
        "mode csp (8) is not supported by the drive (0x6502 = 0x0000002D)"
    );
    let mr = drives::MR_J4_TM;
    let mut axis = Axis::new(mr, config(&mr, CSP)).unwrap();
    axis.step(&Feedback::new(StatusWord::from_raw(0x0250)));
    assert!(axis.request_mode(OperationMode::Vendor(-101)).is_ok());
    let mut axis = Axis::new(mr, config(&mr, CSP)).unwrap();
    axis.step(&Feedback::new(StatusWord::from_raw(0x0250)));
    assert!(axis.request_mode(OperationMode::Vendor(-102)).is_err());
    assert!(axis.request_mode(OperationMode::Velocity).is_err());
}

/// A fault drops the enable request at once, reports 0x603F decoded, refuses enable until reset,
/// and after the reset the drive stays disabled until enable is requested again.
#[test]
fn fault_handling() {
    let caps = drives::MR_J4_TM;
    let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CSP);
    drive.position = 1000;
    let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
    enable(&mut axis, &mut drive);
    events(&mut axis);
    drive.fault = true;
    drive.error_code = 0xFF37;
    cycle(&mut axis, &mut drive); // drive enters fault reaction
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(Command::decode(out.controlword), Command::DisableVoltage);
    let evs = events(&mut axis);
    let fault = evs.iter().find_map(|e| match e {
        Event::Fault { error, .. } => Some(*error),
        _ => None,
    });
    let error = fault.expect("fault event").expect("decoded 0x603F");
    assert_eq!((error.name, error.text), ("AL.37", "Parameter error"));
    let st = axis.status();
    assert_eq!(
        (st.phase, st.target, st.fault),
        (Phase::Faulted, Target::SwitchOnDisabled, true)
    );
    assert_eq!(
        axis.request_enable(),
        Err(AxisError::Faulted {
            error_code: Some(ErrorCode(0xFF37))
        })
    );
    assert!(axis.set_position(0).is_err());
    for _ in 0..10 {
        let out = cycle(&mut axis, &mut drive);
        assert_eq!(out.controlword.raw(), 0x0000);
    }
    // Reset while the cause is present: edges, no success.
    assert!(axis.request_fault_reset());
    assert_eq!(axis.status().phase, Phase::ResettingFault);
    let mut edges = 0;
    let mut prev = 0u16;
    for _ in 0..20 {
        let cw = cycle(&mut axis, &mut drive).controlword.raw();
        if cw & 0x80 != 0 && prev & 0x80 == 0 {
            edges += 1;
        }
        prev = cw;
    }
    assert!(edges >= 2);
    assert_eq!(drive.device.state(), State::Fault);
    // Cause gone: the next edge resets.
    drive.fault = false;
    for _ in 0..10 {
        cycle(&mut axis, &mut drive);
    }
    assert_eq!(drive.device.state(), State::SwitchOnDisabled);
    assert!(events(&mut axis).contains(&Event::FaultCleared));
    assert_eq!(axis.status().phase, Phase::Disabled);
    for _ in 0..20 {
        let out = cycle(&mut axis, &mut drive);
        assert_eq!(out.controlword.raw() & 0x000F, 0, "stays disabled");
    }
    let pos = drive.position;
    enable(&mut axis, &mut drive);
    assert_eq!(drive.position, pos, "re-enabled without a jump");
}

/// The drive quick-stops on its own (e.g. an input): the engine does not re-enable.
#[test]
fn drop_out_drops_the_enable_request() {
    let caps = drives::BLV_R;
    let pv = OperationMode::ProfileVelocity;
    let mut axis = Axis::new(caps, config(&caps, pv)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0237));
    fb.mode_display = Some(pv);
    fb.velocity = Some(0);
    axis.request_enable().unwrap();
    axis.step(&fb);
    fb.statusword = StatusWord::from_raw(0x0217);
    let out = axis.step(&fb);
    assert_eq!(Command::decode(out.controlword), Command::QuickStop);
    assert!(
        events(&mut axis)
            .iter()
            .any(|e| matches!(e, Event::PlannerFailed(PlannerError::LeftTarget { .. })))
    );
    fb.statusword = StatusWord::from_raw(0x0250);
    for _ in 0..20 {
        let out = axis.step(&fb);
        assert!(matches!(
            Command::decode(out.controlword),
            Command::QuickStop | Command::DisableVoltage
        ));
    }
}

#[test]
fn quick_stop_request() {
    let caps = drives::MR_J4_TM;
    let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CSP);
    let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
    enable(&mut axis, &mut drive);
    axis.request_quick_stop();
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(out.controlword.raw(), 0x0002);
    assert_eq!(drive.device.state(), State::QuickStopActive);
    cycle(&mut axis, &mut drive);
    assert_eq!(axis.status().phase, Phase::QuickStopped);
    for _ in 0..5 {
        cycle(&mut axis, &mut drive);
    }
    assert_eq!(drive.device.state(), State::SwitchOnDisabled);
    assert_eq!(axis.status().phase, Phase::QuickStopped);
    // Quick stop on a disabled drive is reported, not acted on.
    axis.request_disable();
    cycle(&mut axis, &mut drive);
    axis.request_quick_stop();
    cycle(&mut axis, &mut drive);
    assert!(matches!(
        axis.status().planner_error,
        Some(PlannerError::Unreachable { .. })
    ));
}

#[test]
fn event_queue_overflow_keeps_the_newest() {
    let mut axis = Axis::new(GENERIC, config(&GENERIC, CSP)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0250));
    fb.mode_display = Some(CSP);
    for i in 0..50 {
        fb.statusword.set(StatusWord::WARNING, i % 2 == 0);
        axis.step(&fb);
    }
    let st = axis.status();
    assert!(st.events_lost > 0);
    let evs = events(&mut axis);
    assert_eq!(evs.len(), 32);
    assert_eq!(evs.last(), Some(&Event::WarningChanged(false)));
}

#[test]
fn mode_display_mismatch_pauses_streaming() {
    let mut axis = Axis::new(GENERIC, config(&GENERIC, CSV)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0237));
    fb.mode_display = Some(CSV);
    fb.velocity = Some(0);
    axis.request_enable().unwrap();
    axis.step(&fb);
    axis.set_velocity(40).unwrap();
    axis.step(&fb);
    fb.mode_display = Some(OperationMode::Vendor(-7));
    let out = axis.step(&fb);
    assert_eq!(out.target_velocity, 40, "held, not jumped");
    assert!(!axis.status().streaming);
    assert!(axis.set_velocity(1).is_err());
    assert!(events(&mut axis).contains(&Event::ModeDisplayMismatch {
        expected: CSV,
        displayed: OperationMode::Vendor(-7)
    }));
}

// ----- properties ------------------------------------------------------------------------------

fn arb_feedback() -> impl Strategy<Value = Feedback> {
    (
        any::<u16>(),
        proptest::option::of(any::<i8>()),
        proptest::option::of(any::<i32>()),
        proptest::option::of(any::<i32>()),
        proptest::option::of(any::<i16>()),
        proptest::option::of(any::<u16>()),
        proptest::option::of(any::<bool>()),
    )
        .prop_map(|(sw, m, p, v, t, e, z)| Feedback {
            statusword: StatusWord::from_raw(sw),
            mode_display: m.map(OperationMode::from_i8),
            position: p,
            velocity: v,
            torque: t,
            error_code: e.map(ErrorCode),
            zero_speed: z,
        })
}

#[derive(Debug, Clone)]
enum Action {
    Nothing,
    Enable,
    Disable,
    QuickStop,
    FaultReset,
    Mode(i8),
    Position(i32),
    Velocity(i32),
    Torque(i16),
    FaultOn(u16),
    FaultOff,
}

fn arb_action() -> impl Strategy<Value = Action> {
    prop_oneof![
        6 => Just(Action::Nothing),
        2 => Just(Action::Enable),
        1 => Just(Action::Disable),
        1 => Just(Action::QuickStop),
        2 => Just(Action::FaultReset),
        1 => prop_oneof![Just(8i8), Just(9), Just(10), Just(1), Just(-101), any::<i8>()]
            .prop_map(Action::Mode),
        2 => (-1000i32..1000).prop_map(Action::Position),
        1 => (-100i32..100).prop_map(Action::Velocity),
        1 => (-100i16..100).prop_map(Action::Torque),
        1 => any::<u16>().prop_map(Action::FaultOn),
        1 => Just(Action::FaultOff),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    /// `step` never panics on any feedback and never energises a drive whose statusword shows a
    /// fault.
    #[test]
    fn step_never_panics(
        fbs in proptest::collection::vec(arb_feedback(), 1..150),
        actions in proptest::collection::vec(arb_action(), 150),
        caps_idx in 0..3usize,
    ) {
        let caps = [drives::MR_J4_TM, drives::BDHDE, GENERIC][caps_idx];
        let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
        for (fb, action) in fbs.iter().zip(actions) {
            apply_action(&mut axis, None, &action);
            let out = axis.step(fb);
            if fb.statusword.contains(StatusWord::FAULT) {
                prop_assert!(matches!(
                    Command::decode(out.controlword),
                    Command::DisableVoltage | Command::FaultReset
                ), "fault bit set but {:?}", Command::decode(out.controlword));
            }
            let _ = axis.status();
            while axis.poll_event().is_some() {}
        }
    }

    /// After a fault, the engine commands Enable operation only after an explicit fault reset
    /// and a later, accepted enable request; the simulated drive never re-enters Operation
    /// enabled otherwise.
    #[test]
    fn never_reenables_after_fault(
        actions in proptest::collection::vec(arb_action(), 1..400),
        caps_idx in 0..3usize,
        mode_lag in 0u32..4,
    ) {
        let caps = [drives::MR_J4_TM, drives::BDHDE, GENERIC][caps_idx];
        let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CSP);
        drive.mode_lag = mode_lag;
        let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
        let mut faulted = false;
        let mut reset_since_fault = false;
        let mut enable_since_reset = false;
        for action in actions {
            let accepted = apply_action(&mut axis, Some(&mut drive), &action);
            match action {
                Action::FaultReset if faulted && accepted => reset_since_fault = true,
                Action::Enable if reset_since_fault && accepted => enable_since_reset = true,
                _ => {}
            }
            let was = drive.device.state();
            let out = cycle(&mut axis, &mut drive);
            if axis.status().fault && !faulted {
                faulted = true;
                reset_since_fault = false;
                enable_since_reset = false;
            }
            if faulted && !axis.status().fault && reset_since_fault {
                // Fault cleared: from here a new fault starts a new round.
                faulted = false;
            }
            let energising = Command::decode(out.controlword) == Command::EnableOperation;
            if energising && (faulted || reset_since_fault) {
                prop_assert!(
                    enable_since_reset,
                    "Enable operation sent after a fault without reset + enable"
                );
            }
            let now = drive.device.state();
            if now == State::OperationEnabled && was != State::OperationEnabled
                && (faulted || reset_since_fault)
            {
                prop_assert!(enable_since_reset, "drive re-enabled after a fault");
            }
        }
    }
}

/// Apply an action; returns whether the engine accepted it (for requests that can fail).
fn apply_action(axis: &mut Axis, drive: Option<&mut SimServo>, action: &Action) -> bool {
    match action {
        Action::Nothing => true,
        Action::Enable => axis.request_enable().is_ok(),
        Action::Disable => {
            axis.request_disable();
            true
        }
        Action::QuickStop => {
            axis.request_quick_stop();
            true
        }
        Action::FaultReset => axis.request_fault_reset(),
        Action::Mode(m) => axis.request_mode(OperationMode::from_i8(*m)).is_ok(),
        Action::Position(d) => {
            let p = axis.status();
            let _ = p;
            axis.set_position(*d).is_ok()
        }
        Action::Velocity(v) => axis.set_velocity(*v).is_ok(),
        Action::Torque(t) => axis.set_torque(*t).is_ok(),
        Action::FaultOn(code) => {
            if let Some(d) = drive {
                d.fault = true;
                d.error_code = *code;
            }
            true
        }
        Action::FaultOff => {
            if let Some(d) = drive {
                d.fault = false;
            }
            true
        }
    }
}

/// A drive whose profile says csp starts on bit 4's edge gets bit 4 from the first streaming
/// cycle in csp (0 before: the edge); other drives never get it in csp.
#[test]
fn csp_start_edge_sets_bit_4_while_streaming() {
    for (edge, want) in [(true, true), (false, false)] {
        let caps = DriveCaps {
            csp_start_edge: edge,
            ..GENERIC
        };
        let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CSP);
        let mut axis = Axis::new(caps, config(&caps, CSP)).unwrap();
        axis.request_enable().expect("enable accepted");
        let (mut before, mut while_streaming) = (false, false);
        for _ in 0..60 {
            let out = cycle(&mut axis, &mut drive);
            let bit4 = out.controlword.contains(ControlWord::NEW_SET_POINT);
            if axis.status().streaming {
                while_streaming |= bit4;
            } else {
                before |= bit4;
            }
        }
        assert!(axis.status().streaming);
        assert!(!before, "bit 4 before streaming (edge {edge})");
        assert_eq!(while_streaming, want, "edge {edge}");
    }
}

/// cst → csp on the MR-J4-TM while the motor turns: a torque of 0 would only let it coast (the
/// generative test's case `cc daae7c29…`), so the engine brakes in csv first, then writes csp at
/// zero speed. The drive never refuses a mode write and never switches while moving.
#[test]
fn zero_speed_switch_from_turning_cst_brakes_in_csv() {
    let caps = drives::MR_J4_TM;
    let mut drive = SimServo::new(caps, State::SwitchOnDisabled, CST);
    let mut axis = Axis::new(caps, config(&caps, CST)).unwrap();
    enable(&mut axis, &mut drive);
    axis.set_torque(300).unwrap();
    for _ in 0..5 {
        cycle(&mut axis, &mut drive);
    }
    axis.set_torque(0).unwrap();
    cycle(&mut axis, &mut drive);
    assert!(drive.velocity > 0, "coasting: {}", drive.velocity);
    events(&mut axis);
    axis.request_mode(CSP).unwrap();
    let mut modes = Vec::new();
    for _ in 0..200 {
        let out = cycle(&mut axis, &mut drive);
        if modes.last() != Some(&out.mode) {
            modes.push(out.mode);
        }
        assert_eq!(axis.status().mode_switch_error, None);
        if axis.status().mode_switch == ModeSwitchPhase::Idle {
            break;
        }
        let phase = axis.status().mode_switch;
        assert!(
            phase == ModeSwitchPhase::Stopping { to: CSP }
                || phase == ModeSwitchPhase::Requested { to: CSP },
            "{phase:?}"
        );
    }
    assert_eq!(modes, [CSV, CSP]);
    assert_eq!(axis.status().active_mode, CSP);
    assert_eq!(drive.refused_mode_writes, 0);
    assert_eq!(drive.switched_while_moving, 0);
    assert_eq!(drive.velocity, 0);
    let velocities: Vec<i32> = drive
        .outputs
        .iter()
        .filter(|o| o.mode == CSV)
        .map(|o| o.target_velocity)
        .collect();
    assert!(
        velocities.windows(2).all(|w| w[1].abs() <= w[0].abs()),
        "the csv set-point only falls: {velocities:?}"
    );
    let ev = events(&mut axis);
    assert!(ev.contains(&Event::ModeSwitched { from: CSV, to: CSP }));
    let out = cycle(&mut axis, &mut drive);
    assert_eq!(
        out.target_position, drive.position,
        "csp starts where the axis is"
    );
}

/// Leaving pp for csp, every frame from the first that names csp carries the actual position
/// in 0x607A, not the pp target left there (a relative one, taken as a csp target, is a jump:
/// found over veth, where the BDHDE moved 8595 counts toward a relative −15 mm target before
/// the master's first csp set-point).
#[test]
fn entering_csp_from_pp_targets_the_actual_position() {
    let pp = OperationMode::ProfilePosition;
    let mut axis = Axis::new(GENERIC, config(&GENERIC, pp)).unwrap();
    let mut fb = Feedback::new(StatusWord::from_raw(0x0237));
    fb.mode_display = Some(pp);
    fb.position = Some(5000);
    fb.velocity = Some(0);
    axis.request_enable().unwrap();
    for _ in 0..5 {
        axis.step(&fb);
    }
    axis.set_position(-1_572_864).unwrap();
    assert_eq!(axis.step(&fb).target_position, -1_572_864);
    axis.request_mode(CSP).unwrap();
    for k in 0..3 {
        let out = axis.step(&fb);
        assert_eq!(out.mode, CSP);
        assert_eq!(out.target_position, 5000, "frame {k} of the switch");
    }
    fb.mode_display = Some(CSP);
    let out = axis.step(&fb);
    assert_eq!(axis.status().active_mode, CSP);
    assert_eq!(out.target_position, 5000, "the switch confirmed");
}
