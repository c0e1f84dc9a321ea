//! Byte-level fuzzing of the surface crate's readers (issue 8 §2): sensor sets
//! (JSON lines, [`read_sets_jsonl`]) and initial segments (JSON,
//! [`read_initial_segments_json`]). Small valid files are damaged byte by byte
//! (flips, inserts, deletes, cuts, numbers replaced by huge, negative or NaN
//! values, repeated runs) or replaced by random bytes, and parsed from memory.
//! Nothing may panic; an error names the source; every `Ok` is
//! self-consistent (one set per non-blank line, each set passing
//! [`SensorSet::validate`]; segments of at least three finite vertices).
//!
//! `cargo test -p surface --test it fuzz` runs 512 cases per reader;
//! `cargo test -p surface --test it fuzz -- --ignored` runs 20 000.
//! The mutator and runner are `testkit::fuzz` (`FUZZ_SEED=<n>` replays a run).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use proptest::prelude::*;
use surface::{SensorSet, read_initial_segments_json, read_sets_jsonl};
use testkit::{CASES, LONG_CASES, Run, fuzz, names_source};

// ---------------------------------------------------------------------------
// Seeds and checks

fn set_seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        (
            "sets.jsonl",
            b"{\"points\": [[0, 0, 1], [0.1, 0, 1.02]], \"axes\": [[0, 0, -1], [0.6, 0, -0.8]]}\n\
              \n\
              {\"points\": [], \"axes\": []}\n\
              {\"axes\": [[1, 0, 0]], \"points\": [[-2.5e-3, 1e2, 3]]}\r\n"
                .to_vec(),
        ),
        (
            "one.jsonl",
            b"{\"points\":[[1.5,2.25,-0.125]],\"axes\":[[0.0,-1.0,0.0]]}".to_vec(),
        ),
    ]
}

fn segment_seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![(
        "table.json",
        b"{\"segments\": [[[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]],\n\
          [[0, 0, 1], [1, 0, 1], [0.5, 0.75, 1]]]}\n"
            .to_vec(),
    )]
}

fn check_sets(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    match read_sets_jsonl(bytes, name) {
        Ok(sets) => {
            // One set per non-blank line (the whole input is UTF-8 here).
            let text = std::str::from_utf8(bytes)
                .map_err(|_| TestCaseError::fail("Ok from input that is not UTF-8"))?;
            let lines = text.lines().filter(|l| !l.trim().is_empty()).count();
            prop_assert_eq!(sets.len(), lines);
            for set in &sets {
                prop_assert!(set.validate().is_ok());
                prop_assert_eq!(set.points.len(), set.axes.len());
            }
        }
        Err(e) => names_source(&e, name)?,
    }
    Ok(())
}

fn check_segments(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    match read_initial_segments_json(&String::from_utf8_lossy(bytes), name) {
        Ok(segments) => {
            for s in &segments {
                prop_assert!(s.len() >= 3);
                prop_assert!(s.iter().all(|p| p.iter().all(|c| c.is_finite())));
            }
        }
        Err(e) => names_source(&e, name)?,
    }
    Ok(())
}

#[test]
fn fuzz_sets_jsonl() {
    fuzz(Run::Short(CASES), set_seeds(), check_sets);
}

#[test]
fn fuzz_initial_segments_json() {
    fuzz(Run::Short(CASES), segment_seeds(), check_segments);
}

#[test]
#[ignore = "long fuzz run (20 000 cases per reader): cargo test -p surface --test it fuzz -- --ignored"]
fn fuzz_long() {
    fuzz(Run::Long(LONG_CASES), set_seeds(), check_sets);
    fuzz(Run::Long(LONG_CASES), segment_seeds(), check_segments);
}

#[test]
fn seeds_are_valid() {
    let sets = read_sets_jsonl(&set_seeds()[0].1[..], "s").unwrap();
    assert_eq!(
        sets.iter().map(SensorSet::len).collect::<Vec<_>>(),
        [2, 0, 1]
    );
    let segs = read_initial_segments_json(std::str::from_utf8(&segment_seeds()[0].1).unwrap(), "t")
        .unwrap();
    assert_eq!(segs.iter().map(Vec::len).collect::<Vec<_>>(), [4, 3]);
}
