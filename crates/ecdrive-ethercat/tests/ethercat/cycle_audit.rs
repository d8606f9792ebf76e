//! Proof that the cycle, once the drives are in OP, allocates nothing and makes no syscall but
//! the sleep (in-process link: the frame I/O is a function call), under load: two drives and an
//! I/O device between them, the axes enabled and running programs with a mode switch. With the
//! emulated MR-J4-TM and BDHDE and the default emergency polling, the one more syscall is the
//! futex that hands each poll's reply to the supervising thread.
//!
//! A counting global allocator counts allocations made by the cycle thread inside a window; a
//! per-thread perf counter on the `raw_syscalls:sys_enter` tracepoint counts the cycle
//! thread's syscalls, and those outside the allowed set. The window opens when every drive is
//! in OP and closes when the stop command arrives; the hooks run on the cycle thread.
//!
//! One more run puts application code in the cycle: a `CycleApp` that reads every accessor and
//! a mapped entry of one axis, writes its set-points (a sine), and feeds the other axis from a
//! set-point stream that a producer thread fills while the window is open, with every cycle
//! recorded.

use crate::support;
use ecdrive_core::cia402::State;
use ecdrive_core::link::FrameLink;
use ecdrive_core::link::netns::{VethPair, require_root};
use ecdrive_core::od::ObjectAddress;
use ecdrive_core::rt::audit::{AllocCounts, skip_or_fail};
use ecdrive_ethercat::cycle::audit::SteadyAudit;
use ecdrive_ethercat::program::{ProbeEdge, RunMode, Step, Target};
use ecdrive_ethercat::session::{Master, MasterConfig};
use ecdrive_ethercat::startup::{DriveSetup, Selector};
use ecdrive_ethercat::telemetry::{Axes, Command, StopKind};
use ecdrive_ethercat::{AppCycle, CycleApp, ProbeState, StreamProducer, Streams};
use ecdrive_sim::devices::{GenericCoeDevice, IoDevice};
use ecdrive_sim::transport::{RawServer, SegmentLink};
use ecdrive_sim::{EscConfig, HostClock, Segment};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use support::generic::GENERIC_TEST;

/// A realistic segment: two drives with an I/O device between them.
/// What runs: generic servo devices on the test profile without emergency polling, or the
/// emulated MR-J4-TM and BDHDE on their own profiles with the default emergency polling.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Load {
    Generic,
    Drives,
    /// The drives in the profile modes: the MR-J4-TM with [Pr. PA01] = 2 stored.
    Profile,
}

fn segment(load: Load) -> Segment {
    let esc = EscConfig {
        sm_watchdog: 0,
        ..Default::default()
    };
    let mut seg = Segment::new(Arc::new(HostClock));
    let devices: [Box<dyn ecdrive_sim::Device>; 3] = match load {
        Load::Generic => [
            Box::new(GenericCoeDevice::new(700).unwrap()),
            Box::new(IoDevice::new(2, 4).with_serial(900)),
            Box::new(GenericCoeDevice::new(701).unwrap()),
        ],
        Load::Drives => [
            ecdrive_sim::devices::by_name("mr-j4-tm", 0).unwrap(),
            Box::new(IoDevice::new(2, 4).with_serial(900)),
            ecdrive_sim::devices::by_name("bdhde", 2).unwrap(),
        ],
        Load::Profile => [
            ecdrive_sim::devices::by_name("mr-j4-tm@0x2001=2", 0).unwrap(),
            Box::new(IoDevice::new(2, 4).with_serial(900)),
            ecdrive_sim::devices::by_name("bdhde", 2).unwrap(),
        ],
    };
    for d in devices {
        seg.push(d, esc.clone()).unwrap();
    }
    // The audit counts allocations and syscalls; the drives' own loss supervision (AL.86 on
    // the MR-J4-TM, 0x818D on the BDHDE) would fault them whenever the loaded test machine
    // stalls the normal-priority cycle, and the enable or the programs would never finish.
    // Loss reactions have their own tests (faults_master, sim_faults).
    for i in 0..seg.len() {
        if let Some(d) = seg.device_mut::<ecdrive_sim::drives::EmulatedDrive>(i) {
            d.set_loss_detection(false);
        }
    }
    seg
}

/// Run the two drives and the I/O device to OP on `link`; with the window open, enable the
/// axes and run their programs (a move, a mode switch, a ramp, a dwell) for at least 300
/// cycles; stop; check the counts.
fn audit_run<L: FrameLink + Send + 'static>(
    link: L,
    load: Load,
    allowed: &'static [libc::c_long],
    what: &str,
) {
    audit_run_with(link, load, allowed, what, None);
}

/// Application code for the audit: a sine on axis 0 from everything it reads, a stream on
/// axis 1.
struct AuditApp {
    streams: Streams,
    centre: Option<i64>,
    seen: i64,
}

impl CycleApp for AuditApp {
    fn cycle(&mut self, c: &mut AppCycle<'_>) {
        self.streams.cycle(c);
        let t = c.time();
        if let Some(a) = c.axis(0)
            && a.enabled()
        {
            let centre = *self.centre.get_or_insert(a.position());
            // A touch probe armed and read every cycle (mapped by `DriveSetup::probes`).
            if a.probe(1) == ProbeState::Off {
                a.arm_probe(1, ProbeEdge::Rising);
            }
            self.seen = self
                .seen
                .wrapping_add(i64::from(matches!(a.probe(1), ProbeState::Armed(_))));
            self.seen = self.seen.wrapping_add(
                a.velocity() as i64
                    + a.torque() as i64
                    + a.following_error()
                    + a.error_code() as i64
                    + a.read(ObjectAddress::new(0x6041, 0)).unwrap_or(0)
                    + a.digital_inputs().map_or(0, i64::from)
                    + i64::from(a.mode().is_some())
                    + i64::from(a.state().is_some()),
            );
            a.set_target(centre as f64 + 2000.0 * (t * 6.0).sin());
        }
    }
}

/// pp with a set of set-points and a touch probe armed, pv, tq, pv to rest, in counts (the
/// profile objects are written by [`profile_objects`], in each drive's unit: the steps' profile
/// values are what a run file would convert, the BDHDE's counts).
fn profile_program() -> Vec<Step> {
    vec![
        Step::TouchProbe {
            probe: 1,
            edge: ProbeEdge::Rising,
        },
        Step::Pp {
            targets: vec![20_000.0, 0.0],
            relative: false,
            immediate: false,
            velocity: 2_000_000.0,
            acceleration: 20_000_000.0,
            deceleration: None,
        },
        Step::Mode { mode: RunMode::Pv },
        Step::Pv {
            velocity: 50_000.0,
            acceleration: 20_000_000.0,
            deceleration: None,
            seconds: 0.05,
        },
        Step::Mode { mode: RunMode::Tq },
        Step::Tq {
            torque: 20.0,
            slope: None,
            seconds: 0.05,
        },
        Step::Mode { mode: RunMode::Pv },
        Step::Pv {
            velocity: 0.0,
            acceleration: 20_000_000.0,
            deceleration: None,
            seconds: 0.0,
        },
        Step::Dwell { seconds: 0.2 },
    ]
}

/// 0x6081/0x6083/0x6084 for the drive at `position`: the MR-J4-TM's 0.01 r/min and ms, the
/// BDHDE's counts.
fn profile_objects(
    position: u16,
) -> Vec<(ecdrive_core::od::ObjectAddress, ecdrive_core::od::Value)> {
    let a = ecdrive_core::od::ObjectAddress::new;
    let v = ecdrive_core::od::Value::Uint;
    if position == 0 {
        vec![
            (a(0x6081, 0), v(100_000)),
            (a(0x6083, 0), v(100)),
            (a(0x6084, 0), v(100)),
        ]
    } else {
        vec![
            (a(0x6081, 0), v(2_000_000)),
            (a(0x6083, 0), v(20_000_000)),
            (a(0x6084, 0), v(20_000_000)),
        ]
    }
}

fn audit_run_with<L: FrameLink + Send + 'static>(
    link: L,
    load: Load,
    allowed: &'static [libc::c_long],
    what: &str,
    app: Option<(Arc<Mutex<AuditApp>>, StreamProducer)>,
) {
    let audit = Arc::new(SteadyAudit::new(allowed));
    let mut cfg = MasterConfig::new(Duration::from_millis(1));
    if load == Load::Generic {
        cfg.emergency_poll = None;
    }
    cfg.hooks = Some(audit.clone());
    cfg.cycle.segment_lost_after = 50;
    let with_app = app.is_some();
    let mut producer = app.map(|(a, p)| {
        cfg.app = Some(a);
        p
    });
    // With the application, every cycle is recorded too (drained by this thread below).
    let mut recording = with_app.then(|| {
        let (tx, rx) = ecdrive_ethercat::recording(1 << 16);
        cfg.record = Some(Arc::new(Mutex::new(tx)));
        rx
    });
    for p in [0, 2] {
        cfg.startup.drives.push(DriveSetup {
            profile: (load == Load::Generic).then_some(&GENERIC_TEST),
            program: if with_app {
                Vec::new()
            } else if load == Load::Profile {
                profile_program()
            } else if load == Load::Generic {
                // The generic test device maps the position set-point only: csp.
                vec![
                    Step::Move {
                        target: Target::By(20_000.0),
                        velocity: 100_000.0,
                        acceleration: 1_000_000.0,
                        jerk: None,
                    },
                    Step::Dwell { seconds: 0.05 },
                    Step::Move {
                        target: Target::By(-20_000.0),
                        velocity: 100_000.0,
                        acceleration: 1_000_000.0,
                        jerk: None,
                    },
                    Step::Dwell { seconds: 0.2 },
                ]
            } else {
                vec![
                    Step::Move {
                        target: Target::By(20_000.0),
                        velocity: 100_000.0,
                        acceleration: 1_000_000.0,
                        jerk: None,
                    },
                    Step::Mode { mode: RunMode::Csv },
                    Step::Ramp {
                        velocity: 50_000.0,
                        acceleration: 1_000_000.0,
                        hold: 0.05,
                    },
                    Step::Dwell { seconds: 0.2 },
                ]
            },
            probes: if with_app {
                vec![(1, ProbeEdge::Rising)]
            } else {
                Vec::new()
            },
            ..DriveSetup::new(Selector::Position(p))
        });
        if load == Load::Profile
            && let Some(d) = cfg.startup.drives.last_mut()
        {
            d.mode = RunMode::Pp;
            d.sdos = profile_objects(p);
        }
    }
    let steps = cfg.startup.drives.first().map_or(0, |d| d.program.len()) as u16;
    let mut m = Master::start(link, cfg).unwrap();
    assert_eq!((m.drives().len(), m.io().len()), (2, 1));
    m.wait_until("OP", Duration::from_secs(10), |t| t.cycle.all_op)
        .unwrap();
    let c0 = m.telemetry().cycle.cycle;
    m.command(Command::Enable(Axes::All)).unwrap();
    m.wait_until("enabled", Duration::from_secs(10), |t| {
        t.axes
            .iter()
            .all(|a| a.state == Some(State::OperationEnabled))
    })
    .unwrap();
    if let Some(p) = producer.as_mut() {
        // Touch probes by command in the window: one mapped, one not (refused, an event).
        for (probe, edge) in [(1, ProbeEdge::Rising), (2, ProbeEdge::Falling)] {
            m.command(Command::ArmProbe {
                axis: 1,
                probe,
                edge,
            })
            .unwrap();
        }
        // Axis 1 from the stream: 600 set-points from where it stands, pushed as room frees.
        let origin = m.telemetry().axes[1].position_actual;
        let mut next = 1i64;
        m.wait_until("the stream and 300 cycles", Duration::from_secs(20), |t| {
            while next <= 600 && p.push((origin + 3 * next) as f64).is_ok() {
                next += 1;
            }
            t.cycle.cycle > c0 + 300 && next > 600
        })
        .unwrap();
        assert!(p.consumed() > 100, "{what}: the stream was not consumed");
        let probes = m
            .telemetry()
            .axes
            .iter()
            .map(|a| a.probes[0])
            .collect::<Vec<_>>();
        assert!(
            probes
                .iter()
                .all(|p| *p == ProbeState::Armed(ProbeEdge::Rising)),
            "{what}: the probes armed by the application and by command: {probes:?}"
        );
        let r = recording.as_mut().expect("recording");
        assert!(r.drain(|_| {}) > 600, "{what}: nothing recorded");
    } else {
        m.command(Command::RunProgram(Axes::All)).unwrap();
        m.wait_until(
            "the programs and 300 cycles",
            Duration::from_secs(20),
            |t| t.cycle.cycle > c0 + 300 && t.axes.iter().all(|a| a.program_step >= steps),
        )
        .unwrap();
    }
    let (report, _) = m.stop(StopKind::Ramp);
    assert!(report.unwrap().shutdown_ok);

    let counts = audit.counts().expect("the window closed");
    assert_eq!(
        counts.allocs,
        AllocCounts::default(),
        "{what}: the cycle allocated in steady state"
    );
    if let Some(e) = audit.error() {
        skip_or_fail(&format!("syscall audit of the cycle ({what}): {e}"));
        return;
    }
    let sys = counts.syscalls.expect("counted");
    let (outside, all) = (sys.outside, sys.all);
    assert_eq!(outside, 0, "{what}: syscalls outside {allowed:?}: {sys:?}");
    // At least one sleep per cycle: at least the 300 cycles we waited for.
    assert!(all >= 300, "{what}: {sys:?}");
}

/// In-process: the frame I/O is a function call, so the only syscall is the sleep.
#[test]
fn steady_cycle_in_process_allocates_nothing_and_only_sleeps() {
    audit_run(
        SegmentLink::new(segment(Load::Generic)),
        Load::Generic,
        &[libc::SYS_clock_nanosleep],
        "in-process",
    );
}

/// The same with the emulated MR-J4-TM and BDHDE on their own profiles and the default
/// emergency polling: the supervisor's mailbox polls ride in the cycle's frames, and the cycle
/// thread hands each reply over by waking the supervising thread (futex): no allocation, and
/// no other syscall.
#[test]
fn steady_cycle_with_the_emulated_drives_and_emergency_polling() {
    audit_run(
        SegmentLink::new(segment(Load::Drives)),
        Load::Drives,
        &[libc::SYS_clock_nanosleep, libc::SYS_futex],
        "in-process, MR-J4-TM and BDHDE, emergency polling",
    );
}

/// The drives in the profile modes (pp with a set of set-points, pv, tq) with a touch probe
/// armed: the handshake engines and the probe allocate nothing either.
#[test]
fn steady_cycle_in_the_profile_modes_allocates_nothing() {
    audit_run(
        SegmentLink::new(segment(Load::Profile)),
        Load::Profile,
        &[libc::SYS_clock_nanosleep, libc::SYS_futex],
        "in-process, MR-J4-TM and BDHDE in pp, pv and tq",
    );
}

/// With application code in the cycle (a callback reading every accessor and writing a sine)
/// and a set-point stream fed by another thread, on the emulated drives with emergency
/// polling: no allocation, no other syscall.
#[test]
fn steady_cycle_with_a_callback_and_a_stream_allocates_nothing() {
    let mut streams = Streams::new();
    let producer = streams.add(1, 64);
    let app = Arc::new(Mutex::new(AuditApp {
        streams,
        centre: None,
        seen: 0,
    }));
    audit_run_with(
        SegmentLink::new(segment(Load::Drives)),
        Load::Drives,
        &[libc::SYS_clock_nanosleep, libc::SYS_futex],
        "in-process, a callback and a stream",
        Some((app, producer)),
    );
}

/// Over a veth pair: the sleep and the raw socket's send, receive and poll.
#[test]
fn steady_cycle_over_veth_allocates_nothing_and_only_does_frame_io_and_sleeps() {
    if !require_root("cycle_audit::steady_cycle_over_veth") {
        return;
    }
    let veth = VethPair::create().expect("veth pair");
    let server = RawServer::spawn(
        veth.open_peer_socket().expect("peer socket"),
        segment(Load::Generic),
    )
    .expect("server");
    audit_run(
        veth.open_host_socket().expect("host socket"),
        Load::Generic,
        &[
            libc::SYS_clock_nanosleep,
            libc::SYS_sendto,
            libc::SYS_recvfrom,
            libc::SYS_poll,
            libc::SYS_ppoll,
        ],
        "veth",
    );
    let (_, served) = server.stop();
    served.expect("server");
}
