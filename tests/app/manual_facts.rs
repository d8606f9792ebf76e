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
//! - `pdo_limits`: the profile's tables; over the bus, the most entries the manual allows
//!   written into the first RxPDO and TxPDO, and one more refused with a listed abort code;
//! - `alarm`: the profile's tables; each alarm raised in an emulated EtherCAT drive, its 0x603F
//!   read in the process data;
//! - `transition`: the profile's capabilities in the core's CiA 402 state machine react to each
//!   controlword as the manual says; the emulated CANopen drives over SDO, the EtherCAT drives
//!   by process data in OP driven by SOEM (`crates/ecdrive-sim/tests/sim/sim_soem.rs`);
//! - `abort_code`: provoked on the emulated drives (a missing object and sub-index, a write to
//!   a read-only object, too long and too short a value, a value past each range, whose ends
//!   must be taken): each answer a code the manual lists for that cause;
//! - `unit`: the conversions the master does, restated per fact (`unit_claim`), against the
//!   profile's units; and through a run: 1 rev/s for 0.5 s in user units of one revolution
//!   moves an emulated EtherCAT drive half a revolution in the manual's units.
//!
//! A contradiction fails unless `tests/manual_facts/open.toml` lists it with its reason; so
//! does a gap — a fact a side cannot be checked against — unless a `[[gap]]` class there
//! explains it. Entries that no longer match anything fail too: the lists only shrink.
//! `a_changed_profile_value_fails_the_oracle` and `a_wrong_value_in_an_emulated_drive_fails_the_oracle`
//! show that a wrong value on either side is caught.

use ecdrive::canopen::master::{Master, MasterConfig};
use ecdrive::canopen::profile::CanDriveProfile;
use ecdrive::cia402::{DriveCaps, ErrorEntry, State};
use ecdrive::drives::{self, CycleTimes, DriveProfile};
use ecdrive::od::{ConstValue, DataType, EntryAccess, ObjectAddress, ObjectDesc};
use ecdrive::pdo::PdoLimits;
use ecdrive_cli::app::canopen::tools as cantools;
use ecdrive_cli::app::ethercat::tools::{self, Target};
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
    from: Option<String>,
    to: Option<String>,
    quantity: Option<String>,
    value: Option<String>,
    controlword: Option<String>,
    exists: Option<bool>,
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

/// The emulated CANopen drive on the in-process virtual bus (`bus` builds it: the demo's
/// three drives, or a changed one for the teeth test).
struct CanPort {
    node: u8,
    bus: fn() -> ecdrive::sim::canopen::SimBus,
}

impl CanPort {
    fn master(&self) -> Master<ecdrive::sim::canopen::SimBus> {
        Master::new((self.bus)(), MasterConfig::default())
    }
}

/// The emulated BLV-R with one wrong value in its own table: 6065h (following error window)
/// reads 123 at power-on.
fn blv_r_with_a_wrong_value() -> ecdrive::sim::canopen::SimBus {
    use ecdrive::od::{ConstValue, ObjectDesc};
    use ecdrive::sim::canopen::{EmulatedNode, NodeSpec, SimBus, drives};
    let base = &drives::blv_r::SPEC;
    let dictionary: Vec<ObjectDesc> = base
        .dictionary
        .iter()
        .map(|o| {
            if o.index != 0x6065 {
                return *o;
            }
            let entries: Vec<_> = o
                .entries
                .iter()
                .map(|e| e.default(ConstValue::Uint(123)))
                .collect();
            ObjectDesc {
                entries: Vec::leak(entries),
                ..*o
            }
        })
        .collect();
    let spec: &'static NodeSpec = Box::leak(Box::new(NodeSpec {
        dictionary: Vec::leak(dictionary),
        ..*base
    }));
    let mut bus = SimBus::new();
    bus.add_node(EmulatedNode::new(spec, 1).expect("node"));
    bus
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

// ---------------------------------------------------------------------------------------------
// Transitions, abort codes, ranges, alarms

/// A state as the facts name it ("Switch on disabled", "switch_on_disabled").
fn state_named(s: &str) -> Option<State> {
    let n = s.to_ascii_lowercase().replace('_', " ");
    State::ALL
        .into_iter()
        .find(|st| st.name().to_ascii_lowercase() == n)
}

/// A transition fact: (from, to, controlword, exists).
fn transition(f: &Fact) -> Option<(State, State, u16, bool)> {
    let from = state_named(f.from.as_deref()?)?;
    let to = state_named(f.to.as_deref()?)?;
    let cw = number(&toml::Value::String(f.controlword.clone()?))? as u16;
    Some((from, to, cw, f.exists.unwrap_or(true)))
}

/// The state a drive of `config` reaches from `from` when it receives `cw` (two steps for
/// "switch on + enable operation" in Ready to switch on: 3 then 4). The motor turns meanwhile
/// (no automatic end of a quick stop).
fn device_reaction(config: ecdrive::cia402::device::DeviceConfig, from: State, cw: u16) -> State {
    use ecdrive::cia402::ControlWord;
    use ecdrive::cia402::device::{Device, DeviceInputs};
    let mut d = Device::with_state(config, from);
    // The motor still turns: no automatic end of a quick stop meanwhile.
    let mut inputs = DeviceInputs::new(ControlWord::from_bits_retain(cw));
    inputs.motion_stopped = false;
    d.step(&inputs);
    if d.state() == State::SwitchedOn && from == State::ReadyToSwitchOn && cw & 0x000F == 0x000F {
        d.step(&inputs);
    }
    d.state()
}

/// The profile side of the transition facts: the master's model of the drive (its profile's
/// capabilities — state skipping, transition 16, the quick-stop option — in the CiA 402 state
/// machine of the core) reacts to each fact's controlword in its `from` state as the manual
/// says.
fn check_transitions_profile(drive: &str, facts: &[Fact], gaps: &mut Vec<String>) -> Vec<String> {
    let caps = profile_view(drive).caps;
    let config =
        ecdrive::cia402::device::DeviceConfig::from_caps(&caps, caps.default_quick_stop_option);
    let mut bad = Vec::new();
    for f in facts.iter().filter(|f| f.kind == "transition") {
        let Some((from, to, cw, exists)) = transition(f) else {
            gaps.push(format!(
                "{drive}: transition fact not understood ({})",
                f.id
            ));
            continue;
        };
        let got = device_reaction(config, from, cw);
        if (got == to) != exists {
            bad.push(format!(
                "{drive} (profile) [{}]: {from} with controlword 0x{cw:04X} goes to {got}, the \
                 manual says {}{to} ({})",
                f.id,
                if exists { "" } else { "not " },
                f.source
            ));
        }
    }
    bad
}

/// The emulated side of the transition facts, over the bus: a CANopen drive is taken to each
/// fact's `from` state and sent its controlword by SDO (0x6040), and its statusword read back
/// (0x6041). The EtherCAT drives act on the controlword only in OP, by process data: SOEM does
/// the same for them over veth (`crates/ecdrive-sim/tests/sim/sim_soem.rs`, `soem_drives_the_transitions_the_manuals_list`).
fn check_transitions_emulated(drive: &str, facts: &[Fact], gaps: &mut Vec<String>) -> Vec<String> {
    let mut bad = Vec::new();
    let Some((_, _, node)) = cantools::EMULATED_NODES
        .iter()
        .find(|(n, _, _)| *n == drive)
        .copied()
    else {
        gaps.push(format!(
            "{drive}: transitions over the bus by process data in OP (SOEM, crates/ecdrive-sim/tests/sim/sim_soem.rs)"
        ));
        return bad;
    };
    let cw_at = ObjectAddress::new(0x6040, 0);
    let sw_at = ObjectAddress::new(0x6041, 0);
    for f in facts.iter().filter(|f| f.kind == "transition") {
        let Some((from, to, cw, exists)) = transition(f) else {
            continue;
        };
        // The way to `from` from Switch on disabled, and whether it can be reached by
        // controlword alone.
        let path: &[u16] = match from {
            State::SwitchOnDisabled => &[0x0000],
            State::ReadyToSwitchOn => &[0x0000, 0x0006],
            State::SwitchedOn => &[0x0000, 0x0006, 0x0007],
            State::OperationEnabled => &[0x0000, 0x0006, 0x0007, 0x000F],
            State::QuickStopActive => &[0x0000, 0x0006, 0x0007, 0x000F, 0x0002],
            _ => {
                gaps.push(format!(
                    "{drive}: {from} cannot be reached by controlword ({})",
                    f.id
                ));
                continue;
            }
        };
        let mut m = Master::new(cantools::demo_bus(), MasterConfig::default());
        let mut reached = true;
        for c in path {
            if m.sdo_download(node, cw_at, &c.to_le_bytes()).is_err() {
                reached = false;
            }
        }
        let read = |m: &mut Master<ecdrive::sim::canopen::SimBus>| -> Option<State> {
            let b = m.sdo_upload(node, sw_at).ok()?;
            State::from_statusword(u16::from_le_bytes([*b.first()?, *b.get(1)?]))
        };
        let at = read(&mut m);
        if !reached || at != Some(from) {
            // Quick stop active ends by itself once the motor stands still (option codes that
            // end in Switch on disabled): not a state an idle motor stays in.
            gaps.push(format!(
                "{drive}: {from} not reached by controlword (read {at:?}) ({})",
                f.id
            ));
            continue;
        }
        let got = match m.sdo_download(node, cw_at, &cw.to_le_bytes()) {
            Ok(_) => read(&mut m),
            Err(e) => {
                bad.push(format!(
                    "{drive} (emulated) [{}]: controlword 0x{cw:04X} in {from} refused: {e}",
                    f.id
                ));
                continue;
            }
        };
        if to == State::QuickStopActive && got == Some(State::SwitchOnDisabled) {
            // An idle motor has stopped at once: a quick stop that ends in Switch on disabled
            // passes through Quick stop active between two reads.
            gaps.push(format!(
                "{drive}: {from} with 0x{cw:04X} ended in Switch on disabled: Quick stop active \
                 is left at once by an idle motor ({})",
                f.id
            ));
            continue;
        }
        if (got == Some(to)) != exists {
            bad.push(format!(
                "{drive} (emulated) [{}]: {from} with controlword 0x{cw:04X} went to {got:?}, \
                 the manual says {}{to} ({})",
                f.id,
                if exists { "" } else { "not " },
                f.source
            ));
        }
    }
    bad
}

/// The emulated side of the alarm facts: each alarm raised in a freshly powered emulated
/// EtherCAT drive, its 0x603F read over the bus against the manual's error code.
fn check_alarms_emulated(drive: &str, facts: &[Fact], gaps: &mut Vec<String>) -> Vec<String> {
    use ecdrive::sim::faults::{DeviceFault, Fault};
    let mut bad = Vec::new();
    if cantools::EMULATED_NODES.iter().any(|(n, _, _)| *n == drive) {
        gaps.push(format!(
            "{drive}: alarms of the CANopen drives cannot be raised on the virtual bus"
        ));
        return bad;
    }
    for f in facts.iter().filter(|f| f.kind == "alarm") {
        let (Some(id), Some(code)) = (f.alarm.as_deref(), f.error_code.as_deref()) else {
            gaps.push(format!("{drive}: alarm without an error code ({})", f.id));
            continue;
        };
        let Some(want) = number(&toml::Value::String(code.into())) else {
            continue;
        };
        let mut seg = ecdrive_cli::app::harness::emulated::segment(&[drive.to_string()])
            .expect("the emulated segment");
        let id: &'static str = Box::leak(id.to_string().into_boxed_str());
        // Raised in the freshly powered drive; the master then finds it in the process data.
        if !seg.apply(&Fault::Device {
            position: 0,
            fault: DeviceFault::RaiseAlarm(id),
        }) {
            gaps.push(format!(
                "{drive}: the emulated drive has no alarm {id} to raise ({})",
                f.id
            ));
            continue;
        }
        let mut cfg = ecdrive::master::MasterConfig::new(std::time::Duration::from_millis(1));
        cfg.startup.drives.push(ecdrive::master::DriveSetup::new(
            ecdrive::master::Selector::Position(0),
        ));
        let link = ecdrive::sim::transport::SegmentLink::new(seg);
        let mut m = match ecdrive::master::Master::start(link, cfg) {
            Ok(m) => m,
            Err(e) => {
                bad.push(format!(
                    "{drive} (emulated) [{}]: start-up: {}",
                    f.id, e.error
                ));
                continue;
            }
        };
        let guard = std::time::Duration::from_secs(10);
        let op = m.wait_until("OP", guard, |t| t.cycle.all_op);
        // The drive's error code in the process data (0x603F in its default TxPDO).
        let raised = op.and_then(|()| {
            m.wait_until("the alarm", guard, |t| {
                t.axes.first().is_some_and(|a| a.error_code != 0)
            })
        });
        let have = m.telemetry().axes.first().map_or(0, |a| a.error_code);
        let _ = m.stop(ecdrive::master::StopKind::Ramp);
        match raised {
            Ok(()) if i128::from(have) != want => bad.push(format!(
                "{drive} (emulated) [{}]: {id} raised, 0x603F reads 0x{have:04X}, the manual's \
                 error code is 0x{want:04X} ({})",
                f.id, f.source
            )),
            Ok(()) => {}
            Err(e) => gaps.push(format!(
                "{drive}: {id} raised, no error code within the guard: {e} ({})",
                f.id
            )),
        }
    }
    bad
}

/// The SDO abort codes a drive's manual lists (`abort_code` facts).
fn listed_aborts(facts: &[Fact]) -> Vec<u32> {
    facts
        .iter()
        .filter(|f| f.kind == "abort_code")
        .filter_map(|f| f.code.as_deref())
        .filter_map(|c| number(&toml::Value::String(c.into())))
        .map(|c| c as u32)
        .collect()
}

/// The request that provokes an abort, and the codes that name its cause.
struct Provocation {
    what: &'static str,
    codes: &'static [u32],
}

/// The emulated side of the abort-code facts, by provoking them: a missing object, a missing
/// sub-index, a write to a read-only object, a value too long and too short, a value above and
/// below the manual's range. Each answer must be a code the manual lists for that cause (where
/// the manual lists one); each listed code no request provokes is a gap. The ranges: every
/// writable object with a range takes its minimum and maximum.
fn check_aborts(
    drive: &str,
    port: &mut dyn SdoPort,
    facts: &[Fact],
    gaps: &mut Vec<String>,
) -> Vec<String> {
    let mut bad = Vec::new();
    let listed = listed_aborts(facts);
    let mut provoked: Vec<u32> = Vec::new();
    let mut judge = |p: &Provocation,
                     on: ObjectAddress,
                     r: Sdo,
                     bad: &mut Vec<String>,
                     gaps: &mut Vec<String>| {
        let id = format!("abort.provoked.{}", p.what.replace(' ', "_"));
        match r {
            Sdo::Abort(c) => {
                provoked.push(c);
                let named: Vec<u32> = p
                    .codes
                    .iter()
                    .copied()
                    .filter(|c| listed.contains(c))
                    .collect();
                if named.is_empty() {
                    gaps.push(format!(
                        "{drive}: the manual lists no abort code for {} (answered 0x{c:08X})",
                        p.what
                    ));
                } else if !named.contains(&c) {
                    bad.push(format!(
                        "{drive} (emulated) [{id}]: {} ({on}) aborted 0x{c:08X}; the manual \
                         lists {named:08X?} for it",
                        p.what
                    ));
                }
            }
            Sdo::Bytes(_) => bad.push(format!(
                "{drive} (emulated) [{id}]: {} ({on}) was accepted",
                p.what
            )),
            Sdo::Failed(e) => {
                bad.push(format!("{drive} (emulated) [{id}]: {} ({on}): {e}", p.what))
            }
        }
    };
    let a = ObjectAddress::new;
    judge(
        &Provocation {
            what: "an object that does not exist",
            codes: &[0x0602_0000],
        },
        a(0x5FFF, 0),
        port.upload(a(0x5FFF, 0)),
        &mut bad,
        gaps,
    );
    judge(
        &Provocation {
            what: "a sub-index that does not exist",
            codes: &[0x0609_0011],
        },
        a(0x1018, 0x7F),
        port.upload(a(0x1018, 0x7F)),
        &mut bad,
        gaps,
    );
    judge(
        &Provocation {
            what: "a write to a read-only object",
            codes: &[0x0601_0002],
        },
        a(0x1018, 1),
        port.download(a(0x1018, 1), &[0, 0, 0, 0]),
        &mut bad,
        gaps,
    );
    judge(
        &Provocation {
            what: "a value too long",
            codes: &[0x0607_0012, 0x0607_0010],
        },
        a(0x6040, 0),
        port.download(a(0x6040, 0), &[0, 0, 0, 0]),
        &mut bad,
        gaps,
    );
    judge(
        &Provocation {
            what: "a value too short",
            codes: &[0x0607_0013, 0x0607_0010],
        },
        a(0x6040, 0),
        port.download(a(0x6040, 0), &[0]),
        &mut bad,
        gaps,
    );
    // The ranges of writable objects: the ends are taken, a value past one is refused with a
    // range code the manual lists. A write refused for another reason the manual lists (the
    // object is mapped in the RxPDO, or under the drive's local control) says nothing about
    // the range: a gap.
    const OTHER_REASONS: [u32; 3] = [0x0601_0006, 0x0800_0021, 0x0800_0022];
    let range_codes: Vec<u32> = [0x0609_0030, 0x0609_0031, 0x0609_0032]
        .into_iter()
        .filter(|c| listed.contains(c))
        .collect();
    let mut beyond: Vec<String> = Vec::new();
    let mut tried = 0;
    for f in facts.iter().filter(|f| f.kind == "object") {
        let (Some(obj), Some(dt)) = (
            f.object.as_deref().and_then(address),
            f.data_type.as_deref().and_then(data_type),
        ) else {
            continue;
        };
        // PDO mapping, assignment and communication objects take only valid entries (their
        // rules: `remap_errors_abort_with_codes_the_manual_lists`); the error history 0x1003
        // takes only 0 (CiA 301 §7.5.2.4).
        if f.access.as_deref() != Some("rw")
            || dt.is_string()
            || obj.index == 0x1003
            || (0x1400..0x1C00).contains(&obj.index)
            || (0x1C10..0x1C20).contains(&obj.index)
        {
            continue;
        }
        let Some(bits) = dt.bit_len().filter(|b| *b <= 32) else {
            continue;
        };
        let (Some(min), Some(max)) = (
            f.min.as_ref().and_then(number),
            f.max.as_ref().and_then(number),
        ) else {
            continue;
        };
        let (tmin, tmax) = if signed(dt) {
            (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
        } else {
            (0, (1i128 << bits) - 1)
        };
        let bytes = |v: i128| (v as u64).to_le_bytes()[..usize::from(bits / 8)].to_vec();
        let other = |c: u32| OTHER_REASONS.contains(&c) && listed.contains(&c);
        for (end, v) in [("minimum", min), ("maximum", max)] {
            if !(tmin..=tmax).contains(&v) {
                continue;
            }
            match port.download(obj, &bytes(v)) {
                Sdo::Bytes(_) => {}
                Sdo::Abort(c) if other(c) => gaps.push(format!(
                    "{drive}: {obj} not written by SDO: refused with the listed 0x{c:08X} \
                     ({})",
                    f.id
                )),
                Sdo::Abort(c) => bad.push(format!(
                    "{drive} (emulated) [{}]: {obj} refused its {end} {v} with 0x{c:08X} ({})",
                    f.id, f.source
                )),
                Sdo::Failed(e) => {
                    bad.push(format!("{drive} (emulated) [{}]: {obj} = {v}: {e}", f.id))
                }
            }
        }
        for (past, v, applies) in [
            ("above", max + 1, max < tmax),
            ("below", min - 1, min > tmin),
        ] {
            if !applies {
                continue;
            }
            tried += 1;
            match port.download(obj, &bytes(v)) {
                Sdo::Abort(c) if range_codes.contains(&c) => provoked.push(c),
                Sdo::Abort(c) if other(c) => tried -= 1,
                Sdo::Abort(c) => beyond.push(format!("{obj} {past} (aborted 0x{c:08X})")),
                Sdo::Bytes(_) => beyond.push(format!("{obj} {past} (accepted)")),
                Sdo::Failed(e) => beyond.push(format!("{obj} {past} ({e})")),
            }
        }
    }
    if range_codes.is_empty() {
        gaps.push(format!(
            "{drive}: the manual lists no abort code for a value out of range"
        ));
    } else if !beyond.is_empty() && cantools::EMULATED_NODES.iter().any(|(n, _, _)| *n == drive) {
        // One finding for the emulated CANopen nodes, whose dictionary is the master's
        // profile's (no ranges of their own).
        bad.push(format!(
            "{drive} (emulated) [abort.provoked.range.canopen_node]: {} of {tried} values past \
             the manual's range not refused with a listed range code ({range_codes:08X?}): {}",
            beyond.len(),
            beyond.join(", ")
        ));
    } else {
        for b in &beyond {
            let obj = b.split(' ').next().unwrap_or("");
            bad.push(format!(
                "{drive} (emulated) [abort.provoked.range.{obj}]: a value {} is not refused \
                 with a listed range code ({range_codes:08X?})",
                b.trim_start_matches(obj).trim()
            ));
        }
    }
    for c in &listed {
        if !provoked.contains(c) {
            gaps.push(format!(
                "{drive}: listed abort code 0x{c:08X} is not provoked by these requests"
            ));
        }
    }
    bad
}

// ---------------------------------------------------------------------------------------------
// Units

/// What a unit fact says, restated for the machine (each entry is the fact's `value` as the
/// manual words it; the fact id names it).
#[derive(Debug, Clone, Copy, PartialEq)]
enum UnitClaim {
    /// 0x60FF/0x606C in r/min × this.
    VelocityRpm(f64),
    /// 0x60FF/0x606C in position units per second.
    VelocityPositionPerS,
    /// 0x6081 in position units per second.
    ProfileVelocityPositionPerS,
    /// Position units per motor revolution (with the default scaling).
    PositionPerRev(f64),
    /// 0x6071/0x6077: this many ‰ of the rated torque per unit.
    TorquePerMille(f64),
    /// 0x6087 in ‰ (of the rated torque) per second.
    TorqueSlopePerMillePerS,
    /// 0x6087 as a time to the rated torque.
    TorqueSlopeMsToRated,
    /// 0x6087 in mN·m per second (an absolute torque rate).
    TorqueSlopeMnmPerS,
    /// 0x6083/0x6084 as a time from 0 to a speed.
    AccelMsTo,
    /// 0x6083/0x6084 in (r/min)/s.
    AccelRpmPerS,
    /// 0x6083/0x6084 in position units per second².
    AccelPositionPerS2,
}

/// The unit facts restated ([`UnitClaim`]), by drive and fact id; a unit fact not here is a
/// gap (a unit of an object the master does not convert, or one it cannot be compared with).
fn unit_claim(drive: &str, id: &str) -> Option<UnitClaim> {
    use UnitClaim::*;
    Some(match (drive, id) {
        ("mr-j4-tm", "unit.encoder_resolution") => PositionPerRev(4_194_304.0),
        ("mr-j4-tm", "unit.velocity") => VelocityRpm(0.01),
        ("mr-j4-tm", "unit.torque") => TorquePerMille(1.0),
        ("mr-j4-tm", "unit.torque_slope") => TorqueSlopePerMillePerS,
        ("mr-j4-tm", "unit.acceleration") => AccelMsTo,
        ("bdhde", "unit.velocity") => VelocityPositionPerS,
        ("bdhde", "unit.acceleration") => AccelPositionPerS2,
        ("bdhde", "unit.torque") | ("bdhde", "unit.target_torque") => TorquePerMille(1.0),
        ("bdhde", "unit.torque_slope") => TorqueSlopeMnmPerS,
        ("blv-r", "unit.velocity") => VelocityRpm(1.0),
        ("blv-r", "unit.acceleration") => AccelRpmPerS,
        ("blv-r", "unit.torque") => TorquePerMille(1.0),
        ("blv-r", "unit.torque_slope") => TorqueSlopePerMillePerS,
        ("blv-r", "unit.encoder_resolution") => PositionPerRev(36_000.0),
        // With 6093h at its default 1:1, as the fact's note says.
        ("asda-a2", "unit.puu_per_rev") => PositionPerRev(1_280_000.0),
        ("asda-a2", "unit.velocity") => VelocityRpm(0.1),
        ("asda-a2", "unit.profile_velocity") => ProfileVelocityPositionPerS,
        ("asda-a2", "unit.acceleration") => AccelMsTo,
        ("asda-a2", "unit.torque") => TorquePerMille(1.0),
        ("asda-a2", "unit.torque_slope") => TorqueSlopeMsToRated,
        ("lexium-mdrive", "unit.position_per_rev") => PositionPerRev(51_200.0),
        ("lexium-mdrive", "unit.velocity_actual") => VelocityPositionPerS,
        ("lexium-mdrive", "unit.acceleration") => AccelPositionPerS2,
        ("lexium-mdrive", "unit.torque") => TorquePerMille(1.0),
        ("lexium-mdrive", "unit.torque_slope") => TorqueSlopePerMillePerS,
        _ => return None,
    })
}

/// The profile side of the unit facts: the profile's units ([`ecdrive::cia402::Units`]), with
/// which the configuration's user units and every program value are converted.
fn check_units_profile(drive: &str, facts: &[Fact], gaps: &mut Vec<String>) -> Vec<String> {
    use UnitClaim::*;
    use ecdrive::cia402::{AccelUnit, TorqueSlopeUnit, VelocityUnit};
    let units = match drives::by_key(drive) {
        Some(p) => p.units,
        None => match cantools::EMULATED_NODES
            .iter()
            .find(|(n, _, _)| *n == drive)
        {
            Some((_, p, _)) => p.units,
            None => return Vec::new(),
        },
    };
    let mut bad = Vec::new();
    for f in facts.iter().filter(|f| f.kind == "unit") {
        let Some(claim) = unit_claim(drive, &f.id) else {
            gaps.push(format!(
                "{drive}: unit fact not restated for a comparison ({})",
                f.id
            ));
            continue;
        };
        let prof = units.profile;
        let ok = match claim {
            VelocityRpm(k) => units.velocity == VelocityUnit::RevPerMinute { scale: k },
            VelocityPositionPerS => units.velocity == VelocityUnit::PositionPerSecond,
            ProfileVelocityPositionPerS => {
                prof.is_some_and(|p| p.profile_velocity == VelocityUnit::PositionPerSecond)
            }
            PositionPerRev(n) => units.position_per_rev == n,
            TorquePerMille(k) => units.torque_per_mille == k,
            TorqueSlopePerMillePerS => {
                prof.is_some_and(|p| p.torque_slope == TorqueSlopeUnit::PerMillePerSecond)
            }
            TorqueSlopeMsToRated => {
                prof.is_some_and(|p| p.torque_slope == TorqueSlopeUnit::MillisecondsToRated)
            }
            // No profile unit is an absolute torque rate.
            TorqueSlopeMnmPerS => false,
            AccelMsTo => {
                prof.is_some_and(|p| matches!(p.acceleration, AccelUnit::MillisecondsTo { .. }))
            }
            AccelRpmPerS => prof.is_some_and(|p| p.acceleration == AccelUnit::RpmPerSecond),
            AccelPositionPerS2 => {
                prof.is_some_and(|p| p.acceleration == AccelUnit::PositionPerSecond2)
            }
        };
        if !ok {
            bad.push(format!(
                "{drive} (profile) [{}]: the manual's {} is {:?}; the profile's units are \
                 {units:?} ({})",
                f.id,
                f.quantity.as_deref().unwrap_or("unit"),
                f.value,
                f.source
            ));
        }
    }
    bad
}

/// The emulated side of the position and velocity unit facts, through the configuration's
/// conversions and the bus: an EtherCAT drive runs 1 rev/s in csv, in user units of one
/// revolution made from the manual's position units per revolution; while it holds that
/// velocity its actual position advances one revolution in the manual's units per second of
/// the bus's clock (DC time, read with the position in the same telemetry snapshot, 300
/// cycles apart) — which holds only if the master's velocity unit and the emulated drive's are
/// both the manual's. No wall-clock time enters: a loaded machine's late cycles move the drive
/// for longer and the DC time with it.
fn check_units_emulated(drive: &str, facts: &[Fact], gaps: &mut Vec<String>) -> Vec<String> {
    let mut bad = Vec::new();
    // The manual's position units per revolution; the BDHDE's are the start-up scaling (2^20
    // per revolution) of its factor group (unit.position), the profile's, which the facts do
    // not fix.
    let per_rev = facts.iter().find_map(|f| match unit_claim(drive, &f.id) {
        Some(UnitClaim::PositionPerRev(n)) => Some((n, f.id.clone())),
        _ => None,
    });
    let Some((per_rev, id)) =
        per_rev.or_else(|| (drive == "bdhde").then(|| (1_048_576.0, "unit.velocity".to_string())))
    else {
        gaps.push(format!(
            "{drive}: no position units per revolution in the facts"
        ));
        return bad;
    };
    if drives::by_key(drive).is_none() {
        return check_units_canopen(drive, per_rev, &id);
    }
    let text = format!(
        "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"{drive}\"]\n\
         loss_detection = false\n[[drive]]\nposition = 0\nmode = \"csv\"\n\
         units = {{ name = \"rev\", counts_per_unit = {per_rev} }}\n\
         program = [{{ step = \"ramp\", velocity = 1, acceleration = 100, hold = 30 }}, \
         {{ step = \"ramp\", velocity = 0, acceleration = 100 }}]\n"
    );
    let cfg =
        ecdrive_cli::app::config::parse(&text, "units.toml").unwrap_or_else(|e| panic!("{e}"));
    let link = cfg
        .target
        .open_with(&cfg.sim)
        .unwrap_or_else(|e| panic!("{e}"));
    let moved = (|| -> Result<f64, String> {
        use ecdrive::master::{Axes, Command, StopKind};
        let mut m = ecdrive::master::Master::start(link, cfg.master.clone())
            .map_err(|f| f.error.to_string())?;
        let guard = std::time::Duration::from_secs(20);
        let e = |e: ecdrive::master::MasterError| e.to_string();
        m.wait_until("OP", guard, |t| t.cycle.all_op).map_err(e)?;
        m.command(Command::Enable(Axes::All)).map_err(e)?;
        m.wait_until("enabled", guard, |t| {
            t.axes
                .iter()
                .all(|a| a.state == Some(State::OperationEnabled))
        })
        .map_err(e)?;
        m.command(Command::RunProgram(Axes::All)).map_err(e)?;
        // Past the ramp up (10 ms at 100 rev/s²) and the drive's answer to it.
        let start = m.telemetry().cycle.cycle;
        m.wait_until("the ramp up", guard, |t| t.cycle.cycle >= start + 100)
            .map_err(e)?;
        let a = m.telemetry().clone();
        let from = a.cycle.cycle;
        m.wait_until("300 cycles at 1 rev/s", guard, |t| {
            t.cycle.cycle >= from + 300
        })
        .map_err(e)?;
        let b = m.telemetry().clone();
        let _ = m.stop(StopKind::Ramp);
        let holding = |t: &ecdrive::master::Telemetry| {
            t.axes[0].program_running && t.axes[0].program_step == 0
        };
        if !(holding(&a) && holding(&b)) {
            return Err("the program did not hold 1 rev/s over the measurement".into());
        }
        let revs = (b.axes[0].position_actual - a.axes[0].position_actual) as f64 / per_rev;
        let seconds = b.cycle.dc_time.saturating_sub(a.cycle.dc_time) as f64 * 1e-9;
        Ok(revs / seconds)
    })();
    // 1 rev/s; the position and the DC time of a snapshot may be one cycle apart (1 ms of
    // 300): 1 %.
    let want = 1.0;
    match moved {
        Ok(moved) if (moved - want).abs() > 0.01 => bad.push(format!(
            "{drive} (emulated) [{id}]: at 1 rev/s the position advanced {moved:.4} rev per \
             second of DC time (the manual's {per_rev} units per revolution), not {want}"
        )),
        Ok(_) => {}
        Err(e) => bad.push(format!("{drive} (emulated) [{id}]: the run: {e}")),
    }
    bad
}

/// [`check_units_emulated`] for a CANopen drive: the same run from a configuration file, on
/// the emulated node (`interface = "can-sim"`, simulated time), in pv: 1 rev/s held; the
/// actual position (6064h through its TPDO) advances one revolution in the manual's units per
/// second of the bus's clock, measured 300 SYNC cycles apart. As for the EtherCAT drives this
/// holds only if the master's conversion and the emulated drive's agree (the profile side,
/// [`check_units_profile`], holds the profile to the manual); the emulated CANopen nodes still
/// take their units from the master's profile (the EDS issue gives them their own tables), so
/// until then this side cannot disagree with the profile.
fn check_units_canopen(drive: &str, per_rev: f64, id: &str) -> Vec<String> {
    use ecdrive::master::{Axes, Command};
    let mut bad = Vec::new();
    let Some((_, _, node)) = cantools::EMULATED_NODES
        .iter()
        .find(|(n, _, _)| *n == drive)
    else {
        return bad;
    };
    let text = format!(
        "interface = \"can-sim\"\ncycle = \"4ms\"\n[[drive]]\nnode = {node}\nprofile = \"{drive}\"\n\
         mode = \"pv\"\nunits = {{ name = \"rev\", counts_per_unit = {per_rev} }}\n\
         program = [{{ step = \"pv\", velocity = 1, acceleration = 100, seconds = 30 }}]\n"
    );
    let cfg = match ecdrive_cli::app::config::parse_any(&text, "units.toml") {
        Ok(ecdrive_cli::app::config::Config::CanOpen(c)) => c,
        Ok(_) => panic!("not a CANopen run"),
        Err(e) => panic!("{e}"),
    };
    let rate = (|| -> Result<f64, String> {
        use ecdrive_cli::app::canopen::run;
        let e = |e: ecdrive::canopen::CanError| e.to_string();
        let bus = run::emulated_bus(&cfg).map_err(e)?;
        let (mut s, _) = run::session(bus, &cfg).map_err(e)?;
        s.command(Command::Enable(Axes::All));
        s.command(Command::RunProgram(Axes::All));
        // Past the ramp (10 ms at 100 rev/s²) and the drive's answer.
        for _ in 0..100 {
            s.cycle().map_err(e)?;
        }
        let at = |s: &ecdrive::canopen::MotionSession<_>| {
            (
                s.telemetry(0).map_or(0, |t| t.position_actual),
                s.master().now_us(),
                s.telemetry(0).is_some_and(|t| t.program_running),
            )
        };
        let a = at(&s);
        for _ in 0..300 {
            s.cycle().map_err(e)?;
        }
        let b = at(&s);
        if !(a.2 && b.2) {
            return Err(format!(
                "the program did not hold 1 rev/s: {:?}",
                s.take_events()
            ));
        }
        Ok((b.0 - a.0) as f64 / per_rev / ((b.1 - a.1) as f64 * 1e-6))
    })();
    match rate {
        Ok(r) if (r - 1.0).abs() > 0.01 => bad.push(format!(
            "{drive} (emulated) [{id}]: at 1 rev/s the position advanced {r:.4} rev per second \
             of the bus's time (the manual's {per_rev} units per revolution), not 1"
        )),
        Ok(_) => {}
        Err(e) => bad.push(format!("{drive} (emulated) [{id}]: the run: {e}")),
    }
    bad
}

fn emulated_port(drive: &str) -> Box<dyn SdoPort> {
    match cantools::EMULATED_NODES
        .iter()
        .find(|(n, _, _)| *n == drive)
    {
        Some((_, _, node)) => Box::new(CanPort {
            node: *node,
            bus: cantools::demo_bus,
        }),
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
    #[serde(default)]
    gap: Vec<GapItem>,
}

/// A class of gaps — facts a side cannot be checked against — with the reason it stands: every
/// gap text on `side` for `drive` (`*`: every drive) containing `pattern`. A gap no entry
/// covers fails, and so does an entry that covers none.
#[derive(Debug, Deserialize)]
struct GapItem {
    side: String,
    drive: String,
    pattern: String,
    why: String,
}

#[derive(Debug, Deserialize)]
struct OpenItem {
    /// `profile` or `emulation`.
    side: String,
    drive: String,
    id: String,
    why: String,
}

fn open_file() -> Open {
    let p = facts_dir().join("open.toml");
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn open_items(side: &str) -> Vec<OpenItem> {
    open_file()
        .open
        .into_iter()
        .filter(|i| i.side == side)
        .collect()
}

/// Fail on gaps (drive, text) no `[[gap]]` entry of `side` covers, and on entries that cover
/// none.
fn judge_gaps(side: &str, gaps: &[(String, String)]) {
    let classes: Vec<GapItem> = open_file()
        .gap
        .into_iter()
        .filter(|g| g.side == side)
        .collect();
    let covers = |g: &GapItem, drive: &str, text: &str| {
        (g.drive == "*" || g.drive == drive) && text.contains(g.pattern.as_str())
    };
    let uncovered: Vec<&str> = gaps
        .iter()
        .filter(|(d, t)| !classes.iter().any(|g| covers(g, d, t)))
        .map(|(_, t)| t.as_str())
        .collect();
    let unused: Vec<String> = classes
        .iter()
        .filter(|g| !gaps.iter().any(|(d, t)| covers(g, d, t)))
        .map(|g| format!("{} {:?} ({})", g.drive, g.pattern, g.why))
        .collect();
    assert!(
        uncovered.is_empty() && unused.is_empty(),
        "{} gaps on the {side} side that tests/manual_facts/open.toml does not explain:\n{}\n\n\
         {} [[gap]] entries that explain nothing (remove them):\n{}",
        uncovered.len(),
        uncovered.join("\n"),
        unused.len(),
        unused.join("\n")
    );
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
        let mut g = Vec::new();
        for b in check_profile(&profile_view(d), &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        for b in check_transitions_profile(d, &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        for b in check_units_profile(d, &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        gaps.extend(g.into_iter().map(|t| (d.to_string(), t)));
    }
    judge("profile", &found);
    judge_gaps("profile", &gaps);
}

#[test]
fn the_emulated_drives_agree_with_the_manuals_over_the_bus() {
    let mut found = Vec::new();
    let mut gaps = Vec::new();
    for d in DRIVES {
        let file = load(d);
        let mut port = emulated_port(d);
        let mut g = Vec::new();
        for b in check_emulation(d, port.as_mut(), &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        for b in check_aborts(d, port.as_mut(), &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        for b in check_transitions_emulated(d, &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        for b in check_alarms_emulated(d, &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        for b in check_units_emulated(d, &file.fact, &mut g) {
            found.push((d.to_string(), fact_id(&b), b));
        }
        gaps.extend(g.into_iter().map(|t| (d.to_string(), t)));
    }
    judge("emulation", &found);
    judge_gaps("emulation", &gaps);
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

/// The oracle has teeth on the emulated side too: an emulated drive whose stored parameters
/// differ from the manual (a following-error window 0x6065 of 123 in non-volatile memory, as
/// `ecdrive sim -d mr-j4-tm@0x6065=123` serves it) is caught over the bus, for each EtherCAT
/// drive, and so is a drive that answers a listed abort with another code (the BDHDE before
/// it answered lengths with 0x06070010: here a provocation whose listed code is not the one
/// answered).
#[test]
fn a_wrong_value_in_an_emulated_drive_fails_the_oracle() {
    for d in ["mr-j4-tm", "bdhde"] {
        let file = load(d);
        let mut gaps = Vec::new();
        let mut good = EcPort(Target::Sim(vec![d.to_string()]));
        let before = check_emulation(d, &mut good, &file.fact, &mut gaps);
        assert!(
            !before.iter().any(|b| b.contains("0x6065:00")),
            "{d}: {before:#?}"
        );
        let mut changed = EcPort(Target::Sim(vec![format!("{d}@0x6065=123")]));
        let caught = check_emulation(d, &mut changed, &file.fact, &mut gaps);
        assert!(
            caught
                .iter()
                .any(|c| c.contains("0x6065:00 reads 123") && c.contains("(emulated)")),
            "{d}: a changed 0x6065 in the emulated drive was not caught: {caught:#?}"
        );
    }
    // The same on the CANopen side: the emulator's own BLV-R table with one wrong default.
    let file = load("blv-r");
    let mut gaps = Vec::new();
    let mut good = CanPort {
        node: 1,
        bus: cantools::demo_bus,
    };
    let before = check_emulation("blv-r", &mut good, &file.fact, &mut gaps);
    assert!(
        !before.iter().any(|b| b.contains("0x6065:00")),
        "blv-r: {before:#?}"
    );
    let mut changed = CanPort {
        node: 1,
        bus: blv_r_with_a_wrong_value,
    };
    let caught = check_emulation("blv-r", &mut changed, &file.fact, &mut gaps);
    assert!(
        caught
            .iter()
            .any(|c| c.contains("0x6065:00 reads 123") && c.contains("(emulated)")),
        "blv-r: a changed 0x6065 in the emulated CANopen node was not caught: {caught:#?}"
    );
    // An abort answered with a code the manual does not list for its cause.
    struct Lengthy(EcPort);
    impl SdoPort for Lengthy {
        fn upload(&mut self, a: ObjectAddress) -> Sdo {
            self.0.upload(a)
        }
        fn download(&mut self, a: ObjectAddress, bytes: &[u8]) -> Sdo {
            match self.0.download(a, bytes) {
                Sdo::Abort(0x0607_0010) => Sdo::Abort(0x0607_0012),
                other => other,
            }
        }
    }
    let file = load("bdhde");
    let mut gaps = Vec::new();
    let mut port = Lengthy(EcPort(Target::Sim(vec!["bdhde".into()])));
    let caught = check_aborts("bdhde", &mut port, &file.fact, &mut gaps);
    assert!(
        caught
            .iter()
            .any(|c| c.contains("[abort.provoked.a_value_too_long]")),
        "an abort code the manual does not list was not caught: {caught:#?}"
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
        let listed = listed_aborts(&file.fact);
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

/// The emulated side of the PDO limits (`pdo_limits` facts), through the bus as a remap writes
/// them in PRE-OP: the first RxPDO and TxPDO take the manual's most entries (from the objects
/// it marks mappable, smallest first, within its byte limit), and one entry more is refused
/// with an abort code the manual lists.
#[test]
fn the_emulated_drives_keep_the_manuals_pdo_limits() {
    for d in ["mr-j4-tm", "bdhde"] {
        let file = load(d);
        let listed = listed_aborts(&file.fact);
        let limit = |k: &str| {
            file.fact
                .iter()
                .filter(|f| f.kind == "pdo_limits")
                .find_map(|f| match k {
                    "rx" => f.max_rx_entries,
                    "tx" => f.max_tx_entries,
                    "rx_bytes" => f.max_rx_bytes,
                    _ => f.max_tx_bytes,
                })
        };
        for (dir, pdo, sm, access) in [
            ("rx", 0x1600u16, 0x1C12u16, "rw"),
            ("tx", 0x1A00, 0x1C13, "ro"),
        ] {
            let max = limit(dir).unwrap_or_else(|| panic!("{d}: no {dir} entry limit")) as usize;
            let bytes = limit(&format!("{dir}_bytes")).map(|b| b as usize);
            // The manual's mappable objects of this direction, smallest first.
            let mut objs: Vec<(u16, u8, u8)> = file
                .fact
                .iter()
                .filter(|f| f.kind == "object" && f.pdo_mappable == Some(true))
                .filter(|f| f.access.as_deref() == Some(access))
                .filter_map(|f| {
                    let a = address(f.object.as_deref()?)?;
                    let bits = data_type(f.data_type.as_deref()?)?.bit_len()?;
                    (bits <= 32).then_some((a.index, a.sub, bits as u8))
                })
                .collect();
            objs.sort_by_key(|o| o.2);
            // `max` entries, cycling through those of at most 16 bits (within the byte limit:
            // the MR-J4-TM's 32 entries in 64 bytes).
            objs.retain(|o| o.2 <= 16);
            let entries: Vec<(u16, u8, u8)> = (0..max).map(|i| objs[i % objs.len()]).collect();
            let total: usize = entries.iter().map(|e| usize::from(e.2)).sum::<usize>() / 8;
            assert!(bytes.is_none_or(|b| total <= b), "{d}: {total} bytes");
            let target = Target::Sim(vec![d.to_string()]);
            let (full, over) = tools::session(&target, move |bus| {
                let mut w = |a: ObjectAddress, raw: Vec<u8>| -> Result<(), String> {
                    let hex: String = raw.iter().map(|b| format!("{b:02x}")).collect();
                    tools::download(bus, 0, a, &hex, Some(DataType::OctetString))
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                };
                w(ObjectAddress::new(sm, 0), vec![0]).map_err(|e| {
                    ecdrive::master::MasterError::new(
                        None,
                        "unassign",
                        ecdrive::master::ErrorKind::Config,
                        e,
                    )
                })?;
                let _ = w(ObjectAddress::new(pdo, 0), vec![0]);
                let mut full = Ok(());
                for (k, (i, s, b)) in entries.iter().enumerate() {
                    let v = (u32::from(*i) << 16) | (u32::from(*s) << 8) | u32::from(*b);
                    if let Err(e) = w(
                        ObjectAddress::new(pdo, k as u8 + 1),
                        v.to_le_bytes().to_vec(),
                    ) {
                        full = Err(format!("entry {}: {e}", k + 1));
                        break;
                    }
                }
                if full.is_ok() {
                    full = w(ObjectAddress::new(pdo, 0), vec![max as u8]);
                }
                let _ = w(ObjectAddress::new(pdo, 0), vec![0]);
                let over = w(ObjectAddress::new(pdo, 0), vec![max as u8 + 1]);
                Ok((full, over))
            })
            .unwrap_or_else(|e| panic!("{d}: {e}"));
            assert!(
                full.is_ok(),
                "{d}: {max} entries in 0x{pdo:04X} (the manual's limit) refused: {full:?}"
            );
            match over {
                Ok(()) => panic!("{d}: {} entries in 0x{pdo:04X} accepted", max + 1),
                Err(e) => {
                    let code = abort_in(&e).unwrap_or_else(|| panic!("{d}: {e}"));
                    assert!(
                        listed.contains(&code),
                        "{d}: {} entries in 0x{pdo:04X} aborted 0x{code:08X}, which the manual \
                         does not list ({e})",
                        max + 1
                    );
                }
            }
        }
    }
}
