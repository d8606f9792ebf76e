//! `ecdrive eds show`: what the EDS reader ([`crate::eds`]) reads from a vendor's EDS or DCF
//! file, in the terms a user commissioning a CANopen drive needs: the identity, the PDOs, the
//! CiA 402 modes the file declares (6502h) and, for each, the objects its cyclic exchange
//! needs and whether the file lets them into a PDO.

use crate::eds::{EdsFile, EdsValue};
use serde::Serialize;

/// The summary of one file.
#[derive(Debug, Clone, Serialize)]
pub struct EdsSummary {
    /// The file as given.
    pub file: String,
    /// `[DeviceInfo]` VendorName.
    pub vendor: String,
    /// VendorNumber (1018h:01).
    pub vendor_number: Option<u32>,
    /// ProductName.
    pub product: String,
    /// ProductNumber (1018h:02).
    pub product_number: Option<u32>,
    /// RevisionNumber (1018h:03).
    pub revision_number: Option<u32>,
    /// 1000h's default (device type), if given.
    pub device_type: Option<u32>,
    /// Whether the file describes a CiA 402 drive.
    pub cia402: bool,
    /// Why it counts as one, or what is odd about it (1000h names another profile while
    /// 6040h/6041h are there; 6502h absent or without a value).
    pub notes: Vec<String>,
    /// The modes 6502h declares, by their short names.
    pub modes: Vec<&'static str>,
    /// NrOfRXPDO, NrOfTXPDO.
    pub pdos: (Option<u16>, Option<u16>),
    /// Supported bit rates, kbit/s.
    pub baud_rates: Vec<u32>,
    /// Objects in the file.
    pub objects: usize,
    /// Entries that can go into an RPDO, a TPDO.
    pub mappable: (usize, usize),
    /// Whether it is a DCF (configured values).
    pub dcf: bool,
    /// Per declared mode: what its cyclic exchange needs.
    pub plans: Vec<ModePlan>,
    /// What the reader took in its own way, with lines.
    pub warnings: Vec<String>,
}

/// The objects a mode's exchange needs and how the file lets them travel.
#[derive(Debug, Clone, Serialize)]
pub struct ModePlan {
    /// The mode's short name.
    pub mode: &'static str,
    /// (object, how) for the master's outputs: `"pdo"` (the file lets it into a PDO),
    /// `"sdo"` (it exists but no PDO may carry it: ecdrive moves it by SDO), `"absent"`.
    pub rx: Vec<(String, &'static str)>,
    /// The same for the drive's inputs.
    pub tx: Vec<(String, &'static str)>,
}

/// 6502h's bits (CiA 402): bit, short name, the set-point it takes, the actual value shown.
const MODES: [(u32, &str, Option<u16>, u16); 9] = [
    (0, "pp", Some(0x607A), 0x6064),
    (1, "vl", Some(0x6042), 0x6044),
    (2, "pv", Some(0x60FF), 0x606C),
    (3, "tq", Some(0x6071), 0x6077),
    (5, "hm", None, 0x6064),
    (6, "ip", Some(0x60C1), 0x6064),
    (7, "csp", Some(0x607A), 0x6064),
    (8, "csv", Some(0x60FF), 0x606C),
    (9, "cst", Some(0x6071), 0x6077),
];

/// Read `path` and summarise it; the reader's error as one line.
pub fn show(path: &std::path::Path) -> Result<EdsSummary, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let f = EdsFile::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let rx = f.mappable(true);
    let tx = f.mappable(false);
    let how = |list: &[(u16, u8, u16)], index: u16| -> &'static str {
        if list.iter().any(|(i, s, _)| *i == index && *s == 0) {
            "pdo"
        } else if f.entry(index, 0).is_some() {
            "sdo"
        } else {
            "absent"
        }
    };
    let mut notes = Vec::new();
    let profile_no = f
        .entry(0x1000, 0)
        .and_then(|e| e.default.resolve(0))
        .map(|v| v & 0xFFFF);
    if f.is_cia402() && profile_no.is_some_and(|p| p != 402) {
        notes.push(format!(
            "1000h names device profile {} (not 402); taken as a CiA 402 drive by its 6040h \
             and 6041h",
            profile_no.unwrap_or(0)
        ));
    }
    match f.entry(0x6502, 0) {
        None => notes.push(
            "no 6502h: the file declares no modes; a run from it assumes pp, pv and hm".into(),
        ),
        Some(e) if e.default.is_none() && e.parameter_value.is_none() => notes.push(
            "6502h has no value: the file declares no modes; a run from it assumes pp, pv and hm"
                .into(),
        ),
        Some(_) if f.supported_modes().is_none() => notes.push(
            "6502h's value is not a 32-bit number: a run from the file assumes pp, pv and hm"
                .into(),
        ),
        Some(_) => {}
    }
    let raw_modes = f.supported_modes().unwrap_or(0);
    let modes: Vec<&'static str> = MODES
        .iter()
        .filter(|(bit, ..)| raw_modes >> bit & 1 == 1)
        .map(|(_, n, ..)| *n)
        .collect();
    let several = modes.len() > 1;
    let plans = MODES
        .iter()
        .filter(|(bit, ..)| raw_modes >> bit & 1 == 1)
        .map(|&(_, mode, set, actual)| {
            let mut r = vec![0x6040u16];
            r.extend(set);
            if several {
                r.push(0x6060);
            }
            let mut t = vec![0x6041u16, actual];
            if several {
                t.push(0x6061);
            }
            ModePlan {
                mode,
                rx: r
                    .into_iter()
                    .map(|i| (format!("{i:04X}h"), how(&rx, i)))
                    .collect(),
                tx: t
                    .into_iter()
                    .map(|i| (format!("{i:04X}h"), how(&tx, i)))
                    .collect(),
            }
        })
        .collect();
    Ok(EdsSummary {
        file: path.display().to_string(),
        vendor: f.device.vendor_name.clone(),
        vendor_number: f.device.vendor_number,
        product: f.device.product_name.clone(),
        product_number: f.device.product_number,
        revision_number: f.device.revision_number,
        device_type: f.entry(0x1000, 0).and_then(|e| match e.default {
            EdsValue::Int(v) => u32::try_from(v & 0xFFFF_FFFF).ok(),
            _ => None,
        }),
        cia402: f.is_cia402(),
        notes,
        modes,
        pdos: (f.device.rx_pdos, f.device.tx_pdos),
        baud_rates: f.device.baud_rates.clone(),
        objects: f.objects.len(),
        mappable: (rx.len(), tx.len()),
        dcf: f.dcf,
        plans,
        warnings: f.warnings.iter().map(|w| w.to_string()).collect(),
    })
}
