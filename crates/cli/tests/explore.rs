//! `surveyor explore` through the binary: `kill -9` mid-run then `--resume`
//! gives the outputs of an uninterrupted run (issue 10 acceptance 5), and bad
//! input gets a clear message.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

#[allow(dead_code)] // not every helper is used here
mod support;

use std::path::Path;
use support::{fails, ok};

fn viewpoints_in_checkpoint(dir: &Path) -> usize {
    std::fs::read(dir.join("checkpoint.json"))
        .ok()
        .and_then(|t| serde_json::from_slice::<serde_json::Value>(&t).ok())
        .and_then(|v| v["viewpoints"].as_array().map(Vec::len))
        .unwrap_or(0)
}

#[cfg(unix)]
#[test]
#[ignore = "three exploration runs: seconds in release; run by .ci/run"]
fn kill_9_then_resume_gives_the_uninterrupted_outputs() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cspace.json");
    let args = |out: &Path| -> Vec<String> {
        [
            "explore",
            "--scenario",
            "bridge1",
            "--max-viewpoints",
            "5",
            "--seed",
            "4",
            "--no-timings",
            "--cspace-cache",
            cache.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]
        .map(String::from)
        .to_vec()
    };
    let whole = dir.path().join("whole");
    let a: Vec<String> = args(&whole);
    ok(&a.iter().map(String::as_str).collect::<Vec<_>>());

    let cut = dir.path().join("cut");
    let mut child = Command::new(env!("CARGO_BIN_EXE_surveyor"))
        .args(args(&cut))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Kill it once two viewpoints are checkpointed (or give up waiting).
    for _ in 0..600 {
        if viewpoints_in_checkpoint(&cut) >= 2 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let killed_at = viewpoints_in_checkpoint(&cut);
    let status = Command::new("kill")
        .args(["-9", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let _ = child.wait();
    assert!(
        (2..5).contains(&killed_at),
        "killed after {killed_at} viewpoints"
    );
    assert!(!cut.join("run.json").exists(), "the killed run finished");

    let mut resume = args(&cut);
    resume.insert(1, "--resume".into());
    ok(&resume.iter().map(String::as_str).collect::<Vec<_>>());
    for name in [
        "viewpoints.csv",
        "run.json",
        "cloud.ply",
        "mesh.ply",
        "discs.csv",
        "segments.json",
    ] {
        let (x, y) = (
            std::fs::read(whole.join(name)).unwrap(),
            std::fs::read(cut.join(name)).unwrap(),
        );
        assert!(
            x == y,
            "{name} differs after resuming at viewpoint {killed_at}"
        );
    }
}

#[test]
fn bad_explore_input_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = out.to_str().unwrap();
    let e = fails(&["explore", "--stages", "three", "--out", o]);
    assert!(e.contains("--stages three") && e.contains("`both`"), "{e}");
    let e = fails(&["explore", "--resume", "--out", o]);
    assert!(e.contains("checkpoint") && e.contains("cannot read"), "{e}");
    let e = fails(&["explore", "--scenario", "bridge9", "--out", o]);
    assert!(e.contains("bridge9") && e.contains("built-ins"), "{e}");
    // Another robot: a URDF needs its scanner link; a start pose that puts
    // the robot into the scene is refused.
    let e = fails(&["explore", "--robot", "x.urdf", "--out", o]);
    assert!(e.contains("--scanner-link"), "{e}");
    let e = fails(&["explore", "--robot", "arm4", "--out", o]);
    assert!(
        e.contains("start pose") && e.contains("into the scene"),
        "{e}"
    );
    // A checkpoint of another run is refused, not continued.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("checkpoint.json"), "{\"format\": 1}").unwrap();
    let e = fails(&["explore", "--resume", "--out", o]);
    assert!(e.contains("not a checkpoint"), "{e}");
    for bad in ["panicked", "RUST_BACKTRACE"] {
        assert!(!e.contains(bad), "{e}");
    }
}
