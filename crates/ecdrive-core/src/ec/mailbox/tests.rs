use super::*;

#[test]
fn header_round_trip_and_lying_length() {
    let mut buf = [0u8; 16];
    let n = emit_header(&mut buf, 10, MailboxType::Coe, 3).unwrap();
    assert_eq!(n, 16);
    assert_eq!(buf[..6], [0x0A, 0x00, 0x00, 0x00, 0x00, 0x33]);
    let m = Mailbox::new_checked(&buf[..]).unwrap();
    assert_eq!(m.counter(), 3);
    assert_eq!(m.mailbox_type(), Some(MailboxType::Coe));
    assert_eq!(m.payload().len(), 10);
    assert_eq!(
        Mailbox::new_checked(&buf[..15]),
        Err(Error::BadLength {
            claimed: 10,
            available: 9
        })
    );
    assert!(matches!(
        Mailbox::new_checked(&buf[..5]),
        Err(Error::Truncated { .. })
    ));
    assert!(matches!(
        emit_header(&mut buf, 11, MailboxType::Coe, 1),
        Err(Error::NoSpace { .. })
    ));
}

#[test]
fn expedited_download_bytes() {
    let mut buf = [0u8; 32];
    let req = SdoRequest::DownloadExpedited {
        index: 0x6040,
        sub: 0,
        complete_access: false,
        data: &[0x0F, 0x00],
    };
    let n = req.emit_mailbox(1, &mut buf).unwrap();
    assert_eq!(
        buf[..n],
        [
            0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20, 0x2B, 0x40, 0x60, 0x00, 0x0F, 0x00,
            0x00, 0x00
        ]
    );
    assert_eq!(
        MailboxMessage::parse(&buf).unwrap(),
        (1, MailboxMessage::SdoRequest(req))
    );
}

#[test]
fn short_segment_is_padded_with_unused_count() {
    let mut buf = [0xEEu8; 32];
    let resp = SdoResponse::UploadSegment {
        toggle: true,
        last: true,
        data: b"abc",
    };
    let n = resp.emit_mailbox(2, &mut buf).unwrap();
    assert_eq!(n, 16);
    assert_eq!(buf[0], 10);
    // 0x00 | t<<4 | n<<1 | c, n = 7 − 3 = 4
    assert_eq!(buf[8], 0x10 | (4 << 1) | 1);
    assert_eq!(&buf[9..16], b"abc\0\0\0\0");
    assert_eq!(
        MailboxMessage::parse(&buf[..n]).unwrap().1,
        MailboxMessage::SdoResponse(resp)
    );
    // A long segment fills the message exactly.
    let data = [7u8; 20];
    let resp = SdoResponse::UploadSegment {
        toggle: false,
        last: false,
        data: &data,
    };
    let n = resp.emit_mailbox(3, &mut buf).unwrap();
    assert_eq!(n, 6 + 3 + 20);
    assert_eq!(buf[8], 0x00);
    assert_eq!(
        MailboxMessage::parse(&buf[..n]).unwrap().1,
        MailboxMessage::SdoResponse(resp)
    );
}

#[test]
fn download_helpers_split_as_soem_does() {
    let data: Vec<u8> = (0..16).collect();
    // SM0 of 20 bytes: 4 bytes in the initiate, then segments of 11.
    let (init, n) = SdoRequest::initiate_download(0x2004, 0, false, &data, 20);
    assert_eq!(n, 4);
    let mut buf = [0u8; 20];
    assert_eq!(init.emit_mailbox(1, &mut buf).unwrap(), 20);
    assert_eq!(
        buf[..12],
        [14, 0, 0, 0, 0, 0x13, 0, 0x20, 0x21, 0x04, 0x20, 0]
    );
    assert_eq!(buf[12..16], [16, 0, 0, 0]);
    let (seg, k) = SdoRequest::download_segment(&data[n..], false, 20);
    assert_eq!(k, 11);
    assert!(matches!(
        seg,
        SdoRequest::DownloadSegment { last: false, .. }
    ));
    let (seg, k) = SdoRequest::download_segment(&data[n + 11..], true, 20);
    assert_eq!(k, 1);
    assert_eq!(seg.emit_mailbox(3, &mut buf).unwrap(), 16);
    // 0x00 | t<<4 | (7 − 1)<<1 | c
    assert_eq!(buf[8], 0x1D);
    // 1–4 bytes go expedited.
    let (init, n) = SdoRequest::initiate_download(0x6040, 0, false, &data[..2], 20);
    assert_eq!(n, 2);
    assert!(matches!(init, SdoRequest::DownloadExpedited { .. }));
}

#[test]
fn entry_description_values_split() {
    let mut out = [0u8; 64];
    let mut data = vec![];
    data.extend_from_slice(&0x1234u16.to_le_bytes());
    data.extend_from_slice(&[1, 0, 2, 0, 3, 0]);
    data.extend_from_slice(b"Controlword");
    let e = EntryDescription {
        index: 0x6040,
        sub: 0,
        value_info: value_info::UNIT_TYPE
            | value_info::DEFAULT
            | value_info::MINIMUM
            | value_info::MAXIMUM,
        data_type: 6,
        bit_len: 16,
        access: 0x3F,
        data: &data,
    };
    let n = e.emit(&mut out).unwrap();
    let p = EntryDescription::parse(&out[..n]).unwrap();
    assert_eq!(p, e);
    let v = p.values().unwrap();
    assert_eq!(v.unit_type, Some(0x1234));
    assert_eq!(v.default, Some(&[1u8, 0][..]));
    assert_eq!(v.maximum, Some(&[3u8, 0][..]));
    assert_eq!(v.name, b"Controlword");
    let short = EntryDescription {
        data: &data[..3],
        ..e
    };
    assert!(short.values().is_err());
}

#[test]
fn emergency_and_error_round_trip() {
    let mut buf = [0u8; 16];
    let e = Emergency {
        error_code: 0x2310,
        error_register: 0x03,
        data: [1, 2, 3, 4, 5],
    };
    let n = e.emit_mailbox(5, &mut buf).unwrap();
    assert_eq!(n, 16);
    assert_eq!(buf[6..8], [0x00, 0x10]);
    assert_eq!(
        MailboxMessage::parse(&buf).unwrap(),
        (5, MailboxMessage::Emergency(e))
    );
    let r = MailboxErrorReply::new(MailboxErrorDetail::UnsupportedProtocol);
    let n = r.emit_mailbox(1, &mut buf).unwrap();
    assert_eq!(buf[..n], [4, 0, 0, 0, 0, 0x10, 1, 0, 2, 0]);
    assert_eq!(
        MailboxMessage::parse(&buf[..n]).unwrap().1,
        MailboxMessage::Error(r)
    );
}
