//! What an emulated CANopen node does beyond its dictionary: the emulator's own data, per drive
//! (found by its vendor ID, 1018h:01), not part of the master's profiles. Each value names the
//! manual section it comes from.

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
    /// Alarm (vendor number) raised for an SDO request within the profile's
    /// `sdo_min_interval_us` of the previous one (ASDA-A2 AL111).
    pub sdo_overrun_alarm: Option<u16>,
    /// Alarm raised for two frames on one RPDO COB-ID within the profile's
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
    };
}

/// Oriental Motor BLV-R (vendor 0x000002BE).
const BLV_R: EmulationQuirks = EmulationQuirks {
    // §5.1: the motor is excited only in NMT Operational.
    operational_required: true,
    // An RPDO shorter than its mapping: EMCY 8210h.
    pdo_length_alarm: Some(0x8210),
    // MANUAL GAP: whether guarding/heartbeat loss stops the motor; the node only sends EMCY
    // 8130h.
    // §7.6.1: probe triggers are USR-LAT-IN0/IN1 or the ZSG-N output (once per revolution).
    touch_probe_index_pulse: true,
    ..EmulationQuirks::NONE
};

/// Delta ASDA-A2 (vendor 0x000001DD).
const ASDA_A2: EmulationQuirks = EmulationQuirks {
    // P3-12 (0x230C) digit X = 0: "enable operation" alone switches on (§2.2.2).
    bit3_enable: Some(Bit3Enable {
        addr: ObjectAddress::new(0x230C, 0),
        mask: 0x000F,
        value: 0,
    }),
    // AL111: SDO requests too close together; AL112: RPDO frames too close together; AL123:
    // RPDO length error; AL170: guarding/heartbeat lost while servo on (alarm list, ch. 10).
    sdo_overrun_alarm: Some(0x0111),
    rpdo_overrun_alarm: Some(0x0112),
    pdo_length_alarm: Some(0x0123),
    guarding_alarm: Some(0x0170),
    // §5.2: interpolation runs whenever mode 7 is active.
    ip_needs_enable_bit: false,
    ..EmulationQuirks::NONE
};

/// Schneider Electric Lexium MDrive (vendor 0x0000021B).
const LEXIUM_MDRIVE: EmulationQuirks = EmulationQuirks {
    // An RPDO shorter than its mapping: EMCY 8210h; guarding/heartbeat lost: EMCY 8130h.
    pdo_length_alarm: Some(0x8210),
    guarding_alarm: Some(0x8130),
    ..EmulationQuirks::NONE
};

/// The emulator's quirks for the drive with this vendor ID, by vendor.
const BY_VENDOR: &[(u32, EmulationQuirks)] = &[
    (0x0000_02BE, BLV_R),
    (0x0000_01DD, ASDA_A2),
    (0x0000_021B, LEXIUM_MDRIVE),
];

/// The quirks of the drive with vendor ID `vendor_id` ([`EmulationQuirks::NONE`] for one the
/// emulator has none for).
pub fn for_vendor(vendor_id: u32) -> EmulationQuirks {
    BY_VENDOR
        .iter()
        .find(|(v, _)| *v == vendor_id)
        .map_or(EmulationQuirks::NONE, |(_, q)| *q)
}
