//! Shared by the `cli_*` tests: running the `ecdrive` binary, and `ecdrive sim` serving
//! emulated devices on one end of a veth pair inside a network namespace the test creates.
#![allow(dead_code)]

use ecdrive::link::netns::{VethPair, require_root};
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, ChildStderr, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The binary under test.
pub const ECDRIVE: &str = env!("CARGO_BIN_EXE_ecdrive");

/// What one run of `ecdrive` printed and how it ended.
#[derive(Debug)]
pub struct Run {
    /// Exit code (`None` if killed by a signal).
    pub code: Option<i32>,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Run {
    /// Assert success and return stdout.
    #[track_caller]
    pub fn ok(&self) -> &str {
        assert_eq!(self.code, Some(0), "{self:#?}");
        let json = self.stdout.trim_start().starts_with(['{', '['])
            && serde_json::from_str::<serde_json::Value>(&self.stdout).is_ok();
        if !json {
            no_debug_text(&self.stdout);
        }
        no_debug_text(&self.stderr);
        &self.stdout
    }

    /// Assert success and parse stdout as JSON.
    #[track_caller]
    pub fn json(&self) -> serde_json::Value {
        let out = self.ok();
        serde_json::from_str(out).unwrap_or_else(|e| panic!("not JSON ({e}):\n{out}"))
    }

    /// Assert exit `code`, nothing on stdout, exactly one line on stderr that names
    /// `ecdrive` and contains each of `has`, and no panic or backtrace. Returns the line.
    #[track_caller]
    pub fn fails(&self, code: i32, has: &[&str]) -> String {
        assert_eq!(self.code, Some(code), "{self:#?}");
        let lines: Vec<&str> = self
            .stderr
            .lines()
            .filter(|l| !l.trim().is_empty())
            .collect();
        assert_eq!(lines.len(), 1, "not one line: {self:#?}");
        let line = lines[0];
        assert!(line.starts_with("ecdrive"), "{line}");
        no_debug_text(line);
        for h in has {
            assert!(line.contains(h), "{line:?} does not mention {h:?}");
        }
        for bad in [
            "panicked",
            "RUST_BACKTRACE",
            "stack backtrace",
            "internal error",
        ] {
            assert!(!self.stderr.contains(bad), "{self:#?}");
        }
        line.to_string()
    }
}

/// User output carries no Rust `Debug` text (`Some(…)`, `Identity { vendor_id: … }`, `OS(1)`).
#[track_caller]
pub fn no_debug_text(text: &str) {
    for bad in ["Some(", "None)", " { ", "OS("] {
        assert!(
            !text.contains(bad),
            "Rust Debug text ({bad:?}) in the output:\n{text}"
        );
    }
}

/// Run `ecdrive` with `args` (stdin closed, stdout and stderr captured).
pub fn ecdrive(args: &[&str]) -> Run {
    let out: Output = Command::new(ECDRIVE)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("run ecdrive");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// `ecdrive sim` serving `devices` on the peer end of a fresh veth pair, inside the pair's
/// namespace. The host end (in the test's namespace) is where the commands under test go.
/// Stopped with SIGINT on drop (killed if it does not stop); the pair and namespace are then
/// removed.
pub struct SimOnVeth {
    child: Child,
    stderr: Option<BufReader<ChildStderr>>,
    /// The `ecdrive sim` arguments after the interface, and the device count.
    args: Vec<String>,
    devices: usize,
    /// The banner `ecdrive sim` printed (one line per device).
    pub banner: String,
    // Dropped after the child is stopped (fields drop in declaration order).
    veth: VethPair,
}

impl SimOnVeth {
    /// Start it; `None` (with the loud skip line of [`require_root`]) without root.
    pub fn start(test: &str, devices: &[&str]) -> Option<Self> {
        Self::start_with(test, devices, &[])
    }

    /// [`SimOnVeth::start`] with more `ecdrive sim` arguments.
    pub fn start_with(test: &str, devices: &[&str], extra: &[&str]) -> Option<Self> {
        if !require_root(test) {
            return None;
        }
        let veth = VethPair::create().expect("veth pair");
        let mut args: Vec<String> = Vec::new();
        for d in devices {
            args.extend(["--device".to_string(), d.to_string()]);
        }
        args.extend(extra.iter().map(|a| a.to_string()));
        let (child, stderr, banner) = Self::spawn(&veth, &args, devices.len());
        Some(Self {
            child,
            stderr: Some(stderr),
            args,
            devices: devices.len(),
            banner,
            veth,
        })
    }

    fn spawn(
        veth: &VethPair,
        args: &[String],
        devices: usize,
    ) -> (Child, BufReader<ChildStderr>, String) {
        let mut cmd = Command::new("ip");
        cmd.args(["netns", "exec", veth.netns().name(), ECDRIVE, "sim"])
            .args(["--interface", veth.peer(), "--sm-watchdog", "0"])
            .args(args);
        let mut child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start ecdrive sim");
        let mut stderr = BufReader::new(child.stderr.take().expect("stderr"));
        let mut banner = String::new();
        let mut line = String::new();
        let last = format!("  {}: ", devices - 1);
        while stderr.read_line(&mut line).expect("read sim stderr") > 0 {
            banner.push_str(&line);
            if line.starts_with(&last) {
                break;
            }
            line.clear();
        }
        assert!(
            banner.contains(&format!("serving {devices} device(s)")),
            "ecdrive sim did not start:\n{banner}"
        );
        (child, stderr, banner)
    }

    /// Switch the emulated devices off and on: stop the simulator (SIGINT) and start it again
    /// with the same arguments on the same pair. Returns what it printed when stopping.
    pub fn power_cycle(&mut self) -> String {
        let out = self.stop_inner();
        let (child, stderr, banner) = Self::spawn(&self.veth, &self.args, self.devices);
        self.child = child;
        self.stderr = Some(stderr);
        self.banner = banner;
        out
    }

    /// The interface the commands under test use.
    pub fn host(&self) -> &str {
        self.veth.host()
    }

    /// Run `ecdrive` with `args`, `-i <host end>` inserted after the command name.
    pub fn ecdrive(&self, args: &[&str]) -> Run {
        let mut all: Vec<&str> = args.to_vec();
        // After the command name; after the subcommand's for the commands whose subcommands
        // take the interface (`foe read`, `sii write`).
        let nested = matches!(all.as_slice(), ["foe", ..] | ["sii", "write", ..]);
        let at = all.len().min(if nested { 2 } else { 1 });
        all.splice(at..at, ["-i", self.host()]);
        ecdrive(&all)
    }

    /// `ecdrive run -c FILE --json` (with `extra` arguments) against the simulator, parsed. The
    /// files under test stop the axes after 3 frames lost in a row, which a shared test
    /// machine loses over veth now and then: such a run is tried again (at most twice); a run
    /// that ends for any other reason is returned as it is.
    pub fn run_json(&self, file: &str, extra: &[&str]) -> serde_json::Value {
        self.run_json_attempts(file, extra)
            .pop()
            .unwrap_or(serde_json::Value::Null)
    }

    /// [`SimOnVeth::run_json`], every attempt's report in order (the last is the one that
    /// counts). A later attempt meets the emulated devices as the one before left them (a
    /// value written, SYNC0 run), which a test of what the first start-up sees checks on the
    /// first.
    pub fn run_json_attempts(&self, file: &str, extra: &[&str]) -> Vec<serde_json::Value> {
        let mut args = vec!["run", "-c", file, "--json"];
        args.extend_from_slice(extra);
        let mut all = Vec::new();
        for _ in 0..3 {
            let r = self.ecdrive(&args);
            let j: serde_json::Value =
                serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {r:#?}"));
            let lost = j["history"]
                .as_array()
                .is_some_and(|h| h.iter().any(|e| e["kind"] == "FrameLost"));
            let done = j["outcome"] == "completed" || !lost;
            all.push(j);
            if done {
                break;
            }
        }
        all
    }

    /// Take the simulator's end of the pair down or up (`ip link set … down|up` in its
    /// namespace), as a cable pull at the slaves' side does.
    pub fn set_peer_link(&self, up: bool) {
        let st = Command::new("ip")
            .args([
                "netns",
                "exec",
                self.veth.netns().name(),
                "ip",
                "link",
                "set",
            ])
            .args([self.veth.peer(), if up { "up" } else { "down" }])
            .status()
            .expect("ip link set");
        assert!(st.success());
    }

    /// Stop the simulator with SIGINT and return what it printed after the banner.
    pub fn stop(mut self) -> String {
        self.stop_inner()
    }

    fn stop_inner(&mut self) -> String {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT);
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            match self.child.try_wait() {
                Ok(Some(_)) => break,
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(10));
                }
                _ => {
                    let _ = self.child.kill();
                    let _ = self.child.wait();
                    break;
                }
            }
        }
        let mut rest = String::new();
        if let Some(mut e) = self.stderr.take() {
            let _ = e.read_to_string(&mut rest);
        }
        rest
    }
}

impl Drop for SimOnVeth {
    fn drop(&mut self) {
        if self.stderr.is_some() {
            self.stop_inner();
        }
    }
}

/// `ecdrive sim --can BUS args…` in a process of its own, once its banner lists `nodes` nodes;
/// its stderr keeps being read so that it never blocks. The banner with it.
pub fn serve_can(bus: &str, args: &[&str], nodes: usize) -> (Child, String) {
    let mut child = Command::new(ECDRIVE)
        .args(["sim", "--can", bus])
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start ecdrive sim --can");
    let mut err = BufReader::new(child.stderr.take().expect("stderr"));
    let mut banner = String::new();
    let mut line = String::new();
    while err.read_line(&mut line).expect("read") > 0 {
        banner.push_str(&line);
        if banner.lines().filter(|l| l.starts_with("  node ")).count() == nodes {
            break;
        }
        line.clear();
    }
    assert!(banner.contains("serving"), "{banner}");
    std::thread::spawn(move || {
        let mut rest = String::new();
        let _ = err.read_to_string(&mut rest);
    });
    (child, banner)
}
