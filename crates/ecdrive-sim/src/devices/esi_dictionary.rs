//! The object dictionary an emulated device built from a vendor's ESI file holds: the file's
//! `<Dictionary>` as far as it reads, completed the way the device's firmware is, from the
//! file's PDO descriptions.
//!
//! Vendor files often describe the process data in two places that disagree, or in one only:
//! the `<RxPdo>`/`<TxPdo>` list (which the SII a configuration tool writes is made from, with
//! `Sm=` marking the default assignment, ETG.2000) and the mapping (0x1600–0x17FF,
//! 0x1A00–0x1BFF) and assignment (0x1C12, 0x1C13) objects of the dictionary. Real files seen:
//! no dictionary at all, no assignment objects, assignment defaults of zero or byte-swapped,
//! mapping defaults that list other objects than the PDO. The emulation takes the PDO list as
//! the device's truth (it is what masters read from the SII), so that the SII and the CoE view
//! of the emulated device agree:
//!
//! - every mapping object takes the entries of its PDO as defaults (an object the dictionary
//!   lacks is added; writable in PRE-OP when the file allows PDO configuration and the PDO is
//!   not `Fixed`);
//! - 0x1C12/0x1C13 take the default-assigned PDOs (writable in PRE-OP when the file allows
//!   PDO assignment), with room for every PDO of the direction, also where the file's
//!   dictionary lacks them: a file's `<Dictionary>` is an optional replica of the firmware's,
//!   and CoE slave stacks (SOES, Beckhoff's slave stack code) keep an assignment object for
//!   each process-data SyncManager, which masters read (SOEM, ethercrab, TwinCAT with
//!   `PdoUpload`);
//! - every object a PDO maps exists with that entry, mappable in the PDO's direction (added
//!   with the PDO entry's data type where the dictionary lacks it).

use crate::esi::{Device, EsiPdo};
use crate::od::{ConstValue, DataType, EntryAccess, EntryDesc, ObjectCode, ObjectDesc};
use crate::pdo::Direction;

fn leak(s: String) -> &'static str {
    String::leak(s)
}

use crate::esi::pdo_entry_type as entry_type;

fn mapped_access(dir: Direction) -> EntryAccess {
    match dir {
        Direction::Rx => EntryAccess::RW.union(EntryAccess::RXPDO),
        Direction::Tx => EntryAccess::RO.union(EntryAccess::TXPDO),
    }
}

/// Make sure object `index` has entry `sub` of `bits` bits, mappable in `dir`.
fn ensure_entry(
    objs: &mut Vec<ObjectDesc>,
    index: u16,
    sub: u8,
    bits: u16,
    t: DataType,
    dir: Direction,
    name: &str,
) {
    let flag = match dir {
        Direction::Rx => EntryAccess::RXPDO,
        Direction::Tx => EntryAccess::TXPDO,
    };
    let new_entry = EntryDesc {
        sub,
        name: leak(if name.is_empty() {
            format!("Object 0x{index:04X}:{sub:02X}")
        } else {
            name.to_string()
        }),
        data_type: entry_type(Some(t), bits),
        bit_len: bits,
        access: mapped_access(dir),
        default: ConstValue::None,
        min: ConstValue::None,
        max: ConstValue::None,
    };
    match objs.iter_mut().find(|o| o.index == index) {
        None => {
            let (code, entries) = if sub == 0 {
                (ObjectCode::Var, vec![new_entry])
            } else {
                let count =
                    EntryDesc::new(0, "Number of entries", DataType::Unsigned8, EntryAccess::RO)
                        .default(ConstValue::Uint(u64::from(sub)));
                (ObjectCode::Record, vec![count, new_entry])
            };
            objs.push(ObjectDesc {
                index,
                name: new_entry.name,
                code,
                entries: Vec::leak(entries),
            });
        }
        Some(o) => {
            let mut entries = o.entries.to_vec();
            let var_zero = entries
                .iter()
                .find(|e| e.sub == 0)
                .is_some_and(|e| e.data_type != DataType::Unsigned8);
            match entries.iter_mut().find(|e| e.sub == sub) {
                Some(e) if e.access.contains(flag) && e.bit_len == bits => return,
                Some(e) => {
                    // The PDO maps it: mappable in its direction, with the PDO's size.
                    e.access |= flag;
                    if dir == Direction::Rx {
                        e.access |= EntryAccess::W;
                    }
                    if e.bit_len != bits {
                        e.bit_len = bits;
                        e.data_type = new_entry.data_type;
                        e.default = ConstValue::None;
                        e.min = ConstValue::None;
                        e.max = ConstValue::None;
                    }
                }
                None if sub != 0 && var_zero => {
                    // A file that maps an object both as a variable and by sub-index: the
                    // variable holds; the other slots carry nothing.
                    return;
                }
                None => {
                    entries.push(new_entry);
                    entries.sort_by_key(|e| e.sub);
                    if o.code == ObjectCode::Var {
                        o.code = ObjectCode::Record;
                    }
                }
            }
            o.entries = Vec::leak(entries);
        }
    }
}

/// Replace (or add) an object of a count at sub-index 0 and `cap` entries of `t`, the first
/// ones defaulting to `values`.
fn list_object(
    objs: &mut Vec<ObjectDesc>,
    index: u16,
    name: &str,
    t: DataType,
    values: &[u64],
    cap: usize,
    writable: bool,
) {
    let cap = cap.clamp(values.len().max(1), 254);
    let access = if writable {
        EntryAccess::RW_PREOP
    } else {
        EntryAccess::RO
    };
    let mut entries = vec![
        EntryDesc::new(0, "Number of entries", DataType::Unsigned8, access)
            .default(ConstValue::Uint(values.len() as u64))
            .range(ConstValue::Uint(0), ConstValue::Uint(cap as u64)),
    ];
    for k in 0..cap {
        let sub = u8::try_from(k + 1).unwrap_or(u8::MAX);
        entries.push(
            EntryDesc::new(sub, leak(format!("SubIndex {sub:03}")), t, access)
                .default(ConstValue::Uint(values.get(k).copied().unwrap_or(0))),
        );
    }
    let name = objs
        .iter()
        .find(|o| o.index == index)
        .map_or_else(|| leak(name.to_string()), |o| o.name);
    objs.retain(|o| o.index != index);
    objs.push(ObjectDesc {
        index,
        name,
        code: if t == DataType::Unsigned32 {
            ObjectCode::Record
        } else {
            ObjectCode::Array
        },
        entries: Vec::leak(entries),
    });
}

fn mapping_value(p: &EsiPdo) -> Vec<u64> {
    p.entries
        .iter()
        .map(|e| u64::from(e.index) << 16 | u64::from(e.sub) << 8 | u64::from(e.bit_len.min(255)))
        .collect()
}

/// The dictionary of the emulated device (see the module documentation). Leaked: built once
/// per emulated device, at start-up.
pub fn emulated_dictionary(dev: &Device) -> &'static [ObjectDesc] {
    let base: &[ObjectDesc] = crate::esi::static_dictionary(dev).unwrap_or(&[]);
    let mut objs: Vec<ObjectDesc> = base.to_vec();
    let coe = dev.mailbox.as_ref().and_then(|m| m.coe.as_ref());
    let (assignable, configurable) = coe.map_or((false, false), |c| (c.pdo_assign, c.pdo_config));
    for dir in [Direction::Rx, Direction::Tx] {
        let pdos: Vec<&EsiPdo> = dev.pdos(dir).iter().filter(|p| !p.virtual_).collect();
        for p in &pdos {
            // An entry naming its own PDO's mapping object (a file maps 0x1600:01 in RxPDO
            // 0x1600) names no data object: the mapping object stays a list (below), and the
            // device's process data is the file's PDO as written.
            for e in p
                .entries
                .iter()
                .filter(|e| !e.is_padding() && e.index != p.index)
            {
                let t = entry_type(e.data_type(), e.bit_len);
                ensure_entry(&mut objs, e.index, e.sub, e.bit_len, t, dir, &e.name);
            }
        }
        for p in &pdos {
            let values = mapping_value(p);
            let cap = objs
                .iter()
                .find(|o| o.index == p.index)
                .map_or(0, |o| o.entries.iter().filter(|e| e.sub > 0).count());
            list_object(
                &mut objs,
                p.index,
                &p.name,
                DataType::Unsigned32,
                &values,
                cap.max(values.len()),
                configurable && !p.fixed,
            );
        }
        let (index, name) = match dir {
            Direction::Rx => (0x1C12, "Sync manager 2 PDO assignment"),
            Direction::Tx => (0x1C13, "Sync manager 3 PDO assignment"),
        };
        let assigned: Vec<u64> = pdos
            .iter()
            .filter(|p| p.is_default())
            .map(|p| u64::from(p.index))
            .collect();
        list_object(
            &mut objs,
            index,
            name,
            DataType::Unsigned16,
            &assigned,
            pdos.len(),
            assignable,
        );
    }
    objs.sort_by_key(|o| o.index);
    Vec::leak(objs)
}
