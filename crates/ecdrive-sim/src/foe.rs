//! The FoE (File access over EtherCAT) server of an emulated slave, and the firmware image the
//! emulated drives accept over it.
//!
//! What a device allows is data, a [`FoeSpec`]: the password, whether files are reachable only
//! in BOOT, the largest file, and whether a written file must be a [`FirmwareImage`] for the
//! device. The server keeps the files written (a flash store, in memory), serves reads of
//! them, and hands a firmware image to the device when the write ends; the device applies it
//! at the next start ([`FoeServer::take_firmware`]).
//!
//! Protocol (ETG.1000.6 §5.8): a write is WRQ → ACK 0, DATA 1 → ACK 1, …; a read is RRQ →
//! DATA 1, ACK 1 → DATA 2, …; a DATA packet shorter than the mailbox allows ends the file.
//! Refusals are FoE ERR messages with the standard codes ([`FoeErrorCode`]): 0x8009 outside
//! BOOT where BOOT is required, 0x800A for a wrong password, 0x8001 for a read of a file that
//! is not there, 0x8005 for a packet out of order, 0x8003 for a file too large, 0x8004 for a
//! firmware image that is not for this device.

use crate::ec::AlState;
use crate::ec::mailbox::{FoeErrorCode, FoeMessage, foe_data_capacity};

/// What a device's FoE server allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FoeSpec {
    /// The password every request must carry (0: none).
    pub password: u32,
    /// Files are reachable only in BOOT (error 0x8009 in other states).
    pub boot_only: bool,
    /// The largest file accepted, bytes.
    pub max_file_bytes: usize,
    /// Written files must be firmware images for this identity (vendor ID, product code).
    pub firmware_for: Option<(u32, u32)>,
}

/// The emulation's firmware image format (\[REC\]: a vendor's format is its own; this one
/// carries what an update changes and a check that the file is whole).
///
/// ```text
/// 0   magic "ECDRVFW1"
/// 8   vendor ID u32, product code u32 (the device it is for)
/// 16  revision number u32 (0x1018:03 after the update)
/// 20  software version, 16 bytes, NUL-padded ASCII (0x100A after the update)
/// 36  payload length u32, payload
/// end CRC-32 (IEEE) of everything before it, u32
/// ```
/// All little-endian.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FirmwareImage {
    /// Vendor ID of the device it is for.
    pub vendor_id: u32,
    /// Product code of the device it is for.
    pub product_code: u32,
    /// Revision number it gives the device.
    pub revision: u32,
    /// Software version it gives the device (at most 16 bytes).
    pub version: String,
    /// The rest.
    pub payload: Vec<u8>,
}

const MAGIC: &[u8; 8] = b"ECDRVFW1";
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

impl FirmwareImage {
    /// The file's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut v = Vec::with_capacity(44 + self.payload.len());
        v.extend_from_slice(MAGIC);
        v.extend_from_slice(&self.vendor_id.to_le_bytes());
        v.extend_from_slice(&self.product_code.to_le_bytes());
        v.extend_from_slice(&self.revision.to_le_bytes());
        let mut version = [0u8; 16];
        for (d, s) in version.iter_mut().zip(self.version.bytes()) {
            *d = s;
        }
        v.extend_from_slice(&version);
        v.extend_from_slice(&(self.payload.len() as u32).to_le_bytes());
        v.extend_from_slice(&self.payload);
        let crc = CRC32.checksum(&v);
        v.extend_from_slice(&crc.to_le_bytes());
        v
    }

    /// Decode a file; the reason in words when it is not an image.
    pub fn decode(b: &[u8]) -> Result<Self, &'static str> {
        let u32_at = |at: usize| {
            b.get(at..at + 4)
                .and_then(|s| <[u8; 4]>::try_from(s).ok())
                .map(u32::from_le_bytes)
        };
        if b.get(..8) != Some(MAGIC.as_slice()) {
            return Err("not a firmware image (no ECDRVFW1 header)");
        }
        let len = u32_at(36).ok_or("firmware image truncated")? as usize;
        let end = 40usize.checked_add(len).ok_or("firmware image length")?;
        if b.len() != end + 4 {
            return Err("firmware image length does not match the file");
        }
        let body = b.get(..end).ok_or("firmware image truncated")?;
        if u32_at(end) != Some(CRC32.checksum(body)) {
            return Err("firmware image CRC-32 wrong");
        }
        let version = b.get(20..36).unwrap_or_default();
        let version: String = version
            .iter()
            .take_while(|c| **c != 0)
            .map(|c| char::from(*c))
            .collect();
        Ok(Self {
            vendor_id: u32_at(8).unwrap_or(0),
            product_code: u32_at(12).unwrap_or(0),
            revision: u32_at(16).unwrap_or(0),
            version,
            payload: b.get(40..end).unwrap_or_default().to_vec(),
        })
    }
}

/// A reply the server wants sent (the mailbox server emits it with its counter).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FoeReply {
    /// ACK of a packet.
    Ack(u32),
    /// DATA packet `packet`: the bytes `range` of the file being read.
    Data {
        /// Packet number.
        packet: u32,
        /// The bytes.
        data: Vec<u8>,
    },
    /// ERR.
    Error(FoeErrorCode, &'static str),
}

impl FoeReply {
    /// As a message.
    pub fn message(&self) -> FoeMessage<'_> {
        match self {
            Self::Ack(p) => FoeMessage::Ack { packet: *p },
            Self::Data { packet, data } => FoeMessage::Data {
                packet: *packet,
                data,
            },
            Self::Error(code, text) => FoeMessage::Error {
                code: *code,
                text: text.as_bytes(),
            },
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Transfer {
    Idle,
    Writing {
        name: Vec<u8>,
        data: Vec<u8>,
        /// The packet acknowledged last.
        acked: u32,
    },
    Reading {
        file: usize,
        /// The packet sent last.
        sent: u32,
        /// Whether that packet was the last one.
        last: bool,
    },
}

/// Counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FoeStats {
    /// Files written completely.
    pub files_written: u64,
    /// Files read completely.
    pub files_read: u64,
    /// ERR replies sent.
    pub errors_sent: u64,
}

/// The FoE server of one device. See the [module documentation](self).
#[derive(Debug, Clone)]
pub struct FoeServer {
    spec: FoeSpec,
    files: Vec<(Vec<u8>, Vec<u8>)>,
    transfer: Transfer,
    firmware: Option<FirmwareImage>,
    stats: FoeStats,
}

impl FoeServer {
    /// A server allowing what `spec` says, with no files.
    pub fn new(spec: FoeSpec) -> Self {
        Self {
            spec,
            files: Vec::new(),
            transfer: Transfer::Idle,
            firmware: None,
            stats: FoeStats::default(),
        }
    }

    /// What it allows.
    pub fn spec(&self) -> &FoeSpec {
        &self.spec
    }

    /// Counters.
    pub fn stats(&self) -> FoeStats {
        self.stats
    }

    /// The firmware image written completely since the last call, if any.
    pub fn take_firmware(&mut self) -> Option<FirmwareImage> {
        self.firmware.take()
    }

    /// The mailbox was reset (state change): a transfer in progress is dropped.
    pub fn reset(&mut self) {
        self.transfer = Transfer::Idle;
    }

    fn fail(&mut self, code: FoeErrorCode, text: &'static str) -> FoeReply {
        self.transfer = Transfer::Idle;
        self.stats.errors_sent += 1;
        tracing::debug!(code = %code, text, "FoE error");
        FoeReply::Error(code, text)
    }

    /// Serve one FoE request (the data of a type-4 mailbox) in `state`, with a reply mailbox
    /// of `mailbox_size` bytes. `None`: nothing to send (an ERR or BUSY from the master).
    pub fn handle(
        &mut self,
        payload: &[u8],
        state: AlState,
        mailbox_size: usize,
    ) -> Option<FoeReply> {
        let msg = match FoeMessage::parse(payload) {
            Ok(m) => m,
            Err(_) => return Some(self.fail(FoeErrorCode::ILLEGAL, "undecodable FoE request")),
        };
        let capacity = foe_data_capacity(mailbox_size);
        match msg {
            FoeMessage::Read { password, name } | FoeMessage::Write { password, name } => {
                if self.spec.boot_only && state != AlState::Bootstrap {
                    return Some(
                        self.fail(FoeErrorCode::NOT_IN_BOOTSTRAP, "file access in BOOT only"),
                    );
                }
                if password != self.spec.password {
                    return Some(self.fail(FoeErrorCode::NO_RIGHTS, "wrong password"));
                }
                if let FoeMessage::Write { .. } = msg {
                    self.transfer = Transfer::Writing {
                        name: name.to_vec(),
                        data: Vec::new(),
                        acked: 0,
                    };
                    return Some(FoeReply::Ack(0));
                }
                let Some(file) = self.files.iter().position(|(n, _)| n == name) else {
                    return Some(self.fail(FoeErrorCode::NOT_FOUND, "no such file"));
                };
                self.transfer = Transfer::Reading {
                    file,
                    sent: 0,
                    last: false,
                };
                Some(self.next_data(1, capacity))
            }
            FoeMessage::Data { packet, data } => {
                let Transfer::Writing {
                    data: buf, acked, ..
                } = &mut self.transfer
                else {
                    return Some(self.fail(FoeErrorCode::ILLEGAL, "DATA without a write request"));
                };
                if packet == *acked && packet != 0 {
                    // The master sent the last packet again (it lost the ACK): ACK it again.
                    return Some(FoeReply::Ack(packet));
                }
                if packet != acked.wrapping_add(1) {
                    return Some(self.fail(FoeErrorCode::PACKET_NUMBER, "packet out of order"));
                }
                if buf.len() + data.len() > self.spec.max_file_bytes {
                    return Some(self.fail(FoeErrorCode::DISK_FULL, "file too large"));
                }
                buf.extend_from_slice(data);
                *acked = packet;
                if data.len() < capacity {
                    return Some(self.finish_write(packet));
                }
                Some(FoeReply::Ack(packet))
            }
            FoeMessage::Ack { packet } => match self.transfer {
                Transfer::Reading { sent, last, .. } if packet == sent => {
                    if last {
                        self.transfer = Transfer::Idle;
                        self.stats.files_read += 1;
                        None
                    } else {
                        Some(self.next_data(sent + 1, capacity))
                    }
                }
                Transfer::Reading { .. } => {
                    Some(self.fail(FoeErrorCode::PACKET_NUMBER, "ACK of a packet not sent"))
                }
                _ => Some(self.fail(FoeErrorCode::ILLEGAL, "ACK without a read")),
            },
            FoeMessage::Error { .. } | FoeMessage::Busy { .. } => {
                self.transfer = Transfer::Idle;
                None
            }
        }
    }

    fn finish_write(&mut self, packet: u32) -> FoeReply {
        let Transfer::Writing { name, data, .. } =
            core::mem::replace(&mut self.transfer, Transfer::Idle)
        else {
            return self.fail(FoeErrorCode::PROGRAM_ERROR, "no write in progress");
        };
        if let Some((vendor, product)) = self.spec.firmware_for {
            match FirmwareImage::decode(&data) {
                Ok(fw) if fw.vendor_id == vendor && fw.product_code == product => {
                    self.firmware = Some(fw);
                }
                Ok(_) => {
                    return self.fail(FoeErrorCode::ILLEGAL, "firmware for another device");
                }
                Err(why) => return self.fail(FoeErrorCode::ILLEGAL, why),
            }
        }
        match self.files.iter_mut().find(|(n, _)| *n == name) {
            Some((_, d)) => *d = data,
            None => self.files.push((name, data)),
        }
        self.stats.files_written += 1;
        FoeReply::Ack(packet)
    }

    fn next_data(&mut self, packet: u32, capacity: usize) -> FoeReply {
        let Transfer::Reading { file, .. } = self.transfer else {
            return self.fail(FoeErrorCode::PROGRAM_ERROR, "no read in progress");
        };
        let content = self
            .files
            .get(file)
            .map(|(_, d)| d.as_slice())
            .unwrap_or(&[]);
        let start = (packet as usize - 1).saturating_mul(capacity.max(1));
        let end = (start + capacity).min(content.len());
        let data = content.get(start..end).unwrap_or_default().to_vec();
        let last = data.len() < capacity;
        self.transfer = Transfer::Reading {
            file,
            sent: packet,
            last,
        };
        FoeReply::Data { packet, data }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: FoeSpec = FoeSpec {
        password: 0x1234,
        boot_only: true,
        max_file_bytes: 4096,
        firmware_for: Some((0xA1E, 0x201)),
    };

    fn image() -> Vec<u8> {
        FirmwareImage {
            vendor_id: 0xA1E,
            product_code: 0x201,
            revision: 0x0003_0000,
            version: "B5".into(),
            payload: (0..200u8).collect(),
        }
        .encode()
    }

    fn req(m: FoeMessage<'_>) -> Vec<u8> {
        let mut b = vec![0u8; 512];
        let n = m.emit_mailbox(1, &mut b).unwrap();
        b.truncate(n);
        b.split_off(6)
    }

    #[test]
    fn image_round_trips_and_damage_is_named() {
        let b = image();
        let fw = FirmwareImage::decode(&b).unwrap();
        assert_eq!((fw.revision, fw.version.as_str()), (0x0003_0000, "B5"));
        let mut bad = b.clone();
        bad[50] ^= 1;
        assert_eq!(
            FirmwareImage::decode(&bad),
            Err("firmware image CRC-32 wrong")
        );
        assert!(FirmwareImage::decode(&b[..30]).is_err());
        assert!(FirmwareImage::decode(b"hello").is_err());
    }

    #[test]
    fn write_then_read_in_boot() {
        let mut s = FoeServer::new(SPEC);
        let b = image();
        let mbx = 64; // 52 data bytes per packet
        let cap = foe_data_capacity(mbx);
        let w = req(FoeMessage::Write {
            password: 0x1234,
            name: b"fw.bin",
        });
        assert_eq!(
            s.handle(&w, AlState::Bootstrap, mbx),
            Some(FoeReply::Ack(0))
        );
        let mut packet = 0;
        for chunk in b.chunks(cap) {
            packet += 1;
            let d = req(FoeMessage::Data {
                packet,
                data: chunk,
            });
            assert_eq!(
                s.handle(&d, AlState::Bootstrap, mbx),
                Some(FoeReply::Ack(packet))
            );
        }
        if b.len() % cap == 0 {
            packet += 1;
            let d = req(FoeMessage::Data { packet, data: &[] });
            assert_eq!(
                s.handle(&d, AlState::Bootstrap, mbx),
                Some(FoeReply::Ack(packet))
            );
        }
        assert_eq!(s.stats().files_written, 1);
        assert_eq!(s.take_firmware().unwrap().version, "B5");
        let r = req(FoeMessage::Read {
            password: 0x1234,
            name: b"fw.bin",
        });
        let mut got = Vec::new();
        let mut reply = s.handle(&r, AlState::Bootstrap, mbx);
        while let Some(FoeReply::Data { packet, data }) = reply {
            got.extend_from_slice(&data);
            reply = s.handle(&req(FoeMessage::Ack { packet }), AlState::Bootstrap, mbx);
        }
        assert_eq!(reply, None);
        assert_eq!(got, b);
    }

    #[test]
    fn refusals_carry_the_standard_codes() {
        let mut s = FoeServer::new(SPEC);
        let w = |password| {
            req(FoeMessage::Write {
                password,
                name: b"fw.bin",
            })
        };
        let code = |r: Option<FoeReply>| match r {
            Some(FoeReply::Error(c, _)) => c,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            code(s.handle(&w(0x1234), AlState::PreOp, 64)),
            FoeErrorCode::NOT_IN_BOOTSTRAP
        );
        assert_eq!(
            code(s.handle(&w(0), AlState::Bootstrap, 64)),
            FoeErrorCode::NO_RIGHTS
        );
        let r = req(FoeMessage::Read {
            password: 0x1234,
            name: b"none",
        });
        assert_eq!(
            code(s.handle(&r, AlState::Bootstrap, 64)),
            FoeErrorCode::NOT_FOUND
        );
        // Not a firmware image: refused at the end.
        assert_eq!(
            s.handle(&w(0x1234), AlState::Bootstrap, 64),
            Some(FoeReply::Ack(0))
        );
        let d = req(FoeMessage::Data {
            packet: 1,
            data: b"short",
        });
        assert_eq!(
            code(s.handle(&d, AlState::Bootstrap, 64)),
            FoeErrorCode::ILLEGAL
        );
        assert_eq!(s.take_firmware(), None);
        // Out of order.
        s.handle(&w(0x1234), AlState::Bootstrap, 64);
        let d = req(FoeMessage::Data {
            packet: 2,
            data: b"x",
        });
        assert_eq!(
            code(s.handle(&d, AlState::Bootstrap, 64)),
            FoeErrorCode::PACKET_NUMBER
        );
        // Garbage never panics.
        for n in 0..8 {
            let _ = s.handle(&[0xFF; 16][..n], AlState::Bootstrap, 64);
        }
    }
}
