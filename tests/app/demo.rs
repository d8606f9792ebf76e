//! The demo's library path: both emulated drives reach OP with DC, run csp, csv and cst, and
//! the report carries what the README promises (recoveries, if the machine stalled, included).

use ecdrive_cli::app::ethercat::demo::{DemoOptions, run};

#[test]
fn demo_runs_both_drives_through_csp_csv_cst() {
    let r = run(&DemoOptions::default()).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&r).unwrap());
    for h in &r.history {
        eprintln!("{:?} {:?}: {}", h.cycle, h.drive, h.text());
    }
    assert!(r.ok, "{:#?}\n{:#?}", r.unhandled, r.errors);
    assert!(r.unhandled.is_empty());
    // A recovery is only ever made after the drives stopped on their own (on a machine that
    // stalls the cycle for 7 ms or more their loss supervision trips), and says why.
    if r.recoveries > 0 {
        assert!(
            r.errors.iter().any(|e| e.contains("fault")),
            "{:#?}",
            r.errors
        );
    }
    for d in &r.drives {
        assert!(d.program_done, "{}", d.name);
    }
    // The history has `ecdrive run`'s shape: objects with a cycle, a drive and a text.
    let j = serde_json::to_value(&r).unwrap();
    let first = &j["history"][0];
    assert!(first.is_object() && first["text"].is_string(), "{first}");
}
