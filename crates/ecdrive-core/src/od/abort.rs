use core::fmt;

/// An SDO abort code (CiA 301 §7.2.4.3.17, with the EtherCAT additions of ETG.1000.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct SdoAbortCode(pub u32);

macro_rules! abort_codes {
    ($( $name:ident = $value:literal, $text:literal; )*) => {
        impl SdoAbortCode {
            $(
                #[doc = $text]
                pub const $name: Self = Self($value);
            )*

            /// The standard text for this code, or `None` for a code neither CiA 301 nor
            /// ETG.1000.6 defines.
            pub const fn text(self) -> Option<&'static str> {
                match self.0 {
                    $( $value => Some($text), )*
                    _ => None,
                }
            }

            /// Every code the standards define, in numeric order.
            pub const ALL: &'static [SdoAbortCode] = &[$( Self::$name, )*];
        }
    };
}

abort_codes! {
    TOGGLE_BIT = 0x0503_0000, "Toggle bit not alternated";
    TIMEOUT = 0x0504_0000, "SDO protocol timed out";
    INVALID_COMMAND = 0x0504_0001, "Client/server command specifier not valid or unknown";
    INVALID_BLOCK_SIZE = 0x0504_0002, "Invalid block size (block mode only)";
    INVALID_SEQUENCE = 0x0504_0003, "Invalid sequence number (block mode only)";
    CRC_ERROR = 0x0504_0004, "CRC error (block mode only)";
    OUT_OF_MEMORY = 0x0504_0005, "Out of memory";
    UNSUPPORTED_ACCESS = 0x0601_0000, "Unsupported access to an object";
    WRITE_ONLY = 0x0601_0001, "Attempt to read a write only object";
    READ_ONLY = 0x0601_0002, "Attempt to write a read only object";
    SUBINDEX0_NOT_ZERO = 0x0601_0003, "Subindex cannot be written, SI0 must be 0 for write access";
    COMPLETE_ACCESS_UNSUPPORTED = 0x0601_0004, "SDO Complete access not supported for objects of variable length";
    OBJECT_TOO_LONG = 0x0601_0005, "Object length exceeds mailbox size";
    MAPPED_TO_RXPDO = 0x0601_0006, "Object mapped to RxPDO, SDO download blocked";
    NO_OBJECT = 0x0602_0000, "Object does not exist in the object dictionary";
    NOT_MAPPABLE = 0x0604_0041, "Object cannot be mapped to the PDO";
    PDO_TOO_LONG = 0x0604_0042, "The number and length of the objects to be mapped would exceed the PDO length";
    PARAMETER_INCOMPATIBLE = 0x0604_0043, "General parameter incompatibility reason";
    INTERNAL_INCOMPATIBLE = 0x0604_0047, "General internal incompatibility in the device";
    HARDWARE_ERROR = 0x0606_0000, "Access failed due to a hardware error";
    LENGTH_MISMATCH = 0x0607_0010, "Data type does not match, length of service parameter does not match";
    LENGTH_TOO_HIGH = 0x0607_0012, "Data type does not match, length of service parameter too high";
    LENGTH_TOO_LOW = 0x0607_0013, "Data type does not match, length of service parameter too low";
    NO_SUBINDEX = 0x0609_0011, "Subindex does not exist";
    VALUE_RANGE = 0x0609_0030, "Value range of parameter exceeded (only for write access)";
    VALUE_TOO_HIGH = 0x0609_0031, "Value of parameter written too high";
    VALUE_TOO_LOW = 0x0609_0032, "Value of parameter written too low";
    MAX_LESS_THAN_MIN = 0x0609_0036, "Maximum value is less than minimum value";
    RESOURCE_UNAVAILABLE = 0x060A_0023, "Resource not available: SDO connection";
    GENERAL = 0x0800_0000, "General error";
    CANNOT_STORE = 0x0800_0020, "Data cannot be transferred or stored to the application";
    LOCAL_CONTROL = 0x0800_0021, "Data cannot be transferred or stored to the application because of local control";
    DEVICE_STATE = 0x0800_0022, "Data cannot be transferred or stored to the application because of the present device state";
    NO_DICTIONARY = 0x0800_0023, "Object dictionary dynamic generation fails or no object dictionary is present";
    NO_DATA = 0x0800_0024, "No data available";
}

impl fmt::Display for SdoAbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.text() {
            Some(t) => write!(f, "0x{:08X} ({t})", self.0),
            None => write!(f, "0x{:08X} (unknown abort code)", self.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_sorted_unique_and_named() {
        for w in SdoAbortCode::ALL.windows(2) {
            assert!(w[0] < w[1], "{} before {}", w[0], w[1]);
        }
        assert_eq!(
            SdoAbortCode(0x0601_0006).to_string(),
            "0x06010006 (Object mapped to RxPDO, SDO download blocked)"
        );
        assert_eq!(
            SdoAbortCode(0x1234_5678).to_string(),
            "0x12345678 (unknown abort code)"
        );
    }
}
