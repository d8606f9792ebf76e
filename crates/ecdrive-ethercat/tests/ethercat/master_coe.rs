//! The master's own CoE client against emulated CoE devices, in-process: every transfer kind,
//! SDO information, aborts named with drive and object, and emergencies that are recorded, not
//! lost — including one that arrives while an SDO is in progress.

use ecdrive_core::ec::mailbox::Emergency;
use ecdrive_core::od::{ObjectAddress, SdoAbortCode};
use ecdrive_ethercat::bus::{BusOptions, MAX_PDI, MAX_SUBDEVICES, SessionError, with_bus};
use ecdrive_ethercat::error::DriveRef;
use ecdrive_sim::devices::GenericCoeDevice;
use ecdrive_sim::devices::generic_coe::USER_TEXT_LEN;
use ecdrive_sim::transport::SegmentLink;
use ecdrive_sim::{EscConfig, HostClock, Segment};
use std::sync::Arc;
use std::time::Duration;

fn segment(n: usize) -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for i in 0..n {
        seg.push(
            Box::new(GenericCoeDevice::new(500 + i as u32).unwrap()),
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

const T: Duration = Duration::from_secs(10);

#[test]
fn transfers_info_aborts_and_emergencies() {
    let link = SegmentLink::new(segment(2));
    let (result, _link) = with_bus(link, BusOptions::default(), |bus| {
        let group = bus
            .block_on(&|| "discovering the segment".into(), T, |md| {
                md.init_single_group::<MAX_SUBDEVICES, MAX_PDI>(ethercrab::std::ethercat_now)
            })
            .unwrap()
            .unwrap();
        assert_eq!(group.len(), 2);
        let addr = group.subdevice(bus.md(), 1).unwrap().configured_address();
        let drive = DriveRef {
            position: 1,
            name: "generic".into(),
        };

        // Expedited upload, and a string that needs a normal or segmented upload.
        let (vendor, name) = bus
            .with_coe(addr, drive.clone(), false, T, async |c| {
                let v = c.upload(ObjectAddress::new(0x1018, 1), false).await?;
                let n = c.upload(ObjectAddress::new(0x1008, 0), false).await?;
                Ok((v, n))
            })
            .unwrap();
        assert_eq!(vendor.len(), 4);
        assert!(String::from_utf8_lossy(&name).starts_with("ecdrive"));

        // A 300-byte segmented download and its read-back.
        let text: Vec<u8> = (0..USER_TEXT_LEN).map(|i| b'a' + (i % 26) as u8).collect();
        let back = bus
            .with_coe(addr, drive.clone(), false, T, async |c| {
                c.download(ObjectAddress::new(0x2001, 0), &text, false).await?;
                c.upload(ObjectAddress::new(0x2001, 0), false).await
            })
            .unwrap();
        assert_eq!(back, text);

        // An abort names the drive, the object and the CiA 301 reason.
        let err = bus
            .with_coe(addr, drive.clone(), false, T, async |c| {
                c.download(ObjectAddress::new(0x1018, 1), &[1, 2, 3, 4], false).await
            })
            .unwrap_err();
        let SessionError::Coe(e) = err else {
            panic!("{err}")
        };
        assert_eq!(e.abort_code(), Some(SdoAbortCode::READ_ONLY));
        assert_eq!(
            e.to_string(),
            "drive 1 (generic) 0x1018:01: SDO abort 0x06010002 (Attempt to write a read only object)"
        );

        // SDO information: the OD list and descriptions.
        let (list, desc, entry) = bus
            .with_coe(addr, drive.clone(), false, T, async |c| {
                let l = c.od_list(1).await?;
                let d = c.object_description(0x1018).await?;
                let e = c.entry_description(ObjectAddress::new(0x1018, 1)).await?;
                Ok((l, d, e))
            })
            .unwrap();
        assert!(list.contains(&0x1018) && list.contains(&0x2001), "{list:x?}");
        assert_eq!(desc.name, "Identity");
        assert_eq!(desc.max_sub, 4);
        assert_eq!(entry.bit_len, 32);

        // Emergencies: queue two in the device mid-session, then do an SDO. The client records
        // both (one already waiting before the request, one delivered while it waits for the
        // reply) and the SDO still completes.
        let dev = bus
            .pump_mut()
            .link_mut()
            .segment_mut()
            .device_mut::<GenericCoeDevice>(1)
            .unwrap();
        dev.push_emergency(Emergency {
            error_code: 0x8611,
            error_register: 0x80,
            data: [1, 2, 3, 4, 5],
        });
        dev.push_emergency(Emergency {
            error_code: 0x3210,
            error_register: 0x04,
            data: [0; 5],
        });
        let v = bus
            .with_coe(addr, drive, false, T, async |c| {
                c.upload(ObjectAddress::new(0x2000, 0), false).await
            })
            .unwrap();
        assert_eq!(v.len(), 4);
        bus.emergencies().lock().unwrap().clone()
    })
    .unwrap();
    let log = result;
    let codes: Vec<u16> = log.iter().map(|e| e.emergency.error_code).collect();
    assert_eq!(codes, [0x8611, 0x3210], "{log:?}");
    assert!(log.iter().all(|e| e.position == 1));
}
