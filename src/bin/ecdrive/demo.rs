//! `ecdrive demo`: argument parsing and output of the demo (the work is `master::demo`).

use clap::Args;
use ecdrive::rt::{RtSettings, Summary};
use ecdrive_cli::app::ethercat::demo::{self, DemoOptions, DemoReport};
use std::process::ExitCode;
use std::time::Duration;

/// Options of `ecdrive demo`.
#[derive(Args, Debug)]
#[command(
    after_help = "Examples:\n  ecdrive demo\n  ecdrive demo --cycle-us 500 --json\n  ecdrive demo --canopen"
)]
pub struct DemoArgs {
    /// Cycle time in µs (the MR-J4-TM accepts 250, 500, 1000, 2000; the BDHDE multiples of 250).
    #[arg(long, default_value_t = 1000, value_name = "US")]
    cycle_us: u64,
    /// SCHED_FIFO priority of the cycle thread (granted with root or CAP_SYS_NICE; without
    /// it the demo runs at normal priority and says so).
    #[arg(long, default_value_t = 80)]
    priority: u8,
    /// Pin the cycle thread to this CPU.
    #[arg(long)]
    cpu: Option<usize>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// The emulated drives without their loss-of-data supervision (MR-J4-TM AL.86.1, BDHDE
    /// 0x818D after about 7 ms without cyclic data): for a machine that cannot keep the cycle
    /// (a busy VM), as [Pr. PN06]/[Pr. PN02] do on a real MR-J4-TM.
    #[arg(long, conflicts_with = "canopen")]
    no_loss_detection: bool,
    /// Run the CANopen demo instead: the emulated Oriental BLV-R, Delta ASDA-A2 and Lexium
    /// MDrive on the virtual CAN bus, through the same CiA 402 engine.
    #[arg(long)]
    canopen: bool,
}

fn us(ns: u64) -> String {
    if ns >= 10_000 {
        format!("{} µs", ns / 1000)
    } else {
        format!("{:.1} µs", ns as f64 / 1000.0)
    }
}

fn row(name: &str, s: &Summary) -> String {
    format!(
        "  {name:<10} {:>10} {:>10} {:>10}",
        us(s.p50),
        us(s.p99),
        us(s.max)
    )
}

fn print_text(r: &DemoReport) {
    println!(
        "ecdrive demo: emulated MR-J4-TM and BDHDE, in-process, DC SYNC0 every {} µs",
        r.cycle_us
    );
    match r.rt.priority_granted {
        Some(p) => println!(
            "real-time: SCHED_FIFO {p}{}",
            if r.rt.memory_locked {
                ", memory locked"
            } else {
                ""
            }
        ),
        None => println!("real-time: not granted — running at normal priority"),
    }
    for w in &r.rt.warnings {
        println!("  warning: {w}");
    }
    println!();
    for d in &r.drives {
        println!(
            "drive {} {} ({}): vendor 0x{:08X}, product 0x{:08X}, revision 0x{:08X}, serial {}",
            d.position, d.name, d.device_name, d.vendor_id, d.product_code, d.revision, d.serial
        );
        println!("  states:  {}", d.states.join(" → "));
        println!("  modes:   {}", d.modes.join(" → "));
        println!(
            "  max following error: {} counts ({:.6} rev){}",
            d.max_following_error,
            d.max_following_error_rev,
            if d.program_done {
                ""
            } else {
                "  — program did not finish"
            }
        );
    }
    println!();
    println!(
        "cycle timing: {} cycles, {} without a reply, {} woken more than a cycle late",
        r.cycles, r.lost, r.overruns
    );
    println!("  {:<10} {:>10} {:>10} {:>10}", "", "p50", "p99", "max");
    println!("{}", row("wake-up", &r.timing.wake_latency));
    println!("{}", row("period", &r.timing.period));
    println!("{}", row("exchange", &r.timing.exchange));
    println!("{}", row("busy", &r.timing.busy));
    println!();
    let what = "both drives ran csp, csv and cst and were stopped and disabled";
    match (r.ok, r.recoveries) {
        (true, 0) => println!("result: OK — {what}"),
        (true, n) => {
            println!(
                "result: OK after {n} recover{} — {what}",
                if n == 1 { "y" } else { "ies" }
            );
            println!(
                "  the drives stopped on their own (the cycle thread woke up to {} late) and \
                 were reset, enabled and run again:",
                us(r.timing.wake_latency.max)
            );
            for e in &r.errors {
                println!("  {e}");
            }
        }
        (false, _) => {
            println!("result: FAILED");
            for e in &r.unhandled {
                println!("  unhandled: {e}");
            }
            for e in &r.errors {
                println!("  {e}");
            }
        }
    }
}

/// Run `ecdrive demo`.
pub fn run(args: DemoArgs) -> ExitCode {
    if args.canopen {
        return match ecdrive_cli::app::canopen::demo::run(
            &ecdrive_cli::app::canopen::demo::DemoOptions::default(),
        ) {
            Ok(s) if args.json => {
                // Per drive: its program's steps (done when the program ran to its end), then
                // the injected alarm; the whole run and reset reports beside.
                let drives: Vec<serde_json::Value> = s
                    .run
                    .drives
                    .iter()
                    .map(|d| {
                        let fault = s.faults.drives.iter().find(|r| r.node == d.node);
                        let mut steps: Vec<serde_json::Value> = d
                            .program
                            .iter()
                            .map(|st| {
                                serde_json::json!({
                                    "step": st,
                                    "ok": d.program_done,
                                    "outcome": if d.program_done { "done" } else { "not done" },
                                })
                            })
                            .collect();
                        let cleared = fault.is_some_and(|r| r.cleared == Some(true));
                        steps.push(serde_json::json!({
                            "step": "alarm injected, then reset",
                            "ok": cleared,
                            "outcome": fault
                                .and_then(|r| r.fault.clone())
                                .unwrap_or_else(|| "no fault shown".into()),
                        }));
                        serde_json::json!({
                            "node": d.node,
                            "drive": d.drive,
                            "ok": d.program_done && d.errors.is_empty() && cleared,
                            "steps": steps,
                        })
                    })
                    .collect();
                let j = serde_json::json!({
                    "config": ecdrive_cli::app::canopen::demo::CONFIG_NAME,
                    "scan": s.scan,
                    "drives": drives,
                    "run": s.run,
                    "faults": s.faults,
                    "sim_time_us": s.sim_time_us,
                    "ok": s.ok(),
                });
                let code = crate::print_json("demo", &j);
                if s.ok() {
                    code
                } else {
                    ExitCode::from(crate::exit::FAULT)
                }
            }
            Ok(s) => {
                println!("{s}");
                if s.ok() {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::from(crate::exit::FAULT)
                }
            }
            Err(e) => crate::fail_with("demo", &e.to_string(), crate::exit::BUS),
        };
    }
    let opts = DemoOptions {
        cycle: Duration::from_micros(args.cycle_us),
        rt: RtSettings {
            priority: Some(args.priority),
            cpu: args.cpu,
            lock_memory: true,
        },
        pcap: crate::pcap().map(std::path::Path::to_path_buf),
        loss_detection: !args.no_loss_detection,
    };
    match demo::run(&opts) {
        Ok(r) => {
            if let Some(c) = &r.capture {
                crate::report_capture("demo", c);
            }
            if args.json {
                let code = crate::print_json("demo", &r);
                if !r.ok {
                    return ExitCode::from(crate::exit::FAULT);
                }
                return code;
            }
            print_text(&r);
            if r.ok {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(crate::exit::FAULT)
            }
        }
        Err(e) => crate::fail("demo", &e),
    }
}
