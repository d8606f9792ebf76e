//! # ecdrive
//!
//! An EtherCAT master for CiA 402 servo drives, built on [`ethercrab`], with a software EtherCAT
//! slave that emulates the drives on the wire.
//!
//! The layers, from the wire up (data flows one way: wire → slave/master → process image →
//! cia402 → application). This crate is the façade: each module is one of ecdrive's crates, or
//! a part of one, re-exported under one path (the core layers are the crate `ecdrive-core`,
//! under the same names), and the EtherCAT master's entry points are at the root:
//!
//! | module | what it is |
//! |---|---|
//! | [`ec`] | EtherCAT protocol definitions shared by master and slave: frames, datagrams, registers, AL states and codes, mailbox and CoE headers, as typed views over byte buffers |
//! | [`od`] | CANopen object dictionary types: addresses, data types, access, object descriptions, SDO abort codes |
//! | [`pdo`] | PDO mapping model, layout into the process image, limits, and the SDO sequence that remaps a drive |
//! | [`cia402`] | the pure CiA 402 layer: control/status words, states, modes, the transition planner and the per-cycle axis engine. No I/O, no clocks |
//! | [`esi`] | ESI (ETG.2000) XML parsing |
//! | [`drives`] | one file per drive: identity, defaults, quirks and alarm tables, as data |
//! | [`link`] | Ethernet frame I/O: raw `AF_PACKET` sockets and the in-process link |
//! | [`sim`] | the software EtherCAT slave: ESC registers, SII, mailbox/CoE, DC and emulated drives |
//! | [`master`] | the EtherCAT master (`ecdrive-ethercat`): start-up, PDO and DC configuration, the cyclic loop |
//! | [`rt`] | real-time thread set-up, absolute-time sleeping, statistics |
//! | [`can`] | CANopen (CiA 301) wire vocabulary and protocols shared by master and emulated nodes: frames, NMT, SDO, EMCY, transports, the CANopen part of the drive profile |
//! | [`canopen`] | the CANopen master (`ecdrive-canopen`): the same CiA 402 layer over CANopen |
//! | [`motion`] | the motion runtime both masters step their axes with (`ecdrive-motion`): programs, homing, profile modes, probes, stops, supervision |
//!
//! The `ecdrive` command and its applications (demo, soak, commissioning tools, the `ecdrive run`
//! configuration file, the jitter harness) are a package of their own, `ecdrive-cli`, built on
//! this façade; nothing here depends on them.
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

pub use ecdrive_core::{can, cia402, drives, ec, eds, esi, link, od, pdo, rt};
/// The motion runtime both masters step their axes with (`ecdrive-motion`).
pub use ecdrive_motion as motion;
pub use ecdrive_sim as sim;

// The façade: what an application driving EtherCAT drives uses, from one path (the README's
// library example imports nothing else). The CANopen master's entry points are at
// `ecdrive::canopen::{Master, MasterConfig, DriveSetup, CanDrive}`.
pub use cia402::{OperationMode, State};
pub use drives::DriveProfile;
pub use ecdrive_core::ErrorClass;
pub use ecdrive_ethercat::{
    AppAxis, AppCycle, Axes, AxisTelemetry, Command, CycleApp, CycleTelemetry, DriveRef,
    DriveSetup, EntryError, ErrorKind, Event, EventKind, HistoryEntry, HistoryEvent, HistoryKind,
    Master, MasterConfig, MasterError, RunMode, Selector, SessionReport, SetpointLimits,
    StartFailure, Step, StopKind, StopReason, StreamProducer, Streams, Target, Telemetry,
};
pub use link::RawSocket;

pub mod canopen;
pub mod master;

/// The README's Rust examples, compiled by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
struct ReadmeDoctests;

/// The book's Rust examples (docs/guide/library.md), compiled by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/guide/library.md")]
struct GuideLibraryDoctests;
