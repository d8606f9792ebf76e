//! The master against behaviour it did not write: each foreign-device quirk of the software
//! slave (`sim::quirks`), and a mixed segment with an I/O device between the drives. Every case
//! runs in-process; the ones the issue names also over a veth pair against `ecdrive sim`.
//!
//! What the master must do (issue "any configuration, any device"):
//! - walk the standard CiA 402 transitions, so that drives without state skipping enable;
//! - read the synchronisation objects before writing them, go on with a warning when a drive
//!   has none or keeps its cycle time read-only, and check the cycle time again once SYNC0 runs;
//! - list what SDO information it can and say what it could not;
//! - judge a drive's inputs only in OP, and keep the outputs safe before;
//! - compute its own following error and flag a 0x60F4 that stays 0;
//! - run every drive of a mixed segment, take the I/O devices to OP with their own mapping and
//!   never speak CoE to a device without a mailbox.

use crate::support;
use ecdrive::cia402::{self, State};
use ecdrive::master::session::{Master, MasterConfig};
use ecdrive::master::telemetry::{Axes, Command, EventKind, StopKind};
use ecdrive::master::{HistoryEvent, HistoryKind};
use ecdrive::sim::EscConfig;
use ecdrive::sim::run::build_segment;
use ecdrive::sim::transport::SegmentLink;
use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, RunReport, run};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use support::cli::{SimOnVeth, ecdrive};
use support::links::SendTap;

/// The runs share the machine's cores with their own cycle threads: one at a time.
static ONE_RUN_AT_A_TIME: Mutex<()> = Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_RUN_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// A configuration on emulated `devices` (in-process), the drives' own supervision of the
/// cyclic data off (the subject here is what the master does), `extra` appended.
fn config(devices: &[&str], extra: &str) -> String {
    let list = devices
        .iter()
        .map(|d| format!("{d:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    format!(
        "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [{list}]\nloss_detection = false\n{extra}"
    )
}

/// `text` with `allow_generic = true`.
fn generic(text: String) -> String {
    format!("allow_generic = true\n{text}")
}

/// A short csp move for the drive at `position`.
fn move_at(position: u16) -> String {
    format!(
        "[[drive]]\nposition = {position}\nprogram = [{{ step = \"move\", by = 200000, velocity = 400000, acceleration = 4000000 }}]\n"
    )
}

fn run_text(text: &str) -> RunReport {
    let cfg =
        ecdrive_cli::app::config::parse(text, "quirks.toml").unwrap_or_else(|e| panic!("{e}"));
    let stop = AtomicBool::new(false);
    run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
}

fn warnings(r: &RunReport) -> Vec<String> {
    r.history
        .iter()
        .filter(|h| h.kind == HistoryKind::Warning)
        .map(|h| {
            format!(
                "{}: {h}",
                h.drive.as_ref().map_or(String::new(), |d| d.to_string()),
            )
        })
        .collect()
}

#[track_caller]
fn completed(r: &RunReport) {
    assert_eq!(
        r.outcome,
        Outcome::Completed,
        "{}\n{:#?}",
        r.reason,
        r.history
    );
    assert!(r.shutdown_ok);
    for d in &r.drives {
        assert!(d.errors.is_empty(), "{}: {:?}", d.name, d.errors);
        assert_eq!(d.steps_done, d.program.len(), "{}", d.name);
    }
}

/// The MR-J4-TM and BDHDE profiles against drives that implement only the standard
/// transitions: both enable (through Ready to switch on and Switched on) and run their move.
#[test]
fn drives_without_state_skipping_enable_in_process() {
    let _one = one_at_a_time();
    let r = run_text(&config(
        &["mr-j4-tm+no-state-skipping", "bdhde+no-state-skipping"],
        &(move_at(0) + &move_at(1)),
    ));
    completed(&r);
    for d in &r.drives {
        for s in ["Ready to switch on", "Switched on", "Operation enabled"] {
            assert!(
                d.states.iter().any(|x| x == s),
                "{}: {:?}",
                d.name,
                d.states
            );
        }
    }
}

/// Drives that refuse OP (AL status code 0x002D) while SYNC0 is activated but has not fired:
/// the master requests OP only after the drives have had SYNC0 cycles (the MR-J4-TM manual
/// §1.4.2 (7): synchronisation in SAFE-OP, then valid command values, then OP). Two cycles of
/// valid outputs would come well before the first SYNC0 (the start delay is set to 11 ms
/// here); a master counting cycles alone would be refused.
#[test]
fn drives_that_need_sync0_before_op_reach_op() {
    let _one = one_at_a_time();
    let text = config(
        &["mr-j4-tm+op-needs-sync0", "bdhde+op-needs-sync0"],
        &format!(
            "[supervision]\nsafeop_cycles = 2\n{}{}",
            move_at(0),
            move_at(1)
        ),
    );
    let r = run_text(&format!("dc_start_delay = \"11ms\"\n{text}"));
    completed(&r);
    assert!(
        !r.history.iter().any(|h| matches!(
            h.cycle_event(),
            Some(EventKind::OpTimeout { .. } | EventKind::LeftOp { .. })
        ) || h.kind == HistoryKind::AlState
            || matches!(&h.event, HistoryEvent::Warning(w) if w.contains("0x002D"))),
        "{:#?}",
        r.history
    );
}

#[test]
fn drives_without_state_skipping_enable_over_veth() {
    let _one = one_at_a_time();
    let Some(sim) = SimOnVeth::start_with(
        "drives_without_state_skipping_enable_over_veth",
        &["mr-j4-tm+no-state-skipping", "bdhde+no-state-skipping"],
        &["--no-loss-detection"],
    ) else {
        return;
    };
    let dir = tempdir("skip");
    let file = dir.join("skip.toml");
    std::fs::write(
        &file,
        config(&["mr-j4-tm", "bdhde"], &(move_at(0) + &move_at(1))),
    )
    .unwrap();
    let j = sim.run_json(&file.display().to_string(), &[]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(j["outcome"], "completed", "{j:#}");
    for d in j["drives"].as_array().unwrap() {
        assert_eq!(d["steps_done"], 1, "{j:#}");
        assert!(
            d["states"]
                .as_array()
                .unwrap()
                .iter()
                .any(|s| s == "Switched on"),
            "{j:#}"
        );
    }
}

/// A read-only cycle time (0x1C32:02, as Ingenia's ESI declares it) on a drive run with the
/// generic CiA 402 profile: a warning naming the object, and the run goes on; once SYNC0 runs
/// the drive shows the cycle there and the master checks it.
#[test]
fn a_generic_run_against_a_read_only_cycle_time_in_process() {
    let _one = one_at_a_time();
    let r = run_text(&generic(config(
        &["generic-coe+cycle-time-read-only"],
        "[[drive]]\nposition = 0\nprogram = [{ step = \"move\", by = 1000, velocity = 20000, acceleration = 200000 }]\n",
    )));
    completed(&r);
    assert_eq!(r.drives[0].name, "generic CiA 402 drive");
    let w = warnings(&r);
    assert!(
        w.iter()
            .any(|w| w.contains("0x1C32:02 (cycle time) is read-only")),
        "{w:#?}"
    );
}

#[test]
fn a_generic_run_against_a_read_only_cycle_time_over_veth() {
    let _one = one_at_a_time();
    let Some(sim) = SimOnVeth::start_with(
        "a_generic_run_against_a_read_only_cycle_time_over_veth",
        &["generic-coe+cycle-time-read-only"],
        &[],
    ) else {
        return;
    };
    let dir = tempdir("ro");
    let file = dir.join("ro.toml");
    std::fs::write(
        &file,
        generic(config(
            &["generic-coe"],
            "[[drive]]\nposition = 0\nprogram = [{ step = \"move\", by = 1000, velocity = 20000, acceleration = 200000 }]\n",
        )),
    )
    .unwrap();
    let runs = sim.run_json_attempts(&file.display().to_string(), &[]);
    let _ = std::fs::remove_dir_all(&dir);
    let j = runs.last().unwrap();
    assert_eq!(j["outcome"], "completed", "{j:#}");
    // The first start-up meets the default the device keeps until SYNC0 runs; an attempt after
    // one that lost frames finds the SYNC0 cycle there already, as a device that takes the
    // cycle from SYNC0 shows it, and has nothing to write.
    let first = &runs[0];
    assert!(
        first["history"]
            .as_array()
            .unwrap()
            .iter()
            .any(|h| h["text"]
                .as_str()
                .unwrap()
                .contains("0x1C32:02 (cycle time) is read-only")),
        "{first:#}"
    );
}

/// The MR-J4-TM with a read-only cycle time that holds 250 µs before SYNC0 runs (its default):
/// compatible (the drive takes the cycle from SYNC0), a warning.
#[test]
fn a_profiled_drive_with_a_read_only_cycle_time_runs_with_a_warning() {
    let _one = one_at_a_time();
    let r = run_text(&config(&["mr-j4-tm+cycle-time-read-only"], &move_at(0)));
    completed(&r);
    let w = warnings(&r);
    assert!(
        w.iter().any(|w| w.contains("drive 0 (MR-J4-TM)")
            && w.contains("0x1C32:02 (cycle time) is read-only (holds 250000 ns)")),
        "{w:#?}"
    );
}

/// A drive without 0x1C32/0x1C33: a warning per object, and the run goes on.
#[test]
fn a_drive_without_sync_objects_runs_with_a_warning() {
    let _one = one_at_a_time();
    let r = run_text(&config(&["mr-j4-tm+sync-objects-absent"], &move_at(0)));
    completed(&r);
    let w = warnings(&r);
    for a in ["0x1C32:01", "0x1C32:02"] {
        assert!(
            w.iter().any(|w| w.contains(&format!("has no {a}"))),
            "{a}: {w:#?}"
        );
    }
}

/// A slave that serves stale inputs (zeros) until OP and applies the outputs already in
/// SAFE-OP: no error (no mode display mismatch in SAFE-OP), and the drive was not energised
/// before every device was in OP (the master keeps Disable voltage below OP).
#[test]
fn stale_inputs_and_outputs_applied_in_safe_op() {
    let _one = one_at_a_time();
    let quirks = "+stale-inputs-until-op+outputs-in-safeop";
    let text = config(
        &[&format!("mr-j4-tm{quirks}"), &format!("bdhde{quirks}")],
        &(move_at(0) + &move_at(1)),
    );
    // The BDHDE maps 0x6061 (mode display): remapped as the case, the MR-J4-TM too.
    let text = text.replace(
        "[[drive]]\nposition = 0\n",
        "[[drive]]\nposition = 0\nmapping = { rx = [{ pdo = 0x1600, entries = [\"0x6040:00\", \"0x607A:00\", \"0x6060:00\"] }], tx = [{ pdo = 0x1A00, entries = [\"0x6041:00\", \"0x6064:00\", \"0x6061:00\", { padding = 8 }] }] }\n",
    );
    let r = run_text(&text);
    completed(&r);
    let all_op = r
        .history
        .iter()
        .position(|h| h.cycle_event() == Some(&EventKind::AllOp))
        .expect("OP");
    for h in &r.history[..all_op] {
        assert!(
            !matches!(
                h.axis_event(),
                Some(cia402::Event::StateChanged {
                    to: Some(State::ReadyToSwitchOn | State::OperationEnabled),
                    ..
                })
            ),
            "energised below OP: {h:?}"
        );
    }
}

/// A 0x60F4 that stays 0 while the axis moves (and the master sees an error) is flagged and not
/// trusted: the master's own following error is reported (and checked) instead. A sine keeps
/// the axis accelerating, so that the error is never 0 for long.
#[test]
fn a_following_error_object_stuck_at_zero_is_flagged() {
    let _one = one_at_a_time();
    let long = "[[drive]]\nposition = 0\nprogram = [{ step = \"sine\", amplitude = 400000, frequency = 2, periods = 3 }]\n";
    let r = run_text(&config(&["mr-j4-tm+following-error-zero", "bdhde"], long));
    completed(&r);
    let d = &r.drives[0];
    assert!(d.following_error_drive_stuck, "{d:#?}");
    assert_eq!(d.max_following_error_drive, Some(0));
    assert!(d.max_following_error > 0, "{d:#?}");
    assert!(
        warnings(&r)
            .iter()
            .any(|w| w.contains("0x60F4 stayed 0") && w.contains("not trusted")),
        "{:#?}",
        warnings(&r)
    );
    // The BDHDE computes it: not flagged.
    assert!(!r.drives[1].following_error_drive_stuck);
}

/// The master's following error and the drive's own 0x60F4 agree within the drive's lag (a
/// one-cycle mismatch of the transport delay would add the distance of a cycle, 400 counts at
/// this speed).
#[test]
fn the_masters_following_error_agrees_with_the_drives() {
    let _one = one_at_a_time();
    let long = "[[drive]]\nposition = 0\nprogram = [{ step = \"move\", by = 1000000, velocity = 400000, acceleration = 4000000 }]\n";
    let r = run_text(&config(&["bdhde"], long));
    completed(&r);
    let d = &r.drives[0];
    let drive = d.max_following_error_drive.expect("0x60F4 mapped");
    assert!(drive > 0, "{d:#?}");
    assert!(
        (d.max_following_error - drive).abs() < 200,
        "master {} drive {drive}",
        d.max_following_error
    );
}

/// SDO information with a malformed entry, a short entry, or none at all: `sdos` lists the rest,
/// names what it could not read (text and JSON) and exits 6; with none, the profile's objects.
#[test]
fn sdos_lists_around_bad_entries() {
    for (q, addr, reason) in [
        (
            "sdo-info-bad-entry",
            "0x1018:02",
            "SDO information error 0x00000000",
        ),
        ("sdo-info-short-entry", "0x1018:03", "truncated"),
    ] {
        let target = format!("sim:generic-coe+{q}");
        let out = ecdrive(&["sdos", "-i", &target, "-p", "0"]);
        assert_eq!(out.code, Some(6), "{out:#?}");
        assert!(out.stdout.contains("SDO 0x6502"), "{out:#?}");
        assert!(
            out.stdout
                .contains(&format!("(not listed: entry description {addr}: ")),
            "{out:#?}"
        );
        let line = out.stderr.trim();
        assert!(!line.contains('\n'), "{line}");
        assert!(
            line.contains("the listing is incomplete") && line.contains(addr),
            "{line}"
        );
        assert!(line.contains(reason), "{line}");
        let j = ecdrive(&["sdos", "-i", &target, "-p", "0", "--json"]);
        assert_eq!(j.code, Some(6));
        let j: serde_json::Value = serde_json::from_str(&j.stdout).unwrap();
        assert_eq!(j["complete"], false);
        assert_eq!(j["problems"][0]["address"], addr);
        // 0x1018 itself is listed, without the broken entry.
        let id = j["objects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["index"] == 0x1018)
            .unwrap();
        assert!(
            id["entries"]
                .as_array()
                .unwrap()
                .iter()
                .all(|e| e["address"] != addr)
        );
        assert_eq!(id["entries"].as_array().unwrap().len(), 4);
    }
    // No SDO information: the MR-J4-TM's profile dictionary instead, complete.
    let out = ecdrive(&["sdos", "-i", "sim:mr-j4-tm+no-sdo-info", "-p", "0"]);
    assert_eq!(out.code, Some(0), "{out:#?}");
    assert!(out.stdout.contains("objects from the MR-J4-TM profile"));
    // A device without a profile and without SDO information: nothing to list, said in one line.
    ecdrive(&["sdos", "-i", "sim:generic-coe+no-sdo-info", "-p", "0"])
        .fails(4, &["drive 0", "no SDO information", "nothing to list"]);
}

#[test]
fn sdos_lists_around_a_bad_entry_over_veth() {
    let Some(sim) = SimOnVeth::start(
        "sdos_lists_around_a_bad_entry_over_veth",
        &["mr-j4-tm+sdo-info-bad-entry"],
    ) else {
        return;
    };
    let out = sim.ecdrive(&["sdos", "-p", "0"]);
    assert_eq!(out.code, Some(6), "{out:#?}");
    assert!(out.stdout.contains("SDO 0x6041"), "{out:#?}");
    assert!(out.stderr.contains("0x1018:02"), "{out:#?}");
}

/// An abort that arrives as CoE service 2 with reserved bits set in its command byte is still
/// an abort, decoded with its code.
#[test]
fn an_odd_abort_is_still_an_abort() {
    ecdrive(&[
        "download",
        "-i",
        "sim:mr-j4-tm+odd-abort",
        "-p",
        "0",
        "0x1000:00",
        "5",
    ])
    .fails(4, &["0x1000:00", "0x06010002"]);
}

/// Complete access refused although the SII advertises it: the master does not depend on it
/// (start-up, the cycle and single uploads work).
#[test]
fn no_complete_access_is_not_needed() {
    let _one = one_at_a_time();
    let r = run_text(&config(
        &["mr-j4-tm+no-complete-access", "bdhde+no-complete-access"],
        &(move_at(0) + &move_at(1)),
    ));
    completed(&r);
    let out = ecdrive(&[
        "upload",
        "-i",
        "sim:mr-j4-tm+no-complete-access",
        "-p",
        "0",
        "0x1018:02",
    ]);
    assert_eq!(out.code, Some(0), "{out:#?}");
}

/// (command, ADP, ADO, length) of a datagram.
type Seen = (u8, u16, u16, usize);

/// Records every datagram the master sends.
fn recording(seen: Arc<Mutex<Vec<Seen>>>) -> impl FnMut(&mut [u8]) + Send {
    move |frame: &mut [u8]| {
        if let Ok(eth) = ecdrive::ec::frame::EthernetFrame::new_checked(&*frame)
            && let Ok(ecat) = ecdrive::ec::frame::EthercatFrame::new_checked(eth.payload())
            && let Ok(mut seen) = seen.lock()
        {
            for d in ecat.datagrams().flatten() {
                seen.push((d.command_raw(), d.adp(), d.ado(), d.data_len()));
            }
        }
    }
}

/// A mixed segment, as in a real cell: two drives with an I/O device between them. The drives
/// run, the I/O device is in OP with its own process data (its inputs in the report), and no
/// mailbox traffic goes to it: nobody reads its SyncManager registers (a mailbox client's first
/// step) or its memory (where a mailbox would be).
#[test]
fn a_mixed_segment_runs_the_drives_and_exchanges_the_io() {
    let _one = one_at_a_time();
    let r = run_text(&config(
        &["mr-j4-tm", "generic-io", "bdhde"],
        &(move_at(0) + &move_at(2)),
    ));
    completed(&r);
    assert_eq!(r.drives.len(), 2);
    assert_eq!((r.drives[0].position, r.drives[1].position), (0, 2));
    assert_eq!(r.io.len(), 1);
    let io = &r.io[0];
    assert_eq!((io.position, io.outputs, io.inputs), (1, 2, 4));
    assert_eq!(io.why, "no mailbox");
    // The device's inputs: a cycle counter that ran, then the echo of its outputs.
    assert_eq!(io.last_inputs.len(), 4);
    assert_ne!(io.last_inputs[..2], [0, 0]);

    // The same segment through a recording link: no CoE to position 1 (station 0x1001).
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    cfg.emergency_poll = Some(Duration::from_millis(20));
    let names: Vec<String> = ["mr-j4-tm", "generic-io", "bdhde"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let link = SendTap::new(
        SegmentLink::new(build_segment(&names, &EscConfig::default()).unwrap()),
        recording(seen.clone()),
    );
    let mut m = Master::start(link, cfg).map_err(|f| f.error).unwrap();
    assert_eq!(m.drives().len(), 2);
    assert_eq!(m.io().len(), 1);
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    m.command(Command::Enable(Axes::All)).unwrap();
    m.wait_until("enabled", Duration::from_secs(5), |t| {
        t.axes
            .iter()
            .all(|a| a.state == Some(ecdrive::cia402::State::OperationEnabled))
    })
    .unwrap();
    // A hundred cycles in OP, enabled (counted, not timed): the master's mailbox polling runs.
    let c0 = m.telemetry().cycle.cycle;
    m.wait_until("100 cycles", Duration::from_secs(10), |t| {
        t.cycle.cycle >= c0 + 100
    })
    .unwrap();
    let (report, _) = m.stop(StopKind::Ramp);
    let report = report.unwrap();
    assert!(report.shutdown_ok);
    let seen = seen.lock().unwrap();
    const FPRD: u8 = 4;
    let to_io: Vec<_> = seen
        .iter()
        .filter(|(cmd, adp, ado, len)| {
            // The start-up reads every device's SyncManagers once, all 64 bytes from 0x0800
            // (to enable one its SII leaves off): not mailbox traffic.
            let sm_check = *cmd == FPRD && *ado == 0x0800 && *len == 0x40;
            *adp == 0x1001
                && !sm_check
                && ((*cmd == FPRD && (0x0800..0x0880).contains(ado)) || *ado >= 0x1000)
        })
        .collect();
    assert!(
        to_io.is_empty(),
        "mailbox traffic to the I/O device: {to_io:x?}"
    );
    // The drives' mailboxes were used (the check would see it).
    assert!(
        seen.iter()
            .any(|(cmd, adp, ado, _)| *adp == 0x1000 && *cmd == FPRD && *ado == 0x080D)
    );
}

#[test]
fn a_mixed_segment_runs_over_veth() {
    let _one = one_at_a_time();
    let Some(sim) = SimOnVeth::start_with(
        "a_mixed_segment_runs_over_veth",
        &["mr-j4-tm", "generic-io", "bdhde"],
        &["--no-loss-detection"],
    ) else {
        return;
    };
    let dir = tempdir("mixed");
    let file = dir.join("mixed.toml");
    std::fs::write(
        &file,
        config(
            &["mr-j4-tm", "generic-io", "bdhde"],
            &(move_at(0) + &move_at(2)),
        ),
    )
    .unwrap();
    let j = sim.run_json(&file.display().to_string(), &[]);
    let text = sim.ecdrive(&["run", "-c", &file.display().to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(j["outcome"], "completed", "{j:#}");
    assert_eq!(j["io"][0]["position"], 1, "{j:#}");
    assert_eq!(j["io"][0]["last_inputs"].as_array().unwrap().len(), 4);
    if text.code == Some(0) {
        assert!(
            text.stdout.contains("Device 1 ECD-IO") && text.stdout.contains("Last inputs:"),
            "{text:#?}"
        );
    }
}

fn tempdir(what: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("ecdrive-foreign-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// 0x60C2 on the BDHDE: the master writes the standard form the drive's own set-up example
/// uses (1 ms = 1 × 10^−3 s); a drive whose 0x60C2:02 is read-only at −4 (as the BDHDE's object
/// table prints it) gets 0x60C2:01 in its 250 µs unit instead, and reaches OP either way.
#[test]
fn the_bdhde_interpolation_period_in_either_form() {
    use ecdrive::ec::AlState;
    use ecdrive::od::{DataType, ObjectAddress};
    use ecdrive_cli::app::ethercat::tools::{self, StatesOptions, Target};
    for (device, value, index) in [
        ("bdhde", "1", "-3"),
        ("bdhde+interpolation-index-read-only", "4", "-4"),
    ] {
        let target = Target::Sim(vec![device.to_string()]);
        let (states, v, i) = tools::session(&target, |bus| {
            let s = tools::states(bus, &StatesOptions::new(AlState::Op))?;
            let v = tools::upload(
                bus,
                0,
                ObjectAddress::new(0x60C2, 1),
                Some(DataType::Unsigned8),
            )?;
            let i = tools::upload(
                bus,
                0,
                ObjectAddress::new(0x60C2, 2),
                Some(DataType::Integer8),
            )?;
            Ok((s, v.text, i.text))
        })
        .unwrap_or_else(|e| panic!("{device}: {e}"));
        assert!(states.iter().all(|s| s.ok), "{device}: {states:?}");
        assert_eq!((v.as_str(), i.as_str()), (value, index), "{device}");
    }
}
