//! The committed fuzz corpus (`fuzz/corpus/<target>/`) as a regression suite: every file goes
//! through the same checks as its cargo-fuzz target (`fuzz/src/lib.rs`, included here, so the
//! targets and this test cannot drift apart), without libFuzzer or a nightly toolchain.

use crate::fuzz_checks as checks;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

/// Replay every file of `fuzz/corpus/<target>` through `check`; fail naming every file whose
/// check panics. The corpus must not be empty (a missing corpus is a failure, not a pass).
fn replay(target: &str, check: fn(&[u8])) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("corpus entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(
        files.len() >= 5,
        "{}: only {} corpus files",
        dir.display(),
        files.len()
    );
    let mut failed = Vec::new();
    for f in &files {
        let data = std::fs::read(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        if catch_unwind(AssertUnwindSafe(|| check(&data))).is_err() {
            failed.push(f.display().to_string());
        }
    }
    assert!(
        failed.is_empty(),
        "{target}: {} of {} corpus files fail their check (reproduce with \
         `cargo +nightly fuzz run {target} <file>`):\n{}",
        failed.len(),
        files.len(),
        failed.join("\n")
    );
}

#[test]
fn segment_corpus_replays_clean() {
    replay("segment", checks::segment);
}

#[test]
fn coe_corpus_replays_clean() {
    replay("coe", checks::coe);
}

#[test]
fn esi_corpus_replays_clean() {
    replay("esi", checks::esi);
}

#[test]
fn eds_corpus_replays_clean() {
    replay("eds", checks::eds);
}

#[test]
fn config_corpus_replays_clean() {
    replay("config", checks::config);
}

/// The corpus reaches past the parsers' first error: some ESI inputs are whole files with
/// devices, and some configuration inputs are accepted.
#[test]
fn the_corpus_reaches_the_success_paths() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let read = |t: &str| -> Vec<Vec<u8>> {
        std::fs::read_dir(dir.join(t))
            .expect("corpus directory")
            .map(|e| std::fs::read(e.expect("corpus entry").path()).expect("corpus file"))
            .collect()
    };
    let esi_with_devices = read("esi")
        .iter()
        .filter(|d| ecdrive::esi::EsiFile::parse_bytes(d).is_ok_and(|f| !f.devices.is_empty()))
        .count();
    assert!(esi_with_devices >= 3, "{esi_with_devices} ESI inputs parse");
    let configs_ok = read("config")
        .iter()
        .filter_map(|d| std::str::from_utf8(d).ok())
        .filter(|t| ecdrive_cli::app::config::parse(t, "corpus.toml").is_ok())
        .count();
    assert!(
        configs_ok >= 3,
        "{configs_ok} configuration inputs are accepted"
    );
}
