//! # ecdrive-core
//!
//! The layers of ecdrive that both buses, both masters and the software slave stand on. Nothing
//! here talks to a bus master: no ethercrab, no threads of its own, no application code.
//!
//! | module | what it is |
//! |---|---|
//! | [`ec`] | EtherCAT protocol definitions shared by master and slave: frames, datagrams, registers, AL states and codes, mailbox and CoE headers, as typed views over byte buffers |
//! | [`can`] | CANopen (CiA 301) wire vocabulary and protocols: frames, NMT, SDO, EMCY, transports, the CANopen drive-profile type |
//! | [`od`] | CANopen object dictionary types: addresses, data types, access, object descriptions, SDO abort codes |
//! | [`pdo`] | PDO mapping model, layout into the process image, limits, and the SDO sequence that remaps a drive |
//! | [`cia402`] | the pure CiA 402 layer: control/status words, states, modes, the transition planner and the per-cycle axis engine. No I/O, no clocks |
//! | [`esi`] | ESI (ETG.2000) XML parsing |
//! | [`drives`] | one file per drive: identity, defaults, quirks and alarm tables, as data (the masters' drive profiles) |
//! | [`link`] | Ethernet frame I/O: raw `AF_PACKET` sockets, network namespaces and veth pairs |
//! | [`rt`] | real-time thread set-up, absolute-time sleeping, statistics, the allocation and syscall audit |
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

pub mod can;
pub mod cia402;
pub mod drives;
pub mod ec;
pub mod eds;
mod error_class;
pub mod esi;
pub mod link;
pub mod od;
pub mod pdo;
pub mod rt;

pub use error_class::ErrorClass;
