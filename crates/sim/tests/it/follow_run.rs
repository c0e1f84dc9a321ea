//! The surface-following episode runner (issue 9) on the built-in scenes:
//! budgets, recording, determinism, the stop flag, ground-truth safety and
//! bad options. Runs here are bounded by `max_sets`; whole runs to the
//! follower's own end are in `follow_complete.rs`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

use follow::RunEnd;
use geom::{Point3, Real};
use scenario::Scenario;
use scenario::job::follow::HardwareFollow;
use sim::follow_job::{FollowRunError, FollowRunOptions, Judgement, SimFollow, StartPose};
use std::sync::atomic::{AtomicBool, Ordering};

fn setup(name: &str, options: &FollowRunOptions) -> SimFollow {
    SimFollow::from_scenario(&Scenario::load(name).unwrap(), options).unwrap()
}

fn budget(n: u64) -> FollowRunOptions {
    FollowRunOptions {
        max_sets: n,
        ..FollowRunOptions::default()
    }
}

fn no_stop() -> AtomicBool {
    AtomicBool::new(false)
}

#[test]
fn a_budgeted_cube_run_records_every_step_and_writes_every_output() {
    let s = setup("cube", &budget(50));
    assert_eq!(s.job.start_joints, vec![0.0, 0.0, 1.1]);
    let robot = s.rig.robot().clone();
    let mut calls = 0;
    let run = s.run(&no_stop(), &mut |_, _| calls += 1).unwrap();
    let rows = &run.episode.rows;
    assert!(!rows.is_empty() && rows.len() <= 50);
    if rows.len() < 50 {
        assert!(
            matches!(run.episode.end, RunEnd::Follower(_)),
            "{:?}",
            run.episode.end
        );
    } else {
        assert_eq!(run.episode.end, RunEnd::MaxSets);
    }
    assert_eq!(calls, rows.len());
    // Each row's control point is the tool point at its joints (point3: the
    // joints are the position), and each step starts where the last ended.
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r.step, k as u64);
        let tool = robot.tool_pose(&r.joints).unwrap().translation.vector;
        assert!((Point3::from(tool) - r.control_point).norm() < 1e-12);
        assert!(r.set_size <= robot.range_finders.len());
    }
    // Starting 0.1 above the top face, the sensors see it at once.
    assert!(rows[0].set_size > 0);
    // 0.1 m from a face with a 0.02 m body: no contact, clearance ≈ 0.08 at the start.
    assert!(
        run.judgement.collisions.is_empty(),
        "{:?}",
        run.judgement.collisions
    );
    let clear = run.judgement.min_clearance_m.unwrap();
    assert!(clear > 0.0 && clear <= 0.08 + 1e-9, "{clear}");
    let outputs = run.outputs().unwrap();
    let names: Vec<&str> = outputs.iter().map(|o| o.0).collect();
    assert_eq!(
        names,
        [
            "surface_model.json",
            "surface_model.obj",
            "steps.csv",
            "path.ply",
            "run.json",
            "model_snapshots.json"
        ]
    );
    let csv = &outputs[2].1;
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,mode,x,y,z,q1,q2,q3,set_size,update_us,direction_us,kinematics_us,link_clearance_m,current_segment,current_edge,robot_time_s"
    );
    // Each step's robot time by hand: a reading (0.01 s), the decision's
    // wall time, and point3's motion to the next step's joints at 0.25 m/s
    // and 1 m/s² (a triangle below 6.25 cm) plus 0.05 s to settle.
    let motion = |a: &[Real], b: &[Real]| {
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, Real::max);
        let (v, acc) = (0.25, 1.0);
        if d == 0.0 {
            0.0
        } else if d >= v * v / acc {
            d / v + v / acc + 0.05
        } else {
            2.0 * (d / acc).sqrt() + 0.05
        }
    };
    for (i, r) in rows.iter().enumerate().take(rows.len() - 1) {
        let by_hand =
            0.01 + r.times.unwrap().total_us() * 1e-6 + motion(&r.joints, &rows[i + 1].joints);
        assert!(
            (r.robot_time_s - by_hand).abs() < 1e-6,
            "step {i}: {} against {by_hand}",
            r.robot_time_s
        );
    }
    // The steps' robot times add up to the run's (run.json's `robot_time_s`).
    let sum: Real = rows.iter().map(|r| r.robot_time_s).sum();
    assert!(
        (sum - run.robot_time.total_s()).abs() < 1e-6,
        "{sum} against {:?}",
        run.robot_time
    );
    assert!(run.robot_time.moving_s > 0.0 && run.robot_time.deciding_s > 0.0);
    for (line, r) in lines.zip(rows) {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 16, "{line}");
        assert_eq!(f[15].parse::<Real>().unwrap(), r.robot_time_s);
        assert_eq!(f[1], r.mode);
        assert_eq!(f[2].parse::<Real>().unwrap(), r.control_point.x);
        assert_eq!(f[8].parse::<usize>().unwrap(), r.set_size);
        assert!(f[9].parse::<Real>().unwrap() >= 0.0);
    }
    assert_eq!(csv.lines().count(), rows.len() + 1);
    let ply = &outputs[3].1;
    let verts: usize = ply
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(verts == rows.len() || verts == rows.len() + 1);
    let json: serde_json::Value = serde_json::from_str(&outputs[4].1).unwrap();
    assert_eq!(json["steps"], rows.len());
    assert_eq!(json["collisions"], 0);
    assert_eq!(json["completed"], false);
    let modes: u64 = json["modes"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(modes, rows.len() as u64);
    // The built-in cube's counted faces: the top and four sides (its bottom
    // rests on the table).
    assert_eq!(json["score"]["faces"].as_array().unwrap().len(), 5);
    let model: serde_json::Value = serde_json::from_str(&outputs[0].1).unwrap();
    assert!(model["segments"].as_array().unwrap().len() >= 2);
    // The evolution: evenly spaced set counts, the last one the final model.
    let snaps: serde_json::Value = serde_json::from_str(&outputs[5].1).unwrap();
    let snaps = snaps["snapshots"].as_array().unwrap();
    let sets: Vec<u64> = snaps.iter().map(|s| s["sets"].as_u64().unwrap()).collect();
    assert_eq!(*sets.last().unwrap(), rows.len() as u64, "{sets:?}");
    assert!(
        sets.len() >= 2 && sets.windows(2).all(|w| w[0] < w[1]),
        "{sets:?}"
    );
    assert_eq!(snaps.last().unwrap()["model"], model);
}

#[test]
fn without_timings_two_runs_are_byte_identical_and_the_seed_matters() {
    let opts = |seed| FollowRunOptions {
        max_sets: 40,
        seed,
        noise_sigma_m: Some(0.002),
        timings: false,
        ..FollowRunOptions::default()
    };
    let out = |seed| {
        setup("cube", &opts(seed))
            .run(&no_stop(), &mut |_, _| {})
            .unwrap()
            .outputs()
            .unwrap()
    };
    let (a, b, c) = (out(7), out(7), out(8));
    assert_eq!(a[0].1, b[0].1, "surface_model.json");
    assert_eq!(a[2].1, b[2].1, "steps.csv");
    assert_eq!(a[5].1, b[5].1, "model_snapshots.json");
    assert_ne!(a[2].1, c[2].1, "another seed, other noise, other steps");
    let row = a[2].1.lines().nth(1).unwrap();
    let f: Vec<&str> = row.split(',').collect();
    assert_eq!(&f[9..12], ["", "", ""], "{row}");
}

/// Issue 46: the job a robot runs ([`HardwareFollow`], nobody judging) on
/// the rig makes the simulated run's steps, model and bag; only the
/// judgement and the scores are the simulator's.
#[test]
fn the_robot_job_on_the_rig_is_the_simulated_run_without_its_judgement() {
    let opts = FollowRunOptions {
        max_sets: 60,
        robot: Some("arm4".to_owned()),
        noise_sigma_m: Some(0.002),
        timings: false,
        ..FollowRunOptions::default()
    };
    let simulated = setup("cube", &opts);
    let on_robot = HardwareFollow::new(simulated.job.clone(), simulated.rig.clone(), 0.0)
        .unwrap()
        .run(&no_stop(), &mut |_, _| {})
        .unwrap();
    let simulated = simulated.run(&no_stop(), &mut |_, _| {}).unwrap();
    let (a, b) = (on_robot.outputs().unwrap(), simulated.outputs().unwrap());
    for k in [0, 1, 2, 3, 5] {
        assert_eq!(a[k].1, b[k].1, "{}", a[k].0);
    }
    assert_eq!(on_robot.bag, simulated.bag, "run.mcap");
    assert_eq!(on_robot.a_priori_faces, simulated.a_priori_faces);
    assert_eq!(on_robot.judgement, Judgement::default());
    assert!(simulated.judgement.min_clearance_m.is_some());
    assert!(on_robot.score.is_none() && simulated.score.is_some());
    let json: serde_json::Value = serde_json::from_str(&a[4].1).unwrap();
    assert!(
        json["score"].is_null() && json["collisions"].is_null(),
        "{json}"
    );
}

/// A robot that does not stand at the start joints is refused before the
/// run.
#[test]
fn the_robot_job_refuses_a_robot_away_from_the_start() {
    let simulated = setup("cube", &budget(10));
    let mut rig = simulated.rig.clone();
    hw::Arm::move_to(&mut rig, &[0.0, 0.0, 1.2]).unwrap();
    let e = HardwareFollow::new(simulated.job, rig, 1e-3).unwrap_err();
    assert!(matches!(e, FollowRunError::Option { .. }), "{e}");
    assert!(e.to_string().contains("start joints"), "{e}");
}

#[test]
fn the_stop_flag_ends_the_run_after_the_current_step_and_keeps_it() {
    let s = setup("cube", &budget(1000));
    let stop = AtomicBool::new(false);
    let run = s
        .run(&stop, &mut |row, _| {
            if row.step == 4 {
                stop.store(true, Ordering::Relaxed);
            }
        })
        .unwrap();
    assert_eq!(run.episode.end, RunEnd::Interrupted);
    assert_eq!(run.episode.rows.len(), 5);
    let json: serde_json::Value = serde_json::from_str(&run.outputs().unwrap()[4].1).unwrap();
    assert_eq!(json["termination"], "interrupted");
}

#[test]
fn arm4_on_block1_starts_delta_above_the_top_face_pointing_down_clear_of_the_block() {
    let opts = FollowRunOptions {
        robot: Some("arm4".into()),
        max_sets: 20,
        ..FollowRunOptions::default()
    };
    let s = setup("block1", &opts);
    let robot = s.rig.robot();
    let tool = robot.tool_pose(&s.job.start_joints).unwrap();
    let world = s.rig.world_from_base() * tool;
    // block1's upper top face is x ∈ [−0.6, 0], y ∈ [−0.35, 0.35] at z = 0.8.
    let p = Point3::from(world.translation.vector);
    assert!((p - Point3::new(-0.3, 0.0, 0.9)).norm() < 1e-3, "{p}");
    assert!((world.rotation * geom::Vector3::z()).z < -0.999);
    let run = s.run(&no_stop(), &mut |_, _| {}).unwrap();
    assert!(
        run.judgement.collisions.iter().all(|c| c.step.is_some()),
        "the start pose touches the block: {:?}",
        run.judgement.collisions
    );
    assert_eq!(run.robot, "arm4");
}

#[test]
fn a_start_pose_through_the_top_face_is_refused() {
    // point3's body is a 0.02 m sphere: 0.01 above the top face it cuts it.
    // A run from there would only count collisions, so it does not start
    // (as exploration refuses a start pose in the scene); 0.03 above is clear.
    let at = |z: Real| FollowRunOptions {
        start: Some(StartPose::ControlPoint([0.0, 0.0, z])),
        max_sets: 1,
        ..FollowRunOptions::default()
    };
    let e = SimFollow::from_scenario(&Scenario::load("cube").unwrap(), &at(1.01)).unwrap_err();
    assert!(matches!(e, FollowRunError::Option { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("link 3 (body)") && text.contains("object cube"),
        "{text}"
    );
    let run = setup("cube", &at(1.03))
        .run(&no_stop(), &mut |_, _| {})
        .unwrap();
    assert!(
        run.judgement.collisions.iter().all(|c| c.step.is_some()),
        "{:?}",
        run.judgement.collisions
    );
}

#[test]
fn bad_options_are_refused_before_anything_runs() {
    let load = || Scenario::load("cube").unwrap();
    let err = |o: FollowRunOptions| SimFollow::from_scenario(&load(), &o).unwrap_err();
    let e = err(FollowRunOptions {
        robot: Some("robby".into()),
        ..FollowRunOptions::default()
    });
    assert!(e.to_string().contains("unknown robot `robby`"), "{e}");
    let e = err(FollowRunOptions {
        start: Some(StartPose::ControlPoint([0.0, Real::NAN, 1.0])),
        ..FollowRunOptions::default()
    });
    assert!(matches!(e, FollowRunError::Option { .. }), "{e}");
    let e = err(budget(0));
    assert!(e.to_string().contains("max_sets"), "{e}");
    let e = err(FollowRunOptions {
        start: Some(StartPose::Joints(vec![0.0, 0.0])),
        ..FollowRunOptions::default()
    });
    assert!(e.to_string().starts_with("joints: "), "{e}");
    let e = err(FollowRunOptions {
        noise_sigma_m: Some(-1.0),
        ..FollowRunOptions::default()
    });
    assert!(e.to_string().contains("noise_sigma_m"), "{e}");
}
