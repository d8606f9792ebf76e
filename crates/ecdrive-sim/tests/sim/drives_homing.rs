//! Homing and the touch probe of both emulated EtherCAT drives, through process data and SDO
//! as a master sees them. The machine (switch and input placements) is written here, and the
//! positions each method must end at come from it and from the CiA 402 method definitions the
//! manuals refer to (MR-J4-TM §5.4.9 (4)/(5): 19 "dog front end", 4 "first Z-phase after the
//! dog front end", 34 "Z-phase detected first", 35/37 "the current position"; BDHDE §5.8:
//! "refer to the CiA-402 standard"), never from the emulator's own homing code.
//!
//! Failure reporting as the manuals give it: MR-J4-TM [AL. 90 Home position return incomplete
//! warning] (statusword bit 13 and the warning bit 7, §5.4.9 (4), §5.3.1); BDHDE fault 0x6100
//! "Homing Error" (Table 10-4) in 0x603F, state Fault (§10.2).

use crate::support::wire;

use ecdrive_core::cia402::State;
use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive_core::od::ObjectAddress;
use ecdrive_sim::drives::{EmulatedDrive, spec_for};
use ecdrive_sim::machine::World;
use wire::{Wire, cyclic};

const MR: &DriveProfile = &mr_j4_tm::PROFILE;
const BD: &DriveProfile = &bdhde::PROFILE;

/// The machine of these tests: limits at ±8 rev, the home switch (dog) from 2.5 rev up, probe
/// input 1 active from 1.3 to 1.7 rev, probe input 2 from −1.6 to −1.2 rev.
const MACHINE: World = World {
    negative_limit_rev: -8.0,
    positive_limit_rev: 8.0,
    home_switch_rev: Some(2.5),
    probe1_rev: Some((1.3, 1.7)),
    probe2_rev: Some((-1.6, -1.2)),
};

/// The drive of `p` on `world`, in OP (the MR-J4-TM with [Pr. PA01] = ___2 for pp).
fn on(p: &DriveProfile, world: World) -> Wire {
    let mut d = EmulatedDrive::new(spec_for(p.key).unwrap(), 1)
        .unwrap()
        .with_world(world);
    if p.key == "mr-j4-tm" {
        d = d.with_stored(ObjectAddress::new(0x2001, 0), 2);
    }
    let mut w = Wire::op_drive(d, p, 1_000_000);
    // Ramps: MR-J4-TM time constants in ms to the rated 50 rev/s (§7.3.12: 6083h/6084h,
    // §7.3.13: 609Ah); BDHDE in position units/s² (§6.4).
    let cpr = p.units.position_per_rev;
    if p.key == "mr-j4-tm" {
        for i in [0x6083, 0x6084, 0x609A] {
            w.write_u32(0, i, 0, 100).unwrap();
        }
    } else {
        for i in [0x6083, 0x6084, 0x609A] {
            w.write_u32(0, i, 0, (500.0 * cpr) as u32).unwrap();
        }
    }
    w
}

/// Velocity units per rev/s (MR-J4-TM 0.01 r/min: 6000; BDHDE position units/s).
fn vpr(p: &DriveProfile) -> f64 {
    p.units.position_per_rev / p.units.velocity_position_per_s()
}

fn enable(w: &mut Wire, mode: i8) {
    let pos = cyclic::position(w.inputs(0));
    let o = w.outputs_mut(0);
    cyclic::set_mode(o, mode);
    cyclic::set_target(o, pos);
    for cw in [0x0006, 0x0007, 0x000F] {
        w.command(0, cw);
    }
    assert_eq!(w.state(0), State::OperationEnabled);
    assert_eq!(cyclic::mode(w.inputs(0)), mode);
}

/// A pp move to `rev` (absolute, reported units) at 5 rev/s; waits for target reached.
fn pp_to(w: &mut Wire, p: &DriveProfile, rev: f64) {
    let cpr = p.units.position_per_rev;
    w.write_u32(0, 0x6081, 0, (5.0 * vpr(p)) as u32).unwrap();
    enable(w, 1);
    cyclic::set_target(w.outputs_mut(0), (rev * cpr).round() as i32);
    w.command(0, 0x001F);
    w.command(0, 0x000F);
    for _ in 0..5000 {
        if cyclic::sw(w.inputs(0)) & 0x0400 != 0 {
            break;
        }
        w.cycle();
    }
    let err = (f64::from(cyclic::position(w.inputs(0))) - rev * cpr).abs();
    assert!(
        err <= 1.0,
        "{}: pp to {rev} rev ended {err} counts away",
        p.name
    );
}

/// Home with `method` at 4 rev/s (switch search) and 0.5 rev/s (creep): the statusword at the
/// end (bit 12 or 13 set, or after 20 s of cycles).
fn home(w: &mut Wire, p: &DriveProfile, method: i8) -> u16 {
    let v = vpr(p);
    w.write_u32(0, 0x6099, 1, (4.0 * v) as u32).unwrap();
    w.write_u32(0, 0x6099, 2, (0.5 * v) as u32).unwrap();
    w.download(0, 0x6098, 0, &[method as u8]).unwrap();
    enable(w, 6);
    let mut sw = w.command(0, 0x001F);
    for _ in 0..20_000 {
        if sw & 0x3000 != 0 && w.drive(0).speed_rev_s() == 0.0 {
            break;
        }
        w.cycle();
        sw = cyclic::sw(w.inputs(0));
    }
    sw
}

/// Where the motor is, in revolutions of the machine (the emulated motor's own position).
fn machine_rev(w: &mut Wire) -> f64 {
    w.drive(0).position_rev()
}

/// Three methods per drive, each from 0.4 rev: on the home switch (19: the dog's front end at
/// 2.5 rev; MR-J4-TM also 4: the first index pulse above it, 3.0 rev), on the index pulse (34:
/// the next whole revolution, 1.0 rev), on the current position (MR-J4-TM 37, BDHDE 35: 0.4
/// rev). Each ends homing attained with target reached, at that machine position within one
/// count, and the position there reads as 0x607C (0).
#[test]
fn homing_ends_where_each_method_defines_the_home() {
    for (p, methods) in [
        (MR, &[(19i8, 2.5), (4, 3.0), (34, 1.0), (37, 0.4)][..]),
        (BD, &[(19i8, 2.5), (34, 1.0), (35, 0.4)][..]),
    ] {
        let cpr = p.units.position_per_rev;
        for &(method, want_rev) in methods {
            let mut w = on(p, MACHINE);
            pp_to(&mut w, p, 0.4);
            let sw = home(&mut w, p, method);
            assert_eq!(
                sw & 0x3400,
                0x1400,
                "{} method {method}: sw 0x{sw:04X}",
                p.name
            );
            let at = machine_rev(&mut w);
            assert!(
                ((at - want_rev) * cpr).abs() <= 1.0,
                "{} method {method}: ended at {at} rev, the method's home is {want_rev} rev",
                p.name
            );
            let home_offset = w.read_u32(0, 0x607C, 0) as i32;
            assert_eq!(cyclic::position(w.inputs(0)), home_offset, "{}", p.name);
            assert_eq!(w.state(0), State::OperationEnabled);
        }
    }
}

/// A machine without a home switch: method 19 searches up to the positive limit switch and
/// fails there, as each drive reports it.
#[test]
fn a_home_switch_never_found_ends_in_the_drives_homing_error() {
    let no_switch = World {
        home_switch_rev: None,
        ..MACHINE
    };
    // MR-J4-TM: homing error (bit 13) with the warning bit 7, AL.90; still enabled.
    let mut w = on(MR, no_switch);
    let sw = home(&mut w, MR, 19);
    assert_ne!(sw & 0x2000, 0, "homing error: 0x{sw:04X}");
    assert_ne!(sw & 0x0080, 0, "warning: 0x{sw:04X}");
    assert_eq!(w.state(0), State::OperationEnabled);
    let (id, text) = w.drive(0).warning().expect("a warning");
    assert_eq!(
        (id, text),
        ("AL.90", "Home position return incomplete warning")
    );
    assert!(
        (machine_rev(&mut w) - 8.0).abs() < 1e-6,
        "stopped at the limit"
    );
    // BDHDE: fault 0x6100 "Homing Error".
    let mut w = on(BD, no_switch);
    home(&mut w, BD, 19);
    for _ in 0..3 {
        w.cycle();
    }
    assert_eq!(w.state(0), State::Fault);
    let code = w.upload(0, 0x603F, 0).unwrap();
    assert_eq!(code, 0x6100u16.to_le_bytes());
}

/// Probe 1 on both edges, single trigger (0x60B8 = 0x0031): a move through the input latches
/// 0x60BA at its rising and 0x60BB at its falling edge, each within one count of where the
/// machine has them (1.3 and 1.7 rev), and 0x60B9 says both are stored (bits 0–2). Clearing
/// the sample bits clears them; probe 2 latches on its own input.
#[test]
fn the_touch_probe_latches_the_edge_positions() {
    for p in [MR, BD] {
        let cpr = p.units.position_per_rev;
        let mut w = on(p, MACHINE);
        w.write_u16(0, 0x60B8, 0, 0x0031).unwrap();
        w.cycle();
        assert_eq!(
            w.read_u32(0, 0x60B9, 0) & 0xFFFF,
            0x0001,
            "{}: enabled",
            p.name
        );
        pp_to(&mut w, p, 2.0);
        assert_eq!(
            w.read_u32(0, 0x60B9, 0) & 0xFFFF,
            0x0007,
            "{}: stored",
            p.name
        );
        for (i, want) in [(0x60BA, 1.3), (0x60BB, 1.7)] {
            let got = w.read_u32(0, i, 0) as i32;
            assert!(
                (f64::from(got) - want * cpr).abs() <= 1.0,
                "{}: 0x{i:04X} = {got}, the edge is at {} counts",
                p.name,
                want * cpr
            );
        }
        // Single trigger: moving back through the input latches nothing new.
        let first = w.read_u32(0, 0x60BA, 0);
        pp_to(&mut w, p, 1.0);
        assert_eq!(
            w.read_u32(0, 0x60BA, 0),
            first,
            "{}: single trigger",
            p.name
        );
        // The sample bits cleared: the stored bits follow.
        w.write_u16(0, 0x60B8, 0, 0x0001).unwrap();
        w.cycle();
        assert_eq!(
            w.read_u32(0, 0x60B9, 0) & 0xFFFF,
            0x0001,
            "{}: cleared",
            p.name
        );
        // Probe 2, rising edge (0x60B8 bits 8, 12): its input from −1.6 rev, met at −1.2 when
        // moving down.
        w.write_u16(0, 0x60B8, 0, 0x1100).unwrap();
        pp_to(&mut w, p, -2.0);
        assert_eq!(
            w.read_u32(0, 0x60B9, 0) & 0xFF00,
            0x0300,
            "{}: probe 2",
            p.name
        );
        let got = w.read_u32(0, 0x60BC, 0) as i32;
        assert!(
            (f64::from(got) + 1.2 * cpr).abs() <= 1.0,
            "{}: 0x60BC = {got}",
            p.name
        );
    }
}

/// The MR-J4-TM's probe can take the encoder's zero point instead of its input (0x60B8 bit 2,
/// §5.5); the BDHDE's cannot ("not support"): the same setting latches nothing there.
#[test]
fn the_probe_on_the_index_pulse_where_the_drive_has_it() {
    for (p, latches) in [(MR, true), (BD, false)] {
        let cpr = p.units.position_per_rev;
        let mut w = on(p, MACHINE);
        w.write_u16(0, 0x60B8, 0, 0x0015).unwrap();
        pp_to(&mut w, p, 1.5);
        let st = w.read_u32(0, 0x60B9, 0) & 0xFFFF;
        if latches {
            assert_eq!(st, 0x0003, "{}", p.name);
            let got = w.read_u32(0, 0x60BA, 0) as i32;
            assert!((f64::from(got) - cpr).abs() <= 1.0, "{}: {got}", p.name);
        } else {
            assert_eq!(st, 0x0001, "{}: nothing latched", p.name);
        }
    }
}

/// Homing interrupted (bit 4 dropped mid-way): the drive decelerates on the homing
/// acceleration (MR-J4-TM §5.7: "hm: The servo motor decelerates to a stop with Homing
/// acceleration (609Ah)"), not at once, and then reports "interrupted or not started" (bit 10
/// only, §5.4.9 (3)).
#[test]
fn an_interrupted_homing_decelerates_then_reports_interrupted() {
    for p in [MR, BD] {
        let mut w = on(p, MACHINE);
        let v = vpr(p);
        w.write_u32(0, 0x6099, 1, (4.0 * v) as u32).unwrap();
        w.write_u32(0, 0x6099, 2, (0.5 * v) as u32).unwrap();
        w.download(0, 0x6098, 0, &[19]).unwrap();
        enable(&mut w, 6);
        w.command(0, 0x001F);
        for _ in 0..200 {
            w.cycle();
        }
        let running = w.drive(0).speed_rev_s();
        assert!(running > 3.0, "{}: searching at {running} rev/s", p.name);
        w.command(0, 0x000F);
        let braking = w.drive(0).speed_rev_s();
        assert!(
            braking > 0.5 && braking < running,
            "{}: {braking} rev/s two cycles after bit 4 dropped (from {running})",
            p.name
        );
        for _ in 0..500 {
            w.cycle();
        }
        let stopped = w.drive(0).speed_rev_s();
        assert!(stopped.abs() < 1e-6, "{}: {stopped} rev/s", p.name);
        let sw = cyclic::sw(w.inputs(0));
        assert_eq!(sw & 0x3400, 0x0400, "{}: interrupted, 0x{sw:04X}", p.name);
    }
}
