//! Issue 9 acceptance 5: "A real scan as the world: an mOSD box scene from
//! `data/` with the table as an initial segment completes with no robot shape
//! closer than δ/2 to any scan point, and every model polygon within λ of the
//! scan." Measured by `sim::scan_check` during and after a whole run of
//! `data/scenarios/mosd_boxes.toml`, and cross-checked here against a
//! brute-force pass over every scan point.
//!
//! A whole run takes about two seconds in release (much longer in debug), so
//! the test is ignored by `cargo test`. It is not in `.ci/run` either, because
//! the follower does not meet acceptance 5 yet (see the `#[ignore]` reason);
//! run it with
//! `cargo test --release -p sim --test it mosd_follow -- --ignored --nocapture`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

use follow::RunEnd;
use follow::Termination;
use geom::{Point3, Real};
use scenario::Scenario;
use sim::follow_job::{FollowRunConfig, FollowRunOptions, SimFollow};
use std::collections::BTreeMap;
use std::sync::atomic::AtomicBool;
/// Issue 9 acceptance 5: point3 over the real mOSD scan (learn0, two boxes on
/// a table) as a point-cloud world, the table as the initial segment
/// (`data/scenarios/mosd_boxes.toml`). The run must end by the follower's own
/// rule, no robot shape may come closer than δ/2 to any scan point (at any
/// pose; `sim::scan_check::scan_clearance`, cross-checked here against a
/// brute-force pass over every scan point), and every non-initial model
/// polygon must lie within λ of the scan (`sim::scan_check::model_to_scan`).
// FAILS today (2026-11-29, the scenario's [follow] table: guard margin 0.04 m,
// steps of at most 0.05 m; 752 sets, surface_complete): the body keeps
// 0.0405 m from the scan, but 9 poses come closer than δ/2 = 0.05 m (the
// defaults: 0.0213 m and 776 poses, three polygons beyond λ). learn5 and
// learn17 keep 0.0404 and 0.0396 m with 198 and 126 close poses. Issue 45
// restated the bound on real scans as 35 mm, which `long/follow_complete.rs`
// holds; δ/2 is kept here as issue 9's check.
#[test]
#[ignore = "fails acceptance 5 today: 9 poses closer than δ/2 to the scan (0.0405 m at the closest); whole run, release profile"]
fn point3_follows_the_mosd_boxes_clear_of_the_scan() {
    let loaded = Scenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/scenarios/mosd_boxes.toml"
    ))
    .unwrap();
    let scene::World::Cloud(world) = loaded.build_world().unwrap() else {
        panic!("a point-cloud world")
    };
    let options = FollowRunOptions {
        max_sets: 20_000,
        timings: false,
        config: FollowRunConfig::of_scenario(&loaded.scenario),
        ..FollowRunOptions::default()
    };
    let delta = options.config.follow.desired_distance_m;
    let lambda = options.config.surface.lambda;
    let setup = SimFollow::from_scenario(&loaded, &options).unwrap();
    let run = setup.run(&AtomicBool::new(false), &mut |_, _| {}).unwrap();
    let scan = run
        .scan_score
        .as_ref()
        .expect("a point-cloud world is scored");
    let clearance = run.judgement.min_scan_clearance_m.unwrap();
    let close = run.judgement.scan_close_poses.unwrap();

    // Brute-force oracle of the clearance: point3 is a 0.02 m sphere at its
    // control point (base at the origin); the poses are each step's and the
    // end pose when the follower did not stop.
    let points = &world.cloud().points;
    let mut poses: Vec<(Option<u64>, Vec<Real>)> = run
        .episode
        .rows
        .iter()
        .map(|r| (Some(r.step), r.joints.clone()))
        .collect();
    if !matches!(run.episode.end, RunEnd::Follower(_)) {
        poses.push((None, run.episode.end_joints.clone()));
    }
    let brute: Vec<(Real, usize)> = poses
        .iter()
        .map(|(_, q)| {
            let c = Point3::new(q[0], q[1], q[2]);
            points
                .iter()
                .enumerate()
                .map(|(i, p)| ((p - c).norm() - 0.02, i))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(d, i)| (d.max(0.0), i))
                .unwrap()
        })
        .collect();
    let worst = (0..poses.len())
        .min_by(|&a, &b| brute[a].0.total_cmp(&brute[b].0))
        .unwrap();
    let (d, i) = brute[worst];
    let label = world.cloud().labels.as_ref().map(|l| l[i]);
    println!(
        "{} / {}: {} sets, {:?}; min scan clearance {clearance:.4} m (brute force {d:.4} m at step {:?}, control point {:?}, scan point {} {:?} label {label:?}), {close} poses closer than δ/2 = {} m; model to scan: worst {:.4} m, {:.1} % of the area within λ, {} of {} polygons beyond λ",
        run.source,
        run.robot,
        run.episode.rows.len(),
        run.episode.end,
        poses[worst].0,
        poses[worst].1,
        i,
        points[i],
        0.5 * delta,
        scan.max_m.unwrap_or(0.0),
        100.0 * scan.within_lambda_fraction,
        scan.polygons_beyond_lambda,
        scan.polygons.len()
    );
    for p in &scan.polygons {
        println!(
            "  polygon {:?}: {} vertices, {:.4} m², normal {:.3?}, max {:.4} m at {:.3?}, {:.1} % within λ",
            p.segment,
            p.vertices,
            p.area_m2,
            p.normal,
            p.max_m,
            p.max_at,
            100.0 * p.within_lambda_fraction
        );
    }
    // Which surfaces the close poses came near (the scan's labels: 1 the
    // table, 20 and 30 the boxes).
    if let Some(labels) = &world.cloud().labels {
        let mut near: BTreeMap<i64, usize> = BTreeMap::new();
        for (d, i) in &brute {
            if *d < 0.5 * delta {
                *near.entry(labels[*i]).or_default() += 1;
            }
        }
        println!("  poses closer than δ/2 by the label of the nearest scan point: {near:?}");
    }
    assert!(
        (clearance - d).abs() < 1e-9,
        "{clearance} vs brute force {d}"
    );
    assert_eq!(
        close,
        brute.iter().filter(|(d, _)| *d < 0.5 * delta).count()
    );

    assert_eq!(
        run.episode.end,
        RunEnd::Follower(Termination::SurfaceComplete),
        "the run must end by the algorithm's own rule"
    );
    assert!(
        clearance >= 0.5 * delta,
        "a link came {clearance:.4} m from a scan point (δ/2 = {} m) at {close} poses",
        0.5 * delta
    );
    assert!(!scan.polygons.is_empty(), "no model polygons");
    for p in &scan.polygons {
        assert!(
            p.max_m <= lambda,
            "polygon {:?} reaches {:.4} m from the scan (λ = {lambda} m) at {:?}",
            p.segment,
            p.max_m,
            p.max_at
        );
    }
}
