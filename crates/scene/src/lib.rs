#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`spec`] | [`SceneSpec`]: scenes as data (TOML), [`SceneSpec::build`] → [`World`] |
//! | [`builtin`] | the built-in scenes of SPEC §4 ([`builtin::scene`], [`builtin::NAMES`]) |
//! | [`world`] | [`Scene`]: triangles + materials + BVH; [`RayCast`], [`Hit`]; nearest point, capsule and triangle contacts |
//! | [`cloud_world`] | [`PointCloudWorld`]: a real scan as a world, Pudney's ε rule (P§4.2) |
//! | [`bvh`] | the binned-SAH bounding-volume hierarchy behind every query |
//! | [`wide`] | its four-wide collapse, with SIMD box tests, for triangle ray casting |
//! | [`primitives`] | (re-exported from `geom`) closed meshes of boxes, prisms, I-beams, cylinders |
//! | [`faces`] | [`faces::true_faces`]: a mesh scene's planar faces (coplanar triangles joined by their edges), [`faces::face_outline`] |
//! | [`sampling`] | uniform area samples of the true surfaces, for coverage metrics |
//! | [`io`] | OBJ / STL / PLY meshes, PLY / PCD / text clouds, PLY output |
//! | [`material`] | [`Material`], the default table, [`MaterialId`] |

pub mod builtin;
pub mod bvh;
pub mod cloud;
pub mod cloud_world;
pub mod error;
pub mod faces;
pub mod fixtures;
pub mod io;
pub mod material;
pub mod sampling;
pub mod spec;
pub mod wide;
pub mod world;

pub use cloud::PointCloud;
pub use cloud_world::PointCloudWorld;
pub use error::SceneError;
pub use geom::mesh::{self, TriMesh};
pub use geom::primitives;
pub use material::{Material, MaterialId, default_materials};
pub use sampling::{
    DEFAULT_MAX_SAMPLES, DEFAULT_SAMPLE_CHUNK, MAX_SAMPLES_CEILING, SamplingConfig, SurfaceSample,
    SurfaceSampler, sample_surfaces,
};
pub use spec::{
    CloudSpec, MAX_COORDINATE_M, MAX_PRIMITIVE_SEGMENTS, ObjectSpec, PoseSpec, SceneSpec,
    ShapeSpec, World,
};
pub use world::{FaceId, Hit, ObjectId, RayCast, Scene, SceneObject};
