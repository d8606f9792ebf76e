//! The bus operations behind the `ecdrive` commands, as library functions with typed,
//! serializable results: the command line only parses arguments, calls one of these and prints.
//!
//! | command | function | result |
//! |---|---|---|
//! | `slaves` | [`slaves`] | [`SlaveReport`] per device |
//! | `upload` / `download` | [`upload`], [`download`] | [`SdoValue`] |
//! | `sdos` | [`sdos`] | [`OdListing`] of [`OdObject`]s |
//! | `pdos` | [`pdos`] | [`PdoReport`] |
//! | `states` | [`states`] | [`StateChange`] per device |
//! | `reg` | [`reg_read`], [`reg_write`] | [`RegisterData`] |
//! | `sii` | [`sii::sii_read`], then [`sii::SiiInfo::decode`] / [`sii::esi_skeleton`] | [`sii::SiiDump`] |
//! | `esi` | [`esi::show`], [`esi::check`] | [`esi::EsiSummary`], [`esi::EsiCheck`] |
//! | `run` | [`run::run`] (with a [`crate::app::config::RunConfig`]) | [`run::RunReport`] |
//! | `reset` | [`reset::reset`] | [`reset::ResetReport`] |
//! | `graph` | [`graph::graph`] (no discovery), then [`graph::Graph::dot`] | [`graph::Graph`] |
//! | `diag` | [`diag::diag`] (no discovery: reads by position, disturbs nothing) | [`diag::DiagReport`] |
//! | `alias` / `sii write` | [`alias::alias`], [`alias::sii_write`] (no discovery; INIT or PRE-OP only) | [`alias::AliasReport`], [`alias::SiiWriteReport`] |
//! | `foe read` / `foe write` | [`foe::foe_read`], [`foe::foe_write`] (no discovery: the device as it is, in BOOT for firmware) | [`foe::FoeReport`] |
//!
//! ecdrive is not a resident master: every operation starts with a fresh discovery
//! ([`startup::discover`]: ethercrab resets every device to INIT, assigns station addresses,
//! reads the SII and takes the segment to PRE-OP), then does its work on the device at the
//! requested position. A [`Target`] names where the segment is: a network interface, or
//! emulated devices in-process (`sim:mr-j4-tm,bdhde`), which needs no root.
//!
//! ```
//! use ecdrive_cli::app::ethercat::tools::{self, Target};
//!
//! let target: Target = "sim:mr-j4-tm,bdhde".parse()?;
//! let slaves = tools::session(&target, |bus| tools::slaves(bus, false))?;
//! assert_eq!(slaves[1].profile.as_deref(), Some("BDHDE"));
//! let product = "0x1018:02".parse()?;
//! // The data type comes from the MR-J4-TM profile.
//! let v = tools::session(&target, move |bus| tools::upload(bus, 0, product, None))?;
//! assert_eq!(v.hex.as_deref(), Some("0x00000201"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Every failure is a [`MasterError`] naming the drive, the object or register, and the reason.
//! Its [`ErrorKind`] tells input that does not fit the segment ([`ErrorKind::Config`]: a
//! position out of range, a value out of range, a type that cannot be inferred) from bus
//! failures and from drives refusing ([`ErrorKind::Sdo`], [`ErrorKind::AlState`]).

pub mod alias;
pub mod diag;
pub mod eeprom;
pub mod esi;
pub mod foe;
pub mod graph;
mod od;
mod pdos;
mod reg;
pub mod reset;
pub mod run;
pub mod sii;
mod slaves;
mod states;

pub use od::{
    JsonValue, OdEntry, OdListing, OdObject, OdSource, SdoValue, TypeSource, download, hex_of,
    sdos, upload,
};
pub use pdos::{PdoEntryReport, PdoReport, PdoSource, ReportedPdo, SmReport, pdos};
pub use reg::{MAX_REGISTER_BYTES, RegisterData, reg_read, reg_write, type_len};
pub use slaves::{
    AlStatusReport, EscInfo, MailboxReport, PortReport, SlaveDetail, SlaveReport, slaves,
};
pub use states::{StateChange, StatesOptions, StatesReport, states, states_timed};

use crate::app::capture::{CaptureFile, CaptureSummary, CaptureTap};
use crate::ec::{AlStatus, AlStatusCode, register};
use crate::link::{FrameLink, LinkError, RawSocket};
use crate::master::bus::{Bus, BusOptions, run_session};
use crate::master::error::{DriveRef, ErrorKind, MasterError, bus_error};
use crate::master::exec::exec_error;
use crate::master::startup::{self, DeviceInfo, Group};
use crate::sim::EscConfig;
use crate::sim::transport::SegmentLink;
use ethercrab::subdevice_group::PreOp;
use std::str::FromStr;
use std::time::Duration;

/// Where the segment is. In JSON: `{"interface": "eth1"}` or `{"sim": ["mr-j4-tm", …]}`.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// A network interface (raw socket; needs `CAP_NET_RAW`).
    Interface(String),
    /// Emulated devices in-process, by `ecdrive sim --device` name, in line order.
    Sim(Vec<String>),
}

impl FromStr for Target {
    type Err = MasterError;

    /// `sim:NAME[,NAME…]` for emulated devices in-process, anything else is an interface name.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.strip_prefix("sim:") {
            Some(list) => {
                let devices: Vec<String> = list
                    .split(',')
                    .map(|d| d.trim().to_string())
                    .filter(|d| !d.is_empty())
                    .collect();
                if devices.is_empty() {
                    return Err(MasterError::new(
                        None,
                        format!("reading the target {s:?}"),
                        ErrorKind::Config,
                        "name at least one emulated device after `sim:` (see `ecdrive sim --list-devices`)",
                    ));
                }
                Ok(Self::Sim(devices))
            }
            None => Ok(Self::Interface(s.to_string())),
        }
    }
}

impl core::fmt::Display for Target {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Interface(i) => f.write_str(i),
            Self::Sim(d) => write!(f, "sim:{}", d.join(",")),
        }
    }
}

/// The link of a [`Target`]: a raw socket or the in-process segment, optionally captured.
#[derive(Debug)]
pub enum ToolLink {
    /// A raw socket on an interface.
    Raw(RawSocket),
    /// Emulated devices in-process.
    Sim(Box<SegmentLink>),
    /// Another link whose frames, both directions, are also copied to a capture (`--pcap`,
    /// [`crate::app::capture`]).
    Captured(Box<ToolLink>, Box<CaptureTap>),
}

impl ToolLink {
    /// This link, its frames also copied to `tap`.
    pub fn captured(self, tap: CaptureTap) -> Self {
        Self::Captured(Box::new(self), Box::new(tap))
    }
}

impl FrameLink for ToolLink {
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        match self {
            Self::Raw(r) => r.send(frame),
            Self::Sim(s) => s.send(frame),
            Self::Captured(l, tap) => {
                tap.frame(true, frame);
                l.send(frame)
            }
        }
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        match self {
            Self::Raw(r) => r.recv(buf, timeout),
            Self::Sim(s) => s.recv(buf, timeout),
            Self::Captured(l, tap) => {
                let n = l.recv(buf, timeout)?;
                if let Some(frame) = n.and_then(|n| buf.get(..n)) {
                    tap.frame(false, frame);
                }
                Ok(n)
            }
        }
    }

    fn describe(&self) -> String {
        match self {
            Self::Raw(r) => r.describe(),
            Self::Sim(s) => s.describe(),
            Self::Captured(l, _) => l.describe(),
        }
    }
}

/// How the emulated devices of a [`Target::Sim`] are built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimSettings {
    /// ESC settings (SM watchdog).
    pub esc: EscConfig,
    /// Whether the emulated drives supervise the cyclic data (on, as the real drives are
    /// delivered: the MR-J4-TM raises AL.86.1 and the BDHDE 0x818D after about 7 ms without
    /// it). Off is what the MR-J4-TM does with [Pr. PN06]/[Pr. PN02] set so: for masters on a
    /// host that cannot keep the cycle (no real-time priority, a loaded machine).
    pub loss_detection: bool,
}

impl Default for SimSettings {
    fn default() -> Self {
        Self {
            esc: EscConfig::default(),
            loss_detection: true,
        }
    }
}

impl Target {
    /// Open the link: the raw socket, or build the emulated devices with `sim`.
    pub fn open_with(&self, sim: &SimSettings) -> Result<ToolLink, MasterError> {
        match self {
            Self::Interface(i) => RawSocket::open(i).map(ToolLink::Raw).map_err(|e| {
                MasterError::new(None, format!("opening interface {i}"), ErrorKind::Link, e)
            }),
            Self::Sim(devices) => {
                let mut segment =
                    crate::sim::run::build_segment(devices, &sim.esc).map_err(|e| {
                        MasterError::new(
                            None,
                            "building the emulated devices",
                            ErrorKind::Config,
                            e,
                        )
                    })?;
                if !sim.loss_detection {
                    crate::sim::drives::set_loss_detection(&mut segment, false);
                }
                Ok(ToolLink::Sim(Box::new(SegmentLink::new(segment))))
            }
        }
    }

    /// Open the link with the default settings for emulated devices.
    pub fn open(&self) -> Result<ToolLink, MasterError> {
        self.open_with(&SimSettings::default())
    }
}

/// Bus timing for tool sessions: the defaults, without ethercrab's static drift compensation
/// at init (tools do not run DC; [`states`] lets the clocks settle itself when it needs them).
pub fn tool_bus_options() -> BusOptions {
    BusOptions {
        dc_static_sync_iterations: 0,
        ..BusOptions::default()
    }
}

/// Open `target` and run `f` with a bus session on it, on a thread with a stack large enough
/// for ethercrab (see [`run_session`]).
pub fn session<R, F>(target: &Target, f: F) -> Result<R, MasterError>
where
    R: Send + 'static,
    F: FnOnce(&mut Bus<'_, ToolLink>) -> Result<R, MasterError> + Send + 'static,
{
    session_captured(target, None, f).map(|(r, _)| r)
}

/// [`session`], with every frame also written to the pcapng file `pcap` (if given); the
/// capture's summary with the result. A capture that cannot be written is an error, after `f`
/// ran.
pub fn session_captured<R, F>(
    target: &Target,
    pcap: Option<&std::path::Path>,
    f: F,
) -> Result<(R, Option<CaptureSummary>), MasterError>
where
    R: Send + 'static,
    F: FnOnce(&mut Bus<'_, ToolLink>) -> Result<R, MasterError> + Send + 'static,
{
    let link = target.open()?;
    let (link, file) = capture_link(link, target, pcap)?;
    let r = on_link(link, f).map(|(r, link)| {
        drop(link);
        r
    });
    let summary = finish_capture(file)?;
    r.map(|r| (r, summary))
}

/// Wrap `link` in a capture into `pcap`, if given.
pub fn capture_link(
    link: ToolLink,
    target: &Target,
    pcap: Option<&std::path::Path>,
) -> Result<(ToolLink, Option<CaptureFile>), MasterError> {
    let Some(path) = pcap else {
        return Ok((link, None));
    };
    let (tap, file) = crate::app::capture::start(path, &target.to_string())
        .map_err(|e| MasterError::new(None, "starting the capture", ErrorKind::Config, e))?;
    Ok((link.captured(tap), Some(file)))
}

/// Close a capture started by [`capture_link`] (after the link was dropped).
pub fn finish_capture(file: Option<CaptureFile>) -> Result<Option<CaptureSummary>, MasterError> {
    file.map(|f| {
        f.finish()
            .map_err(|e| MasterError::new(None, "finishing the capture", ErrorKind::Config, e))
    })
    .transpose()
}

/// Run `f` with a bus session on `link` (any [`FrameLink`]); returns the link with the result.
pub fn on_link<L, R, F>(link: L, f: F) -> Result<(R, L), MasterError>
where
    L: FrameLink + Send + 'static,
    R: Send + 'static,
    F: FnOnce(&mut Bus<'_, L>) -> Result<R, MasterError> + Send + 'static,
{
    match run_session(link, tool_bus_options(), f) {
        Ok((Ok(r), link)) => Ok((r, link)),
        Ok((Err(e), _)) => Err(e),
        Err((e, _)) => Err(MasterError::new(None, "opening the bus", ErrorKind::Bus, e)),
    }
}

/// Timeout of one register access or short step.
pub(crate) const T_STEP: Duration = Duration::from_secs(5);

/// The segment after discovery.
pub(crate) struct Discovered {
    pub group: Group<PreOp>,
    pub devices: Vec<DeviceInfo>,
}

pub(crate) fn discover<L: FrameLink>(bus: &mut Bus<'_, L>) -> Result<Discovered, MasterError> {
    let (group, devices) = startup::discover(bus)?;
    Ok(Discovered { group, devices })
}

impl Discovered {
    /// The device at `position`, or an error that says how many there are.
    pub fn device(&self, position: u16) -> Result<&DeviceInfo, MasterError> {
        self.devices
            .get(usize::from(position))
            .ok_or_else(|| out_of_range(position, self.devices.len()))
    }
}

/// The error for a position beyond the segment.
pub(crate) fn out_of_range(position: u16, count: usize) -> MasterError {
    MasterError::new(
        None,
        format!("selecting the device at position {position}"),
        ErrorKind::Config,
        match count {
            0 => "the segment has no devices".to_string(),
            1 => "the segment has 1 device (position 0)".to_string(),
            n => format!("the segment has {n} devices (positions 0–{})", n - 1),
        },
    )
}

/// How messages name a device: its profile name, or the SII name of unknown devices.
pub(crate) fn drive_ref(d: &DeviceInfo) -> DriveRef {
    DriveRef {
        position: d.position,
        name: d.profile.unwrap_or(d.name.as_str()).to_string(),
    }
}

/// Read AL status (0x0130) and AL status code (0x0134) of the device at `address`.
pub(crate) fn read_al_status<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    address: u16,
    drive: &DriveRef,
) -> Result<(AlStatus, AlStatusCode), MasterError> {
    let b = bus
        .block_on(
            &|| format!("{drive}: reading AL status (0x0130)"),
            T_STEP,
            |md| async move {
                ethercrab::Command::fprd(address, register::AL_STATUS)
                    .receive::<[u8; 6]>(md)
                    .await
            },
        )
        .map_err(|e| exec_error(Some(drive), e))?
        .map_err(|e| bus_error(Some(drive), "reading AL status (0x0130)", e))?;
    Ok((
        AlStatus {
            raw: u16::from_le_bytes([b[0], b[1]]),
        },
        AlStatusCode(u16::from_le_bytes([b[4], b[5]])),
    ))
}

/// The short name of an AL status value (`PREOP`, `SAFEOP+ERR`, `state 0x5`).
pub(crate) fn al_state_text(status: AlStatus) -> String {
    status.to_string()
}
