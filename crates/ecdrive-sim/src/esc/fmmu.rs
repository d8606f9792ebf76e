//! FMMUs: logical addressing (LRD/LWR/LRW) mapped onto the ESC's memory.

use super::*;
use crate::ec::register::FmmuConfig;

impl Esc {
    pub(super) fn rebuild_fmmus(&mut self) {
        self.fmmus.clear();
        for n in 0..usize::from(self.cfg.fmmu_count) {
            let b = 0x0600 + 16 * n;
            let Some(c) = self.mem.get(b..b + 16).and_then(FmmuConfig::parse) else {
                continue;
            };
            if !c.active {
                continue;
            }
            if c.length > 0 && (c.read || c.write) {
                self.fmmus.push(c);
            }
        }
    }

    /// A logical command (LRD/LWR/LRW) at logical address `laddr`: map through the active
    /// FMMUs. Writes use the data as it arrived, then reads overwrite it. Returns the working
    /// counter increment: +1 if a read FMMU access succeeded, +2 (LRW) or +1 (LWR) if a write
    /// succeeded.
    pub fn logical(
        &mut self,
        cmd: Command,
        laddr: u32,
        data: &mut [u8],
        hop: Hop,
        dev: &mut dyn Device,
    ) -> u16 {
        let (do_read, do_write) = match cmd {
            Command::Lrd => (true, false),
            Command::Lwr => (false, true),
            Command::Lrw => (true, true),
            _ => return 0,
        };
        if self.fmmus.is_empty() || data.is_empty() {
            return 0;
        }
        let d0 = u64::from(laddr) * 8;
        let d1 = d0 + data.len() as u64 * 8;
        let mut wrote = false;
        let mut read = false;
        if do_write {
            for i in 0..self.fmmus.len() {
                let Some(f) = self.fmmus.get(i).copied() else {
                    break;
                };
                if f.write {
                    wrote |= self.fmmu_access(f, d0, d1, data, true, hop, dev);
                }
            }
        }
        if do_read {
            for i in 0..self.fmmus.len() {
                let Some(f) = self.fmmus.get(i).copied() else {
                    break;
                };
                if f.read {
                    read |= self.fmmu_access(f, d0, d1, data, false, hop, dev);
                }
            }
        }
        match cmd {
            Command::Lrw => u16::from(read) + 2 * u16::from(wrote),
            _ => u16::from(read || wrote),
        }
    }

    /// One FMMU's part of a logical access; `[d0, d1)` is the datagram in logical bits.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn fmmu_access(
        &mut self,
        f: FmmuConfig,
        d0: u64,
        d1: u64,
        data: &mut [u8],
        write: bool,
        hop: Hop,
        dev: &mut dyn Device,
    ) -> bool {
        let l0 = u64::from(f.logical_start) * 8 + u64::from(f.logical_start_bit);
        let l1 = (u64::from(f.logical_start) + u64::from(f.length) - 1) * 8
            + u64::from(f.logical_stop_bit)
            + 1;
        if l1 <= l0 {
            return false;
        }
        let lo = l0.max(d0);
        let hi = l1.min(d1);
        if lo >= hi {
            return false;
        }
        let p0 = u64::from(f.physical_start) * 8 + u64::from(f.physical_start_bit) + (lo - l0);
        if f.logical_start_bit == 0 && f.logical_stop_bit == 7 && f.physical_start_bit == 0 {
            let (dl, dh) = (((lo - d0) / 8) as usize, ((hi - d0) / 8) as usize);
            let phys = p0 / 8;
            let Ok(phys) = u16::try_from(phys) else {
                return false;
            };
            let Some(slice) = data.get_mut(dl..dh) else {
                return false;
            };
            if phys as usize + slice.len() > 0x1_0000 {
                return false;
            }
            return if write {
                self.ecat_write(phys, slice, hop, dev)
            } else {
                self.ecat_read(phys, slice, false, hop)
            };
        }
        // Bit-granular path: operate on the physical bytes spanned.
        let nbits = hi - lo;
        let pb0 = p0 / 8;
        let pb1 = (p0 + nbits - 1) / 8;
        let Ok(phys) = u16::try_from(pb0) else {
            return false;
        };
        let span = (pb1 - pb0 + 1) as usize;
        if phys as usize + span > 0x1_0000 {
            return false;
        }
        let mut buf = core::mem::take(&mut self.scratch);
        buf.clear();
        buf.resize(span, 0);
        let ok = if write {
            self.peek(phys, &mut buf);
            for k in 0..nbits {
                let src_bit = lo - d0 + k;
                let dst_bit = p0 - pb0 * 8 + k;
                let v = data
                    .get((src_bit / 8) as usize)
                    .map(|b| (b >> (src_bit % 8)) & 1)
                    .unwrap_or(0);
                if let Some(d) = buf.get_mut((dst_bit / 8) as usize) {
                    let m = 1u8 << (dst_bit % 8);
                    *d = if v != 0 { *d | m } else { *d & !m };
                }
            }
            self.ecat_write(phys, &buf, hop, dev)
        } else {
            let ok = self.ecat_read(phys, &mut buf, false, hop);
            if ok {
                for k in 0..nbits {
                    let src_bit = p0 - pb0 * 8 + k;
                    let dst_bit = lo - d0 + k;
                    let v = buf
                        .get((src_bit / 8) as usize)
                        .map(|b| (b >> (src_bit % 8)) & 1)
                        .unwrap_or(0);
                    if let Some(d) = data.get_mut((dst_bit / 8) as usize) {
                        let m = 1u8 << (dst_bit % 8);
                        *d = if v != 0 { *d | m } else { *d & !m };
                    }
                }
            }
            ok
        };
        self.scratch = buf;
        ok
    }
}
