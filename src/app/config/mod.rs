//! The `ecdrive run` configuration file: TOML → [`MasterConfig`] and a [`Target`].
//!
//! ```toml
//! interface = "sim"          # a network interface (raw socket), or "sim": emulated devices in-process
//! cycle = "1ms"              # cycle time (ns, us, ms, s); default 1 ms
//! dc_shift = "500us"         # offset of the master's frame from SYNC0 (default half the cycle)
//! dc_start_delay = "20ms"    # reference clock read to first SYNC0 (default 0.5 ms + 0.15 ms a DC drive)
//! duration = "10s"           # stop after this long (default: when every program has finished)
//! reset_faults = false       # clear faults latched before the run (default: refuse, saying how)
//! answer_rereads = true      # answer ethercrab's start-up re-reads from what ecdrive read (default)
//!
//! [rt]                       # real-time set-up of the cycle thread (optional)
//! priority = 80              # SCHED_FIFO priority 1–99
//! cpu = 1                    # pin to this CPU
//! lock_memory = true         # mlockall
//! reply = "next-wake"        # read the frame's reply at the next wake-up, or "in-cycle" (wait for it)
//! frames = "ecdrive"         # the cycle's frames: ecdrive's own (learnt from ethercrab's first), or "ethercrab"
//!
//! [supervision]              # how the cycle reacts to the bus (optional)
//! lost_before_stop = 3       # consecutive cycles without a reply before the axes are stopped
//! lost_cycles = 3            # consecutive cycles without a reply before the segment counts as lost
//! wkc_errors = 3             # consecutive wrong working counters before the axes are stopped
//! safeop_cycles = 10         # SYNC0 cycles of valid outputs in SAFE-OP before OP is requested
//! op_timeout = "5s"          # how long the drives may take to reach OP
//!
//! [sim]                      # only with interface = "sim"
//! devices = ["mr-j4-tm", "bdhde"]
//! loss_detection = true      # the emulated drives supervise the cyclic data (default)
//!
//! [[drive]]
//! position = 0               # or alias = 0x10, or identity = { vendor_id = 0xA1E, product_code = 0x201 }
//! mode = "csp"               # csp, csv or cst at start
//! units = { name = "deg", counts_per_unit = 11650.8444 }
//! limits = { following_error = 5, max_velocity = 720, max_acceleration = 7200 }
//! sdos = { "0x6065:00" = 100000 }
//! program = [
//!   { step = "move", by = 90, velocity = 360, acceleration = 3600 },
//!   { step = "sine", amplitude = 10, frequency = 2, periods = 3 },
//! ]
//! ```
//!
//! Every table denies unknown keys. A bad file gives one [`ConfigError`] naming the file, the
//! line and column, the key and what is wrong:
//! `examples/bad.toml line 7, column 1: drive[0].velocty: unknown key `velocty` …`.
//!
//! Per drive, [`parse`] checks what it can before anything touches the bus, with the file
//! position: the mode against the drive's supported modes, a PDO mapping override against
//! the drive's PDO limits and dictionary, start-up SDO values against their data types, the
//! cycle time against the drive's allowed cycles, and every program step against the mode it
//! runs in, its own parameters and the drive's `limits`. The drive's profile is known when the
//! entry names it (`profile = "mr-j4-tm"`), selects by identity, or selects a position of the
//! emulated devices; otherwise the master checks the same at start-up, naming the drive.
//!
//! A file whose interface is a CANopen bus (`can-sim`, `vbus:PATH`) or whose drives are
//! selected by `node` is a CANopen run: [`canopen`] reads it with the same program, units,
//! limits and start-up values ([`parse_any`], [`load_any`]).
//!
//! Where to read on: this module has the file's shared parts (the errors and their positions,
//! start-up values); `ethercat` reads an EtherCAT run file (the segment, the cycle, each
//! drive entry), [`canopen`] a CANopen one, and `steps` a drive entry's program for both.
//!
//! Program values are in the drive's user units when `units` is given (positions and distances
//! in `name`, velocities in `name`/s, accelerations in `name`/s², jerks in `name`/s³), otherwise
//! in position counts; torques are always in the drive's torque unit.

pub mod canopen;
mod ethercat;
pub mod profile_file;
mod raw;
pub mod schema;
mod steps;

use crate::app::ethercat::tools::{SimSettings, Target};
use crate::drives::DriveProfile;
use crate::master::session::MasterConfig;
use crate::master::startup::Selector;
use crate::od::{Dictionary, ObjectAddress, Value};
use std::ops::Range;
use std::path::Path;
use std::time::Duration;
use toml::Spanned;

/// A bad configuration file: where, which key, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError {
    /// The file (or the name given to [`parse`]).
    pub file: String,
    /// Line, 1-based (0: no position, e.g. the file cannot be read).
    pub line: usize,
    /// Column, 1-based, in characters.
    pub column: usize,
    /// The key path (`drive[0].mapping`), if the error concerns one.
    pub key: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.file)?;
        if self.line > 0 {
            write!(f, " line {}, column {}", self.line, self.column)?;
        }
        f.write_str(": ")?;
        if let Some(k) = &self.key {
            write!(f, "{k}: ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for ConfigError {}

pub use crate::master::startup::UserUnits;

/// One `[[drive]]` entry after checking.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveConfig {
    /// Which device.
    pub select: Selector,
    /// The profile, when the file names it or it follows from the selector.
    pub profile: Option<&'static DriveProfile>,
    /// User units, if given.
    pub units: Option<UserUnits>,
    /// The program steps, described in the file's units.
    pub steps: Vec<String>,
}

/// What `--check` says of a file whose run can only end on a signal: no program, no duration.
pub const ENDS_ONLY_ON_A_SIGNAL: &str = "no [[drive]] has a program and no duration is given: \
     the run holds the segment in OP until a signal (Ctrl-C, SIGTERM) ends it";

/// A checked configuration file.
#[derive(Clone)]
pub struct RunConfig {
    /// Where it came from (for messages).
    pub source: String,
    /// Where the segment is.
    pub target: Target,
    /// How the emulated devices are built (`[sim]`).
    pub sim: SimSettings,
    /// The master configuration.
    pub master: MasterConfig,
    /// How long to run, if limited.
    pub duration: Option<Duration>,
    /// The drive entries, in file order (index = the `setup` index in
    /// `master.startup.drives`).
    pub drives: Vec<DriveConfig>,
    /// Clear faults latched before the run (a reset edge to each drive in Fault after OP)
    /// instead of refusing to run.
    pub reset_faults: bool,
    /// What the check found questionable but not wrong (a program beyond what the drive
    /// documents), one line each, naming the key.
    pub warnings: Vec<String>,
    /// What the check could not judge without the bus (a drive whose profile is not known
    /// from the file), one line each; start-up checks it.
    pub unchecked: Vec<String>,
    /// What the check decided for the user, one line each, naming the key: the PDOs chosen
    /// from a drive's ESI file for the modes its program runs.
    pub notes: Vec<String>,
}

impl core::fmt::Debug for RunConfig {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RunConfig")
            .field("source", &self.source)
            .field("target", &self.target)
            .field("cycle", &self.master.cycle.cycle)
            .field("startup", &self.master.startup)
            .field("rt", &self.master.cycle.rt)
            .field("duration", &self.duration)
            .field("drives", &self.drives)
            .finish_non_exhaustive()
    }
}

/// Parse a duration as the file writes it: a number and a unit, `ns`, `us` (`µs`), `ms`, `s`,
/// `min` or `h` (`250us`, `1 ms`, `0.5ms`, `10s`, `2min`, `1h`).
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    if t.starts_with('-') {
        return Err(format!(
            "{text:?} is negative: a time is 0 or more (write e.g. \"5s\")"
        ));
    }
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let unit = unit.trim();
    let scale = match unit {
        "ns" => 1e-9,
        "us" | "µs" => 1e-6,
        "ms" => 1e-3,
        "s" => 1.0,
        "min" => 60.0,
        "h" => 3600.0,
        "" => {
            return Err(format!(
                "{text:?} has no unit (write e.g. \"1ms\", \"250us\", \"10s\")"
            ));
        }
        u => {
            return Err(format!(
                "unknown time unit {u:?} in {text:?} (use ns, us, ms, s, min or h)"
            ));
        }
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("{text:?} is not a time (write e.g. \"1ms\", \"250us\", \"10s\")"))?;
    let secs = v * scale;
    if !secs.is_finite() || !(0.0..=86_400.0 * 365.0).contains(&secs) {
        return Err(format!("{text:?} is out of range"));
    }
    Ok(Duration::from_secs_f64(secs))
}

/// Read and check a configuration file.
pub fn load(path: &Path) -> Result<RunConfig, ConfigError> {
    let (text, file) = read_text(path, "the file")?;
    parse(&text, &file)
}

/// The text of `path` and its name as shown, or an error saying `what` cannot be read.
fn read_text(path: &Path, what: &str) -> Result<(String, String), ConfigError> {
    let file = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => Ok((text, file)),
        Err(e) => Err(ConfigError {
            file,
            line: 0,
            column: 0,
            key: None,
            message: format!("cannot read {what}: {e}"),
        }),
    }
}

#[derive(Clone, Copy)]
struct Ctx<'a> {
    text: &'a str,
    file: &'a str,
}

impl Ctx<'_> {
    fn err(
        &self,
        span: Range<usize>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> ConfigError {
        let (line, column) = line_col(self.text, span.start);
        let key = key.into();
        ConfigError {
            file: self.file.to_string(),
            line,
            column,
            key: (!key.is_empty()).then_some(key),
            message: message.into(),
        }
    }
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset.min(text.len())).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Rewrite serde's messages in the file's terms.
fn friendly(msg: &str) -> String {
    msg.replace("unknown field", "unknown key")
        .replace("missing field", "missing key")
        .replace("expected one of", "the keys allowed here are")
        .replace("unknown variant", "unknown step")
}

fn key_path(p: &serde_path_to_error::Path) -> String {
    p.to_string()
        .replace(".$__serde_spanned_private_value", "")
        .replace("$__serde_spanned_private_value", "")
        .trim_matches('.')
        .to_string()
}

/// One step of a key path.
enum Segment {
    Key(String),
    Index(usize),
}

/// The span of the item at `path` in the file (or of the key `unknown` inside it, or of the
/// last key of the path when `unknown` is that key), as precise as the file allows.
fn locate(text: &str, path: &[Segment], unknown: Option<&str>) -> Option<Range<usize>> {
    let doc = toml_edit::ImDocument::parse(text).ok()?;
    let mut item = doc.as_item();
    let mut parent = None;
    for (n, seg) in path.iter().enumerate() {
        let last = n + 1 == path.len();
        let next = match seg {
            Segment::Key(k) => {
                if last && unknown == Some(k.as_str()) {
                    // The unknown key: point at it.
                    return key_span(item, k).or_else(|| item.span());
                }
                item.get(k.as_str())
            }
            Segment::Index(i) => item.get(*i),
        };
        match next {
            Some(x) => {
                parent = Some(item);
                item = x;
            }
            None => {
                return item
                    .span()
                    .or_else(|| parent.and_then(toml_edit::Item::span));
            }
        }
    }
    if let Some(k) = unknown
        && let Some(s) = key_span(item, k)
    {
        return Some(s);
    }
    item.span()
}

fn key_span(item: &toml_edit::Item, key: &str) -> Option<Range<usize>> {
    match item {
        toml_edit::Item::Table(t) => t.key(key).and_then(toml_edit::Key::span),
        toml_edit::Item::Value(toml_edit::Value::InlineTable(t)) => {
            t.key(key).and_then(toml_edit::Key::span)
        }
        _ => None,
    }
}

/// The file's text as `T`, an error located at the key (line and column) when it does not fit.
fn deserialize<T: serde::de::DeserializeOwned>(cx: &Ctx<'_>) -> Result<T, ConfigError> {
    let de = toml::Deserializer::new(cx.text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let key = key_path(e.path());
        let segments: Vec<Segment> = e
            .path()
            .iter()
            .filter_map(|s| match s {
                serde_path_to_error::Segment::Seq { index } => Some(Segment::Index(*index)),
                serde_path_to_error::Segment::Map { key } if !key.starts_with("$__serde") => {
                    Some(Segment::Key(key.clone()))
                }
                _ => None,
            })
            .collect();
        let inner = e.into_inner();
        // The TOML parser's messages can span lines ("invalid string\nexpected ..."), and are
        // empty for some syntax errors (`a =` at the end of the file); an error is shown on one
        // line and says something.
        let mut message = inner
            .message()
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join("; ");
        if message.is_empty() {
            message = "invalid TOML syntax here".to_string();
        }
        let toml_span = inner.span();
        // serde names the unknown key as the last path segment; the key itself is then the
        // most precise position.
        let unknown = message
            .strip_prefix("unknown field `")
            .and_then(|r| r.split('`').next());
        let located = locate(cx.text, &segments, unknown);
        let span = match (toml_span, located) {
            (Some(t), Some(l)) if l.start >= t.start && l.end <= t.end => l,
            (Some(t), _) => t,
            (None, Some(l)) => l,
            (None, None) => 0..0,
        };
        let key = if key == "." { String::new() } else { key };
        cx.err(span, key, friendly(&message))
    })
}

/// Check a configuration file's text. `source` names it in errors.
pub fn parse(text: &str, source: &str) -> Result<RunConfig, ConfigError> {
    let cx = Ctx { text, file: source };
    let f: raw::File = deserialize(&cx)?;
    if canopen::is_canopen(&f) {
        let i = f.interface.get_ref();
        return Err(cx.err(
            f.interface.span(),
            "interface",
            if i == "can-sim" || i.starts_with("vbus:") {
                format!(
                    "{i:?} is a CANopen bus: this file is a CANopen run (`ecdrive run` takes \
                     it); an EtherCAT run needs a network interface or \"sim\""
                )
            } else {
                "a drive selected by `node` makes this file a CANopen run (`ecdrive run` takes \
                 it); an EtherCAT run selects by position, alias or identity"
                    .to_string()
            },
        ));
    }
    ethercat::parse_ethercat(&cx, f)
}

/// A run file of either bus.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
pub enum Config {
    /// An EtherCAT run.
    EtherCat(RunConfig),
    /// A CANopen run (`interface = "can-sim"`, `"vbus:PATH"`, or drives selected by `node`).
    CanOpen(canopen::CanRunConfig),
}

/// Check a run file of either bus: a CANopen run when the interface is a CANopen bus or a
/// drive is selected by `node`, else an EtherCAT run ([`parse`]).
pub fn parse_any(text: &str, source: &str) -> Result<Config, ConfigError> {
    let cx = Ctx { text, file: source };
    let f: raw::File = deserialize(&cx)?;
    if canopen::is_canopen(&f) {
        canopen::parse(&cx, &f).map(Config::CanOpen)
    } else {
        ethercat::parse_ethercat(&cx, f).map(Config::EtherCat)
    }
}

/// Read and check a run file of either bus ([`parse_any`]).
pub fn load_any(path: &Path) -> Result<Config, ConfigError> {
    let (text, file) = read_text(path, "the file")?;
    parse_any(&text, &file)
}

/// The start-up values of a drive entry (`sdos`), typed by the drive's dictionary when its
/// profile is known (`dict`: its objects and name), else by the TOML value. None may be an
/// object a home, pp, pv or tq step writes (`steps_write`): it would silently change that step.
#[allow(clippy::type_complexity)]
fn start_up_values(
    cx: &Ctx<'_>,
    key: &dyn Fn(&str) -> String,
    d: &Spanned<raw::Drive>,
    dict: Option<(&'static [crate::od::ObjectDesc], &str)>,
    steps_write: &[ObjectAddress],
) -> Result<Vec<(ObjectAddress, Value)>, ConfigError> {
    let table = d.get_ref().sdos.as_ref();
    let mut sdos = Vec::new();
    if let Some(table) = table {
        for (a, v) in table.get_ref() {
            let k = key(&format!("sdos.\"{a}\""));
            let addr: ObjectAddress = a.parse().map_err(|e: crate::od::AddressParseError| {
                cx.err(v.span(), k.clone(), e.to_string())
            })?;
            if let Some(why) = set_by_ecdrive(addr) {
                return Err(cx.err(
                    v.span(),
                    k,
                    format!("{addr} is {why}: not a start-up value"),
                ));
            }
            let text = match v.get_ref() {
                toml::Value::Integer(i) => i.to_string(),
                toml::Value::Float(x) => x.to_string(),
                toml::Value::String(s) => s.clone(),
                toml::Value::Boolean(b) => b.to_string(),
                other => {
                    return Err(cx.err(
                        v.span(),
                        k,
                        format!(
                            "a start-up value is a number, a string or a boolean, not {}",
                            other.type_str()
                        ),
                    ));
                }
            };
            let value = match dict {
                Some((objects, name)) => {
                    let dt = Dictionary::new(objects).data_type(addr).ok_or_else(|| {
                        cx.err(
                            v.span(),
                            k.clone(),
                            format!("{addr} is not in the {name} dictionary"),
                        )
                    })?;
                    Value::parse(&text, dt)
                        .map_err(|e| cx.err(v.span(), k.clone(), e.to_string()))?
                }
                None => match v.get_ref() {
                    toml::Value::Integer(i) => Value::Int(*i),
                    toml::Value::Float(x) => Value::Real(*x),
                    toml::Value::Boolean(b) => Value::Uint(u64::from(*b)),
                    _ => Value::Str(text),
                },
            };
            if let Some((objects, name)) = dict
                && let Some(e) = Dictionary::new(objects).entry(addr)
                && !e.access.contains(crate::od::EntryAccess::WRITE_PREOP)
            {
                return Err(cx.err(
                    v.span(),
                    k,
                    format!(
                        "{addr} ({}) is not writable in PRE-OP, where start-up writes its sdos, \
                         by the {name} dictionary",
                        e.name
                    ),
                ));
            }
            sdos.push((addr, value));
        }
    }
    if let Some((a, _)) = sdos.iter().find(|(a, _)| steps_write.contains(a)) {
        let span = table.map_or(d.span(), Spanned::span);
        return Err(cx.err(
            span,
            key("sdos"),
            format!("{a} is written by a step of the program: give it there, not in sdos"),
        ));
    }
    Ok(sdos)
}

/// What ecdrive writes itself, which a start-up value would contradict or be overwritten by.
fn set_by_ecdrive(addr: ObjectAddress) -> Option<&'static str> {
    match (addr.index, addr.sub) {
        (0x6040, _) => Some("the controlword, which the state machine writes every cycle"),
        (0x6060, _) => Some(
            "the mode of operation, which ecdrive sets from `mode` and the program's mode steps",
        ),
        (0x1C12 | 0x1C13 | 0x1600..=0x17FF | 0x1A00..=0x1BFF, _) => {
            Some("part of the PDO mapping, which ecdrive writes from `mapping` (or the profile's)")
        }
        (0x1C32 | 0x1C33, 1 | 2) => Some(
            "the synchronisation (sync mode, cycle time), which ecdrive writes from `cycle` and \
             the drive's profile",
        ),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("1ms"), Ok(Duration::from_millis(1)));
        assert_eq!(parse_duration("250 us"), Ok(Duration::from_micros(250)));
        assert_eq!(parse_duration("0.5ms"), Ok(Duration::from_micros(500)));
        assert_eq!(parse_duration("10s"), Ok(Duration::from_secs(10)));
        assert!(parse_duration("10").unwrap_err().contains("no unit"));
        assert!(
            parse_duration("10 parsecs")
                .unwrap_err()
                .contains("unknown time unit")
        );
        assert!(parse_duration("-1ms").is_err());
        assert!(parse_duration("ms").is_err());
    }

    #[test]
    fn line_and_column() {
        assert_eq!(line_col("ab\ncd\n", 4), (2, 2));
        assert_eq!(line_col("x", 0), (1, 1));
        assert_eq!(line_col("x", 99), (1, 2));
    }
}
