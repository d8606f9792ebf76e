//! What the repository may not hold: a package registry's host or a download URL. Packages are
//! fetched by the package tools (cargo, `pip download`, `pip install --require-hashes`) from
//! whatever index they are configured with, and checked against a checksum kept here; the
//! lock files the tools write themselves are theirs.

/// Hosts of package registries and their file servers, and the path of release downloads.
const FORBIDDEN: &[&str] = &[
    "pythonhosted.org",
    "pypi.org",
    "pypi.python.org",
    "static.crates.io",
    "crates.io/api",
    "index.crates.io",
    "registry.npmjs.org",
    "/releases/download/",
    "/archive/refs/",
];

#[test]
fn no_package_host_or_download_url_in_the_repository() {
    let root = env!("CARGO_MANIFEST_DIR");
    let out = std::process::Command::new("git")
        .args(["-C", root, "ls-files", "-z"])
        .output()
        .expect("git ls-files");
    assert!(out.status.success(), "git ls-files failed");
    let files: Vec<String> = out
        .stdout
        .split(|b| *b == 0)
        .filter(|f| !f.is_empty())
        .map(|f| String::from_utf8_lossy(f).into_owned())
        .collect();
    assert!(files.len() > 100, "{} files", files.len());
    let mut found = Vec::new();
    for f in &files {
        // Written by cargo itself.
        if f.ends_with("Cargo.lock") || f == "tests/app/repository.rs" {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(format!("{root}/{f}")) else {
            continue; // binary
        };
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_ascii_lowercase();
            for host in FORBIDDEN {
                if lower.contains(host) {
                    found.push(format!("{f}:{}: {host}", n + 1));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "package hosts or download URLs:\n{}",
        found.join("\n")
    );
}
