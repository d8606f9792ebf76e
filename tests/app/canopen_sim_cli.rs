//! `ecdrive sim --can vbus:PATH` serves the emulated CANopen drives on a virtual bus that
//! other commands share: `slaves`, `download` and `upload` in separate processes see the same
//! nodes, in the same state (issue "operator-grade runs": `--can virtual` is fresh for every
//! command). No root, no vcan: a Unix socket of this machine.

use crate::support;
use std::process::Child;
use support::cli::ecdrive;

/// `ecdrive sim --can BUS extra…`, started and waited for until its banner is complete.
fn serve(bus: &str, extra: &[&str], nodes: usize) -> (Child, String) {
    support::cli::serve_can(bus, extra, nodes)
}

fn stop(mut child: Child) -> std::process::Output {
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    let status = child.wait().unwrap();
    let mut stdout = Vec::new();
    if let Some(mut o) = child.stdout.take() {
        let _ = std::io::Read::read_to_end(&mut o, &mut stdout);
    }
    std::process::Output {
        status,
        stdout,
        stderr: Vec::new(),
    }
}

#[test]
fn commands_share_the_served_nodes_and_their_state() {
    let dir = std::env::temp_dir().join(format!("ecdrive-can-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sock = dir.join("bus.sock");
    let bus = format!("vbus:{}", sock.display());
    let (first, banner) = serve(&bus, &["--json"], 3);
    assert!(banner.contains("(hub started here)"), "{banner}");

    // Identity through the bus, against the manuals' literal values (object 1018h):
    // BLV-R "Vender ID … 0000 02BEh", "Product code … BLVD-KRD 0000 13F7h" (Oriental BLV-R
    // CANopen manual, object list); ASDA-A2 Vendor ID "Default Value 1DDh", Product code
    // "6000h: A2 Series" (Delta ASDA-A2 CANopen manual, object 1018h); Lexium MDrive Vendor ID
    // "Default value 0000 021Bh" (Schneider Lexium MDrive CANopen manual, object 1018h).
    let j = ecdrive(&["slaves", "--can", &bus, "--json"]).json();
    let list = j.as_array().unwrap();
    let ids: Vec<u64> = list.iter().map(|n| n["node"].as_u64().unwrap()).collect();
    assert_eq!(ids, [1, 0x41, 0x7F], "{j:#}");
    assert_eq!(list[0]["vendor_id"], 0x2BE);
    assert_eq!(list[0]["product_code"], 0x13F7);
    assert_eq!(list[2]["vendor_id"], 0x1DD);
    assert_eq!(list[2]["product_code"], 0x6000);
    assert_eq!(list[1]["vendor_id"], 0x21B);

    // A value written by one command is read by the next: the node kept it.
    ecdrive(&["download", "--can", &bus, "-n", "1", "0x6081:00", "20000"]).ok();
    let v = ecdrive(&["upload", "--can", &bus, "-n", "1", "0x6081:00"])
        .ok()
        .to_string();
    assert!(v.starts_with("20000 "), "{v}");

    // A second server may join the bus, but not with a node-ID that answers there already.
    ecdrive(&["sim", "--can", &bus, "--node", "asda-a2"])
        .fails(2, &["node-ID 127 (0x7F) already answers", "@ID"]);
    let (second, banner) = serve(&bus, &["--node", "asda-a2@0x20"], 1);
    assert!(!banner.contains("hub started here"), "{banner}");
    let j = ecdrive(&["slaves", "--can", &bus, "--json"]).json();
    assert_eq!(j.as_array().unwrap().len(), 4, "{j:#}");
    assert!(stop(second).status.success());

    // Stopped by SIGTERM, it says what it served and removes its socket.
    let out = stop(first);
    assert!(out.status.success(), "{out:?}");
    let rep: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(rep["started_hub"], true);
    assert_eq!(rep["nodes"].as_array().unwrap().len(), 3);
    assert!(!sock.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn what_cannot_be_served_is_named() {
    ecdrive(&["sim", "--can", "virtual"]).fails(2, &["'virtual'", "vbus:PATH"]);
    ecdrive(&["sim", "--can", "vbus:/tmp/x", "--node", "nope"])
        .fails(2, &["\"nope\" is not an emulated CANopen drive", "asda-a2"]);
    ecdrive(&["sim", "--can", "vbus:/tmp/x", "--node", "blv-r@200"])
        .fails(2, &["node-ID must be 1–127"]);
    ecdrive(&[
        "sim",
        "--can",
        "vbus:/tmp/x",
        "--node",
        "blv-r",
        "--node",
        "asda-a2@1",
    ])
    .fails(2, &["node-ID 1 (0x01) is given twice"]);
    let list = ecdrive(&["sim", "--list-devices", "--json"]).json();
    assert_eq!(list["can_nodes"].as_array().unwrap().len(), 4);
}
