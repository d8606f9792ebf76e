//! Mapping validation: one test per rule, each asserting the message names the limit and the
//! offending PDO or entry; the drives' own mappings pass.

use ecdrive_core::drives::{bdhde, mr_j4_tm};
use ecdrive_core::od::{DataType, EntryAccess, EntryDesc, ObjectAddress, ObjectCode, ObjectDesc};
use ecdrive_core::pdo::{
    Direction, DirectionLimits, Mapping, MappingError, Pdo, PdoEntry, PdoLimits, PdoRange,
    RequiredObjects, validate, validate_all,
};

fn rx_only(pdos: Vec<Pdo>) -> Mapping {
    Mapping::owned(
        pdos,
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6041, 0, 16)])],
    )
}

fn messages(errors: &[MappingError]) -> Vec<String> {
    errors.iter().map(ToString::to_string).collect()
}

/// Lenient limits that isolate one rule at a time.
const ROOMY: &[PdoRange] = &[PdoRange::new(0x1600, 0x1603, 8)];
const ROOMY_TX: &[PdoRange] = &[PdoRange::new(0x1A00, 0x1A03, 8)];
const TEST_DRIVE: PdoLimits = PdoLimits {
    drive: "test drive",
    rx: DirectionLimits {
        pdos: ROOMY,
        max_assigned: 4,
        max_entries: 10,
        max_bytes: 64,
    },
    tx: DirectionLimits {
        pdos: ROOMY_TX,
        max_assigned: 4,
        max_entries: 10,
        max_bytes: 64,
    },
    assignment_writable: true,
};

#[test]
fn drive_defaults_and_recommendations_pass() {
    for (limits, default, cyclic, rx_tables, tx_tables) in [
        (
            &mr_j4_tm::PDO_LIMITS,
            &mr_j4_tm::DEFAULT_MAPPING,
            &mr_j4_tm::CYCLIC_MAPPING,
            mr_j4_tm::RX_PDOS,
            mr_j4_tm::TX_PDOS,
        ),
        (
            &bdhde::PDO_LIMITS,
            &bdhde::DEFAULT_MAPPING,
            &bdhde::CYCLIC_MAPPING,
            bdhde::RX_PDOS,
            bdhde::TX_PDOS,
        ),
    ] {
        assert_eq!(validate(default, limits, None), Ok(()), "{}", limits.drive);
        assert_eq!(validate(cyclic, limits, None), Ok(()), "{}", limits.drive);
        // Every power-on table is valid when assigned on its own.
        for rx in rx_tables {
            for tx in tx_tables {
                let m = Mapping::owned(vec![rx.clone()], vec![tx.clone()]);
                assert_eq!(validate_all(&m, limits, None), vec![], "{}", limits.drive);
            }
        }
    }
}

#[test]
fn entries_per_pdo_names_the_drive_and_the_table_range() {
    let m = rx_only(vec![Pdo::owned(
        0x1601,
        vec![
            PdoEntry::new(0x6040, 0, 16),
            PdoEntry::new(0x607A, 0, 32),
            PdoEntry::new(0x6060, 0, 8),
        ],
    )]);
    let err = validate(&m, &bdhde::PDO_LIMITS, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "RxPDO 0x1601 has 3 entries; the BDHDE allows at most 2 in 0x1601–0x1603"
    );
    assert!(matches!(
        err,
        MappingError::TooManyEntriesInPdo {
            index: 0x1601,
            count: 3,
            max: 2,
            ..
        }
    ));

    let nine = Mapping::owned(
        vec![],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6041, 0, 16); 9])],
    );
    let msgs = messages(&validate_all(&nine, &bdhde::PDO_LIMITS, None));
    assert!(
        msgs.contains(&"TxPDO 0x1A00 has 9 entries; the BDHDE allows at most 8 in 0x1A00".into()),
        "{msgs:#?}"
    );
}

#[test]
fn bytes_per_direction_names_the_limit() {
    // 18 × 32 bits = 72 bytes in 18 entries (within the 32-entry limit).
    let m = Mapping::owned(
        vec![],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6064, 0, 32); 18])],
    );
    let err = validate(&m, &mr_j4_tm::PDO_LIMITS, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "TxPDO mapping is 72 bytes; the MR-J4-TM allows at most 64 per direction"
    );
}

#[test]
fn entries_per_direction_names_the_limit() {
    let m = rx_only(vec![
        Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 0, 16); 6]),
        Pdo::owned(0x1601, vec![PdoEntry::new(0x6040, 0, 16); 5]),
    ]);
    let err = validate(&m, &TEST_DRIVE, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "RxPDO mapping has 11 entries; the test drive allows at most 10 per direction"
    );
    // On the MR-J4-TM: 33 entries in one table break both the table and the direction limit.
    let m = rx_only(vec![Pdo::owned(
        0x1600,
        vec![PdoEntry::new(0x6060, 0, 8); 33],
    )]);
    let msgs = messages(&validate_all(&m, &mr_j4_tm::PDO_LIMITS, None));
    assert_eq!(
        msgs,
        vec![
            "RxPDO 0x1600 has 33 entries; the MR-J4-TM allows at most 32 in 0x1600–0x1603",
            "RxPDO mapping has 33 entries; the MR-J4-TM allows at most 32 per direction",
        ]
    );
}

#[test]
fn pdos_per_direction_names_the_limit() {
    let m = rx_only(vec![rx_1600(), Pdo::owned(0x1601, vec![])]);
    let err = validate(&m, &mr_j4_tm::PDO_LIMITS, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "2 RxPDOs are assigned to SM2 (0x1C12); the MR-J4-TM allows at most 1 per direction"
    );
}

fn rx_1600() -> Pdo {
    Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 0, 16)])
}

#[test]
fn pdo_index_of_the_other_direction_is_refused() {
    let m = rx_only(vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6040, 0, 16)])]);
    let err = validate(&m, &TEST_DRIVE, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x1A00 is not an RxPDO (RxPDOs are 0x1600–0x17FF); it cannot be assigned to SM2 (0x1C12)"
    );
    let m = Mapping::owned(vec![], vec![rx_1600()]);
    let err = validate(&m, &TEST_DRIVE, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x1600 is not a TxPDO (TxPDOs are 0x1A00–0x1BFF); it cannot be assigned to SM3 (0x1C13)"
    );
}

#[test]
fn pdo_the_drive_does_not_have_is_refused() {
    let m = rx_only(vec![Pdo::owned(0x1604, vec![PdoEntry::new(0x6040, 0, 16)])]);
    let err = validate(&m, &bdhde::PDO_LIMITS, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "RxPDO 0x1604 does not exist on the BDHDE (its RxPDOs are 0x1600, 0x1601–0x1603)"
    );
}

#[test]
fn duplicate_pdo_in_an_assignment_is_refused() {
    let m = rx_only(vec![rx_1600(), rx_1600()]);
    let err = validate(&m, &TEST_DRIVE, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "RxPDO 0x1600 is assigned twice to SM2 (0x1C12)"
    );
}

#[test]
fn zero_length_entries_are_refused() {
    let m = rx_only(vec![Pdo::owned(
        0x1600,
        vec![PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x6060, 0, 0)],
    )]);
    let err = validate(&m, &TEST_DRIVE, None).unwrap_err();
    assert_eq!(
        err.to_string(),
        "entry 2 of RxPDO 0x1600 (0x60600000) has length 0 bits"
    );
    let gap = rx_only(vec![Pdo::owned(0x1600, vec![PdoEntry::padding(0)])]);
    assert!(matches!(
        validate(&gap, &TEST_DRIVE, None),
        Err(MappingError::ZeroLengthEntry { sub: 1, .. })
    ));
}

// A slice of a drive dictionary, enough for the dictionary rules.
const RW_RX: EntryAccess = EntryAccess::RW.union(EntryAccess::RXPDO);
const RO_TX: EntryAccess = EntryAccess::RO.union(EntryAccess::TXPDO);
const DICT: &[ObjectDesc] = &[
    ObjectDesc {
        index: 0x6040,
        name: "Controlword",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(
            0,
            "Controlword",
            DataType::Unsigned16,
            RW_RX,
        )],
    },
    ObjectDesc {
        index: 0x6041,
        name: "Statusword",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "Statusword", DataType::Unsigned16, RO_TX)],
    },
    ObjectDesc {
        index: 0x6060,
        name: "Modes of operation",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(
            0,
            "Modes of operation",
            DataType::Integer8,
            RW_RX,
        )],
    },
    ObjectDesc {
        index: 0x607A,
        name: "Target position",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(
            0,
            "Target position",
            DataType::Integer32,
            RW_RX,
        )],
    },
];

#[test]
fn dictionary_object_must_exist() {
    let m = rx_only(vec![Pdo::owned(0x1600, vec![PdoEntry::new(0x6099, 5, 32)])]);
    let err = validate(&m, &mr_j4_tm::PDO_LIMITS, Some(DICT)).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x6099:05 does not exist in the MR-J4-TM dictionary (entry 1 of RxPDO 0x1600)"
    );
    // A missing sub-index of an existing object is missing too.
    let m = rx_only(vec![Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 1, 16)])]);
    assert!(matches!(
        validate(&m, &mr_j4_tm::PDO_LIMITS, Some(DICT)),
        Err(MappingError::NoSuchObject { .. })
    ));
}

#[test]
fn dictionary_object_must_be_mappable_in_that_direction() {
    let m = rx_only(vec![Pdo::owned(
        0x1600,
        vec![PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x6041, 0, 16)],
    )]);
    let err = validate(&m, &mr_j4_tm::PDO_LIMITS, Some(DICT)).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x6041:00 is not RxPDO-mappable (entry 2 of RxPDO 0x1600)"
    );
    let m = Mapping::owned(
        vec![],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6040, 0, 16)])],
    );
    let err = validate(&m, &mr_j4_tm::PDO_LIMITS, Some(DICT)).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x6040:00 is not TxPDO-mappable (entry 1 of TxPDO 0x1A00)"
    );
}

#[test]
fn dictionary_object_must_be_mapped_with_its_length() {
    let m = rx_only(vec![Pdo::owned(
        0x1600,
        vec![PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 16)],
    )]);
    let err = validate(&m, &mr_j4_tm::PDO_LIMITS, Some(DICT)).unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x607A:00 is 32 bits, mapped with 16 (entry 2 of RxPDO 0x1600)"
    );
}

#[test]
fn padding_skips_dictionary_checks_and_a_clean_mapping_passes() {
    let m = Mapping::owned(
        vec![Pdo::owned(
            0x1600,
            vec![
                PdoEntry::new(0x6040, 0, 16),
                PdoEntry::padding(8),
                PdoEntry::new(0x607A, 0, 32),
                PdoEntry::new(0x6060, 0, 8),
            ],
        )],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6041, 0, 16)])],
    );
    assert_eq!(validate_all(&m, &mr_j4_tm::PDO_LIMITS, Some(DICT)), vec![]);
    assert_eq!(mr_j4_tm::PDO_LIMITS.validate(&m, Some(DICT)), Ok(()));
}

#[test]
fn validate_all_reports_every_violation_rx_first() {
    let m = Mapping::owned(
        vec![
            Pdo::owned(0x1604, vec![PdoEntry::new(0x6041, 0, 16)]),
            Pdo::owned(0x1A01, vec![]),
        ],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6040, 0, 0)])],
    );
    let errors = validate_all(&m, &bdhde::PDO_LIMITS, Some(DICT));
    assert_eq!(
        messages(&errors),
        vec![
            "2 RxPDOs are assigned to SM2 (0x1C12); the BDHDE allows at most 1 per direction",
            "RxPDO 0x1604 does not exist on the BDHDE (its RxPDOs are 0x1600, 0x1601–0x1603)",
            "0x6041:00 is not RxPDO-mappable (entry 1 of RxPDO 0x1604)",
            "0x1A01 is not an RxPDO (RxPDOs are 0x1600–0x17FF); it cannot be assigned to SM2 (0x1C12)",
            "entry 1 of TxPDO 0x1A00 (0x60400000) has length 0 bits",
        ]
    );
    assert_eq!(
        validate(&m, &bdhde::PDO_LIMITS, Some(DICT)),
        Err(errors[0].clone())
    );
}

#[test]
fn required_objects_per_mode() {
    for table in [mr_j4_tm::REQUIRED_OBJECTS, bdhde::REQUIRED_OBJECTS] {
        for mode in [8, 9, 10] {
            let req = RequiredObjects::find(table, mode).unwrap();
            req.check(&mr_j4_tm::CYCLIC_MAPPING, "x").unwrap();
        }
    }
    // The MR-J4-TM default maps every cyclic and profile mode's set-points.
    for mode in [1, 3, 4, 6, 8, 9, 10] {
        let req = RequiredObjects::find(mr_j4_tm::REQUIRED_OBJECTS, mode).unwrap();
        req.check(&mr_j4_tm::DEFAULT_MAPPING, "MR-J4-TM").unwrap();
    }
    // 0x1601 (CW + target position) alone is no good for csv.
    let m = Mapping::fixed(&bdhde::RX_PDOS[1..2], &bdhde::TX_PDOS[1..2]);
    assert_eq!(m.rx[0].index, 0x1601);
    let csv = RequiredObjects::find(bdhde::REQUIRED_OBJECTS, 9).unwrap();
    assert_eq!(
        csv.missing(&m),
        vec![(Direction::Rx, ObjectAddress::new(0x60FF, 0))]
    );
    let pt = RequiredObjects::find(mr_j4_tm::REQUIRED_OBJECTS, -101).unwrap();
    assert_eq!(
        pt.check(&mr_j4_tm::DEFAULT_MAPPING, mr_j4_tm::PDO_LIMITS.drive)
            .unwrap_err()
            .to_string(),
        "pt (mode -101) on the MR-J4-TM needs 0x2D60:00 in an RxPDO; the mapping does not have it"
    );
    assert!(RequiredObjects::find(bdhde::REQUIRED_OBJECTS, -101).is_none());
}

#[test]
fn limits_answer_questions_about_indices() {
    let l = &bdhde::PDO_LIMITS;
    assert_eq!(l.range_of(0x1602).map(|r| r.max_entries), Some(2));
    assert_eq!(l.range_of(0x1A00).map(|r| r.max_entries), Some(8));
    assert!(l.range_of(0x1604).is_none());
    assert!(l.range_of(0x2000).is_none());
    assert!(l.mapping_writable(0x1A03));
    assert!(!l.mapping_writable(0x1A04));
    let rx: Vec<u16> = l.rx.indices().collect();
    assert_eq!(rx, vec![0x1600, 0x1601, 0x1602, 0x1603]);
    let tx: Vec<u16> = mr_j4_tm::PDO_LIMITS.tx.indices().collect();
    assert_eq!(tx, vec![0x1A00, 0x1A01, 0x1A02, 0x1A03]);
}
