//! Real vendor ESI files, as users bring them: every file of the corpus beside the repository
//! (`../shared/esi-corpus/`, its `MANIFEST.tsv` names each file's source; the files are read
//! from there, never copied here) and every device in it.
//!
//! - every file parses (what it gets wrong read past as warnings) and no device of it is
//!   unreadable;
//! - every device is emulated from its own file (`esi:FILE@0xPRODUCT:0xREVISION`) and brought
//!   to OP by the master, with its process data exchanged;
//! - every CiA 402 drive the file can carry csp for runs a csp move in-process through
//!   `esi = …`, the device emulated from the same file.
//!
//! What does not work yet is listed in [`KNOWN`] with the reason, checked to fail for that
//! reason (so that a fix shows up as a failing test to update, and a new failure is never
//! hidden). `ECDRIVE_ESI_CORPUS_TABLE=FILE` writes the result table (docs/esi-corpus.md is
//! made so, by scripts/esi-corpus-table).

use ecdrive::esi::{DeviceChoice, EsiFile, Severity};
use std::path::{Path, PathBuf};

/// The corpus folder: `ECDRIVE_ESI_CORPUS`, else `../shared/esi-corpus` beside the checkout.
fn corpus() -> Option<PathBuf> {
    let dir = std::env::var_os("ECDRIVE_ESI_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/esi-corpus"));
    if dir.join("MANIFEST.tsv").is_file() {
        Some(dir)
    } else if std::env::var_os("ECDRIVE_CI").is_some() {
        panic!("the ESI corpus is not at {}", dir.display());
    } else {
        eprintln!("skipped: no ESI corpus at {}", dir.display());
        None
    }
}

/// The corpus files, from the manifest (first column), in its order.
fn files(dir: &Path) -> Vec<PathBuf> {
    let manifest = std::fs::read_to_string(dir.join("MANIFEST.tsv")).unwrap();
    manifest
        .lines()
        .skip(1)
        .filter_map(|l| l.split('\t').next())
        .filter(|p| !p.is_empty())
        .map(|p| dir.join(p))
        .collect()
}

/// Devices that do not reach OP or run csp yet, by file name and product code, with the
/// reason a run gives (a part of it). Each is a known gap, named in the docs' table.
const KNOWN: &[(&str, u32, &str, &str)] = &[
    // Process data in the ESC's digital-I/O registers (SMs at 0x0F00..0x0F03) and on several
    // output SyncManagers: the emulated ESC serves one output and one input SM above 0x1000.
    ("iTegva_E7x_Series.xml", 0x100, "op", "0x001D"),
    ("iTegva_E7x_Series.xml", 0x101, "op", "0x001D"),
    ("iTegva_E7x_Series.xml", 0x200, "op", "0x001D"),
    ("iTegva_E7x_Series.xml", 0x201, "op", "0x001D"),
    ("iTegva_E7x_Series.xml", 0x400, "op", "0x001D"),
    ("iTegva_E7x_Series.xml", 0x401, "op", "0x001D"),
    ("SMC EX260-SECx_V11.xml", 0x0100_0001, "op", "0x001D"),
    ("SMC EX260-SECx_V11.xml", 0x0100_0002, "op", "0x001D"),
    ("SMC EX260-SECx_V11.xml", 0x0100_0003, "op", "0x001D"),
    ("SMC EX260-SECx_V11.xml", 0x0100_0004, "op", "0x001D"),
    // PDO entries that name their own mapping object (0x1600:01 "Controlword"): the file
    // does not say which objects the device maps, and it has no 0x1C12/0x1C13.
    ("Somanet_CiA402-multi.xml", 0x201, "op", "0x1c13"),
    ("Somanet_CiA402-multi.xml", 0x302, "op", "0x1c13"),
    ("Somanet_CiA402-multi.xml", 0x303, "op", "0x1c13"),
    ("Somanet_CiA402-multi.xml", 0x304, "op", "0x1c13"),
    ("Somanet_CiA402-multi.xml", 0x305, "op", "0x1c13"),
    // A DC-only drive: OP needs SYNC0, which a bare state request does not start (the csp
    // run starts it, and runs).
    ("STEPPERONLINE_A6_Servo_V0.04.xml", 0x715, "op", "0x0030"),
];

fn known(file: &str, product: u32, what: &str) -> Option<&'static str> {
    KNOWN
        .iter()
        .find(|(f, p, w, _)| *f == file && *p == product && *w == what)
        .map(|(_, _, _, r)| *r)
}

struct Row {
    file: String,
    device: String,
    identity: String,
    warnings: usize,
    cia402: Option<String>,
    op: Result<(), String>,
    csp: Option<Result<(), String>>,
}

/// Why the device is no CiA 402 drive ecdrive can run from its file (`esi show` says the
/// same), or `None` for a drive.
fn not_a_drive(f: &EsiFile, d: &ecdrive::esi::Device) -> Option<String> {
    ecdrive::esi::DrivePlan::new(f, d).not_a_drive
}

/// `ecdrive states OP` on the emulated device, in-process.
fn reach_op(file: &Path, ident: &str) -> Result<(), String> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ecdrive"))
        .args([
            "states",
            "-i",
            &format!("sim:esi:{}@{ident}", file.display()),
            "OP",
        ])
        .output()
        .map_err(|e| e.to_string())?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    if out.status.success() && text.contains(" OP ") {
        Ok(())
    } else {
        Err(text.lines().last().unwrap_or_default().to_string())
    }
}

/// A csp move through `esi = FILE`, the drive chosen by identity, emulated from the same file.
fn csp_move(file: &Path, vendor: u32, d: &ecdrive::esi::Device) -> Result<(), String> {
    use ecdrive::app::ethercat::tools::run::{Outcome, RunOptions, run};
    let revision = d
        .type_
        .revision_no
        .map_or(String::new(), |r| format!(", revision = {r}"));
    let text = format!(
        "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"esi:{f}@{id}\"]\n\
         [[drive]]\nidentity = {{ vendor_id = {vendor}, product_code = {p} }}\n\
         esi = {{ file = \"{f}\", product = {p}{revision} }}\n\
         mode = \"csp\"\nprogram = [{{ step = \"move\", by = 20000, velocity = 100000, \
         acceleration = 1000000 }}]\n",
        f = file.display(),
        id = d.identity_text(),
        p = d.type_.product_code,
    );
    let cfg = ecdrive::app::config::parse(&text, "corpus.toml").map_err(|e| e.to_string())?;
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).map_err(|e| e.to_string())?;
    if r.outcome == Outcome::Completed {
        Ok(())
    } else {
        Err(r.reason)
    }
}

#[test]
fn every_vendor_file_and_device() {
    let Some(dir) = corpus() else { return };
    let mut rows = Vec::new();
    let mut unexpected = Vec::new();
    for path in files(&dir) {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let f = EsiFile::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            f.unreadable.is_empty(),
            "{name}: {:?}",
            f.unreadable
                .iter()
                .map(|u| u.error.to_string())
                .collect::<Vec<_>>()
        );
        let issues = f.check();
        assert!(
            issues.iter().all(|i| i.severity == Severity::Warning),
            "{name}"
        );
        for d in &f.devices {
            let ident = d.identity_text();
            let chosen = f
                .choose(&DeviceChoice::parse(&ident))
                .unwrap_or_else(|e| panic!("{name} {ident}: {e}"));
            assert_eq!(f.devices.get(chosen).map(|x| x.position), Some(d.position));
            let pc = d.type_.product_code;
            let op = reach_op(&path, &ident);
            let cia402 = not_a_drive(&f, d);
            // `states OP` starts no SYNC0: a DC-only drive reaches OP in the run.
            let csp = cia402.is_none().then(|| csp_move(&path, f.vendor.id, d));
            for (what, res) in [("op", Some(&op)), ("csp", csp.as_ref())] {
                let Some(res) = res else { continue };
                match (res, known(&name, pc, what)) {
                    (Ok(()), None) => {}
                    (Err(e), Some(r)) if e.contains(r) => {}
                    (Ok(()), Some(r)) => unexpected.push(format!(
                        "{name} {ident} {what}: works now (was known to fail with {r}): \
                         update KNOWN"
                    )),
                    (Err(e), _) => unexpected.push(format!("{name} {ident} {what}: {e}")),
                }
            }
            rows.push(Row {
                file: name.clone(),
                device: d.name.clone(),
                identity: ident,
                warnings: issues.len(),
                cia402,
                op,
                csp,
            });
        }
    }
    if let Some(out) = std::env::var_os("ECDRIVE_ESI_CORPUS_TABLE") {
        std::fs::write(out, table(&rows)).unwrap();
    }
    assert!(unexpected.is_empty(), "{unexpected:#?}");
}

fn table(rows: &[Row]) -> String {
    let cell = |r: &Result<(), String>| match r {
        Ok(()) => "yes".to_string(),
        Err(e) => format!(
            "no: {}",
            e.trim_start_matches("ecdrive states: ").replace('|', "/")
        ),
    };
    let mut s = String::from(
        "| file | device | identity | file warnings | CiA 402 | reaches OP | csp move |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            r.file,
            r.device.replace('|', "/"),
            r.identity,
            r.warnings,
            match &r.cia402 {
                None => "yes".to_string(),
                Some(w) if w.starts_with("no 0x6040") => "no (I/O)".to_string(),
                Some(w) => format!("no: {w}"),
            },
            cell(&r.op),
            r.csp.as_ref().map_or_else(|| "-".to_string(), cell),
        ));
    }
    s
}

/// One file, four stepper drives (Bohign): `esi = "FILE"` alone is refused on a real
/// interface, listing the devices; on an emulated segment it takes the device the segment holds
/// at the drive's position; `esi = { file, product }` chooses by identity.
#[test]
fn a_multi_device_file_chooses_by_identity() {
    let Some(dir) = corpus() else { return };
    let f = dir.join("bohign/Bohign_MS_ECAT_V2.4.10.xml");
    let program = "mode = \"csp\"\nprogram = [{ step = \"move\", by = 1000, velocity = 100000, \
                   acceleration = 1000000 }]\n";
    let real = format!(
        "interface = \"eth9\"\n[[drive]]\nposition = 0\nesi = \"{}\"\n{program}",
        f.display()
    );
    let e = ecdrive::app::config::parse(&real, "multi.toml").unwrap_err();
    assert!(e.message.contains("describes 4 devices"), "{e}");
    assert!(e.message.contains("Bohigh CL57EC (0x00001B00)"), "{e}");
    let sim = format!(
        "interface = \"sim\"\n[sim]\ndevices = [\"esi:{f}@0x1B00\"]\n[[drive]]\nposition = 0\n\
         esi = \"{f}\"\n{program}",
        f = f.display()
    );
    let cfg = ecdrive::app::config::parse(&sim, "multi.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        cfg.master.startup.drives[0].profile.map(|p| p.name),
        Some("Bohigh CL57EC")
    );
    let table = format!(
        "interface = \"eth9\"\n[[drive]]\nposition = 0\n\
         esi = {{ file = \"{f}\", product = 0x2100 }}\n{program}",
        f = f.display()
    );
    let cfg = ecdrive::app::config::parse(&table, "multi.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        cfg.master.startup.drives[0].profile.map(|p| p.name),
        Some("Bohigh DM860EC")
    );
    let none = table.replace("0x2100", "0x2101");
    let e = ecdrive::app::config::parse(&none, "multi.toml").unwrap_err();
    assert!(
        e.message.contains("the file has no device 0x00002101"),
        "{e}"
    );
}
