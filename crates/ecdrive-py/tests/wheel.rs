//! The Python package as a user gets it: the wheel built with maturin, installed into a fresh
//! virtual environment, and its tests (`tests/python`) run there with pytest, in-process
//! against the emulated drives and, as root, over veth pairs against `ecdrive sim`.
//!
//! maturin, pytest and numpy come from `target/wheelhouse`, which `.ci/run` fills from
//! `.ci/python.txt` (pinned by checksum). Under `ECDRIVE_CI` nothing here may be missing;
//! elsewhere a missing tool skips the test with a loud line.

use ecdrive::link::netns::{VethPair, require_root};
use ecdrive::rt::audit::announce_skip;
use std::path::{Path, PathBuf};
use std::process::Command;

fn required() -> bool {
    std::env::var_os("ECDRIVE_CI").is_some()
}

/// Fail under CI, else skip loudly.
fn missing(what: &str) {
    if required() {
        panic!("ecdrive-py wheel test: {what} (ECDRIVE_CI is set: .ci/run installs it)");
    }
    announce_skip(&format!("SKIPPED: the Python package's tests: {what}"));
}

fn run(cmd: &mut Command, what: &str) {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The wheel, built afresh into `dir`.
fn build_wheel(repo: &Path, maturin: &Path, dir: &Path) -> PathBuf {
    let _ = std::fs::remove_dir_all(dir);
    run(
        Command::new(maturin)
            .current_dir(repo)
            .args(["build", "--release", "--quiet", "--interpreter", "python3"])
            .args(["-m", "crates/ecdrive-py/Cargo.toml", "-o"])
            .arg(dir),
        "maturin build",
    );
    std::fs::read_dir(dir)
        .expect("the wheel directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .expect("maturin built a wheel")
}

/// A fresh virtual environment with the wheel, pytest and numpy (from the wheelhouse only).
fn venv(dir: &Path, wheelhouse: &Path, wheel: &Path) -> PathBuf {
    let _ = std::fs::remove_dir_all(dir);
    run(
        Command::new("python3").args(["-m", "venv"]).arg(dir),
        "python3 -m venv",
    );
    let python = dir.join("bin/python");
    run(
        Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
            ])
            .args(["--no-index", "--find-links"])
            .arg(wheelhouse)
            .args(["pytest", "numpy"])
            .arg(wheel),
        "pip install (the wheel, pytest, numpy)",
    );
    python
}

#[test]
fn the_wheel_installs_and_its_tests_pass() {
    let repo = ecdrive_testkit::repo();
    let target = repo.join("target");
    let wheelhouse = target.join("wheelhouse");
    let Some(maturin) = which("maturin") else {
        return missing("maturin is not on PATH");
    };
    if !wheelhouse.join(".").exists()
        || !std::fs::read_dir(&wheelhouse)
            .map(|d| {
                d.flatten()
                    .any(|e| e.file_name().to_string_lossy().starts_with("pytest-"))
            })
            .unwrap_or(false)
    {
        return missing("target/wheelhouse has no pytest (pip download -r .ci/python.txt)");
    }
    // The binary the tests compare the commissioning reads with, and serve veth from.
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    run(
        Command::new(cargo).current_dir(repo).args([
            "build",
            "--release",
            "--quiet",
            "--bin",
            "ecdrive",
        ]),
        "cargo build --release --bin ecdrive",
    );
    let wheel = build_wheel(repo, &maturin, &target.join("wheels/test"));
    let python = venv(&target.join("py-test-venv"), &wheelhouse, &wheel);
    println!("installed {} into target/py-test-venv", wheel.display());

    let mut pytest = Command::new(&python);
    pytest
        .current_dir(repo.join("crates/ecdrive-py/tests/python"))
        .args(["-m", "pytest", "-v", "-p", "no:cacheprovider", "-rsP"])
        .env("ECDRIVE_BIN", target.join("release/ecdrive"));
    // As root: two veth pairs, the drives served by `ecdrive sim` in each pair's namespace
    // (the second one started by its test, with an alarm to come).
    let pairs = require_root("the Python package over veth").then(|| {
        let a = VethPair::create().expect("veth pair");
        let b = VethPair::create().expect("veth pair");
        (a, b)
    });
    let mut sim = None;
    if let Some((a, b)) = &pairs {
        sim = Some(serve(&target.join("release/ecdrive"), a));
        pytest
            .env("ECDRIVE_PY_VETH", a.host())
            .env("ECDRIVE_PY_VETH_ALARM", b.host())
            .env("ECDRIVE_PY_ALARM_NETNS", b.netns().name())
            .env("ECDRIVE_PY_ALARM_PEER", b.peer());
    }
    let out = pytest.output().expect("run pytest");
    if let Some(mut s) = sim {
        let _ = s.kill();
        let _ = s.wait();
    }
    drop(pairs);
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}\n{}", String::from_utf8_lossy(&out.stderr));
    // Kept beside the environment: the tests' figures (the GIL, the audit) as they printed them.
    let _ = std::fs::write(
        target.join("py-test-venv/pytest-output.txt"),
        text.as_bytes(),
    );
    assert!(out.status.success(), "pytest failed ({})", out.status);
    assert!(
        !text.contains(" SKIPPED") || !required(),
        "a test skipped under CI:\n{text}"
    );
}

/// `ecdrive sim` with the two drives on the peer end of `pair`, once it serves.
fn serve(bin: &Path, pair: &VethPair) -> std::process::Child {
    use std::io::BufRead;
    let mut child = Command::new("ip")
        .args(["netns", "exec", pair.netns().name()])
        .arg(bin)
        .args(["sim", "--interface", pair.peer(), "--sm-watchdog", "0"])
        .args(["--device", "mr-j4-tm", "--device", "bdhde"])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start ecdrive sim");
    let stderr = child.stderr.take().expect("stderr");
    let mut lines = std::io::BufReader::new(stderr).lines();
    let mut banner = String::new();
    for line in lines.by_ref() {
        let line = line.expect("read the sim's banner");
        banner.push_str(&line);
        banner.push('\n');
        if line.starts_with("  1: ") {
            break;
        }
    }
    assert!(
        banner.contains("serving 2 device(s)"),
        "ecdrive sim did not start:\n{banner}"
    );
    // Keep reading its stderr so that it never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    child
}

fn which(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|p| {
        std::env::split_paths(&p)
            .map(|d| d.join(name))
            .find(|f| f.is_file())
    })
}
