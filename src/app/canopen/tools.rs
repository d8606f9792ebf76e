//! Library functions behind `ecdrive slaves`, `upload` and `download` for CANopen nodes
//! (`--can IF` or the virtual bus): open a bus, scan it for nodes with their identity, and
//! read/write objects with the type taken from the node's drive profile.
//!
//! ```no_run
//! use ecdrive::canopen::master::{Master, MasterConfig};
//! use ecdrive_cli::app::canopen::tools::{self, BusSpec};
//! use ecdrive::od::ObjectAddress;
//!
//! let spec: BusSpec = "virtual".parse().unwrap(); // or "can0", or "vbus:/tmp/bus.sock"
//! let bus = tools::open_bus(&spec).unwrap();
//! let mut m = Master::new(bus, MasterConfig::default());
//! for n in tools::scan(&mut m, 1..=127).unwrap() {
//!     println!("{n}");
//! }
//! let v = tools::upload(&mut m, 0x7F, ObjectAddress::new(0x6041, 0), None).unwrap();
//! tools::download(&mut m, 0x7F, ObjectAddress::new(0x6081, 0), "20000", None).unwrap();
//! # let _ = v;
//! ```

use crate::canopen::can_socket::SocketCanTransport;
use crate::canopen::error::{CanError, CanErrorKind};
use crate::canopen::master::Master;
use crate::canopen::nmt::NmtState;
use crate::canopen::profile::CanDriveProfile;
use crate::canopen::sdo::AbortText;
use crate::canopen::transport::{CanTransport, TransportError};
use crate::canopen::unix_bus::UnixBusPort;
use crate::drives::{asda_a2, blv_r, lexium_mdrive};
use crate::od::{DataType, ObjectAddress, SdoAbortCode, Value};
use crate::sim::canopen::NodeSpec as Emulation;
use crate::sim::canopen::{EmulatedNode, SimBus};
use core::fmt;
use core::ops::RangeInclusive;
use core::str::FromStr;
use std::path::PathBuf;

use crate::drives::canopen_by_identity as identify;

/// A bus as the command line names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BusSpec {
    /// A SocketCAN interface, e.g. `can0` (`--can can0`).
    SocketCan(String),
    /// The in-process virtual bus with the three emulated drives of [`demo_bus`]
    /// (`--can virtual`).
    Virtual,
    /// A cross-process virtual bus hub at this socket path (`--can vbus:/path`).
    UnixHub(PathBuf),
}

/// An empty bus specification.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("empty CAN bus name: use an interface (can0), 'virtual', or 'vbus:/path/to/hub'")]
pub struct BusSpecError;

impl FromStr for BusSpec {
    type Err = BusSpecError;
    fn from_str(s: &str) -> Result<Self, BusSpecError> {
        let s = s.trim();
        if s.is_empty() {
            return Err(BusSpecError);
        }
        Ok(if s == "virtual" {
            BusSpec::Virtual
        } else if let Some(p) = s.strip_prefix("vbus:") {
            if p.is_empty() {
                return Err(BusSpecError);
            }
            BusSpec::UnixHub(PathBuf::from(p))
        } else {
            BusSpec::SocketCan(s.to_string())
        })
    }
}

impl fmt::Display for BusSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BusSpec::SocketCan(i) => f.write_str(i),
            BusSpec::Virtual => f.write_str("virtual"),
            BusSpec::UnixHub(p) => write!(f, "vbus:{}", p.display()),
        }
    }
}

/// **\[REC\]** Node-IDs of the drives on the virtual bus: the BLV-R at 1 (its manual states no
/// default), the ASDA-A2 at its default 7Fh, the Lexium at its default 41h.
pub const DEMO_NODES: [(u8, &CanDriveProfile); 3] = [
    (blv_r::EMU_NODE_ID, &blv_r::PROFILE),
    (0x7F, &asda_a2::PROFILE),
    (0x41, &lexium_mdrive::PROFILE),
];

/// The in-process virtual bus with the three emulated drives at [`DEMO_NODES`].
pub fn demo_bus() -> SimBus {
    let mut bus = SimBus::new();
    for (id, p) in DEMO_NODES {
        if let Some(e) = emulation_of(p)
            && let Ok(n) = EmulatedNode::new(e, id)
        {
            bus.add_node(n);
        }
    }
    bus
}

/// The software slave's own model of the drive `profile` describes (its table of the same
/// name, [`crate::sim::canopen::drives`]): the emulation is chosen by the drive's name, never
/// built from the master's profile.
pub fn emulation_of(profile: &CanDriveProfile) -> Option<&'static Emulation> {
    EMULATED_NODES
        .iter()
        .find(|(_, p, _)| core::ptr::eq(*p, profile) || p.name == profile.name)
        .and_then(|(name, _, _)| crate::sim::canopen::drives::by_name(name))
}

/// Open the bus `spec` names.
pub fn open_bus(spec: &BusSpec) -> Result<Box<dyn CanTransport + Send>, TransportError> {
    Ok(match spec {
        BusSpec::SocketCan(i) => Box::new(SocketCanTransport::open(i)?),
        BusSpec::Virtual => Box::new(demo_bus()),
        BusSpec::UnixHub(p) => Box::new(UnixBusPort::connect(p)?),
    })
}

/// One node found by [`scan`].
#[derive(Debug, Clone)]
pub struct NodeInfo {
    /// Node-ID.
    pub node: u8,
    /// 1000h device type.
    pub device_type: Option<u32>,
    /// 1018h:01.
    pub vendor_id: Option<u32>,
    /// 1018h:02.
    pub product_code: Option<u32>,
    /// 1018h:03.
    pub revision: Option<u32>,
    /// 1018h:04.
    pub serial: Option<u32>,
    /// 1008h.
    pub name: Option<String>,
    /// The matching profile.
    pub profile: Option<&'static CanDriveProfile>,
    /// The NMT state last seen.
    pub nmt: Option<NmtState>,
}

impl NodeInfo {
    /// The model name: the profile's model for the product code, else 1008h, else "unknown".
    pub fn model(&self) -> String {
        if let (Some(p), Some(c)) = (self.profile, self.product_code)
            && let Some(m) = p.identity.model(c)
        {
            return m.to_string();
        }
        if let Some(p) = self.profile {
            return p.name.to_string();
        }
        self.name.clone().unwrap_or_else(|| "unknown device".into())
    }
}

fn hex(v: Option<u32>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("0x{v:08X}"))
}

impl fmt::Display for NodeInfo {
    /// One line: `  1 (0x01)  Pre-operational  BLVD-KRD  vendor 0x000002BE  product 0x000013F7
    /// type 0x00020192  rev -  serial -`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:3} (0x{:02X})  {:<15}  {:<28}  vendor {}  product {}  type {}  rev {}  serial {}",
            self.node,
            self.node,
            self.nmt.map(NmtState::name).unwrap_or("?"),
            self.model(),
            hex(self.vendor_id),
            hex(self.product_code),
            hex(self.device_type),
            hex(self.revision),
            hex(self.serial),
        )
    }
}

/// **\[REC\]** How long [`scan`] listens for the answers to its 1000h requests: 200 ms. 127
/// answers of 8 bytes take about 130 ms of bus time at 125 kbit/s; slower buses need a
/// narrower ID range.
pub const SCAN_WINDOW_US: u64 = 200_000;

/// Find the nodes in `ids`: one SDO upload of 1000h to each at once, then for each node that
/// answers its identity 1018h:01–04 and name 1008h (objects it lacks are skipped), and the
/// matching profile, which the master keeps for later transfers.
pub fn scan<T: CanTransport>(
    m: &mut Master<T>,
    ids: RangeInclusive<u8>,
) -> Result<Vec<NodeInfo>, CanError> {
    let found = m.probe(ids, SCAN_WINDOW_US)?;
    let mut out = Vec::new();
    for (node, dt) in found {
        let mut info = NodeInfo {
            node,
            device_type: dt,
            vendor_id: None,
            product_code: None,
            revision: None,
            serial: None,
            name: None,
            profile: None,
            nmt: m.nmt_state(node),
        };
        let u32_of = |m: &mut Master<T>, a: ObjectAddress| -> Option<u32> {
            let raw = m.sdo_upload(node, a).ok()?;
            let b: [u8; 4] = raw.get(..4)?.try_into().ok()?;
            Some(u32::from_le_bytes(b))
        };
        if info.device_type.is_none() {
            info.device_type = u32_of(m, ObjectAddress::new(0x1000, 0));
        }
        info.vendor_id = u32_of(m, ObjectAddress::new(0x1018, 1));
        info.product_code = u32_of(m, ObjectAddress::new(0x1018, 2));
        info.revision = u32_of(m, ObjectAddress::new(0x1018, 3));
        info.serial = u32_of(m, ObjectAddress::new(0x1018, 4));
        info.name = m
            .sdo_upload(node, ObjectAddress::new(0x1008, 0))
            .ok()
            .map(|b| {
                String::from_utf8_lossy(&b)
                    .trim_end_matches('\0')
                    .to_string()
            });
        if let (Some(dt), Some(v)) = (info.device_type, info.vendor_id) {
            info.profile = identify(dt, v, info.product_code);
        }
        if let Some(p) = info.profile
            && m.profile(node).is_none()
        {
            m.set_profile(node, p);
        }
        info.nmt = m.nmt_state(node);
        out.push(info);
    }
    Ok(out)
}

/// Make sure the master knows `node`'s profile (identify it from 1000h/1018h if not).
fn ensure_profile<T: CanTransport>(m: &mut Master<T>, node: u8) {
    if m.profile(node).is_some() {
        return;
    }
    let read = |m: &mut Master<T>, a: ObjectAddress| -> Option<u32> {
        let raw = m.sdo_upload(node, a).ok()?;
        let b: [u8; 4] = raw.get(..4)?.try_into().ok()?;
        Some(u32::from_le_bytes(b))
    };
    let dt = read(m, ObjectAddress::new(0x1000, 0));
    let v = read(m, ObjectAddress::new(0x1018, 1));
    let p = read(m, ObjectAddress::new(0x1018, 2));
    if let (Some(dt), Some(v)) = (dt, v)
        && let Some(profile) = identify(dt, v, p)
    {
        m.set_profile(node, profile);
    }
}

/// Read `addr` of `node` as a typed value. Without `data_type` the type comes from the node's
/// profile dictionary (the node is identified first if needed); an object outside the
/// dictionary then needs an explicit type ([`CanErrorKind::UnknownType`]).
pub fn upload<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    addr: ObjectAddress,
    data_type: Option<DataType>,
) -> Result<Value, CanError> {
    if data_type.is_none() {
        ensure_profile(m, node);
    }
    m.upload_value(node, addr, data_type)
}

/// Parse `text` for the type of `addr` (explicit or from the profile dictionary; decimal or
/// `0x` hex, with range checks) and write it to `node`.
pub fn download<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    addr: ObjectAddress,
    text: &str,
    data_type: Option<DataType>,
) -> Result<(), CanError> {
    if data_type.is_none() {
        ensure_profile(m, node);
    }
    let dt = m.data_type(node, addr, data_type)?;
    let v = Value::parse(text, dt)
        .map_err(|e| CanError::new(m.node_ref(node), Some(addr), CanErrorKind::Value(e)))?;
    m.download_value(node, addr, &v, Some(dt))
}

/// The text of an abort code: CiA 301, else the vendor codes of `profile` (ASDA-A2
/// 0800 00A1h–00A5h), else "unknown abort code".
pub fn abort_text(code: SdoAbortCode, profile: Option<&CanDriveProfile>) -> AbortText {
    match profile {
        Some(p) => p.abort_text(code),
        None => crate::canopen::sdo::abort_text(code, &[]),
    }
}

/// A value for display: unsigned integers also in hex, strings as text.
pub fn format_value(v: &Value, dt: DataType) -> String {
    match v {
        Value::Uint(u) if !matches!(dt, DataType::Boolean) => {
            let digits = usize::from(dt.bit_len().unwrap_or(32) / 4).max(2);
            format!("{u} (0x{u:0digits$X})")
        }
        Value::Str(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The emulated CANopen drives `ecdrive sim --can` serves, by name, with the node-ID each
/// takes unless one is given (the [`DEMO_NODES`] IDs).
pub const EMULATED_NODES: [(&str, &CanDriveProfile, u8); 4] = [
    ("blv-r", &blv_r::PROFILE, blv_r::EMU_NODE_ID),
    ("asda-a2", &asda_a2::PROFILE, 0x7F),
    ("lexium-mdrive", &lexium_mdrive::PROFILE, 0x41),
    (
        "lexium-mdrive-closed-loop",
        &lexium_mdrive::PROFILE_CLOSED_LOOP,
        0x41,
    ),
];

/// One emulated node to serve: `NAME` or `NAME@ID` (`asda-a2@0x20`), a name of
/// [`EMULATED_NODES`] and a node-ID 1–127 (decimal or 0x hex); or `eds:FILE@ID`, any CiA 402
/// drive emulated from its EDS/DCF file (a DCF's own node-ID unless `@ID` is given); or
/// `NAME+eds:FILE[@ID]`, a drive of the project with its vendor's file as its dictionary.
#[derive(Debug, Clone, Copy)]
pub struct NodeSpec {
    /// The node-ID.
    pub node: u8,
    /// What is emulated: the software slave's own table, or one built from an EDS file.
    pub emulation: &'static Emulation,
    /// Its name in [`EMULATED_NODES`], or the file's product name.
    pub name: &'static str,
}

/// A node-ID as `@ID` gives it: 1–127, decimal or 0x hex.
fn node_id(s: &str, t: &str) -> Result<u8, String> {
    let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u8::from_str_radix(h, 16),
        None => t.parse(),
    };
    match v {
        Ok(v @ 1..=127) => Ok(v),
        _ => Err(format!("{s:?}: the node-ID must be 1–127, not {t:?}")),
    }
}

/// An EDS/DCF file read for emulation, its reader's error as one line naming the file.
pub fn read_eds(path: &str) -> Result<crate::eds::EdsFile, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("EDS file {path}: {e}"))?;
    crate::eds::EdsFile::parse(&bytes).map_err(|e| format!("EDS file {path}: {e}"))
}

impl FromStr for NodeSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (name, id) = match s.rsplit_once('@') {
            Some((n, id)) => (n.trim(), Some(id.trim())),
            None => (s.trim(), None),
        };
        let (table, file) = match name.split_once("eds:") {
            Some((t, f)) => (t.trim_end_matches('+').trim(), Some(f.trim())),
            None => (name, None),
        };
        let builtin = if table.is_empty() {
            None
        } else {
            match EMULATED_NODES.iter().find(|(n, _, _)| *n == table) {
                Some(&(n, _, default)) => {
                    crate::sim::canopen::drives::by_name(n).map(|e| (n, e, default))
                }
                None => {
                    let names: Vec<&str> = EMULATED_NODES.iter().map(|(n, _, _)| *n).collect();
                    return Err(format!(
                        "{table:?} is not an emulated CANopen drive (one of {}, or eds:FILE@ID)",
                        names.join(", ")
                    ));
                }
            }
        };
        let (name, emulation, default) = match (builtin, file) {
            (Some(b), None) => b,
            (None, None) => return Err(format!("{s:?}: name an emulated drive or eds:FILE@ID")),
            (b, Some(path)) => {
                let f = read_eds(path)?;
                let e = match b {
                    Some((_, base, _)) => Emulation::refined(base, &f, path),
                    None => Emulation::from_eds(&f, path)?,
                };
                let name = b.map_or(e.name, |(n, _, _)| n);
                (name, e, b.map_or(f.node_id.unwrap_or(0), |(_, _, d)| d))
            }
        };
        let node = match id {
            None if default == 0 => {
                return Err(format!("{s:?}: give the node-ID: {name}@ID (1–127)"));
            }
            None => default,
            Some(t) => node_id(s, t)?,
        };
        Ok(Self {
            node,
            emulation,
            name,
        })
    }
}

/// Why `ecdrive sim --can` cannot serve.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The nodes cannot be served as given (a node-ID twice, the in-process bus).
    #[error("{0}")]
    Invalid(String),
    /// An emulated node cannot be built.
    #[error("node {node} ({name}): {reason}")]
    Node {
        /// Node-ID.
        node: u8,
        /// Its name.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// The bus could not be opened or failed while serving.
    #[error("CAN bus {bus}: {source}")]
    Bus {
        /// The bus.
        bus: String,
        /// Why.
        #[source]
        source: TransportError,
    },
}

/// What [`serve`] did.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ServeReport {
    /// The bus.
    pub bus: String,
    /// Whether this process ran the `vbus` hub (otherwise one was already there).
    pub started_hub: bool,
    /// The nodes served: node-ID and name.
    pub nodes: Vec<(u8, String)>,
}

/// Serve emulated CANopen drives on a bus until `keep_going` says no: on a SocketCAN interface,
/// or on a `vbus:PATH` virtual bus shared by processes (the hub is started at PATH unless one
/// runs there already; it ends with this call). The nodes keep their state between the
/// commands that use them, as drives on a real bus do. `started` is called once they are up.
pub fn serve(
    bus: &BusSpec,
    nodes: &[NodeSpec],
    started: impl FnOnce(&ServeReport),
    mut keep_going: impl FnMut() -> bool,
) -> Result<ServeReport, ServeError> {
    if nodes.is_empty() {
        return Err(ServeError::Invalid("no nodes to serve".into()));
    }
    for (i, a) in nodes.iter().enumerate() {
        if let Some(b) = nodes[..i].iter().find(|b| b.node == a.node) {
            return Err(ServeError::Invalid(format!(
                "node-ID {} (0x{:02X}) is given twice ({} and {}); add @ID to one of them",
                a.node, a.node, b.name, a.name
            )));
        }
    }
    let mut emulated = Vec::with_capacity(nodes.len());
    for n in nodes {
        emulated.push(
            EmulatedNode::new(n.emulation, n.node).map_err(|e| ServeError::Node {
                node: n.node,
                name: n.name,
                reason: e.to_string(),
            })?,
        );
    }
    let io = |source| ServeError::Bus {
        bus: bus.to_string(),
        source,
    };
    let (mut transport, hub): (Box<dyn CanTransport>, _) = match bus {
        BusSpec::Virtual => {
            return Err(ServeError::Invalid(
                "'virtual' is a bus inside each command's own process; serve on vbus:PATH to \
                 share one between commands (then use --can vbus:PATH with them)"
                    .into(),
            ));
        }
        BusSpec::SocketCan(i) => (Box::new(SocketCanTransport::open(i).map_err(io)?), None),
        BusSpec::UnixHub(p) => {
            // A hub already running there is joined; otherwise this process runs it.
            let hub = match crate::canopen::unix_bus::UnixBusHub::spawn(p) {
                Ok(h) => Some(h),
                Err(TransportError::Io { source, .. })
                    if source.kind() == std::io::ErrorKind::AddrInUse =>
                {
                    None
                }
                Err(e) => return Err(io(e)),
            };
            (Box::new(UnixBusPort::connect(p).map_err(io)?), hub)
        }
    };
    // On a bus others may be on, no node-ID may answer already: two nodes with one ID corrupt
    // each other's frames (a fresh hub of our own has nobody else on it).
    if hub.is_none() {
        let probe = open_bus(bus).map_err(io)?;
        let mut m = Master::new(probe, crate::canopen::master::MasterConfig::default());
        let taken = m
            .probe(nodes.iter().map(|n| n.node), SCAN_WINDOW_US)
            .map_err(|e| ServeError::Invalid(format!("probing {bus} for the node-IDs: {e}")))?;
        if let Some(n) = nodes
            .iter()
            .find(|n| taken.iter().any(|(id, _)| *id == n.node))
        {
            return Err(ServeError::Invalid(format!(
                "node-ID {} (0x{:02X}) already answers on {bus}: give {} another with @ID",
                n.node, n.node, n.name
            )));
        }
    }
    let report = ServeReport {
        bus: bus.to_string(),
        started_hub: hub.is_some(),
        nodes: nodes.iter().map(|n| (n.node, n.name.to_string())).collect(),
    };
    started(&report);
    crate::sim::canopen::serve(transport.as_mut(), &mut emulated, 250, |_| keep_going())
        .map_err(io)?;
    drop(transport);
    drop(hub);
    Ok(report)
}
