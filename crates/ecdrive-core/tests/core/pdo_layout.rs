//! Process-image layout: offsets of the drives' default and recommended mappings, computed by
//! hand from the manuals' tables, and resolution of object addresses to field handles.

use ecdrive_core::drives::{bdhde, mr_j4_tm};
use ecdrive_core::od::{DataType, ObjectAddress};
use ecdrive_core::pdo::{Direction, FieldError, Layout, Mapping, Pdo, PdoEntry};

fn addr(index: u16) -> ObjectAddress {
    ObjectAddress::new(index, 0)
}

/// (index, byte offset, bits) of every entry of one image, in order.
fn offsets(layout: &Layout, dir: Direction) -> Vec<(u16, usize, u8)> {
    layout
        .image(dir)
        .iter()
        .map(|e| {
            assert_eq!(e.bit_offset(), 0, "{:?} should be byte aligned", e);
            (e.entry.index, e.byte_offset(), e.bits())
        })
        .collect()
}

#[test]
fn mr_j4_tm_default_rx_image_is_29_bytes_with_the_manual_offsets() {
    // MR-J4-TM manual §3.3(1): 1st RxPDO map 0x1600, map size 29 bytes.
    let layout = Layout::new(&mr_j4_tm::DEFAULT_MAPPING);
    assert_eq!(
        offsets(&layout, Direction::Rx),
        vec![
            (0x6060, 0, 8),
            (0x6040, 1, 16),
            (0x2D01, 3, 16),
            (0x2D02, 5, 16),
            (0x2D03, 7, 16),
            (0x607A, 9, 32),
            (0x60FF, 13, 32),
            (0x2D20, 17, 32),
            (0x6071, 21, 16),
            (0x60E0, 23, 16),
            (0x60E1, 25, 16),
            (0x60B8, 27, 16),
        ]
    );
    assert_eq!(layout.bytes(Direction::Rx), 29);
    assert_eq!(layout.rx().bits(), 29 * 8);
    // Sub-indices in the mapping object count from 1.
    let tp = layout.find(Direction::Rx, addr(0x60B8)).unwrap();
    assert_eq!((tp.pdo, tp.sub), (0x1600, 12));
}

#[test]
fn mr_j4_tm_default_tx_image_is_41_bytes_with_the_manual_offsets() {
    // §3.3(2): 1st TxPDO map 0x1A00, map size 41 bytes.
    let layout = Layout::new(&mr_j4_tm::DEFAULT_MAPPING);
    assert_eq!(
        offsets(&layout, Direction::Tx),
        vec![
            (0x6061, 0, 8),
            (0x6041, 1, 16),
            (0x2D11, 3, 16),
            (0x2D12, 5, 16),
            (0x2D13, 7, 16),
            (0x6064, 9, 32),
            (0x606C, 13, 32),
            (0x60F4, 17, 32),
            (0x6077, 21, 16),
            (0x60B9, 23, 16),
            (0x60BA, 25, 32),
            (0x60BB, 29, 32),
            (0x60BC, 33, 32),
            (0x60BD, 37, 32),
        ]
    );
    assert_eq!(layout.bytes(Direction::Tx), 41);
}

#[test]
fn mr_j4_tm_other_default_tables_have_the_manual_sizes() {
    // §3.3: 0x1601 45 bytes, 0x1602 25 bytes; 0x1A01 is 50 by its objects (the manual says 54).
    let sizes: Vec<(u16, u32)> = mr_j4_tm::RX_PDOS
        .iter()
        .chain(mr_j4_tm::TX_PDOS)
        .map(|p| (p.index, p.bits() / 8))
        .collect();
    assert_eq!(
        sizes,
        vec![
            (0x1600, 29),
            (0x1601, 45),
            (0x1602, 25),
            (0x1603, 0),
            (0x1A00, 41),
            (0x1A01, 50),
            (0x1A02, 0),
            (0x1A03, 0),
        ]
    );
    let counts: Vec<usize> = mr_j4_tm::RX_PDOS
        .iter()
        .chain(mr_j4_tm::TX_PDOS)
        .map(Pdo::len)
        .collect();
    // §3.4 default sub-index 0 values.
    assert_eq!(counts, vec![12, 16, 10, 0, 14, 19, 0, 0]);
}

#[test]
fn bdhde_default_images_are_23_bytes_with_unaligned_fields() {
    // BDHDE manual §5.2.2 / chapter 7: 0x1600 and 0x1A00, 8 entries each, 184 bits.
    let layout = Layout::new(&bdhde::DEFAULT_MAPPING);
    assert_eq!(
        offsets(&layout, Direction::Rx),
        vec![
            (0x607A, 0, 32),
            (0x60FF, 4, 32),
            (0x6060, 8, 8),
            (0x6040, 9, 16),
            (0x6081, 11, 32),
            (0x60B8, 15, 16),
            (0x6071, 17, 16),
            (0x6083, 19, 32),
        ]
    );
    assert_eq!(
        offsets(&layout, Direction::Tx),
        vec![
            (0x6041, 0, 16),
            (0x6064, 2, 32),
            (0x606C, 6, 32),
            (0x6077, 10, 16),
            (0x6061, 12, 8),
            (0x60F4, 13, 32),
            (0x60B9, 17, 16),
            (0x60BA, 19, 32),
        ]
    );
    assert_eq!(layout.bytes(Direction::Rx), 23);
    assert_eq!(layout.bytes(Direction::Tx), 23);
}

#[test]
fn bdhde_default_entry_values_are_the_manual_decimals() {
    // Chapter 7 prints the default mapping entries in decimal.
    let rx: Vec<u32> = bdhde::RX_PDO_1600
        .entries
        .iter()
        .map(|e| e.to_u32())
        .collect();
    assert_eq!(
        rx,
        vec![
            1618608160, 1627324448, 1616904200, 1614807056, 1619066912, 1622671376, 1618018320,
            1619197984
        ]
    );
    let tx: Vec<u32> = bdhde::TX_PDO_1A00
        .entries
        .iter()
        .map(|e| e.to_u32())
        .collect();
    assert_eq!(
        tx,
        vec![
            1614872592, 1617166368, 1617690656, 1618411536, 1616969736, 1626603552, 1622736912,
            1622802464
        ]
    );
    let small: Vec<(u16, Vec<u32>)> = bdhde::RX_PDOS[1..]
        .iter()
        .chain(&bdhde::TX_PDOS[1..])
        .map(|p| (p.index, p.entries.iter().map(|e| e.to_u32()).collect()))
        .collect();
    assert_eq!(
        small,
        vec![
            (0x1601, vec![1614807056, 1618608160]),
            (0x1602, vec![1614807056, 1627324448]),
            (0x1603, vec![1614807056, 1618018320]),
            (0x1A01, vec![1614872592, 1617166368]),
            (0x1A02, vec![1614872592, 1617690656]),
            (0x1A03, vec![1614872592, 1618411536]),
        ]
    );
}

#[test]
fn cyclic_mappings_share_their_layout_and_are_aligned() {
    // Both drives' recommended mappings have the same fields at the same offsets; the MR-J4-TM's
    // adds Status DO 2 (0x2D12, its zero-speed signal) after them.
    assert_eq!(mr_j4_tm::CYCLIC_MAPPING.rx, bdhde::CYCLIC_MAPPING.rx);
    let common_tx = vec![
        (0x6041, 0, 16),
        (0x6064, 2, 32),
        (0x606C, 6, 32),
        (0x6077, 10, 16),
        (0x60F4, 12, 32),
        (0x603F, 16, 16),
        (0x6061, 18, 8),
    ];
    let layout = Layout::new(&mr_j4_tm::CYCLIC_MAPPING);
    assert_eq!(
        offsets(&layout, Direction::Rx),
        vec![
            (0x6040, 0, 16),
            (0x607A, 2, 32),
            (0x60FF, 6, 32),
            (0x6071, 10, 16),
            (0x6060, 12, 8),
        ]
    );
    let mut mr_tx = common_tx.clone();
    mr_tx.push((0x2D12, 19, 16));
    assert_eq!(offsets(&layout, Direction::Tx), mr_tx);
    assert_eq!(layout.bytes(Direction::Rx), 13);
    assert_eq!(layout.bytes(Direction::Tx), 21);
    let bd = Layout::new(&bdhde::CYCLIC_MAPPING);
    assert_eq!(offsets(&bd, Direction::Tx), common_tx);
    assert_eq!(bd.bytes(Direction::Tx), 19);
}

/// Two PDOs per direction, padding and sub-byte entries: PDOs follow each other in assignment
/// order with no alignment, and the SM length rounds the bit count up.
#[test]
fn multi_pdo_layout_is_bit_packed_in_assignment_order() {
    let mapping = Mapping::owned(
        vec![
            Pdo::owned(
                0x1601,
                vec![
                    PdoEntry::new(0x7000, 1, 1),
                    PdoEntry::padding(3),
                    PdoEntry::new(0x7000, 2, 12),
                ],
            ),
            Pdo::owned(
                0x1600,
                vec![PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x7000, 1, 1)],
            ),
        ],
        vec![Pdo::owned(0x1A00, vec![PdoEntry::new(0x6000, 1, 5)])],
    );
    let layout = Layout::new(&mapping);
    let rx: Vec<(u16, u8, usize)> = layout
        .rx()
        .iter()
        .map(|e| (e.pdo, e.sub, e.bit_position))
        .collect();
    assert_eq!(
        rx,
        vec![
            (0x1601, 1, 0),
            (0x1601, 2, 1),
            (0x1601, 3, 4),
            (0x1600, 1, 16),
            (0x1600, 2, 32),
        ]
    );
    assert_eq!(layout.rx().bits(), 33);
    assert_eq!(layout.bytes(Direction::Rx), 5);
    assert_eq!(layout.bytes(Direction::Tx), 1);
    // First occurrence wins; padding is never found.
    let first = layout
        .find(Direction::Rx, ObjectAddress::new(0x7000, 1))
        .unwrap();
    assert_eq!((first.pdo, first.bit_position), (0x1601, 0));
    assert!(
        layout
            .find(Direction::Rx, ObjectAddress::new(0, 0))
            .is_none()
    );
    let second = layout.rx().find(ObjectAddress::new(0x7000, 2)).unwrap();
    assert_eq!((second.byte_offset(), second.bit_offset()), (0, 4));
    assert_eq!(layout.rx().pdo_bits(0x1600), Some(16..33));
    assert_eq!(layout.rx().pdo_bits(0x1601), Some(0..16));
    assert_eq!(layout.rx().pdo_bits(0x1602), None);
}

#[test]
fn resolving_fields_checks_direction_type_and_length() {
    let layout = Layout::new(&mr_j4_tm::DEFAULT_MAPPING);
    let target = layout
        .field(Direction::Rx, addr(0x607A), DataType::Integer32)
        .unwrap();
    assert_eq!((target.byte_offset(), target.bit_offset()), (9, 0));
    assert!(target.is_signed());
    let cw = layout
        .field(Direction::Rx, addr(0x6040), DataType::Unsigned16)
        .unwrap();
    assert!(!cw.is_signed());

    let err = layout
        .field(Direction::Tx, addr(0x607A), DataType::Integer32)
        .unwrap_err();
    assert_eq!(
        err,
        FieldError::NotMapped {
            dir: Direction::Tx,
            addr: addr(0x607A)
        }
    );
    assert_eq!(err.to_string(), "0x607A:00 is not mapped in any TxPDO");

    let err = layout
        .field(Direction::Tx, addr(0x6077), DataType::Integer32)
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x6077:00 is mapped with 16 bits in TxPDO 0x1A00, but its type INTEGER32 has 32 bits"
    );

    let err = layout
        .field(Direction::Rx, addr(0x6040), DataType::VisibleString)
        .unwrap_err();
    assert!(matches!(err, FieldError::Unsupported { .. }), "{err}");

    let raw = layout.raw_field(Direction::Tx, addr(0x6077), true).unwrap();
    assert_eq!((raw.byte_offset(), raw.bits()), (21, 16));
}

#[test]
fn resolving_with_a_dictionary_takes_the_type_from_it() {
    use ecdrive_core::od::{Dictionary, EntryAccess, EntryDesc, ObjectCode, ObjectDesc};
    const OBJECTS: &[ObjectDesc] = &[ObjectDesc {
        index: 0x6077,
        name: "Torque actual value",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(
            0,
            "Torque actual value",
            DataType::Integer16,
            EntryAccess::RO.union(EntryAccess::TXPDO),
        )],
    }];
    let dict = Dictionary::new(OBJECTS);
    let layout = Layout::new(&mr_j4_tm::DEFAULT_MAPPING);
    let torque = layout.resolve(Direction::Tx, addr(0x6077), &dict).unwrap();
    assert!(torque.is_signed());
    let mut img = vec![0u8; layout.bytes(Direction::Tx)];
    torque.write(&mut img, -25i16).unwrap();
    assert_eq!(&img[21..23], &(-25i16).to_le_bytes());
    let err = layout
        .resolve(Direction::Tx, addr(0x6041), &dict)
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "0x6041:00 is not in the drive's dictionary, so its type is unknown"
    );
}
