//! Behaviour of devices that ecdrive did not write, switchable on the emulated devices.
//!
//! The emulated drives are built from the master's own profile data, so a master run against
//! them shows agreement, not correctness. Real devices differ in ways the standards allow (or
//! tolerate): a quirk makes an emulated device behave like one of them, so that the master is
//! tested against behaviour it did not write. Each quirk is a plain switch; a device applies the
//! ones that concern it (a device without a mailbox has no SDO information to break) and
//! refuses the others when it is built ([`Quirks::check_for`]).
//!
//! By name, a device takes quirks after a `+`: `bdhde+no-state-skipping`,
//! `mr-j4-tm+cycle-time-read-only+stale-inputs-until-op` (`ecdrive sim --device`, `-i sim:…`,
//! `[sim] devices`). In the library: [`Quirks`] and each device's `with_quirks`. An emulated
//! drive also takes parameters stored in its non-volatile memory after an `@`
//! (`mr-j4-tm@0x2001=2`, [`stored_params`]).
//!
//! | quirk | what the device does | seen on |
//! |---|---|---|
//! | `no-state-skipping` | only the standard CiA 402 transitions; Switch on / Enable operation from Switch on disabled are ignored | most CiA 402 drives (skipping is optional) |
//! | `cycle-time-read-only` | 0x1C32:02 and 0x1C33:02 (cycle time) are read-only (writes: abort 0x06010002): they keep their default until SYNC0 runs and then show the SYNC0 cycle (ESC 0x09A0), as ETG.1020 describes for a slave that does not take the cycle by SDO | devices whose ESI declares 0x1C32:02 read-only (Ingenia's) |
//! | `sync-objects-absent` | no 0x1C32/0x1C33 at all (abort 0x06020000; not in the object list) | simple slaves that synchronise by the ESC registers only |
//! | `no-sdo-info` | SDO information requests get the mailbox error "service not supported"; the SII no longer advertises it | small slave stacks |
//! | `sdo-info-bad-entry` | the entry description of 0x1018:02 is answered by an SDO information error with code 0x00000000 | a foreign slave seen in the field |
//! | `sdo-info-short-entry` | the entry description of 0x1018:03 is cut after its value-info byte (no data type, bit length, access) | the same |
//! | `no-complete-access` | complete access is refused (abort 0x06010000, as a stack without it answers) although the SII advertises it | devices with an optimistic EEPROM |
//! | `odd-abort` | SDO aborts come as CoE service 2 (SDO request) with reserved bits set in the command byte (0x9F) | stacks that reuse the request path for aborts |
//! | `stale-inputs-until-op` | below OP the input image is not updated: it keeps what it held (zeros after power-on) | slaves that serve inputs only in OP |
//! | `outputs-in-safeop` | the outputs are applied already in SAFE-OP (the CiA 402 state machine follows the controlword there) | slaves that do not treat SAFE-OP outputs as safe state |
//! | `following-error-zero` | 0x60F4 can be mapped but always reads 0 | drives that do not compute it in every mode |
//! | `interpolation-index-read-only` | 0x60C2:02 (interpolation time index) is read-only at its power-on value | the BDHDE as its object table prints it |
//! | `outputs-only-in-op` | the output SyncManager is enabled with OP only: in SAFE-OP the outputs are not taken and do not count in the working counter | a stack that starts its output handler with OP (what this emulator did until KickCAT showed it) |
//! | `modes-only-when-disabled` | 0x6060 is taken only outside Operation enabled: a switch asked for while enabled is never shown in 0x6061 | drives whose firmware changes the mode only with the power stage off |
//! | `pdo-writes-ignored` | writes to the PDO assignment and mapping (0x1C12/0x1C13, 0x1600–0x17FF, 0x1A00–0x1BFF) are acknowledged and not taken: the mapping stays the power-on one | firmware that accepts a remap it does not support; the case ecdrive's answered re-read of the mapping leaves to the drive's own SAFE-OP check |
//! | `op-needs-sync0` | SAFE-OP → OP is refused with AL status code 0x002D (no sync) while SYNC0 is activated but has not yet fired | slave stacks that check for SYNC0 events before OP; the MR-J4-TM manual §1.4.2 (7) has DC synchronisation established in SAFE-OP before OP |

use core::fmt;

/// One foreign-device behaviour. See the [module documentation](self).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Quirk {
    /// Only the standard CiA 402 transitions.
    NoStateSkipping,
    /// 0x1C32:02/0x1C33:02 read-only, showing the SYNC0 cycle once it runs.
    CycleTimeReadOnly,
    /// No 0x1C32/0x1C33.
    SyncObjectsAbsent,
    /// No SDO information service.
    NoSdoInfo,
    /// One entry description answered by an SDO information error with code 0.
    SdoInfoBadEntry,
    /// One entry description cut short.
    SdoInfoShortEntry,
    /// Complete access refused although the SII advertises it.
    NoCompleteAccess,
    /// SDO aborts as CoE service 2 with reserved command bits set.
    OddAbort,
    /// The input image is updated only in OP.
    StaleInputsUntilOp,
    /// Outputs applied already in SAFE-OP.
    OutputsInSafeOp,
    /// 0x60F4 always 0.
    FollowingErrorZero,
    /// 0x60C2:02 read-only.
    InterpolationIndexReadOnly,
    /// SAFE-OP → OP refused (0x002D) until SYNC0 has fired.
    OpNeedsSync0,
    /// The machine around the motor has no home switch.
    NoHomeSwitch,
    /// The output SM is enabled with OP only.
    OutputsOnlyInOp,
    /// 0x6060 taken only outside Operation enabled.
    ModesOnlyWhenDisabled,
    /// PDO assignment and mapping writes acknowledged and not taken.
    PdoWritesIgnored,
}

/// The entry whose description [`Quirk::SdoInfoBadEntry`] breaks: every CoE device has it.
pub const BAD_INFO_ENTRY: (u16, u8) = (0x1018, 2);
/// The entry whose description [`Quirk::SdoInfoShortEntry`] cuts short.
pub const SHORT_INFO_ENTRY: (u16, u8) = (0x1018, 3);
/// The command byte of an SDO abort under [`Quirk::OddAbort`]: specifier 4 (abort) in bits
/// 5–7, the reserved bits 0–4 set.
pub const ODD_ABORT_COMMAND: u8 = 0x9F;

/// What a quirk needs of a device to apply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Needs {
    /// Any device with process data.
    ProcessData,
    /// A CoE mailbox.
    Coe,
    /// A CiA 402 drive.
    Cia402,
    /// A drive that computes 0x60F4.
    FollowingError,
}

/// What a device has, for [`Quirks::check_for`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Capabilities {
    /// A CoE mailbox.
    pub coe: bool,
    /// CiA 402 device control.
    pub cia402: bool,
    /// 0x60F4 (following error actual value).
    pub following_error: bool,
}

impl Quirk {
    /// Every quirk, in the order of the table above.
    pub const ALL: [Quirk; 17] = [
        Quirk::NoStateSkipping,
        Quirk::CycleTimeReadOnly,
        Quirk::SyncObjectsAbsent,
        Quirk::NoSdoInfo,
        Quirk::SdoInfoBadEntry,
        Quirk::SdoInfoShortEntry,
        Quirk::NoCompleteAccess,
        Quirk::OddAbort,
        Quirk::StaleInputsUntilOp,
        Quirk::OutputsInSafeOp,
        Quirk::FollowingErrorZero,
        Quirk::InterpolationIndexReadOnly,
        Quirk::OpNeedsSync0,
        Quirk::NoHomeSwitch,
        Quirk::OutputsOnlyInOp,
        Quirk::ModesOnlyWhenDisabled,
        Quirk::PdoWritesIgnored,
    ];

    /// The name after `+` in a device name.
    pub const fn name(self) -> &'static str {
        match self {
            Quirk::NoStateSkipping => "no-state-skipping",
            Quirk::CycleTimeReadOnly => "cycle-time-read-only",
            Quirk::SyncObjectsAbsent => "sync-objects-absent",
            Quirk::NoSdoInfo => "no-sdo-info",
            Quirk::SdoInfoBadEntry => "sdo-info-bad-entry",
            Quirk::SdoInfoShortEntry => "sdo-info-short-entry",
            Quirk::NoCompleteAccess => "no-complete-access",
            Quirk::OddAbort => "odd-abort",
            Quirk::StaleInputsUntilOp => "stale-inputs-until-op",
            Quirk::OutputsInSafeOp => "outputs-in-safeop",
            Quirk::FollowingErrorZero => "following-error-zero",
            Quirk::InterpolationIndexReadOnly => "interpolation-index-read-only",
            Quirk::OpNeedsSync0 => "op-needs-sync0",
            Quirk::NoHomeSwitch => "no-home-switch",
            Quirk::OutputsOnlyInOp => "outputs-only-in-op",
            Quirk::ModesOnlyWhenDisabled => "modes-only-when-disabled",
            Quirk::PdoWritesIgnored => "pdo-writes-ignored",
        }
    }

    /// One line on what the device then does.
    pub const fn describe(self) -> &'static str {
        match self {
            Quirk::NoStateSkipping => {
                "only the standard CiA 402 transitions (no Switch on disabled → Operation enabled)"
            }
            Quirk::CycleTimeReadOnly => {
                "0x1C32:02/0x1C33:02 read-only, showing the SYNC0 cycle once it runs"
            }
            Quirk::SyncObjectsAbsent => "no 0x1C32/0x1C33 objects",
            Quirk::NoSdoInfo => "no SDO information service",
            Quirk::SdoInfoBadEntry => {
                "SDO information error 0x00000000 for the description of 0x1018:02"
            }
            Quirk::SdoInfoShortEntry => "the description of 0x1018:03 cut short",
            Quirk::NoCompleteAccess => "complete access refused although the SII advertises it",
            Quirk::PdoWritesIgnored => {
                "PDO assignment and mapping writes acknowledged and not taken (the power-on mapping stays)"
            }
            Quirk::OddAbort => "SDO aborts as CoE service 2 with command byte 0x9F",
            Quirk::StaleInputsUntilOp => "inputs updated only in OP (zeros before)",
            Quirk::OutputsInSafeOp => "outputs applied already in SAFE-OP",
            Quirk::FollowingErrorZero => "0x60F4 always reads 0",
            Quirk::InterpolationIndexReadOnly => {
                "0x60C2:02 (interpolation time index) read-only at its power-on value"
            }
            Quirk::OpNeedsSync0 => "SAFE-OP → OP refused (0x002D, no sync) until SYNC0 has fired",
            Quirk::OutputsOnlyInOp => {
                "the output SyncManager enabled with OP only: outputs not taken in SAFE-OP"
            }
            Quirk::ModesOnlyWhenDisabled => {
                "0x6060 taken only outside Operation enabled (a switch while enabled never shows)"
            }
            Quirk::NoHomeSwitch => {
                "no home switch on the emulated machine: homing on it runs into a limit switch \
                 and fails as the drive reports it"
            }
        }
    }

    /// What the device needs for the quirk to mean something.
    pub const fn needs(self) -> Needs {
        match self {
            Quirk::StaleInputsUntilOp
            | Quirk::OutputsInSafeOp
            | Quirk::OpNeedsSync0
            | Quirk::OutputsOnlyInOp => Needs::ProcessData,
            Quirk::NoStateSkipping | Quirk::NoHomeSwitch | Quirk::ModesOnlyWhenDisabled => {
                Needs::Cia402
            }
            Quirk::FollowingErrorZero => Needs::FollowingError,
            _ => Needs::Coe,
        }
    }

    /// The quirk of this name.
    pub fn from_name(name: &str) -> Option<Quirk> {
        Quirk::ALL.into_iter().find(|q| q.name() == name)
    }

    const fn bit(self) -> u32 {
        1 << self as u32
    }
}

impl fmt::Display for Quirk {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of quirks (empty: the device as its profile describes it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Quirks(u32);

impl Quirks {
    /// No quirk.
    pub const NONE: Quirks = Quirks(0);

    /// With `q` as well.
    #[must_use]
    pub const fn with(self, q: Quirk) -> Quirks {
        Quirks(self.0 | q.bit())
    }

    /// Whether `q` is set.
    pub const fn has(self, q: Quirk) -> bool {
        self.0 & q.bit() != 0
    }

    /// Whether none is set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The quirks set, in [`Quirk::ALL`] order.
    pub fn iter(self) -> impl Iterator<Item = Quirk> {
        Quirk::ALL.into_iter().filter(move |q| self.has(*q))
    }

    /// Check that every quirk applies to a device that has `has`; the error names the first
    /// that does not.
    pub fn check_for(self, device: &str, has: Capabilities) -> Result<(), String> {
        for q in self.iter() {
            let (ok, lacks) = match q.needs() {
                Needs::ProcessData => (true, ""),
                Needs::Coe => (has.coe, "no CoE mailbox"),
                Needs::Cia402 => (has.cia402, "no CiA 402 device control"),
                Needs::FollowingError => (has.following_error, "no 0x60F4"),
            };
            if !ok {
                return Err(format!(
                    "quirk {q} does not apply to {device}: it has {lacks}"
                ));
            }
        }
        if self.has(Quirk::SyncObjectsAbsent) && self.has(Quirk::CycleTimeReadOnly) {
            return Err(format!(
                "{device}: quirks {} and {} exclude each other",
                Quirk::SyncObjectsAbsent,
                Quirk::CycleTimeReadOnly
            ));
        }
        Ok(())
    }
}

impl FromIterator<Quirk> for Quirks {
    fn from_iter<I: IntoIterator<Item = Quirk>>(iter: I) -> Self {
        iter.into_iter().fold(Quirks::NONE, Quirks::with)
    }
}

impl fmt::Display for Quirks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, q) in self.iter().enumerate() {
            if i > 0 {
                f.write_str("+")?;
            }
            f.write_str(q.name())?;
        }
        Ok(())
    }
}

/// Split a device name into its base name and quirks: `bdhde+no-state-skipping` →
/// (`bdhde`, {no-state-skipping}). The error names an unknown quirk and lists the known ones.
pub fn split_name(name: &str) -> Result<(&str, Quirks), String> {
    let quirked = name.split_once('@').map_or(name, |(q, _)| q);
    let mut parts = quirked.split('+');
    let base = parts.next().unwrap_or_default();
    let mut quirks = Quirks::NONE;
    for p in parts {
        let q = Quirk::from_name(p).ok_or_else(|| {
            format!(
                "unknown quirk {p:?} in {name:?}; known quirks: {}",
                Quirk::ALL.map(Quirk::name).join(", ")
            )
        })?;
        quirks = quirks.with(q);
    }
    Ok((base, quirks))
}

/// The parameters stored in an emulated drive's non-volatile memory, named after `@`:
/// `mr-j4-tm@0x2001=2` is an MR-J4-TM whose [Pr. PA01] (0x2001) holds 2 from power-on (the
/// profile modes); several are `@A=V@B=W`. Values are decimal or `0x` hex.
pub fn stored_params(name: &str) -> Result<Vec<(crate::od::ObjectAddress, i64)>, String> {
    let mut out = Vec::new();
    if name.starts_with("esi:") {
        // `esi:FILE@0xPRODUCT[:0xREVISION]`: what follows `@` chooses the file's device.
        return Ok(out);
    }
    for p in name.split('@').skip(1) {
        let (obj, value) = p
            .split_once('=')
            .ok_or_else(|| format!("stored parameter {p:?} in {name:?} is not OBJECT=VALUE"))?;
        let addr: crate::od::ObjectAddress = obj
            .parse()
            .map_err(|e| format!("stored parameter {p:?} in {name:?}: {e}"))?;
        let v = match value
            .strip_prefix("0x")
            .or_else(|| value.strip_prefix("0X"))
        {
            Some(h) => i64::from_str_radix(h, 16),
            None => value.parse(),
        }
        .map_err(|_| format!("stored parameter {p:?} in {name:?}: {value:?} is not a number"))?;
        out.push((addr, v));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for q in Quirk::ALL {
            assert_eq!(Quirk::from_name(q.name()), Some(q));
        }
        let (base, qs) = split_name("bdhde+no-state-skipping+odd-abort").unwrap();
        assert_eq!(base, "bdhde");
        assert_eq!(qs.to_string(), "no-state-skipping+odd-abort");
        assert!(
            split_name("bdhde+nope")
                .unwrap_err()
                .contains("known quirks")
        );
        assert_eq!(
            split_name("generic-io").unwrap(),
            ("generic-io", Quirks::NONE)
        );
    }

    #[test]
    fn a_quirk_needs_what_it_breaks() {
        let q = Quirks::NONE.with(Quirk::NoSdoInfo);
        let io = Capabilities::default();
        let drive = Capabilities {
            coe: true,
            cia402: true,
            following_error: true,
        };
        assert!(q.check_for("generic-io", io).is_err());
        assert!(q.check_for("bdhde", drive).is_ok());
        let both = Quirks::NONE
            .with(Quirk::SyncObjectsAbsent)
            .with(Quirk::CycleTimeReadOnly);
        assert!(both.check_for("bdhde", drive).is_err());
    }
}
