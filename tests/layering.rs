//! The layering of ARCHITECTURE.md, checked on the source and the manifests.
//!
//! - the core (`ec`, `od`, `pdo`, `cia402`, `esi`, `drives`, `link`, `rt`, `can`) is the crate
//!   `ecdrive-core`: the compiler keeps it from reaching anything above, and its manifest may
//!   not gain a dependency on a bus master, an async runtime, the CLI or another ecdrive crate;
//!
//! In this crate each part may reach only the top-level modules its layer allows (`crate::m`,
//! `ecdrive::m`, or `m` inside a `crate::{…}` group; doc links count, since they would break
//! when the layers become crates):
//!
//! - the software slave is the crate `ecdrive-sim`: the core only, without the master's drive
//!   profiles (`tests/emulation_independence.rs`), and no other ecdrive crate;
//! - the EtherCAT master is the crate `ecdrive-ethercat`: the core only (its manifest is
//!   checked: no software slave, no async runtime, no CLI);
//! - the CANopen master is the crate `ecdrive-canopen`: the core only (manifest checked);
//! - applications (the rest) may reach everything.

#[path = "support/source_scan.rs"]
mod source_scan;

use std::path::Path;

const CORE: &[&str] = &[
    "ec", "od", "pdo", "cia402", "esi", "drives", "link", "rt", "can",
];
const ALL: &[&str] = &[
    "ec", "od", "pdo", "cia402", "esi", "drives", "link", "rt", "can", "sim", "master", "canopen",
    "config", "harness",
];

/// What the file at `rel` (relative to `src/`) may reach, or `None` for an application.
fn allowed(rel: &str) -> Option<Vec<&'static str>> {
    let top = rel.split('/').next().unwrap_or("");
    let file = rel.rsplit('/').next().unwrap_or("");
    let app_master = ["demo.rs", "soak.rs", "recovery.rs"];
    match top {
        t if CORE.contains(&t) => Some(CORE.to_vec()),
        "sim" => Some(
            CORE.iter()
                .copied()
                .filter(|m| *m != "drives")
                .chain(["sim"])
                .collect(),
        ),
        "master" if rel.starts_with("master/tools/") || app_master.contains(&file) => None,
        "master" => Some(CORE.iter().copied().chain(["master"]).collect()),
        "canopen" if ["demo.rs", "tools.rs"].contains(&file) => None,
        "canopen" => Some(CORE.iter().copied().chain(["canopen"]).collect()),
        _ => None,
    }
}

/// Every top-level module of this crate `text` reaches, with its line.
fn reached(text: &str) -> Vec<(usize, String)> {
    let mut out = source_scan::reached(text, &["crate::", "ecdrive::"]);
    out.retain(|(_, m)| ALL.contains(&m.as_str()));
    out
}

#[test]
fn each_layer_reaches_only_the_layers_below() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = source_scan::rust_files(&src);
    assert!(files.len() > 20, "found only {} files", files.len());
    let mut found = Vec::new();
    let mut checked = 0;
    for f in &files {
        let rel = f
            .strip_prefix(&src)
            .unwrap_or(f)
            .to_string_lossy()
            .replace('\\', "/");
        let Some(ok) = allowed(&rel) else {
            continue;
        };
        checked += 1;
        let text = std::fs::read_to_string(f).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for (line, m) in reached(&text) {
            if !ok.contains(&m.as_str()) {
                found.push(format!("src/{rel}:{line}: reaches crate::{m}"));
            }
        }
    }
    assert!(checked >= 2, "only {checked} library files checked");
    assert!(
        found.is_empty(),
        "layering violations (see ARCHITECTURE.md):\n{}",
        found.join("\n")
    );
}

/// The check sees each form and judges by layer.
#[test]
fn the_check_sees_every_form() {
    let mods = |t: &str| reached(t).into_iter().map(|(_, m)| m).collect::<Vec<_>>();
    assert_eq!(mods("use crate::sim::Segment;"), ["sim"]);
    assert_eq!(
        mods("use crate::{od::Value, config::Raw};"),
        ["od", "config"]
    );
    assert_eq!(mods("/// [`crate::harness`]"), ["harness"]);
    assert!(mods("use super::sim; my_crate::sim").is_empty());
    assert_eq!(allowed("od/value.rs"), Some(CORE.to_vec()));
    assert!(!allowed("sim/esc/mod.rs").unwrap().contains(&"drives"));
    assert!(!allowed("master/cycle.rs").unwrap().contains(&"sim"));
    assert_eq!(allowed("master/tools/od.rs"), None);
    assert_eq!(allowed("master/demo.rs"), None);
    assert!(!allowed("canopen/master.rs").unwrap().contains(&"sim"));
    assert_eq!(allowed("canopen/tools.rs"), None);
    assert_eq!(allowed("config/mod.rs"), None);
    assert_eq!(allowed("lib.rs"), None);
}

/// The dependencies (normal ones) of the manifest at `path`.
fn dependencies(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc: toml::Table = text
        .parse()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    doc.get("dependencies")
        .and_then(|d| d.as_table())
        .map(|t| t.keys().cloned().collect())
        .unwrap_or_default()
}

/// Crates the core may never depend on.
const NOT_IN_CORE: &[&str] = &[
    "ethercrab",
    "tokio",
    "async-io",
    "clap",
    "indicatif",
    "socketcan",
    "toml",
    "toml_edit",
    "serde_json",
    "rtrb",
    "triple_buffer",
];

#[test]
fn the_core_crate_depends_on_no_master_runtime_or_application_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let core = dependencies(&root.join("crates/ecdrive-core/Cargo.toml"));
    assert!(core.iter().any(|d| d == "roxmltree"), "{core:?}");
    let bad: Vec<&String> = core
        .iter()
        .filter(|d| NOT_IN_CORE.contains(&d.as_str()) || d.starts_with("ecdrive"))
        .collect();
    assert!(
        bad.is_empty(),
        "ecdrive-core may not depend on {bad:?} (ARCHITECTURE.md: the core has no bus master, \
         no async runtime, no application code)"
    );
    // The application package depends on the core, not the other way round.
    assert!(dependencies(&root.join("Cargo.toml")).contains(&"ecdrive-core".to_string()));
}

/// The dependencies of crate `dir` that break "the core only": another ecdrive crate than the
/// core, or one of `forbidden`. Also checks that the crate does depend on the core.
fn beyond_the_core(dir: &str, forbidden: &[&str]) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let deps = dependencies(&root.join(dir).join("Cargo.toml"));
    assert!(deps.iter().any(|d| d == "ecdrive-core"), "{dir}: {deps:?}");
    deps.into_iter()
        .filter(|d| {
            (d.starts_with("ecdrive") && d != "ecdrive-core") || forbidden.contains(&d.as_str())
        })
        .collect()
}

/// The EtherCAT master stands on the core: the software slave only as a dev-dependency of its
/// tests, never a normal one; no async runtime, no CLI, no progress bars.
#[test]
fn the_ethercat_master_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-ethercat",
        &["tokio", "clap", "indicatif", "socketcan", "toml"],
    );
    assert!(bad.is_empty(), "ecdrive-ethercat may not depend on {bad:?}");
}

/// The CANopen master stands on the core: the emulated nodes of the software slave only as a
/// dev-dependency of tests; no async runtime, no CLI.
#[test]
fn the_canopen_master_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-canopen",
        &["tokio", "clap", "indicatif", "ethercrab", "toml"],
    );
    assert!(bad.is_empty(), "ecdrive-canopen may not depend on {bad:?}");
}

/// The software slave stands on the core only: no other ecdrive crate, no async runtime, no
/// CLI (it serves ethercrab's in-process transport, so ethercrab is allowed).
#[test]
fn the_slave_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-sim",
        &["tokio", "clap", "indicatif", "socketcan", "toml"],
    );
    assert!(bad.is_empty(), "ecdrive-sim may not depend on {bad:?}");
}
