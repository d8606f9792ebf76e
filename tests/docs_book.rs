//! The book under `docs/` (mdBook): it builds, its command-line reference is what the argument
//! parser says (`scripts/docs-reference` writes it), every relative link in it and in the
//! README leads to a file that exists, and the README stays a front door (at most 400 lines).
//! Under `ECDRIVE_CI` the book must build (`.ci/run` installs mdBook); elsewhere, without
//! `mdbook` on the PATH or in `target/tools/bin`, that one test says so and returns.

mod support {
    pub mod cli;
}
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
