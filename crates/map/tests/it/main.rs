//! The map crate's integration tests, one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod fused_map;
mod fuzz;
mod lying_sizes;
mod material;
mod occupancy;
mod pipeline;
mod segment;
mod sld;
#[path = "../sld_support/mod.rs"]
mod sld_support;
mod traversal;
mod tsdf;
