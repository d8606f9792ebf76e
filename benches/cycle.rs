//! A whole in-process cycle of ecdrive's master: 2, 16, 40, 64 and 128 emulated drives in OP
//! with DC SYNC0, axes enabled and holding position in csp. The drives are the sim's
//! emulations of the Mitsubishi MR-J4-TM and the Servotronix BDHDE, alternating (2 = one of
//! each). `BENCH_DRIVES=2,40` runs only those sizes.
//!
//! What is measured is the **CPU time of the cycle thread per cycle**: the sleep's kernel
//! side, the exchange (`tx_rx_dc`, the frame processed by the emulated segment inline), the
//! AL/WKC checks, one CiA 402 step per axis, outputs and telemetry. The master runs on its own
//! cycle thread at its real cycle time; the bench reads that thread's CPU clock
//! (`pthread_getcpuclockid`, noted by a `CycleHooks` on the cycle thread) before and after
//! `iters` cycles and reports the CPU time of `iters` cycles. Wall-clock figures (wake-up
//! latency, jitter) are `ecdrive jitter`'s job, not a bench's.
//!
//! At 2 drives the same cycle also runs with application code in it (a `CycleApp` writing a
//! sine to every axis from what it reads), with every cycle recorded (drained by another
//! thread), and with both, in the same run: the CPU they add per cycle (`BENCH_EXTRAS=0` skips
//! them).
//!
//! Run with `cargo bench --bench cycle`.

use criterion::{Criterion, criterion_group, criterion_main};
use ecdrive::master::cycle::CycleHooks;
use ecdrive::master::session::{Master, MasterConfig};
use ecdrive::master::startup::{DriveSetup, Selector};
use ecdrive::master::telemetry::{Axes, Command, StopKind};
use ecdrive::master::{AppCycle, CycleApp};
use ecdrive::sim::transport::SegmentLink;
use ecdrive_cli::app::harness::cpu::ThreadCpuClock;
use ecdrive_cli::app::harness::emulated;
use std::sync::{Arc, Mutex};
use std::time::Duration;

#[derive(Default)]
struct Clock(Mutex<Option<ThreadCpuClock>>);

impl CycleHooks for Clock {
    fn steady_begin(&self) {
        if let Ok(mut c) = self.0.lock() {
            *c = ThreadCpuClock::current();
        }
    }
}

/// `n` drives, MR-J4-TM and BDHDE alternating.
fn line(n: usize) -> Vec<String> {
    (0..n)
        .map(|i| if i % 2 == 0 { "mr-j4-tm" } else { "bdhde" }.to_string())
        .collect()
}

/// A sine on every enabled axis from what the callback reads.
struct SineApp {
    centre: Vec<Option<i64>>,
}

impl CycleApp for SineApp {
    fn cycle(&mut self, c: &mut AppCycle<'_>) {
        let t = c.time();
        for (i, a) in c.axes().iter_mut().enumerate() {
            if !a.enabled() {
                continue;
            }
            let Some(slot) = self.centre.get_mut(i) else {
                continue;
            };
            let centre = *slot.get_or_insert(a.position());
            let fe = a.following_error();
            a.set_target(
                centre as f64 + 1000.0 * (t * 6.0).sin() + std::hint::black_box(fe) as f64 * 0.0,
            );
        }
    }
}

/// What else runs in the cycle.
#[derive(Clone, Copy, PartialEq)]
enum Extras {
    None,
    Callback,
    Record,
    Both,
}

impl Extras {
    fn suffix(self) -> &'static str {
        match self {
            Extras::None => "",
            Extras::Callback => "_callback",
            Extras::Record => "_record",
            Extras::Both => "_callback_record",
        }
    }
}

/// The recording's drain, on a thread of its own while the bench runs.
struct Drain {
    done: Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<u64>,
}

fn start(
    n: usize,
    cycle: Duration,
    extras: Extras,
) -> (Master<SegmentLink>, ThreadCpuClock, Option<Drain>) {
    let names = line(n);
    let profiles = emulated::profiles(&names).expect("profiles");
    let link = SegmentLink::new(emulated::segment(&names).expect("segment"));
    let clock = Arc::new(Clock::default());
    let mut cfg = MasterConfig::new(cycle);
    cfg.emergency_poll = None;
    cfg.hooks = Some(clock.clone());
    // A bench measures CPU time, not loss handling: a late frame on a loaded machine must not
    // stop the axes (it would stop a long line before every axis is enabled).
    cfg.cycle.segment_lost_after = 1000;
    cfg.cycle.lost_before_stop = 1000;
    if matches!(extras, Extras::Callback | Extras::Both) {
        cfg.app = Some(Arc::new(Mutex::new(SineApp {
            centre: vec![None; n],
        })));
    }
    let drain = matches!(extras, Extras::Record | Extras::Both).then(|| {
        let (tx, mut rx) = ecdrive::master::recording(1 << 16);
        cfg.record = Some(Arc::new(Mutex::new(tx)));
        let done = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stop = done.clone();
        let thread = std::thread::spawn(move || {
            let mut n = 0u64;
            while !stop.load(std::sync::atomic::Ordering::Acquire) {
                n += rx.drain(|s| {
                    std::hint::black_box(s);
                }) as u64;
                std::thread::sleep(Duration::from_millis(20));
            }
            n
        });
        Drain { done, thread }
    });
    for (i, p) in profiles.into_iter().enumerate() {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(p),
            ..DriveSetup::new(Selector::Position(i as u16))
        });
    }
    let mut m = Master::start(link, cfg).expect("start-up");
    m.wait_until("OP", Duration::from_secs(30), |t| t.cycle.all_op)
        .expect("OP");
    m.command(Command::Enable(Axes::All)).expect("enable");
    m.wait_until("enabled", Duration::from_secs(10), |t| {
        t.axes
            .iter()
            .take(n)
            .all(|a| a.state == Some(ecdrive::cia402::State::OperationEnabled))
    })
    .unwrap_or_else(|e| {
        // What went wrong, without the AL state changes of start-up.
        for h in m
            .history()
            .iter()
            .filter(|h| !matches!(h.cycle_event(), Some(ecdrive::EventKind::AlState { .. })))
            .take(40)
        {
            eprintln!("{:?} {h}", h.drive);
        }
        panic!("every axis enabled: {e}")
    });
    let c = clock
        .0
        .lock()
        .ok()
        .and_then(|c| *c)
        .expect("the cycle's CPU clock");
    (m, c, drain)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("cycle_cpu");
    g.sample_size(
        std::env::var("BENCH_SAMPLES")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(10),
    )
    .warm_up_time(Duration::from_millis(100))
    .measurement_time(Duration::from_millis(
        std::env::var("BENCH_MS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(500),
    ));
    // The shortest cycle both drives take is 250 µs; the larger lines run at 1 ms (64 and 128
    // drives: a process image over two and three LRWs, the working counter checked per
    // datagram). BENCH_DRIVES=2,16 picks the sizes.
    let sizes: Vec<usize> = std::env::var("BENCH_DRIVES")
        .ok()
        .map(|v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![2, 16, 40, 64, 128]);
    let extras = std::env::var("BENCH_EXTRAS").map_or(true, |v| v != "0");
    let runs: Vec<(usize, Extras)> = sizes
        .iter()
        .flat_map(|&n| {
            let all = [Extras::None, Extras::Callback, Extras::Record, Extras::Both];
            let k = if n == 2 && extras { 4 } else { 1 };
            all.into_iter().take(k).map(move |e| (n, e))
        })
        .collect();
    for (n, extra) in runs {
        let cycle = if n <= 2 {
            Duration::from_micros(250)
        } else {
            Duration::from_millis(1)
        };
        let (mut m, clock, drain) = start(n, cycle, extra);
        g.bench_function(format!("{n}_drives{}", extra.suffix()), |b| {
            b.iter_custom(|iters| {
                let c0 = m.telemetry().cycle.cycle;
                let t0 = clock.now_ns().unwrap_or(0);
                std::thread::sleep(cycle.saturating_mul(iters as u32));
                m.wait_until("the cycles", Duration::from_secs(60), |t| {
                    t.cycle.cycle >= c0 + iters
                })
                .expect("cycles");
                let t1 = clock.now_ns().unwrap_or(0);
                let c1 = m.telemetry().cycle.cycle;
                // CPU per cycle over the cycles that really ran, times the cycles asked for.
                let per = (t1 - t0) as f64 / (c1 - c0).max(1) as f64;
                Duration::from_nanos((per * iters as f64) as u64)
            })
        });
        let (r, _) = m.stop(StopKind::QuickStop);
        assert!(r.is_some_and(|r| r.shutdown_ok), "clean shutdown");
        if let Some(d) = drain {
            d.done.store(true, std::sync::atomic::Ordering::Release);
            assert!(d.thread.join().unwrap_or(0) > 0, "the recording drained");
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
