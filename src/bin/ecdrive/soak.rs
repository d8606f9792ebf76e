//! `ecdrive soak`: argument parsing and output of the soak (the work is `master::soak`).

use clap::Args;
use ecdrive::rt::RtSettings;
use ecdrive_cli::app::ethercat::soak::{self, SoakCounts, SoakOptions, SoakReport};
use std::process::ExitCode;
use std::time::Duration;

/// Options of `ecdrive soak`.
#[derive(Args, Debug)]
#[command(
    after_help = "Examples:\n  ecdrive soak --duration 1h --drop 1%\n  ecdrive soak --duration 60s --drop 5% --json"
)]
pub struct SoakArgs {
    /// How long to run: "1h", "10min", "90s".
    #[arg(long, default_value = "1h", value_parser = crate::parse_duration)]
    duration: Duration,
    /// Fraction of frames the emulated segment drops at random: "1%" or "0.01".
    #[arg(long, default_value = "1%", value_parser = crate::sim::fraction)]
    drop: f32,
    /// Seed of the drop pattern (the same seed drops the same frames).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Cycle time in µs.
    #[arg(long, default_value_t = 1000, value_name = "US")]
    cycle_us: u64,
    /// SCHED_FIFO priority of the cycle thread (0: normal priority).
    #[arg(long, default_value_t = 80)]
    priority: u8,
    /// Pin the cycle thread to this CPU.
    #[arg(long)]
    cpu: Option<usize>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// No progress line on stderr.
    #[arg(long, short)]
    quiet: bool,
}

fn progress(t: Duration, c: &SoakCounts) {
    eprint!(
        "\r{:>6.0} s  cycles {:>10}  lost {:>7}  late {:>6}  programs {:>5}  recoveries {:>4}  re-starts {:>3}  unhandled {}   ",
        t.as_secs_f64(),
        c.cycles,
        c.lost_cycles,
        c.late_wakeups,
        c.programs_completed,
        c.recoveries,
        c.restarts,
        c.unhandled.len()
    );
}

fn print_text(r: &SoakReport) {
    let c = &r.counts;
    println!(
        "ecdrive soak: emulated MR-J4-TM and BDHDE, in-process, {} µs cycle, {:.2} % of frames dropped at random, {:.0} s{}",
        r.cycle_us,
        f64::from(r.drop) * 100.0,
        r.seconds,
        if r.interrupted {
            " (ended early by Ctrl-C)"
        } else {
            ""
        }
    );
    println!(
        "  frames answered {}, dropped by the slave {}; cycles {}, lost {} ({:.3} %)",
        r.frames,
        r.frames_dropped,
        c.cycles,
        c.lost_cycles,
        if c.cycles > 0 {
            c.lost_cycles as f64 * 100.0 / c.cycles as f64
        } else {
            0.0
        }
    );
    println!("  wake-ups more than a cycle late: {}", c.late_wakeups);
    let w = &r.wake_latency_ns;
    if w.count > 0 {
        println!(
            "  wake-up latency (µs) p50 {:.1}, p99.9 {:.1}, max {:.1} over {} cycles{}",
            w.p50 as f64 / 1e3,
            w.p999 as f64 / 1e3,
            w.max as f64 / 1e3,
            w.count,
            if c.restarts > 0 {
                " (since the last re-start)"
            } else {
                ""
            }
        );
    }
    println!(
        "  programs completed {}, recoveries after a controlled stop {}, re-starts {}",
        c.programs_completed, c.recoveries, c.restarts
    );
    println!("  history entries by kind:");
    for (k, n) in &c.history {
        println!("    {k:<16} {n}");
    }
    println!(
        "  drives taken to INIT at the end: {}",
        if r.shutdown_ok { "yes" } else { "NO" }
    );
    if c.unhandled.is_empty() {
        if !c.errors.is_empty() {
            println!("  errors the master handled (first {}):", c.errors.len());
            for e in &c.errors {
                println!("    {e}");
            }
        }
        println!("unhandled errors: 0");
    } else {
        println!("unhandled errors: {}", c.unhandled.len());
        for u in &c.unhandled {
            println!("  {u}");
        }
    }
}

/// Run `ecdrive soak`.
pub fn run(args: SoakArgs) -> ExitCode {
    let opts = SoakOptions {
        duration: args.duration,
        cycles: None,
        cycle: Duration::from_micros(args.cycle_us),
        drop: args.drop,
        seed: args.seed,
        rt: RtSettings {
            priority: (args.priority > 0).then_some(args.priority),
            cpu: args.cpu,
            lock_memory: true,
        },
        progress: (!args.quiet && !args.json).then_some(progress as fn(Duration, &SoakCounts)),
        // Ctrl-C ends the soak early, with its report.
        stop: Some(crate::ctrl_c_flag()),
    };
    match soak::run(&opts) {
        Ok(r) => {
            if !args.quiet && !args.json {
                eprintln!();
            }
            let code = if args.json {
                crate::print_json("soak", &r)
            } else {
                print_text(&r);
                ExitCode::SUCCESS
            };
            if r.ok {
                code
            } else {
                ExitCode::from(crate::exit::FAULT)
            }
        }
        Err(e) => crate::fail("soak", &e),
    }
}
