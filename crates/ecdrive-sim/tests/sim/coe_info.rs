//! SDO information through the CoE server (ETG.1000.6 §5.6.3): OD lists of every type, object
//! and entry descriptions, fragmentation when a response exceeds the mailbox, errors.

use crate::coe_util;

use coe_util::{Rig, hex};
use ecdrive_core::ec::mailbox::{EntryDescription, MailboxMessage, ObjectDescription, OdList};
use ecdrive_sim::coe::CoeConfig;

/// The fixture's indices in ascending order.
const ALL: [u16; 26] = [
    0x1000, 0x1001, 0x1008, 0x1018, 0x1600, 0x1601, 0x1A00, 0x1A01, 0x1C00, 0x1C12, 0x1C13, 0x1C32,
    0x1C33, 0x2000, 0x2001, 0x2002, 0x2003, 0x2004, 0x6040, 0x6041, 0x6060, 0x6061, 0x6064, 0x607A,
    0x607D, 0x60FF,
];

fn le16(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn od_list_req(cnt: u8, list_type: u16) -> Vec<u8> {
    let mut v = hex(&format!(
        "08 00 00 00 00 {:02X}  00 80  01 00 00 00",
        0x03 | (cnt << 4)
    ));
    v.extend_from_slice(&list_type.to_le_bytes());
    v
}

/// Send a request and collect all fragments (first as the reply, the rest as unsolicited
/// messages), checking the fragment headers; returns the reassembled service data.
fn collect(rig: &mut Rig, req: &[u8], opcode: u8) -> (Vec<u8>, usize) {
    let mut frag = rig.send(req).expect("a first fragment");
    let mut data = Vec::new();
    let mut count = 0;
    loop {
        count += 1;
        assert_eq!(frag[5] & 0x0F, 0x03, "CoE");
        assert_eq!(frag[6..8], [0x00, 0x80], "service 8, SDO information");
        assert_eq!(frag[8] & 0x7F, opcode);
        let incomplete = frag[8] & 0x80 != 0;
        let left = u16::from_le_bytes([frag[10], frag[11]]);
        assert_eq!(
            incomplete,
            left > 0,
            "incomplete bit iff fragments are left"
        );
        data.extend_from_slice(&frag[12..]);
        if !incomplete {
            break;
        }
        let next = rig.poll().expect("the next fragment when SM1 is free");
        assert_eq!(
            u16::from_le_bytes([next[10], next[11]]),
            left - 1,
            "fragments left counts down"
        );
        frag = next;
    }
    assert_eq!(rig.poll(), None, "nothing after the last fragment");
    (data, count)
}

#[test]
fn od_list_all_in_one_message() {
    let mut rig = Rig::new();
    let mut expect = hex("3C 00 00 00 00 13  00 80  02 00 00 00  01 00");
    expect.extend_from_slice(&le16(&ALL));
    assert_eq!(rig.send(&od_list_req(1, 1)), Some(expect));
    assert_eq!(rig.poll(), None);
}

#[test]
fn od_list_all_is_fragmented_in_a_small_mailbox() {
    // SM1 of 32 bytes: 20 bytes of service data per fragment; 2 + 52 bytes → 3 fragments.
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    let first = rig.send(&od_list_req(1, 1)).unwrap();
    let mut expect = hex("1A 00 00 00 00 13  00 80  82 00 02 00  01 00");
    expect.extend_from_slice(&le16(&ALL[..9]));
    assert_eq!(first, expect);
    let second = rig.poll().unwrap();
    let mut expect = hex("1A 00 00 00 00 23  00 80  82 00 01 00");
    expect.extend_from_slice(&le16(&ALL[9..19]));
    assert_eq!(second, expect);
    let third = rig.poll().unwrap();
    let mut expect = hex("14 00 00 00 00 33  00 80  02 00 00 00");
    expect.extend_from_slice(&le16(&ALL[19..]));
    assert_eq!(third, expect);
    assert_eq!(rig.poll(), None);
    // SOEM's arithmetic: (len − 8) / 2 indices in the first fragment, (len − 6) / 2 after.
    let n = |f: &Vec<u8>, first: bool| {
        (u16::from_le_bytes([f[0], f[1]]) as usize - if first { 8 } else { 6 }) / 2
    };
    assert_eq!(n(&first, true) + n(&second, false) + n(&third, false), 26);
}

#[test]
fn od_list_types_and_quantities() {
    let mut rig = Rig::with(CoeConfig::default(), 24, 24);
    let (data, _) = collect(&mut rig, &od_list_req(1, 0), 2);
    // List type 0, then the lengths of lists 1..5.
    assert_eq!(data, le16(&[0, 26, 4, 3, 2, 2]));
    let (data, _) = collect(&mut rig, &od_list_req(2, 2), 2);
    let l = OdList::parse(&data).unwrap();
    assert_eq!(l.list_type, 2);
    assert_eq!(
        l.values().collect::<Vec<_>>(),
        [0x6040, 0x6060, 0x607A, 0x60FF]
    );
    let (data, _) = collect(&mut rig, &od_list_req(3, 3), 2);
    assert_eq!(data, le16(&[3, 0x6041, 0x6061, 0x6064]));
    let (data, _) = collect(&mut rig, &od_list_req(4, 4), 2);
    assert_eq!(data, le16(&[4, 0x2002, 0x607D]));
    let (data, _) = collect(&mut rig, &od_list_req(5, 5), 2);
    assert_eq!(data, le16(&[5, 0x2002, 0x607D]));
    let (data, frags) = collect(&mut rig, &od_list_req(6, 1), 2);
    assert_eq!(data[2..], le16(&ALL));
    assert_eq!(frags, 54usize.div_ceil(12));
}

#[test]
fn od_list_of_an_unknown_type_is_an_info_error() {
    let mut rig = Rig::new();
    assert_eq!(
        rig.send(&od_list_req(1, 9)),
        Some(hex("0A 00 00 00 00 13  00 80  07 00 00 00  00 00 01 06"))
    );
}

#[test]
fn object_descriptions() {
    let mut rig = Rig::new();
    // RECORD 0x1018: data type 0 (no structure type), max sub 4, object code 9.
    let mut expect = hex("14 00 00 00 00 13  00 80  04 00 00 00  18 10 00 00 04 09");
    expect.extend_from_slice(b"Identity");
    assert_eq!(
        rig.send(&hex("08 00 00 00 00 13  00 80  03 00 00 00  18 10")),
        Some(expect)
    );
    // ARRAY 0x1C00: element type UNSIGNED8, max sub 4, code 8.
    let r = rig
        .send(&hex("08 00 00 00 00 23  00 80  03 00 00 00  00 1C"))
        .unwrap();
    let d = ObjectDescription::parse(&r[12..]).unwrap();
    assert_eq!(
        (d.index, d.data_type, d.max_sub, d.object_code),
        (0x1C00, 0x0005, 4, 8)
    );
    assert_eq!(d.name, b"Sync manager communication type");
    // VAR 0x6041: UNSIGNED16, max sub 0, code 7. SOEM: name length = len − 12.
    let r = rig
        .send(&hex("08 00 00 00 00 33  00 80  03 00 00 00  41 60"))
        .unwrap();
    assert_eq!(r[12..18], hex("41 60 06 00 00 07"));
    assert_eq!(
        u16::from_le_bytes([r[0], r[1]]) as usize - 12,
        "Statusword".len()
    );
    // Missing object: SDO information error 0x06020000.
    assert_eq!(
        rig.send(&hex("08 00 00 00 00 43  00 80  03 00 00 00  55 55")),
        Some(hex("0A 00 00 00 00 43  00 80  07 00 00 00  00 00 02 06"))
    );
}

#[test]
fn object_description_is_fragmented_in_a_tiny_mailbox() {
    // SM1 of 16 bytes: 4 bytes per fragment; 6 + 24 bytes → 8 fragments.
    let mut rig = Rig::with(CoeConfig::default(), 16, 16);
    let (data, frags) = collect(
        &mut rig,
        &hex("08 00 00 00 00 13  00 80  03 00 00 00  08 10"),
        4,
    );
    assert_eq!(frags, 8);
    let d = ObjectDescription::parse(&data).unwrap();
    assert_eq!(d.index, 0x1008);
    assert_eq!(d.data_type, 0x0009);
    assert_eq!(d.name, b"Manufacturer device name");
}

#[test]
fn entry_descriptions_with_value_info() {
    let mut rig = Rig::new();
    // 0x1018:02, asking for unit, default, minimum and maximum: only the default exists.
    let mut expect =
        hex("20 00 00 00 00 13  00 80  06 00 00 00  18 10 02 10  07 00  20 00  07 00  02 04 00 00");
    expect.extend_from_slice(b"Product code");
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 80  05 00 00 00  18 10 02 78")),
        Some(expect)
    );
    // 0x2002: INTEGER16 range −100..100, RW in every state + backup + settings (0x033F).
    let r = rig
        .send(&hex("0A 00 00 00 00 23  00 80  05 00 00 00  02 20 00 78"))
        .unwrap();
    let mut expect = hex("02 20 00 70  03 00  10 00  3F 03  00 00  9C FF  64 00");
    expect.extend_from_slice(b"Limited value");
    assert_eq!(r[12..], expect);
    let e = EntryDescription::parse(&r[12..]).unwrap();
    let v = e.values().unwrap();
    assert_eq!(v.minimum, Some(&[0x9C, 0xFF][..]));
    assert_eq!(v.name, b"Limited value");
    // As SOEM asks (value info 7): name only, its length is mailbox length − 16.
    let r = rig
        .send(&hex("0A 00 00 00 00 33  00 80  05 00 00 00  40 60 00 07"))
        .unwrap();
    assert_eq!(r[15], 0x00, "no optional fields");
    assert_eq!(
        u16::from_le_bytes([r[0], r[1]]) as usize - 16,
        "Controlword".len()
    );
    assert_eq!(&r[22..], b"Controlword");
    // ObjAccess: RW (0x3F) + RxPDO mappable (0x40).
    assert_eq!(r[20..22], [0x7F, 0x00]);
    // A string default fills the entry size (16 bytes).
    let r = rig
        .send(&hex("0A 00 00 00 00 43  00 80  05 00 00 00  04 20 00 10"))
        .unwrap();
    assert_eq!(r[15], 0x10);
    assert_eq!(&r[22..38], b"hello\0\0\0\0\0\0\0\0\0\0\0");
    assert_eq!(&r[38..], b"User text");
}

#[test]
fn entry_description_errors() {
    let mut rig = Rig::new();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 80  05 00 00 00  18 10 07 00")),
        Some(hex("0A 00 00 00 00 13  00 80  07 00 00 00  11 00 09 06"))
    );
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 80  05 00 00 00  55 55 00 00")),
        Some(hex("0A 00 00 00 00 23  00 80  07 00 00 00  00 00 02 06"))
    );
    // Unknown opcode: info error "invalid command".
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 80  09 00 00 00  00 00 00 00")),
        Some(hex("0A 00 00 00 00 33  00 80  07 00 00 00  01 00 04 05"))
    );
    // Truncated request (no index): mailbox error "size too short".
    assert_eq!(
        rig.send(&hex("06 00 00 00 00 43  00 80  03 00 00 00")),
        Some(hex("04 00 00 00 00 40  01 00 06 00"))
    );
}

#[test]
fn a_new_request_ends_a_fragmented_response() {
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    rig.send(&od_list_req(1, 1)).unwrap();
    assert!(rig.server.has_unsolicited());
    // The master moves on (e.g. after a timeout): the rest is dropped, the upload answered.
    let r = rig.send(&coe_util::upload_req(2, 0x1000, 0)).unwrap();
    assert_eq!(r[8], 0x43);
    assert_eq!(rig.poll(), None);
}

#[test]
fn sdo_information_can_be_switched_off() {
    let config = CoeConfig {
        sdo_info: false,
        ..CoeConfig::default()
    };
    let mut rig = Rig::with(config, 128, 128);
    // Mailbox error reply, type 0, detail 4 (service not supported).
    assert_eq!(
        rig.send(&od_list_req(1, 1)),
        Some(hex("04 00 00 00 00 10  01 00 04 00"))
    );
}

#[test]
fn fragments_parse_with_the_mailbox_views() {
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    let first = rig.send(&od_list_req(1, 1)).unwrap();
    match MailboxMessage::parse(&first).unwrap() {
        (1, MailboxMessage::SdoInfo(f)) => {
            assert!(f.incomplete);
            assert_eq!(f.fragments_left, 2);
            assert_eq!(f.data.len(), 20);
        }
        other => panic!("unexpected {other:?}"),
    }
}
