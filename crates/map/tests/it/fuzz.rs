//! Byte-level fuzzing of the map crate's CSV readers (issue 8 §2): disc files
//! ([`map::sld_io::parse_discs_csv`]) and joint-pose files
//! ([`map::segment_io::parse_poses_csv`]). Small valid files are damaged byte by
//! byte (flips, inserts, deletes, cuts, numbers replaced by huge, negative or
//! NaN values, repeated runs) or replaced by random bytes, and parsed from
//! memory. Nothing may panic; an error names the source; every `Ok` has one
//! record per non-blank data line, with finite values, unit normals and
//! positive radii.
//!
//! `cargo test -p map --test it fuzz` runs 512 cases per reader;
//! `cargo test -p map --test it fuzz -- --ignored` runs 20 000.
//! The mutator and runner are `testkit::fuzz` (`FUZZ_SEED=<n>` replays a run).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use map::segment_io::parse_poses_csv;
use map::sld_io::parse_discs_csv;
use proptest::prelude::*;
use testkit::{CASES, LONG_CASES, Run, fuzz, names_source};

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
        Err(e) => names_source(&e, name)?,
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
        Err(e) => names_source(&e, name)?,
    }
    Ok(())
}

#[test]
fn fuzz_discs_csv() {
    fuzz(Run::Short(CASES), disc_seeds(), check_discs);
}

#[test]
fn fuzz_poses_csv() {
    fuzz(Run::Short(CASES), pose_seeds(), check_poses);
}

#[test]
#[ignore = "long fuzz run (20 000 cases per reader): cargo test -p map --test it fuzz -- --ignored"]
fn fuzz_long() {
    fuzz(Run::Long(LONG_CASES), disc_seeds(), check_discs);
    fuzz(Run::Long(LONG_CASES), pose_seeds(), check_poses);
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
