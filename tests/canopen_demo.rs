use ecdrive::app::canopen::demo;

#[test]
fn demo_runs_every_drive_through_every_mode() {
    let s = demo::run(&demo::DemoOptions::default()).unwrap();
    println!("{s}");
    assert!(s.ok(), "{s}");
}

/// `ecdrive demo --canopen --json` prints one JSON object (it printed text before).
#[test]
fn the_canopen_demo_honours_json() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ecdrive"))
        .args(["demo", "--canopen", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["ok"], true);
    assert_eq!(j["drives"].as_array().unwrap().len(), 3);
    assert!(j["drives"][0]["steps"][0]["outcome"].is_string());
}
