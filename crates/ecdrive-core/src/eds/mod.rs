//! EDS and DCF (CiA 306) reading: the electronic data sheet every CANopen device ships, as the
//! ESI file is for an EtherCAT device.
//!
//! An EDS is an INI file: `[FileInfo]`, `[DeviceInfo]` (identity, PDO counts, bit rates),
//! `[DummyUsage]`, the object lists (`[MandatoryObjects]`, `[OptionalObjects]`,
//! `[ManufacturerObjects]`), one section per object (`[6040]`) and per sub-index
//! (`[1018sub1]`), and for `CompactSubObj` the `[XXXXValue]`/`[XXXXName]` sections. A DCF is an
//! EDS of one configured device: `ParameterValue` beside `DefaultValue`, and
//! `[DeviceComissioning]` with its node-ID.
//!
//! ```
//! use ecdrive_core::eds::EdsFile;
//!
//! let text = "[DeviceInfo]\nVendorNumber=0x2BE\nProductNumber=5111\n\
//!             [MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n\
//!             [1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\n\
//!             AccessType=ro\nDefaultValue=0x00020192\nPDOMapping=0\n\
//!             [1400]\nParameterName=RPDO 1\nObjectType=0x9\nSubNumber=1\n\
//!             [1400sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\n\
//!             DefaultValue=$NODEID+0x200\n";
//! let eds = EdsFile::parse(text.as_bytes())?;
//! assert_eq!(eds.device.vendor_number, Some(0x2BE));
//! assert_eq!(eds.entry(0x1000, 0).and_then(|e| e.default.resolve(5)), Some(0x0002_0192));
//! assert_eq!(eds.entry(0x1400, 1).and_then(|e| e.default.resolve(5)), Some(0x205));
//! assert!(eds.is_cia402());
//! # Ok::<(), ecdrive_core::eds::EdsError>(())
//! ```
//!
//! Real vendor files get many things wrong, and this reader takes them as CANopen tools do
//! (`../shared/eds-corpus` holds 28 of them; its README lists what they do): numbers decimal,
//! `0x` hex or (CiA 306) octal with a leading 0; `ObjectType` as `7`, `0x7` or `0x07`;
//! `DataType` decimal or short hex; access types in any case; empty `DefaultValue=`;
//! `$NODEID` formulas in several spellings (`$NodeID + 0x80`; `$MY_NODE_ID+0x200` with a
//! warning); a value with an inline `; comment`; `#` comment lines; a duplicate list key (both
//! objects are taken); `SubNumber` that does not match the sub-sections; objects listed but
//! absent, present but unlisted; bytes that are not UTF-8 (read as Latin-1). Every such problem
//! is a warning with its line ([`EdsFile::warnings`]), all of them at once. Only input over
//! [`MAX_FILE_BYTES`] or [`MAX_LINES`], or a file without a single object, is an [`EdsError`].
//! Nothing in this module panics on any input.

mod dictionary;

pub use dictionary::EdsDictionary;

use crate::od::DataType;
use std::collections::BTreeMap;
use std::fmt;

/// The largest file read (bytes): the biggest real EDS files are a few hundred kilobytes.
pub const MAX_FILE_BYTES: usize = 8 << 20;
/// The most lines read.
pub const MAX_LINES: usize = 200_000;

/// A file that cannot be read at all.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdsError {
    /// The line (1-based; 0: the file as a whole).
    pub line: usize,
    /// What is wrong.
    pub what: String,
}

impl fmt::Display for EdsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            f.write_str(&self.what)
        } else {
            write!(f, "line {}: {}", self.line, self.what)
        }
    }
}

impl std::error::Error for EdsError {}

/// Something the reader took in its own way or left out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdsWarning {
    /// The line (1-based; 0: the file as a whole).
    pub line: usize,
    /// What, and what the reader did.
    pub what: String,
}

impl fmt::Display for EdsWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            f.write_str(&self.what)
        } else {
            write!(f, "line {}: {}", self.line, self.what)
        }
    }
}

/// A value as the file writes it.
#[derive(Debug, Clone, PartialEq)]
pub enum EdsValue {
    /// Absent or empty.
    None,
    /// A number.
    Int(i128),
    /// `$NODEID + offset`: resolved with the node-ID ([`EdsValue::resolve`]).
    NodeId {
        /// The offset.
        offset: i128,
    },
    /// A real number (REAL32/REAL64 entries).
    Real(f64),
    /// Text (strings, and what does not read as a number).
    Text(String),
}

impl EdsValue {
    /// The value as a number for node `node` (`$NODEID` formulas resolved); `None` for text,
    /// reals and absent values.
    pub fn resolve(&self, node: u8) -> Option<i128> {
        match self {
            EdsValue::Int(v) => Some(*v),
            EdsValue::NodeId { offset } => Some(i128::from(node) + offset),
            _ => None,
        }
    }

    /// Whether the file gives no value.
    pub fn is_none(&self) -> bool {
        matches!(self, EdsValue::None)
    }
}

/// The access type of an entry (CiA 306 `AccessType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Read only.
    Ro,
    /// Write only.
    Wo,
    /// Read and write.
    Rw,
    /// Read and write, to be mapped in a TPDO (read-mainly).
    Rwr,
    /// Read and write, to be mapped in an RPDO (write-mainly).
    Rww,
    /// Constant.
    Const,
}

impl Access {
    /// Whether a master may write it (and map it into an RPDO).
    pub const fn writable(self) -> bool {
        matches!(self, Access::Wo | Access::Rw | Access::Rwr | Access::Rww)
    }

    /// Whether it can be read (and mapped into a TPDO).
    pub const fn readable(self) -> bool {
        !matches!(self, Access::Wo)
    }
}

/// The object code of an object (CiA 306 `ObjectType`, CiA 301 table 42).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectKind {
    /// 0x0: NULL.
    Null,
    /// 0x2: DOMAIN.
    Domain,
    /// 0x5: DEFTYPE.
    DefType,
    /// 0x6: DEFSTRUCT.
    DefStruct,
    /// 0x7: VAR (the value is sub-index 0).
    Var,
    /// 0x8: ARRAY.
    Array,
    /// 0x9: RECORD.
    Record,
}

impl ObjectKind {
    fn from_code(code: i128) -> Option<Self> {
        Some(match code {
            0 => ObjectKind::Null,
            2 => ObjectKind::Domain,
            5 => ObjectKind::DefType,
            6 => ObjectKind::DefStruct,
            7 => ObjectKind::Var,
            8 => ObjectKind::Array,
            9 => ObjectKind::Record,
            _ => return None,
        })
    }
}

/// One entry (a VAR, or a sub-index of an ARRAY or RECORD).
#[derive(Debug, Clone, PartialEq)]
pub struct EdsEntry {
    /// Sub-index (0 for a VAR).
    pub sub: u8,
    /// `ParameterName`.
    pub name: String,
    /// The data type, where the code is one ecdrive knows.
    pub data_type: Option<DataType>,
    /// `DataType` as written (a code; `None` when absent or unreadable).
    pub data_type_code: Option<u16>,
    /// `AccessType` (`None` when absent or unknown).
    pub access: Option<Access>,
    /// `PDOMapping`.
    pub pdo_mapping: bool,
    /// `DefaultValue`.
    pub default: EdsValue,
    /// `LowLimit`.
    pub low: EdsValue,
    /// `HighLimit`.
    pub high: EdsValue,
    /// `ParameterValue` (DCF: the configured value).
    pub parameter_value: EdsValue,
    /// Where its section starts.
    pub line: usize,
}

impl EdsEntry {
    /// Its size in bits, where its data type has a fixed one.
    pub fn bit_len(&self) -> Option<u16> {
        self.data_type.and_then(DataType::bit_len)
    }
}

/// One object.
#[derive(Debug, Clone, PartialEq)]
pub struct EdsObject {
    /// Index.
    pub index: u16,
    /// `ParameterName`.
    pub name: String,
    /// `ObjectType`.
    pub kind: ObjectKind,
    /// `SubNumber` as written (ARRAY/RECORD).
    pub sub_number: Option<u8>,
    /// The entries by sub-index (a VAR's value is sub-index 0).
    pub entries: BTreeMap<u8, EdsEntry>,
    /// Whether an object list names it.
    pub listed: bool,
    /// Where its section starts.
    pub line: usize,
}

/// `[DeviceInfo]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeviceInfo {
    /// `VendorName`.
    pub vendor_name: String,
    /// `VendorNumber` (1018h:01).
    pub vendor_number: Option<u32>,
    /// `ProductName`.
    pub product_name: String,
    /// `ProductNumber` (1018h:02).
    pub product_number: Option<u32>,
    /// `RevisionNumber` (1018h:03).
    pub revision_number: Option<u32>,
    /// `OrderCode`.
    pub order_code: String,
    /// The bit rates (kbit/s) the file marks supported (`BaudRate_N=1`).
    pub baud_rates: Vec<u32>,
    /// `NrOfRXPDO`.
    pub rx_pdos: Option<u16>,
    /// `NrOfTXPDO`.
    pub tx_pdos: Option<u16>,
    /// `LSS_Supported`.
    pub lss: Option<bool>,
}

/// An EDS or DCF file, read.
#[derive(Debug, Clone, PartialEq)]
pub struct EdsFile {
    /// `[FileInfo]`, every key as written (keys in lower case).
    pub file_info: BTreeMap<String, String>,
    /// `[DeviceInfo]`.
    pub device: DeviceInfo,
    /// The data types the file allows as dummy entries in a mapping (`[DummyUsage]`).
    pub dummy_usage: Vec<u16>,
    /// The objects by index.
    pub objects: BTreeMap<u16, EdsObject>,
    /// The node-ID of a DCF (`[DeviceComissioning] NodeID`).
    pub node_id: Option<u8>,
    /// Whether the file carries configured values (a DCF).
    pub dcf: bool,
    /// What the reader took in its own way, each with its line.
    pub warnings: Vec<EdsWarning>,
}

/// One `key=value` line.
struct Line<'a> {
    key: String,
    value: &'a str,
    line: usize,
}

/// One section.
struct Section<'a> {
    name: String,
    line: usize,
    lines: Vec<Line<'a>>,
}

impl<'a> Section<'a> {
    /// The first value of `key` (lower case).
    fn get(&self, key: &str) -> Option<(&'a str, usize)> {
        self.lines
            .iter()
            .find(|l| l.key == key)
            .map(|l| (l.value, l.line))
    }
}

/// The text of the file: UTF-8, else Latin-1 (a DOS code-page byte in a vendor's comment).
fn text_of(bytes: &[u8], warnings: &mut Vec<EdsWarning>) -> String {
    let bytes = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_string(),
        Err(e) => {
            let line = bytes[..e.valid_up_to()]
                .iter()
                .filter(|b| **b == b'\n')
                .count()
                + 1;
            warnings.push(EdsWarning {
                line,
                what: "the file is not UTF-8: read as Latin-1".into(),
            });
            bytes.iter().map(|&b| char::from(b)).collect()
        }
    }
}

/// A number as CiA 306 writes it: decimal, `0x` hex, octal with a leading 0; a sign.
fn number(s: &str) -> Option<i128> {
    let t = s.trim();
    let (neg, t) = match t.strip_prefix('-') {
        Some(r) => (true, r.trim_start()),
        None => (false, t.strip_prefix('+').unwrap_or(t)),
    };
    let v = if let Some(h) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        i128::from_str_radix(h, 16).ok()?
    } else if t.len() > 1 && t.starts_with('0') && t.bytes().all(|b| b.is_ascii_digit()) {
        i128::from_str_radix(&t[1..], 8).ok()?
    } else {
        t.parse::<i128>().ok()?
    };
    Some(if neg { -v } else { v })
}

/// A value: a number, a `$NODEID` formula, a real for real types, else text. `what` names the
/// key for warnings.
fn value(raw: &str, dt: Option<DataType>, line: usize, warnings: &mut Vec<EdsWarning>) -> EdsValue {
    let mut v = raw.trim();
    if v.is_empty() {
        return EdsValue::None;
    }
    if dt.is_some_and(DataType::is_string) {
        return EdsValue::Text(v.to_string());
    }
    // An inline comment after a number ("0x3ED ; prevent homing").
    if let Some(at) = v.find(';')
        && number(&v[..at]).is_some()
    {
        warnings.push(EdsWarning {
            line,
            what: format!("{v:?}: the comment after the value is not part of it"),
        });
        v = v[..at].trim();
    }
    if let Some(n) = number(v) {
        return EdsValue::Int(n);
    }
    // $NODEID formulas: "$NODEID+0x180", "$NodeID + 0x80", "0x180+$NODEID".
    let lower = v.to_ascii_lowercase();
    let node_names = ["$nodeid", "$my_node_id"];
    if let Some(name) = node_names.iter().find(|n| lower.contains(*n)) {
        if *name != "$nodeid" {
            warnings.push(EdsWarning {
                line,
                what: format!("{v:?}: {name} is not CiA 306's $NODEID: read as it"),
            });
        }
        let rest = lower.replace(name, "");
        let rest = rest.trim();
        let offset = if rest.is_empty() {
            Some(0)
        } else if let Some(r) = rest.strip_prefix('+') {
            number(r)
        } else if let Some(r) = rest.strip_suffix('+') {
            number(r)
        } else if let Some(r) = rest.strip_prefix('-') {
            number(r).map(|n| -n)
        } else {
            None
        };
        if let Some(offset) = offset {
            return EdsValue::NodeId { offset };
        }
    }
    if dt.is_some_and(DataType::is_real)
        && let Ok(f) = v.parse::<f64>()
    {
        return EdsValue::Real(f);
    }
    warnings.push(EdsWarning {
        line,
        what: format!("{v:?} is not a number: kept as text"),
    });
    EdsValue::Text(v.to_string())
}

/// Split the text into sections of key=value lines; comments (`;`, `#`) and blank lines
/// dropped.
fn sections<'a>(
    text: &'a str,
    warnings: &mut Vec<EdsWarning>,
) -> Result<Vec<Section<'a>>, EdsError> {
    let mut out: Vec<Section<'a>> = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        if line > MAX_LINES {
            return Err(EdsError {
                line,
                what: format!("more than {MAX_LINES} lines: not an EDS file"),
            });
        }
        let l = raw.trim();
        if l.is_empty() || l.starts_with(';') || l.starts_with('#') {
            continue;
        }
        if let Some(name) = l.strip_prefix('[') {
            let Some(name) = name.strip_suffix(']') else {
                warnings.push(EdsWarning {
                    line,
                    what: format!("{l:?}: a section header without its ']': left out"),
                });
                continue;
            };
            out.push(Section {
                name: name.trim().to_ascii_lowercase(),
                line,
                lines: Vec::new(),
            });
            continue;
        }
        let Some((k, v)) = l.split_once('=') else {
            warnings.push(EdsWarning {
                line,
                what: format!("{l:?} is neither a section nor key=value: left out"),
            });
            continue;
        };
        match out.last_mut() {
            Some(s) => s.lines.push(Line {
                key: k.trim().to_ascii_lowercase(),
                value: v.trim(),
                line,
            }),
            None => warnings.push(EdsWarning {
                line,
                what: format!("{l:?} before the first section: left out"),
            }),
        }
    }
    Ok(out)
}

/// The parts of an object section's name: index, and `sub` (`1018sub1`), `value` or `name`
/// (CompactSubObj tables).
enum SectionName {
    Object(u16),
    Sub(u16, u8),
    Value(u16),
    Names(u16),
}

fn section_name(s: &str) -> Option<SectionName> {
    let hex4 = |t: &str| {
        (t.len() == 4)
            .then(|| u16::from_str_radix(t, 16).ok())
            .flatten()
    };
    if let Some(i) = hex4(s) {
        return Some(SectionName::Object(i));
    }
    let (idx, rest) = s.split_at_checked(4)?;
    let index = hex4(idx)?;
    if let Some(sub) = rest.strip_prefix("sub") {
        return u8::from_str_radix(sub, 16)
            .ok()
            .map(|s| SectionName::Sub(index, s));
    }
    match rest {
        "value" => Some(SectionName::Value(index)),
        "name" => Some(SectionName::Names(index)),
        _ => None,
    }
}

fn access_of(s: &str) -> Option<Access> {
    Some(match s.trim().to_ascii_lowercase().as_str() {
        "ro" => Access::Ro,
        "wo" => Access::Wo,
        "rw" => Access::Rw,
        "rwr" => Access::Rwr,
        "rww" => Access::Rww,
        "const" => Access::Const,
        _ => return None,
    })
}

/// An entry from a section (an object's own for a VAR, or a `sub` section).
fn entry_of(sec: &Section<'_>, sub: u8, warnings: &mut Vec<EdsWarning>) -> EdsEntry {
    let name = sec
        .get("parametername")
        .map(|(v, _)| v.to_string())
        .unwrap_or_default();
    let data_type_code = match sec.get("datatype") {
        Some((v, line)) => match number(v).and_then(|n| u16::try_from(n).ok()) {
            Some(c) => Some(c),
            None => {
                warnings.push(EdsWarning {
                    line,
                    what: format!("DataType {v:?} does not read: the entry has no type"),
                });
                None
            }
        },
        None => None,
    };
    let data_type = data_type_code.and_then(DataType::from_code);
    let access = match sec.get("accesstype") {
        Some((v, line)) => {
            let a = access_of(v);
            if a.is_none() {
                warnings.push(EdsWarning {
                    line,
                    what: format!("AccessType {v:?} is not one of CiA 306's: taken as unknown"),
                });
            }
            a
        }
        None => None,
    };
    let pdo_mapping = sec
        .get("pdomapping")
        .and_then(|(v, _)| number(v))
        .is_some_and(|n| n != 0);
    let mut val = |key: &str| match sec.get(key) {
        Some((v, line)) => value(v, data_type, line, warnings),
        None => EdsValue::None,
    };
    EdsEntry {
        sub,
        name,
        data_type,
        data_type_code,
        access,
        pdo_mapping,
        default: val("defaultvalue"),
        low: val("lowlimit"),
        high: val("highlimit"),
        parameter_value: val("parametervalue"),
        line: sec.line,
    }
}

impl EdsFile {
    /// Read an EDS or DCF file.
    pub fn parse(bytes: &[u8]) -> Result<EdsFile, EdsError> {
        if bytes.len() > MAX_FILE_BYTES {
            return Err(EdsError {
                line: 0,
                what: format!(
                    "{} bytes: more than the {MAX_FILE_BYTES} an EDS file may have here",
                    bytes.len()
                ),
            });
        }
        if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
            return Err(EdsError {
                line: 0,
                what: "UTF-16 text: an EDS file is ASCII (CiA 306); save it as ASCII or UTF-8"
                    .into(),
            });
        }
        let mut warnings = Vec::new();
        let text = text_of(bytes, &mut warnings);
        let secs = sections(&text, &mut warnings)?;
        let mut r = Reading {
            file: EdsFile {
                file_info: BTreeMap::new(),
                device: DeviceInfo::default(),
                dummy_usage: Vec::new(),
                objects: BTreeMap::new(),
                node_id: None,
                dcf: false,
                warnings: Vec::new(),
            },
            listed: Vec::new(),
            subs: Vec::new(),
            compact_values: BTreeMap::new(),
            compact_names: BTreeMap::new(),
            warnings,
        };
        let mut seen_sections: BTreeMap<String, usize> = BTreeMap::new();
        for (k, sec) in secs.iter().enumerate() {
            if let Some(first) = seen_sections.insert(sec.name.clone(), sec.line) {
                r.warnings.push(EdsWarning {
                    line: sec.line,
                    what: format!(
                        "[{}] again (first at line {first}): the first is used",
                        sec.name
                    ),
                });
                continue;
            }
            r.section(k, sec);
        }
        r.sub_sections(&secs);
        r.compact_sections(&secs);
        r.lists_against_objects();
        let Reading {
            mut file,
            mut warnings,
            ..
        } = r;
        file.dcf |= file
            .objects
            .values()
            .any(|o| o.entries.values().any(|e| !e.parameter_value.is_none()));
        if file.objects.is_empty() {
            return Err(EdsError {
                line: 0,
                what: "no object section ([1000], [6040], …): not an EDS file".into(),
            });
        }
        // In the file's order (a stable sort: one line's warnings as they came).
        warnings.sort_by_key(|w| w.line);
        file.warnings = warnings;
        Ok(file)
    }

    /// An entry.
    pub fn entry(&self, index: u16, sub: u8) -> Option<&EdsEntry> {
        self.objects.get(&index)?.entries.get(&sub)
    }

    /// Whether the file describes a CiA 402 drive: 1000h's profile number 402 (its low 16
    /// bits), or the controlword and statusword objects.
    pub fn is_cia402(&self) -> bool {
        let by_type = self
            .entry(0x1000, 0)
            .and_then(|e| e.default.resolve(0))
            .is_some_and(|v| v & 0xFFFF == 402);
        by_type || (self.objects.contains_key(&0x6040) && self.objects.contains_key(&0x6041))
    }

    /// The supported drive modes (6502h: a DCF's configured value, else the default), if the
    /// file gives them as a 32-bit number (a larger one is no answer, not all modes).
    pub fn supported_modes(&self) -> Option<u32> {
        self.entry(0x6502, 0)
            .and_then(|e| {
                e.parameter_value
                    .resolve(0)
                    .or_else(|| e.default.resolve(0))
            })
            .and_then(|v| u32::try_from(v).ok())
    }

    /// The entries a PDO can carry: `PDOMapping=1`, a fixed-size type, writable (`rx`: into an
    /// RPDO) or readable (a TPDO). (index, sub, bits), in index order.
    pub fn mappable(&self, rx: bool) -> Vec<(u16, u8, u16)> {
        let mut out = Vec::new();
        for o in self.objects.values() {
            for e in o.entries.values() {
                let Some(bits) = e.bit_len() else { continue };
                let dir_ok = e
                    .access
                    .is_some_and(|a| if rx { a.writable() } else { a.readable() });
                if e.pdo_mapping && dir_ok && bits > 0 {
                    out.push((o.index, e.sub, bits));
                }
            }
        }
        out
    }
}

/// An EDS file being read, section by section: the file so far, and what can only be placed
/// once every section is read (the object lists, the sub-index sections, the CompactSubObj
/// values and names, each by its section's number).
struct Reading {
    file: EdsFile,
    listed: Vec<(u16, usize)>,
    subs: Vec<(u16, u8, usize)>,
    compact_values: BTreeMap<u16, usize>,
    compact_names: BTreeMap<u16, usize>,
    warnings: Vec<EdsWarning>,
}

impl Reading {
    /// Section `k` of the file, read (a section seen before is left out by the caller).
    fn section(&mut self, k: usize, sec: &Section<'_>) {
        let warnings = &mut self.warnings;
        // Duplicate keys within a section (lists handled below).
        let is_list = matches!(
            sec.name.as_str(),
            "mandatoryobjects" | "optionalobjects" | "manufacturerobjects"
        );
        if !is_list {
            let mut keys: BTreeMap<&str, usize> = BTreeMap::new();
            for l in &sec.lines {
                if let Some(first) = keys.insert(l.key.as_str(), l.line) {
                    warnings.push(EdsWarning {
                        line: l.line,
                        what: format!(
                            "{} again in [{}] (first at line {first}): the first is used",
                            l.key, sec.name
                        ),
                    });
                }
            }
        }
        let file = &mut self.file;
        match sec.name.as_str() {
            "fileinfo" => {
                for l in &sec.lines {
                    file.file_info
                        .entry(l.key.clone())
                        .or_insert_with(|| l.value.to_string());
                }
            }
            "deviceinfo" => file.device = device_info(sec, warnings),
            "dummyusage" => {
                for l in &sec.lines {
                    if let Some(t) = l.key.strip_prefix("dummy")
                        && let Ok(code) = u16::from_str_radix(t, 16)
                        && number(l.value).is_some_and(|n| n != 0)
                    {
                        file.dummy_usage.push(code);
                    }
                }
            }
            "devicecomissioning" | "devicecommissioning" => {
                file.dcf = true;
                file.node_id = sec
                    .get("nodeid")
                    .and_then(|(v, _)| number(v))
                    .and_then(|n| u8::try_from(n).ok());
            }
            "mandatoryobjects" | "optionalobjects" | "manufacturerobjects" => {
                object_list(sec, &mut self.listed, warnings);
            }
            name => match section_name(name) {
                Some(SectionName::Object(index)) => {
                    file.objects.insert(index, object_of(sec, index, warnings));
                }
                Some(SectionName::Sub(index, sub)) => self.subs.push((index, sub, k)),
                Some(SectionName::Value(index)) => {
                    self.compact_values.insert(index, k);
                }
                Some(SectionName::Names(index)) => {
                    self.compact_names.insert(index, k);
                }
                None => {
                    if !matches!(name, "comments" | "tools") {
                        warnings.push(EdsWarning {
                            line: sec.line,
                            what: format!("[{name}] is not a section of CiA 306: left out"),
                        });
                    }
                }
            },
        }
    }

    /// Sub-index sections into their objects.
    fn sub_sections(&mut self, secs: &[Section<'_>]) {
        for &(index, sub, k) in &self.subs {
            let Some(sec) = secs.get(k) else { continue };
            let e = entry_of(sec, sub, &mut self.warnings);
            match self.file.objects.get_mut(&index) {
                Some(o) => {
                    o.entries.insert(sub, e);
                }
                None => self.warnings.push(EdsWarning {
                    line: sec.line,
                    what: format!(
                        "[{}] has no object section [{index:04X}]: left out",
                        sec.name
                    ),
                }),
            }
        }
    }

    /// CompactSubObj values and names into their objects' entries.
    fn compact_sections(&mut self, secs: &[Section<'_>]) {
        for (&index, &k) in &self.compact_values {
            if let (Some(o), Some(sec)) = (self.file.objects.get_mut(&index), secs.get(k)) {
                for l in &sec.lines {
                    if let Some(sub) = number(&l.key).and_then(|s| u8::try_from(s).ok())
                        && let Some(e) = o.entries.get_mut(&sub)
                    {
                        e.default = value(l.value, e.data_type, l.line, &mut self.warnings);
                    }
                }
            }
        }
        for (&index, &k) in &self.compact_names {
            if let (Some(o), Some(sec)) = (self.file.objects.get_mut(&index), secs.get(k)) {
                for l in &sec.lines {
                    if let Some(sub) = number(&l.key).and_then(|s| u8::try_from(s).ok())
                        && let Some(e) = o.entries.get_mut(&sub)
                    {
                        e.name = l.value.to_string();
                    }
                }
            }
        }
    }

    /// The object lists against the objects: a listed object without a section, a section
    /// no list names, a SubNumber the sub-index sections do not match.
    fn lists_against_objects(&mut self) {
        let (file, warnings) = (&mut self.file, &mut self.warnings);
        for (index, line) in &self.listed {
            match file.objects.get_mut(index) {
                Some(o) => o.listed = true,
                None => warnings.push(EdsWarning {
                    line: *line,
                    what: format!("{index:04X}h is listed but has no section: left out"),
                }),
            }
        }
        for o in file.objects.values() {
            if !o.listed && !self.listed.is_empty() {
                warnings.push(EdsWarning {
                    line: o.line,
                    what: format!(
                        "{:04X}h has a section but no object list names it: taken",
                        o.index
                    ),
                });
            }
            if let Some(n) = o.sub_number {
                let have = o.entries.len();
                if matches!(o.kind, ObjectKind::Array | ObjectKind::Record)
                    && usize::from(n) != have
                {
                    warnings.push(EdsWarning {
                        line: o.line,
                        what: format!(
                            "{:04X}h says SubNumber={n} and has {have} sub-index section(s): \
                             those are taken",
                            o.index
                        ),
                    });
                }
            }
        }
    }
}

/// An object list section ([MandatoryObjects], …): its indices with their lines into
/// `listed`; a key twice, a value that is no index and a count that does not match are said.
fn object_list(sec: &Section<'_>, listed: &mut Vec<(u16, usize)>, warnings: &mut Vec<EdsWarning>) {
    let mut keys: BTreeMap<&str, usize> = BTreeMap::new();
    let mut count = None;
    let mut n = 0usize;
    for l in &sec.lines {
        if l.key == "supportedobjects" {
            count = number(l.value);
            continue;
        }
        if let Some(first) = keys.insert(l.key.as_str(), l.line) {
            warnings.push(EdsWarning {
                line: l.line,
                what: format!(
                    "list key {} again in [{}] (first at line {first}): both objects are taken",
                    l.key, sec.name
                ),
            });
        }
        match number(l.value).and_then(|v| u16::try_from(v).ok()) {
            Some(i) => {
                listed.push((i, l.line));
                n += 1;
            }
            None => warnings.push(EdsWarning {
                line: l.line,
                what: format!("{:?} in [{}] is not an index", l.value, sec.name),
            }),
        }
    }
    if let Some(c) = count
        && c != n as i128
    {
        warnings.push(EdsWarning {
            line: sec.line,
            what: format!(
                "[{}] says SupportedObjects={c} and lists {n}: all {n} are taken",
                sec.name
            ),
        });
    }
}

/// An object section ([6040]): its kind (VAR where it says none, or one CiA 301 does not
/// have), name and SubNumber, its entry for a VAR or DOMAIN, and its CompactSubObj entries.
fn object_of(sec: &Section<'_>, index: u16, warnings: &mut Vec<EdsWarning>) -> EdsObject {
    let kind = match sec.get("objecttype") {
        Some((v, line)) => match number(v).and_then(ObjectKind::from_code) {
            Some(k) => k,
            None => {
                warnings.push(EdsWarning {
                    line,
                    what: format!(
                        "ObjectType {v:?} of {index:04X}h is not one \
                             of CiA 301's: read as VAR"
                    ),
                });
                ObjectKind::Var
            }
        },
        None => ObjectKind::Var,
    };
    let mut obj = EdsObject {
        index,
        name: sec
            .get("parametername")
            .map(|(v, _)| v.to_string())
            .unwrap_or_default(),
        kind,
        sub_number: sec
            .get("subnumber")
            .and_then(|(v, _)| number(v))
            .and_then(|n| u8::try_from(n).ok()),
        entries: BTreeMap::new(),
        listed: false,
        line: sec.line,
    };
    if matches!(kind, ObjectKind::Var | ObjectKind::Domain) {
        obj.entries.insert(0, entry_of(sec, 0, warnings));
    }
    if let Some((v, line)) = sec.get("compactsubobj")
        && let Some(n) = number(v).filter(|n| *n > 0)
    {
        compact(&mut obj, sec, n, line, warnings);
    }
    obj
}

/// `[DeviceInfo]`.
fn device_info(sec: &Section<'_>, warnings: &mut Vec<EdsWarning>) -> DeviceInfo {
    let text = |k: &str| sec.get(k).map(|(v, _)| v.to_string()).unwrap_or_default();
    let mut u32_of = |k: &str| match sec.get(k) {
        Some((v, line)) => match number(v).and_then(|n| u32::try_from(n).ok()) {
            Some(n) => Some(n),
            None if v.is_empty() => None,
            None => {
                warnings.push(EdsWarning {
                    line,
                    what: format!("{k} {v:?} is not a 32-bit number: not taken"),
                });
                None
            }
        },
        None => None,
    };
    let vendor_number = u32_of("vendornumber");
    let product_number = u32_of("productnumber");
    let revision_number = u32_of("revisionnumber");
    let rx_pdos = u32_of("nrofrxpdo").and_then(|n| u16::try_from(n).ok());
    let tx_pdos = u32_of("nroftxpdo").and_then(|n| u16::try_from(n).ok());
    let baud_rates = [10, 20, 50, 125, 250, 500, 800, 1000]
        .into_iter()
        .filter(|r| {
            sec.get(&format!("baudrate_{r}"))
                .and_then(|(v, _)| number(v))
                .is_some_and(|n| n != 0)
        })
        .collect();
    let lss = sec
        .get("lss_supported")
        .and_then(|(v, _)| number(v))
        .map(|n| n != 0);
    DeviceInfo {
        vendor_name: text("vendorname"),
        vendor_number,
        product_name: text("productname"),
        product_number,
        revision_number,
        order_code: text("ordercode"),
        baud_rates,
        rx_pdos,
        tx_pdos,
        lss,
    }
}

/// `CompactSubObj=n` of an ARRAY: sub 0 holds n (UNSIGNED8, ro), subs 1..=n take the object's
/// type, access and mapping (CiA 306 §4.5.2.2).
fn compact(
    obj: &mut EdsObject,
    sec: &Section<'_>,
    n: i128,
    line: usize,
    warnings: &mut Vec<EdsWarning>,
) {
    let Ok(n) = u8::try_from(n.min(254)) else {
        return;
    };
    if n == 254 {
        warnings.push(EdsWarning {
            line,
            what: format!("CompactSubObj of {:04X}h over 254: cut to 254", obj.index),
        });
    }
    let proto = entry_of(sec, 1, warnings);
    obj.entries.insert(
        0,
        EdsEntry {
            sub: 0,
            name: "Number of entries".into(),
            data_type: Some(DataType::Unsigned8),
            data_type_code: Some(DataType::Unsigned8.code()),
            access: Some(Access::Ro),
            pdo_mapping: false,
            default: EdsValue::Int(i128::from(n)),
            low: EdsValue::None,
            high: EdsValue::None,
            parameter_value: EdsValue::None,
            line: sec.line,
        },
    );
    for s in 1..=n {
        let mut e = proto.clone();
        e.sub = s;
        e.name = format!("{} {s}", obj.name);
        e.default = EdsValue::None;
        obj.entries.insert(s, e);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_as_cia_306_writes_them() {
        assert_eq!(number("0x1A"), Some(26));
        assert_eq!(number("26"), Some(26));
        assert_eq!(number("032"), Some(26));
        assert_eq!(number("-5"), Some(-5));
        assert_eq!(number("0"), Some(0));
        assert_eq!(number("x"), None);
    }

    #[test]
    fn node_id_formulas_in_their_spellings() {
        let mut w = Vec::new();
        for s in [
            "$NODEID+0x180",
            "$NodeID + 0x180",
            "$NODEID +0x180",
            "0x180+$NODEID",
        ] {
            assert_eq!(
                value(s, None, 1, &mut w),
                EdsValue::NodeId { offset: 0x180 },
                "{s}"
            );
        }
        assert!(w.is_empty());
        assert_eq!(
            value("$MY_NODE_ID+0x200", None, 7, &mut w),
            EdsValue::NodeId { offset: 0x200 }
        );
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].line, 7);
    }

    #[test]
    fn compact_sub_objects_and_odd_spellings() {
        let text = "[OptionalObjects]\nSupportedObjects=2\n1=0x1016\n1=0x2000\n\
                    [1016]\nParameterName=Consumer heartbeat time\nObjectType=8\n\
                    DataType=7\nAccessType=RW\nCompactSubObj=2\n\
                    [1016Value]\nNrOfEntries=1\n2=0x00050064\n\
                    [2000]\nParameterName=Odd\nObjectType=0x07\nDataType=0x7\nAccessType=Rww\n\
                    DefaultValue=0x3ED ; a comment\nPDOMapping=1\n";
        let f = EdsFile::parse(text.as_bytes()).unwrap();
        let o = &f.objects[&0x1016];
        assert_eq!(o.entries.len(), 3);
        assert_eq!(o.entries[&0].default, EdsValue::Int(2));
        assert_eq!(o.entries[&2].default, EdsValue::Int(0x0005_0064));
        assert_eq!(o.entries[&1].access, Some(Access::Rw));
        let e = f.entry(0x2000, 0).unwrap();
        assert_eq!(e.default, EdsValue::Int(0x3ED));
        assert_eq!(e.access, Some(Access::Rww));
        assert_eq!(f.mappable(true), vec![(0x2000, 0, 32)]);
        // Both objects of the duplicate list key are taken, with a warning each for the key
        // and the comment.
        assert!(f.objects[&0x2000].listed && o.listed);
        assert!(
            f.warnings
                .iter()
                .any(|w| w.what.contains("list key 1 again"))
        );
        assert!(f.warnings.iter().any(|w| w.what.contains("comment")));
    }

    #[test]
    fn what_is_not_an_eds_file_is_one_error() {
        assert!(EdsFile::parse(b"").is_err());
        assert!(EdsFile::parse(b"[FileInfo]\nFileName=x\n").is_err());
        let big = vec![b'a'; MAX_FILE_BYTES + 1];
        assert!(EdsFile::parse(&big).is_err());
        // Latin-1 bytes are read, with a warning.
        let f =
            EdsFile::parse(b"[1000]\nParameterName=Ger\x94t\nDataType=7\nAccessType=ro\n").unwrap();
        assert_eq!(f.objects[&0x1000].name, "Ger\u{94}t");
        assert_eq!(f.warnings.len(), 1);
    }
}
