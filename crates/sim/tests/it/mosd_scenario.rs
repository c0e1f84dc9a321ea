//! `data/scenarios/mosd_boxes.toml`, `mosd_learn5.toml` and `mosd_learn17.toml`:
//! real scans (mOSD learn0, learn5, learn17) as point-cloud worlds with the
//! fitted table as the initial segment and point3 0.1 m above a box. The
//! scenarios' numbers are recomputed here from the labelled scans (the last
//! two files were written by `sim/examples/table_scan_scenario.rs`, which
//! also writes the first one's numbers).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Point3, Real};
use hw::RangeSensors;
use scenario::table_fit::{fit_table, points_labelled};
use scenario::{LoadedScenario, Scenario};
use scene::World;
use sim::SimRig;
use std::sync::Arc;

fn data(rel: &str) -> String {
    format!("{}/../../data/{rel}", env!("CARGO_MANIFEST_DIR"))
}

/// The scenes: scenario file, scan, and the label of the box point3 starts
/// over.
const SCENES: [(&str, &str, i64); 3] = [
    ("mosd_boxes.toml", "mosd_learn0.pcd", 20),
    ("mosd_learn5.toml", "mosd_learn5.pcd", 20),
    ("mosd_learn17.toml", "mosd_learn17.pcd", 30),
];

fn loaded(file: &str) -> LoadedScenario {
    Scenario::load(&data(&format!("scenarios/{file}"))).unwrap()
}

/// The raw scan (camera frame) and its labels.
fn scan(file: &str) -> (Vec<Point3>, Vec<i64>) {
    let c =
        scene::io::load_cloud(std::path::Path::new(&data(&format!("pointclouds/{file}")))).unwrap();
    let labels = c.labels.clone().unwrap();
    (c.points, labels)
}

#[test]
fn the_scenarios_match_a_fresh_fit_of_their_scans() {
    for (file, cloud, _) in SCENES {
        the_scenario_matches_a_fresh_fit_of_the_scan(file, cloud);
    }
}

fn the_scenario_matches_a_fresh_fit_of_the_scan(file: &str, cloud: &str) {
    let l = loaded(file);
    let (points, labels) = scan(cloud);
    let table = points_labelled(&points, &labels, 1);
    let fit = fit_table(&table, &Point3::origin(), 0.02).unwrap();
    assert!(
        fit.rms_m < 0.003 && fit.p95_m < 0.005,
        "{} {}",
        fit.rms_m,
        fit.p95_m
    );
    // The cloud pose of the file is the fitted world_from_scan.
    let pose = l.scenario.scene.point_cloud.as_ref().unwrap().pose.unwrap();
    let file = pose.isometry();
    for p in table.iter().step_by(997) {
        assert!((file * p - fit.world_from_scan * p).norm() < 1e-6);
    }
    // The initial segment is the fitted outline.
    let poly = &l.scenario.initial_segments[0];
    assert_eq!(poly.len(), fit.polygon.len());
    for (a, b) in poly.iter().zip(&fit.polygon) {
        assert!((Point3::from(*a) - b).norm() < 1e-5, "{a:?} {b:?}");
    }
    // It is a valid initial segment for the surface model (simple, anticlockwise
    // about +z).
    let verts: Vec<Point3> = poly.iter().map(|v| Point3::from(*v)).collect();
    let mut m = surface::SurfaceModel::new(surface::SurfaceConfig::default()).unwrap();
    let id = m.add_initial_segment(&verts).unwrap();
    assert!(m.polygon(id).unwrap().normal().z > 0.999_999);
}

#[test]
fn the_table_polygons_lie_on_the_table_points() {
    for (file, cloud, _) in SCENES {
        the_table_polygon_lies_on_the_table_points(file, cloud);
    }
}

fn the_table_polygon_lies_on_the_table_points(file: &str, cloud: &str) {
    let l = loaded(file);
    let World::Cloud(world) = l.build_world().unwrap() else {
        panic!("a point-cloud world")
    };
    // The ε rule's ε, from the cloud (P§4.2).
    assert!(
        world.epsilon() > 0.001 && world.epsilon() < 0.02,
        "{}",
        world.epsilon()
    );
    let (_, labels) = scan(cloud);
    let table = points_labelled(&world.cloud().points, &labels, 1);
    // The polygon is on z = 0: the table points are within 1 cm of it (95 %),
    // and every vertex is within 1 cm of a table point.
    let mut off: Vec<Real> = table.iter().map(|p| p.z.abs()).collect();
    off.sort_by(Real::total_cmp);
    assert!(
        off[off.len() * 95 / 100] < 0.01,
        "{}",
        off[off.len() * 95 / 100]
    );
    for v in &l.scenario.initial_segments[0] {
        let v = Point3::from(*v);
        let near = table
            .iter()
            .map(|p| (p - v).norm())
            .fold(Real::INFINITY, Real::min);
        assert!(near < 0.01, "vertex {v:?}: nearest table point {near}");
    }
}

#[test]
fn point3_starts_delta_above_the_box_and_clear_of_the_scan() {
    for (file, cloud, box_label) in SCENES {
        starts_delta_above_the_box(file, cloud, box_label);
    }
}

fn starts_delta_above_the_box(file: &str, scan_file: &str, box_label: i64) {
    let l = loaded(file);
    let robot = l.build_robot().unwrap();
    let world = Arc::new(l.build_world().unwrap());
    let World::Cloud(cloud) = world.as_ref() else {
        panic!("a point-cloud world")
    };
    let q = l.scenario.robot.start_joints.clone();
    let start = Point3::new(q[0], q[1], q[2]);
    let (_, labels) = scan(scan_file);
    // Clear of every scan point by more than δ/2 (and of point3's 0.02 m body).
    let (nearest, label) = cloud
        .cloud()
        .points
        .iter()
        .zip(&labels)
        .map(|(p, l)| ((p - start).norm(), *l))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    assert!(nearest > 0.05, "{nearest}");
    // The sensor pointing down reads ≈ δ = 0.1 on the box.
    let mut rig = SimRig::new(
        robot,
        world.clone(),
        l.scenario.world_from_base(),
        &q,
        None,
        1,
    )
    .unwrap();
    let down = rig
        .robot()
        .range_finders
        .iter()
        .position(|m| m.axis.z < -0.999)
        .unwrap();
    let hit = rig.read_all().unwrap()[down].unwrap();
    assert!((hit.distance_m - 0.1).abs() < 0.01, "{hit:?}");
    let hit_label = cloud
        .cloud()
        .points
        .iter()
        .zip(&labels)
        .find(|(p, _)| (*p - hit.point).norm() < 1e-12)
        .map(|(_, l)| *l);
    assert_eq!(hit_label, Some(box_label), "{file}");
    // The nearest scan point is on that box too (its top, 0.1 m below).
    assert_eq!(label, box_label, "{file}");
    assert!(nearest < 0.1 + 0.01);
}
