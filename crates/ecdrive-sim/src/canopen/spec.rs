//! What an emulated CANopen node is, as data: its object dictionary plus the emulator's own
//! model of the drive's behaviour (state machine and modes, PDO rules, EMCY layout and alarm
//! table, homing methods, units of the motor model, NMT error control, rate limits, quirks).
//!
//! The node engine ([`super::EmulatedNode`]) reads a [`NodeSpec`] and never asks which vendor it
//! emulates. A spec comes from one of two places, never from the master:
//! - the emulator's own tables for the project's three drives ([`super::drives`]), written from
//!   their manuals, so that a wrong value on the master's side or the emulator's shows up as a
//!   disagreement (`tests/app/manual_facts.rs` checks both against the manuals);
//! - a vendor's EDS file ([`NodeSpec::from_eds`]) for any other CiA 402 drive: the file's
//!   dictionary, modes and PDO counts, with CiA 402's behaviour where the file says nothing.
//!
//! The field *types* are the shared CANopen vocabulary (`can::profile`); the *values* are the
//! emulator's.

use super::quirks::EmulationQuirks;
use crate::can::profile::{
    Alarm, CanPdoProfile, CommSupport, EmcyFormat, EnabledNmtReaction, HomingSupport,
};
use crate::cia402::DriveCaps;
use crate::cia402::units::Units;
use crate::od::{ObjectAddress, ObjectDesc};

/// An emulated CANopen drive model. See the [module documentation](self).
#[derive(Debug, Clone, Copy)]
pub struct NodeSpec {
    /// Model name, for messages (`"BLV-R"`).
    pub name: &'static str,
    /// Vendor name.
    pub vendor: &'static str,
    /// Where the values come from (a manual, or an EDS file's path).
    pub source: &'static str,
    /// The object dictionary at power-on. COB-IDs of node-relative objects are written for
    /// node-ID 0; the node adds its own.
    pub dictionary: &'static [ObjectDesc],
    /// The CiA 402 state machine and modes (0x6502), the quick-stop options, the error-code
    /// names.
    pub caps: DriveCaps,
    /// The units of the motor model (position units per revolution, velocity and torque
    /// units).
    pub units: Units,
    /// PDO rules and power-on PDOs.
    pub pdo: CanPdoProfile,
    /// Homing methods 0x6098 accepts.
    pub homing: HomingSupport,
    /// Where the vendor alarm number goes in an EMCY.
    pub emcy: EmcyFormat,
    /// The alarm table.
    pub alarms: &'static [Alarm],
    /// Error control, SYNC, error history, store, rate limits.
    pub comm: CommSupport,
    /// Reaction to NMT Stop while the power stage is enabled.
    pub nmt_stop_while_enabled: EnabledNmtReaction,
    /// Reaction to NMT Reset node / Reset communication while enabled.
    pub nmt_reset_while_enabled: EnabledNmtReaction,
    /// Targets the drive clears when it enables.
    pub targets_cleared_on_enable: &'static [ObjectAddress],
    /// What the node does beyond CiA 301/402.
    pub quirks: EmulationQuirks,
}

impl NodeSpec {
    /// The alarm with vendor number `number`.
    pub fn alarm(&self, number: u16) -> Option<&'static Alarm> {
        let alarms: &'static [Alarm] = self.alarms;
        alarms.iter().find(|a| a.number == number)
    }
}
