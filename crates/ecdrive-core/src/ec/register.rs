//! ESC register addresses (ETG.1000.4 and the Beckhoff ESC datasheet, section II).
//!
//! The software slave implements these; the master reads and writes them directly where ethercrab
//! has no API (AL error acknowledge, SM status for mailbox polling, DC diagnostics).

/// ESC type (u8).
pub const TYPE: u16 = 0x0000;
/// ESC revision (u8).
pub const REVISION: u16 = 0x0001;
/// ESC build (u16).
pub const BUILD: u16 = 0x0002;
/// Number of supported FMMUs (u8).
pub const FMMU_COUNT: u16 = 0x0004;
/// Number of supported SyncManagers (u8).
pub const SM_COUNT: u16 = 0x0005;
/// Process RAM size in KiB (u8).
pub const RAM_SIZE: u16 = 0x0006;
/// Port descriptor (u8), two bits per port.
pub const PORT_DESCRIPTOR: u16 = 0x0007;
/// ESC features supported (u16).
pub const FEATURES: u16 = 0x0008;
/// Configured station address (u16).
pub const STATION_ADDRESS: u16 = 0x0010;
/// Configured station alias (u16), loaded from SII word 4.
pub const STATION_ALIAS: u16 = 0x0012;
/// Register write enable (u8).
pub const WRITE_ENABLE: u16 = 0x0020;
/// Register write protection (u8).
pub const WRITE_PROTECTION: u16 = 0x0021;
/// ESC write enable (u8).
pub const ESC_WRITE_ENABLE: u16 = 0x0030;
/// ESC write protection (u8).
pub const ESC_WRITE_PROTECTION: u16 = 0x0031;
/// ESC reset, ECAT side (u8).
pub const ESC_RESET_ECAT: u16 = 0x0040;
/// ESC reset, PDI side (u8).
pub const ESC_RESET_PDI: u16 = 0x0041;
/// DL control (u32).
pub const DL_CONTROL: u16 = 0x0100;
/// Physical read/write offset (u16).
pub const PHYSICAL_RW_OFFSET: u16 = 0x0108;
/// DL status (u16).
pub const DL_STATUS: u16 = 0x0110;
/// AL control (u16).
pub const AL_CONTROL: u16 = 0x0120;
/// AL status (u16).
pub const AL_STATUS: u16 = 0x0130;
/// AL status code (u16).
pub const AL_STATUS_CODE: u16 = 0x0134;
/// RUN LED override (u8).
pub const RUN_LED_OVERRIDE: u16 = 0x0138;
/// ERR LED override (u8).
pub const ERR_LED_OVERRIDE: u16 = 0x0139;
/// PDI control (u8).
pub const PDI_CONTROL: u16 = 0x0140;
/// ESC configuration (u8).
pub const ESC_CONFIGURATION: u16 = 0x0141;
/// PDI configuration (u16).
pub const PDI_CONFIGURATION: u16 = 0x0150;
/// ECAT event mask (u16).
pub const ECAT_EVENT_MASK: u16 = 0x0200;
/// AL event mask (u32).
pub const AL_EVENT_MASK: u16 = 0x0204;
/// ECAT event request (u16).
pub const ECAT_EVENT_REQUEST: u16 = 0x0210;
/// AL event request (u32).
pub const AL_EVENT_REQUEST: u16 = 0x0220;
/// RX error counters, port 0..3 (4 × u16).
pub const RX_ERROR_COUNTER: u16 = 0x0300;
/// Forwarded RX error counters, port 0..3 (4 × u8).
pub const FORWARDED_RX_ERROR_COUNTER: u16 = 0x0308;
/// ECAT processing unit error counter (u8).
pub const EPU_ERROR_COUNTER: u16 = 0x030C;
/// PDI error counter (u8).
pub const PDI_ERROR_COUNTER: u16 = 0x030D;
/// Lost link counters, port 0..3 (4 × u8).
pub const LOST_LINK_COUNTER: u16 = 0x0310;
/// Watchdog divider (u16), in 40 ns units minus 2.
pub const WATCHDOG_DIVIDER: u16 = 0x0400;
/// PDI watchdog time (u16).
pub const WATCHDOG_TIME_PDI: u16 = 0x0410;
/// Process-data (SM) watchdog time (u16).
pub const WATCHDOG_TIME_PROCESS_DATA: u16 = 0x0420;
/// Process-data watchdog status (u16): bit 0 = 1 when OK or disabled.
pub const WATCHDOG_STATUS_PROCESS_DATA: u16 = 0x0440;
/// Process-data watchdog expiry counter (u8).
pub const WATCHDOG_COUNTER_PROCESS_DATA: u16 = 0x0442;
/// PDI watchdog expiry counter (u8).
pub const WATCHDOG_COUNTER_PDI: u16 = 0x0443;
/// SII EEPROM configuration (u8).
pub const SII_CONFIG: u16 = 0x0500;
/// SII EEPROM PDI access state (u8).
pub const SII_PDI_ACCESS: u16 = 0x0501;
/// SII EEPROM control/status (u16).
pub const SII_CONTROL: u16 = 0x0502;
/// SII EEPROM address in words (u32).
pub const SII_ADDRESS: u16 = 0x0504;
/// SII EEPROM data (4 or 8 bytes).
pub const SII_DATA: u16 = 0x0508;
/// First FMMU (16 bytes each).
pub const FMMU_BASE: u16 = 0x0600;
/// Size of one FMMU register block.
pub const FMMU_SIZE: u16 = 16;
/// First SyncManager (8 bytes each).
pub const SM_BASE: u16 = 0x0800;
/// Size of one SyncManager register block.
pub const SM_SIZE: u16 = 8;
/// Offset of the status byte inside a SyncManager block.
pub const SM_STATUS_OFFSET: u16 = 5;
/// Offset of the activate byte inside a SyncManager block.
pub const SM_ACTIVATE_OFFSET: u16 = 6;
/// Offset of the PDI control byte inside a SyncManager block.
pub const SM_PDI_CONTROL_OFFSET: u16 = 7;
/// DC receive time port 0 (u32); a write latches all ports.
pub const DC_RECEIVE_TIME_PORT0: u16 = 0x0900;
/// DC receive time port 1 (u32).
pub const DC_RECEIVE_TIME_PORT1: u16 = 0x0904;
/// DC receive time port 2 (u32).
pub const DC_RECEIVE_TIME_PORT2: u16 = 0x0908;
/// DC receive time port 3 (u32).
pub const DC_RECEIVE_TIME_PORT3: u16 = 0x090C;
/// DC system time (u64): read = local time + offset; write = control-loop input.
pub const DC_SYSTEM_TIME: u16 = 0x0910;
/// DC receive time of the processing unit (u64).
pub const DC_RECEIVE_TIME_EPU: u16 = 0x0918;
/// DC system time offset (u64).
pub const DC_SYSTEM_TIME_OFFSET: u16 = 0x0920;
/// DC system time delay (u32).
pub const DC_SYSTEM_TIME_DELAY: u16 = 0x0928;
/// DC system time difference (u32, sign-magnitude: bit 31 set = local copy ≥ received).
pub const DC_SYSTEM_TIME_DIFFERENCE: u16 = 0x092C;
/// DC speed counter start (u16).
pub const DC_SPEED_COUNTER_START: u16 = 0x0930;
/// DC speed counter difference (u16).
pub const DC_SPEED_COUNTER_DIFF: u16 = 0x0932;
/// DC system time difference filter depth (u8).
pub const DC_TIME_FILTER_DEPTH: u16 = 0x0934;
/// DC speed counter filter depth (u8).
pub const DC_SPEED_FILTER_DEPTH: u16 = 0x0935;
/// DC cyclic unit control (u8).
pub const DC_CYCLIC_UNIT_CONTROL: u16 = 0x0980;
/// DC activation (u8): bit 0 cyclic operation, bit 1 SYNC0, bit 2 SYNC1.
pub const DC_ACTIVATION: u16 = 0x0981;
/// DC SYNC pulse length (u16, 10 ns units).
pub const DC_PULSE_LENGTH: u16 = 0x0982;
/// DC activation status (u8).
pub const DC_ACTIVATION_STATUS: u16 = 0x0984;
/// DC SYNC0 status (u8).
pub const DC_SYNC0_STATUS: u16 = 0x098E;
/// DC SYNC1 status (u8).
pub const DC_SYNC1_STATUS: u16 = 0x098F;
/// DC start time of cyclic operation (u64) / next SYNC0 pulse on read.
pub const DC_START_TIME: u16 = 0x0990;
/// DC next SYNC1 pulse (u64).
pub const DC_NEXT_SYNC1: u16 = 0x0998;
/// DC SYNC0 cycle time (u32, ns).
pub const DC_SYNC0_CYCLE: u16 = 0x09A0;
/// DC SYNC1 cycle time (u32, ns).
pub const DC_SYNC1_CYCLE: u16 = 0x09A4;
/// Start of process RAM.
pub const PROCESS_RAM: u16 = 0x1000;

/// The address of SyncManager `n`'s register block.
pub const fn sm(n: u8) -> u16 {
    SM_BASE + SM_SIZE * n as u16
}

/// The address of FMMU `n`'s register block.
pub const fn fmmu(n: u8) -> u16 {
    FMMU_BASE + FMMU_SIZE * n as u16
}

/// One FMMU register block (ETG.1000.4 Table 57, 16 bytes at [`fmmu`]`(n)`): how the ESC maps a
/// range of the logical address space onto its physical memory. The one view of these bytes
/// for the software slave's ESC and for the master, which reads the mapping back from the
/// configuration it sent (see the working-counter plan of the cycle).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FmmuConfig {
    /// Logical start address (bytes 0–3).
    pub logical_start: u32,
    /// Length in bytes (bytes 4–5).
    pub length: u16,
    /// Logical start bit (byte 6, bits 0–2).
    pub logical_start_bit: u8,
    /// Logical stop bit (byte 7, bits 0–2).
    pub logical_stop_bit: u8,
    /// Physical start address (bytes 8–9).
    pub physical_start: u16,
    /// Physical start bit (byte 10, bits 0–2).
    pub physical_start_bit: u8,
    /// Type bit 0 (byte 11): read access (the master reads: inputs).
    pub read: bool,
    /// Type bit 1 (byte 11): write access (the master writes: outputs).
    pub write: bool,
    /// Activate (byte 12, bit 0).
    pub active: bool,
}

impl FmmuConfig {
    /// Read one block; `None` if `b` is shorter than [`FMMU_SIZE`].
    pub fn parse(b: &[u8]) -> Option<Self> {
        let b = b.get(..usize::from(FMMU_SIZE))?;
        Some(Self {
            logical_start: u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            length: u16::from_le_bytes([b[4], b[5]]),
            logical_start_bit: b[6] & 0x07,
            logical_stop_bit: b[7] & 0x07,
            physical_start: u16::from_le_bytes([b[8], b[9]]),
            physical_start_bit: b[10] & 0x07,
            read: b[11] & 0x01 != 0,
            write: b[11] & 0x02 != 0,
            active: b[12] & 0x01 != 0,
        })
    }

    /// The 16 bytes of the block.
    pub fn emit(&self) -> [u8; FMMU_SIZE as usize] {
        let mut b = [0u8; FMMU_SIZE as usize];
        b[0..4].copy_from_slice(&self.logical_start.to_le_bytes());
        b[4..6].copy_from_slice(&self.length.to_le_bytes());
        b[6] = self.logical_start_bit & 0x07;
        b[7] = self.logical_stop_bit & 0x07;
        b[8..10].copy_from_slice(&self.physical_start.to_le_bytes());
        b[10] = self.physical_start_bit & 0x07;
        b[11] = u8::from(self.read) | u8::from(self.write) << 1;
        b[12] = u8::from(self.active);
        b
    }

    /// The logical bytes the block covers, `logical_start..logical_start + length`.
    pub fn logical_range(&self) -> core::ops::Range<u32> {
        self.logical_start..self.logical_start.saturating_add(u32::from(self.length))
    }
}

/// A short name for a register address, for error messages (`"AL status (0x0130)"`). Addresses
/// without a name print as hex.
pub fn describe(addr: u16) -> String {
    let name = match addr {
        TYPE => "ESC type",
        FEATURES => "ESC features",
        STATION_ADDRESS => "station address",
        STATION_ALIAS => "station alias",
        DL_CONTROL => "DL control",
        DL_STATUS => "DL status",
        AL_CONTROL => "AL control",
        AL_STATUS => "AL status",
        AL_STATUS_CODE => "AL status code",
        SII_CONFIG => "SII configuration",
        SII_CONTROL => "SII control/status",
        SII_ADDRESS => "SII address",
        SII_DATA => "SII data",
        WATCHDOG_DIVIDER => "watchdog divider",
        WATCHDOG_TIME_PROCESS_DATA => "process-data watchdog time",
        DC_RECEIVE_TIME_PORT0 => "DC receive time port 0",
        DC_SYSTEM_TIME => "DC system time",
        DC_SYSTEM_TIME_OFFSET => "DC system time offset",
        DC_SYSTEM_TIME_DELAY => "DC system time delay",
        DC_SYSTEM_TIME_DIFFERENCE => "DC system time difference",
        DC_ACTIVATION => "DC activation",
        DC_START_TIME => "DC start time",
        DC_SYNC0_CYCLE => "DC SYNC0 cycle time",
        a if (FMMU_BASE..SM_BASE).contains(&a) => {
            return format!("FMMU{} (0x{addr:04X})", (a - FMMU_BASE) / FMMU_SIZE);
        }
        a if (SM_BASE..0x0900).contains(&a) => {
            return format!("SM{} (0x{addr:04X})", (a - SM_BASE) / SM_SIZE);
        }
        _ => return format!("register 0x{addr:04X}"),
    };
    format!("{name} (0x{addr:04X})")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn fmmu_block_as_etg1000_4_lays_it_out() {
        // Logical 0x00010000, 6 bytes, bits 0..7, physical 0x1100, read+write, active.
        let b = [
            0x00, 0x00, 0x01, 0x00, 0x06, 0x00, 0x00, 0x07, 0x00, 0x11, 0x00, 0x03, 0x01, 0, 0, 0,
        ];
        let f = FmmuConfig::parse(&b).unwrap();
        assert_eq!(f.logical_start, 0x0001_0000);
        assert_eq!(f.length, 6);
        assert_eq!(f.logical_stop_bit, 7);
        assert_eq!(f.physical_start, 0x1100);
        assert!(f.read && f.write && f.active);
        assert_eq!(f.logical_range(), 0x0001_0000..0x0001_0006);
        assert_eq!(f.emit(), b);
        assert_eq!(FmmuConfig::parse(&b[..15]), None);
    }

    proptest! {
        #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(crate::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
        #[test]
        fn fmmu_parse_emit_round_trip(
            ls in any::<u32>(), len in any::<u16>(), sb in 0u8..8, eb in 0u8..8,
            ps in any::<u16>(), pb in 0u8..8, r in any::<bool>(), w in any::<bool>(),
            a in any::<bool>(),
        ) {
            let f = FmmuConfig {
                logical_start: ls, length: len, logical_start_bit: sb, logical_stop_bit: eb,
                physical_start: ps, physical_start_bit: pb, read: r, write: w, active: a,
            };
            prop_assert_eq!(FmmuConfig::parse(&f.emit()), Some(f));
        }
    }
}
