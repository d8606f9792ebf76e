//! `ecdrive run --record` and `ecdrive plot`, checked on the examples as docs/guide/run.md runs
//! them:
//! every column of the recording means what its header says in every mode (empty where it has
//! none; the following error's maximum is the summary's; the physical columns are the raw ones
//! in the manuals' units), and the SVG has a panel per drive and quantity titled by position
//! and drive, a legend, a band per mode, the latches marked.

use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, RunReport, run};
use ecdrive_cli::app::plot;
use std::collections::BTreeMap;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

fn polylines(svg: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .filter_map(|p| {
            let start = p.find("points=\"")? + 8;
            let end = start + p[start..].find('"')?;
            Some(p[start..end].split_whitespace().count())
        })
        .collect()
}

/// The texts of an SVG (legend entries, captions, tick labels), trimmed.
fn texts(svg: &str) -> Vec<&str> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let start = t.find('>')? + 1;
            let end = start + t[start..].find("</text>")?;
            Some(t[start..end].trim())
        })
        .collect()
}

/// Run `examples/NAME.toml` in-process with `--record` (for `duration` if given); the report
/// and the CSV's path.
fn record(
    name: &str,
    dir: &std::path::Path,
    duration: Option<Duration>,
) -> (RunReport, std::path::PathBuf) {
    let path = format!("{}/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let mut cfg = ecdrive_cli::app::config::load(std::path::Path::new(&path))
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    // The test machine is shared and the run not always real-time: as for the examples in
    // cli_examples.rs, the emulated drives do not supervise the cyclic data here (a stall of a
    // few cycles would fault them and end the run before the modes this test looks at).
    cfg.sim.loss_detection = false;
    let csv = dir.join(format!("{name}.csv"));
    let opts = RunOptions {
        record: Some(csv.clone()),
        duration,
        ..RunOptions::default()
    };
    let stop = AtomicBool::new(false);
    let r = run(&cfg, &opts, &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
    // A run cut short or a recording with gaps would make the checks below vacuous or wrong.
    assert_eq!(
        r.outcome,
        Outcome::Completed,
        "{name}: the run ended early: {}",
        r.reason
    );
    let rec = r.record.as_ref().expect("a recording was asked for");
    assert_eq!(
        rec.dropped, 0,
        "{name}: the recording dropped samples: {rec:?}"
    );
    (r, csv)
}

/// The CSV's rows as column name → cell.
fn rows(csv: &std::path::Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

fn num(r: &BTreeMap<String, String>, c: &str) -> Option<f64> {
    let v = &r[c];
    (!v.is_empty()).then(|| v.parse().unwrap_or_else(|_| panic!("{c} = {v:?}")))
}

#[test]
fn each_example_recording_is_drawn_by_position_and_drive_with_a_legend() {
    let dir = std::env::temp_dir().join(format!("ecdrive-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let examples = [
        "csp_move_sine",
        "csv_ramp",
        "cst_step",
        "mode_switch",
        "mixed_segment",
        "profile_modes",
    ];
    for name in examples {
        let (r, csv) = record(name, &dir, Some(Duration::from_millis(800)));
        let rec = plot::read(&csv).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(rec.axes.len(), r.drives.len(), "{name}: axes");
        let svg_path = dir.join(format!("{name}.svg"));
        plot::draw(&rec, &svg_path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        let texts = texts(&svg);
        for (a, d) in rec.axes.values().zip(&r.drives) {
            // Panels are named by the drive's position and name, not the axis index.
            assert_eq!(a.position, Some(d.position), "{name}");
            assert_eq!(a.drive, d.name, "{name}");
            for panel in plot::PANELS {
                let caption = format!("position {} ({}): {panel} (", d.position, d.name);
                assert_eq!(
                    svg.matches(&caption).count(),
                    1,
                    "{name}: panel {caption:?}"
                );
            }
            // User units where the run has them.
            if let Some(u) = &d.units {
                assert!(
                    svg.contains(&format!(": velocity ({}/s)", u.name)),
                    "{name}"
                );
            }
            assert!(svg.contains(": torque (% of rated torque)"), "{name}");
        }
        // A legend: demand and actual told apart, and every mode the run was in named.
        for label in ["demand", "actual"] {
            assert!(texts.contains(&label), "{name}: legend {label}");
        }
        for a in rec.axes.values() {
            for (code, mode, _) in plot::MODES {
                if a.mode.contains(&code) {
                    assert!(texts.contains(&mode), "{name}: band {mode}");
                }
            }
        }
        // The actual position is one series over every recorded cycle, per drive.
        let samples = rec.axes.values().map(|a| a.t.len()).min().unwrap_or(0);
        assert!(samples > 100, "{name}: {samples} samples");
        let full = polylines(&svg)
            .into_iter()
            .filter(|&n| n >= samples)
            .count();
        // Actual position, velocity and torque at least.
        assert!(
            full >= 3 * rec.axes.len(),
            "{name}: {full} full-length series"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The one-line statement of how the manuals express 0x606C and 0x6077: (counts per second
/// per velocity unit, per mille of rated torque per torque unit).
fn manual_units(drive: &str) -> (f64, f64) {
    match drive {
        // MR-J4-TM: velocity in 0.01 r/min, torque in 0.1 % (manual §5.4.3–§5.4.5), 4 194 304
        // pulses a revolution.
        "MR-J4-TM" => (4_194_304.0 / 60.0 * 0.01, 1.0),
        // BDHDE: velocity in position units per second (§6.3), torque in per mille of 0x6076
        // (§6.6).
        "BDHDE" => (1.0, 1.0),
        d => panic!("no manual units for {d}"),
    }
}

#[test]
fn every_column_means_what_its_header_says_in_every_mode() {
    let dir = std::env::temp_dir().join(format!("ecdrive-plot-cols-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // mode_switch: csp, csv, cst; profile_modes: pp, pv, tq, csp with touch probes.
    for name in ["mode_switch", "profile_modes"] {
        let (r, csv) = record(name, &dir, None);
        let rows = rows(&csv);
        let mut modes_seen = std::collections::BTreeSet::new();
        let mut max_fe: BTreeMap<usize, f64> = BTreeMap::new();
        let mut max_fe_units: BTreeMap<usize, f64> = BTreeMap::new();
        for row in &rows {
            let axis: usize = row["axis"].parse().unwrap();
            let d = &r.drives[axis];
            let sent = row["mode_sent"].parse::<i8>().unwrap();
            modes_seen.insert(sent);
            assert_eq!(row["position"], d.position.to_string(), "{name}");
            assert_eq!(row["drive"], d.name, "{name}");
            // A column is filled exactly in the modes where it has a meaning.
            let has = |c: &str| !row[c].is_empty();
            assert_eq!(has("demand_counts"), sent == 8, "{name} {row:?}");
            assert_eq!(
                has("velocity_demand_drive_units"),
                [3, 9].contains(&sent),
                "{row:?}"
            );
            assert_eq!(
                has("torque_demand_drive_units"),
                [4, 10].contains(&sent),
                "{row:?}"
            );
            if has("following_error_counts") {
                assert_eq!(sent, 8, "{name}: a following error outside csp: {row:?}");
                let fe = num(row, "following_error_counts").unwrap();
                let m = max_fe.entry(axis).or_default();
                *m = m.max(fe.abs());
                let m = max_fe_units.entry(axis).or_default();
                *m = m.max(num(row, "following_error").unwrap().abs());
            }
            // The physical columns are the raw ones in the manuals' units and the file's.
            let u = d.units.as_ref().expect("the examples give units");
            assert_eq!(row["unit"], u.name);
            let (vel_counts, tq_per_mille) = manual_units(&d.name);
            let close = |a: f64, b: f64, what: &str| {
                assert!(
                    (a - b).abs() <= 1e-6 * b.abs().max(1.0),
                    "{name}: {what}: {a} against {b} ({row:?})"
                )
            };
            close(
                num(row, "actual").unwrap(),
                num(row, "actual_counts").unwrap() / u.counts_per_unit,
                "actual",
            );
            close(
                num(row, "velocity_per_s").unwrap(),
                num(row, "velocity_drive_units").unwrap() * vel_counts / u.counts_per_unit,
                "velocity",
            );
            close(
                num(row, "torque_percent").unwrap(),
                num(row, "torque_drive_units").unwrap() * tq_per_mille / 10.0,
                "torque",
            );
            for p in ["probe1", "probe2"] {
                let raw = num(row, &format!("{p}_counts"));
                assert_eq!(raw.is_some(), num(row, p).is_some());
                if let Some(raw) = raw {
                    close(num(row, p).unwrap(), raw / u.counts_per_unit, p);
                }
            }
        }
        // The CSV's largest |following error| is the summary's, in counts and in units.
        for (i, d) in r.drives.iter().enumerate() {
            let csv_max = max_fe.get(&i).copied().unwrap_or(0.0);
            assert_eq!(csv_max, d.max_following_error as f64, "{name}: drive {i}");
            if let Some(m) = d.max_following_error_units {
                let u = max_fe_units.get(&i).copied().unwrap_or(0.0);
                assert!(
                    (u - m).abs() <= 1e-5 * m.max(1.0),
                    "{name}: {u} against {m}"
                );
            }
        }
        // Each latch of the run is in the CSV from its cycle on.
        for (i, d) in r.drives.iter().enumerate() {
            for l in &d.probe_latches {
                let col = format!("probe{}_counts", l.probe);
                assert!(
                    rows.iter().any(|row| row["axis"] == i.to_string()
                        && num(row, &col) == Some(l.counts as f64)),
                    "{name}: drive {i}'s latch at {} counts is not in {col}",
                    l.counts
                );
            }
        }
        let want: &[i8] = if name == "mode_switch" {
            &[8, 9, 10]
        } else {
            &[1, 3, 4, 8]
        };
        for m in want {
            assert!(modes_seen.contains(m), "{name}: mode {m} never recorded");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn touch_probe_latches_are_marked_on_the_position() {
    let dir = std::env::temp_dir().join(format!("ecdrive-plot-probe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (r, csv) = record("profile_modes", &dir, None);
    let latched: usize = r.drives.iter().map(|d| d.probe_latches.len()).sum();
    assert!(latched > 0, "the example latches: {:?}", r.reason);
    let rec = plot::read(&csv).unwrap();
    let marks: usize = rec.axes.values().map(|a| a.latches.len()).sum();
    assert_eq!(marks, latched, "one mark per latch of the run");
    for (a, d) in rec.axes.values().zip(&r.drives) {
        let k = d.units.as_ref().unwrap().counts_per_unit;
        for (m, l) in a.latches.iter().zip(&d.probe_latches) {
            assert_eq!(m.1, l.probe);
            assert!(
                (m.2 - l.counts as f64 / k).abs() < 1e-6,
                "{m:?} against {l:?}"
            );
        }
    }
    let svg_path = dir.join("probe.svg");
    plot::draw(&rec, &svg_path).unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(texts(&svg).contains(&"probe 1 latch"), "legend");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_file_that_is_not_a_recording_is_named_with_the_line() {
    let dir = std::env::temp_dir().join(format!("ecdrive-plot-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("bad.csv");
    std::fs::write(&f, format!("{}\n1,0.1,0,x\n", ecdrive::master::CSV_HEADER)).unwrap();
    let e = plot::read(&f).unwrap_err().to_string();
    assert!(e.ends_with("bad.csv:2: mode is not a number"), "{e}");
    std::fs::write(&f, "a,b\n").unwrap();
    let e = plot::read(&f).unwrap_err().to_string();
    assert!(e.contains("no column time_s"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
