//! `ecdrive version`: what this build is — ecdrive's version and commit, the ethercrab it is
//! built on, the compiler, the build profile and features, and the drive profiles it knows.

use serde::Serialize;
use std::fmt::Write as _;

/// The ethercrab release ecdrive is pinned to (`=0.7.1` in every Cargo.toml that uses it;
/// a test checks it against Cargo.lock).
pub const ETHERCRAB: &str = "0.7.1";

/// The facts of this build.
#[derive(Debug, Clone, Serialize)]
pub struct Version {
    /// ecdrive's version (Cargo.toml).
    pub ecdrive: &'static str,
    /// The git commit the binary was built from, or `unknown`.
    pub commit: &'static str,
    /// The ethercrab release.
    pub ethercrab: &'static str,
    /// The compiler (`rustc --version`).
    pub rustc: &'static str,
    /// `release` or `debug`.
    pub profile: &'static str,
    /// Cargo features of this build (ecdrive has none today).
    pub features: Vec<&'static str>,
    /// EtherCAT drive profiles built in (key: name).
    pub ethercat_drives: Vec<String>,
    /// CANopen drive profiles built in.
    pub canopen_drives: Vec<String>,
}

impl Version {
    /// This build's facts.
    pub fn this_build() -> Self {
        Self {
            ecdrive: env!("CARGO_PKG_VERSION"),
            commit: env!("ECDRIVE_GIT_COMMIT"),
            ethercrab: ETHERCRAB,
            rustc: env!("ECDRIVE_RUSTC"),
            profile: if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            },
            features: Vec::new(),
            ethercat_drives: crate::drives::all()
                .iter()
                .map(|p| format!("{} ({})", p.key, p.name))
                .collect(),
            canopen_drives: crate::drives::CANOPEN_PROFILES
                .iter()
                .map(|p| format!("{} ({})", p.name, p.vendor))
                .collect(),
        }
    }

    /// The text `ecdrive version` prints.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "ecdrive {} (commit {})", self.ecdrive, self.commit);
        let _ = writeln!(s, "ethercrab {}", self.ethercrab);
        let _ = writeln!(s, "{}, {} build", self.rustc, self.profile);
        let _ = writeln!(
            s,
            "features: {}",
            if self.features.is_empty() {
                "none".to_string()
            } else {
                self.features.join(", ")
            }
        );
        let _ = writeln!(s, "EtherCAT drives: {}", self.ethercat_drives.join(", "));
        let _ = write!(s, "CANopen drives: {}", self.canopen_drives.join(", "));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ethercrab_named_is_the_one_built() {
        let lock = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.lock"))
            .expect("Cargo.lock");
        let built = lock
            .split("[[package]]")
            .find(|p| p.contains("name = \"ethercrab\"\n"))
            .and_then(|p| p.lines().find_map(|l| l.strip_prefix("version = \"")))
            .map(|v| v.trim_end_matches('"'));
        assert_eq!(built, Some(ETHERCRAB));
        let v = Version::this_build();
        assert!(v.text().contains("ethercrab 0.7.1"));
        assert!(v.ethercat_drives.iter().any(|d| d.contains("MR-J4-TM")));
    }
}
