//! The software slave is a model of the drives, not of the master: nothing in the crate
//! `ecdrive-sim` may name the master's drive profiles (`ecdrive_core::drives`, which the crate
//! also leaves out of its core re-exports, so `crate::drives` does not compile), the master,
//! the CANopen master or the application (`master`, `canopen`, `app`). Shared *types* (object dictionary, CiA 402 bits, PDO and ESI models)
//! live elsewhere and are fine; shared *values* would let a wrong profile value pass both
//! sides. The emulated EtherCAT drives are built from their ESI files plus their own behaviour
//! tables (`crates/ecdrive-sim/src/drives/`), the emulated CANopen drives from the emulator's
//! own tables (`crates/ecdrive-sim/src/canopen/drives/`) or a vendor's EDS file, and
//! `tests/app/manual_facts.rs` checks both sides against the manuals. No master profile type
//! appears in the slave's source, so none can be handed to an emulated node at run time.
//!
//! This is the CI check of that rule: it reads the source, so it also catches doc links and
//! grouped imports (`use crate::{drives, …}`).

use crate::support::source_scan;

/// Module paths the slave must not reach.
const FORBIDDEN: &[&str] = &["drives", "master", "canopen", "app"];

/// Every place in `text` that reaches a forbidden module: `crate::m`, `ecdrive::m`,
/// `ecdrive_core::m`, or `m` inside a `crate::{…}` group. Returns (line, module).
fn violations(text: &str) -> Vec<(usize, &'static str)> {
    source_scan::reached(text, &["crate::", "ecdrive::", "ecdrive_core::"])
        .into_iter()
        .filter_map(|(line, m)| FORBIDDEN.iter().find(|f| **f == m).map(|f| (line, *f)))
        .collect()
}

#[test]
fn the_software_slave_names_no_master_profile_or_master_module() {
    let root = ecdrive_testkit::repo().join("crates/ecdrive-sim/src");
    let files = source_scan::rust_files(&root);
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
                f.strip_prefix(ecdrive_testkit::repo())
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

/// The master's drive-profile *types* a software-slave file must not name: an emulated node is
/// built from the emulator's own [`NodeSpec`](ecdrive_sim::canopen::NodeSpec) (its tables, or
/// a vendor's EDS file), so no master profile can be handed to it at run time either.
const PROFILE_TYPES: &[&str] = &["CanDriveProfile", "DriveProfile", "CanOpen {", "EtherCat {"];

/// Every line of `text` (outside comments) that names a master profile type.
fn profile_types(text: &str) -> Vec<(usize, &'static str)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        for t in PROFILE_TYPES {
            let hit = code.match_indices(t).any(|(at, _)| {
                // A whole word: `DriveProfile` inside `CanDriveProfile` counts once, as the
                // longer name.
                !code[..at]
                    .chars()
                    .last()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_')
            });
            if hit {
                out.push((n + 1, *t));
            }
        }
    }
    out
}

#[test]
fn no_master_profile_can_reach_an_emulated_canopen_node() {
    let root = ecdrive_testkit::repo().join("crates/ecdrive-sim/src");
    let mut found = Vec::new();
    for f in source_scan::rust_files(&root) {
        let text = std::fs::read_to_string(&f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        for (line, t) in profile_types(&text) {
            found.push(format!("{}:{line}: names {t}", f.display()));
        }
    }
    assert!(
        found.is_empty(),
        "the emulated nodes take the emulator's NodeSpec, never a master profile:\n{}",
        found.join("\n")
    );
    // The three project drives have tables of their own, and an EDS file builds the rest.
    for name in [
        "blv-r",
        "asda-a2",
        "lexium-mdrive",
        "lexium-mdrive-closed-loop",
    ] {
        let spec = ecdrive_sim::canopen::drives::by_name(name)
            .unwrap_or_else(|| panic!("no emulator table {name}"));
        assert!(
            !spec.source.is_empty() && !spec.dictionary.is_empty(),
            "{name}: {spec:?}"
        );
    }
}

/// The check sees a profile type named in code, and not in comments or longer names.
#[test]
fn the_profile_type_check_catches_code_only() {
    let caught = |t: &str| {
        profile_types(t)
            .into_iter()
            .map(|(_, m)| m)
            .collect::<Vec<_>>()
    };
    assert_eq!(
        caught("fn new(p: &'static CanDriveProfile) {}"),
        ["CanDriveProfile"]
    );
    assert_eq!(
        caught("use crate::can::profile::{Alarm, CanDriveProfile};"),
        ["CanDriveProfile"]
    );
    assert_eq!(caught("let p: DriveProfile = x;"), ["DriveProfile"]);
    assert!(caught("// not a CanDriveProfile: the emulator's own").is_empty());
    assert!(caught("struct MyDriveProfileish;").is_empty());
}
