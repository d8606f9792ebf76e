//! What each fuzz target checks, one function per target, on one input.
//!
//! The cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`) call these functions; the normal test suite
//! includes this file with `#[path]` (`tests/app/fuzz_corpus.rs`) and replays every committed corpus
//! file through the same checks, so the corpus is a regression suite without libFuzzer. This
//! file therefore depends on nothing but `ecdrive` and `std`.
//!
//! Every check panics (fails) on a property violation; the functions under test must never
//! panic on any input.

use ecdrive::drives::mr_j4_tm;
use ecdrive::ec::AlState;
use ecdrive::ec::frame::{EthercatFrame, EthernetFrame};
use ecdrive::ec::mailbox::{
    EntryDescription, MailboxMessage, ObjectDescription, OdList, SdoInfoFragment, SdoRequest,
    SdoResponse,
};
use ecdrive::esi::EsiFile;
use ecdrive::sim::coe::{CoeConfig, CoeServer, OdStore, fixture};
use ecdrive::sim::devices::{EchoMailbox, GenericCoeDevice, IoDevice};
use ecdrive::sim::probe::Probe;
use ecdrive::sim::{Device, EscConfig, ManualClock, Segment};
use std::sync::Arc;

// ---------------------------------------------------------------------------------------------
// segment: the software slave's frame and datagram processing
// ---------------------------------------------------------------------------------------------

/// Frames per `segment` input at most.
pub const SEGMENT_MAX_FRAMES: usize = 64;

/// SM0/SM1 as mailbox SyncManagers (0x1000 out, 0x1080 in, 128 bytes each).
const MAILBOX_SMS: [u8; 16] = [
    0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
];

/// A segment of two CoE devices, an I/O device and a mailbox echo device. `configured`:
/// addresses assigned from 0x1000, the mailbox devices' SyncManagers set up and in PRE-OP, and
/// an FMMU over process RAM in every slave (so mailbox, SDO and logical paths are reachable
/// without the input having to set them up).
fn segment_fixture(configured: bool) -> Option<(Probe, ManualClock)> {
    let clock = ManualClock::new(1_000_000_000);
    let mut seg = Segment::new(Arc::new(clock.clone()));
    let devs: Vec<Box<dyn Device>> = vec![
        Box::new(GenericCoeDevice::new(1).ok()?),
        Box::new(IoDevice::new(2, 4)),
        Box::new(EchoMailbox::new()),
        Box::new(GenericCoeDevice::new(2).ok()?),
    ];
    for d in devs {
        seg.push(d, EscConfig::default()).ok()?;
    }
    let mut p = Probe::new(seg);
    if configured {
        p.assign_addresses(0x1000).ok()?;
        for station in [0x1000, 0x1002, 0x1003] {
            p.fpwr(station, 0x0800, &MAILBOX_SMS).ok()?;
            p.fpwr(station, 0x0120, &[0x02, 0]).ok()?;
        }
        let mut f = [0u8; 16];
        f[4] = 8;
        f[7] = 7;
        f[8..10].copy_from_slice(&0x1400u16.to_le_bytes());
        f[11] = 3;
        f[12] = 1;
        p.bwr(0x0600, &f).ok()?;
    }
    Some((p, clock))
}

/// Process one frame: a dropped frame is left untouched; a returned frame has the same length,
/// the same Ethernet and EtherCAT headers (but the source MAC's U/L bit, which every ESC port
/// sets) and the same datagram framing (command, index, length, more and circulating flags; the
/// address too unless the command increments it; reserved commands pass untouched).
fn process_and_check(seg: &mut Segment, frame: &mut [u8]) {
    let orig = frame.to_vec();
    match seg.process(frame) {
        Err(_) => assert_eq!(frame, &orig[..], "a dropped frame is left untouched"),
        Ok(n) => {
            assert_eq!(n, orig.len(), "a reply has the frame's length");
            assert_eq!(frame[6], orig[6] | 0x02, "U/L bit of the source MAC");
            assert_eq!(frame[0..6], orig[0..6], "destination MAC");
            assert_eq!(
                frame[7..16],
                orig[7..16],
                "source MAC, EtherType, EtherCAT header"
            );
            let a = EthernetFrame::new_checked(&orig[..]).expect("a processed frame is Ethernet");
            let b = EthernetFrame::new_checked(&frame[..]).expect("the reply is Ethernet");
            let a = EthercatFrame::new_checked(a.payload()).expect("a processed frame is EtherCAT");
            let b = EthercatFrame::new_checked(b.payload()).expect("the reply is EtherCAT");
            for (x, y) in a.datagrams().zip(b.datagrams()) {
                let (x, y) = (x.expect("datagram"), y.expect("reply datagram"));
                assert_eq!(x.command_raw(), y.command_raw());
                assert_eq!(x.index(), y.index());
                assert_eq!(x.data_len(), y.data_len());
                assert_eq!(x.more(), y.more());
                assert_eq!(x.circulating(), y.circulating());
                if !x.command().is_some_and(|c| c.increments_adp()) {
                    assert_eq!(x.adp(), y.adp());
                }
                if x.command().is_none() {
                    assert_eq!(x.data(), y.data(), "reserved commands pass untouched");
                }
            }
        }
    }
}

/// The segment still behaves: every slave answers BRD, APRD and FPRD with the right working
/// counter and its identification registers, and takes a new station address.
fn still_sane(seg: Segment) {
    let mut p = Probe::new(seg);
    let n = u16::try_from(p.segment.len()).expect("a small segment");
    let r = p.brd(0x0000, 1).expect("BRD after fuzzing");
    assert_eq!(
        (r.wkc, r.adp, r.data[0]),
        (n, n, 0x04),
        "BRD of the ESC type"
    );
    for pos in 0..n {
        let r = p.aprd(pos, 0x0004, 2).expect("APRD answered");
        assert_eq!((r.wkc, &r.data[..]), (1, &[8u8, 8][..]), "slave {pos}");
        p.apwr(pos, 0x0010, &(0x3000 + pos).to_le_bytes())
            .expect("APWR answered");
        let r = p.fprd(0x3000 + pos, 0x0010, 2).expect("FPRD answered");
        assert_eq!(
            (r.wkc, &r.data[..]),
            (1, &(0x3000 + pos).to_le_bytes()[..]),
            "slave {pos} takes a station address"
        );
    }
}

/// `segment` target: `Segment::process` on arbitrary frames.
///
/// Input: a mode byte, then frames, each as a 2-byte little-endian length (mod 1600) and that
/// many bytes. Mode bit 0 clear: the segment is fresh from power-on; set: configured (see
/// [`segment_fixture`]). Between frames the clock advances by `(mode >> 1) × 125 µs` and the
/// segment is polled (SYNC0 pulses, watchdogs). Checked: nothing panics, every frame is
/// dropped untouched or returned with its framing intact, and afterwards every slave still
/// answers correctly.
pub fn segment(data: &[u8]) {
    let Some((&mode, mut rest)) = data.split_first() else {
        return;
    };
    let (probe, clock) = segment_fixture(mode & 1 != 0).expect("the fixture segment builds");
    let mut seg = probe.segment;
    let mut frames = 0;
    let mut buf = vec![0u8; 2048];
    while let [lo, hi, tail @ ..] = rest
        && frames < SEGMENT_MAX_FRAMES
    {
        let len = usize::from(u16::from_le_bytes([*lo, *hi])) % 1600;
        let n = len.min(tail.len());
        let (frame, tail) = tail.split_at(n);
        rest = tail;
        let frame_buf = &mut buf[..n];
        frame_buf.copy_from_slice(frame);
        process_and_check(&mut seg, frame_buf);
        clock.advance(125_000 * u64::from(mode >> 1));
        seg.poll();
        frames += 1;
    }
    still_sane(seg);
}

// ---------------------------------------------------------------------------------------------
// coe: the slave's CoE server and the master's mailbox views
// ---------------------------------------------------------------------------------------------

/// Mailboxes per `coe` input at most.
pub const COE_MAX_MESSAGES: usize = 32;

/// The master's mailbox views on arbitrary bytes: none panics.
fn mailbox_views(bytes: &[u8]) {
    if let Ok((_, m)) = MailboxMessage::parse(bytes) {
        let _ = format!("{m:?}");
    }
    let _ = SdoRequest::parse(bytes);
    let _ = SdoResponse::parse(bytes);
    let _ = SdoInfoFragment::parse(bytes);
    let _ = OdList::parse(bytes).map(|l| l.values().count());
    let _ = ObjectDescription::parse(bytes);
    if let Ok(e) = EntryDescription::parse(bytes) {
        let _ = e.values();
    }
}

/// A reply (or unsolicited message) of `len` bytes in an SM1 of `sm` bytes: it fits and it is
/// a well-formed mailbox message.
fn check_reply(sm1: &[u8], len: usize) {
    assert!(len <= sm1.len(), "a reply fits SM1");
    let reply = &sm1[..len];
    assert!(MailboxMessage::parse(reply).is_ok(), "a reply parses");
    mailbox_views(reply);
}

/// Whatever came before, a correct upload of 0x1000:00 in PRE-OP is answered with an
/// expedited upload response of 0x1000:00 (a second counter is used if the first one happens
/// to repeat the previous request's, which the server treats as a retry).
fn answers_correctly(server: &mut CoeServer, od: &mut OdStore, sm: usize) {
    let mut sm0 = vec![0u8; sm];
    let mut sm1 = vec![0u8; sm];
    let req = SdoRequest::Upload {
        index: 0x1000,
        sub: 0,
        complete_access: false,
    };
    for cnt in [1u8, 2] {
        sm0.fill(0);
        req.emit_mailbox(cnt, &mut sm0)
            .expect("an upload request fits any mailbox SM");
        if let Some(n) = server.handle(&sm0, AlState::PreOp, od, &mut sm1) {
            match MailboxMessage::parse(&sm1[..n]) {
                Ok((
                    _,
                    MailboxMessage::SdoResponse(SdoResponse::UploadExpedited {
                        index: 0x1000,
                        sub: 0,
                        data,
                        ..
                    }),
                )) => assert_eq!(data.len(), 4, "0x1000 is a UDINT"),
                other => panic!("answer to an upload of 0x1000: {other:?}"),
            }
            return;
        }
    }
    panic!("no answer to a correct request");
}

/// `coe` target: `CoeServer::handle_with_foe` (with `poll_unsolicited`) on arbitrary mailboxes,
/// with the emulated MR-J4-TM's FoE server behind it (so FoE requests, type 4, reach file
/// access and firmware checks in every state), and the master's mailbox views (CoE and FoE) on
/// arbitrary bytes and on every reply.
///
/// Input: a config byte (bit 0: the generic fixture dictionary or the MR-J4-TM's; bits 1–3:
/// the AL state; bits 4–5: the SyncManager size 16, 48, 128 or 1486), then mailboxes, each as a
/// 1-byte length and that many bytes (cut or zero-padded to SM0 as the ESC does). Checked:
/// nothing panics, every reply fits SM1 and parses, and afterwards the server still answers a
/// correct request.
pub fn coe(data: &[u8]) {
    let Some((&cfg, mut rest)) = data.split_first() else {
        return;
    };
    mailbox_views(rest);
    let objects = if cfg & 1 == 0 {
        fixture::OBJECTS
    } else {
        mr_j4_tm::PROFILE.dictionary
    };
    let mut od = OdStore::new(objects).expect("the built-in dictionaries load");
    let state = match (cfg >> 1) & 7 {
        0 => AlState::Init,
        1 => AlState::Bootstrap,
        2 | 3 => AlState::PreOp,
        4 | 5 => AlState::SafeOp,
        _ => AlState::Op,
    };
    let sm = [16usize, 48, 128, 1486][usize::from((cfg >> 4) & 3)];
    let mut server = CoeServer::new(CoeConfig::default());
    let mut foe = ecdrive::sim::foe::FoeServer::new(ecdrive::sim::drives::mr_j4_tm::REC_FOE);
    let mut sm0 = vec![0u8; sm];
    let mut sm1 = vec![0u8; sm];
    let mut n = 0;
    while let Some((&len, tail)) = rest.split_first()
        && n < COE_MAX_MESSAGES
    {
        n += 1;
        let (msg, tail) = tail.split_at(usize::from(len).min(tail.len()));
        rest = tail;
        sm0.fill(0);
        let k = msg.len().min(sm);
        sm0[..k].copy_from_slice(&msg[..k]);
        if let Some(r) = server.handle_with_foe(&sm0, state, &mut od, Some(&mut foe), &mut sm1) {
            check_reply(&sm1, r);
        }
        for _ in 0..64 {
            match server.poll_unsolicited(&mut sm1) {
                Some(r) => check_reply(&sm1, r),
                None => break,
            }
        }
    }
    answers_correctly(&mut server, &mut od, sm);
}

// ---------------------------------------------------------------------------------------------
// esi: the ESI parser
// ---------------------------------------------------------------------------------------------

/// `esi` target: `EsiFile::parse_bytes` on arbitrary bytes, and everything derived from a
/// parsed file: the checks, the PDO mappings, the DC modes and the object dictionary. Checked:
/// nothing panics; an error renders as text naming something.
pub fn esi(data: &[u8]) {
    let f = match EsiFile::parse_bytes(data) {
        Ok(f) => f,
        Err(e) => {
            assert!(!e.to_string().is_empty(), "an ESI error says what is wrong");
            return;
        }
    };
    for i in f.check() {
        let _ = i.to_string();
    }
    let _ = f.choose(&ecdrive::esi::DeviceChoice::Only);
    for d in &f.devices {
        let _ = ecdrive::esi::DrivePlan::new(&f, d);
        let _ = f.choose(&ecdrive::esi::DeviceChoice::parse(&d.identity_text()));
        let _ = d.default_mapping();
        let rx: Vec<u16> = d.rx_pdos.iter().map(|p| p.index).collect();
        let tx: Vec<u16> = d.tx_pdos.iter().map(|p| p.index).collect();
        let _ = d.mapping(&rx, &tx);
        for m in &d.dc {
            for cycle in [0, 1, 1_000_000, u64::MAX] {
                let _ = m.mode.sync0_cycle_ns(cycle);
            }
            if let Some(c) = &m.allowed_cycle_times {
                let _ = (c.contains(0), c.contains(u32::MAX), c.min());
            }
        }
        if let Some(dict) = d.dictionary() {
            for o in &dict.objects {
                let _ = dict.resolve_object(o);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// config: the `ecdrive run` configuration parser
// ---------------------------------------------------------------------------------------------

/// `config` target: `config::parse` on arbitrary text (inputs that are not UTF-8 are skipped:
/// the CLI reads files as strings). Checked: nothing panics; an error names the file and a
/// position inside the text (line within the text, column within that line, both 1-based),
/// says what is wrong, and renders as one line.
pub fn config(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match ecdrive_cli::app::config::parse(text, "fuzz.toml") {
        Ok(c) => {
            let _ = format!("{c:?}");
        }
        Err(e) => {
            let shown = e.to_string();
            assert_eq!(e.file, "fuzz.toml", "{shown}");
            assert!(!e.message.is_empty(), "{shown}: no reason");
            let lines: Vec<&str> = text.split('\n').collect();
            assert!(
                e.line >= 1 && e.line <= lines.len(),
                "{shown}: line outside the text"
            );
            let width = lines.get(e.line - 1).map_or(0, |l| l.chars().count());
            assert!(
                e.column >= 1 && e.column <= width + 1,
                "{shown}: column outside line {}",
                e.line
            );
            assert!(!shown.contains('\n'), "not one line: {shown:?}");
        }
    }
}

/// The EDS/DCF reader (`eds::EdsFile::parse`) and what is derived from a file: an error says
/// what is wrong; a file read has at least one object, every warning says something, and the
/// lookups the master uses (identity, modes, mappable objects, values for every node-ID) run.
pub fn eds(data: &[u8]) {
    let f = match ecdrive::eds::EdsFile::parse(data) {
        Ok(f) => f,
        Err(e) => {
            assert!(!e.to_string().is_empty(), "an EDS error says what is wrong");
            return;
        }
    };
    assert!(!f.objects.is_empty(), "a file read has an object");
    for w in &f.warnings {
        assert!(!w.to_string().is_empty(), "a warning says what");
    }
    let _ = (
        f.is_cia402(),
        f.supported_modes(),
        f.mappable(true),
        f.mappable(false),
    );
    for o in f.objects.values() {
        for e in o.entries.values() {
            for node in [0u8, 1, 127, 255] {
                let _ = (e.default.resolve(node), e.parameter_value.resolve(node));
            }
            let _ = e.bit_len();
        }
    }
}
