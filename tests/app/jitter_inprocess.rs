//! The jitter harness in-process: a short run of every loop, twice, produces every figure the
//! JSON promises, for each run and across the repetitions, and an SVG that parses; and each
//! run is what it says (threads, link, polling). No timing is asserted: only that the figures
//! exist and are consistent with each other.
//!
//! A run's figures name every thread of the process that the run started, so each run is a
//! test alone in a process of its own (`support::alone`): another test running beside it in
//! this binary would add its threads.

use crate::support;
use ecdrive_cli::app::harness::{self, JitterConfig, JitterReport, Transport};
use serde_json::Value;
use std::time::Duration;

const CYCLES: u64 = 300;

fn short_run() -> JitterReport {
    let mut cfg = JitterConfig::new(Duration::from_millis(1));
    cfg.cycles = CYCLES;
    cfg.transport = Transport::InProcess;
    cfg.count_syscalls = true;
    cfg.repeat = 2;
    // Given, but SOEM needs an interface: the report says why it did not run.
    cfg.soem = Some("target/soem/soem_cycle".into());
    harness::run(&cfg, &|what| eprintln!("jitter: {what}")).expect("the harness runs in-process")
}

fn summary_ok(v: &Value, what: &str) {
    for k in ["count", "min", "p50", "p90", "p99", "p999", "max", "mean"] {
        assert!(
            v.get(k).is_some_and(Value::is_number),
            "{what}: {k} missing in {v}"
        );
    }
    let get = |k: &str| v[k].as_u64().unwrap_or(0);
    assert!(get("count") > 0, "{what}: no samples");
    assert!(
        get("min") <= get("p50")
            && get("p50") <= get("p90")
            && get("p90") <= get("p99")
            && get("p99") <= get("p999")
            && get("p999") <= get("max"),
        "{what}: percentiles out of order: {v}"
    );
}

fn ratio_ok(v: &Value, what: &str) {
    for k in ["p50", "p90", "p99", "p999", "max"] {
        assert!(v.get(k).is_some(), "{what}: ratio {k} missing in {v}");
    }
}

#[test]
fn every_figure_for_every_run_and_a_plot() {
    support::alone("jitter_inprocess::every_figure_for_every_run_and_a_plot_alone");
}

#[test]
#[ignore = "run alone in a process of its own by the test of the same name without _alone"]
fn every_figure_for_every_run_and_a_plot_alone() {
    let report = short_run();
    let all = serde_json::to_value(&report).unwrap();
    let json = &all["repetitions"][0];
    let settings = &all["settings"];

    // Host conditions and settings.
    for k in [
        "kernel",
        "preempt_rt",
        "cpu_model",
        "cpus",
        "governor",
        "isolated_cpus",
        "sched_rt_runtime_us",
    ] {
        assert!(all["host"].get(k).is_some(), "host.{k} missing");
    }
    assert_eq!(all["schema"], "ecdrive-jitter/2");
    assert_eq!(settings["cycle_ns"], 1_000_000);
    assert_eq!(settings["transport"], "in-process");
    assert_eq!(settings["drives"].as_array().unwrap().len(), 2);
    assert_eq!(settings["repeat"], 2);
    assert!(all["load"]["loadavg_before"].is_array());
    assert!(all["load"]["stress"].is_null());
    // No SOEM in-process, and the reason.
    assert!(
        all["soem_absent"]
            .as_str()
            .is_some_and(|w| w.contains("network interface")),
        "{}",
        all["soem_absent"]
    );
    assert!(json["soem"].is_null() && json["ratios"]["ecdrive_to_soem"].is_null());

    // Whether the priority was granted, and a warning when it was not.
    let granted = all["priority_granted"].as_bool().unwrap();
    let warned = report.warnings.iter().any(|w| w.contains("not granted"));
    assert_eq!(granted, !warned, "{:?}", report.warnings);
    if ecdrive::link::netns::is_root() {
        assert!(granted, "root gets SCHED_FIFO: {:?}", report.warnings);
    }

    for run in ["sleep", "ethercrab", "ecdrive"] {
        let r = &json[run];
        assert_eq!(r["name"], run);
        for k in ["wake_latency", "period", "period_error", "busy"] {
            summary_ok(&r[k], &format!("{run}.{k}"));
        }
        assert!(r["late"].is_u64(), "{run}.late");
        assert!(r["rt"].get("priority_granted").is_some());
        let cpu = &r["cpu"];
        for k in [
            "cycle_thread_ns",
            "master_ns",
            "process_ns",
            "voluntary_switches",
        ] {
            assert!(
                cpu[k]
                    .as_f64()
                    .is_some_and(|v| v > 0.0 || k == "voluntary_switches"),
                "{run}.cpu.{k}: {cpu}"
            );
        }
        assert!(
            cpu["method"]
                .as_str()
                .unwrap()
                .contains("CLOCK_THREAD_CPUTIME_ID")
        );
        let hist: u64 = r["wake_latency_histogram"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["count"].as_u64().unwrap())
            .sum();
        assert_eq!(
            hist,
            r["wake_latency"]["count"].as_u64().unwrap(),
            "{run}: histogram bins"
        );
    }
    // Exact cycle counts where the harness runs the loop itself; ecdrive's window runs from OP
    // to the stop request, at least the cycles asked for.
    assert_eq!(json["sleep"]["cycles"], CYCLES);
    assert_eq!(json["ethercrab"]["cycles"], CYCLES);
    assert!(json["ecdrive"]["cycles"].as_u64().unwrap() >= CYCLES);
    assert!(json["sleep"]["exchange"].is_null() && json["sleep"]["missed"].is_null());

    for run in ["ethercrab", "ecdrive"] {
        let r = &json[run];
        summary_ok(&r["exchange"], &format!("{run}.exchange"));
        assert!(r["missed"].is_u64());
        // The master's CPU: plain ethercrab has its TX/RX thread, ecdrive pumps inline.
        let io = &r["cpu"]["io_thread_ns"];
        assert_eq!(
            io.is_null(),
            run == "ecdrive",
            "{run}.cpu.io_thread_ns = {io}"
        );
        let drives = r["drives"].as_array().unwrap();
        assert_eq!(drives.len(), 2, "{run}: per-drive figures");
        for d in drives {
            summary_ok(&d["arrival_after_sync0"], &format!("{run}: SYNC0 arrival"));
            assert!(d["sync0_pulses"].as_u64().unwrap() > 0);
            assert!(d["sync0_without_outputs"].is_u64());
        }
        // Drive 0 is the DC reference clock: the others are compared with it.
        assert!(drives[0]["dc_difference"].is_null());
        summary_ok(
            &drives[1]["dc_difference"],
            &format!("{run}: DC difference"),
        );
    }

    for base in ["ecdrive_to_sleep", "ecdrive_to_ethercrab"] {
        let q = &json["ratios"][base];
        for k in ["wake_latency", "period_error", "busy"] {
            ratio_ok(&q[k], &format!("{base}.{k}"));
        }
        for k in [
            "cpu_master",
            "cpu_cycle_thread",
            "cpu_process",
            "late",
            "missed",
        ] {
            assert!(q.get(k).is_some(), "{base}.{k}");
        }
        assert!(q["cpu_master"].as_f64().is_some(), "{base}.cpu_master");
    }
    assert!(json["ratios"]["ecdrive_to_sleep"]["exchange"].is_null());
    ratio_ok(
        &json["ratios"]["ecdrive_to_ethercrab"]["exchange"],
        "exchange ratio",
    );
    assert_eq!(
        json["ratios"]["ecdrive_to_ethercrab"]["drives"]
            .as_array()
            .unwrap()
            .len(),
        2
    );

    // The plot: well-formed SVG with one histogram per run and a legend naming them.
    // Each run is what it says (structure, not figures).
    let rep = &report.repetitions[0];
    let threads = |r: &harness::RunReport| {
        let mut t = r.structure.master_threads.clone();
        t.sort();
        t
    };
    assert_eq!(threads(&rep.sleep).len(), 1, "{:?}", rep.sleep.structure);
    // Plain ethercrab: its loop thread, the in-process TX/RX thread, which wakes for frames
    // only (about once a cycle), not also for each SYNC0 as it used to, and the async-io
    // reactor that serves its timers (kernel names: 15 characters).
    assert_eq!(
        threads(&rep.ethercrab),
        ["async-io", "ecdrive-sim-eth", "jitter-ethercra"],
        "{:?}",
        rep.ethercrab.cpu.threads
    );
    assert!(rep.ethercrab.structure.link.contains("frames only"));
    let txrx = rep
        .ethercrab
        .cpu
        .threads
        .iter()
        .find(|t| t.name == "ecdrive-sim-eth")
        .unwrap();
    assert!(
        txrx.voluntary < 1.5,
        "the TX/RX thread wakes {:.2} times a cycle",
        txrx.voluntary
    );
    // ecdrive: its cycle thread (which runs the in-process slaves) and its session thread,
    // with emergency polling on as by default, and no TX/RX thread.
    assert_eq!(
        threads(&rep.ecdrive),
        ["ecdrive-cycle", "ecdrive-session"],
        "{:?}",
        rep.ecdrive.cpu.threads
    );
    assert_eq!(rep.ecdrive.structure.mailbox_poll_ms, Some(50));
    assert!(rep.ecdrive.structure.link.contains("SegmentLink"));
    for r in [&rep.ethercrab, &rep.ecdrive] {
        assert!(
            r.structure.slaves.contains("charged to the master"),
            "{:?}",
            r.structure
        );
        // The master figure is the sum of the master's threads.
        let sum: f64 = r
            .cpu
            .threads
            .iter()
            .filter(|t| t.role == harness::cpu::ThreadRole::Master)
            .map(|t| t.cpu_ns)
            .sum();
        assert_eq!(r.cpu.master_ns, Some(sum), "{}", r.name);
    }

    // Across the repetitions: each figure's median and spread, from each repetition's value.
    assert_eq!(all["repetitions"].as_array().unwrap().len(), 2);
    for run in ["sleep", "ethercrab", "ecdrive"] {
        let f = &all["summary"]["runs"][run];
        for k in [
            "wake_latency_p50",
            "wake_latency_p99",
            "busy_p50",
            "cpu_master_ns",
        ] {
            let sp = &f[k];
            let v: Vec<f64> = sp["values"]
                .as_array()
                .unwrap_or_else(|| panic!("summary.runs.{run}.{k}: {f}"))
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            assert_eq!(v.len(), 2, "{run}.{k}");
            let (lo, hi) = (v[0].min(v[1]), v[0].max(v[1]));
            assert_eq!(sp["min"].as_f64(), Some(lo));
            assert_eq!(sp["max"].as_f64(), Some(hi));
            assert_eq!(sp["median"].as_f64(), Some((lo + hi) / 2.0));
        }
    }
    let r = &all["summary"]["ratios"]["ecdrive_to_ethercrab"]["cpu_master"]["values"];
    assert_eq!(
        r.as_array().map(Vec::len),
        Some(2),
        "a ratio per repetition"
    );

    let svg = harness::svg::render(&report);
    let doc = roxmltree::Document::parse(&svg).expect("the SVG parses as XML");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let paths = doc.descendants().filter(|n| n.has_tag_name("path")).count();
    assert_eq!(paths, 3, "one histogram per run");
    let text: String = doc
        .descendants()
        .filter(|n| n.is_text())
        .map(|n| n.text().unwrap_or(""))
        .collect();
    for run in ["sleep:", "ethercrab:", "ecdrive:"] {
        assert!(text.contains(run), "legend names {run}");
    }

    // The text table names every run and both ratios.
    let table = report.text();
    for w in [
        "sleep",
        "ethercrab",
        "ecdrive",
        "÷ sleep",
        "÷ ethercrab",
        "across 2 repetitions",
        "soem: not run",
    ] {
        assert!(table.contains(w), "{table}");
    }
}

#[test]
fn bad_settings_are_refused_with_the_reason() {
    let mut cfg = JitterConfig::new(Duration::from_micros(10));
    cfg.cycles = 100;
    let e = harness::run(&cfg, &|_| {}).unwrap_err();
    assert!(e.to_string().contains("outside 50 µs"), "{e}");
    let mut cfg = JitterConfig::new(Duration::from_millis(1));
    cfg.drives = vec!["generic-coe".into(), "no-such-drive".into()];
    let e = harness::run(&cfg, &|_| {}).unwrap_err();
    assert!(e.to_string().contains("emulated drive 1"), "{e}");
    assert!(e.to_string().contains("no-such-drive"), "{e}");
}

/// The emulated MR-J4-TM and BDHDE (the drives ecdrive is for) run in every loop: the plain
/// ethercrab loop configures them from their profiles (mapping, sync, 0x60C2, start-up SDOs)
/// and advances the MR-J4-TM's cycle counter, so both stay in OP for the whole window.
#[test]
fn the_emulated_drives_run_in_every_loop() {
    support::alone("jitter_inprocess::the_emulated_drives_run_in_every_loop_alone");
}

#[test]
#[ignore = "run alone in a process of its own by the test of the same name without _alone"]
fn the_emulated_drives_run_in_every_loop_alone() {
    let mut cfg = JitterConfig::new(Duration::from_micros(500));
    cfg.cycles = 200;
    cfg.drives = vec!["mr-j4-tm".into(), "bdhde".into()];
    let report = harness::run(&cfg, &|_| {}).expect("the harness runs the emulated drives");
    assert_eq!(report.settings.profiles, ["MR-J4-TM", "BDHDE"]);
    let rep = &report.repetitions[0];
    for r in [&rep.ethercrab, &rep.ecdrive] {
        assert_eq!(r.drives.len(), 2, "{}", r.name);
        assert!(r.drives.iter().all(|d| d.arrival_after_sync0.is_some()));
        // No device left OP, no drive raised an error (ecdrive's history would hold it).
        assert!(r.notes.is_empty(), "{}: {:?}", r.name, r.notes);
    }
}
