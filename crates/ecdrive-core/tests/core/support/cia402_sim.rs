//! A simulated drive for the planner tests: the `cia402::device` model, a statusword delay of
//! `lag` cycles, and a stop ramp of `ramp_cycles` cycles for quick stops and fault reactions.
#![allow(dead_code)]

use std::collections::VecDeque;

use ecdrive_core::cia402::device::{Device, DeviceConfig, DeviceInputs, Reaction};
use ecdrive_core::cia402::{ControlWord, State, StatusWord};

pub struct SimDrive {
    pub device: Device,
    /// Statuswords in flight: the master sees the front, the drive pushes at the back.
    in_flight: VecDeque<StatusWord>,
    pub ramp_cycles: u32,
    ramp_left: u32,
    pub fault: bool,
    pub main_power: bool,
    pub remote: bool,
    /// Every reaction so far, with the controlword that caused it.
    pub log: Vec<(ControlWord, State, Reaction)>,
}

impl SimDrive {
    pub fn new(config: DeviceConfig, start: State, lag: usize, ramp_cycles: u32) -> Self {
        let device = Device::with_state(config, start);
        let sw = device.statusword();
        let ramp_left = if matches!(start, State::QuickStopActive | State::FaultReactionActive) {
            ramp_cycles
        } else {
            0
        };
        Self {
            device,
            in_flight: std::iter::repeat_n(sw, lag + 1).collect(),
            ramp_cycles,
            ramp_left,
            fault: false,
            main_power: true,
            remote: true,
            log: Vec::new(),
        }
    }

    /// The statusword the master receives this cycle.
    pub fn seen(&self) -> StatusWord {
        self.in_flight.front().copied().unwrap_or_default()
    }

    /// The motor has stopped (what a velocity feedback would tell the master).
    pub fn standstill(&self) -> bool {
        self.ramp_left == 0
    }

    /// The drive processes `cw`.
    pub fn apply(&mut self, cw: ControlWord) -> Reaction {
        let before = self.device.state();
        let inputs = DeviceInputs {
            controlword: cw,
            fault: self.fault,
            motion_stopped: self.ramp_left == 0,
            main_power: self.main_power,
            remote: self.remote,
            warning: false,
        };
        let r = self.device.step(&inputs);
        let after = self.device.state();
        let stopping = matches!(after, State::QuickStopActive | State::FaultReactionActive);
        if after != before && stopping {
            self.ramp_left = self.ramp_cycles;
        } else if stopping {
            self.ramp_left = self.ramp_left.saturating_sub(1);
        } else {
            self.ramp_left = 0;
        }
        self.log.push((cw, before, r));
        self.in_flight.pop_front();
        self.in_flight.push_back(self.device.statusword());
        r
    }
}
