//! Proof that the CANopen session's cycle thread ([`CycleThread`]), once its drives are enabled,
//! allocates nothing and makes no syscall but the frame I/O, the sleep and the futex of an
//! application lock taken by another thread — under load: the BLV-R and the ASDA-A2 in pv, one
//! fed by a callback that reads every accessor and writes a velocity sine, the other by a
//! set-point stream a producer thread fills, over a `vbus:` virtual bus whose emulated nodes
//! are served by another thread (so the bus's frames are real socket I/O of the cycle thread).
//!
//! The window opens inside the callback once both axes take set-points and closes 400 cycles
//! later, on the cycle thread: a counting global allocator counts its allocations, a
//! per-thread perf counter on `raw_syscalls:sys_enter` its syscalls outside the allowed set.

use ecdrive::canopen::master::{DriveSetup, MasterConfig};
use ecdrive::canopen::motion::{
    CycleThread, MotionSession, ProfileSpeeds, SessionDrive, axis_setup, profile_settings,
};
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::canopen::unix_bus::UnixBusPort;
use ecdrive::drives::{asda_a2, blv_r};
use ecdrive::motion::telemetry::{Axes, Command, StopKind};
use ecdrive::rt::audit::{self, AllocCounts, SyscallCounter, SyscallCounts, skip_or_fail};
use ecdrive::{AppCycle, CycleApp, RunMode, Streams};
use ecdrive_cli::app::canopen::tools::{BusSpec, NodeSpec, serve};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

const DRIVES: [(u8, &CanDriveProfile, &str); 2] = [
    (3, &blv_r::PROFILE, "blv-r"),
    (0x7F, &asda_a2::PROFILE, "asda-a2"),
];

/// Cycles in the window.
const WINDOW: u64 = 400;

/// What the cycle thread may call: the sleep, the datagram socket's send (`write` on a
/// connected socket) and receive (and the poll of a receive with a timeout), and the futex of a
/// lock another thread holds.
const ALLOWED: &[libc::c_long] = &[
    libc::SYS_clock_nanosleep,
    libc::SYS_write,
    libc::SYS_sendto,
    libc::SYS_recvfrom,
    libc::SYS_poll,
    libc::SYS_ppoll,
    libc::SYS_futex,
];

#[derive(Default)]
struct Window {
    opened_at: Option<u64>,
    counter: Option<SyscallCounter>,
    counter_error: Option<String>,
    /// What an empty window counts (the stop's `ioctl`s), subtracted.
    base: SyscallCounts,
    result: Option<(AllocCounts, SyscallCounts)>,
    /// Sum of every accessor read in the window, so that none is optimised away.
    seen: i64,
}

struct AuditApp {
    streams: Streams,
    window: Window,
    centre: Option<f64>,
}

impl CycleApp for AuditApp {
    fn cycle(&mut self, c: &mut AppCycle<'_>) {
        let now = c.cycle();
        let dt = c.period();
        let both = c
            .axes()
            .iter()
            .all(|a| a.enabled() && a.mode() == Some(RunMode::Pv));
        if let Some(a) = c.axis(0) {
            if a.enabled() && a.mode() != Some(RunMode::Pv) {
                a.request_mode(RunMode::Pv);
            }
            if a.mode() == Some(RunMode::Pv) {
                let centre = *self.centre.get_or_insert(now as f64);
                let t = (now as f64 - centre) * dt;
                a.set_target(36_000.0 * (2.0 * std::f64::consts::PI * t).sin());
            }
            self.window.seen = self.window.seen.wrapping_add(
                a.position()
                    + i64::from(a.velocity())
                    + i64::from(a.torque())
                    + a.following_error()
                    + i64::from(a.error_code())
                    + i64::from(a.in_op())
                    + i64::from(a.program_running()),
            );
        }
        if let Some(a) = c.axis(1)
            && a.enabled()
            && a.mode() != Some(RunMode::Pv)
        {
            a.request_mode(RunMode::Pv);
        }
        self.streams.cycle(c);
        let w = &mut self.window;
        match w.opened_at {
            None if both => {
                match SyscallCounter::for_current_thread(ALLOWED) {
                    Ok(counter) => {
                        w.base = counter.overhead().unwrap_or_default();
                        w.counter = Some(counter);
                    }
                    Err(e) => w.counter_error = Some(e.to_string()),
                }
                w.opened_at = Some(now);
                audit::alloc_window_begin();
                if let Some(counter) = &w.counter {
                    counter.start();
                }
            }
            Some(at) if now == at + WINDOW => {
                let allocs = audit::alloc_window_end();
                let calls = match &w.counter {
                    Some(counter) => {
                        counter.stop();
                        let c = counter.read().unwrap_or_default();
                        SyscallCounts {
                            all: c.all.saturating_sub(w.base.all),
                            outside: c.outside.saturating_sub(w.base.outside),
                        }
                    }
                    None => SyscallCounts::default(),
                };
                w.result = Some((allocs, calls));
            }
            _ => {}
        }
    }
}

#[test]
fn canopen_cycle_thread_allocates_nothing_and_only_does_frame_io_and_sleeps() {
    let dir = std::env::temp_dir().join(format!("ecdrive-canopen-audit-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("bus.sock");
    let _ = std::fs::remove_file(&path);
    let spec = BusSpec::UnixHub(path.clone());
    let nodes: Vec<NodeSpec> = DRIVES
        .iter()
        .map(|&(node, profile, name)| NodeSpec {
            node,
            emulation: ecdrive_cli::app::canopen::tools::emulation_of(profile)
                .expect("the software slave emulates the drive"),
            name,
        })
        .collect();
    let stop = Arc::new(AtomicBool::new(false));
    let (up_tx, up_rx) = std::sync::mpsc::channel();
    let server = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            serve(
                &spec,
                &nodes,
                |_| {
                    let _ = up_tx.send(());
                },
                || !stop.load(Ordering::Relaxed),
            )
            .map(|_| ())
            .map_err(|e| e.to_string())
        })
    };
    up_rx
        .recv_timeout(Duration::from_secs(30))
        .expect("the emulated nodes are served");

    let port = UnixBusPort::connect(&path).expect("connect to the virtual bus");
    let speeds = ProfileSpeeds {
        velocity_rev_s: 10.0,
        accel_rev_s2: 100.0,
        homing_fast_rev_s: 5.0,
        homing_slow_rev_s: 0.5,
    };
    let drives = DRIVES
        .iter()
        .map(|&(node, p, _)| {
            let mut setup = DriveSetup::new(p);
            setup.settings = profile_settings(p, &speeds);
            SessionDrive {
                node,
                setup,
                axis: axis_setup(p, Vec::new(), RunMode::Pp),
            }
        })
        .collect();
    let cfg = MasterConfig {
        cycle_us: 4_000,
        ..MasterConfig::default()
    };
    let session = MotionSession::start(port, cfg, drives).expect("session");
    let mut streams = Streams::new();
    let mut producer = streams.add(1, 64);
    let app = Arc::new(Mutex::new(AuditApp {
        streams,
        window: Window::default(),
        centre: None,
    }));
    let mut t = CycleThread::spawn(session, Some(app.clone())).expect("cycle thread");
    t.command(Command::Enable(Axes::All)).expect("enable");
    // The producer: a slow velocity ramp for axis 1 (PUU/s), topped up every 10 ms until the
    // window has closed. Its lock of the application makes the cycle thread's futex.
    let mut k = 0u64;
    loop {
        while producer.free() > 0 {
            let v = 1_280_000.0 * ((k as f64) * 0.004).sin();
            if producer.push(v).is_err() {
                break;
            }
            k += 1;
        }
        let done = app
            .lock()
            .map(|a| a.window.result.is_some())
            .unwrap_or(true);
        if done {
            break;
        }
        let view = t.view();
        assert!(
            !view.ended,
            "the cycle thread ended early: {:?}",
            t.events()
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let end = t.stop(StopKind::Ramp).expect("stop");
    assert!(end.error.is_none(), "{:?}", end.error);
    stop.store(true, Ordering::Relaxed);
    server
        .join()
        .expect("server thread")
        .expect("the emulated nodes were served");
    let _ = std::fs::remove_dir_all(&dir);

    let a = app.lock().expect("app");
    let (allocs, calls) = a.window.result.expect("the window closed");
    eprintln!(
        "CANopen cycle thread, {WINDOW} cycles: {allocs:?}, syscalls {calls:?}, seen {}",
        a.window.seen
    );
    assert_eq!(allocs.allocs, 0, "the cycle thread allocated in the window");
    match &a.window.counter_error {
        None => assert_eq!(
            calls.outside, 0,
            "syscalls outside frame I/O, the sleep and the futex: {calls:?}"
        ),
        Some(e) => skip_or_fail(&format!("counting the cycle thread's syscalls: {e}")),
    }
}
