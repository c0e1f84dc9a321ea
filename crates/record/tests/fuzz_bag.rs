//! Byte-level fuzzing of the bag reader (issue 48, acceptance 2): a small
//! bag of each kind a robot brings (an explore run's: joint states, the
//! static frames, laser scans and sweep clouds, read as `surveyor map --bag`
//! does; a follow run's: joint states, `/tf`, `/tf_static` and range
//! readings, read as `surveyor model --bag` does), in several chunks, is
//! damaged by `testkit`'s mutator (flips, inserts, deletes, cuts, numbers
//! and words replaced by huge, negative or NaN values, repeated runs) or
//! replaced by random bytes. Nothing may panic or abort; every read either
//! refuses the bag with a message naming it, or gives what the intact bag
//! gives. With bad messages skipped, every read either refuses or says
//! what it skipped, or gives what the intact bag gives.
//!
//! 10 000 cases in `cargo test` (about 10 s in release);
//! `cargo test --release -p record --test fuzz_bag -- --ignored` runs
//! 20 000 more from a fresh seed (`FUZZ_SEED=<n>` replays a run).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

mod support;

use proptest::prelude::*;
use record::bag::{BadMessages, BagSweeps, RangeSets, ScanTopics, sets_from_bag, sweeps_from_bag};
use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};
use support::{EXPLORE, FOLLOW, explore_bag, follow_bag, robot};
use testkit::{LONG_CASES, Run, fuzz, names_source};

/// Cases in `cargo test`: issue 48 asks for at least 10 000 damaged bags.
const BAG_CASES: u32 = 10_000;
fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        (EXPLORE, explore_bag(&|_| {})),
        (FOLLOW, follow_bag(&|_| {})),
    ]
}

/// What a bag of one kind maps to, the way its command reads it.
#[derive(Debug, PartialEq)]
enum Mapped {
    Sweeps(Vec<sensor::Sweep>, geom::Isometry3),
    Sets(Vec<surface::SensorSet>, Vec<String>),
}

fn map(
    name: &str,
    path: &Path,
    mode: BadMessages,
) -> Result<(Mapped, record::bag::Skipped), record::bag::BagError> {
    if name == EXPLORE {
        let BagSweeps {
            sweeps,
            world_from_base,
            skipped,
            ..
        } = sweeps_from_bag(path, &robot("denso-vm6083"), &ScanTopics::default(), mode)?;
        Ok((Mapped::Sweeps(sweeps, world_from_base), skipped))
    } else {
        let RangeSets {
            sets,
            topics,
            skipped,
            ..
        } = sets_from_bag(path, &[], 1000, mode)?;
        Ok((Mapped::Sets(sets, topics), skipped))
    }
}

/// The intact bags' maps, made once.
fn intact(name: &str) -> &'static Mapped {
    static MAPS: OnceLock<Vec<(&'static str, Mapped)>> = OnceLock::new();
    let maps = MAPS.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        seeds()
            .into_iter()
            .map(|(name, bytes)| {
                let path = dir.path().join(name);
                std::fs::write(&path, bytes).unwrap();
                let (m, skipped) = map(name, &path, BadMessages::Refuse).unwrap();
                assert_eq!(skipped, record::bag::Skipped::default());
                (name, m)
            })
            .collect()
    });
    &maps.iter().find(|(n, _)| *n == name).unwrap().1
}

/// Outcomes: mapped as intact, refused, read with something skipped.
static OUTCOMES: [AtomicUsize; 3] = [const { AtomicUsize::new(0) }; 3];

fn count(k: usize) {
    OUTCOMES[k].fetch_add(1, Ordering::Relaxed);
}

fn check(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    thread_local! {
        static DIR: tempfile::TempDir = tempfile::tempdir().unwrap();
    }
    let path = DIR.with(|d| d.path().join(name));
    // Removed first: ext4 flushes a file truncated and written again on
    // close (auto_da_alloc), 3 ms a case here.
    let _ = std::fs::remove_file(&path);
    std::fs::write(&path, bytes).unwrap();
    match map(name, &path, BadMessages::Refuse) {
        Ok((m, skipped)) => {
            prop_assert_eq!(&skipped, &record::bag::Skipped::default());
            prop_assert!(&m == intact(name), "{name}: mapped differently, silently");
            count(0);
        }
        Err(e) => {
            names_source(&e, name)?;
            count(1);
        }
    }
    match map(name, &path, BadMessages::Skip) {
        Ok((m, skipped)) => {
            if skipped.what.is_empty() {
                prop_assert!(
                    &m == intact(name),
                    "{name}: skipped nothing, mapped differently"
                );
            } else {
                count(2);
            }
        }
        Err(e) => names_source(&e, name)?,
    }
    Ok(())
}

#[test]
fn fuzz_bags() {
    let t = std::time::Instant::now();
    fuzz(Run::Short(BAG_CASES), seeds(), check);
    let [intact, refused, skipped] = OUTCOMES.each_ref().map(|c| c.load(Ordering::Relaxed));
    eprintln!(
        "fuzz_bags: {BAG_CASES} bags in {:.1} s: {intact} mapped as intact, {refused} refused; with bad messages skipped, {skipped} read on",
        t.elapsed().as_secs_f64()
    );
}

#[test]
#[ignore = "long fuzz run (20 000 cases): cargo test --release -p record --test fuzz_bag -- --ignored"]
fn fuzz_bags_long() {
    fuzz(Run::Long(LONG_CASES), seeds(), check);
}

/// The seeds map as the fuzz test expects.
#[test]
fn seeds_map() {
    for (name, _) in seeds() {
        match intact(name) {
            Mapped::Sweeps(s, _) => assert!(s.len() >= 2, "{s:?}"),
            Mapped::Sets(s, t) => assert_eq!((s.len(), t.len()), (10, 4)),
        }
    }
}
