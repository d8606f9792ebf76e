//! An independent master written in Python (SOEM through pysoem, KickCAT through its package)
//! driving an emulated segment over a veth pair: the segment served on one end, the script run
//! on the other with the interface as its first argument, its JSON (the last line of its
//! output that is a JSON object) and the segment back.

use ecdrive_core::link::netns::VethPair;
use ecdrive_sim::Segment;
use ecdrive_sim::transport::RawServer;
use std::process::Command;

/// Whether `python3` imports `module`.
pub fn importable(module: &str) -> bool {
    Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .status()
        .is_ok_and(|s| s.success())
}

/// Whether test `test` can drive a segment with the Python package `module` (the master
/// `who`): root (for veth) and the package importable. Without the package it prints a loud
/// SKIPPED line, unless `require_env` is set, which makes it fail instead.
#[allow(dead_code)] // sim_kickcat names its own pinned install
pub fn ready(test: &str, module: &str, require_env: &str) -> bool {
    if !ecdrive_core::link::netns::require_root(test) {
        return false;
    }
    if importable(module) {
        return true;
    }
    if std::env::var_os(require_env).is_some() {
        panic!("{module} is not importable and {require_env} is set");
    }
    ecdrive_core::rt::audit::announce_skip(&format!(
        "SKIPPED (needs {module}: pip install {module}): {test}"
    ));
    false
}

/// Serve `seg` on a new veth pair, run `script` with the host end's name and `args`, and
/// return the segment and the script's JSON. Fails the test when the script fails (`who`
/// names the master in the message) or prints no JSON.
pub fn run(who: &str, seg: Segment, script: &str, args: &[&str]) -> (Segment, serde_json::Value) {
    let veth = VethPair::create().expect("veth pair");
    let server =
        RawServer::spawn(veth.open_peer_socket().expect("peer socket"), seg).expect("server");
    let mut all = vec!["-c", script, veth.host()];
    all.extend_from_slice(args);
    let output = Command::new("python3")
        .args(&all)
        .output()
        .expect("run python3");
    let (seg, result) = server.stop();
    result.expect("server ran without I/O errors");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{who} failed:\n{stderr}\n{stdout}");
    let json = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_default();
    let v: serde_json::Value =
        serde_json::from_str(json).unwrap_or_else(|e| panic!("JSON from {who}: {e}\n{stdout}"));
    (seg, v)
}
