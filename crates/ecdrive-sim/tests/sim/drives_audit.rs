//! The emulated drives' cyclic path allocates nothing: once in OP and enabled, `Device::sync`
//! (outputs in, state machine, motion, supervision, feedback out) runs allocation-free, also
//! when outputs go missing, an alarm is raised with its EMCY, and the fault is reset.

use crate::support::wire;

use ecdrive_core::drives::{bdhde, mr_j4_tm};
use ecdrive_core::ec::AlState;
use ecdrive_core::rt::audit::{alloc_window_begin, alloc_window_end};
use ecdrive_sim::Device;
use ecdrive_sim::device::{SyncEvent, SyncKind};
use ecdrive_sim::drives::EmulatedDrive;
use wire::{Wire, cyclic};

#[test]
fn cyclic_path_does_not_allocate() {
    for p in [&mr_j4_tm::PROFILE, &bdhde::PROFILE] {
        // In OP and Operation enabled in csp through the wire, then the drive alone.
        let mut w = Wire::op_cyclic(&[p], 1_000_000);
        let pos = cyclic::position(w.inputs(0));
        let o = w.outputs_mut(0);
        cyclic::set_mode(o, 8);
        cyclic::set_target(o, pos);
        for cw in [0x0006, 0x0007, 0x000F] {
            w.command(0, cw);
        }
        let mut outputs = w.outputs_mut(0).to_vec();
        let mut inputs = vec![0u8; w.inputs(0).len()];
        let d: &mut EmulatedDrive = w.drive(0);
        let mut event = SyncEvent {
            kind: SyncKind::Sync0,
            time_ns: 0,
            cycle: 0,
            cycle_time_ns: 1_000_000,
            state: AlState::Op,
            outputs_received: 1,
            last_outputs_ns: Some(0),
            outputs_enabled: true,
        };
        let alarm = if p.key == "bdhde" { "J3" } else { "AL.10" };
        alloc_window_begin();
        let mut target = pos;
        for k in 0..2_000u64 {
            event.cycle = k;
            event.time_ns = k * 1_000_000;
            // Lost outputs now and then (fewer than the loss threshold).
            event.outputs_received = u32::from(k % 10 != 3);
            target = target.wrapping_add(1000);
            cyclic::set_target(&mut outputs, target);
            let cw: u16 = match k {
                500 => {
                    let _ = d.raise_alarm(alarm);
                    0x000F
                }
                600 => 0x0000,
                601 => 0x0080,
                602 => 0x0006,
                603 => 0x0007,
                604.. => 0x000F,
                _ => 0x000F,
            };
            cyclic::set_cw(&mut outputs, cw);
            d.sync(&event, &outputs, &mut inputs).unwrap();
        }
        let counts = alloc_window_end();
        assert_eq!(counts.allocs, 0, "{}: {counts:?}", p.name);
        assert_eq!(counts.frees, 0, "{}: {counts:?}", p.name);
        // The window saw real work: a fault, its EMCY, a reset, motion.
        let s = d.stats();
        assert!(s.alarms >= 1 && s.resets >= 1, "{}: {s:?}", p.name);
        assert!(s.emergencies >= 2);
        assert!(s.missed_outputs >= 100);
        assert_eq!(d.state(), ecdrive_core::cia402::State::OperationEnabled);
    }
}
