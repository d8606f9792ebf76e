//! The remap SDO sequence, asserted write by write, and the read-back that rebuilds a mapping,
//! round-tripped through a fake drive that enforces the CiA 301 write-order rules.

use ecdrive_core::drives::{bdhde, mr_j4_tm};
use ecdrive_core::od::{
    DataType, Dictionary, EntryAccess, EntryDesc, ObjectAddress, ObjectCode, ObjectDesc,
};
use ecdrive_core::pdo::{
    Direction, DirectionLimits, Mapping, Pdo, PdoEntry, PdoLimits, PdoRange, ReadbackError,
    RemapOptions, SdoWrite, read_mapping, read_mapping_sync, remap_sequence,
};
use std::collections::BTreeMap;

fn a(index: u16, sub: u8) -> ObjectAddress {
    ObjectAddress::new(index, sub)
}

fn two_pdo_mapping() -> Mapping {
    Mapping::owned(
        vec![Pdo::owned(
            0x1600,
            vec![PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)],
        )],
        vec![Pdo::owned(
            0x1A00,
            vec![PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6064, 0, 32)],
        )],
    )
}

#[test]
fn two_pdo_sequence_write_by_write() {
    let seq = remap_sequence(&two_pdo_mapping(), &RemapOptions::default()).unwrap();
    let got: Vec<(ObjectAddress, DataType, u32)> = seq
        .iter()
        .map(|w| (w.address, w.data_type, w.value))
        .collect();
    use DataType::{Unsigned8 as U8, Unsigned16 as U16, Unsigned32 as U32};
    assert_eq!(
        got,
        vec![
            (a(0x1C12, 0), U8, 0),
            (a(0x1C13, 0), U8, 0),
            (a(0x1600, 0), U8, 0),
            (a(0x1600, 1), U32, 0x6040_0010),
            (a(0x1600, 2), U32, 0x607A_0020),
            (a(0x1600, 0), U8, 2),
            (a(0x1A00, 0), U8, 0),
            (a(0x1A00, 1), U32, 0x6041_0010),
            (a(0x1A00, 2), U32, 0x6064_0020),
            (a(0x1A00, 0), U8, 2),
            (a(0x1C12, 1), U16, 0x1600),
            (a(0x1C12, 0), U8, 1),
            (a(0x1C13, 1), U16, 0x1A00),
            (a(0x1C13, 0), U8, 1),
        ]
    );
    let text: Vec<String> = seq.iter().map(ToString::to_string).collect();
    assert_eq!(
        text,
        vec![
            "0x1C12:00 = 0 (unassign SM2 PDOs)",
            "0x1C13:00 = 0 (unassign SM3 PDOs)",
            "0x1600:00 = 0 (clear 0x1600 mapping)",
            "0x1600:01 = 0x60400010 (map 0x6040:00, 16 bits)",
            "0x1600:02 = 0x607A0020 (map 0x607A:00, 32 bits)",
            "0x1600:00 = 2 (0x1600 maps 2 entries)",
            "0x1A00:00 = 0 (clear 0x1A00 mapping)",
            "0x1A00:01 = 0x60410010 (map 0x6041:00, 16 bits)",
            "0x1A00:02 = 0x60640020 (map 0x6064:00, 32 bits)",
            "0x1A00:00 = 2 (0x1A00 maps 2 entries)",
            "0x1C12:01 = 0x1600 (assign RxPDO 0x1600 to SM2)",
            "0x1C12:00 = 1 (SM2 has 1 PDO)",
            "0x1C13:01 = 0x1A00 (assign TxPDO 0x1A00 to SM3)",
            "0x1C13:00 = 1 (SM3 has 1 PDO)",
        ]
    );
    // Download data: 1, 2 or 4 little-endian bytes.
    assert_eq!(seq[0].bytes(), vec![0]);
    assert_eq!(seq[3].bytes(), vec![0x10, 0x00, 0x40, 0x60]);
    assert_eq!(seq[10].bytes(), vec![0x00, 0x16]);
    assert_eq!(seq[5].bytes(), vec![2]);
}

const CW: &[EntryDesc] = &[EntryDesc::new(
    0,
    "Controlword",
    DataType::Unsigned16,
    EntryAccess::RW.union(EntryAccess::RXPDO),
)];
const TP: &[EntryDesc] = &[
    EntryDesc::new(0, "Highest sub-index", DataType::Unsigned8, EntryAccess::RO),
    EntryDesc::new(
        1,
        "Input 1",
        DataType::Boolean,
        EntryAccess::RO.union(EntryAccess::TXPDO),
    ),
];
const NAMES: &[ObjectDesc] = &[
    ObjectDesc {
        index: 0x6040,
        name: "Controlword",
        code: ObjectCode::Var,
        entries: CW,
    },
    ObjectDesc {
        index: 0x6000,
        name: "Inputs",
        code: ObjectCode::Record,
        entries: TP,
    },
];

#[test]
fn descriptions_use_dictionary_names_and_describe_gaps() {
    let m = Mapping::owned(
        vec![Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 0, 16)])],
        vec![Pdo::owned(
            0x1A00,
            vec![PdoEntry::new(0x6000, 1, 1), PdoEntry::padding(7)],
        )],
    );
    let opts = RemapOptions {
        names: Some(Dictionary::new(NAMES)),
        ..RemapOptions::default()
    };
    let seq = remap_sequence(&m, &opts).unwrap();
    let d: Vec<&str> = seq.iter().map(|w| w.description.as_str()).collect();
    assert_eq!(d[3], "map 0x6040:00 Controlword, 16 bits");
    assert_eq!(d[6], "map 0x6000:01 Inputs: Input 1, 1 bit");
    assert_eq!(d[7], "7-bit gap");
    assert_eq!(seq[7].value, 0x0000_0007);
    assert_eq!(d[8], "0x1A00 maps 2 entries");
    assert_eq!(d[4], "0x1600 maps 1 entry");
}

const FIXED_TX: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A01, 4).fixed()];
const RX_ANY: &[PdoRange] = &[PdoRange::new(0x1600, 0x1601, 4)];
const PARTLY_FIXED: PdoLimits = PdoLimits {
    drive: "fixed-tx drive",
    rx: DirectionLimits {
        pdos: RX_ANY,
        max_assigned: 2,
        max_entries: 8,
        max_bytes: 32,
    },
    tx: DirectionLimits {
        pdos: FIXED_TX,
        max_assigned: 2,
        max_entries: 8,
        max_bytes: 32,
    },
    assignment_writable: false,
};

#[test]
fn fixed_assignment_and_fixed_mappings_are_skipped() {
    let m = Mapping::owned(
        vec![
            Pdo::owned(0x1601, vec![PdoEntry::new(0x6040, 0, 16)]),
            Pdo::owned(0x1600, vec![PdoEntry::new(0x6060, 0, 8)]),
        ],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6041, 0, 16)])],
    );
    let seq = remap_sequence(&m, &RemapOptions::for_drive(&PARTLY_FIXED, None)).unwrap();
    let got: Vec<(ObjectAddress, u32)> = seq.iter().map(|w| (w.address, w.value)).collect();
    assert_eq!(
        got,
        vec![
            (a(0x1601, 0), 0),
            (a(0x1601, 1), 0x6040_0010),
            (a(0x1601, 0), 1),
            (a(0x1600, 0), 0),
            (a(0x1600, 1), 0x6060_0008),
            (a(0x1600, 0), 1),
        ]
    );
    // With a writable assignment the fixed TxPDO is still assigned, in order.
    let opts = RemapOptions {
        skip_assignment: false,
        fixed_mappings: Some(&PARTLY_FIXED),
        names: None,
    };
    let seq = remap_sequence(&m, &opts).unwrap();
    let tail: Vec<(ObjectAddress, u32)> = seq
        .iter()
        .rev()
        .take(5)
        .rev()
        .map(|w| (w.address, w.value))
        .collect();
    assert_eq!(
        tail,
        vec![
            (a(0x1C12, 1), 0x1601),
            (a(0x1C12, 2), 0x1600),
            (a(0x1C12, 0), 2),
            (a(0x1C13, 1), 0x1A00),
            (a(0x1C13, 0), 1),
        ]
    );
    assert!(!seq.iter().any(|w| w.address.index == 0x1A00));
}

#[test]
fn a_pdo_assigned_twice_is_mapped_once_and_assigned_twice() {
    let p = Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 0, 16)]);
    let m = Mapping::owned(vec![p.clone(), p], vec![]);
    let seq = remap_sequence(&m, &RemapOptions::default()).unwrap();
    assert_eq!(seq.iter().filter(|w| w.address == a(0x1600, 1)).count(), 1);
    assert_eq!(
        seq.iter()
            .filter(|w| w.address.index == 0x1C12 && w.address.sub > 0)
            .count(),
        2
    );
}

#[test]
fn mappings_no_object_can_hold_are_errors() {
    let m = Mapping::owned(
        vec![Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 0, 8); 256])],
        vec![],
    );
    let err = remap_sequence(&m, &RemapOptions::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "RxPDO 0x1600 has 256 entries; a mapping object holds at most 255"
    );
}

/// A fake drive's PDO objects: sub-index values, with the CiA 301 rules a real drive enforces
/// on the order of writes (abort codes as the drives use them).
struct FakeDrive {
    values: BTreeMap<ObjectAddress, u32>,
    limits: PdoLimits,
}

impl FakeDrive {
    fn power_on(limits: PdoLimits, rx: &[Pdo], tx: &[Pdo], default: &Mapping) -> Self {
        let mut values = BTreeMap::new();
        for pdo in rx.iter().chain(tx) {
            values.insert(a(pdo.index, 0), pdo.len() as u32);
            for (i, e) in pdo.entries.iter().enumerate() {
                values.insert(a(pdo.index, i as u8 + 1), e.to_u32());
            }
        }
        for dir in Direction::ALL {
            let pdos = default.pdos(dir);
            values.insert(a(dir.assign_index(), 0), pdos.len() as u32);
            for (i, p) in pdos.iter().enumerate() {
                values.insert(a(dir.assign_index(), i as u8 + 1), u32::from(p.index));
            }
        }
        Self { values, limits }
    }

    fn download(&mut self, w: &SdoWrite) -> Result<(), &'static str> {
        let ad = w.address;
        let is_assign = ad.index == 0x1C12 || ad.index == 0x1C13;
        let is_map = self.limits.range_of(ad.index).is_some();
        if !is_assign && !is_map {
            return Err("0x06020000 object does not exist");
        }
        let count = self.values.get(&a(ad.index, 0)).copied().unwrap_or(0);
        if ad.sub == 0 {
            if w.data_type != DataType::Unsigned8 {
                return Err("0x06070010 length mismatch");
            }
            if is_map {
                let max = self.limits.range_of(ad.index).map_or(0, |r| r.max_entries);
                if w.value > u32::from(max) {
                    return Err("0x06090031 value too high");
                }
            }
            // Every sub-index counted in must hold something.
            if (1..=w.value).any(|s| !self.values.contains_key(&a(ad.index, s as u8))) {
                return Err("0x06040043 incomplete entries");
            }
        } else {
            if count != 0 {
                return Err("0x06010003 sub-index 0 must be 0");
            }
            let expected = if is_assign {
                DataType::Unsigned16
            } else {
                DataType::Unsigned32
            };
            if w.data_type != expected {
                return Err("0x06070010 length mismatch");
            }
        }
        self.values.insert(ad, w.value);
        Ok(())
    }

    fn upload(&self, ad: ObjectAddress, _t: DataType) -> Result<u32, String> {
        self.values
            .get(&ad)
            .copied()
            .ok_or_else(|| format!("0x06090011 no {ad}"))
    }
}

fn round_trip(limits: PdoLimits, rx: &[Pdo], tx: &[Pdo], default: &Mapping, target: &Mapping) {
    let mut drive = FakeDrive::power_on(limits, rx, tx, default);
    // Before remapping, the read-back is the power-on mapping.
    let before = read_mapping_sync(|ad, t| drive.upload(ad, t)).unwrap();
    assert_eq!(&before, default);
    for w in remap_sequence(target, &RemapOptions::for_drive(&limits, None)).unwrap() {
        drive.download(&w).unwrap_or_else(|e| panic!("{w}: {e}"));
    }
    let after = read_mapping_sync(|ad, t| drive.upload(ad, t)).unwrap();
    assert_eq!(&after, target);
}

#[test]
fn read_back_round_trips_through_a_drive_that_enforces_write_order() {
    round_trip(
        mr_j4_tm::PDO_LIMITS,
        mr_j4_tm::RX_PDOS,
        mr_j4_tm::TX_PDOS,
        &mr_j4_tm::DEFAULT_MAPPING,
        &mr_j4_tm::CYCLIC_MAPPING,
    );
    round_trip(
        bdhde::PDO_LIMITS,
        bdhde::RX_PDOS,
        bdhde::TX_PDOS,
        &bdhde::DEFAULT_MAPPING,
        &bdhde::CYCLIC_MAPPING,
    );
    // A shorter remap of a table that held more entries, and another table assigned.
    round_trip(
        bdhde::PDO_LIMITS,
        bdhde::RX_PDOS,
        bdhde::TX_PDOS,
        &bdhde::DEFAULT_MAPPING,
        &Mapping::owned(
            vec![Pdo::owned(0x1601, vec![PdoEntry::new(0x6040, 0, 16)])],
            vec![Pdo::owned(
                0x1A00,
                vec![PdoEntry::new(0x6041, 0, 16), PdoEntry::padding(8)],
            )],
        ),
    );
}

#[test]
fn read_back_errors_name_the_object() {
    // 0x1C12 lists a TxPDO index.
    let mut v: BTreeMap<ObjectAddress, u32> = BTreeMap::new();
    v.insert(a(0x1C12, 0), 1);
    v.insert(a(0x1C12, 1), 0x1A00);
    let err = read_mapping_sync(|ad, _| v.get(&ad).copied().ok_or("no such object")).unwrap_err();
    assert_eq!(
        err,
        ReadbackError::WrongDirection {
            address: a(0x1C12, 1),
            index: 0x1A00,
            dir: Direction::Rx
        }
    );
    assert_eq!(
        err.to_string(),
        "0x1C12:01 assigns 0x1A00, which is not an RxPDO index (0x1600–0x17FF)"
    );

    // A count that is not an UNSIGNED8.
    v.insert(a(0x1C12, 0), 300);
    let err = read_mapping_sync(|ad, _| v.get(&ad).copied().ok_or("no such object")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x1C12:00 returned 300, which is not a UNSIGNED8"
    );

    // The caller's upload error, with the address.
    v.insert(a(0x1C12, 0), 1);
    v.insert(a(0x1C12, 1), 0x1600);
    let err = read_mapping_sync(|ad, _| v.get(&ad).copied().ok_or("no such object")).unwrap_err();
    assert_eq!(err.to_string(), "reading 0x1600:00 failed: no such object");
}

#[test]
fn read_back_asks_for_the_right_types() {
    let drive = FakeDrive::power_on(
        mr_j4_tm::PDO_LIMITS,
        mr_j4_tm::RX_PDOS,
        mr_j4_tm::TX_PDOS,
        &mr_j4_tm::DEFAULT_MAPPING,
    );
    let mut asked = Vec::new();
    read_mapping_sync(|ad, t| {
        asked.push((ad, t));
        drive.upload(ad, t)
    })
    .unwrap();
    assert_eq!(asked[0], (a(0x1C12, 0), DataType::Unsigned8));
    assert_eq!(asked[1], (a(0x1C12, 1), DataType::Unsigned16));
    assert_eq!(asked[2], (a(0x1600, 0), DataType::Unsigned8));
    assert_eq!(asked[3], (a(0x1600, 1), DataType::Unsigned32));
    // 2 + (1 + 12) for Rx, 2 + (1 + 14) for Tx.
    assert_eq!(asked.len(), 32);
}

#[tokio::test]
async fn async_read_back_matches() {
    let drive = FakeDrive::power_on(
        bdhde::PDO_LIMITS,
        bdhde::RX_PDOS,
        bdhde::TX_PDOS,
        &bdhde::DEFAULT_MAPPING,
    );
    let drive = &drive;
    let m = read_mapping(|ad, t| async move {
        tokio::task::yield_now().await;
        drive.upload(ad, t)
    })
    .await
    .unwrap();
    assert_eq!(m, bdhde::DEFAULT_MAPPING);
}
