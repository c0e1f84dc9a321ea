//! `data/scenarios/ur5_cube.toml`: a UR5 with a 17-sensor tool ring over a
//! 0.2 m cube. The start pose puts the tool 0.1 m above the top face pointing
//! down, and the base placement lets the arm go over every top edge and down
//! every side without touching the cube (inverse kinematics by damped
//! least squares on the robot's own Jacobian, checked by forward kinematics
//! and by contact checks along every step).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Isometry3, Point3, Real, Vector3};
use hw::{Arm, RangeSensors};
use nalgebra::{DMatrix, DVector};
use plan::contact::{motion_contacts, robot_contacts};
use robot::Robot;
use scenario::{LoadedScenario, Scenario};
use sim::SimRig;
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;

fn loaded() -> LoadedScenario {
    Scenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/scenarios/ur5_cube.toml"
    ))
    .unwrap()
}

/// Tool position and axis (z) in the world.
fn tool(r: &Robot, world_from_base: &Isometry3, q: &[Real]) -> (Point3, Vector3) {
    let t = world_from_base * r.tool_pose(q).unwrap();
    (
        Point3::from(t.translation.vector),
        t.rotation * Vector3::z(),
    )
}

/// Joints putting the tool at `p` with its axis along `z`, from `q0`: damped
/// least squares on the geometric Jacobian (position error clamped to 5 cm per
/// iteration, axis error as the rotation vector `z_now × z`).
fn ik(r: &Robot, wfb: &Isometry3, q0: &[Real], p: Point3, z: Vector3) -> Option<Vec<Real>> {
    let mut q = q0.to_vec();
    let at = Point3::from(r.tool.1.translation.vector);
    for _ in 0..200 {
        let (now, zc) = tool(r, wfb, &q);
        let dp = p - now;
        let w = zc.cross(&z);
        if dp.norm() < 1e-9 && w.norm() < 1e-9 && zc.dot(&z) > 0.0 {
            return Some(q);
        }
        let j = r.jacobian(&q, r.tool.0, &at).unwrap();
        let mut jw = DMatrix::zeros(6, r.dof());
        for c in 0..r.dof() {
            let lin = wfb.rotation * Vector3::new(j[(0, c)], j[(1, c)], j[(2, c)]);
            let ang = wfb.rotation * Vector3::new(j[(3, c)], j[(4, c)], j[(5, c)]);
            for k in 0..3 {
                jw[(k, c)] = lin[k];
                jw[(k + 3, c)] = ang[k];
            }
        }
        let mut e = DVector::zeros(6);
        for k in 0..3 {
            e[k] = dp[k].clamp(-0.05, 0.05);
            e[k + 3] = w[k];
        }
        let dq = robot::damped_pseudo_inverse(&jw, 1e-3) * e;
        for (qi, d) in q.iter_mut().zip(dq.iter()) {
            *qi += d;
        }
    }
    None
}

#[test]
fn start_pose_is_delta_above_the_top_face_pointing_down() {
    let l = loaded();
    let r = l.build_robot().unwrap();
    assert_eq!(r.range_finders.len(), 17);
    let wfb = l.scenario.world_from_base();
    let q = &l.scenario.robot.start_joints;
    let (p, z) = tool(&r, &wfb, q);
    assert!((p - Point3::new(0.0, 0.0, 0.3)).norm() < 1e-6, "{p:?}");
    assert!(
        z.dot(&-Vector3::z()) > (0.01f64).to_radians().cos(),
        "{z:?}"
    );
    // Clear of the cube, and the tool-axis sensor reads δ = 0.1 on the top face.
    let world = Arc::new(l.build_world().unwrap());
    let scene = world.as_scene().unwrap();
    assert!(robot_contacts(&r, &r.forward_kinematics(q).unwrap(), &wfb, scene).is_empty());
    let mut rig = SimRig::new(r, world.clone(), wfb, q, None, 1).unwrap();
    let readings = rig.read_all().unwrap();
    assert!((readings[0].unwrap().distance_m - 0.1).abs() < 1e-6);
    // The 45° sensors reach 0.1 m sideways: those that meet the top face
    // (0.1 m half-width) read 0.1·√2, the rest pass beyond its edge.
    let hits: Vec<Real> = readings[1..9]
        .iter()
        .flatten()
        .map(|h| h.distance_m)
        .collect();
    assert!(hits.len() >= 4, "{readings:?}");
    assert!(
        hits.iter().all(|d| (d - 0.1 * 2f64.sqrt()).abs() < 1e-5),
        "{hits:?}"
    );
    // The 90° sensors see nothing within 0.2 m (the tool is above the cube).
    assert!(readings[9..].iter().all(Option::is_none));
    rig.move_to(q).unwrap();
}

#[test]
fn the_arm_reaches_over_every_top_edge_and_down_every_side() {
    let l = loaded();
    let r = l.build_robot().unwrap();
    let wfb = l.scenario.world_from_base();
    let world = l.build_world().unwrap();
    let scene = world.as_scene().unwrap();
    let start = l.scenario.robot.start_joints.clone();
    let (half, h, delta) = (0.1, 0.2, 0.1);
    let step = 0.01;
    for n in [Vector3::x(), -Vector3::x(), Vector3::y(), -Vector3::y()] {
        // Top centre → the top edge → round the edge at δ → down the side to
        // 0.05 m above the table, the tool axis always at the surface.
        let mut path: Vec<(Point3, Vector3)> = Vec::new();
        let top = Point3::new(0.0, 0.0, h);
        let edge = top + n * half;
        for i in 0..=10 {
            path.push((
                top + n * (half * i as Real / 10.0) + Vector3::z() * delta,
                -Vector3::z(),
            ));
        }
        for i in 1..=10 {
            let a = FRAC_PI_2 * i as Real / 10.0;
            let dir = Vector3::z() * a.cos() + n * a.sin();
            path.push((edge + dir * delta, -dir));
        }
        for i in 1..=10 {
            let z = h - (h - 0.05) * i as Real / 10.0;
            path.push((Point3::new(0.0, 0.0, z) + n * (half + delta), -n));
        }
        let mut q = start.clone();
        for (p, d) in path {
            let next =
                ik(&r, &wfb, &q, p, d).unwrap_or_else(|| panic!("side {n:?}: no pose at {p:?}"));
            assert!(r.within_limits(&next));
            let (at, axis) = tool(&r, &wfb, &next);
            assert!((at - p).norm() < 1e-6 && axis.dot(&d) > 1.0 - 1e-9);
            let check = motion_contacts(&r, &q, &next, &wfb, scene, step).unwrap();
            assert!(
                check.is_clear(),
                "side {n:?} at {p:?}: {:?}",
                check.first_contact
            );
            q = next;
        }
    }
}
