//! Set-point programs: what an axis does once it is enabled, as a sequence of steps.
//!
//! A program is planned step by step: when a step starts it is planned from the current
//! set-point (so consecutive steps join without a jump) and then sampled once per cycle by the
//! cycle thread, allocation-free. Positions are in drive position units (counts), velocities in
//! counts per second, torques in the drive's torque unit; the cycle converts velocities to the
//! drive's velocity object unit with the drive profile.

use super::setpoint::{Jog, Move, Sample, ShapeError, Sine, TorqueStep, VelocityRamp};
use crate::cia402::OperationMode;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize};

// A program is also what a run file writes (`{ step = "move", by = 90, … }`): the application
// reads its TOML into these types directly, in the file's user units, then takes them to
// counts with [`Step::scaled`]. Where a word of the file is not one the type takes (a mode, an
// edge, a move with both `to` and `by`), the message says what the file may write.

impl From<RunMode> for OperationMode {
    fn from(m: RunMode) -> Self {
        m.operation_mode()
    }
}

impl TryFrom<OperationMode> for RunMode {
    /// The mode, which no program runs in.
    type Error = OperationMode;

    fn try_from(mode: OperationMode) -> Result<Self, OperationMode> {
        Self::of(mode).ok_or(mode)
    }
}

/// The modes of operation a program (and the application) can run an axis in: the cyclic
/// synchronous ones, where the master streams the set-point every cycle, and the profile ones,
/// where the drive generates the motion from a target and its profile objects. Homing (hm) is
/// not one: a `home` step enters it and comes back.
///
/// (Each discriminant is the mode's 0x6060 value, as [`OperationMode`]'s are, so the
/// conversions between the two are a test and a copy: no table for the cycle to fetch.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
#[repr(u8)]
pub enum RunMode {
    /// Cyclic synchronous position (0x6060 = 8): the program streams target positions.
    Csp = 8,
    /// Cyclic synchronous velocity (0x6060 = 9): the program streams target velocities.
    Csv = 9,
    /// Cyclic synchronous torque (0x6060 = 10): the program streams target torques.
    Cst = 10,
    /// Profile position (0x6060 = 1): `pp` steps hand targets to the drive with the
    /// new-set-point handshake.
    Pp = 1,
    /// Profile velocity (0x6060 = 3): `pv` steps give the drive a target velocity.
    Pv = 3,
    /// Profile torque (0x6060 = 4): `tq` steps give the drive a target torque.
    Tq = 4,
    /// Interpolated position (0x6060 = 7): the program streams target positions as in csp,
    /// carried in 0x60C1:01 (the cyclic position mode of drives without csp, such as the
    /// CANopen ASDA-A2), with controlword bit 4 where the drive needs it.
    Ip = 7,
}

impl RunMode {
    /// Every mode, in 0x6060 order of the cyclic ones first.
    pub const ALL: [RunMode; 7] = [
        Self::Csp,
        Self::Csv,
        Self::Cst,
        Self::Ip,
        Self::Pp,
        Self::Pv,
        Self::Tq,
    ];

    /// The CiA 402 mode of operation this is: a run mode is a checked subset of
    /// [`OperationMode`] (the modes a program runs an axis in).
    pub const fn operation_mode(self) -> OperationMode {
        match self {
            Self::Csp => OperationMode::CyclicSyncPosition,
            Self::Csv => OperationMode::CyclicSyncVelocity,
            Self::Cst => OperationMode::CyclicSyncTorque,
            Self::Pp => OperationMode::ProfilePosition,
            Self::Pv => OperationMode::ProfileVelocity,
            Self::Tq => OperationMode::ProfileTorque,
            Self::Ip => OperationMode::InterpolatedPosition,
        }
    }

    /// The run mode a CiA 402 mode is, if a program can run in it (not homing, vl, cstca,
    /// reserved or vendor modes).
    pub const fn of(mode: OperationMode) -> Option<Self> {
        match mode {
            OperationMode::CyclicSyncPosition => Some(Self::Csp),
            OperationMode::CyclicSyncVelocity => Some(Self::Csv),
            OperationMode::CyclicSyncTorque => Some(Self::Cst),
            OperationMode::ProfilePosition => Some(Self::Pp),
            OperationMode::ProfileVelocity => Some(Self::Pv),
            OperationMode::ProfileTorque => Some(Self::Tq),
            OperationMode::InterpolatedPosition => Some(Self::Ip),
            _ => None,
        }
    }

    /// The 0x6060 value.
    pub const fn code(self) -> i8 {
        self.operation_mode().as_i8()
    }

    /// The mode for a raw 0x6060/0x6061 value (as telemetry carries it), if a program can run
    /// in it.
    pub const fn from_code(code: i8) -> Option<Self> {
        Self::of(OperationMode::from_i8(code))
    }

    /// `"csp"`, `"csv"`, `"cst"`, `"pp"`, `"pv"`, `"tq"` or `"ip"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Csp => "csp",
            Self::Csv => "csv",
            Self::Cst => "cst",
            Self::Pp => "pp",
            Self::Pv => "pv",
            Self::Tq => "tq",
            Self::Ip => "ip",
        }
    }

    /// Whether the master streams the set-point every cycle (csp, csv, cst, ip).
    pub const fn is_cyclic(self) -> bool {
        matches!(self, Self::Csp | Self::Csv | Self::Cst | Self::Ip)
    }

    /// Whether the master streams positions (csp, ip).
    pub const fn streams_position(self) -> bool {
        matches!(self, Self::Csp | Self::Ip)
    }
}

/// A mode by its name, in any case (`"csp"`, `"CSV"`); the error lists the names.
impl core::str::FromStr for RunMode {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let lower = s.to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|m| m.name() == lower)
            .ok_or_else(|| {
                format!(
                    "unknown mode {lower:?}; the modes are csp, csv, cst, pp, pv, tq and ip (hm \
                     through a home step)"
                )
            })
    }
}

/// Read as [`FromStr`](core::str::FromStr) reads it: its message lists the modes (serde's
/// would call them variants).
impl<'de> Deserialize<'de> for RunMode {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        String::deserialize(d)?.parse().map_err(D::Error::custom)
    }
}

/// Where a move goes (a run file writes `to = …` or `by = …`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Target {
    /// An absolute position.
    To(f64),
    /// A distance from the position where the step starts.
    By(f64),
}

/// One step of a program.
///
/// When the axis runs it, positions are in counts, velocities, accelerations and jerks in
/// counts per second (², ³) and torques in the drive's torque unit. A run file writes positions
/// and their rates in its user units; [`Step::scaled`] takes them to counts.
///
/// The profile values of the steps the drive runs (pp's velocity and accelerations, pv's
/// accelerations, tq's slope, homing's speeds, acceleration and offset) are the drive's
/// settings, not the axis's: they are written once, in PRE-OP, in the drive's units, and the
/// axis only hands the drive its targets. The application's run file turns a program's values
/// into those start-up writes; a program built in code writes them as start-up values of its
/// own (the drive's setup), and its steps say the same for the reader.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "step", rename_all = "snake_case", deny_unknown_fields)]
pub enum Step {
    /// Switch the mode of operation while enabled (no jump: the new mode starts from the
    /// actual values).
    Mode {
        /// The new mode.
        mode: RunMode,
    },
    /// A point-to-point move (csp: positions; csv: the profile's velocities).
    #[serde(deserialize_with = "move_step")]
    Move {
        /// Destination.
        #[serde(flatten)]
        target: Target,
        /// Velocity limit (counts/s).
        velocity: f64,
        /// Acceleration limit (counts/s²).
        acceleration: f64,
        /// Jerk limit (counts/s³); without it the profile is trapezoidal.
        jerk: Option<f64>,
    },
    /// A sine around the position where the step starts (csp: positions; csv: velocities).
    Sine {
        /// Amplitude (counts).
        amplitude: f64,
        /// Frequency (Hz).
        frequency: f64,
        /// Number of periods.
        periods: f64,
    },
    /// A velocity ramp from the current velocity set-point to `velocity`, then held.
    Ramp {
        /// Final velocity (counts/s).
        velocity: f64,
        /// Acceleration (counts/s²).
        acceleration: f64,
        /// Time to hold the final velocity (s).
        #[serde(default)]
        hold: f64,
    },
    /// Jog at a velocity for a time, then stop, with an acceleration limit.
    Jog {
        /// Jog velocity (counts/s).
        velocity: f64,
        /// Acceleration (counts/s²).
        acceleration: f64,
        /// Time at the jog velocity before stopping (s).
        seconds: f64,
    },
    /// A torque profile (cst): ramp to `torque`, hold, ramp back to zero.
    Torque {
        /// Torque level (drive torque units).
        torque: f64,
        /// Slope (torque units per second); absent = a true step.
        #[serde(default)]
        slope: Option<f64>,
        /// Hold time (s).
        hold: f64,
    },
    /// Hold the current set-point for a time.
    Dwell {
        /// Seconds.
        seconds: f64,
    },
    /// Home the axis: the drive runs homing mode (hm, 0x6060 = 6) with `method` (0x6098) at
    /// the speeds and acceleration start-up wrote (0x6099:01/02, 0x609A); the axis then
    /// returns to the mode the program is in, from the position homing defines. A homing error
    /// stops the run, naming the drive's own report.
    Home {
        /// The homing method (0x6098).
        method: i8,
        /// The speed searching for the switch (counts/s), 0x6099:01.
        speed_switch: f64,
        /// The speed searching for zero (counts/s), 0x6099:02.
        speed_zero: f64,
        /// The homing acceleration (counts/s²), 0x609A; without it the drive uses its own (a
        /// drive without 0x609A, such as the Lexium MDrive, takes none).
        #[serde(default)]
        acceleration: Option<f64>,
        /// The position the home then reads (counts), 0x607C; without it the drive's own.
        #[serde(default)]
        offset: Option<f64>,
    },
    /// Profile position (pp): the drive moves to each target in turn with the profile
    /// velocity and accelerations start-up wrote (0x6081, 0x6083, 0x6084), each target handed
    /// over with the new-set-point handshake (controlword bit 4, statusword bit 12). Done when
    /// the drive reports the last target reached (statusword bit 10).
    #[serde(deserialize_with = "pp_step")]
    Pp {
        /// Targets (counts): absolute, or with `relative` each from the previous target.
        targets: Vec<f64>,
        /// Controlword bit 6: the targets are relative.
        relative: bool,
        /// `false` (set of set-points, bit 5 = 0): every target is queued at once and the drive
        /// runs them one after the other. `true` (single set-point, bit 5 = 1): each target is
        /// handed over once the drive reports the previous one reached.
        immediate: bool,
        /// The profile velocity (counts/s), 0x6081.
        velocity: f64,
        /// The profile acceleration (counts/s²), 0x6083.
        acceleration: f64,
        /// The profile deceleration (counts/s²), 0x6084; without it `acceleration`.
        deceleration: Option<f64>,
    },
    /// Profile velocity (pv): the drive ramps to `velocity` with 0x6083/0x6084, holds it for
    /// `seconds`, then ramps to standstill. Done when the drive reports velocity 0 reached.
    Pv {
        /// Velocity (counts/s), converted to the drive's velocity unit for 0x60FF.
        velocity: f64,
        /// The profile acceleration (counts/s²), 0x6083.
        acceleration: f64,
        /// The profile deceleration (counts/s²), 0x6084; without it `acceleration`.
        #[serde(default)]
        deceleration: Option<f64>,
        /// Time at the velocity (s), from the switch of the target.
        seconds: f64,
    },
    /// Profile torque (tq): the drive ramps to `torque` with the slope 0x6087, holds it for
    /// `seconds`, then ramps it back to 0 (the time the slope needs, [`tq_ramp`], is
    /// waited out: not every drive reports torque reached).
    Tq {
        /// Torque (the drive's torque unit), for 0x6071.
        torque: f64,
        /// The torque slope (torque units per second), 0x6087; without it a step (0x6087 = 0).
        #[serde(default)]
        slope: Option<f64>,
        /// Time at the torque (s), from the switch of the target.
        seconds: f64,
    },
    /// Arm a touch probe (0x60B8): the drive latches the position at the next edge of its
    /// probe input; the program goes on at once, and the latch is reported when the drive
    /// sets it (0x60B9, 0x60BA–0x60BD).
    TouchProbe {
        /// Probe 1 or 2.
        probe: u8,
        /// The edge to latch on.
        edge: ProbeEdge,
    },
    /// Wait until touch probe `probe` (armed by an earlier `TouchProbe` step) has latched,
    /// keeping the motion the axis has: standing still after a move, the velocity after a ramp
    /// (a search for the mark). Done at the latch; without one within `seconds` the program
    /// stops the axes, naming the drive and the probe.
    ProbeWait {
        /// Probe 1 or 2.
        probe: u8,
        /// The longest wait (s).
        seconds: f64,
    },
}

/// A move as a run file writes it: the destination by its key, `to` or `by`.
fn move_step<'de, D: Deserializer<'de>>(d: D) -> Result<(Target, f64, f64, Option<f64>), D::Error> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct MoveKeys {
        #[serde(default)]
        to: Option<f64>,
        #[serde(default)]
        by: Option<f64>,
        velocity: f64,
        acceleration: f64,
        #[serde(default)]
        jerk: Option<f64>,
    }
    let k = MoveKeys::deserialize(d)?;
    let target = match (k.to, k.by) {
        (Some(t), None) => Target::To(t),
        (None, Some(b)) => Target::By(b),
        _ => {
            return Err(D::Error::custom(
                "a move needs exactly one of `to` and `by`",
            ));
        }
    };
    Ok((target, k.velocity, k.acceleration, k.jerk))
}

/// A pp step as a run file writes it: absolute targets as `to = [...]`, relative ones as
/// `by = [...]`.
#[allow(clippy::type_complexity)]
fn pp_step<'de, D: Deserializer<'de>>(
    d: D,
) -> Result<(Vec<f64>, bool, bool, f64, f64, Option<f64>), D::Error> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct PpKeys {
        #[serde(default)]
        to: Option<Vec<f64>>,
        #[serde(default)]
        by: Option<Vec<f64>>,
        velocity: f64,
        acceleration: f64,
        #[serde(default)]
        deceleration: Option<f64>,
        #[serde(default)]
        immediate: bool,
    }
    let k = PpKeys::deserialize(d)?;
    let (targets, relative) = match (k.to, k.by) {
        (Some(t), None) => (t, false),
        (None, Some(b)) => (b, true),
        _ => {
            return Err(D::Error::custom(
                "a pp step needs exactly one of `to` and `by` (lists)",
            ));
        }
    };
    Ok((
        targets,
        relative,
        k.immediate,
        k.velocity,
        k.acceleration,
        k.deceleration,
    ))
}

/// A touch-probe edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProbeEdge {
    /// Input going on.
    Rising,
    /// Input going off.
    Falling,
}

/// `"rising"` or `"falling"`; anything else is named in the message.
impl<'de> Deserialize<'de> for ProbeEdge {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match String::deserialize(d)?.as_str() {
            "rising" => Ok(Self::Rising),
            "falling" => Ok(Self::Falling),
            other => Err(D::Error::custom(format!(
                "touch_probe: edge must be \"rising\" or \"falling\", not {other:?}"
            ))),
        }
    }
}

impl ProbeEdge {
    /// `"rising"` or `"falling"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Rising => "rising",
            Self::Falling => "falling",
        }
    }
}

impl Step {
    /// A short description for logs and summaries.
    pub fn describe(&self) -> String {
        match self {
            Self::Mode { mode } => format!("switch to {}", mode.name()),
            Self::Move { target, .. } => match target {
                Target::To(p) => format!("move to {p}"),
                Target::By(d) => format!("move by {d}"),
            },
            Self::Sine {
                amplitude,
                frequency,
                ..
            } => format!("sine ±{amplitude} at {frequency} Hz"),
            Self::Ramp { velocity, .. } => format!("ramp to {velocity}/s"),
            Self::Jog { velocity, .. } => format!("jog at {velocity}/s"),
            Self::Torque { torque, .. } => format!("torque {torque}"),
            Self::Dwell { seconds } => format!("dwell {seconds} s"),
            Self::Home { method, .. } => format!("home (method {method})"),
            Self::Pp {
                targets, relative, ..
            } => format!(
                "pp {} {} target{}",
                if *relative { "relative" } else { "absolute" },
                targets.len(),
                if targets.len() == 1 { "" } else { "s" }
            ),
            Self::Pv { velocity, .. } => format!("pv at {velocity}/s"),
            Self::Tq { torque, .. } => format!("tq {torque}"),
            Self::TouchProbe { probe, edge } => {
                format!("arm touch probe {probe} ({} edge)", edge.name())
            }
            Self::ProbeWait { probe, seconds } => {
                format!("wait for touch probe {probe} (at most {seconds} s)")
            }
        }
    }

    /// The modes this step can run in.
    pub fn runs_in(&self, mode: RunMode) -> bool {
        match self {
            Self::Mode { .. }
            | Self::Dwell { .. }
            | Self::Home { .. }
            | Self::TouchProbe { .. }
            | Self::ProbeWait { .. } => true,
            Self::Move { .. } | Self::Sine { .. } | Self::Ramp { .. } | Self::Jog { .. } => {
                matches!(mode, RunMode::Csp | RunMode::Csv | RunMode::Ip)
            }
            Self::Torque { .. } => mode == RunMode::Cst,
            Self::Pp { .. } => mode == RunMode::Pp,
            Self::Pv { .. } => mode == RunMode::Pv,
            Self::Tq { .. } => mode == RunMode::Tq,
        }
    }

    /// Why this step needs another mode (for [`ProgramError::WrongMode`]).
    fn mode_rule(&self) -> &'static str {
        match self {
            Self::Torque { .. } => "torque steps need cst (in tq: a `tq` step)",
            Self::Pp { .. } => "pp steps need pp (a `mode` step switches)",
            Self::Pv { .. } => "pv steps need pv (a `mode` step switches)",
            Self::Tq { .. } => "tq steps need tq (a `mode` step switches)",
            _ => {
                "position and velocity steps need csp or csv (on CANopen: ip, where the drive has it)"
            }
        }
    }

    /// Whether the drive runs this step on its own (hm, pp, pv, tq): the cycle runs it and
    /// calls [`Runner::drive_done`].
    pub fn run_by_drive(&self) -> bool {
        matches!(
            self,
            Self::Home { .. } | Self::Pp { .. } | Self::Pv { .. } | Self::Tq { .. }
        )
    }

    /// This step with its positions and their rates (velocities, accelerations, jerks)
    /// multiplied by `counts_per_unit`: a step written in user units, in counts. Times,
    /// frequencies, torques, slopes, the homing method and the probe stay as they are.
    pub fn scaled(&self, counts_per_unit: f64) -> Step {
        let k = counts_per_unit;
        let mut s = self.clone();
        let scale = |v: &mut f64| *v *= k;
        match &mut s {
            Self::Move {
                target: Target::To(x) | Target::By(x),
                velocity,
                acceleration,
                jerk,
            } => {
                [x, velocity, acceleration].into_iter().for_each(scale);
                jerk.iter_mut().for_each(scale);
            }
            Self::Sine { amplitude, .. } => scale(amplitude),
            Self::Ramp {
                velocity,
                acceleration,
                ..
            }
            | Self::Jog {
                velocity,
                acceleration,
                ..
            } => [velocity, acceleration].into_iter().for_each(scale),
            Self::Home {
                speed_switch,
                speed_zero,
                acceleration,
                offset,
                ..
            } => {
                [speed_switch, speed_zero].into_iter().for_each(scale);
                acceleration.iter_mut().chain(offset).for_each(scale);
            }
            Self::Pp {
                targets,
                velocity,
                acceleration,
                deceleration,
                ..
            } => {
                targets.iter_mut().for_each(scale);
                [velocity, acceleration].into_iter().for_each(scale);
                deceleration.iter_mut().for_each(scale);
            }
            Self::Pv {
                velocity,
                acceleration,
                deceleration,
                ..
            } => {
                [velocity, acceleration].into_iter().for_each(scale);
                deceleration.iter_mut().for_each(scale);
            }
            Self::Mode { .. }
            | Self::Torque { .. }
            | Self::Dwell { .. }
            | Self::Tq { .. }
            | Self::TouchProbe { .. }
            | Self::ProbeWait { .. } => {}
        }
        s
    }
}

/// The seconds a tq step of `torque` takes to ramp from 0 to it with `slope` (torque units per
/// second; none: a step, 0 s).
pub fn tq_ramp(torque: f64, slope: Option<f64>) -> f64 {
    slope.map_or(0.0, |sl| torque.abs() / sl)
}

/// A program that cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProgramError {
    /// A step does not fit the mode it would run in.
    #[error("step {index} ({what}) cannot run in {mode}: {why}")]
    WrongMode {
        /// Step number (0-based).
        index: usize,
        /// The step.
        what: String,
        /// The mode at that point of the program.
        mode: &'static str,
        /// Why.
        why: &'static str,
    },
    /// A step's parameters are invalid.
    #[error("step {index} ({what}): {source}")]
    Shape {
        /// Step number (0-based).
        index: usize,
        /// The step.
        what: String,
        /// The parameter problem.
        source: ShapeError,
    },
    /// A `ProbeWait` step waits for a probe no earlier step arms.
    #[error(
        "step {index} (wait for touch probe {probe}): no earlier touch_probe step arms probe {probe}"
    )]
    ProbeNotArmed {
        /// Step number (0-based).
        index: usize,
        /// The probe.
        probe: u8,
    },
}

/// Check that every step runs in the mode the program is in at that point. `start` is the mode
/// the axis starts in.
pub fn validate(steps: &[Step], start: RunMode) -> Result<(), ProgramError> {
    let mut mode = start;
    let mut armed = [false; 2];
    for (index, s) in steps.iter().enumerate() {
        if let Step::Mode { mode: m } = s {
            mode = *m;
            continue;
        }
        match *s {
            Step::TouchProbe { probe, .. } => {
                if let Some(a) = armed.get_mut(usize::from(probe).wrapping_sub(1)) {
                    *a = true;
                }
            }
            Step::ProbeWait { probe, .. }
                if !armed
                    .get(usize::from(probe).wrapping_sub(1))
                    .copied()
                    .unwrap_or(true) =>
            {
                return Err(ProgramError::ProbeNotArmed { index, probe });
            }
            _ => {}
        }
        if !s.runs_in(mode) {
            return Err(ProgramError::WrongMode {
                index,
                what: s.describe(),
                mode: mode.name(),
                why: s.mode_rule(),
            });
        }
        // Plan it once from a neutral state to check the parameters.
        plan_step(s, &Sample::default()).map_err(|source| ProgramError::Shape {
            index,
            what: s.describe(),
            source,
        })?;
    }
    Ok(())
}

/// The modes of operation (0x6060 values) a program runs the axis in, starting in `start`:
/// the start mode, each `mode` step's, and hm (6) for a `home` step; each once, in order.
pub fn modes_used(steps: &[Step], start: RunMode) -> Vec<i8> {
    let mut out = vec![start.code()];
    for s in steps {
        let code = match s {
            Step::Mode { mode } => mode.code(),
            Step::Home { .. } => 6,
            _ => continue,
        };
        if !out.contains(&code) {
            out.push(code);
        }
    }
    out
}

/// The fastest speed a program commands (counts/s) and its step index, started in `start`: a
/// move's or jog's velocity, a ramp's or pv step's, a sine's peak (A·2πf in csp, A in csv).
/// pp steps run at the profile velocity the drive limits itself (0x607F); homing at 0x6099.
pub fn fastest_step(steps: &[Step], start: RunMode) -> Option<(usize, f64)> {
    let mut mode = start;
    let mut fastest: Option<(usize, f64)> = None;
    for (n, s) in steps.iter().enumerate() {
        let v = match s {
            Step::Mode { mode: m } => {
                mode = *m;
                continue;
            }
            Step::Move { velocity, .. }
            | Step::Ramp { velocity, .. }
            | Step::Jog { velocity, .. }
            | Step::Pv { velocity, .. } => velocity.abs(),
            Step::Sine {
                amplitude,
                frequency,
                ..
            } => match mode {
                RunMode::Csv => amplitude.abs(),
                _ => (amplitude * 2.0 * std::f64::consts::PI * frequency).abs(),
            },
            _ => continue,
        };
        if fastest.is_none_or(|(_, f)| v > f) {
            fastest = Some((n, v));
        }
    }
    fastest
}

/// The first value a pp step would write to 0x607A that the drive does not take
/// ([`DriveCaps::pp_target_outside`](crate::cia402::DriveCaps::pp_target_outside); an absolute
/// target, or a relative step's distance): (step index, value in counts, the drive's range).
pub fn pp_target_beyond(
    steps: &[Step],
    caps: &crate::cia402::DriveCaps,
) -> Option<(usize, f64, crate::cia402::ValueRange)> {
    steps.iter().enumerate().find_map(|(n, s)| match s {
        Step::Pp { targets, .. } => targets
            .iter()
            .find_map(|&t| caps.pp_target_outside(t).map(|range| (n, t, range))),
        _ => None,
    })
}

/// The touch probes a program arms: (probe, edge), each once, in order.
pub fn probes_used(steps: &[Step]) -> Vec<(u8, ProbeEdge)> {
    let mut out = Vec::new();
    for s in steps {
        if let Step::TouchProbe { probe, edge } = *s
            && !out.contains(&(probe, edge))
        {
            out.push((probe, edge));
        }
    }
    out
}

/// A planned step, sampled per cycle.
// Boxing the large variant would allocate when a step starts, which happens in the cycle.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
enum Planned {
    Move(Move),
    Sine(Sine),
    Ramp(VelocityRamp),
    Jog {
        jog: Jog,
        until: f64,
    },
    Torque(TorqueStep),
    Dwell {
        hold: Sample,
        seconds: f64,
    },
    /// Waiting for a probe's latch: `from` carried on at its velocity, at most `seconds`.
    ProbeWait {
        from: Sample,
        probe: u8,
        seconds: f64,
    },
    /// A mode switch, or a probe armed: nothing to sample.
    Mode,
    /// A step the drive runs (hm, pp, pv, tq).
    Drive,
}

/// A probe number: 1 or 2.
fn check_probe(probe: u8) -> Result<(), ShapeError> {
    if matches!(probe, 1 | 2) {
        Ok(())
    } else {
        Err(ShapeError::NotFinite {
            name: "probe (1 or 2)",
            value: f64::from(probe),
        })
    }
}

fn plan_step(step: &Step, from: &Sample) -> Result<Planned, ShapeError> {
    match plan_waiting(step, from)? {
        Some(p) => Ok(p),
        None => plan_setpoints(step, from),
    }
}

/// The plan of a step that hands the motion to the drive or waits (mode, home, pp, pv, tq,
/// probes); `None` for a step whose set-points the master generates.
fn plan_waiting(step: &Step, from: &Sample) -> Result<Option<Planned>, ShapeError> {
    Ok(Some(match *step {
        Step::Mode { .. } => Planned::Mode,
        Step::Home { .. } => Planned::Drive,
        Step::Pp { ref targets, .. } => {
            if targets.is_empty() {
                return Err(ShapeError::NotFinite {
                    name: "targets (none given)",
                    value: f64::NAN,
                });
            }
            for &t in targets {
                if !(t.is_finite() && t.abs() <= f64::from(i32::MAX)) {
                    return Err(ShapeError::NotFinite {
                        name: "a pp target (within ±2^31 counts)",
                        value: t,
                    });
                }
            }
            Planned::Drive
        }
        Step::Pv {
            velocity, seconds, ..
        } => {
            finite("velocity", velocity)?;
            non_negative("seconds", seconds)?;
            Planned::Drive
        }
        Step::Tq {
            torque,
            slope,
            seconds,
        } => {
            finite("torque", torque)?;
            non_negative("seconds", seconds)?;
            non_negative("ramp", tq_ramp(torque, slope))?;
            Planned::Drive
        }
        Step::TouchProbe { probe, .. } => {
            check_probe(probe)?;
            Planned::Mode
        }
        Step::ProbeWait { probe, seconds } => {
            check_probe(probe)?;
            non_negative("seconds", seconds)?;
            Planned::ProbeWait {
                from: Sample {
                    acc: 0.0,
                    done: false,
                    ..*from
                },
                probe,
                seconds,
            }
        }
        _ => return Ok(None),
    }))
}

/// The plan of a step whose set-points the master generates (move, sine, ramp, jog, torque,
/// dwell).
fn plan_setpoints(step: &Step, from: &Sample) -> Result<Planned, ShapeError> {
    Ok(match *step {
        Step::Mode { .. }
        | Step::Home { .. }
        | Step::Pp { .. }
        | Step::Pv { .. }
        | Step::Tq { .. }
        | Step::TouchProbe { .. }
        | Step::ProbeWait { .. } => unreachable_plan()?,
        Step::Move {
            target,
            velocity,
            acceleration,
            jerk,
        } => {
            let end = match target {
                Target::To(p) => p,
                Target::By(d) => from.pos + d,
            };
            Planned::Move(match jerk {
                Some(j) => Move::double_s(from.pos, end, velocity, acceleration, j)?,
                None => Move::trapezoid(from.pos, end, velocity, acceleration)?,
            })
        }
        Step::Sine {
            amplitude,
            frequency,
            periods,
        } => Planned::Sine(Sine::new(from.pos, amplitude, frequency, periods)?),
        Step::Ramp {
            velocity,
            acceleration,
            hold,
        } => Planned::Ramp(VelocityRamp::new(
            from.pos,
            from.vel,
            velocity,
            acceleration,
            hold,
        )?),
        Step::Jog {
            velocity,
            acceleration,
            seconds,
        } => {
            let mut jog = Jog::new(from.pos, acceleration)?;
            jog.set_target(velocity);
            non_negative("seconds", seconds)?;
            Planned::Jog {
                jog,
                until: seconds + velocity.abs() / acceleration,
            }
        }
        Step::Torque {
            torque,
            slope,
            hold,
        } => Planned::Torque(TorqueStep::new(
            from.torque,
            torque,
            slope.unwrap_or(f64::INFINITY),
            hold,
        )?),
        Step::Dwell { seconds } => {
            non_negative("seconds", seconds)?;
            Planned::Dwell {
                hold: Sample {
                    vel: 0.0,
                    acc: 0.0,
                    done: false,
                    ..*from
                },
                seconds,
            }
        }
    })
}

/// A step [`plan_waiting`] plans never reaches [`plan_setpoints`].
fn unreachable_plan() -> Result<Planned, ShapeError> {
    Err(ShapeError::NotFinite {
        name: "a step planned twice",
        value: f64::NAN,
    })
}

fn finite(name: &'static str, value: f64) -> Result<f64, ShapeError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ShapeError::NotFinite { name, value })
    }
}

fn non_negative(name: &'static str, value: f64) -> Result<f64, ShapeError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ShapeError::Negative { name, value })
    }
}

/// What the runner wants this cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tick {
    /// Stream this set-point.
    Setpoint(Sample),
    /// Switch to this mode, then call [`Runner::mode_switched`] once the drive confirms it.
    SwitchMode(RunMode),
    /// The program is finished; hold the last set-point.
    Finished(Sample),
    /// Home the axis with this method (hold the set-point meanwhile), then call
    /// [`Runner::drive_done`].
    Home {
        /// The homing method (0x6098).
        method: i8,
    },
    /// The drive runs step `index` (pp, pv or tq; the step is [`Runner::steps`]`[index]`):
    /// run it, then call [`Runner::drive_done`].
    Drive {
        /// The step's index.
        index: usize,
    },
    /// Arm this touch probe (the program goes on with the next tick); hold the set-point.
    Probe {
        /// Probe 1 or 2.
        probe: u8,
        /// The edge.
        edge: ProbeEdge,
        /// The held set-point.
        hold: Sample,
    },
    /// A `ProbeWait` step: stream `setpoint`; once probe `probe` has latched, call
    /// [`Runner::probe_latched`]. `expired`: the step's time is up without the latch.
    ProbeWait {
        /// Probe 1 or 2.
        probe: u8,
        /// The set-point (the motion the axis had, carried on).
        setpoint: Sample,
        /// The wait's time is up.
        expired: bool,
    },
}

/// Runs a program on one axis. Built before the cycle starts; [`Runner::tick`] does not
/// allocate.
///
/// A program is validated against the mode it starts in ([`validate`]), and its `Mode` steps
/// change that mode as it goes, so a run can end (or be cut short by a fault) in another mode.
/// Every run therefore begins by asking for the start mode ([`Tick::SwitchMode`]); when the
/// axis is already in it the caller confirms at once with [`Runner::mode_switched`].
#[derive(Debug, Clone)]
pub struct Runner {
    steps: Vec<Step>,
    /// The mode the program was validated for.
    start: RunMode,
    /// The run has not yet confirmed the start mode.
    entering: bool,
    index: usize,
    planned: Option<Planned>,
    started_at: f64,
    /// Time within the running step at the previous tick (for the stateful jog).
    step_t: f64,
    last: Sample,
    waiting_for_mode: bool,
    failed: Option<(usize, ShapeError)>,
    /// While a single step runs in the program's place ([`Runner::run_single`]): the program
    /// and its start mode; otherwise the single step's slot (capacity reserved at
    /// construction, so that a step is put in it without allocating).
    stash: (Vec<Step>, RunMode),
    single: bool,
}

impl Runner {
    /// A runner for steps validated (with [`validate`]) for the mode `start`.
    pub fn new(steps: Vec<Step>, start: RunMode) -> Self {
        Self {
            steps,
            start,
            entering: true,
            index: 0,
            planned: None,
            started_at: 0.0,
            step_t: 0.0,
            last: Sample::default(),
            waiting_for_mode: false,
            failed: None,
            stash: (Vec::with_capacity(1), start),
            single: false,
        }
    }

    /// Run `step` alone, starting in `start`, in place of the program (until
    /// [`Runner::use_program`]); then [`Runner::seed`] before the next tick. Allocation-free
    /// for a step that holds no list (a move, a ramp, a jog: not a pp step's targets).
    pub fn run_single(&mut self, step: Step, start: RunMode) {
        if !self.single {
            std::mem::swap(&mut self.steps, &mut self.stash.0);
            std::mem::swap(&mut self.start, &mut self.stash.1);
            self.single = true;
        }
        self.steps.clear();
        self.steps.push(step);
        self.start = start;
        self.restart();
    }

    /// Back to the program after [`Runner::run_single`] (nothing to do if no single step
    /// ran); then [`Runner::restart`] to run it.
    pub fn use_program(&mut self) {
        if self.single {
            self.steps.clear();
            std::mem::swap(&mut self.steps, &mut self.stash.0);
            std::mem::swap(&mut self.start, &mut self.stash.1);
            self.single = false;
        }
    }

    /// Whether the program's last set-point is at rest (a move that reached its target, a ramp to
    /// 0), so the next step starts from a standing demand.
    pub fn at_rest(&self) -> bool {
        self.last.vel.abs() < 1e-6
    }

    /// Start over from the first step (allocation-free). Call [`Runner::seed`] before the
    /// next tick.
    pub fn restart(&mut self) {
        self.index = 0;
        self.entering = true;
        self.planned = None;
        self.step_t = 0.0;
        self.waiting_for_mode = false;
        self.failed = None;
    }

    /// The steps.
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    /// The index of the step running (equal to the number of steps when finished).
    pub fn step_index(&self) -> usize {
        self.index
    }

    /// Whether every step has run.
    pub fn finished(&self) -> bool {
        self.index >= self.steps.len()
    }

    /// A step that could not be planned at run time (its index and why); the runner holds the
    /// last set-point after it.
    pub fn failure(&self) -> Option<&(usize, ShapeError)> {
        self.failed.as_ref()
    }

    /// Restart the running step from the actual state (position, velocity, torque), e.g. after
    /// enabling. Steps are planned from this state.
    pub fn seed(&mut self, actual: Sample) {
        self.last = Sample {
            done: false,
            ..actual
        };
        self.planned = None;
    }

    /// The drive confirmed the mode switch the runner asked for (or was already in that mode);
    /// continue with the next step from `actual`.
    pub fn mode_switched(&mut self, actual: Sample) {
        if self.waiting_for_mode {
            self.waiting_for_mode = false;
            if self.entering {
                self.entering = false;
            } else {
                self.index += 1;
            }
            self.seed(actual);
        }
    }

    /// The drive finished the step it runs ([`Tick::Home`], [`Tick::Drive`]; after a home,
    /// back in the program's mode): continue with the next step from `actual` (for a home,
    /// the position homing defined).
    pub fn drive_done(&mut self, actual: Sample) {
        if self.steps.get(self.index).is_some_and(Step::run_by_drive) {
            self.index += 1;
            self.seed(actual);
        }
    }

    /// The probe a `ProbeWait` step waits for has latched: the next step starts from the
    /// set-point the wait streamed last.
    pub fn probe_latched(&mut self) {
        if matches!(self.steps.get(self.index), Some(Step::ProbeWait { .. })) {
            self.index += 1;
            self.planned = None;
        }
    }

    /// A touch-probe step: the probe armed (the program goes on) or, for a probe other than
    /// 1 and 2, the program failed (`None`).
    fn arm(&mut self, probe: u8, edge: ProbeEdge) -> Option<Tick> {
        if !matches!(probe, 1 | 2) {
            self.failed = Some((
                self.index,
                ShapeError::NotFinite {
                    name: "probe (1 or 2)",
                    value: f64::from(probe),
                },
            ));
            return None;
        }
        self.index += 1;
        self.planned = None;
        Some(Tick::Probe {
            probe,
            edge,
            hold: Sample {
                done: false,
                ..self.last
            },
        })
    }

    /// A wait for a touch probe, `t` seconds into it: the motion it started from goes on.
    fn wait_for_probe(&mut self, from: Sample, probe: u8, seconds: f64, t: f64) -> Tick {
        let setpoint = Sample {
            pos: from.pos + from.vel * t,
            ..from
        };
        self.step_t = t;
        self.last = setpoint;
        Tick::ProbeWait {
            probe,
            setpoint,
            expired: t >= seconds,
        }
    }

    /// The set-point of the planned step `t` seconds after it began.
    fn sample(&mut self, planned: Planned, t: f64) -> Sample {
        match planned {
            Planned::Move(m) => m.sample(t),
            Planned::Sine(s) => s.sample(t),
            Planned::Ramp(r) => r.sample(t),
            Planned::Jog { mut jog, until } => {
                if t >= until {
                    jog.set_target(0.0);
                }
                let s = jog.advance(t - self.step_t);
                self.planned = Some(Planned::Jog { jog, until });
                Sample {
                    done: s.done && t >= until,
                    ..s
                }
            }
            Planned::Torque(ts) => ts.sample(t),
            Planned::Dwell { hold, seconds } => Sample {
                done: t >= seconds,
                ..hold
            },
            Planned::Mode | Planned::Drive | Planned::ProbeWait { .. } => Sample {
                done: true,
                ..self.last
            },
        }
    }

    /// The set-point at time `now` (seconds, any monotonic origin).
    pub fn tick(&mut self, now: f64) -> Tick {
        if self.entering && self.failed.is_none() && self.index < self.steps.len() {
            self.waiting_for_mode = true;
            return Tick::SwitchMode(self.start);
        }
        loop {
            let Some(step) = self.steps.get(self.index).filter(|_| self.failed.is_none()) else {
                return Tick::Finished(Sample {
                    vel: 0.0,
                    acc: 0.0,
                    done: true,
                    ..self.last
                });
            };
            if let Step::Mode { mode } = step {
                self.waiting_for_mode = true;
                return Tick::SwitchMode(*mode);
            }
            match step {
                Step::Home { method, .. } => return Tick::Home { method: *method },
                &Step::TouchProbe { probe, edge } => match self.arm(probe, edge) {
                    Some(t) => return t,
                    None => continue,
                },
                s if s.run_by_drive() => {
                    // Checked once, when the step starts.
                    if self.planned.is_none() {
                        match plan_step(s, &self.last) {
                            Ok(p) => self.planned = Some(p),
                            Err(e) => {
                                self.failed = Some((self.index, e));
                                continue;
                            }
                        }
                    }
                    return Tick::Drive { index: self.index };
                }
                _ => {}
            }
            let planned = match self.planned {
                Some(p) => p,
                None => match plan_step(step, &self.last) {
                    Ok(p) => {
                        self.planned = Some(p);
                        self.started_at = now;
                        self.step_t = 0.0;
                        p
                    }
                    Err(e) => {
                        self.failed = Some((self.index, e));
                        continue;
                    }
                },
            };
            let t = (now - self.started_at).max(0.0);
            if let Planned::ProbeWait {
                from,
                probe,
                seconds,
            } = planned
            {
                return self.wait_for_probe(from, probe, seconds, t);
            }
            let s = self.sample(planned, t);
            self.step_t = t;
            self.last = Sample { done: false, ..s };
            if s.done && self.index + 1 < self.steps.len() {
                // The next step starts in this same cycle from this final sample.
                self.index += 1;
                self.planned = None;
                continue;
            }
            if s.done {
                self.index += 1;
                self.planned = None;
            }
            return Tick::Setpoint(s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(steps: Vec<Step>, dt: f64, seconds: f64) -> (Runner, Vec<Tick>) {
        let mut r = Runner::new(steps, RunMode::Csp);
        r.seed(Sample::default());
        let mut out = vec![];
        let mut t = 0.0;
        while t <= seconds {
            let tick = r.tick(t);
            if let Tick::SwitchMode(_) = tick {
                r.mode_switched(r.last);
            }
            out.push(tick);
            t += dt;
        }
        (r, out)
    }

    #[test]
    fn steps_join_without_jumps_and_finish() {
        let steps = vec![
            Step::Move {
                target: Target::By(1000.0),
                velocity: 2000.0,
                acceleration: 10_000.0,
                jerk: None,
            },
            Step::Dwell { seconds: 0.05 },
            Step::Sine {
                amplitude: 100.0,
                frequency: 5.0,
                periods: 1.0,
            },
            Step::Move {
                target: Target::To(0.0),
                velocity: 2000.0,
                acceleration: 10_000.0,
                jerk: Some(1e6),
            },
        ];
        validate(&steps, RunMode::Csp).unwrap();
        let (r, ticks) = run(steps, 0.001, 3.0);
        assert!(r.finished());
        let mut prev = 0.0;
        for t in &ticks {
            let p = match t {
                Tick::Setpoint(s) | Tick::Finished(s) => s.pos,
                Tick::SwitchMode(_)
                | Tick::Home { .. }
                | Tick::Drive { .. }
                | Tick::Probe { .. }
                | Tick::ProbeWait { .. } => continue,
            };
            // The fastest step is the sine: 100 · 2π · 5 ≈ 3142 counts/s.
            let vmax = 2000.0f64.max(100.0 * 2.0 * std::f64::consts::PI * 5.0);
            assert!(
                (p - prev).abs() <= vmax * 0.001 * 1.01 + 1e-6,
                "jump {prev} -> {p}"
            );
            prev = p;
        }
        assert_eq!(prev, 0.0);
    }

    #[test]
    fn mode_switch_waits_for_confirmation() {
        let mut r = Runner::new(
            vec![
                Step::Mode { mode: RunMode::Csv },
                Step::Ramp {
                    velocity: 100.0,
                    acceleration: 1000.0,
                    hold: 0.0,
                },
            ],
            RunMode::Csp,
        );
        r.seed(Sample::default());
        // Every run first asks for the start mode.
        assert_eq!(r.tick(0.0), Tick::SwitchMode(RunMode::Csp));
        r.mode_switched(Sample::default());
        assert_eq!(r.tick(0.0), Tick::SwitchMode(RunMode::Csv));
        // Until the drive confirms, the runner keeps asking.
        assert_eq!(r.tick(0.001), Tick::SwitchMode(RunMode::Csv));
        r.mode_switched(Sample {
            pos: 42.0,
            ..Sample::default()
        });
        match r.tick(0.002) {
            Tick::Setpoint(s) => assert_eq!(s.pos, 42.0),
            t => panic!("{t:?}"),
        }
    }

    #[test]
    fn a_restart_first_returns_to_the_start_mode() {
        let steps = vec![
            Step::Move {
                target: Target::By(100.0),
                velocity: 1000.0,
                acceleration: 10_000.0,
                jerk: None,
            },
            Step::Mode { mode: RunMode::Csv },
            Step::Ramp {
                velocity: 100.0,
                acceleration: 1000.0,
                hold: 0.5,
            },
        ];
        validate(&steps, RunMode::Csp).unwrap();
        let mut r = Runner::new(steps, RunMode::Csp);
        r.seed(Sample::default());
        assert_eq!(r.tick(0.0), Tick::SwitchMode(RunMode::Csp));
        r.mode_switched(Sample::default());
        assert!(matches!(r.tick(0.0), Tick::Setpoint(_)));
        // Run into the csv ramp, then cut the run short (a fault) and start over.
        let mut t = 0.0;
        while r.step_index() < 2 {
            t += 0.001;
            if let Tick::SwitchMode(m) = r.tick(t) {
                assert_eq!(m, RunMode::Csv);
                r.mode_switched(r.last);
            }
        }
        r.restart();
        let here = Sample {
            pos: 500.0,
            ..Sample::default()
        };
        r.seed(here);
        // The axis is in csv now: the move must not run there; the runner asks for csp first,
        // keeps asking until it is confirmed, and then plans the move from where the axis is.
        assert_eq!(r.tick(t), Tick::SwitchMode(RunMode::Csp));
        assert_eq!(r.tick(t + 0.001), Tick::SwitchMode(RunMode::Csp));
        assert_eq!(r.step_index(), 0);
        r.mode_switched(here);
        match r.tick(t + 0.002) {
            Tick::Setpoint(s) => assert!((s.pos - 500.0).abs() < 1.0, "{s:?}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(r.step_index(), 0);
    }

    #[test]
    fn validation_names_the_step_and_mode() {
        let e = validate(
            &[Step::Torque {
                torque: 100.0,
                slope: None,
                hold: 1.0,
            }],
            RunMode::Csp,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "step 0 (torque 100) cannot run in csp: torque steps need cst (in tq: a `tq` step)"
        );
        let e = validate(
            &[Step::Move {
                target: Target::By(1.0),
                velocity: -1.0,
                acceleration: 1.0,
                jerk: None,
            }],
            RunMode::Csp,
        )
        .unwrap_err();
        assert!(e.to_string().contains("velocity must be a positive"), "{e}");
    }

    #[test]
    fn jog_runs_for_its_time_then_stops() {
        let (r, ticks) = run(
            vec![Step::Jog {
                velocity: 1000.0,
                acceleration: 10_000.0,
                seconds: 0.5,
            }],
            0.001,
            1.0,
        );
        assert!(r.finished());
        let peak = ticks
            .iter()
            .filter_map(|t| match t {
                Tick::Setpoint(s) => Some(s.vel),
                _ => None,
            })
            .fold(0.0f64, f64::max);
        assert!((peak - 1000.0).abs() < 1e-6);
        match ticks.last() {
            Some(Tick::Finished(s)) => {
                assert_eq!(s.vel, 0.0);
                // 0.1 s ramp up (50), 0.5 s at speed (500), 0.1 s ramp down (50).
                assert!((s.pos - 600.0).abs() < 2.0, "{}", s.pos);
            }
            t => panic!("{t:?}"),
        }
    }

    /// A home step holds the program until the cycle says the axis homed; the next step is
    /// planned from the position homing defined, not from the one before it.
    #[test]
    fn a_home_step_waits_and_the_next_step_starts_from_the_home() {
        let steps = vec![
            Step::Home {
                method: 19,
                speed_switch: 1000.0,
                speed_zero: 100.0,
                acceleration: None,
                offset: None,
            },
            Step::Move {
                target: Target::By(100.0),
                velocity: 1000.0,
                acceleration: 10_000.0,
                jerk: None,
            },
        ];
        validate(&steps, RunMode::Csp).unwrap();
        let mut r = Runner::new(steps, RunMode::Csp);
        r.seed(Sample {
            pos: 5000.0,
            ..Sample::default()
        });
        assert_eq!(r.tick(0.0), Tick::SwitchMode(RunMode::Csp));
        r.mode_switched(r.last);
        for k in 0..5 {
            assert_eq!(r.tick(0.001 * f64::from(k)), Tick::Home { method: 19 });
        }
        assert_eq!(r.step_index(), 0);
        r.drive_done(Sample::default());
        assert_eq!(r.step_index(), 1);
        let mut last = None;
        for k in 0..1000 {
            if let Tick::Setpoint(s) | Tick::Finished(s) = r.tick(0.01 + 0.001 * f64::from(k)) {
                last = Some(s.pos);
            }
        }
        assert_eq!(last, Some(100.0), "by 100 from the home at 0");
        assert!(r.finished());
    }

    /// A probe wait carries the motion on (here 1000 counts/s after a ramp: the position
    /// advancing 1 count a millisecond), says when its time is up, and ends at the latch.
    #[test]
    fn a_probe_wait_carries_the_motion_on_until_the_latch() {
        let steps = vec![
            Step::TouchProbe {
                probe: 1,
                edge: ProbeEdge::Rising,
            },
            Step::Ramp {
                velocity: 1000.0,
                acceleration: 1e6,
                hold: 0.0,
            },
            Step::ProbeWait {
                probe: 1,
                seconds: 0.1,
            },
        ];
        validate(&steps, RunMode::Csv).unwrap();
        let mut r = Runner::new(steps, RunMode::Csv);
        r.seed(Sample::default());
        let mut waits = Vec::new();
        for k in 0..300 {
            match r.tick(f64::from(k) * 0.001) {
                Tick::SwitchMode(_) => r.mode_switched(r.last),
                Tick::ProbeWait {
                    probe,
                    setpoint,
                    expired,
                } => {
                    assert_eq!(probe, 1);
                    waits.push((setpoint, expired));
                    if waits.len() == 200 {
                        r.probe_latched();
                    }
                }
                _ => {}
            }
        }
        assert_eq!(waits.len(), 200);
        assert!(r.finished());
        for w in waits.windows(2) {
            assert_eq!(w[1].0.vel, 1000.0);
            assert!((w[1].0.pos - w[0].0.pos - 1.0).abs() < 1e-6, "{w:?}");
        }
        // The wait started at its first tick: up after 0.1 s, 101 ticks in.
        let up = waits.iter().position(|w| w.1).unwrap();
        assert!((100..=101).contains(&up), "{up}");
    }

    #[test]
    fn a_probe_wait_needs_an_earlier_arming() {
        let wait = Step::ProbeWait {
            probe: 2,
            seconds: 1.0,
        };
        let arm = |probe| Step::TouchProbe {
            probe,
            edge: ProbeEdge::Falling,
        };
        assert_eq!(
            validate(&[arm(1), wait.clone()], RunMode::Csp),
            Err(ProgramError::ProbeNotArmed { index: 1, probe: 2 })
        );
        assert!(validate(&[arm(2), wait.clone()], RunMode::Csp).is_ok());
        assert!(matches!(
            validate(
                &[Step::ProbeWait {
                    probe: 3,
                    seconds: 1.0
                }],
                RunMode::Csp
            ),
            Err(ProgramError::Shape { .. })
        ));
    }

    /// User units reach counts once, in every quantity that is a position or its rate, and in
    /// nothing else.
    #[test]
    fn scaling_takes_positions_and_their_rates_to_counts() {
        let k = 100.0;
        let moved = Step::Move {
            target: Target::By(2.0),
            velocity: 3.0,
            acceleration: 4.0,
            jerk: Some(5.0),
        };
        assert_eq!(
            moved.scaled(k),
            Step::Move {
                target: Target::By(200.0),
                velocity: 300.0,
                acceleration: 400.0,
                jerk: Some(500.0),
            }
        );
        let home = Step::Home {
            method: 19,
            speed_switch: 1.0,
            speed_zero: 0.5,
            acceleration: None,
            offset: Some(-2.0),
        };
        assert_eq!(
            home.scaled(k),
            Step::Home {
                method: 19,
                speed_switch: 100.0,
                speed_zero: 50.0,
                acceleration: None,
                offset: Some(-200.0),
            }
        );
        let pp = Step::Pp {
            targets: vec![1.0, -1.5],
            relative: true,
            immediate: false,
            velocity: 2.0,
            acceleration: 3.0,
            deceleration: Some(4.0),
        };
        assert_eq!(
            pp.scaled(k),
            Step::Pp {
                targets: vec![100.0, -150.0],
                relative: true,
                immediate: false,
                velocity: 200.0,
                acceleration: 300.0,
                deceleration: Some(400.0),
            }
        );
        // Times, frequencies and torques are not lengths.
        let sine = |amplitude| Step::Sine {
            amplitude,
            frequency: 2.0,
            periods: 3.0,
        };
        assert_eq!(sine(1.0).scaled(k), sine(100.0));
        for s in [
            Step::Tq {
                torque: 50.0,
                slope: Some(100.0),
                seconds: 1.0,
            },
            Step::Torque {
                torque: 50.0,
                slope: None,
                hold: 1.0,
            },
            Step::Dwell { seconds: 1.0 },
        ] {
            assert_eq!(s.scaled(k), s);
        }
    }

    #[test]
    fn modes_read_in_any_case_and_a_wrong_one_lists_them() {
        assert_eq!("CSV".parse::<RunMode>(), Ok(RunMode::Csv));
        assert_eq!("ip".parse::<RunMode>(), Ok(RunMode::Ip));
        let e = "hm".parse::<RunMode>().unwrap_err();
        assert!(
            e.starts_with("unknown mode \"hm\"; the modes are csp"),
            "{e}"
        );
        assert_eq!(tq_ramp(-50.0, Some(100.0)), 0.5);
        assert_eq!(tq_ramp(50.0, None), 0.0);
    }
}
