//! Step helpers on the CANopen master's own engine ([`Master::cycle_step`] with the profile-mode
//! helpers of [`crate::cia402`]): home, a pp move, pv, tq, ip, an injected fault and its
//! reset, each until done or a timeout of simulated time. The low-level API's tests use them;
//! runs, the application API and `demo --canopen` run the drives on the motion runtime instead
//! ([`crate::canopen::motion`]).
//!
//! # Running a drive
//!
//! ```
//! use ecdrive::sim::canopen::{EmulatedNode, SimBus};
//! use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig};
//! use ecdrive::cia402::{ProfilePosition, SetPoint};
//! use ecdrive::drives::blv_r;
//!
//! let mut bus = SimBus::new();
//! bus.add_node(EmulatedNode::new(&ecdrive::sim::canopen::drives::blv_r::SPEC, 3).unwrap());
//! let mut m = Master::new(bus, MasterConfig::default());
//! let mut setup = DriveSetup::new(&blv_r::PROFILE);
//! setup.settings = ecdrive_cli::app::canopen::steps::motion_settings(&blv_r::PROFILE, 10.0, 100.0);
//! m.configure_drive(3, setup).unwrap(); // identity, supervision, PDOs, mode
//! m.start(3).unwrap(); // NMT start
//! m.enable(3, 1_000_000).unwrap(); // Axis → Operation enabled
//! let mut pp = ProfilePosition::default();
//! pp.push(SetPoint::absolute(36_000)).unwrap();
//! loop {
//!     let mut done = false;
//!     m.cycle_step(|d| {
//!         let sw = d.statusword();
//!         let st = pp.step(d.axis_mut(), sw);
//!         done = st.target_reached && st.acknowledged == 1;
//!     })
//!     .unwrap();
//!     if done {
//!         break;
//!     }
//! }
//! assert_eq!(m.transport().node(3).unwrap().position(), 36_000);
//! m.shutdown_node(3, 1_000_000).unwrap(); // disable, then NMT stop
//! ```

use crate::canopen::error::{CanError, CanErrorKind, NodeRef};
use crate::canopen::master::{Master, MasterEvent};
use crate::canopen::motion::{ProfileSpeeds, profile_settings};
use crate::canopen::profile::CanDriveProfile;
use crate::canopen::transport::CanTransport;
use crate::cia402::interpolated::linear_point;
use crate::cia402::{
    Event, Homing, HomingOutcome, Interpolation, OperationMode, ProfilePosition, ProfileTorque,
    ProfileVelocity, SetPoint,
};
use crate::od::{ObjectAddress, Value};

/// **\[REC\]** The helpers' motion: profile velocity 10 rev/s, ramps 100 rev/s², homing 5 / 0.5 rev/s.
pub mod defaults {
    /// Profile velocity, rev/s.
    pub const VELOCITY_REV_S: f64 = 10.0;
    /// Acceleration and deceleration, rev/s².
    pub const ACCEL_REV_S2: f64 = 100.0;
    /// Homing search speed, rev/s.
    pub const HOMING_FAST_REV_S: f64 = 5.0;
    /// Homing creep speed, rev/s.
    pub const HOMING_SLOW_REV_S: f64 = 0.5;
    /// Timeout of each step, µs (simulated time).
    pub const STEP_TIMEOUT_US: u64 = 20_000_000;
}

/// SDO settings for profile velocity, accelerations and homing speeds in the drive's units,
/// with the demo's homing speeds ([`defaults`]): [`profile_settings`] of the CANopen master.
pub fn motion_settings(
    profile: &CanDriveProfile,
    velocity_rev_s: f64,
    accel_rev_s2: f64,
) -> Vec<(ObjectAddress, Value)> {
    profile_settings(
        profile,
        &ProfileSpeeds {
            velocity_rev_s,
            accel_rev_s2,
            homing_fast_rev_s: defaults::HOMING_FAST_REV_S,
            homing_slow_rev_s: defaults::HOMING_SLOW_REV_S,
        },
    )
}

fn err<T: CanTransport>(m: &Master<T>, node: u8, what: String) -> CanError {
    CanError::new(m.node_ref(node), None, CanErrorKind::Timeout(what))
}

fn fault_text<T: CanTransport>(m: &mut Master<T>, node: u8) -> Option<String> {
    let d = m.drive_mut(node)?;
    let mut t = None;
    while let Some(e) = d.axis_mut().poll_event() {
        if let Event::Fault { error, .. } = e {
            t = Some(match error {
                Some(e) => format!("the drive faulted: {e}"),
                None => "the drive faulted".into(),
            });
        }
    }
    t
}

/// Home `node` with `method` (6098h) and home offset `offset` (607Ch): switch to hm, run the
/// [`Homing`] helper to its end. Returns the position afterwards.
pub fn home<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    method: i8,
    offset: i32,
    timeout_us: u64,
) -> Result<i32, CanError> {
    m.switch_mode(node, OperationMode::Homing, timeout_us)?;
    m.download_value(
        node,
        ObjectAddress::new(0x6098, 0),
        &Value::Int(method.into()),
        None,
    )?;
    m.download_value(
        node,
        ObjectAddress::new(0x607C, 0),
        &Value::Int(offset.into()),
        None,
    )?;
    let mut h = Homing::default();
    h.start();
    let deadline = m.now_us().saturating_add(timeout_us);
    loop {
        m.cycle_step(|d| {
            if d.node() == node {
                let sw = d.statusword();
                h.step(d.axis_mut(), sw);
            }
        })?;
        if let Some(f) = fault_text(m, node) {
            return Err(err(m, node, format!("homing: {f}")));
        }
        match h.outcome() {
            Some(HomingOutcome::Completed) => break,
            Some(o) => return Err(err(m, node, format!("homing method {method}: {o:?}"))),
            None => {}
        }
        if m.now_us() > deadline {
            return Err(err(
                m,
                node,
                format!("homing method {method} did not finish"),
            ));
        }
    }
    Ok(m.drive(node)
        .and_then(|d| d.feedback().position)
        .unwrap_or(0))
}

/// Run the pp set-points `sps` on `node` (switching to pp first) until all are acknowledged and
/// the target is reached. Returns the position.
pub fn move_pp<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    sps: &[SetPoint],
    timeout_us: u64,
) -> Result<i32, CanError> {
    m.switch_mode(node, OperationMode::ProfilePosition, timeout_us)?;
    let mut pp = ProfilePosition::default();
    for sp in sps {
        pp.push(*sp).map_err(|e| err(m, node, format!("pp: {e}")))?;
    }
    let n = sps.len() as u32;
    let deadline = m.now_us().saturating_add(timeout_us);
    loop {
        let mut st = None;
        m.cycle_step(|d| {
            if d.node() == node {
                let sw = d.statusword();
                st = Some(pp.step(d.axis_mut(), sw));
            }
        })?;
        if let Some(f) = fault_text(m, node) {
            return Err(err(m, node, format!("pp: {f}")));
        }
        if let Some(st) = st {
            if let Some(e) = st.error {
                return Err(err(m, node, format!("pp: {e}")));
            }
            if st.target_reached && st.acknowledged >= n {
                break;
            }
        }
        if m.now_us() > deadline {
            return Err(err(m, node, "pp: target not reached".into()));
        }
    }
    Ok(m.drive(node)
        .and_then(|d| d.feedback().position)
        .unwrap_or(0))
}

/// Run pv at `velocity` (drive units) on `node` until speed reached, hold it for `hold_us`,
/// then halt until zero speed. Returns the velocity reported at the end of the hold.
pub fn run_pv<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    velocity: i32,
    hold_us: u64,
    timeout_us: u64,
) -> Result<i32, CanError> {
    m.switch_mode(node, OperationMode::ProfileVelocity, timeout_us)?;
    let zero_bit = m.profile(node).is_some_and(|p| p.pv_zero_speed_bit);
    let mut pv = ProfileVelocity::new(zero_bit);
    pv.set_target(velocity);
    let deadline = m.now_us().saturating_add(timeout_us);
    let mut reached_at = None;
    let seen;
    loop {
        let mut st = None;
        m.cycle_step(|d| {
            if d.node() == node {
                let sw = d.statusword();
                st = Some(pv.step(d.axis_mut(), sw));
            }
        })?;
        if let Some(f) = fault_text(m, node) {
            return Err(err(m, node, format!("pv: {f}")));
        }
        let now = m.now_us();
        if st.is_some_and(|s| s.target_reached && s.streaming) && reached_at.is_none() {
            reached_at = Some(now);
        }
        if let Some(t) = reached_at
            && now >= t + hold_us
        {
            seen = m
                .drive(node)
                .and_then(|d| d.feedback().velocity)
                .unwrap_or(0);
            break;
        }
        if now > deadline {
            return Err(err(m, node, "pv: speed not reached".into()));
        }
    }
    pv.set_halt(true);
    loop {
        let mut st = None;
        m.cycle_step(|d| {
            if d.node() == node {
                let sw = d.statusword();
                st = Some(pv.step(d.axis_mut(), sw));
            }
        })?;
        let stopped = st.is_some_and(|s| s.zero_speed.unwrap_or(s.target_reached));
        if stopped {
            break;
        }
        if m.now_us() > deadline {
            return Err(err(m, node, "pv: halt did not stop the axis".into()));
        }
    }
    Ok(seen)
}

/// Run tq at `torque` (‰) on `node` until torque reached, then ramp back to 0 and wait for
/// standstill. Returns the torque reported when reached.
pub fn run_tq<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    torque: i16,
    timeout_us: u64,
) -> Result<i16, CanError> {
    m.switch_mode(node, OperationMode::ProfileTorque, timeout_us)?;
    let mut tq = ProfileTorque::new();
    tq.set_target(torque);
    let deadline = m.now_us().saturating_add(timeout_us);
    let mut got = 0;
    let mut phase = 0;
    loop {
        let mut st = None;
        m.cycle_step(|d| {
            if d.node() == node {
                let sw = d.statusword();
                st = Some(tq.step(d.axis_mut(), sw));
            }
        })?;
        if let Some(f) = fault_text(m, node) {
            return Err(err(m, node, format!("tq: {f}")));
        }
        let fb_t = m.drive(node).and_then(|d| d.feedback().torque).unwrap_or(0);
        if st.is_some_and(|s| s.target_reached && s.streaming) {
            if phase == 0 && fb_t == torque {
                got = fb_t;
                phase = 1;
                tq.set_target(0);
            } else if phase == 1 && fb_t == 0 {
                // Torque off: wait for the load to coast to standstill too.
                let still = m.drive(node).and_then(|d| d.feedback().velocity) == Some(0);
                if still {
                    break;
                }
            }
        }
        if m.now_us() > deadline {
            return Err(err(m, node, "tq: torque not reached".into()));
        }
    }
    Ok(got)
}

/// Run ip on `node` along a straight line from the present position by `distance` over
/// `cycles` cycles (one point per SYNC), then wait until the drive holds the end point.
/// Returns the final position.
pub fn run_ip<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    distance: i32,
    cycles: u32,
    timeout_us: u64,
) -> Result<i32, CanError> {
    m.switch_mode(node, OperationMode::InterpolatedPosition, timeout_us)?;
    let needs_bit = m.profile(node).is_some_and(|p| p.ip_needs_enable_bit);
    let mut ip = Interpolation::new(needs_bit);
    let from = m
        .drive(node)
        .and_then(|d| d.feedback().position)
        .unwrap_or(0);
    let to = from.wrapping_add(distance);
    let deadline = m.now_us().saturating_add(timeout_us);
    let mut k = 0u32;
    loop {
        let p = linear_point(from, to, cycles, k);
        m.cycle_step(|d| {
            if d.node() == node {
                let sw = d.statusword();
                ip.step(d.axis_mut(), sw, p);
            }
        })?;
        if let Some(f) = fault_text(m, node) {
            return Err(err(m, node, format!("ip: {f}")));
        }
        k = k.saturating_add(1);
        let pos = m.drive(node).and_then(|d| d.feedback().position);
        if k > cycles && pos == Some(to) {
            return Ok(to);
        }
        if m.now_us() > deadline {
            return Err(err(
                m,
                node,
                format!("ip: end point {to} not reached (at {pos:?})"),
            ));
        }
    }
}

/// Inject-and-reset check: raise alarm `number` on the emulated node `node` of `bus` access
/// `inject`, wait for the axis to report the fault, reset it and enable again. Returns the
/// EMCY text the master decoded.
pub fn fault_and_reset<T: CanTransport>(
    m: &mut Master<T>,
    node: u8,
    inject: impl FnOnce(&mut T),
    timeout_us: u64,
) -> Result<String, CanError> {
    inject(m.transport_mut());
    let deadline = m.now_us().saturating_add(timeout_us);
    let mut emcy = None;
    let mut faulted = false;
    while !(faulted && emcy.is_some()) {
        m.cycle_step(|_| {})?;
        while let Some(e) = m.poll_event() {
            if let MasterEvent::Emergency(r) = e
                && r.node == node
                && !r.emergency.is_reset()
            {
                emcy = Some(r.to_string());
            }
        }
        if let Some(d) = m.drive_mut(node) {
            while let Some(e) = d.axis_mut().poll_event() {
                if matches!(e, Event::Fault { .. }) {
                    faulted = true;
                }
            }
        }
        if m.now_us() > deadline {
            return Err(err(m, node, "fault: no fault seen".into()));
        }
    }
    let d = m.drive_mut(node).ok_or_else(|| {
        CanError::new(
            NodeRef {
                id: node,
                drive: None,
            },
            None,
            CanErrorKind::NotReady("no drive".into()),
        )
    })?;
    d.axis_mut().request_fault_reset();
    let mut cleared = false;
    while !cleared {
        m.cycle_step(|_| {})?;
        if let Some(d) = m.drive_mut(node) {
            while let Some(e) = d.axis_mut().poll_event() {
                if matches!(e, Event::FaultCleared) {
                    cleared = true;
                }
            }
        }
        if m.now_us() > deadline {
            return Err(err(m, node, "fault reset did not clear the fault".into()));
        }
    }
    m.enable(node, timeout_us)?;
    Ok(emcy.unwrap_or_default())
}

/// **\[REC\]** The homing method each demo drive uses: home switch, positive start (BLV-R 24,
/// others 19).
pub fn demo_homing_method(profile: &CanDriveProfile) -> i8 {
    if profile.homing.supports(24) && !profile.homing.supports(19) {
        24
    } else {
        19
    }
}
