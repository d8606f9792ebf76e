//! CoE through the emulated ESC's mailbox SyncManagers (no master library): SDO transfers of
//! every kind including segmentation both ways, aborts, emergencies posted when SM1 is free,
//! repeat of a lost reply, and the duplicate counter.

use ecdrive_core::ec::mailbox::{
    Coe, CoeService, Emergency, Mailbox, MailboxType, SdoRequest, SdoResponse,
};
use ecdrive_sim::devices::GenericCoeDevice;
use ecdrive_sim::devices::generic_coe::USER_TEXT_LEN;
use ecdrive_sim::probe::Probe;
use ecdrive_sim::{EscConfig, ManualClock, Segment};
use std::sync::Arc;

const MBX: usize = 128;
const ST: u16 = 0x1000;

fn preop() -> Probe {
    let mut seg = Segment::new(Arc::new(ManualClock::new(1_000_000)));
    seg.push(
        Box::new(GenericCoeDevice::new(5).unwrap()),
        EscConfig::default(),
    )
    .unwrap();
    let mut p = Probe::new(seg);
    p.assign_addresses(ST).unwrap();
    p.fpwr(
        ST,
        0x0800,
        &[
            0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
        ],
    )
    .unwrap();
    assert_eq!(p.request_state(ST, 0x0002).unwrap(), (0x0002, 0));
    p
}

struct Master {
    p: Probe,
    counter: u8,
}

impl Master {
    fn next_counter(&mut self) -> u8 {
        self.counter = if self.counter >= 7 {
            1
        } else {
            self.counter + 1
        };
        self.counter
    }

    /// Write one mailbox (whole SM0) and read the reply (whole SM1).
    fn exchange_raw(&mut self, msg: &[u8]) -> Vec<u8> {
        assert_eq!(self.p.fpwr(ST, 0x1000, msg).unwrap().wkc, 1, "SM0 accepted");
        let r = self.p.fprd(ST, 0x1080, MBX).unwrap();
        assert_eq!(r.wkc, 1, "reply in SM1");
        r.data
    }

    fn sdo(&mut self, req: &SdoRequest<'_>) -> Vec<u8> {
        let mut msg = vec![0u8; MBX];
        let c = self.next_counter();
        req.emit_mailbox(c, &mut msg).unwrap();
        self.exchange_raw(&msg)
    }
}

fn sdo_response(reply: &[u8]) -> SdoResponse<'_> {
    let mbx = Mailbox::new_checked(reply).unwrap();
    assert_eq!(mbx.mailbox_type(), Some(MailboxType::Coe));
    let coe = Coe::new_checked(mbx.payload()).unwrap();
    assert!(matches!(
        coe.service(),
        Some(CoeService::SdoResponse | CoeService::SdoRequest)
    ));
    let sdo_len = coe.payload().len();
    // Mailbox header (6) + CoE header (2), then the SDO bytes.
    SdoResponse::parse(&reply[8..8 + sdo_len]).unwrap()
}

#[test]
fn expedited_download_and_upload() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let r = m.sdo(&SdoRequest::DownloadExpedited {
        index: 0x2000,
        sub: 0,
        complete_access: false,
        data: &0xDEAD_BEEFu32.to_le_bytes(),
    });
    assert_eq!(
        sdo_response(&r),
        SdoResponse::Download {
            index: 0x2000,
            sub: 0
        }
    );
    let r = m.sdo(&SdoRequest::Upload {
        index: 0x2000,
        sub: 0,
        complete_access: false,
    });
    match sdo_response(&r) {
        SdoResponse::UploadExpedited { data, .. } => {
            assert_eq!(data, &0xDEAD_BEEFu32.to_le_bytes())
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn segmented_download_and_upload() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let text: Vec<u8> = (0..USER_TEXT_LEN).map(|i| b'a' + (i % 26) as u8).collect();
    // Download: initiate with as much as fits, then segments with alternating toggles.
    let (req, mut sent) = SdoRequest::initiate_download(0x2001, 0, false, &text, MBX);
    assert!(sent < text.len(), "needs segments");
    let r = m.sdo(&req);
    assert_eq!(
        sdo_response(&r),
        SdoResponse::Download {
            index: 0x2001,
            sub: 0
        }
    );
    let mut toggle = false;
    let mut segments = 0;
    while sent < text.len() {
        let (req, n) = SdoRequest::download_segment(&text[sent..], toggle, MBX);
        let r = m.sdo(&req);
        assert_eq!(sdo_response(&r), SdoResponse::DownloadSegment { toggle });
        sent += n;
        toggle = !toggle;
        segments += 1;
    }
    assert!(segments >= 2);
    // Upload: normal initiate with the first part, then upload segments.
    let r = m.sdo(&SdoRequest::Upload {
        index: 0x2001,
        sub: 0,
        complete_access: false,
    });
    let mut got = match sdo_response(&r) {
        SdoResponse::UploadNormal {
            complete_size,
            data,
            ..
        } => {
            assert_eq!(complete_size as usize, USER_TEXT_LEN);
            data.to_vec()
        }
        other => panic!("{other:?}"),
    };
    let mut toggle = false;
    loop {
        let r = m.sdo(&SdoRequest::UploadSegment { toggle });
        match sdo_response(&r) {
            SdoResponse::UploadSegment {
                toggle: t,
                last,
                data,
            } => {
                assert_eq!(t, toggle);
                got.extend_from_slice(data);
                if last {
                    break;
                }
            }
            other => panic!("{other:?}"),
        }
        toggle = !toggle;
    }
    assert_eq!(got, text);
}

#[test]
fn wrong_toggle_aborts_the_transfer() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let text = vec![b'x'; USER_TEXT_LEN];
    let (req, sent) = SdoRequest::initiate_download(0x2001, 0, false, &text, MBX);
    m.sdo(&req);
    let (req, _) = SdoRequest::download_segment(&text[sent..], true, MBX);
    let r = m.sdo(&req);
    assert!(
        matches!(
            sdo_response(&r),
            SdoResponse::Abort {
                code: 0x0503_0000,
                ..
            }
        ),
        "toggle bit not alternated"
    );
}

#[test]
fn aborts_name_the_reason() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let cases: [(u16, u8, u32); 3] = [
        (0x5555, 0, 0x0602_0000), // no object
        (0x1018, 9, 0x0609_0011), // no sub-index
        (0x1000, 0, 0x0601_0002), // read-only
    ];
    for (index, sub, code) in cases {
        let r = m.sdo(&SdoRequest::DownloadExpedited {
            index,
            sub,
            complete_access: false,
            data: &[1, 0, 0, 0],
        });
        match sdo_response(&r) {
            SdoResponse::Abort { code: c, .. } => assert_eq!(c, code, "{index:04X}:{sub}"),
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn emergency_waits_for_a_free_sm1_and_never_replaces_a_reply() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let emcy = Emergency {
        error_code: 0x2310,
        error_register: 0x03,
        data: [1, 2, 3, 4, 5],
    };
    m.p.segment
        .device_mut::<GenericCoeDevice>(0)
        .unwrap()
        .push_emergency(emcy);
    // A request sent now gets its own reply first (the emergency waits).
    let mut msg = vec![0u8; MBX];
    let c = m.next_counter();
    SdoRequest::Upload {
        index: 0x1000,
        sub: 0,
        complete_access: false,
    }
    .emit_mailbox(c, &mut msg)
    .unwrap();
    assert_eq!(m.p.fpwr(ST, 0x1000, &msg).unwrap().wkc, 1);
    let r = m.p.fprd(ST, 0x1080, MBX).unwrap();
    assert!(matches!(
        sdo_response(&r.data),
        SdoResponse::UploadExpedited { index: 0x1000, .. }
    ));
    // Then, polling the SM1 status, the emergency arrives.
    let mut full = false;
    for _ in 0..3 {
        if m.p.fprd(ST, 0x080D, 1).unwrap().data[0] & 0x08 != 0 {
            full = true;
            break;
        }
    }
    assert!(full, "emergency posted");
    let r = m.p.fprd(ST, 0x1080, MBX).unwrap();
    let mbx = Mailbox::new_checked(&r.data[..]).unwrap();
    let coe = Coe::new_checked(mbx.payload()).unwrap();
    assert_eq!(coe.service(), Some(CoeService::Emergency));
    assert_eq!(Emergency::parse(coe.payload()).unwrap(), emcy);
}

#[test]
fn lost_reply_is_repeated_and_duplicates_are_not_executed() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let mut msg = vec![0u8; MBX];
    SdoRequest::Upload {
        index: 0x1018,
        sub: 4,
        complete_access: false,
    }
    .emit_mailbox(3, &mut msg)
    .unwrap();
    let first = m.exchange_raw(&msg);
    // The reply was "lost": toggle the repeat request; the same reply is posted again.
    let act = m.p.fprd(ST, 0x080E, 1).unwrap().data[0];
    m.p.fpwr(ST, 0x080E, &[act ^ 0x02]).unwrap();
    assert_eq!(
        m.p.fprd(ST, 0x080F, 1).unwrap().data[0] & 0x02,
        (act ^ 0x02) & 0x02
    );
    let again = m.p.fprd(ST, 0x1080, MBX).unwrap();
    assert_eq!((again.wkc, &again.data), (1, &first));
    // A request repeated with the same counter is not executed again: no reply.
    assert_eq!(m.p.fpwr(ST, 0x1000, &msg).unwrap().wkc, 1);
    assert_eq!(m.p.fprd(ST, 0x1080, MBX).unwrap().wkc, 0);
    // With a new counter it is answered.
    SdoRequest::Upload {
        index: 0x1018,
        sub: 4,
        complete_access: false,
    }
    .emit_mailbox(4, &mut msg)
    .unwrap();
    let r = m.exchange_raw(&msg);
    match sdo_response(&r) {
        SdoResponse::UploadExpedited { data, .. } => assert_eq!(data, &5u32.to_le_bytes()),
        other => panic!("{other:?}"),
    }
}

/// The generic CoE device's own checks at SAFE-OP→OP in DC mode (0x1C32:01 = 2), each with its
/// AL status code, and the OP it reaches once the SYNC unit is set up right.
#[test]
fn dc_mode_is_checked_at_safeop_to_op() {
    let mut m = Master {
        p: preop(),
        counter: 0,
    };
    let write = |m: &mut Master, index: u16, sub: u8, data: &[u8]| {
        let r = m.sdo(&SdoRequest::DownloadExpedited {
            index,
            sub,
            complete_access: false,
            data,
        });
        assert_eq!(sdo_response(&r), SdoResponse::Download { index, sub });
    };
    write(&mut m, 0x1C32, 1, &2u16.to_le_bytes());
    write(&mut m, 0x1C32, 2, &1_000_000u32.to_le_bytes());
    // Mirrored into the input side.
    let r = m.sdo(&SdoRequest::Upload {
        index: 0x1C33,
        sub: 1,
        complete_access: false,
    });
    assert!(matches!(
        sdo_response(&r),
        SdoResponse::UploadExpedited { data: [2, 0], .. }
    ));
    // Process data SMs for the default mapping (6 bytes each way).
    let p = &mut m.p;
    p.fpwr(ST, 0x0810, &[0x00, 0x11, 6, 0, 0x64, 0, 1, 0])
        .unwrap();
    p.fpwr(ST, 0x0818, &[0x00, 0x14, 6, 0, 0x20, 0, 1, 0])
        .unwrap();
    assert_eq!(p.request_state(ST, 0x0004).unwrap(), (0x0004, 0));
    // No SYNC0: invalid DC sync configuration.
    assert_eq!(p.request_state(ST, 0x0008).unwrap(), (0x0014, 0x0030));
    let sync0 = |p: &mut Probe, cycle: u32| {
        p.fpwr(ST, 0x0981, &[0]).unwrap();
        let now = p.fprd(ST, 0x0910, 8).unwrap().data;
        let start = u64::from_le_bytes(now[..8].try_into().unwrap()) + 10_000_000;
        p.fpwr(ST, 0x0990, &start.to_le_bytes()).unwrap();
        p.fpwr(ST, 0x09A0, &cycle.to_le_bytes()).unwrap();
        p.fpwr(ST, 0x0981, &[0x03]).unwrap();
    };
    // Below the minimum cycle time (0x1C32:05 = 125 µs).
    sync0(p, 100_000);
    assert_eq!(p.request_state(ST, 0x0018).unwrap(), (0x0014, 0x0035));
    // Not the cycle time the master wrote into 0x1C32:02.
    sync0(p, 500_000);
    assert_eq!(p.request_state(ST, 0x0018).unwrap(), (0x0014, 0x0036));
    // Right.
    sync0(p, 1_000_000);
    assert_eq!(p.request_state(ST, 0x0018).unwrap(), (0x0008, 0));
    // PDO objects cannot be written outside PRE-OP.
    let r = m.sdo(&SdoRequest::DownloadExpedited {
        index: 0x1C12,
        sub: 0,
        complete_access: false,
        data: &[0],
    });
    assert!(matches!(
        sdo_response(&r),
        SdoResponse::Abort {
            code: 0x0800_0022,
            ..
        }
    ));
}
