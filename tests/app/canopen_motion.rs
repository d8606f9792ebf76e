//! The three CANopen drives on the motion runtime the EtherCAT master runs too
//! (`ecdrive::canopen::MotionSession`): one program per drive — home, a pp move, pv, and tq
//! where the drive's firmware has it — run through the same `MotionAxis` step as an EtherCAT
//! axis, over the in-process virtual bus against the emulated nodes. What the program reached
//! is read from the emulated node itself (its reported position, velocity and torque), not
//! from the master's telemetry. Simulated time: no wall clock enters.

use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig};
use ecdrive::canopen::motion::{MotionSession, axis_setup};
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::cia402::{OperationMode, State};
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::master::{Axes, Command, EventKind, RunMode, Step};
use ecdrive::od::{ObjectAddress, Value};
use ecdrive::sim::canopen::{EmulatedNode, SimBus};

/// What one drive's program showed, read from the emulated node at each step's end.
#[derive(Debug, Default)]
struct Seen {
    /// Position when each step ended (step index → position).
    at_step_end: Vec<(u16, i32)>,
    /// Largest |velocity| (position units/s) during the pv step and |torque| (‰) during the
    /// tq step.
    max_velocity: f64,
    max_torque: f64,
    faults: Vec<String>,
    refused: Vec<&'static str>,
    done: bool,
}

/// The program's pv and tq steps (home, pp, mode, pv, mode, tq, mode).
const PV_STEP: u16 = 3;
const TQ_STEP: u16 = 5;

fn run(node: u8, p: &'static CanDriveProfile) -> (Seen, f64, f64) {
    let mut bus = SimBus::new();
    bus.add_node(
        EmulatedNode::new(
            ecdrive_cli::app::canopen::tools::emulation_of(p)
                .expect("the software slave emulates the drive"),
            node,
        )
        .expect("emulated node"),
    );
    let mut m = Master::new(bus, MasterConfig::default());
    let mut setup = DriveSetup::new(p);
    setup.settings = ecdrive_cli::app::canopen::steps::motion_settings(p, 10.0, 100.0);
    let method = ecdrive_cli::app::canopen::steps::demo_homing_method(p);
    setup
        .settings
        .push((ObjectAddress::new(0x6098, 0), Value::Int(method.into())));
    m.configure_drive(node, setup).expect("configure");
    m.start(node).expect("NMT start");
    let u = &p.units;
    let rev = u.position_per_rev;
    // 5 rev/s in pv; 30 % torque in tq (the drives' torque unit is ‰).
    let velocity = 5.0 * rev;
    let torque = 300.0;
    // The profile values are the settings above (10 rev/s, 100 rev/s², the demo's homing
    // speeds), written at configuration; the steps say the same.
    let mut program = vec![
        Step::Home {
            method,
            speed_switch: ecdrive_cli::app::canopen::steps::defaults::HOMING_FAST_REV_S * rev,
            speed_zero: ecdrive_cli::app::canopen::steps::defaults::HOMING_SLOW_REV_S * rev,
            acceleration: None,
            offset: None,
        },
        Step::Pp {
            targets: vec![rev, rev / 2.0],
            relative: false,
            immediate: false,
            velocity: 10.0 * rev,
            acceleration: 100.0 * rev,
            deceleration: None,
        },
        Step::Mode { mode: RunMode::Pv },
        Step::Pv {
            velocity,
            acceleration: 100.0 * rev,
            deceleration: None,
            seconds: 0.2,
        },
    ];
    if p.supports(OperationMode::ProfileTorque) {
        program.push(Step::Mode { mode: RunMode::Tq });
        program.push(Step::Tq {
            torque,
            slope: None,
            seconds: 0.2,
        });
    }
    program.push(Step::Mode { mode: RunMode::Pp });
    let mut s =
        MotionSession::new(m, &[(node, axis_setup(p, program, RunMode::Pp))]).expect("session");
    s.command(Command::Enable(Axes::All));
    s.command(Command::RunProgram(Axes::All));
    let mut seen = Seen::default();
    let mut step = 0u16;
    for _ in 0..200_000 {
        s.cycle().expect("cycle");
        let n = s.master().transport().node(node).expect("node");
        let t = s.telemetry(0).expect("axis 0");
        match t.program_step {
            PV_STEP => seen.max_velocity = seen.max_velocity.max(n.velocity_units_per_s().abs()),
            TQ_STEP => seen.max_torque = seen.max_torque.max(n.torque().abs()),
            _ => {}
        }
        if t.program_step != step {
            seen.at_step_end.push((step, n.position()));
            step = t.program_step;
        }
        for e in s.take_events() {
            match e.kind {
                EventKind::ProgramDone { .. } => seen.done = true,
                EventKind::CommandRefused { why, .. } => seen.refused.push(why),
                EventKind::Axis {
                    event: ecdrive::cia402::Event::Fault { .. },
                    ..
                } => seen.faults.push(format!("{e:?}")),
                EventKind::HomingFailed { .. } => seen.faults.push(format!("{e:?}")),
                _ => {}
            }
        }
        if seen.done || !seen.faults.is_empty() || !seen.refused.is_empty() {
            break;
        }
    }
    // Disable through the runtime, then the node must show it.
    s.command(Command::Disable(Axes::All));
    for _ in 0..2_000 {
        s.cycle().expect("cycle");
        if s.master().transport().node(node).expect("node").state() == State::SwitchOnDisabled {
            break;
        }
    }
    assert_eq!(
        s.master().transport().node(node).expect("node").state(),
        State::SwitchOnDisabled,
        "{}: the runtime's disable reached the drive",
        p.name
    );
    (seen, velocity, torque)
}

#[test]
fn each_canopen_drive_runs_a_program_on_the_motion_runtime() {
    let drives: [(u8, &'static CanDriveProfile); 3] = [
        (blv_r::EMU_NODE_ID, &blv_r::PROFILE),
        (0x7F, &asda_a2::PROFILE),
        (0x41, &lexium_mdrive::PROFILE),
    ];
    for (node, p) in drives {
        let (seen, velocity, torque) = run(node, p);
        let name = p.name;
        eprintln!("{name}: {seen:?}");
        assert!(seen.faults.is_empty(), "{name}: {:?}", seen.faults);
        assert!(seen.refused.is_empty(), "{name}: {:?}", seen.refused);
        assert!(seen.done, "{name}: the program did not finish: {seen:?}");
        let rev = p.units.position_per_rev;
        let end = |i: u16| {
            seen.at_step_end
                .iter()
                .find(|(s, _)| *s == i)
                .map(|(_, p)| *p)
                .unwrap_or_else(|| panic!("{name}: step {i} never ended: {seen:?}"))
        };
        // The home step (method 19/24, home offset 0) defines position 0 at the home.
        assert!(end(0).abs() <= 1, "{name}: after homing at {}", end(0));
        // The pp step ends at its last target.
        assert_eq!(f64::from(end(1)), (rev / 2.0).round(), "{name}: pp");
        // pv reached its velocity; tq its torque where the drive has tq.
        assert!(
            (seen.max_velocity - velocity).abs() <= 0.02 * velocity,
            "{name}: pv peaked at {} units/s, not {velocity}",
            seen.max_velocity
        );
        if p.supports(OperationMode::ProfileTorque) {
            assert!(
                (seen.max_torque - torque).abs() <= 0.02 * torque,
                "{name}: tq peaked at {} ‰, not {torque}",
                seen.max_torque
            );
        }
    }
}

/// A BLV-R whose remote input keeps statusword bit 9 at 0 ignores the controlword: a motion
/// session reports it (`MasterEvent::RemoteOff`, watched on the outputs the session sends) and
/// the drive never leaves Switch on disabled, whatever the runtime asks.
#[test]
fn the_remote_gate_is_reported_in_a_motion_session() {
    let p = &blv_r::PROFILE;
    let node = blv_r::EMU_NODE_ID;
    let mut bus = SimBus::new();
    bus.add_node(
        EmulatedNode::new(
            ecdrive_cli::app::canopen::tools::emulation_of(p)
                .expect("the software slave emulates the drive"),
            node,
        )
        .expect("emulated node"),
    );
    let mut m = Master::new(bus, MasterConfig::default());
    m.configure_drive(node, DriveSetup::new(p))
        .expect("configure");
    m.start(node).expect("NMT start");
    m.transport_mut()
        .node_mut(node)
        .expect("node")
        .set_remote(false);
    let mut s =
        MotionSession::new(m, &[(node, axis_setup(p, Vec::new(), RunMode::Pp))]).expect("session");
    s.command(Command::Enable(Axes::All));
    let mut reported = false;
    for _ in 0..500 {
        s.cycle().expect("cycle");
        while let Some(e) = s.master_mut().poll_event() {
            reported |= matches!(e, ecdrive::canopen::MasterEvent::RemoteOff { .. });
        }
        if reported {
            break;
        }
    }
    assert!(reported, "no RemoteOff within 500 cycles");
    assert!(s.master().remote_off(node));
    assert_ne!(
        s.master().transport().node(node).expect("node").state(),
        State::OperationEnabled
    );
}

/// What a callback asks of axis 0 in one cycle.
struct Asks(ecdrive::motion::Requests);

impl ecdrive::CycleApp for Asks {
    fn cycle(&mut self, c: &mut ecdrive::AppCycle<'_>) {
        let Some(a) = c.axis(0) else { return };
        if let Some(m) = self.0.mode {
            a.request_mode(m);
        }
        if let Some(v) = self.0.setpoint {
            a.set_target(v);
        }
        if let Some((t, relative, immediate)) = self.0.pp {
            a.request_pp(t, relative, immediate);
        }
    }
}

/// The application's side of the runtime on CANopen, cycle by cycle in simulated time: a
/// callback ([`MotionSession::cycle_app`]) asks each drive, with no program, for pv and streams its velocity set-point (a ramp to
/// 2 rev/s and back to 0, one value a cycle), then for pp and a target. What the emulated node
/// did is read from the node: its velocity followed the stream, its position ends at the
/// target.
#[test]
fn each_canopen_drive_takes_a_callbacks_requests_and_stream() {
    use ecdrive::motion::Requests;
    let drives: [(u8, &'static CanDriveProfile); 3] = [
        (blv_r::EMU_NODE_ID, &blv_r::PROFILE),
        (0x7F, &asda_a2::PROFILE),
        (0x41, &lexium_mdrive::PROFILE),
    ];
    for (node, p) in drives {
        let name = p.name;
        let mut bus = SimBus::new();
        bus.add_node(
            EmulatedNode::new(
                ecdrive_cli::app::canopen::tools::emulation_of(p)
                    .expect("the software slave emulates the drive"),
                node,
            )
            .expect("emulated node"),
        );
        let mut m = Master::new(bus, MasterConfig::default());
        let mut setup = DriveSetup::new(p);
        setup.settings = ecdrive_cli::app::canopen::steps::motion_settings(p, 10.0, 100.0);
        m.configure_drive(node, setup).expect("configure");
        m.start(node).expect("NMT start");
        let mut s = MotionSession::new(m, &[(node, axis_setup(p, Vec::new(), RunMode::Pp))])
            .expect("session");
        s.command(Command::Enable(Axes::All));
        for _ in 0..500 {
            s.cycle().expect("cycle");
            if s.telemetry(0)
                .is_some_and(|t| t.state == Some(State::OperationEnabled))
            {
                break;
            }
        }
        let rev = p.units.position_per_rev;
        let peak = 2.0 * rev;
        // The stream: up over 100 cycles, hold 100, down over 100 (counts/s).
        let stream = |k: usize| -> f64 {
            let k = k as f64;
            if k < 100.0 {
                peak * k / 100.0
            } else if k < 200.0 {
                peak
            } else {
                (peak * (300.0 - k) / 100.0).max(0.0)
            }
        };
        let mut k = 0usize;
        let mut max_v: f64 = 0.0;
        let mut phase = 0; // 0: to pv, 1: streaming, 2: to pp, 3: pp target, 4: done
        let target = 3.0 * rev;
        for _ in 0..20_000 {
            let mode_now = s.telemetry(0).map_or(0, |t| t.mode_display);
            let req = match phase {
                0 => Requests {
                    mode: Some(RunMode::Pv),
                    ..Requests::default()
                },
                1 => Requests {
                    setpoint: Some(stream(k)),
                    ..Requests::default()
                },
                2 => Requests {
                    mode: Some(RunMode::Pp),
                    ..Requests::default()
                },
                3 => Requests {
                    pp: Some((target, false, false)),
                    ..Requests::default()
                },
                _ => Requests::default(),
            };
            s.cycle_app(&mut Asks(req)).expect("cycle");
            let n = s.master().transport().node(node).expect("node");
            if phase == 1 {
                max_v = max_v.max(n.velocity_units_per_s().abs());
            }
            let t = *s.telemetry(0).expect("axis");
            phase = match phase {
                0 if mode_now == 3 => 1,
                1 => {
                    k += 1;
                    if k > 320 { 2 } else { 1 }
                }
                2 if mode_now == 1 => 3,
                3 => 4,
                4 if t.task == ecdrive::master::DriveTask::TargetReached => 5,
                p => p,
            };
            if phase == 5 {
                break;
            }
        }
        assert_eq!(
            phase,
            5,
            "{name}: stuck in phase {phase}: {:?}",
            s.take_events()
        );
        assert!(
            (max_v - peak).abs() <= 0.02 * peak,
            "{name}: the stream peaked at {peak} counts/s, the drive at {max_v}"
        );
        let n = s.master().transport().node(node).expect("node");
        assert_eq!(f64::from(n.position()), target.round(), "{name}: pp target");
    }
}
