//! The three emulated CANopen drives on a cross-process virtual bus, for trying the master (or
//! `ecdrive … --can vbus:PATH`) against them from another process:
//!
//! ```text
//! cargo run --example canopen_emulator -- /tmp/ecdrive-can.sock [seconds]
//! ```
//!
//! Starts a hub at the path (replacing a stale socket), serves the BLV-R (node 1), the ASDA-A2
//! (7Fh) and the Lexium MDrive (41h) in real time, and ends after `seconds` (default 600).

use ecdrive::canopen::unix_bus::{UnixBusHub, UnixBusPort};
use ecdrive::sim::canopen::{self as emu, EmulatedNode};
use std::path::PathBuf;
use std::time::{Duration, Instant};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "/tmp/ecdrive-can.sock".into()),
    );
    let secs: u64 = match args.next() {
        Some(s) => s.parse()?,
        None => 600,
    };
    let _hub = UnixBusHub::spawn(&path)?;
    let mut port = UnixBusPort::connect(&path)?;
    let mut nodes = Vec::new();
    for (id, name) in [(1, "blv-r"), (0x7F, "asda-a2"), (0x41, "lexium-mdrive")] {
        nodes.push(EmulatedNode::new(
            ecdrive::sim::canopen::drives::by_name(name)
                .expect("the software slave emulates the drive"),
            id,
        )?);
    }
    println!(
        "virtual CAN bus at {}: {} nodes for {secs} s",
        path.display(),
        nodes.len()
    );
    for n in &nodes {
        println!("  node {} (0x{:02X}): {}", n.id(), n.id(), n.spec().name);
    }
    let end = Instant::now() + Duration::from_secs(secs);
    emu::serve(&mut port, &mut nodes, 250, |_| Instant::now() < end)?;
    Ok(())
}
