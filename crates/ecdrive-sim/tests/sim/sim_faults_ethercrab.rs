//! Link faults as plain ethercrab sees them through `EthercrabLink` (in-process, host clock):
//! delayed replies still arrive, a dropped frame costs a retry, a pulled cable times out and
//! the segment answers again once it is back. Outcomes only, no timed assertions.

use ecdrive_sim::devices::IoDevice;
use ecdrive_sim::faults::{DropLeg, Fault, LinkFault};
use ecdrive_sim::transport::EthercrabLink;
use ecdrive_sim::{EscConfig, HostClock, Segment};
use ethercrab::std::ethercat_now;
use ethercrab::{
    MainDevice, MainDeviceConfig, PduStorage, RegisterAddress, RetryBehaviour, Timeouts,
};
use std::sync::Arc;
use std::time::Duration;

const DATA: usize = PduStorage::element_size(1100);

fn segment() -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for i in 0..3 {
        seg.push(
            Box::new(IoDevice::new(2, 4).with_serial(i)),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_through_delays_drops_and_a_cable_pull() {
    let storage: &'static PduStorage<16, DATA> = Box::leak(Box::new(PduStorage::new()));
    let (tx, rx, pdu_loop) = storage.try_split().unwrap();
    let mut seg = segment();
    // Every reply 1 ms late from the start.
    seg.apply(&Fault::Link(LinkFault::Delay {
        fraction: 1.0,
        delay_ns: 1_000_000,
    }));
    let link = EthercrabLink::spawn(seg, tx, rx).unwrap();
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        Timeouts {
            pdu: Duration::from_millis(1000),
            eeprom: Duration::from_millis(1000),
            ..Timeouts::default()
        },
        MainDeviceConfig {
            dc_static_sync_iterations: 10,
            retry_behaviour: RetryBehaviour::Count(1),
        },
    )));
    let group = md
        .init_single_group::<4, 32>(ethercat_now)
        .await
        .expect("init with every reply delayed");
    assert_eq!(group.len(), 3);
    {
        let s = link.segment().stats();
        assert!(s.delayed > 10, "{s:?}");
        assert_eq!(s.delayed, s.frames, "every reply was delayed: {s:?}");
    }
    link.segment().apply(&Fault::Link(LinkFault::Delay {
        fraction: 0.0,
        delay_ns: 0,
    }));
    let sd = group.subdevice(md, 1).expect("device 1");

    // One frame lost on the way back: the slaves saw it, ethercrab resends it.
    link.segment()
        .apply(&Fault::Link(LinkFault::DropOn(DropLeg::Return)));
    link.segment().apply(&Fault::Link(LinkFault::DropNext(1)));
    let addr: u16 = sd
        .register_read(RegisterAddress::ConfiguredStationAddress)
        .await
        .expect("read after one retry");
    assert_eq!(addr, 0x1001);
    assert_eq!(link.segment().stats().dropped_replies, 1);

    // Cable pulled: nothing answers, the retry too.
    link.segment().apply(&Fault::Link(LinkFault::Disconnect));
    let r = sd
        .register_read::<u16>(RegisterAddress::ConfiguredStationAddress)
        .await;
    assert!(r.is_err(), "{r:?}");
    assert!(link.lost() >= 2, "the request and its retry were lost");
    // Back: answers again.
    link.segment().apply(&Fault::Link(LinkFault::Reconnect));
    let addr: u16 = sd
        .register_read(RegisterAddress::ConfiguredStationAddress)
        .await
        .expect("read with the cable back");
    assert_eq!(addr, 0x1001);
    let seg = link.stop();
    assert!(seg.stats().lost_disconnected >= 2);
}
