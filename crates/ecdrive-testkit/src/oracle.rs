//! The manuals' values for the identity objects, from `tests/manual_facts/`: what the reads
//! of the independent masters are compared with (never the emulation's own constants).

/// A number as the manual facts write it.
pub fn fact_number(v: &toml::Value) -> Option<u64> {
    match v {
        toml::Value::Integer(i) => u64::try_from(*i).ok(),
        toml::Value::String(s) => {
            let t = s.trim();
            match t.strip_prefix("0x") {
                Some(h) => u64::from_str_radix(h, 16).ok(),
                None => t.parse().ok(),
            }
        }
        _ => None,
    }
}

/// `(object, default)` from `tests/manual_facts/DRIVE.toml` for the identity and device-type
/// entries: the oracle the reads of independent masters (SOEM, KickCAT) are compared with.
pub fn oracle(drive: &str) -> Vec<((u16, u8), u64)> {
    let p = crate::repo().join(format!("tests/manual_facts/{drive}.toml"));
    let v: toml::Value = toml::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    let mut out = Vec::new();
    for f in v["fact"].as_array().unwrap() {
        let Some(obj) = f.get("object").and_then(|o| o.as_str()) else {
            continue;
        };
        if !["0x1000:00", "0x1018:01", "0x1018:02"].contains(&obj) {
            continue;
        }
        let Some(d) = f.get("default").and_then(fact_number) else {
            continue;
        };
        let (i, s) = obj.split_once(':').unwrap();
        let key = (
            u16::from_str_radix(i.trim_start_matches("0x"), 16).unwrap(),
            u8::from_str_radix(s, 16).unwrap(),
        );
        if !out.iter().any(|(k, _)| *k == key) {
            out.push((key, d));
        }
    }
    out
}

/// The transition facts of a drive's manual: (id, from, to, controlword, exists), the states
/// by their CiA 402 names ("Switch on disabled"), as written in `tests/manual_facts`.
#[allow(dead_code)]
pub fn transitions(drive: &str) -> Vec<(String, String, String, u16, bool)> {
    let p = crate::repo().join(format!("tests/manual_facts/{drive}.toml"));
    let v: toml::Value = toml::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    let name = |s: &str| {
        let n = s.to_ascii_lowercase().replace('_', " ");
        let mut c = n.chars();
        c.next()
            .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
            .unwrap_or_default()
    };
    let mut out = Vec::new();
    for f in v["fact"].as_array().unwrap() {
        if f.get("kind").and_then(|k| k.as_str()) != Some("transition") {
            continue;
        }
        let s = |k: &str| f.get(k).and_then(|x| x.as_str()).unwrap_or("").to_string();
        let cw = u16::from_str_radix(s("controlword").trim_start_matches("0x"), 16).unwrap();
        out.push((
            s("id"),
            name(&s("from")),
            name(&s("to")),
            cw,
            f.get("exists").and_then(|x| x.as_bool()).unwrap_or(true),
        ));
    }
    out
}
