//! The scene crate's integration tests, one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod bounds;
mod builtin_scenes;
mod convention;
mod fuzz;
mod io_bad_input;
#[path = "../io_fixtures/mod.rs"]
mod io_fixtures;
mod io_lying_sizes;
mod io_rays;
mod io_real_files;
mod io_roundtrip;
mod queries;
