//! Build facts for `ecdrive version`: the git commit the binary was built from (if the source
//! is a git checkout) and the compiler's version.

use std::process::Command;

fn run(cmd: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(cmd).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
}

fn main() {
    // The commit, and whether the sources differ from it (a build of uncommitted work must
    // not claim the commit's name alone).
    let commit = run("git", &["rev-parse", "--short=12", "HEAD"]).map(|c| {
        match run(
            "git",
            &[
                "status",
                "--porcelain",
                "--untracked-files=no",
                "--",
                "src",
                "crates",
                "Cargo.toml",
                "Cargo.lock",
                "build.rs",
            ],
        ) {
            Some(_) => format!("{c}+uncommitted changes"),
            None => c,
        }
    });
    println!(
        "cargo:rustc-env=ECDRIVE_GIT_COMMIT={}",
        commit.as_deref().unwrap_or("unknown")
    );
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    println!(
        "cargo:rustc-env=ECDRIVE_RUSTC={}",
        run(&rustc, &["--version"]).unwrap_or_else(|| "unknown".into())
    );
    // Again when a commit moves HEAD or its branch, or when the sources change (then the crate
    // is rebuilt anyway). Not on the index: every `git add` would rebuild the crate.
    for path in [
        ".git/HEAD",
        ".git/refs/heads",
        "src",
        "crates",
        "Cargo.toml",
        "Cargo.lock",
        "build.rs",
    ] {
        println!("cargo:rerun-if-changed={path}");
    }
}
