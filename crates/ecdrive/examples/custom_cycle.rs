//! Your code in the cycle: a sine generated in a `CycleApp` on both emulated drives (MR-J4-TM
//! and BDHDE, in-process, no root), printing each axis's largest following error.
//!
//! ```text
//! cargo run --release --example custom_cycle [-- SECONDS [INTERFACE]]
//! ```
//!
//! With an INTERFACE (root or CAP_NET_RAW) the same code drives whatever answers there, for
//! example `ecdrive sim -i veth1 -d mr-j4-tm -d bdhde` on the far end of a veth pair.

use ecdrive::link::FrameLink;
use ecdrive::link::RawSocket;
use ecdrive::sim::transport::SegmentLink;
use ecdrive::{
    AppCycle, Axes, Command, CycleApp, DriveSetup, Master, MasterConfig, RunMode, Selector,
    SetpointLimits, State, StopKind,
};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A sine of `AMPLITUDE` counts at `FREQ_HZ` around where each axis stood when it was enabled.
#[derive(Default)]
struct Sine {
    start: [Option<(i64, u64)>; 2],
    max_following_error: [i64; 2],
}

const AMPLITUDE: f64 = 20_000.0;
const FREQ_HZ: f64 = 1.0;

impl CycleApp for Sine {
    fn cycle(&mut self, c: &mut AppCycle<'_>) {
        let (now, dt) = (c.cycle(), c.period());
        for (i, a) in c.axes().iter_mut().enumerate().take(2) {
            if !a.enabled() {
                continue;
            }
            let (centre, t0) = *self.start[i].get_or_insert((a.position(), now));
            let t = (now - t0) as f64 * dt;
            a.set_target(
                centre as f64 + AMPLITUDE * (2.0 * std::f64::consts::PI * FREQ_HZ * t).sin(),
            );
            self.max_following_error[i] =
                self.max_following_error[i].max(a.following_error().abs());
        }
    }
}

fn config(app: Arc<Mutex<Sine>>) -> MasterConfig {
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    for i in 0..2 {
        cfg.startup.drives.push(DriveSetup {
            mode: RunMode::Csp,
            // The sine's peak velocity is 2π·f·A ≈ 126 000 counts/s: leave room, refuse a jump.
            limits: SetpointLimits {
                max_velocity: Some(200_000.0),
                max_acceleration: Some(2_000_000.0),
                max_torque: None,
            },
            ..DriveSetup::new(Selector::Position(i))
        });
    }
    cfg.app = Some(app);
    cfg
}

fn run<L: FrameLink + Send + 'static>(
    link: L,
    seconds: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let app = Arc::new(Mutex::new(Sine::default()));
    let mut m = Master::start(link, config(app.clone())).map_err(|f| f.error)?;
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)?;
    m.command(Command::Enable(Axes::All))?;
    m.wait_until("both axes enabled", Duration::from_secs(10), |t| {
        t.axes.len() >= 2
            && t.axes
                .iter()
                .all(|a| a.state == Some(State::OperationEnabled))
    })?;
    std::thread::sleep(Duration::from_secs_f64(seconds));
    let (report, _link) = m.stop(StopKind::Ramp);
    let report = report.ok_or("the session ended without a report")?;
    let app = app.lock().map_err(|_| "the cycle panicked")?;
    for (d, fe) in report.drives.iter().zip(app.max_following_error) {
        println!("{}: max |following error| {fe} counts", d.drive);
    }
    println!("shut down cleanly: {}", report.shutdown_ok);
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(Ok(2.0), |s| s.parse())?;
    match args.next() {
        Some(interface) => run(RawSocket::open(&interface)?, seconds),
        None => {
            let segment = ecdrive::sim::devices::line(&["mr-j4-tm", "bdhde"])?;
            run(SegmentLink::new(segment), seconds)
        }
    }
}

#[cfg(test)]
mod tests {
    /// The example as `cargo run --example custom_cycle` runs it, shorter.
    #[test]
    fn runs_in_process() {
        let segment = ecdrive::sim::devices::line(&["mr-j4-tm", "bdhde"]).unwrap();
        super::run(super::SegmentLink::new(segment), 0.3).unwrap();
    }
}
