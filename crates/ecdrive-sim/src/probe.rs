//! A minimal master-side helper that sends single datagrams (or a few in one frame) through a
//! [`Segment`] and decodes the replies. For tests, fuzzers, benchmarks and tools; it allocates
//! per call and is not meant for a cyclic path.

use super::segment::{Segment, SegmentError};
use crate::ec::Command;
use crate::ec::frame::{
    EthercatFrame, EthernetFrame, FrameBuilder, MAX_FRAME_LEN, MacAddress, physical_address,
};

/// The source MAC the probe sends from (ethercrab's).
pub const PROBE_MAC: MacAddress = MacAddress([0x10; 6]);

/// One datagram to send.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// Command.
    pub command: Command,
    /// Address field: `ADP | ADO << 16` or a logical address.
    pub address: u32,
    /// Data.
    pub data: Vec<u8>,
}

impl Request {
    /// A physical or broadcast datagram.
    pub fn physical(command: Command, adp: u16, ado: u16, data: &[u8]) -> Self {
        Self {
            command,
            address: physical_address(adp, ado),
            data: data.to_vec(),
        }
    }

    /// A logical datagram.
    pub fn logical(command: Command, address: u32, data: &[u8]) -> Self {
        Self {
            command,
            address,
            data: data.to_vec(),
        }
    }
}

/// A returned datagram.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    /// ADP as returned (auto-increment and broadcast commands count the slaves).
    pub adp: u16,
    /// Data as returned.
    pub data: Vec<u8>,
    /// Working counter.
    pub wkc: u16,
}

/// Why a probe request failed.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    /// The segment dropped the frame.
    #[error(transparent)]
    Segment(#[from] SegmentError),
    /// The request did not fit a frame.
    #[error(transparent)]
    Frame(#[from] crate::ec::frame::FrameError),
    /// The reply did not match the request.
    #[error("reply mismatch: {0}")]
    Mismatch(&'static str),
}

/// Sends datagrams through a segment.
#[derive(Debug)]
pub struct Probe {
    /// The segment under test.
    pub segment: Segment,
    buf: Vec<u8>,
    index: u8,
}

impl Probe {
    /// A probe on `segment`.
    pub fn new(segment: Segment) -> Self {
        Self {
            segment,
            buf: vec![0; MAX_FRAME_LEN],
            index: 0,
        }
    }

    /// Send several datagrams in one frame.
    pub fn frame(&mut self, requests: &[Request]) -> Result<Vec<Reply>, ProbeError> {
        let mut b = FrameBuilder::new(&mut self.buf, PROBE_MAC)?;
        for r in requests {
            self.index = self.index.wrapping_add(1);
            b.push(r.command, self.index, r.address, &r.data)?;
        }
        let len = b.finish();
        let frame = self
            .buf
            .get_mut(..len)
            .ok_or(ProbeError::Mismatch("frame length"))?;
        let n = self.segment.process(frame)?;
        let frame = self
            .buf
            .get(..n)
            .ok_or(ProbeError::Mismatch("reply length"))?;
        let eth = EthernetFrame::new_checked(frame)?;
        if eth.src() != PROBE_MAC.with_local_bit() {
            return Err(ProbeError::Mismatch("source MAC without U/L bit"));
        }
        let ec = EthercatFrame::new_checked(eth.payload())?;
        let mut out = Vec::with_capacity(requests.len());
        for (d, r) in ec.datagrams().zip(requests) {
            let d = d?;
            if d.command() != Some(r.command) {
                return Err(ProbeError::Mismatch("command changed"));
            }
            out.push(Reply {
                adp: d.adp(),
                data: d.data().to_vec(),
                wkc: d.wkc(),
            });
        }
        if out.len() != requests.len() {
            return Err(ProbeError::Mismatch("datagram count"));
        }
        Ok(out)
    }

    /// Send one datagram.
    pub fn send(&mut self, request: Request) -> Result<Reply, ProbeError> {
        self.frame(core::slice::from_ref(&request))?
            .pop()
            .ok_or(ProbeError::Mismatch("no datagram"))
    }

    /// A physical/broadcast datagram.
    pub fn physical(
        &mut self,
        command: Command,
        adp: u16,
        ado: u16,
        data: &[u8],
    ) -> Result<Reply, ProbeError> {
        self.send(Request::physical(command, adp, ado, data))
    }

    /// FPRD of `len` bytes.
    pub fn fprd(&mut self, station: u16, ado: u16, len: usize) -> Result<Reply, ProbeError> {
        self.physical(Command::Fprd, station, ado, &vec![0; len])
    }

    /// FPWR.
    pub fn fpwr(&mut self, station: u16, ado: u16, data: &[u8]) -> Result<Reply, ProbeError> {
        self.physical(Command::Fpwr, station, ado, data)
    }

    /// APRD of `len` bytes at position `pos` (0-based).
    pub fn aprd(&mut self, pos: u16, ado: u16, len: usize) -> Result<Reply, ProbeError> {
        self.physical(Command::Aprd, 0u16.wrapping_sub(pos), ado, &vec![0; len])
    }

    /// APWR at position `pos` (0-based).
    pub fn apwr(&mut self, pos: u16, ado: u16, data: &[u8]) -> Result<Reply, ProbeError> {
        self.physical(Command::Apwr, 0u16.wrapping_sub(pos), ado, data)
    }

    /// BRD of `len` bytes.
    pub fn brd(&mut self, ado: u16, len: usize) -> Result<Reply, ProbeError> {
        self.physical(Command::Brd, 0, ado, &vec![0; len])
    }

    /// BWR.
    pub fn bwr(&mut self, ado: u16, data: &[u8]) -> Result<Reply, ProbeError> {
        self.physical(Command::Bwr, 0, ado, data)
    }

    /// A logical datagram.
    pub fn logical(
        &mut self,
        command: Command,
        address: u32,
        data: &[u8],
    ) -> Result<Reply, ProbeError> {
        self.send(Request::logical(command, address, data))
    }

    /// Read a u16 register with FPRD.
    pub fn read_u16(&mut self, station: u16, ado: u16) -> Result<(u16, u16), ProbeError> {
        let r = self.fprd(station, ado, 2)?;
        let v = r
            .data
            .get(0..2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .unwrap_or(0);
        Ok((v, r.wkc))
    }

    /// Assign station addresses `base + position` to every slave (APWR 0x0010), as masters do.
    pub fn assign_addresses(&mut self, base: u16) -> Result<(), ProbeError> {
        for i in 0..self.segment.len() {
            let i = i as u16;
            self.apwr(i, 0x0010, &base.wrapping_add(i).to_le_bytes())?;
        }
        Ok(())
    }

    /// Request an AL state on one slave (FPWR 0x0120) and return the AL status and code read
    /// back.
    pub fn request_state(&mut self, station: u16, control: u16) -> Result<(u16, u16), ProbeError> {
        self.fpwr(station, 0x0120, &control.to_le_bytes())?;
        let r = self.fprd(station, 0x0130, 6)?;
        let g = |i: usize| {
            r.data
                .get(i..i + 2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .unwrap_or(0)
        };
        Ok((g(0), g(4)))
    }
}
