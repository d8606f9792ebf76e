//! Property tests: random and truncated mailboxes never make the CoE server (or the mailbox
//! views, or the dictionary) panic, and the server still answers a correct request afterwards;
//! emitted messages parse back to what was emitted; random master writes never leave the PDO
//! configuration inconsistent.

use crate::coe_util;

use coe_util::{hex, upload_req};
use ecdrive_core::ec::AlState;
use ecdrive_core::ec::mailbox::{MailboxMessage, SdoRequest, SdoResponse};
use ecdrive_core::od::{EntryAccess, ObjectAddress};
use ecdrive_core::pdo::Direction;
use ecdrive_sim::coe::{CoeConfig, CoeServer, ObjectStore, OdStore, fixture};
use proptest::prelude::*;

fn state() -> impl Strategy<Value = AlState> {
    prop_oneof![
        Just(AlState::Init),
        Just(AlState::PreOp),
        Just(AlState::SafeOp),
        Just(AlState::Op),
        Just(AlState::Bootstrap),
    ]
}

/// Valid requests of every kind, as raw mailboxes, to mutate.
fn templates() -> Vec<Vec<u8>> {
    vec![
        upload_req(1, 0x1008, 0),
        upload_req(2, 0x1000, 0),
        hex("0A 00 00 00 00 13  00 20  2B 40 60 00  0F 00 00 00"),
        hex("0E 00 00 00 00 13  00 20  21 04 20 00  10 00 00 00  30 31 32 33"),
        hex("0E 00 00 00 00 23  00 20  00  34 35 36 37 38 39 41 42 43 44 45"),
        hex("0A 00 00 00 00 33  00 20  1D 46 00 00 00 00 00 00"),
        hex("0A 00 00 00 00 23  00 20  60 00 00 00  00 00 00 00"),
        hex("0A 00 00 00 00 33  00 20  70 00 00 00  00 00 00 00"),
        hex("0A 00 00 00 00 13  00 20  50 12 1C 00  00 00 00 00"),
        hex("10 00 00 00 00 23  00 20  31 12 1C 00  06 00 00 00  02 00 00 16 01 16"),
        hex(
            "18 00 00 00 00 13  00 20  31 00 16 00  0E 00 00 00  03 00 10 00 40 60 08 00 60 60 20 00 FF 60",
        ),
        hex("08 00 00 00 00 13  00 80  01 00 00 00  01 00"),
        hex("08 00 00 00 00 13  00 80  03 00 00 00  08 10"),
        hex("0A 00 00 00 00 13  00 80  05 00 00 00  02 20 00 78"),
        hex("0A 00 00 00 00 23  00 20  80 08 10 00  00 00 04 05"),
    ]
}

#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Truncate(usize),
    Length(u16),
    Extend(Vec<u8>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0usize..40, any::<u8>()).prop_map(|(i, x)| Mutation::Flip(i, x)),
        (0usize..40).prop_map(Mutation::Truncate),
        any::<u16>().prop_map(Mutation::Length),
        proptest::collection::vec(any::<u8>(), 0..40).prop_map(Mutation::Extend),
    ]
}

fn mutate(mut m: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for x in muts {
        match x {
            Mutation::Flip(i, v) => {
                if !m.is_empty() {
                    let i = i % m.len();
                    m[i] ^= v;
                }
            }
            Mutation::Truncate(n) => m.truncate(*n),
            Mutation::Length(l) => {
                if m.len() >= 2 {
                    m[..2].copy_from_slice(&l.to_le_bytes());
                }
            }
            Mutation::Extend(e) => m.extend_from_slice(e),
        }
    }
    m
}

/// Feed one message as the ESC would: copied into an SM0 of `sm0` bytes (cut or padded), with
/// the reply into an SM1 of `sm1` bytes; then drain unsolicited messages. Every reply must be
/// a well-formed mailbox that fits SM1.
fn feed(server: &mut CoeServer, od: &mut OdStore, msg: &[u8], sm0: usize, sm1: usize, st: AlState) {
    let mut buf = vec![0u8; sm0];
    let n = msg.len().min(sm0);
    buf[..n].copy_from_slice(&msg[..n]);
    let mut reply = vec![0u8; sm1];
    if let Some(len) = server.handle(&buf, st, od, &mut reply) {
        assert!(len <= sm1);
        assert!(MailboxMessage::parse(&reply[..len]).is_ok(), "reply parses");
    }
    for _ in 0..300 {
        match server.poll_unsolicited(&mut reply) {
            Some(len) => {
                assert!(len <= sm1);
                assert!(MailboxMessage::parse(&reply[..len]).is_ok());
            }
            None => break,
        }
    }
}

/// After whatever came before, a correct upload of 0x1000 is answered correctly (with a second
/// counter if the first one happens to repeat the previous request's).
fn answers_correctly(server: &mut CoeServer, od: &mut OdStore) {
    let mut reply = [0u8; 128];
    let mut sm0 = [0u8; 128];
    for cnt in [1u8, 2] {
        sm0[..16].copy_from_slice(&upload_req(cnt, 0x1000, 0));
        if let Some(n) = server.handle(&sm0, AlState::PreOp, od, &mut reply) {
            assert_eq!(n, 16);
            assert_eq!(reply[..5], [0x0A, 0, 0, 0, 0]);
            assert_eq!(reply[5] & 0x0F, 0x03);
            assert_eq!(
                reply[6..16],
                hex("00 30  43 00 10 00  92 01 02 00")[..],
                "expedited upload response"
            );
            return;
        }
    }
    panic!("no answer to a correct request");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    #[test]
    fn random_mailboxes_never_panic_and_the_server_recovers(
        blobs in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..160), 1..8),
        sm0 in 0usize..200,
        sm1 in 0usize..200,
        st in state(),
        ca in any::<bool>(),
    ) {
        let config = CoeConfig { complete_access: ca, ..CoeConfig::default() };
        let mut server = CoeServer::new(config);
        let mut od = OdStore::new(fixture::OBJECTS).unwrap();
        for b in &blobs {
            feed(&mut server, &mut od, b, sm0, sm1, st);
        }
        answers_correctly(&mut server, &mut od);
    }

    #[test]
    fn mutated_requests_never_panic_and_the_server_recovers(
        picks in proptest::collection::vec(
            (0usize..15, proptest::collection::vec(mutation(), 0..4)), 1..12),
        sm in 16usize..160,
        st in state(),
    ) {
        let t = templates();
        let mut server = CoeServer::new(CoeConfig::default());
        let mut od = OdStore::new(fixture::OBJECTS).unwrap();
        for (i, muts) in &picks {
            let m = mutate(t[*i % t.len()].clone(), muts);
            feed(&mut server, &mut od, &m, sm, sm, st);
        }
        answers_correctly(&mut server, &mut od);
    }

    #[test]
    fn mailbox_views_never_panic(b in proptest::collection::vec(any::<u8>(), 0..120)) {
        let _ = MailboxMessage::parse(&b);
        let _ = SdoRequest::parse(&b);
        let _ = SdoResponse::parse(&b);
        let _ = ecdrive_core::ec::mailbox::SdoInfoFragment::parse(&b);
        if let Ok(e) = ecdrive_core::ec::mailbox::EntryDescription::parse(&b) {
            let _ = e.values();
        }
        let _ = ecdrive_core::ec::mailbox::OdList::parse(&b).map(|l| l.values().count());
        let _ = ecdrive_core::ec::mailbox::ObjectDescription::parse(&b);
    }
}

fn sdo_request() -> impl Strategy<Value = (u8, u16, u8, bool, bool, bool, u32, Vec<u8>)> {
    (
        0u8..6,
        any::<u16>(),
        any::<u8>(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<u32>(),
        proptest::collection::vec(any::<u8>(), 0..60),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
    #[test]
    fn sdo_requests_round_trip((kind, index, sub, ca, t, last, code, data) in sdo_request()) {
        let exp = &data[..data.len().clamp(1, 4).min(data.len())];
        let req = match kind {
            0 if !exp.is_empty() => SdoRequest::DownloadExpedited { index, sub, complete_access: ca, data: exp },
            0 | 1 => SdoRequest::DownloadNormal {
                index, sub, complete_access: ca, complete_size: code, data: &data,
            },
            2 => SdoRequest::DownloadSegment { toggle: t, last, data: &data },
            3 => SdoRequest::Upload { index, sub, complete_access: ca },
            4 => SdoRequest::UploadSegment { toggle: t },
            _ => SdoRequest::Abort { index, sub, code },
        };
        let mut buf = [0u8; 128];
        let n = req.emit_mailbox(5, &mut buf).unwrap();
        prop_assert!(n >= 16, "SDO messages have mailbox length ≥ 10");
        prop_assert_eq!(MailboxMessage::parse(&buf[..n]).unwrap(), (5, MailboxMessage::SdoRequest(req)));
        // A too-small buffer is an error, not a panic.
        prop_assert!(req.emit_mailbox(5, &mut buf[..n - 1]).is_err());
    }

    #[test]
    fn sdo_responses_round_trip((kind, index, sub, ca, t, last, code, data) in sdo_request()) {
        let exp = &data[..data.len().clamp(1, 4).min(data.len())];
        let resp = match kind {
            0 if !exp.is_empty() => SdoResponse::UploadExpedited { index, sub, complete_access: ca, data: exp },
            0 | 1 => SdoResponse::UploadNormal {
                index, sub, complete_access: ca,
                complete_size: data.len() as u32 + (code % 100), data: &data,
            },
            2 => SdoResponse::UploadSegment { toggle: t, last, data: &data },
            3 => SdoResponse::Download { index, sub },
            4 => SdoResponse::DownloadSegment { toggle: t },
            _ => SdoResponse::Abort { index, sub, code },
        };
        let mut buf = [0u8; 128];
        let n = resp.emit_mailbox(3, &mut buf).unwrap();
        let parsed = MailboxMessage::parse(&buf[..n]).unwrap();
        match resp {
            // Aborts travel as SDO requests (the abort service).
            SdoResponse::Abort { index, sub, code } => prop_assert_eq!(
                parsed, (3, MailboxMessage::SdoRequest(SdoRequest::Abort { index, sub, code }))),
            _ => prop_assert_eq!(parsed, (3, MailboxMessage::SdoResponse(resp))),
        }
    }
}

/// Values that make valid PDO configuration writes likely.
fn pdo_write() -> impl Strategy<Value = (u16, u8, Vec<u8>, bool)> {
    let index = prop_oneof![
        Just(0x1C12u16),
        Just(0x1C13),
        Just(0x1600),
        Just(0x1601),
        Just(0x1A00),
        Just(0x1A01),
    ];
    let value = prop_oneof![
        (0u8..5).prop_map(|n| vec![n]),
        prop_oneof![
            Just(0x1600u16),
            Just(0x1601),
            Just(0x1A00),
            Just(0x1A01),
            Just(0)
        ]
        .prop_map(|v| v.to_le_bytes().to_vec()),
        prop_oneof![
            Just(0x6040_0010u32),
            Just(0x607A_0020),
            Just(0x60FF_0020),
            Just(0x6060_0008),
            Just(0x6041_0010),
            Just(0x6064_0020),
            Just(0x6061_0008),
            Just(0x0000_0008),
            Just(0),
        ]
        .prop_map(|v| v.to_le_bytes().to_vec()),
        proptest::collection::vec(any::<u8>(), 0..16),
    ];
    (index, 0u8..6, value, any::<bool>())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    /// Whatever the master writes, the PDO configuration stays readable and every mapped entry
    /// is padding or an object mappable in its direction with the right size.
    #[test]
    fn random_pdo_writes_keep_the_mapping_consistent(
        writes in proptest::collection::vec(pdo_write(), 1..60)
    ) {
        let mut od = OdStore::new(fixture::OBJECTS).unwrap();
        for (index, sub, data, ca) in &writes {
            let _ = if *ca {
                od.write_complete(*index, *sub % 2, AlState::PreOp, data)
            } else {
                od.write(*index, *sub, AlState::PreOp, data)
            };
        }
        let m = od.mapping().unwrap();
        for dir in [Direction::Rx, Direction::Tx] {
            let flag = match dir {
                Direction::Rx => EntryAccess::RXPDO,
                Direction::Tx => EntryAccess::TXPDO,
            };
            for pdo in m.pdos(dir) {
                for e in pdo.entries.iter().filter(|e| !e.is_padding()) {
                    let d = od.entry_desc(ObjectAddress::new(e.index, e.sub)).unwrap();
                    prop_assert!(d.access.contains(flag));
                    prop_assert_eq!(d.bit_len, u16::from(e.bits));
                }
            }
        }
    }

    #[test]
    fn random_dictionary_accesses_never_panic(
        index in prop_oneof![
            proptest::sample::select(fixture::OBJECTS.iter().map(|o| o.index).collect::<Vec<_>>()),
            any::<u16>()
        ],
        sub in 0u8..16,
        data in proptest::collection::vec(any::<u8>(), 0..80),
        st in state(),
        buf_len in 0usize..80,
    ) {
        let mut od = OdStore::new(fixture::OBJECTS).unwrap();
        let _ = od.write(index, sub, st, &data);
        let _ = od.write_complete(index, sub, st, &data);
        let mut buf = vec![0u8; buf_len];
        let _ = od.read(index, sub, st, &mut buf);
        let _ = od.read_complete(index, sub, st, &mut buf);
        let _ = od.set_raw(ObjectAddress::new(index, sub), &data);
    }
}

/// One request through SM0/SM1 of `sm` bytes; the reply bytes.
fn exchange(
    server: &mut CoeServer,
    od: &mut OdStore,
    req: &SdoRequest<'_>,
    cnt: u8,
    sm: usize,
) -> Vec<u8> {
    let mut sm0 = vec![0u8; sm];
    req.emit_mailbox(cnt, &mut sm0).unwrap();
    let mut sm1 = vec![0u8; sm];
    let n = server
        .handle(&sm0, AlState::PreOp, od, &mut sm1)
        .expect("a reply");
    sm1.truncate(n);
    sm1
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
    /// Segmentation both ways through any mailbox size: a download split with the client
    /// helpers arrives whole, and an upload reassembled the way ethercrab and SOEM do it returns
    /// the stored value.
    #[test]
    fn segmented_transfers_through_any_mailbox_size(
        text in proptest::collection::vec(0x20u8..0x7F, 0..=16),
        sm in 16usize..80,
    ) {
        let mut server = CoeServer::new(CoeConfig::default());
        let mut od = OdStore::new(fixture::OBJECTS).unwrap();
        let mut cnt = 0u8;
        let mut next = || { cnt = cnt % 7 + 1; cnt };
        // Download into 0x2004.
        let (init, mut sent) = SdoRequest::initiate_download(0x2004, 0, false, &text, sm);
        let r = exchange(&mut server, &mut od, &init, next(), sm);
        prop_assert_eq!(r[8], 0x60, "initiate download response");
        let mut toggle = false;
        while sent < text.len() {
            let (seg, k) = SdoRequest::download_segment(&text[sent..], toggle, sm);
            let r = exchange(&mut server, &mut od, &seg, next(), sm);
            prop_assert_eq!(r[8], 0x20 | (u8::from(toggle) << 4), "segment response");
            sent += k;
            toggle = !toggle;
        }
        prop_assert!(!server.transfer_in_progress());
        prop_assert_eq!(od.raw(ObjectAddress::new(0x2004, 0)).unwrap(), &text[..]);
        // Upload 0x1008 (60 bytes) and 0x2004 back.
        for (index, want) in [(0x1008u16, fixture::DEVICE_NAME.as_bytes()), (0x2004, &text[..])] {
            let r = exchange(&mut server, &mut od, &SdoRequest::Upload { index, sub: 0, complete_access: false }, next(), sm);
            let mut got = Vec::new();
            match MailboxMessage::parse(&r).unwrap().1 {
                MailboxMessage::SdoResponse(SdoResponse::UploadExpedited { data, .. }) => got.extend_from_slice(data),
                MailboxMessage::SdoResponse(SdoResponse::UploadNormal { complete_size, data, .. }) => {
                    got.extend_from_slice(data);
                    let mut toggle = false;
                    while got.len() < complete_size as usize {
                        let r = exchange(&mut server, &mut od, &SdoRequest::UploadSegment { toggle }, next(), sm);
                        match MailboxMessage::parse(&r).unwrap().1 {
                            MailboxMessage::SdoResponse(SdoResponse::UploadSegment { toggle: t, last, data }) => {
                                prop_assert_eq!(t, toggle);
                                got.extend_from_slice(data);
                                prop_assert_eq!(last, got.len() == complete_size as usize);
                            }
                            other => prop_assert!(false, "unexpected {:?}", other),
                        }
                        toggle = !toggle;
                    }
                }
                other => prop_assert!(false, "unexpected {:?}", other),
            }
            prop_assert_eq!(&got[..], want);
        }
    }
}
