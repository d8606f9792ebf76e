//! The generic object dictionary `OdStore`: table checks, access per state, lengths, ranges,
//! the standard PDO mapping/assignment rules, the device hooks, and device-side value access.

use crate::coe_util;

use ecdrive_core::ec::AlState;
use ecdrive_core::od::{
    ConstValue, DataType, EntryAccess, EntryDesc, ObjectAddress, ObjectCode, ObjectDesc,
    SdoAbortCode, Value,
};
use ecdrive_core::pdo::{Direction, DirectionLimits, PdoEntry, PdoLimits, PdoRange};
use ecdrive_sim::coe::hooks::{AllowedValues, Chain, Mirror, RefuseMappedWrites, RefuseWrites};
use ecdrive_sim::coe::{
    CoeConfig, CoeServer, ListType, ObjectStore, OdHooks, OdStore, ValueStore, fixture,
};

const PRE: AlState = AlState::PreOp;

fn a(index: u16, sub: u8) -> ObjectAddress {
    ObjectAddress::new(index, sub)
}

fn store() -> OdStore {
    OdStore::new(fixture::OBJECTS).unwrap()
}

fn read(od: &mut OdStore, index: u16, sub: u8, state: AlState) -> Result<Vec<u8>, SdoAbortCode> {
    let mut buf = [0u8; 256];
    let n = od.read(index, sub, state, &mut buf)?;
    Ok(buf[..n].to_vec())
}

// ---------------------------------------------------------------------------------------------
// Table checks.

static DUPLICATE: &[ObjectDesc] = &[
    ObjectDesc {
        index: 0x2000,
        name: "a",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "a", DataType::Unsigned8, EntryAccess::RW)],
    },
    ObjectDesc {
        index: 0x2000,
        name: "b",
        code: ObjectCode::Var,
        entries: &[EntryDesc::new(0, "b", DataType::Unsigned8, EntryAccess::RW)],
    },
];

static VAR_WITH_SUB1: &[ObjectDesc] = &[ObjectDesc {
    index: 0x2001,
    name: "v",
    code: ObjectCode::Var,
    entries: &[EntryDesc::new(1, "v", DataType::Unsigned8, EntryAccess::RW)],
}];

static ARRAY_WITHOUT_U8_SUB0: &[ObjectDesc] = &[ObjectDesc {
    index: 0x2002,
    name: "arr",
    code: ObjectCode::Array,
    entries: &[
        EntryDesc::new(0, "n", DataType::Unsigned16, EntryAccess::RO),
        EntryDesc::new(1, "x", DataType::Unsigned16, EntryAccess::RW),
    ],
}];

static BAD_DEFAULT: &[ObjectDesc] = &[ObjectDesc {
    index: 0x2003,
    name: "d",
    code: ObjectCode::Var,
    entries: &[
        EntryDesc::new(0, "d", DataType::Unsigned8, EntryAccess::RW).default(ConstValue::Uint(300))
    ],
}];

static LONG_STRING_DEFAULT: &[ObjectDesc] = &[ObjectDesc {
    index: 0x2004,
    name: "s",
    code: ObjectCode::Var,
    entries: &[
        EntryDesc::new(0, "s", DataType::VisibleString, EntryAccess::RO)
            .bits(4 * 8)
            .default(ConstValue::Str("too long")),
    ],
}];

#[test]
fn bad_tables_are_refused_naming_the_object() {
    for (table, at, reason) in [
        (DUPLICATE, "0x2000", "described twice"),
        (VAR_WITH_SUB1, "0x2001", "exactly one entry"),
        (ARRAY_WITHOUT_U8_SUB0, "0x2002", "UNSIGNED8 sub-index 0"),
        (BAD_DEFAULT, "0x2003:00", "does not fit"),
        (LONG_STRING_DEFAULT, "0x2004:00", "exceeds the entry size"),
    ] {
        let e = OdStore::new(table).unwrap_err();
        assert_eq!(e.at, at);
        assert!(e.reason.contains(reason), "{e}");
        assert!(e.to_string().contains(at));
    }
}

// ---------------------------------------------------------------------------------------------
// Access, length, range.

#[test]
fn access_rights_per_state() {
    let mut od = store();
    let states = [AlState::PreOp, AlState::SafeOp, AlState::Op];
    for s in states {
        // RO: readable everywhere, never writable.
        assert!(read(&mut od, 0x1000, 0, s).is_ok());
        assert_eq!(
            od.write(0x1000, 0, s, &[0; 4]),
            Err(SdoAbortCode::READ_ONLY)
        );
        // WO: writable everywhere, never readable.
        assert_eq!(read(&mut od, 0x2000, 0, s), Err(SdoAbortCode::WRITE_ONLY));
        assert_eq!(od.write(0x2000, 0, s, &[1, 0]), Ok(()));
        // RW in PRE-OP only.
        let expect = if s == AlState::PreOp {
            Ok(())
        } else {
            Err(SdoAbortCode::DEVICE_STATE)
        };
        assert_eq!(od.write(0x2003, 0, s, &[9, 0, 0, 0]), expect, "{s}");
        assert!(read(&mut od, 0x2003, 0, s).is_ok());
    }
    // No CoE access in INIT or BOOT.
    for s in [AlState::Init, AlState::Bootstrap] {
        assert_eq!(read(&mut od, 0x1000, 0, s), Err(SdoAbortCode::DEVICE_STATE));
        assert_eq!(
            od.write(0x6040, 0, s, &[0, 0]),
            Err(SdoAbortCode::DEVICE_STATE)
        );
    }
}

#[test]
fn existence_length_and_range() {
    let mut od = store();
    assert_eq!(read(&mut od, 0x4242, 0, PRE), Err(SdoAbortCode::NO_OBJECT));
    assert_eq!(
        read(&mut od, 0x1018, 5, PRE),
        Err(SdoAbortCode::NO_SUBINDEX)
    );
    assert_eq!(
        od.write(0x6040, 0, PRE, &[1]),
        Err(SdoAbortCode::LENGTH_TOO_LOW)
    );
    assert_eq!(
        od.write(0x6040, 0, PRE, &[1, 2, 3]),
        Err(SdoAbortCode::LENGTH_TOO_HIGH)
    );
    for (v, r) in [
        (-100i16, Ok(())),
        (100, Ok(())),
        (101, Err(SdoAbortCode::VALUE_TOO_HIGH)),
        (-101, Err(SdoAbortCode::VALUE_TOO_LOW)),
        (i16::MIN, Err(SdoAbortCode::VALUE_TOO_LOW)),
    ] {
        assert_eq!(od.write(0x2002, 0, PRE, &v.to_le_bytes()), r, "{v}");
    }
    assert_eq!(od.int(a(0x2002, 0)), Some(100));
}

#[test]
fn strings_up_to_their_size() {
    let mut od = store();
    assert_eq!(read(&mut od, 0x2004, 0, PRE).unwrap(), b"hello");
    od.write(0x2004, 0, PRE, b"hi").unwrap();
    assert_eq!(read(&mut od, 0x2004, 0, PRE).unwrap(), b"hi");
    od.write(0x2004, 0, PRE, &[b'x'; 16]).unwrap();
    assert_eq!(
        od.write(0x2004, 0, PRE, &[b'x'; 17]),
        Err(SdoAbortCode::LENGTH_TOO_HIGH)
    );
    assert_eq!(
        od.value(a(0x2004, 0)),
        Some(Value::Str("xxxxxxxxxxxxxxxx".into()))
    );
}

#[test]
fn sub0_of_an_array_cannot_exceed_its_entries() {
    let mut od = store();
    od.write(0x1601, 0, PRE, &[0]).unwrap();
    assert_eq!(
        od.write(0x1601, 0, PRE, &[9]),
        Err(SdoAbortCode::VALUE_TOO_HIGH)
    );
}

// ---------------------------------------------------------------------------------------------
// PDO rules.

fn w32(od: &mut OdStore, index: u16, sub: u8, v: u32) -> Result<(), SdoAbortCode> {
    od.write(index, sub, PRE, &v.to_le_bytes())
}

#[test]
fn remapping_in_the_standard_order_works() {
    // The ethercrab `sdo_write_array` / ETG order: assignment off, mapping off, entries,
    // mapping count, assignment, assignment count.
    let mut od = store();
    od.write(0x1C12, 0, PRE, &[0]).unwrap();
    od.write(0x1601, 0, PRE, &[0]).unwrap();
    w32(&mut od, 0x1601, 1, 0x6040_0010).unwrap();
    w32(&mut od, 0x1601, 2, 0x0000_0008).unwrap(); // 8 bits of padding
    w32(&mut od, 0x1601, 3, 0x6060_0008).unwrap();
    w32(&mut od, 0x1601, 4, 0x60FF_0020).unwrap();
    od.write(0x1601, 0, PRE, &[4]).unwrap();
    od.write(0x1C12, 1, PRE, &0x1601u16.to_le_bytes()).unwrap();
    od.write(0x1C12, 0, PRE, &[1]).unwrap();
    let m = od.mapping().unwrap();
    assert_eq!(m.rx.len(), 1);
    assert_eq!(m.rx[0].index, 0x1601);
    assert_eq!(
        m.rx[0].entries[..],
        [
            PdoEntry::new(0x6040, 0, 16),
            PdoEntry::padding(8),
            PdoEntry::new(0x6060, 0, 8),
            PdoEntry::new(0x60FF, 0, 32)
        ]
    );
    assert_eq!(m.bytes(Direction::Rx), 8);
    assert_eq!(m.tx[0].index, 0x1A00);
    assert!(od.is_mapped(Direction::Rx, a(0x60FF, 0)));
    assert!(!od.is_mapped(Direction::Rx, a(0x607A, 0)));
    assert!(od.is_mapped(Direction::Tx, a(0x6064, 0)));
}

#[test]
fn mapping_entries_need_sub0_zero_and_mappable_objects() {
    let mut od = store();
    // 0x1600 has sub 0 = 2.
    assert_eq!(
        w32(&mut od, 0x1600, 3, 0x60FF_0020),
        Err(SdoAbortCode::SUBINDEX0_NOT_ZERO)
    );
    od.write(0x1600, 0, PRE, &[0]).unwrap();
    for (v, code) in [
        (0x5555_0010, SdoAbortCode::NOT_MAPPABLE), // no such object
        (0x6040_0110, SdoAbortCode::NOT_MAPPABLE), // no such sub-index
        (0x1000_0020, SdoAbortCode::NOT_MAPPABLE), // not PDO-mappable
        (0x6041_0010, SdoAbortCode::NOT_MAPPABLE), // TxPDO object in an RxPDO
        (0x6040_0020, SdoAbortCode::LENGTH_MISMATCH), // 32 bits for a 16-bit object
    ] {
        assert_eq!(w32(&mut od, 0x1600, 3, v), Err(code), "{v:08X}");
    }
    // Tx direction: an RxPDO object is refused.
    od.write(0x1A01, 0, PRE, &[0]).unwrap();
    assert_eq!(
        w32(&mut od, 0x1A01, 1, 0x6040_0010),
        Err(SdoAbortCode::NOT_MAPPABLE)
    );
    w32(&mut od, 0x1A01, 1, 0x6061_0008).unwrap();
    // Sub 0 may not count entries never written (entry 3 of 0x1600 is 0).
    assert_eq!(
        od.write(0x1600, 0, PRE, &[3]),
        Err(SdoAbortCode::VALUE_TOO_HIGH)
    );
    od.write(0x1600, 0, PRE, &[2]).unwrap();
}

#[test]
fn assignment_entries_name_pdos_of_their_direction() {
    let mut od = store();
    assert_eq!(
        od.write(0x1C12, 2, PRE, &0x1601u16.to_le_bytes()),
        Err(SdoAbortCode::SUBINDEX0_NOT_ZERO)
    );
    od.write(0x1C12, 0, PRE, &[0]).unwrap();
    for p in [0x1A00u16, 0x1605, 0x6040] {
        assert_eq!(
            od.write(0x1C12, 1, PRE, &p.to_le_bytes()),
            Err(SdoAbortCode::VALUE_RANGE),
            "{p:04X}"
        );
    }
    od.write(0x1C13, 0, PRE, &[0]).unwrap();
    assert_eq!(
        od.write(0x1C13, 1, PRE, &0x1600u16.to_le_bytes()),
        Err(SdoAbortCode::VALUE_RANGE)
    );
    // Entry 2 never written: sub 0 = 2 is refused.
    assert_eq!(
        od.write(0x1C12, 0, PRE, &[2]),
        Err(SdoAbortCode::VALUE_TOO_HIGH)
    );
    od.write(0x1C12, 2, PRE, &0x1601u16.to_le_bytes()).unwrap();
    od.write(0x1C12, 0, PRE, &[2]).unwrap();
}

#[test]
fn pdo_objects_are_writable_only_in_preop() {
    let mut od = store();
    for s in [AlState::SafeOp, AlState::Op] {
        assert_eq!(
            od.write(0x1C12, 0, s, &[0]),
            Err(SdoAbortCode::DEVICE_STATE)
        );
        assert_eq!(
            od.write(0x1A00, 0, s, &[0]),
            Err(SdoAbortCode::DEVICE_STATE)
        );
    }
}

static RX_RANGES: &[PdoRange] = &[PdoRange::new(0x1600, 0x1601, 4)];
static TX_RANGES: &[PdoRange] = &[
    PdoRange::single(0x1A00, 8),
    PdoRange::single(0x1A01, 8).fixed(),
];

/// A drive's PDO limits for the fixture: Rx 0x1600/0x1601 of at most 4 entries, two PDOs, 3
/// entries and 8 bytes per direction; Tx 0x1A00 writable, 0x1A01 fixed, one PDO.
const LIMITS: PdoLimits = PdoLimits {
    drive: "fixture",
    rx: DirectionLimits {
        pdos: RX_RANGES,
        max_assigned: 2,
        max_entries: 3,
        max_bytes: 8,
    },
    tx: DirectionLimits {
        pdos: TX_RANGES,
        max_assigned: 1,
        max_entries: 8,
        max_bytes: 32,
    },
    assignment_writable: true,
};

#[test]
fn pdo_size_limits() {
    let mut od = store().with_limits(LIMITS);
    assert_eq!(od.limits(), Some(&LIMITS));
    // Assigned 0x1600: 6 bytes, 2 entries. Adding 0x60FF (4 bytes) → 10 bytes > 8.
    od.write(0x1600, 0, PRE, &[0]).unwrap();
    w32(&mut od, 0x1600, 3, 0x60FF_0020).unwrap();
    assert_eq!(
        od.write(0x1600, 0, PRE, &[3]),
        Err(SdoAbortCode::PDO_TOO_LONG)
    );
    // 2 + 4 + 1 bytes but 4 entries > 3.
    w32(&mut od, 0x1600, 2, 0x6060_0008).unwrap();
    w32(&mut od, 0x1600, 3, 0x6060_0008).unwrap();
    w32(&mut od, 0x1600, 4, 0x6060_0008).unwrap();
    assert_eq!(
        od.write(0x1600, 0, PRE, &[4]),
        Err(SdoAbortCode::PDO_TOO_LONG)
    );
    // More entries than the mapping object of the range holds (4): refused as too long too.
    w32(&mut od, 0x1600, 5, 0x6060_0008).unwrap();
    assert_eq!(
        od.write(0x1600, 0, PRE, &[5]),
        Err(SdoAbortCode::PDO_TOO_LONG)
    );
    od.write(0x1600, 0, PRE, &[3]).unwrap();
    // Assigning a second PDO that crosses the limit is refused at the assignment's sub 0.
    od.write(0x1601, 0, PRE, &[0]).unwrap();
    w32(&mut od, 0x1601, 1, 0x607A_0020).unwrap();
    od.write(0x1601, 0, PRE, &[1]).unwrap(); // not assigned: alone it fits
    od.write(0x1C12, 0, PRE, &[0]).unwrap();
    od.write(0x1C12, 2, PRE, &0x1601u16.to_le_bytes()).unwrap();
    assert_eq!(
        od.write(0x1C12, 0, PRE, &[2]),
        Err(SdoAbortCode::PDO_TOO_LONG)
    );
    od.write(0x1C12, 0, PRE, &[1]).unwrap();
    assert_eq!(od.mapping().unwrap().bytes(Direction::Rx), 4);
}

#[test]
fn pdo_assignment_and_fixed_mapping_limits() {
    let mut od = store().with_limits(LIMITS);
    // One TxPDO per SyncManager: sub 0 = 2 is too high even with valid entries.
    od.write(0x1C13, 0, PRE, &[0]).unwrap();
    od.write(0x1C13, 2, PRE, &0x1A01u16.to_le_bytes()).unwrap();
    assert_eq!(
        od.write(0x1C13, 0, PRE, &[2]),
        Err(SdoAbortCode::VALUE_TOO_HIGH)
    );
    // The fixed mapping 0x1A01 refuses writes, the writable 0x1A00 accepts them.
    assert_eq!(od.write(0x1A01, 0, PRE, &[0]), Err(SdoAbortCode::READ_ONLY));
    od.write(0x1A00, 0, PRE, &[0]).unwrap();
    // It can still be assigned (assignment_writable), alone.
    od.write(0x1C13, 1, PRE, &0x1A01u16.to_le_bytes()).unwrap();
    od.write(0x1C13, 0, PRE, &[1]).unwrap();
    assert_eq!(od.mapping().unwrap().tx[0].index, 0x1A01);
    // A fixed assignment refuses writes to 0x1C12/0x1C13.
    let mut fixed = store().with_limits(PdoLimits {
        assignment_writable: false,
        ..LIMITS
    });
    assert_eq!(
        fixed.write(0x1C12, 0, PRE, &[0]),
        Err(SdoAbortCode::READ_ONLY)
    );
}

// ---------------------------------------------------------------------------------------------
// Hooks: the MR-J4-TM behaviours as data, plus a computed read.

/// Statusword computed from the controlword on read (a stand-in for a device model).
struct ComputedStatusword;

impl OdHooks for ComputedStatusword {
    fn on_read(
        &mut self,
        dict: &ValueStore,
        addr: ObjectAddress,
        _state: AlState,
        buf: &mut [u8],
    ) -> Option<Result<usize, SdoAbortCode>> {
        if addr != ObjectAddress::new(0x6041, 0) {
            return None;
        }
        let cw = dict.uint(ObjectAddress::new(0x6040, 0)).unwrap_or(0) as u16;
        let sw: u16 = if cw & 0x000F == 0x000F {
            0x0237
        } else {
            0x0250
        };
        let dst = buf.get_mut(..2)?;
        dst.copy_from_slice(&sw.to_le_bytes());
        Some(Ok(2))
    }
}

static CYCLES: &[u64] = &[250_000, 500_000, 1_000_000, 2_000_000];
static AUTO_SET: &[ObjectAddress] = &[ObjectAddress::new(0x1C32, 3), ObjectAddress::new(0x1C33, 3)];

fn mrj4_like() -> OdStore {
    store().with_hooks(
        Chain::new()
            .with(RefuseMappedWrites {
                direction: Direction::Rx,
                code: SdoAbortCode::MAPPED_TO_RXPDO,
            })
            .with(AllowedValues {
                address: ObjectAddress::new(0x1C32, 2),
                values: CYCLES,
                code: SdoAbortCode::VALUE_RANGE,
            })
            .with(RefuseWrites {
                objects: &[0x607D],
                entries: AUTO_SET,
                code: SdoAbortCode::VALUE_RANGE,
            })
            .with(Mirror {
                a: ObjectAddress::new(0x1C32, 1),
                b: ObjectAddress::new(0x1C33, 1),
            })
            .with(Mirror {
                a: ObjectAddress::new(0x1C32, 2),
                b: ObjectAddress::new(0x1C33, 2),
            })
            .with(ComputedStatusword),
    )
}

#[test]
fn hook_refuses_writes_to_rxpdo_mapped_objects() {
    let mut od = mrj4_like();
    // 0x6040 and 0x607A are in the default RxPDO 0x1600.
    assert_eq!(
        od.write(0x6040, 0, PRE, &[0x0F, 0]),
        Err(SdoAbortCode::MAPPED_TO_RXPDO)
    );
    od.write(0x60FF, 0, PRE, &5i32.to_le_bytes()).unwrap();
    // Remap 0x60FF instead of 0x607A: now 0x607A is writable and 0x60FF is not.
    od.write(0x1600, 0, PRE, &[0]).unwrap();
    w32(&mut od, 0x1600, 2, 0x60FF_0020).unwrap();
    od.write(0x1600, 0, PRE, &[2]).unwrap();
    od.write(0x607A, 0, PRE, &5i32.to_le_bytes()).unwrap();
    assert_eq!(
        od.write(0x60FF, 0, PRE, &6i32.to_le_bytes()),
        Err(SdoAbortCode::MAPPED_TO_RXPDO)
    );
    // The device itself still writes mapped objects (that is how PDO data arrives).
    od.set_uint(a(0x6040, 0), 0x000F).unwrap();
}

#[test]
fn hooks_restrict_values_refuse_auto_set_objects_and_mirror() {
    let mut od = mrj4_like();
    assert_eq!(
        w32(&mut od, 0x1C32, 2, 300_000),
        Err(SdoAbortCode::VALUE_RANGE)
    );
    w32(&mut od, 0x1C32, 2, 500_000).unwrap();
    assert_eq!(od.uint(a(0x1C33, 2)), Some(500_000), "mirrored");
    assert_eq!(w32(&mut od, 0x1C32, 3, 0), Err(SdoAbortCode::VALUE_RANGE));
    assert_eq!(
        od.write(0x607D, 1, PRE, &0i32.to_le_bytes()),
        Err(SdoAbortCode::VALUE_RANGE)
    );
    od.write(0x1C33, 1, PRE, &2u16.to_le_bytes()).unwrap();
    assert_eq!(od.uint(a(0x1C32, 1)), Some(2), "mirrored the other way");
    // Hooks run after the length check: a 2-byte cycle time is "too short", not "range".
    assert_eq!(
        od.write(0x1C32, 2, PRE, &[0x20, 0xA1]),
        Err(SdoAbortCode::LENGTH_TOO_LOW)
    );
    // ... and after the access check: 0x1C32:02 in OP is a state error.
    assert_eq!(w32(&mut od, 0x1C32, 2, 1_000_000), Ok(()));
    assert_eq!(
        od.write(0x1C32, 2, AlState::Op, &250_000u32.to_le_bytes()),
        Err(SdoAbortCode::DEVICE_STATE)
    );
}

#[test]
fn hook_computes_a_value_on_read() {
    let mut od = mrj4_like();
    assert_eq!(read(&mut od, 0x6041, 0, PRE).unwrap(), [0x50, 0x02]);
    od.set_uint(a(0x6040, 0), 0x000F).unwrap();
    assert_eq!(read(&mut od, 0x6041, 0, PRE).unwrap(), [0x37, 0x02]);
}

#[test]
fn hook_aborts_reach_the_wire_unchanged() {
    let mut od = mrj4_like();
    let mut server = CoeServer::new(CoeConfig::default());
    let mut sm0 = [0u8; 64];
    sm0[..16].copy_from_slice(&coe_util::download_req(1, 0x6040, 0, &[0x0F, 0]));
    let mut sm1 = [0u8; 64];
    let n = server.handle(&sm0, PRE, &mut od, &mut sm1).unwrap();
    assert_eq!(
        sm1[..n],
        coe_util::abort_reply(1, 0x6040, 0, 0x0601_0006)[..]
    );
}

// ---------------------------------------------------------------------------------------------
// Device-side access and enumeration.

#[test]
fn device_side_values() {
    let mut od = store();
    assert_eq!(od.uint(a(0x1000, 0)), Some(0x0002_0192));
    assert_eq!(od.int(a(0x607D, 1)), Some(-1_000_000));
    assert_eq!(
        od.uint(a(0x607D, 1)),
        None,
        "signed entries have no uint view"
    );
    od.set_int(a(0x6064, 0), -5).unwrap();
    assert_eq!(od.raw(a(0x6064, 0)), Some(&(-5i32).to_le_bytes()[..]));
    assert_eq!(
        od.set_int(a(0x6060, 0), 200),
        Err(SdoAbortCode::VALUE_RANGE),
        "does not fit INTEGER8"
    );
    assert_eq!(
        od.set_raw(a(0x6064, 0), &[1, 2]),
        Err(SdoAbortCode::LENGTH_TOO_LOW)
    );
    assert_eq!(od.set_uint(a(0x9999, 0), 1), Err(SdoAbortCode::NO_OBJECT));
    assert_eq!(od.set_uint(a(0x1018, 9), 1), Err(SdoAbortCode::NO_SUBINDEX));
    // Read-only for the master, writable for the device.
    od.set_uint(a(0x1001, 0), 0x81).unwrap();
    assert_eq!(read(&mut od, 0x1001, 0, PRE).unwrap(), [0x81]);
    od.set_value(a(0x2004, 0), &Value::Str("abc".into()))
        .unwrap();
    assert_eq!(read(&mut od, 0x2004, 0, PRE).unwrap(), b"abc");
    od.restore_defaults();
    assert_eq!(od.uint(a(0x1001, 0)), Some(0));
    assert_eq!(od.value(a(0x2004, 0)), Some(Value::Str("hello".into())));
}

#[test]
fn enumeration_and_lists() {
    let od = store();
    let mut all = Vec::new();
    let mut at = od.next_index(None);
    while let Some(i) = at {
        all.push(i);
        at = od.next_index(Some(i));
    }
    assert_eq!(all.len(), fixture::OBJECTS.len());
    assert!(all.windows(2).all(|w| w[0] < w[1]));
    // Between existing indices, the next one up.
    assert_eq!(od.next_index(Some(0x1002)), Some(0x1008));
    assert_eq!(od.next_index(Some(0xFFFF)), None);
    assert!(od.in_list(0x6040, ListType::RxPdoMappable));
    assert!(!od.in_list(0x6040, ListType::TxPdoMappable));
    assert!(od.in_list(0x607D, ListType::Backup));
    assert!(!od.in_list(0x4444, ListType::All));
    let info = od.object(0x1C32).unwrap();
    assert_eq!(info.max_sub, 12);
    assert_eq!(
        ObjectStore::entry(&od, 0x1C32, 8),
        Err(SdoAbortCode::NO_SUBINDEX)
    );
}
