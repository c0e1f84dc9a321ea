//! Bad input through the binary (issue "solid ground", §2): a clear error that
//! names the flag, file or joint, and no file left behind.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

mod support;

use std::path::{Path, PathBuf};
use support::{data, fails, ok};

/// Every entry below `dir`, recursively.
fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            out.push(e.path());
            out.extend(listing(&e.path()));
        }
    }
    out.sort();
    out
}

/// User messages carry no Rust debug output or library paths.
fn clean(msg: &str) {
    for bad in ["Some(", "None", "::", "{ ", "panicked", "RUST_BACKTRACE"] {
        assert!(!msg.contains(bad), "`{bad}` in: {msg}");
    }
}

#[test]
fn scan_flags_that_would_be_ignored_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.ply");
    let o = out.to_str().unwrap();
    for extra in [
        ["--base-xyz", "1,2,3"],
        ["--robot", "arm4"],
        ["--base-rpy-deg", "0,0,90"],
        ["--tip", "tool0"],
    ] {
        let mut args = vec!["scan", "--scenario", "bridge1", "--out", o];
        args.extend(extra);
        let e = fails(&args);
        assert!(e.contains("cannot be used with"), "{e}");
        assert!(e.contains(extra[0]), "{e}");
    }
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn non_finite_base_poses_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.ply");
    for (flag, value) in [
        ("--base-xyz", "nan,0,0"),
        ("--base-xyz", "0,inf,0"),
        ("--base-xyz", "0,0,1e308"),
        ("--base-rpy-deg", "0,-inf,0"),
    ] {
        let e = fails(&[
            "scan",
            "--scene",
            &data("meshes/cinder_block_meters.obj"),
            flag,
            value,
            "--joints",
            "0,0,0,0,0,0",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(e.contains(flag) && e.contains("finite"), "{e}");
        clean(&e);
    }
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn negative_values_parse_and_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let e = fails(&[
        "scan",
        "--scenario",
        "bridge1",
        "--tilt-deg",
        "-10",
        "--out",
        dir.path().join("s.ply").to_str().unwrap(),
    ]);
    assert!(e.contains("tilt_deg") && e.contains("-10"), "{e}");
    clean(&e);
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn surface_following_scenarios_explain_themselves() {
    for name in ["cube", "block1", "block2", "cylinder"] {
        let e = fails(&["scan", "--scenario", name, "--out", "/tmp/never.ply"]);
        assert!(
            e.contains("surface-following") && e.contains("follow") && e.contains(name),
            "{e}"
        );
    }
}

#[test]
fn joint_limit_errors_name_the_joint_value_and_limits() {
    let dir = tempfile::tempdir().unwrap();
    let e = fails(&[
        "scan",
        "--scenario",
        "bridge1",
        "--deg",
        "--joints",
        "0,-55,170,0,-110,0",
        "--out",
        dir.path().join("s.ply").to_str().unwrap(),
    ]);
    // VM-6083 joint 3: −80° … 165°.
    assert!(e.contains("170.0000°") && e.contains("165.0000°"), "{e}");
    assert!(e.contains("q[2]"), "{e}");
    clean(&e);
    assert!(listing(dir.path()).is_empty());

    // fk --json reports the joints outside their limits.
    let json = ok(&[
        "fk",
        "--robot",
        "denso-vm6083",
        "--deg",
        "--joints",
        "0,-55,170,0,-110,0",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let outside = v["outside_limits"].as_array().unwrap();
    assert_eq!(outside.len(), 1);
    assert_eq!(outside[0]["index"], 2);
    assert!((outside[0]["value"].as_f64().unwrap() - 170f64.to_radians()).abs() < 1e-12);
    let within = ok(&[
        "fk",
        "--robot",
        "denso-vm6083",
        "--deg",
        "--joints",
        "0,-55,165,0,-110,0",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&within).unwrap();
    assert!(v["outside_limits"].as_array().unwrap().is_empty());
}

#[test]
fn scan_with_a_urdf_robot_takes_a_tip_and_creates_the_out_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("new/sub/s.ply");
    let stdout = ok(&[
        "scan",
        "--scene",
        &data("meshes/cinder_block_meters.obj"),
        "--robot",
        &data("robots/ur5/ur5_robot.urdf"),
        "--tip",
        "tool0",
        "--joints",
        "0,-1.2,1.2,0,1.5,0",
        "--tilt-deg",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(stdout.contains("points"), "{stdout}");
    assert!(out.exists());
    // A tip on a built-in robot is refused.
    let e = fails(&[
        "scan",
        "--scene",
        &data("meshes/cinder_block_meters.obj"),
        "--robot",
        "denso-vm6083",
        "--tip",
        "tool0",
        "--joints",
        "0,0,0,0,0,0",
        "--out",
        dir.path().join("t.ply").to_str().unwrap(),
    ]);
    assert!(e.contains("URDF robots only"), "{e}");
}

#[test]
fn raycast_bounds_and_no_partial_output() {
    let dir = tempfile::tempdir().unwrap();
    let fx = dir.path().join("fx");
    let e = fails(&[
        "raycast-fixture",
        "--out",
        fx.to_str().unwrap(),
        "--rays",
        "100000000000",
    ]);
    assert!(e.contains("--rays") && e.contains("at most"), "{e}");
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    ok(&[
        "raycast-fixture",
        "--out",
        fx.to_str().unwrap(),
        "--rays",
        "100",
    ]);
    let e = fails(&[
        "raycast",
        "--scene",
        fx.join("structure.ply").to_str().unwrap(),
        "--rays",
        fx.join("rays.bin").to_str().unwrap(),
        "--out",
        dir.path().join("d.bin").to_str().unwrap(),
        "--threads",
        "100000",
    ]);
    assert!(e.contains("--threads") && e.contains("256"), "{e}");
    assert!(!dir.path().join("d.bin").exists());
}

#[test]
fn failed_commands_leave_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    // map: the second scan is broken, so no map folder appears.
    std::fs::write(
        p("bad.ply"),
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
    )
    .unwrap();
    let sweep = sensor::Sweep::from_points(vec![sensor::SweepPoint {
        point: geom::Point3::new(0.3, 0.0, 1.5),
        origin: geom::Point3::new(0.3, 0.0, 0.5),
        intensity: 1.0,
        material: None,
        cell: None,
    }])
    .unwrap();
    sweep.write_ply(Path::new(&p("good.ply"))).unwrap();
    let e = fails(&[
        "map",
        "--scans",
        &p("good.ply"),
        &p("bad.ply"),
        "--out",
        &p("maps"),
    ]);
    assert!(e.contains("bad.ply"), "{e}");
    assert!(!dir.path().join("maps").exists());
    // model: a malformed line, so no model folder appears.
    std::fs::write(
        p("sets.jsonl"),
        "{\"points\": [[0,0,0]], \"axes\": [[0,0,1]]}\n{\"points\": [[0,0,\"x\"]]}\n",
    )
    .unwrap();
    let e = fails(&["model", "--sets", &p("sets.jsonl"), "--out", &p("model")]);
    assert!(e.contains("sets.jsonl") && e.contains(":2"), "{e}");
    assert!(!dir.path().join("model").exists());
    // sld on a missing file: one clear OS error, not two.
    let e = fails(&["sld", "--input", &p("missing.ply"), "--out", &p("d.csv")]);
    assert!(e.contains("missing.ply"), "{e}");
    let os = "No such file or directory";
    assert_eq!(e.matches(os).count(), 1, "{e}");
    let mut left = listing(dir.path());
    left.retain(|f| {
        !f.ends_with("bad.ply") && !f.ends_with("good.ply") && !f.ends_with("sets.jsonl")
    });
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn stage_configs_come_from_the_library_and_toml_files() {
    let dir = tempfile::tempdir().unwrap();
    // The printed defaults are the library's.
    for (cmd, expect) in [
        (
            "sld",
            toml::to_string(&map::sld::SldConfig::default()).unwrap(),
        ),
        (
            "segment",
            toml::to_string(&map::segment::SegmentConfig::default()).unwrap(),
        ),
        (
            "model",
            toml::to_string(&surface::SurfaceConfig::default()).unwrap(),
        ),
        ("map", toml::to_string(&map::MapConfig::default()).unwrap()),
    ] {
        assert_eq!(ok(&[cmd, "--print-config"]), expect, "{cmd}");
    }
    // A file sets the whole config, a flag overrides one field.
    let cfg = dir.path().join("sld.toml");
    std::fs::write(&cfg, "radius_m = 0.08\nmin_points = 12\n").unwrap();
    let printed = ok(&[
        "sld",
        "--config",
        cfg.to_str().unwrap(),
        "--min-points",
        "20",
        "--print-config",
    ]);
    let back: map::sld::SldConfig = toml::from_str(&printed).unwrap();
    assert_eq!(back.radius_m, 0.08);
    assert_eq!(back.min_points, 20);
    // Unknown fields name the file and the field.
    std::fs::write(&cfg, "radius = 0.08\n").unwrap();
    let e = fails(&["sld", "--config", cfg.to_str().unwrap(), "--print-config"]);
    assert!(e.contains("sld.toml") && e.contains("radius"), "{e}");
    // Out-of-range values are refused before any work.
    let e = fails(&[
        "model",
        "--lambda",
        "-1",
        "--sets",
        "x.jsonl",
        "--out",
        dir.path().join("m").to_str().unwrap(),
    ]);
    assert!(e.contains("lambda"), "{e}");
}
