//! `surveyor explore` through the binary: `kill -9` mid-run then `--resume`
//! gives the outputs of an uninterrupted run (issue 10 acceptance 5), bad
//! input gets a clear message, and `surveyor plan-blast` on a run's folder
//! gives the plan the run wrote (issue 11; it shares the Stage Two test's
//! run).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::support;

use std::path::Path;
use support::{fails, fails_with, ok};

/// The viewpoints recorded in `dir`'s checkpoint, by stage.
fn checkpointed(dir: &Path) -> (usize, usize) {
    let v = std::fs::read(dir.join("checkpoint.json"))
        .ok()
        .and_then(|t| serde_json::from_slice::<serde_json::Value>(&t).ok());
    let stages: Vec<u64> = v
        .as_ref()
        .and_then(|v| v["viewpoints"].as_array())
        .map(|a| a.iter().filter_map(|r| r["stage"].as_u64()).collect())
        .unwrap_or_default();
    (
        stages.iter().filter(|s| **s == 1).count(),
        stages.iter().filter(|s| **s == 2).count(),
    )
}

/// The arguments of `surveyor explore <args> --no-timings --cspace-cache
/// CACHE --out OUT`.
fn explore_args(args: &[&str], cache: &Path, out: &Path) -> Vec<String> {
    std::iter::once("explore")
        .chain(args.iter().copied())
        .chain(["--no-timings", "--cspace-cache", cache.to_str().unwrap()])
        .chain(["--out", out.to_str().unwrap()])
        .map(String::from)
        .collect()
}

fn ok_owned(args: &[String]) -> String {
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

/// A bridge1 run through both stages (budget of 3 Stage Two viewpoints,
/// Stage Two's transits scanned every 2°, seed 4), made once for the tests
/// that need one (both kill -9 tests, the resume refusals and
/// plan-blast's): its arguments, C-space cache and folder.
struct StageTwoRun {
    args: Vec<String>,
    cache: std::path::PathBuf,
    whole: std::path::PathBuf,
}

fn stage_two_run() -> &'static StageTwoRun {
    static RUN: std::sync::OnceLock<StageTwoRun> = std::sync::OnceLock::new();
    RUN.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("explore-stage-two");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scenario = dir.join("b.toml");
        // Stage Two's transits scan (and the LRC classifies those scans),
        // so a resume must replay them too.
        let text = ok(&["scenario", "show", "bridge1"])
            .replace(
                "stage_two_max_viewpoints = 20",
                "stage_two_max_viewpoints = 3",
            )
            .replace(
                "stage_two_scan_step_deg = 0.0",
                "stage_two_scan_step_deg = 2.0",
            );
        assert!(text.contains("stage_two_max_viewpoints = 3"));
        assert!(text.contains("stage_two_scan_step_deg = 2.0"));
        std::fs::write(&scenario, text).unwrap();
        let args = vec![
            "--scenario".to_owned(),
            scenario.to_str().unwrap().to_owned(),
            "--seed".to_owned(),
            "4".to_owned(),
        ];
        let cache = dir.join("cspace.json");
        let whole = dir.join("whole");
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        ok_owned(&explore_args(&a, &cache, &whole));
        StageTwoRun { args, cache, whole }
    })
}

/// A one-viewpoint Stage One run of bridge1 with its timings, made once for
/// the tests that need a run folder but not its contents (plan-blast's tool
/// file, the full disk's C-space cache) and for the report's timings card:
/// its C-space cache and folder.
struct SmallRun {
    cache: std::path::PathBuf,
    whole: std::path::PathBuf,
}

fn small_run() -> &'static SmallRun {
    static RUN: std::sync::OnceLock<SmallRun> = std::sync::OnceLock::new();
    RUN.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("explore-small");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (cache, whole) = (dir.join("cspace.json"), dir.join("whole"));
        let args = explore_args(
            &["--stages", "one", "--max-viewpoints", "1"],
            &cache,
            &whole,
        );
        let timed: Vec<String> = args.into_iter().filter(|a| a != "--no-timings").collect();
        ok_owned(&timed);
        SmallRun { cache, whole }
    })
}

/// Spawn `surveyor explore <args>` (`args` of [`explore_args`]) and kill it
/// with `kill -9` once `kill_when` holds of the checkpoint in `out`, or let
/// it end. Returns the checkpoint's viewpoints at the kill, `None` when the
/// run ended first.
#[cfg(unix)]
fn run_until(
    args: &[String],
    out: &Path,
    kill_when: impl Fn((usize, usize)) -> bool,
) -> Option<(usize, usize)> {
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_surveyor"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Up to 10 minutes (a slow or busy machine): the loop ends as soon as
    // the checkpoint shows the viewpoints to kill at, or the run has ended.
    let mut ended = false;
    for _ in 0..24_000 {
        if kill_when(checkpointed(out)) {
            break;
        }
        if child.try_wait().unwrap().is_some() {
            ended = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
    }
    let killed_at = checkpointed(out);
    // SIGKILL (kill -9) through the child handle: no signal to a process id
    // that may already have been reaped and reused.
    child.kill().unwrap();
    let status = child.wait().unwrap();
    (!ended && !status.success()).then_some(killed_at)
}

/// Run `surveyor explore <args> --no-timings --out DIR` killed with `kill -9`
/// once `kill_when` holds of its checkpoint, then resumed (with `twice`, the
/// resumed run is killed again once it has checkpointed a viewpoint more,
/// and resumed once more): every file of the folder, the report and the
/// checkpoint included, must equal the uninterrupted run's in `whole` (same
/// arguments and `cache`), but for the folder's path in the report and for
/// `run.mcap`: the bag records what the hardware did, and a resumed run
/// puts the arm back where each replayed viewpoint stood and sweeps it
/// again, so its bag holds those motions too. Its sweep clouds and disc
/// markers must equal the uninterrupted run's.
#[cfg(unix)]
fn kill_9_then_resume(
    args: &[&str],
    cache: &Path,
    whole: &Path,
    kill_when: impl Fn((usize, usize)) -> bool,
    twice: bool,
) {
    let dir = tempfile::tempdir().unwrap();
    let cut = dir.path().join("cut");
    let killed_at = run_until(&explore_args(args, cache, &cut), &cut, &kill_when);
    assert!(
        killed_at.is_some_and(&kill_when),
        "killed at {killed_at:?} viewpoints"
    );
    assert!(!cut.join("run.json").exists(), "the killed run finished");
    let mut kills = vec![killed_at];
    let mut resume = explore_args(args, cache, &cut);
    resume.insert(1, "--resume".into());
    if twice {
        // Killed again once past the first kill's viewpoints (or let end,
        // when it gets through its last viewpoints between two looks).
        let first = killed_at.unwrap();
        let again = run_until(&resume, &cut, |(one, two)| one + two > first.0 + first.1);
        if again.is_some() {
            assert!(!cut.join("run.json").exists(), "the killed run finished");
        }
        kills.push(again);
    }
    if !cut.join("run.json").exists() {
        ok_owned(&resume);
    }
    let names = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let files = names(whole);
    assert_eq!(names(&cut), files);
    for name in [
        "viewpoints.csv",
        "run.json",
        "report.html",
        "checkpoint.json",
    ] {
        assert!(files.iter().any(|f| f == name), "{files:?}");
    }
    // The report names the folder as given (`--out`): the one difference.
    let (from, to) = (cut.to_str().unwrap(), whole.to_str().unwrap());
    for name in &files {
        let (x, mut y) = (
            std::fs::read(whole.join(name)).unwrap(),
            std::fs::read(cut.join(name)).unwrap(),
        );
        if name == "report.html" {
            let text = String::from_utf8(y).unwrap();
            assert!(text.contains(from), "the report does not name its folder");
            y = text.replace(from, to).into_bytes();
        }
        if name == "run.mcap" {
            // Stamps aside (a resumed run's clock ran through the replay).
            let products = |d: &Path| {
                let wanted =
                    |t: &str| t == record::bag::topics::SWEEP || t == record::bag::topics::DISCS;
                record::bag::read_bag(&d.join(name), &wanted)
                    .unwrap()
                    .into_iter()
                    .map(|m| {
                        if m.topic == record::bag::topics::SWEEP {
                            let c = m.decode::<record::bag::msg::PointCloud2>().unwrap();
                            (c.width as usize, c.data)
                        } else {
                            let mut a = m.decode::<record::bag::msg::MarkerArray>().unwrap();
                            for marker in &mut a.markers {
                                marker.header.stamp = record::bag::msg::Time::default();
                            }
                            (a.markers.len(), format!("{:?}", a.markers).into_bytes())
                        }
                    })
                    .collect::<Vec<_>>()
            };
            let (x, y) = (products(whole), products(&cut));
            assert!(x.len() > 1, "{} sweep clouds and disc arrays", x.len());
            assert!(
                x == y,
                "the sweep clouds or discs of run.mcap differ after resuming at {kills:?}"
            );
            continue;
        }
        assert!(
            x == y,
            "{name} differs after resuming at {kills:?} viewpoints (stage one, stage two)"
        );
    }
}

/// Killed in Stage One of the shared run (two to four viewpoints recorded,
/// none of Stage Two), resumed through both stages.
#[cfg(unix)]
#[test]
#[ignore = "an exploration run (shared with the other kill -9 test): run by .ci/run"]
fn kill_9_in_stage_one_then_resume_gives_the_uninterrupted_outputs() {
    let run = stage_two_run();
    let args: Vec<&str> = run.args.iter().map(String::as_str).collect();
    kill_9_then_resume(
        &args,
        &run.cache,
        &run.whole,
        |(one, two)| (2..5).contains(&one) && two == 0,
        false,
    );
}

/// Killed in Stage Two of the shared run (one or two of its three
/// viewpoints recorded), resumed, killed again a viewpoint later (in Stage
/// Two, or as it writes its folder), resumed to the end.
#[cfg(unix)]
#[test]
#[ignore = "an exploration run (shared with the other kill -9 test): run by .ci/run"]
fn kill_9_in_stage_two_then_resume_gives_the_uninterrupted_outputs() {
    let run = stage_two_run();
    let args: Vec<&str> = run.args.iter().map(String::as_str).collect();
    kill_9_then_resume(
        &args,
        &run.cache,
        &run.whole,
        |(_, two)| (1..3).contains(&two),
        true,
    );
}

/// `--resume` refuses a checkpoint edited by hand (its records would be
/// replayed without audit), one written for other scenario content (the same
/// name) and one of the other `--stages`.
#[test]
#[ignore = "an exploration run (shared with the kill -9 test): run by .ci/run"]
fn resume_refuses_a_changed_checkpoint_or_scenario() {
    let run = stage_two_run();
    let dir = tempfile::tempdir().unwrap();
    let copy = |name: &str| {
        let d = dir.path().join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::copy(run.whole.join("checkpoint.json"), d.join("checkpoint.json")).unwrap();
        d
    };
    let resume = |args: &[String], d: &Path| {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let mut v = explore_args(&a, &run.cache, d);
        v.insert(1, "--resume".into());
        let e = fails(&v.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(!e.contains("panicked"), "{e}");
        assert!(!d.join("run.json").exists());
        e
    };
    // A viewpoint's joints edited (into the floor).
    let edited = copy("edited");
    let path = edited.join("checkpoint.json");
    let mut c: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    c["viewpoints"][1]["joints"] = serde_json::json!([0.0, 1.9, 1.3, 0.0, 0.0, 0.0]);
    std::fs::write(&path, serde_json::to_string(&c).unwrap()).unwrap();
    let e = resume(&run.args, &edited);
    assert!(e.contains("changed after it was written"), "{e}");
    // The same scenario file name, another range noise.
    let scenario = Path::new(&run.args[1]);
    let text = std::fs::read_to_string(scenario).unwrap();
    assert!(text.contains("sigma_near_m = 0.01"));
    let noisier = dir.path().join("noisier");
    std::fs::create_dir_all(&noisier).unwrap();
    let moved = noisier.join(scenario.file_name().unwrap());
    std::fs::write(
        &moved,
        text.replace("sigma_near_m = 0.01", "sigma_near_m = 0.05"),
    )
    .unwrap();
    let mut args = run.args.clone();
    args[1] = moved.to_str().unwrap().to_owned();
    let e = resume(&args, &copy("content"));
    assert!(e.contains("scenario's content"), "{e}");
    // Both stages then, Stage One now.
    let mut args = run.args.clone();
    args.extend(["--stages".to_owned(), "one".to_owned()]);
    let e = resume(&args, &copy("stages"));
    assert!(e.contains("--stages (both then, one now)"), "{e}");
}

/// `surveyor plan-blast` (issue 11) on the folder of an explore run plans
/// exactly the blast plan the run wrote; a tool file changes the limits it
/// records; a damaged inputs file is named.
#[test]
#[ignore = "an exploration run (shared with the kill -9 test): run by .ci/run"]
fn plan_blast_on_an_explore_run_gives_the_plan_explore_wrote() {
    let run = stage_two_run();
    let dir = tempfile::tempdir().unwrap();
    let r = run.whole.to_str().unwrap();
    let read = |p: std::path::PathBuf| std::fs::read_to_string(p).unwrap();
    let explored = read(run.whole.join("blast_plan.json"));
    let plan: serde_json::Value = serde_json::from_str(&explored).unwrap();
    assert!(plan["discs_with_pose"].as_u64().unwrap() > 0);
    let out = dir.path().join("plan");
    let o = out.to_str().unwrap();
    let said = ok(&["plan-blast", "--run", r, "--out", o]);
    assert!(said.contains("blast plan"), "{said}");
    assert_eq!(read(out.join("blast_plan.json")), explored);
    assert_eq!(
        read(out.join("blast_plan.csv")),
        read(run.whole.join("blast_plan.csv"))
    );
    // A tool file changes the limits the plan records; --seed is taken
    // (determinism per seed is checked on the library, sim's blast test).
    // On the small run's folder: its few discs plan in seconds.
    let tool = dir.path().join("tool.toml");
    std::fs::write(&tool, "phi_max_deg = 25.0\n").unwrap();
    let a = dir.path().join("a");
    ok(&[
        "plan-blast",
        "--run",
        small_run().whole.to_str().unwrap(),
        "--tool",
        tool.to_str().unwrap(),
        "--seed",
        "5",
        "--out",
        a.to_str().unwrap(),
    ]);
    let v: serde_json::Value = serde_json::from_str(&read(a.join("blast_plan.json"))).unwrap();
    assert_eq!(v["tool"]["phi_max_deg"].as_f64(), Some(25.0));
    // A damaged inputs file (in a copy of the run folder: the run is
    // shared) is named, not a panic.
    let damaged = dir.path().join("damaged");
    copy_folder(&run.whole, &damaged);
    let d = damaged.to_str().unwrap();
    std::fs::write(damaged.join("blast_inputs.json"), "{\"format\": 1").unwrap();
    fails_with(
        &["plan-blast", "--run", d, "--out", o],
        &["blast_inputs.json"],
    );
    std::fs::copy(
        run.whole.join("blast_inputs.json"),
        damaged.join("blast_inputs.json"),
    )
    .unwrap();
    // Issue 23: a folder of an older format (run.json without its version)
    // is refused, naming the version; so is a scenario.toml of another run.
    let run_json = read(run.whole.join("run.json"));
    let old: String = run_json
        .lines()
        .filter(|l| !l.contains("\"format_version\""))
        .fold(String::new(), |mut acc, l| {
            acc.push_str(l);
            acc.push('\n');
            acc
        });
    std::fs::write(damaged.join("run.json"), old).unwrap();
    fails_with(
        &["plan-blast", "--run", d, "--out", o],
        &["format version 1", "reads version 2"],
    );
    std::fs::write(damaged.join("run.json"), &run_json).unwrap();
    let scenario = read(run.whole.join("scenario.toml"));
    std::fs::write(
        damaged.join("scenario.toml"),
        scenario.replacen("name = \"bridge1\"", "name = \"bridge2\"", 1),
    )
    .unwrap();
    fails_with(
        &["plan-blast", "--run", d, "--out", o],
        &["scenario.toml", "`bridge2`", "another run"],
    );
    std::fs::write(damaged.join("scenario.toml"), &scenario).unwrap();
    let mut inputs: serde_json::Value =
        serde_json::from_str(&read(run.whole.join("blast_inputs.json"))).unwrap();
    inputs["grid"]["config"]["regions"]["a1"]["max"][0] = serde_json::json!(0.5);
    std::fs::write(
        damaged.join("blast_inputs.json"),
        serde_json::to_string(&inputs).unwrap(),
    )
    .unwrap();
    fails_with(
        &["plan-blast", "--run", d, "--out", o],
        &["blast_inputs.json", "other regions", "different runs"],
    );
    // Segments that leave discs out (here: none at all) are refused; the plan
    // was of 0 segments with every disc posed.
    let mut inputs: serde_json::Value =
        serde_json::from_str(&read(run.whole.join("blast_inputs.json"))).unwrap();
    inputs["segments"] = serde_json::json!([]);
    std::fs::write(
        damaged.join("blast_inputs.json"),
        serde_json::to_string(&inputs).unwrap(),
    )
    .unwrap();
    fails_with(
        &["plan-blast", "--run", d, "--out", o],
        &["blast_inputs.json", "disc 0 is in no segment"],
    );
}

#[test]
fn bad_explore_input_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = out.to_str().unwrap();
    let e = fails(&["explore", "--stages", "three", "--out", o]);
    assert!(e.contains("--stages three") && e.contains("`both`"), "{e}");
    let e = fails(&["explore", "--max-viewpoints", "0", "--out", o]);
    assert!(e.contains("--max-viewpoints 0"), "{e}");
    let e = fails(&["explore", "--resume", "--out", o]);
    assert!(
        e.contains("checkpoint.json") && e.contains("no run to continue"),
        "{e}"
    );
    assert!(!out.exists(), "--resume created the folder");
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
    // A bad mapping parameter names its field.
    let bad = dir.path().join("bad.toml");
    let text = ok(&["scenario", "show", "bridge1"]).replace("radius_m = 0.04", "radius_m = -0.04");
    std::fs::write(&bad, text).unwrap();
    let e = fails(&["explore", "--scenario", bad.to_str().unwrap(), "--out", o]);
    assert!(e.contains("radius_m") && e.contains("-0.04"), "{e}");
    // A start pose outside the joint limits names the scenario's key (the
    // scenario by its `name`, not the file's path).
    let text = ok(&["scenario", "show", "bridge1"]).replace(
        "start_joints = [0.0, -0.9599310885968813",
        "start_joints = [10.0, -0.9599310885968813",
    );
    assert!(text.contains("start_joints = [10.0,"));
    std::fs::write(&bad, text).unwrap();
    let e = fails(&["explore", "--scenario", bad.to_str().unwrap(), "--out", o]);
    assert!(
        e.contains("robot.start_joints") && e.contains("outside its limits"),
        "{e}"
    );
    // A checkpoint of another run is refused, not continued.
    std::fs::create_dir_all(&out).unwrap();
    for (text, says) in [
        ("{\"format\": 2}", "not a checkpoint"),
        ("{\"format\": 1}", "checkpoint format 1"),
    ] {
        std::fs::write(out.join("checkpoint.json"), text).unwrap();
        let e = fails(&["explore", "--resume", "--out", o]);
        assert!(e.contains(says) && e.contains("without --resume"), "{e}");
        for bad in ["panicked", "RUST_BACKTRACE"] {
            assert!(!e.contains(bad), "{e}");
        }
    }
}

#[test]
#[ignore = "an exploration run: seconds in release; run by .ci/run"]
fn mapping_parameters_come_from_the_scenario() {
    // Table 6.1's μ = 0.04 m changed to 0.06 m in the scenario file: every
    // disc of the run has that radius.
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("b.toml");
    let text = ok(&["scenario", "show", "bridge1"]).replace("radius_m = 0.04", "radius_m = 0.06");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.path().join("run");
    ok(&[
        "explore",
        "--scenario",
        scenario.to_str().unwrap(),
        "--stages",
        "one",
        "--max-viewpoints",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let discs = std::fs::read_to_string(out.join("discs.csv")).unwrap();
    let mut lines = discs.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "radius").unwrap();
    let radii: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    assert!(radii.len() > 100, "{} discs", radii.len());
    assert!(radii.iter().all(|r| (r - 0.06).abs() < 1e-12), "{radii:?}");
}

/// Copy the files of `from` into a new folder `to`.
fn copy_folder(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// Issue 23: `surveyor report` refuses a run folder missing a file the run
/// writes (it once drew a page without it), naming the file.
#[test]
#[ignore = "an exploration run (shared with the kill -9 test): run by .ci/run"]
fn report_refuses_a_run_folder_missing_a_file() {
    let run = stage_two_run();
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "cloud.ply",
        "mesh.ply",
        "discs.csv",
        "blast_plan.json",
        "path.csv",
        "candidates.csv",
        "scenario.toml",
    ] {
        let copy = dir.path().join(name.replace('.', "_"));
        copy_folder(&run.whole, &copy);
        std::fs::remove_file(copy.join("report.html")).unwrap();
        std::fs::remove_file(copy.join(name)).unwrap();
        fails_with(&["report", copy.to_str().unwrap()], &[name]);
        assert!(!copy.join("report.html").exists(), "{name}");
    }
}

/// Issue 23: a full disk while an exploration writes its outputs leaves no
/// file cut short under its own name and no `run.json` (the checkpoint,
/// rewritten whole after every viewpoint, stays for `--resume`).
#[test]
#[ignore = "an exploration run (and the shared small one): run by .ci/run"]
fn a_full_disk_while_explore_writes_leaves_no_partial_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    // The small run built the C-space cache, so the limit hits the outputs
    // only.
    let cache = &small_run().cache;
    let mut args = explore_args(&["--stages", "one", "--max-viewpoints", "2"], cache, &out);
    let script = "trap '' XFSZ; ulimit -f 2048; exec \"$0\" \"$@\"";
    let surveyor = env!("CARGO_BIN_EXE_surveyor");
    args.insert(0, surveyor.to_owned());
    let status = std::process::Command::new("sh")
        .arg("-c")
        .arg(script)
        .args(&args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&status.stderr);
    assert!(
        !status.status.success() && !err.contains("panicked"),
        "{err}"
    );
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, vec!["checkpoint.json".to_owned()], "{err}");
}

/// Issue 23: `[explore] local_candidates = 0` (the roadmap's nodes only,
/// Paul's own method) ends Stage One with `no_safe_candidate`, and the run
/// says why.
#[test]
#[ignore = "an exploration run: run by .ci/run"]
fn no_local_candidates_is_explained() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("b.toml");
    let text: String = ok(&["scenario", "show", "bridge1"])
        .lines()
        .map(|l| {
            if l.starts_with("local_candidates = ") {
                "local_candidates = 0\n".to_owned()
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    assert!(text.contains("local_candidates = 0"));
    std::fs::write(&scenario, text).unwrap();
    let out = dir.path().join("run");
    let said = ok(&[
        "explore",
        "--scenario",
        scenario.to_str().unwrap(),
        "--stages",
        "one",
        "--max-viewpoints",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        said.contains("(no_safe_candidate) after 1 viewpoints")
            && said.contains("local_candidates = 0 leaves only the roadmap's nodes"),
        "{said}"
    );
}

/// The summary cards of a report page: each card's `run.json` key and the
/// value it holds (its `data-key` and `data-value` attributes).
fn cards_of(html: &str) -> Vec<(String, serde_json::Value)> {
    let unescape = |s: &str| {
        s.replace("&quot;", "\"")
            .replace("&#39;", "'")
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&")
    };
    html.split("data-key=\"")
        .skip(1)
        .map(|rest| {
            let (key, rest) = rest.split_once('"').unwrap();
            let value = rest
                .strip_prefix(" data-value=\"")
                .and_then(|v| v.split_once('"'))
                .unwrap()
                .0;
            (
                unescape(key),
                serde_json::from_str(&unescape(value)).unwrap(),
            )
        })
        .collect()
}

/// Issue 48, the report: it opens with the summary cards, and every card
/// holds its figure as the final `run.json` does, the job's timings
/// included (the page was once written before they were known). Checked on
/// a run with its timings and on the Stage Two run (materials).
#[test]
#[ignore = "an exploration run (and the shared ones): run by .ci/run"]
fn the_report_opens_with_the_run_s_final_figures() {
    for (run, must) in [
        (
            small_run().whole.as_path(),
            &[
                "timings.total_s",
                "robot_time_s.total",
                "collisions",
                "coverage.A1",
            ][..],
        ),
        (
            stage_two_run().whole.as_path(),
            &["material_identification.identified", "material_accuracy"][..],
        ),
    ] {
        let html = std::fs::read_to_string(run.join("report.html")).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
        let cards = cards_of(&html);
        let first_card = html.find("class=\"card\"").unwrap();
        assert!(
            first_card < html.find("<h2>").unwrap(),
            "the cards open the page"
        );
        for key in must {
            assert!(
                cards.iter().any(|(k, _)| k == key),
                "no card of {key}: {cards:?}"
            );
        }
        for (key, value) in &cards {
            let held = key.split('.').try_fold(&json, |v, p| v.get(p)).unwrap();
            assert_eq!(held, value, "{key} in {}", run.display());
        }
    }
}
