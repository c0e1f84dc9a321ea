//! An exploration's viewpoint tables read back, and cut short.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

/// Issue 48: a `candidates.csv` cut at a line end was drawn short by
/// `report` without a word; each Stage One decision's rows must number the
/// candidates `viewpoints.csv` says it scored.
#[test]
fn a_candidates_table_cut_short_is_refused() {
    use record::viewpoints::{
        CANDIDATES_CSV, PATH_CSV, ScoredCandidate, VIEWPOINTS_CSV, ViewpointRecord, candidates_csv,
        path_csv, read_viewpoints, viewpoints_csv,
    };
    let viewpoint = |k: usize, scored: usize| ViewpointRecord {
        k,
        stage: 1,
        joints: vec![0.0; 6],
        f: (k > 0).then_some([1.0, 2.0, 3.0, 4.0]),
        target_disc: None,
        h3: None,
        discs_identified: None,
        h1: 1.0,
        h1_weighted: 1.0,
        h2: 1.0,
        predicted_h1_weighted: None,
        candidates: scored,
        front: 1,
        unreachable: 0,
        predicted_revealed: 0,
        revealed: 0,
        coverage_a1: None,
        joint_travel: 0.0,
        waypoints: 0,
        path: Vec::new(),
        scored: (0..scored)
            .map(|i| ScoredCandidate {
                f: [i as f64, 2.0, 3.0, 4.0],
                front: i == 0,
            })
            .collect(),
        decision_ms: 0.0,
        plan_ms: 0.0,
        sweep_ms: 0.0,
        integrate_ms: 0.0,
        // Robot time in whole microseconds comes back as written.
        robot_time: robot::timing::RobotTime {
            moving_while_scanning_s: 1.25 * k as f64,
            moving_s: 0.5,
            standing_to_sweep_s: 15.125,
            deciding_s: 0.001,
        },
    };
    let records = vec![viewpoint(0, 0), viewpoint(1, 3), viewpoint(2, 4)];
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(VIEWPOINTS_CSV), viewpoints_csv(&records)).unwrap();
    std::fs::write(dir.path().join(PATH_CSV), path_csv(&records)).unwrap();
    let candidates = candidates_csv(&records);
    std::fs::write(dir.path().join(CANDIDATES_CSV), &candidates).unwrap();
    assert_eq!(read_viewpoints(dir.path()).unwrap(), records);
    let lines: Vec<&str> = candidates.lines().collect();
    let cut = lines[..lines.len() - 2].join("\n") + "\n";
    std::fs::write(dir.path().join(CANDIDATES_CSV), cut).unwrap();
    let e = read_viewpoints(dir.path()).unwrap_err().to_string();
    assert!(
        e.contains(CANDIDATES_CSV)
            && e.contains("viewpoint 2 has 2 candidate rows")
            && e.contains("scored 4"),
        "{e}"
    );
}
