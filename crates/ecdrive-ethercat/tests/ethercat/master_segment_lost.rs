//! The segment stopping in the middle of OP: detected within three cycles, the error names the
//! drives, nothing panics, and the master starts again when the segment is back.

use crate::support;
use ecdrive_core::cia402::State;
use ecdrive_ethercat::cycle::CycleEnd;
use ecdrive_ethercat::session::{
    HistoryEntry, HistoryEvent, HistoryKind, Master, MasterConfig, RestartNote, RestartPolicy,
};
use ecdrive_ethercat::startup::{DriveSetup, Selector};
use ecdrive_ethercat::telemetry::{Axes, Command, EventKind, Phase, StopKind};
use ecdrive_sim::transport::SegmentLink;
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
    // The cycle ends by itself once the segment stayed silent for `segment_gone_after`.
    let (report, link) = m.join();
    let report = report.unwrap();
    let cycle = report.cycle.unwrap();
    assert_eq!(cycle.end, CycleEnd::SegmentLost);
    assert!(cycle.cycles >= before);
    // Detected within three cycles: the segment-lost entry comes with the third lost cycle.
    let first_lost = report
        .history
        .iter()
        .find(|h| matches!(h.cycle_event(), Some(EventKind::FrameLost { .. })))
        .expect("a lost-frame entry");
    let lost = report
        .history
        .iter()
        .find(|h| matches!(h.cycle_event(), Some(EventKind::SegmentLost { .. })))
        .expect("a segment-lost entry");
    assert!(lost.error);
    assert!(
        lost.cycle.unwrap() - first_lost.cycle.unwrap() <= 2,
        "first lost cycle {:?}, segment lost at {:?}",
        first_lost.cycle,
        lost.cycle
    );
    // Both name the drives (the lost frames: those that held their set-points).
    for e in [lost, first_lost] {
        let named: Vec<(u16, &str)> = e
            .resolved
            .drives
            .iter()
            .map(|d| (d.position, d.name.as_str()))
            .collect();
        assert_eq!(
            named,
            [(0, "generic test device"), (1, "generic test device")],
            "{e}"
        );
    }
    assert!(
        report
            .history
            .iter()
            .any(|h| matches!(h.cycle_event(), Some(EventKind::SegmentGone { .. }))),
        "{:#?}",
        report.history
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

fn texts(m: &Master<PullableLink<SegmentLink>>) -> Vec<String> {
    m.history().iter().map(HistoryEntry::text).collect()
}

#[test]
fn after_a_cable_pull_a_restart_on_request_brings_the_drives_back_to_op() {
    let pulled = Arc::new(AtomicBool::new(false));
    let link = PullableLink {
        inner: SegmentLink::new(generic_segment(2)),
        pulled: pulled.clone(),
    };
    let mut cfg = config();
    cfg.restart = RestartPolicy::OnRequest;
    cfg.bus.loss.frame_timeout_ns = 5_000_000;
    let mut m = Master::start(link, cfg).unwrap();
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    m.command(Command::Enable(Axes::All)).unwrap();
    m.wait_until("enabled", Duration::from_secs(10), |t| {
        t.axes
            .iter()
            .all(|a| a.state == Some(State::OperationEnabled))
    })
    .unwrap();
    pulled.store(true, Ordering::Relaxed);
    // The session stays, waiting for a request.
    m.wait_until("waiting for a re-start", Duration::from_secs(10), |t| {
        t.cycle.phase == Phase::WaitingForRestart
    })
    .unwrap();
    assert!(m.is_running());
    // Commands other than restart/stop are refused, in the history.
    m.command(Command::Enable(Axes::All)).unwrap();
    // A re-start while the cable is still out fails cleanly and is recorded.
    m.restart().unwrap();
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    while !texts(&m)
        .iter()
        .any(|t| t.starts_with("re-start attempt 1 failed"))
    {
        assert!(std::time::Instant::now() < deadline, "{:#?}", texts(&m));
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(
        m.history().iter().any(|h| h.kind == HistoryKind::NoCycle
            && h.error
            && h.event
                == HistoryEvent::NoCycle {
                    command: Command::Enable(Axes::All).to_string()
                }),
        "{:#?}",
        texts(&m)
    );
    // Cable back, request again: the same master, the same handles, back in OP.
    pulled.store(false, Ordering::Relaxed);
    m.wait_until("waiting again", Duration::from_secs(10), |t| {
        t.cycle.phase == Phase::WaitingForRestart
    })
    .unwrap();
    m.restart().unwrap();
    let r = m.wait_until("OP after the re-start", Duration::from_secs(20), |t| {
        t.cycle.all_op && t.cycle.restarts == 1 && t.cycle.phase == Phase::Cycling
    });
    if let Err(e) = r {
        let c = m.telemetry().cycle;
        panic!("{e}: {c:?} {:#?}", texts(&m));
    }
    // The axes come back disabled (a device that kept its CiA 402 state through the pull is
    // disabled by the master); enabling them works again.
    m.wait_until(
        "the axes disabled after the re-start",
        Duration::from_secs(10),
        |t| {
            t.axes
                .iter()
                .all(|a| a.state != Some(State::OperationEnabled))
        },
    )
    .unwrap();
    m.command(Command::Enable(Axes::All)).unwrap();
    m.wait_until("enabled again", Duration::from_secs(10), |t| {
        t.axes
            .iter()
            .all(|a| a.state == Some(State::OperationEnabled))
    })
    .unwrap();
    let (report, _) = m.stop(StopKind::Ramp);
    let report = report.unwrap();
    assert_eq!(report.restarts, 1);
    assert!(report.shutdown_ok);
    assert_eq!(report.cycle.unwrap().end, CycleEnd::Stopped);
    let h: Vec<String> = report.history.iter().map(HistoryEntry::text).collect();
    let expected: [support::Expected; 6] = [
        ("the segment stopped answering", &|e| {
            matches!(e, HistoryEvent::Cycle(EventKind::SegmentLost { .. }))
        }),
        ("the segment stayed silent", &|e| {
            matches!(e, HistoryEvent::Cycle(EventKind::SegmentGone { .. }))
        }),
        ("waiting for a re-start request", &|e| {
            *e == HistoryEvent::Restart(RestartNote::WaitingForRequest)
        }),
        ("re-start attempt 1 failed", &|e| {
            matches!(
                e,
                HistoryEvent::Restart(RestartNote::AttemptFailed { attempt: 1, .. })
            )
        }),
        ("re-start: the same 2 drives", &|e| {
            *e == HistoryEvent::Restart(RestartNote::SameDrives { drives: 2 })
        }),
        ("re-start 1: every drive is back in OP", &|e| {
            *e == HistoryEvent::Restart(RestartNote::BackInOp { restart: 1 })
        }),
    ];
    for (want, is) in expected {
        assert!(
            report.history.iter().any(|e| is(&e.event)),
            "{want}: {h:#?}"
        );
    }
}

#[test]
fn after_a_cable_pull_an_automatic_restart_brings_the_drives_back_to_op() {
    let pulled = Arc::new(AtomicBool::new(false));
    let link = PullableLink {
        inner: SegmentLink::new(generic_segment(2)),
        pulled: pulled.clone(),
    };
    let mut cfg = config();
    cfg.restart = RestartPolicy::Auto {
        retry_every: Duration::from_millis(100),
        max_attempts: None,
    };
    cfg.bus.loss.frame_timeout_ns = 5_000_000;
    let mut m = Master::start(link, cfg).unwrap();
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    pulled.store(true, Ordering::Relaxed);
    m.wait_until("the cycle ended", Duration::from_secs(10), |t| {
        t.cycle.phase == Phase::Restarting
    })
    .unwrap();
    // Let a few attempts fail, then put the cable back.
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    while !texts(&m)
        .iter()
        .any(|t| t.starts_with("re-start attempt 2 failed"))
    {
        assert!(std::time::Instant::now() < deadline, "{:#?}", texts(&m));
        std::thread::sleep(Duration::from_millis(10));
    }
    pulled.store(false, Ordering::Relaxed);
    m.wait_until("OP after the re-start", Duration::from_secs(20), |t| {
        t.cycle.all_op && t.cycle.restarts == 1
    })
    .unwrap();
    let (report, _) = m.stop(StopKind::Ramp);
    let report = report.unwrap();
    assert_eq!(report.restarts, 1);
    assert!(report.shutdown_ok);
}
