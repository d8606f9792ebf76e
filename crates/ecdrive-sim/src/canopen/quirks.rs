//! What an emulated CANopen node does beyond its dictionary: the emulator's own data, not part
//! of the master's profiles. Each drive's table (`super::drives`) sets its own, naming the
//! manual section each value comes from; a node from an EDS file has none
//! ([`EmulationQuirks::NONE`]).

use crate::od::ObjectAddress;

/// A parameter whose value makes "enable operation" (controlword bit 3) alone switch the drive
/// on (ASDA-A2 P3-12 X = 0, §2.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Bit3Enable {
    /// The parameter object.
    pub addr: ObjectAddress,
    /// The digit's bits.
    pub mask: u32,
    /// The value of those bits that selects "bit 3 alone".
    pub value: u32,
}

/// What the emulated node needs to behave like the drive, beyond the dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmulationQuirks {
    /// "Enable operation" alone switches on, selected by a parameter (ASDA-A2 P3-12 X = 0).
    pub bit3_enable: Option<Bit3Enable>,
    /// Leaving NMT Operational while enabled disables the power stage (BLV-R §5.1 ties
    /// excitation to Operational).
    pub operational_required: bool,
    /// Alarm (vendor number) raised for an SDO request within the spec's
    /// `sdo_min_interval_us` of the previous one (ASDA-A2 AL111).
    pub sdo_overrun_alarm: Option<u16>,
    /// Alarm raised for two frames on one RPDO COB-ID within the spec's
    /// `rpdo_min_interval_us` (ASDA-A2 AL112).
    pub rpdo_overrun_alarm: Option<u16>,
    /// Alarm raised for an RPDO shorter than its mapping (BLV-R, Lexium: EMCY 8210h; ASDA-A2
    /// AL123).
    pub pdo_length_alarm: Option<u16>,
    /// Alarm raised when life guarding or the heartbeat consumer times out (ASDA-A2 AL170; the
    /// others report EMCY 8130h).
    pub guarding_alarm: Option<u16>,
    /// In ip, controlword bit 4 enables interpolation (CiA); `false`: interpolation runs
    /// whenever mode 7 is active (ASDA-A2 §5.2).
    pub ip_needs_enable_bit: bool,
    /// Statusword bit 12 in pv is the zero-speed flag (all three drives).
    pub pv_zero_speed_bit: bool,
    /// The touch probe may trigger on the encoder's zero point (60B8h bit 2/10: the BLV-R's
    /// ZSG-N output, §7.6.1); the probe inputs themselves are the machine's
    /// ([`crate::machine::World`]) for every node whose dictionary has 60B8h.
    pub touch_probe_index_pulse: bool,
    /// A value past an entry's range is refused with CiA 301's refinements 0609 0031h (too
    /// high) / 0609 0032h (too low); `false`: with 0609 0030h only, the one range code the
    /// drive's manual lists (ASDA-A2 §5.3, Lexium MDrive §7.4).
    pub range_abort_high_low: bool,
    /// A value of the wrong length is refused with CiA 301's refinements 0607 0012h (too long)
    /// / 0607 0013h (too short); `false`: with 0607 0010h only (ASDA-A2 §5.3).
    pub length_abort_high_low: bool,
}

impl EmulationQuirks {
    /// A drive that does nothing beyond CiA 301/402.
    pub const NONE: Self = Self {
        bit3_enable: None,
        operational_required: false,
        sdo_overrun_alarm: None,
        rpdo_overrun_alarm: None,
        pdo_length_alarm: None,
        guarding_alarm: None,
        ip_needs_enable_bit: true,
        pv_zero_speed_bit: true,
        touch_probe_index_pulse: false,
        range_abort_high_low: true,
        length_abort_high_low: true,
    };
}
