//! Answers to ethercrab's re-reads, from what ecdrive has read or written moments before.
//!
//! ethercrab 0.7.1 builds its view of the segment by reading, one frame at a time and device
//! after device: each device's SII (EEPROM) through the SII registers 0x0502–0x050F, several
//! times over (identity and name at discovery, the SyncManager and FMMU categories once per
//! direction when it builds the process image), and, for a device with CoE, the PDO assignment
//! (0x1C12/0x1C13) and every mapping entry (0x16xx/0x1Axx), each by one expedited SDO upload of
//! some five frames. ecdrive reads every device's SII at once before ethercrab starts (the
//! crate's `sii_bulk` module: one frame carries a chunk of every device's EEPROM), and it has
//! just written each drive's PDO configuration by SDO, each write acknowledged by the drive.
//!
//! [`Answers`] answers those frames of ethercrab's from that: the [`Pump`](crate::io::Pump)
//! asks it about every frame before sending, and a frame whose every datagram it can answer
//! does not go on the wire; ethercrab gets the reply the device would have given. What it
//! answers:
//!
//! - an SII read (FPWR of the read command to 0x0502, then FPRD of 0x0502 and of 0x0508) of
//!   words read in bulk from that very device;
//! - a mailbox exchange (the SyncManager status reads, the request written to the write
//!   mailbox, the response read from the read mailbox) whose request is an expedited SDO
//!   upload of an object the drive acknowledged writing in this start-up, with the value
//!   written; only for a drive whose every upload at the process image is so covered (the PDO
//!   assignment and mappings of each of its process data SyncManagers), so that no request of
//!   ethercrab's goes to the wire after status reads answered "empty".
//!
//! Anything else goes to the wire, unchanged: other registers, SII words not read in bulk (and
//! the busy polls after such a command: the device's EEPROM may be busy with it), any other
//! mailbox request (from then on the device's mailbox is the wire's until its next answered
//! request). A drive that acknowledged a mapping and does not hold it is refused at
//! SAFE-OP by the drive itself (its SyncManager lengths are checked against its mapping,
//! AL status code 0x001D/0x001E), which start-up names. The switch is
//! [`BusOptions::answer_rereads`](crate::bus::BusOptions::answer_rereads); off,
//! every read goes to the wire as ethercrab sends it.

use crate::ec::command::Command;
use crate::ec::frame::{DATAGRAM_HEADER_LEN, EthercatFrame, EthernetFrame, MAC_LOCAL_BIT, WKC_LEN};
use crate::ec::register;
use crate::od::ObjectAddress;
use std::collections::{HashMap, HashSet};

/// The first SII word of the categories (ETG.1000.6 / ETG.2010).
pub(crate) const FIRST_CATEGORY: u16 = 0x0040;
/// Index of ecdrive's own frames' datagrams: outside ethercrab's frame indices.
pub const RAW_INDEX: u8 = 0xEC;
/// SII control/status: busy (bit 15), the error bits (11–14), the command bits (8–10).
pub(crate) const SII_BUSY: u16 = 0x8000;
const SII_ERRORS: u16 = 0x7800;
/// The error bit of a read that failed: missing EEPROM acknowledge, or an invalid command.
pub(crate) const SII_ACK_ERROR: u16 = 0x2000;
const SII_COMMAND: u16 = 0x0700;
/// A SyncManager's status byte (0x0805 + 8n): mailbox full.
const SM_MAILBOX_FULL: u8 = 0x08;

/// One device's SII words as read in bulk, and its control/status register's capability bits.
#[derive(Debug, Clone, Default)]
pub struct SiiWords {
    words: HashMap<u16, u16>,
    /// 0x0502 as the device shows it idle (read size and addressing bits).
    status: u16,
}

impl SiiWords {
    /// The word at `addr`, if it was read.
    pub fn word(&self, addr: u16) -> Option<u16> {
        self.words.get(&addr).copied()
    }
    /// How many words were read.
    pub fn len(&self) -> usize {
        self.words.len()
    }
    /// Whether nothing was read.
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }
    /// Note the word at `addr`.
    pub fn insert(&mut self, addr: u16, value: u16) {
        self.words.insert(addr, value);
    }
    /// Note 0x0502 as the device shows it (busy, error and command bits dropped).
    pub fn set_status(&mut self, status: u16) {
        self.status = status & !(SII_BUSY | SII_ERRORS | SII_COMMAND);
    }
    /// The word `off` words after `base` (None past the 16-bit word addresses, or not read).
    fn word_after(&self, base: u16, off: u32) -> Option<u16> {
        self.word(u16::try_from(u32::from(base) + off).ok()?)
    }

    /// The SyncManagers of the SyncManager category (41): (number, start, length, type), the
    /// type being 1 (mailbox the master writes), 2 (mailbox it reads), 3 (outputs), 4
    /// (inputs). An empty list when the SII has no such category; None when a word of it was
    /// not read.
    fn sync_managers(&self) -> Option<Vec<(u8, u16, u16, u8)>> {
        let mut at = FIRST_CATEGORY;
        loop {
            let (t, size) = (self.word(at)?, self.word_after(at, 1)?);
            if t == 0xFFFF {
                return Some(Vec::new());
            }
            if t == 41 {
                let mut sms = Vec::new();
                for n in 0..u32::from(size / 4) {
                    let w = 2 + 4 * n;
                    let start = self.word_after(at, w)?;
                    let len = self.word_after(at, w + 1)?;
                    let ty = self.word_after(at, w + 3)?;
                    sms.push((u8::try_from(n).ok()?, start, len, (ty >> 8) as u8));
                }
                return Some(sms);
            }
            at = u16::try_from(u32::from(at) + 2 + u32::from(size)).ok()?;
        }
    }

    /// The (number, start, length) of the mailbox SyncManager of `kind` (1: the master writes,
    /// 2: the master reads), from the SyncManager category.
    fn mailbox_sm(&self, kind: u8) -> Option<(u8, u16, u16)> {
        self.sync_managers()?
            .into_iter()
            .find(|s| s.3 == kind)
            .map(|(n, start, len, _)| (n, start, len))
    }
}

/// One device's mailbox, as far as the answers go.
#[derive(Debug, Clone, Default)]
struct Mailbox {
    /// (SyncManager, start, length) of the mailbox the master writes and of the one it reads.
    write: (u8, u16, u16),
    read: (u8, u16, u16),
    /// The objects the drive acknowledged writing, and their last value.
    values: HashMap<(u16, u8), Vec<u8>>,
    /// The response to the request answered last, until it is read.
    response: Option<Vec<u8>>,
    /// The last request went to the wire: the mailbox is the wire's until the next answered one.
    wire: bool,
    /// The counter of the last request the device itself got (0: none known).
    wire_counter: u8,
}

impl Mailbox {
    /// A value the drive acknowledged, as an unsigned number (little-endian, 1 to 4 bytes).
    fn value(&self, index: u16, sub: u8) -> Option<u32> {
        let v = self.values.get(&(index, sub))?;
        let mut b = [0u8; 4];
        b.get_mut(..v.len())?.copy_from_slice(v);
        Some(u32::from_le_bytes(b))
    }

    /// Whether every upload ethercrab makes when it builds the process image is answered from
    /// the acknowledged values: for each process data SyncManager n of the SII (`pd_sms`), the
    /// PDO assignment 0x1C10 + n (its count and entries), and each assigned PDO's mapping (its
    /// count and entries). Only then are the device's mailbox status reads answered: a request
    /// going to the wire after status reads answered "empty" could meet an emergency that
    /// arrived meanwhile, which ethercrab 0.7.1 would take for the response and panic on.
    fn covers_image_reads(&self, pd_sms: &[u8]) -> bool {
        pd_sms.iter().all(|&n| {
            let assign = 0x1C10 + u16::from(n);
            let Some(count) = self.value(assign, 0) else {
                return false;
            };
            (1..=count.min(255) as u8).all(|i| {
                let Some(pdo) = self.value(assign, i) else {
                    return false;
                };
                let pdo = pdo as u16;
                let Some(entries) = self.value(pdo, 0) else {
                    return false;
                };
                (1..=entries.min(255) as u8).all(|j| self.value(pdo, j).is_some())
            })
        })
    }
}

/// Answers to ethercrab's re-reads; see the [module documentation](self).
#[derive(Debug, Default)]
pub struct Answers {
    /// SII words by position, until the station addresses are known.
    by_position: Vec<SiiWords>,
    /// Station address → position (learnt from the station address writes ethercrab sends).
    stations: HashMap<u16, u16>,
    /// Station address → the SII word a read command asked for, answered here.
    sii_pending: HashMap<u16, u16>,
    /// Stations whose last SII command went to the wire: their EEPROM interface may be busy,
    /// so their status reads go to the wire too until a command is answered here again.
    sii_wire: HashSet<u16>,
    /// Station address → mailbox.
    mailboxes: HashMap<u16, Mailbox>,
    /// Frames answered.
    answered: u64,
}

/// What one datagram of a frame does, when it can be answered.
enum Answer {
    /// Note the read command (station, word).
    SiiCommand(u16, u16),
    /// These bytes as the data.
    Data(Vec<u8>),
    /// A mailbox request answered: (station, response).
    Request(u16, Vec<u8>),
    /// The response of the mailbox read (station), then forget it.
    Response(u16, Vec<u8>),
    /// Learn a station address (position, station); the frame still goes to the wire.
    Learn,
}

impl Answers {
    /// Answers from the SII words read in bulk, by position.
    pub fn new(by_position: Vec<SiiWords>) -> Self {
        Self {
            by_position,
            ..Self::default()
        }
    }

    /// How many frames were answered here so far.
    pub fn answered(&self) -> u64 {
        self.answered
    }

    /// The SII words read from the device at `position`.
    pub fn sii(&self, position: u16) -> Option<&SiiWords> {
        self.by_position.get(usize::from(position))
    }

    /// The counter of the last mailbox request the device at `station` got (from the bus's
    /// record): a request that goes to the wire after answered ones must not repeat it, or the
    /// device drops it as a repeat (ETG.1000.4 mailbox counter).
    pub fn last_counter(&mut self, station: u16, counter: u8) {
        if let Some(m) = self.mailboxes.get_mut(&station) {
            m.wire_counter = counter;
        }
    }

    /// The drive at `station` acknowledged writing `value` to `object`: answer uploads of it.
    pub fn acknowledged(&mut self, station: u16, object: ObjectAddress, value: &[u8]) {
        let Some(&pos) = self.stations.get(&station) else {
            return;
        };
        let Some(sii) = self.by_position.get(usize::from(pos)) else {
            return;
        };
        let (Some(write), Some(read)) = (sii.mailbox_sm(1), sii.mailbox_sm(2)) else {
            return;
        };
        let m = self.mailboxes.entry(station).or_insert_with(|| Mailbox {
            write,
            read,
            ..Mailbox::default()
        });
        m.values.insert((object.index, object.sub), value.to_vec());
    }

    fn sii_of(&self, station: u16) -> Option<&SiiWords> {
        self.by_position
            .get(usize::from(*self.stations.get(&station)?))
    }

    /// The mailbox of `station`, when its traffic may be answered here: its last request was
    /// answered (or none was made yet), and every upload ethercrab will make is covered
    /// ([`Mailbox::covers_image_reads`]).
    fn answerable(&self, station: u16) -> Option<&Mailbox> {
        let m = self.mailboxes.get(&station).filter(|m| !m.wire)?;
        let pd: Vec<u8> = self
            .sii_of(station)?
            .sync_managers()?
            .into_iter()
            .filter(|s| s.3 == 3 || s.3 == 4)
            .map(|s| s.0)
            .collect();
        m.covers_image_reads(&pd).then_some(m)
    }

    /// What the datagram `d` (command, ADP, ADO, data) gets, if it can be answered here.
    fn classify(&self, cmd: Option<Command>, adp: u16, ado: u16, data: &[u8]) -> Option<Answer> {
        match cmd? {
            Command::Apwr if ado == register::STATION_ADDRESS && data.len() >= 2 => {
                Some(Answer::Learn)
            }
            Command::Fpwr if ado == register::SII_CONTROL && data.len() >= 4 => {
                let ctl = u16::from_le_bytes([data[0], data[1]]);
                let word = u16::from_le_bytes([data[2], data[3]]);
                let sii = self.sii_of(adp)?;
                let chunk = if sii.status & 0x0040 != 0 { 4 } else { 2 };
                let cached = (0..chunk).all(|k| sii.word(word.wrapping_add(k)).is_some());
                (ctl & SII_COMMAND == 0x0100 && cached).then_some(Answer::SiiCommand(adp, word))
            }
            Command::Fprd if ado == register::SII_CONTROL => {
                // The status alone (ethercrab's poll of the busy bit) is the idle status the
                // bulk read ended with, unless a command went to the wire (the device's EEPROM
                // may be busy with it); with the address and data, only for a read answered
                // here.
                if self.sii_wire.contains(&adp) {
                    return None;
                }
                if data.len() > 2 {
                    self.sii_pending.get(&adp)?;
                }
                let sii = self.sii_of(adp)?;
                if sii.status == 0 && sii.is_empty() {
                    return None;
                }
                let mut b = vec![0u8; data.len()];
                for (k, byte) in b.iter_mut().enumerate() {
                    // 0x0502–0x0503 the idle status; 0x0504– the address, 0x0508– the data.
                    *byte = match k {
                        0 => sii.status as u8,
                        1 => (sii.status >> 8) as u8,
                        _ => self.sii_byte(adp, k)?,
                    };
                }
                Some(Answer::Data(b))
            }
            Command::Fprd if ado == register::SII_DATA => {
                self.sii_pending.get(&adp)?;
                let b = (0..data.len())
                    .map(|k| self.sii_byte(adp, k + 6))
                    .collect::<Option<Vec<u8>>>()?;
                Some(Answer::Data(b))
            }
            Command::Fprd if data.len() == 1 => {
                let m = self.answerable(adp)?;
                if ado == register::sm(m.read.0) + 5 {
                    Some(Answer::Data(vec![if m.response.is_some() {
                        SM_MAILBOX_FULL
                    } else {
                        0
                    }]))
                } else if ado == register::sm(m.write.0) + 5 {
                    Some(Answer::Data(vec![0]))
                } else {
                    None
                }
            }
            Command::Fpwr => {
                let m = self.answerable(adp)?;
                if ado != m.write.1 {
                    return None;
                }
                upload_response(m, data).map(|r| Answer::Request(adp, r))
            }
            Command::Fprd => {
                let m = self.answerable(adp)?;
                let r = m.response.as_ref()?;
                (ado == m.read.1).then(|| {
                    let mut b = vec![0u8; data.len()];
                    let n = r.len().min(b.len());
                    b[..n].copy_from_slice(&r[..n]);
                    Answer::Response(adp, b)
                })
            }
            _ => None,
        }
    }

    /// Byte `k` of the SII registers from 0x0502 (2: the address, 6: the data) for the read
    /// pending at `station`.
    fn sii_byte(&self, station: u16, k: usize) -> Option<u8> {
        let word = *self.sii_pending.get(&station)?;
        match k {
            2..=5 => Some(u32::from(word).to_le_bytes()[k - 2]),
            6..=13 => {
                let w = self
                    .sii_of(station)?
                    .word(word.wrapping_add((k as u16 - 6) / 2))?;
                Some(w.to_le_bytes()[(k - 6) % 2])
            }
            _ => None,
        }
    }

    /// What to do with the frame ethercrab is about to send. [`Verdict::Answered`]: every
    /// datagram in it was answered, the reply is in `buf`. [`Verdict::Rewritten`]: it goes to
    /// the wire as `buf` holds it (a mailbox request's counter changed so that the device does
    /// not take it for a repeat). [`Verdict::Wire`]: as it is. What it changes is noted (a
    /// station address, a mailbox request sent).
    pub fn answer(&mut self, frame: &[u8], buf: &mut [u8]) -> Verdict {
        match self.answer_inner(frame, buf) {
            Some(v) => v,
            None => Verdict::Wire,
        }
    }

    fn answer_inner(&mut self, frame: &[u8], reply: &mut [u8]) -> Option<Verdict> {
        let eth = EthernetFrame::new_checked(frame).ok()?;
        let ecat = EthercatFrame::new_checked(eth.payload()).ok()?;
        let mut plan: Vec<(Answer, usize)> = Vec::new();
        let mut all = true;
        // A mailbox request to the wire whose counter the device saw last: (byte offset of the
        // counter in the frame, the counter to put there).
        let mut recount: Option<(usize, u8)> = None;
        let mut at = eth.payload_offset() + 2;
        for d in ecat.datagrams() {
            let Ok(d) = d else { return None };
            let len = d.data_len();
            match self.classify(d.command(), d.adp(), d.ado(), d.data()) {
                Some(Answer::Learn) => {
                    let data = d.data();
                    let station = u16::from_le_bytes([data[0], data[1]]);
                    self.stations.insert(station, 0u16.wrapping_sub(d.adp()));
                    all = false;
                }
                Some(a) => plan.push((a, at)),
                None => {
                    all = false;
                    if d.command() == Some(Command::Fpwr) && d.ado() == register::SII_CONTROL {
                        // A read of words not read in bulk (or another command): the device's
                        // registers answer, its status included.
                        self.sii_pending.remove(&d.adp());
                        self.sii_wire.insert(d.adp());
                    }
                    if d.command() == Some(Command::Fpwr)
                        && let Some(m) = self.mailboxes.get_mut(&d.adp())
                        && d.ado() == m.write.1
                        && let Some(&kind) = d.data().get(5)
                    {
                        m.wire = true;
                        m.response = None;
                        let mut c = (kind >> 4) & 0x07;
                        if c != 0 && c == m.wire_counter {
                            c = c % 7 + 1;
                            recount =
                                Some((at + DATAGRAM_HEADER_LEN + 5, (kind & 0x8F) | (c << 4)));
                        }
                        m.wire_counter = c;
                    }
                }
            }
            at += DATAGRAM_HEADER_LEN + len + WKC_LEN;
        }
        if frame.len() > reply.len() {
            return None;
        }
        if let Some((at, kind)) = recount {
            let out = &mut reply[..frame.len()];
            out.copy_from_slice(frame);
            *out.get_mut(at)? = kind;
            return Some(Verdict::Rewritten(frame.len()));
        }
        if !all || plan.is_empty() {
            return None;
        }
        let reply = &mut reply[..frame.len()];
        reply.copy_from_slice(frame);
        // The source address as a slave controller leaves it on a frame it forwarded.
        reply[6] |= MAC_LOCAL_BIT;
        for (a, at) in plan {
            let data_at = at + DATAGRAM_HEADER_LEN;
            let len = usize::from(u16::from_le_bytes([reply[at + 6], reply[at + 7]]) & 0x07FF);
            let fill = |reply: &mut [u8], b: &[u8]| {
                let n = b.len().min(len);
                reply[data_at..data_at + n].copy_from_slice(&b[..n]);
            };
            match a {
                Answer::SiiCommand(station, word) => {
                    self.sii_pending.insert(station, word);
                    self.sii_wire.remove(&station);
                }
                Answer::Data(b) => fill(reply, &b),
                Answer::Request(station, r) => {
                    if let Some(m) = self.mailboxes.get_mut(&station) {
                        m.response = Some(r);
                        m.wire = false;
                    }
                }
                Answer::Response(station, b) => {
                    fill(reply, &b);
                    if let Some(m) = self.mailboxes.get_mut(&station) {
                        m.response = None;
                    }
                }
                Answer::Learn => {}
            }
            reply[data_at + len..data_at + len + WKC_LEN].copy_from_slice(&1u16.to_le_bytes());
        }
        self.answered += 1;
        Some(Verdict::Answered(frame.len()))
    }
}

/// What [`Answers::answer`] decided for a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Sent as it is.
    Wire,
    /// Sent as rewritten into the buffer (this long).
    Rewritten(usize),
    /// Answered: the reply is in the buffer (this long); nothing is sent.
    Answered(usize),
}

/// The response to the mailbox request `req` written to `m`'s write mailbox, when it is an
/// expedited SDO upload (not complete access) of an object in `m.values` of at most 4 bytes.
fn upload_response(m: &Mailbox, req: &[u8]) -> Option<Vec<u8>> {
    // Mailbox header: length, address, channel/priority, type (low nibble; 3 CoE) and counter.
    let kind = *req.get(5)?;
    let coe = u16::from_le_bytes([*req.get(6)?, *req.get(7)?]);
    let cmd = *req.get(8)?;
    let index = u16::from_le_bytes([*req.get(9)?, *req.get(10)?]);
    let sub = *req.get(11)?;
    // CoE service 2 (SDO request), command specifier 2 (upload), complete access off.
    if kind & 0x0F != 3 || coe >> 12 != 2 || cmd >> 5 != 2 || cmd & 0x10 != 0 {
        return None;
    }
    let value = m
        .values
        .get(&(index, sub))
        .filter(|v| (1..=4).contains(&v.len()))?;
    let mut r = vec![0u8; 16];
    r[0..2].copy_from_slice(&10u16.to_le_bytes());
    r[5] = kind;
    // CoE header: SDO response (service 3).
    r[6..8].copy_from_slice(&0x3000u16.to_le_bytes());
    // Upload response, expedited, size indicated, 4 − n bytes unused.
    r[8] = 0x40 | 0x02 | 0x01 | (((4 - value.len()) as u8) << 2);
    r[9..11].copy_from_slice(&index.to_le_bytes());
    r[11] = sub;
    r[12..12 + value.len()].copy_from_slice(value);
    Some(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ec::frame::{FrameBuilder, MacAddress, physical_address};
    use crate::ec::mailbox::{MailboxMessage, SdoRequest, SdoResponse};

    const STATION: u16 = 0x1000;

    /// One device at position 0 whose SII has words 0x08–0x0B and a SyncManager category with
    /// SM0 (mailbox out, 0x1000/128), SM1 (mailbox in, 0x1080/128), SM2 (outputs) and SM3
    /// (inputs); the station address learnt from the write ethercrab sends.
    fn answers() -> Answers {
        let mut w = SiiWords::default();
        w.set_status(0x0040 | 0x8000);
        for (a, v) in [
            (0x08, 0x1111),
            (0x09, 0x2222),
            (0x0A, 0x3333),
            (0x0B, 0x4444),
        ] {
            w.insert(a, v);
        }
        // Category 41 at 0x40: 16 words, SM0 to SM3 (start, length, control|status,
        // enable|type << 8).
        let cat = [
            41, 16, 0x1000, 128, 0x0026, 0x0101, 0x1080, 128, 0x0022, 0x0201, 0x1100, 0, 0x0064,
            0x0301, 0x1400, 0, 0x0020, 0x0401, 0xFFFF,
        ];
        for (i, v) in cat.iter().enumerate() {
            w.insert(FIRST_CATEGORY + i as u16, *v);
        }
        let mut a = Answers::new(vec![w]);
        let mut buf = [0u8; 128];
        assert_eq!(
            a.answer(
                &frame(
                    Command::Apwr,
                    0,
                    register::STATION_ADDRESS,
                    &STATION.to_le_bytes()
                ),
                &mut buf
            ),
            Verdict::Wire,
            "the station address write goes to the wire"
        );
        a
    }

    /// ethercrab's SII read command for `word` to `station`.
    fn sii_command(station: u16, word: u8) -> Vec<u8> {
        frame(
            Command::Fpwr,
            station,
            register::SII_CONTROL,
            &[0, 1, word, 0, 0, 0],
        )
    }

    fn frame(cmd: Command, adp: u16, ado: u16, data: &[u8]) -> Vec<u8> {
        let mut buf = [0u8; 256];
        let mut b = FrameBuilder::new(&mut buf, MacAddress([0x10, 0, 0, 0, 0, 1])).unwrap();
        b.push(cmd, 3, physical_address(adp, ado), data).unwrap();
        let n = b.finish();
        buf[..n].to_vec()
    }

    /// The data and working counter of the single datagram of `reply`.
    fn datagram(reply: &[u8]) -> (Vec<u8>, u16) {
        let eth = EthernetFrame::new_checked(reply).unwrap();
        let ecat = EthercatFrame::new_checked(eth.payload()).unwrap();
        let d = ecat.datagrams().next().unwrap().unwrap();
        (d.data().to_vec(), d.wkc())
    }

    #[test]
    fn an_sii_read_of_words_read_in_bulk_is_answered_and_others_go_to_the_wire() {
        let mut a = answers();
        let mut buf = [0u8; 256];
        let cmd = sii_command(STATION, 8);
        assert!(matches!(a.answer(&cmd, &mut buf), Verdict::Answered(_)));
        assert_eq!(datagram(&buf[..cmd.len()]).1, 1);
        // The status: idle, 8-byte reads; the data: the four words.
        let st = frame(Command::Fprd, STATION, register::SII_CONTROL, &[0, 0]);
        let Verdict::Answered(n) = a.answer(&st, &mut buf) else {
            panic!()
        };
        assert_eq!(datagram(&buf[..n]), (vec![0x40, 0], 1));
        assert_eq!(
            buf[6] & MAC_LOCAL_BIT,
            MAC_LOCAL_BIT,
            "as a slave controller forwards it"
        );
        let data = frame(Command::Fprd, STATION, register::SII_DATA, &[0; 8]);
        let Verdict::Answered(n) = a.answer(&data, &mut buf) else {
            panic!()
        };
        assert_eq!(
            datagram(&buf[..n]).0,
            [0x11, 0x11, 0x22, 0x22, 0x33, 0x33, 0x44, 0x44]
        );
        // Word 0x0C was not read: the command and what follows it go to the wire.
        let other = sii_command(STATION, 0x0C);
        assert_eq!(a.answer(&other, &mut buf), Verdict::Wire);
        assert_eq!(a.answer(&data, &mut buf), Verdict::Wire);
        // Another station: nothing known.
        let cmd2 = sii_command(STATION + 1, 8);
        assert_eq!(a.answer(&cmd2, &mut buf), Verdict::Wire);
        assert_eq!(a.answered(), 3);
    }

    /// What ecdrive writes for one RxPDO 0x1601 with one entry and one TxPDO 0x1A00 with two,
    /// each write acknowledged.
    fn acknowledge_mapping(a: &mut Answers) {
        let writes: [(u16, u8, &[u8]); 9] = [
            (0x1C12, 0, &[1]),
            (0x1C12, 1, &[0x01, 0x16]),
            (0x1601, 0, &[1]),
            (0x1601, 1, &[0x10, 0x00, 0x40, 0x60]),
            (0x1C13, 0, &[1]),
            (0x1C13, 1, &[0x00, 0x1A]),
            (0x1A00, 0, &[2]),
            (0x1A00, 1, &[0x10, 0x00, 0x41, 0x60]),
            (0x1A00, 2, &[0x20, 0x00, 0x64, 0x60]),
        ];
        for (index, sub, v) in writes {
            a.acknowledged(STATION, ObjectAddress::new(index, sub), v);
        }
    }

    #[test]
    fn an_upload_of_an_acknowledged_object_is_answered_with_its_value() {
        let mut a = answers();
        acknowledge_mapping(&mut a);
        a.last_counter(STATION, 5);
        let mut buf = [0u8; 256];
        let mut req = [0u8; 128];
        let up = |index, sub| SdoRequest::Upload {
            index,
            sub,
            complete_access: false,
        };
        let n = up(0x1C12, 1).emit_mailbox(3, &mut req).unwrap();
        let _ = n;
        // Both mailboxes look free, the request is taken, SM1 shows full, the response reads.
        let sm1 = frame(Command::Fprd, STATION, register::sm(1) + 5, &[0]);
        assert!(matches!(a.answer(&sm1, &mut buf), Verdict::Answered(_)));
        let write = frame(Command::Fpwr, STATION, 0x1000, &req);
        assert!(matches!(a.answer(&write, &mut buf), Verdict::Answered(_)));
        let Verdict::Answered(n) = a.answer(&sm1, &mut buf) else {
            panic!()
        };
        assert_eq!(datagram(&buf[..n]).0, [SM_MAILBOX_FULL]);
        let read = frame(Command::Fprd, STATION, 0x1080, &[0; 128]);
        let Verdict::Answered(n) = a.answer(&read, &mut buf) else {
            panic!()
        };
        let (mbx, wkc) = datagram(&buf[..n]);
        assert_eq!(wkc, 1);
        match MailboxMessage::parse(&mbx).unwrap().1 {
            MailboxMessage::SdoResponse(SdoResponse::UploadExpedited {
                index, sub, data, ..
            }) => assert_eq!((index, sub, data), (0x1C12, 1, &[0x01, 0x16][..])),
            m => panic!("{m:?}"),
        }
        // An object not acknowledged goes to the wire; its counter 5, the last the device
        // saw, is changed to 6.
        let n = up(0x1A01, 1).emit_mailbox(5, &mut req).unwrap();
        let _ = n;
        let write = frame(Command::Fpwr, STATION, 0x1000, &req);
        let Verdict::Rewritten(n) = a.answer(&write, &mut buf) else {
            panic!("the counter must change")
        };
        let (sent, _) = datagram(&buf[..n]);
        assert_eq!((sent[5] >> 4) & 7, 6);
        assert_eq!(sent[..5], req[..5]);
        assert_eq!(sent[6..], req[6..]);
        // From then on the mailbox is the wire's.
        assert_eq!(a.answer(&sm1, &mut buf), Verdict::Wire);
    }

    #[test]
    fn a_mailbox_is_answered_only_when_every_upload_of_the_image_is_covered() {
        let mut a = answers();
        let mut buf = [0u8; 256];
        let sm1 = frame(Command::Fprd, STATION, register::sm(1) + 5, &[0]);
        // Nothing acknowledged: ethercrab's status reads go to the wire.
        assert_eq!(a.answer(&sm1, &mut buf), Verdict::Wire);
        // The RxPDO side only (the drive's TxPDO left as it was): still the wire's, from the
        // first status read on, so ethercrab clears a waiting emergency itself.
        let rx_only: [(u16, u8, &[u8]); 4] = [
            (0x1C12, 0, &[1]),
            (0x1C12, 1, &[0x01, 0x16]),
            (0x1601, 0, &[1]),
            (0x1601, 1, &[0x10, 0x00, 0x40, 0x60]),
        ];
        for (index, sub, v) in rx_only {
            a.acknowledged(STATION, ObjectAddress::new(index, sub), v);
        }
        assert_eq!(a.answer(&sm1, &mut buf), Verdict::Wire);
        // A mapping entry missing on the TxPDO side: the same.
        a.acknowledged(STATION, ObjectAddress::new(0x1C13, 0), &[1]);
        a.acknowledged(STATION, ObjectAddress::new(0x1C13, 1), &[0x00, 0x1A]);
        a.acknowledged(STATION, ObjectAddress::new(0x1A00, 0), &[2]);
        a.acknowledged(
            STATION,
            ObjectAddress::new(0x1A00, 1),
            &[0x10, 0x00, 0x41, 0x60],
        );
        assert_eq!(a.answer(&sm1, &mut buf), Verdict::Wire);
        a.acknowledged(
            STATION,
            ObjectAddress::new(0x1A00, 2),
            &[0x20, 0x00, 0x64, 0x60],
        );
        assert!(matches!(a.answer(&sm1, &mut buf), Verdict::Answered(_)));
    }

    #[test]
    fn after_an_sii_command_to_the_wire_the_busy_poll_goes_to_the_wire_too() {
        let mut a = answers();
        let mut buf = [0u8; 256];
        let st = frame(Command::Fprd, STATION, register::SII_CONTROL, &[0, 0]);
        assert!(matches!(a.answer(&st, &mut buf), Verdict::Answered(_)));
        // Word 0x0C was not read in bulk: the command goes out, and the device's EEPROM may be
        // busy with it; its status must come from the device.
        let other = sii_command(STATION, 0x0C);
        assert_eq!(a.answer(&other, &mut buf), Verdict::Wire);
        assert_eq!(a.answer(&st, &mut buf), Verdict::Wire);
        // A command answered here again: so is the status.
        let cached = sii_command(STATION, 8);
        assert!(matches!(a.answer(&cached, &mut buf), Verdict::Answered(_)));
        assert!(matches!(a.answer(&st, &mut buf), Verdict::Answered(_)));
    }

    #[test]
    fn a_category_walk_of_any_sizes_ends_without_overflow() {
        // Category sizes that run past the 16-bit word addresses.
        for size in [0xFFFFu16, 0xFFFE, 0xFBFF, 0x8000] {
            let mut w = SiiWords::default();
            w.insert(FIRST_CATEGORY, 30);
            w.insert(FIRST_CATEGORY + 1, size);
            assert_eq!(w.sync_managers(), None, "size {size:#x}");
        }
        // A SyncManager category whose length runs past the end.
        let mut w = SiiWords::default();
        w.insert(0xFFF0, 41);
        w.insert(0xFFF1, 0xFFFF);
        let mut at = FIRST_CATEGORY;
        w.insert(at, 1);
        w.insert(at + 1, 0xFFAE);
        at += 2 + 0xFFAE;
        assert_eq!(at, 0xFFF0);
        assert_eq!(w.sync_managers(), None);
    }
}
