//! A drive entry's program, the same for an EtherCAT and a CANopen drive: its units, limits
//! and steps, and the start-up writes its home, pp, pv and tq steps ask for.
//!
//! The file's steps are the motion runtime's own ([`Step`], read in the drive's user units).
//! Each is checked in the file's words and units (its values, the entry's `limits`, the cycle),
//! described in them, then taken to counts once ([`Step::scaled`]); everything after works in
//! counts: the runtime's own check ([`program::validate`]), the start-up writes in the drive's
//! units, the warnings against the drive's ratings.

use super::{ConfigError, Ctx, UserUnits, raw};
use crate::drives::DriveProfile;
use crate::master::SetpointLimits;
use crate::master::program::{self, RunMode, Step, Target};
use crate::od::{ObjectAddress, Value};
use std::time::Duration;
use toml::Spanned;

/// A drive entry's program as the file gives it: its units, the following-error limit, and
/// the steps in counts (with each step described in the file's units), checked against the
/// mode they run in, their own parameters, the entry's `limits` and the cycle. The same for an
/// EtherCAT and a CANopen drive.
pub(super) struct Program {
    pub units: Option<UserUnits>,
    /// Counts per user unit (1 without units).
    pub k: f64,
    /// The following-error limit (counts).
    pub fe_limit: Option<u32>,
    /// What the program's set-points must keep (counts).
    pub limits: SetpointLimits,
    /// The steps, in counts.
    pub steps: Vec<Step>,
    /// Each step as the file writes it, in its units.
    pub described: Vec<String>,
}

pub(super) fn program_of(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    d: &Spanned<raw::Drive>,
    mode: RunMode,
    cycle: Duration,
) -> Result<Program, ConfigError> {
    let r = d.get_ref();
    let units = units_of(cx, key, r)?;
    let k = units.as_ref().map_or(1.0, |u| u.counts_per_unit);
    let uname = units
        .as_ref()
        .map_or("counts", |u| u.name.as_str())
        .to_string();
    let fe_limit = match &r.limits {
        Some(l) => following_error_limit(cx, key, l, k, &uname)?,
        None => None,
    };
    let limits = r.limits.as_ref().map(Spanned::get_ref);
    let mut steps = Vec::with_capacity(r.program.len());
    let mut described = Vec::with_capacity(r.program.len());
    for (n, s) in r.program.iter().enumerate() {
        check_step(s.get_ref(), limits, &uname, cycle)
            .map_err(|m| cx.err(s.span(), key(&format!("program[{n}]")), m))?;
        described.push(describe(s.get_ref(), &uname));
        steps.push(s.get_ref().scaled(k));
    }
    program::validate(&steps, mode).map_err(|e| {
        let n = match &e {
            program::ProgramError::WrongMode { index, .. }
            | program::ProgramError::Shape { index, .. }
            | program::ProgramError::ProbeNotArmed { index, .. } => *index,
        };
        let span = r.program.get(n).map_or(d.span(), Spanned::span);
        cx.err(span, key(&format!("program[{n}]")), e.to_string())
    })?;
    let limits = r.limits.as_ref().map_or_else(Default::default, |l| {
        let l = l.get_ref();
        SetpointLimits {
            max_velocity: l.max_velocity.map(|v| v * k),
            max_acceleration: l.max_acceleration.map(|v| v * k),
            max_torque: l.max_torque,
        }
    });
    Ok(Program {
        units,
        k,
        fe_limit,
        limits,
        steps,
        described,
    })
}

/// The entry's `units`, checked.
fn units_of(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    r: &raw::Drive,
) -> Result<Option<UserUnits>, ConfigError> {
    let Some(u) = &r.units else {
        return Ok(None);
    };
    let k = u.get_ref().counts_per_unit;
    if !(k.is_finite() && k > 0.0) {
        return Err(cx.err(
            u.span(),
            key("units.counts_per_unit"),
            format!("must be a positive number, not {k}"),
        ));
    }
    Ok(Some(UserUnits {
        name: u.get_ref().name.clone(),
        counts_per_unit: k,
    }))
}

/// The entry's `limits`, checked (each a positive number), and the following-error limit in
/// counts, if given (`k` counts per user unit `uname`).
fn following_error_limit(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    l: &Spanned<raw::Limits>,
    k: f64,
    uname: &str,
) -> Result<Option<u32>, ConfigError> {
    let lim = l.get_ref();
    for (name, v) in [
        ("following_error", lim.following_error),
        ("max_velocity", lim.max_velocity),
        ("max_acceleration", lim.max_acceleration),
        ("max_torque", lim.max_torque),
    ] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(cx.err(
                l.span(),
                key(&format!("limits.{name}")),
                format!("must be a positive number, not {v}"),
            ));
        }
    }
    let Some(fe) = lim.following_error else {
        return Ok(None);
    };
    let counts = (fe * k).round();
    if counts < 1.0 || counts > f64::from(u32::MAX) {
        return Err(cx.err(
            l.span(),
            key("limits.following_error"),
            format!(
                "{fe} {uname} is {counts} counts; it must be 1 to {} counts",
                u32::MAX
            ),
        ));
    }
    Ok(Some(counts as u32))
}

/// One step as the file writes it (user units `unit`): its own values, the entry's `limits`,
/// and a sine against the cycle.
fn check_step(
    s: &Step,
    limits: Option<&raw::Limits>,
    unit: &str,
    cycle: Duration,
) -> Result<(), String> {
    step_values(s)?;
    if let Some(l) = limits {
        check_limits(s, l, unit)?;
    }
    // A sine at or above half the cycle rate is sampled at the same phase every cycle (or
    // between two), so the axis does not follow it at all: 500 Hz at 1 ms "completed" with
    // nothing moved.
    if let Step::Sine { frequency, .. } = *s {
        let nyquist = 0.5 / cycle.as_secs_f64();
        if frequency >= nyquist {
            return Err(format!(
                "a sine of {frequency} Hz at a {} µs cycle is sampled at or beyond half the \
                 cycle rate ({nyquist} Hz): the axis would not follow it; lower the frequency \
                 well below that",
                cycle.as_micros()
            ));
        }
    }
    Ok(())
}

/// What a step's values must be beyond their types, said in the file's words: the profile
/// values start-up writes are positive, a pp step has a target, a probe is 1 or 2. (The
/// motion runtime's [`program::validate`] then checks each step's parameters in counts.)
fn step_values(s: &Step) -> Result<(), String> {
    match *s {
        Step::Home {
            speed_switch,
            speed_zero,
            acceleration,
            ..
        } => {
            positive_all(
                "home",
                &[("speed_switch", speed_switch), ("speed_zero", speed_zero)],
            )?;
            match acceleration {
                Some(a) => positive_all("home", &[("acceleration", a)]),
                None => Ok(()),
            }
        }
        Step::Pp {
            ref targets,
            velocity,
            acceleration,
            deceleration,
            ..
        } => {
            positive_all(
                "pp",
                &[
                    ("velocity", velocity),
                    ("acceleration", acceleration),
                    ("deceleration", deceleration.unwrap_or(acceleration)),
                ],
            )?;
            if targets.is_empty() {
                return Err("a pp step needs at least one target".into());
            }
            Ok(())
        }
        Step::Pv {
            acceleration,
            deceleration,
            ..
        } => positive_all(
            "pv",
            &[
                ("acceleration", acceleration),
                ("deceleration", deceleration.unwrap_or(acceleration)),
            ],
        ),
        Step::Tq {
            slope: Some(sl), ..
        } => positive_all("tq", &[("slope", sl)]),
        Step::TouchProbe { probe, .. } if !matches!(probe, 1 | 2) => {
            Err(format!("touch_probe: probe must be 1 or 2, not {probe}"))
        }
        Step::ProbeWait { probe, seconds } => {
            if !matches!(probe, 1 | 2) {
                return Err(format!("probe_wait: probe must be 1 or 2, not {probe}"));
            }
            positive_all("probe_wait", &[("seconds", seconds)])
        }
        _ => Ok(()),
    }
}

fn positive_all(step: &str, values: &[(&str, f64)]) -> Result<(), String> {
    for &(name, v) in values {
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("{step}: {name} must be a positive number, not {v}"));
        }
    }
    Ok(())
}

/// Check a step against the drive's limits (in user units).
fn check_limits(s: &Step, l: &raw::Limits, unit: &str) -> Result<(), String> {
    let over = |what: &str, v: f64, lim: Option<f64>, u: &str| match lim {
        Some(lim) if v.abs() > lim => {
            let key = if u == "/s" {
                "max_velocity"
            } else {
                "max_acceleration"
            };
            Err(format!(
                "{what} {} {unit}{u} exceeds the entry's limits.{key} of {lim} {unit}{u}",
                v.abs()
            ))
        }
        _ => Ok(()),
    };
    match *s {
        Step::Move {
            velocity,
            acceleration,
            ..
        }
        | Step::Ramp {
            velocity,
            acceleration,
            ..
        }
        | Step::Jog {
            velocity,
            acceleration,
            ..
        } => {
            over("velocity", velocity, l.max_velocity, "/s")?;
            over("acceleration", acceleration, l.max_acceleration, "/s²")
        }
        Step::Sine {
            amplitude,
            frequency,
            ..
        } => {
            let w = 2.0 * std::f64::consts::PI * frequency;
            over("peak velocity", amplitude * w, l.max_velocity, "/s")?;
            over(
                "peak acceleration",
                amplitude * w * w,
                l.max_acceleration,
                "/s²",
            )
        }
        Step::Torque { torque, .. } | Step::Tq { torque, .. } => match l.max_torque {
            Some(lim) if torque.abs() > lim => Err(format!(
                "torque {} exceeds the entry's limits.max_torque of {lim}",
                torque.abs()
            )),
            _ => Ok(()),
        },
        Step::Home {
            speed_switch,
            speed_zero,
            acceleration,
            ..
        } => {
            over("speed_switch", speed_switch, l.max_velocity, "/s")?;
            over("speed_zero", speed_zero, l.max_velocity, "/s")?;
            match acceleration {
                Some(a) => over("acceleration", a, l.max_acceleration, "/s²"),
                None => Ok(()),
            }
        }
        Step::Pp {
            velocity,
            acceleration,
            deceleration,
            ..
        }
        | Step::Pv {
            velocity,
            acceleration,
            deceleration,
            ..
        } => {
            over("velocity", velocity, l.max_velocity, "/s")?;
            over("acceleration", acceleration, l.max_acceleration, "/s²")?;
            over(
                "deceleration",
                deceleration.unwrap_or(acceleration),
                l.max_acceleration,
                "/s²",
            )
        }
        Step::Mode { .. }
        | Step::Dwell { .. }
        | Step::TouchProbe { .. }
        | Step::ProbeWait { .. } => Ok(()),
    }
}

/// A step as the file writes it, in its user units `u`.
fn describe(s: &Step, u: &str) -> String {
    match s {
        Step::Mode { mode } => format!("switch to {}", mode.name()),
        Step::Move {
            target: Target::To(t),
            ..
        } => format!("move to {t} {u}"),
        Step::Move {
            target: Target::By(b),
            ..
        } => format!("move by {b} {u}"),
        Step::Sine {
            amplitude,
            frequency,
            periods,
        } => format!("sine ±{amplitude} {u} at {frequency} Hz × {periods}"),
        Step::Ramp { velocity, .. } => format!("ramp to {velocity} {u}/s"),
        Step::Jog {
            velocity, seconds, ..
        } => format!("jog at {velocity} {u}/s for {seconds} s"),
        Step::Torque { torque, hold, .. } => format!("torque {torque} for {hold} s"),
        Step::Dwell { seconds } => format!("dwell {seconds} s"),
        Step::Home {
            method,
            speed_switch,
            speed_zero,
            ..
        } => format!("home (method {method}) at {speed_switch}/{speed_zero} {u}/s"),
        Step::Pp {
            targets, relative, ..
        } => format!(
            "pp {} {} {u}",
            if *relative { "by" } else { "to" },
            list(targets)
        ),
        Step::Pv {
            velocity, seconds, ..
        } => format!("pv at {velocity} {u}/s for {seconds} s"),
        Step::Tq {
            torque, seconds, ..
        } => format!("tq {torque} for {seconds} s"),
        Step::TouchProbe { probe, edge } => {
            format!("arm touch probe {probe} ({} edge)", edge.name())
        }
        Step::ProbeWait { probe, seconds } => {
            format!("wait for touch probe {probe} (at most {seconds} s)")
        }
    }
}

fn list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(f64::to_string).collect();
    items.join(", ")
}

/// Warnings for program steps (in counts) beyond what the drive documents independently of
/// the motor ([`DriveProfile::ratings`]).
pub(super) fn rated(i: usize, p: &DriveProfile, steps: &[Step], warnings: &mut Vec<String>) {
    let speed = |counts_per_s: f64| counts_per_s / p.units.position_per_rev;
    for (n, s) in steps.iter().enumerate() {
        let at = format!("drive[{i}].program[{n}]");
        let velocity = match *s {
            Step::Move { velocity, .. }
            | Step::Ramp { velocity, .. }
            | Step::Jog { velocity, .. }
            | Step::Pp { velocity, .. }
            | Step::Pv { velocity, .. } => Some(velocity.abs()),
            Step::Sine {
                amplitude,
                frequency,
                ..
            } => Some((amplitude * 2.0 * std::f64::consts::PI * frequency).abs()),
            _ => None,
        };
        if let (Some(v), Some(rating)) = (velocity, p.ratings.max_speed_rev_s) {
            let rev_s = speed(v);
            if rev_s > rating.value {
                warnings.push(format!(
                    "{at}: {:.1} r/min is beyond the {}'s {:.0} r/min ({})",
                    rev_s * 60.0,
                    p.name,
                    rating.value * 60.0,
                    rating.source
                ));
            }
        }
        if let (Step::Torque { torque, .. } | Step::Tq { torque, .. }, Some(rating)) =
            (s, p.ratings.max_torque)
            && torque.abs() > rating.value
        {
            warnings.push(format!(
                "{at}: torque {} ({}) is beyond the {}'s {} ({})",
                torque.abs(),
                p.units.torque_name(),
                p.name,
                rating.value,
                rating.source
            ));
        }
    }
}

/// The start-up writes of the program's pp, pv and tq steps (in counts) in the drive's units:
/// 0x6081 (pp velocity), 0x6083/0x6084 (pp and pv acceleration and deceleration), 0x6087 (tq
/// slope). They are written once, in PRE-OP, so every step that sets one object must ask the
/// same value of it (the error names both steps).
pub(super) fn profile_writes<B>(
    program: &[Step],
    p: Option<&'static crate::cia402::Profile<B>>,
) -> Result<Vec<(ObjectAddress, Value)>, (usize, String)> {
    let mut out: Vec<(ObjectAddress, Value, usize)> = Vec::new();
    for (n, s) in program.iter().enumerate() {
        let wants = profile_values(s);
        if wants.is_empty() {
            continue;
        }
        let Some(p) = p else {
            return Err((
                n,
                "a pp, pv or tq step needs the drive's profile to write its profile objects in \
                 the drive's units: give profile, esi or profile_file"
                    .into(),
            ));
        };
        let Some(pu) = p.units.profile else {
            return Err((
                n,
                format!(
                    "the {} profile does not give the units of its profile objects",
                    p.name
                ),
            ));
        };
        for (obj, what, v) in wants {
            if obj.index == 0x6087
                && v != 0.0
                && pu.torque_slope == crate::cia402::TorqueSlopeUnit::MilliNewtonMetrePerSecond
            {
                return Err((
                    n,
                    format!(
                        "the {} gives 0x6087 in mN·m/s, which needs the motor's rated torque: \
                         ecdrive does not write a slope for it (leave `slope` out: a step)",
                        p.name
                    ),
                ));
            }
            let r = in_drive_unit(obj, v, &p.units, pu).round();
            check_profile_value(p, obj, what, r).map_err(|m| (n, m))?;
            let value = Value::Uint(r as u64);
            match out.iter().find(|(o, ..)| *o == obj) {
                Some((_, v0, f)) if *v0 != value => {
                    return Err((n, disagreement(obj, what, r, *f)));
                }
                Some(_) => {}
                None => out.push((obj, value, n)),
            }
        }
    }
    Ok(out.into_iter().map(|(o, v, _)| (o, v)).collect())
}

/// The profile objects a step sets, with the key that gives each and its value (counts, or
/// the torque unit per second for 0x6087; 0 = a tq step without `slope`, a step).
fn profile_values(s: &Step) -> Vec<(ObjectAddress, &'static str, f64)> {
    let a = ObjectAddress::new;
    match *s {
        Step::Pp {
            velocity,
            acceleration,
            deceleration,
            ..
        } => vec![
            (a(0x6081, 0), "velocity", velocity),
            (a(0x6083, 0), "acceleration", acceleration),
            (
                a(0x6084, 0),
                "deceleration",
                deceleration.unwrap_or(acceleration),
            ),
        ],
        Step::Pv {
            acceleration,
            deceleration,
            ..
        } => vec![
            (a(0x6083, 0), "acceleration", acceleration),
            (
                a(0x6084, 0),
                "deceleration",
                deceleration.unwrap_or(acceleration),
            ),
        ],
        Step::Tq { slope, .. } => vec![(a(0x6087, 0), "slope", slope.unwrap_or(0.0))],
        _ => Vec::new(),
    }
}

/// A profile object's value `v` (counts/s, counts/s², or torque units per second for 0x6087)
/// in the drive's unit of it, unrounded.
fn in_drive_unit(
    obj: ObjectAddress,
    v: f64,
    u: &crate::cia402::Units,
    pu: crate::cia402::ProfileUnits,
) -> f64 {
    use crate::cia402::TorqueSlopeUnit;
    match obj.index {
        0x6081 => u.from_rev_per_s(pu.profile_velocity, v / u.position_per_rev),
        0x6083 | 0x6084 => accel_in_drive_unit(v, u, pu.acceleration),
        // 0 = a step.
        _ if v == 0.0 => 0.0,
        _ => {
            let permille_s = v * u.torque_per_mille;
            match pu.torque_slope {
                TorqueSlopeUnit::PerMillePerSecond => permille_s,
                TorqueSlopeUnit::MillisecondsToRated => 1000.0 / permille_s * 1000.0,
                // Refused before (it needs the rated torque).
                TorqueSlopeUnit::MilliNewtonMetrePerSecond => f64::NAN,
            }
        }
    }
}

/// An acceleration of `v` counts/s² in the drive's unit of acceleration, unrounded.
fn accel_in_drive_unit(v: f64, u: &crate::cia402::Units, unit: crate::cia402::AccelUnit) -> f64 {
    use crate::cia402::AccelUnit;
    let rev_s2 = v / u.position_per_rev;
    match unit {
        AccelUnit::MillisecondsTo { rpm } => rpm / 60.0 / rev_s2 * 1000.0,
        AccelUnit::RpmPerSecond => rev_s2 * 60.0,
        AccelUnit::PositionPerSecond2 => v,
    }
}

/// A profile object's value `r` in the drive's unit: a whole UNSIGNED32 (at least 1, 0x6087 0
/// too), within the drive's own range of the object (its manual's, or its EDS file's limits).
fn check_profile_value<B>(
    p: &crate::cia402::Profile<B>,
    obj: ObjectAddress,
    what: &str,
    r: f64,
) -> Result<(), String> {
    let min = if obj.index == 0x6087 { 0.0 } else { 1.0 };
    if !(r >= min && r <= f64::from(u32::MAX)) {
        return Err(format!(
            "the step's {what} is {r} in the {}'s unit of {obj}: it must be {min} to {}",
            p.name,
            u32::MAX
        ));
    }
    if let Some(e) = crate::od::Dictionary::new(p.dictionary).entry(obj) {
        let (lo, hi) = (e.min.as_i128(), e.max.as_i128());
        if lo.is_some_and(|lo| (r as i128) < lo) || hi.is_some_and(|hi| (r as i128) > hi) {
            return Err(format!(
                "the step's {what} is {r} in the {}'s unit of {obj}, outside the drive's range \
                 {}–{}",
                p.name,
                lo.map_or_else(|| "…".into(), |v| v.to_string()),
                hi.map_or_else(|| "…".into(), |v| v.to_string()),
            ));
        }
    }
    Ok(())
}

/// Why a step may not set `obj` to `r` when program step `first` set it otherwise.
fn disagreement(obj: ObjectAddress, what: &str, r: f64, first: usize) -> String {
    format!(
        "this step's {what} sets {obj} to {r}{}, program[{first}] sets it otherwise: profile \
         objects are written once at start-up, so the steps of a drive must agree",
        if obj.index == 0x6087 && r == 0.0 {
            " (a tq step without `slope` is a step: 0x6087 = 0)"
        } else {
            ""
        }
    )
}

/// The start-up writes of the program's `home` steps (in counts), in the drive's units:
/// 0x6098, 0x6099:01/02, 0x609A, 0x607C. They are written once, in PRE-OP, so every home step
/// of a drive must ask the same. Checks the method against the drive's 0x60E3 (where its
/// dictionary lists it) and that the drive has hm.
pub(super) fn homing_writes<B>(
    program: &[Step],
    p: Option<&'static crate::cia402::Profile<B>>,
) -> Result<Vec<(ObjectAddress, Value)>, (usize, String)> {
    let Some((n, home)) = the_home_step(program)? else {
        return Ok(Vec::new());
    };
    let Some(p) = p else {
        return Err((
            n,
            "a home step needs the drive's profile to write its homing objects in the drive's \
             units: give profile, esi or profile_file"
                .into(),
        ));
    };
    let &Step::Home { method, .. } = home else {
        return Ok(Vec::new());
    };
    check_homing_method(p, method).map_err(|m| (n, m))?;
    homing_values(p, home).map_err(|m| (n, m))
}

/// The program's first home step and its index, every other home step being the same; `None`
/// without one.
fn the_home_step(program: &[Step]) -> Result<Option<(usize, &Step)>, (usize, String)> {
    let mut first: Option<(usize, &Step)> = None;
    for (n, s) in program.iter().enumerate() {
        if !matches!(s, Step::Home { .. }) {
            continue;
        }
        match first {
            None => first = Some((n, s)),
            Some((_, f)) if f == s => {}
            Some((f, _)) => {
                return Err((
                    n,
                    format!(
                        "this home step differs from program[{f}]'s: the homing method, speeds, \
                         acceleration and offset are written once at start-up, so every home \
                         step of a drive must give the same"
                    ),
                ));
            }
        }
    }
    Ok(first)
}

/// Whether the drive runs homing method `method`: it has hm, the method is one (not 0),
/// within the range its dictionary gives 0x6098 and among those it lists in 0x60E3.
fn check_homing_method<B>(p: &crate::cia402::Profile<B>, method: i8) -> Result<(), String> {
    use crate::cia402::OperationMode;
    if !p.caps.supported_modes.contains(OperationMode::Homing) {
        return Err(format!("the {} has no homing mode (0x6502)", p.name));
    }
    // CiA 402: 0x6098 = 0 is "no homing method assigned" (the BDHDE's manual says so too).
    if method == 0 {
        return Err(
            "homing method 0 means no homing method (CiA 402, 0x6098): name the method the \
             drive is to run"
                .into(),
        );
    }
    // The range the drive's dictionary gives 0x6098 (the BDHDE's manual: at most 35).
    if let Some(e) = p
        .dictionary
        .iter()
        .find(|o| o.index == 0x6098)
        .and_then(|o| o.entries.iter().find(|e| e.sub == 0))
    {
        let m = i128::from(method);
        let below = e.min.as_i128().is_some_and(|lo| m < lo);
        let above = e.max.as_i128().is_some_and(|hi| m > hi);
        if below || above {
            let range = match (e.min.as_i128(), e.max.as_i128()) {
                (Some(lo), Some(hi)) => format!("{lo} to {hi}"),
                (Some(lo), None) => format!("at least {lo}"),
                (None, Some(hi)) => format!("at most {hi}"),
                (None, None) => "no range".to_string(),
            };
            return Err(format!(
                "homing method {method} is outside what the {} takes in 0x6098 ({range})",
                p.name
            ));
        }
    }
    let listed = listed_homing_methods(p.dictionary);
    if !listed.is_empty() && !listed.contains(&i64::from(method)) {
        let l: Vec<String> = listed.iter().map(i64::to_string).collect();
        return Err(format!(
            "homing method {method} is not one the {} lists in 0x60E3 ({})",
            p.name,
            l.join(", ")
        ));
    }
    Ok(())
}

/// The methods a drive lists in 0x60E3 (its dictionary's defaults), if it has the object.
fn listed_homing_methods(dictionary: &[crate::od::ObjectDesc]) -> Vec<i64> {
    dictionary
        .iter()
        .find(|o| o.index == 0x60E3)
        .map(|o| {
            o.entries
                .iter()
                .filter(|e| e.sub > 0)
                .filter_map(|e| e.default.as_i128())
                .filter_map(|v| i64::try_from(v).ok())
                .map(|v| i64::from(v as u8 as i8))
                .filter(|v| *v != 0)
                .collect()
        })
        .unwrap_or_default()
}

/// A home step's objects in the drive's units: the method, the speeds, the acceleration (if
/// given) and the home offset (if given).
fn homing_values<B>(
    p: &crate::cia402::Profile<B>,
    home: &Step,
) -> Result<Vec<(ObjectAddress, Value)>, String> {
    let &Step::Home {
        method,
        speed_switch,
        speed_zero,
        acceleration,
        offset,
    } = home
    else {
        return Ok(Vec::new());
    };
    let Some(pu) = p.units.profile else {
        return Err(format!(
            "the {} profile does not give its homing units",
            p.name
        ));
    };
    let u = &p.units;
    // Each value in the drive's unit must be a whole number the object holds (UNSIGNED32)
    // and not 0: a speed of 0 never moves, an acceleration of 0 means something else.
    let fits = |what: &str, obj: &str, v: f64| -> Result<Value, String> {
        let r = v.round();
        if r >= 1.0 && r <= f64::from(u32::MAX) {
            Ok(Value::Uint(r as u64))
        } else {
            Err(format!(
                "the home step's {what} is {r} in the {}'s unit of {obj}: it must be 1 to {}",
                p.name,
                u32::MAX
            ))
        }
    };
    let speed = |v: f64| u.from_rev_per_s(pu.homing_velocity, v / u.position_per_rev);
    let a = ObjectAddress::new;
    let mut out = vec![
        (a(0x6098, 0), Value::Int(i64::from(method))),
        (
            a(0x6099, 1),
            fits("speed_switch", "0x6099:01", speed(speed_switch))?,
        ),
        (
            a(0x6099, 2),
            fits("speed_zero", "0x6099:02", speed(speed_zero))?,
        ),
    ];
    // Without an acceleration the drive keeps its own 0x609A.
    if let Some(acc) = acceleration {
        let value = accel_in_drive_unit(acc, u, pu.acceleration);
        out.push((a(0x609A, 0), fits("acceleration", "0x609A", value)?));
    }
    // The home offset (0x607C): the position the home then reads, in position units.
    if let Some(o) = offset {
        if let Some(why) = p.caps.home_offset_set_by_drive {
            return Err(format!("the home step's offset cannot be given: {why}"));
        }
        let counts = o.round();
        if !(o.is_finite() && counts.abs() <= f64::from(i32::MAX)) {
            return Err(format!(
                "the home step's offset is {counts} counts: it must fit 0x607C (±2^31)"
            ));
        }
        out.push((a(0x607C, 0), Value::Int(counts as i64)));
    }
    Ok(out)
}
