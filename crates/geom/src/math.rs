//! The scalar type and the nalgebra aliases used across the workspace.
//!
//! Every crate imports these instead of naming nalgebra types directly, so the
//! workspace has one vocabulary: `world_from_base: Isometry3`, `range_m: Real`.

/// The one scalar type for geometry and kinematics (SPEC §2).
pub type Real = f64;
/// A point in 3-D space.
pub type Point3 = nalgebra::Point3<Real>;
/// A vector in 3-D space.
pub type Vector3 = nalgebra::Vector3<Real>;
/// A vector of unit length (directions, normals, axes). Construct with [`unit()`] or
/// [`nalgebra::Unit::try_new`]; never by normalising a possibly-zero vector.
pub type UnitVector3 = nalgebra::Unit<Vector3>;
/// A rigid transform (rotation + translation). Name values `a_from_b`.
pub type Isometry3 = nalgebra::Isometry3<Real>;
/// A rotation as a unit quaternion.
pub type UnitQuaternion = nalgebra::UnitQuaternion<Real>;
/// A rotation as a 3×3 orthonormal matrix.
pub type Rotation3 = nalgebra::Rotation3<Real>;
/// A pure translation.
pub type Translation3 = nalgebra::Translation3<Real>;
/// A 3×3 matrix.
pub type Matrix3 = nalgebra::Matrix3<Real>;
/// A 4×4 matrix (homogeneous transforms in file formats).
pub type Matrix4 = nalgebra::Matrix4<Real>;
/// A point in a plane's 2-D coordinates.
pub type Point2 = nalgebra::Point2<Real>;
/// A vector in a plane's 2-D coordinates.
pub type Vector2 = nalgebra::Vector2<Real>;

/// Smallest norm accepted when turning a vector into a direction.
pub const MIN_DIRECTION_NORM: Real = 1e-12;

/// The unit vector along `v`, or `None` when `v` is (nearly) zero or not finite.
///
/// ```
/// use geom::{unit, Vector3};
/// assert!(unit(Vector3::new(0.0, 0.0, 2.0)).is_some());
/// assert!(unit(Vector3::zeros()).is_none());
/// assert!(unit(Vector3::new(f64::NAN, 0.0, 1.0)).is_none());
/// ```
#[inline]
pub fn unit(v: Vector3) -> Option<UnitVector3> {
    if !(v.x.is_finite() && v.y.is_finite() && v.z.is_finite()) {
        return None;
    }
    UnitVector3::try_new(v, MIN_DIRECTION_NORM)
}

/// Any unit vector perpendicular to `n`.
pub fn any_perpendicular(n: &UnitVector3) -> UnitVector3 {
    // Cross with the world axis least aligned with n: never degenerate.
    let a = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        Vector3::x()
    } else if n.y.abs() <= n.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let c = n.cross(&a);
    UnitVector3::new_normalize(c)
}

/// Two unit vectors `(u, v)` spanning the plane normal to the unit `n`,
/// `(u, v, n)` right-handed: `u = n × x̂` normalised (`n × ŷ` when `n` is
/// within about 26° of the x axis), `v = n × u`. Unlike
/// [`crate::PlaneFrame::new`] (the least-aligned axis), the helper axis
/// changes at one fixed cone; the report's drawings use it.
///
/// ```
/// use geom::Vector3;
/// let n = Vector3::new(0.0, 0.6, 0.8);
/// let (u, v) = geom::math::basis_from_normal(&n);
/// assert!(u.dot(&n).abs() < 1e-12 && v.dot(&n).abs() < 1e-12 && u.dot(&v).abs() < 1e-12);
/// assert!((u.cross(&v) - n).norm() < 1e-12);
/// ```
pub fn basis_from_normal(n: &Vector3) -> (Vector3, Vector3) {
    let helper = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = unit(n.cross(&helper)).map_or_else(Vector3::x, UnitVector3::into_inner);
    (u, n.cross(&u))
}

/// `true` when every coordinate of `p` is finite.
#[inline]
pub fn is_finite_point(p: &Point3) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.z.is_finite()
}

/// The 4×4 homogeneous matrix of an isometry, as row-major nested arrays
/// (the layout file formats and the CLI's JSON use).
pub fn isometry_to_rows(iso: &Isometry3) -> [[Real; 4]; 4] {
    let m = iso.to_homogeneous();
    let mut rows = [[0.0; 4]; 4];
    for (r, row) in rows.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = m[(r, c)];
        }
    }
    rows
}

/// An isometry from a translation and roll-pitch-yaw angles (radians, fixed axes
/// x, then y, then z — the URDF convention).
pub fn isometry_from_xyz_rpy(xyz: [Real; 3], rpy: [Real; 3]) -> Isometry3 {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perpendicular_is_unit_and_orthogonal() {
        for v in [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::new(-1e-3, 1.0, 1e-3),
        ] {
            let n = unit(v).unwrap();
            let p = any_perpendicular(&n);
            assert!((p.norm() - 1.0).abs() < 1e-12);
            assert!(p.dot(&n).abs() < 1e-12);
        }
    }

    #[test]
    fn rpy_matches_urdf_convention() {
        // URDF: R = Rz(yaw) * Ry(pitch) * Rx(roll).
        let iso = isometry_from_xyz_rpy([1.0, 2.0, 3.0], [0.3, -0.2, 1.1]);
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 1.1)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), -0.2)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), 0.3);
        assert!((iso.rotation.to_rotation_matrix().matrix() - r.matrix()).norm() < 1e-12);
        let rows = isometry_to_rows(&iso);
        assert_eq!(rows[0][3], 1.0);
        assert_eq!(rows[3], [0.0, 0.0, 0.0, 1.0]);
    }
}
