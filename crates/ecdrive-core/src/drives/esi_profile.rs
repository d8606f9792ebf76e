//! A drive profile built from a vendor's ESI file, for a CiA 402 drive ecdrive has no profile
//! for: the generic CiA 402 behaviour ([`super::generic`]) with what the file says in place of
//! the generic assumptions.
//!
//! | profile field | from the file |
//! |---|---|
//! | identity, revision, name, vendor | `<Vendor><Id>`, `<Type ProductCode RevisionNo>`, `<Name>` |
//! | dictionary | `<Profile><Dictionary>`, resolved, with types and access (so `upload`/`download` know types) |
//! | supported modes | 0x6502's default (csp, csv, cst bits); the generic three if absent |
//! | default mapping | the default assignment (PDOs with `Sm`, and the mandatory ones) |
//! | cyclic mapping | [`DrivePlan`]: the PDOs carrying csp, csv and cst together, else those of the first mode that can be carried |
//! | PDO limits | the file's PDO indices (fixed when `Fixed` or without `<CoE PdoConfig>`: assigned, never rewritten), entries per mapping object from its dictionary, bytes from the SyncManager's `MaxSize` |
//! | synchronisation | the DC `<OpMode>` with SYNC0 (AssignActivate), free run if offered, the cycle times it lists; 0x1C32:01/02 written only where the dictionary makes them writable |
//! | InitCmds | `<InitCmd>`s with their transitions, in file order ([`InitCommand`]) |
//! | complete access | `<CoE CompleteAccess>` |
//! | units | CiA 402's (position units, units/s, ‰ of rated torque); units per revolution from 0x6092/0x6091's defaults, else 0x608F's ([`units_from`]) |
//!
//! Profiles built this way live for the rest of the process (the profile type holds `'static`
//! data): a configuration builds each once, at start-up, never in the cycle.

use super::profile::{
    CycleTimeObject, CycleTimes, DriveProfile, EtherCat, IdentityMatch, InitCommand, SyncSpec,
};
use crate::cia402::SupportedModes;
use crate::esi::{Device, DrivePlan, EsiFile, SmKind};
use crate::od::{EntryAccess, ObjectAddress, ObjectDesc};
use crate::pdo::{Direction, DirectionLimits, Mapping, PdoLimits, PdoRange};

/// Why a profile cannot be built from a file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}: device {device}: {reason}")]
pub struct EsiProfileError {
    /// The file.
    pub file: String,
    /// The device (order name and product code).
    pub device: String,
    /// What is missing or wrong.
    pub reason: String,
}

impl EsiProfileError {
    /// The error for device `dev` of the file named `source`.
    pub fn new(source: &str, dev: &Device, reason: String) -> Self {
        Self {
            file: source.to_string(),
            // The revision too: one file may describe a product at several revisions (a
            // boot loader and the drive) under one name.
            device: match dev.type_.revision_no {
                Some(r) => format!(
                    "{} (product 0x{:08X}, revision 0x{r:08X})",
                    dev.type_.name_text, dev.type_.product_code
                ),
                None => format!(
                    "{} (product 0x{:08X})",
                    dev.type_.name_text, dev.type_.product_code
                ),
            },
            reason,
        }
    }
}

fn leak(s: &str) -> &'static str {
    String::leak(s.to_owned())
}

/// PDO index ranges of one direction: each PDO of the file on its own, with as many entries
/// as the dictionary's mapping object has sub-indices (the file's own entry count if the
/// dictionary does not say).
/// A PDO that is `Fixed`, or any PDO of a file without `<CoE PdoConfig>`, keeps its content:
/// its range is fixed, so the master assigns it but never writes its mapping object.
fn ranges(
    dev: &Device,
    dir: Direction,
    dict: &[ObjectDesc],
    configurable: bool,
) -> (Vec<PdoRange>, usize) {
    let mut out = Vec::new();
    let mut most = 0;
    for p in dev.pdos(dir) {
        let n = dict
            .iter()
            .find(|o| o.index == p.index)
            .map(|o| o.entries.iter().filter(|e| e.sub > 0).count())
            .unwrap_or(p.entries.len())
            .clamp(p.entries.len(), 255);
        most = most.max(n);
        let r = PdoRange::single(p.index, n as u8);
        out.push(if p.fixed || !configurable {
            r.fixed()
        } else {
            r
        });
    }
    (out, most)
}

/// The most process data bytes the SyncManager takes: its `MaxSize`. `DefaultSize` is the size
/// of the default mapping, not a limit (a file with an 11-byte default takes a 13-byte
/// mapping its PDO rules allow); without a `MaxSize`, 1024 bytes \[REC\] (or the default
/// size, if larger).
fn sm_bytes(dev: &Device, kind: SmKind) -> u16 {
    dev.sync_manager(kind).map_or(1024, |s| {
        s.max_size
            .unwrap_or_else(|| s.default_size.unwrap_or(0).max(1024))
    })
}

/// `pdos` PDOs of at most `entries` entries each, as the limits' types hold them.
fn counts(pdos: usize, entries: usize) -> (u8, u16) {
    let pdos = pdos.clamp(1, 255);
    let total = entries
        .max(1)
        .saturating_mul(pdos)
        .min(usize::from(u16::MAX));
    (pdos as u8, total as u16)
}

fn writable(dict: &[ObjectDesc], a: ObjectAddress) -> bool {
    dict.iter()
        .find(|o| o.index == a.index)
        .and_then(|o| o.entries.iter().find(|e| e.sub == a.sub))
        .is_some_and(|e| e.access.contains(EntryAccess::WRITE_PREOP))
}

/// The default of `a` in the dictionary as an unsigned number, if the file gives one.
fn default_u64(dict: &[ObjectDesc], a: ObjectAddress) -> Option<u64> {
    let e = dict
        .iter()
        .find(|o| o.index == a.index)?
        .entries
        .iter()
        .find(|e| e.sub == a.sub)?;
    u64::try_from(e.default.as_i128()?).ok()
}

/// The units the file gives: CiA 402's own (position units, position units per second, per
/// mille of rated torque), with the position units per motor revolution from the dictionary's
/// defaults:
/// - with the factor group's feed constant 0x6092 (feed :01 per :02 driving-shaft
///   revolutions), that feed per motor revolution, through the gear ratio 0x6091 (:01 motor
///   per :02 driving-shaft revolutions, 1:1 when absent);
/// - else, without 0x6091/0x6092 (position in encoder increments), the encoder resolution
///   0x608F (:01 increments per :02 revolutions).
///
/// Without either a revolution is 1 unit, as in the generic profile, and only the drive's own
/// units apply.
pub fn units_from(dict: &[ObjectDesc]) -> crate::cia402::Units {
    let generic = super::generic::UNITS;
    let get = |i: u16, s: u8| default_u64(dict, ObjectAddress::new(i, s)).filter(|v| *v > 0);
    let has = |i: u16| dict.iter().any(|o| o.index == i);
    let per_rev = if has(0x6092) {
        match (get(0x6092, 1), get(0x6092, 2)) {
            (Some(feed), Some(shaft)) => {
                let (motor, driven) = (get(0x6091, 1).unwrap_or(1), get(0x6091, 2).unwrap_or(1));
                Some(feed as f64 / shaft as f64 * driven as f64 / motor as f64)
            }
            _ => None,
        }
    } else if !has(0x6091) {
        match (get(0x608F, 1), get(0x608F, 2)) {
            (Some(i), Some(r)) => Some(i as f64 / r as f64),
            _ => None,
        }
    } else {
        None
    };
    match per_rev {
        Some(n) => crate::cia402::Units {
            position_name: "position unit",
            position_per_rev: n,
            ..generic
        },
        None => generic,
    }
}

/// The file's dictionary with the standard CiA 402 objects it leaves out
/// ([`super::generic::STANDARD_EXTRA`]), as CiA 402 describes them: vendor files are often
/// partial, and a user who maps the touch probe (0x60B8) of a drive whose file omits it should
/// meet the drive's answer at start-up (an SDO abort naming the object, if the drive lacks
/// it), not a refusal of the file.
fn with_standard_objects(dict: &'static [ObjectDesc]) -> &'static [ObjectDesc] {
    let missing: Vec<ObjectDesc> = super::generic::STANDARD_EXTRA
        .iter()
        .filter(|o| !dict.iter().any(|d| d.index == o.index))
        .cloned()
        .collect();
    if missing.is_empty() {
        return dict;
    }
    let mut all = dict.to_vec();
    all.extend(missing);
    all.sort_by_key(|o| o.index);
    Vec::leak(all)
}

/// The mapping of each set of cyclic modes (bit 0 csp, bit 1 csv, bit 2 cst), as
/// [`crate::esi::mapping_for`] chooses it: the choice `esi = FILE` makes, so that a profile
/// found by `--esi DIR` runs a program with the same PDOs.
fn mode_mappings(dev: &Device) -> Vec<Result<Mapping, &'static str>> {
    (0..8usize)
        .map(|set| {
            let refs: Vec<crate::esi::CyclicModeRef> = crate::esi::CYCLIC_MODES
                .iter()
                .enumerate()
                .filter(|(i, _)| set & (1 << i) != 0)
                .map(|(_, m)| *m)
                .collect();
            let m = crate::esi::mapping_for(dev, &refs);
            m.mapping.ok_or_else(|| {
                let why: Vec<String> = [m.rx.err(), m.tx.err()].into_iter().flatten().collect();
                leak(&format!(
                    "the drive's PDOs cannot carry {}: {}",
                    m.modes.join("+"),
                    why.join("; ")
                ))
            })
        })
        .collect()
}

/// Build the profile of `dev` from `file` (named `source` in errors and in the profile's key,
/// `esi:ORDER`).
pub fn from_esi(
    file: &EsiFile,
    dev: &Device,
    source: &str,
) -> Result<&'static DriveProfile, EsiProfileError> {
    let err = |reason: String| EsiProfileError::new(source, dev, reason);
    if !dev.has_coe() {
        return Err(err(
            "it has no CoE mailbox: a CiA 402 drive is configured over CoE".into(),
        ));
    }
    let dictionary = crate::esi::static_dictionary(dev).map_err(err)?;
    if let Some(missing) = [(0x6040u16, "controlword"), (0x6041, "statusword")]
        .iter()
        .find(|(i, _)| !dictionary.iter().any(|o| o.index == *i))
    {
        return Err(err(format!(
            "not a CiA 402 drive: no 0x{:04X} ({}) in its dictionary",
            missing.0, missing.1
        )));
    }
    let dictionary = with_standard_objects(dictionary);
    let plan = DrivePlan::new(file, dev);
    // What `esi show` says stops a device from running as a drive stops its profile too.
    if let Some(why) = &plan.not_a_drive {
        return Err(err(why.clone()));
    }
    let mut modes = 0u32;
    for m in &plan.modes {
        modes |= match *m {
            "csp" => 1 << 7,
            "csv" => 1 << 8,
            _ => 1 << 9,
        };
    }
    let cyclic = cyclic_mapping(&plan).map_err(err)?;
    let default_mapping = dev
        .default_mapping()
        .unwrap_or_else(|_| Mapping::fixed(&[], &[]));
    let coe = dev.mailbox.as_ref().and_then(|m| m.coe.as_ref());
    let name = leak(&dev.name);
    let pdo_limits = pdo_limits(dev, name, dictionary);
    let sync = sync_spec(dev, dictionary);
    let init_cmds = init_commands(dev);
    let generic = &super::generic::GENERIC_CIA402;
    let profile = DriveProfile {
        name,
        vendor: leak(&file.vendor.name),
        caps: crate::cia402::DriveCaps {
            supported_modes: SupportedModes::from_raw(modes),
            ..generic.caps
        },
        dictionary,
        units: units_from(dictionary),
        bus: EtherCat {
            key: leak(&format!("esi:{}", dev.type_.name_text)),
            identity: IdentityMatch {
                vendor_id: file.vendor.id,
                product_code: dev.type_.product_code,
            },
            revision: dev.type_.revision_no.unwrap_or(0),
            pdo_limits,
            default_mapping,
            cyclic_mapping: cyclic,
            mode_mappings: Vec::leak(mode_mappings(dev)),
            required_objects: super::generic::REQUIRED_OBJECTS,
            startup: &[],
            init_cmds: Vec::leak(init_cmds),
            output_defaults: &[],
            cycle_counter: None,
            sync,
            complete_access: coe.is_some_and(|c| c.complete_access),
            esi: "",
            zero_speed_flag: None,
            mode_selector: None,
            ratings: crate::drives::Ratings::NONE,
        },
    };
    Ok(Box::leak(Box::new(profile)))
}

/// The cyclic mapping of the profile: every mode at once if the PDOs allow it (the plan's last
/// mapping), else the first mode that can be carried (csp before csv before cst); the reason
/// when none can.
fn cyclic_mapping(plan: &DrivePlan) -> Result<Mapping, String> {
    plan.mappings
        .last()
        .and_then(|m| m.mapping.clone())
        .or_else(|| plan.mappings.iter().find_map(|m| m.mapping.clone()))
        .ok_or_else(|| {
            let why: Vec<String> = plan
                .mappings
                .iter()
                .map(|m| {
                    let side = |r: &Result<_, String>| r.as_ref().err().cloned();
                    format!(
                        "{}: {}",
                        m.modes.join("+"),
                        [side(&m.rx), side(&m.tx)]
                            .into_iter()
                            .flatten()
                            .collect::<Vec<_>>()
                            .join("; ")
                    )
                })
                .collect();
            if why.is_empty() {
                return "its 0x6502 (supported drive modes) default lists none of csp, csv and \
                        cst: ecdrive runs a drive in a cyclic mode"
                    .into();
            }
            format!("no cyclic mode can be mapped ({})", why.join(" | "))
        })
}

/// The PDO limits of the device: the ranges of its mapping objects, how many PDOs and entries
/// it takes (configurable only where its CoE says so), and its SyncManagers' sizes.
fn pdo_limits(dev: &Device, name: &'static str, dictionary: &'static [ObjectDesc]) -> PdoLimits {
    let coe = dev.mailbox.as_ref().and_then(|m| m.coe.as_ref());
    let configurable = coe.is_some_and(|c| c.pdo_config);
    let (rx_ranges, rx_most) = ranges(dev, Direction::Rx, dictionary, configurable);
    let (tx_ranges, tx_most) = ranges(dev, Direction::Tx, dictionary, configurable);
    let (rx_assigned, rx_entries) = counts(dev.rx_pdos.len(), rx_most);
    let (tx_assigned, tx_entries) = counts(dev.tx_pdos.len(), tx_most);
    PdoLimits {
        drive: name,
        rx: DirectionLimits {
            pdos: Vec::leak(rx_ranges),
            max_assigned: rx_assigned,
            max_entries: rx_entries,
            max_bytes: sm_bytes(dev, SmKind::Outputs),
        },
        tx: DirectionLimits {
            pdos: Vec::leak(tx_ranges),
            max_assigned: tx_assigned,
            max_entries: tx_entries,
            max_bytes: sm_bytes(dev, SmKind::Inputs),
        },
        assignment_writable: coe.is_some_and(|c| c.pdo_assign),
    }
}

/// The synchronisation of the device: free run where a DC mode without SYNC0 (or none) says
/// so, DC SYNC0 with its cycle times and AssignActivate, and the sync objects it can write.
fn sync_spec(dev: &Device, dictionary: &'static [ObjectDesc]) -> SyncSpec {
    let sync_type = ObjectAddress::new(0x1C32, 1);
    let cycle_time = ObjectAddress::new(0x1C32, 2);
    let sync0_mode = dev.dc.iter().find(|m| m.mode.sync0());
    let free_run = dev.dc.is_empty() || dev.dc.iter().any(|m| m.mode.assign_activate == 0);
    let cycle_times = sync0_mode
        .and_then(|m| m.allowed_cycle_times.as_ref())
        .map(|t| match t {
            crate::esi::CycleTimes::List(l) => CycleTimes::List(Vec::leak(l.clone())),
            crate::esi::CycleTimes::Range { min, max, step } => CycleTimes::Range {
                min_ns: *min,
                max_ns: *max,
                step_ns: (*step).max(1),
            },
        })
        .unwrap_or(super::generic::SYNC.cycle_times);
    SyncSpec {
        free_run,
        dc_sync0: sync0_mode.is_some(),
        cycle_times,
        assign_activate: sync0_mode.map_or(0x0300, |m| m.mode.assign_activate),
        sync_type_object: writable(dictionary, sync_type).then_some(sync_type),
        cycle_time_object: writable(dictionary, cycle_time)
            .then_some(CycleTimeObject::Nanoseconds(cycle_time)),
    }
}

/// What the file's DC mode with SYNC0 asks that ecdrive does not do, one line each: a SYNC0
/// cycle other than the bus cycle (`<CycleTimeSync0 Factor>` ≠ 1) and a SYNC0 shift of its own
/// (`<ShiftTimeSync0>` ≠ 0). ecdrive gives every drive SYNC0 at the cycle, with the segment's
/// shift (ethercrab 0.7.1 sets one SYNC0 period and start time for the group).
pub fn dc_notes(dev: &Device) -> Vec<String> {
    let Some(m) = dev.dc.iter().find(|m| m.mode.sync0()) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let f = m.mode.sync0_cycle_factor;
    if f != 0 && f != 1 {
        out.push(format!(
            "the file's DC mode {:?} asks SYNC0 = {} the cycle (Factor {f}); ecdrive runs \
             SYNC0 at the cycle: choose the cycle the drive needs SYNC0 at",
            m.mode.name,
            if f > 0 {
                format!("{f} ×")
            } else {
                format!("1/{} of", f.unsigned_abs())
            }
        ));
    }
    if m.mode.shift_time0 != 0 {
        out.push(format!(
            "the file's DC mode {:?} asks a SYNC0 shift of {} ns; ecdrive uses the segment's \
             (dc shift in the configuration) for every drive",
            m.mode.name, m.mode.shift_time0
        ));
    }
    out
}

/// A built-in profile refined by the drive's ESI file: everything the profile says (the
/// manual's facts: mapping, synchronisation, start-up values, units) stays, and the file adds
/// its `<InitCmd>`s and the dictionary objects the profile does not have (so `upload` and
/// `download` know their types, e.g. a newer firmware's objects). The file's device must have
/// the profile's identity.
pub fn refine(
    base: &'static DriveProfile,
    file: &EsiFile,
    dev: &Device,
    source: &str,
) -> Result<&'static DriveProfile, EsiProfileError> {
    let err = |reason: String| EsiProfileError::new(source, dev, reason);
    let id = base.bus.identity;
    if (file.vendor.id, dev.type_.product_code) != (id.vendor_id, id.product_code) {
        return Err(err(format!(
            "is vendor 0x{:08X} product 0x{:08X}; the {} profile is vendor 0x{:08X} product \
             0x{:08X}",
            file.vendor.id, dev.type_.product_code, base.name, id.vendor_id, id.product_code
        )));
    }
    let from_file = crate::esi::static_dictionary(dev).map_err(err)?;
    let mut dictionary: Vec<ObjectDesc> = base.dictionary.to_vec();
    for o in from_file {
        if !dictionary.iter().any(|b| b.index == o.index) {
            dictionary.push(*o);
        }
    }
    dictionary.sort_by_key(|o| o.index);
    let mut profile = base.clone();
    profile.dictionary = Vec::leak(dictionary);
    profile.bus.init_cmds = Vec::leak(init_commands(dev));
    Ok(Box::leak(Box::new(profile)))
}

/// The device's `<InitCmd>`s, in file order, without the disabled ones.
fn init_commands(dev: &Device) -> Vec<InitCommand> {
    dev.mailbox
        .as_ref()
        .map(|m| {
            m.init_cmds
                .iter()
                .filter(|c| !c.disabled)
                .map(|c| InitCommand {
                    transitions: Vec::leak(c.transitions.clone()),
                    address: ObjectAddress::new(c.index, c.sub),
                    data: Vec::leak(c.data.clone()),
                    comment: leak(&c.comment),
                    complete_access: c.complete_access,
                    line: c.position.line,
                    timeout_ms: c.timeout_ms,
                    retries: c.retries,
                    fixed: c.fixed,
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The profile of the device with `vendor_id`/`product_code` (and `revision`, if the file
/// distinguishes revisions) in `file`, if the file describes it.
pub fn find_in(
    file: &EsiFile,
    source: &str,
    vendor_id: u32,
    product_code: u32,
    revision: Option<u32>,
) -> Option<Result<&'static DriveProfile, EsiProfileError>> {
    if file.vendor.id != vendor_id {
        return None;
    }
    file.device(product_code, revision)
        .map(|d| from_esi(file, d, source))
}

/// What a folder (or a file) of ESI files gives: see [`load_dir`].
#[derive(Debug, Clone, Default)]
pub struct Loaded {
    /// One profile per device with a CoE mailbox that is a CiA 402 drive ecdrive can run.
    pub profiles: Vec<&'static DriveProfile>,
    /// What cannot be used, one line each naming the file (and for a file that does not
    /// parse, the line and column): a folder of vendor files holds terminals and couplers too.
    pub skipped: Vec<String>,
    /// The identities (vendor, product, revision) of the devices the files describe that are
    /// no drive: a device of one of them is never matched to a drive profile of another
    /// revision of the same product (Elmo's boot loader shares its product code with the
    /// drive).
    pub not_drives: Vec<(u32, u32, u32)>,
}

/// Every drive profile the ESI files in `dir` (`*.xml`, in name order) give, what cannot be
/// used, and the devices that are no drives ([`Loaded`]).
pub fn load_dir(dir: &std::path::Path) -> Result<Loaded, std::io::Error> {
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(dir)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("xml")))
        .collect();
    files.sort();
    let mut out = Loaded::default();
    for path in files {
        load_file(&path, &mut out);
    }
    Ok(out)
}

/// [`load_dir`] for a folder, the same for one file (`--esi FILE|DIR`).
pub fn load_path(path: &std::path::Path) -> Result<Loaded, std::io::Error> {
    if std::fs::metadata(path)?.is_dir() {
        return load_dir(path);
    }
    let mut out = Loaded::default();
    load_file(path, &mut out);
    Ok(out)
}

fn load_file(path: &std::path::Path, out: &mut Loaded) {
    let shown = path.display().to_string();
    let file = match EsiFile::from_path(path) {
        Ok(f) => f,
        Err(e) => {
            out.skipped.push(format!("{shown}: {e}"));
            return;
        }
    };
    for dev in &file.devices {
        let identity = (
            file.vendor.id,
            dev.type_.product_code,
            dev.type_.revision_no.unwrap_or(0),
        );
        if !dev.has_coe() {
            out.not_drives.push(identity);
            continue;
        }
        match from_esi(&file, dev, &shown) {
            Ok(p) => out.profiles.push(p),
            Err(e) => {
                out.not_drives.push(identity);
                out.skipped.push(e.to_string());
            }
        }
    }
}
