//! Set-points streamed from non-real-time code (a ROS 2 node, a Python producer at 1 kHz): one
//! lock-free ring per axis, of a depth the producer chooses, consumed one set-point per cycle
//! while the axis takes set-points.
//!
//! [`Streams`] is a [`CycleApp`]: give it to the master as its application (or call its
//! [`Streams::cycle`] from an application of your own). The producer side, a
//! [`StreamProducer`] per axis, lives on any thread: it pushes set-points, sees the fill level,
//! the set-points consumed and the underruns. An underrun (the ring empty in a cycle where the
//! axis takes set-points, after the first set-point) holds the last set-point, counts, and is
//! reported once per underrun as [`EventKind::StreamUnderrun`].

use crate::app::{AppCycle, CycleApp};
use crate::telemetry::EventKind;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// What the producer can see of its stream.
#[derive(Debug, Default)]
struct Counters {
    consumed: AtomicU64,
    underruns: AtomicU64,
}

/// The producer end of one axis's set-point stream.
pub struct StreamProducer {
    tx: rtrb::Producer<f64>,
    depth: usize,
    counters: Arc<Counters>,
}

impl StreamProducer {
    /// Queue a set-point (drive units of the axis's mode, as [`AppAxis::set_target`](crate::app::AppAxis::set_target));
    /// `Err` with it back when the ring is full.
    pub fn push(&mut self, value: f64) -> Result<(), f64> {
        self.tx.push(value).map_err(|rtrb::PushError::Full(v)| v)
    }
    /// Set-points waiting.
    pub fn fill(&self) -> usize {
        self.depth - self.tx.slots()
    }
    /// Room left.
    pub fn free(&self) -> usize {
        self.tx.slots()
    }
    /// The ring's depth.
    pub fn depth(&self) -> usize {
        self.depth
    }
    /// Set-points the cycle took so far.
    pub fn consumed(&self) -> u64 {
        self.counters.consumed.load(Ordering::Relaxed)
    }
    /// Cycles in which the axis took set-points but the ring was empty (the last one held).
    pub fn underruns(&self) -> u64 {
        self.counters.underruns.load(Ordering::Relaxed)
    }
}

struct Consumer {
    axis: usize,
    rx: rtrb::Consumer<f64>,
    counters: Arc<Counters>,
    last: Option<f64>,
    in_underrun: bool,
}

/// The cycle's end of every axis's stream.
#[derive(Default)]
pub struct Streams {
    consumers: Vec<Consumer>,
}

impl Streams {
    /// No stream yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// A stream of `depth` set-points for axis `axis` (configuration order); its producer.
    /// A second stream for the same axis replaces the first.
    pub fn add(&mut self, axis: usize, depth: usize) -> StreamProducer {
        let depth = depth.max(1);
        let (tx, rx) = rtrb::RingBuffer::new(depth);
        let counters = Arc::new(Counters::default());
        self.consumers.retain(|c| c.axis != axis);
        self.consumers.push(Consumer {
            axis,
            rx,
            counters: counters.clone(),
            last: None,
            in_underrun: false,
        });
        StreamProducer {
            tx,
            depth,
            counters,
        }
    }
}

impl CycleApp for Streams {
    /// One set-point per axis that takes set-points now (Operation enabled, no program).
    fn cycle(&mut self, c: &mut AppCycle<'_>) {
        for s in self.consumers.iter_mut() {
            let Some(axis) = c.axis(s.axis) else {
                continue;
            };
            if !axis.enabled() || axis.program_running() {
                continue;
            }
            match s.rx.pop() {
                Ok(v) => {
                    s.last = Some(v);
                    s.in_underrun = false;
                    axis.set_target(v);
                    s.counters.consumed.fetch_add(1, Ordering::Relaxed);
                }
                Err(rtrb::PopError::Empty) => {
                    let Some(v) = s.last else { continue };
                    axis.set_target(v);
                    let total = s.counters.underruns.fetch_add(1, Ordering::Relaxed) + 1;
                    if !s.in_underrun {
                        s.in_underrun = true;
                        c.emit(EventKind::StreamUnderrun {
                            axis: s.axis as u16,
                            total,
                        });
                    }
                }
            }
        }
    }
}
