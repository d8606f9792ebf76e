//! `ecdrive demo --canopen`: the three emulated CANopen drives on the in-process virtual bus,
//! run as a configuration: `examples/canopen_profile_modes.toml`, the file `ecdrive run -c`
//! takes, on the motion runtime the EtherCAT drives run on. [`run`] returns a
//! [`DemoSummary`]; the CLI prints it.
//!
//! The bus is scanned (identity of every node), the file's programs run (each drive homes, runs
//! pp, pv, tq where its firmware has it, and ip on the ASDA-A2; controlled stop, disable, NMT
//! Stop), then each drive gets an alarm injected and `ecdrive reset`'s procedure clears it,
//! naming it with the drive's alarm table. Simulated time: the demo takes milliseconds of wall
//! time.

use super::reset::{CanResetOptions, CanResetReport, reset};
use super::run::{CanRunReport, emulated_bus, run_on};
use super::tools;
use crate::app::config::canopen::CanRunConfig;
use crate::app::ethercat::tools::run::Outcome;
use crate::canopen::error::{CanError, CanErrorKind, NodeRef};
use crate::canopen::master::{Master, MasterConfig};
use crate::canopen::profile::CanDriveProfile;
use crate::canopen::transport::CanTransport;
use core::fmt;
use std::time::Duration;

/// The demo's configuration, as `ecdrive run -c examples/canopen_profile_modes.toml` reads it.
pub const CONFIG: &str = include_str!("../../../examples/canopen_profile_modes.toml");

/// Its name in messages.
pub const CONFIG_NAME: &str = "examples/canopen_profile_modes.toml";

/// Options of [`run`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DemoOptions {
    /// The SYNC period, µs (`None`: the file's, 4 ms).
    pub cycle_us: Option<u64>,
}

/// The demo's result.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoSummary {
    /// The scan, one line per node.
    pub scan: Vec<String>,
    /// The run of [`CONFIG`].
    pub run: CanRunReport,
    /// The injected alarms, named and reset.
    pub faults: CanResetReport,
    /// Simulated time at the end, µs.
    pub sim_time_us: u64,
}

impl DemoSummary {
    /// Whether the run completed with every program done and no error, and every injected
    /// alarm was named and cleared.
    pub fn ok(&self) -> bool {
        self.run.outcome == Outcome::Completed
            && !self.run.drives.is_empty()
            && self
                .run
                .drives
                .iter()
                .all(|d| d.program_done && d.errors.is_empty())
            && self.faults.drives.len() == self.run.drives.len()
            && self
                .faults
                .drives
                .iter()
                .all(|d| d.fault.is_some() && d.cleared == Some(true))
    }
}

impl fmt::Display for DemoSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "CANopen demo: {CONFIG_NAME} on the emulated drives in-process, SYNC every {} µs",
            self.run.cycle_us
        )?;
        writeln!(f, "nodes found:")?;
        for l in &self.scan {
            writeln!(f, "  {l}")?;
        }
        for d in &self.run.drives {
            let at = match d.position_user {
                Some(u) => format!("{u:.4} {} ({} counts)", d.units, d.position),
                None => format!("{} counts", d.position),
            };
            writeln!(
                f,
                "node {} ({}): {}; modes {}; at {at}",
                d.node,
                d.drive,
                if d.program_done {
                    "program done"
                } else {
                    "program NOT done"
                },
                d.modes.join(" → ")
            )?;
            for e in &d.errors {
                writeln!(f, "  error: {e}")?;
            }
            if let Some(r) = self.faults.drives.iter().find(|r| r.node == d.node) {
                match (&r.fault, r.cleared) {
                    (Some(fault), Some(true)) => {
                        writeln!(f, "  alarm injected: {fault}; reset, now {}", r.after)?
                    }
                    (Some(fault), _) => {
                        writeln!(f, "  alarm injected: {fault}; NOT cleared, {}", r.after)?
                    }
                    (None, _) => writeln!(f, "  alarm injected, but the drive showed no fault")?,
                }
            }
        }
        writeln!(
            f,
            "{}: {} ({} cycles, {} ms simulated); {}",
            self.run.outcome.describe(),
            self.run.reason,
            self.run.cycles,
            self.sim_time_us / 1000,
            if self.ok() { "demo OK" } else { "demo FAILED" }
        )
    }
}

/// **\[REC\]** The alarm each demo drive gets injected: BLV-R 30h overload, ASDA-A2 AL006
/// overload, Lexium 4210h/8h over-temperature.
pub fn demo_alarm(profile: &CanDriveProfile) -> Option<u16> {
    match profile.name {
        "BLV-R" => Some(0x30),
        "ASDA-A2" => Some(0x0006),
        _ => profile
            .alarms
            .iter()
            .find(|a| a.fault && a.code == 0x4210)
            .map(|a| a.number),
    }
}

/// The demo's configuration, with the SYNC period of `opts`.
pub fn config(opts: &DemoOptions) -> Result<CanRunConfig, CanError> {
    let not_canopen = |why: String| {
        CanError::new(
            NodeRef { id: 0, drive: None },
            None,
            CanErrorKind::NotReady(why),
        )
    };
    let mut cfg = match crate::app::config::parse_any(CONFIG, CONFIG_NAME) {
        Ok(crate::app::config::Config::CanOpen(c)) => c,
        Ok(_) => return Err(not_canopen(format!("{CONFIG_NAME} is not a CANopen run"))),
        Err(e) => return Err(not_canopen(e.to_string())),
    };
    if let Some(us) = opts.cycle_us {
        cfg.cycle = Duration::from_micros(us);
    }
    Ok(cfg)
}

/// Run the demo: scan, the configuration's run, an alarm per drive named and reset.
pub fn run(opts: &DemoOptions) -> Result<DemoSummary, CanError> {
    let cfg = config(opts)?;
    let mut bus = emulated_bus(&cfg)?;
    let scan = {
        let mut m = Master::new(&mut bus, MasterConfig::default());
        m.pump(50_000)?;
        tools::scan(&mut m, 1..=127)?
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let report = run_on(&mut bus, &cfg, None, None, &stop)?;
    for d in &cfg.drives {
        if let (Some(number), Some(n)) = (demo_alarm(d.profile), bus.node_mut(d.node)) {
            n.inject_alarm(number);
        }
    }
    let faults = reset(&mut bus, "can-sim", &CanResetOptions::default())?;
    Ok(DemoSummary {
        scan: scan.iter().map(ToString::to_string).collect(),
        run: report,
        faults,
        sim_time_us: bus.now_us(),
    })
}
