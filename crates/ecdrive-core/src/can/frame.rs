//! Classic CAN frames (11-bit identifiers, at most 8 data bytes) and the CANopen pre-defined
//! connection set (CiA 301 §7.3.5): which service a COB-ID belongs to.
//!
//! All three CANopen drives use the pre-defined set (BLV-R §3.3, ASDA-A2 §4.4 defaults, Lexium
//! Table 3.2): NMT 000h, SYNC 080h, EMCY 080h + node, TPDO1–4 180h/280h/380h/480h + node, RPDO1–4
//! 200h/300h/400h/500h + node, SDO 580h + node (server → client) and 600h + node (client →
//! server), error control (boot-up, heartbeat, guarding) 700h + node. Node-IDs are 1–127.

use core::fmt;

/// Largest 11-bit identifier.
pub const MAX_ID: u16 = 0x7FF;

/// A classic CAN data or remote frame with an 11-bit identifier.
///
/// Invariants (checked by the constructors): `id <= 0x7FF`, `len <= 8`; a remote frame carries
/// no data (its `len` is the requested DLC). Bytes beyond `len` are always zero, so equality
/// compares what is on the wire.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CanFrame {
    id: u16,
    rtr: bool,
    len: u8,
    data: [u8; 8],
}

/// A frame that cannot exist on a classic CAN bus with 11-bit identifiers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum FrameError {
    /// The identifier needs more than 11 bits.
    #[error("CAN identifier 0x{0:X} does not fit 11 bits (0x000–0x7FF)")]
    IdTooLarge(u32),
    /// More than 8 data bytes.
    #[error("{0} data bytes do not fit a classic CAN frame (at most 8)")]
    TooLong(usize),
    /// An extended (29-bit) identifier, which CANopen's pre-defined set does not use.
    #[error("extended (29-bit) identifier 0x{0:08X} is not supported")]
    Extended(u32),
    /// A CAN FD or error frame.
    #[error("not a classic CAN data or remote frame: {0}")]
    NotClassic(&'static str),
    /// A wire record of the wrong size.
    #[error("a CAN frame record must be {expected} bytes, got {got}")]
    BadRecord {
        /// Bytes a record has.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
}

impl CanFrame {
    /// A data frame. Errors if `id > 0x7FF` or `data` is longer than 8 bytes.
    pub fn new(id: u16, data: &[u8]) -> Result<Self, FrameError> {
        if id > MAX_ID {
            return Err(FrameError::IdTooLarge(u32::from(id)));
        }
        if data.len() > 8 {
            return Err(FrameError::TooLong(data.len()));
        }
        let mut d = [0u8; 8];
        if let Some(dst) = d.get_mut(..data.len()) {
            dst.copy_from_slice(data);
        }
        Ok(Self {
            id,
            rtr: false,
            len: data.len() as u8,
            data: d,
        })
    }

    /// A remote (RTR) frame requesting `dlc` bytes (used by node guarding and RTR-triggered
    /// TPDOs). Errors if `id > 0x7FF` or `dlc > 8`.
    pub fn remote(id: u16, dlc: u8) -> Result<Self, FrameError> {
        if id > MAX_ID {
            return Err(FrameError::IdTooLarge(u32::from(id)));
        }
        if dlc > 8 {
            return Err(FrameError::TooLong(usize::from(dlc)));
        }
        Ok(Self {
            id,
            rtr: true,
            len: dlc,
            data: [0; 8],
        })
    }

    /// A data frame from a fixed 8-byte buffer of which the first `len` bytes count; `id` and
    /// `len` are clamped to 0x7FF and 8. For builders that already hold valid values.
    pub const fn from_parts(id: u16, data: [u8; 8], len: u8) -> Self {
        let len = if len > 8 { 8 } else { len };
        let mut d = [0u8; 8];
        let mut i = 0;
        while i < len as usize {
            d[i] = data[i];
            i += 1;
        }
        Self {
            id: id & MAX_ID,
            rtr: false,
            len,
            data: d,
        }
    }

    /// The 11-bit identifier (COB-ID).
    pub const fn id(&self) -> u16 {
        self.id
    }

    /// Whether this is a remote (RTR) frame.
    pub const fn is_remote(&self) -> bool {
        self.rtr
    }

    /// The data length code: data bytes, or the requested length of a remote frame.
    pub const fn dlc(&self) -> u8 {
        self.len
    }

    /// The data bytes (empty for a remote frame).
    pub fn data(&self) -> &[u8] {
        if self.rtr {
            &[]
        } else {
            self.data.get(..usize::from(self.len)).unwrap_or(&[])
        }
    }

    /// The data as a zero-padded 8-byte array.
    pub const fn data8(&self) -> [u8; 8] {
        self.data
    }

    /// The service of the pre-defined connection set this identifier belongs to.
    pub const fn service(&self) -> Service {
        Service::classify(self.id)
    }

    /// Size of [`CanFrame::to_record`]: the Linux `struct can_frame` layout.
    pub const RECORD_LEN: usize = 16;

    /// The frame as a Linux `struct can_frame` (can_id with the RTR flag 0x4000_0000, little
    /// endian; len; three padding bytes; 8 data bytes). Used by the cross-process virtual bus.
    pub fn to_record(&self) -> [u8; 16] {
        let mut r = [0u8; 16];
        let mut id = u32::from(self.id);
        if self.rtr {
            id |= CAN_RTR_FLAG;
        }
        r[..4].copy_from_slice(&id.to_le_bytes());
        r[4] = self.len;
        r[8..].copy_from_slice(&self.data);
        r
    }

    /// Parse a record written by [`CanFrame::to_record`]. Rejects extended, error and
    /// oversized frames; bytes beyond the length are ignored (and zeroed).
    pub fn from_record(record: &[u8]) -> Result<Self, FrameError> {
        let r: &[u8; 16] = record.try_into().map_err(|_| FrameError::BadRecord {
            expected: Self::RECORD_LEN,
            got: record.len(),
        })?;
        let raw = u32::from_le_bytes([r[0], r[1], r[2], r[3]]);
        if raw & CAN_ERR_FLAG != 0 {
            return Err(FrameError::NotClassic("error frame"));
        }
        if raw & CAN_EFF_FLAG != 0 {
            return Err(FrameError::Extended(raw & 0x1FFF_FFFF));
        }
        let id_bits = raw & !CAN_RTR_FLAG;
        let id = u16::try_from(id_bits)
            .ok()
            .filter(|i| *i <= MAX_ID)
            .ok_or(FrameError::IdTooLarge(id_bits))?;
        let len = r[4];
        if raw & CAN_RTR_FLAG != 0 {
            return Self::remote(id, len);
        }
        let data = r[8..]
            .get(..usize::from(len))
            .ok_or(FrameError::TooLong(usize::from(len)))?;
        Self::new(id, data)
    }
}

/// `struct can_frame` flags (linux/can.h).
const CAN_EFF_FLAG: u32 = 0x8000_0000;
const CAN_RTR_FLAG: u32 = 0x4000_0000;
const CAN_ERR_FLAG: u32 = 0x2000_0000;

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl fmt::Display for CanFrame {
    /// candump style: `181#4000FF00` or `701#R1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:03X}#", self.id)?;
        if self.rtr {
            return write!(f, "R{}", self.len);
        }
        for b in self.data() {
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

/// The service a COB-ID stands for in the CiA 301 pre-defined connection set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Service {
    /// 000h: NMT node control.
    Nmt,
    /// 080h: SYNC.
    Sync,
    /// 080h + node: emergency.
    Emcy(u8),
    /// 100h: time stamp.
    Time,
    /// 180h/280h/380h/480h + node: TPDO 1–4 (drive → master).
    Tpdo {
        /// PDO number 1–4.
        pdo: u8,
        /// Node-ID.
        node: u8,
    },
    /// 200h/300h/400h/500h + node: RPDO 1–4 (master → drive).
    Rpdo {
        /// PDO number 1–4.
        pdo: u8,
        /// Node-ID.
        node: u8,
    },
    /// 580h + node: SDO server → client (response).
    SdoTx(u8),
    /// 600h + node: SDO client → server (request).
    SdoRx(u8),
    /// 700h + node: NMT error control (boot-up, heartbeat, node guarding).
    ErrorControl(u8),
    /// 7E4h: LSS slave → master.
    LssResponse,
    /// 7E5h: LSS master → slave.
    LssRequest,
    /// Any identifier outside the pre-defined set (or node-ID 0 where one is needed).
    Other(u16),
}

impl Service {
    /// Classify an identifier by the pre-defined connection set.
    pub const fn classify(id: u16) -> Service {
        let function = id >> 7;
        let node = (id & 0x7F) as u8;
        match (function, node) {
            (0, 0) => Service::Nmt,
            (1, 0) => Service::Sync,
            (1, n) => Service::Emcy(n),
            (2, 0) => Service::Time,
            (3, n) if n != 0 => Service::Tpdo { pdo: 1, node: n },
            (4, n) if n != 0 => Service::Rpdo { pdo: 1, node: n },
            (5, n) if n != 0 => Service::Tpdo { pdo: 2, node: n },
            (6, n) if n != 0 => Service::Rpdo { pdo: 2, node: n },
            (7, n) if n != 0 => Service::Tpdo { pdo: 3, node: n },
            (8, n) if n != 0 => Service::Rpdo { pdo: 3, node: n },
            (9, n) if n != 0 => Service::Tpdo { pdo: 4, node: n },
            (10, n) if n != 0 => Service::Rpdo { pdo: 4, node: n },
            (11, n) if n != 0 => Service::SdoTx(n),
            (12, n) if n != 0 => Service::SdoRx(n),
            (14, n) if n != 0 => Service::ErrorControl(n),
            _ if id == 0x7E4 => Service::LssResponse,
            _ if id == 0x7E5 => Service::LssRequest,
            _ => Service::Other(id),
        }
    }
}

/// COB-IDs of the pre-defined connection set.
pub mod cob {
    /// NMT.
    pub const NMT: u16 = 0x000;
    /// SYNC.
    pub const SYNC: u16 = 0x080;
    /// Time stamp.
    pub const TIME: u16 = 0x100;

    /// EMCY of `node`.
    pub const fn emcy(node: u8) -> u16 {
        0x080 + (node as u16 & 0x7F)
    }

    /// TPDO `pdo` (1–4) of `node`: 180h/280h/380h/480h + node. Numbers outside 1–4 give 0.
    pub const fn tpdo(pdo: u8, node: u8) -> u16 {
        match pdo {
            1..=4 => 0x080 + 0x100 * pdo as u16 + (node as u16 & 0x7F),
            _ => 0,
        }
    }

    /// RPDO `pdo` (1–4) of `node`: 200h/300h/400h/500h + node. Numbers outside 1–4 give 0.
    pub const fn rpdo(pdo: u8, node: u8) -> u16 {
        match pdo {
            1..=4 => 0x100 + 0x100 * pdo as u16 + (node as u16 & 0x7F),
            _ => 0,
        }
    }

    /// SDO server → client (response) of `node`.
    pub const fn sdo_tx(node: u8) -> u16 {
        0x580 + (node as u16 & 0x7F)
    }

    /// SDO client → server (request) of `node`.
    pub const fn sdo_rx(node: u8) -> u16 {
        0x600 + (node as u16 & 0x7F)
    }

    /// NMT error control (boot-up, heartbeat, guarding) of `node`.
    pub const fn error_control(node: u8) -> u16 {
        0x700 + (node as u16 & 0x7F)
    }
}

/// A valid CANopen node-ID, 1–127.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(u8);

/// A node-ID outside 1–127.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
#[error("node-ID {0} is outside 1–127")]
pub struct BadNodeId(pub u8);

impl NodeId {
    /// A node-ID, if `id` is 1–127.
    pub const fn new(id: u8) -> Result<Self, BadNodeId> {
        if id >= 1 && id <= 127 {
            Ok(Self(id))
        } else {
            Err(BadNodeId(id))
        }
    }

    /// The raw value.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// Every valid node-ID, 1–127.
    pub fn all() -> impl Iterator<Item = NodeId> {
        (1u8..=127).map(NodeId)
    }
}

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "node {} (0x{:02X})", self.0, self.0)
    }
}

impl TryFrom<u8> for NodeId {
    type Error = BadNodeId;
    fn try_from(v: u8) -> Result<Self, BadNodeId> {
        Self::new(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constructors_check_limits() {
        assert!(CanFrame::new(0x800, &[]).is_err());
        assert!(CanFrame::new(0x7FF, &[0; 9]).is_err());
        let f = CanFrame::new(0x181, &[1, 2, 3]).unwrap();
        assert_eq!(f.data(), &[1, 2, 3]);
        assert_eq!(f.data8(), [1, 2, 3, 0, 0, 0, 0, 0]);
        assert_eq!(f.to_string(), "181#010203");
        let r = CanFrame::remote(0x705, 1).unwrap();
        assert!(r.is_remote());
        assert!(r.data().is_empty());
        assert_eq!(r.to_string(), "705#R1");
    }

    #[test]
    fn records_round_trip() {
        for f in [
            CanFrame::new(0x000, &[1, 5]).unwrap(),
            CanFrame::new(0x7FF, &[0xFF; 8]).unwrap(),
            CanFrame::remote(0x703, 1).unwrap(),
            CanFrame::new(0x080, &[]).unwrap(),
        ] {
            assert_eq!(CanFrame::from_record(&f.to_record()).unwrap(), f);
        }
        let mut bad = CanFrame::new(1, &[]).unwrap().to_record();
        bad[4] = 9;
        assert!(CanFrame::from_record(&bad).is_err());
        bad[4] = 0;
        bad[3] = 0x80;
        assert_eq!(
            CanFrame::from_record(&bad),
            Err(FrameError::Extended(0x0000_0001))
        );
        assert!(CanFrame::from_record(&[0; 15]).is_err());
    }

    #[test]
    fn predefined_connection_set() {
        assert_eq!(Service::classify(0x000), Service::Nmt);
        assert_eq!(Service::classify(0x080), Service::Sync);
        assert_eq!(Service::classify(0x085), Service::Emcy(5));
        assert_eq!(
            Service::classify(0x1A0),
            Service::Tpdo { pdo: 1, node: 0x20 }
        );
        assert_eq!(
            Service::classify(0x4C1),
            Service::Tpdo { pdo: 4, node: 0x41 }
        );
        assert_eq!(
            Service::classify(0x57F),
            Service::Rpdo { pdo: 4, node: 0x7F }
        );
        assert_eq!(Service::classify(0x5FF), Service::SdoTx(0x7F));
        assert_eq!(Service::classify(0x641), Service::SdoRx(0x41));
        assert_eq!(Service::classify(0x701), Service::ErrorControl(1));
        assert_eq!(Service::classify(0x700), Service::Other(0x700));
        assert_eq!(Service::classify(0x7E5), Service::LssRequest);
        for n in 1..=127u8 {
            for p in 1..=4u8 {
                assert_eq!(
                    Service::classify(cob::tpdo(p, n)),
                    Service::Tpdo { pdo: p, node: n }
                );
                assert_eq!(
                    Service::classify(cob::rpdo(p, n)),
                    Service::Rpdo { pdo: p, node: n }
                );
            }
            assert_eq!(Service::classify(cob::sdo_rx(n)), Service::SdoRx(n));
            assert_eq!(Service::classify(cob::emcy(n)), Service::Emcy(n));
        }
        assert!(NodeId::new(0).is_err());
        assert!(NodeId::new(128).is_err());
        assert_eq!(NodeId::all().count(), 127);
    }
}
