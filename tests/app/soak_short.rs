//! A short `ecdrive soak` (12 000 cycles, not the documented hour): the soak loop itself
//! (random frame loss, the master's reactions, the application-style recovery) runs to its end
//! with no unhandled error, and its counts agree with what the software slave dropped. Counted
//! in cycles, never in seconds: a slow machine takes longer, it does not fail.

use ecdrive_cli::app::ethercat::soak::{self, SoakOptions};
use std::time::Duration;

#[test]
fn a_short_soak_with_frame_loss_ends_with_no_unhandled_error() {
    let opts = SoakOptions {
        cycles: Some(12_000),
        drop: 0.02,
        seed: 7,
        ..SoakOptions::default()
    };
    let r = soak::run(&opts).expect("the soak starts");
    let c = &r.counts;
    assert!(
        r.ok,
        "unhandled: {:#?}\nhandled errors: {:#?}",
        c.unhandled, c.errors
    );
    assert!(
        r.shutdown_ok,
        "the drives were not taken to INIT at the end"
    );
    assert!(c.cycles >= 12_000, "only {} cycles", c.cycles);
    // The slave dropped frames, and the master counted about as many lost cycles.
    assert!(r.frames_dropped > 0);
    let lost = c.lost_cycles as f64 / c.cycles as f64;
    assert!(
        (0.005..0.08).contains(&lost),
        "{} lost of {} cycles for 2 % dropped frames",
        c.lost_cycles,
        c.cycles
    );
    assert!(c.history.get("FrameLost").copied().unwrap_or(0) > 0);
    // The programs ran (a program takes about 4 s).
    assert!(c.programs_completed >= 1, "{c:#?}");
}

/// Ctrl-C (the stop flag) ends an hour-long soak early in a controlled way, with its report:
/// nothing counted so far is lost. The flag is set once 1000 cycles were counted (the progress
/// callback sees the counts), not after some seconds.
#[test]
fn a_soak_stopped_early_reports_what_it_counted() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, OnceLock};
    static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();
    fn progress(_: Duration, c: &soak::SoakCounts) {
        if c.cycles > 1_000
            && let Some(s) = STOP.get()
        {
            s.store(true, Ordering::Release);
        }
    }
    let stop = STOP
        .get_or_init(|| Arc::new(AtomicBool::new(false)))
        .clone();
    let opts = SoakOptions {
        duration: Duration::from_secs(3600),
        drop: 0.01,
        stop: Some(stop),
        progress: Some(progress),
        ..SoakOptions::default()
    };
    let r = soak::run(&opts).expect("the soak starts");
    assert!(r.interrupted);
    assert!(r.counts.cycles > 1_000, "{} cycles", r.counts.cycles);
    assert!(r.shutdown_ok);
    assert!(r.counts.unhandled.is_empty(), "{:#?}", r.counts.unhandled);
}
