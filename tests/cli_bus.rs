//! Every bus command of `ecdrive` against `ecdrive sim` on a veth pair in a namespace the test
//! creates: the text output carries the right data for the emulated devices, and the `--json`
//! output parses and carries the same facts. Needs root (skips loudly without it; fails under
//! `ECDRIVE_CI`).

mod support {
    pub mod cli;
}
use serde_json::Value;
use support::cli::SimOnVeth;

/// The devices on the wire, in line order.
const DEVICES: &[&str] = &["generic-coe", "generic-io"];

/// Identity of the devices as the simulator states it (vendor 0xECD is the test vendor).
const IDENTITY: &[(u32, u32, &str)] = &[(0xECD, 0x402, "ECD-COE402"), (0xECD, 0x101, "ECD-IO")];

fn start(test: &str) -> Option<SimOnVeth> {
    SimOnVeth::start(test, DEVICES)
}

#[test]
fn slaves_lists_every_device_in_text_and_json() {
    let Some(sim) = start("cli_bus::slaves_lists_every_device_in_text_and_json") else {
        return;
    };
    let text = sim.ecdrive(&["slaves"]).ok().to_string();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows.len(), 1 + DEVICES.len(), "{text}");
    assert!(rows[0].starts_with("POS  ADDR"), "{text}");
    for (i, (vendor, product, name)) in IDENTITY.iter().enumerate() {
        let row = rows[i + 1];
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(cells[0], i.to_string(), "{row}");
        assert_eq!(cells[1], format!("0x{:04X}", 0x1000 + i), "{row}");
        assert_eq!(cells[3], "PREOP", "{row}");
        assert_eq!(cells[4], format!("0x{vendor:08X}"), "{row}");
        assert_eq!(cells[5], format!("0x{product:08X}"), "{row}");
        assert_eq!(
            cells[7],
            i.to_string(),
            "serial = position in the sim: {row}"
        );
        assert!(row.contains(name), "{row}");
    }
    assert!(rows[1].contains(" CoE "), "{text}");

    let j = sim.ecdrive(&["slaves", "--json"]).json();
    let list = j.as_array().expect("array");
    assert_eq!(list.len(), DEVICES.len());
    for (i, (vendor, product, name)) in IDENTITY.iter().enumerate() {
        let d = &list[i];
        assert_eq!(d["position"], i as u64);
        assert_eq!(d["address"], 0x1000 + i as u64);
        assert_eq!(d["vendor_id"], u64::from(*vendor));
        assert_eq!(d["product_code"], u64::from(*product));
        assert_eq!(d["serial"], i as u64);
        assert_eq!(d["name"], *name);
        assert_eq!(d["al"]["state"], "PREOP");
        assert_eq!(d["dc"], true);
    }
    assert_eq!(list[0]["mailbox_protocols"], serde_json::json!(["CoE"]));
    assert_eq!(list[1]["mailbox_protocols"], serde_json::json!([]));

    let v = sim.ecdrive(&["slaves", "--verbose"]).ok().to_string();
    assert!(
        v.contains("=== Position 0, station address 0x1000 ==="),
        "{v}"
    );
    assert!(v.contains("Standard RX: 0x1000/128, TX: 0x1080/128"), "{v}");
    assert!(v.contains("Distributed clocks: yes"), "{v}");
    let vj = sim.ecdrive(&["slaves", "--verbose", "--json"]).json();
    assert_eq!(vj[0]["detail"]["mailbox"]["rx_size"], 128);
    assert_eq!(vj[0]["detail"]["eeprom_bytes"], 2048);
    assert_eq!(vj[1]["detail"]["mailbox"], Value::Null);
}

#[test]
fn upload_and_download_round_trip_with_inferred_types() {
    let Some(sim) = start("cli_bus::upload_and_download_round_trip_with_inferred_types") else {
        return;
    };
    // Identity over CoE agrees with the SII.
    let out = sim
        .ecdrive(&["upload", "-p", "0", "0x1018:02"])
        .ok()
        .to_string();
    assert_eq!(out.trim(), "0x00000402 1026");
    let j = sim
        .ecdrive(&["upload", "-p", "0", "0x1018:02", "--json"])
        .json();
    assert_eq!(j["value"], 0x402);
    assert_eq!(j["hex"], "0x00000402");
    assert_eq!(j["data_type"], "UNSIGNED32");
    assert_eq!(j["type_source"], "sdo_info");
    assert_eq!(j["bytes"], "02040000");
    let name = sim
        .ecdrive(&["upload", "-p", "0", "0x1008"])
        .ok()
        .to_string();
    assert_eq!(name.trim(), "ecdrive generic CoE device");

    // Download a mode of operation (INTEGER8 from SDO information), read it back.
    let d = sim
        .ecdrive(&["download", "-p", "0", "0x6060:00", "9"])
        .ok()
        .to_string();
    assert!(d.contains("0x6060:00 = 9"), "{d}");
    let back = sim
        .ecdrive(&["upload", "-p", "0", "0x6060:00", "--json"])
        .json();
    assert_eq!(back["value"], 9);
    assert_eq!(back["data_type"], "INTEGER8");
    // Negative values and explicit types.
    sim.ecdrive(&["download", "-p", "0", "0x607A:00", "-1234", "--json"])
        .json();
    let t = sim
        .ecdrive(&["upload", "-p", "0", "0x607A", "--type", "i32"])
        .ok()
        .to_string();
    assert_eq!(t.trim(), "0xFFFFFB2E -1234");
}

#[test]
fn sdos_and_pdos_show_the_dictionary_and_the_mapping() {
    let Some(sim) = start("cli_bus::sdos_and_pdos_show_the_dictionary_and_the_mapping") else {
        return;
    };
    let run = sim.ecdrive(&["sdos", "-p", "0"]);
    assert_eq!(run.stderr, "", "no progress output when piped: {run:#?}");
    let text = run.ok().to_string();
    assert!(text.contains("SDO 0x1018, RECORD, \"Identity\""), "{text}");
    assert!(
        text.contains("  0x1018:02, r-r-r-, UNSIGNED32, 32 bit, \"Product code\""),
        "{text}"
    );
    assert!(
        text.contains("0x6040:00, rwrwrw, UNSIGNED16, 16 bit, rx mappable"),
        "{text}"
    );
    let j = sim
        .ecdrive(&["sdos", "-p", "0", "--values", "--json"])
        .json();
    assert_eq!(j["source"], "sdo_info");
    let objs = j["objects"].as_array().expect("array");
    let identity = objs.iter().find(|o| o["index"] == 0x1018).expect("0x1018");
    assert_eq!(identity["object_code"], "RECORD");
    assert_eq!(identity["entries"][2]["name"], "Product code");
    assert_eq!(identity["entries"][2]["value"], "0x00000402 1026");
    // Every object of the text is in the JSON, and the other way round.
    let text_objects = text.lines().filter(|l| l.starts_with("SDO ")).count();
    assert_eq!(text_objects, objs.len());

    let p = sim.ecdrive(&["pdos", "-p", "0"]).ok().to_string();
    assert!(p.contains("SM2: PhysAddr 0x1100"), "{p}");
    assert!(p.contains("  RxPDO 0x1600"), "{p}");
    assert!(
        p.contains("    PDO entry 0x6040:00, 16 bit, offset   0, \"Controlword\""),
        "{p}"
    );
    assert!(
        p.contains("    PDO entry 0x607A:00, 32 bit, offset  16, \"Target position\""),
        "{p}"
    );
    assert!(
        p.contains("    PDO entry 0x6064:00, 32 bit, offset  16, \"Position actual value\""),
        "{p}"
    );
    let pj = sim.ecdrive(&["pdos", "-p", "0", "--json"]).json();
    assert_eq!(pj["source"], "coe");
    let sm2 = &pj["sync_managers"][2];
    assert_eq!(sm2["kind"], "Outputs");
    assert_eq!(sm2["mapped_bytes"], 6);
    assert_eq!(sm2["pdos"][0]["index"], 0x1600);
    assert_eq!(sm2["pdos"][0]["entries"][1]["address"], "0x607A:00");

    // A device without CoE: the SII's PDOs.
    let io = sim.ecdrive(&["pdos", "-p", "1", "--json"]).json();
    assert_eq!(io["source"], "sii");
    assert_eq!(
        io["sync_managers"][0]["pdos"][0]["entries"]
            .as_array()
            .unwrap()
            .len(),
        2
    );

    // A remap through download shows up in pdos: 0x1600 with the controlword only.
    sim.ecdrive(&["download", "-p", "0", "0x1600:00", "1"]).ok();
    let after = sim.ecdrive(&["pdos", "-p", "0", "--json"]).json();
    // Discovery resets nothing in the drive's dictionary: the remap is still there.
    assert_eq!(
        after["sync_managers"][2]["pdos"][0]["entries"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
}

#[test]
fn states_are_requested_and_reported() {
    let Some(sim) = start("cli_bus::states_are_requested_and_reported") else {
        return;
    };
    let t = sim.ecdrive(&["states", "INIT"]).ok().to_string();
    assert_eq!(t.lines().count(), 1 + DEVICES.len(), "{t}");
    assert!(
        t.lines()
            .skip(1)
            .all(|l| l.contains("INIT") && l.ends_with("ok")),
        "{t}"
    );
    let j = sim.ecdrive(&["states", "OP", "--json"]).json();
    for d in j.as_array().unwrap() {
        assert_eq!(d["requested"], "OP");
        assert_eq!(d["reached"], "OP");
        assert_eq!(d["ok"], true);
    }
    let one = sim
        .ecdrive(&["states", "-p", "1", "safeop", "--json"])
        .json();
    assert_eq!(one.as_array().unwrap().len(), 1);
    assert_eq!(one[0]["position"], 1);
    assert_eq!(one[0]["reached"], "SAFEOP");
    // Refused: the I/O device has no bootstrap mailbox.
    let r = sim.ecdrive(&["states", "-p", "1", "BOOT"]);
    assert_eq!(r.code, Some(4), "{r:#?}");
    assert!(
        r.stdout.contains("refused: AL status code 0x0013"),
        "{r:#?}"
    );
    assert!(r.stderr.contains("did not reach BOOT"), "{r:#?}");
}

#[test]
fn registers_and_the_eeprom() {
    let Some(sim) = start("cli_bus::registers_and_the_eeprom") else {
        return;
    };
    // AL status after discovery: PRE-OP.
    let r = sim
        .ecdrive(&["reg", "-p", "0", "read", "0x0130", "2"])
        .ok()
        .to_string();
    assert_eq!(r.trim(), "0x0130: 02 00");
    let j = sim
        .ecdrive(&[
            "reg", "-p", "0", "read", "0x0130", "--type", "u16", "--json",
        ])
        .json();
    assert_eq!(j["value"], 2);
    assert_eq!(j["bytes"], "0200");
    // ESC type register: the same over both outputs.
    let t = sim
        .ecdrive(&["reg", "-p", "1", "read", "0x0000", "8"])
        .ok()
        .to_string();
    let tj = sim
        .ecdrive(&["reg", "-p", "1", "read", "0x0000", "8", "--json"])
        .json();
    let hex: String = t.trim().trim_start_matches("0x0000: ").split(' ').collect();
    assert_eq!(tj["bytes"], hex);
    // Write and read back ESC memory that discovery does not touch (process data RAM outside
    // every SyncManager): bytes in address order, then a typed value.
    sim.ecdrive(&["reg", "-p", "0", "write", "0x1F00", "78 56 34 12"])
        .ok();
    let back = sim
        .ecdrive(&["reg", "-p", "0", "read", "0x1F00", "--type", "u32"])
        .ok()
        .to_string();
    assert_eq!(back.trim(), "0x1F00: 78 56 34 12  = 305419896 (UNSIGNED32)");
    let w = sim
        .ecdrive(&[
            "reg", "-p", "0", "write", "0x1F00", "-2", "--type", "i16", "--json",
        ])
        .json();
    assert_eq!(w["bytes"], "feff");
    let r = sim
        .ecdrive(&["reg", "-p", "0", "read", "0x1F00", "4"])
        .ok()
        .to_string();
    assert_eq!(r.trim(), "0x1F00: fe ff 34 12");

    // The EEPROM: summary, raw bytes, JSON and an ESI skeleton the parser reads back.
    let run = sim.ecdrive(&["sii", "-p", "0"]);
    // Long operations draw progress on a terminal only: piped, stderr stays empty.
    assert_eq!(run.stderr, "", "{run:#?}");
    let s = run.ok().to_string();
    assert!(
        s.contains(
            "Identity: vendor 0x00000ECD, product 0x00000402, revision 0x00010000, serial 0"
        ),
        "{s}"
    );
    assert!(s.contains("checksum ok"), "{s}");
    let dir = std::env::temp_dir().join(format!("ecdrive-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bin = dir.join("sii.bin");
    sim.ecdrive(&["sii", "-p", "0", "-o", bin.to_str().unwrap()])
        .ok();
    let raw = std::fs::read(&bin).unwrap();
    assert_eq!(raw.len(), 2048);
    let sj = sim.ecdrive(&["sii", "-p", "0", "--json"]).json();
    let hex: String = raw.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(sj["bytes"], hex);
    assert_eq!(sj["info"]["product_code"], 0x402);
    assert_eq!(sj["info"]["general"]["order"], "ECD-COE402");
    let xml = sim.ecdrive(&["sii", "-p", "0", "--esi"]).ok().to_string();
    let esi = ecdrive::esi::EsiFile::parse(&xml).expect("the skeleton parses");
    assert_eq!(esi.vendor.id, 0xECD);
    let dev = esi.device(0x402, Some(0x0001_0000)).expect("device");
    assert_eq!(dev.type_.name_text, "ECD-COE402");
    assert_eq!(dev.sync_managers.len(), 4);
    assert!(dev.has_coe());
    assert!(esi.check().is_empty(), "{:?}", esi.check());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn wrong_input_on_the_bus_gives_one_line_and_an_exit_code() {
    let Some(sim) = start("cli_bus::wrong_input_on_the_bus_gives_one_line_and_an_exit_code") else {
        return;
    };
    sim.ecdrive(&["upload", "-p", "5", "0x1000"])
        .fails(2, &["position 5", "2 devices (positions 0–1)"]);
    sim.ecdrive(&["download", "-p", "0", "0x6060:00", "300"])
        .fails(2, &["0x6060:00", "out of range for INTEGER8 (-128..=127)"]);
    sim.ecdrive(&["download", "-p", "0", "0x1018:01", "5"])
        .fails(
            4,
            &[
                "0x1018:01",
                "0x06010002",
                "Attempt to write a read only object",
            ],
        );
    sim.ecdrive(&["upload", "-p", "0", "0x5FFF:00"])
        .fails(4, &["0x5FFF:00", "Object does not exist"]);
    sim.ecdrive(&["upload", "-p", "1", "0x1000"])
        .fails(2, &["drive 1 (ECD-IO)", "give the type with --type"]);
    sim.ecdrive(&["upload", "-p", "1", "0x1000", "--type", "u32"])
        .fails(3, &["drive 1 (ECD-IO)", "mailbox"]);
    sim.ecdrive(&["sdos", "-p", "9"]).fails(2, &["position 9"]);
    sim.ecdrive(&["reg", "-p", "0", "read", "0xFFFF", "4"])
        .fails(2, &["run past 0xFFFF"]);
}
