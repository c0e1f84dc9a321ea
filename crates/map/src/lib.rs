#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`error`] | [`MapError`]: the one error type of every module |
//! | [`key`] | [`VoxelKey`], [`BlockKey`]: global integer keys |
//! | [`traverse`] | exact voxel walk of a segment ([`traverse::walk_segment`]) and its tie rule |
//! | [`regions`] | [`RegionsConfig`]: A1 ⊂ A2 ⊂ A3 (A§4.2.1) |
//! | [`sweep`] | [`range_jumps`]: occlusion segments between neighbouring returns of a [`sensor::Sweep`] (A§4.2.1) |
//! | [`occupancy`] | [`OccupancyGrid`]: tri-state grid, H1 (A eq. 4.8–4.11), H2 (eq. 4.13–4.14), prediction rays |
//! | [`tsdf`] | [`TsdfMap`]: sparse-block TSDF fusion, marching-cubes mesh (A§5.1.1) |
//! | [`marching_cubes`] | the consistent case table behind [`TsdfMap::extract_mesh`] |
//! | [`stats`] | [`OccupancyReport`]: `occupancy.json` |
//! | [`pipeline`] | [`Mapper`], [`build_from_scans`], [`MapConfig`]: `surveyor map` |
//! | [`sld`] | [`generate_discs`], [`SldConfig`], [`Disc`]: Scale-Like Discs (A§5.2) |
//! | [`sld_io`] | disc CSV files, [`sld_io::load_points`]: the clouds discs are made from |
//! | [`segment`] | [`segment_discs`], [`SegmentConfig`], [`SegmentId`]: map segmentation (A§5.3, Algorithm 1) |
//! | [`segment_io`] | `SEGMENTS.json` and `POSES.csv` files |
//! | [`material`] | [`MaterialBelief`], [`MaterialConfig`]: per-voxel material belief, H3 (A§4.4) |

pub mod error;
mod hash;
pub mod key;
pub mod marching_cubes;
pub mod material;
pub mod occupancy;
pub mod pipeline;
pub mod regions;
pub mod segment;
pub mod segment_io;
pub mod sld;
pub mod sld_io;
pub mod stats;
pub mod sweep;
pub mod traverse;
pub mod tsdf;

pub use error::{IoOp, MapError};
pub use key::{BlockKey, VoxelKey};
pub use material::{MaterialBelief, MaterialConfig};
pub use occupancy::{
    GridGeometry, IntegrationStats, NotFree, OcclusionConfig, OccupancyConfig, OccupancyGrid,
    RegionCounts, UnknownRun, VoxelState, h2_term,
};
pub use pipeline::{MapConfig, MapOutputs, Mapper, SweepSummary, build_from_scans};
pub use regions::{Region, RegionBox, RegionsConfig};
pub use segment::{SegmentConfig, SegmentId, segment_discs};
pub use sld::{Disc, DiscId, Orientation, SldConfig, SldResult, generate_discs};
pub use stats::{OccupancyReport, RegionReport};
pub use sweep::range_jumps;
pub use tsdf::{TsdfConfig, TsdfIntegrator, TsdfMap, TsdfStats, TsdfVoxel, TsdfWeighting};
