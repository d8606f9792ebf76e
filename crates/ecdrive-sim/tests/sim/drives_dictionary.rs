//! Every object of both emulated drives read over CoE through the mailbox, compared with the
//! profile's dictionary and the ESI file; the remap rules with each refusal and its abort code;
//! the drives' write rules (0x1C32, RxPDO-mapped objects, auto-set objects, ranges).

use crate::support::wire;

use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive_core::ec::mailbox::{MailboxMessage, SdoRequest};
use ecdrive_core::esi::{EsiFile, ResolvedObject};
use ecdrive_core::od::{EntryAccess, ObjectAddress, SdoAbortCode, Value};
use ecdrive_sim::drives::spec_for;
use wire::Wire;

const PROFILES: [&DriveProfile; 2] = [&mr_j4_tm::PROFILE, &bdhde::PROFILE];

fn esi_objects(p: &DriveProfile) -> Vec<ResolvedObject> {
    let f = EsiFile::parse(p.esi).unwrap();
    f.device(p.identity.product_code, None)
        .unwrap()
        .dictionary()
        .unwrap()
        .resolve_all()
        .unwrap()
}

fn same(a: &Value, b: &Value) -> bool {
    match (a.as_i128(), b.as_i128()) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

fn code(c: SdoAbortCode) -> u32 {
    c.0
}

/// The code a drive answers for a standard refusal: its own where its manual lists no such code
/// (the emulated drive's `abort_codes` table, checked against the manuals in
/// `tests/app/manual_facts.rs`).
fn own(table: &[(SdoAbortCode, SdoAbortCode)], c: SdoAbortCode) -> u32 {
    table
        .iter()
        .find(|(std, _)| *std == c)
        .map_or(c, |(_, o)| *o)
        .0
}

/// Every entry of the dictionary is read over the wire. Readable entries return exactly their
/// type's size (strings up to it), decode as their type, and equal the default the profile and
/// the ESI file state, except the entries the drive keeps up to date itself; write-only entries
/// abort with 0x06010001. With SDO information (MR-J4-TM) every entry's type, length and access
/// as served equals the profile's. Absent objects and sub-indices abort as the standard says.
#[test]
fn every_object_reads_over_coe_as_the_esi_and_the_profile_say() {
    for p in PROFILES {
        let spec = spec_for(p.key).unwrap();
        let runtime = spec.runtime_objects();
        let esi = esi_objects(p);
        let mut w = Wire::drives(&[p]);
        w.preop(0);
        let list = w.od_list(0, 1);
        let sdo_info = list.is_some();
        if let Some(l) = &list {
            let want: Vec<u16> = p.dictionary.iter().map(|o| o.index).collect();
            assert_eq!(l, &want, "{}: the OD list is the dictionary", p.name);
        }
        let esi_coe = EsiFile::parse(p.esi).unwrap().devices[0]
            .mailbox
            .clone()
            .unwrap()
            .coe
            .unwrap();
        assert_eq!(sdo_info, esi_coe.sdo_info, "{}: SDO information", p.name);
        let mut read = 0;
        let mut compared = 0;
        for o in p.dictionary {
            let e_obj = esi.iter().find(|x| x.index == o.index).unwrap();
            for e in o.entries {
                let at = format!("{} 0x{:04X}:{:02X}", p.name, o.index, e.sub);
                let addr = ObjectAddress::new(o.index, e.sub);
                if sdo_info {
                    let (dt, bits, access) = w.entry_description(0, o.index, e.sub).unwrap();
                    assert_eq!(dt, e.data_type.code(), "{at}: data type");
                    assert_eq!(bits, e.bit_len, "{at}: bit length");
                    let mask =
                        (EntryAccess::R | EntryAccess::W | EntryAccess::RXPDO | EntryAccess::TXPDO)
                            .bits();
                    assert_eq!(access & mask, e.access.bits() & mask, "{at}: access");
                }
                let r = w.upload(0, o.index, e.sub);
                if !e.access.readable() {
                    assert_eq!(r, Err(code(SdoAbortCode::WRITE_ONLY)), "{at}");
                    continue;
                }
                let bytes = r.unwrap_or_else(|c| panic!("{at}: abort 0x{c:08X}"));
                read += 1;
                let size = usize::from(e.bit_len).div_ceil(8);
                if e.data_type.is_string() {
                    assert!(bytes.len() <= size, "{at}: {} bytes", bytes.len());
                } else {
                    assert_eq!(bytes.len(), size, "{at}: length");
                }
                let v = Value::decode(e.data_type, &bytes).unwrap();
                if runtime.contains(&addr) {
                    continue;
                }
                if let Some(d) = e.default.to_value() {
                    assert!(same(&v, &d), "{at}: read {v}, profile default {d}");
                    compared += 1;
                }
                if let Some(d) = e_obj.entry(e.sub).and_then(|x| x.default.clone()) {
                    assert!(same(&v, &d), "{at}: read {v}, ESI default {d}");
                }
            }
        }
        assert!(read > 150, "{}: {read} entries read", p.name);
        assert!(compared > 100, "{}: {compared} defaults compared", p.name);
        // Absent objects and sub-indices.
        let absent = if p.key == "mr-j4-tm" { 0x60C2 } else { 0x1C32 };
        assert_eq!(w.upload(0, absent, 0), Err(code(SdoAbortCode::NO_OBJECT)));
        assert_eq!(w.upload(0, 0x6041, 1), Err(code(SdoAbortCode::NO_SUBINDEX)));
        assert_eq!(w.upload(0, 0x1018, 5), Err(code(SdoAbortCode::NO_SUBINDEX)));
        // The identity object agrees with the profile; the serial is the drive's own.
        assert_eq!(w.read_u32(0, 0x1018, 1), p.identity.vendor_id);
        assert_eq!(w.read_u32(0, 0x1018, 2), p.identity.product_code);
        assert_eq!(w.read_u32(0, 0x1018, 3), p.revision);
        assert_eq!(w.read_u32(0, 0x1018, 4), 1);
    }
}

/// Complete access is refused on both drives: by the MR-J4-TM as a stack without it answers
/// (0x06010000, unsupported access), by the BDHDE with the code its manual's Table 10-2 gives
/// for it (0x06010004, "cannot be accessed via complete access").
#[test]
fn no_complete_access() {
    for p in PROFILES {
        let mut w = Wire::drives(&[p]);
        w.preop(0);
        let r = w.complete_access_upload(0, 0x1C12);
        let want = if p.name == "BDHDE" {
            SdoAbortCode::COMPLETE_ACCESS_UNSUPPORTED
        } else {
            SdoAbortCode::UNSUPPORTED_ACCESS
        };
        assert_eq!(r, code(want), "{}", p.name);
    }
}

trait CompleteAccess {
    fn complete_access_upload(&mut self, pos: usize, index: u16) -> u32;
}

impl CompleteAccess for Wire {
    fn complete_access_upload(&mut self, pos: usize, index: u16) -> u32 {
        // Build the request by hand through the public SDO request type.
        let req = SdoRequest::Upload {
            index,
            sub: 0,
            complete_access: true,
        };
        let mut msg = vec![0u8; 128];
        let n = req.emit_mailbox(3, &mut msg).unwrap();
        assert!(n <= 128);
        let st = Wire::station(pos);
        assert_eq!(self.p.fpwr(st, 0x1000, &msg).unwrap().wkc, 1);
        let r = self.p.fprd(st, 0x1080, 128).unwrap();
        assert_eq!(r.wkc, 1);
        match MailboxMessage::parse(&r.data).unwrap().1 {
            MailboxMessage::SdoRequest(SdoRequest::Abort { code, .. }) => code,
            MailboxMessage::SdoResponse(ecdrive_core::ec::mailbox::SdoResponse::Abort {
                code,
                ..
            }) => code,
            other => panic!("{other:?}"),
        }
    }
}

/// MR-J4-TM remapping: every refusal with its abort code, then the recommended mapping.
#[test]
fn mr_j4_remap_rules() {
    let p = &mr_j4_tm::PROFILE;
    let mut w = Wire::drives(&[p]);
    w.preop(0);
    let c = |x| own(ecdrive_sim::drives::mr_j4_tm::REC_ABORT_CODES, x);
    // Entries only with sub 0 = 0.
    assert_eq!(
        w.write_u32(0, 0x1600, 1, 0x6040_0010),
        Err(c(SdoAbortCode::SUBINDEX0_NOT_ZERO))
    );
    w.write_u8(0, 0x1C12, 0, 0).unwrap();
    w.write_u8(0, 0x1600, 0, 0).unwrap();
    // Not RxPDO-mappable: a communication object, a TxPDO object, a missing object.
    for bad in [0x1000_0020, 0x6041_0010, 0x9999_0010] {
        assert_eq!(
            w.write_u32(0, 0x1600, 1, bad),
            Err(c(SdoAbortCode::NOT_MAPPABLE)),
            "0x{bad:08X}"
        );
    }
    // The wrong length for the object.
    assert_eq!(
        w.write_u32(0, 0x1600, 1, 0x6040_0008),
        Err(c(SdoAbortCode::LENGTH_MISMATCH))
    );
    // 32 entries at most; sub-index 33 does not exist.
    assert_eq!(
        w.write_u32(0, 0x1600, 33, 0x6040_0010),
        Err(c(SdoAbortCode::NO_SUBINDEX))
    );
    assert_eq!(
        w.write_u8(0, 0x1600, 0, 33),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // 64 bytes at most: 17 × 32 bits is refused when sub 0 is written.
    for k in 1..=17 {
        w.write_u32(0, 0x1600, k, 0x607A_0020).unwrap();
    }
    assert_eq!(
        w.write_u8(0, 0x1600, 0, 17),
        Err(c(SdoAbortCode::PDO_TOO_LONG))
    );
    w.write_u8(0, 0x1600, 0, 16).unwrap();
    w.write_u8(0, 0x1600, 0, 0).unwrap();
    // Sub 0 cannot count an entry that was never written.
    w.write_u32(0, 0x1603, 1, 0x6040_0010).unwrap();
    assert_eq!(
        w.write_u8(0, 0x1603, 0, 2),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // Assignment: only RxPDO mapping objects of the drive (the entry's range 0x1600–0x1603),
    // one per SyncManager.
    for (bad, abort) in [
        (0x1A00u16, SdoAbortCode::VALUE_TOO_HIGH),
        (0x1604, SdoAbortCode::VALUE_TOO_HIGH),
        (0x1000, SdoAbortCode::VALUE_TOO_LOW),
    ] {
        assert_eq!(w.write_u16(0, 0x1C12, 1, bad), Err(c(abort)), "0x{bad:04X}");
    }
    w.write_u16(0, 0x1C12, 2, 0x1601).unwrap();
    assert_eq!(
        w.write_u8(0, 0x1C12, 0, 2),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // Back to a consistent state, then the recommended mapping with the standard sequence.
    w.write_u32(0, 0x1600, 1, 0x6040_0010).unwrap();
    w.write_u8(0, 0x1600, 0, 1).unwrap();
    w.write_u8(0, 0x1C12, 0, 1).unwrap();
    wire::remap(&mut w, 0, &p.cyclic_mapping);
    let back = ecdrive_core::pdo::read_mapping_sync(|a, _| {
        w.upload(0, a.index, a.sub).map(|b| {
            let mut raw = [0u8; 4];
            raw[..b.len()].copy_from_slice(&b);
            u32::from_le_bytes(raw)
        })
    })
    .unwrap();
    assert_eq!(back, p.cyclic_mapping);
    // Outside PRE-OP the mapping and the assignment refuse writes.
    let m = &p.cyclic_mapping;
    w.configure_pd(&[(
        m.bytes(ecdrive_core::pdo::Direction::Rx),
        m.bytes(ecdrive_core::pdo::Direction::Tx),
    )]);
    assert_eq!(w.request(0, 0x0004), (0x0004, 0));
    assert_eq!(
        w.write_u8(0, 0x1C12, 0, 0),
        Err(c(SdoAbortCode::DEVICE_STATE))
    );
    assert_eq!(
        w.write_u8(0, 0x1A00, 0, 0),
        Err(c(SdoAbortCode::DEVICE_STATE))
    );
    assert_eq!(
        w.write_u32(0, 0x1C32, 2, 1_000_000),
        Err(c(SdoAbortCode::DEVICE_STATE))
    );
}

/// MR-J4-TM write rules: 0x1C32, RxPDO-mapped objects, auto-set objects, ranges, access.
#[test]
fn mr_j4_write_rules() {
    let p = &mr_j4_tm::PROFILE;
    let mut w = Wire::drives(&[p]);
    w.preop(0);
    let c = code;
    // 0x1C32:02: 250/500/1000/2000 µs only, mirrored into 0x1C33:02 (and back).
    for ns in [250_000u32, 500_000, 1_000_000, 2_000_000] {
        w.write_u32(0, 0x1C32, 2, ns).unwrap();
        assert_eq!(w.read_u32(0, 0x1C33, 2), ns);
    }
    for ns in [0u32, 125_000, 750_000, 4_000_000] {
        assert_eq!(
            w.write_u32(0, 0x1C32, 2, ns),
            Err(c(SdoAbortCode::VALUE_RANGE)),
            "{ns}"
        );
    }
    w.write_u32(0, 0x1C33, 2, 500_000).unwrap();
    assert_eq!(w.read_u32(0, 0x1C32, 2), 500_000);
    // 0x1C32:01: 0 free run or 2 DC SYNC0, mirrored.
    for bad in [1u16, 3] {
        assert_eq!(
            w.write_u16(0, 0x1C32, 1, bad),
            Err(c(SdoAbortCode::VALUE_RANGE))
        );
    }
    w.write_u16(0, 0x1C32, 1, 2).unwrap();
    assert_eq!(w.read_u32(0, 0x1C33, 1), 2);
    // Shift times are set by the drive.
    assert_eq!(
        w.write_u32(0, 0x1C32, 3, 0),
        Err(c(SdoAbortCode::VALUE_RANGE))
    );
    assert_eq!(
        w.write_u32(0, 0x1C33, 3, 0),
        Err(c(SdoAbortCode::VALUE_RANGE))
    );
    assert_eq!(w.read_u32(0, 0x1C32, 3), 222_222);
    // Objects mapped in the RxPDO (the default 0x1600) refuse SDO downloads.
    for (index, data) in [
        (0x6040u16, vec![0u8, 0]),
        (0x6060, vec![9]),
        (0x60E0, 5000u16.to_le_bytes().to_vec()),
        (0x2D20, 1000u32.to_le_bytes().to_vec()),
    ] {
        assert_eq!(
            w.download(0, index, 0, &data),
            Err(c(SdoAbortCode::MAPPED_TO_RXPDO)),
            "0x{index:04X}"
        );
    }
    // An unmapped writable object is fine; after a remap that drops 0x60E0 it is writable too.
    w.write_u32(0, 0x6065, 0, 4_194_304).unwrap();
    wire::remap(&mut w, 0, &p.cyclic_mapping);
    w.write_u16(0, 0x60E0, 0, 5000).unwrap();
    assert_eq!(
        w.write_u16(0, 0x60E0, 0, 10_001),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    assert_eq!(
        w.download(0, 0x6040, 0, &[0, 0]),
        Err(c(SdoAbortCode::MAPPED_TO_RXPDO))
    );
    // Auto-set objects refuse every write with 0x06090030.
    for (a, data) in [
        (ObjectAddress::new(0x607C, 0), 0u32.to_le_bytes().to_vec()),
        (ObjectAddress::new(0x607B, 1), 0u32.to_le_bytes().to_vec()),
        (
            ObjectAddress::new(0x608F, 1),
            4_194_304u32.to_le_bytes().to_vec(),
        ),
        (ObjectAddress::new(0x6092, 1), 1u32.to_le_bytes().to_vec()),
        (ObjectAddress::new(0x60A8, 0), 0u32.to_le_bytes().to_vec()),
        (ObjectAddress::new(0x60A9, 0), 0u32.to_le_bytes().to_vec()),
    ] {
        assert_eq!(
            w.download(0, a.index, a.sub, &data),
            Err(c(SdoAbortCode::VALUE_RANGE)),
            "{a}"
        );
    }
    assert_eq!(w.read_u32(0, 0x60A9, 0), 0xFEB4_4700, "0.01 r/min");
    // 0x10F1:02 in the automatic threshold mode: refused by local control (B4+).
    assert_eq!(
        w.write_u32(0, 0x10F1, 2, 21),
        Err(c(SdoAbortCode::LOCAL_CONTROL))
    );
    // Single-value objects.
    assert_eq!(
        w.write_u16(0, 0x605A, 0, 1),
        Err(c(SdoAbortCode::VALUE_TOO_LOW))
    );
    assert_eq!(
        w.write_u16(0, 0x605A, 0, 6),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    w.write_u16(0, 0x605A, 0, 2).unwrap();
    assert_eq!(
        w.download(0, 0x6086, 0, &0i16.to_le_bytes()),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // Access and length.
    assert_eq!(
        w.write_u16(0, 0x6041, 0, 0),
        Err(c(SdoAbortCode::READ_ONLY))
    );
    assert_eq!(w.upload(0, 0x2A40, 0), Err(c(SdoAbortCode::WRITE_ONLY)));
    assert_eq!(
        w.write_u16(0, 0x2A40, 0, 0x1234),
        Err(c(SdoAbortCode::VALUE_RANGE))
    );
    w.write_u16(0, 0x2A40, 0, 0x1EA5).unwrap();
    assert_eq!(
        w.write_u16(0, 0x6065, 0, 1),
        Err(c(SdoAbortCode::LENGTH_TOO_LOW))
    );
    assert_eq!(
        w.download(0, 0x6065, 0, &[1, 0, 0, 0, 0]),
        Err(c(SdoAbortCode::LENGTH_TOO_HIGH))
    );
    // The mode is mapped in the recommended mapping as well: it is set by PDO only.
    assert_eq!(
        w.download(0, 0x6060, 0, &[9]),
        Err(c(SdoAbortCode::MAPPED_TO_RXPDO))
    );
    // Without it in the mapping, 0x6060 takes the values of 0x6502 only.
    let mut m = p.cyclic_mapping.clone();
    m.rx.to_mut()[0].entries.to_mut().pop();
    wire::remap(&mut w, 0, &m);
    assert_eq!(
        w.download(0, 0x6060, 0, &[2]),
        Err(c(SdoAbortCode::VALUE_RANGE))
    );
    w.download(0, 0x6060, 0, &[(-101i8) as u8]).unwrap();
    w.download(0, 0x6060, 0, &[9]).unwrap();
}

/// BDHDE remapping and write rules.
#[test]
fn bdhde_remap_and_write_rules() {
    let p = &bdhde::PROFILE;
    let mut w = Wire::drives(&[p]);
    w.preop(0);
    let c = |x| own(ecdrive_sim::drives::bdhde::REC_ABORT_CODES, x);
    assert_eq!(
        w.write_u32(0, 0x1600, 1, 0x6040_0010),
        Err(c(SdoAbortCode::SUBINDEX0_NOT_ZERO))
    );
    w.write_u8(0, 0x1C12, 0, 0).unwrap();
    // 0x1600 holds 8 entries, 0x1601–0x1603 two.
    w.write_u8(0, 0x1600, 0, 0).unwrap();
    assert_eq!(
        w.write_u8(0, 0x1600, 0, 9),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    assert_eq!(
        w.write_u32(0, 0x1600, 9, 0x6040_0010),
        Err(c(SdoAbortCode::NO_SUBINDEX))
    );
    w.write_u8(0, 0x1601, 0, 0).unwrap();
    assert_eq!(
        w.write_u32(0, 0x1601, 3, 0x6040_0010),
        Err(c(SdoAbortCode::NO_SUBINDEX))
    );
    assert_eq!(
        w.write_u8(0, 0x1601, 0, 3),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // 0x6066 is not mappable on this drive (chapter 9), nor is a TxPDO object.
    for bad in [0x6066_0010u32, 0x6064_0020] {
        assert_eq!(
            w.write_u32(0, 0x1600, 1, bad),
            Err(c(SdoAbortCode::NOT_MAPPABLE)),
            "0x{bad:08X}"
        );
    }
    // One PDO per SyncManager.
    w.write_u16(0, 0x1C12, 1, 0x1600).unwrap();
    assert_eq!(
        w.write_u8(0, 0x1C12, 0, 2),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // The entry's range is 0x1600–0x17FF (§7 1C12h).
    assert_eq!(
        w.write_u16(0, 0x1C12, 1, 0x1A00),
        Err(c(SdoAbortCode::VALUE_TOO_HIGH))
    );
    // Restore 0x1600 and 0x1601, then the recommended mapping.
    let defaults = [0x1600u16, 0x1601];
    for (i, pdo) in defaults.iter().enumerate() {
        let d = &bdhde::RX_PDOS[i];
        for (k, e) in d.entries.iter().enumerate() {
            w.write_u32(0, *pdo, k as u8 + 1, e.to_u32()).unwrap();
        }
        w.write_u8(0, *pdo, 0, d.entries.len() as u8).unwrap();
    }
    w.write_u8(0, 0x1C12, 0, 1).unwrap();
    wire::remap(&mut w, 0, &p.cyclic_mapping);
    // This drive takes SDO downloads to mapped objects.
    w.download(0, 0x6040, 0, &[0, 0]).unwrap();
    // Write rules.
    assert_eq!(
        w.write_u16(0, 0x605A, 0, 1),
        Err(c(SdoAbortCode::VALUE_RANGE))
    );
    for qs in [0u16, 2, 6] {
        w.write_u16(0, 0x605A, 0, qs).unwrap();
    }
    assert_eq!(
        w.download(0, 0x6060, 0, &[7]),
        Err(c(SdoAbortCode::VALUE_RANGE)),
        "ip"
    );
    assert_eq!(
        w.download(0, 0x6060, 0, &[2]),
        Err(c(SdoAbortCode::VALUE_RANGE)),
        "vl"
    );
    w.download(0, 0x6060, 0, &[8]).unwrap();
    assert_eq!(
        w.write_u8(0, 0x607E, 0, 0x40),
        Err(c(SdoAbortCode::VALUE_RANGE))
    );
    // 0x60C2: −4 at power-on (the drive's 250 µs unit, §2.4); the standard form its own
    // set-up example writes (1 and −3 for 1 ms) is taken too; :01 is never 0, :02 a power of
    // ten of seconds down to −9.
    assert_eq!(w.upload(0, 0x60C2, 2).unwrap(), vec![0xFC], "-4");
    assert_eq!(
        w.write_u8(0, 0x60C2, 1, 0),
        Err(c(SdoAbortCode::VALUE_TOO_LOW))
    );
    w.write_u8(0, 0x60C2, 1, 2).unwrap();
    w.write_u8(0, 0x60C2, 2, 0xFD).unwrap();
    assert_eq!(w.upload(0, 0x60C2, 2).unwrap(), vec![0xFD], "-3");
    assert_eq!(
        w.write_u8(0, 0x60C2, 2, 0xF6),
        Err(c(SdoAbortCode::VALUE_TOO_LOW)),
        "-10"
    );
    w.write_u8(0, 0x60C2, 2, 0xFC).unwrap();
    // No 0x1C32 on this drive.
    assert_eq!(
        w.write_u16(0, 0x1C32, 1, 2),
        Err(c(SdoAbortCode::NO_OBJECT))
    );
    // Outside PRE-OP no remapping.
    safeop_cyclic(&mut w, p);
    assert_eq!(
        w.write_u8(0, 0x1C12, 0, 0),
        Err(c(SdoAbortCode::DEVICE_STATE))
    );
    assert_eq!(
        w.write_u8(0, 0x1600, 0, 0),
        Err(c(SdoAbortCode::DEVICE_STATE))
    );
}

fn safeop_cyclic(w: &mut Wire, p: &DriveProfile) {
    let m = &p.cyclic_mapping;
    w.configure_pd(&[(
        m.bytes(ecdrive_core::pdo::Direction::Rx),
        m.bytes(ecdrive_core::pdo::Direction::Tx),
    )]);
    assert_eq!(w.request(0, 0x0004), (0x0004, 0), "{}: SAFE-OP", p.name);
}

/// PRE-OP → SAFE-OP checks the SyncManager lengths against the mapping (the ESC) and the
/// mapping against the drive (the drive).
#[test]
fn safe_op_needs_matching_process_data() {
    for p in PROFILES {
        let mut w = Wire::drives(&[p]);
        w.preop(0);
        w.configure_pd(&[(3, 3)]);
        let (status, code) = w.request(0, 0x0004);
        assert_eq!(status & 0x0F, 0x02, "{}: stays in PRE-OP", p.name);
        assert_eq!(code, 0x001D, "{}: invalid output configuration", p.name);
        let m = &p.default_mapping;
        w.configure_pd(&[(
            m.bytes(ecdrive_core::pdo::Direction::Rx),
            m.bytes(ecdrive_core::pdo::Direction::Tx),
        )]);
        assert_eq!(w.request_ack(0, 0x0004), (0x0004, 0), "{}", p.name);
    }
}
