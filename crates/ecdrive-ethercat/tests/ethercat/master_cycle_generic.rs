//! The cycle against emulated generic CoE devices (not drives): the cycle takes them from
//! SAFE-OP to OP, keeps the working counter right, and a stop takes them to INIT.

use crate::support;
use ecdrive_ethercat::program::RunMode;
use ecdrive_ethercat::session::{Master, MasterConfig};
use ecdrive_ethercat::startup::{DriveSetup, Selector};
use ecdrive_ethercat::telemetry::{EventKind, StopKind};
use ecdrive_sim::transport::SegmentLink;
use std::time::Duration;
use support::generic::{GENERIC_TEST, generic_segment};

#[test]
fn cycle_reaches_op_and_stops_to_init() {
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    for p in 0..3 {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            mode: RunMode::Csp,
            ..DriveSetup::new(Selector::Position(p))
        });
    }
    let mut m = Master::start(SegmentLink::new(generic_segment(3)), cfg).unwrap();
    assert_eq!(m.drives().len(), 3);
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    // Some cycles in OP with the right working counter (3 per device: outputs 2 + inputs 1).
    let c0 = m.telemetry().cycle.cycle;
    m.wait_until("50 cycles in OP", Duration::from_secs(10), |t| {
        t.cycle.cycle > c0 + 50
    })
    .unwrap();
    let t = m.telemetry().clone();
    assert_eq!(t.cycle.wkc_expected, 9);
    let (report, link) = m.stop(StopKind::Ramp);
    let report = report.unwrap();
    assert!(report.shutdown_ok);
    let cyc = report.cycle.unwrap();
    assert_eq!(cyc.end, ecdrive_ethercat::cycle::CycleEnd::Stopped);
    assert!(
        report
            .history
            .iter()
            .any(|h| h.cycle_event() == Some(&EventKind::AllOp)),
        "{:#?}",
        report.history
    );
    assert!(
        !report
            .history
            .iter()
            .any(|h| matches!(h.cycle_event(), Some(EventKind::WorkingCounter { .. }))),
        "{:#?}",
        report.history
    );
    for p in 0..3 {
        assert_eq!(
            link.segment().slave(p).unwrap().esc.al_state(),
            ecdrive_core::ec::AlState::Init
        );
    }
}
