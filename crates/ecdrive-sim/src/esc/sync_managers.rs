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
                // One-buffer ("mailbox") mode on a process-data SM (an SMC EX250's outputs on
                // the digital output register, ControlByte 0x46) is process data all the same:
                // its PDI takes each buffer at once.
                mailbox: ctl & 0x03 == 0x02
                    && !self.sm_out_pd.contains(n)
                    && !self.sm_in_pd.contains(n),
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

    /// Where a process-data SM may lie: in process RAM, or (outputs) on the digital output
    /// register.
    pub(super) fn pd_sm_in_place(&self, start: usize, end: usize, ecat_writes: bool) -> bool {
        (start >= REG_SPACE && end <= self.mem.len())
            || (ecat_writes && DIGITAL_OUT.contains(&start) && end <= DIGITAL_OUT.end)
    }

    /// (start, end) of each enabled process-data SM of `set`, in SM order.
    pub(super) fn pd_ranges(&self, set: SmSet) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.pd_sms(set).map(|(_, s, e)| (s, e))
    }

    /// (number, start, end) of each enabled process-data SM of `set`, in SM order.
    pub(super) fn pd_sms(&self, set: SmSet) -> impl Iterator<Item = (u8, usize, usize)> + '_ {
        set.iter().filter_map(move |n| {
            if n >= self.cfg.sm_count || !self.sm_enabled(n) {
                return None;
            }
            let b = Self::sm_base(n);
            let start = usize::from(self.get_u16(b));
            let len = usize::from(self.get_u16(b + 2));
            let end = start.checked_add(len)?;
            let writes = (self.byte(b + 4) >> 2) & 0x03 == 0x01;
            (len > 0 && self.pd_sm_in_place(start, end, writes)).then_some((n, start, end))
        })
    }

    /// The run of register space starting at `pos` (before `b`, at most [`REG_SPACE`]) that an
    /// enabled SM on the digital output register covers, or that none does: its end and the
    /// SM. Accesses to the first go through the SM, like RAM; an SM elsewhere in register
    /// space guards nothing (the registers stay registers).
    pub(super) fn next_register_run(&self, pos: usize, b: usize) -> (usize, Option<SmView>) {
        let mut next_start = b;
        let on_register = |s: &&SmView| DIGITAL_OUT.contains(&s.start) && s.end <= DIGITAL_OUT.end;
        for sm in self.sms.iter().filter(on_register) {
            if sm.start <= pos && pos < sm.end {
                return (sm.end.min(b), Some(*sm));
            }
            if sm.start > pos && sm.start < next_start {
                next_start = sm.start;
            }
        }
        (next_start, None)
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
        for n in self.sm_in_pd.iter() {
            set(self, n, matches!(st, AlState::SafeOp | AlState::Op));
        }
        let on = if self.outputs_only_in_op {
            st == AlState::Op
        } else {
            matches!(st, AlState::SafeOp | AlState::Op)
        };
        for n in self.sm_out_pd.iter() {
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

    /// The size of the output image and where in it `sm`'s bytes go, and whether `sm` is the
    /// last output SM (so that its completion completes the image).
    fn output_place(&self, sm: SmView) -> (usize, usize, bool) {
        let (mut total, mut offset, mut last) = (0, 0, true);
        for (n, s, e) in self.pd_sms(self.sm_out_pd) {
            if n < sm.idx {
                offset += e - s;
            } else if n > sm.idx {
                last = false;
            }
            total += e - s;
        }
        (total, offset, last)
    }

    pub(super) fn outputs_completed(&mut self, sm: SmView, hop: Hop) {
        let (total, offset, last) = self.output_place(sm);
        if self.pd.outputs.len() != total {
            self.pd.outputs.resize(total, 0);
        }
        if let (Some(src), Some(dst)) = (
            self.mem.get(sm.start..sm.end),
            self.pd
                .outputs
                .get_mut(offset..offset + (sm.end - sm.start)),
        ) {
            dst.copy_from_slice(src);
        }
        if !last {
            return;
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
                if self.sm_out_pd.contains(n) && new & 0x01 != 0 {
                    let len: usize = self.pd_ranges(self.sm_out_pd).map(|(s, e)| e - s).sum();
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
