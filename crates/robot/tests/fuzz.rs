//! Byte-level fuzzing of the URDF reader (issue 8 §2): the UR5's real URDF
//! and a small hand-written one (capsule, cylinder, box and sphere collision,
//! limits, a fixed joint, a prismatic joint) are damaged byte by byte (flips,
//! inserts, deletes, cuts, numbers replaced by huge, negative or NaN values,
//! repeated runs) or replaced by random bytes, and parsed from memory (mesh
//! files are not read). Nothing may panic; every `Ok` robot must pass
//! [`Robot::validate`] and give finite forward kinematics inside its limits.
//!
//! `cargo test -p robot --test fuzz` runs 128 cases;
//! `cargo test -p robot --test fuzz -- --ignored` runs 20 000.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{RngSeed, TestCaseError, TestRunner};
use robot::Robot;
use std::path::Path;
use std::sync::Arc;

/// Cases per run in `cargo test`. Fewer than the other parsers' fuzz tests:
/// every robot that loads gets its bounding ellipsoids fitted, about 0.4 s for
/// the UR5 in a debug build, and most damaged URDFs still load.
const CASES: u32 = 128;
/// Cases in the `--ignored` run.
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

const SMALL: &str = r#"<?xml version="1.0"?>
<robot name="small">
  <link name="base">
    <collision><origin xyz="0 0 0.1" rpy="0 0 0"/><geometry><cylinder radius="0.05" length="0.2"/></geometry></collision>
  </link>
  <link name="upper">
    <collision><geometry><capsule radius="0.04" length="0.3"/></geometry></collision>
    <collision><origin xyz="0.1 0 0" rpy="0 1.5707963 0"/><geometry><box size="0.1 0.2 0.3"/></geometry></collision>
  </link>
  <link name="slider"><collision><geometry><sphere radius="0.03"/></geometry></collision></link>
  <link name="tool0"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.2" rpy="0 0 0.5"/><axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" effort="10" velocity="1"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="upper"/><child link="slider"/>
    <origin xyz="0.3 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.25" effort="10" velocity="1"/>
  </joint>
  <joint name="flange" type="fixed">
    <parent link="slider"/><child link="tool0"/>
    <origin xyz="0 0 0.05" rpy="0 0 0"/>
  </joint>
</robot>
"#;

fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    let ur5 = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/robots/ur5/ur5_robot.urdf"),
    )
    .unwrap();
    vec![("ur5.urdf", ur5), ("small.urdf", SMALL.as_bytes().to_vec())]
}

fn check(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let xml = String::from_utf8_lossy(bytes);
    let base_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/robots/ur5");
    let tips = [None, Some("tool0")];
    for tip in tips {
        match Robot::from_urdf_str(&xml, &base_dir, name, tip) {
            Ok(robot) => {
                if let Err(e) = robot.validate() {
                    return Err(TestCaseError::fail(format!("Ok robot fails validate: {e}")));
                }
                // Mid-range joint values (0 for unlimited joints).
                let q: Vec<f64> = robot
                    .joints
                    .iter()
                    .filter(|j| j.is_actuated())
                    .map(|j| j.limits.map_or(0.0, |l| 0.5 * (l.min + l.max)))
                    .collect();
                prop_assert_eq!(q.len(), robot.dof());
                let frames = robot
                    .forward_kinematics(&q)
                    .map_err(|e| TestCaseError::fail(format!("FK at mid-limits fails: {e}")))?;
                prop_assert_eq!(frames.len(), robot.joints.len() + 1);
            }
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.contains(name), "{msg:?} does not name {name}");
            }
        }
    }
    Ok(())
}

#[test]
fn fuzz_urdf() {
    fuzz(Run::Short, seeds(), check);
}

#[test]
#[ignore = "long fuzz run (20 000 cases, about 14 min in debug): cargo test -p robot --test fuzz -- --ignored"]
fn fuzz_urdf_long() {
    fuzz(Run::Long, seeds(), check);
}

#[test]
fn seeds_are_valid() {
    for (name, bytes) in seeds() {
        let xml = String::from_utf8(bytes).unwrap();
        let robot = Robot::from_urdf_str(&xml, Path::new("."), name, Some("tool0"))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(robot.dof() >= 2, "{name}");
    }
}
