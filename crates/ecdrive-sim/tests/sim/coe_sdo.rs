//! SDO transfers through the CoE server, byte for byte as ETG.1000.6 §5.6.2 lays them out:
//! expedited, normal and segmented, both ways; complete access; toggles; aborts.

use crate::coe_util;

use coe_util::{Rig, abort_reply, download_req, hex, upload_req};
use ecdrive_core::ec::AlState;
use ecdrive_core::od::{ObjectAddress, SdoAbortCode, Value};
use ecdrive_core::pdo::{Direction, PdoEntry};
use ecdrive_sim::coe::{CoeConfig, fixture};

fn addr(index: u16, sub: u8) -> ObjectAddress {
    ObjectAddress::new(index, sub)
}

#[test]
fn expedited_upload_of_4_2_and_1_bytes() {
    let mut rig = Rig::new();
    rig.od.set_uint(addr(0x6041, 0), 0x0237).unwrap();
    // 0x1000 UNSIGNED32 = 0x00020192: command 0x43 (e = 1, s = 1, n = 0).
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 20  40 00 10 00  00 00 00 00")),
        Some(hex("0A 00 00 00 00 13  00 30  43 00 10 00  92 01 02 00"))
    );
    // 0x6041 UNSIGNED16: command 0x4B (n = 2 unused bytes).
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  40 41 60 00  00 00 00 00")),
        Some(hex("0A 00 00 00 00 23  00 30  4B 41 60 00  37 02 00 00"))
    );
    // 0x6060 INTEGER8 = 8: command 0x4F (n = 3).
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  40 60 60 00  00 00 00 00")),
        Some(hex("0A 00 00 00 00 33  00 30  4F 60 60 00  08 00 00 00"))
    );
}

#[test]
fn pdo_configuration_is_always_uploaded_expedited() {
    // ethercrab reads 0x1C12:00 (u8), 0x1C12:01 (u16) and mapping entries (u32) expedited only.
    let mut rig = Rig::new();
    assert_eq!(
        rig.send(&upload_req(1, 0x1C12, 0)),
        Some(hex("0A 00 00 00 00 13  00 30  4F 12 1C 00  01 00 00 00"))
    );
    assert_eq!(
        rig.send(&upload_req(2, 0x1C12, 1)),
        Some(hex("0A 00 00 00 00 23  00 30  4B 12 1C 01  00 16 00 00"))
    );
    assert_eq!(
        rig.send(&upload_req(3, 0x1600, 2)),
        Some(hex("0A 00 00 00 00 33  00 30  43 00 16 02  20 00 7A 60"))
    );
}

#[test]
fn expedited_download_of_1_2_and_4_bytes() {
    let mut rig = Rig::new();
    // 0x6060 INTEGER8 := -1: command 0x2F.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 20  2F 60 60 00  FF 00 00 00")),
        Some(hex("0A 00 00 00 00 13  00 30  60 60 60 00  00 00 00 00"))
    );
    // 0x6040 UNSIGNED16 := 0x000F: command 0x2B.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  2B 40 60 00  0F 00 00 00")),
        Some(hex("0A 00 00 00 00 23  00 30  60 40 60 00  00 00 00 00"))
    );
    // 0x607A INTEGER32 := -100000: command 0x23.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  23 7A 60 00  60 79 FE FF")),
        Some(hex("0A 00 00 00 00 33  00 30  60 7A 60 00  00 00 00 00"))
    );
    assert_eq!(rig.od.int(addr(0x6060, 0)), Some(-1));
    assert_eq!(rig.od.uint(addr(0x6040, 0)), Some(0x000F));
    assert_eq!(rig.od.int(addr(0x607A, 0)), Some(-100_000));
}

#[test]
fn normal_upload_and_download() {
    let mut rig = Rig::new();
    // 0x2004 holds "hello" (5 bytes): normal response 0x41, size 5, mailbox length 10 + 5.
    assert_eq!(
        rig.send(&upload_req(1, 0x2004, 0)),
        Some(hex(
            "0F 00 00 00 00 13  00 30  41 04 20 00  05 00 00 00  68 65 6C 6C 6F"
        ))
    );
    // Normal download 0x21 of 7 bytes in one message: mailbox length 10 + 7.
    assert_eq!(
        rig.send(&hex(
            "11 00 00 00 00 23  00 20  21 04 20 00  07 00 00 00  77 6F 72 6C 64 21 21"
        )),
        Some(hex("0A 00 00 00 00 23  00 30  60 04 20 00  00 00 00 00"))
    );
    assert_eq!(
        rig.od.value(addr(0x2004, 0)),
        Some(Value::Str("world!!".into()))
    );
}

/// The segments of `data` a server with an SM1 of `sm1` bytes sends: ≤ sm1 − 9 bytes each.
fn upload_segmented(rig: &mut Rig, index: u16, first_cnt: u8) -> (Vec<u8>, Vec<Vec<u8>>) {
    let init = rig.send(&upload_req(first_cnt, index, 0)).unwrap();
    let mut replies = vec![init.clone()];
    let size = u32::from_le_bytes(init[12..16].try_into().unwrap()) as usize;
    let mut out = Vec::new();
    let mut toggle = false;
    let mut cnt = first_cnt;
    loop {
        cnt = cnt % 7 + 1;
        let req = hex(&format!(
            "0A 00 00 00 00 {:02X}  00 20  {:02X} 00 00 00  00 00 00 00",
            0x03 | (cnt << 4),
            0x60 | (u8::from(toggle) << 4)
        ));
        let r = rig.send(&req).unwrap();
        let len = u16::from_le_bytes([r[0], r[1]]) as usize;
        let cmd = r[8];
        assert_eq!(cmd & 0xE0, 0x00, "upload segment response");
        assert_eq!(cmd & 0x10 != 0, toggle, "toggle echoed");
        // Both masters: k = len − 3, minus the unused count when len − 3 == 7.
        let mut k = len - 3;
        if k == 7 {
            k -= ((cmd >> 1) & 7) as usize;
        }
        out.extend_from_slice(&r[9..9 + k]);
        replies.push(r);
        if cmd & 1 != 0 {
            break;
        }
        toggle = !toggle;
    }
    assert_eq!(out.len(), size);
    (out, replies)
}

#[test]
fn segmented_upload_of_a_60_byte_string_through_a_small_mailbox() {
    // SM1 of 32 bytes: a normal response carries at most 16 data bytes, a segment 23.
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    let name = fixture::DEVICE_NAME.as_bytes();
    assert_eq!(name.len(), 60);
    let (data, r) = upload_segmented(&mut rig, 0x1008, 1);
    assert_eq!(data, name);
    // Initiate response: normal (0x41), complete size 60, no data (mailbox length 10).
    assert_eq!(
        r[0],
        hex("0A 00 00 00 00 13  00 30  41 08 10 00  3C 00 00 00")
    );
    // Segments 23 + 23 + 14 with toggles 0, 1, 0; the last one has c = 1.
    let mut seg1 = hex("1A 00 00 00 00 23  00 30  00");
    seg1.extend_from_slice(&name[..23]);
    assert_eq!(r[1], seg1);
    let mut seg2 = hex("1A 00 00 00 00 33  00 30  10");
    seg2.extend_from_slice(&name[23..46]);
    assert_eq!(r[2], seg2);
    let mut seg3 = hex("11 00 00 00 00 43  00 30  01");
    seg3.extend_from_slice(&name[46..]);
    assert_eq!(r[3], seg3);
    assert!(!rig.server.transfer_in_progress());
}

#[test]
fn short_last_upload_segment_is_padded_to_7_bytes() {
    // SM1 of 36 bytes: segments of 27, 27, then 6 bytes → mailbox length 10, n = 1 unused.
    let mut rig = Rig::with(CoeConfig::default(), 36, 36);
    let (data, r) = upload_segmented(&mut rig, 0x1008, 1);
    assert_eq!(data, fixture::DEVICE_NAME.as_bytes());
    let last = &r[3];
    assert_eq!(last[..9], hex("0A 00 00 00 00 43  00 30  03"));
    assert_eq!(&last[9..15], &fixture::DEVICE_NAME.as_bytes()[54..]);
    assert_eq!(last[15], 0, "padding byte");
}

#[test]
fn segmented_download_through_a_small_mailbox() {
    // SM0 of 20 bytes: the initiate carries 20 − 16 = 4 bytes, a segment 20 − 9 = 11.
    let mut rig = Rig::with(CoeConfig::default(), 20, 20);
    // "0123456789ABCDEF" (16 bytes) into 0x2004.
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 13  00 20  21 04 20 00  10 00 00 00  30 31 32 33"
        )),
        Some(hex("0A 00 00 00 00 13  00 30  60 04 20 00  00 00 00 00"))
    );
    assert!(rig.server.transfer_in_progress());
    // Segment t = 0, 11 bytes: mailbox length 3 + 11, command 0x00.
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 23  00 20  00  34 35 36 37 38 39 41 42 43 44 45"
        )),
        Some(hex("0A 00 00 00 00 23  00 30  20 00 00 00  00 00 00 00"))
    );
    // Nothing stored before the last segment.
    assert_eq!(
        rig.od.value(addr(0x2004, 0)),
        Some(Value::Str("hello".into()))
    );
    // Last segment t = 1, 1 byte: mailbox length 10, n = 6 unused, c = 1 → 0x1D.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  1D 46 00 00 00 00 00 00")),
        Some(hex("0A 00 00 00 00 33  00 30  30 00 00 00  00 00 00 00"))
    );
    assert_eq!(
        rig.od.value(addr(0x2004, 0)),
        Some(Value::Str("0123456789ABCDEF".into()))
    );
    assert!(!rig.server.transfer_in_progress());
}

#[test]
fn segmented_download_that_the_object_refuses_is_aborted_at_the_end() {
    let mut rig = Rig::with(CoeConfig::default(), 20, 20);
    // 17 bytes into a 16-byte string.
    rig.send(&hex(
        "0E 00 00 00 00 13  00 20  21 04 20 00  11 00 00 00  30 31 32 33",
    ))
    .unwrap();
    rig.send(&hex(
        "0E 00 00 00 00 23  00 20  00  34 35 36 37 38 39 41 42 43 44 45",
    ))
    .unwrap();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  1B 46 47 00 00 00 00 00")),
        Some(abort_reply(3, 0x2004, 0, 0x0607_0012))
    );
    assert_eq!(
        rig.od.value(addr(0x2004, 0)),
        Some(Value::Str("hello".into()))
    );
}

#[test]
fn segmented_download_with_more_or_less_data_than_announced_is_aborted() {
    let mut rig = Rig::with(CoeConfig::default(), 20, 20);
    // Announce 6 bytes, send 4 + a last segment of 1.
    rig.send(&hex(
        "0E 00 00 00 00 13  00 20  21 04 20 00  06 00 00 00  30 31 32 33",
    ))
    .unwrap();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  0D 34 00 00 00 00 00 00")),
        Some(abort_reply(2, 0x2004, 0, 0x0607_0010))
    );
    // Announce 5 bytes, send 4 + a segment of 2.
    rig.send(&hex(
        "0E 00 00 00 00 33  00 20  21 04 20 00  05 00 00 00  30 31 32 33",
    ))
    .unwrap();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 43  00 20  0B 34 35 00 00 00 00 00")),
        Some(abort_reply(4, 0x2004, 0, 0x0607_0010))
    );
}

#[test]
fn toggle_errors_abort_the_transfer() {
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    rig.send(&upload_req(1, 0x1008, 0)).unwrap();
    // First segment must have t = 0; t = 1 → 0x05030000, transfer gone.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  70 00 00 00  00 00 00 00")),
        Some(abort_reply(2, 0x1008, 0, 0x0503_0000))
    );
    assert!(!rig.server.transfer_in_progress());
    // Download: t = 0, then t = 0 again.
    let mut rig = Rig::with(CoeConfig::default(), 20, 20);
    rig.send(&hex(
        "0E 00 00 00 00 13  00 20  21 04 20 00  10 00 00 00  30 31 32 33",
    ))
    .unwrap();
    rig.send(&hex(
        "0E 00 00 00 00 23  00 20  00  34 35 36 37 38 39 41 42 43 44 45",
    ))
    .unwrap();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  0D 46 00 00 00 00 00 00")),
        Some(abort_reply(3, 0x2004, 0, 0x0503_0000))
    );
    assert_eq!(
        rig.od.value(addr(0x2004, 0)),
        Some(Value::Str("hello".into()))
    );
}

#[test]
fn unexpected_segments_are_invalid_commands() {
    let mut rig = Rig::new();
    // Upload segment without an upload.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 20  60 00 00 00  00 00 00 00")),
        Some(abort_reply(1, 0, 0, 0x0504_0001))
    );
    // Download segment without a download.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  01 41 00 00  00 00 00 00")),
        Some(abort_reply(2, 0, 0, 0x0504_0001))
    );
    // Download segment in the middle of a segmented upload: aborted, upload ended.
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    rig.send(&upload_req(1, 0x1008, 0)).unwrap();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  01 41 00 00  00 00 00 00")),
        Some(abort_reply(2, 0, 0, 0x0504_0001))
    );
    assert!(!rig.server.transfer_in_progress());
    // Block transfers (ccs 5, 6) and ccs 7 do not exist in CoE.
    let mut rig = Rig::new();
    for (i, cmd) in [0xA0u8, 0xC0, 0xE0].into_iter().enumerate() {
        let cnt = i as u8 + 1;
        let req = hex(&format!(
            "0A 00 00 00 00 {:02X}  00 20  {cmd:02X} 00 10 00  00 00 00 00",
            0x03 | (cnt << 4)
        ));
        assert_eq!(
            rig.send(&req),
            Some(abort_reply(cnt, 0x1000, 0, 0x0504_0001))
        );
    }
}

#[test]
fn a_new_initiate_replaces_a_transfer_in_progress() {
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    rig.send(&upload_req(1, 0x1008, 0)).unwrap();
    rig.send(&hex("0A 00 00 00 00 23  00 20  60 00 00 00  00 00 00 00"))
        .unwrap();
    // The master gives up and starts over with an expedited upload: answered normally.
    assert_eq!(
        rig.send(&upload_req(3, 0x1000, 0)),
        Some(hex("0A 00 00 00 00 33  00 30  43 00 10 00  92 01 02 00"))
    );
    assert!(!rig.server.transfer_in_progress());
    // And a segment request now is unexpected.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 43  00 20  70 00 00 00  00 00 00 00")),
        Some(abort_reply(4, 0, 0, 0x0504_0001))
    );
    // A fresh upload of the string restarts at toggle 0 and returns all of it.
    let (data, _) = upload_segmented(&mut rig, 0x1008, 5);
    assert_eq!(data, fixture::DEVICE_NAME.as_bytes());
}

#[test]
fn abort_from_the_master_ends_the_transfer_without_reply() {
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    rig.send(&upload_req(1, 0x1008, 0)).unwrap();
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  80 08 10 00  00 00 04 05")),
        None
    );
    assert!(!rig.server.transfer_in_progress());
}

#[test]
fn complete_access_upload_of_assignment_and_mapping() {
    let mut rig = Rig::new();
    // 0x1C12 from sub 0: n = 1 (u8), pad, 0x1600 (u16) → 4 bytes → expedited with CA: 0x53.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 20  50 12 1C 00  00 00 00 00")),
        Some(hex("0A 00 00 00 00 13  00 30  53 12 1C 00  01 00 00 16"))
    );
    // 0x1600 from sub 0: 2, pad, 0x60400010, 0x607A0020 → 10 bytes, normal with CA: 0x51.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  50 00 16 00  00 00 00 00")),
        Some(hex(
            "14 00 00 00 00 23  00 30  51 00 16 00  0A 00 00 00  02 00 10 00 40 60 20 00 7A 60"
        ))
    );
    // From sub 1 the sub-0 value and pad are left out.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  50 00 16 01  00 00 00 00")),
        Some(hex(
            "12 00 00 00 00 33  00 30  51 00 16 01  08 00 00 00  10 00 40 60 20 00 7A 60"
        ))
    );
    // 0x1C00 as SOEM reads it: 04 00 01 02 03 04.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 43  00 20  50 00 1C 00  00 00 00 00")),
        Some(hex(
            "10 00 00 00 00 43  00 30  51 00 1C 00  06 00 00 00  04 00 01 02 03 04"
        ))
    );
}

#[test]
fn complete_access_skips_record_gaps_and_packs_bits() {
    let mut rig = Rig::new();
    // 0x1C32: sub 0 = 12, subs 7, 8, 10, 11 do not exist.
    let r = rig
        .send(&hex("0A 00 00 00 00 13  00 20  50 32 1C 00  00 00 00 00"))
        .unwrap();
    let mut image = vec![12u8, 0];
    image.extend_from_slice(&0u16.to_le_bytes()); // 1 sync type
    image.extend_from_slice(&1_000_000u32.to_le_bytes()); // 2 cycle
    image.extend_from_slice(&0u32.to_le_bytes()); // 3 shift
    image.extend_from_slice(&5u16.to_le_bytes()); // 4 supported
    image.extend_from_slice(&250_000u32.to_le_bytes()); // 5 min cycle
    image.extend_from_slice(&100_000u32.to_le_bytes()); // 6 calc and copy
    image.extend_from_slice(&0u32.to_le_bytes()); // 9 delay
    image.extend_from_slice(&0u16.to_le_bytes()); // 12 too small
    assert_eq!(r[8], 0x51);
    assert_eq!(u32::from_le_bytes(r[12..16].try_into().unwrap()), 28);
    assert_eq!(&r[16..], &image[..]);
    // 0x2001: BOOLEAN 1, BIT3 5, BIT4 0xA packed into one byte (1 | 5 << 1 | 0xA << 4 = 0xAB),
    // then the UNSIGNED16 on the next byte boundary.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  50 01 20 00  00 00 00 00")),
        Some(hex(
            "0F 00 00 00 00 23  00 30  51 01 20 00  05 00 00 00  04 00 AB 34 12"
        ))
    );
    // Download the same layout with other values.
    assert_eq!(
        rig.send(&hex(
            "0F 00 00 00 00 33  00 20  31 01 20 00  05 00 00 00  04 00 56 78 56"
        )),
        Some(hex("0A 00 00 00 00 33  00 30  60 01 20 00  00 00 00 00"))
    );
    // 0x56 = 0b0101_0110: enable 0, mode 0b011, level 0b0101.
    assert_eq!(rig.od.uint(addr(0x2001, 1)), Some(0));
    assert_eq!(rig.od.uint(addr(0x2001, 2)), Some(3));
    assert_eq!(rig.od.uint(addr(0x2001, 3)), Some(5));
    assert_eq!(rig.od.uint(addr(0x2001, 4)), Some(0x5678));
}

#[test]
fn complete_access_download_of_mapping_and_assignment() {
    let mut rig = Rig::new();
    // 0x1600 := [0x60400010, 0x60600008, 0x60FF0020] from sub 0 (normal download, CA: 0x31).
    assert_eq!(
        rig.send(&hex(
            "18 00 00 00 00 13  00 20  31 00 16 00  0E 00 00 00  03 00 10 00 40 60 08 00 60 60 20 00 FF 60"
        )),
        Some(hex("0A 00 00 00 00 13  00 30  60 00 16 00  00 00 00 00"))
    );
    // 0x1C12 := [0x1600, 0x1601] (0x1601 is empty, which is allowed).
    assert_eq!(
        rig.send(&hex(
            "10 00 00 00 00 23  00 20  31 12 1C 00  06 00 00 00  02 00 00 16 01 16"
        )),
        Some(hex("0A 00 00 00 00 23  00 30  60 12 1C 00  00 00 00 00"))
    );
    let m = rig.od.mapping().unwrap();
    assert_eq!(m.rx.len(), 2);
    assert_eq!(
        m.rx[0].entries[..],
        [
            PdoEntry::new(0x6040, 0, 16),
            PdoEntry::new(0x6060, 0, 8),
            PdoEntry::new(0x60FF, 0, 32)
        ]
    );
    assert_eq!(m.bytes(Direction::Rx), 7);
    // Uploading it back gives the same image.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  50 12 1C 00  00 00 00 00")),
        Some(hex(
            "10 00 00 00 00 33  00 30  51 12 1C 00  06 00 00 00  02 00 00 16 01 16"
        ))
    );
    // Outside PRE-OP the same download is refused with 0x08000022 and nothing changes.
    rig.state = AlState::SafeOp;
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 43  00 20  31 12 1C 00  04 00 00 00  01 00 01 16"
        )),
        Some(abort_reply(4, 0x1C12, 0, 0x0800_0022))
    );
    assert_eq!(rig.od.mapping().unwrap(), m);
}

#[test]
fn complete_access_errors() {
    let mut rig = Rig::new();
    // Wrong length: 0x1C12 with n = 2 but one entry.
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 13  00 20  31 12 1C 00  04 00 00 00  02 00 00 16"
        )),
        Some(abort_reply(1, 0x1C12, 0, 0x0607_0013))
    );
    // Sub-index 2 with complete access.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  50 12 1C 02  00 00 00 00")),
        Some(abort_reply(2, 0x1C12, 2, 0x0601_0000))
    );
    // Read-only identity: same value accepted, another refused.
    let mut image = vec![4u8, 0];
    for v in [
        fixture::VENDOR_ID,
        fixture::PRODUCT_CODE,
        0x0001_0000,
        0x1234_5678,
    ] {
        image.extend_from_slice(&v.to_le_bytes());
    }
    let mut req = hex("1C 00 00 00 00 33  00 20  31 18 10 00  12 00 00 00");
    req.extend_from_slice(&image);
    assert_eq!(
        rig.send(&req),
        Some(hex("0A 00 00 00 00 33  00 30  60 18 10 00  00 00 00 00"))
    );
    let last = req.len() - 1;
    req[5] = 0x43;
    req[last] ^= 0xFF;
    assert_eq!(rig.send(&req), Some(abort_reply(4, 0x1018, 0, 0x0601_0002)));
}

#[test]
fn complete_access_is_refused_when_the_device_has_none() {
    let config = CoeConfig {
        complete_access: false,
        ..CoeConfig::default()
    };
    let mut rig = Rig::with(config, 128, 128);
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 13  00 20  50 12 1C 00  00 00 00 00")),
        Some(abort_reply(1, 0x1C12, 0, 0x0601_0000))
    );
    assert_eq!(
        rig.send(&hex(
            "10 00 00 00 00 23  00 20  31 12 1C 00  06 00 00 00  02 00 00 16 01 16"
        )),
        Some(abort_reply(2, 0x1C12, 0, 0x0601_0000))
    );
    // Expedited CA download too.
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 33  00 20  33 12 1C 00  00 00 00 00")),
        Some(abort_reply(3, 0x1C12, 0, 0x0601_0000))
    );
    // Single-entry access still works.
    assert_eq!(
        rig.send(&upload_req(4, 0x1C12, 1)),
        Some(hex("0A 00 00 00 00 43  00 30  4B 12 1C 01  00 16 00 00"))
    );
}

/// Every abort code a single SDO access can produce, with the request that produces it.
#[test]
fn abort_codes_of_single_accesses() {
    let mut rig = Rig::new();
    let mut cnt = 0u8;
    let mut next = || {
        cnt = cnt % 7 + 1;
        cnt
    };
    let cases: Vec<(Vec<u8>, u16, u8, SdoAbortCode, AlState)> = vec![
        // existence
        (
            upload_req(0, 0x5555, 0),
            0x5555,
            0,
            SdoAbortCode::NO_OBJECT,
            AlState::PreOp,
        ),
        (
            upload_req(0, 0x1018, 9),
            0x1018,
            9,
            SdoAbortCode::NO_SUBINDEX,
            AlState::PreOp,
        ),
        (
            upload_req(0, 0x1C32, 7),
            0x1C32,
            7,
            SdoAbortCode::NO_SUBINDEX,
            AlState::PreOp,
        ),
        // access
        (
            upload_req(0, 0x2000, 0),
            0x2000,
            0,
            SdoAbortCode::WRITE_ONLY,
            AlState::PreOp,
        ),
        (
            download_req(0, 0x1000, 0, &[1, 2, 3, 4]),
            0x1000,
            0,
            SdoAbortCode::READ_ONLY,
            AlState::PreOp,
        ),
        (
            download_req(0, 0x2003, 0, &[1, 0, 0, 0]),
            0x2003,
            0,
            SdoAbortCode::DEVICE_STATE,
            AlState::SafeOp,
        ),
        (
            download_req(0, 0x2003, 0, &[1, 0, 0, 0]),
            0x2003,
            0,
            SdoAbortCode::DEVICE_STATE,
            AlState::Op,
        ),
        (
            upload_req(0, 0x1000, 0),
            0x1000,
            0,
            SdoAbortCode::DEVICE_STATE,
            AlState::Init,
        ),
        // length
        (
            download_req(0, 0x6040, 0, &[1, 2, 3, 4]),
            0x6040,
            0,
            SdoAbortCode::LENGTH_TOO_HIGH,
            AlState::PreOp,
        ),
        (
            download_req(0, 0x607A, 0, &[1, 2]),
            0x607A,
            0,
            SdoAbortCode::LENGTH_TOO_LOW,
            AlState::PreOp,
        ),
        // range
        (
            download_req(0, 0x2002, 0, &101i16.to_le_bytes()),
            0x2002,
            0,
            SdoAbortCode::VALUE_TOO_HIGH,
            AlState::PreOp,
        ),
        (
            download_req(0, 0x2002, 0, &(-101i16).to_le_bytes()),
            0x2002,
            0,
            SdoAbortCode::VALUE_TOO_LOW,
            AlState::PreOp,
        ),
        (
            download_req(0, 0x1C12, 0, &[3]),
            0x1C12,
            0,
            SdoAbortCode::VALUE_TOO_HIGH,
            AlState::PreOp,
        ),
        // PDO rules
        (
            download_req(0, 0x1C12, 0, &[1]),
            0x1C12,
            0,
            SdoAbortCode::DEVICE_STATE,
            AlState::SafeOp,
        ),
        (
            download_req(0, 0x1600, 1, &[0x10, 0, 0x40, 0x60]),
            0x1600,
            1,
            SdoAbortCode::SUBINDEX0_NOT_ZERO,
            AlState::PreOp,
        ),
        (
            download_req(0, 0x1C12, 1, &[0x01, 0x16]),
            0x1C12,
            1,
            SdoAbortCode::SUBINDEX0_NOT_ZERO,
            AlState::PreOp,
        ),
    ];
    for (mut req, index, sub, code, state) in cases {
        let c = next();
        req[5] = 0x03 | (c << 4);
        rig.state = state;
        assert_eq!(
            rig.send(&req),
            Some(abort_reply(c, index, sub, code.0)),
            "{index:04X}:{sub:02X} in {state} should abort with {code}"
        );
    }
}

#[test]
fn write_then_read_back_across_states() {
    let mut rig = Rig::new();
    rig.state = AlState::Op;
    // RW in every state.
    assert!(
        rig.send(&download_req(1, 0x2002, 0, &(-50i16).to_le_bytes()))
            .unwrap()[8]
            == 0x60
    );
    assert_eq!(
        rig.send(&upload_req(2, 0x2002, 0)),
        Some(hex("0A 00 00 00 00 23  00 30  4B 02 20 00  CE FF 00 00"))
    );
    // PRE-OP-only entries are still readable in OP.
    assert_eq!(
        rig.send(&upload_req(3, 0x2003, 0)),
        Some(hex("0A 00 00 00 00 33  00 30  43 03 20 00  07 00 00 00"))
    );
}

#[test]
fn segmented_downloads_that_cannot_succeed_are_refused_at_the_start() {
    let config = CoeConfig {
        max_object_size: 32,
        ..CoeConfig::default()
    };
    let mut rig = Rig::with(config, 20, 20);
    // Unknown object: 0x06020000 before any segment.
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 13  00 20  21 55 55 00  10 00 00 00  30 31 32 33"
        )),
        Some(abort_reply(1, 0x5555, 0, 0x0602_0000))
    );
    // Unknown sub-index: 0x06090011.
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 23  00 20  21 18 10 09  10 00 00 00  30 31 32 33"
        )),
        Some(abort_reply(2, 0x1018, 9, 0x0609_0011))
    );
    // More than the server transfers: 0x06070012.
    assert_eq!(
        rig.send(&hex(
            "0E 00 00 00 00 33  00 20  21 04 20 00  00 01 00 00  30 31 32 33"
        )),
        Some(abort_reply(3, 0x2004, 0, 0x0607_0012))
    );
    assert!(!rig.server.transfer_in_progress());
}
