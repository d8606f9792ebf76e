//! Controlword (0x6040) and statusword (0x6041) as bit sets.
//!
//! Bits 4–6, 8, 9 of the controlword and bits 10, 12, 13 of the statusword mean different things
//! in different modes of operation. Each meaning has its own named constant; constants that share
//! a bit are aliases (e.g. [`ControlWord::NEW_SET_POINT`] and [`ControlWord::HOMING_START`] are
//! both bit 4). Which alias applies depends on the mode in 0x6061.

use bitflags::bitflags;

use super::state::State;

bitflags! {
    /// Controlword, object 0x6040 (UNSIGNED16).
    ///
    /// Bits 0–3 and 7 select the device-control command (see [`Command`](super::Command)); the
    /// rest are mode-specific, halt, reserved or manufacturer-specific. Unknown bits are kept
    /// as they are (`from_bits_retain`), so any 16-bit value round-trips.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct ControlWord: u16 {
        /// Bit 0, switch on.
        const SWITCH_ON = 1 << 0;
        /// Bit 1, enable voltage.
        const ENABLE_VOLTAGE = 1 << 1;
        /// Bit 2, quick stop. **Active low**: 0 requests a quick stop.
        const QUICK_STOP = 1 << 2;
        /// Bit 3, enable operation.
        const ENABLE_OPERATION = 1 << 3;
        /// Bit 4 in pp (and the MR-J4 pt/idx modes): new set-point, taken on the rising edge.
        const NEW_SET_POINT = 1 << 4;
        /// Bit 4 in hm: homing operation start (1 = start/continue).
        const HOMING_START = 1 << 4;
        /// Bit 5 in pp: change set immediately (1 = single set-point, abort the current move).
        const CHANGE_SET_IMMEDIATELY = 1 << 5;
        /// Bit 6 in pp: 0 = absolute, 1 = relative target position.
        const RELATIVE = 1 << 6;
        /// Bit 7, fault reset: a 0 → 1 edge resets a fault (transition 15).
        const FAULT_RESET = 1 << 7;
        /// Bit 8, halt: 1 = stop per 0x605D (pp, pv, tq, hm; ignored in csp/csv/cst on many drives).
        const HALT = 1 << 8;
        /// Bit 9 in pp: change on set-point (only with bit 5 = 0).
        const CHANGE_ON_SET_POINT = 1 << 9;
        /// Bit 10, reserved (write 0).
        const RESERVED_10 = 1 << 10;
        /// Bit 11, manufacturer-specific.
        const MANUFACTURER_11 = 1 << 11;
        /// Bit 12, manufacturer-specific.
        const MANUFACTURER_12 = 1 << 12;
        /// Bit 13, manufacturer-specific.
        const MANUFACTURER_13 = 1 << 13;
        /// Bit 14, manufacturer-specific.
        const MANUFACTURER_14 = 1 << 14;
        /// Bit 15, manufacturer-specific.
        const MANUFACTURER_15 = 1 << 15;
    }
}

impl ControlWord {
    /// The bits that encode a device-control command: 0, 1, 2, 3 and 7 (`0x008F`).
    pub const COMMAND_MASK: u16 = 0x008F;
    /// The mode-specific bits 4, 5, 6, 8 and 9 (`0x0370`): what an application may set in a mode
    /// of operation (new set-point, change set immediately, abs/rel, halt, change on set-point,
    /// homing start).
    pub const MODE_SPECIFIC_MASK: u16 = 0x0370;

    /// A controlword from its raw value; every value is accepted.
    pub const fn from_raw(raw: u16) -> Self {
        Self::from_bits_retain(raw)
    }

    /// The raw 16-bit value.
    pub const fn raw(self) -> u16 {
        self.bits()
    }

    /// Only the mode-specific bits (4, 5, 6, 8, 9) of this controlword.
    pub const fn mode_specific(self) -> Self {
        Self::from_bits_retain(self.bits() & Self::MODE_SPECIFIC_MASK)
    }
}

bitflags! {
    /// Statusword, object 0x6041 (UNSIGNED16).
    ///
    /// Bits 0, 1, 2, 3, 5, 6 encode the device state ([`StatusWord::state`]); the others are
    /// status flags, mode-specific or manufacturer-specific. Any 16-bit value is accepted.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct StatusWord: u16 {
        /// Bit 0, ready to switch on.
        const READY_TO_SWITCH_ON = 1 << 0;
        /// Bit 1, switched on.
        const SWITCHED_ON = 1 << 1;
        /// Bit 2, operation enabled.
        const OPERATION_ENABLED = 1 << 2;
        /// Bit 3, fault.
        const FAULT = 1 << 3;
        /// Bit 4, voltage enabled (main/DC-bus voltage present).
        const VOLTAGE_ENABLED = 1 << 4;
        /// Bit 5, quick stop. **Active low**: 0 = a quick stop is in progress (in the states where
        /// the bit is defined).
        const QUICK_STOP = 1 << 5;
        /// Bit 6, switch on disabled.
        const SWITCH_ON_DISABLED = 1 << 6;
        /// Bit 7, warning.
        const WARNING = 1 << 7;
        /// Bit 8, manufacturer-specific (e.g. BLV-R "DPRDY").
        const MANUFACTURER_8 = 1 << 8;
        /// Bit 9, remote: 1 = the drive follows the controlword.
        const REMOTE = 1 << 9;
        /// Bit 10 in pp/pv/tq/hm: target reached (with halt = 1: the axis has stopped).
        const TARGET_REACHED = 1 << 10;
        /// Bit 11, internal limit active (e.g. stroke end or software position limit).
        const INTERNAL_LIMIT_ACTIVE = 1 << 11;
        /// Bit 12 in pp (and the MR-J4 pt/idx modes): set-point acknowledge.
        const SET_POINT_ACKNOWLEDGE = 1 << 12;
        /// Bit 12 in csp/csv/cst: drive follows the command value (0 = target ignored).
        const DRIVE_FOLLOWS_COMMAND = 1 << 12;
        /// Bit 12 in pv: speed is zero.
        const SPEED_ZERO = 1 << 12;
        /// Bit 12 in hm: homing attained.
        const HOMING_ATTAINED = 1 << 12;
        /// Bit 13 in pp/csp: following error.
        const FOLLOWING_ERROR = 1 << 13;
        /// Bit 13 in hm: homing error.
        const HOMING_ERROR = 1 << 13;
        /// Bit 14, manufacturer-specific.
        const MANUFACTURER_14 = 1 << 14;
        /// Bit 15, manufacturer-specific.
        const MANUFACTURER_15 = 1 << 15;
    }
}

impl StatusWord {
    /// The bits that encode the device state: 0, 1, 2, 3, 5, 6 (`0x006F`).
    pub const STATE_MASK: u16 = 0x006F;

    /// A statusword from its raw value; every value is accepted.
    pub const fn from_raw(raw: u16) -> Self {
        Self::from_bits_retain(raw)
    }

    /// The raw 16-bit value.
    pub const fn raw(self) -> u16 {
        self.bits()
    }

    /// The device state this statusword encodes, or `None` when bits 0–3, 5, 6 match no row of
    /// the CiA 402 table. Never panics; see [`State::from_statusword`].
    pub const fn state(self) -> Option<State> {
        State::from_statusword(self.bits())
    }

    /// This statusword with its state bits (0–3, 5, 6) replaced by the canonical pattern of
    /// `state`; all other bits are kept.
    pub const fn with_state(self, state: State) -> Self {
        Self::from_bits_retain((self.bits() & !Self::STATE_MASK) | state.statusword_bits())
    }
}
