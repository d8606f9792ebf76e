//! The book under `docs/` (mdBook): it builds, its command-line reference is what the argument
//! parser says (`scripts/docs-reference` writes it), every relative link in it and in the
//! README leads to a file that exists, and the README stays a front door (at most 400 lines).
//! Under `ECDRIVE_CI` the book must build (`.ci/run` installs mdBook); elsewhere, without
//! `mdbook` on the PATH or in `target/tools/bin`, that one test says so and returns.

use crate::support;
use std::path::{Path, PathBuf};
use support::cli::ecdrive;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

#[test]
fn the_cli_reference_is_what_the_parser_says() {
    let generated = ecdrive(&["markdown-help"]);
    let generated = generated.ok();
    let committed = std::fs::read_to_string(Path::new(ROOT).join("docs/reference/cli.md"))
        .expect("docs/reference/cli.md");
    assert!(
        generated == committed,
        "docs/reference/cli.md is not what `ecdrive markdown-help` prints: run \
         scripts/docs-reference and commit the result"
    );
    // Every visible command is in it.
    for cmd in [
        "slaves", "run", "sim", "reset", "eds", "esi", "jitter", "plot", "version",
    ] {
        assert!(
            committed.contains(&format!("### `ecdrive {cmd}`")),
            "no section for {cmd}"
        );
    }
    assert!(
        !committed.contains("markdown-help"),
        "the hidden command is listed"
    );
}

/// The book's key index is what the run-file parser takes, table by table and step by step.
#[test]
fn the_configuration_key_index_is_what_the_parser_says() {
    let generated = ecdrive(&["markdown-help", "config"]);
    let generated = generated.ok();
    let committed =
        std::fs::read_to_string(Path::new(ROOT).join("docs/reference/configuration-keys.md"))
            .expect("docs/reference/configuration-keys.md");
    assert!(
        generated == committed,
        "docs/reference/configuration-keys.md is not what `ecdrive markdown-help config` \
         prints: run scripts/docs-reference and commit the result"
    );
    // Every table and step came with its keys (an empty list: the probe found no error list).
    for line in committed
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| table"))
    {
        if line.starts_with("| `step =`") {
            continue;
        }
        assert!(line.trim_end().ends_with("` |"), "no keys: {line}");
    }
    assert!(committed.contains("| [[drive]] | "), "{committed}");
    assert!(committed.contains("| `move` | "), "{committed}");
}

/// The chapters `docs/SUMMARY.md` lists.
fn chapters() -> Vec<PathBuf> {
    let docs = Path::new(ROOT).join("docs");
    let summary = std::fs::read_to_string(docs.join("SUMMARY.md")).expect("docs/SUMMARY.md");
    let mut out = Vec::new();
    for line in summary.lines() {
        if let Some((_, rest)) = line.split_once("](")
            && let Some((target, _)) = rest.split_once(')')
            && !target.is_empty()
        {
            out.push(docs.join(target));
        }
    }
    out
}

/// Relative links in a Markdown file that lead nowhere: `[text](path#anchor)` where `path` is
/// not a URL, an anchor alone, or a mail address, and does not exist beside the file.
fn broken_links(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let dir = file.parent().unwrap_or(Path::new("."));
    let mut broken = Vec::new();
    let mut in_code = false;
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        let mut rest = line;
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = &rest[..end];
            rest = &rest[end..];
            let path = target.split('#').next().unwrap_or("");
            if path.is_empty() || path.contains("://") || path.starts_with("mailto:") {
                continue;
            }
            if !dir.join(path).exists() {
                broken.push(format!("{}:{}: {target}", file.display(), n + 1));
            }
        }
    }
    broken
}

#[test]
fn every_chapter_exists_and_every_relative_link_resolves() {
    let chapters = chapters();
    assert!(chapters.len() >= 10, "{chapters:?}");
    let mut broken = Vec::new();
    for c in &chapters {
        assert!(
            c.exists(),
            "SUMMARY.md lists {} which does not exist",
            c.display()
        );
        broken.extend(broken_links(c));
    }
    broken.extend(broken_links(&Path::new(ROOT).join("README.md")));
    broken.extend(broken_links(&Path::new(ROOT).join("ARCHITECTURE.md")));
    assert!(
        broken.is_empty(),
        "links that lead nowhere:\n{}",
        broken.join("\n")
    );
    // Every Markdown file of the book is a chapter (mdBook leaves out what SUMMARY does not list).
    let listed: Vec<PathBuf> = chapters
        .iter()
        .filter_map(|c| c.canonicalize().ok())
        .collect();
    let mut unlisted = Vec::new();
    let mut stack = vec![Path::new(ROOT).join("docs")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "md")
                && p.file_name().is_some_and(|n| n != "SUMMARY.md")
                && !listed.contains(&p.canonicalize().unwrap_or_default())
            {
                unlisted.push(p.display().to_string());
            }
        }
    }
    assert!(unlisted.is_empty(), "not in docs/SUMMARY.md: {unlisted:?}");
}

#[test]
fn the_readme_is_a_front_door() {
    let readme = std::fs::read_to_string(Path::new(ROOT).join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(
        lines <= 400,
        "README.md has {lines} lines; the book is for the rest"
    );
    let head: Vec<&str> = readme.lines().take(6).collect();
    assert_eq!(
        head,
        [
            "# ecdrive",
            "",
            "```sh",
            "cargo run --release -- demo",
            "cargo test --release",
            "```"
        ],
        "the README opens with the two commands"
    );
}

/// `mdbook`, from the PATH or where `.ci/run` installs it.
fn mdbook() -> Option<PathBuf> {
    let local = Path::new(ROOT).join("target/tools/bin/mdbook");
    if local.exists() {
        return Some(local);
    }
    std::process::Command::new("mdbook")
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|_| PathBuf::from("mdbook"))
}

#[test]
fn the_book_builds() {
    let Some(mdbook) = mdbook() else {
        assert!(
            std::env::var_os("ECDRIVE_CI").is_none(),
            "mdbook is not installed; .ci/run installs it (the book must build in CI)"
        );
        eprintln!("mdbook not installed: the book's build is not checked here");
        return;
    };
    let out = std::env::temp_dir().join(format!("ecdrive-book-{}", std::process::id()));
    let run = std::process::Command::new(&mdbook)
        .args(["build", "docs", "--dest-dir"])
        .arg(&out)
        .current_dir(ROOT)
        .output()
        .expect("mdbook runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "mdbook build failed:\n{stderr}");
    assert!(
        !stderr.contains("ERROR") && !stderr.contains("WARN"),
        "mdbook warns:\n{stderr}"
    );
    for page in [
        "index.html",
        "reference/cli.html",
        "reference/configuration.html",
    ] {
        assert!(out.join(page).exists(), "the book has no {page}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The keys the configuration parser takes where `text` puts the key `zzz` (the parser's own
/// "unknown key" list: the schema itself).
fn parser_keys(text: &str) -> Vec<String> {
    let keys = ecdrive_cli::app::config::schema::keys_at(text);
    assert!(!keys.is_empty(), "{text}: the parser listed no keys");
    keys
}

/// The words inside backticks of `text` (`identity = { vendor_id, product_code }` gives
/// identity, vendor_id, product_code).
fn code_words(text: &str) -> std::collections::BTreeSet<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .flat_map(|span| {
            span.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .filter(|w| !w.is_empty())
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The configuration reference against the parser, so neither drifts: every key every table
/// takes, and every program step with its keys, is in `docs/reference/configuration.md`; the
/// reference's step table lists exactly the parser's steps; its example error lists the drive
/// table's keys as the parser does.
#[test]
fn the_configuration_reference_names_every_key_the_parser_takes() {
    let doc = std::fs::read_to_string(Path::new(ROOT).join("docs/reference/configuration.md"))
        .expect("configuration.md");
    // The reference's prose and tables, not its examples (a key only an example shows is not
    // explained).
    let prose: String = doc.split("```").step_by(2).collect::<Vec<_>>().join("\n");
    let words = code_words(&prose);
    let head = "interface = \"sim\"\n[sim]\ndevices = [\"bdhde\"]\n";
    let drive = format!("{head}[[drive]]\nposition = 0\n");
    let tables = [
        ("the file", "interface = \"sim\"\nzzz = 1\n".to_string()),
        ("[rt]", "interface = \"sim\"\n[rt]\nzzz = 1\n".to_string()),
        (
            "[supervision]",
            "interface = \"sim\"\n[supervision]\nzzz = 1\n".to_string(),
        ),
        ("[sim]", format!("{head}zzz = 1\n")),
        ("[[drive]]", format!("{head}[[drive]]\nzzz = 1\n")),
        (
            "identity",
            format!("{head}[[drive]]\nidentity = {{ vendor_id = 1, product_code = 1, zzz = 1 }}\n"),
        ),
        (
            "units",
            format!("{drive}units = {{ name = \"mm\", counts_per_unit = 1, zzz = 1 }}\n"),
        ),
        ("limits", format!("{drive}limits = {{ zzz = 1 }}\n")),
        ("mapping", format!("{drive}mapping = {{ zzz = 1 }}\n")),
        (
            "a PDO",
            format!("{drive}mapping = {{ rx = [{{ pdo = 0x1600, entries = [], zzz = 1 }}] }}\n"),
        ),
    ];
    let mut missing = Vec::new();
    for (table, text) in &tables {
        for k in parser_keys(text) {
            if !words.contains(&k) {
                missing.push(format!("{table}: `{k}`"));
            }
        }
    }
    // Steps: the parser's list, each with its keys, in its row of the step table.
    let steps = parser_keys(&format!("{drive}program = [{{ step = \"zzz\" }}]\n"));
    assert!(steps.len() >= 13, "{steps:?}");
    let rows: Vec<&str> = doc.lines().filter(|l| l.starts_with("| `")).collect();
    let documented: Vec<String> = rows
        .iter()
        .filter(|r| r.matches('|').count() == 4)
        .filter_map(|r| r.split('`').nth(1).map(str::to_string))
        .collect();
    for s in &steps {
        let Some(row) = rows
            .iter()
            .find(|r| r.starts_with(&format!("| `{s}` |")) && r.matches('|').count() == 4)
        else {
            missing.push(format!("the step table: `{s}`"));
            continue;
        };
        let in_row = code_words(row);
        for k in parser_keys(&format!(
            "{drive}program = [{{ step = \"{s}\", zzz = 1 }}]\n"
        )) {
            if !in_row.contains(&k) {
                missing.push(format!("step `{s}`: `{k}`"));
            }
        }
    }
    for d in &documented {
        assert!(
            steps.contains(d),
            "the step table lists `{d}`, which the parser does not take"
        );
    }
    assert!(
        missing.is_empty(),
        "not in docs/reference/configuration.md:\n{}",
        missing.join("\n")
    );
    // The example error, as the parser would write it.
    let example = doc
        .lines()
        .find(|l| l.contains("unknown key `velocty`"))
        .expect("the example error");
    let listed: Vec<&str> = example
        .split("the keys allowed here are")
        .nth(1)
        .unwrap_or("")
        .split('`')
        .skip(1)
        .step_by(2)
        .collect();
    assert_eq!(
        listed,
        parser_keys(&format!("{head}[[drive]]\nzzz = 1\n")),
        "{example}"
    );
}

/// The book's `ecdrive sim --list-devices` is what the binary lists (the quirk table lacked
/// two quirks the binary had).
#[test]
fn the_books_device_list_is_the_binarys() {
    let doc = std::fs::read_to_string(Path::new(ROOT).join("docs/guide/sim.md")).expect("sim.md");
    let block = doc
        .split("```text\n$ ecdrive sim --list-devices\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("the --list-devices block in docs/guide/sim.md");
    let listed = ecdrive(&["sim", "--list-devices"]);
    assert_eq!(
        block.trim_end(),
        listed.ok().trim_end(),
        "docs/guide/sim.md's device list is not what `ecdrive sim --list-devices` prints"
    );
}

/// ARCHITECTURE.md reads as a map, not a wall: no table cell of 1 000 characters or more.
#[test]
fn architecture_has_no_wall_of_a_table_cell() {
    let text = std::fs::read_to_string(Path::new(ROOT).join("ARCHITECTURE.md")).unwrap();
    for (n, line) in text.lines().enumerate() {
        if !line.trim_start().starts_with('|') {
            continue;
        }
        for cell in line.split('|') {
            assert!(
                cell.chars().count() < 1000,
                "ARCHITECTURE.md line {}: a table cell of {} characters",
                n + 1,
                cell.chars().count()
            );
        }
    }
}
