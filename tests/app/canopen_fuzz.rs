//! Garbage frames never panic: the parsers, the emulated nodes (any frame on any COB-ID, in any
//! NMT state) and the master (any frame arriving at any time, including as the answer to its
//! SDO requests). After garbage a node still boots and answers SDO.

use ecdrive::canopen::emcy::Emergency;
use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig};
use ecdrive::canopen::nmt::{ErrorControl, NmtCommand};
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::canopen::sdo::{SdoRequest, SdoResponse};
use ecdrive::canopen::{CanFrame, CanTransport, TransportError};
use ecdrive::drives::{asda_a2, blv_r, lexium_mdrive};
use ecdrive::ec::AlState;
use ecdrive::od::ObjectAddress;
use ecdrive::sim::canopen::SdoServer;
use ecdrive::sim::canopen::{EmulatedNode, SimBus};
use proptest::prelude::*;
use std::collections::VecDeque;

const PROFILES: [&CanDriveProfile; 3] =
    [&blv_r::PROFILE, &asda_a2::PROFILE, &lexium_mdrive::PROFILE];
const NODE: u8 = 5;

fn arb_id() -> impl Strategy<Value = u16> {
    prop_oneof![
        Just(0x000u16),
        Just(0x080),
        Just(0x600 + NODE as u16),
        Just(0x700 + NODE as u16),
        (1u16..=4).prop_map(|p| 0x100 + 0x100 * p + NODE as u16),
        (1u16..=4).prop_map(|p| 0x080 + 0x100 * p + NODE as u16),
        0u16..=0x7FF,
    ]
}

fn arb_frame() -> impl Strategy<Value = CanFrame> {
    (
        arb_id(),
        prop::collection::vec(any::<u8>(), 0..=8),
        any::<bool>(),
        0u8..=8,
    )
        .prop_map(|(id, data, rtr, dlc)| {
            if rtr {
                CanFrame::remote(id, dlc).unwrap()
            } else {
                CanFrame::new(id, &data).unwrap()
            }
        })
}

/// A transport that hands out scripted frames and answers nothing; time advances 100 µs per
/// receive.
struct Script {
    incoming: VecDeque<CanFrame>,
    now: u64,
}

impl CanTransport for Script {
    fn name(&self) -> &str {
        "script"
    }
    fn now_us(&self) -> u64 {
        self.now
    }
    fn send(&mut self, _: &CanFrame) -> Result<(), TransportError> {
        Ok(())
    }
    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        self.now += timeout_us.min(100);
        Ok(self.incoming.pop_front())
    }
}

/// The simulated bus with garbage mixed into what the master receives.
struct Noisy {
    bus: SimBus,
    garbage: VecDeque<CanFrame>,
    every: usize,
    n: usize,
}

impl CanTransport for Noisy {
    fn name(&self) -> &str {
        "noisy"
    }
    fn now_us(&self) -> u64 {
        self.bus.now_us()
    }
    fn send(&mut self, f: &CanFrame) -> Result<(), TransportError> {
        self.bus.send(f)
    }
    fn recv(&mut self, timeout_us: u64) -> Result<Option<CanFrame>, TransportError> {
        self.n += 1;
        if self.n % self.every == 0
            && let Some(f) = self.garbage.pop_front()
        {
            return Ok(Some(f));
        }
        self.bus.recv(timeout_us)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
    #[test]
    fn parsers_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..24)) {
        let _ = SdoRequest::parse(&bytes);
        let _ = SdoResponse::parse(&bytes);
        let _ = Emergency::parse(&bytes);
        let _ = CanFrame::from_record(&bytes);
        let mut server = SdoServer::new();
        let mut node = EmulatedNode::new(&ecdrive::sim::canopen::drives::blv_r::SPEC, NODE).unwrap();
        node.power_on(0);
        let _ = server.handle(&bytes, AlState::PreOp, &mut node);
        if let Ok(f) = CanFrame::new(0x700 + NODE as u16, bytes.get(..bytes.len().min(8)).unwrap_or(&[])) {
            let _ = ErrorControl::parse(&f);
            let _ = NmtCommand::parse(&f);
        }
    }

    #[test]
    fn nodes_survive_garbage(
        frames in prop::collection::vec(arb_frame(), 0..150),
        which in 0usize..3,
        start in any::<bool>(),
    ) {
        let p = PROFILES[which];
        let mut node = EmulatedNode::new(ecdrive_cli::app::canopen::tools::emulation_of(p).expect("the software slave emulates the drive"), NODE).unwrap();
        node.power_on(0);
        let mut t = 0u64;
        if start {
            node.receive(&NmtCommand::Start.frame(0), t);
        }
        for f in &frames {
            node.receive(f, t);
            t += 100;
            node.tick(t);
            while let Some(out) = node.poll_transmit() {
                prop_assert!(out.id() <= 0x7FF && out.dlc() <= 8);
            }
        }
        // Still alive: a reset brings the boot-up message, and SDO answers 1000h.
        node.receive(&NmtCommand::ResetNode.frame(NODE), t);
        let mut booted = false;
        while let Some(out) = node.poll_transmit() {
            booted |= out.id() == 0x700 + NODE as u16 && out.data() == [0];
        }
        prop_assert!(booted);
        t += 2_000;
        node.tick(t);
        while node.poll_transmit().is_some() {}
        let req = SdoRequest::initiate_upload(ObjectAddress::new(0x1000, 0));
        node.receive(&CanFrame::new(0x600 + NODE as u16, &req).unwrap(), t);
        let resp = std::iter::from_fn(|| node.poll_transmit())
            .find(|f| f.id() == 0x580 + NODE as u16)
            .unwrap();
        prop_assert_eq!(&resp.data()[4..8], &p.identity.device_type.to_le_bytes()[..]);
    }

    #[test]
    fn master_survives_garbage(frames in prop::collection::vec(arb_frame(), 0..150)) {
        let mut m = Master::new(
            Script { incoming: frames.into(), now: 0 },
            MasterConfig { sdo_timeout_us: 20_000, ..MasterConfig::default() },
        );
        m.set_profile(NODE, &blv_r::PROFILE);
        let _ = m.pump(5_000);
        let _ = m.probe(1..=127, 5_000);
        let _ = m.sdo_upload(NODE, ObjectAddress::new(0x1008, 0));
        let _ = m.sdo_download(NODE, ObjectAddress::new(0x1008, 0), &[1; 20]);
        let _ = m.nmt(NODE, NmtCommand::ResetNode);
        let _ = m.cycle();
        while m.poll_event().is_some() {}
    }

    #[test]
    fn a_running_drive_survives_garbage_at_the_master(
        frames in prop::collection::vec(arb_frame(), 1..60),
        every in 2usize..20,
    ) {
        let mut bus = SimBus::new();
        bus.add_node(EmulatedNode::new(&ecdrive::sim::canopen::drives::blv_r::SPEC, NODE).unwrap());
        let mut m = Master::new(
            Noisy { bus, garbage: VecDeque::new(), every, n: 0 },
            MasterConfig::default(),
        );
        m.pump(10_000).unwrap();
        m.configure_drive(NODE, DriveSetup::new(&blv_r::PROFILE)).unwrap();
        m.start(NODE).unwrap();
        m.transport_mut().garbage = frames.into();
        let _ = m.enable(NODE, 2_000_000);
        for _ in 0..100 {
            let r = m.cycle_step(|_| {});
            prop_assert!(r.is_ok(), "{:?}", r.err());
        }
        while m.poll_event().is_some() {}
    }
}
