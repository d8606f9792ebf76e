//! # ecdrive-sim
//!
//! The software EtherCAT slave: emulated slave controllers (ESC) with SII, SyncManagers, FMMUs,
//! mailbox, distributed clocks and the device applications behind them.
//!
//! - [`esc::Esc`]: one slave controller, register-accurate on the wire;
//! - [`device::Device`]: the firmware behind it (state checks, mailbox, process data at SYNC0);
//! - [`sii`]: the SII EEPROM image, built from a [`sii::DeviceDescription`];
//! - [`segment::Segment`]: a line of slaves processing frames in place;
//! - [`transport`]: serving a segment on a raw socket, to ethercrab's `PduTx`/`PduRx`
//!   in-process, or as a synchronous [`crate::link::FrameLink`];
//! - [`coe`]: the CoE mailbox server and object dictionary store devices use;
//! - [`foe`]: the FoE server (files, firmware images) of devices with file access;
//! - [`devices`]: ready-made test devices (generic CoE servo, EEPROM-only I/O, mailbox echo);
//! - [`drives`]: the emulated drives (MR-J4-TM, BDHDE), built from their ESI files and their
//!   own behaviour tables;
//! - [`canopen`]: the emulated CANopen drives (BLV-R, ASDA-A2, Lexium MDrive) and the
//!   deterministic simulated CAN bus [`canopen::SimBus`];
//! - [`faults`]: fault injection from any thread, without locks or allocation: lost, delayed
//!   and corrupted frames, a pulled cable, a slave restarting to INIT, clock drift, drive
//!   alarms, SDO aborts, emergencies in the middle of an SDO transfer;
//! - [`clock`]: host and manual time sources;
//! - [`probe`]: a minimal datagram sender for tests and tools;
//! - [`quirks`]: behaviour of devices ecdrive did not write, switchable on the emulated devices
//!   (`bdhde+no-state-skipping`);
//! - [`run`]: serving named devices on an interface (`ecdrive sim`);
//! - [`rec`]: the emulation's own choices (\[REC\]) in one place.
//!
//! ```
//! use ecdrive_core::ec::Command;
//! use ecdrive_sim::{ManualClock, Segment, devices::IoDevice, probe::Probe};
//! use std::sync::Arc;
//!
//! let mut segment = Segment::new(Arc::new(ManualClock::new(0)));
//! for _ in 0..3 {
//!     segment.push_device(Box::new(IoDevice::new(2, 4))).unwrap();
//! }
//! let mut probe = Probe::new(segment);
//! let reply = probe.brd(0x0000, 1).unwrap(); // count the slaves, as masters do
//! assert_eq!((reply.wkc, reply.adp), (3, 3));
//! ```

#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

// The core layers this crate builds on, under the paths the modules use. The masters' drive
// profiles (the core's `drives` module) are left out on purpose: the emulated drives are
// built from their ESI files and their own tables (crates/ecdrive-sim/tests/sim/emulation_independence.rs).
pub(crate) use ecdrive_core::{can, cia402, ec, eds, esi, link, od, pdo, rt};

pub mod canopen;
pub mod clock;
pub mod coe;
pub mod device;
pub mod devices;
pub mod drives;
pub mod esc;
pub mod faults;
pub mod foe;
pub mod machine;
pub mod probe;
pub mod quirks;
pub mod rec;
pub mod run;
pub mod segment;
pub mod sii;
pub mod transport;

pub use clock::{Clock, HostClock, ManualClock};
pub use device::{Device, ProcessDataSizes, StateRequest, SyncEvent, SyncKind};
pub use esc::{DcSupport, Esc, EscConfig};
pub use faults::{DeviceFault, Fault, FaultHandle, LinkFault, SlaveFault};
pub use segment::{Segment, SegmentConfig, SegmentError, SegmentReply, SegmentStats, Slave};
pub use sii::DeviceDescription;
