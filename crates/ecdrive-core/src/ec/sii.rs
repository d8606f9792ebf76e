//! The SII EEPROM layout (ETG.1000.6 §5.4, ETG.2010): word addresses of the fixed header and
//! the category types that follow it. Shared by the software slave (which builds images) and the
//! master's tools (which decode them).

/// The SII checksum: CRC-8, polynomial 0x07, initial value 0xFF, no reflection, stored in the
/// low byte of word 7 over bytes 0..14 (words 0–6). One definition for the slave that writes
/// it and the master's tools that check it.
pub const SII_CRC: crc::Crc<u8> = crc::Crc::<u8>::new(&crc::Algorithm {
    width: 8,
    poly: 0x07,
    init: 0xFF,
    refin: false,
    refout: false,
    xorout: 0x00,
    check: 0xFB,
    residue: 0x00,
});

/// The checksum of an SII image's header (its first 14 bytes), or `None` if it is shorter.
pub fn header_checksum(image: &[u8]) -> Option<u8> {
    image.get(..14).map(|h| SII_CRC.checksum(h))
}

/// Word address of the first category.
pub const FIRST_CATEGORY_WORD: u16 = 0x0040;

/// SII category types (ETG.2010 table 6).
pub mod category {
    /// Strings.
    pub const STRINGS: u16 = 10;
    /// Data types.
    pub const DATA_TYPES: u16 = 20;
    /// General.
    pub const GENERAL: u16 = 30;
    /// FMMU usage.
    pub const FMMU: u16 = 40;
    /// SyncManagers.
    pub const SYNC_MANAGER: u16 = 41;
    /// FMMU extension (FMMU → SM assignment).
    pub const FMMU_EX: u16 = 42;
    /// TxPDOs (inputs).
    pub const TXPDO: u16 = 50;
    /// RxPDOs (outputs).
    pub const RXPDO: u16 = 51;
    /// Distributed clock operation modes.
    pub const DC: u16 = 60;
    /// End marker.
    pub const END: u16 = 0xFFFF;

    /// The category's name, as ESI and the IgH tool print it.
    pub fn name(kind: u16) -> &'static str {
        match kind {
            STRINGS => "Strings",
            DATA_TYPES => "DataTypes",
            GENERAL => "General",
            FMMU => "FMMU",
            SYNC_MANAGER => "SyncM",
            FMMU_EX => "FMMUX",
            TXPDO => "TxPDO",
            RXPDO => "RxPDO",
            DC => "DC",
            1..=9 => "NOP",
            0x0800..=0x0FFF => "vendor specific",
            _ => "unknown",
        }
    }
}
