//! `surveyor plan-blast` through the binary (issue 11): a broken tool file or
//! a folder without the run's files gets a clear message, not a panic. That
//! it plans exactly the blast plan explore wrote is checked in `explore.rs`
//! on the run its Stage Two test makes.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::support;

use support::fails_with;

#[test]
fn broken_tool_files_and_missing_run_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plan");
    let out = out.to_str().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let empty = empty.to_str().unwrap();
    // A folder that is not a run.
    fails_with(
        &["plan-blast", "--run", empty, "--out", out],
        &["scenario.toml", "blast_inputs.json", "surveyor explore"],
    );
    // Tool files: a wrong type, an unknown field, limits out of order, a
    // missing file.
    let tool = dir.path().join("tool.toml");
    let t = tool.to_str().unwrap();
    for (text, needles) in [
        (
            "phi_max_deg = \"wide\"\n",
            &["tool.toml", "phi_max_deg"][..],
        ),
        ("nozzle_length_m = 0.2\n", &["tool.toml", "nozzle_length_m"]),
        ("d_min_m = 0.6\n", &["tool.toml", "d_max_m"]),
        (
            "nozzle_radius_m = -0.01\n",
            &["tool.toml", "nozzle_radius_m"],
        ),
        (
            "aim_scale_m = 0.0\n",
            &["tool.toml", "aim_scale_m", "positive"],
        ),
        // As thick as the shortest stream: no pose could clear the surface.
        (
            "nozzle_radius_m = 1.0\n",
            &["tool.toml", "nozzle_radius_m", "less than tool.d_min_m"],
        ),
    ] {
        std::fs::write(&tool, text).unwrap();
        fails_with(
            &["plan-blast", "--run", empty, "--tool", t, "--out", out],
            needles,
        );
    }
    let missing = dir.path().join("no-such-tool.toml");
    fails_with(
        &[
            "plan-blast",
            "--run",
            empty,
            "--tool",
            missing.to_str().unwrap(),
            "--out",
            out,
        ],
        &["no-such-tool.toml", "cannot read"],
    );
}
