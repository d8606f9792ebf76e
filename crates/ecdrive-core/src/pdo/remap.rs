//! The SDO sequence that installs a [`Mapping`] on a drive in PRE-OP, and the read-back that
//! rebuilds a [`Mapping`] from what a drive reports.
//!
//! The sequence is the CiA 301 / ETG.1000.6 procedure, one single-sub-index download per step
//! (neither drive supports Complete Access):
//!
//! 1. unassign: 0x1C12:00 = 0, 0x1C13:00 = 0;
//! 2. for each assigned PDO, Rx first: 0x16xx:00 = 0, 0x16xx:01..n = entries, 0x16xx:00 = n;
//! 3. assign: 0x1C12:01..m = PDO indices, 0x1C12:00 = m; then the same for 0x1C13.
//!
//! Sub-index 0 counts are UNSIGNED8, assignment entries UNSIGNED16, mapping entries UNSIGNED32.

use super::limits::PdoLimits;
use super::{Direction, Mapping, Pdo, PdoEntry};
use crate::od::{DataType, Dictionary, ObjectAddress, ObjectCode, Value};
use core::fmt;
use core::future::Future;
use core::pin::pin;
use core::task::{Context, Poll, Waker};

/// One SDO download of a remap sequence.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct SdoWrite {
    /// Where to write.
    pub address: ObjectAddress,
    /// `UNSIGNED8` (sub-index 0 counts), `UNSIGNED16` (assignment entries) or `UNSIGNED32`
    /// (mapping entries).
    pub data_type: DataType,
    /// The value; it always fits `data_type`.
    pub value: u32,
    /// What the write does, for logs and the CLI, e.g. `"clear 0x1600 mapping"`.
    pub description: String,
}

impl SdoWrite {
    /// An UNSIGNED8 write (a sub-index 0 count).
    pub fn count(address: ObjectAddress, n: u8, description: impl Into<String>) -> Self {
        Self {
            address,
            data_type: DataType::Unsigned8,
            value: u32::from(n),
            description: description.into(),
        }
    }

    /// An UNSIGNED16 write (a PDO index in 0x1C12/0x1C13).
    pub fn pdo_index(address: ObjectAddress, index: u16, description: impl Into<String>) -> Self {
        Self {
            address,
            data_type: DataType::Unsigned16,
            value: u32::from(index),
            description: description.into(),
        }
    }

    /// An UNSIGNED32 write (a mapping entry).
    pub fn entry(address: ObjectAddress, value: u32, description: impl Into<String>) -> Self {
        Self {
            address,
            data_type: DataType::Unsigned32,
            value,
            description: description.into(),
        }
    }

    /// The value as a runtime [`Value`].
    pub fn to_value(&self) -> Value {
        Value::Uint(u64::from(self.value))
    }

    /// The little-endian download data: 1, 2 or 4 bytes by data type.
    pub fn bytes(&self) -> Vec<u8> {
        let n = match self.data_type {
            DataType::Unsigned8 => 1,
            DataType::Unsigned16 => 2,
            _ => 4,
        };
        self.value.to_le_bytes().into_iter().take(n).collect()
    }
}

impl fmt::Display for SdoWrite {
    /// `0x1600:01 = 0x60400010 (map 0x6040:00 Controlword, 16 bits)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.data_type {
            DataType::Unsigned8 => write!(f, "{} = {}", self.address, self.value)?,
            DataType::Unsigned16 => write!(f, "{} = 0x{:04X}", self.address, self.value)?,
            _ => write!(f, "{} = 0x{:08X}", self.address, self.value)?,
        }
        write!(f, " ({})", self.description)
    }
}

/// How [`remap_sequence`] adapts to a drive.
#[derive(Debug, Clone, Copy, Default)]
pub struct RemapOptions<'a> {
    /// Leave 0x1C12/0x1C13 alone (the drive's assignment is fixed): no unassign, no assign.
    pub skip_assignment: bool,
    /// Skip the mapping writes of PDOs these limits mark as fixed
    /// ([`PdoRange::mapping_writable`](super::PdoRange) is `false`); they are still assigned.
    pub fixed_mappings: Option<&'a PdoLimits>,
    /// Names for the descriptions (the drive's dictionary).
    pub names: Option<Dictionary<'a>>,
}

impl<'a> RemapOptions<'a> {
    /// Options for a drive: skip what its limits mark as fixed, and name objects from its
    /// dictionary.
    pub fn for_drive(limits: &'a PdoLimits, names: Option<Dictionary<'a>>) -> Self {
        Self {
            skip_assignment: !limits.assignment_writable,
            fixed_mappings: Some(limits),
            names,
        }
    }
}

/// Why a mapping cannot be expressed as SDO writes at all (a drive's own limits are far lower;
/// run [`validate`](super::validate) first).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RemapError {
    /// A mapping object has sub-indices 1..=255 only.
    #[error("{dir} 0x{pdo:04X} has {count} entries; a mapping object holds at most 255")]
    TooManyEntries {
        /// Direction.
        dir: Direction,
        /// The PDO.
        pdo: u16,
        /// Its entries.
        count: usize,
    },
    /// An assignment object has sub-indices 1..=255 only.
    #[error("{count} {dir}s are assigned; 0x{:04X} holds at most 255", dir.assign_index())]
    TooManyPdos {
        /// Direction.
        dir: Direction,
        /// PDOs assigned.
        count: usize,
    },
}

/// The SDO downloads that install `mapping`, in order (see the module documentation). A PDO
/// assigned twice has its mapping written once.
pub fn remap_sequence(
    mapping: &Mapping,
    options: &RemapOptions<'_>,
) -> Result<Vec<SdoWrite>, RemapError> {
    let mut out = Vec::new();
    let assign = !options.skip_assignment;
    if assign {
        for dir in Direction::ALL {
            out.push(SdoWrite::count(
                ObjectAddress::new(dir.assign_index(), 0),
                0,
                format!("unassign SM{} PDOs", dir.sync_manager()),
            ));
        }
    }
    for dir in Direction::ALL {
        let pdos = mapping.pdos(dir);
        for (i, pdo) in pdos.iter().enumerate() {
            let fixed = options
                .fixed_mappings
                .is_some_and(|l| !l.mapping_writable(pdo.index));
            if fixed || pdos.iter().take(i).any(|p| p.index == pdo.index) {
                continue;
            }
            write_pdo(dir, pdo, options.names.as_ref(), &mut out)?;
        }
    }
    if assign {
        for dir in Direction::ALL {
            let pdos = mapping.pdos(dir);
            let count = u8::try_from(pdos.len()).map_err(|_| RemapError::TooManyPdos {
                dir,
                count: pdos.len(),
            })?;
            let sm = dir.sync_manager();
            for (sub, pdo) in (1..=count).zip(pdos.iter()) {
                out.push(SdoWrite::pdo_index(
                    ObjectAddress::new(dir.assign_index(), sub),
                    pdo.index,
                    format!("assign {dir} 0x{:04X} to SM{sm}", pdo.index),
                ));
            }
            out.push(SdoWrite::count(
                ObjectAddress::new(dir.assign_index(), 0),
                count,
                format!(
                    "SM{sm} has {count} PDO{}",
                    if count == 1 { "" } else { "s" }
                ),
            ));
        }
    }
    Ok(out)
}

fn write_pdo(
    dir: Direction,
    pdo: &Pdo,
    names: Option<&Dictionary<'_>>,
    out: &mut Vec<SdoWrite>,
) -> Result<(), RemapError> {
    let count = u8::try_from(pdo.len()).map_err(|_| RemapError::TooManyEntries {
        dir,
        pdo: pdo.index,
        count: pdo.len(),
    })?;
    let at = |sub| ObjectAddress::new(pdo.index, sub);
    out.push(SdoWrite::count(
        at(0),
        0,
        format!("clear 0x{:04X} mapping", pdo.index),
    ));
    for (sub, e) in (1..=count).zip(pdo.entries.iter()) {
        out.push(SdoWrite::entry(at(sub), e.to_u32(), describe(*e, names)));
    }
    out.push(SdoWrite::count(
        at(0),
        count,
        format!(
            "0x{:04X} maps {count} entr{}",
            pdo.index,
            if count == 1 { "y" } else { "ies" }
        ),
    ));
    Ok(())
}

fn describe(e: PdoEntry, names: Option<&Dictionary<'_>>) -> String {
    if e.is_padding() {
        return format!("{}-bit gap", e.bits);
    }
    let name = names.and_then(|d| d.lookup(e.address())).map(|(o, en)| {
        if o.code == ObjectCode::Var {
            o.name.to_string()
        } else {
            format!("{}: {}", o.name, en.name)
        }
    });
    let unit = if e.bits == 1 { "bit" } else { "bits" };
    match name {
        Some(n) => format!("map {} {n}, {} {unit}", e.address(), e.bits),
        None => format!("map {}, {} {unit}", e.address(), e.bits),
    }
}

/// Why reading a drive's mapping back failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReadbackError<E> {
    /// The upload itself failed (the caller's error, e.g. an SDO abort).
    Upload {
        /// What was read.
        address: ObjectAddress,
        /// The caller's error.
        source: E,
    },
    /// The drive returned a value too large for the object's type.
    BadValue {
        /// What was read.
        address: ObjectAddress,
        /// The value.
        value: u32,
        /// The type it should have.
        data_type: DataType,
    },
    /// An assignment object lists a PDO of the other direction.
    WrongDirection {
        /// The assignment entry read.
        address: ObjectAddress,
        /// The index it holds.
        index: u16,
        /// The SyncManager's direction.
        dir: Direction,
    },
}

impl<E: fmt::Display> fmt::Display for ReadbackError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Upload { address, source } => write!(f, "reading {address} failed: {source}"),
            Self::BadValue {
                address,
                value,
                data_type,
            } => write!(f, "{address} returned {value}, which is not a {data_type}"),
            Self::WrongDirection {
                address,
                index,
                dir,
            } => {
                let (lo, hi) = dir.mapping_range();
                write!(
                    f,
                    "{address} assigns 0x{index:04X}, which is not {} index (0x{lo:04X}–0x{hi:04X})",
                    dir.with_article()
                )
            }
        }
    }
}

impl<E: std::error::Error + 'static> std::error::Error for ReadbackError<E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Upload { source, .. } => Some(source),
            _ => None,
        }
    }
}

async fn read_as<F, Fut, E>(
    upload: &mut F,
    address: ObjectAddress,
    data_type: DataType,
) -> Result<u32, ReadbackError<E>>
where
    F: FnMut(ObjectAddress, DataType) -> Fut,
    Fut: Future<Output = Result<u32, E>>,
{
    let value = upload(address, data_type)
        .await
        .map_err(|source| ReadbackError::Upload { address, source })?;
    let max = match data_type {
        DataType::Unsigned8 => u32::from(u8::MAX),
        DataType::Unsigned16 => u32::from(u16::MAX),
        _ => u32::MAX,
    };
    if value > max {
        return Err(ReadbackError::BadValue {
            address,
            value,
            data_type,
        });
    }
    Ok(value)
}

/// Read a drive's PDO assignment and mapping with `upload` and rebuild the [`Mapping`]:
/// 0x1C12:00, 0x1C12:01..n, then each assigned PDO's :00 and :01..m, then the same for 0x1C13.
/// `upload(address, type)` performs one SDO upload and returns the value (`UNSIGNED8`,
/// `UNSIGNED16` or `UNSIGNED32`, as `u32`). A PDO assigned twice is read once.
pub async fn read_mapping<F, Fut, E>(mut upload: F) -> Result<Mapping, ReadbackError<E>>
where
    F: FnMut(ObjectAddress, DataType) -> Fut,
    Fut: Future<Output = Result<u32, E>>,
{
    let mut per_dir: [Vec<Pdo>; 2] = [Vec::new(), Vec::new()];
    for (dir, pdos) in Direction::ALL.into_iter().zip(per_dir.iter_mut()) {
        let assign = dir.assign_index();
        let n = read_as(
            &mut upload,
            ObjectAddress::new(assign, 0),
            DataType::Unsigned8,
        )
        .await?;
        let mut indices = Vec::new();
        for sub in 1..=n {
            let address = ObjectAddress::new(assign, sub as u8);
            let index = read_as(&mut upload, address, DataType::Unsigned16).await? as u16;
            if Direction::of_pdo_index(index) != Some(dir) {
                return Err(ReadbackError::WrongDirection {
                    address,
                    index,
                    dir,
                });
            }
            indices.push(index);
        }
        for index in indices {
            if let Some(seen) = pdos.iter().find(|p| p.index == index) {
                let again = seen.clone();
                pdos.push(again);
                continue;
            }
            let m = read_as(
                &mut upload,
                ObjectAddress::new(index, 0),
                DataType::Unsigned8,
            )
            .await?;
            let mut entries = Vec::new();
            for sub in 1..=m {
                let v = read_as(
                    &mut upload,
                    ObjectAddress::new(index, sub as u8),
                    DataType::Unsigned32,
                )
                .await?;
                entries.push(PdoEntry::from_u32(v));
            }
            pdos.push(Pdo::owned(index, entries));
        }
    }
    let [rx, tx] = per_dir;
    Ok(Mapping::owned(rx, tx))
}

/// [`read_mapping`] with a blocking `upload` (the emulated drive reading its own dictionary,
/// tests, tools without an executor).
pub fn read_mapping_sync<E>(
    mut upload: impl FnMut(ObjectAddress, DataType) -> Result<u32, E>,
) -> Result<Mapping, ReadbackError<E>> {
    let mut fut = pin!(read_mapping(|address, data_type| {
        core::future::ready(upload(address, data_type))
    }));
    let mut cx = Context::from_waker(Waker::noop());
    // Every future awaited inside is `ready`, so the first poll completes.
    loop {
        if let Poll::Ready(result) = fut.as_mut().poll(&mut cx) {
            return result;
        }
    }
}
