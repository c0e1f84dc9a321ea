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

use proptest::prelude::*;
use record::bag::{
    BadMessages, BagSweeps, BagWriter, RangeSets, SCANNER_FRAME, ScanTopics, joint_state,
    laser_scan, link_frames, point_cloud, range, sets_from_bag, static_frames, sweeps_from_bag,
    topics,
};
use std::io::Cursor;
use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};
use testkit::{LONG_CASES, Run, fuzz, names_source};

/// Cases in `cargo test`: issue 48 asks for at least 10 000 damaged bags.
const BAG_CASES: u32 = 10_000;
/// Chunks of about this many bytes (uncompressed): several per bag.
const CHUNK_BYTES: u64 = 1500;

const EXPLORE: &str = "explore.mcap";
const FOLLOW: &str = "follow.mcap";

fn robot(name: &str) -> robot::Robot {
    robot::builtin(name).unwrap()
}

/// An explore run's bag: the arm moving through six joint states, a scan
/// of 12 bearings every 0.25 s between them, a sweep cloud every 2 s.
fn explore_bag() -> Vec<u8> {
    let robot = robot("denso-vm6083");
    let names: Vec<String> = robot
        .joint_names()
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    let mut w = BagWriter::with_chunk_size(Cursor::new(Vec::new()), Some(CHUNK_BYTES)).unwrap();
    let base = geom::Isometry3::translation(0.5, 0.0, 0.0);
    w.write(topics::TF_STATIC, 0, &static_frames(&robot, &base))
        .unwrap();
    let bearings: Vec<f64> = (0..12).map(|i| -0.6 + 0.1 * f64::from(i)).collect();
    let second = 1_000_000_000;
    for k in 0..6u32 {
        let t = u64::from(k) * second;
        let q = [
            0.1 * f64::from(k),
            -0.96,
            2.88 - 0.05 * f64::from(k),
            0.0,
            -1.92,
            0.0,
        ];
        w.write(topics::JOINT_STATES, t, &joint_state(t, &names, &q))
            .unwrap();
        if k == 5 {
            break;
        }
        for s in 0..4u32 {
            let ts = t + u64::from(s) * second / 4;
            let ranges: Vec<Option<f64>> = (0..12)
                .map(|i| (i % 5 != 3).then(|| 1.0 + 0.05 * f64::from(i + s)))
                .collect();
            let intensities: Vec<f64> = (0..12).map(f64::from).collect();
            let mut scan = laser_scan(ts, &bearings, &ranges, &intensities, (0.1, 10.0), 0.1);
            scan.header.frame_id = SCANNER_FRAME.to_owned();
            w.write(topics::SCAN, ts, &scan).unwrap();
        }
        if k % 2 == 1 {
            let tm = t + second - 1;
            w.write(topics::SWEEP, tm, &point_cloud(tm, [])).unwrap();
        }
    }
    w.finish().unwrap().into_inner()
}

/// A follow run's bag: the point robot moving through ten joint states, its
/// links on `/tf` with each, four range finders read at each.
fn follow_bag() -> Vec<u8> {
    let robot = robot("point3");
    let names: Vec<String> = robot
        .joint_names()
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    let mut w = BagWriter::with_chunk_size(Cursor::new(Vec::new()), Some(CHUNK_BYTES)).unwrap();
    w.write(
        topics::TF_STATIC,
        0,
        &static_frames(&robot, &geom::Isometry3::identity()),
    )
    .unwrap();
    for k in 0..10u32 {
        let t = u64::from(k) * 100_000_000;
        let q: Vec<f64> = (0..robot.dof())
            .map(|j| 0.01 * f64::from(k) * (j as f64 + 1.0))
            .collect();
        w.write(topics::JOINT_STATES, t, &joint_state(t, &names, &q))
            .unwrap();
        w.write(topics::TF, t, &link_frames(t, &robot, &q)).unwrap();
        for j in 0..4 {
            let d = (j != 2).then(|| 0.5 + 0.01 * f64::from(k));
            w.write(&topics::range_finder(j), t, &range(t, j, 2.0, d))
                .unwrap();
        }
    }
    w.finish().unwrap().into_inner()
}

fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![(EXPLORE, explore_bag()), (FOLLOW, follow_bag())]
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
