//! # ecdrive-ethercat
//!
//! The EtherCAT master: ethercrab integration, start-up, PDO and DC configuration, the cyclic
//! loop, supervision. Built on `ecdrive-core` and `ecdrive-motion`; it does not depend on the
//! software slave (`ecdrive-sim`) in any way, not even for its own tests: the tests that run it
//! against emulated drives live in the root package.
//!
//! An application needs only the types at the crate root: [`Master`] with its
//! [`MasterConfig`] (a [`DriveSetup`] per drive, found by a [`Selector`], with a program of
//! [`Step`]s), [`Command`]s in, [`Telemetry`] and the history out, a [`SessionReport`] at the
//! end. Code of its own runs in the cycle as a [`CycleApp`] (typed access to every axis through
//! [`AppAxis`]); set-points streamed from other threads go through [`Streams`]. The modules below are the master's parts, public for the tools built on them.
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

// The core layers this crate builds on, under the paths the modules use.
pub(crate) use ecdrive_core::{cia402, drives, ec, link, od, pdo, rt};
// The motion runtime this master runs per axis (shared with the CANopen master), under the
// paths the applications know.
pub use ecdrive_motion::{app, program, setpoint, stream, telemetry};

pub mod answers;
pub mod bus;
pub mod coe;
pub mod cycle;
pub mod error;
pub mod exec;
mod history;
pub mod io;
mod record;
pub mod session;
mod sii_bulk;
pub mod startup;
mod supervise;

mod wkc;

pub use app::{AppAxis, AppCycle, CycleApp, EntryError, SetpointLimits};
pub use cycle::{CycleEnd, CycleReport, CycleSettings, FramesBy, ReplyWait};
pub use error::{DriveRef, ErrorKind, MasterError};
pub use history::{HistoryEntry, HistoryEvent, HistoryKind, HistoryLog, Resolved, RestartNote};
pub use program::{ProbeEdge, RunMode, Step, Target};
pub use record::{CSV_HEADER, CsvWriter, CycleSample, RecordTx, Recording, SampleScale, recording};
pub use session::{
    DriveOutcome, DriveSummary, Master, MasterConfig, SdoRequester, SessionReport, StartFailure,
};
pub use startup::{DriveSetup, Selector, StartupConfig, StartupFrames, StartupTimes};
pub use stream::{StreamProducer, Streams};
pub use telemetry::{
    Axes, AxisTelemetry, Command, CycleTelemetry, DriveTask, Event, EventKind, ProbeState,
    StopKind, StopReason, Telemetry,
};
pub use wkc::{DatagramWkc, WkcPlan};
