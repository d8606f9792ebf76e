//! The operator shared by `ecdrive demo` and `ecdrive soak` (`master::recovery::Operator`):
//! it enables the axes and runs their programs, and after a drive fault in the middle of a
//! program (the other axis stopped by the master) it resets the fault, enables both axes and
//! runs the programs again to their end — counting one recovery and one completed program, and
//! nothing unhandled.

use ecdrive::cia402::State;
use ecdrive::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive::master::session::{HistoryKind, Master, MasterConfig};
use ecdrive::master::startup::{DriveSetup, Selector};
use ecdrive::master::telemetry::StopKind;
use ecdrive::rt::RtSettings;
use ecdrive::sim::drives::{EmulatedDrive, spec_for};
use ecdrive::sim::faults::{DeviceFault, Fault};
use ecdrive::sim::transport::SegmentLink;
use ecdrive::sim::{EscConfig, HostClock, Segment};
use ecdrive_cli::app::ethercat::demo;
use ecdrive_cli::app::ethercat::recovery::{self, Operator};
use std::sync::Arc;
use std::time::{Duration, Instant};

const PROFILES: [&DriveProfile; 2] = [&mr_j4_tm::PROFILE, &bdhde::PROFILE];

#[test]
fn after_a_drive_alarm_mid_program_the_operator_recovers_and_the_programs_complete() {
    // Without the drives' own loss supervision: the alarm here is the injected one (a stall
    // of the test machine would add its own, which the operator would handle too, but the
    // counts below would differ).
    let mut seg = Segment::new(Arc::new(HostClock));
    for (i, p) in PROFILES.iter().enumerate() {
        let d = EmulatedDrive::new(spec_for(p.key).unwrap(), 4000 + i as u32)
            .unwrap()
            .without_loss_detection();
        seg.push(Box::new(d), EscConfig::default()).unwrap();
    }
    let mut faults = seg.fault_handle();
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    cfg.cycle.rt = RtSettings {
        priority: Some(80),
        cpu: None,
        lock_memory: false,
    };
    for (i, p) in PROFILES.iter().enumerate() {
        cfg.startup.drives.push(DriveSetup {
            program: demo::program(p),
            ..DriveSetup::new(Selector::Position(i as u16))
        });
    }
    let steps: Vec<usize> = PROFILES.iter().map(|p| demo::program(p).len()).collect();
    let mut m = Master::start(SegmentLink::new(seg), cfg).unwrap();
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();

    let mut op = Operator::new(steps);
    let mut injected = false;
    let mut unhandled = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(40);
    while op.programs_completed == 0 {
        assert!(Instant::now() < deadline, "{:?}", m.telemetry().axes);
        std::thread::sleep(recovery::POLL);
        let t = m.telemetry().clone();
        // The alarm once both axes are in the csv part of the program (mode 9).
        if !injected
            && t.axes.iter().all(|a| {
                a.program_running && a.mode_display == 9 && a.state == Some(State::OperationEnabled)
            })
        {
            faults
                .inject(Fault::Device {
                    position: 1,
                    fault: DeviceFault::RaiseAlarm("J3"),
                })
                .unwrap();
            injected = true;
        }
        unhandled.extend(op.step(&mut m, &t).unwrap());
    }
    assert!(injected);
    assert!(unhandled.is_empty(), "{unhandled:#?}");
    assert_eq!(op.recoveries, 1);
    assert_eq!(op.programs_completed, 1);
    let (r, _) = m.stop(StopKind::Ramp);
    let r = r.unwrap();
    assert!(r.shutdown_ok);
    let faults: Vec<_> = r
        .history
        .iter()
        .filter(|h| h.kind == HistoryKind::DriveFault)
        .collect();
    // The BDHDE's excessive position error, in its own table's words: J3 (FLT 87).
    assert!(
        faults.len() == 1 && faults[0].resolved.fault.map(|d| d.name) == Some("J3 (FLT 87)"),
        "{faults:#?}"
    );
    assert!(
        !r.history.iter().any(|h| recovery::unhandled_kind(h.kind)),
        "{:#?}",
        r.history
    );
}
