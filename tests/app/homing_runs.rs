//! Homing in a program, through the master: `{ step = "home", … }` before csp steps, on both
//! emulated EtherCAT drives, as `ecdrive run` runs it. The recording (every cycle's actual
//! position as the drive reported it) shows where each drive homed: the drives start at 0, so
//! the position read just before the home is (within the last cycle's travel) the machine
//! position of the home, and the position standing there afterwards reads 0.
//! The machine is the emulator's default (its home switch from +2.5 rev, index pulses at whole
//! revolutions, [`ecdrive::sim::machine::World`]); where each method ends on it comes from the
//! manuals' method definitions (MR-J4-TM §5.4.9 (4): 19 "dog front end"; 4 "first Z-phase after
//! the dog front end").

use crate::support::runs;
use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, RunReport, run};
use runs::{example_without_loss_detection, run_recorded};
use std::sync::atomic::AtomicBool;

/// Run `text` with a recording: the report and, per axis, the recorded actual positions
/// (counts) in cycle order.
fn run_positions(text: &str, name: &str) -> (RunReport, Vec<Vec<i64>>) {
    let (r, rec) = run_recorded(text, name);
    let pos = rec
        .into_iter()
        .map(|a| a.iter().map(|x| x.actual).collect())
        .collect();
    (r, pos)
}

/// `examples/home_then_csp.toml`: the MR-J4-TM homes with method 19 (the dog's front end, 2.5
/// rev), the BDHDE with method 4 (the first index pulse after it, 3.0 rev); each position then
/// reads 0 and the program's absolute moves count from there (90° and −45° after the sines).
#[test]
fn the_example_homes_each_drive_then_moves_from_its_home() {
    let (r, pos) = run_positions(
        &example_without_loss_detection("home_then_csp.toml"),
        "home_then_csp",
    );
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    for d in &r.drives {
        assert_eq!(d.steps_done, 3, "{}: {:?}", d.name, d.errors);
    }
    let rec = r.record.as_ref().expect("a recording");
    assert_eq!(rec.dropped, 0, "the recording is complete");
    // (counts per revolution, the home in revolutions, the last move's target in counts)
    let cases = [
        (4_194_304.0, 2.5, (90.0 * 11_650.844_444f64).round()),
        (1_048_576.0, 3.0, (-45.0 * 2_912.711_111f64).round()),
    ];
    for (a, (cpr, home_rev, last)) in cases.into_iter().enumerate() {
        let p = &pos[a];
        // The home: the one cycle the position drops back by more than a revolution.
        let jump = p
            .windows(2)
            .position(|w| (w[0] - w[1]) as f64 > cpr)
            .unwrap_or_else(|| panic!("axis {a}: no home in the recording"));
        // The reading before the home is where the motor was one cycle before the drive set
        // it, on the creep speed (90°/s: a quarter revolution per second) with the motor's lag:
        // within three cycles of that travel. (crates/ecdrive-sim/tests/sim/drives_homing.rs checks the machine
        // position to the count.)
        let before = p[jump] as f64;
        let creep = 0.25 * cpr * 0.001;
        assert!(
            (before - home_rev * cpr).abs() <= 3.0 * creep,
            "axis {a}: homed at {before} counts, the method's home is {} counts",
            home_rev * cpr
        );
        // After it the position reads near 0 as the motor settles on the home (the emulated
        // motor's position loop converging), before the program's move begins.
        let after = &p[jump + 1..(jump + 11).min(p.len())];
        let nearest = after.iter().map(|x| x.abs()).min().unwrap_or(i64::MAX);
        assert!(
            nearest <= 20,
            "axis {a}: after the home it read {after:?}, never within 20 counts of 0"
        );
        // The program after the home counts from it: the sine ends at the move's target.
        let end = *p.last().unwrap() as f64;
        assert!(
            (end - last).abs() <= 0.01 * cpr,
            "axis {a}: ended at {end} counts, the program's target is {last}"
        );
    }
}

/// A machine without a home switch (`+no-home-switch`): method 19 runs into the limit switch.
/// The run ends as a drive fault (exit 5) naming the drive, the method and the drive's own
/// report: the MR-J4-TM's AL.90 warning, the BDHDE's fault 0x6100.
#[test]
fn a_home_switch_never_found_ends_the_run_naming_the_drives_error() {
    for (device, units, says) in [
        (
            "mr-j4-tm+no-home-switch",
            11_650.844_444,
            "AL.90 Home position return incomplete warning",
        ),
        (
            "bdhde+no-home-switch",
            2_912.711_111,
            "fault 0x6100 Homing Error",
        ),
    ] {
        let text = format!(
            "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"{device}\"]\n\
             loss_detection = false\n[[drive]]\nposition = 0\nmode = \"csp\"\n\
             units = {{ name = \"deg\", counts_per_unit = {units} }}\nprogram = [\n\
             {{ step = \"home\", method = 19, speed_switch = 1440, speed_zero = 90, \
             acceleration = 7200 }},\n\
             {{ step = \"move\", to = 90, velocity = 360, acceleration = 3600 }},\n]\n"
        );
        let cfg =
            ecdrive_cli::app::config::parse(&text, "fail.toml").unwrap_or_else(|e| panic!("{e}"));
        let stop = AtomicBool::new(false);
        let r =
            run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r.outcome, Outcome::DriveFault, "{device}: {}", r.reason);
        for part in [
            "drive 0",
            "homing (method 19) failed",
            "statusword bit 13",
            says,
        ] {
            assert!(
                r.reason.contains(part),
                "{device}: {part:?} not in {}",
                r.reason
            );
        }
        assert_eq!(r.drives[0].steps_done, 0);
    }
}

/// What the configuration refuses before the bus is touched: a method the MR-J4-TM does not
/// list in 0x60E3, home steps that disagree (their objects are written once), a speed that is
/// not positive.
#[test]
fn home_steps_are_checked_with_the_configuration() {
    let cfg = |program: &str| {
        let text = format!(
            "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"mr-j4-tm\"]\n\
             [[drive]]\nposition = 0\nmode = \"csp\"\nprogram = [{program}]\n"
        );
        ecdrive_cli::app::config::parse(&text, "home.toml")
    };
    let home = |m: i8, v: f64| {
        format!(
            "{{ step = \"home\", method = {m}, speed_switch = {v}, speed_zero = 100000, \
             acceleration = 1000000 }}"
        )
    };
    let e = cfg(&home(1, 1e6)).expect_err("method 1").to_string();
    assert!(
        e.contains("homing method 1 is not one the MR-J4-TM lists in 0x60E3"),
        "{e}"
    );
    let e = cfg(&format!("{}, {}", home(19, 1e6), home(19, 2e6)))
        .expect_err("two different home steps")
        .to_string();
    assert!(e.contains("differs from program[0]'s"), "{e}");
    let e = cfg(&home(19, -5.0))
        .expect_err("negative speed")
        .to_string();
    assert!(e.contains("speed_switch must be a positive number"), "{e}");
    // The homing objects go to the drive at start-up, in its units (0.01 r/min).
    let c = cfg(&home(19, 4_194_304.0)).unwrap_or_else(|e| panic!("{e}"));
    let sdos = &c.master.startup.drives[0].sdos;
    let get = |i: u16, s: u8| {
        sdos.iter()
            .find(|(a, _)| *a == ecdrive::od::ObjectAddress::new(i, s))
            .map(|(_, v)| v.clone())
    };
    assert_eq!(get(0x6098, 0), Some(ecdrive::od::Value::Int(19)));
    // 1 rev/s = 60 r/min = 6000 × 0.01 r/min.
    assert_eq!(get(0x6099, 1), Some(ecdrive::od::Value::Uint(6000)));
}

/// A home step after a move, away from where the drive started: homing redefines the position,
/// and nothing from before the home is commanded after it (the following-error limit of 5°
/// would stop the run on any jump).
#[test]
fn a_home_step_after_a_move_goes_on_without_a_jump() {
    let text = "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"mr-j4-tm\", \"bdhde\"]\n\
                loss_detection = false\n\
                [[drive]]\nposition = 0\nmode = \"csp\"\n\
                units = { name = \"deg\", counts_per_unit = 11650.844444 }\n\
                limits = { following_error = 5 }\nprogram = [\n\
                { step = \"move\", by = 360, velocity = 720, acceleration = 7200 },\n\
                { step = \"home\", method = 19, speed_switch = 1440, speed_zero = 90, acceleration = 7200 },\n\
                { step = \"move\", to = 90, velocity = 360, acceleration = 3600 },\n]\n\
                [[drive]]\nposition = 1\nmode = \"csp\"\n\
                units = { name = \"deg\", counts_per_unit = 2912.711111 }\n\
                limits = { following_error = 5 }\nprogram = [\n\
                { step = \"move\", by = -360, velocity = 720, acceleration = 7200 },\n\
                { step = \"home\", method = 19, speed_switch = 1440, speed_zero = 90, acceleration = 7200 },\n\
                { step = \"move\", to = -45, velocity = 360, acceleration = 3600 },\n]\n";
    let cfg =
        ecdrive_cli::app::config::parse(text, "after_move.toml").unwrap_or_else(|e| panic!("{e}"));
    let stop = AtomicBool::new(false);
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    for d in &r.drives {
        assert_eq!(d.steps_done, 3, "{}: {:?}", d.name, d.errors);
        let fe = d.max_following_error_units.unwrap_or(f64::MAX);
        assert!(fe < 5.0, "{}: following error {fe}°", d.name);
    }
}

/// The home offset: on the BDHDE 0x607C is the position the home reads (CiA 402), written at
/// start-up in its units; the MR-J4-TM sets it itself and refuses a written one (§7.3.13 (1)),
/// which the configuration says before the run. Method 35 (the current position) on the BDHDE:
/// right after the home the position reads the offset, in degrees.
#[test]
fn a_home_offset_is_where_the_home_reads_or_refused_by_the_manual() {
    let text = "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"bdhde\"]\n\
                loss_detection = false\n\
                [[drive]]\nposition = 0\nmode = \"csp\"\n\
                units = { name = \"deg\", counts_per_unit = 2912.711111 }\nprogram = [\n\
                { step = \"move\", by = 100, velocity = 360, acceleration = 3600 },\n\
                { step = \"home\", method = 35, speed_switch = 90, speed_zero = 10, acceleration = 3600, offset = 30 },\n\
                { step = \"dwell\", seconds = 0.05 },\n]\n";
    let (r, pos) = run_positions(text, "home-offset");
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    // The last reading: standing at the home, which reads 30° (87 381 counts).
    let last = *pos[0].last().unwrap();
    assert!(
        (last - (30.0f64 * 2912.711111).round() as i64).abs() <= 1,
        "the home reads {last} counts"
    );
    let e = ecdrive_cli::app::config::parse(
        &text
            .replace("\"bdhde\"", "\"mr-j4-tm\"")
            .replace("method = 35", "method = 37"),
        "offset.toml",
    )
    .expect_err("an offset on the MR-J4-TM")
    .to_string();
    assert!(e.contains("0x06090030") && e.contains("§7.3.13 (1)"), "{e}");
}
