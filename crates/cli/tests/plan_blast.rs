//! `surveyor plan-blast` through the binary (issue 11): on a folder written
//! by `surveyor explore` it plans exactly the blast plan explore wrote, and
//! a broken tool file or a folder without the run's files gets a clear
//! message, not a panic.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

#[allow(dead_code)] // not every helper is used here
mod support;

use support::{fails, ok};

/// `args` must fail with a message holding every one of `needles`, and
/// without a panic.
fn fails_with(args: &[&str], needles: &[&str]) {
    let e = fails(args);
    assert!(!e.contains("panicked"), "{e}");
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
}

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

#[test]
#[ignore = "an exploration run: a minute in release; run by .ci/run"]
fn plan_blast_on_an_explore_run_gives_the_plan_explore_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let cache = dir.path().join("cspace.json");
    let r = run.to_str().unwrap();
    ok(&[
        "explore",
        "--scenario",
        "bridge1",
        "--stages",
        "one",
        "--no-timings",
        "--cspace-cache",
        cache.to_str().unwrap(),
        "--out",
        r,
    ]);
    let read = |p: std::path::PathBuf| std::fs::read_to_string(p).unwrap();
    let explored = read(run.join("blast_plan.json"));
    let plan: serde_json::Value = serde_json::from_str(&explored).unwrap();
    assert!(plan["discs_with_pose"].as_u64().unwrap() > 0);
    let out = dir.path().join("plan");
    let o = out.to_str().unwrap();
    let said = ok(&["plan-blast", "--run", r, "--out", o]);
    assert!(said.contains("blast plan"), "{said}");
    assert_eq!(read(out.join("blast_plan.json")), explored);
    assert_eq!(
        read(out.join("blast_plan.csv")),
        read(run.join("blast_plan.csv"))
    );
    // A tool file changes the limits the plan records; --seed is taken
    // (determinism per seed is checked on the library, sim's blast test).
    let tool = dir.path().join("tool.toml");
    std::fs::write(&tool, "phi_max_deg = 25.0\n").unwrap();
    let a = dir.path().join("a");
    ok(&[
        "plan-blast",
        "--run",
        r,
        "--tool",
        tool.to_str().unwrap(),
        "--seed",
        "5",
        "--out",
        a.to_str().unwrap(),
    ]);
    let v: serde_json::Value = serde_json::from_str(&read(a.join("blast_plan.json"))).unwrap();
    assert_eq!(v["tool"]["phi_max_deg"].as_f64(), Some(25.0));
    // A damaged inputs file is named, not a panic.
    std::fs::write(run.join("blast_inputs.json"), "{\"format\": 1").unwrap();
    fails_with(
        &["plan-blast", "--run", r, "--out", o],
        &["blast_inputs.json"],
    );
}
