//! NMT and error control: the enabled-drive rule for NMT Stop/Reset, the drives' own reactions
//! when a master breaks it (ASDA-A2 AL401, Lexium error class 2), the BLV-R remote gate, the
//! ASDA-A2 P3-12 and target-clearing quirks, heartbeat and node guarding in both directions,
//! boot-up, store/restore.

use crate::canopen_util;

use canopen_util::{T, bus, events, node_int, ready, setup, write};
use ecdrive::canopen::CanTransport;
use ecdrive::canopen::error::CanErrorKind;
use ecdrive::canopen::master::{Master, MasterEvent, Supervision};
use ecdrive::canopen::nmt::{NmtCommand, NmtState};
use ecdrive::cia402::{OperationMode, ProfileVelocity, State};
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::od::{ObjectAddress, SdoAbortCode, Value};
use ecdrive::sim::canopen::SimBus;
use ecdrive_cli::app::canopen::steps;

fn state(m: &Master<SimBus>, id: u8) -> State {
    m.transport().node(id).unwrap().state()
}

#[test]
fn stop_and_resets_are_refused_to_an_enabled_drive() {
    for (p, id) in [
        (&asda_a2::PROFILE, 0x7Fu8),
        (&lexium_mdrive::PROFILE, 0x41),
        (&blv_r::PROFILE, 3),
    ] {
        let mut m = ready(p, id);
        for cmd in [
            NmtCommand::Stop,
            NmtCommand::ResetNode,
            NmtCommand::ResetCommunication,
        ] {
            for target in [id, 0] {
                let e = m.nmt(target, cmd).unwrap_err();
                assert!(
                    matches!(
                        e.kind,
                        CanErrorKind::NmtRefused {
                            state: State::OperationEnabled,
                            ..
                        }
                    ),
                    "{}: {e}",
                    p.name
                );
                assert_eq!(e.node.id, id);
                assert!(e.to_string().contains("refused"), "{e}");
            }
        }
        m.pump(50_000).unwrap();
        let n = m.transport().node(id).unwrap();
        assert_eq!(n.state(), State::OperationEnabled, "{}", p.name);
        assert_eq!(n.nmt_state(), NmtState::Operational);
        assert!(n.alarm().is_none(), "no AL401 / class-2 error");
        // Disabled through the controlword first, the same commands pass.
        m.disable(id, T).unwrap();
        m.nmt(id, NmtCommand::Stop).unwrap();
        m.pump(10_000).unwrap();
        let n = m.transport().node(id).unwrap();
        assert_eq!(n.nmt_state(), NmtState::Stopped);
        assert!(n.alarm().is_none());
        m.reset_communication(id).unwrap();
        assert_eq!(m.nmt_state(id), Some(NmtState::PreOperational));
    }
}

fn raw_nmt(m: &mut Master<SimBus>, cmd: NmtCommand, id: u8) {
    m.transport_mut().send(&cmd.frame(id)).unwrap();
}

#[test]
fn asda_a2_raises_al401_on_a_raw_nmt_stop_while_enabled() {
    let mut m = ready(&asda_a2::PROFILE, 0x7F);
    events(&mut m);
    raw_nmt(&mut m, NmtCommand::Stop, 0x7F);
    m.pump(100_000).unwrap();
    let n = m.transport().node(0x7F).unwrap();
    assert_eq!(n.alarm().unwrap().name, "AL401");
    assert!(matches!(
        n.state(),
        State::Fault | State::FaultReactionActive
    ));
    let emcy = events(&mut m)
        .into_iter()
        .find_map(|e| match e {
            MasterEvent::Emergency(r) => Some(r),
            _ => None,
        })
        .unwrap();
    assert_eq!(emcy.emergency.error_code, 0x8100);
    assert_eq!(emcy.decoded.unwrap().alarm.unwrap().name, "AL401");
    assert!(
        emcy.to_string()
            .contains("NMT reset or stop received while enabled"),
        "{emcy}"
    );
}

#[test]
fn lexium_makes_a_class_2_stop_on_a_raw_nmt_stop_while_enabled() {
    let mut m = ready(&lexium_mdrive::PROFILE, 0x41);
    // Get the motor running in pv.
    m.switch_mode(0x41, OperationMode::ProfileVelocity, T)
        .unwrap();
    let mut pv = ProfileVelocity::new(true);
    pv.set_target(256_000); // 5 rev/s
    for _ in 0..200 {
        m.cycle_step(|d| {
            let sw = d.statusword();
            pv.step(d.axis_mut(), sw);
        })
        .unwrap();
    }
    let v0 = m.transport().node(0x41).unwrap().velocity_units_per_s();
    assert!((v0 - 256_000.0).abs() < 1.0, "{v0}");
    events(&mut m);
    raw_nmt(&mut m, NmtCommand::Stop, 0x41);
    // Quick stop first (fault reaction with the quick-stop ramp), power stage off afterwards.
    m.transport_mut().advance(1_000);
    let n = m.transport().node(0x41).unwrap();
    assert_eq!(n.state(), State::FaultReactionActive);
    let v1 = n.velocity_units_per_s();
    assert!(v1 > 0.0 && v1 < v0, "decelerating on the ramp: {v1}");
    m.transport_mut().advance(2_000_000);
    let n = m.transport().node(0x41).unwrap();
    assert_eq!(n.state(), State::Fault);
    assert_eq!(n.velocity_units_per_s(), 0.0);
    assert_eq!(n.nmt_state(), NmtState::Stopped);
    m.pump(1_000).unwrap();
    let texts: Vec<String> = events(&mut m).iter().map(ToString::to_string).collect();
    assert!(
        texts.iter().any(|t| t.contains("error class 2")),
        "{texts:?}"
    );
}

#[test]
fn blv_r_remote_gate_is_reported_not_timed_out() {
    let mut m = bus(&[(&blv_r::PROFILE, 3)]);
    m.configure_drive(3, setup(&blv_r::PROFILE)).unwrap();
    m.start(3).unwrap();
    // S-ON input active: statusword bit 9 = 0, the drive ignores the controlword.
    m.transport_mut().node_mut(3).unwrap().set_remote(false);
    let t0 = m.now_us();
    let e = m.enable(3, T).unwrap_err();
    assert!(matches!(e.kind, CanErrorKind::RemoteOff), "{e}");
    assert!(e.to_string().contains("bit 9"), "{e}");
    // Reported within a few cycles of simulated time, far from the 5 s planner timeout.
    assert!(m.now_us() - t0 < 100_000, "{} µs", m.now_us() - t0);
    assert_eq!(state(&m, 3), State::SwitchOnDisabled);
    let ev = events(&mut m);
    assert!(
        ev.iter().any(|e| matches!(e, MasterEvent::RemoteOff { node } if node.id == 3 && node.drive == Some("BLV-R"))),
        "{ev:?}"
    );
    // Remote back: the same request succeeds.
    m.transport_mut().node_mut(3).unwrap().set_remote(true);
    m.enable(3, T).unwrap();
    assert_eq!(state(&m, 3), State::OperationEnabled);
    assert!(events(&mut m).contains(&MasterEvent::RemoteOn { node: 3 }));
    // With remote = 0 a quick stop still acts (BLV-R §6.1).
    m.transport_mut().node_mut(3).unwrap().set_remote(false);
    m.drive_mut(3).unwrap().axis_mut().request_quick_stop();
    for _ in 0..20 {
        m.cycle_step(|_| {}).unwrap();
    }
    assert!(matches!(
        state(&m, 3),
        State::QuickStopActive | State::SwitchOnDisabled
    ));
}

#[test]
fn asda_a2_p3_12_default_switches_on_with_bit_3_until_configured() {
    let mut m = bus(&[(&asda_a2::PROFILE, 0x7F)]);
    m.set_profile(0x7F, &asda_a2::PROFILE);
    assert_eq!(node_int(&m, 0x7F, 0x230C, 0), 0, "P3-12 factory value");
    // The hazard the manual describes: controlword 0008h alone switches the servo on.
    write(&mut m, 0x7F, 0x6040, 0, Value::Uint(0x0008));
    m.pump(5_000).unwrap();
    assert_eq!(state(&m, 0x7F), State::OperationEnabled);
    write(&mut m, 0x7F, 0x6040, 0, Value::Uint(0x0000));
    m.pump(5_000).unwrap();
    assert_eq!(state(&m, 0x7F), State::SwitchOnDisabled);
    // The master's configuration sets P3-12 X = 1: now only the DS402 sequence enables.
    m.configure_drive(0x7F, setup(&asda_a2::PROFILE)).unwrap();
    assert_eq!(node_int(&m, 0x7F, 0x230C, 0) & 0xF, 1);
    write(&mut m, 0x7F, 0x6040, 0, Value::Uint(0x0008));
    m.pump(5_000).unwrap();
    assert_eq!(state(&m, 0x7F), State::SwitchOnDisabled);
}

#[test]
fn asda_a2_clears_targets_on_enable_and_the_master_writes_them_after() {
    // The drive's behaviour: 60FFh written before servo on is cleared when it enables.
    let mut m = bus(&[(&asda_a2::PROFILE, 0x7F)]);
    m.configure_drive(0x7F, setup(&asda_a2::PROFILE)).unwrap();
    write(&mut m, 0x7F, 0x6060, 0, Value::Int(3));
    write(&mut m, 0x7F, 0x60FF, 0, Value::Int(3000));
    for cw in [0x6u64, 0x7, 0xF] {
        write(&mut m, 0x7F, 0x6040, 0, Value::Uint(cw));
        m.pump(2_000).unwrap();
    }
    assert_eq!(state(&m, 0x7F), State::OperationEnabled);
    assert_eq!(node_int(&m, 0x7F, 0x60FF, 0), 0, "cleared on servo on");
    m.pump(200_000).unwrap();
    assert_eq!(
        m.transport().node(0x7F).unwrap().velocity_units_per_s(),
        0.0
    );

    // Through the Axis: the pv target is given before enabling, goes out only in Operation
    // enabled, and the drive runs at it.
    let mut m = bus(&[(&asda_a2::PROFILE, 0x7F)]);
    let mut s = setup(&asda_a2::PROFILE);
    s.initial_mode = OperationMode::ProfileVelocity;
    m.configure_drive(0x7F, s).unwrap();
    m.start(0x7F).unwrap();
    let mut pv = ProfileVelocity::new(true);
    pv.set_target(3000);
    m.drive_mut(0x7F)
        .unwrap()
        .axis_mut()
        .request_enable()
        .unwrap();
    let mut reached = false;
    for _ in 0..1000 {
        let mut st = None;
        m.cycle_step(|d| {
            let sw = d.statusword();
            st = Some(pv.step(d.axis_mut(), sw));
        })
        .unwrap();
        if st.is_some_and(|s| s.streaming && s.target_reached) {
            reached = true;
            break;
        }
    }
    assert!(reached);
    assert_eq!(node_int(&m, 0x7F, 0x60FF, 0), 3000);
    assert_eq!(node_int(&m, 0x7F, 0x606C, 0), 3000);
}

#[test]
fn heartbeat_loss_is_detected_and_names_the_node() {
    let mut m = bus(&[(&blv_r::PROFILE, 1), (&asda_a2::PROFILE, 0x7F)]);
    for (id, p) in [(1u8, &blv_r::PROFILE), (0x7F, &asda_a2::PROFILE)] {
        m.configure_drive(id, setup(p)).unwrap();
        m.start(id).unwrap();
    }
    events(&mut m);
    for _ in 0..500 {
        m.cycle_step(|_| {}).unwrap();
    }
    let ev = events(&mut m);
    assert!(
        !ev.iter()
            .any(|e| matches!(e, MasterEvent::HeartbeatLost { .. })),
        "{ev:?}"
    );
    assert_eq!(m.nmt_state(0x7F), Some(NmtState::Operational));
    // Cable pulled.
    m.transport_mut().remove_node(0x7F).unwrap();
    for _ in 0..500 {
        m.cycle_step(|_| {}).unwrap();
    }
    let lost: Vec<MasterEvent> = events(&mut m)
        .into_iter()
        .filter(|e| matches!(e, MasterEvent::HeartbeatLost { .. }))
        .collect();
    assert_eq!(lost.len(), 1, "{lost:?}");
    let MasterEvent::HeartbeatLost {
        node,
        last_state,
        silent_us,
    } = lost[0]
    else {
        unreachable!()
    };
    assert_eq!(node.id, 0x7F);
    assert_eq!(node.drive, Some("ASDA-A2"));
    assert_eq!(last_state, Some(NmtState::Operational));
    assert!(silent_us > 350_000);
    let text = lost[0].to_string();
    assert!(
        text.contains("node 127") && text.contains("ASDA-A2") && text.contains("heartbeat lost"),
        "{text}"
    );
}

#[test]
fn node_guarding_both_ways() {
    let mut m = bus(&[(&blv_r::PROFILE, 2), (&lexium_mdrive::PROFILE, 0x41)]);
    for (id, p) in [(2u8, &blv_r::PROFILE), (0x41, &lexium_mdrive::PROFILE)] {
        let mut s = setup(p);
        s.supervision = Supervision::Guarding {
            guard_ms: 50,
            life_factor: 3,
        };
        m.configure_drive(id, s).unwrap();
        m.start(id).unwrap();
    }
    events(&mut m);
    m.pump(1_000_000).unwrap();
    let ev = events(&mut m);
    assert!(
        !ev.iter().any(|e| matches!(
            e,
            MasterEvent::GuardingLost { .. } | MasterEvent::GuardingToggle { .. }
        )),
        "{ev:?}"
    );
    assert!(m.transport().node(2).unwrap().stats().guard_replies >= 15);
    assert_eq!(node_int(&m, 2, 0x100C, 0), 50);
    assert_eq!(
        node_int(&m, 2, 0x1017, 0),
        0,
        "heartbeat off while guarding"
    );

    // A reply whose toggle bit did not alternate (a repeat from a foreign device) is reported.
    m.pump(60_000).unwrap();
    // Replies alternate from toggle 0: after n replies the last one had toggle (n - 1) odd.
    let replies = m.transport().node(2).unwrap().stats().guard_replies;
    let last_toggle = (replies - 1) % 2 == 1;
    let byte = 0x05 | if last_toggle { 0x80 } else { 0 };
    m.transport_mut()
        .inject(&ecdrive::canopen::CanFrame::new(0x702, &[byte]).unwrap());
    m.pump(1_000).unwrap();
    assert!(events(&mut m).contains(&MasterEvent::GuardingToggle { node: 2 }));

    // The node's side: the master goes quiet (time passes without guarding requests); the
    // Lexium's life time expires → Fault; the BLV-R sends EMCY 8130h.
    m.enable(0x41, T).unwrap();
    m.transport_mut().advance(400_000);
    let lex = m.transport().node(0x41).unwrap();
    assert!(matches!(
        lex.state(),
        State::Fault | State::FaultReactionActive
    ));
    assert_eq!(lex.alarm().unwrap().code, 0x8130);
    m.pump(1_000).unwrap();
    let codes: Vec<(u8, u16)> = events(&mut m)
        .iter()
        .filter_map(|e| match e {
            MasterEvent::Emergency(r) => Some((r.node, r.emergency.error_code)),
            _ => None,
        })
        .collect();
    assert!(
        codes.contains(&(2, 0x8130)) && codes.contains(&(0x41, 0x8130)),
        "{codes:?}"
    );

    // The master's side: the node stops answering.
    m.transport_mut().remove_node(2).unwrap();
    m.pump(1_000_000).unwrap();
    let lost: Vec<MasterEvent> = events(&mut m)
        .into_iter()
        .filter(|e| matches!(e, MasterEvent::GuardingLost { .. }))
        .collect();
    assert_eq!(lost.len(), 1, "{lost:?}");
    assert!(matches!(lost[0], MasterEvent::GuardingLost { node, missed: 3 } if node.id == 2));
}

#[test]
fn boot_up_after_reset_and_store_restore() {
    let mut m = bus(&[(&blv_r::PROFILE, 3)]);
    m.configure_drive(3, setup(&blv_r::PROFILE)).unwrap();
    let mapped = node_int(&m, 3, 0x1600, 0);
    assert_ne!(mapped, 1);
    // Reset communication reloads the stored (factory) communication objects.
    let boots = m.boot_ups(3);
    m.reset_communication(3).unwrap();
    assert_eq!(m.boot_ups(3), boots + 1);
    assert_eq!(node_int(&m, 3, 0x1600, 0), 1, "factory RPDO1 mapping back");
    // Stored with "save" on 1010h:02 (communication), it survives the reset.
    m.configure_drive(3, setup(&blv_r::PROFILE)).unwrap();
    let bad = m
        .sdo_download(
            3,
            ObjectAddress::new(0x1010, 2),
            &0x1234_5678u32.to_le_bytes(),
        )
        .unwrap_err();
    assert_eq!(bad.abort_code(), Some(SdoAbortCode::CANNOT_STORE));
    m.sdo_download(3, ObjectAddress::new(0x1010, 2), b"save")
        .unwrap();
    m.reset_communication(3).unwrap();
    assert_eq!(node_int(&m, 3, 0x1600, 0), mapped);
    // Restore defaults ("load" on 1011h:01) takes effect at the next reset node.
    m.sdo_download(3, ObjectAddress::new(0x1011, 1), b"load")
        .unwrap();
    assert_eq!(node_int(&m, 3, 0x1600, 0), mapped);
    m.reset_node(3).unwrap();
    assert_eq!(node_int(&m, 3, 0x1600, 0), 1);
    // The drive still works after all that.
    m.configure_drive(3, setup(&blv_r::PROFILE)).unwrap();
    m.start(3).unwrap();
    m.enable(3, T).unwrap();
    assert_eq!(
        steps::move_pp(&mut m, 3, &[ecdrive::cia402::SetPoint::absolute(100)], T).unwrap(),
        100
    );
}
