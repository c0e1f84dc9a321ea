//! Issue 23's campaign of bad input (a careless or hostile user): each
//! finding gets a clear error, no partial output and no hang. Every test
//! here failed before its fix.

use crate::support::{data, fails_with, ok, surveyor};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_surveyor")
}

/// Run `args` with the standard output given.
fn run_with_stdout(args: &[&str], stdout: Stdio) -> std::process::Output {
    Command::new(bin())
        .args(args)
        .stdout(stdout)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

/// A small surface-following run folder (point3 on block1, 30 sets).
fn follow_run(dir: &Path) -> PathBuf {
    let out = dir.join("follow30");
    ok(&[
        "follow",
        "--scenario",
        "block1",
        "--max-sets",
        "30",
        "--out",
        out.to_str().unwrap(),
    ]);
    out
}

#[test]
fn a_closed_pipe_ends_quietly_and_a_full_stdout_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let run = follow_run(dir.path());
    let commands: Vec<Vec<&str>> = vec![
        vec!["scenario", "show", "bridge3"],
        vec!["scenario", "list"],
        vec!["follow", "--print-config"],
        vec!["sld", "--print-config"],
        vec!["segment", "--print-config"],
        vec!["map", "--print-config"],
        vec!["model", "--print-config"],
        vec!["report", run.to_str().unwrap()],
        // Issue 48: help and version went into a full stdout with exit 0.
        vec!["--help"],
        vec!["model", "--help"],
        vec!["--version"],
    ];
    for args in &commands {
        // A pipe whose reader is gone before the command writes a byte.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = run_with_stdout(args, Stdio::from(writer));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        // A full disk behind stdout.
        if Path::new("/dev/full").exists() {
            let full = std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap();
            let out = run_with_stdout(args, Stdio::from(full));
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!err.contains("panicked"), "{args:?}: {err}");
            assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
            assert!(
                err.contains("writing to standard output"),
                "{args:?}: {err}"
            );
        }
    }
}

/// `scenario show bridge1` with `edit` applied, written to `dir/name`.
fn bridge1_with(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> String {
    let text = ok(&["scenario", "show", "bridge1"]);
    let edited = edit(text.clone());
    assert_ne!(edited, text, "{name}: the edit changed nothing");
    let path = dir.join(name);
    std::fs::write(&path, edited).unwrap();
    path.to_str().unwrap().to_owned()
}

/// Replace the line starting with `key = ` (the first one after `[table]`).
fn set(text: &str, table: &str, key: &str, value: &str) -> String {
    let start = text
        .find(&format!("[{table}]\n"))
        .unwrap_or_else(|| panic!("no [{table}]"));
    let rel = text[start..]
        .find(&format!("\n{key} = "))
        .unwrap_or_else(|| panic!("no {key} in [{table}]"));
    let at = start + rel + 1;
    let end = at + text[at..].find('\n').unwrap();
    format!("{}{key} = {value}{}", &text[..at], &text[end..])
}

#[test]
fn settings_that_exhaust_memory_or_time_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    for (table, key, value, needles) in [
        (
            "explore",
            "local_candidates",
            "1000000000",
            &["explore.local_candidates", "10000"][..],
        ),
        (
            "explore",
            "local_reach_m",
            "1e308",
            &["explore.local_reach_m"],
        ),
        (
            "explore.plan",
            "check_step_m",
            "1e-9",
            &["plan.check_step_m", "0.001"],
        ),
        ("explore.plan", "n_q", "100000000", &["plan.n_q"]),
        (
            "explore",
            "significant_h3",
            "nan",
            &["explore.significant_h3"],
        ),
        (
            "explore.prediction",
            "ray_step_deg",
            "1e-9",
            &["explore.prediction.ray_step_deg"],
        ),
        (
            "metrics.sampling",
            "max_samples",
            "1000000000000",
            &["max_samples", "50000000"],
        ),
    ] {
        let file = bridge1_with(dir.path(), &format!("{key}.toml"), |t| {
            set(&t, table, key, value)
        });
        fails_with(&["explore", "--scenario", &file, "--out", o], needles);
        assert!(!out.exists(), "{key}: an output folder was made");
    }
    // A sensor set of 200 000 points: the ceiling of max_set_points.
    let config = dir.path().join("model.toml");
    std::fs::write(&config, "max_set_points = 200000\n").unwrap();
    let sets = dir.path().join("sets.jsonl");
    std::fs::write(&sets, "{\"points\": [[0,0,0]], \"axes\": [[0,0,-1]]}\n").unwrap();
    fails_with(
        &[
            "model",
            "--sets",
            sets.to_str().unwrap(),
            "--config",
            config.to_str().unwrap(),
            "--out",
            o,
        ],
        &["max_set_points", "16384"],
    );
    assert!(!out.exists());
}

#[test]
fn absurd_but_finite_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan.ply");
    let o = out.to_str().unwrap();
    for (name, edit, needles) in [
        (
            "sigma",
            Box::new(|t: String| set(&t, "scanner.config.noise", "sigma_near_m", "1e308"))
                as Box<dyn Fn(String) -> String>,
            &["noise.sigma_near_m"][..],
        ),
        (
            "rpy",
            Box::new(|t: String| set(&t, "robot.base_pose", "rpy_deg", "[1e308, 0.0, 0.0]")),
            &["rpy_deg[0]", "360"],
        ),
        (
            "range",
            Box::new(|t: String| set(&t, "scanner.config", "max_range_m", "1e308")),
            &["max_range_m"],
        ),
    ] {
        let file = bridge1_with(dir.path(), &format!("{name}.toml"), edit);
        fails_with(&["scan", "--scenario", &file, "--out", o], needles);
        assert!(!out.exists(), "{name}");
    }
    let cloud = data("pointclouds/pc2beam_steel_beams_test_points.txt");
    fails_with(
        &["sld", "--input", &cloud, "--radius", "1e308", "--out", o],
        &["radius_m"],
    );
    let sets = dir.path().join("sets.jsonl");
    std::fs::write(&sets, "{\"points\": [[0,0,0]], \"axes\": [[0,0,-1]]}\n").unwrap();
    fails_with(
        &[
            "model",
            "--sets",
            sets.to_str().unwrap(),
            "--lambda",
            "1e308",
            "--out",
            o,
        ],
        &["lambda"],
    );
    fails_with(
        &[
            "follow",
            "--scenario",
            "cube",
            "--noise-m",
            "1e308",
            "--out",
            o,
        ],
        &["--noise-m"],
    );
    assert!(!out.exists());
}

#[test]
fn fixed_size_lists_with_extra_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("s.ply");
    let o = o.to_str().unwrap();
    for (name, table, key, value) in [
        (
            "translation",
            "robot.base_pose",
            "translation",
            "[0.0, 0.0, 0.0, 5.0]",
        ),
        ("rpy", "robot.base_pose", "rpy_deg", "[0.0, 0.0, 0.0, 0.0]"),
        ("region", "regions.a1", "min", "[-1.1, -1.1, -0.6, 9.0]"),
        ("short", "regions.a1", "max", "[1.1, 1.1]"),
    ] {
        let file = bridge1_with(dir.path(), &format!("{name}.toml"), |t| {
            set(&t, table, key, value)
        });
        fails_with(
            &["scan", "--scenario", &file, "--out", o],
            &[&format!("{name}.toml"), key, "expected exactly 3 values"],
        );
    }
}

#[test]
fn a_follow_start_inside_an_object_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    fails_with(
        &[
            "follow",
            "--scenario",
            "cube",
            "--start",
            "0,0,0.5",
            "--out",
            out.to_str().unwrap(),
        ],
        &["start", "inside object cube"],
    );
    assert!(!out.exists());
}

#[test]
fn flags_that_would_be_ignored_or_give_nothing_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let discs = d.join("discs.csv");
    std::fs::write(
        &discs,
        "cx,cy,cz,nx,ny,nz,radius,points\n0,0,0,0,0,1,0.04,8\n",
    )
    .unwrap();
    let seg = d.join("seg.json");
    fails_with(
        &[
            "segment",
            "--discs",
            discs.to_str().unwrap(),
            "--tau-q-deg",
            "1,2,3,4,5,6",
            "--out",
            seg.to_str().unwrap(),
        ],
        &["--tau-q-deg", "--poses"],
    );
    let scan = d.join("scan.ply");
    fails_with(
        &[
            "scan",
            "--scenario",
            "bridge1",
            "--deg",
            "--out",
            scan.to_str().unwrap(),
        ],
        &["--deg", "--joints"],
    );
    let fx = d.join("fx");
    fails_with(
        &[
            "raycast-fixture",
            "--rays",
            "0",
            "--out",
            fx.to_str().unwrap(),
        ],
        &["--rays", "at least 1"],
    );
    assert!(!seg.exists() && !scan.exists() && !fx.exists());
}

#[test]
fn negative_counts_say_what_they_expected() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("x");
    let o = o.to_str().unwrap();
    for args in [
        vec!["explore", "--seed", "-1", "--out", o],
        vec!["explore", "--max-viewpoints", "-3", "--out", o],
        vec![
            "follow",
            "--scenario",
            "cube",
            "--max-sets",
            "-1",
            "--out",
            o,
        ],
        vec!["sld", "--input", "x.ply", "--min-points", "-8", "--out", o],
        vec!["raycast-fixture", "--rays", "-5", "--out", o],
        vec!["plan-blast", "--run", o, "--seed", "-2", "--out", o],
    ] {
        let flag = args[args
            .iter()
            .position(|a| a.starts_with('-') && a.as_bytes()[1].is_ascii_digit())
            .unwrap()
            - 1];
        fails_with(&args, &[flag, "expected a whole number ≥ 0"]);
    }
    let help = ok(&["raycast", "--help"]);
    assert!(!help.contains("../shared"), "{help}");
}

/// Run `args` with writes limited to `kib` KiB per file (as on a full
/// disk: writes past it fail, the process goes on).
fn with_file_size_limit(kib: u64, args: &[&str]) -> std::process::Output {
    let script = format!("trap '' XFSZ; ulimit -f {}; exec \"$0\" \"$@\"", 2 * kib);
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(bin())
        .args(args)
        .output()
        .unwrap()
}

/// Names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn a_full_disk_leaves_no_partial_output() {
    let dir = tempfile::tempdir().unwrap();
    // A run folder: its report (megabytes of embedded JavaScript) does not fit.
    let fresh = dir.path().join("fresh");
    let args = [
        "follow",
        "--scenario",
        "block1",
        "--max-sets",
        "30",
        "--out",
        fresh.to_str().unwrap(),
    ];
    let out = with_file_size_limit(1024, &args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && !err.contains("panicked"), "{err}");
    assert!(
        err.contains("File too large") || err.contains("too large"),
        "{err}"
    );
    assert!(!fresh.exists(), "a folder was left: {:?}", listing(&fresh));
    // Over an older run: the older run stays whole.
    let old = follow_run(dir.path());
    let before: Vec<(String, Vec<u8>)> = listing(&old)
        .into_iter()
        .map(|n| (n.clone(), std::fs::read(old.join(&n)).unwrap()))
        .collect();
    let args = [
        "follow",
        "--scenario",
        "block1",
        "--max-sets",
        "40",
        "--out",
        old.to_str().unwrap(),
    ];
    let out = with_file_size_limit(1024, &args);
    assert!(!out.status.success());
    let after: Vec<(String, Vec<u8>)> = listing(&old)
        .into_iter()
        .map(|n| (n.clone(), std::fs::read(old.join(&n)).unwrap()))
        .collect();
    assert_eq!(before, after, "the older run changed");
    // `report` of that run: no page cut short, no temporary left.
    std::fs::remove_file(old.join("report.html")).unwrap();
    let out = with_file_size_limit(1024, &["report", old.to_str().unwrap()]);
    assert!(!out.status.success());
    let names = listing(&old);
    assert!(!names.iter().any(|n| n.contains("report")), "{names:?}");
}

#[test]
fn run_folders_under_non_utf8_paths_work() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let out = dir
        .path()
        .join(std::ffi::OsStr::from_bytes(b"run-\xff\xfe"));
    let status = Command::new(bin())
        .args([
            "follow",
            "--scenario",
            "block1",
            "--max-sets",
            "30",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    for name in ["run.json", "steps.csv", "report.html", "scenario.toml"] {
        assert!(out.join(name).exists(), "{name}");
    }
    std::fs::remove_file(out.join("report.html")).unwrap();
    let again = Command::new(bin())
        .arg("report")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(out.join("report.html").exists());
    let _ = surveyor(&["--version"]);
}
