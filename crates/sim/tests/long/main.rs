//! The sim crate's long tests (run in release by `.ci/run`), one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod explore_oracle;
mod explore_stage_one;
mod follow_complete;
mod material_oracle;
mod shared;
