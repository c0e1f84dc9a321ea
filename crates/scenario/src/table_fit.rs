//! A support plane (a table) fitted to scan points, as the world frame and the
//! initial segment of a point-cloud scenario (Pudney's a-priori table, P§4.3).
//!
//! [`fit_table`] takes the points of the table (e.g. those a labelled scan
//! marks as table) and the sensor position, both in the scan's frame:
//!
//! 1. the plane of best fit by PCA of the points ([`geom::Pca::of_offsets`]):
//!    through their centroid, normal along the least-variance axis, turned to
//!    face the sensor (the table's top is the side the sensor saw);
//! 2. the world frame `world_from_scan`: origin at the centroid, z the normal,
//!    x the scan's x axis projected onto the plane (its y axis when x is within
//!    1° of the normal), y = z × x — so the table is `z = 0` and up is +z;
//! 3. the table polygon: the convex hull of the points projected onto the
//!    plane, anticlockwise about +z, in world coordinates (`z = 0`), with
//!    vertices closer than `min_edge_m` to their predecessor dropped.

use crate::ScenarioError;
use geom::{
    Isometry3, Pca, Point2, Point3, Real, Rotation3, Translation3, UnitQuaternion, Vector3, unit,
};
use serde::Serialize;

/// A table plane fitted to scan points.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableFit {
    /// The table frame (z up out of the table, table at z = 0) in the scan's
    /// frame: `p_world = world_from_scan * p_scan`.
    pub world_from_scan: Isometry3,
    /// The table polygon in the world frame (z = 0), anticlockwise about +z.
    pub polygon: Vec<Point3>,
    /// Root-mean-square distance of the points to the plane, metres.
    pub rms_m: Real,
    /// 95th percentile of the distances of the points to the plane, metres.
    pub p95_m: Real,
    /// Points used.
    pub points: usize,
}

/// The points whose label is `label` (a labelled scan's points and labels,
/// in the same order; the mOSD scans label the table 1).
pub fn points_labelled(points: &[Point3], labels: &[i64], label: i64) -> Vec<Point3> {
    points
        .iter()
        .zip(labels)
        .filter(|(_, l)| **l == label)
        .map(|(p, _)| *p)
        .collect()
}

/// Fit the table plane to `points` seen from `sensor` (both in the scan's
/// frame); see the [module documentation](self). `min_edge_m` thins the hull.
///
/// Errors: fewer than three points, a non-finite point, points that span no
/// plane, or a sensor on the plane.
pub fn fit_table(
    points: &[Point3],
    sensor: &Point3,
    min_edge_m: Real,
) -> Result<TableFit, ScenarioError> {
    let bad = |message: String| ScenarioError::InvalidArgument {
        what: "table points".into(),
        message,
    };
    if points.len() < 3 {
        return Err(bad(format!("{} points (at least 3 needed)", points.len())));
    }
    if let Some(i) = points.iter().position(|p| !geom::math::is_finite_point(p)) {
        return Err(bad(format!("point {i} is not finite")));
    }
    let reference = points[0];
    let offsets: Vec<Vector3> = points.iter().map(|p| p - reference).collect();
    let pca = Pca::of_offsets(&offsets).ok_or_else(|| bad("no PCA".into()))?;
    let normal = pca
        .plane_normal(0.0)
        .ok_or_else(|| bad("the points span no plane".into()))?;
    let centroid = reference + pca.centroid.coords;
    let side = normal.dot(&(sensor - centroid));
    if side.abs() < 1e-9 {
        return Err(bad("the sensor lies on the table plane".into()));
    }
    let z = if side > 0.0 { normal } else { -normal };
    let reference_axis = if z.x.abs() < 1f64.to_radians().cos() {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let x = unit(reference_axis - z.into_inner() * z.dot(&reference_axis))
        .ok_or_else(|| bad("no in-plane axis".into()))?;
    let y = z.cross(&x);
    // scan_from_world has columns x, y, z and translation `centroid`.
    let rot = Rotation3::from_basis_unchecked(&[x.into_inner(), y, z.into_inner()]);
    let scan_from_world = Isometry3::from_parts(
        Translation3::from(centroid.coords),
        UnitQuaternion::from_rotation_matrix(&rot),
    );
    let world_from_scan = scan_from_world.inverse();
    let mut dist: Vec<Real> = points
        .iter()
        .map(|p| (world_from_scan * p).z.abs())
        .collect();
    let rms_m = (dist.iter().map(|d| d * d).sum::<Real>() / dist.len() as Real).sqrt();
    dist.sort_by(Real::total_cmp);
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let p95_m = dist[((0.95 * dist.len() as Real).ceil() as usize).clamp(1, dist.len()) - 1];
    let hull = geom::polygon2::convex_hull(
        points
            .iter()
            .map(|p| {
                let w = world_from_scan * p;
                Point2::new(w.x, w.y)
            })
            .collect(),
    );
    let mut polygon: Vec<Point3> = Vec::with_capacity(hull.len());
    for q in &hull {
        if polygon
            .last()
            .is_none_or(|l| (Point2::new(l.x, l.y) - q).norm() >= min_edge_m)
        {
            polygon.push(Point3::new(q.x, q.y, 0.0));
        }
    }
    while polygon.len() > 3
        && polygon
            .first()
            .zip(polygon.last())
            .is_some_and(|(f, l)| (f - l).norm() < min_edge_m)
    {
        polygon.pop();
    }
    if polygon.len() < 3 {
        return Err(bad("the table's outline has fewer than 3 vertices".into()));
    }
    Ok(TableFit {
        world_from_scan,
        polygon,
        rms_m,
        p95_m,
        points: points.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tilted_square_is_recovered() {
        // A 1 m square grid on the plane through (0, 0, 2) with normal
        // (0, −1, −1)/√2, seen from the origin.
        let n = unit(Vector3::new(0.0, -1.0, -1.0)).unwrap().into_inner();
        let u = Vector3::x();
        let v = n.cross(&u);
        let c = Point3::new(0.0, 0.0, 2.0);
        let mut pts = Vec::new();
        for i in 0..=20 {
            for j in 0..=20 {
                let (a, b) = (f64::from(i) / 20.0 - 0.5, f64::from(j) / 20.0 - 0.5);
                pts.push(c + u * a + v * b);
            }
        }
        let fit = fit_table(&pts, &Point3::origin(), 0.01).unwrap();
        assert!(fit.rms_m < 1e-12 && fit.p95_m < 1e-12);
        // Up is towards the sensor; the centre maps to the origin.
        let up = fit.world_from_scan.inverse().rotation * Vector3::z();
        assert!((up - n).norm() < 1e-12, "{up:?}");
        assert!((fit.world_from_scan * c).coords.norm() < 1e-12);
        // The hull is the square's 4 corners, anticlockwise about +z.
        assert_eq!(fit.polygon.len(), 4);
        let area: Real = (0..4)
            .map(|i| {
                let (p, q) = (fit.polygon[i], fit.polygon[(i + 1) % 4]);
                0.5 * (p.x * q.y - q.x * p.y)
            })
            .sum();
        assert!((area - 1.0).abs() < 1e-12, "{area}");
        assert!(
            fit.polygon
                .iter()
                .all(|p| p.z == 0.0 && (p.x.abs() - 0.5).abs() < 1e-12)
        );
        // Collinear points span no plane.
        let line: Vec<Point3> = (0..5)
            .map(|i| Point3::new(f64::from(i), 0.0, 0.0))
            .collect();
        assert!(fit_table(&line, &Point3::new(0.0, 0.0, 1.0), 0.01).is_err());
    }
}
