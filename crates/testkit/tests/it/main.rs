//! The testkit crate's integration tests, one binary (a module per topic) so a test build links few executables.

mod mutator;
