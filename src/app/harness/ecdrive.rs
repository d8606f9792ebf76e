//! The ecdrive run: the real master ([`Master`] and its cycle), measured by the cycle's own
//! figures.
//!
//! The master starts as a user would start it (profiles, PDO mapping, DC, OP), with
//! [`CycleSettings::steady_timing_only`](crate::master::cycle::CycleSettings) so that its
//! [`Timing`](crate::master::cycle::Timing) histograms and lost/overrun counts cover steady
//! state only: from the cycle after every drive reached OP to the stop request. Once in OP every
//! axis is enabled and holds its position in csp, so each cycle runs the whole path (exchange,
//! AL/WKC checks, CiA 402 engine, outputs, telemetry). ecdrive's defaults stay on, emergency
//! polling (every 50 ms) among them, although the plain ethercrab loop polls no mailboxes: the
//! figures are those of the master as a user runs it.
//!
//! CPU time: a [`CycleHooks`] implementation samples the cycle thread's CPU clock, its context
//! switches and the process CPU clock on the cycle thread when steady state begins and ends
//! (`steady_begin` / `steady_end`); nothing is read per cycle.

use super::HarnessError;
use super::cpu::{CpuReport, CpuSample, SyscallWindow, apply_syscalls, start_syscalls};
use super::report::{CycleBreakdown, RunHistograms, RunReport};
use crate::cia402::State;
use crate::drives::DriveProfile;
use crate::link::FrameLink;
use crate::master::cycle::CycleHooks;
use crate::master::session::{Master, MasterConfig};
use crate::master::startup::{DriveSetup, Selector};
use crate::master::telemetry::{Axes, Command, StopKind};
use crate::rt::RtSettings;
use crate::rt::audit::AuditError;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// What the ecdrive run needs to know.
#[derive(Debug, Clone)]
pub struct EcdriveSettings {
    /// Cycle time.
    pub cycle: Duration,
    /// Cycles in the measured window.
    pub cycles: u64,
    /// Real-time set-up of the cycle thread.
    pub rt: RtSettings,
    /// The profile of each device, in line order.
    pub profiles: Vec<&'static DriveProfile>,
    /// How long the devices may take to reach OP.
    pub op_timeout: Duration,
    /// Count the cycle thread's syscalls ([`super::cpu::SyscallWindow`]).
    pub count_syscalls: bool,
    /// When the frame is sent after SYNC0.
    pub sync0_shift: Duration,
}

/// CPU samples (and optionally a syscall count) at the edges of steady state, taken on the
/// cycle thread. The mutexes are taken only there and after the run.
#[derive(Default)]
struct SteadyWindow {
    count_syscalls: bool,
    begin: Mutex<Option<CpuSample>>,
    end: Mutex<Option<CpuSample>>,
    syscalls: Mutex<Option<SyscallWindow>>,
    counted: Mutex<Option<Result<u64, AuditError>>>,
    notes: Mutex<Vec<String>>,
}

impl CycleHooks for SteadyWindow {
    fn steady_begin(&self) {
        let s = CpuSample::take(None);
        if let Ok(mut b) = self.begin.lock() {
            *b = Some(s);
        }
        if let (Ok(mut notes), Ok(mut sys)) = (self.notes.lock(), self.syscalls.lock()) {
            *sys = start_syscalls(self.count_syscalls, &mut notes);
        }
    }

    fn steady_end(&self) {
        let counted = self
            .syscalls
            .lock()
            .ok()
            .and_then(|mut w| w.take())
            .map(SyscallWindow::stop);
        let s = CpuSample::take(None);
        if let Ok(mut e) = self.end.lock() {
            *e = Some(s);
        }
        if let Ok(mut c) = self.counted.lock() {
            *c = counted;
        }
    }
}

fn err(what: impl Into<String>, reason: impl ToString) -> HarnessError {
    HarnessError::Run {
        run: "ecdrive",
        what: what.into(),
        reason: reason.to_string(),
    }
}

/// Run ecdrive's master on `link`; returns its report (without drive figures) and the link.
pub fn run<L: FrameLink + Send + 'static>(
    link: L,
    s: &EcdriveSettings,
) -> Result<(RunReport, L), HarnessError> {
    let cycle_ns = s.cycle.as_nanos() as u64;
    let window = Arc::new(SteadyWindow {
        count_syscalls: s.count_syscalls,
        ..SteadyWindow::default()
    });
    let mut cfg = MasterConfig::new(s.cycle);
    cfg.cycle.rt = s.rt.clone();
    cfg.cycle.steady_timing_only = true;
    cfg.cycle.op_timeout = s.op_timeout;
    cfg.startup.dc.shift = Some(s.sync0_shift);
    // The axes hold position: a short stop ramp ends the run without many cycles in OP after
    // the window (the slave-side statistics cover the whole time in OP).
    cfg.cycle.stop_ramp = s.cycle.saturating_mul(10);
    // A stalled machine shows up as missed cycles in the figures, not as an aborted run.
    cfg.cycle.segment_lost_after =
        u32::try_from((1_000_000_000 / cycle_ns.max(1)).max(50)).unwrap_or(u32::MAX);
    let mailbox_poll_ms = cfg
        .emergency_poll
        .map(|d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX));
    cfg.hooks = Some(window.clone());
    for (i, p) in s.profiles.iter().enumerate() {
        cfg.startup.drives.push(DriveSetup {
            profile: Some(*p),
            ..DriveSetup::new(Selector::Position(i as u16))
        });
    }
    let mut m = Master::start(link, cfg).map_err(|f| err("start-up", f.error))?;
    let op = m.wait_until("OP", s.op_timeout + Duration::from_secs(5), |t| {
        t.cycle.all_op
    });
    if let Err(e) = op {
        let _ = m.stop(StopKind::QuickStop);
        return Err(err("waiting for OP", e));
    }
    let c0 = m.telemetry().cycle.cycle;
    let _ = m.command(Command::Enable(Axes::All));
    // Sleep through the window rather than polling, so the harness adds little to the
    // process's CPU time; then wait for the last cycles.
    std::thread::sleep(
        s.cycle
            .saturating_mul(u32::try_from(s.cycles).unwrap_or(u32::MAX)),
    );
    // A cycle that cannot keep the period skips the instants it missed (they count as late),
    // so the cycles may take longer than the window: wait as long again at most, then report
    // what ran rather than nothing.
    let target = c0 + s.cycles + 1;
    let span = s
        .cycle
        .saturating_mul(u32::try_from(s.cycles).unwrap_or(u32::MAX));
    let waited = m.wait_until("the measured cycles", Duration::from_secs(2) + span, |t| {
        t.cycle.cycle >= target
    });
    let reached = m.telemetry().cycle.cycle.saturating_sub(c0);
    let enabled = m
        .telemetry()
        .axes
        .iter()
        .take(s.profiles.len())
        .all(|a| a.state == Some(State::OperationEnabled));
    let (report, link) = m.stop(StopKind::Ramp);
    let short = waited.is_err().then(|| {
        format!(
            "the cycle ran {reached} of the {} cycles asked for in twice the window's time: \
             it could not keep the period (see late)",
            s.cycles
        )
    });
    let report = report.ok_or_else(|| err("running", "the session produced no report"))?;
    let cycle = report
        .cycle
        .ok_or_else(|| err("running", "the cycle produced no report"))?;
    let t = &cycle.timing;
    let h = RunHistograms {
        wake_latency: t.wake_latency.clone(),
        period: t.period.clone(),
        exchange: Some(t.exchange.clone()),
        busy: t.busy.clone(),
    };
    let begin = window.begin.lock().ok().and_then(|b| b.clone());
    let end = window.end.lock().ok().and_then(|e| e.clone());
    let mut notes = window.notes.lock().map(|n| n.clone()).unwrap_or_default();
    let counted = window.counted.lock().ok().and_then(|mut c| c.take());
    let cpu = match (begin, end) {
        (Some(b), Some(e)) => apply_syscalls(
            counted,
            CpuReport::between(&b, &e, t.wake_latency.len()),
            &mut notes,
        ),
        _ => {
            notes.push("the steady-state window did not open and close; no CPU figures".into());
            CpuReport::default()
        }
    };
    if !enabled {
        notes.push("not every axis reached Operation enabled during the window".into());
    }
    if let crate::master::FramesBy::Ethercrab { why } = cycle.frames_by {
        notes.push(format!(
            "the process image went out in ethercrab's frames (tx_rx_dc), not ecdrive's: {why}"
        ));
    }
    notes.extend(short);
    // Errors of the run's history, each text once with how often it came.
    let mut seen: Vec<(String, usize)> = Vec::new();
    for e in report.history.iter().filter(|e| e.error) {
        let text = format!(
            "{}{}",
            e.drive.as_ref().map_or(String::new(), |d| format!("{d}: ")),
            e.text()
        );
        match seen.iter_mut().find(|(t, _)| *t == text) {
            Some((_, n)) => *n += 1,
            None => seen.push((text, 1)),
        }
    }
    for (text, n) in seen.into_iter().take(20) {
        notes.push(if n > 1 {
            format!("{text} (×{n})")
        } else {
            text
        });
    }
    let mut r = h.report(
        "ecdrive",
        cycle_ns,
        cycle.rt.clone(),
        cycle.overruns,
        Some(cycle.lost),
        cpu,
        Vec::new(),
        notes,
    );
    r.structure.mailbox_poll_ms = mailbox_poll_ms;
    r.parts = Some(CycleBreakdown::new(
        t.parts.per_cycle(),
        r.cpu.cycle_thread_ns,
    ));
    Ok((r, link))
}
