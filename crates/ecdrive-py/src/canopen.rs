//! A `Master` on a CANopen run file: its drives configured and started as `ecdrive run` does
//! (identity, PDO plan, supervision, start-up values, NMT Operational), stepped by the motion
//! runtime on the CANopen master's cycle thread, paced by its SYNC. The same `Drive` objects
//! drive them: commands, telemetry and events are the runtime's, shared with EtherCAT.

use crate::backend::{Backend, CanAxis, CanOpen};
use crate::devices::{Device, FoundDrive, FoundOf};
use crate::errors::Failure;
use ecdrive::canopen::motion::CycleThread;
use ecdrive::canopen::transport::CanTransport;
use ecdrive::master::HistoryLog;
use ecdrive::{DriveRef, Telemetry};
use ecdrive_cli::app::canopen::run::{emulated_bus, session};
use ecdrive_cli::app::canopen::tools::open_bus;
use ecdrive_cli::app::config::canopen::{CanRunConfig, CanTarget};

/// Start the drives of `cfg` on its bus (`can-sim`: the emulated drives in-process) and their
/// cycle thread; the backend and the drives found.
pub(crate) fn start(cfg: &CanRunConfig) -> Result<(Box<dyn Backend>, FoundOf), Failure> {
    let fail = |e: ecdrive::canopen::CanError| {
        Failure::new(
            e.class(),
            None,
            "starting the CANopen drives",
            e.to_string(),
        )
    };
    match &cfg.target {
        CanTarget::Sim => on(emulated_bus(cfg).map_err(fail)?, cfg),
        CanTarget::Bus(spec) => {
            let t = open_bus(spec).map_err(|e| {
                Failure::new(
                    ecdrive::ErrorClass::Bus,
                    None,
                    format!("opening CAN bus {spec}"),
                    e.to_string(),
                )
            })?;
            on(t, cfg)
        }
    }
}

fn on<T: CanTransport + Send + 'static>(
    transport: T,
    cfg: &CanRunConfig,
) -> Result<(Box<dyn Backend>, FoundOf), Failure> {
    let (s, _) = session(transport, cfg).map_err(|e| {
        Failure::new(
            e.class(),
            None,
            "starting the CANopen drives",
            e.to_string(),
        )
    })?;
    let thread = CycleThread::spawn(s, None).map_err(|e| {
        Failure::new(
            ecdrive::ErrorClass::Bus,
            None,
            "starting the CANopen cycle thread",
            e.to_string(),
        )
    })?;
    let mut axes = Vec::new();
    let mut drives = Vec::new();
    for d in &cfg.drives {
        let drive = DriveRef {
            position: u16::from(d.node),
            name: d.profile.name.to_string(),
        };
        let id = d.profile.bus.identity;
        drives.push(FoundDrive {
            drive: drive.clone(),
            device: Device {
                position: u16::from(d.node),
                name: d.profile.name.to_string(),
                vendor_id: id.vendor_id,
                product_code: id.products.first().map_or(0, |p| p.0),
                revision: id.revision.unwrap_or(0),
                serial: 0,
                alias: 0,
                profile: Some(d.profile.name.to_string()),
                state: String::new(),
                is_drive: true,
            },
            dictionary: Some(d.profile.dictionary),
            velocity_scale: d.profile.units.velocity_position_per_s(),
        });
        axes.push(CanAxis {
            drive,
            errors: d.profile.caps.error_table,
        });
    }
    let bus = CanOpen {
        thread: Some(thread),
        axes,
        history: HistoryLog::new(HistoryLog::DEFAULT_CAPACITY),
        telemetry: Telemetry::default(),
    };
    Ok((Box::new(bus), (drives, Vec::new())))
}
