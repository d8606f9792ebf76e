//! The master over a real raw socket: the software slave serves a segment on one end of a veth
//! pair inside a network namespace the test creates; the master runs on the other end.

use crate::support;
use ecdrive_core::link::netns::{VethPair, require_root};
use ecdrive_ethercat::cycle::CycleEnd;
use ecdrive_ethercat::session::{Master, MasterConfig};
use ecdrive_ethercat::startup::{DriveSetup, Selector};
use ecdrive_ethercat::telemetry::StopKind;
use ecdrive_sim::transport::RawServer;
use std::time::Duration;
use support::generic::{GENERIC_TEST, generic_segment};

#[test]
fn master_reaches_op_over_veth_and_stops_to_init() {
    if !require_root("master_veth::master_reaches_op_over_veth_and_stops_to_init") {
        return;
    }
    let veth = VethPair::create().expect("veth pair");
    let server = RawServer::spawn(
        veth.open_peer_socket().expect("peer socket"),
        generic_segment(2),
    )
    .expect("server");
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    for p in 0..2 {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            ..DriveSetup::new(Selector::Position(p))
        });
    }
    // A loaded CI machine can delay a reply by milliseconds: allow more than the default
    // budget before counting a cycle as lost.
    cfg.cycle.segment_lost_after = 50;
    let socket = veth.open_host_socket().expect("host socket");
    let mut m = Master::start(socket, cfg).expect("start-up over veth");
    m.wait_until("OP", Duration::from_secs(20), |t| t.cycle.all_op)
        .unwrap();
    let c0 = m.telemetry().cycle.cycle;
    m.wait_until("100 cycles in OP", Duration::from_secs(20), |t| {
        t.cycle.cycle > c0 + 100
    })
    .unwrap();
    let (report, _) = m.stop(StopKind::Ramp);
    let report = report.unwrap();
    assert_eq!(report.cycle.as_ref().unwrap().end, CycleEnd::Stopped);
    assert!(report.shutdown_ok);
    let (segment, served) = server.stop();
    served.expect("the server ran without a link error");
    for p in 0..2 {
        assert_eq!(
            segment.slave(p).unwrap().esc.al_state(),
            ecdrive_core::ec::AlState::Init
        );
    }
}
