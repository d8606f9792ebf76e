//! The object-store interface the CoE server talks to, and the generic complete-access layout.

use crate::ec::AlState;
use crate::od::{DataType, EntryAccess, EntryDesc, ObjectCode, SdoAbortCode};

/// Which OD list a "get OD list" request asks for (ETG.1000.6 §5.6.3.3). List type 0
/// (quantities) is answered from these five.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ListType {
    /// Every object.
    All,
    /// Objects with at least one entry mappable into an RxPDO.
    RxPdoMappable,
    /// Objects with at least one entry mappable into a TxPDO.
    TxPdoMappable,
    /// Objects with at least one entry flagged for backup (device replacement).
    Backup,
    /// Objects with at least one entry flagged as a start-up setting.
    Startup,
}

impl ListType {
    /// The five lists in wire order (list types 1 to 5).
    pub const ALL_TYPES: [ListType; 5] = [
        Self::All,
        Self::RxPdoMappable,
        Self::TxPdoMappable,
        Self::Backup,
        Self::Startup,
    ];

    /// Decode a list type 1–5.
    pub const fn from_code(code: u16) -> Option<Self> {
        Some(match code {
            1 => Self::All,
            2 => Self::RxPdoMappable,
            3 => Self::TxPdoMappable,
            4 => Self::Backup,
            5 => Self::Startup,
            _ => return None,
        })
    }

    /// The wire code 1–5.
    pub const fn code(self) -> u16 {
        match self {
            Self::All => 1,
            Self::RxPdoMappable => 2,
            Self::TxPdoMappable => 3,
            Self::Backup => 4,
            Self::Startup => 5,
        }
    }

    /// Whether an entry with these access flags puts its object on this list.
    pub const fn matches(self, access: EntryAccess) -> bool {
        match self {
            Self::All => true,
            Self::RxPdoMappable => access.contains(EntryAccess::RXPDO),
            Self::TxPdoMappable => access.contains(EntryAccess::TXPDO),
            Self::Backup => access.contains(EntryAccess::BACKUP),
            Self::Startup => access.contains(EntryAccess::SETTINGS),
        }
    }
}

pub use crate::od::ObjectInfo;

/// An object dictionary as the CoE server sees it.
///
/// Every access is given the current [`AlState`]; a refusal is an [`SdoAbortCode`] that the
/// server sends to the master unchanged. The trait is dyn-compatible: the server takes
/// `&mut dyn ObjectStore`.
///
/// The required methods cover single entries; complete access is provided on top of them
/// ([`ObjectStore::read_complete`], [`ObjectStore::write_complete`]) and can be overridden.
pub trait ObjectStore {
    /// Describe object `index`; `None` if it does not exist.
    fn object(&self, index: u16) -> Option<ObjectInfo>;

    /// Describe one entry. Errors: [`SdoAbortCode::NO_OBJECT`], [`SdoAbortCode::NO_SUBINDEX`].
    fn entry(&self, index: u16, sub: u8) -> Result<EntryDesc, SdoAbortCode>;

    /// The smallest existing index greater than `after` (the first index for `None`): the
    /// dictionary in ascending order, without allocation.
    fn next_index(&self, after: Option<u16>) -> Option<u16>;

    /// Read one entry's value into `buf` as it goes over SDO (little-endian, bit types as whole
    /// bytes, strings with their current length); returns the number of bytes.
    fn read(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        buf: &mut [u8],
    ) -> Result<usize, SdoAbortCode>;

    /// Write one entry from the bytes of an SDO download.
    fn write(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode>;

    /// Whether object `index` belongs on OD list `list` (some entry carries the flag).
    fn in_list(&self, index: u16, list: ListType) -> bool {
        let Some(obj) = self.object(index) else {
            return false;
        };
        if list == ListType::All {
            return true;
        }
        (0..=obj.max_sub).any(|sub| self.entry(index, sub).is_ok_and(|e| list.matches(e.access)))
    }

    /// Complete-access upload of object `index` starting at `sub` (0 or 1) into `buf`.
    ///
    /// Layout (ETG.1000.6 §5.6.2, as SOES and SOEM implement it): starting at sub 0, the sub-0
    /// value as a u8 plus one pad byte (sub 0 padded to 16 bits); then the entries 1 to the
    /// current sub-0 value in order, skipping sub-indices that do not exist (RECORD gaps).
    /// Entries whose size is not a whole number of bytes are packed bit by bit, the others start
    /// on a byte boundary. A VAR object is its value. Objects with string or domain entries are
    /// refused with [`SdoAbortCode::COMPLETE_ACCESS_UNSUPPORTED`].
    fn read_complete(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        buf: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        let obj = ca_object(self, index, sub)?;
        if obj.code() == Some(ObjectCode::Var) {
            return self.read(index, 0, state, buf);
        }
        let mut tmp = [0u8; 8];
        let n = read_sub0(self, index, state)?;
        let mut w = BitWriter::new(buf);
        if sub == 0 {
            w.bytes(&[n, 0])?;
        }
        for s in 1..=n {
            let e = match self.entry(index, s) {
                Ok(e) => e,
                Err(SdoAbortCode::NO_SUBINDEX) => continue,
                Err(code) => return Err(code),
            };
            let len = self.read(index, s, state, &mut tmp)?;
            w.entry(&e, tmp.get(..len).unwrap_or(&[]))?;
        }
        Ok(w.len())
    }

    /// Complete-access download of object `index` starting at `sub` (0 or 1), in the layout of
    /// [`ObjectStore::read_complete`].
    ///
    /// Starting at sub 0, the first byte is the new number of entries `n` and entries 1..=n
    /// follow; starting at sub 1, the entries 1 to the current sub-0 value follow. The length
    /// must match exactly (0x06070012 / 0x06070013).
    ///
    /// Order of writes, so that PDO mapping and assignment objects accept it: sub 0 := 0 (if
    /// sub 0 is writable), the entries in order, then sub 0 := n. Read-only entries (and a
    /// read-only sub 0) must carry their current value, which is then skipped; a different
    /// value aborts with [`SdoAbortCode::READ_ONLY`]. Every write goes through
    /// [`ObjectStore::write`] with all its checks; on an abort the writes before it stay done,
    /// as on devices that do not buffer a complete access.
    fn write_complete(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        let obj = ca_object(self, index, sub)?;
        if obj.code() == Some(ObjectCode::Var) {
            return self.write(index, 0, state, data);
        }
        let current_n = read_sub0(self, index, state)?;
        let (n, body) = if sub == 0 {
            let n = *data.first().ok_or(SdoAbortCode::LENGTH_TOO_LOW)?;
            (n, data.get(2..).ok_or(SdoAbortCode::LENGTH_TOO_LOW)?)
        } else {
            (current_n, data)
        };
        if n > obj.max_sub {
            return Err(SdoAbortCode::VALUE_TOO_HIGH);
        }
        // Size check before any write.
        let mut bits = 0usize;
        for s in 1..=n {
            match self.entry(index, s) {
                Ok(e) => bits = layout_advance(bits, &e),
                Err(SdoAbortCode::NO_SUBINDEX) => {}
                Err(code) => return Err(code),
            }
        }
        let expected = bits.div_ceil(8);
        if body.len() > expected {
            return Err(SdoAbortCode::LENGTH_TOO_HIGH);
        }
        if body.len() < expected {
            return Err(SdoAbortCode::LENGTH_TOO_LOW);
        }
        let sub0_writable = self.entry(index, 0)?.access.writable();
        if sub == 0 {
            if sub0_writable {
                self.write(index, 0, state, &[0])?;
            } else if n != current_n {
                return Err(SdoAbortCode::READ_ONLY);
            }
        }
        let mut r = BitReader::new(body);
        let mut cur = [0u8; 8];
        for s in 1..=n {
            let e = match self.entry(index, s) {
                Ok(e) => e,
                Err(_) => continue,
            };
            let value = r.entry(&e);
            let bytes = value.get(..entry_bytes(&e)).unwrap_or(&[]);
            if e.access.writable() {
                self.write(index, s, state, bytes)?;
            } else {
                let len = self.read(index, s, state, &mut cur)?;
                if cur.get(..len) != Some(bytes) {
                    return Err(SdoAbortCode::READ_ONLY);
                }
            }
        }
        if sub == 0 && sub0_writable {
            self.write(index, 0, state, &[n])?;
        }
        Ok(())
    }
}

/// Checks common to both complete-access directions; returns the object description.
fn ca_object<S: ObjectStore + ?Sized>(
    store: &S,
    index: u16,
    sub: u8,
) -> Result<ObjectInfo, SdoAbortCode> {
    let obj = store.object(index).ok_or(SdoAbortCode::NO_OBJECT)?;
    if sub > 1 {
        // Complete access addresses a whole object from sub 0 or sub 1, nothing else.
        return Err(SdoAbortCode::UNSUPPORTED_ACCESS);
    }
    if obj.code() == Some(ObjectCode::Var) {
        return if sub == 0 {
            Ok(obj)
        } else {
            Err(SdoAbortCode::NO_SUBINDEX)
        };
    }
    for s in 0..=obj.max_sub {
        if let Ok(e) = store.entry(index, s)
            && (e.data_type.is_string() || e.data_type.bit_len().is_none())
        {
            return Err(SdoAbortCode::COMPLETE_ACCESS_UNSUPPORTED);
        }
    }
    Ok(obj)
}

fn read_sub0<S: ObjectStore + ?Sized>(
    store: &mut S,
    index: u16,
    state: AlState,
) -> Result<u8, SdoAbortCode> {
    let mut b = [0u8; 8];
    let len = store.read(index, 0, state, &mut b)?;
    if len == 0 {
        return Err(SdoAbortCode::GENERAL);
    }
    Ok(b[0])
}

/// Bytes an entry's value takes over SDO (bit types: one byte).
pub(crate) fn entry_bytes(e: &EntryDesc) -> usize {
    match e.data_type.bit_len() {
        Some(b) => (b as usize).div_ceil(8),
        None => (e.bit_len as usize).div_ceil(8),
    }
}

/// Whether an entry is packed bit by bit in a complete-access image.
fn packed(e: &EntryDesc) -> bool {
    e.bit_len % 8 != 0 || matches!(e.data_type, DataType::Boolean)
}

/// Size in bits an entry takes in a complete-access image.
fn image_bits(e: &EntryDesc) -> usize {
    if packed(e) {
        (e.bit_len as usize).max(1)
    } else {
        e.bit_len as usize
    }
}

/// The bit offset after placing `e` at `bits`.
fn layout_advance(bits: usize, e: &EntryDesc) -> usize {
    let start = if packed(e) {
        bits
    } else {
        bits.div_ceil(8) * 8
    };
    start + image_bits(e)
}

struct BitWriter<'a> {
    buf: &'a mut [u8],
    bits: usize,
}

impl<'a> BitWriter<'a> {
    fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, bits: 0 }
    }

    fn len(&self) -> usize {
        self.bits.div_ceil(8)
    }

    fn bytes(&mut self, b: &[u8]) -> Result<(), SdoAbortCode> {
        let at = self.bits.div_ceil(8);
        let dst = self
            .buf
            .get_mut(at..at + b.len())
            .ok_or(SdoAbortCode::OUT_OF_MEMORY)?;
        dst.copy_from_slice(b);
        self.bits = (at + b.len()) * 8;
        Ok(())
    }

    fn entry(&mut self, e: &EntryDesc, value: &[u8]) -> Result<(), SdoAbortCode> {
        if !packed(e) {
            let n = image_bits(e) / 8;
            let mut tmp = [0u8; 8];
            let src = value.get(..n.min(value.len())).unwrap_or(&[]);
            if let Some(d) = tmp.get_mut(..src.len()) {
                d.copy_from_slice(src);
            }
            return self.bytes(tmp.get(..n).unwrap_or(&[]));
        }
        let nbits = image_bits(e);
        let mut raw = [0u8; 8];
        let src = value.get(..value.len().min(8)).unwrap_or(&[]);
        if let Some(d) = raw.get_mut(..src.len()) {
            d.copy_from_slice(src);
        }
        let v = u64::from_le_bytes(raw);
        for i in 0..nbits {
            let bit = v.checked_shr(i as u32).unwrap_or(0) & 1;
            let pos = self.bits + i;
            let byte = self
                .buf
                .get_mut(pos / 8)
                .ok_or(SdoAbortCode::OUT_OF_MEMORY)?;
            if pos % 8 == 0 {
                // First bit of a fresh byte: clear what an earlier use of the buffer left.
                *byte = 0;
            }
            *byte |= (bit as u8) << (pos % 8);
        }
        self.bits += nbits;
        Ok(())
    }
}

struct BitReader<'a> {
    data: &'a [u8],
    bits: usize,
}

impl<'a> BitReader<'a> {
    fn new(data: &'a [u8]) -> Self {
        Self { data, bits: 0 }
    }

    /// The next entry's value as SDO bytes (little-endian, zero-extended), in an 8-byte array.
    fn entry(&mut self, e: &EntryDesc) -> [u8; 8] {
        let mut out = [0u8; 8];
        if !packed(e) {
            let at = self.bits.div_ceil(8);
            let n = image_bits(e) / 8;
            if let (Some(src), Some(dst)) = (self.data.get(at..at + n), out.get_mut(..n.min(8))) {
                dst.copy_from_slice(src.get(..dst.len()).unwrap_or(&[]));
            }
            self.bits = (at + n) * 8;
            return out;
        }
        let nbits = image_bits(e);
        let mut v = 0u64;
        for i in 0..nbits.min(64) {
            let pos = self.bits + i;
            let bit = self.data.get(pos / 8).map_or(0, |b| (b >> (pos % 8)) & 1);
            v |= u64::from(bit) << i;
        }
        self.bits += nbits;
        out = v.to_le_bytes();
        out
    }
}
