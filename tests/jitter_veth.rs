//! The jitter harness over a veth pair it creates (root): the emulated drives on the far end
//! inside a network namespace, every run on the host end. Skipped loudly without root, fails
//! without root under `ECDRIVE_CI`. No timing is asserted.

use ecdrive::app::harness::{self, JitterConfig, Transport};
use ecdrive::link::netns::require_root;
use std::time::Duration;

#[test]
fn every_figure_over_veth() {
    if !require_root("jitter_veth::every_figure_over_veth") {
        return;
    }
    let mut cfg = JitterConfig::new(Duration::from_millis(1));
    cfg.cycles = 300;
    cfg.transport = Transport::Veth;
    let report = harness::run(&cfg, &|what| eprintln!("jitter: {what}")).expect("veth run");
    assert!(report.priority_granted, "{:?}", report.warnings);
    assert_eq!(report.settings.transport, "veth");
    assert!(report.settings.interface.is_some());
    for r in [&report.sleep, &report.ethercrab, &report.ecdrive] {
        assert!(r.wake_latency.count > 0 && r.busy.count > 0, "{}", r.name);
        assert!(r.cpu.master_ns.is_some(), "{}", r.name);
    }
    for r in [&report.ethercrab, &report.ecdrive] {
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
    assert!(report.ethercrab.cpu.io_thread_ns.is_some());
    assert!(report.ecdrive.cpu.io_thread_ns.is_none());
    roxmltree::Document::parse(&harness::svg::render(&report)).expect("SVG");
}
