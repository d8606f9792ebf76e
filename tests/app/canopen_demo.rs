use ecdrive_cli::app::canopen::demo;

/// The demo is the example file run on the emulated drives: every program done (home, pp,
/// pv, tq where the drive has it, ip on the ASDA-A2), then each drive's injected alarm named
/// with its alarm table and cleared.
#[test]
fn demo_runs_every_drive_through_every_mode() {
    let s = demo::run(&demo::DemoOptions::default()).unwrap();
    println!("{s}");
    assert!(s.ok(), "{s}");
    assert_eq!(s.scan.len(), 3, "{s}");
    let asda = s.run.drives.iter().find(|d| d.drive == "ASDA-A2").unwrap();
    assert!(asda.modes.iter().any(|m| m.starts_with("ip")), "{asda:?}");
    for d in &s.faults.drives {
        let p = ecdrive::drives::CANOPEN_PROFILES
            .iter()
            .find(|p| p.name == d.drive)
            .unwrap();
        let alarm = demo::demo_alarm(p).and_then(|n| p.alarm(n)).unwrap();
        let fault = d.fault.as_deref().unwrap();
        assert!(fault.contains(alarm.name), "{}: {fault}", d.drive);
    }
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
