//! Every cycle of a run recorded to CSV from the library: a move on both emulated drives
//! (MR-J4-TM and BDHDE, in-process, no root), the master's ring drained by a thread of this
//! program into the file, the samples and any the writer could not keep up with counted.
//!
//! ```text
//! cargo run --release --example record [-- OUT.csv [INTERFACE]]
//! ecdrive plot OUT.csv -o OUT.svg
//! ```

use ecdrive::link::{FrameLink, RawSocket};
use ecdrive::master::{CsvWriter, SampleScale, recording};
use ecdrive::sim::transport::SegmentLink;
use ecdrive::{
    Axes, Command, DriveSetup, Master, MasterConfig, Selector, State, Step, StopKind, Target,
};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

fn run<L: FrameLink + Send + 'static>(
    link: L,
    out: &Path,
) -> Result<(u64, u64), Box<dyn std::error::Error>> {
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    for i in 0..2 {
        cfg.startup.drives.push(DriveSetup {
            program: vec![Step::Move {
                target: Target::By(100_000.0),
                velocity: 400_000.0,
                acceleration: 4_000_000.0,
                jerk: None,
            }],
            ..DriveSetup::new(Selector::Position(i))
        });
    }
    // Half a second of samples in flight: 1 kHz × 2 axes × 0.5 s.
    let (tx, mut rx) = recording(1000);
    cfg.record = Some(Arc::new(Mutex::new(tx)));
    let mut csv = CsvWriter::new(std::io::BufWriter::new(std::fs::File::create(out)?))?;
    let done = Arc::new(AtomicBool::new(false));
    let stop = done.clone();
    // The drives' units, for the CSV's physical columns, once the master has started.
    let (drives_tx, drives_rx) = std::sync::mpsc::channel::<Vec<SampleScale>>();
    let writer = std::thread::spawn(move || -> std::io::Result<(u64, u64)> {
        loop {
            let last = stop.load(Ordering::Acquire);
            if let Ok(scales) = drives_rx.try_recv() {
                csv.set_drives(scales)?;
            }
            csv.drain(&mut rx)?;
            if last {
                let (_, lines) = csv.finish()?;
                return Ok((lines, rx.dropped()));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    });
    let mut m = Master::start(link, cfg).map_err(|f| f.error)?;
    drives_tx.send(SampleScale::of_drives(m.drives()))?;
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)?;
    m.command(Command::Enable(Axes::All))?;
    m.wait_until("enabled", Duration::from_secs(10), |t| {
        t.axes
            .iter()
            .all(|a| a.state == Some(State::OperationEnabled))
    })?;
    m.command(Command::RunProgram(Axes::All))?;
    m.wait_until("the moves", Duration::from_secs(10), |t| {
        t.axes
            .iter()
            .all(|a| !a.program_running && a.program_step >= 1)
    })?;
    let (report, _link) = m.stop(StopKind::Ramp);
    done.store(true, Ordering::Release);
    let counts = writer.join().map_err(|_| "the writer panicked")??;
    println!(
        "{} samples to {} ({} dropped); shut down cleanly: {}",
        counts.0,
        out.display(),
        counts.1,
        report.is_some_and(|r| r.shutdown_ok)
    );
    Ok(counts)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = args.next().unwrap_or_else(|| "record.csv".into());
    match args.next() {
        Some(interface) => run(RawSocket::open(&interface)?, Path::new(&out)),
        None => {
            let segment = ecdrive::sim::devices::line(&["mr-j4-tm", "bdhde"])?;
            run(SegmentLink::new(segment), Path::new(&out))
        }
    }
    .map(|_| ())
}

#[cfg(test)]
mod tests {
    /// The example as `cargo run --example record` runs it, into a temporary file, with the
    /// emulated drives' loss supervision off: the recording is under test, not the host's
    /// timing (a stall of a shared CI machine faulted both drives once, AL.86 and 0x818D).
    #[test]
    fn records_in_process() {
        let out =
            std::env::temp_dir().join(format!("ecdrive-record-ex-{}.csv", std::process::id()));
        let mut segment = ecdrive::sim::devices::line(&["mr-j4-tm", "bdhde"]).unwrap();
        ecdrive::sim::drives::set_loss_detection(&mut segment, false);
        let (lines, dropped) = super::run(super::SegmentLink::new(segment), &out).unwrap();
        assert!(lines + dropped > 100);
        let text = std::fs::read_to_string(&out).unwrap();
        assert_eq!(text.lines().count() as u64, lines + 1);
        std::fs::remove_file(&out).ok();
    }
}
