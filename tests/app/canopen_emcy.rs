//! EMCY consumer: every drive's messages decoded with its own format and alarm table, and the
//! fault reaching the Axis with 603Fh decoded by the drive's error table.

use crate::canopen_util;

use canopen_util::{T, bus, events, node_int, ready};
use ecdrive::canopen::emcy::Emergency;
use ecdrive::canopen::master::{EmergencyRecord, Master, MasterEvent};
use ecdrive::cia402::{ErrorSource, Event, Phase, State, StatusWord};
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::sim::canopen::SimBus;

fn emcys(m: &mut Master<SimBus>) -> Vec<EmergencyRecord> {
    events(m)
        .into_iter()
        .filter_map(|e| match e {
            MasterEvent::Emergency(r) => Some(r),
            _ => None,
        })
        .collect()
}

fn inject(m: &mut Master<SimBus>, id: u8, n: u16) -> EmergencyRecord {
    assert!(m.transport_mut().node_mut(id).unwrap().inject_alarm(n));
    m.pump(1_000).unwrap();
    let v = emcys(m);
    assert_eq!(v.len(), 1, "{v:?}");
    v[0]
}

#[test]
fn blv_r_alarm_codes_ffxx() {
    let mut m = ready(&blv_r::PROFILE, 1);
    events(&mut m);
    let r = inject(&mut m, 1, 0x31);
    assert_eq!(
        r.emergency,
        Emergency {
            error_code: 0xFF31,
            error_register: 0x81,
            data: [0; 5]
        }
    );
    let d = r.decoded.unwrap();
    assert_eq!(d.vendor_number, Some(0x31));
    assert_eq!(d.alarm.unwrap().text, "overspeed");
    assert_eq!(
        r.to_string(),
        "node 1 (0x01, BLV-R): EMCY 0xFF31 alarm 31h overspeed, error register 0x81"
    );
    // 603Fh = alarm + FF00h, the axis decodes it with the drive's table.
    for _ in 0..10 {
        m.cycle_step(|_| {}).unwrap();
    }
    assert_eq!(node_int(&m, 1, 0x603F, 0), 0xFF31);
    let fault = std::iter::from_fn(|| m.drive_mut(1).unwrap().axis_mut().poll_event())
        .find_map(|e| match e {
            Event::Fault { error, .. } => error,
            _ => None,
        })
        .unwrap();
    assert_eq!(fault.name, "alarm 31h");
    assert_eq!(fault.source, ErrorSource::Drive);
    assert_eq!(m.drive(1).unwrap().axis().status().phase, Phase::Faulted);
    // CAN-side codes carry register 11h and no alarm number.
    let r = inject(&mut m, 1, 0x8130);
    assert_eq!(r.emergency.error_register, 0x11);
    assert_eq!(
        r.decoded.unwrap().alarm.unwrap().text,
        "node guarding or heartbeat error"
    );
}

#[test]
fn asda_a2_tells_shared_codes_apart_by_the_panel_number() {
    let mut m = ready(&asda_a2::PROFILE, 0x7F);
    events(&mut m);
    // AL011 and AL024 share 7305h; bytes 3–4 carry the panel number.
    let r = inject(&mut m, 0x7F, 0x0024);
    assert_eq!(r.emergency.error_code, 0x7305);
    assert_eq!(r.emergency.data[..2], [0x24, 0x00]);
    assert_eq!(r.decoded.unwrap().alarm.unwrap().name, "AL024");
    assert_eq!(node_int(&m, 0x7F, 0x1003, 1), 0x0024_7305);
    // A warning does not fault the drive.
    for _ in 0..5 {
        m.cycle_step(|_| {}).unwrap();
    }
    assert!(m.drive_mut(0x7F).unwrap().axis_mut().request_fault_reset());
    for _ in 0..20 {
        m.cycle_step(|_| {}).unwrap();
    }
    m.enable(0x7F, T).unwrap();
    events(&mut m);
    let r = inject(&mut m, 0x7F, 0x0023);
    assert_eq!(r.decoded.unwrap().alarm.unwrap().name, "AL023");
    for _ in 0..20 {
        m.cycle_step(|_| {}).unwrap();
    }
    assert_eq!(
        m.transport().node(0x7F).unwrap().state(),
        State::OperationEnabled
    );
    assert!(
        m.drive(0x7F)
            .unwrap()
            .statusword()
            .contains(StatusWord::WARNING)
    );
    // History keeps the newest first, at most 5 entries.
    assert_eq!(node_int(&m, 0x7F, 0x1003, 1), 0x0023_3231);
    assert_eq!(node_int(&m, 0x7F, 0x1003, 2), 0x0024_7305);
    for n in [0x0001u16, 0x0002, 0x0003, 0x0004] {
        m.transport_mut().node_mut(0x7F).unwrap().inject_alarm(n);
    }
    assert_eq!(node_int(&m, 0x7F, 0x1003, 0), 5);
}

#[test]
fn lexium_vendor_code_in_bytes_6_7() {
    let mut m = bus(&[(&lexium_mdrive::PROFILE, 0x41)]);
    m.set_profile(0x41, &lexium_mdrive::PROFILE);
    events(&mut m);
    let r = inject(&mut m, 0x41, 0x0016);
    assert_eq!(r.emergency.error_code, 0x4210);
    assert_eq!(r.emergency.data, [0, 0, 0, 0x16, 0]);
    assert_eq!(
        r.decoded.unwrap().alarm.unwrap().text,
        "pending over-temperature warning"
    );
    let r = inject(&mut m, 0x41, 0x0008);
    assert_eq!(
        r.decoded.unwrap().alarm.unwrap().text,
        "over-temperature error"
    );
    assert_eq!(node_int(&m, 0x41, 0x1003, 1), 0x0008_4210);
}

#[test]
fn unidentified_nodes_are_reported_raw() {
    let mut m = bus(&[(&blv_r::PROFILE, 1)]);
    events(&mut m);
    let r = inject(&mut m, 1, 0x20);
    assert!(r.decoded.is_none());
    assert!(r.to_string().contains("EMCY 0xFF20"), "{r}");
    assert_eq!(m.emergencies(1).count(), 1);
}
