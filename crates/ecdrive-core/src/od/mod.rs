//! CANopen / CoE object dictionary types (CiA 301, ETG.1000.6): object addresses, data types,
//! access rights, static object descriptions and a [`Dictionary`] view over them, runtime values,
//! SDO abort codes and the segmented SDO transfer ([`Segmented`]) both buses use.
//!
//! These types are shared by the drive profiles (which describe what a drive's dictionary holds),
//! the software slave (which serves a dictionary over CoE) and the master (which reads and writes
//! one).

mod abort;
mod address;
mod desc;
mod dictionary;
mod emergency;
mod segmented;
pub mod standard;
mod types;
mod value;

pub use abort::SdoAbortCode;
pub use address::{AddressParseError, ObjectAddress};
pub use desc::{EntryAccess, EntryDesc, ObjectCode, ObjectDesc, ObjectInfo};
pub use dictionary::{Dictionary, DictionaryError};
pub use emergency::{Emergency, EmergencyLengthError};
pub use segmented::{Segment, SegmentError, Segmented};
pub use types::DataType;
pub use value::{ConstValue, Value, ValueError};
