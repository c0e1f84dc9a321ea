//! Byte-level fuzzing of the URDF reader (issue 8 §2): the UR5's real URDF
//! and a small hand-written one (capsule, cylinder, box and sphere collision,
//! limits, a fixed joint, a prismatic joint) are damaged byte by byte (flips,
//! inserts, deletes, cuts, numbers replaced by huge, negative or NaN values,
//! repeated runs) or replaced by random bytes, and parsed from memory (mesh
//! files are not read). Nothing may panic; every `Ok` robot must pass
//! [`Robot::validate`] and give finite forward kinematics inside its limits.
//!
//! `cargo test -p robot --test it fuzz` runs 128 cases;
//! `cargo test -p robot --test it fuzz -- --ignored` runs 20 000.
//! The mutator and runner are `testkit::fuzz` (`FUZZ_SEED=<n>` replays a run).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use proptest::prelude::*;
use robot::Robot;
use std::path::Path;
use testkit::{LONG_CASES, Run, fuzz, names_source};

/// Cases per run in `cargo test`. Fewer than the other parsers' fuzz tests:
/// every robot that loads gets its bounding ellipsoids fitted, about 0.4 s for
/// the UR5 in a debug build, and most damaged URDFs still load.
const CASES: u32 = 128;

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
            Err(e) => names_source(&e, name)?,
        }
    }
    Ok(())
}

#[test]
fn fuzz_urdf() {
    fuzz(Run::Short(CASES), seeds(), check);
}

#[test]
#[ignore = "long fuzz run (20 000 cases, about 14 min in debug): cargo test -p robot --test it fuzz -- --ignored"]
fn fuzz_urdf_long() {
    fuzz(Run::Long(LONG_CASES), seeds(), check);
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
