//! Consistency checks of a parsed ESI file: things that parse but contradict each other.

use super::dictionary::ResolvedObject;
use super::error::Position;
use super::model::{Device, EsiFile, EsiPdo, FmmuUsage, SmKind};
use crate::od::{DataType, EntryAccess, Value};
use crate::pdo::Direction;
use core::fmt;

/// One problem found by [`EsiFile::check`] / [`Device::check`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckIssue {
    /// Where the offending element starts.
    pub position: Position,
    /// What is wrong.
    pub message: String,
    /// Whether it stops a device from being used.
    pub severity: Severity,
}

/// How much a [`CheckIssue`] matters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// The device cannot be used: it could not be read.
    Error,
    /// Read past: a value left out or taken by a tolerance rule, or a contradiction between
    /// parts of the file. What a run depends on is checked again where it is used.
    Warning,
}

impl fmt::Display for CheckIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.position, self.message)
    }
}

impl EsiFile {
    /// Check every device ([`Device::check`]), plus: the device's `<GroupType>` names a
    /// group of the file, and 0x1018 defaults in the dictionary match the vendor ID, product
    /// code and revision.
    pub fn check(&self) -> Vec<CheckIssue> {
        let mut out: Vec<CheckIssue> = self
            .unreadable
            .iter()
            .map(|u| CheckIssue {
                position: u.error.position,
                message: format!(
                    "device {:?} cannot be used: {}",
                    if u.name.is_empty() {
                        &u.type_text
                    } else {
                        &u.name
                    },
                    u.error.message
                ),
                severity: Severity::Error,
            })
            .chain(self.warnings.iter().map(|w| CheckIssue {
                position: w.position,
                message: w.message.clone(),
                severity: Severity::Warning,
            }))
            .collect();
        for d in &self.devices {
            let issue = |msg: String| CheckIssue {
                position: d.position,
                message: format!("device {:?}: {msg}", d.name),
                severity: Severity::Warning,
            };
            if let Some(g) = &d.group_type {
                if self.group(g).is_none() {
                    out.push(issue(format!("<GroupType> {g:?} names no <Group>")));
                }
            }
            if let Some(Ok(id)) = d.dictionary().and_then(|dict| dict.resolve(0x1018)) {
                let mut ident = |sub: u8, want: Option<u32>, what: &str| {
                    let got = id.entry(sub).and_then(|e| e.default.as_ref());
                    if let (Some(got), Some(want)) = (got.and_then(Value::as_i128), want) {
                        if got != i128::from(want) {
                            out.push(issue(format!(
                                "0x1018:{sub:02X} default {got:#010X} differs from the {what} \
                                 {want:#010X}"
                            )));
                        }
                    }
                };
                ident(1, Some(self.vendor.id), "vendor <Id>");
                ident(2, Some(d.type_.product_code), "ProductCode");
                ident(3, d.type_.revision_no, "RevisionNo");
            }
            out.extend(d.check());
        }
        out
    }
}

impl Device {
    /// Check the device description for contradictions a configuration tool or master would
    /// trip over: duplicate or unknown PDOs, default PDOs that exclude each other, PDOs
    /// assigned to a SyncManager of the wrong kind, entry sizes, missing FMMUs or mailbox
    /// SyncManagers, SyncManager default sizes that differ from the default mapping, duplicate
    /// DC mode names, and — when the device has a dictionary — objects that cannot be
    /// resolved, PDO entries that are not in the dictionary, of another size or not mappable,
    /// and mapping/assignment defaults (0x16xx, 0x1Axx, 0x1C12, 0x1C13) that differ from the
    /// PDO descriptions.
    pub fn check(&self) -> Vec<CheckIssue> {
        let mut out = Vec::new();
        let dev = &self.name;
        let mut issue = |position: Position, msg: String| {
            out.push(CheckIssue {
                position,
                message: format!("device {dev:?}: {msg}"),
                severity: Severity::Warning,
            });
        };
        let resolved = self.resolved_objects(&mut issue);
        for dir in [Direction::Rx, Direction::Tx] {
            let pdos = self.pdos(dir);
            for (i, p) in pdos.iter().enumerate() {
                self.check_pdo(dir, i, p, &resolved, &mut issue);
            }
            if let Some(o) = resolved.iter().find(|o| o.index == dir.assign_index()) {
                self.check_assignment_defaults(dir, o, &mut issue);
            }
            self.check_process_data_sm(dir, &mut issue);
        }
        if self.mailbox.is_some() {
            for k in [SmKind::MBoxOut, SmKind::MBoxIn] {
                if self.sync_manager(k).is_none() {
                    issue(
                        self.position,
                        format!("the device has a <Mailbox> but no <Sm>{}</Sm>", k.name()),
                    );
                }
            }
        }
        for (i, m) in self.dc.iter().enumerate() {
            if self
                .dc
                .get(..i)
                .unwrap_or_default()
                .iter()
                .any(|x| x.mode.name == m.mode.name)
            {
                issue(
                    m.position,
                    format!("DC <OpMode> {:?} is described twice", m.mode.name),
                );
            }
        }
        out
    }

    /// The dictionary's objects resolved (what cannot be resolved, and each object's problems,
    /// said).
    fn resolved_objects(&self, issue: &mut dyn FnMut(Position, String)) -> Vec<ResolvedObject> {
        let Some(dict) = self.dictionary() else {
            return Vec::new();
        };
        dict.objects
            .iter()
            .filter_map(|o| match dict.resolve_object(o) {
                Ok(r) => {
                    for p in &r.problems {
                        issue(p.position, p.message.clone());
                    }
                    Some(r)
                }
                Err(e) => {
                    issue(e.position, e.message);
                    None
                }
            })
            .collect()
    }

    /// PDO `p`, the `i`-th of its direction: described once, excluding only PDOs that are
    /// described and not assigned by default with it, assigned to a SyncManager of its kind,
    /// its entries ([`Device::check_entries`]) and its mapping object's defaults.
    fn check_pdo(
        &self,
        dir: Direction,
        i: usize,
        p: &EsiPdo,
        resolved: &[ResolvedObject],
        issue: &mut dyn FnMut(Position, String),
    ) {
        let d = dir.name();
        let pdos = self.pdos(dir);
        let want_sm = process_data_sm(dir);
        if pdos
            .get(..i)
            .unwrap_or_default()
            .iter()
            .any(|q| q.index == p.index)
        {
            issue(
                p.position,
                format!("{d} 0x{:04X} is described twice", p.index),
            );
        }
        for x in &p.excludes {
            let known =
                self.pdo(Direction::Rx, *x).is_some() || self.pdo(Direction::Tx, *x).is_some();
            if !known {
                issue(
                    p.position,
                    format!(
                        "{d} 0x{:04X} excludes 0x{x:04X}, which is not described",
                        p.index
                    ),
                );
            }
            if p.is_default() && pdos.iter().any(|q| q.index == *x && q.is_default()) {
                issue(
                    p.position,
                    format!(
                        "{d} 0x{:04X} and 0x{x:04X} are both assigned by default but exclude \
                         each other",
                        p.index
                    ),
                );
            }
        }
        if let Some(sm) = p.sm {
            match self.sync_managers.get(usize::from(sm)) {
                Some(s) if s.kind == want_sm => {}
                Some(s) => issue(
                    p.position,
                    format!(
                        "{d} 0x{:04X} is assigned to SM{sm}, which is {:?}, not {:?}",
                        p.index, s.kind, want_sm
                    ),
                ),
                None => issue(
                    p.position,
                    format!(
                        "{d} 0x{:04X} is assigned to SM{sm}, which does not exist",
                        p.index
                    ),
                ),
            }
        }
        self.check_entries(dir, p, resolved, issue);
        if let Some(o) = resolved.iter().find(|o| o.index == p.index) {
            check_mapping_defaults(d, p, o, issue);
        }
    }

    /// The default assignment against the defaults of 0x1C12 / 0x1C13 (`o`).
    fn check_assignment_defaults(
        &self,
        dir: Direction,
        o: &ResolvedObject,
        issue: &mut dyn FnMut(Position, String),
    ) {
        let d = dir.name();
        let defaults: Vec<u16> = self
            .pdos(dir)
            .iter()
            .filter(|p| p.is_default())
            .map(|p| p.index)
            .collect();
        let pos = self
            .dictionary()
            .and_then(|dd| dd.object(o.index))
            .map(|x| x.position)
            .unwrap_or(self.position);
        if let Some(n) = default_int(o, 0) {
            if n != defaults.len() as i128 {
                issue(
                    pos,
                    format!(
                        "0x{:04X}:00 default {n} differs from the {} {d}s assigned by default",
                        o.index,
                        defaults.len()
                    ),
                );
            }
        }
        for (i, want) in defaults.iter().enumerate() {
            let sub = (i + 1).min(255) as u8;
            if let Some(v) = default_int(o, sub) {
                if v != i128::from(*want) {
                    issue(
                        pos,
                        format!(
                            "0x{:04X}:{sub:02X} default {v:#06X} differs from the \
                             default-assigned {d} 0x{want:04X}",
                            o.index
                        ),
                    );
                }
            }
        }
    }

    /// The direction's process-data SyncManager: there when the device has PDOs of it, its
    /// default size that of the default PDOs, and an FMMU for it.
    fn check_process_data_sm(&self, dir: Direction, issue: &mut dyn FnMut(Position, String)) {
        let d = dir.name();
        let pdos = self.pdos(dir);
        let want_sm = process_data_sm(dir);
        let Some(sm) = self.sync_manager(want_sm) else {
            if !pdos.is_empty() {
                issue(
                    self.position,
                    format!("the device has {d}s but no <Sm>{}</Sm>", want_sm.name()),
                );
            }
            return;
        };
        let bits: u32 = pdos
            .iter()
            .filter(|p| p.is_default())
            .map(EsiPdo::bits)
            .sum();
        let bytes = bits.div_ceil(8);
        if let Some(size) = sm.default_size {
            if u32::from(size) != bytes {
                issue(
                    sm.position,
                    format!(
                        "SM{} DefaultSize {size} differs from the {bytes} bytes of the default \
                         {d}s",
                        sm.index
                    ),
                );
            }
        }
        let fmmu = match dir {
            Direction::Rx => FmmuUsage::Outputs,
            Direction::Tx => FmmuUsage::Inputs,
        };
        if !pdos.is_empty() && !self.fmmus.iter().any(|f| f.usage == fmmu) {
            issue(
                sm.position,
                format!("the device has {d}s but no <Fmmu>{}</Fmmu>", fmmu.name()),
            );
        }
    }

    fn check_entries(
        &self,
        dir: Direction,
        p: &EsiPdo,
        resolved: &[ResolvedObject],
        issue: &mut dyn FnMut(Position, String),
    ) {
        let object = |index: u16| resolved.iter().find(|o| o.index == index);
        let d = dir.name();
        let has_dict = self.dictionary().is_some();
        for e in &p.entries {
            let at = format!(
                "{d} 0x{:04X} entry 0x{:04X}:{:02X}",
                p.index, e.index, e.sub
            );
            if e.bit_len == 0 || e.bit_len > 255 {
                issue(
                    e.position,
                    format!("{at} has BitLen {} (1..=255 allowed)", e.bit_len),
                );
            }
            if let Some(dt) = e.data_type() {
                if let Some(bits) = dt.bit_len() {
                    // BOOL is 1 bit in PDOs.
                    let bits = if dt == DataType::Boolean { 1 } else { bits };
                    if bits != e.bit_len {
                        issue(
                            e.position,
                            format!(
                                "{at} has BitLen {} but DataType {dt} is {bits} bits",
                                e.bit_len
                            ),
                        );
                    }
                }
            }
            if e.is_padding() || !has_dict {
                continue;
            }
            let Some(entry) = object(e.index).and_then(|o| o.entry(e.sub)) else {
                issue(e.position, format!("{at} is not in the object dictionary"));
                continue;
            };
            if entry.bit_len != u32::from(e.bit_len) {
                issue(
                    e.position,
                    format!(
                        "{at} has BitLen {} but the dictionary says {}",
                        e.bit_len, entry.bit_len
                    ),
                );
            }
            let flag = match dir {
                Direction::Rx => EntryAccess::RXPDO,
                Direction::Tx => EntryAccess::TXPDO,
            };
            if !entry.access.contains(flag) {
                issue(
                    e.position,
                    format!("{at}: the dictionary does not mark it mappable as {d}"),
                );
            }
        }
    }
}

fn default_int(o: &ResolvedObject, sub: u8) -> Option<i128> {
    o.entry(sub)?.default.as_ref()?.as_i128()
}

/// The defaults of a mapping object (sub 0 = count, subs 1.. = entries) against the PDO.
fn check_mapping_defaults(
    d: &str,
    p: &EsiPdo,
    o: &ResolvedObject,
    issue: &mut dyn FnMut(Position, String),
) {
    if let Some(n) = default_int(o, 0) {
        if n != p.entries.len() as i128 {
            issue(
                p.position,
                format!(
                    "{d} 0x{:04X} lists {} entries but 0x{:04X}:00 defaults to {n}",
                    p.index,
                    p.entries.len(),
                    o.index
                ),
            );
        }
    }
    for (i, e) in p.entries.iter().enumerate() {
        let Ok(sub) = u8::try_from(i + 1) else { break };
        let want = u32::from(e.index) << 16 | u32::from(e.sub) << 8 | u32::from(e.bit_len & 0xFF);
        if let Some(v) = default_int(o, sub) {
            if v != i128::from(want) {
                issue(
                    e.position,
                    format!(
                        "{d} 0x{:04X} entry {sub} is {want:#010X} but 0x{:04X}:{sub:02X} defaults \
                         to {v:#010X}",
                        p.index, o.index
                    ),
                );
            }
        }
    }
}

/// The SyncManager kind a direction's PDOs go to: RxPDOs to the outputs, TxPDOs to the inputs.
fn process_data_sm(dir: Direction) -> SmKind {
    match dir {
        Direction::Rx => SmKind::Outputs,
        Direction::Tx => SmKind::Inputs,
    }
}
