//! `ecdrive diag`: the ESC error counters and the DL status of every device, read without
//! disturbing the segment, with the links that look broken named in words.
//!
//! Unlike the other commands, `diag` does no discovery (which would take every device to INIT):
//! it reads by auto-increment position (APRD), so it can run while another master cycles the
//! segment, and `--reset` clears only the counters. Per device it reads:
//!
//! | register | what |
//! |---|---|
//! | 0x0110 | DL status: per port physical link (b4+p), loop closed (b8+2p), communication (b9+2p) |
//! | 0x0130 | AL status (the device's state) |
//! | 0x0300 + 2p | invalid frames received on port p (not a valid EtherCAT frame) |
//! | 0x0301 + 2p | RX errors on port p (a bit error on the cable or in the PHY: CRC, symbol) |
//! | 0x0308 + p | forwarded RX errors on port p (a frame that an earlier device already marked as broken) |
//! | 0x030C | processing unit errors |
//! | 0x030D | PDI errors (the device's own processor and its ESC) |
//! | 0x0310 + p | lost links on port p |
//!
//! A write to 0x0300 clears 0x0300–0x030B; 0x030C, 0x030D and 0x0310–0x0313 clear
//! individually (ESC datasheets, Section II register description).
//!
//! Reading the counters ([`findings`]): RX errors at a device's port 0 that the devices before
//! it do not forward point at the cable into that device (or its port 0 PHY); forwarded errors
//! only say the damage happened upstream; lost links on a port say that port's link went down
//! (a loose connector, a pulled cable, a power cycle of the neighbour).

use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{ErrorKind, MasterError, bus_error};
use crate::master::exec::exec_error;
use ethercrab::Command;
use serde::Serialize;
use std::time::Duration;

/// How long one register access may take.
pub(super) const T_REG: Duration = Duration::from_millis(500);

/// The counters and link bits of one port.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PortDiag {
    /// Port number, 0–3.
    pub port: u8,
    /// A physical link is up (DL status b4+p).
    pub link: bool,
    /// The port is closed: the frame loops back inside the ESC (DL status b8+2p).
    pub loop_closed: bool,
    /// Communication established on the port (DL status b9+2p).
    pub communication: bool,
    /// Invalid frames received (0x0300 + 2p).
    pub invalid_frames: u8,
    /// RX errors (0x0301 + 2p).
    pub rx_errors: u8,
    /// Forwarded RX errors (0x0308 + p).
    pub forwarded_rx_errors: u8,
    /// Lost links (0x0310 + p).
    pub lost_links: u8,
}

impl PortDiag {
    /// Whether the port is open (a neighbour is connected): link and communication, not looped.
    pub fn open(&self) -> bool {
        self.communication && !self.loop_closed
    }
}

/// One device's counters.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DeviceDiag {
    /// Position on the segment (0 = next to the master).
    pub position: u16,
    /// Configured station address (0x0010), 0 if none was assigned.
    pub station_address: u16,
    /// AL state (0x0130 bits 0–3) as a name.
    pub al_state: String,
    /// Whether the device reports an AL error (0x0130 bit 4).
    pub al_error: bool,
    /// DL status register, raw.
    pub dl_status: u16,
    /// Ports 0–3.
    pub ports: Vec<PortDiag>,
    /// Processing unit errors (0x030C).
    pub processing_unit_errors: u8,
    /// PDI errors (0x030D).
    pub pdi_errors: u8,
}

/// What `ecdrive diag` reports.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DiagReport {
    /// Devices on the segment.
    pub device_count: u16,
    /// The devices read (all, or the one asked for), counters as read (before a reset).
    pub devices: Vec<DeviceDiag>,
    /// The links that look broken, in words; empty when every counter is 0.
    pub findings: Vec<String>,
    /// Whether the counters were cleared after reading.
    pub reset: bool,
}

fn al_name(v: u8) -> String {
    match v & 0x0F {
        1 => "INIT".into(),
        2 => "PRE-OP".into(),
        3 => "BOOT".into(),
        4 => "SAFE-OP".into(),
        8 => "OP".into(),
        x => format!("0x{x:X}"),
    }
}

/// Decode a device's registers: DL status, AL status, 0x0300–0x0313 (20 bytes).
pub fn decode(position: u16, station: u16, dl: u16, al: u8, c: &[u8]) -> DeviceDiag {
    let at = |i: usize| c.get(i).copied().unwrap_or(0);
    let ports = (0..4u8)
        .map(|p| {
            let i = usize::from(p);
            PortDiag {
                port: p,
                link: dl & (1 << (4 + i)) != 0,
                loop_closed: dl & (1 << (8 + 2 * i)) != 0,
                communication: dl & (1 << (9 + 2 * i)) != 0,
                invalid_frames: at(2 * i),
                rx_errors: at(2 * i + 1),
                forwarded_rx_errors: at(8 + i),
                lost_links: at(0x10 + i),
            }
        })
        .collect();
    DeviceDiag {
        position,
        station_address: station,
        al_state: al_name(al),
        al_error: al & 0x10 != 0,
        dl_status: dl,
        ports,
        processing_unit_errors: at(0x0C),
        pdi_errors: at(0x0D),
    }
}

/// The links that look broken, in words, from the counters of every device in line order.
pub fn findings(devices: &[DeviceDiag]) -> Vec<String> {
    let mut out = Vec::new();
    for (k, d) in devices.iter().enumerate() {
        let upstream = if k == 0 {
            "the master".to_string()
        } else {
            format!("device {}", k - 1)
        };
        for p in &d.ports {
            if p.rx_errors > 0 || p.invalid_frames > 0 {
                let into = if p.port == 0 {
                    format!("the cable from {upstream} into device {}", d.position)
                } else {
                    format!("the cable on device {}'s port {}", d.position, p.port)
                };
                out.push(format!(
                    "device {} port {}: {} RX error(s), {} invalid frame(s) received here: \
                     {into} (or that port's connector or PHY) corrupts frames",
                    d.position, p.port, p.rx_errors, p.invalid_frames
                ));
            }
            if p.lost_links > 0 {
                out.push(format!(
                    "device {} port {}: the link went down {} time(s) (a loose or pulled \
                     cable, or the neighbour lost power)",
                    d.position, p.port, p.lost_links
                ));
            }
        }
        if d.processing_unit_errors > 0 {
            out.push(format!(
                "device {}: {} processing unit error(s)",
                d.position, d.processing_unit_errors
            ));
        }
        if d.pdi_errors > 0 {
            out.push(format!(
                "device {}: {} PDI error(s) (between its ESC and its own processor)",
                d.position, d.pdi_errors
            ));
        }
    }
    // Forwarded errors alone are a consequence, not a cause: name them only when no device
    // counts an RX error (the cause is then outside what was read, e.g. before the first
    // device read with --position).
    let any_cause = devices
        .iter()
        .flat_map(|d| &d.ports)
        .any(|p| p.rx_errors > 0 || p.invalid_frames > 0);
    if !any_cause
        && let Some(d) = devices
            .iter()
            .find(|d| d.ports.iter().any(|p| p.forwarded_rx_errors > 0))
    {
        out.push(format!(
            "device {} saw frames already marked as broken: the damage happened before it",
            d.position
        ));
    }
    out
}

fn count_devices<L: FrameLink>(bus: &mut Bus<'_, L>) -> Result<u16, MasterError> {
    // APRD of the ESC type register, position by position: a position past the last device
    // comes back with working counter 0.
    let mut n: u16 = 0;
    loop {
        // ethercrab turns the position into the auto-increment address (−position).
        let address = n;
        let r = bus
            .block_on(
                &|| "counting the devices".to_string(),
                T_REG,
                |md| async move { Command::aprd(address, 0x0000).receive::<u8>(md).await },
            )
            .map_err(|e| exec_error(None, e))?;
        match r {
            Ok(_) => n += 1,
            Err(ethercrab::error::Error::WorkingCounter { .. }) => return Ok(n),
            Err(e) => return Err(bus_error(None, "counting the devices", e)),
        }
        if n == u16::MAX {
            return Ok(n);
        }
    }
}

/// Read `len` bytes of `register` of the device at `position` (APRD: no station address needed).
pub(super) fn aprd<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    register: u16,
    len: u16,
) -> Result<Vec<u8>, MasterError> {
    let step = format!("device {position}: reading register 0x{register:04X} ({len} bytes)");
    bus.block_on(&|| step.clone(), T_REG, |md| async move {
        Command::aprd(position, register)
            .receive_slice(md, len)
            .await
            .map(|b| b.to_vec())
    })
    .map_err(|e| exec_error(None, e))?
    .map_err(|e| bus_error(None, step.clone(), e))
}

/// Write `data` to `register` of the device at `position` (APWR).
pub(super) fn apwr<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    register: u16,
    data: &[u8],
) -> Result<(), MasterError> {
    let step = format!("device {position}: writing register 0x{register:04X}");
    bus.block_on(&|| step.clone(), T_REG, |md| async move {
        Command::apwr(position, register).send(md, data).await
    })
    .map_err(|e| exec_error(None, e))?
    .map_err(|e| bus_error(None, step.clone(), e))
}

/// Read the counters of every device (or the one at `position`), then clear them if `reset`.
pub fn diag<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: Option<u16>,
    reset: bool,
) -> Result<DiagReport, MasterError> {
    let count = count_devices(bus)?;
    let positions: Vec<u16> = match position {
        Some(p) if p >= count => return Err(super::out_of_range(p, usize::from(count))),
        Some(p) => vec![p],
        None => (0..count).collect(),
    };
    if count == 0 {
        return Err(MasterError::new(
            None,
            "reading the error counters",
            ErrorKind::Config,
            "the segment has no devices",
        ));
    }
    let mut devices = Vec::with_capacity(positions.len());
    for &p in &positions {
        let dl = aprd(bus, p, 0x0110, 2)?;
        let al = aprd(bus, p, 0x0130, 1)?;
        let station = aprd(bus, p, 0x0010, 2)?;
        let counters = aprd(bus, p, 0x0300, 0x14)?;
        let u16le = |b: &[u8]| {
            u16::from_le_bytes([
                b.first().copied().unwrap_or(0),
                b.get(1).copied().unwrap_or(0),
            ])
        };
        devices.push(decode(
            p,
            u16le(&station),
            u16le(&dl),
            al.first().copied().unwrap_or(0),
            &counters,
        ));
    }
    if reset {
        for &p in &positions {
            apwr(bus, p, 0x0300, &[0])?;
            apwr(bus, p, 0x030C, &[0; 2])?;
            apwr(bus, p, 0x0310, &[0; 4])?;
        }
    }
    let findings = findings(&devices);
    Ok(DiagReport {
        device_count: count,
        devices,
        findings,
        reset,
    })
}

impl DiagReport {
    /// The table `ecdrive diag` prints.
    pub fn text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{:>3} {:>7} {:<8} {:>4} {:<13} {:>7} {:>6} {:>9} {:>9} {:>4} {:>4}",
            "pos",
            "station",
            "state",
            "port",
            "link",
            "invalid",
            "rx err",
            "forwarded",
            "lost link",
            "PU",
            "PDI"
        );
        for d in &self.devices {
            for p in &d.ports {
                let link = match (p.link, p.loop_closed, p.communication) {
                    (_, false, true) => "open",
                    (true, true, _) => "link, looped",
                    (false, true, _) => "closed",
                    (true, false, false) => "link, no comm",
                    (false, false, false) => "down",
                };
                let first = p.port == 0;
                let _ = writeln!(
                    s,
                    "{:>3} {:>7} {:<8} {:>4} {:<13} {:>7} {:>6} {:>9} {:>9} {:>4} {:>4}",
                    if first {
                        d.position.to_string()
                    } else {
                        String::new()
                    },
                    if first {
                        format!("0x{:04X}", d.station_address)
                    } else {
                        String::new()
                    },
                    if first {
                        format!("{}{}", d.al_state, if d.al_error { " E" } else { "" })
                    } else {
                        String::new()
                    },
                    p.port,
                    link,
                    p.invalid_frames,
                    p.rx_errors,
                    p.forwarded_rx_errors,
                    p.lost_links,
                    if first {
                        d.processing_unit_errors.to_string()
                    } else {
                        String::new()
                    },
                    if first {
                        d.pdi_errors.to_string()
                    } else {
                        String::new()
                    },
                );
            }
        }
        if self.findings.is_empty() {
            let _ = writeln!(s, "no errors counted");
        }
        for f in &self.findings {
            let _ = writeln!(s, "{f}");
        }
        if self.reset {
            let _ = writeln!(s, "counters cleared");
        }
        s.trim_end().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_decode_and_the_broken_cable_is_named() {
        let mut c = [0u8; 20];
        c[1] = 5; // port 0 RX errors
        c[0x10] = 1; // port 0 lost link
        let d1 = decode(1, 0x1001, 0x0A33 | 0x5000, 8, &c);
        assert_eq!(d1.ports[0].rx_errors, 5);
        assert_eq!(d1.ports[0].lost_links, 1);
        assert!(d1.ports[0].open() && d1.ports[1].open());
        let mut f = [0u8; 20];
        f[8] = 5;
        let d2 = decode(2, 0x1002, 0x5613, 8, &f);
        let text = findings(&[decode(0, 0x1000, 0x5A33, 8, &[0; 20]), d1, d2]);
        assert!(
            text.iter()
                .any(|t| t.contains("device 1 port 0: 5 RX error") && t.contains("from device 0")),
            "{text:?}"
        );
        assert!(
            text.iter().any(|t| t.contains("went down 1 time")),
            "{text:?}"
        );
        // Device 2's forwarded errors are a consequence: not named on their own.
        assert_eq!(text.len(), 2, "{text:?}");
    }
}
