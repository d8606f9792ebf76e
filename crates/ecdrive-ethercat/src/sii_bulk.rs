//! Every device's SII read at once, before ethercrab's initialisation reads it device after
//! device: each frame carries one chunk of every device's EEPROM (see [`crate::answers`],
//! which answers ethercrab's reads from it).

use crate::answers::{FIRST_CATEGORY, RAW_INDEX, SII_BUSY, SII_ERRORS, SiiWords};
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
/// The chunks of the fixed header read (words 0–0x3F): the identity (0x08–0x0F), the
/// mailbox (0x18–0x1C), the EEPROM size (0x3E). The rest of it nobody reads at start-up.
const HEADER_CHUNKS: [u16; 5] = [0x08, 0x0C, 0x18, 0x1C, 0x3C];
/// The source address of ecdrive's own frames (locally administered, like ethercrab's).
const SRC: MacAddress = MacAddress([0x10, 0, 0, 0, 0, 0x01]);

/// What one device's read of its SII stands at, in the bulk read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Walk {
    /// The fixed header: this entry of [`HEADER_CHUNKS`] next.
    Header(usize),
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
            Self::Header(i) => HEADER_CHUNKS.get(i).copied(),
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
            Self::Header(i) if i + 1 < HEADER_CHUNKS.len() => Self::Header(i + 1),
            Self::Header(_) => category(FIRST_CATEGORY),
            Self::Category(at) => {
                let (Some(kind), Some(size)) = (w.word(at), w.word(at + 1)) else {
                    return Self::Done;
                };
                if kind == 0xFFFF {
                    return Self::Done;
                }
                let content = at + 2;
                let after = content.saturating_add(size);
                let take = match kind {
                    10 => size.min(STRINGS_WORDS),
                    k if BULK_CATEGORIES.contains(&k) => size,
                    _ => 0,
                };
                // The header's chunk brought the first content words with it.
                let next = content + got.saturating_sub(2).min(take);
                if next < content + take {
                    Self::Content {
                        next,
                        until: content + take,
                        after,
                    }
                } else {
                    category(after)
                }
            }
            Self::Content { next, until, after } if next + got < until => Self::Content {
                next: next + got,
                until,
                after,
            },
            Self::Content { after, .. } => category(after),
            Self::Done => Self::Done,
        }
    }
}

/// Read the SII of the `n` devices on the segment at once, by position (auto-increment
/// addressing: the station addresses are not set yet): each frame carries one 8-byte (or
/// 4-byte) chunk of every device whose read is not done. The header's [`HEADER_CHUNKS`], every
/// category header,
/// and the categories ethercrab reads ([`BULK_CATEGORIES`]). A device whose EEPROM reports an
/// error, or that stops answering, is left with what was read (ethercrab's own reads of the
/// rest go to the wire). Returns the words by position, and the frames sent.
pub fn read_sii_all<L: FrameLink>(
    pump: &mut Pump<'_, L>,
    n: u16,
    deadline_ns: u64,
) -> Result<(Vec<SiiWords>, u64), LinkError> {
    let mut out: Vec<SiiWords> = (0..n).map(|_| SiiWords::default()).collect();
    let mut walks: Vec<Walk> = vec![Walk::Header(0); usize::from(n)];
    // Per device: its last read found the EEPROM busy (poll again, no new command).
    let mut busy = vec![false; usize::from(n)];
    // Per device: reads in a row that did not move its walk on (a device whose EEPROM stays
    // busy, or whose address register does not echo the command, is left to the wire).
    let mut stalls = vec![0u8; usize::from(n)];
    let mut frames = 0u64;
    let mut tx = [0u8; crate::io::MAX_FRAME];
    let mut rx = [0u8; crate::io::MAX_FRAME + 4];
    // The master takes the EEPROM (0x0500 = 0: EtherCAT, not the PDI), every device at once.
    let mut b = FrameBuilder::new(&mut tx, SRC).map_err(frame_err)?;
    b.push(Command::Bwr, RAW_INDEX, raw_address(0, 0x0500), &[0])
        .map_err(frame_err)?;
    let len = b.finish();
    frames += 1;
    pump.exchange_raw(&tx[..len], &mut rx, deadline_ns)?;
    let mut rounds = 0u32;
    while walks.iter().any(|w| *w != Walk::Done) && rounds < 4 * u32::from(MAX_WORD) {
        rounds += 1;
        if crate::rt::monotonic_ns() >= deadline_ns {
            break;
        }
        let active: Vec<u16> = (0..n)
            .filter(|&p| walks[usize::from(p)] != Walk::Done)
            .collect();
        // Per device, in one frame: the read command to 0x0502 (command, word address), then
        // the read of 0x0502–0x050F (status, address, data). The ESC runs the command as the
        // frame passes; an EEPROM slower than that shows busy, and the next frame reads again.
        for part in active.chunks(PER_FRAME) {
            let mut b = FrameBuilder::new(&mut tx, SRC).map_err(frame_err)?;
            for &p in part {
                let adp = 0u16.wrapping_sub(p);
                let word = walks[usize::from(p)].word().unwrap_or(0);
                if !busy[usize::from(p)] {
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
            let Some(got) = pump.exchange_raw(&tx[..len], &mut rx, deadline_ns)? else {
                return Ok((out, frames));
            };
            let reads = datagram_data(&rx[..got])
                .into_iter()
                .filter(|(d, _)| d.len() == 14);
            for (&p, (data, wkc)) in part.iter().zip(reads) {
                let i = usize::from(p);
                let (Some(walk), Some(w)) = (walks.get_mut(i), out.get_mut(i)) else {
                    continue;
                };
                busy[i] = false;
                let before = *walk;
                *walk = taken(before, w, data, wkc, &mut busy[i]);
                stalls[i] = if *walk == before { stalls[i] + 1 } else { 0 };
                if stalls[i] > MAX_STALLS {
                    *walk = Walk::Done;
                }
            }
        }
    }
    Ok((out, frames))
}

/// Reads in a row without progress before a device's bulk read is given up.
const MAX_STALLS: u8 = 50;

/// Devices per frame: a command (18 bytes) and a read (26 bytes) each.
const PER_FRAME: usize = 33;

/// One device's read of 0x0502–0x050F (`data`, its working counter `wkc`) taken into `w`:
/// the walk's next step. Busy: the same step, `busy` set. The data counts only for the word
/// the address register (0x0504) names, when neither busy nor an error shows.
fn taken(walk: Walk, w: &mut SiiWords, data: &[u8], wkc: u16, busy: &mut bool) -> Walk {
    let Some(word) = walk.word() else {
        return Walk::Done;
    };
    if wkc != 1 || data.len() < 14 {
        return Walk::Done;
    }
    let status = u16::from_le_bytes([data[0], data[1]]);
    if status & SII_BUSY != 0 {
        *busy = true;
        return walk;
    }
    if status & SII_ERRORS != 0 {
        return Walk::Done;
    }
    let at = u16::from_le_bytes([data[2], data[3]]);
    if at != word {
        // The command did not take (the interface was busy): ask again.
        return walk;
    }
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
