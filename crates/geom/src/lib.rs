#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`math`] | [`Real`], [`Point3`], [`Vector3`], [`UnitVector3`], [`Isometry3`], [`unit()`] |
//! | [`aabb`] | [`Aabb`]: boxes, slab ray test, overlap |
//! | [`ray`] | [`Ray`]: origin + unit direction |
//! | [`plane`] | [`Plane`]: signed distance, projection, line intersection, two-plane line |
//! | [`mod@line`] | [`Line3`], [`Segment3`]: closest points between lines and segments |
//! | [`polygon2`] | signed area, simplicity, containment, sight tests, 2-D segment queries, the overlap of two polygons |
//! | [`polygon3`] | [`PlaneFrame`]: 2-D coordinates on a plane, planar polygons in 3-D |
//! | [`moments`] | [`Moments`]: moment sums (P§2.2) and [`Pca`] by symmetric eigen-decomposition |
//! | [`triangle`] | [`Triangle`]: ray hit, closest point, segment/triangle distance, intersection |
//! | [`ellipsoid`] | [`Ellipsoid`]: algebraic distance of Paul eq. 3.5 |
//! | [`capsule`] | [`Capsule`]: distances to points, segments, capsules and triangles |
//! | [`mesh`] | [`TriMesh`]: the workspace's one indexed triangle mesh |
//! | [`primitives`] | closed meshes of boxes, prisms, I-beams, cylinders |
//!
//! Queries are named `[operation]_[shape]_[shape]` where two shapes are involved,
//! e.g. [`line::distance_segment_segment`].

pub mod aabb;
pub mod capsule;
pub mod ellipsoid;
pub mod exact;
pub mod line;
pub mod math;
pub mod mesh;
pub mod moments;
pub mod plane;
pub mod polygon2;
pub mod polygon3;
pub mod primitives;
pub mod ray;
pub mod triangle;

pub use aabb::Aabb;
pub use capsule::Capsule;
pub use ellipsoid::Ellipsoid;
pub use line::{Line3, Segment3};
pub use math::{
    Isometry3, Matrix3, Matrix4, Point2, Point3, Real, Rotation3, Translation3, UnitQuaternion,
    UnitVector3, Vector2, Vector3, unit,
};
pub use mesh::{MeshError, TriMesh};
pub use moments::{Moments, Pca};
pub use plane::Plane;
pub use polygon3::PlaneFrame;
pub use ray::Ray;
pub use triangle::Triangle;

/// Largest accepted magnitude of a coordinate or translation read from a
/// user's file, metres (10 000 km, more than UTM northings). Beyond it,
/// squared distances lose the precision surveyor's tolerances need, and
/// `1e308` would overflow to infinity in the first squared norm.
pub const MAX_COORDINATE_M: Real = 1e7;

/// A structure's invariant that does not hold, as found by its
/// `check_invariants` (the BVH, the occupancy grid, the TSDF, ...).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{structure}: invariant violated: {detail}")]
pub struct InvariantViolation {
    /// The structure checked.
    pub structure: &'static str,
    /// What does not hold, with the index of the element at fault.
    pub detail: String,
}

impl InvariantViolation {
    /// A violation of `structure`'s invariants.
    pub fn new(structure: &'static str, detail: impl Into<String>) -> Self {
        Self {
            structure,
            detail: detail.into(),
        }
    }
}
