//! `Robot::reach_bound` against forward kinematics: every configuration's
//! point within the bound, the hand-computed radius of the VM-6083, and a
//! bound that the arm comes close to (not vacuously large).

use crate::fk::data;
use geom::{Isometry3, Point3, Real, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::{Robot, builtin};

/// Random configurations within the limits (±π for unlimited joints).
fn configurations(robot: &Robot, n: usize, seed: u64) -> Vec<Vec<Real>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            robot
                .limits()
                .iter()
                .map(|l| {
                    let (lo, hi) = l.map_or((-std::f64::consts::PI, std::f64::consts::PI), |l| {
                        (l.min, l.max)
                    });
                    rng.random_range(lo..=hi)
                })
                .collect()
        })
        .collect()
}

/// The largest distance, over `qs`, from the point to the nearest centre,
/// and the bound's radius.
fn worst(robot: &Robot, link_from_point: &Isometry3, qs: &[Vec<Real>]) -> (Real, Real) {
    let link = robot.tool.0;
    let bound = robot.reach_bound(link, link_from_point, 360).unwrap();
    let mut worst: Real = 0.0;
    for q in qs {
        let frames = robot.forward_kinematics(q).unwrap();
        let p = Point3::from((frames[link.index()] * link_from_point).translation.vector);
        let nearest = bound
            .centres
            .iter()
            .map(|c| (p - c).norm())
            .fold(Real::INFINITY, Real::min);
        worst = worst.max(nearest);
        assert!(
            nearest <= bound.radius + 1e-12,
            "{}: q = {q:?} puts the point {nearest} m from the centres, bound {}",
            robot.name,
            bound.radius
        );
    }
    (worst, bound.radius)
}

#[test]
fn every_configuration_is_within_the_bound() {
    let nozzle = Isometry3::translation(0.0, 0.0, 0.15);
    let ur5 = Robot::from_urdf_file(&data("robots/ur5/ur5_robot.urdf"), Some("tool0")).unwrap();
    for robot in [
        builtin("denso-vm6083").unwrap(),
        builtin("arm4").unwrap(),
        ur5,
    ] {
        let qs = configurations(&robot, 20_000, 7);
        let (far, radius) = worst(&robot, &nozzle, &qs);
        // Not vacuous: random configurations come within 20 % of it.
        assert!(
            far > 0.8 * radius,
            "{}: farthest {far} m of a {radius} m bound",
            robot.name
        );
    }
}

#[test]
fn the_vm6083_bound_is_its_link_lengths() {
    // Paul Table C.1: the shoulder 0.18 m off the base axis at 0.475 m; then
    // a₂ = 0.385 to the elbow, the wrist centre a₃ = −0.1 and d₄ = 0.445
    // (at right angles) beyond it, and d₆ = 0.084 and the point 0.15 m
    // along the flange's z beyond the wrist centre (on joints 4 to 6's axes,
    // so their motion adds nothing else).
    let robot = builtin("denso-vm6083").unwrap();
    let bound = robot
        .reach_bound(robot.tool.0, &Isometry3::translation(0.0, 0.0, 0.15), 340)
        .unwrap();
    assert_eq!(bound.centres.len(), 341);
    for c in &bound.centres {
        assert!((Vector3::new(c.x, c.y, 0.0).norm() - 0.18).abs() < 1e-12);
        assert!((c.z - 0.475).abs() < 1e-12);
    }
    // 340 samples over 340°: chords of 1° on a 0.18 m circle.
    let chord = 2.0 * 0.18 * (0.5 as Real).to_radians().sin();
    let expected = 0.385 + (0.1 as Real).hypot(0.445) + 0.084 + 0.15 + chord;
    assert!(
        (bound.radius - expected).abs() < 1e-9,
        "{} against {expected}",
        bound.radius
    );
    // The far side of the base is out of reach, the flange's own spot is not.
    let far = Point3::new(-2.5, 0.0, 0.5);
    assert!(!bound.may_reach(0.0, |c| (far - c).norm()));
    let q = vec![0.0; 6];
    let here = robot.tool_pose(&q).unwrap().translation.vector;
    assert!(bound.may_reach(0.0, |c| (Point3::from(here) - c).norm()));
}

#[test]
fn an_unlimited_prismatic_joint_has_no_bound() {
    let mut robot = builtin("point3").unwrap();
    assert!(
        robot
            .reach_bound(robot.tool.0, &Isometry3::identity(), 10)
            .is_some()
    );
    robot.joints[0].limits = None;
    assert!(
        robot
            .reach_bound(robot.tool.0, &Isometry3::identity(), 10)
            .is_none()
    );
}

/// The largest distance from the centres over many configurations, against
/// the radius: how tight the bound is, per robot (printed with `--nocapture`).
#[test]
fn the_bound_is_tight_where_the_wrist_is_spherical() {
    let robot = builtin("denso-vm6083").unwrap();
    let qs = configurations(&robot, 20_000, 11);
    // The wrist centre (link 4's origin) and the flange: every length of the
    // chain is reached at once when the arm is stretched, so random
    // configurations come within 3 % of the bound.
    for (link, what) in [(4usize, "wrist centre"), (6, "flange")] {
        let bound = robot
            .reach_bound(robot::LinkId(link), &Isometry3::identity(), 360)
            .unwrap();
        let mut far: Real = 0.0;
        for q in &qs {
            let frames = robot.forward_kinematics(q).unwrap();
            let p = Point3::from(frames[link].translation.vector);
            let nearest = bound
                .centres
                .iter()
                .map(|c| (p - c).norm())
                .fold(Real::INFINITY, Real::min);
            assert!(
                nearest <= bound.radius + 1e-12,
                "{what}: {nearest} > {}",
                bound.radius
            );
            far = far.max(nearest);
        }
        println!("{what}: {far} m reached of {} m", bound.radius);
        assert!(
            far > 0.97 * bound.radius,
            "{what}: {far} of {}",
            bound.radius
        );
    }
}

/// The VM-6083's wrist is spherical (Table C.1: a₄ = a₅ = a₆ = d₅ = 0):
/// link 4's origin is on joints 5 and 6's axes and stays put in the flange's
/// frame, 0.084 m behind it on its axis, whatever they do. The UR5's wrist
/// joints are offset (d₅, d₆): only the last moving link, `wrist_3_link`
/// (on joint 6's axis, `tool0` fixed to it), qualifies.
#[test]
fn the_vm6083_wrist_centre_is_fixed_in_the_flange_frame() {
    let robot = builtin("denso-vm6083").unwrap();
    let tool = robot.tool.0;
    assert_eq!(robot.fixed_point_link(tool), Some(robot::LinkId(4)));
    for q in configurations(&robot, 200, 3) {
        let frames = robot.forward_kinematics(&q).unwrap();
        let p = frames[tool.index()].inverse() * Point3::from(frames[4].translation.vector);
        assert!((p - Point3::new(0.0, 0.0, -0.084)).norm() < 1e-12, "{p:?}");
    }
    let ur5 = Robot::from_urdf_file(&data("robots/ur5/ur5_robot.urdf"), Some("tool0")).unwrap();
    let l = ur5.fixed_point_link(ur5.tool.0).unwrap();
    assert_eq!(ur5.links[l.index()].name, "wrist_3_link");
}
