//! A simulated servo for the axis-engine tests: the `cia402::device` state machine plus a crude
//! motion model and a mode switch that takes `mode_lag` cycles and, where the caps say so, only
//! happens at zero speed (MR-J4-TM §5.4.2).
#![allow(dead_code)]

use ecdrive_core::cia402::device::{Device, DeviceConfig, DeviceInputs};
use ecdrive_core::cia402::{
    ControlWord, DriveCaps, ErrorCode, Feedback, OperationMode, Output, State, StatusWord,
};

pub struct SimServo {
    pub caps: DriveCaps,
    pub device: Device,
    /// 0x6061.
    pub mode: OperationMode,
    /// The last 0x6060 received and for how many cycles it has been waiting.
    pending: Option<(OperationMode, u32)>,
    /// Cycles a mode switch takes; `u32::MAX` = never.
    pub mode_lag: u32,
    pub position: i32,
    pub velocity: i32,
    pub torque: i16,
    pub fault: bool,
    pub error_code: u16,
    /// Deceleration per cycle while stopping on its own (quick stop, fault, coasting).
    pub decel: i32,
    /// Mode writes the drive refused because the motor turned (zero-speed rule).
    pub refused_mode_writes: u32,
    /// 0x6060 values that took effect while the motor turned.
    pub switched_while_moving: u32,
    pub outputs: Vec<Output>,
}

impl SimServo {
    pub fn new(caps: DriveCaps, start: State, mode: OperationMode) -> Self {
        let cfg = DeviceConfig::from_caps(&caps, caps.default_quick_stop_option);
        Self {
            caps,
            device: Device::with_state(cfg, start),
            mode,
            pending: None,
            mode_lag: 2,
            position: 0,
            velocity: 0,
            torque: 0,
            fault: false,
            error_code: 0,
            decel: 10,
            refused_mode_writes: 0,
            switched_while_moving: 0,
            outputs: Vec::new(),
        }
    }

    pub fn feedback(&self) -> Feedback {
        Feedback {
            statusword: self.device.statusword()
                | if self.device.state() == State::OperationEnabled {
                    StatusWord::DRIVE_FOLLOWS_COMMAND
                } else {
                    StatusWord::empty()
                },
            mode_display: Some(self.mode),
            position: Some(self.position),
            velocity: Some(self.velocity),
            torque: Some(self.torque),
            error_code: Some(ErrorCode(self.error_code)),
            zero_speed: None,
        }
    }

    pub fn apply(&mut self, out: &Output) {
        self.outputs.push(*out);
        self.device.step(&DeviceInputs {
            controlword: out.controlword,
            fault: self.fault,
            motion_stopped: self.velocity == 0,
            main_power: true,
            remote: true,
            warning: false,
        });
        self.switch_mode(out.mode);
        self.move_axis(out);
    }

    fn switch_mode(&mut self, requested: OperationMode) {
        if requested == self.mode || requested == OperationMode::NoMode {
            self.pending = None;
            return;
        }
        if !self.caps.supported_modes.contains(requested) {
            return; // ignored, 0x6061 keeps the old mode
        }
        let position_involved =
            self.caps.is_position_mode(requested) || self.caps.is_position_mode(self.mode);
        let moving = self.velocity != 0;
        if self.caps.position_mode_switch_needs_zero_speed && position_involved && moving {
            self.refused_mode_writes += 1;
            self.pending = None;
            return;
        }
        let waited = match self.pending {
            Some((m, n)) if m == requested => n + 1,
            _ => 0,
        };
        if waited >= self.mode_lag {
            if moving && position_involved {
                self.switched_while_moving += 1;
            }
            self.mode = requested;
            self.pending = None;
        } else {
            self.pending = Some((requested, waited));
        }
    }

    fn move_axis(&mut self, out: &Output) {
        let toward_zero = |v: i32, d: i32| {
            if v > 0 {
                (v - d).max(0)
            } else {
                (v + d).min(0)
            }
        };
        match self.device.state() {
            State::OperationEnabled => match self.mode {
                OperationMode::CyclicSyncPosition => {
                    self.velocity = out.target_position.wrapping_sub(self.position);
                    self.position = out.target_position;
                }
                OperationMode::CyclicSyncVelocity => {
                    self.velocity = out.target_velocity;
                    self.position = self.position.wrapping_add(self.velocity);
                }
                OperationMode::CyclicSyncTorque => {
                    self.torque = out.target_torque;
                    self.velocity += i32::from(self.torque) / 10;
                    self.position = self.position.wrapping_add(self.velocity);
                }
                _ => {
                    if out.controlword.contains(ControlWord::HALT) {
                        self.velocity = toward_zero(self.velocity, self.decel);
                    }
                    self.position = self.position.wrapping_add(self.velocity);
                }
            },
            _ => {
                self.velocity = toward_zero(self.velocity, self.decel);
                self.position = self.position.wrapping_add(self.velocity);
                self.torque = 0;
            }
        }
    }
}
