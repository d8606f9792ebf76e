//! `ecdrive graph`: the segment's topology — which port of which device connects to which —
//! as Graphviz DOT (or data), with each device's identity and state.
//!
//! Like `diag` it does no discovery, so the segment's state is untouched: per device (by
//! auto-increment position) it reads the DL status (0x0110: which ports are open), the AL
//! status (0x0130) and the identity words of the SII EEPROM (vendor, product, revision at words
//! 0x0008–0x000D, through the EEPROM interface 0x0502–0x050B).
//!
//! The topology follows from the positions and the open ports: a frame enters each device on
//! port 0, and the ESC forwards it through its open ports in the order 3, 1, 2 (port 0 last,
//! back towards the master). So the device after `k` in position order hangs on `k`'s first
//! open port in that order, its subtree follows, then the next open port's (ETG.1000.4, the
//! ESC frame processing order; the same rule SOEM and IgH use).

use super::diag::DeviceDiag;
#[cfg(test)]
use super::diag::decode;
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::MasterError;
use serde::Serialize;
use std::fmt::Write as _;

/// One device.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Node {
    /// Position on the segment.
    pub position: u16,
    /// The drive profile its identity matches, if any.
    pub profile: Option<String>,
    /// Vendor ID (SII word 0x0008).
    pub vendor_id: u32,
    /// Product code (SII word 0x000A).
    pub product_code: u32,
    /// Revision (SII word 0x000C).
    pub revision: u32,
    /// AL state.
    pub al_state: String,
    /// Ports that are open (a neighbour is connected).
    pub open_ports: Vec<u8>,
}

/// One cable: `from`'s port to `to`'s port (`from` is `None` for the master).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Link {
    /// The device nearer the master (`None`: the master).
    pub from: Option<u16>,
    /// Its port (`None` for the master).
    pub from_port: Option<u8>,
    /// The device further away.
    pub to: u16,
    /// Its port (0: frames enter a device on port 0).
    pub to_port: u8,
}

/// The topology.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Graph {
    /// Devices in position order.
    pub nodes: Vec<Node>,
    /// Cables.
    pub links: Vec<Link>,
    /// Open ports that lead to no device read (a cable to nothing, or more devices than
    /// answered), as `(position, port)`.
    pub dangling: Vec<(u16, u8)>,
}

/// The cables, from each device's open ports in position order.
pub fn topology(devices: &[DeviceDiag]) -> (Vec<Link>, Vec<(u16, u8)>) {
    fn attach(
        devs: &[DeviceDiag],
        parent: usize,
        next: &mut usize,
        links: &mut Vec<Link>,
        dangling: &mut Vec<(u16, u8)>,
    ) {
        let Some(d) = devs.get(parent) else {
            return;
        };
        for port in [3u8, 1, 2] {
            let open = d.ports.get(usize::from(port)).is_some_and(|p| p.open());
            if !open {
                continue;
            }
            if *next >= devs.len() {
                dangling.push((d.position, port));
                continue;
            }
            let child = *next;
            *next += 1;
            links.push(Link {
                from: Some(d.position),
                from_port: Some(port),
                to: devs[child].position,
                to_port: 0,
            });
            attach(devs, child, next, links, dangling);
        }
    }
    let mut links = Vec::new();
    let mut dangling = Vec::new();
    if let Some(first) = devices.first() {
        links.push(Link {
            from: None,
            from_port: None,
            to: first.position,
            to_port: 0,
        });
        let mut next = 1;
        attach(devices, 0, &mut next, &mut links, &mut dangling);
        // Devices that no open port leads to (inconsistent DL status): hang them on the
        // master's side of the previous one so that none is lost from the picture.
        while next < devices.len() {
            links.push(Link {
                from: devices.get(next - 1).map(|d| d.position),
                from_port: None,
                to: devices[next].position,
                to_port: 0,
            });
            next += 1;
        }
    }
    (links, dangling)
}

/// Read the topology of the segment.
pub fn graph<L: FrameLink>(bus: &mut Bus<'_, L>) -> Result<Graph, MasterError> {
    let report = super::diag::diag(bus, None, false)?;
    let mut nodes = Vec::with_capacity(report.devices.len());
    for d in &report.devices {
        let p = d.position;
        let vendor_id = super::eeprom::read_u32(bus, p, 0x0008)?;
        let product_code = super::eeprom::read_u32(bus, p, 0x000A)?;
        let revision = super::eeprom::read_u32(bus, p, 0x000C)?;
        nodes.push(Node {
            position: p,
            profile: crate::drives::by_identity(vendor_id, product_code)
                .map(|x| x.name.to_string()),
            vendor_id,
            product_code,
            revision,
            al_state: d.al_state.clone(),
            open_ports: d
                .ports
                .iter()
                .filter(|x| x.open())
                .map(|x| x.port)
                .collect(),
        });
    }
    let (links, dangling) = topology(&report.devices);
    Ok(Graph {
        nodes,
        links,
        dangling,
    })
}

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

impl Graph {
    /// The topology as Graphviz DOT (`dot -Tsvg` draws it).
    pub fn dot(&self, master: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "graph ecdrive {{");
        let _ = writeln!(s, "  rankdir=LR;");
        let _ = writeln!(s, "  node [shape=box, fontname=\"sans-serif\"];");
        let _ = writeln!(
            s,
            "  master [label=\"master\\n{}\", shape=ellipse];",
            esc(master)
        );
        for n in &self.nodes {
            let name = n.profile.clone().unwrap_or_else(|| "device".into());
            let _ = writeln!(
                s,
                "  d{} [label=\"{}: {}\\nvendor 0x{:08X} product 0x{:08X}\\nrevision 0x{:08X}\\n{}\"];",
                n.position,
                n.position,
                esc(&name),
                n.vendor_id,
                n.product_code,
                n.revision,
                esc(&n.al_state)
            );
        }
        for l in &self.links {
            let from = l.from.map_or("master".to_string(), |p| format!("d{p}"));
            let tail = l
                .from_port
                .map_or(String::new(), |p| format!("taillabel=\"{p}\", "));
            let _ = writeln!(
                s,
                "  {from} -- d{} [{tail}headlabel=\"{}\"];",
                l.to, l.to_port
            );
        }
        for (i, (p, port)) in self.dangling.iter().enumerate() {
            let _ = writeln!(
                s,
                "  open{i} [label=\"open port, no device\", shape=plaintext];\n  d{p} -- open{i} [taillabel=\"{port}\", style=dashed];"
            );
        }
        s.push_str("}\n");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dev(position: u16, open: &[u8]) -> DeviceDiag {
        // Communication on open ports, loop closed on the others.
        let mut dl: u16 = 0;
        for p in 0..4u16 {
            if open.contains(&(p as u8)) {
                dl |= (1 << (4 + p)) | (1 << (9 + 2 * p));
            } else {
                dl |= 1 << (8 + 2 * p);
            }
        }
        decode(position, 0, dl, 1, &[])
    }

    #[test]
    fn a_line_and_a_branch() {
        // A line of three.
        let (l, d) = topology(&[dev(0, &[0, 1]), dev(1, &[0, 1]), dev(2, &[0])]);
        assert!(d.is_empty());
        let pairs: Vec<_> = l.iter().map(|l| (l.from, l.from_port, l.to)).collect();
        assert_eq!(
            pairs,
            [
                (None, None, 0),
                (Some(0), Some(1), 1),
                (Some(1), Some(1), 2)
            ]
        );
        // A coupler with ports 0, 1 and 3: port 3 comes first (its branch: devices 1, 2),
        // then port 1 (device 3).
        let (l, _) = topology(&[
            dev(0, &[0, 1, 3]),
            dev(1, &[0, 1]),
            dev(2, &[0]),
            dev(3, &[0]),
        ]);
        let pairs: Vec<_> = l.iter().map(|l| (l.from, l.from_port, l.to)).collect();
        assert_eq!(
            pairs,
            [
                (None, None, 0),
                (Some(0), Some(3), 1),
                (Some(1), Some(1), 2),
                (Some(0), Some(1), 3)
            ]
        );
        // An open port with nothing after it.
        let (_, d) = topology(&[dev(0, &[0, 1])]);
        assert_eq!(d, [(0, 1)]);
    }
}
