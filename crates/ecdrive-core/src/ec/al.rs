//! Application-layer (AL) states, the AL status register and AL status codes (ETG.1000.6).

use core::fmt;

/// An EtherCAT state machine (ESM) state, as written to AL control (0x0120) and read from AL
/// status (0x0130) bits 0–3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum AlState {
    /// INIT: no mailbox, no process data.
    Init = 0x01,
    /// PRE-OP: mailbox communication.
    PreOp = 0x02,
    /// BOOT: firmware update (FoE only).
    Bootstrap = 0x03,
    /// SAFE-OP: inputs valid, outputs in a safe state.
    SafeOp = 0x04,
    /// OP: inputs and outputs valid.
    Op = 0x08,
}

impl AlState {
    /// Decode the low four bits of AL control or AL status. `None` for values that are no state.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        match bits & 0x0F {
            0x01 => Some(Self::Init),
            0x02 => Some(Self::PreOp),
            0x03 => Some(Self::Bootstrap),
            0x04 => Some(Self::SafeOp),
            0x08 => Some(Self::Op),
            _ => None,
        }
    }

    /// The short name used by the IgH tool and in log messages: `INIT`, `PREOP`, `BOOT`,
    /// `SAFEOP`, `OP`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Init => "INIT",
            Self::PreOp => "PREOP",
            Self::Bootstrap => "BOOT",
            Self::SafeOp => "SAFEOP",
            Self::Op => "OP",
        }
    }

    /// Parse a state name as users type it (`init`, `preop`, `pre-op`, `safeop`, `safe-op`,
    /// `op`, `boot`), case-insensitive.
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_uppercase().replace(['-', '_'], "");
        match s.as_str() {
            "INIT" => Some(Self::Init),
            "PREOP" => Some(Self::PreOp),
            "BOOT" | "BOOTSTRAP" => Some(Self::Bootstrap),
            "SAFEOP" => Some(Self::SafeOp),
            "OP" => Some(Self::Op),
            _ => None,
        }
    }
}

impl fmt::Display for AlState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The AL status register (0x0130): the current state, the error flag and the ID flag.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub struct AlStatus {
    /// Raw register value.
    pub raw: u16,
}

impl AlStatus {
    /// Error indication flag (bit 4): the last requested transition failed or the device left
    /// a state on its own; the reason is in AL status code (0x0134).
    pub const ERROR: u16 = 0x0010;
    /// Device identification loaded (bit 5).
    pub const ID_LOADED: u16 = 0x0020;

    /// The state in bits 0–3, if it is a valid state.
    pub const fn state(self) -> Option<AlState> {
        AlState::from_bits(self.raw as u8)
    }

    /// Whether the error flag is set.
    pub const fn error(self) -> bool {
        self.raw & Self::ERROR != 0
    }
}

impl fmt::Display for AlStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.state() {
            Some(s) => write!(f, "{s}")?,
            None => write!(f, "state 0x{:X}", self.raw & 0x0F)?,
        }
        if self.error() {
            f.write_str("+ERR")?;
        }
        Ok(())
    }
}

/// An AL status code (register 0x0134), with its ETG.1000.6 meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct AlStatusCode(pub u16);

macro_rules! al_codes {
    ($( $name:ident = $value:literal, $text:literal; )*) => {
        impl AlStatusCode {
            $(
                #[doc = $text]
                pub const $name: Self = Self($value);
            )*

            /// The ETG.1000.6 text for this code, or `None` for codes the standard does not list
            /// (vendor-specific codes are 0x8000 and above).
            pub const fn text(self) -> Option<&'static str> {
                match self.0 {
                    $( $value => Some($text), )*
                    _ => None,
                }
            }
        }
    };
}

al_codes! {
    NO_ERROR = 0x0000, "No error";
    UNSPECIFIED = 0x0001, "Unspecified error";
    NO_MEMORY = 0x0002, "No memory";
    INVALID_DEVICE_SETUP = 0x0003, "Invalid device setup";
    SII_MISMATCH = 0x0006, "SII/EEPROM information does not match firmware";
    FIRMWARE_UPDATE_FAILED = 0x0007, "Firmware update not successful";
    LICENSE_ERROR = 0x000E, "License error";
    INVALID_STATE_CHANGE = 0x0011, "Invalid requested state change";
    UNKNOWN_STATE = 0x0012, "Unknown requested state";
    BOOTSTRAP_NOT_SUPPORTED = 0x0013, "Bootstrap not supported";
    NO_VALID_FIRMWARE = 0x0014, "No valid firmware";
    INVALID_MAILBOX_CONFIG_BOOT = 0x0015, "Invalid mailbox configuration (BOOT)";
    INVALID_MAILBOX_CONFIG = 0x0016, "Invalid mailbox configuration (PREOP)";
    INVALID_SM_CONFIG = 0x0017, "Invalid sync manager configuration";
    NO_VALID_INPUTS = 0x0018, "No valid inputs available";
    NO_VALID_OUTPUTS = 0x0019, "No valid outputs";
    SYNC_ERROR = 0x001A, "Synchronization error";
    SM_WATCHDOG = 0x001B, "Sync manager watchdog";
    INVALID_SM_TYPES = 0x001C, "Invalid sync manager types";
    INVALID_OUTPUT_CONFIG = 0x001D, "Invalid output configuration";
    INVALID_INPUT_CONFIG = 0x001E, "Invalid input configuration";
    INVALID_WATCHDOG_CONFIG = 0x001F, "Invalid watchdog configuration";
    NEEDS_COLD_START = 0x0020, "Slave needs cold start";
    NEEDS_INIT = 0x0021, "Slave needs INIT";
    NEEDS_PREOP = 0x0022, "Slave needs PREOP";
    NEEDS_SAFEOP = 0x0023, "Slave needs SAFEOP";
    INVALID_INPUT_MAPPING = 0x0024, "Invalid input mapping";
    INVALID_OUTPUT_MAPPING = 0x0025, "Invalid output mapping";
    INCONSISTENT_SETTINGS = 0x0026, "Inconsistent settings";
    FREERUN_NOT_SUPPORTED = 0x0027, "FreeRun not supported";
    SYNCMODE_NOT_SUPPORTED = 0x0028, "SyncMode not supported";
    FREERUN_NEEDS_3BUFFER = 0x0029, "FreeRun needs 3-buffer mode";
    BACKGROUND_WATCHDOG = 0x002A, "Background watchdog";
    NO_VALID_INPUTS_OUTPUTS = 0x002B, "No valid inputs and outputs";
    FATAL_SYNC_ERROR = 0x002C, "Fatal sync error";
    NO_SYNC_ERROR = 0x002D, "No sync error";
    CYCLE_TIME_TOO_SMALL = 0x002E, "Cycle time too small";
    INVALID_DC_SYNC_CONFIG = 0x0030, "Invalid DC SYNC configuration";
    INVALID_DC_LATCH_CONFIG = 0x0031, "Invalid DC latch configuration";
    PLL_ERROR = 0x0032, "PLL error";
    DC_SYNC_IO_ERROR = 0x0033, "DC sync IO error";
    DC_SYNC_TIMEOUT = 0x0034, "DC sync timeout error";
    DC_INVALID_CYCLE_TIME = 0x0035, "DC invalid sync cycle time";
    DC_SYNC0_CYCLE_TIME = 0x0036, "DC SYNC0 cycle time";
    DC_SYNC1_CYCLE_TIME = 0x0037, "DC SYNC1 cycle time";
    MBX_AOE = 0x0041, "Mailbox AoE error";
    MBX_EOE = 0x0042, "Mailbox EoE error";
    MBX_COE = 0x0043, "Mailbox CoE error";
    MBX_FOE = 0x0044, "Mailbox FoE error";
    MBX_SOE = 0x0045, "Mailbox SoE error";
    MBX_VOE = 0x004F, "Mailbox VoE error";
    EEPROM_NO_ACCESS = 0x0050, "EEPROM no access";
    EEPROM_ERROR = 0x0051, "EEPROM error";
    EXTERNAL_HARDWARE_NOT_READY = 0x0052, "External hardware not ready";
    RESTARTED_LOCALLY = 0x0060, "Slave restarted locally";
    DEVICE_ID_UPDATED = 0x0061, "Device identification value updated";
    MODULE_ID_LIST_MISMATCH = 0x0070, "Detected module ident list does not match";
    APPLICATION_CONTROLLER_AVAILABLE = 0x00F0, "Application controller available";
}

impl fmt::Display for AlStatusCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.text() {
            Some(t) => write!(f, "0x{:04X} ({t})", self.0),
            None if self.0 >= 0x8000 => write!(f, "0x{:04X} (vendor-specific)", self.0),
            None => write!(f, "0x{:04X} (unknown AL status code)", self.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_round_trip_and_names() {
        for s in [
            AlState::Init,
            AlState::PreOp,
            AlState::Bootstrap,
            AlState::SafeOp,
            AlState::Op,
        ] {
            assert_eq!(AlState::from_bits(s as u8), Some(s));
            assert_eq!(AlState::parse(s.name()), Some(s));
        }
        assert_eq!(AlState::parse("safe-op"), Some(AlState::SafeOp));
        assert_eq!(AlState::from_bits(0x05), None);
    }

    #[test]
    fn status_display_shows_error_flag() {
        assert_eq!(AlStatus { raw: 0x0014 }.to_string(), "SAFEOP+ERR");
        assert_eq!(AlStatus { raw: 0x0008 }.to_string(), "OP");
    }

    #[test]
    fn code_texts() {
        assert_eq!(
            AlStatusCode::SM_WATCHDOG.to_string(),
            "0x001B (Sync manager watchdog)"
        );
        assert_eq!(AlStatusCode(0x8001).to_string(), "0x8001 (vendor-specific)");
    }
}
