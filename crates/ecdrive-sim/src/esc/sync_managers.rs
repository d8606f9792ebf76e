//! SyncManagers: their views, buffer and mailbox handshakes on the RAM side, and what writing their registers does.

use super::*;

impl Esc {
    pub(super) fn rebuild_sms(&mut self) {
        self.sms.clear();
        let ram_end = self.mem.len();
        for n in 0..self.cfg.sm_count {
            let b = 0x0800 + 8 * usize::from(n);
            if self.byte(b + 6) & 0x01 == 0 {
                continue;
            }
            let start = usize::from(self.get_u16(b));
            let len = usize::from(self.get_u16(b + 2));
            if len == 0 {
                continue;
            }
            let ctl = self.byte(b + 4);
            self.sms.push(SmView {
                idx: n,
                start,
                end: (start + len).min(ram_end.max(start)),
                mailbox: ctl & 0x03 == 0x02,
                ecat_writes: (ctl >> 2) & 0x03 == 0x01,
                usable: self.byte(b + 7) & 0x01 == 0,
            });
        }
    }

    pub(super) fn sm_base(n: u8) -> usize {
        0x0800 + 8 * usize::from(n)
    }

    pub(super) fn sm_enabled(&self, n: u8) -> bool {
        self.byte(Self::sm_base(n) + 6) & 0x01 != 0
    }

    pub(super) fn sm_full(&self, n: u8) -> bool {
        self.byte(Self::sm_base(n) + 5) & 0x08 != 0
    }

    pub(super) fn set_sm_full(&mut self, n: u8, full: bool) {
        self.set_bits(Self::sm_base(n) + 5, 0x08, full);
    }

    /// (start, end) of an enabled process-data SM.
    pub(super) fn pd_sm_range(&self, sm: Option<u8>) -> Option<(usize, usize)> {
        let n = sm?;
        if !self.sm_enabled(n) {
            return None;
        }
        let b = Self::sm_base(n);
        let start = usize::from(self.get_u16(b));
        let len = usize::from(self.get_u16(b + 2));
        let end = start.checked_add(len)?;
        if end > self.mem.len() || start < REG_SPACE {
            return None;
        }
        Some((start, end))
    }

    /// Set PDI-deactivate bits of the device's SMs according to the AL state: mailbox SMs are
    /// usable from PRE-OP (or BOOT), the process-data SMs from SAFE-OP on. Slave stacks start
    /// the output channel with the input handler at PRE-OP → SAFE-OP, so that "the master can
    /// check if the slave could update inputs and outputs before switching the slave to OP"
    /// (ETG.1020; SOES enables SM2 in that step too): in SAFE-OP the outputs are taken (and
    /// counted in the working counter) but not acted on (the MR-J4-TM manual §1.4.1: "Though
    /// the PDO communication also can be performed, all operations (commands) such as servo
    /// motor drive are invalid").
    pub(super) fn update_pdi_deactivation(&mut self) {
        let st = self.state;
        let mbx_on = self.mailbox.running;
        let set = |esc: &mut Self, n: u8, on: bool| {
            if n < esc.cfg.sm_count {
                esc.set_bits(Self::sm_base(n) + 7, 0x01, !on);
            }
        };
        let layout = if st == AlState::Bootstrap {
            self.boot_mbx
        } else {
            self.mbx
        };
        if let Some(m) = layout.or(self.mbx) {
            set(self, m.sm_out, mbx_on);
            set(self, m.sm_in, mbx_on);
        }
        if let Some(n) = self.sm_in_pd {
            set(self, n, matches!(st, AlState::SafeOp | AlState::Op));
        }
        if let Some(n) = self.sm_out_pd {
            let on = if self.outputs_only_in_op {
                st == AlState::Op
            } else {
                matches!(st, AlState::SafeOp | AlState::Op)
            };
            set(self, n, on);
        }
        self.rebuild_sms();
    }

    /// The run of RAM starting at `pos` (before `b`) that is covered by one SM, or by none:
    /// returns its end and the SM.
    pub(super) fn next_run(&self, pos: usize, b: usize) -> (usize, Option<SmView>) {
        let mut next_start = b;
        for sm in &self.sms {
            if sm.start <= pos && pos < sm.end {
                return (sm.end.min(b), Some(*sm));
            }
            if sm.start > pos && sm.start < next_start {
                next_start = sm.start;
            }
        }
        (next_start, None)
    }

    /// A buffered-mode buffer was completed (written or read including its last byte).
    pub(super) fn buffer_done(&mut self, n: u8) {
        let st = Self::sm_base(n) + 5;
        let cur = (self.byte(st) >> 4) & 0x03;
        let next = if cur >= 2 { 0 } else { cur + 1 };
        if let Some(b) = self.mem.get_mut(st) {
            *b = (*b & !0x30) | (next << 4);
        }
    }

    pub(super) fn outputs_completed(&mut self, sm: SmView, hop: Hop) {
        let len = sm.end - sm.start;
        if self.pd.outputs.len() != len {
            self.pd.outputs.resize(len, 0);
        }
        if let Some(src) = self.mem.get(sm.start..sm.end) {
            self.pd.outputs.copy_from_slice(src);
        }
        self.pd.outputs_received = self.pd.outputs_received.saturating_add(1);
        let t = if self.cfg.dc.supported() {
            self.system_time(hop.forward_ns)
        } else {
            self.local_time(hop.forward_ns)
        };
        self.pd.last_outputs_ns = Some(t);
        if self.state == AlState::Op
            && self.dc.sync.active
            && self.dc.sync.count > 0
            && let Some(stats) = self.timing.as_deref_mut()
        {
            // Pulses up to now were delivered before this frame: the latest one was a cycle
            // before the next.
            let cycle = i128::from(self.dc.sync.cycle.max(1));
            let last = i128::from(self.dc.sync.next) - cycle;
            let since = (i128::from(t) - last).rem_euclid(cycle);
            stats.record_arrival(since as u64);
        }
        // Re-trigger the SM watchdog.
        if self.byte(Self::sm_base(sm.idx) + 4) & 0x40 != 0 {
            self.wd_deadline = self.watchdog_ns().map(|w| hop.forward_ns.saturating_add(w));
            self.set_bits(0x0440, 0x01, true);
        }
    }

    pub(super) fn sm_registers_written(&mut self, old_act: &[u8; MAX_SM], dev: &mut dyn Device) {
        let mut changed = false;
        for n in 0..self.cfg.sm_count {
            let base = Self::sm_base(n);
            let old = old_act.get(usize::from(n)).copied().unwrap_or(0);
            let new = self.byte(base + 6);
            if old & 0x01 != new & 0x01 {
                changed = true;
                // Enabling or disabling resets the buffer state.
                let ctl = self.byte(base + 4);
                let status = if ctl & 0x03 == 0x02 { 0x00 } else { 0x30 };
                self.put(base + 5, &[status]);
                let is_mbx = self.mbx.is_some_and(|m| m.sm_out == n || m.sm_in == n);
                if is_mbx {
                    if n == self.mbx.map(|m| m.sm_in).unwrap_or(u8::MAX) {
                        self.mailbox.backup_valid = false;
                        // Repeat request/ack restart in sync.
                        self.set_bits(base + 7, 0x02, new & 0x02 != 0);
                    }
                    dev.mailbox_reset();
                }
                if Some(n) == self.sm_out_pd && new & 0x01 != 0 {
                    let len = usize::from(self.get_u16(base + 2));
                    self.pd.outputs.clear();
                    self.pd.outputs.resize(len, 0);
                }
            }
            if old & 0x02 != new & 0x02 && self.mbx.is_some_and(|m| m.sm_in == n) {
                self.pending |= pending::MBX_REPEAT;
            }
            if old != new {
                changed = true;
            }
        }
        self.rebuild_sms();
        if changed {
            self.pending |= pending::SM_CHANGED;
        }
    }

    pub(super) fn check_sm_change(&mut self, dev: &mut dyn Device) {
        let st = self.state;
        if matches!(st, AlState::PreOp | AlState::SafeOp | AlState::Op) {
            if let Some(m) = self.mbx {
                if !self.mailbox_config_ok(&m) {
                    self.local_error(AlState::Init, AlStatusCode::INVALID_MAILBOX_CONFIG, dev);
                    return;
                }
            }
        }
        if matches!(st, AlState::SafeOp | AlState::Op) {
            if let Err(c) = self.check_process_data(dev) {
                self.local_error(AlState::PreOp, c, dev);
            }
        }
    }
}
