//! Fault injection at the slave level (issue 8): each fault's effect as a master sees it on the
//! wire, through raw frames on an in-process segment with a manual clock (no host time, no
//! timed assertions): lost frames on either leg, a seeded drop fraction, delayed replies, each
//! kind of corruption, a pulled cable with the SM watchdog and the drives' loss-of-data alarms,
//! a local reset to INIT, a drifting clock, an injected SDO abort and an emergency in the middle
//! of a segmented SDO transfer.

use crate::support::wire;

use ecdrive_core::cia402::State;
use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive_core::ec::Command;
use ecdrive_core::ec::frame::{EthercatFrame, EthernetFrame, FrameBuilder, physical_address};
use ecdrive_core::ec::mailbox::{MailboxMessage, SdoRequest, SdoResponse};
use ecdrive_core::link::FrameLink;
use ecdrive_sim::devices::generic_coe::USER_TEXT_LEN;
use ecdrive_sim::devices::{GenericCoeDevice, IoDevice};
use ecdrive_sim::faults::{Corruption, DeviceFault, DropLeg, Fault, LinkFault, SlaveFault};
use ecdrive_sim::probe::{PROBE_MAC, Probe, ProbeError};
use ecdrive_sim::transport::SegmentLink;
use ecdrive_sim::{EscConfig, ManualClock, Segment, SegmentError};
use std::sync::Arc;
use std::time::Duration;
use wire::{Wire, cyclic};

const T0: u64 = 1_000_000_000_000;
const ST: u16 = 0x1000;

fn io_segment(n: usize) -> (Segment, ManualClock) {
    let clock = ManualClock::new(T0);
    let mut seg = Segment::new(Arc::new(clock.clone()));
    for i in 0..n {
        seg.push(
            Box::new(IoDevice::new(2, 4).with_serial(i as u32)),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    (seg, clock)
}

fn link(fault: LinkFault) -> Fault {
    Fault::Link(fault)
}

fn lost(r: Result<ecdrive_sim::probe::Reply, ProbeError>) -> Option<SegmentError> {
    match r {
        Err(ProbeError::Segment(e)) => Some(e),
        Ok(_) => None,
        Err(e) => panic!("unexpected probe error {e}"),
    }
}

/// A BRD frame of one byte with datagram index `idx`.
fn brd_frame(idx: u8) -> Vec<u8> {
    let mut buf = vec![0u8; 64];
    let mut b = FrameBuilder::new(&mut buf, PROBE_MAC).unwrap();
    b.push(Command::Brd, idx, physical_address(0, 0x0000), &[0])
        .unwrap();
    let n = b.finish();
    buf.truncate(n);
    buf
}

/// (index, working counter) of the first datagram of a reply.
fn first_datagram(frame: &[u8]) -> (u8, u16) {
    let eth = EthernetFrame::new_checked(frame).unwrap();
    let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
    let d = ec.datagrams().next().unwrap().unwrap();
    (d.index(), d.wkc())
}

// ------------------------------------------------------------------------------- dropping

#[test]
fn a_frame_dropped_on_the_way_out_is_never_seen_and_one_dropped_on_the_way_back_is() {
    let (seg, _) = io_segment(2);
    let mut p = Probe::new(seg);
    // Through the lock-free handle, as a test thread would.
    let mut h = p.segment.fault_handle();
    h.inject(link(LinkFault::DropNext(1))).unwrap();
    // Lost on the way out: the station address is not written.
    let e = lost(p.apwr(0, 0x0010, &ST.to_le_bytes()));
    assert_eq!(
        e,
        Some(SegmentError::Lost {
            reached_slaves: false
        })
    );
    assert_eq!(p.aprd(0, 0x0010, 2).unwrap().data, vec![0, 0]);
    // Lost on the way back: no reply, but the slave applied the write.
    h.inject(link(LinkFault::DropOn(DropLeg::Return))).unwrap();
    h.inject(link(LinkFault::DropNext(1))).unwrap();
    let e = lost(p.apwr(0, 0x0010, &ST.to_le_bytes()));
    assert_eq!(
        e,
        Some(SegmentError::Lost {
            reached_slaves: true
        })
    );
    let r = p.aprd(0, 0x0010, 2).unwrap();
    assert_eq!((r.data, r.wkc), (ST.to_le_bytes().to_vec(), 1));
    let s = p.segment.stats();
    assert_eq!((s.dropped, s.dropped_replies), (2, 1));
    assert_eq!(s.faults_applied, 3);
}

#[test]
fn drop_fraction_is_about_the_fraction_and_reproducible() {
    let run = |seed: u64| {
        let (mut seg, _) = io_segment(1);
        seg.apply(&link(LinkFault::Seed(seed)));
        seg.apply(&link(LinkFault::DropFraction(0.1)));
        let mut frame = brd_frame(1);
        let pattern: Vec<bool> = (0..10_000)
            .map(|_| match seg.process(&mut frame) {
                Ok(_) => false,
                Err(SegmentError::Lost { .. }) => true,
                Err(e) => panic!("{e}"),
            })
            .collect();
        (pattern, seg.stats())
    };
    let (a, stats) = run(42);
    let n = a.iter().filter(|&&l| l).count() as u64;
    // Binomial(10 000, 0.1): standard deviation 30; ±150 is five of them.
    assert!((850..=1150).contains(&n), "{n} of 10 000 dropped");
    assert_eq!(stats.dropped, n);
    assert_eq!(stats.frames, 10_000 - n);
    // Same seed, same frames lost; another seed, others.
    assert_eq!(run(42).0, a);
    assert_ne!(run(43).0, a);
    // 0.0 ends it.
    let (mut seg, _) = io_segment(1);
    seg.apply(&link(LinkFault::DropFraction(1.0)));
    assert!(seg.process(&mut brd_frame(1)).is_err());
    seg.apply(&link(LinkFault::DropFraction(0.0)));
    assert!((0..100).all(|_| seg.process(&mut brd_frame(1)).is_ok()));
}

// -------------------------------------------------------------------------------- delay

#[test]
fn a_delayed_reply_arrives_after_the_delay_on_the_segment_clock() {
    let (seg, clock) = io_segment(2);
    let mut l = SegmentLink::new(seg);
    let mut rx = [0u8; 1600];
    l.segment_mut().apply(&link(LinkFault::Delay {
        fraction: 1.0,
        delay_ns: 200_000,
    }));
    l.send(&brd_frame(7)).unwrap();
    // Not before its time (a zero timeout never sleeps).
    assert_eq!(l.recv(&mut rx, Some(Duration::ZERO)).unwrap(), None);
    clock.advance(199_999);
    assert_eq!(l.recv(&mut rx, Some(Duration::ZERO)).unwrap(), None);
    assert_eq!(l.pending_replies(), 1);
    clock.advance(1);
    let n = l
        .recv(&mut rx, Some(Duration::ZERO))
        .unwrap()
        .expect("due now");
    assert_eq!(first_datagram(&rx[..n]), (7, 2));

    // The slaves process a delayed frame on time; a later, undelayed frame overtakes its
    // reply.
    let mut f = vec![0u8; 64];
    let mut b = FrameBuilder::new(&mut f, PROBE_MAC).unwrap();
    b.push(
        Command::Apwr,
        8,
        physical_address(0, 0x0010),
        &ST.to_le_bytes(),
    )
    .unwrap();
    let len = b.finish();
    l.send(&f[..len]).unwrap();
    l.segment_mut().apply(&link(LinkFault::Delay {
        fraction: 0.0,
        delay_ns: 0,
    }));
    let mut b = FrameBuilder::new(&mut f, PROBE_MAC).unwrap();
    b.push(Command::Fprd, 9, physical_address(ST, 0x0010), &[0, 0])
        .unwrap();
    let len = b.finish();
    l.send(&f[..len]).unwrap();
    let n = l
        .recv(&mut rx, Some(Duration::ZERO))
        .unwrap()
        .expect("undelayed");
    assert_eq!(first_datagram(&rx[..n]), (9, 1), "address already written");
    assert_eq!(l.recv(&mut rx, Some(Duration::ZERO)).unwrap(), None);
    clock.advance(200_000);
    let n = l
        .recv(&mut rx, Some(Duration::ZERO))
        .unwrap()
        .expect("late");
    assert_eq!(first_datagram(&rx[..n]), (8, 1));
    assert_eq!(l.segment().stats().delayed, 2);
}

// ----------------------------------------------------------------------------- corruption

#[test]
fn a_corrupted_datagram_is_detectably_wrong_and_only_the_next_n_are() {
    let (mut seg, _) = io_segment(3);
    let good = {
        let mut f = brd_frame(5);
        seg.process(&mut f).unwrap();
        f
    };
    assert_eq!(first_datagram(&good), (5, 3));
    let corrupted = |seg: &mut Segment, c: Corruption| {
        seg.apply(&link(LinkFault::CorruptWith(c)));
        seg.apply(&link(LinkFault::CorruptNext(2)));
        let out: Vec<Vec<u8>> = (0..3)
            .map(|_| {
                let mut f = brd_frame(5);
                seg.process(&mut f).unwrap();
                f
            })
            .collect();
        // Two corrupted, then good again.
        assert_eq!(out[0], out[1]);
        assert_eq!(out[2], good, "{c:?}: only the next 2 frames");
        assert_ne!(out[0], good, "{c:?}");
        out[0].clone()
    };
    // Working counter: the count is not what the slaves produced.
    let f = corrupted(&mut seg, Corruption::WorkingCounter);
    assert_eq!(first_datagram(&f), (5, 3 ^ 0x8000));
    // Index: no longer the request's.
    let f = corrupted(&mut seg, Corruption::Index);
    assert_eq!(first_datagram(&f), (5 ^ 0x80, 3));
    // Command: a reserved code.
    let f = corrupted(&mut seg, Corruption::Command);
    let eth = EthernetFrame::new_checked(&f[..]).unwrap();
    let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
    assert_eq!(ec.datagrams().next().unwrap().unwrap().command(), None);
    // Length: the frame no longer parses.
    let f = corrupted(&mut seg, Corruption::Length);
    let eth = EthernetFrame::new_checked(&f[..]).unwrap();
    let parsed = EthercatFrame::new_checked(eth.payload()).and_then(|ec| ec.check());
    assert!(parsed.is_err(), "{parsed:?}");
    // Data: every byte inverted, header and working counter intact.
    let f = corrupted(&mut seg, Corruption::Data);
    let eth = EthernetFrame::new_checked(&f[..]).unwrap();
    let ec = EthercatFrame::new_checked(eth.payload()).unwrap();
    let d = ec.datagrams().next().unwrap().unwrap();
    let eth_good = EthernetFrame::new_checked(&good[..]).unwrap();
    let ec_good = EthercatFrame::new_checked(eth_good.payload()).unwrap();
    let g = ec_good.datagrams().next().unwrap().unwrap();
    assert_eq!((d.index(), d.wkc()), (g.index(), g.wkc()));
    assert_eq!(d.data(), &[!g.data()[0]]);
    assert_eq!(seg.stats().corrupted, 10);
}

// ---------------------------------------------------------------------------- cable pull

fn enabled(p: &DriveProfile) -> Wire {
    let mut w = Wire::op_cyclic(&[p], 1_000_000);
    let pos = cyclic::position(w.inputs(0));
    let o = w.outputs_mut(0);
    cyclic::set_mode(o, 8);
    cyclic::set_target(o, pos);
    for cw in [0x0006, 0x0007, 0x000F] {
        w.command(0, cw);
    }
    assert_eq!(w.state(0), State::OperationEnabled);
    w
}

fn al_status(w: &mut Wire) -> (u16, u16) {
    let r = w.p.fprd(ST, 0x0130, 6).unwrap();
    assert_eq!(r.wkc, 1);
    let g = |i: usize| u16::from_le_bytes([r.data[i], r.data[i + 1]]);
    (g(0), g(4))
}

/// A pulled cable: the slaves stay powered, SYNC0 keeps firing, so each drive raises its
/// loss-of-data alarm (MR-J4-TM [AL. 86.1] after 7 ms, BDHDE Fb8 / 0x818D after 7 ms \[REC\]);
/// the SM watchdog (100 ms) takes the ESC to SAFE-OP with 0x001B. With the cable back the
/// slave answers again and reports all of it.
#[test]
fn cable_pull_trips_watchdog_and_drive_alarm_and_reconnect_answers_again() {
    for (profile, alarm) in [(&mr_j4_tm::PROFILE, "AL.86.1"), (&bdhde::PROFILE, "Fb8")] {
        let mut w = enabled(profile);
        // SM watchdog at its ESC reset value (100 ms): armed by the next outputs.
        assert_eq!(w.p.fpwr(ST, 0x0420, &1000u16.to_le_bytes()).unwrap().wkc, 1);
        w.cycle();
        w.p.segment.apply(&link(LinkFault::Disconnect));
        assert!(w.p.segment.is_disconnected());
        let image = w.image.clone();
        let mut alarm_at = None;
        for ms in 1..=150u32 {
            let e = lost(w.p.logical(Command::Lrw, 0, &image));
            assert_eq!(e, Some(SegmentError::Disconnected), "{}", profile.name);
            w.skip_cycle();
            if alarm_at.is_none() && w.drive(0).alarm().is_some() {
                alarm_at = Some(ms);
            }
        }
        let name = profile.name;
        assert_eq!(w.drive(0).alarm().map(|a| a.id), Some(alarm), "{name}");
        assert!(alarm_at.is_some_and(|ms| ms <= 10), "{name}: {alarm_at:?}");
        assert_eq!(w.drive(0).state(), State::Fault, "{name}: power stage off");
        let esc = &w.p.segment.slave(0).unwrap().esc;
        assert_eq!(
            (esc.al_state(), esc.al_error(), esc.al_status_code().0),
            (ecdrive_core::ec::AlState::SafeOp, true, 0x001B),
            "{name}"
        );
        // Nothing answered while the cable was out.
        assert_eq!(w.p.segment.stats().lost_disconnected, 150);
        // Reconnect: answers again, and the master reads what happened.
        w.p.segment.apply(&link(LinkFault::Reconnect));
        assert_eq!(al_status(&mut w), (0x0014, 0x001B), "{name}");
        // The master acknowledges, goes back to OP and resets the fault.
        assert_eq!(w.request_ack(0, 0x0004), (0x0004, 0));
        w.activate_dc(1_000_000);
        assert_eq!(w.request(0, 0x0008), (0x0008, 0), "{name}");
        w.cycle();
        assert_eq!(w.state(0), State::Fault);
        w.command(0, 0x0000);
        w.command(0, 0x0080);
        assert_eq!(w.state(0), State::SwitchOnDisabled, "{name}: fault reset");
    }
}

/// Reconnect arrives through the handle while no frames flow: the segment's poll applies it.
#[test]
fn faults_apply_on_poll_while_no_frame_arrives() {
    let (mut seg, _) = io_segment(1);
    let mut h = seg.fault_handle();
    h.inject(link(LinkFault::Disconnect)).unwrap();
    seg.poll();
    assert!(seg.is_disconnected());
    assert_eq!(
        seg.process(&mut brd_frame(1)),
        Err(SegmentError::Disconnected)
    );
    h.inject(link(LinkFault::Reconnect)).unwrap();
    seg.poll();
    assert!(!seg.is_disconnected());
    assert!(seg.process(&mut brd_frame(1)).is_ok());
}

// -------------------------------------------------------------------------- slave faults

#[test]
fn reset_to_init_falls_back_with_restarted_locally_and_keeps_the_address() {
    let mut w = enabled(&mr_j4_tm::PROFILE);
    let vendor = w.upload(0, 0x1018, 1).unwrap();
    w.p.segment.apply(&Fault::Slave {
        position: 0,
        fault: SlaveFault::ResetToInit,
    });
    // Same station address; INIT with the error bit; 0x0060 "Slave restarted locally".
    assert_eq!(al_status(&mut w), (0x0011, 0x0060));
    // Process data no longer exchanged.
    let image = w.image.clone();
    assert_eq!(w.p.logical(Command::Lrw, 0, &image).unwrap().wkc, 0);
    // The drive's power stage went off with the ESC.
    assert_ne!(w.drive(0).state(), State::OperationEnabled);
    // A master restarts it: acknowledge in INIT, then PRE-OP (the mailbox SMs were kept).
    assert_eq!(w.request_ack(0, 0x0001), (0x0001, 0));
    assert_eq!(w.request(0, 0x0002), (0x0002, 0));
    assert_eq!(w.upload(0, 0x1018, 1), Ok(vendor));
}

#[test]
fn clock_drift_changes_the_rate_of_the_local_clock_without_a_step() {
    let (seg, clock) = io_segment(1);
    let mut p = Probe::new(seg);
    p.assign_addresses(ST).unwrap();
    let sys = |p: &mut Probe| {
        u64::from_le_bytes(p.fprd(ST, 0x0910, 8).unwrap().data[..8].try_into().unwrap())
    };
    for ppb in [100_000i32, -250_000, 0] {
        let before = sys(&mut p);
        p.segment.apply(&Fault::Slave {
            position: 0,
            fault: SlaveFault::ClockDrift(ppb),
        });
        // No step.
        assert_eq!(sys(&mut p), before, "{ppb} ppb");
        clock.advance(1_000_000_000);
        let after = sys(&mut p);
        let expected = 1_000_000_000i64 + i64::from(ppb);
        let got = after as i64 - before as i64;
        assert!(
            (got - expected).abs() <= 1,
            "{ppb} ppb: {got} ns per second"
        );
    }
}

// ----------------------------------------------------------------------------------- SDO

#[test]
fn an_injected_sdo_abort_answers_once_and_the_next_request_is_served() {
    let mut w = Wire::drives(&[&mr_j4_tm::PROFILE]);
    w.preop(0);
    let vendor = w.upload(0, 0x1018, 1).unwrap();
    // Any subindex of 0x1018.
    w.p.segment.apply(&Fault::Device {
        position: 0,
        fault: DeviceFault::AbortSdo {
            index: 0x1018,
            subindex: None,
            code: 0x0800_0022,
        },
    });
    // Another object is not affected.
    assert!(w.upload(0, 0x1000, 0).is_ok());
    assert_eq!(w.upload(0, 0x1018, 2), Err(0x0800_0022));
    assert_eq!(w.upload(0, 0x1018, 1), Ok(vendor));
    // One subindex, on a download.
    w.p.segment.apply(&Fault::Device {
        position: 0,
        fault: DeviceFault::AbortSdo {
            index: 0x6065,
            subindex: Some(0),
            code: 0x0609_0030,
        },
    });
    assert_eq!(w.write_u32(0, 0x6065, 0, 1000), Err(0x0609_0030));
    assert_eq!(w.write_u32(0, 0x6065, 0, 1000), Ok(()));
    assert_eq!(w.read_u32(0, 0x6065, 0), 1000);
}

const MBX: usize = 128;

/// A master on a generic CoE device that shows every mailbox message in order.
struct Mbx {
    p: Probe,
    counter: u8,
}

impl Mbx {
    fn new() -> Self {
        let mut seg = Segment::new(Arc::new(ManualClock::new(T0)));
        seg.push(
            Box::new(GenericCoeDevice::new(5).unwrap()),
            EscConfig::default(),
        )
        .unwrap();
        let mut p = Probe::new(seg);
        p.assign_addresses(ST).unwrap();
        p.fpwr(
            ST,
            0x0800,
            &[
                0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
            ],
        )
        .unwrap();
        assert_eq!(p.request_state(ST, 0x0002).unwrap(), (0x0002, 0));
        Self { p, counter: 0 }
    }

    fn write(&mut self, req: &SdoRequest<'_>) {
        self.counter = self.counter % 7 + 1;
        let mut msg = vec![0u8; MBX];
        req.emit_mailbox(self.counter, &mut msg).unwrap();
        assert_eq!(self.p.fpwr(ST, 0x1000, &msg).unwrap().wkc, 1);
    }

    /// Read SM1 once (`None`: empty).
    fn read(&mut self) -> Option<Vec<u8>> {
        let r = self.p.fprd(ST, 0x1080, MBX).unwrap();
        (r.wkc == 1).then_some(r.data)
    }
}

fn sdo(m: &[u8]) -> SdoResponse<'_> {
    match MailboxMessage::parse(m).unwrap().1 {
        MailboxMessage::SdoResponse(r) => r,
        other => panic!("expected an SDO response, got {other:?}"),
    }
}

#[test]
fn an_emergency_in_the_middle_of_segmented_transfers_which_still_complete() {
    let mut m = Mbx::new();
    let fault = Fault::Device {
        position: 0,
        fault: DeviceFault::EmergencyDuringSdo {
            error_code: 0x8611,
            error_register: 0x80,
            data: [1, 2, 3, 4, 5],
        },
    };
    let is_our_emergency = |msg: &[u8]| match MailboxMessage::parse(msg).unwrap().1 {
        MailboxMessage::Emergency(e) => {
            assert_eq!(
                (e.error_code, e.error_register, e.data),
                (0x8611, 0x80, [1, 2, 3, 4, 5])
            );
            true
        }
        _ => false,
    };
    let text: Vec<u8> = (0..USER_TEXT_LEN).map(|i| b'A' + (i % 26) as u8).collect();

    // Segmented download.
    m.p.segment.apply(&fault);
    let (req, mut sent) = SdoRequest::initiate_download(0x2001, 0, false, &text, MBX);
    m.write(&req);
    let r = m.read().unwrap();
    assert_eq!(
        sdo(&r),
        SdoResponse::Download {
            index: 0x2001,
            sub: 0
        }
    );
    let mut toggle = false;
    let mut emergencies = 0;
    let mut segments = 0;
    while sent < text.len() {
        let (req, n) = SdoRequest::download_segment(&text[sent..], toggle, MBX);
        m.write(&req);
        let mut r = m.read().expect("a message");
        if is_our_emergency(&r) {
            emergencies += 1;
            assert_eq!(segments, 0, "between the initiate and the first segment");
            r = m.read().expect("the segment response follows");
        }
        assert_eq!(sdo(&r), SdoResponse::DownloadSegment { toggle });
        sent += n;
        toggle = !toggle;
        segments += 1;
    }
    assert!(segments >= 2);
    assert_eq!(emergencies, 1);

    // Segmented upload of the same value.
    m.p.segment.apply(&fault);
    m.write(&SdoRequest::Upload {
        index: 0x2001,
        sub: 0,
        complete_access: false,
    });
    let r = m.read().unwrap();
    let mut got = match sdo(&r) {
        SdoResponse::UploadNormal {
            complete_size,
            data,
            ..
        } => {
            assert_eq!(complete_size as usize, USER_TEXT_LEN);
            data.to_vec()
        }
        other => panic!("{other:?}"),
    };
    let mut toggle = false;
    let mut emergencies = 0;
    loop {
        m.write(&SdoRequest::UploadSegment { toggle });
        let mut r = m.read().expect("a message");
        if is_our_emergency(&r) {
            emergencies += 1;
            r = m.read().expect("the segment response follows");
        }
        match sdo(&r) {
            SdoResponse::UploadSegment {
                toggle: t,
                last,
                data,
            } => {
                assert_eq!(t, toggle);
                got.extend_from_slice(data);
                if last {
                    break;
                }
            }
            other => panic!("{other:?}"),
        }
        toggle = !toggle;
    }
    assert_eq!(got, text);
    assert_eq!(emergencies, 1);
    // One shot: the mailbox is quiet afterwards.
    assert_eq!(m.read(), None);
}

#[test]
fn unsupported_faults_and_bad_positions_are_counted_as_ignored() {
    let (mut seg, _) = io_segment(1);
    // An I/O device has no CoE: nothing to abort.
    assert!(!seg.apply(&Fault::Device {
        position: 0,
        fault: DeviceFault::AbortSdo {
            index: 0x1000,
            subindex: None,
            code: 0x0800_0000,
        },
    }));
    assert!(!seg.apply(&Fault::Slave {
        position: 5,
        fault: SlaveFault::ResetToInit,
    }));
    let mut w = Wire::drives(&[&mr_j4_tm::PROFILE]);
    // An alarm name the drive does not have.
    assert!(!w.p.segment.apply(&Fault::Device {
        position: 0,
        fault: DeviceFault::RaiseAlarm("AL.XX"),
    }));
    assert!(w.drive(0).alarm().is_none());
    assert_eq!(seg.stats().faults_ignored, 2);
    assert_eq!(w.p.segment.stats().faults_ignored, 1);
}

/// Delayed replies do not count against the link's in-flight limit: a master keeps sending
/// while they are on their way; only replies that are due and never received do.
#[test]
fn delayed_replies_do_not_block_sending() {
    use ecdrive_sim::transport::IN_FLIGHT;
    let (seg, clock) = io_segment(1);
    let mut l = SegmentLink::new(seg);
    l.segment_mut().apply(&link(LinkFault::Delay {
        fraction: 1.0,
        delay_ns: 1_000_000_000,
    }));
    for _ in 0..130 {
        l.send(&brd_frame(1)).unwrap();
    }
    // 128 held; the frames beyond reached the slave, their replies were lost.
    assert_eq!(l.pending_replies(), 128);
    assert_eq!(l.replies_lost(), 2);
    assert_eq!(l.segment().stats().frames, 130);
    clock.advance(1_000_000_000);
    let mut rx = [0u8; 1600];
    let mut n = 0;
    while l.recv(&mut rx, Some(Duration::ZERO)).unwrap().is_some() {
        n += 1;
    }
    assert_eq!(n, 128);
    // Without a delay: IN_FLIGHT replies due and not received refuse the next send.
    l.segment_mut().apply(&link(LinkFault::Delay {
        fraction: 0.0,
        delay_ns: 0,
    }));
    for _ in 0..IN_FLIGHT {
        l.send(&brd_frame(1)).unwrap();
    }
    let e = l.send(&brd_frame(1)).unwrap_err();
    assert!(e.to_string().contains("receive before sending more"), "{e}");
}
