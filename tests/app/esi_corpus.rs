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

use crate::support;

fn corpus() -> Option<PathBuf> {
    support::corpus::dir()
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
const KNOWN: &[(&str, u32, &str, &str)] = &[];

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

/// `ecdrive states OP` on the emulated device, in-process; for a drive with `--esi FILE`, so
/// that a drive that needs DC SYNC0 gets it.
fn reach_op(file: &Path, ident: &str, drive: bool) -> Result<(), String> {
    let sim = format!("sim:esi:{}@{ident}", file.display());
    let mut args = vec!["states", "-i", &sim, "OP"];
    let esi = file.display().to_string();
    if drive {
        args.extend(["--esi", &esi]);
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ecdrive"))
        .args(&args)
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
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
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
    let cfg = ecdrive_cli::app::config::parse(&text, "corpus.toml").map_err(|e| e.to_string())?;
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
            let cia402 = not_a_drive(&f, d);
            let op = reach_op(&path, &ident, cia402.is_none());
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

/// One file, four stepper drives (Bohign): `esi = "FILE"` alone takes, on a real interface,
/// the device the segment reports at the drive's position (start-up reads its identity); on an
/// emulated segment the device the segment holds there; `esi = { file, product }` chooses by
/// identity.
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
    // On a real interface the file does not say which device is at position 0: start-up
    // takes the one the device reports, as one run shows (the same configuration, the segment
    // given as `run -i` does); a device the file does not describe is refused, listing them.
    let mut cfg =
        ecdrive_cli::app::config::parse(&real, "multi.toml").unwrap_or_else(|e| panic!("{e}"));
    let choices: Vec<&str> = cfg.master.startup.drives[0]
        .esi_choices
        .iter()
        .map(|p| p.name)
        .collect();
    assert_eq!(
        choices,
        [
            "Bohigh DM556EC",
            "Bohigh DM860EC",
            "Bohigh CL57EC",
            "Bohigh CL86EC"
        ]
    );
    assert!(
        cfg.notes
            .iter()
            .any(|n| n.contains("describes 4 devices; start-up takes the one")),
        "{:?}",
        cfg.notes
    );
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
    let stop = std::sync::atomic::AtomicBool::new(false);
    cfg.target = format!("sim:esi:{}@0x1D00", f.display()).parse().unwrap();
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap();
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
    assert_eq!(r.drives[0].name, "Bohigh CL86EC");
    cfg.target = "sim:mr-j4-tm".parse().unwrap();
    let e = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap_err();
    assert!(
        e.to_string()
            .contains("product 0x00000201, revision 0x00020002; the drive's ESI file describes"),
        "{e}"
    );
    let sim = format!(
        "interface = \"sim\"\n[sim]\ndevices = [\"esi:{f}@0x1B00\"]\n[[drive]]\nposition = 0\n\
         esi = \"{f}\"\n{program}",
        f = f.display()
    );
    let cfg = ecdrive_cli::app::config::parse(&sim, "multi.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        cfg.master.startup.drives[0].profile.map(|p| p.name),
        Some("Bohigh CL57EC")
    );
    let table = format!(
        "interface = \"eth9\"\n[[drive]]\nposition = 0\n\
         esi = {{ file = \"{f}\", product = 0x2100 }}\n{program}",
        f = f.display()
    );
    let cfg =
        ecdrive_cli::app::config::parse(&table, "multi.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        cfg.master.startup.drives[0].profile.map(|p| p.name),
        Some("Bohigh DM860EC")
    );
    let none = table.replace("0x2100", "0x2101");
    let e = ecdrive_cli::app::config::parse(&none, "multi.toml").unwrap_err();
    assert!(
        e.message.contains("the file has no device 0x00002101"),
        "{e}"
    );
}

/// Process data where devices without a microcontroller keep it (ETG.2000 files of digital
/// I/O modules): output SyncManagers of one byte each on the ESC's digital output register
/// (0x0F00–0x0F03), several per direction, inputs in RAM. Set up as a master does from the SII
/// (an FMMU per SM), the bytes written reach the device in SM order and, echoed by the
/// emulated module, come back in its inputs; the 4-output module takes all four bytes.
#[test]
fn outputs_on_the_digital_output_register_and_several_sms() {
    use ecdrive::ec::Command;
    use ecdrive::sim::probe::Probe;
    use ecdrive::sim::{EscConfig, ManualClock, Segment, SegmentConfig};
    use std::sync::Arc;
    let Some(dir) = corpus() else { return };
    let serve = |name: String| {
        let clock = ManualClock::new(1_000_000_000);
        let mut seg = Segment::with_config(Arc::new(clock.clone()), SegmentConfig::default());
        let dev = ecdrive::sim::devices::by_name(&name, 0).unwrap_or_else(|e| panic!("{e}"));
        seg.push(dev, EscConfig::default()).unwrap();
        let mut p = Probe::new(seg);
        p.assign_addresses(0x1000).unwrap();
        p
    };
    // (SM n: start, length, control) and an FMMU per SM: logical n, physical the SM's start.
    let setup = |p: &mut Probe, sms: &[(u16, u16, u8)]| {
        let mut logical = 0u32;
        for (n, &(start, len, ctl)) in sms.iter().enumerate() {
            let (s, l) = (start.to_le_bytes(), len.to_le_bytes());
            let sm = [s[0], s[1], l[0], l[1], ctl, 0, 1, 0];
            assert_eq!(p.fpwr(0x1000, 0x0800 + 8 * n as u16, &sm).unwrap().wkc, 1);
            let mut f = [0u8; 16];
            f[0..4].copy_from_slice(&logical.to_le_bytes());
            f[4..6].copy_from_slice(&len.to_le_bytes());
            f[7] = 7;
            f[8..10].copy_from_slice(&s);
            f[11] = if ctl & 0x04 != 0 { 2 } else { 1 };
            f[12] = 1;
            assert_eq!(p.fpwr(0x1000, 0x0600 + 16 * n as u16, &f).unwrap().wkc, 1);
            logical += u32::from(len);
        }
        for (state, name) in [(2u16, "PREOP"), (4, "SAFEOP"), (8, "OP")] {
            assert_eq!(
                p.request_state(0x1000, state).unwrap(),
                (state, 0),
                "{name}"
            );
        }
    };
    // E7.820.001: 16 relay outputs on SM0 (0x0F02) and SM1 (0x0F03), 16 inputs at 0x1000.
    let itegva = dir.join("itegva/iTegva_E7x_Series.xml");
    let mut p = serve(format!("esi:{}@0x100", itegva.display()));
    setup(
        &mut p,
        &[(0x0F02, 1, 0x44), (0x0F03, 1, 0x44), (0x1000, 2, 0x00)],
    );
    let mut last = Vec::new();
    for _ in 0..2 {
        let r = p.logical(Command::Lrw, 0, &[0xA5, 0x3C, 0, 0]).unwrap();
        // One device, read and written: 1 + 2.
        assert_eq!(r.wkc, 3);
        last = r.data;
    }
    assert_eq!(p.segment.slave(0).unwrap().esc.outputs(), &[0xA5, 0x3C]);
    assert_eq!(&last[2..4], &[0xA5, 0x3C], "the inputs echo the outputs");
    // EX260-SEC1: 32 valve outputs on four one-byte SMs, 0x0F00..0x0F03, one FMMU in the file.
    let smc = dir.join("smc/SMC EX260-SECx_V11.xml");
    let mut p = serve(format!("esi:{}@0x01000001", smc.display()));
    let sms: Vec<(u16, u16, u8)> = (0..4).map(|n| (0x0F00 + n, 1, 0x44)).collect();
    setup(&mut p, &sms);
    let r = p.logical(Command::Lwr, 0, &[1, 2, 3, 4]).unwrap();
    assert_eq!(r.wkc, 1);
    assert_eq!(p.segment.slave(0).unwrap().esc.outputs(), &[1, 2, 3, 4]);

    // An output SM in one-buffer mode (ControlByte 0x46, an SMC EX250 file's) is process data
    // too (before: SAFE-OP refused with 0x001D). A file of that shape, written here.
    let file = std::env::temp_dir().join(format!("ecdrive-one-buffer-{}.xml", std::process::id()));
    std::fs::write(
        &file,
        "<EtherCATInfo><Vendor><Id>276</Id><Name>V</Name></Vendor><Descriptions><Devices>\
         <Device><Type ProductCode=\"#x10\" RevisionNo=\"0\">OneBuffer</Type>\
         <Sm StartAddress=\"#x0f00\" ControlByte=\"#x46\" Enable=\"9\">Outputs</Sm>\
         <Sm StartAddress=\"#x1000\" ControlByte=\"#x0\" Enable=\"1\">Inputs</Sm>\
         <RxPdo Fixed=\"1\" Sm=\"0\"><Index>#x1600</Index><Name>O</Name><Entry><Index>#x7000</Index>\
         <SubIndex>1</SubIndex><BitLen>16</BitLen><Name>o</Name><DataType>UINT</DataType></Entry></RxPdo>\
         <TxPdo Fixed=\"1\" Sm=\"1\"><Index>#x1A00</Index><Name>I</Name><Entry><Index>#x6000</Index>\
         <SubIndex>1</SubIndex><BitLen>16</BitLen><Name>i</Name><DataType>UINT</DataType></Entry></TxPdo>\
         </Device></Devices></Descriptions></EtherCATInfo>",
    )
    .unwrap();
    let mut p = serve(format!("esi:{}", file.display()));
    setup(&mut p, &[(0x0F00, 2, 0x46), (0x1000, 2, 0x00)]);
    let _ = std::fs::remove_file(&file);
    for _ in 0..2 {
        last = p.logical(Command::Lrw, 0, &[7, 8, 0, 0]).unwrap().data;
    }
    assert_eq!(p.segment.slave(0).unwrap().esc.outputs(), &[7, 8]);
    assert_eq!(&last[2..4], &[7, 8]);
}

/// `run --esi FILE|DIR` (a drive found by identity among the profiles of vendor files) and
/// `esi = FILE` (the drive's own file) choose the same PDOs for a program: those the file's
/// PDOs offer for the program's modes, the smallest that holds them, never the all-modes
/// mapping for a csp program. Every CiA 402 drive of the corpus, each cyclic mode it has.
#[test]
fn esi_dir_and_esi_file_choose_the_same_pdos() {
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
    let Some(dir) = corpus() else { return };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let mut checked = 0;
    for path in files(&dir) {
        let f = EsiFile::from_path(&path).unwrap();
        for d in f.devices.iter() {
            let plan = ecdrive::esi::DrivePlan::new(&f, d);
            if plan.not_a_drive.is_some() {
                continue;
            }
            for mode in plan.modes.iter() {
                let sim = format!("esi:{}@{}", path.display(), d.identity_text());
                let head = format!(
                    "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"{sim}\"]\n\
                     [[drive]]\nposition = 0\nmode = \"{mode}\"\n\
                     program = [{{ step = \"dwell\", seconds = 0.01 }}]\n"
                );
                let own = format!("{head}esi = \"{}\"\n", path.display());
                let pdos = |text: &str, esi: bool| {
                    let mut cfg = ecdrive_cli::app::config::parse(text, "pdos.toml")
                        .unwrap_or_else(|e| panic!("{sim} {mode}: {e}"));
                    if esi {
                        let l = ecdrive::drives::esi_profile::load_path(&path).unwrap();
                        cfg.master.startup.esi_profiles = l.profiles;
                        cfg.master.startup.esi_not_drives = l.not_drives;
                    }
                    let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {})
                        .unwrap_or_else(|e| panic!("{sim} {mode}: {e}"));
                    assert_eq!(r.outcome, Outcome::Completed, "{sim} {mode}: {}", r.reason);
                    r.drives[0].pdos.clone()
                };
                assert_eq!(pdos(&own, false), pdos(&head, true), "{sim} {mode}");
                checked += 1;
            }
        }
    }
    assert!(checked >= 8, "{checked}");
}
