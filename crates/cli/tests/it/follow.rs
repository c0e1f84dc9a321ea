//! `surveyor follow` through the binary: the output files and their columns,
//! byte-identical reruns with --no-timings, Ctrl-C, scene files, and bad input
//! (a clear message naming the flag, nothing written). The follower does not
//! complete surfaces yet: runs are bounded by --max-sets and completion is not
//! asserted.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::support;

use std::fmt::Write as _;
use std::path::Path;
use support::{data, fails, ok};

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn json(dir: &Path, name: &str) -> serde_json::Value {
    serde_json::from_str(&read(dir, name)).unwrap()
}

/// Rows of steps.csv as fields, after checking the header.
fn rows(dir: &Path, dof: usize) -> Vec<Vec<String>> {
    let csv = read(dir, "steps.csv");
    let mut lines = csv.lines();
    let mut header = vec!["step", "mode", "x", "y", "z"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    header.extend((1..=dof).map(|i| format!("q{i}")));
    header.extend(
        [
            "set_size",
            "update_us",
            "direction_us",
            "kinematics_us",
            "link_clearance_m",
            "current_segment",
            "current_edge",
            "robot_time_s",
        ]
        .map(String::from),
    );
    assert_eq!(lines.next().unwrap(), header.join(","));
    lines
        .map(|l| {
            let f: Vec<String> = l.split(',').map(String::from).collect();
            assert_eq!(f.len(), header.len(), "{l}");
            f
        })
        .collect()
}

#[test]
fn a_short_cube_run_writes_every_file_with_its_columns() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = out.to_str().unwrap();
    let said = ok(&[
        "follow",
        "--scenario",
        "cube",
        "--max-sets",
        "50",
        "--out",
        o,
    ]);
    assert!(said.contains("50 sets, termination max_sets"), "{said}");
    assert!(said.contains("0 collisions"), "{said}");
    let r = json(&out, "run.json");
    for key in [
        "sets",
        "steps",
        "completed",
        "termination",
        "collisions",
        "min_clearance_m",
        "modes",
        "score",
        "scenario",
        "seed",
        "robot",
        "options",
    ] {
        assert!(!r[key].is_null(), "run.json lacks {key}: {r}");
    }
    assert_eq!(r["sets"], 50);
    assert_eq!(r["steps"], 50);
    assert_eq!(r["termination"], "max_sets");
    assert_eq!(r["scenario"], "cube");
    assert_eq!(r["robot"], "point3");
    for k in ["mean", "median", "p95"] {
        assert!(r["step_us"][k].as_f64().unwrap() > 0.0);
    }
    let rows = rows(&out, 3);
    assert_eq!(rows.len(), 50);
    let modes = r["modes"].as_object().unwrap();
    for row in &rows {
        assert!(modes.contains_key(&row[1]), "{row:?}");
        // point3's joints are its control point.
        assert_eq!(row[2..5], row[5..8]);
        assert!(row[9].parse::<f64>().unwrap() >= 0.0);
    }
    assert_eq!(modes.values().map(|v| v.as_u64().unwrap()).sum::<u64>(), 50);
    // The start: 0.1 m above the top face's centre.
    assert_eq!(rows[0][2..5], ["0", "0", "1.1"]);
    let ply = read(&out, "path.ply");
    assert!(ply.starts_with("ply\nformat ascii 1.0\n"));
    let count = |what: &str| -> usize {
        ply.lines()
            .find_map(|l| l.strip_prefix(what))
            .unwrap()
            .parse()
            .unwrap()
    };
    let (v, e) = (count("element vertex "), count("element edge "));
    assert!(v == 50 || v == 51, "{v}");
    assert_eq!(e, v - 1);
    let body: Vec<&str> = ply.split("end_header\n").nth(1).unwrap().lines().collect();
    assert_eq!(body.len(), v + e);
    assert_eq!(body[0], "0 0 1.1");
    assert!(read(&out, "surface_model.obj").starts_with("# surveyor surface model"));
    let model = json(&out, "surface_model.json");
    assert!(!model["segments"].as_array().unwrap().is_empty());
}

#[test]
fn no_timings_reruns_are_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str| {
        let out = dir.path().join(name);
        ok(&[
            "follow",
            "--scenario",
            "cube",
            "--max-sets",
            "60",
            "--noise-m",
            "0.002",
            "--seed",
            "3",
            "--no-timings",
            "--out",
            out.to_str().unwrap(),
        ]);
        out
    };
    let (a, b) = (run("a"), run("b"));
    for name in ["steps.csv", "surface_model.json", "run.json"] {
        assert_eq!(read(&a, name), read(&b, name), "{name}");
    }
    for row in rows(&a, 3) {
        assert_eq!(row[9..12], ["", "", ""], "{row:?}");
    }
}

#[test]
fn arm4_follows_block1_from_its_base_at_minus_1_6() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("arm");
    let o = out.to_str().unwrap();
    ok(&[
        "follow",
        "--scenario",
        "block1",
        "--robot",
        "arm4",
        "--max-sets",
        "20",
        "--out",
        o,
    ]);
    let rows = rows(&out, 6);
    assert_eq!(rows.len(), 20);
    // δ above the centre of block1's upper top face (x ∈ [−0.6, 0], z = 0.8).
    let p: Vec<f64> = rows[0][2..5].iter().map(|s| s.parse().unwrap()).collect();
    assert!((p[0] + 0.3).abs() < 1e-3 && p[1].abs() < 1e-3 && (p[2] - 0.9).abs() < 1e-3);
    assert_eq!(json(&out, "run.json")["robot"], "arm4");
}

#[test]
fn a_scene_file_starts_above_its_bounding_box_with_a_table_under_it() {
    let dir = tempfile::tempdir().unwrap();
    // A 0.4 × 0.4 × 0.3 box standing on z = 0.2, as OBJ (faces outward).
    let (x0, x1, y0, y1, z0, z1) = (0.1, 0.5, -0.2, 0.2, 0.2, 0.5);
    let mut obj = String::new();
    for &(x, y, z) in &[
        (x0, y0, z0),
        (x1, y0, z0),
        (x1, y1, z0),
        (x0, y1, z0),
        (x0, y0, z1),
        (x1, y0, z1),
        (x1, y1, z1),
        (x0, y1, z1),
    ] {
        writeln!(obj, "v {x} {y} {z}").unwrap();
    }
    for f in [
        [1, 3, 2],
        [1, 4, 3],
        [5, 6, 7],
        [5, 7, 8],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 4, 8],
        [3, 8, 7],
        [4, 1, 5],
        [4, 5, 8],
    ] {
        writeln!(obj, "f {} {} {}", f[0], f[1], f[2]).unwrap();
    }
    let scene = dir.path().join("box.obj");
    std::fs::write(&scene, obj).unwrap();
    let out = dir.path().join("run");
    ok(&[
        "follow",
        "--scene",
        scene.to_str().unwrap(),
        "--scale",
        "2",
        "--max-sets",
        "10",
        "--no-timings",
        "--out",
        out.to_str().unwrap(),
    ]);
    let rows = rows(&out, 3);
    // Scaled by 2: top at z = 1.0, centre (0.6, 0); start δ = 0.1 above (the
    // mesh is stored in single precision: within 1e-6).
    let p: Vec<f64> = rows[0][2..5].iter().map(|s| s.parse().unwrap()).collect();
    assert!((p[0] - 0.6).abs() < 1e-6 && p[1].abs() < 1e-6 && (p[2] - 1.1).abs() < 1e-6);
    let model = json(&out, "surface_model.json");
    let table = model["segments"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["initial"] == true)
        .expect("the table initial segment");
    // At the bottom of the scaled box (z = 0.4).
    for v in table["vertices"].as_array().unwrap() {
        assert!((v[2].as_f64().unwrap() - 0.4).abs() < 1e-6, "{v}");
    }
    let r = json(&out, "run.json");
    // Top and four sides count; the bottom rests on the table.
    assert_eq!(r["score"]["faces"].as_array().unwrap().len(), 5);
}

#[test]
fn print_config_round_trips_through_config() {
    let dir = tempfile::tempdir().unwrap();
    let printed = ok(&["follow", "--print-config"]);
    assert!(printed.contains("[follow]") && printed.contains("[surface]"));
    let edited = printed.replace("max_step_m = 0.1", "max_step_m = 0.05");
    let file = dir.path().join("f.toml");
    std::fs::write(&file, &edited).unwrap();
    let again = ok(&[
        "follow",
        "--print-config",
        "--config",
        file.to_str().unwrap(),
    ]);
    assert_eq!(again, edited);
    std::fs::write(&file, "[follow]\nmax_stepp_m = 0.1\n").unwrap();
    let e = fails(&[
        "follow",
        "--print-config",
        "--config",
        file.to_str().unwrap(),
    ]);
    assert!(e.contains("max_stepp_m"), "{e}");
    // A scenario's own [follow] table is in effect unless --config replaces
    // it: the mOSD scans keep a 0.04 m guard margin and 0.05 m steps.
    let scan = data("scenarios/mosd_boxes.toml");
    let own = ok(&["follow", "--scenario", &scan, "--print-config"]);
    assert!(
        own.contains("guard_margin_m = 0.04\n") && own.contains("max_step_m = 0.05\n"),
        "{own}"
    );
    std::fs::write(&file, &edited).unwrap();
    let replaced = ok(&[
        "follow",
        "--scenario",
        &scan,
        "--print-config",
        "--config",
        file.to_str().unwrap(),
    ]);
    assert_eq!(replaced, edited);
}

#[test]
fn bad_input_names_the_flag_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    let o = out.to_str().unwrap();
    let missing = dir.path().join("missing.json");
    // The table clockwise seen from above: its normal points away from the
    // robot.
    let cw = dir.path().join("cw.json");
    std::fs::write(
        &cw,
        r#"{"segments": [[[-2, -2, 0], [-2, 2, 0], [2, 2, 0], [2, -2, 0]]]}"#,
    )
    .unwrap();
    // A second segment of three points on a line: no area.
    let flat = dir.path().join("flat.json");
    std::fs::write(
        &flat,
        r#"{"segments": [[[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], [[0, 0, 0], [1, 0, 0], [2, 0, 0]]]}"#,
    )
    .unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--scenario", "cube", "--initial", cw.to_str().unwrap()],
            "segment 0 faces away from the robot",
        ),
        (
            vec!["--scenario", "cube", "--initial", flat.to_str().unwrap()],
            "segment 1: ",
        ),
        (
            vec!["--scenario", "cube", "--robot", "robby"],
            "unknown robot",
        ),
        (
            vec![
                "--scenario",
                "cube",
                "--start",
                "0,0,1.1",
                "--joints",
                "0,0,1.1",
            ],
            "--joints",
        ),
        (
            vec!["--scenario", "cube", "--start", "0,nan,1.1"],
            "--start",
        ),
        (vec!["--scenario", "cube", "--start", "0,1.1"], "--start"),
        (
            vec!["--scenario", "cube", "--joints", "0,inf,1.1"],
            "--joints",
        ),
        (vec!["--scenario", "cube", "--joints", "0,1.1"], "joint"),
        (vec!["--scenario", "cube", "--noise-m", "-0.1"], "--noise-m"),
        (vec!["--scenario", "cube", "--noise-m", "NaN"], "--noise-m"),
        (vec!["--scenario", "cube", "--max-sets", "0"], "--max-sets"),
        (vec!["--scenario", "cube", "--scale", "2"], "--scene"),
        (vec!["--scenario", "nowhere"], "nowhere"),
        (
            vec!["--scenario", "cube", "--initial", missing.to_str().unwrap()],
            "missing.json",
        ),
        (vec!["--scene", "/nonexistent/box.obj"], "box.obj"),
        (vec!["--max-sets", "5"], "--scenario"),
        // Inside the block (a run from there only counted collisions).
        (
            vec![
                "--scenario",
                "block1",
                "--robot",
                "arm4",
                "--start",
                "0,0,0.1",
            ],
            "into the scene (object block1)",
        ),
    ];
    for (extra, expect) in cases {
        let mut args = vec!["follow", "--out", o];
        args.extend(&extra);
        let e = fails(&args);
        assert!(e.contains(expect), "{extra:?}: `{expect}` not in: {e}");
        for bad in ["panicked", "RUST_BACKTRACE", "Some("] {
            assert!(!e.contains(bad), "{extra:?}: {e}");
        }
        assert!(!out.exists(), "{extra:?} left {}", out.display());
    }
    // An out folder that is a file, or holds another command's run, is
    // refused before the run; the files there are untouched.
    let file = dir.path().join("afile");
    std::fs::write(&file, "keep").unwrap();
    let e = fails(&[
        "follow",
        "--scenario",
        "cube",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert!(e.contains("not a folder"), "{e}");
    let explored = dir.path().join("explored");
    std::fs::create_dir_all(&explored).unwrap();
    std::fs::write(explored.join("viewpoints.csv"), "k\n").unwrap();
    let x = explored.to_str().unwrap();
    let e = fails(&["follow", "--scenario", "cube", "--out", x]);
    assert!(e.contains("surveyor explore"), "{e}");
    assert_eq!(
        std::fs::read_dir(&explored).unwrap().count(),
        1,
        "files were added"
    );
    let followed = dir.path().join("followed");
    std::fs::create_dir_all(&followed).unwrap();
    std::fs::write(followed.join("steps.csv"), "step\n").unwrap();
    let f = followed.to_str().unwrap();
    let e = fails(&["explore", "--scenario", "bridge1", "--out", f]);
    assert!(e.contains("surveyor follow"), "{e}");
    assert_eq!(std::fs::read_dir(&followed).unwrap().count(), 1);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
}

#[cfg(unix)]
#[test]
fn ctrl_c_writes_the_steps_so_far_as_interrupted() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_surveyor"))
        .args([
            "follow",
            // The cylinder: point3 takes over 20 000 sets (about 8 s) there,
            // so the signal after 1.5 s comes mid-run (the cube now ends in
            // about 1.2 s).
            "--scenario",
            "cylinder",
            "--max-sets",
            "100000000",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert!(status.success(), "{status:?}");
    let r = json(&out, "run.json");
    assert_eq!(r["termination"], "interrupted");
    let n = r["steps"].as_u64().unwrap() as usize;
    assert!(n > 0);
    assert_eq!(rows(&out, 3).len(), n);
}

#[test]
fn scenario_files_run_a_urdf_arm_and_a_point_cloud_world() {
    let dir = tempfile::tempdir().unwrap();
    let ur5 = dir.path().join("ur5");
    ok(&[
        "follow",
        "--scenario",
        &data("scenarios/ur5_cube.toml"),
        "--max-sets",
        "10",
        "--out",
        ur5.to_str().unwrap(),
    ]);
    let rows = rows(&ur5, 6);
    assert!(!rows.is_empty() && rows.len() <= 10);
    // The scenario's start: the tool 0.1 m above the 0.2 m cube's top centre.
    let p: Vec<f64> = rows[0][2..5].iter().map(|s| s.parse().unwrap()).collect();
    assert!(
        p[0].abs() < 1e-3 && p[1].abs() < 1e-3 && (p[2] - 0.3).abs() < 1e-3,
        "{p:?}"
    );
    assert_eq!(json(&ur5, "run.json")["collisions"], 0);
    // A point-cloud world has no true surface: no collisions or score to report.
    let cloud = dir.path().join("cloud");
    let said = ok(&[
        "follow",
        "--scenario",
        &data("scenarios/mosd_boxes.toml"),
        "--max-sets",
        "10",
        "--out",
        cloud.to_str().unwrap(),
    ]);
    let r = json(&cloud, "run.json");
    assert!(r["collisions"].is_null() && r["score"].is_null() && r["min_clearance_m"].is_null());
    assert_eq!(r["robot"], "point3");
    // It is measured against the scan points instead: point3's 0.02 m body
    // starts 0.1 m above a box top, 0.08 m clear, and the scenario's guard
    // margin (0.04 m) keeps it more than 35 mm off as it closes in.
    assert!(
        said.contains("scan: links at least") && said.contains("model polygons"),
        "{said}"
    );
    let c = r["min_scan_clearance_m"].as_f64().unwrap();
    assert!(c > 0.035 && c < 0.1, "{c}");
    assert!(r["scan_close_poses"].is_u64());
    assert!(r["model_to_scan"].is_object());
    assert!(r["model_to_scan_within_lambda"].is_f64());
    // A mesh world leaves them null.
    let u = json(&ur5, "run.json");
    assert!(u["min_scan_clearance_m"].is_null() && u["model_to_scan"].is_null());
}
