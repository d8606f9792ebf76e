//! Register-level tests of the emulated ESC through whole frames: working counters and
//! auto-increment for every command, write masks, SII interface, AL state machine with its
//! refusal codes, SyncManager mailbox handshake and repeat, process data, SM watchdog and DC.

use ecdrive_core::ec::{AlState, AlStatusCode, Command};
use ecdrive_sim::devices::{EchoMailbox, IoDevice};
use ecdrive_sim::probe::{Probe, Request};
use ecdrive_sim::sii::{SII_CRC, SiiImage};
use ecdrive_sim::{Device, EscConfig, ManualClock, Segment, SegmentConfig};
use std::sync::Arc;

const T0: u64 = 1_000_000_000_000;

fn probe_with(devices: Vec<Box<dyn Device>>, cfg: EscConfig) -> (Probe, ManualClock) {
    let clock = ManualClock::new(T0);
    let mut seg = Segment::with_config(Arc::new(clock.clone()), SegmentConfig::default());
    for d in devices {
        seg.push(d, cfg.clone()).unwrap();
    }
    (Probe::new(seg), clock)
}

fn io_segment(n: usize) -> (Probe, ManualClock) {
    let devs = (0..n)
        .map(|i| Box::new(IoDevice::new(2, 4).with_serial(i as u32)) as Box<dyn Device>)
        .collect();
    let cfg = EscConfig {
        sm_watchdog: 0,
        ..Default::default()
    };
    let (mut p, c) = probe_with(devs, cfg);
    p.assign_addresses(0x1000).unwrap();
    (p, c)
}

fn u16le(d: &[u8]) -> u16 {
    u16::from_le_bytes([d[0], d[1]])
}

fn u32le(d: &[u8]) -> u32 {
    u32::from_le_bytes([d[0], d[1], d[2], d[3]])
}

fn u64le(d: &[u8]) -> u64 {
    u64::from_le_bytes(d[0..8].try_into().unwrap())
}

/// SM and FMMU setup of an IoDevice (SM0 outputs 2 bytes at 0x1000, SM1 inputs 4 bytes at
/// 0x1800) mapping outputs to logical `out` and inputs to logical `inp`.
fn configure_io(p: &mut Probe, station: u16, out: u32, inp: u32) {
    assert_eq!(
        p.fpwr(station, 0x0800, &[0x00, 0x10, 2, 0, 0x64, 0, 1, 0])
            .unwrap()
            .wkc,
        1
    );
    assert_eq!(
        p.fpwr(station, 0x0808, &[0x00, 0x18, 4, 0, 0x20, 0, 1, 0])
            .unwrap()
            .wkc,
        1
    );
    let mut f0 = [0u8; 16];
    f0[0..4].copy_from_slice(&out.to_le_bytes());
    f0[4..6].copy_from_slice(&2u16.to_le_bytes());
    f0[7] = 7;
    f0[8..10].copy_from_slice(&0x1000u16.to_le_bytes());
    f0[11] = 2;
    f0[12] = 1;
    assert_eq!(p.fpwr(station, 0x0600, &f0).unwrap().wkc, 1);
    let mut f1 = [0u8; 16];
    f1[0..4].copy_from_slice(&inp.to_le_bytes());
    f1[4..6].copy_from_slice(&4u16.to_le_bytes());
    f1[7] = 7;
    f1[8..10].copy_from_slice(&0x1800u16.to_le_bytes());
    f1[11] = 1;
    f1[12] = 1;
    assert_eq!(p.fpwr(station, 0x0610, &f1).unwrap().wkc, 1);
}

fn to_state(p: &mut Probe, station: u16, ctl: u16) -> (u16, u16) {
    p.request_state(station, ctl).unwrap()
}

// ------------------------------------------------------------------------------ commands / WKC

#[test]
fn broadcast_read_counts_every_slave_and_ors_data() {
    let (mut p, _) = io_segment(3);
    let r = p.brd(0x0000, 1).unwrap();
    assert_eq!(r.wkc, 3);
    assert_eq!(r.adp, 3, "BRD increments ADP at every slave");
    assert_eq!(r.data, vec![0x04]);
    // AL status of all slaves ORed: all INIT.
    let r = p.brd(0x0130, 2).unwrap();
    assert_eq!((r.wkc, u16le(&r.data)), (3, 0x0001));
    // One slave in PREOP shows up as a mixed state in the OR.
    assert_eq!(to_state(&mut p, 0x1001, 0x0002).0, 0x0002);
    let r = p.brd(0x0130, 2).unwrap();
    assert_eq!(u16le(&r.data), 0x0003);
}

#[test]
fn broadcast_write_counts_only_existing_writable_registers() {
    let (mut p, _) = io_segment(3);
    assert_eq!(p.bwr(0x0120, &[0x01, 0x00]).unwrap().wkc, 3);
    // AL status is read-only.
    assert_eq!(p.bwr(0x0130, &[0x08, 0x00]).unwrap().wkc, 0);
    assert_eq!(p.brd(0x0130, 2).unwrap().data, vec![0x01, 0x00]);
    // FMMU 4 exists (8 FMMUs), FMMU 8 does not.
    assert_eq!(p.bwr(0x0640, &[0; 16]).unwrap().wkc, 3);
    assert_eq!(p.bwr(0x0680, &[0; 16]).unwrap().wkc, 0);
    // SM 8 does not exist either.
    assert_eq!(p.bwr(0x0840, &[0; 8]).unwrap().wkc, 0);
    // The DC system time difference is read-only.
    assert_eq!(p.bwr(0x092C, &[0; 4]).unwrap().wkc, 0);
    // The receive-time latch counts although nothing is stored.
    assert_eq!(p.bwr(0x0900, &[0; 4]).unwrap().wkc, 3);
    let r = p.bwr(0x0000, &[0xAA]).unwrap();
    assert_eq!(r.wkc, 0);
    assert_eq!(r.adp, 3);
}

#[test]
fn broadcast_without_dc_counts_only_dc_slaves() {
    let clock = ManualClock::new(T0);
    let mut seg = Segment::new(Arc::new(clock));
    seg.push(Box::new(IoDevice::new(2, 4)), EscConfig::default())
        .unwrap();
    seg.push(
        Box::new(IoDevice::new(2, 4)),
        EscConfig {
            dc: ecdrive_sim::DcSupport::None,
            ..Default::default()
        },
    )
    .unwrap();
    seg.push(Box::new(IoDevice::new(2, 4)), EscConfig::default())
        .unwrap();
    let mut p = Probe::new(seg);
    assert_eq!(p.bwr(0x0900, &[0; 4]).unwrap().wkc, 2);
    assert_eq!(p.bwr(0x0910, &[0; 8]).unwrap().wkc, 2);
    assert_eq!(p.brd(0x0008, 2).unwrap().data[0] & 0x04, 0x04);
}

#[test]
fn broadcast_read_write_returns_old_or_and_writes_new() {
    let (mut p, _) = io_segment(3);
    for (i, v) in [0x01u8, 0x02, 0x04].into_iter().enumerate() {
        p.fpwr(0x1000 + i as u16, 0x0F80, &[v]).unwrap();
    }
    let r = p.physical(Command::Brw, 0, 0x0F80, &[0x80]).unwrap();
    assert_eq!(r.wkc, 9, "BRW: +1 read +2 write per slave");
    assert_eq!(
        r.data,
        vec![0x87],
        "old contents ORed into the written value"
    );
    // Each slave writes the data as it arrives there, i.e. ORed by the slaves before it.
    for (i, v) in [0x80u8, 0x81, 0x83].into_iter().enumerate() {
        assert_eq!(p.fprd(0x1000 + i as u16, 0x0F80, 1).unwrap().data, vec![v]);
    }
}

#[test]
fn auto_increment_addresses_by_position() {
    let (mut p, _) = io_segment(3);
    for pos in 0..3u16 {
        let r = p.aprd(pos, 0x0010, 2).unwrap();
        assert_eq!(r.wkc, 1);
        assert_eq!(u16le(&r.data), 0x1000 + pos);
        assert_eq!(r.adp, 0u16.wrapping_sub(pos).wrapping_add(3));
    }
    // Beyond the last slave nobody answers; ADP still counts every slave.
    let r = p.aprd(5, 0x0010, 2).unwrap();
    assert_eq!((r.wkc, r.data.clone()), (0, vec![0, 0]));
    assert_eq!(r.adp, 0u16.wrapping_sub(5).wrapping_add(3));
    // APRW: old value back, new value stored, WKC 3.
    let r = p
        .physical(Command::Aprw, 0u16.wrapping_sub(2), 0x0010, &[0x34, 0x12])
        .unwrap();
    assert_eq!((r.wkc, u16le(&r.data)), (3, 0x1002));
    assert_eq!(p.read_u16(0x1234, 0x0010).unwrap(), (0x1234, 1));
    // APWR to a read-only register does not count.
    assert_eq!(p.apwr(1, 0x0130, &[8, 0]).unwrap().wkc, 0);
}

#[test]
fn configured_address_commands() {
    let (mut p, _) = io_segment(3);
    let r = p.fprd(0x1001, 0x0010, 2).unwrap();
    assert_eq!((r.wkc, r.adp, u16le(&r.data)), (1, 0x1001, 0x1001));
    // Unknown address: no one answers, nothing changes.
    let r = p.fprd(0x2000, 0x0010, 2).unwrap();
    assert_eq!((r.wkc, r.adp, r.data.clone()), (0, 0x2000, vec![0, 0]));
    assert_eq!(p.fpwr(0x1002, 0x0F80, &[7]).unwrap().wkc, 1);
    let r = p.physical(Command::Fprw, 0x1002, 0x0F80, &[9]).unwrap();
    assert_eq!((r.wkc, r.data.clone()), (3, vec![7]));
    assert_eq!(p.fprd(0x1002, 0x0F80, 1).unwrap().data, vec![9]);
    // Reading past the register space into RAM that no SM covers works like memory.
    let r = p.fprd(0x1002, 0x0FFF, 3).unwrap();
    assert_eq!(r.wkc, 1);
    // A station address change takes effect for the next datagram in the same frame.
    let rs = p
        .frame(&[
            Request::physical(Command::Fpwr, 0x1000, 0x0010, &[0x00, 0x20]),
            Request::physical(Command::Fprd, 0x2000, 0x0010, &[0, 0]),
            Request::physical(Command::Fprd, 0x1000, 0x0010, &[0, 0]),
        ])
        .unwrap();
    assert_eq!(rs[0].wkc, 1);
    assert_eq!((rs[1].wkc, u16le(&rs[1].data)), (1, 0x2000));
    assert_eq!(rs[2].wkc, 0);
}

#[test]
fn station_alias_matches_only_when_enabled() {
    let (mut p, _) = io_segment(2);
    // Alias comes from SII word 4 (0 here) and is read-only for ECAT.
    assert_eq!(p.fpwr(0x1000, 0x0012, &[0x55, 0x00]).unwrap().wkc, 0);
    assert_eq!(p.read_u16(0x0000, 0x0012).unwrap().1, 0);
    // Enable alias addressing (DL control 0x0103 bit 0): alias 0 now also matches.
    assert_eq!(p.bwr(0x0103, &[1]).unwrap().wkc, 2);
    assert_eq!(p.fprd(0x0000, 0x0010, 2).unwrap().wkc, 2);
    assert_eq!(p.bwr(0x0103, &[0]).unwrap().wkc, 2);
    assert_eq!(p.fprd(0x0000, 0x0010, 2).unwrap().wkc, 0);
}

#[test]
fn read_multiple_write_commands() {
    let (mut p, clock) = io_segment(3);
    clock.advance(1_000);
    // FRMW: the addressed slave reads its system time, the others take it as a write.
    let r = p.physical(Command::Frmw, 0x1001, 0x0910, &[0; 8]).unwrap();
    assert_eq!(r.wkc, 3);
    assert_ne!(u64le(&r.data), 0, "slave 1's system time");
    assert_eq!(r.adp, 0x1001, "FRMW does not increment ADP");
    // ARMW: position 0 reads, the others write; ADP increments.
    let r = p.physical(Command::Armw, 0, 0x0910, &[0; 8]).unwrap();
    assert_eq!((r.wkc, r.adp), (3, 3));
    // On a register that is read-only, only the reader counts.
    let r = p.physical(Command::Frmw, 0x1000, 0x0130, &[0; 2]).unwrap();
    assert_eq!((r.wkc, u16le(&r.data)), (1, 1));
}

#[test]
fn nop_and_reserved_commands_pass_untouched() {
    let (mut p, _) = io_segment(2);
    let r = p.physical(Command::Nop, 0x1234, 0x0010, &[1, 2]).unwrap();
    assert_eq!((r.wkc, r.adp, r.data), (0, 0x1234, vec![1, 2]));
    // A reserved command code (0x20).
    let mut buf = [0u8; 64];
    let mut b = ecdrive_core::ec::frame::FrameBuilder::new(&mut buf, ecdrive_sim::probe::PROBE_MAC)
        .unwrap();
    b.push_raw(0x20, 1, 0x0010_0000, &[5, 6]).unwrap();
    let n = b.finish();
    let orig = buf;
    let len = p.segment.process(&mut buf[..n]).unwrap();
    assert_eq!(len, n);
    assert_eq!(buf[6], 0x12, "U/L bit set");
    assert_eq!(&buf[12..n], &orig[12..n]);
}

#[test]
fn logical_commands_map_through_fmmus() {
    let (mut p, _) = io_segment(2);
    // Plain RAM through FMMUs (no SyncManager): slave 0 at logical 0x10..0x12 (write) and
    // 0x20..0x24 (read), slave 1 at 0x12..0x14 and 0x24..0x28.
    for (station, out, inp) in [(0x1000u16, 0x10u32, 0x20u32), (0x1001, 0x12, 0x24)] {
        let mut f0 = [0u8; 16];
        f0[0..4].copy_from_slice(&out.to_le_bytes());
        f0[4] = 2;
        f0[7] = 7;
        f0[8..10].copy_from_slice(&0x1400u16.to_le_bytes());
        f0[11] = 2;
        f0[12] = 1;
        p.fpwr(station, 0x0600, &f0).unwrap();
        let mut f1 = f0;
        f1[0..4].copy_from_slice(&inp.to_le_bytes());
        f1[4] = 4;
        f1[8..10].copy_from_slice(&0x1500u16.to_le_bytes());
        f1[11] = 1;
        p.fpwr(station, 0x0610, &f1).unwrap();
        p.fpwr(station, 0x1500, &[station as u8, 0xB, 0xC, 0xD])
            .unwrap();
    }
    let r = p.logical(Command::Lwr, 0x10, &[1, 2, 3, 4]).unwrap();
    assert_eq!(r.wkc, 2);
    assert_eq!(p.fprd(0x1000, 0x1400, 2).unwrap().data, vec![1, 2]);
    assert_eq!(p.fprd(0x1001, 0x1400, 2).unwrap().data, vec![3, 4]);
    let r = p.logical(Command::Lrd, 0x20, &[0; 8]).unwrap();
    assert_eq!(r.wkc, 2);
    assert_eq!(r.data, vec![0x00, 0xB, 0xC, 0xD, 0x01, 0xB, 0xC, 0xD]);
    // LRW covering both: +3 per slave.
    let r = p.logical(Command::Lrw, 0x10, &[0; 0x18]).unwrap();
    assert_eq!(r.wkc, 6);
    // Partial overlap: only slave 1's output FMMU is hit.
    let r = p.logical(Command::Lrw, 0x13, &[9]).unwrap();
    assert_eq!(r.wkc, 2);
    assert_eq!(p.fprd(0x1001, 0x1400, 2).unwrap().data, vec![0, 9]);
    // Outside every FMMU: nobody counts.
    assert_eq!(p.logical(Command::Lrw, 0x1000, &[0; 4]).unwrap().wkc, 0);
}

#[test]
fn bit_granular_fmmu() {
    let (mut p, _) = io_segment(1);
    // Logical bits 0x10.4 ..= 0x10.7 → physical 0x1400 bits 0..3 (write), and back (read)
    // from 0x1401 bits 2..5 → logical 0x11.0 ..= 0x11.3.
    let mut f = [0u8; 16];
    f[0..4].copy_from_slice(&0x10u32.to_le_bytes());
    f[4] = 1;
    f[6] = 4;
    f[7] = 7;
    f[8..10].copy_from_slice(&0x1400u16.to_le_bytes());
    f[11] = 2;
    f[12] = 1;
    p.fpwr(0x1000, 0x0600, &f).unwrap();
    let mut g = [0u8; 16];
    g[0..4].copy_from_slice(&0x11u32.to_le_bytes());
    g[4] = 1;
    g[7] = 3;
    g[8..10].copy_from_slice(&0x1401u16.to_le_bytes());
    g[10] = 2;
    g[11] = 1;
    g[12] = 1;
    p.fpwr(0x1000, 0x0610, &g).unwrap();
    p.fpwr(0x1000, 0x1400, &[0xF0, 0b0010_1000]).unwrap();
    let r = p.logical(Command::Lrw, 0x10, &[0xA5, 0xFF]).unwrap();
    assert_eq!(r.wkc, 3);
    // Written: the high nibble of 0xA5 (0xA) into bits 0..3, bits 4..7 untouched.
    assert_eq!(p.fprd(0x1000, 0x1400, 1).unwrap().data, vec![0xFA]);
    // Read: physical bits 2..5 of 0b0010_1000 = 0b1010 into logical 0x11 bits 0..3; the
    // other bits of the datagram stay as sent.
    assert_eq!(r.data, vec![0xA5, 0xFA]);
}

// ------------------------------------------------------------------------------ registers

#[test]
fn write_masks_protect_read_only_bits() {
    let (mut p, _) = io_segment(1);
    // AL control high byte is reserved.
    p.fpwr(0x1000, 0x0120, &[0x01, 0xFF]).unwrap();
    assert_eq!(p.read_u16(0x1000, 0x0120).unwrap().0, 0x0001);
    // SII control: capability bits 5–7 are read-only; only the write-enable bit is stored.
    let before = p.read_u16(0x1000, 0x0502).unwrap().0;
    assert_eq!(before & 0x0040, 0x0040, "8-byte reads supported");
    p.fpwr(0x1000, 0x0502, &[0x00, 0x00]).unwrap();
    assert_eq!(
        p.read_u16(0x1000, 0x0502).unwrap().0 & 0x00E0,
        before & 0x00E0
    );
    // SM status and PDI control bytes are read-only from ECAT.
    p.fpwr(0x1000, 0x0800, &[0x00, 0x10, 2, 0, 0x64, 0xFF, 0, 0xFF])
        .unwrap();
    let r = p.fprd(0x1000, 0x0800, 8).unwrap();
    assert_eq!(r.data[5], 0x00);
    assert_eq!(r.data[7] & 0x01, 0x01, "PDI keeps SM0 deactivated in INIT");
    // SM configuration cannot change while the SM is enabled.
    p.fpwr(0x1000, 0x0806, &[1]).unwrap();
    p.fpwr(0x1000, 0x0800, &[0x00, 0x11, 9, 0]).unwrap();
    let r = p.fprd(0x1000, 0x0800, 4).unwrap();
    assert_eq!(r.data, vec![0x00, 0x10, 2, 0]);
    // SOEM-style 6-byte read of AL status + code.
    let r = p.fprd(0x1000, 0x0130, 6).unwrap();
    assert_eq!((r.wkc, r.data.len()), (1, 6));
}

#[test]
fn dl_status_reflects_position() {
    let (mut p, _) = io_segment(3);
    let dl: Vec<u16> = (0..3)
        .map(|i| p.read_u16(0x1000 + i, 0x0110).unwrap().0)
        .collect();
    // First and middle: ports 0 and 1 with link and communication, 2/3 loop closed.
    assert_eq!(dl[0], 0x5A33);
    assert_eq!(dl[1], 0x5A33);
    // Last: port 1 loop closed.
    assert_eq!(dl[2], 0x5613);
    // SOEM's rule: port p open ⇔ (dl >> (8+2p)) & 3 == 0b10.
    let open = |v: u16, port: u16| (v >> (8 + 2 * port)) & 3 == 0b10;
    assert!(open(dl[1], 0) && open(dl[1], 1) && !open(dl[1], 2));
    assert!(open(dl[2], 0) && !open(dl[2], 1));
}

#[test]
fn error_counters_clear_on_write_and_count_bad_frames() {
    let (mut p, _) = io_segment(2);
    let mut junk = vec![0u8; 40];
    junk[12] = 0x88;
    junk[13] = 0xA4;
    junk[14] = 0x20; // length 32: runs past the frame
    junk[15] = 0x10;
    assert!(p.segment.process(&mut junk).is_err());
    assert_eq!(p.fprd(0x1000, 0x0300, 1).unwrap().data, vec![1]);
    assert_eq!(p.fprd(0x1001, 0x0300, 1).unwrap().data, vec![0]);
    assert_eq!(p.fpwr(0x1000, 0x0304, &[0]).unwrap().wkc, 1);
    assert_eq!(p.fprd(0x1000, 0x0300, 8).unwrap().data, vec![0; 8]);
}

#[test]
fn ecat_reset_sequence_restores_power_on_state() {
    let (mut p, _) = io_segment(1);
    assert_eq!(to_state(&mut p, 0x1000, 0x0002).0, 0x0002);
    p.fpwr(0x1000, 0x0040, b"R").unwrap();
    p.fpwr(0x1000, 0x0040, b"E").unwrap();
    assert_eq!(p.fprd(0x1000, 0x0040, 1).unwrap().data, vec![2]);
    p.fpwr(0x1000, 0x0040, b"S").unwrap();
    // Station address is gone, state is INIT again.
    assert_eq!(p.fprd(0x1000, 0x0130, 2).unwrap().wkc, 0);
    let r = p.aprd(0, 0x0130, 2).unwrap();
    assert_eq!(u16le(&r.data), 0x0001);
    assert_eq!(p.aprd(0, 0x0010, 2).unwrap().data, vec![0, 0]);
}

// ------------------------------------------------------------------------------ SII

fn sii_read(p: &mut Probe, station: u16, word: u32) -> Vec<u8> {
    let mut req = vec![0x00, 0x01];
    req.extend_from_slice(&word.to_le_bytes());
    assert_eq!(p.fpwr(station, 0x0502, &req).unwrap().wkc, 1);
    let st = p.read_u16(station, 0x0502).unwrap().0;
    assert_eq!(st & 0x8000, 0, "never busy");
    assert_eq!(st & 0x0700, 0, "command done");
    p.fprd(station, 0x0508, 8).unwrap().data
}

#[test]
fn sii_reads_identity_and_crc() {
    let (mut p, _) = io_segment(2);
    let d = sii_read(&mut p, 0x1001, 0x0008);
    assert_eq!(u32le(&d[0..4]), 0x0000_0ECD);
    assert_eq!(u32le(&d[4..8]), 0x0000_0101);
    let d = sii_read(&mut p, 0x1001, 0x000E);
    assert_eq!(u32le(&d[0..4]), 1, "serial of slave 1");
    // Words 0–7: CRC over bytes 0..14 in the low byte of word 7.
    let mut head = sii_read(&mut p, 0x1000, 0);
    head.extend(sii_read(&mut p, 0x1000, 4));
    assert_eq!(head[14], SII_CRC.checksum(&head[..14]));
    assert_eq!(head[15], 0);
    // Beyond the EEPROM: erased.
    assert_eq!(sii_read(&mut p, 0x1000, 0x4000), vec![0xFF; 8]);
    // An unknown command is refused with the command error bit.
    p.fpwr(0x1000, 0x0502, &[0x00, 0x03, 0, 0, 0, 0]).unwrap();
    assert_eq!(p.read_u16(0x1000, 0x0502).unwrap().0 & 0x2000, 0x2000);
}

/// An EEPROM as slow as an I²C one (`eeprom_busy_frames`): busy, the command bits showing the
/// read, for that many frames after the command; a command meanwhile is not taken; then the
/// data is there and the address register names its word. 4-byte reads show bit 6 clear.
#[test]
fn a_slow_eeprom_is_busy_for_its_frames_and_takes_no_command_meanwhile() {
    let devs = vec![Box::new(IoDevice::new(2, 4).with_serial(7)) as Box<dyn Device>];
    let cfg = EscConfig {
        sm_watchdog: 0,
        eeprom_busy_frames: 3,
        eeprom_reads_4_bytes: true,
        ..Default::default()
    };
    let (mut p, _) = probe_with(devs, cfg);
    p.assign_addresses(0x1000).unwrap();
    assert_eq!(
        p.read_u16(0x1000, 0x0502).unwrap().0 & 0x0040,
        0,
        "4-byte reads"
    );
    assert_eq!(
        p.fpwr(0x1000, 0x0502, &[0x00, 0x01, 0x0E, 0, 0, 0])
            .unwrap()
            .wkc,
        1
    );
    // Busy for three frames: the command's, then this read's, then another command's, which
    // is not taken.
    let st = p.read_u16(0x1000, 0x0502).unwrap().0;
    assert_eq!(st & 0x8700, 0x8100, "busy, reading");
    p.fpwr(0x1000, 0x0502, &[0x00, 0x01, 0x08, 0, 0, 0])
        .unwrap();
    let d = p.fprd(0x1000, 0x0502, 14).unwrap().data;
    assert_eq!(u16le(&d[0..2]) & 0x8700, 0, "done");
    assert_eq!(u32le(&d[2..6]), 0x0E, "the word of the command taken");
    assert_eq!(u32le(&d[6..10]), 7, "the serial number");
}

#[test]
fn sii_write_needs_write_enable_and_reload_applies_alias() {
    let (mut p, _) = io_segment(1);
    // Without write enable: write-enable error, nothing written.
    p.fpwr(0x1000, 0x0508, &[0x34, 0x12]).unwrap();
    p.fpwr(0x1000, 0x0502, &[0x00, 0x02, 4, 0, 0, 0]).unwrap();
    assert_eq!(p.read_u16(0x1000, 0x0502).unwrap().0 & 0x4000, 0x4000);
    assert_eq!(&sii_read(&mut p, 0x1000, 4)[0..2], &[0, 0]);
    // With write enable (in the same write as the command).
    p.fpwr(0x1000, 0x0508, &[0x34, 0x12]).unwrap();
    p.fpwr(0x1000, 0x0502, &[0x01, 0x02, 4, 0, 0, 0]).unwrap();
    let st = p.read_u16(0x1000, 0x0502).unwrap().0;
    assert_eq!(st & 0x4001, 0, "no error, write enable self-clears");
    assert_eq!(&sii_read(&mut p, 0x1000, 4)[0..2], &[0x34, 0x12]);
    // Reload with a stale checksum: checksum error, alias not loaded.
    p.fpwr(0x1000, 0x0502, &[0x00, 0x04, 0, 0, 0, 0]).unwrap();
    assert_eq!(p.read_u16(0x1000, 0x0502).unwrap().0 & 0x0800, 0x0800);
    assert_eq!(p.read_u16(0x1000, 0x0012).unwrap().0, 0);
    // Fix the checksum (word 7) and reload.
    let mut head = sii_read(&mut p, 0x1000, 0);
    head.extend(sii_read(&mut p, 0x1000, 4));
    let crc = SII_CRC.checksum(&head[..14]);
    p.fpwr(0x1000, 0x0508, &[crc, 0]).unwrap();
    p.fpwr(0x1000, 0x0502, &[0x01, 0x02, 7, 0, 0, 0]).unwrap();
    p.fpwr(0x1000, 0x0502, &[0x00, 0x04, 0, 0, 0, 0]).unwrap();
    assert_eq!(p.read_u16(0x1000, 0x0502).unwrap().0 & 0x0800, 0);
    assert_eq!(p.read_u16(0x1000, 0x0012).unwrap().0, 0x1234);
    let img: &SiiImage = p.segment.slave(0).unwrap().esc.sii();
    assert!(img.checksum_ok());
}

/// A power cycle (in-process): every register back to its reset value, the station address
/// gone, the device in INIT, and the alias written to the EEPROM (with its checksum) loaded
/// into 0x0012 from the EEPROM, which keeps its content.
#[test]
fn a_power_cycle_keeps_the_eeprom_and_loads_the_alias() {
    let (mut p, _) = io_segment(2);
    let mut head = sii_read(&mut p, 0x1000, 0);
    head.extend(sii_read(&mut p, 0x1000, 4));
    head[8..10].copy_from_slice(&[0xCD, 0xAB]);
    let crc = SII_CRC.checksum(&head[..14]);
    for (word, v) in [(4u8, [0xCD, 0xAB]), (7, [crc, 0])] {
        p.fpwr(0x1000, 0x0508, &v).unwrap();
        p.fpwr(0x1000, 0x0502, &[0x01, 0x02, word, 0, 0, 0])
            .unwrap();
    }
    p.request_state(0x1000, AlState::PreOp as u16).unwrap();
    assert_eq!(
        p.read_u16(0x1000, 0x0012).unwrap().0,
        0,
        "not before a power cycle"
    );
    assert!(p.segment.power_cycle(0));
    assert!(!p.segment.power_cycle(9));
    // The station address is gone (reset value 0): address the device by position.
    let r = p.aprd(0, 0x0010, 2).unwrap();
    assert_eq!(r.data, [0, 0]);
    assert_eq!(p.aprd(0, 0x0012, 2).unwrap().data, [0xCD, 0xAB]);
    assert_eq!(p.aprd(0, 0x0130, 2).unwrap().data, [AlState::Init as u8, 0]);
    // The other device was not touched.
    assert_eq!(p.read_u16(0x1001, 0x0012).unwrap().0, 0);
}

/// A write-protected EEPROM does not acknowledge a write (0x0502 bit 13); the word keeps its
/// value.
#[test]
fn a_write_protected_eeprom_does_not_acknowledge() {
    let (mut p, _) = io_segment(1);
    p.segment
        .slave_mut(0)
        .unwrap()
        .esc
        .set_eeprom_write_protected(true);
    p.fpwr(0x1000, 0x0508, &[0x34, 0x12]).unwrap();
    p.fpwr(0x1000, 0x0502, &[0x01, 0x02, 4, 0, 0, 0]).unwrap();
    assert_eq!(p.read_u16(0x1000, 0x0502).unwrap().0 & 0x6000, 0x2000);
    assert_eq!(&sii_read(&mut p, 0x1000, 4)[0..2], &[0, 0]);
}

// ------------------------------------------------------------------------------ AL state machine

#[test]
fn invalid_transitions_are_refused_with_codes() {
    let (mut p, _) = io_segment(1);
    // INIT → SAFEOP / OP: invalid state change.
    assert_eq!(to_state(&mut p, 0x1000, 0x0004), (0x0011, 0x0011));
    // Not acknowledged: further requests are ignored.
    assert_eq!(to_state(&mut p, 0x1000, 0x0002), (0x0011, 0x0011));
    // Acknowledge together with a valid request.
    assert_eq!(to_state(&mut p, 0x1000, 0x0012), (0x0002, 0x0000));
    // PREOP → OP directly.
    assert_eq!(to_state(&mut p, 0x1000, 0x0008), (0x0012, 0x0011));
    // INIT always works, error or not.
    assert_eq!(to_state(&mut p, 0x1000, 0x0001), (0x0001, 0x0000));
    // Unknown state (0x05).
    assert_eq!(to_state(&mut p, 0x1000, 0x0005), (0x0011, 0x0012));
    assert_eq!(to_state(&mut p, 0x1000, 0x0011), (0x0001, 0x0000));
    // BOOT without a bootstrap mailbox.
    assert_eq!(to_state(&mut p, 0x1000, 0x0003), (0x0011, 0x0013));
    assert_eq!(to_state(&mut p, 0x1000, 0x0011), (0x0001, 0x0000));
}

#[test]
fn process_data_configuration_is_checked_at_safeop() {
    let (mut p, _) = io_segment(1);
    assert_eq!(to_state(&mut p, 0x1000, 0x0002).0, 0x0002);
    // No SMs configured: invalid output configuration.
    assert_eq!(to_state(&mut p, 0x1000, 0x0004), (0x0012, 0x001D));
    // Outputs right, inputs with the wrong length.
    p.fpwr(0x1000, 0x0800, &[0x00, 0x10, 2, 0, 0x64, 0, 1, 0])
        .unwrap();
    p.fpwr(0x1000, 0x0808, &[0x00, 0x18, 3, 0, 0x20, 0, 1, 0])
        .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0014), (0x0012, 0x001E));
    // Outputs with the wrong direction.
    p.fpwr(0x1000, 0x0806, &[0]).unwrap();
    p.fpwr(0x1000, 0x0800, &[0x00, 0x10, 2, 0, 0x20, 0, 1, 0])
        .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0014), (0x0012, 0x001D));
    // Everything right.
    p.fpwr(0x1000, 0x0806, &[0]).unwrap();
    p.fpwr(0x1000, 0x080E, &[0]).unwrap();
    configure_io(&mut p, 0x1000, 0, 0x100);
    assert_eq!(to_state(&mut p, 0x1000, 0x0014), (0x0004, 0x0000));
    assert_eq!(to_state(&mut p, 0x1000, 0x0008), (0x0008, 0x0000));
    // Changing the SM while in OP drops to PREOP with the error.
    p.fpwr(0x1000, 0x080E, &[0]).unwrap();
    let r = p.fprd(0x1000, 0x0130, 6).unwrap();
    assert_eq!(
        (u16le(&r.data[0..2]), u16le(&r.data[4..6])),
        (0x0012, 0x001E)
    );
}

#[test]
fn mailbox_configuration_is_checked_at_preop() {
    let (mut p, _) = probe_with(vec![Box::new(EchoMailbox::new())], EscConfig::default());
    p.assign_addresses(0x1000).unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0002), (0x0011, 0x0016));
    // Wrong length of SM1.
    p.fpwr(
        0x1000,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 64, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0012), (0x0011, 0x0016));
    p.bwr(0x0800, &[0; 16]).unwrap();
    p.fpwr(
        0x1000,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0012), (0x0002, 0x0000));
    // Disabling SM0 in PREOP drops the slave to INIT with the error.
    p.fpwr(0x1000, 0x0806, &[0]).unwrap();
    assert_eq!(p.fprd(0x1000, 0x0130, 6).unwrap().data[4], 0x16);
    assert_eq!(p.read_u16(0x1000, 0x0130).unwrap().0, 0x0011);
}

#[test]
fn device_can_refuse_a_transition() {
    let dev = IoDevice::new(2, 4).refusing(AlState::Op, AlStatusCode::NO_VALID_OUTPUTS);
    let (mut p, _) = probe_with(vec![Box::new(dev)], EscConfig::default());
    p.assign_addresses(0x1000).unwrap();
    configure_io(&mut p, 0x1000, 0, 0x100);
    assert_eq!(to_state(&mut p, 0x1000, 0x0002).0, 0x0002);
    assert_eq!(to_state(&mut p, 0x1000, 0x0004).0, 0x0004);
    assert_eq!(to_state(&mut p, 0x1000, 0x0008), (0x0014, 0x0019));
    let seen = &p.segment.device::<IoDevice>(0).unwrap().seen;
    assert_eq!(
        seen.transitions.last(),
        Some(&(
            AlState::SafeOp,
            AlState::SafeOp,
            Some(AlStatusCode::NO_VALID_OUTPUTS)
        ))
    );
}

// ------------------------------------------------------------------------------ process data

#[test]
fn lrw_working_counter_by_state() {
    let (mut p, _) = io_segment(2);
    configure_io(&mut p, 0x1000, 0x00, 0x10);
    configure_io(&mut p, 0x1001, 0x02, 0x14);
    let lrw = |p: &mut Probe, out: [u8; 4]| {
        let mut d = vec![0u8; 0x18];
        d[0..4].copy_from_slice(&out);
        p.logical(Command::Lrw, 0, &d).unwrap()
    };
    // PREOP: SMs deactivated by the PDI, nothing counts.
    p.bwr(0x0120, &[2, 0]).unwrap();
    assert_eq!(lrw(&mut p, [1, 2, 3, 4]).wkc, 0);
    // SAFE-OP: inputs and outputs count, as slave stacks enable the output SM with SAFE-OP
    // ("the master can check if the slave could update inputs and outputs before switching
    // the slave to OP", ETG.1020); the application does not act on the outputs yet.
    p.bwr(0x0120, &[4, 0]).unwrap();
    assert_eq!(p.brd(0x0130, 2).unwrap().data, vec![4, 0]);
    assert_eq!(lrw(&mut p, [9, 9, 9, 9]).wkc, 6);
    assert_eq!(p.segment.slave(1).unwrap().esc.outputs(), &[9, 9]);
    let r = lrw(&mut p, [1, 2, 3, 4]);
    assert_eq!(&r.data[0x12..0x14], &[0, 0], "no echo before OP");
    // OP: inputs and outputs.
    p.bwr(0x0120, &[8, 0]).unwrap();
    let r = lrw(&mut p, [1, 2, 3, 4]);
    assert_eq!(r.wkc, 6);
    // Outputs reached the devices; inputs carry the counter and the echo (from the previous
    // cycle: the device runs after the frame).
    let r = lrw(&mut p, [5, 6, 7, 8]);
    assert_eq!(&r.data[0x12..0x14], &[1, 2]);
    assert_eq!(&r.data[0x16..0x18], &[3, 4]);
    assert_eq!(p.segment.slave(1).unwrap().esc.outputs(), &[7, 8]);
}

#[test]
fn sm_watchdog_drops_op_to_safeop() {
    let dev = IoDevice::new(2, 4);
    let (mut p, clock) = probe_with(vec![Box::new(dev)], EscConfig::default());
    p.assign_addresses(0x1000).unwrap();
    configure_io(&mut p, 0x1000, 0, 0x10);
    to_state(&mut p, 0x1000, 0x0002);
    to_state(&mut p, 0x1000, 0x0004);
    assert_eq!(to_state(&mut p, 0x1000, 0x0008).0, 0x0008);
    // Outputs every 60 ms keep it in OP (watchdog 100 ms at reset values).
    for _ in 0..5 {
        clock.advance(60_000_000);
        assert_eq!(p.logical(Command::Lrw, 0, &[0; 0x14]).unwrap().wkc, 3);
    }
    // 101 ms of silence: noticed by the next poll.
    clock.advance(101_000_000);
    p.segment.poll();
    let r = p.fprd(0x1000, 0x0130, 6).unwrap();
    assert_eq!(
        (u16le(&r.data[0..2]), u16le(&r.data[4..6])),
        (0x0014, 0x001B)
    );
    assert_eq!(p.read_u16(0x1000, 0x0440).unwrap().0 & 1, 0);
    assert_eq!(p.fprd(0x1000, 0x0442, 1).unwrap().data, vec![1]);
    // Acknowledge and go back to OP.
    assert_eq!(to_state(&mut p, 0x1000, 0x0014), (0x0004, 0));
    assert_eq!(to_state(&mut p, 0x1000, 0x0008), (0x0008, 0));
    // With the watchdog time set to 0 it is off.
    p.fpwr(0x1000, 0x0420, &[0, 0]).unwrap();
    p.logical(Command::Lrw, 0, &[0; 0x14]).unwrap();
    clock.advance(10_000_000_000);
    p.segment.poll();
    assert_eq!(p.read_u16(0x1000, 0x0130).unwrap().0, 0x0008);
}

// ------------------------------------------------------------------------------ mailbox

fn echo_preop() -> (Probe, ManualClock) {
    let (mut p, c) = probe_with(vec![Box::new(EchoMailbox::new())], EscConfig::default());
    p.assign_addresses(0x1000).unwrap();
    p.fpwr(
        0x1000,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0002), (0x0002, 0));
    (p, c)
}

fn mbx(counter: u8, payload: &[u8]) -> Vec<u8> {
    let mut m = vec![0u8; 128];
    m[0..2].copy_from_slice(&(payload.len() as u16).to_le_bytes());
    m[5] = 0x0F | counter << 4;
    m[6..6 + payload.len()].copy_from_slice(payload);
    m
}

#[test]
fn mailbox_handshake() {
    let (mut p, _) = echo_preop();
    // SM1 empty: reading it is refused.
    assert_eq!(p.fprd(0x1000, 0x1080, 128).unwrap().wkc, 0);
    // Write a request: accepted; the firmware answers after the frame.
    assert_eq!(p.fpwr(0x1000, 0x1000, &mbx(1, b"hello")).unwrap().wkc, 1);
    assert_eq!(
        p.fprd(0x1000, 0x080D, 1).unwrap().data[0] & 0x08,
        0x08,
        "SM1 full"
    );
    assert_eq!(
        p.fprd(0x1000, 0x0805, 1).unwrap().data[0] & 0x08,
        0,
        "SM0 consumed"
    );
    // A second request while the reply is unread stays in SM0 …
    assert_eq!(p.fpwr(0x1000, 0x1000, &mbx(2, b"again")).unwrap().wkc, 1);
    assert_eq!(p.fprd(0x1000, 0x0805, 1).unwrap().data[0] & 0x08, 0x08);
    // … and a third is refused: SM0 is full.
    assert_eq!(p.fpwr(0x1000, 0x1000, &mbx(3, b"more")).unwrap().wkc, 0);
    // Reading the reply frees SM1; the firmware then takes the pending request.
    let r = p.fprd(0x1000, 0x1080, 128).unwrap();
    assert_eq!(r.wkc, 1);
    assert_eq!(&r.data[6..11], b"hello");
    let r = p.fprd(0x1000, 0x1080, 128).unwrap();
    assert_eq!((r.wkc, &r.data[6..11]), (1, &b"again"[..]));
    assert_eq!(p.fprd(0x1000, 0x1080, 128).unwrap().wkc, 0, "empty again");
    // A read that does not include the last byte does not free the mailbox.
    p.fpwr(0x1000, 0x1000, &mbx(4, b"part")).unwrap();
    assert_eq!(p.fprd(0x1000, 0x1080, 64).unwrap().wkc, 1);
    assert_eq!(p.fprd(0x1000, 0x080D, 1).unwrap().data[0] & 0x08, 0x08);
    assert_eq!(p.fprd(0x1000, 0x1080, 128).unwrap().wkc, 1);
    let dev = p.segment.device::<EchoMailbox>(0).unwrap();
    assert_eq!(dev.requests.len(), 3);
}

#[test]
fn mailbox_repeat_reposts_the_last_reply() {
    let (mut p, _) = echo_preop();
    p.fpwr(0x1000, 0x1000, &mbx(1, b"first")).unwrap();
    let r = p.fprd(0x1000, 0x1080, 128).unwrap();
    assert_eq!(&r.data[6..11], b"first");
    // The master lost that reply: toggle the repeat request (0x080E bit 1).
    let act = p.fprd(0x1000, 0x080E, 1).unwrap().data[0];
    assert_eq!(p.fpwr(0x1000, 0x080E, &[act ^ 0x02]).unwrap().wkc, 1);
    // Repeat acknowledged in PDI control bit 1, reply posted again.
    assert_eq!(
        p.fprd(0x1000, 0x080F, 1).unwrap().data[0] & 0x02,
        (act ^ 0x02) & 0x02
    );
    let r = p.fprd(0x1000, 0x1080, 128).unwrap();
    assert_eq!((r.wkc, &r.data[6..11]), (1, &b"first"[..]));
    // Toggling back acknowledges again.
    p.fpwr(0x1000, 0x080E, &[act]).unwrap();
    assert_eq!(
        p.fprd(0x1000, 0x080F, 1).unwrap().data[0] & 0x02,
        act & 0x02
    );
}

#[test]
fn unsolicited_messages_wait_for_a_free_read_mailbox() {
    let (mut p, _) = echo_preop();
    p.segment
        .device_mut::<EchoMailbox>(0)
        .unwrap()
        .unsolicited
        .push(mbx(1, b"emcy"));
    // Polling the status lets the firmware post it.
    assert_eq!(p.fprd(0x1000, 0x080D, 1).unwrap().data[0] & 0x08, 0);
    assert_eq!(p.fprd(0x1000, 0x080D, 1).unwrap().data[0] & 0x08, 0x08);
    let r = p.fprd(0x1000, 0x1080, 128).unwrap();
    assert_eq!(&r.data[6..10], b"emcy");
}

#[test]
fn mailbox_is_reset_on_init_and_sm_reconfiguration() {
    let (mut p, _) = echo_preop();
    let resets = p.segment.device::<EchoMailbox>(0).unwrap().resets;
    p.fpwr(0x1000, 0x1000, &mbx(1, b"x")).unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0001), (0x0001, 0));
    assert!(p.segment.device::<EchoMailbox>(0).unwrap().resets > resets);
    // In INIT the mailbox is closed: writes are refused.
    assert_eq!(p.fpwr(0x1000, 0x1000, &mbx(2, b"y")).unwrap().wkc, 0);
    // Disable/enable SMs and go back to PREOP: the old reply is gone.
    p.bwr(0x0800, &[0; 16]).unwrap();
    p.fpwr(
        0x1000,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0002), (0x0002, 0));
    assert_eq!(p.fprd(0x1000, 0x1080, 128).unwrap().wkc, 0);
}

// ------------------------------------------------------------------------------ DC

#[test]
fn receive_time_latch_orders_ports_along_the_line() {
    let (mut p, clock) = io_segment(3);
    clock.advance(12_345);
    assert_eq!(p.bwr(0x0900, &[0; 4]).unwrap().wkc, 3);
    let t: Vec<Vec<u8>> = (0..3)
        .map(|i| p.fprd(0x1000 + i, 0x0900, 16).unwrap().data)
        .collect();
    let p0: Vec<u32> = t.iter().map(|d| u32le(&d[0..4])).collect();
    let p1: Vec<u32> = t.iter().map(|d| u32le(&d[4..8])).collect();
    assert!(p0[0] < p0[1] && p0[1] < p0[2]);
    assert!(p1[0] > p0[0] && p1[1] > p0[1]);
    assert!(p1[0] > p1[1], "the return passes slave 0 last");
    assert_eq!(p1[2], 0, "port 1 of the last slave is closed");
    // Propagation: (p1 - p0) differences give twice the hop delay per slave.
    assert_eq!((p1[0] - p0[0]) - (p1[1] - p0[1]), 2 * 300);
    // 0x0918 holds the EPU receive time as u64.
    let epu = u64le(&p.fprd(0x1001, 0x0918, 8).unwrap().data);
    assert_eq!(epu as u32, p0[1]);
}

#[test]
fn system_time_offset_and_drift_loop() {
    let clock = ManualClock::new(T0);
    let mut seg = Segment::new(Arc::new(clock.clone()));
    for (i, (off, drift)) in [(0i64, 0i64), (5_000_000, 40_000), (-3_000_000, -25_000)]
        .into_iter()
        .enumerate()
    {
        seg.push(
            Box::new(IoDevice::new(2, 4).with_serial(i as u32)),
            EscConfig {
                clock_offset_ns: off,
                clock_drift_ppb: drift,
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    let mut p = Probe::new(seg);
    p.assign_addresses(0x1000).unwrap();
    // Reset as masters do, latch, and set offsets so that system time = master time.
    p.bwr(0x0910, &[0; 8]).unwrap();
    p.bwr(0x0934, &[0x00, 0x0C]).unwrap();
    p.bwr(0x0930, &[0x00, 0x10]).unwrap();
    p.bwr(0x0900, &[0; 4]).unwrap();
    let master_now: u64 = 500_000_000_000;
    let rx0 = u64le(&p.fprd(0x1000, 0x0918, 8).unwrap().data);
    let rx: Vec<u64> = (0..3)
        .map(|i| u64le(&p.fprd(0x1000 + i, 0x0918, 8).unwrap().data))
        .collect();
    let _ = rx0;
    for i in 0..3u16 {
        let off = master_now.wrapping_sub(rx[i as usize]);
        p.fpwr(0x1000 + i, 0x0920, &off.to_le_bytes()).unwrap();
        p.fpwr(0x1000 + i, 0x0928, &(u32::from(i) * 300).to_le_bytes())
            .unwrap();
    }
    // A read of 0x0910 is local time + offset.
    let st = u64le(&p.fprd(0x1001, 0x0910, 8).unwrap().data);
    assert!(st.abs_diff(master_now) < 10_000, "{st} vs {master_now}");
    // Drift compensation: FRMW every ms for 4 s; the followers' 0x092C ends up small.
    for _ in 0..4000 {
        clock.advance(1_000_000);
        assert_eq!(
            p.physical(Command::Frmw, 0x1000, 0x0910, &[0; 8])
                .unwrap()
                .wkc,
            3
        );
    }
    for i in 1..3u16 {
        let diff = p.fprd(0x1000 + i, 0x092C, 4).unwrap();
        let v = u32le(&diff.data) & 0x7FFF_FFFF;
        assert!(v < 50, "slave {i}: |diff| {v} ns");
    }
    // The system times agree (within the hop delays) after drift compensation.
    let r = p
        .frame(&[
            Request::physical(Command::Fprd, 0x1000, 0x0910, &[0; 8]),
            Request::physical(Command::Fprd, 0x1002, 0x0910, &[0; 8]),
        ])
        .unwrap();
    let (a, b) = (u64le(&r[0].data), u64le(&r[1].data));
    assert!(a.abs_diff(b) < 2_000, "{a} vs {b}");
    // The difference register is read-only.
    assert_eq!(p.fpwr(0x1001, 0x092C, &[0; 4]).unwrap().wkc, 0);
}

fn activate_sync0(p: &mut Probe, station: u16, start: u64, cycle: u32) {
    p.fpwr(station, 0x0981, &[0]).unwrap();
    p.fpwr(station, 0x0990, &start.to_le_bytes()).unwrap();
    p.fpwr(station, 0x09A0, &u64::from(cycle).to_le_bytes())
        .unwrap();
    p.fpwr(station, 0x0981, &[0x03]).unwrap();
}

#[test]
fn sync0_events_are_delivered_exactly_and_report_missing_outputs() {
    let (mut p, clock) = io_segment(1);
    configure_io(&mut p, 0x1000, 0, 0x10);
    to_state(&mut p, 0x1000, 0x0002);
    let now = u64le(&p.fprd(0x1000, 0x0910, 8).unwrap().data);
    let start = now + 1_000_000;
    activate_sync0(&mut p, 0x1000, start, 1_000_000);
    assert_eq!(u64le(&p.fprd(0x1000, 0x0990, 8).unwrap().data), start);
    to_state(&mut p, 0x1000, 0x0004);
    to_state(&mut p, 0x1000, 0x0008);
    // 10 cycles, each with one LRW half-way through the cycle.
    clock.advance(1_500_000);
    for _ in 0..10 {
        p.logical(
            Command::Lrw,
            0,
            &[
                0xAA, 0x55, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
            ],
        )
        .unwrap();
        clock.advance(1_000_000);
    }
    p.segment.poll();
    let seen = p.segment.device::<IoDevice>(0).unwrap().seen.clone();
    assert_eq!(seen.sync0_events, 11);
    assert_eq!(seen.sync0_cycle_ns, 1_000_000);
    assert_eq!(seen.last_sync0_ns, Some(start + 10_000_000));
    // The first pulse came (in OP) before any outputs; all others had fresh outputs.
    assert_eq!(seen.cycles_without_outputs, 1);
    assert_eq!(seen.missed_in_op, 1);
    assert_eq!(seen.last_outputs, vec![0xAA, 0x55]);
    // Skip a frame: the next pulse reports no fresh outputs.
    clock.advance(1_000_000);
    p.segment.poll();
    let seen = &p.segment.device::<IoDevice>(0).unwrap().seen;
    assert_eq!((seen.sync0_events, seen.missed_in_op), (12, 2));
    // Reading 0x0990 while running gives the next pulse.
    let next = u64le(&p.fprd(0x1000, 0x0990, 8).unwrap().data);
    assert_eq!(next, start + 12_000_000);
    // Deactivation stops the pulses.
    p.fpwr(0x1000, 0x0981, &[0]).unwrap();
    clock.advance(5_000_000);
    p.segment.poll();
    assert_eq!(
        p.segment.device::<IoDevice>(0).unwrap().seen.sync0_events,
        12
    );
}

/// A start time already past when the Sync Out Unit is activated with 0x03 (what ethercrab,
/// SOEM and KickCAT write): the ESC waits for the system time to reach it, which a 64-bit one
/// never does (datasheet section II, 0x0981 bit 5 = 0). The first pulse stays pending, 0x0990
/// reads the start time, 0x0984 bit 2 says it was outside the near future; the start time
/// cannot be written while the unit is activated, and deactivating, writing a start time ahead
/// and activating again starts the pulses there.
#[test]
fn sync0_start_time_in_the_past_waits_until_the_master_arms_it_again() {
    let (mut p, clock) = io_segment(1);
    let now = u64le(&p.fprd(0x1000, 0x0910, 8).unwrap().data);
    let past = now - 2_500_000;
    activate_sync0(&mut p, 0x1000, past, 1_000_000);
    clock.advance(50_000_000);
    p.segment.poll();
    assert_eq!(
        p.segment.device::<IoDevice>(0).unwrap().seen.sync0_events,
        0
    );
    assert_eq!(u64le(&p.fprd(0x1000, 0x0990, 8).unwrap().data), past);
    assert_eq!(p.fprd(0x1000, 0x0984, 1).unwrap().data[0], 0x05);
    // Written while activated: refused.
    let later = u64le(&p.fprd(0x1000, 0x0910, 8).unwrap().data) + 2_000_000;
    p.fpwr(0x1000, 0x0990, &later.to_le_bytes()).unwrap();
    assert_eq!(u64le(&p.fprd(0x1000, 0x0990, 8).unwrap().data), past);
    // Armed again.
    activate_sync0(&mut p, 0x1000, later, 1_000_000);
    assert_eq!(p.fprd(0x1000, 0x0984, 1).unwrap().data[0], 0x01);
    clock.advance(2_500_000);
    p.segment.poll();
    let seen = &p.segment.device::<IoDevice>(0).unwrap().seen;
    assert_eq!(seen.sync0_events, 1);
    assert_eq!(seen.last_sync0_ns, Some(later));
    assert_eq!(p.fprd(0x1000, 0x0984, 1).unwrap().data[0], 0x00);
}

/// With the start-time plausibility check on (0x0981 bit 5) a past start time gives a pulse
/// at once (datasheet section II, 0x0981).
#[test]
fn sync0_start_time_in_the_past_with_the_plausibility_check_pulses_at_once() {
    let (mut p, clock) = io_segment(1);
    let now = u64le(&p.fprd(0x1000, 0x0910, 8).unwrap().data);
    activate_sync0(&mut p, 0x1000, now - 2_500_000, 1_000_000);
    p.fpwr(0x1000, 0x0981, &[0]).unwrap();
    p.fpwr(0x1000, 0x0981, &[0x23]).unwrap();
    clock.advance(10_000);
    p.segment.poll();
    let seen = &p.segment.device::<IoDevice>(0).unwrap().seen;
    assert_eq!(seen.sync0_events, 1);
    assert_eq!(p.fprd(0x1000, 0x0984, 1).unwrap().data[0], 0x04);
}

#[test]
fn late_outputs_are_reported_at_the_next_pulse() {
    let (mut p, clock) = io_segment(1);
    configure_io(&mut p, 0x1000, 0, 0x10);
    to_state(&mut p, 0x1000, 0x0002);
    let now = u64le(&p.fprd(0x1000, 0x0910, 8).unwrap().data);
    activate_sync0(&mut p, 0x1000, now + 1_000_000, 1_000_000);
    to_state(&mut p, 0x1000, 0x0004);
    to_state(&mut p, 0x1000, 0x0008);
    // Cycle k's frame arrives after SYNC0 k (late), so pulse k sees none and pulse k+1 two.
    clock.advance(1_500_000); // 0.5 ms after pulse 0
    p.logical(Command::Lrw, 0, &[1; 0x14]).unwrap();
    clock.advance(700_000); // 0.2 ms after pulse 1: the frame for cycle 1 is late
    p.logical(Command::Lrw, 0, &[2; 0x14]).unwrap();
    clock.advance(500_000);
    p.logical(Command::Lrw, 0, &[3; 0x14]).unwrap(); // 0.7 ms after pulse 1
    clock.advance(600_000); // past pulse 2
    p.segment.poll();
    let seen = &p.segment.device::<IoDevice>(0).unwrap().seen;
    // Pulse 0: nothing yet; pulse 1: one buffer; pulse 2: two buffers (one late).
    assert_eq!(seen.sync0_events, 3);
    assert_eq!(seen.missed_in_op, 1);
    assert_eq!(seen.late_outputs, 1);
    assert_eq!(seen.last_outputs, vec![3, 3]);
}

#[test]
fn without_dc_every_process_data_frame_is_a_cycle() {
    let (mut p, _) = io_segment(1);
    configure_io(&mut p, 0x1000, 0, 0x10);
    to_state(&mut p, 0x1000, 0x0002);
    to_state(&mut p, 0x1000, 0x0004);
    // SAFE-OP: inputs only; the device runs after each frame that read them.
    p.logical(Command::Lrd, 0x10, &[0; 4]).unwrap();
    p.logical(Command::Lrd, 0x10, &[0; 4]).unwrap();
    let cycles = p.segment.device::<IoDevice>(0).unwrap().seen.cycles;
    assert_eq!(cycles, 2);
    // A frame that does not touch process data is no cycle.
    p.brd(0x0130, 2).unwrap();
    assert_eq!(p.segment.device::<IoDevice>(0).unwrap().seen.cycles, 2);
    // The counter in the inputs advances with each cycle.
    let r = p.logical(Command::Lrd, 0x10, &[0; 4]).unwrap();
    assert_eq!(u16le(&r.data), 2);
}

#[test]
fn segment_link_is_a_synchronous_frame_link() {
    use ecdrive_core::ec::frame::{EthercatFrame, EthernetFrame, FrameBuilder, physical_address};
    use ecdrive_core::link::FrameLink;
    use ecdrive_sim::transport::SegmentLink;
    let (p, _) = io_segment(2);
    let mut link = SegmentLink::new(p.segment);
    let mut buf = [0u8; 64];
    let mut b = FrameBuilder::new(&mut buf, ecdrive_sim::probe::PROBE_MAC).unwrap();
    b.push(Command::Brd, 9, physical_address(0, 0x0000), &[0])
        .unwrap();
    let n = b.finish();
    // Two frames in flight, replies in order.
    link.send(&buf[..n]).unwrap();
    buf[14 + 2 + 1] = 10; // second frame: index 10
    link.send(&buf[..n]).unwrap();
    let mut rx = [0u8; 1600];
    for idx in [9u8, 10] {
        let len = link.recv(&mut rx, None).unwrap().expect("reply");
        assert_eq!(len, n);
        let eth = EthernetFrame::new_checked(&rx[..len]).unwrap();
        let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
        let d = ec.datagrams().next().unwrap().unwrap();
        assert_eq!((d.index(), d.wkc(), d.adp()), (idx, 2, 2));
    }
    // Nothing in flight: an immediate timeout.
    assert_eq!(link.recv(&mut rx, None).unwrap(), None);
    // A malformed frame is dropped like on a wire.
    link.send(&[0u8; 20]).unwrap();
    assert_eq!(link.recv(&mut rx, None).unwrap(), None);
}

/// A device with a bootstrap mailbox (64-byte SMs) next to its standard one; its firmware
/// echoes mailboxes in both.
struct BootDevice(EchoMailbox);

impl Device for BootDevice {
    fn description(&self) -> ecdrive_sim::DeviceDescription {
        let mut d = EchoMailbox::new().description();
        if let Some(m) = d.mailbox.as_mut() {
            m.bootstrap = Some([0x1000, 64, 0x1080, 64]);
        }
        d
    }
    fn process_data_sizes(&self) -> ecdrive_sim::ProcessDataSizes {
        Default::default()
    }
    fn mailbox_request(&mut self, state: AlState, req: &[u8], reply: &mut [u8]) -> Option<usize> {
        self.0.mailbox_request(state, req, reply)
    }
}

#[test]
fn bootstrap_state_checks_its_own_mailbox() {
    let dev = BootDevice(EchoMailbox::new());
    let (mut p, _) = probe_with(vec![Box::new(dev)], EscConfig::default());
    p.assign_addresses(0x1000).unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0003), (0x0011, 0x0015));
    // The standard mailbox configuration is not the bootstrap one.
    p.fpwr(
        0x1000,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0013), (0x0011, 0x0015));
    p.bwr(0x0800, &[0; 16]).unwrap();
    p.fpwr(
        0x1000,
        0x0800,
        &[
            0x00, 0x10, 64, 0, 0x26, 0, 1, 0, 0x80, 0x10, 64, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(to_state(&mut p, 0x1000, 0x0013), (0x0003, 0));
    // The bootstrap mailbox works with its own (64-byte) buffers.
    let mut m = vec![0u8; 64];
    m[0] = 4;
    m[5] = 0x1F;
    m[6..10].copy_from_slice(b"boot");
    assert_eq!(p.fpwr(0x1000, 0x1000, &m).unwrap().wkc, 1);
    let r = p.fprd(0x1000, 0x1080, 64).unwrap();
    assert_eq!((r.wkc, &r.data[6..10]), (1, &b"boot"[..]));
    // From BOOT only INIT is allowed.
    assert_eq!(to_state(&mut p, 0x1000, 0x0002), (0x0013, 0x0011));
    assert_eq!(to_state(&mut p, 0x1000, 0x0001), (0x0001, 0));
}

/// The drive ESI files become SII images that a master reads back as the ESI says.
#[test]
fn sii_from_the_drive_esi_files() {
    use ecdrive_core::esi::EsiFile;
    use ecdrive_sim::sii::{self, category};
    for path in [
        "esi/Mitsubishi_MR-J4-TM.xml",
        "esi/Servotronix_BDHDE.xml",
        "tests/data/esi/Acme_Terminals.xml",
    ] {
        let file = EsiFile::from_path(ecdrive_testkit::repo().join(path)).unwrap();
        for dev in &file.devices {
            let desc = sii::from_esi(file.vendor.id, dev, 77).unwrap();
            let img = sii::build(&desc).unwrap_or_else(|e| panic!("{path}: {e}"));
            assert!(img.checksum_ok());
            let id = img.identity();
            assert_eq!(id.vendor_id, file.vendor.id);
            assert_eq!(id.product_code, dev.type_.product_code);
            assert_eq!(id.serial, 77);
            let g = img.category(category::GENERAL).unwrap();
            assert_eq!(img.string(g[3]), Some(dev.name.as_str()));
            assert_eq!(img.string(g[2]), Some(dev.type_.name_text.as_str()));
            let sm = img.category(category::SYNC_MANAGER).unwrap_or(&[]);
            assert_eq!(sm.len(), 8 * dev.sync_managers.len());
            let pdo_bits: u32 = dev.tx_pdos.iter().map(|p| p.bits()).sum();
            if let Some(tx) = img.category(category::TXPDO) {
                // Sum of entry bit lengths as the SII holds them.
                let mut at = 0usize;
                let mut bits = 0u32;
                while at + 8 <= tx.len() {
                    let n = usize::from(tx[at + 2]);
                    for k in 0..n {
                        bits += u32::from(tx[at + 8 + 8 * k + 5]);
                    }
                    at += 8 + 8 * n;
                }
                assert_eq!(bits, pdo_bits, "{}", dev.name);
            } else {
                assert_eq!(pdo_bits, 0);
            }
            // An ESC built on it accepts the mailbox configuration the SII advertises.
            if let Some(m) = &desc.mailbox {
                assert_eq!(img.word(0x18), m.rx_offset);
                assert_eq!(img.word(0x1B), m.tx_size);
                assert_ne!(img.word(0x1C) & 0x0004, 0, "CoE");
            }
        }
    }
}
