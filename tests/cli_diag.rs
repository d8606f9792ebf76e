//! `ecdrive diag` against `ecdrive sim` over veth: the ESC error counters that the software
//! slave keeps as silicon does, moved by injected faults (bit errors on one cable, a pulled
//! cable), read without disturbing the segment, named in words, and cleared by `--reset`. Needs
//! root (skips loudly without it; fails under `ECDRIVE_CI`).

mod support {
    pub mod cli;
}
use std::time::{Duration, Instant};
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
    let started = Instant::now();
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
    // After the cable was pulled and put back.
    std::thread::sleep(Duration::from_millis(1500).saturating_sub(started.elapsed()));
    let j = sim.ecdrive(&["diag", "--json"]).json();
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
