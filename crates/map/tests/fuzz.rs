//! Byte-level fuzzing of the map crate's CSV readers (issue 8 §2): disc files
//! ([`map::sld_io::parse_discs_csv`]) and joint-pose files
//! ([`map::segment_io::parse_poses_csv`]). Small valid files are damaged byte by
//! byte (flips, inserts, deletes, cuts, numbers replaced by huge, negative or
//! NaN values, repeated runs) or replaced by random bytes, and parsed from
//! memory. Nothing may panic; an error names the source; every `Ok` has one
//! record per non-blank data line, with finite values, unit normals and
//! positive radii.
//!
//! `cargo test -p map --test fuzz` runs 512 cases per reader;
//! `cargo test -p map --test fuzz -- --ignored` runs 20 000.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use map::segment_io::parse_poses_csv;
use map::sld_io::parse_discs_csv;
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{RngSeed, TestCaseError, TestRunner};
use std::sync::Arc;

/// Cases per reader in `cargo test`.
const CASES: u32 = 512;
/// Cases per reader in the `--ignored` run.
const LONG_CASES: u32 = 20_000;

// ---------------------------------------------------------------------------
// Byte-level mutator (the same in every crate's tests/fuzz.rs): a seed file
// damaged by up to eight edits, or (one case in ten) random bytes.

/// Replacements for a number in a text header or field.
const NUMBERS: [&str; 16] = [
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
/// Little-endian words written over binary count and size fields.
const WORDS: [u32; 8] = [
    0,
    1,
    0x7fff_ffff,
    0x8000_0000,
    u32::MAX,
    4_000_000_000,
    0x7fc0_0000, // f32 NaN
    0x7f80_0000, // f32 +inf
];

#[derive(Clone, Debug)]
enum Edit {
    Set(Index, u8),
    Flip(Index, u8),
    Insert(Index, Vec<u8>),
    Delete(Index, usize),
    Truncate(Index),
    /// Replace the number at or after a position by `NUMBERS[k]`.
    Number(Index, usize),
    /// Overwrite four bytes with `WORDS[k]`.
    Word(Index, usize),
    /// Copy a run of bytes elsewhere (repeated records, lines, tags).
    Duplicate(Index, Index, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
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

fn apply(bytes: &mut Vec<u8>, edit: &Edit) {
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
fn damaged(seeds: Vec<(&'static str, Vec<u8>)>) -> impl Strategy<Value = (&'static str, Vec<u8>)> {
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

/// How long a fuzz run is.
#[derive(Clone, Copy, Debug)]
enum Run {
    /// `CASES` inputs per parser from a fixed RNG seed: the same inputs on
    /// every `cargo test`, so a failure reproduces.
    Short,
    /// `LONG_CASES` inputs per parser from a fresh seed (printed).
    Long,
}

/// Run `check` on inputs made from `seeds`; a panic or a failed assertion
/// fails the test with the (shrunk) input. `FUZZ_SEED=<n>` replays a run (an
/// abort, e.g. a failed allocation, prints no input, only the seed line).
fn fuzz(
    run: Run,
    seeds: Vec<(&'static str, Vec<u8>)>,
    check: impl Fn(&str, &[u8]) -> Result<(), TestCaseError>,
) {
    let (cases, default_seed) = match run {
        Run::Short => (CASES, 0x5eed_0008),
        Run::Long => (
            LONG_CASES,
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

// ---------------------------------------------------------------------------
// Seeds and checks

fn disc_seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        (
            "discs.csv",
            b"cx,cy,cz,nx,ny,nz,radius,points\n\
              0.5,-1.25,0.75,0,0,1,0.04,12\n\
              0.1,0.2,0.3,0.6,0.8,0,0.04,7\n\
              \n\
              -3e-2,1e1,2.5,0.5773502691896258,0.5773502691896258,0.5773502691896258,0.02,100\n"
                .to_vec(),
        ),
        (
            "segments.csv",
            b"segment,points,radius,cz,cy,cx,nz,ny,nx,p_steel\r\n\
              3,9,0.05,1,2,3,1,0,0,0.25\r\n\
              0,40,0.05,-1,-2,-3,0,-1,0,1\r\n"
                .to_vec(),
        ),
    ]
}

fn pose_seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![(
        "poses.csv",
        b"q1,q2,q3,q4,q5,q6\n0,-0.9599310885968813,2.8797932657906435,0,-1.9198621771937625,0\n\
          \n0.1, 0.2, 0.3, -0.4, 0.5, 6.283185307179586\n"
            .to_vec(),
    )]
}

/// Non-blank lines after the first non-blank (header) line.
fn data_lines(text: &str) -> usize {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .count()
        .saturating_sub(1)
}

fn check_discs(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    match parse_discs_csv(&text, name) {
        Ok(discs) => {
            prop_assert_eq!(discs.len(), data_lines(&text));
            for d in &discs {
                prop_assert!(d.centre.iter().all(|c| c.is_finite()));
                prop_assert!(
                    (d.normal.norm() - 1.0).abs() < 1e-9,
                    "normal {:?}",
                    d.normal
                );
                prop_assert!(d.radius_m > 0.0 && d.radius_m.is_finite());
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.contains(name), "{msg:?} does not name {name}");
        }
    }
    Ok(())
}

fn check_poses(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    match parse_poses_csv(&text, name) {
        Ok(poses) => {
            prop_assert_eq!(poses.len(), data_lines(&text));
            prop_assert!(poses.iter().flatten().all(|q| q.is_finite()));
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.contains(name), "{msg:?} does not name {name}");
        }
    }
    Ok(())
}

#[test]
fn fuzz_discs_csv() {
    fuzz(Run::Short, disc_seeds(), check_discs);
}

#[test]
fn fuzz_poses_csv() {
    fuzz(Run::Short, pose_seeds(), check_poses);
}

#[test]
#[ignore = "long fuzz run (20 000 cases per reader): cargo test -p map --test fuzz -- --ignored"]
fn fuzz_long() {
    fuzz(Run::Long, disc_seeds(), check_discs);
    fuzz(Run::Long, pose_seeds(), check_poses);
}

#[test]
fn seeds_are_valid() {
    let parsed: Vec<_> = disc_seeds()
        .into_iter()
        .map(|(name, bytes)| parse_discs_csv(std::str::from_utf8(&bytes).unwrap(), name).unwrap())
        .collect();
    let [a, b] = &parsed[..] else {
        panic!("two seeds")
    };
    assert_eq!((a.len(), b.len()), (3, 2));
    assert_eq!(b[0].centre, geom::Point3::new(3.0, 2.0, 1.0));
    let poses = parse_poses_csv(std::str::from_utf8(&pose_seeds()[0].1).unwrap(), "p").unwrap();
    assert_eq!(poses.len(), 2);
}
