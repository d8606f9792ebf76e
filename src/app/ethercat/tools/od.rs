//! `ecdrive upload`, `download` and `sdos`: the object dictionary over CoE.

use super::{Discovered, discover, drive_ref};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::coe::{CoeError, CoeErrorKind};
use crate::master::error::{DriveRef, ErrorKind, MasterError};
use crate::master::startup::DeviceInfo;
use crate::od::{DataType, Dictionary, EntryAccess, ObjectAddress, ObjectCode, Value};
use serde::Serialize;
use std::time::Duration;

/// Timeout of one SDO transfer or SDO information exchange (including segments).
const T_SDO: Duration = Duration::from_secs(10);

/// Where the data type of an upload or download came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TypeSource {
    /// Given by the user (`--type`).
    Explicit,
    /// The matched drive profile's dictionary.
    Profile,
    /// The drive's SDO information (entry description).
    SdoInfo,
}

impl TypeSource {
    /// `--type`, `profile` or `SDO information`, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Explicit => "--type",
            Self::Profile => "profile",
            Self::SdoInfo => "SDO information",
        }
    }
}

/// A value as JSON carries it: integers and reals as numbers, strings as text, octet strings
/// as hex digits.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum JsonValue {
    /// A signed integer.
    Int(i64),
    /// An unsigned integer.
    Uint(u64),
    /// A real.
    Real(f64),
    /// Text (strings; octet strings as `0x…` hex).
    Text(String),
}

impl From<&Value> for JsonValue {
    fn from(v: &Value) -> Self {
        match v {
            Value::Int(i) => Self::Int(*i),
            Value::Uint(u) => Self::Uint(*u),
            Value::Real(r) => Self::Real(*r),
            Value::Str(s) => Self::Text(s.clone()),
            Value::Bytes(_) => Self::Text(v.to_string()),
        }
    }
}

/// The result of an upload or a download.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SdoValue {
    /// Position of the device.
    pub position: u16,
    /// The device (profile name, or the SII name).
    pub drive: String,
    /// `0xINDEX:SUB`.
    pub address: String,
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// The entry's name, when the profile's dictionary has it.
    pub name: Option<String>,
    /// The data type, CiA 301 name (`UNSIGNED16`).
    pub data_type: String,
    /// Where the data type came from.
    pub type_source: TypeSource,
    /// The value.
    pub value: JsonValue,
    /// The value as text (`592`, `MR-J4`, `0x0102`).
    pub text: String,
    /// Integers: the value in hex, as wide as the type (`0x0250`).
    pub hex: Option<String>,
    /// The bytes transferred, in hex, in wire order.
    pub bytes: String,
}

/// The hex form of an integer value, as wide as its type (`0x0250` for a 16-bit value).
pub fn hex_of(v: &Value, dt: DataType) -> Option<String> {
    let bits = u32::from(dt.bit_len()?);
    let digits = (bits.div_ceil(4)).max(2) as usize;
    let raw = match v {
        Value::Uint(u) => *u,
        // Two's complement within the type's width.
        Value::Int(i) => {
            let mask = if bits >= 64 {
                u64::MAX
            } else {
                (1u64 << bits) - 1
            };
            (*i as u64) & mask
        }
        _ => return None,
    };
    Some(format!("0x{raw:0digits$X}"))
}

fn hex_bytes(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

fn profile_of(d: &DeviceInfo) -> Option<&'static crate::drives::DriveProfile> {
    crate::drives::by_identity(d.vendor_id, d.product_code)
}

/// The type of `addr` on device `d`: `explicit`, else the profile's dictionary, else the
/// drive's SDO information, else an error asking for `--type`. Also the entry's name when SDO
/// information gave it.
fn infer_type<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    d: &DeviceInfo,
    drive: &DriveRef,
    addr: ObjectAddress,
    explicit: Option<DataType>,
) -> Result<(DataType, TypeSource, Option<String>), MasterError> {
    if let Some(t) = explicit {
        return Ok((t, TypeSource::Explicit, None));
    }
    let profile = profile_of(d);
    if let Some(t) = profile.and_then(|p| Dictionary::new(p.dictionary).data_type(addr)) {
        return Ok((t, TypeSource::Profile, None));
    }
    let info = bus.with_coe(d.address, drive.clone(), false, T_SDO, async |c| {
        c.entry_description(addr).await
    });
    let why = match info {
        Ok(e) => match DataType::from_code(e.data_type) {
            Some(t) => {
                let name = (!e.name.is_empty()).then_some(e.name);
                return Ok((t, TypeSource::SdoInfo, name));
            }
            None => format!(
                "the drive's SDO information gives data type 0x{:04X}, which ecdrive does not know",
                e.data_type
            ),
        },
        Err(crate::master::bus::SessionError::Coe(e)) => {
            if is_missing(&e)
                && let Some(code) = e.abort_code()
            {
                return Err(MasterError::new(
                    Some(drive),
                    format!("{addr}"),
                    ErrorKind::Sdo(code),
                    format!("the drive has no such object (SDO information: {code})"),
                ));
            }
            format!("the drive's SDO information does not say ({})", e.kind)
        }
        Err(e) => return Err(MasterError::from(e)),
    };
    let not_in_profile = match profile {
        Some(p) => format!("{addr} is not in the {} dictionary, and ", p.name),
        None => "no drive profile matches this device, and ".to_string(),
    };
    Err(MasterError::new(
        Some(drive),
        format!("finding the data type of {addr}"),
        ErrorKind::Config,
        format!("{not_in_profile}{why}; give the type with --type (e.g. --type u16)"),
    ))
}

fn entry_name(d: &DeviceInfo, addr: ObjectAddress) -> Option<String> {
    let p = profile_of(d)?;
    let (obj, entry) = Dictionary::new(p.dictionary).lookup(addr)?;
    Some(if obj.code == ObjectCode::Var || entry.name.is_empty() {
        obj.name.to_string()
    } else {
        format!("{} / {}", obj.name, entry.name)
    })
}

fn coe_error(e: crate::master::bus::SessionError) -> MasterError {
    MasterError::from(e)
}

#[allow(clippy::too_many_arguments)]
fn sdo_value(
    d: &DeviceInfo,
    drive: &DriveRef,
    addr: ObjectAddress,
    dt: DataType,
    source: TypeSource,
    name: Option<String>,
    value: &Value,
    bytes: &[u8],
) -> SdoValue {
    SdoValue {
        position: d.position,
        drive: drive.name.clone(),
        address: addr.to_string(),
        index: addr.index,
        sub: addr.sub,
        name: name.or_else(|| entry_name(d, addr)),
        data_type: dt.name().to_string(),
        type_source: source,
        value: JsonValue::from(value),
        text: match value {
            Value::Str(s) => s.clone(),
            other => other.to_string(),
        },
        hex: hex_of(value, dt),
        bytes: hex_bytes(bytes),
    }
}

fn selected<'a, L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    found: &'a mut Option<Discovered>,
) -> Result<&'a DeviceInfo, MasterError> {
    let f = found.insert(discover(bus)?);
    f.device(position)
}

/// Read `addr` from the device at `position`. The data type is `data_type`, else the profile's,
/// else the drive's SDO information's (see [`TypeSource`]).
pub fn upload<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    addr: ObjectAddress,
    data_type: Option<DataType>,
) -> Result<SdoValue, MasterError> {
    let mut found = None;
    let d = selected(bus, position, &mut found)?.clone();
    let drive = drive_ref(&d);
    let (dt, source, name) = infer_type(bus, &d, &drive, addr, data_type)?;
    let bytes = bus
        .with_coe(d.address, drive.clone(), false, T_SDO, async |c| {
            c.upload(addr, false).await
        })
        .map_err(coe_error)?;
    let value = Value::decode(dt, &bytes).map_err(|e| {
        MasterError::new(
            Some(&drive),
            format!("decoding {addr} as {dt} ({})", source.describe()),
            ErrorKind::Bus,
            format!(
                "{e}; the drive sent {} byte(s): {}",
                bytes.len(),
                hex_bytes(&bytes)
            ),
        )
    })?;
    Ok(sdo_value(
        &d, &drive, addr, dt, source, name, &value, &bytes,
    ))
}

/// Write `value` (as the user typed it: decimal or `0x` hex for integers) to `addr` on the
/// device at `position`. The value must fit the data type (found as for [`upload`]).
pub fn download<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    addr: ObjectAddress,
    value: &str,
    data_type: Option<DataType>,
) -> Result<SdoValue, MasterError> {
    // Check the value against an explicit type before touching the bus.
    if let Some(dt) = data_type {
        Value::parse(value, dt).map_err(|e| {
            MasterError::new(
                None,
                format!("parsing the value for {addr}"),
                ErrorKind::Config,
                e,
            )
        })?;
    }
    let mut found = None;
    let d = selected(bus, position, &mut found)?.clone();
    let drive = drive_ref(&d);
    let (dt, source, name) = infer_type(bus, &d, &drive, addr, data_type)?;
    let v = Value::parse(value, dt).map_err(|e| {
        MasterError::new(
            Some(&drive),
            format!(
                "parsing the value for {addr} ({dt} from {})",
                source.describe()
            ),
            ErrorKind::Config,
            e,
        )
    })?;
    let bytes = v.encode(dt).map_err(|e| {
        MasterError::new(
            Some(&drive),
            format!("encoding the value for {addr}"),
            ErrorKind::Config,
            e,
        )
    })?;
    let sent = bytes.clone();
    bus.with_coe(d.address, drive.clone(), false, T_SDO, async move |c| {
        c.download(addr, &sent, false).await
    })
    .map_err(|e| {
        // A refusal the drive's manual explains: say so, with its words.
        let why = crate::drives::by_identity(d.vendor_id, d.product_code)
            .and_then(|p| p.caps.sdo_refused_while_rx_mapped);
        let mut err = coe_error(e);
        if let (ErrorKind::Sdo(code), Some(why)) = (&err.kind, why)
            && *code == crate::od::SdoAbortCode::MAPPED_TO_RXPDO
        {
            err.reason = format!("{}: {why}", err.reason);
        }
        err
    })?;
    Ok(sdo_value(&d, &drive, addr, dt, source, name, &v, &bytes))
}

/// One entry of an object, as SDO information describes it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OdEntry {
    /// Sub-index.
    pub sub: u8,
    /// `0xINDEX:SUB`.
    pub address: String,
    /// Name.
    pub name: String,
    /// Data type name (CiA 301), or `0xNNNN` for a type ecdrive does not know.
    pub data_type: String,
    /// Size in bits.
    pub bit_len: u16,
    /// Access per state as the IgH tool writes it: `rwrwrw` = read/write in PRE-OP, SAFE-OP, OP.
    pub access: String,
    /// `rx`, `tx` or none: PDO mappability.
    pub pdo_mapping: Option<String>,
    /// The value, with `--values`, for readable entries (the upload error's text otherwise).
    pub value: Option<String>,
}

/// One object of the dictionary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OdObject {
    /// Index.
    pub index: u16,
    /// Name.
    pub name: String,
    /// `VAR`, `ARRAY`, `RECORD` (or the numeric code).
    pub object_code: String,
    /// Highest sub-index.
    pub max_sub: u8,
    /// The entries that exist.
    pub entries: Vec<OdEntry>,
}

fn access_text(a: EntryAccess) -> String {
    let mut s = String::with_capacity(6);
    for (r, w) in [
        (EntryAccess::READ_PREOP, EntryAccess::WRITE_PREOP),
        (EntryAccess::READ_SAFEOP, EntryAccess::WRITE_SAFEOP),
        (EntryAccess::READ_OP, EntryAccess::WRITE_OP),
    ] {
        s.push(if a.contains(r) { 'r' } else { '-' });
        s.push(if a.contains(w) { 'w' } else { '-' });
    }
    s
}

fn mapping_text(a: EntryAccess) -> Option<String> {
    match (
        a.contains(EntryAccess::RXPDO),
        a.contains(EntryAccess::TXPDO),
    ) {
        (true, true) => Some("rx/tx".into()),
        (true, false) => Some("rx".into()),
        (false, true) => Some("tx".into()),
        (false, false) => None,
    }
}

fn type_name(code: u16) -> String {
    DataType::from_code(code).map_or_else(|| format!("0x{code:04X}"), |t| t.name().to_string())
}

/// Whether a CoE error means "this sub-index does not exist" (a gap in a RECORD).
fn is_missing(e: &CoeError) -> bool {
    matches!(
        e.kind,
        CoeErrorKind::Abort(c) | CoeErrorKind::InfoError(c)
            if c == crate::od::SdoAbortCode::NO_SUBINDEX
                || c == crate::od::SdoAbortCode::NO_OBJECT
    )
}

/// Where an object listing came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OdSource {
    /// The drive's SDO information: what the drive itself says.
    SdoInfo,
    /// The matched drive profile's dictionary, because the drive offers no SDO information.
    Profile,
}

/// What `sdos` reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OdListing {
    /// Position of the device.
    pub position: u16,
    /// The device (profile name, or the SII name).
    pub drive: String,
    /// Where the listing came from.
    pub source: OdSource,
    /// Why the drive's SDO information was not used, when `source` is the profile.
    pub note: Option<String>,
    /// The objects in index order.
    pub objects: Vec<OdObject>,
    /// What could not be read: the listing went on without it (an object or entry whose
    /// description came back as an error or malformed), or stopped there (the drive stopped
    /// answering).
    pub problems: Vec<OdProblem>,
    /// Whether every object and entry the drive lists is in `objects`.
    pub complete: bool,
}

/// An object or entry `sdos` could not read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OdProblem {
    /// `0xINDEX` for an object, `0xINDEX:SUB` for an entry.
    pub address: String,
    /// What was being read: `object description`, `entry description`.
    pub what: String,
    /// Why it failed.
    pub reason: String,
    /// Whether the listing stopped here (the drive stopped answering) instead of going on.
    pub stopped: bool,
}

/// Whether an SDO-information failure concerns only the item asked for (an error reply, an
/// abort, a reply that does not decode): the listing goes on without it.
fn item_only(e: &CoeError) -> bool {
    matches!(
        e.kind,
        CoeErrorKind::Abort(_)
            | CoeErrorKind::InfoError(_)
            | CoeErrorKind::Protocol(_)
            | CoeErrorKind::MailboxError(_)
    )
}

/// Upload `addr` and render it for a listing: `0x0250 592`, a string, or the abort.
async fn value_text(
    c: &mut crate::master::coe::CoeClient<'_>,
    addr: ObjectAddress,
    dt: Option<DataType>,
) -> Result<String, CoeError> {
    Ok(match c.upload(addr, false).await {
        Ok(bytes) => match dt {
            Some(dt) => Value::decode(dt, &bytes)
                .map(|v| match hex_of(&v, dt) {
                    Some(h) => format!("{h} {v}"),
                    None => v.to_string(),
                })
                .unwrap_or_else(|_| format!("0x{}", hex_bytes(&bytes))),
            None => format!("0x{}", hex_bytes(&bytes)),
        },
        Err(err) => match err.abort_code() {
            Some(code) => format!("SDO abort {code}"),
            None => return Err(err),
        },
    })
}

/// The object dictionary of the device at `position`, read through SDO information (object
/// list, object and entry descriptions). A drive without SDO information is listed from its
/// drive profile's dictionary instead ([`OdSource::Profile`]), if it has one. With `values`,
/// every readable entry is uploaded too. `progress(done, total)` is called after each object.
pub fn sdos<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    values: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<OdListing, MasterError> {
    let mut found = None;
    let d = selected(bus, position, &mut found)?.clone();
    let drive = drive_ref(&d);
    let listing = |source, note, objects, problems: Vec<OdProblem>| OdListing {
        position,
        drive: drive.name.clone(),
        source,
        note,
        objects,
        complete: problems.is_empty(),
        problems,
    };
    let indices = match bus.with_coe(d.address, drive.clone(), false, T_SDO, async |c| {
        c.od_list(crate::ec::mailbox::list_type::ALL).await
    }) {
        Ok(i) => i,
        Err(crate::master::bus::SessionError::Coe(e))
            if matches!(
                e.kind,
                CoeErrorKind::MailboxError(_) | CoeErrorKind::InfoError(_)
            ) && profile_of(&d).is_some() =>
        {
            let p = profile_of(&d).ok_or_else(|| {
                MasterError::from(crate::master::bus::SessionError::Coe(e.clone()))
            })?;
            let note = format!(
                "the drive offers no SDO information ({}); objects from the {} profile",
                e.kind, p.name
            );
            let objects = profile_objects(bus, &d, &drive, p, values, progress)?;
            return Ok(listing(OdSource::Profile, Some(note), objects, Vec::new()));
        }
        Err(crate::master::bus::SessionError::Coe(e))
            if matches!(
                e.kind,
                CoeErrorKind::MailboxError(_) | CoeErrorKind::InfoError(_)
            ) =>
        {
            return Err(MasterError::new(
                Some(&drive),
                "reading the object list (SDO information)",
                ErrorKind::Incompatible,
                format!(
                    "{}; the drive offers no SDO information and ecdrive has no profile with its \
                     dictionary, so there is nothing to list (upload single objects instead)",
                    e.kind
                ),
            ));
        }
        Err(e) => {
            let mut e = coe_error(e);
            e.step = "reading the object list (SDO information)".into();
            return Err(e);
        }
    };
    let total = indices.len();
    let mut out = Vec::with_capacity(total);
    let mut problems: Vec<OdProblem> = Vec::new();
    for (n, index) in indices.into_iter().enumerate() {
        let r = bus.with_coe(d.address, drive.clone(), false, T_SDO * 4, async |c| {
            described_object(c, index, values).await
        });
        match r {
            Ok((obj, bad)) => {
                out.extend(obj);
                problems.extend(bad);
            }
            Err(e) => {
                // The drive stopped answering (a timeout, the bus): what was read stands. The
                // problem names the object or entry being read then.
                let e = coe_error(e);
                let address = if e.step.starts_with("0x") {
                    e.step.clone()
                } else {
                    format!("0x{index:04X}")
                };
                problems.push(OdProblem {
                    address,
                    what: "SDO information (the drive stopped answering)".into(),
                    reason: e.reason,
                    stopped: true,
                });
                break;
            }
        }
        progress(n + 1, total);
    }
    Ok(listing(OdSource::SdoInfo, None, out, problems))
}

/// Object `index` read through SDO information: its description and each entry's (with its
/// value, with `values`), and the items that could not be read. An error only when the drive
/// stopped answering.
async fn described_object(
    c: &mut crate::master::coe::CoeClient<'_>,
    index: u16,
    values: bool,
) -> Result<(Option<OdObject>, Vec<OdProblem>), CoeError> {
    let mut bad = Vec::new();
    let o = match c.object_description(index).await {
        Ok(o) => o,
        Err(e) if item_only(&e) => {
            bad.push(OdProblem {
                address: format!("0x{index:04X}"),
                what: "object description".into(),
                reason: e.kind.to_string(),
                stopped: false,
            });
            return Ok((None, bad));
        }
        Err(e) => return Err(e),
    };
    let subs: Vec<u8> = match ObjectCode::from_code(o.object_code) {
        Some(ObjectCode::Var) | None => vec![0],
        _ => (0..=o.max_sub).collect(),
    };
    let mut entries = Vec::with_capacity(subs.len());
    for sub in subs {
        let addr = ObjectAddress::new(index, sub);
        let e = match c.entry_description(addr).await {
            Ok(e) => e,
            Err(e) if is_missing(&e) => continue,
            Err(e) if item_only(&e) => {
                bad.push(OdProblem {
                    address: addr.to_string(),
                    what: "entry description".into(),
                    reason: e.kind.to_string(),
                    stopped: false,
                });
                continue;
            }
            Err(e) => return Err(e),
        };
        let value = if values && e.access.readable() {
            Some(value_text(c, addr, DataType::from_code(e.data_type)).await?)
        } else {
            None
        };
        entries.push(OdEntry {
            sub,
            address: addr.to_string(),
            name: e.name,
            data_type: type_name(e.data_type),
            bit_len: e.bit_len,
            access: access_text(e.access),
            pdo_mapping: mapping_text(e.access),
            value,
        });
    }
    Ok((
        Some(OdObject {
            index,
            name: o.name.into_owned(),
            object_code: ObjectCode::from_code(o.object_code)
                .map_or_else(|| o.object_code.to_string(), |c| c.name().to_string()),
            max_sub: o.max_sub,
            entries,
        }),
        bad,
    ))
}

/// The objects of a profile's dictionary, as a listing (values uploaded with `values`).
fn profile_objects<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    d: &DeviceInfo,
    drive: &DriveRef,
    p: &'static crate::drives::DriveProfile,
    values: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<OdObject>, MasterError> {
    let total = p.dictionary.len();
    let mut out = Vec::with_capacity(total);
    for (n, o) in p.dictionary.iter().enumerate() {
        let mut entries = Vec::with_capacity(o.entries.len());
        for e in o.entries {
            let addr = o.at(e.sub);
            let value = if values && e.access.readable() {
                let dt = e.data_type;
                Some(
                    bus.with_coe(d.address, drive.clone(), false, T_SDO, async |c| {
                        value_text(c, addr, Some(dt)).await
                    })
                    .map_err(coe_error)?,
                )
            } else {
                None
            };
            entries.push(OdEntry {
                sub: e.sub,
                address: addr.to_string(),
                name: e.name.to_string(),
                data_type: e.data_type.name().to_string(),
                bit_len: e.bit_len,
                access: access_text(e.access),
                pdo_mapping: mapping_text(e.access),
                value,
            });
        }
        out.push(OdObject {
            index: o.index,
            name: o.name.to_string(),
            object_code: o.code.name().to_string(),
            max_sub: o.entries.iter().map(|e| e.sub).max().unwrap_or(0),
            entries,
        });
        progress(n + 1, total);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_is_as_wide_as_the_type() {
        assert_eq!(
            hex_of(&Value::Uint(0x250), DataType::Unsigned16).as_deref(),
            Some("0x0250")
        );
        assert_eq!(
            hex_of(&Value::Int(-1), DataType::Integer8).as_deref(),
            Some("0xFF")
        );
        assert_eq!(
            hex_of(&Value::Int(-2), DataType::Integer32).as_deref(),
            Some("0xFFFFFFFE")
        );
        assert_eq!(
            hex_of(&Value::Str("x".into()), DataType::VisibleString),
            None
        );
    }

    #[test]
    fn access_is_written_per_state() {
        assert_eq!(access_text(EntryAccess::RW), "rwrwrw");
        assert_eq!(access_text(EntryAccess::RO), "r-r-r-");
        assert_eq!(access_text(EntryAccess::RW_PREOP), "rwr-r-");
        assert_eq!(
            mapping_text(EntryAccess::RO | EntryAccess::TXPDO).as_deref(),
            Some("tx")
        );
    }
}
