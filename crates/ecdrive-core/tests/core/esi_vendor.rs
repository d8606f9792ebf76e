//! The ESI parser on a hand-written file in the shape vendors publish (tests/data/esi/
//! Acme_Terminals.xml): several groups and devices, two revisions of one device, fixed and
//! alternative PDOs, CoE init commands, names in two languages, several DC modes, ISO-8859-1.

use ecdrive_core::esi::*;
use ecdrive_core::od::{
    ConstValue, DataType, EntryAccess, EntryDesc, ObjectCode, ObjectDesc, Value,
};
use ecdrive_core::pdo::{Direction, PdoEntry};

const PATH: &str = concat!(
    concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
    "/tests/data/esi/Acme_Terminals.xml"
);

fn file() -> EsiFile {
    EsiFile::from_path(PATH).unwrap_or_else(|e| panic!("{e}"))
}

fn ac3102(f: &EsiFile) -> &Device {
    f.device(0x0c1e_3052, Some(0x0014_0000)).expect("AC3102")
}

#[test]
fn vendor_groups_and_devices() {
    let f = file();
    assert_eq!(f.version.as_deref(), Some("1.6"));
    assert_eq!(f.vendor.id, 0x0ACE);
    assert_eq!(f.vendor.name, "Acme Fieldbus Components");
    assert_eq!(f.vendor.names.len(), 2);
    assert_eq!(f.vendor.names[1].lcid, Some(1031));
    assert_eq!(f.vendor.names[1].text, "Acme Feldbuskomponenten");

    let types: Vec<&str> = f.groups.iter().map(|g| g.type_.as_str()).collect();
    assert_eq!(types, ["SystemCouplers", "DigOut", "AnaIn", "Drives"]);
    // English preferred even when listed second; otherwise the first (here German, decoded
    // from ISO-8859-1).
    assert_eq!(f.group("SystemCouplers").unwrap().name, "Couplers");
    assert_eq!(f.group("AnaIn").unwrap().name, "Analoge Eingänge");
    assert_eq!(f.group("Drives").unwrap().names[0].lcid, None);

    assert_eq!(f.devices.len(), 4);
    let names: Vec<&str> = f
        .devices
        .iter()
        .map(|d| d.type_.name_text.as_str())
        .collect();
    assert_eq!(names, ["AC1100", "AC1100", "AC2004", "AC3102"]);
}

#[test]
fn revisions_of_one_product() {
    let f = file();
    assert_eq!(f.devices_with_product(0x044c_2c52).count(), 2);
    let old = f.device(0x044c_2c52, Some(0x0010_0000)).unwrap();
    assert_eq!(old.type_.revision_no, Some(0x0010_0000));
    // Without a revision: the last (newest) one.
    let newest = f.device(0x044c_2c52, None).unwrap();
    assert_eq!(newest.type_.revision_no, Some(0x0011_0000));
    assert!(f.device(0x044c_2c52, Some(0x0012_0000)).is_none());
    assert!(f.device(0x1234, None).is_none());

    assert_eq!(old.name, "AC1100 EtherCAT Coupler (2A E-Bus)");
    assert_eq!(old.names[1].text, "AC1100 EtherCAT-Koppler (2A E-Bus)");
    assert_eq!(old.physics.as_deref(), Some("YYK"));
    assert_eq!(old.group_type.as_deref(), Some("SystemCouplers"));
    assert!(old.sync_managers.is_empty() && old.mailbox.is_none() && old.dc.is_empty());
    let ee = old.eeprom.as_ref().unwrap();
    assert_eq!(ee.byte_size, Some(256));
    assert_eq!(ee.config_data, [4, 1, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn fixed_mandatory_output_pdos() {
    let f = file();
    let d = f.device(0x07d4_3052, None).unwrap();
    assert_eq!(d.name, "AC2004 4Ch. Dig. Output 24V, 0.5A");
    assert!(d.mailbox.is_none());
    assert!(!d.has_coe());
    assert_eq!(d.fmmus.len(), 1);
    assert_eq!(d.fmmus[0].usage, FmmuUsage::Outputs);
    let sm = d.sync_manager(SmKind::Outputs).unwrap();
    assert_eq!(
        (
            sm.index,
            sm.start_address,
            sm.control_byte,
            sm.enable,
            sm.default_size
        ),
        (0, 0x0F00, 0x44, true, Some(1))
    );
    assert_eq!(d.rx_pdos.len(), 4);
    assert!(
        d.rx_pdos
            .iter()
            .all(|p| p.fixed && p.mandatory && p.sm == Some(0))
    );
    assert!(d.tx_pdos.is_empty());

    let m = d.default_mapping().unwrap();
    let idx: Vec<u16> = m.rx.iter().map(|p| p.index).collect();
    assert_eq!(idx, [0x1600, 0x1601, 0x1602, 0x1603]);
    assert_eq!(m.rx[0].entries[..], [PdoEntry::new(0x7000, 1, 1)]);
    assert_eq!(
        m.rx[3].entries[..],
        [PdoEntry::new(0x7030, 1, 1), PdoEntry::padding(4)]
    );
    assert_eq!(m.bits(Direction::Rx), 8);
    assert_eq!(m.bytes(Direction::Rx), 1);
    assert_eq!(m.bytes(Direction::Tx), 0);
    let e = &d.rx_pdos[0].entries[0];
    assert_eq!(e.data_type(), Some(DataType::Boolean));
    assert_eq!(e.name, "Output");

    // Mandatory PDOs cannot be left out.
    assert_eq!(
        d.mapping(&[0x1600], &[]),
        Err(EsiConvertError::MissingMandatory {
            dir: "RxPDO",
            index: 0x1601
        })
    );
}

#[test]
fn alternative_pdos_with_exclude() {
    let f = file();
    let d = ac3102(&f);
    assert_eq!(d.name, "AC3102 2Ch. Ana. Input +/-10V, Diff.");
    assert_eq!(d.names[0].lcid, Some(1031));
    let tx: Vec<(u16, Option<u8>, Vec<u16>)> = d
        .tx_pdos
        .iter()
        .map(|p| (p.index, p.sm, p.excludes.clone()))
        .collect();
    assert_eq!(
        tx,
        [
            (0x1A00, Some(3), vec![0x1A01]),
            (0x1A01, None, vec![0x1A00]),
            (0x1A02, Some(3), vec![0x1A03]),
            (0x1A03, None, vec![0x1A02]),
        ]
    );
    assert_eq!(d.tx_pdos[0].name, "AI Standard Ch.1");

    // Default: the PDOs with an Sm attribute.
    let m = d.default_mapping().unwrap();
    assert!(m.rx.is_empty());
    let idx: Vec<u16> = m.tx.iter().map(|p| p.index).collect();
    assert_eq!(idx, [0x1A00, 0x1A02]);
    assert_eq!(
        m.tx[0].entries[..],
        [
            PdoEntry::new(0x6000, 1, 1),
            PdoEntry::new(0x6000, 2, 1),
            PdoEntry::padding(14),
            PdoEntry::new(0x6000, 0x11, 16),
        ]
    );
    assert_eq!(m.bytes(Direction::Tx), 8);

    // The compact alternative.
    let compact = d.mapping(&[], &[0x1A01, 0x1A03]).unwrap();
    assert_eq!(compact.bytes(Direction::Tx), 4);
    assert_eq!(compact.tx[1].entries[..], [PdoEntry::new(0x6010, 17, 16)]);
    assert_eq!(
        d.mapping(&[], &[0x1A00, 0x1A01]),
        Err(EsiConvertError::Excluded {
            dir: "TxPDO",
            a: 0x1A00,
            b: 0x1A01
        })
    );
    assert_eq!(
        d.mapping(&[], &[0x1A04]),
        Err(EsiConvertError::UnknownPdo {
            dir: "TxPDO",
            index: 0x1A04
        })
    );
    assert_eq!(
        d.mapping(&[], &[0x1A01, 0x1A01]),
        Err(EsiConvertError::Duplicate {
            dir: "TxPDO",
            index: 0x1A01
        })
    );
}

#[test]
fn sync_managers_fmmus_eeprom() {
    let f = file();
    let d = ac3102(&f);
    let sms: Vec<_> = d
        .sync_managers
        .iter()
        .map(|s| {
            (
                s.index,
                s.kind,
                s.start_address,
                s.default_size,
                s.control_byte,
                s.enable,
            )
        })
        .collect();
    assert_eq!(
        sms,
        [
            (0, SmKind::MBoxOut, 0x1000, Some(128), 0x26, true),
            (1, SmKind::MBoxIn, 0x1080, Some(128), 0x22, true),
            (2, SmKind::Outputs, 0x1100, None, 0x24, false),
            (3, SmKind::Inputs, 0x1180, None, 0x20, true),
        ]
    );
    assert_eq!(d.sync_managers[0].min_size, Some(34));
    assert_eq!(d.sync_managers[0].max_size, Some(128));
    let sii: Vec<(u8, u8)> = d
        .sync_managers
        .iter()
        .map(|s| (s.kind.sii_type(), s.sii_enable()))
        .collect();
    assert_eq!(sii, [(1, 1), (2, 1), (3, 0), (4, 1)]);
    let fmmu: Vec<u8> = d.fmmus.iter().map(|f| f.usage.sii_code()).collect();
    assert_eq!(fmmu, [1, 2, 3]);

    let ee = d.eeprom.as_ref().unwrap();
    assert_eq!(ee.byte_size, Some(2048));
    assert_eq!(ee.config_data, [0x08, 0x0C, 0, 0, 0xE8, 0x03, 0, 0]);
    assert_eq!(
        ee.boot_strap,
        [0x00, 0x10, 0xF4, 0x00, 0xF4, 0x10, 0xF4, 0x00]
    );
    assert_eq!(
        ee.categories,
        [EepromCategory {
            cat_no: 1,
            data: vec![0x0A, 0x0B]
        }]
    );
}

#[test]
fn mailbox_coe_and_init_commands() {
    let f = file();
    let d = ac3102(&f);
    assert!(d.has_coe());
    let mb = d.mailbox.as_ref().unwrap();
    assert_eq!(mb.protocols, MailboxProtocols::COE | MailboxProtocols::FOE);
    assert!(mb.data_link_layer);
    let coe = mb.coe.as_ref().unwrap();
    assert!(coe.sdo_info && coe.pdo_assign && coe.pdo_upload);
    assert!(!coe.pdo_config && !coe.complete_access);
    assert!(coe.segmented_sdo, "SegmentedSdo defaults to true");
    // SII CoE details: SDO | SDO info | PDO assign | PDO upload.
    assert_eq!(coe.sii_byte(), 0x01 | 0x02 | 0x04 | 0x10);

    assert_eq!(mb.init_cmds.len(), 3);
    let c = &mb.init_cmds[0];
    assert_eq!(
        (c.transitions.as_slice(), c.index, c.sub, c.data.as_slice()),
        ([Transition::PS].as_slice(), 0x1C13, 0, [0u8].as_slice())
    );
    assert_eq!(c.comment, "clear sm pdos (0x1C13)");
    assert!(!c.fixed && !c.complete_access);
    assert!(mb.init_cmds[1].fixed);
    assert_eq!(mb.init_cmds[1].data, [0x00, 0x1A]);
    let c = &mb.init_cmds[2];
    assert_eq!(c.transitions, [Transition::IP, Transition::PS]);
    assert_eq!((c.index, c.sub), (0x8000, 0x15));
    assert!(c.complete_access);
    assert_eq!(c.comment, "filter settings");
}

#[test]
fn several_dc_op_modes() {
    let f = file();
    let d = ac3102(&f);
    let names: Vec<&str> = d.dc.iter().map(|m| m.mode.name.as_str()).collect();
    assert_eq!(names, ["Synchron", "DcSync", "DcSyncInput"]);

    let sm = d.dc_op_mode("synchron").unwrap();
    assert_eq!(sm.mode.description, "SM-Synchron");
    assert_eq!(sm.mode.assign_activate, 0);
    assert!(!sm.mode.cyclic() && !sm.mode.sync0() && !sm.mode.sync1());

    let dc = d.dc_op_mode("DcSync").unwrap();
    assert_eq!(dc.mode.assign_activate, 0x0700);
    assert!(dc.mode.cyclic() && dc.mode.sync0() && dc.mode.sync1());
    assert_eq!(dc.mode.sync0_cycle_factor, 1);
    assert_eq!(dc.mode.sync0_cycle_ns(1_000_000), 1_000_000);
    assert_eq!(dc.mode.sync1_cycle_factor, 1);
    assert!(dc.allowed_cycle_times.is_none());

    let inp = d.dc_op_mode("DcSyncInput").unwrap();
    assert_eq!(inp.mode.sync0_cycle_factor, -2);
    assert_eq!(inp.mode.sync0_cycle_ns(1_000_000), 500_000);
    assert_eq!(inp.mode.shift_time0, -5000);
    assert_eq!(inp.shift_time_sync0_factor, Some(1));
    assert!(inp.shift_time_sync0_input);
    assert_eq!(inp.mode.sync1_cycle_factor, 2);
    assert_eq!(inp.mode.shift_time1, 2000);
    assert_eq!(
        inp.sms,
        [DcSm {
            no: 3,
            sync_type: Some(2),
            cycle_time: Some(0),
            shift_time: Some(0),
            pdos: vec![0x1A00, 0x1A02],
        }]
    );
}

#[test]
fn dictionary_resolves_var_record_array() {
    let f = file();
    let d = ac3102(&f);
    assert_eq!(d.profiles.len(), 1);
    assert_eq!(d.profiles[0].profile_no, Some(5001));
    assert_eq!(d.profiles[0].add_info, Some(0));
    let dict = d.dictionary().unwrap();
    assert_eq!(dict.objects.len(), 8);
    assert!(dict.data_type("DT1018").is_some());

    let o = dict.resolve(0x1000).unwrap().unwrap();
    assert_eq!(o.code, ObjectCode::Var);
    assert_eq!(o.entries.len(), 1);
    let e = &o.entries[0];
    assert_eq!(
        (e.sub, e.data_type, e.bit_len),
        (0, Some(DataType::Unsigned32), 32)
    );
    assert_eq!(e.default, Some(Value::Uint(0x1389)));
    assert_eq!(e.access, EntryAccess::RO);

    let o = dict.resolve(0x1008).unwrap().unwrap();
    assert_eq!(o.entries[0].data_type, Some(DataType::VisibleString));
    assert_eq!(o.entries[0].bit_len, 48);
    assert_eq!(o.entries[0].default, Some(Value::Str("AC3102".into())));

    let o = dict.resolve(0x1018).unwrap().unwrap();
    assert_eq!(o.code, ObjectCode::Record);
    let subs: Vec<u8> = o.entries.iter().map(|e| e.sub).collect();
    assert_eq!(subs, [0, 1, 2, 3, 4]);
    assert_eq!(o.entry(1).unwrap().name, "Vendor ID");
    assert_eq!(o.entry(1).unwrap().default, Some(Value::Uint(0x0ACE)));
    assert_eq!(o.entry(2).unwrap().default, Some(Value::Uint(0x0c1e_3052)));

    // An ETG-style array: sub 0 plus an array-typed sub-item expanded from LBound.
    let o = dict.resolve(0x1C13).unwrap().unwrap();
    assert_eq!(o.code, ObjectCode::Array);
    let subs: Vec<(u8, Option<DataType>, u32)> = o
        .entries
        .iter()
        .map(|e| (e.sub, e.data_type, e.bit_len))
        .collect();
    assert_eq!(
        subs,
        [
            (0, Some(DataType::Unsigned8), 8),
            (1, Some(DataType::Unsigned16), 16),
            (2, Some(DataType::Unsigned16), 16),
        ]
    );
    assert_eq!(o.entry(2).unwrap().default, Some(Value::Uint(0x1A02)));
    assert_eq!(o.entry(0).unwrap().access, EntryAccess::RW);
    // WriteRestrictions="PreOP".
    assert_eq!(o.entry(1).unwrap().access, EntryAccess::RW_PREOP);

    // A record with a gap sub-item (no SubIdx) and sparse sub-indices.
    let o = dict.resolve(0x6000).unwrap().unwrap();
    let subs: Vec<u8> = o.entries.iter().map(|e| e.sub).collect();
    assert_eq!(subs, [0, 1, 2, 17]);
    assert_eq!(o.entry(0).unwrap().default, Some(Value::Uint(17)));
    let v = o.entry(17).unwrap();
    assert_eq!(v.data_type, Some(DataType::Integer16));
    assert_eq!(v.access, EntryAccess::RO | EntryAccess::TXPDO);

    let o = dict.resolve(0x8000).unwrap().unwrap();
    let filt = o.entry(6).unwrap();
    assert_eq!(
        filt.access,
        EntryAccess::R
            | EntryAccess::WRITE_PREOP
            | EntryAccess::WRITE_SAFEOP
            | EntryAccess::BACKUP
            | EntryAccess::SETTINGS
    );
    assert_eq!(filt.default, Some(Value::Uint(1)));
    let s = o.entry(21).unwrap();
    assert_eq!(
        (s.min.clone(), s.max.clone(), s.default.clone()),
        (
            Some(Value::Uint(0)),
            Some(Value::Uint(7)),
            Some(Value::Uint(0))
        )
    );
    assert!(dict.resolve(0x9999).is_none());
    assert_eq!(dict.resolve_all().unwrap().len(), 8);
}

static SETTINGS_ENTRIES: [EntryDesc; 3] = [
    EntryDesc::new(0, "Number of entries", DataType::Unsigned8, EntryAccess::RO)
        .default(ConstValue::Uint(21)),
    EntryDesc::new(
        6,
        "Enable filter",
        DataType::Boolean,
        EntryAccess::from_bits_truncate(
            EntryAccess::R.bits()
                | EntryAccess::WRITE_PREOP.bits()
                | EntryAccess::WRITE_SAFEOP.bits(),
        ),
    )
    .default(ConstValue::Uint(1)),
    EntryDesc::new(21, "Filter settings", DataType::Unsigned16, EntryAccess::RW)
        .range(ConstValue::Uint(0), ConstValue::Uint(7)),
];

#[test]
fn compare_with_profile_descriptions() {
    let f = file();
    let dict = ac3102(&f).dictionary().unwrap();
    let o = dict.resolve(0x8000).unwrap().unwrap();
    let same = ObjectDesc {
        index: 0x8000,
        name: "Settings",
        code: ObjectCode::Record,
        entries: &SETTINGS_ENTRIES,
    };
    assert_eq!(o.compare(&same), []);

    static OTHER: [EntryDesc; 2] = [
        EntryDesc::new(0, "n", DataType::Unsigned8, EntryAccess::RO).default(ConstValue::Uint(2)),
        EntryDesc::new(
            21,
            "Filter settings",
            DataType::Unsigned32,
            EntryAccess::RW_PREOP,
        )
        .range(ConstValue::Uint(0), ConstValue::Uint(9)),
    ];
    let other = ObjectDesc {
        index: 0x8000,
        name: "Settings",
        code: ObjectCode::Array,
        entries: &OTHER,
    };
    let diffs = o.compare(&other);
    let fields: Vec<(Option<u8>, &str)> = diffs.iter().map(|d| (d.sub, d.field)).collect();
    assert_eq!(
        fields,
        [
            (None, "code"),
            (Some(0), "default"),
            (Some(6), "entry"),
            (Some(21), "data type"),
            (Some(21), "bit length"),
            (Some(21), "access"),
            (Some(21), "max"),
        ]
    );
    assert_eq!(diffs[1].to_string(), "0x8000:00 default: ESI 21, profile 2");
}

#[test]
fn consistent_file_has_no_check_issues() {
    let f = file();
    let issues: Vec<String> = f.check().iter().map(|i| i.to_string()).collect();
    assert!(issues.is_empty(), "{issues:#?}");
}

#[test]
fn latin1_and_utf8_copies_parse_the_same() {
    let bytes = std::fs::read(PATH).unwrap();
    assert!(
        std::str::from_utf8(&bytes).is_err(),
        "the test file is ISO-8859-1"
    );
    let text: String = bytes.iter().map(|&b| char::from(b)).collect();
    let utf8 = text.replace("ISO-8859-1", "UTF-8");
    assert_eq!(EsiFile::parse(&utf8).unwrap(), file());
    // With a UTF-8 byte-order mark too.
    let mut bom = vec![0xEF, 0xBB, 0xBF];
    bom.extend_from_slice(utf8.as_bytes());
    assert_eq!(EsiFile::parse_bytes(&bom).unwrap(), file());
}

#[test]
fn a_cycle_factor_the_sii_cannot_carry_is_refused_by_name() {
    // The SII's DC category holds the SYNC0/SYNC1 cycle factors as INT16 (ETG.2010), so the one
    // DC mode type keeps them as i16 and the parser leaves a mode with a larger one out, with a
    // warning where it stands (the device keeps its other modes).
    let bytes = std::fs::read(PATH).unwrap();
    let text: String = bytes.iter().map(|&b| char::from(b)).collect();
    let text = text.replacen(
        r#"<CycleTimeSync0 Factor="-2">"#,
        r#"<CycleTimeSync0 Factor="40000">"#,
        1,
    );
    let f = EsiFile::parse(&text).unwrap();
    let dev = f
        .devices
        .iter()
        .find(|d| d.type_.name_text == "AC3102")
        .unwrap();
    assert!(dev.dc_op_mode("DcSyncInput").is_none());
    assert!(dev.dc_op_mode("DcSync").is_some());
    assert_eq!(f.warnings.len(), 1, "{:?}", f.warnings);
    let e = f.warnings[0].to_string();
    assert!(e.contains("Factor") && e.contains("DcSyncInput"), "{e}");
    assert!(e.contains("16-bit"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}
