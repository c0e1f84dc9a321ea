//! Forward kinematics against independent computations: plain 4×4 arrays, written
//! here without any of the crate's code.

// Helpers and statics outside #[test] functions unwrap too: a failure is a test failure.
#![allow(clippy::unwrap_used)]
// Numbers are typed exactly as the URDF, YAML and thesis print them.
#![allow(clippy::unreadable_literal)]

use geom::{Isometry3, Point3, Real, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::Robot;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

type M4 = [[Real; 4]; 4];

const IDENTITY: M4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn rot_x(t: Real) -> M4 {
    let (s, c) = t.sin_cos();
    [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, c, -s, 0.0],
        [0.0, s, c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn rot_y(t: Real) -> M4 {
    let (s, c) = t.sin_cos();
    [
        [c, 0.0, s, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [-s, 0.0, c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn rot_z(t: Real) -> M4 {
    let (s, c) = t.sin_cos();
    [
        [c, -s, 0.0, 0.0],
        [s, c, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn trans(x: Real, y: Real, z: Real) -> M4 {
    let mut m = IDENTITY;
    m[0][3] = x;
    m[1][3] = y;
    m[2][3] = z;
    m
}

/// Corke standard DH: Rz(θ) Tz(d) Tx(a) Rx(α).
fn dh(theta: Real, d: Real, a: Real, alpha: Real) -> M4 {
    mul(
        &mul(
            &mul(&rot_z(theta), &trans(0.0, 0.0, d)),
            &trans(a, 0.0, 0.0),
        ),
        &rot_x(alpha),
    )
}

fn max_diff(iso: &Isometry3, m: &M4) -> Real {
    let h = iso.to_homogeneous();
    let mut worst: Real = 0.0;
    for (i, row) in m.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            worst = worst.max((h[(i, j)] - v).abs());
        }
    }
    worst
}

fn position(m: &M4) -> Vector3 {
    Vector3::new(m[0][3], m[1][3], m[2][3])
}

pub(crate) fn data(path: &str) -> std::path::PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/")).join(path)
}

fn random_q(robot: &Robot, rng: &mut ChaCha8Rng) -> Vec<Real> {
    robot
        .limits()
        .iter()
        .map(|l| {
            let l = l.unwrap_or(robot::JointLimits::symmetric(PI));
            rng.random_range(l.min..l.max)
        })
        .collect()
}

#[test]
fn vm6083_matches_hand_written_dh_at_random_poses() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    // Paul Table C.1, typed in again.
    let a = [0.18, 0.385, -0.1, 0.0, 0.0, 0.0];
    let d = [0.475, 0.0, 0.0, 0.445, 0.0, 0.084];
    let alpha = [-PI / 2.0, 0.0, PI / 2.0, -PI / 2.0, PI / 2.0, 0.0];
    let offset = [0.0, -PI / 2.0, PI / 2.0, 0.0, 0.0, 0.0];
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut frames = Vec::new();
    for _ in 0..500 {
        let q: Vec<Real> = (0..6)
            .map(|_| rng.random_range(-2.0 * PI..2.0 * PI))
            .collect();
        robot.fk_into(&q, &mut frames).unwrap();
        assert_eq!(frames.len(), 7);
        let mut t = IDENTITY;
        assert!(max_diff(&frames[0], &t) < 1e-12);
        for i in 0..6 {
            t = mul(&t, &dh(q[i] + offset[i], d[i], a[i], alpha[i]));
            let err = max_diff(&frames[i + 1], &t);
            assert!(err < 1e-9, "link {} at q = {q:?}: error {err}", i + 1);
        }
        let tool = robot.tool_pose(&q).unwrap();
        assert!(max_diff(&tool, &t) < 1e-9);
    }
}

#[test]
fn vm6083_reference_poses() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let zero = robot.tool_pose(&[0.0; 6]).unwrap();
    assert!((zero.translation.vector - Vector3::new(0.08, 0.0, 1.389)).norm() < 1e-12);
    // SPEC §4 start pose: crouched, flange at ≈(0.317, 0, 0.7216), z pointing up.
    let q = [
        0.0,
        -55f64.to_radians(),
        165f64.to_radians(),
        0.0,
        -110f64.to_radians(),
        0.0,
    ];
    let crouched = robot.tool_pose(&q).unwrap();
    assert!((crouched.translation.vector - Vector3::new(0.317, 0.0, 0.7216)).norm() < 1e-3);
    let z = crouched.rotation * Vector3::z();
    assert!(z.z > 1.0 - 1e-9, "flange z = {z:?}");
    // The scanner sits 5 cm out along the flange z axis, its centre ray along z.
    let scanner = robot.scanner_pose(&q).unwrap().unwrap();
    assert!((scanner.translation.vector - crouched.translation.vector - z * 0.05).norm() < 1e-12);
}

/// The scanner pose from frames already computed is the scanner pose, to
/// the bit (callers reuse one forward kinematics for the links and the
/// scanner).
#[test]
fn scanner_pose_in_frames_is_scanner_pose() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..200 {
        let q: Vec<Real> = (0..6).map(|_| rng.random_range(-2.5..2.5)).collect();
        let frames = robot.forward_kinematics(&q).unwrap();
        assert_eq!(
            robot.scanner_pose_in(&frames).unwrap(),
            robot.scanner_pose(&q).unwrap()
        );
    }
    assert!(robot.scanner_pose_in(&[]).is_err());
}

#[test]
fn vm6083_joint5_tilts_the_scan_plane() {
    // With the identity mount, joint 5's axis is the scanner's y axis (the ±90° ray),
    // so tilting joint 5 nods the scan plane (whose normal is the scanner x axis).
    // This holds while joint 6 is at zero (joint 6 turns the scanner about z).
    let robot = robot::builtin("denso-vm6083").unwrap();
    let poses = [
        [0.0; 6],
        [0.3, -0.4, 1.1, 0.7, -0.9, 0.0],
        [-1.2, 0.5, 0.2, -2.0, 1.3, 0.0],
        [
            0.0,
            -55f64.to_radians(),
            165f64.to_radians(),
            0.0,
            -110f64.to_radians(),
            0.0,
        ],
    ];
    for q in poses {
        let frames = robot.forward_kinematics(&q).unwrap();
        // Joint 5 (index 4) rotates about z of frame 4.
        let (_, axis5) = robot.joint_axis_in_base(&frames, 4).unwrap();
        let scanner = robot.scanner_pose(&q).unwrap().unwrap();
        let y = scanner.rotation * Vector3::y();
        assert!(axis5.dot(&y).abs() > 1.0 - 1e-12, "q = {q:?}");
    }
}

/// The UR5 chain of `ur5_robot.urdf`, typed in from its `<joint>` elements:
/// origins (xyz, rpy) and axes. Returns the frames world, base_link, shoulder,
/// upper_arm, forearm, wrist_1, wrist_2, wrist_3, then `last` (tool0 or ee_link).
fn ur5_hand_chain(q: &[Real], last: &str) -> Vec<M4> {
    // URDF rpy → Rz(yaw) Ry(pitch) Rx(roll); only single-axis rpys occur here.
    let joints: [(M4, char); 6] = [
        (trans(0.0, 0.0, 0.089159), 'z'),
        (mul(&trans(0.0, 0.13585, 0.0), &rot_y(1.570796325)), 'y'),
        (trans(0.0, -0.1197, 0.425), 'y'),
        (mul(&trans(0.0, 0.0, 0.39225), &rot_y(1.570796325)), 'y'),
        (trans(0.0, 0.093, 0.0), 'z'),
        (trans(0.0, 0.0, 0.09465), 'y'),
    ];
    let mut frames = vec![IDENTITY, IDENTITY]; // world, base_link (world_joint is identity)
    let mut t = IDENTITY;
    for ((origin, axis), &qi) in joints.iter().zip(q) {
        let motion = match axis {
            'y' => rot_y(qi),
            _ => rot_z(qi),
        };
        t = mul(&mul(&t, origin), &motion);
        frames.push(t);
    }
    let fixed = match last {
        "tool0" => mul(&trans(0.0, 0.0823, 0.0), &rot_x(-1.570796325)),
        _ => mul(&trans(0.0, 0.0823, 0.0), &rot_z(1.570796325)),
    };
    frames.push(mul(&t, &fixed));
    frames
}

#[test]
fn ur5_matches_hand_written_urdf_chain() {
    let path = data("robots/ur5/ur5_robot.urdf");
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for tip in ["tool0", "ee_link"] {
        let robot = Robot::from_urdf_file(&path, Some(tip)).unwrap();
        let names: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "world",
                "base_link",
                "shoulder_link",
                "upper_arm_link",
                "forearm_link",
                "wrist_1_link",
                "wrist_2_link",
                "wrist_3_link",
                tip
            ]
        );
        assert_eq!(
            robot.joint_names(),
            [
                "shoulder_pan_joint",
                "shoulder_lift_joint",
                "elbow_joint",
                "wrist_1_joint",
                "wrist_2_joint",
                "wrist_3_joint"
            ]
        );
        // The clock's limits: each joint's <limit velocity> as typed in
        // the file (3.15 rad/s for the first three, 3.2 for the wrists).
        assert_eq!(
            robot::timing::MotionLimits::of(&robot).velocity,
            [3.15, 3.15, 3.15, 3.2, 3.2, 3.2]
        );
        assert_eq!(robot.tool.0, robot::LinkId(8));
        for _ in 0..200 {
            let q = random_q(&robot, &mut rng);
            let frames = robot.forward_kinematics(&q).unwrap();
            let expected = ur5_hand_chain(&q, tip);
            assert_eq!(frames.len(), expected.len());
            for (i, (f, e)) in frames.iter().zip(&expected).enumerate() {
                let err = max_diff(f, e);
                assert!(err < 1e-9, "{tip}: link {i} at q = {q:?}: error {err}");
            }
        }
    }
}

#[test]
fn ur5_matches_published_dh_parameters() {
    // config/ur5_physical_parameters.yaml: the UR5's standard DH table, with
    // α = [π/2, 0, 0, π/2, −π/2, 0] and θ_i = q_i (UR convention).
    let (d1, a2, a3, d4, d5, d6) = (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823);
    let a = [0.0, a2, a3, 0.0, 0.0, 0.0];
    let d = [d1, 0.0, 0.0, d4, d5, d6];
    let alpha = [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0];
    // Fixed transforms between the two descriptions:
    // * base: the DH base frame is the ROS-I `base` frame, which the URDF places at
    //   `base_link` rotated by −π about z (`base_link-base_fixed_joint`); our chain's
    //   root `world` coincides with `base_link`. So base_link_from_dh0 = Rz(π)
    //   (Rz(−π) = Rz(π)).
    // * tool: DH frame 6 is the ROS-I `tool0` frame (same origin; same axes up to
    //   the URDF's rounding of −π/2 in tool0's rpy); DH frames 4 and 5
    //   have their origins at the `wrist_2_link` and `wrist_3_link` origins.
    // * zero shift: the URDF writes π/2 as 1.570796325 in the shoulder_lift and
    //   wrist_1 origins (both rotations about the joint's own y axis), which equals
    //   an exact π/2 plus a joint-zero shift of −ε, ε = π/2 − 1.570796325 ≈ 1.8e-9 rad.
    //   The shift is added to θ2 and θ4 so the comparison can hold to 1e-9.
    let eps = FRAC_PI_2 - 1.570796325;
    let shift = [0.0, -eps, 0.0, -eps, 0.0, 0.0];
    let base_link_from_dh0 = rot_z(PI);
    let robot = Robot::from_urdf_file(&data("robots/ur5/ur5_robot.urdf"), Some("tool0")).unwrap();
    let wrist_2 = robot.link_index("wrist_2_link").unwrap();
    let wrist_3 = robot.link_index("wrist_3_link").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..300 {
        let q = random_q(&robot, &mut rng);
        let frames = robot.forward_kinematics(&q).unwrap();
        let mut t = base_link_from_dh0;
        let mut dh_frames = Vec::new();
        for i in 0..6 {
            t = mul(&t, &dh(q[i] + shift[i], d[i], a[i], alpha[i]));
            dh_frames.push(t);
        }
        for (link, dh_frame) in [(wrist_2, 3), (wrist_3, 4)] {
            let err = (frames[link.0].translation.vector - position(&dh_frames[dh_frame])).norm();
            assert!(
                err < 1e-9,
                "wrist frame {dh_frame} at q = {q:?}: error {err}"
            );
        }
        let tool = robot.tool_pose(&q).unwrap();
        let err = (tool.translation.vector - position(&dh_frames[5])).norm();
        assert!(err < 1e-9, "tool0 at q = {q:?}: error {err}");
        // The orientation agrees too, to the URDF's own rounding of −π/2 in the
        // tool0 rpy (a fixed rotation about x, which no joint shift can absorb).
        let err = max_diff(&tool, &dh_frames[5]);
        assert!(err < 1e-8, "tool0 orientation at q = {q:?}: error {err}");
    }
}

#[test]
fn fk_into_reuses_its_buffer_and_point3_moves_along_axes() {
    let robot = robot::builtin("point3").unwrap();
    let mut frames = Vec::with_capacity(4);
    let ptr = frames.as_ptr();
    robot.fk_into(&[1.0, -2.0, 0.5], &mut frames).unwrap();
    assert_eq!(ptr, frames.as_ptr(), "no reallocation");
    assert_eq!(frames[3] * Point3::origin(), Point3::new(1.0, -2.0, 0.5));
    // On error the buffer is left as it was.
    let before = frames.clone();
    assert!(robot.fk_into(&[1.0], &mut frames).is_err());
    assert_eq!(before, frames);
}

#[test]
fn arm4_geometry() {
    let robot = robot::builtin("arm4").unwrap();
    assert_eq!(robot.dof(), 6);
    // All joints zero: straight up, the control point at (0, 0, 4).
    let tool = robot.tool_pose(&[0.0; 6]).unwrap();
    assert!((tool.translation.vector - Vector3::new(0.0, 0.0, 4.0)).norm() < 1e-12);
    // Pitch joint 2 by 90°: links 2–4 lie horizontal at height 1.
    let bent = robot
        .tool_pose(&[0.0, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0])
        .unwrap();
    assert!((bent.translation.vector - Vector3::new(3.0, 0.0, 1.0)).norm() < 1e-12);
    // Yaw joint 1 by 90° then: along y.
    let turned = robot
        .tool_pose(&[FRAC_PI_2, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0])
        .unwrap();
    assert!((turned.translation.vector - Vector3::new(0.0, 3.0, 1.0)).norm() < 1e-12);
    // Roll joint 3 about link 2's axis does not move a straight arm's tip.
    let rolled = robot.tool_pose(&[0.0, 0.4, 1.0, 0.0, 0.0, 0.0]).unwrap();
    let straight = robot.tool_pose(&[0.0, 0.4, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert!((rolled.translation.vector - straight.translation.vector).norm() < 1e-12);
    // Pitch joint 4 at the end of link 2 (height 2 when upright).
    let elbow = robot
        .tool_pose(&[0.0, 0.0, 0.0, FRAC_PI_2, 0.0, 0.0])
        .unwrap();
    assert!((elbow.translation.vector - Vector3::new(2.0, 0.0, 2.0)).norm() < 1e-12);
}
