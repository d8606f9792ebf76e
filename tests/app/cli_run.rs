//! `ecdrive run` against the generic CoE test device in-process, with the generic CiA 402
//! profile the file asks for: the run itself, and a drive refusing its configuration.

use crate::support;
use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
use std::sync::atomic::AtomicBool;
use support::cli::ecdrive;

const GENERIC: &str = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["generic-coe"]
[[drive]]
position = 0
profile = "generic-cia402"
mode = "csp"
limits = { following_error = 5000 }
program = [
  { step = "move", by = 1000, velocity = 20000, acceleration = 200000 },
  { step = "dwell", seconds = 0.05 },
]
[drive.mapping]
rx = [{ pdo = 0x1600, entries = ["0x6040:00", "0x607A:00"] }]
tx = [{ pdo = 0x1A00, entries = ["0x6041:00", "0x6064:00"] }]
"#;

#[test]
fn the_generic_device_runs_a_program_and_reports_it() {
    let cfg = ecdrive_cli::app::config::parse(GENERIC, "generic.toml").unwrap();
    let stop = AtomicBool::new(false);
    let mut phases = Vec::new();
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |p| {
        if phases.last() != Some(&p.phase) {
            phases.push(p.phase);
        }
    })
    .unwrap();
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    assert_eq!(r.reason, "every program finished");
    assert_eq!(
        phases,
        [
            "starting",
            "waiting for OP",
            "checking for faults",
            "enabling",
            "running",
            "stopping"
        ]
    );
    let d = &r.drives[0];
    assert_eq!(d.name, "generic CiA 402 drive");
    assert_eq!(d.device.name, "ECD-COE402");
    assert_eq!(d.steps_done, 2);
    assert_eq!(d.modes_run, ["csp"]);
    // The drive leaves Not ready to switch on by itself (CiA 402); which of the two the first
    // cycle in OP sees depends on how long SAFE-OP took.
    assert!(
        matches!(
            d.states.first().map(String::as_str),
            Some("Not ready to switch on" | "Switch on disabled")
        ),
        "{:?}",
        d.states
    );
    assert!(
        d.states.iter().any(|s| s == "Operation enabled"),
        "{:?}",
        d.states
    );
    assert_eq!(
        d.states.last().map(String::as_str),
        Some("Switch on disabled")
    );
    assert!(d.errors.is_empty(), "{:?}", d.errors);
    assert!(r.shutdown_ok);
    let c = r.cycle.unwrap();
    assert!(c.cycles > 100);
    // The period is measured (its values are the machine's: no timing is asserted here; the
    // jitter harness and benches/ are where timing is judged).
    assert!(c.period.count > 0, "{:?}", c.period);
}

#[test]
fn a_refused_configuration_is_exit_4_naming_the_object() {
    let dir = std::env::temp_dir().join(format!("ecdrive-cli-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A mapping with 0x6071, which the test device cannot map.
    let f = dir.join("refused.toml");
    std::fs::write(
        &f,
        "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\"]\n[[drive]]\nposition = 0\nprofile = \"generic-cia402\"\n\
         [drive.mapping]\nrx = [{ pdo = 0x1600, entries = [\"0x6040:00\", \"0x607A:00\", \"0x60FF:00\", \"0x6071:00\"] }]\n\
         tx = [{ pdo = 0x1A00, entries = [\"0x6041:00\", \"0x6064:00\"] }]\n",
    )
    .unwrap();
    ecdrive(&["run", "-c", &f.display().to_string()]).fails(
        4,
        &[
            "drive 0 (generic CiA 402 drive)",
            "0x1600:04",
            "0x06040041",
            "cannot be mapped",
        ],
    );
    // The good file through the binary, as JSON.
    let g = dir.join("generic.toml");
    std::fs::write(&g, GENERIC).unwrap();
    let j = ecdrive(&["run", "-c", &g.display().to_string(), "--json"]).json();
    assert_eq!(j["outcome"], "completed");
    assert_eq!(j["drives"][0]["steps_done"], 2);
    let _ = std::fs::remove_dir_all(&dir);
}
