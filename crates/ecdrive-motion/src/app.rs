//! Application code in the cycle: a [`CycleApp`] the cycle thread calls once per cycle, after
//! the inputs of the frame just exchanged are read and before the axes' outputs are computed,
//! with typed access to every axis ([`AppAxis`]).
//!
//! The CiA 402 engine stays in charge: a set-point reaches a drive only in Operation enabled
//! and while no program runs on the axis; it is checked against the axis's
//! [`SetpointLimits`] first (a violation stops the axis with a ramp and names the limit); a
//! mode request goes through the engine's switch without a jump. Other mapped entries are read
//! and written by object address, resolved at start-up; entries the engine drives
//! (controlword, mode, targets, the cycle counter) cannot be written.
//!
//! Everything here is allocation-free per cycle: the views are built once per run.

pub use crate::SetpointLimits;
use crate::cia402::State;
use crate::program::{ProbeEdge, RunMode};
use crate::telemetry::{AxisTelemetry, DriveTask, EventKind, ProbeState};
use crate::{MotionAxis, Requests};
use ecdrive_core::od::ObjectAddress;
use ecdrive_core::pdo::{Direction, Field, Layout};

/// Application code called by the cycle thread once per cycle. It must not block, sleep,
/// allocate or make syscalls: the cycle audit holds it to the same rules as the cycle.
pub trait CycleApp: Send {
    /// One cycle: read the axes, set set-points, request modes, write mapped entries.
    fn cycle(&mut self, c: &mut AppCycle<'_>);
}

/// Why a write to a mapped entry was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EntryError {
    /// The entry is not in the axis's process image.
    #[error("{0} is not mapped on this axis")]
    NotMapped(ObjectAddress),
    /// The entry is an input (drive → master).
    #[error("{0} is an input")]
    Input(ObjectAddress),
    /// The CiA 402 engine drives the entry (controlword, mode, targets, cycle counter).
    #[error("{0} is driven by the CiA 402 engine")]
    Engine(ObjectAddress),
    /// More writes this cycle than the axis has free outputs.
    #[error("too many writes this cycle")]
    TooMany,
}

/// One mapped entry of an axis, resolved at start-up.
#[derive(Debug, Clone, Copy)]
struct Entry {
    address: ObjectAddress,
    field: Field,
    direction: Direction,
    engine: bool,
}

/// One axis as the application sees it in a cycle: the inputs just read, and what the
/// application asks of it.
#[derive(Debug)]
pub struct AppAxis {
    tel: AxisTelemetry,
    enabled: bool,
    program_running: bool,
    in_op: bool,
    inputs: Vec<u8>,
    outputs: Vec<u8>,
    entries: Vec<Entry>,
    setpoint: Option<f64>,
    mode_request: Option<RunMode>,
    writes: Vec<(Field, u64)>,
    home_request: Option<i8>,
    pp_request: Option<(f64, bool, bool)>,
    probe_request: Option<(u8, ProbeEdge)>,
}

impl AppAxis {
    /// The view of an axis whose process image is `layout` (the master builds it at set-up:
    /// allocations allowed). `engine` says which entries the engine drives, `signed` which
    /// hold a signed type.
    pub fn new(
        layout: &Layout,
        engine: &dyn Fn(ObjectAddress) -> bool,
        signed: &dyn Fn(ObjectAddress) -> bool,
    ) -> Self {
        let mut entries = Vec::new();
        for direction in [Direction::Rx, Direction::Tx] {
            for e in layout.image(direction).iter().filter(|e| !e.is_padding()) {
                let Ok(field) = e.field(signed(e.address())) else {
                    continue;
                };
                entries.push(Entry {
                    address: e.address(),
                    field,
                    direction,
                    engine: direction == Direction::Rx && engine(e.address()),
                });
            }
        }
        let free = entries
            .iter()
            .filter(|e| e.direction == Direction::Rx && !e.engine)
            .count();
        Self {
            tel: AxisTelemetry::default(),
            enabled: false,
            program_running: false,
            in_op: false,
            inputs: vec![0; layout.bytes(Direction::Tx)],
            outputs: vec![0; layout.bytes(Direction::Rx)],
            entries,
            setpoint: None,
            mode_request: None,
            writes: Vec::with_capacity(free),
            home_request: None,
            pp_request: None,
            probe_request: None,
        }
    }

    /// Everything the cycle knows of the axis (inputs of this cycle; demand and following
    /// error as computed in the last one).
    pub fn telemetry(&self) -> &AxisTelemetry {
        &self.tel
    }
    /// The CiA 402 state (`None` below OP or before the first statusword).
    pub fn state(&self) -> Option<State> {
        self.tel.state
    }
    /// In Operation enabled and taking set-points: a set-point now reaches the drive.
    pub fn enabled(&self) -> bool {
        self.enabled
    }
    /// The drive is in OP (its inputs are valid).
    pub fn in_op(&self) -> bool {
        self.in_op
    }
    /// A program of the configuration runs on the axis: its set-points win over the
    /// application's.
    pub fn program_running(&self) -> bool {
        self.program_running
    }
    /// The mode the drive displays (0x6061), if a program or the application can run in it.
    pub fn mode(&self) -> Option<RunMode> {
        RunMode::from_code(self.tel.mode_display)
    }
    /// Actual position, counts (unwrapped).
    pub fn position(&self) -> i64 {
        self.tel.position_actual
    }
    /// Actual velocity, the drive's velocity unit (0x606C).
    pub fn velocity(&self) -> i32 {
        self.tel.velocity_actual
    }
    /// Actual torque, the drive's torque unit (0x6077).
    pub fn torque(&self) -> i16 {
        self.tel.torque_actual
    }
    /// Following error as the master computes it (demand − actual), counts.
    pub fn following_error(&self) -> i64 {
        self.tel.following_error
    }
    /// The drive's error code (0x603F).
    pub fn error_code(&self) -> u16 {
        self.tel.error_code
    }
    /// Digital inputs (0x60FD), when mapped.
    pub fn digital_inputs(&self) -> Option<u32> {
        self.read(ObjectAddress::new(0x60FD, 0))
            .and_then(|v| u32::try_from(v).ok())
    }
    /// Touch probe status (0x60B9), when mapped.
    pub fn touch_probe_status(&self) -> Option<u16> {
        self.read(ObjectAddress::new(0x60B9, 0))
            .and_then(|v| u16::try_from(v).ok())
    }
    /// Touch probe 1 position on the positive edge (0x60BA), when mapped.
    pub fn touch_probe_position(&self) -> Option<i32> {
        self.read(ObjectAddress::new(0x60BA, 0))
            .and_then(|v| i32::try_from(v).ok())
    }

    /// A mapped entry's value (inputs as read this cycle, outputs as last written), sign
    /// extended by its data type; `None` when not mapped.
    pub fn read(&self, address: ObjectAddress) -> Option<i64> {
        let e = self.entries.iter().find(|e| e.address == address)?;
        let image = match e.direction {
            Direction::Tx => &self.inputs,
            Direction::Rx => &self.outputs,
        };
        e.field
            .read_int(image)
            .ok()
            .and_then(|v| i64::try_from(v).ok())
    }

    /// Write a mapped output the engine does not drive; it goes out with this cycle's outputs
    /// and stays until written again.
    pub fn write(&mut self, address: ObjectAddress, value: i64) -> Result<(), EntryError> {
        let e = self
            .entries
            .iter()
            .find(|e| e.address == address)
            .ok_or(EntryError::NotMapped(address))?;
        if e.direction == Direction::Tx {
            return Err(EntryError::Input(address));
        }
        if e.engine {
            return Err(EntryError::Engine(address));
        }
        if self.writes.len() == self.writes.capacity() {
            return Err(EntryError::TooMany);
        }
        let bits = e.field.bits();
        let raw = if bits >= 64 {
            value as u64
        } else {
            (value as u64) & ((1u64 << bits) - 1)
        };
        self.writes.push((e.field, raw));
        Ok(())
    }

    /// This cycle's set-point in the active mode (csp: position, counts; csv and pv:
    /// velocity, position units per second; cst and tq: torque, the drive's unit; in pv and tq
    /// the drive ramps to it with its profile objects, and it stays until set again). It is
    /// taken only in Operation enabled with no program running, within the axis's
    /// [`SetpointLimits`]. In pp targets go through [`AppAxis::request_pp`].
    pub fn set_target(&mut self, value: f64) {
        self.setpoint = Some(value);
    }

    /// Home the axis: hm with the method the drive holds in 0x6098 (written at start-up: a
    /// `sdos` value, or a program's home step), then back to the mode it was in, as a program's
    /// `home` step does; `method` names it in reports. Taken in Operation enabled with no
    /// program and no homing running; follow it with [`AppAxis::task`].
    pub fn request_home(&mut self, method: i8) {
        self.home_request = Some(method);
    }

    /// Hand a pp target (counts) to the drive with the new-set-point handshake: `relative`
    /// (controlword bit 6) to the last target, `immediate` (bit 5 = 1) replacing the running
    /// move, else queued behind it. Taken in pp, in Operation enabled with no program running;
    /// follow it with [`AppAxis::task`].
    pub fn request_pp(&mut self, target: f64, relative: bool, immediate: bool) {
        self.pp_request = Some((target, relative, immediate));
    }

    /// Arm touch probe `probe` (1 or 2) on `edge` (0x60B8): the drive latches the position at
    /// the next such edge of its probe input; armed again, it latches again. Taken in OP with
    /// no program running, when the mapping carries 0x60B8, 0x60B9 and the probe's position
    /// object (on EtherCAT a `DriveSetup`'s `probes` maps them); else refused with an
    /// event. Follow it with [`AppAxis::probe`].
    pub fn arm_probe(&mut self, probe: u8, edge: ProbeEdge) {
        self.probe_request = Some((probe, edge));
    }

    /// Touch probe `probe` (1 or 2): off, armed, or latched with its position; `Off` for
    /// another number.
    pub fn probe(&self, probe: u8) -> ProbeState {
        self.tel
            .probes
            .get(usize::from(probe).wrapping_sub(1))
            .copied()
            .unwrap_or_default()
    }

    /// Where the homing or pp move the application started stands.
    pub fn task(&self) -> DriveTask {
        self.tel.task
    }

    /// Ask for a switch to `mode` (the engine switches without a jump).
    pub fn request_mode(&mut self, mode: RunMode) {
        self.mode_request = Some(mode);
    }

    /// The master's side, before the application: clear last cycle's requests and bring the
    /// view up to date with axis `m` and this cycle's images (`in_op`: the drive's inputs are
    /// valid). Allocation-free.
    pub fn refresh(&mut self, m: &MotionAxis, in_op: bool, inputs: &[u8], outputs: &[u8]) {
        self.setpoint = None;
        self.mode_request = None;
        self.writes.clear();
        self.home_request = None;
        self.pp_request = None;
        self.probe_request = None;
        self.in_op = in_op;
        if !in_op {
            self.enabled = false;
            return;
        }
        self.tel = *m.telemetry();
        let st = m.status();
        self.tel.state = st.state;
        self.enabled = st.state == Some(State::OperationEnabled) && st.streaming;
        self.program_running = m.program_running();
        let n = self.inputs.len().min(inputs.len());
        self.inputs[..n].copy_from_slice(&inputs[..n]);
        let n = self.outputs.len().min(outputs.len());
        self.outputs[..n].copy_from_slice(&outputs[..n]);
    }

    /// The master's side, after the application: what it asked of the axis this cycle, for
    /// [`MotionAxis::step`].
    pub fn requests(&self) -> Requests {
        Requests {
            setpoint: self.setpoint,
            mode: self.mode_request,
            home: self.home_request,
            pp: self.pp_request,
            probe: self.probe_request,
        }
    }

    /// The master's side, after the step: the application's writes to mapped outputs this
    /// cycle (field, raw value), to put into the output image after the engine's.
    pub fn writes(&self) -> &[(Field, u64)] {
        &self.writes
    }
}

/// What the application gets each cycle.
pub struct AppCycle<'a> {
    cycle: u64,
    dt: f64,
    dc_time_ns: u64,
    axes: &'a mut [AppAxis],
    events: &'a mut dyn FnMut(EventKind),
}

impl<'a> AppCycle<'a> {
    /// The master's side: cycle `cycle` of period `dt` seconds at the bus's time
    /// `bus_time_ns` (EtherCAT: the DC system time; CANopen: the transport's clock), with the
    /// axes' views and where the application's events go.
    pub fn new(
        cycle: u64,
        dt: f64,
        bus_time_ns: u64,
        axes: &'a mut [AppAxis],
        events: &'a mut dyn FnMut(EventKind),
    ) -> Self {
        Self {
            cycle,
            dt,
            dc_time_ns: bus_time_ns,
            axes,
            events,
        }
    }

    /// The cycle number.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }
    /// The cycle time, seconds.
    pub fn period(&self) -> f64 {
        self.dt
    }
    /// Time since the cycle began, seconds (cycle number × period).
    pub fn time(&self) -> f64 {
        self.cycle as f64 * self.dt
    }
    /// The bus's time of this cycle, ns: on EtherCAT the DC system time of this cycle's frame
    /// (the reference clock's; 0 before it first answered), on CANopen the transport's clock
    /// when the SYNC went out. A cycle that wakes a whole period late still counts one cycle, but the DC
    /// time moves on: a trajectory computed from it stays with the drives' SYNC0 instants.
    pub fn dc_time_ns(&self) -> u64 {
        self.dc_time_ns
    }
    /// The axes, in configuration order.
    pub fn axes(&mut self) -> &mut [AppAxis] {
        self.axes
    }
    /// Axis `i`.
    pub fn axis(&mut self, i: usize) -> Option<&mut AppAxis> {
        self.axes.get_mut(i)
    }
    /// Report something in the event stream (and so the run's history).
    pub fn emit(&mut self, kind: EventKind) {
        (self.events)(kind);
    }
}
