//! The `ecdrive` command line. Argument parsing and output only: the work is in the library.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

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
    }
}
