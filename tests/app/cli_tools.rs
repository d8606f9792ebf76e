//! The library side of the `ecdrive` commands (`master::tools`) without a bus: SII decoding
//! and the ESI skeleton against EEPROM images the software slave builds from the drives' ESI
//! files, and the commands in-process (`sim:` targets, no root).

use ecdrive::esi::EsiFile;
use ecdrive::pdo::Direction;
use ecdrive::sim::sii;
use ecdrive_cli::app::ethercat::tools::sii::{SiiInfo, esi_skeleton};
use ecdrive_cli::app::ethercat::tools::{self, Target};

fn image_of(esi_path: &str, serial: u32) -> (EsiFile, Vec<u8>) {
    let file = EsiFile::from_path(esi_path).unwrap();
    let dev = file.devices.first().unwrap();
    let desc = sii::from_esi(file.vendor.id, dev, serial).unwrap();
    let img = sii::build(&desc).unwrap();
    (file, img.bytes().to_vec())
}

#[test]
fn sii_of_the_drive_esi_files_decodes_to_what_the_files_say() {
    for path in ["esi/Mitsubishi_MR-J4-TM.xml", "esi/Servotronix_BDHDE.xml"] {
        let (file, bytes) = image_of(path, 42);
        let dev = file.devices.first().unwrap();
        let info = SiiInfo::decode(&bytes).unwrap();
        assert!(info.checksum_ok, "{path}");
        assert_eq!(info.vendor_id, file.vendor.id, "{path}");
        assert_eq!(info.product_code, dev.type_.product_code, "{path}");
        assert_eq!(Some(info.revision), dev.type_.revision_no, "{path}");
        assert_eq!(info.serial, 42, "{path}");
        assert_eq!(info.size_bytes, bytes.len(), "{path}");
        assert!(info.protocols.contains(&"CoE".to_string()), "{path}");
        let g = info.general.as_ref().unwrap();
        assert_eq!(g.order, dev.type_.name_text, "{path}");
        assert_eq!(g.name, dev.name, "{path}");
        assert_eq!(info.sync_managers.len(), dev.sync_managers.len(), "{path}");
        for (s, e) in info.sync_managers.iter().zip(&dev.sync_managers) {
            assert_eq!(s.start, e.start_address, "{path}");
            assert_eq!(s.control, e.control_byte, "{path}");
            assert_eq!(s.kind, e.kind.name(), "{path}");
        }
        for (dir, pdos) in [
            (Direction::Rx, &info.rx_pdos),
            (Direction::Tx, &info.tx_pdos),
        ] {
            let want = dev.pdos(dir);
            assert_eq!(pdos.len(), want.len(), "{path} {dir:?}");
            for (p, w) in pdos.iter().zip(want) {
                assert_eq!(p.index, w.index, "{path}");
                assert_eq!(p.name, w.name, "{path}");
                assert_eq!(p.entries.len(), w.entries.len(), "{path} 0x{:04X}", p.index);
                for (e, we) in p.entries.iter().zip(&w.entries) {
                    assert_eq!((e.index, e.sub), (we.index, we.sub), "{path}");
                    assert_eq!(u16::from(e.bits), we.bit_len, "{path}");
                }
            }
        }
        assert_eq!(info.dc_modes.len(), dev.dc.len(), "{path}");
        for (m, w) in info.dc_modes.iter().zip(&dev.dc) {
            assert_eq!(m.name, w.mode.name, "{path}");
            assert_eq!(m.assign_activate, w.mode.assign_activate, "{path}");
        }
    }
}

#[test]
fn the_esi_skeleton_reads_back_with_the_same_device() {
    for path in ["esi/Mitsubishi_MR-J4-TM.xml", "esi/Servotronix_BDHDE.xml"] {
        let (file, bytes) = image_of(path, 7);
        let orig = file.devices.first().unwrap();
        let info = SiiInfo::decode(&bytes).unwrap();
        let xml = esi_skeleton(&info, &bytes);
        let back = EsiFile::parse(&xml).unwrap_or_else(|e| panic!("{path}: {e}\n{xml}"));
        assert!(back.check().is_empty(), "{path}: {:?}", back.check());
        assert_eq!(back.vendor.id, file.vendor.id);
        let dev = back
            .device(orig.type_.product_code, orig.type_.revision_no)
            .unwrap();
        assert_eq!(dev.name, orig.name);
        assert_eq!(dev.has_coe(), orig.has_coe());
        // The default process image is the same as the original file's.
        let m0 = orig.default_mapping().unwrap();
        let m1 = dev.default_mapping().unwrap();
        assert_eq!(m1.bytes(Direction::Rx), m0.bytes(Direction::Rx), "{path}");
        assert_eq!(m1.bytes(Direction::Tx), m0.bytes(Direction::Tx), "{path}");
        for dir in [Direction::Rx, Direction::Tx] {
            let a: Vec<(u16, usize)> = orig
                .pdos(dir)
                .iter()
                .map(|p| (p.index, p.entries.len()))
                .collect();
            let b: Vec<(u16, usize)> = dev
                .pdos(dir)
                .iter()
                .map(|p| (p.index, p.entries.len()))
                .collect();
            assert_eq!(a, b, "{path}");
        }
        // And the SII the skeleton describes is the one it came from.
        let again = sii::build(&sii::from_esi(back.vendor.id, dev, 7).unwrap()).unwrap();
        let info2 = SiiInfo::decode(again.bytes()).unwrap();
        assert_eq!(info2.rx_pdos, info.rx_pdos, "{path}");
        assert_eq!(info2.tx_pdos, info.tx_pdos, "{path}");
        assert_eq!(info2.sync_managers, info.sync_managers, "{path}");
        assert_eq!(info2.dc_modes, info.dc_modes, "{path}");
    }
}

#[test]
fn truncated_and_corrupt_images_are_errors_not_panics() {
    let (_, bytes) = image_of("esi/Mitsubishi_MR-J4-TM.xml", 1);
    // Cut inside the categories: either a clean stop or an error naming the category.
    for cut in [0, 10, 64, 127, 128, 129, 200, 400, 1000] {
        let r = SiiInfo::decode(&bytes[..cut.min(bytes.len())]);
        if let Err(e) = r {
            assert!(e.to_string().starts_with("SII "), "{e}");
        }
    }
    // A category length running past the end.
    let mut bad = bytes.clone();
    bad[0x82] = 0xFF;
    bad[0x83] = 0x7F;
    let e = SiiInfo::decode(&bad).unwrap_err();
    assert!(e.to_string().contains("words announced"), "{e}");
    let mut crc = bytes;
    crc[14] ^= 0xFF;
    assert!(!SiiInfo::decode(&crc).unwrap().checksum_ok);
}

fn sim(devices: &str) -> Target {
    format!("sim:{devices}").parse().unwrap()
}

#[test]
fn targets_parse_and_name_themselves() {
    assert_eq!(
        "eth1".parse::<Target>().unwrap(),
        Target::Interface("eth1".into())
    );
    assert_eq!(
        sim("generic-coe, generic-io"),
        Target::Sim(vec!["generic-coe".into(), "generic-io".into()])
    );
    assert_eq!(sim("generic-coe").to_string(), "sim:generic-coe");
    assert!("sim:".parse::<Target>().is_err());
}

#[test]
fn in_process_commands_report_typed_results() {
    let s = tools::session(&sim("generic-coe,generic-io"), |bus| {
        tools::slaves(bus, true)
    })
    .unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s[0].mailbox_protocols, vec!["CoE".to_string()]);
    let d0 = s[0].detail.as_ref().unwrap();
    assert_eq!(d0.mailbox.as_ref().unwrap().tx_offset, 0x1080);
    assert!(
        d0.ports[0].link && d0.ports[1].link,
        "device 0 has a neighbour on port 1"
    );
    let d1 = s[1].detail.as_ref().unwrap();
    assert!(
        d1.ports[0].link && !d1.ports[1].link,
        "the last device has no port 1 link"
    );

    let v = tools::session(&sim("generic-coe"), |bus| {
        tools::download(bus, 0, "0x607A:00".parse().unwrap(), "-5", None)?;
        tools::upload(bus, 0, "0x607A:00".parse().unwrap(), None)
    })
    .unwrap();
    assert_eq!(v.value, tools::JsonValue::Int(-5));
    assert_eq!(v.type_source, tools::TypeSource::SdoInfo);
    assert_eq!(v.name.as_deref(), Some("Target position"));

    let mut calls = 0;
    let objs = tools::session(&sim("generic-coe"), move |bus| {
        tools::sdos(bus, 0, false, &mut |done, total| {
            assert!(done <= total);
            calls += 1;
        })
        .map(|o| (o, calls))
    })
    .unwrap();
    assert_eq!(objs.1, objs.0.objects.len(), "progress once per object");
    assert_eq!(objs.0.source, tools::OdSource::SdoInfo);
    assert!(objs.0.objects.iter().any(|o| o.index == 0x6041));
}
