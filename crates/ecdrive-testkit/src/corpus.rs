//! The corpora of real vendor ESI and EDS files beside the checkout (`../shared/esi-corpus`,
//! `../shared/eds-corpus`, each listed in
//! its `MANIFEST.tsv`), read from there, never copied into the repository.

use std::path::{Path, PathBuf};

/// A corpus folder: the variable `var`, else `../shared/FOLDER` beside the checkout. Missing:
/// a failure under `ECDRIVE_CI`, else `None` with a loud line.
fn corpus(var: &str, folder: &str) -> Option<PathBuf> {
    let dir = std::env::var_os(var)
        .map(PathBuf::from)
        .unwrap_or_else(|| crate::repo().join("../shared").join(folder));
    if dir.join("MANIFEST.tsv").is_file() {
        Some(dir)
    } else if std::env::var_os("ECDRIVE_CI").is_some() {
        panic!("the corpus {folder} is not at {}", dir.display());
    } else {
        eprintln!("skipped: no corpus {folder} at {}", dir.display());
        None
    }
}

/// The ESI corpus: `ECDRIVE_ESI_CORPUS`, else `../shared/esi-corpus`.
#[allow(dead_code)] // each test file uses the corpus it needs
pub fn dir() -> Option<PathBuf> {
    corpus("ECDRIVE_ESI_CORPUS", "esi-corpus")
}

/// The corpus of real vendor EDS/DCF files: `ECDRIVE_EDS_CORPUS`, else `../shared/eds-corpus`.
#[allow(dead_code)]
pub fn eds_dir() -> Option<PathBuf> {
    corpus("ECDRIVE_EDS_CORPUS", "eds-corpus")
}

/// The rows of a corpus's `MANIFEST.tsv` as column name → value.
#[allow(dead_code)]
pub fn manifest(dir: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("MANIFEST.tsv")).expect("MANIFEST.tsv");
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split('\t')
        .map(String::from)
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split('\t').map(String::from))
                .collect()
        })
        .collect()
}
