//! Writes the seed corpus of the fuzz targets into `fuzz/corpus/<target>/`:
//!
//! - `segment`: the frames ecdrive's master sends while it discovers a segment of the fuzz
//!   target's devices and talks CoE to them, recorded and cut into inputs of 24 frames (the
//!   first input from power-on, the others on the pre-configured segment);
//! - `coe`: SDO and SDO information requests of every kind as mailboxes;
//! - `esi`: the ESI files of the repository (`esi/`, `tests/data/esi/`), one file per device of
//!   the multi-device file, and the drive files with their dictionary cut down (small inputs
//!   that still parse);
//! - `config`: the example configuration files, one file with every key, typical mistakes.
//!
//! Run from the repository root: `cargo run --manifest-path fuzz/Cargo.toml --bin seeds`.

use ecdrive::ec::mailbox::{SdoInfoRequest, SdoRequest, list_type, value_info};
use ecdrive::link::{FrameLink, LinkError};
use ecdrive::master::error::DriveRef;
use ecdrive::app::ethercat::tools;
use ecdrive::od::ObjectAddress;
use ecdrive::sim::devices::{EchoMailbox, GenericCoeDevice, IoDevice};
use ecdrive::sim::transport::SegmentLink;
use ecdrive::sim::{Device, EscConfig, HostClock, Segment};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

struct Recorder {
    inner: SegmentLink,
    frames: Arc<Mutex<Vec<Vec<u8>>>>,
}

impl FrameLink for Recorder {
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        if let Ok(mut f) = self.frames.lock() {
            f.push(frame.to_vec());
        }
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        self.inner.recv(buf, timeout)
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) {
    std::fs::create_dir_all(dir).expect("corpus directory");
    std::fs::write(dir.join(name), bytes).expect("seed file");
}

fn segment_seeds(root: &Path) {
    let mut seg = Segment::new(Arc::new(HostClock));
    let devs: Vec<Box<dyn Device>> = vec![
        Box::new(GenericCoeDevice::new(1).expect("device")),
        Box::new(IoDevice::new(2, 4)),
        Box::new(EchoMailbox::new()),
        Box::new(GenericCoeDevice::new(2).expect("device")),
    ];
    for d in devs {
        seg.push(d, EscConfig::default()).expect("slave");
    }
    let frames = Arc::new(Mutex::new(Vec::new()));
    let link = Recorder {
        inner: SegmentLink::new(seg),
        frames: frames.clone(),
    };
    let r = tools::on_link(link, |bus| {
        let (_group, devices) = ecdrive::master::startup::discover(bus)?;
        for d in devices.iter().filter(|d| d.position != 1) {
            let drive = DriveRef {
                position: d.position,
                name: d.name.clone(),
            };
            let _ = bus.with_coe(d.address, drive, true, Duration::from_secs(2), async |c| {
                let _ = c.upload(ObjectAddress::new(0x1008, 0), false).await;
                let _ = c.upload(ObjectAddress::new(0x1018, 1), true).await;
                let _ = c
                    .download(ObjectAddress::new(0x2001, 0), &[0x41; 300], false)
                    .await;
                let _ = c.upload(ObjectAddress::new(0x2001, 0), false).await;
                let _ = c.od_list(1).await;
                let _ = c.object_description(0x1018).await;
                let _ = c.entry_description(ObjectAddress::new(0x1018, 2)).await;
                Ok(())
            });
        }
        Ok(())
    });
    if let Err(e) = r {
        eprintln!("recording: {e}");
    }
    let all = frames.lock().map(|f| f.clone()).unwrap_or_default();
    // Busy polls (the same frame again, but for its datagram index) collapse into one.
    let same = |a: &[u8], b: &[u8]| {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .enumerate()
                .all(|(i, (x, y))| i == 17 || x == y)
    };
    let mut frames: Vec<Vec<u8>> = Vec::new();
    for f in all {
        if frames.last().is_none_or(|l| !same(l, &f)) {
            frames.push(f);
        }
    }
    frames.truncate(24 * 200);
    let dir = root.join("segment");
    for (i, chunk) in frames.chunks(24).enumerate() {
        // The first chunk starts from power-on; later ones run on the configured segment.
        let mut input = vec![if i == 0 { 2 } else { 3 }];
        for f in chunk {
            input.extend_from_slice(&(f.len() as u16).to_le_bytes());
            input.extend_from_slice(f);
        }
        write(&dir, &format!("recorded-{i:03}"), &input);
    }
    println!(
        "segment: {} frames in {} inputs",
        frames.len(),
        frames.len().div_ceil(24)
    );
}

fn coe_seeds(root: &Path) {
    let dir = root.join("coe");
    let mut buf = [0u8; 256];
    let data = [0x5Au8; 200];
    let requests: Vec<SdoRequest<'_>> = vec![
        SdoRequest::Upload {
            index: 0x1008,
            sub: 0,
            complete_access: false,
        },
        SdoRequest::Upload {
            index: 0x1018,
            sub: 1,
            complete_access: true,
        },
        SdoRequest::Upload {
            index: 0x1C12,
            sub: 0,
            complete_access: true,
        },
        SdoRequest::UploadSegment { toggle: false },
        SdoRequest::UploadSegment { toggle: true },
        SdoRequest::DownloadExpedited {
            index: 0x6060,
            sub: 0,
            complete_access: false,
            data: &[8],
        },
        SdoRequest::DownloadExpedited {
            index: 0x1C12,
            sub: 0,
            complete_access: false,
            data: &[0],
        },
        SdoRequest::DownloadNormal {
            index: 0x2001,
            sub: 0,
            complete_access: false,
            complete_size: 200,
            data: &data[..100],
        },
        SdoRequest::DownloadNormal {
            index: 0x1600,
            sub: 0,
            complete_access: true,
            complete_size: 9,
            data: &[2, 0, 0, 0x10, 0x40, 0x60, 0x20, 0, 0x7A],
        },
        SdoRequest::DownloadSegment {
            toggle: false,
            last: true,
            data: &data[..100],
        },
        SdoRequest::Abort {
            index: 0x2001,
            sub: 0,
            code: 0x0504_0000,
        },
    ];
    let mut input = vec![0x05u8];
    for (i, r) in requests.iter().enumerate() {
        let Ok(n) = r.emit_mailbox((i % 7 + 1) as u8, &mut buf) else {
            continue;
        };
        let mut one = vec![0x05u8, n.min(255) as u8];
        one.extend_from_slice(&buf[..n.min(255)]);
        write(&dir, &format!("sdo-{i:02}"), &one);
        input.push(n.min(255) as u8);
        input.extend_from_slice(&buf[..n.min(255)]);
    }
    write(&dir, "sdo-all", &input);
    let infos = [
        SdoInfoRequest::OdList {
            list_type: list_type::ALL,
        },
        SdoInfoRequest::OdList { list_type: 0 },
        SdoInfoRequest::ObjectDescription { index: 0x1018 },
        SdoInfoRequest::EntryDescription {
            index: 0x1018,
            sub: 1,
            value_info: value_info::DEFAULT | value_info::MINIMUM | value_info::MAXIMUM,
        },
    ];
    for (i, r) in infos.iter().enumerate() {
        if let Ok(n) = r.emit_mailbox(1, &mut buf) {
            let mut one = vec![0x25u8, n as u8];
            one.extend_from_slice(&buf[..n]);
            write(&dir, &format!("info-{i:02}"), &one);
        }
    }
    println!("coe: written");
}

fn copy_seeds(root: &Path, target: &str, files: &[&Path]) {
    let dir = root.join(target);
    for f in files {
        let bytes = std::fs::read(f).expect("seed source");
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or("seed");
        write(&dir, name, &bytes);
    }
    println!("{target}: {} files", files.len());
}

/// Byte ranges `open..close-end` of the elements `<tag>…</tag>` (not nested in themselves).
fn elements(text: &[u8], open: &[u8], close: &[u8]) -> Vec<(usize, usize)> {
    let find = |from: usize, pat: &[u8]| {
        text.get(from..)?
            .windows(pat.len())
            .position(|w| w == pat)
            .map(|p| from + p)
    };
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(s) = find(at, open) {
        let Some(e) = find(s, close) else { break };
        out.push((s, e + close.len()));
        at = e + close.len();
    }
    out
}

/// `text` without the byte ranges in `cut` (sorted, disjoint).
fn without(text: &[u8], cut: &[(usize, usize)]) -> Vec<u8> {
    let mut out = Vec::with_capacity(text.len());
    let mut at = 0;
    for &(s, e) in cut {
        out.extend_from_slice(&text[at..s]);
        at = e;
    }
    out.extend_from_slice(&text[at..]);
    out
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// Small ESI seeds derived from the repository's ESI files, so that the fuzzer mutates inputs
/// of a few kB that still parse (the drive files are 100–220 kB, mostly their dictionary):
///
/// - one file per device of a multi-device file (`<name>-device<k>.xml`);
/// - each drive file with its dictionary cut to the objects of `KEEP` and the data types they
///   need (`<name>-small.xml`).
fn esi_derived(root: &Path, files: &[PathBuf]) {
    const KEEP: [&[u8]; 5] = [b"#x1000<", b"#x1018<", b"#x1C12<", b"#x6040<", b"#x6060<"];
    let dir = root.join("esi");
    let mut n = 0;
    for f in files {
        let text = std::fs::read(f).expect("ESI file");
        let stem = f.file_stem().and_then(|s| s.to_str()).unwrap_or("esi");
        let devices = elements(&text, b"<Device ", b"</Device>");
        if devices.len() > 1 {
            for k in 0..devices.len() {
                let others: Vec<_> = devices
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != k)
                    .map(|(_, r)| *r)
                    .collect();
                write(
                    &dir,
                    &format!("{stem}-device{k}.xml"),
                    &without(&text, &others),
                );
                n += 1;
            }
        }
        let objects = elements(&text, b"<Object>", b"</Object>");
        if objects.len() > KEEP.len() {
            let drop: Vec<_> = objects
                .iter()
                .filter(|&&(s, e)| !KEEP.iter().any(|k| contains(&text[s..e], k)))
                .copied()
                .collect();
            let mut small = without(&text, &drop);
            // Drop the data types nothing refers to any more, until none is left to drop.
            loop {
                let types = elements(&small, b"<DataType>", b"</DataType>");
                let unused: Vec<_> = types
                    .iter()
                    .filter(|&&(s, e)| {
                        let block = &small[s..e];
                        let name = elements(block, b"<Name>", b"</Name>")
                            .first()
                            .map(|&(a, b)| block[a + 6..b - 7].to_vec())
                            .unwrap_or_default();
                        let mut rest = small[..s].to_vec();
                        rest.extend_from_slice(&small[e..]);
                        let as_type = [b"<Type>".as_slice(), &name, b"</Type>"].concat();
                        let as_base = [b"<BaseType>".as_slice(), &name, b"</BaseType>"].concat();
                        !name.is_empty() && !contains(&rest, &as_type) && !contains(&rest, &as_base)
                    })
                    .copied()
                    .collect();
                if unused.is_empty() {
                    break;
                }
                small = without(&small, &unused);
            }
            write(&dir, &format!("{stem}-small.xml"), &small);
            n += 1;
        }
    }
    println!("esi: {n} derived files");
}

/// Configuration seeds beyond the examples: every section and key the parser knows, and
/// typical mistakes (each one error).
const CONFIG_SEEDS: [(&str, &str); 8] = [
    (
        "all-keys.toml",
        r#"interface = "sim"
cycle = "500us"
dc_shift = "100us"
duration = "2s"
[rt]
priority = 80
cpu = 1
lock_memory = true
[supervision]
lost_cycles = 10
wkc_errors = 4
op_timeout = "8s"
[sim]
devices = ["generic-coe", "generic-coe", "mr-j4-tm", "bdhde"]
sm_watchdog = 0
loss_detection = false
[[drive]]
position = 1
mode = "csv"
units = { name = "mm", counts_per_unit = 1000 }
limits = { following_error = 0.5, max_velocity = 100, max_acceleration = 1000 }
sdos = { "0x6065:00" = 5000, "0x2001:00" = "0x10" }
program = [
  { step = "ramp", velocity = 50, acceleration = 500, hold = 0.1 },
  { step = "mode", mode = "csp" },
  { step = "move", to = 10, velocity = 20, acceleration = 200, jerk = 5000 },
  { step = "sine", amplitude = 1, frequency = 2, periods = 1 },
  { step = "dwell", seconds = 0.1 },
]
[[drive]]
identity = { vendor_id = 0xECD, product_code = 0x402 }
mode = "cst"
program = [{ step = "torque", torque = 50, slope = 500, hold = 0.2 }]
[[drive]]
alias = 7
profile = "mr-j4-tm"
[drive.mapping]
rx = [{ pdo = 0x1600, entries = ["0x6040:00", "0x607A:00"] }]
tx = [{ pdo = 0x1A00, entries = ["0x6041:00", "0x6064:00"] }]
"#,
    ),
    (
        "unknown-key.toml",
        "interface = \"eth0\"\ncycel = \"1ms\"\n",
    ),
    (
        "bad-unit.toml",
        "interface = \"eth0\"\ncycle = \"1 fortnight\"\n",
    ),
    ("no-sim.toml", "interface = \"sim\"\n"),
    (
        "two-selectors.toml",
        "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\"]\n[[drive]]\nposition = 0\nalias = 5\n",
    ),
    (
        "torque-in-csp.toml",
        "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\"]\n[[drive]]\nposition = 0\nmode = \"csp\"\nprogram = [\n  { step = \"torque\", torque = 10, hold = 1 },\n]\n",
    ),
    (
        "bad-mapping.toml",
        "interface = \"sim\"\n[sim]\ndevices = [\"generic-coe\"]\n[[drive]]\nposition = 0\n[drive.mapping]\nrx = [{ pdo = 0x1A00, entries = [\"0x6041:00\", \"0x9999:01\"] }]\n",
    ),
    ("bad-toml.toml", "interface = \"eth0\n[rt\npriority = = 3\n"),
];

fn main() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let root = repo.join("fuzz/corpus");
    segment_seeds(&root);
    coe_seeds(&root);
    let mut esi: Vec<PathBuf> = Vec::new();
    for d in ["esi", "tests/data/esi"] {
        let mut files: Vec<_> = std::fs::read_dir(repo.join(d))
            .expect("ESI directory")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "xml"))
            .collect();
        files.sort();
        esi.extend(files);
    }
    copy_seeds(
        &root,
        "esi",
        &esi.iter().map(|p| p.as_path()).collect::<Vec<_>>(),
    );
    esi_derived(&root, &esi);
    let cfg: Vec<_> = std::fs::read_dir(repo.join("examples"))
        .expect("examples")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    copy_seeds(
        &root,
        "config",
        &cfg.iter().map(|p| p.as_path()).collect::<Vec<_>>(),
    );
    for (name, text) in CONFIG_SEEDS {
        write(&root.join("config"), name, text.as_bytes());
    }
    println!("config: {} more", CONFIG_SEEDS.len());
}
