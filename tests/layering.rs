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

use std::path::{Path, PathBuf};

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

/// Every top-level module `text` reaches from the crate root, with its line.
fn reached(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let line_of = |pos: usize| text[..pos].matches('\n').count() + 1;
    for root in ["crate::", "ecdrive::"] {
        let mut from = 0;
        while let Some(i) = text[from..].find(root) {
            let at = from + i;
            let prev = text[..at].chars().next_back();
            from = at + root.len();
            if prev.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let rest = &text[from..];
            let ident = |s: &str| -> String {
                s.chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect()
            };
            if let Some(group) = rest.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                for item in group[..end].split(',') {
                    out.push((line_of(at), ident(item.trim())));
                }
            } else {
                out.push((line_of(at), ident(rest)));
            }
        }
    }
    out.retain(|(_, m)| ALL.contains(&m.as_str()));
    out
}

#[test]
fn each_layer_reaches_only_the_layers_below() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
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
    "crc",
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

/// The EtherCAT master stands on the core: the software slave only as a dev-dependency of its
/// tests, never a normal one; no async runtime, no CLI, no progress bars.
#[test]
fn the_ethercat_master_crate_depends_on_the_core_only() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let m = dependencies(&root.join("crates/ecdrive-ethercat/Cargo.toml"));
    assert!(m.iter().any(|d| d == "ecdrive-core"), "{m:?}");
    assert!(m.iter().any(|d| d == "ethercrab"), "{m:?}");
    let bad: Vec<&String> = m
        .iter()
        .filter(|d| {
            (d.starts_with("ecdrive") && *d != "ecdrive-core")
                || ["tokio", "clap", "indicatif", "socketcan", "toml"].contains(&d.as_str())
        })
        .collect();
    assert!(bad.is_empty(), "ecdrive-ethercat may not depend on {bad:?}");
}

/// The CANopen master stands on the core: the emulated nodes of the software slave only as a
/// dev-dependency of tests; no async runtime, no CLI.
#[test]
fn the_canopen_master_crate_depends_on_the_core_only() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let m = dependencies(&root.join("crates/ecdrive-canopen/Cargo.toml"));
    assert!(m.iter().any(|d| d == "ecdrive-core"), "{m:?}");
    let bad: Vec<&String> = m
        .iter()
        .filter(|d| {
            (d.starts_with("ecdrive") && *d != "ecdrive-core")
                || ["tokio", "clap", "indicatif", "ethercrab", "toml"].contains(&d.as_str())
        })
        .collect();
    assert!(bad.is_empty(), "ecdrive-canopen may not depend on {bad:?}");
}

/// The software slave stands on the core only: no other ecdrive crate, no async runtime, no
/// CLI (it serves ethercrab's in-process transport, so ethercrab is allowed).
#[test]
fn the_slave_crate_depends_on_the_core_only() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sim = dependencies(&root.join("crates/ecdrive-sim/Cargo.toml"));
    assert!(sim.iter().any(|d| d == "ecdrive-core"), "{sim:?}");
    let bad: Vec<&String> = sim
        .iter()
        .filter(|d| {
            (d.starts_with("ecdrive") && *d != "ecdrive-core")
                || ["tokio", "clap", "indicatif", "socketcan", "toml"].contains(&d.as_str())
        })
        .collect();
    assert!(bad.is_empty(), "ecdrive-sim may not depend on {bad:?}");
}
