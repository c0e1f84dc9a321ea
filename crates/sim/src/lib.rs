#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`rig`] | [`SimRig`]: the `hw` traits over a ground-truth world |
//! | [`explore_job`] | [`explore_job::SimExplore`]: a scenario's exploration on a [`SimRig`], judged by [`explore_job::ExploreJudge`]; [`scenario::job::explore::write_run`] stages its run folder with the blast plan |
//! | [`follow_job`] | [`follow_job::SimFollow`]: a scenario's or a scene file's surface following (the job of `scenario::job::follow`) on a [`SimRig`], judged by [`follow_job::FollowJudge`] and scored; [`follow_job::follow`] writes its run folder |
//! | [`scan_job`] | the `surveyor scan` job as library calls |
//! | [`metrics`] | [`metrics::coverage`], [`metrics::accuracy`], [`metrics::CoverageTracker`] against the ground truth |
//! | [`surface_score`] | [`surface_score::score_surface_model`]: a surface model against the true faces, edges and corners |
//! | [`scan_check`] | [`scan_check::ScanIndex`] (kd-tree over scan points), [`scan_check::scan_clearance`] (link capsules against a scan), [`scan_check::model_to_scan`] (model polygons against a scan) |
//! | [`oracle`] | [`oracle::OracleJob`], [`oracle::OraclePool`]: the coverage oracle, greedy sweeps chosen knowing the true scene |
//! | [`material_oracle`] | [`material_oracle::MaterialOracleJob`], [`material_oracle::MaterialPool`], [`material_oracle::compare`]: the material oracle, what Stage Two could identify knowing the true scene |
//! | [`truth`] | [`truth::ground_truth_grid`], [`truth::reachable_discs`]: the blast plan's oracle |

pub mod explore_job;
pub mod follow_job;
pub mod material_oracle;
pub mod metrics;
pub mod oracle;
pub mod rig;
pub mod scan_check;
pub mod scan_job;
pub mod surface_score;
pub mod truth;

pub use rig::SimRig;

/// What can go wrong running a scenario: the simulator's jobs fail as the
/// jobs of [`scenario::job`] do on any hardware.
pub type SimError = scenario::job::JobError;
