//! `ecdrive run --check` catches what start-up would refuse, whenever the drives' profiles are
//! known from the file (`[sim]`, `profile`, `identity`), and says which checks it could not
//! make otherwise. What it cannot see gets a clear start-up error naming the drive, the object
//! and the reason. One case per item of the newcomer's list (issue "any configuration, any
//! device").

use crate::support;
use support::cli::ecdrive;

struct Files(std::path::PathBuf);

impl Files {
    /// A directory of its own for each test: tests run in parallel and each removes its own.
    fn new() -> Self {
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let d = std::env::temp_dir().join(format!("ecdrive-check-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        Self(d)
    }

    fn write(&self, name: &str, text: &str) -> String {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    }
}

impl Drop for Files {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const SIM: &str = "interface = \"sim\"\n[sim]\ndevices = [\"mr-j4-tm\", \"bdhde\"]\n";

/// `--check` fails with exit 2, one line naming the file, the key and `has`.
#[track_caller]
fn caught(files: &Files, name: &str, text: &str, key: &str, has: &[&str]) {
    let f = files.write(name, text);
    let mut all = vec![name, key];
    all.extend_from_slice(has);
    ecdrive(&["run", "-c", &f, "--check"]).fails(2, &all);
}

#[test]
fn a_cycle_time_a_drive_does_not_accept_even_without_a_drive_table() {
    let files = Files::new();
    caught(
        &files,
        "cycle.toml",
        &SIM.replace(
            "interface = \"sim\"\n",
            "interface = \"sim\"\ncycle = \"100us\"\n",
        ),
        "cycle",
        &["100 µs", "MR-J4-TM", "250, 500, 1000, 2000 µs"],
    );
}

#[test]
fn a_mapping_without_the_controlword_statusword_or_set_point() {
    let files = Files::new();
    let m = |rx: &str, tx: &str, extra: &str| {
        format!(
            "{SIM}[[drive]]\nposition = 0\n{extra}[drive.mapping]\nrx = [{{ pdo = 0x1600, entries = [{rx}] }}]\ntx = [{{ pdo = 0x1A00, entries = [{tx}] }}]\n"
        )
    };
    caught(
        &files,
        "cw.toml",
        &m("\"0x607A:00\"", "\"0x6041:00\"", ""),
        "drive[0].mapping",
        &["controlword (0x6040:00)", "RxPDO"],
    );
    caught(
        &files,
        "sw.toml",
        &m("\"0x6040:00\", \"0x607A:00\"", "\"0x6064:00\"", ""),
        "drive[0].mapping",
        &["statusword (0x6041:00)", "TxPDO"],
    );
    caught(
        &files,
        "csv.toml",
        &m(
            "\"0x6040:00\", \"0x607A:00\"",
            "\"0x6041:00\"",
            "mode = \"csv\"\n",
        ),
        "drive[0].mapping",
        &["target velocity of csv (0x60FF:00)"],
    );
    // A program that switches to cst needs 0x6071 and 0x6060 too.
    caught(
        &files,
        "switch.toml",
        &m(
            "\"0x6040:00\", \"0x607A:00\", \"0x6060:00\"",
            "\"0x6041:00\"",
            "program = [{ step = \"mode\", mode = \"cst\" }]\n",
        ),
        "drive[0].mapping",
        &["target torque of cst (0x6071:00)"],
    );
}

#[test]
fn a_forced_profile_that_does_not_fit_the_device() {
    let files = Files::new();
    caught(
        &files,
        "profile.toml",
        &format!("{SIM}[[drive]]\nposition = 0\nprofile = \"bdhde\"\n"),
        "drive[0].profile",
        &["BDHDE profile does not fit emulated device 0", "MR-J4-TM"],
    );
    // A device that is no drive, named as one.
    caught(
        &files,
        "io.toml",
        "interface = \"sim\"\n[sim]\ndevices = [\"mr-j4-tm\", \"generic-io\"]\n[[drive]]\nposition = 1\n",
        "drive[0].position",
        &["generic-io", "no CiA 402 drive"],
    );
    // Where the file cannot know the device, start-up says it: the file forces the MR-J4-TM
    // profile, the device at position 0 is a BDHDE.
    let f = files.write(
        "startup.toml",
        &format!("{SIM}[[drive]]\nposition = 0\nprofile = \"mr-j4-tm\"\n"),
    );
    ecdrive(&["run", "-c", &f, "-i", "sim:bdhde,mr-j4-tm"]).fails(
        2,
        &[
            "drive 0 (BDHDE)",
            "matching a drive profile",
            "forces the MR-J4-TM profile",
            "vendor 0x000002E1, product 0x000BE2EB",
        ],
    );
}

#[test]
fn torque_and_velocity_beyond_the_drives_documented_maximum_warn_with_the_number() {
    let files = Files::new();
    let f = files.write(
        "rated.toml",
        &format!(
            "{SIM}[[drive]]\nposition = 1\nmode = \"cst\"\nprogram = [{{ step = \"torque\", torque = 6000, hold = 0.1 }}]\n\
             [[drive]]\nposition = 0\nprogram = [{{ step = \"move\", by = 100000000, velocity = 1e10, acceleration = 1e11 }}]\n"
        ),
    );
    let out = ecdrive(&["run", "-c", &f, "--check"]);
    let text = out.ok();
    assert!(
        text.contains(
            "warning: drive[0].program[0]: torque 6000 (0.1 % of rated torque) is beyond the BDHDE's 5000"
        ),
        "{text}"
    );
    // 1e10 counts/s at 4 194 304 counts/rev: 143 051 r/min, beyond 20 000.
    assert!(
        text.contains(
            "warning: drive[1].program[0]: 143051.1 r/min is beyond the MR-J4-TM's 20000 r/min"
        ),
        "{text}"
    );
    let j = ecdrive(&["run", "-c", &f, "--check", "--json"]).json();
    assert_eq!(j["warnings"].as_array().unwrap().len(), 2, "{j:#}");
}

#[test]
fn a_cpu_that_does_not_exist() {
    let files = Files::new();
    caught(
        &files,
        "cpu.toml",
        "interface = \"eth9\"\n[rt]\ncpu = 4096\n",
        "rt.cpu",
        &["CPU 4096 does not exist on this machine"],
    );
}

#[test]
fn without_profiles_it_says_what_it_could_not_check() {
    let files = Files::new();
    let f = files.write(
        "eth.toml",
        "interface = \"eth9\"\n[[drive]]\nposition = 0\nmode = \"csv\"\n",
    );
    let out = ecdrive(&["run", "-c", &f, "--check"]);
    let text = out.ok();
    assert!(
        text.contains("not checked: drive[0] (position 0): its profile is not known from the file"),
        "{text}"
    );
    assert!(
        text.contains("not checked: devices without a [[drive]] table"),
        "{text}"
    );
    let j = ecdrive(&["run", "-c", &f, "--check", "--json"]).json();
    assert_eq!(j["unchecked"].as_array().unwrap().len(), 2, "{j:#}");
    // With a profile named, the same entry is checked.
    let f = files.write(
        "named.toml",
        "interface = \"eth9\"\n[[drive]]\nposition = 0\nprofile = \"mr-j4-tm\"\nmode = \"csv\"\n",
    );
    let j = ecdrive(&["run", "-c", &f, "--check", "--json"]).json();
    assert_eq!(j["unchecked"].as_array().unwrap().len(), 1, "{j:#}");
}

/// A selector that matches nothing on the segment is named as a user writes it (no Rust
/// `Debug` text such as `Identity { vendor_id: 737, … }`).
#[test]
fn a_selector_matching_nothing_is_named_plainly() {
    let files = Files::new();
    let f = files.write(
        "nomatch.toml",
        "interface = \"sim\"\n[sim]\ndevices = [\"bdhde\"]\n[[drive]]\nidentity = { vendor_id = 0x2E1, product_code = 1 }\n",
    );
    ecdrive(&["run", "-c", &f]).fails(
        2,
        &[
            "no device on the segment matches vendor 0x000002E1 product 0x00000001",
            "0 BDHDE",
        ],
    );
}
