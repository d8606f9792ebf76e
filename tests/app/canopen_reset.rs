//! `ecdrive reset` on CANopen drives: a latched fault named with the drive's alarm table and
//! cleared, read back from the emulated node itself; the command over a `vbus:` bus served by
//! another process, after a run left the nodes in NMT Stopped.

use crate::support;

use ecdrive::cia402::State;
use ecdrive_cli::app::canopen::demo::demo_alarm;
use ecdrive_cli::app::canopen::reset::{CanResetOptions, reset};
use ecdrive_cli::app::canopen::tools::{DEMO_NODES, demo_bus};
use support::cli::ecdrive;

/// Every drive with an alarm latched: each is named with its error code and the alarm its
/// table gives, gets the reset edge and leaves Fault — and the node says so too (its alarm
/// gone, Switch on disabled).
#[test]
fn each_canopen_drives_latched_fault_is_named_and_cleared() {
    let mut bus = demo_bus();
    for (node, p) in DEMO_NODES {
        let number = demo_alarm(p).expect("an alarm");
        assert!(bus.node_mut(node).expect("node").inject_alarm(number));
    }
    let r = reset(&mut bus, "virtual", &CanResetOptions::default()).expect("reset");
    eprintln!("{r:#?}");
    assert_eq!(r.drives.len(), 3, "{r:?}");
    assert!(r.all_clear, "{r:?}");
    for d in &r.drives {
        let p = DEMO_NODES
            .iter()
            .find(|(n, _)| *n == d.node)
            .map(|(_, p)| *p)
            .expect("a demo node");
        let alarm = demo_alarm(p).and_then(|n| p.alarm(n)).expect("an alarm");
        assert_eq!(d.before, "Fault", "{d:?}");
        let fault = d.fault.as_deref().expect("the fault named");
        assert!(
            fault.contains(&format!("error code 0x{:04X}", alarm.code)),
            "{}: {fault} (alarm {alarm:?})",
            p.name
        );
        assert!(
            fault.contains(&format!("{} {}", alarm.name, alarm.text)),
            "{}: {fault} does not name {} {}",
            p.name,
            alarm.name,
            alarm.text
        );
        assert_eq!(d.cleared, Some(true), "{d:?}");
        assert_eq!(d.after, "Switch on disabled", "{d:?}");
        let n = bus.node(d.node).expect("node");
        assert!(n.alarm().is_none(), "{}: {:?}", p.name, n.alarm());
        assert_eq!(n.state(), State::SwitchOnDisabled, "{}", p.name);
    }
}

/// No drive in Fault: each is reported as it is, nothing else happens.
#[test]
fn reset_without_a_fault_reports_each_drive() {
    let mut bus = demo_bus();
    let r = reset(&mut bus, "virtual", &CanResetOptions::default()).expect("reset");
    assert_eq!(r.drives.len(), 3);
    assert!(
        r.drives
            .iter()
            .all(|d| d.fault.is_none() && d.cleared.is_none())
    );
    assert!(r.all_clear);
}

/// The command as docs/guide/run.md gives it, over `vbus:` against `ecdrive sim --can` in another
/// process: after a run that left the nodes in NMT Stopped (so they answer no SDO), `reset`
/// takes them to Pre-operational, finds each drive, reports it, exits 0; `upload` then works
/// again, and so does another run; a node that is not there is named in one line, exit 3.
#[test]
fn reset_over_vbus_after_a_run_left_the_nodes_stopped() {
    let dir = std::env::temp_dir().join(format!("ecdrive-can-reset-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let bus = format!("vbus:{}", dir.join("bus.sock").display());
    let (mut child, _) =
        support::cli::serve_can(&bus, &["--node", "blv-r@3", "--node", "asda-a2"], 2);
    let file = dir.join("run.toml");
    std::fs::write(
        &file,
        "interface = \"can-sim\"\n[[drive]]\nnode = 3\nprofile = \"blv-r\"\n\
         program = [{ step = \"pp\", to = [36000], velocity = 360000, acceleration = 3600000 }]\n",
    )
    .expect("write");
    let path = file.display().to_string();
    let run = ecdrive(&["run", "-c", &path, "-i", &bus, "--json"]);
    let stopped = ecdrive(&["upload", "--can", &bus, "-n", "3", "0x6041:00"]);
    let reset = ecdrive(&["reset", "--can", &bus]);
    let after = ecdrive(&["upload", "--can", &bus, "-n", "3", "0x6041:00"]);
    // And a run again after the reset (the run's life guarding starts afresh).
    let again = ecdrive(&["run", "-c", &path, "-i", &bus, "--json"]);
    let absent = ecdrive(&["reset", "--can", &bus, "-n", "9"]);
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
    let _ = child.wait();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert_ne!(
        stopped.code,
        Some(0),
        "a Stopped node answered: {}",
        stopped.stdout
    );
    assert!(
        stopped.stderr.contains("ecdrive reset --can"),
        "the refusal says how to get the node back: {}",
        stopped.stderr
    );
    assert_eq!(reset.code, Some(0), "{}{}", reset.stdout, reset.stderr);
    assert!(
        reset
            .stdout
            .contains("node 3 (BLV-R): Switch on disabled, no fault"),
        "{}",
        reset.stdout
    );
    assert!(
        reset.stdout.contains("node 127 (ASDA-A2)"),
        "{}",
        reset.stdout
    );
    assert_eq!(after.code, Some(0), "{}", after.stderr);
    assert_eq!(again.code, Some(0), "{}{}", again.stdout, again.stderr);
    assert_eq!(absent.code, Some(3), "{}", absent.stderr);
    assert_eq!(absent.stderr.lines().count(), 1, "{}", absent.stderr);
    assert!(
        absent.stderr.contains("node 9 (0x09)") && absent.stderr.contains("does not answer"),
        "{}",
        absent.stderr
    );
}
