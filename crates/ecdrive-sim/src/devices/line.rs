//! A line of emulated devices by name: what the examples, the jitter harness and the tests
//! run the master against in-process.

use super::{DeviceError, by_name};
use crate::{EscConfig, HostClock, Segment};
use std::sync::Arc;

/// \[REC\] The emulated oscillators: device `i` of a [`line`] runs `DRIFT_PPB[i % 4]` fast
/// (negative: slow) against the host clock, with its local clock `i × 13.7 µs` ahead. Real
/// crystals are specified to ±50–100 ppm; without drift the DC difference would be trivially
/// zero and say nothing about the master's drift compensation.
pub const DRIFT_PPB: [i64; 4] = [30_000, -20_000, 45_000, -35_000];

/// Why a [`line`] cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum LineError {
    /// No device named.
    #[error("no devices to emulate")]
    Empty,
    /// The device name is unknown or the device cannot be built.
    #[error("emulated device {position}: {source}")]
    Device {
        /// Position in the line.
        position: usize,
        /// Why.
        #[source]
        source: DeviceError,
    },
    /// The SII of a device cannot be built.
    #[error("emulated device {position} ({name}): {reason}")]
    Sii {
        /// Position in the line.
        position: usize,
        /// Device name.
        name: String,
        /// Why.
        reason: String,
    },
}

/// A fresh segment of the named devices ([`by_name`]) on the host clock, every ESC recording
/// its timing statistics ([`crate::esc::TimingStats`]), each with its own oscillator
/// ([`DRIFT_PPB`]) and offset. The SM watchdog is off so that a stalled master ends in a
/// late-cycle count rather than an aborted run.
///
/// ```
/// let seg = ecdrive_sim::devices::line(&["mr-j4-tm", "bdhde"]).unwrap();
/// assert_eq!(seg.len(), 2);
/// ```
pub fn line<S: AsRef<str>>(names: &[S]) -> Result<Segment, LineError> {
    if names.is_empty() {
        return Err(LineError::Empty);
    }
    let mut seg = Segment::new(Arc::new(HostClock));
    for (position, name) in names.iter().enumerate() {
        let name = name.as_ref();
        let dev =
            by_name(name, position).map_err(|source| LineError::Device { position, source })?;
        let at = seg
            .push(
                dev,
                EscConfig {
                    sm_watchdog: 0,
                    clock_drift_ppb: DRIFT_PPB[position % DRIFT_PPB.len()],
                    clock_offset_ns: position as i64 * 13_700,
                    ..Default::default()
                },
            )
            .map_err(|e| LineError::Sii {
                position,
                name: name.to_string(),
                reason: e.to_string(),
            })?;
        if let Some(s) = seg.slave_mut(at) {
            s.esc.enable_timing_stats();
        }
    }
    Ok(seg)
}
