//! A [`MotionSession`] on its own cycle thread, paced by the SYNC it produces, as the
//! EtherCAT master's session runs its cycle: commands in, telemetry and events out, the
//! application's [`CycleApp`] (a callback, [`Streams`](ecdrive_motion::Streams) of
//! set-points) called by the thread between the read and the step.
//!
//! The thread never allocates per cycle: commands arrive through a lock-free ring, events leave
//! through another, the telemetry is copied into a view the caller reads under a lock the
//! thread only tries (a cycle that finds it taken publishes the next cycle). Each cycle starts
//! at its absolute deadline (start + n × period, `clock_nanosleep`); a transport on the
//! monotonic clock (SocketCAN, `vbus:`) has already waited there in [`Master::cycle`], one on
//! simulated time (the in-process emulated nodes) is held to the period by the sleep.

use super::MotionSession;
use crate::error::{CanError, CanErrorKind, NodeRef};
use crate::transport::CanTransport;
use ecdrive_core::rt::{monotonic_ns, sleep_until_ns};
use ecdrive_motion::CycleApp;
use ecdrive_motion::telemetry::{AxisTelemetry, Command, Event, StopKind};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Commands queued between two cycles before [`CycleThread::command`] refuses one.
const COMMANDS: usize = 64;
/// Events queued for the caller; beyond that the oldest are lost (counted).
const EVENTS: usize = 4096;

/// What the cycle thread publishes after each cycle.
#[derive(Debug, Clone, Default)]
pub struct SessionView {
    /// Cycles so far.
    pub cycle: u64,
    /// The bus's time of the last cycle, µs.
    pub bus_time_us: u64,
    /// Each axis's telemetry, in the order of the set-ups.
    pub axes: Vec<AxisTelemetry>,
    /// Cycles that started more than a period late.
    pub late_cycles: u64,
    /// Events the caller did not collect in time (the ring was full).
    pub events_lost: u64,
    /// The thread ended (a stop that completed, or an error).
    pub ended: bool,
}

/// How the cycle thread ended: the session back (its master for NMT and SDO after the run),
/// the error that ended it early, and the counts.
pub struct ThreadEnd<T: CanTransport> {
    /// The session, its axes stopped.
    pub session: MotionSession<T>,
    /// The bus error that ended the thread, if one did.
    pub error: Option<CanError>,
    /// The last view published.
    pub view: SessionView,
}

/// The shared state of the thread and its handle.
struct Shared {
    view: Mutex<SessionView>,
    /// 0: run; 1 + StopKind index: stop with that kind.
    stop: AtomicU8,
    ended: AtomicBool,
}

/// A [`MotionSession`] running on its own thread. See the [module documentation](self).
pub struct CycleThread<T: CanTransport + Send + 'static> {
    handle: Option<JoinHandle<ThreadEnd<T>>>,
    commands: rtrb::Producer<Command>,
    events: rtrb::Consumer<Event>,
    shared: Arc<Shared>,
    nodes: Vec<NodeRef>,
}

fn stop_code(kind: StopKind) -> u8 {
    match kind {
        StopKind::Ramp => 1,
        StopKind::QuickStop => 2,
    }
}

fn stop_kind(code: u8) -> Option<StopKind> {
    match code {
        1 => Some(StopKind::Ramp),
        2 => Some(StopKind::QuickStop),
        _ => None,
    }
}

impl<T: CanTransport + Send + 'static> CycleThread<T> {
    /// Run `session` on a new thread, with `app` called every cycle (none: commands only).
    /// The drives should be configured and started (NMT Operational); enable them with
    /// [`Command::Enable`].
    pub fn spawn(
        session: MotionSession<T>,
        app: Option<Arc<Mutex<dyn CycleApp>>>,
    ) -> std::io::Result<Self> {
        let (commands, cmd_rx) = rtrb::RingBuffer::new(COMMANDS);
        let (ev_tx, events) = rtrb::RingBuffer::new(EVENTS);
        let view = SessionView {
            axes: (0..session.len())
                .filter_map(|i| session.telemetry(i).copied())
                .collect(),
            ..SessionView::default()
        };
        let nodes = (0..session.len()).filter_map(|i| session.node(i)).collect();
        let shared = Arc::new(Shared {
            view: Mutex::new(view),
            stop: AtomicU8::new(0),
            ended: AtomicBool::new(false),
        });
        let sh = shared.clone();
        let handle = std::thread::Builder::new()
            .name("ecdrive-canopen-cycle".into())
            .spawn(move || run(session, app, cmd_rx, ev_tx, &sh))?;
        Ok(Self {
            handle: Some(handle),
            commands,
            events,
            shared,
            nodes,
        })
    }

    /// Queue a command for the next cycle (as [`MotionSession::command`]); an error when the
    /// thread has ended or the queue is full.
    pub fn command(&mut self, cmd: Command) -> Result<(), CanError> {
        if self.shared.ended.load(Ordering::Acquire) {
            return Err(self.not_running("the cycle thread has ended"));
        }
        self.commands
            .push(cmd)
            .map_err(|_| self.not_running("the command queue is full"))
    }

    /// A copy of the last view the thread published.
    pub fn view(&self) -> SessionView {
        self.shared
            .view
            .lock()
            .map(|v| v.clone())
            .unwrap_or_default()
    }

    /// The events since the last call.
    pub fn events(&mut self) -> Vec<Event> {
        let mut out = Vec::with_capacity(self.events.slots());
        while let Ok(e) = self.events.pop() {
            out.push(e);
        }
        out
    }

    /// Wait until `done` holds for the published view; an error naming `what` after
    /// `timeout`, or when the thread ends first.
    pub fn wait_until(
        &self,
        what: &str,
        timeout: Duration,
        mut done: impl FnMut(&SessionView) -> bool,
    ) -> Result<(), CanError> {
        let start = Instant::now();
        loop {
            if let Ok(v) = self.shared.view.lock() {
                if done(&v) {
                    return Ok(());
                }
                if v.ended {
                    return Err(self.not_running(&format!(
                        "the cycle thread ended before {what} (after {} cycles)",
                        v.cycle
                    )));
                }
            }
            if start.elapsed() >= timeout {
                return Err(self.not_running(&format!(
                    "{what}: not within {:.1} s",
                    timeout.as_secs_f64()
                )));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Stop every axis with `kind` (a ramp, or the drive's quick stop), then disable; wait for the
    /// stops to end and the thread with them, and give the session back.
    pub fn stop(mut self, kind: StopKind) -> Result<ThreadEnd<T>, CanError> {
        self.shared.stop.store(stop_code(kind), Ordering::Release);
        self.join()
    }

    fn join(&mut self) -> Result<ThreadEnd<T>, CanError> {
        let handle = self
            .handle
            .take()
            .ok_or_else(|| self.not_running("the cycle thread was joined already"))?;
        handle
            .join()
            .map_err(|_| self.not_running("the cycle thread panicked"))
    }

    /// An error of the session: named by its node when it has one drive, else "all nodes".
    fn not_running(&self, why: &str) -> CanError {
        let node = match self.nodes.as_slice() {
            [one] => *one,
            _ => NodeRef { id: 0, drive: None },
        };
        CanError::new(
            node,
            None,
            CanErrorKind::NotReady(format!("the CANopen session's cycle thread: {why}")),
        )
    }
}

impl<T: CanTransport + Send + 'static> Drop for CycleThread<T> {
    /// A thread still running is stopped with a ramp: no drive is left enabled.
    fn drop(&mut self) {
        if self.handle.is_some() {
            self.shared
                .stop
                .store(stop_code(StopKind::Ramp), Ordering::Release);
            let _ = self.join();
        }
    }
}

/// The cycle thread: commands, the cycle with the application, events and telemetry out,
/// the sleep to the next deadline; a requested stop until every axis has stopped.
fn run<T: CanTransport>(
    mut s: MotionSession<T>,
    app: Option<Arc<Mutex<dyn CycleApp>>>,
    mut commands: rtrb::Consumer<Command>,
    mut events: rtrb::Producer<Event>,
    shared: &Shared,
) -> ThreadEnd<T> {
    let period = s.cycle_us().saturating_mul(1000);
    let mut next = monotonic_ns();
    let (mut late, mut lost) = (0u64, 0u64);
    let mut stopping: Option<u64> = None;
    let mut error = None;
    loop {
        while let Ok(c) = commands.pop() {
            s.command(c);
        }
        if stopping.is_none()
            && let Some(kind) = stop_kind(shared.stop.load(Ordering::Acquire))
        {
            s.command(Command::Stop(kind));
            stopping = Some(s.cycles());
        }
        let r = match &app {
            Some(a) => match a.lock() {
                Ok(mut g) => s.cycle_app(&mut *g),
                // An application that panicked elsewhere: its lock poisoned, run without it.
                Err(_) => s.cycle(),
            },
            None => s.cycle(),
        };
        if let Err(e) = r {
            error = Some(e);
        }
        s.drain_events(|e| {
            if events.push(e).is_err() {
                lost += 1;
            }
        });
        let done = error.is_some()
            || stopping.is_some_and(|at| {
                !s.any_busy() || s.cycles() - at > s.stop_timeout_cycles.saturating_mul(2)
            });
        publish(&s, shared, late, lost, done);
        if done {
            break;
        }
        next = next.saturating_add(period);
        let now = monotonic_ns();
        if now > next.saturating_add(period) {
            late += 1;
            next = now;
        }
        sleep_until_ns(next);
    }
    shared.ended.store(true, Ordering::Release);
    let view = shared.view.lock().map(|v| v.clone()).unwrap_or_default();
    ThreadEnd {
        session: s,
        error,
        view,
    }
}

/// Copy the session's telemetry into the shared view, if the caller is not reading it now
/// (always, at the end). Allocation-free: the view's axes were sized at spawn.
fn publish<T: CanTransport>(
    s: &MotionSession<T>,
    shared: &Shared,
    late: u64,
    lost: u64,
    ended: bool,
) {
    let guard = if ended {
        shared.view.lock().ok()
    } else {
        shared.view.try_lock().ok()
    };
    let Some(mut v) = guard else { return };
    v.cycle = s.cycles();
    v.bus_time_us = s.master().now_us();
    v.late_cycles = late;
    v.events_lost = lost;
    v.ended = ended;
    for (i, t) in v.axes.iter_mut().enumerate() {
        if let Some(src) = s.telemetry(i) {
            *t = *src;
        }
    }
}
