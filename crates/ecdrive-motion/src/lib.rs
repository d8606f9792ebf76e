//! # ecdrive-motion
//!
//! The motion runtime both masters share: what an axis does once its drive is in Operation
//! enabled, independent of the bus that carries it. Per axis one I/O-free step per cycle
//! ([`MotionAxis::step`]): the drive's feedback and the application's requests in, the CiA 402
//! engine's output and the run's events out. It holds the programs and their set-point
//! generation ([`program`], [`setpoint`]), homing, the profile modes pp/pv/tq, the touch
//! probes, controlled stops, following-error supervision and the limits of the application's
//! set-points; the events and telemetry it reports are the vocabulary both masters publish
//! ([`telemetry`]). The application's code in the cycle ([`CycleApp`], its view of an axis
//! [`AppAxis`]) and set-points streamed from other threads ([`Streams`]) are the same on both
//! buses: each master builds the views, calls the application between its read and its step,
//! and hands the requests to the step.
//!
//! Built on `ecdrive-core` only: the masters read their bus into a
//! [`Feedback`](ecdrive_core::cia402::Feedback), call the step and write its
//! [`Output`](ecdrive_core::cia402::Output) back. Nothing here allocates or blocks per cycle.
#![warn(missing_docs)]

pub(crate) use ecdrive_core::cia402;

pub mod app;
mod axis;
mod limits;
pub mod program;
pub mod setpoint;
pub mod stream;
pub mod telemetry;

pub use app::{AppAxis, AppCycle, CycleApp, EntryError};
pub use axis::{
    AxisSetup, DRIVE_FE_STUCK_CYCLES, EventSink, FEEDBACK_PULSES, Inputs, MODES_KEPT, MotionAxis,
    ProbeObjects, Requests, STANDSTILL_REV_S, SetpointSteps, StepContext, mode_names,
};
pub use limits::SetpointLimits;
pub use program::{ProbeEdge, RunMode, Step, Target};
pub use stream::{StreamProducer, Streams};
