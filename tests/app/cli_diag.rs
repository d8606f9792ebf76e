//! `ecdrive diag` against `ecdrive sim` over veth: the ESC error counters that the software
//! slave keeps as silicon does, moved by injected faults (bit errors on one cable, a pulled
//! cable), read without disturbing the segment, named in words, and cleared by `--reset`. Needs
//! root (skips loudly without it; fails under `ECDRIVE_CI`).

use crate::support;
use std::time::Duration;
use support::cli::SimOnVeth;

#[test]
fn diag_shows_bit_errors_and_a_cable_pull_and_reset_clears_them() {
    let Some(sim) = SimOnVeth::start_with(
        "cli_diag::diag_shows_bit_errors_and_a_cable_pull_and_reset_clears_them",
        &["mr-j4-tm", "bdhde", "generic-io"],
        &[
            // Five frames meet a bit error on the cable into device 1; the cable to the
            // master is pulled at 1.0 s and put back at 1.2 s.
            "--crc-error-at",
            "1@0s:5",
            "--disconnect-at",
            "1s",
            "--reconnect-at",
            "1200ms",
        ],
    ) else {
        return;
    };
    // The first frames meet the bit errors and are lost: diag fails with one line naming what
    // it was doing, until the five are spent.
    let mut tries = 0;
    loop {
        let r = sim.ecdrive(&["diag"]);
        if r.code == Some(0) {
            break;
        }
        r.fails(3, &["ecdrive diag", "counting the devices"]);
        tries += 1;
        assert!(tries <= 5, "diag never succeeded");
    }
    // After the cable was pulled and put back (an event: device 0 has counted the lost link
    // and answers again), however long that takes on this machine.
    let mut polls = 0;
    let j = loop {
        let r = sim.ecdrive(&["diag", "--json"]);
        if r.code == Some(0) {
            let j = r.json();
            if j["devices"][0]["ports"][0]["lost_links"].as_u64() == Some(1) {
                break j;
            }
        }
        polls += 1;
        assert!(polls < 3000, "the pulled cable was never counted");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(j["device_count"], 3);
    let port = |d: usize, p: usize, k: &str| j["devices"][d]["ports"][p][k].as_u64().unwrap();
    // Where the bit errors happened: device 1's port 0 counts them as RX errors; device 2
    // counts them forwarded; every device with port 1 open counts them forwarded as the frame
    // comes back; device 0 counts the pulled cable as a lost link on port 0.
    assert_eq!(port(1, 0, "rx_errors"), 5, "{j}");
    assert_eq!(port(0, 0, "rx_errors"), 0, "{j}");
    assert_eq!(port(2, 0, "forwarded_rx_errors"), 5, "{j}");
    assert_eq!(port(0, 1, "forwarded_rx_errors"), 5, "{j}");
    assert_eq!(
        port(2, 1, "forwarded_rx_errors"),
        0,
        "the last device loops port 1: {j}"
    );
    assert_eq!(port(0, 0, "lost_links"), 1, "{j}");
    // The topology bits: a line of three, the last device's port 1 closed.
    assert_eq!(j["devices"][1]["ports"][1]["communication"], true);
    assert_eq!(j["devices"][2]["ports"][1]["loop_closed"], true);
    // diag did no discovery: nothing was configured (no station address, still INIT).
    assert_eq!(j["devices"][0]["al_state"], "INIT");
    let findings: Vec<&str> = j["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert_eq!(findings.len(), 2, "{findings:?}");
    assert!(findings[0].contains("device 0 port 0: the link went down 1 time"));
    assert!(findings[1].contains("device 1 port 0: 5 RX error(s)"));
    assert!(findings[1].contains("the cable from device 0 into device 1"));

    // Text, and clearing.
    let text = sim.ecdrive(&["diag", "--reset"]).ok().to_string();
    assert!(text.contains("device 1 port 0: 5 RX error(s)"), "{text}");
    assert!(text.trim_end().ends_with("counters cleared"), "{text}");
    let j = sim.ecdrive(&["diag", "--json"]).json();
    for d in j["devices"].as_array().unwrap() {
        for p in d["ports"].as_array().unwrap() {
            for k in [
                "invalid_frames",
                "rx_errors",
                "forwarded_rx_errors",
                "lost_links",
            ] {
                assert_eq!(p[k], 0, "{k} after --reset: {j}");
            }
        }
    }
    assert!(j["findings"].as_array().unwrap().is_empty());
    let text = sim.ecdrive(&["diag", "-p", "2"]).ok().to_string();
    assert!(text.contains("no errors counted"), "{text}");
    sim.ecdrive(&["diag", "-p", "3"])
        .fails(2, &["position 3", "the segment has 3 devices"]);
}

/// `ecdrive graph` over veth: the DOT names every device with its identity and state and the
/// cables port to port; Graphviz renders it (installed by `.ci/run`); `--json` is the same as
/// data.
#[test]
fn graph_draws_the_segment() {
    let Some(sim) = SimOnVeth::start(
        "cli_diag::graph_draws_the_segment",
        &["mr-j4-tm", "bdhde", "generic-io"],
    ) else {
        return;
    };
    let dot = sim.ecdrive(&["graph"]).ok().to_string();
    // Identities as the manuals give them (MR-J4-TM: vendor 0x00000A1E product 0x00000201;
    // BDHDE: vendor 0x000002E1 product 0x000BE2EB), read through the bus from the SII.
    assert!(
        dot.contains("d0 [label=\"0: MR-J4-TM\\nvendor 0x00000A1E product 0x00000201"),
        "{dot}"
    );
    assert!(
        dot.contains("d1 [label=\"1: BDHDE\\nvendor 0x000002E1 product 0x000BE2EB"),
        "{dot}"
    );
    assert!(dot.contains("master -- d0 [headlabel=\"0\"]"), "{dot}");
    assert!(
        dot.contains("d0 -- d1 [taillabel=\"1\", headlabel=\"0\"]"),
        "{dot}"
    );
    assert!(
        dot.contains("d1 -- d2 [taillabel=\"1\", headlabel=\"0\"]"),
        "{dot}"
    );
    assert_eq!(dot.matches(" -- ").count(), 3, "{dot}");
    // Graphviz draws it.
    let ci = std::env::var_os("ECDRIVE_CI").is_some();
    match std::process::Command::new("dot")
        .arg("-Tsvg")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
    {
        Ok(mut child) => {
            use std::io::Write as _;
            child
                .stdin
                .take()
                .unwrap()
                .write_all(dot.as_bytes())
                .unwrap();
            let out = child.wait_with_output().unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let svg = String::from_utf8(out.stdout).unwrap();
            assert!(svg.contains("<svg") && svg.contains("BDHDE"), "{svg}");
        }
        Err(e) if !ci => eprintln!("SKIPPED: Graphviz `dot` not available ({e})"),
        Err(e) => panic!("Graphviz `dot` must be installed under CI: {e}"),
    }
    let j = sim.ecdrive(&["graph", "--json"]).json();
    assert_eq!(j["nodes"].as_array().unwrap().len(), 3);
    assert_eq!(j["nodes"][0]["vendor_id"], 0x0A1E);
    assert_eq!(j["nodes"][2]["open_ports"], serde_json::json!([0]));
    assert_eq!(
        j["links"][0],
        serde_json::json!({"from": null, "from_port": null, "to": 0, "to_port": 0})
    );
    assert_eq!(
        j["links"][2],
        serde_json::json!({"from": 1, "from_port": 1, "to": 2, "to_port": 0})
    );
    assert!(j["dangling"].as_array().unwrap().is_empty());
    // Nothing was configured by reading: every device is still in INIT.
    assert!(
        j["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .all(|n| n["al_state"] == "INIT")
    );
}
