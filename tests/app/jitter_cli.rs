//! `ecdrive jitter` from the command line, as a user without root runs it: it works
//! in-process, warns that the real-time priority was not granted, and writes the JSON (with
//! the command that produced it) and the SVG. No timing is asserted.

use std::process::Command;

#[test]
fn without_root_it_runs_in_process_warns_and_writes_json_and_svg() {
    let dir = std::env::temp_dir().join(format!("ecdrive-jitter-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("out.json");
    let svg = dir.join("out.svg");
    let exe = env!("CARGO_BIN_EXE_ecdrive");
    let args = [
        "jitter",
        "--cycle-us",
        "1000",
        "--cycles",
        "200",
        "--json",
        json.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ];
    let root = ecdrive::link::netns::is_root();
    let out = if root {
        // Drop to nobody: no CAP_SYS_NICE, no rtprio or memlock allowance.
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o777)).unwrap();
        match Command::new("setpriv")
            .args(["--reuid=65534", "--regid=65534", "--clear-groups", exe])
            .args(args)
            .output()
        {
            Ok(o) => o,
            Err(e) => {
                ecdrive::rt::audit::skip_or_fail(&format!(
                    "running as root and cannot drop privileges with setpriv: {e}"
                ));
                return;
            }
        }
    } else {
        Command::new(exe).args(args).output().unwrap()
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stderr}\n{stdout}");
    assert!(
        stderr.contains("warning: real-time priority SCHED_FIFO 80 not granted"),
        "{stderr}"
    );
    assert!(stdout.contains("NOT granted"), "{stdout}");
    for run in ["sleep", "ethercrab", "ecdrive"] {
        assert!(stdout.contains(run), "{stdout}");
    }

    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["priority_granted"], false);
    assert!(
        v["command"]
            .as_str()
            .unwrap()
            .starts_with("ecdrive jitter --cycle-us 1000")
    );
    for run in ["sleep", "ethercrab", "ecdrive"] {
        let r = &v["repetitions"][0][run];
        assert_eq!(r["rt"]["priority_granted"], serde_json::Value::Null);
        assert!(r["wake_latency"]["p999"].is_u64());
    }
    let svg = std::fs::read_to_string(&svg).unwrap();
    roxmltree::Document::parse(&svg).expect("the SVG parses as XML");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_arguments_are_named() {
    let out = Command::new(env!("CARGO_BIN_EXE_ecdrive"))
        .args(["jitter", "--device", "generic-coe:0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--device generic-coe:0"), "{stderr}");
}

use crate::support;

/// `jitter -i IF` measures the drives the far end serves without `--device` repeating them:
/// it discovers them (issue "operator-grade runs").
#[test]
fn over_an_interface_it_discovers_the_far_ends_drives() {
    let Some(sim) = support::cli::SimOnVeth::start(
        "jitter_cli::over_an_interface_it_discovers_the_far_ends_drives",
        &["mr-j4-tm", "bdhde"],
    ) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("ecdrive-jitter-if-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("out.json");
    let r = sim.ecdrive(&[
        "jitter",
        "--cycles",
        "200",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(r.code, Some(0), "{r:#?}");
    assert!(r.stderr.contains("discovering the drives on"), "{r:#?}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        v["settings"]["drives"],
        serde_json::json!(["mr-j4-tm", "bdhde"])
    );
    assert_eq!(
        v["settings"]["profiles"],
        serde_json::json!(["MR-J4-TM", "BDHDE"])
    );
    assert_eq!(v["settings"]["transport"], "interface");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A device the harness cannot drive is named, with its identity, and the run does not start.
#[test]
fn over_an_interface_a_device_without_a_drive_profile_is_named() {
    let Some(sim) = support::cli::SimOnVeth::start(
        "jitter_cli::over_an_interface_a_device_without_a_drive_profile_is_named",
        &["mr-j4-tm", "generic-io"],
    ) else {
        return;
    };
    let r = sim.ecdrive(&["jitter", "--cycles", "200"]);
    assert_eq!(r.code, Some(2), "{r:#?}");
    assert!(
        r.stderr.contains("device 1 on") && r.stderr.contains("matches no drive profile"),
        "{r:#?}"
    );
}
