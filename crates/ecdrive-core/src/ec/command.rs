//! EtherCAT datagram commands (ETG.1000.4 table "EtherCAT command types").

use core::fmt;

/// A datagram command code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Command {
    /// No operation.
    Nop = 0,
    /// Auto-increment physical read.
    Aprd = 1,
    /// Auto-increment physical write.
    Apwr = 2,
    /// Auto-increment physical read-write.
    Aprw = 3,
    /// Configured-address physical read.
    Fprd = 4,
    /// Configured-address physical write.
    Fpwr = 5,
    /// Configured-address physical read-write.
    Fprw = 6,
    /// Broadcast read.
    Brd = 7,
    /// Broadcast write.
    Bwr = 8,
    /// Broadcast read-write.
    Brw = 9,
    /// Logical memory read.
    Lrd = 10,
    /// Logical memory write.
    Lwr = 11,
    /// Logical memory read-write.
    Lrw = 12,
    /// Auto-increment physical read, multiple write.
    Armw = 13,
    /// Configured-address physical read, multiple write.
    Frmw = 14,
}

impl Command {
    /// Decode a command byte; `None` for reserved codes (15–255).
    pub const fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            0 => Self::Nop,
            1 => Self::Aprd,
            2 => Self::Apwr,
            3 => Self::Aprw,
            4 => Self::Fprd,
            5 => Self::Fpwr,
            6 => Self::Fprw,
            7 => Self::Brd,
            8 => Self::Bwr,
            9 => Self::Brw,
            10 => Self::Lrd,
            11 => Self::Lwr,
            12 => Self::Lrw,
            13 => Self::Armw,
            14 => Self::Frmw,
            _ => return None,
        })
    }

    /// The mnemonic, e.g. `"FPRD"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Nop => "NOP",
            Self::Aprd => "APRD",
            Self::Apwr => "APWR",
            Self::Aprw => "APRW",
            Self::Fprd => "FPRD",
            Self::Fpwr => "FPWR",
            Self::Fprw => "FPRW",
            Self::Brd => "BRD",
            Self::Bwr => "BWR",
            Self::Brw => "BRW",
            Self::Lrd => "LRD",
            Self::Lwr => "LWR",
            Self::Lrw => "LRW",
            Self::Armw => "ARMW",
            Self::Frmw => "FRMW",
        }
    }

    /// Whether the address field is a 32-bit logical address (LRD/LWR/LRW).
    pub const fn is_logical(self) -> bool {
        matches!(self, Self::Lrd | Self::Lwr | Self::Lrw)
    }

    /// Whether the position field is auto-incremented by every slave (AP*, ARMW and B*).
    pub const fn increments_adp(self) -> bool {
        matches!(
            self,
            Self::Aprd | Self::Apwr | Self::Aprw | Self::Armw | Self::Brd | Self::Bwr | Self::Brw
        )
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
