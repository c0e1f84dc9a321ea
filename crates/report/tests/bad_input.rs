//! Broken run folders give errors that name the file, line and field, and
//! write no report.

use std::path::Path;

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
    write(d, "run.json", "{\"scenario\": \"x\"}");
    write(
        d,
        "viewpoints.csv",
        "k,stage,q1,h1,h1_weighted,h2,h3,predicted_h1_weighted,coverage_a1,joint_travel,decision_ms,plan_ms,sweep_ms,integrate_ms\n\
         0,1,0,5,4,3,,,0.1,0,0,0,0,0\n\
         1,1,0,5,abc,3,,,0.1,0,0,0,0,0\n",
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
    write(d, "run.json", "{\"scenario\": \"x\"}");
    let header = "k,stage,q1,h1,h1_weighted,h2,h3,predicted_h1_weighted,coverage_a1,joint_travel,decision_ms,plan_ms,sweep_ms,integrate_ms\n";
    for bad in ["NaN", "inf", "-inf"] {
        write(
            d,
            "viewpoints.csv",
            &format!("{header}0,1,0,5,4,3,,,0.1,0,0,0,0,0\n1,1,0,5,{bad},3,,,0.1,0,0,0,0,0\n"),
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
    write(
        d,
        "viewpoints.csv",
        &format!("{header}0,1,0,5,4,3,,,0.1,0,0,0,0,0\n"),
    );
    for run in ["[1, 2, 3]", "{}", "{\"scenario\": 7}"] {
        write(d, "run.json", run);
        let e = report::write(d).unwrap_err().to_string();
        assert!(
            e.contains("run.json") && e.contains("`scenario`"),
            "{run}: {e}"
        );
    }
    assert!(!d.join("report.html").exists());
}
