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

mod support {
    pub mod corpus;
}

use ecdrive::app::config::{self, Config};
use ecdrive::app::ethercat::tools::run::Outcome;

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
        let opts = ecdrive::app::canopen::run::CanRunOptions {
            record: Some(csv.to_path_buf()),
            ..Default::default()
        };
        let stop = std::sync::atomic::AtomicBool::new(false);
        let r = ecdrive::app::canopen::run::run(&cfg, &opts, &stop).map_err(|e| e.to_string())?;
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
