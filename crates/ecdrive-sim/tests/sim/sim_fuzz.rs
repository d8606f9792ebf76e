//! Garbage never hurts the emulated slaves: random frames, random datagrams and truncated or
//! corrupted frames never panic, a frame is either dropped or returned with its length, header
//! and datagram framing unchanged, and the segment still answers correctly afterwards.

use ecdrive_core::ec::Command;
use ecdrive_core::ec::frame::{
    EthercatFrame, EthernetFrame, FrameBuilder, MAX_FRAME_LEN, physical_address,
};
use ecdrive_sim::devices::{EchoMailbox, GenericCoeDevice, IoDevice};
use ecdrive_sim::probe::{PROBE_MAC, Probe};
use ecdrive_sim::{Device, EscConfig, ManualClock, Segment};
use proptest::prelude::*;
use std::sync::Arc;

fn fresh_probe() -> (Probe, ManualClock) {
    let clock = ManualClock::new(1_000_000_000);
    let mut seg = Segment::new(Arc::new(clock.clone()));
    let devs: Vec<Box<dyn Device>> = vec![
        Box::new(IoDevice::new(2, 4)),
        Box::new(EchoMailbox::new()),
        Box::new(IoDevice::new(1, 1)),
        Box::new(GenericCoeDevice::new(4).unwrap()),
    ];
    for d in devs {
        seg.push(d, EscConfig::default()).unwrap();
    }
    let mut p = Probe::new(seg);
    p.assign_addresses(0x1000).unwrap();
    // Put the mailbox device in PRE-OP so that mailbox paths are live, and give the I/O
    // devices an FMMU over RAM so logical commands hit something.
    p.fpwr(
        0x1001,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    p.fpwr(0x1001, 0x0120, &[0x02, 0]).unwrap();
    p.fpwr(
        0x1003,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    p.fpwr(0x1003, 0x0120, &[0x02, 0]).unwrap();
    assert_eq!(p.read_u16(0x1003, 0x0130).unwrap().0, 0x0002);
    let mut f = [0u8; 16];
    f[4] = 8;
    f[7] = 7;
    f[8..10].copy_from_slice(&0x1400u16.to_le_bytes());
    f[11] = 3;
    f[12] = 1;
    p.bwr(0x0600, &f).unwrap();
    (p, clock)
}

/// The segment still behaves: every slave answers BRD/APRD/FPRD with the right working
/// counter and identification data.
fn still_sane(p: &mut Probe) {
    let n = p.segment.len() as u16;
    let r = p.brd(0x0000, 1).expect("BRD answered");
    assert_eq!((r.wkc, r.adp, r.data[0]), (n, n, 0x04));
    for pos in 0..n {
        let r = p.aprd(pos, 0x0004, 2).expect("APRD answered");
        assert_eq!((r.wkc, r.data.clone()), (1, vec![8, 8]), "slave {pos}");
        // Re-assign the address (random writes may have changed it) and read it back.
        p.apwr(pos, 0x0010, &(0x3000 + pos).to_le_bytes()).unwrap();
        let r = p.fprd(0x3000 + pos, 0x0010, 2).unwrap();
        assert_eq!(
            (r.wkc, r.data.clone()),
            (1, (0x3000 + pos).to_le_bytes().to_vec())
        );
    }
}

/// Process a frame; if it comes back, its size and framing are unchanged.
fn process_and_check(p: &mut Probe, frame: &mut [u8]) {
    let orig = frame.to_vec();
    match p.segment.process(frame) {
        Err(_) => assert_eq!(frame, &orig[..], "a dropped frame is left untouched"),
        Ok(n) => {
            assert_eq!(n, orig.len());
            assert_eq!(frame[6], orig[6] | 0x02, "U/L bit");
            assert_eq!(&frame[0..6], &orig[0..6]);
            assert_eq!(&frame[7..16], &orig[7..16]);
            let a = EthernetFrame::new_checked(&orig[..]).unwrap();
            let b = EthernetFrame::new_checked(&frame[..]).unwrap();
            let (a, b) = (
                EthercatFrame::new_checked(a.payload()).unwrap(),
                EthercatFrame::new_checked(b.payload()).unwrap(),
            );
            for (x, y) in a.datagrams().zip(b.datagrams()) {
                let (x, y) = (x.unwrap(), y.unwrap());
                assert_eq!(x.command_raw(), y.command_raw());
                assert_eq!(x.index(), y.index());
                assert_eq!(x.data_len(), y.data_len());
                assert_eq!(x.more(), y.more());
                assert_eq!(x.circulating(), y.circulating());
                if !x.command().is_some_and(|c| c.increments_adp()) {
                    assert_eq!(x.adp(), y.adp());
                }
                if x.command().is_none() {
                    assert_eq!(x.data(), y.data(), "reserved commands pass untouched");
                }
            }
        }
    }
}

fn datagram() -> impl Strategy<Value = (u8, u32, Vec<u8>)> {
    let cmd = prop_oneof![0u8..=14u8, any::<u8>()];
    let ado = prop_oneof![
        any::<u16>(),
        0x0000u16..0x0200,
        0x0500u16..0x0510,
        0x0600u16..0x0700,
        0x0800u16..0x0840,
        0x0900u16..0x09B0,
        0x1000u16..0x1100,
    ];
    let adp = prop_oneof![any::<u16>(), 0x1000u16..0x1004, 0xFFFCu16..=0xFFFF, 0u16..4];
    (
        cmd,
        adp,
        ado,
        prop::collection::vec(any::<u8>(), 0..48),
        any::<bool>(),
    )
        .prop_map(|(c, adp, ado, data, logical)| {
            let addr = if logical && (10..=12).contains(&c) {
                u32::from(ado) & 0x3F
            } else {
                physical_address(adp, ado)
            };
            (c, addr, data)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..200), ecat in any::<bool>()) {
        let (mut p, _) = fresh_probe();
        let mut frame = bytes;
        if ecat && frame.len() >= 14 {
            frame[12] = 0x88;
            frame[13] = 0xA4;
        }
        process_and_check(&mut p, &mut frame);
        still_sane(&mut p);
    }

    #[test]
    fn random_datagrams_never_panic(
        dgs in prop::collection::vec(datagram(), 1..8),
        advance in 0u64..5_000_000,
    ) {
        let (mut p, clock) = fresh_probe();
        let mut buf = vec![0u8; MAX_FRAME_LEN];
        let mut b = FrameBuilder::new(&mut buf, PROBE_MAC).unwrap();
        for (i, (c, a, d)) in dgs.iter().enumerate() {
            b.push_raw(*c, i as u8, *a, d).unwrap();
        }
        let n = b.finish();
        clock.advance(advance);
        process_and_check(&mut p, &mut buf[..n]);
        // And again, after time has passed (SYNC0, watchdogs).
        clock.advance(advance);
        process_and_check(&mut p, &mut buf[..n]);
        p.segment.poll();
        still_sane(&mut p);
    }

    #[test]
    fn truncated_and_corrupted_frames_never_panic(
        dgs in prop::collection::vec(datagram(), 1..6),
        cut in any::<prop::sample::Index>(),
        flip_at in any::<prop::sample::Index>(),
        flip in any::<u8>(),
    ) {
        let (mut p, _) = fresh_probe();
        let mut buf = vec![0u8; MAX_FRAME_LEN];
        let mut b = FrameBuilder::new(&mut buf, PROBE_MAC).unwrap();
        for (i, (c, a, d)) in dgs.iter().enumerate() {
            b.push_raw(*c, i as u8, *a, d).unwrap();
        }
        let n = b.finish();
        // Truncated anywhere.
        let cut = cut.index(n + 1);
        let mut t = buf[..cut].to_vec();
        process_and_check(&mut p, &mut t);
        // One corrupted byte in the EtherCAT part (header, lengths, flags, data).
        let mut c = buf[..n].to_vec();
        let at = 14 + flip_at.index(n - 14);
        c[at] ^= flip | 1;
        process_and_check(&mut p, &mut c);
        still_sane(&mut p);
    }
}

#[test]
fn garbage_between_good_frames_does_not_change_answers() {
    let (mut p, _) = fresh_probe();
    let mut junk = vec![0u8; 60];
    junk[12] = 0x88;
    junk[13] = 0xA4;
    junk[14] = 0xFF;
    junk[15] = 0x17; // reserved bit set
    let before = p.fprd(0x1000, 0x0300, 1).unwrap().data[0];
    assert!(p.segment.process(&mut junk).is_err());
    assert_eq!(p.fprd(0x1000, 0x0300, 1).unwrap().data[0], before + 1);
    let r = p.physical(Command::Brd, 0, 0x0130, &[0, 0]).unwrap();
    assert_eq!(r.wkc, 4);
    assert_eq!(p.segment.stats().invalid_frames, 1);
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
    /// Random mailbox content written into the CoE device's SM0: the CoE server behind the
    /// ESC never panics, and a valid SDO upload still gets its answer afterwards.
    #[test]
    fn random_mailboxes_into_the_coe_device(
        msgs in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..128), 1..6),
    ) {
        let (mut p, _) = fresh_probe();
        for m in &msgs {
            let mut full = vec![0u8; 128];
            full[..m.len()].copy_from_slice(m);
            p.fpwr(0x1003, 0x1000, &full).unwrap();
            // Drain whatever reply came.
            p.fprd(0x1003, 0x1080, 128).unwrap();
        }
        // Drain unsolicited messages (SDO info fragments) until SM1 stays empty.
        for _ in 0..64 {
            if p.fprd(0x1003, 0x080D, 1).unwrap().data[0] & 0x08 == 0 {
                break;
            }
            p.fprd(0x1003, 0x1080, 128).unwrap();
        }
        // A fresh, valid upload of 0x1018:01 (counter 7, unlikely to repeat the last one;
        // send twice with different counters to be sure one is new).
        let mut answered = false;
        for counter in [6u8, 7] {
            let mut req = vec![0u8; 128];
            req[0] = 10;
            req[5] = 0x03 | counter << 4;
            req[6..8].copy_from_slice(&0x2000u16.to_le_bytes());
            req[8] = 0x40;
            req[9..11].copy_from_slice(&0x1018u16.to_le_bytes());
            req[11] = 1;
            prop_assert_eq!(p.fpwr(0x1003, 0x1000, &req).unwrap().wkc, 1);
            let r = p.fprd(0x1003, 0x1080, 128).unwrap();
            if r.wkc == 1 && r.data[8] == 0x43 {
                prop_assert_eq!(&r.data[12..16], &0x0ECDu32.to_le_bytes()[..]);
                answered = true;
            }
        }
        prop_assert!(answered);
        still_sane(&mut p);
    }
}
