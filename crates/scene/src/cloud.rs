//! Point clouds read from files or produced by sensors.

use geom::{Aabb, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// A set of points in metres, with optional per-point attributes. Attribute
/// vectors, when present, have one entry per point.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud {
    /// Positions.
    pub points: Vec<Point3>,
    /// Unit normals, when the source provides them.
    pub normals: Option<Vec<Vector3>>,
    /// Integer labels (segment, instance or class ids), when the source provides them.
    pub labels: Option<Vec<i64>>,
    /// Return intensity, when the source provides it.
    pub intensities: Option<Vec<f32>>,
}

impl PointCloud {
    /// A cloud of bare points.
    pub fn from_points(points: Vec<Point3>) -> Self {
        Self {
            points,
            ..Self::default()
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// `true` when there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Bounding box of the points.
    pub fn bounding_box(&self) -> Aabb {
        Aabb::from_points(&self.points)
    }
}
