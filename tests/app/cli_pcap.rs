//! `--pcap FILE`: the master's frames, both directions, as pcapng that Wireshark's EtherCAT
//! dissector reads without a malformed frame — checked with `tshark` (installed by `.ci/run`;
//! without it the tests skip loudly, under `ECDRIVE_CI` they fail).

use crate::support;
use support::cli::{SimOnVeth, ecdrive};

/// `tshark` with `args`, its stdout; `None` (after a loud skip line) when it is not installed
/// outside CI.
/// The tests of this file each run a real-time cycle (a run, the demo, a sim over veth): run
/// together on a two-core CI machine they stalled each other for 20 ms and the emulated drives'
/// loss supervision stopped the demo. One at a time.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn tshark(args: &[&str]) -> Option<String> {
    match std::process::Command::new("tshark").args(args).output() {
        Ok(out) => {
            assert!(
                out.status.success(),
                "tshark {args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            Some(String::from_utf8_lossy(&out.stdout).into_owned())
        }
        Err(e) if std::env::var_os("ECDRIVE_CI").is_none() => {
            eprintln!("SKIPPED: tshark not available ({e})");
            None
        }
        Err(e) => panic!("tshark must be installed under CI: {e}"),
    }
}

fn count(path: &str, filter: &str) -> Option<usize> {
    tshark(&[
        "-r",
        path,
        "-Y",
        filter,
        "-T",
        "fields",
        "-e",
        "frame.number",
    ])
    .map(|s| s.lines().filter(|l| !l.trim().is_empty()).count())
}

/// The frames the capture line on stderr says were written.
fn frames_written(stderr: &str, path: &str) -> usize {
    let line = stderr
        .lines()
        .find(|l| l.contains(&format!("capture {path}: ")))
        .unwrap_or_else(|| panic!("no capture line: {stderr}"));
    line.split(": ")
        .nth(2)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{line}"))
}

/// Every frame is an EtherCAT frame, none malformed, both directions present, as many as
/// ecdrive says it wrote.
fn check(path: &str, written: usize) {
    let Some(all) = count(path, "frame") else {
        return;
    };
    assert!(all > 10, "{all} frames");
    assert_eq!(all, written, "frames in the file");
    assert_eq!(count(path, "ecat").unwrap(), all, "every frame is EtherCAT");
    assert_eq!(count(path, "_ws.malformed").unwrap(), 0, "malformed frames");
    let out = count(path, "frame.packet_flags_direction == 2").unwrap();
    let inb = count(path, "frame.packet_flags_direction == 1").unwrap();
    assert!(
        out > 0 && inb > 0 && out + inb == all,
        "outbound {out}, inbound {inb}"
    );
}

#[test]
fn a_run_capture_opens_in_tshark_without_a_malformed_frame() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("ecdrive-pcap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("run.pcapng");
    let p = path.to_str().unwrap();
    // The README's example, with the emulated drives' loss supervision off: a host stall of a
    // few ms on a loaded CI machine tripped it once (a drive fault, exit 5), which says nothing
    // about the capture under test.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/csp_move_sine.toml"
    ))
    .unwrap()
    .replacen("[sim]\n", "[sim]\nloss_detection = false\n", 1);
    assert!(text.contains("loss_detection = false"));
    let cfg = dir.join("run.toml");
    std::fs::write(&cfg, text).unwrap();
    let file = cfg.to_str().unwrap();
    let r = ecdrive(&["run", "-c", file, "--pcap", p]);
    r.ok();
    let written = frames_written(&r.stderr, p);
    assert!(!r.stderr.contains("dropped"), "{}", r.stderr);
    check(p, written);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_demo_captures_its_in_process_frames() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("ecdrive-pcap-demo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("demo.pcapng");
    let p = path.to_str().unwrap();
    // The capture is under test, not the host's timing: the drives' loss supervision off, so
    // that a stall of the shared machine cannot end the demo.
    let r = ecdrive(&["demo", "--no-loss-detection", "--pcap", p]);
    r.ok();
    check(p, frames_written(&r.stderr, p));
    // A command that sends no EtherCAT frames through it refuses --pcap.
    ecdrive(&["sim", "--list-devices", "--pcap", p]).fails(2, &["--pcap"]);
    // The CANopen demo has no emulated EtherCAT drives to switch it off in.
    ecdrive(&["demo", "--canopen", "--no-loss-detection"]).fails(2, &["--no-loss-detection"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_tool_capture_over_veth() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some(sim) = SimOnVeth::start("cli_pcap::a_tool_capture_over_veth", &["mr-j4-tm", "bdhde"])
    else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("ecdrive-pcap-veth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("slaves.pcapng");
    let p = path.to_str().unwrap();
    let r = sim.ecdrive(&["slaves", "--pcap", p]);
    r.ok();
    check(p, frames_written(&r.stderr, p));
    // A file that cannot be written: one line naming it, before anything goes on the wire.
    sim.ecdrive(&["slaves", "--pcap", "/nonexistent-dir/x.pcapng"])
        .fails(2, &["/nonexistent-dir/x.pcapng"]);
    let _ = std::fs::remove_dir_all(&dir);
}
