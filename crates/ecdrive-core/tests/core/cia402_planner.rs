//! The transition planner: unit tests on the manuals' sequences, and property tests against the
//! device-side reference model (`cia402::device`).

use crate::support::cia402_drives as drives;
use crate::support::cia402_sim as sim;

use std::time::Duration;

use ecdrive_core::cia402::device::{DeviceConfig, Reaction, Transition};
use ecdrive_core::cia402::{
    Command, DriveCaps, Planner, PlannerConfig, PlannerConfigError, PlannerError, Progress,
    QuickStopEnd, QuickStopOption, StallCause, State, StatusWord, StopRamp, Target,
};
use proptest::prelude::*;
use sim::SimDrive;

fn planner(caps: &DriveCaps, qs: i16, timeout: u32, hold: u32) -> Planner {
    Planner::new(
        caps,
        PlannerConfig {
            timeout_cycles: timeout,
            fault_reset_hold_cycles: hold,
            quick_stop_option: qs,
        },
    )
    .expect("valid config")
}

/// Run planner and simulated drive until the planner reports something other than
/// InProgress or `max` cycles pass. Returns the commands sent and the final progress.
fn run(p: &mut Planner, d: &mut SimDrive, max: usize) -> (Vec<u16>, Progress) {
    let mut sent = Vec::new();
    for _ in 0..max {
        let step = p.next(d.seen(), d.standstill());
        if step.progress != Progress::InProgress {
            return (sent, step.progress);
        }
        sent.push(step.controlword().raw());
        d.apply(step.controlword());
    }
    (sent, Progress::InProgress)
}

fn sw(state: State) -> StatusWord {
    StatusWord::from_raw(state.statusword_bits() | 0x0210)
}

// ----- sequences from the manuals --------------------------------------------------------------

fn e_statusword(e: &PlannerError) -> u16 {
    match e {
        PlannerError::Timeout { statusword, .. } => *statusword,
        other => panic!("{other:?}"),
    }
}

/// The MR-J4-TM accepts state skipping (Enable operation straight from Switch on disabled),
/// but the planner walks the standard transitions on it too: a drive that only has those must
/// enable, and the two saved cycles are not worth depending on optional behaviour.
#[test]
fn mr_j4_enables_with_the_standard_sequence_too() {
    let caps = drives::MR_J4_TM;
    let mut p = planner(&caps, 2, 100, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP),
        State::SwitchOnDisabled,
        0,
        0,
    );
    p.set_target(Target::OperationEnabled);
    let (sent, progress) = run(&mut p, &mut d, 10);
    assert_eq!(sent, vec![0x0006, 0x0007, 0x000F]);
    assert_eq!(progress, Progress::Reached);
    assert_eq!(d.device.state(), State::OperationEnabled);
}

/// BDHDE (no skipping): Shutdown, Switch on, Enable operation.
#[test]
fn bdhde_enables_with_the_standard_sequence() {
    let caps = drives::BDHDE;
    let mut p = planner(&caps, 0, 100, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::DISABLE_DRIVE),
        State::SwitchOnDisabled,
        0,
        0,
    );
    p.set_target(Target::OperationEnabled);
    let (sent, progress) = run(&mut p, &mut d, 10);
    assert_eq!(sent, vec![0x0006, 0x0007, 0x000F]);
    assert_eq!(progress, Progress::Reached);
    // Disable operation back to Switched on (transition 5), then Switch on disabled.
    p.set_target(Target::SwitchedOn);
    assert_eq!(run(&mut p, &mut d, 10), (vec![0x0007], Progress::Reached));
    p.set_target(Target::SwitchOnDisabled);
    assert_eq!(run(&mut p, &mut d, 10), (vec![0x0000], Progress::Reached));
}

/// BLV-R with 0x605A = 6 (stay) and no transition 16: after standstill the planner leaves Quick
/// stop active through Switch on disabled.
#[test]
fn blv_r_leaves_quick_stop_through_switch_on_disabled() {
    let caps = drives::BLV_R;
    let mut p = planner(&caps, 6, 100, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP_STAY),
        State::QuickStopActive,
        0,
        3,
    );
    p.set_target(Target::OperationEnabled);
    let (sent, progress) = run(&mut p, &mut d, 20);
    // Quick stop held while the motor still turns, then disable voltage, then 6/7/F.
    assert_eq!(
        sent,
        vec![0x0002, 0x0002, 0x0002, 0x0000, 0x0006, 0x0007, 0x000F]
    );
    assert_eq!(progress, Progress::Reached);
}

/// BDHDE with 0x605A = 6 has transition 16: Enable operation from Quick stop active.
#[test]
fn bdhde_uses_transition_16() {
    let caps = drives::BDHDE;
    let mut p = planner(&caps, 6, 100, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP_STAY),
        State::QuickStopActive,
        0,
        0,
    );
    p.set_target(Target::OperationEnabled);
    assert_eq!(run(&mut p, &mut d, 10), (vec![0x000F], Progress::Reached));
}

/// Quick stop from Operation enabled; from Switch on disabled it is unreachable.
#[test]
fn quick_stop_target() {
    let caps = drives::MR_J4_TM;
    let mut p = planner(&caps, 2, 100, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP),
        State::OperationEnabled,
        0,
        5,
    );
    p.set_target(Target::QuickStop);
    assert_eq!(run(&mut p, &mut d, 10), (vec![0x0002], Progress::Reached));
    // The drive ends in Switch on disabled after its ramp (code 2); still reached.
    for _ in 0..10 {
        let s = p.next(d.seen(), d.standstill());
        assert_eq!(s.progress, Progress::Reached);
        assert_eq!(s.command, Command::QuickStop);
        d.apply(s.controlword());
    }
    assert_eq!(d.device.state(), State::SwitchOnDisabled);

    let mut p = planner(&caps, 2, 100, 10);
    p.set_target(Target::QuickStop);
    let s = p.next(sw(State::SwitchOnDisabled), true);
    let Progress::Failed(e) = s.progress else {
        panic!("expected failure, got {:?}", s.progress)
    };
    assert!(matches!(
        e,
        PlannerError::Unreachable {
            from: State::SwitchOnDisabled,
            target: Target::QuickStop,
            ..
        }
    ));
    assert_eq!(
        e.to_string(),
        "Quick stop cannot be reached from Switch on disabled: the drive is disabled: there is \
         no motion to stop"
    );
    assert_eq!(s.command, Command::DisableVoltage);
}

// ----- fault reset -----------------------------------------------------------------------------

/// Bit 7: one cycle low, `hold` cycles high, `hold` low, repeated while the fault persists.
#[test]
fn fault_reset_pulse_shape() {
    let mut p = planner(&DriveCaps::CIA402, 2, 1000, 3);
    p.set_target(Target::SwitchOnDisabled);
    let fault = sw(State::Fault);
    let s = p.next(fault, true);
    assert_eq!(s.command, Command::DisableVoltage);
    assert!(matches!(
        s.progress,
        Progress::Failed(PlannerError::Faulted { .. })
    ));
    p.request_fault_reset();
    let cws: Vec<u16> = (0..11)
        .map(|_| p.next(fault, true).controlword().raw())
        .collect();
    assert_eq!(
        cws,
        vec![
            0x00, 0x80, 0x80, 0x80, 0x00, 0x00, 0x00, 0x80, 0x80, 0x80, 0x00
        ]
    );
    // The drive leaves Fault: the reset request ends, the target is reached.
    let s = p.next(sw(State::SwitchOnDisabled), true);
    assert_eq!(
        (s.command, s.progress),
        (Command::DisableVoltage, Progress::Reached)
    );
    assert!(!p.fault_reset_pending());
}

/// A persistent fault: re-pulse until the timeout, then report it and stop pulsing.
#[test]
fn persistent_fault_times_out() {
    let caps = drives::MR_J4_TM;
    let mut p = planner(&caps, 2, 40, 3);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP),
        State::Fault,
        1,
        0,
    );
    d.fault = true;
    p.set_target(Target::SwitchOnDisabled);
    assert!(!p.request_fault_reset(), "no fault seen yet: ignored");
    let s = p.next(d.seen(), true);
    d.apply(s.controlword());
    assert!(p.request_fault_reset());
    let (sent, progress) = run(&mut p, &mut d, 100);
    let edges = sent
        .windows(2)
        .filter(|w| w[0] & 0x80 == 0 && w[1] & 0x80 != 0)
        .count();
    assert!(edges >= 5, "re-pulses while the fault persists: {edges}");
    let Progress::Failed(e) = progress else {
        panic!("{progress:?}")
    };
    assert!(matches!(
        e,
        PlannerError::Timeout {
            stuck_in: State::Fault,
            cause: StallCause::FaultPersists,
            ..
        }
    ));
    assert!(
        e.to_string()
            .starts_with("drive stuck in Fault for 40 cycles")
    );
    // Latched: no more edges.
    for _ in 0..10 {
        assert_eq!(p.next(d.seen(), true).command, Command::DisableVoltage);
    }
    // A new request is a new attempt; this time the fault is gone.
    d.fault = false;
    assert!(p.request_fault_reset());
    assert_eq!(run(&mut p, &mut d, 20).1, Progress::Reached);
    assert_eq!(d.device.state(), State::SwitchOnDisabled);
}

/// A fault while enabling cancels the enable target; after the reset the drive stays disabled.
#[test]
fn fault_cancels_enable() {
    let caps = drives::BDHDE;
    let mut p = planner(&caps, 0, 100, 2);
    p.set_target(Target::OperationEnabled);
    assert_eq!(
        p.next(sw(State::SwitchOnDisabled), true).command,
        Command::Shutdown
    );
    let s = p.next(sw(State::FaultReactionActive), true);
    assert_eq!(s.command, Command::DisableVoltage);
    assert!(matches!(
        s.progress,
        Progress::Failed(PlannerError::Faulted {
            state: State::FaultReactionActive,
            target: Target::OperationEnabled
        })
    ));
    assert_eq!(p.target(), Target::SwitchOnDisabled);
    p.request_fault_reset();
    let mut saw_edge = false;
    for _ in 0..6 {
        let s = p.next(sw(State::Fault), true);
        saw_edge |= s.command == Command::FaultReset;
    }
    assert!(saw_edge);
    for _ in 0..10 {
        let s = p.next(sw(State::SwitchOnDisabled), true);
        assert_eq!(
            s.command,
            Command::DisableVoltage,
            "never re-enables on its own"
        );
    }
    p.set_target(Target::OperationEnabled);
    assert_eq!(
        p.next(sw(State::SwitchOnDisabled), true).command,
        Command::Shutdown
    );
}

// ----- stalls and drop-outs ----------------------------------------------------------------------

/// BLV-R §6.1: remote = 0 → the drive ignores the controlword; the timeout names the cause.
#[test]
fn remote_off_is_reported() {
    let caps = drives::BLV_R;
    let mut p = planner(&caps, 2, 30, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP),
        State::SwitchOnDisabled,
        2,
        0,
    );
    d.remote = false;
    d.apply(Command::DisableVoltage.controlword());
    d.apply(Command::DisableVoltage.controlword());
    d.apply(Command::DisableVoltage.controlword());
    p.set_target(Target::OperationEnabled);
    let (sent, progress) = run(&mut p, &mut d, 100);
    assert_eq!(sent.len(), 30);
    let Progress::Failed(e) = progress else {
        panic!("{progress:?}")
    };
    assert_eq!(
        e,
        PlannerError::Timeout {
            stuck_in: State::SwitchOnDisabled,
            target: Target::OperationEnabled,
            cycles: 30,
            command: Command::Shutdown,
            statusword: e_statusword(&e),
            cause: StallCause::RemoteOff
        }
    );
    assert_eq!(
        e.to_string(),
        format!(
            "drive stuck in Switch on disabled for 30 cycles on the way to Operation enabled: \
             it did not take transition 2 (Shutdown, controlword 0x0006), statusword 0x{:04X}; \
             statusword bit 9 (remote) is 0, so the drive ignores the controlword",
            e_statusword(&e)
        )
    );
    assert_eq!(
        e_statusword(&e) & 0x024F,
        0x0040,
        "Switch on disabled, remote 0"
    );
    assert!(
        d.log
            .iter()
            .all(|(_, _, r)| !matches!(r, Reaction::Transition(_)))
    );
}

#[test]
fn missing_main_power_is_reported() {
    let caps = drives::BDHDE;
    let mut p = planner(&caps, 0, 20, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::DISABLE_DRIVE),
        State::SwitchOnDisabled,
        0,
        0,
    );
    d.main_power = false;
    d.apply(Command::DisableVoltage.controlword());
    p.set_target(Target::OperationEnabled);
    let (_, progress) = run(&mut p, &mut d, 100);
    assert!(matches!(
        progress,
        Progress::Failed(PlannerError::Timeout {
            stuck_in: State::SwitchOnDisabled,
            cause: StallCause::NoMainVoltage,
            ..
        })
    ));
}

/// The planner thinks 0x605A = 2 (ends in Switch on disabled) but the drive runs 6 (stays).
#[test]
fn quick_stop_code_mismatch_is_reported() {
    let caps = DriveCaps {
        transition_16: false,
        ..DriveCaps::CIA402
    };
    let mut p = planner(&caps, 2, 25, 10);
    let mut d = SimDrive::new(
        DeviceConfig::from_caps(&caps, QuickStopOption::QUICK_STOP_RAMP_STAY),
        State::QuickStopActive,
        0,
        0,
    );
    p.set_target(Target::OperationEnabled);
    let (sent, progress) = run(&mut p, &mut d, 100);
    assert!(
        sent.iter().all(|c| *c == 0x0002),
        "never cuts the quick stop"
    );
    assert!(matches!(
        progress,
        Progress::Failed(PlannerError::Timeout {
            stuck_in: State::QuickStopActive,
            cause: StallCause::QuickStopHeld,
            ..
        })
    ));
}

#[test]
fn no_standstill_is_reported() {
    let caps = drives::BLV_R;
    let mut p = planner(&caps, 6, 25, 10);
    for _ in 0..25 {
        let s = p.next(sw(State::QuickStopActive), false);
        assert_eq!(s.command, Command::QuickStop);
        assert_eq!(s.progress, Progress::InProgress);
    }
    let s = p.next(sw(State::QuickStopActive), false);
    assert!(matches!(
        s.progress,
        Progress::Failed(PlannerError::Timeout {
            cause: StallCause::NotAtStandstill,
            ..
        })
    ));
    assert_eq!(s.command, Command::QuickStop);
}

/// A statusword matching no state: the last command is repeated (a glitch must not disable a
/// running axis) unless bit 3 says fault; after the timeout it is an error.
#[test]
fn undecodable_statusword() {
    let mut p = planner(&DriveCaps::CIA402, 2, 10, 10);
    p.set_target(Target::OperationEnabled);
    let oe = sw(State::OperationEnabled);
    for _ in 0..3 {
        p.next(sw(State::SwitchedOn), true);
    }
    assert_eq!(p.next(oe, true).progress, Progress::Reached);
    let glitch = StatusWord::from_raw(0x0001);
    assert_eq!(glitch.state(), None);
    let s = p.next(glitch, true);
    assert_eq!(
        (s.command, s.progress),
        (Command::EnableOperation, Progress::InProgress)
    );
    assert_eq!(p.next(oe, true).progress, Progress::Reached);
    // Fault bit in an undecodable word: disable at once.
    let fault_glitch = StatusWord::from_raw(0x0009);
    assert_eq!(fault_glitch.state(), None);
    assert_eq!(p.next(fault_glitch, true).command, Command::DisableVoltage);
    // Persistent garbage.
    let mut last = Progress::InProgress;
    for _ in 0..12 {
        last = p.next(glitch, true).progress;
    }
    assert!(matches!(
        last,
        Progress::Failed(PlannerError::InvalidStatusWord {
            statusword: 0x0001,
            ..
        })
    ));
}

/// After Operation enabled was reached, a quick stop by the drive itself (e.g. an input) is a
/// failure and the planner does not re-enable.
#[test]
fn drop_out_is_not_undone() {
    for (caps, qs) in [
        (drives::BLV_R, 6i16),
        (drives::BDHDE, 6),
        (drives::MR_J4_TM, 2),
    ] {
        let mut p = planner(&caps, qs, 100, 10);
        p.set_target(Target::OperationEnabled);
        p.next(sw(State::OperationEnabled), true);
        let s = p.next(sw(State::QuickStopActive), true);
        assert_eq!(
            s.progress,
            Progress::Failed(PlannerError::LeftTarget {
                target: Target::OperationEnabled,
                now: State::QuickStopActive
            })
        );
        for _ in 0..20 {
            let s = p.next(sw(State::QuickStopActive), true);
            assert_eq!(s.command, Command::QuickStop);
        }
        for _ in 0..20 {
            let s = p.next(sw(State::SwitchOnDisabled), true);
            assert!(
                matches!(s.command, Command::QuickStop | Command::DisableVoltage),
                "{:?}",
                s.command
            );
        }
    }
}

#[test]
fn config_checks() {
    let bad_qs = Planner::new(
        &drives::MR_J4_TM,
        PlannerConfig {
            timeout_cycles: 10,
            fault_reset_hold_cycles: 1,
            quick_stop_option: 6,
        },
    );
    assert_eq!(
        bad_qs.unwrap_err(),
        PlannerConfigError::UnsupportedQuickStopOption { code: 6 }
    );
    let zero = Planner::new(
        &DriveCaps::CIA402,
        PlannerConfig {
            timeout_cycles: 0,
            fault_reset_hold_cycles: 1,
            quick_stop_option: 2,
        },
    );
    assert!(matches!(zero, Err(PlannerConfigError::ZeroCycles { .. })));
    // 10 ms hold (MR-J4 §5.1) and 5 s timeout in cycles.
    let c = PlannerConfig::for_cycle_time(&drives::MR_J4_TM, Duration::from_micros(250));
    assert_eq!((c.fault_reset_hold_cycles, c.timeout_cycles), (40, 20_000));
    let c = PlannerConfig::for_cycle_time(&drives::BDHDE, Duration::from_millis(1));
    assert_eq!((c.fault_reset_hold_cycles, c.quick_stop_option), (10, 0));
    let c = PlannerConfig::for_cycle_time(&drives::BDHDE, Duration::from_millis(3));
    assert_eq!(c.fault_reset_hold_cycles, 4);
}

// ----- property tests against the device model ----------------------------------------------------

/// Every quick-stop code the tests exercise: the nine standard ones and BLV-R's vendor ones.
const ALL_QS: &[QuickStopOption] = &[
    QuickStopOption::DISABLE_DRIVE,
    QuickStopOption::SLOW_DOWN_RAMP,
    QuickStopOption::QUICK_STOP_RAMP,
    QuickStopOption::CURRENT_LIMIT,
    QuickStopOption::VOLTAGE_LIMIT,
    QuickStopOption::SLOW_DOWN_RAMP_STAY,
    QuickStopOption::QUICK_STOP_RAMP_STAY,
    QuickStopOption::CURRENT_LIMIT_STAY,
    QuickStopOption::VOLTAGE_LIMIT_STAY,
    QuickStopOption::vendor(-3, StopRamp::Vendor, QuickStopEnd::StayInQuickStopActive),
    QuickStopOption::vendor(-2, StopRamp::Vendor, QuickStopEnd::StayInQuickStopActive),
    QuickStopOption::vendor(-1, StopRamp::Immediate, QuickStopEnd::StayInQuickStopActive),
];

const TARGETS: [Target; 4] = [
    Target::OperationEnabled,
    Target::SwitchedOn,
    Target::SwitchOnDisabled,
    Target::QuickStop,
];

fn caps_for(skipping: bool, t16: bool) -> DriveCaps {
    DriveCaps {
        state_skipping: skipping,
        transition_16: t16,
        quick_stop_options: ALL_QS,
        ..DriveCaps::CIA402
    }
}

/// The stated bound (see the planner's "Cycle bound"): at most 5 transitions observed with lag
/// `lag`, plus initialisation, one stop ramp, and the first fault-reset edge (2 cycles).
fn bound(init: u32, ramp: u32, lag: usize) -> usize {
    init as usize + ramp as usize + 5 * (lag + 1) + 4
}

fn in_target(target: Target, s: State) -> bool {
    match target {
        Target::OperationEnabled => s == State::OperationEnabled,
        Target::SwitchedOn => s == State::SwitchedOn,
        Target::SwitchOnDisabled => s == State::SwitchOnDisabled,
        Target::QuickStop => matches!(s, State::QuickStopActive | State::SwitchOnDisabled),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    /// Every (start state, target) pair, with and without state skipping and transition 16, for
    /// every quick-stop code, with statusword delays of 0–3 cycles: the target is reached within
    /// `bound`, or the planner says why not (only Quick stop from a disabled drive). The planner
    /// never sends a command the drive ignores.
    #[test]
    fn reaches_every_target(
        skipping in any::<bool>(),
        t16 in any::<bool>(),
        qs in 0..ALL_QS.len(),
        start in 0..8usize,
        target in 0..4usize,
        lag in 0usize..4,
        ramp in 0u32..20,
        init in 0u32..5,
        hold in 1u32..5,
    ) {
        let caps = caps_for(skipping, t16);
        let qs = ALL_QS[qs];
        let start = State::ALL[start];
        let target = TARGETS[target];
        let mut dc = DeviceConfig::from_caps(&caps, qs);
        dc.init_cycles = init;
        let mut d = SimDrive::new(dc, start, lag, ramp);
        let mut p = planner(&caps, qs.code, 100_000, hold);
        let limit = bound(init, ramp, lag);
        let mut spent = 0;
        if start.is_fault() {
            // A fault never leads to enabling by itself: an energising target is refused …
            let energising = matches!(target, Target::OperationEnabled | Target::SwitchedOn);
            p.set_target(if energising { target } else { Target::SwitchOnDisabled });
            let s = p.next(d.seen(), d.standstill());
            prop_assert!(
                matches!(s.progress, Progress::Failed(PlannerError::Faulted { .. })),
                "{:?}", s.progress
            );
            prop_assert_eq!(s.command, Command::DisableVoltage);
            d.apply(s.controlword());
            // … so the caller resets first (as the axis engine does), then asks again.
            p.set_target(Target::SwitchOnDisabled);
            prop_assert!(p.request_fault_reset());
            let (sent, progress) = run(&mut p, &mut d, limit);
            prop_assert_eq!(progress, Progress::Reached);
            spent = sent.len() + 1;
        }
        p.set_target(target);
        let (_, progress) = run(&mut p, &mut d, limit + 1 - spent.min(limit));
        for (cw, st, r) in &d.log {
            prop_assert!(
                !matches!(r, Reaction::Ignored),
                "{st} ignored controlword 0x{:04X}", cw.raw()
            );
        }
        match progress {
            Progress::Reached => {
                prop_assert!(in_target(target, d.device.state()),
                    "reached {target} but the drive is in {}", d.device.state());
            }
            Progress::Failed(PlannerError::Unreachable { from, target: t, .. }) => {
                prop_assert_eq!(t, Target::QuickStop);
                prop_assert_eq!(from, State::SwitchOnDisabled);
                prop_assert_eq!(d.device.state(), State::SwitchOnDisabled);
            }
            other => prop_assert!(false, "{other:?} after {limit} cycles, drive in {}",
                d.device.state()),
        }
    }

    /// A fault injected at a random moment: the drive is never enabled again by the planner;
    /// after the fault clears and a reset is requested it ends in Switch on disabled, and only a
    /// new target enables it again.
    #[test]
    fn fault_injection(
        skipping in any::<bool>(),
        t16 in any::<bool>(),
        qs in 0..ALL_QS.len(),
        target in 0..4usize,
        lag in 0usize..4,
        ramp in 0u32..10,
        hold in 1u32..5,
        fault_at in 0usize..30,
        fault_len in 1usize..30,
        reset_delay in 0usize..10,
    ) {
        let caps = caps_for(skipping, t16);
        let qs = ALL_QS[qs];
        let target = TARGETS[target];
        let dc = DeviceConfig::from_caps(&caps, qs);
        let mut d = SimDrive::new(dc, State::SwitchOnDisabled, lag, ramp);
        let mut p = planner(&caps, qs.code, 100_000, hold);
        p.set_target(target);
        let clear_at = fault_at + fault_len;
        let total = clear_at + reset_delay + bound(0, ramp, lag) + 2 * hold as usize + 8;
        let mut faulted_at_log = None;
        let mut reset_requested = false;
        for cycle in 0..total {
            if cycle == fault_at {
                d.fault = true;
            }
            if cycle == clear_at {
                d.fault = false;
            }
            let seen = d.seen();
            let s = p.next(seen, d.standstill());
            d.apply(s.controlword());
            if !reset_requested && cycle >= clear_at + reset_delay
                && seen.state().is_some_and(State::is_fault)
            {
                prop_assert!(p.request_fault_reset());
                reset_requested = true;
            }
            if faulted_at_log.is_none() && d.device.state() == State::FaultReactionActive {
                faulted_at_log = Some(d.log.len());
            }
        }
        for (cw, st, r) in &d.log {
            prop_assert!(
                !matches!(r, Reaction::Ignored),
                "{st} ignored controlword 0x{:04X}", cw.raw()
            );
        }
        let first_fault = faulted_at_log.expect("the fault was injected");
        for (_, _, r) in &d.log[first_fault..] {
            prop_assert!(
                !matches!(r, Reaction::Transition(Transition { to: State::OperationEnabled, .. })),
                "re-enabled after a fault"
            );
        }
        prop_assert_eq!(d.device.state(), State::SwitchOnDisabled);
        if matches!(target, Target::OperationEnabled | Target::SwitchedOn) {
            prop_assert_eq!(p.target(), Target::SwitchOnDisabled);
        }
        // Recovery takes an explicit new target.
        p.set_target(Target::OperationEnabled);
        let (_, progress) = run(&mut p, &mut d, bound(0, ramp, lag) + 1);
        prop_assert_eq!(progress, Progress::Reached);
        prop_assert_eq!(d.device.state(), State::OperationEnabled);
    }

    /// The planner never panics and always answers, whatever the statusword sequence.
    #[test]
    fn arbitrary_statuswords(
        words in proptest::collection::vec(any::<u16>(), 1..200),
        target in 0..4usize,
        standstill in any::<bool>(),
        reset in any::<bool>(),
    ) {
        let mut p = planner(&drives::BLV_R, -1, 20, 2);
        p.set_target(TARGETS[target]);
        for w in words {
            let sw = StatusWord::from_raw(w);
            let s = p.next(sw, standstill);
            if reset {
                p.request_fault_reset();
            }
            // A statusword with the fault bit never gets an energising command.
            if sw.contains(StatusWord::FAULT) {
                prop_assert!(
                    matches!(s.command, Command::DisableVoltage | Command::FaultReset),
                    "0x{w:04X} -> {:?}", s.command
                );
            }
        }
    }
}
