//! Set-points streamed from a thread of your own (as a ROS 2 node or a Python producer at 1 kHz
//! would): a cosine move on the emulated MR-J4-TM, pushed through a ring of 50 set-points that
//! the cycle consumes one per cycle; the producer reports the fill level, the set-points the
//! cycle took, and the underrun once it stops (the history's warning).
//!
//! ```text
//! cargo run --release --example stream_setpoints [-- SECONDS [INTERFACE]]
//! ```
//!
//! In-process by default (no root); with an INTERFACE, the first drive found there.

use ecdrive::link::{FrameLink, RawSocket};
use ecdrive::sim::transport::SegmentLink;
use ecdrive::{
    Axes, Command, DriveSetup, HistoryKind, Master, MasterConfig, RunMode, Selector, State,
    StopKind, Streams,
};
use std::sync::{Arc, Mutex};
use std::time::Duration;

fn run<L: FrameLink + Send + 'static>(
    link: L,
    seconds: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut streams = Streams::new();
    let mut producer = streams.add(0, 50);
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    cfg.startup.drives.push(DriveSetup {
        mode: RunMode::Csp,
        ..DriveSetup::new(Selector::Position(0))
    });
    cfg.app = Some(Arc::new(Mutex::new(streams)));
    let mut m = Master::start(link, cfg).map_err(|f| f.error)?;
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)?;
    m.command(Command::Enable(Axes::All))?;
    m.wait_until("enabled", Duration::from_secs(10), |t| {
        t.axes
            .first()
            .is_some_and(|a| a.state == Some(State::OperationEnabled))
    })?;
    let origin = m.telemetry().axes[0].position_actual as f64;
    // A cosine move of 50 000 counts, one set-point per millisecond. The producer is not
    // real-time: it tops the ring up and sleeps 10 ms, so the ring's 50 set-points must cover
    // its sleep and its lateness (the fill level shows the margin).
    let n = (seconds * 1000.0) as usize;
    let (mut pushed, mut min_fill) = (0, usize::MAX);
    while pushed < n {
        if pushed > 0 {
            min_fill = min_fill.min(producer.fill());
        }
        while pushed < n {
            let k = pushed as f64 / n as f64;
            let p = origin + 25_000.0 * (1.0 - (std::f64::consts::PI * k).cos());
            if producer.push(p).is_err() {
                break;
            }
            pushed += 1;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    // Let it drain, then some cycles of underrun.
    while producer.fill() > 0 {
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(20));
    println!(
        "pushed {pushed}, consumed {}, fill at least {min_fill} of {} before each top-up, \
         underrun cycles {} (after the last set-point)",
        producer.consumed(),
        producer.depth(),
        producer.underruns()
    );
    let (report, _link) = m.stop(StopKind::Ramp);
    let report = report.ok_or("the session ended without a report")?;
    for h in report
        .history
        .iter()
        .filter(|h| h.kind == HistoryKind::Warning)
    {
        println!("history: {}", h.text());
    }
    println!("shut down cleanly: {}", report.shutdown_ok);
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(Ok(2.0), |s| s.parse())?;
    match args.next() {
        Some(interface) => run(RawSocket::open(&interface)?, seconds),
        None => run(
            SegmentLink::new(ecdrive::sim::devices::line(&["mr-j4-tm"])?),
            seconds,
        ),
    }
}

#[cfg(test)]
mod tests {
    /// The example as `cargo run --example stream_setpoints` runs it, shorter.
    #[test]
    fn runs_in_process() {
        let segment = ecdrive::sim::devices::line(&["mr-j4-tm"]).unwrap();
        super::run(super::SegmentLink::new(segment), 0.3).unwrap();
    }
}
