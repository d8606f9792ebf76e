//! `--pcap FILE`: the master's frames, both directions, with timestamps, as pcapng (Wireshark's
//! EtherCAT dissector reads it), written off the thread that moves the frames.
//!
//! The thread that sends and receives (ecdrive's cycle thread in `run`, the session thread of a
//! tool) only copies each frame into a slot of a lock-free ring ([`CaptureTap::frame`]: no
//! allocation, no syscall; the timestamp is `CLOCK_REALTIME`, read through the vDSO). A writer
//! thread drains the ring into the file ([`CaptureFile`]), with the well-kept `pcap-file` crate:
//! one Section Header, one Interface Description (Ethernet, nanosecond timestamps, the
//! interface's name) and one Enhanced Packet Block per frame, its direction in the EPB flags
//! (outbound: sent by the master; inbound: the reply). A full ring drops the frame and counts it;
//! the cycle never waits for the disk.

use pcap_file::DataLink;
use pcap_file::pcapng::PcapNgWriter;
use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use std::borrow::Cow;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// Largest frame kept whole (an Ethernet frame without its FCS).
const MAX_FRAME: usize = 1514;
/// Frames the ring holds (\[REC\]: about 2 s of a 1 kHz cycle's two frames, 6 MB).
pub const RING: usize = 4096;

struct Slot {
    ns: u64,
    outbound: bool,
    len: u16,
    data: [u8; MAX_FRAME],
}

/// The side of the thread that moves frames.
pub struct CaptureTap {
    tx: rtrb::Producer<Slot>,
    dropped: Arc<AtomicU64>,
}

impl core::fmt::Debug for CaptureTap {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("CaptureTap").finish_non_exhaustive()
    }
}

impl CaptureTap {
    /// Keep a copy of one frame (`outbound`: sent by the master). Never blocks: when the ring
    /// is full the frame is counted as dropped.
    pub fn frame(&mut self, outbound: bool, bytes: &[u8]) {
        let ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        let len = bytes.len().min(MAX_FRAME);
        let mut data = [0u8; MAX_FRAME];
        if let (Some(dst), Some(src)) = (data.get_mut(..len), bytes.get(..len)) {
            dst.copy_from_slice(src);
        }
        let slot = Slot {
            ns,
            outbound,
            len: len as u16,
            data,
        };
        if self.tx.push(slot).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// What a capture wrote.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct CaptureSummary {
    /// The file.
    pub path: PathBuf,
    /// Frames written.
    pub frames: u64,
    /// Frames dropped because the ring was full (the writer fell behind).
    pub dropped: u64,
}

/// The writer thread and its file.
pub struct CaptureFile {
    stop: Arc<AtomicBool>,
    dropped: Arc<AtomicU64>,
    thread: JoinHandle<Result<u64, String>>,
    path: PathBuf,
}

/// Start a capture into `path` for the interface `interface`.
pub fn start(path: &Path, interface: &str) -> Result<(CaptureTap, CaptureFile), String> {
    let file = std::fs::File::create(path)
        .map_err(|e| format!("creating the capture {}: {e}", path.display()))?;
    let mut writer = PcapNgWriter::new(BufWriter::new(file))
        .map_err(|e| format!("writing the capture {}: {e}", path.display()))?;
    writer
        .write_pcapng_block(InterfaceDescriptionBlock {
            linktype: DataLink::ETHERNET,
            snaplen: 0,
            options: vec![
                InterfaceDescriptionOption::IfName(Cow::Owned(interface.to_string())),
                InterfaceDescriptionOption::IfTsResol(9),
            ],
        })
        .map_err(|e| format!("writing the capture {}: {e}", path.display()))?;
    let (tx, mut rx) = rtrb::RingBuffer::<Slot>::new(RING);
    let stop = Arc::new(AtomicBool::new(false));
    let dropped = Arc::new(AtomicU64::new(0));
    let s = stop.clone();
    let shown = path.display().to_string();
    let thread = std::thread::Builder::new()
        .name("ecdrive-pcap".into())
        .spawn(move || {
            let mut frames = 0u64;
            loop {
                let done = s.load(Ordering::Acquire);
                while let Ok(slot) = rx.pop() {
                    let len = usize::from(slot.len);
                    writer
                        .write_pcapng_block(EnhancedPacketBlock {
                            interface_id: 0,
                            timestamp: Duration::from_nanos(slot.ns),
                            original_len: u32::from(slot.len),
                            data: Cow::Borrowed(slot.data.get(..len).unwrap_or(&[])),
                            // Direction (bits 0–1): 1 inbound, 2 outbound.
                            options: vec![EnhancedPacketOption::Flags(if slot.outbound {
                                2
                            } else {
                                1
                            })],
                        })
                        .map_err(|e| format!("writing the capture {shown}: {e}"))?;
                    frames += 1;
                }
                if done {
                    break;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            use std::io::Write as _;
            writer
                .get_mut()
                .flush()
                .map_err(|e| format!("writing the capture {shown}: {e}"))?;
            Ok(frames)
        })
        .map_err(|e| format!("starting the capture writer: {e}"))?;
    Ok((
        CaptureTap {
            tx,
            dropped: dropped.clone(),
        },
        CaptureFile {
            stop,
            dropped,
            thread,
            path: path.to_path_buf(),
        },
    ))
}

impl CaptureFile {
    /// Write what is left and close the file (drop the [`CaptureTap`] first, or its last frames
    /// may be missed).
    pub fn finish(self) -> Result<CaptureSummary, String> {
        self.stop.store(true, Ordering::Release);
        let frames = self
            .thread
            .join()
            .map_err(|_| "the capture writer panicked".to_string())??;
        Ok(CaptureSummary {
            path: self.path,
            frames,
            dropped: self.dropped.load(Ordering::Relaxed),
        })
    }
}
