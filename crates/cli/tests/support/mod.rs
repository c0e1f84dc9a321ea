//! Helpers shared by the binary's integration tests (`mod support;` in each):
//! run the built `surveyor`, expect success or failure, find `data/` files.
#![allow(dead_code, reason = "each test file uses some of these helpers")]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Run the built binary with `args`.
pub fn surveyor(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_surveyor"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// Run `args`, which must succeed; its stdout.
pub fn ok(args: &[&str]) -> String {
    let out = surveyor(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Run `args`, which must fail; its stderr.
pub fn fails(args: &[&str]) -> String {
    let out = surveyor(args);
    assert!(!out.status.success(), "{args:?} should fail");
    String::from_utf8(out.stderr).unwrap()
}

/// `args` must fail with a message holding every one of `needles`, and
/// without a panic.
pub fn fails_with(args: &[&str], needles: &[&str]) {
    let e = fails(args);
    assert!(!e.contains("panicked"), "{e}");
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
}

/// The path of `rel` below the repository's `data/` folder.
pub fn data(rel: &str) -> String {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/"))
        .join(rel)
        .display()
        .to_string()
}
