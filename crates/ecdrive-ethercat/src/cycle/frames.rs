//! The cycle's process image, and the cycle's frames as ecdrive builds them itself.
//!
//! [`Image`] holds every device's inputs and outputs, laid out as ethercrab lays out the
//! group's process data (the inputs of every device, then the outputs of every device, in
//! position order): the steps read and write it, whichever path carries it.
//!
//! [`OwnFrames`] carries it without ethercrab's PDU machinery. The cycle's first exchange goes
//! through ethercrab's `tx_rx_dc`; the pump keeps a copy of the frames it sent, and from them
//! [`OwnFrames::learn`] takes the datagrams, byte for byte: the reference clock's system time
//! (FRMW, or FPRD without drift compensation), the LRW of the process image in as many chunks
//! as ethercrab cut it into, and every device's AL status (FPRD 0x0130). From then on the
//! cycle copies the outputs into those frames, sends them all at once, and at the next
//! wake-up copies the inputs, the working counters, the system time and the AL states out of
//! the replies: the same frames on the wire, with no futures, wakers or frame slots in
//! between. Learning checks each device's part of the image against the FMMUs the master
//! configured, and every device's AL-status datagram; when anything does not match, the cycle
//! stays on ethercrab's path.
//!
//! To the last frame the cycle adds one datagram of its own, where it fits: a broadcast read
//! (BRD) of SM1's status byte (0x080D), which every device ORs its own into. Its "mailbox full"
//! bit says whether any device has something waiting in its mailbox (SM1 is the mailbox
//! SyncManager from the device to the master, ETG.2000); the session thread reads the drives'
//! mailboxes for emergencies only when it is set, or when the cycle cannot say
//! ([`MailWatch`]).

use crate::ec::Command;
use crate::ec::frame::{
    DATAGRAM_HEADER_LEN, ECAT_HEADER_LEN, ETHERNET_HEADER_LEN, FrameBuilder, MAC_LOCAL_BIT,
    WKC_LEN, physical_address,
};
use crate::ec::register::{self, FmmuConfig};
use crate::io::{FrameLink, LogicalSeen, MAX_FRAME, Pump, first_datagram_is};
use crate::link::LinkError;
use core::ops::Range;
use std::sync::atomic::{AtomicU8, Ordering};

/// SM1's status byte (0x080D), read by broadcast: every device ORs its own in.
const SM1_STATUS: u16 = register::sm(1) + register::SM_STATUS_OFFSET;
/// The status byte's "mailbox full" bit (bit 3, a SyncManager in mailbox mode).
const MAILBOX_FULL: u8 = 0x08;

/// What the cycle last saw of the devices' mailboxes (SM1's "mailbox full" bit, ORed over the
/// segment by a broadcast read in the cycle's own frames), for the session thread: it reads the
/// drives' mailboxes only when one may hold something. Written by the cycle when what the
/// replies say changes, read by the session; one byte, no lock.
#[derive(Debug, Default)]
pub struct MailWatch(AtomicU8);

impl MailWatch {
    /// The cycle cannot say (ethercrab's frames, no reply, the cycle not running): look.
    const UNKNOWN: u8 = 0;
    /// No device's mailbox holds anything.
    const EMPTY: u8 = 1;
    /// Some device's mailbox holds something.
    const WAITING: u8 = 2;

    /// Record what a reply said (`None`: nothing to go by).
    pub(crate) fn set(&self, full: Option<bool>) {
        let v = match full {
            None => Self::UNKNOWN,
            Some(false) => Self::EMPTY,
            Some(true) => Self::WAITING,
        };
        self.0.store(v, Ordering::Relaxed);
    }

    /// Whether a device's mailbox may hold something: the last reply said so, or the cycle
    /// could not say.
    pub fn may_hold_mail(&self) -> bool {
        self.0.load(Ordering::Relaxed) != Self::EMPTY
    }
}

/// The DC system time register (the reference clock's time, 8 bytes).
const SYSTEM_TIME: u16 = 0x0910;
/// The AL status register (2 bytes).
const AL_STATUS: u16 = 0x0130;

/// Every device's inputs and outputs, in the layout of the group's process data.
#[derive(Debug, Clone, Default)]
pub(crate) struct Image {
    pdi: Vec<u8>,
    /// By position: its inputs and its outputs within `pdi`.
    devices: Vec<(Range<usize>, Range<usize>)>,
    /// Bytes of inputs (they come first).
    inputs_len: usize,
}

impl Image {
    /// The image for devices of these (input, output) sizes, in position order.
    pub(crate) fn new(sizes: &[(usize, usize)]) -> Self {
        let inputs_len: usize = sizes.iter().map(|s| s.0).sum();
        let outputs_len: usize = sizes.iter().map(|s| s.1).sum();
        let (mut i, mut o) = (0, inputs_len);
        let devices = sizes
            .iter()
            .map(|&(n_in, n_out)| {
                let r = (i..i + n_in, o..o + n_out);
                i += n_in;
                o += n_out;
                r
            })
            .collect();
        Self {
            pdi: vec![0; inputs_len + outputs_len],
            devices,
            inputs_len,
        }
    }

    fn ranges(&self, pos: usize) -> (Range<usize>, Range<usize>) {
        self.devices.get(pos).cloned().unwrap_or((0..0, 0..0))
    }

    /// A device's inputs (empty for an unknown position).
    pub(crate) fn inputs(&self, pos: usize) -> &[u8] {
        self.pdi.get(self.ranges(pos).0).unwrap_or(&[])
    }

    /// A device's outputs (empty for an unknown position).
    pub(crate) fn outputs(&self, pos: usize) -> &[u8] {
        self.pdi.get(self.ranges(pos).1).unwrap_or(&[])
    }

    /// A device's inputs, and its outputs to write.
    pub(crate) fn io_mut(&mut self, pos: usize) -> (&[u8], &mut [u8]) {
        let (i, o) = self.ranges(pos);
        let split = self.inputs_len.min(self.pdi.len());
        let (inputs, outputs) = self.pdi.split_at_mut(split);
        let o = o.start.saturating_sub(self.inputs_len)..o.end.saturating_sub(self.inputs_len);
        (
            inputs.get(i).unwrap_or(&[]),
            outputs.get_mut(o).unwrap_or(&mut []),
        )
    }

    /// A device's inputs, set from elsewhere (ethercrab's copy of the image).
    pub(crate) fn set_inputs(&mut self, pos: usize, from: &[u8]) {
        let r = self.ranges(pos).0;
        if let Some(d) = self.pdi.get_mut(r)
            && d.len() == from.len()
        {
            d.copy_from_slice(from);
        }
    }

    /// Whether each device's inputs and outputs sit in the logical image starting at `start`
    /// where the FMMUs the master configured put them (`fmmus`: (station address, block)).
    pub(crate) fn matches_fmmus(
        &self,
        start: u32,
        addresses: &[u16],
        fmmus: &[(u16, FmmuConfig)],
    ) -> bool {
        let at = |r: &Range<usize>| -> Option<Range<u32>> {
            let s = start.checked_add(u32::try_from(r.start).ok()?)?;
            let e = start.checked_add(u32::try_from(r.end).ok()?)?;
            Some(s..e)
        };
        // The union of a device's blocks of one direction must be exactly its range.
        let covered = |station: u16, want: Option<Range<u32>>, read: bool| -> bool {
            let Some(want) = want else { return false };
            let mut blocks: Vec<Range<u32>> = fmmus
                .iter()
                .filter(|(st, c)| *st == station && c.active && c.length > 0)
                .filter(|(_, c)| if read { c.read } else { c.write && !c.read })
                .map(|(_, c)| c.logical_range())
                .collect();
            blocks.sort_by_key(|r| r.start);
            if want.is_empty() {
                return blocks.is_empty();
            }
            let mut next = want.start;
            for b in &blocks {
                if b.start != next {
                    return false;
                }
                next = b.end;
            }
            next == want.end
        };
        self.devices.len() == addresses.len()
            && self
                .devices
                .iter()
                .zip(addresses)
                .all(|((i, o), &st)| covered(st, at(i), true) && covered(st, at(o), false))
    }
}

/// What one datagram of a learnt frame carries.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Part {
    /// The reference clock's system time, at this data offset.
    SystemTime { data: usize },
    /// A chunk of the process image: its data offset, its range in the image, its working
    /// counter's offset.
    Image {
        data: usize,
        pdi: Range<usize>,
        wkc: usize,
        address: u32,
    },
    /// A device's AL status: the data offset, its position.
    AlStatus { data: usize, position: usize },
    /// SM1's status ORed over every device (ecdrive's own, not learnt): the data offset and
    /// the working counter's.
    MailFull { data: usize, wkc: usize },
}

/// One frame of the cycle, as learnt.
#[derive(Debug, Clone)]
struct Frame {
    bytes: Vec<u8>,
    parts: Vec<Part>,
    /// Offset of the first datagram's index (the frame's sequence number goes there).
    index_at: usize,
    /// The first datagram's command byte and address, to tell the reply from other frames.
    first: [u8; 5],
    /// Its reply has come in this cycle.
    answered: bool,
}

impl Frame {
    /// Append the broadcast read of SM1's status after the last datagram, when the frame has
    /// room for it (else the cycle does without, and the session polls as without own frames).
    fn add_mail_check(&mut self) {
        let Some(end) = self.parts.iter().map(Part::end).max() else {
            return;
        };
        let mut buf = vec![0u8; MAX_FRAME];
        let (Some(dst), Some(src)) = (buf.get_mut(..end), self.bytes.get(..end)) else {
            return;
        };
        dst.copy_from_slice(src);
        let Ok(mut b) = FrameBuilder::resume(&mut buf, end) else {
            return;
        };
        let Ok(data) = b.push(Command::Brd, 0, physical_address(0, SM1_STATUS), &[0]) else {
            return;
        };
        // ethercrab pads a short frame: the frame keeps its length, the datagram goes before
        // the padding.
        let len = b.finish().max(self.bytes.len());
        buf.truncate(len);
        self.bytes = buf;
        self.parts.push(Part::MailFull {
            data,
            wkc: data + 1,
        });
    }
}

impl Part {
    /// Where the datagram this part reads ends (after its working counter).
    fn end(&self) -> usize {
        match self {
            Part::SystemTime { data } => data + 8 + WKC_LEN,
            Part::Image { wkc, .. } | Part::MailFull { wkc, .. } => wkc + WKC_LEN,
            Part::AlStatus { data, .. } => data + 2 + WKC_LEN,
        }
    }
}

/// What the replies of one cycle's frames said.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct OwnReply {
    /// The working counter summed over the image's datagrams.
    pub wkc: u16,
    /// The reference clock's system time.
    pub dc_time: u64,
    /// Whether any device's mailbox holds something (`None`: the frames do not ask, or no
    /// device answered).
    pub mail: Option<bool>,
}

/// How reading the replies went.
#[derive(Debug)]
pub(crate) enum OwnOutcome {
    /// Every frame came back.
    Answered(OwnReply),
    /// Not every frame came back before the deadline.
    Late,
}

/// The cycle's frames, built by ecdrive from what ethercrab sent (see the
/// [module documentation](self)).
#[derive(Debug)]
pub(crate) struct OwnFrames {
    frames: Vec<Frame>,
    /// Each device's AL state (low nibble of 0x0130) from the last replies, by position.
    states: Vec<u8>,
    reply: Box<[u8; MAX_FRAME + 4]>,
    seq: u8,
    /// Frames sent whose replies are outstanding.
    in_flight: bool,
    drift_compensation: bool,
}

/// Why the frames ethercrab sent could not be taken over (the cycle then stays on ethercrab's
/// path).
pub(crate) type NotLearnt = &'static str;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*b.get(at)?, *b.get(at + 1)?]))
}

impl OwnFrames {
    /// Take the frames of one cycle as ethercrab sent them (`sent`, in order; frames that do
    /// not begin as the cycle's do, the session's, are passed over), for an image laid out as
    /// `image` that the FMMUs put at `fmmus`, and devices with these station addresses (by
    /// position).
    pub(crate) fn learn<'f>(
        sent: impl IntoIterator<Item = &'f [u8]>,
        image: &Image,
        addresses: &[u16],
        fmmus: &[(u16, FmmuConfig)],
        drift_compensation: bool,
    ) -> Result<Self, NotLearnt> {
        let mut frames = Vec::new();
        let mut image_start: Option<u32> = None;
        let mut covered = 0usize;
        let mut seen = vec![false; addresses.len()];
        let mut time = false;
        for bytes in sent {
            if !Self::is_cyclic(bytes) {
                // The session's mailbox traffic, sent meanwhile.
                continue;
            }
            let mut parts = Vec::new();
            let mut at = ETHERNET_HEADER_LEN + ECAT_HEADER_LEN;
            let mut first = None;
            loop {
                let h = bytes
                    .get(at..at + DATAGRAM_HEADER_LEN)
                    .ok_or("short frame")?;
                let (cmd, adp, ado) = (h[0], u16_at(h, 2).unwrap_or(0), u16_at(h, 4).unwrap_or(0));
                let lf = u16_at(h, 6).unwrap_or(0);
                let len = usize::from(lf & 0x07FF);
                let data = at + DATAGRAM_HEADER_LEN;
                let wkc = data + len;
                if bytes.len() < wkc + WKC_LEN {
                    return Err("short frame");
                }
                first.get_or_insert([cmd, h[2], h[3], h[4], h[5]]);
                let logical = u32::from_le_bytes([h[2], h[3], h[4], h[5]]);
                let part = match Command::from_u8(cmd) {
                    Some(Command::Frmw | Command::Fprd) if ado == SYSTEM_TIME && len == 8 => {
                        if time || !frames.is_empty() || !parts.is_empty() {
                            return Err("the system time is not the first datagram");
                        }
                        time = true;
                        Part::SystemTime { data }
                    }
                    Some(Command::Lrw) => {
                        let start = *image_start.get_or_insert(logical);
                        if logical != start.wrapping_add(covered as u32) {
                            return Err("the image's chunks are not contiguous");
                        }
                        let pdi = covered..covered + len;
                        covered += len;
                        Part::Image {
                            data,
                            pdi,
                            wkc,
                            address: logical,
                        }
                    }
                    Some(Command::Fprd) if ado == AL_STATUS && len == 2 => {
                        let position = addresses
                            .iter()
                            .position(|&a| a == adp)
                            .ok_or("an AL status of an unknown device")?;
                        if std::mem::replace(&mut seen[position], true) {
                            return Err("a device's AL status twice");
                        }
                        Part::AlStatus { data, position }
                    }
                    _ => return Err("a datagram that is not the cycle's"),
                };
                parts.push(part);
                if lf & 0x8000 == 0 {
                    break;
                }
                at = wkc + WKC_LEN;
            }
            frames.push(Frame {
                bytes: bytes.to_vec(),
                parts,
                index_at: ETHERNET_HEADER_LEN + ECAT_HEADER_LEN + 1,
                first: first.ok_or("an empty frame")?,
                answered: false,
            });
        }
        if !time {
            return Err("no system time");
        }
        if covered != image.pdi.len() {
            return Err("the image's chunks do not cover the image");
        }
        if !seen.iter().all(|&s| s) {
            return Err("not every device's AL status");
        }
        if let Some(start) = image_start
            && !image.matches_fmmus(start, addresses, fmmus)
        {
            return Err("the image does not sit where the FMMUs put it");
        }
        // The system time goes out as the drift compensation has it (see `send`).
        let cmd = if drift_compensation {
            Command::Frmw
        } else {
            Command::Fprd
        } as u8;
        for f in frames.iter_mut() {
            if matches!(f.parts.first(), Some(Part::SystemTime { .. })) {
                f.first[0] = cmd;
            }
        }
        if let Some(last) = frames.last_mut() {
            last.add_mail_check();
        }
        Ok(Self {
            frames,
            states: vec![0; addresses.len()],
            reply: Box::new([0; MAX_FRAME + 4]),
            seq: 0,
            in_flight: false,
            drift_compensation,
        })
    }

    /// Whether a frame begins as the cycle's frames do: the system time, a chunk of the
    /// image, or an AL status.
    fn is_cyclic(frame: &[u8]) -> bool {
        let at = ETHERNET_HEADER_LEN + ECAT_HEADER_LEN;
        let Some(h) = frame.get(at..at + DATAGRAM_HEADER_LEN) else {
            return false;
        };
        let (ado, len) = (
            u16_at(h, 4).unwrap_or(0),
            u16_at(h, 6).unwrap_or(0) & 0x07FF,
        );
        match Command::from_u8(h[0]) {
            Some(Command::Frmw | Command::Fprd) if ado == SYSTEM_TIME && len == 8 => true,
            Some(Command::Lrw) => true,
            Some(Command::Fprd) => ado == AL_STATUS && len == 2,
            _ => false,
        }
    }

    /// Each frame's length and first datagram (command and address), for
    /// [`Pump::own_frames`].
    pub(crate) fn shapes(&self) -> Vec<(usize, [u8; 5])> {
        self.frames
            .iter()
            .map(|f| (f.bytes.len(), f.first))
            .collect()
    }

    /// The logical datagrams of the frames, as `(address, length)`.
    pub(crate) fn logical(&self) -> impl Iterator<Item = (u32, u16)> + '_ {
        self.frames
            .iter()
            .flat_map(|f| f.parts.iter())
            .filter_map(|p| match p {
                Part::Image { address, pdi, .. } => {
                    Some((*address, u16::try_from(pdi.len()).unwrap_or(u16::MAX)))
                }
                _ => None,
            })
    }

    /// Whether frames are out whose replies have not been read.
    pub(crate) fn in_flight(&self) -> bool {
        self.in_flight
    }

    /// Forget the frames in flight (their replies, should they come, are stale).
    pub(crate) fn give_up(&mut self) {
        self.in_flight = false;
    }

    /// Each device's AL state (its AL status's low nibble) from the last replies, by position.
    pub(crate) fn states(&self) -> &[u8] {
        &self.states
    }

    /// Send the cycle's frames with the image's outputs, then whatever ethercrab has queued.
    /// No allocation.
    pub(crate) fn send<L: FrameLink>(
        &mut self,
        pump: &mut Pump<'_, L>,
        image: &Image,
    ) -> Result<(), LinkError> {
        self.seq = self.seq.wrapping_add(1);
        let cmd = if self.drift_compensation {
            Command::Frmw
        } else {
            Command::Fprd
        } as u8;
        for f in &mut self.frames {
            for p in &f.parts {
                match p {
                    Part::Image { data, pdi, .. } => {
                        if let (Some(d), Some(s)) = (
                            f.bytes.get_mut(*data..*data + pdi.len()),
                            image.pdi.get(pdi.clone()),
                        ) {
                            d.copy_from_slice(s);
                        }
                    }
                    // Always the frame's first datagram: the reply is told by it too.
                    Part::SystemTime { data } => {
                        if let Some(c) = f.bytes.get_mut(data - DATAGRAM_HEADER_LEN) {
                            *c = cmd;
                            f.first[0] = cmd;
                        }
                    }
                    Part::AlStatus { .. } | Part::MailFull { .. } => {}
                }
            }
            if let Some(i) = f.bytes.get_mut(f.index_at) {
                *i = self.seq;
            }
            f.answered = false;
        }
        self.in_flight = true;
        for f in &self.frames {
            pump.send_own(&f.bytes)?;
        }
        // And whatever ethercrab has queued meanwhile (the session's mailbox traffic).
        pump.send_queued()?;
        Ok(())
    }

    /// Read the replies of the frames in flight until `deadline_ns`: the inputs into the
    /// image, the AL states; frames that are not the cycle's go to ethercrab (and what
    /// ethercrab has queued goes out first). No allocation.
    pub(crate) fn receive<L: FrameLink>(
        &mut self,
        pump: &mut Pump<'_, L>,
        image: &mut Image,
        deadline_ns: u64,
    ) -> Result<OwnOutcome, LinkError> {
        let mut out = OwnReply::default();
        let seq = self.seq;
        pump.send_queued()?;
        while self.frames.iter().any(|f| !f.answered) {
            let frames = &self.frames;
            // A reply to one of the cycle's frames: its first datagram and its length; this
            // cycle's by its sequence number, else a late reply to an earlier cycle's.
            let ours = |r: &[u8]| {
                if r.get(6).is_none_or(|b| b & MAC_LOCAL_BIT == 0) {
                    return None;
                }
                let f = frames
                    .iter()
                    .find(|f| r.len() == f.bytes.len() && first_datagram_is(r, &f.first))?;
                Some(!f.answered && r.get(f.index_at) == Some(&seq))
            };
            let Some(len) = pump.receive_own(&mut self.reply[..], deadline_ns, ours)? else {
                self.in_flight = false;
                return Ok(OwnOutcome::Late);
            };
            let r = &self.reply[..len];
            let Some(f) = self
                .frames
                .iter_mut()
                .find(|f| !f.answered && first_datagram_is(r, &f.first))
            else {
                continue;
            };
            f.answered = true;
            for p in &f.parts {
                match p {
                    Part::SystemTime { data } => {
                        if let Some(b) = r.get(*data..*data + 8) {
                            let mut t = [0u8; 8];
                            t.copy_from_slice(b);
                            out.dc_time = u64::from_le_bytes(t);
                        }
                    }
                    Part::Image {
                        data,
                        pdi,
                        wkc,
                        address,
                    } => {
                        let got = u16_at(r, *wkc).unwrap_or(0);
                        out.wkc = out.wkc.wrapping_add(got);
                        pump.note_logical(LogicalSeen {
                            address: *address,
                            len: u16::try_from(pdi.len()).unwrap_or(u16::MAX),
                            wkc: got,
                        });
                        // The inputs only: the outputs are the master's.
                        let n = pdi.end.min(image.inputs_len).saturating_sub(pdi.start);
                        if let (Some(d), Some(s)) = (
                            image.pdi.get_mut(pdi.start..pdi.start + n),
                            r.get(*data..*data + n),
                        ) {
                            d.copy_from_slice(s);
                        }
                    }
                    Part::AlStatus { data, position } => {
                        if let (Some(s), Some(&b)) = (self.states.get_mut(*position), r.get(*data))
                        {
                            *s = b & 0x0F;
                        }
                    }
                    Part::MailFull { data, wkc } => {
                        out.mail = match (r.get(*data), u16_at(r, *wkc)) {
                            (Some(&b), Some(w)) if w > 0 => Some(b & MAILBOX_FULL != 0),
                            _ => None,
                        };
                    }
                }
            }
        }
        self.in_flight = false;
        Ok(OwnOutcome::Answered(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ec::frame::MacAddress;

    /// A frame as ethercrab's `tx_rx_dc` builds it for two devices (station addresses 0x1001,
    /// 0x1002) whose image is 2 + 1 input bytes and 3 output bytes at logical 0x10000: the
    /// reference clock's time, the LRW, the AL status of each.
    fn ethercrab_frame(extra: Option<(Command, u32)>) -> Vec<u8> {
        let mut buf = [0u8; 256];
        let mut b = FrameBuilder::new(&mut buf, MacAddress([0x10; 6])).unwrap();
        b.push(
            Command::Frmw,
            1,
            physical_address(0x1001, SYSTEM_TIME),
            &[0; 8],
        )
        .unwrap();
        b.push(Command::Lrw, 2, 0x10000, &[0; 6]).unwrap();
        for (i, st) in [0x1001u16, 0x1002].into_iter().enumerate() {
            b.push(
                Command::Fprd,
                3 + i as u8,
                physical_address(st, AL_STATUS),
                &[0; 2],
            )
            .unwrap();
        }
        if let Some((c, a)) = extra {
            b.push(c, 9, a, &[0; 2]).unwrap();
        }
        let n = b.finish();
        buf[..n].to_vec()
    }

    fn fmmu(start: u32, length: u16, read: bool) -> FmmuConfig {
        FmmuConfig {
            logical_start: start,
            length,
            logical_start_bit: 0,
            logical_stop_bit: 7,
            physical_start: 0x1100,
            physical_start_bit: 0,
            read,
            write: !read,
            active: true,
        }
    }

    /// Device 0: inputs 0x10000..+2, outputs 0x10003..+3; device 1: inputs 0x10002..+1.
    fn fmmus() -> Vec<(u16, FmmuConfig)> {
        vec![
            (0x1001, fmmu(0x10000, 2, true)),
            (0x1001, fmmu(0x10003, 3, false)),
            (0x1002, fmmu(0x10002, 1, true)),
        ]
    }

    #[test]
    fn ethercrabs_frame_is_learnt_datagram_by_datagram() {
        let img = Image::new(&[(2, 3), (1, 0)]);
        let f = ethercrab_frame(None);
        let own = OwnFrames::learn([&f[..]], &img, &[0x1001, 0x1002], &fmmus(), true).unwrap();
        assert_eq!(own.frames.len(), 1);
        let data = |k: usize| ETHERNET_HEADER_LEN + ECAT_HEADER_LEN + k + DATAGRAM_HEADER_LEN;
        let lrw = data(12 + 8);
        assert_eq!(
            own.frames[0].parts,
            vec![
                Part::SystemTime { data: data(0) },
                Part::Image {
                    data: lrw,
                    pdi: 0..6,
                    wkc: lrw + 6,
                    address: 0x10000,
                },
                Part::AlStatus {
                    data: lrw + 6 + 2 + 10,
                    position: 0,
                },
                Part::AlStatus {
                    data: lrw + 6 + 2 + 10 + 14,
                    position: 1,
                },
                // ecdrive's own: SM1's status by broadcast, after the last learnt datagram.
                Part::MailFull {
                    data: lrw + 6 + 2 + 10 + 14 + 14,
                    wkc: lrw + 6 + 2 + 10 + 14 + 14 + 1,
                },
            ]
        );
    }

    /// The datagrams of `frame`, read by the wire crate's own parser: command, ADP, ADO, data
    /// length, whether more follow.
    fn datagrams(frame: &[u8]) -> Vec<(Option<Command>, u16, u16, usize, bool)> {
        let e = crate::ec::frame::EthercatFrame::new_checked(&frame[ETHERNET_HEADER_LEN..])
            .expect("an EtherCAT frame");
        let summary = e.check().expect("a valid datagram chain");
        assert_eq!(
            summary.used_len,
            e.length(),
            "header length = the datagrams'"
        );
        e.datagrams()
            .map(|d| {
                let d = d.expect("datagram");
                (d.command(), d.adp(), d.ado(), d.data_len(), d.more())
            })
            .collect()
    }

    #[test]
    fn the_mailbox_check_goes_after_the_last_datagram_and_before_any_padding() {
        let img = Image::new(&[(2, 3), (1, 0)]);
        let stations = [0x1001, 0x1002];
        let plain = ethercrab_frame(None);
        // The same frame padded to Ethernet's minimum and beyond, as a sender may pad it.
        let mut padded = plain.clone();
        padded.resize(plain.len() + 20, 0);
        for sent in [plain.clone(), padded] {
            let own = OwnFrames::learn([&sent[..]], &img, &stations, &fmmus(), true).unwrap();
            let f = &own.frames[0].bytes;
            assert_eq!(f.len(), (plain.len() + 13).max(sent.len()));
            let d = datagrams(f);
            assert_eq!(d.len(), 5);
            assert_eq!(&d[..3].iter().map(|x| x.4).collect::<Vec<_>>(), &[true; 3]);
            assert_eq!(d[3], (Some(Command::Fprd), 0x1002, AL_STATUS, 2, true));
            assert_eq!(d[4], (Some(Command::Brd), 0, 0x080D, 1, false));
            // The reply is told by its length: the shape the pump is given is the new one.
            assert_eq!(own.shapes()[0].0, f.len());
        }
        // Padding to the largest frame is no content: the check still goes in.
        let mut max = plain.clone();
        max.resize(MAX_FRAME, 0);
        let own = OwnFrames::learn([&max[..]], &img, &stations, &fmmus(), true).unwrap();
        assert_eq!(datagrams(&own.frames[0].bytes).len(), 5);
        // A frame whose datagrams leave no room goes without it, unchanged.
        let n = MAX_FRAME - ETHERNET_HEADER_LEN - ECAT_HEADER_LEN - DATAGRAM_HEADER_LEN - WKC_LEN;
        let mut buf = vec![0u8; MAX_FRAME];
        let mut b = FrameBuilder::new(&mut buf, MacAddress([0x10; 6])).unwrap();
        b.push(Command::Lrw, 1, 0x10000, &vec![0; n]).unwrap();
        let len = b.finish();
        let mut frame = Frame {
            bytes: buf[..len].to_vec(),
            parts: vec![Part::Image {
                data: len - WKC_LEN - n,
                pdi: 0..n,
                wkc: len - WKC_LEN,
                address: 0x10000,
            }],
            index_at: ETHERNET_HEADER_LEN + ECAT_HEADER_LEN + 1,
            first: [0; 5],
            answered: false,
        };
        let before = frame.bytes.clone();
        frame.add_mail_check();
        assert_eq!(frame.bytes, before);
        assert_eq!(frame.parts.len(), 1);
    }

    #[test]
    fn frames_that_are_not_the_cycles_are_not_learnt() {
        let img = Image::new(&[(2, 3), (1, 0)]);
        let stations = [0x1001, 0x1002];
        let learn = |f: &[u8], fmmus: &[(u16, FmmuConfig)]| {
            OwnFrames::learn([f], &img, &stations, fmmus, true).map(|_| ())
        };
        // A mailbox write among them.
        let f = ethercrab_frame(Some((Command::Fpwr, physical_address(0x1001, 0x1000))));
        assert_eq!(
            learn(&f, &fmmus()),
            Err("a datagram that is not the cycle's")
        );
        // A device's AL status twice (a state read of the session's in the same capture).
        let f = ethercrab_frame(Some((Command::Fprd, physical_address(0x1002, AL_STATUS))));
        assert_eq!(learn(&f, &fmmus()), Err("a device's AL status twice"));
        // The outputs somewhere else than the image says.
        let mut moved = fmmus();
        moved[1].1.logical_start = 0x10004;
        let f = ethercrab_frame(None);
        assert_eq!(
            learn(&f, &moved),
            Err("the image does not sit where the FMMUs put it")
        );
        // An image of another size.
        let img = Image::new(&[(2, 4), (1, 0)]);
        assert_eq!(
            OwnFrames::learn([&f[..]], &img, &stations, &fmmus(), true).map(|_| ()),
            Err("the image's chunks do not cover the image")
        );
    }

    #[test]
    fn the_image_puts_every_input_before_every_output() {
        let mut img = Image::new(&[(2, 3), (0, 1), (4, 0)]);
        assert_eq!(img.pdi.len(), 10);
        assert_eq!(img.ranges(0), (0..2, 6..9));
        assert_eq!(img.ranges(1), (2..2, 9..10));
        assert_eq!(img.ranges(2), (2..6, 10..10));
        img.set_inputs(2, &[1, 2, 3, 4]);
        let (i, o) = img.io_mut(0);
        assert_eq!(i, &[0, 0]);
        o.copy_from_slice(&[7, 8, 9]);
        assert_eq!(img.inputs(2), &[1, 2, 3, 4]);
        assert_eq!(img.outputs(0), &[7, 8, 9]);
        assert_eq!(img.pdi, vec![0, 0, 1, 2, 3, 4, 7, 8, 9, 0]);
        assert_eq!(img.inputs(9), &[] as &[u8]);
    }
}
