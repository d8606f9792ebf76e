//! The AL state machine: AL control, the checks of each transition, AL status and status codes.

use super::*;

impl Esc {
    pub(super) fn dc_status(&self) -> DcSyncStatus {
        let act = self.byte(0x0981);
        DcSyncStatus {
            supported: self.cfg.dc.supported(),
            sync0_active: self.dc.sync.active && act & 0x03 == 0x03,
            sync1_active: self.dc.sync.active && act & 0x04 != 0,
            sync0_cycle_ns: self.get_u32(0x09A0),
            sync1_cycle_ns: self.get_u32(0x09A4),
            sync0_pulses: if self.dc.sync.active {
                self.dc.sync.count
            } else {
                0
            },
        }
    }

    pub(super) fn set_al_status(&mut self, state: AlState, error: Option<AlStatusCode>) {
        self.state = state;
        let v = state as u16 | if error.is_some() { 0x10 } else { 0 };
        self.put_u16(0x0130, v);
        self.put_u16(0x0134, error.map(|c| c.0).unwrap_or(0));
    }

    /// Check the process-data SMs of one direction against the expected size: every enabled
    /// one in three- or one-buffer mode, in the right direction and in place, their lengths
    /// adding up.
    pub(super) fn pd_config_ok(&self, set: SmSet, expected: usize, ecat_writes: bool) -> bool {
        let mut total = 0usize;
        for n in set.iter().filter(|&n| n < self.cfg.sm_count) {
            let b = Self::sm_base(n);
            let len = usize::from(self.get_u16(b + 2));
            if self.byte(b + 6) & 0x01 == 0 || len == 0 {
                continue;
            }
            let start = usize::from(self.get_u16(b));
            let ctl = self.byte(b + 4);
            let dir_ok = (ctl >> 2) & 0x03 == if ecat_writes { 1 } else { 0 };
            // Three-buffer or one-buffer mode (ETG.1000.4: both serve process data).
            let mode_ok = matches!(ctl & 0x03, 0x00 | 0x02);
            if !mode_ok || !dir_ok || !self.pd_sm_in_place(start, start + len, ecat_writes) {
                return false;
            }
            total += len;
        }
        total == expected
    }

    pub(super) fn check_process_data(&self, dev: &dyn Device) -> Result<(), AlStatusCode> {
        let sizes = dev.process_data_sizes();
        if !self.pd_config_ok(self.sm_out_pd, sizes.outputs, true) {
            return Err(AlStatusCode::INVALID_OUTPUT_CONFIG);
        }
        if !self.pd_config_ok(self.sm_in_pd, sizes.inputs, false) {
            return Err(AlStatusCode::INVALID_INPUT_CONFIG);
        }
        Ok(())
    }

    pub(super) fn al_control(&mut self, hop: Hop, dev: &mut dyn Device) {
        let ctl = self.byte(0x0120);
        let ack = ctl & 0x10 != 0;
        let req_bits = ctl & 0x0F;
        let from = self.state;
        let has_error = self.al_error();
        // An error must be acknowledged (or INIT requested) before anything else happens.
        if has_error && !ack && req_bits != AlState::Init as u8 {
            return;
        }
        let Some(to) = AlState::from_bits(req_bits) else {
            let state = if from == AlState::Op {
                self.leave_op();
                AlState::SafeOp
            } else {
                from
            };
            self.finish_transition(from, state, Some(AlStatusCode::UNKNOWN_STATE), dev);
            return;
        };
        use AlState::*;
        let result: Result<AlState, (AlState, AlStatusCode)> = match (from, to) {
            (a, b) if a == b => Ok(a),
            (Init, PreOp) => match self.mbx {
                Some(m) if !self.mailbox_config_ok(&m) => {
                    Err((Init, AlStatusCode::INVALID_MAILBOX_CONFIG))
                }
                _ => self
                    .ask(dev, from, to)
                    .map(|_| PreOp)
                    .map_err(|c| (Init, c)),
            },
            (Init, Bootstrap) => match self.boot_mbx {
                None => Err((Init, AlStatusCode::BOOTSTRAP_NOT_SUPPORTED)),
                Some(m) if !self.mailbox_config_ok(&m) => {
                    Err((Init, AlStatusCode::INVALID_MAILBOX_CONFIG_BOOT))
                }
                Some(_) => self
                    .ask(dev, from, to)
                    .map(|_| Bootstrap)
                    .map_err(|c| (Init, c)),
            },
            (PreOp, SafeOp) => match self.check_process_data(dev) {
                Err(c) => Err((PreOp, c)),
                Ok(()) => self
                    .ask(dev, from, to)
                    .map(|_| SafeOp)
                    .map_err(|c| (PreOp, c)),
            },
            (SafeOp, Op)
                if dev.quirks().has(Quirk::OpNeedsSync0)
                    && self.dc_status().sync0_active
                    && self.dc_status().sync0_pulses == 0 =>
            {
                Err((SafeOp, AlStatusCode::NO_SYNC_ERROR))
            }
            (SafeOp, Op) => self.ask(dev, from, to).map(|_| Op).map_err(|c| (SafeOp, c)),
            (_, Init) => Ok(Init),
            (Op, SafeOp) | (Op, PreOp) | (SafeOp, PreOp) => Ok(to),
            (Op, Bootstrap) => Err((SafeOp, AlStatusCode::INVALID_STATE_CHANGE)),
            (Bootstrap, _) => Err((Bootstrap, AlStatusCode::INVALID_STATE_CHANGE)),
            (s, _) => Err((s, AlStatusCode::INVALID_STATE_CHANGE)),
        };
        let (new_state, error) = match result {
            Ok(s) => (s, None),
            Err((s, c)) => (s, Some(c)),
        };
        // Leave states as needed.
        if from == Op && new_state != Op {
            self.leave_op();
        }
        if matches!(new_state, Init | Bootstrap) && from != new_state {
            self.stop_mailbox(dev);
        }
        if matches!(from, Init | Bootstrap)
            && matches!(new_state, PreOp | Bootstrap)
            && from != new_state
        {
            let layout = if new_state == Bootstrap {
                self.boot_mbx
            } else {
                self.mbx
            };
            self.start_mailbox(layout, dev);
        }
        if new_state == Op && from != Op {
            self.wd_deadline = self.watchdog_ns().map(|w| hop.forward_ns.saturating_add(w));
            self.set_bits(0x0440, 0x01, true);
            self.pending |= pending::DEADLINE;
        }
        self.finish_transition(from, new_state, error, dev);
    }

    pub(super) fn ask(
        &self,
        dev: &mut dyn Device,
        from: AlState,
        to: AlState,
    ) -> Result<(), AlStatusCode> {
        dev.request_state(&StateRequest {
            from,
            to,
            dc: self.dc_status(),
        })
    }

    pub(super) fn leave_op(&mut self) {
        self.wd_deadline = None;
    }

    pub(super) fn finish_transition(
        &mut self,
        from: AlState,
        to: AlState,
        error: Option<AlStatusCode>,
        dev: &mut dyn Device,
    ) {
        self.set_al_status(to, error);
        self.outputs_only_in_op = dev.quirks().has(Quirk::OutputsOnlyInOp);
        self.update_pdi_deactivation();
        if from != to || error.is_some() {
            dev.state_changed(from, to, error);
        }
    }

    /// Drop to a lower state with an error on the slave's own initiative (watchdog, sync
    /// error, SM change).
    pub(super) fn local_error(&mut self, to: AlState, code: AlStatusCode, dev: &mut dyn Device) {
        let from = self.state;
        if from == AlState::Op {
            self.leave_op();
        }
        if matches!(to, AlState::Init) {
            self.stop_mailbox(dev);
        }
        self.finish_transition(from, to, Some(code), dev);
    }

    /// A local restart of the application controller (an injected
    /// [`SlaveFault::ResetToInit`](crate::faults::SlaveFault::ResetToInit)): INIT with the
    /// error bit and AL status code 0x0060 "Slave restarted locally"; the mailbox stops, the
    /// device sees the change as a local error. ESC registers (station address, SyncManager
    /// and FMMU configuration) are kept.
    pub fn local_reset(&mut self, dev: &mut dyn Device) {
        self.local_error(AlState::Init, AlStatusCode::RESTARTED_LOCALLY, dev);
    }
}
