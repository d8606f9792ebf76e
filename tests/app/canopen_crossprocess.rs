//! The virtual bus across processes: this test binary re-executes itself as the node side (an
//! emulated BLV-R served on a Unix-socket hub port, the ignored test [`node_process`], run
//! alone) while the parent runs the master on its own port of the same hub, in real time. No
//! vcan, only sockets of this machine.
//!
//! Timeouts are generous failure guards, not timing assertions.

use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig};
use ecdrive::canopen::nmt::NmtState;
use ecdrive::canopen::unix_bus::{UnixBusHub, UnixBusPort};
use ecdrive::cia402::SetPoint;
use ecdrive::drives::blv_r;
use ecdrive::od::{ObjectAddress, Value};
use ecdrive::sim::canopen::{self as emu, EmulatedNode};
use ecdrive_cli::app::canopen::steps;
use ecdrive_cli::app::canopen::tools;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

const CHILD_ENV: &str = "ECDRIVE_CANOPEN_NODE_HUB";
const NODE: u8 = 5;
const GUARD: Duration = Duration::from_secs(60);

fn child(hub: &str) {
    let mut port = UnixBusPort::connect(Path::new(hub)).expect("connect to the hub");
    let mut nodes =
        vec![EmulatedNode::new(&ecdrive::sim::canopen::drives::blv_r::SPEC, NODE).expect("node")];
    let start = Instant::now();
    emu::serve(&mut port, &mut nodes, 250, |n| {
        n[0].nmt_state() != NmtState::Stopped && start.elapsed() < GUARD
    })
    .expect("serve");
    // Report what the node saw, for the parent's log.
    let n = &nodes[0];
    println!(
        "child: node {} ended in {:?}/{:?} at position {}, {} SDO requests, {} RPDOs",
        n.id(),
        n.nmt_state(),
        n.state(),
        n.position(),
        n.stats().sdo_requests,
        n.stats().rpdos_applied
    );
    assert_eq!(n.position(), 3600, "the move reached the node");
}

/// The master side: the hub, the node process, the master on its own port.
fn parent() {
    let dir = std::env::temp_dir().join(format!("ecdrive-canopen-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let hub_path = dir.join("hub.sock");
    let hub = UnixBusHub::spawn(&hub_path).expect("hub");
    let port = UnixBusPort::connect(&hub_path).expect("master port");
    let exe = std::env::current_exe().expect("own path");
    let mut child = Command::new(exe)
        .args([
            "canopen_crossprocess::node_process",
            "--exact",
            "--ignored",
            "--nocapture",
        ])
        .env(CHILD_ENV, &hub_path)
        .spawn()
        .expect("spawn the node process");

    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut m = Master::new(
            port,
            MasterConfig {
                cycle_us: 4_000,
                ..MasterConfig::default()
            },
        );
        let t0 = Instant::now();
        while m.boot_ups(NODE) == 0 {
            assert!(t0.elapsed() < GUARD, "no boot-up from the node process");
            m.pump(10_000).unwrap();
        }
        let found = tools::scan(&mut m, 1..=10).unwrap();
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].node, NODE);
        assert_eq!(found[0].profile.map(|p| p.name), Some("BLV-R"));
        assert_eq!(
            tools::upload(&mut m, NODE, ObjectAddress::new(0x1008, 0), None).unwrap(),
            Value::Str("BLVD-KRD".into())
        );
        let mut setup = DriveSetup::new(&blv_r::PROFILE);
        setup.settings = steps::motion_settings(&blv_r::PROFILE, 10.0, 100.0);
        m.configure_drive(NODE, setup).unwrap();
        m.start(NODE).unwrap();
        let guard = GUARD.as_micros() as u64;
        m.enable(NODE, guard).unwrap();
        let pos = steps::move_pp(&mut m, NODE, &[SetPoint::absolute(3600)], guard).unwrap();
        assert_eq!(pos, 3600);
        // Disable through the controlword, then NMT Stop: the node process ends.
        m.shutdown_node(NODE, guard).unwrap();
    }));
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break Some(s);
        }
        if t0.elapsed() > GUARD {
            let _ = child.kill();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    drop(hub);
    let _ = std::fs::remove_dir_all(&dir);
    if let Err(e) = result {
        std::panic::resume_unwind(e);
    }
    let status = status.expect("the node process did not end after NMT Stop");
    assert!(status.success(), "node process: {status}");
}

#[test]
fn master_and_node_in_two_processes() {
    parent();
}

/// The node side, in the process [`master_and_node_in_two_processes`] starts.
#[test]
#[ignore = "the node side of master_and_node_in_two_processes, which runs it in a process of its own"]
fn node_process() {
    let hub = std::env::var(CHILD_ENV).expect("run by master_and_node_in_two_processes");
    child(&hub);
}
