//! Measurements against a real scan (`sim::scan_check`, issue 9 acceptance 5)
//! on hand-made clouds whose answers are known analytically, and the per-pose
//! clearance of a short run over the mOSD scan against a brute-force pass over
//! every scan point.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

use follow::RunEnd;
use geom::{Capsule, Isometry3, Point3, Real, Vector3};
use scenario::Scenario;
use scenario::job::follow::ScanFigures;
use scene::World;
use sim::follow_job::{FollowRunOptions, SimFollow, StartPose};
use sim::scan_check::{ModelScanConfig, ScanIndex, model_to_scan, polygon_to_scan, scan_clearance};
use std::sync::atomic::AtomicBool;
use surface::{SensorSet, SurfaceConfig, SurfaceModel};

/// Spacing of the flat test grid, metres.
const G: Real = 0.002;

/// Points on z = 0, `G` apart, over [−0.5, 0.5]².
fn flat_grid() -> Vec<Point3> {
    let n = (0.5 / G).round() as i64;
    let mut v = Vec::with_capacity(((2 * n + 1) * (2 * n + 1)) as usize);
    for i in -n..=n {
        for j in -n..=n {
            v.push(Point3::new(i as Real * G, j as Real * G, 0.0));
        }
    }
    v
}

fn square(half: Real, z: Real) -> Vec<Point3> {
    vec![
        Point3::new(-half, -half, z),
        Point3::new(half, -half, z),
        Point3::new(half, half, z),
        Point3::new(-half, half, z),
    ]
}

/// Over a flat grid of spacing `G`, a point at height `h` above the grid's
/// extent is between `h` and `√(h² + G²/2)` from the nearest grid point.
fn above_grid_bounds(h: Real) -> (Real, Real) {
    (h, (h * h + 0.5 * G * G).sqrt())
}

#[test]
fn a_polygon_3cm_above_the_scan_is_within_lambda_and_7cm_is_not() {
    let scan = ScanIndex::new(&flat_grid()).unwrap();
    let cfg = ModelScanConfig::default();
    assert_eq!(cfg.lambda_m, 0.05);
    assert!(cfg.sample_spacing_m <= cfg.lambda_m / 5.0);

    let near = polygon_to_scan(&square(0.2, 0.03), &scan, &cfg).unwrap();
    let (lo, hi) = above_grid_bounds(0.03);
    assert!(
        near.max_m >= lo - 1e-12 && near.max_m <= hi + 1e-12,
        "{near:?}"
    );
    assert!(near.within_lambda);
    assert_eq!(near.within_lambda_fraction, 1.0);
    assert!((near.area_m2 - 0.16).abs() < 1e-12);
    assert!(near.normal[2] > 0.999_999);
    // Dense: at least one interior sample per spacing² of area.
    assert!(near.samples as Real >= near.area_m2 / cfg.sample_spacing_m.powi(2));

    let far = polygon_to_scan(&square(0.2, 0.07), &scan, &cfg).unwrap();
    let (lo, hi) = above_grid_bounds(0.07);
    assert!(
        far.max_m >= lo - 1e-12 && far.max_m <= hi + 1e-12,
        "{far:?}"
    );
    assert!(!far.within_lambda);
    assert_eq!(far.within_lambda_fraction, 0.0);
}

#[test]
fn a_polygon_hanging_over_the_scan_edge_is_caught_by_its_far_corner() {
    // The scan ends at x = 0.5; a polygon on the scan's plane reaching to
    // x = 0.6 has its far edge about 0.1 m from the nearest point (an oracle
    // for the perimeter and vertex samples), and only its inner part within λ.
    let scan = ScanIndex::new(&flat_grid()).unwrap();
    let cfg = ModelScanConfig::default();
    let poly = vec![
        Point3::new(0.2, -0.1, 0.0),
        Point3::new(0.6, -0.1, 0.0),
        Point3::new(0.6, 0.1, 0.0),
        Point3::new(0.2, 0.1, 0.0),
    ];
    let r = polygon_to_scan(&poly, &scan, &cfg).unwrap();
    // Its far edge x = 0.6 is 0.1 from the scan's last column x = 0.5, and up
    // to G/2 along it from the nearest point of that column.
    assert!(
        r.max_m >= 0.1 - 1e-12 && r.max_m <= (0.01 + 0.25 * G * G).sqrt() + 1e-12,
        "{r:?}"
    );
    assert!((r.max_at[0] - 0.6).abs() < 1e-9);
    assert!(!r.within_lambda);
    // Within λ up to x = 0.55: (0.55 − 0.2) / 0.4 of the area, to within a
    // grid column of samples.
    let want = 0.35 / 0.4;
    assert!(
        (r.within_lambda_fraction - want).abs() <= cfg.sample_spacing_m / 0.4 + 1e-9,
        "{}",
        r.within_lambda_fraction
    );
}

/// A model with one polygon built from sensor points on z = `h` (point3's
/// downward sensing axis), and an initial segment 1 m above the scan.
fn model_at(h: Real) -> SurfaceModel {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.add_initial_segment(&square(0.3, 1.0)).unwrap();
    for i in 0..6 {
        let mut pts = Vec::new();
        for j in 0..6 {
            for k in 0..3 {
                pts.push(Point3::new(
                    -0.1 + 0.04 * Real::from(i) + 0.01 * Real::from(k),
                    -0.1 + 0.04 * Real::from(j),
                    h,
                ));
            }
        }
        let axes = vec![-Vector3::z_axis(); pts.len()];
        m.update(&SensorSet::new(pts, axes).unwrap()).unwrap();
    }
    m
}

#[test]
fn model_polygons_are_scored_and_initial_segments_are_not() {
    let scan = ScanIndex::new(&flat_grid()).unwrap();
    let cfg = ModelScanConfig::default();
    for (h, within) in [(0.03, true), (0.07, false)] {
        let m = model_at(h);
        let r = model_to_scan(&m, &scan, &cfg).unwrap();
        let polygons = m
            .segments()
            .filter(|s| !s.is_initial() && s.as_polygon().is_some())
            .count();
        assert!(polygons >= 1);
        // The initial square at z = 1 would be ~1 m away: it is not scored.
        assert_eq!(r.polygons.len(), polygons);
        let (lo, hi) = above_grid_bounds(h);
        for p in &r.polygons {
            assert!(p.segment.is_some());
            assert!(p.max_m >= lo - 1e-9 && p.max_m <= hi + 1e-9, "{p:?}");
            assert_eq!(p.within_lambda, within);
        }
        let max = r.max_m.unwrap();
        assert!(max >= lo - 1e-9 && max <= hi + 1e-9);
        assert_eq!(r.polygons_beyond_lambda, if within { 0 } else { polygons });
        assert_eq!(r.within_lambda_fraction, if within { 1.0 } else { 0.0 });
        // Every vertex is h above the grid: all within λ = 0.05 m, or none.
        assert_eq!(
            r.vertices_within_lambda_fraction,
            if within { 1.0 } else { 0.0 }
        );
        // What run.json counts as modelled: the whole polygons' area, or none.
        let area: f64 = m
            .segments()
            .filter(|s| !s.is_initial())
            .filter_map(|s| s.as_polygon())
            .map(surface::Polygon::area)
            .sum();
        let modelled = ScanFigures::modelled_m2(&r);
        assert!(area > 0.0);
        assert!(
            (modelled - if within { area } else { 0.0 }).abs() < 1e-12,
            "{modelled} of {area} m²"
        );
    }
    // No polygons: nothing beyond λ, no maximum.
    let mut only_initial = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    only_initial.add_initial_segment(&square(0.3, 1.0)).unwrap();
    let r = model_to_scan(&only_initial, &scan, &cfg).unwrap();
    assert!(r.polygons.is_empty() && r.max_m.is_none());
    assert_eq!(r.vertices_within_lambda_fraction, 1.0);
}

#[test]
fn capsule_clearance_over_a_flat_scan_is_analytic() {
    let scan = ScanIndex::new(&flat_grid()).unwrap();
    // A horizontal capsule along the grid line y = 0 at height 0.2: the
    // points under its axis are 0.2 from it.
    let c = Capsule::new(
        Point3::new(-0.3, 0.0, 0.2),
        Point3::new(0.3, 0.0, 0.2),
        0.02,
    );
    assert!((scan.capsule_distance(&c) - 0.18).abs() < 1e-12);
    // A sphere (point3's body) above the middle of a grid cell.
    let s = Capsule::new(
        Point3::new(0.5 * G, 0.5 * G, 0.1),
        Point3::new(0.5 * G, 0.5 * G, 0.1),
        0.02,
    );
    let want = (0.5 * G * G + 0.01).sqrt() - 0.02;
    assert!((scan.capsule_distance(&s) - want).abs() < 1e-12);
    // A tilted capsule whose lower end is nearest: 0.1 straight down.
    let t = Capsule::new(Point3::new(0.0, 0.0, 0.1), Point3::new(0.1, 0.0, 0.3), 0.02);
    assert!((scan.capsule_distance(&t) - 0.08).abs() < 1e-12);
    // Points inside the capsule: clearance 0.
    let low = Capsule::new(
        Point3::new(0.0, 0.0, 0.01),
        Point3::new(0.1, 0.0, 0.01),
        0.02,
    );
    assert_eq!(scan.capsule_distance(&low), 0.0);
}

#[test]
fn point3_clearance_is_its_body_above_the_scan() {
    let scan = ScanIndex::new(&flat_grid()).unwrap();
    let robot = scenario::RobotChoice::Builtin("point3".into())
        .build()
        .unwrap();
    // The base 0.05 m up: the body at joints (0, 0, 0.1) is 0.15 m over the
    // scan, its 0.02 m sphere 0.13 m clear.
    let base = Isometry3::translation(0.0, 0.0, 0.05);
    let frames = robot.forward_kinematics(&[0.0, 0.0, 0.1]).unwrap();
    let d = scan_clearance(&robot, &frames, &base, &scan).unwrap();
    assert!((d - 0.13).abs() < 1e-12, "{d}");
}

fn data(rel: &str) -> String {
    format!("{}/../../data/{rel}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn run_clearance_over_the_mosd_scan_matches_brute_force() {
    let loaded = Scenario::load(&data("scenarios/mosd_boxes.toml")).unwrap();
    let World::Cloud(world) = loaded.build_world().unwrap() else {
        panic!("a point-cloud world")
    };
    let points = world.cloud().points.clone();
    // Start 0.06 m above box 1's top (the scenario starts δ = 0.1 above it):
    // closer than δ/2 = 0.05 once the body's 0.02 m radius is counted.
    let mut start = loaded.scenario.robot.start_joints.clone();
    start[2] -= 0.04;
    let options = FollowRunOptions {
        max_sets: 15,
        timings: false,
        start: Some(StartPose::Joints(start)),
        ..FollowRunOptions::default()
    };
    let setup = SimFollow::from_scenario(&loaded, &options).unwrap();
    let base = setup.rig.world_from_base();
    let run = setup.run(&AtomicBool::new(false), &mut |_, _| {}).unwrap();
    // The poses visited: each step's, and where the run ended. point3's
    // control point is its body's centre (a 0.02 m sphere), base = identity.
    assert_eq!(base, Isometry3::identity());
    let mut poses: Vec<Vec<Real>> = run.episode.rows.iter().map(|r| r.joints.clone()).collect();
    // The end pose was checked unless the follower stopped without moving.
    if !matches!(run.episode.end, RunEnd::Follower(_)) {
        poses.push(run.episode.end_joints.clone());
    }
    let brute: Vec<Real> = poses
        .iter()
        .map(|q| {
            let c = Point3::new(q[0], q[1], q[2]);
            (points
                .iter()
                .map(|p| (p - c).norm())
                .fold(Real::INFINITY, Real::min)
                - 0.02)
                .max(0.0)
        })
        .collect();
    let min = brute.iter().copied().fold(Real::INFINITY, Real::min);
    let got = run.judgement.min_scan_clearance_m.unwrap();
    assert!((got - min).abs() < 1e-9, "{got} vs brute force {min}");
    assert!(brute[0] < 0.05, "{}", brute[0]);
    assert_eq!(
        run.judgement.scan_close_poses,
        Some(brute.iter().filter(|d| **d < 0.05).count())
    );
    // No ground truth to collide with.
    assert!(run.judgement.min_clearance_m.is_none() && run.score.is_none());
    let json = serde_json::to_value(run.summary()).unwrap();
    assert_eq!(json["min_scan_clearance_m"], got);
    assert!(json["collisions"].is_null());
}
