//! Control-point motion (P§3.2, Fig. 27): the vector sum of a corrective motion
//! to the desired distance δ from the model and a perpendicular motion along
//! the model in the surface-following direction, of total length σ.

use geom::{Point3, Real, Vector3};

/// The control-point motion `ẋ` for one step.
///
/// * `control_point`, `closest`: the control point and the model point closest
///   to it;
/// * `direction`: the surface-following direction (any length; zero for none);
/// * `desired_distance`: δ;
/// * `step`: σ, already limited to σ_max and any mode limit. σ is further
///   limited to the distance between the control point and the model, so a
///   motion never carries the control point into the model (P§3.2).
///
/// The corrective motion has priority: when |δ − d| ≥ σ it alone is taken,
/// shortened to σ.
///
/// ```
/// use geom::{Point3, Vector3};
/// // 0.15 above a plane, δ = 0.1, σ = 0.1: corrective −0.05 in z, then
/// // perpendicular √(0.1² − 0.05²) along x.
/// let m = follow::control_point_motion(
///     &Point3::new(0.0, 0.0, 0.15),
///     &Point3::origin(),
///     &Vector3::new(1.0, 0.0, 0.3),
///     0.1,
///     0.1,
/// );
/// assert!((m.z + 0.05).abs() < 1e-12);
/// assert!((m.x - (0.01_f64 - 0.0025).sqrt()).abs() < 1e-12);
/// assert!((m.norm() - 0.1).abs() < 1e-12);
/// ```
pub fn control_point_motion(
    control_point: &Point3,
    closest: &Point3,
    direction: &Vector3,
    desired_distance: Real,
    step: Real,
) -> Vector3 {
    let away = control_point - closest;
    let d = away.norm();
    let sigma = step.min(d).max(0.0);
    if d <= 0.0 || sigma <= 0.0 {
        return Vector3::zeros();
    }
    let normal = away / d;
    let corrective = desired_distance - d;
    if corrective.abs() >= sigma {
        return normal * sigma.copysign(corrective);
    }
    let along = direction - normal * direction.dot(&normal);
    let len = along.norm();
    let perpendicular = if len > 1e-12 {
        along * ((sigma * sigma - corrective * corrective).max(0.0).sqrt() / len)
    } else {
        Vector3::zeros()
    };
    normal * corrective + perpendicular
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The motion has length σ (= min(σ, d)) whenever a perpendicular
        /// direction exists, never moves closer to the closest point than
        /// the corrective part asks, and its normal component is the corrective
        /// motion clamped to ±σ.
        #[test]
        fn length_and_priority(
            h in 0.01f64..0.5, dx in -1.0f64..1.0, dy in -1.0f64..1.0, dz in -1.0f64..1.0,
            sigma in 0.001f64..0.2,
        ) {
            let cp = Point3::new(0.0, 0.0, h);
            let dir = Vector3::new(dx, dy, dz);
            let m = control_point_motion(&cp, &Point3::origin(), &dir, 0.1, sigma);
            let s = sigma.min(h);
            let corr = 0.1 - h;
            let expect_normal = corr.clamp(-s, s);
            prop_assert!((m.z - expect_normal).abs() < 1e-9);
            let has_perp = dx.hypot(dy) > 1e-9;
            if corr.abs() < s && has_perp {
                prop_assert!((m.norm() - s).abs() < 1e-9);
            }
            // Never into the model: the new height stays ≥ 0.
            prop_assert!(h + m.z >= -1e-12);
        }
    }
}
