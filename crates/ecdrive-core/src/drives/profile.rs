//! The drive-profile model: everything the generic layers need to know about one drive type,
//! as static data.
//!
//! A [`DriveProfile`] is read by the master (what to configure at start-up, how to decode
//! faults), by the software slave (how the emulated drive answers), by the CLI (type inference,
//! names) and by the tests. Quirks are fields here, not `if vendor == …` in the logic.

pub use crate::cia402::interpolated::{interpolation_cycle_ns, interpolation_standard_form};
use crate::od::{ConstValue, ObjectAddress};
use crate::pdo::{Mapping, PdoLimits, RequiredObjects};

/// Vendor ID and product code as 0x1018:01/02 and the SII report them. Any revision matches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IdentityMatch {
    /// Vendor ID (0x1018:01).
    pub vendor_id: u32,
    /// Product code (0x1018:02).
    pub product_code: u32,
}

impl IdentityMatch {
    /// Whether a device with this vendor ID and product code is this drive type.
    pub const fn matches(&self, vendor_id: u32, product_code: u32) -> bool {
        self.vendor_id == vendor_id && self.product_code == product_code
    }
}

/// The SYNC0 / PDO cycle times a drive accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CycleTimes {
    /// Exactly these (ns).
    List(&'static [u32]),
    /// From `min_ns` to `max_ns` in steps of `step_ns` (ns).
    Range {
        /// Shortest cycle.
        min_ns: u32,
        /// Longest cycle.
        max_ns: u32,
        /// Granularity.
        step_ns: u32,
    },
}

impl CycleTimes {
    /// Whether `ns` is allowed.
    pub fn contains(&self, ns: u32) -> bool {
        match *self {
            Self::List(l) => l.contains(&ns),
            Self::Range {
                min_ns,
                max_ns,
                step_ns,
            } => (min_ns..=max_ns).contains(&ns) && step_ns != 0 && (ns - min_ns) % step_ns == 0,
        }
    }

    /// A human description: `250, 500, 1000, 2000 µs` or `1000–16000 µs in 250 µs steps`.
    pub fn describe(&self) -> String {
        match *self {
            Self::List(l) => {
                let v: Vec<String> = l.iter().map(|n| (n / 1000).to_string()).collect();
                format!("{} µs", v.join(", "))
            }
            Self::Range {
                min_ns,
                max_ns,
                step_ns,
            } => format!(
                "{}–{} µs in {} µs steps",
                min_ns / 1000,
                max_ns / 1000,
                step_ns / 1000
            ),
        }
    }
}

/// How the drive learns the cycle time over CoE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CycleTimeObject {
    /// The cycle in ns goes into this object (MR-J4-TM: 0x1C32:02).
    Nanoseconds(ObjectAddress),
    /// 0x60C2 interpolation time period with a vendor reading of one index: while `:02` holds
    /// `index`, `:01` counts `unit_ns` (BDHDE: FBITIDX −4 stands for 250 µs, §2.4); any other
    /// index is the standard `:01 × 10^(:02)` s. The master writes the standard form, as the
    /// drive's own set-up example does (1 and −3 for 1 ms), never with `index` as the power of
    /// ten; where `:02` cannot be written and holds `index`, it writes `:01` in `unit_ns`.
    InterpolationFixedIndex {
        /// The time unit of `:01` while `:02` holds `index`, ns.
        unit_ns: u32,
        /// The vendor's index.
        index: i8,
    },
    /// 0x60C2 in the standard CiA 402 form `:01 × 10^(:02)` s.
    InterpolationStandard,
}

/// Synchronisation the drive supports, and what the master must write for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncSpec {
    /// Free run (no DC) supported for the cyclic synchronous modes.
    pub free_run: bool,
    /// DC SYNC0 supported.
    pub dc_sync0: bool,
    /// Allowed cycle times.
    pub cycle_times: CycleTimes,
    /// ESI AssignActivate value for DC SYNC0 (written to 0x0980/0x0981 by the DC set-up).
    pub assign_activate: u16,
    /// Where the synchronisation type is written (0x1C32:01 = 2 for DC SYNC0), if at all.
    pub sync_type_object: Option<ObjectAddress>,
    /// Where the cycle time is written, if at all.
    pub cycle_time_object: Option<CycleTimeObject>,
}

/// When a start-up SDO is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartupWhen {
    /// Always.
    Always,
    /// By SDO if the object is not mapped in the RxPDO (drives refuse SDO writes to mapped
    /// objects); if it is mapped, the value is sent in that output from the first cycle on.
    IfNotMapped,
}

/// An `<InitCmd>` of the drive's ESI file: an SDO download the configuration tool sends at the
/// transitions it names, in file order, with its data as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InitCommand {
    /// The transitions (`PS`: PRE-OP → SAFE-OP, `SO`: SAFE-OP → OP, `IP`: INIT → PRE-OP, …).
    pub transitions: &'static [crate::esi::Transition],
    /// The object.
    pub address: ObjectAddress,
    /// The bytes to download.
    pub data: &'static [u8],
    /// The file's comment (named in errors).
    pub comment: &'static str,
    /// Complete access.
    pub complete_access: bool,
    /// Line of the `<InitCmd>` in the file (0: written by hand in a profile file).
    pub line: u32,
    /// `<Timeout>`, ms: how long the drive may take to answer (None: the master's SDO
    /// timeout).
    pub timeout_ms: Option<u32>,
    /// `<Retries>`: how often it is sent again after a timeout or a refusal before the
    /// transition fails.
    pub retries: u8,
    /// `Fixed`: the configuration may not write the same object.
    pub fixed: bool,
}

impl InitCommand {
    /// Whether it is sent at `t`.
    pub fn at(&self, t: crate::esi::Transition) -> bool {
        self.transitions.contains(&t)
    }

    /// Whether it writes a PDO assignment or mapping object (0x1C12, 0x1C13, 0x1600–0x17FF,
    /// 0x1A00–0x1BFF): the master writes the mapping it chose itself and leaves these out.
    pub fn writes_mapping(&self) -> bool {
        matches!(
            self.address.index,
            0x1C12 | 0x1C13 | 0x1600..=0x17FF | 0x1A00..=0x1BFF
        )
    }

    /// How it is named in errors and logs: line, transitions and the file's comment.
    pub fn describe(&self) -> String {
        let t: Vec<&str> = self.transitions.iter().map(|t| t.name()).collect();
        let from = if self.line == 0 {
            "InitCmd of the profile file".to_string()
        } else {
            format!("InitCmd at line {} of the ESI file", self.line)
        };
        format!("{from}, {}: {:?}", t.join(","), self.comment)
    }
}

/// An SDO the master writes in PRE-OP for a safe start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartupSdo {
    /// The object.
    pub address: ObjectAddress,
    /// The value (typed by the dictionary entry).
    pub value: ConstValue,
    /// Why (shown in logs and errors).
    pub why: &'static str,
    /// When to write it.
    pub when: StartupWhen,
}

/// A value the master must put into a mapped output from the first cycle on, because the
/// drive's default of 0 would be unsafe or stop it (MR-J4-TM: 0x2D20 speed limit, 0x60E0/0x60E1
/// torque limits — zeros mean no speed / no torque).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputDefault {
    /// The mapped object.
    pub address: ObjectAddress,
    /// The value to send.
    pub value: i64,
    /// Why.
    pub why: &'static str,
}

/// A counter the master must advance every cycle when it is mapped, and the drive's echo
/// (MR-J4-TM: 0x2D23 DL counter, 0x2D24 UL = DL + 1; a wrong update raises AL.86.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CycleCounter {
    /// The master's counter (RxPDO).
    pub output: ObjectAddress,
    /// The drive's echo (TxPDO), if any.
    pub echo: Option<ObjectAddress>,
}

pub use crate::cia402::Profile;
pub use crate::cia402::units::Units;

/// An EtherCAT drive's profile: the common part and [`EtherCat`] (see [`Profile`]).
pub type DriveProfile = Profile<EtherCat>;

/// What only an EtherCAT drive's profile has.
#[derive(Debug, Clone)]
pub struct EtherCat {
    /// The `--device` key (`"mr-j4-tm"`).
    pub key: &'static str,
    /// Identity.
    pub identity: IdentityMatch,
    /// Revision reported by the emulated drive (and expected from real ones, informational).
    pub revision: u32,
    /// PDO limits.
    pub pdo_limits: PdoLimits,
    /// Power-on mapping.
    pub default_mapping: Mapping,
    /// Recommended mapping for csp/csv/cst.
    pub cyclic_mapping: Mapping,
    /// For a profile built from an ESI file: the mapping for each set of cyclic modes a
    /// program uses, chosen from the file's PDOs as `esi = FILE` chooses it
    /// ([`crate::esi::mapping_for`]: the smallest that holds the modes), or why the PDOs cannot
    /// carry them; indexed by the set (bit 0 csp, bit 1 csv, bit 2 cst). Empty for the built-in
    /// profiles, which run [`cyclic_mapping`](Self::cyclic_mapping). See
    /// [`mapping_for_modes`](Self::mapping_for_modes).
    pub mode_mappings: &'static [Result<Mapping, &'static str>],
    /// Objects each mode needs mapped.
    pub required_objects: &'static [RequiredObjects],
    /// SDOs written in PRE-OP for a safe start.
    pub startup: &'static [StartupSdo],
    /// The ESI file's `<InitCmd>`s (profiles built from an ESI; empty for the built-in ones,
    /// whose files have none).
    pub init_cmds: &'static [InitCommand],
    /// Values mapped outputs must carry from the first cycle.
    pub output_defaults: &'static [OutputDefault],
    /// A counter to advance every cycle when mapped.
    pub cycle_counter: Option<CycleCounter>,
    /// Synchronisation.
    pub sync: SyncSpec,
    /// Whether SDO complete access works.
    pub complete_access: bool,
    /// The drive's ESI file (XML text), `include_str!`'d from `esi/`; empty for a profile
    /// without one (the generic profile). See [`DriveProfile::esi_file`].
    pub esi: &'static str,
    /// A status bit the drive sets at zero speed, which the CiA 402 engine uses (when mapped)
    /// to decide standstill before a mode switch that needs it (MR-J4-TM: 0x2D12 bit 3 S_ZSP).
    pub zero_speed_flag: Option<StatusFlag>,
    /// A parameter that selects which modes of operation are usable, read at power-on
    /// (MR-J4-TM [Pr. PA01]: the cyclic modes or the profile modes, never both). Start-up reads
    /// it and refuses a program that needs a mode it does not allow, naming the setting.
    pub mode_selector: Option<ModeSelector>,
    /// The largest torque and speed the drive itself documents, whatever the motor: a program
    /// beyond them gets a warning when the configuration is checked.
    pub ratings: Ratings,
}

/// A parameter that selects the usable modes of operation ([`EtherCat::mode_selector`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeSelector {
    /// The parameter.
    pub object: ObjectAddress,
    /// How the manual names it ("[Pr. PA01] Operation mode").
    pub name: &'static str,
    /// The bits of the value that select the group (the group is `value & mask`).
    pub mask: i64,
    /// The groups.
    pub groups: &'static [ModeGroup],
    /// Where the manual says so.
    pub source: &'static str,
}

/// The modes one setting of a [`ModeSelector`] allows (the type is the core's, shared with the
/// software slave's own tables).
pub use crate::cia402::ModeGroup;

impl EtherCat {
    /// The mapping to run a program with the modes `codes` (0x6060 values; modes other than
    /// csp, csv and cst count as none): [`mode_mappings`](Self::mode_mappings) where the
    /// profile has them, else [`cyclic_mapping`](Self::cyclic_mapping).
    pub fn mapping_for_modes(&self, codes: &[i8]) -> Result<&Mapping, &'static str> {
        if self.mode_mappings.is_empty() {
            return Ok(&self.cyclic_mapping);
        }
        let set = codes.iter().fold(0usize, |s, c| match c {
            8 => s | 1,
            9 => s | 2,
            10 => s | 4,
            _ => s,
        });
        match self.mode_mappings.get(set) {
            Some(Ok(m)) => Ok(m),
            Some(Err(e)) => Err(e),
            None => Ok(&self.cyclic_mapping),
        }
    }
}

impl ModeSelector {
    /// The group a read value selects (`None`: a value the manual does not list).
    pub fn group(&self, value: i64) -> Option<&'static ModeGroup> {
        self.groups.iter().find(|g| g.value == value & self.mask)
    }

    /// Whether the setting `value` allows every one of `modes` (0x6060 values); the error says
    /// which mode it does not allow, what the setting allows, and the setting that would.
    pub fn judge(&self, modes: &[i8], value: i64) -> Result<(), String> {
        let names = |ms: &[i8]| -> String {
            ms.iter()
                .map(|m| crate::cia402::OperationMode::from_i8(*m).short_name())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let group = self.group(value);
        let Some(&bad) = modes
            .iter()
            .find(|m| !group.is_some_and(|g| g.modes.contains(m)))
        else {
            return Ok(());
        };
        let now = match group {
            Some(g) => format!("\"{}\" (allows {})", g.name, names(g.modes)),
            None => "a setting the manual does not list".to_string(),
        };
        let fix = match self.group_for(modes) {
            Some(g) => format!("set it to \"{}\" and power-cycle the drive", g.name),
            None => format!(
                "no one setting allows all of {}: split the program",
                names(modes)
            ),
        };
        Err(format!(
            "the program runs {}, which {} ({}) = 0x{value:04X} does not allow: it selects {now} \
             ({}); {fix}",
            crate::cia402::OperationMode::from_i8(bad).short_name(),
            self.name,
            self.object,
            self.source
        ))
    }

    /// A group that allows every one of `modes`, if there is one.
    pub fn group_for(&self, modes: &[i8]) -> Option<&'static ModeGroup> {
        self.groups
            .iter()
            .find(|g| modes.iter().all(|m| g.modes.contains(m)))
    }
}

/// One documented maximum, with where it comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rating {
    /// The value (unit given by the field it is in).
    pub value: f64,
    /// The manual's words for it, with the section.
    pub source: &'static str,
}

/// The largest torque and speed a drive documents independently of the motor it drives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ratings {
    /// Largest torque, in the drive's torque unit ([`Units::torque_per_mille`]).
    pub max_torque: Option<Rating>,
    /// Largest speed, motor revolutions per second.
    pub max_speed_rev_s: Option<Rating>,
}

impl Ratings {
    /// Nothing documented (the motor decides).
    pub const NONE: Ratings = Ratings {
        max_torque: None,
        max_speed_rev_s: None,
    };
}

/// One bit of a mapped status object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StatusFlag {
    /// The object.
    pub address: ObjectAddress,
    /// The bit.
    pub bit: u8,
}

/// A cycle time the drive does not accept.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the {drive} does not accept a cycle of {cycle_ns} ns; it accepts {allowed}")]
pub struct CycleTimeError {
    /// Drive name.
    pub drive: &'static str,
    /// The cycle asked for, ns.
    pub cycle_ns: u32,
    /// The accepted cycles, as text.
    pub allowed: String,
}

/// One SDO download the master makes for the synchronisation set-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncWrite {
    /// The object.
    pub address: ObjectAddress,
    /// The value, as an unsigned or signed integer of the object's type.
    pub value: i64,
    /// Why.
    pub why: &'static str,
}

impl SyncSpec {
    /// The writes that tell the drive its cycle and synchronisation mode, in order: the
    /// synchronisation type (if the drive has such an object: 2 for DC SYNC0, 0 for free run),
    /// then the cycle time in the drive's form. Fails if the drive does not accept `cycle_ns` or
    /// the mode.
    pub fn writes(
        &self,
        drive: &'static str,
        cycle_ns: u32,
        dc: bool,
    ) -> Result<Vec<SyncWrite>, CycleTimeError> {
        let refuse = || CycleTimeError {
            drive,
            cycle_ns,
            allowed: self.cycle_times.describe(),
        };
        if !self.cycle_times.contains(cycle_ns) || (dc && !self.dc_sync0) || (!dc && !self.free_run)
        {
            let mut e = refuse();
            if dc && !self.dc_sync0 {
                e.allowed = format!("{} in free run only (no DC SYNC0)", e.allowed);
            } else if !dc && !self.free_run {
                e.allowed = format!("{} with DC SYNC0 only (no free run)", e.allowed);
            }
            return Err(e);
        }
        let mut out = Vec::with_capacity(3);
        if let Some(address) = self.sync_type_object {
            out.push(SyncWrite {
                address,
                value: if dc { 2 } else { 0 },
                why: if dc {
                    "synchronisation type: DC SYNC0"
                } else {
                    "synchronisation type: free run"
                },
            });
        }
        match self.cycle_time_object {
            None => {}
            Some(CycleTimeObject::Nanoseconds(address)) => out.push(SyncWrite {
                address,
                value: i64::from(cycle_ns),
                why: "cycle time, ns",
            }),
            Some(CycleTimeObject::InterpolationFixedIndex { unit_ns, index }) => {
                // The standard form, index first (the drive's own set-up example writes 1 and
                // −3 for 1 ms); the vendor's unit where the cycle has no standard form.
                match interpolation_standard_form(cycle_ns, Some(index)) {
                    Some((value, power)) => {
                        out.push(SyncWrite {
                            address: ObjectAddress::new(0x60C2, 2),
                            value: i64::from(power),
                            why: "interpolation time index (power of ten of seconds)",
                        });
                        out.push(SyncWrite {
                            address: ObjectAddress::new(0x60C2, 1),
                            value: i64::from(value),
                            why: "interpolation time period value",
                        });
                    }
                    None => {
                        if unit_ns == 0 || cycle_ns % unit_ns != 0 {
                            return Err(refuse());
                        }
                        out.push(SyncWrite {
                            address: ObjectAddress::new(0x60C2, 1),
                            value: i64::from(cycle_ns / unit_ns),
                            why: "interpolation time period in the drive's unit for its own \
                                  index (0x60C2:02)",
                        });
                    }
                }
            }
            Some(CycleTimeObject::InterpolationStandard) => {
                // value × 10^index s with the smallest index that keeps value an integer ≤ 255.
                let mut value = u64::from(cycle_ns);
                let mut index: i64 = -9;
                while value % 10 == 0 && index < 0 {
                    value /= 10;
                    index += 1;
                }
                if value > 255 {
                    return Err(refuse());
                }
                out.push(SyncWrite {
                    address: ObjectAddress::new(0x60C2, 1),
                    value: value as i64,
                    why: "interpolation time period value",
                });
                out.push(SyncWrite {
                    address: ObjectAddress::new(0x60C2, 2),
                    value: index,
                    why: "interpolation time index (power of ten of seconds)",
                });
            }
        }
        Ok(out)
    }
}

impl DriveProfile {
    /// Whether a device with this vendor ID and product code is this drive type.
    pub const fn matches(&self, vendor_id: u32, product_code: u32) -> bool {
        self.bus.identity.matches(vendor_id, product_code)
    }

    /// A view over the dictionary (type inference, mapping checks).
    pub const fn od(&self) -> crate::od::Dictionary<'static> {
        crate::od::Dictionary::new(self.dictionary)
    }

    /// Decode a 0x603F / EMCY error code with the drive's alarm table first.
    pub fn describe_error(&self, code: u16) -> crate::cia402::ErrorDescription {
        crate::cia402::ErrorCode(code).describe(self.caps.error_table)
    }

    /// Whether the profile carries an ESI file (the generic profile does not).
    pub fn has_esi(&self) -> bool {
        !self.esi.is_empty()
    }

    /// The drive's ESI file, parsed; `None` for a profile without one.
    pub fn esi_file(&self) -> Option<Result<crate::esi::EsiFile, crate::esi::EsiError>> {
        self.has_esi().then(|| crate::esi::EsiFile::parse(self.esi))
    }

    /// The writes for the synchronisation set-up (see [`SyncSpec::writes`]).
    pub fn sync_writes(&self, cycle_ns: u32, dc: bool) -> Result<Vec<SyncWrite>, CycleTimeError> {
        self.sync.writes(self.name, cycle_ns, dc)
    }
}

impl PartialEq for DriveProfile {
    /// Profiles are equal when they are for the same drive type (same key).
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
    }
}
