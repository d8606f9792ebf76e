//! FoE (File access over EtherCAT) over the same mailbox handshake as CoE: counters, repeat
//! requests and emergencies are the mailbox's, not a protocol's.
//!
//! A write sends WRQ and waits for ACK 0, then DATA packets of as many bytes as the device's
//! receive mailbox takes (SM0 length − 12), each acknowledged before the next; the packet
//! shorter than that ends the file (an empty one when the file fills the last packet). A read
//! sends RRQ and acknowledges each DATA packet until the short one. BUSY from the device means
//! "send the last packet again" (for a read: wait); ERR ends the transfer with the device's
//! code and text.

use super::{CoeClient, CoeError, CoeErrorKind};
use crate::ec::mailbox::{FoeMessage, MailboxMessage, foe_data_capacity};
use crate::rt::monotonic_ns;
use std::time::Duration;

/// What a transfer moved.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct FoeTransfer {
    /// Bytes moved.
    pub bytes: usize,
    /// DATA packets exchanged.
    pub packets: u32,
    /// BUSY replies the device gave.
    pub busy: u32,
}

/// How long a device may answer BUSY before the transfer is given up.
const BUSY_LIMIT: Duration = Duration::from_secs(30);

impl CoeClient<'_> {
    /// Send one FoE message, wait for the FoE reply, and return its bytes in `self.buf`.
    async fn foe_exchange(&mut self, msg: FoeMessage<'_>) -> Result<usize, CoeError> {
        self.drain().await?;
        let counter = self.next_counter();
        let mut out = vec![0u8; self.sms.out_len as usize];
        let n = msg
            .emit_mailbox(counter, &mut out)
            .map_err(|e| self.error(None, CoeErrorKind::TooLarge(e.to_string())))?;
        self.send(&out[..n], None).await?;
        self.receive_reply(None, |m| matches!(m, MailboxMessage::Foe(_)))
            .await
    }

    /// Wait for the next FoE message without sending (a read's next DATA after BUSY).
    async fn foe_wait(&mut self) -> Result<usize, CoeError> {
        self.receive_reply(None, |m| matches!(m, MailboxMessage::Foe(_)))
            .await
    }

    fn foe_reply(&self, len: usize) -> Result<FoeMessage<'_>, CoeError> {
        match MailboxMessage::parse(&self.buf[..len]) {
            Ok((_, MailboxMessage::Foe(FoeMessage::Error { code, text }))) => Err(self.error(
                None,
                CoeErrorKind::Foe {
                    code,
                    text: String::from_utf8_lossy(text)
                        .trim_end_matches('\0')
                        .to_string(),
                },
            )),
            Ok((_, MailboxMessage::Foe(m))) => Ok(m),
            Ok(_) => Err(self.error(None, CoeErrorKind::Protocol("not an FoE reply".into()))),
            Err(e) => Err(self.error(None, CoeErrorKind::Protocol(e.to_string()))),
        }
    }

    fn foe_unexpected(&self, what: &str, got: &FoeMessage<'_>) -> CoeError {
        self.error(
            None,
            CoeErrorKind::Protocol(format!("{what}: the device answered {:?}", got.opcode())),
        )
    }

    /// Write `data` as file `name` with `password` (0: none). `progress(done, total)` after
    /// each acknowledged packet.
    pub async fn foe_write(
        &mut self,
        name: &str,
        password: u32,
        data: &[u8],
        progress: &mut (dyn FnMut(usize, usize) + Send),
    ) -> Result<FoeTransfer, CoeError> {
        let mut t = FoeTransfer {
            bytes: 0,
            packets: 0,
            busy: 0,
        };
        let capacity = foe_data_capacity(usize::from(self.sms.out_len));
        if capacity == 0 {
            return Err(self.error(
                None,
                CoeErrorKind::TooLarge("the receive mailbox is too small for FoE".into()),
            ));
        }
        let wrq = FoeMessage::Write {
            password,
            name: name.as_bytes(),
        };
        let len = self.foe_exchange(wrq).await?;
        match self.foe_reply(len)? {
            FoeMessage::Ack { packet: 0 } => {}
            other => return Err(self.foe_unexpected("write request", &other)),
        }
        let busy_until = monotonic_ns() + BUSY_LIMIT.as_nanos() as u64;
        let mut packet: u32 = 1;
        let mut offset = 0usize;
        loop {
            let end = (offset + capacity).min(data.len());
            let chunk = data.get(offset..end).unwrap_or_default();
            let len = self
                .foe_exchange(FoeMessage::Data {
                    packet,
                    data: chunk,
                })
                .await?;
            match self.foe_reply(len)? {
                FoeMessage::Ack { packet: p } if p == packet => {
                    t.packets = packet;
                    offset = end;
                    t.bytes = offset;
                    progress(offset, data.len());
                    if chunk.len() < capacity {
                        return Ok(t);
                    }
                    packet = packet.wrapping_add(1);
                }
                FoeMessage::Busy { .. } => {
                    // Send the same packet again once the device has had a moment.
                    t.busy += 1;
                    if monotonic_ns() > busy_until {
                        return Err(
                            self.error(None, CoeErrorKind::Timeout(BUSY_LIMIT.as_millis() as u64))
                        );
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                other => return Err(self.foe_unexpected(&format!("DATA {packet}"), &other)),
            }
        }
    }

    /// Read file `name` with `password` (0: none). `progress(done)` after each packet.
    pub async fn foe_read(
        &mut self,
        name: &str,
        password: u32,
        max_bytes: usize,
        progress: &mut (dyn FnMut(usize) + Send),
    ) -> Result<(Vec<u8>, FoeTransfer), CoeError> {
        let capacity = foe_data_capacity(usize::from(self.sms.in_len));
        let mut out = Vec::new();
        let mut t = FoeTransfer {
            bytes: 0,
            packets: 0,
            busy: 0,
        };
        let rrq = FoeMessage::Read {
            password,
            name: name.as_bytes(),
        };
        let mut len = self.foe_exchange(rrq).await?;
        let busy_until = monotonic_ns() + BUSY_LIMIT.as_nanos() as u64;
        let mut expect: u32 = 1;
        loop {
            let (packet, n) = match self.foe_reply(len)? {
                FoeMessage::Data { packet, data } if packet == expect => {
                    if out.len() + data.len() > max_bytes {
                        return Err(self.error(
                            None,
                            CoeErrorKind::TooLarge(format!(
                                "the file is larger than {max_bytes} bytes"
                            )),
                        ));
                    }
                    out.extend_from_slice(data);
                    (packet, data.len())
                }
                FoeMessage::Busy { .. } => {
                    t.busy += 1;
                    if monotonic_ns() > busy_until {
                        return Err(
                            self.error(None, CoeErrorKind::Timeout(BUSY_LIMIT.as_millis() as u64))
                        );
                    }
                    len = self.foe_wait().await?;
                    continue;
                }
                other => return Err(self.foe_unexpected(&format!("DATA {expect}"), &other)),
            };
            t.packets = packet;
            t.bytes = out.len();
            progress(out.len());
            if n < capacity {
                // The last packet: acknowledge it; the device sends nothing more.
                self.foe_ack_last(packet).await?;
                return Ok((out, t));
            }
            len = self.foe_exchange(FoeMessage::Ack { packet }).await?;
            expect = expect.wrapping_add(1);
        }
    }

    async fn foe_ack_last(&mut self, packet: u32) -> Result<(), CoeError> {
        let counter = self.next_counter();
        let mut out = vec![0u8; self.sms.out_len as usize];
        let n = FoeMessage::Ack { packet }
            .emit_mailbox(counter, &mut out)
            .map_err(|e| self.error(None, CoeErrorKind::TooLarge(e.to_string())))?;
        self.send(&out[..n], None).await
    }
}
