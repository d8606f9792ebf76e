//! Reading the source for the layering checks (`tests/app/layering.rs`,
//! `crates/ecdrive-sim/tests/sim/emulation_independence.rs`): the Rust files under a directory, and the top-level
//! modules a text reaches from a crate root (`crate::m`, `ecdrive::m`, `m` inside a
//! `crate::{…}` group; doc links and comments count, since they break when layers become
//! crates).

use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, sorted.
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, &mut out);
    out.sort();
    out
}

/// Every module path head `text` reaches after one of `roots` (e.g. `"crate::"`), with its
/// line: `crate::sim::Segment` gives `sim`; `crate::{od::Value, config}` gives `od` and
/// `config`. A root inside a longer identifier (`my_ecdrive::`) does not count.
pub fn reached(text: &str, roots: &[&str]) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let line_of = |pos: usize| text[..pos].matches('\n').count() + 1;
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    for root in roots {
        let mut from = 0;
        while let Some(i) = text[from..].find(root) {
            let at = from + i;
            let prev = text[..at].chars().next_back();
            from = at + root.len();
            if prev.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let rest = &text[from..];
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
    out
}
