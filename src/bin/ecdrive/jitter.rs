//! `ecdrive jitter`: arguments and output. The measurement is `ecdrive_cli::app::harness`.

use super::exit;
use clap::Args;
use ecdrive::rt::RtSettings;
use ecdrive_cli::app::harness::{self, HarnessError, JitterConfig, Transport};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Measure ecdrive's cycle against a bare sleep loop, a plain ethercrab loop and (over an
/// interface) a SOEM loop, one after the other, at the same period, priority and CPU, on
/// emulated drives; repeated and interleaved with --repeat.
#[derive(Args, Debug)]
pub struct JitterArgs {
    /// Cycle time in µs (e.g. 1000, 500, 250, 125).
    #[arg(long, value_name = "US", default_value_t = 1000)]
    cycle_us: u64,
    /// Length of each run in seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 10.0,
        conflicts_with = "cycles"
    )]
    seconds: f64,
    /// Length of each run in cycles (instead of --seconds).
    #[arg(long, value_name = "N")]
    cycles: Option<u64>,
    /// Run over a veth pair the harness creates, the emulated drives on its far end in a
    /// network namespace (needs root). Default: in-process.
    #[arg(long, conflicts_with = "interface")]
    veth: bool,
    /// Run over this interface; its far end must already serve the drives (e.g. `ecdrive sim`
    /// on the other end of a veth pair), which are discovered unless --device names them.
    /// Needs root or CAP_NET_RAW.
    #[arg(long, short, value_name = "IF")]
    interface: Option<String>,
    /// SCHED_FIFO priority of every run's cycle thread (0: normal scheduling).
    #[arg(long, value_name = "1-99", default_value_t = 80, value_parser = clap::value_parser!(u8).range(0..=99))]
    priority: u8,
    /// Pin every run's cycle thread to this CPU.
    #[arg(long, value_name = "N")]
    cpu: Option<usize>,
    /// Do not lock memory (mlockall).
    #[arg(long)]
    no_mlock: bool,
    /// An emulated drive, in line order, optionally repeated (`generic-coe:64`); repeat the
    /// option for more. Default: generic-coe:2, or with --interface the drives discovered there.
    #[arg(long = "device", short = 'd', value_name = "NAME[:COUNT]")]
    devices: Vec<String>,
    /// How long the drives may take to reach OP, in seconds.
    #[arg(long, value_name = "S", default_value_t = 10)]
    op_timeout: u64,
    /// When both masters send their frame after SYNC0, in µs (default: half the cycle).
    #[arg(long, value_name = "US")]
    shift_us: Option<u64>,
    /// Also count each run's cycle-thread syscalls per cycle (root; the kernel tracepoint adds
    /// a little to every syscall, so leave it off when the CPU figures matter).
    #[arg(long)]
    syscalls: bool,
    /// Repeat the measurement N times, interleaved (sleep, ethercrab, SOEM, ecdrive, sleep, …),
    /// and report each figure's median and spread across the repetitions.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=100))]
    repeat: u16,
    /// Load the machine during the runs: one normal-priority thread on each CPU other than
    /// --cpu (each CPU without --cpu) writing through a 16 MiB buffer and yielding after each
    /// MiB.
    #[arg(long)]
    stress: bool,
    /// The SOEM loop program (built by benches/soem/build.sh). Default: $ECDRIVE_SOEM_LOOP,
    /// else target/soem/soem_cycle. Runs over --veth or --interface only; when it is missing
    /// the report says why there is no SOEM run.
    #[arg(long, value_name = "PATH", conflicts_with = "no_soem")]
    soem: Option<PathBuf>,
    /// Do not run the SOEM loop.
    #[arg(long)]
    no_soem: bool,
    /// Write every figure as JSON to this file.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Draw the latency histograms of the first repetition's runs on one log-scale plot (SVG).
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
}

fn expand(devices: &[String], interface: bool) -> Result<Vec<String>, String> {
    if devices.is_empty() {
        // Over an interface, the harness discovers what the far end serves.
        return Ok(if interface {
            Vec::new()
        } else {
            vec!["generic-coe".into(), "generic-coe".into()]
        });
    }
    crate::sim::repeat_devices(devices)
}

/// Run `ecdrive jitter`.
pub fn run(args: JitterArgs) -> ExitCode {
    let drives = match expand(&args.devices, args.interface.is_some()) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("ecdrive jitter: {e}");
            return ExitCode::from(exit::USAGE);
        }
    };
    let cycle = Duration::from_micros(args.cycle_us);
    let cycles = args.cycles.unwrap_or_else(|| {
        (args.seconds.max(0.0) * 1e6 / args.cycle_us.max(1) as f64).round() as u64
    });
    let mut cfg = JitterConfig::new(cycle);
    cfg.cycles = cycles;
    cfg.drives = drives;
    cfg.op_timeout = Duration::from_secs(args.op_timeout);
    cfg.count_syscalls = args.syscalls;
    cfg.sync0_shift = args.shift_us.map(Duration::from_micros);
    cfg.repeat = usize::from(args.repeat);
    cfg.stress = args.stress;
    cfg.soem = if args.no_soem {
        None
    } else {
        Some(args.soem.clone().unwrap_or_else(|| {
            std::env::var_os("ECDRIVE_SOEM_LOOP")
                .map(PathBuf::from)
                .unwrap_or_else(|| PathBuf::from("target/soem/soem_cycle"))
        }))
    };
    cfg.rt = RtSettings {
        priority: (args.priority > 0).then_some(args.priority),
        cpu: args.cpu,
        lock_memory: !args.no_mlock,
    };
    cfg.transport = match (&args.interface, args.veth) {
        (Some(i), _) => Transport::Interface(i.clone()),
        (None, true) => Transport::Veth,
        (None, false) => Transport::InProcess,
    };
    let report = match harness::run(&cfg, &|what| eprintln!("ecdrive jitter: {what}")) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("ecdrive jitter: {e}");
            return ExitCode::from(match e {
                HarnessError::Settings(_) | HarnessError::Emulation(_) => exit::USAGE,
                HarnessError::Run { .. }
                | HarnessError::Netns(_)
                | HarnessError::Link(_)
                | HarnessError::Discovery { .. } => exit::BUS,
            });
        }
    };
    for w in &report.warnings {
        eprintln!("ecdrive jitter: warning: {w}");
    }
    println!("{}", report.text());
    let command = std::iter::once("ecdrive".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let mut ok = true;
    if let Some(path) = &args.json {
        let json = serde_json::to_value(&report).map(|mut v| {
            if let Some(o) = v.as_object_mut() {
                o.insert("command".into(), serde_json::Value::String(command.clone()));
            }
            v
        });
        let written = json
            .and_then(|v| serde_json::to_string_pretty(&v))
            .map_err(|e| e.to_string())
            .and_then(|s| std::fs::write(path, s + "\n").map_err(|e| e.to_string()));
        if let Err(e) = written {
            eprintln!("ecdrive jitter: writing {}: {e}", path.display());
            ok = false;
        }
    }
    if let Some(path) = &args.svg
        && let Err(e) = std::fs::write(path, harness::svg::render(&report))
    {
        eprintln!("ecdrive jitter: writing {}: {e}", path.display());
        ok = false;
    }
    if ok {
        ExitCode::from(exit::OK)
    } else {
        ExitCode::from(exit::USAGE)
    }
}
