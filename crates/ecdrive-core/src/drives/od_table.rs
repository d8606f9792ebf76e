//! Short names for writing object-dictionary tables as data (crate-private).

use crate::od::{ConstValue, DataType, EntryAccess};

pub(crate) const U8: DataType = DataType::Unsigned8;
pub(crate) const U16: DataType = DataType::Unsigned16;
pub(crate) const U32: DataType = DataType::Unsigned32;
pub(crate) const I8: DataType = DataType::Integer8;
pub(crate) const I16: DataType = DataType::Integer16;
pub(crate) const I32: DataType = DataType::Integer32;
pub(crate) const VSTR: DataType = DataType::VisibleString;

/// Read-only in every state.
pub(crate) const RO: EntryAccess = EntryAccess::RO;
/// Read-only, TxPDO-mappable.
pub(crate) const RO_TX: EntryAccess = EntryAccess::RO.union(EntryAccess::TXPDO);
/// Read-write in every state.
pub(crate) const RW: EntryAccess = EntryAccess::RW;
/// Read-write in every state, RxPDO-mappable.
pub(crate) const RW_RX: EntryAccess = EntryAccess::RW.union(EntryAccess::RXPDO);
/// Read-write in every state, TxPDO-mappable (MR-J4-TM 0x2B01).
pub(crate) const RW_TX: EntryAccess = EntryAccess::RW.union(EntryAccess::TXPDO);
/// Readable always, writable in PRE-OP only.
pub(crate) const RW_PREOP: EntryAccess = EntryAccess::RW_PREOP;
/// Write-only.
pub(crate) const WO: EntryAccess = EntryAccess::WO;

/// An unsigned constant.
pub(crate) const fn u(v: u64) -> ConstValue {
    ConstValue::Uint(v)
}

/// A signed constant.
pub(crate) const fn i(v: i64) -> ConstValue {
    ConstValue::Int(v)
}
