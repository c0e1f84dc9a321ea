//! Bad input through the binary (issue "solid ground", §2): a clear error that
//! names the flag, file or joint, and no file left behind.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::support;

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

/// A 100-ray fixture in `dir/fx`.
fn fixture(dir: &Path) -> PathBuf {
    let fx = dir.join("fx");
    ok(&[
        "raycast-fixture",
        "--out",
        fx.to_str().unwrap(),
        "--rays",
        "100",
    ]);
    fx
}

/// `surveyor raycast` of the fixture in `fx` into `out`, `--repeat repeat`.
fn raycast(fx: &Path, out: &Path, repeat: &str) -> Vec<String> {
    let scene = fx.join("structure.ply");
    let rays = fx.join("rays.bin");
    [
        "raycast",
        "--scene",
        scene.to_str().unwrap(),
        "--rays",
        rays.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--repeat",
        repeat,
    ]
    .map(String::from)
    .to_vec()
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn raycast_repeat_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let fx = fixture(dir.path());
    let out = dir.path().join("d.bin");
    for repeat in ["0", "1001", "18446744073709551615"] {
        let e = fails(&strs(&raycast(&fx, &out, repeat)));
        assert!(e.contains("--repeat") && e.contains("1 to 1000"), "{e}");
        clean(&e);
    }
    assert!(!out.exists());
}

/// An output path that is a symbolic link writes the link's target (the
/// link stays); a FIFO is written into, not replaced by a file; a folder
/// is an error.
#[cfg(unix)]
#[test]
fn outputs_follow_links_and_write_into_fifos() {
    let dir = tempfile::tempdir().unwrap();
    let fx = fixture(dir.path());
    // A link, also one whose target does not exist yet.
    let target = dir.path().join("target.bin");
    let link = dir.path().join("link.bin");
    std::os::unix::fs::symlink("target.bin", &link).unwrap();
    ok(&strs(&raycast(&fx, &link, "1")));
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::metadata(&target).unwrap().len(), 400);
    // A FIFO: a reader gets the 100 distances, the FIFO stays one.
    let fifo = dir.path().join("fifo");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let f = fifo.clone();
        let reader = std::thread::spawn(move || std::fs::read(f).unwrap());
        ok(&strs(&raycast(&fx, &fifo, "1")));
        assert_eq!(reader.join().unwrap().len(), 400);
        assert!(std::os::unix::fs::FileTypeExt::is_fifo(
            &std::fs::metadata(&fifo).unwrap().file_type()
        ));
    }
    // A folder.
    let folder = dir.path().join("folder");
    std::fs::create_dir(&folder).unwrap();
    let e = fails(&strs(&raycast(&fx, &folder, "1")));
    assert!(e.contains("is a folder"), "{e}");
    assert!(listing(&folder).is_empty());
}

#[test]
fn out_folders_that_are_files_fail_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("afile");
    std::fs::write(&file, "keep").unwrap();
    let f = file.to_str().unwrap();
    for args in [
        vec!["explore", "--scenario", "bridge1", "--out", f],
        vec!["plan-blast", "--run", "nowhere", "--out", f],
    ] {
        let e = fails(&args);
        assert!(e.contains("exists and is not a folder"), "{e}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
}

#[test]
fn degrees_convert_revolute_joints_only() {
    // point3's three joints are prismatic: --deg leaves them in metres.
    let out = ok(&[
        "fk", "--robot", "point3", "--deg", "--joints", "1,2,3", "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let tip = &v["tip"];
    for (row, want) in [(0, 1.0), (1, 2.0), (2, 3.0)] {
        let got = tip[row][3].as_f64().unwrap();
        assert!(
            (got - want).abs() < 1e-9,
            "tip row {row}: {got}, want {want}"
        );
    }
    // A URDF with one of each: the revolute joint is converted.
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("rp.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="rp"><link name="a"/><link name="b"/><link name="c"/>
<joint name="r" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
<joint name="p" type="prismatic"><parent link="b"/><child link="c"/><axis xyz="1 0 0"/>
<limit lower="0" upper="2" effort="1" velocity="1"/></joint></robot>"#,
    )
    .unwrap();
    let out = ok(&[
        "fk",
        "--robot",
        urdf.to_str().unwrap(),
        "--deg",
        "--joints",
        "90,1.5",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    // 90° about z, then 1.5 m along the rotated x: (0, 1.5, 0).
    let (x, y) = (
        v["tip"][0][3].as_f64().unwrap(),
        v["tip"][1][3].as_f64().unwrap(),
    );
    assert!(
        x.abs() < 1e-9 && (y - 1.5).abs() < 1e-9,
        "tip at ({x}, {y})"
    );
    // Issue 48: 1e308 (degrees or radians) was taken as it was.
    for args in [
        &["--deg", "--joints", "1e308,0,0,0,0,0"][..],
        &["--joints", "0,0,0,0,0,13"],
    ] {
        let mut all = vec!["fk", "--robot", "denso-vm6083"];
        all.extend(args);
        let e = fails(&all);
        assert!(
            e.contains("--joints value") && e.contains("two turns"),
            "{e}"
        );
        clean(&e);
    }
    let e = fails(&["fk", "--robot", "point3", "--joints", "0,0,1e308"]);
    assert!(
        e.contains("--joints value 3") && e.contains("1000 m"),
        "{e}"
    );
}

#[test]
fn model_reads_sets_with_the_configured_limit_and_rejects_no_sets() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    // One set of 5000 points on the plane z = 0, seen from above.
    let pts: Vec<String> = (0..5000)
        .map(|i| {
            format!(
                "[{}, {}, 0]",
                f64::from(i % 100) * 0.002,
                f64::from(i / 100) * 0.002
            )
        })
        .collect();
    let axes = vec!["[0, 0, -1]"; 5000];
    std::fs::write(
        p("big.jsonl"),
        format!(
            "{{\"points\": [{}], \"axes\": [{}]}}\n",
            pts.join(", "),
            axes.join(", ")
        ),
    )
    .unwrap();
    let e = fails(&["model", "--sets", &p("big.jsonl"), "--out", &p("m0")]);
    assert!(e.contains("max_set_points"), "{e}");
    std::fs::write(p("m.toml"), "max_set_points = 10000\n").unwrap();
    ok(&[
        "model",
        "--sets",
        &p("big.jsonl"),
        "--config",
        &p("m.toml"),
        "--out",
        &p("m1"),
    ]);
    assert!(dir.path().join("m1").is_dir());
    std::fs::write(p("empty.jsonl"), "\n").unwrap();
    let e = fails(&["model", "--sets", &p("empty.jsonl"), "--out", &p("m2")]);
    assert!(
        e.contains("empty.jsonl") && e.contains("no sensor sets"),
        "{e}"
    );
    assert!(!dir.path().join("m2").exists());
}

/// Issue 48: `model --initial` with two segments overlapping on the same
/// surface (the campaign's case: accepted silently, the surface modelled
/// twice) is refused naming the file, both segments and their lines, and
/// writes nothing; tiles that only touch are a model.
#[test]
fn model_refuses_initial_segments_that_overlap() {
    use std::fmt::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    // Sets of 3×3 points on the plane z = 0, seen from above.
    let mut sets = String::new();
    for i in 0..20 {
        let pts: Vec<String> = (0..9)
            .map(|k| {
                format!(
                    "[{}, {}, 0]",
                    0.1 + 0.04 * f64::from(i) + 0.02 * f64::from(k % 3),
                    0.4 + 0.02 * f64::from(k / 3)
                )
            })
            .collect();
        writeln!(
            sets,
            "{{\"points\": [{}], \"axes\": [{}]}}",
            pts.join(", "),
            ["[0, 0, -1]"; 9].join(", ")
        )
        .unwrap();
    }
    std::fs::write(p("sets.jsonl"), sets).unwrap();
    let square = |x0: f64, y0: f64, x1: f64, y1: f64| {
        format!("[[{x0}, {y0}, 0], [{x1}, {y0}, 0], [{x1}, {y1}, 0], [{x0}, {y1}, 0]]")
    };
    // Two tiles of a table that meet along x = 1, then a square over both.
    let tiles = [square(0.0, 0.0, 1.0, 1.0), square(1.0, 0.0, 2.0, 1.0)];
    std::fs::write(
        p("tiles.json"),
        format!("{{\"segments\": [\n  {},\n  {}\n]}}\n", tiles[0], tiles[1]),
    )
    .unwrap();
    std::fs::write(
        p("overlap.json"),
        format!(
            "{{\"segments\": [\n  {},\n  {},\n\n  {}\n]}}\n",
            tiles[0],
            tiles[1],
            square(0.5, 0.5, 1.5, 1.5)
        ),
    )
    .unwrap();
    let said = ok(&[
        "model",
        "--sets",
        &p("sets.jsonl"),
        "--initial",
        &p("tiles.json"),
        "--out",
        &p("tiles"),
    ]);
    assert!(said.contains("20 sets"), "{said}");
    let e = fails(&[
        "model",
        "--sets",
        &p("sets.jsonl"),
        "--initial",
        &p("overlap.json"),
        "--out",
        &p("overlap"),
    ]);
    // The third segment (line 5) is the first that overlaps: the first tile
    // (line 2), over its quarter of 0.25 m².
    assert!(
        e.contains(&format!(
            "{}:5: segments[2] overlaps segments[0] (line 2) over 2.500e-1 m²",
            p("overlap.json")
        )),
        "{e}"
    );
    clean(&e);
    assert!(!dir.path().join("overlap").exists());
}

#[test]
fn urdf_warnings_reach_the_user() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("nl.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="t"><link name="a"/><link name="b"/>
<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>"#,
    )
    .unwrap();
    let out = support::surveyor(&["fk", "--robot", urdf.to_str().unwrap(), "--joints", "1"]);
    assert!(out.status.success());
    let e = String::from_utf8(out.stderr).unwrap();
    assert!(
        e.contains("warning: ") && e.contains("nl.urdf:2") && e.contains("'j1' has no <limit"),
        "{e}"
    );
}

/// Fields the scan itself does not use are still checked when the scenario
/// is read (a Stage Two setting, the scanner's reflection model, the
/// regions).
#[test]
fn scenario_files_are_checked_whole() {
    let dir = tempfile::tempdir().unwrap();
    let shown = ok(&["scenario", "show", "bridge1"]);
    for (from, to, field) in [
        ("d_max_m = 0.8", "d_max_m = -5.0", "pose.d_max_m"),
        (
            "specular_range_bias_m = 0.006",
            "specular_range_bias_m = nan",
            "reflection.specular_range_bias_m",
        ),
        (
            "peak_intensity = 4000.0",
            "peak_intensity = -4000.0",
            "reflection.peak_intensity",
        ),
        // A1's max below its min on x.
        (
            "max = [1.1, 1.1, 1.5750000000000002]",
            "max = [-2.0, 1.1, 1.575]",
            "regions.a1",
        ),
    ] {
        assert!(shown.contains(from), "`{from}` not in the shown scenario");
        let path = dir.path().join("s.toml");
        std::fs::write(&path, shown.replacen(from, to, 1)).unwrap();
        let out = dir.path().join("s.ply");
        let e = fails(&[
            "scan",
            "--scenario",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(e.contains("s.toml") && e.contains(field), "{e}");
        clean(&e);
        assert!(!out.exists());
    }
}

/// Inputs with nothing in them are errors, not empty outputs.
#[test]
fn empty_inputs_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    // A discs CSV of its header only.
    ok(&[
        "sld",
        "--input",
        &data("meshes/cinder_block_meters.obj"),
        "--out",
        &p("discs.csv"),
    ]);
    let text = std::fs::read_to_string(p("discs.csv")).unwrap();
    let header = text.lines().next().unwrap();
    std::fs::write(p("header.csv"), format!("{header}\n")).unwrap();
    let e = fails(&[
        "segment",
        "--discs",
        &p("header.csv"),
        "--out",
        &p("s.json"),
    ]);
    assert!(e.contains("header.csv") && e.contains("no discs"), "{e}");
    // A PLY of no vertices.
    std::fs::write(
        p("none.ply"),
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
    )
    .unwrap();
    let e = fails(&["sld", "--input", &p("none.ply"), "--out", &p("d.csv")]);
    assert!(e.contains("none.ply") && e.contains("no points"), "{e}");
    // No rays.
    let fx = fixture(dir.path());
    std::fs::write(fx.join("rays.bin"), b"").unwrap();
    let e = fails(&strs(&raycast(&fx, &dir.path().join("d.bin"), "1")));
    assert!(e.contains("rays.bin") && e.contains("no rays"), "{e}");
    for f in ["s.json", "d.csv", "d.bin"] {
        assert!(!dir.path().join(f).exists(), "{f} was written");
    }
}

#[test]
fn messages_name_things_once_and_plainly() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("x.obj");
    std::fs::write(&obj, "v 0 0 0\n").unwrap();
    let o = obj.to_str().unwrap();
    // A robot given as a file that is not a URDF.
    let e = fails(&["fk", "--robot", o, "--joints", "1"]);
    assert!(
        e.contains("not a URDF") && e.contains("denso-vm6083"),
        "{e}"
    );
    // The file named once.
    let out = dir.path().join("d.csv");
    let e = fails(&["sld", "--input", o, "--out", out.to_str().unwrap()]);
    assert_eq!(e.matches("x.obj").count(), 1, "{e}");
    // A report of a folder that does not exist.
    let e = fails(&["report", dir.path().join("nowhere").to_str().unwrap()]);
    assert!(e.contains("no such folder"), "{e}");
}

/// A point-cloud world's ε (derived from the cloud when the file gives
/// none) is printed: a two-point cloud gets an ε of metres, which the user
/// must be able to see.
#[test]
fn scan_of_a_point_cloud_prints_its_epsilon() {
    use std::fmt::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("roof.txt");
    let mut text = String::new();
    for i in 0..21 {
        for j in 0..21 {
            writeln!(
                text,
                "{} {} 1.5",
                -0.5 + 0.05 * f64::from(i),
                -0.5 + 0.05 * f64::from(j)
            )
            .unwrap();
        }
    }
    std::fs::write(&cloud, text).unwrap();
    let out = ok(&[
        "scan",
        "--scene",
        cloud.to_str().unwrap(),
        "--deg",
        "--joints",
        "0,-55,165,0,-110,0",
        "--out",
        dir.path().join("s.ply").to_str().unwrap(),
    ]);
    assert!(
        out.contains("point cloud of 441 points") && out.contains("ε = "),
        "{out}"
    );
}

/// `map --bag` and `model --bag` on bags they cannot use: a file that is
/// no bag, a bag cut short, a bag without the topics asked for, a robot
/// whose joints the bag does not name. Each error names the file and what
/// is missing, and no output folder is left behind.
#[test]
fn bad_bags_are_refused_by_name() {
    use record::bag::msg::{Header, JointState, Range, TfMessage};
    use record::bag::{BagWriter, topics};
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_owned();
    std::fs::write(p("junk.mcap"), b"\x89MCAP0\r\nnot really").unwrap();
    // Small bags: joint states (of the DENSO's six joints, or of a
    // shoulder and an elbow), range readings.
    let small = |names: &[&str]| {
        let mut w = BagWriter::new(std::io::Cursor::new(Vec::new())).unwrap();
        w.write(topics::TF_STATIC, 0, &TfMessage::default())
            .unwrap();
        for k in 0..50u64 {
            let t = k * 1_000_000;
            let js = JointState {
                header: Header::new(t, ""),
                name: names.iter().map(|&n| n.to_owned()).collect(),
                position: vec![0.1; names.len()],
                ..JointState::default()
            };
            w.write(topics::JOINT_STATES, t, &js).unwrap();
            let r = Range {
                header: Header::new(t, "nowhere"),
                max_range: 1.0,
                range: 0.5,
                ..Range::default()
            };
            w.write("/range/a", t, &r).unwrap();
        }
        w.finish().unwrap().into_inner()
    };
    let bytes = small(&["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]);
    std::fs::write(p("small.mcap"), &bytes).unwrap();
    std::fs::write(p("cut.mcap"), &bytes[..bytes.len() * 2 / 3]).unwrap();
    std::fs::write(p("names.mcap"), small(&["shoulder", "elbow"])).unwrap();
    let map = |bag: &str, out: &str| {
        fails(&[
            "map",
            "--bag",
            &p(bag),
            "--robot",
            "denso-vm6083",
            "--out",
            &p(out),
        ])
    };
    for (bag, says) in [
        ("junk.mcap", "junk.mcap"),
        ("cut.mcap", "cut.mcap"),
        ("missing.mcap", "missing.mcap"),
        ("small.mcap", "no `sensor_msgs/msg/LaserScan` on /scan"),
        ("names.mcap", "has no joint `joint1` of robot denso-vm6083"),
    ] {
        let e = map(bag, "m");
        assert!(e.contains(says), "{bag}: {e}");
        clean(&e);
    }
    let e = fails(&[
        "map",
        "--bag",
        &p("small.mcap"),
        "--robot",
        "denso-vm6083",
        "--scan-topic",
        "/range/a",
        "--out",
        &p("m"),
    ]);
    assert!(e.contains("carries sensor_msgs/msg/Range"), "{e}");
    let model = |bag: &str, extra: &[&str]| {
        let (bag, out) = (p(bag), p("md"));
        let mut args = vec!["model", "--bag", &bag];
        args.extend_from_slice(extra);
        args.extend(["--out", &out]);
        fails(&args)
    };
    let e = model("small.mcap", &[]);
    assert!(e.contains("frame `nowhere` is not placed"), "{e}");
    let e = model("small.mcap", &["--range-topics", "/range/b"]);
    assert!(e.contains("no messages on /range/b"), "{e}");
    let e = model("cut.mcap", &[]);
    assert!(e.contains("cut.mcap"), "{e}");
    clean(&e);
    let e = fails(&["map", "--bag", &p("small.mcap"), "--out", &p("m")]);
    assert!(e.contains("--robot"), "{e}");
    // Issue 48: bag flags without a bag, and a topic of another type given
    // as a Range topic.
    let sets = p("sets.jsonl");
    std::fs::write(&sets, "{\"points\": [[0,0,0]], \"axes\": [[0,0,1]]}\n").unwrap();
    let e = fails(&[
        "model",
        "--sets",
        &sets,
        "--range-topics",
        "/range/a",
        "--out",
        &p("md"),
    ]);
    assert!(e.contains("--range-topics applies with --bag"), "{e}");
    let e = fails(&[
        "model",
        "--sets",
        &sets,
        "--skip-bad-messages",
        "--out",
        &p("md"),
    ]);
    assert!(e.contains("--skip-bad-messages applies with --bag"), "{e}");
    let e = model("small.mcap", &["--range-topics", "/joint_states"]);
    assert!(
        e.contains("/joint_states is not `sensor_msgs/msg/Range`"),
        "{e}"
    );
    clean(&e);
    let left: Vec<_> = listing(dir.path())
        .into_iter()
        .filter(|f| f.extension().is_none_or(|e| e != "mcap" && e != "jsonl"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// `sim-robot`: without `--ros2` (the one transport), with a speed, a
/// duration or a rate out of range, with a `ROS_DOMAIN_ID` that is no domain, or an
/// unknown scenario: a clear error before any DDS traffic.
#[test]
fn sim_robot_refuses_what_it_cannot_serve() {
    support::fails_with(&["sim-robot", "--scenario", "bridge1"], &["--ros2"]);
    support::fails_with(
        &[
            "sim-robot",
            "--scenario",
            "bridge1",
            "--ros2",
            "--joint-speed",
            "0",
        ],
        &["--joint-speed 0", "at most 10 rad/s"],
    );
    support::fails_with(
        &[
            "sim-robot",
            "--scenario",
            "bridge1",
            "--ros2",
            "--for",
            "-1",
        ],
        &["--for -1"],
    );
    for rate in ["0", "-2", "101", "NaN"] {
        support::fails_with(
            &[
                "sim-robot",
                "--scenario",
                "bridge1",
                "--ros2",
                "--rate",
                rate,
            ],
            &[&format!("--rate {rate}"), "at most 100"],
        );
    }
    support::fails_with(
        &[
            "sim-robot",
            "--scenario",
            "no_such_scene",
            "--ros2",
            "--for",
            "1",
        ],
        &["no_such_scene"],
    );
    for bad in ["233", "abc", "-1"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_surveyor"))
            .args(["sim-robot", "--scenario", "bridge1", "--ros2", "--for", "1"])
            .env("ROS_DOMAIN_ID", bad)
            .output()
            .unwrap();
        assert!(!out.status.success(), "ROS_DOMAIN_ID={bad}");
        let e = String::from_utf8(out.stderr).unwrap();
        assert!(
            e.contains(&format!("ROS_DOMAIN_ID={bad}")) && e.contains("0 to 232"),
            "{e}"
        );
        clean(&e);
    }
}

/// `explore --ros2` and `follow --ros2` with no robot answering stop with
/// an error naming what they waited for, after the `[ros2]` timeout, and
/// write nothing; a bad `[ros2]` table and `--lockstep` without `--ros2`
/// are refused before any DDS traffic.
#[test]
fn ros2_runs_without_a_robot_stop_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let quick = |name: &str, table: &str| {
        let base = scenario::builtin_scenario(name).unwrap().to_toml().unwrap();
        let file = dir.path().join(format!("{name}.toml"));
        std::fs::write(&file, format!("{base}\n[ros2]\n{table}\n")).unwrap();
        file.to_str().unwrap().to_owned()
    };
    let (block1, bridge1) = (
        quick("block1", "timeout_s = 0.5"),
        quick("bridge1", "timeout_s = 0.5"),
    );
    let out = dir.path().join("run");
    let domain = (200 + std::process::id() % 30).to_string();
    for args in [
        vec!["follow", "--scenario", &block1, "--ros2"],
        vec!["explore", "--scenario", &bridge1, "--ros2", "--no-oracle"],
    ] {
        let done = std::process::Command::new(env!("CARGO_BIN_EXE_surveyor"))
            .args(&args)
            .args(["--out", out.to_str().unwrap()])
            .env("ROS_DOMAIN_ID", &domain)
            .output()
            .unwrap();
        assert!(!done.status.success(), "{args:?}");
        let e = String::from_utf8(done.stderr).unwrap();
        assert!(
            e.contains("no joint state before the timeout"),
            "{args:?}: {e}"
        );
        clean(&e);
        assert!(!out.exists(), "{args:?} left {}", out.display());
    }
    let loose = quick("block1", "tolerance_rad = 1");
    support::fails_with(
        &["follow", "--scenario", &loose, "--ros2", "--out", "x"],
        &["ros2.tolerance_rad", "at most 0.05"],
    );
    support::fails_with(
        &[
            "explore",
            "--scenario",
            "bridge1",
            "--lockstep",
            "--out",
            "x",
        ],
        &["--ros2"],
    );
}

/// `map --robot` belongs to `--bag`; given with `--scans` it would be
/// ignored, so it is an error.
#[test]
fn map_robot_without_a_bag_is_an_error() {
    support::fails_with(
        &[
            "map",
            "--scans",
            "a.ply",
            "--robot",
            "denso-vm6083",
            "--out",
            "m",
        ],
        &["--bag"],
    );
}

/// `scenario mjcf` (issue 47) writes the model and its sidecar together;
/// an output that is no `.xml`, a point-cloud world and an unknown robot
/// are refused clearly and leave no file.
#[test]
fn scenario_mjcf_writes_both_files_or_none() {
    let dir = tempfile::tempdir().unwrap();
    let xml = dir.path().join("m/bridge1.xml");
    let said = ok(&[
        "scenario",
        "mjcf",
        "bridge1",
        "--out",
        xml.to_str().unwrap(),
    ]);
    assert!(said.contains("14 scene geoms"), "{said}");
    let text = std::fs::read_to_string(&xml).unwrap();
    assert!(text.starts_with("<mujoco model=\"bridge1 (denso-vm6083)\">"));
    let sidecar = std::fs::read_to_string(xml.with_extension("json")).unwrap();
    assert!(sidecar.contains("\"bearings_rad\""), "{sidecar}");
    let other = tempfile::tempdir().unwrap();
    let out = |name: &str| other.path().join(name).to_str().unwrap().to_owned();
    for (args, needle) in [
        (vec!["bridge1", "--out", &out("m.mjcf")], "ending in .xml"),
        (
            vec![&data("scenarios/mosd_boxes.toml"), "--out", &out("m.xml")],
            "point cloud",
        ),
        (
            vec!["bridge1", "--robot", "puma", "--out", &out("m.xml")],
            "puma",
        ),
    ] {
        let msg = fails(&[&["scenario", "mjcf"][..], &args[..]].concat());
        assert!(msg.contains(needle), "{msg}");
        clean(&msg);
    }
    assert!(
        listing(other.path()).is_empty(),
        "{:?}",
        listing(other.path())
    );
}
