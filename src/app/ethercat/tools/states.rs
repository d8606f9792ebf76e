//! `ecdrive states`: request an EtherCAT state and report what each device reached.
//!
//! INIT, PRE-OP and BOOT are requested directly through AL control (0x0120), BOOT by way of
//! INIT as the state machine demands. SAFE-OP and OP need process data: when every device on
//! the segment has a drive profile, the segment is configured as the master does it
//! ([`startup::configure`]: the profile's PDO mapping, synchronisation, DC SYNC0) and ends in
//! SAFE-OP; otherwise ethercrab sizes the process data from each device's current mapping. OP
//! is then requested while process data (all outputs zero: no drive is enabled) is exchanged
//! every cycle, until each requested device reports OP or refuses with an AL status code.
//!
//! ecdrive is not a resident master: when the command ends nobody exchanges process data any
//! more, and a device's SyncManager watchdog takes it back from OP to SAFE-OP.

use super::{T_STEP, al_state_text, discover, drive_ref, read_al_status};
use crate::ec::{AlState, register};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{DriveRef, MasterError, bus_error};
use crate::master::exec::exec_error;
use crate::master::startup::{self, DeviceInfo, StartupConfig};
use serde::Serialize;
use std::time::Duration;

/// What to request.
#[derive(Debug, Clone)]
pub struct StatesOptions {
    /// One device, or every device.
    pub position: Option<u16>,
    /// The state to request.
    pub target: AlState,
    /// Cycle time of the process data exchanged for SAFE-OP and OP (and of SYNC0).
    pub cycle: Duration,
    /// How long a device may take to reach the state.
    pub timeout: Duration,
    /// Profiles from vendor ESI files (`--esi`): a device no built-in profile matches is
    /// configured from its own, as `run` does.
    pub esi_profiles: Vec<&'static crate::drives::DriveProfile>,
    /// The devices the same files describe that are no drives (vendor, product, revision).
    pub esi_not_drives: Vec<(u32, u32, u32)>,
}

impl StatesOptions {
    /// Defaults: every device, 1 ms cycle, 10 s per transition.
    pub fn new(target: AlState) -> Self {
        Self {
            position: None,
            target,
            cycle: Duration::from_millis(1),
            timeout: Duration::from_secs(10),
            esi_profiles: Vec::new(),
            esi_not_drives: Vec::new(),
        }
    }
}

/// The outcome for one device.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StateChange {
    /// Position.
    pub position: u16,
    /// The device (profile name, or the SII name).
    pub drive: String,
    /// The state requested.
    pub requested: String,
    /// The AL status at the end (`OP`, `SAFEOP+ERR`, …).
    pub reached: String,
    /// Whether the device is in the requested state without error.
    pub ok: bool,
    /// The AL status code when the device refused.
    pub al_status_code: Option<u16>,
    /// Its meaning.
    pub code_text: Option<String>,
    /// What to do about a refusal, where ecdrive knows (`None` otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hint: Option<String>,
}

fn write_control<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    address: u16,
    drive: &DriveRef,
    value: u16,
) -> Result<(), MasterError> {
    bus.block_on(
        &|| format!("{drive}: writing AL control (0x0120)"),
        T_STEP,
        |md| async move {
            ethercrab::Command::fpwr(address, register::AL_CONTROL)
                .send(md, value)
                .await
        },
    )
    .map_err(|e| exec_error(Some(drive), e))?
    .map_err(|e| bus_error(Some(drive), "writing AL control (0x0120)", e))
}

/// One device being moved.
struct Pending {
    address: u16,
    drive: DriveRef,
    done: Option<StateChange>,
}

/// Request `target` from every pending device, then poll until each reached it or refused,
/// calling `exchange` between polls (process data, returns the time to the next cycle).
fn drive_to<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    pending: &mut [Pending],
    target: AlState,
    timeout: Duration,
    exchange: &mut dyn FnMut(&mut Bus<'_, L>) -> Result<Duration, MasterError>,
) -> Result<(), MasterError> {
    for p in pending.iter_mut() {
        let (status, _) = read_al_status(bus, p.address, &p.drive)?;
        // Acknowledge a pending error together with the request (AL control bit 4).
        let ack = if status.error() { 0x0010 } else { 0 };
        write_control(bus, p.address, &p.drive, target as u16 | ack)?;
    }
    let deadline = crate::rt::monotonic_ns() + timeout.as_nanos() as u64;
    let mut next_poll = 0u64;
    loop {
        let wait = exchange(bus)?;
        let now = crate::rt::monotonic_ns();
        if now >= next_poll {
            next_poll = now + 10_000_000;
            for p in pending.iter_mut().filter(|p| p.done.is_none()) {
                let (status, code) = read_al_status(bus, p.address, &p.drive)?;
                let refused = status.error();
                if status.state() == Some(target) || refused || now > deadline {
                    let ok = status.state() == Some(target) && !refused;
                    p.done = Some(StateChange {
                        position: p.drive.position,
                        drive: p.drive.name.clone(),
                        requested: target.name().to_string(),
                        reached: al_state_text(status),
                        ok,
                        al_status_code: (!ok && refused).then_some(code.0),
                        code_text: (!ok && refused)
                            .then(|| code.text().unwrap_or("unknown AL status code").to_string()),
                        hint: None,
                    });
                }
            }
            if pending.iter().all(|p| p.done.is_some()) {
                return Ok(());
            }
        }
        if !wait.is_zero() {
            std::thread::sleep(wait);
        }
    }
}

/// Set SM0/SM1 to the bootstrap mailbox the device's SII gives (words 0x14–0x17: receive
/// offset and size, send offset and size), as INIT → BOOT requires (ETG.1000.6: the ESC checks
/// the mailbox SyncManagers against it). A device without one is left as it is: it refuses
/// BOOT itself (AL status code 0x0013 "Bootstrap not supported").
fn configure_bootstrap_mailbox<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    group: &crate::master::startup::Group<ethercrab::subdevice_group::PreOp>,
    position: u16,
    address: u16,
    drive: &DriveRef,
) -> Result<(), MasterError> {
    let none = &mut |_: usize, _: usize| {};
    let w = super::sii::read_eeprom(bus, group, position, drive, 0x0014, 8, none)?;
    let word = |i: usize| {
        u16::from_le_bytes([
            w.get(2 * i).copied().unwrap_or(0),
            w.get(2 * i + 1).copied().unwrap_or(0),
        ])
    };
    let (rx_start, rx_len, tx_start, tx_len) = (word(0), word(1), word(2), word(3));
    let valid = |start: u16, len: u16| start >= 0x1000 && len > 0 && len != 0xFFFF;
    if !valid(rx_start, rx_len) || !valid(tx_start, tx_len) {
        return Ok(());
    }
    // Control 0x26: mailbox, master writes, PDI interrupt; 0x22: mailbox, master reads.
    // Activate bit 0: enabled.
    let sm = |start: u16, len: u16, control: u8| {
        let (s, l) = (start.to_le_bytes(), len.to_le_bytes());
        [s[0], s[1], l[0], l[1], control, 0, 0x01, 0]
    };
    let mut regs = [0u8; 16];
    regs[..8].copy_from_slice(&sm(rx_start, rx_len, 0x26));
    regs[8..].copy_from_slice(&sm(tx_start, tx_len, 0x22));
    // An ESC takes a SyncManager's start, length and control only while it is deactivated:
    // first deactivate both (the standard mailbox of PRE-OP may still be set up), then write.
    let off = [0u8; 16];
    for (data, what) in [
        (off, "deactivating SM0/SM1"),
        (regs, "writing the bootstrap mailbox SyncManagers (SM0/SM1)"),
    ] {
        bus.block_on(&|| format!("{drive}: {what}"), T_STEP, |md| async move {
            ethercrab::Command::fpwr(address, register::sm(0))
                .send(md, data)
                .await
        })
        .map_err(|e| exec_error(Some(drive), e))?
        .map_err(|e| bus_error(Some(drive), what, e))?;
    }
    Ok(())
}

fn no_exchange<L: FrameLink>(_: &mut Bus<'_, L>) -> Result<Duration, MasterError> {
    Ok(Duration::from_millis(1))
}

fn finish(pending: Vec<Pending>, target: AlState) -> Vec<StateChange> {
    pending
        .into_iter()
        .map(|p| {
            p.done.unwrap_or(StateChange {
                position: p.drive.position,
                drive: p.drive.name,
                requested: target.name().to_string(),
                reached: "?".into(),
                ok: false,
                al_status_code: None,
                code_text: None,
                hint: None,
            })
        })
        .collect()
}

/// Request `opts.target` from one device or all, and report what each reached. A refusal is
/// not an error of this function: it is reported in the device's [`StateChange`] with the AL
/// status code.
pub fn states<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    opts: &StatesOptions,
) -> Result<Vec<StateChange>, MasterError> {
    states_timed(bus, opts).map(|r| r.devices)
}

/// What [`states_timed`] reports: each device's state change and, for SAFEOP and OP on a
/// segment of known drives (configured as `run` does it), where start-up's time went.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StatesReport {
    /// Per device, in segment order.
    pub devices: Vec<StateChange>,
    /// Where start-up's time went (`None` for INIT, PREOP and BOOT, and for a segment
    /// configured from the devices' own mappings).
    pub startup: Option<crate::master::StartupTimes>,
}

/// [`states`] with the start-up times.
pub fn states_timed<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    opts: &StatesOptions,
) -> Result<StatesReport, MasterError> {
    let mut startup = None;
    let devices = request(bus, opts, &mut startup)?;
    Ok(StatesReport { devices, startup })
}

/// Every device selected (or the one at `opts.position`) taken to `opts.target`: INIT, PRE-OP
/// and BOOT by AL control alone, SAFE-OP and OP with process data exchanged, configured as
/// `run` configures a drive where every device has a profile (`startup` then says where its
/// time went), else from the devices' own SII.
fn request<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    opts: &StatesOptions,
    startup: &mut Option<crate::master::StartupTimes>,
) -> Result<Vec<StateChange>, MasterError> {
    let found = discover(bus)?;
    let selected: Vec<DeviceInfo> = match opts.position {
        Some(p) => vec![found.device(p)?.clone()],
        None => found.devices.clone(),
    };
    let mut pending: Vec<Pending> = selected
        .iter()
        .map(|d| Pending {
            address: d.address,
            drive: drive_ref(d),
            done: None,
        })
        .collect();
    let target = opts.target;
    match target {
        AlState::Init | AlState::PreOp => {
            drive_to(bus, &mut pending, target, opts.timeout, &mut no_exchange)?;
        }
        AlState::Bootstrap => to_bootstrap(bus, &found, &selected, &mut pending, opts)?,
        AlState::SafeOp | AlState::Op => {
            let all_known = found.devices.iter().all(|d| {
                crate::drives::by_identity(d.vendor_id, d.product_code).is_some()
                    || startup::esi_profile_for(&opts.esi_profiles, &opts.esi_not_drives, d)
                        .is_some()
            });
            if all_known {
                *startup = Some(to_op_configured(bus, found, &mut pending, opts)?);
            } else if let Some(refused) = to_op_from_sii(bus, found, &mut pending, opts)? {
                return Ok(finish(pending, refused));
            }
        }
    }
    Ok(finish(pending, target))
}

/// BOOT, which is reached from INIT only: INIT first, then each device's bootstrap mailbox
/// configured, then BOOT; a device that did not reach INIT did not reach BOOT either.
fn to_bootstrap<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    found: &super::Discovered,
    selected: &[DeviceInfo],
    pending: &mut [Pending],
    opts: &StatesOptions,
) -> Result<(), MasterError> {
    let target = opts.target;
    drive_to(bus, pending, AlState::Init, opts.timeout, &mut no_exchange)?;
    let failed: Vec<bool> = pending
        .iter()
        .map(|p| p.done.as_ref().is_some_and(|d| !d.ok))
        .collect();
    for p in pending.iter_mut() {
        p.done = None;
    }
    for (p, d) in pending.iter().zip(selected) {
        configure_bootstrap_mailbox(bus, &found.group, d.position, p.address, &p.drive)?;
    }
    drive_to(bus, pending, target, opts.timeout, &mut no_exchange)?;
    for (p, f) in pending.iter_mut().zip(failed) {
        if let (Some(d), true) = (p.done.as_mut(), f) {
            d.ok = false;
        }
    }
    Ok(())
}

/// SAFE-OP or OP with the segment configured as `run` configures it (every device has a
/// profile): valid outputs, with SYNC0 running on every drive, for as many cycles as the cycle
/// gives them before OP. Returns where start-up's time went.
fn to_op_configured<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    found: super::Discovered,
    pending: &mut [Pending],
    opts: &StatesOptions,
) -> Result<crate::master::StartupTimes, MasterError> {
    let target = opts.target;
    let mut cfg = StartupConfig::new(opts.cycle);
    cfg.esi_profiles = opts.esi_profiles.clone();
    cfg.esi_not_drives = opts.esi_not_drives.clone();
    let plan = startup::assign_roles(&found.devices, &cfg)?;
    let started = startup::configure(bus, found.group, found.devices, plan, &cfg)?;
    let mut times = started.times;
    let group = started.group;
    let dc_time = std::cell::Cell::new(0u64);
    let mut exchange = |bus: &mut Bus<'_, L>| -> Result<Duration, MasterError> {
        let r = bus
            .block_on(&|| "exchanging process data".into(), T_STEP, |md| {
                group.tx_rx_dc(md)
            })
            .map_err(|e| exec_error(None, e))?
            .map_err(|e| bus_error(None, "exchanging process data", e))?;
        dc_time.set(r.extra.dc_system_time);
        Ok(r.extra.next_cycle_wait)
    };
    // Valid outputs before OP, with SYNC0 running on every drive, for as many
    // cycles as the cycle gives them (bounded by the timeout).
    let cycles = crate::master::CycleSettings::new(opts.cycle).safeop_cycles;
    let not_before = crate::master::startup::op_not_before_dc(
        &started.drives,
        cycles,
        opts.cycle.as_nanos() as u64,
    );
    let until = crate::rt::monotonic_ns() + opts.timeout.as_nanos() as u64;
    let mut n = 0u32;
    while n < cycles || dc_time.get() < not_before {
        let w = exchange(bus)?;
        n = n.saturating_add(1);
        if crate::rt::monotonic_ns() > until {
            break;
        }
        std::thread::sleep(w);
    }
    drive_to(bus, pending, target, opts.timeout, &mut exchange)?;
    if target == AlState::Op {
        times.reached_op(crate::rt::monotonic_ns());
    }
    Ok(times)
}

/// SAFE-OP or OP with the process image the devices' SII gives (a device without a profile):
/// SAFE-OP first on the way to OP. Returns the state to report a refusal at when a device did
/// not reach SAFE-OP; a device that wants DC SYNC0 is told how to give it what it needs.
fn to_op_from_sii<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    found: super::Discovered,
    pending: &mut [Pending],
    opts: &StatesOptions,
) -> Result<Option<AlState>, MasterError> {
    let target = opts.target;
    let group = bus
        .block_on(
            &|| "building the process image (PRE-OP)".into(),
            T_STEP,
            |md| found.group.into_pre_op_pdi(md),
        )
        .map_err(|e| exec_error(None, e))?
        .map_err(|e| bus_error(None, "building the process image (PRE-OP)", e))?;
    // As the run's start-up does: process-data SMs the SII leaves off, enabled.
    startup::enable_process_data_sms(bus, &found.devices, &mut Vec::new())?;
    let cycle = opts.cycle;
    let mut exchange = |bus: &mut Bus<'_, L>| -> Result<Duration, MasterError> {
        bus.block_on(&|| "exchanging process data".into(), T_STEP, |md| {
            group.tx_rx(md)
        })
        .map_err(|e| exec_error(None, e))?
        .map_err(|e| bus_error(None, "exchanging process data", e))?;
        Ok(cycle)
    };
    if target == AlState::Op {
        drive_to(bus, pending, AlState::SafeOp, opts.timeout, &mut exchange)?;
        if pending
            .iter()
            .any(|p| p.done.as_ref().is_some_and(|d| !d.ok))
        {
            return Ok(Some(AlState::SafeOp));
        }
        for p in pending.iter_mut() {
            p.done = None;
        }
    }
    drive_to(bus, pending, target, opts.timeout, &mut exchange)?;
    // Configured from its SII alone, a device that needs DC SYNC0 refuses: say how
    // to give it what it needs.
    for p in pending.iter_mut() {
        if let Some(d) = p
            .done
            .as_mut()
            .filter(|d| d.al_status_code.is_some_and(|c| DC_REFUSALS.contains(&c)))
        {
            d.hint = Some(
                "the device wants DC SYNC0, which `states` sets up only for a drive \
                 it has a profile for: give the device's ESI file with --esi FILE \
                 (or a folder of them) and it is configured as `run` would"
                    .to_string(),
            );
        }
    }
    Ok(None)
}

/// AL status codes of a device that wants distributed clocks configured (ETG.1000.6 Table
/// 11): 0x002C fatal sync error, 0x002D no sync error, 0x0030 invalid DC SYNC configuration,
/// 0x0035 invalid sync cycle time.
const DC_REFUSALS: [u16; 4] = [0x002C, 0x002D, 0x0030, 0x0035];
