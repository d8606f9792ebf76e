//! A CANopen drive profile built from a vendor's EDS/DCF file, for a CiA 402 drive ecdrive has
//! no profile for — and a built-in profile refined by its vendor's file.
//!
//! | profile field | from the file |
//! |---|---|
//! | identity | `[DeviceInfo]` VendorNumber/ProductNumber/RevisionNumber (1018h's defaults where the header has none), 1000h |
//! | dictionary | every VAR/ARRAY/RECORD with its type, access, `PDOMapping`, default and limits ([`EdsFile::dictionary`]) |
//! | supported modes | 6502h's default; pp, pv and hm (\[REC\]) without it |
//! | PDO rules | the mapping objects 1600h–1603h / 1A00h–1A03h the file has (fixed where sub-index 0 is read-only: used as they are), entries per PDO from their sub-indices, 8 bytes per PDO, every CiA 301 transmission type |
//! | power-on PDOs | 14xxh/16xxh and 18xxh/1Axxh defaults |
//! | homing | 60E3h's methods, else CiA 402's 1–35 and 37; 6098h's default |
//! | units | position units per revolution from 6092h/6091h, else 608Fh ([`EdsFile::position_per_rev`]); velocities in position units/s, accelerations in units/s², torque in ‰ of rated (CiA 402) |
//! | NMT error control | guarding when 100Ch and 100Dh exist, heartbeat consumers from 1016h, the error history's depth from 1003h |
//!
//! Everything else is plain CiA 402 and labelled \[REC\] below: no vendor alarm table (an EMCY is
//! decoded by the CiA 301/402 error codes), no enable preconditions beyond NMT Operational.
//!
//! Profiles built this way live for the rest of the process (the profile type holds `'static`
//! data): a configuration builds each once, at start-up, never in the cycle.

use crate::can::profile::{
    CanDriveProfile, CanOpen, CanPdoProfile, CommSupport, EmcyFormat, EnableConditions,
    EnabledNmtReaction, HomingSupport, Identity, PdoDefault, TransmissionTypes,
};
use crate::cia402::units::Units;
use crate::cia402::{DriveCaps, QuickStopOption, SupportedModes};
use crate::eds::EdsFile;
use crate::od::ObjectDesc;
use crate::pdo::{PdoEntry, PdoLimits};

/// Why a file cannot drive a profile.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}: {reason}")]
pub struct EdsProfileError {
    /// The file.
    pub file: String,
    /// What is missing or wrong.
    pub reason: String,
}

fn leak(s: &str) -> &'static str {
    String::leak(s.to_owned())
}

/// **\[REC\]** Modes of a file without 6502h: pp, pv and hm.
pub const FALLBACK_MODES: u32 = 0x0000_0025;

/// **\[REC\]** Bit rate of a file that marks none, kbit/s.
pub const FALLBACK_BITRATE_KBIT: u16 = 500;

fn u32_of(v: Option<i128>) -> Option<u32> {
    v.and_then(|v| u32::try_from(v & 0xFFFF_FFFF).ok())
}

/// The power-on PDOs of one direction: communication record `comm` + n, mapping `map` + n.
fn defaults(f: &EdsFile, comm: u16, map: u16) -> &'static [PdoDefault] {
    let mut out = Vec::new();
    for n in 0..4u16 {
        let Some(cob) = u32_of(f.number(comm + n, 1)) else {
            continue;
        };
        let count = f.number(map + n, 0).unwrap_or(0).clamp(0, 64) as u8;
        let mapping: Vec<PdoEntry> = (1..=count)
            .filter_map(|s| u32_of(f.number(map + n, s)))
            .filter(|v| *v != 0)
            .map(|v| PdoEntry::new((v >> 16) as u16, (v >> 8) as u8, v as u8))
            .collect();
        out.push(PdoDefault {
            number: n as u8 + 1,
            // For node-ID 0: the node adds its own.
            cob_id: node_zero(cob),
            transmission_type: f.number(comm + n, 2).unwrap_or(255).clamp(0, 255) as u8,
            inhibit_time: f.number(comm + n, 3).unwrap_or(0).clamp(0, 0xFFFF) as u16,
            event_timer: f.number(comm + n, 5).unwrap_or(0).clamp(0, 0xFFFF) as u16,
            mapping: Vec::leak(mapping),
        });
    }
    Vec::leak(out)
}

/// A COB-ID for node-ID 0: a literal of the predefined connection set (`0x181`) taken back to
/// its base; `$NODEID` formulas already are.
fn node_zero(cob: u32) -> u32 {
    let low = cob & 0x7F;
    let predefined = matches!(
        cob & 0x780,
        0x180 | 0x200 | 0x280 | 0x300 | 0x380 | 0x400 | 0x480 | 0x500
    );
    if low != 0 && predefined {
        cob - low
    } else {
        cob
    }
}

/// **\[REC\]** 1000h of a file that gives none (maxon leaves it empty): a CiA 402 drive with
/// no further bits.
pub const FALLBACK_DEVICE_TYPE: u32 = 0x0002_0192;

/// The identity a device of the file reports: 1018h's values where the file gives them (not
/// zero), else the `[DeviceInfo]` header's; the product codes of both are accepted (Elmo's
/// header names a product its 1018h:02 leaves at 0).
fn identity(f: &EdsFile, name: &'static str) -> Identity {
    let od = |sub: u8| u32_of(f.number(0x1018, sub)).filter(|v| *v != 0);
    let vendor = od(1).or(f.device.vendor_number).unwrap_or(0);
    let mut products = Vec::new();
    for p in [od(2), f.device.product_number].into_iter().flatten() {
        if !products.iter().any(|(q, _)| *q == p) {
            products.push((p, name));
        }
    }
    if products.is_empty() {
        // Neither says: the device reports 0 (or nothing) in 1018h:02.
        products.push((0, name));
    }
    Identity {
        vendor_id: vendor,
        products: Vec::leak(products),
        device_type: u32_of(f.number(0x1000, 0))
            .filter(|v| *v != 0)
            .unwrap_or(FALLBACK_DEVICE_TYPE),
        other_device_types: &[],
        revision: od(3).or(f.device.revision_number),
    }
}

/// A profile for the CiA 402 drive `file` describes (see the [module documentation](self));
/// `source` names the file in messages.
pub fn from_eds(file: &EdsFile, source: &str) -> Result<&'static CanDriveProfile, EdsProfileError> {
    let err = |reason: String| EdsProfileError {
        file: source.to_string(),
        reason,
    };
    if !file.is_cia402() {
        return Err(err(
            "not a CiA 402 drive (1000h is not profile 402 and 6040h/6041h are missing)".into(),
        ));
    }
    let dict = file.dictionary();
    let has = |i: u16| dict.objects.iter().any(|o: &ObjectDesc| o.index == i);
    for (index, what) in [
        (0x6040, "controlword"),
        (0x6041, "statusword"),
        (0x6060, "modes of operation"),
    ] {
        if !has(index) {
            return Err(err(format!(
                "no {index:04X}h ({what}): a CiA 402 master needs it"
            )));
        }
    }
    let name = leak(match file.device.product_name.trim() {
        "" => source,
        n => n,
    });
    let modes = file.supported_modes().unwrap_or(FALLBACK_MODES);
    let caps = DriveCaps {
        supported_modes: SupportedModes::from_raw(modes),
        // The file lists no options; the master writes none and judges the stop by the states.
        quick_stop_options: &QuickStopOption::STANDARD,
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
        default_rpdos: defaults(file, 0x1400, 0x1600),
        default_tpdos: defaults(file, 0x1800, 0x1A00),
    };
    let methods: Vec<i8> = file
        .homing_methods()
        .unwrap_or_else(|| (1..=35).chain(std::iter::once(37)).collect());
    let default_method = file
        .number(0x6098, 0)
        .and_then(|v| i8::try_from(v).ok())
        .unwrap_or(0);
    let bitrates: Vec<u16> = file
        .device
        .baud_rates
        .iter()
        .filter_map(|b| u16::try_from(*b).ok())
        .collect();
    let default_bitrate = if bitrates.contains(&FALLBACK_BITRATE_KBIT) || bitrates.is_empty() {
        FALLBACK_BITRATE_KBIT
    } else {
        bitrates[0]
    };
    let comm = CommSupport::from_eds(file);
    Ok(Box::leak(Box::new(CanDriveProfile {
        name,
        vendor: leak(file.device.vendor_name.trim()),
        caps,
        dictionary: dict.objects,
        units,
        bus: CanOpen {
            source: leak(source),
            identity: identity(file, name),
            default_node_id: file.node_id,
            default_bitrate_kbit: default_bitrate,
            bitrates_kbit: Vec::leak(bitrates),
            modes_note: "6502h's default in the file",
            pdo,
            enable: EnableConditions {
                remote_required: false,
                voltage_required: false,
                // [REC] The master runs its drives in NMT Operational anyway.
                needs_operational: true,
                settings: &[],
                targets_cleared_on_enable: &[],
                notes: "from the EDS file: no vendor preconditions known",
            },
            homing: HomingSupport {
                methods: Vec::leak(methods),
                default_method,
                index_pulse: true,
            },
            // [REC] No vendor layout known: bytes 3–7 are not read as an alarm number unless
            // the code is FFxxh.
            emcy: EmcyFormat::AlarmInCodeLowByte,
            alarms: &[],
            vendor_abort_codes: &[],
            comm,
            nmt_stop_while_enabled: EnabledNmtReaction::Unspecified,
            nmt_reset_while_enabled: EnabledNmtReaction::Unspecified,
            ip_needs_enable_bit: true,
            pv_zero_speed_bit: true,
        },
    })))
}

/// The built-in profile `base` refined by its vendor's `file`: the file's identity (a device
/// reports what its firmware's file says, e.g. the Lexium MDrive file's vendor ID 0800005Ah) and
/// dictionary (its objects, plus the profile's objects the file lacks); the behaviour — caps,
/// units, PDO rules, alarms, enable conditions — stays the profile's. The product codes and
/// device types of both are accepted; the vendor ID is the file's.
pub fn refine(
    base: &'static CanDriveProfile,
    file: &EdsFile,
    source: &str,
) -> &'static CanDriveProfile {
    let dict = file.dictionary();
    let mut objects: Vec<ObjectDesc> = dict.objects.to_vec();
    for o in base.dictionary {
        if !objects.iter().any(|x| x.index == o.index) {
            objects.push(*o);
        }
    }
    objects.sort_by_key(|o| o.index);
    let from_file = identity(file, base.name);
    let mut products: Vec<(u32, &'static str)> = base.identity.products.to_vec();
    for p in from_file.products {
        if !products.contains(p) {
            products.push(*p);
        }
    }
    let mut device_types: Vec<u32> = base.identity.other_device_types.to_vec();
    device_types.push(base.identity.device_type);
    let identity = Identity {
        vendor_id: from_file.vendor_id,
        products: Vec::leak(products),
        device_type: from_file.device_type,
        other_device_types: Vec::leak(device_types),
        revision: from_file.revision.or(base.identity.revision),
    };
    Box::leak(Box::new(CanDriveProfile {
        dictionary: Vec::leak(objects),
        bus: CanOpen {
            source: leak(&format!("{} with {source}", base.source)),
            identity,
            ..base.bus
        },
        ..*base
    }))
}
