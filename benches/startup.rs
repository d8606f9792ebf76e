//! Start-up: from `Master::start` to every drive in OP, in-process, for 2 and 64 emulated
//! drives (the sim's MR-J4-TM and BDHDE emulations, alternating), 1 ms cycle with DC SYNC0. This covers discovery,
//! SII reads, profile matching, PDO remapping over CoE, DC set-up and settling, SAFE-OP and the
//! cycle's OP request. Shutting down (not measured) follows each start.
//!
//! Run with `cargo bench --bench startup`.

use criterion::{Criterion, criterion_group, criterion_main};
use ecdrive::master::session::{Master, MasterConfig};
use ecdrive::master::startup::{DriveSetup, Selector};
use ecdrive::master::telemetry::StopKind;
use ecdrive::sim::transport::SegmentLink;
use ecdrive_cli::app::harness::emulated;
use std::time::{Duration, Instant};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("startup_to_op");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(1))
        .measurement_time(Duration::from_secs(5));
    for n in [2usize, 64] {
        let names: Vec<String> = (0..n)
            .map(|i| if i % 2 == 0 { "mr-j4-tm" } else { "bdhde" }.to_string())
            .collect();
        let profiles = emulated::profiles(&names).expect("profiles");
        g.bench_function(format!("{n}_drives"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let link = SegmentLink::new(emulated::segment(&names).expect("segment"));
                    let mut cfg = MasterConfig::new(Duration::from_millis(1));
                    cfg.emergency_poll = None;
                    for (i, p) in profiles.iter().enumerate() {
                        cfg.startup.drives.push(DriveSetup {
                            profile: Some(*p),
                            ..DriveSetup::new(Selector::Position(i as u16))
                        });
                    }
                    let t0 = Instant::now();
                    let mut m = Master::start(link, cfg).expect("start-up");
                    m.wait_until("OP", Duration::from_secs(60), |t| t.cycle.all_op)
                        .expect("OP");
                    total += t0.elapsed();
                    let (r, _) = m.stop(StopKind::QuickStop);
                    assert!(r.is_some_and(|r| r.shutdown_ok), "clean shutdown");
                }
                total
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
