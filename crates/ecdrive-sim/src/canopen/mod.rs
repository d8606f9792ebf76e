//! Emulated CANopen drives on the virtual bus.
//!
//! - [`EmulatedNode`]: one drive, generic, with all drive differences taken from its
//!   [`NodeSpec`] ([`node`]): the emulator's own tables for the BLV-R, ASDA-A2 and Lexium
//!   MDrive ([`drives`]), or a vendor's EDS file ([`eds_node`]) — never the master's profiles.
//! - [`SdoServer`]: the SDO server of a node, over the same object store as the CoE server.
//! - [`motion`]: the drive side of pp, pv, tq, hm, ip and a simple motor.
//! - [`SimBus`]: the deterministic in-process world: a [`Hub`] with the master's port and one
//!   port per node, and a **simulated clock** that advances only while the master waits in
//!   [`CanTransport::recv`]. Tests and the demo run on it without threads and without sleeping.
//! - [`serve`]: runs nodes in real time on any transport (another thread's [`VirtualPort`], the
//!   cross-process `UnixBusPort` of the CANopen master, even SocketCAN).
//!
//! [`VirtualPort`]: crate::can::transport::VirtualPort

pub mod drives;
pub mod eds_node;
pub mod motion;
pub mod node;
pub mod quirks;
pub mod sdo_server;
pub mod spec;

pub use motion::World;
pub use node::{EmuError, EmulatedNode, NodeStats};
pub use sdo_server::SdoServer;
pub use spec::NodeSpec;

use crate::can::frame::CanFrame;
use crate::can::transport::{CanTransport, Hub, PortId, TransportError};

/// **\[REC\]** Step of the simulated clock: nodes run every 250 µs of simulated time (the BLV-R's
/// SYNC granularity).
pub const SIM_TICK_US: u64 = 250;

/// **\[REC\]** Frames moved in one delivery round before the world assumes a loop.
const MAX_DELIVERIES: usize = 100_000;

/// One frame the master put on the bus, with the simulated time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TraceEntry {
    /// Simulated time, µs.
    pub time_us: u64,
    /// The frame.
    pub frame: CanFrame,
}

/// The in-process simulated bus with emulated nodes. Implements [`CanTransport`] for the
/// master's side; its clock is simulated (see the [module documentation](self)).
#[derive(Debug, Clone)]
pub struct SimBus {
    hub: Hub,
    master: PortId,
    nodes: Vec<(PortId, EmulatedNode)>,
    now_us: u64,
    tick_us: u64,
    trace: Option<Vec<TraceEntry>>,
    name: String,
}

impl Default for SimBus {
    fn default() -> Self {
        Self::new()
    }
}

impl SimBus {
    /// An empty bus at simulated time 0.
    pub fn new() -> Self {
        let mut hub = Hub::default();
        let master = hub.attach();
        Self {
            hub,
            master,
            nodes: Vec::new(),
            now_us: 0,
            tick_us: SIM_TICK_US,
            trace: None,
            name: "virtual".to_string(),
        }
    }

    /// The same with another tick (µs, at least 1).
    pub fn with_tick(mut self, tick_us: u64) -> Self {
        self.tick_us = tick_us.max(1);
        self
    }

    /// Attach a node and power it on now (it sends its boot-up message).
    pub fn add_node(&mut self, mut node: EmulatedNode) {
        let port = self.hub.attach();
        node.power_on(self.now_us);
        self.nodes.push((port, node));
        self.deliver();
    }

    /// The node with `id`.
    pub fn node(&self, id: u8) -> Option<&EmulatedNode> {
        self.nodes.iter().map(|(_, n)| n).find(|n| n.id() == id)
    }

    /// The node with `id`, mutably (fault injection, inputs).
    pub fn node_mut(&mut self, id: u8) -> Option<&mut EmulatedNode> {
        self.nodes.iter_mut().map(|(_, n)| n).find(|n| n.id() == id)
    }

    /// Every node.
    pub fn nodes(&self) -> impl Iterator<Item = &EmulatedNode> {
        self.nodes.iter().map(|(_, n)| n)
    }

    /// Remove a node from the bus (its frames stop: a cable pulled).
    pub fn remove_node(&mut self, id: u8) -> Option<EmulatedNode> {
        let pos = self.nodes.iter().position(|(_, n)| n.id() == id)?;
        let (port, node) = self.nodes.remove(pos);
        self.hub.detach(port);
        Some(node)
    }

    /// Put `frame` on the bus from a device outside the simulation (a foreign node, a faulty
    /// one): the master and every node receive it.
    pub fn inject(&mut self, frame: &CanFrame) {
        let outsider = self.hub.attach();
        self.hub.send(outsider, frame);
        self.hub.detach(outsider);
        self.deliver();
    }

    /// Record every frame the master sends (for timing checks).
    pub fn set_trace(&mut self, on: bool) {
        self.trace = on.then(Vec::new);
    }

    /// The recorded frames.
    pub fn trace(&self) -> &[TraceEntry] {
        self.trace.as_deref().unwrap_or(&[])
    }

    /// Let `us` microseconds of simulated time pass (nodes run; frames for the master queue).
    pub fn advance(&mut self, us: u64) {
        let end = self.now_us.saturating_add(us);
        while self.now_us < end {
            let step = self.tick_us.min(end - self.now_us);
            self.step(step);
        }
    }

    fn step(&mut self, us: u64) {
        self.now_us = self.now_us.saturating_add(us);
        let now = self.now_us;
        for (_, n) in &mut self.nodes {
            n.tick(now);
        }
        self.deliver();
    }

    /// Move frames between the ports until nothing moves.
    fn deliver(&mut self) {
        let now = self.now_us;
        for _ in 0..MAX_DELIVERIES {
            let mut moved = false;
            for i in 0..self.nodes.len() {
                let Some((port, _)) = self.nodes.get(i) else {
                    continue;
                };
                let port = *port;
                while let Some(f) = self.hub.recv(port) {
                    if let Some((_, n)) = self.nodes.get_mut(i) {
                        n.receive(&f, now);
                    }
                    moved = true;
                }
                loop {
                    let out = self.nodes.get_mut(i).and_then(|(_, n)| n.poll_transmit());
                    let Some(f) = out else { break };
                    self.hub.send(port, &f);
                    moved = true;
                }
            }
            if !moved {
                return;
            }
        }
    }
}

impl CanTransport for SimBus {
    fn name(&self) -> &str {
        &self.name
    }

    fn now_us(&self) -> u64 {
        self.now_us
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        if let Some(t) = &mut self.trace {
            t.push(TraceEntry {
                time_us: self.now_us,
                frame: *frame,
            });
        }
        self.hub.send(self.master, frame);
        self.deliver();
        Ok(())
    }

    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        let end = self.now_us.saturating_add(timeout_us);
        loop {
            self.deliver();
            if let Some(f) = self.hub.recv(self.master) {
                return Ok(Some(f));
            }
            if self.now_us >= end {
                return Ok(None);
            }
            let step = self.tick_us.min(end - self.now_us);
            self.step(step);
        }
    }
}

/// Run `nodes` in real time on `transport` until `keep_going` returns false: frames from the bus
/// go to every node, frames from a node go to the bus and to the other nodes here, and the nodes
/// tick every `tick_us` of the transport's clock. For the node side of a cross-process test or a
/// stand-alone emulator. Transport errors end the loop and are returned.
pub fn serve(
    transport: &mut dyn CanTransport,
    nodes: &mut [EmulatedNode],
    tick_us: u64,
    mut keep_going: impl FnMut(&[EmulatedNode]) -> bool,
) -> Result<(), TransportError> {
    let now = transport.now_us();
    for n in nodes.iter_mut() {
        n.power_on(now);
    }
    let tick = tick_us.max(1);
    let mut next_tick = now;
    while keep_going(nodes) {
        // Outgoing frames: to the bus and to the other local nodes.
        for i in 0..nodes.len() {
            loop {
                let out = nodes.get_mut(i).and_then(EmulatedNode::poll_transmit);
                let Some(f) = out else { break };
                transport.send(&f)?;
                let now = transport.now_us();
                for (j, other) in nodes.iter_mut().enumerate() {
                    if j != i {
                        other.receive(&f, now);
                    }
                }
            }
        }
        let now = transport.now_us();
        let wait = next_tick.saturating_sub(now);
        // Each frame at the time it was on the bus (the sender's, on a vbus hub).
        if let Some((f, at)) = transport.recv_stamped(wait)? {
            for n in nodes.iter_mut() {
                n.receive(&f, at);
            }
        }
        let now = transport.now_us();
        if now >= next_tick {
            for n in nodes.iter_mut() {
                n.tick(now);
            }
            next_tick = now + tick;
        }
    }
    Ok(())
}
