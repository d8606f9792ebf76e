//! Your code in the CANopen cycle: the BLV-R, the ASDA-A2 and the Lexium MDrive (emulated,
//! in-process) on one bus, driven by a `CycleApp` on the session's own cycle thread — the
//! application API of the EtherCAT master (`custom_cycle`, `stream_setpoints`), on CANopen.
//!
//! ```text
//! cargo run --release --example canopen_custom_cycle [-- SECONDS [INTERFACE]]
//! ```
//!
//! The callback homes each drive (`request_home`, the method its manual lists), hands it a pp
//! target of one revolution (`request_pp`) and switches it to pv (`request_mode`); then this
//! thread streams a velocity profile to every axis through `Streams` (up to 2 rev/s, hold, down
//! to 0 over SECONDS, 1.0 by default), one set-point per SYNC, and the session stops with a
//! ramp. With an INTERFACE (`can0`, or `vbus:PATH` served by
//! `ecdrive sim --can vbus:PATH --node blv-r@3 --node asda-a2 --node lexium-mdrive`) the same
//! code drives the drives there.

use ecdrive::canopen::can_socket::SocketCanTransport;
use ecdrive::canopen::master::{DriveSetup, MasterConfig};
use ecdrive::canopen::motion::{
    CycleThread, MotionSession, ProfileSpeeds, SessionDrive, axis_setup, profile_settings,
};
use ecdrive::canopen::nmt::NmtCommand;
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::canopen::transport::CanTransport;
use ecdrive::canopen::unix_bus::UnixBusPort;
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::motion::telemetry::DriveTask;
use ecdrive::od::{ObjectAddress, Value};
use ecdrive::sim::canopen::{EmulatedNode, SimBus};
use ecdrive::{AppCycle, Axes, Command, CycleApp, RunMode, StopKind, Streams};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The drives: node, profile, homing method (the BLV-R knows 24, the others 19).
/// The drives: node-ID, the master's profile, the homing method, and the software slave's
/// emulation of the same drive (by its name; the emulation takes nothing from the profile).
const DRIVES: [(u8, &CanDriveProfile, i8, &str); 3] = [
    (3, &blv_r::PROFILE, 24, "blv-r"),
    (0x7F, &asda_a2::PROFILE, 19, "asda-a2"),
    (0x41, &lexium_mdrive::PROFILE, 19, "lexium-mdrive"),
];

/// Where the callback stands with an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum Phase {
    #[default]
    Enabling,
    Homing,
    Moving,
    ToPv,
    /// In pv: the stream drives it.
    Streaming,
}

/// What the callback saw of one axis.
#[derive(Debug, Clone, Copy, Default)]
pub struct AxisResult {
    /// Position when the homing completed (counts).
    pub homed_at: Option<i64>,
    /// Position when the drive reported the pp target reached (counts).
    pub pp_reached_at: Option<i64>,
    /// Largest |actual velocity| while streaming (position units per second).
    pub max_stream_velocity: f64,
    /// Phase reached.
    phase: Phase,
}

/// The callback: one phase machine per axis, and the stream consumer after it.
struct App {
    streams: Streams,
    /// Each axis's position per revolution and velocity unit (position units/s per 0x606C unit).
    scale: Vec<(f64, f64)>,
    axes: Vec<AxisResult>,
}

impl CycleApp for App {
    fn cycle(&mut self, c: &mut AppCycle<'_>) {
        for (i, a) in c.axes().iter_mut().enumerate() {
            let (Some(r), Some(&(rev, vel))) = (self.axes.get_mut(i), self.scale.get(i)) else {
                continue;
            };
            let (_, _, method, _) = DRIVES[i];
            r.phase = match (r.phase, a.task()) {
                (Phase::Enabling, _) if a.enabled() => {
                    a.request_home(method);
                    Phase::Homing
                }
                (Phase::Homing, DriveTask::Homed { .. }) => {
                    r.homed_at = Some(a.position());
                    a.request_pp(rev, false, true);
                    Phase::Moving
                }
                (Phase::Moving, DriveTask::TargetReached) => {
                    r.pp_reached_at = Some(a.position());
                    a.request_mode(RunMode::Pv);
                    Phase::ToPv
                }
                (Phase::ToPv, _) if a.mode() == Some(RunMode::Pv) => Phase::Streaming,
                (Phase::ToPv, _) => {
                    a.request_mode(RunMode::Pv);
                    Phase::ToPv
                }
                (Phase::Streaming, _) => {
                    let v = f64::from(a.velocity()).abs() * vel;
                    r.max_stream_velocity = r.max_stream_velocity.max(v);
                    Phase::Streaming
                }
                (p, _) => p,
            };
        }
        // Set-points from the producer thread, for the axes that take them now (in pv).
        self.streams.cycle(c);
    }
}

/// Run the example on `bus`; each axis's result, in the order of [`DRIVES`].
pub fn run<T: CanTransport + Send + 'static>(
    bus: T,
    seconds: f64,
) -> Result<Vec<AxisResult>, Box<dyn std::error::Error>> {
    let speeds = ProfileSpeeds {
        velocity_rev_s: 10.0,
        accel_rev_s2: 100.0,
        homing_fast_rev_s: 5.0,
        homing_slow_rev_s: 0.5,
    };
    // Each drive configured with its profile speeds and homing method, on a 4 ms SYNC.
    let drives = DRIVES
        .iter()
        .map(|&(node, p, method, _)| {
            let mut setup = DriveSetup::new(p);
            setup.settings = profile_settings(p, &speeds);
            setup
                .settings
                .push((ObjectAddress::new(0x6098, 0), Value::Int(method.into())));
            SessionDrive {
                node,
                setup,
                axis: axis_setup(p, Vec::new(), RunMode::Pp),
            }
        })
        .collect();
    let cfg = MasterConfig {
        cycle_us: 4_000,
        ..MasterConfig::default()
    };
    let session = MotionSession::start(bus, cfg, drives)?;
    let mut streams = Streams::new();
    let mut producers: Vec<_> = (0..DRIVES.len()).map(|i| streams.add(i, 100)).collect();
    let app = Arc::new(Mutex::new(App {
        streams,
        scale: DRIVES
            .iter()
            .map(|(_, p, _, _)| (p.units.position_per_rev, p.units.velocity_position_per_s()))
            .collect(),
        axes: vec![AxisResult::default(); DRIVES.len()],
    }));
    let mut t = CycleThread::spawn(session, Some(app.clone()))?;
    t.command(Command::Enable(Axes::All))?;
    let streaming = |app: &Mutex<App>| {
        app.lock()
            .is_ok_and(|a| a.axes.iter().all(|r| r.phase == Phase::Streaming))
    };
    t.wait_until(
        "every axis homed, moved and in pv",
        Duration::from_secs(60),
        |_| streaming(&app),
    )?;
    // The stream: 2 rev/s peak, a third of the time up, a third held, a third down; one
    // set-point per 4 ms SYNC. The producer tops the rings up and sleeps 20 ms.
    let n = ((seconds / 0.004) as usize).max(3);
    let profile = |k: usize, rev: f64| {
        let x = k as f64 / n as f64;
        2.0 * rev * (3.0 * x).min(1.0).min(3.0 * (1.0 - x)).max(0.0)
    };
    let mut pushed = vec![0usize; DRIVES.len()];
    while pushed.iter().any(|&k| k <= n) {
        for (i, prod) in producers.iter_mut().enumerate() {
            let rev = DRIVES[i].1.units.position_per_rev;
            while pushed[i] <= n && prod.push(profile(pushed[i], rev)).is_ok() {
                pushed[i] += 1;
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    while producers.iter().any(|p| p.fill() > 0) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let end = t.stop(StopKind::Ramp)?;
    if let Some(e) = end.error {
        return Err(e.into());
    }
    let mut m = end.session.into_master();
    // The drives are disabled; NMT Stop ends their PDOs.
    for (node, _, _, _) in DRIVES {
        m.nmt(node, NmtCommand::Stop)?;
    }
    let results = app
        .lock()
        .map_err(|_| "the callback panicked")?
        .axes
        .clone();
    for ((node, p, _, _), r) in DRIVES.iter().zip(&results) {
        println!(
            "node {node} ({}): homed at {:?}, pp target reached at {:?} counts, \
             stream peak {:.0} counts/s",
            p.name, r.homed_at, r.pp_reached_at, r.max_stream_velocity
        );
    }
    println!(
        "{} cycles, {} late; {} set-points consumed per axis",
        end.view.cycle,
        end.view.late_cycles,
        producers[0].consumed()
    );
    Ok(results)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(Ok(1.0), |s| s.parse())?;
    match args.next() {
        Some(interface) => match interface.strip_prefix("vbus:") {
            Some(path) => {
                run(UnixBusPort::connect(std::path::Path::new(path))?, seconds)?;
            }
            None => {
                run(SocketCanTransport::open(&interface)?, seconds)?;
            }
        },
        None => {
            let mut bus = SimBus::new();
            for (node, _, _, emulation) in DRIVES {
                bus.add_node(EmulatedNode::new(
                    ecdrive::sim::canopen::drives::by_name(emulation)
                        .expect("the software slave emulates the drive"),
                    node,
                )?);
            }
            run(bus, seconds)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example as `cargo run --example canopen_custom_cycle` runs it, shorter: every
    /// drive, through the callback and the stream, homed, reached its pp target and followed
    /// the streamed velocity (as its TPDOs reported them).
    #[test]
    fn each_canopen_drive_through_a_callback_and_a_stream() {
        let mut bus = SimBus::new();
        for (node, _, _, emulation) in DRIVES {
            bus.add_node(
                EmulatedNode::new(
                    ecdrive::sim::canopen::drives::by_name(emulation)
                        .expect("the software slave emulates the drive"),
                    node,
                )
                .expect("emulated node"),
            );
        }
        let results = run(bus, 0.6).expect("the example runs");
        for ((_, p, _, _), r) in DRIVES.iter().zip(&results) {
            let rev = p.units.position_per_rev;
            assert!(r.homed_at.is_some(), "{}: {r:?}", p.name);
            let reached = r.pp_reached_at.expect("pp target reached") as f64;
            assert!(
                (reached - rev).abs() <= 0.001 * rev,
                "{}: pp ended at {reached}, target {rev}",
                p.name
            );
            assert!(
                (r.max_stream_velocity - 2.0 * rev).abs() <= 0.05 * 2.0 * rev,
                "{}: the stream peaked at 2 rev/s, the drive at {} counts/s",
                p.name,
                r.max_stream_velocity
            );
        }
    }
}
