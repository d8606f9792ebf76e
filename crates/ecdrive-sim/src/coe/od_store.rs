//! [`OdStore`]: a generic object dictionary built from static descriptor tables, enforcing the
//! CoE access rules and the standard PDO mapping/assignment rules, with a [`OdHooks`] trait for
//! device-specific behaviour.

use super::store::{ObjectInfo, ObjectStore, entry_bytes};
use crate::ec::AlState;
use crate::od::{
    DataType, EntryAccess, EntryDesc, ObjectAddress, ObjectCode, ObjectDesc, SdoAbortCode, Value,
};
use crate::pdo::{Direction, Mapping, PdoEntry, PdoLimits, ReadbackError, read_mapping_sync};
use core::ops::{Deref, DerefMut};

use super::MAX_UNSIZED_STRING;
use crate::quirks::{Quirk, Quirks};

/// Why a descriptor table cannot be served.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("object dictionary entry {at}: {reason}")]
pub struct OdError {
    /// The object (and sub-index) at fault, e.g. `0x1C12:01`.
    pub at: String,
    /// What is wrong.
    pub reason: String,
}

/// What a standard PDO configuration object is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PdoObject {
    /// 0x1C12 / 0x1C13.
    Assign(Direction),
    /// 0x1600–0x17FF / 0x1A00–0x1BFF.
    Map(Direction),
}

fn pdo_object(index: u16) -> Option<PdoObject> {
    match index {
        0x1C12 => Some(PdoObject::Assign(Direction::Rx)),
        0x1C13 => Some(PdoObject::Assign(Direction::Tx)),
        0x1600..=0x17FF => Some(PdoObject::Map(Direction::Rx)),
        0x1A00..=0x1BFF => Some(PdoObject::Map(Direction::Tx)),
        _ => None,
    }
}

fn pdo_index_in(dir: Direction, index: u16) -> bool {
    match dir {
        Direction::Rx => (0x1600..=0x17FF).contains(&index),
        Direction::Tx => (0x1A00..=0x1BFF).contains(&index),
    }
}

fn le_u64(b: &[u8]) -> u64 {
    let mut raw = [0u8; 8];
    let n = b.len().min(8);
    if let (Some(d), Some(s)) = (raw.get_mut(..n), b.get(..n)) {
        d.copy_from_slice(s);
    }
    u64::from_le_bytes(raw)
}

/// The state bit of `access` that allows reading (`write == false`) or writing in `state`.
fn allowed_in(access: EntryAccess, state: AlState, write: bool) -> bool {
    let flag = match (state, write) {
        (AlState::PreOp, false) => EntryAccess::READ_PREOP,
        (AlState::SafeOp, false) => EntryAccess::READ_SAFEOP,
        (AlState::Op, false) => EntryAccess::READ_OP,
        (AlState::PreOp, true) => EntryAccess::WRITE_PREOP,
        (AlState::SafeOp, true) => EntryAccess::WRITE_SAFEOP,
        (AlState::Op, true) => EntryAccess::WRITE_OP,
        // No CoE in INIT and BOOT.
        (AlState::Init | AlState::Bootstrap, _) => return false,
    };
    access.contains(flag)
}

/// The object descriptors and their current values, plus the PDO limits: the runtime value store
/// behind an [`OdStore`]. (Not to be confused with [`crate::od::Dictionary`], the read-only view
/// over a static descriptor table, or [`crate::esi::Dictionary`], an ESI file's dictionary.)
///
/// Access here is the device's own (no access rights, no hooks): the emulated drive reads and
/// writes its values through these methods, and [`OdHooks`] get it to inspect or update values.
#[derive(Debug, Clone)]
pub struct ValueStore {
    /// Objects sorted by index.
    objects: Vec<&'static ObjectDesc>,
    /// Index of each object's first value in `values`.
    base: Vec<usize>,
    /// One value per entry, in object order then entry order, as SDO bytes.
    values: Vec<Vec<u8>>,
    /// The drive's PDO rules; `None`: only what the mapping objects can hold.
    limits: Option<PdoLimits>,
}

/// Largest byte size an entry's value may take.
fn max_bytes(e: &EntryDesc) -> usize {
    if e.data_type.is_string() {
        let declared = (e.bit_len as usize).div_ceil(8);
        if declared > 0 {
            declared
        } else {
            default_len(e).max(MAX_UNSIZED_STRING)
        }
    } else {
        entry_bytes(e)
    }
}

fn default_len(e: &EntryDesc) -> usize {
    match e.default {
        crate::od::ConstValue::Str(s) => s.len(),
        crate::od::ConstValue::Bytes(b) => b.len(),
        _ => 0,
    }
}

/// The initial value bytes of an entry from its default.
fn initial_value(obj: &ObjectDesc, e: &EntryDesc) -> Result<Vec<u8>, OdError> {
    let at = ObjectAddress::new(obj.index, e.sub).to_string();
    let err = |reason: String| OdError {
        at: at.clone(),
        reason,
    };
    let cap = max_bytes(e);
    if e.data_type.is_string() {
        let mut v = Vec::with_capacity(cap);
        match e.default.to_value() {
            None => {}
            Some(Value::Str(s)) => v.extend_from_slice(s.as_bytes()),
            Some(Value::Bytes(b)) => v.extend_from_slice(&b),
            Some(other) => {
                return Err(err(format!(
                    "default {other} is not a string for {}",
                    e.data_type
                )));
            }
        }
        if v.len() > cap {
            return Err(err(format!(
                "default string of {} bytes exceeds the entry size of {cap} bytes",
                v.len()
            )));
        }
        return Ok(v);
    }
    let mut v = vec![0u8; cap];
    if let Some(d) = e.default.to_value() {
        d.encode_into(e.data_type, &mut v)
            .map_err(|x| err(format!("default value does not fit: {x}")))?;
    }
    Ok(v)
}

impl ValueStore {
    /// [`Quirk::CycleTimeReadOnly`](crate::quirks::Quirk::CycleTimeReadOnly): at a SYNC0
    /// event, 0x1C32:02 and 0x1C33:02 (where they exist) show the SYNC0 cycle.
    pub fn show_sync0_cycle(&mut self, event: &crate::SyncEvent) {
        if event.kind == crate::SyncKind::Sync0 && event.cycle_time_ns > 0 {
            for index in [0x1C32, 0x1C33] {
                let a = crate::od::ObjectAddress::new(index, 2);
                if self.raw(a).is_some() {
                    let _ = self.set_uint(a, u64::from(event.cycle_time_ns));
                }
            }
        }
    }

    /// Build from descriptor tables, values initialised from the defaults (zero or empty where
    /// none is given). Checks the tables: unique indices and sub-indices, a VAR has exactly
    /// sub 0, an ARRAY/RECORD has an UNSIGNED8 sub 0, defaults fit their types.
    pub fn new(objects: &'static [ObjectDesc]) -> Result<Self, OdError> {
        let mut sorted: Vec<&'static ObjectDesc> = objects.iter().collect();
        sorted.sort_by_key(|o| o.index);
        for w in sorted.windows(2) {
            if let [a, b] = w
                && a.index == b.index
            {
                return Err(OdError {
                    at: format!("0x{:04X}", a.index),
                    reason: "the index is described twice".into(),
                });
            }
        }
        let mut base = Vec::with_capacity(sorted.len());
        let mut values = Vec::new();
        for obj in &sorted {
            let at = format!("0x{:04X}", obj.index);
            let mut subs: Vec<u8> = obj.entries.iter().map(|e| e.sub).collect();
            subs.sort_unstable();
            if subs.windows(2).any(|w| w.first() == w.get(1)) {
                return Err(OdError {
                    at,
                    reason: "a sub-index is described twice".into(),
                });
            }
            match obj.code {
                ObjectCode::Var => {
                    if subs != [0] {
                        return Err(OdError {
                            at,
                            reason: "a VAR object must have exactly one entry, sub-index 0".into(),
                        });
                    }
                }
                ObjectCode::Array | ObjectCode::Record => {
                    if obj.entry(0).map(|e| e.data_type) != Some(DataType::Unsigned8) {
                        return Err(OdError {
                            at,
                            reason: "an ARRAY or RECORD needs an UNSIGNED8 sub-index 0".into(),
                        });
                    }
                }
            }
            base.push(values.len());
            for e in obj.entries {
                values.push(initial_value(obj, e)?);
            }
        }
        Ok(Self {
            objects: sorted,
            base,
            values,
            limits: None,
        })
    }

    /// The PDO limits enforced on master writes (`None`: none beyond the object sizes).
    pub fn limits(&self) -> Option<&PdoLimits> {
        self.limits.as_ref()
    }

    /// Replace the PDO limits.
    pub fn set_limits(&mut self, limits: Option<PdoLimits>) {
        self.limits = limits;
    }

    /// Reset every value to its default (a power cycle of a device that stores nothing).
    pub fn restore_defaults(&mut self) {
        for (pos, obj) in self.objects.iter().enumerate() {
            let Some(&b) = self.base.get(pos) else {
                continue;
            };
            for (i, e) in obj.entries.iter().enumerate() {
                if let (Ok(v), Some(slot)) = (initial_value(obj, e), self.values.get_mut(b + i)) {
                    *slot = v;
                }
            }
        }
    }

    fn position(&self, index: u16) -> Option<usize> {
        self.objects.binary_search_by_key(&index, |o| o.index).ok()
    }

    /// The descriptor of object `index`.
    pub fn object_desc(&self, index: u16) -> Option<&'static ObjectDesc> {
        self.position(index)
            .and_then(|p| self.objects.get(p).copied())
    }

    /// The descriptor of one entry.
    pub fn entry_desc(&self, addr: ObjectAddress) -> Option<&'static EntryDesc> {
        self.object_desc(addr.index).and_then(|o| o.entry(addr.sub))
    }

    /// All objects in index order.
    pub fn objects(&self) -> impl Iterator<Item = &'static ObjectDesc> + '_ {
        self.objects.iter().copied()
    }

    fn slot(&self, addr: ObjectAddress) -> Option<usize> {
        let pos = self.position(addr.index)?;
        let obj = self.objects.get(pos)?;
        let i = obj.entries.iter().position(|e| e.sub == addr.sub)?;
        Some(self.base.get(pos)? + i)
    }

    /// The current value as SDO bytes.
    pub fn raw(&self, addr: ObjectAddress) -> Option<&[u8]> {
        self.slot(addr)
            .and_then(|s| self.values.get(s))
            .map(Vec::as_slice)
    }

    /// Set a value from SDO bytes, as the device itself: only the size is checked (exactly the
    /// type's size; strings up to the entry size). No access rights, ranges or hooks. Does not
    /// allocate for fixed-size entries, nor for strings (their capacity is reserved).
    pub fn set_raw(&mut self, addr: ObjectAddress, bytes: &[u8]) -> Result<(), SdoAbortCode> {
        let e = self.entry_desc(addr).ok_or_else(|| self.missing(addr))?;
        check_len(e, bytes)?;
        let slot = self
            .slot(addr)
            .and_then(|s| self.values.get_mut(s))
            .ok_or(SdoAbortCode::GENERAL)?;
        if e.data_type.is_string() {
            slot.clear();
            slot.extend_from_slice(bytes);
        } else {
            slot.copy_from_slice(bytes);
        }
        Ok(())
    }

    fn missing(&self, addr: ObjectAddress) -> SdoAbortCode {
        if self.object_desc(addr.index).is_some() {
            SdoAbortCode::NO_SUBINDEX
        } else {
            SdoAbortCode::NO_OBJECT
        }
    }

    /// The current value, decoded.
    pub fn value(&self, addr: ObjectAddress) -> Option<Value> {
        let e = self.entry_desc(addr)?;
        Value::decode(e.data_type, self.raw(addr)?).ok()
    }

    /// Set a value as the device itself (see [`ValueStore::set_raw`]); the value must fit the
    /// data type (0x06090030 otherwise).
    pub fn set_value(&mut self, addr: ObjectAddress, v: &Value) -> Result<(), SdoAbortCode> {
        let e = self.entry_desc(addr).ok_or_else(|| self.missing(addr))?;
        if e.data_type.is_string() {
            let bytes = v
                .encode(e.data_type)
                .map_err(|_| SdoAbortCode::VALUE_RANGE)?;
            return self.set_raw(addr, &bytes);
        }
        let mut buf = [0u8; 8];
        let n = v
            .encode_into(e.data_type, &mut buf)
            .map_err(|_| SdoAbortCode::VALUE_RANGE)?;
        self.set_raw(addr, buf.get(..n).unwrap_or(&[]))
    }

    /// An unsigned, boolean or bit entry's value. `None` for other types.
    pub fn uint(&self, addr: ObjectAddress) -> Option<u64> {
        let e = self.entry_desc(addr)?;
        if !e.data_type.is_unsigned() {
            return None;
        }
        Some(le_u64(self.raw(addr)?))
    }

    /// An integer entry's value (signed types sign-extended). `None` for other types and for
    /// UNSIGNED64 values above `i64::MAX`.
    pub fn int(&self, addr: ObjectAddress) -> Option<i64> {
        match self.value(addr)? {
            Value::Int(v) => Some(v),
            Value::Uint(v) => i64::try_from(v).ok(),
            _ => None,
        }
    }

    /// Set an integer entry (signed or unsigned) as the device itself; the value must fit the
    /// type (0x06090030). Does not allocate.
    pub fn set_int(&mut self, addr: ObjectAddress, v: i64) -> Result<(), SdoAbortCode> {
        self.set_value(addr, &Value::Int(v))
    }

    /// Set an unsigned entry as the device itself; the value must fit the type (0x06090030).
    /// Does not allocate.
    pub fn set_uint(&mut self, addr: ObjectAddress, v: u64) -> Result<(), SdoAbortCode> {
        self.set_value(addr, &Value::Uint(v))
    }

    /// The current PDO assignment and mapping: the PDOs listed in 0x1C12/0x1C13 entries
    /// 1..=sub 0, each with its mapping entries 1..=sub 0, read with the same
    /// [`read_mapping_sync`] a master uses on a drive. A direction whose assignment object does
    /// not exist is empty. Errors carry the abort code a master would have got for the entry.
    pub fn mapping(&self) -> Result<Mapping, ReadbackError<SdoAbortCode>> {
        read_mapping_sync(|address, _| {
            if address.sub == 0
                && pdo_object(address.index).is_some_and(|k| matches!(k, PdoObject::Assign(_)))
                && self.object_desc(address.index).is_none()
            {
                return Ok(0);
            }
            let e = self
                .entry_desc(address)
                .ok_or_else(|| self.missing(address))?;
            if !e.data_type.is_unsigned() {
                return Err(SdoAbortCode::LENGTH_MISMATCH);
            }
            let v = self.raw(address).map(le_u64).ok_or(SdoAbortCode::GENERAL)?;
            u32::try_from(v).map_err(|_| SdoAbortCode::VALUE_RANGE)
        })
    }

    /// The sub-0 value of an ARRAY/RECORD (0 if missing).
    fn count(&self, index: u16) -> u8 {
        self.raw(ObjectAddress::new(index, 0))
            .and_then(|b| b.first().copied())
            .unwrap_or(0)
    }

    /// Whether `addr` is in the current mapping of `dir`. Does not allocate.
    pub fn is_mapped(&self, dir: Direction, addr: ObjectAddress) -> bool {
        let ai = dir.assign_index();
        (1..=self.count(ai)).any(|s| {
            let pdo = self
                .raw(ObjectAddress::new(ai, s))
                .map_or(0, |b| le_u64(b) as u16);
            pdo_index_in(dir, pdo)
                && (1..=self.count(pdo)).any(|k| {
                    self.raw(ObjectAddress::new(pdo, k)).is_some_and(|b| {
                        let e = PdoEntry::from_u32(le_u64(b) as u32);
                        !e.is_padding() && e.address() == addr
                    })
                })
        })
    }

    /// Bits and entry count of PDO `pdo` with `n` entries.
    fn pdo_size(&self, pdo: u16, n: u8) -> (u64, u64) {
        let mut bits = 0u64;
        for k in 1..=n {
            let v = self.raw(ObjectAddress::new(pdo, k)).map_or(0, le_u64);
            bits += u64::from(PdoEntry::from_u32(v as u32).bits);
        }
        (bits, u64::from(n))
    }

    /// Check a mapping-entry value for direction `dir`: padding, or an existing entry
    /// mappable in `dir` with a matching bit length.
    fn check_mapping_entry(&self, dir: Direction, v: u32) -> Result<(), SdoAbortCode> {
        let pe = PdoEntry::from_u32(v);
        if pe.is_padding() {
            return Ok(());
        }
        let e = self
            .entry_desc(pe.address())
            .ok_or(SdoAbortCode::NOT_MAPPABLE)?;
        let flag = match dir {
            Direction::Rx => EntryAccess::RXPDO,
            Direction::Tx => EntryAccess::TXPDO,
        };
        if !e.access.contains(flag) {
            return Err(SdoAbortCode::NOT_MAPPABLE);
        }
        if e.bit_len != u16::from(pe.bits) {
            return Err(SdoAbortCode::LENGTH_MISMATCH);
        }
        Ok(())
    }

    /// Whether the PDOs `assigned` to direction `dir` stay within the limits (bytes and entries
    /// per direction), with PDO `changed.0` counted with `changed.1` entries instead of its
    /// current sub-0 value.
    fn check_limits(&self, dir: Direction, assigned: &[u16], changed: Option<(u16, u8)>) -> bool {
        let Some(lim) = self.limits.as_ref().map(|l| *l.direction(dir)) else {
            return true;
        };
        let (mut bits, mut entries) = (0u64, 0u64);
        for &p in assigned {
            let n = match changed {
                Some((cp, cn)) if cp == p => cn,
                _ => self.count(p),
            };
            let (b, e) = self.pdo_size(p, n);
            bits += b;
            entries += e;
        }
        bits.div_ceil(8) <= u64::from(lim.max_bytes) && entries <= u64::from(lim.max_entries)
    }

    /// Whether `index` is a mapping object of `dir` the device has: in the dictionary and,
    /// with limits, in one of the direction's ranges.
    fn pdo_exists(&self, dir: Direction, index: u16) -> bool {
        pdo_index_in(dir, index)
            && self.object_desc(index).is_some()
            && self
                .limits
                .as_ref()
                .is_none_or(|l| l.direction(dir).range_of(index).is_some())
    }

    fn assigned_indices(&self, dir: Direction, n: u8) -> Vec<u16> {
        let ai = dir.assign_index();
        (1..=n)
            .map(|s| {
                self.raw(ObjectAddress::new(ai, s))
                    .map_or(0, |b| le_u64(b) as u16)
            })
            .collect()
    }

    /// The standard PDO rules for a master write of `data` to `addr` (already checked for
    /// existence, access and length). See [`OdStore`] for the list.
    pub fn check_pdo_write(
        &self,
        addr: ObjectAddress,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        let Some(kind) = pdo_object(addr.index) else {
            return Ok(());
        };
        if state != AlState::PreOp {
            return Err(SdoAbortCode::DEVICE_STATE);
        }
        let v = le_u64(data);
        if let Some(l) = &self.limits {
            let writable = match kind {
                PdoObject::Assign(_) => l.assignment_writable,
                PdoObject::Map(_) => l.mapping_writable(addr.index),
            };
            if !writable {
                return Err(SdoAbortCode::READ_ONLY);
            }
        }
        match (kind, addr.sub) {
            (PdoObject::Map(_), s) | (PdoObject::Assign(_), s) if s > 0 => {
                if self.count(addr.index) != 0 {
                    return Err(SdoAbortCode::SUBINDEX0_NOT_ZERO);
                }
                match kind {
                    PdoObject::Map(dir) => {
                        if v != 0 {
                            self.check_mapping_entry(dir, v as u32)?;
                        }
                    }
                    PdoObject::Assign(dir) => {
                        let p = v as u16;
                        if p != 0 && !self.pdo_exists(dir, p) {
                            return Err(SdoAbortCode::VALUE_RANGE);
                        }
                    }
                }
                Ok(())
            }
            (PdoObject::Map(dir), _) => {
                let n = v as u8;
                if let Some(r) = self.limits.as_ref().and_then(|l| l.range_of(addr.index))
                    && n > r.max_entries
                {
                    return Err(SdoAbortCode::PDO_TOO_LONG);
                }
                for k in 1..=n {
                    let e = self
                        .raw(ObjectAddress::new(addr.index, k))
                        .map_or(0, le_u64) as u32;
                    if e == 0 {
                        // Sub 0 may not count entries that were never written.
                        return Err(SdoAbortCode::VALUE_TOO_HIGH);
                    }
                    self.check_mapping_entry(dir, e)?;
                }
                let mut assigned = self.assigned_indices(dir, self.count(dir.assign_index()));
                if !assigned.contains(&addr.index) {
                    assigned.clear();
                    assigned.push(addr.index);
                }
                if !self.check_limits(dir, &assigned, Some((addr.index, n))) {
                    return Err(SdoAbortCode::PDO_TOO_LONG);
                }
                Ok(())
            }
            (PdoObject::Assign(dir), _) => {
                let n = v as u8;
                if let Some(l) = &self.limits
                    && n > l.direction(dir).max_assigned
                {
                    return Err(SdoAbortCode::VALUE_TOO_HIGH);
                }
                let assigned = self.assigned_indices(dir, n);
                for &p in &assigned {
                    if p == 0 {
                        return Err(SdoAbortCode::VALUE_TOO_HIGH);
                    }
                    if !self.pdo_exists(dir, p) {
                        return Err(SdoAbortCode::VALUE_RANGE);
                    }
                }
                if !self.check_limits(dir, &assigned, None) {
                    return Err(SdoAbortCode::PDO_TOO_LONG);
                }
                Ok(())
            }
        }
    }
}

/// Length check of SDO bytes for an entry: fixed types exactly their size, strings up to the
/// entry size.
fn check_len(e: &EntryDesc, data: &[u8]) -> Result<(), SdoAbortCode> {
    let max = max_bytes(e);
    if e.data_type.is_string() {
        if data.len() > max {
            return Err(SdoAbortCode::LENGTH_TOO_HIGH);
        }
        return Ok(());
    }
    match data.len().cmp(&max) {
        core::cmp::Ordering::Greater => Err(SdoAbortCode::LENGTH_TOO_HIGH),
        core::cmp::Ordering::Less => Err(SdoAbortCode::LENGTH_TOO_LOW),
        core::cmp::Ordering::Equal => Ok(()),
    }
}

/// Range check against the descriptor's minimum and maximum.
fn check_range(e: &EntryDesc, data: &[u8]) -> Result<(), SdoAbortCode> {
    if e.data_type.is_string() {
        return Ok(());
    }
    let Ok(v) = Value::decode(e.data_type, data) else {
        return Err(SdoAbortCode::LENGTH_MISMATCH);
    };
    let below = |min: crate::od::ConstValue| match (&v, min) {
        (Value::Real(x), crate::od::ConstValue::Real(m)) => *x < m,
        (_, m) => match (v.as_i128(), m.as_i128()) {
            (Some(x), Some(m)) => x < m,
            _ => false,
        },
    };
    let above = |max: crate::od::ConstValue| match (&v, max) {
        (Value::Real(x), crate::od::ConstValue::Real(m)) => *x > m,
        (_, m) => match (v.as_i128(), m.as_i128()) {
            (Some(x), Some(m)) => x > m,
            _ => false,
        },
    };
    if below(e.min) {
        return Err(SdoAbortCode::VALUE_TOO_LOW);
    }
    if above(e.max) {
        return Err(SdoAbortCode::VALUE_TOO_HIGH);
    }
    Ok(())
}

/// Device-specific behaviour plugged into an [`OdStore`]. Every method has a default that does
/// nothing, so a hook implements only what its device needs. Hooks see the
/// [`ValueStore`] (values, mapping) and the AL state.
///
/// The order of a master write is: existence → access rights for the state → the PDO objects'
/// PRE-OP rule → length → [`OdHooks::before_write`] → minimum/maximum → sub 0 of
/// ARRAY/RECORD ≤ highest sub-index → the PDO mapping/assignment rules → store →
/// [`OdHooks::after_write`]. A read is: existence → access rights → [`OdHooks::on_read`] (which
/// may compute the value) → the stored value.
///
/// Examples that fit: refuse a download to an object mapped in the RxPDO (0x06010006), accept
/// only some cycle times in 0x1C32:02, refuse all writes to auto-set objects (0x06090030),
/// mirror 0x1C32:01 into 0x1C33:01, compute 0x6041 on read. Ready-made ones are in
/// [`super::hooks`].
pub trait OdHooks: Send {
    /// Called before a master write is stored; an error refuses it with that abort code.
    fn before_write(
        &mut self,
        dict: &ValueStore,
        addr: ObjectAddress,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        let _ = (dict, addr, state, data);
        Ok(())
    }

    /// Called after a master write was stored; may update other values.
    fn after_write(&mut self, dict: &mut ValueStore, addr: ObjectAddress, state: AlState) {
        let _ = (dict, addr, state);
    }

    /// Called on a master read after the access checks. `Some` replaces the stored value:
    /// `Ok(n)` with `n` bytes written into `buf`, or an abort.
    fn on_read(
        &mut self,
        dict: &ValueStore,
        addr: ObjectAddress,
        state: AlState,
        buf: &mut [u8],
    ) -> Option<Result<usize, SdoAbortCode>> {
        let _ = (dict, addr, state, buf);
        None
    }
}

/// Hooks that do nothing: a plain CiA 301 / ETG dictionary.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHooks;

impl OdHooks for NoHooks {}

/// A generic object dictionary served over CoE: a [`ValueStore`] built from
/// `&'static [ObjectDesc]` plus device [`OdHooks`].
///
/// Master accesses (through [`ObjectStore`]) are checked:
/// - object / sub-index existence: 0x06020000 / 0x06090011;
/// - access per AL state from [`EntryAccess`]: reading a write-only entry 0x06010001, writing a
///   read-only one 0x06010002, an access the current state does not allow 0x08000022;
/// - length: fixed types exactly their size (0x06070012 too long, 0x06070013 too short),
///   strings up to the entry size (0x06070012);
/// - range: below the minimum 0x06090032, above the maximum 0x06090031;
/// - sub 0 of an ARRAY/RECORD cannot exceed the highest sub-index (0x06090031).
///
/// And the standard PDO rules for 0x1C12/0x1C13 (assignment) and 0x1600–0x17FF/0x1A00–0x1BFF
/// (mapping):
/// - writable only in PRE-OP (0x08000022);
/// - entries 1.. may only be written while sub 0 is 0 (0x06010003);
/// - a mapping entry must be padding (index 0) or name an existing entry mappable in the PDO's
///   direction (0x06040041) whose size equals the entry's bit length. **Choice:** a bit-length
///   mismatch is 0x06070010 (length does not match), which names the actual fault better than
///   0x06040041;
/// - an assignment entry must name an existing PDO of the right direction. **Choice:**
///   0x06090030 (value range exceeded): the value is outside the PDO index range of the
///   direction, or names no PDO;
/// - sub 0 cannot exceed the number of written (non-zero) entries (0x06090031), and its entries
///   are checked again as above;
/// - with a drive's [`PdoLimits`] ([`OdStore::with_limits`]): the assigned PDOs of a direction
///   must stay within its byte and entry budget (0x06040042), checked when a mapping's or an
///   assignment's sub 0 is written; a mapping's sub 0 cannot exceed its range's entry count
///   (0x06040042); an assignment's sub 0 cannot exceed the PDOs per SyncManager (0x06090031);
///   an assignment entry must name a mapping object of the limits (0x06090030); a fixed mapping
///   or a fixed assignment refuses writes (0x06010002).
pub struct OdStore {
    dict: ValueStore,
    hooks: Box<dyn OdHooks>,
    /// [`Quirk::SyncObjectsAbsent`] / [`Quirk::CycleTimeReadOnly`] as the master sees them.
    sync_objects: SyncObjects,
    /// The device's own codes for standard refusals ([`OdStore::with_abort_codes`]).
    abort_codes: &'static [(SdoAbortCode, SdoAbortCode)],
    /// [`Quirk::InterpolationIndexReadOnly`].
    interpolation_index_read_only: bool,
    /// [`Quirk::PdoWritesIgnored`].
    pdo_writes_ignored: bool,
}

/// How 0x1C32/0x1C33 (the SyncManager parameters) appear to the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SyncObjects {
    AsDescribed,
    ReadOnly,
    Absent,
}

fn is_sync_object(index: u16) -> bool {
    matches!(index, 0x1C32 | 0x1C33)
}

impl core::fmt::Debug for OdStore {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("OdStore")
            .field("dict", &self.dict)
            .finish_non_exhaustive()
    }
}

impl OdStore {
    /// A store without device hooks.
    pub fn new(objects: &'static [ObjectDesc]) -> Result<Self, OdError> {
        Ok(Self {
            dict: ValueStore::new(objects)?,
            hooks: Box::new(NoHooks),
            sync_objects: SyncObjects::AsDescribed,
            abort_codes: &[],
            interpolation_index_read_only: false,
            pdo_writes_ignored: false,
        })
    }

    /// With the object-dictionary quirks among `quirks` ([`Quirk::CycleTimeReadOnly`],
    /// [`Quirk::SyncObjectsAbsent`]); the others are not the store's.
    pub fn with_quirks(mut self, quirks: Quirks) -> Self {
        self.set_quirks(quirks);
        self
    }

    /// [`with_quirks`](Self::with_quirks) on a store already built.
    pub fn set_quirks(&mut self, quirks: Quirks) {
        self.interpolation_index_read_only = quirks.has(Quirk::InterpolationIndexReadOnly);
        self.pdo_writes_ignored = quirks.has(Quirk::PdoWritesIgnored);
        self.sync_objects = if quirks.has(Quirk::SyncObjectsAbsent) {
            SyncObjects::Absent
        } else if quirks.has(Quirk::CycleTimeReadOnly) {
            SyncObjects::ReadOnly
        } else {
            SyncObjects::AsDescribed
        };
    }

    /// Whether the master sees the object at `index` (the device itself always does).
    fn visible(&self, index: u16) -> bool {
        !(self.sync_objects == SyncObjects::Absent && is_sync_object(index))
    }

    /// The access the master sees for entry `e` of the object at `index`.
    fn access(&self, index: u16, e: &EntryDesc) -> EntryAccess {
        if (self.sync_objects == SyncObjects::ReadOnly && is_sync_object(index) && e.sub == 2)
            || (self.interpolation_index_read_only && index == 0x60C2 && e.sub == 2)
        {
            e.access - EntryAccess::W
        } else {
            e.access
        }
    }

    /// With device hooks.
    pub fn with_hooks(mut self, hooks: impl OdHooks + 'static) -> Self {
        self.hooks = Box::new(hooks);
        self
    }

    /// With a drive's PDO limits (see the rules above).
    pub fn with_limits(mut self, limits: PdoLimits) -> Self {
        self.dict.set_limits(Some(limits));
        self
    }

    /// Answer with a device's own abort codes where it has one for a standard refusal:
    /// `(standard, the device's)`.
    pub fn with_abort_codes(mut self, codes: &'static [(SdoAbortCode, SdoAbortCode)]) -> Self {
        self.abort_codes = codes;
        self
    }

    fn device_code(&self, c: SdoAbortCode) -> SdoAbortCode {
        self.abort_codes
            .iter()
            .find(|(std, _)| *std == c)
            .map_or(c, |(_, own)| *own)
    }

    /// The dictionary (values, mapping).
    pub fn dict(&self) -> &ValueStore {
        &self.dict
    }

    /// The dictionary, mutable (device-side value updates).
    pub fn dict_mut(&mut self) -> &mut ValueStore {
        &mut self.dict
    }

    /// The current PDO assignment and mapping.
    pub fn mapping(&self) -> Result<Mapping, ReadbackError<SdoAbortCode>> {
        self.dict.mapping()
    }

    fn lookup(&self, index: u16, sub: u8) -> Result<&'static EntryDesc, SdoAbortCode> {
        if !self.visible(index) {
            return Err(SdoAbortCode::NO_OBJECT);
        }
        let obj = self
            .dict
            .object_desc(index)
            .ok_or(SdoAbortCode::NO_OBJECT)?;
        obj.entry(sub).ok_or(SdoAbortCode::NO_SUBINDEX)
    }
}

impl Deref for OdStore {
    type Target = ValueStore;

    fn deref(&self) -> &ValueStore {
        &self.dict
    }
}

impl DerefMut for OdStore {
    fn deref_mut(&mut self) -> &mut ValueStore {
        &mut self.dict
    }
}

impl ObjectStore for OdStore {
    fn object(&self, index: u16) -> Option<ObjectInfo> {
        if !self.visible(index) {
            return None;
        }
        let o = self.dict.object_desc(index)?;
        Some(ObjectInfo::describe(o))
    }

    fn entry(&self, index: u16, sub: u8) -> Result<EntryDesc, SdoAbortCode> {
        let mut e = *self.lookup(index, sub)?;
        e.access = self.access(index, &e);
        Ok(e)
    }

    fn next_index(&self, after: Option<u16>) -> Option<u16> {
        let start = match after {
            None => 0,
            Some(a) => match self.dict.objects.binary_search_by_key(&a, |o| o.index) {
                Ok(p) => p + 1,
                Err(p) => p,
            },
        };
        self.dict
            .objects
            .get(start..)
            .unwrap_or(&[])
            .iter()
            .map(|o| o.index)
            .find(|i| self.visible(*i))
    }

    fn read(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        buf: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        let e = self.lookup(index, sub)?;
        if !e.access.readable() {
            return Err(SdoAbortCode::WRITE_ONLY);
        }
        if !allowed_in(e.access, state, false) {
            return Err(SdoAbortCode::DEVICE_STATE);
        }
        let addr = ObjectAddress::new(index, sub);
        if let Some(r) = self.hooks.on_read(&self.dict, addr, state, buf) {
            return r;
        }
        let v = self.dict.raw(addr).ok_or(SdoAbortCode::GENERAL)?;
        let dst = buf.get_mut(..v.len()).ok_or(SdoAbortCode::OUT_OF_MEMORY)?;
        dst.copy_from_slice(v);
        Ok(v.len())
    }

    fn write(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        self.write_checked(index, sub, state, data)
            .map_err(|c| self.device_code(c))
    }
}

impl OdStore {
    fn write_checked(
        &mut self,
        index: u16,
        sub: u8,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        let obj = self
            .dict
            .object_desc(index)
            .filter(|_| self.visible(index))
            .ok_or(SdoAbortCode::NO_OBJECT)?;
        let e = obj.entry(sub).ok_or(SdoAbortCode::NO_SUBINDEX)?;
        if !self.access(index, e).writable() {
            return Err(SdoAbortCode::READ_ONLY);
        }
        if !allowed_in(e.access, state, true) {
            return Err(SdoAbortCode::DEVICE_STATE);
        }
        if pdo_object(index).is_some() && state != AlState::PreOp {
            return Err(SdoAbortCode::DEVICE_STATE);
        }
        check_len(e, data)?;
        if self.pdo_writes_ignored && pdo_object(index).is_some() {
            // Acknowledged, not taken.
            return Ok(());
        }
        let addr = ObjectAddress::new(index, sub);
        self.hooks.before_write(&self.dict, addr, state, data)?;
        check_range(e, data)?;
        if sub == 0 && obj.code != ObjectCode::Var {
            let highest = obj.entries.iter().map(|e| e.sub).max().unwrap_or(0);
            if data.first().copied().unwrap_or(0) > highest {
                return Err(SdoAbortCode::VALUE_TOO_HIGH);
            }
        }
        self.dict.check_pdo_write(addr, state, data)?;
        self.dict.set_raw(addr, data)?;
        self.hooks.after_write(&mut self.dict, addr, state);
        Ok(())
    }
}
