//! Mutations of a text for the fuzz targets (`tests/fuzz.rs`, and the Hub target in
//! `tests/hub_push.rs`): replace a literal with a value that has broken readers before, cut the
//! text short, delete, duplicate or flip bytes. Included with `#[path]` by the tests that fuzz.

use proptest::prelude::*;

/// Inputs per target: `PROPTEST_CASES`, else 64 (seconds in `make test`).
pub fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

/// Values that have broken readers before: overflowing, not-a-number, empty, negative, huge.
pub const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e300",
    "1e-300",
    "-1",
    "0",
    "0.0",
    "4294967296",
    "18446744073709551615",
    "[]",
    "[1.0, 2.0, 3.0]",
    "\"\"",
    "\"0000\"",
    "\"../../x\"",
    "true",
    "{}",
    "-5.0",
    "1e9",
];

/// One edit of a text: replace the `k`-th number (or quoted string) with a token (of [`TOKENS`]
/// and the target's own), cut the text short, or delete, duplicate or flip a byte.
#[derive(Clone, Debug)]
pub enum Edit {
    Token { k: usize, token: usize },
    Truncate(usize),
    Delete(usize),
    Duplicate(usize),
    Flip(usize, u8),
}

pub fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let one = prop_oneof![
        4 => (any::<usize>(), any::<usize>()).prop_map(|(k, token)| Edit::Token { k, token }),
        1 => any::<usize>().prop_map(Edit::Truncate),
        1 => any::<usize>().prop_map(Edit::Delete),
        1 => any::<usize>().prop_map(Edit::Duplicate),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Flip(i, b)),
    ];
    prop::collection::vec(one, 1..4)
}

/// The byte ranges of number literals and quoted strings in `s`.
fn literals(s: &[u8]) -> Vec<(usize, usize)> {
    let mut out = vec![];
    let mut i = 0;
    while i < s.len() {
        let start = i;
        if s[i] == b'"' {
            i += 1;
            while i < s.len() && s[i] != b'"' {
                i += 1;
            }
            out.push((start, (i + 1).min(s.len())));
        } else if s[i].is_ascii_digit() || (s[i] == b'-' && s.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            i += 1;
            while i < s.len() && (s[i].is_ascii_alphanumeric() || b".+-".contains(&s[i])) {
                i += 1;
            }
            out.push((start, i));
            continue;
        }
        i += 1;
    }
    out
}

pub fn apply(base: &[u8], edits: &[Edit], extra: &[String]) -> Vec<u8> {
    let mut s = base.to_vec();
    for e in edits {
        if s.is_empty() {
            break;
        }
        let n = s.len();
        match *e {
            Edit::Token { k, token } => {
                let lits = literals(&s);
                if let Some(&(a, b)) = lits.get(k % lits.len().max(1)) {
                    let all = TOKENS.len() + extra.len();
                    let t = TOKENS
                        .get(token % all)
                        .copied()
                        .unwrap_or_else(|| &extra[token % all - TOKENS.len()]);
                    s.splice(a..b, t.bytes());
                }
            }
            Edit::Truncate(i) => s.truncate(i % n),
            Edit::Delete(i) => {
                s.remove(i % n);
            }
            Edit::Duplicate(i) => {
                let (a, b) = (i % n, (i % n + 64).min(n));
                let copy = s[a..b].to_vec();
                s.splice(a..a, copy);
            }
            Edit::Flip(i, b) => s[i % n] ^= b.max(1),
        }
    }
    s
}
