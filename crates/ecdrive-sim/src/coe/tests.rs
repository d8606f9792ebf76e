//! Unit tests of the CoE server internals. The wire behaviour is tested in `tests/coe_*.rs`.

use super::*;
use crate::ec::mailbox::MailboxMessage;
use crate::od::{ObjectAddress, Value};

fn rig() -> (CoeServer, OdStore) {
    (
        CoeServer::new(CoeConfig::default()),
        OdStore::new(fixture::OBJECTS).expect("fixture is valid"),
    )
}

fn upload(cnt: u8, index: u16, sub: u8, ca: bool) -> [u8; 16] {
    let mut b = [0u8; 16];
    SdoRequest::Upload {
        index,
        sub,
        complete_access: ca,
    }
    .emit_mailbox(cnt, &mut b)
    .expect("fits");
    b
}

#[test]
fn fixture_is_valid_and_its_name_is_60_bytes() {
    assert_eq!(fixture::DEVICE_NAME.len(), 60);
    let od = OdStore::new(fixture::OBJECTS).expect("fixture is valid");
    assert_eq!(
        od.value(ObjectAddress::new(0x1008, 0)),
        Some(Value::Str(fixture::DEVICE_NAME.into()))
    );
}

#[test]
fn reply_that_does_not_fit_is_not_sent_and_does_not_use_a_counter() {
    let (mut s, mut od) = rig();
    // 15 bytes cannot hold a 16-byte SDO response.
    let mut small = [0u8; 15];
    assert_eq!(
        s.handle(
            &upload(1, 0x1000, 0, false),
            AlState::PreOp,
            &mut od,
            &mut small
        ),
        None
    );
    assert_eq!(s.stats().replies_too_large, 1);
    let mut reply = [0u8; 64];
    let n = s
        .handle(
            &upload(2, 0x1000, 0, false),
            AlState::PreOp,
            &mut od,
            &mut reply,
        )
        .expect("answered");
    assert_eq!(n, 16);
    assert_eq!(
        reply[5] >> 4,
        1,
        "the unsent reply did not consume counter 1"
    );
}

#[test]
fn segmented_upload_state_survives_only_sent_replies() {
    let (mut s, mut od) = rig();
    let mut reply = [0u8; 32];
    s.handle(
        &upload(1, 0x1008, 0, false),
        AlState::PreOp,
        &mut od,
        &mut reply,
    )
    .expect("initiate response");
    assert!(s.transfer_in_progress());
    let mut seg = [0u8; 16];
    SdoRequest::UploadSegment { toggle: false }
        .emit_mailbox(2, &mut seg)
        .expect("fits");
    // SM1 too small for any segment: nothing sent, the transfer still waits for toggle 0.
    let mut tiny = [0u8; 9];
    assert_eq!(s.handle(&seg, AlState::PreOp, &mut od, &mut tiny), None);
    SdoRequest::UploadSegment { toggle: false }
        .emit_mailbox(3, &mut seg)
        .expect("fits");
    let n = s
        .handle(&seg, AlState::PreOp, &mut od, &mut reply)
        .expect("segment");
    match MailboxMessage::parse(&reply[..n]).expect("parses").1 {
        MailboxMessage::SdoResponse(SdoResponse::UploadSegment { toggle, data, .. }) => {
            assert!(!toggle);
            assert_eq!(data, &fixture::DEVICE_NAME.as_bytes()[..23]);
        }
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn complete_access_image_round_trips_through_the_store() {
    let (_, mut od) = rig();
    let mut buf = [0u8; 64];
    let n = od
        .read_complete(0x2001, 0, AlState::PreOp, &mut buf)
        .expect("readable");
    assert_eq!(buf[..n], [4, 0, 0xAB, 0x34, 0x12]);
    // Write an image with every packed field at its maximum.
    od.write_complete(0x2001, 0, AlState::PreOp, &[4, 0, 0xFF, 0xFF, 0xFF])
        .expect("writable");
    assert_eq!(od.uint(ObjectAddress::new(0x2001, 1)), Some(1));
    assert_eq!(od.uint(ObjectAddress::new(0x2001, 2)), Some(7));
    assert_eq!(od.uint(ObjectAddress::new(0x2001, 3)), Some(15));
    assert_eq!(od.uint(ObjectAddress::new(0x2001, 4)), Some(0xFFFF));
    // A dirty buffer does not leak into the packed byte.
    let mut dirty = [0xEEu8; 64];
    od.write_complete(0x2001, 0, AlState::PreOp, &[4, 0, 0x00, 0x00, 0x00])
        .expect("writable");
    let n = od
        .read_complete(0x2001, 0, AlState::PreOp, &mut dirty)
        .expect("readable");
    assert_eq!(dirty[..n], [4, 0, 0, 0, 0]);
    // The image must fit the buffer.
    assert_eq!(
        od.read_complete(0x2001, 0, AlState::PreOp, &mut [0u8; 3]),
        Err(SdoAbortCode::OUT_OF_MEMORY)
    );
}

#[test]
fn complete_access_to_a_var_is_its_value_and_strings_are_refused() {
    let (_, mut od) = rig();
    let mut buf = [0u8; 64];
    let n = od
        .read_complete(0x1000, 0, AlState::PreOp, &mut buf)
        .expect("readable");
    assert_eq!(buf[..n], 0x0002_0192u32.to_le_bytes());
    assert_eq!(
        od.read_complete(0x1000, 1, AlState::PreOp, &mut buf),
        Err(SdoAbortCode::NO_SUBINDEX)
    );
    // A VAR string is fine (it is one value) ...
    assert!(
        od.read_complete(0x1008, 0, AlState::PreOp, &mut buf)
            .is_ok()
    );
    // ... and an unknown object is reported as such.
    assert_eq!(
        od.read_complete(0x5555, 0, AlState::PreOp, &mut buf),
        Err(SdoAbortCode::NO_OBJECT)
    );
}
