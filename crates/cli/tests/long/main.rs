//! The cli crate's long tests (run in release by `.ci/run`), one binary so a test build links few executables.

mod explore;
#[path = "../support/mod.rs"]
mod support;
