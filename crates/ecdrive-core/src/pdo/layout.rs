//! Where each mapped entry sits in the process images.
//!
//! The output image (SM2) is the concatenation of the RxPDOs in 0x1C12 order, each PDO's entries
//! in mapping order, padding included; the input image (SM3) is the same for the TxPDOs in 0x1C13
//! order. Entries are bit-packed with no implicit alignment, and a SyncManager's length is its
//! bit count rounded up to whole bytes — exactly what the drive and ethercrab compute.
//!
//! A [`Layout`] is built once (it allocates); the cycle then uses [`Field`] handles resolved from
//! it.

use super::image::{Field, ImageError};
use super::{Direction, Mapping, PdoEntry};
use crate::od::{DataType, Dictionary, ObjectAddress};
use core::ops::Range;

/// One entry of a process image, with its position.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MappedEntry {
    /// The PDO (mapping object index) carrying it.
    pub pdo: u16,
    /// Its sub-index in that mapping object (1-based).
    pub sub: u8,
    /// What is mapped.
    pub entry: PdoEntry,
    /// Position of its least significant bit in the image, from bit 0 of byte 0.
    pub bit_position: usize,
}

impl MappedEntry {
    /// Byte of the image holding the entry's first bit.
    pub const fn byte_offset(&self) -> usize {
        self.bit_position / 8
    }

    /// Bit (0–7) within [`MappedEntry::byte_offset`] of the entry's first bit.
    pub const fn bit_offset(&self) -> u8 {
        (self.bit_position % 8) as u8
    }

    /// Size in bits.
    pub const fn bits(&self) -> u8 {
        self.entry.bits
    }

    /// Whether this is a padding gap.
    pub const fn is_padding(&self) -> bool {
        self.entry.is_padding()
    }

    /// The mapped object's address.
    pub const fn address(&self) -> ObjectAddress {
        self.entry.address()
    }

    /// The bits it occupies in the image.
    pub const fn bit_range(&self) -> Range<usize> {
        self.bit_position..self.bit_position.saturating_add(self.entry.bits as usize)
    }

    /// A field handle for it. Entries of 0 or more than 64 bits have none.
    pub const fn field(&self, signed: bool) -> Result<Field, ImageError> {
        Field::new(self.bit_position, self.entry.bits, signed)
    }
}

/// The layout of one direction's image (outputs for Rx, inputs for Tx).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ImageLayout {
    entries: Vec<MappedEntry>,
    bits: usize,
}

impl ImageLayout {
    fn build(pdos: &[super::Pdo]) -> Self {
        let mut entries = Vec::with_capacity(pdos.iter().map(|p| p.len()).sum());
        let mut pos: usize = 0;
        for pdo in pdos {
            for (i, e) in pdo.entries.iter().enumerate() {
                entries.push(MappedEntry {
                    pdo: pdo.index,
                    // Sub-indices beyond 255 cannot exist on a drive; validation reports such a
                    // PDO, the layout just saturates.
                    sub: u8::try_from(i + 1).unwrap_or(u8::MAX),
                    entry: *e,
                    bit_position: pos,
                });
                pos = pos.saturating_add(usize::from(e.bits));
            }
        }
        Self { entries, bits: pos }
    }

    /// Every entry in image order, padding included.
    pub fn entries(&self) -> &[MappedEntry] {
        &self.entries
    }

    /// Iterate over the entries in image order.
    pub fn iter(&self) -> core::slice::Iter<'_, MappedEntry> {
        self.entries.iter()
    }

    /// Number of entries, padding included.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the image maps nothing.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Total size in bits.
    pub fn bits(&self) -> usize {
        self.bits
    }

    /// Size in bytes: the SyncManager length (bits rounded up).
    pub fn bytes(&self) -> usize {
        self.bits.div_ceil(8)
    }

    /// The first occurrence of `addr` (padding never matches).
    pub fn find(&self, addr: ObjectAddress) -> Option<&MappedEntry> {
        self.entries
            .iter()
            .find(|e| !e.is_padding() && e.address() == addr)
    }

    /// The bits one PDO occupies (its first occurrence, if assigned twice).
    pub fn pdo_bits(&self, pdo: u16) -> Option<Range<usize>> {
        let mut it = self.entries.iter().filter(|e| e.pdo == pdo);
        let first = it.next()?;
        let mut end = first.bit_range().end;
        for e in it {
            if e.bit_position != end {
                break;
            }
            end = e.bit_range().end;
        }
        Some(first.bit_position..end)
    }
}

impl<'a> IntoIterator for &'a ImageLayout {
    type Item = &'a MappedEntry;
    type IntoIter = core::slice::Iter<'a, MappedEntry>;

    fn into_iter(self) -> Self::IntoIter {
        self.entries.iter()
    }
}

/// The layout of both process images of one drive.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Layout {
    rx: ImageLayout,
    tx: ImageLayout,
}

impl Layout {
    /// Lay out `mapping`. Never fails: a mapping the drive would refuse (see
    /// [`validate`](super::validate)) is still laid out as written.
    pub fn new(mapping: &Mapping) -> Self {
        Self {
            rx: ImageLayout::build(&mapping.rx),
            tx: ImageLayout::build(&mapping.tx),
        }
    }

    /// The output image (RxPDOs, SM2).
    pub fn rx(&self) -> &ImageLayout {
        &self.rx
    }

    /// The input image (TxPDOs, SM3).
    pub fn tx(&self) -> &ImageLayout {
        &self.tx
    }

    /// One direction's image.
    pub fn image(&self, dir: Direction) -> &ImageLayout {
        match dir {
            Direction::Rx => &self.rx,
            Direction::Tx => &self.tx,
        }
    }

    /// Size in bytes of one direction's image.
    pub fn bytes(&self, dir: Direction) -> usize {
        self.image(dir).bytes()
    }

    /// The first occurrence of `addr` in `dir`.
    pub fn find(&self, dir: Direction, addr: ObjectAddress) -> Option<&MappedEntry> {
        self.image(dir).find(addr)
    }

    /// Resolve `addr` to a field for an object of type `data_type`: the signedness comes from
    /// the type, and the mapped length must equal the type's (a 32-bit object mapped with 16
    /// bits is an error here, not a silent truncation every cycle). `REAL32`/`REAL64` resolve to
    /// unsigned fields for [`Field::read_f32`] and friends.
    pub fn field(
        &self,
        dir: Direction,
        addr: ObjectAddress,
        data_type: DataType,
    ) -> Result<Field, FieldError> {
        let e = self
            .find(dir, addr)
            .ok_or(FieldError::NotMapped { dir, addr })?;
        let unsupported = FieldError::Unsupported {
            dir,
            addr,
            bits: e.bits(),
            data_type: Some(data_type),
        };
        let type_bits = data_type.bit_len().ok_or(unsupported)?;
        if type_bits != u16::from(e.bits()) {
            return Err(FieldError::LengthMismatch {
                dir,
                addr,
                pdo: e.pdo,
                mapped: e.bits(),
                data_type,
            });
        }
        e.field(data_type.is_signed()).map_err(|_| unsupported)
    }

    /// [`Layout::field`] with the type taken from the drive's dictionary.
    pub fn resolve(
        &self,
        dir: Direction,
        addr: ObjectAddress,
        dictionary: &Dictionary<'_>,
    ) -> Result<Field, FieldError> {
        let data_type = dictionary
            .data_type(addr)
            .ok_or(FieldError::NotInDictionary { addr })?;
        self.field(dir, addr, data_type)
    }

    /// Resolve `addr` to a field of whatever length it is mapped with, for raw access.
    pub fn raw_field(
        &self,
        dir: Direction,
        addr: ObjectAddress,
        signed: bool,
    ) -> Result<Field, FieldError> {
        let e = self
            .find(dir, addr)
            .ok_or(FieldError::NotMapped { dir, addr })?;
        e.field(signed).map_err(|_| FieldError::Unsupported {
            dir,
            addr,
            bits: e.bits(),
            data_type: None,
        })
    }
}

/// Why an object address could not be resolved to a [`Field`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FieldError {
    /// The object is not in this direction's image.
    #[error("{addr} is not mapped in any {dir}")]
    NotMapped {
        /// Direction searched.
        dir: Direction,
        /// The object.
        addr: ObjectAddress,
    },
    /// The object is not in the dictionary used to resolve it.
    #[error("{addr} is not in the drive's dictionary, so its type is unknown")]
    NotInDictionary {
        /// The object.
        addr: ObjectAddress,
    },
    /// Mapped with a length other than its type's.
    #[error(
        "{addr} is mapped with {mapped} bits in {dir} 0x{pdo:04X}, but its type {data_type} has {} bits",
        data_type.bit_len().unwrap_or(0)
    )]
    LengthMismatch {
        /// Direction.
        dir: Direction,
        /// The object.
        addr: ObjectAddress,
        /// The PDO mapping it.
        pdo: u16,
        /// Mapped length.
        mapped: u8,
        /// The type it was resolved as.
        data_type: DataType,
    },
    /// Not accessible as a 1–64-bit field (a string, a domain, or a zero-length entry).
    #[error("{addr} ({bits} bits in the {dir} image{}) cannot be accessed as a 1–64-bit field",
        match data_type { Some(t) => format!(", type {t}"), None => String::new() })]
    Unsupported {
        /// Direction.
        dir: Direction,
        /// The object.
        addr: ObjectAddress,
        /// Mapped length.
        bits: u8,
        /// The type asked for, if any.
        data_type: Option<DataType>,
    },
}
