//! A mailbox device whose firmware echoes every request.

use crate::device::{Device, ProcessDataSizes};
use crate::ec::AlState;
use crate::sii::{
    DeviceDescription, FmmuUsage, Identity, MailboxDesc, MailboxProtocols, SmDesc, SmEnable, SmType,
};

use super::io::TEST_VENDOR_ID;

/// Start of the master → slave mailbox.
pub const ECHO_MBX_OUT: u16 = 0x1000;
/// Start of the slave → master mailbox.
pub const ECHO_MBX_IN: u16 = 0x1080;
/// Size of each mailbox.
pub const ECHO_MBX_SIZE: u16 = 128;

/// A device with a standard mailbox (SM0 at 0x1000, SM1 at 0x1080, 128 bytes each) and no
/// process data. Its firmware returns every complete request unchanged (header and data, up to
/// the length in the mailbox header), and can be given unsolicited messages to post.
#[derive(Debug, Clone, Default)]
pub struct EchoMailbox {
    serial: u32,
    /// Requests received, in order (whole SM0 buffers).
    pub requests: Vec<Vec<u8>>,
    /// Messages to post unsolicited when SM1 is free.
    pub unsolicited: Vec<Vec<u8>>,
    /// Number of `mailbox_reset` calls.
    pub resets: u32,
}

impl EchoMailbox {
    /// A new echo device.
    pub fn new() -> Self {
        Self::default()
    }

    /// With a serial number.
    pub fn with_serial(mut self, serial: u32) -> Self {
        self.serial = serial;
        self
    }
}

impl Device for EchoMailbox {
    fn description(&self) -> DeviceDescription {
        DeviceDescription {
            identity: Identity {
                vendor_id: TEST_VENDOR_ID,
                product_code: 0x0000_0102,
                revision: 1,
                serial: self.serial,
            },
            order: "ECD-ECHO".into(),
            name: "ecdrive mailbox echo".into(),
            group: "ecdrive test devices".into(),
            mailbox: Some(MailboxDesc {
                rx_offset: ECHO_MBX_OUT,
                rx_size: ECHO_MBX_SIZE,
                tx_offset: ECHO_MBX_IN,
                tx_size: ECHO_MBX_SIZE,
                // [REC] VoE: a vendor protocol no master interprets, so masters leave it alone.
                protocols: MailboxProtocols::VOE,
                bootstrap: None,
            }),
            sync_managers: vec![
                SmDesc {
                    start: ECHO_MBX_OUT,
                    length: ECHO_MBX_SIZE,
                    control: 0x26,
                    enable: SmEnable::ENABLE,
                    kind: SmType::MailboxOut,
                },
                SmDesc {
                    start: ECHO_MBX_IN,
                    length: ECHO_MBX_SIZE,
                    control: 0x22,
                    enable: SmEnable::ENABLE,
                    kind: SmType::MailboxIn,
                },
            ],
            fmmus: vec![FmmuUsage::SmStatus],
            ..Default::default()
        }
    }

    fn process_data_sizes(&self) -> ProcessDataSizes {
        ProcessDataSizes::default()
    }

    fn mailbox_request(
        &mut self,
        _state: AlState,
        request: &[u8],
        reply: &mut [u8],
    ) -> Option<usize> {
        self.requests.push(request.to_vec());
        let len = request
            .get(0..2)
            .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]])))?;
        let n = (6 + len).min(request.len()).min(reply.len());
        reply.get_mut(..n)?.copy_from_slice(request.get(..n)?);
        Some(n)
    }

    fn mailbox_poll(&mut self, reply: &mut [u8]) -> Option<usize> {
        if self.unsolicited.is_empty() {
            return None;
        }
        let m = self.unsolicited.remove(0);
        let n = m.len().min(reply.len());
        reply.get_mut(..n)?.copy_from_slice(m.get(..n)?);
        Some(n)
    }

    fn mailbox_reset(&mut self) {
        self.resets += 1;
    }
}
