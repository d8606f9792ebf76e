//! `ecdrive sim`: serve emulated devices on an interface until Ctrl-C, optionally injecting
//! faults.

use crate::{Command, exit, fail_with, print_json};
use ecdrive::sim::faults::{Corruption, DropLeg, LinkFault};
use ecdrive::sim::run::{FaultSpec, ScheduledFault, SimError};
use std::process::ExitCode;
use std::time::Duration;

/// Where dropped frames are lost.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default)]
pub enum Leg {
    /// On the way to the slaves: they never see the frame.
    #[default]
    Outbound,
    /// On the way back: the slaves processed the frame, the reply is lost.
    Return,
}

/// What `--corrupt-at` corrupts in the first datagram of a frame.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default)]
pub enum Kind {
    /// The working counter (XOR 0x8000).
    #[default]
    Wkc,
    /// The datagram index (XOR 0x80).
    Index,
    /// The command (XOR 0x80: a reserved code).
    Command,
    /// The length field (set to 2047: the frame no longer parses).
    Length,
    /// Every data byte (inverted).
    Data,
}

/// EEPROM and firmware options of `ecdrive sim`.
#[derive(clap::Args, Clone, Debug, Default)]
#[command(next_help_heading = "EEPROM and firmware")]
pub struct StoreArgs {
    /// Keep each device's EEPROM in DIR (POS-NAME.sii): loaded at start when there, saved
    /// when the sim stops, so a station alias or SII a master wrote is still there at the next
    /// start, as on a device switched off and on.
    #[arg(long, value_name = "DIR")]
    pub eeprom_dir: Option<std::path::PathBuf>,
    /// Write-protect the EEPROM of the device at POS (writes are not acknowledged); repeat for
    /// more.
    #[arg(long, value_name = "POS")]
    pub eeprom_write_protect: Vec<u16>,
    /// Write a firmware image in the emulation's format for the first --device (one that
    /// takes firmware over FoE, the MR-J4-TM) to FILE and exit.
    #[arg(long, value_name = "FILE")]
    pub make_firmware: Option<std::path::PathBuf>,
    /// With --make-firmware: the revision number the image gives the device (0x1018:03).
    #[arg(long, value_name = "N", default_value = "0x00030000", value_parser = crate::parse_u32)]
    pub firmware_revision: u32,
    /// With --make-firmware: the software version it gives the device (0x100A, ≤ 16 chars).
    #[arg(long, value_name = "TEXT", default_value = "B5")]
    pub firmware_version: String,
}

/// `--make-firmware`: an image for the first device of `devices`.
fn make_firmware(devices: &[String], store: &StoreArgs, path: &std::path::Path) -> ExitCode {
    let Some(name) = devices.first() else {
        return fail_with("sim", "--make-firmware needs --device", exit::USAGE);
    };
    let Some(spec) = ecdrive::sim::drives::spec_for(name.split('+').next().unwrap_or(name)) else {
        return fail_with(
            "sim",
            &format!("--make-firmware: {name:?} is not an emulated EtherCAT drive"),
            exit::USAGE,
        );
    };
    let Some((vendor_id, product_code)) = spec.foe.and_then(|f| f.firmware_for) else {
        return fail_with(
            "sim",
            &format!(
                "--make-firmware: the emulated {} takes no firmware over FoE",
                spec.name
            ),
            exit::USAGE,
        );
    };
    if store.firmware_version.len() > 16 || !store.firmware_version.is_ascii() {
        return fail_with(
            "sim",
            "--firmware-version: at most 16 ASCII characters",
            exit::USAGE,
        );
    }
    let image = ecdrive::sim::foe::FirmwareImage {
        vendor_id,
        product_code,
        revision: store.firmware_revision,
        version: store.firmware_version.clone(),
        payload: (0..4096u32).map(|i| (i * 7 + 3) as u8).collect(),
    };
    let bytes = image.encode();
    if let Err(e) = std::fs::write(path, &bytes) {
        return fail_with(
            "sim",
            &format!("writing {}: {e}", path.display()),
            exit::USAGE,
        );
    }
    eprintln!(
        "ecdrive sim: {} bytes: firmware for the {} (revision 0x{:08X}, version {}) in {}",
        bytes.len(),
        spec.name,
        image.revision,
        image.version,
        path.display()
    );
    ExitCode::SUCCESS
}

/// Fault injection options of `ecdrive sim`. Times (T) count from when serving starts, with a
/// unit: `500ms`, `5s`. Positions (POS) are 0-based in `--device` order. Numbers may be
/// decimal or 0x hex.
#[derive(clap::Args, Clone, Debug, Default)]
#[command(next_help_heading = "Fault injection")]
pub struct FaultArgs {
    /// Drop this fraction of frames, from the start: a percentage (`1%`) or a fraction (`0.01`).
    #[arg(long, value_name = "P", value_parser = parse_drop)]
    drop: Option<ScheduledFault>,
    /// Where dropped frames are lost.
    #[arg(long, value_enum, value_name = "LEG", default_value_t)]
    drop_leg: Leg,
    /// Delay the reply of a fraction of frames (the slaves process them on time):
    /// `P:TIME`, e.g. `5%:200us`.
    #[arg(long, value_name = "P:TIME", value_parser = parse_delay)]
    delay: Option<ScheduledFault>,
    /// Corrupt the first datagram of N frames (default 1) from time T: `T[:N]`, e.g. `3s`,
    /// `3s:10`. Repeatable.
    #[arg(long, value_name = "T[:N]", value_parser = parse_corrupt)]
    corrupt_at: Vec<ScheduledFault>,
    /// What --corrupt-at corrupts.
    #[arg(long, value_enum, value_name = "KIND", default_value_t)]
    corrupt_kind: Kind,
    /// A bit error on the cable into device POS for N frames (default 1) from time T:
    /// `POS@T[:N]`. That device counts RX errors on port 0, the devices after it forwarded
    /// RX errors (`ecdrive diag` shows them); the frames are lost. Repeatable.
    #[arg(long, value_name = "POS@T[:N]", value_parser = parse_crc_error)]
    crc_error_at: Vec<ScheduledFault>,
    /// Pull the cable at time T: nothing reaches the slaves, which keep running (SYNC0,
    /// watchdogs, the drives' loss-of-data alarms). Repeatable.
    #[arg(long, value_name = "T", value_parser = parse_disconnect)]
    disconnect_at: Vec<ScheduledFault>,
    /// Put the cable back at time T. Repeatable; each follows a --disconnect-at.
    #[arg(long, value_name = "T", value_parser = parse_reconnect)]
    reconnect_at: Vec<ScheduledFault>,
    /// The slave at POS restarts locally at time T: INIT with AL status code 0x0060:
    /// `POS@T`. Repeatable.
    #[arg(long, value_name = "POS@T", value_parser = parse_reset)]
    reset_at: Vec<ScheduledFault>,
    /// The drive at POS raises its alarm ID (the manual's name, e.g. `AL.52`, `J3`) at time T:
    /// `POS:ID@T`. Repeatable.
    #[arg(long, value_name = "POS:ID@T", value_parser = parse_alarm)]
    alarm: Vec<ScheduledFault>,
    /// The drive at POS sees this following error (position units) from time T:
    /// `POS:VALUE@T`. Repeatable.
    #[arg(long, value_name = "POS:VALUE@T", value_parser = parse_following_error)]
    following_error: Vec<ScheduledFault>,
    /// The device at POS answers the next SDO request to INDEX[:SUB] with abort CODE (from
    /// time T, default at once): `POS:INDEX[:SUB]:CODE[@T]`, e.g. `0:0x6060:0x08000022`.
    /// Repeatable.
    #[arg(long, value_name = "POS:INDEX[:SUB]:CODE[@T]", value_parser = parse_sdo_abort)]
    sdo_abort: Vec<ScheduledFault>,
    /// The device at POS sends an emergency with CODE in the middle of its next segmented SDO
    /// transfer (from time T, default at once): `POS:CODE[@T]`. Repeatable.
    #[arg(long, value_name = "POS:CODE[@T]", value_parser = parse_emergency_during_sdo)]
    emergency_during_sdo: Vec<ScheduledFault>,
    /// The local clock of the slave at POS drifts by PPB parts per billion (from time T,
    /// default at once): `POS:PPB[@T]`, e.g. `1:50000`. Repeatable.
    #[arg(long, value_name = "POS:PPB[@T]", value_parser = parse_drift)]
    drift: Vec<ScheduledFault>,
    /// Seed of the random choices of --drop and --delay (the same seed drops the same frames).
    #[arg(long, value_name = "N", value_parser = parse_seed)]
    seed: Option<ScheduledFault>,
}

impl FaultArgs {
    /// Every fault, settings included.
    pub fn faults(&self) -> Vec<ScheduledFault> {
        let mut out = Vec::new();
        let setting = |f: LinkFault, source: String| ScheduledFault {
            at: Duration::ZERO,
            fault: FaultSpec::Link(f),
            source,
        };
        if !self.is_empty() {
            let leg = match self.drop_leg {
                Leg::Outbound => DropLeg::Outbound,
                Leg::Return => DropLeg::Return,
            };
            out.push(setting(LinkFault::DropOn(leg), "--drop-leg".into()));
            let kind = match self.corrupt_kind {
                Kind::Wkc => Corruption::WorkingCounter,
                Kind::Index => Corruption::Index,
                Kind::Command => Corruption::Command,
                Kind::Length => Corruption::Length,
                Kind::Data => Corruption::Data,
            };
            out.push(setting(
                LinkFault::CorruptWith(kind),
                "--corrupt-kind".into(),
            ));
        }
        out.extend(self.seed.iter().cloned());
        out.extend(self.drop.iter().cloned());
        out.extend(self.delay.iter().cloned());
        for v in [
            &self.corrupt_at,
            &self.crc_error_at,
            &self.disconnect_at,
            &self.reconnect_at,
            &self.reset_at,
            &self.alarm,
            &self.following_error,
            &self.sdo_abort,
            &self.emergency_during_sdo,
            &self.drift,
        ] {
            out.extend(v.iter().cloned());
        }
        out
    }

    /// No fault asked for.
    pub fn is_empty(&self) -> bool {
        self.drop.is_none()
            && self.delay.is_none()
            && self.seed.is_none()
            && self.corrupt_at.is_empty()
            && self.crc_error_at.is_empty()
            && self.disconnect_at.is_empty()
            && self.reconnect_at.is_empty()
            && self.reset_at.is_empty()
            && self.alarm.is_empty()
            && self.following_error.is_empty()
            && self.sdo_abort.is_empty()
            && self.emergency_during_sdo.is_empty()
            && self.drift.is_empty()
    }
}

// ------------------------------------------------------------------------------- parsing

fn num(s: &str, what: &str) -> Result<u64, String> {
    let t = s.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u64::from_str_radix(h, 16),
        None => t.parse::<u64>(),
    }
    .map_err(|_| format!("{what} {t:?} is not a number (decimal or 0x hex)"))
}

fn bounded<T: TryFrom<u64>>(s: &str, what: &str, max: u64) -> Result<T, String> {
    let v = num(s, what)?;
    if v > max {
        return Err(format!("{what} {s:?} is larger than {max:#X}"));
    }
    T::try_from(v).map_err(|_| format!("{what} {s:?} is out of range"))
}

fn position(s: &str) -> Result<u16, String> {
    s.trim()
        .parse::<u16>()
        .map_err(|_| format!("position {s:?} is not a number from 0 to 65535"))
}

fn time(s: &str) -> Result<Duration, String> {
    ecdrive_cli::app::config::parse_duration(s)
}

/// A probability: `1%`, `0.5 %` or `0.01`; 0 to 1.
pub(crate) fn fraction(s: &str) -> Result<f32, String> {
    let t = s.trim();
    let (v, scale) = match t.strip_suffix('%') {
        Some(p) => (p.trim(), 100.0),
        None => (t, 1.0),
    };
    let v: f64 = v
        .parse()
        .map_err(|_| format!("{s:?} is not a fraction (write e.g. \"1%\" or \"0.01\")"))?;
    let f = v / scale;
    if !f.is_finite() || !(0.0..=1.0).contains(&f) {
        return Err(format!("{s:?} is not between 0 and 100%"));
    }
    Ok(f as f32)
}

/// Split `X@T` into `X` and the time (`None` without `@`).
fn at(s: &str) -> Result<(&str, Option<Duration>), String> {
    match s.rsplit_once('@') {
        Some((x, t)) => Ok((x, Some(time(t)?))),
        None => Ok((s, None)),
    }
}

fn required_at(s: &str) -> Result<(&str, Duration), String> {
    match at(s)? {
        (x, Some(t)) => Ok((x, t)),
        (_, None) => Err(format!("{s:?} has no time: add @T, e.g. @5s")),
    }
}

fn sched(opt: &str, value: &str, at: Duration, fault: FaultSpec) -> ScheduledFault {
    ScheduledFault {
        at,
        fault,
        source: format!("--{opt} {value}"),
    }
}

fn parse_drop(s: &str) -> Result<ScheduledFault, String> {
    let f = fraction(s)?;
    Ok(sched(
        "drop",
        s,
        Duration::ZERO,
        FaultSpec::Link(LinkFault::DropFraction(f)),
    ))
}

fn parse_delay(s: &str) -> Result<ScheduledFault, String> {
    let (p, t) = s
        .split_once(':')
        .ok_or_else(|| format!("{s:?} is not P:TIME (write e.g. \"5%:200us\")"))?;
    let fraction = fraction(p)?;
    let d = time(t)?;
    if d.is_zero() {
        return Err(format!("the delay in {s:?} is zero"));
    }
    let delay_ns = u64::try_from(d.as_nanos()).map_err(|_| format!("{s:?}: delay too long"))?;
    Ok(sched(
        "delay",
        s,
        Duration::ZERO,
        FaultSpec::Link(LinkFault::Delay { fraction, delay_ns }),
    ))
}

fn parse_corrupt(s: &str) -> Result<ScheduledFault, String> {
    let (t, n) = match s.split_once(':') {
        Some((t, n)) => (t, bounded::<u32>(n, "count", u64::from(u32::MAX))?),
        None => (s, 1),
    };
    if n == 0 {
        return Err(format!("the count in {s:?} is zero"));
    }
    Ok(sched(
        "corrupt-at",
        s,
        time(t)?,
        FaultSpec::Link(LinkFault::CorruptNext(n)),
    ))
}

fn parse_disconnect(s: &str) -> Result<ScheduledFault, String> {
    Ok(sched(
        "disconnect-at",
        s,
        time(s)?,
        FaultSpec::Link(LinkFault::Disconnect),
    ))
}

fn parse_reconnect(s: &str) -> Result<ScheduledFault, String> {
    Ok(sched(
        "reconnect-at",
        s,
        time(s)?,
        FaultSpec::Link(LinkFault::Reconnect),
    ))
}

fn parse_crc_error(s: &str) -> Result<ScheduledFault, String> {
    let (p, rest) = s
        .split_once('@')
        .ok_or_else(|| format!("{s:?}: expected POS@T[:N], e.g. 1@2s:5"))?;
    let (t, n) = match rest.split_once(':') {
        Some((t, n)) => (t, bounded::<u32>(n, "count", u64::from(u32::MAX))?),
        None => (rest, 1),
    };
    if n == 0 {
        return Err(format!("the count in {s:?} is zero"));
    }
    Ok(sched(
        "crc-error-at",
        s,
        time(t)?,
        FaultSpec::Link(LinkFault::CrcErrorAt {
            position: position(p)?,
            frames: n,
        }),
    ))
}

fn parse_reset(s: &str) -> Result<ScheduledFault, String> {
    let (p, t) = required_at(s)?;
    Ok(sched(
        "reset-at",
        s,
        t,
        FaultSpec::Reset {
            position: position(p)?,
        },
    ))
}

fn parse_alarm(s: &str) -> Result<ScheduledFault, String> {
    let (x, t) = required_at(s)?;
    let (p, id) = x
        .split_once(':')
        .ok_or_else(|| format!("{s:?} is not POS:ID@T (write e.g. \"0:AL.52@5s\")"))?;
    if id.trim().is_empty() {
        return Err(format!("{s:?} names no alarm"));
    }
    Ok(sched(
        "alarm",
        s,
        t,
        FaultSpec::Alarm {
            position: position(p)?,
            id: id.trim().to_string(),
        },
    ))
}

fn parse_following_error(s: &str) -> Result<ScheduledFault, String> {
    let (x, t) = required_at(s)?;
    let (p, v) = x
        .split_once(':')
        .ok_or_else(|| format!("{s:?} is not POS:VALUE@T (write e.g. \"1:50000@2s\")"))?;
    let value: i32 = v
        .trim()
        .parse()
        .map_err(|_| format!("following error {v:?} is not a 32-bit integer"))?;
    Ok(sched(
        "following-error",
        s,
        t,
        FaultSpec::FollowingError {
            position: position(p)?,
            value,
        },
    ))
}

fn parse_sdo_abort(s: &str) -> Result<ScheduledFault, String> {
    let (x, t) = at(s)?;
    let parts: Vec<&str> = x.split(':').collect();
    let (p, index, sub, code) = match parts.as_slice() {
        [p, i, c] => (*p, *i, None, *c),
        [p, i, sub, c] => (*p, *i, Some(*sub), *c),
        _ => {
            return Err(format!(
                "{s:?} is not POS:INDEX[:SUB]:CODE (write e.g. \"0:0x6060:0x08000022\")"
            ));
        }
    };
    Ok(sched(
        "sdo-abort",
        s,
        t.unwrap_or(Duration::ZERO),
        FaultSpec::SdoAbort {
            position: position(p)?,
            index: bounded(index, "index", 0xFFFF)?,
            subindex: sub.map(|v| bounded(v, "subindex", 0xFF)).transpose()?,
            code: bounded(code, "abort code", u64::from(u32::MAX))?,
        },
    ))
}

fn parse_emergency_during_sdo(s: &str) -> Result<ScheduledFault, String> {
    let (x, t) = at(s)?;
    let (p, c) = x
        .split_once(':')
        .ok_or_else(|| format!("{s:?} is not POS:CODE (write e.g. \"0:0xFF10\")"))?;
    Ok(sched(
        "emergency-during-sdo",
        s,
        t.unwrap_or(Duration::ZERO),
        FaultSpec::EmergencyDuringSdo {
            position: position(p)?,
            error_code: bounded(c, "error code", 0xFFFF)?,
        },
    ))
}

fn parse_drift(s: &str) -> Result<ScheduledFault, String> {
    let (x, t) = at(s)?;
    let (p, v) = x
        .split_once(':')
        .ok_or_else(|| format!("{s:?} is not POS:PPB (write e.g. \"1:50000\")"))?;
    let ppb: i32 = v
        .trim()
        .parse()
        .map_err(|_| format!("drift {v:?} is not an integer number of ppb"))?;
    // Real oscillators stay within ±100 ppm; the ESC's drift loop corrects up to ±1000 ppm.
    if ppb.unsigned_abs() > 1_000_000 {
        return Err(format!(
            "drift {ppb} ppb is beyond ±1000 ppm (±1000000 ppb), more than the DC loop corrects"
        ));
    }
    Ok(sched(
        "drift",
        s,
        t.unwrap_or(Duration::ZERO),
        FaultSpec::Drift {
            position: position(p)?,
            ppb,
        },
    ))
}

fn parse_seed(s: &str) -> Result<ScheduledFault, String> {
    let n = num(s, "seed")?;
    Ok(sched(
        "seed",
        s,
        Duration::ZERO,
        FaultSpec::Link(LinkFault::Seed(n)),
    ))
}

/// What `ecdrive sim --json` prints when it stops.
#[derive(serde::Serialize)]
struct Report {
    /// Frames answered and dropped by the server.
    served: ecdrive::sim::transport::ServeStats,
    /// The segment's counters, injected faults included.
    segment: ecdrive::sim::segment::SegmentStats,
}

/// How the devices are served: the serving thread's real-time set-up (`--priority`, `--cpu`)
/// and the slaves' supervision (`--sm-watchdog`, `--no-loss-detection`).
pub struct SimRt {
    /// SCHED_FIFO priority (0: normal scheduling).
    pub priority: Option<u8>,
    /// CPU to pin to.
    pub cpu: Option<usize>,
    /// SM watchdog reset value.
    pub sm_watchdog: Option<u16>,
    /// The emulated drives supervise the cyclic data.
    pub loss_detection: bool,
}

/// `ecdrive sim`: emulated EtherCAT devices on an interface, or with `--can` CANopen drives
/// on a CAN bus.
pub fn command(c: Command) -> ExitCode {
    match c {
        Command::Sim {
            can: Some(bus),
            nodes,
            json,
            devices,
            faults,
            ..
        } => {
            // The EtherCAT segment's devices and faults mean nothing on a CAN bus: say so
            // rather than serve without them.
            if !devices.is_empty() || !faults.is_empty() {
                return fail_with(
                    "sim",
                    "--device and the fault options (--alarm, --drop, …) are for an EtherCAT \
                     segment; with --can, give the CANopen drives with --node (faults: inject \
                     them in-process through `sim::canopen::EmulatedNode::inject_alarm`)",
                    exit::USAGE,
                );
            }
            crate::can::sim(&bus, &nodes, json.json)
        }
        Command::Sim {
            interface,
            can: None,
            nodes: _,
            devices,
            sm_watchdog,
            no_loss_detection,
            priority,
            cpu,
            list_devices,
            faults,
            store,
            json,
        } => sim(
            SimRt {
                priority: Some(priority),
                cpu,
                sm_watchdog,
                loss_detection: !no_loss_detection,
            },
            interface,
            devices,
            list_devices,
            faults,
            store,
            json.json,
        ),
        _ => unreachable!("dispatch sends only sim here"),
    }
}

pub fn sim(
    rt: SimRt,
    interface: Option<String>,
    devices: Vec<String>,
    list_devices: bool,
    faults: Box<FaultArgs>,
    store: StoreArgs,
    json: bool,
) -> ExitCode {
    if let Some(path) = &store.make_firmware {
        return make_firmware(&devices, &store, path);
    }
    if list_devices {
        return list(json);
    }
    let Some(interface) = interface else {
        return fail_with("sim", "--interface is required", exit::USAGE);
    };
    let devices = match repeat_devices(&devices) {
        Ok(d) => d,
        Err(e) => return fail_with("sim", &e, exit::USAGE),
    };
    let opts = ecdrive::sim::run::SimOptions {
        interface,
        devices,
        sm_watchdog: rt.sm_watchdog,
        loss_detection: rt.loss_detection,
        faults: faults.faults(),
        priority: rt.priority.filter(|p| *p > 0),
        cpu: rt.cpu,
        eeprom_dir: store.eeprom_dir.clone(),
        eeprom_write_protected: store.eeprom_write_protect.clone(),
    };
    let mut prepared = match ecdrive::sim::run::Prepared::new(&opts) {
        Ok(p) => p,
        Err(e) => {
            let code = match e {
                SimError::Link(_) => exit::BUS,
                _ => exit::USAGE,
            };
            return fail_with("sim", &e.to_string(), code);
        }
    };
    eprintln!(
        "ecdrive sim: serving {} device(s) on {} — Ctrl-C to stop",
        opts.devices.len(),
        opts.interface
    );
    for line in prepared.describe() {
        eprintln!("  {line}");
    }
    // Ctrl-C, SIGTERM and SIGHUP stop serving.
    let stop = crate::stop_signals().stop;
    let settings = ecdrive::rt::RtSettings {
        priority: opts.priority,
        cpu: opts.cpu,
        lock_memory: false,
    };
    let served = prepared.serve_rt(&stop, &settings);
    say_eeproms_saved(&prepared, &store);
    served_report(served, &prepared, !faults.is_empty(), json)
}

/// `ecdrive sim --list-devices`: the emulated devices, the quirks, the stored parameters and
/// the CANopen drives.
fn list(json: bool) -> ExitCode {
    use ecdrive_cli::app::canopen::tools::EMULATED_NODES;
    let names = ecdrive::sim::devices::device_names();
    use ecdrive::sim::quirks::Quirk;
    if json {
        #[derive(serde::Serialize)]
        struct Dev {
            name: &'static str,
            description: String,
        }
        #[derive(serde::Serialize)]
        struct List {
            devices: Vec<Dev>,
            quirks: Vec<Dev>,
            can_nodes: Vec<CanNode>,
        }
        #[derive(serde::Serialize)]
        struct CanNode {
            name: &'static str,
            profile: &'static str,
            node: u8,
        }
        let list = List {
            devices: names
                .into_iter()
                .map(|(name, description)| Dev { name, description })
                .collect(),
            quirks: Quirk::ALL
                .into_iter()
                .map(|q| Dev {
                    name: q.name(),
                    description: q.describe().into(),
                })
                .collect(),
            can_nodes: EMULATED_NODES
                .iter()
                .map(|(name, _, node)| CanNode {
                    name,
                    profile: ecdrive::sim::canopen::drives::by_name(name).map_or("-", |e| e.name),
                    node: *node,
                })
                .collect(),
        };
        return print_json("sim", &list);
    }
    for (name, what) in names {
        println!("{name:14} {what}");
    }
    println!();
    println!("Quirks (behaviour of devices ecdrive did not write): DEVICE+QUIRK[+QUIRK…]");
    for q in Quirk::ALL {
        println!("  {:30} {}", q.name(), q.describe());
    }
    println!();
    println!(
        "Stored parameters (emulated drives): DEVICE@OBJECT=VALUE[@…], in effect from \
         power-on, e.g. mr-j4-tm@0x2001=2 ([Pr. PA01] = profile mode)"
    );
    println!();
    println!("CANopen drives (ecdrive sim --can BUS --node NAME[@ID]), default node-ID:");
    for (name, _, node) in EMULATED_NODES {
        if let Some(e) = ecdrive::sim::canopen::drives::by_name(name) {
            println!(
                "  {name:26} {} ({}), node {node} (0x{node:02X})",
                e.name, e.source
            );
        }
    }
    println!(
        "  eds:FILE@ID                any CiA 402 drive from its EDS/DCF file; NAME+eds:FILE \
         a drive above with its vendor's file as its dictionary"
    );
    ExitCode::SUCCESS
}

/// Where the EEPROMs were saved (with `--eeprom-dir`), or why not.
fn say_eeproms_saved(prepared: &ecdrive::sim::run::Prepared, store: &StoreArgs) {
    match prepared.save_eeproms() {
        Ok(files) if !files.is_empty() => {
            eprintln!(
                "ecdrive sim: EEPROMs saved in {}",
                store
                    .eeprom_dir
                    .as_deref()
                    .unwrap_or(std::path::Path::new("."))
                    .display()
            );
        }
        Ok(_) => {}
        Err(e) => eprintln!("ecdrive sim: {e}"),
    }
}

/// What serving did: the frames answered and dropped, what the faults injected, and with
/// `--json` the report.
fn served_report(
    served: Result<ecdrive::sim::transport::ServeStats, SimError>,
    prepared: &ecdrive::sim::run::Prepared,
    injected: bool,
    json: bool,
) -> ExitCode {
    match served {
        Ok(stats) => {
            let seg = prepared.segment_stats();
            eprintln!(
                "ecdrive sim: stopped; {} frames answered, {} dropped{}",
                stats.frames,
                stats.dropped,
                if stats.link_down > 0 {
                    format!("; the interface went down {} time(s)", stats.link_down)
                } else {
                    String::new()
                }
            );
            if injected {
                eprintln!(
                    "ecdrive sim: injected: {} frames dropped ({} on the way back), {} delayed, \
                     {} corrupted, {} lost while disconnected; {} faults applied, {} ignored",
                    seg.dropped,
                    seg.dropped_replies,
                    seg.delayed,
                    seg.corrupted,
                    seg.lost_disconnected,
                    seg.faults_applied,
                    seg.faults_ignored
                );
            }
            if json {
                return print_json(
                    "sim",
                    &Report {
                        served: stats,
                        segment: seg,
                    },
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => fail_with("sim", &e.to_string(), exit::BUS),
    }
}

/// `--device NAME[:COUNT]` as the devices in line order: `mr-j4-tm:32` is 32 MR-J4-TM; quirks
/// (`NAME+QUIRK`) stay with the name. At most as many devices as the master takes on one
/// segment.
pub(crate) fn repeat_devices(devices: &[String]) -> Result<Vec<String>, String> {
    let max = ecdrive::master::bus::MAX_SUBDEVICES;
    let mut out = Vec::new();
    for d in devices {
        match d
            .rsplit_once(':')
            .filter(|(_, n)| n.chars().all(|c| c.is_ascii_digit()))
        {
            Some((name, n)) => {
                let n: usize = n
                    .parse()
                    .ok()
                    .filter(|n| (1..=max).contains(n))
                    .ok_or_else(|| format!("--device {d}: the count must be 1 to {max}"))?;
                out.extend(std::iter::repeat_n(name.to_string(), n));
            }
            None => out.push(d.clone()),
        }
    }
    if out.len() > max {
        return Err(format!(
            "{} devices: at most {max} on one segment",
            out.len()
        ));
    }
    Ok(out)
}
