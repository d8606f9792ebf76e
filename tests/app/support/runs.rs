//! Runs of the examples through `ecdrive run` in-process, and their recordings.

// Each test file uses the part it needs.
#![allow(dead_code)]

/// `examples/NAME` as written, with the emulated drives' loss supervision off (`loss_detection =
/// false` after its `devices = …` line): a host stall on a loaded machine is not what these
/// tests are about.
pub fn example_without_loss_detection(name: &str) -> String {
    let path = format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut out = String::with_capacity(text.len() + 24);
    for line in text.lines() {
        out.push_str(line);
        out.push('\n');
        if line.starts_with("devices = ") {
            out.push_str("loss_detection = false\n");
        }
    }
    out
}

/// Run configuration `text` in-process as `ecdrive run --record` does (`name` names its
/// temporary folder); the report and, per axis, every recorded cycle.
pub fn run_recorded(
    text: &str,
    name: &str,
) -> (
    ecdrive_cli::app::ethercat::tools::run::RunReport,
    Vec<Vec<Rec>>,
) {
    use ecdrive_cli::app::ethercat::tools::run::{RunOptions, run};
    let dir = std::env::temp_dir().join(format!("ecdrive-runs-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = ecdrive_cli::app::config::parse(text, &format!("{name}.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let file = dir.join("run.csv");
    let opts = RunOptions {
        record: Some(file.clone()),
        ..RunOptions::default()
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = run(&cfg, &opts, &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let rec = recording(&std::fs::read_to_string(&file).unwrap(), cfg.drives.len());
    let _ = std::fs::remove_dir_all(&dir);
    (r, rec)
}

/// One recorded cycle of one axis (`run --record`).
#[derive(Debug, Clone, Copy)]
pub struct Rec {
    /// When the cycle woke, s from the first recorded cycle (the host's monotonic clock).
    pub time_s: f64,
    /// Velocity demand sent (0x60FF), the drive's unit (csv and pv only).
    pub velocity_demand: Option<i64>,
    /// Demand position, counts (csp only).
    pub demand: Option<i64>,
    /// Actual position, counts.
    pub actual: i64,
    /// Actual velocity, the drive's unit.
    pub velocity: i64,
    /// Actual torque, the drive's unit.
    pub torque: i64,
    /// 0x6061.
    pub mode: i8,
}

/// Per axis, the recorded cycles in order.
pub fn recording(csv: &str, axes: usize) -> Vec<Vec<Rec>> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::trim)
        .collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (time, vel_demand) = (col("time_s"), col("velocity_demand_drive_units"));
    let (axis, demand, actual, vel, tq, mode) = (
        col("axis"),
        col("demand_counts"),
        col("actual_counts"),
        col("velocity_drive_units"),
        col("torque_drive_units"),
        col("mode"),
    );
    let mut out = vec![Vec::new(); axes];
    for l in lines {
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        let a: usize = f[axis].parse().unwrap();
        out[a].push(Rec {
            time_s: f[time].parse().unwrap(),
            velocity_demand: (!f[vel_demand].is_empty()).then(|| f[vel_demand].parse().unwrap()),
            demand: (!f[demand].is_empty()).then(|| f[demand].parse().unwrap()),
            actual: f[actual].parse().unwrap(),
            velocity: f[vel].parse().unwrap(),
            torque: f[tq].parse().unwrap(),
            mode: f[mode].parse().unwrap(),
        });
    }
    out
}
