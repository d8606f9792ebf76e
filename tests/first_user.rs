//! What a careful first user tripped over (issue 34), each a regression test: the file or the
//! run as the user wrote it, and what ecdrive must say or do.

use ecdrive::app::ethercat::tools::run::{Outcome, RunOptions, run};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

fn parse(text: &str) -> Result<ecdrive::app::config::RunConfig, ecdrive::app::config::ConfigError> {
    ecdrive::app::config::parse(text, "user.toml")
}

/// A controlword mapped twice passed every check, then the BDHDE took the second copy (0) and
/// never enabled; the run said only "not every axis reached Operation enabled". Now the file
/// is refused at the entry, naming the first one, and the library's start-up refuses the same
/// mapping given through the API.
#[test]
fn an_object_mapped_twice_is_refused_where_it_is_written() {
    let text = "interface = \"sim\"\n[sim]\ndevices = [\"bdhde\"]\n[[drive]]\nposition = 0\n\
        mapping = { rx = [{ pdo = 0x1600, entries = [\"0x6040:00\", \"0x6060:00\", \"0x607A:00\", \
        \"0x6040:00\"] }], tx = [{ pdo = 0x1A00, entries = [\"0x6041:00\", \"0x6064:00\"] }] }\n";
    let e = parse(text).unwrap_err();
    assert!(
        e.message
            .contains("0x6040:00 is mapped twice in the RxPDOs (also mapping.rx[0].entries[0])"),
        "{e}"
    );
    assert!(
        e.key
            .as_deref()
            .is_some_and(|k| k.contains("mapping.rx[0].entries[3]")),
        "{e}"
    );

    // The same mapping through the library: start-up refuses it before anything is written.
    let ok = text.replace(", \"0x6040:00\"] }]", "] }]");
    let mut cfg = parse(&ok).unwrap_or_else(|e| panic!("{e}"));
    let m = cfg.master.startup.drives[0].mapping.as_mut().unwrap();
    let mut rx = m.rx.to_vec();
    let mut entries = rx[0].entries.to_vec();
    entries.push(entries[0]);
    rx[0] = ecdrive::pdo::Pdo::owned(rx[0].index, entries);
    *m = ecdrive::pdo::Mapping::owned(rx, m.tx.to_vec());
    let stop = AtomicBool::new(false);
    let e = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap_err();
    assert!(
        e.to_string()
            .contains("0x6040:00 is mapped twice in the RxPDO"),
        "{e}"
    );
}

/// A drive that does not reach Operation enabled in time is named with the state it stays in,
/// its statusword and controlword and the usual causes (the README's promise), not only "not
/// every axis reached Operation enabled".
#[test]
fn an_enable_that_does_not_finish_says_where_each_drive_stands() {
    let text = "interface = \"sim\"\n[sim]\ndevices = [\"mr-j4-tm\", \"bdhde\"]\n\
        [[drive]]\nposition = 0\n[[drive]]\nposition = 1\n";
    let cfg = parse(text).unwrap_or_else(|e| panic!("{e}"));
    let opts = RunOptions {
        // No time at all: the first look after the enable command finds no drive enabled.
        enable_timeout: Duration::ZERO,
        ..RunOptions::default()
    };
    let stop = AtomicBool::new(false);
    let r = run(&cfg, &opts, &stop, &mut |_| {}).unwrap();
    assert_eq!(r.outcome, Outcome::Refused);
    for d in ["drive 0 (MR-J4-TM) stays in", "drive 1 (BDHDE) stays in"] {
        assert!(r.reason.contains(d), "{}", r.reason);
    }
    assert!(r.reason.contains("statusword 0x"), "{}", r.reason);
    assert!(r.reason.contains("controlword 0x"), "{}", r.reason);
    assert!(r.reason.contains("usual causes"), "{}", r.reason);
}
