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
//! `tests/canopen_motion.rs`: configure and start the drive with the [`Master`], build the
//! session with [`axis_setup`] and a program, send [`Command::Enable`] and
//! [`Command::RunProgram`], and call [`MotionSession::cycle`] until the program's
//! [`EventKind::ProgramDone`].

use crate::error::{CanError, CanErrorKind, NodeRef};
use crate::master::Master;
use crate::profile::CanDriveProfile;
use crate::transport::CanTransport;
use ecdrive_motion::program::{RunMode, Step};
use ecdrive_motion::telemetry::{AxisTelemetry, Command, Event, EventKind, StopKind};
use ecdrive_motion::{
    AxisSetup, EventSink, Inputs, MotionAxis, ProbeObjects, Requests, SetpointLimits, StepContext,
};
use std::time::Duration;

/// **\[REC\]** A controlled stop's ramp: 0.2 s (as the EtherCAT master's default).
pub const STOP_RAMP: Duration = Duration::from_millis(200);

/// **\[REC\]** A controlled stop that has not ended after 2 s disables regardless.
pub const STOP_TIMEOUT: Duration = Duration::from_secs(2);

/// What the runtime needs of a CANopen drive from its profile, with a program to run from
/// `mode`: its capabilities and velocity unit; no following-error limit, no set-point limits
/// and no touch probe (set them on the result).
pub fn axis_setup(profile: &CanDriveProfile, program: Vec<Step>, mode: RunMode) -> AxisSetup {
    AxisSetup {
        caps: profile.caps,
        velocity_unit: profile.units.velocity_position_per_s(),
        program,
        mode,
        following_error_limit: None,
        limits: SetpointLimits::default(),
        probe_objects: ProbeObjects::default(),
    }
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
    events: Vec<Event>,
    /// Cycles so far, and those in which every drive had fed back (the programs' clock).
    cycle: u64,
    tick: u64,
    dt: f64,
    stop_ramp_cycles: u64,
    stop_timeout_cycles: u64,
}

impl<T: CanTransport> MotionSession<T> {
    /// The session of `master` with one motion axis per `(node, setup)`: every node must be a
    /// drive the master configured. An error names the node and why.
    pub fn new(master: Master<T>, axes: &[(u8, AxisSetup)]) -> Result<Self, CanError> {
        let cycle_us = master.config().cycle_us.max(1);
        let cycle = Duration::from_micros(cycle_us);
        let mut nodes = Vec::with_capacity(axes.len());
        let mut built = Vec::with_capacity(axes.len());
        for (node, setup) in axes {
            let why = |what: &str| {
                CanError::new(
                    master.node_ref(*node),
                    None,
                    CanErrorKind::NotReady(what.into()),
                )
            };
            if master.drive(*node).is_none() {
                return Err(why("not a configured drive"));
            }
            let a = MotionAxis::new(setup, cycle)
                .ok_or_else(|| why("the drive's capabilities give no axis for this cycle"))?;
            nodes.push(*node);
            built.push(a);
        }
        let cycles = |d: Duration| (d.as_micros() as u64).div_ceil(cycle_us).max(1);
        Ok(Self {
            master,
            nodes,
            axes: built,
            events: Vec::new(),
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

    /// One cycle with no requests of an application: [`MotionSession::cycle_with`].
    pub fn cycle(&mut self) -> Result<(), CanError> {
        self.cycle_with(|_, _| Requests::default())
    }

    /// One cycle: the bus's ([`Master::cycle`]), then for each drive with feedback the
    /// runtime's step with what `requests` asks of axis `i` (given its telemetry), its outputs
    /// into the RPDO image; then the stops supervised (a drive that faulted stops the others).
    pub fn cycle_with(
        &mut self,
        mut requests: impl FnMut(usize, &AxisTelemetry) -> Requests,
    ) -> Result<(), CanError> {
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
        let mut sink = Sink {
            events: &mut self.events,
            cycle: self.cycle,
            time_us: self.master.now_us(),
        };
        for (i, (node, a)) in self.nodes.iter().zip(self.axes.iter_mut()).enumerate() {
            let Some(d) = self.master.drive_mut(*node) else {
                continue;
            };
            if !d.has_feedback() {
                continue;
            }
            let inputs = Inputs {
                feedback: d.feedback(),
                probe_status: 0,
                probe_positions: [0; 4],
                following_error_drive: d.binding().following_error(d.tx_image()),
            };
            let fb = a.read(&inputs, ctx.pulse);
            let req = requests(i, a.telemetry());
            let out = a.step(i, fb, &ctx, &mut sink, req);
            d.write_output(&out);
        }
        self.supervise();
        Ok(())
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
