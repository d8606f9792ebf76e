//! The `ecdrive` command line. Argument parsing and output only: the work is in the library.

mod jitter;

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// EtherCAT master for CiA 402 servo drives.
#[derive(Parser)]
#[command(name = "ecdrive", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the main job on emulated drives: an MR-J4-TM and a BDHDE in-process, brought to OP
    /// with DC, through a csp, csv and cst sequence. Needs no hardware and no root.
    Demo,
    /// Emulate a line of EtherCAT devices on a network interface until Ctrl-C (needs root or
    /// CAP_NET_RAW). Any master on the other end of the wire sees real slaves.
    Sim {
        /// Interface to serve on (e.g. one end of a veth pair).
        #[arg(long, short, required_unless_present = "list_devices")]
        interface: Option<String>,
        /// A device, in line order; repeat for more devices.
        #[arg(long = "device", short = 'd', value_name = "NAME")]
        devices: Vec<String>,
        /// SM watchdog reset value in units of 100 µs (0 disables it; default: the ESC reset
        /// value of 1000 = 100 ms).
        #[arg(long, value_name = "UNITS")]
        sm_watchdog: Option<u16>,
        /// List the device names and exit.
        #[arg(long)]
        list_devices: bool,
    },
    /// Measure the cycle's timing against a bare sleep loop and a plain ethercrab loop.
    Jitter(jitter::JitterArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Demo => {
            eprintln!(
                "ecdrive demo: not available yet.\n\
                 When finished it will start an emulated Mitsubishi MR-J4-TM and a Servotronix \
                 BDHDE in-process, bring both to OP with DC SYNC0, run a csp move, a csv ramp and \
                 a cst step, and print a summary per drive and the cycle timing.\n\
                 The software slave and the master loop it needs are still being built."
            );
            ExitCode::from(2)
        }
        Command::Sim {
            interface,
            devices,
            sm_watchdog,
            list_devices,
        } => sim(interface, devices, sm_watchdog, list_devices),
        Command::Jitter(args) => jitter::run(args),
    }
}

fn sim(
    interface: Option<String>,
    devices: Vec<String>,
    sm_watchdog: Option<u16>,
    list_devices: bool,
) -> ExitCode {
    use ecdrive::sim::devices::DEVICE_NAMES;
    if list_devices {
        for (name, what) in DEVICE_NAMES {
            println!("{name:14} {what}");
        }
        return ExitCode::SUCCESS;
    }
    let Some(interface) = interface else {
        eprintln!("ecdrive sim: --interface is required");
        return ExitCode::from(2);
    };
    let opts = ecdrive::sim::run::SimOptions {
        interface,
        devices,
        sm_watchdog,
    };
    let prepared = match ecdrive::sim::run::Prepared::new(&opts) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("ecdrive sim: {e}");
            return ExitCode::FAILURE;
        }
    };
    eprintln!(
        "ecdrive sim: serving {} device(s) on {} — Ctrl-C to stop",
        opts.devices.len(),
        opts.interface
    );
    for line in prepared.describe() {
        eprintln!("  {line}");
    }
    let stop = Arc::new(AtomicBool::new(false));
    let on_signal = stop.clone();
    let waiter = std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .build();
        match rt {
            Ok(rt) => {
                let _ = rt.block_on(tokio::signal::ctrl_c());
            }
            Err(e) => eprintln!("ecdrive sim: cannot wait for Ctrl-C ({e}); stopping"),
        }
        on_signal.store(true, Ordering::Release);
    });
    match prepared.serve(&stop) {
        Ok(stats) => {
            let _ = waiter.join();
            eprintln!(
                "ecdrive sim: stopped; {} frames answered, {} dropped",
                stats.frames, stats.dropped
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("ecdrive sim: {e}");
            ExitCode::FAILURE
        }
    }
}
