//! Emulated nodes from EDS files: any CiA 402 drive a vendor describes, and the project's drives
//! with their vendor's file in place of the emulator's own dictionary.
//!
//! [`NodeSpec::from_eds`] takes from the file what a file can say — the dictionary (defaults,
//! access, mapping, ranges), the modes (6502h), the PDO counts and entries per PDO, the homing
//! methods (60E3h), the quick-stop codes 605Ah's range allows, which NMT error-control objects
//! exist, the error-history depth, the position units per revolution (608Fh/6091h/6092h) — and
//! behaves as CiA 301/402 describe where a file cannot say. Every such choice is marked
//! **\[REC\]** here, in one place. [`NodeSpec::refined`] keeps a drive model's behaviour and
//! takes the file's dictionary (a vendor file of a newer firmware, an identity the manual does
//! not give).

use super::quirks::EmulationQuirks;
use super::spec::NodeSpec;
use crate::can::profile::{
    Alarm, CanPdoProfile, CommSupport, EmcyFormat, EnabledNmtReaction, HomingSupport,
    TransmissionTypes,
};
use crate::cia402::units::Units;
use crate::cia402::{DriveCaps, QuickStopOption, SupportedModes};
use crate::eds::EdsFile;
use crate::od::{ConstValue, ObjectDesc};
use crate::pdo::PdoLimits;

fn leak(s: &str) -> &'static str {
    String::leak(s.to_owned())
}

/// **\[REC\]** Modes of a file without 6502h: pp, pv and hm, the modes every CiA 402 servo of
/// the corpus offers.
pub const FALLBACK_MODES: u32 = 0x0000_0025;

/// **\[REC\]** Homing methods of a file without 60E3h: CiA 402's methods 1–35 and 37.
const STANDARD_HOMING: [i8; 36] = {
    let mut m = [0i8; 36];
    let mut k = 0;
    while k < 35 {
        m[k] = (k + 1) as i8;
        k += 1;
    }
    m[35] = 37;
    m
};

/// **\[REC\]** The alarms a drive from a file can raise (test injection): CiA 402 error codes
/// (EMCY bytes 3–7 zero), numbered by their code. The file has no alarm table.
const GENERIC_ALARMS: &[Alarm] = &[
    Alarm {
        number: 0x2310,
        code: 0x2310,
        register: 0x03,
        name: "2310h",
        text: "continuous over-current",
        fault: true,
    },
    Alarm {
        number: 0x3210,
        code: 0x3210,
        register: 0x05,
        name: "3210h",
        text: "DC link over-voltage",
        fault: true,
    },
    Alarm {
        number: 0x4310,
        code: 0x4310,
        register: 0x09,
        name: "4310h",
        text: "excess temperature drive",
        fault: true,
    },
    Alarm {
        number: 0x8611,
        code: 0x8611,
        register: 0x21,
        name: "8611h",
        text: "following error",
        fault: true,
    },
];

/// **\[REC\]** 1000h of a file that gives none: a CiA 402 drive with no further bits.
const FALLBACK_DEVICE_TYPE: u64 = 0x0002_0192;

/// The dictionary with the identity a device of the file reports: 1000h and 1018h:01–03 where
/// the file leaves them empty or zero take the `[DeviceInfo]` header's numbers (maxon leaves
/// 1000h and 1018h without values, Animatics writes 1018h:01 = 0).
fn with_identity(file: &EdsFile, objects: &'static [ObjectDesc]) -> &'static [ObjectDesc] {
    let header = |index: u16, sub: u8| -> Option<u64> {
        match (index, sub) {
            (0x1000, 0) => Some(FALLBACK_DEVICE_TYPE),
            (0x1018, 1) => file.device.vendor_number.map(u64::from),
            (0x1018, 2) => file.device.product_number.map(u64::from),
            (0x1018, 3) => file.device.revision_number.map(u64::from),
            _ => None,
        }
    };
    let out: Vec<ObjectDesc> = objects
        .iter()
        .map(|o| {
            if o.index != 0x1000 && o.index != 0x1018 {
                return *o;
            }
            let entries: Vec<_> = o
                .entries
                .iter()
                .map(|e| match (e.default, header(o.index, e.sub)) {
                    (ConstValue::None | ConstValue::Uint(0), Some(v)) => {
                        e.default(ConstValue::Uint(v))
                    }
                    _ => *e,
                })
                .collect();
            ObjectDesc {
                entries: Vec::leak(entries),
                ..*o
            }
        })
        .collect();
    Vec::leak(out)
}

/// The quick-stop codes 605Ah's range allows (every standard code if the file gives none), and
/// its default.
fn quick_stop(f: &EdsFile) -> (&'static [QuickStopOption], QuickStopOption) {
    let e = f.entry(0x605A, 0);
    let lo = e.and_then(|e| e.low.resolve(0)).unwrap_or(0);
    let hi = e.and_then(|e| e.high.resolve(0)).unwrap_or(8);
    let options: Vec<QuickStopOption> = QuickStopOption::STANDARD
        .iter()
        .copied()
        .filter(|o| (lo..=hi).contains(&i128::from(o.code)))
        .collect();
    let default = f
        .number(0x605A, 0)
        .and_then(|v| i16::try_from(v).ok())
        .and_then(QuickStopOption::standard)
        .filter(|o| options.contains(o))
        .or_else(|| options.last().copied())
        .unwrap_or(QuickStopOption::QUICK_STOP_RAMP);
    if options.is_empty() {
        return (&QuickStopOption::STANDARD, QuickStopOption::QUICK_STOP_RAMP);
    }
    (Vec::leak(options), default)
}

impl NodeSpec {
    /// A node for the CiA 402 drive `file` describes (see the [module documentation](self));
    /// `source` names the file in messages. Refused when the file is no CiA 402 drive.
    pub fn from_eds(file: &EdsFile, source: &str) -> Result<&'static NodeSpec, String> {
        if !file.is_cia402() {
            return Err(format!(
                "{source}: not a CiA 402 drive (1000h is not profile 402 and 6040h/6041h are \
                 missing)"
            ));
        }
        let dict = file.dictionary();
        if dict.objects.is_empty() {
            return Err(format!("{source}: no object the emulation can serve"));
        }
        let name = if file.device.product_name.trim().is_empty() {
            leak(source)
        } else {
            leak(file.device.product_name.trim())
        };
        let modes = file.supported_modes().unwrap_or(FALLBACK_MODES);
        let (qs_options, qs_default) = quick_stop(file);
        let caps = DriveCaps {
            supported_modes: SupportedModes::from_raw(modes),
            quick_stop_options: qs_options,
            default_quick_stop_option: qs_default,
            ..DriveCaps::CIA402
        };
        let (per_rev, _) = file.position_per_rev();
        let units = Units::cia402(per_rev);
        let pdo = CanPdoProfile {
            limits: PdoLimits {
                drive: name,
                rx: file.pdo_limits(0x1600),
                tx: file.pdo_limits(0x1A00),
                assignment_writable: true,
            },
            max_pdo_bytes: 8,
            rpdo_types: TransmissionTypes::ALL,
            tpdo_types: TransmissionTypes::ALL,
            rpdo_comm_subs: file.highest_sub(0x1400).max(2),
            default_rpdos: &[],
            default_tpdos: &[],
        };
        let methods = file
            .homing_methods()
            .unwrap_or_else(|| STANDARD_HOMING.to_vec());
        let default_method = file
            .number(0x6098, 0)
            .and_then(|v| i8::try_from(v).ok())
            .filter(|m| methods.contains(m))
            .or_else(|| methods.first().copied())
            .unwrap_or(35);
        let homing = HomingSupport {
            methods: Vec::leak(methods),
            default_method,
            index_pulse: true,
        };
        let comm = CommSupport::from_eds(file);
        Ok(Box::leak(Box::new(NodeSpec {
            name,
            vendor: leak(file.device.vendor_name.trim()),
            source: leak(source),
            dictionary: with_identity(file, dict.objects),
            caps,
            units,
            pdo,
            homing,
            emcy: EmcyFormat::AlarmInCodeLowByte,
            alarms: GENERIC_ALARMS,
            comm,
            // [REC] CiA 402 leaves the reaction open: the power stage is disabled.
            nmt_stop_while_enabled: EnabledNmtReaction::Unspecified,
            nmt_reset_while_enabled: EnabledNmtReaction::Unspecified,
            targets_cleared_on_enable: &[],
            quirks: EmulationQuirks::NONE,
        })))
    }

    /// The drive model `base` with the dictionary of its vendor's `file`: the file's objects
    /// (identity, defaults, access as the file gives them) and the model's objects the file
    /// does not have; everything else is the model's.
    pub fn refined(base: &NodeSpec, file: &EdsFile, source: &str) -> &'static NodeSpec {
        let dict = file.dictionary();
        let mut objects: Vec<ObjectDesc> = dict.objects.to_vec();
        for o in base.dictionary {
            if !objects.iter().any(|x| x.index == o.index) {
                objects.push(*o);
            }
        }
        objects.sort_by_key(|o| o.index);
        Box::leak(Box::new(NodeSpec {
            source: leak(&format!("{} with {source}", base.source)),
            dictionary: Vec::leak(objects),
            ..*base
        }))
    }

    /// The default of an entry of the spec's dictionary, as a number.
    pub fn default_number(&self, index: u16, sub: u8) -> Option<i128> {
        let e = self
            .dictionary
            .iter()
            .find(|o| o.index == index)?
            .entries
            .iter()
            .find(|e| e.sub == sub)?;
        match e.default {
            ConstValue::Int(v) => Some(i128::from(v)),
            ConstValue::Uint(v) => Some(i128::from(v)),
            _ => None,
        }
    }
}
