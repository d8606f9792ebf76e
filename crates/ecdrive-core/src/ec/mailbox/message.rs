//! Any received mailbox: [`MailboxMessage::parse`], [`mailbox_payload`].

use super::*;

// ---------------------------------------------------------------------------------------------
// Whole messages.

/// What a mailbox carries, decoded as far as this module knows the protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MailboxMessage<'a> {
    /// A mailbox error reply.
    Error(MailboxErrorReply),
    /// CoE "SDO request" (including aborts from either side).
    SdoRequest(SdoRequest<'a>),
    /// CoE "SDO response".
    SdoResponse(SdoResponse<'a>),
    /// CoE emergency.
    Emergency(Emergency),
    /// CoE SDO information (request, response fragment or error).
    SdoInfo(SdoInfoFragment<'a>),
    /// Another CoE service (PDO services), undecoded.
    OtherCoe {
        /// The raw service field.
        service: u8,
        /// The data after the CoE header.
        payload: &'a [u8],
    },
    /// An FoE message.
    Foe(FoeMessage<'a>),
    /// Another mailbox protocol, undecoded.
    Other {
        /// The raw type field.
        mailbox_type: u8,
        /// The mailbox data.
        payload: &'a [u8],
    },
}

impl<'a> MailboxMessage<'a> {
    /// Parse a received mailbox (a whole SyncManager buffer: header, data, padding). Returns the
    /// counter and the message.
    pub fn parse(buf: &'a [u8]) -> Result<(u8, Self), Error> {
        let mbx = Mailbox::new_checked(buf)?;
        let counter = mbx.counter();
        let payload = payload_of(buf);
        let msg = match mbx.mailbox_type() {
            Some(MailboxType::Error) => Self::Error(MailboxErrorReply::parse(payload)?),
            Some(MailboxType::Coe) => {
                let coe = Coe::new_checked(payload)?;
                let data = tail(payload, COE_HEADER_LEN);
                match coe.service() {
                    Some(CoeService::SdoRequest) => Self::SdoRequest(SdoRequest::parse(data)?),
                    Some(CoeService::SdoResponse) => Self::SdoResponse(SdoResponse::parse(data)?),
                    Some(CoeService::Emergency) => Self::Emergency(Emergency::parse_coe(data)?),
                    Some(CoeService::SdoInfo) => Self::SdoInfo(SdoInfoFragment::parse(data)?),
                    _ => Self::OtherCoe {
                        service: coe.service_raw(),
                        payload: data,
                    },
                }
            }
            Some(MailboxType::Foe) => Self::Foe(FoeMessage::parse(payload)?),
            _ => Self::Other {
                mailbox_type: mbx.mailbox_type_raw(),
                payload,
            },
        };
        Ok((counter, msg))
    }
}

/// The `length` data bytes of a mailbox already checked with [`Mailbox::new_checked`], with
/// the buffer's lifetime.
pub(super) fn payload_of(buf: &[u8]) -> &[u8] {
    let len = rd_u16(buf, 0) as usize;
    buf.get(MAILBOX_HEADER_LEN..MAILBOX_HEADER_LEN + len)
        .unwrap_or(&[])
}

/// The data bytes of a mailbox after checking its header: `length` bytes after the 6-byte
/// header, with the buffer's lifetime.
pub fn mailbox_payload(buf: &[u8]) -> Result<&[u8], Error> {
    Mailbox::new_checked(buf)?;
    Ok(payload_of(buf))
}
