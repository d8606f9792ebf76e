//! The `ecdrive` command line. Argument parsing and output only: the work is in the library
//! (`ecdrive_cli::app::ethercat::tools`, `ecdrive_cli::app::config`, `ecdrive::sim::run`).

mod bus;
mod can;
mod demo;
mod jitter;
mod print;
mod reference;
mod run;
mod sim;
mod soak;

use clap::{Args, Parser, Subcommand};
use ecdrive::ec::AlState;
use ecdrive::master::error::{ErrorKind, MasterError};
use ecdrive::od::{DataType, ObjectAddress};
use ecdrive_cli::app::ethercat::tools::{self, Target};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Exit codes (documented in `--help` and in docs/guide/run.md, "Exit codes").
pub mod exit {
    /// Success.
    pub const OK: u8 = 0;
    /// An internal error (a bug: please report it).
    pub const INTERNAL: u8 = 1;
    /// Usage or input error: bad arguments, a bad configuration or ESI file, a position out of
    /// range, a value that does not fit its type.
    pub const USAGE: u8 = 2;
    /// Bus or link error: the interface is missing or down, no permission, nothing answers,
    /// timeouts, the segment was lost.
    pub const BUS: u8 = 3;
    /// A drive refused: SDO abort, AL state change refused, OP not reached.
    pub const REFUSED: u8 = 4;
    /// A drive faulted during `run` (fault, following error).
    pub const FAULT: u8 = 5;
    /// The output is incomplete: `sdos` printed what it could read and names what it could
    /// not.
    pub const INCOMPLETE: u8 = 6;
}

const EXIT_CODES: &str = "\
Exit codes:
  0  success
  1  internal error (a bug; please report it)
  2  usage or input error (bad arguments, configuration or ESI file, position or value out of range)
  3  bus or link error (interface missing or down, no permission, no answer, timeout)
  4  a drive refused (SDO abort, AL state change refused, OP not reached)
  5  a drive faulted during `run` (fault, following error)
  6  incomplete output: `sdos` listed what it could read and names, on stderr, what it could not";

/// EtherCAT master for CiA 402 servo drives: IgH-style tools, cyclic runs from a configuration
/// file, and a software EtherCAT slave. No kernel module needed.
///
/// Bus commands take `-i IF`: a network interface (raw socket: root or CAP_NET_RAW), or
/// `sim:DEVICE,…` for emulated devices in-process (no root; see `ecdrive sim --list-devices`).
/// ecdrive is not a resident master: each command discovers the segment afresh (every device
/// goes INIT → PRE-OP), does its work, and exits.
#[derive(Parser)]
#[command(name = "ecdrive", version, about, long_about, after_help = EXIT_CODES)]
struct Cli {
    /// Write the master's frames, both directions, with timestamps, to this pcapng file
    /// (Wireshark reads it), from bus commands, `run` and `demo`; written off the cycle thread, frames
    /// the writer could not keep up with are counted, never waited for.
    #[arg(long, global = true, value_name = "FILE")]
    pcap: Option<PathBuf>,
    /// Which diagnostics go to stderr besides the command's own output: error, warn (the
    /// default: what the software slave and the harness have to say, such as a value a device
    /// did not accept or an interface that went down), info, debug or trace; `RUST_LOG` (same
    /// syntax, per module too) wins when set.
    #[arg(long, global = true, value_name = "LEVEL", default_value = "warn")]
    log: String,
    #[command(subcommand)]
    command: Command,
}

/// Diagnostics (`tracing` events of the library: the software slave, the harness) to stderr,
/// one line each, at `--log` or `RUST_LOG`. The library leaves this choice to the
/// application; without it these events reach nobody.
fn install_log(level: &str) -> Result<(), String> {
    use tracing_subscriber::EnvFilter;
    let filter = match std::env::var("RUST_LOG") {
        Ok(v) if !v.trim().is_empty() => {
            EnvFilter::try_new(v.trim()).map_err(|e| format!("RUST_LOG={v:?}: {e}"))?
        }
        _ => {
            // A bare word is taken by the filter syntax as a module name (`--log wran` would
            // silence everything): --log takes a level.
            const LEVELS: [&str; 6] = ["error", "warn", "info", "debug", "trace", "off"];
            if !LEVELS.contains(&level.to_ascii_lowercase().as_str()) {
                return Err(format!(
                    "--log {level:?} is not a level: give error, warn, info, debug, trace or \
                     off (RUST_LOG takes per-module directives)"
                ));
            }
            EnvFilter::try_new(level).map_err(|e| format!("--log {level:?}: {e}"))?
        }
    };
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .without_time()
        .with_ansi(false)
        .try_init()
        .map_err(|e| e.to_string())
}

/// `--pcap`, for the commands' sessions.
static PCAP: std::sync::OnceLock<Option<PathBuf>> = std::sync::OnceLock::new();

/// The capture file asked for with `--pcap`, if any.
pub fn pcap() -> Option<&'static std::path::Path> {
    PCAP.get().and_then(|p| p.as_deref())
}

/// Say what a capture wrote (stderr, one line).
pub fn report_capture(cmd: &str, c: &ecdrive_cli::app::capture::CaptureSummary) {
    eprintln!(
        "ecdrive {cmd}: capture {}: {} frames{}",
        c.path.display(),
        c.frames,
        if c.dropped > 0 {
            format!(", {} dropped (the writer fell behind)", c.dropped)
        } else {
            String::new()
        }
    );
}

#[derive(Args, Clone)]
struct BusArgs {
    /// Network interface of the EtherCAT segment, or `sim:DEVICE,…` for emulated devices
    /// in-process.
    #[arg(short, long, value_name = "IF")]
    interface: String,
}

#[derive(Args, Clone)]
struct AnyBusArgs {
    /// EtherCAT: network interface of the segment, or `sim:DEVICE,…` for emulated devices
    /// in-process.
    #[arg(
        short,
        long,
        value_name = "IF",
        required_unless_present = "can",
        conflicts_with = "can"
    )]
    interface: Option<String>,
    /// CANopen: a SocketCAN interface (`can0`), `virtual` (in-process bus with the emulated
    /// BLV-R, ASDA-A2 and Lexium at nodes 1, 0x7F and 0x41, fresh for every command) or
    /// `vbus:/path` (a virtual bus shared between processes; `ecdrive sim --can vbus:/path`
    /// serves emulated drives there that keep their state across commands).
    #[arg(long, value_name = "IF")]
    can: Option<String>,
}

#[derive(Args, Clone, Copy)]
struct Json {
    /// Print the result as JSON (one object or array on stdout).
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Run the main job on emulated drives: an MR-J4-TM and a BDHDE in-process, brought to OP
    /// with DC, through a csp, csv and cst sequence. Needs no hardware and no root. If the
    /// drives stop on their own (a stall of the machine trips their loss supervision), the
    /// demo resets, enables and runs again, at most three times, and says so.
    Demo(demo::DemoArgs),
    /// Run the demo's two emulated drives for a long time (default an hour) while the
    /// emulated segment drops a fraction of the frames at random (default 1 %); the programs
    /// repeat, the master recovers from controlled stops and re-starts by itself, and the
    /// report counts what happened and any unhandled error (exit code 5 if there is one).
    /// Ctrl-C ends it early, in a controlled way, with the report so far.
    Soak(soak::SoakArgs),
    /// List the devices on the segment: position, station address, alias, the AL state each
    /// was in when found (with the AL status code if its error flag was set; discovery then
    /// takes every device to PREOP), identity, name, matched drive profile, DC support and
    /// mailbox protocols. With --can:
    /// the CANopen nodes (node-ID, NMT state, device type, identity, name, profile).
    #[command(
        after_help = "Examples:\n  ecdrive slaves -i eth1\n  ecdrive slaves -i eth1 --verbose\n  ecdrive slaves -i sim:mr-j4-tm,bdhde --json\n  ecdrive slaves --can can0"
    )]
    Slaves {
        #[command(flatten)]
        bus: AnyBusArgs,
        /// Also ESC type and resources, port links, propagation delay, mailbox, EEPROM size.
        #[arg(short, long)]
        verbose: bool,
        #[command(flatten)]
        json: Json,
    },
    /// Read an object over CoE (SDO upload). The data type comes from --type, else the drive
    /// profile, else the drive's SDO information.
    #[command(
        after_help = "Examples:\n  ecdrive upload -i eth1 -p 0 0x6041:00\n  ecdrive upload -i eth1 -p 1 0x1008:00 --type string\n  ecdrive upload -i eth1 -p 0 0x6064 --json\n  ecdrive upload --can virtual -n 0x7F 0x6041:00"
    )]
    Upload {
        #[command(flatten)]
        bus: AnyBusArgs,
        /// EtherCAT: position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS", required_unless_present = "can")]
        position: Option<u16>,
        /// CANopen: node-ID (1–127, decimal or 0x hex).
        #[arg(short, long, value_name = "NODE", value_parser = parse_node, required_unless_present = "interface", conflicts_with = "position")]
        node: Option<u8>,
        /// The object: INDEX:SUB (`0x6041:00`, `6041h:0`; a bare index means sub-index 0).
        #[arg(value_name = "INDEX:SUB", value_parser = parse_address)]
        address: ObjectAddress,
        /// Data type: u8…u64, i8…i64, f32, f64, bool, string, bytes, or a CiA/IEC name
        /// (UNSIGNED16, UINT, DINT, …).
        #[arg(short = 't', long = "type", value_name = "T", value_parser = parse_type)]
        data_type: Option<DataType>,
        #[command(flatten)]
        json: Json,
    },
    /// Write an object over CoE (SDO download). Values in decimal or 0x hex; the value must fit
    /// the data type (found as for upload).
    #[command(
        after_help = "Examples:\n  ecdrive download -i eth1 -p 0 0x6065:00 100000\n  ecdrive download -i eth1 -p 1 0x6060:00 8\n  ecdrive download -i eth1 -p 0 0x2001:00 0x10 --type u16\n  ecdrive download --can can0 -n 1 0x6081:00 20000"
    )]
    Download {
        #[command(flatten)]
        bus: AnyBusArgs,
        /// EtherCAT: position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS", required_unless_present = "can")]
        position: Option<u16>,
        /// CANopen: node-ID (1–127, decimal or 0x hex).
        #[arg(short, long, value_name = "NODE", value_parser = parse_node, required_unless_present = "interface", conflicts_with = "position")]
        node: Option<u8>,
        /// The object: INDEX:SUB.
        #[arg(value_name = "INDEX:SUB", value_parser = parse_address)]
        address: ObjectAddress,
        /// The value.
        #[arg(value_name = "VALUE", allow_hyphen_values = true)]
        value: String,
        /// Data type (see `upload --help`).
        #[arg(short = 't', long = "type", value_name = "T", value_parser = parse_type)]
        data_type: Option<DataType>,
        #[command(flatten)]
        json: Json,
    },
    /// List the object dictionary through SDO information (objects, entries, types, access,
    /// PDO mappability).
    #[command(
        after_help = "Examples:\n  ecdrive sdos -i eth1 -p 0\n  ecdrive sdos -i eth1 -p 0 --values\n  ecdrive sdos -i eth1 -p 1 --json"
    )]
    Sdos {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        /// Also upload every readable entry's value.
        #[arg(long)]
        values: bool,
        #[command(flatten)]
        json: Json,
    },
    /// Show the SyncManagers and the PDO assignment and mapping as the drive reports them
    /// (over CoE; from the SII for devices without CoE).
    #[command(
        after_help = "Examples:\n  ecdrive pdos -i eth1 -p 0\n  ecdrive pdos -i eth1 -p 1 --json"
    )]
    Pdos {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        #[command(flatten)]
        json: Json,
    },
    /// Request an EtherCAT state (INIT, PREOP, SAFEOP, OP, BOOT) and report what each device
    /// reached. SAFEOP and OP configure the whole segment first (PDO mapping, DC) and exchange
    /// process data with every output zero; no drive is enabled. ecdrive does not stay
    /// resident: once it exits, a device's watchdog takes it out of OP.
    #[command(
        after_help = "Examples:\n  ecdrive states -i eth1 PREOP\n  ecdrive states -i eth1 -p 1 OP\n  ecdrive states -i eth1 INIT --json"
    )]
    States {
        #[command(flatten)]
        bus: BusArgs,
        /// Only this device (default: every device).
        #[arg(short, long, value_name = "POS")]
        position: Option<u16>,
        /// The state: INIT, PREOP, SAFEOP, OP or BOOT.
        #[arg(value_name = "STATE", value_parser = parse_state)]
        state: AlState,
        /// Cycle time of the process data for SAFEOP and OP, µs.
        #[arg(long, value_name = "US", default_value_t = 1000)]
        cycle_us: u32,
        /// A vendor ESI file, or a folder of them (*.xml): a drive no built-in profile matches
        /// is configured from its file, found by identity, as `run` does it (its PDO mapping,
        /// DC SYNC0 for a drive that needs it).
        #[arg(long, value_name = "FILE|DIR")]
        esi: Option<PathBuf>,
        #[command(flatten)]
        json: Json,
    },
    /// Clear the faults the drives have latched: a short cyclic session that gives each drive
    /// in Fault the rising edge on controlword bit 7, reports what it had latched (0x603F with
    /// the drive's alarm name) and whether it cleared, and takes the drives down again (EtherCAT:
    /// INIT; CANopen: disabled, NMT Pre-operational). A fault that does not clear (the cause is
    /// still there, or the drive needs a power cycle) is said so, with exit code 4.
    #[command(
        after_help = "Examples:\n  ecdrive reset -i eth1\n  ecdrive reset -i eth1 -p 0 --json\n  ecdrive reset --can can0\n  ecdrive reset --can vbus:/tmp/can.sock -n 3\n  ecdrive reset --can vbus:/tmp/can.sock -n 5 --eds EPOS4.eds"
    )]
    Reset {
        #[command(flatten)]
        bus: AnyBusArgs,
        /// EtherCAT: only this drive (default: every drive).
        #[arg(short, long, value_name = "POS", conflicts_with = "can")]
        position: Option<u16>,
        /// CANopen: only this node (1–127, decimal or 0x hex; default: every node with a
        /// drive profile).
        #[arg(short, long, value_name = "NODE", value_parser = parse_node, conflicts_with = "interface")]
        node: Option<u8>,
        /// Cycle time of the session, µs (default: EtherCAT 1000, CANopen 4000).
        #[arg(long, value_name = "US")]
        cycle_us: Option<u32>,
        /// CANopen: the EDS/DCF file of a drive ecdrive has no profile for; the nodes with its
        /// identity are reset as that drive.
        #[arg(long, value_name = "FILE", conflicts_with = "interface")]
        eds: Option<PathBuf>,
        #[command(flatten)]
        json: Json,
    },
    /// The ESC error counters and link status of every device (or one), with the links that
    /// look broken named in words. Reads by position without a discovery: the segment's state
    /// is not touched, so it can run while another master cycles it.
    #[command(
        after_help = "Examples:\n  ecdrive diag -i eth1\n  ecdrive diag -i eth1 -p 3\n  ecdrive diag -i eth1 --reset\n\nCounters: invalid frames and RX errors per port (0x0300+2p, 0x0301+2p), forwarded RX\nerrors (0x0308+p), processing unit and PDI errors (0x030C, 0x030D), lost links (0x0310+p).\nThey saturate at 255; --reset clears them after reading."
    )]
    Diag {
        #[command(flatten)]
        bus: BusArgs,
        /// Only the device at this position (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: Option<u16>,
        /// Clear the counters after reading them.
        #[arg(long)]
        reset: bool,
        #[command(flatten)]
        json: Json,
    },
    /// The segment's topology (which port of which device connects to which) as Graphviz DOT,
    /// with each device's identity and state; --json gives the same as data. Reads by position
    /// without a discovery, like diag.
    #[command(
        after_help = "Examples:\n  ecdrive graph -i eth1 | dot -Tsvg > segment.svg\n  ecdrive graph -i eth1 --json"
    )]
    Graph {
        #[command(flatten)]
        bus: BusArgs,
        #[command(flatten)]
        json: Json,
    },
    /// Read or write ESC registers of one device.
    #[command(
        after_help = "Examples:\n  ecdrive reg -i eth1 -p 0 read 0x0130 2\n  ecdrive reg -i eth1 -p 0 read 0x0910 --type u64\n  ecdrive reg -i eth1 -p 0 write 0x0120 2 --type u16\n  ecdrive reg -i eth1 -p 0 write 0x0012 0x1234 --type u16\n  ecdrive reg -i eth1 -p 0 write 0x0012 \"34 12\" --bytes"
    )]
    Reg {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        #[command(subcommand)]
        op: RegOp,
        #[command(flatten)]
        json: Json,
    },
    /// Read a device's SII EEPROM: a decoded summary, a hex dump, the raw bytes to a file, or
    /// an ESI skeleton.
    #[command(
        after_help = "Examples:\n  ecdrive sii -i eth1 -p 0\n  ecdrive sii -i eth1 -p 0 --hex\n  ecdrive sii -i eth1 -p 0 -o drive0.bin\n  ecdrive sii -i eth1 -p 0 --esi > drive0.xml\n  ecdrive sii write -i eth1 -p 0 drive0.bin",
        subcommand_negates_reqs = true
    )]
    Sii {
        #[command(subcommand)]
        op: Option<SiiOp>,
        /// Network interface of the EtherCAT segment, or `sim:DEVICE,…` for emulated devices
        /// in-process.
        #[arg(short, long, value_name = "IF", required = true)]
        interface: Option<String>,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS", required = true)]
        position: Option<u16>,
        /// Render the SII as an ESI skeleton (XML) on stdout.
        #[arg(long, conflicts_with_all = ["hex", "json"])]
        esi: bool,
        /// Print a hex dump of the whole EEPROM.
        #[arg(long, conflicts_with = "json")]
        hex: bool,
        /// Write the raw EEPROM bytes to FILE.
        #[arg(short, long, value_name = "FILE")]
        output: Option<PathBuf>,
        #[command(flatten)]
        json: Json,
    },
    /// Set a device's station alias in its SII EEPROM (word 4, with the header checksum), and
    /// read it back. By position, without a discovery; the device must be in INIT or PRE-OP.
    /// The ESC loads the new alias at the device's next power cycle.
    #[command(
        after_help = "Examples:\n  ecdrive alias -i eth1 -p 0 0x1001\n  ecdrive alias -i eth1 -p 2 0 --json"
    )]
    Alias {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        /// The alias (decimal or 0x hex, 0–0xFFFF; 0 = none).
        #[arg(value_name = "ALIAS", value_parser = parse_u16)]
        alias: u16,
        #[command(flatten)]
        json: Json,
    },
    /// Read or write a file on a device over FoE (File access over EtherCAT): firmware in
    /// BOOT. By position, without a discovery: the device as it is (put it into BOOT with
    /// `ecdrive states -p POS BOOT` first).
    #[command(
        after_help = "Examples:\n  ecdrive states -i eth1 -p 0 BOOT\n  ecdrive foe write -i eth1 -p 0 --password 0x4D524A34 firmware.efw fw-b5.efw\n  ecdrive foe read -i eth1 -p 0 --password 0x4D524A34 firmware.efw back.efw\n  ecdrive states -i eth1 -p 0 INIT\n\nFoE errors are the device's: 0x8009 not in Bootstrap, 0x800A wrong password, 0x8001\nfile not found, 0x8004 illegal (a file the device does not take)."
    )]
    Foe {
        #[command(subcommand)]
        op: FoeOp,
    },
    /// Show what the parser reads from an ESI file, or check it and say why it is invalid.
    #[command(
        after_help = "Examples:\n  ecdrive esi show esi/Mitsubishi_MR-J4-TM.xml\n  ecdrive esi check vendor.xml\n  ecdrive esi show esi/Servotronix_BDHDE.xml --json\n  ecdrive esi profile vendor.xml -o drive.toml"
    )]
    Esi {
        #[command(subcommand)]
        op: EsiOp,
    },
    /// Show what the reader takes from a CANopen device's EDS or DCF file (CiA 306).
    #[command(
        after_help = "Example:\n  ecdrive eds show BLVD-KRD_CANopen_V400.eds\n  ecdrive eds show drive.dcf --json"
    )]
    Eds {
        #[command(subcommand)]
        op: EdsOp,
    },
    /// A cyclic run from a configuration file: OP, enable, each drive's set-point program,
    /// controlled stop, summary. Progress on a terminal; quiet when piped. A file whose
    /// interface is a CANopen bus (can-sim, vbus:PATH) or whose drives are selected by `node`
    /// is a CANopen run: the same programs on the CANopen drives, paced by SYNC.
    #[command(
        after_help = "Examples:\n  ecdrive run -c examples/csp_move_sine.toml\n  ecdrive run -c examples/csv_ramp.toml --duration 5s --json\n  ecdrive run -c examples/csp_move_sine.toml -i veth0\n  ecdrive run -c examples/canopen_profile_modes.toml\n  ecdrive run -c examples/canopen_profile_modes.toml -i vbus:/tmp/can.sock\n\nThe configuration file is described in docs/reference/configuration.md."
    )]
    Run {
        /// The configuration file (TOML).
        #[arg(short, long, value_name = "FILE")]
        config: PathBuf,
        /// Run on this interface instead of the file's `interface` (a network interface, or
        /// sim:DEVICE,… for emulated devices in-process). The file's `[sim]` devices still tell
        /// the checks which drives to expect.
        #[arg(short, long, value_name = "IF")]
        interface: Option<String>,
        /// Stop after this long (e.g. 10s, 500ms), overriding the file's `duration`.
        #[arg(long, value_name = "TIME", value_parser = parse_duration)]
        duration: Option<Duration>,
        /// Only check the file, do not run.
        #[arg(long)]
        check: bool,
        /// Record every cycle into this CSV file: one line per axis and cycle with a reply
        /// (demand, actual, velocity, torque, following error, statusword, mode, probes,
        /// wake-up latency, exchange time, working counter, in counts and drive units and again
        /// in the run's units; the header names the columns, a column without meaning in the
        /// cycle's mode is empty). Written off
        /// the cycle thread; samples it could not keep up with are counted, never waited for.
        #[arg(long, value_name = "FILE")]
        record: Option<PathBuf>,
        /// Draw the recording as a scope into this SVG when the run ends (needs --record).
        #[arg(long, value_name = "OUT.svg", requires = "record")]
        plot: Option<PathBuf>,
        /// A vendor ESI file, or a folder of them (*.xml): a drive no built-in profile matches
        /// gets the profile its ESI file gives, found by identity, and runs its program with
        /// the PDOs `esi = FILE` would choose (files and devices that cannot be used are listed
        /// as warnings).
        #[arg(long, value_name = "FILE|DIR")]
        esi: Option<PathBuf>,
        /// A CANopen run only: every CAN frame, both directions, in candump's log format
        /// (`candump -l`: `(seconds) IFACE ID#DATA`), at the bus's time (simulated on can-sim).
        #[arg(long, value_name = "FILE")]
        candump: Option<PathBuf>,
        #[command(flatten)]
        json: Json,
    },
    /// Draw a recording of `ecdrive run --record FILE` as a scope (SVG): per drive (by position
    /// and name), position, following error, velocity and torque against time, demand and
    /// actual with a legend, in the run's units (the recording carries them); the mode of
    /// operation as bands, faults as red bands, touch-probe latches as marks.
    #[command(
        after_help = "Example:\n  ecdrive run -c examples/csp_move_sine.toml --record run.csv\n  ecdrive plot run.csv -o run.svg"
    )]
    Plot {
        /// The recording (CSV, as `run --record` writes it).
        file: PathBuf,
        /// The SVG to write.
        #[arg(short, long, value_name = "OUT.svg")]
        output: PathBuf,
    },
    /// Emulate a line of EtherCAT devices on a network interface until Ctrl-C (needs root or
    /// CAP_NET_RAW). Any master on the other end of the wire sees real slaves. With --can:
    /// emulated CANopen drives on a CAN bus (a SocketCAN interface, or vbus:PATH, a virtual
    /// bus other commands share with --can vbus:PATH).
    #[command(
        after_help = "Examples:\n  ecdrive sim --list-devices\n  ecdrive sim -i veth1 --device mr-j4-tm --device bdhde\n  ecdrive sim -i veth1 -d mr-j4-tm -d bdhde --drop 1% --seed 7 --delay 5%:200us\n  ecdrive sim -i veth1 -d mr-j4-tm --disconnect-at 5s --reconnect-at 8s --alarm 0:AL.52@12s\n  ecdrive sim -i veth1 -d bdhde+no-state-skipping -d generic-coe+cycle-time-read-only\n  ecdrive sim --can vbus:/tmp/can.sock\n  ecdrive sim --can vcan0 --node asda-a2@0x20 --node blv-r\n  ecdrive sim --can vbus:/tmp/can.sock --node eds:maxon/EPOS4.eds@5\n\nA device takes quirks after '+' (behaviour of devices ecdrive did not write; listed by\n--list-devices). Fault times (T) count from the start of serving and need a unit (500ms, 5s); positions (POS)\nare 0-based in --device order; numbers are decimal or 0x hex. The counters of injected faults\nare printed when ecdrive sim stops (and are in its --json output)."
    )]
    Sim {
        /// Interface to serve on (e.g. one end of a veth pair).
        #[arg(long, short, required_unless_present_any = ["list_devices", "can", "make_firmware"], conflicts_with = "can")]
        interface: Option<String>,
        /// Serve emulated CANopen drives on this CAN bus instead: a SocketCAN interface (vcan0,
        /// can0) or vbus:PATH (a virtual bus shared between processes; the hub starts at PATH
        /// unless one runs there).
        #[arg(long, value_name = "BUS", conflicts_with = "devices")]
        can: Option<String>,
        /// With --can: an emulated CANopen drive, NAME or NAME@ID; eds:FILE@ID for any CiA 402
        /// drive from its EDS/DCF file; NAME+eds:FILE[@ID] for a drive above with its vendor's
        /// file as its dictionary; repeat for more. Default: blv-r@1, asda-a2@0x7F,
        /// lexium-mdrive@0x41 (see --list-devices).
        #[arg(long = "node", value_name = "NAME[@ID]", requires = "can")]
        nodes: Vec<String>,
        /// A device, in line order, optionally repeated (`mr-j4-tm:32`); repeat the option for
        /// more devices. NAME+QUIRK[+QUIRK…] makes it behave like a device ecdrive did not
        /// write (see --list-devices). `esi:FILE` serves the device an ESI file describes
        /// (its identity, SII and dictionary, the PDO mapping its PDO list gives) with the
        /// generic servo's behaviour, or as an I/O device whose inputs echo its outputs when
        /// it has no CiA 402 device control; `esi:FILE@0xPRODUCT[:0xREVISION]` chooses one
        /// device of a file that describes several.
        /// NAME@OBJECT=VALUE stores a parameter in an emulated drive, in effect from power-on
        /// (`mr-j4-tm@0x2001=2`: [Pr. PA01] profile mode).
        #[arg(long = "device", short = 'd', value_name = "NAME[:COUNT]")]
        devices: Vec<String>,
        /// SM watchdog reset value in units of 100 µs (0 disables it; default: the ESC reset
        /// value of 1000 = 100 ms).
        #[arg(long, value_name = "UNITS")]
        sm_watchdog: Option<u16>,
        /// The emulated drives do not supervise the cyclic data (as the MR-J4-TM with
        /// [Pr. PN06]/[Pr. PN02] so set): for masters that cannot keep the cycle.
        #[arg(long)]
        no_loss_detection: bool,
        /// SCHED_FIFO priority of the serving thread, 1–99, or 0 for normal scheduling: an
        /// ESC answers in hardware time, and at normal priority a loaded machine loses frames.
        /// Without the privilege it serves at normal priority, with a warning.
        #[arg(long, value_name = "N", default_value_t = 70, value_parser = clap::value_parser!(u8).range(0..=99))]
        priority: u8,
        /// Pin the serving thread to this CPU.
        #[arg(long, value_name = "CPU")]
        cpu: Option<usize>,
        /// List the device names and the quirks, and exit.
        #[arg(long)]
        list_devices: bool,
        #[command(flatten)]
        faults: Box<sim::FaultArgs>,
        #[command(flatten)]
        store: sim::StoreArgs,
        #[command(flatten)]
        json: Json,
    },
    /// Measure the cycle's timing against a bare sleep loop, a plain ethercrab loop and a SOEM
    /// loop, on emulated drives (in-process, or over a veth pair or an interface), repeated
    /// and interleaved.
    Jitter(jitter::JitterArgs),
    /// Print what this build is: ecdrive's version and commit, ethercrab's version, the
    /// compiler, the build's profile and features, the drive profiles built in.
    Version {
        #[command(flatten)]
        json: Json,
    },
    /// The command-line reference as Markdown, from this parser (the book's
    /// `reference/cli.md`, written by `scripts/docs-reference`); with `config`, the run file's
    /// keys from the run-file parser (`reference/configuration-keys.md`).
    #[command(hide = true)]
    MarkdownHelp {
        /// `config`: the run file's keys instead of the command line.
        what: Option<String>,
    },
}

#[derive(Subcommand, Clone)]
enum SiiOp {
    /// Write a whole SII image (an `ecdrive sii -o` file, a vendor's .bin) into the device's
    /// EEPROM: only the words that differ, all read back. Checked first: the size against the
    /// EEPROM (always), the header checksum, the categories and the identity (--force
    /// overrides these). The device must be in INIT or PRE-OP.
    Write {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        /// The SII image.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        /// Write it even if the checksum, the categories or the identity do not fit.
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        json: Json,
    },
}

#[derive(Subcommand, Clone)]
enum FoeOp {
    /// Read file NAME from the device into FILE (`-` or none: standard output).
    Read {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        /// The FoE password (decimal or 0x hex; 0 = none).
        #[arg(long, value_name = "N", default_value = "0", value_parser = parse_u32)]
        password: u32,
        /// The file's name on the device.
        #[arg(value_name = "NAME")]
        name: String,
        /// Where to put it.
        #[arg(value_name = "FILE")]
        file: Option<PathBuf>,
        #[command(flatten)]
        json: Json,
    },
    /// Write FILE to the device as file NAME.
    Write {
        #[command(flatten)]
        bus: BusArgs,
        /// Position of the device on the segment (0 = first).
        #[arg(short, long, value_name = "POS")]
        position: u16,
        /// The FoE password (decimal or 0x hex; 0 = none).
        #[arg(long, value_name = "N", default_value = "0", value_parser = parse_u32)]
        password: u32,
        /// The file's name on the device.
        #[arg(value_name = "NAME")]
        name: String,
        /// The file to send.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        #[command(flatten)]
        json: Json,
    },
}

#[derive(Subcommand, Clone)]
enum RegOp {
    /// Read LEN bytes (default: the size of --type, else 1) from ADDR.
    Read {
        /// Register address (decimal or 0x hex).
        #[arg(value_name = "ADDR", value_parser = parse_u16)]
        address: u16,
        /// Number of bytes.
        #[arg(value_name = "LEN", value_parser = parse_u16)]
        len: Option<u16>,
        /// Decode the bytes as this type (little-endian).
        #[arg(short = 't', long = "type", value_name = "T", value_parser = parse_type)]
        data_type: Option<DataType>,
    },
    /// Write VALUE to ADDR: a number as --type (decimal or 0x, written little-endian, as the
    /// register is), or with --bytes hex bytes in address order.
    #[command(group(clap::ArgGroup::new("encoding").required(true).args(["data_type", "bytes"])))]
    Write {
        /// Register address (decimal or 0x hex).
        #[arg(value_name = "ADDR", value_parser = parse_u16)]
        address: u16,
        /// The value: a number for --type (`258`, `0x0102`, `-2`), hex bytes for --bytes
        /// (`"02 01"`, `0201`).
        #[arg(value_name = "VALUE", allow_hyphen_values = true)]
        value: String,
        /// Encode the value as this type, little-endian (u8, u16, u32, i16, …).
        #[arg(short = 't', long = "type", value_name = "T", value_parser = parse_type)]
        data_type: Option<DataType>,
        /// VALUE is hex bytes, written as given, the first byte to ADDR.
        #[arg(long)]
        bytes: bool,
    },
}

#[derive(Subcommand, Clone)]
enum EdsOp {
    /// Identity, PDO counts, bit rates, the CiA 402 modes 6502h declares and for each the
    /// objects its cyclic exchange needs (in a PDO, or not mappable), the mappable objects, and
    /// every warning with its line.
    Show {
        /// The EDS or DCF file.
        file: PathBuf,
        #[command(flatten)]
        json: Json,
    },
}

#[derive(Subcommand, Clone)]
enum EsiOp {
    /// What the parser reads: vendor, devices, SyncManagers, PDOs, DC modes, dictionary size.
    Show {
        /// The ESI file.
        file: PathBuf,
        #[command(flatten)]
        json: Json,
    },
    /// Write the drive profile ecdrive builds from the file as TOML to edit and use with
    /// `[[drive]] profile_file = "…"` (identity, modes, units, synchronisation, mapping,
    /// InitCmds).
    Profile {
        /// The ESI file.
        file: PathBuf,
        /// The device, when the file describes several: its identity 0xPRODUCT[:0xREVISION],
        /// or its <Type> or <Name> text (refused, listing them, when that fits several).
        #[arg(long, value_name = "TYPE")]
        device: Option<String>,
        /// Write to FILE instead of standard output (the ESI file is then named relative to
        /// it).
        #[arg(short = 'o', long, value_name = "FILE")]
        output: Option<PathBuf>,
    },
    /// Parse and check for consistency; exit 2 with every problem (line, column, what) if the
    /// file is invalid.
    Check {
        /// The ESI file.
        file: PathBuf,
        #[command(flatten)]
        json: Json,
    },
}

fn parse_address(s: &str) -> Result<ObjectAddress, String> {
    s.parse::<ObjectAddress>().map_err(|e| e.to_string())
}

fn parse_type(s: &str) -> Result<DataType, String> {
    DataType::parse(s).ok_or_else(|| {
        format!(
            "unknown data type {s:?} (use u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, \
             string, bytes, or a CiA/IEC name such as UNSIGNED16 or DINT)"
        )
    })
}

fn parse_node(s: &str) -> Result<u8, String> {
    let v = parse_u16(s)?;
    u8::try_from(v)
        .ok()
        .filter(|n| (1..=127).contains(n))
        .ok_or_else(|| format!("node-ID {s:?} is not in 1–127"))
}

fn parse_state(s: &str) -> Result<AlState, String> {
    AlState::parse(s)
        .ok_or_else(|| format!("unknown state {s:?} (use INIT, PREOP, SAFEOP, OP or BOOT)"))
}

/// A 32-bit number from the command line, decimal or 0x hex (also `ecdrive sim`'s).
pub(crate) fn parse_u32(s: &str) -> Result<u32, String> {
    let t = s.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16),
        None => t.parse::<u32>(),
    }
    .map_err(|_| format!("{s:?} is not a 32-bit number (decimal or 0x hex)"))
}

fn parse_u16(s: &str) -> Result<u16, String> {
    let t = s.trim();
    let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16),
        None => t.parse::<u32>(),
    }
    .map_err(|_| format!("{s:?} is not a number (decimal or 0x hex)"))?;
    u16::try_from(v).map_err(|_| format!("{s:?} is larger than 0xFFFF"))
}

fn parse_duration(s: &str) -> Result<Duration, String> {
    ecdrive_cli::app::config::parse_duration(s)
}

/// The exit code for a library error.
/// A flag that Ctrl-C sets: long runs (`run`, `soak`) poll it and end in a controlled way
/// (ramp, disable, INIT) with their report. The thread waiting for the signal is left waiting
/// when the run ends by itself.
/// Stop requests by signal. SIGINT (Ctrl-C), SIGTERM (systemd, docker, `timeout`) and SIGHUP
/// (the terminal went away) all ask for a controlled stop (`stop`: ramp, disable, INIT,
/// summary); a second one asks to hurry (`hurry`: a quick stop instead of the ramp, the drives
/// still disabled before the process ends).
pub struct StopSignals {
    /// The first signal came.
    pub stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// A second signal came.
    pub hurry: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

pub fn stop_signals() -> StopSignals {
    use std::sync::atomic::Ordering;
    use tokio::signal::unix::{SignalKind, signal};
    let s = StopSignals {
        stop: std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false)),
        hurry: std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false)),
    };
    let (stop, hurry) = (s.stop.clone(), s.hurry.clone());
    let _ = std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            let Ok(rt) = tokio::runtime::Builder::new_current_thread()
                .enable_io()
                .build()
            else {
                return;
            };
            rt.block_on(async move {
                let (Ok(mut int), Ok(mut term), Ok(mut hup)) = (
                    signal(SignalKind::interrupt()),
                    signal(SignalKind::terminate()),
                    signal(SignalKind::hangup()),
                ) else {
                    return;
                };
                loop {
                    tokio::select! {
                        _ = int.recv() => {}
                        _ = term.recv() => {}
                        _ = hup.recv() => {}
                    }
                    if stop.swap(true, Ordering::AcqRel) {
                        hurry.store(true, Ordering::Release);
                    }
                }
            });
        });
    s
}

/// The first stop signal ([`stop_signals`]) as a flag.
pub fn ctrl_c_flag() -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    stop_signals().stop
}

pub fn exit_code(kind: &ErrorKind) -> u8 {
    exit_of(kind.class())
}

/// The exit code of a class of failure.
pub fn exit_of(class: ecdrive::ErrorClass) -> u8 {
    match class {
        ecdrive::ErrorClass::Input => exit::USAGE,
        ecdrive::ErrorClass::Bus => exit::BUS,
        ecdrive::ErrorClass::Refused => exit::REFUSED,
        ecdrive::ErrorClass::Fault => exit::FAULT,
    }
}

/// Print a library error as one line and return its exit code.
pub fn fail(cmd: &str, e: &MasterError) -> ExitCode {
    eprintln!("ecdrive {cmd}: {}", one_line(&e.to_string()));
    ExitCode::from(exit_code(&e.kind))
}

/// Print a message as one line and return `code`.
/// `ecdrive plot`: read a recording, draw it.
fn plot_file(file: &std::path::Path, out: &std::path::Path) -> ExitCode {
    use ecdrive_cli::app::plot;
    match plot::read(file).and_then(|r| plot::draw(&r, out).map(|()| r)) {
        Ok(r) => {
            eprintln!(
                "ecdrive plot: {} drive(s), {} panels, to {}",
                r.axes.len(),
                r.axes.len() * plot::PANELS.len(),
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => fail_with("plot", &e.to_string(), exit::USAGE),
    }
}

/// `--esi FILE|DIR` of `run` and `states`: the drive profiles its files give, or the one-line
/// error (exit 2) when there are none.
pub fn load_esi(
    cmd: &str,
    path: &std::path::Path,
) -> Result<ecdrive::drives::esi_profile::Loaded, ExitCode> {
    let shown = path.display();
    match ecdrive::drives::esi_profile::load_path(path) {
        Ok(l) if !l.profiles.is_empty() => Ok(l),
        Ok(l) => {
            let why = if l.skipped.is_empty() {
                "no ESI file (*.xml) there".to_string()
            } else {
                format!("no drive in its ESI files: {}", l.skipped.join("; "))
            };
            Err(fail_with(
                cmd,
                &format!("--esi {shown}: {why}"),
                exit::USAGE,
            ))
        }
        Err(e) => Err(fail_with(cmd, &format!("--esi {shown}: {e}"), exit::USAGE)),
    }
}

pub fn fail_with(cmd: &str, msg: &str, code: u8) -> ExitCode {
    eprintln!("ecdrive {cmd}: {}", one_line(msg));
    ExitCode::from(code)
}

/// Collapse whitespace and line breaks into single spaces.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Print `value` as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(cmd: &str, value: &T) -> ExitCode {
    match serde_json::to_string_pretty(value) {
        Ok(s) => {
            println!("{s}");
            ExitCode::SUCCESS
        }
        Err(e) => fail_with(cmd, &format!("cannot write JSON: {e}"), exit::INTERNAL),
    }
}

/// Clap's error as one line: `error: … (see ecdrive CMD --help)`.
fn usage_error(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut parts = Vec::new();
    for line in text.lines() {
        let l = line.trim();
        if l.starts_with("Usage:") || l.starts_with("For more information") {
            break;
        }
        if !l.is_empty() {
            parts.push(l.trim_start_matches("error: ").to_string());
        }
    }
    let mut s = parts.join(" ");
    if let Some(tip) = s.find("tip:") {
        // Keep clap's tip, it is usually the useful part ("a similar subcommand exists").
        s.replace_range(tip..tip + 4, "—");
    }
    s
}

fn session<R, F>(cmd: &str, target: &str, f: F) -> Result<R, ExitCode>
where
    R: Send + 'static,
    F: FnOnce(&mut ecdrive::master::bus::Bus<'_, tools::ToolLink>) -> Result<R, MasterError>
        + Send
        + 'static,
{
    let t: Target = target.parse().map_err(|e| fail(cmd, &e))?;
    let (r, capture) = tools::session_captured(&t, pcap(), f).map_err(|e| fail(cmd, &e))?;
    if let Some(c) = &capture {
        report_capture(cmd, c);
    }
    Ok(r)
}

fn main() -> ExitCode {
    // Output piped into `head` and the like: end quietly when the reader goes away, as Unix
    // tools do, instead of failing on every later write.
    // SAFETY: restoring the default disposition of SIGPIPE before any thread is started; no
    // handler runs Rust code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Bad input never panics; should a bug panic anyway, say so in one line, without a
    // backtrace, and exit with the internal-error code.
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".into());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!(
            "ecdrive: internal error (please report it): {}{at}",
            one_line(&msg)
        );
    }));
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind as K;
            return match e.kind() {
                K::DisplayHelp | K::DisplayVersion => {
                    let _ = e.print();
                    ExitCode::SUCCESS
                }
                K::DisplayHelpOnMissingArgumentOrSubcommand => {
                    let _ = e.print();
                    ExitCode::from(exit::USAGE)
                }
                _ => {
                    eprintln!("ecdrive: {} (see --help)", usage_error(&e));
                    ExitCode::from(exit::USAGE)
                }
            };
        }
    };
    if let Err(e) = install_log(&cli.log) {
        eprintln!("ecdrive: {e} (see --help)");
        return ExitCode::from(exit::USAGE);
    }
    match std::panic::catch_unwind(move || dispatch(cli)) {
        Ok(code) => code,
        Err(_) => ExitCode::from(exit::INTERNAL),
    }
}

/// Run the command the line asks for: one function per command (the bus commands are
/// [`bus`]'s, the others their modules' or below).
fn dispatch(cli: Cli) -> ExitCode {
    if cli.pcap.is_some() && !sends_frames(&cli.command) {
        eprintln!(
            "ecdrive: --pcap captures the EtherCAT frames of the bus commands and run; this \
             command sends none through it"
        );
        return ExitCode::from(exit::USAGE);
    }
    let _ = PCAP.set(cli.pcap.clone());
    match cli.command {
        Command::Demo(args) => demo::run(args),
        Command::Soak(args) => soak::run(args),
        c @ (Command::Upload { .. }
        | Command::Download { .. }
        | Command::Sdos { .. }
        | Command::Pdos { .. }) => bus::dictionary(c),
        c @ (Command::Slaves { .. }
        | Command::States { .. }
        | Command::Reset { .. }
        | Command::Diag { .. }
        | Command::Graph { .. }
        | Command::Reg { .. }
        | Command::Sii { .. }
        | Command::Alias { .. }
        | Command::Foe { .. }) => bus::device(c),
        Command::Eds {
            op: EdsOp::Show { file, json },
        } => eds_show(&file, json.json),
        Command::Esi { op } => esi(op),
        c @ Command::Run { .. } => run::command(c),
        Command::Plot { file, output } => plot_file(&file, &output),
        Command::MarkdownHelp { what } => match what.as_deref() {
            None => {
                print!(
                    "{}",
                    reference::markdown(&<Cli as clap::CommandFactory>::command())
                );
                ExitCode::SUCCESS
            }
            Some("config") => {
                print!("{}", ecdrive_cli::app::config::schema::markdown());
                ExitCode::SUCCESS
            }
            Some(other) => {
                eprintln!("ecdrive markdown-help: {other:?} is not a reference (only `config`)");
                ExitCode::from(2)
            }
        },
        Command::Version { json } => version(json.json),
        c @ Command::Sim { .. } => sim::command(c),
        Command::Jitter(args) => jitter::run(args),
    }
}

/// Whether the command sends EtherCAT frames that `--pcap` can capture: the bus commands and
/// run.
fn sends_frames(c: &Command) -> bool {
    matches!(
        c,
        Command::Slaves { .. }
            | Command::Upload { .. }
            | Command::Download { .. }
            | Command::Sdos { .. }
            | Command::Pdos { .. }
            | Command::States { .. }
            | Command::Diag { .. }
            | Command::Graph { .. }
            | Command::Reg { .. }
            | Command::Sii { .. }
            | Command::Alias { .. }
            | Command::Foe { .. }
            | Command::Run { .. }
            | Command::Demo(_)
    )
}

/// `ecdrive eds show`.
fn eds_show(file: &std::path::Path, json: bool) -> ExitCode {
    match ecdrive_cli::app::canopen::eds::show(file) {
        Ok(s) if json => print_json("eds", &s),
        Ok(s) => {
            print::eds_summary(&s);
            ExitCode::SUCCESS
        }
        Err(e) => fail_with("eds", &e, exit::USAGE),
    }
}

/// `ecdrive esi show|profile|check`.
fn esi(op: EsiOp) -> ExitCode {
    match op {
        EsiOp::Show { file, json } => match tools::esi::show(&file) {
            Ok(s) if json.json => print_json("esi", &s),
            Ok(s) => {
                print::esi_summary(&s);
                ExitCode::SUCCESS
            }
            Err(e) => fail_with("esi", &e.to_string(), exit::USAGE),
        },
        EsiOp::Profile {
            file,
            device,
            output,
        } => match tools::esi::profile(&file, device.as_deref(), output.as_deref()) {
            Ok(text) => match output {
                Some(o) => match std::fs::write(&o, text) {
                    Ok(()) => {
                        eprintln!("wrote {}", o.display());
                        ExitCode::SUCCESS
                    }
                    Err(e) => fail_with(
                        "esi",
                        &format!("cannot write {}: {e}", o.display()),
                        exit::USAGE,
                    ),
                },
                None => {
                    print!("{text}");
                    ExitCode::SUCCESS
                }
            },
            Err(e) => fail_with("esi", &e, exit::USAGE),
        },
        EsiOp::Check { file, json } => {
            let c = tools::esi::check(&file);
            if json.json {
                let code = print_json("esi", &c);
                if code != ExitCode::SUCCESS {
                    return code;
                }
            } else {
                print::esi_check(&c);
            }
            if c.valid {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(exit::USAGE)
            }
        }
    }
}

/// `ecdrive version`.
fn version(json: bool) -> ExitCode {
    let v = ecdrive_cli::app::version::Version::this_build();
    if json {
        print_json("version", &v)
    } else {
        println!("{}", v.text());
        ExitCode::SUCCESS
    }
}
