//! `ecdrive sim`: serve emulated devices on an interface until Ctrl-C.

use crate::{exit, fail_with, print_json};
use ecdrive::sim::run::SimError;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

pub fn sim(
    interface: Option<String>,
    devices: Vec<String>,
    sm_watchdog: Option<u16>,
    list_devices: bool,
    json: bool,
) -> ExitCode {
    if list_devices {
        let names = ecdrive::sim::devices::device_names();
        if json {
            #[derive(serde::Serialize)]
            struct Dev {
                name: &'static str,
                description: String,
            }
            let list: Vec<Dev> = names
                .into_iter()
                .map(|(name, description)| Dev { name, description })
                .collect();
            return print_json("sim", &list);
        }
        for (name, what) in names {
            println!("{name:14} {what}");
        }
        return ExitCode::SUCCESS;
    }
    let Some(interface) = interface else {
        return fail_with("sim", "--interface is required", exit::USAGE);
    };
    let opts = ecdrive::sim::run::SimOptions {
        interface,
        devices,
        sm_watchdog,
    };
    let prepared = match ecdrive::sim::run::Prepared::new(&opts) {
        Ok(p) => p,
        Err(e) => {
            let code = match e {
                SimError::Link(_) => exit::BUS,
                _ => exit::USAGE,
            };
            return fail_with("sim", &e.to_string(), code);
        }
    };
    eprintln!(
        "ecdrive sim: serving {} device(s) on {} — Ctrl-C to stop",
        opts.devices.len(),
        opts.interface
    );
    for line in prepared.describe() {
        eprintln!("  {line}");
    }
    let stop = Arc::new(AtomicBool::new(false));
    let on_signal = stop.clone();
    let waiter = std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .build();
        match rt {
            Ok(rt) => {
                let _ = rt.block_on(tokio::signal::ctrl_c());
            }
            Err(e) => eprintln!("ecdrive sim: cannot wait for Ctrl-C ({e}); stopping"),
        }
        on_signal.store(true, Ordering::Release);
    });
    match prepared.serve(&stop) {
        Ok(stats) => {
            let _ = waiter.join();
            eprintln!(
                "ecdrive sim: stopped; {} frames answered, {} dropped",
                stats.frames, stats.dropped
            );
            ExitCode::SUCCESS
        }
        Err(e) => fail_with("sim", &e.to_string(), exit::BUS),
    }
}
