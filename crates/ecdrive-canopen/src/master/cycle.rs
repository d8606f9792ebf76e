//! The cycle: SYNC, PDOs, the axes, enable, disable, mode switches, shutdown.

use super::*;

impl<T: CanTransport> Master<T> {
    /// One communication cycle: send every drive's RPDOs (the outputs of its last
    /// [`CanDrive::step`]) to Operational nodes, then SYNC, then receive until the next cycle
    /// starts (the TPDOs answering the SYNC arrive meanwhile). Finally checks each drive's
    /// remote bit.
    pub fn cycle(&mut self) -> Result<(), CanError> {
        let now = self.t.now_us();
        let start = match self.next_cycle_us {
            Some(t) if t >= now => {
                self.pump_until(t, |_| false)?;
                t
            }
            _ => now,
        };
        for i in 0..self.drives.len() {
            let sent_at = self.t.now_us();
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            let node = d.node();
            if d.last_output().is_none() || self.nmt_state(node) != Some(NmtState::Operational) {
                continue;
            }
            // Outputs no RPDO of the drive can carry (6060h not mappable, fixed RPDOs or none,
            // as its EDS file says) go by SDO when they change, before the RPDOs.
            while let Some((k, addr, bytes, len)) =
                self.drives.get(i).and_then(CanDrive::next_sdo_output)
            {
                self.sdo_download(node, addr, bytes.get(..len).unwrap_or(&[]))?;
                if let Some(d) = self.drives.get_mut(i) {
                    d.sdo_output_written(k, bytes);
                }
            }
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            // RPDOs no closer than the drive takes them (ASDA-A2: two on one COB-ID within
            // 1 ms raise AL112): a cycle whose frames went out late keeps its place in the
            // schedule, so the next may come sooner; then this cycle's wait for the next
            // (the drive keeps the last values, as on a lost frame).
            let min = u64::from(d.profile().comm.rpdo_min_interval_us);
            if min > 0
                && d.rpdo_sent_us()
                    .is_some_and(|t| sent_at.saturating_sub(t) < min)
            {
                self.stats.rpdos_deferred += 1;
                continue;
            }
            for k in 0..d.rpdos().len() {
                let frame = self
                    .drives
                    .get(i)
                    .and_then(|d| d.rpdo_bytes(k))
                    .and_then(|(c, b)| CanFrame::new(c, b).ok());
                if let Some(f) = frame {
                    self.send(&f)?;
                }
            }
            // When the last of them went out: the next may not come before this plus the gap.
            let done = self.t.now_us();
            if let Some(d) = self.drives.get_mut(i) {
                d.set_rpdo_sent_us(done);
            }
        }
        if self.cfg.sync_producer {
            self.send(&CanFrame::from_parts(cob::SYNC, [0; 8], 0))?;
            self.stats.syncs += 1;
        }
        // Inputs no TPDO of the drive can carry: read by SDO, after the SYNC.
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            let node = d.node();
            if d.sdo_inputs().is_empty() || self.nmt_state(node) != Some(NmtState::Operational) {
                continue;
            }
            for k in 0..d.sdo_inputs().len() {
                let Some(addr) = self
                    .drives
                    .get(i)
                    .and_then(|d| d.sdo_inputs().get(k).map(|(a, _)| *a))
                else {
                    continue;
                };
                let v = self.sdo_upload(node, addr)?;
                if let Some(d) = self.drives.get_mut(i) {
                    d.store_sdo_input(k, &v);
                }
            }
        }
        let next = start.saturating_add(self.cfg.cycle_us.max(1));
        self.next_cycle_us = Some(next);
        self.pump_until(next, |_| false)?;
        self.stats.cycles += 1;
        self.check_remote();
        Ok(())
    }

    /// Remote-bit events. Allocation-free (it runs every cycle).
    pub(super) fn check_remote(&mut self) {
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            if !d.profile().enable.remote_required || !d.has_feedback() {
                continue;
            }
            let node = d.node();
            // The axis wants the drive enabled: the drive's own engine (enable, the demo) or
            // the outputs sent (a motion session steps another engine): enable voltage set.
            let wants = d.axis().status().target == Target::OperationEnabled
                || d.last_output()
                    .is_some_and(|o| o.controlword.raw() & 0x0002 != 0);
            let off = !d.statusword().contains(StatusWord::REMOTE);
            let was = self.slot(node).is_some_and(|s| s.remote_off);
            let event = if off && wants && !was {
                Some(MasterEvent::RemoteOff {
                    node: self.node_ref(node),
                })
            } else if !off && was {
                Some(MasterEvent::RemoteOn { node })
            } else {
                None
            };
            if let Some(e) = event {
                if let Some(s) = self.slot_mut(node) {
                    s.remote_off = off;
                }
                self.push_event(e);
            }
        }
    }

    /// Whether `node`'s drive ignores the controlword because bit 9 is 0 (profiles that need it).
    pub fn remote_off(&self, node: u8) -> bool {
        self.slot(node).is_some_and(|s| s.remote_off)
    }

    /// One cycle ([`Master::cycle`]), then for each drive: `hook` (profile-mode helpers,
    /// set-points) and [`CanDrive::step`].
    pub fn cycle_step(&mut self, mut hook: impl FnMut(&mut CanDrive)) -> Result<(), CanError> {
        self.cycle()?;
        for d in &mut self.drives {
            hook(d);
            d.step();
        }
        Ok(())
    }

    pub(super) fn run_axis_until(
        &mut self,
        node: u8,
        timeout_us: u64,
        what: &str,
        done: impl Fn(&CanDrive) -> bool,
        remote_matters: bool,
    ) -> Result<(), CanError> {
        let deadline = self.t.now_us().saturating_add(timeout_us);
        let mut cycles = 0u32;
        loop {
            self.cycle_step(|_| {})?;
            cycles = cycles.saturating_add(1);
            let Some(d) = self.drive_mut(node) else {
                return Err(self.err(
                    node,
                    None,
                    CanErrorKind::NotReady("not a configured drive".into()),
                ));
            };
            let mut failure = None;
            while let Some(e) = d.axis_mut().poll_event() {
                match e {
                    Event::PlannerFailed(p) => failure = Some(p.to_string()),
                    Event::Fault { error, .. } => {
                        failure = Some(match error {
                            Some(e) => format!("the drive faulted: {e}"),
                            None => "the drive faulted".to_string(),
                        })
                    }
                    _ => {}
                }
            }
            if done(d) {
                return Ok(());
            }
            // A statusword older than the request may still show the old remote bit.
            if remote_matters && cycles > REMOTE_GRACE_CYCLES && self.remote_off(node) {
                return Err(self.err(node, None, CanErrorKind::RemoteOff));
            }
            if let Some(f) = failure {
                return Err(self.err(node, None, CanErrorKind::Timeout(format!("{what}: {f}"))));
            }
            if self.t.now_us() >= deadline {
                let st = self.drive(node).map(|d| d.axis().status());
                return Err(self.err(
                    node,
                    None,
                    CanErrorKind::Timeout(format!(
                        "{what}: not done within {} ms (phase {}, statusword 0x{:04X})",
                        timeout_us / 1000,
                        st.map(|s| s.phase.to_string()).unwrap_or_default(),
                        st.map(|s| s.statusword.raw()).unwrap_or(0)
                    )),
                ));
            }
        }
    }

    /// Enable `node`'s drive: run cycles until Operation enabled. Like [`Master::disable`] and
    /// [`Master::switch_mode`] it consumes the axis' events (older ones are discarded first).
    /// Fails at once with
    /// [`CanErrorKind::RemoteOff`] if the drive needs the remote bit and it is 0, and on a
    /// fault or planner failure.
    pub fn enable(&mut self, node: u8, timeout_us: u64) -> Result<(), CanError> {
        let missing = self.err(
            node,
            None,
            CanErrorKind::NotReady("not a configured drive".into()),
        );
        let d = self.drive_mut(node).ok_or(missing)?;
        while d.axis_mut().poll_event().is_some() {}
        d.axis_mut().request_enable().map_err(|e| {
            CanError::new(
                NodeRef {
                    id: node,
                    drive: Some(d.profile().name),
                },
                None,
                CanErrorKind::Axis(e),
            )
        })?;
        self.run_axis_until(
            node,
            timeout_us,
            "enable",
            |d| d.axis().status().phase == Phase::Enabled && d.axis().status().streaming,
            true,
        )
    }

    /// Disable `node`'s drive: run cycles until Switch on disabled.
    pub fn disable(&mut self, node: u8, timeout_us: u64) -> Result<(), CanError> {
        let missing = self.err(
            node,
            None,
            CanErrorKind::NotReady("not a configured drive".into()),
        );
        let d = self.drive_mut(node).ok_or(missing)?;
        while d.axis_mut().poll_event().is_some() {}
        d.axis_mut().request_disable();
        self.run_axis_until(
            node,
            timeout_us,
            "disable",
            |d| {
                let s = d.axis().status();
                s.phase == Phase::Disabled || s.state.is_some_and(|st| !st.is_energised())
            },
            false,
        )
    }

    /// Switch to `mode` and run cycles until 0x6061 confirms it.
    pub fn switch_mode(
        &mut self,
        node: u8,
        mode: OperationMode,
        timeout_us: u64,
    ) -> Result<(), CanError> {
        let missing = self.err(
            node,
            None,
            CanErrorKind::NotReady("not a configured drive".into()),
        );
        let d = self.drive_mut(node).ok_or(missing)?;
        while d.axis_mut().poll_event().is_some() {}
        d.axis_mut().request_mode(mode).map_err(|e| {
            CanError::new(
                NodeRef {
                    id: node,
                    drive: Some(d.profile().name),
                },
                None,
                CanErrorKind::Axis(e),
            )
        })?;
        self.run_axis_until(
            node,
            timeout_us,
            "mode switch",
            move |d| {
                let s = d.axis().status();
                s.active_mode == mode && s.mode_switch == crate::cia402::ModeSwitchPhase::Idle
            },
            false,
        )
    }

    /// Take `node` off the bus safely: disable its drive through the controlword (if it is a
    /// configured drive), then NMT Stop.
    pub fn shutdown_node(&mut self, node: u8, timeout_us: u64) -> Result<(), CanError> {
        if self.drive(node).is_some() {
            self.disable(node, timeout_us)?;
        }
        self.nmt(node, NmtCommand::Stop)
    }
}
