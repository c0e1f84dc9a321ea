//! Sensor sets taken by a surface follower (P ch. 3), fed to the model.
//!
//! `data/follower_cube_point3_40.jsonl` holds the first 40 sets the `follow`
//! crate's point3 robot took on the built-in cube, δ = 0.1 m above its top
//! face (z = 1 m, x, y ∈ [−0.5, 0.5]): 26 range finders give 9 points a set on
//! a 0.1 m grid, and successive sets are up to 0.1 m apart (recorded with the
//! harness of `crates/follow/tests/support`, noise-free, seed 1).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use geom::{Point3, Real};
use surface::{SurfaceConfig, SurfaceModel};

fn replay() -> SurfaceModel {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/follower_cube_point3_40.jsonl"
    );
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let sets = surface::read_sets_jsonl(file, path).unwrap();
    assert_eq!(sets.len(), 40);
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.add_initial_segment(&[
        Point3::new(-2.0, -2.0, 0.0),
        Point3::new(2.0, -2.0, 0.0),
        Point3::new(2.0, 2.0, 0.0),
        Point3::new(-2.0, 2.0, 0.0),
    ])
    .unwrap();
    for s in &sets {
        m.update(s).unwrap();
        m.check_invariants().unwrap();
    }
    m
}

/// The top face is one polygon on the true face, and every point left as a
/// point segment is at least λ from it (P§2.4.2 merges points closer than λ).
/// Before: a point 3 cm from the perimeter failed to merge (the λ-circle left
/// an edge within 10⁻⁸ m of its end vertex), and a diamond of 5 points 4.6 cm
/// beside the face found no bridge (P§2.4.3) and stayed a second polygon.
#[test]
fn follower_sets_build_one_top_polygon() {
    let m = replay();
    let lambda = m.config().lambda;
    let polys: Vec<_> = m
        .segments()
        .filter_map(|s| s.as_polygon().filter(|p| !p.is_initial()))
        .collect();
    assert_eq!(polys.len(), 1, "one polygon for the top face");
    let top = polys[0];
    assert!((top.normal().z - 1.0).abs() < 1e-9);
    for v in top.vertices() {
        // Ground truth: on the top face, its vertices sensor points or on
        // segments between them.
        assert!((v.z - 1.0).abs() < 1e-9);
        assert!(v.x.abs() <= 0.5 + 1e-9 && v.y.abs() <= 0.5 + 1e-9, "{v:?}");
    }
    let mut points = 0;
    for s in m.segments() {
        if let Some(p) = s.as_point() {
            points += 1;
            let d: Real = top.distance_to_point(&p.centroid());
            assert!(d >= lambda * (1.0 - 1e-6), "a point {d} m from the face");
        }
    }
    assert!(points > 0);
}
