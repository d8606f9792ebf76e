//! CANopen (CiA 301) master and the CANopen drives, through the same [`crate::cia402`] layer.
//!
//! Not implemented yet: see issue 9.
