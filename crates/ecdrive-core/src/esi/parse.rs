//! The parser: roxmltree document → [`EsiFile`].
//!
//! Elements are matched by local name (namespaces are ignored except for this project's own
//! vendor-specific extension). Unknown elements and attributes are skipped; a missing element
//! the schema requires, or a value that is not allowed, is an [`EsiError`] with the position of
//! the offending text.

use super::dictionary::{
    ArrayInfo, Category, Dictionary, EsiDataType, EsiObject, EsiSubItem, EsiValue, Flags,
    ObjectInfo,
};
use super::error::{EsiError, EsiErrorKind, Position};
use super::model::*;
use super::num::{self, EsiInt};
use crate::od::EntryAccess;
use roxmltree::{Document, Node};
use std::cell::RefCell;

/// The XML namespace of this project's vendor-specific elements.
pub const ECDRIVE_NAMESPACE: &str = "urn:ecdrive:esi";

type R<T> = Result<T, EsiError>;

/// Parse ESI text.
pub(crate) fn parse_str(text: &str) -> R<EsiFile> {
    if text.len() > MAX_TEXT_BYTES {
        return Err(EsiError::new(
            EsiErrorKind::Invalid,
            Position::default(),
            format!(
                "the file is {} MiB; ESI files of more than {} MiB are not read",
                text.len() >> 20,
                MAX_TEXT_BYTES >> 20
            ),
        ));
    }
    check_depth(text)?;
    let opts = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_NODES,
    };
    let doc = Document::parse_with_options(text, opts).map_err(|e| {
        // The parser gives no position for a file that ends too early: it ends at its end
        // (a truncated file), which is where to look.
        let (row, col) = if matches!(e, roxmltree::Error::UnexpectedEndOfStream) {
            end_of(text)
        } else {
            let p = e.pos();
            (p.row, p.col)
        };
        EsiError::new(
            EsiErrorKind::Xml,
            Position::new(row, col),
            format!("malformed XML: {e}"),
        )
    })?;
    P {
        doc: &doc,
        warnings: RefCell::new(Vec::new()),
    }
    .file()
}

/// Line and column (1-based, in characters) just past the last character of `text`.
fn end_of(text: &str) -> (u32, u32) {
    let line = text.matches('\n').count() + 1;
    let last = text.rsplit('\n').next().unwrap_or("");
    let col = last.chars().count() + 1;
    (
        u32::try_from(line).unwrap_or(u32::MAX),
        u32::try_from(col).unwrap_or(u32::MAX),
    )
}

/// The largest ESI text read (the largest real files are a few MiB).
pub const MAX_TEXT_BYTES: usize = 64 << 20;
/// The deepest element nesting read (ESI files nest about a dozen levels).
pub const MAX_DEPTH: usize = 256;
/// The most XML nodes read.
const MAX_NODES: u32 = 16_000_000;

/// Refuse text whose elements nest deeper than [`MAX_DEPTH`], before the XML parser (and
/// anything walking its tree) sees it: one line of error at the element that goes too deep.
/// The scan follows XML's lexical rules only as far as nesting needs (comments, CDATA,
/// processing instructions, declarations, quoted attribute values, empty-element tags); the
/// XML parser judges the rest.
fn check_depth(text: &str) -> R<()> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0usize;
    let find = |from: usize, pat: &[u8]| -> usize {
        b.get(from..)
            .and_then(|rest| rest.windows(pat.len()).position(|w| w == pat))
            .map_or(b.len(), |p| from + p + pat.len())
    };
    while let Some(off) = b.get(i..).and_then(|r| r.iter().position(|&c| c == b'<')) {
        let at = i + off;
        let rest = b.get(at..).unwrap_or_default();
        if rest.starts_with(b"<!--") {
            i = find(at + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = find(at + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = find(at + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = find(at + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = find(at + 2, b">");
        } else {
            // A start tag: to its '>' outside quotes; '/>' closes it at once.
            let mut j = at + 1;
            let mut quote: Option<u8> = None;
            let mut empty = false;
            while let Some(&c) = b.get(j) {
                match quote {
                    Some(q) if c == q => quote = None,
                    Some(_) => {}
                    None if c == b'"' || c == b'\'' => quote = Some(c),
                    None if c == b'>' => {
                        empty = j > at + 1 && b.get(j - 1) == Some(&b'/');
                        break;
                    }
                    None => {}
                }
                j += 1;
            }
            if !empty {
                depth += 1;
                if depth > MAX_DEPTH {
                    let line = b
                        .get(..at)
                        .unwrap_or_default()
                        .iter()
                        .filter(|&&c| c == b'\n')
                        .count() as u32
                        + 1;
                    let line_start = b
                        .get(..at)
                        .unwrap_or_default()
                        .iter()
                        .rposition(|&c| c == b'\n')
                        .map_or(0, |p| p + 1);
                    let column =
                        text.get(line_start..at).map_or(0, |s| s.chars().count()) as u32 + 1;
                    return Err(EsiError::new(
                        EsiErrorKind::Invalid,
                        Position::new(line, column),
                        format!(
                            "elements nest deeper than {MAX_DEPTH} levels: not an ESI file \
                             (ESI files nest about a dozen)"
                        ),
                    ));
                }
            }
            i = j + 1;
        }
    }
    Ok(())
}

/// Decode the bytes of an ESI file into text: UTF-8 (with or without BOM), UTF-16 with BOM,
/// or — when the bytes are not UTF-8 — ISO-8859-1 if the XML declaration says so (many
/// vendor files are Latin-1).
pub(crate) fn decode_bytes(bytes: &[u8]) -> R<String> {
    if let Some(rest) = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]) {
        return utf8(rest);
    }
    let utf16 = |le: bool, rest: &[u8]| -> R<String> {
        let units = rest.chunks(2).map(|c| match (c, le) {
            ([a, b], true) => u16::from_le_bytes([*a, *b]),
            ([a, b], false) => u16::from_be_bytes([*a, *b]),
            _ => 0xFFFF,
        });
        char::decode_utf16(units)
            .map(|c| {
                c.ok().filter(|_| rest.len() % 2 == 0).ok_or_else(|| {
                    EsiError::new(
                        EsiErrorKind::Encoding,
                        Position::default(),
                        "the file starts with a UTF-16 byte-order mark but is not valid \
                             UTF-16",
                    )
                })
            })
            .collect()
    };
    if let Some(rest) = bytes.strip_prefix(&[0xFF, 0xFE]) {
        return utf16(true, rest);
    }
    if let Some(rest) = bytes.strip_prefix(&[0xFE, 0xFF]) {
        return utf16(false, rest);
    }
    match std::str::from_utf8(bytes) {
        Ok(s) => Ok(s.to_string()),
        Err(e) => {
            if declared_latin1(bytes) {
                Ok(bytes.iter().map(|&b| char::from(b)).collect())
            } else {
                Err(utf8_error(bytes, e))
            }
        }
    }
}

fn utf8(bytes: &[u8]) -> R<String> {
    std::str::from_utf8(bytes)
        .map(str::to_string)
        .map_err(|e| utf8_error(bytes, e))
}

fn utf8_error(bytes: &[u8], e: std::str::Utf8Error) -> EsiError {
    let good = bytes.get(..e.valid_up_to()).unwrap_or_default();
    let line = good.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
    let line_start = good
        .iter()
        .rposition(|&b| b == b'\n')
        .map(|p| p + 1)
        .unwrap_or(0);
    let col = std::str::from_utf8(good.get(line_start..).unwrap_or_default())
        .map(|s| s.chars().count())
        .unwrap_or(0) as u32
        + 1;
    EsiError::new(
        EsiErrorKind::Encoding,
        Position::new(line, col),
        "not valid UTF-8, and the XML declaration does not name ISO-8859-1",
    )
}

/// Whether the XML declaration names a Latin-1 encoding.
fn declared_latin1(bytes: &[u8]) -> bool {
    let head = bytes.get(..bytes.len().min(200)).unwrap_or_default();
    let Some(end) = head.windows(2).position(|w| w == b"?>") else {
        return false;
    };
    let decl: String = head
        .get(..end)
        .unwrap_or_default()
        .iter()
        .map(|&b| char::from(b).to_ascii_lowercase())
        .collect();
    decl.starts_with("<?xml")
        && [
            "iso-8859-1",
            "iso8859-1",
            "latin1",
            "latin-1",
            "windows-1252",
            "cp1252",
        ]
        .iter()
        .any(|enc| decl.contains(enc))
}

struct P<'a, 'input> {
    doc: &'a Document<'input>,
    /// Problems read past: the value is left out (or taken as the tolerance says) and the
    /// reading goes on.
    warnings: RefCell<Vec<EsiError>>,
}

fn children<'a, 'i>(node: Node<'a, 'i>, name: &'static str) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == name)
}

fn child<'a, 'i>(node: Node<'a, 'i>, name: &'static str) -> Option<Node<'a, 'i>> {
    children(node, name).next()
}

/// The text of an element (its direct text children), trimmed.
fn text_of(node: Node) -> String {
    let s: String = node
        .children()
        .filter(|c| c.is_text())
        .filter_map(|c| c.text())
        .collect();
    s.trim().to_string()
}

impl<'a, 'input> P<'a, 'input> {
    fn pos(&self, byte: usize) -> Position {
        // roxmltree slices the input at `byte`: keep it on a character boundary.
        let text = self.doc.input_text();
        let mut b = byte.min(text.len());
        while b > 0 && !text.is_char_boundary(b) {
            b -= 1;
        }
        let p = self.doc.text_pos_at(b);
        Position::new(p.row, p.col)
    }

    fn node_pos(&self, node: Node) -> Position {
        self.pos(node.range().start)
    }

    /// Position of an element's value: its first non-blank text character, or the element.
    fn text_pos(&self, node: Node) -> Position {
        for c in node.children() {
            if let (true, Some(t)) = (c.is_text(), c.text()) {
                if let Some(off) = t.find(|ch: char| !ch.is_whitespace()) {
                    // The offset is into the unescaped text; use it only when the source
                    // text is the same (no entities, no CDATA markup).
                    let start = c.range().start;
                    let raw = self.doc.input_text().get(c.range());
                    return self.pos(if raw == Some(t) { start + off } else { start });
                }
            }
        }
        self.node_pos(node)
    }

    /// Note a problem read past.
    fn warn(&self, e: EsiError) {
        self.warnings.borrow_mut().push(e);
    }

    /// The value, or — noting the problem — `None`.
    fn soft<T>(&self, r: R<T>) -> Option<T> {
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                self.warn(e);
                None
            }
        }
    }

    fn invalid(&self, pos: Position, msg: String) -> EsiError {
        EsiError::new(EsiErrorKind::Invalid, pos, msg)
    }

    fn missing(&self, node: Node, msg: String) -> EsiError {
        EsiError::new(EsiErrorKind::Missing, self.node_pos(node), msg)
    }

    fn req_child(
        &self,
        node: Node<'a, 'input>,
        name: &'static str,
        scope: &str,
    ) -> R<Node<'a, 'input>> {
        child(node, name).ok_or_else(|| self.missing(node, format!("{scope} has no <{name}>")))
    }

    /// A number in child element `name`, if present.
    fn num_child<T: EsiInt>(&self, node: Node, name: &'static str, scope: &str) -> R<Option<T>> {
        match child(node, name) {
            None => Ok(None),
            Some(c) => self.num_text(c, name, scope).map(Some),
        }
    }

    fn num_text<T: EsiInt>(&self, el: Node, name: &str, scope: &str) -> R<T> {
        let t = text_of(el);
        num::parse_num::<T>(&t)
            .map_err(|m| self.invalid(self.text_pos(el), format!("{scope} has {name} {t:?}: {m}")))
    }

    fn req_num_child<T: EsiInt>(&self, node: Node, name: &'static str, scope: &str) -> R<T> {
        self.num_child(node, name, scope)?
            .ok_or_else(|| self.missing(node, format!("{scope} has no <{name}>")))
    }

    fn attr_num<T: EsiInt>(&self, node: Node, name: &'static str, scope: &str) -> R<Option<T>> {
        let Some(a) = node.attributes().find(|a| a.name() == name) else {
            return Ok(None);
        };
        num::parse_num::<T>(a.value()).map(Some).map_err(|m| {
            self.invalid(
                self.pos(a.range_value().start),
                format!("{scope} has {name}=\"{}\": {m}", a.value()),
            )
        })
    }

    fn attr_bool(&self, node: Node, name: &'static str, scope: &str) -> R<Option<bool>> {
        let Some(a) = node.attributes().find(|a| a.name() == name) else {
            return Ok(None);
        };
        num::parse_bool(a.value()).map(Some).map_err(|m| {
            self.invalid(
                self.pos(a.range_value().start),
                format!("{scope} has {name}=\"{}\": {m}", a.value()),
            )
        })
    }

    /// A boolean in child element `name` (`true`/`false`/`1`/`0`), if present.
    fn bool_child(&self, node: Node, name: &'static str, scope: &str) -> R<Option<bool>> {
        let Some(c) = child(node, name) else {
            return Ok(None);
        };
        let t = text_of(c);
        num::parse_bool(&t)
            .map(Some)
            .map_err(|m| self.invalid(self.text_pos(c), format!("{scope} has {name} {t:?}: {m}")))
    }

    fn flag(&self, node: Node, name: &'static str, scope: &str) -> R<bool> {
        Ok(self.attr_bool(node, name, scope)?.unwrap_or(false))
    }

    /// A flag attribute; a value that is not a boolean is noted and read as `false`.
    fn soft_flag(&self, node: Node, name: &'static str, scope: &str) -> bool {
        self.soft(self.flag(node, name, scope)).unwrap_or(false)
    }

    fn hex_child(&self, node: Node, name: &'static str, scope: &str) -> R<Option<Vec<u8>>> {
        match child(node, name) {
            None => Ok(None),
            Some(c) => {
                let t = text_of(c);
                num::parse_hex_bytes(&t).map(Some).map_err(|m| {
                    self.invalid(self.text_pos(c), format!("{scope} has {name} {t:?}: {m}"))
                })
            }
        }
    }

    /// All `<name>` children as localized texts.
    fn names(&self, node: Node, name: &'static str, scope: &str) -> R<Vec<LocalizedText>> {
        children(node, name)
            .map(|n| {
                Ok(LocalizedText {
                    lcid: self.attr_num::<u32>(n, "LcId", scope)?,
                    text: text_of(n),
                })
            })
            .collect()
    }

    fn file(&self) -> R<EsiFile> {
        let root = self.doc.root_element();
        if root.tag_name().name() != "EtherCATInfo" {
            return Err(self.invalid(
                self.node_pos(root),
                format!(
                    "the root element is <{}>, expected <EtherCATInfo> (is this an ESI file?)",
                    root.tag_name().name()
                ),
            ));
        }
        let vendor = self.vendor(self.req_child(root, "Vendor", "<EtherCATInfo>")?)?;
        let desc = self.req_child(root, "Descriptions", "<EtherCATInfo>")?;
        let mut groups = Vec::new();
        if let Some(g) = child(desc, "Groups") {
            for n in children(g, "Group") {
                let scope = "<Group>";
                let t = self.req_child(n, "Type", scope)?;
                let names = self.names(n, "Name", scope)?;
                groups.push(Group {
                    type_: text_of(t),
                    name: preferred_text(&names).to_string(),
                    names,
                });
            }
        }
        let devs = self.req_child(desc, "Devices", "<Descriptions>")?;
        let mut devices = Vec::new();
        let mut unreadable = Vec::new();
        for d in children(devs, "Device") {
            match self.device(d) {
                Ok(dev) => devices.push(dev),
                Err(error) => unreadable.push(self.unreadable(d, error)),
            }
        }
        let mut warnings = self.warnings.take();
        warnings.sort_by_key(|w| w.position);
        Ok(EsiFile {
            version: root.attribute("Version").map(str::to_string),
            vendor,
            groups,
            devices,
            unreadable,
            warnings,
        })
    }

    fn vendor(&self, n: Node) -> R<Vendor> {
        let scope = "<Vendor>";
        let id_el = self.req_child(n, "Id", scope)?;
        let t = text_of(id_el);
        let id = num::parse_u32_wrapping(&t).map_err(|m| {
            self.invalid(self.text_pos(id_el), format!("{scope} has Id {t:?}: {m}"))
        })?;
        let names = self.names(n, "Name", scope)?;
        Ok(Vendor {
            id,
            name: preferred_text(&names).to_string(),
            names,
        })
    }

    /// What can still be said of a device that could not be read: its identity, as far as it
    /// reads, and why.
    fn unreadable(&self, n: Node, error: EsiError) -> UnreadableDevice {
        let t = child(n, "Type");
        let ident = |attr: &str| {
            t.and_then(|t| t.attribute(attr))
                .and_then(|v| num::parse_u32_wrapping(v).ok())
        };
        let names = self.names(n, "Name", "<Device>").unwrap_or_default();
        UnreadableDevice {
            position: self.node_pos(n),
            type_text: t.map(text_of).unwrap_or_default(),
            name: preferred_text(&names).to_string(),
            product_code: ident("ProductCode"),
            revision_no: ident("RevisionNo"),
            error,
        }
    }

    fn device(&self, n: Node<'a, 'input>) -> R<Device> {
        let t = self.req_child(n, "Type", "<Device>")?;
        let type_text = text_of(t);
        let scope = format!("<Device> {type_text:?}");
        let ident = |attr: &'static str| -> R<Option<u32>> {
            let Some(a) = t.attributes().find(|a| a.name() == attr) else {
                return Ok(None);
            };
            num::parse_u32_wrapping(a.value()).map(Some).map_err(|m| {
                self.invalid(
                    self.pos(a.range_value().start),
                    format!("{scope} has {attr}=\"{}\": {m}", a.value()),
                )
            })
        };
        let product_code = ident("ProductCode")?.ok_or_else(|| {
            self.missing(t, format!("<Type> of {scope} has no ProductCode attribute"))
        })?;
        let revision_no = ident("RevisionNo")?;
        let names = self.names(n, "Name", &scope)?;
        let name = match preferred_text(&names) {
            "" => type_text.clone(),
            s => s.to_string(),
        };

        let fmmus = self.fmmus(n, &scope);
        let mut sync_managers = self.sync_managers(n, &scope)?;

        let mut rx_pdos = children(n, "RxPdo")
            .map(|p| self.pdo(p, "RxPdo"))
            .collect::<R<Vec<_>>>()?;
        let mut tx_pdos = children(n, "TxPdo")
            .map(|p| self.pdo(p, "TxPdo"))
            .collect::<R<Vec<_>>>()?;
        let mailbox = child(n, "Mailbox")
            .map(|m| self.mailbox(m, &scope))
            .transpose()?;
        // A DC mode that does not read is left out (the device keeps the others); the EEPROM
        // data is only shown; profiles read entry by entry.
        let dc = match child(n, "Dc") {
            Some(dc) => children(dc, "OpMode")
                .filter_map(|m| self.soft(self.op_mode(m, &scope)))
                .collect(),
            None => Vec::new(),
        };
        self.sm_directions(&mut sync_managers, &rx_pdos, &tx_pdos, &scope);
        let eeprom = child(n, "Eeprom").and_then(|e| self.soft(self.eeprom(e, &scope)));
        let profiles: Vec<Profile> = children(n, "Profile")
            .map(|p| self.profile(p, &scope))
            .collect();

        if let Some(dict) = profiles.iter().find_map(|p| p.dictionary.as_ref()) {
            for p in rx_pdos.iter_mut().chain(tx_pdos.iter_mut()) {
                self.var_entries(p, dict);
            }
        }
        Ok(Device {
            position: self.node_pos(n),
            type_: DeviceType {
                product_code,
                revision_no,
                name_text: type_text,
            },
            name,
            names,
            group_type: child(n, "GroupType").map(text_of),
            physics: n.attribute("Physics").map(str::to_string),
            fmmus,
            sync_managers,
            rx_pdos,
            tx_pdos,
            mailbox,
            dc,
            eeprom,
            profiles,
        })
    }

    /// The device's `<Fmmu>`s; a usage that is none of ETG.2000's is read by position, noted.
    fn fmmus(&self, n: Node<'a, 'input>, scope: &str) -> Vec<Fmmu> {
        let mut fmmus = Vec::new();
        for f in children(n, "Fmmu") {
            let s = format!("<Fmmu> in {scope}");
            let text = text_of(f);
            let usage = match text.to_ascii_lowercase().as_str() {
                "outputs" => FmmuUsage::Outputs,
                "inputs" => FmmuUsage::Inputs,
                "mboxstate" => FmmuUsage::SmStatus,
                "" => FmmuUsage::Unused,
                _ => {
                    // ETG.2000's order: FMMU 0 outputs, 1 inputs, 2 the mailbox state.
                    let (usage, read_as) = match fmmus.len() {
                        0 => (FmmuUsage::Outputs, "Outputs, as FMMU 0 is"),
                        1 => (FmmuUsage::Inputs, "Inputs, as FMMU 1 is"),
                        2 => (FmmuUsage::SmStatus, "MBoxState, as FMMU 2 is"),
                        _ => (FmmuUsage::Unused, "unused"),
                    };
                    self.warn(self.invalid(
                        self.text_pos(f),
                        format!(
                            "{s} has usage {text:?}: expected Outputs, Inputs or MBoxState \
                         (read as {read_as})"
                        ),
                    ));
                    usage
                }
            };
            fmmus.push(Fmmu {
                usage,
                sm: self.soft(self.attr_num(f, "Sm", &s)).flatten(),
                op_only: self.soft_flag(f, "OpOnly", &s),
            });
        }
        fmmus
    }

    /// The device's `<Sm>`s, numbered in order ([`Self::sm_kind`] reads each one's type).
    fn sync_managers(&self, n: Node<'a, 'input>, scope: &str) -> R<Vec<SyncManager>> {
        let mut sync_managers = Vec::new();
        for (i, sm) in children(n, "Sm").enumerate() {
            let index = u8::try_from(i).map_err(|_| {
                self.invalid(
                    self.node_pos(sm),
                    format!("{scope} has more than 256 <Sm>s"),
                )
            })?;
            let s = format!("<Sm> {i} in {scope}");
            let kind = self.sm_kind(sm, &s)?;
            let start_address = self
                .attr_num::<u16>(sm, "StartAddress", &s)?
                .ok_or_else(|| self.missing(sm, format!("{s} has no StartAddress attribute")))?;
            sync_managers.push(SyncManager {
                position: self.node_pos(sm),
                index,
                kind,
                start_address,
                default_size: self.attr_num(sm, "DefaultSize", &s)?,
                min_size: self.attr_num(sm, "MinSize", &s)?,
                max_size: self.attr_num(sm, "MaxSize", &s)?,
                control_byte: self
                    .attr_num(sm, "ControlByte", &s)?
                    .ok_or_else(|| self.missing(sm, format!("{s} has no ControlByte attribute")))?,
                enable: self.attr_num::<u8>(sm, "Enable", &s)?.unwrap_or(0) != 0,
                virtual_: self.soft_flag(sm, "Virtual", &s),
                op_only: self.soft_flag(sm, "OpOnly", &s),
            });
        }
        Ok(sync_managers)
    }

    /// An `<Sm>`'s type (`s` names it): one of ETG.2000's, else what its ControlByte says,
    /// noted; without one, the file is wrong.
    fn sm_kind(&self, sm: Node<'a, 'input>, s: &str) -> R<SmKind> {
        let text = text_of(sm);
        Ok(match text.to_ascii_lowercase().as_str() {
            "mboxout" | "mbxout" => SmKind::MBoxOut,
            "mboxin" | "mbxin" => SmKind::MBoxIn,
            "outputs" => SmKind::Outputs,
            "inputs" => SmKind::Inputs,
            "" => SmKind::Unused,
            _ => {
                // What the ESC does with it is in its control byte (ETG.1000-4: bits
                // 0-1 mailbox or buffered, bits 2-3 the master reads or writes).
                let Some(cb) = self
                    .soft(self.attr_num::<u8>(sm, "ControlByte", s))
                    .flatten()
                else {
                    return Err(self.invalid(
                        self.text_pos(sm),
                        format!(
                            "{s} has type {text:?}: expected MBoxOut, MBoxIn, Outputs or \
                         Inputs"
                        ),
                    ));
                };
                let kind = match (cb & 0x03 == 0x02, cb & 0x0C == 0x04) {
                    (true, true) => SmKind::MBoxOut,
                    (true, false) => SmKind::MBoxIn,
                    (false, true) => SmKind::Outputs,
                    (false, false) => SmKind::Inputs,
                };
                self.warn(self.invalid(
                    self.text_pos(sm),
                    format!(
                        "{s} has type {text:?}: expected MBoxOut, MBoxIn, Outputs or \
                     Inputs (read as {}, as its ControlByte 0x{cb:02X} says)",
                        kind.name()
                    ),
                ));
                kind
            }
        })
    }

    /// A process-data SM whose type contradicts both its ControlByte's direction and the PDOs
    /// assigned to it (an SMC EX250 file labels its input SM `Outputs`, with ControlByte 0x00,
    /// the master reads, and its TxPDO on it): the ESC does what the control byte says and the
    /// device sends what the PDOs say, so it is read as the other direction, noted.
    fn sm_directions(&self, sms: &mut [SyncManager], rx: &[EsiPdo], tx: &[EsiPdo], scope: &str) {
        for sm in sms.iter_mut() {
            if sm.control_byte & 0x03 != 0x00 {
                continue;
            }
            let master_writes = sm.control_byte & 0x0C == 0x04;
            let on = |pdos: &[EsiPdo]| pdos.iter().any(|p| p.sm == Some(sm.index));
            let other = match sm.kind {
                SmKind::Outputs if !master_writes && on(tx) && !on(rx) => SmKind::Inputs,
                SmKind::Inputs if master_writes && on(rx) && !on(tx) => SmKind::Outputs,
                _ => continue,
            };
            self.warn(self.invalid(
                sm.position,
                format!(
                    "<Sm> {} in {scope} has type {}, but its ControlByte 0x{:02X} and the PDOs \
                     assigned to it say {} (read as {})",
                    sm.index,
                    sm.kind.name(),
                    sm.control_byte,
                    other.name(),
                    other.name()
                ),
            ));
            sm.kind = other;
        }
    }

    /// A PDO entry naming sub-index n > 0 of an object the file's dictionary describes as a
    /// simple variable (sub-index 0 only) maps that variable: read as sub-index 0, noted (one
    /// vendor file maps `0x607A:04`, while its own 0x1600 defaults map `0x607A:00`).
    fn var_entries(&self, p: &mut EsiPdo, dict: &Dictionary) {
        for e in p.entries.iter_mut().filter(|e| e.sub != 0 && e.index != 0) {
            let Some(o) = dict.object(e.index) else {
                continue;
            };
            let var = dict
                .data_type(&o.type_name)
                .is_none_or(|t| t.sub_items.is_empty() && t.array.is_none());
            if var {
                self.warn(self.invalid(
                    e.position,
                    format!(
                        "<Entry> in PDO 0x{:04X} maps 0x{:04X}:{:02X}, but the dictionary's \
                         0x{:04X} {:?} has sub-index 0 only (read as 0x{:04X}:00)",
                        p.index, e.index, e.sub, e.index, o.name, e.index
                    ),
                ));
                e.sub = 0;
            }
        }
    }

    fn pdo(&self, n: Node, tag: &str) -> R<EsiPdo> {
        let idx_el =
            child(n, "Index").ok_or_else(|| self.missing(n, format!("<{tag}> has no <Index>")))?;
        let index: u16 = self.num_text(idx_el, "Index", &format!("<{tag}>"))?;
        let scope = format!("<{tag}> 0x{index:04X}");
        let names = self.names(n, "Name", &scope)?;
        let excludes = children(n, "Exclude")
            .map(|e| self.num_text::<u16>(e, "Exclude", &scope))
            .collect::<R<Vec<_>>>()?;
        let mut entries = Vec::new();
        for e in children(n, "Entry") {
            let s = format!("<Entry> in {scope}");
            let index: u16 = self.req_num_child(e, "Index", &s)?;
            let names = self.names(e, "Name", &s)?;
            entries.push(EsiPdoEntry {
                position: self.node_pos(e),
                index,
                sub: self.num_child(e, "SubIndex", &s)?.unwrap_or(0),
                bit_len: self.req_num_child(e, "BitLen", &s)?,
                name: preferred_text(&names).to_string(),
                data_type_name: child(e, "DataType").map(text_of),
            });
        }
        Ok(EsiPdo {
            position: self.node_pos(n),
            index,
            name: preferred_text(&names).to_string(),
            sm: self.attr_num(n, "Sm", &scope)?,
            fixed: self.soft_flag(n, "Fixed", &scope),
            mandatory: self.soft_flag(n, "Mandatory", &scope),
            virtual_: self.soft_flag(n, "Virtual", &scope),
            excludes,
            entries,
        })
    }

    fn mailbox(&self, n: Node, dev: &str) -> R<Mailbox> {
        let scope = format!("<Mailbox> in {dev}");
        let mut protocols = MailboxProtocols::empty();
        for (tag, bit) in [
            ("AoE", MailboxProtocols::AOE),
            ("EoE", MailboxProtocols::EOE),
            ("CoE", MailboxProtocols::COE),
            ("FoE", MailboxProtocols::FOE),
            ("SoE", MailboxProtocols::SOE),
            ("VoE", MailboxProtocols::VOE),
        ] {
            if children(n, tag).next().is_some() {
                protocols |= bit;
            }
        }
        let mut coe = None;
        let mut init_cmds = Vec::new();
        if let Some(c) = child(n, "CoE") {
            let s = format!("<CoE> in {dev}");
            coe = Some(CoeDetails {
                sdo_info: self.soft_flag(c, "SdoInfo", &s),
                pdo_assign: self.soft_flag(c, "PdoAssign", &s),
                pdo_config: self.soft_flag(c, "PdoConfig", &s),
                pdo_upload: self.soft_flag(c, "PdoUpload", &s),
                complete_access: self.soft_flag(c, "CompleteAccess", &s),
                segmented_sdo: self
                    .soft(self.attr_bool(c, "SegmentedSdo", &s))
                    .flatten()
                    .unwrap_or(true),
                diag_history: self.soft_flag(c, "DiagHistory", &s),
                eds_file: c.attribute("EdsFile").map(str::to_string),
            });
            for ic in children(c, "InitCmd") {
                let s = format!("<InitCmd> in <CoE> of {dev}");
                let mut transitions = Vec::new();
                for t in children(ic, "Transition") {
                    let text = text_of(t);
                    transitions.push(Transition::parse(&text).ok_or_else(|| {
                        self.invalid(
                            self.text_pos(t),
                            format!(
                                "{s} has Transition {text:?}: expected IP, PS, SO, SP, OS, OP, \
                                 PI, SI, OI, IB, BI or II"
                            ),
                        )
                    })?);
                }
                if transitions.is_empty() {
                    return Err(self.missing(ic, format!("{s} has no <Transition>")));
                }
                let index: u16 = self.req_num_child(ic, "Index", &s)?;
                let s = format!("<InitCmd> 0x{index:04X} in <CoE> of {dev}");
                init_cmds.push(InitCmd {
                    position: self.node_pos(ic),
                    transitions,
                    index,
                    sub: self.num_child(ic, "SubIndex", &s)?.unwrap_or(0),
                    data: self
                        .hex_child(ic, "Data", &s)?
                        .ok_or_else(|| self.missing(ic, format!("{s} has no <Data>")))?,
                    comment: child(ic, "Comment").map(text_of).unwrap_or_default(),
                    complete_access: self.flag(ic, "CompleteAccess", &s)?,
                    fixed: self.flag(ic, "Fixed", &s)?,
                    timeout_ms: self.num_child::<u32>(ic, "Timeout", &s)?.filter(|t| *t > 0),
                    retries: self.num_child(ic, "Retries", &s)?.unwrap_or(0),
                    disabled: self.bool_child(ic, "Disabled", &s)?.unwrap_or(false),
                });
            }
        }
        Ok(Mailbox {
            protocols,
            data_link_layer: self.soft_flag(n, "DataLinkLayer", &scope),
            coe,
            init_cmds,
        })
    }

    fn op_mode(&self, n: Node, dev: &str) -> R<OpMode> {
        let name_el = self.req_child(n, "Name", &format!("<OpMode> in {dev}"))?;
        let name = text_of(name_el);
        let scope = format!("<OpMode> {name:?} in {dev}");
        let assign_activate = self.req_num_child::<u16>(n, "AssignActivate", &scope)?;
        let (c0, s0, c1) = (
            child(n, "CycleTimeSync0"),
            child(n, "ShiftTimeSync0"),
            child(n, "CycleTimeSync1"),
        );
        // The SII carries the cycle factors as INT16: a larger one is refused here, by name.
        let factor = |el: Option<Node>| -> R<i16> {
            el.map(|e| self.attr_num::<i16>(e, "Factor", &scope))
                .transpose()
                .map(|f| f.flatten().unwrap_or_default())
        };
        let cycle = |el: Option<Node>, tag: &str| -> R<u32> {
            el.map(|e| self.num_text::<u32>(e, tag, &scope))
                .transpose()
                .map(Option::unwrap_or_default)
        };
        let shift = |el: Option<Node>, tag: &str| -> R<i32> {
            el.map(|e| self.num_text::<i32>(e, tag, &scope))
                .transpose()
                .map(Option::unwrap_or_default)
        };
        let mut sms = Vec::new();
        for sm in children(n, "Sm") {
            let no = self
                .attr_num::<u8>(sm, "No", &scope)?
                .ok_or_else(|| self.missing(sm, format!("<Sm> in {scope} has no No attribute")))?;
            let s = format!("<Sm> {no} in {scope}");
            sms.push(DcSm {
                no,
                sync_type: self.num_child(sm, "SyncType", &s)?,
                cycle_time: self.num_child(sm, "CycleTime", &s)?,
                shift_time: self.num_child(sm, "ShiftTime", &s)?,
                pdos: children(sm, "Pdo")
                    .map(|p| self.num_text::<u16>(p, "Pdo", &s))
                    .collect::<R<Vec<_>>>()?,
            });
        }
        Ok(OpMode {
            position: self.node_pos(n),
            mode: DcOpMode {
                description: child(n, "Desc").map(text_of).unwrap_or_default(),
                assign_activate,
                cycle_time0: cycle(c0, "CycleTimeSync0")?,
                sync0_cycle_factor: factor(c0)?,
                shift_time0: shift(s0, "ShiftTimeSync0")?,
                shift_time1: shift(child(n, "ShiftTimeSync1"), "ShiftTimeSync1")?,
                sync1_cycle_factor: factor(c1)?,
                name,
            },
            shift_time_sync0_factor: s0
                .map(|e| self.attr_num::<i32>(e, "Factor", &scope))
                .transpose()?
                .flatten(),
            shift_time_sync0_input: match s0 {
                Some(e) => self.flag(e, "Input", &scope)?,
                None => false,
            },
            cycle_time_sync1: cycle(c1, "CycleTimeSync1")?,
            sms,
            allowed_cycle_times: self.cycle_times(n, &scope)?,
        })
    }

    /// This project's extension: `<VendorSpecific><ecdrive:CycleTimes>` with
    /// `<ecdrive:CycleTime>` values or one `<ecdrive:CycleTimeRange Min= Max= Step=/>`.
    fn cycle_times(&self, n: Node, scope: &str) -> R<Option<CycleTimes>> {
        let ours = |c: &Node| {
            c.is_element()
                && c.tag_name().namespace() == Some(ECDRIVE_NAMESPACE)
                && c.tag_name().name() == "CycleTimes"
        };
        let Some(ct) = children(n, "VendorSpecific")
            .flat_map(|v| v.children())
            .find(ours)
        else {
            return Ok(None);
        };
        let s = format!("<ecdrive:CycleTimes> in {scope}");
        let mut list = Vec::new();
        for c in ct.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "CycleTime" => list.push(self.num_text::<u32>(c, "CycleTime", &s)?),
                "CycleTimeRange" => {
                    let req = |a: &'static str| -> R<u32> {
                        self.attr_num::<u32>(c, a, &s)?.ok_or_else(|| {
                            self.missing(c, format!("<CycleTimeRange> in {s} has no {a}"))
                        })
                    };
                    let (min, max) = (req("Min")?, req("Max")?);
                    if min > max {
                        return Err(self.invalid(
                            self.node_pos(c),
                            format!("<CycleTimeRange> in {s} has Min {min} > Max {max}"),
                        ));
                    }
                    return Ok(Some(CycleTimes::Range {
                        min,
                        max,
                        step: self.attr_num::<u32>(c, "Step", &s)?.unwrap_or(0),
                    }));
                }
                _ => {}
            }
        }
        if list.is_empty() {
            return Err(self.missing(ct, format!("{s} lists no cycle time")));
        }
        Ok(Some(CycleTimes::List(list)))
    }

    fn eeprom(&self, n: Node, dev: &str) -> R<Eeprom> {
        let scope = format!("<Eeprom> in {dev}");
        let mut categories = Vec::new();
        for c in children(n, "Category") {
            let s = format!("<Category> in {scope}");
            categories.push(EepromCategory {
                cat_no: self.req_num_child(c, "CatNo", &s)?,
                data: self.hex_child(c, "Data", &s)?.unwrap_or_default(),
            });
        }
        Ok(Eeprom {
            byte_size: self.num_child(n, "ByteSize", &scope)?,
            config_data: self.hex_child(n, "ConfigData", &scope)?.unwrap_or_default(),
            boot_strap: self.hex_child(n, "BootStrap", &scope)?.unwrap_or_default(),
            data: self.hex_child(n, "Data", &scope)?.unwrap_or_default(),
            categories,
        })
    }

    fn profile(&self, n: Node, dev: &str) -> Profile {
        let scope = format!("<Profile> in {dev}");
        // ETG.2000 places ProfileNo in <Profile> and, in newer files, in <ChannelInfo>.
        let info = child(n, "ChannelInfo");
        let num = |name: &'static str| {
            self.soft(self.num_child(n, name, &scope))
                .flatten()
                .or_else(|| info.and_then(|i| self.soft(self.num_child(i, name, &scope)).flatten()))
        };
        Profile {
            profile_no: num("ProfileNo"),
            add_info: num("AddInfo"),
            channel: self.soft(self.attr_num(n, "Channel", &scope)).flatten(),
            dictionary: child(n, "Dictionary").map(|d| self.dictionary(d, dev)),
        }
    }

    fn dictionary(&self, n: Node, dev: &str) -> Dictionary {
        let mut data_types = Vec::new();
        if let Some(dts) = child(n, "DataTypes") {
            for dt in children(dts, "DataType") {
                if let Some(t) = self.soft(self.data_type(dt, dev)) {
                    data_types.push(t);
                }
            }
        }
        let mut objects = Vec::new();
        if let Some(objs) = child(n, "Objects") {
            for o in children(objs, "Object") {
                if let Some(o) = self.soft(self.object(o, dev)) {
                    objects.push(o);
                }
            }
        }
        Dictionary {
            data_types,
            objects,
        }
    }

    /// One `<DataType>`; one that does not read is left out, noted.
    fn data_type(&self, dt: Node, dev: &str) -> R<EsiDataType> {
        let name = text_of(self.req_child(dt, "Name", &format!("<DataType> in {dev}"))?);
        let scope = format!("<DataType> {name:?}");
        let array = match child(dt, "ArrayInfo") {
            None => None,
            Some(a) => {
                let s = format!("<ArrayInfo> of {scope}");
                Some(ArrayInfo {
                    lbound: self.req_num_child(a, "LBound", &s)?,
                    elements: self.req_num_child(a, "Elements", &s)?,
                })
            }
        };
        let mut sub_items = Vec::new();
        for si in children(dt, "SubItem") {
            let s = format!("<SubItem> of {scope}");
            sub_items.push(EsiSubItem {
                sub_idx: self.num_child(si, "SubIdx", &s)?,
                name: child(si, "Name").map(text_of).unwrap_or_default(),
                type_name: text_of(self.req_child(si, "Type", &s)?),
                bit_size: self.req_num_child(si, "BitSize", &s)?,
                bit_offs: self.num_child(si, "BitOffs", &s)?.unwrap_or(0),
                flags: child(si, "Flags").map(|f| self.flags(f, &s)),
            });
        }
        Ok(EsiDataType {
            position: self.node_pos(dt),
            base_type: child(dt, "BaseType").map(text_of),
            bit_size: self.req_num_child(dt, "BitSize", &scope)?,
            array,
            sub_items,
            name,
        })
    }

    /// One `<Object>`; one whose index, type or size does not read is left out, noted.
    fn object(&self, o: Node, dev: &str) -> R<EsiObject> {
        let index: u16 = self.req_num_child(o, "Index", &format!("<Object> in {dev}"))?;
        let scope = format!("<Object> 0x{index:04X}");
        let names = self.names(o, "Name", &scope)?;
        Ok(EsiObject {
            position: self.node_pos(o),
            index,
            name: preferred_text(&names).to_string(),
            type_name: text_of(self.req_child(o, "Type", &scope)?),
            bit_size: self.num_child(o, "BitSize", &scope)?.unwrap_or(0),
            info: match child(o, "Info") {
                Some(i) => self.info(i, &scope),
                None => ObjectInfo::default(),
            },
            flags: child(o, "Flags").map(|f| self.flags(f, &scope)),
        })
    }

    fn info(&self, n: Node, scope: &str) -> ObjectInfo {
        // Data that is not hex is noted and left out (the object keeps its other values).
        let value = |data: &'static str, value: &'static str| -> Option<EsiValue> {
            if let Some(d) = self.soft(self.hex_child(n, data, scope)).flatten() {
                return Some(EsiValue::Data(d));
            }
            child(n, value).map(|v| EsiValue::Value(text_of(v)))
        };
        let default = match value("DefaultData", "DefaultValue") {
            Some(v) => Some(v),
            None => child(n, "DefaultString").map(|s| EsiValue::String(text_of(s))),
        };
        let mut sub_items = Vec::new();
        for si in children(n, "SubItem") {
            let name = child(si, "Name").map(text_of).unwrap_or_default();
            let s = format!("<SubItem> {name:?} of {scope}");
            let info = match child(si, "Info") {
                Some(i) => self.info(i, &s),
                None => ObjectInfo::default(),
            };
            sub_items.push((name, info));
        }
        ObjectInfo {
            default,
            min: value("MinData", "MinValue"),
            max: value("MaxData", "MaxValue"),
            unit: child(n, "Unit").map(text_of).filter(|u| !u.is_empty()),
            sub_items,
        }
    }

    /// `<Flags>`: a value that is not one of the schema's is noted and read as absent.
    fn flags(&self, n: Node, scope: &str) -> Flags {
        let s = format!("<Flags> of {scope}");
        let mut flags = Flags::default();
        if let Some(a) = child(n, "Access") {
            flags.access = self.soft(self.access(a, &s));
        }
        if let Some(p) = child(n, "PdoMapping") {
            let text = text_of(p);
            flags.pdo_mapping = match text.to_ascii_uppercase().as_str() {
                "R" => EntryAccess::RXPDO,
                "T" => EntryAccess::TXPDO,
                "RT" | "TR" => EntryAccess::RXPDO | EntryAccess::TXPDO,
                "" => EntryAccess::empty(),
                _ => {
                    self.warn(self.invalid(
                        self.text_pos(p),
                        format!("{s} has PdoMapping {text:?}: expected R, T or RT"),
                    ));
                    EntryAccess::empty()
                }
            };
        }
        if let Some(c) = child(n, "Category") {
            let text = text_of(c);
            flags.category = match text.as_str() {
                "m" | "M" => Some(Category::Mandatory),
                "o" | "O" => Some(Category::Optional),
                "c" | "C" => Some(Category::Conditional),
                _ => {
                    self.warn(self.invalid(
                        self.text_pos(c),
                        format!("{s} has Category {text:?}: expected m, o or c"),
                    ));
                    None
                }
            };
        }
        let bit = |name: &'static str| {
            self.soft(self.num_child::<u8>(n, name, &s))
                .flatten()
                .unwrap_or(0)
                != 0
        };
        flags.backup = bit("Backup");
        flags.setting = bit("Setting");
        flags
    }

    /// `<Access>` with its restrictions.
    fn access(&self, a: Node, s: &str) -> R<EntryAccess> {
        let text = text_of(a);
        let (read, write) = match text.to_ascii_lowercase().as_str() {
            "ro" => (true, false),
            "rw" => (true, true),
            "wo" => (false, true),
            _ => {
                return Err(self.invalid(
                    self.text_pos(a),
                    format!("{s} has Access {text:?}: expected ro, rw or wo"),
                ));
            }
        };
        let states = |attr: &'static str| -> R<(bool, bool, bool)> {
            let Some(at) = a.attributes().find(|x| x.name() == attr) else {
                return Ok((true, true, true));
            };
            let v = at.value().trim().to_ascii_lowercase();
            let set = match v.as_str() {
                "preop" => (true, false, false),
                "safeop" => (false, true, false),
                "op" => (false, false, true),
                "preop_safeop" => (true, true, false),
                "preop_op" => (true, false, true),
                "safeop_op" => (false, true, true),
                _ => {
                    return Err(self.invalid(
                        self.pos(at.range_value().start),
                        format!(
                            "{s} has {attr}=\"{}\": expected PreOP, SafeOP, OP, \
                                 PreOP_SafeOP, PreOP_OP or SafeOP_OP",
                            at.value()
                        ),
                    ));
                }
            };
            Ok(set)
        };
        let (rp, rs, ro) = states("ReadRestrictions")?;
        let (wp, ws, wo) = states("WriteRestrictions")?;
        let mut acc = EntryAccess::empty();
        acc.set(EntryAccess::READ_PREOP, read && rp);
        acc.set(EntryAccess::READ_SAFEOP, read && rs);
        acc.set(EntryAccess::READ_OP, read && ro);
        acc.set(EntryAccess::WRITE_PREOP, write && wp);
        acc.set(EntryAccess::WRITE_SAFEOP, write && ws);
        acc.set(EntryAccess::WRITE_OP, write && wo);
        Ok(acc)
    }
}
