//! Ellipsoids and the algebraic distance of Paul eq. 3.5.

use crate::aabb::Aabb;
use crate::math::{Isometry3, Point3, Real, Vector3};
use serde::{Deserialize, Serialize};

/// An ellipsoid with semi-axes `radii` along the axes of its own frame, placed by
/// `pose` (its frame in the frame it is expressed in — a link frame for the robot's
/// bounding ellipsoids, A§3.2.1.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ellipsoid {
    /// Frame of the ellipsoid: centre `p_c` and axis directions.
    pub pose: Isometry3,
    /// Semi-axes `[a_e, b_e, c_e]` (equatorial, equatorial, polar), all > 0.
    pub radii: Vector3,
}

impl Ellipsoid {
    /// An ellipsoid with frame `pose` and semi-axes `radii`.
    pub fn new(pose: Isometry3, radii: Vector3) -> Self {
        Self { pose, radii }
    }

    /// Algebraic distance of `p` (expressed in the same frame as `pose`):
    /// `(p' − p_c)ᵀ diag(a⁻², b⁻², c⁻²) (p' − p_c)` with `p'` in the ellipsoid's
    /// axes (Paul eq. 3.5). Below 1 inside, 1 on the surface, above 1 outside.
    #[inline]
    pub fn algebraic_distance(&self, p: &Point3) -> Real {
        let q = self.pose.inverse_transform_point(p);
        let s = q.coords.component_div(&self.radii);
        s.norm_squared()
    }

    /// The same ellipsoid re-expressed after applying `frame_from_here`
    /// (e.g. moving a link ellipsoid into the world frame).
    pub fn transformed(&self, frame_from_here: &Isometry3) -> Self {
        Self {
            pose: frame_from_here * self.pose,
            radii: self.radii,
        }
    }

    /// A box that contains the ellipsoid.
    pub fn bounding_box(&self) -> Aabb {
        // Half-extent along world axis i: sqrt(Σ_j (R_ij r_j)²).
        let r = self.pose.rotation.to_rotation_matrix();
        let m = r.matrix();
        let mut half = Vector3::zeros();
        for i in 0..3 {
            half[i] = (0..3)
                .map(|j| (m[(i, j)] * self.radii[j]).powi(2))
                .sum::<Real>()
                .sqrt();
        }
        let c = Point3::from(self.pose.translation.vector);
        Aabb::new(c - half, c + half)
    }

    /// Volume.
    pub fn volume(&self) -> Real {
        4.0 / 3.0 * std::f64::consts::PI * self.radii.x * self.radii.y * self.radii.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Translation3, UnitQuaternion};

    #[test]
    fn algebraic_distance_by_hand() {
        let e = Ellipsoid::new(
            Isometry3::from_parts(Translation3::new(1.0, 0.0, 0.0), UnitQuaternion::identity()),
            Vector3::new(2.0, 1.0, 0.5),
        );
        assert!((e.algebraic_distance(&Point3::new(3.0, 0.0, 0.0)) - 1.0).abs() < 1e-15);
        assert!((e.algebraic_distance(&Point3::new(1.0, 0.0, 0.5)) - 1.0).abs() < 1e-15);
        assert!((e.algebraic_distance(&Point3::new(1.0, 2.0, 0.0)) - 4.0).abs() < 1e-15);
        assert_eq!(e.algebraic_distance(&Point3::new(1.0, 0.0, 0.0)), 0.0);
        // Rotated 90° about z: the long axis now runs along y.
        let r = e.transformed(&Isometry3::rotation(
            Vector3::z() * std::f64::consts::FRAC_PI_2,
        ));
        let tip = Point3::new(0.0, 3.0, 0.0);
        assert!((r.algebraic_distance(&tip) - 1.0).abs() < 1e-12);
        let bb = r.bounding_box();
        assert!((bb.max.y - 3.0).abs() < 1e-12 && (bb.max.x - 1.0).abs() < 1e-12);
    }
}
