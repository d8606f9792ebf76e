//! Every bus command of `ecdrive` against `ecdrive sim` serving the emulated MR-J4-TM and
//! BDHDE on a veth pair in a namespace the test creates: the text output carries the right data
//! for each drive (checked against the drive profiles and the ESI files, not against the
//! emulator), and the `--json` output parses and carries the same facts. Needs root (skips
//! loudly without it; fails under `ECDRIVE_CI`).

use crate::support;
use ecdrive::drives::{self, DriveProfile};
use ecdrive::esi::EsiFile;
use ecdrive::pdo::Direction;
use support::cli::SimOnVeth;

/// The drives on the wire, in line order.
const DEVICES: &[&str] = &["mr-j4-tm", "bdhde"];
/// Their ESI files.
const ESI: &[&str] = &["esi/Mitsubishi_MR-J4-TM.xml", "esi/Servotronix_BDHDE.xml"];

fn profile(i: usize) -> &'static DriveProfile {
    drives::by_key(DEVICES[i]).expect("profile")
}

fn esi(i: usize) -> EsiFile {
    EsiFile::from_path(ESI[i]).expect("ESI file")
}

fn start(test: &str) -> Option<SimOnVeth> {
    SimOnVeth::start(test, DEVICES)
}

#[test]
fn slaves_lists_both_drives_in_text_and_json() {
    let Some(sim) = start("cli_bus::slaves_lists_both_drives_in_text_and_json") else {
        return;
    };
    let text = sim.ecdrive(&["slaves"]).ok().to_string();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows.len(), 1 + DEVICES.len(), "{text}");
    assert!(rows[0].starts_with("POS  ADDR    ALIAS  STATE"), "{text}");
    let j = sim.ecdrive(&["slaves", "--json"]).json();
    let list = j.as_array().expect("array");
    assert_eq!(list.len(), DEVICES.len());
    for i in 0..DEVICES.len() {
        let (p, f) = (profile(i), esi(i));
        let dev = &f.devices[0];
        let protocols: Vec<&str> = [(0x04, "CoE"), (0x08, "FoE")]
            .into_iter()
            .filter(|(b, _)| dev.mailbox.as_ref().unwrap().protocols.bits() & b != 0)
            .map(|(_, n)| n)
            .collect();
        // Text.
        let row = rows[i + 1];
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(cells[0], i.to_string(), "{row}");
        assert_eq!(cells[1], format!("0x{:04X}", 0x1000 + i), "{row}");
        // The state as found: a fresh segment is in INIT (discovery leaves it in PREOP).
        assert_eq!(cells[3], "INIT", "{row}");
        assert_eq!(cells[4], format!("0x{:08X}", p.identity.vendor_id), "{row}");
        assert_eq!(
            cells[5],
            format!("0x{:08X}", p.identity.product_code),
            "{row}"
        );
        assert_eq!(cells[6], format!("0x{:08X}", p.revision), "{row}");
        assert_eq!(cells[8], "yes", "DC: {row}");
        assert_eq!(cells[9], protocols.join(","), "{row}");
        assert_eq!(cells[10], p.name, "{row}");
        assert!(
            row.ends_with(&format!("{} ({})", dev.type_.name_text, dev.name)),
            "{row}"
        );
        // JSON: the same facts.
        let d = &list[i];
        assert_eq!(d["position"], i as u64);
        assert_eq!(d["address"], 0x1000 + i as u64);
        assert_eq!(d["found"]["state"], "PREOP");
        assert_eq!(d["al"]["state"], "PREOP");
        assert_eq!(d["vendor_id"], u64::from(p.identity.vendor_id));
        assert_eq!(d["product_code"], u64::from(p.identity.product_code));
        assert_eq!(d["revision"], u64::from(p.revision));
        assert_eq!(d["serial"], cells[7].parse::<u64>().unwrap());
        assert_eq!(d["name"], dev.type_.name_text.as_str());
        assert_eq!(d["description"], dev.name.as_str());
        assert_eq!(d["profile"], p.name);
        assert_eq!(d["dc"], true);
        assert_eq!(d["mailbox_protocols"], serde_json::json!(protocols));
    }

    let v = sim.ecdrive(&["slaves", "--verbose"]).ok().to_string();
    assert!(
        v.contains("=== Position 1, station address 0x1001 ==="),
        "{v}"
    );
    assert!(v.contains("Profile: MR-J4-TM (Mitsubishi Electric"), "{v}");
    let vj = sim.ecdrive(&["slaves", "--verbose", "--json"]).json();
    for i in 0..DEVICES.len() {
        let f = esi(i);
        let dev = &f.devices[0];
        let sm = |k| dev.sync_manager(k).unwrap();
        let mbx = &vj[i]["detail"]["mailbox"];
        assert_eq!(
            mbx["rx_offset"],
            sm(ecdrive::esi::SmKind::MBoxOut).start_address
        );
        assert_eq!(
            mbx["tx_offset"],
            sm(ecdrive::esi::SmKind::MBoxIn).start_address
        );
        assert_eq!(
            vj[i]["detail"]["eeprom_bytes"],
            dev.eeprom.as_ref().unwrap().byte_size.unwrap()
        );
        assert!(v.contains(&format!(
            "Standard RX: 0x{:04X}/{}",
            mbx["rx_offset"].as_u64().unwrap(),
            mbx["rx_size"]
        )));
    }
}

#[test]
fn upload_and_download_with_types_from_the_profiles() {
    let Some(sim) = start("cli_bus::upload_and_download_with_types_from_the_profiles") else {
        return;
    };
    for i in 0..DEVICES.len() {
        let p = profile(i);
        let pos = i.to_string();
        // Identity over CoE agrees with the profile.
        let out = sim
            .ecdrive(&["upload", "-p", &pos, "0x1018:02"])
            .ok()
            .to_string();
        let code = p.identity.product_code;
        assert_eq!(out.trim(), format!("0x{code:08X} {code}"));
        let j = sim
            .ecdrive(&["upload", "-p", &pos, "0x1018:02", "--json"])
            .json();
        assert_eq!(j["value"], u64::from(code));
        assert_eq!(j["data_type"], "UNSIGNED32");
        assert_eq!(j["type_source"], "profile");
        assert_eq!(j["drive"], p.name);
        assert_eq!(
            j["bytes"],
            code.to_le_bytes()
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect::<String>()
        );
        let name = sim
            .ecdrive(&["upload", "-p", &pos, "0x1008"])
            .ok()
            .to_string();
        assert_eq!(name.trim(), p.name, "0x1008 of {}", p.name);

        // Following error window (UNSIGNED32 in both dictionaries): write, read back.
        let d = sim
            .ecdrive(&["download", "-p", &pos, "0x6065:00", "123456"])
            .ok()
            .to_string();
        assert_eq!(
            d.trim(),
            "0x6065:00 = 123456 (0x0001E240), UNSIGNED32, type from profile"
        );
        let back = sim
            .ecdrive(&["upload", "-p", &pos, "0x6065", "--json"])
            .json();
        assert_eq!(back["value"], 123456);
        assert_eq!(back["hex"], "0x0001E240");
    }
    // A signed value (the MR-J4-TM's torque offset, INTEGER16), read back as unsigned.
    sim.ecdrive(&["download", "-p", "0", "0x60B2:00", "-100"])
        .ok();
    let t = sim
        .ecdrive(&["upload", "-p", "0", "0x60B2", "--type", "u16"])
        .ok()
        .to_string();
    assert_eq!(t.trim(), "0xFF9C 65436");
    let t = sim
        .ecdrive(&["upload", "-p", "0", "0x60B2"])
        .ok()
        .to_string();
    assert_eq!(t.trim(), "0xFF9C -100");
}

#[test]
fn sdos_and_pdos_show_the_dictionary_and_the_mapping() {
    let Some(sim) = start("cli_bus::sdos_and_pdos_show_the_dictionary_and_the_mapping") else {
        return;
    };
    // The MR-J4-TM answers SDO information.
    let run = sim.ecdrive(&["sdos", "-p", "0"]);
    assert_eq!(run.stderr, "", "no progress output when piped: {run:#?}");
    let text = run.ok().to_string();
    assert!(
        text.contains("SDO 0x1018, RECORD, \"Identity Object\"")
            || text.contains("SDO 0x1018, RECORD"),
        "{text}"
    );
    assert!(text.contains("  0x6040:00, "), "{text}");
    let j = sim
        .ecdrive(&["sdos", "-p", "0", "--values", "--json"])
        .json();
    assert_eq!(j["source"], "sdo_info");
    let objs = j["objects"].as_array().expect("array");
    let text_objects = text.lines().filter(|l| l.starts_with("SDO ")).count();
    assert_eq!(text_objects, objs.len());
    // Every object of the profile's dictionary is on the drive.
    for o in profile(0).dictionary {
        assert!(
            objs.iter().any(|x| x["index"] == u64::from(o.index)),
            "0x{:04X} missing",
            o.index
        );
    }
    let identity = objs.iter().find(|o| o["index"] == 0x1018).expect("0x1018");
    let code = profile(0).identity.product_code;
    assert_eq!(
        identity["entries"][2]["value"],
        format!("0x{code:08X} {code}")
    );
    // The BDHDE has none: its profile's dictionary, said so.
    let b = sim.ecdrive(&["sdos", "-p", "1"]).ok().to_string();
    assert!(b.starts_with("(the drive offers no SDO information"), "{b}");
    let bj = sim.ecdrive(&["sdos", "-p", "1", "--json"]).json();
    assert_eq!(bj["source"], "profile");
    assert_eq!(
        bj["objects"].as_array().unwrap().len(),
        profile(1).dictionary.len()
    );

    // pdos: the power-on mapping of each drive, as its profile states it.
    for i in 0..DEVICES.len() {
        let pos = i.to_string();
        let want = &profile(i).default_mapping;
        let t = sim.ecdrive(&["pdos", "-p", &pos]).ok().to_string();
        let pj = sim.ecdrive(&["pdos", "-p", &pos, "--json"]).json();
        assert_eq!(pj["source"], "coe");
        let sms = pj["sync_managers"].as_array().unwrap();
        for (dir, kind, name) in [
            (Direction::Rx, "Outputs", "RxPDO"),
            (Direction::Tx, "Inputs", "TxPDO"),
        ] {
            let sm = sms.iter().find(|s| s["kind"] == kind).expect(kind);
            assert_eq!(sm["mapped_bytes"], want.bytes(dir) as u64, "{pos} {kind}");
            let pdos = sm["pdos"].as_array().unwrap();
            assert_eq!(pdos.len(), want.pdos(dir).len());
            for (got, w) in pdos.iter().zip(want.pdos(dir)) {
                assert_eq!(got["index"], u64::from(w.index));
                assert!(t.contains(&format!("  {name} 0x{:04X} ", w.index)), "{t}");
                let entries = got["entries"].as_array().unwrap();
                assert_eq!(entries.len(), w.entries.len());
                let mut offset = 0u32;
                for (e, we) in entries.iter().zip(w.entries.iter()) {
                    assert_eq!(e["address"], we.address().to_string());
                    assert_eq!(e["bits"], u64::from(we.bits));
                    assert_eq!(e["bit_offset"], u64::from(offset));
                    assert!(
                        t.contains(&format!(
                            "    PDO entry {}, {:2} bit, offset {:3}, ",
                            we.address(),
                            we.bits,
                            offset
                        )),
                        "{t}"
                    );
                    offset += u32::from(we.bits);
                }
            }
        }
    }
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
            .all(|l| l.contains(" INIT ") && l.ends_with("ok")),
        "{t}"
    );
    // OP: configured as the master does it (profile mapping, DC SYNC0), outputs zero.
    let j = sim.ecdrive(&["states", "OP", "--json"]).json();
    // Where start-up's time went, to OP.
    let st = &j["startup"];
    assert!(st["op_ms"].as_f64().is_some_and(|v| v > 0.0), "{j}");
    assert!(
        st["total_ms"].as_f64() >= st["discovery_ms"].as_f64(),
        "{j}"
    );
    let list = j["devices"].as_array().unwrap();
    assert_eq!(list.len(), DEVICES.len());
    for (i, d) in list.iter().enumerate() {
        assert_eq!(d["drive"], profile(i).name);
        assert_eq!(d["requested"], "OP");
        assert_eq!(d["reached"], "OP");
        assert_eq!(d["ok"], true);
    }
    let one = sim
        .ecdrive(&["states", "-p", "1", "safeop", "--json"])
        .json();
    assert_eq!(one["devices"].as_array().unwrap().len(), 1);
    assert_eq!(one["devices"][0]["position"], 1);
    assert_eq!(one["devices"][0]["reached"], "SAFEOP");
    assert!(one["startup"]["op_ms"].is_null(), "{one}");
    // Refused: the BDHDE has no bootstrap mailbox (the MR-J4-TM has one: tests/app/cli_foe.rs).
    let r = sim.ecdrive(&["states", "-p", "1", "BOOT"]);
    assert_eq!(r.code, Some(4), "{r:#?}");
    assert!(
        r.stdout
            .contains("refused: AL status code 0x0013 (Bootstrap not supported)"),
        "{r:#?}"
    );
    assert!(
        r.stderr.contains("drive 1 (BDHDE) did not reach BOOT"),
        "{r:#?}"
    );
    // `slaves` shows the state each device was left in, as found, before discovery resets it:
    // the refused BOOT request left the BDHDE with the error flag and its code (ETG.1000.6
    // 0x0013 "Bootstrap not supported"); the MR-J4-TM in PREOP, where that command's discovery
    // took it.
    let text = sim.ecdrive(&["slaves"]).ok().to_string();
    let row1 = text.lines().nth(2).unwrap();
    assert!(row1.contains(" INIT+ERR(0x0013) "), "{text}");
    assert!(text.lines().nth(1).unwrap().contains(" PREOP "), "{text}");
    sim.ecdrive(&["states", "-p", "1", "BOOT"]);
    let found = sim.ecdrive(&["slaves", "--json"]).json();
    assert_eq!(found[1]["found"]["state"], "INIT+ERR", "{found:#}");
    assert_eq!(found[1]["found"]["error"], true, "{found:#}");
    assert_eq!(found[1]["found"]["code"], 0x0013, "{found:#}");
    assert_eq!(found[1]["al"]["state"], "PREOP", "{found:#}");
    assert_eq!(found[1]["al"]["error"], false, "{found:#}");
    assert_eq!(found[0]["found"]["state"], "PREOP", "{found:#}");
    sim.ecdrive(&["states", "-p", "1", "SAFEOP"]).ok();
    let v = sim.ecdrive(&["slaves", "--verbose"]).ok().to_string();
    assert!(
        v.contains("State when found: SAFEOP\nState after discovery: PREOP"),
        "{v}"
    );
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
            "reg", "-p", "1", "read", "0x0130", "--type", "u16", "--json",
        ])
        .json();
    assert_eq!(j["value"], 2);
    assert_eq!(j["bytes"], "0200");
    assert_eq!(j["drive"], "BDHDE");
    // Write and read back ESC memory that discovery does not touch (process data RAM outside
    // every SyncManager): bytes in address order, then a typed value.
    sim.ecdrive(&[
        "reg",
        "-p",
        "0",
        "write",
        "0x1F00",
        "78 56 34 12",
        "--bytes",
    ])
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
    // A number is written little-endian for its --type, decimal or 0x alike (the register
    // holds it so); without --type or --bytes the command says which to give.
    for value in ["258", "0x0102"] {
        let w = sim
            .ecdrive(&[
                "reg", "-p", "0", "write", "0x1F00", value, "--type", "u16", "--json",
            ])
            .json();
        assert_eq!(w["bytes"], "0201", "{value}");
    }
    sim.ecdrive(&["reg", "-p", "0", "write", "0x1F00", "258"])
        .fails(2, &["--type", "--bytes"]);
    sim.ecdrive(&["reg", "-p", "0", "write", "0x1F00", "258", "--bytes"])
        .fails(2, &["\"258\"", "hex bytes"]);

    // The EEPROM of each drive: summary, raw bytes, JSON, and an ESI skeleton that agrees
    // with the drive's ESI file.
    let dir = std::env::temp_dir().join(format!("ecdrive-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for i in 0..DEVICES.len() {
        let (p, f) = (profile(i), esi(i));
        let want = &f.devices[0];
        let pos = i.to_string();
        let run = sim.ecdrive(&["sii", "-p", &pos]);
        // Long operations draw progress on a terminal only: piped, stderr stays empty.
        assert_eq!(run.stderr, "", "{run:#?}");
        let s = run.ok().to_string();
        assert!(
            s.contains(&format!(
                "Identity: vendor 0x{:08X}, product 0x{:08X}, revision 0x{:08X}",
                p.identity.vendor_id, p.identity.product_code, p.revision
            )),
            "{s}"
        );
        assert!(s.contains("checksum ok"), "{s}");
        let bin = dir.join(format!("sii{i}.bin"));
        sim.ecdrive(&["sii", "-p", &pos, "-o", bin.to_str().unwrap()])
            .ok();
        let raw = std::fs::read(&bin).unwrap();
        assert_eq!(
            raw.len() as u32,
            want.eeprom.as_ref().unwrap().byte_size.unwrap()
        );
        let sj = sim.ecdrive(&["sii", "-p", &pos, "--json"]).json();
        let hex: String = raw.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(sj["bytes"], hex);
        assert_eq!(
            sj["info"]["product_code"],
            u64::from(p.identity.product_code)
        );
        assert_eq!(
            sj["info"]["general"]["order"],
            want.type_.name_text.as_str()
        );
        let xml = sim.ecdrive(&["sii", "-p", &pos, "--esi"]).ok().to_string();
        let back = EsiFile::parse(&xml).expect("the skeleton parses");
        assert_eq!(back.vendor.id, f.vendor.id);
        let dev = back
            .device(want.type_.product_code, want.type_.revision_no)
            .expect("device");
        assert_eq!(dev.name, want.name);
        assert_eq!(dev.sync_managers.len(), want.sync_managers.len());
        for dir in [Direction::Rx, Direction::Tx] {
            let a: Vec<u16> = want.pdos(dir).iter().map(|p| p.index).collect();
            let b: Vec<u16> = dev.pdos(dir).iter().map(|p| p.index).collect();
            assert_eq!(a, b);
        }
        assert!(back.check().is_empty(), "{:?}", back.check());
    }
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
    sim.ecdrive(&["download", "-p", "1", "0x6065:00", "-1"])
        .fails(2, &["drive 1 (BDHDE)", "out of range for UNSIGNED32"]);
    sim.ecdrive(&["download", "-p", "0", "0x1018:01", "5"])
        .fails(
            4,
            &[
                "drive 0 (MR-J4-TM)",
                "0x1018:01",
                "0x06010002",
                "Attempt to write a read only object",
            ],
        );
    sim.ecdrive(&["upload", "-p", "0", "0x5FFF:00"])
        .fails(4, &["0x5FFF:00", "Object does not exist"]);
    // The drive refuses SDO writes to what its RxPDO carries.
    sim.ecdrive(&["download", "-p", "0", "0x6060:00", "8"])
        .fails(
            4,
            &["drive 0 (MR-J4-TM)", "0x06010006", "Object mapped to RxPDO"],
        );
    sim.ecdrive(&["upload", "-p", "1", "0x5FFF:00"]).fails(
        2,
        &[
            "drive 1 (BDHDE)",
            "not in the BDHDE dictionary",
            "give the type with --type",
        ],
    );
    sim.ecdrive(&["upload", "-p", "1", "0x5FFF:00", "--type", "u32"])
        .fails(4, &["drive 1 (BDHDE)", "0x06020000"]);
    sim.ecdrive(&["sdos", "-p", "9"]).fails(2, &["position 9"]);
    sim.ecdrive(&["reg", "-p", "0", "read", "0xFFFF", "4"])
        .fails(2, &["run past 0xFFFF"]);
}

#[test]
fn run_drives_both_over_the_wire() {
    // The test machine is shared and neither this master nor the simulator is guaranteed
    // real-time: the emulated drives do not supervise the cyclic data here
    // (`--no-loss-detection`), the cycle is 2 ms with the cycle thread at SCHED_FIFO 50, and a
    // late reply now and then does not count as a lost segment (`supervision.lost_cycles`).
    let Some(sim) = SimOnVeth::start_with(
        "cli_bus::run_drives_both_over_the_wire",
        DEVICES,
        &["--no-loss-detection"],
    ) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("ecdrive-cli-run-veth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("veth.toml");
    std::fs::write(
        &f,
        format!(
            r#"interface = "{}"
cycle = "2ms"
[rt]
priority = 50
[supervision]
lost_cycles = 50
[[drive]]
position = 0
mode = "csp"
units = {{ name = "deg", counts_per_unit = 11650.844444 }}
program = [{{ step = "move", by = 45, velocity = 360, acceleration = 3600 }}]
[[drive]]
position = 1
mode = "csv"
units = {{ name = "rev", counts_per_unit = 1048576 }}
program = [
  {{ step = "ramp", velocity = 2, acceleration = 20 }},
  {{ step = "ramp", velocity = 0, acceleration = 20 }},
]
"#,
            sim.host()
        ),
    )
    .unwrap();
    let path = f.display().to_string();
    let text = support::cli::ecdrive(&["run", "-c", &path])
        .ok()
        .to_string();
    assert!(
        text.contains("completed (every program finished)"),
        "{text}"
    );
    let j = support::cli::ecdrive(&["run", "-c", &path, "--json"]).json();
    assert_eq!(j["outcome"], "completed");
    assert_eq!(j["target"]["interface"], sim.host());
    for (i, mode) in ["csp", "csv"].into_iter().enumerate() {
        let d = &j["drives"][i];
        assert_eq!(d["name"], profile(i).name);
        assert_eq!(d["modes_run"], serde_json::json!([mode]));
        assert_eq!(d["steps_done"], d["program"].as_array().unwrap().len());
        assert!(
            d["states"]
                .as_array()
                .unwrap()
                .iter()
                .any(|s| s == "Operation enabled"),
            "{d}"
        );
        assert!(
            text.contains(&format!("Drive {i} {} ", profile(i).name)),
            "{text}"
        );
    }
    assert_eq!(j["shutdown_ok"], true);
    let _ = std::fs::remove_dir_all(&dir);
}
