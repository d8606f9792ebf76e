//! Mutated ESI files never make the parser, the checks or the conversions panic: byte-level
//! damage (mostly malformed XML) and value-level damage (well-formed XML with odd numbers,
//! keywords and structures).

use ecdrive_core::esi::EsiFile;
use proptest::prelude::*;

const FILES: [&str; 3] = [
    concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
        "/tests/data/esi/Acme_Terminals.xml"
    ),
    concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
        "/esi/Mitsubishi_MR-J4-TM.xml"
    ),
    concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
        "/esi/Servotronix_BDHDE.xml"
    ),
];

/// Replacement values for element texts and attribute values.
const TOKENS: [&str; 27] = [
    "",
    "0",
    "-1",
    "1",
    "255",
    "256",
    "65536",
    "#x",
    "#xFFFFFFFF",
    "#x100000000",
    "-2147483649",
    "99999999999999999999999999999999999999999",
    "0x7FFF",
    "true",
    "maybe",
    "é",
    "aéa",
    "RT",
    "rw",
    "PreOP_OP",
    "DT1018",
    "UINT",
    "STRING(0)",
    "  12  ",
    "&#x20;\u{3000}\u{3000}x",
    "<![CDATA[ #x10 ]]>",
    "&amp;",
];

/// Replacement structures, inserted at element boundaries.
const SNIPPETS: [&str; 8] = [
    "<Entry><Index>#x0</Index><BitLen>300</BitLen></Entry>",
    "<SubItem><Name>X</Name><Type>DT1018</Type><BitSize>8</BitSize></SubItem>",
    "<ArrayInfo><LBound>250</LBound><Elements>20</Elements></ArrayInfo>",
    "<ArrayInfo><LBound>0</LBound><Elements>0</Elements></ArrayInfo>",
    "<Sm StartAddress=\"1\" ControlByte=\"1\">Inputs</Sm>",
    "<Exclude>#x1600</Exclude>",
    "<DefaultData>0</DefaultData>",
    "</Device>",
];

fn exercise(bytes: &[u8]) {
    let Ok(f) = EsiFile::parse_bytes(bytes) else {
        return;
    };
    for i in f.check() {
        let _ = i.to_string();
    }
    for d in &f.devices {
        let _ = d.default_mapping();
        let rx: Vec<u16> = d.rx_pdos.iter().map(|p| p.index).collect();
        let tx: Vec<u16> = d.tx_pdos.iter().map(|p| p.index).collect();
        let _ = d.mapping(&rx, &tx);
        for m in &d.dc {
            for cycle in [0, 1, 1_000_000, u64::MAX] {
                let _ = m.mode.sync0_cycle_ns(cycle);
            }
            if let Some(c) = &m.allowed_cycle_times {
                let _ = (c.contains(0), c.contains(u32::MAX), c.min());
            }
        }
        if let Some(dict) = d.dictionary() {
            for o in &dict.objects {
                let _ = dict.resolve_object(o);
            }
        }
    }
}

#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Delete(usize, usize),
    Insert(usize, Vec<u8>),
    ElementText(usize, usize),
    AttributeValue(usize, usize),
    Snippet(usize, usize),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    // Weighted towards value-level damage, which gets past the XML parser.
    prop_oneof![
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::Flip(p, b)),
        1 => (any::<usize>(), 1usize..64).prop_map(|(p, n)| Mutation::Delete(p, n)),
        1 => (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(p, v)| Mutation::Insert(p, v)),
        6 => (any::<usize>(), 0..TOKENS.len()).prop_map(|(p, t)| Mutation::ElementText(p, t)),
        4 => (any::<usize>(), 0..TOKENS.len()).prop_map(|(p, t)| Mutation::AttributeValue(p, t)),
        3 => (any::<usize>(), 0..SNIPPETS.len()).prop_map(|(p, t)| Mutation::Snippet(p, t)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

/// Positions `i` where `bytes[i..]` starts with `pat`.
fn find_all(bytes: &[u8], pat: &[u8]) -> Vec<usize> {
    bytes
        .windows(pat.len())
        .enumerate()
        .filter(|(_, w)| *w == pat)
        .map(|(i, _)| i)
        .collect()
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let len = bytes.len();
    match m {
        Mutation::Flip(p, b) => bytes[p % len] = *b,
        Mutation::Delete(p, n) => {
            let s = p % len;
            let e = (s + n).min(len);
            bytes.drain(s..e);
        }
        Mutation::Insert(p, v) => {
            let s = p % len;
            bytes.splice(s..s, v.iter().copied());
        }
        Mutation::ElementText(p, t) => {
            // Replace the text after a '>' up to the next '<'.
            let starts = find_all(bytes, b">");
            if let Some(&s) = starts.get(p % starts.len().max(1)) {
                let e = bytes[s + 1..]
                    .iter()
                    .position(|&b| b == b'<')
                    .map(|x| s + 1 + x)
                    .unwrap_or(len);
                bytes.splice(s + 1..e, TOKENS[*t].bytes());
            }
        }
        Mutation::AttributeValue(p, t) => {
            let starts = find_all(bytes, b"=\"");
            if let Some(&s) = starts.get(p % starts.len().max(1)) {
                let v = s + 2;
                let e = bytes[v..]
                    .iter()
                    .position(|&b| b == b'"')
                    .map(|x| v + x)
                    .unwrap_or(len);
                bytes.splice(v..e, TOKENS[*t].bytes());
            }
        }
        Mutation::Snippet(p, t) => {
            let starts = find_all(bytes, b"</");
            if let Some(&s) = starts.get(p % starts.len().max(1)) {
                bytes.splice(s..s, SNIPPETS[*t].bytes());
            }
        }
        Mutation::Truncate(p) => bytes.truncate(p % len),
    }
}

// 256 cases each by default; set PROPTEST_CASES for a longer run.
proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]
    #[test]
    fn mutated_files_never_panic(
        file in 0..FILES.len(),
        muts in proptest::collection::vec(mutation(), 1..6),
    ) {
        let mut bytes = std::fs::read(FILES[file]).unwrap();
        for m in &muts {
            apply(&mut bytes, m);
        }
        exercise(&bytes);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        exercise(&bytes);
    }
}

#[test]
fn the_unmutated_files_parse() {
    for f in FILES {
        EsiFile::from_path(f).unwrap_or_else(|e| panic!("{e}"));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive_core::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    /// Nesting of any depth and attributes of any length: a file or one line of error, never
    /// a stack overflow or a panic; past the depth bound always the same error.
    #[test]
    fn deep_nesting_and_long_attributes_are_bounded(depth in 0usize..2_000, long in 0usize..20_000) {
        let text = format!(
            "<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>\
             <Type ProductCode=\"#x{}\">D</Type><Name a=\"{}\">N</Name>{}{}</Device></Devices>\
             </Descriptions></EtherCATInfo>",
            "1".repeat(long % 40 + 1),
            "v".repeat(long),
            "<x>".repeat(depth),
            "</x>".repeat(depth),
        );
        match EsiFile::parse(&text) {
            Ok(f) => prop_assert!(depth + 4 <= ecdrive_core::esi::MAX_DEPTH, "{} devices", f.devices.len()),
            Err(e) => {
                prop_assert_eq!(e.to_string().lines().count(), 1);
                if depth + 5 > ecdrive_core::esi::MAX_DEPTH {
                    prop_assert!(e.message.contains("nest deeper"), "{}", e);
                }
            }
        }
        exercise(text.as_bytes());
    }
}
