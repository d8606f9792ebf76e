//! Each drive's side of the process image: its fields, cycle counter and AL state around its
//! axis of the motion runtime, and the application's view of it.

use super::*;

/// One drive on the segment: its place in the process image, what the bus side remembers of
/// it, and its axis of the motion runtime.
pub(super) struct CycleDrive {
    /// Position on the segment (index in the group).
    pub(super) sub: usize,
    pub(super) fields: DriveFields,
    pub(super) counter: u8,
    pub(super) al_state: u8,
    /// This cycle's inputs, read before the application runs.
    pub(super) fb: Option<Feedback>,
    pub(super) m: MotionAxis,
}

/// The drive's capabilities as this run has them: where a setting of the drive selects the
/// usable modes (the MR-J4-TM's [Pr. PA01]), only the modes of the setting start-up found
/// allowing the program's (so the engine never brakes in a mode the drive refuses now).
fn caps_now(d: &ConfiguredDrive) -> crate::cia402::DriveCaps {
    let mut caps = d.profile.caps;
    if let Some(sel) = &d.profile.bus.mode_selector
        && let Some(g) = sel.group_for(&crate::program::modes_used(&d.setup.program, d.setup.mode))
    {
        caps.supported_modes = caps.supported_modes.restricted_to(g.modes);
    }
    caps
}

impl CycleDrive {
    /// The axis of drive `d` (set-up: allocations allowed), or `None` if its engine cannot be
    /// built.
    pub(super) fn new(d: &ConfiguredDrive, cycle: Duration) -> Option<Self> {
        let pf = &d.fields.probe;
        let setup = AxisSetup {
            caps: caps_now(d),
            velocity_unit: d.profile.units.velocity_position_per_s(),
            position_per_rev: d.profile.units.position_per_rev,
            program: d.setup.program.clone(),
            mode: d.setup.mode,
            following_error_limit: d.setup.following_error_limit,
            limits: d.setup.limits,
            probe_objects: ProbeObjects {
                function: pf.function.is_some(),
                status: pf.status.is_some(),
                positions: pf.positions.map(|p| p.is_some()),
            },
            // CiA 402: the drive interpolates with controlword bit 4 set.
            ip_enable_bit: true,
        };
        Some(Self {
            sub: usize::from(d.info.position),
            fields: d.fields.clone(),
            counter: 0,
            al_state: 0,
            fb: None,
            m: MotionAxis::new(&setup, cycle)?,
        })
    }

    /// Outputs that carry fixed values from the first cycle on, and Disable voltage.
    pub(super) fn initial_outputs(&self, out: &mut [u8]) {
        for (f, v) in &self.fields.held_outputs {
            let _ = f.write_raw(out, *v);
        }
        for (f, v) in &self.fields.output_defaults {
            pdo::axis::write(Some(*f), out, *v);
        }
        self.fields.axis.write_disable_voltage(out);
    }

    /// Advance the drive's cycle counter (if mapped) in `out`: one per cycle, as the drive
    /// expects, also on a cycle whose outputs are otherwise unchanged.
    pub(super) fn count(&mut self, out: &mut [u8]) {
        if let Some((c, _)) = &self.fields.counter {
            self.counter = self.counter.wrapping_add(1);
            pdo::axis::write(Some(*c), out, i64::from(self.counter));
        }
    }

    /// Below OP nothing of the drive is judged: a slave may serve stale inputs until OP (a mode
    /// display of 0, a statusword of 0), and it should not act on the outputs. They stay safe
    /// all the same, for a slave that does: Disable voltage.
    pub(super) fn below_op(&mut self, out: &mut [u8]) {
        self.fields.axis.write_disable_voltage(out);
        self.count(out);
        self.m.below_op();
        self.m.telemetry_mut().al_state = self.al_state;
    }

    /// Read this cycle's inputs from the process image into the motion axis.
    pub(super) fn read_inputs(&mut self, inputs: &[u8], pulse: u64) -> Feedback {
        let pf = &self.fields.probe;
        let b = &self.fields.axis;
        let [status, p0, p1, p2, p3, fe] = pdo::axis::read_each(
            inputs,
            [
                pf.status,
                pf.positions[0],
                pf.positions[1],
                pf.positions[2],
                pf.positions[3],
                b.following_error,
            ],
        );
        let read = Inputs {
            feedback: b.feedback(inputs),
            probe_status: status.unwrap_or(0) as u16,
            probe_positions: [p0, p1, p2, p3].map(|p| p.unwrap_or(0) as i32),
            following_error_drive: fe,
        };
        self.m.read(&read, pulse)
    }

    /// The engine's outputs into the process image, and the cycle counter.
    pub(super) fn write_outputs(&mut self, out: &Output, image: &mut [u8]) {
        self.fields.axis.write(out, image);
        if let Some(f) = self.m.probe_function() {
            pdo::axis::write(self.fields.probe.function, image, i64::from(f));
        }
        self.count(image);
        self.m.telemetry_mut().al_state = self.al_state;
    }
}

/// The application's view of drive `d` (set-up): every mapped entry, the ones the engine
/// drives marked.
pub(super) fn app_view(d: &ConfiguredDrive) -> AppAxis {
    let b = &d.fields.axis;
    let mut engine: Vec<usize> = [
        b.controlword,
        b.mode,
        b.target_position,
        b.target_velocity,
        b.target_torque,
        b.velocity_offset,
        b.torque_offset,
        b.ip_position,
    ]
    .into_iter()
    .flatten()
    .map(|f| f.bit_position())
    .collect();
    if let Some((c, _)) = &d.fields.counter {
        engine.push(c.bit_position());
    }
    let rx = d.layout.image(pdo::Direction::Rx);
    let is_engine =
        |a: crate::od::ObjectAddress| rx.find(a).is_some_and(|e| engine.contains(&e.bit_position));
    let dict = crate::od::Dictionary::new(d.profile.dictionary);
    let signed = |a: crate::od::ObjectAddress| dict.data_type(a).is_some_and(|t| t.is_signed());
    AppAxis::new(&d.layout, &is_engine, &signed)
}
