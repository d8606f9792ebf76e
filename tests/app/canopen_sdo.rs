//! SDO on the virtual bus: segmented transfers both ways, aborts with the codes and texts the
//! manuals list, typed upload/download with the profile's dictionary (the library side of
//! `ecdrive upload/download --can`), node scan (`ecdrive slaves --can`), the ASDA-A2 SDO rate
//! limit, timeouts.

use crate::canopen_util;

use canopen_util::{bus, events, node_int};
use ecdrive::canopen::error::CanErrorKind;
use ecdrive::canopen::master::MasterEvent;
use ecdrive::canopen::sdo::SdoError;
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::od::{DataType, ObjectAddress, SdoAbortCode, Value};
use ecdrive_cli::app::canopen::tools::{self, BusSpec};

fn a(i: u16, s: u8) -> ObjectAddress {
    ObjectAddress::new(i, s)
}

#[test]
fn segmented_uploads_and_downloads() {
    let mut m = bus(&[(&lexium_mdrive::PROFILE, 0x41), (&blv_r::PROFILE, 1)]);
    m.transport_mut().set_trace(true);
    // 41-byte device name: a segmented upload of six segments.
    let v = tools::upload(&mut m, 0x41, a(0x1008, 0), None).unwrap();
    assert_eq!(v, Value::Str(lexium_mdrive::DEVICE_NAME.into()));
    let segs = m
        .transport()
        .trace()
        .iter()
        .filter(|t| t.frame.id() == 0x641 && t.frame.data()[0] & 0xE0 == 0x60)
        .count();
    assert_eq!(segs, 6, "41 bytes = 6 segments of up to 7");
    assert_eq!(
        tools::upload(&mut m, 1, a(0x1008, 0), None).unwrap(),
        Value::Str("BLVD-KRD".into())
    );
    // A segmented download (forced for a 4-byte value) is written.
    m.sdo_download_segmented(0x41, a(0x6081, 0), &400_000u32.to_le_bytes())
        .unwrap();
    assert_eq!(node_int(&m, 0x41, 0x6081, 0), 400_000);
    // A segmented download to a read-only string is refused at the initiate request: no
    // segment goes out.
    m.transport_mut().set_trace(true);
    let e = m.sdo_download(0x41, a(0x1008, 0), &[b'x'; 41]).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::READ_ONLY));
    let segments = m
        .transport()
        .trace()
        .iter()
        .filter(|t| t.frame.id() == 0x641 && t.frame.data()[0] & 0xE0 == 0x00)
        .count();
    assert_eq!(segments, 0);
    // Too long for the object: refused at the initiate (size indicated).
    let e = m.sdo_download(0x41, a(0x6081, 0), &[0; 8]).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::LENGTH_TOO_HIGH));
}

#[test]
fn aborts_name_node_object_code_and_text() {
    let mut m = bus(&[
        (&lexium_mdrive::PROFILE, 0x41),
        (&blv_r::PROFILE, 1),
        (&asda_a2::PROFILE, 0x7F),
    ]);
    tools::scan(&mut m, 1..=127).unwrap();
    let e = m.sdo_upload(0x41, a(0x1234, 0)).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::NO_OBJECT));
    assert_eq!(
        e.to_string(),
        "node 65 (0x41, Lexium MDrive) 0x1234:00: SDO abort 0x06020000 (Object does not exist \
         in the object dictionary)"
    );
    // TPDO communication sub 04h does not exist on the Lexium and the BLV-R: 0609 0011h. The
    // ASDA-A2 manual lists it ("reserved", UNSIGNED8, RW, default 0; §4.4 1800h).
    for id in [0x41u8, 1] {
        let e = m.sdo_upload(id, a(0x1800, 4)).unwrap_err();
        assert_eq!(e.abort_code(), Some(SdoAbortCode::NO_SUBINDEX), "{e}");
    }
    assert_eq!(m.sdo_upload(0x7F, a(0x1800, 4)).expect("1800h:04"), [0]);
    // Writes to read-only objects: the statusword everywhere, 1014h on the ASDA-A2.
    let e = m.sdo_download(1, a(0x6041, 0), &[0, 0]).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::READ_ONLY));
    let e = m
        .sdo_download(0x7F, a(0x1014, 0), &0x80u32.to_le_bytes())
        .unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::READ_ONLY));
    // BLV-R: reading an empty error history gives 0800 0024h.
    let e = m.sdo_upload(1, a(0x1003, 1)).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::NO_DATA));
    // Range and length.
    let e = m
        .sdo_download(1, a(0x1016, 1), &0x0100_0000u32.to_le_bytes())
        .unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::VALUE_TOO_HIGH));
    let e = m.sdo_download(1, a(0x6081, 0), &[1, 0]).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::LENGTH_TOO_LOW));
    // Modes and homing methods outside the drive's lists.
    let e = m.sdo_download(0x41, a(0x6060, 0), &[7]).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::VALUE_RANGE));
    let e = m.sdo_download(1, a(0x6098, 0), &[3]).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::VALUE_RANGE));
    // Vendor abort codes get the vendor's text.
    assert!(
        tools::abort_text(SdoAbortCode(0x0800_00A1), Some(&asda_a2::PROFILE))
            .to_string()
            .contains("EEPROM")
    );
    assert!(
        tools::abort_text(SdoAbortCode(0x0800_00A1), None)
            .to_string()
            .contains("unknown")
    );
}

#[test]
fn typed_upload_and_download_use_the_profile_dictionary() {
    let mut m = bus(&[(&asda_a2::PROFILE, 0x7F)]);
    // No scan beforehand: the tools identify the node on first use.
    tools::download(&mut m, 0x7F, a(0x6081, 0), "0x1F4", None).unwrap();
    assert_eq!(node_int(&m, 0x7F, 0x6081, 0), 500);
    assert_eq!(m.profile(0x7F).unwrap().name, "ASDA-A2");
    assert_eq!(
        tools::upload(&mut m, 0x7F, a(0x6081, 0), None).unwrap(),
        Value::Uint(500)
    );
    tools::download(&mut m, 0x7F, a(0x607C, 0), "-1234", None).unwrap();
    assert_eq!(
        tools::upload(&mut m, 0x7F, a(0x607C, 0), None).unwrap(),
        Value::Int(-1234)
    );
    assert_eq!(
        tools::upload(&mut m, 0x7F, a(0x6098, 0), None).unwrap(),
        Value::Int(0)
    );
    // P3-12 is INTEGER16 in the dictionary.
    assert_eq!(
        m.data_type(0x7F, a(0x230C, 0), None).unwrap(),
        DataType::Integer16
    );
    // A value that does not fit the type: refused before anything is sent.
    let e = tools::download(&mut m, 0x7F, a(0x6081, 0), "-5", None).unwrap_err();
    assert!(matches!(e.kind, CanErrorKind::Value(_)), "{e}");
    assert!(e.to_string().contains("0x6081:00"), "{e}");
    // An object outside the dictionary needs a type; with one, the drive's abort answers.
    let e = tools::upload(&mut m, 0x7F, a(0x2FFF, 0), None).unwrap_err();
    assert!(matches!(e.kind, CanErrorKind::UnknownType), "{e}");
    let e = tools::upload(&mut m, 0x7F, a(0x2FFF, 0), Some(DataType::Integer16)).unwrap_err();
    assert_eq!(e.abort_code(), Some(SdoAbortCode::NO_OBJECT));
    assert_eq!(
        tools::format_value(&Value::Uint(500), DataType::Unsigned32),
        "500 (0x000001F4)"
    );
}

#[test]
fn scan_finds_each_node_with_identity() {
    let mut m = bus(&[
        (&blv_r::PROFILE, 1),
        (&asda_a2::PROFILE, 0x7F),
        (&lexium_mdrive::PROFILE, 0x41),
    ]);
    let found = tools::scan(&mut m, 1..=127).unwrap();
    let ids: Vec<u8> = found.iter().map(|n| n.node).collect();
    assert_eq!(ids, vec![1, 0x41, 0x7F]);
    let lines: Vec<String> = found.iter().map(ToString::to_string).collect();
    assert!(
        lines[0].contains("BLVD-KRD") && lines[0].contains("0x000002BE"),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].contains("Lexium MDrive") && lines[1].contains("0x1454523E"),
        "{}",
        lines[1]
    );
    assert!(
        lines[2].contains("ASDA-A2") && lines[2].contains("0x04020192"),
        "{}",
        lines[2]
    );
    // The emulator's own reading of the manual's "N/A" (its table's MANUAL GAP).
    assert_eq!(
        found[2].revision,
        Some(ecdrive::sim::canopen::drives::asda_a2::REVISION)
    );
    assert_eq!(found[0].revision, None, "BLV-R 1018h has no revision");
    // A partial range finds only what is in it.
    let found = tools::scan(&mut m, 2..=0x40).unwrap();
    assert!(found.is_empty());
    // The virtual bus spec opens the same three drives.
    let spec: BusSpec = "virtual".parse().unwrap();
    let t = tools::open_bus(&spec).unwrap();
    let mut m2 = ecdrive::canopen::master::Master::new(t, Default::default());
    m2.pump(10_000).unwrap();
    assert_eq!(tools::scan(&mut m2, 1..=127).unwrap().len(), 3);
    assert_eq!(
        "vbus:/tmp/x".parse::<BusSpec>().unwrap(),
        BusSpec::UnixHub("/tmp/x".into())
    );
    assert_eq!(
        "can0".parse::<BusSpec>().unwrap(),
        BusSpec::SocketCan("can0".into())
    );
    assert!("".parse::<BusSpec>().is_err());
}

#[test]
fn asda_a2_sdo_rate_limit_is_enforced_by_the_client() {
    let mut m = bus(&[(&asda_a2::PROFILE, 0x7F)]);
    m.set_profile(0x7F, &asda_a2::PROFILE);
    events(&mut m);
    m.transport_mut().set_trace(true);
    for _ in 0..20 {
        m.sdo_upload(0x7F, a(0x6041, 0)).unwrap();
    }
    m.sdo_download_segmented(0x7F, a(0x6081, 0), &123u32.to_le_bytes())
        .unwrap();
    let times: Vec<u64> = m
        .transport()
        .trace()
        .iter()
        .filter(|t| t.frame.id() == 0x67F)
        .map(|t| t.time_us)
        .collect();
    assert_eq!(times.len(), 22);
    for w in times.windows(2) {
        assert!(w[1] - w[0] >= 1000, "SDO requests {} µs apart", w[1] - w[0]);
    }
    assert_eq!(m.transport().node(0x7F).unwrap().stats().sdo_overruns, 0);
    assert!(m.transport().node(0x7F).unwrap().alarm().is_none());
    // Without the pacing the drive loses the second request and raises AL111.
    m.set_sdo_interval(0x7F, Some(0));
    m.pump(2_000).unwrap();
    m.sdo_upload(0x7F, a(0x6041, 0)).unwrap();
    let e = m.sdo_upload(0x7F, a(0x6041, 0)).unwrap_err();
    assert!(
        matches!(e.kind, CanErrorKind::Sdo(SdoError::Timeout(_))),
        "{e}"
    );
    let node = m.transport().node(0x7F).unwrap();
    assert_eq!(node.stats().sdo_overruns, 1);
    assert_eq!(node.alarm().unwrap().name, "AL111");
    let al111 = events(&mut m).into_iter().any(|e| {
        matches!(e, MasterEvent::Emergency(r) if r.decoded.and_then(|d| d.alarm).map(|a| a.name) == Some("AL111"))
    });
    assert!(al111);
}

#[test]
fn timeouts_name_the_node_and_abort_the_transfer() {
    let mut m = bus(&[(&blv_r::PROFILE, 1)]);
    m.transport_mut().set_trace(true);
    let e = m.sdo_upload(9, a(0x1000, 0)).unwrap_err();
    assert!(
        matches!(e.kind, CanErrorKind::Sdo(SdoError::Timeout(500))),
        "{e}"
    );
    assert!(e.to_string().starts_with("node 9 (0x09) 0x1000:00"), "{e}");
    let abort = m
        .transport()
        .trace()
        .iter()
        .any(|t| t.frame.id() == 0x609 && t.frame.data()[0] == 0x80);
    assert!(abort, "the client aborts a timed-out transfer");
    assert!(m.sdo_upload(0, a(0x1000, 0)).is_err());
    assert!(m.sdo_upload(128, a(0x1000, 0)).is_err());
}
