//! The cycle's outputs to the rest of the master: the telemetry each cycle, the recording, and
//! the report when the run ends.

use super::*;

impl<L: FrameLink> Cycle<'_, '_, L> {
    /// Publish the telemetry: the cycle, every axis, every I/O device.
    /// One sample per axis into the recording, if there is one (a full ring drops and counts).
    pub(super) fn record_samples(&mut self) {
        let Some(r) = self.record.as_deref_mut() else {
            return;
        };
        let c = &self.clock;
        let (latency, exchange) = (
            u32::try_from(c.latency).unwrap_or(u32::MAX),
            u32::try_from(c.t_ex_done.saturating_sub(c.t_ex)).unwrap_or(u32::MAX),
        );
        for (i, a) in self.axes.iter_mut().enumerate() {
            let judged = a.m.take_fe_judged();
            let t = a.m.telemetry();
            r.push(CycleSample {
                wake_latency_ns: latency,
                exchange_ns: exchange,
                wkc: self.counts.last_wkc,
                ..CycleSample::of_axis(c.cycle, c.woke, i as u16, t, judged)
            });
        }
    }

    pub(super) fn publish(&mut self, good: bool) {
        let c = &self.clock;
        let t = self.telemetry.input_buffer_mut();
        t.cycle = CycleTelemetry {
            cycle: c.cycle,
            dc_time: c.dc_time,
            wkc: self.counts.last_wkc,
            wkc_expected: self.counts.last_wkc_expected,
            lost: self.counts.lost_total,
            overruns: self.counts.overruns,
            wake_latency_ns: c.latency,
            exchange_ns: c.t_ex_done - c.t_ex,
            busy_ns: monotonic_ns() - c.woke,
            all_op: self.op == OpState::AllOp,
            lost_in_a_row: self.counts.consecutive_lost,
            phase: if matches!(self.phase, RunPhase::Ending { .. }) {
                Phase::Stopping
            } else {
                Phase::Cycling
            },
            restarts: *self.restarts,
        };
        self.last_telemetry = t.cycle;
        for (slot, a) in t.axes.iter_mut().zip(self.axes.iter()) {
            *slot = *a.m.telemetry();
        }
        // Every field of every slot each time: the triple buffer hands out three buffers in
        // turn.
        let slots =
            t.io.iter_mut()
                .zip(self.io_last.iter_mut())
                .zip(self.others);
        for ((slot, last), o) in slots {
            let pos = usize::from(o.info.position);
            last.position = o.info.position;
            last.al_state = self.al_states.get(pos).copied().unwrap_or(0);
            if good {
                let inp = self.image.inputs(pos);
                let n = inp.len().min(IO_TELEMETRY_BYTES);
                last.inputs[..n].copy_from_slice(&inp[..n]);
                last.input_len = n as u16;
            }
            *slot = *last;
        }
        self.telemetry.publish();
    }

    /// The run has ended: say so until the session publishes what comes next (a whole
    /// snapshot: the input buffer of the triple buffer holds an older one), and report.
    pub(super) fn finish(mut self, end: CycleEnd, rt: RtReport) -> CycleReport {
        self.batch.flush_all(&mut self.timing);
        self.pump.capture(false);
        if let OwnPath::On(own) = &mut self.own {
            own.give_up();
        }
        // ethercrab's copy of the outputs as the cycle left them, for whatever comes next.
        self.outputs_to_ethercrab();
        self.pump.record_logical(false);
        self.pump.set_drift_compensation(true);
        let t = self.telemetry.input_buffer_mut();
        t.cycle = CycleTelemetry {
            phase: Phase::Stopping,
            ..self.last_telemetry
        };
        for (slot, a) in t.axes.iter_mut().zip(self.axes.iter()) {
            *slot = *a.m.telemetry();
        }
        self.telemetry.publish();
        if let Some(h) = self.hooks
            && self.steady
        {
            h.steady_end();
        }
        let axes = &self.axes;
        CycleReport {
            end,
            cycles: self.clock.cycle,
            lost: self.counts.recorded_lost,
            overruns: self.counts.recorded_overruns,
            timing: self.timing,
            rt,
            first_stop: self.ev.first_stop,
            max_following_error: axes
                .iter()
                .map(|a| a.m.telemetry().max_following_error)
                .collect(),
            max_following_error_drive: axes
                .iter()
                .map(|a| {
                    a.fields
                        .axis
                        .following_error
                        .map(|_| a.m.telemetry().max_following_error_drive)
                })
                .collect(),
            following_error_drive_stuck: axes
                .iter()
                .map(|a| a.m.telemetry().following_error_drive_stuck)
                .collect(),
            modes_run: axes.iter().map(|a| a.m.modes_run().to_vec()).collect(),
            modes_omitted: axes.iter().map(|a| a.m.modes_omitted()).collect(),
            probe_latches: axes.iter().map(|a| a.m.latches().to_vec()).collect(),
            max_setpoint_step: axes.iter().map(|a| a.m.setpoint_steps()).collect(),
            states: axes.iter().map(|a| a.m.states().to_vec()).collect(),
            frames_by: match (&self.own, self.not_learnt) {
                (OwnPath::On(_), _) => FramesBy::Ecdrive,
                (_, Some(why)) => FramesBy::Ethercrab { why },
                _ if self.settings.own_frames => FramesBy::Ethercrab {
                    why: "the run ended before the frames were learnt",
                },
                _ => FramesBy::Ethercrab {
                    why: "the setting asked for ethercrab's",
                },
            },
            frames: {
                let (now, then) = (self.pump.stats(), self.counts.pump_at_start);
                FrameStats {
                    sent: now.sent - then.sent,
                    answered: now.received - then.received,
                    retransmitted: now.retransmitted - then.retransmitted,
                    lost: self.counts.lost_total,
                    late: self.counts.late_total,
                    wrong_wkc: self.counts.wkc_wrong_total,
                    seconds: self.clock.cycle as f64 * self.consts.dt,
                }
            },
        }
    }
}
