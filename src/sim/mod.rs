//! The software EtherCAT slave: emulated slave controllers (ESC) with SII, SyncManagers, FMMUs,
//! mailbox, distributed clocks and the device applications behind them.
//!
//! - [`esc::Esc`]: one slave controller, register-accurate on the wire;
//! - [`device::Device`]: the firmware behind it (state checks, mailbox, process data at SYNC0);
//! - [`sii`]: the SII EEPROM image, built from a [`sii::DeviceDescription`];
//! - [`segment::Segment`]: a line of slaves processing frames in place;
//! - [`transport`]: serving a segment on a raw socket, to ethercrab's `PduTx`/`PduRx`
//!   in-process, or as a synchronous [`link::FrameLink`](crate::link::FrameLink);
//! - [`coe`]: the CoE mailbox server and object dictionary store devices use;
//! - [`devices`]: ready-made test devices;
//! - [`clock`]: host and manual time sources.

pub mod clock;
pub mod coe;
pub mod device;
pub mod devices;
pub mod esc;
pub mod probe;
pub mod rec;
pub mod run;
pub mod segment;
pub mod sii;
pub mod transport;

pub use clock::{Clock, HostClock, ManualClock};
pub use device::{Device, ProcessDataSizes, StateRequest, SyncEvent, SyncKind};
pub use esc::{DcSupport, Esc, EscConfig};
pub use segment::{Segment, SegmentConfig, SegmentError, Slave};
pub use sii::DeviceDescription;
