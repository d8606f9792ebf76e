//! The SII EEPROM interface (registers 0x0500–0x050F).

use super::*;

impl Esc {
    pub(super) fn sii_reload(&mut self) {
        let ok = self.sii.checksum_ok();
        self.set_bits(0x0503, 0x08, !ok);
        // b6: 8-byte reads; b7: 2-byte addressing for EEPROMs above 16 Kbit.
        let big = self.sii.bytes().len() > 2048;
        self.set_bits(0x0502, 0x40, !self.cfg.eeprom_reads_4_bytes);
        self.set_bits(0x0502, 0x80, big);
        if ok {
            let w0 = self.sii.word(0);
            let w1 = self.sii.word(1);
            let w2 = self.sii.word(2);
            let w3 = self.sii.word(3);
            let w4 = self.sii.word(4);
            self.put_u16(0x0140, w0);
            self.put_u16(0x0150, w1);
            self.put_u16(0x0152, w3);
            if self.cfg.dc.supported() {
                self.put_u16(0x0982, w2);
            }
            self.put_u16(0x0012, w4);
            self.station_address_changed = true;
        }
        let dl = self.get_u16(0x0110);
        self.put_u16(0x0110, if ok { dl | 1 } else { dl & !1 });
    }

    /// A command written to 0x0502: done at once, or after
    /// [`EscConfig::eeprom_busy_frames`] frames, busy until then.
    pub(super) fn sii_command(&mut self) {
        let cmd = (self.get_u16(0x0502) >> 8) & 0x07;
        let frames = self.cfg.eeprom_busy_frames;
        if cmd == 0 || frames == 0 {
            self.sii_execute();
            return;
        }
        self.sii_busy = frames;
        // Busy, the command bits showing the command running.
        self.set_bits(0x0503, 0x80, true);
        self.pending |= super::pending::SII_BUSY;
    }

    /// A frame has passed while a command runs.
    pub(super) fn sii_frame_end(&mut self) {
        self.sii_busy = self.sii_busy.saturating_sub(1);
        if self.sii_busy == 0 {
            self.sii_execute();
            self.set_bits(0x0503, 0x80, false);
        } else {
            self.pending |= super::pending::SII_BUSY;
        }
    }

    fn sii_execute(&mut self) {
        let ctl = self.get_u16(0x0502);
        let cmd = (ctl >> 8) & 0x07;
        // Command field reads back as 0 (done). A new command clears the error bits.
        let mut status = self.byte(0x0503) & 0x08; // keep checksum error
        match cmd {
            0 => {}
            1 => {
                let addr = self.get_u32(0x0504);
                let mut data = [0u8; 8];
                for (i, chunk) in data.chunks_exact_mut(2).enumerate() {
                    let w = self.sii.word(addr.wrapping_add(i as u32));
                    chunk.copy_from_slice(&w.to_le_bytes());
                }
                let n = if self.cfg.eeprom_reads_4_bytes { 4 } else { 8 };
                self.put(0x0508, &data[..n]);
            }
            2 => {
                if ctl & 0x0001 == 0 {
                    status |= 0x40; // write enable error
                } else if self.cfg.eeprom_write_protected {
                    status |= 0x20; // the EEPROM does not acknowledge
                } else {
                    let addr = self.get_u32(0x0504) as usize;
                    let v = [self.byte(0x0508), self.byte(0x0509)];
                    match self.sii.bytes_mut().get_mut(addr * 2..addr * 2 + 2) {
                        Some(d) => d.copy_from_slice(&v),
                        None => status |= 0x20,
                    }
                }
            }
            4 => {
                self.sii_reload();
                status = self.byte(0x0503) & 0x08;
            }
            _ => status |= 0x20, // command error
        }
        self.put(0x0503, &[status | (self.byte(0x0503) & 0x80)]);
        // Write enable is self-clearing.
        self.set_bits(0x0502, 0x01, false);
    }
}
