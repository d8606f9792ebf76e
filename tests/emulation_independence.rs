//! The software slave is a model of the drives, not of the master: nothing in the crate
//! `ecdrive-sim` may name the master's drive profiles (`ecdrive_core::drives`, which the crate
//! also leaves out of its core re-exports, so `crate::drives` does not compile), the master,
//! the CANopen master or the application (`master`, `canopen`, `config`, `harness`). Shared *types* (object dictionary, CiA 402 bits, PDO and ESI models)
//! live elsewhere and are fine; shared *values* would let a wrong profile value pass both
//! sides. The emulated drives are built from their ESI files plus their own behaviour tables
//! (`src/sim/drives/`), and `tests/manual_facts.rs` checks both sides against the manuals.
//!
//! This is the CI check of that rule: it reads the source, so it also catches doc links and
//! grouped imports (`use crate::{drives, …}`).

use std::path::{Path, PathBuf};

/// Module paths the slave must not reach.
const FORBIDDEN: &[&str] = &["drives", "master", "canopen", "config", "harness"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every place in `text` that reaches a forbidden module from the crate root: `crate::m`,
/// `ecdrive::m`, or `m` inside a `crate::{…}` / `ecdrive::{…}` group. Returns (line, module).
fn violations(text: &str) -> Vec<(usize, &'static str)> {
    let mut out = Vec::new();
    let line_of = |pos: usize| text[..pos].matches('\n').count() + 1;
    for root in ["crate::", "ecdrive::", "ecdrive_core::"] {
        let mut from = 0;
        while let Some(i) = text[from..].find(root) {
            let at = from + i;
            // `ecdrive::` inside a longer identifier (`my_ecdrive::`) is not the crate.
            let prev = text[..at].chars().next_back();
            from = at + root.len();
            if prev.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let rest = &text[from..];
            if let Some(group) = rest.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                for item in group[..end].split(',') {
                    let head = item.trim().split("::").next().unwrap_or("").trim();
                    if let Some(m) = FORBIDDEN.iter().find(|m| **m == head) {
                        out.push((line_of(from), *m));
                    }
                }
                continue;
            }
            let ident: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if let Some(m) = FORBIDDEN.iter().find(|m| **m == ident) {
                out.push((line_of(at), *m));
            }
        }
    }
    out
}

#[test]
fn the_software_slave_names_no_master_profile_or_master_module() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ecdrive-sim/src");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    files.sort();
    assert!(
        files.len() > 20,
        "found only {} files under {}",
        files.len(),
        root.display()
    );
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        for (line, m) in violations(&text) {
            found.push(format!(
                "{}:{line}: reaches crate::{m}",
                f.strip_prefix(env!("CARGO_MANIFEST_DIR"))
                    .unwrap_or(f)
                    .display()
            ));
        }
    }
    assert!(
        found.is_empty(),
        "the software slave must be built from its ESI files and its own tables, not from the \
         master's code or profiles:\n{}",
        found.join("\n")
    );
}

/// The check sees each form of reaching a forbidden module, and leaves the allowed ones.
#[test]
fn the_check_catches_every_form() {
    let caught = |t: &str| {
        violations(t)
            .into_iter()
            .map(|(_, m)| m)
            .collect::<Vec<_>>()
    };
    assert_eq!(caught("use crate::drives::mr_j4_tm::PROFILE;"), ["drives"]);
    assert_eq!(
        caught("let p = &crate::drives::bdhde::PROFILE;"),
        ["drives"]
    );
    assert_eq!(caught("/// see [`crate::drives::all`]"), ["drives"]);
    assert_eq!(caught("use ecdrive::drives;"), ["drives"]);
    assert_eq!(
        caught("use crate::{od::ObjectAddress, drives::DriveProfile};"),
        ["drives"]
    );
    assert_eq!(caught("use crate::master::Bus;"), ["master"]);
    assert_eq!(caught("use ecdrive_core::drives::bdhde;"), ["drives"]);
    assert_eq!(caught("use ecdrive_core::{od, drives::all};"), ["drives"]);
    assert_eq!(caught("use crate::canopen::profile::od;"), ["canopen"]);
    assert!(caught("use crate::od::ObjectAddress; use crate::cia402::State;").is_empty());
    assert!(caught("use super::drives::EmulatedDrive;").is_empty());
    assert!(caught("use crate::pdo::{PdoLimits, drives_helper};").is_empty());
    assert!(caught("my_ecdrive::drives").is_empty());
}
