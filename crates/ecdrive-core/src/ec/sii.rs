//! The SII EEPROM layout (ETG.1000.6 §5.4, ETG.2010): word addresses of the fixed header and
//! the category types that follow it. Shared by the software slave (which builds images) and the
//! master's tools (which decode them).

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
