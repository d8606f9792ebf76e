//! The emulated drives' EEPROM, read through the SII registers, against their ESI files and
//! their profiles: identity, names, EEPROM configuration words, mailbox, CoE details,
//! SyncManagers, FMMUs, every PDO with its entries, the default assignment and the DC modes.

use crate::support::wire;

use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive_core::esi::{EsiFile, SmKind};
use ecdrive_core::pdo::{Direction, Pdo, PdoEntry};
use ecdrive_sim::sii::{SiiImage, category};
use wire::Wire;

const PROFILES: [&DriveProfile; 2] = [&mr_j4_tm::PROFILE, &bdhde::PROFILE];

fn u16le(d: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([d[at], d[at + 1]])
}

fn u32le(d: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]])
}

/// A PDO as the SII TxPDO/RxPDO category holds it.
#[derive(Debug)]
struct SiiPdo {
    pdo: Pdo,
    sm: u8,
    name: String,
    data_types: Vec<u8>,
}

fn pdos(sii: &SiiImage, kind: u16) -> Vec<SiiPdo> {
    let Some(d) = sii.category(kind) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut at = 0;
    while at + 8 <= d.len() {
        let index = u16le(d, at);
        let n = usize::from(d[at + 2]);
        let sm = d[at + 3];
        let name = sii.string(d[at + 5]).unwrap_or("").to_string();
        let mut entries = Vec::new();
        let mut data_types = Vec::new();
        for k in 0..n {
            let e = at + 8 + 8 * k;
            entries.push(PdoEntry::new(u16le(d, e), d[e + 2], d[e + 5]));
            data_types.push(d[e + 4]);
        }
        out.push(SiiPdo {
            pdo: Pdo::owned(index, entries),
            sm,
            name,
            data_types,
        });
        at += 8 + 8 * n;
    }
    out
}

#[test]
fn eeprom_is_the_esi_file() {
    for p in PROFILES {
        let f = EsiFile::parse(p.esi).unwrap();
        let dev = f.device(p.identity.product_code, None).unwrap();
        let mut w = Wire::drives(&[p]);
        let img = w.eeprom(0);
        let sii = SiiImage::from_bytes(img.clone());
        let name = p.name;
        assert!(sii.checksum_ok(), "{name}: SII checksum");
        // Size and configuration words.
        let ee = dev.eeprom.as_ref().unwrap();
        assert_eq!(
            img.len() as u32,
            ee.byte_size.unwrap(),
            "{name}: EEPROM size"
        );
        assert_eq!(&img[0..10], &ee.config_data[0..10], "{name}: ConfigData");
        // Identity: ESI = profile = SII; the serial is the drive's.
        let id = sii.identity();
        assert_eq!(id.vendor_id, f.vendor.id);
        assert_eq!(id.vendor_id, p.identity.vendor_id, "{name}");
        assert_eq!(id.product_code, dev.type_.product_code);
        assert_eq!(id.product_code, p.identity.product_code, "{name}");
        assert_eq!(Some(id.revision), dev.type_.revision_no);
        assert_eq!(id.revision, p.revision, "{name}");
        assert_eq!(id.serial, 1);
        // Names: device name first (SOEM), order code, group.
        let general = sii.category(category::GENERAL).unwrap();
        assert_eq!(
            sii.string(general[3]),
            Some(dev.name.as_str()),
            "{name}: name"
        );
        assert_eq!(
            sii.string(general[2]),
            Some(dev.type_.name_text.as_str()),
            "{name}: order code"
        );
        assert_eq!(sii.string(1), Some(dev.name.as_str()));
        // CoE details: complete access as the profile says, SDO info as the ESI says.
        let coe = dev.mailbox.as_ref().unwrap().coe.as_ref().unwrap();
        assert_eq!(general[5], coe.sii_byte(), "{name}: CoE details");
        assert_eq!(
            general[5] & 0x20 != 0,
            p.complete_access,
            "{name}: complete access"
        );
        assert_eq!(general[9], 1, "{name}: one DS402 channel");
        // Mailbox words = the ESI mailbox SyncManagers; protocols.
        let out = dev.sync_manager(SmKind::MBoxOut).unwrap();
        let inp = dev.sync_manager(SmKind::MBoxIn).unwrap();
        let mbx: Vec<u16> = (0..5).map(|k| u16le(&img, (0x18 + k) * 2)).collect();
        assert_eq!(
            mbx,
            [
                out.start_address,
                out.default_size.unwrap(),
                inp.start_address,
                inp.default_size.unwrap(),
                dev.mailbox.as_ref().unwrap().protocols.bits()
            ],
            "{name}: mailbox words"
        );
        // SyncManagers and FMMUs.
        let sms = sii.category(category::SYNC_MANAGER).unwrap();
        assert_eq!(sms.len(), 8 * dev.sync_managers.len());
        for (s, e) in sms.chunks(8).zip(&dev.sync_managers) {
            assert_eq!(u16le(s, 0), e.start_address, "{name}: SM{}", e.index);
            assert_eq!(
                Some(u16le(s, 2)),
                e.default_size.or(Some(0)),
                "{name}: SM{}",
                e.index
            );
            assert_eq!(s[4], e.control_byte);
            assert_eq!(s[6], e.sii_enable());
            assert_eq!(s[7], e.kind.sii_type());
        }
        let fmmus = sii.category(category::FMMU).unwrap();
        let want: Vec<u8> = dev.fmmus.iter().map(|f| f.usage.sii_code()).collect();
        assert_eq!(&fmmus[..want.len()], want.as_slice(), "{name}: FMMUs");
        // PDOs: every ESI PDO with its entries and types, the ones with an Sm attribute
        // assigned; they are the profile's power-on contents and default mapping.
        for (dir, kind, profile_pdos) in [
            (
                Direction::Rx,
                category::RXPDO,
                if p.key == "bdhde" {
                    bdhde::RX_PDOS
                } else {
                    mr_j4_tm::RX_PDOS
                },
            ),
            (
                Direction::Tx,
                category::TXPDO,
                if p.key == "bdhde" {
                    bdhde::TX_PDOS
                } else {
                    mr_j4_tm::TX_PDOS
                },
            ),
        ] {
            let got = pdos(&sii, kind);
            let esi = dev.pdos(dir);
            assert_eq!(got.len(), esi.len(), "{name} {dir}");
            for ((g, e), q) in got.iter().zip(esi).zip(profile_pdos) {
                assert_eq!(g.pdo, e.to_pdo(dir).unwrap(), "{name} {dir}");
                assert_eq!(&g.pdo, q, "{name} {dir}: profile power-on contents");
                assert_eq!(g.name, e.name);
                let types: Vec<u8> = e
                    .entries
                    .iter()
                    .map(|x| x.data_type().unwrap().code() as u8)
                    .collect();
                assert_eq!(g.data_types, types, "{name} 0x{:04X} types", e.index);
                assert_eq!(g.sm == 0xFF, e.sm.is_none(), "{name} 0x{:04X}", e.index);
            }
            let assigned: Vec<&Pdo> = got
                .iter()
                .filter(|g| g.sm != 0xFF)
                .map(|g| &g.pdo)
                .collect();
            let default: Vec<&Pdo> = p.default_mapping.pdos(dir).iter().collect();
            assert_eq!(assigned, default, "{name} {dir}: default assignment");
        }
        // DC modes: the ESI's, with the profile's AssignActivate; free run where the profile
        // has it.
        let dc = sii.category(category::DC).unwrap();
        assert_eq!(dc.len(), 24 * dev.dc.len());
        let mut assign = Vec::new();
        for (m, e) in dc.chunks(24).zip(&dev.dc) {
            assert_eq!(u32le(m, 0), e.mode.cycle_time0);
            assert_eq!(u32le(m, 4), e.mode.shift_time0 as u32);
            let aa = u16le(m, 14);
            assert_eq!(aa, e.mode.assign_activate);
            assert_eq!(sii.string(m[18]), Some(e.mode.name.as_str()));
            assign.push(aa);
        }
        assert!(
            assign.contains(&p.sync.assign_activate),
            "{name}: DC SYNC0 mode"
        );
        assert_eq!(
            assign.contains(&0),
            p.sync.free_run,
            "{name}: free run mode"
        );
    }
}

/// A drift between the ESI file and the emulated EEPROM cannot happen: an edited ESI gives an
/// edited SII.
#[test]
fn sii_follows_the_esi_text() {
    let p = &mr_j4_tm::PROFILE;
    let text = p.esi.replace(
        "<Sm DefaultSize=\"128\" StartAddress=\"#x1000\"",
        "<Sm DefaultSize=\"256\" StartAddress=\"#x1000\"",
    );
    assert_ne!(text, p.esi);
    let f = EsiFile::parse(&text).unwrap();
    let d = ecdrive_sim::sii::from_esi(f.vendor.id, &f.devices[0], 9).unwrap();
    assert_eq!(d.mailbox.unwrap().rx_size, 256);
    let d = ecdrive_sim::drives::description(p.key, 9).unwrap();
    assert_eq!(d.mailbox.as_ref().unwrap().rx_size, 128);
    assert_eq!(d.identity.serial, 9);
    // The generic profile has no ESI file and no emulation.
    let g = &ecdrive_core::drives::generic::GENERIC_CIA402;
    assert!(ecdrive_sim::drives::description(g.key, 0).is_err());
    assert!(ecdrive_sim::drives::emulated(g.key, 0).is_err());
}

/// `ecdrive sim --device` names: the registry's drives plus the test devices.
#[test]
fn device_names_come_from_the_registry() {
    let names = ecdrive_sim::devices::device_names();
    let keys: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
    assert_eq!(&keys[..2], ["mr-j4-tm", "bdhde"]);
    assert!(keys.contains(&"generic-coe"));
    assert!(names[0].1.contains("MR-J4-TM"));
    for (pos, key) in ["mr-j4-tm", "bdhde"].into_iter().enumerate() {
        let d = ecdrive_sim::devices::by_name(key, pos).unwrap();
        let desc = d.description();
        assert_eq!(desc.identity.serial, pos as u32);
        assert_eq!(
            desc.identity.product_code,
            ecdrive_core::drives::by_key(key)
                .unwrap()
                .identity
                .product_code
        );
    }
    let e = ecdrive_sim::devices::by_name("mr-j5", 0).err().unwrap();
    assert!(e.to_string().contains("mr-j4-tm, bdhde"), "{e}");
}
