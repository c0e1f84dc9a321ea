//! Jacobian columns against central finite differences of forward kinematics:
//! linear rows against the moving point, angular rows against the log map of the
//! link rotation.

// Helpers and statics outside #[test] functions unwrap too: a failure is a test failure.
#![allow(clippy::unwrap_used)]

use geom::{Point3, Real};
use nalgebra::Matrix6xX;
use proptest::prelude::*;
use robot::Robot;
use std::path::Path;
use std::sync::LazyLock;

static VM6083: LazyLock<Robot> = LazyLock::new(|| robot::builtin("denso-vm6083").unwrap());
static ARM4: LazyLock<Robot> = LazyLock::new(|| robot::builtin("arm4").unwrap());
static POINT3: LazyLock<Robot> = LazyLock::new(|| robot::builtin("point3").unwrap());
static UR5: LazyLock<Robot> = LazyLock::new(|| {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/robots/ur5/ur5_robot.urdf"
    ));
    Robot::from_urdf_file(path, Some("tool0")).unwrap()
});

/// Joint values from unit-interval samples, spread over the limits (±π if none).
fn q_from_unit(robot: &Robot, u: &[Real]) -> Vec<Real> {
    robot
        .limits()
        .iter()
        .zip(u)
        .map(|(l, t)| {
            let l = l.unwrap_or(robot::JointLimits::symmetric(std::f64::consts::PI));
            l.min + t * (l.max - l.min)
        })
        .collect()
}

fn finite_difference(robot: &Robot, q: &[Real], link: usize, p: &Point3) -> Matrix6xX<Real> {
    let h = 1e-6;
    let mut out = Matrix6xX::zeros(q.len());
    for k in 0..q.len() {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[k] += h;
        qm[k] -= h;
        let fp = robot.forward_kinematics(&qp).unwrap()[link];
        let fm = robot.forward_kinematics(&qm).unwrap()[link];
        let v = ((fp * p) - (fm * p)) / (2.0 * h);
        let w = (fp.rotation * fm.rotation.inverse()).scaled_axis() / (2.0 * h);
        for r in 0..3 {
            out[(r, k)] = v[r];
            out[(r + 3, k)] = w[r];
        }
    }
    out
}

fn check(robot: &Robot, u: &[Real], link_pick: usize, p: [Real; 3]) -> Result<(), TestCaseError> {
    let q = q_from_unit(robot, u);
    let link = link_pick % robot.links.len();
    let p = Point3::from(p);
    let j = robot.jacobian(&q, robot::LinkId(link), &p).unwrap();
    prop_assert_eq!(j.shape(), (6, robot.dof()));
    let fd = finite_difference(robot, &q, link, &p);
    let err = (&j - &fd).amax();
    prop_assert!(
        err < 1e-6,
        "{}: link {} q {:?}: |J − FD| = {}\nJ = {}\nFD = {}",
        robot.name,
        link,
        q,
        err,
        j,
        fd
    );
    // The allocation-free form from precomputed frames agrees exactly.
    let frames = robot.forward_kinematics(&q).unwrap();
    let mut j2 = Matrix6xX::zeros(robot.dof());
    robot.jacobian_into(&frames, robot::LinkId(link), &p, &mut j2);
    prop_assert_eq!(j, j2);
    Ok(())
}

fn unit6() -> impl Strategy<Value = Vec<Real>> {
    prop::collection::vec(0.0..1.0, 6)
}

fn point() -> impl Strategy<Value = [Real; 3]> {
    [-0.5..0.5, -0.5..0.5, -0.5..0.5]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn vm6083_jacobian_matches_finite_differences(u in unit6(), link in 0usize..64, p in point()) {
        check(&VM6083, &u, link, p)?;
    }

    #[test]
    fn arm4_jacobian_matches_finite_differences(u in unit6(), link in 0usize..64, p in point()) {
        check(&ARM4, &u, link, p)?;
    }

    #[test]
    fn point3_jacobian_matches_finite_differences(u in prop::collection::vec(0.0..1.0, 3), link in 0usize..64, p in point()) {
        check(&POINT3, &u, link, p)?;
    }

    #[test]
    fn ur5_jacobian_matches_finite_differences(u in unit6(), link in 0usize..64, p in point()) {
        check(&UR5, &u, link, p)?;
    }
}

#[test]
fn joints_after_the_link_give_zero_columns() {
    let robot = &*VM6083;
    let q = [0.2, -0.3, 0.9, 0.1, 0.5, -0.7];
    let j = robot
        .jacobian(&q, robot::LinkId(3), &Point3::new(0.1, 0.0, 0.0))
        .unwrap();
    for col in 3..6 {
        assert!(j.column(col).iter().all(|v| *v == 0.0));
    }
    // The base does not move at all.
    let j0 = robot
        .jacobian(&q, robot::LinkId(0), &Point3::new(0.1, 0.2, 0.3))
        .unwrap();
    assert!(j0.iter().all(|v| *v == 0.0));
    // point3: the Jacobian of the control point is [I; 0].
    let jp = POINT3
        .jacobian(&[0.3, 0.1, -2.0], robot::LinkId(3), &Point3::origin())
        .unwrap();
    let mut expected = Matrix6xX::zeros(3);
    for i in 0..3 {
        expected[(i, i)] = 1.0;
    }
    assert_eq!(jp, expected);
    // A wrongly sized output is resized, not a panic; an out-of-range link gives zeros.
    let frames = robot.forward_kinematics(&q).unwrap();
    let mut out = Matrix6xX::zeros(2);
    robot.jacobian_into(&frames, robot::LinkId(99), &Point3::origin(), &mut out);
    assert_eq!(out.ncols(), 6);
    assert!(out.iter().all(|v| *v == 0.0));
}
