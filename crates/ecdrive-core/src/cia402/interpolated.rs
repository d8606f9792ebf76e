//! Interpolated position mode (ip, 6060h = 7): one position per SYNC period.
//!
//! CiA 402: controlword bit 4 = enable ip; statusword bit 12 = ip mode active. The ASDA-A2's ip
//! (the only ip among the three CANopen drives, §3.2, §5.2) differs: it does **not** use bit 4 —
//! interpolation runs whenever mode 7 is active and data arrives — and reports bit 12 = ip mode
//! active and the vendor bit 14 = SYNC OK (the SYNC arrived before the path generator started).
//! The position goes to 60C1h:01 (interpolation data record), written every SYNC period before
//! the SYNC; with sub-mode 60C0h = 0 (P1-01 = 0x0C) the drive interpolates linearly and needs no
//! velocity term. The drive has no input buffer: a missing value is extrapolated, two missing
//! SYNCs stop it with an error (AL301–AL305).
//!
//! [`Interpolation`] feeds the [`Axis`] one position per cycle ([`Axis::set_position`]; the
//! master writes the axis' target position into 60C1h:01 and/or 607Ah, whichever is mapped) and
//! sets bit 4 for drives that need it.

use super::axis::Axis;
use super::bits::{ControlWord, StatusWord};
use super::mode::OperationMode;

/// Controlword bit 4 in ip: enable ip mode.
pub const ENABLE_IP: ControlWord = ControlWord::from_raw(1 << 4);
/// Statusword bit 12 in ip: ip mode active.
pub const IP_ACTIVE: StatusWord = StatusWord::from_raw(1 << 12);
/// Statusword bit 14 on the ASDA-A2 in ip: SYNC OK (vendor).
pub const SYNC_OK: StatusWord = StatusWord::from_raw(1 << 14);

/// What the ip status bits say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IpStatus {
    /// Bit 12: ip mode active.
    pub active: bool,
    /// Bit 14 (ASDA-A2): SYNC OK.
    pub sync_ok: bool,
    /// Bit 13: following error.
    pub following_error: bool,
    /// Whether the axis took this cycle's position.
    pub streaming: bool,
}

/// The ip feeder.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Interpolation {
    enable_bit: bool,
    enabled: bool,
}

impl Interpolation {
    /// A feeder; `enable_bit`: the drive needs controlword bit 4 = 1 to interpolate (CiA);
    /// `false` for the ASDA-A2.
    pub const fn new(enable_bit: bool) -> Self {
        Self {
            enable_bit,
            enabled: true,
        }
    }

    /// Enable or suspend interpolation (bit 4 on drives that use it). Suspended, the feeder
    /// holds the last position.
    pub fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
    }

    /// One cycle, before [`Axis::step`]: hand `position` (the path point for the next SYNC) to
    /// the axis.
    pub fn step(&mut self, axis: &mut Axis, sw: StatusWord, position: i32) -> IpStatus {
        let st = axis.status();
        let active = st.streaming && st.active_mode == OperationMode::InterpolatedPosition;
        if active {
            if self.enabled {
                let _ = axis.set_position(position);
            }
            let bits = if self.enable_bit && self.enabled {
                ENABLE_IP
            } else {
                ControlWord::empty()
            };
            axis.set_mode_bits(bits);
        }
        IpStatus {
            active: sw.contains(IP_ACTIVE),
            sync_ok: sw.contains(SYNC_OK),
            following_error: sw.contains(StatusWord::FOLLOWING_ERROR),
            streaming: active,
        }
    }
}

/// A linear path from `from` to `to` over `cycles` cycles, one point per cycle, for ip: the
/// point for cycle `k` (clamped to `to` after the end). Pure integer arithmetic.
pub fn linear_point(from: i32, to: i32, cycles: u32, k: u32) -> i32 {
    if cycles == 0 || k >= cycles {
        return to;
    }
    let d = i64::from(to) - i64::from(from);
    let p = i64::from(from) + d * i64::from(k) / i64::from(cycles);
    i32::try_from(p).unwrap_or(to)
}

// ---------------------------------------------------------------------------------------------
// 0x60C2 interpolation time period: `:01 × 10^(:02)` s (CiA 402).

/// The standard 0x60C2 form of `cycle_ns`: `(value, index)` with `value × 10^index` s, the
/// largest index from −3 down to −9 that keeps `value` an integer of at most 255, never `avoid`
/// (a vendor's own reading of that index, e.g. the BDHDE's 250 µs unit for −4).
/// `None` when the cycle has no such form.
pub fn interpolation_standard_form(cycle_ns: u32, avoid: Option<i8>) -> Option<(u8, i8)> {
    (-9i8..=-3)
        .rev()
        .filter(|i| Some(*i) != avoid)
        .find_map(|index| {
            let unit = 10u64.pow(u32::from((9 + index) as u8));
            let c = u64::from(cycle_ns);
            (c % unit == 0)
                .then(|| c / unit)
                .and_then(|v| u8::try_from(v).ok())
                .filter(|v| *v > 0)
                .map(|v| (v, index))
        })
}

/// The cycle a drive's 0x60C2 tells, ns: `value × unit_ns` while `index` is the vendor's
/// (`vendor = Some((index, unit_ns))`), `value × 10^index` s otherwise.
pub fn interpolation_cycle_ns(value: u64, index: i8, vendor: Option<(i8, u32)>) -> Option<u64> {
    match vendor {
        Some((i, unit)) if i == index => value.checked_mul(u64::from(unit)),
        _ if (-9..=0).contains(&index) => {
            value.checked_mul(10u64.pow(u32::from((9 + index) as u8)))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cia402::mode_test_support::Rig;

    #[test]
    fn delta_ip_has_no_enable_bit_and_reads_sync_ok() {
        let mut rig = Rig::enabled(OperationMode::InterpolatedPosition);
        let mut ip = Interpolation::new(false);
        rig.extra = IP_ACTIVE | SYNC_OK;
        let s = rig.statusword();
        let st = ip.step(&mut rig.axis, s, 1234);
        assert!(st.active && st.sync_ok && st.streaming);
        let o = rig.cycle();
        assert_eq!(o.target_position, 1234);
        assert!(!o.controlword.contains(ENABLE_IP));
    }

    #[test]
    fn cia_ip_sets_bit_4() {
        let mut rig = Rig::enabled(OperationMode::InterpolatedPosition);
        let mut ip = Interpolation::new(true);
        let s = rig.statusword();
        ip.step(&mut rig.axis, s, 10);
        assert!(rig.cycle().controlword.contains(ENABLE_IP));
        ip.set_enabled(false);
        let s = rig.statusword();
        ip.step(&mut rig.axis, s, 99);
        let o = rig.cycle();
        assert!(!o.controlword.contains(ENABLE_IP));
        assert_eq!(o.target_position, 10, "suspended: last position held");
    }

    #[test]
    fn linear_points() {
        assert_eq!(linear_point(0, 100, 4, 0), 0);
        assert_eq!(linear_point(0, 100, 4, 2), 50);
        assert_eq!(linear_point(0, 100, 4, 4), 100);
        assert_eq!(linear_point(0, 100, 4, 9), 100);
        assert_eq!(linear_point(i32::MIN, i32::MAX, 2, 1), -1);
        assert_eq!(linear_point(5, -5, 0, 0), -5);
    }
}
