//! Serving named devices on an interface: the library side of `ecdrive sim`.

use super::clock::HostClock;
use super::devices::{self, DeviceError};
use super::esc::EscConfig;
use super::segment::Segment;
use super::sii::SiiError;
use super::transport::{ServeStats, serve};
use crate::link::{LinkError, RawSocket};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

/// What to serve.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimOptions {
    /// Network interface.
    pub interface: String,
    /// Device names in line order (see [`devices::device_names`]).
    pub devices: Vec<String>,
    /// Reset value of the SM watchdog (0x0420) in watchdog units of 100 µs; `None` keeps the ESC
    /// reset value (1000 = 100 ms), `Some(0)` disables it.
    pub sm_watchdog: Option<u16>,
}

/// Why a segment cannot be served.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// No device given.
    #[error("no devices given: name at least one with --device (known: {known})")]
    NoDevices {
        /// The known names.
        known: String,
    },
    /// A device name is unknown or cannot be built.
    #[error("device {position}: {source}")]
    Device {
        /// Position in the line (0-based).
        position: usize,
        /// Why.
        #[source]
        source: DeviceError,
    },
    /// The SII of a device cannot be built.
    #[error("device {position} ({name}): {source}")]
    Sii {
        /// Position in the line (0-based).
        position: usize,
        /// Device name.
        name: String,
        /// Why.
        #[source]
        source: SiiError,
    },
    /// Frame I/O failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

/// Build a segment of named devices on the host clock.
pub fn build_segment(names: &[String], esc: &EscConfig) -> Result<Segment, SimError> {
    if names.is_empty() {
        return Err(SimError::NoDevices {
            known: devices::known_names(),
        });
    }
    let mut seg = Segment::new(Arc::new(HostClock));
    for (position, name) in names.iter().enumerate() {
        let dev = devices::by_name(name, position)
            .map_err(|source| SimError::Device { position, source })?;
        seg.push(dev, esc.clone()).map_err(|source| SimError::Sii {
            position,
            name: name.clone(),
            source,
        })?;
    }
    Ok(seg)
}

/// A segment of named devices with its socket open, ready to serve.
#[derive(Debug)]
pub struct Prepared {
    socket: RawSocket,
    segment: Mutex<Segment>,
}

impl Prepared {
    /// Build the devices of `opts` and open its interface (needs `CAP_NET_RAW`).
    pub fn new(opts: &SimOptions) -> Result<Self, SimError> {
        let mut esc = EscConfig::default();
        if let Some(wd) = opts.sm_watchdog {
            esc.sm_watchdog = wd;
        }
        let segment = build_segment(&opts.devices, &esc)?;
        let socket = RawSocket::open(&opts.interface)?;
        Ok(Self {
            socket,
            segment: Mutex::new(segment),
        })
    }

    /// One line per device: position, name and identity.
    pub fn describe(&self) -> Vec<String> {
        let seg = super::transport::lock(&self.segment);
        seg.slaves()
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let d = s.device.description();
                format!(
                    "{i}: {} ({}) vendor 0x{:08X} product 0x{:08X} revision 0x{:08X} serial {}",
                    d.order,
                    d.name,
                    d.identity.vendor_id,
                    d.identity.product_code,
                    d.identity.revision,
                    d.identity.serial
                )
            })
            .collect()
    }

    /// Serve until `stop` is set.
    pub fn serve(&self, stop: &AtomicBool) -> Result<ServeStats, SimError> {
        Ok(serve(&self.socket, &self.segment, stop)?)
    }
}

/// Serve the devices of `opts` on its interface until `stop` is set.
pub fn serve_interface(opts: &SimOptions, stop: &AtomicBool) -> Result<ServeStats, SimError> {
    Prepared::new(opts)?.serve(stop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_and_missing_devices_are_named() {
        let e = build_segment(&[], &EscConfig::default()).unwrap_err();
        assert!(e.to_string().contains("generic-coe"), "{e}");
        let names = vec!["generic-io".to_string(), "nope".to_string()];
        let e = build_segment(&names, &EscConfig::default()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("device 1: unknown device \"nope\""),
            "{e}"
        );
        let names = vec!["generic-coe".to_string(), "generic-io".to_string()];
        let seg = build_segment(&names, &EscConfig::default()).unwrap();
        assert_eq!(seg.len(), 2);
    }
}
