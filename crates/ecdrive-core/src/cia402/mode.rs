//! Modes of operation (0x6060 / 0x6061) and supported drive modes (0x6502).

use core::fmt;
use core::hash::{Hash, Hasher};

/// A mode of operation, the INTEGER8 value of 0x6060 (request) and 0x6061 (display).
///
/// | value | mode | 0x6502 bit |
/// |---|---|---|
/// | 0 | no mode / no change | – |
/// | 1 | profile position (pp) | 0 |
/// | 2 | velocity (vl) | 1 |
/// | 3 | profile velocity (pv) | 2 |
/// | 4 | profile torque (tq) | 3 |
/// | 5 | reserved | 4 |
/// | 6 | homing (hm) | 5 |
/// | 7 | interpolated position (ip) | 6 |
/// | 8 | cyclic synchronous position (csp) | 7 |
/// | 9 | cyclic synchronous velocity (csv) | 8 |
/// | 10 | cyclic synchronous torque (cst) | 9 |
/// | 11 | cst with commutation angle (cstca) | 10 |
/// | 12…127 | reserved | – |
/// | −128…−1 | manufacturer-specific (e.g. MR-J4-TM jg −100, pt −101, idx −103) | 16–31, per drive |
///
/// Every `i8` converts losslessly: [`OperationMode::from_i8`] puts 5 and 12…127 into
/// [`OperationMode::Reserved`] and negative values into [`OperationMode::Vendor`], and
/// [`OperationMode::as_i8`] gives the value back. Equality and hashing compare the `i8` value, so
/// a hand-built `Vendor(5)` equals `Reserved(5)`.
///
/// The discriminant of each CiA 402 mode is its value, so [`OperationMode::as_i8`] and the
/// comparisons built on it compile to a test and a copy, without a table: the cycle runs them
/// cold from memory after each sleep.
#[derive(Debug, Clone, Copy, serde::Serialize)]
#[repr(u8)]
pub enum OperationMode {
    /// 0: no mode assigned / no mode change.
    NoMode = 0,
    /// 1: profile position (pp).
    ProfilePosition = 1,
    /// 2: velocity (vl, frequency-converter style).
    Velocity = 2,
    /// 3: profile velocity (pv).
    ProfileVelocity = 3,
    /// 4: profile torque (tq).
    ProfileTorque = 4,
    /// 6: homing (hm).
    Homing = 6,
    /// 7: interpolated position (ip).
    InterpolatedPosition = 7,
    /// 8: cyclic synchronous position (csp).
    CyclicSyncPosition = 8,
    /// 9: cyclic synchronous velocity (csv).
    CyclicSyncVelocity = 9,
    /// 10: cyclic synchronous torque (cst).
    CyclicSyncTorque = 10,
    /// 11: cyclic synchronous torque with commutation angle (cstca).
    CyclicSyncTorqueCommutation = 11,
    /// 5 or 12…127: reserved by CiA 402; kept as received.
    Reserved(i8) = 12,
    /// −128…−1: manufacturer-specific; kept as received.
    Vendor(i8) = 13,
}

impl OperationMode {
    /// The CiA 402 modes 1–4 and 6–11, in value order.
    pub const STANDARD: [OperationMode; 10] = [
        OperationMode::ProfilePosition,
        OperationMode::Velocity,
        OperationMode::ProfileVelocity,
        OperationMode::ProfileTorque,
        OperationMode::Homing,
        OperationMode::InterpolatedPosition,
        OperationMode::CyclicSyncPosition,
        OperationMode::CyclicSyncVelocity,
        OperationMode::CyclicSyncTorque,
        OperationMode::CyclicSyncTorqueCommutation,
    ];

    /// The mode for an 0x6060/0x6061 value.
    pub const fn from_i8(v: i8) -> Self {
        match v {
            0 => OperationMode::NoMode,
            1 => OperationMode::ProfilePosition,
            2 => OperationMode::Velocity,
            3 => OperationMode::ProfileVelocity,
            4 => OperationMode::ProfileTorque,
            6 => OperationMode::Homing,
            7 => OperationMode::InterpolatedPosition,
            8 => OperationMode::CyclicSyncPosition,
            9 => OperationMode::CyclicSyncVelocity,
            10 => OperationMode::CyclicSyncTorque,
            11 => OperationMode::CyclicSyncTorqueCommutation,
            v if v < 0 => OperationMode::Vendor(v),
            v => OperationMode::Reserved(v),
        }
    }

    /// The 0x6060/0x6061 value.
    pub const fn as_i8(self) -> i8 {
        match self {
            OperationMode::NoMode => 0,
            OperationMode::ProfilePosition => 1,
            OperationMode::Velocity => 2,
            OperationMode::ProfileVelocity => 3,
            OperationMode::ProfileTorque => 4,
            OperationMode::Homing => 6,
            OperationMode::InterpolatedPosition => 7,
            OperationMode::CyclicSyncPosition => 8,
            OperationMode::CyclicSyncVelocity => 9,
            OperationMode::CyclicSyncTorque => 10,
            OperationMode::CyclicSyncTorqueCommutation => 11,
            OperationMode::Reserved(v) | OperationMode::Vendor(v) => v,
        }
    }

    /// The bit of 0x6502 that CiA 402 assigns to this mode (modes 1–4 and 6–11), or `None` for
    /// no-mode, reserved and vendor modes (vendor bits are per drive, see [`VendorModeBit`]).
    pub const fn standard_bit(self) -> Option<u8> {
        match self.as_i8() {
            v @ 1..=4 | v @ 6..=11 => Some((v - 1) as u8),
            _ => None,
        }
    }

    /// The short name CiA 402 uses ("csp", "pp", …); `"vendor"`, `"reserved"`, `"none"` otherwise.
    pub const fn short_name(self) -> &'static str {
        match self {
            OperationMode::NoMode => "none",
            OperationMode::ProfilePosition => "pp",
            OperationMode::Velocity => "vl",
            OperationMode::ProfileVelocity => "pv",
            OperationMode::ProfileTorque => "tq",
            OperationMode::Homing => "hm",
            OperationMode::InterpolatedPosition => "ip",
            OperationMode::CyclicSyncPosition => "csp",
            OperationMode::CyclicSyncVelocity => "csv",
            OperationMode::CyclicSyncTorque => "cst",
            OperationMode::CyclicSyncTorqueCommutation => "cstca",
            OperationMode::Reserved(_) => "reserved",
            OperationMode::Vendor(_) => "vendor",
        }
    }

    /// A position mode in the sense of the MR-J4-TM zero-speed rule (§5.4.2): pp, hm, ip, csp.
    /// Vendor modes are not classified here (a drive profile that needs it must say so).
    pub const fn is_position_mode(self) -> bool {
        matches!(
            self,
            OperationMode::ProfilePosition
                | OperationMode::Homing
                | OperationMode::InterpolatedPosition
                | OperationMode::CyclicSyncPosition
        )
    }

    /// csp, csv, cst or cstca: the master sends a set-point every cycle.
    pub const fn is_cyclic(self) -> bool {
        matches!(
            self,
            OperationMode::CyclicSyncPosition
                | OperationMode::CyclicSyncVelocity
                | OperationMode::CyclicSyncTorque
                | OperationMode::CyclicSyncTorqueCommutation
        )
    }

    /// The set-point a mode takes from the master: position (pp, ip, csp → 0x607A), velocity
    /// (vl, pv, csv → 0x60FF) or torque (tq, cst, cstca → 0x6071). `None` for hm, no-mode,
    /// reserved and vendor modes.
    pub const fn set_point_kind(self) -> Option<SetPointKind> {
        match self {
            OperationMode::ProfilePosition
            | OperationMode::InterpolatedPosition
            | OperationMode::CyclicSyncPosition => Some(SetPointKind::Position),
            OperationMode::Velocity
            | OperationMode::ProfileVelocity
            | OperationMode::CyclicSyncVelocity => Some(SetPointKind::Velocity),
            OperationMode::ProfileTorque
            | OperationMode::CyclicSyncTorque
            | OperationMode::CyclicSyncTorqueCommutation => Some(SetPointKind::Torque),
            _ => None,
        }
    }
}

impl PartialEq for OperationMode {
    fn eq(&self, other: &Self) -> bool {
        self.as_i8() == other.as_i8()
    }
}

impl Eq for OperationMode {}

impl Hash for OperationMode {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.as_i8().hash(state);
    }
}

impl From<i8> for OperationMode {
    fn from(v: i8) -> Self {
        Self::from_i8(v)
    }
}

impl From<OperationMode> for i8 {
    fn from(m: OperationMode) -> Self {
        m.as_i8()
    }
}

impl fmt::Display for OperationMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.short_name(), self.as_i8())
    }
}

/// Which target object a mode takes its set-point from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SetPointKind {
    /// Target position 0x607A (INTEGER32).
    Position,
    /// Target velocity 0x60FF (INTEGER32).
    Velocity,
    /// Target torque 0x6071 (INTEGER16).
    Torque,
}

impl fmt::Display for SetPointKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SetPointKind::Position => "position (0x607A)",
            SetPointKind::Velocity => "velocity (0x60FF)",
            SetPointKind::Torque => "torque (0x6071)",
        })
    }
}

/// One manufacturer-specific bit of 0x6502 and the (negative) mode value it stands for. CiA 402
/// reserves bits 16–31 for the manufacturer without fixing which mode each means, so a drive
/// profile supplies the mapping (MR-J4-TM: bit 16 → −100 jg, bit 17 → −101 pt, bit 19 → −103
/// idx).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct VendorModeBit {
    /// Bit number in 0x6502, 16–31.
    pub bit: u8,
    /// The 0x6060 value of the mode.
    pub mode: i8,
}

/// Supported drive modes, object 0x6502 (UNSIGNED32), plus the drive's mapping of vendor bits
/// 16–31 to vendor mode values. Const-constructible so drive profiles can hold it as static data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SupportedModes {
    raw: u32,
    vendor_bits: &'static [VendorModeBit],
}

impl SupportedModes {
    /// Every standard CiA 402 mode (bits 0–3, 5–10), no vendor modes.
    pub const ALL_STANDARD: SupportedModes = SupportedModes::from_raw(0x0000_07EF);

    /// From the raw 0x6502 value, with no vendor-bit mapping.
    pub const fn from_raw(raw: u32) -> Self {
        Self {
            raw,
            vendor_bits: &[],
        }
    }

    /// The same value with a vendor-bit mapping.
    pub const fn with_vendor_bits(self, vendor_bits: &'static [VendorModeBit]) -> Self {
        Self {
            raw: self.raw,
            vendor_bits,
        }
    }

    /// The raw 0x6502 value.
    pub const fn raw(self) -> u32 {
        self.raw
    }

    /// The vendor-bit mapping.
    pub const fn vendor_bits(self) -> &'static [VendorModeBit] {
        self.vendor_bits
    }

    /// Whether the drive supports `mode`: the CiA bit for standard modes, the mapped bit for
    /// vendor modes. No-mode and reserved values are never supported.
    pub fn contains(self, mode: OperationMode) -> bool {
        if let Some(bit) = mode.standard_bit() {
            return self.bit_set(bit);
        }
        match mode {
            OperationMode::Vendor(v) => self
                .vendor_bits
                .iter()
                .any(|vb| vb.mode == v && self.bit_set(vb.bit)),
            _ => false,
        }
    }

    /// Only the modes of `allowed` (0x6060 values): what a drive offers while a setting of its
    /// own restricts the usable modes (the MR-J4-TM's [Pr. PA01]).
    pub fn restricted_to(self, allowed: &[i8]) -> Self {
        let mut raw = 0u32;
        for m in self.iter() {
            if !allowed.contains(&m.as_i8()) {
                continue;
            }
            let bit = m.standard_bit().or_else(|| match m {
                OperationMode::Vendor(v) => self
                    .vendor_bits
                    .iter()
                    .find(|vb| vb.mode == v)
                    .map(|vb| vb.bit),
                _ => None,
            });
            if let Some(b) = bit {
                raw |= 1u32.checked_shl(u32::from(b)).unwrap_or(0);
            }
        }
        Self {
            raw,
            vendor_bits: self.vendor_bits,
        }
    }

    /// Set bits in 16–31 that the vendor mapping does not explain.
    pub fn unmapped_vendor_bits(self) -> u32 {
        let mut mapped = 0u32;
        for vb in self.vendor_bits {
            mapped |= 1u32.checked_shl(u32::from(vb.bit)).unwrap_or(0);
        }
        self.raw & 0xFFFF_0000 & !mapped
    }

    /// The supported modes: standard ones in value order, then the mapped vendor modes.
    pub fn iter(self) -> impl Iterator<Item = OperationMode> {
        let standard = OperationMode::STANDARD
            .into_iter()
            .filter(move |m| self.contains(*m));
        let vendor = self
            .vendor_bits
            .iter()
            .filter(move |vb| self.bit_set(vb.bit))
            .map(|vb| OperationMode::from_i8(vb.mode));
        standard.chain(vendor)
    }

    fn bit_set(self, bit: u8) -> bool {
        1u32.checked_shl(u32::from(bit))
            .is_some_and(|m| self.raw & m != 0)
    }
}

/// The modes one setting of a mode-selecting parameter allows (the MR-J4-TM's [Pr. PA01],
/// read at power-on: cyclic modes or profile modes, never both). One type for the masters'
/// drive profiles and the software slave's own tables; each side states its values itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeGroup {
    /// The selector value (after the parameter's mask).
    pub value: i64,
    /// How the manual names the setting ("___2: Profile mode").
    pub name: &'static str,
    /// The 0x6060 values it allows.
    pub modes: &'static [i8],
}
