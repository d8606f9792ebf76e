//! A CANopen run file: the EtherCAT run file's schema with a CANopen bus as `interface` and
//! each `[[drive]]` selected by its `node`.
//!
//! ```toml
//! interface = "can-sim"      # the emulated drives in-process, one per [[drive]] at its node;
//!                            # or "vbus:PATH" (ecdrive sim --can vbus:PATH in another
//!                            # process), or a SocketCAN interface ("can0")
//! cycle = "4ms"              # the SYNC period (default 4 ms)
//! duration = "10s"           # stop after this long (default: when every program has finished)
//! reset_faults = false       # clear faults latched before the run (default: refuse, saying which)
//!
//! [[drive]]
//! node = 3                   # node-ID 1–127
//! profile = "blv-r"          # blv-r, asda-a2, lexium-mdrive, lexium-mdrive-closed-loop
//! # eds = "BLVD-KRD.eds"     # the vendor's EDS/DCF file (relative to this file): alone, any
//! #                          # CiA 402 drive; with `profile`, the profile takes the file's
//! #                          # identity and dictionary
//! mode = "pp"                # the mode at start: pp, pv or tq
//! units = { name = "rev", counts_per_unit = 36000 }
//! sdos = { "0x607C:00" = 0 }
//! program = [
//!   { step = "home", method = 24, speed_switch = 5, speed_zero = 0.5, acceleration = 100 },
//!   { step = "pp", to = [1, 0.5], velocity = 10, acceleration = 100 },
//! ]
//! ```
//!
//! The steps, units, limits and start-up values are read and checked as for an EtherCAT drive
//! (the same functions); what only the EtherCAT bus has (`position`, `alias`, `identity`,
//! `esi`, `profile_file`, `mapping`, `[sim]`, `dc_shift`, `[rt]`, `[supervision]`,
//! `allow_generic`) is refused with the key named. The cyclic modes (csp, csv, cst) and the
//! touch probe are not run over CANopen yet: the PDO plans carry the profile modes.

use super::steps::{Program, homing_writes, profile_writes, program_of};
use super::{ConfigError, Ctx, UserUnits, parse_duration, raw, start_up_values};
use crate::app::canopen::tools::{BusSpec, EMULATED_NODES};
use crate::canopen::profile::CanDriveProfile;
use crate::master::SetpointLimits;
use crate::master::program::{RunMode, Step};
use crate::od::{ObjectAddress, Value};
use crate::sim::canopen::NodeSpec as Emulation;
use std::time::Duration;
use toml::Spanned;

/// Where a CANopen run's drives are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CanTarget {
    /// `interface = "can-sim"`: an emulated drive per `[[drive]]`, in-process, at its node,
    /// on simulated time.
    Sim,
    /// A bus: a SocketCAN interface or a `vbus:PATH` hub.
    Bus(BusSpec),
}

impl core::fmt::Display for CanTarget {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Sim => f.write_str("can-sim (emulated drives in-process)"),
            Self::Bus(b) => write!(f, "CAN bus {b}"),
        }
    }
}

/// One checked `[[drive]]` of a CANopen run.
#[derive(Debug, Clone)]
pub struct CanDriveConfig {
    /// Node-ID.
    pub node: u8,
    /// The profile's name in the file (`blv-r`).
    pub key: &'static str,
    /// The drive's profile.
    pub profile: &'static CanDriveProfile,
    /// The EDS/DCF file the profile was built or refined from, as shown.
    pub eds: Option<String>,
    /// What `interface = "can-sim"` emulates at the node: the software slave's own table of
    /// the drive, or a node built from the same EDS file (never the master's profile).
    pub emulation: &'static Emulation,
    /// The mode at start.
    pub mode: RunMode,
    /// User units, if given.
    pub units: Option<UserUnits>,
    /// The program, in counts.
    pub steps: Vec<Step>,
    /// The program steps, described in the file's units.
    pub described: Vec<String>,
    /// Start-up writes: the home, pp, pv and tq steps' objects, then `sdos`.
    pub settings: Vec<(ObjectAddress, Value)>,
    /// The master's following-error limit, counts (judged in the cyclic position mode only).
    pub following_error_limit: Option<u32>,
    /// What the program's set-points must keep (counts).
    pub limits: SetpointLimits,
}

/// A checked CANopen run file.
#[derive(Debug, Clone)]
pub struct CanRunConfig {
    /// Where it came from (for messages).
    pub source: String,
    /// Where the drives are.
    pub target: CanTarget,
    /// The SYNC period.
    pub cycle: Duration,
    /// How long to run, if limited.
    pub duration: Option<Duration>,
    /// The drives, in file order.
    pub drives: Vec<CanDriveConfig>,
    /// What the check found questionable but not wrong.
    pub warnings: Vec<String>,
    /// Clear faults latched before the run (a fault reset to each drive in Fault) instead of
    /// refusing to run.
    pub reset_faults: bool,
}

/// Whether the file is a CANopen run: a CANopen interface or a drive selected by node.
pub(super) fn is_canopen(f: &raw::File) -> bool {
    let i = f.interface.get_ref();
    i == "can-sim"
        || i.starts_with("vbus:")
        || f.drive
            .iter()
            .any(|d| d.get_ref().node.is_some() || d.get_ref().eds.is_some())
}

/// **\[REC\]** The SYNC period of a CANopen run unless the file gives one: 4 ms, which every
/// drive of the project takes (the ASDA-A2 needs RPDOs at least 1 ms apart).
pub const DEFAULT_CYCLE: Duration = Duration::from_millis(4);

pub(super) fn parse(cx: &Ctx<'_>, f: &raw::File) -> Result<CanRunConfig, ConfigError> {
    let iface = f.interface.get_ref().as_str();
    let target = match iface {
        "" => return Err(cx.err(f.interface.span(), "interface", "is empty")),
        "can-sim" => CanTarget::Sim,
        "sim" | "virtual" => {
            return Err(cx.err(
                f.interface.span(),
                "interface",
                format!(
                    "{iface:?} is not a CANopen bus: a CANopen run takes \"can-sim\" (the \
                     emulated drives in-process), \"vbus:PATH\" or a SocketCAN interface"
                ),
            ));
        }
        other => CanTarget::Bus(other.parse().map_err(
            |e: crate::app::canopen::tools::BusSpecError| {
                cx.err(f.interface.span(), "interface", e.to_string())
            },
        )?),
    };
    ethercat_only(cx, f)?;
    let cycle = match &f.cycle {
        Some(c) => parse_duration(c.get_ref()).map_err(|m| cx.err(c.span(), "cycle", m))?,
        None => DEFAULT_CYCLE,
    };
    if cycle < Duration::from_micros(250) || cycle > Duration::from_secs(1) {
        let span = f.cycle.as_ref().map_or(f.interface.span(), Spanned::span);
        return Err(cx.err(span, "cycle", "a SYNC period is between 250 us and 1 s"));
    }
    let duration = match &f.duration {
        Some(d) => Some(parse_duration(d.get_ref()).map_err(|m| cx.err(d.span(), "duration", m))?),
        None => None,
    };
    let mut drives: Vec<CanDriveConfig> = Vec::with_capacity(f.drive.len());
    let mut warnings = Vec::new();
    for (i, d) in f.drive.iter().enumerate() {
        let dc = drive(cx, i, d, cycle, &f.cycle, &mut warnings)?;
        if let Some(j) = drives.iter().position(|o| o.node == dc.node) {
            return Err(cx.err(
                d.span(),
                format!("drive[{i}].node"),
                format!("node {} is drive[{j}] too", dc.node),
            ));
        }
        drives.push(dc);
    }
    if drives.is_empty() {
        return Err(cx.err(
            f.interface.span(),
            "drive",
            "a CANopen run needs at least one [[drive]] with its node",
        ));
    }
    Ok(CanRunConfig {
        source: cx.file.to_string(),
        target,
        cycle,
        duration,
        drives,
        warnings,
        reset_faults: f.reset_faults,
    })
}

/// The file-level keys only an EtherCAT run has.
fn ethercat_only(cx: &Ctx<'_>, f: &raw::File) -> Result<(), ConfigError> {
    let at = f.interface.span();
    let refuse = |key: &str, what: &str| {
        Err(cx.err(
            at.clone(),
            key,
            format!("{what} is for EtherCAT runs; this file is a CANopen run (interface or a drive's node)"),
        ))
    };
    if let Some(s) = &f.sim {
        return Err(cx.err(
            s.span(),
            "sim",
            "[sim] lists emulated EtherCAT devices; a CANopen run emulates its drives with \
             interface = \"can-sim\", one per [[drive]] at its node",
        ));
    }
    for (key, s) in [
        ("dc_shift", &f.dc_shift),
        ("dc_start_delay", &f.dc_start_delay),
    ] {
        if let Some(s) = s {
            return Err(cx.err(
                s.span(),
                key,
                "distributed clocks are EtherCAT's; a CANopen run is paced by SYNC",
            ));
        }
    }
    if f.rt.is_some() {
        return refuse("rt", "[rt]");
    }
    if f.supervision.is_some() {
        return refuse("supervision", "[supervision]");
    }
    if f.allow_generic {
        return refuse("allow_generic", "allow_generic");
    }
    Ok(())
}

/// One `[[drive]]` of a CANopen run.
fn drive(
    cx: &Ctx<'_>,
    i: usize,
    d: &Spanned<raw::Drive>,
    cycle: Duration,
    cycle_key: &Option<Spanned<String>>,
    warnings: &mut Vec<String>,
) -> Result<CanDriveConfig, ConfigError> {
    let key = |k: &str| {
        if k.is_empty() {
            format!("drive[{i}]")
        } else {
            format!("drive[{i}].{k}")
        }
    };
    let r = d.get_ref();
    no_ethercat_keys(cx, &key, r)?;
    let node = node_of(cx, &key, d)?;
    let builtin = builtin_of(cx, &key, r)?;
    let (name, profile, emulation, eds) =
        drive_model(cx, &key, d.span(), builtin, r.eds.as_ref(), warnings)?;
    check_cycle(cx, &key, d, profile, cycle, cycle_key)?;
    let mode = start_mode(cx, &key, r)?;
    let Program {
        units,
        fe_limit,
        limits,
        steps,
        described,
        ..
    } = program_of(cx, &key, d, mode, cycle)?;
    runs_here(cx, &key, d, profile, mode, &steps, (cycle, cycle_key))?;
    let settings = settings_of(cx, &key, d, i, profile, mode, &steps, warnings)?;
    Ok(CanDriveConfig {
        node,
        key: name,
        profile,
        eds,
        emulation,
        mode,
        units,
        steps,
        described,
        settings,
        following_error_limit: fe_limit,
        limits,
    })
}

/// What only the EtherCAT bus has, named at its key.
fn no_ethercat_keys(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    r: &raw::Drive,
) -> Result<(), ConfigError> {
    for (given, name) in [
        (r.position.as_ref().map(Spanned::span), "position"),
        (r.alias.as_ref().map(Spanned::span), "alias"),
        (r.identity.as_ref().map(Spanned::span), "identity"),
        (r.esi.as_ref().map(Spanned::span), "esi"),
        (r.profile_file.as_ref().map(Spanned::span), "profile_file"),
        (r.mapping.as_ref().map(Spanned::span), "mapping"),
    ] {
        if let Some(span) = given {
            return Err(cx.err(
                span,
                key(name),
                format!(
                    "`{name}` is an EtherCAT key; a CANopen drive is selected by `node` and \
                     its PDOs are planned from its profile"
                ),
            ));
        }
    }
    Ok(())
}

/// The drive's node-ID (`node`, 1–127).
fn node_of(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    d: &Spanned<raw::Drive>,
) -> Result<u8, ConfigError> {
    match &d.get_ref().node {
        Some(n) if (1..=127).contains(n.get_ref()) => Ok(*n.get_ref()),
        Some(n) => Err(cx.err(
            n.span(),
            key("node"),
            format!("a node-ID is 1–127, not {}", n.get_ref()),
        )),
        None => Err(cx.err(d.span(), key(""), "say which node: give `node` (1–127)")),
    }
}

/// The built-in profile `profile` names, if it names one: its name and profile.
fn builtin_of(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    r: &raw::Drive,
) -> Result<Option<(&'static str, &'static CanDriveProfile)>, ConfigError> {
    let Some(p) = &r.profile else {
        return Ok(None);
    };
    match EMULATED_NODES.iter().find(|(n, _, _)| *n == p.get_ref()) {
        Some(&(name, profile, _)) => Ok(Some((name, profile))),
        None => Err(cx.err(
            p.span(),
            key("profile"),
            format!(
                "{:?} is not a CANopen drive profile: {}, or give the drive's EDS file                          (eds = \"FILE\")",
                p.get_ref(),
                profile_names()
            ),
        )),
    }
}

/// The mode the drive starts in (`mode`, pp by default): a cyclic one only as ip.
fn start_mode(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    r: &raw::Drive,
) -> Result<RunMode, ConfigError> {
    let Some(m) = &r.mode else {
        return Ok(RunMode::Pp);
    };
    let mode: RunMode = m
        .get_ref()
        .parse()
        .map_err(|e: String| cx.err(m.span(), key("mode"), e))?;
    if mode.is_cyclic() && mode != RunMode::Ip {
        return Err(cx.err(
            m.span(),
            key("mode"),
            format!(
                "{} is not run over CANopen yet: pp, pv, tq, or ip where the drive has it",
                mode.name()
            ),
        ));
    }
    Ok(mode)
}

/// The program and the start mode on this drive: each step one it runs
/// ([`unsupported_step`]), its touch probes in the PDO plan, ip at this SYNC period, and the
/// start mode one the drive supports and can command.
fn runs_here(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    d: &Spanned<raw::Drive>,
    profile: &'static CanDriveProfile,
    mode: RunMode,
    steps: &[Step],
    (cycle, cycle_key): (Duration, &Option<Spanned<String>>),
) -> Result<(), ConfigError> {
    let r = d.get_ref();
    for (n, s) in steps.iter().enumerate() {
        if let Some(m) = unsupported_step(profile, s) {
            let span = r.program.get(n).map_or(d.span(), Spanned::span);
            return Err(cx.err(span, key(&format!("program[{n}]")), m));
        }
    }
    let probes = crate::master::program::probes_used(steps);
    if let Err(why) = crate::canopen::PdoPlan::with_probes(profile, &probes) {
        return Err(cx.err(d.span(), key("program"), why));
    }
    let uses_ip = mode == RunMode::Ip
        || steps
            .iter()
            .any(|s| matches!(s, Step::Mode { mode } if *mode == RunMode::Ip));
    if uses_ip && let Err(why) = ip_period(profile, cycle) {
        let (span, k) = match cycle_key {
            Some(c) => (c.span(), "cycle".to_string()),
            None => (d.span(), key("")),
        };
        return Err(cx.err(span, k, why));
    }
    let span = r.mode.as_ref().map_or(d.span(), Spanned::span);
    if !profile.supports(mode.operation_mode()) {
        return Err(cx.err(
            span,
            key("mode"),
            format!(
                "the {} does not support {} ({})",
                profile.name,
                mode.name(),
                modes_offered(profile)
            ),
        ));
    }
    if let Some(why) = missing_setpoint(profile, mode) {
        return Err(cx.err(span, key("mode"), why));
    }
    Ok(())
}

/// Why the drive cannot run step `s`: a cyclic mode other than ip, a mode it does not have or
/// cannot command, a homing method it does not take, a touch probe it does not have.
fn unsupported_step(profile: &CanDriveProfile, s: &Step) -> Option<String> {
    match s {
        Step::Mode { mode } if mode.is_cyclic() && *mode != RunMode::Ip => {
            Some(format!("{} is not run over CANopen yet", mode.name()))
        }
        Step::Mode { mode } if !profile.supports(mode.operation_mode()) => Some(format!(
            "the {} does not support {} ({})",
            profile.name,
            mode.name(),
            modes_offered(profile)
        )),
        Step::Home { method, .. } if *method == 0 || !profile.homing.supports(*method) => {
            let listed: Vec<String> = profile
                .homing
                .methods
                .iter()
                .filter(|m| **m != 0)
                .map(i8::to_string)
                .collect();
            Some(format!(
                "homing method {method} is not one the {} takes ({})",
                profile.name,
                listed.join(", ")
            ))
        }
        // Methods 1–14, 33 and 34 home on the index pulse (CiA 402).
        Step::Home { method, .. }
            if !profile.homing.index_pulse && matches!(method, 1..=14 | 33 | 34) =>
        {
            Some(format!(
                "homing method {method} homes on the index pulse, which the {} (without \
                 encoder) does not have",
                profile.name
            ))
        }
        Step::Mode { mode } => missing_setpoint(profile, *mode),
        Step::TouchProbe { .. } | Step::ProbeWait { .. }
            if crate::od::Dictionary::new(profile.dictionary)
                .object(0x60B8)
                .is_none() =>
        {
            Some(format!("the {} has no touch probe (60B8h)", profile.name))
        }
        _ => None,
    }
}

/// The drive's start-up writes: the home, pp, pv and tq steps' objects (those the drive has;
/// the others said, not written), the halt option where the program moves in pp or pv, then
/// `sdos`.
#[allow(clippy::too_many_arguments)]
fn settings_of(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    d: &Spanned<raw::Drive>,
    i: usize,
    profile: &'static CanDriveProfile,
    mode: RunMode,
    steps: &[Step],
    warnings: &mut Vec<String>,
) -> Result<Vec<(ObjectAddress, Value)>, ConfigError> {
    let r = d.get_ref();
    let step_err = |n: usize, m: String| {
        let span = r.program.get(n).map_or(d.span(), Spanned::span);
        cx.err(span, key(&format!("program[{n}]")), m)
    };
    let homing = homing_writes(steps, Some(profile)).map_err(|(n, m)| step_err(n, m))?;
    let objects = profile_writes(steps, Some(profile)).map_err(|(n, m)| step_err(n, m))?;
    let steps_write: Vec<ObjectAddress> = homing.iter().chain(&objects).map(|(a, _)| *a).collect();
    let dict = Some((profile.dictionary, profile.name));
    let sdos = start_up_values(cx, key, d, dict, &steps_write)?;
    // A step's object the drive does not have (the Lexium MDrive has no homing acceleration
    // 0x609A): the drive uses its own value; said, not written.
    let dict = crate::od::Dictionary::new(profile.dictionary);
    let mut settings = Vec::new();
    for (a, v) in homing.into_iter().chain(objects) {
        if dict.entry(a).is_some() {
            settings.push((a, v));
        } else {
            warnings.push(format!(
                "drive[{i}]: the {} has no {a}: the program's value for it is not written, the \
                 drive uses its own",
                profile.name
            ));
        }
    }
    // A controlled stop in pp or pv is a halt (controlword bit 8): where 605Dh can say so, the
    // drive halts on the slow-down ramp (6084h, the deceleration the file's steps set) rather
    // than on its quick-stop ramp (the Lexium MDrive's default 605Dh = 2 halts on 6085h, 200 000
    // steps/s²: a pp move at 10 rev/s then overshot its target by two revolutions). A `sdos`
    // value of the file's own comes after and wins.
    let halt = ObjectAddress::new(0x605D, 0);
    let profile_moves = matches!(mode, RunMode::Pp | RunMode::Pv)
        || steps.iter().any(|s| {
            matches!(s, Step::Pp { .. } | Step::Pv { .. })
                || matches!(s, Step::Mode { mode } if matches!(mode, RunMode::Pp | RunMode::Pv))
        });
    if profile_moves
        && let Some(e) = dict.entry(halt)
        && e.min.as_i128().is_none_or(|lo| lo <= 1)
        && e.max.as_i128().is_none_or(|hi| hi >= 1)
    {
        settings.push((halt, Value::Int(1)));
    }
    settings.extend(sdos);
    Ok(settings)
}

/// Why `mode` cannot run on the drive: its set-point object (607Ah, 60FFh, 6071h, 60C1h:01)
/// is not in the dictionary, or not writable — a drive whose EDS file declares the mode in
/// 6502h but has no object to command it (a Schunk PRL120 file without 60FFh).
fn missing_setpoint(p: &CanDriveProfile, mode: RunMode) -> Option<String> {
    let (index, sub, what) = match mode {
        RunMode::Pp => (0x607A, 0, "target position"),
        RunMode::Pv => (0x60FF, 0, "target velocity"),
        RunMode::Tq => (0x6071, 0, "target torque"),
        RunMode::Ip => (0x60C1, 1, "interpolation data record"),
        _ => return None,
    };
    let addr = ObjectAddress::new(index, sub);
    match crate::od::Dictionary::new(p.dictionary).entry(addr) {
        Some(e) if e.access.writable() => None,
        Some(_) => Some(format!(
            "{} needs {addr} ({what}) written, which the {} makes read-only",
            mode.name(),
            p.name
        )),
        None => Some(format!(
            "the {} has no {addr} ({what}): {} cannot be commanded on it",
            p.name,
            mode.name()
        )),
    }
}

/// `s` as one shell word, quoted when it holds a space or a quote (a command the user copies).
fn shell_word(s: &str) -> String {
    if s.chars()
        .all(|c| c.is_ascii_alphanumeric() || "/._-+:@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// The modes a drive offers, for a refusal: "its 6502h declares vl, hm, ip".
fn modes_offered(p: &CanDriveProfile) -> String {
    let names: Vec<&str> = p
        .caps
        .supported_modes
        .iter()
        .map(crate::cia402::OperationMode::short_name)
        .collect();
    format!("its 6502h declares {}", names.join(", "))
}

/// The drive's model: a built-in profile, one built from its EDS file, or a built-in profile
/// refined by its vendor's file; with what `can-sim` emulates for it (the software slave's own
/// table, or a node from the same file). Returns the name, the profile, the emulation and the
/// file as shown.
fn drive_model(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    span: std::ops::Range<usize>,
    builtin: Option<(&'static str, &'static CanDriveProfile)>,
    eds: Option<&Spanned<String>>,
    warnings: &mut Vec<String>,
) -> Result<
    (
        &'static str,
        &'static CanDriveProfile,
        &'static Emulation,
        Option<String>,
    ),
    ConfigError,
> {
    let table = |name: &str| {
        crate::sim::canopen::drives::by_name(name).ok_or_else(|| {
            cx.err(
                span.clone(),
                key("profile"),
                format!("the software slave has no emulation named {name:?}"),
            )
        })
    };
    let Some(e) = eds else {
        let Some((name, profile)) = builtin else {
            return Err(cx.err(
                span,
                key(""),
                format!(
                    "name the drive's profile ({}) or its EDS file (eds = \"FILE\")",
                    profile_names()
                ),
            ));
        };
        return Ok((name, profile, table(name)?, None));
    };
    let dir = std::path::Path::new(cx.file)
        .parent()
        .unwrap_or(std::path::Path::new(""));
    let path = dir.join(e.get_ref());
    let shown = path.display().to_string();
    let file = crate::app::canopen::tools::read_eds(&shown)
        .map_err(|why| cx.err(e.span(), key("eds"), why))?;
    if !file.warnings.is_empty() {
        warnings.push(format!(
            "{}: the EDS file {shown} has {} oddities the reader took in its own way (`ecdrive \
             eds show {}` lists them)",
            key("eds"),
            file.warnings.len(),
            shell_word(&shown)
        ));
    }
    match builtin {
        Some((name, base)) => {
            let profile = crate::drives::eds_can::refine(base, &file, &shown);
            let emulation = Emulation::refined(table(name)?, &file, &shown);
            Ok((name, profile, emulation, Some(shown)))
        }
        None => {
            if file.supported_modes().is_none() {
                warnings.push(format!(
                    "{}: the EDS file {shown} declares no modes (6502h): pp, pv and hm assumed",
                    key("eds")
                ));
            }
            let profile = crate::drives::eds_can::from_eds(&file, &shown)
                .map_err(|why| cx.err(e.span(), key("eds"), why.reason))?;
            let emulation = Emulation::from_eds(&file, &shown)
                .map_err(|why| cx.err(e.span(), key("eds"), why))?;
            Ok((profile.name, profile, emulation, Some(shown)))
        }
    }
}

/// The SYNC period against what the drive takes: RPDOs no closer than its minimum gap, and a
/// whole multiple of its cycle-period granularity (0x1006).
fn check_cycle(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    d: &Spanned<raw::Drive>,
    p: &CanDriveProfile,
    cycle: Duration,
    cycle_key: &Option<Spanned<String>>,
) -> Result<(), ConfigError> {
    let us = u64::try_from(cycle.as_micros()).unwrap_or(u64::MAX);
    let c = &p.comm;
    let why = if us < u64::from(c.rpdo_min_interval_us) {
        Some(format!(
            "the {} takes RPDOs at least {} µs apart",
            p.name, c.rpdo_min_interval_us
        ))
    } else if c.cycle_period_granularity_us > 0
        && us % u64::from(c.cycle_period_granularity_us) != 0
    {
        Some(format!(
            "the {}'s cycle period (0x1006) is a multiple of {} µs",
            p.name, c.cycle_period_granularity_us
        ))
    } else {
        None
    };
    match why {
        Some(w) => {
            let (span, k) = match cycle_key {
                Some(c) => (c.span(), "cycle".to_string()),
                None => (d.span(), key("")),
            };
            Err(cx.err(span, k, format!("a SYNC period of {us} µs: {w}")))
        }
        None => Ok(()),
    }
}

/// Whether the drive interpolates at this SYNC period: the master writes the period into
/// 60C2h:01 in milliseconds (60C2h:02 = −3), so it must be whole milliseconds within the
/// range the drive's dictionary gives 60C2h:01 (the ASDA-A2: 1–20 ms).
fn ip_period(p: &CanDriveProfile, cycle: Duration) -> Result<(), String> {
    let dict = crate::od::Dictionary::new(p.dictionary);
    let Some(e) = dict.entry(crate::od::ObjectAddress::new(0x60C2, 1)) else {
        return Ok(());
    };
    let ms = |v: crate::od::ConstValue| v.as_i128();
    let (lo, hi) = (ms(e.min).unwrap_or(1), ms(e.max).unwrap_or(255));
    let us = cycle.as_micros();
    let whole = us % 1000 == 0;
    let n = (us / 1000) as i128;
    if whole && (lo..=hi).contains(&n) {
        return Ok(());
    }
    Err(format!(
        "a SYNC period of {us} µs: ip on the {} interpolates at 60C2h:01 milliseconds, \
         {lo}–{hi} ms, so the period must be whole milliseconds in that range",
        p.name
    ))
}

fn profile_names() -> String {
    let names: Vec<&str> = EMULATED_NODES.iter().map(|(n, _, _)| *n).collect();
    format!("profile = one of {}", names.join(", "))
}
