//! The CANopen drives on the motion runtime the EtherCAT master runs too
//! ([`ecdrive_motion::MotionAxis`]): programs, homing, the profile modes, controlled stops,
//! following-error supervision and the application's requests, the same code for both buses.
//!
//! A [`MotionSession`] owns a configured and started [`Master`] and one motion axis per drive.
//! Each [`MotionSession::cycle`] is read → step → write: one communication cycle (RPDOs, SYNC,
//! the TPDOs answering it), then for every drive with feedback the runtime's step on the
//! TPDO data, its [`Output`](crate::cia402::Output) into the RPDO image sent with the next SYNC.
//! Commands ([`Command`]) and the runtime's events ([`Event`]) are those of the EtherCAT
//! master; the cycle number is the SYNC count, the DC time the bus's clock
//! ([`CanTransport::now_us`]).
//!
//! Each of the three drives homes, runs pp, pv and tq (where its firmware has it) on it in
//! `tests/app/canopen_motion.rs`: configure and start the drive with the [`Master`], build the
//! session with [`axis_setup`] and a program, send [`Command::Enable`] and
//! [`Command::RunProgram`], and call [`MotionSession::cycle`] until the program's
//! [`EventKind::ProgramDone`].

use crate::cia402::Feedback;
use crate::error::{CanError, CanErrorKind, NodeRef};
use crate::master::Master;
use crate::od::{Dictionary, ObjectAddress, Value};
use crate::pdo::{AxisBinding, Direction, Field, axis::standard_type};
use crate::profile::CanDriveProfile;
use crate::transport::CanTransport;
use ecdrive_motion::program::{RunMode, Step};
use ecdrive_motion::telemetry::{AxisTelemetry, Command, Event, EventKind, StopKind};
use ecdrive_motion::{AppAxis, AppCycle, CycleApp};
use ecdrive_motion::{
    AxisSetup, EventSink, Inputs, MotionAxis, ProbeObjects, Requests, SetpointLimits, StepContext,
};
use std::time::Duration;

mod thread;
pub use thread::{CycleThread, SessionView, ThreadEnd};

/// **\[REC\]** A controlled stop's ramp: 0.2 s (as the EtherCAT master's default).
pub const STOP_RAMP: Duration = Duration::from_millis(200);

/// **\[REC\]** A controlled stop that has not ended after 2 s disables regardless.
pub const STOP_TIMEOUT: Duration = Duration::from_secs(2);

/// What the runtime needs of a CANopen drive from its profile, with a program to run from
/// `mode`: its capabilities and velocity unit; no following-error limit and no set-point
/// limits (set them on the result). The touch-probe objects are the ones the drive's PDO plan
/// carries ([`crate::PdoPlan::with_probes`]), found by [`MotionSession::new`].
pub fn axis_setup(profile: &CanDriveProfile, program: Vec<Step>, mode: RunMode) -> AxisSetup {
    AxisSetup {
        caps: profile.caps,
        velocity_unit: profile.units.velocity_position_per_s(),
        position_per_rev: profile.units.position_per_rev,
        program,
        mode,
        following_error_limit: None,
        limits: SetpointLimits::default(),
        probe_objects: ProbeObjects::default(),
        ip_enable_bit: profile.ip_needs_enable_bit,
    }
}

/// Profile-mode speeds in revolutions of the motor shaft, for [`profile_settings`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileSpeeds {
    /// Profile velocity (6081h), rev/s.
    pub velocity_rev_s: f64,
    /// Profile acceleration and deceleration, quick-stop deceleration (6083h–6085h), rev/s².
    pub accel_rev_s2: f64,
    /// Homing search speed (6099h:01), rev/s.
    pub homing_fast_rev_s: f64,
    /// Homing creep speed (6099h:02), rev/s.
    pub homing_slow_rev_s: f64,
}

/// SDO settings for `speeds` in the drive's units (r/min, PUU/s and ms-to-3000 r/min,
/// steps/s … — converted with its [`Units`](crate::profile::Units)), for a [`DriveSetup`]'s
/// `settings`: only the objects the drive's dictionary has; none for a profile that does not
/// describe its profile-mode units.
///
/// [`DriveSetup`]: crate::master::DriveSetup
pub fn profile_settings(
    profile: &CanDriveProfile,
    speeds: &ProfileSpeeds,
) -> Vec<(ObjectAddress, Value)> {
    let uint = |v: f64| Value::Uint(v.round().clamp(1.0, f64::from(u32::MAX)) as u64);
    let u = &profile.units;
    let (Some(pu), Some(acc)) = (u.profile, u.accel_from_rev_per_s2(speeds.accel_rev_s2)) else {
        return Vec::new();
    };
    let acc = uint(acc);
    let mut v = vec![
        (
            ObjectAddress::new(0x6081, 0),
            uint(u.from_rev_per_s(pu.profile_velocity, speeds.velocity_rev_s)),
        ),
        (ObjectAddress::new(0x6083, 0), acc.clone()),
        (ObjectAddress::new(0x6084, 0), acc.clone()),
        (ObjectAddress::new(0x6085, 0), acc),
        (
            ObjectAddress::new(0x6099, 1),
            uint(u.from_rev_per_s(pu.homing_velocity, speeds.homing_fast_rev_s)),
        ),
        (
            ObjectAddress::new(0x6099, 2),
            uint(u.from_rev_per_s(pu.homing_velocity, speeds.homing_slow_rev_s)),
        ),
    ];
    let dict = Dictionary::new(profile.dictionary);
    v.retain(|(a, _)| dict.entry(*a).is_some());
    v
}

/// Events held between two [`MotionSession::take_events`] without reallocation.
const EVENTS_CAPACITY: usize = 256;

/// Where a drive's PDOs carry its touch-probe objects: 60B8h (RPDO), 60B9h and the latches
/// 60BAh–60BDh (TPDOs).
#[derive(Debug, Clone, Copy, Default)]
struct ProbeFields {
    function: Option<Field>,
    status: Option<Field>,
    positions: [Option<Field>; 4],
}

impl ProbeFields {
    fn of(d: &crate::drive::CanDrive) -> Self {
        use crate::od::DataType::{Integer32, Unsigned16};
        let l = d.layout();
        let a = |i: u16| ObjectAddress::new(i, 0);
        let field = |dir, i, t| l.field(dir, a(i), t).ok();
        Self {
            function: field(Direction::Rx, 0x60B8, Unsigned16),
            status: field(Direction::Tx, 0x60B9, Unsigned16),
            positions: [0x60BA, 0x60BB, 0x60BC, 0x60BD].map(|i| field(Direction::Tx, i, Integer32)),
        }
    }
}

/// The application's view of drive `d`: every entry its PDOs map, the ones the CiA 402 engine
/// writes ([`AxisBinding::drives`]) marked, typed by the drive's dictionary.
fn app_view(d: &crate::drive::CanDrive) -> AppAxis {
    let dict = Dictionary::new(d.profile().dictionary);
    let signed = |a: ObjectAddress| {
        dict.data_type(a)
            .or_else(|| standard_type(a))
            .is_some_and(|t| t.is_signed())
    };
    AppAxis::new(d.layout(), &AxisBinding::drives, &signed)
}

/// The events of the runtime's steps, stamped with the cycle and the bus's time.
struct Sink<'a> {
    events: &'a mut Vec<Event>,
    cycle: u64,
    time_us: u64,
}

impl EventSink for Sink<'_> {
    fn emit(&mut self, kind: EventKind) {
        self.events.push(Event {
            cycle: self.cycle,
            time_ns: self.time_us.saturating_mul(1000),
            kind,
        });
    }
}

/// A configured, started [`Master`] whose drives the motion runtime runs. See the
/// [module documentation](self).
pub struct MotionSession<T: CanTransport> {
    master: Master<T>,
    /// The node of each axis, in the order of the set-ups.
    nodes: Vec<u8>,
    axes: Vec<MotionAxis>,
    /// The application's view of each axis, and each axis's feedback of this cycle.
    views: Vec<AppAxis>,
    feedback: Vec<Option<Feedback>>,
    /// Each axis's touch-probe objects in its PDOs.
    probes: Vec<ProbeFields>,
    events: Vec<Event>,
    /// Cycles so far, and those in which every drive had fed back (the programs' clock).
    cycle: u64,
    tick: u64,
    dt: f64,
    stop_ramp_cycles: u64,
    stop_timeout_cycles: u64,
}

/// One drive of [`MotionSession::start`]: its node, how the master configures it, and its axis.
#[derive(Debug, Clone)]
pub struct SessionDrive {
    /// Node-ID.
    pub node: u8,
    /// The master's configuration of it (PDO plan, supervision, start-up values).
    pub setup: crate::master::DriveSetup,
    /// What the motion runtime runs on it.
    pub axis: AxisSetup,
}

impl<T: CanTransport> MotionSession<T> {
    /// A master on `transport` with `cfg`, every drive taken to NMT Pre-operational (a node an
    /// earlier session left Stopped serves no SDO), configured, started (Operational), and
    /// the session of their axes. An error names the node and why.
    pub fn start(
        transport: T,
        cfg: crate::master::MasterConfig,
        drives: Vec<SessionDrive>,
    ) -> Result<Self, CanError> {
        let mut m = Master::new(transport, cfg);
        m.pump(50_000)?;
        for d in &drives {
            m.nmt(d.node, crate::nmt::NmtCommand::EnterPreOperational)?;
        }
        m.pump(20_000)?;
        let mut axes = Vec::with_capacity(drives.len());
        for d in drives {
            m.configure_drive(d.node, d.setup)?;
            m.start(d.node)?;
            axes.push((d.node, d.axis));
        }
        Self::new(m, &axes)
    }

    /// The session of `master` with one motion axis per `(node, setup)`: every node must be a
    /// drive the master configured. An error names the node and why.
    pub fn new(master: Master<T>, axes: &[(u8, AxisSetup)]) -> Result<Self, CanError> {
        let cycle_us = master.config().cycle_us.max(1);
        let cycle = Duration::from_micros(cycle_us);
        let mut nodes = Vec::with_capacity(axes.len());
        let mut built = Vec::with_capacity(axes.len());
        let mut views = Vec::with_capacity(axes.len());
        let mut probes = Vec::with_capacity(axes.len());
        for (node, setup) in axes {
            let why = |what: &str| {
                CanError::new(
                    master.node_ref(*node),
                    None,
                    CanErrorKind::NotReady(what.into()),
                )
            };
            let Some(d) = master.drive(*node) else {
                return Err(why("not a configured drive"));
            };
            views.push(app_view(d));
            let pf = ProbeFields::of(d);
            probes.push(pf);
            // The probe objects the PDOs carry, as the EtherCAT start-up tells its axes.
            let setup = AxisSetup {
                probe_objects: ProbeObjects {
                    function: pf.function.is_some(),
                    status: pf.status.is_some(),
                    positions: pf.positions.map(|p| p.is_some()),
                },
                ..setup.clone()
            };
            let a = MotionAxis::new(&setup, cycle)
                .ok_or_else(|| why("the drive's capabilities give no axis for this cycle"))?;
            nodes.push(*node);
            built.push(a);
        }
        let cycles = |d: Duration| (d.as_micros() as u64).div_ceil(cycle_us).max(1);
        Ok(Self {
            master,
            nodes,
            feedback: vec![None; built.len()],
            axes: built,
            views,
            probes,
            events: Vec::with_capacity(EVENTS_CAPACITY),
            cycle: 0,
            tick: 0,
            dt: cycle.as_secs_f64(),
            stop_ramp_cycles: cycles(STOP_RAMP),
            stop_timeout_cycles: cycles(STOP_TIMEOUT),
        })
    }

    /// Apply a command to every axis it addresses; a refusal is an event
    /// ([`EventKind::CommandRefused`]). A stop begins a controlled stop of every axis.
    pub fn command(&mut self, cmd: Command) {
        let mut sink = Sink {
            events: &mut self.events,
            cycle: self.cycle,
            time_us: self.master.now_us(),
        };
        for (i, a) in self.axes.iter_mut().enumerate() {
            let why = match cmd {
                Command::Stop(kind) => {
                    a.begin_stop(kind, self.tick, self.cycle);
                    None
                }
                Command::Restart => {
                    a.begin_stop(StopKind::Ramp, self.tick, self.cycle);
                    None
                }
                other => a.apply(&other, i),
            };
            if let Some(why) = why {
                sink.emit(EventKind::CommandRefused {
                    axis: i as u16,
                    why,
                });
            }
        }
    }

    /// One cycle with no application: [`MotionSession::cycle_app`] without one.
    pub fn cycle(&mut self) -> Result<(), CanError> {
        self.cycle_inner(None)
    }

    /// One cycle with the application's code in it: the bus's ([`Master::cycle`]: RPDOs,
    /// SYNC, the TPDOs answering it), then every axis's view refreshed from its TPDO data,
    /// then `app` (its requests, its writes to mapped outputs the engine does not drive), then
    /// for each drive with feedback the runtime's step with those requests, its outputs and
    /// the application's writes into the RPDO image sent with the next SYNC; then the stops
    /// supervised (a drive that faulted stops the others). Allocation-free.
    pub fn cycle_app(&mut self, app: &mut dyn CycleApp) -> Result<(), CanError> {
        self.cycle_inner(Some(app))
    }

    fn cycle_inner(&mut self, mut app: Option<&mut dyn CycleApp>) -> Result<(), CanError> {
        self.master.cycle()?;
        self.cycle += 1;
        let fed = self
            .nodes
            .iter()
            .all(|n| self.master.drive(*n).is_some_and(|d| d.has_feedback()));
        if fed {
            self.tick += 1;
        }
        let ctx = StepContext {
            cycle: self.cycle,
            tick: self.tick,
            dt: self.dt,
            // The TPDOs of this cycle answer the SYNC just sent.
            pulse: self.cycle,
            ending: false,
            any_energised_before: self.axes.iter().any(MotionAxis::busy),
            stop_ramp_cycles: self.stop_ramp_cycles,
            stop_timeout_cycles: self.stop_timeout_cycles,
        };
        let now_us = self.master.now_us();
        self.read_feedback(&ctx, app.is_some());
        if let Some(app) = app.as_deref_mut() {
            let events = &mut self.events;
            let cycle = self.cycle;
            let mut emit = |kind: EventKind| {
                events.push(Event {
                    cycle,
                    time_ns: now_us.saturating_mul(1000),
                    kind,
                })
            };
            let mut c = AppCycle::new(
                self.cycle,
                self.dt,
                now_us.saturating_mul(1000),
                &mut self.views,
                &mut emit,
            );
            app.cycle(&mut c);
        }
        let mut sink = Sink {
            events: &mut self.events,
            cycle: self.cycle,
            time_us: now_us,
        };
        for (i, ((node, a), view)) in self
            .nodes
            .iter()
            .zip(self.axes.iter_mut())
            .zip(self.views.iter())
            .enumerate()
        {
            let Some(fb) = self.feedback.get_mut(i).and_then(Option::take) else {
                continue;
            };
            let Some(d) = self.master.drive_mut(*node) else {
                continue;
            };
            let req = if app.is_some() {
                view.requests()
            } else {
                Requests::default()
            };
            let out = a.step(i, fb, &ctx, &mut sink, req);
            d.write_output(&out);
            if let (Some(f), Some(v)) = (
                self.probes.get(i).and_then(|p| p.function),
                a.probe_function(),
            ) {
                d.write_raw(f, u64::from(v));
            }
            for &(field, raw) in view.writes() {
                d.write_raw(field, raw);
            }
        }
        self.supervise();
        Ok(())
    }

    /// Each drive's feedback of this cycle (its TPDO data) read into its axis, and with an
    /// application its view refreshed.
    fn read_feedback(&mut self, ctx: &StepContext, with_app: bool) {
        for (i, (node, a)) in self.nodes.iter().zip(self.axes.iter_mut()).enumerate() {
            let Some(d) = self.master.drive(*node) else {
                continue;
            };
            // TPDOs come from Operational nodes only.
            let in_op = d.has_feedback();
            let fb = in_op.then(|| {
                let pf = self.probes.get(i).copied().unwrap_or_default();
                let tx = d.tx_image();
                let read = |f: Option<Field>| {
                    f.and_then(|f| f.read_int(tx).ok())
                        .and_then(|v| i64::try_from(v).ok())
                        .unwrap_or(0)
                };
                let inputs = Inputs {
                    feedback: d.feedback(),
                    probe_status: read(pf.status) as u16,
                    probe_positions: pf.positions.map(|p| read(p) as i32),
                    following_error_drive: d.binding().following_error(tx),
                };
                a.read(&inputs, ctx.pulse)
            });
            if let Some(slot) = self.feedback.get_mut(i) {
                *slot = fb;
            }
            if with_app && let Some(view) = self.views.get_mut(i) {
                view.refresh(a, in_op, d.tx_image(), d.rx_image());
            }
        }
    }

    /// After the steps: a drive that faulted stops every other axis; stops that take too long
    /// end in disable.
    fn supervise(&mut self) {
        if self.axes.iter().any(|a| a.status().fault) {
            for a in self.axes.iter_mut() {
                let st = a.status();
                if !st.fault
                    && !a.stopping()
                    && st.state == Some(crate::cia402::State::OperationEnabled)
                {
                    a.begin_stop(StopKind::Ramp, self.tick, self.cycle);
                }
            }
        }
        for a in self.axes.iter_mut() {
            a.supervise_stop(self.cycle, self.stop_timeout_cycles, false);
        }
    }

    /// The events so far (the caller may [`MotionSession::take_events`]).
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// The events so far, leaving none.
    pub fn take_events(&mut self) -> Vec<Event> {
        core::mem::take(&mut self.events)
    }

    /// Hand every event so far to `f`, keeping the buffer (allocation-free: the cycle
    /// thread's way, [`CycleThread`]).
    pub fn drain_events(&mut self, mut f: impl FnMut(Event)) {
        for e in self.events.drain(..) {
            f(e);
        }
    }

    /// Whether any axis is energised or stopping (a controlled stop has not ended yet).
    pub fn any_busy(&self) -> bool {
        self.axes.iter().any(|a| a.busy() || a.stopping())
    }

    /// The cycle period, µs.
    pub fn cycle_us(&self) -> u64 {
        self.master.config().cycle_us.max(1)
    }

    /// Cycles so far.
    pub fn cycles(&self) -> u64 {
        self.cycle
    }

    /// The number of axes.
    pub fn len(&self) -> usize {
        self.axes.len()
    }

    /// Whether the session has no axis.
    pub fn is_empty(&self) -> bool {
        self.axes.is_empty()
    }

    /// Axis `i`'s telemetry (in the order of the set-ups).
    pub fn telemetry(&self, i: usize) -> Option<&AxisTelemetry> {
        self.axes.get(i).map(MotionAxis::telemetry)
    }

    /// Axis `i`'s motion axis (its states, modes and latches so far).
    pub fn axis(&self, i: usize) -> Option<&MotionAxis> {
        self.axes.get(i)
    }

    /// The node of axis `i`, with its drive's name.
    pub fn node(&self, i: usize) -> Option<NodeRef> {
        self.nodes.get(i).map(|n| self.master.node_ref(*n))
    }

    /// The master (its drives, nodes, EMCY records and events).
    pub fn master(&self) -> &Master<T> {
        &self.master
    }

    /// The master, for SDO transfers and NMT between cycles.
    pub fn master_mut(&mut self) -> &mut Master<T> {
        &mut self.master
    }

    /// The master back, the axes dropped.
    pub fn into_master(self) -> Master<T> {
        self.master
    }
}
