//! The robot crate's integration tests, one binary (a module per topic) so a test build links few executables.

#[path = "../common/mod.rs"]
mod common;
mod errors;
mod fk;
mod fuzz;
mod jacobian;
mod nullspace;
mod shapes;
