//! The jitter harness over a veth pair it creates (root): the emulated drives on the far end
//! inside a network namespace, every run on the host end. Skipped loudly without root, fails
//! without root under `ECDRIVE_CI`. No timing is asserted.

use ecdrive::link::netns::require_root;
use ecdrive_cli::app::harness::{self, JitterConfig, Transport};
use std::time::Duration;

#[test]
fn every_figure_over_veth() {
    if !require_root("jitter_veth::every_figure_over_veth") {
        return;
    }
    let mut cfg = JitterConfig::new(Duration::from_millis(1));
    cfg.cycles = 300;
    cfg.transport = Transport::Veth;
    // The SOEM loop is built by benches/soem/build.sh, never by CI: without it the report
    // says why there is no SOEM run; with it, SOEM runs like the others.
    let soem = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/soem/soem_cycle");
    cfg.soem = Some(soem.clone());
    let report = harness::run(&cfg, &|what| eprintln!("jitter: {what}")).expect("veth run");
    assert!(report.priority_granted, "{:?}", report.warnings);
    assert_eq!(report.settings.transport, "veth");
    assert!(report.settings.interface.is_some());
    let rep = &report.repetitions[0];
    match &rep.soem {
        None => {
            assert!(!soem.exists());
            let why = report.soem_absent.as_deref().unwrap_or_default();
            assert!(why.contains("benches/soem/build.sh"), "{why}");
        }
        Some(s) => {
            assert!(s.exchange.is_some_and(|e| e.count > 0));
            assert_eq!(s.drives.len(), 2, "the far end is the harness's");
            assert_eq!(s.structure.master_threads, ["soem_cycle"]);
            assert!(rep.ratios.ecdrive_to_soem.is_some());
        }
    }
    // Over veth the emulated slaves are a thread of the harness: charged to no master.
    for r in [&rep.ethercrab, &rep.ecdrive] {
        assert!(r.structure.slaves.contains("charged to no master"));
        assert!(
            r.cpu
                .threads
                .iter()
                .all(|t| t.role != harness::cpu::ThreadRole::Master
                    || !t.name.starts_with(harness::cpu::FAR_END_THREAD)),
            "{:?}",
            r.cpu.threads
        );
    }
    let report_runs = rep.runs();
    for r in report_runs {
        assert!(r.wake_latency.count > 0 && r.busy.count > 0, "{}", r.name);
        assert!(r.cpu.master_ns.is_some(), "{}", r.name);
    }
    for r in [&rep.ethercrab, &rep.ecdrive] {
        assert!(r.exchange.is_some_and(|e| e.count > 0), "{}", r.name);
        assert_eq!(
            r.drives.len(),
            2,
            "{}: the far end is the harness's",
            r.name
        );
        assert!(r.drives[1].dc_difference.is_some(), "{}", r.name);
        assert!(r.drives.iter().all(|d| d.arrival_after_sync0.is_some()));
    }
    // Over a wire the TX/RX thread only moves frames; ecdrive's cycle thread does it itself.
    assert!(rep.ethercrab.cpu.io_thread_ns.is_some());
    assert!(rep.ecdrive.cpu.io_thread_ns.is_none());
    roxmltree::Document::parse(&harness::svg::render(&report)).expect("SVG");
}
