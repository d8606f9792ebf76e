//! The emulator's own tables of the project's CANopen drives, one file each, written from the
//! drives' manuals: dictionary, CiA 402 behaviour, PDO rules, EMCY and alarms, homing, units,
//! NMT error control and quirks. They share no value with the master's profiles
//! (`crates/ecdrive-sim/tests/sim/emulation_independence.rs`); `tests/app/manual_facts.rs` checks both against the manuals
//! over the bus, so a wrong value on either side shows up as a disagreement.
//!
//! A vendor's EDS file can stand in for a table's dictionary ([`NodeSpec::refined`]), and any
//! other CiA 402 drive is emulated from its file alone ([`NodeSpec::from_eds`]).

pub mod asda_a2;
pub mod blv_r;
pub mod lexium_mdrive;

use super::spec::NodeSpec;
use crate::can::profile::HomingSupport;
use crate::cia402::{DriveCaps, SupportedModes};

/// The Lexium MDrive's closed-loop models (encoder, hMTechnology): as the open-loop table, plus
/// tq (§6.8, although 6502h still reads 25h as the manual prints it) and the homing methods on
/// the encoder's index pulse.
pub const LEXIUM_MDRIVE_CLOSED_LOOP: NodeSpec = NodeSpec {
    name: "Lexium MDrive (closed loop)",
    caps: DriveCaps {
        supported_modes: SupportedModes::from_raw(0x0000_002D),
        ..lexium_mdrive::SPEC.caps
    },
    homing: HomingSupport {
        index_pulse: true,
        ..lexium_mdrive::SPEC.homing
    },
    ..lexium_mdrive::SPEC
};

/// Every table by the name `ecdrive sim --can --node NAME` takes.
pub const ALL: [(&str, &NodeSpec); 4] = [
    ("blv-r", &blv_r::SPEC),
    ("asda-a2", &asda_a2::SPEC),
    ("lexium-mdrive", &lexium_mdrive::SPEC),
    ("lexium-mdrive-closed-loop", &LEXIUM_MDRIVE_CLOSED_LOOP),
];

/// The table named `name` (see [`ALL`]).
pub fn by_name(name: &str) -> Option<&'static NodeSpec> {
    ALL.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}
