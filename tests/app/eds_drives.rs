//! Every CiA 402 drive of the EDS corpus (`../shared/eds-corpus`, real vendor files listed in
//! its `MANIFEST.tsv`), run the way a user with only the vendor's file would: a configuration
//! file that names the file and the node and nothing else about the drive (`eds = "FILE"`,
//! `node = 5`), on `interface = "can-sim"`, where the software slave emulates the drive from the
//! same file. Each drive is enabled, runs pv at a set velocity, switches to pp and moves to two
//! targets; the test asserts the values — the velocity the drive reported in pv, the position
//! it reported at the end — not only that the run completed.
//!
//! `ECDRIVE_EDS_TABLE=PATH` writes the result table (`scripts/eds-corpus-table` makes
//! `docs/eds-corpus.md` from it).

use crate::support;

use ecdrive_cli::app::config::{self, Config};
use ecdrive_cli::app::ethercat::tools::run::Outcome;

/// The pv velocity and pp targets, position units (the file's own; no user units), and the
/// accelerations: within every corpus file's limits (Faulhaber's 6083h stops at 32000).
const PV_VELOCITY: i64 = 2_000;
const PP_TARGETS: [i64; 2] = [5_000, 1_000];
const ACCELERATION: i64 = 20_000;

/// One file's configuration: its path and node, the program; nothing from a profile. The
/// program runs pv, then pp, of those the file's 6502h declares.
fn config_text(eds: &std::path::Path, pv: bool, pp: bool) -> String {
    let mut steps = Vec::new();
    if pv {
        steps.push(format!(
            "{{ step = \"pv\", velocity = {PV_VELOCITY}, acceleration = {ACCELERATION}, seconds = 0.3 }}"
        ));
    }
    if pp {
        if pv {
            steps.push("{ step = \"mode\", mode = \"pp\" }".to_string());
        }
        steps.push(format!(
            "{{ step = \"pp\", to = [{}, {}], velocity = 4000, acceleration = {ACCELERATION} }}",
            PP_TARGETS[0], PP_TARGETS[1]
        ));
    }
    format!(
        r#"interface = "can-sim"
cycle = "4ms"

[[drive]]
node = 5
eds = {eds:?}
mode = "{}"
program = [
  {}
]
"#,
        if pv { "pv" } else { "pp" },
        steps.join(",\n  ")
    )
}

struct Row {
    file: String,
    product: String,
    /// 6502h's pv and pp bits.
    pv: bool,
    pp: bool,
    result: Result<(i64, f64, Vec<String>), String>,
}

fn run_one(dir: &std::path::Path, rel: &str, csv: &std::path::Path) -> Row {
    let path = dir.join(rel);
    let bytes = std::fs::read(&path).expect("file");
    let file = ecdrive::eds::EdsFile::parse(&bytes).expect("the reader takes every corpus file");
    let product = file.device.product_name.clone();
    let modes = file.supported_modes().unwrap_or(0x25);
    let (pp, pv) = (modes & 1 == 1, modes >> 2 & 1 == 1);
    let text = config_text(&path, pv, pp || !pv);
    let result = (|| {
        let cfg = match config::parse_any(&text, "drive.toml").map_err(|e| e.to_string())? {
            Config::CanOpen(c) => c,
            Config::EtherCat(_) => return Err("read as an EtherCAT run".to_string()),
        };
        let opts = ecdrive_cli::app::canopen::run::CanRunOptions {
            record: Some(csv.to_path_buf()),
            ..Default::default()
        };
        let stop = std::sync::atomic::AtomicBool::new(false);
        let r =
            ecdrive_cli::app::canopen::run::run(&cfg, &opts, &stop).map_err(|e| e.to_string())?;
        if r.outcome != Outcome::Completed {
            return Err(format!("{:?}: {}", r.outcome, r.reason));
        }
        let d = r.drives.first().ok_or("no drive in the report")?;
        if !d.program_done || !d.errors.is_empty() {
            return Err(format!("program not done: {:?}", d.errors));
        }
        // The pv velocity the drive reported (0x606C through its TPDO), at its peak.
        let csv_text = std::fs::read_to_string(csv).map_err(|e| e.to_string())?;
        let mut lines = csv_text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
        let col = |n: &str| header.iter().position(|h| *h == n);
        let (Some(mode), Some(sent), Some(vel)) =
            (col("mode"), col("mode_sent"), col("velocity_drive_units"))
        else {
            return Err(format!("recording columns: {header:?}"));
        };
        // The pv phase: the drive shows pv (6061h), or, where its file does not let 6061h
        // into a TPDO (Roboteq), the master sends pv.
        let is_pv = |m: Option<&&str>| m.is_some_and(|m| *m == "pv" || *m == "3");
        let pv_peak = lines
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|r| is_pv(r.get(mode)) || is_pv(r.get(sent)))
            .filter_map(|r| r.get(vel).and_then(|v| v.parse::<f64>().ok()))
            .fold(0.0f64, |a, v| a.max(v));
        Ok((d.position, pv_peak, d.modes.clone()))
    })();
    // The table names corpus files as the docs do, not by where this machine keeps them.
    let result = result.map_err(|e| e.replace(&dir.display().to_string(), "../shared/eds-corpus"));
    Row {
        file: rel.to_string(),
        product: if product.trim().is_empty() {
            "(no ProductName)".to_string()
        } else {
            product
        },
        pv,
        pp,
        result,
    }
}

#[test]
fn every_corpus_drive_runs_pv_and_pp_from_its_eds_file_alone() {
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let tmp = std::env::temp_dir().join(format!("ecdrive-eds-drives-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).expect("dir");
    let mut rows = Vec::new();
    for m in support::corpus::manifest(&dir) {
        if m["has_6040"] != "yes" || m["has_6041"] != "yes" {
            continue;
        }
        let row = run_one(&dir, &m["path"], &tmp.join("run.csv"));
        eprintln!("{}: {:?}", row.file, row.result);
        rows.push(row);
    }
    let _ = std::fs::remove_dir_all(&tmp);
    if let Some(out) = std::env::var_os("ECDRIVE_EDS_TABLE") {
        let mut t = String::from(
            "| file | product | pv peak (units/s) | end position | modes run | result |\n\
             |---|---|---|---|---|---|\n",
        );
        for r in &rows {
            match &r.result {
                Ok((pos, peak, modes)) => t.push_str(&format!(
                    "| `{}` | {} | {peak:.0} | {pos} | {} | ran |\n",
                    r.file,
                    r.product,
                    modes.join(", ")
                )),
                Err(e) => t.push_str(&format!(
                    "| `{}` | {} | | | | {} |\n",
                    r.file,
                    r.product,
                    e.replace('|', "\\|")
                )),
            }
        }
        std::fs::write(&out, t).expect("table");
    }
    assert!(
        rows.len() >= 25,
        "{} CiA 402 drives in the corpus",
        rows.len()
    );
    let failed: Vec<String> = rows
        .iter()
        .filter_map(|r| match &r.result {
            // A file whose 6502h declares neither pp nor pv: the check refuses pp, naming it.
            Err(e) if !r.pp && !r.pv && e.contains("does not support pp") => None,
            Err(e) => Some(format!("{}: {e}", r.file)),
            Ok((pos, _, _)) if r.pp && *pos != PP_TARGETS[1] => {
                Some(format!("{}: ended at {pos}, not {}", r.file, PP_TARGETS[1]))
            }
            Ok((_, peak, _))
                if r.pv && (peak - PV_VELOCITY as f64).abs() > 0.02 * PV_VELOCITY as f64 =>
            {
                Some(format!(
                    "{}: pv peaked at {peak}, not {PV_VELOCITY}",
                    r.file
                ))
            }
            Ok(_) if !r.pp && !r.pv => Some(format!("{}: ran pp, which its 6502h lacks", r.file)),
            Ok(_) => None,
        })
        .collect();
    assert!(
        failed.is_empty(),
        "{} of {} drives did not run:\n{}",
        failed.len(),
        rows.len(),
        failed.join("\n")
    );
}

/// A copy of a corpus file without the sections of `objects` (the file as a vendor might
/// ship it for a model without them).
fn without(dir: &std::path::Path, rel: &str, objects: &[&str]) -> std::path::PathBuf {
    let text = String::from_utf8_lossy(&std::fs::read(dir.join(rel)).expect("file")).to_string();
    let mut out = String::new();
    let mut skip = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            let name = t
                .trim_matches(|c| c == '[' || c == ']')
                .to_ascii_uppercase();
            skip = objects
                .iter()
                .any(|o| name == *o || name.starts_with(&format!("{o}SUB")));
        }
        if !skip {
            out.push_str(line);
            out.push('\n');
        }
    }
    let path = std::env::temp_dir().join(format!(
        "ecdrive-eds-without-{}-{}.eds",
        objects.join("-"),
        std::process::id()
    ));
    std::fs::write(&path, out).expect("write");
    path
}

/// A file that declares pv in 6502h but has no 60FFh (target velocity): `--check` refuses pv,
/// naming the object, instead of a run that "completes" with the drive standing still.
#[test]
fn a_mode_without_its_set_point_object_is_refused_by_the_check() {
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let path = without(&dir, "maxon/maxon_motor_EPOS4.eds", &["60FF"]);
    let text = config_text(&path, true, true);
    let e = config::parse_any(&text, "drive.toml").expect_err("pv without 60FFh");
    let _ = std::fs::remove_file(&path);
    let e = e.to_string();
    assert!(
        e.contains("drive[0].mode") && e.contains("no 0x60FF:00 (target velocity)"),
        "{e}"
    );
}

/// A node served from an EDS file answers `upload`/`download` without a type given: the
/// types CiA 301/402 give their objects stand in for the dictionary the master has no profile
/// of; and `reset` takes the drive's file to know it.
#[test]
fn tools_work_on_a_node_from_an_eds_file() {
    use ecdrive::canopen::master::{Master, MasterConfig};
    use ecdrive::od::{ObjectAddress, Value};
    use ecdrive::sim::canopen::{EmulatedNode, NodeSpec, SimBus};
    use ecdrive_cli::app::canopen::tools;
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let path = dir.join("maxon/maxon_motor_EPOS4.eds");
    let file = tools::read_eds(&path.display().to_string()).expect("read");
    let mut bus = SimBus::new();
    let spec = NodeSpec::from_eds(&file, "EPOS4").expect("emulation");
    bus.add_node(EmulatedNode::new(spec, 5).expect("node"));
    let mut m = Master::new(bus, MasterConfig::default());
    m.pump(20_000).expect("boot");
    let v = tools::upload(&mut m, 5, ObjectAddress::new(0x1018, 1), None).expect("1018h:01");
    assert_eq!(v, Value::Uint(0xFB), "maxon's vendor ID");
    tools::download(&mut m, 5, ObjectAddress::new(0x6081, 0), "20000", None).expect("6081h");
    let v = tools::upload(&mut m, 5, ObjectAddress::new(0x6081, 0), None).expect("6081h");
    assert_eq!(v, Value::Uint(20_000));
    // reset: refused without the file (naming --eds), done with it.
    let mut bus = SimBus::new();
    bus.add_node(EmulatedNode::new(spec, 5).expect("node"));
    use ecdrive_cli::app::canopen::reset::{CanResetOptions, reset};
    let opts = CanResetOptions {
        node: Some(5),
        ..CanResetOptions::default()
    };
    let e = reset(bus, "virtual", &opts).expect_err("no profile");
    assert!(e.to_string().contains("--eds FILE"), "{e}");
    let mut bus = SimBus::new();
    bus.add_node(EmulatedNode::new(spec, 5).expect("node"));
    let profile = ecdrive::drives::eds_can::from_eds(&file, "EPOS4").expect("profile");
    let opts = CanResetOptions {
        node: Some(5),
        eds: Some(profile),
        ..CanResetOptions::default()
    };
    let r = reset(bus, "virtual", &opts).expect("reset with the file");
    assert_eq!(r.drives.len(), 1, "{r:?}");
    assert!(r.all_clear, "{r:?}");
}
