//! The corpus of real vendor ESI files beside the checkout (`../shared/esi-corpus`, listed in
//! its `MANIFEST.tsv`), read from there, never copied into the repository.

use std::path::{Path, PathBuf};

/// The corpus folder: `ECDRIVE_ESI_CORPUS`, else `../shared/esi-corpus` beside the checkout.
/// Missing: a failure under `ECDRIVE_CI`, else `None` with a loud line.
pub fn dir() -> Option<PathBuf> {
    let dir = std::env::var_os("ECDRIVE_ESI_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/esi-corpus"));
    if dir.join("MANIFEST.tsv").is_file() {
        Some(dir)
    } else if std::env::var_os("ECDRIVE_CI").is_some() {
        panic!("the ESI corpus is not at {}", dir.display());
    } else {
        eprintln!("skipped: no ESI corpus at {}", dir.display());
        None
    }
}
