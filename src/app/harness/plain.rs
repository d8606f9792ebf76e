//! The plain ethercrab baseline: ethercrab alone, as its own `dc` example runs it, with no
//! ecdrive master code.
//!
//! `MainDevice::new` (ethercrab's default timeouts) → `init_single_group` → per device the
//! PRE-OP SDOs the drive needs (PDO mapping, synchronisation type, cycle time, the profile's
//! start-up SDOs; written with ethercrab's `sdo_write`, the values taken from the drive's
//! profile as an application would hard-code them) and `set_dc_sync(Sync0)` →
//! `into_pre_op_pdi` → `configure_dc_sync` → `into_safe_op` → `request_into_op` → `tx_rx_dc`
//! cycles until every device is in OP. Then the measured loop: absolute sleep
//! (`clock_nanosleep`) to the instant `tx_rx_dc` asked for (start of the exchange +
//! `next_cycle_wait`), `tx_rx_dc`, then the application: read each device's inputs, write its
//! outputs (the drives stay disabled; outputs that must not be zero are set once before the
//! first cycle, and a drive's cycle counter, MR-J4-TM 0x2D23, advances every cycle). The
//! futures run on `async_io::block_on` (what `smol::block_on` is), so ethercrab's PDU timeouts
//! are its usual `async_io` timers.
//!
//! The frames are moved by a separate TX/RX thread, as with ethercrab's own drivers:
//! in-process by [`EthercrabLink`] (which also runs the emulated slaves, and wakes for frames
//! only, as ecdrive's in-process link does its slaves' work only when a frame comes), on an
//! interface by `ethercrab::std::tx_rx_task`. It gets the same real-time set-up as the loop thread, and its
//! CPU time is reported separately.

use super::HarnessError;
use super::cpu::{CpuReport, CpuSample, ThreadCpuClock, apply_syscalls, start_syscalls};
use super::report::{RunHistograms, RunReport};
use crate::drives::{CycleTimeObject, DriveProfile, StartupWhen};
use crate::od::{self, ObjectAddress};
use crate::pdo::{self, Direction, Field, RemapOptions};
use crate::rt::{RtReport, RtSettings, monotonic_ns, sleep_until_ns};
use crate::sim::Segment;
use crate::sim::transport::{EthercrabLink, Wakeups};
use ethercrab::std::ethercat_now;
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{DcSync, MainDevice, MainDeviceConfig, PduStorage, Timeouts};
use std::sync::mpsc;
use std::time::Duration;

/// Same group dimensions as ecdrive's (`master::bus`), so both copy the same structures.
const MAX_SUBDEVICES: usize = 256;
const MAX_PDI: usize = 16384;
const MAX_FRAMES: usize = 16;
/// ethercrab 0.7.1's `tx_rx_task` receives into a buffer of the interface's MTU (1 500 bytes on
/// Ethernet and veth), which must also hold the 14-byte Ethernet header: a reply longer than
/// 1 500 bytes comes back cut and the task fails ("failed to receive an EtherCAT frame"). So
/// the baseline's frames stay within 1 500 bytes (ecdrive's own pump reads whole 1 514-byte
/// frames). From about 31 emulated drives the process image and the AL status reads fill a
/// frame: the baseline then sends slightly shorter frames, a few more of them, than ecdrive.
const MAX_FRAME: usize = 1500;
/// Whole frames of at most `MAX_FRAME` bytes (`element_size` adds ethercrab's headers).
type Storage =
    PduStorage<MAX_FRAMES, { PduStorage::element_size(MAX_FRAME - PduStorage::element_size(0)) }>;

/// Stack of the loop thread: ethercrab keeps the group (tens of KiB) inline in its futures.
const STACK: usize = 16 * 1024 * 1024;

/// Where the plain ethercrab loop sends its frames.
pub enum PlainTransport {
    /// In-process: this segment, served by an [`EthercrabLink`] thread.
    InProcess(Segment),
    /// A network interface, served by `ethercrab::std::tx_rx_task` on its own thread.
    Interface(String),
}

/// What the measurement needs to know.
#[derive(Debug, Clone)]
pub struct PlainSettings {
    /// Cycle time.
    pub cycle: Duration,
    /// Cycles in the measured window.
    pub cycles: u64,
    /// Real-time set-up of the loop and TX/RX threads.
    pub rt: RtSettings,
    /// The profile of each device, in line order.
    pub profiles: Vec<&'static DriveProfile>,
    /// How long the devices may take to reach OP.
    pub op_timeout: Duration,
    /// Reply budget as a fraction of the cycle (a slower exchange counts as missed).
    pub reply_budget: f64,
    /// Count the loop thread's syscalls ([`super::cpu::SyscallWindow`]).
    pub count_syscalls: bool,
    /// When the frame is sent after SYNC0 (ethercrab's `sync0_shift`).
    pub sync0_shift: Duration,
}

fn err(what: impl Into<String>, reason: impl ToString) -> HarnessError {
    HarnessError::Run {
        run: "ethercrab",
        what: what.into(),
        reason: reason.to_string(),
    }
}

/// Run the plain ethercrab loop; returns its report (without drive figures) and, in-process,
/// the segment back.
pub fn run(
    transport: PlainTransport,
    settings: &PlainSettings,
) -> Result<(RunReport, Option<Segment>), HarnessError> {
    // ethercrab's TX/RX handles must outlive every thread that uses them; one storage per run
    // is leaked (about 25 KiB) rather than reused with `unsafe`.
    let storage: &'static Storage = Box::leak(Box::new(Storage::new()));
    let (tx, rx, pdu_loop) = storage
        .try_split()
        .map_err(|()| err("splitting the PDU storage", "already split"))?;

    let (clock_tx, clock_rx) = mpsc::channel::<(Option<ThreadCpuClock>, RtReport)>();
    let io_rt = settings.rt.clone();
    let on_start = move || {
        let rep = io_rt.apply_to_current_thread();
        let _ = clock_tx.send((ThreadCpuClock::current(), rep));
    };
    enum Io {
        Link(EthercrabLink),
        Task(std::thread::JoinHandle<Result<(), String>>),
    }
    let io = match transport {
        PlainTransport::InProcess(segment) => Io::Link(
            EthercrabLink::spawn_configured(segment, tx, rx, Wakeups::FramesOnly, on_start)
                .map_err(|e| err("starting the in-process TX/RX thread", e))?,
        ),
        PlainTransport::Interface(iface) => {
            let h = std::thread::Builder::new()
                .name("jitter-ethercrab-txrx".into())
                .spawn(move || {
                    on_start();
                    let task = ethercrab::std::tx_rx_task(&iface, tx, rx)
                        .map_err(|e| format!("opening {iface}: {e}"))?;
                    async_io::block_on(task)
                        .map(|_| ())
                        .map_err(|e| format!("TX/RX task on {iface}: {e}"))
                })
                .map_err(|e| err("starting the TX/RX thread", e))?;
            Io::Task(h)
        }
    };
    let (io_clock, io_rt_report) = clock_rx
        .recv_timeout(Duration::from_secs(5))
        .map_err(|_| err("starting the TX/RX thread", "it did not start"))?;

    let s = settings.clone();
    let lp = std::thread::Builder::new()
        .name("jitter-ethercrab".into())
        .stack_size(STACK)
        .spawn(move || {
            // ethercrab's 30 ms PDU timeout is shorter than a loaded machine may keep the
            // in-process segment's thread from running (other cycles at SCHED_FIFO); the
            // harness's links lose no frame, so a longer wait measures the same cycles.
            let timeouts = Timeouts {
                pdu: Duration::from_millis(500),
                ..Timeouts::default()
            };
            let md = MainDevice::new(pdu_loop, timeouts, MainDeviceConfig::default());
            let r = async_io::block_on(measure(&md, &s, io_clock));
            // SAFETY: every group built on `md` was dropped inside `measure` and no frame is in
            // flight (each exchange was awaited to completion or timed out); the storage is
            // not used again. Releasing makes the TX/RX task return.
            let _ = unsafe { md.release_all() };
            r
        })
        .map_err(|e| err("starting the loop thread", e))?;
    let result = lp.join().map_err(|_| err("the loop thread", "panicked"))?;

    let mut io_error = None;
    let segment = match io {
        Io::Link(link) => Some(link.stop()),
        Io::Task(h) => {
            // The task ends once `release_all` signalled it; a stuck interface must not hang
            // the harness, so give it a moment and otherwise leave it.
            let t0 = monotonic_ns();
            while !h.is_finished() && monotonic_ns() - t0 < 2_000_000_000 {
                std::thread::sleep(Duration::from_millis(5));
            }
            if h.is_finished() {
                match h.join() {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => io_error = Some(e),
                    Err(_) => io_error = Some("the TX/RX thread panicked".into()),
                }
            }
            None
        }
    };
    let mut report = match (result, io_error) {
        (Ok(r), Some(e)) => {
            tracing::warn!("plain ethercrab baseline: {e}");
            r
        }
        (Ok(r), None) => r,
        // The TX/RX thread's failure (e.g. no permission for the interface) is the cause.
        (Err(_), Some(e)) => return Err(err("TX/RX thread", e)),
        (Err(e), None) => return Err(e),
    };
    if !io_rt_report.warnings.is_empty() {
        report.notes.extend(
            io_rt_report
                .warnings
                .iter()
                .map(|w| format!("TX/RX thread: {w}")),
        );
    }
    Ok((report, segment))
}

/// What the plain loop does for one drive, from its profile (data, as any ethercrab
/// application would hard-code it): PRE-OP SDO writes, outputs that must not be zero, and the
/// cycle counter a drive may require to advance every cycle.
pub(super) struct DrivePlan {
    /// `(object, little-endian value, why)`.
    pub(super) writes: Vec<(ObjectAddress, Vec<u8>, String)>,
    /// Output fields set once before the first cycle.
    pub(super) defaults: Vec<(Field, i64)>,
    /// Output field incremented (mod 256) every cycle.
    pub(super) counter: Option<Field>,
}

pub(super) fn drive_plan(
    profile: &DriveProfile,
    cycle_ns: u32,
    position: usize,
) -> Result<DrivePlan, HarnessError> {
    let what = |w: &str| format!("drive {position} ({}): {w}", profile.name);
    let mapping = &profile.cyclic_mapping;
    let mut writes: Vec<(ObjectAddress, Vec<u8>, String)> =
        pdo::remap_sequence(mapping, &RemapOptions::for_drive(&profile.pdo_limits, None))
            .map_err(|e| err(what("PDO mapping"), e))?
            .into_iter()
            .map(|w| (w.address, w.bytes(), w.description))
            .collect();
    if let Some(a) = profile.sync.sync_type_object {
        writes.push((a, 2u16.to_le_bytes().to_vec(), "sync type DC SYNC0".into()));
    }
    match profile.sync.cycle_time_object {
        Some(CycleTimeObject::Nanoseconds(a)) => {
            writes.push((a, cycle_ns.to_le_bytes().to_vec(), "cycle time".into()));
        }
        Some(CycleTimeObject::InterpolationFixedIndex { unit_ns, .. }) => {
            let v = u8::try_from(cycle_ns / unit_ns.max(1)).map_err(|_| {
                err(
                    what("interpolation period"),
                    format!("{cycle_ns} ns is more than 255 units of {unit_ns} ns"),
                )
            })?;
            writes.push((
                ObjectAddress::new(0x60C2, 1),
                vec![v],
                "interpolation period".into(),
            ));
        }
        Some(CycleTimeObject::InterpolationStandard) => {
            // cycle = value × 10^index s with value ≤ 255.
            let (mut value, mut index) = (u64::from(cycle_ns), -9i8);
            while value > 255 || (value % 10 == 0 && value > 0 && index < 0) {
                value /= 10;
                index += 1;
            }
            writes.push((
                ObjectAddress::new(0x60C2, 1),
                vec![value as u8],
                "interpolation value".into(),
            ));
            writes.push((
                ObjectAddress::new(0x60C2, 2),
                vec![index as u8],
                "interpolation index".into(),
            ));
        }
        None => {}
    }
    let dict = od::Dictionary::new(profile.dictionary);
    for sdo in profile.startup {
        if sdo.when == StartupWhen::IfNotMapped && mapping.contains(Direction::Rx, sdo.address) {
            continue;
        }
        let bytes = sdo
            .value
            .to_value()
            .zip(dict.data_type(sdo.address))
            .ok_or_else(|| {
                err(
                    what("start-up SDO"),
                    format!("{} has no typed value", sdo.address),
                )
            })
            .and_then(|(v, dt)| v.encode(dt).map_err(|e| err(what("start-up SDO"), e)))?;
        writes.push((sdo.address, bytes, sdo.why.to_string()));
    }
    let layout = pdo::Layout::new(mapping);
    let defaults = profile
        .output_defaults
        .iter()
        .filter_map(|d| {
            layout
                .raw_field(Direction::Rx, d.address, true)
                .ok()
                .map(|f| (f, d.value))
        })
        .collect();
    let counter = profile
        .cycle_counter
        .and_then(|c| layout.raw_field(Direction::Rx, c.output, false).ok());
    Ok(DrivePlan {
        writes,
        defaults,
        counter,
    })
}

/// One expedited SDO download with ethercrab (1, 2 or 4 bytes).
async fn sdo_write<S: std::ops::Deref<Target = ethercrab::SubDevice>>(
    sd: &ethercrab::SubDeviceRef<'_, S>,
    a: ObjectAddress,
    bytes: &[u8],
) -> Result<(), String> {
    let r = match *bytes {
        [b] => sd.sdo_write(a.index, a.sub, b).await,
        [b0, b1] => {
            sd.sdo_write(a.index, a.sub, u16::from_le_bytes([b0, b1]))
                .await
        }
        [b0, b1, b2, b3] => {
            sd.sdo_write(a.index, a.sub, u32::from_le_bytes([b0, b1, b2, b3]))
                .await
        }
        _ => {
            return Err(format!(
                "{} bytes: ethercrab downloads 1, 2 or 4 bytes only",
                bytes.len()
            ));
        }
    };
    r.map_err(|e| e.to_string())
}

/// The group once OP was requested.
type OpGroup = ethercrab::SubDeviceGroup<
    MAX_SUBDEVICES,
    MAX_PDI,
    ethercrab::DefaultLock,
    ethercrab::subdevice_group::Op,
    ethercrab::subdevice_group::HasDc,
>;

/// Outputs that must not be zero, before the first cycle.
fn output_defaults(group: &OpGroup, md: &MainDevice<'_>, plans: &[DrivePlan]) {
    for (i, plan) in plans.iter().enumerate() {
        if let Ok(sd) = group.subdevice(md, i) {
            let mut io = sd.io_raw_mut();
            for (f, v) in &plan.defaults {
                let _ = f.write_int(io.outputs(), i128::from(*v));
            }
        }
    }
}

/// The application part of a cycle: read each drive's inputs, write its outputs (the drives
/// stay disabled: the controlword stays 0), advance the cycle counters.
fn application(group: &OpGroup, md: &MainDevice<'_>, plans: &[DrivePlan], counter: u8) {
    for (i, plan) in plans.iter().enumerate() {
        if let Ok(sd) = group.subdevice(md, i) {
            let mut io = sd.io_raw_mut();
            std::hint::black_box(io.inputs().first().copied());
            if let Some(c) = &plan.counter {
                let _ = c.write_raw(io.outputs(), u64::from(counter));
            }
        }
    }
}

async fn measure(
    md: &MainDevice<'_>,
    s: &PlainSettings,
    io_clock: Option<ThreadCpuClock>,
) -> Result<RunReport, HarnessError> {
    let cycle_ns = s.cycle.as_nanos() as u64;
    let (group, plans) = request_op(md, s, cycle_ns).await?;
    // The cycle starts: real-time set-up now (as ecdrive's cycle thread does it).
    let rt = s.rt.apply_to_current_thread();
    output_defaults(&group, md, &plans);
    let mut counter: u8 = 0;
    let next = cycle_until_op(&group, md, &plans, s, &mut counter).await?;
    let mut notes = Vec::new();
    let begin = CpuSample::take(io_clock.as_ref());
    let sys = start_syscalls(s.count_syscalls, &mut notes);
    let w = window(&group, md, &plans, s, next, &mut counter).await;
    let sys_end = sys.map(|w| w.stop());
    let end = CpuSample::take(io_clock.as_ref());
    let cpu = apply_syscalls(
        sys_end,
        CpuReport::between(&begin, &end, s.cycles),
        &mut notes,
    );
    if s.count_syscalls {
        notes.push("syscalls are counted on the loop thread only, not the TX/RX thread".into());
    }
    if w.not_op > 0 {
        notes.push(format!("{} cycles with a device not in OP", w.not_op));
    }
    back_to_init(group, md, &mut notes).await;
    Ok(w.h.report(
        "ethercrab",
        cycle_ns,
        rt,
        w.late,
        Some(w.missed),
        cpu,
        Vec::new(),
        notes,
    ))
}

/// Discovery, each drive's start-up SDOs and SYNC0, PRE-OP with the process image, DC, SAFE-OP
/// and OP requested, as a plain ethercrab user does it. Returns the group and the drives' plans.
async fn request_op(
    md: &MainDevice<'_>,
    s: &PlainSettings,
    cycle_ns: u64,
) -> Result<(OpGroup, Vec<DrivePlan>), HarnessError> {
    // ethercrab's default PDU timeout (what a plain user has) is short enough that a host
    // stall during discovery on a loaded machine loses a frame; that says nothing about the
    // cycle this loop measures, so start-up is tried once more, and said.
    let mut group = match md
        .init_single_group::<MAX_SUBDEVICES, MAX_PDI>(ethercat_now)
        .await
    {
        Ok(g) => g,
        Err(ethercrab::error::Error::Timeout(t)) => {
            tracing::warn!(
                "plain ethercrab baseline: init_single_group: timeout ({t}); starting once more"
            );
            md.init_single_group::<MAX_SUBDEVICES, MAX_PDI>(ethercat_now)
                .await
                .map_err(|e| err("init_single_group", e))?
        }
        Err(e) => return Err(err("init_single_group", e)),
    };
    if group.len() != s.profiles.len() {
        return Err(err(
            "discovery",
            format!(
                "found {} devices, expected {}",
                group.len(),
                s.profiles.len()
            ),
        ));
    }
    let cycle32 = u32::try_from(cycle_ns).unwrap_or(u32::MAX);
    let plans = s
        .profiles
        .iter()
        .enumerate()
        .map(|(i, p)| drive_plan(p, cycle32, i))
        .collect::<Result<Vec<_>, _>>()?;
    for (i, mut sd) in group.iter_mut(md).enumerate() {
        let Some(plan) = plans.get(i) else {
            continue;
        };
        for (a, bytes, why) in &plan.writes {
            sdo_write(&sd, *a, bytes)
                .await
                .map_err(|e| err(format!("drive {i}: SDO {a} ({why})"), e))?;
        }
        sd.set_dc_sync(DcSync::Sync0);
    }
    let group = group
        .into_pre_op_pdi(md)
        .await
        .map_err(|e| err("into_pre_op_pdi", e))?;
    let group = group
        .configure_dc_sync(
            md,
            DcConfiguration {
                start_delay: Duration::from_millis(100),
                sync0_period: s.cycle,
                sync0_shift: s.sync0_shift,
            },
        )
        .await
        .map_err(|e| err("configure_dc_sync", e))?;
    let group = group
        .into_safe_op(md)
        .await
        .map_err(|e| err("into_safe_op", e))?;
    let group = group
        .request_into_op(md)
        .await
        .map_err(|e| err("request_into_op", e))?;
    Ok((group, plans))
}

/// Cycle until every device is in OP (not measured). Returns when the next cycle is due.
async fn cycle_until_op(
    group: &OpGroup,
    md: &MainDevice<'_>,
    plans: &[DrivePlan],
    s: &PlainSettings,
    counter: &mut u8,
) -> Result<u64, HarnessError> {
    let cycle_ns = s.cycle.as_nanos() as u64;
    let deadline = monotonic_ns() + s.op_timeout.as_nanos() as u64;
    let mut next = monotonic_ns();
    loop {
        sleep_until_ns(next);
        let t0 = monotonic_ns();
        let r = group.tx_rx_dc(md).await;
        *counter = counter.wrapping_add(1);
        application(group, md, plans, *counter);
        match r {
            Ok(resp) if resp.all_op() => {
                next = t0 + resp.extra.next_cycle_wait.as_nanos() as u64;
                break;
            }
            Ok(resp) => next = t0 + resp.extra.next_cycle_wait.as_nanos() as u64,
            Err(_) => next = t0 + cycle_ns,
        }
        if monotonic_ns() > deadline {
            return Err(err(
                "waiting for OP",
                format!(
                    "not every device in OP after {} ms",
                    s.op_timeout.as_millis()
                ),
            ));
        }
    }
    Ok(next)
}

/// What the measured window saw: the histograms, the late wake-ups, the cycles whose reply
/// missed its budget, the cycles with a device not in OP.
struct Window {
    h: RunHistograms,
    late: u64,
    missed: u64,
    not_op: u64,
}

/// The measured window: `s.cycles` cycles from `next`, each woken, exchanged and given to the
/// application.
async fn window(
    group: &OpGroup,
    md: &MainDevice<'_>,
    plans: &[DrivePlan],
    s: &PlainSettings,
    mut next: u64,
    counter: &mut u8,
) -> Window {
    let cycle_ns = s.cycle.as_nanos() as u64;
    let mut h = RunHistograms::new(true);
    let mut late = 0u64;
    let mut missed = 0u64;
    let mut not_op = 0u64;
    let budget = (cycle_ns as f64 * s.reply_budget) as u64;
    let mut last_wake = 0u64;
    for _ in 0..s.cycles {
        sleep_until_ns(next);
        let woke = monotonic_ns();
        let latency = woke.saturating_sub(next);
        h.wake_latency.record(latency);
        if last_wake != 0 {
            h.period.record(woke - last_wake);
        }
        last_wake = woke;
        if latency > cycle_ns {
            late += 1;
        }
        let t0 = monotonic_ns();
        let r = group.tx_rx_dc(md).await;
        let t1 = monotonic_ns();
        let wait = match r {
            Ok(resp) => {
                if let Some(e) = h.exchange.as_mut() {
                    e.record(t1 - t0);
                }
                if t1 - woke > budget {
                    missed += 1;
                }
                // An application checks the states that ride along (ecdrive's cycle does).
                if !resp.all_op() {
                    not_op += 1;
                }
                resp.extra.next_cycle_wait.as_nanos() as u64
            }
            Err(_) => {
                missed += 1;
                cycle_ns
            }
        };
        *counter = counter.wrapping_add(1);
        application(group, md, plans, *counter);
        h.busy.record(monotonic_ns() - woke);
        next = t0 + wait;
    }
    Window {
        h,
        late,
        missed,
        not_op,
    }
}

/// Back to INIT (not measured); what fails is noted.
async fn back_to_init(group: OpGroup, md: &MainDevice<'_>, notes: &mut Vec<String>) {
    // Back to INIT (not measured).
    match group.into_safe_op(md).await {
        Ok(g) => match g.into_pre_op(md).await {
            Ok(g) => {
                if let Err(e) = g.into_init(md).await {
                    notes.push(format!("PRE-OP → INIT at the end failed: {e}"));
                }
            }
            Err(e) => notes.push(format!("SAFE-OP → PRE-OP at the end failed: {e}")),
        },
        Err(e) => notes.push(format!("OP → SAFE-OP at the end failed: {e}")),
    }
}
