#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
//! Acceptance 1: real scans fed as sets of 20–30 nearby points, checked after
//! every update.

use crate::support;

use geom::{Point3, UnitVector3, unit};
use support::{chunk_sets, feed_checked, voxel_subsample};
use surface::{SurfaceConfig, SurfaceModel};

fn data(name: &str) -> std::path::PathBuf {
    std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/pointclouds"
    ))
    .join(name)
}

/// Points of a camera-frame cloud (optionally only some labels) with sensing
/// axes from the camera origin.
fn camera_cloud(name: &str, labels: Option<&[i64]>) -> (Vec<Point3>, Vec<UnitVector3>) {
    let c = scene::io::load_cloud(&data(name)).unwrap();
    let mut pts = Vec::new();
    let mut axes = Vec::new();
    for (i, p) in c.points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            continue;
        }
        if let (Some(want), Some(l)) = (labels, c.labels.as_ref())
            && !want.contains(&l[i])
        {
            continue;
        }
        let Some(a) = unit(p.coords) else { continue };
        pts.push(*p);
        axes.push(a);
    }
    (pts, axes)
}

fn feed(points: &[Point3], axes: &[UnitVector3], voxel: f64) -> SurfaceModel {
    let (p, a) = voxel_subsample(points, axes, voxel);
    let sets = chunk_sets(&p, &a, 26, 0.005);
    assert!(sets.iter().all(|s| (1..=30).contains(&s.len())));
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    feed_checked(&mut m, &sets);
    let st = m.stats();
    println!("{} points in {} sets -> {st:?}", p.len(), sets.len());
    m
}

/// The largest polygons' areas, descending.
fn big_areas(m: &SurfaceModel, n: usize) -> Vec<f64> {
    let mut a: Vec<f64> = m
        .segments()
        .filter_map(surface::Segment::as_polygon)
        .map(surface::Polygon::area)
        .collect();
    a.sort_by(|x, y| y.total_cmp(x));
    a.truncate(n);
    a
}

#[test]
fn mosd_boxes() {
    for f in ["mosd_learn0.pcd", "mosd_learn5.pcd", "mosd_learn17.pcd"] {
        let (p, a) = camera_cloud(f, Some(&[20, 30]));
        let m = feed(&p, &a, 0.003);
        let areas = big_areas(&m, 3);
        println!("{f}: largest polygons {areas:.4?}");
        // Box faces of a few dm² each are modelled by large polygons.
        assert!(areas[0] > 0.005, "{f}: {areas:?}");
    }
}

#[test]
fn milk_carton() {
    let (p, a) = camera_cloud("pcl_milk.pcd", None);
    let m = feed(&p, &a, 0.0);
    let areas = big_areas(&m, 3);
    println!("milk: largest polygons {areas:.4?}");
    assert!(areas[0] > 0.002, "{areas:?}");
}

#[test]
fn pc2beam_beams() {
    let c = scene::io::load_cloud(&data("pc2beam_steel_beams_test_points.txt")).unwrap();
    let normals = c.normals.as_ref().unwrap();
    let mut pts = Vec::new();
    let mut axes = Vec::new();
    for (p, n) in c.points.iter().zip(normals) {
        if let Some(a) = unit(-n) {
            pts.push(*p);
            axes.push(a);
        }
    }
    let m = feed(&pts, &axes, 0.0);
    let areas = big_areas(&m, 3);
    println!("pc2beam: largest polygons {areas:.4?}");
    assert!(areas[0] > 0.01, "{areas:?}");
}

/// All points of every scan, sets of 20 and 30, invariants after every update.
/// Run with `cargo test -p surface --release --test it real_data -- --ignored`.
#[test]
#[ignore = "long: full-resolution scans"]
fn stress_full_scans() {
    for f in [
        "mosd_learn0.pcd",
        "mosd_learn5.pcd",
        "mosd_learn17.pcd",
        "pcl_milk.pcd",
    ] {
        let labels: Option<&[i64]> = if f.starts_with("mosd") {
            Some(&[20, 30])
        } else {
            None
        };
        let (p, a) = camera_cloud(f, labels);
        for (size, cell) in [(20, 0.002), (30, 0.01)] {
            let sets = chunk_sets(&p, &a, size, cell);
            let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
            feed_checked(&mut m, &sets);
            println!("{f} sets of {size}: {:?}", m.stats());
        }
    }
}
