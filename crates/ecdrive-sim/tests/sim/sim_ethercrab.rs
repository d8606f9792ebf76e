//! Acceptance: plain ethercrab (no ecdrive master code in between) against emulated segments,
//! in-process through `PduTx`/`PduRx` and over a veth pair with raw sockets.
//!
//! Each scenario: discover three devices, read identity, names and the EEPROM, bring them to
//! OP with DC SYNC0, exchange process data and check the working counter and the echoed data.

use ecdrive_core::link::netns::{VethPair, require_root};
use ecdrive_sim::devices::{GenericCoeDevice, IoDevice};
use ecdrive_sim::transport::{EthercrabLink, RawServer};
use ecdrive_sim::{EscConfig, HostClock, Segment};
use ethercrab::std::ethercat_now;
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{
    DcSync, MainDevice, MainDeviceConfig, PduStorage, RegisterAddress, SubIndex, Timeouts,
};
use std::sync::Arc;
use std::time::Duration;

const N: usize = 3;
const MAX_SUBDEVICES: usize = 8;
const MAX_PDI: usize = 64;
const DATA: usize = PduStorage::element_size(1100);

fn storage() -> &'static PduStorage<16, DATA> {
    Box::leak(Box::new(PduStorage::new()))
}

fn timeouts() -> Timeouts {
    Timeouts {
        // Generous: CI machines stall.
        pdu: Duration::from_millis(2000),
        state_transition: Duration::from_secs(10),
        eeprom: Duration::from_millis(500),
        mailbox_response: Duration::from_secs(2),
        mailbox_echo: Duration::from_secs(2),
        wait_loop_delay: Duration::from_millis(1),
    }
}

fn coe_segment() -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for i in 0..N {
        seg.push(
            Box::new(GenericCoeDevice::new(200 + i as u32).unwrap()),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

fn segment() -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for i in 0..N {
        seg.push(
            Box::new(IoDevice::new(2, 4).with_serial(100 + i as u32)),
            EscConfig {
                // The SM watchdog stays at its reset value except that scheduling hiccups
                // on a loaded CI machine must not drop the devices out of OP.
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

/// What the scenario learned, checked against the segment afterwards.
struct Outcome {
    eeprom: Vec<Vec<u8>>,
}

async fn scenario(md: &MainDevice<'static>) -> Outcome {
    let mut group = md
        .init_single_group::<MAX_SUBDEVICES, MAX_PDI>(ethercat_now)
        .await
        .expect("init");
    assert_eq!(group.len(), N);

    let mut eeprom = Vec::new();
    for (i, sd) in group.iter(md).enumerate() {
        let id = sd.identity();
        assert_eq!(id.vendor_id, 0x0000_0ECD);
        assert_eq!(id.product_id, 0x0000_0101);
        assert_eq!(id.revision, 0x0001_0000);
        assert_eq!(id.serial, 100 + i as u32);
        assert_eq!(sd.name(), "ECD-IO");
        assert_eq!(sd.configured_address(), 0x1000 + i as u16);
        assert!(sd.dc_support().any());
        let desc = sd.description().await.expect("description");
        assert_eq!(desc.as_deref(), Some("ecdrive generic I/O 2/4"));
        let size = sd.eeprom_size(md).await.expect("eeprom size");
        assert_eq!(size, 2048);
        let mut buf = vec![0u8; 256];
        let n = sd
            .eeprom_read_raw(md, 0, &mut buf)
            .await
            .expect("eeprom read");
        buf.truncate(n);
        eeprom.push(buf);
    }
    // The first device is the reference clock; all others got a propagation delay.
    let delays: Vec<u32> = group.iter(md).map(|sd| sd.propagation_delay()).collect();
    assert_eq!(delays[0], 0);
    assert!(delays[1] > 0 && delays[2] > delays[1], "{delays:?}");

    for mut sd in group.iter_mut(md) {
        sd.set_dc_sync(DcSync::Sync0);
    }
    let group = group.into_pre_op_pdi(md).await.expect("PRE-OP with PDI");
    for sd in group.iter(md) {
        let io = sd.io_raw();
        assert_eq!((io.inputs().len(), io.outputs().len()), (4, 2));
    }
    let group = group
        .configure_dc_sync(
            md,
            DcConfiguration {
                start_delay: Duration::from_millis(20),
                sync0_period: Duration::from_millis(1),
                sync0_shift: Duration::from_micros(500),
            },
        )
        .await
        .expect("DC sync");
    let group = group.into_safe_op(md).await.expect("SAFE-OP");
    let group = group.request_into_op(md).await.expect("request OP");

    // Cycle until every device is in OP.
    let mut in_op = false;
    for _ in 0..5_000 {
        let r = group.tx_rx_dc(md).await.expect("tx_rx_dc");
        if r.all_op() {
            in_op = true;
            break;
        }
        tokio::time::sleep(r.extra.next_cycle_wait).await;
    }
    assert!(in_op, "devices did not reach OP");

    // In OP: WKC = 3 per device (outputs written +2, inputs read +1). Every device echoes its
    // outputs into inputs 2..4 at SYNC0; the value shows up after a few cycles.
    let mut echoed = [false; N];
    for cycle in 0..2_000u32 {
        for (i, sd) in group.iter(md).enumerate() {
            let mut o = sd.outputs_raw_mut();
            o.copy_from_slice(&[0xA0 + i as u8, 0x5A]);
        }
        let r = group.tx_rx_dc(md).await.expect("tx_rx_dc");
        assert_eq!(r.working_counter, 3 * N as u16, "cycle {cycle}");
        assert!(r.all_op());
        for (i, sd) in group.iter(md).enumerate() {
            let inp = sd.inputs_raw();
            if inp[2..4] == [0xA0 + i as u8, 0x5A] {
                echoed[i] = true;
            }
        }
        if echoed.iter().all(|e| *e) && cycle >= 20 {
            break;
        }
        tokio::time::sleep(r.extra.next_cycle_wait).await;
    }
    assert_eq!(echoed, [true; N], "outputs echoed back through the devices");

    // The devices are synchronised: their system time difference is small.
    for sd in group.iter(md) {
        let diff: u32 = sd
            .register_read(RegisterAddress::DcSystemTimeDifference)
            .await
            .expect("0x092C");
        assert!(diff & 0x7FFF_FFFF < 100_000, "0x092C = {diff:#x}");
    }

    let group = group.into_safe_op(md).await.expect("back to SAFE-OP");
    let group = group.into_pre_op(md).await.expect("back to PRE-OP");
    let _ = group.into_init(md).await.expect("back to INIT");
    Outcome { eeprom }
}

fn check_segment(seg: &Segment, outcome: &Outcome) {
    for (i, ee) in outcome.eeprom.iter().enumerate() {
        let slave = seg.slave(i).unwrap();
        assert_eq!(
            &slave.esc.sii().bytes()[..ee.len()],
            &ee[..],
            "EEPROM of device {i}"
        );
        let dev = seg.device::<IoDevice>(i).unwrap();
        assert!(dev.seen.sync0_events > 0, "device {i} saw SYNC0");
        assert_eq!(dev.seen.sync0_cycle_ns, 1_000_000);
        assert_eq!(dev.seen.last_outputs, vec![0xA0 + i as u8, 0x5A]);
        assert_eq!(slave.esc.al_state(), ecdrive_core::ec::AlState::Init);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_in_process_dc_op() {
    let (tx, rx, pdu_loop) = storage().try_split().unwrap();
    let link = EthercrabLink::spawn(segment(), tx, rx).unwrap();
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: 200,
            ..MainDeviceConfig::default()
        },
    )));
    let outcome = scenario(md).await;
    let seg = link.stop();
    check_segment(&seg, &outcome);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_over_veth_dc_op() {
    if !require_root("sim_ethercrab::ethercrab_over_veth_dc_op") {
        return;
    }
    let veth = VethPair::create().expect("veth pair");
    let server =
        RawServer::spawn(veth.open_peer_socket().expect("peer socket"), segment()).expect("server");
    let (tx, rx, pdu_loop) = storage().try_split().unwrap();
    let task = ethercrab::std::tx_rx_task(veth.host(), tx, rx).expect("tx/rx task");
    let handle = tokio::spawn(task);
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: 200,
            ..MainDeviceConfig::default()
        },
    )));
    let outcome = scenario(md).await;
    handle.abort();
    let (seg, result) = server.stop();
    let stats = result.expect("server ran without I/O errors");
    assert!(stats.frames > 100);
    check_segment(&seg, &outcome);
}

/// CoE devices: identity over SII and SDO, PDO remapping in PRE-OP (csv mapping on all three),
/// DC SYNC0 with 0x1C32:01 = 2, the CiA 402 power state machine over process data, csv motion.
async fn coe_scenario(md: &MainDevice<'static>) -> Outcome {
    let mut group = md
        .init_single_group::<MAX_SUBDEVICES, MAX_PDI>(ethercat_now)
        .await
        .expect("init");
    assert_eq!(group.len(), N);
    let mut eeprom = Vec::new();
    for (i, sd) in group.iter(md).enumerate() {
        let id = sd.identity();
        assert_eq!((id.vendor_id, id.product_id), (0x0000_0ECD, 0x0000_0402));
        assert_eq!(id.serial, 200 + i as u32);
        assert_eq!(sd.name(), "ECD-COE402");
        // Identity over SDO agrees with the SII.
        let serial: u32 = sd.sdo_read(0x1018, 4).await.expect("0x1018:04");
        assert_eq!(serial, 200 + i as u32);
        let device_type: u32 = sd.sdo_read(0x1000, 0).await.expect("0x1000");
        assert_eq!(device_type, 0x0002_0192);
        // A normal (non-expedited) upload: 0x1C00 as an array.
        let types = sd.sdo_read_array::<u8, 8>(0x1C00).await.expect("0x1C00");
        assert_eq!(types.as_slice(), &[1, 2, 3, 4]);
        // Complete access (ethercrab starts at sub 1, so sub 0 is not included).
        let tx: u16 = sd
            .sdo_read(0x1C13, SubIndex::Complete)
            .await
            .expect("0x1C13 complete access");
        assert_eq!(tx, 0x1A00);
        // An abort comes back as an error naming the code.
        let err = sd.sdo_read::<u32>(0x5555, 0).await.unwrap_err();
        assert!(format!("{err:?}").contains("Abort"), "{err:?}");
        let mut buf = vec![0u8; 128];
        let n = sd.eeprom_read_raw(md, 0, &mut buf).await.expect("eeprom");
        buf.truncate(n);
        eeprom.push(buf);
    }

    // Remap in PRE-OP: csv RxPDO 0x1601 (controlword, target velocity, mode) and TxPDO 0x1A01
    // (statusword, position, velocity, mode display).
    for mut sd in group.iter_mut(md) {
        sd.sdo_write(0x1C12, 0, 0u8).await.expect("unassign Rx");
        sd.sdo_write(0x1C13, 0, 0u8).await.expect("unassign Tx");
        sd.sdo_write_array(0x1601, [0x6040_0010u32, 0x60FF_0020, 0x6060_0008])
            .await
            .expect("map 0x1601");
        sd.sdo_write_array(0x1C12, [0x1601u16])
            .await
            .expect("assign Rx");
        sd.sdo_write_array(0x1C13, [0x1A01u16])
            .await
            .expect("assign Tx");
        sd.sdo_write(0x6060, 0, 9i8).await.expect("csv");
        sd.sdo_write(0x1C32, 1, 2u16).await.expect("DC SYNC0 mode");
        sd.sdo_write(0x1C32, 2, 1_000_000u32)
            .await
            .expect("cycle time");
        // A PDO object cannot be remapped while assigned: sub 0 must be 0 first.
        let e = sd.sdo_write(0x1601, 1, 0x6040_0010u32).await.unwrap_err();
        assert!(format!("{e:?}").contains("Abort"), "{e:?}");
        sd.set_dc_sync(DcSync::Sync0);
    }
    let group = group.into_pre_op_pdi(md).await.expect("PRE-OP with PDI");
    for sd in group.iter(md) {
        let io = sd.io_raw();
        assert_eq!((io.outputs().len(), io.inputs().len()), (7, 11));
    }
    let group = group
        .configure_dc_sync(
            md,
            DcConfiguration {
                start_delay: Duration::from_millis(20),
                sync0_period: Duration::from_millis(1),
                sync0_shift: Duration::from_micros(500),
            },
        )
        .await
        .expect("DC sync");
    let group = group.into_safe_op(md).await.expect("SAFE-OP");
    let group = group.request_into_op(md).await.expect("request OP");
    let mut in_op = false;
    for _ in 0..5_000 {
        let r = group.tx_rx_dc(md).await.expect("tx_rx_dc");
        if r.all_op() {
            in_op = true;
            break;
        }
        tokio::time::sleep(r.extra.next_cycle_wait).await;
    }
    assert!(in_op, "devices did not reach OP");

    // Power up each drive (shutdown, switch on, enable) and run at 1000 + 100·i counts/s.
    let mut enabled = [false; N];
    let mut start_pos = [None::<i32>; N];
    let mut moved = [false; N];
    let mut mode_seen = [false; N];
    for cycle in 0..3_000u32 {
        for (i, sd) in group.iter(md).enumerate() {
            let status = {
                let inp = sd.inputs_raw();
                u16::from_le_bytes([inp[0], inp[1]])
            };
            let cw: u16 = match status & 0x006F {
                0x0040 | 0x0060 => 0x0006,
                0x0021 => 0x0007,
                0x0023 => 0x000F,
                _ => 0x000F,
            };
            if status & 0x006F == 0x0027 {
                enabled[i] = true;
            }
            let mut o = sd.outputs_raw_mut();
            o[0..2].copy_from_slice(&cw.to_le_bytes());
            o[2..6].copy_from_slice(&(1_000_000 + 100_000 * i as i32).to_le_bytes());
            o[6] = 9;
        }
        let r = group.tx_rx_dc(md).await.expect("tx_rx_dc");
        assert_eq!(r.working_counter, 3 * N as u16, "cycle {cycle}");
        for (i, sd) in group.iter(md).enumerate() {
            let inp = sd.inputs_raw();
            let pos = i32::from_le_bytes(inp[2..6].try_into().unwrap());
            let vel = i32::from_le_bytes(inp[6..10].try_into().unwrap());
            // Until the outputs written here have reached the drive (at its next SYNC0), its
            // inputs reflect the zero outputs of the first OP cycles (mode 0) or nothing yet.
            if inp[10] as i8 == 9 {
                mode_seen[i] = true;
            }
            if enabled[i] {
                match start_pos[i] {
                    None => start_pos[i] = Some(pos),
                    Some(p0) if pos > p0 && vel == 1_000_000 + 100_000 * i as i32 => {
                        moved[i] = true
                    }
                    _ => {}
                }
            }
        }
        if moved.iter().all(|m| *m) && cycle > 20 {
            break;
        }
        tokio::time::sleep(r.extra.next_cycle_wait).await;
    }
    assert_eq!(
        mode_seen, [true; N],
        "mode display follows the mode of operation"
    );
    assert_eq!(enabled, [true; N], "drives reached operation enabled");
    assert_eq!(moved, [true; N], "drives move at the commanded velocity");
    // An SDO read in OP agrees with the process data.
    for sd in group.iter(md) {
        let sw: u16 = sd.sdo_read(0x6041, 0).await.expect("statusword by SDO");
        assert_eq!(sw & 0x006F, 0x0027);
    }
    let group = group.into_safe_op(md).await.expect("back to SAFE-OP");
    let group = group.into_pre_op(md).await.expect("back to PRE-OP");
    let _ = group.into_init(md).await.expect("back to INIT");
    Outcome { eeprom }
}

fn check_coe_segment(seg: &Segment, outcome: &Outcome) {
    for (i, ee) in outcome.eeprom.iter().enumerate() {
        let slave = seg.slave(i).unwrap();
        assert_eq!(
            &slave.esc.sii().bytes()[..ee.len()],
            &ee[..],
            "EEPROM of device {i}"
        );
        let dev = seg.device::<GenericCoeDevice>(i).unwrap();
        assert!(dev.seen.sync0_events > 0, "device {i} saw SYNC0");
        assert_eq!(dev.seen.sync0_cycle_ns, 1_000_000);
        assert_eq!(slave.esc.al_state(), ecdrive_core::ec::AlState::Init);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_in_process_coe_remap_dc_op() {
    let (tx, rx, pdu_loop) = storage().try_split().unwrap();
    let link = EthercrabLink::spawn(coe_segment(), tx, rx).unwrap();
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: 200,
            ..MainDeviceConfig::default()
        },
    )));
    let outcome = coe_scenario(md).await;
    let seg = link.stop();
    check_coe_segment(&seg, &outcome);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_over_veth_coe_remap_dc_op() {
    if !require_root("sim_ethercrab::ethercrab_over_veth_coe_remap_dc_op") {
        return;
    }
    let veth = VethPair::create().expect("veth pair");
    let server = RawServer::spawn(veth.open_peer_socket().expect("peer socket"), coe_segment())
        .expect("server");
    let (tx, rx, pdu_loop) = storage().try_split().unwrap();
    let task = ethercrab::std::tx_rx_task(veth.host(), tx, rx).expect("tx/rx task");
    let handle = tokio::spawn(task);
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: 200,
            ..MainDeviceConfig::default()
        },
    )));
    let outcome = coe_scenario(md).await;
    handle.abort();
    let (seg, result) = server.stop();
    result.expect("server ran without I/O errors");
    check_coe_segment(&seg, &outcome);
}

/// A line of 128 I/O devices: discovery, OP and process data with the right working counter.
/// (ethercrab keeps its 128-slave group on the stack, hence the big thread stack.)
#[test]
fn ethercrab_in_process_128_slaves() {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(|| {
            tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .thread_stack_size(256 << 20)
                .enable_all()
                .build()
                .unwrap()
                .block_on(run_128_slaves())
        })
        .unwrap()
        .join()
        .unwrap();
}

async fn run_128_slaves() {
    const M: usize = 128;
    let mut seg = Segment::new(Arc::new(HostClock));
    for i in 0..M {
        seg.push(
            Box::new(IoDevice::new(2, 4).with_serial(i as u32)),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    let (tx, rx, pdu_loop) = storage().try_split().unwrap();
    let link = EthercrabLink::spawn(seg, tx, rx).unwrap();
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: 10,
            ..MainDeviceConfig::default()
        },
    )));
    let group = md
        .init_single_group::<M, 1024>(ethercat_now)
        .await
        .expect("init");
    assert_eq!(group.len(), M);
    for (i, sd) in group.iter(md).enumerate() {
        assert_eq!(sd.identity().serial, i as u32);
    }
    let group = group.into_op(md).await.expect("OP");
    for cycle in 0..5 {
        for (i, sd) in group.iter(md).enumerate() {
            sd.outputs_raw_mut().copy_from_slice(&[i as u8, cycle]);
        }
        let r = group.tx_rx(md).await.expect("tx_rx");
        assert_eq!(r.working_counter, 3 * M as u16);
        assert!(r.all_op());
    }
    let _ = group.into_safe_op(md).await.expect("SAFE-OP");
    let seg = link.stop();
    // Without DC sync each frame is a cycle: the last outputs reached every device.
    for i in 0..M {
        let dev = seg.device::<IoDevice>(i).unwrap();
        assert_eq!(dev.seen.last_outputs, vec![i as u8, 4]);
    }
}

/// A device whose SII comes from a drive ESI file (MR-J4-TM), with the generic CoE firmware
/// behind it: ethercrab parses the SII (strict bitflags and all), configures the ESI's mailbox
/// and reaches PRE-OP, and SDOs go through.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_reads_an_sii_built_from_an_esi_file() {
    use ecdrive_core::ec::AlState;
    use ecdrive_sim::sii::{self, DeviceDescription};
    use ecdrive_sim::{Device, ProcessDataSizes};

    struct EsiBacked(DeviceDescription, GenericCoeDevice);
    impl Device for EsiBacked {
        fn description(&self) -> DeviceDescription {
            self.0.clone()
        }
        fn process_data_sizes(&self) -> ProcessDataSizes {
            self.1.process_data_sizes()
        }
        fn mailbox_request(&mut self, s: AlState, req: &[u8], rep: &mut [u8]) -> Option<usize> {
            self.1.mailbox_request(s, req, rep)
        }
        fn mailbox_poll(&mut self, rep: &mut [u8]) -> Option<usize> {
            self.1.mailbox_poll(rep)
        }
        fn mailbox_reset(&mut self) {
            self.1.mailbox_reset()
        }
    }

    let file = ecdrive_core::esi::EsiFile::from_path(
        ecdrive_testkit::repo().join("esi/Mitsubishi_MR-J4-TM.xml"),
    )
    .unwrap();
    let esi_dev = file.devices.last().unwrap();
    let desc = sii::from_esi(file.vendor.id, esi_dev, 4711).unwrap();
    let mut seg = Segment::new(Arc::new(HostClock));
    seg.push(
        Box::new(EsiBacked(desc, GenericCoeDevice::new(4711).unwrap())),
        EscConfig::default(),
    )
    .unwrap();
    let (tx, rx, pdu_loop) = storage().try_split().unwrap();
    let link = EthercrabLink::spawn(seg, tx, rx).unwrap();
    let md = Box::leak(Box::new(MainDevice::new(
        pdu_loop,
        timeouts(),
        MainDeviceConfig {
            dc_static_sync_iterations: 10,
            ..MainDeviceConfig::default()
        },
    )));
    let group = md
        .init_single_group::<2, 64>(ethercat_now)
        .await
        .expect("init");
    let sd = group.subdevice(md, 0).unwrap();
    assert_eq!(sd.name(), esi_dev.type_.name_text);
    assert_eq!(sd.identity().vendor_id, file.vendor.id);
    assert_eq!(sd.identity().product_id, esi_dev.type_.product_code);
    assert_eq!(sd.identity().serial, 4711);
    let serial: u32 = sd
        .sdo_read(0x1018, 4)
        .await
        .expect("SDO through the ESI mailbox");
    assert_eq!(serial, 4711);
    drop(link.stop());
}
