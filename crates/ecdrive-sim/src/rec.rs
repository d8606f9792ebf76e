//! The software slave's own choices (\[REC\]): values neither the ESC datasheet, the ETG
//! documents nor the drive manuals give, chosen for the emulation. Kept here, in one place,
//! so that nobody mistakes them for vendor facts.
//!
//! Values that *are* datasheet facts (register reset values such as the watchdog divider
//! 0x09C2 and the SM watchdog time 1000) live with the register code in [`super::esc`].

/// \[REC\] Vendor ID of ecdrive's generic test devices. Not an ETG-assigned ID.
pub const TEST_VENDOR_ID: u32 = 0x0000_0ECD;

/// \[REC\] ESC type reported in register 0x0000 (0x04, as the Beckhoff IP core and KickCAT's
/// emulated ESC report).
pub const ESC_TYPE: u8 = 0x04;
/// \[REC\] ESC revision (0x0001).
pub const ESC_REVISION: u8 = 0x01;
/// \[REC\] ESC build (0x0002).
pub const ESC_BUILD: u16 = 0x0001;
/// \[REC\] FMMUs per ESC (0x0004): 8, enough for ethercrab's SM-indexed FMMUs and SOEM.
pub const FMMU_COUNT: u8 = 8;
/// \[REC\] SyncManagers per ESC (0x0005).
pub const SM_COUNT: u8 = 8;
/// \[REC\] Process RAM in KiB (0x0006).
pub const RAM_KIB: u8 = 8;

/// \[REC\] Port-to-port forwarding delay of one emulated slave in ns (KickCAT uses the same),
/// which is what DC propagation-delay measurement sees.
pub const HOP_DELAY_NS: u32 = 300;

/// \[REC\] DC drift loop: proportional gain as a right shift (1/2 of the difference per
/// update).
pub const DC_KP_SHIFT: i64 = 1;
/// \[REC\] DC drift loop: the integral term learns 1/50 of the observed rate error per update.
pub const DC_KI_DIV: i64 = 50;
/// \[REC\] DC drift loop: the rate correction changes by at most this many ppb per update,
/// which keeps the loop stable when updates come at irregular intervals (a loaded machine).
/// Gains and limits were chosen by simulating drifts up to ±200 ppm with update intervals
/// from 20 µs to 200 ms: the difference settles below 20 ns.
pub const DC_MAX_RATE_STEP_PPB: i64 = 10_000;
/// \[REC\] DC drift loop: rate corrections are learned only from updates at least this many ns
/// apart (static drift compensation sends its FRMWs back to back).
pub const DC_KI_MIN_INTERVAL_NS: u64 = 50_000;
/// \[REC\] DC drift loop: largest rate correction in ppb (±1000 ppm).
pub const DC_MAX_RATE_PPB: i64 = 1_000_000;
/// \[REC\] DC drift loop: smallest per-update step limit in ns (the limit is otherwise 1000 ppm
/// of the time since the previous update).
pub const DC_MIN_STEP_NS: i64 = 200;

/// \[REC\] Smallest SYNC0 cycle the generic CoE device accepts (its 0x1C32:05), in ns.
pub const GENERIC_COE_MIN_CYCLE_NS: u32 = 125_000;
