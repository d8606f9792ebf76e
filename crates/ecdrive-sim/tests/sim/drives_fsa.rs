//! CiA 402 state-machine conformance of both emulated drives, through the process data on the
//! wire: every transition each drive supports, the ones it refuses, the MR-J4-TM's state
//! skipping, the quick-stop options, the fault reaction and reset with their EMCYs, the remote
//! bit and main power, and the EtherCAT-state rules (commands only in OP, leaving OP).

use crate::support::wire;

use ecdrive_core::cia402::State::{self, *};
use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use wire::{Wire, cyclic};

const SHUTDOWN: u16 = 0x0006;
const SWITCH_ON: u16 = 0x0007;
const ENABLE: u16 = 0x000F;
const DISABLE_VOLTAGE: u16 = 0x0000;
const QUICK_STOP: u16 = 0x0002;
const FAULT_RESET: u16 = 0x0080;

const MR: &DriveProfile = &mr_j4_tm::PROFILE;
const BD: &DriveProfile = &bdhde::PROFILE;

fn st(sw: u16) -> State {
    State::from_statusword(sw).unwrap()
}

/// A drive in OP (csp, DC 1 ms), commanded to `path` and checked at every step.
fn walk(w: &mut Wire, path: &[(u16, State)]) {
    for &(cw, want) in path {
        let sw = w.command(0, cw);
        assert_eq!(
            st(sw),
            want,
            "after controlword 0x{cw:04X}: statusword 0x{sw:04X}"
        );
    }
}

fn op(p: &DriveProfile) -> Wire {
    let mut w = Wire::op_cyclic(&[p], 1_000_000);
    // csp: the target follows the actual position so that enabling does not move the motor.
    cyclic::set_mode(w.outputs_mut(0), 8);
    w.cycle();
    w.cycle();
    w
}

/// Transitions 2–10 of the standard table, on both drives (each path starts in Switch on
/// disabled).
#[test]
fn standard_transitions() {
    for p in [MR, BD] {
        let mut w = op(p);
        assert_eq!(
            w.state(0),
            SwitchOnDisabled,
            "{}: transition 1 after power-on",
            p.name
        );
        let sw = cyclic::sw(w.inputs(0));
        assert_eq!(
            sw & 0x0210,
            0x0210,
            "{}: voltage enabled and remote",
            p.name
        );
        walk(
            &mut w,
            &[
                (SHUTDOWN, ReadyToSwitchOn),         // 2
                (SWITCH_ON, SwitchedOn),             // 3
                (ENABLE, OperationEnabled),          // 4
                (SWITCH_ON, SwitchedOn),             // 5
                (SHUTDOWN, ReadyToSwitchOn),         // 6
                (DISABLE_VOLTAGE, SwitchOnDisabled), // 7
                (SHUTDOWN, ReadyToSwitchOn),
                (QUICK_STOP, SwitchOnDisabled), // 7 by quick stop
                (SHUTDOWN, ReadyToSwitchOn),
                (SWITCH_ON, SwitchedOn),
                (ENABLE, OperationEnabled),
                (SHUTDOWN, ReadyToSwitchOn), // 8
                (SWITCH_ON, SwitchedOn),
                (ENABLE, OperationEnabled),
                (DISABLE_VOLTAGE, SwitchOnDisabled), // 9
                (SHUTDOWN, ReadyToSwitchOn),
                (SWITCH_ON, SwitchedOn),
                (DISABLE_VOLTAGE, SwitchOnDisabled), // 10
                (SHUTDOWN, ReadyToSwitchOn),
                (SWITCH_ON, SwitchedOn),
                (QUICK_STOP, SwitchOnDisabled), // 10 by quick stop
            ],
        );
        // Holding commands keep their state.
        walk(
            &mut w,
            &[
                (DISABLE_VOLTAGE, SwitchOnDisabled),
                (SHUTDOWN, ReadyToSwitchOn),
                (SHUTDOWN, ReadyToSwitchOn),
            ],
        );
        // In Operation enabled in csp the drive follows the target (statusword bit 12).
        walk(
            &mut w,
            &[(SWITCH_ON, SwitchedOn), (ENABLE, OperationEnabled)],
        );
        assert_ne!(cyclic::sw(w.inputs(0)) & 0x1000, 0, "{}: bit 12", p.name);
        assert_eq!(cyclic::mode(w.inputs(0)), 8);
    }
}

/// MR-J4-TM §5.1: Switch on and Enable operation from Switch on disabled, and Enable operation
/// from Ready to switch on, jump; the BDHDE does not skip (Switch on / Enable operation in
/// Switch on disabled are ignored; Enable operation in Ready to switch on is 3 then 4).
#[test]
fn state_skipping() {
    assert!(MR.caps.state_skipping && !BD.caps.state_skipping);
    let mut w = op(MR);
    walk(
        &mut w,
        &[
            (SWITCH_ON, SwitchedOn),
            (DISABLE_VOLTAGE, SwitchOnDisabled),
            (ENABLE, OperationEnabled),
            (SHUTDOWN, ReadyToSwitchOn),
            (ENABLE, OperationEnabled),
        ],
    );
    let mut w = op(BD);
    walk(
        &mut w,
        &[
            (SWITCH_ON, SwitchOnDisabled),
            (ENABLE, SwitchOnDisabled),
            (SHUTDOWN, ReadyToSwitchOn),
        ],
    );
    // Ready to switch on + Enable operation: Switched on at the first SYNC0, Operation enabled
    // at the next.
    cyclic::set_cw(w.outputs_mut(0), ENABLE);
    w.cycle();
    w.cycle();
    assert_eq!(w.state(0), SwitchedOn);
    w.cycle();
    assert_eq!(w.state(0), OperationEnabled);
}

/// Moving at a constant speed in csv, then a quick stop.
fn moving_then_quick_stop(w: &mut Wire, velocity: i32) -> Vec<State> {
    cyclic::set_mode(w.outputs_mut(0), 9);
    walk(
        w,
        &[
            (SHUTDOWN, ReadyToSwitchOn),
            (SWITCH_ON, SwitchedOn),
            (ENABLE, OperationEnabled),
        ],
    );
    cyclic::set_velocity(w.outputs_mut(0), velocity);
    for _ in 0..100 {
        w.cycle();
    }
    assert!(w.drive(0).speed_rev_s() > 10.0, "moving");
    cyclic::set_cw(w.outputs_mut(0), QUICK_STOP);
    let mut states = Vec::new();
    for _ in 0..400 {
        w.cycle();
        states.push(w.state(0));
    }
    states
}

/// MR-J4-TM quick stop, option 2 only: ramp on 0x6085 (100 ms from the rated speed), then
/// Switch on disabled on its own (transition 12); no transition 16; in cst the power stage
/// goes off at once (dynamic brake).
#[test]
fn mr_j4_quick_stop() {
    let mut w = op(MR);
    // 20 rev/s = 1200 r/min = 120000 × 0.01 r/min.
    let states = moving_then_quick_stop(&mut w, 120_000);
    let qs = states.iter().filter(|s| **s == QuickStopActive).count();
    // 1200 r/min at 3000 r/min per 100 ms: 40 ms of ramp, then Switch on disabled for good.
    assert!((35..=45).contains(&qs), "{qs} cycles in Quick stop active");
    assert_eq!(
        states[0], OperationEnabled,
        "the frame before the quick stop acted"
    );
    assert!(states[1..=qs].iter().all(|s| *s == QuickStopActive));
    assert!(states[qs + 1..].iter().all(|s| *s == SwitchOnDisabled));
    assert!(w.drive(0).speed_rev_s().abs() < 1.0);
    // Transition 16 does not exist: Enable operation in Quick stop active is ignored.
    let mut w = op(MR);
    cyclic::set_mode(w.outputs_mut(0), 9);
    walk(&mut w, &[(ENABLE, OperationEnabled)]);
    cyclic::set_velocity(w.outputs_mut(0), 120_000);
    for _ in 0..100 {
        w.cycle();
    }
    cyclic::set_cw(w.outputs_mut(0), QUICK_STOP);
    w.cycle();
    w.cycle();
    assert_eq!(w.state(0), QuickStopActive);
    cyclic::set_cw(w.outputs_mut(0), ENABLE);
    for _ in 0..5 {
        w.cycle();
        assert_eq!(w.state(0), QuickStopActive, "no transition 16");
    }
    // cst: the quick stop disables at once.
    let mut w = op(MR);
    cyclic::set_mode(w.outputs_mut(0), 10);
    walk(&mut w, &[(ENABLE, OperationEnabled)]);
    cyclic::set_torque(w.outputs_mut(0), 500);
    for _ in 0..50 {
        w.cycle();
    }
    assert!(w.drive(0).speed_rev_s() > 1.0);
    cyclic::set_cw(w.outputs_mut(0), QUICK_STOP);
    let mut seen = Vec::new();
    for _ in 0..4 {
        w.cycle();
        seen.push(w.state(0));
    }
    assert!(seen.contains(&SwitchOnDisabled), "{seen:?}");
    assert!(
        seen.iter().filter(|s| **s == QuickStopActive).count() <= 1,
        "{seen:?}"
    );
}

/// BDHDE quick-stop option codes (§9 605Ah): 0 disables at once (the motor coasts), 2 ramps on
/// 0x6085 and ends in Switch on disabled, 6 ramps and stays in Quick stop active, from where
/// Enable operation returns to Operation enabled (transition 16) and Disable voltage leaves
/// (transition 12).
#[test]
fn bdhde_quick_stop_options() {
    let rev = 1 << 20;
    for code in [0u16, 2, 6] {
        let mut w = op(BD);
        // The start-up wrote 2; the option is changed by SDO (not mapped).
        w.write_u16(0, 0x605A, 0, code).unwrap();
        let states = moving_then_quick_stop(&mut w, 20 * rev);
        let qs = states.iter().filter(|s| **s == QuickStopActive).count();
        match code {
            0 => {
                // Quick stop active for one cycle, then the power stage is off.
                assert_eq!(qs, 1, "code 0");
                assert_eq!(states.last(), Some(&SwitchOnDisabled));
            }
            2 => {
                // 20 rev/s at 1000 rev/s² (start-up 0x6085): 20 ms.
                assert!((18..=22).contains(&qs), "code 2: {qs}");
                assert_eq!(states.last(), Some(&SwitchOnDisabled));
            }
            _ => {
                assert!(states[1..].iter().all(|s| *s == QuickStopActive), "code 6");
                assert!(w.drive(0).speed_rev_s().abs() < 0.5, "stopped");
                walk(
                    &mut w,
                    &[(ENABLE, OperationEnabled), (QUICK_STOP, QuickStopActive)],
                );
                walk(&mut w, &[(DISABLE_VOLTAGE, SwitchOnDisabled)]);
            }
        }
    }
}

/// Fault reaction and reset, with the EMCYs and error objects of each drive.
#[test]
fn faults_and_reset() {
    // MR-J4-TM: AL.10 → 0xFF10, 0x2A41 = 0x00100001, 0x1001 bit 0; 0x603F keeps the latest
    // alarm after the reset.
    let mut w = op(MR);
    walk(&mut w, &[(ENABLE, OperationEnabled)]);
    w.drive(0).raise_alarm("AL.10").unwrap();
    let mut seen = Vec::new();
    for _ in 0..4 {
        w.cycle();
        seen.push(w.state(0));
    }
    // Transition 13 at the next SYNC0, 14 at the one after (the power stage is off at once).
    assert_eq!(seen, [OperationEnabled, FaultReactionActive, Fault, Fault]);
    assert_eq!(cyclic::error_code(w.inputs(0)), 0xFF10);
    assert_eq!(w.read_u32(0, 0x2A41, 0), 0x0010_0001);
    assert_eq!(w.read_u32(0, 0x1001, 0), 1);
    assert_eq!(w.read_u32(0, 0x1003, 1), 0xFF10);
    w.drain(0);
    let e = w.emergencies.pop().unwrap().1;
    assert_eq!(e.error_code, 0xFF10);
    assert_eq!(e.error_register, 1);
    assert_eq!(
        e.data,
        [0x01, 0x00, 0x10, 0x00, 0x00],
        "0x2A41 little-endian"
    );
    assert_eq!(MR.describe_error(e.error_code).name, "AL.10");
    // Commands other than a reset edge do nothing in Fault.
    walk(&mut w, &[(ENABLE, Fault), (SHUTDOWN, Fault)]);
    walk(&mut w, &[(FAULT_RESET, SwitchOnDisabled)]);
    assert_eq!(w.read_u32(0, 0x2A41, 0), 0);
    assert_eq!(w.read_u32(0, 0x1001, 0), 0);
    assert_eq!(
        cyclic::error_code(w.inputs(0)),
        0xFF10,
        "latest error since power-on"
    );
    w.drain(0);
    assert_eq!(w.emergencies.pop().unwrap().1.error_code, 0, "reset EMCY");
    // A held bit 7 is not a new edge; an alarm fault reset cannot clear stays.
    w.drive(0).raise_alarm("AL.37").unwrap();
    w.cycle();
    w.cycle();
    w.cycle();
    assert_eq!(w.state(0), Fault);
    walk(
        &mut w,
        &[
            (FAULT_RESET, Fault),
            (DISABLE_VOLTAGE, Fault),
            (FAULT_RESET, Fault),
        ],
    );
    assert!(w.drive(0).alarm().is_some());

    // BDHDE: J3 → 0x8689, cleared by the reset.
    let mut w = op(BD);
    walk(
        &mut w,
        &[
            (SHUTDOWN, ReadyToSwitchOn),
            (SWITCH_ON, SwitchedOn),
            (ENABLE, OperationEnabled),
        ],
    );
    w.drive(0).raise_alarm("J3").unwrap();
    let mut seen = Vec::new();
    for _ in 0..4 {
        w.cycle();
        seen.push(w.state(0));
    }
    assert_eq!(seen, [OperationEnabled, FaultReactionActive, Fault, Fault]);
    assert_eq!(cyclic::error_code(w.inputs(0)), 0x8689);
    let d = BD.describe_error(0x8689);
    assert_eq!(d.name, "J3 (FLT 87)");
    w.drain(0);
    let e = w.emergencies.pop().unwrap().1;
    assert_eq!((e.error_code, e.data), (0x8689, [0; 5]));
    walk(
        &mut w,
        &[(DISABLE_VOLTAGE, Fault), (FAULT_RESET, SwitchOnDisabled)],
    );
    assert_eq!(cyclic::error_code(w.inputs(0)), 0);
}

/// The BDHDE acts on the controlword only with statusword bit 9 (COMMmode 1); quick stop still
/// acts. Without bus voltage neither drive leaves Switch on disabled; losing it in Operation
/// enabled is transition 8.
#[test]
fn remote_and_main_power() {
    let mut w = op(BD);
    w.drive(0).set_remote(false);
    let sw = w.command(0, SHUTDOWN);
    assert_eq!(sw & 0x0200, 0, "remote bit off");
    assert_eq!(st(sw), SwitchOnDisabled);
    w.drive(0).set_remote(true);
    walk(
        &mut w,
        &[(SHUTDOWN, ReadyToSwitchOn), (SWITCH_ON, SwitchedOn)],
    );
    w.drive(0).set_remote(false);
    walk(&mut w, &[(QUICK_STOP, SwitchOnDisabled)]);
    for p in [MR, BD] {
        let mut w = op(p);
        w.drive(0).set_main_power(false);
        let sw = w.command(0, SHUTDOWN);
        assert_eq!(sw & 0x0010, 0, "{}: voltage enabled off", p.name);
        assert_eq!(st(sw), SwitchOnDisabled, "{}", p.name);
        w.drive(0).set_main_power(true);
        walk(
            &mut w,
            &[
                (SHUTDOWN, ReadyToSwitchOn),
                (SWITCH_ON, SwitchedOn),
                (ENABLE, OperationEnabled),
            ],
        );
        w.drive(0).set_main_power(false);
        w.cycle();
        w.cycle();
        assert_eq!(w.state(0), ReadyToSwitchOn, "{}: transition 8", p.name);
    }
}

/// Commands act only in OP; leaving OP with the motor energised is a fault of its own (MR-J4-TM
/// [AL. 86.1], BDHDE 0xF080), without it the drive just returns to Switch on disabled.
#[test]
fn commands_only_in_op_and_leaving_op() {
    for (p, code) in [(MR, 0xFF86u16), (BD, 0xF080)] {
        let mut w = op(p);
        walk(
            &mut w,
            &[(SHUTDOWN, ReadyToSwitchOn), (SWITCH_ON, SwitchedOn)],
        );
        // OP → SAFE-OP: the outputs are no longer valid; the drive is in Switch on disabled and
        // ignores the controlword.
        assert_eq!(w.request(0, 0x0004), (0x0004, 0));
        assert_eq!(w.command(0, ENABLE), w.command(0, ENABLE));
        assert_eq!(w.state(0), SwitchOnDisabled, "{}", p.name);
        assert!(
            w.drive(0).alarm().is_none(),
            "{}: not energised, no fault",
            p.name
        );
        // Back in OP and enabled, then OP is left.
        assert_eq!(w.request(0, 0x0008), (0x0008, 0));
        walk(
            &mut w,
            &[
                (SHUTDOWN, ReadyToSwitchOn),
                (SWITCH_ON, SwitchedOn),
                (ENABLE, OperationEnabled),
            ],
        );
        assert_eq!(w.request(0, 0x0004), (0x0004, 0));
        w.cycle();
        w.cycle();
        assert_eq!(w.state(0), Fault, "{}", p.name);
        assert_eq!(cyclic::error_code(w.inputs(0)), code, "{}", p.name);
        w.drain(0);
        assert!(w.emergencies.iter().any(|(_, e)| e.error_code == code));
        // Reset in OP.
        assert_eq!(w.request(0, 0x0008), (0x0008, 0));
        walk(
            &mut w,
            &[(DISABLE_VOLTAGE, Fault), (FAULT_RESET, SwitchOnDisabled)],
        );
    }
}
