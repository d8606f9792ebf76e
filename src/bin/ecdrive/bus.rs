//! The bus commands, one function each: `slaves`, `upload`, `download`, `sdos`, `pdos`,
//! `reset`, `states`, `diag`, `graph`, `reg`, `sii`, `alias` and `foe`. Each opens a session
//! on the EtherCAT segment (or hands a `--can` bus to [`crate::can`]), runs its tool
//! (`ecdrive_cli::app::ethercat::tools`) and prints the result, as text or JSON.

use crate::{
    AnyBusArgs, BusArgs, Command, FoeOp, RegOp, SiiOp, exit, fail, fail_with, load_esi, print,
    print_json, session,
};
use ecdrive::ec::AlState;
use ecdrive::od::{DataType, ObjectAddress};
use ecdrive_cli::app::ethercat::tools::{self, Target};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// The commands on a drive's object dictionary: `upload`, `download`, `sdos`, `pdos`.
pub fn dictionary(c: Command) -> ExitCode {
    match c {
        Command::Upload {
            bus,
            position,
            node,
            address,
            data_type,
            json,
        } => upload(bus, (position, node), address, data_type, json.json),
        Command::Download {
            bus,
            position,
            node,
            address,
            value,
            data_type,
            json,
        } => download(
            bus,
            (position, node),
            address,
            (value, data_type),
            json.json,
        ),
        Command::Sdos {
            bus,
            position,
            values,
            json,
        } => sdos(bus, position, values, json.json),
        Command::Pdos {
            bus,
            position,
            json,
        } => pdos(bus, position, json.json),
        _ => unreachable!("dispatch sends only the object dictionary's commands here"),
    }
}

/// The commands on the devices themselves: `slaves`, `states`, `reset`, `diag`, `graph`, `reg`,
/// `sii`, `alias`, `foe`.
pub fn device(c: Command) -> ExitCode {
    match c {
        Command::Slaves { bus, verbose, json } => slaves(bus, verbose, json.json),
        Command::Reset {
            bus,
            position,
            node,
            cycle_us,
            eds,
            json,
        } => reset(bus, (position, node), cycle_us, eds, json.json),
        Command::States {
            bus,
            position,
            state,
            cycle_us,
            esi,
            json,
        } => states(bus, position, (state, cycle_us), esi, json.json),
        Command::Diag {
            bus,
            position,
            reset,
            json,
        } => diag(bus, position, reset, json.json),
        Command::Graph { bus, json } => graph(bus, json.json),
        Command::Reg {
            bus,
            position,
            op,
            json,
        } => reg(bus, position, op, json.json),
        Command::Sii {
            op:
                Some(SiiOp::Write {
                    bus,
                    position,
                    file,
                    force,
                    json,
                }),
            ..
        } => sii_write(&bus.interface, position, &file, force, json.json),
        Command::Sii {
            op: None,
            interface: Some(interface),
            position: Some(position),
            esi,
            hex,
            output,
            json,
        } => sii_read(interface, position, SiiView { esi, hex }, output, json.json),
        Command::Sii { op: None, .. } => fail_with(
            "sii",
            "--interface and --position are required (see --help)",
            exit::USAGE,
        ),
        Command::Alias {
            bus,
            position,
            alias,
            json,
        } => self::alias(bus, position, alias, json.json),
        Command::Foe { op } => foe(op),
        _ => unreachable!("dispatch sends only the devices' commands here"),
    }
}

/// A session's result printed as JSON (`--json`) or as `text` prints it; a failed session's
/// exit code as it is.
fn shown<R: serde::Serialize>(
    cmd: &str,
    r: Result<R, ExitCode>,
    json: bool,
    text: impl FnOnce(&R),
) -> ExitCode {
    match r {
        Ok(r) if json => print_json(cmd, &r),
        Ok(r) => {
            text(&r);
            ExitCode::SUCCESS
        }
        Err(code) => code,
    }
}

/// `ecdrive slaves`.
pub fn slaves(bus: AnyBusArgs, verbose: bool, json: bool) -> ExitCode {
    let Some(interface) = bus.interface else {
        return crate::can::slaves(bus.can.as_deref().unwrap_or_default(), json);
    };
    let r = session("slaves", &interface, move |b| tools::slaves(b, verbose));
    shown("slaves", r, json, |r| print::slaves(r, verbose))
}

/// `ecdrive upload`.
pub fn upload(
    bus: AnyBusArgs,
    (position, node): (Option<u16>, Option<u8>),
    address: ObjectAddress,
    data_type: Option<DataType>,
    json: bool,
) -> ExitCode {
    let (Some(interface), Some(position)) = (bus.interface, position) else {
        return crate::can::upload(
            bus.can.as_deref().unwrap_or_default(),
            node.unwrap_or_default(),
            address,
            data_type,
            json,
        );
    };
    let r = session("upload", &interface, move |b| {
        tools::upload(b, position, address, data_type)
    });
    shown("upload", r, json, print::sdo_value)
}

/// `ecdrive download`.
pub fn download(
    bus: AnyBusArgs,
    (position, node): (Option<u16>, Option<u8>),
    address: ObjectAddress,
    (value, data_type): (String, Option<DataType>),
    json: bool,
) -> ExitCode {
    let (Some(interface), Some(position)) = (bus.interface, position) else {
        return crate::can::download(
            bus.can.as_deref().unwrap_or_default(),
            node.unwrap_or_default(),
            address,
            &value,
            data_type,
            json,
        );
    };
    let r = session("download", &interface, move |b| {
        tools::download(b, position, address, &value, data_type)
    });
    shown("download", r, json, print::downloaded)
}

/// `ecdrive sdos`: the listing, then, when some items could not be read, an error saying how
/// many and the first.
pub fn sdos(bus: BusArgs, position: u16, values: bool, json: bool) -> ExitCode {
    let bar = print::progress("reading the object dictionary");
    let b2 = bar.clone();
    let r = session("sdos", &bus.interface, move |b| {
        tools::sdos(b, position, values, &mut |done, total| {
            b2.set_length(total as u64);
            b2.set_position(done as u64);
        })
    });
    bar.finish_and_clear();
    let r = match r {
        Ok(r) => r,
        Err(code) => return code,
    };
    let printed = if json {
        print_json("sdos", &r)
    } else {
        print::sdos(&r);
        ExitCode::SUCCESS
    };
    if printed != ExitCode::SUCCESS {
        return printed;
    }
    let Some(p) = r.problems.first() else {
        return ExitCode::SUCCESS;
    };
    eprintln!(
        "ecdrive sdos: drive {} ({}): the listing is incomplete: {} item(s) could not be \
         read{}, the first {} {}: {}",
        r.position,
        r.drive,
        r.problems.len(),
        if r.problems.iter().any(|p| p.stopped) {
            " and the drive stopped answering"
        } else {
            ""
        },
        p.what,
        p.address,
        p.reason
    );
    ExitCode::from(exit::INCOMPLETE)
}

/// `ecdrive pdos`.
pub fn pdos(bus: BusArgs, position: u16, json: bool) -> ExitCode {
    let r = session("pdos", &bus.interface, move |b| tools::pdos(b, position));
    shown("pdos", r, json, print::pdos)
}

/// `ecdrive reset`: the reset edge to the drives in Fault, refused when one stays there.
pub fn reset(
    bus: AnyBusArgs,
    (position, node): (Option<u16>, Option<u8>),
    cycle_us: Option<u32>,
    eds: Option<PathBuf>,
    json: bool,
) -> ExitCode {
    let Some(interface) = bus.interface else {
        let cycle = Duration::from_micros(u64::from(cycle_us.unwrap_or(4000)));
        return crate::can::reset(
            bus.can.as_deref().unwrap_or_default(),
            node,
            cycle,
            eds.as_deref(),
            json,
        );
    };
    let cycle_us = cycle_us.unwrap_or(1000);
    let target: Target = match interface.parse() {
        Ok(t) => t,
        Err(e) => return fail("reset", &e),
    };
    let link = match target.open() {
        Ok(l) => l,
        Err(e) => return fail("reset", &e),
    };
    let opts = tools::reset::ResetOptions {
        position,
        cycle: Duration::from_micros(u64::from(cycle_us)),
        ..tools::reset::ResetOptions::default()
    };
    let r = match tools::reset::reset(link, &opts) {
        Ok(r) => r,
        Err(e) => return fail("reset", &e),
    };
    if json {
        let c = print_json("reset", &r);
        if c != ExitCode::SUCCESS {
            return c;
        }
    } else {
        print::reset(&r);
    }
    let Some(d) = r.drives.iter().find(|d| d.cleared == Some(false)) else {
        return ExitCode::SUCCESS;
    };
    eprintln!(
        "ecdrive reset: drive {} ({}): still in {} after the reset edge ({}): its cause is \
         still present, or the drive needs a power cycle",
        d.position,
        d.drive,
        d.after,
        d.fault.as_deref().unwrap_or("fault")
    );
    ExitCode::from(exit::REFUSED)
}

/// `ecdrive states`: the devices taken to the state asked (with `--esi`, the file's profiles
/// known too); refused, naming each, when one did not reach it.
pub fn states(
    bus: BusArgs,
    position: Option<u16>,
    (state, cycle_us): (AlState, u32),
    esi: Option<PathBuf>,
    json: bool,
) -> ExitCode {
    let mut opts = tools::StatesOptions::new(state);
    opts.position = position;
    opts.cycle = Duration::from_micros(u64::from(cycle_us));
    if let Some(path) = &esi {
        let l = match load_esi("states", path) {
            Ok(l) => l,
            Err(code) => return code,
        };
        for s in l.skipped {
            eprintln!("ecdrive states: warning: --esi: {s}");
        }
        opts.esi_profiles = l.profiles;
        opts.esi_not_drives = l.not_drives;
    }
    let report = match session("states", &bus.interface, move |b| {
        tools::states_timed(b, &opts)
    }) {
        Ok(r) => r,
        Err(code) => return code,
    };
    let r = &report.devices;
    if json {
        let c = print_json("states", &report);
        if c != ExitCode::SUCCESS {
            return c;
        }
    } else {
        print::states(r);
        if let Some(t) = &report.startup {
            print::startup(t);
        }
    }
    if r.iter().all(|c| c.ok) {
        return ExitCode::SUCCESS;
    }
    for c in r.iter().filter(|c| !c.ok) {
        eprintln!(
            "ecdrive states: drive {} ({}) did not reach {}: {}{}",
            c.position,
            c.drive,
            c.requested,
            c.reached,
            c.al_status_code
                .map(|k| format!(
                    ", AL status code 0x{k:04X} ({})",
                    c.code_text.as_deref().unwrap_or("?")
                ))
                .unwrap_or_default()
        );
        if let Some(h) = &c.hint {
            eprintln!("ecdrive states: {h}");
        }
    }
    ExitCode::from(exit::REFUSED)
}

/// `ecdrive diag`.
pub fn diag(bus: BusArgs, position: Option<u16>, reset: bool, json: bool) -> ExitCode {
    let r = session("diag", &bus.interface, move |b| {
        tools::diag::diag(b, position, reset)
    });
    shown("diag", r, json, |r| println!("{}", r.text()))
}

/// `ecdrive graph`: the segment as Graphviz dot.
pub fn graph(bus: BusArgs, json: bool) -> ExitCode {
    let master = bus.interface.clone();
    let r = session("graph", &bus.interface, tools::graph::graph);
    shown("graph", r, json, |g| print!("{}", g.dot(&master)))
}

/// `ecdrive reg read|write`: an ESC register of a device.
pub fn reg(bus: BusArgs, position: u16, op: RegOp, json: bool) -> ExitCode {
    let r = match op {
        RegOp::Read {
            address,
            len,
            data_type,
        } => {
            let len = match (len, data_type) {
                (Some(l), _) => l,
                (None, Some(t)) => match tools::type_len(t) {
                    Ok(l) => l,
                    Err(e) => return fail("reg", &e),
                },
                (None, None) => 1,
            };
            session("reg", &bus.interface, move |b| {
                tools::reg_read(b, position, address, len, data_type)
            })
        }
        RegOp::Write {
            address,
            value,
            data_type,
            bytes: _,
        } => session("reg", &bus.interface, move |b| {
            tools::reg_write(b, position, address, &value, data_type)
        }),
    };
    shown("reg", r, json, print::register)
}

/// How `ecdrive sii` shows the EEPROM it read: as an ESI skeleton, a hex dump, or (without
/// `--output`) decoded.
#[derive(Clone, Copy)]
pub struct SiiView {
    /// `--esi`.
    pub esi: bool,
    /// `--hex`.
    pub hex: bool,
}

/// `ecdrive sii`: a device's EEPROM read, written to `--output` if given, and shown.
pub fn sii_read(
    interface: String,
    position: u16,
    view: SiiView,
    output: Option<PathBuf>,
    json: bool,
) -> ExitCode {
    let bar = print::progress("reading the EEPROM");
    let b2 = bar.clone();
    let r = session("sii", &interface, move |b| {
        tools::sii::sii_read(b, position, &mut |done, total| {
            b2.set_length(total as u64);
            b2.set_position(done as u64);
        })
    });
    bar.finish_and_clear();
    let dump = match r {
        Ok(d) => d,
        Err(code) => return code,
    };
    if let Some(path) = &output
        && let Err(e) = std::fs::write(path, &dump.bytes)
    {
        return fail_with(
            "sii",
            &format!("cannot write {}: {e}", path.display()),
            exit::USAGE,
        );
    }
    let info = match tools::sii::SiiInfo::decode(&dump.bytes) {
        Ok(i) => i,
        Err(e) => {
            return fail_with(
                "sii",
                &format!("drive {} ({}): {e}", dump.position, dump.drive),
                exit::BUS,
            );
        }
    };
    if json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            dump: &'a tools::sii::SiiDump,
            info: &'a tools::sii::SiiInfo,
        }
        return print_json(
            "sii",
            &Out {
                dump: &dump,
                info: &info,
            },
        );
    }
    if view.esi {
        print!("{}", tools::sii::esi_skeleton(&info, &dump.bytes));
    } else if view.hex {
        print::hex_dump(&dump.bytes);
    } else if let Some(p) = &output {
        eprintln!(
            "ecdrive sii: wrote {} bytes to {}",
            dump.bytes.len(),
            p.display()
        );
    } else {
        print::sii(&dump, &info);
    }
    ExitCode::SUCCESS
}

/// The bytes of a file a write command sends, or its one-line refusal (exit 2).
fn read_input(cmd: &str, file: &Path) -> Result<Vec<u8>, ExitCode> {
    std::fs::read(file).map_err(|e| {
        fail_with(
            cmd,
            &format!("reading {}: {e}", file.display()),
            exit::USAGE,
        )
    })
}

/// `ecdrive sii write`.
pub fn sii_write(interface: &str, position: u16, file: &Path, force: bool, json: bool) -> ExitCode {
    let image = match read_input("sii", file) {
        Ok(b) => b,
        Err(code) => return code,
    };
    let bar = print::progress("writing the EEPROM");
    let b2 = bar.clone();
    let r = session("sii", interface, move |b| {
        tools::alias::sii_write(b, position, &image, force, &mut |done, total| {
            b2.set_length(total as u64);
            b2.set_position(done as u64);
        })
    });
    bar.finish_and_clear();
    shown("sii", r, json, |r| {
        for o in &r.overridden {
            eprintln!("ecdrive sii: --force: {o}");
        }
        println!(
            "device {}: {} bytes written to the EEPROM ({} words changed, {} unchanged), read \
             back",
            r.position, r.bytes, r.words_written, r.words_unchanged
        );
    })
}

/// `ecdrive alias`: a device's station alias written to its EEPROM.
pub fn alias(bus: BusArgs, position: u16, alias: u16, json: bool) -> ExitCode {
    let r = session("alias", &bus.interface, move |b| {
        tools::alias::alias(b, position, alias)
    });
    shown("alias", r, json, |r| {
        println!(
            "device {}: station alias 0x{:04X} (was 0x{:04X}); {} EEPROM word(s) written, \
             checksum 0x{:02X}, read back. The ESC loads it at the next power cycle (0x0012 \
             reads 0x{:04X} now).",
            r.position, r.alias, r.previous, r.words_written, r.checksum, r.register_0x0012
        );
    })
}

/// `ecdrive foe read|write`.
pub fn foe(op: FoeOp) -> ExitCode {
    match op {
        FoeOp::Write {
            bus,
            position,
            password,
            name,
            file,
            json,
        } => foe_write(
            &bus.interface,
            position,
            (&name, password),
            &file,
            json.json,
        ),
        FoeOp::Read {
            bus,
            position,
            password,
            name,
            file,
            json,
        } => foe_read(
            &bus.interface,
            position,
            (name, password),
            file.as_deref(),
            json.json,
        ),
    }
}

/// `ecdrive foe write`: `file` sent to the drive as `name` with `password`.
fn foe_write(
    interface: &str,
    position: u16,
    (name, password): (&str, u32),
    file: &Path,
    json: bool,
) -> ExitCode {
    let data = match read_input("foe", file) {
        Ok(b) => b,
        Err(code) => return code,
    };
    let bar = print::progress("writing over FoE");
    let b2 = bar.clone();
    let name = name.to_string();
    let r = session("foe", interface, move |b| {
        tools::foe::foe_write(b, position, &name, password, &data, &mut |done, total| {
            b2.set_length(total as u64);
            b2.set_position(done as u64);
        })
    });
    bar.finish_and_clear();
    shown("foe", r, json, |r| {
        println!(
            "drive {} ({}, {}): wrote {} bytes as {:?} in {} packet(s)",
            r.position, r.drive, r.al_state, r.transfer.bytes, r.name, r.transfer.packets
        );
    })
}

/// `ecdrive foe read`: the drive's file `name` to `file` (standard output without one, or
/// with `-`); the report on standard error, or as JSON.
fn foe_read(
    interface: &str,
    position: u16,
    (name, password): (String, u32),
    file: Option<&Path>,
    json: bool,
) -> ExitCode {
    let to_stdout = file.is_none_or(|f| f.as_os_str() == "-");
    if json && to_stdout {
        return fail_with(
            "foe",
            "--json prints the report: give FILE for the data",
            exit::USAGE,
        );
    }
    let bar = print::progress("reading over FoE");
    let b2 = bar.clone();
    let r = session("foe", interface, move |b| {
        tools::foe::foe_read(b, position, &name, password, &mut |done| {
            b2.set_position(done as u64);
        })
    });
    bar.finish_and_clear();
    let (data, report) = match r {
        Ok(x) => x,
        Err(code) => return code,
    };
    if to_stdout {
        use std::io::Write as _;
        if let Err(e) = std::io::stdout().write_all(&data) {
            return fail_with("foe", &format!("writing standard output: {e}"), exit::USAGE);
        }
    } else if let Some(f) = file
        && let Err(e) = std::fs::write(f, &data)
    {
        return fail_with("foe", &format!("writing {}: {e}", f.display()), exit::USAGE);
    }
    if json {
        return print_json("foe", &report);
    }
    eprintln!(
        "drive {} ({}, {}): read {} bytes of {:?} in {} packet(s)",
        report.position,
        report.drive,
        report.al_state,
        report.transfer.bytes,
        report.name,
        report.transfer.packets
    );
    ExitCode::SUCCESS
}
