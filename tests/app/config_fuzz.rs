//! Property tests for the `ecdrive run` configuration parser (`config::parse`), the entry point
//! of the `config` fuzz target, with the same checks (`fuzz/src/lib.rs`): damaged example files
//! and random TOML-ish text never make it panic, and every error names the file, a line and
//! column inside the text and a reason, on one line.

use crate::fuzz_checks as checks;

use proptest::prelude::*;

const EXAMPLES: [&str; 5] = [
    include_str!("../../examples/csp_move_sine.toml"),
    include_str!("../../examples/cst_step.toml"),
    include_str!("../../examples/csv_ramp.toml"),
    include_str!("../../examples/interface.toml"),
    include_str!("../../examples/mode_switch.toml"),
];

/// Replacement values: out of range, wrong type, odd units, odd TOML.
const TOKENS: [&str; 24] = [
    "\"\"",
    "0",
    "-1",
    "1e400",
    "nan",
    "-inf",
    "0xFFFFFFFFFFFF",
    "-9223372036854775808",
    "1.5",
    "true",
    "[]",
    "{}",
    "[[]]",
    "\"0us\"",
    "\"1 fortnight\"",
    "\"999999999999 s\"",
    "\"1.5e3ms\"",
    "\"sim\"",
    "\"csp\"",
    "\"0x6040:00\"",
    "\"0x10000:00\"",
    "{ step = \"move\" }",
    "\"µ\\n\"",
    "1979-05-27T07:32:00Z",
];

#[derive(Debug, Clone)]
enum Mutation {
    /// Delete line `n`.
    DeleteLine(usize),
    /// Repeat line `n`.
    DuplicateLine(usize),
    /// Replace the value of the `n`-th `key = value` line.
    Value(usize, usize),
    /// Insert text at char `n`.
    Insert(usize, String),
    /// Cut the text at char `n`.
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        1 => any::<usize>().prop_map(Mutation::DeleteLine),
        1 => any::<usize>().prop_map(Mutation::DuplicateLine),
        3 => (any::<usize>(), 0..TOKENS.len()).prop_map(|(n, t)| Mutation::Value(n, t)),
        1 => (any::<usize>(), "[\\[\\]{}=\",.#a-z0-9 \n]{1,6}").prop_map(|(n, s)| Mutation::Insert(n, s)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let mut lines: Vec<String> = text.split('\n').map(str::to_string).collect();
    let n_lines = lines.len();
    let chars: Vec<char> = text.chars().collect();
    match m {
        Mutation::DeleteLine(n) => {
            lines.remove(n % n_lines);
            lines.join("\n")
        }
        Mutation::DuplicateLine(n) => {
            let l = lines[n % n_lines].clone();
            lines.insert(n % n_lines, l);
            lines.join("\n")
        }
        Mutation::Value(n, t) => {
            let with_value: Vec<usize> =
                (0..n_lines).filter(|&i| lines[i].contains(" = ")).collect();
            if let Some(&i) = with_value.get(n % with_value.len().max(1)) {
                let key = lines[i].split(" = ").next().unwrap_or_default().to_string();
                lines[i] = format!("{key} = {}", TOKENS[*t]);
            }
            lines.join("\n")
        }
        Mutation::Insert(n, s) => {
            let at = n % (chars.len() + 1);
            chars[..at]
                .iter()
                .copied()
                .chain(s.chars())
                .chain(chars[at..].iter().copied())
                .collect()
        }
        Mutation::Truncate(n) => chars[..n % (chars.len() + 1)].iter().collect(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive::rt::audit::test_seed(file!())), ..ProptestConfig::default() })]

    #[test]
    fn damaged_examples_give_positioned_errors(
        file in 0..EXAMPLES.len(),
        muts in proptest::collection::vec(mutation(), 1..5),
    ) {
        let mut text = EXAMPLES[file].to_string();
        for m in &muts {
            text = apply(&text, m);
        }
        checks::config(text.as_bytes());
    }

    #[test]
    fn random_text_gives_positioned_errors(text in "[\\[\\]{}=\",.#a-z0-9_ \n]{0,80}") {
        checks::config(text.as_bytes());
    }
}

/// The unmutated examples are accepted (so the mutations start from files that get past the
/// TOML syntax into the checks).
#[test]
fn the_examples_parse() {
    for (i, text) in EXAMPLES.iter().enumerate() {
        if let Err(e) = ecdrive_cli::app::config::parse(text, "example.toml") {
            panic!("example {i}: {e}");
        }
    }
}

/// Found by these tests: the TOML parser's messages for syntax errors span lines, or are empty
/// for a value missing at the end of the file; the error still renders as one line and says
/// what is wrong, where.
#[test]
fn syntax_errors_are_one_line_with_a_reason() {
    let e = ecdrive_cli::app::config::parse("interface = [\n", "x.toml").unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.toml line 2, column 1: invalid array; expected `]`"
    );
    let e = ecdrive_cli::app::config::parse("interface =", "x.toml").unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.toml line 1, column 12: invalid TOML syntax here"
    );
    checks::config(b"a=");
    checks::config(b"a=\n");
}
