//! Shared by the fuzz tests of the engine and of the scenes crate (which includes this file by
//! path): the case budget, a proptest runner that counts outcomes and turns panics into
//! failures that print the input, and mutations of text documents (RON, JSON, WGSL), both
//! unstructured (delete, insert, duplicate, truncate, swap brackets) and token-aware (replace a
//! number, a string or a word; drop or repeat an entry of a list, map or struct).
//!
//! `LIGHTGRAPH_FUZZ_CASES=N` sets the number of inputs of every fuzz test and
//! `LIGHTGRAPH_FUZZ_SEED=K` its random seed (fixed by default, so CI runs are reproducible);
//! `LIGHTGRAPH_FUZZ_VERBOSE=1` prints every error.

#![allow(dead_code)]

use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use std::cell::Cell;
use std::fmt;
use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

/// What one input did: accepted, or refused with an error that has the properties asked for.
/// A refusal whose error lacks them is an `Err` of the check, naming what is missing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// Parsed (and whatever the test runs after parsing succeeded).
    Ok,
    /// Refused with a good error (printed when `LIGHTGRAPH_FUZZ_VERBOSE` is set).
    Refused(String),
}

/// Runs `default_cases` inputs (or `LIGHTGRAPH_FUZZ_CASES`) drawn from `strategy` through
/// `check` and prints `fuzz NAME: N inputs, A ok, B errors, 0 panics (T s, seed K)` (on
/// stderr, even when the test harness captures output). A panic or a bad error fails the test
/// with the (shrunk) input.
pub fn fuzz<S>(name: &str, default_cases: u32, strategy: S, check: impl Fn(&S::Value) -> Result<Outcome, String>)
where
    S: Strategy,
    S::Value: fmt::Debug,
{
    let cases = std::env::var("LIGHTGRAPH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default_cases);
    let seed = std::env::var("LIGHTGRAPH_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x11_9b7_9a9);
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(seed),
        max_shrink_iters: 512,
        ..Config::default()
    });
    let verbose = std::env::var_os("LIGHTGRAPH_FUZZ_VERBOSE").is_some();
    let (tried, ok, refused, panics) = (Cell::new(0u64), Cell::new(0u64), Cell::new(0u64), Cell::new(0u64));
    let start = Instant::now();
    let result = runner.run(&strategy, |input| {
        tried.set(tried.get() + 1);
        match catch_unwind(AssertUnwindSafe(|| check(&input))) {
            Ok(Ok(Outcome::Ok)) => ok.set(ok.get() + 1),
            Ok(Ok(Outcome::Refused(error))) => {
                if verbose {
                    eprintln!("{error}");
                }
                refused.set(refused.get() + 1)
            }
            Ok(Err(why)) => return Err(TestCaseError::fail(format!("bad error: {why}\ninput: {input:?}"))),
            Err(panic) => {
                panics.set(panics.get() + 1);
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                return Err(TestCaseError::fail(format!("panic: {what}\ninput: {input:?}")));
            }
        }
        Ok(())
    });
    let summary = format!(
        "fuzz {name}: {} inputs, {} ok, {} errors, {} panics ({:.1} s, seed {seed})",
        tried.get(),
        ok.get(),
        refused.get(),
        panics.get(),
        start.elapsed().as_secs_f64()
    );
    // Written past the test harness's capture, so that CI logs show it for passing tests too.
    let _ = writeln!(std::io::stderr(), "{summary}");
    if let Err(e) = result {
        panic!("{summary}\n{e}");
    }
}

/// Checks that an error message is not empty and starts with `file:LINE:COLUMN: ` (1-based,
/// within the `lines` lines of the file, or one past its end) followed by some text.
pub fn check_located(message: &str, file: &str, lines: usize) -> Result<(), String> {
    let rest = message
        .strip_prefix(file)
        .and_then(|r| r.strip_prefix(':'))
        .ok_or_else(|| format!("'{message}' does not start with '{file}:'"))?;
    let mut parts = rest.splitn(3, ':');
    let line: usize = parts.next().and_then(|l| l.parse().ok()).unwrap_or(0);
    let column: usize = parts.next().and_then(|c| c.parse().ok()).unwrap_or(0);
    let text = parts.next().unwrap_or("").trim();
    if line == 0 || line > lines + 1 || column == 0 {
        return Err(format!(
            "'{message}' has no line and column within the {lines} lines of {file}"
        ));
    }
    if text.is_empty() {
        return Err(format!("'{message}' says nothing after its location"));
    }
    Ok(())
}

/// The interesting literals of a text format.
pub struct Dialect {
    /// Numbers to put in place of a number (as text).
    pub numbers: &'static [&'static str],
    /// Values of other types to put in place of a number or string.
    pub values: &'static [&'static str],
    /// Odd string contents to put in place of a string.
    pub strings: &'static [&'static str],
}

/// RON (graphs, catalogs, scenes) and WGSL: numbers of every kind a field might hold.
#[rustfmt::skip]
pub const RON: Dialect = Dialect {
    numbers: &[
        "0", "-1", "1", "2", "-0.0", "NaN", "inf", "-inf", "1e30", "-1e30", "1e-45", "0.5", "3.5", "1025", "65536",
        "2147483648", "4294967295", "4294967296", "18446744073709551615", "99999999999999999999",
    ],
    values: &["()", "[]", "{}", "\"x\"", "None", "Some(1)", "true", "U32(1)", "F32(NaN)", "Step", "Loop"],
    strings: &[
        "", "x", "lg_x", "1abc", "a b", "a-b", "é", "N * 2", "N / 0", "0 - N", "min(N)", "foo(N)", "((N)", "1e400",
        "N * N * N * N", "../x.wgsl", "%FF", "Walk", "Done",
    ],
};

/// JSON (glTF): indices, counts, component types, byte sizes and the values of other types.
#[rustfmt::skip]
pub const JSON: Dialect = Dialect {
    numbers: &[
        "0", "-1", "1", "2", "3", "4", "7", "12", "255", "256", "65535", "65536", "1.5", "1e30", "-1e30", "5120",
        "5121", "5122", "5123", "5125", "5126", "2147483648", "4294967295", "4294967296", "18446744073709551615",
    ],
    values: &["null", "\"x\"", "[]", "{}", "true", "[0]", "[0, 0]", "-1", "0"],
    strings: &[
        "", "x", "%FF", "%", "data:,", "data:application/octet-stream;base64,AAAA", "/", "a/../../b", "SCALAR",
        "VEC3", "VEC4", "MAT4",
    ],
};

/// A file's text after edits, printed in full when an input fails.
#[derive(Clone)]
pub struct Mutated {
    /// The file's name.
    pub file: String,
    /// The edited text.
    pub text: String,
    /// The edits.
    pub edits: Vec<Edit>,
}

impl Mutated {
    /// `text` of `file` after `edits`.
    pub fn new(file: &str, text: &str, edits: Vec<Edit>, dialect: &Dialect) -> Mutated {
        Mutated {
            file: file.to_string(),
            text: apply(text, &edits, dialect),
            edits,
        }
    }
}

impl fmt::Debug for Mutated {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} after {:?}:\n{}\n", self.file, self.edits, self.text)
    }
}

/// One edit of a text.
#[derive(Debug, Clone)]
pub enum Edit {
    /// Deletes up to `len` characters.
    Delete(Index, usize),
    /// Inserts the text.
    Insert(Index, String),
    /// Copies up to `len` characters from the first place to the second.
    Duplicate(Index, usize, Index),
    /// Cuts the text off.
    Truncate(Index),
    /// Replaces a bracket by this one.
    Bracket(Index, char),
    /// Replaces a number by the dialect's number (or value, past the numbers).
    Number(Index, Index),
    /// Replaces a string's contents by another string of the text (`None`) or a dialect string.
    Str(Index, Option<Index>, Index),
    /// Replaces a string by a value of another type.
    StrValue(Index, Index),
    /// Wraps a string's contents in parentheses, this many deep.
    Nest(Index, usize),
    /// Replaces a word (identifier) by another word of the text.
    Word(Index, Index),
    /// Removes an entry of a list, map or struct.
    DropEntry(Index),
    /// Repeats an entry of a list, map or struct.
    RepeatEntry(Index),
}

/// Up to `most` edits, unstructured and token-aware in about equal shares.
pub fn edits(most: usize) -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(edit(), 1..=most)
}

fn edit() -> impl Strategy<Value = Edit> {
    let i = || any::<Index>();
    let chars = prop::collection::vec(
        prop::sample::select("(){}[]:,\"\n -.019eaxN_/#\\é".chars().collect::<Vec<_>>()),
        1..8,
    )
    .prop_map(|c| c.into_iter().collect::<String>());
    let deep = (
        prop::sample::select(vec!["(", "[", "{", "Some(", "-", "\""]),
        64..4000usize,
    )
        .prop_map(|(s, n)| s.repeat(n));
    prop_oneof![
        2 => (i(), 1..40usize).prop_map(|(a, n)| Edit::Delete(a, n)),
        2 => (i(), prop_oneof![4 => chars, 1 => deep]).prop_map(|(a, s)| Edit::Insert(a, s)),
        1 => (i(), 1..200usize, i()).prop_map(|(a, n, b)| Edit::Duplicate(a, n, b)),
        1 => i().prop_map(Edit::Truncate),
        1 => (i(), prop::sample::select(vec!['(', ')', '[', ']', '{', '}'])).prop_map(|(a, c)| Edit::Bracket(a, c)),
        4 => (i(), i()).prop_map(|(a, b)| Edit::Number(a, b)),
        3 => (i(), prop::option::of(i()), i()).prop_map(|(a, b, c)| Edit::Str(a, b, c)),
        1 => (i(), i()).prop_map(|(a, b)| Edit::StrValue(a, b)),
        1 => (i(), prop_oneof![1..4usize, 100..5000usize]).prop_map(|(a, n)| Edit::Nest(a, n)),
        2 => (i(), i()).prop_map(|(a, b)| Edit::Word(a, b)),
        3 => i().prop_map(Edit::DropEntry),
        2 => i().prop_map(Edit::RepeatEntry),
    ]
}

/// Applies `edits` in order to `text`.
pub fn apply(text: &str, edits: &[Edit], dialect: &Dialect) -> String {
    edits.iter().fold(text.to_string(), |t, e| apply_one(&t, e, dialect))
}

/// The byte offset of the character picked by `i` (or the end, for an empty text).
fn char_at(text: &str, i: &Index) -> usize {
    let n = text.chars().count();
    if n == 0 {
        return 0;
    }
    text.char_indices().nth(i.index(n)).map_or(text.len(), |(o, _)| o)
}

/// The byte offset `n` characters after `from` (or the end).
fn chars_after(text: &str, from: usize, n: usize) -> usize {
    text[from..].char_indices().nth(n).map_or(text.len(), |(o, _)| from + o)
}

fn pick<'a, T>(items: &'a [T], i: &Index) -> Option<&'a T> {
    (!items.is_empty()).then(|| &items[i.index(items.len())])
}

fn splice(text: &str, range: std::ops::Range<usize>, with: &str) -> String {
    format!("{}{with}{}", &text[..range.start], &text[range.end..])
}

fn apply_one(text: &str, edit: &Edit, d: &Dialect) -> String {
    let tokens = tokenize(text);
    let of = |kind: Kind| -> Vec<&Token> { tokens.iter().filter(|t| t.kind == kind).collect() };
    match edit {
        Edit::Delete(a, n) => {
            let s = char_at(text, a);
            splice(text, s..chars_after(text, s, *n), "")
        }
        Edit::Insert(a, s) => splice(text, char_at(text, a)..char_at(text, a), s),
        Edit::Duplicate(a, n, b) => {
            let s = char_at(text, a);
            let copy = &text[s..chars_after(text, s, *n)];
            let at = char_at(text, b);
            splice(text, at..at, copy)
        }
        Edit::Truncate(a) => text[..char_at(text, a)].to_string(),
        Edit::Bracket(a, c) => {
            let brackets: Vec<usize> = text
                .match_indices(['(', ')', '[', ']', '{', '}'])
                .map(|(o, _)| o)
                .collect();
            match pick(&brackets, a) {
                Some(&o) => splice(text, o..o + 1, &c.to_string()),
                None => text.to_string(),
            }
        }
        Edit::Number(a, b) => match pick(&of(Kind::Number), a) {
            Some(t) => {
                let all: Vec<&str> = d.numbers.iter().chain(d.values).copied().collect();
                splice(text, t.range.clone(), all[b.index(all.len())])
            }
            None => text.to_string(),
        },
        Edit::Str(a, other, b) => {
            let strings = of(Kind::Str);
            let Some(t) = pick(&strings, a) else {
                return text.to_string();
            };
            let with = match other {
                Some(o) => text[pick(&strings, o).map_or(t.range.clone(), |s| s.range.clone())].to_string(),
                None => format!("\"{}\"", d.strings[b.index(d.strings.len())]),
            };
            splice(text, t.range.clone(), &with)
        }
        Edit::StrValue(a, b) => match pick(&of(Kind::Str), a) {
            Some(t) => splice(text, t.range.clone(), d.values[b.index(d.values.len())]),
            None => text.to_string(),
        },
        Edit::Nest(a, n) => match pick(&of(Kind::Str), a) {
            Some(t) if t.range.len() >= 2 && text[t.range.clone()].ends_with('"') => {
                let inner = &text[t.range.start + 1..t.range.end - 1];
                splice(
                    text,
                    t.range.clone(),
                    &format!("\"{}{inner}{}\"", "(".repeat(*n), ")".repeat(*n)),
                )
            }
            _ => text.to_string(),
        },
        Edit::Word(a, b) => {
            let words = of(Kind::Word);
            match (pick(&words, a), pick(&words, b)) {
                (Some(t), Some(u)) => splice(text, t.range.clone(), &text[u.range.clone()]),
                _ => text.to_string(),
            }
        }
        Edit::DropEntry(a) => match pick(&of(Kind::Entry), a) {
            Some(t) => splice(text, t.range.clone(), ""),
            None => text.to_string(),
        },
        Edit::RepeatEntry(a) => match pick(&of(Kind::Entry), a) {
            Some(t) => {
                let entry = &text[t.range.clone()];
                let copy = if entry.trim_end().ends_with(',') {
                    entry.to_string()
                } else {
                    format!("{entry}, ")
                };
                splice(text, t.range.start..t.range.start, &copy)
            }
            None => text.to_string(),
        },
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Number,
    Str,
    Word,
    /// An element of a bracketed, comma-separated list (with its comma).
    Entry,
}

#[derive(Debug, Clone)]
struct Token {
    kind: Kind,
    range: std::ops::Range<usize>,
}

/// Numbers, strings, words and bracketed entries of a RON, JSON or WGSL text (`//` comments
/// skipped).
fn tokenize(text: &str) -> Vec<Token> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    // Per open bracket: where its current entry starts.
    let mut open: Vec<usize> = Vec::new();
    let entry = |out: &mut Vec<Token>, start: usize, end: usize| {
        if text[start..end].trim().trim_end_matches(',').trim().is_empty() {
            return;
        }
        let lead = text[start..end].len() - text[start..end].trim_start().len();
        out.push(Token {
            kind: Kind::Entry,
            range: start + lead..end,
        });
    };
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        match c {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                i = (i + 1).min(bytes.len());
                out.push(Token {
                    kind: Kind::Str,
                    range: start..i,
                });
                continue;
            }
            b'0'..=b'9' => {
                while i < bytes.len()
                    && (bytes[i].is_ascii_alphanumeric()
                        || bytes[i] == b'.'
                        || bytes[i] == b'_'
                        || (matches!(bytes[i], b'+' | b'-') && matches!(bytes[i - 1], b'e' | b'E')))
                {
                    i += 1;
                }
                let neg = start > 0 && bytes[start - 1] == b'-';
                out.push(Token {
                    kind: Kind::Number,
                    range: start - neg as usize..i,
                });
                continue;
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                out.push(Token {
                    kind: Kind::Word,
                    range: start..i,
                });
                continue;
            }
            b'(' | b'[' | b'{' => open.push(i + 1),
            b',' => {
                if let Some(s) = open.last_mut() {
                    entry(&mut out, *s, i + 1);
                    *s = i + 1;
                }
            }
            b')' | b']' | b'}' => {
                if let Some(s) = open.pop() {
                    entry(&mut out, s, i);
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_and_entries() {
        let text = "(a: [1, -2.5e3], b: \"x,\\\"y\") // c, 3";
        let kinds: Vec<(Kind, &str)> = tokenize(text)
            .iter()
            .map(|t| (t.kind, &text[t.range.clone()]))
            .collect();
        assert!(kinds.contains(&(Kind::Number, "-2.5e3")), "{kinds:?}");
        assert!(kinds.contains(&(Kind::Str, "\"x,\\\"y\"")), "{kinds:?}");
        assert!(kinds.contains(&(Kind::Entry, "a: [1, -2.5e3],")), "{kinds:?}");
        assert!(kinds.contains(&(Kind::Entry, "b: \"x,\\\"y\"")), "{kinds:?}");
        assert!(
            !kinds.iter().any(|(_, t)| *t == "c" || *t == "3"),
            "comments are skipped"
        );
    }
}
