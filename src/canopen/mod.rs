//! CANopen (CiA 301) master and the CANopen drives, through the same [`crate::cia402`] layer
//! as the EtherCAT drives.
//!
//! Three drives of `/work/shared/manuals` are CANopen drives: the Oriental Motor BLV-R, the
//! Delta ASDA-A2 and the Schneider Lexium MDrive. Their profiles are data in
//! [`crate::drives::blv_r`], [`crate::drives::asda_a2`] and [`crate::drives::lexium_mdrive`]
//! (type: [`profile::CanDriveProfile`]); every drive difference below comes from there.
//!
//! # Layers
//!
//! | module | what |
//! |---|---|
//! | [`frame`] | classic CAN frames, the pre-defined connection set, node-IDs |
//! | [`nmt`], [`sdo`], [`emcy`] | the protocols as typed views and pure state machines (SDO client and server) |
//! | [`transport`] | [`CanTransport`] (send, receive with timeout, time) and the virtual bus [`Hub`] / [`VirtualBus`] |
//! | [`can_socket`] | SocketCAN for real adapters (the `socketcan` crate) |
//! | [`unix_bus`] | the virtual bus across processes: a hub on a Unix datagram socket |
//! | [`profile`] | the drive-profile type and `const` dictionary builders |
//! | [`pdo_plan`] | a drive's PDO configuration, checked against its limits, and the SDO sequence that installs it |
//! | [`master`] | the master: NMT (with the enabled-drive rule), SDO client (paced), SYNC producer, heartbeat consumer, node guarding, EMCY consumer, drive configuration, the cycle |
//! | [`drive`] | a configured drive: process images, fields, and its [`Axis`](crate::cia402::Axis) |
//! | [`emu`] | emulated nodes of the three drives and the deterministic simulated bus [`emu::SimBus`] |
//! | [`tools`] | what `ecdrive slaves/upload/download --can` need |
//! | [`demo`] | `ecdrive demo --canopen` |
//! | [`error`] | errors naming node, drive, object and reason |
//!
//! # For the CLI
//!
//! - Open a bus: [`tools::BusSpec`] parses `can0` (SocketCAN), `virtual` (in-process bus with
//!   the three emulated drives at [`tools::DEMO_NODES`]) or `vbus:/path` (cross-process hub);
//!   [`tools::open_bus`]`(&BusSpec) -> Result<Box<dyn CanTransport>, TransportError>`; then
//!   [`master::Master::new`]`(transport, MasterConfig::default())`.
//! - `slaves --can IF`: [`tools::scan`]`(&mut Master<T>, 1..=127) -> Result<Vec<NodeInfo>,
//!   CanError>`; each [`tools::NodeInfo`] has node-ID, 1000h, 1018h:01–04, 1008h, matched
//!   profile, NMT state, and a one-line `Display`.
//! - `upload --can IF NODE INDEX:SUB [--type T]`: [`tools::upload`]`(&mut m, node, addr,
//!   Option<DataType>) -> Result<Value, CanError>` (type from the profile's dictionary when
//!   `None`); print with [`tools::format_value`].
//! - `download --can IF NODE INDEX:SUB VALUE [--type T]`: [`tools::download`]`(&mut m, node,
//!   addr, text, Option<DataType>) -> Result<(), CanError>`.
//! - Abort texts: [`CanError`](error::CanError)'s `Display` already names node, drive, object,
//!   code and text; [`tools::abort_text`] for a bare code.
//! - `demo --canopen`: [`demo::run`]`(&DemoOptions) -> Result<DemoSummary, CanError>`;
//!   `DemoSummary` implements `Display` and [`demo::DemoSummary::ok`].
//!
//! # Running a drive
//!
//! ```
//! use ecdrive::canopen::emu::{EmulatedNode, SimBus};
//! use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig};
//! use ecdrive::cia402::{ProfilePosition, SetPoint};
//! use ecdrive::drives::blv_r;
//!
//! let mut bus = SimBus::new();
//! bus.add_node(EmulatedNode::new(&blv_r::PROFILE, 3).unwrap());
//! let mut m = Master::new(bus, MasterConfig::default());
//! let mut setup = DriveSetup::new(&blv_r::PROFILE);
//! setup.settings = ecdrive::canopen::demo::motion_settings(&blv_r::PROFILE, 10.0, 100.0);
//! m.configure_drive(3, setup).unwrap(); // identity, supervision, PDOs, mode
//! m.start(3).unwrap(); // NMT start
//! m.enable(3, 1_000_000).unwrap(); // Axis → Operation enabled
//! let mut pp = ProfilePosition::default();
//! pp.push(SetPoint::absolute(36_000)).unwrap();
//! loop {
//!     let mut done = false;
//!     m.cycle_step(|d| {
//!         let sw = d.statusword();
//!         let st = pp.step(d.axis_mut(), sw);
//!         done = st.target_reached && st.acknowledged == 1;
//!     })
//!     .unwrap();
//!     if done {
//!         break;
//!     }
//! }
//! assert_eq!(m.transport().node(3).unwrap().position(), 36_000);
//! m.shutdown_node(3, 1_000_000).unwrap(); // disable, then NMT stop
//! ```

pub mod can_socket;
pub mod demo;
pub mod drive;
pub mod emcy;
pub mod emu;
pub mod error;
pub mod frame;
pub mod master;
pub mod nmt;
pub mod pdo_plan;
pub mod profile;
pub mod sdo;
pub mod tools;
pub mod transport;
pub mod unix_bus;

pub use frame::{CanFrame, FrameError, NodeId, Service};
pub use transport::{CanTransport, Hub, PortId, TransportError, VirtualBus, VirtualPort};
