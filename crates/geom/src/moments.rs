//! Moment sums of point sets and principal component analysis.
//!
//! Pudney keeps, per model segment, the "model segment data" (P§2.2):
//! `m, Σx, Σy, Σz, Σxy, Σxz, Σyz, Σx², Σy², Σz²`. Two segments merge by adding their
//! sums; the centroid and covariance follow without revisiting the points. The
//! plane of best fit passes through the centroid with the normal along the
//! eigenvector of the smallest covariance eigenvalue (Pearson). Paul's Scale-Like
//! Discs (A§5.2) use the same PCA for their normals.

use crate::math::{Matrix3, Point3, Real, UnitVector3, Vector3, unit};
use serde::{Deserialize, Serialize};

/// Moment sums of a set of points (P§2.2 "model segment data").
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Number of points represented.
    pub m: u64,
    /// Σx, Σy, Σz.
    pub sum: Vector3,
    /// Σxy, Σxz, Σyz.
    pub sum_cross: Vector3,
    /// Σx², Σy², Σz².
    pub sum_sq: Vector3,
}

/// Principal axes of a point set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pca {
    /// The centroid.
    pub centroid: Point3,
    /// Covariance eigenvalues in ascending order (variances along `axes`).
    pub eigenvalues: [Real; 3],
    /// Unit eigenvectors matching `eigenvalues`: `axes[0]` is the plane normal of
    /// best fit, `axes[2]` the direction of greatest spread.
    pub axes: [UnitVector3; 3],
}

impl Moments {
    /// The sums of a single point.
    pub fn from_point(p: &Point3) -> Self {
        let mut s = Self::default();
        s.add(p);
        s
    }

    /// The sums of all `points`.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Point3>) -> Self {
        let mut s = Self::default();
        for p in points {
            s.add(p);
        }
        s
    }

    /// Add one point.
    #[inline]
    pub fn add(&mut self, p: &Point3) {
        self.m += 1;
        self.sum += p.coords;
        self.sum_cross += Vector3::new(p.x * p.y, p.x * p.z, p.y * p.z);
        self.sum_sq += p.coords.component_mul(&p.coords);
    }

    /// The sums of the union of two disjoint point sets.
    #[inline]
    pub fn merged(&self, other: &Self) -> Self {
        Self {
            m: self.m + other.m,
            sum: self.sum + other.sum,
            sum_cross: self.sum_cross + other.sum_cross,
            sum_sq: self.sum_sq + other.sum_sq,
        }
    }

    /// `true` when no point is represented (e.g. an initial segment, P§4.3).
    pub fn is_empty(&self) -> bool {
        self.m == 0
    }

    /// The centroid, or `None` when empty.
    pub fn centroid(&self) -> Option<Point3> {
        (self.m > 0).then(|| Point3::from(self.sum / self.m as Real))
    }

    /// The covariance matrix `C` of P§2.2 (population normalisation, `1/m`),
    /// or `None` when empty.
    pub fn covariance(&self) -> Option<Matrix3> {
        if self.m == 0 {
            return None;
        }
        let m = self.m as Real;
        let c = self.sum / m;
        let xx = self.sum_sq.x / m - c.x * c.x;
        let yy = self.sum_sq.y / m - c.y * c.y;
        let zz = self.sum_sq.z / m - c.z * c.z;
        let xy = self.sum_cross.x / m - c.x * c.y;
        let xz = self.sum_cross.y / m - c.x * c.z;
        let yz = self.sum_cross.z / m - c.y * c.z;
        Some(Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz))
    }

    /// Variance about the centroid, `s²_pt = s²x + s²y + s²z` (P§2.2): the trace of
    /// the covariance. `None` when empty.
    pub fn point_variance(&self) -> Option<Real> {
        self.covariance().map(|c| c.trace().max(0.0))
    }

    /// Principal component analysis by symmetric eigen-decomposition of the
    /// covariance. `None` when empty or when the sums are not finite.
    pub fn pca(&self) -> Option<Pca> {
        Pca::from_covariance(self.centroid()?, &self.covariance()?)
    }
}

impl Pca {
    /// The principal axes of a covariance matrix about `centroid`: its
    /// symmetric eigen-decomposition, eigenvalues sorted ascending (clamped at
    /// 0), axes a right-handed frame. `None` when an entry is not finite.
    pub fn from_covariance(centroid: Point3, cov: &Matrix3) -> Option<Self> {
        if !cov.iter().all(|v| v.is_finite()) {
            return None;
        }
        let eig = nalgebra::SymmetricEigen::new(*cov);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let axis = |i: usize| -> Option<UnitVector3> { unit(eig.eigenvectors.column(i).into()) };
        let a0 = axis(order[0])?;
        let a1 = axis(order[1])?;
        // Right-handed frame: axes[2] = axes[0] × axes[1] (same eigen-line).
        let a2 = unit(a0.cross(&a1))?;
        Some(Self {
            centroid,
            eigenvalues: [
                eig.eigenvalues[order[0]].max(0.0),
                eig.eigenvalues[order[1]].max(0.0),
                eig.eigenvalues[order[2]].max(0.0),
            ],
            axes: [a0, a1, a2],
        })
    }

    /// PCA of points given as offsets from a reference point (two passes:
    /// mean, then covariance about it, population normalisation). Working
    /// relative to a nearby reference keeps full precision far from the
    /// origin, where raw moment sums cancel; the result's `centroid` is the
    /// mean offset (add the reference back). `None` when empty or not finite.
    pub fn of_offsets(offsets: &[Vector3]) -> Option<Self> {
        if offsets.is_empty() {
            return None;
        }
        let n = offsets.len() as Real;
        let mean = offsets.iter().sum::<Vector3>() / n;
        let mut cov = Matrix3::zeros();
        for d in offsets {
            let c = d - mean;
            cov += c * c.transpose();
        }
        Self::from_covariance(Point3::from(mean), &(cov / n))
    }

    /// The plane-of-best-fit normal when the points span a plane: `None` for
    /// collinear or coincident points (`λ_mid ≤ 10⁻⁹ λ_max`, or nothing
    /// spread) and when `λ_mid < min_ratio · λ_min` (a planarity test such as
    /// Paul's dimensionality reduction, A§5.2).
    pub fn plane_normal(&self, min_ratio: Real) -> Option<UnitVector3> {
        let [l0, l1, l2] = self.eigenvalues;
        if l2.is_nan() || l2 <= 0.0 || l1 <= 1e-9 * l2 || l1 < min_ratio * l0 {
            return None;
        }
        Some(self.axes[0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centroid_and_covariance_by_hand() {
        let pts = [
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(-1.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(0.0, -2.0, 0.0),
        ];
        let m = Moments::from_points(&pts);
        assert_eq!(m.centroid().unwrap(), Point3::origin());
        let c = m.covariance().unwrap();
        assert!((c[(0, 0)] - 0.5).abs() < 1e-15);
        assert!((c[(1, 1)] - 2.0).abs() < 1e-15);
        assert_eq!(c[(2, 2)], 0.0);
        assert!((m.point_variance().unwrap() - 2.5).abs() < 1e-15);
        let pca = m.pca().unwrap();
        assert!(pca.eigenvalues[0].abs() < 1e-15);
        assert!((pca.eigenvalues[1] - 0.5).abs() < 1e-12);
        assert!((pca.eigenvalues[2] - 2.0).abs() < 1e-12);
        assert!((pca.axes[0].z.abs() - 1.0).abs() < 1e-12);
        assert!((pca.axes[2].y.abs() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn merge_equals_union() {
        let a = [Point3::new(1.0, 2.0, 3.0), Point3::new(-1.0, 0.5, 2.0)];
        let b = [Point3::new(0.0, 0.0, 1.0), Point3::new(4.0, -2.0, 0.0)];
        let ma = Moments::from_points(&a);
        let mb = Moments::from_points(&b);
        let all = Moments::from_points(a.iter().chain(b.iter()));
        let merged = ma.merged(&mb);
        assert_eq!(merged.m, 4);
        assert!((merged.sum - all.sum).norm() < 1e-15);
        assert!((merged.covariance().unwrap() - all.covariance().unwrap()).norm() < 1e-12);
        assert!(Moments::default().pca().is_none());
        // The two-pass PCA of offsets agrees, and keeps precision 10 km out.
        let far = Vector3::new(1e4, -2e4, 3e3);
        let offsets: Vec<Vector3> = a.iter().chain(b.iter()).map(|p| p.coords).collect();
        let pca = Pca::of_offsets(&offsets).unwrap();
        let direct = all.pca().unwrap();
        for k in 0..3 {
            assert!((pca.eigenvalues[k] - direct.eigenvalues[k]).abs() < 1e-12);
        }
        let shifted: Vec<Point3> = a.iter().chain(b.iter()).map(|p| p + far).collect();
        let rel: Vec<Vector3> = shifted.iter().map(|p| p - shifted[0]).collect();
        let two_pass = Pca::of_offsets(&rel).unwrap();
        let err = |p: &Pca| {
            (0..3)
                .map(|k| (p.eigenvalues[k] - direct.eigenvalues[k]).abs())
                .fold(0.0, Real::max)
        };
        assert!(err(&two_pass) < 1e-9, "{}", err(&two_pass));
        // Collinear points have no plane; a flat patch has one.
        let line: Vec<Vector3> = (0..5).map(|i| Vector3::new(i as Real, 0.0, 0.0)).collect();
        assert!(Pca::of_offsets(&line).unwrap().plane_normal(1.0).is_none());
        let n = Pca::of_offsets(&offsets[..3])
            .unwrap()
            .plane_normal(1.0)
            .unwrap();
        assert!(n.dot(&(a[1] - a[0])).abs() < 1e-12);
    }

    #[test]
    fn tilted_plane_normal() {
        let n = unit(Vector3::new(1.0, -2.0, 0.5)).unwrap();
        let u = crate::math::any_perpendicular(&n);
        let v = n.cross(&u);
        let mut m = Moments::default();
        for i in 0..10 {
            for j in 0..7 {
                let p = Point3::new(3.0, -1.0, 2.0)
                    + u.into_inner() * (i as f64 * 0.1)
                    + v * (j as f64 * 0.13);
                m.add(&p);
            }
        }
        let pca = m.pca().unwrap();
        assert!(pca.axes[0].dot(&n).abs() > 1.0 - 1e-9);
        assert!(pca.eigenvalues[0] < 1e-12);
    }
}
