//! Serving named devices on an interface: the library side of `ecdrive sim`.

use super::clock::HostClock;
use super::devices::{self, DeviceError};
use super::drives::EmulatedDrive;
use super::esc::EscConfig;
use super::faults::{DeviceFault, Fault, FaultHandle, LinkFault, SlaveFault};
use super::segment::{Segment, SegmentStats};
use super::sii::SiiError;
use super::transport::{ServeStats, serve};
use crate::link::{LinkError, RawSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A fault for `ecdrive sim`, naming things as the command line does; checked against the
/// devices and turned into a [`Fault`] when the segment is built.
#[derive(Debug, Clone, PartialEq)]
pub enum FaultSpec {
    /// A link fault (see [`LinkFault`]).
    Link(LinkFault),
    /// [`SlaveFault::ResetToInit`] at `position`.
    Reset {
        /// Position in the line (0-based).
        position: u16,
    },
    /// [`SlaveFault::ClockDrift`] at `position`.
    Drift {
        /// Position in the line.
        position: u16,
        /// Drift in ppb.
        ppb: i32,
    },
    /// [`DeviceFault::RaiseAlarm`]: the drive at `position` raises the alarm named `id` (as
    /// its manual names it, e.g. `AL.52`, `J3`).
    Alarm {
        /// Position in the line.
        position: u16,
        /// Alarm name.
        id: String,
    },
    /// [`DeviceFault::ForceFollowingError`] at `position`.
    FollowingError {
        /// Position in the line.
        position: u16,
        /// Following error in position units.
        value: i32,
    },
    /// [`DeviceFault::AbortSdo`] at `position`.
    SdoAbort {
        /// Position in the line.
        position: u16,
        /// Object index.
        index: u16,
        /// Subindex, `None` for any.
        subindex: Option<u8>,
        /// Abort code.
        code: u32,
    },
    /// [`DeviceFault::EmergencyDuringSdo`] at `position` (the error register follows from
    /// the code's class, manufacturer bytes zero).
    EmergencyDuringSdo {
        /// Position in the line.
        position: u16,
        /// Emergency error code.
        error_code: u16,
    },
}

/// A fault and when to inject it.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledFault {
    /// Time after serving starts; zero: before the first frame.
    pub at: Duration,
    /// The fault.
    pub fault: FaultSpec,
    /// How the user wrote it (e.g. `--alarm 0:AL.52@5s`), for error messages.
    pub source: String,
}

/// The error register of an emergency with `code` (CiA 301 §7.5.2.2, object 0x1001): bit 0
/// (generic error) always, plus current (0x2xxx), voltage (0x3xxx), temperature (0x4xxx),
/// communication (0x81xx) or manufacturer-specific (0xFFxx) by the code's class.
fn error_register(code: u16) -> u8 {
    let class = match code >> 8 {
        0x20..=0x2F => 0x02,
        0x30..=0x3F => 0x04,
        0x40..=0x4F => 0x08,
        0x81 => 0x10,
        0xFF => 0x80,
        _ => 0,
    };
    0x01 | class
}

impl ScheduledFault {
    /// Check the fault against `segment` and resolve names (an alarm name to the drive's own).
    pub fn resolve(&self, segment: &Segment) -> Result<Fault, SimError> {
        let bad = |reason: String| SimError::Fault {
            source_text: self.source.clone(),
            reason,
        };
        let slave = |position: u16| {
            segment.slave(usize::from(position)).ok_or_else(|| {
                bad(format!(
                    "there is no device at position {position} (positions 0 to {} are served)",
                    segment.len().saturating_sub(1)
                ))
            })
        };
        let drive = |position: u16| {
            slave(position)?;
            segment
                .device::<EmulatedDrive>(usize::from(position))
                .ok_or_else(|| bad(format!("the device at position {position} is not a drive")))
        };
        let coe = |position: u16| {
            let s = slave(position)?;
            let has = s
                .device
                .description()
                .mailbox
                .is_some_and(|m| m.protocols.contains(super::sii::MailboxProtocols::COE));
            if has {
                Ok(())
            } else {
                Err(bad(format!(
                    "the device at position {position} has no CoE mailbox"
                )))
            }
        };
        Ok(match self.fault {
            FaultSpec::Link(l) => Fault::Link(l),
            FaultSpec::Reset { position } => {
                slave(position)?;
                Fault::Slave {
                    position,
                    fault: SlaveFault::ResetToInit,
                }
            }
            FaultSpec::Drift { position, ppb } => {
                if !slave(position)?.esc.config().dc.supported() {
                    return Err(bad(format!(
                        "the device at position {position} has no distributed clock"
                    )));
                }
                Fault::Slave {
                    position,
                    fault: SlaveFault::ClockDrift(ppb),
                }
            }
            FaultSpec::Alarm { position, ref id } => {
                let d = drive(position)?;
                let spec = d.spec();
                let Some(a) = spec.alarm(id) else {
                    let names: Vec<&str> = spec.alarms.iter().map(|a| a.id).collect();
                    return Err(bad(format!(
                        "the {} at position {position} has no alarm {id:?} (it has {})",
                        spec.name,
                        names.join(", ")
                    )));
                };
                Fault::Device {
                    position,
                    fault: DeviceFault::RaiseAlarm(a.id),
                }
            }
            FaultSpec::FollowingError { position, value } => {
                drive(position)?;
                Fault::Device {
                    position,
                    fault: DeviceFault::ForceFollowingError(Some(value)),
                }
            }
            FaultSpec::SdoAbort {
                position,
                index,
                subindex,
                code,
            } => {
                coe(position)?;
                Fault::Device {
                    position,
                    fault: DeviceFault::AbortSdo {
                        index,
                        subindex,
                        code,
                    },
                }
            }
            FaultSpec::EmergencyDuringSdo {
                position,
                error_code,
            } => {
                coe(position)?;
                Fault::Device {
                    position,
                    fault: DeviceFault::EmergencyDuringSdo {
                        error_code,
                        error_register: error_register(error_code),
                        data: [0; 5],
                    },
                }
            }
        })
    }
}

/// What to serve.
#[derive(Debug, Clone, PartialEq)]
pub struct SimOptions {
    /// Network interface.
    pub interface: String,
    /// Device names in line order (see [`devices::device_names`]).
    pub devices: Vec<String>,
    /// Reset value of the SM watchdog (0x0420) in watchdog units of 100 µs; `None` keeps the ESC
    /// reset value (1000 = 100 ms), `Some(0)` disables it.
    pub sm_watchdog: Option<u16>,
    /// Whether the emulated drives supervise the cyclic data (on, as real drives are
    /// delivered; off for masters on a host that cannot keep the cycle, see
    /// [`super::drives::EmulatedDrive::set_loss_detection`]).
    pub loss_detection: bool,
    /// Faults to inject, in any order.
    pub faults: Vec<ScheduledFault>,
    /// SCHED_FIFO priority of the serving thread (`None`: normal scheduling). An ESC answers
    /// in hardware time; at normal priority a loaded machine turns into lost frames.
    pub priority: Option<u8>,
    /// Pin the serving thread to this CPU.
    pub cpu: Option<usize>,
    /// Keep each device's EEPROM in this directory (`POS-NAME.sii`): loaded at start when
    /// there, saved when serving ends, so what a master wrote (a station alias, a whole SII)
    /// is still there after a restart, as on a device that was switched off and on.
    pub eeprom_dir: Option<std::path::PathBuf>,
    /// Positions whose EEPROM is write-protected (writes are not acknowledged).
    pub eeprom_write_protected: Vec<u16>,
}

/// The file of the device at `position` named `name` in an EEPROM directory.
pub fn eeprom_file(dir: &std::path::Path, position: usize, name: &str) -> std::path::PathBuf {
    let clean: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    dir.join(format!("{position}-{clean}.sii"))
}

/// Why a segment cannot be served.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// No device given.
    #[error("no devices given: name at least one with --device (known: {known})")]
    NoDevices {
        /// The known names.
        known: String,
    },
    /// A device name is unknown or cannot be built.
    #[error("device {position}: {source}")]
    Device {
        /// Position in the line (0-based).
        position: usize,
        /// Why.
        #[source]
        source: DeviceError,
    },
    /// The SII of a device cannot be built.
    #[error("device {position} ({name}): {source}")]
    Sii {
        /// Position in the line (0-based).
        position: usize,
        /// Device name.
        name: String,
        /// Why.
        #[source]
        source: SiiError,
    },
    /// A fault cannot be injected into these devices.
    #[error("{source_text}: {reason}")]
    Fault {
        /// The fault as the user wrote it.
        source_text: String,
        /// Why.
        reason: String,
    },
    /// Frame I/O failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// An EEPROM file cannot be read, used or written.
    #[error("EEPROM file {path}: {reason}")]
    Eeprom {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
}

/// Build a segment of named devices on the host clock.
pub fn build_segment(names: &[String], esc: &EscConfig) -> Result<Segment, SimError> {
    if names.is_empty() {
        return Err(SimError::NoDevices {
            known: devices::known_names(),
        });
    }
    let mut seg = Segment::new(Arc::new(HostClock));
    for (position, name) in names.iter().enumerate() {
        let dev = devices::by_name(name, position)
            .map_err(|source| SimError::Device { position, source })?;
        seg.push(dev, esc.clone()).map_err(|source| SimError::Sii {
            position,
            name: name.clone(),
            source,
        })?;
    }
    Ok(seg)
}

/// Load the EEPROM of each device from `dir` where its file is there (the directory is
/// created if missing).
fn load_eeproms(
    segment: &mut Segment,
    dir: &std::path::Path,
    names: &[String],
) -> Result<(), SimError> {
    std::fs::create_dir_all(dir).map_err(|e| SimError::Eeprom {
        path: dir.display().to_string(),
        reason: e.to_string(),
    })?;
    for (i, name) in names.iter().enumerate() {
        let path = eeprom_file(dir, i, name);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => {
                return Err(SimError::Eeprom {
                    path: path.display().to_string(),
                    reason: e.to_string(),
                });
            }
        };
        if let Some(s) = segment.slave_mut(i) {
            s.esc
                .load_eeprom(&bytes)
                .map_err(|reason| SimError::Eeprom {
                    path: path.display().to_string(),
                    reason,
                })?;
        }
    }
    Ok(())
}

/// A segment of named devices with its socket open, ready to serve.
#[derive(Debug)]
pub struct Prepared {
    socket: RawSocket,
    segment: Mutex<Segment>,
    /// Faults still to inject, by time.
    schedule: Vec<(Duration, Fault)>,
    handle: Option<FaultHandle>,
    eeprom_dir: Option<std::path::PathBuf>,
    names: Vec<String>,
}

/// Check the faults of `opts` against `segment`, apply the immediate ones and return the rest
/// by time.
pub fn plan_faults(
    segment: &mut Segment,
    faults: &[ScheduledFault],
) -> Result<Vec<(Duration, Fault)>, SimError> {
    let mut timed = Vec::new();
    let mut resolved = Vec::with_capacity(faults.len());
    for f in faults {
        resolved.push((f.at, f.resolve(segment)?, f));
    }
    // Cable pulls must alternate with reconnects.
    let mut cable: Vec<(Duration, bool, &ScheduledFault)> = resolved
        .iter()
        .filter_map(|(at, f, src)| match f {
            Fault::Link(LinkFault::Disconnect) => Some((*at, true, *src)),
            Fault::Link(LinkFault::Reconnect) => Some((*at, false, *src)),
            _ => None,
        })
        .collect();
    cable.sort_by_key(|c| c.0);
    let mut pulled = false;
    for (_, pull, src) in cable {
        if pull == pulled {
            return Err(SimError::Fault {
                source_text: src.source.clone(),
                reason: if pull {
                    "the cable is already pulled then (add a --reconnect-at before it)".into()
                } else {
                    "the cable is not pulled then (add a --disconnect-at before it)".into()
                },
            });
        }
        pulled = pull;
    }
    // Settings first (seed, where drops happen, what corruption does), so that a fault at the
    // same time uses them.
    let order = |f: &Fault| match f {
        Fault::Link(LinkFault::Seed(_) | LinkFault::DropOn(_) | LinkFault::CorruptWith(_)) => 0,
        _ => 1,
    };
    resolved.sort_by_key(|(at, f, _)| (*at, order(f)));
    for (at, f, _) in resolved {
        if at.is_zero() {
            segment.apply(&f);
        } else {
            timed.push((at, f));
        }
    }
    Ok(timed)
}

impl Prepared {
    /// Build the devices of `opts` and open its interface (needs `CAP_NET_RAW`).
    pub fn new(opts: &SimOptions) -> Result<Self, SimError> {
        let mut esc = EscConfig::default();
        if let Some(wd) = opts.sm_watchdog {
            esc.sm_watchdog = wd;
        }
        let mut segment = build_segment(&opts.devices, &esc)?;
        if !opts.loss_detection {
            super::drives::set_loss_detection(&mut segment, false);
        }
        for &p in &opts.eeprom_write_protected {
            let n = segment.len();
            let s = segment
                .slave_mut(usize::from(p))
                .ok_or_else(|| SimError::Fault {
                    source_text: format!("--eeprom-write-protect {p}"),
                    reason: format!("no device at position {p} (0–{})", n.saturating_sub(1)),
                })?;
            s.esc.set_eeprom_write_protected(true);
        }
        if let Some(dir) = &opts.eeprom_dir {
            load_eeproms(&mut segment, dir, &opts.devices)?;
        }
        let schedule = plan_faults(&mut segment, &opts.faults)?;
        let handle = (!schedule.is_empty()).then(|| segment.fault_handle());
        let socket = RawSocket::open(&opts.interface)?;
        Ok(Self {
            socket,
            segment: Mutex::new(segment),
            schedule,
            handle,
            eeprom_dir: opts.eeprom_dir.clone(),
            names: opts.devices.clone(),
        })
    }

    /// Save every device's EEPROM into the EEPROM directory, if one was given; returns the
    /// files written.
    pub fn save_eeproms(&self) -> Result<Vec<std::path::PathBuf>, SimError> {
        let Some(dir) = &self.eeprom_dir else {
            return Ok(Vec::new());
        };
        let seg = super::transport::lock(&self.segment);
        let mut out = Vec::new();
        for (i, (s, name)) in seg.slaves().iter().zip(&self.names).enumerate() {
            let path = eeprom_file(dir, i, name);
            std::fs::write(&path, s.esc.sii().bytes()).map_err(|e| SimError::Eeprom {
                path: path.display().to_string(),
                reason: e.to_string(),
            })?;
            out.push(path);
        }
        Ok(out)
    }

    /// The segment's counters (frames, injected faults).
    pub fn segment_stats(&self) -> SegmentStats {
        super::transport::lock(&self.segment).stats()
    }

    /// One line per device: position, name and identity.
    pub fn describe(&self) -> Vec<String> {
        let seg = super::transport::lock(&self.segment);
        seg.slaves()
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let d = s.device.description();
                format!(
                    "{i}: {} ({}) vendor 0x{:08X} product 0x{:08X} revision 0x{:08X} serial {}",
                    d.order,
                    d.name,
                    d.identity.vendor_id,
                    d.identity.product_code,
                    d.identity.revision,
                    d.identity.serial
                )
            })
            .collect()
    }

    /// Serve until `stop` is set, injecting the scheduled faults at their times (counted from
    /// now).
    pub fn serve(&mut self, stop: &AtomicBool) -> Result<ServeStats, SimError> {
        self.serve_rt(stop, &crate::rt::RtSettings::default())
    }

    /// [`serve`](Self::serve) with the calling thread set up as `rt` says (priority, CPU);
    /// what could not be granted is logged as a warning.
    pub fn serve_rt(
        &mut self,
        stop: &AtomicBool,
        rt: &crate::rt::RtSettings,
    ) -> Result<ServeStats, SimError> {
        let got = rt.apply_to_current_thread();
        for w in &got.warnings {
            tracing::warn!("{w}");
        }
        let start = Instant::now();
        let done = AtomicBool::new(false);
        let schedule = std::mem::take(&mut self.schedule);
        let handle = self.handle.take();
        let (socket, segment) = (&self.socket, &self.segment);
        let r = std::thread::scope(|s| {
            if let Some(h) = handle {
                let done = &done;
                std::thread::Builder::new()
                    .name("ecdrive-sim-faults".into())
                    .spawn_scoped(s, move || inject_on_time(h, &schedule, start, stop, done))
                    .map_err(|e| {
                        LinkError::Peer(format!("cannot start the fault scheduler: {e}"))
                    })?;
            }
            let r = serve(socket, segment, stop);
            done.store(true, Ordering::Release);
            r
        });
        Ok(r?)
    }
}

/// Inject each fault at its time after `start` until `stop` or `done`.
fn inject_on_time(
    mut handle: FaultHandle,
    schedule: &[(Duration, Fault)],
    start: Instant,
    stop: &AtomicBool,
    done: &AtomicBool,
) {
    let quit = || stop.load(Ordering::Acquire) || done.load(Ordering::Acquire);
    for (at, fault) in schedule {
        loop {
            if quit() {
                return;
            }
            let left = at.saturating_sub(start.elapsed());
            if left.is_zero() {
                break;
            }
            std::thread::sleep(left.min(Duration::from_millis(50)));
        }
        // The segment applies faults at every frame and at least every 10 ms: the queue
        // empties quickly; retry while it is full.
        while handle.inject(*fault).is_err() {
            if quit() {
                return;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

/// Serve the devices of `opts` on its interface until `stop` is set.
pub fn serve_interface(opts: &SimOptions, stop: &AtomicBool) -> Result<ServeStats, SimError> {
    Prepared::new(opts)?.serve_rt(
        stop,
        &crate::rt::RtSettings {
            priority: opts.priority,
            cpu: opts.cpu,
            lock_memory: false,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_and_missing_devices_are_named() {
        let e = build_segment(&[], &EscConfig::default()).unwrap_err();
        assert!(e.to_string().contains("generic-coe"), "{e}");
        let names = vec!["generic-io".to_string(), "nope".to_string()];
        let e = build_segment(&names, &EscConfig::default()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("device 1: unknown device \"nope\""),
            "{e}"
        );
        let names = vec!["generic-coe".to_string(), "generic-io".to_string()];
        let seg = build_segment(&names, &EscConfig::default()).unwrap();
        assert_eq!(seg.len(), 2);
    }
}
