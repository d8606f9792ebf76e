//! The cycle's own frames (`CycleSettings::own_frames`, `cycle::frames`): learnt from the frames
//! ethercrab's `tx_rx_dc` sends, they put the same datagrams on the wire, carry the same
//! outputs, and the cycle reads the same inputs and states from their replies. They add one
//! datagram of ecdrive's, a broadcast read of SM1's status, and the session reads the drives'
//! mailboxes only when it says one holds something.

use crate::support;
use ecdrive_core::ec::Command;
use ecdrive_core::ec::frame::{EthercatFrame, EthernetFrame};
use ecdrive_ethercat::FramesBy;
use ecdrive_ethercat::program::RunMode;
use ecdrive_ethercat::session::{Master, MasterConfig};
use ecdrive_ethercat::startup::{DriveSetup, Selector};
use ecdrive_ethercat::telemetry::StopKind;
use ecdrive_sim::transport::SegmentLink;
use ecdrive_testkit::links::SendTap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use support::generic::{GENERIC_TEST, generic_segment};

/// One datagram as the wire shows it: command, address, length, and the data the master sent.
type Datagram = (u8, u32, usize, Vec<u8>);

/// SM0's and SM1's status registers.
const SM_STATUS: [u32; 2] = [0x0805, 0x080D];

fn datagrams(frame: &[u8]) -> Vec<Datagram> {
    let Ok(eth) = EthernetFrame::new_checked(frame) else {
        return Vec::new();
    };
    let Ok(ecat) = EthercatFrame::new_checked(eth.payload()) else {
        return Vec::new();
    };
    ecat.datagrams()
        .map_while(Result::ok)
        .map(|d| {
            let cmd = d.command().map_or(0, |c| c as u8);
            let address = if d.command().is_some_and(Command::is_logical) {
                d.logical_address()
            } else {
                u32::from(d.adp()) | u32::from(d.ado()) << 16
            };
            (cmd, address, d.data_len(), d.data().to_vec())
        })
        .collect()
}

/// Keeps the cycle's frames (those that begin with the reference clock's time) as the master
/// sent them, and counts the reads of a mailbox SyncManager's status in the other frames (the
/// session's mailbox polls).
fn recording(
    cyclic: Arc<Mutex<Vec<Vec<Datagram>>>>,
    mailbox_looks: Arc<AtomicUsize>,
) -> impl FnMut(&mut [u8]) + Send {
    move |frame: &mut [u8]| {
        let d = datagrams(frame);
        let is_cyclic = d.first().is_some_and(|&(cmd, address, len, _)| {
            cmd == Command::Frmw as u8 && address >> 16 == 0x0910 && len == 8
        });
        if !is_cyclic {
            let looks = d
                .iter()
                .filter(|&&(cmd, address, _, _)| {
                    cmd == Command::Fprd as u8 && SM_STATUS.contains(&(address >> 16))
                })
                .count();
            mailbox_looks.fetch_add(looks, Ordering::Relaxed);
        }
        if is_cyclic && let Ok(mut c) = cyclic.lock() {
            c.push(d);
        }
    }
}

/// Three generic devices in csp for 100 cycles in OP, with ecdrive's frames or ethercrab's, the
/// mailboxes polled every 2 ms: whose frames carried the image, the cycle's frames as sent, and
/// how often the session looked at a mailbox in those 100 cycles.
fn run(own_frames: bool) -> (FramesBy, Vec<Vec<Datagram>>, usize) {
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    cfg.cycle.own_frames = own_frames;
    cfg.emergency_poll = Some(Duration::from_millis(2));
    for p in 0..3 {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            mode: RunMode::Csp,
            ..DriveSetup::new(Selector::Position(p))
        });
    }
    let cyclic = Arc::new(Mutex::new(Vec::new()));
    let mailbox_looks = Arc::new(AtomicUsize::new(0));
    let link = SendTap::new(
        SegmentLink::new(generic_segment(3)),
        recording(cyclic.clone(), mailbox_looks.clone()),
    );
    let Ok(mut m) = Master::start(link, cfg) else {
        panic!("start-up failed");
    };
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    // Past the first cycles in OP, when the session's first poll (which also reads each
    // drive's mailbox SyncManagers) may still be under way.
    let c0 = m.telemetry().cycle.cycle;
    m.wait_until("20 cycles in OP", Duration::from_secs(10), |t| {
        t.cycle.cycle > c0 + 20
    })
    .unwrap();
    let looks0 = mailbox_looks.load(Ordering::Relaxed);
    let c1 = m.telemetry().cycle.cycle;
    m.wait_until("100 cycles more", Duration::from_secs(10), |t| {
        t.cycle.cycle > c1 + 100
    })
    .unwrap();
    let looks = mailbox_looks.load(Ordering::Relaxed) - looks0;
    let t = m.telemetry().clone();
    assert_eq!((t.cycle.wkc, t.cycle.wkc_expected), (9, 9));
    let (report, _) = m.stop(StopKind::Ramp);
    let cycle = report.unwrap().cycle.unwrap();
    let frames = cyclic.lock().unwrap().clone();
    (cycle.frames_by, frames, looks)
}

#[test]
fn ecdrives_frames_put_ethercrabs_datagrams_on_the_wire() {
    let (by_own, own, own_looks) = run(true);
    let (by_ethercrab, theirs, their_looks) = run(false);
    assert_eq!(by_own, FramesBy::Ecdrive);
    assert_eq!(
        by_ethercrab,
        FramesBy::Ethercrab {
            why: "the setting asked for ethercrab's"
        }
    );
    // The same datagrams, in the same order: the system time (FRMW to the reference clock),
    // the LRW of the image, each device's AL status; the data the master sends in them is the
    // system time's zeros, the image and the status's zeros. Then ecdrive's own: a BRD of SM1's
    // status, one byte.
    let shape = |f: &[Datagram]| f.iter().map(|d| (d.0, d.1, d.2)).collect::<Vec<_>>();
    let last_own = own.last().expect("cyclic frames with ecdrive's");
    let last_theirs = theirs.last().expect("cyclic frames with ethercrab's");
    let mut expected = shape(last_theirs);
    expected.push((Command::Brd as u8, 0x080D << 16, 1));
    assert_eq!(shape(last_own), expected);
    assert_eq!(
        shape(last_theirs).len(),
        1 + 1 + 3,
        "{:?}",
        shape(last_theirs)
    );
    // No device had anything in its mailbox: with ecdrive's frames the session did not look,
    // with ethercrab's it looked at every drive's mailbox every 2 ms.
    assert_eq!(own_looks, 0);
    assert!(their_looks >= 3 * 10, "{their_looks}");
    assert!(own.len() > 100 && theirs.len() > 100);
    // ethercrab's first (the cycle learns from it; a few when a mailbox frame came between),
    // then ecdrive's, every one with the same datagrams.
    let learning = own
        .iter()
        .take_while(|f| shape(f) == shape(last_theirs))
        .count();
    assert!((1..=5).contains(&learning), "{learning}");
    for (k, f) in own.iter().enumerate() {
        if k >= learning {
            assert_eq!(
                shape(f),
                shape(last_own),
                "every cyclic frame has the same datagrams"
            );
        }
        assert!(
            f[0].3.iter().all(|&b| b == 0),
            "the system time goes out as zeros"
        );
    }
}
