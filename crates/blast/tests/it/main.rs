//! The blast crate's integration tests, one binary (a module per topic) so a test build links few executables.

mod poses;
