//! Start-up with ethercrab's re-reads answered from what ecdrive read and wrote
//! (`BusOptions::answer_rereads`, the module `answers`) against start-up with every read on the
//! wire, on one segment of the emulated MR-J4-TM and BDHDE and every device of every file of the
//! real vendor ESI corpus: the same devices, the same roles, the same process image (every
//! SyncManager and FMMU as the devices hold them, every drive's layout), with far fewer frames.
//! And a drive that acknowledges a remap it does not take: both paths refuse it, naming it.

use ecdrive_core::drives::{bdhde, esi_profile, mr_j4_tm};
use ecdrive_core::esi::EsiFile;
use ecdrive_ethercat::bus::{BusOptions, with_bus};
use ecdrive_ethercat::error::{ErrorKind, MasterError};
use ecdrive_ethercat::startup::{self, DeviceInfo, DriveSetup, Selector, StartupConfig};
use ecdrive_sim::drives::{EmulatedDrive, spec_for};
use ecdrive_sim::transport::SegmentLink;
use ecdrive_sim::{EscConfig, HostClock, Segment};
use std::sync::Arc;
use std::time::Duration;

/// What one start-up gave: the devices, each drive's layout and each I/O device's image, the
/// SyncManager and FMMU registers of every device, and the frames of each phase (sent,
/// answered).
#[derive(Debug)]
struct Outcome {
    devices: Vec<DeviceInfo>,
    images: Vec<String>,
    registers: Vec<Vec<u8>>,
    frames: startup::StartupFrames,
}

/// The segment: both emulated drives, then every device of every corpus file (emulated from
/// its file), in manifest order. Also the profiles the corpus files give.
fn segment() -> (Segment, StartupConfig, usize) {
    segment_with(|_| EscConfig::default())
}

/// [`segment`] with each position's ESC as `esc` makes it.
fn segment_with(esc: impl Fn(usize) -> EscConfig) -> (Segment, StartupConfig, usize) {
    let mut seg = Segment::new(Arc::new(HostClock));
    for (i, key) in [mr_j4_tm::PROFILE.key, bdhde::PROFILE.key]
        .into_iter()
        .enumerate()
    {
        let d = EmulatedDrive::new(spec_for(key).unwrap(), 3000 + i as u32)
            .unwrap()
            .without_loss_detection();
        seg.push(Box::new(d), esc(i)).unwrap();
    }
    let mut cfg = StartupConfig::new(Duration::from_millis(1));
    let mut corpus_devices = 0;
    if let Some(dir) = ecdrive_testkit::corpus::dir() {
        let mut vendor_dirs = std::collections::BTreeSet::new();
        let mut seen: Vec<(u32, u32)> = Vec::new();
        for row in ecdrive_testkit::corpus::manifest(&dir) {
            let path = dir.join(&row["path"]);
            vendor_dirs.insert(path.parent().unwrap().to_path_buf());
            let file = EsiFile::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
            for d in &file.devices {
                seen.push((file.vendor.id, d.type_.product_code));
                let name = format!("esi:{}@{}", path.display(), d.identity_text());
                let pos = seg.len();
                let dev = ecdrive_sim::devices::by_name(&name, pos)
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                seg.push(dev, esc(pos)).unwrap();
                corpus_devices += 1;
            }
        }
        for v in vendor_dirs {
            let loaded = esi_profile::load_dir(&v).unwrap();
            cfg.esi_profiles.extend(loaded.profiles);
            cfg.esi_not_drives.extend(loaded.not_drives);
        }
        // Two files of one vendor describe one identity with different default PDOs
        // (Synapticon's single- and multi-device files, 0x201 rev. 0x0A000002): a folder of
        // both gives one profile to both devices, and the other file's device does not run on
        // it. Such identities run here as I/O devices (their own PDO configuration).
        let id = |p: &ecdrive_core::drives::DriveProfile| {
            let i = &p.bus.identity;
            (i.vendor_id, i.product_code)
        };
        cfg.esi_profiles
            .retain(|p| seen.iter().filter(|&&x| x == id(p)).count() == 1);
    }
    for i in 0..2 {
        cfg.drives.push(DriveSetup::new(Selector::Position(i)));
    }
    (seg, cfg, corpus_devices)
}

/// The bus options with answers on or off.
fn options(answer: bool) -> BusOptions {
    BusOptions {
        answer_rereads: answer,
        ..BusOptions::default()
    }
}

/// Start-up as the master runs it: discovery, roles, configuration to SAFE-OP.
fn start_up<L: ecdrive_core::link::FrameLink>(
    bus: &mut ecdrive_ethercat::bus::Bus<'_, L>,
    cfg: &StartupConfig,
) -> Result<startup::Started, MasterError> {
    let (group, devices) = startup::discover(bus)?;
    let roles = startup::assign_roles(&devices, cfg)?;
    startup::configure(bus, group, devices, roles, cfg)
}

/// Start-up to SAFE-OP on a fresh segment, answers on or off.
fn start(answer: bool) -> Result<Outcome, MasterError> {
    start_on(segment(), answer)
}

/// Start-up to SAFE-OP on `segment`, answers on or off.
fn start_on(
    (seg, cfg, _): (Segment, StartupConfig, usize),
    answer: bool,
) -> Result<Outcome, MasterError> {
    let (r, _link) = with_bus(SegmentLink::new(seg), options(answer), move |bus| {
        let started = start_up(bus, &cfg)?;
        let mut registers = Vec::new();
        for d in &started.devices {
            let addr = d.address;
            let regs = bus
                .block_on(
                    &|| "reading SMs and FMMUs".into(),
                    Duration::from_secs(5),
                    |md| async move {
                        let f = ethercrab::Command::fprd(addr, 0x0600)
                            .receive::<[u8; 48]>(md)
                            .await?;
                        let s = ethercrab::Command::fprd(addr, 0x0800)
                            .receive::<[u8; 32]>(md)
                            .await?;
                        Ok::<_, ethercrab::error::Error>((f, s))
                    },
                )
                .unwrap()
                .unwrap();
            // FMMUs whole; each SM without its status byte (5) and PDI control (7).
            let mut r = regs.0.to_vec();
            for sm in regs.1.chunks(8) {
                r.extend_from_slice(&sm[..5]);
                r.push(sm[6]);
            }
            registers.push(r);
        }
        let images = started
            .drives
            .iter()
            .map(|d| format!("{} {:?} {:?}", d.drive, d.mapping, d.layout))
            .chain(started.io.iter().map(|o| format!("{o:?}")))
            .collect();
        Ok::<_, MasterError>(Outcome {
            devices: started.devices.clone(),
            images,
            registers,
            frames: started.times.frames,
        })
    })
    .unwrap_or_else(|(e, _)| panic!("{e}"));
    r
}

#[test]
fn answered_rereads_give_the_same_image_as_the_wire_with_fewer_frames() {
    let (_, _, corpus_devices) = segment();
    let on = start(true).unwrap_or_else(|e| panic!("answers on: {e}"));
    let off = start(false).unwrap_or_else(|e| panic!("answers off: {e}"));
    assert_eq!(on.devices.len(), 2 + corpus_devices);
    assert_eq!(on.devices, off.devices, "the devices as discovered");
    assert_eq!(
        on.images, off.images,
        "the drives' layouts and the I/O images"
    );
    for (i, (a, b)) in on.registers.iter().zip(&off.registers).enumerate() {
        assert_eq!(
            a, b,
            "device {i} ({}): SM and FMMU registers",
            on.devices[i].name
        );
    }
    let (f1, f0) = (on.frames, off.frames);
    eprintln!(
        "{} devices: discovery {} frames (+{} answered) against {}, SII {} against {}; \
         process image {} (+{} answered) against {}",
        on.devices.len(),
        f1.discovery,
        f1.answered_discovery,
        f0.discovery,
        f1.sii,
        f0.sii,
        f1.image,
        f1.answered_image,
        f0.image
    );
    assert_eq!((f0.answered_discovery, f0.answered_image), (0, 0));
    assert!(f1.answered_discovery > 0 && f1.answered_image > 0, "{f1:?}");
    // What was answered did not go on the wire: far fewer frames.
    assert!(f1.discovery * 2 < f0.discovery, "{f1:?} against {f0:?}");
    assert!(f1.image * 2 < f0.image, "{f1:?} against {f0:?}");
}

/// The same with EEPROMs as real ones are: busy for a few frames after each command, on every
/// other device, and reading 4 bytes per command on every third (ESC datasheets: 0x0502 bits
/// 6 and 15). The bulk read polls the busy ones and reads the header in 4-byte steps; ethercrab's
/// own reads of words not read in bulk (the PDO categories of devices without CoE) wait for the
/// device's busy bit, never an answered one. Devices, images and registers as on fast EEPROMs.
#[test]
fn slow_and_4_byte_eeproms_give_the_same_start_up_either_way() {
    let slow = |pos: usize| EscConfig {
        eeprom_busy_frames: if pos % 2 == 0 { 3 } else { 0 },
        eeprom_reads_4_bytes: pos % 3 == 0,
        ..EscConfig::default()
    };
    let fast = start(true).unwrap_or_else(|e| panic!("fast EEPROMs: {e}"));
    for answer in [true, false] {
        let r = start_on(segment_with(slow), answer)
            .unwrap_or_else(|e| panic!("slow EEPROMs, answers {answer}: {e}"));
        assert_eq!(r.devices, fast.devices, "answers {answer}");
        assert_eq!(r.images, fast.images, "answers {answer}");
        for (i, (a, b)) in r.registers.iter().zip(&fast.registers).enumerate() {
            assert_eq!(a, b, "answers {answer}: device {i} ({})", r.devices[i].name);
        }
        if answer {
            assert!(r.frames.answered_discovery > 0, "{:?}", r.frames);
        }
    }
}

/// A drive that acknowledges the remap and keeps its power-on mapping (`pdo-writes-ignored`):
/// with answers, its own SAFE-OP check refuses the SyncManagers sized for the acknowledged
/// mapping (AL status code 0x001D), and the error says what the answered read-back means;
/// without, the image ethercrab read back does not fit the mapping start-up wrote. Both name
/// the drive.
#[test]
fn a_drive_that_does_not_hold_an_acknowledged_mapping_is_named_either_way() {
    for answer in [true, false] {
        let mut seg = Segment::new(Arc::new(HostClock));
        seg.push(
            ecdrive_sim::devices::by_name("mr-j4-tm+pdo-writes-ignored", 0).unwrap(),
            EscConfig::default(),
        )
        .unwrap();
        let mut cfg = StartupConfig::new(Duration::from_millis(1));
        cfg.drives.push(DriveSetup::new(Selector::Position(0)));
        let (r, _) = with_bus(SegmentLink::new(seg), options(answer), move |bus| {
            start_up(bus, &cfg).map(|_| ())
        })
        .unwrap_or_else(|(e, _)| panic!("{e}"));
        let e = r.expect_err("start-up must fail");
        assert_eq!(e.drive.as_ref().map(|d| d.position), Some(0), "{e}");
        if answer {
            assert!(
                matches!(e.kind, ErrorKind::AlState(c) if c.0 == 0x001D),
                "{e}"
            );
            assert!(e.reason.contains("answer_rereads = false"), "{e}");
        } else {
            assert!(e.to_string().contains("configured mapping"), "{e}");
        }
    }
}

/// A link that loses the reply to one frame of ecdrive's SII bulk read (the `lose`-th) and,
/// if `late`, hands it over after the next frame has gone out, before that frame's reply: a
/// reply a loaded network delivered after the master had given up on it.
struct LosesOneReply {
    inner: SegmentLink,
    raw: u32,
    lose: u32,
    late: bool,
    swallow: bool,
    held: Option<Vec<u8>>,
    delivered_late: bool,
}

impl ecdrive_core::link::FrameLink for LosesOneReply {
    fn send(&mut self, frame: &[u8]) -> Result<(), ecdrive_core::link::LinkError> {
        // The datagram index of ecdrive's own frames.
        if frame.get(17) == Some(&ecdrive_ethercat::answers::RAW_INDEX) {
            self.raw += 1;
            self.swallow = self.raw == self.lose;
        }
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, ecdrive_core::link::LinkError> {
        if self.swallow {
            self.swallow = false;
            let n = self.inner.recv(buf, timeout)?.expect("the reply");
            if self.late {
                self.held = Some(buf[..n].to_vec());
            }
            return Ok(None);
        }
        if self.raw > self.lose
            && let Some(h) = self.held.take()
        {
            buf[..h.len()].copy_from_slice(&h);
            self.delivered_late = true;
            return Ok(Some(h.len()));
        }
        self.inner.recv(buf, timeout)
    }
}

/// The bulk read goes on when a frame's reply is lost (it sends the chunk again), and a reply
/// that comes late, after the next frame went out, is not taken for that frame's: the same
/// devices and image as without loss, whichever frame of the read it hits.
#[test]
fn a_lost_or_late_bulk_read_reply_changes_nothing() {
    let want = start(true).unwrap_or_else(|e| panic!("{e}"));
    for (lose, late) in [(2, false), (5, true), (9, true)] {
        let (seg, cfg, _) = segment();
        let link = LosesOneReply {
            inner: SegmentLink::new(seg),
            raw: 0,
            lose,
            late,
            swallow: false,
            held: None,
            delivered_late: false,
        };
        let (r, link) = with_bus(link, options(true), move |bus| {
            start_up(bus, &cfg).map(|s| (s.devices, s.times.frames))
        })
        .unwrap_or_else(|(e, _)| panic!("{e}"));
        let (devices, frames) = r.unwrap_or_else(|e| panic!("frame {lose} lost: {e}"));
        assert_eq!(devices, want.devices, "frame {lose} lost (late: {late})");
        assert!(frames.answered_discovery > 0, "{frames:?}");
        assert!(link.raw > lose, "the read went on after frame {lose}");
        assert_eq!(link.delivered_late, late, "frame {lose}");
    }
}
