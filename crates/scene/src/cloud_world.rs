//! A world made of a point set (a real scan) instead of surfaces.
//!
//! Pudney evaluated his single-point range finders on range images (P§4.2): "For
//! each sensing axis, the range image points within a small distance ε of the
//! axis are determined. Of these, the range image point nearest the sensor end of
//! the sensing axis becomes a sensor point", with
//! `ε = max_i min_{j≠i} ‖r_i − r_j‖`, the largest nearest-neighbour distance.

use crate::bvh::{Aabb32, Bvh, RayF32};
use crate::cloud::PointCloud;
use crate::error::SceneError;
use crate::material::MaterialId;
use crate::world::{Hit, RayCast};
use geom::{Point3, Ray, Real, unit};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZero;

/// A point-cloud world answering ray queries by Pudney's ε rule.
#[derive(Clone, Debug)]
pub struct PointCloudWorld {
    cloud: PointCloud,
    epsilon: Real,
    material: Option<MaterialId>,
    bvh: Bvh,
    /// Points in BVH slot order, single precision.
    slots: Vec<[f32; 3]>,
}

/// Pudney's ε: the largest distance from a point to its nearest neighbour.
/// `None` for fewer than two distinct points.
pub fn max_nearest_neighbour_distance(points: &[Point3]) -> Option<Real> {
    if points.len() < 2 {
        return None;
    }
    let arr: Vec<[Real; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: ImmutableKdTree<Real, 3> = ImmutableKdTree::new_from_slice(&arr);
    let two = NonZero::new(2)?;
    let d2 = arr
        .par_iter()
        .map(|q| {
            tree.nearest_n::<SquaredEuclidean>(q, two)
                .iter()
                .map(|n| n.distance)
                .fold(0.0, Real::max)
        })
        .reduce(|| 0.0, Real::max);
    Some(d2.sqrt())
}

impl PointCloudWorld {
    /// A world from a cloud; `epsilon` defaults to Pudney's rule. Every point
    /// must be finite; at least one point is required.
    pub fn new(
        cloud: PointCloud,
        epsilon: Option<Real>,
        material: Option<MaterialId>,
    ) -> Result<Self, SceneError> {
        if cloud.is_empty() {
            return Err(SceneError::invalid("point cloud", "has no points"));
        }
        if let Some(i) = cloud
            .points
            .iter()
            .position(|p| !geom::math::is_finite_point(p))
        {
            return Err(SceneError::invalid(
                "point cloud",
                format!("point {i} has a non-finite coordinate"),
            ));
        }
        let epsilon = match epsilon {
            Some(e) if e.is_finite() && e > 0.0 => e,
            Some(e) => {
                return Err(SceneError::invalid(
                    "epsilon",
                    format!("expected a positive distance, got {e}"),
                ));
            }
            None => max_nearest_neighbour_distance(&cloud.points)
                .filter(|e| *e > 0.0)
                .ok_or_else(|| {
                    SceneError::invalid(
                        "point cloud",
                        "ε cannot be derived: fewer than two distinct points (give epsilon)",
                    )
                })?,
        };
        let e = epsilon as f32;
        let (bounds, centroids): (Vec<Aabb32>, Vec<[f32; 3]>) = cloud
            .points
            .iter()
            .map(|p| {
                let c = [p.x as f32, p.y as f32, p.z as f32];
                let b = Aabb32 {
                    min: [c[0] - e, c[1] - e, c[2] - e],
                    max: [c[0] + e, c[1] + e, c[2] + e],
                };
                (b, c)
            })
            .unzip();
        let bvh = Bvh::build(&bounds, &centroids);
        let slots = bvh
            .prim_indices
            .iter()
            .map(|&i| centroids[i as usize])
            .collect();
        Ok(Self {
            cloud,
            epsilon,
            material,
            bvh,
            slots,
        })
    }

    /// The ε in use.
    pub fn epsilon(&self) -> Real {
        self.epsilon
    }

    /// The cloud.
    pub fn cloud(&self) -> &PointCloud {
        &self.cloud
    }
}

impl RayCast for PointCloudWorld {
    fn cast_ray(&self, ray: &Ray, max_range_m: Real) -> Option<Hit> {
        let r = RayF32::from_ray(ray);
        let e2 = (self.epsilon * self.epsilon) as f32;
        let (slot, _) = self.bvh.closest_hit(&r, max_range_m as f32, |slot, best| {
            let p = &self.slots[slot as usize];
            let v = [p[0] - r.origin[0], p[1] - r.origin[1], p[2] - r.origin[2]];
            let t = v[0] * r.dir[0] + v[1] * r.dir[1] + v[2] * r.dir[2];
            if t <= 0.0 || t >= best {
                return None;
            }
            let perp2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - t * t;
            (perp2 <= e2).then_some(t)
        })?;
        let index = self.bvh.prim_indices[slot as usize];
        let point = self.cloud.points[index as usize];
        let distance = ray.project_param(&point);
        if distance > max_range_m || distance <= 0.0 {
            return None;
        }
        let normal = self
            .cloud
            .normals
            .as_ref()
            .and_then(|n| unit(n[index as usize]))
            .map_or(-ray.dir, |n| if n.dot(&ray.dir) > 0.0 { -n } else { n });
        Some(Hit {
            distance,
            point,
            normal,
            material: self.material,
            object: None,
            element: index,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::{UnitVector3, Vector3};

    fn grid(step: f64) -> Vec<Point3> {
        let mut v = Vec::new();
        for i in -20..=20 {
            for j in -20..=20 {
                v.push(Point3::new(f64::from(i) * step, f64::from(j) * step, 1.0));
            }
        }
        v
    }

    #[test]
    fn epsilon_is_grid_spacing() {
        let e = max_nearest_neighbour_distance(&grid(0.01)).unwrap();
        assert!((e - 0.01).abs() < 1e-12);
    }

    #[test]
    fn ray_returns_the_nearest_point_within_epsilon() {
        let mut pts = grid(0.01);
        // A second layer farther away must be hidden behind the first.
        pts.extend(grid(0.01).iter().map(|p| p + Vector3::new(0.0, 0.0, 0.5)));
        let w = PointCloudWorld::new(PointCloud::from_points(pts), None, None).unwrap();
        let ray = Ray::new(Point3::new(0.003, 0.002, 0.0), Vector3::z_axis());
        let hit = w.cast_ray(&ray, 5.0).unwrap();
        assert!((hit.point.z - 1.0).abs() < 1e-12);
        assert!(ray.line_distance_squared(&hit.point).sqrt() <= w.epsilon() + 1e-9);
        // Out of range, and pointing away.
        assert!(w.cast_ray(&ray, 0.5).is_none());
        let away = Ray::new(ray.origin, UnitVector3::new_normalize(-Vector3::z()));
        assert!(w.cast_ray(&away, 5.0).is_none());
        // Outside the cloud's extent.
        let off = Ray::new(Point3::new(1.0, 0.0, 0.0), Vector3::z_axis());
        assert!(w.cast_ray(&off, 5.0).is_none());
    }

    #[test]
    fn rejects_bad_clouds() {
        assert!(PointCloudWorld::new(PointCloud::default(), None, None).is_err());
        let nan = PointCloud::from_points(vec![Point3::new(f64::NAN, 0.0, 0.0)]);
        let err = PointCloudWorld::new(nan, Some(0.1), None).unwrap_err();
        assert!(err.to_string().contains("point 0"));
        let one = PointCloud::from_points(vec![Point3::origin()]);
        assert!(PointCloudWorld::new(one, None, None).is_err());
    }
}
