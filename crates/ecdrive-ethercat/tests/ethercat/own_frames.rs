//! The cycle's own frames (`CycleSettings::own_frames`, `cycle::frames`): learnt from the frames
//! ethercrab's `tx_rx_dc` sends, they put the same datagrams on the wire, carry the same
//! outputs, and the cycle reads the same inputs and states from their replies.

use crate::support;
use ecdrive_core::ec::Command;
use ecdrive_core::ec::frame::{EthercatFrame, EthernetFrame};
use ecdrive_core::link::{FrameLink, LinkError};
use ecdrive_ethercat::FramesBy;
use ecdrive_ethercat::program::RunMode;
use ecdrive_ethercat::session::{Master, MasterConfig};
use ecdrive_ethercat::startup::{DriveSetup, Selector};
use ecdrive_ethercat::telemetry::StopKind;
use ecdrive_sim::transport::SegmentLink;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use support::generic::{GENERIC_TEST, generic_segment};

/// One datagram as the wire shows it: command, address, length, and the data the master sent.
type Datagram = (u8, u32, usize, Vec<u8>);

/// A link that keeps the cycle's frames (those that begin with the reference clock's time)
/// as the master sent them.
struct Recording {
    inner: SegmentLink,
    cyclic: Arc<Mutex<Vec<Vec<Datagram>>>>,
}

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

impl FrameLink for Recording {
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let d = datagrams(frame);
        let cyclic = d.first().is_some_and(|&(cmd, address, len, _)| {
            cmd == Command::Frmw as u8 && address >> 16 == 0x0910 && len == 8
        });
        if cyclic && let Ok(mut c) = self.cyclic.lock() {
            c.push(d);
        }
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        self.inner.recv(buf, timeout)
    }
}

/// Three generic devices in csp for 100 cycles in OP, with ecdrive's frames or ethercrab's:
/// whose frames carried the image, and the cycle's frames as sent.
fn run(own_frames: bool) -> (FramesBy, Vec<Vec<Datagram>>) {
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    cfg.cycle.own_frames = own_frames;
    for p in 0..3 {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(&GENERIC_TEST),
            mode: RunMode::Csp,
            ..DriveSetup::new(Selector::Position(p))
        });
    }
    let cyclic = Arc::new(Mutex::new(Vec::new()));
    let link = Recording {
        inner: SegmentLink::new(generic_segment(3)),
        cyclic: cyclic.clone(),
    };
    let Ok(mut m) = Master::start(link, cfg) else {
        panic!("start-up failed");
    };
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let c0 = m.telemetry().cycle.cycle;
    m.wait_until("100 cycles in OP", Duration::from_secs(10), |t| {
        t.cycle.cycle > c0 + 100
    })
    .unwrap();
    let t = m.telemetry().clone();
    assert_eq!((t.cycle.wkc, t.cycle.wkc_expected), (9, 9));
    let (report, _) = m.stop(StopKind::Ramp);
    let cycle = report.unwrap().cycle.unwrap();
    let frames = cyclic.lock().unwrap().clone();
    (cycle.frames_by, frames)
}

#[test]
fn ecdrives_frames_put_ethercrabs_datagrams_on_the_wire() {
    let (by_own, own) = run(true);
    let (by_ethercrab, theirs) = run(false);
    assert_eq!(by_own, FramesBy::Ecdrive);
    assert_eq!(
        by_ethercrab,
        FramesBy::Ethercrab {
            why: "the setting asked for ethercrab's"
        }
    );
    // The same datagrams, in the same order: the system time (FRMW to the reference clock),
    // the LRW of the image, each device's AL status; the data the master sends in them is the
    // system time's zeros, the image and the status's zeros.
    let shape = |f: &[Datagram]| f.iter().map(|d| (d.0, d.1, d.2)).collect::<Vec<_>>();
    let last_own = own.last().expect("cyclic frames with ecdrive's");
    let last_theirs = theirs.last().expect("cyclic frames with ethercrab's");
    assert_eq!(shape(last_own), shape(last_theirs));
    assert_eq!(shape(last_own).len(), 1 + 1 + 3, "{:?}", shape(last_own));
    assert!(own.len() > 100 && theirs.len() > 100);
    for f in &own {
        assert_eq!(
            shape(f),
            shape(last_own),
            "every cyclic frame has the same datagrams"
        );
        assert!(
            f[0].3.iter().all(|&b| b == 0),
            "the system time goes out as zeros"
        );
    }
}
