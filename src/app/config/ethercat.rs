//! An EtherCAT run file: the segment (a network interface, or `"sim"` and the emulated devices
//! of `[sim]`), the cycle and its real-time and supervision settings, and each `[[drive]]`
//! selected by position, alias or identity, with the profile its entry names or its ESI file
//! describes, the mapping its program's modes need and its start-up values.

use super::start_up_values;
use super::steps::{Program, homing_writes, profile_writes, program_of, rated};
use super::{ConfigError, Ctx, DriveConfig, RunConfig, parse_duration, profile_file, raw};
use crate::app::ethercat::tools::{SimSettings, Target};
use crate::drives::DriveProfile;
use crate::master::program::{self, RunMode, Step};
use crate::master::session::MasterConfig;
use crate::master::startup::{DriveSetup, Selector};
use crate::od::{Dictionary, ObjectAddress};
use crate::pdo::{Direction, Mapping, Pdo, PdoEntry};
use std::path::Path;
use std::time::Duration;
use toml::Spanned;

/// An EtherCAT run file, read in the order a reader would check it: where the segment is, the
/// cycle and its settings, then each drive entry, then what the entries must agree on.
pub(super) fn parse_ethercat(cx: &Ctx<'_>, f: raw::File) -> Result<RunConfig, ConfigError> {
    let cx = *cx;
    let (target, sim_names) = segment(&cx, &f)?;
    let cycle = match &f.cycle {
        Some(c) => {
            let d = duration_at(&cx, c, "cycle")?;
            if d < Duration::from_micros(50) || d > Duration::from_secs(1) {
                return Err(cx.err(c.span(), "cycle", "must be between 50 us and 1 s"));
            }
            d
        }
        None => Duration::from_millis(1),
    };
    let mut master = MasterConfig::new(cycle);
    if let Some(s) = &f.dc_shift {
        let d = duration_at(&cx, s, "dc_shift")?;
        if d >= cycle {
            return Err(cx.err(s.span(), "dc_shift", "must be shorter than the cycle"));
        }
        master.startup.dc.shift = Some(d);
    }
    if let Some(s) = &f.dc_start_delay {
        let d = duration_at(&cx, s, "dc_start_delay")?;
        if d > Duration::from_secs(10) {
            return Err(cx.err(s.span(), "dc_start_delay", "must be at most 10 s"));
        }
        master.startup.dc.start_delay = Some(d);
    }
    let duration = f
        .duration
        .as_ref()
        .map(|d| duration_at(&cx, d, "duration"))
        .transpose()?;
    if let Some(rt) = &f.rt {
        rt_settings(&cx, rt, &mut master.cycle.rt)?;
        if let Some(r) = &rt.reply {
            master.cycle.reply_wait = match r.get_ref().as_str() {
                "next-wake" => crate::master::ReplyWait::NextWake,
                "in-cycle" => crate::master::ReplyWait::InCycle,
                other => {
                    return Err(cx.err(
                        r.span(),
                        "rt.reply",
                        format!("{other:?} is not a reply wait: \"next-wake\" or \"in-cycle\""),
                    ));
                }
            };
        }
        if let Some(f) = &rt.frames {
            master.cycle.own_frames = match f.get_ref().as_str() {
                "ecdrive" => true,
                "ethercrab" => false,
                other => {
                    return Err(cx.err(
                        f.span(),
                        "rt.frames",
                        format!(
                            "{other:?} is not whose frames carry the image: \"ecdrive\" or \"ethercrab\""
                        ),
                    ));
                }
            };
        }
    }
    if let Some(a) = f.answer_rereads {
        master.bus.answer_rereads = a;
    }
    if let Some(sv) = &f.supervision {
        supervision(&cx, sv, &mut master.cycle)?;
    }
    master.startup.allow_generic = f.allow_generic;

    let mut said = Said::default();
    let drives = drive_entries(&cx, &f, sim_names.as_deref(), cycle, &mut master, &mut said)?;
    match &sim_names {
        Some(names) => {
            identities_have_their_devices(&cx, &f, names, &master.startup.drives)?;
            unlisted_devices_take_the_cycle(&cx, &f, names, &drives, cycle)?;
        }
        None => said.unchecked.push(
            "devices without a [[drive]] table: what they are is known only from the bus; \
             start-up checks them"
                .to_string(),
        ),
    }
    Ok(RunConfig {
        source: cx.file.to_string(),
        target,
        sim: sim_settings(&f),
        master,
        duration,
        drives,
        reset_faults: f.reset_faults,
        warnings: said.warnings,
        unchecked: said.unchecked,
        notes: said.notes,
    })
}

/// What the check says besides an error: warnings, what it could not check, and what it
/// decided ([`RunConfig::warnings`], [`RunConfig::unchecked`], [`RunConfig::notes`]).
#[derive(Default)]
struct Said {
    warnings: Vec<String>,
    unchecked: Vec<String>,
    notes: Vec<String>,
}

/// A duration of the file (`"1ms"`), or an error at its key.
fn duration_at(cx: &Ctx<'_>, s: &Spanned<String>, key: &str) -> Result<Duration, ConfigError> {
    parse_duration(s.get_ref()).map_err(|m| cx.err(s.span(), key, m))
}

/// Where the segment is: a network interface, or `"sim"` and the emulated devices of `[sim]`
/// (their names, each built once here so that what only building finds is named at its line).
fn segment(cx: &Ctx<'_>, f: &raw::File) -> Result<(Target, Option<Vec<String>>), ConfigError> {
    let interface = |message: String| Err(cx.err(f.interface.span(), "interface", message));
    match (f.interface.get_ref().as_str(), &f.sim) {
        ("sim", Some(sim)) => {
            let names = sim_devices(cx, sim)?;
            Ok((Target::Sim(names.clone()), Some(names)))
        }
        ("sim", None) => {
            interface("interface = \"sim\" needs a [sim] table listing the emulated devices".into())
        }
        ("", _) => interface("is empty".into()),
        (name, _) if name.starts_with("sim:") => {
            let list: Vec<String> = name["sim:".len()..]
                .split(',')
                .map(|d| format!("{:?}", d.trim()))
                .collect();
            interface(format!(
                "{name:?} is the command line's way to name emulated devices; in a \
                 configuration file write interface = \"sim\" and [sim] devices = [{}]",
                list.join(", ")
            ))
        }
        (name, Some(sim)) => Err(cx.err(
            sim.span(),
            "sim",
            format!("a [sim] table only goes with interface = \"sim\", not {name:?}"),
        )),
        (name, None) if name.starts_with("vbus:") || name == "virtual" => interface(format!(
            "{name:?} is a CANopen bus (the commands take it with --can); an EtherCAT run needs a \
             network interface or \"sim\""
        )),
        (name, None) => Ok((Target::Interface(name.to_string()), None)),
    }
}

/// The emulated devices `[sim]` lists, each checked and built once.
fn sim_devices(cx: &Ctx<'_>, sim: &Spanned<raw::Sim>) -> Result<Vec<String>, ConfigError> {
    let s = sim.get_ref();
    if s.devices.is_empty() {
        return Err(cx.err(sim.span(), "sim.devices", "name at least one device"));
    }
    let mut names: Vec<String> = Vec::with_capacity(s.devices.len());
    for (i, d) in s.devices.iter().enumerate() {
        if let Err(e) = crate::sim::devices::check_name(d.get_ref()) {
            return Err(cx.err(d.span(), format!("sim.devices[{i}]"), e.to_string()));
        }
        let name = sim_esi_name(cx, d, &format!("sim.devices[{i}]"))?;
        // Built once here, so what only building finds (a quirk the device cannot
        // have, a stored parameter it does not take) is named at its line too.
        if let Err(e) = crate::sim::devices::by_name(&name, i) {
            return Err(cx.err(d.span(), format!("sim.devices[{i}]"), e.to_string()));
        }
        names.push(name);
    }
    Ok(names)
}

/// How the emulated devices are built (`[sim]`'s watchdog and loss detection).
fn sim_settings(f: &raw::File) -> SimSettings {
    let mut sim = SimSettings::default();
    if let Some(s) = &f.sim {
        if let Some(wd) = s.get_ref().sm_watchdog {
            sim.esc.sm_watchdog = wd;
        }
        if let Some(on) = s.get_ref().loss_detection {
            sim.loss_detection = on;
        }
    }
    sim
}

/// `[rt]`: the cycle thread's priority and CPU (one this machine has), and memory locking.
fn rt_settings(
    cx: &Ctx<'_>,
    rt: &raw::Rt,
    out: &mut crate::rt::RtSettings,
) -> Result<(), ConfigError> {
    if let Some(p) = &rt.priority
        && !(1..=99).contains(p.get_ref())
    {
        return Err(cx.err(p.span(), "rt.priority", "SCHED_FIFO priorities are 1–99"));
    }
    out.priority = rt.priority.as_ref().map(|p| *p.get_ref());
    if let Some(cpu) = &rt.cpu
        && let Some(online) = online_cpus()
        && !online.contains(cpu.get_ref())
    {
        return Err(cx.err(
            cpu.span(),
            "rt.cpu",
            format!(
                "CPU {} does not exist on this machine (online CPUs: {})",
                cpu.get_ref(),
                online
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    out.cpu = rt.cpu.as_ref().map(|c| *c.get_ref());
    out.lock_memory = rt.lock_memory;
    Ok(())
}

/// `[supervision]`: how many lost cycles and wrong working counters the cycle bears, the
/// SAFE-OP cycles before OP, and how long OP may take.
fn supervision(
    cx: &Ctx<'_>,
    sv: &raw::Supervision,
    out: &mut crate::master::CycleSettings,
) -> Result<(), ConfigError> {
    for (key, v, slot) in [
        (
            "supervision.lost_cycles",
            &sv.lost_cycles,
            &mut out.segment_lost_after,
        ),
        (
            "supervision.lost_before_stop",
            &sv.lost_before_stop,
            &mut out.lost_before_stop,
        ),
        (
            "supervision.wkc_errors",
            &sv.wkc_errors,
            &mut out.wkc_errors_before_stop,
        ),
        (
            "supervision.safeop_cycles",
            &sv.safeop_cycles,
            &mut out.safeop_cycles,
        ),
    ] {
        if let Some(v) = v {
            if *v.get_ref() == 0 {
                return Err(cx.err(v.span(), key, "must be at least 1"));
            }
            *slot = *v.get_ref();
        }
    }
    if let Some(t) = &sv.op_timeout {
        out.op_timeout = duration_at(cx, t, "supervision.op_timeout")?;
    }
    Ok(())
}

/// Each `[[drive]]` entry, checked ([`drive`]), its start-up setup added to `master`; no two
/// select the same device.
fn drive_entries(
    cx: &Ctx<'_>,
    f: &raw::File,
    sim_names: Option<&[String]>,
    cycle: Duration,
    master: &mut MasterConfig,
    said: &mut Said,
) -> Result<Vec<DriveConfig>, ConfigError> {
    let mut drives = Vec::with_capacity(f.drive.len());
    for (i, d) in f.drive.iter().enumerate() {
        let (setup, dc) = drive(
            cx,
            i,
            d,
            sim_names,
            cycle,
            &f.cycle,
            (&mut said.warnings, &mut said.notes),
        )?;
        if dc.profile.is_none() {
            said.unchecked.push(format!(
                "drive[{i}] ({}): its profile is not known from the file (name a profile, select \
                 by identity, or list the device in [sim]): its mode, cycle time, mapping sizes \
                 and start-up values are checked at start-up",
                match setup.select {
                    Selector::Position(p) => format!("position {p}"),
                    Selector::Alias(a) => format!("alias {a}"),
                    Selector::Identity { .. } => "by identity".into(),
                }
            ));
        }
        // The same device twice: the same selector, or (on an emulated segment the file lists)
        // an identity whose every device another entry names by position.
        if let Some(j) = master.startup.drives.iter().position(|s: &DriveSetup| {
            s.select == setup.select && !matches!(s.select, Selector::Identity { .. })
        }) {
            return Err(cx.err(
                d.span(),
                format!("drive[{i}]"),
                format!("selects the same device as drive[{j}]"),
            ));
        }
        if let Some((p, j)) = identity_taken(setup.select, sim_names, &f.drive) {
            return Err(cx.err(
                d.span(),
                format!("drive[{i}]"),
                format!(
                    "selects the same device as drive[{j}] (device {p} of [sim], the only one \
                     with its identity): one entry per device"
                ),
            ));
        }
        master.startup.drives.push(setup);
        drives.push(dc);
    }
    Ok(drives)
}

/// No identity that more listed devices have than entries select by it (start-up refuses it
/// too, from the identities it reads).
fn identities_have_their_devices(
    cx: &Ctx<'_>,
    f: &raw::File,
    names: &[String],
    setups: &[DriveSetup],
) -> Result<(), ConfigError> {
    for (i, s) in setups.iter().enumerate() {
        let Selector::Identity { .. } = s.select else {
            continue;
        };
        let entries = setups.iter().filter(|o| o.select == s.select).count();
        let matching: Vec<usize> = (0..names.len())
            .filter(|&p| {
                let p16 = u16::try_from(p).unwrap_or(u16::MAX);
                sim_identity_is(&names[p], s.select)
                    && !setups.iter().any(|o| o.select == Selector::Position(p16))
            })
            .collect();
        if matching.len() > entries
            && let Some(d) = f.drive.get(i)
        {
            return Err(cx.err(
                d.span(),
                format!("drive[{i}]"),
                format!(
                    "its identity matches {} devices of [sim] ({}): select each by position \
                     (entries by identity take the matching devices in line order, one each)",
                    matching.len(),
                    matching
                        .iter()
                        .map(|p| format!("{p} {}", names[*p]))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// The emulated devices the file has no [[drive]] table for run their profile's defaults: the
/// cycle time must suit them too.
fn unlisted_devices_take_the_cycle(
    cx: &Ctx<'_>,
    f: &raw::File,
    names: &[String],
    drives: &[DriveConfig],
    cycle: Duration,
) -> Result<(), ConfigError> {
    for (pos, name) in names.iter().enumerate() {
        let pos16 = u16::try_from(pos).unwrap_or(u16::MAX);
        if drives.iter().any(|d| d.select == Selector::Position(pos16)) {
            continue;
        }
        let Some(p) = crate::sim::quirks::split_name(name)
            .ok()
            .and_then(|(n, _)| crate::drives::by_key(n))
        else {
            continue;
        };
        let ns = u32::try_from(cycle.as_nanos()).unwrap_or(u32::MAX);
        if !p.sync.cycle_times.contains(ns) {
            let span = f
                .cycle
                .as_ref()
                .map_or_else(|| f.interface.span(), Spanned::span);
            return Err(cx.err(
                span,
                if f.cycle.is_some() {
                    "cycle"
                } else {
                    "interface"
                },
                format!(
                    "{} µs is not a cycle time the {} (emulated device {pos}, run with its \
                     defaults) accepts ({})",
                    cycle.as_micros(),
                    p.name,
                    p.sync.cycle_times.describe()
                ),
            ));
        }
    }
    Ok(())
}

/// The CPUs online on this machine (`/sys/devices/system/cpu/online`, e.g. `0-3,6`), isolated
/// ones included (an RT cycle is usually pinned to an isolated CPU); `None` when it cannot be
/// read (then the CPU is not checked).
fn online_cpus() -> Option<Vec<usize>> {
    let text = std::fs::read_to_string("/sys/devices/system/cpu/online").ok()?;
    let mut out = Vec::new();
    for part in text.trim().split(',').filter(|p| !p.is_empty()) {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b): (usize, usize) = (a.parse().ok()?, b.parse().ok()?);
                out.extend(a..=b.min(a.saturating_add(4096)));
            }
            None => out.push(part.parse().ok()?),
        }
    }
    Some(out)
}

/// The device of `esi = "FILE"` (relative to the configuration file's folder): the one the
/// selector's identity names, or the file's only device. Every problem of the file is found
/// here, before the bus is touched: the ESI parser's line and column, a device the file does
/// not have. Returns the file, the device's index in it and the file's name as shown.
fn esi_device(
    cx: &Ctx<'_>,
    e: &Spanned<String>,
    select: Selector,
    choice: Option<&crate::esi::DeviceChoice>,
    key: &str,
) -> Result<(crate::esi::EsiFile, usize, String), ConfigError> {
    let dir = Path::new(cx.file).parent().unwrap_or(Path::new(""));
    let path = dir.join(e.get_ref());
    let shown = path.display().to_string();
    let f = crate::esi::EsiFile::from_path(&path)
        .map_err(|x| cx.err(e.span(), key, format!("ESI file {shown}: {x}")))?;
    if let Some(c) = choice {
        // `esi = { file, product, revision }`: that device, or why not; an identity selector
        // must agree with it.
        let i = f
            .choose(c)
            .map_err(|x| cx.err(e.span(), key, format!("ESI file {shown}: {x}")))?;
        if let (Selector::Identity { product_code, .. }, Some(d)) = (select, f.devices.get(i))
            && d.type_.product_code != product_code
        {
            return Err(cx.err(
                e.span(),
                key,
                format!(
                    "ESI file {shown}: the device chosen ({}) is not the product code \
                     0x{product_code:08X} the drive's identity names",
                    d.identity_text()
                ),
            ));
        }
        return Ok((f, i, shown));
    }
    let index = match select {
        Selector::Identity {
            vendor_id,
            product_code,
        } => {
            if f.vendor.id != vendor_id {
                return Err(cx.err(
                    e.span(),
                    key,
                    format!(
                        "ESI file {shown} is from vendor 0x{:08X}, the drive's identity says \
                         0x{vendor_id:08X}",
                        f.vendor.id
                    ),
                ));
            }
            let newest = f.device(product_code, None).map(|d| d.position);
            match f.devices.iter().position(|d| Some(d.position) == newest) {
                Some(i) => i,
                None => {
                    // A device of that identity the file has but that cannot be read says
                    // why; else there is none.
                    let choice = crate::esi::DeviceChoice::Identity {
                        product_code,
                        revision: None,
                    };
                    let why = match f.choose(&choice) {
                        Err(w) if w.contains("cannot be used") => w,
                        _ => format!("has no device with product code 0x{product_code:08X}"),
                    };
                    return Err(cx.err(e.span(), key, format!("ESI file {shown}: {why}")));
                }
            }
        }
        _ => match f.devices.len() {
            1 if f.unreadable.is_empty() => 0,
            0 | 1 if !f.unreadable.is_empty() => {
                let why = f
                    .choose(&crate::esi::DeviceChoice::Only)
                    .err()
                    .unwrap_or_default();
                return Err(cx.err(e.span(), key, format!("ESI file {shown}: {why}")));
            }
            n => {
                let list: Vec<String> = f
                    .devices
                    .iter()
                    .map(|d| format!("{} (0x{:08X})", d.type_.name_text, d.type_.product_code))
                    .collect();
                return Err(cx.err(
                    e.span(),
                    key,
                    format!(
                        "ESI file {shown} describes {n} devices ({}): select the drive by \
                         identity to say which",
                        list.join(", ")
                    ),
                ));
            }
        },
    };
    Ok((f, index, shown))
}

/// An emulated device from an ESI file (`esi:PATH[@0xPRODUCT[:0xREVISION]]`): its path taken
/// relative to the configuration file, as `[[drive]] esi` is (the same file then runs from any
/// working directory), and the file read now, so that a file that cannot serve is named here
/// rather than when the segment starts. Other names as written.
fn sim_esi_name(cx: &Ctx<'_>, d: &Spanned<String>, key: &str) -> Result<String, ConfigError> {
    let name = d.get_ref();
    let Some(rest) = name.strip_prefix("esi:") else {
        return Ok(name.clone());
    };
    let (path, sel) = match rest.rsplit_once('@') {
        Some((p, sel)) if sel.starts_with("0x") || sel.starts_with("0X") => (p, Some(sel)),
        _ => (rest, None),
    };
    let dir = Path::new(cx.file).parent().unwrap_or(Path::new(""));
    let full = dir.join(path);
    let f = crate::esi::EsiFile::from_path(&full)
        .map_err(|x| cx.err(d.span(), key, format!("ESI file {}: {x}", full.display())))?;
    let choice = sel.map_or(
        crate::esi::DeviceChoice::Only,
        crate::esi::DeviceChoice::parse,
    );
    if let Err(why) = f.choose(&choice) {
        let why = if choice == crate::esi::DeviceChoice::Only && f.devices.len() > 1 {
            format!(
                "the file describes {} devices ({}): say which with esi:FILE@0xPRODUCT[:0xREVISION]",
                f.devices.len(),
                f.device_list()
            )
        } else {
            why
        };
        return Err(cx.err(d.span(), key, format!("ESI file {}: {why}", full.display())));
    }
    Ok(match sel {
        Some(sel) => format!("esi:{}@{sel}", full.display()),
        None => format!("esi:{}", full.display()),
    })
}

/// `esi = "FILE"` on a file of several devices, the drive selected by position or alias: the
/// profile of every drive the file describes, for start-up to take the one whose identity the
/// device reports ([`crate::master::DriveSetup::esi_choices`]), with a note saying so. `None`
/// for a file of one device (the usual path chooses it).
fn esi_choices_for(
    cx: &Ctx<'_>,
    e: &Spanned<String>,
    select: Selector,
    key: &str,
    notes: &mut Vec<String>,
) -> Result<Option<Vec<&'static DriveProfile>>, ConfigError> {
    let dir = Path::new(cx.file).parent().unwrap_or(Path::new(""));
    let path = dir.join(e.get_ref());
    let shown = path.display().to_string();
    let f = crate::esi::EsiFile::from_path(&path)
        .map_err(|x| cx.err(e.span(), key, format!("ESI file {shown}: {x}")))?;
    if f.devices.len() < 2 {
        return Ok(None);
    }
    let mut profiles = Vec::new();
    let mut why = Vec::new();
    for d in &f.devices {
        match crate::drives::esi_profile::from_esi(&f, d, &shown) {
            Ok(p) => profiles.push(p),
            Err(x) => why.push(format!("{}: {}", d.identity_text(), x.reason)),
        }
    }
    if profiles.is_empty() {
        return Err(cx.err(
            e.span(),
            key,
            format!(
                "ESI file {shown} describes {} devices and none is a drive ecdrive can run: {}",
                f.devices.len(),
                why.join("; ")
            ),
        ));
    }
    notes.push(format!(
        "{key}: {shown} describes {} devices; start-up takes the one the device at {select} \
         reports ({})",
        f.devices.len(),
        profiles
            .iter()
            .map(|p| format!("{} 0x{:08X}", p.name, p.identity.product_code))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    Ok(Some(profiles))
}

/// The mapping for `modes` chosen from the drive's ESI file ([`crate::esi::mapping_for`]), with
/// a note saying which PDOs; a drive whose PDOs cannot carry the modes is refused here, naming
/// what is missing.
fn esi_mapping(
    cx: &Ctx<'_>,
    key: &str,
    e: &Spanned<String>,
    f: &crate::esi::EsiFile,
    dev: usize,
    modes: &[RunMode],
    notes: &mut Vec<String>,
) -> Result<Mapping, ConfigError> {
    let refs: Vec<crate::esi::CyclicModeRef> = crate::esi::CYCLIC_MODES
        .iter()
        .copied()
        .filter(|m| modes.iter().any(|x| x.code() == m.code))
        .collect();
    let d = f
        .devices
        .get(dev)
        .ok_or_else(|| cx.err(e.span(), key, "device index out of range"))?;
    let m = crate::esi::mapping_for(d, &refs);
    let names: Vec<&str> = refs.iter().map(|m| m.name).collect();
    let side = |r: &Result<crate::esi::DirectionChoice, String>| match r {
        Ok(c) => Ok(c
            .pdos
            .iter()
            .map(|p| format!("0x{p:04X}"))
            .collect::<Vec<_>>()
            .join("+")
            + match c.source {
                crate::esi::MappingSource::Default => " (the file's default)",
                crate::esi::MappingSource::Chosen => " (chosen from the file's PDOs)",
                crate::esi::MappingSource::Built => " (configured)",
            }),
        Err(why) => Err(why.clone()),
    };
    match (side(&m.rx), side(&m.tx), m.mapping) {
        (Ok(rx), Ok(tx), Some(mapping)) => {
            notes.push(format!(
                "{key}: {} from the ESI file: RxPDO {rx}, TxPDO {tx}",
                names.join("+")
            ));
            Ok(mapping)
        }
        (rx, tx, _) => {
            let why: Vec<String> = [rx.err(), tx.err()].into_iter().flatten().collect();
            Err(cx.err(
                e.span(),
                key,
                format!(
                    "the drive's PDOs cannot carry {}: {}",
                    names.join("+"),
                    why.join("; ")
                ),
            ))
        }
    }
}

/// For an entry selecting by identity on an emulated segment the file lists: when every listed
/// device with that identity is named by another entry's position, the first of them and that
/// entry's index (start-up would find the identity's device taken).
fn identity_taken(
    select: Selector,
    sim: Option<&[String]>,
    entries: &[Spanned<raw::Drive>],
) -> Option<(usize, usize)> {
    let names = sim?;
    let Selector::Identity { .. } = select else {
        return None;
    };
    let by_position = |p: usize| {
        entries.iter().position(|e| {
            e.get_ref()
                .position
                .as_ref()
                .is_some_and(|q| usize::from(*q.get_ref()) == p)
        })
    };
    let matching: Vec<usize> = (0..names.len())
        .filter(|&p| sim_identity_is(&names[p], select))
        .collect();
    let first = *matching.first()?;
    if matching.iter().all(|&p| by_position(p).is_some()) {
        by_position(first).map(|j| (first, j))
    } else {
        None
    }
}

/// Whether the emulated device `name` (a built-in drive) has the identity `select` names.
fn sim_identity_is(name: &str, select: Selector) -> bool {
    let Selector::Identity {
        vendor_id,
        product_code,
    } = select
    else {
        return false;
    };
    crate::sim::quirks::split_name(name)
        .ok()
        .and_then(|(n, _)| crate::drives::by_key(n))
        .is_some_and(|p| {
            p.bus.identity.vendor_id == vendor_id && p.bus.identity.product_code == product_code
        })
}

/// The built-in profile `p` names, or an error listing the known ones.
fn builtin_profile(
    cx: &Ctx<'_>,
    p: &Spanned<String>,
    key: &str,
) -> Result<&'static DriveProfile, ConfigError> {
    crate::drives::by_key(p.get_ref()).ok_or_else(|| {
        cx.err(
            p.span(),
            key,
            format!(
                "unknown drive profile {:?}; known: {}",
                p.get_ref(),
                profile_keys()
            ),
        )
    })
}

fn profile_keys() -> String {
    let mut keys: Vec<&str> = crate::drives::all().iter().map(|p| p.key).collect();
    if let Some(g) = crate::drives::by_key("generic-cia402") {
        keys.push(g.key);
    }
    if keys.is_empty() {
        "none".into()
    } else {
        keys.join(", ")
    }
}

/// One `[[drive]]` entry of an EtherCAT run: which device, its profile (when the file tells),
/// the mode it starts in, its program, the mapping the program's modes need and its start-up
/// values, each checked against the profile where it is known.
fn drive(
    cx: &Ctx<'_>,
    i: usize,
    d: &Spanned<raw::Drive>,
    sim: Option<&[String]>,
    cycle: Duration,
    cycle_key: &Option<Spanned<String>>,
    (warnings, notes): (&mut Vec<String>, &mut Vec<String>),
) -> Result<(DriveSetup, DriveConfig), ConfigError> {
    let key = |k: &str| {
        if k.is_empty() {
            format!("drive[{i}]")
        } else {
            format!("drive[{i}].{k}")
        }
    };
    let at = Entry { cx, key: &key, d };
    let r = d.get_ref();
    let select = selector(&at)?;
    let known = drive_profile(&at, select, sim, notes)?;
    let profile = known.profile;
    emulated_device_fits(&at, select, sim, profile)?;
    let mode = start_mode(&at, profile)?;
    if let Some(p) = profile {
        takes_the_cycle(&at, i, p, cycle, cycle_key)?;
    }
    let program = program_of(cx, &key, d, mode, cycle)?;
    if let Some(p) = profile {
        rated(i, p, &program.steps, warnings);
        pp_targets_fit(&at, p, &program)?;
        if let Selector::Position(pos) = select {
            stored_mode_selector_allows(&at, p, pos, sim, &program.steps, mode)?;
        }
    }
    let homing = homing_writes(&program.steps, profile).map_err(|(n, m)| at.step(n, m))?;
    let has_home = !homing.is_empty();
    let profile_objects =
        profile_writes(&program.steps, profile).map_err(|(n, m)| at.step(n, m))?;
    let modes = program_modes(&at, mode, &program.steps)?;
    let mapping = match &r.mapping {
        Some(m) => Some(mapping_override(
            &at,
            m,
            profile,
            &modes,
            &program.steps,
            has_home,
        )?),
        None => match (&known.esi_source, &known.esi) {
            (Some((f, dev)), Some(e)) => {
                Some(esi_mapping(cx, &key("esi"), e, f, *dev, &modes, notes)?)
            }
            _ => None,
        },
    };
    let sdos = drive_sdos(&at, profile, homing, profile_objects)?;
    let Program {
        units,
        fe_limit,
        limits,
        steps,
        described,
        ..
    } = program;
    Ok((
        DriveSetup {
            select,
            // Forced when the file names a profile or an ESI file; else start-up identifies
            // the device.
            profile: if r.profile.is_some() || r.esi.is_some() || r.profile_file.is_some() {
                profile
            } else {
                None
            },
            mode,
            mapping,
            sdos,
            following_error_limit: fe_limit,
            limits,
            units: units.clone(),
            program: steps,
            probes: Vec::new(),
            esi_choices: known.esi_choices,
        },
        DriveConfig {
            select,
            profile,
            units,
            steps: described,
        },
    ))
}

/// A drive entry being read: the file, the entry's key path (`key("mode")` is
/// `drive[0].mode`) and the entry, for errors at its keys.
struct Entry<'a> {
    cx: &'a Ctx<'a>,
    key: &'a dyn Fn(&str) -> String,
    d: &'a Spanned<raw::Drive>,
}

impl Entry<'_> {
    /// An error at the entry's key `k` (`""`: the entry), at `span`.
    fn err(&self, span: std::ops::Range<usize>, k: &str, m: impl Into<String>) -> ConfigError {
        self.cx.err(span, (self.key)(k), m)
    }

    /// An error at program step `n` (the entry, if it has no such step).
    fn step(&self, n: usize, m: impl Into<String>) -> ConfigError {
        let span = self
            .d
            .get_ref()
            .program
            .get(n)
            .map_or(self.d.span(), Spanned::span);
        self.err(span, &format!("program[{n}]"), m)
    }

    /// The span of the entry's value at `k`, or the entry's.
    fn span_of<T>(&self, v: Option<&Spanned<T>>) -> std::ops::Range<usize> {
        v.map_or(self.d.span(), Spanned::span)
    }
}

/// Which device the entry selects: by position, alias or identity, exactly one.
fn selector(at: &Entry<'_>) -> Result<Selector, ConfigError> {
    let r = at.d.get_ref();
    match (&r.position, &r.alias, &r.identity) {
        (Some(p), None, None) => Ok(Selector::Position(*p.get_ref())),
        (None, Some(a), None) => {
            if *a.get_ref() == 0 {
                return Err(at.err(
                    a.span(),
                    "alias",
                    "alias 0 means \"no alias\"; select by position",
                ));
            }
            Ok(Selector::Alias(*a.get_ref()))
        }
        (None, None, Some(id)) => Ok(Selector::Identity {
            vendor_id: id.get_ref().vendor_id,
            product_code: id.get_ref().product_code,
        }),
        (None, None, None) => Err(at.err(
            at.d.span(),
            "",
            "say which device: give position, alias or identity",
        )),
        _ => Err(at.err(
            at.d.span(),
            "",
            "give only one of position, alias and identity",
        )),
    }
}

/// What the file tells of a drive's profile: the profile if it can be known now, the ESI file
/// (`esi = …`), the file and device the profile was built from, and the profiles start-up
/// chooses from by the identity the device reports (a plain `esi` of several devices).
struct KnownProfile {
    profile: Option<&'static DriveProfile>,
    esi: Option<Spanned<String>>,
    esi_source: Option<(crate::esi::EsiFile, usize)>,
    esi_choices: Vec<&'static DriveProfile>,
}

/// The drive's profile, if it can be known now: a built-in one the entry names (refined by its
/// ESI file when it names one too), one built from its ESI file or loaded from its profile
/// file, or the one its identity or its emulated device has.
fn drive_profile(
    at: &Entry<'_>,
    select: Selector,
    sim: Option<&[String]>,
    notes: &mut Vec<String>,
) -> Result<KnownProfile, ConfigError> {
    let (cx, key, r) = (at.cx, at.key, at.d.get_ref());
    if let (Some(f), true) = (&r.profile_file, r.esi.is_some() || r.profile.is_some()) {
        return Err(at.err(
            f.span(),
            "profile_file",
            "a profile file names its ESI file itself: give profile_file alone, without \
             profile or esi",
        ));
    }
    let esi_choice = esi_choice(r, select, sim);
    let esi: Option<Spanned<String>> = r
        .esi
        .as_ref()
        .map(|e| Spanned::new(e.span(), e.get_ref().file().to_string()));
    let mut esi_source = None;
    let mut esi_choices = Vec::new();
    let profile = match (&esi, &r.profile) {
        // A built-in profile refined by the drive's ESI file: its InitCmds and the objects
        // its dictionary adds.
        (Some(e), Some(p)) => Some(refined_profile(at, e, p, select, esi_choice, notes)?),
        (None, None) if r.profile_file.is_some() => {
            let f = r
                .profile_file
                .as_ref()
                .map_or_else(String::new, |f| f.get_ref().clone());
            let dir = Path::new(cx.file).parent().unwrap_or(Path::new(""));
            Some(profile_file::load(&dir.join(&f))?)
        }
        (Some(e), None)
            if esi_choice.is_none()
                && !matches!(select, Selector::Identity { .. })
                && let Some(c) = esi_choices_for(cx, e, select, &key("esi"), notes)? =>
        {
            esi_choices = c;
            None
        }
        (Some(e), None) => {
            let (f, dev, shown) = esi_device(cx, e, select, esi_choice.as_ref(), &key("esi"))?;
            let p = f
                .devices
                .get(dev)
                .ok_or_else(|| at.err(e.span(), "esi", "device index out of range"))
                .and_then(|d| {
                    crate::drives::esi_profile::from_esi(&f, d, &shown)
                        .map_err(|x| at.err(e.span(), "esi", x.to_string()))
                })?;
            if let Some(d) = f.devices.get(dev) {
                for n in crate::drives::esi_profile::dc_notes(d) {
                    notes.push(format!("{}: {n}", key("esi")));
                }
            }
            esi_source = Some((f, dev));
            Some(p)
        }
        (None, Some(p)) => Some(builtin_profile(cx, p, &key("profile"))?),
        (None, None) => implied_profile(select, sim),
    };
    Ok(KnownProfile {
        profile,
        esi,
        esi_source,
        esi_choices,
    })
}

/// The device of the entry's ESI file it names: `esi = { file, product, revision }`, or on an
/// emulated segment the device the segment holds at the drive's position
/// (`esi:FILE@0xPRODUCT:0xREVISION`); `None` for a plain file elsewhere.
fn esi_choice(
    r: &raw::Drive,
    select: Selector,
    sim: Option<&[String]>,
) -> Option<crate::esi::DeviceChoice> {
    r.esi
        .as_ref()
        .and_then(|e| e.get_ref().choice())
        .or_else(|| {
            let Selector::Position(p) = select else {
                return None;
            };
            let name = sim?.get(usize::from(p))?;
            let (_, sel) = name.strip_prefix("esi:")?.rsplit_once('@')?;
            (sel.starts_with("0x") || sel.starts_with("0X"))
                .then(|| crate::esi::DeviceChoice::parse(sel))
        })
}

/// The built-in profile `p` refined by the entry's ESI file `e` (its InitCmds and the objects
/// its dictionary adds), with a note saying so.
fn refined_profile(
    at: &Entry<'_>,
    e: &Spanned<String>,
    p: &Spanned<String>,
    select: Selector,
    esi_choice: Option<crate::esi::DeviceChoice>,
    notes: &mut Vec<String>,
) -> Result<&'static DriveProfile, ConfigError> {
    let key = at.key;
    let base = builtin_profile(at.cx, p, &key("profile"))?;
    let sel = match select {
        Selector::Identity { .. } => select,
        _ => Selector::Identity {
            vendor_id: base.bus.identity.vendor_id,
            product_code: base.bus.identity.product_code,
        },
    };
    let (f, dev, shown) = esi_device(at.cx, e, sel, esi_choice.as_ref(), &key("esi"))?;
    let refined = f
        .devices
        .get(dev)
        .ok_or_else(|| at.err(e.span(), "esi", "device index out of range"))
        .and_then(|d| {
            crate::drives::esi_profile::refine(base, &f, d, &shown)
                .map_err(|x| at.err(e.span(), "esi", x.to_string()))
        })?;
    notes.push(format!(
        "{}: the {} profile refined by {shown} ({} InitCmds)",
        key(""),
        base.name,
        refined.bus.init_cmds.len()
    ));
    Ok(refined)
}

/// The profile an entry that names none implies: its identity's built-in profile, or that of
/// the emulated device at its position.
fn implied_profile(select: Selector, sim: Option<&[String]>) -> Option<&'static DriveProfile> {
    match select {
        Selector::Identity {
            vendor_id,
            product_code,
        } => crate::drives::by_identity(vendor_id, product_code),
        Selector::Position(p) => sim
            .and_then(|names| names.get(usize::from(p)))
            .and_then(|n| crate::sim::quirks::split_name(n).ok())
            .and_then(|(n, _)| crate::drives::by_key(n)),
        Selector::Alias(_) => None,
    }
}

/// The emulated device at the entry's position, when the file lists them: a drive at all, one
/// a forced profile fits (start-up refuses a profile whose identity does not match the
/// device), and a position the segment has.
fn emulated_device_fits(
    at: &Entry<'_>,
    select: Selector,
    sim: Option<&[String]>,
    profile: Option<&'static DriveProfile>,
) -> Result<(), ConfigError> {
    let (Selector::Position(p), Some(names)) = (select, sim) else {
        return Ok(());
    };
    let r = at.d.get_ref();
    if let Some(name) = names.get(usize::from(p)) {
        let base = crate::sim::quirks::split_name(name).map_or(name.as_str(), |(b, _)| b);
        let device_profile = crate::drives::by_key(base);
        let drivable =
            device_profile.is_some() || base == "generic-coe" || base.starts_with("esi:");
        let span = r
            .profile
            .as_ref()
            .map_or_else(|| at.span_of(r.position.as_ref()), Spanned::span);
        if !drivable {
            return Err(at.err(
                span,
                if r.profile.is_some() {
                    "profile"
                } else {
                    "position"
                },
                format!(
                    "emulated device {p} is a {base}, which is no CiA 402 drive (no CoE \
                     mailbox or no device control); leave it out of the [[drive]] tables: it \
                     runs as an I/O device"
                ),
            ));
        }
        if let (Some(forced), Some(actual)) = (r.profile.as_ref().and(profile), device_profile)
            && forced.key != actual.key
            && forced.key != "generic-cia402"
        {
            return Err(at.err(
                span,
                "profile",
                format!(
                    "the {} profile does not fit emulated device {p}, a {} (vendor 0x{:08X} \
                     product 0x{:08X}): give profile = \"{}\", or leave profile out",
                    forced.name,
                    actual.name,
                    actual.identity.vendor_id,
                    actual.identity.product_code,
                    actual.key
                ),
            ));
        }
    }
    if let Some(pos) = &r.position
        && usize::from(p) >= names.len()
    {
        return Err(at.err(
            pos.span(),
            "position",
            format!(
                "there are {} emulated device(s) (positions 0–{})",
                names.len(),
                names.len().saturating_sub(1)
            ),
        ));
    }
    Ok(())
}

/// The mode the drive starts in (`mode`, csp by default): not ip, which an EtherCAT run does
/// not stream, and one the drive supports.
fn start_mode(
    at: &Entry<'_>,
    profile: Option<&'static DriveProfile>,
) -> Result<RunMode, ConfigError> {
    let Some(m) = &at.d.get_ref().mode else {
        return Ok(RunMode::Csp);
    };
    let mode: RunMode = m
        .get_ref()
        .parse()
        .map_err(|e: String| at.err(m.span(), "mode", e))?;
    if mode == RunMode::Ip {
        return Err(at.err(m.span(), "mode", IP_ON_ETHERCAT));
    }
    if let Some(p) = profile
        && !p.caps.supported_modes.contains(mode.operation_mode())
    {
        return Err(at.err(
            m.span(),
            "mode",
            format!("the {} does not support {}", p.name, mode.name()),
        ));
    }
    Ok(mode)
}

/// The cycle time is one the drive (entry `i`) accepts.
fn takes_the_cycle(
    at: &Entry<'_>,
    i: usize,
    p: &DriveProfile,
    cycle: Duration,
    cycle_key: &Option<Spanned<String>>,
) -> Result<(), ConfigError> {
    let ns = u32::try_from(cycle.as_nanos()).unwrap_or(u32::MAX);
    if p.sync.cycle_times.contains(ns) {
        return Ok(());
    }
    let span = at.span_of(cycle_key.as_ref());
    Err(at.cx.err(
        span,
        if cycle_key.is_some() {
            "cycle".to_string()
        } else {
            (at.key)("")
        },
        format!(
            "{} µs is not a cycle time the {} (drive[{i}]) accepts ({})",
            cycle.as_micros(),
            p.name,
            p.sync.cycle_times.describe()
        ),
    ))
}

/// pp targets within what the drive takes in 0x607A.
fn pp_targets_fit(at: &Entry<'_>, p: &DriveProfile, program: &Program) -> Result<(), ConfigError> {
    let Some((n, t, range)) = program::pp_target_beyond(&program.steps, &p.caps) else {
        return Ok(());
    };
    let user = match &program.units {
        Some(u) => format!("{} {} ({t} counts)", t / program.k, u.name),
        None => format!("{t} counts"),
    };
    Err(at.step(
        n,
        format!(
            "pp: {user} is beyond what the drive takes: {}; move in `by` steps within it, or \
             make the drive's position unit coarser and `units` with it",
            range.source
        ),
    ))
}

/// A drive whose setting selects the usable modes (the MR-J4-TM's [Pr. PA01]), emulated here
/// with the setting stored in its name (`mr-j4-tm@0x2001=2`): the file check says what
/// start-up would read and refuse. (Without one, the factory setting, which the drive's
/// EtherCAT manual leaves to another manual, is read at start-up.)
fn stored_mode_selector_allows(
    at: &Entry<'_>,
    p: &DriveProfile,
    pos: u16,
    sim: Option<&[String]>,
    steps: &[Step],
    mode: RunMode,
) -> Result<(), ConfigError> {
    let (Some(sel), Some(name)) = (
        &p.bus.mode_selector,
        sim.and_then(|names| names.get(usize::from(pos))),
    ) else {
        return Ok(());
    };
    let stored = crate::sim::quirks::stored_params(name).ok().and_then(|v| {
        v.into_iter()
            .find(|(a, _)| *a == sel.object)
            .map(|(_, v)| v)
    });
    if let Some(value) = stored
        && let Err(why) = sel.judge(&program::modes_used(steps, mode), value)
    {
        let span = at.span_of(at.d.get_ref().mode.as_ref());
        return Err(at.err(
            span,
            "mode",
            format!("emulated device {pos} ({name}): {why}"),
        ));
    }
    Ok(())
}

/// Every mode the program runs in, the start mode first; ip refused (an EtherCAT drive
/// streams positions in csp).
fn program_modes(
    at: &Entry<'_>,
    mode: RunMode,
    steps: &[Step],
) -> Result<Vec<RunMode>, ConfigError> {
    let mut modes = vec![mode];
    for (n, s) in steps.iter().enumerate() {
        if let Step::Mode { mode } = s {
            if *mode == RunMode::Ip {
                return Err(at.step(n, IP_ON_ETHERCAT));
            }
            if !modes.contains(mode) {
                modes.push(*mode);
            }
        }
    }
    Ok(modes)
}

/// The entry's own `mapping`, checked against the drive's PDO limits and dictionary, and
/// carrying what the cycle needs of every drive and what the program needs
/// ([`required_objects`]).
fn mapping_override(
    at: &Entry<'_>,
    m: &Spanned<raw::Mapping>,
    profile: Option<&'static DriveProfile>,
    modes: &[RunMode],
    steps: &[Step],
    has_home: bool,
) -> Result<Mapping, ConfigError> {
    let mapping = build_mapping(at.cx, at.key, m, profile)?;
    if let Some(p) = profile {
        crate::pdo::validate(&mapping, &p.pdo_limits, Some(p.dictionary))
            .map_err(|e| at.err(m.span(), "mapping", e.to_string()))?;
    }
    for (dir, obj, what) in required_objects(modes, steps, has_home) {
        if !mapping.contains(dir, obj) {
            return Err(at.err(
                m.span(),
                "mapping",
                format!("{what} ({obj}) must be mapped in the {}", dir.name()),
            ));
        }
    }
    Ok(mapping)
}

/// What the cycle needs mapped of every drive (the controlword and statusword), the set-point
/// of every mode the program runs in, the objects of the touch probes it arms, and the mode
/// of operation where it switches modes (start-up refuses the same): direction, object, what.
fn required_objects(
    modes: &[RunMode],
    steps: &[Step],
    has_home: bool,
) -> Vec<(Direction, ObjectAddress, String)> {
    let a = ObjectAddress::new;
    let mut need = vec![
        (Direction::Rx, a(0x6040, 0), "the controlword".to_string()),
        (Direction::Tx, a(0x6041, 0), "the statusword".to_string()),
    ];
    for m in modes {
        let (obj, what) = match m {
            RunMode::Csp | RunMode::Pp => (a(0x607A, 0), "target position"),
            RunMode::Csv | RunMode::Pv => (a(0x60FF, 0), "target velocity"),
            RunMode::Cst | RunMode::Tq => (a(0x6071, 0), "target torque"),
            RunMode::Ip => (a(0x60C1, 1), "interpolation data record"),
        };
        need.push((Direction::Rx, obj, format!("the {what} of {}", m.name())));
    }
    for (probe, edge) in program::probes_used(steps) {
        for (dir, obj) in [
            (Direction::Rx, a(0x60B8, 0)),
            (Direction::Tx, a(0x60B9, 0)),
            (
                Direction::Tx,
                crate::master::startup::probe_position_object(probe, edge),
            ),
        ] {
            need.push((
                dir,
                obj,
                format!("for touch probe {probe} ({} edge), {obj}", edge.name()),
            ));
        }
    }
    if modes.len() > 1 || has_home {
        need.push((
            Direction::Rx,
            a(0x6060, 0),
            "the mode of operation (the program switches modes)".to_string(),
        ));
    }
    need
}

/// The drive's start-up writes: the home steps' and the profile steps' objects first, then the
/// entry's `sdos` ([`start_up_values`]), which may not give a home offset the drive sets itself
/// nor an object a Fixed InitCmd of its ESI file sets.
fn drive_sdos(
    at: &Entry<'_>,
    profile: Option<&'static DriveProfile>,
    homing: Vec<(ObjectAddress, crate::od::Value)>,
    profile_objects: Vec<(ObjectAddress, crate::od::Value)>,
) -> Result<Vec<(ObjectAddress, crate::od::Value)>, ConfigError> {
    let dict = profile.map(|p| (p.dictionary, p.name));
    let steps_write: Vec<ObjectAddress> = homing
        .iter()
        .chain(&profile_objects)
        .map(|(a, _)| *a)
        .collect();
    let mut sdos = start_up_values(at.cx, at.key, at.d, dict, &steps_write)?;
    let span = at.span_of(at.d.get_ref().sdos.as_ref());
    // The home offset, where the drive sets it itself (a home step's `offset` is refused for
    // the same reason).
    if let Some(p) = profile
        && let Some(why) = p.caps.home_offset_set_by_drive
        && sdos
            .iter()
            .any(|(a, _)| *a == ObjectAddress::new(0x607C, 0))
    {
        return Err(at.err(
            span,
            "sdos.\"0x607C:00\"",
            format!("the home offset cannot be given: {why}"),
        ));
    }
    // A value for the object of one of the ESI file's Fixed InitCmds.
    if let Some(p) = profile
        && let Some(ic) = p.bus.init_cmds.iter().find(|ic| {
            ic.fixed && !ic.writes_mapping() && sdos.iter().any(|(a, _)| *a == ic.address)
        })
    {
        return Err(at.err(
            span,
            "sdos",
            format!(
                "{} is set by the {} and is Fixed: the configuration may not write it",
                ic.address,
                ic.describe()
            ),
        ));
    }
    sdos.splice(0..0, homing.into_iter().chain(profile_objects));
    Ok(sdos)
}

/// A `mapping` table (of a drive entry, or of a profile file) as the PDOs it names, checked
/// against the drive's dictionary where its profile is known.
pub(super) fn build_mapping(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    m: &Spanned<raw::Mapping>,
    profile: Option<&'static DriveProfile>,
) -> Result<Mapping, ConfigError> {
    let dict = profile.map(|p| Dictionary::new(p.dictionary));
    let mut dirs: [Vec<Pdo>; 2] = [Vec::new(), Vec::new()];
    let mut seen: Vec<((usize, u16, u8), usize, usize)> = Vec::new();
    for (d, (name, list)) in [("rx", &m.get_ref().rx), ("tx", &m.get_ref().tx)]
        .into_iter()
        .enumerate()
    {
        for (pi, p) in list.iter().enumerate() {
            let mut entries = Vec::new();
            for (ei, e) in p.get_ref().entries.iter().enumerate() {
                let k = key(&format!("mapping.{name}[{pi}].entries[{ei}]"));
                let bad = || {
                    cx.err(
                        e.span(),
                        k.clone(),
                        "a mapping entry is \"0xINDEX:SUB\", { object = \"0xINDEX:SUB\", bits = N } or { padding = N }",
                    )
                };
                let entry = match e.get_ref() {
                    toml::Value::String(s) => {
                        let a: ObjectAddress =
                            s.parse().map_err(|er: crate::od::AddressParseError| {
                                cx.err(e.span(), k.clone(), er.to_string())
                            })?;
                        // Without a profile the standard CiA 402 objects still have their
                        // standard sizes.
                        let standard =
                            Dictionary::new(crate::drives::generic::GENERIC_CIA402.dictionary);
                        let standard_entry = || {
                            crate::drives::generic::standard_object(a.index)
                                .and_then(|o| o.entries.iter().find(|en| en.sub == a.sub))
                                .map(|en| en.bit_len)
                        };
                        let bits = dict
                            .as_ref()
                            .unwrap_or(&standard)
                            .entry(a)
                            .map(|en| en.bit_len)
                            .or_else(|| {
                                // A profile built from a vendor file: a standard object its
                                // dictionary leaves out has the standard size.
                                match profile {
                                    Some(p) if !p.bus.key.starts_with("esi:") => None,
                                    _ => standard_entry(),
                                }
                            })
                            .ok_or_else(|| {
                                cx.err(
                                    e.span(),
                                    k.clone(),
                                    match profile {
                                        Some(p) => format!("{a} is not in the {} dictionary", p.name),
                                        None => format!(
                                            "the size of {a} is not known without a drive profile (only the standard CiA 402 objects are); write {{ object = \"{s}\", bits = N }} or name the drive's profile"
                                        ),
                                    },
                                )
                            })?;
                        let bits = u8::try_from(bits).map_err(|_| {
                            cx.err(
                                e.span(),
                                k.clone(),
                                format!("{a} has {bits} bits, too large for a PDO entry"),
                            )
                        })?;
                        PdoEntry::new(a.index, a.sub, bits)
                    }
                    toml::Value::Table(t) => {
                        let get = |n: &str| t.get(n);
                        if let Some(unknown) = t
                            .keys()
                            .find(|n| !["object", "bits", "padding"].contains(&n.as_str()))
                        {
                            return Err(cx.err(
                                e.span(),
                                k.clone(),
                                format!("unknown key `{unknown}` in a mapping entry"),
                            ));
                        }
                        match (get("object"), get("bits"), get("padding")) {
                            (Some(toml::Value::String(s)), Some(toml::Value::Integer(b)), None) => {
                                let a: ObjectAddress =
                                    s.parse().map_err(|er: crate::od::AddressParseError| {
                                        cx.err(e.span(), k.clone(), er.to_string())
                                    })?;
                                let bits =
                                    u8::try_from(*b).ok().filter(|b| *b > 0).ok_or_else(|| {
                                        cx.err(
                                            e.span(),
                                            k.clone(),
                                            format!("bits must be 1–255, not {b}"),
                                        )
                                    })?;
                                PdoEntry::new(a.index, a.sub, bits)
                            }
                            (None, None, Some(toml::Value::Integer(b))) => {
                                let bits =
                                    u8::try_from(*b).ok().filter(|b| *b > 0).ok_or_else(|| {
                                        cx.err(
                                            e.span(),
                                            k.clone(),
                                            format!("padding must be 1–255 bits, not {b}"),
                                        )
                                    })?;
                                PdoEntry::padding(bits)
                            }
                            _ => return Err(bad()),
                        }
                    }
                    _ => return Err(bad()),
                };
                // An object mapped twice in the RxPDOs: the drive would take two values for it
                // in one cycle (the BDHDE took the second controlword, 0, and never enabled).
                // [REC] each object once there (a copy in the TxPDOs only costs bytes).
                if entry.index != 0 && d == 0 {
                    let earlier = seen
                        .iter()
                        .find(|(x, ..)| *x == (d, entry.index, entry.sub));
                    if let Some((_, epi, eei)) = earlier {
                        let dir = "RxPDOs";
                        return Err(cx.err(
                            e.span(),
                            k.clone(),
                            format!(
                                "0x{:04X}:{:02X} is mapped twice in the {dir} (also \
                                 mapping.{name}[{epi}].entries[{eei}]): the drive would get two \
                                 values for one object in every cycle",
                                entry.index, entry.sub
                            ),
                        ));
                    }
                    seen.push(((d, entry.index, entry.sub), pi, ei));
                }
                entries.push(entry);
            }
            if let Some(slot) = dirs.get_mut(d) {
                slot.push(Pdo::owned(p.get_ref().pdo, entries));
            }
        }
    }
    let [rx, tx] = dirs;
    Ok(Mapping::owned(rx, tx))
}

/// Why an EtherCAT run refuses ip.
const IP_ON_ETHERCAT: &str = "ip is run on CANopen drives without csp (the ASDA-A2); an \
                              EtherCAT drive streams positions in csp";
