//! Distributed clocks as seen by the registers: writes to the DC unit, receive-time latches, SYNC0/SYNC1 start and delivery, the watchdog, drift.

use super::*;

impl Esc {
    pub(super) fn dc_written(
        &mut self,
        a: usize,
        b: usize,
        data: &[u8],
        old_sys: Option<u64>,
        old_activation: u8,
        hop: Hop,
    ) {
        if overlaps(a, b, 0x0900, 0x0904) {
            self.latch_receive_times(hop);
        }
        if let Some(own) = old_sys {
            if overlaps(a, b, 0x0910, 0x0918) {
                // Merge the written bytes over the own time to get the received value; compare
                // in the width that was written.
                let mut v = own.to_le_bytes();
                let mut hi_byte = 0usize;
                for (i, &d) in data.iter().enumerate() {
                    let at = a + i;
                    if (0x0910..0x0918).contains(&at) {
                        if let Some(x) = v.get_mut(at - 0x0910) {
                            *x = d;
                        }
                        hi_byte = hi_byte.max(at - 0x0910 + 1);
                    }
                }
                let received = u64::from_le_bytes(v);
                let delay = u64::from(self.get_u32(0x0928));
                let own_cmp = own.wrapping_sub(delay);
                let e = if hi_byte <= 4 {
                    i64::from((own_cmp as u32).wrapping_sub(received as u32) as i32)
                } else {
                    own_cmp.wrapping_sub(received) as i64
                };
                let depth = self.byte(0x0934);
                let f = self.dc.loop_input(hop.forward_ns, e, depth);
                self.put_u32(0x092C, DcUnit::encode_difference(f));
                if self.state == AlState::Op
                    && let Some(t) = self.timing.as_deref_mut()
                {
                    t.record_dc_difference(f);
                }
            }
        }
        if overlaps(a, b, 0x0930, 0x0932) || overlaps(a, b, 0x0934, 0x0936) {
            self.dc.reset_loop();
            self.put_u32(0x092C, 0);
        }
        if overlaps(a, b, 0x0981, 0x0982) {
            let new = self.byte(0x0981);
            let was = old_activation & 0x03 == 0x03;
            let now_on = new & 0x03 == 0x03;
            if now_on && !was {
                self.start_sync(hop);
            } else if !now_on {
                self.dc.sync.active = false;
                self.put(0x0984, &[0]);
            }
        }
    }

    pub(super) fn latch_receive_times(&mut self, hop: Hop) {
        let p0 = self.local_time(hop.forward_ns);
        self.put_u32(0x0900, p0 as u32);
        if let Some(r) = hop.return_ns {
            let p1 = self.local_time(r);
            self.put_u32(0x0904, p1 as u32);
        }
        self.put_u64(0x0918, p0);
    }

    /// The Sync Out Unit is activated (0x0981 bits 0 and 1 set): when its first pulse comes,
    /// as the ESC datasheet (section II, 0x0981, 0x0984, 0x0990) has it. The start time is
    /// compared with the system time in the DC unit's width (32 or 64 bits):
    /// - within the near future (0x0981 bit 6 = 0: half the width, 2^31 or 2^63 ns ahead;
    ///   bit 6 = 1: about 2.1 s, 2^31 ns): the first pulse at the start time;
    /// - outside it, with the start-time plausibility check on (bit 5): a pulse at once;
    /// - outside it without the check (what ethercrab, SOEM and KickCAT write, 0x03): "SyncSignal
    ///   generation if Start Time is reached": a start time already past is reached again only
    ///   when the system time wraps, after about 4.3 s with 32 bits and never with 64. The first
    ///   pulse stays pending (0x0984 bit 0) and 0x0990 reads the start time until the master
    ///   deactivates the unit and writes a new one.
    ///
    /// 0x0984 bit 2 holds the check's result (the start time was outside the near future).
    pub(super) fn start_sync(&mut self, hop: Hop) {
        let flags = self.byte(0x0981);
        let start = self.get_u64(0x0990);
        let cycle = self.get_u32(0x09A0);
        let now = self.system_time(hop.forward_ns);
        let bits64 = matches!(self.cfg.dc, DcSupport::Bits64);
        // How far ahead the start time is, in the unit's width (a past one is far ahead).
        let ahead = if bits64 {
            start.wrapping_sub(now)
        } else {
            u64::from((start as u32).wrapping_sub(now as u32))
        };
        let near = if flags & 0x40 != 0 || !bits64 {
            1u64 << 31
        } else {
            1u64 << 63
        };
        let near_future = ahead > 0 && ahead < near;
        let mut status = 0x01; // the first SYNC0 pulse is pending
        if !near_future {
            status |= 0x04;
        }
        let (next, waiting) = if near_future {
            (now + ahead, false)
        } else if flags & 0x20 != 0 {
            (now, false)
        } else if bits64 {
            (start, true)
        } else {
            (now.saturating_add(ahead), false)
        };
        self.dc.sync = SyncGen {
            active: true,
            next,
            cycle,
            count: 0,
            waiting,
        };
        self.pending |= pending::DEADLINE;
        self.put(0x0984, &[status]);
    }

    pub(super) fn watchdog_ns(&self) -> Option<u64> {
        let t = u64::from(self.get_u16(0x0420));
        if t == 0 {
            return None;
        }
        let unit = (u64::from(self.get_u16(0x0400)) + 2) * 40;
        Some(t * unit)
    }

    /// Change the local clock's drift against the host clock from host time `host_ns` on (an
    /// injected [`SlaveFault::ClockDrift`](crate::faults::SlaveFault::ClockDrift)). The
    /// local time does not jump; a later ESC reset keeps the new drift (it is the oscillator's).
    pub fn set_clock_drift(&mut self, host_ns: u64, drift_ppb: i64) {
        self.dc.set_drift(host_ns, drift_ppb);
        self.cfg.clock_drift_ppb = drift_ppb;
        self.cfg.clock_offset_ns = self.dc.offset_ns;
    }

    /// Host time at which [`run_due`](Self::run_due) has something to do (next SYNC0 pulse or
    /// watchdog expiry), conservatively early.
    pub fn next_deadline(&self, host_now: u64) -> Option<u64> {
        let mut d = self.wd_deadline;
        if self.dc.sync.active && !self.dc.sync.waiting {
            let sys_now = self.system_time(host_now);
            let ahead = self.dc.sync.next.saturating_sub(sys_now);
            // System time may run up to 0.2 % faster than the host clock (drift + loop); aim
            // early by that much plus a microsecond.
            let margin = ahead / 500 + 1_000;
            let t = host_now.saturating_add(ahead.saturating_sub(margin));
            d = Some(d.map_or(t, |x| x.min(t)));
        }
        d
    }

    /// Deliver every SYNC0 pulse that has passed by host time `host_ns`, in order, and apply
    /// an expired SM watchdog.
    pub fn run_due(&mut self, host_ns: u64, dev: &mut dyn Device) {
        if self.dc.sync.active {
            let now = self.system_time(host_ns);
            let mut guard = 0u32;
            while self.dc.sync.active && !self.dc.sync.waiting && self.dc.sync.next <= now {
                let t = self.dc.sync.next;
                let cycle = self.dc.sync.cycle;
                self.put(0x098E, &[0x01]);
                self.set_bits(0x0984, 0x01, false);
                let count = self.dc.sync.count;
                self.deliver_sync(SyncKind::Sync0, t, cycle, dev);
                self.dc.sync.count = count + 1;
                if cycle == 0 {
                    self.dc.sync.active = false;
                } else {
                    self.dc.sync.next = t.saturating_add(u64::from(cycle));
                }
                guard += 1;
                if guard >= 10_000_000 {
                    // More than ten million missed pulses (hours of a fast cycle): skip
                    // ahead instead of spinning.
                    let c = u64::from(cycle.max(1));
                    let k = (now - self.dc.sync.next) / c + 1;
                    self.dc.sync.next = self.dc.sync.next.saturating_add(k * c);
                    self.dc.sync.count = self.dc.sync.count.saturating_add(k);
                    break;
                }
            }
        }
        if let Some(d) = self.wd_deadline {
            if host_ns >= d {
                self.wd_deadline = None;
                self.set_bits(0x0440, 0x01, false);
                if let Some(c) = self.mem.get_mut(0x0442) {
                    *c = c.saturating_add(1);
                }
                // The firmware watches the process-data watchdog only where the outputs'
                // SyncManager triggers it (control byte bit 6; Beckhoff's slave stack code
                // monitors it only then): a device whose ESI leaves the bit off (ControlByte
                // 0x24) runs without it, as the hardware counter still shows.
                let triggered = self
                    .sm_out_pd
                    .iter()
                    .any(|n| self.byte(Self::sm_base(n) + 4) & 0x40 != 0);
                if self.state == AlState::Op && triggered {
                    self.local_error(AlState::SafeOp, AlStatusCode::SM_WATCHDOG, dev);
                }
            }
        }
    }

    pub(super) fn deliver_sync(
        &mut self,
        kind: SyncKind,
        t: u64,
        cycle_time: u32,
        dev: &mut dyn Device,
    ) {
        let cycle = match kind {
            SyncKind::Sync0 => self.dc.sync.count,
            SyncKind::Frame => {
                let c = self.pd.frame_cycles;
                self.pd.frame_cycles += 1;
                c
            }
        };
        if kind == SyncKind::Sync0
            && self.state == AlState::Op
            && let Some(stats) = self.timing.as_deref_mut()
        {
            stats.sync0_pulses += 1;
            if self.pd.outputs_received == 0 {
                stats.sync0_without_outputs += 1;
            }
        }
        let quirks = dev.quirks();
        let ev = SyncEvent {
            kind,
            time_ns: t,
            cycle,
            cycle_time_ns: cycle_time,
            state: self.state,
            outputs_received: core::mem::take(&mut self.pd.outputs_received),
            last_outputs_ns: self.pd.last_outputs_ns,
            outputs_enabled: self.state == AlState::Op
                || (self.state == AlState::SafeOp && quirks.has(Quirk::OutputsInSafeOp)),
        };
        let (mut ranges, mut len) = (0usize, 0usize);
        let mut single = None;
        for (s, e) in self.pd_ranges(self.sm_in_pd) {
            ranges += 1;
            len += e - s;
            single = Some((s, e));
        }
        let outputs = core::mem::take(&mut self.pd.outputs);
        let r = if self.state != AlState::Op && quirks.has(Quirk::StaleInputsUntilOp) {
            // The device runs, but its inputs do not reach the image before OP.
            let mut scratch = core::mem::take(&mut self.pd.scratch);
            if scratch.len() < len {
                // Sized once, at the first cycle below OP.
                scratch.resize(len, 0);
            }
            let r = dev.sync(&ev, &outputs, scratch.get_mut(..len).unwrap_or(&mut []));
            self.pd.scratch = scratch;
            r
        } else if ranges > 1 {
            // Several input SMs: the device writes one image, scattered into them.
            let mut image = core::mem::take(&mut self.pd.in_image);
            if image.len() != len {
                // Sized once, when the SMs are set up.
                image.resize(len, 0);
            }
            let r = dev.sync(&ev, &outputs, &mut image);
            let mut runs = [(0usize, 0usize); MAX_SM];
            for (run, r) in runs.iter_mut().zip(self.pd_ranges(self.sm_in_pd)) {
                *run = r;
            }
            let mut at = 0;
            for &(s, e) in runs.iter().take(ranges) {
                if let (Some(dst), Some(src)) = (self.mem.get_mut(s..e), image.get(at..at + e - s))
                {
                    dst.copy_from_slice(src);
                }
                at += e - s;
            }
            self.pd.in_image = image;
            r
        } else {
            let inputs: &mut [u8] = match single {
                Some((s, e)) => self.mem.get_mut(s..e).unwrap_or(&mut []),
                None => &mut [],
            };
            dev.sync(&ev, &outputs, inputs)
        };
        self.pd.outputs = outputs;
        if self.mailbox.running {
            // The application may have queued a mailbox message.
            self.pending |= pending::MBX_POLL;
        }
        if let Err(code) = r {
            if self.state == AlState::Op {
                self.local_error(AlState::SafeOp, code, dev);
            }
        }
    }
}
