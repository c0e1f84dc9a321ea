#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`rig`] | [`SimRig`]: the `hw` traits over a ground-truth world |
//! | [`explore_job`] | [`explore_job::SimExplore`]: a scenario's exploration on a [`SimRig`], judged by [`explore_job::ExploreJudge`]; [`explore_job::write_run`] stages its run folder with the blast plan |
//! | [`follow_job`] | [`follow_job::FollowSetup`]: a scenario's or a scene file's surface following on a [`SimRig`], judged by [`follow_job::FollowJudge`]; [`follow_job::FollowRun::write`] |
//! | [`scan_job`] | the `surveyor scan` job as library calls |
//! | [`metrics`] | [`metrics::coverage`], [`metrics::accuracy`], [`metrics::CoverageTracker`] against the ground truth |
//! | [`surface_score`] | [`surface_score::score_surface_model`]: a surface model against the true faces, edges and corners |
//! | [`scan_check`] | [`scan_check::ScanIndex`] (kd-tree over scan points), [`scan_check::scan_clearance`] (link capsules against a scan), [`scan_check::model_to_scan`] (model polygons against a scan) |
//! | [`oracle`] | [`oracle::OracleJob`], [`oracle::OraclePool`]: the coverage oracle, greedy sweeps chosen knowing the true scene |
//! | [`material_oracle`] | [`material_oracle::MaterialOracleJob`], [`material_oracle::MaterialPool`], [`material_oracle::compare`]: the material oracle, what Stage Two could identify knowing the true scene |
//! | [`truth`] | [`truth::ground_truth_grid`], [`truth::reachable_discs`]: the blast plan's oracle |

pub mod explore_job;
pub mod follow_job;
pub mod follow_reach;
pub mod material_oracle;
pub mod metrics;
pub mod oracle;
pub mod rig;
pub mod scan_check;
pub mod scan_job;
pub mod surface_score;
pub mod truth;

pub use rig::SimRig;

/// What can go wrong running a scenario.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A scenario file or field is invalid.
    #[error("scenario {source_name}: {message}")]
    Scenario {
        /// The file or scenario name.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// A scenario could not be read or built.
    #[error(transparent)]
    ScenarioFile(#[from] scenario::ScenarioError),
    /// The hardware (the simulated rig) refused or failed.
    #[error(transparent)]
    Hw(#[from] hw::HwError),
    /// A run-folder file could not be written or read.
    #[error(transparent)]
    Record(#[from] record::RecordError),
    /// Blast planning failed.
    #[error(transparent)]
    Blast(Box<blast::BlastError>),
    /// The robot model rejected something.
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// The scene could not be built or loaded.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// An argument of a library call is invalid.
    #[error("{what}: {message}")]
    InvalidArgument {
        /// The argument.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// A sensor configuration is invalid.
    #[error(transparent)]
    Sensor(#[from] sensor::SensorError),
    /// Planning (the C-space model, safety) failed.
    #[error(transparent)]
    Plan(Box<plan::PlanError>),
    /// Exploration failed.
    #[error(transparent)]
    Explore(Box<explore::ExploreError>),
    /// A map refused a value.
    #[error(transparent)]
    Map(Box<map::MapError>),
}

// Boxed: the planning and exploration errors are large, and `SimError` is
// returned on every path.
impl From<plan::PlanError> for SimError {
    fn from(e: plan::PlanError) -> Self {
        Self::Plan(Box::new(e))
    }
}

impl From<explore::ExploreError> for SimError {
    fn from(e: explore::ExploreError) -> Self {
        Self::Explore(Box::new(e))
    }
}

impl From<blast::BlastError> for SimError {
    fn from(e: blast::BlastError) -> Self {
        Self::Blast(Box::new(e))
    }
}

// A run's bag is a run-folder file.
impl From<record::bag::BagError> for SimError {
    fn from(e: record::bag::BagError) -> Self {
        Self::Record(e.into())
    }
}

impl From<map::MapError> for SimError {
    fn from(e: map::MapError) -> Self {
        Self::Map(Box::new(e))
    }
}
