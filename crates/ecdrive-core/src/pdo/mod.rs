//! PDO mapping model, process-image layout, limits, and the remap SDO sequence.
//!
//! A [`Mapping`] says which PDOs are assigned to the output SyncManager (SM2, object 0x1C12,
//! RxPDOs, master → drive) and the input SyncManager (SM3, 0x1C13, TxPDOs, drive → master), and
//! which object entries each PDO carries. The same type holds a drive's static default mapping
//! (borrowed) and a user's mapping read from a configuration file (owned).
//!
//! Around the model:
//! - [`layout`]: where every mapped entry sits in the output and input images (bit-packed, as
//!   EtherCAT does), and resolution of object addresses to [`Field`] handles at start-up;
//! - [`image`]: allocation-free, panic-free typed reads and writes of a [`Field`] in a process
//!   image — what the cyclic loop uses every cycle;
//! - [`limits`]: what a drive accepts ([`PdoLimits`]) and [`validate`], whose errors name the
//!   limit and the offending PDO or entry;
//! - [`remap`]: the SDO download sequence that installs a mapping in PRE-OP, and the read-back
//!   that rebuilds a [`Mapping`] from a drive's 0x1C12/0x1C13 and 0x16xx/0x1Axx.

pub mod axis;
pub mod image;
pub mod layout;
pub mod limits;
pub mod remap;

pub use axis::AxisBinding;
pub use image::{Field, FieldValue, ImageError, ImageView};
pub use layout::{FieldError, ImageLayout, Layout, MappedEntry};
pub use limits::{
    DirectionLimits, MappingError, PdoLimits, PdoRange, RequiredObjects, validate, validate_all,
};
pub use remap::{
    ReadbackError, RemapError, RemapOptions, SdoWrite, read_mapping, read_mapping_sync,
    remap_sequence,
};

use crate::od::ObjectAddress;
use core::fmt;
use std::borrow::Cow;

/// One mapped object entry: index, sub-index and size in bits. Index 0 is padding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PdoEntry {
    /// Object index (0 for a padding gap).
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Size in bits.
    pub bits: u8,
}

impl PdoEntry {
    /// An entry.
    pub const fn new(index: u16, sub: u8, bits: u8) -> Self {
        Self { index, sub, bits }
    }

    /// A padding gap of `bits` bits.
    pub const fn padding(bits: u8) -> Self {
        Self {
            index: 0,
            sub: 0,
            bits,
        }
    }

    /// Decode a mapping-entry value as stored in 0x16xx/0x1Axx (`index << 16 | sub << 8 | bits`).
    pub const fn from_u32(v: u32) -> Self {
        Self {
            index: (v >> 16) as u16,
            sub: (v >> 8) as u8,
            bits: v as u8,
        }
    }

    /// Encode as a mapping-entry value (`index << 16 | sub << 8 | bits`).
    pub const fn to_u32(self) -> u32 {
        (self.index as u32) << 16 | (self.sub as u32) << 8 | self.bits as u32
    }

    /// Whether this entry is a padding gap.
    pub const fn is_padding(self) -> bool {
        self.index == 0
    }

    /// The mapped object's address.
    pub const fn address(self) -> ObjectAddress {
        ObjectAddress::new(self.index, self.sub)
    }
}

/// Which way a PDO travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// RxPDO: master → drive (outputs, SM2, assigned in 0x1C12, mapped in 0x16xx).
    Rx,
    /// TxPDO: drive → master (inputs, SM3, assigned in 0x1C13, mapped in 0x1Axx).
    Tx,
}

impl Direction {
    /// The assignment object: 0x1C12 for Rx, 0x1C13 for Tx.
    pub const fn assign_index(self) -> u16 {
        match self {
            Self::Rx => 0x1C12,
            Self::Tx => 0x1C13,
        }
    }

    /// The process-data SyncManager: 2 for Rx, 3 for Tx.
    pub const fn sync_manager(self) -> u8 {
        match self {
            Self::Rx => 2,
            Self::Tx => 3,
        }
    }

    /// `"RxPDO"` or `"TxPDO"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Rx => "RxPDO",
            Self::Tx => "TxPDO",
        }
    }

    /// `"an RxPDO"` or `"a TxPDO"`, for messages.
    pub const fn with_article(self) -> &'static str {
        match self {
            Self::Rx => "an RxPDO",
            Self::Tx => "a TxPDO",
        }
    }

    /// Both directions, Rx first (the order of the remap sequence and of the images).
    pub const ALL: [Direction; 2] = [Self::Rx, Self::Tx];

    /// The index range of this direction's mapping objects (CiA 301 / ETG.1000.6):
    /// 0x1600–0x17FF for Rx, 0x1A00–0x1BFF for Tx.
    pub const fn mapping_range(self) -> (u16, u16) {
        match self {
            Self::Rx => (0x1600, 0x17FF),
            Self::Tx => (0x1A00, 0x1BFF),
        }
    }

    /// The direction a mapping-object index belongs to, or `None` outside both ranges.
    pub const fn of_pdo_index(index: u16) -> Option<Self> {
        match index {
            0x1600..=0x17FF => Some(Self::Rx),
            0x1A00..=0x1BFF => Some(Self::Tx),
            _ => None,
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One PDO: its mapping object index (0x16xx or 0x1Axx) and its entries in order.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Pdo {
    /// Mapping object index.
    pub index: u16,
    /// Mapped entries, in order.
    pub entries: Cow<'static, [PdoEntry]>,
}

impl Pdo {
    /// A PDO from static data.
    pub const fn fixed(index: u16, entries: &'static [PdoEntry]) -> Self {
        Self {
            index,
            entries: Cow::Borrowed(entries),
        }
    }

    /// A PDO from runtime data.
    pub fn owned(index: u16, entries: Vec<PdoEntry>) -> Self {
        Self {
            index,
            entries: Cow::Owned(entries),
        }
    }

    /// Total size in bits.
    pub fn bits(&self) -> u32 {
        self.entries
            .iter()
            .fold(0u32, |acc, e| acc.saturating_add(u32::from(e.bits)))
    }

    /// Number of entries (padding included), i.e. the value of the mapping object's sub-index 0.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the PDO maps nothing.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The direction its index belongs to (0x16xx Rx, 0x1Axx Tx), or `None` for an index outside
    /// both ranges.
    pub const fn direction(&self) -> Option<Direction> {
        Direction::of_pdo_index(self.index)
    }
}

/// The PDO assignment of both process-data SyncManagers.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Mapping {
    /// RxPDOs assigned to SM2 (0x1C12), in order.
    pub rx: Cow<'static, [Pdo]>,
    /// TxPDOs assigned to SM3 (0x1C13), in order.
    pub tx: Cow<'static, [Pdo]>,
}

impl Mapping {
    /// A mapping from static data.
    pub const fn fixed(rx: &'static [Pdo], tx: &'static [Pdo]) -> Self {
        Self {
            rx: Cow::Borrowed(rx),
            tx: Cow::Borrowed(tx),
        }
    }

    /// A mapping from runtime data.
    pub fn owned(rx: Vec<Pdo>, tx: Vec<Pdo>) -> Self {
        Self {
            rx: Cow::Owned(rx),
            tx: Cow::Owned(tx),
        }
    }

    /// The PDOs of one direction.
    pub fn pdos(&self, dir: Direction) -> &[Pdo] {
        match dir {
            Direction::Rx => &self.rx,
            Direction::Tx => &self.tx,
        }
    }

    /// Total size in bits of one direction.
    pub fn bits(&self, dir: Direction) -> u32 {
        self.pdos(dir)
            .iter()
            .fold(0u32, |acc, p| acc.saturating_add(p.bits()))
    }

    /// Size in bytes of one direction's SyncManager (bits rounded up).
    pub fn bytes(&self, dir: Direction) -> usize {
        (self.bits(dir) as usize).div_ceil(8)
    }

    /// Number of entries (padding included) of one direction.
    pub fn entry_count(&self, dir: Direction) -> usize {
        self.pdos(dir).iter().map(Pdo::len).sum()
    }

    /// The assigned PDO with mapping index `index`, in either direction.
    pub fn pdo(&self, index: u16) -> Option<&Pdo> {
        self.rx
            .iter()
            .chain(self.tx.iter())
            .find(|p| p.index == index)
    }

    /// Whether `addr` is mapped in `dir`.
    pub fn contains(&self, dir: Direction, addr: ObjectAddress) -> bool {
        self.pdos(dir)
            .iter()
            .flat_map(|p| p.entries.iter())
            .any(|e| !e.is_padding() && e.address() == addr)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_u32_round_trip() {
        let e = PdoEntry::new(0x6040, 0, 16);
        assert_eq!(e.to_u32(), 0x6040_0010);
        assert_eq!(
            PdoEntry::from_u32(0x607A_0020),
            PdoEntry::new(0x607A, 0, 32)
        );
    }

    #[test]
    fn directions_of_mapping_indices() {
        assert_eq!(Direction::of_pdo_index(0x1600), Some(Direction::Rx));
        assert_eq!(Direction::of_pdo_index(0x17FF), Some(Direction::Rx));
        assert_eq!(Direction::of_pdo_index(0x1800), None);
        assert_eq!(Direction::of_pdo_index(0x1A00), Some(Direction::Tx));
        assert_eq!(Direction::of_pdo_index(0x1BFF), Some(Direction::Tx));
        assert_eq!(Direction::of_pdo_index(0x1C12), None);
        assert_eq!(Direction::Tx.to_string(), "TxPDO");
    }

    #[test]
    fn mapping_sizes() {
        static RX: &[Pdo] = &[Pdo::fixed(
            0x1600,
            &[PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)],
        )];
        static TX: &[Pdo] = &[Pdo::fixed(
            0x1A00,
            &[PdoEntry::new(0x6041, 0, 16), PdoEntry::padding(4)],
        )];
        let m = Mapping::fixed(RX, TX);
        assert_eq!(m.bytes(Direction::Rx), 6);
        assert_eq!(m.bits(Direction::Tx), 20);
        assert_eq!(m.bytes(Direction::Tx), 3);
        assert!(m.contains(Direction::Rx, ObjectAddress::new(0x607A, 0)));
        assert!(!m.contains(Direction::Tx, ObjectAddress::new(0, 0)));
    }
}
