//! `ecdrive run` in-process: configuration files run against emulated devices, and the
//! configuration errors a user meets.

mod support {
    pub mod generic;
}
use ecdrive::master::tools::run::{Outcome, RunOptions, run};
use std::sync::atomic::AtomicBool;
use support::generic::GENERIC_TEST;

#[test]
fn generic_device_runs_a_csp_program() {
    let text = r#"
interface = "sim"
cycle = "1ms"
[sim]
devices = ["generic-coe"]
sm_watchdog = 0
[[drive]]
position = 0
mode = "csp"
program = [
  { step = "move", by = 1000, velocity = 20000, acceleration = 200000 },
  { step = "dwell", seconds = 0.05 },
]
"#;
    let mut cfg = ecdrive::config::parse(text, "test.toml").unwrap();
    cfg.master.startup.drives[0].profile = Some(&GENERIC_TEST);
    let stop = AtomicBool::new(false);
    let mut seen = Vec::new();
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |p| {
        seen.push(p.phase)
    })
    .unwrap();
    println!("{}", serde_json::to_string_pretty(&r).unwrap());
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
}
