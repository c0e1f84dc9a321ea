//! Planning for AXBAM exploration (SPEC §3.7; Paul §3.2.1.3–3.2.1.4, §3.2.3,
//! §4.3): the manipulator's configuration-space model and safe motion.
//!
//! - [`Roadmap`]: `n_Q` nodes sampled within the joint limits, joined in the
//!   joint-weighted distance; A* between poses, each motion checked lazily
//!   against the map of the moment; node usage likelihoods `L(cᵢ)`.
//! - [`Safety`]: `dist(Q)` of eq. 3.5 against occupied **and unknown** voxels;
//!   a pose is usable only when `dist(Q) > 1`.
//! - [`CspaceModel`]: roadmap + `L(cᵢ)` + voxel interference `P(ʲx_c)` (eq.
//!   4.13), built once and cached to a file.
//! - [`contact`]: the robot's link shapes against a triangle scene: contacts
//!   at a configuration and along a joint-space motion, clearance.
//! - [`PoseSelector`]: Stage Two (A§3.3): a pose from which the scanner's
//!   centre ray meets a disc [`Target`] within the LRC's constraints, by
//!   Levenberg–Marquardt on the sigmoid costs `g₁…g₆` (eq. 3.14–3.20).
//!
//! ```
//! use geom::Isometry3;
//! use map::{OccupancyConfig, OccupancyGrid, RegionsConfig, VoxelState};
//! use plan::{CspaceModel, PlanConfig};
//!
//! let robot = robot::builtin("denso-vm6083")?;
//! let config = PlanConfig { n_q: 60, ..PlanConfig::default() };
//! let model = CspaceModel::build(&robot, &Isometry3::identity(), 0.1, &config)?;
//! assert_eq!(model.roadmap().len(), 60);
//! assert_eq!(model.roadmap().components(), 1);
//!
//! // An unexplored grid: every pose is unsafe (its links reach unknown space).
//! let mut grid = OccupancyGrid::new(OccupancyConfig {
//!     voxel_m: 0.1,
//!     regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.3, 1.5]),
//!     ..OccupancyConfig::default()
//! })?;
//! model.apply_to(&mut grid)?;
//! assert!(grid.h2() > 0.0);
//! let q0 = model.roadmap().node(0).to_vec();
//! assert!(model.safety().dist(&grid, &q0)? < 1.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod config;
pub mod contact;
mod error;
pub mod interference;
mod model;
pub mod pose;
pub mod roadmap;
pub mod safety;

pub use config::PlanConfig;
pub use error::PlanError;
pub use interference::{Interference, interfering_voxels};
pub use model::{CacheOutcome, CspaceModel, MAX_INTERFERENCE_PAIRS};
pub use pose::{
    Constraints, PlaneHit, PoseConfig, PoseEvaluation, PoseRun, PoseSelector, PoseSolution,
    PoseTermination, Target, ViewGeometry, view_geometry,
};
pub use roadmap::{
    Edge, MemoChecker, MotionChecker, Path, Roadmap, RoadmapParts, weighted_distance,
};
pub use safety::{Safety, SafetyChecker};
