//! The device-side state machine model against the transition tables of the manuals.

use crate::support::cia402_drives as drives;

use ecdrive_core::cia402::device::{
    Block, Device, DeviceConfig, DeviceInputs, Reaction, Transition,
};
use ecdrive_core::cia402::{Command, ControlWord, DriveCaps, QuickStopOption, State, StatusWord};

fn cfg(caps: &DriveCaps, qs: QuickStopOption) -> DeviceConfig {
    DeviceConfig::from_caps(caps, qs)
}

fn step(dev: &mut Device, cmd: Command) -> Reaction {
    dev.step(&DeviceInputs::new(cmd.controlword()))
}

fn transition(r: Reaction) -> (State, State, Option<u8>) {
    match r {
        Reaction::Transition(Transition { from, to, number }) => (from, to, number),
        other => panic!("expected a transition, got {other:?}"),
    }
}

/// CiA 402 / MR-J4-TM Table 5.1: each numbered transition from its start state.
#[test]
fn numbered_transitions_of_table_5_1() {
    use Command as C;
    use State::*;
    let plain = cfg(&DriveCaps::CIA402, QuickStopOption::QUICK_STOP_RAMP);
    let table: [(State, Command, State, u8); 13] = [
        (SwitchOnDisabled, C::Shutdown, ReadyToSwitchOn, 2),
        (ReadyToSwitchOn, C::SwitchOn, SwitchedOn, 3),
        (SwitchedOn, C::EnableOperation, OperationEnabled, 4),
        (OperationEnabled, C::DisableOperation, SwitchedOn, 5),
        (SwitchedOn, C::Shutdown, ReadyToSwitchOn, 6),
        (ReadyToSwitchOn, C::DisableVoltage, SwitchOnDisabled, 7),
        (ReadyToSwitchOn, C::QuickStop, SwitchOnDisabled, 7),
        (OperationEnabled, C::Shutdown, ReadyToSwitchOn, 8),
        (OperationEnabled, C::DisableVoltage, SwitchOnDisabled, 9),
        (SwitchedOn, C::DisableVoltage, SwitchOnDisabled, 10),
        (SwitchedOn, C::QuickStop, SwitchOnDisabled, 10),
        (OperationEnabled, C::QuickStop, QuickStopActive, 11),
        (QuickStopActive, C::DisableVoltage, SwitchOnDisabled, 12),
    ];
    for (from, cmd, to, n) in table {
        let mut d = Device::with_state(plain, from);
        assert_eq!(
            transition(step(&mut d, cmd)),
            (from, to, Some(n)),
            "{from} + {cmd}"
        );
        assert_eq!(d.statusword().state(), Some(to));
    }
}

/// Transitions 0, 1 (power-on, automatic), 13, 14 (fault), 15 (fault reset edge).
#[test]
fn automatic_and_fault_transitions() {
    let mut c = cfg(&DriveCaps::CIA402, QuickStopOption::QUICK_STOP_RAMP);
    c.init_cycles = 2;
    let mut d = Device::new(c);
    assert_eq!(d.state(), State::NotReadyToSwitchOn);
    assert_eq!(step(&mut d, Command::Shutdown), Reaction::Waiting);
    assert_eq!(step(&mut d, Command::Shutdown), Reaction::Waiting);
    assert_eq!(
        transition(step(&mut d, Command::Shutdown)),
        (State::NotReadyToSwitchOn, State::SwitchOnDisabled, Some(1))
    );

    // 13 from any non-fault state.
    for s in State::ALL.into_iter().filter(|s| !s.is_fault()) {
        let mut d = Device::with_state(c, s);
        let mut inp = DeviceInputs::new(Command::EnableOperation.controlword());
        inp.fault = true;
        assert_eq!(
            transition(d.step(&inp)),
            (s, State::FaultReactionActive, Some(13))
        );
    }

    // 14 once the fault reaction has finished.
    let mut d = Device::with_state(c, State::FaultReactionActive);
    let mut inp = DeviceInputs::new(ControlWord::empty());
    inp.fault = true;
    inp.motion_stopped = false;
    assert_eq!(d.step(&inp), Reaction::Waiting);
    inp.motion_stopped = true;
    assert_eq!(
        transition(d.step(&inp)),
        (State::FaultReactionActive, State::Fault, Some(14))
    );

    // 15 only on a rising edge of bit 7, and only once the fault is gone.
    assert_eq!(
        d.step(&DeviceInputs::new(ControlWord::empty())),
        Reaction::Hold
    );
    inp.controlword = Command::FaultReset.controlword();
    assert_eq!(d.step(&inp), Reaction::Blocked(Block::FaultPresent));
    // Held high: no new edge even though the fault is gone now.
    assert_eq!(step(&mut d, Command::FaultReset), Reaction::Hold);
    assert_eq!(step(&mut d, Command::DisableVoltage), Reaction::Hold);
    assert_eq!(
        transition(step(&mut d, Command::FaultReset)),
        (State::Fault, State::SwitchOnDisabled, Some(15))
    );
}

/// MR-J4-TM §5.1 state skipping: SOD + switch on → SO, SOD + enable → OE, RTSO + enable → OE.
#[test]
fn mr_j4_state_skipping() {
    let c = cfg(&drives::MR_J4_TM, QuickStopOption::QUICK_STOP_RAMP);
    let rows = [
        (
            State::SwitchOnDisabled,
            Command::SwitchOn,
            State::SwitchedOn,
        ),
        (
            State::SwitchOnDisabled,
            Command::EnableOperation,
            State::OperationEnabled,
        ),
        (
            State::ReadyToSwitchOn,
            Command::EnableOperation,
            State::OperationEnabled,
        ),
    ];
    for (from, cmd, to) in rows {
        let mut d = Device::with_state(c, from);
        assert_eq!(transition(step(&mut d, cmd)), (from, to, None));
    }
    // The same commands on a drive without skipping.
    let plain = cfg(&drives::BDHDE, QuickStopOption::DISABLE_DRIVE);
    let mut d = Device::with_state(plain, State::SwitchOnDisabled);
    assert_eq!(step(&mut d, Command::SwitchOn), Reaction::Ignored);
    assert_eq!(step(&mut d, Command::EnableOperation), Reaction::Ignored);
    // "Switch on + enable operation" from Ready to switch on: 3, then 4 (BLV-R §6 table).
    let mut d = Device::with_state(plain, State::ReadyToSwitchOn);
    assert_eq!(
        transition(step(&mut d, Command::EnableOperation)),
        (State::ReadyToSwitchOn, State::SwitchedOn, Some(3))
    );
    assert_eq!(
        transition(step(&mut d, Command::EnableOperation)),
        (State::SwitchedOn, State::OperationEnabled, Some(4))
    );
}

/// MR-J4-TM: quick-stop code 2 decelerates, then Switch on disabled (12a); no transition 16.
#[test]
fn mr_j4_quick_stop_ends_in_switch_on_disabled() {
    let c = cfg(&drives::MR_J4_TM, QuickStopOption::QUICK_STOP_RAMP);
    let mut d = Device::with_state(c, State::OperationEnabled);
    assert_eq!(
        transition(step(&mut d, Command::QuickStop)),
        (State::OperationEnabled, State::QuickStopActive, Some(11))
    );
    let mut moving = DeviceInputs::new(Command::EnableOperation.controlword());
    moving.motion_stopped = false;
    // Enable operation during the ramp does not bring it back (no transition 16).
    assert_eq!(d.step(&moving), Reaction::Waiting);
    assert_eq!(d.state(), State::QuickStopActive);
    moving.motion_stopped = true;
    assert_eq!(
        transition(d.step(&moving)),
        (State::QuickStopActive, State::SwitchOnDisabled, Some(12))
    );
}

/// BDHDE default 0x605A = 0: disable drive — Quick stop active for one step, then Switch on
/// disabled without waiting for the motor.
#[test]
fn bdhde_quick_stop_code_0_disables_at_once() {
    let c = cfg(&drives::BDHDE, QuickStopOption::DISABLE_DRIVE);
    let mut d = Device::with_state(c, State::OperationEnabled);
    step(&mut d, Command::QuickStop);
    let mut inp = DeviceInputs::new(Command::QuickStop.controlword());
    inp.motion_stopped = false;
    assert_eq!(
        transition(d.step(&inp)),
        (State::QuickStopActive, State::SwitchOnDisabled, Some(12))
    );
}

/// BDHDE 0x605A = 6 with transition 16; BLV-R 6 without it (§6.2: "not supported").
#[test]
fn stay_codes_and_transition_16() {
    let bd = cfg(&drives::BDHDE, QuickStopOption::QUICK_STOP_RAMP_STAY);
    let mut d = Device::with_state(bd, State::QuickStopActive);
    assert_eq!(step(&mut d, Command::QuickStop), Reaction::Hold);
    assert_eq!(
        transition(step(&mut d, Command::EnableOperation)),
        (State::QuickStopActive, State::OperationEnabled, Some(16))
    );

    let blv = cfg(&drives::BLV_R, QuickStopOption::QUICK_STOP_RAMP_STAY);
    let mut d = Device::with_state(blv, State::QuickStopActive);
    assert_eq!(step(&mut d, Command::EnableOperation), Reaction::Ignored);
    assert_eq!(step(&mut d, Command::Shutdown), Reaction::Ignored);
    assert_eq!(d.state(), State::QuickStopActive);
    assert_eq!(
        transition(step(&mut d, Command::DisableVoltage)),
        (State::QuickStopActive, State::SwitchOnDisabled, Some(12))
    );
}

/// BLV-R vendor codes −3…−1 stay in Quick stop active; 0, 1, 2 end in Switch on disabled.
#[test]
fn blv_r_quick_stop_codes() {
    for code in [-3i16, -2, -1, 0, 1, 2, 5, 6] {
        let qs = drives::BLV_R.quick_stop_option(code).expect("listed code");
        let mut d = Device::with_state(cfg(&drives::BLV_R, qs), State::OperationEnabled);
        step(&mut d, Command::QuickStop);
        assert_eq!(d.state(), State::QuickStopActive);
        for _ in 0..3 {
            step(&mut d, Command::QuickStop);
        }
        let expected = if !(0..5).contains(&code) {
            State::QuickStopActive
        } else {
            State::SwitchOnDisabled
        };
        assert_eq!(d.state(), expected, "0x605A = {code}");
    }
    assert!(drives::BLV_R.quick_stop_option(3).is_none());
    assert!(drives::BLV_R.quick_stop_option(7).is_none());
    assert!(drives::MR_J4_TM.quick_stop_option(1).is_none());
    assert!(drives::MR_J4_TM.quick_stop_option(2).is_some());
}

/// BLV-R §6.1: with remote = 0 only quick stop and fault reset act.
#[test]
fn remote_bit_gates_the_controlword() {
    let c = cfg(&drives::BLV_R, QuickStopOption::QUICK_STOP_RAMP);
    let mut d = Device::with_state(c, State::SwitchOnDisabled);
    let mut inp = DeviceInputs::new(Command::Shutdown.controlword());
    inp.remote = false;
    assert_eq!(d.step(&inp), Reaction::Blocked(Block::NotRemote));
    assert!(!d.statusword().contains(StatusWord::REMOTE));
    let mut d = Device::with_state(c, State::OperationEnabled);
    inp.controlword = Command::DisableVoltage.controlword();
    assert_eq!(d.step(&inp), Reaction::Blocked(Block::NotRemote));
    inp.controlword = Command::QuickStop.controlword();
    assert_eq!(
        transition(d.step(&inp)),
        (State::OperationEnabled, State::QuickStopActive, Some(11))
    );
    // A drive that does not gate ignores the bit.
    let mut d = Device::with_state(
        cfg(&drives::MR_J4_TM, QuickStopOption::QUICK_STOP_RAMP),
        State::SwitchOnDisabled,
    );
    inp.controlword = Command::Shutdown.controlword();
    assert!(matches!(d.step(&inp), Reaction::Transition(_)));
}

/// BDHDE §5.4 note: without bus voltage no 3 → 4; MR-J4 8(b): main power off in Operation
/// enabled → Ready to switch on.
#[test]
fn main_power() {
    let c = cfg(&drives::BDHDE, QuickStopOption::DISABLE_DRIVE);
    let mut d = Device::with_state(c, State::SwitchOnDisabled);
    let mut inp = DeviceInputs::new(Command::Shutdown.controlword());
    inp.main_power = false;
    assert_eq!(d.step(&inp), Reaction::Blocked(Block::NoMainPower));
    assert!(!d.statusword().contains(StatusWord::VOLTAGE_ENABLED));
    let mut d = Device::with_state(c, State::OperationEnabled);
    inp.controlword = Command::EnableOperation.controlword();
    assert_eq!(
        transition(d.step(&inp)),
        (State::OperationEnabled, State::ReadyToSwitchOn, Some(8))
    );
}

/// Commands that a state does not accept are reported as ignored; hold commands as hold.
#[test]
fn hold_and_ignored() {
    let c = cfg(&DriveCaps::CIA402, QuickStopOption::QUICK_STOP_RAMP);
    let holds = [
        (State::SwitchOnDisabled, Command::DisableVoltage),
        (State::SwitchOnDisabled, Command::QuickStop),
        (State::ReadyToSwitchOn, Command::Shutdown),
        (State::SwitchedOn, Command::SwitchOn),
        (State::OperationEnabled, Command::EnableOperation),
        (State::OperationEnabled, Command::FaultReset),
        (State::Fault, Command::EnableOperation),
    ];
    for (s, cmd) in holds {
        let mut d = Device::with_state(c, s);
        assert_eq!(step(&mut d, cmd), Reaction::Hold, "{s} + {cmd}");
        assert_eq!(d.state(), s);
    }
}

/// Every (state, controlword) pair steps without panic and yields a decodable statusword.
#[test]
fn every_state_and_controlword() {
    for qs in QuickStopOption::STANDARD {
        for skipping in [false, true] {
            let mut c = cfg(&DriveCaps::CIA402, qs);
            c.state_skipping = skipping;
            for s in State::ALL {
                for raw in (0u32..=0xFFFF).step_by(7) {
                    let mut d = Device::with_state(c, s);
                    d.step(&DeviceInputs::new(ControlWord::from_raw(raw as u16)));
                    assert_eq!(d.statusword().state(), Some(d.state()));
                }
            }
        }
    }
}
