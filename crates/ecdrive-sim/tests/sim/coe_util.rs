//! Shared helpers of the `coe_*` tests: a CoE server with the fixture dictionary behind an SM0 /
//! SM1 pair of given sizes, and hex vectors. (Also built as its own, empty, test target.)
#![allow(dead_code)]

use ecdrive_core::ec::AlState;
use ecdrive_sim::coe::{CoeConfig, CoeServer, OdStore, fixture};

/// A server, the fixture dictionary and the mailbox sizes.
pub struct Rig {
    pub server: CoeServer,
    pub od: OdStore,
    pub sm0: usize,
    pub sm1: usize,
    pub state: AlState,
}

impl Default for Rig {
    fn default() -> Self {
        Self::new()
    }
}

impl Rig {
    /// Default configuration (complete access and SDO info on), 128-byte mailboxes, PRE-OP.
    pub fn new() -> Self {
        Self::with(CoeConfig::default(), 128, 128)
    }

    /// Given configuration and mailbox sizes, PRE-OP.
    pub fn with(config: CoeConfig, sm0: usize, sm1: usize) -> Self {
        Self {
            server: CoeServer::new(config),
            od: OdStore::new(fixture::OBJECTS).expect("fixture dictionary is valid"),
            sm0,
            sm1,
            state: AlState::PreOp,
        }
    }

    /// The master writes `req` into SM0 (zero-padded to the SM0 length, as masters do); the
    /// reply mailbox, cut to its header length, or `None`.
    pub fn send(&mut self, req: &[u8]) -> Option<Vec<u8>> {
        assert!(req.len() <= self.sm0, "test request longer than SM0");
        let mut sm0 = vec![0u8; self.sm0];
        sm0[..req.len()].copy_from_slice(req);
        let mut sm1 = vec![0xAAu8; self.sm1];
        let n = self
            .server
            .handle(&sm0, self.state, &mut self.od, &mut sm1)?;
        assert!(n <= self.sm1);
        // The returned length is exactly the mailbox: header + length field.
        assert_eq!(n, 6 + u16::from_le_bytes([sm1[0], sm1[1]]) as usize);
        Some(sm1[..n].to_vec())
    }

    /// What the server posts when SM1 is free.
    pub fn poll(&mut self) -> Option<Vec<u8>> {
        let mut sm1 = vec![0xAAu8; self.sm1];
        let n = self.server.poll_unsolicited(&mut sm1)?;
        assert_eq!(n, 6 + u16::from_le_bytes([sm1[0], sm1[1]]) as usize);
        Some(sm1[..n].to_vec())
    }
}

/// Bytes from hex text, whitespace ignored: `"0A 00 13"`.
pub fn hex(s: &str) -> Vec<u8> {
    let digits: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    assert!(digits.len() % 2 == 0, "odd hex vector {s:?}");
    (0..digits.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&digits[i..i + 2], 16).expect("hex vector"))
        .collect()
}

/// A mailbox header for CoE with `len` data bytes and counter `cnt`.
pub fn coe_header(len: u16, cnt: u8) -> Vec<u8> {
    let l = len.to_le_bytes();
    vec![l[0], l[1], 0, 0, 0, 0x03 | (cnt << 4)]
}

/// The abort reply the server sends: service 2 (SDO request), command 0x80.
pub fn abort_reply(cnt: u8, index: u16, sub: u8, code: u32) -> Vec<u8> {
    let mut v = coe_header(10, cnt);
    v.extend_from_slice(&[0x00, 0x20, 0x80]);
    v.extend_from_slice(&index.to_le_bytes());
    v.push(sub);
    v.extend_from_slice(&code.to_le_bytes());
    v
}

/// An expedited upload request.
pub fn upload_req(cnt: u8, index: u16, sub: u8) -> Vec<u8> {
    let mut v = coe_header(10, cnt);
    v.extend_from_slice(&[0x00, 0x20, 0x40]);
    v.extend_from_slice(&index.to_le_bytes());
    v.extend_from_slice(&[sub, 0, 0, 0, 0]);
    v
}

/// An expedited download request of 1–4 bytes.
pub fn download_req(cnt: u8, index: u16, sub: u8, data: &[u8]) -> Vec<u8> {
    assert!((1..=4).contains(&data.len()));
    let mut v = coe_header(10, cnt);
    let cmd = 0x23 | (((4 - data.len()) as u8) << 2);
    v.extend_from_slice(&[0x00, 0x20, cmd]);
    v.extend_from_slice(&index.to_le_bytes());
    v.push(sub);
    let mut d = [0u8; 4];
    d[..data.len()].copy_from_slice(data);
    v.extend_from_slice(&d);
    v
}
