//! Every real vendor EDS/DCF file of the corpus (`../shared/eds-corpus`, its `MANIFEST.tsv`
//! naming each file's source), read by the EDS reader: no file is refused, the identity each
//! file declares is the one its manifest row records, every file the manifest marks as having
//! 6040h/6041h is a CiA 402 drive to the reader, and the three project drives' files give the
//! values their manuals and the corpus README name, and disagree with the manuals only where
//! `tests/manual_facts/vendor-eds.toml` says so, with both readings. Cut and damaged copies of
//! every file never panic the reader (seeded; `ECDRIVE_SEED` replays a run).

use crate::support;

use ecdrive_core::eds::EdsFile;

fn num(s: &str) -> Option<i128> {
    let t = s.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => i128::from_str_radix(h, 16).ok(),
        None => t.parse().ok(),
    }
}

#[test]
fn every_vendor_file_reads_with_its_identity() {
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let rows = support::corpus::manifest(&dir);
    assert!(rows.len() >= 28, "{} files in the manifest", rows.len());
    let mut drives = 0;
    for row in &rows {
        let path = dir.join(&row["path"]);
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let f = EdsFile::parse(&bytes).unwrap_or_else(|e| panic!("{}: {e}", row["path"]));
        if let Some(v) = num(&row["vendor_number"]) {
            assert_eq!(
                f.device.vendor_number.map(i128::from),
                Some(v),
                "{}: VendorNumber",
                row["path"]
            );
        }
        if let Some(p) = num(&row["product_number"]) {
            assert_eq!(
                f.device.product_number.map(i128::from),
                Some(p),
                "{}: ProductNumber",
                row["path"]
            );
        }
        if row["has_6040"] == "yes" && row["has_6041"] == "yes" {
            assert!(
                f.is_cia402(),
                "{}: not a CiA 402 drive to the reader",
                row["path"]
            );
            assert!(
                !f.mappable(true).is_empty() && !f.mappable(false).is_empty(),
                "{}: nothing mappable",
                row["path"]
            );
            drives += 1;
        }
        eprintln!(
            "{}: {} objects, {} warnings",
            row["path"],
            f.objects.len(),
            f.warnings.len()
        );
    }
    assert!(drives >= 25, "{drives} CiA 402 drives");
}

/// The project's three CANopen drives, from their vendors' files: the values the corpus README
/// records and where they differ from the manuals (the Lexium MDrive's identity: the file's
/// 1018h:01 is the LSS vendor ID of its manual's §5.6, 0800005Ah, not the 021Bh of §8.5.16).
#[test]
fn the_project_drives_files_give_their_identity_and_modes() {
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let read = |p: &str| EdsFile::parse(&std::fs::read(dir.join(p)).unwrap()).unwrap();
    let v200 = read("oriental-motor/BLVD-KRD_CANopen_V200.eds");
    assert_eq!(v200.device.vendor_number, Some(702));
    assert_eq!(v200.device.product_number, Some(5111));
    assert_eq!(v200.supported_modes(), Some(0x25));
    let v400 = read("oriental-motor/BLVD-KRD_CANopen_V400.eds");
    assert_eq!(v400.supported_modes(), Some(0x2D), "V400 adds tq");
    let asda = read("delta/ASDA_A2_1042sub980_C.eds");
    assert_eq!(asda.device.vendor_number, Some(0x1DD));
    assert_eq!(asda.device.product_number, Some(0x6000));
    assert_eq!(asda.device.revision_number, Some(0x0200_0001));
    assert_eq!(
        asda.entry(0x1000, 0).and_then(|e| e.default.resolve(1)),
        Some(0x0402_0192)
    );
    let lexium = read("schneider-electric-motion-usa/NEMA23_7_23_12.eds");
    assert_eq!(
        lexium.entry(0x1018, 1).and_then(|e| e.default.resolve(1)),
        Some(0x0800_005A)
    );
    assert_eq!(lexium.supported_modes(), Some(0xAD));
    for f in [&v200, &v400, &asda, &lexium] {
        assert!(f.is_cia402());
        // The RPDO COB-IDs are node-ID formulas: node 5's first RPDO listens at 0x205.
        assert_eq!(
            f.entry(0x1400, 1)
                .and_then(|e| e.default.resolve(5))
                .map(|v| v & 0x7FF),
            Some(0x205),
            "{:?}",
            f.entry(0x1400, 1)
        );
    }
}

/// Damaged copies of every vendor file — cut at eight places, and with bytes overwritten at
/// random (the seed printed; `ECDRIVE_SEED` replays it) — are read or refused in one error,
/// never a panic.
#[test]
fn cut_and_damaged_vendor_files_never_panic() {
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let seed = ecdrive_core::rt::audit::test_seed(file!());
    let mut state = seed | 1;
    let mut next = move || {
        // xorshift64
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for row in support::corpus::manifest(&dir) {
        let bytes = std::fs::read(dir.join(&row["path"])).unwrap();
        for k in 1..8 {
            let _ = EdsFile::parse(&bytes[..bytes.len() * k / 8]);
        }
        for _ in 0..16 {
            let mut b = bytes.clone();
            for _ in 0..32 {
                let at = (next() as usize) % b.len().max(1);
                if let Some(x) = b.get_mut(at) {
                    *x = next() as u8;
                }
            }
            let _ = EdsFile::parse(&b);
        }
    }
}

/// A value as the facts and the discrepancy list write it: a number (decimal or 0x hex), else
/// the text.
fn reading(s: &str) -> Result<i128, String> {
    num(s).ok_or_else(|| s.trim().to_string())
}

/// Where the three project drives' vendor EDS files disagree with their manuals: every object
/// fact of a manual (`tests/manual_facts/DRIVE.toml`) compared with the vendor file's
/// DefaultValue. Each disagreement must be listed, with both readings, in
/// `tests/manual_facts/vendor-eds.toml`; an entry that no longer disagrees fails too.
#[test]
fn the_vendor_files_disagree_with_the_manuals_only_where_listed() {
    let Some(dir) = support::corpus::eds_dir() else {
        return;
    };
    let root = ecdrive_testkit::repo().join("tests/manual_facts");
    let list: toml::Value = toml::from_str(
        &std::fs::read_to_string(root.join("vendor-eds.toml")).expect("vendor-eds.toml"),
    )
    .expect("vendor-eds.toml is TOML");
    let str_of = |v: &toml::Value, k: &str| {
        v.get(k)
            .and_then(toml::Value::as_str)
            .unwrap_or_default()
            .to_string()
    };
    let listed: Vec<(String, String, String, String)> = list
        .get("discrepancy")
        .and_then(toml::Value::as_array)
        .into_iter()
        .flatten()
        .map(|d| {
            assert!(!str_of(d, "why").is_empty(), "{d:?}: say why");
            (
                str_of(d, "drive"),
                str_of(d, "fact"),
                str_of(d, "manual"),
                str_of(d, "eds"),
            )
        })
        .collect();
    let mut found = Vec::new();
    let files = list
        .get("file")
        .and_then(toml::Value::as_array)
        .expect("[[file]]");
    for f in files {
        let (drive, path) = (str_of(f, "drive"), str_of(f, "eds"));
        let eds = EdsFile::parse(&std::fs::read(dir.join(&path)).expect("file")).expect("read");
        let facts: toml::Value = toml::from_str(
            &std::fs::read_to_string(root.join(format!("{drive}.toml"))).expect("facts"),
        )
        .expect("facts are TOML");
        let mut compared = 0;
        for fact in facts
            .get("fact")
            .and_then(toml::Value::as_array)
            .expect("facts")
        {
            if str_of(fact, "kind") != "object" {
                continue;
            }
            let Some(default) = fact.get("default").and_then(toml::Value::as_str) else {
                continue;
            };
            let object = str_of(fact, "object");
            let (i, s) = object.split_once(':').expect("0xIIII:SS");
            let index = u16::from_str_radix(i.trim_start_matches("0x"), 16).expect("index");
            let sub = u8::from_str_radix(s, 16).expect("sub");
            let entry = eds.entry(index, sub);
            let Some(e) = entry else {
                found.push((
                    drive.clone(),
                    str_of(fact, "id"),
                    default.to_string(),
                    "absent".into(),
                ));
                continue;
            };
            let theirs = match &e.default {
                // The file says nothing, or a node-ID formula (the manual writes those for
                // node 0 in words).
                ecdrive_core::eds::EdsValue::None | ecdrive_core::eds::EdsValue::NodeId { .. } => {
                    continue;
                }
                ecdrive_core::eds::EdsValue::Int(v) => Ok(*v),
                ecdrive_core::eds::EdsValue::Text(t) => Err(t.trim().to_string()),
                ecdrive_core::eds::EdsValue::Real(r) => Err(r.to_string()),
            };
            compared += 1;
            if reading(default) != theirs {
                let shown = match theirs {
                    Ok(v) => v.to_string(),
                    Err(t) => t,
                };
                found.push((
                    drive.clone(),
                    str_of(fact, "id"),
                    default.to_string(),
                    shown,
                ));
            }
        }
        assert!(
            compared > 30,
            "{drive}: only {compared} facts compared with {path}"
        );
    }
    let same = |a: &(String, String, String, String), b: &(String, String, String, String)| {
        a.0 == b.0 && a.1 == b.1 && reading(&a.2) == reading(&b.2) && reading(&a.3) == reading(&b.3)
    };
    let unlisted: Vec<String> = found
        .iter()
        .filter(|f| !listed.iter().any(|l| same(f, l)))
        .map(|(d, id, m, e)| format!("{d} {id}: manual {m:?}, vendor file {e:?}"))
        .collect();
    let stale: Vec<String> = listed
        .iter()
        .filter(|l| !found.iter().any(|f| same(f, l)))
        .map(|(d, id, m, e)| format!("{d} {id}: manual {m:?}, vendor file {e:?}"))
        .collect();
    assert!(
        unlisted.is_empty() && stale.is_empty(),
        "vendor file and manual disagree where tests/manual_facts/vendor-eds.toml does not say \
         so:\n{}\n\nlisted but no longer disagreeing:\n{}",
        unlisted.join("\n"),
        stale.join("\n")
    );
}
