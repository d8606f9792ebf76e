//! The SII EEPROM interface (registers 0x0500–0x050F).

use super::*;

impl Esc {
    pub(super) fn sii_reload(&mut self) {
        let ok = self.sii.checksum_ok();
        self.set_bits(0x0503, 0x08, !ok);
        // b6: 8-byte reads; b7: 2-byte addressing for EEPROMs above 16 Kbit.
        let big = self.sii.bytes().len() > 2048;
        self.set_bits(0x0502, 0x40, true);
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

    pub(super) fn sii_command(&mut self) {
        let ctl = self.get_u16(0x0502);
        let cmd = (ctl >> 8) & 0x07;
        // Command field reads back as 0 (done); busy never set: commands complete at once.
        // A new command clears the error bits.
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
                self.put(0x0508, &data);
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
        self.put(0x0503, &[status]);
        // Write enable is self-clearing.
        self.set_bits(0x0502, 0x01, false);
    }
}
