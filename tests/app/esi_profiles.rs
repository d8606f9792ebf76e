//! What ecdrive makes of a drive from its ESI file alone (`esi::DrivePlan`, printed by `ecdrive
//! esi show`), on three vendor-shaped files that are not ecdrive's two drives
//! (`tests/data/esi/make_drives.py` wrote them): fixed PDOs with alternatives excluded by
//! `<Exclude>` (Nordwind ND40), configurable PDOs with 10 entries per mapping object (Kestrel
//! KS2), and a read-only 0x1C32 with InitCmds that set the cycle time through a vendor object
//! (Taiga TX7). The expected values are read off the files, not off the code.

use crate::support;

use ecdrive::esi::{CYCLIC_MODES, DrivePlan, EsiFile, MappingSource, mapping_for};
use ecdrive::od::ObjectAddress;
use ecdrive::pdo::Direction;
use support::links::SendTap;

fn path(name: &str) -> String {
    format!("{}/tests/data/esi/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn plan(name: &str) -> (EsiFile, DrivePlan) {
    let f = EsiFile::from_path(path(name)).unwrap_or_else(|e| panic!("{e}"));
    let d = f.devices.first().expect("one device").clone();
    let p = DrivePlan::new(&f, &d);
    (f, p)
}

fn pdos(m: &ecdrive::esi::ModeMapping, dir: Direction) -> (MappingSource, Vec<u16>) {
    let side = match dir {
        Direction::Rx => &m.rx,
        Direction::Tx => &m.tx,
    };
    let c = side
        .as_ref()
        .unwrap_or_else(|e| panic!("{:?}: {e}", m.modes));
    (c.source.clone(), c.pdos.clone())
}

#[test]
fn fixed_pdos_with_exclusions_one_per_mode() {
    let (_, p) = plan("Nordwind_ND40.xml");
    assert_eq!((p.vendor_id, p.product_code), (0x0E01, 0x40));
    assert_eq!(p.modes, ["csp", "csv", "cst"]);
    assert!(p.modes_from_0x6502);
    let by = |name: &str| {
        p.mappings
            .iter()
            .find(|m| m.modes.join("+") == name)
            .unwrap()
    };
    // csp: the default assignment (0x1600 on SM2, 0x1A00 on SM3).
    assert_eq!(
        pdos(by("csp"), Direction::Rx),
        (MappingSource::Default, vec![0x1600])
    );
    assert_eq!(
        pdos(by("csp"), Direction::Tx),
        (MappingSource::Default, vec![0x1A00])
    );
    // csv and cst: the alternative fixed RxPDO that carries the set-point.
    assert_eq!(
        pdos(by("csv"), Direction::Rx),
        (MappingSource::Chosen, vec![0x1601])
    );
    assert_eq!(
        pdos(by("cst"), Direction::Rx),
        (MappingSource::Chosen, vec![0x1602])
    );
    // All three at once: the PDOs exclude each other and cannot be configured.
    let all = by("csp+csv+cst");
    assert!(!all.ok());
    let why = all.rx.as_ref().unwrap_err();
    assert!(why.contains("0x60FF:00 (Target velocity)"), "{why}");
    assert!(why.contains("0x6071:00 (Target torque)"), "{why}");
    assert!(why.contains("cannot be configured"), "{why}");
    // The chosen mapping is the file's PDO, entry for entry.
    let m = by("csv").mapping.as_ref().unwrap();
    assert!(m.contains(Direction::Rx, ObjectAddress::new(0x60FF, 0)));
    assert_eq!(m.bytes(Direction::Rx), 8);
    let dc = p.dc.as_ref().unwrap();
    assert_eq!(
        (dc.name.as_str(), dc.assign_activate, dc.sync0_factor),
        ("DC", 0x0300, 1)
    );
    assert_eq!(p.cycle_time_writable, Some(true));
    assert_eq!(p.init_cmds.len(), 1);
    assert_eq!(p.init_cmds[0].object, "0x605A:00");
    assert_eq!(p.init_cmds[0].data, "0200");
    assert_eq!(p.init_cmds[0].transitions, ["PS"]);
}

#[test]
fn configurable_pdos_are_built_within_the_entry_limit() {
    let (f, p) = plan("Kestrel_KS2.xml");
    let by = |name: &str| {
        p.mappings
            .iter()
            .find(|m| m.modes.join("+") == name)
            .unwrap()
    };
    assert_eq!(
        pdos(by("csp"), Direction::Rx),
        (MappingSource::Default, vec![0x1600])
    );
    assert_eq!(
        pdos(by("csv"), Direction::Rx),
        (MappingSource::Built, vec![0x1600])
    );
    let all = by("csp+csv+cst");
    assert_eq!(
        pdos(all, Direction::Rx),
        (MappingSource::Built, vec![0x1600])
    );
    assert_eq!(
        pdos(all, Direction::Tx),
        (MappingSource::Built, vec![0x1A00])
    );
    let m = all.mapping.as_ref().unwrap();
    // The default entries first, then what the modes need, each with its dictionary length.
    let rx: Vec<(u16, u8)> = m.pdos(Direction::Rx)[0]
        .entries
        .iter()
        .map(|e| (e.index, e.bits))
        .collect();
    assert_eq!(
        rx,
        [
            (0x6040, 16),
            (0x607A, 32),
            (0x60FF, 32),
            (0x6071, 16),
            (0x6060, 8)
        ]
    );
    assert!(m.contains(Direction::Tx, ObjectAddress::new(0x6061, 0)));
    // The limit the dictionary implies: 0x1600 has sub-indices 1–10. With 8 more objects in
    // the default PDO, three modes need 13 entries.
    let mut d = f.devices[0].clone();
    let extra = d.rx_pdos[0].entries[0].clone();
    for i in 0..8u16 {
        let mut e = extra.clone();
        e.index = 0x2000 + i;
        d.rx_pdos[0].entries.push(e);
    }
    let m = mapping_for(&d, &CYCLIC_MODES);
    let why = m.rx.unwrap_err();
    assert!(
        why.contains("RxPDO 0x1600 would need 13 entries; the file's dictionary gives it 10"),
        "{why}"
    );
}

#[test]
fn read_only_cycle_time_and_init_commands_in_file_order() {
    let (_, p) = plan("Taiga_TX7.xml");
    assert_eq!(p.cycle_time_writable, Some(false));
    let all = p
        .mappings
        .iter()
        .find(|m| m.modes.len() == 3)
        .expect("all modes");
    assert_eq!(
        pdos(all, Direction::Rx),
        (MappingSource::Default, vec![0x1600])
    );
    assert_eq!(
        pdos(all, Direction::Tx),
        (MappingSource::Default, vec![0x1A00])
    );
    let cmds: Vec<(&str, &str, String)> = p
        .init_cmds
        .iter()
        .map(|c| (c.object.as_str(), c.data.as_str(), c.transitions.join(",")))
        .collect();
    assert_eq!(
        cmds,
        [
            ("0x2010:00", "E803", "PS".to_string()),
            ("0x2011:00", "01", "PS".to_string()),
            ("0x2FFF:00", "01", "PS".to_string()),
            ("0x6060:00", "08", "PS,SO".to_string()),
        ]
    );
    assert!(p.init_cmds[0].comment.contains("0x1C32:02 is read-only"));
    assert!(p.init_cmds[0].line < p.init_cmds[1].line);
    // Its attributes and the network description's elements, as the file writes them.
    let c0 = &p.init_cmds[0];
    assert!(c0.fixed && !c0.disabled);
    assert_eq!((c0.timeout_ms, c0.retries), (Some(3000), 1));
    let c1 = &p.init_cmds[1];
    assert!(!c1.fixed && !c1.disabled);
    assert_eq!((c1.timeout_ms, c1.retries), (None, 0));
    assert!(p.init_cmds[2].disabled);
}

/// A configuration value for the object of a `Fixed` InitCmd is refused when the configuration
/// is checked, naming the key, the object, the InitCmd's line and comment.
#[test]
fn a_value_for_a_fixed_init_command_object_is_refused() {
    let text = run_config("Taiga_TX7.xml", "csp", CSP_MOVE)
        .replace("esi = ", "sdos = { \"0x2010:00\" = 500 }\nesi = ");
    let e = ecdrive_cli::app::config::parse(&text, &path("run.toml"))
        .expect_err("a value for a Fixed InitCmd's object")
        .to_string();
    for part in [
        "run.toml line ",
        "drive[0].sdos",
        "0x2010:00",
        "InitCmd at line",
        "Fixed",
        "cycle time 1000 us",
    ] {
        assert!(e.contains(part), "{part:?} not in: {e}");
    }
}

#[test]
fn esi_show_prints_the_plan() {
    let r = support::cli::ecdrive(&["esi", "show", &path("Nordwind_ND40.xml")]);
    let text = r.ok().to_string();
    assert!(
        text.contains("From this file alone: cyclic modes csp, csv, cst (0x6502)"),
        "{text}"
    );
    assert!(
        text.contains("csv          RxPDO 0x1601 (chosen); TxPDO 0x1A00 (default)"),
        "{text}"
    );
    assert!(text.contains("csp+csv+cst  RxPDO impossible: "), "{text}");
    assert!(text.contains("InitCmd line "), "{text}");
    let j = support::cli::ecdrive(&["esi", "show", &path("Taiga_TX7.xml"), "--json"]).json();
    let plan = &j["devices"][0]["plan"];
    assert_eq!(plan["cycle_time_writable"], false, "{plan}");
    assert_eq!(plan["init_cmds"][3]["object"], "0x6060:00", "{plan}");
    assert_eq!(plan["init_cmds"][2]["disabled"], true, "{plan}");
    assert_eq!(plan["init_cmds"][0]["timeout_ms"], 3000, "{plan}");
    assert_eq!(
        plan["mappings"][0]["rx"]["Ok"]["source"], "default",
        "{plan}"
    );
}

/// A configuration file next to the ESI files (so `esi = "…"` is relative to it).
fn config(
    body: &str,
) -> Result<ecdrive_cli::app::config::RunConfig, ecdrive_cli::app::config::ConfigError> {
    let text = format!("interface = \"eth9\"\ncycle = \"1ms\"\n{body}");
    ecdrive_cli::app::config::parse(&text, &path("drives.toml"))
}

#[test]
fn a_configuration_drive_gets_its_profile_from_the_esi_file() {
    let cfg = config(
        "[[drive]]\nposition = 0\nesi = \"Taiga_TX7.xml\"\nmode = \"csv\"\n\
         program = [{ step = \"dwell\", seconds = 0.1 }]\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let p = cfg.drives[0].profile.expect("a profile from the ESI");
    assert_eq!(p.bus.key, "esi:TX7");
    assert_eq!(
        (p.bus.identity.vendor_id, p.bus.identity.product_code),
        (0x0E03, 0x0007_0007)
    );
    // 0x1C32:02 is read-only in the file: ecdrive does not write the cycle time there; the
    // InitCmds set it through 0x2010.
    assert_eq!(p.bus.sync.cycle_time_object, None);
    // The disabled one (0x2FFF) is not in the profile.
    assert_eq!(p.bus.init_cmds.len(), 3);
    assert!(p.bus.init_cmds.iter().all(|c| c.address.index != 0x2FFF));
    assert_eq!(
        (
            p.bus.init_cmds[0].timeout_ms,
            p.bus.init_cmds[0].retries,
            p.bus.init_cmds[0].fixed
        ),
        (Some(3000), 1, true)
    );
    assert_eq!(p.bus.init_cmds[0].address, ObjectAddress::new(0x2010, 0));
    assert_eq!(p.bus.init_cmds[0].data, [0xE8, 0x03]);
    // Types for upload/download come from the file's dictionary.
    let d = ecdrive::od::Dictionary::new(p.dictionary);
    assert!(d.entry(ObjectAddress::new(0x2010, 0)).is_some());
    assert!(
        p.bus
            .cyclic_mapping
            .contains(Direction::Rx, ObjectAddress::new(0x60FF, 0))
    );

    // The ND40 cannot carry csp, csv and cst at once, but each alone: its cyclic mapping is
    // the one of csp (its default assignment); for a csv program the file's csv PDO is chosen
    // and the check says so.
    let cfg = config("[[drive]]\nposition = 0\nesi = \"Nordwind_ND40.xml\"\n").unwrap();
    let p = cfg.drives[0].profile.unwrap();
    assert!(
        p.bus
            .cyclic_mapping
            .contains(Direction::Rx, ObjectAddress::new(0x607A, 0))
    );
    assert!(p.bus.sync.cycle_time_object.is_some());
    let cfg =
        config("[[drive]]\nposition = 0\nesi = \"Nordwind_ND40.xml\"\nmode = \"csv\"\n").unwrap();
    let m = cfg.master.startup.drives[0]
        .mapping
        .as_ref()
        .expect("chosen");
    assert_eq!(m.pdos(Direction::Rx)[0].index, 0x1601);
    assert_eq!(
        cfg.notes,
        [
            "drive[0].esi: csv from the ESI file: RxPDO 0x1601 (chosen from the file's PDOs), \
          TxPDO 0x1A00 (the file's default)"
        ]
    );
    // A program that switches csp → csv needs both set-points at once: refused, named.
    let e = config(
        "[[drive]]\nposition = 0\nesi = \"Nordwind_ND40.xml\"\nmode = \"csp\"\n\
         program = [{ step = \"mode\", mode = \"csv\" }]\n",
    )
    .unwrap_err();
    assert!(e.message.contains("cannot carry csp+csv"), "{e}");
    assert!(e.message.contains("0x60FF:00 (Target velocity)"), "{e}");
}

#[test]
fn a_bad_or_missing_esi_is_named_before_the_bus_is_touched() {
    let e = config("[[drive]]\nposition = 0\nesi = \"Nowhere.xml\"\n").unwrap_err();
    assert_eq!((e.line, e.key.as_deref()), (5, Some("drive[0].esi")), "{e}");
    assert!(e.message.contains("Nowhere.xml"), "{e}");
    let e = config("[[drive]]\nposition = 0\nesi = \"Acme_Terminals.xml\"\n").unwrap_err();
    assert!(e.message.contains("describes 4 devices"), "{e}");
    let e = config(
        "[[drive]]\nidentity = { vendor_id = 0x0E01, product_code = 0x41 }\n\
         esi = \"Nordwind_ND40.xml\"\n",
    )
    .unwrap_err();
    assert!(
        e.message.contains("no device with product code 0x00000041"),
        "{e}"
    );
    // A built-in profile refined by another drive's file.
    let e = config("[[drive]]\nposition = 0\nesi = \"Kestrel_KS2.xml\"\nprofile = \"mr-j4-tm\"\n")
        .unwrap_err();
    assert!(e.message.contains("is from vendor 0x00000E02"), "{e}");
    // A broken file: the parser's line and column inside it.
    let dir = std::env::temp_dir().join(format!("ecdrive-esi-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(path("Kestrel_KS2.xml")).unwrap();
    std::fs::write(
        dir.join("broken.xml"),
        text.replacen("<BitLen>16</BitLen>", "<BitLen>sixteen</BitLen>", 1),
    )
    .unwrap();
    let e = ecdrive_cli::app::config::parse(
        "interface = \"eth9\"\n[[drive]]\nposition = 0\nesi = \"broken.xml\"\n",
        dir.join("c.toml").to_str().unwrap(),
    )
    .unwrap_err();
    assert!(e.message.contains("broken.xml"), "{e}");
    assert!(e.message.contains("line "), "{e}");
    assert!(e.message.contains("column "), "{e}");
    assert!(e.message.contains("sixteen"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The emulated MR-J4-TM driven with a profile built from its ESI file alone (no Rust
/// profile), the file given two `<InitCmd>`s: the run reaches OP and completes a move; an
/// InitCmd the drive refuses (a write to the read-only 0x1018:01), sent again as its
/// `<Retries>` say, stops start-up with the drive, the object, the transition, the line and
/// the comment named.
#[test]
fn a_run_on_a_profile_from_the_esi_sends_its_init_commands() {
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
    let dir = std::env::temp_dir().join(format!("ecdrive-esi-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let esi = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/esi/Mitsubishi_MR-J4-TM.xml"
    ))
    .unwrap();
    let with = |cmds: &str| {
        let open = esi.find("<CoE SdoInfo=").expect("<CoE>");
        let close = open + esi[open..].find("/>").expect("self-closing <CoE/>");
        format!("{}>{cmds}</CoE>{}", &esi[..close], &esi[close + 2..])
    };
    let good = "<InitCmd><Transition>PS</Transition><Index>#x6065</Index><SubIndex>0</SubIndex>\
                <Data>00100000</Data><Comment>following error window</Comment></InitCmd>";
    let bad = "<InitCmd><Transition>PS</Transition><Index>#x1018</Index><SubIndex>1</SubIndex>\
               <Data>00000000</Data><Comment>a vendor ID written by mistake</Comment>\
               <Retries>2</Retries></InitCmd>";
    std::fs::write(dir.join("good.xml"), with(good)).unwrap();
    std::fs::write(dir.join("bad.xml"), with(&format!("{good}{bad}"))).unwrap();
    let cfg = |file: &str| {
        let text = format!(
            "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"mr-j4-tm\"]\nloss_detection = false\n\
             [[drive]]\nposition = 0\nesi = \"{file}\"\nmode = \"csp\"\n\
             program = [{{ step = \"move\", by = 100000, velocity = 1000000, acceleration = 10000000 }}]\n"
        );
        ecdrive_cli::app::config::parse(&text, dir.join("run.toml").to_str().unwrap())
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let c = cfg("good.xml");
    assert_eq!(c.drives[0].profile.unwrap().bus.init_cmds.len(), 1);
    let r = run(&c, &RunOptions::default(), &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    // The built-in profile refined by the same file: the manual's profile (its key, its
    // start-up values) with the file's InitCmd; it runs the same move.
    let text = "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"mr-j4-tm\"]\nloss_detection = false\n\
         [[drive]]\nposition = 0\nprofile = \"mr-j4-tm\"\nesi = \"good.xml\"\nmode = \"csp\"\n\
         program = [{ step = \"move\", by = 100000, velocity = 1000000, acceleration = 10000000 }]\n";
    let refined = ecdrive_cli::app::config::parse(text, dir.join("run.toml").to_str().unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let p = refined.drives[0].profile.unwrap();
    let builtin = ecdrive::drives::by_key("mr-j4-tm").unwrap();
    assert_eq!(p.bus.key, builtin.bus.key);
    assert_eq!(p.bus.startup.len(), builtin.bus.startup.len());
    assert_eq!(p.bus.cyclic_mapping, builtin.bus.cyclic_mapping);
    assert_eq!(p.bus.init_cmds.len(), 1);
    assert_eq!(p.bus.init_cmds[0].address, ObjectAddress::new(0x6065, 0));
    assert!(
        refined.notes.iter().any(|n| n.contains("refined by")),
        "{:?}",
        refined.notes
    );
    let r =
        run(&refined, &RunOptions::default(), &stop, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    let e = match run(&cfg("bad.xml"), &RunOptions::default(), &stop, &mut |_| {}) {
        Err(e) => e.to_string(),
        Ok(r) => format!("{:?}: {}", r.outcome, r.reason),
    };
    for part in [
        "drive 0",
        "0x1018:01",
        "InitCmd at line",
        "PS",
        "a vendor ID written by mistake",
        "0x06010002",
        "sent 3 times",
    ] {
        assert!(e.contains(part), "{part:?} not in: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- the three files as emulated devices (`esi:FILE`), driven from the files alone ---------

/// A configuration running the device of `file` (emulated from the same file) with `esi =`.
fn run_config(file: &str, mode: &str, program: &str) -> String {
    format!(
        "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"esi:{}\"]\n\
         [[drive]]\nposition = 0\nesi = \"{file}\"\nmode = \"{mode}\"\nprogram = [{program}]\n",
        path(file)
    )
}

const CSP_MOVE: &str = "{ step = \"move\", by = 20000, velocity = 100000, acceleration = 1000000 }";

#[test]
fn each_vendor_file_reaches_op_and_moves_with_only_its_esi() {
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
    let stop = std::sync::atomic::AtomicBool::new(false);
    for (file, mode, program) in [
        ("Nordwind_ND40.xml", "csp", CSP_MOVE),
        (
            "Nordwind_ND40.xml",
            "csv",
            "{ step = \"ramp\", velocity = 20000, acceleration = 200000, hold = 0.05 }, { step = \"ramp\", velocity = 0, acceleration = 200000 }",
        ),
        ("Kestrel_KS2.xml", "csp", CSP_MOVE),
        // csv on the KS2 needs 0x60FF configured into its RxPDO 0x1600.
        (
            "Kestrel_KS2.xml",
            "csv",
            "{ step = \"ramp\", velocity = 20000, acceleration = 200000, hold = 0.05 }, { step = \"ramp\", velocity = 0, acceleration = 200000 }",
        ),
        ("Taiga_TX7.xml", "csp", CSP_MOVE),
    ] {
        let text = run_config(file, mode, program);
        let cfg = ecdrive_cli::app::config::parse(&text, &path("run.toml"))
            .unwrap_or_else(|e| panic!("{file} {mode}: {e}"));
        assert!(
            cfg.notes[0].contains(&format!("{mode} from the ESI file")),
            "{:?}",
            cfg.notes
        );
        let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {})
            .unwrap_or_else(|e| panic!("{file} {mode}: {e}"));
        assert_eq!(r.outcome, Outcome::Completed, "{file} {mode}: {}", r.reason);
    }
}

/// What [`mailbox_tap`] saw: (register, bytes), in wire order.
type Seen = std::sync::Arc<std::sync::Mutex<Vec<(u16, Vec<u8>)>>>;

/// The first device's segment link, keeping in wire order every mailbox request the master
/// writes to its SM0 (station 0x1000, SM0 at 0x1000 in these files) and every AL control write
/// that reaches it (0x0120: to it, or broadcast to every device), as (register, bytes).
fn mailbox_tap(
    seg: ecdrive::sim::Segment,
    seen: Seen,
) -> SendTap<ecdrive::sim::transport::SegmentLink, impl FnMut(&mut [u8]) + Send> {
    const FPWR: u8 = 5;
    const BWR: u8 = 8;
    SendTap::new(
        ecdrive::sim::transport::SegmentLink::new(seg),
        move |frame: &mut [u8]| {
            if let Ok(eth) = ecdrive::ec::frame::EthernetFrame::new_checked(&*frame)
                && let Ok(ecat) = ecdrive::ec::frame::EthercatFrame::new_checked(eth.payload())
                && let Ok(mut seen) = seen.lock()
            {
                for d in ecat.datagrams().flatten() {
                    let to_it = d.command_raw() == FPWR
                        && d.adp() == 0x1000
                        && matches!(d.ado(), 0x1000 | 0x0120);
                    if to_it || (d.command_raw() == BWR && d.ado() == 0x0120) {
                        seen.push((d.ado(), d.data().to_vec()));
                    }
                }
            }
        },
    )
}

/// The TX7's InitCmds arrive at the drive in file order, each once, and the drive accepts
/// them (the session reaches OP): in PRE-OP before SAFE-OP is requested, 0x2010 (its cycle
/// time, as 0x1C32:02 is read-only), 0x2011, then 0x6060 = 8; in SAFE-OP before OP is
/// requested, 0x6060 = 8 again (the file gives it PS and SO). The disabled one (0x2FFF) never
/// goes out, and ecdrive writes nothing to the read-only 0x1C32:02.
#[test]
fn init_commands_arrive_in_file_order_at_their_transitions() {
    use ecdrive::ec::mailbox::{MailboxMessage, SdoRequest};
    use ecdrive::master::session::{Master, MasterConfig};
    let text = run_config("Taiga_TX7.xml", "csp", CSP_MOVE);
    let cfg = ecdrive_cli::app::config::parse(&text, &path("run.toml")).unwrap();
    let seg = ecdrive::sim::run::build_segment(
        &[format!("esi:{}", path("Taiga_TX7.xml"))],
        &ecdrive::sim::EscConfig::default(),
    )
    .unwrap();
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let link = mailbox_tap(seg, seen.clone());
    let mc: MasterConfig = cfg.master.clone();
    let mut m = Master::start(link, mc).map_err(|f| f.error).unwrap();
    m.wait_until("OP", std::time::Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let _ = m.stop(ecdrive::master::telemetry::StopKind::Ramp);
    // The wire, in order: "S4" for an AL control request of SAFE-OP, "S8" for OP, and
    // "IIII:SS=data" for each expedited download.
    let events: Vec<String> = seen
        .lock()
        .unwrap()
        .iter()
        .filter_map(|(reg, b)| match (reg, MailboxMessage::parse(b)) {
            (0x0120, _) => Some(format!("S{}", b.first().copied().unwrap_or(0) & 0x0F)),
            (
                _,
                Ok((
                    _,
                    MailboxMessage::SdoRequest(SdoRequest::DownloadExpedited {
                        index,
                        sub,
                        data,
                        ..
                    }),
                )),
            ) => Some(format!(
                "{index:04X}:{sub:02X}={}",
                data.iter().map(|x| format!("{x:02X}")).collect::<String>()
            )),
            _ => None,
        })
        .collect();
    eprintln!("{events:?}");
    let at = |e: &str| events.iter().position(|x| x == e);
    let all = |e: &str| {
        events
            .iter()
            .enumerate()
            .filter(|(_, x)| *x == e)
            .map(|(i, _)| i)
            .collect::<Vec<_>>()
    };
    let (safe_op, op) = (at("S4"), at("S8"));
    let (c2010, c2011, mode) = (at("2010:00=E803"), at("2011:00=01"), all("6060:00=08"));
    assert!(safe_op.is_some() && op.is_some(), "{events:?}");
    assert!(c2010.is_some() && c2011.is_some(), "{events:?}");
    assert_eq!(mode.len(), 2, "0x6060 at PS and at SO: {events:?}");
    // PS: in file order, before SAFE-OP is requested.
    assert!(c2010 < c2011 && c2011 < Some(mode[0]), "{events:?}");
    assert!(Some(mode[0]) < safe_op, "{events:?}");
    // SO: after SAFE-OP, before OP.
    assert!(safe_op < Some(mode[1]) && Some(mode[1]) < op, "{events:?}");
    assert_eq!(all("2010:00=E803").len(), 1, "{events:?}");
    assert!(
        !events.iter().any(|e| e.starts_with("2FFF")),
        "disabled: {events:?}"
    );
    assert!(
        !events.iter().any(|e| e.starts_with("1C32:02")),
        "0x1C32:02 is read-only in the file: {events:?}"
    );
}

/// Over veth: `ecdrive sim -d esi:FILE` serves the KS2 as its file describes it, and `ecdrive
/// run` drives it in csv from the same file (its RxPDO configured with 0x60FF).
#[test]
fn a_vendor_file_over_veth() {
    let dev = format!("esi:{}", path("Kestrel_KS2.xml"));
    let Some(sim) =
        support::cli::SimOnVeth::start("esi_profiles::a_vendor_file_over_veth", &[dev.as_str()])
    else {
        return;
    };
    assert!(sim.banner.contains("KS2"), "{}", sim.banner);
    let dir = std::env::temp_dir().join(format!("ecdrive-esi-veth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("ks2.toml");
    std::fs::write(
        &file,
        format!(
            "interface = \"eth9\"\ncycle = \"1ms\"\n[[drive]]\nposition = 0\nesi = \"{}\"\n\
             mode = \"csv\"\nprogram = [{{ step = \"ramp\", velocity = 20000, acceleration = 200000, \
             hold = 0.05 }}, {{ step = \"ramp\", velocity = 0, acceleration = 200000 }}]\n",
            path("Kestrel_KS2.xml")
        ),
    )
    .unwrap();
    let j = sim.run_json(file.to_str().unwrap(), &[]);
    assert_eq!(j["outcome"], "completed", "{j:#}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `ecdrive run --esi DIR`: the drives of a configuration that names neither a profile nor an
/// ESI file are found by identity among the folder's files; without it they are unknown. The
/// folder's terminals (Acme_Terminals.xml) are listed as not usable, and do not stop the run.
#[test]
fn a_folder_of_vendor_files_is_searched_by_identity() {
    let loaded = ecdrive::drives::esi_profile::load_dir(std::path::Path::new(&path(""))).unwrap();
    let (profiles, skipped) = (loaded.profiles, loaded.skipped);
    let mut keys: Vec<&str> = profiles.iter().map(|p| p.bus.key).collect();
    keys.sort_unstable();
    assert_eq!(keys, ["esi:KS2", "esi:ND40", "esi:TX7"]);
    assert!(
        skipped
            .iter()
            .any(|s| s.contains("Acme_Terminals.xml") && s.contains("AC3102")),
        "{skipped:?}"
    );

    let dir = std::env::temp_dir().join(format!("ecdrive-esi-dir-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("two.toml");
    std::fs::write(
        &file,
        format!(
            "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"esi:{}\", \"esi:{}\"]\n\
             [[drive]]\nposition = 0\nprogram = [{CSP_MOVE}]\n\
             [[drive]]\nposition = 1\nprogram = [{CSP_MOVE}]\n",
            path("Nordwind_ND40.xml"),
            path("Taiga_TX7.xml")
        ),
    )
    .unwrap();
    let f = file.to_str().unwrap();
    let without = support::cli::ecdrive(&["run", "-c", f]);
    assert_ne!(without.code, Some(0), "{without:#?}");
    assert!(without.stderr.contains("vendor 0x00000E01"), "{without:#?}");
    let with = support::cli::ecdrive(&["run", "-c", f, "--esi", &path(""), "--json"]);
    let j = with.json();
    assert_eq!(j["outcome"], "completed", "{j:#}");
    assert!(with.stderr.contains("--esi: ND40 servo drive"), "{with:#?}");
    assert!(with.stderr.contains("warning: --esi: "), "{with:#?}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- `esi profile` and `[[drive]] profile_file` ---------------------------------------------

/// A fresh folder with a copy of the vendor file `name` in it.
fn folder_with(name: &str, tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ecdrive-profile-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(path(name), dir.join(name)).unwrap();
    dir
}

/// A configuration in `dir` that runs the emulated device of `esi` with `drive` keys.
fn profile_run_config(dir: &std::path::Path, esi: &str, drive: &str, mode: &str) -> String {
    format!(
        "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"esi:{}\"]\n\
         [[drive]]\nposition = 0\n{drive}\nmode = \"{mode}\"\nprogram = [{CSP_MOVE}]\n",
        dir.join(esi).display()
    )
}

/// `ecdrive esi profile FILE -o P.toml` for each of the three vendor files, then
/// `[[drive]] profile_file = "P.toml"`: the loaded profile is the one `esi = FILE` builds
/// (identity, modes, units, synchronisation, mapping, InitCmds), and the run reaches OP and
/// completes a csp move on the device emulated from the file.
#[test]
fn an_esi_profile_file_loads_as_the_profile_the_esi_builds() {
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
    for file in ["Nordwind_ND40.xml", "Kestrel_KS2.xml", "Taiga_TX7.xml"] {
        let dir = folder_with(file, "rt");
        let out = dir.join("drive.toml");
        let r = support::cli::ecdrive(&[
            "esi",
            "profile",
            dir.join(file).to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        r.ok();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains(&format!("esi = \"{file}\"")), "{text}");
        let by_file = |keys: &str| {
            let t = profile_run_config(&dir, file, keys, "csp");
            ecdrive_cli::app::config::parse(&t, dir.join("run.toml").to_str().unwrap())
                .unwrap_or_else(|e| panic!("{file}: {e}"))
        };
        let a = by_file("profile_file = \"drive.toml\"");
        let b = by_file(&format!("esi = \"{file}\""));
        let (pa, pb) = (a.drives[0].profile.unwrap(), b.drives[0].profile.unwrap());
        assert_eq!(pa.bus.identity, pb.bus.identity, "{file}");
        assert_eq!(pa.bus.revision, pb.bus.revision, "{file}");
        assert_eq!(
            pa.caps.supported_modes.raw(),
            pb.caps.supported_modes.raw(),
            "{file}"
        );
        assert_eq!(pa.units, pb.units, "{file}");
        assert_eq!(pa.bus.sync.dc_sync0, pb.bus.sync.dc_sync0, "{file}");
        assert_eq!(pa.bus.sync.free_run, pb.bus.sync.free_run, "{file}");
        assert_eq!(
            pa.bus.sync.assign_activate, pb.bus.sync.assign_activate,
            "{file}"
        );
        assert_eq!(
            pa.bus.sync.sync_type_object, pb.bus.sync.sync_type_object,
            "{file}"
        );
        assert_eq!(
            pa.bus.sync.cycle_time_object, pb.bus.sync.cycle_time_object,
            "{file}"
        );
        assert_eq!(pa.bus.cyclic_mapping, pb.bus.cyclic_mapping, "{file}");
        assert_eq!(pa.bus.init_cmds, pb.bus.init_cmds, "{file}");
        let stop = std::sync::atomic::AtomicBool::new(false);
        let r = run(&a, &RunOptions::default(), &stop, &mut |_| {})
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(r.outcome, Outcome::Completed, "{file}: {}", r.reason);
        let _ = std::fs::remove_dir_all(&dir);
    }
    // The KS2 gives 0x608F: 2^23 increments per revolution reach the profile's units.
    let f = EsiFile::from_path(path("Kestrel_KS2.xml")).unwrap();
    let p = ecdrive::drives::esi_profile::from_esi(&f, &f.devices[0], "KS2").unwrap();
    assert_eq!(p.units.position_per_rev, 8_388_608.0);
}

/// What a user edits in the profile file is what goes to the drive: the TX7's InitCmd for
/// 0x2011 given other data, the one for 0x6060 removed.
#[test]
fn an_edited_profile_file_is_what_the_drive_gets() {
    use ecdrive::ec::mailbox::{MailboxMessage, SdoRequest};
    use ecdrive::master::session::{Master, MasterConfig};
    let file = "Taiga_TX7.xml";
    let dir = folder_with(file, "edit");
    let r = support::cli::ecdrive(&["esi", "profile", dir.join(file).to_str().unwrap()]);
    // TOML, whose inline tables the Rust-Debug check of `ok()` would take for Debug text.
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let text = r.stdout.clone();
    // Run from the folder: name the ESI file relative to it.
    let text = text.replace(
        &format!("esi = \"{}\"", dir.join(file).display()),
        &format!("esi = \"{file}\""),
    );
    let start = text
        .find("[[init_cmd]]\ntransitions = [\"PS\", \"SO\"]")
        .expect("0x6060's InitCmd");
    let edited = format!("{}\n", &text[..start]).replace("data = \"01\"", "data = \"00\"");
    assert!(
        edited.contains("object = \"0x2011:00\"\ndata = \"00\""),
        "{edited}"
    );
    std::fs::write(dir.join("drive.toml"), &edited).unwrap();
    let cfg_text = profile_run_config(&dir, file, "profile_file = \"drive.toml\"", "csp");
    let cfg = ecdrive_cli::app::config::parse(&cfg_text, dir.join("run.toml").to_str().unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cfg.drives[0].profile.unwrap().bus.init_cmds.len(), 2);
    let seg = ecdrive::sim::run::build_segment(
        &[format!("esi:{}", dir.join(file).display())],
        &ecdrive::sim::EscConfig::default(),
    )
    .unwrap();
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let link = mailbox_tap(seg, seen.clone());
    let mut m = Master::start(link, MasterConfig::clone(&cfg.master))
        .map_err(|f| f.error)
        .unwrap();
    m.wait_until("OP", std::time::Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let _ = m.stop(ecdrive::master::telemetry::StopKind::Ramp);
    let downloads: Vec<(u16, Vec<u8>)> = seen
        .lock()
        .unwrap()
        .iter()
        .filter_map(|(_, b)| match MailboxMessage::parse(b) {
            Ok((
                _,
                MailboxMessage::SdoRequest(SdoRequest::DownloadExpedited { index, data, .. }),
            )) => Some((index, data.to_vec())),
            _ => None,
        })
        .collect();
    assert!(downloads.contains(&(0x2011, vec![0x00])), "{downloads:x?}");
    assert!(!downloads.contains(&(0x2011, vec![0x01])), "{downloads:x?}");
    assert!(
        downloads.contains(&(0x2010, vec![0xE8, 0x03])),
        "{downloads:x?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A profile file with a mistake is named with its line and column before the bus is touched;
/// profile_file does not combine with profile or esi.
#[test]
fn a_bad_profile_file_is_named_with_line_and_column() {
    let file = "Kestrel_KS2.xml";
    let dir = folder_with(file, "bad");
    let out = dir.join("drive.toml");
    support::cli::ecdrive(&[
        "esi",
        "profile",
        dir.join(file).to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ])
    .ok();
    let good = std::fs::read_to_string(&out).unwrap();
    let cfg = |drive: &str| {
        let t = profile_run_config(&dir, file, drive, "csp");
        ecdrive_cli::app::config::parse(&t, dir.join("run.toml").to_str().unwrap())
    };
    for (from, to, want) in [
        (
            "velocity = \"position/s\"",
            "velocity = \"fast\"",
            "units.velocity",
        ),
        (
            "dc_sync0 = true",
            "dc_sync0 = true\nsync0_shift = 5",
            "unknown key",
        ),
        (
            "{ object = \"0x6040:00\", bits = 16 }",
            "{ object = \"0x6040:00\", bits = 12 }",
            "mapping",
        ),
        (
            "device = \"KS2\"",
            "device = \"KS3\"",
            "has no device \"KS3\"",
        ),
    ] {
        assert!(good.contains(from), "{from:?} not in the written profile");
        std::fs::write(&out, good.replace(from, to)).unwrap();
        let e = cfg("profile_file = \"drive.toml\"")
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains("drive.toml line ") && e.contains(want),
            "{want:?}: {e}"
        );
        let line = e
            .split("drive.toml line ")
            .nth(1)
            .and_then(|r| r.split(',').next());
        assert!(
            line.is_some_and(|l| l.parse::<u32>().is_ok_and(|n| n > 1)),
            "line: {e}"
        );
    }
    std::fs::write(&out, &good).unwrap();
    let e = cfg(&format!("profile_file = \"drive.toml\"\nesi = \"{file}\""))
        .expect_err("refused")
        .to_string();
    assert!(e.contains("profile_file alone"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A DC mode asking SYNC0 at another cycle than the bus's, or a SYNC0 shift of its own, is
/// said when the configuration is checked (ecdrive gives every drive SYNC0 at the cycle, with
/// the segment's shift).
#[test]
fn a_dc_mode_ecdrive_cannot_follow_is_said_at_the_check() {
    let dir = folder_with("Nordwind_ND40.xml", "dc");
    let f = dir.join("Nordwind_ND40.xml");
    let text = std::fs::read_to_string(&f).unwrap().replace(
        "<CycleTimeSync0 Factor=\"1\">0</CycleTimeSync0>\n            <ShiftTimeSync0>0</ShiftTimeSync0>",
        "<CycleTimeSync0 Factor=\"2\">0</CycleTimeSync0>\n            <ShiftTimeSync0>250000</ShiftTimeSync0>",
    );
    assert!(text.contains("Factor=\"2\""));
    std::fs::write(&f, text).unwrap();
    let t = profile_run_config(
        &dir,
        "Nordwind_ND40.xml",
        "esi = \"Nordwind_ND40.xml\"",
        "csp",
    );
    let cfg = ecdrive_cli::app::config::parse(&t, dir.join("run.toml").to_str().unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let notes = cfg.notes.join("\n");
    assert!(
        notes.contains("SYNC0 = 2 × the cycle (Factor 2)"),
        "{notes}"
    );
    assert!(notes.contains("SYNC0 shift of 250000 ns"), "{notes}");
    let _ = std::fs::remove_dir_all(&dir);
}
