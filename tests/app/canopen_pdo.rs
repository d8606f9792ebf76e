//! PDOs on the virtual bus: each drive's limits enforced by the master before anything is
//! written and by the emulated drive on every SDO write (with the abort codes of its manual);
//! defaults overwritten; transmission types 0, 1–240 and 254/255 (inhibit time) behave; short
//! RPDOs and too-fast RPDOs raise the drive's alarm.

use crate::canopen_util;

use canopen_util::{T, bus, events, node_int, ready, setup};
use ecdrive::canopen::CanFrame;
use ecdrive::canopen::CanTransport;
use ecdrive::canopen::error::CanErrorKind;
use ecdrive::canopen::master::{Master, MasterConfig, MasterEvent};
use ecdrive::canopen::pdo_plan::{CanPdo, PdoPlan, PdoPlanError};
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::od::{ObjectAddress, SdoAbortCode};
use ecdrive::pdo::{MappingError, PdoEntry};
use ecdrive::sim::canopen::SimBus;

fn a(i: u16, s: u8) -> ObjectAddress {
    ObjectAddress::new(i, s)
}

fn dl(m: &mut Master<SimBus>, id: u8, i: u16, s: u8, v: u32, bytes: usize) -> Option<SdoAbortCode> {
    m.sdo_download(id, a(i, s), &v.to_le_bytes()[..bytes])
        .err()
        .and_then(|e| e.abort_code())
}

#[test]
fn bad_plans_are_refused_before_anything_is_written() {
    let cases: Vec<(
        &'static ecdrive::canopen::profile::CanDriveProfile,
        u8,
        PdoPlan,
        &str,
    )> = vec![
        (
            &blv_r::PROFILE,
            1,
            {
                let mut p = PdoPlan::standard(&blv_r::PROFILE);
                p.rpdos[0].entries = vec![
                    PdoEntry::new(0x6040, 0, 16),
                    PdoEntry::new(0x6060, 0, 8),
                    PdoEntry::new(0x6060, 0, 8),
                    PdoEntry::new(0x6060, 0, 8),
                    PdoEntry::new(0x6060, 0, 8),
                ];
                p
            },
            "at most 4",
        ),
        (
            &blv_r::PROFILE,
            1,
            {
                let mut p = PdoPlan::standard(&blv_r::PROFILE);
                p.rpdos[0].transmission_type = 10;
                p
            },
            "transmission type 10",
        ),
        (
            &asda_a2::PROFILE,
            0x7F,
            {
                let mut p = PdoPlan::standard(&asda_a2::PROFILE);
                p.tpdos[0].entries.push(PdoEntry::new(0x606C, 0, 32));
                p
            },
            "at most 8",
        ),
        (
            &lexium_mdrive::PROFILE,
            0x41,
            {
                let mut p = PdoPlan::standard(&lexium_mdrive::PROFILE);
                p.rpdos.push(CanPdo {
                    number: 4,
                    cob_id: None,
                    transmission_type: 0,
                    inhibit_time: 0,
                    event_timer: 0,
                    entries: vec![PdoEntry::new(0x6071, 0, 32)],
                    fixed: false,
                });
                p
            },
            "0x6071:00 is 16 bits, mapped with 32",
        ),
    ];
    for (p, id, plan, text) in cases {
        let mut m = bus(&[(p, id)]);
        m.transport_mut().set_trace(true);
        let mut s = setup(p);
        s.plan = plan;
        let e = m.configure_drive(id, s).unwrap_err();
        assert!(matches!(e.kind, CanErrorKind::Pdo(_)), "{e}");
        assert!(e.to_string().contains(text), "{}: {e}", p.name);
        let writes_to_pdo_objects = m.transport().trace().iter().any(|t| {
            let d = t.frame.data();
            t.frame.id() == 0x600 + u16::from(id)
                && d[0] & 0xE0 == 0x20
                && (0x14..=0x1B).contains(&d[2])
        });
        assert!(!writes_to_pdo_objects, "{}: nothing written", p.name);
    }
    // The mapping error type names the rule.
    let mut plan = PdoPlan::standard(&blv_r::PROFILE);
    plan.rpdos[0].entries.push(PdoEntry::new(0x6060, 0, 8));
    plan.rpdos[0].entries.push(PdoEntry::new(0x6060, 0, 8));
    assert!(matches!(
        plan.validate(&blv_r::PROFILE),
        Err(PdoPlanError::Mapping(MappingError::TooManyEntriesInPdo {
            max: 4,
            ..
        })) | Err(PdoPlanError::TooManyBytes { .. })
    ));
}

#[test]
fn blv_r_enforces_its_pdo_rules_on_sdo_writes() {
    let mut m = bus(&[(&blv_r::PROFILE, 3)]);
    m.set_profile(3, &blv_r::PROFILE);
    // RPDOs take transmission types 00h, FEh, FFh only.
    assert_eq!(
        dl(&mut m, 3, 0x1400, 2, 1, 1),
        Some(SdoAbortCode::VALUE_RANGE)
    );
    assert_eq!(dl(&mut m, 3, 0x1400, 2, 0xFE, 1), None);
    // The mapping of a valid PDO cannot change.
    assert_eq!(
        dl(&mut m, 3, 0x1600, 0, 0, 1),
        Some(SdoAbortCode::DEVICE_STATE)
    );
    // Invalidate RPDO1, clear its mapping.
    assert_eq!(dl(&mut m, 3, 0x1400, 1, 0x8000_0203, 4), None);
    assert_eq!(dl(&mut m, 3, 0x1600, 0, 0, 1), None);
    // Entries: unknown object, not RPDO-mappable, wrong length.
    assert_eq!(
        dl(&mut m, 3, 0x1600, 1, 0x1234_0010, 4),
        Some(SdoAbortCode::NO_OBJECT)
    );
    assert_eq!(
        dl(&mut m, 3, 0x1600, 1, 0x6041_0010, 4),
        Some(SdoAbortCode::NOT_MAPPABLE)
    );
    assert_eq!(
        dl(&mut m, 3, 0x1600, 1, 0x6040_0020, 4),
        Some(SdoAbortCode::NOT_MAPPABLE)
    );
    // 80 bits do not fit 8 bytes.
    assert_eq!(dl(&mut m, 3, 0x1600, 1, 0x607A_0020, 4), None);
    assert_eq!(dl(&mut m, 3, 0x1600, 2, 0x60FF_0020, 4), None);
    assert_eq!(dl(&mut m, 3, 0x1600, 3, 0x6040_0010, 4), None);
    assert_eq!(
        dl(&mut m, 3, 0x1600, 0, 3, 1),
        Some(SdoAbortCode::PDO_TOO_LONG)
    );
    // At most 4 entries (sub 00h range 0–4).
    assert_eq!(
        dl(&mut m, 3, 0x1600, 0, 5, 1),
        Some(SdoAbortCode::VALUE_TOO_HIGH)
    );
    assert_eq!(dl(&mut m, 3, 0x1600, 0, 2, 1), None);
    // Entries cannot change while sub 00h is not 0.
    assert_eq!(
        dl(&mut m, 3, 0x1600, 1, 0x6040_0010, 4),
        Some(SdoAbortCode::DEVICE_STATE)
    );
    // The inhibit time of a valid TPDO cannot change (§8.1); of an invalid one it can.
    assert_eq!(
        dl(&mut m, 3, 0x1800, 3, 0, 2),
        Some(SdoAbortCode::DEVICE_STATE)
    );
    assert_eq!(dl(&mut m, 3, 0x1800, 1, 0xC000_0183, 4), None);
    assert_eq!(dl(&mut m, 3, 0x1800, 3, 0, 2), None);
    // The 11-bit ID of a valid PDO cannot change; 29-bit IDs are not supported.
    assert_eq!(
        dl(&mut m, 3, 0x1801, 1, 0x4000_0299, 4),
        Some(SdoAbortCode::VALUE_RANGE)
    );
    assert_eq!(
        dl(&mut m, 3, 0x1801, 1, 0xA000_0283, 4),
        Some(SdoAbortCode::VALUE_RANGE)
    );
    // RPDO communication records have no sub 03h on the BLV-R.
    assert_eq!(
        dl(&mut m, 3, 0x1400, 3, 0, 2),
        Some(SdoAbortCode::NO_SUBINDEX)
    );
}

#[test]
fn asda_a2_and_lexium_pdo_rules() {
    let mut m = bus(&[(&asda_a2::PROFILE, 0x7F), (&lexium_mdrive::PROFILE, 0x41)]);
    m.set_profile(0x7F, &asda_a2::PROFILE);
    m.set_profile(0x41, &lexium_mdrive::PROFILE);
    // ASDA-A2 defaults: no mapping, type 0.
    assert_eq!(node_int(&m, 0x7F, 0x1600, 0), 0);
    assert_eq!(node_int(&m, 0x7F, 0x1800, 2), 0);
    assert_eq!(dl(&mut m, 0x7F, 0x1400, 1, 0x8000_027F, 4), None);
    // Past the range: 0609 0030h, the one range code the ASDA-A2 lists (§5.3).
    assert_eq!(
        dl(&mut m, 0x7F, 0x1600, 0, 9, 1),
        Some(SdoAbortCode::VALUE_RANGE)
    );
    for s in 1..=8u8 {
        assert_eq!(dl(&mut m, 0x7F, 0x1600, s, 0x6060_0008, 4), None);
    }
    assert_eq!(
        dl(&mut m, 0x7F, 0x1600, 0, 8, 1),
        None,
        "8 entries fit the ASDA-A2"
    );
    // RTR transmission types are not offered by the ASDA-A2.
    assert_eq!(
        dl(&mut m, 0x7F, 0x1800, 2, 253, 1),
        Some(SdoAbortCode::VALUE_RANGE)
    );
    // Lexium: only PDO1 is valid at power-on; the other defaults carry bit 31.
    assert_eq!(node_int(&m, 0x41, 0x1400, 1), 0x241);
    assert_eq!(node_int(&m, 0x41, 0x1401, 1), 0x8000_0341);
    assert_eq!(
        node_int(&m, 0x41, 0x1801, 5),
        100,
        "TPDO2 event timer 100 ms"
    );
    // 8 entries per PDO, and the dictionary's mapping flags (6077h is TPDO-only).
    assert_eq!(
        dl(&mut m, 0x41, 0x1603, 1, 0x6077_0010, 4),
        Some(SdoAbortCode::DEVICE_STATE)
    );
    assert_eq!(
        dl(&mut m, 0x41, 0x1603, 0, 0, 1),
        None,
        "RPDO4 is invalid: remappable"
    );
    assert_eq!(
        dl(&mut m, 0x41, 0x1603, 1, 0x6077_0010, 4),
        Some(SdoAbortCode::NOT_MAPPABLE)
    );
    // After the master's configuration every PDO is what the plan says.
    m.configure_drive(0x41, setup(&lexium_mdrive::PROFILE))
        .unwrap();
    let plan = PdoPlan::standard(&lexium_mdrive::PROFILE);
    for n in 1..=4u16 {
        let valid = node_int(&m, 0x41, 0x13FF + n, 1) & 0x8000_0000 == 0;
        assert_eq!(valid, usize::from(n) <= plan.rpdos.len(), "RPDO{n}");
    }
}

#[test]
fn tpdo_transmission_types() {
    // Type 1: one TPDO per SYNC per PDO.
    let mut m = ready(&blv_r::PROFILE, 3);
    let n_tpdo = m.drive(3).unwrap().tpdos().len() as u64;
    let before = m.transport().node(3).unwrap().stats();
    for _ in 0..100 {
        m.cycle_step(|_| {}).unwrap();
    }
    let after = m.transport().node(3).unwrap().stats();
    assert_eq!(after.syncs - before.syncs, 100);
    assert_eq!(after.tpdos_sent - before.tpdos_sent, 100 * n_tpdo);

    // Type 255 with a 5 ms inhibit time while the axis moves: at most one per 5 ms.
    let mut m = bus(&[(&blv_r::PROFILE, 3)]);
    let mut s = setup(&blv_r::PROFILE);
    for p in &mut s.plan.tpdos {
        p.transmission_type = 255;
        p.inhibit_time = 50;
    }
    m.configure_drive(3, s).unwrap();
    m.start(3).unwrap();
    m.enable(3, T).unwrap();
    let before = m.transport().node(3).unwrap().stats().tpdos_sent;
    let t0 = m.now_us();
    ecdrive_cli::app::canopen::steps::move_pp(
        &mut m,
        3,
        &[ecdrive::cia402::SetPoint::absolute(36_000)],
        T,
    )
    .unwrap();
    let dt_ms = (m.now_us() - t0) / 1000;
    let sent = m.transport().node(3).unwrap().stats().tpdos_sent - before;
    assert!(sent > 0);
    assert!(
        sent <= (dt_ms / 5 + 2) * n_tpdo,
        "{sent} TPDOs in {dt_ms} ms"
    );
}

#[test]
fn rpdo_type_0_applies_at_the_next_sync() {
    let mut m = ready(&blv_r::PROFILE, 3);
    let rpdo1 = m.drive(3).unwrap().rpdos()[0];
    // An RPDO1 with controlword 0 (disable voltage): nothing happens until SYNC.
    let mut data = m.drive(3).unwrap().rx_image()[rpdo1.offset..rpdo1.offset + rpdo1.len].to_vec();
    data[0] = 0;
    data[1] = 0;
    m.transport_mut()
        .send(&CanFrame::new(rpdo1.cob, &data).unwrap())
        .unwrap();
    m.transport_mut().advance(5_000);
    assert_eq!(
        node_int(&m, 3, 0x6040, 0) & 0xF,
        0xF,
        "not applied before SYNC"
    );
    m.transport_mut()
        .send(&CanFrame::new(0x80, &[]).unwrap())
        .unwrap();
    assert_eq!(node_int(&m, 3, 0x6040, 0), 0, "applied at SYNC");
}

#[test]
fn short_and_too_fast_rpdos_raise_the_drive_alarm() {
    // BLV-R: a short RPDO is dropped with EMCY 8210h.
    let mut m = ready(&blv_r::PROFILE, 3);
    events(&mut m);
    let cob = m.drive(3).unwrap().rpdos()[0].cob;
    m.transport_mut()
        .send(&CanFrame::new(cob, &[0x0F]).unwrap())
        .unwrap();
    m.pump(1_000).unwrap();
    let emcy: Vec<u16> = events(&mut m)
        .iter()
        .filter_map(|e| match e {
            MasterEvent::Emergency(r) => Some(r.emergency.error_code),
            _ => None,
        })
        .collect();
    assert_eq!(emcy, vec![0x8210]);
    assert!(m.transport().node(3).unwrap().stats().rpdos_rejected >= 1);

    // ASDA-A2: two frames on one RPDO COB-ID within 1 ms → AL112.
    let mut m = ready(&asda_a2::PROFILE, 0x7F);
    let slot = m.drive(0x7F).unwrap().rpdos()[0];
    let data = m.drive(0x7F).unwrap().rx_image()[slot.offset..slot.offset + slot.len].to_vec();
    m.pump(2_000).unwrap();
    let f = CanFrame::new(slot.cob, &data).unwrap();
    m.transport_mut().send(&f).unwrap();
    m.transport_mut().send(&f).unwrap();
    m.pump(1_000).unwrap();
    assert_eq!(
        m.transport().node(0x7F).unwrap().alarm().unwrap().name,
        "AL112"
    );

    // The master refuses a cycle that would do that itself.
    let mut m = canopen_util::bus_with(
        &[(&asda_a2::PROFILE, 0x7F)],
        MasterConfig {
            cycle_us: 500,
            ..MasterConfig::default()
        },
    );
    let e = m
        .configure_drive(0x7F, setup(&asda_a2::PROFILE))
        .unwrap_err();
    assert!(e.to_string().contains("one frame per COB-ID"), "{e}");
}
