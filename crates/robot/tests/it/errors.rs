//! Bad input gives a clear error, never a panic: each message names what it should
//! (file, line, element, attribute, joint, expected value).

// Helpers outside #[test] functions unwrap too: a failure is a test failure.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::scene_meshes;

use geom::{Point3, Real};
use robot::{DhRow, JointLimits, Robot, RobotError};
use std::path::Path;

fn parse(xml: &str, tip: Option<&str>) -> Result<Robot, RobotError> {
    Robot::from_urdf_str(xml, Path::new("/nonexistent"), "test.urdf", tip)
}

fn err(xml: &str, tip: Option<&str>) -> String {
    match parse(xml, tip) {
        Ok(_) => panic!("expected an error for:\n{xml}"),
        Err(e) => e.to_string(),
    }
}

/// A two-link robot with one joint whose inner XML is `joint_body` (line 5 on).
fn one_joint(kind: &str, joint_body: &str) -> String {
    format!(
        r#"<robot name="t">
  <link name="a"/>
  <link name="b"/>
  <joint name="j1" type="{kind}">
    <parent link="a"/>
    <child link="b"/>
{joint_body}
  </joint>
</robot>"#
    )
}

fn assert_contains(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(
            message.contains(p),
            "message {message:?} does not contain {p:?}"
        );
    }
}

#[test]
fn wrong_joint_count_and_nan() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let e = robot.forward_kinematics(&[0.0; 5]).unwrap_err();
    assert_eq!(
        e,
        RobotError::JointCount {
            expected: 6,
            got: 5
        }
    );
    assert_contains(&e.to_string(), &["expected 6 joint values", "got 5"]);
    let e = robot
        .tool_pose(&[0.0, 0.0, Real::NAN, 0.0, 0.0, 0.0])
        .unwrap_err();
    assert_contains(&e.to_string(), &["joint joint3", "q[2]", "NaN"]);
    let e = robot
        .jacobian(
            &[0.0, 0.0, 0.0, Real::INFINITY, 0.0, 0.0],
            robot::LinkId(6),
            &Point3::origin(),
        )
        .unwrap_err();
    assert_contains(&e.to_string(), &["joint4", "inf"]);
    assert!(!robot.within_limits(&[0.0; 7]));
    assert!(!robot.within_limits(&[Real::NAN; 6]));
    assert!(robot.within_limits(&[0.0; 6]));
    assert!(
        !robot.within_limits(&[0.0, 0.0, 0.0, 0.0, 0.0, 7.0]),
        "joint 6 is limited to ±360°"
    );
    let e = robot
        .jacobian(&[0.0; 6], robot::LinkId(7), &Point3::origin())
        .unwrap_err();
    assert_contains(&e.to_string(), &["link index 7", "7 links"]);
    let e = robot
        .min_algebraic_distance(
            &[0.0; 6],
            &[Point3::origin(), Point3::new(0.0, Real::NAN, 0.0)],
        )
        .unwrap_err();
    assert_contains(&e.to_string(), &["point 1", "NaN"]);
    assert!(robot.scanner_pose(&[0.0; 3]).is_err());
}

#[test]
fn unknown_builtin_lists_the_valid_names() {
    let e = robot::builtin("denso").unwrap_err().to_string();
    assert_contains(&e, &["'denso'", "denso-vm6083", "point3", "arm4"]);
    assert_eq!(robot::builtin_names(), ["denso-vm6083", "point3", "arm4"]);
}

#[test]
fn bad_dh_rows() {
    let e = Robot::from_dh(
        "x",
        &[
            DhRow::new(0.1, 0.0, 0.0, 0.0),
            DhRow::new(Real::NAN, 0.0, 0.0, 0.0),
        ],
    )
    .unwrap_err()
    .to_string();
    assert_contains(&e, &["DH row 1 (joint 2)", "a = NaN"]);
    let e = Robot::from_dh(
        "x",
        &[DhRow::new(0.1, 0.0, 0.0, 0.0).with_limits(JointLimits::new(1.0, -1.0))],
    )
    .unwrap_err()
    .to_string();
    assert_contains(&e, &["DH row 0", "min ≤ max"]);
}

#[test]
fn malformed_xml_names_the_line() {
    let xml = "<robot name=\"t\">\n  <link name=\"a\">\n  <link name=\"b\"/>\n</robot>\n";
    let e = parse(xml, None).unwrap_err();
    match &e {
        RobotError::Xml { file, line, .. } => {
            assert_eq!(file, "test.urdf");
            assert_eq!(*line, 4, "{e}");
        }
        other => panic!("expected an XML error, got {other}"),
    }
    assert!(e.to_string().starts_with("test.urdf:4:"), "{e}");
    let e = err("<model/>", None);
    assert_contains(&e, &["test.urdf:1", "<model>", "expected <robot>"]);
    let e = err("<robot name=\"t\"></robot>", None);
    assert_contains(&e, &["no <link>"]);
}

#[test]
fn missing_attributes_and_elements() {
    let xml = "<robot name=\"t\">\n  <link name=\"a\"/>\n  <link/>\n</robot>";
    assert_contains(&err(xml, None), &["test.urdf:3", "<link>", "'name'"]);
    let xml = "<robot name=\"t\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <joint name=\"j\">\n  </joint>\n</robot>";
    assert_contains(&err(xml, None), &["test.urdf:4", "<joint>", "'type'"]);
    let xml = "<robot name=\"t\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n  </joint>\n</robot>";
    assert_contains(&err(xml, None), &["test.urdf:4", "<joint>", "<child>"]);
    let xml = one_joint(
        "revolute",
        "    <origin/>\n    <axis xyz=\"0 0 1\"/>\n    <limit upper=\"1\"/>",
    );
    // Origin attributes default to zero, lower defaults to 0 (URDF spec).
    let robot = parse(&xml, None).unwrap();
    assert_eq!(robot.limits(), [Some(JointLimits::new(0.0, 1.0))]);
    let xml = "<robot name=\"t\">\n  <link name=\"a\">\n    <collision>\n      <geometry>\n        <mesh/>\n      </geometry>\n    </collision>\n  </link>\n</robot>";
    assert_contains(&err(xml, None), &["test.urdf:5", "<mesh>", "'filename'"]);
    let xml = "<robot name=\"t\">\n  <link name=\"a\">\n    <collision>\n    </collision>\n  </link>\n</robot>";
    assert_contains(
        &err(xml, None),
        &["test.urdf:3", "<collision>", "<geometry>"],
    );
    let xml = "<robot name=\"t\">\n  <link name=\"a\">\n    <collision>\n      <geometry>\n        <cone radius=\"1\"/>\n      </geometry>\n    </collision>\n  </link>\n</robot>";
    assert_contains(&err(xml, None), &["test.urdf:5", "<cone>", "link 'a'"]);
}

#[test]
fn unknown_and_unsupported_joint_types() {
    let e = err(&one_joint("screw", ""), None);
    assert_contains(&e, &["test.urdf:4", "joint 'j1'", "unknown type 'screw'"]);
    let e = err(&one_joint("floating", ""), None);
    assert_contains(
        &e,
        &[
            "test.urdf:4",
            "joint 'j1'",
            "floating",
            "only fixed, revolute",
        ],
    );
    let e = err(&one_joint("planar", ""), Some("b"));
    assert_contains(&e, &["planar"]);
    // A floating joint off the chain is ignored.
    let xml = "<robot name=\"t\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <link name=\"c\"/>\n  <joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\"/></joint>\n  <joint name=\"free\" type=\"floating\"><parent link=\"a\"/><child link=\"c\"/></joint>\n</robot>";
    let robot = parse(xml, Some("b")).unwrap();
    assert_eq!(robot.joint_names(), ["j1"]);
    assert!(robot.warnings.is_empty());
    // A mimic joint is kept, with a warning naming it.
    let robot = parse(&one_joint("continuous", "    <mimic joint=\"j0\"/>"), None).unwrap();
    assert_eq!(robot.dof(), 1);
    assert_eq!(robot.warnings.len(), 1);
    assert_contains(&robot.warnings[0], &["test.urdf:4", "'j1'", "<mimic>"]);
}

#[test]
fn bad_numbers_name_file_line_and_attribute() {
    for (value, what) in [
        ("1 two 3", "xyz"),
        ("1 2", "xyz"),
        ("1 2 3 4", "xyz"),
        ("nan 0 0", "xyz"),
        ("0 0 inf", "rpy"),
    ] {
        let xml = one_joint("fixed", &format!("    <origin {what}=\"{value}\"/>"));
        let e = parse(&xml, None).unwrap_err();
        match &e {
            RobotError::BadValue {
                line,
                element,
                attribute,
                value: v,
                ..
            } => {
                assert_eq!(
                    (*line, element.as_str(), attribute.as_str(), v.as_str()),
                    (7, "origin", what, value)
                );
            }
            other => panic!("expected a bad-value error, got {other}"),
        }
        assert_contains(
            &e.to_string(),
            &["test.urdf:7", "<origin", what, "3 finite numbers"],
        );
    }
    let e = err(&one_joint("revolute", "    <axis xyz=\"0 0 0\"/>"), None);
    assert_contains(
        &e,
        &["test.urdf:7", "<axis xyz=\"0 0 0\">", "non-zero axis"],
    );
    let e = err(
        &one_joint("revolute", "    <limit lower=\"1\" upper=\"-1\"/>"),
        None,
    );
    assert_contains(
        &e,
        &[
            "test.urdf:7",
            "joint 'j1'",
            "lower=\"1\" upper=\"-1\"",
            "lower ≤ upper",
        ],
    );
    let e = err(
        &one_joint("prismatic", "    <limit lower=\"low\" upper=\"1\"/>"),
        None,
    );
    assert_contains(&e, &["test.urdf:7", "lower=\"low\"", "a finite number"]);
    let xml = "<robot name=\"t\">\n  <link name=\"a\">\n    <collision>\n      <geometry>\n        <sphere radius=\"-1\"/>\n      </geometry>\n    </collision>\n  </link>\n</robot>";
    assert_contains(&err(xml, None), &["test.urdf:5", "radius", "positive"]);
}

#[test]
fn tree_structure_errors() {
    // Branching without a tip: the leaves are listed.
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/robots/ur5/ur5_robot.urdf"
    ));
    let e = Robot::from_urdf_file(path, None).unwrap_err();
    assert!(matches!(e, RobotError::BranchingTree { .. }));
    assert_contains(
        &e.to_string(),
        &[
            "ur5_robot.urdf",
            "branches at link 'base_link'",
            "ee_link",
            "tool0",
            "base",
        ],
    );
    let e = Robot::from_urdf_file(path, Some("tool1")).unwrap_err();
    assert_contains(
        &e.to_string(),
        &["tip link 'tool1' is not defined", "tool0"],
    );
    // Unknown link, duplicate names, two parents, several roots.
    let e = err(
        &one_joint("fixed", "").replace("<child link=\"b\"/>", "<child link=\"c\"/>"),
        None,
    );
    assert_contains(
        &e,
        &["test.urdf:4", "joint 'j1'", "link 'c'", "not defined"],
    );
    let e = err(
        &one_joint("fixed", "").replace("<link name=\"b\"/>", "<link name=\"a\"/>"),
        None,
    );
    assert_contains(&e, &["test.urdf:3", "second link is called 'a'"]);
    let xml = "<robot name=\"t\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <link name=\"c\"/>\n  <joint name=\"j1\" type=\"fixed\"><parent link=\"a\"/><child link=\"c\"/></joint>\n  <joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n</robot>";
    assert_contains(
        &err(xml, None),
        &["test.urdf:6", "link 'c'", "'j1'", "'j2'", "tree"],
    );
    let xml = "<robot name=\"t\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n</robot>";
    assert_contains(&err(xml, None), &["several root links (a, b)"]);
    // With a tip, the disconnected link does not matter.
    assert_eq!(parse(xml, Some("b")).unwrap().links.len(), 1);
}

#[test]
fn missing_and_broken_mesh_files() {
    let dir = tempfile::tempdir().unwrap();
    let xml = "<robot name=\"t\">\n  <link name=\"a\">\n    <collision>\n      <geometry>\n        <mesh filename=\"package://pkg/meshes/missing.stl\"/>\n      </geometry>\n    </collision>\n  </link>\n</robot>";
    let path = dir.path().join("robot.urdf");
    std::fs::write(&path, xml).unwrap();
    let e = Robot::from_urdf_file_with(&path, None, &scene_meshes).unwrap_err();
    let expected_mesh = dir.path().join("meshes/missing.stl");
    assert_contains(
        &e.to_string(),
        &[
            &format!("{}:5", path.display()),
            "package://pkg/meshes/missing.stl",
            &expected_mesh.display().to_string(),
        ],
    );
    // An unreadable (garbage) STL is an error too.
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::write(&expected_mesh, b"solid x\nfacet normal oops\n").unwrap();
    let e = Robot::from_urdf_file_with(&path, None, &scene_meshes)
        .unwrap_err()
        .to_string();
    assert_contains(&e, &[":5", "missing.stl", "STL"]);
    // Without a loader the mesh is skipped with a warning naming it.
    std::fs::remove_file(&expected_mesh).unwrap();
    let r = Robot::from_urdf_file(&path, None).unwrap();
    assert_contains(&r.warnings[0], &[":5", "missing.stl", "not read"]);
    // A missing URDF names its path.
    let e = Robot::from_urdf_file(&dir.path().join("nope.urdf"), None)
        .unwrap_err()
        .to_string();
    assert_contains(&e, &["nope.urdf", "cannot read"]);
}

#[test]
fn origins_beyond_the_coordinate_limit_are_errors() {
    let xml = one_joint("fixed", r#"    <origin xyz="1e300 0 0"/>"#);
    assert_contains(&err(&xml, None), &["test.urdf:7", "xyz", "1e300", "1e7"]);
    // At the limit it reads.
    let xml = one_joint("fixed", r#"    <origin xyz="1e7 0 0"/>"#);
    assert!(parse(&xml, None).is_ok());
}

/// `<limit velocity>`: a negative speed names the file, line, element and
/// attribute; 0 is "not given" with a warning; a positive one is kept.
#[test]
fn joint_velocity_limits() {
    let xml = one_joint(
        "revolute",
        r#"    <limit lower="-1" upper="1" velocity="-2"/>"#,
    );
    assert_contains(
        &err(&xml, None),
        &["test.urdf:7", "<limit velocity=\"-2\">", "at least 0"],
    );
    let xml = one_joint(
        "revolute",
        r#"    <limit lower="-1" upper="1" velocity="0"/>"#,
    );
    let robot = parse(&xml, None).unwrap();
    assert_eq!(robot.joints[0].max_velocity, None);
    assert!(
        robot.warnings.iter().any(|w| w.contains("velocity=\"0\"")),
        "{:?}",
        robot.warnings
    );
    let xml = one_joint("continuous", r#"    <limit effort="1" velocity="2.5"/>"#);
    assert_eq!(parse(&xml, None).unwrap().joints[0].max_velocity, Some(2.5));
}
