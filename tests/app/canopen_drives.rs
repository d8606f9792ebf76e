//! Acceptance on the virtual bus: each emulated CANopen drive boots, is found by a scan,
//! configured, enabled, homed, moved in pp and pv (tq where it has it, ip on the ASDA-A2),
//! faulted and reset, and shut down — all through `cia402::Axis` and the profile-mode helpers.
//! Every outcome is checked on the emulated node itself, not only on the master's view.

use crate::canopen_util;

use canopen_util::{T, bus, events, node_int, setup};
use ecdrive::canopen::master::{Master, MasterEvent};
use ecdrive::canopen::nmt::NmtState;
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::cia402::{OperationMode, SetPoint, State};
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::od::ObjectAddress;
use ecdrive::sim::canopen::{EmulatedNode, SimBus};
use ecdrive_cli::app::canopen::steps;
use ecdrive_cli::app::canopen::tools;

struct Case {
    profile: &'static CanDriveProfile,
    id: u8,
    homing_method: i8,
    alarm: u16,
    alarm_name: &'static str,
}

fn node(m: &Master<SimBus>, id: u8) -> &EmulatedNode {
    m.transport().node(id).unwrap()
}

fn acceptance(c: Case) {
    let p = c.profile;
    let id = c.id;
    let rev = p.units.position_per_rev as i32;

    // Boot: the boot-up message reaches the master; the node is Pre-operational.
    let mut m = bus(&[(p, id)]);
    let ev = events(&mut m);
    assert!(ev.contains(&MasterEvent::BootUp { node: id }), "{ev:?}");
    assert_eq!(m.nmt_state(id), Some(NmtState::PreOperational));
    assert_eq!(node(&m, id).nmt_state(), NmtState::PreOperational);

    // Scan: the node is found with its identity and profile.
    let found = tools::scan(&mut m, 1..=127).unwrap();
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].node, id);
    assert_eq!(found[0].device_type, Some(p.identity.device_type));
    assert_eq!(found[0].vendor_id, Some(p.identity.vendor_id));
    assert_eq!(
        found[0].profile.map(|q| q.identity.vendor_id),
        Some(p.identity.vendor_id)
    );

    // Configure: the plan and the supervision are in the node's dictionary.
    let s = setup(p);
    let plan = s.plan.clone();
    m.configure_drive(id, s).unwrap();
    assert_eq!(node_int(&m, id, 0x1017, 0), 100);
    for (k, pdo) in plan.rpdos.iter().enumerate() {
        let map = 0x1600 + pdo.number as u16 - 1;
        assert_eq!(node_int(&m, id, map, 0), pdo.entries.len() as i64);
        assert_eq!(
            node_int(&m, id, map, 1),
            pdo.entries[0].to_u32() as i64,
            "RPDO {k}"
        );
        let cob = node_int(&m, id, 0x1400 + pdo.number as u16 - 1, 1);
        assert_eq!(
            cob,
            0x100 + 0x100 * pdo.number as i64 + id as i64,
            "RPDO valid"
        );
    }
    // PDOs outside the plan are invalid (bit 31), whatever their default.
    for n in (plan.tpdos.len() + 1)..=4 {
        assert!(node_int(&m, id, 0x1800 + n as u16 - 1, 1) & 0x8000_0000 != 0);
    }
    m.start(id).unwrap();
    assert_eq!(node(&m, id).nmt_state(), NmtState::Operational);

    // Enable through the Axis.
    m.enable(id, T).unwrap();
    assert_eq!(node(&m, id).state(), State::OperationEnabled);

    // Home with a method the drive lists and a home offset.
    let pos = steps::home(&mut m, id, c.homing_method, 1000, T).unwrap();
    assert_eq!(pos, 1000);
    assert_eq!(node(&m, id).position(), 1000);
    assert_eq!(node_int(&m, id, 0x6061, 0), 6);

    // pp: absolute, then a relative set-point queued behind it.
    let pos = steps::move_pp(
        &mut m,
        id,
        &[
            SetPoint::absolute(2 * rev),
            SetPoint::relative(rev / 4).queued(),
        ],
        T,
    )
    .unwrap();
    assert_eq!(pos, 2 * rev + rev / 4);
    assert_eq!(node(&m, id).position(), 2 * rev + rev / 4);
    assert_eq!(node_int(&m, id, 0x6061, 0), 1);

    // pv: 5 rev/s in the drive's velocity unit, then halt to zero speed.
    let u = &p.units;
    let v = u.from_rev_per_s(u.velocity, 5.0).round() as i32;
    let held = steps::run_pv(&mut m, id, v, 100_000, T).unwrap();
    assert_eq!(held, v);
    assert!(node(&m, id).velocity_units_per_s().abs() < 1.0, "halted");

    // tq where the drive has it.
    if p.supports(OperationMode::ProfileTorque) {
        assert_eq!(steps::run_tq(&mut m, id, 300, T).unwrap(), 300);
        assert_eq!(node(&m, id).torque(), 0.0);
    }

    // ip on the ASDA-A2.
    if p.supports(OperationMode::InterpolatedPosition) {
        let start = node(&m, id).position();
        let end = steps::run_ip(&mut m, id, rev, 200, T).unwrap();
        // The path starts where the axis is (a coasting load may have crept a few counts).
        assert!((end - start - rev).abs() <= rev / 1000, "{start} -> {end}");
        assert_eq!(node(&m, id).position(), end);
        let sw = node_int(&m, id, 0x6041, 0);
        assert!(sw & (1 << 12) != 0, "ip mode active (bit 12): 0x{sw:04X}");
    }

    // Fault: the node raises an alarm; the master decodes the EMCY with the alarm table; the
    // axis reports the fault, resets it and enables again.
    let alarm = c.alarm;
    let text = steps::fault_and_reset(
        &mut m,
        id,
        |bus| {
            assert!(bus.node_mut(id).unwrap().inject_alarm(alarm));
        },
        T,
    )
    .unwrap();
    assert!(text.contains(c.alarm_name), "{text}");
    let rec = m
        .emergencies(id)
        .find(|r| !r.emergency.is_reset())
        .copied()
        .unwrap();
    assert_eq!(rec.decoded.unwrap().alarm.unwrap().number, alarm);
    assert!(
        m.emergencies(id).any(|r| r.emergency.is_reset()),
        "error reset EMCY"
    );
    assert_eq!(node(&m, id).state(), State::OperationEnabled);
    assert_eq!(node_int(&m, id, 0x603F, 0), 0);
    assert!(node_int(&m, id, 0x1003, 0) >= 1);
    let a = p.alarm(alarm).unwrap();
    assert_eq!(
        node_int(&m, id, 0x1003, 1) as u32,
        p.emcy.history_entry(a.code, a.number)
    );

    // Safe shutdown: disable through the controlword, then NMT Stop — no alarm.
    m.shutdown_node(id, T).unwrap();
    assert!(!node(&m, id).state().is_energised());
    assert_eq!(node(&m, id).nmt_state(), NmtState::Stopped);
    assert!(node(&m, id).alarm().is_none());
}

#[test]
fn blv_r_acceptance() {
    acceptance(Case {
        profile: &blv_r::PROFILE,
        id: 3,
        homing_method: 24,
        alarm: 0x30,
        alarm_name: "overload",
    });
}

#[test]
fn asda_a2_acceptance() {
    acceptance(Case {
        profile: &asda_a2::PROFILE,
        id: 0x7F,
        homing_method: 34,
        alarm: 0x0011,
        alarm_name: "AL011",
    });
}

#[test]
fn lexium_acceptance() {
    acceptance(Case {
        profile: &lexium_mdrive::PROFILE,
        id: 0x41,
        homing_method: 19,
        alarm: lexium_mdrive::alarm::OVER_TEMPERATURE,
        alarm_name: "over-temperature error",
    });
}

#[test]
fn lexium_closed_loop_acceptance_with_tq_and_index_homing() {
    acceptance(Case {
        profile: &lexium_mdrive::PROFILE_CLOSED_LOOP,
        id: 0x41,
        homing_method: 34,
        alarm: lexium_mdrive::alarm::STALL,
        alarm_name: "motor idle during commanded move",
    });
}

#[test]
fn homing_methods_the_drive_does_not_list_are_refused() {
    // BLV-R lists 1, 2, 8, 12, 17, 18, 24, 28, 35, 37, -1 only: 19 is aborted at 6098h.
    let mut m = canopen_util::ready(&blv_r::PROFILE, 3);
    let e = steps::home(&mut m, 3, 19, 0, T).unwrap_err();
    assert_eq!(e.address, Some(ObjectAddress::new(0x6098, 0)));
    assert_eq!(e.abort_code(), Some(ecdrive::od::SdoAbortCode::VALUE_RANGE));
    // Lexium open loop: index methods end in a homing error (no encoder).
    let mut m = canopen_util::ready(&lexium_mdrive::PROFILE, 0x41);
    let e = steps::home(&mut m, 0x41, 33, 0, T).unwrap_err();
    assert!(e.to_string().contains("Error"), "{e}");
    // Method 35 (current position) works everywhere it is listed.
    let mut m = canopen_util::ready(&asda_a2::PROFILE, 0x7F);
    assert_eq!(steps::home(&mut m, 0x7F, 35, -500, T).unwrap(), -500);
}

#[test]
fn modes_the_drive_lacks_are_refused_by_the_axis() {
    let mut m = canopen_util::ready(&lexium_mdrive::PROFILE, 0x41);
    let e = m
        .switch_mode(0x41, OperationMode::ProfileTorque, T)
        .unwrap_err();
    assert!(e.to_string().contains("not supported"), "{e}");
    let mut m = canopen_util::ready(&blv_r::PROFILE, 3);
    assert!(
        m.switch_mode(3, OperationMode::InterpolatedPosition, T)
            .is_err()
    );
    assert!(
        m.switch_mode(3, OperationMode::CyclicSyncPosition, T)
            .is_err()
    );
}

#[test]
fn three_drives_share_one_bus() {
    let mut m = bus(&[
        (&blv_r::PROFILE, 1),
        (&asda_a2::PROFILE, 0x7F),
        (&lexium_mdrive::PROFILE, 0x41),
    ]);
    for (id, p) in [
        (1u8, &blv_r::PROFILE),
        (0x7F, &asda_a2::PROFILE),
        (0x41, &lexium_mdrive::PROFILE),
    ] {
        m.configure_drive(id, setup(p)).unwrap();
        m.start(id).unwrap();
    }
    for id in [1u8, 0x7F, 0x41] {
        m.enable(id, T).unwrap();
    }
    for (id, p) in [
        (1u8, &blv_r::PROFILE),
        (0x7F, &asda_a2::PROFILE),
        (0x41, &lexium_mdrive::PROFILE),
    ] {
        let rev = p.units.position_per_rev as i32;
        assert_eq!(
            steps::move_pp(&mut m, id, &[SetPoint::absolute(rev)], T).unwrap(),
            rev
        );
    }
    // The others kept their state while one moved.
    for id in [1u8, 0x7F, 0x41] {
        assert_eq!(
            m.transport().node(id).unwrap().state(),
            State::OperationEnabled
        );
    }
}
