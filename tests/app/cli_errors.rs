//! Wrong input to `ecdrive` gives one clear line on stderr and the documented exit code, never
//! a panic or a backtrace; plus the commands that need no bus (`esi`, `run --check`,
//! `sim --list-devices`) and the in-process `sim:` target. No root needed.

use crate::support;
use support::cli::ecdrive;

fn write_temp(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ecdrive-cli-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn usage_errors_are_one_line_with_exit_2() {
    ecdrive(&["upload", "-i", "sim:generic-coe", "-p", "0", "0x60zz:00"])
        .fails(2, &["0x60zz:00", "the index is not a number", "INDEX:SUB"]);
    ecdrive(&["upload", "-i", "sim:generic-coe", "-p", "0", "0x6040:0x100"])
        .fails(2, &["the sub-index is larger than 0xFF"]);
    ecdrive(&[
        "upload",
        "-i",
        "sim:generic-coe",
        "-p",
        "0",
        "0x6040",
        "--type",
        "u7",
    ])
    .fails(2, &["unknown data type \"u7\""]);
    ecdrive(&["upload", "-i", "sim:generic-coe", "0x6040"]).fails(2, &["--position"]);
    ecdrive(&["upload", "-i", "sim:generic-coe", "-p", "x", "0x6040"])
        .fails(2, &["invalid value 'x'"]);
    ecdrive(&["states", "-i", "sim:generic-coe", "OPERATIONAL"])
        .fails(2, &["unknown state \"OPERATIONAL\""]);
    ecdrive(&["slavs"]).fails(2, &["unrecognized subcommand 'slavs'"]);
    ecdrive(&["reg", "-i", "sim:generic-coe", "-p", "0", "read", "0x1FFFF"])
        .fails(2, &["larger than 0xFFFF"]);
    ecdrive(&["upload", "--can", "virtual", "-n", "200", "0x6041"])
        .fails(2, &["node-ID \"200\" is not in 1–127"]);
}

#[test]
fn input_that_does_not_fit_the_devices_is_exit_2() {
    ecdrive(&["upload", "-i", "sim:generic-coe", "-p", "3", "0x1000"])
        .fails(2, &["position 3", "the segment has 1 device (position 0)"]);
    ecdrive(&[
        "download",
        "-i",
        "sim:generic-coe",
        "-p",
        "0",
        "0x6040:00",
        "70000",
    ])
    .fails(
        2,
        &["value 70000 is out of range for UNSIGNED16 (0..=65535)"],
    );
    ecdrive(&[
        "download",
        "-i",
        "sim:generic-coe",
        "-p",
        "0",
        "0x6040:00",
        "12abc",
    ])
    .fails(2, &["\"12abc\" is not a valid UNSIGNED16 value"]);
    ecdrive(&["slaves", "-i", "sim:warp-drive"]).fails(2, &["unknown device \"warp-drive\""]);
    ecdrive(&["slaves", "-i", "sim:"]).fails(2, &["name at least one emulated device"]);
}

#[test]
fn an_unknown_interface_is_a_link_error() {
    ecdrive(&["slaves", "-i", "nosuchif0"]).fails(3, &["nosuchif0"]);
    ecdrive(&["upload", "-i", "nosuchif0", "-p", "0", "0x1000"]).fails(3, &["nosuchif0"]);
    ecdrive(&["sim", "-i", "nosuchif0", "--device", "generic-coe"]).fails(3, &["nosuchif0"]);
    ecdrive(&["sim", "-i", "lo", "--device", "warp-drive"])
        .fails(2, &["unknown device \"warp-drive\""]);
}

#[test]
fn a_bad_configuration_file_names_line_key_and_reason() {
    let bad = write_temp(
        "bad.toml",
        "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\"]\n\n[[drive]]\nposition = 0\nvelocty = 3\n",
    );
    let path = bad.display().to_string();
    let line = ecdrive(&["run", "-c", &path]).fails(
        2,
        &[
            &path,
            "line 7, column 1",
            "drive[0].velocty",
            "unknown key `velocty`",
        ],
    );
    assert!(line.starts_with("ecdrive run: "), "{line}");
    ecdrive(&["run", "-c", "/nonexistent/x.toml"]).fails(2, &["cannot read the file"]);
    let good = write_temp(
        "good.toml",
        "interface = \"sim\"\ncycle = \"500us\"\n[sim]\ndevices = [\"generic-coe\"]\n[[drive]]\nposition = 0\n",
    );
    let out = ecdrive(&["run", "-c", &good.display().to_string(), "--check"]);
    assert!(
        out.ok()
            .contains("valid; 1 drive entry, cycle 500 µs, on sim:generic-coe"),
        "{out:#?}"
    );
    let j = ecdrive(&[
        "run",
        "-c",
        &good.display().to_string(),
        "--check",
        "--json",
    ])
    .json();
    assert_eq!(j["valid"], true);
    assert_eq!(j["cycle_ns"], 500_000);
    // The generic device has no drive profile: the run refuses it at start-up, naming it.
    ecdrive(&["run", "-c", &good.display().to_string()]).fails(
        2,
        &[
            "drive 0 (ECD-COE402)",
            "unknown device",
            "vendor 0x00000ECD",
        ],
    );
}

#[test]
fn esi_show_and_check() {
    let show = ecdrive(&["esi", "show", "esi/Mitsubishi_MR-J4-TM.xml"])
        .ok()
        .to_string();
    assert!(
        show.contains("vendor 0x00000A1E \"Mitsubishi Electric Corporation\""),
        "{show}"
    );
    assert!(show.contains("product 0x00000201"), "{show}");
    assert!(show.contains("RxPDO 0x1600"), "{show}");
    let j = ecdrive(&["esi", "show", "esi/Mitsubishi_MR-J4-TM.xml", "--json"]).json();
    assert_eq!(j["vendor_id"], 0xA1E);
    assert_eq!(j["devices"][0]["product_code"], 0x201);
    assert_eq!(
        j["devices"][0]["default_image_bytes"],
        serde_json::json!([29, 41])
    );
    let c = ecdrive(&["esi", "check", "esi/Servotronix_BDHDE.xml"])
        .ok()
        .to_string();
    assert!(c.contains("valid (1 device(s))"), "{c}");

    let bad = write_temp(
        "bad.xml",
        "<EtherCATInfo>\n  <Vendor><Id>#xZZ</Id></Vendor>\n</EtherCATInfo>\n",
    );
    let r = ecdrive(&["esi", "check", &bad.display().to_string()]);
    assert_eq!(r.code, Some(2), "{r:#?}");
    assert!(r.stdout.contains("line 2, column"), "{r:#?}");
    assert!(r.stdout.contains("<Vendor>"), "{r:#?}");
    let rj = ecdrive(&["esi", "check", &bad.display().to_string(), "--json"]);
    assert_eq!(rj.code, Some(2));
    let v: serde_json::Value = serde_json::from_str(&rj.stdout).unwrap();
    assert_eq!(v["valid"], false);
    assert_eq!(v["issues"][0]["line"], 2);
    ecdrive(&["esi", "show", &bad.display().to_string()]).fails(2, &["line 2, column"]);
    ecdrive(&["esi", "show", "/nonexistent.xml"]).fails(2, &["cannot read"]);
}

#[test]
fn help_documents_exit_codes_and_examples() {
    let h = ecdrive(&["--help"]).ok().to_string();
    for line in [
        "2  usage or input error",
        "3  bus or link error",
        "4  a drive refused",
        "5  a drive faulted",
    ] {
        assert!(h.contains(line), "{h}");
    }
    for cmd in [
        "slaves", "upload", "download", "sdos", "pdos", "states", "reg", "sii", "esi", "run", "sim",
    ] {
        let c = ecdrive(&[cmd, "--help"]).ok().to_string();
        assert!(c.contains("Examples:"), "{cmd}: {c}");
    }
    let list = ecdrive(&["sim", "--list-devices", "--json"]).json();
    let devices = &list["devices"];
    assert!(
        devices
            .as_array()
            .unwrap()
            .iter()
            .any(|d| d["name"] == "generic-coe")
    );
    assert_eq!(devices[0]["name"], "mr-j4-tm");
    assert_eq!(devices[1]["name"], "bdhde");
    assert!(
        list["quirks"]
            .as_array()
            .unwrap()
            .iter()
            .any(|q| q["name"] == "no-state-skipping")
    );
}

#[test]
fn the_in_process_target_needs_no_root() {
    let j = ecdrive(&["slaves", "-i", "sim:generic-coe,generic-io", "--json"]).json();
    assert_eq!(j.as_array().unwrap().len(), 2);
    assert_eq!(j[1]["name"], "ECD-IO");
    let v = ecdrive(&["upload", "-i", "sim:generic-coe", "-p", "0", "0x1018:01"])
        .ok()
        .to_string();
    assert_eq!(v.trim(), "0x00000ECD 3789");
    // A device without CoE: its PDOs come from the SII.
    let io = ecdrive(&["pdos", "-i", "sim:generic-io", "-p", "0", "--json"]).json();
    assert_eq!(io["source"], "sii");
    assert_eq!(io["sync_managers"][0]["pdos"][0]["index"], 0x1600);
    let t = ecdrive(&["pdos", "-i", "sim:generic-io", "-p", "0"])
        .ok()
        .to_string();
    assert!(t.contains("(from the SII: the device has no CoE)"), "{t}");
    assert!(
        t.contains("PDO entry 0x7000:01,  8 bit, offset   0, \"Output 1\""),
        "{t}"
    );
}

#[test]
fn canopen_nodes_on_the_virtual_bus() {
    let s = ecdrive(&["slaves", "--can", "virtual"]).ok().to_string();
    assert!(s.contains("BLV-R"), "{s}");
    assert!(s.contains("ASDA-A2"), "{s}");
    assert!(s.contains("Lexium"), "{s}");
    let j = ecdrive(&["slaves", "--can", "virtual", "--json"]).json();
    let nodes: Vec<u64> = j
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["node"].as_u64().unwrap())
        .collect();
    assert_eq!(nodes, vec![1, 0x41, 0x7F]);
    let u = ecdrive(&[
        "upload",
        "--can",
        "virtual",
        "-n",
        "0x7F",
        "0x6041:00",
        "--json",
    ])
    .json();
    assert_eq!(u["node"], 0x7F);
    assert_eq!(u["data_type"], "UNSIGNED16");
    let d = ecdrive(&[
        "download",
        "--can",
        "virtual",
        "-n",
        "1",
        "0x6081:00",
        "20000",
    ])
    .ok()
    .to_string();
    assert!(d.contains("0x6081:00 = 20000"), "{d}");
    ecdrive(&["download", "--can", "virtual", "-n", "1", "0x6081:00", "-5"])
        .fails(2, &["node 1", "out of range for UNSIGNED32"]);
    ecdrive(&["upload", "--can", "virtual", "-n", "5", "0x6041:00"])
        .fails(3, &["node 5 (0x05) does not answer"]);
    // An object the drive's profile lacks takes CiA 301's type (1008h: VISIBLE_STRING), and
    // the drive itself says it has none; a vendor object without a type needs -t.
    ecdrive(&["upload", "--can", "virtual", "-n", "0x7F", "0x1008:00"])
        .fails(4, &["node 127", "0x1008:00", "Object does not exist"]);
    ecdrive(&["upload", "--can", "virtual", "-n", "0x7F", "0x2345:00"])
        .fails(2, &["node 127", "give the type"]);
}

/// `ecdrive version`: this build's facts, as text and JSON (the commit is git's, or `unknown`
/// outside a checkout).
#[test]
fn version_names_ecdrive_ethercrab_and_the_profiles() {
    let text = ecdrive(&["version"]).ok().to_string();
    assert!(text.starts_with("ecdrive 0.1.0 (commit "), "{text}");
    assert!(text.contains("ethercrab 0.7.1"), "{text}");
    assert!(text.contains("mr-j4-tm (MR-J4-TM)"), "{text}");
    let v = ecdrive(&["version", "--json"]).json();
    assert_eq!(v["ethercrab"], "0.7.1");
    assert!(v["commit"].as_str().is_some_and(|c| !c.is_empty()));
    assert!(v["features"].is_array());
}

/// An SDO download the drive refuses for a reason its manual gives says the manual's reason:
/// the MR-J4-TM refuses one to an object mapped in its RxPDO (§4.2, abort 0x06010006), as
/// KickCAT's DS402 sequence (0x6060 by SDO in PRE-OP) meets it.
#[test]
fn a_refusal_the_manual_explains_says_so() {
    // Exit 4: a drive refused.
    let e = ecdrive(&[
        "download",
        "-i",
        "sim:mr-j4-tm",
        "-p",
        "0",
        "0x6060:00",
        "8",
    ])
    .fails(
        4,
        &[
            "SDO abort 0x06010006",
            "manual §4.2",
            "write it through the PDO, or remap in PRE-OP without it first",
        ],
    );
    assert_eq!(e.lines().count(), 1, "{e}");
}
