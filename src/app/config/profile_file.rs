//! A drive profile as a TOML file a user can edit: `ecdrive esi profile FILE` writes what
//! ecdrive builds from a vendor's ESI file ([`write`]), and `[[drive]] profile_file = "…"`
//! loads it back ([`load`]).
//!
//! The file names the ESI file it came from: the dictionary (types and access, so `upload` and
//! `download` know types) and the PDO limits still come from there. Everything a user tunes
//! is in the TOML, and what the TOML says wins: the identity, the cyclic modes, the units, the
//! synchronisation, the cyclic mapping (in the syntax of `[[drive]] mapping`) and the
//! InitCmds.

use super::ethercat::build_mapping;
use super::{ConfigError, Ctx, deserialize, raw, read_text};
use crate::drives::esi_profile::{self, EsiProfileError};
use crate::drives::{CycleTimeObject, DriveProfile, InitCommand};
use crate::esi::{Device, EsiFile, Transition};
use crate::od::ObjectAddress;
use crate::pdo::Direction;
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::Path;
use toml::Spanned;

/// The file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProfile {
    esi: Spanned<String>,
    device: Spanned<String>,
    name: String,
    vendor_id: u32,
    product_code: u32,
    #[serde(default)]
    revision: u32,
    modes: Spanned<Vec<String>>,
    units: Spanned<RawUnits>,
    sync: Spanned<RawSync>,
    mapping: Spanned<raw::Mapping>,
    #[serde(default)]
    init_cmd: Vec<Spanned<RawInitCmd>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawUnits {
    position_name: String,
    position_per_rev: f64,
    velocity: Spanned<String>,
    torque_per_mille: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSync {
    dc_sync0: bool,
    free_run: bool,
    assign_activate: u16,
    #[serde(default)]
    sync_type_object: Option<Spanned<String>>,
    #[serde(default)]
    cycle_time_object: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInitCmd {
    transitions: Vec<Spanned<String>>,
    object: Spanned<String>,
    data: Spanned<String>,
    #[serde(default)]
    comment: String,
    #[serde(default)]
    complete_access: bool,
    #[serde(default)]
    timeout_ms: Option<u32>,
    #[serde(default)]
    retries: u8,
    #[serde(default)]
    fixed: bool,
    /// The line of the `<InitCmd>` in the ESI file it came from (0: written by hand).
    #[serde(default)]
    esi_line: u32,
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

fn quoted(s: &str) -> String {
    // A TOML basic string (JSON's escapes are TOML's).
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".to_string())
}

fn velocity_text(v: crate::cia402::VelocityUnit) -> String {
    match v {
        crate::cia402::VelocityUnit::PositionPerSecond => "position/s".to_string(),
        crate::cia402::VelocityUnit::RevPerMinute { scale } => format!("{scale} r/min"),
    }
}

/// The profile ecdrive builds from device `dev` of `file`, as TOML text. `esi` is how the
/// file names the ESI file (relative to where the TOML will be).
pub fn write(file: &EsiFile, dev: &Device, esi: &str) -> Result<String, EsiProfileError> {
    let p = esi_profile::from_esi(file, dev, esi)?;
    let b = &p.bus;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# The drive profile ecdrive builds from {esi} ({}), written by `ecdrive esi profile`.\n\
         # Edit it and point a drive at it: [[drive]] profile_file = \"THIS.toml\".\n\
         # What this file says wins; the dictionary (types, access) and the PDO limits come from\n\
         # the ESI file named here (relative to this file).\n",
        dev.type_.name_text
    );
    let _ = writeln!(t, "esi = {}", quoted(esi));
    let _ = writeln!(t, "# The <Type> of the device in the ESI file.");
    let _ = writeln!(t, "device = {}", quoted(&dev.type_.name_text));
    let _ = writeln!(t, "name = {}", quoted(p.name));
    let _ = writeln!(t, "vendor_id = 0x{:08X}", b.identity.vendor_id);
    let _ = writeln!(t, "product_code = 0x{:08X}", b.identity.product_code);
    let _ = writeln!(t, "revision = 0x{:08X}", b.revision);
    let modes: Vec<String> = crate::esi::CYCLIC_MODES
        .iter()
        .filter(|m| {
            p.caps
                .supported_modes
                .contains(crate::cia402::OperationMode::from_i8(m.code))
        })
        .map(|m| quoted(m.name))
        .collect();
    let _ = writeln!(
        t,
        "# The cyclic modes the drive runs (from 0x6502 when the file gives it).\nmodes = [{}]",
        modes.join(", ")
    );
    let u = &p.units;
    let _ = writeln!(
        t,
        "\n# Units of the drive's objects: position units per motor revolution (0x608F when the\n\
         # file gives it), the unit of 0x60FF/0x606C (\"position/s\" or \"SCALE r/min\"), and one\n\
         # torque unit (0x6071/0x6077) in per mille of rated torque.\n[units]"
    );
    let _ = writeln!(t, "position_name = {}", quoted(u.position_name));
    let _ = writeln!(t, "position_per_rev = {:?}", u.position_per_rev);
    let _ = writeln!(t, "velocity = {}", quoted(&velocity_text(u.velocity)));
    let _ = writeln!(t, "torque_per_mille = {:?}", u.torque_per_mille);
    let s = &b.sync;
    let _ = writeln!(
        t,
        "\n# Synchronisation: DC SYNC0 with the ESI's AssignActivate, or free run; the objects the\n\
         # master writes the synchronisation type (2) and the cycle time (ns) to, where the\n\
         # dictionary makes them writable (leave a key out: not written).\n[sync]"
    );
    let _ = writeln!(t, "dc_sync0 = {}", s.dc_sync0);
    let _ = writeln!(t, "free_run = {}", s.free_run);
    let _ = writeln!(t, "assign_activate = 0x{:04X}", s.assign_activate);
    if let Some(a) = s.sync_type_object {
        let _ = writeln!(t, "sync_type_object = \"{a}\"");
    }
    if let Some(CycleTimeObject::Nanoseconds(a)) = s.cycle_time_object {
        let _ = writeln!(t, "cycle_time_object = \"{a}\"");
    }
    let _ = writeln!(
        t,
        "\n# The cyclic mapping (as [[drive]] mapping writes it). PDOs the ESI marks Fixed are\n\
         # assigned but never rewritten.\n[mapping]"
    );
    for (dir, key) in [(Direction::Rx, "rx"), (Direction::Tx, "tx")] {
        let _ = writeln!(t, "{key} = [");
        for pdo in b.cyclic_mapping.pdos(dir) {
            let entries: Vec<String> = pdo
                .entries
                .iter()
                .map(|e| {
                    if e.is_padding() {
                        format!("{{ padding = {} }}", e.bits)
                    } else {
                        format!("{{ object = \"{}\", bits = {} }}", e.address(), e.bits)
                    }
                })
                .collect();
            let _ = writeln!(
                t,
                "  {{ pdo = 0x{:04X}, entries = [\n    {},\n  ] }},",
                pdo.index,
                entries.join(",\n    ")
            );
        }
        let _ = writeln!(t, "]");
    }
    if !b.init_cmds.is_empty() {
        let _ = writeln!(
            t,
            "\n# The ESI's <InitCmd>s (SDO downloads at the transitions named: IP, PS in PRE-OP;\n\
             # SO in SAFE-OP before OP), in order. Commands to the PDO assignment or mapping\n\
             # objects are not sent: the master writes the mapping above."
        );
    }
    for c in b.init_cmds {
        let tr: Vec<String> = c.transitions.iter().map(|x| quoted(x.name())).collect();
        let _ = writeln!(t, "\n[[init_cmd]]");
        let _ = writeln!(t, "transitions = [{}]", tr.join(", "));
        let _ = writeln!(t, "object = \"{}\"", c.address);
        let _ = writeln!(t, "data = \"{}\"", hex(c.data));
        let _ = writeln!(t, "comment = {}", quoted(c.comment));
        if c.complete_access {
            let _ = writeln!(t, "complete_access = true");
        }
        if let Some(ms) = c.timeout_ms {
            let _ = writeln!(t, "timeout_ms = {ms}");
        }
        if c.retries > 0 {
            let _ = writeln!(t, "retries = {}", c.retries);
        }
        if c.fixed {
            let _ = writeln!(t, "fixed = true");
        }
        let _ = writeln!(t, "esi_line = {}", c.line);
    }
    Ok(t)
}

fn parse_hex_bytes(s: &str) -> Result<Vec<u8>, String> {
    let t: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    if t.is_empty() || t.len() % 2 != 0 {
        return Err(format!(
            "{s:?} is not hex bytes (an even number of hex digits, the first byte first)"
        ));
    }
    (0..t.len() / 2)
        .map(|i| {
            t.get(2 * i..2 * i + 2)
                .and_then(|b| u8::from_str_radix(b, 16).ok())
                .ok_or_else(|| format!("{s:?} is not hex bytes"))
        })
        .collect()
}

fn parse_velocity(s: &str) -> Option<crate::cia402::VelocityUnit> {
    let t = s.trim();
    if t == "position/s" {
        return Some(crate::cia402::VelocityUnit::PositionPerSecond);
    }
    let scale: f64 = t.strip_suffix("r/min")?.trim().parse().ok()?;
    (scale > 0.0).then_some(crate::cia402::VelocityUnit::RevPerMinute { scale })
}

fn leak(s: &str) -> &'static str {
    String::leak(s.to_owned())
}

/// Load the profile file at `path` (every problem named with the file's line and column).
pub fn load(path: &Path) -> Result<&'static DriveProfile, ConfigError> {
    let (text, file) = read_text(path, "the profile file")?;
    let cx = Ctx {
        text: &text,
        file: &file,
    };
    let r: RawProfile = deserialize(&cx)?;
    // The ESI file and its device.
    let dir = path.parent().unwrap_or(Path::new(""));
    let esi_path = dir.join(r.esi.get_ref());
    let shown = esi_path.display().to_string();
    let esi = EsiFile::from_path(&esi_path)
        .map_err(|x| cx.err(r.esi.span(), "esi", format!("ESI file {shown}: {x}")))?;
    let dev = esi
        .devices
        .iter()
        .find(|d| d.type_.name_text == *r.device.get_ref())
        .ok_or_else(|| {
            let have: Vec<&str> = esi
                .devices
                .iter()
                .map(|d| d.type_.name_text.as_str())
                .collect();
            cx.err(
                r.device.span(),
                "device",
                format!(
                    "ESI file {shown} has no device {:?} (it has {})",
                    r.device.get_ref(),
                    have.join(", ")
                ),
            )
        })?;
    let base = esi_profile::from_esi(&esi, dev, &shown)
        .map_err(|x| cx.err(r.esi.span(), "esi", x.to_string()))?;
    let mut p = base.clone();
    p.name = leak(&r.name);
    p.bus.identity.vendor_id = r.vendor_id;
    p.bus.identity.product_code = r.product_code;
    p.bus.revision = r.revision;
    p.bus.key = leak(&format!("profile:{}", r.name));
    // Modes.
    let mut modes = 0u32;
    for m in r.modes.get_ref() {
        let c = crate::esi::CYCLIC_MODES
            .iter()
            .find(|x| x.name == m.as_str())
            .ok_or_else(|| {
                cx.err(
                    r.modes.span(),
                    "modes",
                    format!("unknown cyclic mode {m:?} (use csp, csv, cst)"),
                )
            })?;
        // 0x6502: bit (code − 1) for the standard modes (csp bit 7, csv 8, cst 9).
        modes |= 1u32 << (c.code - 1);
    }
    p.caps.supported_modes = crate::cia402::SupportedModes::from_raw(modes);
    // Units.
    let u = r.units.get_ref();
    if !(u.position_per_rev.is_finite() && u.position_per_rev > 0.0) {
        return Err(cx.err(
            r.units.span(),
            "units.position_per_rev",
            "must be a positive number",
        ));
    }
    p.units.position_name = leak(&u.position_name);
    p.units.position_per_rev = u.position_per_rev;
    p.units.torque_per_mille = u.torque_per_mille;
    p.units.velocity = parse_velocity(u.velocity.get_ref()).ok_or_else(|| {
        cx.err(
            u.velocity.span(),
            "units.velocity",
            format!(
                "{:?} is not a velocity unit (use \"position/s\" or \"SCALE r/min\", e.g. \
                 \"0.01 r/min\")",
                u.velocity.get_ref()
            ),
        )
    })?;
    // Synchronisation.
    let s = r.sync.get_ref();
    let object = |o: &Option<Spanned<String>>, key: &str| -> Result<_, ConfigError> {
        o.as_ref()
            .map(|o| {
                o.get_ref()
                    .parse::<ObjectAddress>()
                    .map_err(|e| cx.err(o.span(), key, e.to_string()))
            })
            .transpose()
    };
    p.bus.sync.dc_sync0 = s.dc_sync0;
    p.bus.sync.free_run = s.free_run;
    p.bus.sync.assign_activate = s.assign_activate;
    p.bus.sync.sync_type_object = object(&s.sync_type_object, "sync.sync_type_object")?;
    p.bus.sync.cycle_time_object =
        object(&s.cycle_time_object, "sync.cycle_time_object")?.map(CycleTimeObject::Nanoseconds);
    if !s.dc_sync0 && !s.free_run {
        return Err(cx.err(
            r.sync.span(),
            "sync",
            "dc_sync0 and free_run are both false: the drive could not be synchronised",
        ));
    }
    // The mapping, checked against the file's PDO limits and dictionary.
    let key = |k: &str| k.to_string();
    let mapping = build_mapping(&cx, &key, &r.mapping, Some(base))?;
    crate::pdo::validate(&mapping, &base.pdo_limits, Some(base.dictionary))
        .map_err(|e| cx.err(r.mapping.span(), "mapping", e.to_string()))?;
    p.bus.cyclic_mapping = mapping;
    // InitCmds.
    let mut cmds = Vec::new();
    for (i, c) in r.init_cmd.iter().enumerate() {
        let k = |f: &str| format!("init_cmd[{i}].{f}");
        let c = c.get_ref();
        let mut transitions = Vec::new();
        for t in &c.transitions {
            transitions.push(Transition::parse(t.get_ref()).ok_or_else(|| {
                cx.err(
                    t.span(),
                    k("transitions"),
                    format!("{:?} is not a transition (IP, PS, SO, …)", t.get_ref()),
                )
            })?);
        }
        cmds.push(InitCommand {
            transitions: Vec::leak(transitions),
            address: c
                .object
                .get_ref()
                .parse()
                .map_err(|e: crate::od::AddressParseError| {
                    cx.err(c.object.span(), k("object"), e.to_string())
                })?,
            data: Vec::leak(
                parse_hex_bytes(c.data.get_ref())
                    .map_err(|e| cx.err(c.data.span(), k("data"), e))?,
            ),
            comment: leak(&c.comment),
            complete_access: c.complete_access,
            line: c.esi_line,
            timeout_ms: c.timeout_ms.filter(|t| *t > 0),
            retries: c.retries,
            fixed: c.fixed,
        });
    }
    p.bus.init_cmds = Vec::leak(cmds);
    Ok(Box::leak(Box::new(p)))
}
