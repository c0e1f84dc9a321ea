//! AXBAM two-stage exploration (SPEC §3.8; Paul ch. 3, 4, 6).
//!
//! Stage One ([`StageOne`], A§3.2): every sampled C-space node is a contending
//! viewpoint; its tilt sweep's information is predicted by casting rays
//! through the planning grid, and the objectives f1 (geometric information
//! remaining, eq. 4.11), f2 (C-space information remaining, eq. 4.14), f3
//! (joint travel, eq. 3.3) and f4 (`dist(Q)`, eq. 3.5) choose the next
//! viewpoint on the Pareto front (eq. 3.8); A* through the roadmap reaches it
//! through known free space; Stage One stops by the 1 % rule (A§3.2.4).
//!
//! The loop that moves an arm, sweeps and integrates lives in `sim`, behind
//! its hardware traits; this crate decides.

mod config;
mod error;
pub mod pareto;
pub mod stage_one;

pub use config::{ExploreConfig, MappingConfig, PredictionConfig};
pub use error::ExploreError;
pub use stage_one::{Candidate, Choice, Decision, StageOne, Termination};
