//! The emulated CANopen drives on the machine model the EtherCAT drives use
//! (`sim::machine::World`: limit switches, home switch, index pulses, probe inputs), checked as
//! `crates/ecdrive-sim/tests/sim/drives_homing.rs` checks the EtherCAT drives: the machine is written here, and where
//! a homing method must end comes from it and from the method's definition (CiA 402, which the
//! three manuals follow: BLV-R §7.5.5 — 24 "home switch, start positive", as 8 without the
//! index, homes on the switch's rising-edge side; 35/37 the current position; the ASDA-A2 and
//! the Lexium MDrive list the same methods), never from the emulator's homing code. Each drive
//! runs a program from a run file (pp to 0.4 rev, then the home step) through the master.

use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::sim::canopen::{EmulatedNode, SimBus};
use ecdrive::sim::machine::World;
use ecdrive_cli::app::config::{self, Config};
use ecdrive_cli::app::ethercat::tools::run::Outcome;

/// The machine of these tests: limits at ±8 rev, the home switch from 2.5 rev up, probe input 1
/// active from 1.3 to 1.7 rev, probe input 2 from −1.6 to −1.2 rev.
const MACHINE: World = World {
    negative_limit_rev: -8.0,
    positive_limit_rev: 8.0,
    home_switch_rev: Some(2.5),
    probe1_rev: Some((1.3, 1.7)),
    probe2_rev: Some((-1.6, -1.2)),
};

const DRIVES: [(u8, &CanDriveProfile, &str); 3] = [
    (3, &blv_r::PROFILE, "blv-r"),
    (0x7F, &asda_a2::PROFILE, "asda-a2"),
    (0x41, &lexium_mdrive::PROFILE, "lexium-mdrive"),
];

/// Run `steps` (in revolutions) on drive `(node, p)` standing in `world`; the report's outcome,
/// reason and errors, and where the motor ended on the machine.
fn run(
    (node, p, key): (u8, &'static CanDriveProfile, &str),
    world: World,
    steps: &str,
) -> (Outcome, String, Vec<String>, f64) {
    let text = format!(
        "interface = \"can-sim\"\n[[drive]]\nnode = {node}\nprofile = \"{key}\"\nmode = \"pp\"\n\
         units = {{ name = \"rev\", counts_per_unit = {} }}\nprogram = [\n\
         {{ step = \"pp\", to = [0.4], velocity = 5, acceleration = 50 }},\n{steps}\n]\n",
        p.units.position_per_rev
    );
    let cfg = match config::parse_any(&text, "machine.toml").unwrap_or_else(|e| panic!("{e}")) {
        Config::CanOpen(c) => c,
        Config::EtherCat(_) => panic!("not a CANopen run"),
    };
    let mut bus = SimBus::new();
    bus.add_node(
        EmulatedNode::with_world(
            ecdrive_cli::app::canopen::tools::emulation_of(p)
                .expect("the software slave emulates the drive"),
            node,
            world,
        )
        .expect("node"),
    );
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = ecdrive_cli::app::canopen::run::run_on(&mut bus, &cfg, None, None, &stop).expect("run");
    let at = bus.node(node).expect("node").machine_rev();
    let errors = r
        .drives
        .first()
        .map(|d| d.errors.clone())
        .unwrap_or_default();
    (r.outcome, r.reason, errors, at)
}

/// Method 24 from 0.4 rev ends on the home switch's edge, 2.5 rev; method 35 where the motor
/// stands, 0.4 rev; each within one count, on every drive.
#[test]
fn each_canopen_drive_homes_where_the_method_puts_the_home_on_the_machine() {
    for d in DRIVES {
        let cpr = d.1.units.position_per_rev;
        for (method, want) in [(24i8, 2.5), (35, 0.4)] {
            let step = format!(
                "{{ step = \"home\", method = {method}, speed_switch = 2, speed_zero = 0.2 }},"
            );
            let (outcome, reason, errors, at) = run(d, MACHINE, &step);
            assert_eq!(
                outcome,
                Outcome::Completed,
                "{} {method}: {reason} {errors:?}",
                d.1.name
            );
            assert!(
                ((at - want) * cpr).abs() <= 1.0,
                "{} method {method}: ended at {at} rev, the method's home is {want} rev",
                d.1.name
            );
        }
    }
}

/// A machine without a home switch: method 24 starts positive, reverses at the positive limit
/// switch (BLV-R §7.5.5: method 8 "reverses on the limit switch", 24 "as 8 without index"),
/// searches down to the negative one and fails there; the run ends naming the drive and the
/// failed homing, and the motor stands at that limit switch, not beyond.
#[test]
fn a_home_switch_never_found_fails_the_home_step_at_the_limit() {
    let no_switch = World {
        home_switch_rev: None,
        ..MACHINE
    };
    for d in DRIVES {
        let step = "{ step = \"home\", method = 24, speed_switch = 2, speed_zero = 0.2 },";
        let (outcome, reason, errors, at) = run(d, no_switch, step);
        assert_ne!(outcome, Outcome::Completed, "{}: {reason}", d.1.name);
        let text = format!("{reason} {errors:?}");
        assert!(text.contains("homing"), "{}: {text}", d.1.name);
        assert!(
            (at + 8.0).abs() <= 0.05,
            "{}: stopped at {at} rev, the negative limit switch is at −8 rev",
            d.1.name
        );
    }
}

/// Probe 1 armed on the rising edge, a pp move through its input: the latch is where the
/// machine's input goes on (1.3 rev) on the drive that has a touch probe (the BLV-R), within one
/// count whatever the SYNC period.
#[test]
fn the_probe_latches_where_the_machines_input_goes_on() {
    let d = DRIVES[0];
    let steps = "{ step = \"touch_probe\", probe = 1, edge = \"rising\" },\n\
                 { step = \"pp\", to = [2], velocity = 2, acceleration = 20 },\n\
                 { step = \"probe_wait\", probe = 1, seconds = 1 },";
    let text = format!(
        "interface = \"can-sim\"\ncycle = \"6ms\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n\
         units = {{ name = \"rev\", counts_per_unit = 36000 }}\nprogram = [\n{steps}\n]\n"
    );
    let cfg = match config::parse_any(&text, "probe.toml").unwrap_or_else(|e| panic!("{e}")) {
        Config::CanOpen(c) => c,
        Config::EtherCat(_) => panic!("not a CANopen run"),
    };
    let mut bus = SimBus::new();
    bus.add_node(
        EmulatedNode::with_world(
            ecdrive_cli::app::canopen::tools::emulation_of(d.1)
                .expect("the software slave emulates the drive"),
            d.0,
            MACHINE,
        )
        .expect("node"),
    );
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = ecdrive_cli::app::canopen::run::run_on(&mut bus, &cfg, None, None, &stop).expect("run");
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    let l = r.drives[0].probe_latches.first().expect("a latch");
    assert_eq!((l.probe, l.edge), (1, "rising"));
    assert!(
        (l.counts - 46_800).abs() <= 1,
        "latched at {} counts",
        l.counts
    );
}
