//! Helpers of this test binary; those shared with other crates' tests are `ecdrive-testkit`'s.

pub mod cli;
pub mod runs;
pub use ecdrive_testkit::{corpus, generic, links, source_scan};

/// Run the test `name` of this binary (its full path, the test marked `#[ignore]` with the
/// reason) alone in a process of its own, and fail if it fails. For the few tests whose
/// subject is the whole process, such as the jitter harness's per-thread CPU figures, which
/// name every thread a run started: another test running beside it in this binary would add
/// its own. The child's output goes straight to this process's stdout and stderr.
pub fn alone(name: &str) {
    let exe = std::env::current_exe().expect("the test binary's own path");
    let status = std::process::Command::new(exe)
        .args([
            name,
            "--exact",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .status()
        .expect("start the test binary again");
    assert!(
        status.success(),
        "{name}, run alone in a process of its own, failed ({status}; its output is above)"
    );
}
