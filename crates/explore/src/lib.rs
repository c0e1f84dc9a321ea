//! AXBAM two-stage exploration (SPEC §3.8; Paul ch. 3, 4, 6).
//!
//! Stage One ([`StageOne`], A§3.2): every sampled C-space node is a contending
//! viewpoint; its tilt sweep's information is predicted by casting rays
//! through the planning grid, and the objectives f1 (geometric information
//! remaining, eq. 4.11), f2 (C-space information remaining, eq. 4.14), f3
//! (joint travel, eq. 3.3) and f4 (`dist(Q)`, eq. 3.5) choose the next
//! viewpoint on the Pareto front (eq. 3.8); A* through the roadmap reaches it
//! through known free space; Stage One stops by the 1 % rule (A§3.2.4).
//! Stage Two (A§3.3) aims the scanner at the discs whose material is least
//! certain and identifies them with the LRC.
//!
//! [`run()`] is the episode over any hardware that implements the `hw`
//! traits, from a [`Setup`], judged by a [`Judge`] when there is a ground
//! truth; [`ExploreRun::write`] stages its run folder.
//!
//! | module | entry points |
//! |---|---|
//! | [`setup`] | [`Setup`], [`SetupInputs`]: the robot, parameters, regions, materials, the C-space model |
//! | [`run`](mod@run) | [`run()`], [`RunOptions`], [`ExploreRun`]: both stages, the checkpoint, the map products |
//! | [`judge`] | [`Judge`], [`NoJudge`], [`SafetyTally`] |
//! | [`stage_one`] | [`StageOne`]: the decision of A§3.2 |
//! | [`pareto`] | the Pareto front and rank sum (eq. 3.7–3.8) |
//! | [`discs`] | [`DiscMap`]: discs, segments, material belief |

mod config;
pub mod discs;
mod error;
pub mod judge;
mod materials;
mod output;
pub mod pareto;
mod probe;
pub mod run;
pub mod setup;
pub mod stage_one;

pub use config::{ExploreConfig, MappingConfig, PredictionConfig};
pub use discs::DiscMap;
pub use error::ExploreError;
pub use judge::{Judge, NoJudge, SafetyTally};
pub use run::{ExploreRun, RunIdentity, RunOptions, run};
pub use setup::{Setup, SetupInputs};
pub use stage_one::{Candidate, Choice, Decision, StageOne, Termination};
