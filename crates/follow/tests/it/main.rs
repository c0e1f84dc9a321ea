//! The follow crate's integration tests, one binary (a module per topic) so a test build links few executables.

mod follow_scenes;
#[path = "../support/mod.rs"]
mod support;
