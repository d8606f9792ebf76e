//! Shared by the master tests: a profile for the sim's generic CoE test device, and segment
//! builders.
#![allow(dead_code)]

use ecdrive_core::cia402::VelocityUnit;
use ecdrive_core::cia402::{DriveCaps, SupportedModes};
use ecdrive_core::drives::{
    CycleTimeObject, CycleTimes, DriveProfile, EtherCat, IdentityMatch, SyncSpec, Units,
};
use ecdrive_core::od::ObjectAddress;
use ecdrive_core::pdo::{DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange};
use ecdrive_sim::devices::generic_coe::{GENERIC_COE_PRODUCT, OBJECTS};
use ecdrive_sim::devices::{GenericCoeDevice, TEST_VENDOR_ID};
use ecdrive_sim::{EscConfig, HostClock, Segment};
use std::sync::Arc;

static RANGES_RX: &[PdoRange] = &[PdoRange::new(0x1600, 0x1601, 8)];
static RANGES_TX: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A01, 8)];
pub static RX: &[Pdo] = &[Pdo::fixed(
    0x1600,
    &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)],
)];
pub static TX: &[Pdo] = &[Pdo::fixed(
    0x1A00,
    &[PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6064, 0, 32)],
)];

/// A profile for the sim's generic CoE test device, as a test would write one for a new drive.
pub static GENERIC_TEST: DriveProfile = DriveProfile {
    name: "generic test device",
    vendor: "ecdrive",
    caps: DriveCaps {
        supported_modes: SupportedModes::ALL_STANDARD,
        ..DriveCaps::CIA402
    },
    dictionary: OBJECTS,
    units: Units {
        position_name: "increment",
        position_per_rev: 1.0,
        velocity: VelocityUnit::PositionPerSecond,
        torque_per_mille: 1.0,
        profile: None,
    },
    bus: EtherCat {
        key: "generic-test",
        identity: IdentityMatch {
            vendor_id: TEST_VENDOR_ID,
            product_code: GENERIC_COE_PRODUCT,
        },
        revision: 1,
        pdo_limits: PdoLimits {
            drive: "generic test device",
            rx: DirectionLimits {
                pdos: RANGES_RX,
                max_assigned: 2,
                max_entries: 16,
                max_bytes: 64,
            },
            tx: DirectionLimits {
                pdos: RANGES_TX,
                max_assigned: 2,
                max_entries: 16,
                max_bytes: 64,
            },
            assignment_writable: true,
        },
        default_mapping: Mapping::fixed(RX, TX),
        cyclic_mapping: Mapping::fixed(RX, TX),
        mode_mappings: &[],
        required_objects: &[],
        startup: &[],
        init_cmds: &[],
        output_defaults: &[],
        cycle_counter: None,
        sync: SyncSpec {
            free_run: true,
            dc_sync0: true,
            cycle_times: CycleTimes::Range {
                min_ns: 250_000,
                max_ns: 10_000_000,
                step_ns: 250_000,
            },
            assign_activate: 0x0300,
            sync_type_object: Some(ObjectAddress::new(0x1C32, 1)),
            cycle_time_object: Some(CycleTimeObject::Nanoseconds(ObjectAddress::new(0x1C32, 2))),
        },
        complete_access: false,
        esi: "",
        zero_speed_flag: None,
        mode_selector: None,
        ratings: ecdrive_core::drives::Ratings::NONE,
    },
};

/// A segment of `n` generic CoE devices (SM watchdog off: CI machines stall).
pub fn generic_segment(n: usize) -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for i in 0..n {
        seg.push(
            Box::new(GenericCoeDevice::new(700 + i as u32).unwrap()),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

/// A link whose cable can be pulled: while pulled, frames go nowhere and nothing comes back.
pub struct PullableLink<L> {
    pub inner: L,
    pub pulled: Arc<std::sync::atomic::AtomicBool>,
}

impl<L: ecdrive_core::link::FrameLink> ecdrive_core::link::FrameLink for PullableLink<L> {
    fn send(&mut self, frame: &[u8]) -> Result<(), ecdrive_core::link::LinkError> {
        if self.pulled.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(());
        }
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<std::time::Duration>,
    ) -> Result<Option<usize>, ecdrive_core::link::LinkError> {
        if self.pulled.load(std::sync::atomic::Ordering::Relaxed) {
            if let Some(t) = timeout {
                std::thread::sleep(t.min(std::time::Duration::from_millis(1)));
            }
            return Ok(None);
        }
        self.inner.recv(buf, timeout)
    }
}
