#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
//! Acceptance 1: streams of points sampled on random convex polyhedra (boxes and
//! prisms of random size and pose), fed in local batches of 20–30 points, with
//! the invariant checker after every update.

use crate::support;

use geom::{
    Isometry3, Point3, Real, Rotation3, Translation3, UnitQuaternion, UnitVector3, Vector3, unit,
};
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use support::{chunk_sets, feed_checked};
use surface::{SurfaceConfig, SurfaceModel};

/// A convex polyhedron as faces, each a convex polygon anticlockwise about its
/// outward normal.
fn polyhedron(rng: &mut ChaCha8Rng, prism: bool) -> Vec<Vec<Point3>> {
    let faces: Vec<Vec<Point3>> = if prism {
        let n = rng.random_range(3..8usize);
        let r = rng.random_range(0.2..0.6);
        let h = rng.random_range(0.2..0.8);
        // Random convex base: points on a circle at sorted random angles.
        let mut angles: Vec<Real> = (0..n)
            .map(|_| rng.random_range(0.0..std::f64::consts::TAU))
            .collect();
        angles.sort_by(Real::total_cmp);
        angles.dedup_by(|a, b| (*a - *b).abs() < 0.3);
        if angles.len() < 3 {
            angles = vec![0.0, 2.1, 4.2];
        }
        let base: Vec<Point3> = angles
            .iter()
            .map(|a| Point3::new(r * a.cos(), r * a.sin(), 0.0))
            .collect();
        let top: Vec<Point3> = base.iter().map(|p| p + Vector3::new(0.0, 0.0, h)).collect();
        let m = base.len();
        let mut f = vec![top.clone(), base.iter().rev().copied().collect()];
        for i in 0..m {
            let j = (i + 1) % m;
            f.push(vec![base[i], base[j], top[j], top[i]]);
        }
        f
    } else {
        let (a, b, c) = (
            rng.random_range(0.2..0.9),
            rng.random_range(0.2..0.9),
            rng.random_range(0.2..0.9),
        );
        let v = |x: Real, y: Real, z: Real| Point3::new(x * a, y * b, z * c);
        vec![
            vec![
                v(0.0, 0.0, 1.0),
                v(1.0, 0.0, 1.0),
                v(1.0, 1.0, 1.0),
                v(0.0, 1.0, 1.0),
            ],
            vec![
                v(0.0, 0.0, 0.0),
                v(0.0, 1.0, 0.0),
                v(1.0, 1.0, 0.0),
                v(1.0, 0.0, 0.0),
            ],
            vec![
                v(0.0, 0.0, 0.0),
                v(1.0, 0.0, 0.0),
                v(1.0, 0.0, 1.0),
                v(0.0, 0.0, 1.0),
            ],
            vec![
                v(1.0, 1.0, 0.0),
                v(0.0, 1.0, 0.0),
                v(0.0, 1.0, 1.0),
                v(1.0, 1.0, 1.0),
            ],
            vec![
                v(1.0, 0.0, 0.0),
                v(1.0, 1.0, 0.0),
                v(1.0, 1.0, 1.0),
                v(1.0, 0.0, 1.0),
            ],
            vec![
                v(0.0, 1.0, 0.0),
                v(0.0, 0.0, 0.0),
                v(0.0, 0.0, 1.0),
                v(0.0, 1.0, 1.0),
            ],
        ]
    };
    let rot = UnitQuaternion::from_euler_angles(
        rng.random_range(-3.1..3.1),
        rng.random_range(-3.1..3.1),
        rng.random_range(-3.1..3.1),
    );
    let pose = Isometry3::from_parts(
        Translation3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(0.0..1.0),
        ),
        rot,
    );
    faces
        .into_iter()
        .map(|f| f.iter().map(|p| pose * p).collect())
        .collect()
}

/// Points on every face on a jittered grid of spacing `h`, with sensing axes
/// against the outward normal tilted by up to ~40°, and Gaussian-free uniform
/// range noise of ±`noise` along the axis.
fn sample(
    faces: &[Vec<Point3>],
    h: Real,
    noise: Real,
    rng: &mut ChaCha8Rng,
) -> (Vec<Point3>, Vec<UnitVector3>) {
    let mut pts = Vec::new();
    let mut axes = Vec::new();
    for f in faces {
        let n = unit(geom::polygon3::newell_normal(f)).unwrap();
        let frame = geom::PlaneFrame::new(f[0], n);
        let poly: Vec<_> = f.iter().map(|p| frame.to_2d(p)).collect();
        let (lo, hi) = poly.iter().fold(
            (
                geom::Point2::new(Real::MAX, Real::MAX),
                geom::Point2::new(Real::MIN, Real::MIN),
            ),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        let mut y = lo.y + 0.5 * h;
        while y < hi.y {
            let mut x = lo.x + 0.5 * h;
            while x < hi.x {
                let q = geom::Point2::new(
                    x + rng.random_range(-0.3..0.3) * h,
                    y + rng.random_range(-0.3..0.3) * h,
                );
                if geom::polygon2::locate_point(&poly, &q, 0.0)
                    == geom::polygon2::Containment::Inside
                {
                    let tilt = Rotation3::from_axis_angle(
                        &geom::math::any_perpendicular(&n),
                        rng.random_range(-0.7..0.7),
                    );
                    let axis = unit(tilt * -n.into_inner()).unwrap();
                    let p = frame.to_3d(&q) + axis.into_inner() * rng.random_range(-noise..=noise);
                    pts.push(p);
                    axes.push(axis);
                }
                x += h;
            }
            y += h;
        }
    }
    (pts, axes)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn random_convex_polyhedra(seed in any::<u64>(), prism in any::<bool>(), noisy in any::<bool>(), batch in 20usize..=30) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let faces = polyhedron(&mut rng, prism);
        let (pts, axes) = sample(&faces, 0.03, if noisy { 0.01 } else { 0.0 }, &mut rng);
        let sets = chunk_sets(&pts, &axes, batch, 0.02);
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        feed_checked(&mut m, &sets);
        prop_assert!(m.stats().polygons >= 1);
    }
}
