//! The drive side of the profile modes and a simple motor, for the emulated nodes.
//!
//! Good enough for pp, pv, tq, hm and ip to run to completion with the timing and status bits
//! the manuals describe; not a physical model. The axis follows its demand exactly (no following
//! error unless injected). Positions are kept in the drive's position units as `f64` ("world"
//! coordinates); the reported position is world + an offset that homing sets.
//!
//! Every number here that is not from a manual is in [`World`] or the constants below, labelled
//! \[REC\].

use super::quirks::EmulationQuirks;
use super::spec::NodeSpec;
use crate::can::profile::{HomingSupport, Units};
use crate::cia402::{ControlWord, OperationMode, State, StatusWord};

/// **\[REC\]** Velocity below which the motor counts as stopped, rev/s.
pub const STOPPED_REV_S: f64 = 1e-4;
/// **\[REC\]** Speed window for "speed reached" when the drive has no 606Dh, rev/s.
pub const DEFAULT_SPEED_WINDOW_REV_S: f64 = 0.05;
/// **\[REC\]** Zero-speed threshold when the drive has no 606Fh, rev/s.
pub const DEFAULT_ZERO_SPEED_REV_S: f64 = 0.05;
/// **\[REC\]** Acceleration used when a ramp object is 0 or absent, rev/s².
pub const FALLBACK_ACCEL_REV_S2: f64 = 100.0;
/// **\[REC\]** Profile velocity of a drive with neither 6081h nor 607Fh (an EDS file that
/// lists neither), rev/s.
pub const FALLBACK_PROFILE_VELOCITY_REV_S: f64 = 1.0;
/// **\[REC\]** Acceleration that stands for "immediately" (a time of 0 ms), rev/s².
pub const STEP_ACCEL_REV_S2: f64 = 1.0e6;
/// **\[REC\]** Torque-mode load: at 1000 ‰ the speed settles at this many rev/s.
pub const TORQUE_SPEED_REV_S: f64 = 20.0;
/// **\[REC\]** Torque-mode load time constant, s.
pub const TORQUE_TIME_CONSTANT_S: f64 = 0.05;
/// **\[REC\]** Homing: distance before the reference at which the slow speed takes over, rev.
pub const HOMING_CREEP_REV: f64 = 0.05;

pub use crate::machine::World;

/// The objects the motion reads each tick (already converted where noted).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// 607Ah, reported units.
    pub target_position: i32,
    /// 6081h → position units/s.
    pub profile_velocity: f64,
    /// 6083h → position units/s².
    pub acceleration: f64,
    /// 6084h → position units/s².
    pub deceleration: f64,
    /// 6085h → position units/s².
    pub quick_stop_deceleration: f64,
    /// 60FFh → position units/s.
    pub target_velocity: f64,
    /// 6071h, ‰.
    pub target_torque: f64,
    /// 6087h → ‰/s.
    pub torque_slope: f64,
    /// 6098h.
    pub homing_method: i8,
    /// 6099h:01 → position units/s.
    pub homing_fast: f64,
    /// 6099h:02 → position units/s.
    pub homing_slow: f64,
    /// 609Ah → position units/s².
    pub homing_acceleration: f64,
    /// 607Ch, reported units.
    pub home_offset: i32,
    /// 6067h, position units.
    pub position_window: f64,
    /// 606Dh → position units/s.
    pub velocity_window: f64,
    /// 606Fh → position units/s.
    pub zero_speed_threshold: f64,
    /// 605Dh: 2 = halt on the quick-stop ramp, else the mode's deceleration.
    pub halt_option: i16,
    /// 60C1h:01, reported units.
    pub ip_position: i32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum HomingRun {
    Idle,
    /// Moving to `reference`: the home, or (`failing`) the limit switch where a search that
    /// finds no home switch ends in a homing error.
    Running {
        reference: f64,
        stopping: bool,
        failing: bool,
    },
    Done,
    Error,
    Interrupted,
}

/// The drive-side motion state.
#[derive(Debug, Clone)]
pub struct Motion {
    /// World position, position units.
    pub pos: f64,
    /// Velocity, position units/s.
    pub vel: f64,
    /// Torque, ‰ of rated.
    pub torque: f64,
    /// Reported position = world + offset.
    pub offset: f64,
    /// Inject a following error (statusword bit 13 in pp/ip).
    pub following_error: bool,
    world: World,
    ppr: f64,
    // pp
    pp_ack: bool,
    pp_last_bit4: bool,
    pp_active: Option<f64>,
    pp_buffer: Option<f64>,
    pp_base: f64,
    pp_any: bool,
    // hm
    hm: HomingRun,
    hm_last_bit4: bool,
    // ip
    ip_from: f64,
    ip_to: f64,
    ip_sync_us: Option<u64>,
    ip_period_us: u64,
    last_mode: OperationMode,
    was_enabled: bool,
}

fn approach(v: f64, target: f64, acc: f64, dec: f64, dt: f64) -> f64 {
    let speeding_up = target.abs() > v.abs() && (target * v >= 0.0);
    let rate = if speeding_up { acc } else { dec };
    let step = rate * dt;
    if (target - v).abs() <= step {
        target
    } else if target > v {
        v + step
    } else {
        v - step
    }
}

impl Motion {
    /// A motor at rest at world position 0.
    pub fn new(world: World, units: &Units) -> Self {
        Self {
            pos: 0.0,
            vel: 0.0,
            torque: 0.0,
            offset: 0.0,
            following_error: false,
            world,
            ppr: units.position_per_rev,
            pp_ack: false,
            pp_last_bit4: false,
            pp_active: None,
            pp_buffer: None,
            pp_base: 0.0,
            pp_any: false,
            hm: HomingRun::Idle,
            hm_last_bit4: false,
            ip_from: 0.0,
            ip_to: 0.0,
            ip_sync_us: None,
            ip_period_us: 0,
            last_mode: OperationMode::NoMode,
            was_enabled: false,
        }
    }

    /// The reported position (wraps like a 32-bit counter).
    pub fn reported_position(&self) -> i32 {
        ((self.pos + self.offset).round() as i64) as i32
    }

    /// World coordinates of a reported position.
    fn world_of(&self, reported: i32) -> f64 {
        f64::from(reported) - self.offset
    }

    /// The machine around the motor.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Position units per revolution.
    pub fn ppr(&self) -> f64 {
        self.ppr
    }

    /// Digital inputs 60FDh: bit 0 negative limit, bit 1 positive limit, bit 2 home switch.
    pub fn digital_inputs(&self) -> u32 {
        self.world.digital_inputs(self.pos, self.ppr)
    }

    fn stopped(&self) -> bool {
        self.vel.abs() <= STOPPED_REV_S * self.ppr
    }

    /// A SYNC arrived at `now_us` with 60C1h:01 = `ip_position` (reported units).
    pub fn on_sync(&mut self, now_us: u64, ip_position: i32, period_hint_us: u64) {
        if let Some(t) = self.ip_sync_us {
            self.ip_period_us = now_us.saturating_sub(t).max(1);
        } else {
            self.ip_period_us = period_hint_us.max(1);
        }
        self.ip_sync_us = Some(now_us);
        self.ip_from = self.pos;
        self.ip_to = self.world_of(ip_position);
    }

    /// One tick of `dt` seconds at `now_us`. Returns the mode-specific statusword bits (10, 12,
    /// 13, 14) and whether the motor is stopped.
    #[allow(clippy::too_many_arguments)]
    pub fn tick(
        &mut self,
        now_us: u64,
        dt: f64,
        state: State,
        mode: OperationMode,
        cw: ControlWord,
        p: &Params,
        spec: &NodeSpec,
        quirks: &EmulationQuirks,
        quick_stop_immediate: bool,
    ) -> (StatusWord, bool) {
        let enabled = state == State::OperationEnabled;
        if enabled && !self.was_enabled {
            self.pp_base = self.pos + self.offset;
            self.pp_active = None;
            self.pp_buffer = None;
            self.pp_ack = false;
            self.pp_any = false;
            self.hm = HomingRun::Idle;
            self.ip_from = self.pos;
            self.ip_to = self.pos;
            self.ip_sync_us = None;
        }
        if mode != self.last_mode {
            self.pp_active = None;
            self.pp_buffer = None;
            self.pp_ack = false;
            self.pp_any = false;
            self.pp_base = self.pos + self.offset;
            self.hm = HomingRun::Idle;
            self.ip_from = self.pos;
            self.ip_to = self.pos;
            self.last_mode = mode;
        }
        self.was_enabled = enabled;

        let mut bits = StatusWord::empty();
        match state {
            State::OperationEnabled => {
                bits = self.run_mode(now_us, dt, mode, cw, p, spec, quirks);
            }
            State::QuickStopActive | State::FaultReactionActive => {
                self.torque = 0.0;
                if quick_stop_immediate {
                    self.vel = 0.0;
                } else {
                    let d = p.quick_stop_deceleration;
                    self.vel = approach(self.vel, 0.0, d, d, dt);
                }
                self.pos += self.vel * dt;
                if self.stopped() {
                    bits |= StatusWord::TARGET_REACHED;
                }
            }
            _ => {
                // Power stage off: the emulated motor stops at once.
                self.vel = 0.0;
                self.torque = 0.0;
            }
        }
        (bits, self.stopped())
    }

    fn halted_decel(&self, p: &Params, mode_decel: f64) -> f64 {
        if p.halt_option == 2 {
            p.quick_stop_deceleration
        } else {
            mode_decel
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn run_mode(
        &mut self,
        now_us: u64,
        dt: f64,
        mode: OperationMode,
        cw: ControlWord,
        p: &Params,
        spec: &NodeSpec,
        quirks: &EmulationQuirks,
    ) -> StatusWord {
        let halt = cw.contains(ControlWord::HALT);
        let mut bits = StatusWord::empty();
        match mode {
            OperationMode::ProfilePosition => {
                self.pp_handshake(cw, p);
                if halt {
                    let d = self.halted_decel(p, p.deceleration);
                    self.vel = approach(self.vel, 0.0, d, d, dt);
                    self.pos += self.vel * dt;
                    bits.set(StatusWord::TARGET_REACHED, self.stopped());
                } else {
                    let arrived = self.pp_move(dt, p);
                    bits.set(StatusWord::TARGET_REACHED, arrived && self.pp_any);
                }
                bits.set(StatusWord::SET_POINT_ACKNOWLEDGE, self.pp_ack);
                bits.set(StatusWord::FOLLOWING_ERROR, self.following_error);
            }
            OperationMode::ProfileVelocity => {
                let target = if halt { 0.0 } else { p.target_velocity };
                let dec = if halt {
                    self.halted_decel(p, p.deceleration)
                } else {
                    p.deceleration
                };
                self.vel = approach(self.vel, target, p.acceleration, dec, dt);
                self.pos += self.vel * dt;
                bits.set(
                    StatusWord::TARGET_REACHED,
                    (self.vel - target).abs() <= p.velocity_window,
                );
                if quirks.pv_zero_speed_bit {
                    bits.set(
                        StatusWord::SPEED_ZERO,
                        self.vel.abs() <= p.zero_speed_threshold,
                    );
                }
            }
            OperationMode::ProfileTorque => {
                let target = if halt { 0.0 } else { p.target_torque };
                let slope = p.torque_slope;
                self.torque = approach(self.torque, target, slope, slope, dt);
                // First-order load: the speed settles at torque × TORQUE_SPEED.
                let v_ss = self.torque / 1000.0 * TORQUE_SPEED_REV_S * self.ppr;
                let k = (dt / TORQUE_TIME_CONSTANT_S).min(1.0);
                self.vel += (v_ss - self.vel) * k;
                if self.torque == 0.0 && self.stopped() {
                    self.vel = 0.0;
                }
                self.pos += self.vel * dt;
                bits.set(
                    StatusWord::TARGET_REACHED,
                    (self.torque - target).abs() < 0.5,
                );
            }
            OperationMode::Homing => {
                bits = self.homing(dt, cw, p, &spec.homing);
            }
            OperationMode::InterpolatedPosition => {
                let enabled =
                    !quirks.ip_needs_enable_bit || cw.contains(ControlWord::NEW_SET_POINT);
                let sync_ok = self
                    .ip_sync_us
                    .is_some_and(|t| now_us.saturating_sub(t) <= 2 * self.ip_period_us.max(1));
                if enabled && sync_ok && !halt {
                    let t = now_us.saturating_sub(self.ip_sync_us.unwrap_or(now_us)) as f64;
                    let frac = (t / self.ip_period_us.max(1) as f64).min(1.0);
                    let new = self.ip_from + (self.ip_to - self.ip_from) * frac;
                    self.vel = if dt > 0.0 { (new - self.pos) / dt } else { 0.0 };
                    self.pos = new;
                } else {
                    let d = p.quick_stop_deceleration;
                    self.vel = approach(self.vel, 0.0, d, d, dt);
                    self.pos += self.vel * dt;
                }
                bits.set(StatusWord::from_raw(1 << 12), enabled);
                bits.set(StatusWord::from_raw(1 << 14), sync_ok);
                bits.set(StatusWord::FOLLOWING_ERROR, self.following_error);
                bits.set(
                    StatusWord::TARGET_REACHED,
                    (self.pos - self.ip_to).abs() < 0.5 && self.stopped(),
                );
            }
            _ => {
                // No mode or an unsupported one: hold still.
                self.vel = 0.0;
            }
        }
        bits
    }

    fn pp_handshake(&mut self, cw: ControlWord, p: &Params) {
        let bit4 = cw.contains(ControlWord::NEW_SET_POINT);
        if bit4 && !self.pp_last_bit4 && !self.pp_ack {
            let relative = cw.contains(ControlWord::RELATIVE);
            let immediate = cw.contains(ControlWord::CHANGE_SET_IMMEDIATELY);
            // Relative moves count from the previous target (BLV-R 60F2h default).
            let reported = if relative {
                self.pp_base + f64::from(p.target_position)
            } else {
                f64::from(p.target_position)
            };
            self.pp_base = reported;
            let world = reported - self.offset;
            if immediate || self.pp_active.is_none() {
                self.pp_active = Some(world);
                self.pp_buffer = None;
            } else {
                self.pp_buffer = Some(world);
            }
            self.pp_any = true;
            self.pp_ack = true;
        } else if !bit4 && self.pp_ack && self.pp_buffer.is_none() {
            self.pp_ack = false;
        }
        self.pp_last_bit4 = bit4;
    }

    /// Move toward the active pp target; true when there is none left (arrived).
    fn pp_move(&mut self, dt: f64, p: &Params) -> bool {
        let Some(target) = self.pp_active else {
            self.vel = approach(self.vel, 0.0, p.deceleration, p.deceleration, dt);
            self.pos += self.vel * dt;
            return self.stopped();
        };
        let arrived = self.move_to(
            target,
            p.profile_velocity,
            p.acceleration,
            p.deceleration,
            dt,
        );
        if arrived {
            self.pp_active = self.pp_buffer.take();
            return self.pp_active.is_none()
                && (self.pos - target).abs() <= p.position_window.max(0.5);
        }
        false
    }

    /// One step of a trapezoidal move to `target`; true on arrival (snapped, stopped).
    fn move_to(&mut self, target: f64, vmax: f64, acc: f64, dec: f64, dt: f64) -> bool {
        let d = target - self.pos;
        if d.abs() < 0.5 && self.vel.abs() * dt < 0.5 {
            self.pos = target;
            self.vel = 0.0;
            return true;
        }
        let brake = (2.0 * dec * d.abs()).sqrt();
        let desired = d.signum() * vmax.abs().min(brake);
        self.vel = approach(self.vel, desired, acc, dec, dt);
        let next = self.pos + self.vel * dt;
        if (target - next).signum() != d.signum() || (target - next).abs() < 0.5 {
            self.pos = target;
            self.vel = 0.0;
            return true;
        }
        self.pos = next;
        false
    }

    /// Where the method ends on the machine ([`crate::machine::homing_end`]), and whether it
    /// ends there in a homing error (a search that finds no home switch runs into a limit
    /// switch, as on the EtherCAT drives); `None` when it cannot start (unknown method, no
    /// index pulse).
    fn homing_reference(&self, method: i8, hs: &HomingSupport) -> Option<(f64, bool)> {
        // **\[REC\]** A vendor method −1 (the BLV-R lists it) ends on the home switch's edge,
        // as method 19 does.
        let method = if method == -1 { 19 } else { method };
        match crate::machine::homing_end(method, &self.world, self.pos, self.ppr, hs.index_pulse) {
            crate::machine::HomingEnd::Reference(r) => Some((r, false)),
            crate::machine::HomingEnd::Fails { at } => Some((at, true)),
            _ => None,
        }
    }

    fn homing(&mut self, dt: f64, cw: ControlWord, p: &Params, hs: &HomingSupport) -> StatusWord {
        let bit4 = cw.contains(ControlWord::HOMING_START);
        let edge = bit4 && !self.hm_last_bit4;
        self.hm_last_bit4 = bit4;
        if edge {
            self.hm = match self.homing_reference(p.homing_method, hs) {
                Some((reference, failing)) if hs.supports(p.homing_method) => HomingRun::Running {
                    reference,
                    stopping: false,
                    failing,
                },
                _ => HomingRun::Error,
            };
        }
        if !bit4
            && let HomingRun::Running {
                reference, failing, ..
            } = self.hm
        {
            self.hm = HomingRun::Running {
                reference,
                stopping: true,
                failing,
            };
        }
        let halt = cw.contains(ControlWord::HALT);
        match self.hm {
            HomingRun::Running {
                reference,
                stopping,
                failing,
            } => {
                if stopping || halt {
                    let d = p.homing_acceleration;
                    self.vel = approach(self.vel, 0.0, d, d, dt);
                    self.pos += self.vel * dt;
                    if stopping && self.stopped() {
                        self.hm = HomingRun::Interrupted;
                    }
                } else {
                    let near = (reference - self.pos).abs() <= HOMING_CREEP_REV * self.ppr;
                    let speed = if near { p.homing_slow } else { p.homing_fast };
                    let a = p.homing_acceleration;
                    if self.move_to(reference, speed, a, a, dt) {
                        if failing {
                            self.hm = HomingRun::Error;
                        } else {
                            self.offset = f64::from(p.home_offset) - reference;
                            self.pp_base = f64::from(p.home_offset);
                            self.hm = HomingRun::Done;
                        }
                    }
                }
            }
            _ => {
                let d = p.homing_acceleration;
                self.vel = approach(self.vel, 0.0, d, d, dt);
                self.pos += self.vel * dt;
            }
        }
        let mut bits = StatusWord::empty();
        match self.hm {
            HomingRun::Idle | HomingRun::Interrupted => {
                bits |= StatusWord::TARGET_REACHED;
            }
            HomingRun::Running { .. } => {}
            HomingRun::Done => {
                bits |= StatusWord::HOMING_ATTAINED;
                bits.set(StatusWord::TARGET_REACHED, self.stopped());
            }
            HomingRun::Error => {
                bits |= StatusWord::HOMING_ERROR;
                bits.set(StatusWord::TARGET_REACHED, self.stopped());
            }
        }
        bits
    }
}
