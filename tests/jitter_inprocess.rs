//! The jitter harness in-process: a short run of all three loops produces every figure the
//! JSON promises, for each run, and an SVG that parses. No timing is asserted: only that the
//! figures exist and are consistent with each other.

use ecdrive::app::harness::{self, JitterConfig, JitterReport, Transport};
use serde_json::Value;
use std::time::Duration;

const CYCLES: u64 = 300;

fn short_run() -> JitterReport {
    let mut cfg = JitterConfig::new(Duration::from_millis(1));
    cfg.cycles = CYCLES;
    cfg.transport = Transport::InProcess;
    cfg.count_syscalls = true;
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
fn every_figure_for_all_three_runs_and_a_plot() {
    let report = short_run();
    let json = serde_json::to_value(&report).unwrap();

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
        assert!(json["host"].get(k).is_some(), "host.{k} missing");
    }
    assert_eq!(json["schema"], "ecdrive-jitter/1");
    assert_eq!(json["settings"]["cycle_ns"], 1_000_000);
    assert_eq!(json["settings"]["transport"], "in-process");
    assert_eq!(json["settings"]["drives"].as_array().unwrap().len(), 2);

    // Whether the priority was granted, and a warning when it was not.
    let granted = json["priority_granted"].as_bool().unwrap();
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
    for w in ["sleep", "ethercrab", "ecdrive", "÷ sleep", "÷ ethercrab"] {
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
    let mut cfg = JitterConfig::new(Duration::from_micros(500));
    cfg.cycles = 200;
    cfg.drives = vec!["mr-j4-tm".into(), "bdhde".into()];
    let report = harness::run(&cfg, &|_| {}).expect("the harness runs the emulated drives");
    assert_eq!(report.settings.profiles, ["MR-J4-TM", "BDHDE"]);
    for r in [&report.ethercrab, &report.ecdrive] {
        assert_eq!(r.drives.len(), 2, "{}", r.name);
        assert!(r.drives.iter().all(|d| d.arrival_after_sync0.is_some()));
        // No device left OP, no drive raised an error (ecdrive's history would hold it).
        assert!(r.notes.is_empty(), "{}: {:?}", r.name, r.notes);
    }
}
