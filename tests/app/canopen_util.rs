//! Shared helpers of the CANopen integration tests: a master on the simulated bus with emulated
//! drives, configured and enabled through the public API.
#![allow(dead_code)]

use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig, MasterEvent};
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::od::{ObjectAddress, Value};
use ecdrive::sim::canopen::{EmulatedNode, SimBus};
use ecdrive_cli::app::canopen::steps;

/// Simulated-time timeout for one step, µs.
pub const T: u64 = 20_000_000;

/// A master on a simulated bus with `nodes`, after their boot-up messages.
pub fn bus(nodes: &[(&'static CanDriveProfile, u8)]) -> Master<SimBus> {
    bus_with(nodes, MasterConfig::default())
}

/// The same with a master configuration.
pub fn bus_with(nodes: &[(&'static CanDriveProfile, u8)], cfg: MasterConfig) -> Master<SimBus> {
    let mut sim = SimBus::new();
    for (p, id) in nodes {
        sim.add_node(
            EmulatedNode::new(
                ecdrive_cli::app::canopen::tools::emulation_of(p)
                    .expect("the software slave emulates the drive"),
                *id,
            )
            .unwrap(),
        );
    }
    let mut m = Master::new(sim, cfg);
    m.pump(20_000).unwrap();
    m
}

/// The standard setup with the demo's motion settings.
pub fn setup(p: &'static CanDriveProfile) -> DriveSetup {
    let mut s = DriveSetup::new(p);
    s.settings = steps::motion_settings(p, 10.0, 100.0);
    s
}

/// Configured, started and enabled.
pub fn ready(p: &'static CanDriveProfile, id: u8) -> Master<SimBus> {
    let mut m = bus(&[(p, id)]);
    m.configure_drive(id, setup(p)).unwrap();
    m.start(id).unwrap();
    m.enable(id, T).unwrap();
    m
}

/// Drain the master's events.
pub fn events(m: &mut Master<SimBus>) -> Vec<MasterEvent> {
    let mut v = Vec::new();
    while let Some(e) = m.poll_event() {
        v.push(e);
    }
    v
}

/// An object of the emulated node, as an integer.
pub fn node_int(m: &Master<SimBus>, id: u8, index: u16, sub: u8) -> i64 {
    m.transport()
        .node(id)
        .unwrap()
        .int(ObjectAddress::new(index, sub))
        .unwrap()
}

/// Write an object of the emulated node over SDO through the master.
pub fn write(m: &mut Master<SimBus>, id: u8, index: u16, sub: u8, v: Value) {
    m.download_value(id, ObjectAddress::new(index, sub), &v, None)
        .unwrap();
}
