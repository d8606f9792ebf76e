//! The demo's library path: both emulated drives reach OP with DC, run csp, csv and cst, and
//! the report carries what the README promises.

use ecdrive::master::demo::{DemoOptions, run};

#[test]
fn demo_runs_both_drives_through_csp_csv_cst() {
    let r = run(&DemoOptions::default()).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&r).unwrap());
    for h in &r.history {
        eprintln!("{h}");
    }
    assert!(r.ok, "{:#?}", r.errors);
}
