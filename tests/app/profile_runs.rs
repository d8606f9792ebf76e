//! Profile position, profile velocity, profile torque and the touch probe in a program, through
//! the master, on both emulated EtherCAT drives, as `ecdrive run` runs them.
//!
//! The MR-J4-TM runs pp/pv/tq only with [Pr. PA01] = ___2 (MR-J4-TM manual §5.4.1 table: "___2:
//! Profile mode" allows pp, pv, tq and hm, not csp/csv/cst), so it is emulated with 0x2001 = 2
//! stored (`mr-j4-tm@0x2001=2`) and starts in pp; the BDHDE has every mode at once and mixes
//! csp with them. What is checked comes from the recording (every cycle's actual position,
//! velocity and torque as the drive reported them), the run report, and the machine the
//! emulated drives sit on (its probe input 1 switches on at +1.3 rev,
//! [`ecdrive::sim::machine::World`]), never from the master's own constants.

use crate::support::runs;
use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, RunReport, run};
use runs::{Rec, example_without_loss_detection, run_recorded};
use std::sync::atomic::AtomicBool;

/// Counts per revolution: MR-J4-TM 4 194 304 (22-bit encoder), BDHDE 2^20.
const MR_CPR: f64 = 4_194_304.0;
const BD_CPR: f64 = 1_048_576.0;

/// `examples/profile_modes.toml` (the MR-J4-TM in profile mode, the BDHDE from csp through
/// every profile mode back to csp; each arms touch probe 1 on the rising edge and crosses the
/// probe input on the way), without loss supervision.
fn example() -> String {
    example_without_loss_detection("profile_modes.toml")
}

fn run_config(text: &str, name: &str) -> (RunReport, Vec<Vec<Rec>>) {
    run_recorded(text, &format!("profile-{name}"))
}

/// The cycles of the `k`-th stretch (0-based) in mode `mode` (0x6061).
fn stretch(rec: &[Rec], mode: i8, k: usize) -> Vec<Rec> {
    let mut runs: Vec<Vec<Rec>> = Vec::new();
    let mut prev = None;
    for r in rec {
        if r.mode == mode {
            if prev != Some(mode) {
                runs.push(Vec::new());
            }
            if let Some(last) = runs.last_mut() {
                last.push(*r);
            }
        }
        prev = Some(r.mode);
    }
    runs.get(k)
        .cloned()
        .unwrap_or_else(|| panic!("no stretch {k} in mode {mode}"))
}

#[test]
fn pp_pv_tq_and_the_touch_probe_run_on_both_drives() {
    let (r, rec) = run_config(&example(), "all");
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    // Per drive: its pp targets (rev), its pv velocity (rev/s) and time. The MR-J4-TM's pp
    // targets stay within the ±999999 pulses its manual allows in pp (§7.3.12 (1)).
    let cases = [
        ("MR-J4-TM", MR_CPR, 0usize, [0.2, -0.1, 0.1], 2.0, 0.75),
        ("BDHDE", BD_CPR, 1usize, [3.0, 4.5, 1.0], -2.0, 0.5),
    ];
    for (name, cpr, a, targets, pv_velocity, pv_seconds) in cases {
        let d = &r.drives[a];
        assert_eq!(d.name, name);
        assert_eq!(d.steps_done, d.program.len(), "{name}: {:?}", d.errors);
        assert!(d.errors.is_empty(), "{name}: {:?}", d.errors);
        let rec = &rec[a];

        // pp, a set of set-points (controlword bit 5 = 0): each target in turn. The drive
        // stops at each one (BDHDE §5.7 "The movement is stopped at the current target
        // position"; MR-J4-TM §5.4.6 (5) "After the current positioning operation is
        // completed, the next positioning is started"); the motor passes within 1/1 000 rev
        // of the intermediate ones and stands on the last (to the count). How close it passes
        // is the motor's lag behind the drive's demand where the demand turns back at once,
        // which grows with a late cycle on a loaded machine (620 counts, 0.0006 rev, once in
        // CI; 1/10 000 rev unloaded): the targets are 0.2 rev apart and more.
        let pp = stretch(rec, 1, 0);
        let mut from = 0;
        for (k, target_rev) in targets.into_iter().enumerate() {
            let target = (target_rev * cpr).round() as i64;
            let (at, closest) = pp[from..]
                .iter()
                .enumerate()
                .map(|(i, x)| (from + i, (x.actual - target).abs()))
                .min_by_key(|&(_, d)| d)
                .unwrap();
            assert!(
                closest as f64 <= cpr / 1_000.0,
                "{name}: pp target {k} ({target_rev} rev) missed by {closest} counts"
            );
            from = at;
        }
        let last = pp.last().unwrap();
        let last_target = (targets[2] * cpr).round() as i64;
        assert!(
            (last.actual - last_target).abs() <= 1,
            "{name}: pp ended at {} counts, not on its last target {last_target}",
            last.actual,
        );

        // pv: the master holds the target velocity v for t s of its cycles (BDHDE −2 rev/s for
        // 0.5 s, MR-J4-TM +2 rev/s for 0.75 s), then sends 0 and waits for standstill before
        // the next mode. With equal ramps up and down the drive travels v × the time it held
        // v: v·t rev on an unloaded host (−1 rev, +1.5 rev). The drive runs on its own clock
        // and the master's cycles are what a stalled host skips (a stall of 29 ms made the
        // BDHDE's −1.058 rev once), so the time is the wall clock's between the cycle that
        // first sent v and the one that first sent something else, each as it woke; the
        // drive takes either at the SYNC0 after it, so the two ends shift alike. The velocity
        // the drive reports reaches v on the way.
        let pv = stretch(rec, 3, 0);
        let travel = (pv.last().unwrap().actual - pv.first().unwrap().actual) as f64 / cpr;
        let v_sent = pv
            .iter()
            .filter_map(|x| x.velocity_demand)
            .max_by_key(|v| v.abs())
            .unwrap();
        let from = pv
            .iter()
            .position(|x| x.velocity_demand == Some(v_sent))
            .unwrap();
        let to = from
            + pv[from..]
                .iter()
                .position(|x| x.velocity_demand != Some(v_sent))
                .unwrap();
        let cycles = (to - from) as f64;
        assert!(
            (cycles - pv_seconds * 1000.0).abs() <= 2.0,
            "{name}: pv held for {cycles} cycles of 1 ms, not {pv_seconds} s"
        );
        let held_s = pv[to].time_s - pv[from].time_s;
        let want_travel = pv_velocity * held_s;
        assert!(
            (travel - want_travel).abs() < 0.01 * want_travel.abs(),
            "{name}: pv travelled {travel} rev in {held_s} s at {pv_velocity} rev/s, not \
             {want_travel} rev"
        );
        let fastest = pv
            .iter()
            .map(|x| x.velocity)
            .max_by_key(|v| v.abs())
            .unwrap();
        // The drives' velocity units: MR-J4-TM 0.01 r/min (§7.3.10 (7)), BDHDE counts/s.
        let want = if a == 0 {
            pv_velocity * 6000.0
        } else {
            pv_velocity * cpr
        };
        assert!(
            (fastest as f64 - want).abs() <= want.abs() * 0.01,
            "{name}: pv peaked at {fastest}, the target is {want}"
        );

        // tq: the torque the drive reports reaches the target (50 in the drive's torque unit,
        // ‰ of the rated torque on both) and goes back to 0.
        let tq = stretch(rec, 4, 0);
        let peak = tq.iter().map(|x| x.torque).max().unwrap();
        assert!((45..=55).contains(&peak), "{name}: tq peaked at {peak}");
        assert!(
            tq.last().unwrap().torque.abs() <= 2,
            "{name}: tq ended at {}",
            tq.last().unwrap().torque
        );

        // The touch probe: the drive's latch of the probe input's rising edge, as the master
        // reports it, within one count of where the machine has the edge (+1.3 rev).
        let edge = ecdrive::sim::machine::World::default()
            .probe1_rev
            .unwrap()
            .0;
        let latches = &d.probe_latches;
        assert_eq!(latches.len(), 1, "{name}: {latches:?}");
        let l = &latches[0];
        assert_eq!((l.probe, l.edge), (1, "rising"));
        assert!(
            (l.counts as f64 - edge * cpr).abs() <= 1.0,
            "{name}: latched at {} counts, the edge is at {} counts",
            l.counts,
            edge * cpr
        );
        assert!((l.value.unwrap() - edge).abs() <= 1.0 / cpr);
    }
    // The MR-J4-TM's last pp: single set-points (bit 5 = 1), each relative to the last
    // target and handed over once the one before is reached: +0.2 then +0.1 rev.
    let pp = stretch(&rec[0], 1, 1);
    let start = pp.first().unwrap().actual;
    let end = pp.last().unwrap().actual;
    assert!(
        ((end - start) as f64 / MR_CPR - 0.3).abs() <= 2.0 / MR_CPR,
        "MR-J4-TM: the relative pp moved {} counts",
        end - start
    );
    let mid = (start as f64 + 0.2 * MR_CPR) as i64;
    assert!(
        pp.iter().any(|x| (x.actual - mid).abs() <= 100),
        "MR-J4-TM: the relative pp did not stop at +0.2 rev"
    );
    // The modes as the drives displayed them, in order.
    assert_eq!(r.drives[0].modes_run, ["pp", "pv", "tq", "pv", "pp"]);
    assert_eq!(
        r.drives[1].modes_run,
        ["csp", "pp", "pv", "tq", "pv", "csp"]
    );
}

/// Without [Pr. PA01] = ___2 the MR-J4-TM refuses the profile modes (§5.4.1): start-up reads
/// 0x2001 and says so before anything is enabled, naming the parameter, what it allows and the
/// setting that would do.
#[test]
fn the_mr_j4_tm_without_profile_mode_refuses_a_pp_program_by_name() {
    let text = example().replace("mr-j4-tm@0x2001=2", "mr-j4-tm");
    let cfg = ecdrive_cli::app::config::parse(&text, "profile.toml").unwrap();
    let stop = AtomicBool::new(false);
    let e = run(&cfg, &RunOptions::default(), &stop, &mut |_| {})
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    for part in [
        "drive 0 (MR-J4-TM)",
        "the program runs pp",
        "[Pr. PA01] Operation mode (0x2001:00) = 0x0000",
        "allows hm, csp, csv, cst",
        "\"___2: Profile mode\"",
        "power-cycle",
    ] {
        assert!(e.contains(part), "{part:?} not in: {e}");
    }
    // One setting for pp and csp does not exist: the message says so.
    let text = example().replace("\nmode = \"pp\"\n", "\nmode = \"csp\"\n").replace(
        "  { step = \"touch_probe\", probe = 1, edge = \"rising\" },\n  { step = \"pp\", to = [0.2",
        "  { step = \"touch_probe\", probe = 1, edge = \"rising\" },\n  { step = \"mode\", mode = \"pp\" },\n  { step = \"pp\", to = [0.2",
    );
    // The emulated drive's name stores [Pr. PA01] = 2: the file check says it already (a
    // drive on a bus: start-up, as above).
    let e = match ecdrive_cli::app::config::parse(&text, "profile.toml") {
        Err(e) => e.to_string(),
        Ok(cfg) => run(&cfg, &RunOptions::default(), &stop, &mut |_| {})
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default(),
    };
    assert!(e.contains("no one setting allows all of"), "{e}");
}

/// The touch probe's objects: the BDHDE's recommended mapping has one TxPDO of at most 8
/// entries (its manual, chapter 7), so arming a probe gives the probe status and latch the
/// places of inputs the cycle can do without; a mapping of the user's that lacks them is
/// refused, naming the object and the direction.
#[test]
fn touch_probe_objects_are_chosen_or_required() {
    let text = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["bdhde"]
loss_detection = false
[[drive]]
position = 0
mode = "csp"
mapping = { rx = [{ pdo = 0x1600, entries = ["0x6040:00", "0x607A:00"] }], tx = [{ pdo = 0x1A00, entries = ["0x6041:00", "0x6064:00", "0x60B9:00"] }] }
program = [
  { step = "touch_probe", probe = 2, edge = "falling" },
  { step = "move", by = 100000, velocity = 100000, acceleration = 1000000 },
]
"#;
    let e = ecdrive_cli::app::config::parse(text, "probe.toml")
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("0x60B8:00"), "{e}");
    assert!(e.contains("touch probe 2 (falling edge)"), "{e}");
}

/// A probe armed again latches again: its function bits go 0 for one cycle so the drive clears
/// what it stored (the emulated drive, like CiA 402 drives, latches once per arming in
/// first-event mode). Probe 2 on the falling edge as well: the machine's input 2 is on from
/// −1.6 to −1.2 rev, so moving down through it, the falling edge is at −1.6 rev.
#[test]
fn a_probe_armed_again_latches_again() {
    let text = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["bdhde"]
loss_detection = false
[[drive]]
position = 0
mode = "csp"
units = { name = "rev", counts_per_unit = 1048576 }
program = [
  { step = "touch_probe", probe = 1, edge = "rising" },
  { step = "move", to = 2, velocity = 4, acceleration = 40 },
  { step = "move", to = 0, velocity = 4, acceleration = 40 },
  { step = "touch_probe", probe = 1, edge = "rising" },
  { step = "touch_probe", probe = 2, edge = "falling" },
  { step = "move", to = 2, velocity = 4, acceleration = 40 },
  { step = "move", to = -2, velocity = 4, acceleration = 40 },
]
"#;
    let (r, _) = run_config(text, "rearm");
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    let world = ecdrive::sim::machine::World::default();
    let p1 = world.probe1_rev.unwrap().0 * BD_CPR;
    let p2 = world.probe2_rev.unwrap().0 * BD_CPR;
    let got: Vec<(u8, &str, i64)> = r.drives[0]
        .probe_latches
        .iter()
        .map(|l| (l.probe, l.edge, l.counts))
        .collect();
    assert_eq!(got.len(), 3, "{got:?}");
    for (k, (probe, edge, at)) in [(1, "rising", p1), (1, "rising", p1), (2, "falling", p2)]
        .into_iter()
        .enumerate()
    {
        assert_eq!((got[k].0, got[k].1), (probe, edge), "{got:?}");
        assert!(
            (got[k].2 as f64 - at).abs() <= 1.0,
            "{got:?}: latch {k} not at {at}"
        );
    }
}

/// A search for a mark in csv: the probe armed, a ramp to 1 rev/s, a `probe_wait` that keeps
/// that velocity until the latch, then a ramp to standstill. The wait ends at the latch, not at
/// its 5 s: the axis stops within the ramp-down's distance (1²/(2·10) = 0.05 rev) plus a few
/// cycles after the edge the machine puts at +1.3 rev, where 5 s at 1 rev/s would be +5 rev.
/// The MR-J4-TM's wait, in csp after a move across the edge, finds its latch there already.
/// `examples/probe_search.toml` as written, without loss supervision.
#[test]
fn a_probe_wait_searches_for_the_mark_and_ends_at_the_latch() {
    let text = example_without_loss_detection("probe_search.toml");
    let (r, rec) = run_config(&text, "search");
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    let edge = ecdrive::sim::machine::World::default()
        .probe1_rev
        .unwrap()
        .0;
    for (a, cpr) in [(0usize, MR_CPR), (1, BD_CPR)] {
        let d = &r.drives[a];
        assert_eq!(d.steps_done, d.program.len(), "{}: {:?}", d.name, d.errors);
        let l = d.probe_latches.first().expect("a latch");
        assert!(
            (l.counts as f64 - edge * cpr).abs() <= 1.0,
            "{}: latched at {} counts, the edge is at {} counts",
            d.name,
            l.counts,
            edge * cpr
        );
    }
    // The BDHDE stands where the search stopped it: past the edge by at most the ramp-down's
    // 0.05 rev and 10 cycles at 1 rev/s.
    let end = rec[1].last().unwrap().actual as f64 / BD_CPR;
    assert!(
        end > edge && end < edge + 0.05 + 0.01,
        "BDHDE: stopped at {end} rev; the edge is at {edge} rev"
    );
    // The MR-J4-TM went back to 0 after its wait.
    assert!(
        rec[0].last().unwrap().actual.abs() <= 1,
        "MR-J4-TM did not return"
    );
}

/// A `probe_wait` without its latch ends the run after its time, naming the drive and the
/// probe, with the axes disabled; a wait for a probe no step arms is refused by the
/// configuration, naming the step.
#[test]
fn a_probe_wait_without_a_latch_stops_the_run_by_name() {
    let text = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["bdhde"]
loss_detection = false
[[drive]]
position = 0
mode = "csp"
units = { name = "rev", counts_per_unit = 1048576 }
program = [
  { step = "touch_probe", probe = 2, edge = "falling" },
  { step = "move", to = 0.5, velocity = 4, acceleration = 40 },
  { step = "probe_wait", probe = 2, seconds = 0.3 },
  { step = "move", to = 0, velocity = 4, acceleration = 40 },
]
"#;
    let (r, _) = run_config(text, "nolatch");
    assert_eq!(r.outcome, Outcome::DriveFault, "{}", r.reason);
    for want in ["BDHDE", "touch probe 2", "0.3 s"] {
        assert!(r.reason.contains(want), "{want:?} not in {:?}", r.reason);
    }
    let d = &r.drives[0];
    assert_eq!(d.steps_done, 2, "{:?}", d.errors);
    assert!(d.probe_latches.is_empty());
    assert_eq!(
        d.states.last().map(String::as_str),
        Some("Switch on disabled"),
        "{:?}",
        d.states
    );

    let unarmed = text.replace(
        r#"{ step = "touch_probe", probe = 2, edge = "falling" },"#,
        "",
    );
    let Err(e) = ecdrive_cli::app::config::parse(&unarmed, "wait.toml") else {
        panic!("a wait for an unarmed probe was taken");
    };
    let e = e.to_string();
    for want in ["program[1]", "no earlier touch_probe step arms probe 2"] {
        assert!(e.contains(want), "{want:?} not in {e}");
    }
}

/// The MR-J4-TM takes −999999 to 999999 pos units in 0x607A in pp (manual §7.3.12 (1): "Profile
/// position mode (pp) … FFF0BDC1h to 000F423Fh (-999999 to 999999)"); with one encoder pulse per
/// pos unit that is ±0.238 rev. A target beyond it is refused before anything runs: by the
/// configuration, naming the step, and by start-up for a program built in code.
#[test]
fn a_pp_target_beyond_the_mr_j4_tm_range_is_refused_before_the_run() {
    let text = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["mr-j4-tm@0x2001=2"]
[[drive]]
position = 0
mode = "pp"
units = { name = "rev", counts_per_unit = 4194304 }
program = [
  { step = "pp", to = [0.2, 0.25], velocity = 5, acceleration = 50 },
]
"#;
    let Err(e) = ecdrive_cli::app::config::parse(text, "range.toml") else {
        panic!("0.25 rev = 1048576 pulses was taken");
    };
    let e = e.to_string();
    for want in [
        "program[0]",
        "0.25 rev (1048576 counts)",
        "§7.3.12 (1)",
        "999999",
    ] {
        assert!(e.contains(want), "{want:?} not in {e}");
    }
    // 0.2 rev = 838861 pulses is within.
    assert!(ecdrive_cli::app::config::parse(&text.replace("0.25", "0.2"), "range.toml").is_ok());

    use ecdrive::master::program::Step;
    use ecdrive::master::session::{Master, MasterConfig};
    use ecdrive::master::startup::{DriveSetup, Selector};
    let mut seg = ecdrive::sim::Segment::new(std::sync::Arc::new(ecdrive::sim::HostClock));
    seg.push(
        ecdrive::sim::devices::by_name("mr-j4-tm@0x2001=2", 0).unwrap(),
        ecdrive::sim::EscConfig::default(),
    )
    .unwrap();
    let mut cfg = MasterConfig::new(std::time::Duration::from_millis(1));
    cfg.startup.drives.push(DriveSetup {
        mode: ecdrive::master::RunMode::Pp,
        program: vec![Step::Pp {
            targets: vec![2_000_000.0],
            relative: true,
            immediate: false,
            velocity: 4_194_304.0,
            acceleration: 41_943_040.0,
            deceleration: None,
        }],
        ..DriveSetup::new(Selector::Position(0))
    });
    let Err(f) = Master::start(ecdrive::sim::transport::SegmentLink::new(seg), cfg) else {
        panic!("a relative pp step of 2000000 pulses was taken");
    };
    let e = f.error.to_string();
    for want in ["MR-J4-TM", "2000000 counts to 0x607A", "§7.3.12 (1)"] {
        assert!(e.contains(want), "{want:?} not in {e}");
    }
}

/// A relative pp move, then csp: the switch makes no jump. Over veth the BDHDE moved 8595
/// counts toward its relative pp target (−1.5 rev, taken as an absolute csp target) in the
/// frames before the master's first csp set-point; the engine now sends the actual position
/// from the first frame that names csp.
#[test]
fn csp_after_a_relative_pp_move_starts_where_the_axis_stands() {
    let text = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["bdhde"]
loss_detection = false
[[drive]]
position = 0
mode = "csp"
units = { name = "rev", counts_per_unit = 1048576 }
program = [
  { step = "mode", mode = "pp" },
  { step = "pp", to = [0.5, 1.5], velocity = 5, acceleration = 50 },
  { step = "pp", by = [-1.5], velocity = 5, acceleration = 50 },
  { step = "mode", mode = "csp" },
  { step = "dwell", seconds = 0.1 },
]
"#;
    let (r, rec) = run_config(text, "ppcsp");
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    let csp = stretch(&rec[0], 8, 1);
    let stand = csp.first().unwrap().actual;
    assert!(
        stand.abs() <= 1,
        "pp by −1.5 rev from 1.5 rev ended at {stand}"
    );
    let worst = csp.iter().map(|x| (x.actual - stand).abs()).max().unwrap();
    assert!(
        worst <= 2,
        "the axis moved {worst} counts after the switch to csp"
    );
}
