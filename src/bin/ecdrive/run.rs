//! `ecdrive run -c FILE`: a cyclic run from a configuration file.

use crate::{Command, exit, fail, fail_with, plot_file, print, print_json};
use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, RunProgress, run as run_config};
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

/// `ecdrive run`: the run, then with `--record` and `--plot` the recording drawn, whatever
/// the run's end (a failed drawing is the command's failure).
pub fn command(c: Command) -> ExitCode {
    match c {
        Command::Run {
            config,
            interface,
            duration,
            check,
            record,
            plot,
            esi,
            candump,
            json,
        } => {
            let files = RunFiles {
                record: record.as_deref(),
                esi: esi.as_deref(),
                candump: candump.as_deref(),
            };
            let code = run(
                &config,
                interface.as_deref(),
                duration,
                check,
                files,
                json.json,
            );
            // With --plot, the recording is drawn after the run, whatever its end; a failed
            // drawing is the command's failure.
            match (&record, &plot) {
                (Some(r), Some(p)) if !check => {
                    let drawn = plot_file(r, p);
                    if drawn == ExitCode::SUCCESS {
                        code
                    } else {
                        drawn
                    }
                }
                _ => code,
            }
        }
        _ => unreachable!("dispatch sends only run here"),
    }
}

pub fn run(
    path: &Path,
    interface: Option<&str>,
    duration: Option<Duration>,
    check: bool,
    files: RunFiles<'_>,
    json: bool,
) -> ExitCode {
    let RunFiles {
        record,
        esi,
        candump,
    } = files;
    let mut cfg = match ecdrive_cli::app::config::load_any(path) {
        Ok(ecdrive_cli::app::config::Config::EtherCat(c)) => c,
        Ok(ecdrive_cli::app::config::Config::CanOpen(c)) => {
            return run_canopen(c, interface, duration, check, files, json);
        }
        Err(e) => return fail_with("run", &e.to_string(), exit::USAGE),
    };
    if candump.is_some() {
        return fail_with(
            "run",
            &format!(
                "{}: --candump logs the frames of a CANopen run; this file is an EtherCAT run (--pcap captures its frames)",
                cfg.source
            ),
            exit::USAGE,
        );
    }
    if let Some(dir) = esi {
        let l = match crate::load_esi("run", dir) {
            Ok(l) => l,
            Err(code) => return code,
        };
        for s in l.skipped {
            cfg.warnings.push(format!("--esi: {s}"));
        }
        for p in &l.profiles {
            cfg.notes.push(format!(
                "--esi: {} (vendor 0x{:08X} product 0x{:08X} revision 0x{:08X})",
                p.name, p.identity.vendor_id, p.identity.product_code, p.revision
            ));
        }
        cfg.master.startup.esi_profiles = l.profiles;
        cfg.master.startup.esi_not_drives = l.not_drives;
    }
    if let Some(i) = interface {
        match i.parse() {
            Ok(t) => cfg.target = t,
            Err(e) => return fail("run", &e),
        }
    }
    if check {
        // Said by the check only: a run without programs that holds OP is what such a file is
        // for, and its start says nothing more.
        if cfg.duration.is_none()
            && cfg
                .master
                .startup
                .drives
                .iter()
                .all(|d| d.program.is_empty())
        {
            cfg.warnings
                .push(ecdrive_cli::app::config::ENDS_ONLY_ON_A_SIGNAL.to_string());
        }
        if json {
            #[derive(serde::Serialize)]
            struct Checked<'a> {
                config: &'a str,
                target: &'a ecdrive_cli::app::ethercat::tools::Target,
                cycle_ns: u64,
                drives: usize,
                valid: bool,
                warnings: &'a [String],
                unchecked: &'a [String],
            }
            return print_json(
                "run",
                &Checked {
                    config: &cfg.source,
                    target: &cfg.target,
                    cycle_ns: cfg.master.cycle.cycle.as_nanos() as u64,
                    drives: cfg.drives.len(),
                    valid: true,
                    warnings: &cfg.warnings,
                    unchecked: &cfg.unchecked,
                },
            );
        }
        println!(
            "{}: valid; {} drive entr{}, cycle {} µs, on {}",
            cfg.source,
            cfg.drives.len(),
            if cfg.drives.len() == 1 { "y" } else { "ies" },
            cfg.master.cycle.cycle.as_micros(),
            cfg.target
        );
        for n in &cfg.notes {
            println!("note: {n}");
        }
        for w in &cfg.warnings {
            println!("warning: {w}");
        }
        for u in &cfg.unchecked {
            println!("not checked: {u}");
        }
        return ExitCode::SUCCESS;
    }
    for n in &cfg.notes {
        eprintln!("ecdrive run: {n}");
    }
    for w in &cfg.warnings {
        eprintln!("ecdrive run: warning: {w}");
    }
    // Ctrl-C, SIGTERM and SIGHUP end the run in a controlled way (ramp, disable, INIT); a
    // second one turns the ramp into a quick stop.
    let signals = crate::stop_signals();
    let stop = signals.stop;
    let opts = RunOptions {
        duration,
        hurry: Some(signals.hurry),
        record: record.map(Path::to_path_buf),
        pcap: crate::pcap().map(Path::to_path_buf),
        ..RunOptions::default()
    };
    let bar = print::run_progress();
    let mut show = |p: &RunProgress| print::update_run_progress(&bar, p);
    let r = run_config(&cfg, &opts, &stop, &mut show);
    bar.finish_and_clear();
    let report = match r {
        Ok(r) => r,
        Err(e) => return fail("run", &e),
    };
    if let Some(c) = &report.capture {
        crate::report_capture("run", c);
    }
    finish(
        &report,
        report.outcome,
        &report.reason,
        json,
        print::run_report,
    )
}

/// A run's report on stdout (its JSON, or `text`), why it ended on stderr unless it
/// completed, and its exit code: the same for both buses.
fn finish<R: serde::Serialize>(
    report: &R,
    outcome: Outcome,
    reason: &str,
    json: bool,
    text: fn(&R),
) -> ExitCode {
    let code = match outcome {
        Outcome::Completed | Outcome::Interrupted => exit::OK,
        Outcome::DriveFault => exit::FAULT,
        Outcome::Refused => exit::REFUSED,
        Outcome::BusLost => exit::BUS,
    };
    if json {
        let c = print_json("run", report);
        if c != ExitCode::SUCCESS {
            return c;
        }
    } else {
        text(report);
    }
    if code != exit::OK {
        eprintln!("ecdrive run: {}: {reason}", outcome.describe());
    }
    ExitCode::from(code)
}

/// The files a run may be asked to read or write: `--record`, `--esi`, `--candump`.
#[derive(Clone, Copy)]
pub struct RunFiles<'a> {
    pub record: Option<&'a Path>,
    pub esi: Option<&'a Path>,
    pub candump: Option<&'a Path>,
}

/// A CANopen run file: the drives on the motion runtime over the file's CAN bus.
fn run_canopen(
    mut cfg: ecdrive_cli::app::config::canopen::CanRunConfig,
    interface: Option<&str>,
    duration: Option<Duration>,
    check: bool,
    files: RunFiles<'_>,
    json: bool,
) -> ExitCode {
    use ecdrive_cli::app::config::canopen::CanTarget;
    if files.esi.is_some() || crate::pcap().is_some() {
        return fail_with(
            "run",
            &format!(
                "{}: --esi and --pcap are for EtherCAT runs (a CANopen drive's file is its EDS)",
                cfg.source
            ),
            exit::USAGE,
        );
    }
    if let Some(i) = interface {
        if i == "sim" || i.starts_with("sim:") {
            return fail_with(
                "run",
                &format!(
                    "--interface {i:?} is an emulated EtherCAT segment; {} is a CANopen run: \
                     can-sim (its emulated drives in-process), vbus:PATH or a SocketCAN interface",
                    cfg.source
                ),
                exit::USAGE,
            );
        }
        cfg.target = if i == "can-sim" {
            CanTarget::Sim
        } else {
            match i.parse() {
                Ok(b) => CanTarget::Bus(b),
                Err(e) => return fail_with("run", &format!("--interface {i:?}: {e}"), exit::USAGE),
            }
        };
    }
    if check {
        if json {
            #[derive(serde::Serialize)]
            struct Checked<'a> {
                config: &'a str,
                bus: String,
                cycle_ns: u64,
                drives: usize,
                valid: bool,
                warnings: &'a [String],
            }
            return print_json(
                "run",
                &Checked {
                    config: &cfg.source,
                    bus: cfg.target.to_string(),
                    cycle_ns: cfg.cycle.as_nanos() as u64,
                    drives: cfg.drives.len(),
                    valid: true,
                    warnings: &cfg.warnings,
                },
            );
        }
        println!(
            "{}: valid; CANopen run, {} drive{}, SYNC every {} µs, on {}",
            cfg.source,
            cfg.drives.len(),
            if cfg.drives.len() == 1 { "" } else { "s" },
            cfg.cycle.as_micros(),
            cfg.target
        );
        for w in &cfg.warnings {
            println!("warning: {w}");
        }
        return ExitCode::SUCCESS;
    }
    for w in &cfg.warnings {
        eprintln!("ecdrive run: warning: {w}");
    }
    let signals = crate::stop_signals();
    let opts = ecdrive_cli::app::canopen::run::CanRunOptions {
        duration,
        record: files.record.map(Path::to_path_buf),
        candump: files.candump.map(Path::to_path_buf),
    };
    let report = match ecdrive_cli::app::canopen::run::run(&cfg, &opts, &signals.stop) {
        Ok(r) => r,
        // The drive refused (an SDO abort, identity, an NMT refusal): 4; the bus: 3.
        Err(e) => return fail_with("run", &e.to_string(), crate::can::exit_code(&e)),
    };
    finish(
        &report,
        report.outcome,
        &report.reason,
        json,
        print::can_run_report,
    )
}
