//! Every cycle's samples as columns: the master's recording ring, drained by a thread of its
//! own (never the cycle thread) into one growing list per column, which `Master.record()`
//! hands to Python.

use ecdrive::master::{CycleSample, RecordTx, Recording, recording};
use pyo3::IntoPyObjectExt;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// The ring between the cycle and the drain thread: two seconds of samples at 1 kHz for 8
/// axes (the drain thread empties it every 20 ms).
const RING: usize = 16_384;

/// The samples since the last `take`, one list per column (one row per axis and cycle with a
/// reply).
#[derive(Debug, Default)]
pub struct Columns {
    cycle: Vec<u64>,
    time_ns: Vec<u64>,
    axis: Vec<u16>,
    wake_latency_ns: Vec<u32>,
    exchange_ns: Vec<u32>,
    wkc: Vec<u16>,
    mode: Vec<i8>,
    statusword: Vec<u16>,
    position_demand: Vec<Option<i64>>,
    position: Vec<i64>,
    velocity_demand: Vec<Option<f64>>,
    velocity: Vec<f64>,
    torque_demand: Vec<Option<i16>>,
    torque: Vec<i16>,
    following_error: Vec<Option<i64>>,
}

impl Columns {
    /// One sample; `scale`: counts/s per unit of the axis's velocity objects.
    fn push(&mut self, s: &CycleSample, scale: f64) {
        self.cycle.push(s.cycle);
        self.time_ns.push(s.time_ns);
        self.axis.push(s.axis);
        self.wake_latency_ns.push(s.wake_latency_ns);
        self.exchange_ns.push(s.exchange_ns);
        self.wkc.push(s.wkc);
        self.mode.push(s.mode);
        self.statusword.push(s.statusword);
        self.position_demand.push(s.demand);
        self.position.push(s.actual);
        self.velocity_demand
            .push(s.velocity_demand.map(|v| f64::from(v) * scale));
        self.velocity.push(f64::from(s.velocity) * scale);
        self.torque_demand.push(s.torque_demand);
        self.torque.push(s.torque);
        self.following_error.push(s.following_error);
    }

    /// The columns as a dict of lists.
    pub fn into_py(self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let d = PyDict::new(py);
        d.set_item("cycle", self.cycle)?;
        d.set_item("time_ns", self.time_ns)?;
        d.set_item("axis", self.axis)?;
        d.set_item("wake_latency_ns", self.wake_latency_ns)?;
        d.set_item("exchange_ns", self.exchange_ns)?;
        d.set_item("wkc", self.wkc)?;
        d.set_item("mode", self.mode)?;
        d.set_item("statusword", self.statusword)?;
        d.set_item("position_demand", self.position_demand)?;
        d.set_item("position", self.position)?;
        d.set_item("velocity_demand", self.velocity_demand)?;
        d.set_item("velocity", self.velocity)?;
        d.set_item("torque_demand", self.torque_demand)?;
        d.set_item("torque", self.torque)?;
        d.set_item("following_error", self.following_error)?;
        d.into_py_any(py)
    }
}

/// What the drain thread keeps, and the ring it drains (so that a `take` drains it first).
pub struct Kept {
    rx: Recording,
    columns: Columns,
    /// Largest wake-up latency of any cycle recorded since the master started, ns.
    pub max_wake_latency_ns: u64,
    /// Samples the ring could not take (the drain thread fell behind).
    pub dropped: u64,
    /// Whether the samples are kept (the latency is followed either way).
    keep: bool,
    /// Per axis: counts/s per unit of its velocity objects (1 until the master started).
    scales: Vec<f64>,
}

impl Kept {
    /// Everything waiting in the ring into the columns.
    fn drain(&mut self) {
        let (columns, max, keep) = (&mut self.columns, &mut self.max_wake_latency_ns, self.keep);
        let scales = &self.scales;
        self.rx.drain(|s| {
            *max = (*max).max(u64::from(s.wake_latency_ns));
            if keep {
                let scale = scales.get(usize::from(s.axis)).copied().unwrap_or(1.0);
                columns.push(s, scale);
            }
        });
        self.dropped = self.rx.dropped();
    }
}

/// The drain thread of one master run.
pub struct Recorder {
    pub kept: Arc<Mutex<Kept>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Recorder {
    /// The ring for the master's configuration, and its drain thread; `keep` says whether the
    /// samples are kept as columns (the latency is followed either way).
    pub fn start(keep: bool) -> std::io::Result<(Arc<Mutex<RecordTx>>, Self)> {
        let (tx, rx) = recording(RING);
        let kept = Arc::new(Mutex::new(Kept {
            rx,
            columns: Columns::default(),
            max_wake_latency_ns: 0,
            dropped: 0,
            keep,
            scales: Vec::new(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (k, s) = (kept.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name("ecdrive-py-record".into())
            .spawn(move || drain(&k, &s))?;
        Ok((
            Arc::new(Mutex::new(tx)),
            Self {
                kept,
                stop,
                thread: Some(thread),
            },
        ))
    }

    /// The samples since the last call, up to the last cycle recorded.
    pub fn take(&self) -> Columns {
        self.kept
            .lock()
            .map(|mut k| {
                k.drain();
                std::mem::take(&mut k.columns)
            })
            .unwrap_or_default()
    }

    /// The drives' velocity units, counts/s per unit, by axis.
    pub fn set_velocity_scales(&self, scales: Vec<f64>) {
        if let Ok(mut k) = self.kept.lock() {
            k.scales = scales;
        }
    }

    /// Largest wake-up latency so far, ns.
    pub fn max_wake_latency_ns(&self) -> u64 {
        self.kept.lock().map_or(0, |mut k| {
            k.drain();
            k.max_wake_latency_ns
        })
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn drain(kept: &Mutex<Kept>, stop: &AtomicBool) {
    loop {
        let last = stop.load(Ordering::Acquire);
        if let Ok(mut k) = kept.lock() {
            k.drain();
        }
        if last {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
