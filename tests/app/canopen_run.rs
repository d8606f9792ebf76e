//! CANopen runs from the configuration file (`ecdrive run -c FILE` with a CANopen interface
//! and `[[drive]] node = N`): the three CANopen drives run programs — home, pp, pv, tq where
//! the drive has it — through the same configuration schema and motion runtime as the
//! EtherCAT drives, in-process on `can-sim` and over a `vbus:` hub served by `ecdrive sim
//! --can` in another process; and what a CANopen run cannot take is named with its key.

use crate::support;
use ecdrive_cli::app::config::{self, Config};
use support::cli::ecdrive;

/// Each drive ends its program with a pp move to 2 rev: the reported position (0x6064 through
/// its TPDO) must be there, in each drive's own position unit.
const ENDS_AT_TWO_REV: &str = r#"
interface = "can-sim"
cycle = "4ms"

[[drive]]
node = 3
profile = "blv-r"
units = { name = "rev", counts_per_unit = 36000 }
program = [
  { step = "home", method = 24, speed_switch = 5, speed_zero = 0.5, acceleration = 100 },
  { step = "pp", to = [1, 0.5], velocity = 10, acceleration = 100 },
  { step = "mode", mode = "pv" },
  { step = "pv", velocity = 5, acceleration = 100, seconds = 0.2 },
  { step = "mode", mode = "tq" },
  { step = "tq", torque = 300, seconds = 0.1 },
  { step = "mode", mode = "pp" },
  { step = "pp", to = [2], velocity = 10, acceleration = 100 },
]

[[drive]]
node = 0x7F
profile = "asda-a2"
units = { name = "rev", counts_per_unit = 1280000 }
program = [
  { step = "home", method = 19, speed_switch = 5, speed_zero = 0.5, acceleration = 100 },
  { step = "pp", to = [1, 0.5], velocity = 10, acceleration = 100 },
  { step = "mode", mode = "pv" },
  { step = "pv", velocity = 5, acceleration = 100, seconds = 0.2 },
  { step = "mode", mode = "pp" },
  { step = "pp", to = [2], velocity = 10, acceleration = 100 },
]

[[drive]]
node = 0x41
profile = "lexium-mdrive"
units = { name = "rev", counts_per_unit = 51200 }
program = [
  { step = "home", method = 19, speed_switch = 5, speed_zero = 0.5, acceleration = 100 },
  { step = "mode", mode = "pv" },
  { step = "pv", velocity = -5, acceleration = 100, seconds = 0.2 },
  { step = "mode", mode = "pp" },
  { step = "pp", to = [2], velocity = 10, acceleration = 100 },
]
"#;

fn can(text: &str) -> config::canopen::CanRunConfig {
    match config::parse_any(text, "can.toml").unwrap_or_else(|e| panic!("{e}")) {
        Config::CanOpen(c) => c,
        Config::EtherCat(_) => panic!("not read as a CANopen run"),
    }
}

#[test]
fn the_three_drives_run_their_programs_from_a_file_on_can_sim() {
    let cfg = can(ENDS_AT_TWO_REV);
    let stop = std::sync::atomic::AtomicBool::new(false);
    let dir = std::env::temp_dir().join(format!("ecdrive-can-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let csv = dir.join("run.csv");
    let opts = ecdrive_cli::app::canopen::run::CanRunOptions {
        record: Some(csv.clone()),
        ..Default::default()
    };
    let r = ecdrive_cli::app::canopen::run::run(&cfg, &opts, &stop).expect("run");
    eprintln!("{r:#?}");
    assert_eq!(
        r.outcome,
        ecdrive_cli::app::ethercat::tools::run::Outcome::Completed,
        "{}",
        r.reason
    );
    assert_eq!(r.drives.len(), 3);
    for (d, want) in r.drives.iter().zip([72_000, 2_560_000, 102_400]) {
        assert!(d.program_done, "{d:?}");
        assert!(d.errors.is_empty(), "{d:?}");
        assert_eq!(d.position, want, "{}: {d:?}", d.drive);
        assert_eq!(d.position_user, Some(2.0), "{d:?}");
        assert_eq!(
            d.states.last().map(String::as_str),
            Some("Switch on disabled")
        );
    }
    assert!(
        r.drives[0].modes.iter().any(|m| m.starts_with("tq")),
        "{:?}",
        r.drives[0]
    );
    assert!(
        r.drives[2].modes.iter().any(|m| m.starts_with("hm")),
        "{:?}",
        r.drives[2]
    );
    assert!(r.emergencies.is_empty(), "{:?}", r.emergencies);
    // The recording, against what the emulated machine does: each axis leaves hm at its home
    // (position 0, home offset 0) and ends at its pp target; one line per axis and cycle.
    let rec = r.record.as_ref().expect("recorded");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let _ = std::fs::remove_dir_all(&dir);
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (axis, mode, actual) = (col("axis"), col("mode"), col("actual_counts"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len() as u64, rec.samples);
    for (i, want) in [72_000i64, 2_560_000, 102_400].into_iter().enumerate() {
        let own: Vec<(i8, i64)> = rows
            .iter()
            .filter(|r| r[axis] == i.to_string())
            .map(|r| {
                (
                    r[mode].parse().expect("mode"),
                    r[actual].parse().expect("actual"),
                )
            })
            .collect();
        let left_hm = own
            .windows(2)
            .find(|w| w[0].0 == 6 && w[1].0 != 6)
            .map(|w| w[1].1)
            .unwrap_or_else(|| panic!("axis {i}: never left hm"));
        assert!(left_hm.abs() <= 1, "axis {i}: left hm at {left_hm}");
        assert_eq!(own.last().map(|s| s.1), Some(want), "axis {i}");
    }
}

#[test]
fn the_example_runs_from_the_command_line() {
    let j = ecdrive(&["run", "-c", "examples/canopen_profile_modes.toml", "--json"]).json();
    assert_eq!(j["outcome"], "completed", "{j:#}");
    for d in j["drives"].as_array().expect("drives") {
        assert_eq!(d["program_done"], true, "{d:#}");
    }
    // Recorded and plotted, as an EtherCAT run is.
    let dir = std::env::temp_dir().join(format!("ecdrive-can-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let (csv, svg) = (dir.join("r.csv"), dir.join("r.svg"));
    let out = ecdrive(&[
        "run",
        "-c",
        "examples/canopen_profile_modes.toml",
        "--record",
        &csv.display().to_string(),
        "--plot",
        &svg.display().to_string(),
    ])
    .ok()
    .to_string();
    assert!(out.contains("recorded "), "{out}");
    let drawing = std::fs::read_to_string(&svg).expect("svg");
    for caption in [
        "(BLV-R)",
        "(ASDA-A2)",
        "(Lexium MDrive)",
        "\nhm\n",
        "\ntq\n",
    ] {
        assert!(drawing.contains(caption), "{caption} not in the plot");
    }
    // Every frame, in candump's log format: boot-ups, NMT, SDO, SYNC (080, no data), each
    // drive's RPDOs and TPDOs, at the bus's (simulated) time, never going back.
    let log = dir.join("r.log");
    let out = ecdrive(&[
        "run",
        "-c",
        "examples/canopen_profile_modes.toml",
        "--candump",
        &log.display().to_string(),
    ])
    .ok()
    .to_string();
    let text = std::fs::read_to_string(&log).expect("candump log");
    let n = text.lines().count();
    assert!(out.contains(&format!("logged {n} CAN frames to ")), "{out}");
    let mut last = 0.0f64;
    let mut ids = std::collections::BTreeSet::new();
    for l in text.lines() {
        let (time, rest) = l.split_once(") ").expect("(time) …");
        let t: f64 = time.trim_start_matches('(').parse().expect("seconds");
        assert!(t >= last, "time went back: {l}");
        last = t;
        let (iface, frame) = rest.split_once(' ').expect("iface frame");
        assert_eq!(iface, "can_sim");
        let (id, data) = frame.split_once('#').expect("ID#DATA");
        assert_eq!(id.len(), 3, "{l}");
        ids.insert(u16::from_str_radix(id, 16).expect("hex id"));
        assert!(
            data == "R" || (data.len() % 2 == 0 && data.len() <= 16),
            "{l}"
        );
    }
    // NMT, SYNC; the BLV-R's (node 3) boot-up, SDO request and response, TPDO1 and RPDO1.
    for id in [0x000, 0x080, 0x703, 0x603, 0x583, 0x183, 0x203] {
        assert!(ids.contains(&id), "no frame with COB-ID 0x{id:03X}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    let out = ecdrive(&[
        "run",
        "-c",
        "examples/canopen_profile_modes.toml",
        "--check",
    ])
    .ok()
    .to_string();
    assert!(
        out.contains("valid; CANopen run, 3 drives, SYNC every 4000 µs"),
        "{out}"
    );
}

#[test]
fn a_file_runs_over_a_bus_served_by_another_process() {
    let dir = std::env::temp_dir().join(format!("ecdrive-can-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let sock = dir.join("bus.sock");
    let bus = format!("vbus:{}", sock.display());
    let nodes = [
        "--node",
        "blv-r@3",
        "--node",
        "asda-a2",
        "--node",
        "lexium-mdrive",
    ];
    let (mut child, _) = support::cli::serve_can(&bus, &nodes, 3);
    let file = dir.join("run.toml");
    std::fs::write(&file, ENDS_AT_TWO_REV).expect("write");
    let path = file.display().to_string();
    let run = || ecdrive(&["run", "-c", &path, "-i", &bus, "--json"]).json();
    let first = run();
    // Again, against the same nodes: the first run left them in NMT Stopped.
    let j = run();
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
    let _ = child.wait();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(first["outcome"], "completed", "{first:#}");
    assert_eq!(j["outcome"], "completed", "{j:#}");
    for (d, want) in j["drives"]
        .as_array()
        .expect("drives")
        .iter()
        .zip([72_000, 2_560_000, 102_400])
    {
        assert_eq!(d["program_done"], true, "{d:#}");
        assert_eq!(d["position"], want, "{d:#}");
    }
}

/// The ASDA-A2's cyclic mode, ip (it has no csp; SYNC-paced 60C1h:01, 60C2h:01 = the SYNC
/// period in ms), from a run file: relative pp moves (the last one −0.5 rev: 607Ah holds that
/// increment, which ip must never take as a position), then into ip, a `move` and a `sine`
/// streamed one point per SYNC, back to pp and home. The node's own position says where each
/// part ended; the recording has the demand and the master's following error in ip, the error
/// stays within two SYNC periods' travel at the move's speed, and the motor never moves
/// faster than the program's fastest step.
#[test]
fn the_asda_a2_runs_ip_from_a_run_file() {
    let text = "interface = \"can-sim\"\ncycle = \"4ms\"\n[[drive]]\nnode = 0x7F\n\
                profile = \"asda-a2\"\nmode = \"pp\"\n\
                units = { name = \"rev\", counts_per_unit = 1280000 }\n\
                limits = { following_error = 0.1 }\nprogram = [\n\
                { step = \"pp\", by = [1.5, -0.5], velocity = 10, acceleration = 100 },\n\
                { step = \"mode\", mode = \"ip\" },\n\
                { step = \"move\", by = 2, velocity = 5, acceleration = 50 },\n\
                { step = \"dwell\", seconds = 0.05 },\n\
                { step = \"sine\", amplitude = 0.25, frequency = 2, periods = 2 },\n\
                { step = \"mode\", mode = \"pp\" },\n\
                { step = \"pp\", to = [0.5], velocity = 10, acceleration = 100 },\n]\n";
    let cfg = can(text);
    let dir = std::env::temp_dir().join(format!("ecdrive-can-ip-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let csv = dir.join("ip.csv");
    let mut bus = ecdrive_cli::app::canopen::run::emulated_bus(&cfg).expect("bus");
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = ecdrive_cli::app::canopen::run::run_on(&mut bus, &cfg, None, Some(&csv), &stop)
        .expect("run");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(
        r.outcome,
        ecdrive_cli::app::ethercat::tools::run::Outcome::Completed,
        "{}: {r:#?}",
        r.reason
    );
    let d = &r.drives[0];
    assert!(d.errors.is_empty(), "{d:?}");
    assert!(
        d.modes.iter().any(|m| m.starts_with("ip (7)")),
        "{:?}",
        d.modes
    );
    // The node itself: back at 0.5 rev after the final pp move.
    assert_eq!(bus.node(0x7F).expect("node").position(), 640_000);
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (mode_sent, demand, actual, fe) = (
        col("mode_sent"),
        col("demand_counts"),
        col("actual_counts"),
        col("following_error_counts"),
    );
    let ip: Vec<Vec<&str>> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[mode_sent] == "7")
        .collect();
    assert!(ip.len() > 200, "{} cycles in ip", ip.len());
    // The move ended at 3 rev: the dwell's demand, and the drive there by the dwell's end.
    assert!(
        ip.iter()
            .any(|r| r[demand] == "3840000" && r[actual] == "3840000"),
        "the ip move never stood at 3 rev"
    );
    // No jump anywhere, the mode switches included: at most 10 rev/s × 4 ms between cycles.
    let actuals: Vec<i64> = text
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').nth(actual)?.parse().ok())
        .collect();
    let max_step = actuals
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .max()
        .unwrap_or(0);
    assert!(
        max_step <= 51_200,
        "the motor moved {max_step} PUU in one cycle"
    );
    let max_fe = ip
        .iter()
        .filter_map(|r| r[fe].parse::<i64>().ok())
        .map(i64::abs)
        .max()
        .expect("the following error is recorded in ip");
    // 5 rev/s × 1 280 000 PUU/rev × 2 × 4 ms = 51 200 PUU.
    assert!(max_fe <= 51_200, "max |following error| {max_fe} PUU in ip");
}

/// The BLV-R's touch probe (§7.6) from a run file: probe 1 armed on the rising edge, a pv move
/// across the machine's probe input 1 (active from 1.3 to 1.7 rev, [REC] in the emulator's
/// machine model), the program waits for the latch; then probe 1 armed for the falling edge
/// and probe 2 for its rising edge (its input from −1.6 to −1.2 rev) while a pp move goes back
/// to −2 rev. Each latch sits where the motor crossed the input's boundary (exact whatever the
/// SYNC period), as the node reports it in 60BAh–60BCh; 60B8h went out in an RPDO and 60B9h and
/// the latches came back in TPDOs, which the file's probe steps added to the PDO plan.
#[test]
fn the_blv_r_latches_its_touch_probe_from_a_run_file() {
    let text = "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n\
                mode = \"pv\"\nunits = { name = \"rev\", counts_per_unit = 36000 }\nprogram = [\n\
                { step = \"touch_probe\", probe = 1, edge = \"rising\" },\n\
                { step = \"pv\", velocity = 1, acceleration = 20, seconds = 2 },\n\
                { step = \"probe_wait\", probe = 1, seconds = 1 },\n\
                { step = \"mode\", mode = \"pp\" },\n\
                { step = \"touch_probe\", probe = 1, edge = \"falling\" },\n\
                { step = \"touch_probe\", probe = 2, edge = \"rising\" },\n\
                { step = \"pp\", to = [-2], velocity = 2, acceleration = 20 },\n\
                { step = \"probe_wait\", probe = 2, seconds = 1 },\n]\n";
    let cfg = can(text);
    let mut bus = ecdrive_cli::app::canopen::run::emulated_bus(&cfg).expect("bus");
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = ecdrive_cli::app::canopen::run::run_on(&mut bus, &cfg, None, None, &stop).expect("run");
    assert_eq!(
        r.outcome,
        ecdrive_cli::app::ethercat::tools::run::Outcome::Completed,
        "{}: {r:#?}",
        r.reason
    );
    let d = &r.drives[0];
    assert!(d.errors.is_empty(), "{d:?}");
    let latches: Vec<(u8, &str, i64)> = d
        .probe_latches
        .iter()
        .map(|l| (l.probe, l.edge, l.counts))
        .collect();
    // 36 000 counts per revolution: input 1 goes on at 1.3 rev moving up; moving down it goes
    // on at 1.7 rev and off at 1.3 rev; input 2 goes on at −1.2 rev moving down.
    assert_eq!(
        latches,
        vec![
            (1, "rising", 46_800),
            (1, "falling", 46_800),
            (2, "rising", -43_200)
        ],
        "{d:?}"
    );
    // The node's own objects say the same.
    let n = bus.node(3).expect("node");
    let obj = |i: u16| match n.value(ecdrive::od::ObjectAddress::new(i, 0)) {
        Some(ecdrive::od::Value::Int(v)) => Some(v),
        Some(ecdrive::od::Value::Uint(v)) => i64::try_from(v).ok(),
        _ => None,
    };
    assert_eq!(obj(0x60BA), Some(46_800));
    assert_eq!(obj(0x60BB), Some(46_800));
    assert_eq!(obj(0x60BC), Some(-43_200));
}

/// A master that goes silent in the middle of a run (killed, its host hung): a run sets up
/// life guarding (100Ch/100Dh), so each drive notices within its life time (300 ms) and reacts
/// as its manual says — the ASDA-A2 AL170 (guarding error with the servo on, a fault), the
/// Lexium MDrive Fault on life-time expiry; the BLV-R reports EMCY 8130h, and its manual names
/// no motor reaction (docs/guide/canopen.md: what to add in the machine). Simulated time; the
/// master simply sends nothing more.
#[test]
fn a_master_that_goes_silent_is_noticed_by_each_drive() {
    use ecdrive::State;
    use ecdrive::master::{Axes, Command};
    let cfg = can(
        "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\nmode = \"pv\"\n\
         [[drive]]\nnode = 0x7F\nprofile = \"asda-a2\"\nmode = \"pv\"\n\
         [[drive]]\nnode = 0x41\nprofile = \"lexium-mdrive\"\nmode = \"pv\"\n",
    );
    let mut bus = ecdrive_cli::app::canopen::run::emulated_bus(&cfg).expect("bus");
    {
        let (mut s, _) = ecdrive_cli::app::canopen::run::session(&mut bus, &cfg).expect("session");
        s.command(Command::Enable(Axes::All));
        for _ in 0..2_000 {
            s.cycle().expect("cycle");
            if (0..3).all(|i| {
                s.telemetry(i)
                    .is_some_and(|t| t.state == Some(State::OperationEnabled))
            }) {
                break;
            }
        }
        assert!(
            (0..3).all(|i| s
                .telemetry(i)
                .is_some_and(|t| t.state == Some(State::OperationEnabled))),
            "enabled"
        );
        // The master dies here: the session is dropped, nothing more goes out.
    }
    bus.advance(1_000_000);
    assert_eq!(
        bus.node(0x7F).expect("node").state(),
        State::Fault,
        "ASDA-A2"
    );
    assert_eq!(
        bus.node(0x41).expect("node").state(),
        State::Fault,
        "Lexium MDrive"
    );
    // The BLV-R's EMCY (COB-ID 80h + 3), among the frames queued for the master: error code
    // 8130h, little-endian.
    let mut emcy = false;
    while let Ok(Some(f)) = ecdrive::canopen::CanTransport::recv(&mut bus, 0) {
        emcy |= f.id() == 0x83 && f.data().get(..2) == Some(&[0x30, 0x81][..]);
    }
    assert!(emcy, "BLV-R: EMCY 8130h");
}

/// A run that ends during a pp move (its duration passed) halts each drive on the deceleration
/// the file gave (100 rev/s²: 0.5 rev from 10 rev/s), not on a drive's own quick-stop ramp:
/// the Lexium MDrive halts on 6085h by default (605Dh = 2; 200 000 steps/s², 3.9 rev/s²) and
/// overshot its 20 rev target; a run writes 605Dh = 1 where a drive has it. Each axis stands
/// still when disabled, about 10.5 rev from the start.
#[test]
fn a_run_ending_during_a_pp_move_halts_on_the_files_deceleration() {
    let mut text = String::from("interface = \"can-sim\"\n");
    for (node, key, cpr) in [
        (0x41, "lexium-mdrive", 51_200),
        (3, "blv-r", 36_000),
        (0x7F, "asda-a2", 1_280_000),
    ] {
        text.push_str(&format!(
            "[[drive]]\nnode = {node}\nprofile = \"{key}\"\nmode = \"pp\"\n\
             units = {{ name = \"rev\", counts_per_unit = {cpr} }}\n\
             program = [{{ step = \"pp\", to = [20], velocity = 10, acceleration = 100 }}]\n"
        ));
    }
    let cfg = can(&text);
    let mut bus = ecdrive_cli::app::canopen::run::emulated_bus(&cfg).expect("bus");
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = ecdrive_cli::app::canopen::run::run_on(
        &mut bus,
        &cfg,
        Some(std::time::Duration::from_secs(1)),
        None,
        &stop,
    )
    .expect("run");
    for d in &r.drives {
        let at = d.position_user.expect("units");
        assert!(
            (9.5..11.0).contains(&at),
            "{}: stopped at {at} rev",
            d.drive
        );
        let n = bus.node(d.node).expect("node");
        assert!(
            n.velocity_units_per_s().abs() < 1e-6,
            "{} still turning",
            d.drive
        );
    }
}

/// The emulated bus with another master on it that, after `after` SYNCs of ours, sends
/// "enter Pre-operational" to `node` (what a second tool on the bus, or the drive's own reaction
/// to a lost master, does to a run).
struct Intruder<'a> {
    bus: &'a mut ecdrive::sim::canopen::SimBus,
    syncs: u32,
    after: u32,
    node: u8,
}

impl ecdrive::canopen::CanTransport for Intruder<'_> {
    fn name(&self) -> &str {
        "can-sim"
    }
    fn now_us(&self) -> u64 {
        self.bus.now_us()
    }
    fn send(
        &mut self,
        f: &ecdrive::canopen::CanFrame,
    ) -> Result<(), ecdrive::canopen::TransportError> {
        if f.id() == 0x80 {
            self.syncs += 1;
            if self.syncs == self.after {
                let nmt =
                    ecdrive::canopen::CanFrame::new(0x000, &[0x80, self.node]).expect("frame");
                self.bus.inject(&nmt);
            }
        }
        self.bus.send(f)
    }
    fn recv(
        &mut self,
        timeout_us: u64,
    ) -> Result<Option<ecdrive::canopen::CanFrame>, ecdrive::canopen::TransportError> {
        self.bus.recv(timeout_us)
    }
}

/// A drive that leaves NMT Operational in the middle of a run sends no more PDOs and takes
/// none: the run ends as a drive fault naming the node and why (exit 5), it does not carry on
/// to "completed" on the drive's last, stale statusword.
#[test]
fn a_drive_that_leaves_operational_mid_run_ends_the_run_naming_it() {
    use ecdrive_cli::app::ethercat::tools::run::Outcome;
    let cfg = can(
        "interface = \"can-sim\"\n[[drive]]\nnode = 0x7F\nprofile = \"asda-a2\"\nmode = \"pv\"\n\
         units = { name = \"rev\", counts_per_unit = 1280000 }\n\
         program = [{ step = \"pv\", velocity = 1, acceleration = 10, seconds = 3 }]\n",
    );
    let mut bus = ecdrive_cli::app::canopen::run::emulated_bus(&cfg).expect("bus");
    let t = Intruder {
        bus: &mut bus,
        syncs: 0,
        after: 300,
        node: 0x7F,
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = ecdrive_cli::app::canopen::run::run_on(t, &cfg, None, None, &stop).expect("run");
    assert_eq!(r.outcome, Outcome::DriveFault, "{}: {r:#?}", r.reason);
    assert!(r.reason.contains("node 127 (ASDA-A2)"), "{}", r.reason);
    let errors = r.drives[0].errors.join("; ");
    assert!(
        errors.contains("left NMT Operational on its own (now Pre-operational)"),
        "{errors}"
    );
    assert!(!r.drives[0].program_done, "{:?}", r.drives[0]);
}

/// What only an EtherCAT run has, or what the CANopen drives cannot do, is refused before
/// anything touches the bus, one line naming the key.
#[test]
fn what_a_canopen_run_cannot_take_is_named() {
    let base = "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n";
    for (extra, key, says) in [
        ("position = 0\n", "drive[0].position", "is an EtherCAT key"),
        (
            "mode = \"csp\"\n",
            "drive[0].mode",
            "not run over CANopen yet",
        ),
        (
            "program = [{ step = \"mode\", mode = \"csv\" }]\n",
            "drive[0].program[0]",
            "not run over CANopen yet",
        ),
        (
            "sdos = { \"0x7777:00\" = 1 }\n",
            "drive[0].sdos.\"0x7777:00\"",
            "not in the BLV-R dictionary",
        ),
    ] {
        let e = config::parse_any(&format!("{base}{extra}"), "can.toml").unwrap_err();
        assert_eq!(e.key.as_deref(), Some(key), "{e}");
        assert!(e.to_string().contains(says), "{e}");
    }
    let e = config::parse_any(
        "interface = \"can-sim\"\ncycle = \"500us\"\n[[drive]]\nnode = 0x7F\nprofile = \"asda-a2\"\n",
        "can.toml",
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("cycle"), "{e}");
    assert!(e.to_string().contains("at least 1000 µs apart"), "{e}");
    // Homing methods: the drive's own list, and no index-pulse method without an encoder.
    for (profile, node, method, says) in [
        (
            "asda-a2",
            "0x7F",
            99,
            "homing method 99 is not one the ASDA-A2 takes",
        ),
        (
            "lexium-mdrive",
            "0x41",
            33,
            "the Lexium MDrive (without encoder) does not have",
        ),
    ] {
        let e = config::parse_any(
            &format!(
                "interface = \"can-sim\"\n[[drive]]\nnode = {node}\nprofile = \"{profile}\"\n\
                 program = [{{ step = \"home\", method = {method}, speed_switch = 100, speed_zero = 10 }}]\n"
            ),
            "can.toml",
        )
        .unwrap_err();
        assert_eq!(e.key.as_deref(), Some("drive[0].program[0]"), "{e}");
        assert!(e.to_string().contains(says), "{e}");
    }
    // A value the drive refuses at start-up (an SDO abort: 0x6065 beyond the BLV-R's range,
    // which its dictionary in the profile does not carry) is the drive's refusal, exit 4, one
    // line naming the node and the object. (A read-only object is named by the file check.)
    let dir = std::env::temp_dir().join(format!("ecdrive-can-abort-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("abort.toml");
    std::fs::write(
        &file,
        "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\nsdos = { \"0x6065:00\" = 4294967295 }\n",
    )
    .expect("write");
    let out = ecdrive(&["run", "-c", &file.display().to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.code, Some(4), "{}", out.stderr);
    assert_eq!(out.stderr.lines().count(), 1, "{}", out.stderr);
    assert!(
        out.stderr.contains("node 3")
            && out.stderr.contains("0x6065")
            && out.stderr.contains("SDO abort"),
        "{}",
        out.stderr
    );
    // The touch probe only where the drive has one (60B8h): the BLV-R does, the ASDA-A2 not.
    let e = config::parse_any(
        "interface = \"can-sim\"\n[[drive]]\nnode = 0x7F\nprofile = \"asda-a2\"\n\
         program = [{ step = \"touch_probe\", probe = 1, edge = \"rising\" }]\n",
        "can.toml",
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("drive[0].program[0]"), "{e}");
    assert!(
        e.to_string()
            .contains("the ASDA-A2 has no touch probe (60B8h)"),
        "{e}"
    );
    // ip: only where the drive has it, at a SYNC period its 60C2h:01 takes, never on EtherCAT.
    let e = config::parse_any(&format!("{base}mode = \"ip\"\n"), "can.toml").unwrap_err();
    assert!(
        e.to_string().contains("the BLV-R does not support ip"),
        "{e}"
    );
    let e = config::parse_any(
        "interface = \"can-sim\"\ncycle = \"2500us\"\n[[drive]]\nnode = 0x7F\nprofile = \"asda-a2\"\nmode = \"ip\"\n",
        "can.toml",
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("cycle"), "{e}");
    assert!(
        e.to_string().contains("60C2h:01 milliseconds, 1–20 ms"),
        "{e}"
    );
    let e = config::parse_any(
        "interface = \"sim\"\n[sim]\ndevices = [\"bdhde\"]\n[[drive]]\nposition = 0\nmode = \"ip\"\n",
        "ethercat.toml",
    )
    .unwrap_err();
    assert!(e.to_string().contains("ip is run on CANopen drives"), "{e}");
    let e = config::parse_any(
        "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"mr-j4-tm\"\n",
        "can.toml",
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("blv-r, asda-a2, lexium-mdrive"),
        "{e}"
    );
    let e = config::parse_any(
        "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n[[drive]]\nnode = 3\nprofile = \"asda-a2\"\n",
        "can.toml",
    )
    .unwrap_err();
    assert!(e.to_string().contains("node 3 is drive[0] too"), "{e}");
    let e = config::parse_any(
        "interface = \"can-sim\"\n[sim]\ndevices = [\"bdhde\"]\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n",
        "can.toml",
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("sim"), "{e}");
    // An EtherCAT tool given a CANopen file says what it is.
    let e = config::parse(base, "can.toml").unwrap_err();
    assert!(e.message.contains("is a CANopen bus"), "{e}");
}

/// A fault latched before the run (an earlier run's, the drive's own): the run refuses, naming
/// the drive, its error code and its EMCY decoded with the drive's alarm table; with
/// `reset_faults = true` it resets the fault and runs.
#[test]
fn a_latched_fault_is_named_or_reset_as_the_file_says() {
    use ecdrive_cli::app::ethercat::tools::run::Outcome;
    let text = "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n\
                program = [{ step = \"pp\", to = [36000], velocity = 360000, acceleration = 3600000 }]\n";
    for reset in [false, true] {
        let cfg = can(&if reset {
            format!("reset_faults = true\n{text}")
        } else {
            text.to_string()
        });
        let mut bus = ecdrive_cli::app::canopen::run::emulated_bus(&cfg).expect("bus");
        let p = &ecdrive::drives::blv_r::PROFILE;
        let alarm = ecdrive_cli::app::canopen::demo::demo_alarm(p).expect("an alarm");
        assert!(bus.node_mut(3).expect("node").inject_alarm(alarm));
        let stop = std::sync::atomic::AtomicBool::new(false);
        let r = ecdrive_cli::app::canopen::run::run_on(bus, &cfg, None, None, &stop).expect("run");
        if reset {
            assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
            assert_eq!(r.drives[0].position, 36_000);
        } else {
            assert_eq!(r.outcome, Outcome::Refused, "{}", r.reason);
            assert!(
                r.reason
                    .contains("node 3 (BLV-R) is in Fault, error code 0x"),
                "{}",
                r.reason
            );
            assert!(r.reason.contains("reset_faults = true"), "{}", r.reason);
            // The EMCY decoded with the BLV-R's alarm table (alarm 30h, overload).
            assert!(r.reason.contains("alarm 30h overload"), "{}", r.reason);
            assert!(
                !r.drives[0].states.iter().any(|s| s == "Operation enabled"),
                "{r:?}"
            );
        }
    }
}
