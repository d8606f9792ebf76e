//! Start-up: from power-on to a group in SAFE-OP with DC running, ready for the cycle.
//!
//! 1. **Discover** the segment (ethercrab init: addresses, SII, DC delays, PRE-OP) and match
//!    every device to a drive profile by identity. Unknown devices are reported with their
//!    identity and only run with the generic CiA 402 profile when the configuration allows it.
//! 2. **Validate** the whole configuration (mappings against each drive's limits and
//!    dictionary, cycle time against each drive's allowed cycles) **before anything is
//!    written**.
//! 3. **Configure in PRE-OP** per drive over CoE: PDO assignment and mapping, synchronisation
//!    type and cycle time (0x1C32 or 0x60C2, per profile), start-up SDOs, mode of operation.
//! 4. **Process image**: ethercrab sizes SyncManagers and FMMUs from the mapping; ecdrive checks
//!    each drive's image size against its mapping and resolves every field once.
//! 5. **DC**: enable SYNC0, wait until every drive's system-time difference (0x092C) is below
//!    the threshold (naming the drive that does not settle), start SYNC0, go to SAFE-OP.
//!
//! Every failure names the drive, the object or register, and the reason.

use super::bus::{Bus, Discovery, MAILBOXES_AT_ONCE, MAX_PDI, MAX_SUBDEVICES, SessionError};
use super::coe::{CoeClient, CoeError};
use super::error::{DriveRef, ErrorKind, MasterError, bus_error};
use super::exec::exec_error;
use super::program::{RunMode, Step};
use crate::drives::{CycleTimeObject, DriveProfile, InitCommand, ModeSelector, StartupWhen};
use crate::ec::{AlState, AlStatusCode, register};
use crate::link::FrameLink;
use crate::od::{self, DataType, ObjectAddress, Value};
use crate::pdo::{self, AxisBinding, Direction, Field, Layout, Mapping, RemapOptions};
use ethercrab::subdevice_group::{DcConfiguration, HasDc, PreOp, SafeOp};
use ethercrab::{Command, DcSync, DefaultLock, SubDeviceGroup};
use std::time::Duration;

/// The group in a given state.
pub type Group<S, DC = ethercrab::subdevice_group::NoDc> =
    SubDeviceGroup<MAX_SUBDEVICES, MAX_PDI, DefaultLock, S, DC>;

/// How a configuration entry picks its device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Selector {
    /// By position on the segment (0 = first).
    Position(u16),
    /// By configured station alias (0x0012, from the SII).
    Alias(u16),
    /// The first not yet selected device with this vendor ID and product code.
    Identity {
        /// Vendor ID.
        vendor_id: u32,
        /// Product code.
        product_code: u32,
    },
}

impl core::fmt::Display for Selector {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Selector::Position(p) => write!(f, "position {p}"),
            Selector::Alias(a) => write!(f, "alias {a}"),
            Selector::Identity {
                vendor_id,
                product_code,
            } => write!(f, "vendor 0x{vendor_id:08X} product 0x{product_code:08X}"),
        }
    }
}

/// User units of one drive: program values and limits are multiplied by `counts_per_unit`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UserUnits {
    /// Unit name (`deg`, `mm`).
    pub name: String,
    /// Position counts per unit.
    pub counts_per_unit: f64,
}

/// How one drive is to be configured and run.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveSetup {
    /// Which device.
    pub select: Selector,
    /// Force a profile instead of matching by identity (e.g. the generic CiA 402 profile).
    pub profile: Option<&'static DriveProfile>,
    /// Mode of operation at start.
    pub mode: RunMode,
    /// PDO mapping; `None` = the profile's recommended cyclic mapping.
    pub mapping: Option<Mapping>,
    /// Extra start-up SDOs, written after the profile's.
    pub sdos: Vec<(ObjectAddress, Value)>,
    /// Master-side following-error limit (position units); `None` = no master-side check.
    pub following_error_limit: Option<u32>,
    /// Limits the application's set-points must keep ([`crate::app::CycleApp`]; programs are
    /// checked against the configuration's limits when it is read).
    pub limits: crate::app::SetpointLimits,
    /// The user's units, for messages (a following error is then also said in them).
    pub units: Option<UserUnits>,
    /// The set-point program.
    pub program: Vec<Step>,
    /// Touch probes the application arms ([`crate::AppAxis::arm_probe`]): mapped at start-up
    /// like a program's `TouchProbe` steps (0x60B8, 0x60B9 and the probe's position object).
    pub probes: Vec<(u8, super::program::ProbeEdge)>,
    /// The drive's ESI file describes several devices and the configuration does not say
    /// which (`esi = "FILE"` with a position or an alias): the profile of each of them, and
    /// start-up takes the one whose identity the device reports (the same revision first).
    pub esi_choices: Vec<&'static DriveProfile>,
}

impl DriveSetup {
    /// The defaults for a device: csp, the profile's cyclic mapping, no program.
    pub fn new(select: Selector) -> Self {
        Self {
            select,
            profile: None,
            mode: RunMode::Csp,
            mapping: None,
            sdos: Vec::new(),
            following_error_limit: None,
            limits: crate::app::SetpointLimits::default(),
            units: None,
            program: Vec::new(),
            probes: Vec::new(),
            esi_choices: Vec::new(),
        }
    }
}

/// Distributed-clock settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DcSettings {
    /// When the master sends its frame, after the SYNC0 instant. `None`: half a cycle, so the
    /// outputs reach every drive well before its next SYNC0 whatever the wake-up jitter (with
    /// a shift near 0 or a whole cycle, jitter moves frames across SYNC0 and drives count the
    /// cycles they miss).
    pub shift: Option<Duration>,
    /// From reading the reference clock to the first SYNC0. ethercrab computes one start time
    /// for every drive from that reading and then configures the drives one after the other;
    /// a drive configured after the start time has passed would wait for its ESC's clock to
    /// wrap, so start-up arms it again with a later start time on the same grid (up to three
    /// times, the margin doubled each time) and fails naming this setting only after that.
    /// `None`: \[REC\] 0.5 ms plus 0.15 ms per drive with DC (a drive's SYNC0 set-up is four
    /// writes one after the other, about 0.1 ms a drive over veth at 64 drives; SOEM and IgH
    /// use a fixed 100 ms).
    pub start_delay: Option<Duration>,
    /// The system-time difference every drive must get below before SYNC0 starts, ns.
    pub settle_threshold_ns: u32,
    /// Checks in a row, each after one more drift-compensation frame, that must find every
    /// drive below the threshold (\[REC\] 3: one check could catch a clock passing through
    /// zero on its way to the other side).
    pub settle_checks: u32,
    /// How long to wait for it.
    pub settle_timeout: Duration,
}

impl DcSettings {
    /// The start delay for `dc_drives` drives with DC: the configured one or the default.
    pub fn start_delay_for(&self, dc_drives: usize) -> Duration {
        self.start_delay
            .unwrap_or(Duration::from_micros(500 + 150 * dc_drives as u64))
    }
}

impl Default for DcSettings {
    fn default() -> Self {
        Self {
            shift: None,
            start_delay: None,
            settle_threshold_ns: 1000,
            settle_checks: 3,
            settle_timeout: Duration::from_secs(5),
        }
    }
}

/// The profile of `d` among profiles built from ESI files: the same identity and revision,
/// else the same identity unless the files describe `d`'s revision as no drive (`not_drives`:
/// vendor, product, revision).
pub fn esi_profile_for(
    profiles: &[&'static DriveProfile],
    not_drives: &[(u32, u32, u32)],
    d: &DeviceInfo,
) -> Option<&'static DriveProfile> {
    let same = |p: &&&'static DriveProfile| p.identity.matches(d.vendor_id, d.product_code);
    profiles
        .iter()
        .filter(same)
        .find(|p| p.revision == d.revision)
        .or_else(|| {
            if not_drives.contains(&(d.vendor_id, d.product_code, d.revision)) {
                None
            } else {
                profiles.iter().find(same)
            }
        })
        .copied()
}

/// The start-up configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct StartupConfig {
    /// The cycle time.
    pub cycle: Duration,
    /// Distributed clocks. Required by drives whose profile has no free run.
    pub dc: DcSettings,
    /// Per-drive configuration. Devices without an entry run with the defaults of their
    /// profile ([`DriveSetup::new`]).
    pub drives: Vec<DriveSetup>,
    /// Run unknown devices with the generic CiA 402 profile
    /// ([`crate::drives::generic::GENERIC_CIA402`]); only when the user asks for it.
    pub allow_generic: bool,
    /// Profiles built from vendor ESI files (`ecdrive run --esi DIR`,
    /// [`crate::drives::esi_profile::load_dir`]): a device no built-in profile matches is
    /// matched against these by identity (the same revision first, then any).
    pub esi_profiles: Vec<&'static DriveProfile>,
    /// The devices the same ESI files describe that are no drives (vendor, product,
    /// revision): never given a drive profile of another revision.
    pub esi_not_drives: Vec<(u32, u32, u32)>,
}

impl StartupConfig {
    /// Defaults: the given cycle, DC with default settings, all devices by profile.
    pub fn new(cycle: Duration) -> Self {
        Self {
            cycle,
            dc: DcSettings::default(),
            drives: Vec::new(),
            allow_generic: false,
            esi_profiles: Vec::new(),
            esi_not_drives: Vec::new(),
        }
    }
}

/// What discovery learned about one device.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct DeviceInfo {
    /// Position on the segment.
    pub position: u16,
    /// Configured station address (0x1000 + position).
    pub address: u16,
    /// Station alias.
    pub alias: u16,
    /// The SII name.
    pub name: String,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// Whether the ESC supports distributed clocks.
    pub dc: bool,
    /// The matched profile's name, if any.
    pub profile: Option<&'static str>,
    /// Whether the SII announces a CoE mailbox (standard mailbox sizes and protocol CoE):
    /// ecdrive speaks CoE only to such devices.
    pub coe: bool,
    /// The device type (0x1000), read over CoE from devices no profile matches; the low 16
    /// bits are the device profile (0x0192 = 402: a CiA 402 drive).
    pub device_type: Option<u32>,
    /// The AL status the device had when discovery found it, before ecdrive reset it to INIT
    /// (a device left in SAFEOP+ERR by an earlier master shows it here); `None` if it did not
    /// answer the read.
    pub found: Option<FoundState>,
}

/// A device's AL status (0x0130) and AL status code (0x0134) as discovery found them, read by
/// position before anything was written to the segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct FoundState {
    /// AL status.
    pub status: crate::ec::AlStatus,
    /// AL status code (meaningful when the error flag is set).
    pub code: crate::ec::AlStatusCode,
}

impl DeviceInfo {
    /// Whether the device says it is a CiA 402 drive: a known drive profile, or device type
    /// 0x….0192.
    pub fn declares_cia402(&self) -> bool {
        self.profile.is_some() || self.device_type.is_some_and(|t| t & 0xFFFF == 402)
    }

    /// How messages name it.
    pub fn drive_ref(&self) -> DriveRef {
        DriveRef {
            position: self.position,
            name: self
                .profile
                .map_or_else(|| self.name.clone(), str::to_string),
        }
    }
}

/// Resolved process-image fields of one drive. Outputs are in the drive's output (RxPDO)
/// image, inputs in its input (TxPDO) image. Resolved once; used every cycle.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveFields {
    /// The CiA 402 objects (the binding both buses use); the controlword and the statusword
    /// are always mapped.
    pub axis: AxisBinding,
    /// The profile's cycle counter (output) and its echo (input).
    pub counter: Option<(Field, Option<Field>)>,
    /// Outputs that carry a fixed value from the first cycle on.
    pub output_defaults: Vec<(Field, i64)>,
    /// Mapped outputs the master does not drive (a limit, an offset): they carry the raw value
    /// the drive holds at the end of the PRE-OP configuration (its own, or a start-up value),
    /// so that mapping an object does not set it to 0.
    pub held_outputs: Vec<(Field, u64)>,
    /// The touch-probe objects, where mapped.
    pub probe: ProbeFields,
}

/// The touch-probe objects of one drive (CiA 402 0x60B8–0x60BD), where mapped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ProbeFields {
    /// 0x60B8 Touch probe function (output).
    pub function: Option<Field>,
    /// 0x60B9 Touch probe status (input).
    pub status: Option<Field>,
    /// The latched positions: 0x60BA (probe 1 rising), 0x60BB (probe 1 falling), 0x60BC
    /// (probe 2 rising), 0x60BD (probe 2 falling) (inputs).
    pub positions: [Option<Field>; 4],
}

/// The touch-probe function object (0x60B8).
pub const PROBE_FUNCTION: ObjectAddress = ObjectAddress::new(0x60B8, 0);
/// The touch-probe status object (0x60B9).
pub const PROBE_STATUS: ObjectAddress = ObjectAddress::new(0x60B9, 0);

/// The object holding the position latched by `probe` (1 or 2) on `edge`: 0x60BA–0x60BD.
pub const fn probe_position_object(probe: u8, edge: crate::program::ProbeEdge) -> ObjectAddress {
    let rising = matches!(edge, crate::program::ProbeEdge::Rising);
    ObjectAddress::new(
        match (probe, rising) {
            (1, true) => 0x60BA,
            (1, false) => 0x60BB,
            (_, true) => 0x60BC,
            (_, false) => 0x60BD,
        },
        0,
    )
}

/// One drive after start-up.
#[derive(Debug, Clone)]
pub struct ConfiguredDrive {
    /// What discovery learned.
    pub info: DeviceInfo,
    /// How messages name it.
    pub drive: DriveRef,
    /// Its profile.
    pub profile: &'static DriveProfile,
    /// The mapping configured.
    pub mapping: Mapping,
    /// Its layout.
    pub layout: Layout,
    /// Resolved fields.
    pub fields: DriveFields,
    /// Its setup.
    pub setup: DriveSetup,
    /// The DC system time of its first SYNC0 (ns), as its slave controller holds it (0x0990);
    /// `None` without DC. The cycle requests OP only after the drives have seen SYNC0 run
    /// (MR-J4-TM manual §1.4.2 (7): DC synchronisation is established in SAFE-OP, then valid
    /// command values, then OP).
    pub sync0_start_ns: Option<u64>,
}

/// The DC system time from which OP may be requested: `cycles` SYNC0 cycles of `cycle_ns`
/// after the last drive's first SYNC0 ([`ConfiguredDrive::sync0_start_ns`]); 0 without DC.
pub fn op_not_before_dc(drives: &[ConfiguredDrive], cycles: u32, cycle_ns: u64) -> u64 {
    drives
        .iter()
        .filter_map(|d| d.sync0_start_ns)
        .max()
        .map_or(0, |s| s.saturating_add(u64::from(cycles) * cycle_ns))
}

/// A device that is not driven ([`Role::Io`]): in OP with its own PDO configuration, its
/// process data exchanged every cycle.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfiguredIo {
    /// What discovery learned.
    pub info: DeviceInfo,
    /// Output bytes (master → device).
    pub outputs: usize,
    /// Input bytes (device → master).
    pub inputs: usize,
    /// Why it is not driven.
    pub why: String,
}

/// Where start-up's time went, in milliseconds of wall time, phase by phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct StartupTimes {
    /// Discovery: ethercrab's initialisation (station addresses, the SII of every device, DC
    /// propagation delays, mailboxes, INIT → PRE-OP) and each device's identity.
    pub discovery_ms: f64,
    /// Within discovery, from the first to the last SII (EEPROM) access on the wire (ethercrab
    /// measures the DC propagation delays and requests PRE-OP in between).
    pub sii_ms: f64,
    /// CoE configuration of the drives: PDO mapping and assignment, synchronisation objects,
    /// start-up SDOs, read-backs, the mailbox drain.
    pub coe_ms: f64,
    /// The process image: ethercrab's FMMU and SyncManager set-up and the drives' fields.
    pub image_ms: f64,
    /// Waiting for the distributed clocks to settle (measured, not slept).
    pub dc_settle_ms: f64,
    /// Starting SYNC0, PRE-OP → SAFE-OP, and the checks of read-only cycle times.
    pub safe_op_ms: f64,
    /// SAFE-OP → OP: from SAFE-OP (the cycle thread's start, its SYNC0 cycles of valid
    /// outputs, the OP request) until the cycle saw every device report OP (`None` until
    /// then, or when the caller did not go to OP).
    pub op_ms: Option<f64>,
    /// From the start of discovery to SAFE-OP (to OP when `op_ms` is known).
    pub total_ms: f64,
    /// Frames sent in each phase: what the wire had to carry, whatever a frame's round trip
    /// costs on the link at hand.
    pub frames: StartupFrames,
    /// Drives whose SYNC0 start time had passed before they were configured, armed again with
    /// a later one on the same grid (counted once per arming).
    pub sync0_rearmed: usize,
    /// When SAFE-OP was reached (monotonic ns): where `op_ms` counts from.
    #[serde(skip)]
    pub safe_op_at_ns: u64,
}

/// Frames sent in each phase of start-up (first transmissions; SAFE-OP → OP is the cycle's,
/// one frame per cycle plus the OP requests).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct StartupFrames {
    /// Discovery.
    pub discovery: u64,
    /// Of discovery's, frames with an SII (EEPROM) access.
    pub sii: u64,
    /// CoE configuration.
    pub coe: u64,
    /// The process image.
    pub image: u64,
    /// DC settle.
    pub dc_settle: u64,
    /// Starting SYNC0 and PRE-OP → SAFE-OP.
    pub safe_op: u64,
    /// Of ethercrab's frames in discovery, those answered from the SII ecdrive read at once
    /// (not sent, not counted above; [`crate::answers`]).
    pub answered_discovery: u64,
    /// Of ethercrab's frames while it built the process image, those answered from the PDO
    /// configuration the drives acknowledged (not sent, not counted above).
    pub answered_image: u64,
}

impl StartupTimes {
    /// Record that every device reached OP now (the first time only).
    pub fn reached_op(&mut self, now_ns: u64) {
        if self.op_ms.is_none() {
            let op = now_ns.saturating_sub(self.safe_op_at_ns) as f64 / 1e6;
            self.op_ms = Some(op);
            self.total_ms += op;
        }
    }
}

fn ms_since(t0: u64) -> f64 {
    crate::rt::monotonic_ns().saturating_sub(t0) as f64 / 1e6
}

/// The result of start-up: the group in SAFE-OP with DC running, and the drives.
pub struct Started {
    /// The group.
    pub group: Group<SafeOp, HasDc>,
    /// The drives, in segment order.
    pub drives: Vec<ConfiguredDrive>,
    /// The devices that are not driven, in segment order.
    pub io: Vec<ConfiguredIo>,
    /// Every device found, in segment order.
    pub devices: Vec<DeviceInfo>,
    /// What start-up accepted but the user should know (a drive without 0x1C32, a read-only
    /// cycle time), per drive.
    pub warnings: Vec<(DriveRef, String)>,
    /// Where the time went (discovery is filled by [`configure`] from what [`discover`] noted
    /// on the bus, [`Bus::discovery`]).
    pub times: StartupTimes,
}

const T_INIT: Duration = Duration::from_secs(30);
const T_STEP: Duration = Duration::from_secs(10);

/// Discover the segment: ethercrab init (addresses, SII, DC delays, mailboxes, PRE-OP), then
/// each device's identity and matching profile.
pub fn discover<L: FrameLink>(
    bus: &mut Bus<'_, L>,
) -> Result<(Group<PreOp>, Vec<DeviceInfo>), MasterError> {
    let t0 = crate::rt::monotonic_ns();
    let f0 = bus.pump().stats().sent;
    let a0 = bus.pump().stats().answered;
    let _ = bus.pump_mut().take_sii_span();
    let link = bus.pump().link_name();
    let lost = |bus: &mut Bus<'_, L>, e: super::exec::ExecError| match e {
        // The very first frames got no reply: nothing on this interface speaks EtherCAT.
        super::exec::ExecError::FrameLost { .. } => {
            let echoes = bus.pump().stats().echoes;
            MasterError::new(
                None,
                format!("discovering the segment on {link}"),
                ErrorKind::Discovery,
                if echoes > 0 {
                    "no EtherCAT device answered: the frames came back unprocessed (a \
                     loopback or a switch, not an EtherCAT segment?)"
                        .to_string()
                } else {
                    "no EtherCAT device answered (is the segment connected and powered?)"
                        .to_string()
                },
            )
        }
        e => exec_error(None, e),
    };
    // Each device's state as found, by position (auto-increment addressing: ethercrab's `aprd`
    // takes the position and negates it), before ethercrab resets the segment; until a
    // position no device answers. Eight positions at a time, their frames in flight together.
    let mut found: Vec<FoundState> = Vec::new();
    'probe: for first in (0..MAX_SUBDEVICES as u16).step_by(MAILBOXES_AT_ONCE) {
        let last = (first + MAILBOXES_AT_ONCE as u16).min(MAX_SUBDEVICES as u16);
        let states = bus
            .block_on_each(
                &|| format!("discovering the segment on {link}: reading each device's AL status"),
                T_STEP,
                (first..last).collect(),
                async |md, i| {
                    ethercrab::Command::aprd(i, crate::ec::register::AL_STATUS)
                        .receive::<[u8; 6]>(md)
                        .await
                },
            )
            .map_err(|e| lost(bus, e))?;
        for b in states {
            let Ok(b) = b else { break 'probe };
            found.push(FoundState {
                status: crate::ec::AlStatus {
                    raw: u16::from_le_bytes([b[0], b[1]]),
                },
                code: crate::ec::AlStatusCode(u16::from_le_bytes([b[4], b[5]])),
            });
        }
    }
    // Every device's SII at once, to answer ethercrab's reads of it (`crate::answers`).
    if bus.options().answer_rereads && !found.is_empty() {
        read_sii_at_once(bus, found.len()).map_err(|e| lost(bus, e))?;
    }
    let group = bus
        .block_on(
            &|| format!("discovering the segment on {link}"),
            T_INIT,
            |md| md.init_single_group::<MAX_SUBDEVICES, MAX_PDI>(ethercrab::std::ethercat_now),
        )
        .map_err(|e| lost(bus, e))?
        .map_err(|e| {
            let kind = if matches!(e, ethercrab::error::Error::NotFound { .. }) {
                ErrorKind::Discovery
            } else {
                ErrorKind::Bus
            };
            MasterError::new(None, format!("discovering the segment on {link}"), kind, e)
        })?;
    if group.is_empty() {
        return Err(MasterError::new(
            None,
            format!("discovering the segment on {link}"),
            ErrorKind::Discovery,
            "no EtherCAT device answered",
        ));
    }
    let mut devices = Vec::with_capacity(group.len());
    for (i, sd) in group.iter(bus.md()).enumerate() {
        let id = sd.identity();
        devices.push(DeviceInfo {
            position: i as u16,
            address: sd.configured_address(),
            alias: sd.alias_address(),
            name: sd.name().to_string(),
            vendor_id: id.vendor_id,
            product_code: id.product_id,
            revision: id.revision,
            serial: id.serial,
            dc: sd.dc_support().any(),
            profile: crate::drives::by_identity(id.vendor_id, id.product_id).map(|p| p.name),
            coe: false,
            device_type: None,
            found: found.get(i).copied(),
        });
    }
    // The mailbox from the SII (words 0x18–0x1C: receive/send mailbox offset and size, the
    // protocols), eight devices at a time; then, for devices no profile matches, their device
    // type over CoE.
    let words = bus
        .block_on_each(
            &|| "reading the SII mailbox words (0x18–0x1C) of every device".into(),
            T_STEP,
            (0..devices.len()).collect(),
            async |md, pos| {
                let sd = group.subdevice(md, pos)?;
                let mut buf = [0u8; 10];
                sd.eeprom_read_raw(md, 0x18, &mut buf).await?;
                Ok::<_, ethercrab::error::Error>(buf)
            },
        )
        .map_err(|e| exec_error(None, e))?;
    for (d, words) in devices.iter_mut().zip(words) {
        let words = words
            .map_err(|e| bus_error(Some(&d.drive_ref()), "reading the SII mailbox words", e))?;
        let w = |i: usize| u16::from_le_bytes([words[2 * i], words[2 * i + 1]]);
        d.coe = w(1) > 0 && w(3) > 0 && w(4) & 0x0004 != 0;
        if d.coe && d.profile.is_none() {
            d.device_type = bus
                .with_coe(d.address, d.drive_ref(), false, T_STEP, async |c| {
                    c.upload(ObjectAddress::new(0x1000, 0), false).await
                })
                .ok()
                .filter(|v| v.len() >= 4)
                .map(|v| u32::from_le_bytes([v[0], v[1], v[2], v[3]]));
        }
    }
    // The answers wait for the process image (a tool that reads the SII itself reads the wire).
    let answers = bus.pump_mut().set_answers(None);
    bus.stash_answers(answers);
    let sii = bus.pump_mut().take_sii_span();
    bus.set_discovery(Discovery {
        answered: bus.pump().stats().answered - a0,
        ms: ms_since(t0),
        sii_ms: sii.map_or(0.0, |(a, b, _)| b.saturating_sub(a) as f64 / 1e6),
        frames: bus.pump().stats().sent - f0,
        sii_frames: sii.map_or(0, |(_, _, n)| n),
    });
    Ok((group, devices))
}

/// Read the SII of the `n` devices at once and answer ethercrab's SII reads from it
/// ([`crate::sii_bulk`], [`crate::answers`]).
fn read_sii_at_once<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    n: usize,
) -> Result<(), super::exec::ExecError> {
    let link = bus.pump().link_name();
    let n = u16::try_from(n).unwrap_or(u16::MAX);
    let t0 = crate::rt::monotonic_ns();
    let deadline = t0 + T_STEP.as_nanos() as u64;
    let (words, frames) =
        crate::sii_bulk::read_sii_all(bus.pump_mut(), n, deadline).map_err(|source| {
            super::exec::ExecError::Link {
                what: format!("reading the SII of every device on {link}"),
                source,
            }
        })?;
    tracing::debug!(
        "the SII of {n} devices read at once in {frames} frames, {:.1} ms: {:?} words",
        ms_since(t0),
        words.iter().map(|w| w.len()).collect::<Vec<_>>()
    );
    bus.pump_mut()
        .set_answers(Some(crate::answers::Answers::new(words)));
    Ok(())
}

/// What start-up does with a device.
#[derive(Debug, Clone, PartialEq)]
pub enum Role {
    /// Driven through CiA 402 with this setup and profile.
    Drive {
        /// The setup (from the configuration, or the profile's defaults; boxed: the `Io` role
        /// is small).
        setup: Box<DriveSetup>,
        /// The profile.
        profile: &'static DriveProfile,
    },
    /// Not driven: taken to OP with its own PDO configuration (SII or default mapping), its
    /// process data exchanged. ecdrive's only request to its mailbox is the read of its device
    /// type (0x1000, when no profile matches); it reads out waiting emergencies before ethercrab
    /// reads the PDO assignment. A device without a mailbox gets no mailbox traffic at all.
    Io {
        /// Why it is not driven, in words.
        why: String,
    },
}

impl Role {
    /// The drive's setup and profile, if it is one.
    pub fn drive(&self) -> Option<(&DriveSetup, &'static DriveProfile)> {
        match self {
            Role::Drive { setup, profile } => Some((setup, profile)),
            Role::Io { .. } => None,
        }
    }
}

/// A configuration that does not fit the segment found (no drive of its own to name).
fn matching_error(why: String) -> MasterError {
    MasterError::new(
        None,
        "matching the configuration to the segment",
        ErrorKind::Config,
        why,
    )
}

/// Entries that select by identity take the matching devices in line order, one each: an
/// identity that more devices match (besides those other entries name by position or alias)
/// than entries select by it would leave the choice to the line order silently (a second
/// MR-J4-TM, and the first one moves). Refused, naming them.
fn ambiguous_identities(devices: &[DeviceInfo], cfg: &StartupConfig) -> Result<(), MasterError> {
    for setup in &cfg.drives {
        let Selector::Identity { .. } = setup.select else {
            continue;
        };
        let entries = cfg
            .drives
            .iter()
            .filter(|s| s.select == setup.select)
            .count();
        // Devices another entry names by position or alias are not in question.
        let named = |d: &DeviceInfo| {
            cfg.drives
                .iter()
                .any(|s| !matches!(s.select, Selector::Identity { .. }) && selects(s.select, d))
        };
        let matching: Vec<&DeviceInfo> = devices
            .iter()
            .filter(|d| selects(setup.select, d) && !named(d))
            .collect();
        if matching.len() > entries {
            return Err(matching_error(format!(
                "{} matches {} devices ({}) but {} [[drive]] {} by it: select each by \
                     position or alias (entries by identity take the matching devices in line \
                     order, one each)",
                setup.select,
                matching.len(),
                matching
                    .iter()
                    .map(|d| format!("{} {}", d.position, d.name))
                    .collect::<Vec<_>>()
                    .join(", "),
                entries,
                if entries == 1 {
                    "entry selects"
                } else {
                    "entries select"
                }
            )));
        }
    }
    Ok(())
}

/// The device each `[[drive]]` entry selects (by position, alias, or identity in line order,
/// one each), or why an entry selects none or one another entry took.
fn choose(
    devices: &[DeviceInfo],
    cfg: &StartupConfig,
) -> Result<Vec<Option<DriveSetup>>, MasterError> {
    ambiguous_identities(devices, cfg)?;
    let mut chosen: Vec<Option<DriveSetup>> = vec![None; devices.len()];
    for setup in &cfg.drives {
        let pos = devices
            .iter()
            .position(|d| chosen[d.position as usize].is_none() && selects(setup.select, d));
        if pos.is_none()
            && let Some(taken) = devices.iter().find(|d| selects(setup.select, d))
        {
            // The device is there, but another entry took it (a position and an identity that
            // select the same drive).
            return Err(matching_error(format!(
                "{} selects device {} ({}), which an earlier [[drive]] entry already \
                     selects: one entry per device",
                setup.select, taken.position, taken.name
            )));
        }
        let Some(pos) = pos else {
            return Err(matching_error(format!(
                "no device on the segment matches {} ({} device(s) found: {})",
                setup.select,
                devices.len(),
                devices
                    .iter()
                    .map(|d| format!("{} {}", d.position, d.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        };
        chosen[pos] = Some(setup.clone());
    }
    Ok(chosen)
}

/// Decide what to do with every device: a drive (a setup and a profile) or an I/O device.
///
/// A device is driven when a profile matches its identity, when the configuration forces a
/// profile (which must match its identity; the generic CiA 402 profile only a device that does
/// not declare another device profile), or when `allow_generic` is set and it declares CiA 402
/// (device type 0x….0192). Every other device is an I/O device. Fails on setups that select
/// nothing, on a device the configuration names that cannot be driven, and on a forced profile
/// that does not fit.
pub fn assign_roles(devices: &[DeviceInfo], cfg: &StartupConfig) -> Result<Vec<Role>, MasterError> {
    let chosen = choose(devices, cfg)?;
    let mut out = Vec::with_capacity(devices.len());
    for (d, setup) in devices.iter().zip(chosen) {
        let named = setup.is_some();
        let setup = setup.unwrap_or_else(|| DriveSetup::new(Selector::Position(d.position)));
        let dref = DriveRef {
            position: d.position,
            name: d.name.clone(),
        };
        let generic = &crate::drives::generic::GENERIC_CIA402;
        let profile = match setup.profile {
            Some(p) if core::ptr::eq(p, generic) || p.key == generic.key => {
                if !d.coe {
                    return Err(MasterError::new(
                        Some(&dref),
                        "matching a drive profile",
                        ErrorKind::Config,
                        "the configuration runs it with the generic CiA 402 profile, but it has \
                         no CoE mailbox",
                    ));
                }
                if !d.declares_cia402() && d.device_type.is_some() {
                    return Err(MasterError::new(
                        Some(&dref),
                        "matching a drive profile",
                        ErrorKind::Config,
                        format!(
                            "the configuration runs it with the generic CiA 402 profile, but its \
                             device type 0x1000 is 0x{:08X} (profile {}, not 402)",
                            d.device_type.unwrap_or(0),
                            d.device_type.unwrap_or(0) & 0xFFFF
                        ),
                    ));
                }
                p
            }
            Some(p) => {
                if p.identity.vendor_id != d.vendor_id || p.identity.product_code != d.product_code
                {
                    return Err(MasterError::new(
                        Some(&dref),
                        "matching a drive profile",
                        ErrorKind::Config,
                        format!(
                            "the configuration forces the {} profile (vendor 0x{:08X}, product \
                             0x{:08X}), but the device is vendor 0x{:08X}, product 0x{:08X} \
                             ({:?}); {}",
                            p.name,
                            p.identity.vendor_id,
                            p.identity.product_code,
                            d.vendor_id,
                            d.product_code,
                            d.name,
                            match crate::drives::by_identity(d.vendor_id, d.product_code) {
                                Some(own) => format!(
                                    "it is a {}: give profile = \"{}\", or leave profile out",
                                    own.name, own.key
                                ),
                                None => "use the generic-cia402 profile for a drive ecdrive has \
                                         no profile for"
                                    .to_string(),
                            }
                        ),
                    ));
                }
                p
            }
            // The drive's own ESI file, when it names one: nothing else may stand in for it.
            None if !setup.esi_choices.is_empty() => esi_profile_for(&setup.esi_choices, &[], d)
                .ok_or_else(|| esi_choice_error(&dref, d, &setup.esi_choices))?,
            None => match crate::drives::by_identity(d.vendor_id, d.product_code)
                .or_else(|| esi_profile_for(&cfg.esi_profiles, &cfg.esi_not_drives, d))
            {
                Some(p) => p,
                None if cfg.allow_generic && d.declares_cia402() => generic,
                None if named => {
                    // The configuration names it as a drive: say why it cannot run it.
                    let e = crate::drives::identify(d.vendor_id, d.product_code, d.revision, false)
                        .err()
                        .map(|e| e.to_string())
                        .unwrap_or_default();
                    let why = if !d.coe {
                        "it has no CoE mailbox, so it is no CiA 402 drive".to_string()
                    } else if d.declares_cia402() {
                        "it declares CiA 402 (device type 0x….0192): allow_generic = true runs it \
                         with the generic CiA 402 profile"
                            .to_string()
                    } else {
                        format!(
                            "its device type is {}, not a CiA 402 drive",
                            d.device_type
                                .map_or("unreadable".into(), |t| format!("0x{t:08X}"))
                        )
                    };
                    return Err(MasterError::new(
                        Some(&dref),
                        "matching a drive profile",
                        ErrorKind::UnknownDevice,
                        format!("{e} (serial {}); {why}", d.serial),
                    ));
                }
                None => {
                    out.push(Role::Io { why: io_reason(d) });
                    continue;
                }
            },
        };
        out.push(Role::Drive {
            setup: Box::new(setup),
            profile,
        });
    }
    Ok(out)
}

/// Whether `sel` selects device `d`.
fn selects(sel: Selector, d: &DeviceInfo) -> bool {
    match sel {
        Selector::Position(p) => d.position == p,
        Selector::Alias(a) => d.alias == a && a != 0,
        Selector::Identity {
            vendor_id,
            product_code,
        } => d.vendor_id == vendor_id && d.product_code == product_code,
    }
}

/// Why a device no profile matches is an I/O device, in words.
fn io_reason(d: &DeviceInfo) -> String {
    if !d.coe {
        "no mailbox".to_string()
    } else if d.declares_cia402() {
        "a CiA 402 device ecdrive has no profile for (allow_generic = true runs it with the \
         generic CiA 402 profile)"
            .to_string()
    } else {
        format!(
            "not a CiA 402 drive (device type {})",
            d.device_type
                .map_or("unreadable".into(), |t| format!("0x{t:08X}"))
        )
    }
}

/// The device at a drive's position is none of those its ESI file describes.
fn esi_choice_error(
    dref: &DriveRef,
    d: &DeviceInfo,
    choices: &[&'static DriveProfile],
) -> MasterError {
    let list: Vec<String> = choices
        .iter()
        .map(|p| {
            format!(
                "{} (product 0x{:08X}, revision 0x{:08X})",
                p.name, p.identity.product_code, p.revision
            )
        })
        .collect();
    MasterError::new(
        Some(dref),
        "matching the drive's ESI file",
        ErrorKind::Config,
        format!(
            "the device there is vendor 0x{:08X}, product 0x{:08X}, revision 0x{:08X}; the \
             drive's ESI file describes {}",
            d.vendor_id,
            d.product_code,
            d.revision,
            list.join(", ")
        ),
    )
}

/// Check every drive's configuration against its profile before anything is written.
pub fn validate(
    drives: &[(&DeviceInfo, &DriveSetup, &'static DriveProfile)],
    cfg: &StartupConfig,
) -> Result<Vec<Mapping>, MasterError> {
    let cycle_ns = u32::try_from(cfg.cycle.as_nanos()).unwrap_or(u32::MAX);
    let mut mappings = Vec::with_capacity(drives.len());
    for &(d, setup, profile) in drives {
        let drive = DriveRef {
            position: d.position,
            name: profile.name.to_string(),
        };
        if !profile.sync.cycle_times.contains(cycle_ns) {
            return Err(MasterError::new(
                Some(&drive),
                "checking the cycle time",
                ErrorKind::Config,
                format!(
                    "{} µs is not a cycle time the {} accepts ({})",
                    cycle_ns / 1000,
                    profile.name,
                    profile.sync.cycle_times.describe()
                ),
            ));
        }
        if !profile.sync.dc_sync0 {
            return Err(MasterError::new(
                Some(&drive),
                "checking the synchronisation",
                ErrorKind::Config,
                format!("the {} does not support DC SYNC0", profile.name),
            ));
        }
        if !d.dc {
            return Err(MasterError::new(
                Some(&drive),
                "checking the synchronisation",
                ErrorKind::Config,
                "the device's ESC reports no distributed-clock support",
            ));
        }
        let mapping = mapping_for_program(setup, profile)
            .map_err(|(what, e)| MasterError::new(Some(&drive), what, ErrorKind::Config, e))?;
        pdo::limits::validate(&mapping, &profile.pdo_limits, Some(profile.dictionary)).map_err(
            |e| {
                MasterError::new(
                    Some(&drive),
                    "checking the PDO mapping",
                    ErrorKind::Config,
                    e,
                )
            },
        )?;
        if Layout::new(&mapping).bytes(Direction::Rx) == 0 {
            return Err(MasterError::new(
                Some(&drive),
                "checking the PDO mapping",
                ErrorKind::Config,
                "the RxPDO mapping is empty",
            ));
        }
        super::program::validate(&setup.program, setup.mode).map_err(|e| {
            MasterError::new(Some(&drive), "checking the program", ErrorKind::Config, e)
        })?;
        mappings.push(mapping);
    }
    Ok(mappings)
}

/// The mapping a drive runs its program with, checked against the modes the program uses:
/// every mode must be one the drive supports, and its objects (the profile's table of objects
/// per mode, else the controlword, statusword and the mode's set-point) must be mapped. A
/// program that arms a touch probe needs 0x60B8 out and 0x60B9 plus the latched positions in:
/// with the profile's own mapping they are added (in the same PDO while the drive allows,
/// else in the next free one); a mapping of the user's must carry them. The error is
/// (what was being checked, why).
fn mapping_for_program(
    setup: &DriveSetup,
    profile: &'static DriveProfile,
) -> Result<Mapping, (&'static str, String)> {
    if let Some((n, t, range)) = super::program::pp_target_beyond(&setup.program, &profile.caps) {
        return Err((
            "checking the program",
            format!(
                "step {n} (pp) writes {t} counts to 0x607A, beyond what the drive takes: {}",
                range.source
            ),
        ));
    }
    let modes = super::program::modes_used(&setup.program, setup.mode);
    for &code in &modes {
        let mode = crate::cia402::OperationMode::from_i8(code);
        if !profile.caps.supported_modes.contains(mode) {
            return Err((
                "checking the mode of operation",
                format!(
                    "the {} does not support {}{}",
                    profile.name,
                    mode.short_name(),
                    if code == setup.mode.code() {
                        ""
                    } else {
                        ", which the program uses"
                    }
                ),
            ));
        }
    }
    let mut probes = super::program::probes_used(&setup.program);
    for &p in &setup.probes {
        if !probes.contains(&p) {
            probes.push(p);
        }
    }
    let mut need: Vec<(Direction, ObjectAddress)> = Vec::new();
    if !probes.is_empty() {
        need.push((Direction::Rx, PROBE_FUNCTION));
        need.push((Direction::Tx, PROBE_STATUS));
        for &(probe, edge) in &probes {
            need.push((Direction::Tx, probe_position_object(probe, edge)));
        }
    }
    let mapping = match &setup.mapping {
        Some(m) => m.clone(),
        None => {
            let base = profile
                .mapping_for_modes(&modes)
                .map_err(|e| ("choosing the PDO mapping", e.to_string()))?;
            with_objects(base, &need, profile).map_err(|e| {
                (
                    "choosing the PDO mapping",
                    format!("the touch probe needs {e}"),
                )
            })?
        }
    };
    if let Some((dir, e)) = mapped_twice(&mapping) {
        return Err((
            "checking the PDO mapping",
            format!(
                "0x{:04X}:{:02X} is mapped twice in the {}: each object once (two values for \
                 one object in a cycle leave the drive to pick one)",
                e.index,
                e.sub,
                dir.name()
            ),
        ));
    }
    for (dir, addr, what) in [
        (Direction::Rx, CW, "the controlword 0x6040"),
        (Direction::Tx, SW, "the statusword 0x6041"),
    ] {
        if !mapping.contains(dir, addr) {
            return Err((
                "checking the PDO mapping",
                format!("{what} ({addr}) must be mapped in the {}", dir.name()),
            ));
        }
    }
    for &code in &modes {
        match pdo::limits::RequiredObjects::find(profile.required_objects, code) {
            Some(req) => req
                .check(&mapping, profile.name)
                .map_err(|e| ("checking the PDO mapping", e.to_string()))?,
            None => {
                if let Some(m) = RunMode::from_code(code) {
                    let addr = setpoint_object(m);
                    if !mapping.contains(Direction::Rx, addr) {
                        return Err((
                            "checking the PDO mapping",
                            format!(
                                "the set-point of {} ({addr}) must be mapped in the {}",
                                m.name(),
                                Direction::Rx.name()
                            ),
                        ));
                    }
                }
            }
        }
    }
    for &(dir, addr) in &need {
        if !mapping.contains(dir, addr) {
            return Err((
                "checking the PDO mapping",
                format!(
                    "the program arms a touch probe: {addr} must be mapped in the {}",
                    dir.name()
                ),
            ));
        }
    }
    Ok(mapping)
}

/// The first object a mapping maps twice in the RxPDOs, if any (\[REC\]: two values for one
/// object in a cycle leave the drive to pick one; a copy in the TxPDOs only costs bytes).
fn mapped_twice(m: &Mapping) -> Option<(Direction, pdo::PdoEntry)> {
    let all: Vec<&pdo::PdoEntry> =
        m.rx.iter()
            .flat_map(|p| p.entries.iter())
            .filter(|e| e.index != 0)
            .collect();
    all.iter()
        .enumerate()
        .find(|(i, e)| {
            all[..*i]
                .iter()
                .any(|x| x.index == e.index && x.sub == e.sub)
        })
        .map(|(_, e)| (Direction::Rx, **e))
}

/// `base` with the objects of `need` it lacks added: in the last PDO of their direction while
/// the drive's limits allow, else in new PDOs at the first free indices of a writable range,
/// else in the last PDO in place of inputs the cycle can do without ([`DROPPABLE`]). The error
/// names the objects that do not fit.
fn with_objects(
    base: &Mapping,
    need: &[(Direction, ObjectAddress)],
    profile: &DriveProfile,
) -> Result<Mapping, String> {
    let dict = od::Dictionary::new(profile.dictionary);
    let mut out = base.clone();
    for dir in [Direction::Rx, Direction::Tx] {
        let mut entries = Vec::new();
        for &(d, addr) in need {
            if d != dir || base.contains(dir, addr) {
                continue;
            }
            let bits = dict
                .data_type(addr)
                .or_else(|| pdo::axis::standard_type(addr))
                .and_then(|t| t.bit_len())
                .ok_or_else(|| format!("{addr}, which the {} dictionary lacks", profile.name))?;
            entries.push(pdo::PdoEntry::new(addr.index, addr.sub, bits as u8));
        }
        if entries.is_empty() {
            continue;
        }
        let fits = |m: &Mapping| {
            pdo::limits::validate(m, &profile.pdo_limits, Some(profile.dictionary)).is_ok()
        };
        let mut pdos = out.pdos(dir).to_vec();
        // In the last PDO.
        if let Some(last) = pdos.last() {
            let mut e = last.entries.to_vec();
            e.extend(entries.iter().copied());
            let mut grown = pdos.clone();
            if let Some(l) = grown.last_mut() {
                *l = pdo::Pdo::owned(l.index, e);
            }
            let trial = set_pdos(&out, dir, grown);
            if fits(&trial) {
                out = trial;
                continue;
            }
        }
        // In new PDOs, as many entries each as the range allows.
        let limits = profile.pdo_limits.direction(dir);
        let used: Vec<u16> = pdos.iter().map(|p| p.index).collect();
        let mut free = limits
            .pdos
            .iter()
            .filter(|r| r.mapping_writable)
            .flat_map(|r| r.indices().map(move |i| (i, r.max_entries)))
            .filter(|(i, _)| !used.contains(i));
        let mut rest = entries.as_slice();
        while !rest.is_empty() {
            let Some((index, max)) = free.next() else {
                break;
            };
            let (now, later) = rest.split_at(usize::from(max).min(rest.len()));
            pdos.push(pdo::Pdo::owned(index, now.to_vec()));
            rest = later;
        }
        let trial = set_pdos(&out, dir, pdos);
        if rest.is_empty() && fits(&trial) {
            out = trial;
            continue;
        }
        // In the last PDO, in place of inputs the cycle can do without (the drive's own
        // following error, the torque, the error code, in that order), as few as it takes.
        let pdos = out.pdos(dir).to_vec();
        if let Some(last) = pdos.last() {
            let mut e: Vec<pdo::PdoEntry> = last.entries.to_vec();
            for drop in DROPPABLE {
                if dir != Direction::Tx {
                    break;
                }
                e.retain(|x| x.address() != drop);
                let mut grown = pdos.clone();
                if let Some(l) = grown.last_mut() {
                    let mut with = e.clone();
                    with.extend(entries.iter().copied());
                    *l = pdo::Pdo::owned(l.index, with);
                }
                let trial = set_pdos(&out, dir, grown);
                if fits(&trial) {
                    out = trial;
                    break;
                }
            }
            if entries.iter().all(|x| out.contains(dir, x.address())) {
                continue;
            }
        }
        let names: Vec<String> = entries.iter().map(|e| e.address().to_string()).collect();
        return Err(format!(
            "{} in the {}, and the {}'s mapping has no room for them: give a mapping that \
             carries them",
            names.join(", "),
            dir.name(),
            profile.name
        ));
    }
    Ok(out)
}

/// Inputs of a profile's mapping the cycle can do without, in the order they give way to
/// objects a program needs: the drive's following error 0x60F4 (the master computes its own),
/// the torque actual value 0x6077 (telemetry only), the error code 0x603F (the fault is still
/// seen in the statusword, and read by SDO).
const DROPPABLE: [ObjectAddress; 3] = [
    ObjectAddress::new(0x60F4, 0),
    ObjectAddress::new(0x6077, 0),
    ObjectAddress::new(0x603F, 0),
];

fn set_pdos(m: &Mapping, dir: Direction, pdos: Vec<pdo::Pdo>) -> Mapping {
    match dir {
        Direction::Rx => Mapping::owned(pdos, m.tx.to_vec()),
        Direction::Tx => Mapping::owned(m.rx.to_vec(), pdos),
    }
}

const CW: ObjectAddress = ObjectAddress::new(0x6040, 0);
const SW: ObjectAddress = ObjectAddress::new(0x6041, 0);
const MODE: ObjectAddress = ObjectAddress::new(0x6060, 0);

fn setpoint_object(mode: RunMode) -> ObjectAddress {
    match mode {
        RunMode::Csp | RunMode::Pp => ObjectAddress::new(0x607A, 0),
        RunMode::Csv | RunMode::Pv => ObjectAddress::new(0x60FF, 0),
        RunMode::Cst | RunMode::Tq => ObjectAddress::new(0x6071, 0),
        RunMode::Ip => ObjectAddress::new(0x60C1, 1),
    }
}

/// Encode a value for an object using the profile's dictionary for the type.
fn encode(profile: &DriveProfile, addr: ObjectAddress, v: &Value) -> Result<Vec<u8>, String> {
    let dict = od::Dictionary::new(profile.dictionary);
    let dt = dict
        .data_type(addr)
        .ok_or_else(|| format!("{addr} is not in the {} dictionary", profile.name))?;
    v.encode(dt).map_err(|e| e.to_string())
}

/// A mapped output the cycle does not drive, and its value read before it was mapped (or why
/// it could not be read).
type HeldValue = (ObjectAddress, Result<Vec<u8>, String>);

/// What a synchronisation-object write sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SyncWhat {
    /// 0x1C32:01 synchronisation type.
    Type,
    /// 0x1C32:02 cycle time, ns.
    CycleTime,
}

/// One synchronisation object to set (ETG.1020).
#[derive(Debug, Clone, Copy)]
struct SyncWrite {
    address: ObjectAddress,
    value: u32,
    len: usize,
    what: SyncWhat,
}

impl SyncWrite {
    fn describe(&self) -> String {
        match self.what {
            SyncWhat::Type => "synchronisation type = DC SYNC0 (2)".into(),
            SyncWhat::CycleTime => format!("cycle time = {} ns", self.value),
        }
    }

    fn bytes(&self) -> Vec<u8> {
        self.value.to_le_bytes()[..self.len.min(4)].to_vec()
    }
}

/// The ETG.1020 names of 0x1C32:01 values.
fn sync_type_name(v: u32) -> &'static str {
    match v {
        0 => "free run",
        1 => "synchronous with the SM2 event",
        2 => "DC SYNC0",
        3 => "DC SYNC1",
        34 => "synchronous with the SM3 event",
        _ => "unknown",
    }
}

/// How a drive took a synchronisation object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SyncOutcome {
    /// It already held the value: nothing written.
    AlreadySet,
    /// Written.
    Written,
    /// The drive has no such object.
    Absent,
    /// The drive refused the write as read-only (or not writable now): what it holds, and for
    /// the cycle time its minimum cycle time (0x1C32:05), where readable.
    ReadOnly {
        has: Option<u32>,
        min_cycle: Option<u32>,
    },
}

fn le_u32(b: &[u8]) -> u32 {
    let mut v = [0u8; 4];
    for (d, s) in v.iter_mut().zip(b) {
        *d = *s;
    }
    u32::from_le_bytes(v)
}

/// Set a synchronisation object the way a careful engineer does on a drive they did not
/// write: read it first and write only when it differs; a drive without the object, or one
/// that refuses the write as read-only, is not an error by itself (see [`SyncOutcome::judge`]).
/// 0x60C2 on a drive with a vendor reading of one index ([`CycleTimeObject::InterpolationFixedIndex`]):
/// 0x60C2:02 is read first; the standard form is written (index, then value), as the drive's
/// own set-up example does; where 0x60C2:02 cannot be changed and holds the vendor's index,
/// 0x60C2:01 is written in the vendor's unit. `Ok(Err(why))` when neither form can tell the
/// cycle.
async fn write_interpolation(
    c: &mut super::coe::CoeClient<'_>,
    cycle_ns: u32,
    unit_ns: u32,
    vendor: i8,
) -> Result<Result<String, String>, super::coe::CoeError> {
    use crate::od::SdoAbortCode as A;
    let index_at = ObjectAddress::new(0x60C2, 2);
    let value_at = ObjectAddress::new(0x60C2, 1);
    let has = c
        .upload(index_at, false)
        .await
        .ok()
        .and_then(|v| v.first().map(|b| *b as i8));
    if let Some((value, index)) = crate::drives::interpolation_standard_form(cycle_ns, Some(vendor))
    {
        let set = if has == Some(index) {
            Ok(())
        } else {
            c.download(index_at, &[index as u8], false).await
        };
        // A value beyond the drive's range (the BDHDE takes 1–64: 750 µs is 75 × 10^−5 s)
        // falls back to the vendor's unit, as a refused index does.
        let set = match set {
            Ok(()) => c.download(value_at, &[value], false).await,
            Err(e) => Err(e),
        };
        match set {
            Ok(()) => {
                return Ok(Ok(format!("{value} × 10^{index} s")));
            }
            Err(e)
                if matches!(
                    e.abort_code(),
                    Some(
                        A::READ_ONLY
                            | A::UNSUPPORTED_ACCESS
                            | A::VALUE_RANGE
                            | A::VALUE_TOO_HIGH
                            | A::VALUE_TOO_LOW
                    )
                ) => {}
            Err(e) => return Err(e),
        }
    }
    // The vendor's unit: with its index in 0x60C2:02 (set back if the drive takes it; it may
    // have taken the standard form's index above before refusing the value).
    let vendor_index = has.is_some()
        && (c.download(index_at, &[vendor as u8], false).await.is_ok()
            || (has == Some(vendor)
                && c.upload(index_at, false)
                    .await
                    .ok()
                    .and_then(|v| v.first().map(|b| *b as i8))
                    == Some(vendor)));
    if vendor_index
        && unit_ns > 0
        && cycle_ns % unit_ns == 0
        && let Ok(v) = u8::try_from(cycle_ns / unit_ns)
    {
        c.download(value_at, &[v], false).await?;
        return Ok(Ok(format!(
            "{v} × {} µs (0x60C2:02 = {vendor}, the drive's own unit)",
            unit_ns / 1000
        )));
    }
    Ok(Err(format!(
        "0x60C2:02 {} and does not take the standard form: a cycle of {cycle_ns} ns cannot be \
         told",
        has.map_or("cannot be read".to_string(), |h| format!("holds {h}"))
    )))
}

async fn write_sync(
    c: &mut super::coe::CoeClient<'_>,
    w: &SyncWrite,
) -> Result<SyncOutcome, super::coe::CoeError> {
    use crate::od::SdoAbortCode as A;
    let absent =
        |e: &super::coe::CoeError| matches!(e.abort_code(), Some(A::NO_OBJECT | A::NO_SUBINDEX));
    let has = match c.upload(w.address, false).await {
        Ok(v) => Some(le_u32(&v)),
        Err(e) if absent(&e) => return Ok(SyncOutcome::Absent),
        Err(e) if e.abort_code().is_some() => None,
        Err(e) => return Err(e),
    };
    if has == Some(w.value) {
        return Ok(SyncOutcome::AlreadySet);
    }
    match c.download(w.address, &w.bytes(), false).await {
        Ok(()) => Ok(SyncOutcome::Written),
        Err(e) if absent(&e) => Ok(SyncOutcome::Absent),
        Err(e)
            if matches!(
                e.abort_code(),
                Some(
                    A::READ_ONLY
                        | A::UNSUPPORTED_ACCESS
                        | A::CANNOT_STORE
                        | A::LOCAL_CONTROL
                        | A::DEVICE_STATE
                )
            ) =>
        {
            let min_cycle = if w.what == SyncWhat::CycleTime {
                c.upload(ObjectAddress::new(w.address.index, 5), false)
                    .await
                    .ok()
                    .map(|v| le_u32(&v))
                    .filter(|m| *m > 0)
            } else {
                None
            };
            Ok(SyncOutcome::ReadOnly { has, min_cycle })
        }
        Err(e) => Err(e),
    }
}

impl SyncOutcome {
    /// Whether the run can go on: `Ok(None)` silently, `Ok(Some(warning))`, or `Err(why)`
    /// naming the value the drive has and the value needed.
    fn judge(&self, w: &SyncWrite, profile: &DriveProfile) -> Result<Option<String>, String> {
        let a = w.address;
        match (*self, w.what) {
            (SyncOutcome::AlreadySet | SyncOutcome::Written, _) => Ok(None),
            (SyncOutcome::Absent, _) => Ok(Some(format!(
                "has no {a} (which the {} profile names for the {}); taken to synchronise to \
                 SYNC0 by its slave-controller registers alone",
                profile.name,
                match w.what {
                    SyncWhat::Type => "synchronisation type",
                    SyncWhat::CycleTime => "cycle time",
                }
            ))),
            (SyncOutcome::ReadOnly { has: Some(v), .. }, SyncWhat::Type) => Err(format!(
                "{a} is read-only and holds {v} ({}); DC SYNC0 needs 2",
                sync_type_name(v)
            )),
            (SyncOutcome::ReadOnly { has: None, .. }, SyncWhat::Type) => Ok(Some(format!(
                "{a} (synchronisation type) can be neither read nor written; continuing with DC \
                 SYNC0"
            ))),
            (SyncOutcome::ReadOnly { has, min_cycle }, SyncWhat::CycleTime) => {
                let holds = has.map_or("cannot be read".to_string(), |v| format!("holds {v} ns"));
                if let Some(m) = min_cycle
                    && w.value < m
                {
                    return Err(format!(
                        "{a} (cycle time) is read-only ({holds}) and the drive's minimum cycle \
                         time 0x{:04X}:05 is {m} ns; the cycle needs {} ns",
                        a.index, w.value
                    ));
                }
                Ok(Some(format!(
                    "{a} (cycle time) is read-only ({holds}): the drive takes its cycle from \
                     SYNC0 (ETG.1020); checked again once SYNC0 runs"
                )))
            }
        }
    }
}

/// Read a device's PDO assignment and mapping over CoE (0x1C12/0x1C13, 0x16xx/0x1Axx); `what`
/// names the step in errors.
pub fn read_mapping<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    address: u16,
    drive: &DriveRef,
    what: &str,
) -> Result<Mapping, MasterError> {
    crate::pdo::read_mapping_sync(|a: ObjectAddress, dt: DataType| {
        let bytes = bus.with_coe(address, drive.clone(), false, T_STEP, async |c| {
            c.upload(a, false).await
        })?;
        let v = Value::decode(dt, &bytes).map_err(|e| {
            super::bus::SessionError::Coe(super::coe::CoeError {
                drive: drive.clone(),
                address: Some(a),
                kind: super::coe::CoeErrorKind::Protocol(e.to_string()),
            })
        })?;
        match v {
            Value::Uint(u) => u32::try_from(u).map_err(|_| {
                super::bus::SessionError::Coe(super::coe::CoeError {
                    drive: drive.clone(),
                    address: Some(a),
                    kind: super::coe::CoeErrorKind::Protocol(format!("{u} does not fit 32 bits")),
                })
            }),
            other => Err(super::bus::SessionError::Coe(super::coe::CoeError {
                drive: drive.clone(),
                address: Some(a),
                kind: super::coe::CoeErrorKind::Protocol(format!("unexpected value {other}")),
            })),
        }
    })
    .map_err(|e| match e {
        crate::pdo::ReadbackError::Upload { source, .. } => {
            let mut e = MasterError::from(source);
            e.step = format!("{what}: {}", e.step);
            e
        }
        other => MasterError::new(Some(drive), what, ErrorKind::Bus, other),
    })
}

/// Drives on the generic CiA 402 profile whose configuration gives no mapping: a drive ecdrive
/// has no profile for has a mapping of its own, and its PDOs accept what its dictionary says,
/// not what a profile assumes. Read the drive's current mapping (0x1C12/0x1C13, 0x16xx/0x1Axx);
/// when it carries the controlword, the statusword and the set-point of the start mode, use it
/// unchanged (no remap); otherwise map the smallest standard set the drive has (controlword,
/// set-point, mode; statusword, actual position, mode display) into its first PDO of each
/// direction. Returns the positions of the drives that keep their own mapping.
fn generic_mappings<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    devices: &[DeviceInfo],
    plan: &mut [Role],
    warnings: &mut Vec<(DriveRef, String)>,
) -> Result<Vec<u16>, MasterError> {
    let generic = &crate::drives::generic::GENERIC_CIA402;
    let mut own = Vec::new();
    for (d, role) in devices.iter().zip(plan.iter_mut()) {
        let Role::Drive { setup, profile } = role else {
            continue;
        };
        if profile.key != generic.key || setup.mapping.is_some() {
            continue;
        }
        let drive = DriveRef {
            position: d.position,
            name: profile.name.to_string(),
        };
        if !d.coe {
            return Err(MasterError::new(
                Some(&drive),
                "reading the PDO mapping",
                ErrorKind::Config,
                "the device has no CoE mailbox: it cannot be run as a CiA 402 drive",
            ));
        }
        let addr = d.address;
        let current = read_mapping(
            bus,
            addr,
            &drive,
            "reading the PDO mapping (generic profile)",
        )?;
        let setpoint = setpoint_object(setup.mode);
        if current.contains(Direction::Rx, CW)
            && current.contains(Direction::Tx, SW)
            && current.contains(Direction::Rx, setpoint)
        {
            warnings.push((
                drive,
                format!(
                    "runs with the generic CiA 402 profile on its own PDO mapping ({} output, {} \
                     input bytes)",
                    Layout::new(&current).bytes(Direction::Rx),
                    Layout::new(&current).bytes(Direction::Tx)
                ),
            ));
            setup.mapping = Some(current);
            own.push(d.position);
            continue;
        }
        // The smallest standard mapping of what the drive has.
        let mut exists = |a: ObjectAddress| -> Result<bool, MasterError> {
            match bus.with_coe(addr, drive.clone(), false, T_STEP, async |c| {
                c.upload(a, false).await
            }) {
                Ok(_) => Ok(true),
                Err(super::bus::SessionError::Coe(e)) if e.abort_code().is_some() => Ok(false),
                Err(e) => Err(e.into()),
            }
        };
        let entry = |a: ObjectAddress| {
            let bits = pdo::axis::standard_type(a)
                .and_then(DataType::bit_len)
                .unwrap_or(32)
                .min(64) as u8;
            crate::pdo::PdoEntry::new(a.index, a.sub, bits)
        };
        let mut rx = vec![entry(CW), entry(setpoint)];
        if exists(MODE)? {
            rx.push(entry(MODE));
        }
        let mut tx = vec![entry(SW)];
        for a in [ObjectAddress::new(0x6064, 0), ObjectAddress::new(0x6061, 0)] {
            if exists(a)? {
                tx.push(entry(a));
            }
        }
        let rx_index = current
            .pdos(Direction::Rx)
            .first()
            .map_or(0x1600, |p| p.index);
        let tx_index = current
            .pdos(Direction::Tx)
            .first()
            .map_or(0x1A00, |p| p.index);
        let m = Mapping::owned(
            vec![crate::pdo::Pdo::owned(rx_index, rx)],
            vec![crate::pdo::Pdo::owned(tx_index, tx)],
        );
        warnings.push((
            drive,
            format!(
                "runs with the generic CiA 402 profile; its own mapping lacks what {} needs, so \
                 ecdrive maps the standard minimum ({} output, {} input bytes)",
                setup.mode.name(),
                Layout::new(&m).bytes(Direction::Rx),
                Layout::new(&m).bytes(Direction::Tx)
            ),
        ));
        setup.mapping = Some(m);
    }
    Ok(own)
}

/// Configure every drive in PRE-OP (mapping, sync, start-up SDOs, mode), build the process
/// image, run DC to SAFE-OP. `devices`/`plan` come from [`discover`] and [`assign_roles`].
pub fn configure<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    mut group: Group<PreOp>,
    devices: Vec<DeviceInfo>,
    mut plan: Vec<Role>,
    cfg: &StartupConfig,
) -> Result<Started, MasterError> {
    let mut warnings: Vec<(DriveRef, String)> = Vec::new();
    let found = bus.discovery().unwrap_or_default();
    let mut times = StartupTimes {
        discovery_ms: found.ms,
        sii_ms: found.sii_ms,
        frames: StartupFrames {
            discovery: found.frames,
            sii: found.sii_frames,
            answered_discovery: found.answered,
            ..StartupFrames::default()
        },
        ..StartupTimes::default()
    };
    let sent = |bus: &Bus<'_, L>| bus.pump().stats().sent;
    let f_coe = sent(bus);
    let t_coe = crate::rt::monotonic_ns();
    // Drives on the generic profile without a mapping in the configuration: their own mapping
    // when it carries what the mode needs, else the smallest standard one they have.
    let own = generic_mappings(bus, &devices, &mut plan, &mut warnings)?;
    let drives_plan: Vec<(&DeviceInfo, &DriveSetup, &'static DriveProfile)> = devices
        .iter()
        .zip(&plan)
        .filter_map(|(d, r)| r.drive().map(|(s, p)| (d, s, p)))
        .collect();
    let mappings = validate(&drives_plan, cfg)?;
    let cycle_ns = u32::try_from(cfg.cycle.as_nanos()).unwrap_or(u32::MAX);
    // Read-only cycle times, checked again once SYNC0 runs.
    let mut recheck: Vec<(u16, DriveRef, ObjectAddress)> = Vec::new();
    // Per drive: the values of the mapped outputs the cycle does not drive.
    let mut held_values: Vec<Vec<HeldValue>> = Vec::new();
    let mut plans: Vec<(DriveRef, DriveWrites)> = Vec::new();
    for (&(d, setup, profile), mapping) in drives_plan.iter().zip(&mappings) {
        let drive = DriveRef {
            position: d.position,
            name: profile.name.to_string(),
        };
        let writes = DriveWrites::plan(
            &drive,
            setup,
            profile,
            mapping,
            !own.contains(&d.position),
            cycle_ns,
        )?;
        plans.push((drive, writes));
    }
    // The drives' mailboxes, several at once (each drive's own writes in order).
    let jobs = plans
        .iter()
        .zip(&drives_plan)
        .map(|((drive, w), (d, _, p))| (d.address, drive.clone(), p.complete_access, w))
        .collect();
    let done = bus
        .with_coe_each(jobs, T_STEP, async |c, w: &DriveWrites| {
            configure_mailbox(c, w, cycle_ns).await
        })
        .map_err(MasterError::from)?;
    for (((drive, writes), (d, _, profile)), r) in plans.iter().zip(&drives_plan).zip(done) {
        let held = judge_drive(d, drive, profile, writes, r, &mut warnings, &mut recheck)?;
        held_values.push(held);
    }
    // The InitCmds for SAFE-OP → OP, sent once the drives are in SAFE-OP.
    let so_jobs: Vec<(u16, DriveRef, bool, &[&'static InitCommand])> = plans
        .iter()
        .zip(&drives_plan)
        .filter(|((_, w), _)| !w.init_so.is_empty())
        .map(|((drive, w), (d, _, p))| {
            (d.address, drive.clone(), p.complete_access, &w.init_so[..])
        })
        .collect();

    // SYNC0 on every drive; the SYNC0 start itself comes with `configure_dc_sync`. I/O devices
    // run free (SM-synchronous): the process data frame updates them.
    let driven: Vec<u16> = drives_plan.iter().map(|(d, _, _)| d.position).collect();
    for (i, mut sd) in group.iter_mut(bus.md()).enumerate() {
        if driven.contains(&(i as u16)) {
            sd.set_dc_sync(DcSync::Sync0);
        }
    }

    drain_mailboxes(bus, &devices, &drives_plan)?;

    times.coe_ms = ms_since(t_coe);
    times.frames.coe = sent(bus) - f_coe;
    let f_image = sent(bus);
    let t_image = crate::rt::monotonic_ns();
    let acknowledged = plans.iter().zip(&drives_plan).map(|((_, w), (d, _, _))| {
        let remap = w.writes.iter().take(w.remap_len);
        (d.address, remap.map(|(o, b, _)| (*o, b.as_slice())))
    });
    let (group, answered) = build_image_answered(bus, group, &devices, acknowledged);
    times.frames.answered_image = answered;
    let group = group?;
    let mut drives = resolve_drives(bus, &group, drives_plan, mappings, held_values)?;
    // The I/O devices: their images as ethercrab sized them from their own configuration.
    let mut io = Vec::new();
    for (d, r) in devices.iter().zip(&plan) {
        let Role::Io { why } = r else { continue };
        let sd = group
            .subdevice(bus.md(), d.position as usize)
            .map_err(|e| bus_error(Some(&d.drive_ref()), "reading the process image", e))?;
        let img = sd.io_raw();
        io.push(ConfiguredIo {
            info: d.clone(),
            outputs: img.outputs().len(),
            inputs: img.inputs().len(),
            why: why.clone(),
        });
    }

    enable_process_data_sms(bus, &devices, &mut warnings)?;
    times.image_ms = ms_since(t_image);
    times.frames.image = sent(bus) - f_image;
    let group = to_safe_op(bus, group, &mut drives, cfg, &mut times)?;
    send_so_init_cmds(bus, so_jobs)?;
    recheck_cycle_times(bus, recheck, cfg, &mut warnings)?;
    times.safe_op_at_ns = crate::rt::monotonic_ns();
    times.safe_op_ms = times.safe_op_at_ns.saturating_sub(t_image) as f64 / 1e6
        - times.image_ms
        - times.dc_settle_ms;
    times.total_ms =
        times.discovery_ms + times.coe_ms + times.image_ms + times.dc_settle_ms + times.safe_op_ms;
    Ok(Started {
        group,
        drives,
        io,
        devices,
        warnings,
        times,
    })
}

/// Drain the mailbox of every device with CoE (drives and CoE I/O devices): ethercrab reads
/// the PDO configuration through its own SDO client, which panics if an emergency is waiting
/// (ethercrab 0.7.1). Draining only reads what is waiting; a device without a mailbox gets
/// nothing.
fn drain_mailboxes<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    devices: &[DeviceInfo],
    drives_plan: &[(&DeviceInfo, &DriveSetup, &'static DriveProfile)],
) -> Result<(), MasterError> {
    for d in devices.iter().filter(|d| d.coe) {
        let drive = drives_plan
            .iter()
            .find(|(x, _, _)| x.position == d.position)
            .map_or_else(
                || d.drive_ref(),
                |(_, _, p)| DriveRef {
                    position: d.position,
                    name: p.name.to_string(),
                },
            );
        bus.with_coe(d.address, drive, false, T_STEP, async |c| {
            c.drain().await.map(|_| ())
        })?;
    }
    Ok(())
}

/// What start-up writes to one drive in PRE-OP, in order, and what it reads back.
struct DriveWrites {
    /// Every SDO write: (object, bytes, why). The PDO remap comes first (`remap_len` of them).
    writes: Vec<(ObjectAddress, Vec<u8>, String)>,
    remap_len: usize,
    /// Synchronisation type and cycle time: read first, written only when different, and a
    /// drive that does not take them by SDO is checked for compatibility (`write_sync`).
    sync_writes: Vec<SyncWrite>,
    /// 0x60C2 with a vendor index: decided against what the drive holds
    /// (`write_interpolation`).
    interpolation: Option<(u32, i8)>,
    /// Start-up values of objects mapped as outputs: the drive gets them in every cycle.
    carried: Vec<(ObjectAddress, Vec<u8>)>,
    /// The mapped outputs the cycle does not drive: their values are read once every start-up
    /// value is written, and sent (`held_outputs`).
    undriven: Vec<ObjectAddress>,
    /// The ESI file's InitCmds for INIT → PRE-OP and PRE-OP → SAFE-OP, in file order, sent in
    /// PRE-OP right after the PDO remap (so the profile's and the user's values, written
    /// later, override those that are not `Fixed`).
    init_pre: Vec<&'static InitCommand>,
    /// Those for SAFE-OP → OP, sent once the drive is in SAFE-OP (`send_so_init_cmds`).
    init_so: Vec<&'static InitCommand>,
    /// The profile's mode selector and the modes the program uses: read and judged first.
    mode_selector: Option<(ModeSelector, Vec<i8>)>,
    /// The program's fastest step: (step index, motor revolutions per second), judged against
    /// the motor's maximum speed 0x6080 the drive reports.
    fastest: Option<(usize, f64)>,
}

impl DriveWrites {
    /// The writes for `drive` with `mapping` (installed by SDO when `remap`).
    fn plan(
        drive: &DriveRef,
        setup: &DriveSetup,
        profile: &'static DriveProfile,
        mapping: &Mapping,
        remap: bool,
        cycle_ns: u32,
    ) -> Result<Self, MasterError> {
        let mut w = Self {
            writes: Vec::new(),
            remap_len: 0,
            sync_writes: Vec::new(),
            interpolation: None,
            carried: Vec::new(),
            undriven: Vec::new(),
            init_pre: Vec::new(),
            init_so: Vec::new(),
            mode_selector: profile
                .mode_selector
                .map(|m| (m, super::program::modes_used(&setup.program, setup.mode))),
            // Only where the profile knows its position units per motor revolution (a profile
            // from an ESI file without a factor group or encoder resolution has 1: unknown).
            fastest: super::program::fastest_step(&setup.program, setup.mode)
                .filter(|_| profile.units.position_per_rev > 1.0)
                .map(|(n, counts_per_s)| (n, counts_per_s / profile.units.position_per_rev)),
        };
        w.plan_init_cmds(drive, setup, profile)?;
        if remap {
            let seq = pdo::remap_sequence(
                mapping,
                &RemapOptions::for_drive(
                    &profile.pdo_limits,
                    Some(od::Dictionary::new(profile.dictionary)),
                ),
            )
            .map_err(|e| {
                MasterError::new(Some(drive), "building the PDO remap", ErrorKind::Config, e)
            })?;
            for s in seq {
                w.writes.push((s.address, s.bytes(), s.description.clone()));
            }
        }
        w.remap_len = w.writes.len();
        w.plan_sync(profile, cycle_ns);
        w.plan_startup(drive, setup, profile, mapping)?;
        // Last, so that a start-up value written to such an object is what it keeps.
        let driven: Vec<ObjectAddress> = mapping
            .pdos(Direction::Rx)
            .iter()
            .flat_map(|p| p.entries.iter())
            .map(|e| e.address())
            .filter(|a| AxisBinding::drives(*a))
            .chain(profile.cycle_counter.map(|c| c.output))
            .chain(profile.output_defaults.iter().map(|o| o.address))
            .collect();
        w.undriven = mapping
            .pdos(Direction::Rx)
            .iter()
            .flat_map(|p| p.entries.iter())
            .filter(|e| !e.is_padding() && !driven.contains(&e.address()))
            .map(|e| e.address())
            .collect();
        Ok(w)
    }

    /// The ESI file's InitCmds by the state they are sent in. Those writing the PDO assignment
    /// or mapping objects are left out: the master writes the mapping it chose itself. A
    /// configuration value for the object of a `Fixed` one is refused.
    fn plan_init_cmds(
        &mut self,
        drive: &DriveRef,
        setup: &DriveSetup,
        profile: &'static DriveProfile,
    ) -> Result<(), MasterError> {
        use ecdrive_core::esi::Transition;
        for ic in profile.init_cmds {
            if ic.writes_mapping() {
                continue;
            }
            if ic.fixed && setup.sdos.iter().any(|(a, _)| *a == ic.address) {
                return Err(MasterError::new(
                    Some(drive),
                    format!("start-up SDO {}", ic.address),
                    ErrorKind::Config,
                    format!(
                        "the {} sets this object and is Fixed: the configuration may not \
                         write it",
                        ic.describe()
                    ),
                ));
            }
            if ic.at(Transition::IP) || ic.at(Transition::PS) {
                self.init_pre.push(ic);
            }
            if ic.at(Transition::SO) {
                self.init_so.push(ic);
            }
        }
        Ok(())
    }

    /// The synchronisation type and the cycle time, in whichever object the drive takes it.
    fn plan_sync(&mut self, profile: &DriveProfile, cycle_ns: u32) {
        let writes = &mut self.writes;
        let sync_writes = &mut self.sync_writes;
        let interpolation = &mut self.interpolation;
        if let Some(a) = profile.sync.sync_type_object {
            sync_writes.push(SyncWrite {
                address: a,
                value: 2,
                len: 2,
                what: SyncWhat::Type,
            });
        }
        match profile.sync.cycle_time_object {
            Some(CycleTimeObject::Nanoseconds(a)) => {
                sync_writes.push(SyncWrite {
                    address: a,
                    value: cycle_ns,
                    len: 4,
                    what: SyncWhat::CycleTime,
                });
            }
            Some(CycleTimeObject::InterpolationFixedIndex { unit_ns, index }) => {
                *interpolation = Some((unit_ns, index));
            }
            Some(CycleTimeObject::InterpolationStandard) => {
                // cycle = value × 10^index s, with the largest index that keeps value ≤ 255.
                let (mut value, mut index) = (u64::from(cycle_ns), -9i8);
                while value > 255 || (value % 10 == 0 && value > 0 && index < 0) {
                    if value % 10 != 0 && value <= 255 {
                        break;
                    }
                    value /= 10;
                    index += 1;
                }
                writes.push((
                    ObjectAddress::new(0x60C2, 1),
                    vec![value as u8],
                    "interpolation period value".into(),
                ));
                writes.push((
                    ObjectAddress::new(0x60C2, 2),
                    vec![index as u8],
                    "interpolation period index".into(),
                ));
            }
            None => {}
        }
    }

    /// The profile's start-up SDOs, the user's, and the mode when 0x6060 is not mapped.
    fn plan_startup(
        &mut self,
        drive: &DriveRef,
        setup: &DriveSetup,
        profile: &DriveProfile,
        mapping: &Mapping,
    ) -> Result<(), MasterError> {
        let writes = &mut self.writes;
        let carried = &mut self.carried;
        // Start-up SDOs of the profile, then the user's. A value whose object is mapped as an
        // output goes there instead (`carried`): the drive gets it in every cycle.
        for s in profile.startup {
            let mapped =
                s.when == StartupWhen::IfNotMapped && mapping.contains(Direction::Rx, s.address);
            let v = s.value.to_value().ok_or_else(|| {
                MasterError::new(
                    Some(drive),
                    format!("start-up SDO {}", s.address),
                    ErrorKind::Config,
                    "has no value",
                )
            })?;
            let bytes = encode(profile, s.address, &v).map_err(|e| {
                MasterError::new(
                    Some(drive),
                    format!("start-up SDO {}", s.address),
                    ErrorKind::Config,
                    e,
                )
            })?;
            if mapped {
                carried.push((s.address, bytes));
            } else {
                writes.push((s.address, bytes, s.why.to_string()));
            }
        }
        for (a, v) in &setup.sdos {
            let bytes = encode(profile, *a, v).map_err(|e| {
                MasterError::new(
                    Some(drive),
                    format!("start-up SDO {a}"),
                    ErrorKind::Config,
                    e,
                )
            })?;
            writes.push((*a, bytes, format!("user start-up value {v}")));
        }
        // Mode of operation: by SDO only when 0x6060 is not mapped.
        if !mapping.contains(Direction::Rx, MODE) {
            writes.push((
                MODE,
                vec![setup.mode.code() as u8],
                format!("mode of operation = {}", setup.mode.name()),
            ));
        }

        Ok(())
    }
}

/// What one drive's mailbox work in PRE-OP gave.
struct MailboxDone {
    outcomes: Vec<SyncOutcome>,
    interpolated: Option<Result<String, String>>,
    held: Vec<HeldValue>,
    /// The InitCmd that failed (after its retries) and why; nothing after it was written.
    init_failed: Option<(&'static InitCommand, CoeError)>,
    /// The mode selector's value does not allow the program's modes, or the program is faster
    /// than the motor: why (nothing was written).
    modes_refused: Option<(&'static str, String)>,
}

/// Whether the program's fastest step is within the motor's maximum speed 0x6080 as the drive
/// reports it (r/min in both manuals: MR-J4-TM "Max motor speed (6080h) … Operation cannot be
/// performed at a speed exceeding the speed set with this object. Unit: [r/min]"; BDHDE
/// "6080h – Motor Maximum Speed … Units rpm"). 0 or an object the drive does not have says
/// nothing.
fn judge_max_speed((step, rev_s): (usize, f64), raw: &[u8]) -> Result<(), String> {
    let mut b = [0u8; 4];
    for (d, s) in b.iter_mut().zip(raw) {
        *d = *s;
    }
    let max_rpm = u32::from_le_bytes(b);
    if max_rpm == 0 || rev_s * 60.0 <= f64::from(max_rpm) {
        return Ok(());
    }
    Err(format!(
        "program[{step}] commands {:.0} r/min ({rev_s:.1} rev/s), beyond the motor's maximum \
         speed 0x6080 = {max_rpm} r/min ({:.1} rev/s) that the drive reports: the drive cannot \
         run it (lower the step's velocity)",
        rev_s * 60.0,
        f64::from(max_rpm) / 60.0
    ))
}

/// Whether the mode selector's value allows every mode the program uses; `Err` says which
/// mode, the setting read, what it allows, and the setting that would.
fn judge_mode_selector(sel: &ModeSelector, modes: &[i8], raw: &[u8]) -> Result<(), String> {
    let mut b = [0u8; 8];
    for (d, s) in b.iter_mut().zip(raw) {
        *d = *s;
    }
    sel.judge(modes, i64::from_le_bytes(b))
}

/// Send one InitCmd with its own timeout, again after a timeout or a refusal as often as its
/// `<Retries>` say. The client's timeout is restored afterwards.
async fn send_init_cmd(c: &mut CoeClient<'_>, ic: &InitCommand) -> Result<(), CoeError> {
    let before = c.timeout();
    if let Some(ms) = ic.timeout_ms {
        c.set_timeout(Duration::from_millis(u64::from(ms)));
    }
    let mut r = Ok(());
    for attempt in 0..=ic.retries {
        r = c
            .download(ic.address, ic.data, ic.complete_access)
            .await
            .map(|_| ());
        match &r {
            Ok(()) => break,
            Err(e) if attempt < ic.retries => {
                tracing::info!(
                    "{}: {} failed ({}), sent again",
                    e.drive,
                    ic.describe(),
                    e.kind
                )
            }
            Err(_) => {}
        }
    }
    c.set_timeout(before);
    r
}

/// The InitCmds `cmds` in order; the first that fails ends the list.
async fn send_init_cmds(
    c: &mut CoeClient<'_>,
    cmds: &[&'static InitCommand],
) -> Result<Option<(&'static InitCommand, CoeError)>, CoeError> {
    for ic in cmds {
        match send_init_cmd(c, ic).await {
            Ok(()) => {}
            // A drive that stopped answering is a bus problem, not the command's.
            Err(e) if matches!(e.kind, crate::coe::CoeErrorKind::Bus(_)) => return Err(e),
            Err(e) => return Ok(Some((ic, e))),
        }
    }
    Ok(None)
}

/// The ESI files' InitCmds for SAFE-OP → OP, each drive's in file order, sent in SAFE-OP before
/// OP is requested.
fn send_so_init_cmds<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    jobs: Vec<(u16, DriveRef, bool, &[&'static InitCommand])>,
) -> Result<(), MasterError> {
    if jobs.is_empty() {
        return Ok(());
    }
    let drives: Vec<DriveRef> = jobs.iter().map(|j| j.1.clone()).collect();
    let done = bus
        .with_coe_each(jobs, T_STEP, async |c, cmds: &[&'static InitCommand]| {
            send_init_cmds(c, cmds).await
        })
        .map_err(MasterError::from)?;
    for (drive, r) in drives.iter().zip(done) {
        match r {
            Ok(None) => {}
            Ok(Some((ic, e))) => return Err(init_cmd_error(drive, ic, &e)),
            Err(e) => return Err(MasterError::from(SessionError::Coe(e))),
        }
    }
    Ok(())
}

/// The error for an InitCmd that failed: the drive, the object, the line, transitions and
/// comment from the file, and the drive's reason.
fn init_cmd_error(drive: &DriveRef, ic: &InitCommand, e: &CoeError) -> MasterError {
    let reason = match e.abort_code() {
        Some(code) => format!("refused: {code}"),
        None => e.kind.to_string(),
    };
    let tries = if ic.retries > 0 {
        format!(" (sent {} times)", u32::from(ic.retries) + 1)
    } else {
        String::new()
    };
    MasterError::new(
        Some(drive),
        format!("writing {} ({})", ic.address, ic.describe()),
        ErrorKind::Incompatible,
        format!("{reason}{tries}"),
    )
}

/// One drive's mailbox work in PRE-OP, in order: drain, the PDO remap, the synchronisation
/// objects, 0x60C2, the start-up values, then the values of the mapped outputs the cycle does
/// not drive (last, so that a start-up value written to such an object is what it keeps).
async fn configure_mailbox(
    c: &mut CoeClient<'_>,
    plan: &DriveWrites,
    cycle_ns: u32,
) -> Result<MailboxDone, CoeError> {
    let n_writes = plan.writes.len();
    let (pdo_writes, later) = plan.writes.split_at(plan.remap_len.min(n_writes));
    let mut done = MailboxDone {
        outcomes: Vec::new(),
        interpolated: None,
        held: Vec::new(),
        init_failed: None,
        modes_refused: None,
    };
    c.drain().await?;
    if let Some((sel, modes)) = &plan.mode_selector {
        let judged = match c.upload(sel.object, false).await {
            Ok(raw) => judge_mode_selector(sel, modes, &raw),
            Err(e) => Err(format!(
                "reading {} ({}), which selects the modes the drive allows: {}",
                sel.name, sel.object, e.kind
            )),
        };
        if let Err(why) = judged {
            done.modes_refused = Some(("checking the modes of operation", why));
            return Ok(done);
        }
    }
    if let Some(fastest) = plan.fastest
        && let Ok(raw) = c.upload(ObjectAddress::new(0x6080, 0), false).await
        && let Err(why) = judge_max_speed(fastest, &raw)
    {
        done.modes_refused = Some((
            "checking the program against the motor's maximum speed",
            why,
        ));
        return Ok(done);
    }
    for (addr, bytes, _why) in pdo_writes {
        c.download(*addr, bytes, false).await?;
    }
    done.init_failed = send_init_cmds(c, &plan.init_pre).await?;
    if done.init_failed.is_some() {
        return Ok(done);
    }
    for w in &plan.sync_writes {
        done.outcomes.push(write_sync(c, w).await?);
    }
    if let Some((unit_ns, index)) = plan.interpolation {
        done.interpolated = Some(write_interpolation(c, cycle_ns, unit_ns, index).await?);
    }
    for (addr, bytes, _why) in later {
        c.download(*addr, bytes, false).await?;
    }
    for a in &plan.undriven {
        let value = match plan.carried.iter().find(|(c, _)| c == a) {
            Some((_, bytes)) => Ok(bytes.clone()),
            None => c.upload(*a, false).await.map_err(|e| e.kind.to_string()),
        };
        done.held.push((*a, value));
    }
    Ok(done)
}

/// After one drive's mailbox work: the failed write named with its purpose, 0x60C2 and the
/// synchronisation objects judged against the profile, the warnings, the read-only cycle times
/// to check again once SYNC0 runs. Returns the held values of the undriven outputs.
fn judge_drive(
    d: &DeviceInfo,
    drive: &DriveRef,
    profile: &DriveProfile,
    plan: &DriveWrites,
    done: Result<MailboxDone, CoeError>,
    warnings: &mut Vec<(DriveRef, String)>,
    recheck: &mut Vec<(u16, DriveRef, ObjectAddress)>,
) -> Result<Vec<HeldValue>, MasterError> {
    let MailboxDone {
        outcomes,
        interpolated,
        held,
        init_failed,
        modes_refused,
    } = done.map_err(|e| {
        let mut e = MasterError::from(SessionError::Coe(e));
        // Name the purpose of the write that failed.
        if let Some((_, _, why)) = plan.writes.iter().find(|(a, _, _)| e.step == a.to_string()) {
            e.step = format!("writing {} ({why})", e.step);
        } else if let Some(w) = plan
            .sync_writes
            .iter()
            .find(|w| e.step == w.address.to_string())
        {
            e.step = format!("writing {} ({})", e.step, w.describe());
        }
        e
    })?;
    if let Some((step, why)) = modes_refused {
        // What the drive reports (its mode setting, its motor's maximum speed) refuses the
        // program: the drive's refusal (exit 4), not an error of the file (exit 2).
        return Err(MasterError::new(Some(drive), step, ErrorKind::Refused, why));
    }
    if let Some((ic, e)) = init_failed {
        return Err(init_cmd_error(drive, ic, &e));
    }
    match interpolated {
        Some(Err(why)) => {
            return Err(MasterError::new(
                Some(drive),
                "writing 0x60C2 (interpolation time period)",
                ErrorKind::Incompatible,
                why,
            ));
        }
        Some(Ok(form)) => tracing::info!("{drive}: interpolation time period {form}"),
        None => {}
    }
    for (w, o) in plan.sync_writes.iter().zip(&outcomes) {
        match o.judge(w, profile) {
            Ok(None) => {}
            Ok(Some(note)) => {
                tracing::warn!("{drive}: {note}");
                warnings.push((drive.clone(), note));
            }
            Err(why) => {
                return Err(MasterError::new(
                    Some(drive),
                    format!("writing {} ({})", w.address, w.describe()),
                    ErrorKind::Incompatible,
                    why,
                ));
            }
        }
        if matches!(o, SyncOutcome::ReadOnly { .. }) && w.what == SyncWhat::CycleTime {
            recheck.push((d.address, drive.clone(), w.address));
        }
    }
    tracing::info!("{drive}: configured ({} SDO writes)", plan.writes.len());
    for (a, r) in &held {
        if let Err(why) = r {
            warnings.push((
                drive.clone(),
                format!(
                    "{a} is mapped but the master does not drive it and cannot read its \
                     value ({why}): it is sent as 0"
                ),
            ));
        }
    }
    Ok(held)
}

/// Build the process image (PRE-OP with PDI): ethercrab reads each device's PDO assignment.
/// [`build_image`], with ethercrab's read-back of the PDO configuration each drive has just
/// acknowledged writing (`acknowledged`: station address, objects and values) answered from
/// those writes ([`crate::answers`]), as its SII reads were. Returns the frames answered.
fn build_image_answered<'a, L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: Group<PreOp>,
    devices: &[DeviceInfo],
    acknowledged: impl Iterator<Item = (u16, impl Iterator<Item = (ObjectAddress, &'a [u8])>)>,
) -> (
    Result<Group<ethercrab::subdevice_group::PreOpPdi>, MasterError>,
    u64,
) {
    if let Some(mut a) = bus.take_answers() {
        for (station, writes) in acknowledged {
            for (object, bytes) in writes {
                a.acknowledged(station, object, bytes);
            }
            a.last_counter(station, bus.mailbox_sequence(station).last);
        }
        bus.pump_mut().set_answers(Some(a));
    }
    let before = bus.pump().stats().answered;
    let group = build_image(bus, group, devices);
    let _ = bus.pump_mut().set_answers(None);
    (group, bus.pump().stats().answered - before)
}

fn build_image<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: Group<PreOp>,
    devices: &[DeviceInfo],
) -> Result<Group<ethercrab::subdevice_group::PreOpPdi>, MasterError> {
    let step = "building the process image (PRE-OP)";
    let r = bus.block_on(&|| step.into(), T_STEP, |md| group.into_pre_op_pdi(md));
    // ethercrab reads each device's PDO assignment over CoE here; when that fails, its error
    // names no device: name the one it last talked to.
    let culprit = || {
        let addr = bus.last_ethercrab_mailbox()?;
        devices
            .iter()
            .find(|d| d.address == addr)
            .map(|d| DriveRef {
                position: d.position,
                name: d.name.clone(),
            })
    };
    match r {
        Ok(Ok(g)) => Ok(g),
        Ok(Err(e)) => {
            let what = match &e {
                ethercrab::error::Error::Mailbox(_) | ethercrab::error::Error::Timeout(_) => {
                    format!("{step}: reading the PDO assignment (0x1C12/0x1C13) over CoE")
                }
                _ => step.to_string(),
            };
            Err(bus_error(culprit().as_ref(), what, e))
        }
        Err(e) => Err(exec_error(culprit().as_ref(), e)),
    }
}

/// One SyncManager channel as its registers (0x0800 + 8n) read.
pub(crate) struct SmChannel {
    /// Length (bytes 2–3).
    pub len: u16,
    /// Control (byte 4): bits 2–3 the direction, 01 the master writes.
    pub control: u8,
    /// Activation (byte 6): bit 0 enabled.
    pub activation: u8,
    /// PDI control (byte 7): bit 0 deactivated by the device.
    pub pdi_control: u8,
}

/// The buffered (process-data) SyncManagers with a length among the registers read from
/// 0x0800, with their numbers.
pub(crate) fn process_data_sms(regs: &[u8]) -> impl Iterator<Item = (usize, SmChannel)> + '_ {
    regs.chunks_exact(8).enumerate().filter_map(|(n, sm)| {
        let ch = SmChannel {
            len: u16::from_le_bytes([sm[2], sm[3]]),
            control: sm[4],
            activation: sm[6],
            pdi_control: sm[7],
        };
        (ch.len > 0 && ch.control & 0x03 == 0x00).then_some((n, ch))
    })
}

/// Process-data SyncManagers that carry data but are left off. ETG.2000's `<Sm Enable>` is the
/// SyncManager's default activation, which vendor files set to 0 on the SyncManager of an
/// optional input (Beckhoff's EK1101 ID switch) or on every process-data SyncManager (a
/// stepper drive, a fieldbus coupler); configuration tools enable an SM when PDOs are assigned
/// to it. ethercrab 0.7.1 enables an SM only where the SII does, and the device then refuses
/// SAFE-OP (0x001D/0x001E, invalid output/input configuration). Here, before SAFE-OP is
/// requested, every buffered SyncManager with a length and its activation bit clear is
/// enabled (0x0806 bit 0), and the start-up says so for the device.
pub fn enable_process_data_sms<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    devices: &[DeviceInfo],
    warnings: &mut Vec<(DriveRef, String)>,
) -> Result<(), MasterError> {
    const SMS: usize = 8;
    for d in devices {
        let drive = d.drive_ref();
        let regs: [u8; 8 * SMS] = bus
            .block_on(
                &|| "reading the SyncManagers (0x0800)".into(),
                T_STEP,
                |md| Command::fprd(d.address, 0x0800).receive::<[u8; 8 * SMS]>(md),
            )
            .map_err(|e| exec_error(Some(&drive), e))?
            .map_err(|e| bus_error(Some(&drive), "reading the SyncManagers (0x0800)", e))?;
        for (n, sm) in process_data_sms(&regs) {
            let (len, act) = (sm.len, sm.activation);
            if act & 0x01 != 0 {
                continue;
            }
            let reg = 0x0806 + 8 * n as u16;
            bus.block_on(&|| format!("enabling SM{n} (0x{reg:04X})"), T_STEP, |md| {
                Command::fpwr(d.address, reg).send(md, act | 0x01)
            })
            .map_err(|e| exec_error(Some(&drive), e))?
            .map_err(|e| bus_error(Some(&drive), format!("enabling SM{n} (0x{reg:04X})"), e))?;
            warnings.push((
                drive.clone(),
                format!(
                    "its SII leaves SM{n} off (the ESI's Enable=\"0\") though {len} bytes of \
                     process data are assigned to it: enabled before SAFE-OP, as configuration \
                     tools do"
                ),
            ));
        }
    }
    Ok(())
}

/// Resolve each drive's fields and check its image size against its mapping.
fn resolve_drives<L: FrameLink>(
    bus: &Bus<'_, L>,
    group: &Group<ethercrab::subdevice_group::PreOpPdi>,
    drives_plan: Vec<(&DeviceInfo, &DriveSetup, &'static DriveProfile)>,
    mappings: Vec<Mapping>,
    held_values: Vec<Vec<HeldValue>>,
) -> Result<Vec<ConfiguredDrive>, MasterError> {
    let mut drives = Vec::with_capacity(drives_plan.len());
    for (((d, setup, profile), mapping), held) in
        drives_plan.into_iter().zip(mappings).zip(held_values)
    {
        let drive = DriveRef {
            position: d.position,
            name: profile.name.to_string(),
        };
        let layout = Layout::new(&mapping);
        let sd = group
            .subdevice(bus.md(), d.position as usize)
            .map_err(|e| bus_error(Some(&drive), "reading the process image", e))?;
        let io = sd.io_raw();
        let (ni, no) = (io.inputs().len(), io.outputs().len());
        drop(io);
        if ni != layout.bytes(Direction::Tx) || no != layout.bytes(Direction::Rx) {
            // The drive's own account of its process data disagrees: a drive-side refusal.
            return Err(MasterError::new(
                Some(&drive),
                "checking the process image",
                ErrorKind::Refused,
                format!(
                    "the drive reports {no} output and {ni} input bytes, the configured mapping \
                     needs {} and {}",
                    layout.bytes(Direction::Rx),
                    layout.bytes(Direction::Tx)
                ),
            ));
        }
        let mut fields = resolve_fields(&layout, profile).map_err(|e| {
            MasterError::new(
                Some(&drive),
                "resolving the process image",
                ErrorKind::Config,
                e,
            )
        })?;
        for (a, bytes) in held {
            if let (Ok(f), Ok(bytes)) = (layout.raw_field(Direction::Rx, a, false), bytes) {
                let mut raw = [0u8; 8];
                for (d, s) in raw.iter_mut().zip(&bytes) {
                    *d = *s;
                }
                fields.held_outputs.push((f, u64::from_le_bytes(raw)));
            }
        }
        drives.push(ConfiguredDrive {
            info: d.clone(),
            drive,
            profile,
            mapping,
            layout,
            fields,
            setup: setup.clone(),
            sync0_start_ns: None,
        });
    }
    Ok(drives)
}

/// DC: let the clocks settle, then start SYNC0 and go to SAFE-OP.
fn to_safe_op<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: Group<ethercrab::subdevice_group::PreOpPdi>,
    drives: &mut [ConfiguredDrive],
    cfg: &StartupConfig,
    times: &mut StartupTimes,
) -> Result<Group<SafeOp, HasDc>, MasterError> {
    let t = crate::rt::monotonic_ns();
    let f = bus.pump().stats().sent;
    settle_dc(bus, &group, drives, &cfg.dc)?;
    times.dc_settle_ms = ms_since(t);
    times.frames.dc_settle = bus.pump().stats().sent - f;
    let f = bus.pump().stats().sent;
    let dc_drives = drives.iter().filter(|d| d.info.dc).count();
    let start_delay = cfg.dc.start_delay_for(dc_drives);
    let dc_conf = DcConfiguration {
        start_delay,
        sync0_period: cfg.cycle,
        sync0_shift: cfg.dc.shift.unwrap_or(cfg.cycle / 2),
    };
    let group = bus
        .block_on(&|| "starting SYNC0".into(), T_STEP, |md| {
            group.configure_dc_sync(md, dc_conf)
        })
        .map_err(|e| exec_error(None, e))?
        .map_err(|e| bus_error(None, "starting SYNC0", e))?;
    times.sync0_rearmed = sync0_starts(bus, drives, start_delay, cfg.cycle)?;
    let addrs: Vec<(u16, DriveRef)> = drives
        .iter()
        .map(|d| (d.info.address, d.drive.clone()))
        .collect();
    let r = bus.block_on(&|| "PRE-OP → SAFE-OP".into(), T_STEP, |md| {
        group.into_safe_op(md)
    });
    times.frames.safe_op = bus.pump().stats().sent - f;
    let fallback = match r {
        Ok(Ok(g)) => return Ok(g),
        Ok(Err(e)) => bus_error(None, "PRE-OP → SAFE-OP", e),
        Err(e) => exec_error(None, e),
    };
    let mut e = explain_transition(bus, &addrs, AlState::SafeOp, fallback);
    // 0x001D–0x0020: the process data SyncManagers do not fit the drive's mapping. The
    // mapping was not read back (`crate::answers`): say what that means.
    if bus.options().answer_rereads
        && matches!(e.kind, ErrorKind::AlState(AlStatusCode(0x001D..=0x0020)))
    {
        e.reason.push_str(
            " (the drive acknowledged the PDO mapping start-up wrote, and its SyncManagers were \
             sized for it; a drive that does not hold an acknowledged mapping refuses so: \
             answer_rereads = false reads the mapping back from the drive instead)",
        );
    }
    Err(e)
}

/// Times start-up arms SYNC0 again on drives whose start time passed before they were
/// configured, each time with twice the margin, before it gives up.
const SYNC0_REARMS: u32 = 3;

/// What the one read of [`SYNC_REGS`] is, in messages.
const SYNC_STATE: &str = "SYNC0 activation and start time (0x0981–0x0997)";

/// 0x0981 (activation) to the end of 0x0990 (the start time), read at once.
const SYNC_REGS: usize = (register::DC_START_TIME - register::DC_ACTIVATION) as usize + 8;

/// Each DC drive's first SYNC0 (0x0990, read back), into [`ConfiguredDrive::sync0_start_ns`],
/// and SYNC0 armed again where its start time had passed. ethercrab computes one start time
/// from a single reading of the reference clock and configures the drives one after the
/// other, so a start delay too short for the segment leaves the last drives with a start time
/// already past when their Sync Out Unit was activated: the ESC then waits for the system time
/// to reach it again (the 32-bit wrap, or never with 64 bits; datasheet section II, 0x0981
/// bit 5). Such a drive still has its first pulse pending (0x0984 bit 0) with a start time at
/// or before the system time. It is armed again on the same grid (its start time plus whole
/// cycles, so every drive keeps the phase of the others): 0x0981 = 0, the new start time, the
/// activation it had. Returns how many drives were armed again.
fn sync0_starts<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    drives: &mut [ConfiguredDrive],
    start_delay: Duration,
    cycle: Duration,
) -> Result<usize, MasterError> {
    let dc: Vec<(usize, u16)> = drives
        .iter()
        .enumerate()
        .filter(|(_, d)| d.info.dc)
        .map(|(i, d)| (i, d.info.address))
        .collect();
    let Some(&(_, probe)) = dc.last() else {
        return Ok(0);
    };
    let cycle_ns = u64::try_from(cycle.as_nanos()).unwrap_or(u64::MAX).max(1);
    let mut margin = u64::try_from(start_delay.as_nanos())
        .unwrap_or(u64::MAX)
        .max(cycle_ns);
    let mut todo = dc;
    let mut rearmed = 0;
    for attempt in 0..=SYNC0_REARMS {
        let states = bus
            .block_on_each(
                &|| format!("reading each drive's {SYNC_STATE}"),
                T_STEP,
                todo.iter().map(|&(_, a)| a).collect(),
                async |md, addr| {
                    // 0x0981 activation … 0x0984 activation status … 0x0990 start time, in
                    // one read.
                    Command::fprd(addr, register::DC_ACTIVATION)
                        .receive::<[u8; SYNC_REGS]>(md)
                        .await
                },
            )
            .map_err(|e| exec_error(None, e))?;
        // The system time of the drive configured last, read after every start time was
        // written.
        let now = bus
            .block_on(
                &|| "reading the DC system time (0x0910)".into(),
                T_STEP,
                |md| Command::fprd(probe, register::DC_SYSTEM_TIME).receive::<u64>(md),
            )
            .map_err(|e| exec_error(None, e))?
            .map_err(|e| bus_error(None, "reading the DC system time (0x0910)", e))?;
        let mut late = Vec::new();
        for (&(i, addr), state) in todo.iter().zip(states) {
            let d = &mut drives[i];
            let regs = state
                .map_err(|e| bus_error(Some(&d.drive), format!("reading its {SYNC_STATE}"), e))?;
            let (act, status) = (regs[0], regs[3]);
            let mut start = [0u8; 8];
            start.copy_from_slice(&regs[SYNC_REGS - 8..]);
            let start = u64::from_le_bytes(start);
            d.sync0_start_ns = Some(start);
            // Pending with a start time at or before now: it will not come.
            if status & 0x01 != 0 && start.wrapping_sub(now) as i64 <= 0 {
                late.push((i, addr, act, start));
            }
        }
        if late.is_empty() {
            return Ok(rearmed);
        }
        if attempt == SYNC0_REARMS {
            let d = &drives[late[0].0];
            return Err(MasterError::new(
                Some(&d.drive),
                "starting SYNC0",
                ErrorKind::DcSettle,
                format!(
                    "its SYNC0 start time had passed before it was configured, {} times \
                     (start delay {} ms for {} drives with DC; set a longer \
                     dc_start_delay in the run file, DcSettings::start_delay in the API)",
                    SYNC0_REARMS + 1,
                    start_delay.as_millis(),
                    drives.iter().filter(|d| d.info.dc).count(),
                ),
            ));
        }
        let at = now.saturating_add(margin);
        let writes = bus
            .block_on_each(
                &|| "arming SYNC0 again (0x0981, 0x0990)".into(),
                T_STEP,
                late.iter()
                    .map(|&(_, addr, act, start)| {
                        let cycles = at.saturating_sub(start).div_ceil(cycle_ns);
                        (
                            addr,
                            act,
                            start.saturating_add(cycles.saturating_mul(cycle_ns)),
                        )
                    })
                    .collect(),
                async |md, (addr, act, new): (u16, u8, u64)| {
                    Command::fpwr(addr, register::DC_ACTIVATION)
                        .send(md, 0u8)
                        .await?;
                    Command::fpwr(addr, register::DC_START_TIME)
                        .send(md, new)
                        .await?;
                    Command::fpwr(addr, register::DC_ACTIVATION)
                        .send(md, act)
                        .await
                },
            )
            .map_err(|e| exec_error(None, e))?;
        for (&(i, ..), w) in late.iter().zip(writes) {
            w.map_err(|e| bus_error(Some(&drives[i].drive), "arming SYNC0 again (0x0990)", e))?;
        }
        rearmed += late.len();
        todo = late.iter().map(|&(i, addr, ..)| (i, addr)).collect();
        margin = margin.saturating_mul(2);
    }
    Ok(rearmed)
}

/// A read-only cycle time shows the SYNC0 cycle once SYNC0 runs (ETG.1020): check it, from the
/// first SYNC0 on (after the start delay) for some cycles.
fn recheck_cycle_times<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    recheck: Vec<(u16, DriveRef, ObjectAddress)>,
    cfg: &StartupConfig,
    warnings: &mut Vec<(DriveRef, String)>,
) -> Result<(), MasterError> {
    let cycle_ns = u32::try_from(cfg.cycle.as_nanos()).unwrap_or(u32::MAX);
    let wait = cfg.dc.start_delay_for(MAX_SUBDEVICES) + cfg.cycle * 20 + Duration::from_millis(200);
    for (addr, drive, object) in recheck {
        let until = crate::rt::monotonic_ns() + wait.as_nanos() as u64;
        let reads = loop {
            let v = bus.with_coe(addr, drive.clone(), false, T_STEP, async |c| {
                c.upload(object, false).await
            })?;
            let v = le_u32(&v);
            if v == cycle_ns || crate::rt::monotonic_ns() > until {
                break v;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        match reads {
            x if x == cycle_ns => {}
            0 => warnings.push((
                drive,
                format!("{object} (cycle time) still reads 0 with SYNC0 running at {cycle_ns} ns"),
            )),
            x => {
                return Err(MasterError::new(
                    Some(&drive),
                    format!("checking {object} (cycle time) in SAFE-OP"),
                    ErrorKind::Incompatible,
                    format!(
                        "the drive reports a cycle of {x} ns with SYNC0 running at {cycle_ns} ns"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// After a failed transition: find the drive that refused and say why (its AL status code).
pub fn explain_transition<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    drives: &[(u16, DriveRef)],
    target: AlState,
    fallback: MasterError,
) -> MasterError {
    for (addr, drive) in drives {
        let r = bus.block_on(
            &|| format!("{drive}: reading AL status"),
            Duration::from_secs(1),
            |md| async move {
                Command::fprd(*addr, register::AL_STATUS)
                    .receive::<[u8; 6]>(md)
                    .await
            },
        );
        if let Ok(Ok(b)) = r {
            let status = crate::ec::AlStatus {
                raw: u16::from_le_bytes([b[0], b[1]]),
            };
            let code = AlStatusCode(u16::from_le_bytes([b[4], b[5]]));
            if status.error() || status.state() != Some(target) {
                return MasterError::new(
                    Some(drive),
                    format!(
                        "{} → {target}",
                        status.state().map_or("?".into(), |s| s.to_string())
                    ),
                    ErrorKind::AlState(code),
                    format!("refused: AL status {status}, AL status code {code}"),
                );
            }
        }
    }
    fallback
}

fn resolve_fields(layout: &Layout, profile: &DriveProfile) -> Result<DriveFields, String> {
    let dict = od::Dictionary::new(profile.dictionary);
    let mut axis = AxisBinding::resolve(layout, &dict).map_err(|e| e.to_string())?;
    if axis.controlword.is_none() {
        return Err("the controlword 0x6040:00 is not mapped".into());
    }
    if axis.statusword.is_none() {
        return Err("the statusword 0x6041:00 is not mapped".into());
    }
    let get = |dir: Direction, addr: ObjectAddress| -> Result<Option<Field>, String> {
        pdo::axis::resolve_mapped(layout, &dict, dir, addr).map_err(|e| e.to_string())
    };
    let counter = match profile.cycle_counter {
        Some(c) => get(Direction::Rx, c.output)?
            .map(|out| {
                Ok::<_, String>((
                    out,
                    match c.echo {
                        Some(e) => get(Direction::Tx, e)?,
                        None => None,
                    },
                ))
            })
            .transpose()?,
        None => None,
    };
    axis.zero_speed = match profile.zero_speed_flag {
        Some(z) => layout
            .raw_field(Direction::Tx, z.address, false)
            .ok()
            .map(|f| (f, z.bit)),
        None => None,
    };
    let mut output_defaults = Vec::new();
    for d in profile.output_defaults {
        if let Some(f) = get(Direction::Rx, d.address)? {
            output_defaults.push((f, d.value));
        }
    }
    let mut probe = ProbeFields {
        function: get(Direction::Rx, PROBE_FUNCTION)?,
        status: get(Direction::Tx, PROBE_STATUS)?,
        positions: [None; 4],
    };
    for (slot, index) in probe.positions.iter_mut().zip(0x60BAu16..=0x60BD) {
        *slot = get(Direction::Tx, ObjectAddress::new(index, 0))?;
    }
    Ok(DriveFields {
        axis,
        counter,
        output_defaults,
        held_outputs: Vec::new(),
        probe,
    })
}

/// Drift compensation, measured: exchange frames with system-time synchronisation (each one a
/// step of every clock's control loop) back to back until every clock's system-time difference
/// (0x092C) has stayed below the threshold for [`DcSettings::settle_checks`] checks in a row.
///
/// One broadcast read checks the whole segment: a BRD ORs every device's 0x092C, and each
/// difference's magnitude (bits 0–30) is at most the OR of them all, so an OR below the
/// threshold means every clock is below it. Only when it is not are the drives read one by one
/// (eight at a time), to name the worst in the error.
fn settle_dc<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: &Group<ethercrab::subdevice_group::PreOpPdi>,
    drives: &[ConfiguredDrive],
    dc: &DcSettings,
) -> Result<(), MasterError> {
    let deadline = crate::rt::monotonic_ns() + dc.settle_timeout.as_nanos() as u64;
    // The last readings of each drive's 0x092C (newest last), for the error.
    let mut last: Vec<std::collections::VecDeque<u32>> =
        vec![std::collections::VecDeque::with_capacity(5); drives.len()];
    let mut below = 0u32;
    loop {
        bus.block_on(
            &|| "synchronising distributed clocks".into(),
            T_STEP,
            |md| group.tx_rx_sync_system_time(md),
        )
        .map_err(|e| exec_error(None, e))?
        .map_err(|e| bus_error(None, "synchronising distributed clocks", e))?;
        let or: u32 = bus
            .block_on(&|| "reading 0x092C of every device".into(), T_STEP, |md| {
                Command::brd(register::DC_SYSTEM_TIME_DIFFERENCE)
                    .ignore_wkc()
                    .receive::<u32>(md)
            })
            .map_err(|e| exec_error(None, e))?
            .map_err(|e| {
                bus_error(
                    None,
                    "reading the DC system-time difference (0x092C) of every device",
                    e,
                )
            })?;
        let worst = if or & 0x7FFF_FFFF < dc.settle_threshold_ns {
            None
        } else {
            worst_drive(bus, drives, dc, &mut last)?
        };
        let Some((i, diff)) = worst else {
            below += 1;
            if below >= dc.settle_checks.max(1) {
                return Ok(());
            }
            continue;
        };
        below = 0;
        if crate::rt::monotonic_ns() <= deadline {
            continue;
        }
        let d = &drives[i];
        return Err(MasterError::new(
            Some(&d.drive),
            "waiting for distributed clocks to settle (0x092C)",
            ErrorKind::DcSettle,
            format!(
                "system-time difference still {diff} ns after {} ms (threshold {} ns); \
                 its last readings of 0x092C: {} ns (its clock does not lock to the \
                 reference: a clock beyond the slave controller's drift range?)",
                dc.settle_timeout.as_millis(),
                dc.settle_threshold_ns,
                last.get(i).map_or(String::new(), |l| l
                    .iter()
                    .map(u32::to_string)
                    .collect::<Vec<_>>()
                    .join(", "))
            ),
        ));
    }
}

/// Each drive's 0x092C, eight at a time, kept in `last` (newest last, five per drive): the
/// drive farthest above the threshold, `None` when every drive is below it.
fn worst_drive<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    drives: &[ConfiguredDrive],
    dc: &DcSettings,
    last: &mut [std::collections::VecDeque<u32>],
) -> Result<Option<(usize, u32)>, MasterError> {
    const KEEP: usize = 5;
    let addrs: Vec<u16> = drives.iter().map(|d| d.info.address).collect();
    let reads = bus
        .block_on_each(
            &|| "reading 0x092C of each drive".into(),
            T_STEP,
            addrs,
            async |md, addr| {
                Command::fprd(addr, register::DC_SYSTEM_TIME_DIFFERENCE)
                    .receive::<u32>(md)
                    .await
            },
        )
        .map_err(|e| exec_error(None, e))?;
    let mut worst: Option<(usize, u32)> = None;
    for (i, (d, raw)) in drives.iter().zip(reads).enumerate() {
        let raw = raw.map_err(|e| {
            bus_error(
                Some(&d.drive),
                "reading the DC system-time difference (0x092C)",
                e,
            )
        })?;
        let diff = raw & 0x7FFF_FFFF;
        if let Some(l) = last.get_mut(i) {
            if l.len() == KEEP {
                l.pop_front();
            }
            l.push_back(diff);
        }
        if diff >= dc.settle_threshold_ns && worst.is_none_or(|(_, w)| diff > w) {
            worst = Some((i, diff));
        }
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(what: SyncWhat, value: u32) -> SyncWrite {
        SyncWrite {
            address: ObjectAddress::new(0x1C32, if what == SyncWhat::Type { 1 } else { 2 }),
            value,
            len: if what == SyncWhat::Type { 2 } else { 4 },
            what,
        }
    }

    const P: &DriveProfile = &crate::drives::generic::GENERIC_CIA402;

    #[test]
    fn a_read_only_sync_type_that_is_not_dc_sync0_fails_naming_both_values() {
        let o = SyncOutcome::ReadOnly {
            has: Some(0),
            min_cycle: None,
        };
        let e = o.judge(&w(SyncWhat::Type, 2), P).unwrap_err();
        assert_eq!(
            e,
            "0x1C32:01 is read-only and holds 0 (free run); DC SYNC0 needs 2"
        );
    }

    #[test]
    fn a_read_only_cycle_time_is_judged_by_the_minimum_cycle_time() {
        let ok = SyncOutcome::ReadOnly {
            has: Some(250_000),
            min_cycle: Some(250_000),
        };
        let note = ok
            .judge(&w(SyncWhat::CycleTime, 1_000_000), P)
            .unwrap()
            .unwrap();
        assert!(note.contains("read-only (holds 250000 ns)"), "{note}");
        let too_fast = SyncOutcome::ReadOnly {
            has: Some(500_000),
            min_cycle: Some(500_000),
        };
        let e = too_fast
            .judge(&w(SyncWhat::CycleTime, 250_000), P)
            .unwrap_err();
        assert!(
            e.contains("holds 500000 ns")
                && e.contains("minimum cycle time 0x1C32:05 is 500000 ns")
                && e.contains("the cycle needs 250000 ns"),
            "{e}"
        );
    }

    #[test]
    fn set_or_absent_objects_need_no_more_than_a_warning() {
        assert_eq!(
            SyncOutcome::AlreadySet.judge(&w(SyncWhat::Type, 2), P),
            Ok(None)
        );
        assert_eq!(
            SyncOutcome::Written.judge(&w(SyncWhat::CycleTime, 1_000_000), P),
            Ok(None)
        );
        let n = SyncOutcome::Absent
            .judge(&w(SyncWhat::Type, 2), P)
            .unwrap()
            .unwrap();
        assert!(n.starts_with("has no 0x1C32:01"), "{n}");
    }
}
