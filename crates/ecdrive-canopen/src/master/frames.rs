//! Frames: sending, pumping the transport, timers, and what arrives (error control, EMCY).

use super::*;

impl<T: CanTransport> Master<T> {
    pub(super) fn send(&mut self, f: &CanFrame) -> Result<(), CanError> {
        self.stats.frames_tx += 1;
        self.t
            .send(f)
            .map_err(|e| CanError::new(NodeRef { id: 0, drive: None }, None, e.into()))
    }

    /// Receive and handle frames until `deadline_us` or until `done` holds; returns whether
    /// `done` held. Timers (heartbeat consumer, guarding) run meanwhile.
    pub(super) fn pump_until(
        &mut self,
        deadline_us: u64,
        done: impl Fn(&Self) -> bool,
    ) -> Result<bool, CanError> {
        loop {
            if done(self) {
                return Ok(true);
            }
            let now = self.t.now_us();
            self.timers(now)?;
            if now >= deadline_us {
                return Ok(done(self));
            }
            // Wake for the next timer (heartbeat deadline, guarding request) at the latest.
            let until = deadline_us.min(self.next_timer_us().unwrap_or(u64::MAX));
            let wait = until.saturating_sub(now).max(1);
            let got = self.t.recv(wait).map_err(|e| {
                CanError::new(
                    NodeRef { id: 0, drive: None },
                    None,
                    CanErrorKind::Transport(e),
                )
            })?;
            if let Some(f) = got {
                self.dispatch(&f);
            }
        }
    }

    /// Receive and handle frames for `us` microseconds.
    pub fn pump(&mut self, us: u64) -> Result<(), CanError> {
        let deadline = self.t.now_us().saturating_add(us);
        self.pump_until(deadline, |_| false).map(|_| ())
    }

    pub(super) fn next_timer_us(&self) -> Option<u64> {
        let mut next: Option<u64> = None;
        for s in &self.nodes {
            if let (Some(t), Some(last), false) = (s.hb_timeout_us, s.last_seen_us, s.hb_lost) {
                let d = last.saturating_add(t).saturating_add(1);
                next = Some(next.map_or(d, |n| n.min(d)));
            }
            if let Some(g) = s.guard
                && !g.lost
            {
                next = Some(next.map_or(g.next_us, |n| n.min(g.next_us)));
            }
        }
        next
    }

    /// Heartbeat deadlines and guarding requests. Allocation-free (it runs every cycle).
    pub(super) fn timers(&mut self, now: u64) -> Result<(), CanError> {
        for id in 0..SLOTS {
            let mut event = None;
            let mut guard_request = false;
            if let Some(s) = self.nodes.get_mut(id) {
                let node = NodeRef {
                    id: id as u8,
                    drive: s.profile.map(|p| p.name),
                };
                if let (Some(t), Some(last)) = (s.hb_timeout_us, s.last_seen_us)
                    && !s.hb_lost
                    && now.saturating_sub(last) > t
                {
                    s.hb_lost = true;
                    event = Some(MasterEvent::HeartbeatLost {
                        node,
                        last_state: s.nmt,
                        silent_us: now.saturating_sub(last),
                    });
                }
                if let Some(g) = &mut s.guard
                    && !g.lost
                    && now >= g.next_us
                {
                    if g.outstanding >= g.life_factor.max(1) {
                        g.lost = true;
                        event = Some(MasterEvent::GuardingLost {
                            node,
                            missed: g.outstanding,
                        });
                    } else {
                        g.outstanding += 1;
                        g.next_us = now.saturating_add(g.period_us.max(1));
                        guard_request = true;
                    }
                }
            }
            if let Some(e) = event {
                self.push_event(e);
            }
            if guard_request {
                self.send(&ErrorControl::guard_request(id as u8))?;
            }
        }
        Ok(())
    }

    pub(super) fn dispatch(&mut self, f: &CanFrame) {
        self.stats.frames_rx += 1;
        let now = self.t.now_us();
        if !f.is_remote()
            && let Some(Some((drive, slot))) = self.tpdo_route.get(usize::from(f.id()))
        {
            let (drive, slot) = (usize::from(*drive), usize::from(*slot));
            if let Some(d) = self.drives.get_mut(drive) {
                d.store_tpdo(slot, f.data(), now);
            }
            return;
        }
        match f.service() {
            Service::ErrorControl(node) if !f.is_remote() => self.on_error_control(node, f, now),
            Service::Emcy(node) if !f.is_remote() => self.on_emcy(node, f, now),
            Service::SdoTx(node) if !f.is_remote() => {
                let data = f.data8();
                if f.data().len() != 8 {
                    self.stats.stray_sdo += 1;
                } else if let Some(r) = &mut self.scan_replies {
                    r.push((node, data));
                } else if self.sdo_wait == Some(node) && self.sdo_reply.is_none() {
                    self.sdo_reply = Some(data);
                } else {
                    self.stats.stray_sdo += 1;
                }
                if let Some(s) = self.slot_mut(node) {
                    s.seen = true;
                    s.last_seen_us = s.last_seen_us.max(Some(now));
                }
            }
            _ => self.stats.unhandled += 1,
        }
    }

    pub(super) fn on_error_control(&mut self, node: u8, f: &CanFrame, now: u64) {
        let Ok(ec) = ErrorControl::parse(f) else {
            self.stats.unhandled += 1;
            return;
        };
        let mut events: [Option<MasterEvent>; 4] = [None; 4];
        let mut n = 0usize;
        let mut push = |e: MasterEvent| {
            if let Some(slot) = events.get_mut(n) {
                *slot = Some(e);
                n += 1;
            }
        };
        let Some(s) = self.nodes.get_mut(usize::from(node)) else {
            return;
        };
        s.seen = true;
        s.last_seen_us = Some(now);
        if s.hb_lost {
            s.hb_lost = false;
            push(MasterEvent::HeartbeatResumed { node });
        }
        let state = if ec.state == NmtState::BootUp {
            s.boot_ups += 1;
            push(MasterEvent::BootUp { node });
            if let Some(g) = &mut s.guard {
                g.toggle = None;
            }
            NmtState::PreOperational
        } else {
            ec.state
        };
        if let Some(g) = &mut s.guard
            && ec.state != NmtState::BootUp
        {
            g.outstanding = 0;
            g.lost = false;
            if g.toggle.is_some_and(|t| t == ec.toggle) {
                push(MasterEvent::GuardingToggle { node });
            }
            g.toggle = Some(ec.toggle);
        }
        if s.nmt != Some(state) {
            push(MasterEvent::StateChanged {
                node,
                from: s.nmt,
                to: state,
            });
            s.nmt = Some(state);
        }
        for e in events.into_iter().flatten() {
            self.push_event(e);
        }
    }

    pub(super) fn on_emcy(&mut self, node: u8, f: &CanFrame, now: u64) {
        let Ok(e) = Emergency::parse(f.data()) else {
            self.stats.unhandled += 1;
            return;
        };
        let cap = self.cfg.emcy_log.max(1);
        let Some(s) = self.nodes.get_mut(usize::from(node)) else {
            return;
        };
        s.seen = true;
        let rec = EmergencyRecord {
            node,
            drive: s.profile.map(|p| p.name),
            time_us: now,
            emergency: e,
            decoded: s.profile.map(|p| p.decode_emcy(&e)),
        };
        if s.emcy.len() >= cap {
            s.emcy.pop_front();
        }
        s.emcy.push_back(rec);
        self.push_event(MasterEvent::Emergency(rec));
    }
}
