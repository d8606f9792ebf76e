//! The bus's side of the cycle: the devices' AL states, the working counter, lost frames, and
//! the way to OP and back.

use super::*;

/// How many cycles the AL status code of a device that left OP is asked for.
const AL_CODE_TRIES: u8 = 20;

impl<L: FrameLink> Cycle<'_, '_, L> {
    /// Device `i` is in AL state `raw`: note it, and a device that left OP on its own.
    pub(super) fn on_al_state(&mut self, i: usize, raw: u8, scan: &mut StateScan) {
        if raw == 0 && scan.missing.is_none() {
            scan.missing = Some(i as u16);
        }
        if raw != 8 {
            scan.every_op = false;
        }
        if let Some(a) = self.axes.iter_mut().find(|a| a.sub == i) {
            a.al_state = raw;
        }
        let Some(prev) = self.al_states.get_mut(i) else {
            return;
        };
        if *prev == raw {
            return;
        }
        let was_op = *prev == 8;
        *prev = raw;
        self.ev.emit(EventKind::AlState {
            device: i as u16,
            state: raw,
        });
        if was_op && raw != 8 && !self.ending() {
            // A device left OP on its own: decode why, stop every axis, end. The code is read
            // within a quarter cycle; a device that does not answer that fast (a loaded host,
            // a slow link) is asked again in the next cycles, and the event waits for it.
            let code = self.al_status_code(i);
            match code {
                Some(_) => self.ev.emit(EventKind::LeftOp {
                    device: i as u16,
                    state: raw,
                    code,
                }),
                None => self.left_op_code = Some((i, raw, 1)),
            }
            if scan.left_op.is_none() {
                scan.left_op = Some(i as u16);
                self.end_reason = Some(CycleEnd::DriveLeftOp {
                    device: i as u16,
                    al_state: raw,
                    code,
                });
            }
        }
    }
    /// A device that left OP and whose AL status code (0x0134) did not come within its
    /// cycle: asked again once per cycle, up to [`AL_CODE_TRIES`] times; then the event goes out
    /// with the code or without it, and the end reason gets it.
    /// `last`: the cycle ends, no more tries.
    pub(super) fn retry_left_op_code(&mut self, last: bool) {
        let Some((i, raw, tries)) = self.left_op_code else {
            return;
        };
        let code = self.al_status_code(i);
        if code.is_none() && tries < AL_CODE_TRIES && !last {
            self.left_op_code = Some((i, raw, tries + 1));
            return;
        }
        self.left_op_code = None;
        self.ev.emit(EventKind::LeftOp {
            device: i as u16,
            state: raw,
            code,
        });
        if let Some(CycleEnd::DriveLeftOp {
            device, code: c, ..
        }) = &mut self.end_reason
            && usize::from(*device) == i
        {
            *c = code;
        }
    }

    /// Device `i`'s AL status code (0x0134), if it answers within a quarter cycle.
    pub(super) fn al_status_code(&mut self, i: usize) -> Option<u16> {
        let addr = self.addresses.get(i).copied().unwrap_or(0);
        let fut = pin!(EcCommand::fprd(addr, register::AL_STATUS_CODE).receive::<u16>(self.md));
        match exec::exchange(self.pump, fut, monotonic_ns() + self.consts.cycle_ns / 4) {
            Ok(Ok(c)) => Some(c),
            _ => None,
        }
    }
    /// After a reply: a device that left OP stops every axis; every device in OP begins steady
    /// state; in OP, the working counter is checked.
    pub(super) fn supervise_bus(&mut self, scan: StateScan, wkc: u16) {
        let (tick, cycle) = (self.clock.tick, self.clock.cycle);
        if let Some(device) = scan.left_op {
            self.ev.emit(EventKind::Stopping {
                reason: StopReason::DriveLeftOp { device },
            });
            self.begin_ending();
            for a in self.axes.iter_mut() {
                a.m.begin_stop(StopKind::Ramp, tick, cycle);
            }
        }
        if !self.all_op() && scan.every_op && !self.al_states.is_empty() {
            self.op = OpState::AllOp;
            if *self.restarting {
                *self.restarting = false;
                *self.restarts += 1;
            }
            self.ev.emit(EventKind::AllOp);
            if self.settings.steady_timing_only && self.window == TimingWindow::NotYet {
                self.window = TimingWindow::OpensNext;
            }
            if let Some(h) = self.hooks {
                h.steady_begin();
                self.steady = true;
            }
        }
        let (expected, datagram) = self.expected_wkc();
        self.counts.last_wkc_expected = expected;
        if self.op == OpState::SafeOp && !self.ending() {
            // SAFE-OP before OP: slave stacks take outputs from SAFE-OP on (ETG.1020), so the
            // working counter must be whole here too: a device whose outputs (or inputs) are
            // not taken is named before OP is requested.
            let c = &mut self.counts;
            if (wkc == expected && datagram.is_none()) || c.safeop_wkc_tolerated {
                c.safeop_wkc_good = c.safeop_wkc_good.saturating_add(1);
                c.safeop_wkc_bad = 0;
            } else {
                c.safeop_wkc_good = 0;
                c.safeop_wkc_bad = c.safeop_wkc_bad.saturating_add(1);
                c.safeop_wkc_last = Some((wkc, expected, datagram));
                c.wkc_wrong_total += 1;
            }
            return;
        }
        if !self.all_op() || self.ending() {
            return;
        }
        if wkc == expected && datagram.is_none() {
            self.counts.wkc_errors = 0;
            return;
        }
        self.counts.wkc_errors += 1;
        self.counts.wkc_wrong_total += 1;
        self.ev.emit(EventKind::WorkingCounter {
            got: wkc,
            expected,
            missing: scan.missing,
            datagram,
        });
        if self.counts.wkc_errors == self.settings.wkc_errors_before_stop {
            self.ev.emit(EventKind::Stopping {
                reason: StopReason::WorkingCounter,
            });
            for a in self.axes.iter_mut() {
                a.m.begin_stop(StopKind::Ramp, tick, cycle);
            }
        }
    }
    /// The working counter the last reply should show, and its first logical datagram that
    /// came back wrong: per datagram from the plan when the reply's datagrams were recorded,
    /// else the whole-image value. No allocation.
    pub(super) fn expected_wkc(&self) -> (u16, Option<DatagramWkc>) {
        let (seen, overflow) = self.pump.logical_seen();
        match &self.wkc_plan {
            Some(plan) if !seen.is_empty() && !overflow => {
                plan.check(seen.iter().map(|d| (d.address, d.len, d.wkc)))
            }
            _ => (self.consts.wkc_whole, None),
        }
    }
    /// No reply this cycle: count it, stop the moving axes after a few, end when the segment
    /// has been silent too long.
    pub(super) fn on_lost(&mut self) -> Option<CycleEnd> {
        let s = self.settings;
        let c = &mut self.counts;
        c.lost_total += 1;
        if self.window.recording() {
            c.recorded_lost += 1;
        }
        c.consecutive_lost += 1;
        let lost = c.consecutive_lost;
        // Each lost cycle up to the stop and the detection; after that the segment counts as
        // lost, and the count comes with `FramesResumed` or `SegmentGone`.
        if lost <= s.lost_before_stop.max(s.segment_lost_after) {
            self.ev.emit(EventKind::FrameLost { consecutive: lost });
        }
        let (tick, cycle) = (self.clock.tick, self.clock.cycle);
        if lost == s.lost_before_stop && !self.ending() {
            self.ev.emit(EventKind::Stopping {
                reason: StopReason::FramesLost { cycles: lost },
            });
            self.stop_moving_axes(tick, cycle);
        }
        if lost == s.segment_lost_after && !self.counts.segment_lost {
            self.counts.segment_lost = true;
            self.ev.emit(EventKind::SegmentLost { cycles: lost });
            self.stop_moving_axes(tick, cycle);
        }
        if u64::from(lost) >= self.consts.segment_gone_cycles {
            self.ev.emit(EventKind::SegmentGone { cycles: lost });
            return Some(CycleEnd::SegmentLost);
        }
        None
    }
    /// OP: request it once the drives have had [`CycleSettings::safeop_cycles`] cycles of
    /// valid outputs with SYNC0 running (by the reference clock's time; or, should it never
    /// answer, after the OP timeout, and the drives decide), each of the last of them with the
    /// whole working counter, then wait for it. A working counter wrong in SAFE-OP for
    /// [`CycleSettings::wkc_errors_before_stop`] cycles in a row ends the start-up, naming the
    /// device whose outputs are not taken.
    pub(super) fn request_op(&mut self) -> Option<CycleEnd> {
        let cycle = self.clock.cycle;
        let synchronised = self.clock.dc_time >= self.consts.op_not_before_dc
            || cycle * self.consts.cycle_ns > self.settings.op_timeout.as_nanos() as u64;
        if self.op == OpState::SafeOp
            && self.counts.safeop_wkc_bad >= self.settings.wkc_errors_before_stop.max(1)
            && let Some((got, expected, datagram)) = self.counts.safeop_wkc_last
        {
            let (lo, hi) = datagram
                .and_then(|d| d.devices)
                .unwrap_or((0, self.addresses.len().saturating_sub(1) as u16));
            let device = (lo..=hi)
                .find(|&p| self.outputs_deactivated(p))
                .unwrap_or(lo);
            let al_state = self
                .al_states
                .get(usize::from(device))
                .copied()
                .unwrap_or(4);
            // An I/O device may enable its outputs in OP only by design (an ESI's OpOnly
            // SyncManager or FMMU): said, and OP requested; a drive must take them.
            let io = self.others.iter().any(|o| o.info.position == device);
            self.ev.emit(EventKind::OutputsNotTaken {
                device,
                got,
                expected,
                datagram,
                io,
            });
            if !io {
                return Some(CycleEnd::OpFailed { device, al_state });
            }
            self.counts.safeop_wkc_tolerated = true;
            self.counts.safeop_wkc_bad = 0;
        }
        match self.op {
            OpState::SafeOp
                if cycle >= u64::from(self.settings.safeop_cycles)
                    && self.counts.safeop_wkc_good >= self.settings.safeop_cycles
                    && synchronised =>
            {
                self.request_al_state(0x0008);
                self.op = OpState::Requested { at: cycle };
            }
            OpState::Requested { at }
                if (cycle - at) * self.consts.cycle_ns
                    > self.settings.op_timeout.as_nanos() as u64 =>
            {
                let (device, al_state) = self
                    .al_states
                    .iter()
                    .enumerate()
                    .find(|(_, s)| **s != 8)
                    .map(|(i, s)| (i as u16, *s))
                    .unwrap_or((0, 0));
                self.ev.emit(EventKind::OpTimeout { device, al_state });
                return Some(CycleEnd::OpFailed { device, al_state });
            }
            _ => {}
        }
        None
    }
    /// Whether the device at `position` has an output SyncManager its PDI keeps deactivated
    /// (0x0807 bit 0 of a buffered SM the master writes, with a length): the device that does
    /// not take its outputs. Read once, when start-up fails on it (not in the steady cycle).
    pub(super) fn outputs_deactivated(&mut self, position: u16) -> bool {
        let Some(&addr) = self.addresses.get(usize::from(position)) else {
            return false;
        };
        let fut = pin!(EcCommand::fprd(addr, 0x0800).receive::<[u8; 64]>(self.md));
        let Ok(Ok(regs)) = exec::exchange(self.pump, fut, monotonic_ns() + self.consts.cycle_ns)
        else {
            return false;
        };
        crate::startup::process_data_sms(&regs).any(|(_, sm)| {
            (sm.control >> 2) & 0x03 == 0x01 && sm.activation & 1 != 0 && sm.pdi_control & 1 != 0
        })
    }
    /// Write `state` to every device's AL control register: one broadcast write, which every
    /// device on the segment must count in its working counter (one round trip, where a write
    /// to each device one after the other took one a device: 64 of them are more than a 1 ms
    /// cycle); should a device not count it, a write to each device, each within half a cycle.
    pub(super) fn request_al_state(&mut self, state: u16) {
        let n = u16::try_from(self.addresses.len()).unwrap_or(u16::MAX);
        let fut = pin!(
            EcCommand::bwr(register::AL_CONTROL)
                .with_wkc(n)
                .send_receive_slice(self.md, state)
        );
        let all = exec::exchange(self.pump, fut, monotonic_ns() + self.consts.cycle_ns / 2);
        if matches!(all, Ok(Ok(_))) {
            return;
        }
        for &addr in &self.addresses {
            let fut = pin!(EcCommand::fpwr(addr, register::AL_CONTROL).send(self.md, state));
            let _ = exec::exchange(self.pump, fut, monotonic_ns() + self.consts.cycle_ns / 2);
        }
    }
    /// Ending and every axis disabled: leave OP while still exchanging process data (drives
    /// in OP with SYNC0 treat missing data as a communication fault): request PRE-OP, and end
    /// once no drive is in OP any more.
    pub(super) fn leave_op(&mut self) -> Option<CycleEnd> {
        let RunPhase::Ending { preop_requested_at } = self.phase else {
            return None;
        };
        // Energised as last seen (on a lost cycle: as of the last reply). A drive below
        // SAFE-OP sends no valid inputs and takes no outputs (its own state machine has
        // disabled it): its last statusword says nothing, so it does not hold the end up.
        let any_energised = self.axes.iter().any(|a| {
            matches!(a.al_state & 0x0F, 4 | 8)
                && a.m.telemetry().state.is_some_and(State::is_energised)
        });
        let stopping = self.axes.iter().any(|a| a.m.braking());
        if any_energised || stopping {
            return None;
        }
        let cycle = self.clock.cycle;
        match preop_requested_at {
            None => {
                self.request_al_state(0x0002);
                self.phase = RunPhase::Ending {
                    preop_requested_at: Some(cycle),
                };
            }
            Some(at) => {
                let out_of_op = self.al_states.iter().all(|s| s & 0x0F != 8);
                if out_of_op || (cycle - at) * self.consts.cycle_ns > 1_000_000_000 {
                    self.retry_left_op_code(true);
                    self.ev.emit(EventKind::Stopped);
                    return Some(self.end_reason.unwrap_or(CycleEnd::Stopped));
                }
            }
        }
        None
    }
}

/// The raw AL state (0x0130 low byte) ethercrab read for a device.
pub(super) fn raw_al_state(st: &SubDeviceState) -> u8 {
    match st {
        SubDeviceState::None => 0,
        SubDeviceState::Init => 1,
        SubDeviceState::PreOp => 2,
        SubDeviceState::Bootstrap => 3,
        SubDeviceState::SafeOp => 4,
        SubDeviceState::Op => 8,
        SubDeviceState::Other(v) => *v,
    }
}

/// What one reply's AL states showed.
pub(super) struct StateScan {
    /// The first device that did not answer.
    pub(super) missing: Option<u16>,
    /// Every device is in OP.
    pub(super) every_op: bool,
    /// The first device that left OP on its own.
    pub(super) left_op: Option<u16>,
}

impl Default for StateScan {
    fn default() -> Self {
        Self {
            missing: None,
            every_op: true,
            left_op: None,
        }
    }
}

/// Decode a drive's raw AL state for messages.
pub fn al_state_name(raw: u8) -> String {
    let s = crate::ec::AlStatus {
        raw: u16::from(raw),
    };
    s.to_string()
}
