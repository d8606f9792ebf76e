//! Real-time support: thread set-up, absolute-time sleeping, cycle statistics.
