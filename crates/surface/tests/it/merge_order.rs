//! The order in which a new point tries the polygons near it (P§2.3 step
//! 2(a); `SurfaceConfig::merge_order`), on a hand-made case: two faces 20°
//! apart with a gap between them, and one point on the newer face's plane
//! within λ of both polygons and 3.6 mm off the older one's plane. Both
//! mergers are valid; the order decides which face the point joins.

use geom::{Point3, Real, Vector3, unit};
use surface::{MergeOrder, SensorSet, SurfaceConfig, SurfaceModel};

const TILT_DEG: Real = 20.0;

/// Height of the newer face's plane: through the line x = 0.2, z = 0.5,
/// rising by tan 20° along x.
fn tilted_z(x: Real) -> Real {
    0.5 + (x - 0.2) * TILT_DEG.to_radians().tan()
}

/// A grid of points 2 cm apart over `x0..=x1` × `0..=0.2` on `z(x)`, seen
/// from above.
fn face(x0: Real, x1: Real, z: impl Fn(Real) -> Real) -> SensorSet {
    let down = unit(-Vector3::z()).unwrap();
    let nx = ((x1 - x0) / 0.02).round() as usize;
    let points: Vec<Point3> = (0..=nx)
        .flat_map(|i| (0..=10).map(move |j| (i, j)))
        .map(|(i, j)| {
            let x = x0 + 0.02 * i as Real;
            Point3::new(x, 0.02 * j as Real, z(x))
        })
        .collect();
    let axes = vec![down; points.len()];
    SensorSet::new(points, axes).unwrap()
}

/// The points of the flat (older) and the tilted (newer) polygon.
fn counts(m: &SurfaceModel) -> (u64, u64) {
    let (mut flat, mut tilted) = (0, 0);
    for s in m.segments() {
        let Some(p) = s.as_polygon() else { continue };
        if p.is_initial() {
            continue;
        }
        let tilt = p.normal().z.acos().to_degrees();
        if tilt < 1.0 {
            flat += s.points();
        } else if (tilt - TILT_DEG).abs() < 1.0 {
            tilted += s.points();
        } else {
            panic!("a polygon tilted {tilt:.2}°");
        }
    }
    (flat, tilted)
}

/// The model after both faces and then the one point; the polygons' point
/// counts before and after the point.
fn run(order: MergeOrder) -> ((u64, u64), (u64, u64)) {
    let mut m = SurfaceModel::new(SurfaceConfig {
        merge_order: order,
        ..SurfaceConfig::default()
    })
    .unwrap();
    m.update(&face(0.0, 0.18, |_| 0.5)).unwrap();
    m.update(&face(0.24, 0.4, tilted_z)).unwrap();
    m.check_invariants().unwrap();
    let before = counts(&m);
    let x = 0.21;
    let point = Point3::new(x, 0.1, tilted_z(x));
    let set = SensorSet::new(vec![point], vec![unit(-Vector3::z()).unwrap()]).unwrap();
    m.update(&set).unwrap();
    m.check_invariants().unwrap();
    (before, counts(&m))
}

#[test]
fn a_point_joins_the_polygon_nearest_its_plane() {
    let (before, after) = run(MergeOrder::NearestPlane);
    assert_eq!(before, (11 * 10, 11 * 9), "the two faces as fed");
    assert_eq!(after, (before.0, before.1 + 1), "joined the tilted face");
}

#[test]
fn in_the_thesis_order_a_point_joins_the_oldest_polygon() {
    let (before, after) = run(MergeOrder::Thesis);
    assert_eq!(before, (11 * 10, 11 * 9), "the two faces as fed");
    assert_eq!(after, (before.0 + 1, before.1), "joined the flat face");
}

#[test]
fn the_order_is_read_from_a_config() {
    let c: SurfaceConfig = serde_json::from_str(r#"{"merge_order": "thesis"}"#).unwrap();
    assert_eq!(c.merge_order, MergeOrder::Thesis);
    assert_eq!(
        SurfaceConfig::default().merge_order,
        MergeOrder::NearestPlane
    );
    let e = serde_json::from_str::<SurfaceConfig>(r#"{"merge_order": "oldest"}"#).unwrap_err();
    assert!(e.to_string().contains("nearest_plane"), "{e}");
}
