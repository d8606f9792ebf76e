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
//! | [`frame`], [`nmt`], [`sdo`], [`emcy`], [`transport`], [`profile`] | re-exported from [`crate::can`]: the wire vocabulary and protocols the master shares with the emulated nodes |
//! | [`can_socket`] | SocketCAN for real adapters (the `socketcan` crate) |
//! | [`unix_bus`] | the virtual bus across processes: a hub on a Unix datagram socket |
//! | [`pdo_plan`] | a drive's PDO configuration, checked against its limits, and the SDO sequence that installs it |
//! | [`master`] | the master: NMT (with the enabled-drive rule), SDO client (paced), SYNC producer, heartbeat consumer, node guarding, EMCY consumer, drive configuration, the cycle |
//! | [`drive`] | a configured drive: process images, fields, and its [`Axis`](crate::cia402::Axis) |
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
//! The example in [`demo`] runs the BLV-R on the software slave's simulated bus: configure,
//! start, enable, a pp move, shut down.

pub use ecdrive_canopen::*;

pub mod demo;
pub mod tools;
