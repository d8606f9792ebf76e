//! `ecdrive sim`'s fault options: bad values are usage errors (exit 2, one line naming the
//! option and why) before anything is opened; good ones pass validation (the run then stops at
//! the missing interface, exit 3). With root, end to end on a veth pair: frames dropped or
//! delayed by `ecdrive sim` as a master sees them, and the counters it prints when it stops.

use crate::support::cli;

use cli::{SimOnVeth, ecdrive};

/// No such interface: validation happens before the socket is opened.
const NO_IF: &str = "ecd-nonexistent0";

fn sim(extra: &[&str]) -> cli::Run {
    let mut args = vec!["sim", "-i", NO_IF, "-d", "mr-j4-tm", "-d", "generic-io"];
    args.extend_from_slice(extra);
    ecdrive(&args)
}

#[test]
fn bad_fault_options_are_usage_errors_naming_option_and_reason() {
    let cases: &[(&[&str], &[&str])] = &[
        (&["--drop", "150%"], &["--drop", "between 0 and 100%"]),
        (&["--drop", "often"], &["--drop", "not a fraction"]),
        (&["--delay", "5%"], &["--delay", "P:TIME"]),
        (&["--delay", "5%:0s"], &["--delay", "zero"]),
        (&["--delay", "5%:200"], &["--delay", "no unit"]),
        (&["--corrupt-at", "1s:0"], &["--corrupt-at", "zero"]),
        (&["--disconnect-at", "soon"], &["--disconnect-at"]),
        (&["--reset-at", "0"], &["--reset-at", "no time"]),
        (&["--reset-at", "x@1s"], &["--reset-at", "position"]),
        (&["--alarm", "0:AL.52"], &["--alarm", "no time"]),
        (
            &["--following-error", "0:1.5@1s"],
            &["--following-error", "integer"],
        ),
        (
            &["--sdo-abort", "0:0x6060"],
            &["--sdo-abort", "POS:INDEX[:SUB]:CODE"],
        ),
        (
            &["--sdo-abort", "0:0x16060:0x08000022"],
            &["--sdo-abort", "index", "0xFFFF"],
        ),
        (
            &["--sdo-abort", "0:0x6060:0x100:0x08000022"],
            &["--sdo-abort", "subindex"],
        ),
        (
            &["--emergency-during-sdo", "0:0x1FF10"],
            &["--emergency-during-sdo", "error code"],
        ),
        (&["--drift", "0:2000000"], &["--drift", "1000 ppm"]),
        (&["--seed", "12x"], &["--seed", "not a number"]),
        (&["--corrupt-kind", "everything"], &["--corrupt-kind"]),
        // Checked against the devices (after they are built, before the interface opens).
        (
            &["--alarm", "2:AL.52@1s"],
            &["--alarm 2:AL.52@1s", "no device at position 2"],
        ),
        (
            &["--alarm", "0:AL.99@1s"],
            &["--alarm 0:AL.99@1s", "no alarm \"AL.99\"", "AL.52"],
        ),
        (
            &["--alarm", "1:AL.52@1s"],
            &["--alarm 1:AL.52@1s", "not a drive"],
        ),
        (
            &["--following-error", "1:100@1s"],
            &["--following-error", "not a drive"],
        ),
        (
            &["--sdo-abort", "1:0x6060:0x08000022"],
            &["--sdo-abort", "no CoE mailbox"],
        ),
        (
            &["--emergency-during-sdo", "1:0xFF10"],
            &["--emergency-during-sdo", "no CoE"],
        ),
        (
            &["--reset-at", "5@1s"],
            &["--reset-at 5@1s", "no device at position 5"],
        ),
        (
            &["--reconnect-at", "3s"],
            &["--reconnect-at 3s", "not pulled"],
        ),
        (
            &["--disconnect-at", "1s", "--disconnect-at", "2s"],
            &["--disconnect-at 2s", "already pulled"],
        ),
        (
            &["--disconnect-at", "1s", "--reconnect-at", "500ms"],
            &["--reconnect-at 500ms", "not pulled"],
        ),
    ];
    for (args, has) in cases {
        let r = sim(args);
        r.fails(2, has);
    }
}

#[test]
fn good_fault_options_pass_validation() {
    let cases: &[&[&str]] = &[
        &["--drop", "1%"],
        &["--drop", "0.25", "--drop-leg", "return", "--seed", "0x2A"],
        &["--delay", "5%:200us"],
        &[
            "--corrupt-at",
            "2s",
            "--corrupt-at",
            "3s:10",
            "--corrupt-kind",
            "index",
        ],
        &[
            "--disconnect-at",
            "5s",
            "--reconnect-at",
            "8s",
            "--disconnect-at",
            "10s",
        ],
        &["--reset-at", "0@1s", "--reset-at", "1@2s"],
        &["--alarm", "0:AL.52@12s", "--alarm", "0:al.86.1@13s"],
        &["--following-error", "0:-50000@3s"],
        &[
            "--sdo-abort",
            "0:0x6060:0x08000022",
            "--sdo-abort",
            "0:0x1018:2:0x06020000@1s",
        ],
        &["--emergency-during-sdo", "0:0xFF10"],
        &["--drift", "0:50000", "--drift", "1:-20000@2s"],
    ];
    for args in cases {
        // Validation passed: the run stops at the interface, a link error.
        sim(args).fails(3, &[NO_IF]);
    }
}

#[test]
fn help_documents_the_fault_options() {
    let r = ecdrive(&["sim", "--help"]);
    let out = r.ok();
    for opt in [
        "--drop <P>",
        "--drop-leg",
        "--delay <P:TIME>",
        "--corrupt-at",
        "--corrupt-kind",
        "--disconnect-at",
        "--reconnect-at",
        "--reset-at <POS@T>",
        "--alarm <POS:ID@T>",
        "--following-error <POS:VALUE@T>",
        "--sdo-abort <POS:INDEX[:SUB]:CODE[@T]>",
        "--emergency-during-sdo",
        "--drift <POS:PPB[@T]>",
        "--seed <N>",
        "0x0060",
    ] {
        assert!(out.contains(opt), "--help does not mention {opt}");
    }
}

/// Every frame dropped: a master finds nothing, and `ecdrive sim` reports the drops.
#[test]
fn dropped_frames_never_reach_the_master() {
    let Some(sim) = SimOnVeth::start_with(
        "sim_faults_cli::dropped_frames_never_reach_the_master",
        &["generic-io"],
        &["--drop", "100%"],
    ) else {
        return;
    };
    let r = sim.ecdrive(&["slaves"]);
    assert_eq!(r.code, Some(3), "{r:#?}");
    let rest = sim.stop();
    assert!(number_before(&rest, " frames dropped") > 0, "{rest}");
    assert_eq!(number_before(&rest, " frames answered"), 0, "{rest}");
}

/// Every reply delayed by 2 ms: slower, but a master still finds the devices; the counters say
/// every answered frame was delayed.
#[test]
fn delayed_replies_still_arrive() {
    let Some(sim) = SimOnVeth::start_with(
        "sim_faults_cli::delayed_replies_still_arrive",
        &["generic-coe", "generic-io"],
        &["--delay", "100%:2ms"],
    ) else {
        return;
    };
    let r = sim.ecdrive(&["slaves"]);
    let out = r.ok();
    assert!(
        out.contains("ECD-COE402") && out.contains("ECD-IO"),
        "{out}"
    );
    let rest = sim.stop();
    let answered = number_before(&rest, " frames answered");
    let delayed = number_before(&rest, " delayed");
    assert!(answered > 0, "{rest}");
    // Every frame was delayed (a reply still held when the simulator stopped is counted as
    // delayed, not as answered).
    assert!(delayed >= answered, "{rest}");
}

/// The number just before `word` in `text`.
fn number_before(text: &str, word: &str) -> u64 {
    let at = text
        .find(word)
        .unwrap_or_else(|| panic!("{word:?} not in {text}"));
    let head = &text[..at];
    let start = head
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    head[start..]
        .parse()
        .unwrap_or_else(|_| panic!("no number before {word:?} in {text}"))
}
