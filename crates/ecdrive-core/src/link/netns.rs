//! Network namespaces and veth pairs for tests, the jitter harness and demos, and the shared
//! root check for tests that need raw sockets.
//!
//! ```no_run
//! use ecdrive_core::link::netns::{VethPair, require_root};
//! if !require_root("my_veth_test") {
//!     return; // not root, not CI: a loud SKIPPED line was printed
//! }
//! let veth = VethPair::create().unwrap();
//! // The master opens `veth.host()` in the current namespace; the emulated slaves serve the
//! // other end inside the namespace:
//! let slave_socket = veth.open_peer_socket().unwrap();
//! // Both ends and the namespace are removed when `veth` is dropped, also when the test panics.
//! ```
//!
//! Names are unique per process and call (`ecdrive-<pid>-<n>` for namespaces, `ec<pid><n>m/s`
//! for interfaces), so tests running in parallel do not collide; namespaces left behind by a
//! killed process are removed the next time one is created.

use super::{LinkError, RawSocket};
use std::fs::File;
use std::process::Command;
use std::sync::atomic::{AtomicU32, Ordering};

/// Environment variable that turns skipped root-only tests into failures (set by `.ci/run`).
pub const CI_ENV: &str = "ECDRIVE_CI";

/// Whether the process runs as root (effective UID 0).
pub fn is_root() -> bool {
    // SAFETY: geteuid(2) has no preconditions and cannot fail.
    unsafe { libc::geteuid() == 0 }
}

/// Gate for tests that need root (raw sockets, namespaces). Returns `true` when the test can
/// run. Without root it prints `SKIPPED (needs root): <test>` to stderr and returns `false` —
/// unless [`CI_ENV`] is set, in which case it panics so that CI cannot pass by skipping.
#[track_caller]
pub fn require_root(test: &str) -> bool {
    if is_root() {
        return true;
    }
    if std::env::var_os(CI_ENV).is_some() {
        panic!("{test} needs root (raw sockets, network namespaces) and {CI_ENV} is set");
    }
    crate::rt::audit::announce_skip(&format!(
        "SKIPPED (needs root): {test} — run as root for raw sockets and network namespaces"
    ));
    false
}

/// Errors setting up namespaces and veth pairs.
#[derive(Debug, thiserror::Error)]
pub enum NetnsError {
    /// The `ip` tool could not be started.
    #[error("cannot run `ip` (iproute2): {0}")]
    NoIpTool(#[source] std::io::Error),
    /// An `ip` command failed.
    #[error("`ip {args}` failed: {stderr}")]
    Command {
        /// The arguments.
        args: String,
        /// What `ip` printed.
        stderr: String,
    },
    /// Entering the namespace failed.
    #[error("entering network namespace {name} failed: {source}")]
    Enter {
        /// Namespace name.
        name: String,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The thread running inside the namespace panicked.
    #[error("the thread running inside network namespace {0} panicked")]
    ThreadPanicked(String),
    /// A link error inside the namespace.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The veth pair did not come up.
    #[error("veth pair {host}/{peer} has no carrier after {waited_ms} ms")]
    NoCarrier {
        /// The host end.
        host: String,
        /// The peer end.
        peer: String,
        /// How long we waited.
        waited_ms: u64,
    },
}

fn ip(args: &[&str]) -> Result<(), NetnsError> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(NetnsError::NoIpTool)?;
    if out.status.success() {
        Ok(())
    } else {
        Err(NetnsError::Command {
            args: args.join(" "),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_owned(),
        })
    }
}

static COUNTER: AtomicU32 = AtomicU32::new(0);

fn base36(mut v: u32) -> String {
    const DIGITS: &[u8] = b"0123456789abcdefghijklmnopqrstuvwxyz";
    let mut s = Vec::new();
    loop {
        s.push(DIGITS.get((v % 36) as usize).copied().unwrap_or(b'0'));
        v /= 36;
        if v == 0 {
            break;
        }
    }
    s.reverse();
    String::from_utf8(s).unwrap_or_default()
}

/// Remove `ecdrive-<pid>-<n>` namespaces whose process no longer exists.
fn remove_stale() {
    let Ok(entries) = std::fs::read_dir("/run/netns") else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = name.strip_prefix("ecdrive-") else {
            continue;
        };
        let Some(pid) = rest.split('-').next() else {
            continue;
        };
        if pid.parse::<u32>().is_ok() && !std::path::Path::new(&format!("/proc/{pid}")).exists() {
            let _ = ip(&["netns", "del", &name]);
        }
    }
}

/// A network namespace, deleted on drop.
#[derive(Debug)]
pub struct Netns {
    name: String,
}

impl Netns {
    /// Create a namespace with a unique name.
    pub fn create() -> Result<Self, NetnsError> {
        remove_stale();
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let name = format!("ecdrive-{}-{n}", std::process::id());
        ip(&["netns", "add", &name])?;
        let ns = Self { name };
        ns.run(|| {
            let _ = set_loopback_up();
        })?;
        Ok(ns)
    }

    /// The namespace name (usable with `ip netns exec`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Run `f` on a new thread that has entered the namespace, and return its result. Sockets
    /// created inside stay in the namespace when used from other threads afterwards.
    pub fn run<T: Send + 'static>(
        &self,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Result<T, NetnsError> {
        let path = format!("/run/netns/{}", self.name);
        let name = self.name.clone();
        let file = File::open(&path).map_err(|source| NetnsError::Enter {
            name: name.clone(),
            source,
        })?;
        let handle = std::thread::Builder::new()
            .name(format!("netns {name}"))
            .spawn(move || {
                nix::sched::setns(&file, nix::sched::CloneFlags::CLONE_NEWNET)
                    .map_err(|e| std::io::Error::from_raw_os_error(e as i32))?;
                Ok::<T, std::io::Error>(f())
            })
            .map_err(|source| NetnsError::Enter {
                name: name.clone(),
                source,
            })?;
        match handle.join() {
            Ok(Ok(v)) => Ok(v),
            Ok(Err(source)) => Err(NetnsError::Enter { name, source }),
            Err(_) => Err(NetnsError::ThreadPanicked(name)),
        }
    }

    /// Open a raw socket on `interface` inside the namespace.
    pub fn open_raw_socket(&self, interface: &str) -> Result<RawSocket, NetnsError> {
        let iface = interface.to_owned();
        Ok(self.run(move || RawSocket::open(&iface))??)
    }
}

impl Drop for Netns {
    fn drop(&mut self) {
        let _ = ip(&["netns", "del", &self.name]);
    }
}

fn set_loopback_up() -> Result<(), NetnsError> {
    ip(&["link", "set", "lo", "up"])
}

/// Disable IPv6 on an interface of the calling thread's namespace (no autoconfiguration noise).
fn disable_ipv6(interface: &str) {
    let _ = std::fs::write(
        format!("/proc/sys/net/ipv6/conf/{interface}/disable_ipv6"),
        "1",
    );
}

/// A veth pair: one end (`host`) in the current network namespace, the other (`peer`) in a
/// fresh namespace. Both ends are up, with IPv6 disabled. Dropping it removes the pair and the
/// namespace.
#[derive(Debug)]
pub struct VethPair {
    host: String,
    peer: String,
    ns: Netns,
}

impl VethPair {
    /// Create a pair with unique names.
    pub fn create() -> Result<Self, NetnsError> {
        let ns = Netns::create()?;
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        // At most 2 + 5 + 1 + 4 + 1 = 13 bytes (IFNAMSIZ allows 15).
        let stem = format!(
            "ec{}x{}",
            base36(std::process::id()),
            base36(n % (36 * 36 * 36 * 36))
        );
        let host = format!("{stem}m");
        let peer = format!("{stem}s");
        ip(&["link", "add", &host, "type", "veth", "peer", "name", &peer])?;
        let pair = Self { host, peer, ns };
        pair.setup()?;
        Ok(pair)
    }

    fn setup(&self) -> Result<(), NetnsError> {
        ip(&["link", "set", &self.peer, "netns", self.ns.name()])?;
        disable_ipv6(&self.host);
        ip(&["link", "set", &self.host, "up"])?;
        let peer = self.peer.clone();
        self.ns.run(move || {
            disable_ipv6(&peer);
            ip(&["link", "set", &peer, "up"])
        })??;
        // The carrier comes up asynchronously; frames sent before are silently dropped, which
        // a master sees as a lost first frame. The host end has carrier only when both ends
        // are up.
        let carrier = format!("/sys/class/net/{}/carrier", self.host);
        let start = std::time::Instant::now();
        let limit = std::time::Duration::from_secs(5);
        loop {
            if std::fs::read_to_string(&carrier).is_ok_and(|c| c.trim() == "1") {
                return Ok(());
            }
            if start.elapsed() > limit {
                return Err(NetnsError::NoCarrier {
                    host: self.host.clone(),
                    peer: self.peer.clone(),
                    waited_ms: limit.as_millis() as u64,
                });
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    /// The end in the current namespace.
    pub fn host(&self) -> &str {
        &self.host
    }

    /// The end inside the namespace.
    pub fn peer(&self) -> &str {
        &self.peer
    }

    /// The namespace holding the peer end.
    pub fn netns(&self) -> &Netns {
        &self.ns
    }

    /// Open a raw socket on the peer end (inside the namespace).
    pub fn open_peer_socket(&self) -> Result<RawSocket, NetnsError> {
        self.ns.open_raw_socket(&self.peer)
    }

    /// Open a raw socket on the host end.
    pub fn open_host_socket(&self) -> Result<RawSocket, LinkError> {
        RawSocket::open(&self.host)
    }
}

impl Drop for VethPair {
    fn drop(&mut self) {
        // Deleting one end removes both at once; deleting only the namespace would leave the
        // host end around until the kernel's asynchronous namespace cleanup runs.
        let _ = ip(&["link", "del", &self.host]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base36_names_are_short() {
        assert_eq!(base36(0), "0");
        assert_eq!(base36(35), "z");
        assert_eq!(base36(36), "10");
        // Largest Linux PID (4194304) and the largest counter value used.
        let stem = format!("ec{}x{}", base36(4_194_304), base36(36 * 36 * 36 * 36 - 1));
        assert!(stem.len() + 1 < 16, "{stem}");
    }

    #[test]
    fn veth_pair_lifecycle() {
        if !require_root("link::netns::tests::veth_pair_lifecycle") {
            return;
        }
        let host;
        let ns_name;
        {
            let pair = VethPair::create().unwrap();
            host = pair.host().to_owned();
            ns_name = pair.netns().name().to_owned();
            let sock = pair.open_host_socket().unwrap();
            let peer = pair.open_peer_socket().unwrap();
            // A frame sent on one end arrives on the other.
            let mut f = [0u8; 30];
            f[0..6].copy_from_slice(&[0xFF; 6]);
            f[6..12].copy_from_slice(&[0x10; 6]);
            f[12..14].copy_from_slice(&[0x88, 0xA4]);
            f[14] = 0x0E;
            f[15] = 0x10;
            sock.send(&f).unwrap();
            let mut buf = [0u8; 1600];
            let n = peer
                .recv(&mut buf, Some(std::time::Duration::from_secs(5)))
                .unwrap();
            assert_eq!(n, Some(30));
            assert_eq!(&buf[..30], &f);
            // The sender does not see its own frame.
            assert_eq!(
                sock.recv(&mut buf, Some(std::time::Duration::from_millis(20)))
                    .unwrap(),
                None
            );
        }
        assert!(RawSocket::open(&host).is_err(), "host end removed");
        assert!(
            !std::path::Path::new(&format!("/run/netns/{ns_name}")).exists(),
            "namespace removed"
        );
    }
}
