//! `ecdrive demo`: the main job on the embedded default — an emulated MR-J4-TM and an emulated
//! BDHDE, in-process, brought to OP with DC SYNC0 and driven through csp, csv and cst.
//!
//! Everything is real except the drives: the software slave emulates both drives on the wire
//! (ESC registers, SII built from their ESI files, CoE, DC, CiA 402 with a motor model), and the
//! master is the same code that runs against hardware. Needs no hardware and no root (without
//! the privilege for SCHED_FIFO it says so and runs at normal priority).

use super::recovery::{self, Operator};
use crate::app::ethercat::tools::{ToolLink, finish_capture};
use crate::drives::{self, DriveProfile};
use crate::master::cycle::CycleSettings;
use crate::master::error::{ErrorKind, MasterError};
use crate::master::program::{RunMode, Step, Target};
use crate::master::session::{HistoryEntry, Master, MasterConfig};
use crate::master::startup::{DriveSetup, Selector};
use crate::master::telemetry::StopKind;
use crate::rt::host::HostInfo;
use crate::rt::{RtReport, RtSettings, Summary};
use crate::sim::transport::SegmentLink;
use crate::sim::{EscConfig, HostClock, Segment};
use serde::Serialize;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Options of the demo.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoOptions {
    /// Cycle time.
    pub cycle: Duration,
    /// Real-time settings of the cycle thread.
    pub rt: RtSettings,
    /// Write every frame to this pcapng file (`--pcap`, see [`crate::app::capture`]).
    pub pcap: Option<std::path::PathBuf>,
    /// Whether the emulated drives supervise the cyclic data as the real ones do (fault after
    /// about 7 ms without it: MR-J4-TM AL.86.1, BDHDE 0x818D); `false` (`--no-loss-detection`)
    /// is for machines that cannot keep the cycle, as [Pr. PN06]/[Pr. PN02] do on a real
    /// MR-J4-TM.
    pub loss_detection: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            cycle: Duration::from_millis(1),
            rt: RtSettings {
                priority: Some(80),
                cpu: None,
                lock_memory: true,
            },
            pcap: None,
            loss_detection: true,
        }
    }
}

/// What the demo did with one drive.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DemoDrive {
    /// Position on the segment.
    pub position: u16,
    /// Profile name.
    pub name: String,
    /// SII name.
    pub device_name: String,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// CiA 402 states reached, in order.
    pub states: Vec<String>,
    /// Modes set-points were streamed in, in order.
    pub modes: Vec<String>,
    /// Largest |following error| while enabled, in position units.
    pub max_following_error: i64,
    /// The same in motor revolutions.
    pub max_following_error_rev: f64,
    /// Whether the drive's program ran to its end.
    pub program_done: bool,
}

/// Cycle timing of the demo, ns.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DemoTiming {
    /// Wake-up latency against the intended instant.
    pub wake_latency: Summary,
    /// Period between wake-ups.
    pub period: Summary,
    /// Frame round trip.
    pub exchange: Summary,
    /// Time awake per cycle.
    pub busy: Summary,
}

/// The demo's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DemoReport {
    /// Cycle time, µs.
    pub cycle_us: u64,
    /// The capture of the frames (`--pcap`), if one was asked for.
    pub capture: Option<crate::app::capture::CaptureSummary>,
    /// The drives.
    pub drives: Vec<DemoDrive>,
    /// Timing.
    pub timing: DemoTiming,
    /// Cycles run.
    pub cycles: u64,
    /// Cycles without a reply.
    pub lost: u64,
    /// Cycles woken more than a cycle late.
    pub overruns: u64,
    /// What the RT set-up got.
    pub rt: RtReport,
    /// The host.
    pub host: HostInfo,
    /// Times the axes were brought back to motion after the drives stopped on their own
    /// (reset, enable, run the programs again).
    pub recoveries: u64,
    /// Errors in the history: empty on a clean run; after a recovery, the faults it recovered
    /// from.
    pub errors: Vec<String>,
    /// Errors the master or the demo did not handle (see [`recovery::unhandled_kind`]); empty
    /// when the demo succeeded.
    pub unhandled: Vec<String>,
    /// The whole history, as `ecdrive run` reports it (one shape for every command's JSON).
    pub history: Vec<HistoryEntry>,
    /// Whether everything completed.
    pub ok: bool,
}

/// The program each drive runs: a csp move and sine, a csv ramp, a cst torque step, and back to
/// csp, in the drive's own units (one motor revolution = `counts_per_rev`).
pub fn program(profile: &DriveProfile) -> Vec<Step> {
    let rev = profile.units.position_per_rev;
    vec![
        Step::Move {
            target: Target::By(0.5 * rev),
            velocity: 2.0 * rev,
            acceleration: 20.0 * rev,
            jerk: Some(400.0 * rev),
        },
        Step::Sine {
            amplitude: 0.05 * rev,
            frequency: 2.0,
            periods: 2.0,
        },
        Step::Mode { mode: RunMode::Csv },
        Step::Ramp {
            velocity: 1.0 * rev,
            acceleration: 10.0 * rev,
            hold: 0.3,
        },
        Step::Ramp {
            velocity: 0.0,
            acceleration: 10.0 * rev,
            hold: 0.05,
        },
        Step::Mode { mode: RunMode::Cst },
        Step::Torque {
            torque: 50.0,
            slope: Some(1000.0),
            hold: 0.1,
        },
        Step::Torque {
            torque: -50.0,
            slope: Some(1000.0),
            hold: 0.1,
        },
        // Back to position control through csv, which brakes with the drive's velocity loop
        // (with zero torque a free motor coasts, and the MR-J4-TM switches to a position mode
        // only at zero speed).
        Step::Mode { mode: RunMode::Csv },
        Step::Ramp {
            velocity: 0.0,
            acceleration: 10.0 * rev,
            hold: 0.05,
        },
        Step::Mode { mode: RunMode::Csp },
        Step::Move {
            target: Target::By(-0.5 * rev),
            velocity: 2.0 * rev,
            acceleration: 20.0 * rev,
            jerk: None,
        },
    ]
}

/// The demo segment: an emulated MR-J4-TM and an emulated BDHDE.
pub fn segment() -> Result<Segment, MasterError> {
    let mut seg = Segment::new(Arc::new(HostClock));
    for (i, p) in [&drives::mr_j4_tm::PROFILE, &drives::bdhde::PROFILE]
        .iter()
        .enumerate()
    {
        let dev = crate::sim::drives::emulated(p.key, 1000 + i as u32).map_err(|e| {
            MasterError::new(
                None,
                format!("building the emulated {}", p.name),
                ErrorKind::Config,
                e,
            )
        })?;
        seg.push(dev, EscConfig::default()).map_err(|e| {
            MasterError::new(
                None,
                format!("building the emulated {}", p.name),
                ErrorKind::Config,
                e,
            )
        })?;
    }
    Ok(seg)
}

/// How long the demo may take to complete the programs once in OP, recoveries included.
const DEMO_LIMIT: Duration = Duration::from_secs(30);
/// At most this many recoveries; more fail the demo.
const MAX_RECOVERIES: u64 = 3;

/// Run the demo: OP, enable, run the programs once, stop. If the drives stop on their own
/// (a fault) the demo recovers as an application would (at most `MAX_RECOVERIES` times) and
/// the report says so; it succeeds when the programs completed, nothing was left unhandled and
/// the drives were shut down.
pub fn run(opts: &DemoOptions) -> Result<DemoReport, MasterError> {
    let profiles = [&drives::mr_j4_tm::PROFILE, &drives::bdhde::PROFILE];
    let mut cfg = MasterConfig::new(opts.cycle);
    cfg.cycle = CycleSettings {
        rt: opts.rt.clone(),
        ..CycleSettings::new(opts.cycle)
    };
    for (i, p) in profiles.iter().enumerate() {
        cfg.startup.drives.push(DriveSetup {
            program: program(p),
            ..DriveSetup::new(Selector::Position(i as u16))
        });
    }
    let steps: Vec<usize> = profiles.iter().map(|p| program(p).len()).collect();
    let mut segment = segment()?;
    crate::sim::drives::set_loss_detection(&mut segment, opts.loss_detection);
    let link = ToolLink::Sim(Box::new(SegmentLink::new(segment)));
    let (link, capture) = match &opts.pcap {
        Some(path) => {
            let (tap, file) = crate::app::capture::start(path, "in-process (ecdrive demo)")
                .map_err(|e| {
                    MasterError::new(None, "starting the capture", ErrorKind::Config, e)
                })?;
            (link.captured(tap), Some(file))
        }
        None => (link, None),
    };
    let mut m = match Master::start(link, cfg) {
        Ok(m) => m,
        Err(f) => {
            drop(f.link);
            let _ = finish_capture(capture);
            return Err(f.error);
        }
    };
    m.wait_until("every drive in OP", Duration::from_secs(10), |t| {
        t.cycle.all_op
    })?;
    let (op, mut unhandled) = operate(&mut m, steps, opts.loss_detection)?;
    let done = op.programs_completed > 0;
    let (report, link) = m.stop(StopKind::Ramp);
    drop(link);
    let capture = finish_capture(capture)?;
    let report = report.ok_or_else(|| {
        MasterError::new(
            None,
            "the demo",
            ErrorKind::Bus,
            "the session ended without a report",
        )
    })?;
    let cycle = report.cycle.clone().ok_or_else(|| {
        MasterError::new(None, "the demo", ErrorKind::Bus, "the cycle did not run")
    })?;
    let drives = demo_drives(&report, &cycle, &profiles, done);
    let errors: Vec<String> = report
        .history
        .iter()
        .filter(|h| h.error)
        .map(|h| match &h.drive {
            Some(d) => format!("{d}: {}", h.text()),
            None => h.text(),
        })
        .collect();
    let history = report.history.clone();
    unhandled.extend(
        report
            .history
            .iter()
            .filter(|h| h.error && recovery::unhandled_kind(h.kind))
            .map(|h| match &h.drive {
                Some(d) => format!("{d}: {}", h.text()),
                None => h.text(),
            }),
    );
    let ok = done && unhandled.is_empty() && report.shutdown_ok;
    Ok(DemoReport {
        cycle_us: opts.cycle.as_micros() as u64,
        drives,
        timing: DemoTiming {
            wake_latency: cycle.timing.wake_latency.summary(),
            period: cycle.timing.period.summary(),
            exchange: cycle.timing.exchange.summary(),
            busy: cycle.timing.busy.summary(),
        },
        cycles: cycle.cycles,
        lost: cycle.lost,
        overruns: cycle.overruns,
        rt: cycle.rt.clone(),
        host: HostInfo::read(),
        recoveries: op.recoveries,
        errors,
        unhandled,
        history,
        capture,
        ok,
    })
}

/// The operator enables the axes and runs the programs (`steps` each); if the drives stop on
/// their own (their loss supervision trips when the machine stalls the cycle for 7 ms or more)
/// it resets, enables and runs the programs again, as an application would, and says so.
/// Returns the operator and what it could not handle; giving up names the way out when the
/// drives' `loss_detection` is on.
fn operate(
    m: &mut Master<ToolLink>,
    steps: Vec<usize>,
    loss_detection: bool,
) -> Result<(Operator, Vec<String>), MasterError> {
    let mut op = Operator::new(steps);
    let mut unhandled = Vec::new();
    let deadline = Instant::now() + DEMO_LIMIT;
    loop {
        std::thread::sleep(recovery::POLL);
        if !m.is_running() {
            unhandled.push("the session ended by itself".to_string());
            break;
        }
        let t = m.telemetry().clone();
        unhandled.extend(op.step(m, &t)?);
        if op.programs_completed > 0 || !unhandled.is_empty() {
            break;
        }
        if op.recoveries > MAX_RECOVERIES {
            unhandled.push(format!(
                "gave up after {MAX_RECOVERIES} recoveries: the drives keep stopping{}",
                if loss_detection {
                    " (their loss supervision trips when this machine holds the cycle back \
                     for 7 ms or more; `ecdrive demo --no-loss-detection` runs without it)"
                } else {
                    ""
                }
            ));
            break;
        }
        if Instant::now() >= deadline {
            unhandled.push(format!(
                "the programs did not finish within {} s",
                DEMO_LIMIT.as_secs()
            ));
            break;
        }
    }
    Ok((op, unhandled))
}

/// Each drive of the demo: its device, the states and modes it went through, its largest
/// following error (in revolutions too), whether its program completed.
fn demo_drives(
    report: &crate::master::SessionReport,
    cycle: &crate::master::CycleReport,
    profiles: &[&DriveProfile],
    done: bool,
) -> Vec<DemoDrive> {
    report
        .drives
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let rev = profiles.get(i).map_or(1.0, |p| p.units.position_per_rev);
            let fe = cycle.max_following_error.get(i).copied().unwrap_or(0);
            DemoDrive {
                position: d.info.position,
                name: d.profile.to_string(),
                device_name: d.info.name.clone(),
                vendor_id: d.info.vendor_id,
                product_code: d.info.product_code,
                revision: d.info.revision,
                serial: d.info.serial,
                states: cycle
                    .states
                    .get(i)
                    .map(|v| v.iter().map(|s| s.to_string()).collect())
                    .unwrap_or_default(),
                modes: cycle
                    .modes_run
                    .get(i)
                    .map(|v| v.iter().map(|m| m.short_name().to_string()).collect())
                    .unwrap_or_default(),
                max_following_error: fe,
                max_following_error_rev: fe as f64 / rev,
                program_done: done,
            }
        })
        .collect()
}
