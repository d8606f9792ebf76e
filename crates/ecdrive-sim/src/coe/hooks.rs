//! Ready-made [`OdHooks`] for common device behaviour, combinable with [`Chain`]. A drive
//! profile describes its quirks as a list of these (data, not code).

use super::od_store::{OdHooks, ValueStore};
use crate::ec::AlState;
use crate::od::{ObjectAddress, SdoAbortCode};
use crate::pdo::Direction;

/// Several hooks in order: every `before_write` must pass (the first refusal wins), every
/// `after_write` runs, the first `on_read` that answers wins.
#[derive(Default)]
pub struct Chain(pub Vec<Box<dyn OdHooks>>);

impl Chain {
    /// An empty chain.
    pub fn new() -> Self {
        Self::default()
    }

    /// Append a hook.
    pub fn with(mut self, hook: impl OdHooks + 'static) -> Self {
        self.0.push(Box::new(hook));
        self
    }
}

impl OdHooks for Chain {
    fn before_write(
        &mut self,
        dict: &ValueStore,
        addr: ObjectAddress,
        state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        self.0
            .iter_mut()
            .try_for_each(|h| h.before_write(dict, addr, state, data))
    }

    fn after_write(&mut self, dict: &mut ValueStore, addr: ObjectAddress, state: AlState) {
        for h in &mut self.0 {
            h.after_write(dict, addr, state);
        }
    }

    fn on_read(
        &mut self,
        dict: &ValueStore,
        addr: ObjectAddress,
        state: AlState,
        buf: &mut [u8],
    ) -> Option<Result<usize, SdoAbortCode>> {
        self.0
            .iter_mut()
            .find_map(|h| h.on_read(dict, addr, state, buf))
    }
}

/// Refuse an SDO download to any entry currently mapped in a PDO of `direction` (MR-J4-TM:
/// RxPDO-mapped objects, abort 0x06010006).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RefuseMappedWrites {
    /// Which mapping blocks writes.
    pub direction: Direction,
    /// The abort code.
    pub code: SdoAbortCode,
}

impl OdHooks for RefuseMappedWrites {
    fn before_write(
        &mut self,
        dict: &ValueStore,
        addr: ObjectAddress,
        _state: AlState,
        _data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        if dict.is_mapped(self.direction, addr) {
            Err(self.code)
        } else {
            Ok(())
        }
    }
}

/// Refuse every master write to some objects or entries with one abort code (auto-set objects
/// that the manual lists as writable but that reject writes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RefuseWrites {
    /// Whole objects (every sub-index).
    pub objects: &'static [u16],
    /// Single entries.
    pub entries: &'static [ObjectAddress],
    /// The abort code.
    pub code: SdoAbortCode,
}

impl OdHooks for RefuseWrites {
    fn before_write(
        &mut self,
        _dict: &ValueStore,
        addr: ObjectAddress,
        _state: AlState,
        _data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        if self.objects.contains(&addr.index) || self.entries.contains(&addr) {
            Err(self.code)
        } else {
            Ok(())
        }
    }
}

/// Accept only a fixed set of values for one unsigned entry (e.g. the cycle times a drive
/// supports in 0x1C32:02).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AllowedValues {
    /// The entry.
    pub address: ObjectAddress,
    /// The accepted values.
    pub values: &'static [u64],
    /// The abort code for any other value.
    pub code: SdoAbortCode,
}

impl OdHooks for AllowedValues {
    fn before_write(
        &mut self,
        _dict: &ValueStore,
        addr: ObjectAddress,
        _state: AlState,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        if addr != self.address {
            return Ok(());
        }
        let mut raw = [0u8; 8];
        let n = data.len().min(8);
        if let (Some(d), Some(s)) = (raw.get_mut(..n), data.get(..n)) {
            d.copy_from_slice(s);
        }
        if self.values.contains(&u64::from_le_bytes(raw)) {
            Ok(())
        } else {
            Err(self.code)
        }
    }
}

/// Keep two entries equal: a master write to either is copied into the other (0x1C32:01 and
/// 0x1C33:01 on drives whose SM2 and SM3 share one synchronisation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mirror {
    /// One entry.
    pub a: ObjectAddress,
    /// The other, of the same type.
    pub b: ObjectAddress,
}

impl OdHooks for Mirror {
    fn after_write(&mut self, dict: &mut ValueStore, addr: ObjectAddress, _state: AlState) {
        let (from, to) = if addr == self.a {
            (self.a, self.b)
        } else if addr == self.b {
            (self.b, self.a)
        } else {
            return;
        };
        let mut buf = [0u8; 8];
        let Some(v) = dict.raw(from) else {
            return;
        };
        let n = v.len().min(8);
        if let (Some(d), Some(s)) = (buf.get_mut(..n), v.get(..n)) {
            d.copy_from_slice(s);
        }
        // Same type by construction; a mismatch (bad profile data) leaves `to` unchanged.
        if let Err(code) = dict.set_raw(to, buf.get(..n).unwrap_or(&[])) {
            tracing::warn!(%from, %to, %code, "mirror hook: entries of different types");
        }
    }
}
