//! Property tests for FoE, as `coe_fuzz.rs` does for CoE: random, truncated and mutated FoE
//! mailboxes in every AL state never make the emulated MR-J4-TM (its mailbox server and FoE
//! server) or the FoE views panic; every reply is a well-formed mailbox that fits SM1; and a
//! correct firmware write and read in BOOT still work afterwards. FoE messages emitted parse
//! back to what was emitted.

use ecdrive_core::ec::AlState;
use ecdrive_core::ec::mailbox::{FoeErrorCode, FoeMessage, MailboxMessage, foe_data_capacity};
use ecdrive_sim::device::Device;
use ecdrive_sim::foe::FirmwareImage;
use proptest::prelude::*;

const PASSWORD: u32 = 0x4D52_4A34;
/// The emulated MR-J4-TM's bootstrap mailbox size (its ESI's `<BootStrap>`).
const BOOT_MBX: usize = 512;

fn state() -> impl Strategy<Value = AlState> {
    prop_oneof![
        Just(AlState::Init),
        Just(AlState::PreOp),
        Just(AlState::SafeOp),
        Just(AlState::Op),
        Just(AlState::Bootstrap),
    ]
}

fn drive() -> Box<dyn Device> {
    ecdrive_sim::drives::emulated("mr-j4-tm", 0).expect("emulated MR-J4-TM")
}

/// One FoE message as a mailbox with counter `cnt`.
fn mbx(m: FoeMessage<'_>, cnt: u8) -> Vec<u8> {
    let mut b = vec![0u8; 2048];
    let n = m.emit_mailbox(cnt, &mut b).expect("fits");
    b.truncate(n);
    b
}

/// Feed one request as the ESC would (in an SM0 of `sm0` bytes, reply in an SM1 of `sm1`).
/// Returns the reply, which must parse and fit.
fn feed(d: &mut dyn Device, msg: &[u8], sm0: usize, sm1: usize, st: AlState) -> Option<Vec<u8>> {
    let mut buf = vec![0u8; sm0];
    let n = msg.len().min(sm0);
    buf[..n].copy_from_slice(&msg[..n]);
    let mut reply = vec![0u8; sm1];
    let len = d.mailbox_request(st, &buf, &mut reply)?;
    assert!(len <= sm1, "reply of {len} bytes in an SM1 of {sm1}");
    assert!(
        MailboxMessage::parse(&reply[..len]).is_ok(),
        "reply parses: {:02X?}",
        &reply[..len]
    );
    reply.truncate(len);
    Some(reply)
}

fn foe_reply(r: &[u8]) -> FoeMessage<'_> {
    match MailboxMessage::parse(r) {
        Ok((_, MailboxMessage::Foe(m))) => m,
        other => panic!("not an FoE reply: {other:?}"),
    }
}

/// After whatever came before: a firmware write then read in BOOT, with fresh counters,
/// round-trips.
fn still_works(d: &mut dyn Device) {
    d.mailbox_reset();
    let fw = FirmwareImage {
        vendor_id: 0xA1E,
        product_code: 0x201,
        revision: 7,
        version: "B9".into(),
        payload: (0..1500u32).map(|i| i as u8).collect(),
    }
    .encode();
    let cap = foe_data_capacity(BOOT_MBX);
    let mut cnt = 0u8;
    let mut next = || {
        cnt = cnt % 7 + 1;
        cnt
    };
    let st = AlState::Bootstrap;
    let w = FoeMessage::Write {
        password: PASSWORD,
        name: b"f",
    };
    let r = feed(d, &mbx(w, next()), BOOT_MBX, BOOT_MBX, st).expect("reply");
    assert_eq!(foe_reply(&r), FoeMessage::Ack { packet: 0 });
    let mut chunks: Vec<&[u8]> = fw.chunks(cap).collect();
    if fw.len() % cap == 0 {
        chunks.push(&[]);
    }
    for (i, c) in chunks.into_iter().enumerate() {
        let packet = i as u32 + 1;
        let m = FoeMessage::Data { packet, data: c };
        let r = feed(d, &mbx(m, next()), BOOT_MBX, BOOT_MBX, st).expect("reply");
        assert_eq!(foe_reply(&r), FoeMessage::Ack { packet });
    }
    let rq = FoeMessage::Read {
        password: PASSWORD,
        name: b"f",
    };
    let mut got = Vec::new();
    let mut r = feed(d, &mbx(rq, next()), BOOT_MBX, BOOT_MBX, st).expect("reply");
    loop {
        let FoeMessage::Data { packet, data } = foe_reply(&r) else {
            panic!("expected DATA");
        };
        got.extend_from_slice(data);
        let last = data.len() < cap;
        let ack = mbx(FoeMessage::Ack { packet }, next());
        match feed(d, &ack, BOOT_MBX, BOOT_MBX, st) {
            Some(x) => r = x,
            None => {
                assert!(last);
                break;
            }
        }
    }
    assert_eq!(got, fw);
}

/// Valid FoE requests of every kind, to mutate.
fn templates() -> Vec<Vec<u8>> {
    vec![
        mbx(
            FoeMessage::Write {
                password: PASSWORD,
                name: b"fw",
            },
            1,
        ),
        mbx(
            FoeMessage::Read {
                password: PASSWORD,
                name: b"fw",
            },
            2,
        ),
        mbx(
            FoeMessage::Data {
                packet: 1,
                data: &[1, 2, 3],
            },
            3,
        ),
        mbx(FoeMessage::Ack { packet: 1 }, 4),
        mbx(
            FoeMessage::Error {
                code: FoeErrorCode::ILLEGAL,
                text: b"x",
            },
            5,
        ),
        mbx(FoeMessage::Busy { done: 1, entire: 2 }, 6),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    #[test]
    fn random_foe_mailboxes_never_panic_and_the_drive_recovers(
        blobs in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..200), 1..8),
        sm0 in 0usize..600,
        sm1 in 0usize..600,
        st in state(),
    ) {
        let mut d = drive();
        for b in &blobs {
            // Random bytes under an FoE mailbox header (type 4), so they reach the FoE server.
            let mut m = vec![b.len() as u8, (b.len() >> 8) as u8, 0, 0, 0, 0x14];
            m.extend_from_slice(b);
            feed(d.as_mut(), &m, sm0, sm1, st);
        }
        still_works(d.as_mut());
    }

    #[test]
    fn mutated_foe_requests_never_panic_and_the_drive_recovers(
        picks in proptest::collection::vec(
            (0usize..6, proptest::collection::vec((0usize..40, any::<u8>()), 0..4), 0usize..60),
            1..12),
        sm in 16usize..600,
        st in state(),
    ) {
        let t = templates();
        let mut d = drive();
        for (i, flips, cut) in &picks {
            let mut m = t[*i % t.len()].clone();
            for (at, x) in flips {
                let n = m.len();
                m[at % n] ^= x;
            }
            if *cut < m.len() {
                m.truncate(*cut);
            }
            feed(d.as_mut(), &m, sm, sm, st);
        }
        still_works(d.as_mut());
    }

    #[test]
    fn foe_messages_round_trip(
        op in 1u8..=6,
        field in any::<u32>(),
        data in proptest::collection::vec(any::<u8>(), 0..100),
    ) {
        let m = match op {
            1 => FoeMessage::Read { password: field, name: &data },
            2 => FoeMessage::Write { password: field, name: &data },
            3 => FoeMessage::Data { packet: field, data: &data },
            4 => FoeMessage::Ack { packet: field },
            5 => FoeMessage::Error { code: FoeErrorCode(field), text: &data },
            _ => FoeMessage::Busy { done: field as u16, entire: (field >> 16) as u16 },
        };
        let b = mbx(m, 3);
        match MailboxMessage::parse(&b) {
            Ok((3, MailboxMessage::Foe(back))) => prop_assert_eq!(back, m),
            other => prop_assert!(false, "{:?}", other),
        }
    }

    #[test]
    fn foe_views_never_panic(b in proptest::collection::vec(any::<u8>(), 0..64)) {
        let _ = FoeMessage::parse(&b);
        let _ = FirmwareImage::decode(&b);
    }
}
