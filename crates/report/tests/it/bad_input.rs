//! Broken run folders give errors that name the file, line and field, and
//! write no report.

use std::path::Path;

/// A `run.json` of this format version.
const RUN_JSON: &str = "{\"scenario\": \"x\", \"format_version\": 2}";

/// The header of `viewpoints.csv` for a one-joint robot, and a first row.
const HEADER: &str = "k,stage,q1,f1,f2,f3,f4,h1,h1_weighted,h2,h3,predicted_h1_weighted,actual_h1_weighted,\
candidates,front,unreachable,predicted_revealed,revealed,coverage_a1,joint_travel,waypoints,\
decision_ms,plan_ms,sweep_ms,integrate_ms,target_disc\n";
const ROW0: &str = "0,1,0,,,,,5,4,3,,,4,0,0,0,0,0,0.1,0,0,0,0,0,0,\n";

/// Row `k` with `h1_weighted` written as `h1w`.
fn row(k: usize, h1w: &str) -> String {
    format!("{k},1,0,,,,,5,{h1w},3,,,4,0,0,0,0,0,0.1,0,0,0,0,0,0,\n")
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap_or_else(|e| panic!("{name}: {e}"));
}

#[test]
fn not_a_run_folder() {
    let dir = tempfile::tempdir().unwrap();
    let e = report::write(dir.path()).unwrap_err().to_string();
    assert!(e.contains("not a run folder"), "{e}");
    assert!(!dir.path().join("report.html").exists());
}

#[test]
fn malformed_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // run.json that is not JSON.
    write(d, "viewpoints.csv", "k,stage\n0,1\n");
    write(d, "run.json", "{\"scenario\": \"x\",\n oops}");
    let e = report::write(d).unwrap_err().to_string();
    assert!(e.contains("run.json") && e.contains("line 2"), "{e}");

    // A number column holding text, on the third line.
    write(d, "run.json", RUN_JSON);
    write(
        d,
        "viewpoints.csv",
        &format!("{HEADER}{ROW0}{}", row(1, "abc")),
    );
    let e = report::write(d).unwrap_err().to_string();
    assert!(
        e.contains("viewpoints.csv") && e.contains("line 3") && e.contains("h1_weighted"),
        "{e}"
    );

    // A missing column.
    write(d, "viewpoints.csv", "k,stage\n0,1\n");
    let e = report::write(d).unwrap_err().to_string();
    assert!(
        e.contains("viewpoints.csv") && e.contains("missing column"),
        "{e}"
    );

    // A ragged row.
    write(d, "viewpoints.csv", "k,stage\n0,1,7\n");
    let e = report::write(d).unwrap_err().to_string();
    assert!(e.contains("viewpoints.csv"), "{e}");
    assert!(!d.join("report.html").exists());
}

#[test]
fn non_finite_numbers_and_a_run_json_of_another_shape_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "run.json", RUN_JSON);
    for bad in ["NaN", "inf", "-inf"] {
        write(
            d,
            "viewpoints.csv",
            &format!("{HEADER}{ROW0}{}", row(1, bad)),
        );
        let e = report::write(d).unwrap_err().to_string();
        assert!(
            e.contains("viewpoints.csv")
                && e.contains("line 3")
                && e.contains("h1_weighted")
                && e.contains("finite"),
            "{bad}: {e}"
        );
    }
    write(d, "viewpoints.csv", &format!("{HEADER}{ROW0}"));
    for run in [
        "[1, 2, 3]",
        "{}",
        "{\"scenario\": 7, \"format_version\": 2}",
    ] {
        write(d, "run.json", run);
        let e = report::write(d).unwrap_err().to_string();
        assert!(
            e.contains("run.json") && e.contains("`scenario`"),
            "{run}: {e}"
        );
    }
    assert!(!d.join("report.html").exists());
}

/// Issue 23 acceptance 4: a run folder of an older format (no
/// `format_version`: version 1, or another number) is refused, naming the
/// version, before any of its files is read.
#[test]
fn run_folders_of_another_format_version_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "viewpoints.csv", &format!("{HEADER}{ROW0}"));
    for (run, version) in [
        ("{\"scenario\": \"x\"}", "version 1"),
        ("{\"scenario\": \"x\", \"format_version\": 1}", "version 1"),
        ("{\"scenario\": \"x\", \"format_version\": 3}", "version 3"),
    ] {
        write(d, "run.json", run);
        let e = report::write(d).unwrap_err().to_string();
        assert!(
            e.contains("format") && e.contains(version) && e.contains("reads version 2"),
            "{run}: {e}"
        );
        assert!(!d.join("report.html").exists());
    }
}
