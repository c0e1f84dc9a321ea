//! The null-space projector of Pudney eq. 3 and the pseudo-inverses behind it.

// Helpers and statics outside #[test] functions unwrap too: a failure is a test failure.
#![allow(clippy::unwrap_used)]

use geom::{Point3, Real};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use robot::{Robot, damped_pseudo_inverse, null_space_projector, pseudo_inverse};
use std::sync::LazyLock;

static VM6083: LazyLock<Robot> = LazyLock::new(|| robot::builtin("denso-vm6083").unwrap());
static ARM4: LazyLock<Robot> = LazyLock::new(|| robot::builtin("arm4").unwrap());

fn q_in_limits(robot: &Robot, u: &[Real]) -> Vec<Real> {
    robot
        .limits()
        .iter()
        .zip(u)
        .map(|(l, t)| l.map_or(0.0, |l| l.min + t * (l.max - l.min)))
        .collect()
}

/// The control point's Jacobian: the 3 position rows (arm4's 3-D task) or all 6.
fn task_jacobian(robot: &Robot, q: &[Real], rows: usize) -> DMatrix<Real> {
    let (link, link_from_tool) = robot.tool;
    let p = link_from_tool * Point3::origin();
    let j = robot.jacobian(q, link, &p).unwrap();
    DMatrix::from_fn(rows, j.ncols(), |r, c| j[(r, c)])
}

fn check_projector(j: &DMatrix<Real>) -> Result<(), TestCaseError> {
    let pinv = pseudo_inverse(j, 1e-10);
    let n = null_space_projector(j, &pinv);
    let scale = 1.0 + j.amax();
    prop_assert!((j * &n).amax() < 1e-9 * scale, "J N = {}", j * &n);
    prop_assert!((&n * &n - &n).amax() < 1e-9, "N² − N = {}", &n * &n - &n);
    prop_assert!((&n - n.transpose()).amax() < 1e-9);
    // Any z projected into the null space leaves the task still.
    let z = DVector::from_fn(j.ncols(), |i, _| (i as Real).sin() + 0.3);
    prop_assert!((j * (&n * z)).amax() < 1e-9 * scale);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn arm4_position_task_projector(u in prop::collection::vec(0.0..1.0, 6)) {
        let q = q_in_limits(&ARM4, &u);
        let j = task_jacobian(&ARM4, &q, 3);
        prop_assert_eq!(j.shape(), (3, 6));
        check_projector(&j)?;
        // Redundant arm away from singularities: a 3-D null space.
        let n = null_space_projector(&j, &pseudo_inverse(&j, 1e-10));
        let rank = j.clone().svd(false, false).rank(1e-8);
        prop_assert!((n.trace() - (6 - rank) as Real).abs() < 1e-6);
    }

    #[test]
    fn vm6083_projector(u in prop::collection::vec(0.0..1.0, 6)) {
        let q = q_in_limits(&VM6083, &u);
        check_projector(&task_jacobian(&VM6083, &q, 6))?;
        check_projector(&task_jacobian(&VM6083, &q, 3))?;
    }
}

#[test]
fn damped_pseudo_inverse_converges_to_the_pseudo_inverse() {
    // Away from singularities (checked by the smallest singular value), the damped
    // inverse approaches J⁺ as λ → 0, with error O(λ²).
    let q_arm4 = [0.3, 0.4, 0.2, -0.5, 0.7, 0.1];
    let q_vm6083 = [0.3, -0.4, 1.2, 0.5, -0.9, 0.2];
    for (robot, q, rows) in [
        (&*ARM4, q_arm4, 3),
        (&*VM6083, q_vm6083, 6),
        (&*VM6083, q_vm6083, 3),
    ] {
        let j = task_jacobian(robot, &q, rows);
        let s = j.clone().svd(false, false).singular_values;
        assert!(s.min() > 1e-2, "{} is near a singularity: {s}", robot.name);
        let exact = pseudo_inverse(&j, 1e-10);
        let mut previous = Real::INFINITY;
        for damping in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5] {
            let err = (damped_pseudo_inverse(&j, damping) - &exact).amax();
            assert!(
                err < previous,
                "{}: error {err} at λ = {damping} did not shrink",
                robot.name
            );
            previous = err;
        }
        assert!(previous < 1e-6, "{}: residual {previous}", robot.name);
    }
    // Tall (n < m) matrices take the n × n branch and converge too.
    let tall = task_jacobian(&ARM4, &q_arm4, 6).columns(0, 4).into_owned();
    let err = (damped_pseudo_inverse(&tall, 1e-6) - pseudo_inverse(&tall, 1e-10)).amax();
    assert!(err < 1e-6);
}

#[test]
fn damped_pseudo_inverse_stays_bounded_at_a_singularity() {
    // arm4 stretched straight up: the tip cannot move vertically (rank drop).
    let j = task_jacobian(&ARM4, &[0.0; 6], 3);
    let damped = damped_pseudo_inverse(&j, 0.05);
    assert!(damped.iter().all(|v| v.is_finite()));
    // Its norm is bounded by 1 / (2λ).
    let s = damped.svd(false, false).singular_values;
    assert!(s.max() <= 1.0 / (2.0 * 0.05) + 1e-9);
}
