//! Acceptance: plain ethercrab (no ecdrive master code in between) brings an emulated MR-J4-TM
//! and an emulated BDHDE to OP in-process: discovery from the SII built from the ESI files,
//! remapping to the profiles' recommended mapping with single-entry SDO downloads, the start-up
//! SDOs and synchronisation writes of the profiles, DC SYNC0 at 1 ms, the CiA 402 enable
//! sequence, and csp motion.

use ecdrive_core::drives::{DriveProfile, bdhde, mr_j4_tm};
use ecdrive_core::od::{DataType, Value};
use ecdrive_core::pdo::{RemapOptions, remap_sequence};
use ecdrive_sim::drives::EmulatedDrive;
use ecdrive_sim::transport::EthercrabLink;
use ecdrive_sim::{EscConfig, HostClock, Segment};
use ethercrab::std::ethercat_now;
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{DcSync, MainDevice, MainDeviceConfig, PduStorage, SubDeviceRef, Timeouts};
use std::sync::Arc;
use std::time::Duration;

const PROFILES: [&DriveProfile; 2] = [&mr_j4_tm::PROFILE, &bdhde::PROFILE];
const DATA: usize = PduStorage::element_size(1100);

fn storage() -> &'static PduStorage<16, DATA> {
    Box::leak(Box::new(PduStorage::new()))
}

fn timeouts() -> Timeouts {
    Timeouts {
        pdu: Duration::from_millis(2000),
        state_transition: Duration::from_secs(10),
        eeprom: Duration::from_millis(500),
        mailbox_response: Duration::from_secs(2),
        wait_loop_delay: Duration::from_millis(1),
        ..Timeouts::default()
    }
}

fn segment() -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for (i, p) in PROFILES.iter().enumerate() {
        // A master that is not real-time, on a shared machine, in a debug build, misses SYNC0s
        // now and then; the drives' loss-of-data detection (tested in drives_comm) would
        // fault them. Off here, as the MR-J4-TM allows with [Pr. PN06]/[Pr. PN02].
        let spec = ecdrive_sim::drives::spec_for(p.key).unwrap();
        let drive = EmulatedDrive::new(spec, 100 + i as u32)
            .unwrap()
            .without_loss_detection();
        seg.push(
            Box::new(drive),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

/// One typed SDO download through ethercrab.
async fn write<S>(sd: &SubDeviceRef<'_, S>, p: &DriveProfile, index: u16, sub: u8, v: i64)
where
    S: std::ops::Deref<Target = ethercrab::SubDevice>,
{
    let e = p
        .od()
        .entry(ecdrive_core::od::ObjectAddress::new(index, sub))
        .unwrap();
    let r = match e.data_type {
        DataType::Unsigned8 => sd.sdo_write(index, sub, v as u8).await,
        DataType::Integer8 => sd.sdo_write(index, sub, v as i8).await,
        DataType::Unsigned16 => sd.sdo_write(index, sub, v as u16).await,
        DataType::Integer16 => sd.sdo_write(index, sub, v as i16).await,
        DataType::Unsigned32 => sd.sdo_write(index, sub, v as u32).await,
        DataType::Integer32 => sd.sdo_write(index, sub, v as i32).await,
        other => panic!("{other}"),
    };
    r.unwrap_or_else(|e| panic!("{}: 0x{index:04X}:{sub:02X} = {v}: {e:?}", p.name));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ethercrab_runs_both_emulated_drives() {
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
    let mut group = md
        .init_single_group::<4, 128>(ethercat_now)
        .await
        .expect("init");
    assert_eq!(group.len(), 2);
    for (i, sd) in group.iter(md).enumerate() {
        let p = PROFILES[i];
        let id = sd.identity();
        assert_eq!(
            (id.vendor_id, id.product_id),
            (p.identity.vendor_id, p.identity.product_code)
        );
        assert_eq!(id.revision, p.revision);
        assert_eq!(id.serial, 100 + i as u32);
        let vendor: u32 = sd.sdo_read(0x1018, 1).await.expect("0x1018:01");
        assert_eq!(vendor, p.identity.vendor_id);
    }
    for (i, mut sd) in group.iter_mut(md).enumerate() {
        let p = PROFILES[i];
        // The recommended mapping, one sub-index at a time (no complete access on either).
        let opts = RemapOptions::for_drive(&p.pdo_limits, Some(p.od()));
        for s in remap_sequence(&p.cyclic_mapping, &opts).unwrap() {
            write(&sd, p, s.address.index, s.address.sub, i64::from(s.value)).await;
        }
        for s in p.startup {
            let v = match s.value.to_value().unwrap() {
                Value::Int(v) => v,
                Value::Uint(v) => v as i64,
                other => panic!("{other:?}"),
            };
            write(&sd, p, s.address.index, s.address.sub, v).await;
        }
        for s in p.sync_writes(1_000_000, true).unwrap() {
            write(&sd, p, s.address.index, s.address.sub, s.value).await;
        }
        sd.set_dc_sync(DcSync::Sync0);
    }
    let group = group.into_pre_op_pdi(md).await.expect("PRE-OP with PDI");
    for (sd, p) in group.iter(md).zip(PROFILES) {
        let io = sd.io_raw();
        let l = ecdrive_core::pdo::Layout::new(&p.cyclic_mapping);
        assert_eq!(
            (io.outputs().len(), io.inputs().len()),
            (
                l.bytes(ecdrive_core::pdo::Direction::Rx),
                l.bytes(ecdrive_core::pdo::Direction::Tx)
            )
        );
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
    assert!(in_op, "drives did not reach OP");

    // Enable (resetting a fault if a scheduling stall on a loaded machine raised one), hold the
    // position, then move 0.25 revolution at 5 rev/s.
    let mut target: [Option<i32>; 2] = [None; 2];
    let mut moved = [false; 2];
    let mut start = [0i32; 2];
    let mut last_cw = [0u16; 2];
    for _ in 0..8_000u32 {
        for (i, sd) in group.iter(md).enumerate() {
            // Copy the inputs: ethercrab's input and output images share one lock.
            let inp: Vec<u8> = sd.inputs_raw().to_vec();
            let sw = u16::from_le_bytes([inp[0], inp[1]]);
            let pos = i32::from_le_bytes(inp[2..6].try_into().unwrap());
            let cw: u16 = match sw & 0x006F {
                // Fault reset on a rising edge of bit 7.
                s if s & 0x004F == 0x0008 => {
                    if last_cw[i] == 0x0080 {
                        0x0000
                    } else {
                        0x0080
                    }
                }
                s if s & 0x004F == 0x000F => 0x0000,
                0x0040 | 0x0060 => 0x0006,
                0x0021 => 0x0007,
                0x0023 => 0x000F,
                // In Operation enabled, bit 4 too: the BDHDE starts csp on its 0→1 edge (its
                // manual's CSP example); the MR-J4-TM ignores it in csp.
                0x0027 => 0x001F,
                _ => 0x0000,
            };
            let cpr = PROFILES[i].units.position_per_rev as i32;
            let t = match (sw & 0x006F == 0x0027, target[i]) {
                (true, Some(t)) if t.wrapping_sub(start[i]) < cpr / 4 => {
                    Some(t + cpr / 200) // 5 rev/s at 1 ms
                }
                (true, Some(t)) => {
                    if pos.wrapping_sub(start[i]) >= cpr / 4 - cpr / 100 {
                        moved[i] = true;
                    }
                    Some(t)
                }
                (true, None) => {
                    start[i] = pos;
                    Some(pos)
                }
                (false, _) => None,
            };
            target[i] = t;
            last_cw[i] = cw;
            let mut o = sd.outputs_raw_mut();
            o[0..2].copy_from_slice(&cw.to_le_bytes());
            o[2..6].copy_from_slice(&t.unwrap_or(pos).to_le_bytes());
            o[12] = 8;
        }
        let r = group.tx_rx_dc(md).await.expect("tx_rx_dc");
        assert_eq!(r.working_counter, 6);
        if moved.iter().all(|m| *m) {
            break;
        }
        tokio::time::sleep(r.extra.next_cycle_wait).await;
    }
    assert_eq!(moved, [true; 2], "both drives moved in csp");
    // The proper way out: Shutdown, then SAFE-OP, PRE-OP, INIT.
    for _ in 0..20 {
        for sd in group.iter(md) {
            sd.outputs_raw_mut()[0..2].copy_from_slice(&0x0006u16.to_le_bytes());
        }
        let r = group.tx_rx_dc(md).await.expect("tx_rx_dc");
        tokio::time::sleep(r.extra.next_cycle_wait).await;
    }
    let group = group.into_safe_op(md).await.expect("back to SAFE-OP");
    let group = group.into_pre_op(md).await.expect("back to PRE-OP");
    let _ = group.into_init(md).await.expect("back to INIT");
    let seg = link.stop();
    for (i, p) in PROFILES.iter().enumerate() {
        let d = seg.device::<EmulatedDrive>(i).unwrap();
        assert!(d.stats().cycles > 100, "{}: cycles", p.name);
        assert!(d.alarm().is_none(), "{}: {:?}", p.name, d.alarm());
        let moved = d.position_rev().abs();
        assert!(moved > 0.2, "{}: {moved} rev", p.name);
    }
}
