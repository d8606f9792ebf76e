//! A small synchronous master for the drive tests: everything through frames on the wire of an
//! in-process segment with a manual clock (no ethercrab, no host time), so that the tests see
//! exactly what a master sees: the EEPROM through the SII registers, CoE through the mailbox
//! SyncManagers, process data through FMMUs, DC SYNC0 through the DC registers.
#![allow(dead_code)]

use ecdrive_core::drives::DriveProfile;
use ecdrive_core::ec::Command;
use ecdrive_core::ec::mailbox::{
    Emergency, EntryDescription, MailboxMessage, SdoInfoOpcode, SdoInfoRequest, SdoRequest,
    SdoResponse,
};
use ecdrive_sim::drives::{EmulatedDrive, emulated};
use ecdrive_sim::probe::Probe;
use ecdrive_sim::{Device, EscConfig, ManualClock, Segment};
use std::sync::Arc;

/// The time the clock starts at.
pub const T0: u64 = 1_000_000_000_000;
/// Station address of position 0.
pub const BASE: u16 = 0x1000;

/// Where one device's process data sits in the logical image.
#[derive(Debug, Clone, Copy, Default)]
pub struct PdSlot {
    /// Output bytes.
    pub out_len: usize,
    /// Input bytes.
    pub in_len: usize,
    /// Offset of the outputs in the image.
    pub out_off: usize,
    /// Offset of the inputs in the image.
    pub in_off: usize,
}

/// The master.
pub struct Wire {
    pub p: Probe,
    pub clock: ManualClock,
    counter: u8,
    /// Mailbox SyncManagers per position: (out start, out len, in start, in len).
    mbx: Vec<(u16, u16, u16, u16)>,
    /// Emergencies received, with the position they came from.
    pub emergencies: Vec<(usize, Emergency)>,
    pub pd: Vec<PdSlot>,
    /// The process image: outputs of every device, then inputs of every device.
    pub image: Vec<u8>,
    pub cycle_ns: u32,
}

fn u16le(d: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([d[at], d[at + 1]])
}

impl Wire {
    /// A segment of `devices` (SM watchdog off), addresses assigned.
    pub fn new(devices: Vec<Box<dyn Device>>) -> Self {
        Self::with_config(
            devices,
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
    }

    /// With an ESC configuration.
    pub fn with_config(devices: Vec<Box<dyn Device>>, cfg: EscConfig) -> Self {
        let clock = ManualClock::new(T0);
        let mut seg = Segment::new(Arc::new(clock.clone()));
        let n = devices.len();
        for d in devices {
            seg.push(d, cfg.clone()).unwrap();
        }
        let mut p = Probe::new(seg);
        p.assign_addresses(BASE).unwrap();
        Self {
            p,
            clock,
            counter: 0,
            mbx: vec![(0, 0, 0, 0); n],
            emergencies: Vec::new(),
            pd: vec![PdSlot::default(); n],
            image: Vec::new(),
            cycle_ns: 1_000_000,
        }
    }

    /// One emulated drive per profile, serial = position + 1.
    pub fn drives(profiles: &[&DriveProfile]) -> Self {
        Self::new(
            profiles
                .iter()
                .enumerate()
                .map(|(i, p)| emulated(p.key, i as u32 + 1).unwrap())
                .collect(),
        )
    }

    pub fn station(pos: usize) -> u16 {
        BASE + pos as u16
    }

    /// The emulated drive at `pos`.
    pub fn drive(&mut self, pos: usize) -> &mut EmulatedDrive {
        self.p.segment.device_mut::<EmulatedDrive>(pos).unwrap()
    }

    // ------------------------------------------------------------------------------- EEPROM

    /// Read 8 bytes of the EEPROM at word address `word` through the SII registers.
    pub fn sii_read(&mut self, pos: usize, word: u32) -> Vec<u8> {
        let st = Self::station(pos);
        let mut req = vec![0x00, 0x01];
        req.extend_from_slice(&word.to_le_bytes());
        assert_eq!(self.p.fpwr(st, 0x0502, &req).unwrap().wkc, 1);
        let status = self.p.read_u16(st, 0x0502).unwrap().0;
        assert_eq!(status & 0x8000, 0, "EEPROM busy");
        self.p.fprd(st, 0x0508, 8).unwrap().data
    }

    /// The whole EEPROM (its size from word 0x3E).
    pub fn eeprom(&mut self, pos: usize) -> Vec<u8> {
        let w = self.sii_read(pos, 0x3E);
        let kbit = u32::from(u16le(&w, 0)) + 1;
        let bytes = kbit * 1024 / 8;
        let mut out = Vec::with_capacity(bytes as usize);
        let mut word = 0;
        while (out.len() as u32) < bytes {
            out.extend(self.sii_read(pos, word));
            word += 4;
        }
        out.truncate(bytes as usize);
        out
    }

    // ------------------------------------------------------------------------------- AL state

    /// Request an AL state; returns (AL status, AL status code).
    pub fn request(&mut self, pos: usize, state: u16) -> (u16, u16) {
        self.p.request_state(Self::station(pos), state).unwrap()
    }

    /// Request an AL state acknowledging an error indication (AL control bit 4).
    pub fn request_ack(&mut self, pos: usize, state: u16) -> (u16, u16) {
        self.p
            .request_state(Self::station(pos), state | 0x0010)
            .unwrap()
    }

    /// Configure the mailbox from the SII and go to PRE-OP.
    pub fn preop(&mut self, pos: usize) {
        let st = Self::station(pos);
        let w = self.sii_read(pos, 0x18);
        let (rx_off, rx_len, tx_off, tx_len) =
            (u16le(&w, 0), u16le(&w, 2), u16le(&w, 4), u16le(&w, 6));
        let mut sm = [0u8; 16];
        sm[0..2].copy_from_slice(&rx_off.to_le_bytes());
        sm[2..4].copy_from_slice(&rx_len.to_le_bytes());
        sm[4] = 0x26;
        sm[6] = 1;
        sm[8..10].copy_from_slice(&tx_off.to_le_bytes());
        sm[10..12].copy_from_slice(&tx_len.to_le_bytes());
        sm[12] = 0x22;
        sm[14] = 1;
        assert_eq!(self.p.fpwr(st, 0x0800, &sm).unwrap().wkc, 1);
        self.mbx[pos] = (rx_off, rx_len, tx_off, tx_len);
        assert_eq!(self.request(pos, 0x0002), (0x0002, 0), "PRE-OP");
    }

    // ------------------------------------------------------------------------------- mailbox

    fn next_counter(&mut self) -> u8 {
        self.counter = if self.counter >= 7 {
            1
        } else {
            self.counter + 1
        };
        self.counter
    }

    /// Read SM1 once; `None` if it is empty.
    fn read_mailbox(&mut self, pos: usize) -> Option<Vec<u8>> {
        let (_, _, in_start, in_len) = self.mbx[pos];
        let r = self
            .p
            .fprd(Self::station(pos), in_start, usize::from(in_len))
            .unwrap();
        (r.wkc == 1).then_some(r.data)
    }

    /// Collect the emergencies waiting in SM1.
    pub fn drain(&mut self, pos: usize) {
        for _ in 0..64 {
            let Some(m) = self.read_mailbox(pos) else {
                return;
            };
            if let Ok((_, MailboxMessage::Emergency(e))) = MailboxMessage::parse(&m) {
                self.emergencies.push((pos, e));
            }
        }
    }

    /// Write a request into SM0 and return the next reply that is not an emergency.
    fn exchange(&mut self, pos: usize, build: impl FnOnce(u8, &mut [u8]) -> usize) -> Vec<u8> {
        let (out_start, out_len, _, _) = self.mbx[pos];
        let mut msg = vec![0u8; usize::from(out_len)];
        let c = self.next_counter();
        build(c, &mut msg);
        let r = self.p.fpwr(Self::station(pos), out_start, &msg).unwrap();
        assert_eq!(r.wkc, 1, "SM0 accepted the request");
        for _ in 0..64 {
            if let Some(m) = self.read_mailbox(pos) {
                match MailboxMessage::parse(&m) {
                    Ok((_, MailboxMessage::Emergency(e))) => self.emergencies.push((pos, e)),
                    Ok(_) => return m,
                    Err(e) => panic!("bad mailbox reply: {e}"),
                }
            }
        }
        panic!("no mailbox reply");
    }

    fn sdo(&mut self, pos: usize, req: &SdoRequest<'_>) -> Vec<u8> {
        self.exchange(pos, |c, buf| req.emit_mailbox(c, buf).unwrap())
    }

    /// SDO upload of one entry (expedited, normal or segmented). `Err(abort code)`.
    pub fn upload(&mut self, pos: usize, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
        let m = self.sdo(
            pos,
            &SdoRequest::Upload {
                index,
                sub,
                complete_access: false,
            },
        );
        let mut out = match MailboxMessage::parse(&m).unwrap().1 {
            MailboxMessage::SdoResponse(SdoResponse::UploadExpedited { data, .. }) => {
                return Ok(data.to_vec());
            }
            MailboxMessage::SdoResponse(SdoResponse::UploadNormal {
                complete_size,
                data,
                ..
            }) => {
                if data.len() >= complete_size as usize {
                    return Ok(data[..complete_size as usize].to_vec());
                }
                data.to_vec()
            }
            MailboxMessage::SdoResponse(SdoResponse::Abort { code, .. })
            | MailboxMessage::SdoRequest(SdoRequest::Abort { code, .. }) => return Err(code),
            other => panic!("0x{index:04X}:{sub:02X}: unexpected {other:?}"),
        };
        let mut toggle = false;
        loop {
            let m = self.sdo(pos, &SdoRequest::UploadSegment { toggle });
            match MailboxMessage::parse(&m).unwrap().1 {
                MailboxMessage::SdoResponse(SdoResponse::UploadSegment { last, data, .. }) => {
                    out.extend_from_slice(data);
                    if last {
                        return Ok(out);
                    }
                }
                MailboxMessage::SdoResponse(SdoResponse::Abort { code, .. })
                | MailboxMessage::SdoRequest(SdoRequest::Abort { code, .. }) => return Err(code),
                other => panic!("unexpected {other:?}"),
            }
            toggle = !toggle;
        }
    }

    /// SDO download (expedited up to 4 bytes, else normal/segmented). `Err(abort code)`.
    pub fn download(&mut self, pos: usize, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let mbx = usize::from(self.mbx[pos].1);
        let (req, mut sent) = SdoRequest::initiate_download(index, sub, false, data, mbx);
        let m = self.sdo(pos, &req);
        match MailboxMessage::parse(&m).unwrap().1 {
            MailboxMessage::SdoResponse(SdoResponse::Download { .. }) => {}
            MailboxMessage::SdoResponse(SdoResponse::Abort { code, .. })
            | MailboxMessage::SdoRequest(SdoRequest::Abort { code, .. }) => return Err(code),
            other => panic!("unexpected {other:?}"),
        }
        let mut toggle = false;
        while sent < data.len() {
            let (req, n) = SdoRequest::download_segment(&data[sent..], toggle, mbx);
            let m = self.sdo(pos, &req);
            match MailboxMessage::parse(&m).unwrap().1 {
                MailboxMessage::SdoResponse(SdoResponse::DownloadSegment { .. }) => {}
                MailboxMessage::SdoResponse(SdoResponse::Abort { code, .. })
                | MailboxMessage::SdoRequest(SdoRequest::Abort { code, .. }) => return Err(code),
                other => panic!("unexpected {other:?}"),
            }
            sent += n;
            toggle = !toggle;
        }
        Ok(())
    }

    pub fn write_u8(&mut self, pos: usize, index: u16, sub: u8, v: u8) -> Result<(), u32> {
        self.download(pos, index, sub, &[v])
    }

    pub fn write_u16(&mut self, pos: usize, index: u16, sub: u8, v: u16) -> Result<(), u32> {
        self.download(pos, index, sub, &v.to_le_bytes())
    }

    pub fn write_u32(&mut self, pos: usize, index: u16, sub: u8, v: u32) -> Result<(), u32> {
        self.download(pos, index, sub, &v.to_le_bytes())
    }

    pub fn read_u32(&mut self, pos: usize, index: u16, sub: u8) -> u32 {
        let b = self.upload(pos, index, sub).unwrap();
        let mut raw = [0u8; 4];
        raw[..b.len().min(4)].copy_from_slice(&b[..b.len().min(4)]);
        u32::from_le_bytes(raw)
    }

    /// SDO information: the entry description (data type, bit length, access), or the error.
    pub fn entry_description(
        &mut self,
        pos: usize,
        index: u16,
        sub: u8,
    ) -> Result<(u16, u16, u16), u32> {
        let req = SdoInfoRequest::EntryDescription {
            index,
            sub,
            value_info: 0,
        };
        let m = self.exchange(pos, |c, buf| req.emit_mailbox(c, buf).unwrap());
        match MailboxMessage::parse(&m).unwrap().1 {
            MailboxMessage::SdoInfo(f) if f.opcode == SdoInfoOpcode::Error => {
                Err(f.error_code().unwrap())
            }
            MailboxMessage::SdoInfo(f) => {
                assert!(!f.incomplete, "entry description in one fragment");
                let e = EntryDescription::parse(f.data).unwrap();
                assert_eq!((e.index, e.sub), (index, sub));
                Ok((e.data_type, e.bit_len, e.access))
            }
            other => panic!("unexpected {other:?}"),
        }
    }

    /// The OD list of `list_type` over SDO information (all fragments), or `None` if the device
    /// answers with a mailbox error (no SDO information service).
    pub fn od_list(&mut self, pos: usize, list_type: u16) -> Option<Vec<u16>> {
        let req = SdoInfoRequest::OdList { list_type };
        let mut m = self.exchange(pos, |c, buf| req.emit_mailbox(c, buf).unwrap());
        let mut data = Vec::new();
        loop {
            match MailboxMessage::parse(&m).unwrap().1 {
                MailboxMessage::SdoInfo(f) => {
                    data.extend_from_slice(f.data);
                    if !f.incomplete {
                        break;
                    }
                }
                MailboxMessage::Error(_) => return None,
                other => panic!("unexpected {other:?}"),
            }
            m = (0..64)
                .find_map(|_| self.read_mailbox(pos))
                .expect("next SDO information fragment");
        }
        Some(
            data[2..]
                .chunks(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .collect(),
        )
    }

    // ------------------------------------------------------------------------------- process data

    /// Configure SM2/SM3 (addresses from the SII SyncM category defaults) and FMMUs for the
    /// given sizes, one device after the other in the logical image.
    pub fn configure_pd(&mut self, sizes: &[(usize, usize)]) {
        let total_out: usize = sizes.iter().map(|s| s.0).sum();
        let total_in: usize = sizes.iter().map(|s| s.1).sum();
        self.image = vec![0; total_out + total_in];
        let (mut o, mut i) = (0usize, total_out);
        for (pos, &(out_len, in_len)) in sizes.iter().enumerate() {
            let st = Self::station(pos);
            let (sm2, sm3) = self.pd_sm_addresses(pos);
            self.pd[pos] = PdSlot {
                out_len,
                in_len,
                out_off: o,
                in_off: i,
            };
            let mut sm = [0u8; 16];
            sm[0..2].copy_from_slice(&sm2.to_le_bytes());
            sm[2..4].copy_from_slice(&(out_len as u16).to_le_bytes());
            sm[4] = 0x64;
            sm[6] = u8::from(out_len > 0);
            sm[8..10].copy_from_slice(&sm3.to_le_bytes());
            sm[10..12].copy_from_slice(&(in_len as u16).to_le_bytes());
            sm[12] = 0x20;
            sm[14] = u8::from(in_len > 0);
            // An enabled SyncManager cannot be reconfigured: disable both first.
            assert_eq!(self.p.fpwr(st, 0x0816, &[0]).unwrap().wkc, 1);
            assert_eq!(self.p.fpwr(st, 0x081E, &[0]).unwrap().wkc, 1);
            assert_eq!(self.p.fpwr(st, 0x0810, &sm).unwrap().wkc, 1);
            for (k, (logical, len, phys, dir)) in [(o, out_len, sm2, 2u8), (i, in_len, sm3, 1u8)]
                .into_iter()
                .enumerate()
            {
                let mut f = [0u8; 16];
                f[0..4].copy_from_slice(&(logical as u32).to_le_bytes());
                f[4..6].copy_from_slice(&(len as u16).to_le_bytes());
                f[7] = 7;
                f[8..10].copy_from_slice(&phys.to_le_bytes());
                f[11] = dir;
                f[12] = u8::from(len > 0);
                assert_eq!(self.p.fpwr(st, 0x0600 + 16 * k as u16, &f).unwrap().wkc, 1);
            }
            o += out_len;
            i += in_len;
        }
    }

    /// SM2/SM3 start addresses from the SII SyncM category.
    fn pd_sm_addresses(&mut self, pos: usize) -> (u16, u16) {
        let img = self.eeprom(pos);
        let sii = ecdrive_sim::sii::SiiImage::from_bytes(img);
        let cat = sii
            .category(ecdrive_sim::sii::category::SYNC_MANAGER)
            .unwrap()
            .to_vec();
        let mut out = (0, 0);
        for sm in cat.chunks(8) {
            match sm[7] {
                3 => out.0 = u16le(sm, 0),
                4 => out.1 = u16le(sm, 0),
                _ => {}
            }
        }
        out
    }

    /// Activate SYNC0 with `cycle_ns` on every device, starting one cycle from now.
    pub fn activate_dc(&mut self, cycle_ns: u32) {
        self.cycle_ns = cycle_ns;
        for pos in 0..self.pd.len() {
            let st = Self::station(pos);
            let now = u64::from_le_bytes(
                self.p.fprd(st, 0x0910, 8).unwrap().data[..8]
                    .try_into()
                    .unwrap(),
            );
            let start = now + u64::from(cycle_ns);
            self.p.fpwr(st, 0x0981, &[0]).unwrap();
            self.p.fpwr(st, 0x0990, &start.to_le_bytes()).unwrap();
            self.p
                .fpwr(st, 0x09A0, &u64::from(cycle_ns).to_le_bytes())
                .unwrap();
            self.p.fpwr(st, 0x0981, &[0x03]).unwrap();
        }
        // Half a cycle past the first pulse: frames then run mid-cycle.
        self.clock
            .advance(u64::from(cycle_ns) + u64::from(cycle_ns) / 2);
        self.p.segment.poll();
    }

    /// One cycle: exchange the image (LRW) mid-cycle, then let the next SYNC0 pass.
    pub fn cycle(&mut self) {
        let img = self.image.clone();
        let r = self.p.logical(Command::Lrw, 0, &img).unwrap();
        self.image.copy_from_slice(&r.data);
        self.clock.advance(u64::from(self.cycle_ns));
        self.p.segment.poll();
    }

    /// A cycle in which the frame is lost: only the time passes.
    pub fn skip_cycle(&mut self) {
        self.clock.advance(u64::from(self.cycle_ns));
        self.p.segment.poll();
    }

    pub fn outputs_mut(&mut self, pos: usize) -> &mut [u8] {
        let s = self.pd[pos];
        &mut self.image[s.out_off..s.out_off + s.out_len]
    }

    pub fn inputs(&self, pos: usize) -> &[u8] {
        let s = self.pd[pos];
        &self.image[s.in_off..s.in_off + s.in_len]
    }
}

/// The recommended cyclic mapping layout of both drives (profile `cyclic_mapping`):
/// outputs: controlword 0, target position 2, target velocity 6, target torque 10, mode 12;
/// inputs: statusword 0, position 2, velocity 6, torque 10, following error 12, error code 16,
/// mode display 18. The MR-J4-TM's adds Status DO 2 (0x2D12) at the end of its inputs.
pub mod cyclic {
    pub const OUT: usize = 13;
    pub const IN: usize = 19;

    /// Output and input image sizes of a profile's recommended cyclic mapping.
    pub fn sizes(p: &ecdrive_core::drives::DriveProfile) -> (usize, usize) {
        let l = ecdrive_core::pdo::Layout::new(&p.cyclic_mapping);
        (
            l.bytes(ecdrive_core::pdo::Direction::Rx),
            l.bytes(ecdrive_core::pdo::Direction::Tx),
        )
    }

    pub fn set_cw(o: &mut [u8], cw: u16) {
        o[0..2].copy_from_slice(&cw.to_le_bytes());
    }
    pub fn set_target(o: &mut [u8], p: i32) {
        o[2..6].copy_from_slice(&p.to_le_bytes());
    }
    pub fn set_velocity(o: &mut [u8], v: i32) {
        o[6..10].copy_from_slice(&v.to_le_bytes());
    }
    pub fn set_torque(o: &mut [u8], t: i16) {
        o[10..12].copy_from_slice(&t.to_le_bytes());
    }
    pub fn set_mode(o: &mut [u8], m: i8) {
        o[12] = m as u8;
    }
    pub fn sw(i: &[u8]) -> u16 {
        u16::from_le_bytes([i[0], i[1]])
    }
    pub fn position(i: &[u8]) -> i32 {
        i32::from_le_bytes(i[2..6].try_into().unwrap())
    }
    pub fn velocity(i: &[u8]) -> i32 {
        i32::from_le_bytes(i[6..10].try_into().unwrap())
    }
    pub fn torque(i: &[u8]) -> i16 {
        i16::from_le_bytes(i[10..12].try_into().unwrap())
    }
    pub fn following_error(i: &[u8]) -> i32 {
        i32::from_le_bytes(i[12..16].try_into().unwrap())
    }
    pub fn error_code(i: &[u8]) -> u16 {
        u16::from_le_bytes([i[16], i[17]])
    }
    pub fn mode(i: &[u8]) -> i8 {
        i[18] as i8
    }
}

/// Install `mapping` (one PDO per direction) by SDO in PRE-OP, the standard sequence.
pub fn remap(w: &mut Wire, pos: usize, mapping: &ecdrive_core::pdo::Mapping) {
    use ecdrive_core::pdo::remap_sequence;
    for s in remap_sequence(mapping, &Default::default()).unwrap() {
        w.download(pos, s.address.index, s.address.sub, &s.bytes())
            .unwrap_or_else(|c| panic!("{}: abort 0x{c:08X} ({})", s.address, s.description));
    }
}

impl Wire {
    /// Every drive of the segment in OP with the recommended cyclic mapping, the profile's
    /// start-up SDOs and synchronisation writes, DC SYNC0 at `cycle_ns`, outputs zero.
    pub fn op_cyclic(profiles: &[&DriveProfile], cycle_ns: u32) -> Self {
        let mut w = Self::drives(profiles);
        for (pos, p) in profiles.iter().enumerate() {
            w.preop(pos);
            remap(&mut w, pos, &p.cyclic_mapping);
            for s in p.startup {
                let e = p.od().entry(s.address).unwrap();
                let bytes = s.value.to_value().unwrap().encode(e.data_type).unwrap();
                w.download(pos, s.address.index, s.address.sub, &bytes)
                    .unwrap_or_else(|c| panic!("{}: {} abort 0x{c:08X}", p.name, s.address));
            }
            for s in p.sync_writes(cycle_ns, true).unwrap() {
                let e = p.od().entry(s.address).unwrap();
                let bytes = ecdrive_core::od::Value::Int(s.value)
                    .encode(e.data_type)
                    .unwrap();
                w.download(pos, s.address.index, s.address.sub, &bytes)
                    .unwrap_or_else(|c| panic!("{}: {} abort 0x{c:08X}", p.name, s.address));
            }
        }
        let sizes: Vec<(usize, usize)> = profiles.iter().map(|p| cyclic::sizes(p)).collect();
        w.configure_pd(&sizes);
        for pos in 0..profiles.len() {
            assert_eq!(w.request(pos, 0x0004), (0x0004, 0), "SAFE-OP");
        }
        w.activate_dc(cycle_ns);
        for pos in 0..profiles.len() {
            assert_eq!(w.request(pos, 0x0008), (0x0008, 0), "OP");
        }
        w.cycle();
        w
    }

    /// One emulated `drive` (built by the test: a stored parameter, another machine) brought
    /// to OP with `p`'s cyclic mapping, start-up values and DC at `cycle_ns`, like
    /// [`Wire::op_cyclic`].
    #[allow(dead_code)]
    pub fn op_drive(drive: EmulatedDrive, p: &DriveProfile, cycle_ns: u32) -> Self {
        let mut w = Self::new(vec![Box::new(drive)]);
        w.preop(0);
        remap(&mut w, 0, &p.cyclic_mapping);
        for s in p.startup {
            let e = p.od().entry(s.address).unwrap();
            let b = s.value.to_value().unwrap().encode(e.data_type).unwrap();
            w.download(0, s.address.index, s.address.sub, &b).unwrap();
        }
        for s in p.sync_writes(cycle_ns, true).unwrap() {
            let e = p.od().entry(s.address).unwrap();
            let b = ecdrive_core::od::Value::Int(s.value)
                .encode(e.data_type)
                .unwrap();
            w.download(0, s.address.index, s.address.sub, &b).unwrap();
        }
        w.configure_pd(&[cyclic::sizes(p)]);
        assert_eq!(w.request(0, 4), (4, 0));
        w.activate_dc(cycle_ns);
        assert_eq!(w.request(0, 8), (8, 0));
        w.cycle();
        w
    }

    /// Set the controlword of `pos`, run two cycles (the drive acts at the first SYNC0, the
    /// second frame reads the result) and return the statusword.
    pub fn command(&mut self, pos: usize, cw: u16) -> u16 {
        cyclic::set_cw(self.outputs_mut(pos), cw);
        self.cycle();
        self.cycle();
        cyclic::sw(self.inputs(pos))
    }

    /// The CiA 402 state from the statusword of `pos`.
    pub fn state(&self, pos: usize) -> ecdrive_core::cia402::State {
        ecdrive_core::cia402::State::from_statusword(cyclic::sw(self.inputs(pos))).unwrap()
    }
}
