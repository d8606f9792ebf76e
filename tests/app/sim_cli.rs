//! `ecdrive sim` end to end: the binary serves a generic CoE device and a generic I/O device on
//! one end of a veth pair (inside a network namespace); plain ethercrab on the other end finds
//! them; Ctrl-C (SIGINT) stops the binary cleanly with its frame count.

use ecdrive::link::netns::{VethPair, require_root};
use ethercrab::std::ethercat_now;
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};
use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};
use std::time::Duration;

#[test]
fn ecdrive_sim_serves_devices_until_ctrl_c() {
    if !require_root("sim_cli::ecdrive_sim_serves_devices_until_ctrl_c") {
        return;
    }
    let veth = VethPair::create().expect("veth pair");
    let mut child = Command::new("ip")
        .args(["netns", "exec", veth.netns().name()])
        .arg(env!("CARGO_BIN_EXE_ecdrive"))
        .args(["sim", "--interface", veth.peer(), "--device", "generic-coe"])
        .args(["--device", "generic-io", "--sm-watchdog", "0"])
        .stderr(Stdio::piped())
        .spawn()
        .expect("start ecdrive sim");
    let mut stderr = BufReader::new(child.stderr.take().expect("stderr"));
    let mut banner = String::new();
    let mut line = String::new();
    while stderr.read_line(&mut line).expect("read stderr") > 0 {
        banner.push_str(&line);
        if line.contains("1: ECD-IO") {
            break;
        }
        line.clear();
    }
    assert!(banner.contains("serving 2 device(s)"), "{banner}");
    assert!(banner.contains("0: ECD-COE402"), "{banner}");

    let storage: &'static PduStorage<16, { PduStorage::element_size(1100) }> =
        Box::leak(Box::new(PduStorage::new()));
    let (tx, rx, pdu_loop) = storage.try_split().expect("split");
    let md = MainDevice::new(
        pdu_loop,
        Timeouts {
            pdu: Duration::from_millis(2000),
            eeprom: Duration::from_millis(500),
            ..Timeouts::default()
        },
        MainDeviceConfig {
            dc_static_sync_iterations: 10,
            ..MainDeviceConfig::default()
        },
    );
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let names = rt.block_on(async {
        let task = ethercrab::std::tx_rx_task(veth.host(), tx, rx).expect("tx/rx task");
        let handle = tokio::spawn(task);
        let group = md
            .init_single_group::<4, 32>(ethercat_now)
            .await
            .expect("init against ecdrive sim");
        let names: Vec<String> = group.iter(&md).map(|s| s.name().to_string()).collect();
        handle.abort();
        names
    });
    assert_eq!(names, vec!["ECD-COE402", "ECD-IO"]);

    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGINT,
    )
    .expect("SIGINT");
    let status = child.wait().expect("wait");
    let mut rest = String::new();
    stderr.read_to_string(&mut rest).expect("read stderr");
    assert!(status.success(), "exit status {status}: {rest}");
    assert!(rest.contains("stopped;"), "{rest}");
    assert!(rest.contains("frames answered"), "{rest}");
}
