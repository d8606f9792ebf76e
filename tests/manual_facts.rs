//! The oracle: literal facts from the five drive manuals (`tests/manual_facts/*.toml`, each with
//! the manual's section and line and a quote), checked against **both** sides that could be
//! wrong — the master's drive profile and the emulated drive, the latter only through the bus
//! (SDO uploads and downloads), never by reading a Rust constant. A wrong value in a profile
//! that the emulation copied would pass a master-against-emulator test; it fails here.
//!
//! What is checked, per kind of fact (see `tests/manual_facts/README.md`):
//! - every fact: its quote stands in the manual, at (or within three lines of) the line cited;
//! - `object`: data type, access, default, range and PDO mappability against the profile's
//!   dictionary; over SDO, the size and (for values the drive does not produce at run time) the
//!   default, and that a read-only entry refuses a write;
//! - `pdo_default` / `pdo_assign_default`: the profile's power-on mapping, and the emulated
//!   drive's mapping and assignment objects read over SDO;
//! - `modes`: the profile's supported modes and 0x6502 read over SDO;
//! - `quick_stop_option`: the profile's codes, and each code written to 0x605A over SDO;
//! - `cycle_times`: the profile's cycle times, and over SDO each one written to 0x1C32:02
//!   where the drive takes its cycle there;
//! - `pdo_limits`, `alarm`: the profile's tables.
//!
//! Entries the manual lists and a side does not have are printed as coverage gaps, not failures:
//! a failure is a contradiction of the manual.

use ecdrive::app::canopen::tools as cantools;
use ecdrive::app::ethercat::tools::{self, Target};
use ecdrive::canopen::master::{Master, MasterConfig};
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::cia402::{DriveCaps, ErrorEntry};
use ecdrive::drives::{self, CycleTimes, DriveProfile};
use ecdrive::od::{ConstValue, DataType, EntryAccess, ObjectAddress, ObjectDesc};
use ecdrive::pdo::PdoLimits;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Debug, Deserialize)]
struct FactFile {
    drive: String,
    manual: String,
    fact: Vec<Fact>,
}

#[derive(Debug, Clone, Deserialize)]
#[allow(dead_code)]
struct Fact {
    id: String,
    kind: String,
    source: String,
    quote: String,
    note: Option<String>,
    object: Option<String>,
    default: Option<toml::Value>,
    access: Option<String>,
    data_type: Option<String>,
    min: Option<toml::Value>,
    max: Option<toml::Value>,
    pdo_mappable: Option<bool>,
    modes: Option<Vec<String>>,
    pdo: Option<String>,
    entries: Option<Vec<String>>,
    sm: Option<String>,
    pdos: Option<Vec<String>>,
    max_rx_entries: Option<i64>,
    max_tx_entries: Option<i64>,
    max_rx_pdos: Option<i64>,
    max_tx_pdos: Option<i64>,
    max_rx_bytes: Option<i64>,
    max_tx_bytes: Option<i64>,
    cycle_times_us: Option<Vec<i64>>,
    code: Option<String>,
    meaning: Option<String>,
    values: Option<Vec<i64>>,
    alarm: Option<String>,
    name: Option<String>,
    error_code: Option<String>,
    emcy: Option<String>,
}

const DRIVES: [&str; 5] = ["mr-j4-tm", "bdhde", "blv-r", "asda-a2", "lexium-mdrive"];

fn facts_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/manual_facts")
}

fn load(drive: &str) -> FactFile {
    let p = facts_dir().join(format!("{drive}.toml"));
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The manuals: `ECDRIVE_MANUALS`, else `../shared/manuals` next to the checkout.
fn manual_text(name: &str) -> Option<String> {
    let dir = std::env::var_os("ECDRIVE_MANUALS")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/manuals")
        });
    std::fs::read_to_string(dir.join(name)).ok()
}

// ---------------------------------------------------------------------------------------------
// Values

/// A number as the facts write it: decimal, `0x` hex, negative decimal.
fn number(v: &toml::Value) -> Option<i128> {
    match v {
        toml::Value::Integer(i) => Some(i128::from(*i)),
        toml::Value::String(s) => {
            let t = s.trim().replace(['_', ' '], "");
            let (neg, t) = match t.strip_prefix('-') {
                Some(r) => (true, r.to_string()),
                None => (false, t),
            };
            let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
                Some(h) => i128::from_str_radix(h, 16).ok()?,
                None => t.parse::<i128>().ok()?,
            };
            Some(if neg { -v } else { v })
        }
        _ => None,
    }
}

fn const_number(c: ConstValue) -> Option<i128> {
    match c {
        ConstValue::Int(i) => Some(i128::from(i)),
        ConstValue::Uint(u) => Some(i128::from(u)),
        _ => None,
    }
}

/// `0xIIII:SS`, both hex (the facts write sub-indices as the manuals do, `0C` = 12).
fn address(s: &str) -> Option<ObjectAddress> {
    let (i, sub) = s.trim().split_once(':')?;
    let i = i.trim_start_matches("0x").trim_start_matches("0X");
    let sub = sub.trim_start_matches("0x").trim_start_matches("0X");
    Some(ObjectAddress::new(
        u16::from_str_radix(i, 16).ok()?,
        u8::from_str_radix(sub, 16).ok()?,
    ))
}

/// The CiA 301 name of a fact's data type, accepting the manuals' abbreviations.
fn data_type(s: &str) -> Option<DataType> {
    let n = s.trim().to_ascii_uppercase().replace([' ', '-'], "_");
    let n = match n.as_str() {
        "UINT8" | "U8" | "USINT" => "UNSIGNED8",
        "UINT16" | "U16" | "UINT" => "UNSIGNED16",
        "UINT32" | "U32" | "UDINT" => "UNSIGNED32",
        "UINT64" | "U64" => "UNSIGNED64",
        "INT8" | "I8" | "SINT" => "INTEGER8",
        "INT16" | "I16" | "INT" => "INTEGER16",
        "INT32" | "I32" | "DINT" => "INTEGER32",
        "INT64" | "I64" => "INTEGER64",
        "VISIBLESTRING" | "STRING" | "VIS_STRING" => "VISIBLE_STRING",
        "BOOL" => "BOOLEAN",
        other => other,
    }
    .to_string();
    [
        DataType::Boolean,
        DataType::Integer8,
        DataType::Integer16,
        DataType::Integer32,
        DataType::Integer64,
        DataType::Unsigned8,
        DataType::Unsigned16,
        DataType::Unsigned32,
        DataType::Unsigned64,
        DataType::Real32,
        DataType::VisibleString,
        DataType::OctetString,
        DataType::Domain,
    ]
    .into_iter()
    .find(|d| d.name() == n)
}

fn signed(dt: DataType) -> bool {
    matches!(
        dt,
        DataType::Integer8 | DataType::Integer16 | DataType::Integer32 | DataType::Integer64
    )
}

/// Little-endian bytes as a number of `dt`.
fn decode(dt: DataType, b: &[u8]) -> Option<i128> {
    let n = usize::from(dt.bit_len()?.div_ceil(8));
    let b = b.get(..n)?;
    let mut raw: u128 = 0;
    for (i, x) in b.iter().enumerate() {
        raw |= u128::from(*x) << (8 * i);
    }
    if signed(dt) && n > 0 && b[n - 1] & 0x80 != 0 {
        Some(raw as i128 - (1i128 << (8 * n)))
    } else {
        Some(raw as i128)
    }
}

// ---------------------------------------------------------------------------------------------
// The profile side, for both buses

/// What the checks read from a profile (EtherCAT or CANopen).
#[derive(Clone)]
struct ProfileView {
    name: &'static str,
    dictionary: Vec<ObjectDesc>,
    caps: DriveCaps,
    /// Default PDOs: mapping index → entries (index, sub, bits).
    pdos: BTreeMap<u16, Vec<(u16, u8, u8)>>,
    /// Default assignment (EtherCAT): 0x1C12/0x1C13 → PDO indices.
    assign: BTreeMap<u16, Vec<u16>>,
    cycle_times: Option<CycleTimes>,
    limits: PdoLimits,
    /// CANopen: the manuals state limits per PDO (entries per mapping object, bytes per
    /// frame), EtherCAT manuals per SyncManager.
    per_pdo: Option<PerPdo>,
}

#[derive(Clone, Copy)]
struct PerPdo {
    rx_entries: u8,
    tx_entries: u8,
    bytes: u8,
}

impl ProfileView {
    fn ethercat(p: &'static DriveProfile) -> Self {
        let mut pdos = BTreeMap::new();
        for pdo in p
            .default_mapping
            .rx
            .iter()
            .chain(p.default_mapping.tx.iter())
        {
            pdos.insert(
                pdo.index,
                pdo.entries
                    .iter()
                    .map(|e| (e.index, e.sub, e.bits))
                    .collect(),
            );
        }
        let mut assign = BTreeMap::new();
        assign.insert(
            0x1C12,
            p.default_mapping.rx.iter().map(|p| p.index).collect(),
        );
        assign.insert(
            0x1C13,
            p.default_mapping.tx.iter().map(|p| p.index).collect(),
        );
        Self {
            name: p.name,
            dictionary: p.dictionary.to_vec(),
            caps: p.caps,
            pdos,
            assign,
            cycle_times: Some(p.sync.cycle_times),
            limits: p.pdo_limits,
            per_pdo: None,
        }
    }

    fn canopen(p: &'static CanDriveProfile) -> Self {
        let mut pdos = BTreeMap::new();
        for d in p.pdo.default_rpdos {
            pdos.insert(
                0x1600 + u16::from(d.number) - 1,
                d.mapping.iter().map(|e| (e.index, e.sub, e.bits)).collect(),
            );
        }
        for d in p.pdo.default_tpdos {
            pdos.insert(
                0x1A00 + u16::from(d.number) - 1,
                d.mapping.iter().map(|e| (e.index, e.sub, e.bits)).collect(),
            );
        }
        Self {
            name: p.name,
            dictionary: p.dictionary.to_vec(),
            caps: p.caps,
            pdos,
            assign: BTreeMap::new(),
            cycle_times: None,
            limits: p.pdo.limits,
            per_pdo: Some(PerPdo {
                rx_entries: p
                    .pdo
                    .limits
                    .rx
                    .pdos
                    .iter()
                    .map(|r| r.max_entries)
                    .max()
                    .unwrap_or(0),
                tx_entries: p
                    .pdo
                    .limits
                    .tx
                    .pdos
                    .iter()
                    .map(|r| r.max_entries)
                    .max()
                    .unwrap_or(0),
                bytes: p.pdo.max_pdo_bytes,
            }),
        }
    }

    fn entry(&self, a: ObjectAddress) -> Option<ecdrive::od::EntryDesc> {
        self.dictionary
            .iter()
            .find(|o| o.index == a.index)
            .and_then(|o| o.entry(a.sub))
            .copied()
    }
}

fn profile_view(drive: &str) -> ProfileView {
    match drives::by_key(drive) {
        Some(p) => ProfileView::ethercat(p),
        None => {
            let (_, p, _) = cantools::EMULATED_NODES
                .iter()
                .find(|(n, _, _)| *n == drive)
                .unwrap_or_else(|| panic!("no profile for {drive}"));
            ProfileView::canopen(p)
        }
    }
}

fn mode_bit(m: &str) -> Option<u32> {
    Some(match m {
        "pp" => 0,
        "vl" => 1,
        "pv" => 2,
        "tq" => 3,
        "hm" => 5,
        "ip" => 6,
        "csp" => 7,
        "csv" => 8,
        "cst" => 9,
        _ => return None,
    })
}

fn entry_spec(s: &str) -> Option<(u16, u8, u8)> {
    let (a, bits) = s.split_once('/')?;
    let a = address(a)?;
    Some((a.index, a.sub, bits.trim().parse().ok()?))
}

/// Contradictions between the profile and the facts (empty: none); coverage gaps go to `gaps`.
fn check_profile(p: &ProfileView, facts: &[Fact], gaps: &mut Vec<String>) -> Vec<String> {
    let mut bad = Vec::new();
    let mut wrong = |f: &Fact, what: String| {
        bad.push(format!(
            "{} [{}] {}: {what} ({})",
            p.name, f.id, f.kind, f.source
        ))
    };
    for f in facts {
        match f.kind.as_str() {
            "object" => {
                let Some(a) = f.object.as_deref().and_then(address) else {
                    wrong(f, format!("unreadable object {:?}", f.object));
                    continue;
                };
                let Some(e) = p.entry(a) else {
                    gaps.push(format!(
                        "{}: {a} not in the profile's dictionary ({})",
                        p.name, f.id
                    ));
                    continue;
                };
                if let Some(dt) = f.data_type.as_deref().and_then(data_type)
                    && dt != e.data_type
                    && !(dt.is_string() && e.data_type.is_string())
                {
                    wrong(
                        f,
                        format!(
                            "{a} is {} in the profile, {} in the manual",
                            e.data_type.name(),
                            dt.name()
                        ),
                    );
                }
                match f.access.as_deref().map(str::to_ascii_lowercase).as_deref() {
                    Some("ro") | Some("const") if e.access.writable() => wrong(
                        f,
                        format!("{a} is writable in the profile, read-only in the manual"),
                    ),
                    Some("rw") if !(e.access.readable() && e.access.writable()) => wrong(
                        f,
                        format!(
                            "{a} is {} in the profile, rw in the manual",
                            e.access.short()
                        ),
                    ),
                    Some("wo") if !e.access.writable() => wrong(
                        f,
                        format!("{a} is not writable in the profile, wo in the manual"),
                    ),
                    _ => {}
                }
                if let Some(m) = f.pdo_mappable {
                    let has = e.access.intersects(EntryAccess::RXPDO | EntryAccess::TXPDO);
                    if has != m {
                        wrong(f, format!("{a} PDO-mappable: profile {has}, manual {m}"));
                    }
                }
                for (what, fact, prof) in [
                    ("default", &f.default, e.default),
                    ("minimum", &f.min, e.min),
                    ("maximum", &f.max, e.max),
                ] {
                    let Some(fv) = fact else { continue };
                    match (number(fv), const_number(prof), prof) {
                        (Some(want), Some(have), _) => {
                            // Compare as the entry's width holds it (0xFFFF and -1 in an
                            // INTEGER16 are one value).
                            let same = want == have
                                || e.data_type.bit_len().is_some_and(|b| {
                                    let m = (1i128 << b) - 1;
                                    want & m == have & m
                                });
                            if !same {
                                wrong(f, format!("{a} {what}: profile {have}, manual {want}"));
                            }
                        }
                        (None, _, ConstValue::Str(s)) => {
                            if let toml::Value::String(w) = fv
                                && w.trim() != s.trim()
                            {
                                wrong(f, format!("{a} {what}: profile {s:?}, manual {w:?}"));
                            }
                        }
                        (_, None, ConstValue::None) => gaps.push(format!(
                            "{}: {a} has no {what} in the profile ({})",
                            p.name, f.id
                        )),
                        _ => {}
                    }
                }
            }
            "modes" => {
                for m in f.modes.iter().flatten() {
                    match mode_bit(m) {
                        Some(bit) if p.caps.supported_modes.raw() & (1 << bit) == 0 => {
                            wrong(f, format!("mode {m} is not supported in the profile"))
                        }
                        None => wrong(f, format!("unknown mode {m:?}")),
                        _ => {}
                    }
                }
            }
            "pdo_default" => {
                let (Some(pdo), Some(entries)) = (
                    f.pdo
                        .as_deref()
                        .and_then(|s| number(&toml::Value::String(s.into()))),
                    &f.entries,
                ) else {
                    wrong(f, "pdo and entries needed".into());
                    continue;
                };
                let want: Option<Vec<_>> = entries.iter().map(|e| entry_spec(e)).collect();
                let Some(want) = want else {
                    wrong(f, format!("unreadable entries {entries:?}"));
                    continue;
                };
                match p.pdos.get(&(pdo as u16)) {
                    Some(have) if *have != want => wrong(
                        f,
                        format!(
                            "PDO 0x{pdo:04X}: profile {}, manual {}",
                            show(have),
                            show(&want)
                        ),
                    ),
                    None => gaps.push(format!(
                        "{}: PDO 0x{pdo:04X} not a default PDO in the profile ({})",
                        p.name, f.id
                    )),
                    _ => {}
                }
            }
            "pdo_assign_default" => {
                let sm =
                    f.sm.as_deref()
                        .and_then(|s| number(&toml::Value::String(s.into())));
                let want: Option<Vec<u16>> = f
                    .pdos
                    .iter()
                    .flatten()
                    .map(|s| number(&toml::Value::String(s.clone())).map(|n| n as u16))
                    .collect();
                if let (Some(sm), Some(want)) = (sm, want)
                    && let Some(have) = p.assign.get(&(sm as u16))
                    && *have != want
                {
                    wrong(
                        f,
                        format!("0x{sm:04X}: profile {have:04X?}, manual {want:04X?}"),
                    );
                }
            }
            "cycle_times" => {
                if let Some(ct) = &p.cycle_times {
                    for us in f.cycle_times_us.iter().flatten() {
                        if !ct.contains((*us as u32).saturating_mul(1000)) {
                            wrong(f, format!("cycle {us} µs is not accepted by the profile"));
                        }
                    }
                }
            }
            "quick_stop_option" => {
                for v in f.values.iter().flatten() {
                    if !p
                        .caps
                        .quick_stop_options
                        .iter()
                        .any(|q| i64::from(q.code) == *v)
                    {
                        wrong(
                            f,
                            format!("0x605A = {v} is not a quick-stop option of the profile"),
                        );
                    }
                }
            }
            "pdo_limits" => {
                let l = &p.limits;
                let (rx_e, tx_e, rx_b, tx_b) = match p.per_pdo {
                    Some(pp) => (
                        i64::from(pp.rx_entries),
                        i64::from(pp.tx_entries),
                        i64::from(pp.bytes),
                        i64::from(pp.bytes),
                    ),
                    None => (
                        i64::from(l.rx.max_entries),
                        i64::from(l.tx.max_entries),
                        i64::from(l.rx.max_bytes),
                        i64::from(l.tx.max_bytes),
                    ),
                };
                for (what, fact, prof) in [
                    ("RxPDO entries", f.max_rx_entries, rx_e),
                    ("TxPDO entries", f.max_tx_entries, tx_e),
                    ("RxPDOs", f.max_rx_pdos, i64::from(l.rx.max_assigned)),
                    ("TxPDOs", f.max_tx_pdos, i64::from(l.tx.max_assigned)),
                    ("RxPDO bytes", f.max_rx_bytes, rx_b),
                    ("TxPDO bytes", f.max_tx_bytes, tx_b),
                ] {
                    if let Some(want) = fact
                        && want != prof
                    {
                        wrong(f, format!("most {what}: profile {prof}, manual {want}"));
                    }
                }
            }
            "alarm" => {
                let Some(code) = f
                    .error_code
                    .as_deref()
                    .and_then(|s| number(&toml::Value::String(s.into())))
                else {
                    // No code in the manual: the alarm should still be named in the table.
                    if let Some(al) = &f.alarm
                        && !p.caps.error_table.iter().any(|e| norm(e.name) == norm(al))
                    {
                        gaps.push(format!(
                            "{}: {al} is not named in the profile's alarm table ({})",
                            p.name, f.id
                        ));
                    }
                    continue;
                };
                let table: &[ErrorEntry] = p.caps.error_table;
                match table.iter().find(|e| (code as u16) & e.mask == e.code) {
                    None => gaps.push(format!(
                        "{}: error code 0x{code:04X} ({}) not in the profile's alarm table ({})",
                        p.name,
                        f.alarm.as_deref().unwrap_or("?"),
                        f.id
                    )),
                    // Entries covering a range or a group of alarms (a mask, or several names
                    // in one) say nothing about one alarm's name.
                    Some(e) if e.mask != 0xFFFF || e.name.contains('/') || e.name.contains('-') => {
                    }
                    Some(e) => {
                        if let Some(al) = &f.alarm
                            && al.chars().any(|c| c.is_ascii_digit())
                            && e.name.chars().any(|c| c.is_ascii_digit())
                            && !norm(e.name).contains(&norm(al))
                            && !norm(al).contains(&norm(e.name))
                        {
                            wrong(
                                f,
                                format!(
                                    "0x{code:04X} is {} in the profile, {al} in the manual",
                                    e.name
                                ),
                            );
                        }
                    }
                }
            }
            _ => {}
        }
    }
    bad
}

fn norm(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_ascii_uppercase()
}

fn show(v: &[(u16, u8, u8)]) -> String {
    v.iter()
        .map(|(i, s, b)| format!("0x{i:04X}:{s:02X}/{b}"))
        .collect::<Vec<_>>()
        .join(" ")
}

// ---------------------------------------------------------------------------------------------
// The emulated side, through the bus

/// How the drive answers one SDO transfer.
enum Sdo {
    Bytes(Vec<u8>),
    Abort(u32),
    Failed(String),
}

/// The SDO client of either bus, against a freshly powered emulated drive.
trait SdoPort {
    fn upload(&mut self, a: ObjectAddress) -> Sdo;
    fn download(&mut self, a: ObjectAddress, bytes: &[u8]) -> Sdo;
}

/// The abort code in an error message (`… SDO abort 0x06010002 …`).
fn abort_in(text: &str) -> Option<u32> {
    let at = text.find("abort")?;
    let rest = &text[at..];
    let i = rest.find("0x")?;
    let h = rest.get(i + 2..i + 10)?;
    u32::from_str_radix(h, 16).ok()
}

/// The emulated EtherCAT drive, in-process, through ecdrive's tools (the wire in between).
struct EcPort(Target);

impl SdoPort for EcPort {
    fn upload(&mut self, a: ObjectAddress) -> Sdo {
        match tools::session(&self.0, move |bus| {
            tools::upload(bus, 0, a, Some(DataType::OctetString))
        }) {
            Ok(v) => Sdo::Bytes(
                (0..v.bytes.len() / 2)
                    .filter_map(|i| u8::from_str_radix(&v.bytes[2 * i..2 * i + 2], 16).ok())
                    .collect(),
            ),
            Err(e) => match abort_in(&e.to_string()) {
                Some(c) => Sdo::Abort(c),
                None => Sdo::Failed(e.to_string()),
            },
        }
    }

    fn download(&mut self, a: ObjectAddress, bytes: &[u8]) -> Sdo {
        let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        match tools::session(&self.0, move |bus| {
            tools::download(bus, 0, a, &hex, Some(DataType::OctetString))
        }) {
            Ok(_) => Sdo::Bytes(Vec::new()),
            Err(e) => match abort_in(&e.to_string()) {
                Some(c) => Sdo::Abort(c),
                None => Sdo::Failed(e.to_string()),
            },
        }
    }
}

/// The emulated CANopen drive on the in-process virtual bus.
struct CanPort {
    node: u8,
}

impl CanPort {
    fn master(&self) -> Master<ecdrive::sim::canopen::SimBus> {
        Master::new(cantools::demo_bus(), MasterConfig::default())
    }
}

fn can_result<T>(
    r: Result<T, ecdrive::canopen::error::CanError>,
    ok: impl FnOnce(T) -> Vec<u8>,
) -> Sdo {
    match r {
        Ok(v) => Sdo::Bytes(ok(v)),
        Err(e) => match abort_in(&e.to_string()) {
            Some(c) => Sdo::Abort(c),
            None => Sdo::Failed(e.to_string()),
        },
    }
}

impl SdoPort for CanPort {
    fn upload(&mut self, a: ObjectAddress) -> Sdo {
        let mut m = self.master();
        can_result(m.sdo_upload(self.node, a), |v| v)
    }

    fn download(&mut self, a: ObjectAddress, bytes: &[u8]) -> Sdo {
        let mut m = self.master();
        can_result(m.sdo_download(self.node, a, bytes), |_| Vec::new())
    }
}

/// Objects whose value the drive produces itself: measured or demanded values, status, and
/// what the drive sets from the motor it finds or the control mode (rated current and torque
/// 0x6075/0x6076, DC link voltage 0x6079, maximum motor speed 0x6080, SI units 0x60A8/0x60A9,
/// which the MR-J4-TM manual says are "set automatically with the control mode"). Their
/// manual "default" is not what a freshly powered drive must read back.
fn live(index: u16) -> bool {
    matches!(
        index,
        0x1001
            | 0x1002
            | 0x1003
            | 0x10F1
            | 0x603F
            | 0x6041
            | 0x6061
            | 0x6062
            | 0x6063
            | 0x6064
            | 0x606B
            | 0x606C
            | 0x6074
            | 0x6075
            | 0x6076
            | 0x6077
            | 0x6078
            | 0x6079
            | 0x6080
            | 0x60A8
            | 0x60A9
            | 0x60F4
            | 0x60FA
            | 0x60FC
            | 0x60FD
            | 0x2D11
            | 0x2D12
    )
}

/// Contradictions between the emulated drive (read over the bus) and the facts.
fn check_emulation(
    name: &str,
    port: &mut dyn SdoPort,
    facts: &[Fact],
    gaps: &mut Vec<String>,
) -> Vec<String> {
    let mut bad = Vec::new();
    for f in facts {
        let mut wrong = |what: String| {
            bad.push(format!(
                "{name} (emulated) [{}]: {what} ({})",
                f.id, f.source
            ))
        };
        match f.kind.as_str() {
            "object" => {
                let Some(a) = f.object.as_deref().and_then(address) else {
                    continue;
                };
                let dt = f.data_type.as_deref().and_then(data_type);
                let bytes = match port.upload(a) {
                    Sdo::Bytes(b) => b,
                    Sdo::Abort(0x0602_0000) | Sdo::Abort(0x0609_0011) => {
                        gaps.push(format!("{name} (emulated): {a} does not exist ({})", f.id));
                        continue;
                    }
                    Sdo::Abort(c) if f.access.as_deref() == Some("wo") => {
                        let _ = c;
                        continue;
                    }
                    Sdo::Abort(c) => {
                        wrong(format!("{a} upload aborted 0x{c:08X}"));
                        continue;
                    }
                    Sdo::Failed(e) => {
                        wrong(format!("{a} upload failed: {e}"));
                        continue;
                    }
                };
                if let Some(dt) = dt
                    && let Some(bits) = dt.bit_len()
                    && bytes.len() != usize::from(bits.div_ceil(8))
                {
                    wrong(format!(
                        "{a} read {} bytes, the manual's {} has {}",
                        bytes.len(),
                        dt.name(),
                        bits.div_ceil(8)
                    ));
                    continue;
                }
                if let (Some(fv), false) = (&f.default, live(a.index)) {
                    match (dt, number(fv)) {
                        (Some(dt), Some(want)) if !dt.is_string() => {
                            if let Some(have) = decode(dt, &bytes) {
                                let m = dt.bit_len().map_or(-1, |b| (1i128 << b) - 1);
                                if want & m != have & m {
                                    wrong(format!(
                                        "{a} reads {have} (0x{have:X}), the manual's default is {want} (0x{want:X})"
                                    ));
                                }
                            }
                        }
                        _ => {
                            if let toml::Value::String(w) = fv
                                && dt.is_some_and(DataType::is_string)
                            {
                                let have = String::from_utf8_lossy(&bytes)
                                    .trim_end_matches('\0')
                                    .trim()
                                    .to_string();
                                if have != w.trim() {
                                    wrong(format!("{a} reads {have:?}, the manual says {w:?}"));
                                }
                            }
                        }
                    }
                }
                if matches!(f.access.as_deref(), Some("ro") | Some("const")) {
                    match port.download(a, &bytes) {
                        Sdo::Abort(0x0601_0002) => {}
                        Sdo::Abort(c) => wrong(format!(
                            "{a} is read-only; a write aborted 0x{c:08X}, not 0x06010002"
                        )),
                        Sdo::Bytes(_) => wrong(format!(
                            "{a} is read-only in the manual; the emulated drive accepted a write"
                        )),
                        Sdo::Failed(e) => wrong(format!("{a} write failed: {e}")),
                    }
                }
            }
            "modes" => {
                if let Sdo::Bytes(b) = port.upload(ObjectAddress::new(0x6502, 0))
                    && let Some(raw) = decode(DataType::Unsigned32, &b)
                {
                    for m in f.modes.iter().flatten() {
                        if let Some(bit) = mode_bit(m)
                            && raw & (1 << bit) == 0
                        {
                            wrong(format!("0x6502 = 0x{raw:08X} lacks {m}"));
                        }
                    }
                }
            }
            "pdo_default" => {
                let Some(pdo) = f
                    .pdo
                    .as_deref()
                    .and_then(|s| number(&toml::Value::String(s.into())))
                else {
                    continue;
                };
                let pdo = pdo as u16;
                let want: Vec<_> = f
                    .entries
                    .iter()
                    .flatten()
                    .filter_map(|e| entry_spec(e))
                    .collect();
                let n = match port.upload(ObjectAddress::new(pdo, 0)) {
                    Sdo::Bytes(b) => b.first().copied().unwrap_or(0),
                    _ => {
                        gaps.push(format!(
                            "{name} (emulated): PDO 0x{pdo:04X} not readable ({})",
                            f.id
                        ));
                        continue;
                    }
                };
                let mut have = Vec::new();
                for s in 1..=n {
                    if let Sdo::Bytes(b) = port.upload(ObjectAddress::new(pdo, s))
                        && let Some(v) = decode(DataType::Unsigned32, &b)
                    {
                        have.push(((v >> 16) as u16, (v >> 8) as u8, v as u8));
                    }
                }
                if have != want {
                    wrong(format!(
                        "PDO 0x{pdo:04X} reads {}, the manual's default is {}",
                        show(&have),
                        show(&want)
                    ));
                }
            }
            "pdo_assign_default" => {
                let Some(sm) =
                    f.sm.as_deref()
                        .and_then(|s| number(&toml::Value::String(s.into())))
                else {
                    continue;
                };
                let sm = sm as u16;
                let want: Vec<u16> = f
                    .pdos
                    .iter()
                    .flatten()
                    .filter_map(|s| number(&toml::Value::String(s.clone())).map(|n| n as u16))
                    .collect();
                let n = match port.upload(ObjectAddress::new(sm, 0)) {
                    Sdo::Bytes(b) => b.first().copied().unwrap_or(0),
                    _ => continue,
                };
                let mut have = Vec::new();
                for s in 1..=n {
                    if let Sdo::Bytes(b) = port.upload(ObjectAddress::new(sm, s))
                        && let Some(v) = decode(DataType::Unsigned16, &b)
                    {
                        have.push(v as u16);
                    }
                }
                if have != want {
                    wrong(format!(
                        "0x{sm:04X} reads {have:04X?}, the manual's default is {want:04X?}"
                    ));
                }
            }
            "quick_stop_option" => {
                // Every code the manual lists is accepted in 0x605A.
                let a = ObjectAddress::new(0x605A, 0);
                if !matches!(port.upload(a), Sdo::Bytes(_)) {
                    continue;
                }
                for v in f.values.iter().flatten() {
                    let code = *v as i16;
                    match port.download(a, &code.to_le_bytes()) {
                        Sdo::Bytes(_) => {}
                        Sdo::Abort(c) => {
                            wrong(format!("0x605A = {v} refused with abort 0x{c:08X}"))
                        }
                        Sdo::Failed(e) => wrong(format!("0x605A = {v}: {e}")),
                    }
                }
            }
            "cycle_times" => {
                // A drive told its cycle in ns (0x1C32:02) accepts every cycle the manual lists.
                let a = ObjectAddress::new(0x1C32, 2);
                if !matches!(port.upload(a), Sdo::Bytes(_)) {
                    continue;
                }
                for us in f.cycle_times_us.iter().flatten() {
                    let ns = (*us as u32).saturating_mul(1000);
                    match port.download(a, &ns.to_le_bytes()) {
                        Sdo::Bytes(_) => {}
                        Sdo::Abort(c) => wrong(format!(
                            "0x1C32:02 = {ns} ns ({us} µs) refused with abort 0x{c:08X}"
                        )),
                        Sdo::Failed(e) => wrong(format!("0x1C32:02 = {ns} ns: {e}")),
                    }
                }
            }
            _ => {}
        }
    }
    bad
}

fn emulated_port(drive: &str) -> Box<dyn SdoPort> {
    match cantools::EMULATED_NODES
        .iter()
        .find(|(n, _, _)| *n == drive)
    {
        Some((_, _, node)) => Box::new(CanPort { node: *node }),
        None => Box::new(EcPort(Target::Sim(vec![drive.to_string()]))),
    }
}

// ---------------------------------------------------------------------------------------------
// The tests

/// Whitespace-insensitive text for quote matching.
fn squash(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn the_facts_are_many_unique_and_quote_their_manual() {
    let mut total = 0;
    let mut problems = Vec::new();
    for d in DRIVES {
        let file = load(d);
        assert_eq!(file.drive, d);
        total += file.fact.len();
        let mut ids = std::collections::HashSet::new();
        for f in &file.fact {
            if !ids.insert(f.id.clone()) {
                problems.push(format!("{d}: id {} twice", f.id));
            }
            if f.source.trim().is_empty() || f.quote.trim().is_empty() {
                problems.push(format!("{d} [{}]: no source or quote", f.id));
            }
        }
        let Some(text) = manual_text(&file.manual) else {
            // The manuals are not part of the checkout (they are the vendors' text): the
            // quotes are checked where they are at hand (next to the checkout, or
            // ECDRIVE_MANUALS), and said to be unchecked otherwise — but never in CI, where
            // an unchecked quote would pass as checked.
            assert!(
                std::env::var_os("ECDRIVE_CI").is_none(),
                "{d}: the manual {} is not at hand (../shared/manuals or ECDRIVE_MANUALS): \
                 under ECDRIVE_CI the quotes must be checked",
                file.manual
            );
            eprintln!(
                "SKIP quote check for {d}: {} not found (set ECDRIVE_MANUALS)",
                file.manual
            );
            continue;
        };
        let lines: Vec<String> = text.lines().map(squash).collect();
        for f in &file.fact {
            let parts: Vec<String> = f
                .quote
                .split('…')
                .map(squash)
                .filter(|p| !p.is_empty())
                .collect();
            let Some(first) = parts.first() else { continue };
            let line: Option<usize> = f
                .source
                .rsplit("line ")
                .next()
                .and_then(|t| t.split(|c: char| !c.is_ascii_digit()).next())
                .and_then(|t| t.parse().ok());
            let found_near = line.is_some_and(|l: usize| {
                let lo = l.saturating_sub(4);
                let hi = (l + 3).min(lines.len());
                let window = lines.get(lo..hi).map(|w| w.join(" ")).unwrap_or_default();
                parts.iter().all(|p| window.contains(p.as_str()))
            });
            if !found_near {
                let anywhere = lines.iter().any(|l| l.contains(first.as_str()));
                problems.push(format!(
                    "{d} [{}]: quote {:?} not at the cited line {:?}{}",
                    f.id,
                    f.quote,
                    line,
                    if anywhere {
                        " (it is elsewhere in the manual)"
                    } else {
                        " (nowhere in the manual)"
                    }
                ));
            }
        }
    }
    assert!(total >= 150, "{total} facts; the oracle needs at least 150");
    assert!(
        problems.is_empty(),
        "{} problems:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// Contradictions found and not yet resolved, each with the fact id and why it stands
/// (`tests/manual_facts/open.toml`). A contradiction not listed fails; a listed one that no
/// longer occurs fails too, so that the list only shrinks as the profiles and the emulation are
/// corrected.
#[derive(Debug, Deserialize)]
struct Open {
    #[serde(default)]
    open: Vec<OpenItem>,
}

#[derive(Debug, Deserialize)]
struct OpenItem {
    /// `profile` or `emulation`.
    side: String,
    drive: String,
    id: String,
    why: String,
}

fn open_items(side: &str) -> Vec<OpenItem> {
    let p = facts_dir().join("open.toml");
    let text = std::fs::read_to_string(&p).unwrap_or_default();
    let o: Open = toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    o.open.into_iter().filter(|i| i.side == side).collect()
}

/// Fail on contradictions not in the open list, and on open items that no longer occur.
fn judge(side: &str, found: &[(String, String, String)]) {
    let open = open_items(side);
    let mut unexpected = Vec::new();
    for (drive, id, text) in found {
        if !open.iter().any(|o| &o.drive == drive && &o.id == id) {
            unexpected.push(text.clone());
        }
    }
    let stale: Vec<String> = open
        .iter()
        .filter(|o| !found.iter().any(|(d, id, _)| d == &o.drive && id == &o.id))
        .map(|o| format!("{} [{}] ({})", o.drive, o.id, o.why))
        .collect();
    for (_, _, t) in found {
        eprintln!("contradiction: {t}");
    }
    assert!(
        unexpected.is_empty() && stale.is_empty(),
        "{} contradictions not in tests/manual_facts/open.toml:\n{}\n\n{} open items that no longer occur (remove them):\n{}",
        unexpected.len(),
        unexpected.join("\n"),
        stale.len(),
        stale.join("\n")
    );
}

fn fact_id(text: &str) -> String {
    text.split_once('[')
        .and_then(|(_, r)| r.split_once(']'))
        .map(|(id, _)| id.to_string())
        .unwrap_or_default()
}

#[test]
fn the_profiles_agree_with_the_manuals() {
    let mut found = Vec::new();
    let mut gaps = Vec::new();
    for d in DRIVES {
        let file = load(d);
        for b in check_profile(&profile_view(d), &file.fact, &mut gaps) {
            found.push((d.to_string(), fact_id(&b), b));
        }
    }
    for g in &gaps {
        eprintln!("gap: {g}");
    }
    judge("profile", &found);
}

#[test]
fn the_emulated_drives_agree_with_the_manuals_over_the_bus() {
    let mut found = Vec::new();
    let mut gaps = Vec::new();
    for d in DRIVES {
        let file = load(d);
        let mut port = emulated_port(d);
        for b in check_emulation(d, port.as_mut(), &file.fact, &mut gaps) {
            found.push((d.to_string(), fact_id(&b), b));
        }
    }
    for g in &gaps {
        eprintln!("gap: {g}");
    }
    judge("emulation", &found);
}

/// The oracle has teeth: one changed value in a scratch copy of a profile (the MR-J4-TM's
/// product code in 0x1018:02, its first default RxPDO's first entry) is caught.
#[test]
fn a_changed_profile_value_fails_the_oracle() {
    let file = load("mr-j4-tm");
    let good = profile_view("mr-j4-tm");
    let mut gaps = Vec::new();
    let before = check_profile(&good, &file.fact, &mut gaps).len();

    let mut changed = good.clone();
    let o = changed
        .dictionary
        .iter_mut()
        .find(|o| o.index == 0x1018)
        .expect("0x1018 in the profile");
    let entries: Vec<ecdrive::od::EntryDesc> = o
        .entries
        .iter()
        .map(|e| {
            let mut e = *e;
            if e.sub == 2
                && let ConstValue::Uint(v) = e.default
            {
                e.default = ConstValue::Uint(v + 1);
            }
            e
        })
        .collect();
    o.entries = Box::leak(entries.into_boxed_slice());
    let caught = check_profile(&changed, &file.fact, &mut gaps);
    assert!(
        caught.len() > before && caught.iter().any(|c| c.contains("0x1018:02")),
        "a changed product code was not caught: {caught:#?}"
    );

    let mut changed = good.clone();
    if let Some(first) = changed.pdos.values_mut().next()
        && let Some(e) = first.first_mut()
    {
        e.2 = e.2.wrapping_add(8);
    }
    assert!(
        check_profile(&changed, &file.fact, &mut gaps).len() > before,
        "a changed default PDO entry was not caught"
    );
}

/// A drive refuses a wrong remap (PRE-OP, as SOEM or TwinCAT users write it) with an abort
/// code its manual lists, not one of the emulation's own choosing: an object that cannot go
/// into an RxPDO, a non-PDO index in the assignment, more
/// entries than the mapping object has, an object that does not exist.
#[test]
fn remap_errors_abort_with_codes_the_manual_lists() {
    for d in ["mr-j4-tm", "bdhde"] {
        let file = load(d);
        let listed: Vec<u32> = file
            .fact
            .iter()
            .filter(|f| f.kind == "abort_code")
            .filter_map(|f| f.code.as_deref())
            .filter_map(|c| number(&toml::Value::String(c.into())))
            .map(|c| c as u32)
            .collect();
        assert!(listed.len() >= 10, "{d}: {listed:?}");
        let target = Target::Sim(vec![d.to_string()]);
        let results = tools::session(&target, |bus| {
            let mut w = |a: ObjectAddress, hex: &str| -> Result<(), String> {
                tools::download(bus, 0, a, hex, Some(DataType::OctetString))
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            };
            let mut out = Vec::new();
            // (Whether a mapping may change while it is assigned neither manual says: not
            // tested.) Unassign and clear the mapping, as the remap sequence does, then the
            // wrong writes.
            let unassign = w(ObjectAddress::new(0x1C12, 0), "00")
                .and_then(|()| w(ObjectAddress::new(0x1600, 0), "00"));
            out.push((
                "a TxPDO object (0x6041) in an RxPDO",
                w(ObjectAddress::new(0x1600, 1), "10004160"),
            ));
            out.push((
                "the identity (0x1018:01) in an RxPDO",
                w(ObjectAddress::new(0x1600, 1), "20011810"),
            ));
            out.push((
                "0x1700 in the RxPDO assignment",
                w(ObjectAddress::new(0x1C12, 1), "0017"),
            ));
            out.push((
                "64 entries in 0x1600",
                w(ObjectAddress::new(0x1600, 0), "40"),
            ));
            out.push((
                "an entry written while 0x1600:00 is not 0",
                w(ObjectAddress::new(0x1600, 1), "10004060")
                    .and_then(|()| w(ObjectAddress::new(0x1600, 0), "01"))
                    .and_then(|()| w(ObjectAddress::new(0x1600, 2), "10004060")),
            ));
            out.push((
                "an object that does not exist (0x5FFF)",
                w(ObjectAddress::new(0x5FFF, 0), "00"),
            ));
            Ok((unassign, out))
        })
        .unwrap();
        let (unassign, out) = results;
        assert!(
            unassign.is_ok(),
            "{d}: unassigning 0x1C12, clearing 0x1600: {unassign:?}"
        );
        for (what, r) in out {
            match r {
                Ok(()) => panic!("{d}: {what} was accepted"),
                Err(e) => {
                    let code = abort_in(&e).unwrap_or_else(|| panic!("{d}: {what}: {e}"));
                    assert!(
                        listed.contains(&code),
                        "{d}: {what} aborted 0x{code:08X}, which its manual does not list ({e})"
                    );
                }
            }
        }
    }
}
