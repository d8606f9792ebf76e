//! The register map of the emulated ESC: which register bytes exist and which bits the master
//! (ECAT side) may write.
//!
//! Register space 0x0000–0x0FFF is byte memory. Each byte has a write mask (bits ECAT may change)
//! and flags: whether the byte exists at all (accesses to missing registers do not count in the
//! working counter) and whether a write has an effect although no bit is stored ("trigger"
//! registers such as the DC receive-time latch 0x0900 or the error counters, which a write
//! clears). Values follow the Beckhoff ESC datasheet section II register descriptions.

use super::EscConfig;

/// Number of register bytes (process RAM starts at 0x1000).
pub const REG_SPACE: usize = 0x1000;

/// The byte exists: ECAT reads count.
pub const IMPLEMENTED: u8 = 0x01;
/// A write to the byte counts and has a side effect even though no bit is stored.
pub const TRIGGER: u8 = 0x02;

/// Per-byte attributes of the register space.
#[derive(Debug, Clone)]
pub struct RegisterMap {
    /// ECAT write mask per byte.
    pub wmask: Box<[u8]>,
    /// [`IMPLEMENTED`] / [`TRIGGER`] per byte.
    pub flags: Box<[u8]>,
}

impl RegisterMap {
    /// Build the map for an ESC with the given configuration.
    pub fn new(cfg: &EscConfig) -> Self {
        let mut m = Self {
            wmask: vec![0u8; REG_SPACE].into_boxed_slice(),
            flags: vec![0u8; REG_SPACE].into_boxed_slice(),
        };
        // Read-only identification.
        m.ro(0x0000, 10);
        // Station address (R/W), alias (ECAT read-only: loaded from SII word 4).
        m.rw(0x0010, &[0xFF, 0xFF]);
        m.ro(0x0012, 2);
        // Write enable / protection.
        m.rw(0x0020, &[0x01, 0x01]);
        m.rw(0x0030, &[0x01, 0x01]);
        // ESC reset ECAT (write 'R' 'E' 'S'); reads return the sequence progress.
        m.rw(0x0040, &[0xFF]);
        m.ro(0x0041, 1);
        // DL control: forwarding rule, temporary loop, loop ports, FIFO size, alias enable.
        m.rw(0x0100, &[0x03, 0xFF, 0x07, 0x03]);
        m.rw(0x0108, &[0xFF, 0xFF]);
        // DL status.
        m.ro(0x0110, 2);
        // AL control (state, ack, ID request), AL status, AL status code.
        m.rw(0x0120, &[0x3F, 0x00]);
        m.ro(0x0130, 2);
        m.ro(0x0134, 2);
        // LED override.
        m.rw(0x0138, &[0x1F, 0x1F]);
        // PDI control, ESC configuration, PDI information, PDI configuration (from SII).
        m.ro(0x0140, 2);
        m.ro(0x014E, 2);
        m.ro(0x0150, 4);
        // ECAT event mask (R/W), AL event mask (PDI side), event requests.
        m.rw(0x0200, &[0xFF, 0xFF]);
        m.ro(0x0204, 4);
        m.ro(0x0210, 2);
        m.ro(0x0220, 4);
        // Error counters: a write to any RX error counter clears them all; the others clear
        // individually.
        m.trigger(0x0300, 14);
        m.ro(0x030E, 2);
        m.trigger(0x0310, 4);
        // Watchdogs.
        m.rw(0x0400, &[0xFF, 0xFF]);
        m.rw(0x0410, &[0xFF, 0xFF]);
        m.rw(0x0420, &[0xFF, 0xFF]);
        m.ro(0x0440, 2);
        m.trigger(0x0442, 2);
        // SII EEPROM interface. 0x0500: b0 PDI access offered, b1 force PDI release.
        m.rw(0x0500, &[0x03]);
        m.ro(0x0501, 1);
        // 0x0502: b0 write enable; b5–b7 read-only capability bits.
        // 0x0503: b0–b2 command; b3–b7 status (read-only).
        m.rw(0x0502, &[0x01, 0x07]);
        m.rw(0x0504, &[0xFF, 0xFF, 0xFF, 0xFF]);
        m.rw(0x0508, &[0xFF; 8]);
        // FMMUs.
        for n in 0..usize::from(cfg.fmmu_count.min(16)) {
            let b = 0x0600 + 16 * n;
            m.rw(b, &[0xFF; 6]);
            m.rw(b + 6, &[0x07, 0x07]);
            m.rw(b + 8, &[0xFF, 0xFF, 0x07, 0x03, 0x01]);
            m.ro(b + 13, 3);
        }
        // SyncManagers: start, length, control (R/W while disabled), status (RO), activate,
        // PDI control (RO from ECAT).
        for n in 0..usize::from(cfg.sm_count.min(16)) {
            let b = 0x0800 + 8 * n;
            m.rw(b, &[0xFF, 0xFF, 0xFF, 0xFF, 0x7F]);
            m.ro(b + 5, 1);
            m.rw(b + 6, &[0xC3]);
            m.ro(b + 7, 1);
        }
        if cfg.dc.supported() {
            // Receive times: a write to port 0's register latches all ports.
            m.trigger(0x0900, 4);
            m.ro(0x0904, 12);
            // System time: a write is a control-loop input, not a store.
            m.trigger(0x0910, 8);
            m.ro(0x0918, 8);
            m.rw(0x0920, &[0xFF; 8]);
            m.rw(0x0928, &[0xFF, 0xFF, 0xFF, 0x0F]);
            m.ro(0x092C, 4);
            m.rw(0x0930, &[0xFF, 0x7F]);
            m.ro(0x0932, 2);
            m.rw(0x0934, &[0x0F, 0x0F]);
            // Cyclic unit control, activation, pulse length, status.
            m.rw(0x0980, &[0x31, 0xFF, 0xFF, 0xFF]);
            m.ro(0x0984, 1);
            m.ro(0x098E, 2);
            m.rw(0x0990, &[0xFF; 8]);
            m.ro(0x0998, 8);
            m.rw(0x09A0, &[0xFF; 8]);
            // Latch unit: control R/W, status and times read-only.
            m.rw(0x09A8, &[0x03, 0x03]);
            m.ro(0x09AE, 2);
            m.ro(0x09B0, 32);
            m.ro(0x09F0, 16);
        }
        // ESC specific, digital I/O, GPIO, user RAM.
        m.ro(0x0E00, 0x100);
        m.rw(0x0F00, &[0xFF; 4]);
        m.rw(0x0F10, &[0xFF; 8]);
        m.ro(0x0F18, 8);
        for a in 0x0F80..0x1000 {
            m.rw(a, &[0xFF]);
        }
        m
    }

    fn ro(&mut self, at: usize, len: usize) {
        for a in at..at + len {
            self.flags[a] |= IMPLEMENTED;
        }
    }

    fn rw(&mut self, at: usize, masks: &[u8]) {
        for (i, &mask) in masks.iter().enumerate() {
            self.flags[at + i] |= IMPLEMENTED;
            self.wmask[at + i] = mask;
        }
    }

    fn trigger(&mut self, at: usize, len: usize) {
        for a in at..at + len {
            self.flags[a] |= IMPLEMENTED | TRIGGER;
        }
    }
}
