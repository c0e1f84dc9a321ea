//! Byte-level fuzzing of the scenario TOML reader (issue 8 §2): every
//! built-in scenario, written as TOML, is damaged byte by byte (flips,
//! inserts, deletes, cuts, numbers replaced by huge, negative or NaN values,
//! repeated runs) or replaced by random bytes, then parsed from memory
//! ([`Scenario::from_toml`]) and from a file ([`Scenario::load`]). Nothing may
//! panic; an error names the source; an `Ok` scenario writes back to TOML that
//! parses to the same TOML again.
//!
//! `cargo test -p sim --test it fuzz` runs 512 cases;
//! `cargo test -p sim --test it fuzz -- --ignored` runs 20 000.
//! The mutator and runner are `testkit::fuzz` (`FUZZ_SEED=<n>` replays a run).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use proptest::prelude::*;
use scenario::{BUILTIN_NAMES, Scenario, builtin_scenario};
use testkit::{CASES, LONG_CASES, Run, fuzz, names_source};

// ---------------------------------------------------------------------------
// Seeds and checks

fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    BUILTIN_NAMES
        .iter()
        .map(|name| {
            let toml = builtin_scenario(name).unwrap().to_toml().unwrap();
            (*name, toml.into_bytes())
        })
        .collect()
}

fn check_ok(scenario: &Scenario) -> Result<(), TestCaseError> {
    let fail = |what: &str, e: &dyn std::fmt::Display| TestCaseError::fail(format!("{what}: {e}"));
    let once = scenario
        .to_toml()
        .map_err(|e| fail("Ok scenario does not write", &e))?;
    let again = Scenario::from_toml(&once, "again")
        .map_err(|e| fail("written scenario does not parse", &e))?;
    let twice = again.to_toml().map_err(|e| fail("second write", &e))?;
    prop_assert_eq!(once, twice);
    Ok(())
}

fn check(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let source = format!("{name}.toml");
    match Scenario::from_toml(&String::from_utf8_lossy(bytes), &source) {
        Ok(s) => check_ok(&s)?,
        Err(e) => names_source(&e, &source)?,
    }
    // The same bytes as a file (not UTF-8 is an error there, not a panic).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(&source);
    std::fs::write(&path, bytes).unwrap();
    match Scenario::load(path.to_str().unwrap()) {
        Ok(loaded) => check_ok(&loaded.scenario)?,
        Err(e) => names_source(&e, &source)?,
    }
    Ok(())
}

#[test]
fn fuzz_scenario_toml() {
    fuzz(Run::Short(CASES), seeds(), check);
}

#[test]
#[ignore = "long fuzz run (20 000 cases): cargo test -p sim --test it fuzz -- --ignored"]
fn fuzz_scenario_toml_long() {
    fuzz(Run::Long(LONG_CASES), seeds(), check);
}

#[test]
fn seeds_are_valid() {
    for (name, bytes) in seeds() {
        let s = Scenario::from_toml(std::str::from_utf8(&bytes).unwrap(), name).unwrap();
        assert_eq!(Some(s), builtin_scenario(name));
    }
}
