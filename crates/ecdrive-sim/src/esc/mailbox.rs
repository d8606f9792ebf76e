//! The mailbox: its layout, starting and stopping it, repeat requests, serving the device's replies.

use super::*;

impl Esc {
    /// The mailbox layout in use: the bootstrap mailbox in BOOT, the standard one otherwise.
    pub(super) fn active_mbx(&self) -> Option<MbxLayout> {
        if self.state == AlState::Bootstrap {
            self.boot_mbx
        } else {
            self.mbx
        }
    }

    pub(super) fn mailbox_read_done(&mut self, n: u8) {
        if let Some(m) = self.active_mbx() {
            if n == m.sm_in {
                let (s, e) = (
                    usize::from(m.in_start),
                    usize::from(m.in_start) + usize::from(m.in_len),
                );
                if let Some(src) = self.mem.get(s..e) {
                    if self.mailbox.backup.len() == src.len() {
                        self.mailbox.backup.copy_from_slice(src);
                        self.mailbox.backup_valid = true;
                    }
                }
            }
        }
        self.set_sm_full(n, false);
        self.set_bits(Self::sm_base(n) + 5, 0x02, true);
        self.pending |= pending::MBX_READ;
    }

    pub(super) fn mailbox_config_ok(&self, layout: &MbxLayout) -> bool {
        let check = |n: u8, start: u16, len: u16, dir: u8| {
            if n >= self.cfg.sm_count {
                return false;
            }
            let b = Self::sm_base(n);
            self.get_u16(b) == start
                && self.get_u16(b + 2) == len
                && self.byte(b + 4) & 0x0F == (0x02 | dir << 2)
                && self.byte(b + 6) & 0x01 != 0
        };
        check(layout.sm_out, layout.out_start, layout.out_len, 1)
            && check(layout.sm_in, layout.in_start, layout.in_len, 0)
    }

    pub(super) fn start_mailbox(&mut self, layout: Option<MbxLayout>, dev: &mut dyn Device) {
        self.mailbox.running = true;
        self.mailbox.backup_valid = false;
        if let Some(m) = layout {
            // Buffers sized for this mailbox (allocates only when the size changes, at a state
            // transition).
            self.mailbox.request.resize(usize::from(m.out_len), 0);
            self.mailbox.reply.resize(usize::from(m.in_len), 0);
            self.mailbox.backup.resize(usize::from(m.in_len), 0);
            // The repeat toggle starts in sync with what the master has.
            let act = self.byte(Self::sm_base(m.sm_in) + 6);
            self.set_bits(Self::sm_base(m.sm_in) + 7, 0x02, act & 0x02 != 0);
        }
        dev.mailbox_reset();
    }

    pub(super) fn stop_mailbox(&mut self, dev: &mut dyn Device) {
        if self.mailbox.running {
            dev.mailbox_reset();
        }
        self.mailbox.running = false;
        self.mailbox.backup_valid = false;
    }

    pub(super) fn mailbox_repeat(&mut self) {
        let Some(m) = self.active_mbx() else { return };
        let base = Self::sm_base(m.sm_in);
        let req = self.byte(base + 6) & 0x02;
        if self.mailbox.running && !self.sm_full(m.sm_in) && self.mailbox.backup_valid {
            let s = usize::from(m.in_start);
            let backup = core::mem::take(&mut self.mailbox.backup);
            self.put(s, &backup);
            self.mailbox.backup = backup;
            self.set_sm_full(m.sm_in, true);
        }
        self.set_bits(base + 7, 0x02, req != 0);
    }

    pub(super) fn service_mailbox(&mut self, dev: &mut dyn Device) {
        let Some(m) = self.active_mbx() else { return };
        let state = self.state;
        if self.sm_full(m.sm_in) || !self.sm_enabled(m.sm_in) {
            return;
        }
        let out_start = usize::from(m.in_start);
        let out_len = usize::from(m.in_len);
        if self.sm_full(m.sm_out) {
            let s = usize::from(m.out_start);
            let e = s + usize::from(m.out_len);
            let mut req = core::mem::take(&mut self.mailbox.request);
            let mut rep = core::mem::take(&mut self.mailbox.reply);
            if let Some(src) = self.mem.get(s..e) {
                if req.len() == src.len() {
                    req.copy_from_slice(src);
                }
            }
            self.set_sm_full(m.sm_out, false);
            self.set_bits(Self::sm_base(m.sm_out) + 5, 0x01, false);
            rep.fill(0);
            let n = dev.mailbox_request(state, &req, &mut rep);
            if let Some(n) = n {
                self.post_mailbox(out_start, out_len, &rep, n, m.sm_in);
            }
            self.mailbox.request = req;
            self.mailbox.reply = rep;
            return;
        }
        let mut rep = core::mem::take(&mut self.mailbox.reply);
        rep.fill(0);
        if let Some(n) = dev.mailbox_poll(&mut rep) {
            self.post_mailbox(out_start, out_len, &rep, n, m.sm_in);
        }
        self.mailbox.reply = rep;
    }

    pub(super) fn post_mailbox(&mut self, start: usize, len: usize, rep: &[u8], n: usize, sm: u8) {
        if n == 0 || n > len {
            return;
        }
        if let Some(dst) = self.mem.get_mut(start..start + len) {
            dst.fill(0);
            if let (Some(d), Some(s)) = (dst.get_mut(..n), rep.get(..n)) {
                d.copy_from_slice(s);
            }
        }
        self.set_sm_full(sm, true);
        self.set_bits(Self::sm_base(sm) + 5, 0x02, false);
    }
}
