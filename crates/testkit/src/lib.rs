#![doc = include_str!("../README.md")]

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{RngSeed, TestCaseError, TestRunner};
use std::fmt::Display;
use std::sync::Arc;

/// A fuzz seed: a file name (the parser's source name, and the extension that
/// picks a format) and the valid bytes the mutator damages.
pub type Seed = (&'static str, Vec<u8>);

/// The RNG seed of every [`Run::Short`] run (unless `FUZZ_SEED` is set).
pub const SHORT_SEED: u64 = 0x5eed_0008;

/// Inputs per parser in `cargo test` ([`Run::Short`]), unless a parser's test
/// states why it runs fewer.
pub const CASES: u32 = 512;

/// Inputs per parser in the `#[ignore]`d long runs ([`Run::Long`]).
pub const LONG_CASES: u32 = 20_000;

/// Replacements for a number in a text header or field ([`Edit::Number`]).
pub const NUMBERS: [&str; 16] = [
    "0",
    "-1",
    "1",
    "4294967295",
    "4294967296",
    "4000000000",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "-9223372036854775809",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e309",
    "1.5",
];

/// Little-endian words written over binary count and size fields
/// ([`Edit::Word`]).
pub const WORDS: [u32; 8] = [
    0,
    1,
    0x7fff_ffff,
    0x8000_0000,
    u32::MAX,
    4_000_000_000,
    0x7fc0_0000, // f32 NaN
    0x7f80_0000, // f32 +inf
];

/// One damage done to a file by [`apply`]. Positions are proptest
/// [`Index`]es, scaled to the file's length when applied.
#[derive(Clone, Debug)]
pub enum Edit {
    /// Set the byte at a position.
    Set(Index, u8),
    /// XOR the byte at a position with a one-bit mask.
    Flip(Index, u8),
    /// Insert bytes before a position (or at the end).
    Insert(Index, Vec<u8>),
    /// Delete up to `n` bytes from a position.
    Delete(Index, usize),
    /// Cut the file at a position.
    Truncate(Index),
    /// Replace the number at or after a position by `NUMBERS[k]`.
    Number(Index, usize),
    /// Overwrite four bytes with `WORDS[k]`.
    Word(Index, usize),
    /// Copy a run of bytes elsewhere (repeated records, lines, tags).
    Duplicate(Index, Index, usize),
}

/// Any one [`Edit`], each kind equally likely.
pub fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<Index>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<Index>(), 0u8..8).prop_map(|(i, b)| Edit::Flip(i, 1 << b)),
        (any::<Index>(), vec(any::<u8>(), 1..16)).prop_map(|(i, b)| Edit::Insert(i, b)),
        (any::<Index>(), 1usize..32).prop_map(|(i, n)| Edit::Delete(i, n)),
        any::<Index>().prop_map(Edit::Truncate),
        (any::<Index>(), 0..NUMBERS.len()).prop_map(|(i, k)| Edit::Number(i, k)),
        (any::<Index>(), 0..WORDS.len()).prop_map(|(i, k)| Edit::Word(i, k)),
        (any::<Index>(), any::<Index>(), 1usize..64).prop_map(|(a, b, n)| Edit::Duplicate(a, b, n)),
    ]
}

/// Apply one edit to `bytes`. An empty file can only grow by an
/// [`Edit::Insert`]; every other edit leaves it empty.
///
/// `edit` must come from [`edit`]: an [`Edit::Number`] or [`Edit::Word`] index
/// past [`NUMBERS`] or [`WORDS`] panics.
pub fn apply(bytes: &mut Vec<u8>, edit: &Edit) {
    let n = bytes.len();
    if n == 0 {
        if let Edit::Insert(_, b) = edit {
            bytes.extend_from_slice(b);
        }
        return;
    }
    match edit {
        Edit::Set(i, b) => bytes[i.index(n)] = *b,
        Edit::Flip(i, m) => bytes[i.index(n)] ^= m,
        Edit::Insert(i, b) => {
            let at = i.index(n + 1);
            bytes.splice(at..at, b.iter().copied());
        }
        Edit::Delete(i, len) => {
            let at = i.index(n);
            bytes.drain(at..(at + len).min(n));
        }
        Edit::Truncate(i) => bytes.truncate(i.index(n)),
        Edit::Number(i, k) => {
            let from = i.index(n);
            let start = bytes[from..]
                .iter()
                .position(u8::is_ascii_digit)
                .map_or(from, |p| from + p);
            let end = bytes[start..]
                .iter()
                .position(|b| !(b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'e' | b'+')))
                .map_or(n, |p| start + p);
            bytes.splice(start..end, NUMBERS[*k].bytes());
        }
        Edit::Word(i, k) => {
            let at = i.index(n);
            for (j, b) in WORDS[*k].to_le_bytes().into_iter().enumerate() {
                if let Some(x) = bytes.get_mut(at + j) {
                    *x = b;
                }
            }
        }
        Edit::Duplicate(a, b, len) => {
            let from = a.index(n);
            let chunk = bytes[from..(from + len).min(n)].to_vec();
            let at = b.index(n + 1);
            bytes.splice(at..at, chunk);
        }
    }
}

/// Inputs for a parser: `(seed name, bytes)`, a seed damaged by up to eight
/// edits (nine cases in ten) or random bytes under a seed's name.
///
/// Panics if `seeds` is empty.
pub fn damaged(seeds: Vec<Seed>) -> impl Strategy<Value = Seed> {
    assert!(!seeds.is_empty());
    let seeds = Arc::new(seeds);
    let names: Vec<&'static str> = seeds.iter().map(|(name, _)| *name).collect();
    let n = seeds.len();
    prop_oneof![
        9 => (0..n, vec(edit(), 0..8)).prop_map(move |(k, edits)| {
            let (name, mut bytes) = seeds[k].clone();
            for e in &edits {
                apply(&mut bytes, e);
            }
            (name, bytes)
        }),
        1 => (0..n, vec(any::<u8>(), 0..300)).prop_map(move |(k, bytes)| (names[k], bytes)),
    ]
}

/// How long a fuzz run is, in inputs per [`fuzz`] call.
#[derive(Clone, Copy, Debug)]
pub enum Run {
    /// This many inputs from the fixed RNG seed [`SHORT_SEED`]: the same
    /// inputs on every `cargo test`, so a failure reproduces.
    Short(u32),
    /// This many inputs from a fresh seed (printed), for `#[ignore]`d runs.
    Long(u32),
}

/// Run `check` on inputs made from `seeds` (see [`damaged`]); a panic or a
/// failed assertion fails the test with the (shrunk) input. `FUZZ_SEED=<n>`
/// replays a run (an abort, e.g. a failed allocation, prints no input, only
/// the seed line `fuzz: <cases> cases, FUZZ_SEED=<n>` on stderr).
///
/// Panics, naming the seed, when `check` fails or panics on some input.
pub fn fuzz(run: Run, seeds: Vec<Seed>, check: impl Fn(&str, &[u8]) -> Result<(), TestCaseError>) {
    let (cases, default_seed) = match run {
        Run::Short(cases) => (cases, SHORT_SEED),
        Run::Long(cases) => (
            cases,
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(1, |d| d.as_nanos() as u64),
        ),
    };
    let seed = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default_seed);
    eprintln!("fuzz: {cases} cases, FUZZ_SEED={seed}");
    let mut runner = TestRunner::new(ProptestConfig {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(seed),
        ..ProptestConfig::default()
    });
    let result = runner.run(&damaged(seeds), |(name, bytes)| check(name, &bytes));
    if let Err(e) = result {
        panic!("FUZZ_SEED={seed}: {e}");
    }
}

/// The check every parser's error must pass: its message names the source
/// (`name`, the file name or the name the bytes were parsed under).
pub fn names_source(error: &dyn Display, name: &str) -> Result<(), TestCaseError> {
    let msg = error.to_string();
    prop_assert!(msg.contains(name), "{msg:?} does not name {name}");
    Ok(())
}
