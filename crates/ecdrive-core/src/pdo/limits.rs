//! What a drive accepts as a PDO mapping, and validation of a [`Mapping`] against it.
//!
//! Each drive profile declares a `const` [`PdoLimits`]: which mapping objects exist per
//! direction and how many entries each holds, how many PDOs may be assigned per SyncManager, and
//! the entry and byte budget per direction. [`validate`] checks a mapping against them (and,
//! given the drive's dictionary, checks every mapped object) before anything is written to the
//! drive, so a bad configuration fails with a message that names the limit and the offending PDO
//! or entry instead of an SDO abort halfway through a remap.

use super::{Direction, Mapping, PdoEntry};
use crate::od::{Dictionary, EntryAccess, ObjectAddress, ObjectDesc};
use core::fmt;

/// A run of mapping objects that share their rules, e.g. 0x1601–0x1603 with at most 2 entries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PdoRange {
    /// First mapping-object index.
    pub first: u16,
    /// Last mapping-object index (inclusive).
    pub last: u16,
    /// Most entries (sub-index 0 value) one of these PDOs may hold.
    pub max_entries: u8,
    /// Whether the master may rewrite the mapping (`false`: fixed, only assignable).
    pub mapping_writable: bool,
}

impl PdoRange {
    /// Writable mapping objects `first..=last` of at most `max_entries` entries.
    pub const fn new(first: u16, last: u16, max_entries: u8) -> Self {
        Self {
            first,
            last,
            max_entries,
            mapping_writable: true,
        }
    }

    /// One writable mapping object.
    pub const fn single(index: u16, max_entries: u8) -> Self {
        Self::new(index, index, max_entries)
    }

    /// The same range with a fixed (read-only) mapping.
    pub const fn fixed(self) -> Self {
        Self {
            mapping_writable: false,
            ..self
        }
    }

    /// Whether `index` is in the range.
    pub const fn contains(&self, index: u16) -> bool {
        self.first <= index && index <= self.last
    }

    /// The indices of the range.
    pub fn indices(&self) -> impl Iterator<Item = u16> + use<> {
        self.first..=self.last
    }
}

impl fmt::Display for PdoRange {
    /// `0x1600` or `0x1601–0x1603`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.first == self.last {
            write!(f, "0x{:04X}", self.first)
        } else {
            write!(f, "0x{:04X}–0x{:04X}", self.first, self.last)
        }
    }
}

/// The limits of one direction (one process-data SyncManager).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DirectionLimits {
    /// The mapping objects this direction has.
    pub pdos: &'static [PdoRange],
    /// Most PDOs assignable to the SyncManager (0x1C12/0x1C13 sub-index 0).
    pub max_assigned: u8,
    /// Most entries over all assigned PDOs.
    pub max_entries: u16,
    /// Most bytes over all assigned PDOs (the SyncManager length).
    pub max_bytes: u16,
}

impl DirectionLimits {
    /// The range holding `index`.
    pub const fn range_of(&self, index: u16) -> Option<&PdoRange> {
        let mut i = 0;
        while i < self.pdos.len() {
            if self.pdos[i].contains(index) {
                return Some(&self.pdos[i]);
            }
            i += 1;
        }
        None
    }

    /// Every mapping-object index of this direction.
    pub fn indices(&self) -> impl Iterator<Item = u16> + use<> {
        self.pdos.iter().flat_map(PdoRange::indices)
    }
}

/// The PDO rules of one drive model. Const-constructible, so each profile declares one as data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PdoLimits {
    /// Drive name as error messages use it, e.g. `"MR-J4-TM"`.
    pub drive: &'static str,
    /// Outputs: RxPDOs, SM2, 0x1C12.
    pub rx: DirectionLimits,
    /// Inputs: TxPDOs, SM3, 0x1C13.
    pub tx: DirectionLimits,
    /// Whether 0x1C12/0x1C13 can be written (`false`: the assignment is fixed).
    pub assignment_writable: bool,
}

impl PdoLimits {
    /// The limits of one direction.
    pub const fn direction(&self, dir: Direction) -> &DirectionLimits {
        match dir {
            Direction::Rx => &self.rx,
            Direction::Tx => &self.tx,
        }
    }

    /// The range holding mapping object `index`, in whichever direction it belongs to.
    pub const fn range_of(&self, index: u16) -> Option<&PdoRange> {
        match Direction::of_pdo_index(index) {
            Some(dir) => self.direction(dir).range_of(index),
            None => None,
        }
    }

    /// Whether the mapping of `index` may be rewritten (`false` also for unknown indices).
    pub const fn mapping_writable(&self, index: u16) -> bool {
        match self.range_of(index) {
            Some(r) => r.mapping_writable,
            None => false,
        }
    }

    /// [`validate`] with these limits.
    pub fn validate(
        &self,
        mapping: &Mapping,
        dictionary: Option<&[ObjectDesc]>,
    ) -> Result<(), MappingError> {
        validate(mapping, self, dictionary)
    }
}

/// Check `mapping` against a drive's `limits`, and, given the drive's dictionary, check that
/// every mapped object exists, is mappable in its direction (`EntryAccess::RXPDO`/`TXPDO`) and is
/// mapped with its own bit length. Returns the first violation; [`validate_all`] returns all.
pub fn validate(
    mapping: &Mapping,
    limits: &PdoLimits,
    dictionary: Option<&[ObjectDesc]>,
) -> Result<(), MappingError> {
    match validate_all(mapping, limits, dictionary).into_iter().next() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Every violation [`validate`] looks for, Rx first, in mapping order.
pub fn validate_all(
    mapping: &Mapping,
    limits: &PdoLimits,
    dictionary: Option<&[ObjectDesc]>,
) -> Vec<MappingError> {
    let dict = dictionary.map(Dictionary::new);
    let drive = limits.drive;
    let mut out = Vec::new();
    for dir in Direction::ALL {
        let lim = limits.direction(dir);
        let pdos = mapping.pdos(dir);
        if pdos.len() > usize::from(lim.max_assigned) {
            out.push(MappingError::TooManyPdos {
                drive,
                dir,
                count: pdos.len(),
                max: lim.max_assigned,
            });
        }
        for (i, pdo) in pdos.iter().enumerate() {
            let index = pdo.index;
            if Direction::of_pdo_index(index) != Some(dir) {
                out.push(MappingError::WrongDirection { dir, index });
                continue;
            }
            if pdos.iter().take(i).any(|p| p.index == index) {
                out.push(MappingError::DuplicatePdo { dir, index });
                continue;
            }
            match lim.range_of(index) {
                None => out.push(MappingError::UnknownPdo {
                    drive,
                    dir,
                    index,
                    available: lim.pdos,
                }),
                Some(range) if pdo.len() > usize::from(range.max_entries) => {
                    out.push(MappingError::TooManyEntriesInPdo {
                        drive,
                        dir,
                        index,
                        count: pdo.len(),
                        max: range.max_entries,
                        range: *range,
                    })
                }
                Some(_) => {}
            }
            for (n, entry) in pdo.entries.iter().enumerate() {
                let sub = n.saturating_add(1);
                check_entry(dir, index, sub, *entry, drive, dict.as_ref(), &mut out);
            }
        }
        let entries = mapping.entry_count(dir);
        if entries > usize::from(lim.max_entries) {
            out.push(MappingError::TooManyEntries {
                drive,
                dir,
                count: entries,
                max: lim.max_entries,
            });
        }
        let bytes = mapping.bytes(dir);
        if bytes > usize::from(lim.max_bytes) {
            out.push(MappingError::TooManyBytes {
                drive,
                dir,
                bytes,
                max: lim.max_bytes,
            });
        }
    }
    out
}

fn check_entry(
    dir: Direction,
    pdo: u16,
    sub: usize,
    entry: PdoEntry,
    drive: &'static str,
    dict: Option<&Dictionary<'_>>,
    out: &mut Vec<MappingError>,
) {
    if entry.bits == 0 {
        out.push(MappingError::ZeroLengthEntry {
            dir,
            pdo,
            sub,
            entry,
        });
        return;
    }
    let Some(dict) = dict else { return };
    if entry.is_padding() {
        return;
    }
    let addr = entry.address();
    let Some(desc) = dict.entry(addr) else {
        out.push(MappingError::NoSuchObject {
            drive,
            dir,
            pdo,
            sub,
            addr,
        });
        return;
    };
    let flag = match dir {
        Direction::Rx => EntryAccess::RXPDO,
        Direction::Tx => EntryAccess::TXPDO,
    };
    if !desc.access.contains(flag) {
        out.push(MappingError::NotMappable {
            dir,
            pdo,
            sub,
            addr,
        });
    }
    if desc.bit_len != u16::from(entry.bits) {
        out.push(MappingError::BitLengthMismatch {
            dir,
            pdo,
            sub,
            addr,
            object_bits: desc.bit_len,
            mapped: entry.bits,
        });
    }
}

/// The objects a mode of operation needs in the process data, per drive (e.g. the MR-J4-TM
/// manual's "mapping-necessary objects" table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RequiredObjects {
    /// The 0x6060 value of the mode.
    pub mode: i8,
    /// Its short name, e.g. `"csp"`.
    pub mode_name: &'static str,
    /// Objects that must be in an RxPDO.
    pub rx: &'static [ObjectAddress],
    /// Objects that must be in a TxPDO.
    pub tx: &'static [ObjectAddress],
}

impl RequiredObjects {
    /// The entry for `mode` in a drive's table.
    pub fn find(table: &[RequiredObjects], mode: i8) -> Option<&RequiredObjects> {
        table.iter().find(|r| r.mode == mode)
    }

    /// The required objects `mapping` lacks, Rx first.
    pub fn missing(&self, mapping: &Mapping) -> Vec<(Direction, ObjectAddress)> {
        let rx = self.rx.iter().map(|a| (Direction::Rx, *a));
        let tx = self.tx.iter().map(|a| (Direction::Tx, *a));
        rx.chain(tx)
            .filter(|(dir, addr)| !mapping.contains(*dir, *addr))
            .collect()
    }

    /// Check that `mapping` carries every required object; the error names the first missing
    /// one.
    pub fn check(&self, mapping: &Mapping, drive: &'static str) -> Result<(), MappingError> {
        match self.missing(mapping).first() {
            Some(&(dir, addr)) => Err(MappingError::MissingObject {
                drive,
                mode: self.mode,
                mode_name: self.mode_name,
                dir,
                addr,
            }),
            None => Ok(()),
        }
    }
}

/// One way a PDO mapping breaks a drive's rules. Each message names the limit and the PDO or
/// entry at fault.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MappingError {
    /// More PDOs assigned to a SyncManager than the drive allows.
    #[error(
        "{count} {dir}s are assigned to SM{} (0x{:04X}); the {drive} allows at most {max} per direction",
        dir.sync_manager(), dir.assign_index()
    )]
    TooManyPdos {
        /// Drive name.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// PDOs assigned.
        count: usize,
        /// The limit.
        max: u8,
    },
    /// A mapping index of the other direction (or of neither) in an assignment.
    #[error(
        "0x{index:04X} is not {} ({dir}s are 0x{:04X}–0x{:04X}); it cannot be assigned to SM{} (0x{:04X})",
        dir.with_article(), dir.mapping_range().0, dir.mapping_range().1, dir.sync_manager(), dir.assign_index()
    )]
    WrongDirection {
        /// The SyncManager's direction.
        dir: Direction,
        /// The index assigned.
        index: u16,
    },
    /// A PDO the drive does not have.
    #[error(
        "{dir} 0x{index:04X} does not exist on the {drive} (its {dir}s are {})",
        list(available)
    )]
    UnknownPdo {
        /// Drive name.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// The index assigned.
        index: u16,
        /// The drive's mapping objects in this direction.
        available: &'static [PdoRange],
    },
    /// The same PDO assigned twice to one SyncManager.
    #[error("{dir} 0x{index:04X} is assigned twice to SM{} (0x{:04X})", dir.sync_manager(), dir.assign_index())]
    DuplicatePdo {
        /// Direction.
        dir: Direction,
        /// The PDO.
        index: u16,
    },
    /// A PDO with more entries than its mapping object holds.
    #[error("{dir} 0x{index:04X} has {count} entries; the {drive} allows at most {max} in {range}")]
    TooManyEntriesInPdo {
        /// Drive name.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// The PDO.
        index: u16,
        /// Its entries.
        count: usize,
        /// The limit.
        max: u8,
        /// The mapping objects the limit applies to.
        range: PdoRange,
    },
    /// More entries in one direction than the drive allows.
    #[error("{dir} mapping has {count} entries; the {drive} allows at most {max} per direction")]
    TooManyEntries {
        /// Drive name.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// Entries over all assigned PDOs.
        count: usize,
        /// The limit.
        max: u16,
    },
    /// A process image larger than the drive allows.
    #[error("{dir} mapping is {bytes} bytes; the {drive} allows at most {max} per direction")]
    TooManyBytes {
        /// Drive name.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// Image size.
        bytes: usize,
        /// The limit.
        max: u16,
    },
    /// An entry of length 0.
    #[error("entry {sub} of {dir} 0x{pdo:04X} (0x{:08X}) has length 0 bits", entry.to_u32())]
    ZeroLengthEntry {
        /// Direction.
        dir: Direction,
        /// The PDO.
        pdo: u16,
        /// Position of the entry in the PDO (sub-index, from 1).
        sub: usize,
        /// The entry.
        entry: PdoEntry,
    },
    /// A mapped object missing from the drive's dictionary.
    #[error("{addr} does not exist in the {drive} dictionary (entry {sub} of {dir} 0x{pdo:04X})")]
    NoSuchObject {
        /// Drive name.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// The PDO.
        pdo: u16,
        /// Position of the entry in the PDO (sub-index, from 1).
        sub: usize,
        /// The object.
        addr: ObjectAddress,
    },
    /// An object that cannot be mapped in this direction.
    #[error("{addr} is not {dir}-mappable (entry {sub} of {dir} 0x{pdo:04X})")]
    NotMappable {
        /// Direction.
        dir: Direction,
        /// The PDO.
        pdo: u16,
        /// Position of the entry in the PDO (sub-index, from 1).
        sub: usize,
        /// The object.
        addr: ObjectAddress,
    },
    /// An object mapped with a length other than its own.
    #[error(
        "{addr} is {object_bits} bits, mapped with {mapped} (entry {sub} of {dir} 0x{pdo:04X})"
    )]
    BitLengthMismatch {
        /// Direction.
        dir: Direction,
        /// The PDO.
        pdo: u16,
        /// Position of the entry in the PDO (sub-index, from 1).
        sub: usize,
        /// The object.
        addr: ObjectAddress,
        /// The object's size.
        object_bits: u16,
        /// The mapped size.
        mapped: u8,
    },
    /// A mode of operation needs an object the mapping lacks.
    #[error("{mode_name} (mode {mode}) on the {drive} needs {addr} in {}; the mapping does not have it", dir.with_article())]
    MissingObject {
        /// Drive name.
        drive: &'static str,
        /// 0x6060 value.
        mode: i8,
        /// Mode short name.
        mode_name: &'static str,
        /// Direction it must be mapped in.
        dir: Direction,
        /// The object.
        addr: ObjectAddress,
    },
}

fn list(ranges: &[PdoRange]) -> String {
    if ranges.is_empty() {
        return "none".to_string();
    }
    ranges
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}
