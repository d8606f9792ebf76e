//! The `ecdrive run` configuration file: what a good file becomes, and the line, column, key and
//! reason of every kind of bad file.

use ecdrive::master::program::{RunMode, Step, Target as MoveTarget};
use ecdrive::master::startup::Selector;
use ecdrive_cli::app::config::{ConfigError, parse, parse_duration};
use ecdrive_cli::app::ethercat::tools::Target;
use std::time::Duration;

fn err(text: &str) -> ConfigError {
    match parse(text, "bad.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

/// Assert the error's line, key and a piece of its message, and that it renders as one line.
fn check(text: &str, line: usize, key: Option<&str>, has: &str) {
    let e = err(text);
    let shown = e.to_string();
    assert_eq!(e.line, line, "{shown}");
    assert_eq!(e.key.as_deref(), key, "{shown}");
    assert!(shown.contains(has), "{shown:?} does not mention {has:?}");
    assert!(!shown.contains('\n'), "not one line: {shown:?}");
    assert!(
        shown.starts_with(&format!("bad.toml line {line}, column ")),
        "{shown}"
    );
}

const HEAD: &str = "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\", \"generic-coe\"]\n";

#[test]
fn a_good_file_becomes_the_master_configuration() {
    let text = r#"
interface = "sim"
cycle = "500us"
dc_shift = "100us"
duration = "2s"
[rt]
priority = 80
cpu = 1
lock_memory = true
[supervision]
lost_cycles = 10
wkc_errors = 4
safeop_cycles = 5
op_timeout = "8s"
[sim]
devices = ["generic-coe", "generic-coe"]
sm_watchdog = 0
loss_detection = false
[[drive]]
position = 1
mode = "csv"
units = { name = "mm", counts_per_unit = 1000 }
limits = { following_error = 0.5, max_velocity = 100, max_acceleration = 1000 }
sdos = { "0x6065:00" = 5000, "0x2001:00" = "0x10" }
program = [
  { step = "ramp", velocity = 50, acceleration = 500, hold = 0.1 },
  { step = "mode", mode = "csp" },
  { step = "move", to = 10, velocity = 20, acceleration = 200 },
  { step = "sine", amplitude = 1, frequency = 2, periods = 1 },
  { step = "dwell", seconds = 0.1 },
]
[[drive]]
identity = { vendor_id = 0xECD, product_code = 0x402 }
mode = "cst"
program = [{ step = "torque", torque = 50, slope = 500, hold = 0.2 }]
"#;
    let c = parse(text, "good.toml").unwrap();
    assert_eq!(
        c.target,
        Target::Sim(vec!["generic-coe".into(), "generic-coe".into()])
    );
    assert_eq!(c.sim.esc.sm_watchdog, 0);
    assert!(!c.sim.loss_detection);
    assert_eq!(c.duration, Some(Duration::from_secs(2)));
    assert_eq!(c.master.cycle.cycle, Duration::from_micros(500));
    assert_eq!(c.master.startup.cycle, Duration::from_micros(500));
    assert_eq!(c.master.startup.dc.shift, Some(Duration::from_micros(100)));
    assert_eq!(c.master.cycle.rt.priority, Some(80));
    assert_eq!(c.master.cycle.rt.cpu, Some(1));
    assert!(c.master.cycle.rt.lock_memory);
    assert_eq!(c.master.cycle.segment_lost_after, 10);
    assert_eq!(c.master.cycle.wkc_errors_before_stop, 4);
    assert_eq!(c.master.cycle.safeop_cycles, 5);
    assert_eq!(c.master.cycle.op_timeout, Duration::from_secs(8));
    let d = &c.master.startup.drives;
    assert_eq!(d.len(), 2);
    assert_eq!(d[0].select, Selector::Position(1));
    assert_eq!(d[0].mode, RunMode::Csv);
    // User units: mm at 1000 counts/mm.
    assert_eq!(d[0].following_error_limit, Some(500));
    assert_eq!(
        d[0].program[0],
        Step::Ramp {
            velocity: 50_000.0,
            acceleration: 500_000.0,
            hold: 0.1
        }
    );
    assert_eq!(d[0].program[1], Step::Mode { mode: RunMode::Csp });
    assert_eq!(
        d[0].program[2],
        Step::Move {
            target: MoveTarget::To(10_000.0),
            velocity: 20_000.0,
            acceleration: 200_000.0,
            jerk: None
        }
    );
    assert_eq!(d[0].sdos.len(), 2);
    assert_eq!(
        d[1].select,
        Selector::Identity {
            vendor_id: 0xECD,
            product_code: 0x402
        }
    );
    // Torques are not scaled.
    assert_eq!(
        d[1].program[0],
        Step::Torque {
            torque: 50.0,
            slope: Some(500.0),
            hold: 0.2
        }
    );
    assert_eq!(c.drives[0].steps[2], "move to 10 mm");
    assert_eq!(c.drives[0].units.as_ref().unwrap().counts_per_unit, 1000.0);
}

#[test]
fn an_interface_name_runs_over_a_raw_socket() {
    let c = parse("interface = \"eth1\"\n", "x.toml").unwrap();
    assert_eq!(c.target, Target::Interface("eth1".into()));
    assert_eq!(c.master.cycle.cycle, Duration::from_millis(1));
    assert!(c.drives.is_empty());
}

#[test]
fn unknown_keys_are_errors_with_line_and_key() {
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nvelocty = 5\n"),
        6,
        Some("drive[0].velocty"),
        "unknown key `velocty`",
    );
    check(
        "interface = \"eth0\"\ncycel = \"1ms\"\n",
        2,
        Some("cycel"),
        "unknown key `cycel`",
    );
    check(
        &format!("{HEAD}[rt]\npriority = 10\nnice = 3\n"),
        6,
        Some("rt.nice"),
        "unknown key `nice`",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nprogram = [\n  {{ step = \"dwell\", seconds = 1, speed = 2 }},\n]\n"
        ),
        7,
        Some("drive[0].program[0]"),
        "unknown key `speed`",
    );
    // A move's `to`/`by` are plain keys: a typo next to them is still caught.
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nprogram = [{{ step = \"move\", by = 1, velocity = 1, acceleration = 1, jrk = 5 }}]\n"
        ),
        6,
        Some("drive[0].program[0]"),
        "unknown key `jrk`",
    );
}

#[test]
fn wrong_types_and_values_name_the_key() {
    check(
        "interface = 5\n",
        1,
        Some("interface"),
        "invalid type: integer `5`",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 70000\n"),
        5,
        Some("drive[0].position"),
        "70000",
    );
    check(
        "interface = \"eth0\"\ncycle = \"1 fortnight\"\n",
        2,
        Some("cycle"),
        "unknown time unit",
    );
    check(
        "interface = \"eth0\"\ncycle = \"1\"\n",
        2,
        Some("cycle"),
        "has no unit",
    );
    check(
        "interface = \"eth0\"\ncycle = \"10us\"\n",
        2,
        Some("cycle"),
        "between 50 us and 1 s",
    );
    check(
        "interface = \"eth0\"\ncycle = \"1ms\"\ndc_shift = \"2ms\"\n",
        3,
        Some("dc_shift"),
        "shorter than the cycle",
    );
    check(
        "interface = \"eth0\"\n[supervision]\nlost_cycles = 0\n",
        3,
        Some("supervision.lost_cycles"),
        "at least 1",
    );
    check(
        "interface = \"eth0\"\n[rt]\npriority = 0\n",
        3,
        Some("rt.priority"),
        "1–99",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nmode = \"vl\"\n"),
        6,
        Some("drive[0].mode"),
        "csp, csv, cst, pp, pv, tq and ip",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nmode = \"ip\"\n"),
        6,
        Some("drive[0].mode"),
        "ip is run on CANopen drives",
    );
    check("interface = \"eth0\"\ncycle = \"1ms\n", 2, None, "");
}

#[test]
fn the_target_must_be_consistent() {
    check(
        "interface = \"sim\"\n",
        1,
        Some("interface"),
        "needs a [sim] table",
    );
    check(
        "interface = \"eth0\"\n[sim]\ndevices = [\"generic-coe\"]\n",
        2,
        Some("sim"),
        "only goes with interface = \"sim\"",
    );
    check(
        "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\", \"warp-drive\"]\n",
        3,
        Some("sim.devices[1]"),
        "unknown device \"warp-drive\"",
    );
    check(
        "interface = \"sim\"\n[sim]\ndevices = []\n",
        2,
        Some("sim.devices"),
        "at least one device",
    );
}

#[test]
fn each_drive_selects_exactly_one_device() {
    check(
        &format!("{HEAD}[[drive]]\nmode = \"csp\"\n"),
        4,
        Some("drive[0]"),
        "give position, alias or identity",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nalias = 5\n"),
        4,
        Some("drive[0]"),
        "only one of position, alias and identity",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\n[[drive]]\nposition = 0\n"),
        6,
        Some("drive[1]"),
        "same device as drive[0]",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 2\n"),
        5,
        Some("drive[0].position"),
        "2 emulated device(s)",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nprofile = \"warp-drive\"\n"),
        6,
        Some("drive[0].profile"),
        "unknown drive profile \"warp-drive\"",
    );
}

#[test]
fn programs_are_checked_against_mode_parameters_and_limits() {
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nmode = \"csp\"\nprogram = [\n  {{ step = \"dwell\", seconds = 1 }},\n  {{ step = \"torque\", torque = 10, hold = 1 }},\n]\n"
        ),
        9,
        Some("drive[0].program[1]"),
        "torque steps need cst",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nprogram = [{{ step = \"move\", velocity = 1, acceleration = 1 }}]\n"
        ),
        6,
        Some("drive[0].program[0]"),
        "exactly one of `to` and `by`",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nprogram = [{{ step = \"move\", by = 10, velocity = -1, acceleration = 1 }}]\n"
        ),
        6,
        Some("drive[0].program[0]"),
        "positive",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nlimits = {{ max_velocity = 100 }}\nprogram = [{{ step = \"move\", by = 10, velocity = 150, acceleration = 1 }}]\n"
        ),
        7,
        Some("drive[0].program[0]"),
        "velocity 150 counts/s exceeds the entry's limits.max_velocity of 100 counts/s",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nunits = {{ name = \"deg\", counts_per_unit = 100 }}\nlimits = {{ max_acceleration = 1000 }}\nprogram = [{{ step = \"sine\", amplitude = 10, frequency = 5, periods = 1 }}]\n"
        ),
        8,
        Some("drive[0].program[0]"),
        "peak acceleration",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nprogram = [{{ step = \"warp\", factor = 9 }}]\n"),
        6,
        Some("drive[0].program[0].step"),
        "unknown step `warp`",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\nprogram = [{{ step = \"mode\", mode = \"ip\" }}]\n"
        ),
        6,
        Some("drive[0].program[0]"),
        "an EtherCAT drive streams positions in csp",
    );
}

#[test]
fn mappings_and_start_up_values_are_checked() {
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\n[drive.mapping]\nrx = [{{ pdo = 0x1600, entries = [\"0x6040:00\", \"0x2000:00\"] }}]\n"
        ),
        7,
        Some("drive[0].mapping.rx[0].entries[1]"),
        "not known without a drive profile (only the standard CiA 402 objects are)",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\n[drive.mapping]\nrx = [{{ pdo = 0x1600, entries = [{{ object = \"0x6040:00\", bit = 16 }}] }}]\n"
        ),
        7,
        Some("drive[0].mapping.rx[0].entries[0]"),
        "unknown key `bit`",
    );
    check(
        &format!(
            "{HEAD}[[drive]]\nposition = 0\n[drive.mapping]\ntx = [{{ pdo = 0x1A00, entries = [{{ object = \"0x6041\", bits = 0 }}] }}]\n"
        ),
        7,
        Some("drive[0].mapping.tx[0].entries[0]"),
        "bits must be 1–255",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nsdos = {{ \"0x60zz:00\" = 1 }}\n"),
        6,
        Some("drive[0].sdos.\"0x60zz:00\""),
        "malformed object address",
    );
    check(
        &format!("{HEAD}[[drive]]\nposition = 0\nsdos = {{ \"0x6065:00\" = [1, 2] }}\n"),
        6,
        Some("drive[0].sdos.\"0x6065:00\""),
        "a number, a string or a boolean",
    );
}

#[test]
fn a_file_that_cannot_be_read_is_named() {
    let e = ecdrive_cli::app::config::load(std::path::Path::new("/nonexistent/ecdrive.toml"))
        .unwrap_err();
    assert_eq!(e.line, 0);
    assert!(
        e.to_string()
            .starts_with("/nonexistent/ecdrive.toml: cannot read the file"),
        "{e}"
    );
}

#[test]
fn durations_read_like_people_write_them() {
    assert_eq!(parse_duration("250us"), Ok(Duration::from_micros(250)));
    assert_eq!(parse_duration("250 µs"), Ok(Duration::from_micros(250)));
    assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
    assert!(parse_duration("").is_err());
    assert!(parse_duration("1e3ms").is_err());
}
