//! `ecdrive plot`: a recording of each example configuration that runs in-process is drawn,
//! and the SVG is checked for its structure: one panel per axis and quantity, and for each
//! axis five series (demand, actual, following error, velocity, torque) with a point per
//! recorded cycle.

use ecdrive::app::ethercat::tools::run::{RunOptions, run};
use ecdrive::app::plot;
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

#[test]
fn each_example_recording_is_drawn_one_panel_per_axis_and_quantity() {
    let dir = std::env::temp_dir().join(format!("ecdrive-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let examples = [
        "csp_move_sine",
        "csv_ramp",
        "cst_step",
        "mode_switch",
        "mixed_segment",
    ];
    for name in examples {
        let path = format!("{}/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let cfg = ecdrive::app::config::load(std::path::Path::new(&path))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let csv = dir.join(format!("{name}.csv"));
        let opts = RunOptions {
            record: Some(csv.clone()),
            duration: Some(Duration::from_millis(800)),
            ..RunOptions::default()
        };
        let stop = AtomicBool::new(false);
        let r = run(&cfg, &opts, &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        let rec = plot::read(&csv).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(rec.axes.len(), r.drives.len(), "{name}: axes");
        let svg_path = dir.join(format!("{name}.svg"));
        plot::draw(&rec, &svg_path, &plot::units_of(&cfg))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        for axis in rec.axes.keys() {
            for panel in plot::PANELS {
                let caption = format!("axis {axis}: {}", panel.split(" (").next().unwrap());
                assert_eq!(
                    svg.matches(&caption).count(),
                    1,
                    "{name}: panel {caption:?}"
                );
            }
        }
        let samples = rec.axes.values().map(|a| a.t.len()).min().unwrap_or(0);
        assert!(samples > 100, "{name}: {samples} samples");
        let series = polylines(&svg)
            .into_iter()
            .filter(|&n| n >= samples)
            .count();
        assert_eq!(series, 5 * rec.axes.len(), "{name}: data series");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_file_that_is_not_a_recording_is_named_with_the_line() {
    let dir = std::env::temp_dir().join(format!("ecdrive-plot-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("bad.csv");
    std::fs::write(&f, format!("{}\n1,0.1,0,x\n", ecdrive::master::CSV_HEADER)).unwrap();
    let e = plot::read(&f).unwrap_err().to_string();
    assert!(
        e.ends_with("bad.csv:2: demand_counts is not a number"),
        "{e}"
    );
    std::fs::write(&f, "a,b\n").unwrap();
    let e = plot::read(&f).unwrap_err().to_string();
    assert!(e.contains("no column time_s"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
