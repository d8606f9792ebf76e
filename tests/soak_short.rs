//! A short `ecdrive soak` (seconds, not the documented hour): the soak loop itself (random frame
//! loss, the master's reactions, the application-style recovery) runs to its end with no
//! unhandled error, and its counts agree with what the software slave dropped.

use ecdrive::master::soak::{self, SoakOptions};
use std::time::Duration;

#[test]
fn a_short_soak_with_frame_loss_ends_with_no_unhandled_error() {
    let opts = SoakOptions {
        duration: Duration::from_secs(12),
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
    assert!(c.cycles > 8_000, "only {} cycles in 12 s", c.cycles);
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
/// nothing counted so far is lost.
#[test]
fn a_soak_stopped_early_reports_what_it_counted() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let stop = Arc::new(AtomicBool::new(false));
    let opts = SoakOptions {
        duration: Duration::from_secs(3600),
        drop: 0.01,
        stop: Some(stop.clone()),
        ..SoakOptions::default()
    };
    let t = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(2));
        stop.store(true, Ordering::Release);
    });
    let r = soak::run(&opts).expect("the soak starts");
    t.join().unwrap();
    assert!(r.interrupted);
    assert!(r.seconds < 30.0, "{} s", r.seconds);
    assert!(r.counts.cycles > 1_000, "{} cycles", r.counts.cycles);
    assert!(r.shutdown_ok);
    assert!(r.counts.unhandled.is_empty(), "{:#?}", r.counts.unhandled);
}
