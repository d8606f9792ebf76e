//! The CANopen applications: the demo and the tools behind `ecdrive … --can`.

pub mod candump;
pub mod demo;
pub mod eds;
pub mod reset;
pub mod run;
pub mod steps;
pub mod tools;
