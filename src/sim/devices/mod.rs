//! Ready-made emulated devices for tests, benchmarks and `ecdrive sim`.
//!
//! - [`IoDevice`]: a digital-I/O-like device without mailbox. Its PDOs come from the SII
//!   (TxPDO/RxPDO categories), SyncManagers and FMMUs from the SII too: the path ethercrab and
//!   SOEM take for EEPROM-only devices. Inputs echo the outputs behind a cycle counter, so a test
//!   can see the process data round trip.
//! - [`EchoMailbox`]: a device with a standard mailbox whose firmware returns every request
//!   unchanged; it exercises the SyncManager mailbox handshake without any protocol.
//!
//! [`by_name`] creates devices from the names `ecdrive sim --device` accepts.

mod echo;
mod io;

pub use echo::EchoMailbox;
pub use io::{IoDevice, IoObservations};

use super::device::Device;

/// Names accepted by [`by_name`], with a one-line description each.
pub const DEVICE_NAMES: &[(&str, &str)] = &[
    (
        "generic-io",
        "digital I/O without mailbox: 2 output bytes, 4 input bytes (counter + echo), DC capable",
    ),
    (
        "echo-mailbox",
        "mailbox device that returns every mailbox request unchanged (no process data)",
    ),
];

/// Create a device by name (see [`DEVICE_NAMES`]). `position` makes serial numbers unique.
pub fn by_name(name: &str, position: usize) -> Option<Box<dyn Device>> {
    let serial = u32::try_from(position).unwrap_or(u32::MAX);
    match name {
        "generic-io" => Some(Box::new(IoDevice::new(2, 4).with_serial(serial))),
        "echo-mailbox" => Some(Box::new(EchoMailbox::new().with_serial(serial))),
        _ => None,
    }
}
