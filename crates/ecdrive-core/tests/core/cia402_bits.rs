//! Statusword / controlword / mode decoding and encoding against the drive manuals' tables.

use crate::support::cia402_drives as drives;

use ecdrive_core::cia402::{
    Command, ControlWord, OperationMode, SetPointKind, State, StatusWord, SupportedModes,
};

/// Expand a manual pattern like `x0xx xxx0 x01x 0111` (bit 15 … bit 0) into every statusword it
/// stands for, by enumerating the x bits. Returns the concrete values.
fn expand(pattern: &str) -> Vec<u16> {
    let bits: Vec<char> = pattern.chars().filter(|c| !c.is_whitespace()).collect();
    assert_eq!(bits.len(), 16, "pattern {pattern}");
    let mut fixed = 0u16;
    let mut free = Vec::new();
    for (i, c) in bits.iter().enumerate() {
        let bit = 15 - i as u16;
        match c {
            '1' => fixed |= 1 << bit,
            '0' => {}
            'x' => free.push(bit),
            other => panic!("bad pattern char {other}"),
        }
    }
    (0u32..(1 << free.len()))
        .map(|n| {
            let mut v = fixed;
            for (k, bit) in free.iter().enumerate() {
                if n & (1 << k) != 0 {
                    v |= 1 << bit;
                }
            }
            v
        })
        .collect()
}

/// MR-J4-TM manual §5.3.1: the FSA patterns as printed (bits 8 and 14 shown as 0).
#[test]
fn mr_j4_statusword_patterns_decode_to_the_tabled_state() {
    let table = [
        ("x0xx xxx0 x0xx 0000", State::NotReadyToSwitchOn),
        ("x0xx xxx0 x1xx 0000", State::SwitchOnDisabled),
        ("x0xx xxx0 x01x 0001", State::ReadyToSwitchOn),
        ("x0xx xxx0 x01x 0011", State::SwitchedOn),
        ("x0xx xxx0 x01x 0111", State::OperationEnabled),
        ("x0xx xxx0 x00x 0111", State::QuickStopActive),
        ("x0xx xxx0 x0xx 1111", State::FaultReactionActive),
        ("x0xx xxx0 x0xx 1000", State::Fault),
    ];
    for (pattern, state) in table {
        let values = expand(pattern);
        assert!(!values.is_empty());
        for v in values {
            assert_eq!(
                StatusWord::from_raw(v).state(),
                Some(state),
                "MR-J4 pattern {pattern}: 0x{v:04X}"
            );
        }
    }
}

/// BDHDE manual §5.4: bits 6, 5, 3, 2, 1, 0 per state; every other bit free.
#[test]
fn bdhde_statusword_table_decodes_to_the_tabled_state() {
    // (b6, b5, b3, b2, b1, b0) with None = X.
    type Row = ([Option<u8>; 6], State);
    let table: [Row; 8] = [
        (
            [Some(0), None, Some(0), Some(0), Some(0), Some(0)],
            State::NotReadyToSwitchOn,
        ),
        (
            [Some(1), None, Some(0), Some(0), Some(0), Some(0)],
            State::SwitchOnDisabled,
        ),
        (
            [Some(0), Some(1), Some(0), Some(0), Some(0), Some(1)],
            State::ReadyToSwitchOn,
        ),
        (
            [Some(0), Some(1), Some(0), Some(0), Some(1), Some(1)],
            State::SwitchedOn,
        ),
        (
            [Some(0), Some(1), Some(0), Some(1), Some(1), Some(1)],
            State::OperationEnabled,
        ),
        (
            [Some(0), Some(0), Some(0), Some(1), Some(1), Some(1)],
            State::QuickStopActive,
        ),
        (
            [Some(0), None, Some(1), Some(1), Some(1), Some(1)],
            State::FaultReactionActive,
        ),
        (
            [Some(0), None, Some(1), Some(0), Some(0), Some(0)],
            State::Fault,
        ),
    ];
    let positions = [6u16, 5, 3, 2, 1, 0];
    for (row, state) in table {
        for sw in 0u32..=0xFFFF {
            let sw = sw as u16;
            let matches = row
                .iter()
                .zip(positions)
                .all(|(want, bit)| want.is_none_or(|w| u16::from(w) == (sw >> bit) & 1));
            if matches {
                assert_eq!(StatusWord::from_raw(sw).state(), Some(state), "0x{sw:04X}");
            }
        }
    }
}

/// The BDHDE typical values (§6.1 [REC] of the reference, with bits 4 and 9 set).
#[test]
fn bdhde_typical_statuswords() {
    let typical = [
        (0x0250, State::SwitchOnDisabled),
        (0x0231, State::ReadyToSwitchOn),
        (0x0233, State::SwitchedOn),
        (0x0237, State::OperationEnabled),
        (0x0217, State::QuickStopActive),
        (0x021F, State::FaultReactionActive),
        (0x0218, State::Fault),
    ];
    for (sw, state) in typical {
        assert_eq!(StatusWord::from_raw(sw).state(), Some(state), "0x{sw:04X}");
    }
}

/// All 65 536 statuswords decode without panic; exactly the tabled patterns decode to a state,
/// and each decoded state re-encodes to the same state bits.
#[test]
fn all_statuswords_decode() {
    let mut per_state = [0u32; 8];
    let mut undefined = 0u32;
    for raw in 0u32..=0xFFFF {
        let sw = StatusWord::from_raw(raw as u16);
        match sw.state() {
            Some(s) => {
                let idx = State::ALL.iter().position(|x| *x == s).unwrap();
                per_state[idx] += 1;
                // Re-encoding the state keeps the other bits and decodes to the same state.
                assert_eq!(sw.with_state(s).state(), Some(s));
                assert_eq!(sw.with_state(s).raw() & !0x006F, sw.raw() & !0x006F);
            }
            None => undefined += 1,
        }
    }
    // 0x4F-masked states leave 11 bits free (2048 values), 0x6F-masked ones 10 bits (1024).
    assert_eq!(per_state, [2048, 2048, 1024, 1024, 1024, 1024, 2048, 2048]);
    assert_eq!(undefined, 65536 - 12 * 1024);
}

#[test]
fn canonical_state_bits_round_trip() {
    for s in State::ALL {
        assert_eq!(State::from_statusword(s.statusword_bits()), Some(s));
    }
}

/// Command values from the MR-J4-TM (§5.1), BDHDE (§5.5) and BLV-R (§6) command tables.
#[test]
fn command_values_from_the_tables() {
    let table = [
        (Command::Shutdown, 0x0006),
        (Command::SwitchOn, 0x0007),
        (Command::EnableOperation, 0x000F),
        (Command::DisableVoltage, 0x0000),
        (Command::QuickStop, 0x0002),
        (Command::DisableOperation, 0x0007),
        (Command::FaultReset, 0x0080),
    ];
    for (cmd, value) in table {
        assert_eq!(cmd.bits(), value, "{cmd}");
        assert_eq!(cmd.controlword().raw(), value);
    }
    assert_eq!(Command::Shutdown.transitions(), &[2, 6, 8]);
    assert_eq!(Command::DisableVoltage.transitions(), &[7, 9, 10, 12]);
    assert_eq!(Command::QuickStop.transitions(), &[7, 10, 11]);
    assert_eq!(Command::EnableOperation.transitions(), &[4, 16]);
    assert_eq!(Command::FaultReset.transitions(), &[15]);
}

/// Decoding every controlword pattern by the table: (b7, b3, b2, b1, b0) with x = don't care.
#[test]
fn command_decoding_follows_the_table() {
    for raw in 0u32..=0xFFFF {
        let cw = ControlWord::from_raw(raw as u16);
        let b = |n: u32| (raw >> n) & 1;
        let expected = if b(7) == 1 {
            Command::FaultReset
        } else if b(1) == 0 {
            Command::DisableVoltage // 0 x x 0 x
        } else if b(2) == 0 {
            Command::QuickStop // 0 x 0 1 x
        } else if b(0) == 0 {
            Command::Shutdown // 0 x 1 1 0
        } else if b(3) == 0 {
            Command::SwitchOn // 0 0 1 1 1
        } else {
            Command::EnableOperation // 0 1 1 1 1
        };
        assert_eq!(Command::decode(cw), expected, "0x{raw:04X}");
    }
    // The typical values decode to themselves.
    for cmd in Command::ALL {
        let decoded = Command::decode(cmd.controlword());
        let expected = if cmd == Command::DisableOperation {
            Command::SwitchOn
        } else {
            cmd
        };
        assert_eq!(decoded, expected);
    }
}

/// Writing a command never touches the mode-specific, halt, reserved or manufacturer bits.
#[test]
fn command_apply_keeps_mode_specific_bits() {
    for raw in 0u32..=0xFFFF {
        let cw = ControlWord::from_raw(raw as u16);
        for cmd in Command::ALL {
            let out = cmd.apply(cw);
            assert_eq!(out.raw() & !0x008F, cw.raw() & !0x008F);
            assert_eq!(out.raw() & 0x008F, cmd.bits());
        }
    }
    let pp = ControlWord::NEW_SET_POINT | ControlWord::CHANGE_SET_IMMEDIATELY | ControlWord::HALT;
    assert_eq!(Command::EnableOperation.apply(pp).raw(), 0x013F);
    assert_eq!(
        ControlWord::from_raw(0xFFFF).mode_specific().raw(),
        ControlWord::MODE_SPECIFIC_MASK
    );
}

#[test]
fn mode_specific_bit_aliases() {
    assert_eq!(ControlWord::NEW_SET_POINT.raw(), 1 << 4);
    assert_eq!(ControlWord::HOMING_START.raw(), 1 << 4);
    assert_eq!(ControlWord::CHANGE_SET_IMMEDIATELY.raw(), 1 << 5);
    assert_eq!(ControlWord::RELATIVE.raw(), 1 << 6);
    assert_eq!(ControlWord::HALT.raw(), 1 << 8);
    assert_eq!(StatusWord::TARGET_REACHED.raw(), 1 << 10);
    assert_eq!(StatusWord::INTERNAL_LIMIT_ACTIVE.raw(), 1 << 11);
    assert_eq!(StatusWord::SET_POINT_ACKNOWLEDGE.raw(), 1 << 12);
    assert_eq!(StatusWord::DRIVE_FOLLOWS_COMMAND.raw(), 1 << 12);
    assert_eq!(StatusWord::FOLLOWING_ERROR.raw(), 1 << 13);
    assert_eq!(StatusWord::WARNING.raw(), 1 << 7);
    assert_eq!(StatusWord::REMOTE.raw(), 1 << 9);
}

/// 0x6060 values (CiA 402; MR-J4-TM §7.3.8(6) adds −100, −101, −103).
#[test]
fn operation_mode_values() {
    let table = [
        (0, OperationMode::NoMode, "none"),
        (1, OperationMode::ProfilePosition, "pp"),
        (2, OperationMode::Velocity, "vl"),
        (3, OperationMode::ProfileVelocity, "pv"),
        (4, OperationMode::ProfileTorque, "tq"),
        (6, OperationMode::Homing, "hm"),
        (7, OperationMode::InterpolatedPosition, "ip"),
        (8, OperationMode::CyclicSyncPosition, "csp"),
        (9, OperationMode::CyclicSyncVelocity, "csv"),
        (10, OperationMode::CyclicSyncTorque, "cst"),
        (11, OperationMode::CyclicSyncTorqueCommutation, "cstca"),
    ];
    for (v, mode, name) in table {
        assert_eq!(OperationMode::from_i8(v), mode);
        assert_eq!(mode.as_i8(), v);
        assert_eq!(mode.short_name(), name);
    }
    for v in i8::MIN..=i8::MAX {
        let m = OperationMode::from_i8(v);
        assert_eq!(m.as_i8(), v, "round trip {v}");
        if v < 0 {
            assert!(matches!(m, OperationMode::Vendor(x) if x == v));
        }
        if v == 5 || v >= 12 {
            assert!(matches!(m, OperationMode::Reserved(x) if x == v));
        }
    }
    assert_eq!(OperationMode::Vendor(-101).to_string(), "vendor (-101)");
    assert_eq!(OperationMode::CyclicSyncPosition.to_string(), "csp (8)");
    assert_eq!(
        OperationMode::CyclicSyncTorque.set_point_kind(),
        Some(SetPointKind::Torque)
    );
    assert_eq!(OperationMode::Homing.set_point_kind(), None);
    assert!(OperationMode::Homing.is_position_mode());
    assert!(!OperationMode::CyclicSyncVelocity.is_position_mode());
}

/// 0x6502 of each drive: MR-J4-TM 0x000B03AD (§7.1 of the reference, derived from §7.3.8),
/// BDHDE 941 = 0x3AD (§9 6502h), BLV-R 0x2D (fw ≥ 4.00) / 0x25.
#[test]
fn supported_modes_of_the_drives() {
    use OperationMode::*;
    let mr = drives::MR_J4_TM.supported_modes;
    let mr_modes: Vec<OperationMode> = mr.iter().collect();
    assert_eq!(
        mr_modes,
        vec![
            ProfilePosition,
            ProfileVelocity,
            ProfileTorque,
            Homing,
            CyclicSyncPosition,
            CyclicSyncVelocity,
            CyclicSyncTorque,
            Vendor(-100),
            Vendor(-101),
            Vendor(-103),
        ]
    );
    assert!(!mr.contains(Vendor(-102)));
    assert!(!mr.contains(Velocity));
    assert!(!mr.contains(InterpolatedPosition));
    assert_eq!(mr.unmapped_vendor_bits(), 0);
    assert!(drives::MR_J4_TM.is_position_mode(Vendor(-101)));
    assert!(drives::MR_J4_TM.is_position_mode(Homing));
    assert!(!drives::MR_J4_TM.is_position_mode(Vendor(-100)));
    assert!(!drives::MR_J4_TM.is_position_mode(CyclicSyncTorque));

    let bd = drives::BDHDE.supported_modes;
    assert_eq!(bd.raw(), 941);
    assert_eq!(bd.iter().count(), 7);
    assert!(
        !bd.contains(InterpolatedPosition),
        "BDHDE: ip 'not supported'"
    );
    assert!(!bd.contains(Velocity));

    let blv = drives::BLV_R.supported_modes;
    assert_eq!(
        blv.iter().collect::<Vec<_>>(),
        vec![ProfilePosition, ProfileVelocity, ProfileTorque, Homing]
    );
    assert!(!SupportedModes::from_raw(0x25).contains(ProfileTorque));
    assert!(!blv.contains(CyclicSyncPosition));

    // Vendor bits without a mapping are reported, not guessed.
    let raw = SupportedModes::from_raw(0x000B_03AD);
    assert!(!raw.contains(Vendor(-100)));
    assert_eq!(raw.unmapped_vendor_bits(), 0x000B_0000);
    // No-mode and reserved values are never supported.
    assert!(!SupportedModes::from_raw(u32::MAX).contains(NoMode));
    assert!(!SupportedModes::from_raw(u32::MAX).contains(Reserved(5)));
}
