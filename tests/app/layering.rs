//! The layering of ARCHITECTURE.md, checked on the sources and the manifests. The layers are
//! crates, so the compiler keeps each from reaching anything above it; these tests keep the
//! manifests from gaining an arrow upwards or sideways:
//!
//! - the core (`ec`, `od`, `pdo`, `cia402`, `esi`, `eds`, `drives`, `link`, `rt`, `can`) is
//!   the crate `ecdrive-core`: no bus master, no async runtime, no CLI, no other ecdrive crate;
//! - the software slave is the crate `ecdrive-sim`: the core only, without the master's drive
//!   profiles (`crates/ecdrive-sim/tests/sim/emulation_independence.rs`);
//! - the EtherCAT master (`ecdrive-ethercat`) and the CANopen master (`ecdrive-canopen`): the
//!   core and the motion runtime (`ecdrive-motion`, itself the core only);
//! - the library `ecdrive` is a façade: it re-exports those crates and holds no code;
//! - the application, the package `ecdrive-cli` (the `ecdrive` command), may use everything;
//!   no library crate depends on it, nor on the test helpers (`ecdrive-testkit`).

use crate::support::source_scan;

use std::path::Path;

/// The library crates: the façade and what it re-exports.
const LIBRARY: &[&str] = &[
    "crates/ecdrive",
    "crates/ecdrive-core",
    "crates/ecdrive-sim",
    "crates/ecdrive-ethercat",
    "crates/ecdrive-canopen",
    "crates/ecdrive-motion",
];

/// The library is a façade over the crates: its sources re-export them and document, nothing
/// else (no function, type, implementation or value of its own).
#[test]
fn the_library_is_a_facade_over_the_crates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = source_scan::rust_files(&root.join("crates/ecdrive/src"));
    assert!(files.len() >= 3, "{files:?}");
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        for (i, line) in text.lines().enumerate() {
            let code = code_of(line);
            let code = code.trim();
            let own = [
                "fn ",
                "impl ",
                "static ",
                "const ",
                "enum ",
                "trait ",
                "macro_rules!",
            ]
            .iter()
            .any(|k| code.starts_with(k) || code.starts_with(&format!("pub {k}")))
                || (code.starts_with("pub struct") || code.starts_with("struct "))
                    && !code.ends_with("Doctests;");
            if own {
                found.push(format!("{}:{}: {code}", f.display(), i + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "the library façade holds code of its own (it belongs in one of the crates):\n{}",
        found.join("\n")
    );
}

/// The façade depends on the library crates and nothing else; no library crate depends on the
/// application or on the test helpers (those only as development dependencies).
#[test]
fn no_library_crate_depends_on_the_application_or_the_test_helpers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let facade = dependencies(&root.join("crates/ecdrive/Cargo.toml"));
    let expected: Vec<String> = LIBRARY[1..]
        .iter()
        .map(|d| d.trim_start_matches("crates/").to_string())
        .collect();
    let mut sorted = facade.clone();
    sorted.sort();
    let mut want = expected.clone();
    want.sort();
    assert_eq!(sorted, want, "the façade's dependencies");
    for dir in LIBRARY {
        let deps = dependencies(&root.join(dir).join("Cargo.toml"));
        let bad: Vec<&String> = deps
            .iter()
            .filter(|d| *d == "ecdrive-cli" || *d == "ecdrive-testkit")
            .collect();
        assert!(bad.is_empty(), "{dir} depends on {bad:?}");
    }
    // The application stands on the façade.
    assert!(dependencies(&root.join("Cargo.toml")).contains(&"ecdrive".to_string()));
}

/// The dependencies (normal ones) of the manifest at `path`.
fn dependencies(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc: toml::Table = text
        .parse()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    doc.get("dependencies")
        .and_then(|d| d.as_table())
        .map(|t| t.keys().cloned().collect())
        .unwrap_or_default()
}

/// Crates the core may never depend on.
const NOT_IN_CORE: &[&str] = &[
    "ethercrab",
    "tokio",
    "async-io",
    "clap",
    "indicatif",
    "socketcan",
    "toml",
    "toml_edit",
    "serde_json",
    "rtrb",
    "triple_buffer",
];

#[test]
fn the_core_crate_depends_on_no_master_runtime_or_application_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let core = dependencies(&root.join("crates/ecdrive-core/Cargo.toml"));
    assert!(core.iter().any(|d| d == "roxmltree"), "{core:?}");
    let bad: Vec<&String> = core
        .iter()
        .filter(|d| NOT_IN_CORE.contains(&d.as_str()) || d.starts_with("ecdrive"))
        .collect();
    assert!(
        bad.is_empty(),
        "ecdrive-core may not depend on {bad:?} (ARCHITECTURE.md: the core has no bus master, \
         no async runtime, no application code)"
    );
}

/// The dependencies of crate `dir` that break "the core only": another ecdrive crate than the
/// core and the motion runtime (which the masters step their axes with), or one of
/// `forbidden`. Also checks that the crate does depend on the core.
fn beyond_the_core(dir: &str, forbidden: &[&str]) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let deps = dependencies(&root.join(dir).join("Cargo.toml"));
    assert!(deps.iter().any(|d| d == "ecdrive-core"), "{dir}: {deps:?}");
    deps.into_iter()
        .filter(|d| {
            (d.starts_with("ecdrive") && d != "ecdrive-core" && d != "ecdrive-motion")
                || forbidden.contains(&d.as_str())
        })
        .collect()
}

/// The EtherCAT master stands on the core: the software slave only as a dev-dependency of its
/// tests, never a normal one; no async runtime, no CLI, no progress bars.
#[test]
fn the_ethercat_master_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-ethercat",
        &["tokio", "clap", "indicatif", "socketcan", "toml"],
    );
    assert!(bad.is_empty(), "ecdrive-ethercat may not depend on {bad:?}");
}

/// The CANopen master stands on the core: the emulated nodes of the software slave only as a
/// dev-dependency of tests; no async runtime, no CLI.
#[test]
fn the_canopen_master_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-canopen",
        &["tokio", "clap", "indicatif", "ethercrab", "toml"],
    );
    assert!(bad.is_empty(), "ecdrive-canopen may not depend on {bad:?}");
}

/// The motion runtime stands on the core only: no bus master, no bus, no threads of its own,
/// no async runtime, no CLI. Both masters step their axes with it. (The set-point streams'
/// lock-free ring, `rtrb`, is a data structure the application API shares across both buses,
/// not a thread.)
#[test]
fn the_motion_runtime_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-motion",
        &[
            "ethercrab",
            "socketcan",
            "tokio",
            "async-io",
            "clap",
            "indicatif",
            "toml",
            "triple_buffer",
        ],
    );
    assert!(bad.is_empty(), "ecdrive-motion may not depend on {bad:?}");
    // Both masters step their axes with it.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for master in ["crates/ecdrive-ethercat", "crates/ecdrive-canopen"] {
        let deps = dependencies(&root.join(master).join("Cargo.toml"));
        assert!(
            deps.iter().any(|d| d == "ecdrive-motion"),
            "{master}: {deps:?}"
        );
    }
}

/// The software slave stands on the core only: no other ecdrive crate, no async runtime, no
/// CLI (it serves ethercrab's in-process transport, so ethercrab is allowed).
#[test]
fn the_slave_crate_depends_on_the_core_only() {
    let bad = beyond_the_core(
        "crates/ecdrive-sim",
        &[
            "tokio",
            "clap",
            "indicatif",
            "socketcan",
            "toml",
            "ecdrive-motion",
        ],
    );
    assert!(bad.is_empty(), "ecdrive-sim may not depend on {bad:?}");
}

/// The module path of the file at `rel` under a crate's `src/`: `a.rs` and `a/mod.rs` are
/// `a`, `a/b.rs` is `a::b`, `lib.rs` and `main.rs` the root.
fn module_of(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(str::to_string)
        .collect();
    if parts
        .last()
        .is_some_and(|l| l == "mod" || l == "lib" || l == "main")
    {
        parts.pop();
    }
    parts
}

/// The module paths `text` (the file of module `module`) names in code, comments left out:
/// `super::x::…`, `self::x::…` and `crate::x::…`, each item of a `{…}` group on its own.
fn named_paths(text: &str, module: &[String]) -> Vec<(usize, Vec<String>)> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        for root in ["super::", "self::", "crate::"] {
            let mut from = 0;
            while let Some(i) = code[from..].find(root) {
                let at = from + i;
                from = at + root.len();
                if code[..at]
                    .chars()
                    .next_back()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':')
                {
                    continue;
                }
                let mut base: Vec<String> = match root {
                    "crate::" => Vec::new(),
                    "self::" => module.to_vec(),
                    _ => module[..module.len().saturating_sub(1)].to_vec(),
                };
                let mut rest = &code[from..];
                while let Some(r) = rest.strip_prefix("super::") {
                    base.pop();
                    rest = r;
                }
                let mut heads = Vec::new();
                if let Some(group) = rest.strip_prefix('{') {
                    let end = group.find('}').unwrap_or(group.len());
                    for item in group[..end].split(',') {
                        heads.push(item.trim().split("::").map(ident).collect::<Vec<_>>());
                    }
                } else {
                    let mut segs = Vec::new();
                    let mut r = rest;
                    loop {
                        let id = ident(r);
                        if id.is_empty() {
                            break;
                        }
                        r = &r[id.len()..];
                        segs.push(id);
                        match r.strip_prefix("::") {
                            Some(x) => r = x,
                            None => break,
                        }
                    }
                    heads.push(segs);
                }
                for h in heads {
                    let mut p = base.clone();
                    p.extend(h.into_iter().filter(|s| !s.is_empty()));
                    out.push((n + 1, p));
                }
            }
        }
    }
    out
}

/// The module-level import circles of the crate whose sources are in `src`: for each pair of
/// sibling modules (a reference from deep inside one counts for the sibling it lies in), an
/// edge when one names the other in code; every strongly connected set of two or more
/// siblings is reported with the references that close it.
fn import_circles(src: &Path) -> Vec<String> {
    use std::collections::{BTreeMap, BTreeSet};
    let files = source_scan::rust_files(src);
    let rel = |f: &Path| {
        f.strip_prefix(src)
            .unwrap_or(f)
            .to_string_lossy()
            .replace('\\', "/")
    };
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_of(&rel(f))).collect();
    let mut edges: BTreeMap<(Vec<String>, Vec<String>), String> = BTreeMap::new();
    for f in &files {
        let r = rel(f);
        let from = module_of(&r);
        let text = std::fs::read_to_string(f).unwrap_or_default();
        for (line, path) in named_paths(&text, &from) {
            // The longest prefix that is a module of this crate.
            let Some(to) = (0..=path.len())
                .rev()
                .map(|k| path[..k].to_vec())
                .find(|p| modules.contains(p))
            else {
                continue;
            };
            let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common == from.len() || common == to.len() {
                continue; // the module itself, an ancestor or a descendant
            }
            let key = (from[..=common].to_vec(), to[..=common].to_vec());
            edges
                .entry(key)
                .or_insert_with(|| format!("{r}:{line} names {}", path.join("::")));
        }
    }
    // Strongly connected sets, by mutual reachability (the graphs are small).
    let nodes: BTreeSet<Vec<String>> = edges
        .keys()
        .flat_map(|(a, b)| [a.clone(), b.clone()])
        .collect();
    let reach = |start: &Vec<String>| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![start.clone()];
        while let Some(n) = todo.pop() {
            for (a, b) in edges.keys() {
                if *a == n && seen.insert(b.clone()) {
                    todo.push(b.clone());
                }
            }
        }
        seen
    };
    let reachable: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> =
        nodes.iter().map(|n| (n.clone(), reach(n))).collect();
    let mut found = Vec::new();
    let mut done = BTreeSet::new();
    for n in &nodes {
        if done.contains(n) || !reachable[n].contains(n) {
            continue;
        }
        let set: BTreeSet<Vec<String>> = nodes
            .iter()
            .filter(|m| reachable[n].contains(*m) && reachable[*m].contains(n))
            .cloned()
            .collect();
        let how: Vec<&String> = edges
            .iter()
            .filter(|((a, b), _)| set.contains(a) && set.contains(b))
            .map(|(_, w)| w)
            .collect();
        let names: Vec<String> = set.iter().map(|m| m.join("::")).collect();
        found.push(format!("{{{}}}: {how:?}", names.join(", ")));
        done.extend(set);
    }
    found
}

/// No module-level import circles in any crate: each module of a layer can be read, and
/// split off, without the modules that use it.
#[test]
fn no_crate_has_an_import_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    for dir in [
        "crates/ecdrive-core/src",
        "crates/ecdrive-sim/src",
        "crates/ecdrive-ethercat/src",
        "crates/ecdrive-canopen/src",
        "crates/ecdrive-motion/src",
        "crates/ecdrive-py/src",
    ] {
        for c in import_circles(&root.join(dir)) {
            found.push(format!("{dir}: {c}"));
        }
    }
    assert!(found.is_empty(), "import circles:\n{}", found.join("\n"));
}

/// The circle check sees a circle between siblings, through a group and from deep inside one,
/// and not a child naming its parent.
#[test]
fn the_circle_check_sees_circles() {
    let m = |s: &str| s.split("::").map(str::to_string).collect::<Vec<_>>();
    let paths = |t: &str, module: &str| -> Vec<String> {
        named_paths(t, &m(module))
            .into_iter()
            .map(|(_, p)| p.join("::"))
            .collect()
    };
    assert_eq!(paths("use super::coe::CoeError;", "bus"), ["coe::CoeError"]);
    assert_eq!(paths("use super::{a, b::C};", "x::y"), ["x::a", "x::b::C"]);
    assert_eq!(paths("// use super::coe;", "bus"), Vec::<String>::new());
    assert_eq!(paths("crate::od::Value", "a::b"), ["od::Value"]);
    let dir = std::env::temp_dir().join(format!("ecdrive-circles-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("a")).expect("temp dir");
    let write = |p: &str, t: &str| std::fs::write(dir.join(p), t).expect("write");
    write("lib.rs", "mod a; mod b; mod c;");
    write("a/mod.rs", "mod inner; pub use inner::X;");
    write("a/inner.rs", "use crate::b::Y; use super::X;");
    write("b.rs", "use super::c::Z;");
    write("c.rs", "pub struct Z; fn f() { crate::a::X; }");
    let found = import_circles(&dir);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with("{a, b, c}"), "{found:?}");
    write("c.rs", "pub struct Z;");
    assert!(import_circles(&dir).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The code of a line: comments, string and character literals blanked out (so that braces in
/// them do not count).
fn code_of(line: &str) -> String {
    let mut out = String::new();
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => break,
            '"' => {
                while let Some(d) = chars.next() {
                    match d {
                        '\\' => {
                            chars.next();
                        }
                        '"' => break,
                        _ => {}
                    }
                }
                out.push_str("\"\"");
            }
            '\'' => {
                // A character literal ('{', '\n') — not a lifetime ('a).
                let rest: String = chars.clone().take(3).collect();
                let lit = rest.starts_with('\\') || rest.chars().nth(1) == Some('\'');
                if lit {
                    while let Some(d) = chars.next() {
                        if d == '\\' {
                            chars.next();
                        } else if d == '\'' {
                            break;
                        }
                    }
                    out.push_str("' '");
                } else {
                    out.push(c);
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// The functions of `text` longer than `max` lines (signature to closing brace), test code
/// (items under `#[cfg(test)]`) left out: (line, name, lines).
fn long_functions(text: &str, max: usize) -> Vec<(usize, String, usize)> {
    let lines: Vec<String> = text.lines().map(code_of).collect();
    let block_end = |from: usize| -> usize {
        let mut depth = 0i64;
        let mut opened = false;
        for (k, l) in lines.iter().enumerate().skip(from) {
            depth += l.matches('{').count() as i64 - l.matches('}').count() as i64;
            opened |= l.contains('{');
            if !opened && l.trim_end().ends_with(';') {
                return k;
            }
            if opened && depth <= 0 {
                return k;
            }
        }
        lines.len().saturating_sub(1)
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i].trim_start();
        if t.starts_with("#[cfg(test)]") {
            let mut j = i + 1;
            while j < lines.len() && lines[j].trim_start().starts_with("#[") {
                j += 1;
            }
            i = block_end(j) + 1;
            continue;
        }
        let words: Vec<&str> = t.split_whitespace().collect();
        if let Some(k) = words.iter().position(|w| *w == "fn")
            && words[..k]
                .iter()
                .all(|w| ["pub", "const", "async", "unsafe"].contains(w) || w.starts_with("pub("))
            && let Some(name) = words.get(k + 1)
        {
            let end = block_end(i);
            let n = end - i + 1;
            if n > max {
                let name: String = name
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                out.push((i + 1, name, n));
            }
            i += 1;
            continue;
        }
        i += 1;
    }
    out
}

/// No function of any crate of the workspace, the application's included, is longer than 150
/// lines (tests excepted): each step of start-up, the cycle, the emulation, the configuration
/// and the command line reads in one place. The motion runtime's are held to 80
/// ([`no_function_of_the_motion_runtime_exceeds_80_lines`]).
#[test]
fn no_function_in_any_crate_exceeds_150_lines() {
    let found = functions_over(
        &[
            "src",
            "crates/ecdrive/src",
            "crates/ecdrive-core/src",
            "crates/ecdrive-motion/src",
            "crates/ecdrive-ethercat/src",
            "crates/ecdrive-canopen/src",
            "crates/ecdrive-sim/src",
            "crates/ecdrive-testkit/src",
            "crates/ecdrive-py/src",
        ],
        150,
    );
    assert!(
        found.is_empty(),
        "functions over 150 lines:\n{}",
        found.join("\n")
    );
}

/// Every function over `limit` lines in the crates under `dirs` (test code left out), as
/// `file:line: fn name has n lines`.
fn functions_over(dirs: &[&str], limit: usize) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    for dir in dirs {
        for f in source_scan::rust_files(&root.join(dir)) {
            let rel = f
                .strip_prefix(root)
                .unwrap_or(&f)
                .to_string_lossy()
                .replace('\\', "/");
            if rel.ends_with("/tests.rs") || rel.contains("/tests/") {
                continue;
            }
            let text = std::fs::read_to_string(&f).unwrap_or_default();
            for (line, name, n) in long_functions(&text, limit) {
                found.push(format!("{rel}:{line}: fn {name} has {n} lines"));
            }
        }
    }
    found
}

/// The EtherCAT cycle keeps only the bus's work (the motion is the runtime's): none of its
/// files is over 1 000 lines (`master::cycle`: the turn, the bus's supervision, each drive's
/// process image, the settings and report).
#[test]
fn the_ethercat_cycle_keeps_only_the_buss_work() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = source_scan::rust_files(&root.join("crates/ecdrive-ethercat/src/cycle"));
    assert!(files.len() >= 2, "{files:?}");
    for f in files {
        let n = std::fs::read_to_string(&f)
            .unwrap_or_default()
            .lines()
            .count();
        assert!(n < 1000, "{}: {n} lines", f.display());
    }
}

/// No function of the motion runtime (the crate both masters step their axes with) is longer
/// than 80 lines (tests excepted).
#[test]
fn no_function_of_the_motion_runtime_exceeds_80_lines() {
    let found = functions_over(&["crates/ecdrive-motion/src"], 80);
    assert!(
        found.is_empty(),
        "functions over 80 lines:\n{}",
        found.join("\n")
    );
}

/// The length check counts from the signature to the closing brace, sees through braces in
/// strings and characters, and leaves test code out.
#[test]
fn the_length_check_counts_lines() {
    let body = |n: usize| "    let x = 1;\n".repeat(n);
    let f = format!("pub fn long() {{\n{}}}\nfn short() {{\n}}\n", body(10));
    assert_eq!(long_functions(&f, 11), [(1, "long".to_string(), 12)]);
    assert!(long_functions(&f, 12).is_empty());
    let tricky = format!(
        "fn a() {{\n    let s = \"}}\"; let c = '}}';\n{}}}\n",
        body(3)
    );
    assert_eq!(long_functions(&tricky, 4), [(1, "a".to_string(), 6)]);
    let test = format!(
        "#[cfg(test)]\nmod tests {{\n    fn t() {{\n{}    }}\n}}\n",
        body(20)
    );
    assert!(long_functions(&test, 5).is_empty());
}
