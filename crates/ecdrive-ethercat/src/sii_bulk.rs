//! Every device's SII read at once, before ethercrab's initialisation reads it device after
//! device: each frame carries one chunk of every device's EEPROM (see [`crate::answers`],
//! which answers ethercrab's reads from it).

use crate::answers::{FIRST_CATEGORY, RAW_INDEX, SII_ACK_ERROR, SII_BUSY, SiiWords};
use crate::ec::command::Command;
use crate::ec::frame::{
    DATAGRAM_HEADER_LEN, EthercatFrame, EthernetFrame, FrameBuilder, MacAddress, WKC_LEN,
};
use crate::ec::register;
use crate::io::{FrameLink, LinkError, Pump};

/// Categories read in bulk: strings (the device's name; the first [`STRINGS_WORDS`] words),
/// general, FMMU, SyncManager, FMMU extension, DC. The PDO categories (50/51), large and read
/// by ethercrab only for devices without CoE, are left to the wire.
const BULK_CATEGORIES: [u16; 6] = [10, 30, 40, 41, 42, 60];
/// Words of the strings category read in bulk: the device name is among the first strings.
const STRINGS_WORDS: u16 = 128;
/// The furthest word the bulk read goes (an EEPROM of 16 Kbit).
const MAX_WORD: u16 = 0x0400;
/// The parts of the fixed header read (words 0–0x3F), as word ranges: the identity
/// (0x08–0x0F), the mailbox (0x18–0x1C), the EEPROM size (0x3E). The rest of it nobody reads
/// at start-up. An ESC reads 8 bytes (4 words) or 4 bytes (2 words) per command: each range is
/// read in as many commands as that takes.
const HEADER_RANGES: [(u16, u16); 3] = [(0x08, 0x10), (0x18, 0x20), (0x3C, 0x40)];
/// The source address of ecdrive's own frames (locally administered, like ethercrab's).
const SRC: MacAddress = MacAddress([0x10, 0, 0, 0, 0, 0x01]);

/// What one device's read of its SII stands at, in the bulk read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Walk {
    /// The fixed header: this word next (in [`HEADER_RANGES`]).
    Header(u16),
    /// The category header at this word next.
    Category(u16),
    /// A category's content: this word next, up to `until`, then the header at `after`.
    Content {
        next: u16,
        until: u16,
        after: u16,
    },
    Done,
}

impl Walk {
    /// The word to read next.
    fn word(self) -> Option<u16> {
        match self {
            Self::Header(w) => Some(w),
            Self::Category(w) | Self::Content { next: w, .. } => Some(w),
            Self::Done => None,
        }
    }

    /// After `got` words were read at [`word`](Self::word) into `w`: the next step.
    fn advance(self, w: &SiiWords, got: u16) -> Self {
        let category = |at: u16| {
            if at >= MAX_WORD {
                Self::Done
            } else {
                Self::Category(at)
            }
        };
        match self {
            Self::Header(at) => {
                let next = at.saturating_add(got);
                match HEADER_RANGES.iter().find(|r| next < r.1) {
                    Some(&(start, _)) => Self::Header(next.max(start)),
                    None => category(FIRST_CATEGORY),
                }
            }
            Self::Category(at) => {
                let (Some(kind), Some(size)) = (w.word(at), w.word(at + 1)) else {
                    return Self::Done;
                };
                if kind == 0xFFFF {
                    return Self::Done;
                }
                let content = at.saturating_add(2);
                let after = content.saturating_add(size);
                let take = match kind {
                    10 => size.min(STRINGS_WORDS),
                    k if BULK_CATEGORIES.contains(&k) => size,
                    _ => 0,
                };
                // The header's chunk brought the first content words with it.
                let until = content.saturating_add(take);
                let next = content.saturating_add(got.saturating_sub(2).min(take));
                if next < until {
                    Self::Content { next, until, after }
                } else {
                    category(after)
                }
            }
            Self::Content { next, until, after } if next.saturating_add(got) < until => {
                Self::Content {
                    next: next + got,
                    until,
                    after,
                }
            }
            Self::Content { after, .. } => category(after),
            Self::Done => Self::Done,
        }
    }
}

/// Read the SII of the `n` devices on the segment at once, by position (auto-increment
/// addressing: the station addresses are not set yet): each frame carries one 8-byte (or
/// 4-byte) chunk of every device whose read is not done. The header's [`HEADER_RANGES`], every
/// category header, and the categories ethercrab reads ([`BULK_CATEGORIES`]). A device whose EEPROM reports an
/// error, or that stops answering, is left with what was read (ethercrab's own reads of the
/// rest go to the wire). Returns the words by position, and the frames sent.
pub fn read_sii_all<L: FrameLink>(
    pump: &mut Pump<'_, L>,
    n: u16,
    deadline_ns: u64,
) -> Result<(Vec<SiiWords>, u64), LinkError> {
    let mut out: Vec<SiiWords> = (0..n).map(|_| SiiWords::default()).collect();
    let mut walks: Vec<Walk> = vec![Walk::Header(HEADER_RANGES[0].0); usize::from(n)];
    let mut reads: Vec<Reading> = vec![Reading::default(); usize::from(n)];
    let mut frames = 0u64;
    let mut tx = [0u8; crate::io::MAX_FRAME];
    let mut rx = [0u8; crate::io::MAX_FRAME + 4];
    // The master takes the EEPROM (0x0500 = 0: EtherCAT, not the PDI), every device at once.
    let mut b = FrameBuilder::new(&mut tx, SRC).map_err(frame_err)?;
    b.push(Command::Bwr, RAW_INDEX, raw_address(0, 0x0500), &[0])
        .map_err(frame_err)?;
    let len = b.finish();
    frames += 1;
    // Lost, it changes nothing: the EEPROM is the master's after power-on.
    let first = deadline_ns.min(crate::rt::monotonic_ns() + FRAME_TIMEOUT_NS);
    pump.exchange_raw(&tx[..len], &mut rx, first)?;
    let mut rounds = 0u32;
    while walks.iter().any(|w| *w != Walk::Done) && rounds < 16 * u32::from(MAX_WORD) {
        rounds += 1;
        if crate::rt::monotonic_ns() >= deadline_ns {
            break;
        }
        let active: Vec<u16> = (0..n)
            .filter(|&p| walks[usize::from(p)] != Walk::Done)
            .collect();
        // Per device, in one frame: the read command to 0x0502 (command, word address), then
        // the read of 0x0502–0x050F (status, address, data). An ESC that runs the command as
        // the frame passes shows its result at once; one that takes register writes at the
        // end of the frame, or an EEPROM slower than the frame, shows the result in a later
        // frame, which only reads (see [`Reading`]).
        for part in active.chunks(PER_FRAME) {
            let mut b = FrameBuilder::new(&mut tx, SRC).map_err(frame_err)?;
            for &p in part {
                let adp = 0u16.wrapping_sub(p);
                let word = walks[usize::from(p)].word().unwrap_or(0);
                let r = &mut reads[usize::from(p)];
                r.commanded = !r.poll;
                if r.commanded {
                    let mut req = [0u8; 6];
                    req[0..2].copy_from_slice(&0x0100u16.to_le_bytes());
                    req[2..4].copy_from_slice(&word.to_le_bytes());
                    b.push(
                        Command::Apwr,
                        RAW_INDEX,
                        raw_address(adp, register::SII_CONTROL),
                        &req,
                    )
                    .map_err(frame_err)?;
                }
                b.push(
                    Command::Aprd,
                    RAW_INDEX,
                    raw_address(adp, register::SII_CONTROL),
                    &[0u8; 14],
                )
                .map_err(frame_err)?;
            }
            let len = b.finish();
            frames += 1;
            // A frame lost is sent again (as the next round), within the deadline.
            let frame_deadline = deadline_ns.min(crate::rt::monotonic_ns() + FRAME_TIMEOUT_NS);
            let mut reply = pump.exchange_raw(&tx[..len], &mut rx, frame_deadline)?;
            // A late reply to an earlier frame (one given up as lost) is not this one's: its
            // datagrams may be other devices'.
            while let Some(got) = reply
                && !same_shape(&tx[..len], &rx[..got], n)
            {
                reply = pump.receive_raw(&mut rx, frame_deadline)?;
            }
            let Some(got) = reply else {
                for &p in part {
                    let r = &mut reads[usize::from(p)];
                    r.stalls += 1;
                    if r.stalls > MAX_STALLS {
                        walks[usize::from(p)] = Walk::Done;
                    }
                }
                continue;
            };
            let replies = datagram_data(&rx[..got])
                .into_iter()
                .filter(|(d, _)| d.len() == 14);
            for (&p, (data, wkc)) in part.iter().zip(replies) {
                let i = usize::from(p);
                let (Some(walk), Some(w), Some(r)) =
                    (walks.get_mut(i), out.get_mut(i), reads.get_mut(i))
                else {
                    continue;
                };
                *walk = r.take(*walk, w, data, wkc);
            }
        }
    }
    Ok((out, frames))
}

/// Reads in a row whose address did not echo the command (after a frame that only read),
/// or frames lost, before a device's bulk read is given up.
const MAX_STALLS: u16 = 50;
/// Reads in a row that found the EEPROM busy before a device's bulk read is given up (an
/// 8-byte read takes well under a millisecond; this is far more than any frame rate needs).
const MAX_BUSY: u16 = 5000;
/// How long one frame of the bulk read is waited for before it is sent again.
const FRAME_TIMEOUT_NS: u64 = 20_000_000;

/// One device's read in progress.
#[derive(Debug, Clone, Copy, Default)]
struct Reading {
    /// The next frame only reads (a command is running, or may have been taken at the end of
    /// the frame that carried it).
    poll: bool,
    /// This frame carries a command.
    commanded: bool,
    stalls: u16,
    busy: u16,
}

impl Reading {
    /// The device's read of 0x0502–0x050F (`data`, its working counter `wkc`) taken into `w`:
    /// the walk's next step. The data counts only for the word the address register (0x0504)
    /// names, when the EEPROM is not busy and shows no acknowledge error.
    fn take(&mut self, walk: Walk, w: &mut SiiWords, data: &[u8], wkc: u16) -> Walk {
        let Some(word) = walk.word() else {
            return Walk::Done;
        };
        if wkc != 1 || data.len() < 14 {
            return Walk::Done;
        }
        let status = u16::from_le_bytes([data[0], data[1]]);
        if status & SII_BUSY != 0 {
            self.poll = true;
            self.busy += 1;
            return if self.busy > MAX_BUSY {
                Walk::Done
            } else {
                walk
            };
        }
        self.busy = 0;
        // Missing acknowledge (or an invalid command): this device's reads are left to the
        // wire. The checksum, loading and write-enable bits say nothing about this read
        // (ethercrab takes its data with them too).
        if status & SII_ACK_ERROR != 0 {
            return Walk::Done;
        }
        let at = u16::from_le_bytes([data[2], data[3]]);
        if at != word {
            // The command of this frame may be taken at its end: read once more before
            // commanding again; after a frame that only read, the command did not take.
            if self.commanded {
                self.poll = true;
            } else {
                self.poll = false;
                self.stalls += 1;
            }
            return if self.stalls > MAX_STALLS {
                Walk::Done
            } else {
                walk
            };
        }
        self.poll = false;
        self.stalls = 0;
        let words: u16 = if status & 0x0040 != 0 { 4 } else { 2 };
        w.set_status(status);
        for k in 0..words {
            let b = 6 + 2 * usize::from(k);
            w.insert(
                word.wrapping_add(k),
                u16::from_le_bytes([data[b], data[b + 1]]),
            );
        }
        walk.advance(w, words)
    }
}

/// Devices per frame: a command (18 bytes) and a read (26 bytes) each.
const PER_FRAME: usize = 33;

fn frame_err(e: crate::ec::frame::FrameError) -> LinkError {
    LinkError::Io {
        interface: String::new(),
        op: "building the SII read frame",
        source: std::io::Error::other(e),
    }
}

/// ADP | ADO << 16.
fn raw_address(adp: u16, ado: u16) -> u32 {
    crate::ec::frame::physical_address(adp, ado)
}

/// Whether `reply` is the reply to `request` on a segment of `n` devices: the same datagrams
/// (command, offset, length), each auto-increment address moved on by every device. A late
/// reply to an earlier frame for other devices differs in an address.
fn same_shape(request: &[u8], reply: &[u8], n: u16) -> bool {
    /// Command, ADP, ADO, data length.
    type Shape = (Option<Command>, u16, u16, usize);
    let parse = |f: &[u8]| -> Option<Vec<Shape>> {
        let eth = EthernetFrame::new_checked(f).ok()?;
        let ecat = EthercatFrame::new_checked(eth.payload()).ok()?;
        ecat.datagrams()
            .map(|d| {
                d.ok()
                    .map(|d| (d.command(), d.adp(), d.ado(), d.data_len()))
            })
            .collect()
    };
    let (Some(a), Some(b)) = (parse(request), parse(reply)) else {
        return false;
    };
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| x.0 == y.0 && x.2 == y.2 && x.3 == y.3 && y.1 == x.1.wrapping_add(n))
}

/// Each datagram's data and working counter, in order.
fn datagram_data(frame: &[u8]) -> Vec<(&[u8], u16)> {
    let Ok(eth) = EthernetFrame::new_checked(frame) else {
        return Vec::new();
    };
    let Ok(ecat) = EthercatFrame::new_checked(eth.payload()) else {
        return Vec::new();
    };
    let off = eth.payload_offset() + 2;
    let mut at = off;
    let mut out = Vec::new();
    for d in ecat.datagrams() {
        let Ok(d) = d else { break };
        let len = d.data_len();
        let data = frame.get(at + DATAGRAM_HEADER_LEN..at + DATAGRAM_HEADER_LEN + len);
        if let Some(data) = data {
            out.push((data, d.wkc()));
        }
        at += DATAGRAM_HEADER_LEN + len + WKC_LEN;
    }
    out
}
