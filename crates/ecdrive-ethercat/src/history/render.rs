//! The history in words: what [`super::HistoryEntry::text`] says of each event. Only here; the
//! session records typed events and the command line, the JSON and applications put them in
//! words through this.

use super::{HistoryEvent, Resolved, RestartNote};
use crate::cia402;
use crate::cycle::al_state_name;
use crate::error::DriveRef;
use crate::telemetry::{EventKind, StopReason};
use crate::wkc::DatagramWkc;

/// The words of `event`.
pub(super) fn text(event: &HistoryEvent, r: &Resolved) -> String {
    match event {
        HistoryEvent::Cycle(e) => cycle_text(e, r),
        HistoryEvent::Emergency {
            error_code,
            error_register,
        } => {
            let d = r.fault.map_or_else(
                || cia402::ErrorCode(*error_code).describe(&[]).to_string(),
                |d| d.to_string(),
            );
            format!("emergency: {d} (error register 0x{error_register:02X})")
        }
        HistoryEvent::Warning(w) => format!("warning: {w}"),
        HistoryEvent::Restart(n) => restart_text(n),
        HistoryEvent::NoCycle { command } => {
            format!("{command} refused: no cycle runs (waiting for a re-start)")
        }
        HistoryEvent::CycleThreadFailed(e) => format!("cannot start the cycle thread: {e}"),
    }
}

fn restart_text(n: &RestartNote) -> String {
    match n {
        RestartNote::Requested => "re-starting the drives on request".into(),
        RestartNote::WaitingForRequest => "waiting for a re-start request (Master::restart)".into(),
        RestartNote::Automatic { retry_every_ms } => {
            format!("re-starting automatically, trying every {retry_every_ms} ms")
        }
        RestartNote::AttemptFailed { attempt, error } => {
            format!("re-start attempt {attempt} failed: {error}")
        }
        RestartNote::GivingUp { failures } => format!(
            "giving up automatic re-starts after {failures} failed attempts; waiting for a \
             re-start request"
        ),
        RestartNote::SameDrives { drives } => format!(
            "re-start: the segment answers with the same {drives} drive(s); taking them to OP"
        ),
        RestartNote::BackInOp { restart } => {
            format!("re-start {restart}: every drive is back in OP")
        }
    }
}

/// The drives, named, for the events that concern every one.
fn all_drives(r: &Resolved) -> String {
    r.drives
        .iter()
        .map(DriveRef::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A position in the axis's units where it has them ("1.3000 rev (109051904 counts)"), else
/// in counts.
fn in_units(r: &Resolved, counts: i64) -> String {
    match &r.units {
        Some(u) => format!(
            "{:.4} {} ({counts} counts)",
            counts as f64 / u.counts_per_unit,
            u.name
        ),
        None => format!("{counts} counts"),
    }
}

fn cycle_text(e: &EventKind, r: &Resolved) -> String {
    match *e {
        EventKind::AllOp => "every drive is in OP".to_string(),
        EventKind::OpTimeout { al_state, .. } => {
            format!("did not reach OP (AL status {})", al_state_name(al_state))
        }
        EventKind::Axis { event, .. } => axis_text(event, r),
        EventKind::WorkingCounter { .. } | EventKind::OutputsNotTaken { .. } => wkc_text(e),
        EventKind::AlState { state, .. } => format!("AL state {}", al_state_name(state)),
        EventKind::FrameLost { consecutive } => format!(
            "no reply in this cycle ({consecutive} in a row); {} held their set-points",
            all_drives(r)
        ),
        EventKind::SegmentGone { cycles } => format!(
            "the segment stayed silent for {cycles} cycles: the cycle ends; {} are disabled by \
             their own watchdogs; a re-start brings them back",
            all_drives(r)
        ),
        EventKind::LeftOp { state, code, .. } => format!(
            "left OP on its own: AL status {}, AL status code {}",
            al_state_name(state),
            code.map_or("unreadable".to_string(), |c| {
                crate::ec::AlStatusCode(c).to_string()
            })
        ),
        EventKind::FramesResumed { lost } => {
            format!("replies resumed after {lost} lost cycle(s)")
        }
        EventKind::SegmentLost { cycles } => format!(
            "the segment stopped answering ({cycles} cycles without a reply); drives: {}",
            all_drives(r)
        ),
        EventKind::DriveFollowingErrorStuck { cycles, master, .. } => format!(
            "warning: 0x60F4 stayed 0 over {cycles} cycles of motion while the master's own \
             following error reached {master}: the drive's value is not trusted (the master's \
             is shown and checked against the limit)"
        ),
        EventKind::FollowingError { value, limit, .. } => match &r.units {
            Some(u) => format!(
                "master-side following error {:.4} {n} ({value} counts) exceeds the limit of \
                 {:.4} {n} ({limit} counts)",
                value as f64 / u.counts_per_unit,
                f64::from(limit) / u.counts_per_unit,
                n = u.name
            ),
            None => format!(
                "master-side following error {value} counts exceeds the limit of {limit} counts"
            ),
        },
        EventKind::ProgramStep { step, .. } => format!("program step {step}"),
        EventKind::ProgramDone { .. } => "program done".into(),
        EventKind::CommandRefused { why, .. } => why.to_string(),
        EventKind::HomingFailed { .. } | EventKind::ProbeNotLatched { .. } => {
            crate::telemetry::event_text(e)
        }
        EventKind::ProbeLatched {
            probe,
            edge,
            position,
            ..
        } => format!(
            "touch probe {probe} latched on the {} edge at {}",
            edge.name(),
            in_units(r, position)
        ),
        EventKind::SetpointLimit {
            limit, value, max, ..
        } => format!(
            "the application's set-point breaks {limit}: {value:.1} > {max:.1} (drive units); \
             the axis is stopped"
        ),
        EventKind::StreamUnderrun { total, .. } => format!(
            "set-point stream ran empty: the last set-point is held ({total} cycle(s) without a \
             new one so far)"
        ),
        EventKind::Stopping { reason } => format!(
            "stopping the axes in a controlled way: {}",
            stop_reason(reason, r)
        ),
        EventKind::Stopped => "every axis disabled; cycle ended".into(),
    }
}

/// An engine event of an axis in words; a fault in the drive's own words where its alarm table
/// has them ([`Resolved::fault`]).
fn axis_text(event: cia402::Event, r: &Resolved) -> String {
    let state_name = |s: Option<cia402::State>| s.map_or("?".into(), |s| s.to_string());
    match event {
        cia402::Event::Fault { state, error } => match r.fault.or(error) {
            Some(d) => format!("fault ({}): {d}", state_name(state)),
            None => format!("fault ({})", state_name(state)),
        },
        cia402::Event::PlannerFailed(p) => format!("state machine: {p}"),
        cia402::Event::ModeSwitchFailed(m) => format!("mode switch failed: {m}"),
        cia402::Event::StateChanged { from, to } => {
            let name =
                |s: Option<cia402::State>| s.map_or("(no state)".to_string(), |s| s.to_string());
            format!("state {} → {}", name(from), name(to))
        }
        cia402::Event::TargetReached(t) => format!("reached {t}"),
        cia402::Event::FaultCleared => "fault cleared".into(),
        cia402::Event::WarningChanged(w) => {
            if w { "warning set" } else { "warning cleared" }.into()
        }
        cia402::Event::ModeSwitched { from, to } => format!("mode {from} → {to}"),
        cia402::Event::ModeDisplayMismatch {
            expected,
            displayed,
        } => format!("0x6061 shows {displayed} instead of {expected}; set-points paused"),
    }
}

/// Why the axes were stopped, in words; the drive or device named is [`Resolved::subject`].
fn stop_reason(reason: StopReason, r: &Resolved) -> String {
    let axis = |axis: u16| {
        r.subject
            .as_ref()
            .map_or_else(|| format!("axis {axis}"), DriveRef::to_string)
    };
    match reason {
        StopReason::Requested => "requested".to_string(),
        StopReason::Restart => "re-start requested".to_string(),
        StopReason::DriveFault { axis: a } => format!("{} faulted", axis(a)),
        StopReason::FollowingError { axis: a } => format!("following error of {}", axis(a)),
        StopReason::FramesLost { cycles } => format!("{cycles} cycles in a row without a reply"),
        StopReason::DriveLeftOp { device } => format!(
            "{} left OP",
            r.subject
                .as_ref()
                .map_or_else(|| format!("device {device}"), DriveRef::to_string)
        ),
        StopReason::WorkingCounter => "the working counter stayed wrong".to_string(),
        StopReason::HomingFailed { axis: a } => format!("homing of {} failed", axis(a)),
        StopReason::ProbeNotLatched { axis: a, probe } => {
            format!("touch probe {probe} of {} did not latch", axis(a))
        }
    }
}

fn wkc_text(kind: &EventKind) -> String {
    match *kind {
        EventKind::WorkingCounter {
            got,
            expected,
            missing,
            datagram,
        } => format!(
            "working counter {got}, expected {expected}{}{}",
            datagram.map(describe_datagram).unwrap_or_default(),
            if missing.is_some() {
                " (this device did not answer)"
            } else {
                ""
            }
        ),
        EventKind::OutputsNotTaken {
            got,
            expected,
            datagram,
            io,
            ..
        } => format!(
            "in SAFE-OP its process data is not taken: working counter {got}, expected \
             {expected}{}; {}",
            datagram.map(describe_datagram).unwrap_or_default(),
            if io {
                "an I/O device may take its outputs in OP only (an OpOnly SyncManager or FMMU in \
                 its ESI): OP requested"
            } else {
                "OP was not requested (slave stacks take outputs from SAFE-OP on, ETG.1020)"
            }
        ),
        _ => String::new(),
    }
}

fn describe_datagram(d: DatagramWkc) -> String {
    let devices = match d.devices {
        Some((lo, hi)) if lo == hi => format!(", device {lo}"),
        Some((lo, hi)) => format!(", devices {lo}–{hi}"),
        None => ", no device".to_owned(),
    };
    format!(
        ": logical datagram {} of {} (logical 0x{:08X}, {} bytes{devices}) came back with {}, expected {}",
        d.index, d.of, d.address, d.len, d.got, d.expected
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wrong_datagram_is_named_with_its_devices() {
        let d = DatagramWkc {
            index: 2,
            of: 2,
            address: 1466,
            len: 118,
            got: 18,
            expected: 20,
            devices: Some((38, 47)),
        };
        assert_eq!(
            describe_datagram(d),
            ": logical datagram 2 of 2 (logical 0x000005BA, 118 bytes, devices 38–47) came back \
             with 18, expected 20"
        );
        let one = DatagramWkc {
            devices: Some((5, 5)),
            ..d
        };
        assert!(describe_datagram(one).contains(", device 5)"));
    }
}
