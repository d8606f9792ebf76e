//! Error codes of object 0x603F (and of EMCY messages / 0x1003): classification by the CiA 301 /
//! CiA 402 ranges, the standard code names, and a hook for per-drive tables.
//!
//! Look-up order in [`ErrorCode::describe`]: the drive's table first (so a profile can name its
//! own codes, including ones inside the standard ranges such as the BDHDE's `0x8689`), then the
//! standard codes below, then the standard group (`0xNN00`), then the class (first hex digit).
//!
//! The standard names come from the CiA 301 / CiA 402 (IEC 61800-7-201) error-code tables. The
//! drive manuals confirm many of them (the ASDA-A2 and BDHDE tables use 0x2310, 0x3110, 0x3120,
//! 0x3130, 0x3210, 0x4210, 0x4310, 0x7121, 0x7122, 0x7305, 0x7306, 0x7510, 0x7520, 0x8611 with the
//! same meaning); the others are from the standard and not restated in those manuals.

use core::fmt;

/// A 16-bit error code as found in 0x603F, the low word of 0x1003 sub-entries, and EMCY bytes 0–1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, serde::Serialize)]
pub struct ErrorCode(pub u16);

/// The class of an error code: its range in the CiA 301 / CiA 402 table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ErrorClass {
    /// `0x0000`: no error (or "error reset" in an EMCY).
    NoError,
    /// `0x1000`–`0x1FFF`: generic error.
    Generic,
    /// `0x2000`–`0x2FFF`: current.
    Current,
    /// `0x3000`–`0x3FFF`: voltage.
    Voltage,
    /// `0x4000`–`0x4FFF`: temperature.
    Temperature,
    /// `0x5000`–`0x5FFF`: device hardware.
    DeviceHardware,
    /// `0x6000`–`0x6FFF`: device software.
    DeviceSoftware,
    /// `0x7000`–`0x7FFF`: additional modules (motor, sensors, communication modules, …).
    AdditionalModules,
    /// `0x8000`–`0x8FFF`: monitoring (communication, protocol, torque/speed/position control).
    Monitoring,
    /// `0x9000`–`0x9FFF`: external error.
    External,
    /// `0xF000`–`0xF0FF`: additional functions.
    AdditionalFunctions,
    /// `0xFF00`–`0xFFFF`: device-specific (vendor alarm numbers live here on the MR-J4-TM and
    /// BLV-R: `0xFF00` + alarm number).
    DeviceSpecific,
    /// Any other value (`0x0001`–`0x0FFF`, `0xA000`–`0xEFFF`, `0xF100`–`0xFEFF`): reserved.
    Reserved,
}

impl ErrorClass {
    /// The class name.
    pub const fn name(self) -> &'static str {
        match self {
            ErrorClass::NoError => "no error",
            ErrorClass::Generic => "generic error",
            ErrorClass::Current => "current",
            ErrorClass::Voltage => "voltage",
            ErrorClass::Temperature => "temperature",
            ErrorClass::DeviceHardware => "device hardware",
            ErrorClass::DeviceSoftware => "device software",
            ErrorClass::AdditionalModules => "additional modules",
            ErrorClass::Monitoring => "monitoring",
            ErrorClass::External => "external error",
            ErrorClass::AdditionalFunctions => "additional functions",
            ErrorClass::DeviceSpecific => "device-specific",
            ErrorClass::Reserved => "reserved",
        }
    }
}

impl fmt::Display for ErrorClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One row of a per-drive error table: a code matches when `code & mask == entry.code`.
///
/// Exact codes use `mask: 0xFFFF`; a catch-all such as "any MR-J4-TM alarm" uses
/// `code: 0xFF00, mask: 0xFF00`. The first matching row wins, so put exact rows first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ErrorEntry {
    /// The code (already masked).
    pub code: u16,
    /// Which bits of a received code must equal `code`.
    pub mask: u16,
    /// Short name, e.g. `"AL.20"` or `"FLT 17"`.
    pub name: &'static str,
    /// What it means, e.g. `"Encoder normal communication error"`.
    pub text: &'static str,
}

impl ErrorEntry {
    /// An entry matching exactly `code`.
    pub const fn exact(code: u16, name: &'static str, text: &'static str) -> Self {
        Self {
            code,
            mask: 0xFFFF,
            name,
            text,
        }
    }

    /// Whether `code` matches this entry.
    pub const fn matches(&self, code: u16) -> bool {
        code & self.mask == self.code & self.mask
    }
}

/// Where a description came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ErrorSource {
    /// The drive's own table.
    Drive,
    /// The exact code is in the CiA 301 / CiA 402 table.
    Standard,
    /// Only the group (`0xNN00`) is in the standard table.
    StandardGroup,
    /// Only the class is known.
    Class,
}

/// A decoded error code. Holds only `'static` text, so it is `Copy` and costs no allocation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub struct ErrorDescription {
    /// The code.
    pub code: ErrorCode,
    /// Its CiA class.
    pub class: ErrorClass,
    /// Short name from the drive table (`"AL.20"`), empty otherwise.
    pub name: &'static str,
    /// What it means.
    pub text: &'static str,
    /// Which table supplied `name`/`text`.
    pub source: ErrorSource,
}

impl fmt::Display for ErrorDescription {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "error code 0x{:04X}", self.code.0)?;
        if !self.name.is_empty() {
            write!(f, " {}", self.name)?;
        }
        write!(f, ": {} ({})", self.text, self.class)
    }
}

impl ErrorCode {
    /// No error.
    pub const NONE: ErrorCode = ErrorCode(0);
    /// CiA 402 following error.
    pub const FOLLOWING_ERROR: ErrorCode = ErrorCode(0x8611);
    /// CiA 402 reference limit.
    pub const REFERENCE_LIMIT: ErrorCode = ErrorCode(0x8612);

    /// The class by range.
    pub const fn class(self) -> ErrorClass {
        match self.0 {
            0x0000 => ErrorClass::NoError,
            0x1000..=0x1FFF => ErrorClass::Generic,
            0x2000..=0x2FFF => ErrorClass::Current,
            0x3000..=0x3FFF => ErrorClass::Voltage,
            0x4000..=0x4FFF => ErrorClass::Temperature,
            0x5000..=0x5FFF => ErrorClass::DeviceHardware,
            0x6000..=0x6FFF => ErrorClass::DeviceSoftware,
            0x7000..=0x7FFF => ErrorClass::AdditionalModules,
            0x8000..=0x8FFF => ErrorClass::Monitoring,
            0x9000..=0x9FFF => ErrorClass::External,
            0xF000..=0xF0FF => ErrorClass::AdditionalFunctions,
            0xFF00..=0xFFFF => ErrorClass::DeviceSpecific,
            _ => ErrorClass::Reserved,
        }
    }

    /// `0x0000`.
    pub const fn is_none(self) -> bool {
        self.0 == 0
    }

    /// The low byte of a device-specific code (`0xFFxx` → `xx`): the alarm number on drives
    /// that report `0xFF00 + alarm` (MR-J4-TM from software B2, BLV-R).
    pub const fn device_specific_low_byte(self) -> Option<u8> {
        if self.0 & 0xFF00 == 0xFF00 {
            Some((self.0 & 0x00FF) as u8)
        } else {
            None
        }
    }

    /// The name of the exact code in the CiA 301 / CiA 402 table, if it is there.
    pub fn standard_name(self) -> Option<&'static str> {
        STANDARD_CODES
            .iter()
            .find(|(c, _)| *c == self.0)
            .map(|(_, t)| *t)
    }

    /// Describe the code: `drive_table` first, then the standard code, group and class.
    pub fn describe(self, drive_table: &[ErrorEntry]) -> ErrorDescription {
        let class = self.class();
        if let Some(e) = drive_table.iter().find(|e| e.matches(self.0)) {
            return ErrorDescription {
                code: self,
                class,
                name: e.name,
                text: e.text,
                source: ErrorSource::Drive,
            };
        }
        if let Some(text) = self.standard_name() {
            return ErrorDescription {
                code: self,
                class,
                name: "",
                text,
                source: ErrorSource::Standard,
            };
        }
        let group = self.0 & 0xFF00;
        if class != ErrorClass::Reserved
            && let Some((_, text)) = STANDARD_CODES.iter().find(|(c, _)| *c == group)
        {
            return ErrorDescription {
                code: self,
                class,
                name: "",
                text,
                source: ErrorSource::StandardGroup,
            };
        }
        ErrorDescription {
            code: self,
            class,
            name: "",
            text: class.name(),
            source: ErrorSource::Class,
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "0x{:04X}", self.0)
    }
}

impl From<u16> for ErrorCode {
    fn from(v: u16) -> Self {
        ErrorCode(v)
    }
}

/// The standard codes (CiA 301 communication codes and the CiA 402 drive codes), sorted.
/// Groups end in `00`.
pub const STANDARD_CODES: &[(u16, &str)] = &[
    (0x0000, "no error"),
    (0x1000, "generic error"),
    (0x2000, "current"),
    (0x2100, "current, device input side"),
    (0x2110, "short circuit / earth leakage (input)"),
    (0x2120, "earth leakage (input)"),
    (0x2130, "short circuit (input)"),
    (0x2200, "current inside the device"),
    (0x2211, "internal current no. 1"),
    (0x2212, "internal current no. 2"),
    (0x2213, "over-current in ramp function"),
    (0x2214, "over-current in the sequence"),
    (0x2220, "continuous current (device internal)"),
    (0x2230, "short circuit / earth leakage (device internal)"),
    (0x2240, "earth leakage (device internal)"),
    (0x2250, "short circuit (device internal)"),
    (0x2300, "current on device output side"),
    (0x2310, "continuous over-current"),
    (0x2311, "continuous over-current no. 1"),
    (0x2312, "continuous over-current no. 2"),
    (0x2320, "short circuit / earth leakage (motor side)"),
    (0x2330, "earth leakage (motor side)"),
    (0x2340, "short circuit (motor side)"),
    (0x3000, "voltage"),
    (0x3100, "mains voltage"),
    (0x3110, "mains over-voltage"),
    (0x3120, "mains under-voltage"),
    (0x3130, "phase failure"),
    (0x3140, "mains frequency"),
    (0x3200, "DC link voltage"),
    (0x3210, "DC link over-voltage"),
    (0x3220, "DC link under-voltage"),
    (0x3230, "load error"),
    (0x3300, "output voltage"),
    (0x3310, "output over-voltage"),
    (0x3320, "armature circuit"),
    (0x3330, "field circuit"),
    (0x4000, "temperature"),
    (0x4100, "ambient temperature"),
    (0x4200, "device temperature"),
    (0x4210, "excess temperature device"),
    (0x4300, "drive temperature"),
    (0x4310, "excess temperature drive"),
    (0x4400, "supply temperature"),
    (0x5000, "device hardware"),
    (0x5100, "supply"),
    (0x5110, "supply low voltage"),
    (0x5200, "control"),
    (0x5210, "measurement circuit"),
    (0x5220, "computing circuit"),
    (0x5300, "operating unit"),
    (0x5400, "power section"),
    (0x5410, "output stages"),
    (0x5420, "chopper"),
    (0x5430, "input stages"),
    (0x5440, "contacts"),
    (0x5450, "fuses"),
    (0x5500, "data storage"),
    (0x5510, "working memory"),
    (0x5520, "program memory"),
    (0x5530, "non-volatile data memory"),
    (0x6000, "device software"),
    (0x6010, "software reset (watchdog)"),
    (0x6100, "internal software"),
    (0x6200, "user software"),
    (0x6300, "data record"),
    (0x6310, "loss of parameters"),
    (0x6320, "parameter error"),
    (0x7000, "additional modules"),
    (0x7100, "power"),
    (0x7110, "brake chopper"),
    (0x7120, "motor"),
    (0x7121, "motor blocked"),
    (0x7122, "motor error or commutation malfunction"),
    (0x7123, "motor tilted"),
    (0x7200, "measurement circuit"),
    (0x7300, "sensor"),
    (0x7301, "tacho fault"),
    (0x7302, "tacho wrong polarity"),
    (0x7303, "resolver 1 fault"),
    (0x7304, "resolver 2 fault"),
    (0x7305, "incremental sensor 1 fault"),
    (0x7306, "incremental sensor 2 fault"),
    (0x7307, "incremental sensor 3 fault"),
    (0x7310, "speed"),
    (0x7320, "position"),
    (0x7400, "computation circuit"),
    (0x7500, "communication"),
    (0x7510, "serial interface no. 1"),
    (0x7520, "serial interface no. 2"),
    (0x7600, "data storage"),
    (0x8000, "monitoring"),
    (0x8100, "communication"),
    (0x8110, "CAN overrun (objects lost)"),
    (0x8120, "CAN in error passive mode"),
    (0x8130, "life guard or heartbeat error"),
    (0x8140, "recovered from bus off"),
    (0x8150, "CAN-ID collision"),
    (0x8200, "protocol error"),
    (0x8210, "PDO not processed due to length error"),
    (0x8220, "PDO length exceeded"),
    (0x8300, "torque control"),
    (0x8311, "excess torque"),
    (0x8312, "difficult start up"),
    (0x8313, "standstill torque"),
    (0x8321, "insufficient torque"),
    (0x8331, "torque fault"),
    (0x8400, "velocity speed controller"),
    (0x8500, "position controller"),
    (0x8600, "positioning controller"),
    (0x8611, "following error"),
    (0x8612, "reference limit"),
    (0x8700, "sync controller"),
    (0x8800, "winding controller"),
    (0x9000, "external error"),
    (0xF000, "additional functions"),
    (0xF001, "deceleration"),
    (0xF002, "sub-synchronous run"),
    (0xF003, "stroke operation"),
    (0xF004, "control"),
    (0xFF00, "device-specific"),
];
