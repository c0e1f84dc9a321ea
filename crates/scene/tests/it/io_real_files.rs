//! Every third-party file shipped in `data/` loads through `scene::io`, with the
//! counts and extents recorded in `data/SOURCES.md` and `shared/data/SOURCES.md`.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers outside #[test] functions fail the test on any error"
)]

use geom::{Point3, Real};
use scene::io::{self, PcdData};
use scene::{PointCloud, TriMesh};
use std::collections::BTreeMap;

use crate::io_fixtures;
use io_fixtures::data;

fn mesh(rel: &str) -> TriMesh {
    io::load_mesh(&data(rel), 1.0).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn cloud(rel: &str) -> PointCloud {
    io::load_cloud(&data(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Bounding box corners of a point set.
fn bbox(points: &[Point3]) -> ([Real; 3], [Real; 3]) {
    let mut lo = [Real::INFINITY; 3];
    let mut hi = [Real::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

fn assert_close(actual: [Real; 3], expected: [Real; 3], tol: Real, what: &str) {
    for k in 0..3 {
        assert!(
            (actual[k] - expected[k]).abs() <= tol,
            "{what}[{k}] = {} but expected {} ± {tol}",
            actual[k],
            expected[k]
        );
    }
}

fn extent(points: &[Point3]) -> [Real; 3] {
    let (lo, hi) = bbox(points);
    [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]
}

fn label_counts(c: &PointCloud) -> BTreeMap<i64, usize> {
    let mut m = BTreeMap::new();
    for l in c.labels.as_ref().expect("labels") {
        *m.entry(*l).or_default() += 1;
    }
    m
}

fn assert_unit_normals(c: &PointCloud, tol: Real) {
    let normals = c.normals.as_ref().expect("normals");
    assert_eq!(normals.len(), c.points.len());
    for (i, n) in normals.iter().enumerate() {
        assert!(
            (n.norm() - 1.0).abs() < tol,
            "normal {i} has norm {}",
            n.norm()
        );
    }
}

#[test]
fn truss_bridge_obj() {
    let m = mesh("meshes/truss_bridge_meters.obj");
    assert_eq!(m.vertices.len(), 2432);
    assert_eq!(m.triangles.len(), 3404);
    // SOURCES: open surfaces, 908 boundary edges.
    assert_eq!(m.boundary_edge_count(), 908);
    let (lo, hi) = bbox(&m.vertices);
    assert_close(lo, [-4.2359, -7.8068, -0.9310], 1e-4, "truss min");
    assert_close(hi, [4.2359, 7.8068, 3.9505], 1e-4, "truss max");
}

#[test]
fn truss_bridge_scale_multiplies_coordinates() {
    let metres = mesh("meshes/truss_bridge_meters.obj");
    let mm = io::load_mesh(&data("meshes/truss_bridge_meters.obj"), 1000.0).unwrap();
    assert_eq!(mm.triangles, metres.triangles);
    for (a, b) in metres.vertices.iter().zip(&mm.vertices) {
        assert!((a * 1000.0 - b).norm() < 1e-9);
    }
}

#[test]
fn cinder_block_obj_is_closed() {
    let m = mesh("meshes/cinder_block_meters.obj");
    assert_eq!(m.triangles.len(), 84);
    assert_eq!(m.vertices.len(), 40);
    assert_eq!(m.boundary_edge_count(), 0);
    assert_close(
        extent(&m.vertices),
        [0.4348, 0.2032, 0.2032],
        1e-4,
        "cinder extent",
    );
    assert!(bbox(&m.vertices).0[2].abs() < 1e-6, "base at z = 0");
}

#[test]
fn stud_2x4_obj() {
    let m = mesh("meshes/2x4x48_meters.obj");
    assert_eq!(m.triangles.len(), 152);
    assert_eq!(m.vertices.len(), 40);
    assert_close(
        extent(&m.vertices),
        [1.2192, 0.0396, 0.0905],
        1e-4,
        "2x4 extent",
    );
}

#[test]
fn sugar_box_obj_loads_without_its_mtl() {
    // The file says `mtllib 004_sugar_box_textured.mtl`, which is not shipped.
    let path = data("meshes/004_sugar_box_textured.obj");
    assert!(!path.with_extension("mtl").exists());
    let m = io::load_mesh(&path, 1.0).unwrap();
    assert_eq!(m.vertices.len(), 8194);
    assert_eq!(m.triangles.len(), 16384);
    assert_eq!(m.boundary_edge_count(), 0, "closed scan");
    assert_close(
        extent(&m.vertices),
        [0.0495, 0.0942, 0.176],
        1e-3,
        "sugar box extent",
    );
    // First vertex line of the file: v -0.013735 -0.061919 0.000994, used by face 1.
    let first = m.vertices[m.triangles[0][0] as usize];
    assert_close(
        [first.x, first.y, first.z],
        [-0.013_735, -0.061_919, 0.000_994],
        1e-8,
        "first vertex",
    );
}

#[test]
fn ur5_collision_stls() {
    for (name, triangles) in [
        ("base", 578),
        ("shoulder", 674),
        ("upper_arm", 1176),
        ("forearm", 1050),
        ("wrist_1", 702),
        ("wrist_2", 702),
        ("wrist_3", 446),
    ] {
        let m = mesh(&format!("robots/ur5/meshes/ur5/collision/{name}.stl"));
        assert_eq!(m.triangles.len(), triangles, "{name}");
        assert!(!m.vertices.is_empty());
        // Link meshes are tens of centimetres across.
        let e = extent(&m.vertices);
        assert!(
            e.iter().all(|&d| d > 0.01 && d < 1.0),
            "{name} extent {e:?}"
        );
    }
}

#[test]
fn mosd_learn0_pcd() {
    let c = cloud("pointclouds/mosd_learn0.pcd");
    assert_eq!(c.points.len(), 182_292);
    assert!(c.normals.is_none() && c.intensities.is_none());
    let labels = label_counts(&c);
    assert_eq!(c.labels.as_ref().unwrap().len(), c.points.len());
    assert_eq!(labels.get(&20), Some(&20_792));
    assert_eq!(labels.get(&30), Some(&8_177));
    assert!(labels.contains_key(&1), "table label");
    assert!(
        !labels.contains_key(&0),
        "label 0 marks NaN pixels, all dropped"
    );
    let (lo, hi) = bbox(&c.points);
    assert_close(lo, [-0.75, -0.21, 0.58], 0.01, "learn0 min");
    assert_close(hi, [0.63, 0.29, 1.30], 0.01, "learn0 max");
    let h = io::read_pcd_header(&data("pointclouds/mosd_learn0.pcd")).unwrap();
    assert_eq!((h.width, h.height, h.points), (640, 480, 307_200));
    assert_eq!(h.data, PcdData::BinaryCompressed);
    let names: Vec<&str> = h.fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["label", "x", "y", "z", "rgba"]);
}

#[test]
fn mosd_learn5_and_17_pcd() {
    for (file, finite, l20, l30) in [
        ("pointclouds/mosd_learn5.pcd", 199_001, 28_034, 6_088),
        ("pointclouds/mosd_learn17.pcd", 197_828, 9_356, 11_914),
    ] {
        let c = cloud(file);
        assert_eq!(c.points.len(), finite, "{file}");
        let labels = label_counts(&c);
        assert_eq!(labels.get(&20), Some(&l20), "{file}");
        assert_eq!(labels.get(&30), Some(&l30), "{file}");
        // Camera frame: everything in front of the sensor.
        assert!(c.points.iter().all(|p| p.z > 0.3 && p.z < 3.0), "{file}");
    }
}

#[test]
fn pcl_milk_pcd() {
    let c = cloud("pointclouds/pcl_milk.pcd");
    assert_eq!(c.points.len(), 13_704);
    assert!(c.normals.is_none() && c.labels.is_none());
    let (lo, hi) = bbox(&c.points);
    assert_close(lo, [-0.140, -0.264, 0.714], 0.001, "milk min");
    assert_close(hi, [0.014, -0.012, 0.891], 0.001, "milk max");
}

#[test]
fn pcl_bun0_ascii_pcd_with_normals() {
    let c = cloud("pointclouds/pcl_bun0.pcd");
    assert_eq!(c.points.len(), 397);
    assert_unit_normals(&c, 1e-5);
    // First data line: 0.0054215998 0.11349 0.040748999 -0.16884723 -0.45159745 -0.87609947 …
    // The fields are F 4: each value is the nearest f32, as a binary file would hold.
    let f = |text: &str| f64::from(text.parse::<f32>().unwrap());
    assert_eq!(
        c.points[0],
        Point3::new(f("0.0054215998"), f("0.11349"), f("0.040748999"))
    );
    let n = c.normals.as_ref().unwrap()[0];
    assert_eq!(
        [n.x, n.y, n.z],
        [f("-0.16884723"), f("-0.45159745"), f("-0.87609947")]
    );
    let (lo, hi) = bbox(&c.points);
    assert_close(lo, [-0.094, 0.037, -0.055], 0.001, "bun0 min");
    assert_close(hi, [0.060, 0.185, 0.058], 0.001, "bun0 max");
}

#[test]
fn pc2beam_text_cloud() {
    let c = cloud("pointclouds/pc2beam_steel_beams_test_points.txt");
    assert_eq!(c.points.len(), 3907);
    assert_unit_normals(&c, 1e-3);
    let labels = label_counts(&c);
    assert_eq!(labels, BTreeMap::from([(0, 967), (1, 2940)]));
    let (lo, hi) = bbox(&c.points);
    assert!(lo[0] > -0.85 && hi[0] < -0.54, "x range {lo:?} {hi:?}");
    assert!(lo[1] > 17.91 && hi[1] < 19.12, "y range {lo:?} {hi:?}");
    assert!(lo[2] > 6.13 && hi[2] < 7.06, "z range {lo:?} {hi:?}");
    assert_close(lo, [-0.84, 17.92, 6.14], 0.01, "pc2beam min");
    assert_close(hi, [-0.55, 19.11, 7.05], 0.01, "pc2beam max");
    // First line of the file.
    assert_close(
        [c.points[0].x, c.points[0].y, c.points[0].z],
        [-0.6909, 18.350_901, 6.6215],
        1e-12,
        "pc2beam point 0",
    );
}

#[test]
fn mesh_vertices_as_cloud() {
    let c = io::load_cloud_or_mesh_vertices(&data("meshes/cinder_block_meters.obj")).unwrap();
    assert_eq!(c.points.len(), 40);
    // The OBJ's faces give every vertex a unit normal.
    let normals = c.normals.as_ref().unwrap();
    assert!(normals.iter().all(|n| (n.norm() - 1.0).abs() < 1e-9));
    let c = io::load_cloud_or_mesh_vertices(&data("pointclouds/pcl_milk.pcd")).unwrap();
    assert_eq!(c.points.len(), 13_704);
    assert!(c.normals.is_none());
}

/// A PLY mesh (like `surveyor map`'s TSDF mesh) read as a cloud: its vertices
/// in file order with the area-weighted normals of their faces, outward for a
/// closed outward-wound mesh; a PLY cloud without faces gets no normals.
#[test]
fn ply_mesh_vertices_carry_face_normals() {
    let dir = tempfile::tempdir().unwrap();
    let centre = Point3::new(1.0, 2.0, 3.0);
    let cube = geom::primitives::cuboid(
        centre - geom::Vector3::repeat(0.5),
        centre + geom::Vector3::repeat(0.5),
    );
    let path = dir.path().join("cube.ply");
    io::write_mesh_ply(&path, &cube).unwrap();
    let c = io::load_cloud_or_mesh_vertices(&path).unwrap();
    assert_eq!(c.points, cube.vertices);
    let normals = c.normals.unwrap();
    for (p, n) in c.points.iter().zip(&normals) {
        let out = (p - centre) / (p - centre).norm();
        assert!(n.dot(&out) > 0.5, "{p:?}: {n:?}");
    }
    // The plain cloud reader ignores the faces.
    assert!(io::load_cloud(&path).unwrap().normals.is_none());
    let cloud_path = dir.path().join("cloud.ply");
    let column = |k: usize| -> Vec<f32> { cube.vertices.iter().map(|v| v[k] as f32).collect() };
    let (x, y, z) = (column(0), column(1), column(2));
    io::write_ply_vertices_file(&cloud_path, &["x", "y", "z"], &[&x, &y, &z]).unwrap();
    assert!(
        io::load_cloud_or_mesh_vertices(&cloud_path)
            .unwrap()
            .normals
            .is_none()
    );
}

/// Load times of the real files (release build: `cargo test --release -p scene
/// --test it io_real_files -- --ignored --nocapture`). Prints, asserts nothing.
#[test]
#[ignore = "timing report, run by hand in release mode"]
fn load_timings() {
    for rel in [
        "pointclouds/mosd_learn0.pcd",
        "pointclouds/mosd_learn5.pcd",
        "pointclouds/pcl_milk.pcd",
        "pointclouds/pcl_bun0.pcd",
        "pointclouds/pc2beam_steel_beams_test_points.txt",
        "meshes/004_sugar_box_textured.obj",
        "meshes/truss_bridge_meters.obj",
        "robots/ur5/meshes/ur5/collision/upper_arm.stl",
    ] {
        let path = data(rel);
        let is_mesh = !rel.starts_with("pointclouds/");
        let mut best = f64::INFINITY;
        for _ in 0..10 {
            let t = std::time::Instant::now();
            let n = if is_mesh {
                io::load_mesh(&path, 1.0).unwrap().triangles.len()
            } else {
                io::load_cloud(&path).unwrap().points.len()
            };
            best = best.min(t.elapsed().as_secs_f64());
            std::hint::black_box(n);
        }
        println!("{rel}: best of 10 = {:.2} ms", best * 1e3);
    }
}
