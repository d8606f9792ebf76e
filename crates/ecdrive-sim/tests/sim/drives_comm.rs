//! Loss of cyclic data as each emulated drive detects it (MR-J4-TM [AL. 86.1] with its error
//! counter, the incremental counter 0x2D23/0x2D24 and [AL. 86.2]; BDHDE 0x818D), and the
//! synchronisation rules at SAFE-OP → OP (0x1C32 / 0x60C2 against SYNC0, free run).

use crate::support::wire;

use ecdrive_core::cia402::State;
use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive_core::pdo::{Mapping, Pdo, PdoEntry};
use wire::{Wire, cyclic};

const MR: &DriveProfile = &mr_j4_tm::PROFILE;
const BD: &DriveProfile = &bdhde::PROFILE;

fn enabled(p: &DriveProfile, cycle_ns: u32) -> Wire {
    let mut w = Wire::op_cyclic(&[p], cycle_ns);
    let pos = cyclic::position(w.inputs(0));
    let o = w.outputs_mut(0);
    cyclic::set_mode(o, 8);
    cyclic::set_target(o, pos);
    for cw in [0x0006, 0x0007, 0x000F] {
        w.command(0, cw);
    }
    assert_eq!(w.state(0), State::OperationEnabled);
    w
}

/// MR-J4-TM §7.3.1(10): +3 per cycle without data, [AL. 86.1] at the automatic threshold of
/// 7 ms; −1 per good cycle (\[REC\]), so sparse losses never add up.
#[test]
fn mr_j4_network_error_1_counts_missed_cycles() {
    for (cycle_ns, misses) in [(1_000_000u32, 7u32), (250_000, 28), (2_000_000, 4)] {
        let mut w = enabled(MR, cycle_ns);
        // One frame too few to raise it: the counter says 3 per miss.
        for _ in 0..misses - 1 {
            w.skip_cycle();
        }
        assert_eq!(w.drive(0).sync_error_counter(), 3 * (misses - 1));
        assert!(w.drive(0).alarm().is_none(), "{cycle_ns} ns");
        assert_eq!(w.drive(0).state(), State::OperationEnabled);
        // Good cycles take 1 each.
        for _ in 0..5 {
            w.cycle();
        }
        assert_eq!(w.drive(0).sync_error_counter(), 3 * (misses - 1) - 5);
        // One in four lost: +3 −3 per four cycles, never an alarm.
        for _ in 0..50 {
            w.skip_cycle();
            for _ in 0..3 {
                w.cycle();
            }
        }
        assert!(w.drive(0).alarm().is_none());
        // `misses` in a row from a clean counter: the alarm after 7 ms.
        for _ in 0..100 {
            w.cycle();
        }
        assert_eq!(w.drive(0).sync_error_counter(), 0);
        for k in 1..=misses {
            w.skip_cycle();
            assert_eq!(
                w.drive(0).alarm().is_some(),
                k == misses,
                "{cycle_ns} ns, miss {k}"
            );
        }
        w.cycle();
        w.cycle();
        assert_eq!(w.state(0), State::Fault);
        assert_eq!(cyclic::error_code(w.inputs(0)), 0xFF86);
        assert_eq!(w.read_u32(0, 0x2A41, 0), 0x0086_0001);
        w.drain(0);
        assert!(w.emergencies.iter().any(|(_, e)| e.error_code == 0xFF86));
        // AL.86 can be reset.
        w.command(0, 0x0000);
        assert_eq!(w.command(0, 0x0080) & 0x4F, 0x40);
    }
}

/// The fault-injection path: `drop_outputs` makes outputs "not arrive" although frames do.
#[test]
fn dropped_outputs_count_like_lost_frames() {
    let mut w = enabled(MR, 1_000_000);
    w.drive(0).drop_outputs(6);
    for _ in 0..6 {
        w.cycle();
    }
    assert_eq!(w.drive(0).sync_error_counter(), 18);
    assert_eq!(w.drive(0).stats().missed_outputs, 6);
    assert!(w.drive(0).alarm().is_none());
    w.drive(0).drop_outputs(1);
    w.cycle();
    assert_eq!(w.drive(0).alarm().map(|a| a.id), Some("AL.86.1"));
}

/// The BDHDE's packet-loss fault 0x818D after 7 ms of consecutive cycles without data
/// (\[REC\]), at 500 µs: 14 misses.
#[test]
fn bdhde_packet_loss() {
    let mut w = enabled(BD, 500_000);
    for _ in 0..13 {
        w.skip_cycle();
    }
    assert!(w.drive(0).alarm().is_none());
    assert_eq!(w.drive(0).sync_error_counter(), 39);
    // 39 good cycles bring the counter back to 0; then the 14th miss in a row raises it.
    for _ in 0..39 {
        w.cycle();
    }
    assert_eq!(w.drive(0).sync_error_counter(), 0);
    for _ in 0..13 {
        w.skip_cycle();
    }
    assert!(w.drive(0).alarm().is_none());
    w.skip_cycle();
    assert_eq!(w.drive(0).alarm().map(|a| a.id), Some("Fb8"));
    w.cycle();
    w.cycle();
    assert_eq!(cyclic::error_code(w.inputs(0)), 0x818D);
    assert_eq!(w.state(0), State::Fault);
}

/// A long gap (a stalled master: 40 ms without data) raises the alarm once; the counter stands
/// still while the alarm is present and the reset starts it at 0 (\[REC\] for both drives), so
/// the next single lost frame after the reset does not raise the alarm again.
#[test]
fn after_a_long_gap_a_reset_starts_the_loss_counter_afresh() {
    for p in [MR, BD] {
        let mut w = enabled(p, 1_000_000);
        for _ in 0..40 {
            w.skip_cycle();
        }
        assert!(w.drive(0).alarm().is_some(), "{}", p.name);
        w.cycle();
        w.cycle();
        assert_eq!(w.state(0), State::Fault, "{}", p.name);
        w.command(0, 0x0000);
        assert_eq!(w.command(0, 0x0080) & 0x4F, 0x40, "{}: reset", p.name);
        assert_eq!(w.drive(0).sync_error_counter(), 0, "{}", p.name);
        w.skip_cycle();
        w.cycle();
        assert!(w.drive(0).alarm().is_none(), "{}: alarm again", p.name);
        assert_eq!(w.state(0), State::SwitchOnDisabled, "{}", p.name);
    }
}

/// The recommended mapping plus the incremental counters: 0x2D23 (DL) at the end of the
/// outputs, 0x2D24 (UL) at the end of the inputs.
fn with_counter(p: &DriveProfile) -> Mapping {
    let mut rx: Vec<PdoEntry> = p.cyclic_mapping.rx[0].entries.to_vec();
    rx.push(PdoEntry::new(0x2D23, 0, 8));
    let mut tx: Vec<PdoEntry> = p.cyclic_mapping.tx[0].entries.to_vec();
    tx.push(PdoEntry::new(0x2D24, 0, 8));
    Mapping::owned(vec![Pdo::owned(0x1600, rx)], vec![Pdo::owned(0x1A00, tx)])
}

/// MR-J4-TM §6.2: with 0x2D23 mapped the master adds 1 per cycle; the drive returns 0x2D24 =
/// 0x2D23 + 1; a lost frame is allowed for (the master counted on); a wrong update raises
/// [AL. 86.2].
#[test]
fn mr_j4_incremental_counter() {
    let mut w = Wire::drives(&[MR]);
    w.preop(0);
    let m = with_counter(MR);
    wire::remap(&mut w, 0, &m);
    w.write_u16(0, 0x1C32, 1, 2).unwrap();
    w.write_u32(0, 0x1C32, 2, 1_000_000).unwrap();
    let (out_len, in_len) = (
        m.bytes(ecdrive_core::pdo::Direction::Rx),
        m.bytes(ecdrive_core::pdo::Direction::Tx),
    );
    let (dl_at, ul_at) = (out_len - 1, in_len - 1);
    w.configure_pd(&[(out_len, in_len)]);
    assert_eq!(w.request(0, 4), (4, 0));
    w.activate_dc(1_000_000);
    assert_eq!(w.request(0, 8), (8, 0));
    let mut dl: u8 = 250;
    for k in 0..20 {
        dl = dl.wrapping_add(1);
        w.outputs_mut(0)[dl_at] = dl;
        if k == 10 {
            // A lost frame: the master's counter moves on anyway.
            w.skip_cycle();
            continue;
        }
        w.cycle();
        if k > 1 && k != 11 {
            assert_eq!(
                w.inputs(0)[ul_at],
                dl.wrapping_add(0),
                "UL = DL + 1 of the previous frame"
            );
        }
    }
    assert!(w.drive(0).alarm().is_none(), "{:?}", w.drive(0).alarm());
    // The master forgets to count.
    w.cycle();
    w.cycle();
    assert_eq!(w.drive(0).alarm().map(|a| a.id), Some("AL.86.2"));
    assert_eq!(w.read_u32(0, 0x2A41, 0), 0x0086_0002);
}

/// SAFE-OP → OP checks the SYNC0 cycle against the drive's cycle object: the MR-J4-TM's
/// 0x1C32:02 and the BDHDE's 0x60C2:01 × 250 µs (refused with 0x0035, \[REC\]); DC mode without
/// SYNC0 is 0x0030; the BDHDE has no free run.
#[test]
fn sync_cycle_rules() {
    // MR-J4-TM: 0x1C32:02 = 1 ms, SYNC0 at 500 µs.
    let mut w = Wire::drives(&[MR]);
    w.preop(0);
    w.write_u16(0, 0x1C32, 1, 2).unwrap();
    w.write_u32(0, 0x1C32, 2, 1_000_000).unwrap();
    let m = &MR.default_mapping;
    w.configure_pd(&[(
        m.bytes(ecdrive_core::pdo::Direction::Rx),
        m.bytes(ecdrive_core::pdo::Direction::Tx),
    )]);
    assert_eq!(w.request(0, 4), (4, 0));
    // DC mode asked for, SYNC0 not active.
    assert_eq!(w.request(0, 8), (0x14, 0x0030));
    w.activate_dc(500_000);
    assert_eq!(w.request_ack(0, 8), (0x14, 0x0035));
    w.activate_dc(1_000_000);
    assert_eq!(w.request_ack(0, 8), (8, 0));

    // BDHDE: 0x60C2:01 = 4 (1 ms) by default; 500 µs needs 2.
    let mut w = Wire::drives(&[BD]);
    w.preop(0);
    assert_eq!(w.upload(0, 0x60C2, 1).unwrap(), vec![4]);
    let m = &BD.default_mapping;
    w.configure_pd(&[(
        m.bytes(ecdrive_core::pdo::Direction::Rx),
        m.bytes(ecdrive_core::pdo::Direction::Tx),
    )]);
    assert_eq!(w.request(0, 4), (4, 0));
    assert_eq!(w.request(0, 8), (0x14, 0x0030), "no free run");
    w.activate_dc(500_000);
    assert_eq!(w.request_ack(0, 8), (0x14, 0x0035));
    assert_eq!(w.request_ack(0, 2), (2, 0));
    w.write_u8(0, 0x60C2, 1, 2).unwrap();
    assert_eq!(w.request(0, 4), (4, 0));
    assert_eq!(w.request(0, 8), (8, 0), "500 µs with 0x60C2:01 = 2");
}

/// MR-J4-TM free run (0x1C32:01 = 0, software B4+): every frame is a cycle of the 0x1C32:02
/// time, and the drive runs csp without SYNC0.
#[test]
fn mr_j4_free_run() {
    let mut w = Wire::drives(&[MR]);
    w.preop(0);
    wire::remap(&mut w, 0, &MR.cyclic_mapping);
    for s in MR.sync_writes(1_000_000, false).unwrap() {
        let e = MR.od().entry(s.address).unwrap();
        let b = ecdrive_core::od::Value::Int(s.value)
            .encode(e.data_type)
            .unwrap();
        w.download(0, s.address.index, s.address.sub, &b).unwrap();
    }
    assert_eq!(w.read_u32(0, 0x1C33, 1), 0);
    w.configure_pd(&[cyclic::sizes(MR)]);
    assert_eq!(w.request(0, 4), (4, 0));
    assert_eq!(w.request(0, 8), (8, 0));
    w.cycle();
    let pos = cyclic::position(w.inputs(0));
    let o = w.outputs_mut(0);
    cyclic::set_mode(o, 8);
    cyclic::set_target(o, pos);
    for cw in [0x0006, 0x0007, 0x000F] {
        w.command(0, cw);
    }
    assert_eq!(w.state(0), State::OperationEnabled);
    // 100 frames of 1 rev/s = 4194 counts per frame: 0.1 rev.
    let mut t = pos;
    for _ in 0..100 {
        t += 4194;
        cyclic::set_target(w.outputs_mut(0), t);
        w.cycle();
    }
    w.cycle();
    w.cycle();
    let moved = cyclic::position(w.inputs(0)) - pos;
    assert!((moved - 419_400).abs() < 200, "{moved}");
    // No SYNC0: no loss detection from missing frames.
    for _ in 0..20 {
        w.skip_cycle();
    }
    assert!(w.drive(0).alarm().is_none());
}
