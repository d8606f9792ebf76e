//! Writing to devices over veth against `ecdrive sim`: the station alias and a whole SII into
//! the EEPROM (kept across a power cycle of the emulated devices, refused when write-protected
//! or outside INIT/PRE-OP), and firmware over FoE in BOOT on the emulated MR-J4-TM (refused
//! outside BOOT and with a wrong password, with the FoE error codes; in force after the next
//! INIT). Needs root (skips loudly without it; fails under `ECDRIVE_CI`).
//!
//! What the tests check comes from outside the code under test: the FoE error codes are
//! ETG.1000.6's (0x8009 "not in Bootstrap", 0x800A "no rights", as SOES also defines them),
//! the SII checksum is recomputed here with the CRC the ETG specifies (CRC-8, poly 0x07, init
//! 0xFF) rather than taken from the master, and the firmware's identity is read back through
//! CoE (0x1018:03, 0x100A, MR-J4-TM manual §7.3.1(6), (9)).

use crate::support;
use support::cli::SimOnVeth;

/// The CRC-8 of an SII header (ETG.2010: poly 0x07, init 0xFF, over bytes 0–13), computed
/// here bit by bit.
fn sii_crc(b: &[u8]) -> u8 {
    let mut crc: u8 = 0xFF;
    for &x in &b[..14] {
        crc ^= x;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

fn tmp(test: &str, name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ecdrive-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn alias_survives_a_power_cycle_and_write_protection_and_state_refuse_it() {
    let dir = tmp("alias", "eeprom");
    let _ = std::fs::remove_dir_all(&dir);
    let dir_s = dir.to_str().unwrap().to_string();
    let Some(mut sim) = SimOnVeth::start_with(
        "cli_foe::alias_survives_a_power_cycle_and_write_protection_and_state_refuse_it",
        &["mr-j4-tm", "bdhde", "generic-io"],
        &["--eeprom-dir", &dir_s, "--eeprom-write-protect", "2"],
    ) else {
        return;
    };
    // Written by position, without a discovery, in INIT.
    let j = sim
        .ecdrive(&["alias", "-p", "1", "0x1234", "--json"])
        .json();
    assert_eq!(
        (j["previous"].as_u64(), j["alias"].as_u64()),
        (Some(0), Some(0x1234)),
        "{j}"
    );
    assert_eq!(j["al_state"], "INIT");
    assert_eq!(j["words_written"], 2, "word 4 and the checksum: {j}");
    // Not in force before the power cycle.
    assert_eq!(j["register_0x0012"], 0, "{j}");
    // The EEPROM as a master reads it: the alias in word 4, a valid checksum.
    let bin = tmp("alias", "dev1.sii");
    sim.ecdrive(&["sii", "-p", "1", "-o", bin.to_str().unwrap()])
        .ok();
    let b = std::fs::read(&bin).unwrap();
    assert_eq!(u16::from_le_bytes([b[8], b[9]]), 0x1234);
    assert_eq!(b[14], sii_crc(&b), "header checksum");
    // Text output.
    let t = sim
        .ecdrive(&["alias", "-p", "1", "0x1234"])
        .ok()
        .to_string();
    assert!(
        t.contains("station alias 0x1234 (was 0x1234); 0 EEPROM word(s) written"),
        "{t}"
    );

    // A simulated power cycle: the alias is in the ESC's register and in `slaves`.
    let out = sim.power_cycle();
    assert!(out.contains("EEPROMs saved"), "{out}");
    let r = sim
        .ecdrive(&[
            "reg", "-p", "1", "read", "0x0012", "--type", "u16", "--json",
        ])
        .json();
    assert_eq!(r["value"], 0x1234, "{r}");
    let s = sim.ecdrive(&["slaves", "--json"]).json();
    assert_eq!(s[1]["alias"], 0x1234, "{s}");
    assert_eq!(s[0]["alias"], 0, "{s}");

    // Write-protected EEPROM: the write is not acknowledged, the command names it.
    sim.ecdrive(&["alias", "-p", "2", "5"])
        .fails(4, &["device 2", "EEPROM word 0x0004", "write-protected"]);
    // Outside INIT/PRE-OP: refused before anything is written.
    sim.ecdrive(&["states", "SAFEOP"]).ok();
    sim.ecdrive(&["alias", "-p", "0", "9"]).fails(
        2,
        &["device 0", "SAFEOP", "INIT or PRE-OP", "states -p 0 PREOP"],
    );
    // A position that is not there.
    sim.ecdrive(&["alias", "-p", "7", "9"])
        .fails(2, &["device 7", "no device at this position"]);

    // sii write: the MR-J4-TM's image refused on the BDHDE (identity), accepted with --force
    // only after the refusal named it; the device's own image back is accepted and changes
    // nothing.
    sim.ecdrive(&["states", "INIT"]).ok();
    let own = tmp("alias", "dev0.sii");
    sim.ecdrive(&["sii", "-p", "0", "-o", own.to_str().unwrap()])
        .ok();
    sim.ecdrive(&["sii", "write", "-p", "1", own.to_str().unwrap()])
        .fails(2, &["device 1", "vendor 0x00000A1E", "--force"]);
    let j = sim
        .ecdrive(&["sii", "write", "-p", "0", own.to_str().unwrap(), "--json"])
        .json();
    assert_eq!(j["words_written"], 0, "{j}");
    // A changed image (a new alias and checksum, made here) is written and read back.
    let mut img = std::fs::read(&own).unwrap();
    img[8] = 0x21;
    img[9] = 0x43;
    img[14] = sii_crc(&img);
    let changed = tmp("alias", "dev0-changed.sii");
    std::fs::write(&changed, &img).unwrap();
    let j = sim
        .ecdrive(&[
            "sii",
            "write",
            "-p",
            "0",
            changed.to_str().unwrap(),
            "--json",
        ])
        .json();
    assert_eq!(j["words_written"], 2, "{j}");
    sim.power_cycle();
    let s = sim.ecdrive(&["slaves", "--json"]).json();
    assert_eq!(s[0]["alias"], 0x4321, "{s}");
    let _ = std::fs::remove_dir_all(dir.parent().unwrap());
}

#[test]
fn firmware_round_trips_over_foe_in_boot_and_takes_effect_after_init() {
    let Some(sim) = SimOnVeth::start(
        "cli_foe::firmware_round_trips_over_foe_in_boot_and_takes_effect_after_init",
        &["mr-j4-tm", "bdhde"],
    ) else {
        return;
    };
    let fw = tmp("foe", "fw.efw");
    let r = support::cli::ecdrive(&[
        "sim",
        "-d",
        "mr-j4-tm",
        "--make-firmware",
        fw.to_str().unwrap(),
        "--firmware-revision",
        "0x00030001",
        "--firmware-version",
        "B7",
    ]);
    assert_eq!(r.code, Some(0), "{r:#?}");
    let fw_s = fw.to_str().unwrap();
    const PW: &str = "0x4D524A34";
    // In INIT (no mailbox): the command says what to do.
    sim.ecdrive(&["foe", "write", "-p", "0", "--password", PW, "fw", fw_s])
        .fails(2, &["drive 0", "no mailbox", "states -p 0 BOOT"]);
    // In PRE-OP the drive refuses file access: 0x8009 (not in Bootstrap).
    sim.ecdrive(&["states", "PREOP"]).ok();
    sim.ecdrive(&["foe", "write", "-p", "0", "--password", PW, "fw", fw_s])
        .fails(4, &["drive 0 (MR-J4-TM)", "FoE write", "0x8009"]);
    // BOOT: wrong password → 0x800A; right one → written; read back equal.
    let t = sim.ecdrive(&["states", "-p", "0", "BOOT"]).ok().to_string();
    assert!(t.contains("BOOT       BOOT"), "{t}");
    sim.ecdrive(&["foe", "write", "-p", "0", "--password", "1", "fw", fw_s])
        .fails(4, &["drive 0 (MR-J4-TM)", "0x800A"]);
    let w = sim
        .ecdrive(&[
            "foe",
            "write",
            "-p",
            "0",
            "--password",
            PW,
            "fw",
            fw_s,
            "--json",
        ])
        .json();
    let size = std::fs::metadata(&fw).unwrap().len();
    assert_eq!(w["bytes"].as_u64(), Some(size), "{w}");
    assert_eq!(w["al_state"], "BOOT");
    assert!(
        w["packets"].as_u64().unwrap() > 1,
        "more than one packet: {w}"
    );
    let back = tmp("foe", "back.efw");
    let r = sim
        .ecdrive(&[
            "foe",
            "read",
            "-p",
            "0",
            "--password",
            PW,
            "fw",
            back.to_str().unwrap(),
            "--json",
        ])
        .json();
    assert_eq!(r["bytes"].as_u64(), Some(size), "{r}");
    assert_eq!(std::fs::read(&back).unwrap(), std::fs::read(&fw).unwrap());
    // A file that is not there: 0x8001.
    sim.ecdrive(&[
        "foe",
        "read",
        "-p",
        "0",
        "--password",
        PW,
        "nothing",
        back.to_str().unwrap(),
    ])
    .fails(4, &["0x8001"]);
    // Not a firmware image: 0x8004 (illegal).
    let junk = tmp("foe", "junk.bin");
    std::fs::write(&junk, vec![0x55u8; 3000]).unwrap();
    sim.ecdrive(&[
        "foe",
        "write",
        "-p",
        "0",
        "--password",
        PW,
        "junk",
        junk.to_str().unwrap(),
    ])
    .fails(4, &["0x8004"]);
    // BOOT → INIT: the drive restarts with the new firmware; its identity through CoE says so.
    sim.ecdrive(&["states", "-p", "0", "INIT"]).ok();
    let rev = sim
        .ecdrive(&["upload", "-p", "0", "0x1018:03", "--json"])
        .json();
    assert_eq!(rev["hex"], "0x00030001", "{rev}");
    let ver = sim
        .ecdrive(&["upload", "-p", "0", "0x100A", "--json"])
        .json();
    assert_eq!(ver["value"], "B7", "{ver}");
    let _ = std::fs::remove_dir_all(fw.parent().unwrap());
}
