//! No timed assertions in tests: "a slow machine takes longer, it does not fail"
//! (docs/development/testing.md). A
//! test waits for an event (`wait_until`, a polling loop, a join) or counts cycles; it does not
//! sleep and then assert on what it hopes happened meanwhile, nor assert on elapsed time.
//!
//! This check reads every test's source — `tests/`, `examples/`, and the `#[cfg(test)]` part of
//! every file under `src/` and `crates/*/src/` — and finds:
//!
//! - **sleep, then assert**: a `sleep(` outside a loop whose block goes on to an assertion
//!   before anything that waits (`wait`, a loop, `recv`, `join`, `poll`);
//! - **elapsed time asserted**: an assertion whose arguments read `elapsed()` — except against
//!   a guard (an identifier ending in `GUARD`, declared as at least 10 s: the upper bound of a
//!   wait for an event, not a claim about speed).
//!
//! A sleep that is not a claim about time (letting a process run before a signal whose outcome
//! does not depend on how far it got) carries `// untimed: REASON` on its line or the line
//! before. `a_sleep_then_an_assert_is_found` shows that the check finds what it is meant to.

use crate::support::source_scan;

use std::path::{Path, PathBuf};

/// One finding: file, line (1-based), what.
type Finding = (String, usize, &'static str);

/// The code of a line without its `//` comment (outside strings, roughly: enough for tests).
fn code(line: &str) -> &str {
    let mut in_str = false;
    let b = line.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'"' if i == 0 || b[i - 1] != b'\\' => in_str = !in_str,
            b'/' if !in_str && b.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
        i += 1;
    }
    line
}

fn is_assert(code: &str) -> bool {
    code.contains("assert!(")
        || code.contains("assert_eq!(")
        || code.contains("assert_ne!(")
        || code.contains("prop_assert")
}

fn waits(code: &str) -> bool {
    [
        "wait", "loop", "while ", "for ", "recv", "join(", "poll", ".drain(",
    ]
    .iter()
    .any(|w| code.contains(w))
}

fn is_loop_header(code: &str) -> bool {
    let c = code.trim_start();
    c.starts_with("loop")
        || c.starts_with("for ")
        || c.starts_with("while ")
        || c.contains(" loop {")
        || c.contains("= loop")
}

/// Whether the block opened on line `h` contains a `break` or a `return` (it ends on a
/// condition: it polls).
fn block_breaks(lines: &[&str], h: usize) -> bool {
    let mut depth = 0i32;
    for l in &lines[h..] {
        let c = code(l);
        if c.contains("break") || c.contains("return") {
            return true;
        }
        depth += c.matches('{').count() as i32 - c.matches('}').count() as i32;
        if depth <= 0 && c.contains('}') {
            return false;
        }
    }
    false
}

/// The guards declared in `text` of at least 10 s: `const NAME_GUARD: Duration =
/// Duration::from_secs(N)`.
fn long_guards(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| {
            let l = l.trim();
            let rest = l
                .strip_prefix("const ")
                .or_else(|| l.strip_prefix("pub const "))?;
            let (name, value) = rest.split_once(':')?;
            let secs: u64 = value
                .split("from_secs(")
                .nth(1)?
                .split(')')
                .next()?
                .trim()
                .parse()
                .ok()?;
            (name.ends_with("GUARD") && secs >= 10).then(|| name.trim().to_string())
        })
        .collect()
}

/// The findings in `text` (the test code of `file`), its first `skip` lines not test code.
fn scan(file: &str, text: &str, skip: usize) -> Vec<Finding> {
    let lines: Vec<&str> = text.lines().collect();
    let guards = long_guards(text);
    let mut found = Vec::new();
    // The header line of every open block.
    let mut stack: Vec<usize> = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let c = code(lines[i]);
        if i >= skip {
            if c.contains("sleep(") {
                let marked = lines[i].contains("// untimed:")
                    || (i > 0 && lines[i - 1].trim_start().starts_with("// untimed:"));
                let header = stack.last().map(|&h| (h, code(lines[h])));
                // A loop that polls (ends on a condition) waits; a `for` over a fixed count
                // that never breaks only repeats the sleep: what follows it is still timed.
                let repeats = header.is_some_and(|(h, hc)| {
                    hc.trim_start().starts_with("for ") && !block_breaks(&lines, h)
                });
                let in_loop = header.is_some_and(|(_, hc)| is_loop_header(hc)) && !repeats
                    || is_loop_header(c);
                if !marked && !in_loop {
                    // The rest of the block (and after a repeating loop, the block around
                    // it): an assert before anything that waits.
                    let mut depth = 0i32;
                    let mut leave = i32::from(repeats);
                    for (k, l) in lines.iter().enumerate().skip(i + 1) {
                        let lc = code(l);
                        if waits(lc) && !(leave > 0 && lc.trim_start().starts_with('}')) {
                            break;
                        }
                        if is_assert(lc) && depth == 0 {
                            found.push((file.to_string(), k + 1, "sleep, then assert"));
                            break;
                        }
                        depth += lc.matches('{').count() as i32 - lc.matches('}').count() as i32;
                        if depth < 0 {
                            if leave == 0 {
                                break;
                            }
                            leave -= 1;
                            depth = 0;
                        }
                    }
                }
            }
            if is_assert(c) {
                // The whole assertion, to its closing `);`.
                let mut stmt = c.to_string();
                let mut k = i;
                while !code(lines[k]).trim_end().ends_with(';') && k + 1 < lines.len() {
                    k += 1;
                    stmt.push_str(code(lines[k]));
                }
                if stmt.contains("elapsed()") && !guards.iter().any(|g| stmt.contains(g.as_str())) {
                    found.push((file.to_string(), i + 1, "elapsed time asserted"));
                }
            }
        }
        for ch in c.chars() {
            match ch {
                '{' => stack.push(i),
                '}' => {
                    stack.pop();
                }
                _ => {}
            }
        }
        i += 1;
    }
    found
}

/// The test code of a source file: all of a file under `tests/` or `examples/`, the part from
/// the first `#[cfg(test)]` on elsewhere (`None`: no tests in it).
fn test_part(path: &Path, text: &str) -> Option<usize> {
    let s = path.to_string_lossy();
    if s.contains("/tests/") || s.contains("/examples/") {
        return Some(0);
    }
    text.lines().position(|l| l.trim() == "#[cfg(test)]")
}

fn sources() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for d in ["tests", "examples", "src"] {
        files.extend(source_scan::rust_files(&root.join(d)));
    }
    if let Ok(crates) = std::fs::read_dir(root.join("crates")) {
        let mut dirs: Vec<PathBuf> = crates.flatten().map(|e| e.path()).collect();
        dirs.sort();
        for c in dirs {
            for d in ["src", "tests", "examples"] {
                files.extend(source_scan::rust_files(&c.join(d)));
            }
        }
    }
    files
}

#[test]
fn no_test_sleeps_then_asserts_or_asserts_on_elapsed_time() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    let files = sources();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        // This file's own examples are what it looks for.
        if f.ends_with("tests/app/untimed.rs") {
            continue;
        }
        let Some(skip) = test_part(f, &text) else {
            continue;
        };
        let rel = f
            .strip_prefix(root)
            .unwrap_or(f)
            .to_string_lossy()
            .to_string();
        found.extend(scan(&rel, &text, skip));
    }
    assert!(files.len() > 100, "{} files read", files.len());
    assert!(
        found.is_empty(),
        "timed assertions (wait for an event or count cycles instead):\n{}",
        found
            .iter()
            .map(|(f, l, w)| format!("  {f}:{l}: {w}"))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn a_sleep_then_an_assert_is_found() {
    let timed = "fn t() {\n    m.command(x);\n    std::thread::sleep(Duration::from_millis(50));\n    \
                 let p = m.telemetry().pos;\n    assert!(p > 10);\n}\n";
    assert_eq!(
        scan("t.rs", timed, 0),
        vec![("t.rs".to_string(), 5, "sleep, then assert")]
    );
    let elapsed = "fn t() {\n    let t0 = Instant::now();\n    run();\n    \
                   assert!(t0.elapsed() < Duration::from_millis(30), \"slow\");\n}\n";
    assert_eq!(
        scan("t.rs", elapsed, 0),
        vec![("t.rs".to_string(), 4, "elapsed time asserted")]
    );
    let repeated = "fn t() {\n    for _ in 0..2 {\n        inject(f);\n        \
                    std::thread::sleep(Duration::from_millis(300));\n    }\n    \
                    let t = m.telemetry();\n    assert!(t.lost >= 4);\n}\n";
    assert_eq!(
        scan("t.rs", repeated, 0),
        vec![("t.rs".to_string(), 7, "sleep, then assert")]
    );
    // Waiting, polling, a guard and a marked sleep are not timed assertions.
    let fine = "const WAIT_GUARD: Duration = Duration::from_secs(60);\nfn t() {\n    \
                std::thread::sleep(Duration::from_millis(5));\n    \
                m.wait_until(\"x\", T, |t| t.ok).unwrap();\n    assert!(m.ok());\n    \
                loop {\n        std::thread::sleep(Duration::from_millis(5));\n        \
                assert!(t0.elapsed() < WAIT_GUARD, \"no reply\");\n        \
                if done() { break; }\n    }\n    \
                // untimed: let the child run before the signal; any point is fine\n    \
                std::thread::sleep(Duration::from_secs(1));\n    assert!(stop(child));\n}\n";
    assert_eq!(scan("t.rs", fine, 0), vec![]);
}
