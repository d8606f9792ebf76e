//! The library side of the `ecdrive` commands (`master::tools`) against emulated devices
//! in-process: no root, no interface.

use ecdrive::master::tools::{self, Target};

fn sim(devices: &str) -> Target {
    format!("sim:{devices}").parse().unwrap()
}

#[test]
fn slaves_lists_identity_and_mailbox() {
    let s = tools::session(&sim("generic-coe,generic-io"), |bus| {
        tools::slaves(bus, true)
    })
    .unwrap();
    println!("{s:#?}");
    assert_eq!(s.len(), 2);
}
