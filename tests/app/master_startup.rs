//! Start-up against emulated devices, in-process: discovery, profile matching, validation before
//! any write, PRE-OP configuration over CoE, DC settling and SAFE-OP.

use crate::support;
use ecdrive::master::bus::{BusOptions, run_session as with_bus};
use ecdrive::master::error::ErrorKind;
use ecdrive::master::program::RunMode;
use ecdrive::master::startup::{self, DriveSetup, Selector, StartupConfig};
use ecdrive::od::ObjectAddress;
use ecdrive::pdo::{Mapping, Pdo, PdoEntry};
use ecdrive::sim::Segment;
use ecdrive::sim::devices::GenericCoeDevice;
use ecdrive::sim::devices::TEST_VENDOR_ID;
use ecdrive::sim::devices::generic_coe::GENERIC_COE_PRODUCT;
use ecdrive::sim::transport::SegmentLink;
use std::time::Duration;
use support::generic::{GENERIC_TEST, TX, generic_segment};

fn segment(n: usize) -> Segment {
    generic_segment(n)
}

fn config(n: usize) -> StartupConfig {
    let mut cfg = StartupConfig::new(Duration::from_millis(1));
    for p in 0..n {
        cfg.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            ..DriveSetup::new(Selector::Position(p as u16))
        });
    }
    cfg
}

#[test]
fn reaches_safe_op_with_dc_and_the_configured_image() {
    let cfg = config(3);
    let (r, link) = with_bus(
        SegmentLink::new(segment(3)),
        BusOptions::default(),
        move |bus| {
            let (group, devices) = startup::discover(bus)?;
            assert_eq!(devices.len(), 3);
            assert!(
                devices
                    .iter()
                    .all(|d| d.dc && d.vendor_id == TEST_VENDOR_ID)
            );
            let plan = startup::assign_roles(&devices, &cfg)?;
            let started = startup::configure(bus, group, devices, plan, &cfg)?;
            Ok::<_, ecdrive::master::error::MasterError>(
                started
                    .drives
                    .iter()
                    .map(|d| {
                        (
                            d.layout.bytes(ecdrive::pdo::Direction::Rx),
                            d.layout.bytes(ecdrive::pdo::Direction::Tx),
                        )
                    })
                    .collect::<Vec<_>>(),
            )
        },
    )
    .unwrap();
    let sizes = r.unwrap();
    assert_eq!(sizes, vec![(6, 6); 3]);
    // Every device ended in SAFE-OP with the cycle time written over CoE.
    for p in 0..3 {
        let dev = link.segment().device::<GenericCoeDevice>(p).unwrap();
        assert_eq!(
            dev.od().dict().uint(ObjectAddress::new(0x1C32, 2)),
            Some(1_000_000)
        );
        // The device's download counter counts (the refused case below reads 0 from it).
        assert!(dev.coe_stats().downloads_accepted > 0);
        assert_eq!(
            link.segment().slave(p).unwrap().esc.al_state(),
            ecdrive::ec::AlState::SafeOp
        );
    }
}

/// A device no profile matches is not driven unless the configuration asks for it: it is an
/// I/O device, and the reason says why (here: a CiA 402 device, device type 0x…0192, that
/// `allow_generic` would run). A configuration that names it as a drive gets an error naming
/// its identity.
#[test]
fn unknown_devices_are_named_with_their_identity() {
    let cfg = StartupConfig::new(Duration::from_millis(1));
    let mut named = cfg.clone();
    named
        .drives
        .push(startup::DriveSetup::new(startup::Selector::Position(0)));
    let (r, _) = with_bus(
        SegmentLink::new(segment(2)),
        BusOptions::default(),
        move |bus| {
            let (_group, devices) = startup::discover(bus).unwrap();
            assert!(devices.iter().all(|d| d.coe && d.declares_cia402()));
            let roles = startup::assign_roles(&devices, &cfg).unwrap();
            for r in &roles {
                match r {
                    startup::Role::Io { why } => {
                        assert!(why.contains("allow_generic"), "{why}")
                    }
                    other => panic!("{other:?}"),
                }
            }
            startup::assign_roles(&devices, &named).map(|_| ())
        },
    )
    .unwrap();
    let e = r.unwrap_err();
    assert_eq!(e.kind, ErrorKind::UnknownDevice);
    let text = e.to_string();
    assert!(
        text.starts_with(
            "drive 0 (ECD-COE402): matching a drive profile: unknown device: vendor 0x00000ECD"
        ),
        "{text}"
    );
    assert!(
        text.contains(&format!("product 0x{GENERIC_COE_PRODUCT:08X}")),
        "{text}"
    );
}

#[test]
fn a_mapping_over_the_limit_is_refused_before_anything_is_written() {
    static BIG: &[Pdo] = &[Pdo::fixed(
        0x1600,
        &[
            PdoEntry::new(0x6040, 0, 16),
            PdoEntry::new(0x607A, 0, 32),
            PdoEntry::new(0x60FF, 0, 32),
            PdoEntry::new(0x6060, 0, 8),
            PdoEntry::padding(8),
            PdoEntry::padding(8),
            PdoEntry::padding(8),
            PdoEntry::padding(8),
            PdoEntry::padding(8),
        ],
    )];
    let mut cfg = config(1);
    cfg.drives[0].mapping = Some(Mapping::fixed(BIG, TX));
    let (r, link) = with_bus(
        SegmentLink::new(segment(1)),
        BusOptions::default(),
        move |bus| {
            let (group, devices) = startup::discover(bus).unwrap();
            let plan = startup::assign_roles(&devices, &cfg).unwrap();
            startup::configure(bus, group, devices, plan, &cfg).map(|_| ())
        },
    )
    .unwrap();
    let e = r.unwrap_err();
    assert_eq!(e.kind, ErrorKind::Config);
    assert!(e.to_string().contains("0x1600 has 9 entries"), "{e}");
    // Nothing was written: the device accepted no SDO download at all (its own counter), and
    // still has its power-on assignment and no cycle time.
    let dev = link.segment().device::<GenericCoeDevice>(0).unwrap();
    assert_eq!(dev.coe_stats().downloads_accepted, 0);
    assert_eq!(dev.od().dict().uint(ObjectAddress::new(0x1C32, 2)), Some(0));
    assert_eq!(dev.od().dict().uint(ObjectAddress::new(0x1600, 0)), Some(2));
}

#[test]
fn a_cycle_time_the_drive_does_not_accept_is_refused() {
    let mut cfg = config(1);
    cfg.cycle = Duration::from_micros(300);
    cfg.drives[0].mode = RunMode::Csp;
    let (r, _) = with_bus(
        SegmentLink::new(segment(1)),
        BusOptions::default(),
        move |bus| {
            let (group, devices) = startup::discover(bus).unwrap();
            let plan = startup::assign_roles(&devices, &cfg).unwrap();
            startup::configure(bus, group, devices, plan, &cfg).map(|_| ())
        },
    )
    .unwrap();
    let e = r.unwrap_err();
    assert_eq!(
        e.to_string(),
        "drive 0 (generic test device): checking the cycle time: 300 µs is not a cycle time the generic test device accepts (250–10000 µs in 250 µs steps)"
    );
}

/// Outputs count from SAFE-OP on (ETG.1020: the master checks that the slave updates inputs
/// and outputs before switching it to OP): a device whose stack takes its outputs only in OP
/// (`outputs-only-in-op`) is named before OP is requested, with the working counter expected
/// and seen; the same segment without it runs. The drives' loss supervision is off: a stall of
/// a shared CI machine faulted the MR-J4-TM once (AL.86), which says nothing about SAFE-OP.
#[test]
fn a_device_that_takes_no_outputs_in_safe_op_is_named_before_op() {
    use ecdrive_cli::app::ethercat::tools::run::{Outcome, RunOptions, run};
    let config = |second: &str| {
        format!(
            "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"mr-j4-tm\", \"{second}\"]\n\
             loss_detection = false\n[[drive]]\nposition = 0\nmode = \"csp\"\nprogram = [{{ step = \"move\", by = 0.05, \
             velocity = 1, acceleration = 10 }}]\n[[drive]]\nposition = 1\nmode = \"csp\"\n\
             program = [{{ step = \"move\", by = 0.5, velocity = 10, acceleration = 100 }}]\n"
        )
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let cfg =
        ecdrive_cli::app::config::parse(&config("bdhde+outputs-only-in-op"), "q.toml").unwrap();
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap();
    assert_eq!(r.outcome, Outcome::Refused, "{}", r.reason);
    assert!(
        r.reason.starts_with("drive 1 (BDHDE): in SAFE-OP its process data is not taken: working counter 4, expected 6"),
        "{}",
        r.reason
    );
    let cfg = ecdrive_cli::app::config::parse(&config("bdhde"), "q.toml").unwrap();
    let r = run(&cfg, &RunOptions::default(), &stop, &mut |_| {}).unwrap();
    assert_eq!(r.outcome, Outcome::Completed, "{}", r.reason);
}
