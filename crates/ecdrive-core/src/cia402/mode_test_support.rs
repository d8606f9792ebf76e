//! Test support for the profile-mode helpers: an [`Axis`] in front of the [`Device`] model, so
//! the helpers are exercised through the same public API the masters use.

use super::axis::{Axis, AxisConfig, Feedback, Output};
use super::bits::{ControlWord, StatusWord};
use super::caps::DriveCaps;
use super::device::{Device, DeviceConfig, DeviceInputs};
use super::mode::OperationMode;
use super::state::State;
use core::time::Duration;

/// An axis and a device, stepped together. `extra` are the mode-specific statusword bits the
/// test's drive logic sets.
pub struct Rig {
    pub axis: Axis,
    pub device: Device,
    pub extra: StatusWord,
    pub last: Option<Output>,
    pub mode: OperationMode,
}

impl Rig {
    /// An axis in `mode`, enabled (Operation enabled, mode confirmed).
    pub fn enabled(mode: OperationMode) -> Self {
        let caps = DriveCaps::CIA402;
        let cfg = AxisConfig::for_cycle_time(&caps, Duration::from_millis(1), mode);
        let axis = Axis::new(caps, cfg).unwrap();
        let device = Device::new(DeviceConfig::from_caps(
            &caps,
            caps.default_quick_stop_option,
        ));
        let mut rig = Self {
            axis,
            device,
            extra: StatusWord::empty(),
            last: None,
            mode,
        };
        rig.axis.request_enable().unwrap();
        for _ in 0..50 {
            rig.cycle();
        }
        assert_eq!(rig.device.state(), State::OperationEnabled);
        assert!(rig.axis.status().streaming);
        rig
    }

    /// The statusword the drive reports now.
    pub fn statusword(&self) -> StatusWord {
        self.device.statusword() | self.extra
    }

    /// Feedback of this cycle.
    pub fn feedback(&self) -> Feedback {
        let mut fb = Feedback::new(self.statusword());
        fb.mode_display = Some(self.mode);
        fb.position = Some(0);
        fb.velocity = Some(0);
        fb
    }

    /// Axis step, then the device reacts to the controlword. Returns the output.
    pub fn cycle(&mut self) -> Output {
        let fb = self.feedback();
        let out = self.axis.step(&fb);
        self.device.step(&DeviceInputs::new(out.controlword));
        self.last = Some(out);
        out
    }

    /// The last controlword.
    pub fn cw(&self) -> ControlWord {
        self.last.map(|o| o.controlword).unwrap_or_default()
    }
}
