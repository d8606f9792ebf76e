//! The segment stopping in the middle of OP: detected within three cycles, the error names the
//! drives, nothing panics, and the master starts again when the segment is back.

mod support {
    pub mod generic;
}
use ecdrive::master::cycle::CycleEnd;
use ecdrive::master::session::{Master, MasterConfig};
use ecdrive::master::startup::{DriveSetup, Selector};
use ecdrive::master::telemetry::StopKind;
use ecdrive::sim::transport::SegmentLink;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use support::generic::{GENERIC_TEST, PullableLink, generic_segment};

fn config() -> MasterConfig {
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    for p in 0..2 {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            ..DriveSetup::new(Selector::Position(p))
        });
    }
    cfg
}

#[test]
fn cable_pull_is_detected_within_three_cycles_and_the_master_restarts() {
    let pulled = Arc::new(AtomicBool::new(false));
    let link = PullableLink {
        inner: SegmentLink::new(generic_segment(2)),
        pulled: pulled.clone(),
    };
    let mut m = Master::start(link, config()).unwrap();
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let before = m.telemetry().cycle.cycle;
    pulled.store(true, Ordering::Relaxed);
    // The cycle ends by itself.
    let (report, link) = m.join();
    let report = report.unwrap();
    let cycle = report.cycle.unwrap();
    assert_eq!(cycle.end, CycleEnd::SegmentLost);
    // Detected within three cycles of the last good exchange.
    assert!(
        cycle.lost <= 3,
        "lost {} cycles before giving up",
        cycle.lost
    );
    assert!(cycle.cycles >= before);
    let lost = report
        .history
        .iter()
        .find(|h| h.text.starts_with("the segment stopped answering"))
        .expect("a segment-lost entry");
    assert!(lost.error);
    assert!(
        lost.text.contains("drive 0 (generic test device)")
            && lost.text.contains("drive 1 (generic test device)"),
        "{}",
        lost.text
    );
    assert!(!report.shutdown_ok);

    // Cable back in: a new master on the same link reaches OP again.
    pulled.store(false, Ordering::Relaxed);
    let mut m = Master::start(link, config()).unwrap();
    m.wait_until("OP again", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let (report, _) = m.stop(StopKind::Ramp);
    assert!(report.unwrap().shutdown_ok);
}

#[test]
fn starting_on_a_dead_segment_fails_cleanly_and_returns_the_link() {
    let pulled = Arc::new(AtomicBool::new(true));
    let link = PullableLink {
        inner: SegmentLink::new(generic_segment(1)),
        pulled: pulled.clone(),
    };
    let mut cfg = config();
    cfg.startup.drives.truncate(1);
    cfg.bus.loss.frame_timeout_ns = 5_000_000;
    let err = match Master::start(link, cfg.clone()) {
        Ok(_) => panic!("started on a dead segment"),
        Err(e) => e,
    };
    assert!(
        err.error
            .to_string()
            .starts_with("discovering the segment on"),
        "{}",
        err.error
    );
    pulled.store(false, Ordering::Relaxed);
    let m = Master::start(err.link, cfg).unwrap();
    let (r, _) = m.stop(StopKind::Ramp);
    assert!(r.is_some());
}
