//! `ecdrive esi show|check`: what the parser reads from an ESI file, or why it is invalid. No
//! bus involved.

use crate::esi::{EsiError, EsiFile, SmKind};
use crate::pdo::Direction;
use serde::Serialize;
use std::path::Path;

/// One PDO as the file describes it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct EsiPdoSummary {
    /// `RxPDO` or `TxPDO`.
    pub direction: String,
    /// Mapping index.
    pub index: u16,
    /// Name.
    pub name: String,
    /// Default SyncManager, if assigned by default.
    pub sm: Option<u8>,
    /// Fixed content.
    pub fixed: bool,
    /// Number of entries.
    pub entries: usize,
    /// Size in bits.
    pub bits: u32,
}

/// One SyncManager.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct EsiSmSummary {
    /// Number.
    pub index: u8,
    /// `MBoxOut`, `MBoxIn`, `Outputs`, `Inputs` or empty.
    pub kind: String,
    /// Start address.
    pub start: u16,
    /// Default size, if given.
    pub default_size: Option<u16>,
    /// Control byte.
    pub control: u8,
}

/// One device of the file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EsiDeviceSummary {
    /// Product code.
    pub product_code: u32,
    /// Revision, if given.
    pub revision: Option<u32>,
    /// Type text (order code).
    pub type_name: String,
    /// Name.
    pub name: String,
    /// The drive profile ecdrive has for this identity, if any.
    pub profile: Option<String>,
    /// Mailbox protocols.
    pub mailbox_protocols: Vec<String>,
    /// SyncManagers.
    pub sync_managers: Vec<EsiSmSummary>,
    /// PDOs.
    pub pdos: Vec<EsiPdoSummary>,
    /// Default mapping sizes `(outputs, inputs)` in bytes, if the default assignment is valid.
    pub default_image_bytes: Option<(usize, usize)>,
    /// DC operation modes (`name`: `AssignActivate`).
    pub dc_modes: Vec<String>,
    /// Objects in the dictionary.
    pub dictionary_objects: usize,
    /// EEPROM size, bytes, if given.
    pub eeprom_bytes: Option<u32>,
    /// What ecdrive would make of the device from this file alone (without a drive profile):
    /// modes, the mapping for each cyclic mode, DC mode, cycle-time object, InitCmds.
    pub plan: crate::esi::DrivePlan,
}

/// What `esi show` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EsiSummary {
    /// The file.
    pub file: String,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Vendor name.
    pub vendor: String,
    /// Schema version, if given.
    pub version: Option<String>,
    /// Devices in file order.
    pub devices: Vec<EsiDeviceSummary>,
}

/// One problem of a file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct EsiIssue {
    /// Line (0 when unknown).
    pub line: u32,
    /// Column (0 when unknown).
    pub column: u32,
    /// What is wrong.
    pub message: String,
    /// `error` (the file, or a device of it, cannot be used) or `warning` (read past).
    pub severity: crate::esi::Severity,
}

/// What `esi check` prints.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct EsiCheck {
    /// The file.
    pub file: String,
    /// Whether the file parses and every device in it can be read (warnings allowed).
    pub valid: bool,
    /// Devices that can be used (0 when the file does not parse).
    pub devices: usize,
    /// Warnings among the issues.
    pub warnings: usize,
    /// The parse error or the inconsistencies, in file order.
    pub issues: Vec<EsiIssue>,
}

fn protocols(m: Option<&crate::esi::Mailbox>) -> Vec<String> {
    super::slaves::protocol_names(m.map_or(0, |m| m.protocols.bits()))
}

/// `esi profile`: the TOML profile of the file's device `device` (its `<Type>` name; the only
/// one when `None`), naming the ESI file relative to `output`'s folder when it is written
/// there (as given otherwise).
pub fn profile(path: &Path, device: Option<&str>, output: Option<&Path>) -> Result<String, String> {
    let shown = path.display().to_string();
    let f = EsiFile::from_path(path).map_err(|e| format!("{shown}: {e}"))?;
    // By identity (`0xPRODUCT[:0xREVISION]`) or name; a choice that fits several devices
    // is refused, listing them (never silently the first).
    let choice = device.map_or(
        crate::esi::DeviceChoice::Only,
        crate::esi::DeviceChoice::parse,
    );
    let dev = f
        .choose(&choice)
        .map_err(|e| {
            if choice == crate::esi::DeviceChoice::Only && f.devices.len() > 1 {
                format!(
                    "{shown} describes {} devices ({}): say which with --device \
                     0xPRODUCT[:0xREVISION]",
                    f.devices.len(),
                    f.device_list()
                )
            } else {
                format!("{shown}: {e}")
            }
        })
        .and_then(|i| {
            f.devices
                .get(i)
                .ok_or_else(|| format!("{shown}: device index out of range"))
        })?;
    let named = match output.and_then(Path::parent) {
        Some(dir) => {
            let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
            let (esi, dir) = (
                abs(path),
                abs(if dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    dir
                }),
            );
            esi.strip_prefix(&dir)
                .map(Path::to_path_buf)
                .unwrap_or(esi)
                .display()
                .to_string()
        }
        None => shown.clone(),
    };
    crate::app::config::profile_file::write(&f, dev, &named).map_err(|e| e.to_string())
}

/// Parse `path` and summarise what the parser reads.
pub fn show(path: &Path) -> Result<EsiSummary, EsiError> {
    let f = EsiFile::from_path(path)?;
    let devices = f
        .devices
        .iter()
        .map(|d| {
            let mut pdos = Vec::new();
            for dir in [Direction::Rx, Direction::Tx] {
                for p in d.pdos(dir) {
                    pdos.push(EsiPdoSummary {
                        direction: dir.name().to_string(),
                        index: p.index,
                        name: p.name.clone(),
                        sm: p.sm,
                        fixed: p.fixed,
                        entries: p.entries.len(),
                        bits: p.bits(),
                    });
                }
            }
            EsiDeviceSummary {
                product_code: d.type_.product_code,
                revision: d.type_.revision_no,
                type_name: d.type_.name_text.clone(),
                name: d.name.clone(),
                profile: crate::drives::by_identity(f.vendor.id, d.type_.product_code)
                    .map(|p| p.name.to_string()),
                mailbox_protocols: protocols(d.mailbox.as_ref()),
                sync_managers: d
                    .sync_managers
                    .iter()
                    .map(|s| EsiSmSummary {
                        index: s.index,
                        kind: if s.kind == SmKind::Unused {
                            String::new()
                        } else {
                            s.kind.name().to_string()
                        },
                        start: s.start_address,
                        default_size: s.default_size,
                        control: s.control_byte,
                    })
                    .collect(),
                pdos,
                default_image_bytes: d
                    .default_mapping()
                    .ok()
                    .map(|m| (m.bytes(Direction::Rx), m.bytes(Direction::Tx))),
                dc_modes: d
                    .dc
                    .iter()
                    .map(|m| {
                        format!(
                            "{}: AssignActivate 0x{:04X}",
                            m.mode.name, m.mode.assign_activate
                        )
                    })
                    .collect(),
                dictionary_objects: d.dictionary().map_or(0, |x| x.objects.len()),
                eeprom_bytes: d.eeprom.as_ref().and_then(|e| e.byte_size),
                plan: crate::esi::DrivePlan::new(&f, d),
            }
        })
        .collect();
    Ok(EsiSummary {
        file: path.display().to_string(),
        vendor_id: f.vendor.id,
        vendor: f.vendor.name.clone(),
        version: f.version.clone(),
        devices,
    })
}

/// Parse `path` and check it for consistency ([`EsiFile::check`]). Never fails: a file that
/// does not parse is reported as one issue with the parser's line and column.
pub fn check(path: &Path) -> EsiCheck {
    let file = path.display().to_string();
    match EsiFile::from_path(path) {
        Ok(f) => {
            let mut issues: Vec<EsiIssue> = f
                .check()
                .into_iter()
                .map(|i| EsiIssue {
                    line: i.position.line,
                    column: i.position.column,
                    message: i.message,
                    severity: i.severity,
                })
                .collect();
            issues.sort_by_key(|i| (i.severity, i.line, i.column));
            let warnings = issues
                .iter()
                .filter(|i| i.severity == crate::esi::Severity::Warning)
                .count();
            EsiCheck {
                file,
                valid: warnings == issues.len() && !f.devices.is_empty(),
                devices: f.devices.len(),
                warnings,
                issues,
            }
        }
        Err(e) => EsiCheck {
            file,
            valid: false,
            devices: 0,
            warnings: 0,
            issues: vec![EsiIssue {
                line: e.line(),
                column: e.column(),
                message: e.message,
                severity: crate::esi::Severity::Error,
            }],
        },
    }
}
