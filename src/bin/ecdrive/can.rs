//! `slaves`, `upload` and `download` on a CANopen bus (`--can IF`): the library side is
//! `ecdrive_cli::app::canopen::tools`.

use crate::{exit, fail_with, print_json};
use ecdrive::canopen::error::CanError;
use ecdrive::canopen::master::{Master, MasterConfig};
use ecdrive::canopen::transport::CanTransport;
use ecdrive::od::{DataType, ObjectAddress, Value};
use ecdrive_cli::app::canopen::tools::{self, BusSpec};
use serde_json::json;
use std::process::ExitCode;

/// The exit code for a CANopen error: a drive's refusal (an SDO abort, an identity that is not
/// the profile's, an NMT command refused) 4, a value or request the user gave wrong 2, the bus
/// 3 — the classes of the exit-code table (docs/guide/run.md).
pub fn exit_code(e: &CanError) -> u8 {
    crate::exit_of(e.class())
}

fn fail(cmd: &str, e: &CanError) -> ExitCode {
    fail_with(cmd, &e.to_string(), exit_code(e))
}

fn open(cmd: &str, bus: &str) -> Result<Master<Box<dyn CanTransport>>, ExitCode> {
    let spec: BusSpec = bus
        .parse()
        .map_err(|e: tools::BusSpecError| fail_with(cmd, &e.to_string(), exit::USAGE))?;
    let t = tools::open_bus(&spec)
        .map_err(|e| fail_with(cmd, &format!("opening CAN bus {spec}: {e}"), exit::BUS))?;
    Ok(Master::new(t, MasterConfig::default()))
}

/// Fail with a clear line when `node` does not answer at all (rather than with what the
/// first transfer happens to report).
fn present<T: CanTransport>(cmd: &str, m: &mut Master<T>, node: u8) -> Result<(), ExitCode> {
    match tools::scan(m, node..=node) {
        Ok(found) if found.iter().any(|n| n.node == node) => Ok(()),
        Ok(_) => Err(fail_with(
            cmd,
            &format!(
                "node {node} (0x{node:02X}) does not answer: no reply to an SDO upload of 0x1000 \
                 within {} ms (a node in NMT Stopped serves no SDO: `ecdrive reset --can {} -n \
                 {node}` takes it to Pre-operational, with `--eds FILE` for a drive ecdrive has \
                 no profile for)",
                tools::SCAN_WINDOW_US / 1000,
                m.transport().name()
            ),
            exit::BUS,
        )),
        Err(e) => Err(fail(cmd, &e)),
    }
}

fn hex(v: Option<u32>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("0x{v:08X}"))
}

pub fn slaves(bus: &str, json: bool) -> ExitCode {
    let mut m = match open("slaves", bus) {
        Ok(m) => m,
        Err(c) => return c,
    };
    let nodes = match tools::scan(&mut m, 1..=127) {
        Ok(n) => n,
        Err(e) => return fail("slaves", &e),
    };
    if json {
        let list: Vec<serde_json::Value> = nodes
            .iter()
            .map(|n| {
                json!({
                    "node": n.node,
                    "nmt_state": n.nmt.map(|s| s.name()),
                    "device_type": n.device_type,
                    "vendor_id": n.vendor_id,
                    "product_code": n.product_code,
                    "revision": n.revision,
                    "serial": n.serial,
                    "name": n.name,
                    "model": n.model(),
                    "profile": n.profile.map(|p| p.name),
                })
            })
            .collect();
        return print_json("slaves", &list);
    }
    let mut rows = vec![
        [
            "NODE", "NMT", "VENDOR", "PRODUCT", "TYPE", "REVISION", "SERIAL", "PROFILE", "MODEL",
        ]
        .map(String::from)
        .to_vec(),
    ];
    for n in &nodes {
        rows.push(vec![
            format!("{} (0x{:02X})", n.node, n.node),
            n.nmt.map_or("unknown", |s| s.name()).to_string(),
            hex(n.vendor_id),
            hex(n.product_code),
            hex(n.device_type),
            hex(n.revision),
            hex(n.serial),
            n.profile.map_or("-", |p| p.name).to_string(),
            n.model(),
        ]);
    }
    crate::print::table(&rows);
    if nodes.is_empty() {
        eprintln!(
            "ecdrive slaves: no node answered an SDO upload of 0x1000 on {bus}; a node in NMT \
             Stopped (as a run leaves them) answers none: `ecdrive reset --can {bus}` takes \
             every node to Pre-operational"
        );
    }
    ExitCode::SUCCESS
}

fn value_json(node: u8, addr: ObjectAddress, dt: Option<DataType>, v: &Value) -> serde_json::Value {
    let value = match v {
        Value::Int(i) => json!(i),
        Value::Uint(u) => json!(u),
        Value::Real(r) => json!(r),
        Value::Str(s) => json!(s),
        Value::Bytes(_) => json!(v.to_string()),
    };
    json!({
        "node": node,
        "address": addr.to_string(),
        "index": addr.index,
        "sub": addr.sub,
        "data_type": dt.map(|t| t.name()),
        "value": value,
        "text": dt.map_or_else(|| v.to_string(), |t| tools::format_value(v, t)),
    })
}

pub fn upload(
    bus: &str,
    node: u8,
    addr: ObjectAddress,
    dt: Option<DataType>,
    json: bool,
) -> ExitCode {
    let mut m = match open("upload", bus) {
        Ok(m) => m,
        Err(c) => return c,
    };
    if let Err(c) = present("upload", &mut m, node) {
        return c;
    }
    let v = match tools::upload(&mut m, node, addr, dt) {
        Ok(v) => v,
        Err(e) => return fail("upload", &e),
    };
    let dt = m.data_type(node, addr, dt).ok();
    if json {
        return print_json("upload", &value_json(node, addr, dt, &v));
    }
    match dt {
        Some(t) => println!("{}", tools::format_value(&v, t)),
        None => println!("{v}"),
    }
    ExitCode::SUCCESS
}

pub fn download(
    bus: &str,
    node: u8,
    addr: ObjectAddress,
    text: &str,
    dt: Option<DataType>,
    json: bool,
) -> ExitCode {
    let mut m = match open("download", bus) {
        Ok(m) => m,
        Err(c) => return c,
    };
    if let Err(c) = present("download", &mut m, node) {
        return c;
    }
    if let Err(e) = tools::download(&mut m, node, addr, text, dt) {
        return fail("download", &e);
    }
    let t = m.data_type(node, addr, dt).ok();
    let v = t.and_then(|t| Value::parse(text, t).ok());
    if json {
        return match v {
            Some(v) => print_json("download", &value_json(node, addr, t, &v)),
            None => print_json(
                "download",
                &json!({"node": node, "address": addr.to_string()}),
            ),
        };
    }
    match (v, t) {
        (Some(v), Some(t)) => println!(
            "node {node} {addr} = {} ({})",
            tools::format_value(&v, t),
            t.name()
        ),
        _ => println!("node {node} {addr} = {text}"),
    }
    ExitCode::SUCCESS
}

/// `ecdrive sim --can BUS [--node NAME[@ID]…]`: serve emulated CANopen drives until a stop
/// signal.
pub fn sim(bus: &str, nodes: &[String], json: bool) -> ExitCode {
    use ecdrive_cli::app::canopen::tools::{DEMO_NODES, EMULATED_NODES, NodeSpec};
    let spec: BusSpec = match bus.parse() {
        Ok(s) => s,
        Err(e) => return fail_with("sim", &format!("--can {bus}: {e}"), exit::USAGE),
    };
    let nodes: Vec<NodeSpec> = if nodes.is_empty() {
        DEMO_NODES
            .iter()
            .filter_map(|(id, p)| {
                let (name, _, _) = EMULATED_NODES
                    .iter()
                    .find(|(_, q, _)| std::ptr::eq(*q, *p))?;
                Some(NodeSpec {
                    node: *id,
                    emulation: tools::emulation_of(p)?,
                    name,
                })
            })
            .collect()
    } else {
        match nodes.iter().map(|n| n.parse()).collect() {
            Ok(n) => n,
            Err(e) => return fail_with("sim", &format!("--node: {e}"), exit::USAGE),
        }
    };
    let stop = crate::stop_signals().stop;
    let r = tools::serve(
        &spec,
        &nodes,
        |rep| {
            eprintln!(
                "ecdrive sim: serving {} CANopen node(s) on {}{} — Ctrl-C to stop",
                rep.nodes.len(),
                rep.bus,
                if rep.started_hub {
                    " (hub started here)"
                } else {
                    ""
                }
            );
            for n in &nodes {
                eprintln!(
                    "  node {} (0x{:02X}): {} ({})",
                    n.node, n.node, n.emulation.name, n.emulation.source
                );
            }
        },
        || !stop.load(std::sync::atomic::Ordering::Relaxed),
    );
    match r {
        Ok(rep) => {
            eprintln!("ecdrive sim: stopped");
            if json {
                return print_json("sim", &rep);
            }
            ExitCode::SUCCESS
        }
        Err(e @ tools::ServeError::Bus { .. }) => fail_with("sim", &e.to_string(), exit::BUS),
        Err(e) => fail_with("sim", &e.to_string(), exit::USAGE),
    }
}

/// `ecdrive reset --can BUS [-n NODE]`: exit 0 when no drive is left in Fault, 4 when one is.
pub fn reset(
    bus: &str,
    node: Option<u8>,
    cycle: std::time::Duration,
    eds: Option<&std::path::Path>,
    json: bool,
) -> ExitCode {
    use ecdrive_cli::app::canopen::reset::{CanResetOptions, reset};
    let eds = match eds {
        None => None,
        Some(path) => {
            let shown = path.display().to_string();
            let built = tools::read_eds(&shown).and_then(|f| {
                ecdrive::drives::eds_can::from_eds(&f, &shown).map_err(|e| e.to_string())
            });
            match built {
                Ok(p) => Some(p),
                Err(e) => return fail_with("reset", &format!("--eds: {e}"), exit::USAGE),
            }
        }
    };
    let spec: BusSpec = match bus.parse() {
        Ok(s) => s,
        Err(e) => {
            let e: tools::BusSpecError = e;
            return fail_with("reset", &e.to_string(), exit::USAGE);
        }
    };
    let t = match tools::open_bus(&spec) {
        Ok(t) => t,
        Err(e) => return fail_with("reset", &format!("opening CAN bus {spec}: {e}"), exit::BUS),
    };
    let opts = CanResetOptions {
        node,
        cycle,
        eds,
        ..CanResetOptions::default()
    };
    let r = match reset(t, &spec.to_string(), &opts) {
        Ok(r) => r,
        Err(e) => return fail("reset", &e),
    };
    if json {
        let c = print_json("reset", &r);
        if c != ExitCode::SUCCESS {
            return c;
        }
    } else {
        crate::print::can_reset(&r);
    }
    match r.drives.iter().find(|d| d.cleared == Some(false)) {
        None => ExitCode::SUCCESS,
        Some(d) => {
            eprintln!(
                "ecdrive reset: node {} ({}): still in {} after the reset edge ({}): its cause \
                 is still present, or the drive needs a power cycle",
                d.node,
                d.drive,
                d.after,
                d.fault.as_deref().unwrap_or("fault")
            );
            ExitCode::from(exit::REFUSED)
        }
    }
}
