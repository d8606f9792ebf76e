//! Mailbox-level behaviour of the CoE server: error replies (type 0), the duplicate counter and
//! its reset, the reply counter, and the emergency queue and its delivery order.

use crate::coe_util;

use coe_util::{Rig, hex, upload_req};
use ecdrive_core::ec::mailbox::{Emergency, MailboxMessage, SdoResponse};
use ecdrive_sim::coe::CoeConfig;

#[test]
fn unsupported_protocols_get_a_mailbox_error() {
    let mut rig = Rig::new();
    // EoE (type 2), FoE (4), SoE (5), VoE (15), AoE (1), ERR (0), reserved (6).
    for (i, t) in [2u8, 4, 5, 15, 1, 0, 6].into_iter().enumerate() {
        let cnt = (i % 7) as u8 + 1;
        let req = [0x04, 0x00, 0x00, 0x00, 0x00, t | (cnt << 4), 1, 2, 3, 4];
        // Reply: length 4, type 0, own counter; command 0x0001, detail 2.
        let reply = rig.send(&req).unwrap();
        assert_eq!(reply[..5], [0x04, 0x00, 0x00, 0x00, 0x00]);
        assert_eq!(reply[5] & 0x0F, 0x00);
        assert_eq!(reply[6..], [0x01, 0x00, 0x02, 0x00], "type {t}");
    }
}

#[test]
fn unsupported_coe_services_get_a_mailbox_error() {
    let mut rig = Rig::new();
    // Emergency (1), SDO response (3), TxPDO (4), RxPDO (5), RTRs (6, 7), reserved (0, 9, 15).
    for (i, s) in [1u8, 3, 4, 5, 6, 7, 0, 9, 15].into_iter().enumerate() {
        let cnt = (i % 7) as u8 + 1;
        let req = [
            0x0A,
            0x00,
            0x00,
            0x00,
            0x00,
            0x03 | (cnt << 4),
            0x00,
            s << 4,
            0x40,
            0x00,
            0x10,
            0x00,
            0,
            0,
            0,
            0,
        ];
        let reply = rig.send(&req).unwrap();
        assert_eq!(reply[6..], [0x01, 0x00, 0x04, 0x00], "service {s}");
    }
}

#[test]
fn malformed_mailboxes_get_a_mailbox_error() {
    let mut rig = Rig::with(CoeConfig::default(), 16, 128);
    // Length field larger than SM0 can hold: detail 8 (invalid size).
    assert_eq!(
        rig.send(&hex("40 00 00 00 00 13  00 20  40 00 10 00  00 00 00 00")),
        Some(hex("04 00 00 00 00 10  01 00 08 00"))
    );
    // No CoE header (length 1): detail 6 (size too short).
    assert_eq!(
        rig.send(&hex("01 00 00 00 00 23  00")),
        Some(hex("04 00 00 00 00 20  01 00 06 00"))
    );
    // SDO shorter than the 8-byte minimum (mailbox length 6): detail 6.
    assert_eq!(
        rig.send(&hex("06 00 00 00 00 33  00 20  40 00 10 00")),
        Some(hex("04 00 00 00 00 30  01 00 06 00"))
    );
    // SM0 shorter than a mailbox header.
    let mut sm1 = [0u8; 64];
    let n = rig
        .server
        .handle(&[0x0A, 0x00, 0x00], rig.state, &mut rig.od, &mut sm1)
        .unwrap();
    assert_eq!(sm1[..n], hex("04 00 00 00 00 40  01 00 06 00"));
}

#[test]
fn a_repeated_counter_is_not_executed_twice() {
    let mut rig = Rig::new();
    // Write 0x6040 := 1 with counter 3 ...
    let write = |v: u8, cnt: u8| {
        hex(&format!(
            "0A 00 00 00 00 {:02X}  00 20  2B 40 60 00  {v:02X} 00 00 00",
            0x03 | (cnt << 4)
        ))
    };
    assert!(rig.send(&write(1, 3)).is_some());
    // ... the device changes the value itself ...
    rig.od
        .set_uint(ecdrive_core::od::ObjectAddress::new(0x6040, 0), 7)
        .unwrap();
    // ... a repeat with counter 3 (even with other content) is ignored: no reply, no write.
    assert_eq!(rig.send(&write(1, 3)), None);
    assert_eq!(rig.send(&write(2, 3)), None);
    assert_eq!(
        rig.od.uint(ecdrive_core::od::ObjectAddress::new(0x6040, 0)),
        Some(7)
    );
    assert_eq!(rig.server.stats().repeats_ignored, 2);
    // The next counter is executed.
    assert!(rig.send(&write(2, 4)).is_some());
    assert_eq!(
        rig.od.uint(ecdrive_core::od::ObjectAddress::new(0x6040, 0)),
        Some(2)
    );
    // Counter 0 is never a duplicate.
    assert!(rig.send(&write(5, 0)).is_some());
    assert!(rig.send(&write(6, 0)).is_some());
    assert_eq!(
        rig.od.uint(ecdrive_core::od::ObjectAddress::new(0x6040, 0)),
        Some(6)
    );
    // The same counter after another one is a new request.
    assert!(rig.send(&write(8, 4)).is_some());
}

#[test]
fn reset_forgets_the_counter_for_a_restarted_master() {
    let mut rig = Rig::new();
    assert!(rig.send(&upload_req(1, 0x1000, 0)).is_some());
    // Mailbox reconfigured (INIT → PRE-OP): a fresh master starts at counter 1 again.
    rig.server.reset();
    assert_eq!(
        rig.send(&upload_req(1, 0x1000, 0)),
        // and the reply counter restarts at 1 too.
        Some(hex("0A 00 00 00 00 13  00 30  43 00 10 00  92 01 02 00"))
    );
    // Without the reset the same counter would have been dropped.
    assert_eq!(rig.send(&upload_req(1, 0x1000, 0)), None);
}

#[test]
fn reset_aborts_segmented_transfers() {
    let mut rig = Rig::with(CoeConfig::default(), 32, 32);
    rig.send(&upload_req(1, 0x1008, 0)).unwrap();
    assert!(rig.server.transfer_in_progress());
    rig.server.reset();
    assert!(!rig.server.transfer_in_progress());
    assert_eq!(
        rig.send(&hex("0A 00 00 00 00 23  00 20  60 00 00 00  00 00 00 00")),
        Some(coe_util::abort_reply(1, 0, 0, 0x0504_0001))
    );
}

#[test]
fn reply_counters_run_1_to_7() {
    let mut rig = Rig::new();
    let mut seen = Vec::new();
    for i in 0..16u8 {
        let r = rig.send(&upload_req(i % 7 + 1, 0x1000, 0)).unwrap();
        seen.push(r[5] >> 4);
    }
    assert_eq!(seen, [1, 2, 3, 4, 5, 6, 7, 1, 2, 3, 4, 5, 6, 7, 1, 2]);
}

#[test]
fn emergencies_are_delivered_only_when_sm1_is_free() {
    let mut rig = Rig::new();
    let e1 = Emergency {
        error_code: 0x7500,
        error_register: 0x11,
        data: [1, 2, 3, 4, 5],
    };
    rig.server.push_emergency(e1);
    assert!(rig.server.has_unsolicited());
    // ethercrab panics if an SDO request is answered with an emergency: the reply to a request
    // is always the SDO response, the emergency waits for the next free SM1.
    let r = rig.send(&upload_req(1, 0x1000, 0)).unwrap();
    assert!(matches!(
        MailboxMessage::parse(&r).unwrap().1,
        MailboxMessage::SdoResponse(SdoResponse::UploadExpedited { index: 0x1000, .. })
    ));
    // CoE service 1, mailbox length 10: code, register, 5 bytes.
    assert_eq!(
        rig.poll(),
        Some(hex("0A 00 00 00 00 23  00 10  00 75 11 01 02 03 04 05"))
    );
    assert_eq!(rig.poll(), None);
    assert!(!rig.server.has_unsolicited());
}

#[test]
fn the_emergency_queue_is_bounded_and_counts_overflow() {
    let config = CoeConfig {
        emergency_queue_len: 3,
        ..CoeConfig::default()
    };
    let mut rig = Rig::with(config, 128, 128);
    for code in 0..5u16 {
        rig.server.push_emergency(Emergency {
            error_code: 0x1000 + code,
            ..Emergency::default()
        });
    }
    assert_eq!(rig.server.stats().emergencies_dropped, 2);
    // The first three, in order, one per poll.
    for code in 0..3u16 {
        let m = rig.poll().unwrap();
        match MailboxMessage::parse(&m).unwrap().1 {
            MailboxMessage::Emergency(e) => assert_eq!(e.error_code, 0x1000 + code),
            other => panic!("unexpected {other:?}"),
        }
    }
    assert_eq!(rig.poll(), None);
    // A reply buffer too small keeps the emergency queued.
    rig.server.push_emergency(Emergency::default());
    let mut tiny = [0u8; 8];
    assert_eq!(rig.server.poll_unsolicited(&mut tiny), None);
    assert!(rig.server.has_unsolicited());
    assert!(rig.poll().is_some());
}

#[test]
fn reset_drops_queued_emergencies() {
    let mut rig = Rig::new();
    rig.server.push_emergency(Emergency::default());
    rig.server.reset();
    assert_eq!(rig.poll(), None);
}
