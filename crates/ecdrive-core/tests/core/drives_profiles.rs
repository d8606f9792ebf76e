//! The drive profiles: registry, dictionaries against the ESI files, identity, PDO data and DC
//! modes against the ESI files, start-up data against the dictionaries, synchronisation writes,
//! units and alarm decoding.

use ecdrive_core::drives::{self, CycleTimes, DriveProfile, StartupWhen, bdhde, generic, mr_j4_tm};
use ecdrive_core::esi::{self, EsiFile};
use ecdrive_core::od::{Dictionary, EntryAccess, ObjectAddress, Value};
use ecdrive_core::pdo::{Direction, RequiredObjects};

fn esi_device(p: &DriveProfile) -> esi::Device {
    let f: EsiFile = p
        .esi_file()
        .expect("profile has an ESI")
        .expect("ESI parses");
    assert_eq!(f.vendor.id, p.identity.vendor_id, "{}", p.name);
    f.device(p.identity.product_code, Some(p.revision))
        .unwrap_or_else(|| {
            panic!(
                "{}: the ESI has no device with the profile's identity",
                p.name
            )
        })
        .clone()
}

#[test]
fn registry_finds_profiles_by_identity_and_key() {
    let all = drives::all();
    assert_eq!(all.len(), 2);
    for p in all {
        assert!(std::ptr::eq(
            drives::by_identity(p.identity.vendor_id, p.identity.product_code).unwrap(),
            *p
        ));
        assert!(std::ptr::eq(drives::by_key(p.key).unwrap(), *p));
        assert!(std::ptr::eq(
            drives::by_key(&p.key.to_uppercase()).unwrap(),
            *p
        ));
    }
    assert_eq!(drives::by_key("mr-j4-tm").unwrap().name, "MR-J4-TM");
    assert_eq!(drives::by_key("bdhde").unwrap().name, "BDHDE");
    assert!(std::ptr::eq(
        drives::by_key("generic-cia402").unwrap(),
        &generic::GENERIC_CIA402
    ));
    assert!(drives::by_key("mr-j5").is_none());
    // Any revision matches.
    assert_eq!(
        drives::identify(0x0A1E, 0x0201, 0x0003_0000, false)
            .unwrap()
            .key,
        "mr-j4-tm"
    );
    // An unknown device is reported with its identity and the known drives, and runs with the
    // generic profile only on request.
    let e = drives::identify(0x0000_0ECD, 0x0000_0402, 0x0001_0000, false).unwrap_err();
    let text = e.to_string();
    for needle in [
        "vendor 0x00000ECD",
        "product 0x00000402",
        "revision 0x00010000",
        "MR-J4-TM",
        "BDHDE",
    ] {
        assert!(text.contains(needle), "{needle} in {text}");
    }
    assert_eq!(
        drives::identify(0x0000_0ECD, 0x0000_0402, 0, true)
            .unwrap()
            .key,
        "generic-cia402"
    );
    // The generic profile's identity matches nothing a registry lookup finds.
    assert!(drives::by_identity(0, 0).is_none());
}

#[test]
fn dictionaries_are_consistent() {
    for p in drives::all()
        .iter()
        .copied()
        .chain([&generic::GENERIC_CIA402])
    {
        let d = p.od();
        assert!(d.is_sorted(), "{}: sorted by index", p.name);
        let problems = d.problems();
        assert!(problems.is_empty(), "{}: {problems:#?}", p.name);
    }
}

/// Every object of the profile dictionary is in the ESI file and vice versa, and every entry
/// agrees: object code, sub-indices, type, bit length, access per state, PDO mappability, and
/// default / minimum / maximum where both state one.
#[test]
fn dictionaries_match_the_esi_files() {
    for p in drives::all() {
        let dev = esi_device(p);
        let esi_dict = dev.dictionary().expect("ESI dictionary");
        let resolved = esi_dict.resolve_all().unwrap();
        let mut esi_indices: Vec<u16> = resolved.iter().map(|o| o.index).collect();
        esi_indices.sort_unstable();
        let profile_indices: Vec<u16> = p.dictionary.iter().map(|o| o.index).collect();
        assert_eq!(esi_indices, profile_indices, "{}: the same objects", p.name);
        let mut diffs = Vec::new();
        for o in &resolved {
            let desc = p.od().object(o.index).unwrap();
            diffs.extend(
                o.compare(desc)
                    .into_iter()
                    .map(|d| format!("{}: {d}", p.name)),
            );
        }
        assert!(diffs.is_empty(), "{diffs:#?}");
    }
}

/// A drift between the ESI file and the profile is seen (the comparison can fail).
#[test]
fn a_changed_esi_value_is_reported() {
    let p = &mr_j4_tm::PROFILE;
    let text = p.esi.replacen(
        "<DefaultValue>#x00C00000</DefaultValue>",
        "<DefaultValue>#x00C00001</DefaultValue>",
        1,
    );
    assert_ne!(
        text, p.esi,
        "the 0x6065 default is written like this in the ESI"
    );
    let f = EsiFile::parse(&text).unwrap();
    let o = f.devices[0]
        .dictionary()
        .unwrap()
        .resolve(0x6065)
        .unwrap()
        .unwrap();
    let diffs = o.compare(p.od().object(0x6065).unwrap());
    assert_eq!(diffs.len(), 1, "{diffs:?}");
    assert_eq!(diffs[0].field, "default");
}

#[test]
fn identity_pdos_and_dc_modes_match_the_esi_files() {
    for p in drives::all() {
        let dev = esi_device(p);
        assert_eq!(dev.type_.revision_no, Some(p.revision), "{}", p.name);
        // The power-on assignment.
        let m = dev.default_mapping().unwrap();
        assert_eq!(m, p.default_mapping, "{}: default mapping", p.name);
        // Every PDO the ESI offers has the profile's power-on contents, and the profile's
        // limits hold every mapping object of the ESI.
        for dir in Direction::ALL {
            let (esi_pdos, profile_pdos) = match (p.key, dir) {
                ("mr-j4-tm", Direction::Rx) => (dev.pdos(dir), mr_j4_tm::RX_PDOS),
                ("mr-j4-tm", Direction::Tx) => (dev.pdos(dir), mr_j4_tm::TX_PDOS),
                ("bdhde", Direction::Rx) => (dev.pdos(dir), bdhde::RX_PDOS),
                (_, _) => (dev.pdos(dir), bdhde::TX_PDOS),
            };
            assert_eq!(esi_pdos.len(), profile_pdos.len(), "{} {dir}", p.name);
            for (e, q) in esi_pdos.iter().zip(profile_pdos) {
                assert_eq!(e.to_pdo(dir).unwrap(), *q, "{} {dir}", p.name);
                let range = p.pdo_limits.direction(dir).range_of(e.index).unwrap();
                assert!(q.entries.len() <= usize::from(range.max_entries));
            }
        }
        // DC modes: AssignActivate and the allowed cycle times; free run only if the profile
        // allows it.
        let dc = dev
            .dc
            .iter()
            .find(|m| m.mode.assign_activate != 0)
            .expect("a DC mode");
        assert_eq!(
            dc.mode.assign_activate, p.sync.assign_activate,
            "{}",
            p.name
        );
        assert!(dc.mode.sync0() && !dc.mode.sync1());
        assert_eq!(
            dev.dc.iter().any(|m| m.mode.assign_activate == 0),
            p.sync.free_run,
            "{}: free run",
            p.name
        );
        for m in &dev.dc {
            let allowed = m.allowed_cycle_times.as_ref().unwrap();
            match (allowed, p.sync.cycle_times) {
                (esi::CycleTimes::List(l), CycleTimes::List(q)) => assert_eq!(l.as_slice(), q),
                (
                    esi::CycleTimes::Range { min, max, step },
                    CycleTimes::Range {
                        min_ns,
                        max_ns,
                        step_ns,
                    },
                ) => assert_eq!((*min, *max, *step), (min_ns, max_ns, step_ns)),
                (a, b) => panic!("{}: {a:?} vs {b:?}", p.name),
            }
        }
        // Mailbox: complete access as the profile says.
        let coe = dev.mailbox.as_ref().unwrap().coe.as_ref().unwrap();
        assert_eq!(coe.complete_access, p.complete_access, "{}", p.name);
    }
}

#[test]
fn mappings_fit_the_limits_and_carry_what_the_modes_need() {
    for p in drives::all()
        .iter()
        .copied()
        .chain([&generic::GENERIC_CIA402])
    {
        let dict = Some(p.dictionary);
        if !p.default_mapping.rx.is_empty() {
            p.pdo_limits
                .validate(&p.default_mapping, dict)
                .unwrap_or_else(|e| panic!("{}: default mapping: {e}", p.name));
        }
        p.pdo_limits
            .validate(&p.cyclic_mapping, dict)
            .unwrap_or_else(|e| panic!("{}: cyclic mapping: {e}", p.name));
        for mode in [8, 9, 10] {
            RequiredObjects::find(p.required_objects, mode)
                .unwrap()
                .check(&p.cyclic_mapping, p.name)
                .unwrap();
        }
        // The cyclic mapping carries the error code, which no default map does.
        assert!(
            p.cyclic_mapping
                .contains(Direction::Tx, ObjectAddress::new(0x603F, 0))
        );
    }
}

#[test]
fn startup_data_fits_the_dictionaries() {
    for p in drives::all() {
        let d: Dictionary<'static> = p.od();
        for s in p.startup {
            let e = d
                .entry(s.address)
                .unwrap_or_else(|| panic!("{}: {} missing", p.name, s.address));
            assert!(e.access.contains(EntryAccess::WRITE_PREOP), "{}", s.address);
            let v = s.value.to_value().unwrap();
            let bytes = v.encode(e.data_type).unwrap();
            assert_eq!(bytes.len() * 8, usize::from(e.bit_len));
            if let (Some(x), Some(min)) = (v.as_i128(), e.min.as_i128()) {
                assert!(x >= min, "{}: {} below its minimum", p.name, s.address);
            }
            if let (Some(x), Some(max)) = (v.as_i128(), e.max.as_i128()) {
                assert!(x <= max, "{}: {} above its maximum", p.name, s.address);
            }
            assert!(!s.why.is_empty());
            if s.when == StartupWhen::IfNotMapped {
                assert!(e.access.contains(EntryAccess::RXPDO), "{}", s.address);
            }
        }
        for o in p.output_defaults {
            let e = d.entry(o.address).unwrap();
            assert!(e.access.contains(EntryAccess::RXPDO), "{}", o.address);
            assert!(o.value > 0, "{}: a non-zero output", o.address);
            assert!(Value::Int(o.value).encode(e.data_type).is_ok());
            assert!(p.default_mapping.contains(Direction::Rx, o.address));
        }
        if let Some(c) = p.cycle_counter {
            assert!(
                d.entry(c.output)
                    .unwrap()
                    .access
                    .contains(EntryAccess::RXPDO)
            );
            assert!(
                d.entry(c.echo.unwrap())
                    .unwrap()
                    .access
                    .contains(EntryAccess::TXPDO)
            );
        }
        // Every object the synchronisation set-up writes exists and is writable in PRE-OP.
        for w in p.sync_writes(1_000_000, true).unwrap() {
            let e = d.entry(w.address).unwrap();
            assert!(e.access.contains(EntryAccess::WRITE_PREOP), "{}", w.address);
        }
    }
    // The BDHDE's defaults are unusable and the start-up replaces them in a useful order: the
    // factor group first.
    let s = bdhde::STARTUP;
    assert_eq!(s[0].address, ObjectAddress::new(0x6091, 1));
    for a in [0x6065, 0x607F, 0x605A, 0x6085] {
        assert!(s.iter().any(|x| x.address.index == a), "0x{a:04X}");
    }
    // MR-J4-TM: the default map's speed and torque limits start non-zero.
    let outs: Vec<u16> = mr_j4_tm::OUTPUT_DEFAULTS
        .iter()
        .map(|o| o.address.index)
        .collect();
    assert_eq!(outs, [0x2D20, 0x60E0, 0x60E1]);
}

#[test]
fn sync_writes_per_drive() {
    let mr = &mr_j4_tm::PROFILE;
    let w = mr.sync_writes(1_000_000, true).unwrap();
    let got: Vec<(ObjectAddress, i64)> = w.iter().map(|w| (w.address, w.value)).collect();
    assert_eq!(
        got,
        [
            (ObjectAddress::new(0x1C32, 1), 2),
            (ObjectAddress::new(0x1C32, 2), 1_000_000)
        ]
    );
    let w = mr.sync_writes(250_000, false).unwrap();
    assert_eq!((w[0].value, w[1].value), (0, 250_000));
    let e = mr.sync_writes(750_000, true).unwrap_err();
    assert_eq!(
        e.to_string(),
        "the MR-J4-TM does not accept a cycle of 750000 ns; it accepts 250, 500, 1000, 2000 µs"
    );
    // The BDHDE: the standard form its own set-up example writes (1 and −3 for 1 ms), index
    // first, never −4 as a power of ten (the drive reads −4 as its 250 µs unit); no 0x1C32.
    let bd = &bdhde::PROFILE;
    for (cycle, value, index) in [
        (250_000, 25, -5),
        (500_000, 50, -5),
        (1_000_000, 1, -3),
        (1_250_000, 125, -5),
        (16_000_000, 16, -3),
    ] {
        let w = bd.sync_writes(cycle, true).unwrap();
        let got: Vec<(ObjectAddress, i64)> = w.iter().map(|w| (w.address, w.value)).collect();
        assert_eq!(
            got,
            [
                (ObjectAddress::new(0x60C2, 2), index),
                (ObjectAddress::new(0x60C2, 1), value)
            ],
            "{cycle} ns"
        );
    }
    // 2.75 ms has no standard form within UNSIGNED8: the drive's own unit (11 × 250 µs).
    let w = bd.sync_writes(2_750_000, true).unwrap();
    assert_eq!(
        (w.len(), w[0].address, w[0].value),
        (1, ObjectAddress::new(0x60C2, 1), 11)
    );
    assert!(bd.sync_writes(1_100_000, true).is_err());
    assert!(bd.sync_writes(16_250_000, true).is_err());
    let e = bd.sync_writes(1_000_000, false).unwrap_err();
    assert!(e.to_string().contains("DC SYNC0 only"), "{e}");
}

#[test]
fn units_and_alarm_names() {
    let u = mr_j4_tm::UNITS;
    // 3000 r/min = 300000 units of 0.01 r/min = 50 rev/s.
    assert_eq!(u.velocity_to_drive(50.0 * 4_194_304.0), 300_000);
    assert!((u.velocity_from_drive(300_000) - 50.0 * 4_194_304.0).abs() < 1e-6);
    let b = bdhde::UNITS;
    assert_eq!(b.position_per_rev, 1_048_576.0);
    assert_eq!(b.velocity_to_drive(1_048_576.0), 1_048_576);

    let d = mr_j4_tm::PROFILE.describe_error(0xFF86);
    assert_eq!((d.name, d.text), ("AL.86", "Network communication error"));
    // The warnings the MR-J4-TM manual names are in its table, with the manual's names
    // ([AL. 92 Battery cable disconnection warning], [AL. 9F Battery warning], line 1253;
    // [AL. E3 Absolute position counter warning], line 1276; [AL. F4 Positioning warning],
    // line 1153; [AL. 90 Home position return incomplete warning], line 1878).
    for (code, name, text) in [
        (0xFF90, "AL.90", "Home position return incomplete warning"),
        (0xFF92, "AL.92", "Battery cable disconnection warning"),
        (0xFF98, "AL.98", "Software limit warning"),
        (0xFF9F, "AL.9F", "Battery warning"),
        (0xFFE3, "AL.E3", "Absolute position counter warning"),
        (0xFFF4, "AL.F4", "Positioning warning"),
    ] {
        let d = mr_j4_tm::PROFILE.describe_error(code);
        assert_eq!((d.name, d.text), (name, text));
    }
    let d = bdhde::PROFILE.describe_error(0x8689);
    assert_eq!((d.name, d.text), ("J3 (FLT 87)", "Excessive PE Value"));
    // Shared codes name every fault they may be.
    let d = bdhde::PROFILE.describe_error(0x3199);
    assert!(d.text.contains("Regeneration fault") && d.text.contains("Regen Resistor Overload"));
    // Every row of the BDHDE table is a code of Table 10-4: 39 distinct codes.
    assert_eq!(bdhde::ERRORS.len(), 39);
    let mut codes: Vec<u16> = bdhde::ERRORS.iter().map(|e| e.code).collect();
    codes.dedup();
    assert_eq!(codes.len(), 39, "sorted and distinct");
}

/// A pp target is judged against the range the drive's manual gives 0x607A in pp, rounded as it
/// is written (the MR-J4-TM's ±999 999 pos units): the one check of the run file, start-up and
/// the axis. A drive without a narrower range takes any.
#[test]
fn pp_targets_are_judged_against_the_drives_range_as_written() {
    let caps = &mr_j4_tm::PROFILE.caps;
    assert_eq!(caps.pp_target_outside(999_999.4), None);
    assert_eq!(caps.pp_target_outside(-999_999.0), None);
    let range = caps.pp_target_outside(999_999.6).expect("beyond the range");
    assert_eq!((range.min, range.max), (-999_999, 999_999));
    assert!(caps.pp_target_outside(-1_000_000.0).is_some());
    assert_eq!(bdhde::PROFILE.caps.pp_target_outside(1e9), None);
}
