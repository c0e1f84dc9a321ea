//! Bounding shapes of link geometry: an enclosing capsule (the default collision
//! shape) and an enclosing ellipsoid (the AXBAM "ellipsoidal virtual bounding
//! field" of A§3.2.1.4, used by the safety distance of A eq. 3.5).
//!
//! The ellipsoid is the minimum-volume enclosing ellipsoid (MVEE) computed by
//! Khachiyan's algorithm, then scaled up just enough that every input point has
//! algebraic distance ≤ 1: enclosure is exact, minimality is to the tolerance.

use geom::{
    Capsule, Ellipsoid, Isometry3, Matrix3, Moments, Point3, Real, Rotation3, Translation3,
    UnitQuaternion, Vector3, unit,
};
use nalgebra::{Matrix4, Vector4};

/// Convergence tolerance of Khachiyan's algorithm (change of the weight vector).
pub const MVEE_TOLERANCE: Real = 1e-4;

/// Iteration cap of Khachiyan's algorithm; the result is valid (enclosing) even
/// when the cap is hit, only less tight.
const MVEE_MAX_ITERATIONS: usize = 20_000;

/// Smallest capsule radius produced (for point or collinear sets).
const MIN_RADIUS: Real = 1e-6;

/// Relative safety margin applied after fitting, against rounding.
const MARGIN: Real = 1e-9;

/// A capsule containing every point: its axis runs along the direction of greatest
/// spread (PCA), centred on the points' cross-section, and its radius and end points
/// are chosen (over a few radius candidates) to minimise the volume while keeping
/// every point inside. `None` for an empty or non-finite set.
///
/// ```
/// use geom::Point3;
/// let pts = [Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 0.0, 0.0), Point3::new(1.0, 0.3, 0.0)];
/// let c = robot::bounds::enclosing_capsule(&pts).unwrap();
/// assert!(pts.iter().all(|p| c.distance_to_point(p) <= 0.0));
/// ```
pub fn enclosing_capsule(points: &[Point3]) -> Option<Capsule> {
    if points.is_empty() || !points.iter().all(geom::math::is_finite_point) {
        return None;
    }
    let pca = Moments::from_points(points).pca()?;
    let axis = pca.axes[2].into_inner();
    let (u, v) = (pca.axes[0].into_inner(), pca.axes[1].into_inner());
    // Centre the axis line on the 2-D bounding box of the cross-section.
    let (mut umin, mut umax, mut vmin, mut vmax) = (Real::MAX, Real::MIN, Real::MAX, Real::MIN);
    for p in points {
        let d = p - pca.centroid;
        let (a, b) = (d.dot(&u), d.dot(&v));
        umin = umin.min(a);
        umax = umax.max(a);
        vmin = vmin.min(b);
        vmax = vmax.max(b);
    }
    let centre = pca.centroid + u * (0.5 * (umin + umax)) + v * (0.5 * (vmin + vmax));
    // Axial coordinate and radial distance of every point.
    let tr: Vec<(Real, Real)> = points
        .iter()
        .map(|p| {
            let d = p - centre;
            let t = d.dot(&axis);
            (t, (d - axis * t).norm())
        })
        .collect();
    let rho_max = tr
        .iter()
        .map(|&(_, r)| r)
        .fold(0.0, Real::max)
        .max(MIN_RADIUS);
    // The capsule of radius r: each point needs the axis segment to reach
    // t_i ± sqrt(r² − ρ_i²); the segment shrinks to a point once that is possible.
    let fit = |r: Real| {
        let mut lo = Real::MAX; // smallest allowed start: min(t_i + s_i)
        let mut hi = Real::MIN; // largest required end: max(t_i − s_i)
        for &(t, rho) in &tr {
            let s = (r * r - rho * rho).max(0.0).sqrt();
            lo = lo.min(t + s);
            hi = hi.max(t - s);
        }
        let (ta, tb) = if hi <= lo {
            let mid = 0.5 * (hi + lo);
            (mid, mid)
        } else {
            (lo, hi)
        };
        Capsule::new(
            centre + axis * ta,
            centre + axis * tb,
            r * (1.0 + MARGIN) + MARGIN,
        )
    };
    // Smallest volume over the radius: a coarse scan, then a fine one around the best.
    let mut best = (Real::MAX, rho_max);
    for k in 0..=20 {
        let r = rho_max * (1.0 + 0.05 * Real::from(k));
        let v = fit(r).volume();
        if v < best.0 {
            best = (v, r);
        }
    }
    let coarse = best.1;
    for k in -20..=20 {
        let r = (coarse * (1.0 + 0.0025 * Real::from(k))).max(rho_max);
        let v = fit(r).volume();
        if v < best.0 {
            best = (v, r);
        }
    }
    Some(fit(best.1))
}

/// The minimum-volume ellipsoid enclosing `points` (Khachiyan's algorithm to
/// [`MVEE_TOLERANCE`]), scaled up so that every point has algebraic distance ≤ 1.
/// `None` for fewer than 4 points, non-finite points, or points that do not span
/// 3-D space (coplanar or collinear sets).
///
/// ```
/// use geom::Point3;
/// let mut pts = Vec::new();
/// for x in [-1.0, 1.0] { for y in [-2.0, 2.0] { for z in [-0.5, 0.5] { pts.push(Point3::new(x, y, z)); } } }
/// let e = robot::bounds::enclosing_ellipsoid(&pts).unwrap();
/// assert!(pts.iter().all(|p| e.algebraic_distance(p) <= 1.0));
/// // The MVEE of a box has semi-axes √3 × the half-extents.
/// let mut r: Vec<f64> = e.radii.iter().copied().collect();
/// r.sort_by(f64::total_cmp);
/// assert!((r[2] - 2.0 * 3f64.sqrt()).abs() < 1e-2);
/// ```
pub fn enclosing_ellipsoid(points: &[Point3]) -> Option<Ellipsoid> {
    let n = points.len();
    if n < 4 || !points.iter().all(geom::math::is_finite_point) {
        return None;
    }
    // Work about the mean and at unit scale, for conditioning.
    let mean = points.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n as Real;
    let scale = points
        .iter()
        .map(|p| (p.coords - mean).amax())
        .fold(0.0, Real::max);
    if scale <= 0.0 || !scale.is_finite() {
        return None;
    }
    let lifted: Vec<Vector4<Real>> = points
        .iter()
        .map(|p| {
            let d = (p.coords - mean) / scale;
            Vector4::new(d.x, d.y, d.z, 1.0)
        })
        .collect();
    let u = khachiyan(&lifted)?;
    // Centre and shape from the weights: S = Σ u_i (p_i − c)(p_i − c)ᵀ, A = S⁻¹ / 3.
    let mut c = Vector3::zeros();
    for (q, w) in lifted.iter().zip(&u) {
        c += q.xyz() * *w;
    }
    let mut s = Matrix3::zeros();
    for (q, w) in lifted.iter().zip(&u) {
        let d = q.xyz() - c;
        s += d * d.transpose() * *w;
    }
    let eig = nalgebra::SymmetricEigen::new(s);
    let max_eig = eig.eigenvalues.max();
    if max_eig.is_nan() || max_eig <= 0.0 || eig.eigenvalues.min() <= max_eig * 1e-12 {
        return None;
    }
    let mut axes = eig.eigenvectors;
    if axes.determinant() < 0.0 {
        let flipped = -axes.column(2);
        axes.set_column(2, &flipped);
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
    let radii = eig.eigenvalues.map(|l| (3.0 * l).sqrt() * scale);
    let centre = mean + c * scale;
    let mut ellipsoid = Ellipsoid::new(
        Isometry3::from_parts(Translation3::from(centre), rotation),
        radii,
    );
    // Scale up so every point is inside (the MVEE is tight only to the tolerance).
    let worst = points
        .iter()
        .map(|p| ellipsoid.algebraic_distance(p))
        .fold(0.0, Real::max);
    if !worst.is_finite() {
        return None;
    }
    ellipsoid.radii *= worst.max(1.0).sqrt() * (1.0 + MARGIN);
    Some(ellipsoid)
}

/// Khachiyan's barycentric coordinate ascent for the MVEE of the lifted points
/// `(p, 1)`; returns the weights `u` (summing to 1). Rank-one updates of
/// `X = Σ u_i q_i q_iᵀ`, refreshed periodically.
fn khachiyan(q: &[Vector4<Real>]) -> Option<Vec<Real>> {
    const D1: Real = 4.0; // dimension + 1
    let n = q.len();
    let mut u = vec![1.0 / n as Real; n];
    let full = |u: &[Real]| {
        let mut x = Matrix4::zeros();
        for (qi, w) in q.iter().zip(u) {
            x += qi * qi.transpose() * *w;
        }
        x
    };
    let mut x = full(&u);
    for iteration in 0..MVEE_MAX_ITERATIONS {
        if iteration % 64 == 63 {
            x = full(&u);
        }
        let x_inv = x.try_inverse()?;
        let (mut j, mut m_j) = (0, Real::MIN);
        for (i, qi) in q.iter().enumerate() {
            let m = qi.dot(&(x_inv * qi));
            if m > m_j {
                j = i;
                m_j = m;
            }
        }
        if !m_j.is_finite() || m_j <= 1.0 {
            return None;
        }
        let step = (m_j - D1) / (D1 * (m_j - 1.0));
        // ‖u_new − u‖² = step² (Σ u_i² − 2 u_j + 1), using u_new = (1 − step) u + step e_j.
        let sum_sq: Real = u.iter().map(|w| w * w).sum();
        let change = step.abs() * (sum_sq - 2.0 * u[j] + 1.0).max(0.0).sqrt();
        for w in &mut u {
            *w *= 1.0 - step;
        }
        u[j] += step;
        x = x * (1.0 - step) + q[j] * q[j].transpose() * step;
        if change < MVEE_TOLERANCE {
            break;
        }
    }
    Some(u)
}

/// Points whose convex hull contains `capsule`: each end sphere sampled on a
/// 15° latitude/longitude grid at radius `r / cos 15°` (so the hull of the samples
/// covers the sphere). An ellipsoid enclosing these points encloses the capsule.
pub fn capsule_sample_points(capsule: &Capsule) -> Vec<Point3> {
    const STEP_DEG: usize = 15;
    let step = (STEP_DEG as Real).to_radians();
    let r = capsule.radius / step.cos();
    let rings = 180 / STEP_DEG; // latitude bands
    let around = 360 / STEP_DEG;
    let mut directions = vec![Vector3::z(), -Vector3::z()];
    for i in 1..rings {
        let polar = step * i as Real;
        for k in 0..around {
            let azimuth = step * k as Real;
            directions.push(Vector3::new(
                polar.sin() * azimuth.cos(),
                polar.sin() * azimuth.sin(),
                polar.cos(),
            ));
        }
    }
    let mut out = Vec::with_capacity(2 * directions.len());
    let ends = if capsule.axis().norm() > 0.0 {
        vec![capsule.segment.a, capsule.segment.b]
    } else {
        vec![capsule.segment.a]
    };
    for end in ends {
        out.extend(directions.iter().map(|d| end + d * r));
    }
    out
}

/// The enclosing ellipsoid of a set of capsules and mesh vertices (all in one
/// frame): the MVEE of the vertices plus [`capsule_sample_points`] of each capsule.
pub fn enclosing_ellipsoid_of(capsules: &[Capsule], vertices: &[Point3]) -> Option<Ellipsoid> {
    let mut points = vertices.to_vec();
    for c in capsules {
        points.extend(capsule_sample_points(c));
    }
    enclosing_ellipsoid(&points)
}

/// A unit vector along `v`, or z when `v` is (nearly) zero.
pub(crate) fn unit_or_z(v: Vector3) -> geom::UnitVector3 {
    unit(v).unwrap_or_else(Vector3::z_axis)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_points_give_a_sphere() {
        let c = Capsule::new(Point3::new(1.0, 2.0, 3.0), Point3::new(1.0, 2.0, 3.0), 0.5);
        let e = enclosing_ellipsoid(&capsule_sample_points(&c)).unwrap();
        for r in e.radii.iter() {
            assert!(*r >= 0.5 && *r < 0.5 * 1.06, "radius {r}");
        }
        assert!((e.pose.translation.vector - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-3);
    }

    #[test]
    fn capsule_is_inside_its_ellipsoid() {
        let c = Capsule::new(Point3::new(0.0, 0.0, 0.0), Point3::new(0.3, 0.2, 1.0), 0.05);
        let e = enclosing_ellipsoid_of(&[c], &[]).unwrap();
        // Dense check of the capsule surface.
        let axis = unit_or_z(c.axis());
        let u = geom::math::any_perpendicular(&axis);
        let v = axis.cross(&u);
        for i in 0..=40 {
            let s = Real::from(i) / 40.0;
            for k in 0..72 {
                let a = std::f64::consts::TAU * Real::from(k) / 72.0;
                let p = c.segment.point_at(s) + (u.into_inner() * a.cos() + v * a.sin()) * c.radius;
                assert!(e.algebraic_distance(&p) <= 1.0);
            }
        }
        for d in [axis.into_inner(), -axis.into_inner()] {
            let tip = if d.dot(&axis) > 0.0 {
                c.segment.b
            } else {
                c.segment.a
            };
            assert!(e.algebraic_distance(&(tip + d * c.radius)) <= 1.0);
        }
    }

    #[test]
    fn degenerate_sets_have_no_ellipsoid() {
        let flat: Vec<Point3> = (0..10)
            .map(|i| Point3::new(Real::from(i), Real::from(i * i), 0.0))
            .collect();
        assert!(enclosing_ellipsoid(&flat).is_none());
        assert!(enclosing_ellipsoid(&flat[..3]).is_none());
        assert!(enclosing_capsule(&[]).is_none());
        let one = enclosing_capsule(&[Point3::new(1.0, 1.0, 1.0)]).unwrap();
        assert!(one.distance_to_point(&Point3::new(1.0, 1.0, 1.0)) <= 0.0);
    }
}
