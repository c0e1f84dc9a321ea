//! TSDF fusion and mesh extraction against analytic and simulated ground truth
//! (STYLE §11: tolerances from the resolution).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code may panic

use geom::{Isometry3, Point3, Real, Translation3, UnitQuaternion, Vector3};
use map::{TsdfConfig, TsdfIntegrator, TsdfMap};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scene::{MaterialId, RayCast, Scene, TriMesh, default_materials, primitives::cuboid};
use sensor::Sweep;
use sensor::{Scanner, ScannerConfig, SweepConfig};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// A nodding sweep (151 scans over 60° about the scanner's y axis) from
/// `world_from_target`: world_from_scanner = world_from_target · R_y(tilt).
fn sweep<W: RayCast>(world: &W, world_from_target: &Isometry3, noise: bool, seed: u64) -> Sweep {
    let mut config = ScannerConfig::default();
    config.noise.enabled = noise;
    config.material_range_bias = noise;
    let scanner = Scanner::new(config).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    scanner
        .nodding_sweep(world, world_from_target, &SweepConfig::default(), &mut rng)
        .unwrap()
}

fn pose(x: Real, y: Real, z: Real, r: UnitQuaternion) -> Isometry3 {
    Isometry3::from_parts(Translation3::new(x, y, z), r)
}

/// No two vertices at the same position, no triangle repeating a vertex or of
/// zero area, every index valid.
fn assert_clean(mesh: &TriMesh) {
    let n = mesh.vertices.len();
    let mut seen = HashSet::new();
    for v in &mesh.vertices {
        assert!(
            seen.insert([v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]),
            "duplicate vertex {v}"
        );
    }
    for t in &mesh.triangles {
        assert!(t.iter().all(|&i| (i as usize) < n));
        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "{t:?}");
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        assert!((b - a).cross(&(c - a)).norm() > 0.0, "degenerate {t:?}");
    }
}

/// Every directed edge at most once (consistent winding, at most two
/// triangles per edge); returns the number of edges without a partner
/// (boundary edges).
fn open_edges(mesh: &TriMesh) -> usize {
    let mut directed = HashSet::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            assert!(
                directed.insert((t[k], t[(k + 1) % 3])),
                "edge used twice the same way"
            );
        }
    }
    directed
        .iter()
        .filter(|(a, b)| !directed.contains(&(*b, *a)))
        .count()
}

#[test]
fn noiseless_plane_meshes_onto_the_plane() {
    let slab = cuboid(Point3::new(-2.0, -2.0, 1.0), Point3::new(2.0, 2.0, 1.05));
    let scene = Scene::from_mesh("slab", slab, default_materials(), MaterialId(0)).unwrap();
    let sweep = sweep(&scene, &Isometry3::identity(), false, 1);
    let mut tsdf = TsdfMap::new(TsdfConfig::default()).unwrap();
    let stats = tsdf.integrate_sweep(&sweep);
    assert!(stats.points > 40_000);
    tsdf.check_invariants().unwrap();
    let mesh = tsdf.extract_mesh();
    assert!(mesh.triangles.len() > 10_000, "{}", mesh.triangles.len());
    assert_clean(&mesh);
    open_edges(&mesh);
    let errors: Vec<Real> = mesh.vertices.iter().map(|v| (v.z - 1.0).abs()).collect();
    let mean = errors.iter().sum::<Real>() / errors.len() as Real;
    let max = errors.iter().copied().fold(0.0, Real::max);
    println!(
        "plane: {} vertices, mean |dz| {:.3} mm, max {:.3} mm",
        errors.len(),
        mean * 1e3,
        max * 1e3
    );
    // Projective distances along oblique rays bend the zero crossing a little
    // where incidence is high (up to ~64° at the field's corners): within 0.1
    // voxel on average, 0.6 voxel at worst, and 0.1 voxel at worst below the
    // sensor (|x|, |y| < 0.5 m: incidence under ~27°).
    assert!(mean < 0.001, "mean {mean}");
    assert!(max < 0.006, "max {max}");
    let central = mesh
        .vertices
        .iter()
        .filter(|v| v.x.abs().max(v.y.abs()) < 0.5)
        .map(|v| (v.z - 1.0).abs())
        .fold(0.0, Real::max);
    assert!(central < 0.001, "central max {central}");
    // Normals point down, toward the sensor below the plane.
    let down = mesh
        .iter_triangles()
        .filter(|t| (t.b - t.a).cross(&(t.c - t.a)).z < 0.0)
        .count();
    assert_eq!(down, mesh.triangles.len());
}

#[test]
fn closed_room_gives_a_watertight_mesh_facing_the_sensor() {
    // Rays from the centre of the box [−1, 1]³ in all directions (a Fibonacci
    // sphere), ending on its walls: the walls' inner faces close around the sensor.
    let n = 200_000;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let origin = Point3::new(0.013, -0.021, 0.007);
    let mut points = Vec::with_capacity(n);
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as Real + 0.5) / n as Real;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as Real;
        let d = Vector3::new(r * phi.cos(), r * phi.sin(), z);
        // First wall hit: the smallest positive t with |origin + t d|_∞ = 1.
        let t = (0..3)
            .filter(|&ax| d[ax] != 0.0)
            .map(|ax| (d[ax].signum() - origin[ax]) / d[ax])
            .fold(Real::INFINITY, Real::min);
        points.push(origin + d * t);
    }
    let origins = vec![origin; n];
    let mut tsdf = TsdfMap::new(TsdfConfig::with_voxel_m(0.02)).unwrap();
    tsdf.integrate_points(&origins, &points).unwrap();
    tsdf.check_invariants().unwrap();
    let mesh = tsdf.extract_mesh();
    assert_clean(&mesh);
    assert_eq!(open_edges(&mesh), 0, "the room's mesh has holes");
    // Euler characteristic of a sphere.
    let mut edges = HashSet::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    let chi = mesh.vertices.len() as i64 - edges.len() as i64 + mesh.triangles.len() as i64;
    assert_eq!(chi, 2);
    // Every triangle faces the sensor, and lies on a wall.
    for t in mesh.iter_triangles() {
        let c = Point3::from((t.a.coords + t.b.coords + t.c.coords) / 3.0);
        assert!((t.b - t.a).cross(&(t.c - t.a)).dot(&(origin - c)) > 0.0);
        let wall = c.coords.amax();
        assert!((wall - 1.0).abs() < 0.02, "{c}");
    }
}

/// Mean and 95th percentile distance of every `step`-th vertex to the scene.
fn distances(scene: &Scene, mesh: &TriMesh, step: usize) -> (Real, Real) {
    let mut d: Vec<Real> = mesh
        .vertices
        .iter()
        .step_by(step)
        .map(|v| scene.closest_point(v, 0.5).map_or(0.5, |(d, _, _)| d))
        .collect();
    d.sort_by(Real::total_cmp);
    let mean = d.iter().sum::<Real>() / d.len() as Real;
    (mean, d[(d.len() * 95) / 100])
}

/// Scanner poses inside bridge1's channel looking up, left, right, forward,
/// back and down (scanner z = the centre ray).
fn bridge_poses() -> Vec<Isometry3> {
    let rx = |deg: Real| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), deg.to_radians());
    let ry = |deg: Real| UnitQuaternion::from_axis_angle(&Vector3::y_axis(), deg.to_radians());
    vec![
        pose(0.317, 0.0, 0.7716, UnitQuaternion::identity()), // up (the start pose)
        pose(0.0, 0.2, 0.8, rx(-90.0)),                       // left (+y)
        pose(0.0, -0.2, 0.8, rx(90.0)),                       // right (−y)
        pose(0.2, 0.0, 0.9, ry(90.0)),                        // forward (+x)
        pose(-0.2, 0.0, 0.9, ry(-90.0)),                      // back (−x)
        pose(0.0, 0.0, 0.6, rx(180.0)),                       // down
    ]
}

#[test]
fn bridge1_from_six_sweeps_meshes_within_half_a_voxel() {
    let world = scene::builtin::scene("bridge1")
        .unwrap()
        .build(Path::new("."))
        .unwrap();
    let scene = world.as_scene().unwrap();
    let config = TsdfConfig::default();
    let mut tsdf = TsdfMap::new(config).unwrap();
    for (k, p) in bridge_poses().iter().enumerate() {
        let s = sweep(&world, p, true, 10 + k as u64);
        let stats = tsdf.integrate_sweep(&s);
        assert!(stats.points > 20_000, "sweep {k}: {stats:?}");
    }
    tsdf.check_invariants().unwrap();
    let mesh = tsdf.extract_mesh();
    assert_clean(&mesh);
    let open = open_edges(&mesh);
    let (mean, p95) = distances(scene, &mesh, 3);
    println!(
        "bridge1: {} blocks, {} vertices, {} triangles, {open} open edges, mean {:.2} mm, p95 {:.2} mm",
        tsdf.block_count(),
        mesh.vertices.len(),
        mesh.triangles.len(),
        mean * 1e3,
        p95 * 1e3
    );
    assert!(mesh.vertices.len() > 50_000);
    assert!(mean <= 0.5 * config.voxel_m, "mean distance {mean}");
}

#[test]
fn fusion_is_deterministic_and_grid_equals_list() {
    let world = scene::builtin::scene("bridge1")
        .unwrap()
        .build(Path::new("."))
        .unwrap();
    let s = sweep(&world, &bridge_poses()[1], true, 5);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut tsdf = TsdfMap::new(TsdfConfig::default()).unwrap();
            tsdf.integrate_sweep(&s);
            tsdf.extract_mesh()
        })
    };
    let a = run(1);
    let b = run(2);
    assert_eq!(a, b);
    let (origins, points) = (s.origins(), s.positions());
    let mut from_list = TsdfMap::new(TsdfConfig::default()).unwrap();
    from_list.integrate_points(&origins, &points).unwrap();
    assert_eq!(from_list.extract_mesh(), a);
}

#[test]
fn bad_input_and_config_are_errors() {
    let mut tsdf = TsdfMap::new(TsdfConfig::default()).unwrap();
    let o = Point3::origin();
    let e = tsdf
        .integrate_points(&[o], &[Point3::new(Real::NAN, 0.0, 1.0)])
        .unwrap_err();
    assert!(e.to_string().contains("point 0"), "{e}");
    assert_eq!(tsdf.block_count(), 0);
    for bad in [
        TsdfConfig {
            truncation_m: 0.001,
            ..TsdfConfig::default()
        },
        TsdfConfig {
            block_size: 1,
            ..TsdfConfig::default()
        },
        // A band of 200 voxels each side (an audit's voxel_m = 0.0002 with
        // the default truncation took 8 GB and aborted).
        TsdfConfig {
            voxel_m: 0.0002,
            ..TsdfConfig::default()
        },
        TsdfConfig {
            max_range_m: 0.0,
            ..TsdfConfig::default()
        },
        TsdfConfig {
            voxel_m: Real::NAN,
            ..TsdfConfig::default()
        },
    ] {
        assert!(TsdfMap::new(bad).is_err());
    }
    // Out-of-window ranges are skipped, not errors.
    let stats = tsdf
        .integrate_points(
            &[o, o],
            &[Point3::new(0.0, 0.0, 0.01), Point3::new(0.0, 0.0, 9.0)],
        )
        .unwrap();
    assert_eq!(stats.skipped, 2);
    assert_eq!(tsdf.block_count(), 0);
    let _: HashMap<u8, u8> = HashMap::new();
}

#[test]
fn merged_integrator_bundles_returns_per_voxel() {
    let world = scene::builtin::scene("bridge1")
        .unwrap()
        .build(Path::new("."))
        .unwrap();
    let scene = world.as_scene().unwrap();
    let merged = TsdfConfig {
        integrator: TsdfIntegrator::Merged,
        ..TsdfConfig::default()
    };
    // One return per voxel: merging changes nothing.
    let origin = Point3::new(0.3, 0.0, 0.77);
    let points: Vec<Point3> = (0..40)
        .map(|i| Point3::new(0.0 + 0.025 * Real::from(i), 0.105, 1.52))
        .collect();
    let origins = vec![origin; points.len()];
    let mut a = TsdfMap::new(TsdfConfig::default()).unwrap();
    let mut b = TsdfMap::new(merged).unwrap();
    a.integrate_points(&origins, &points).unwrap();
    b.integrate_points(&origins, &points).unwrap();
    assert_eq!(a.block_keys(), b.block_keys());
    let key = map::VoxelKey::of_point(&Point3::new(0.2, 0.105, 1.51), 0.01).unwrap();
    assert_eq!(a.voxel(key), b.voxel(key));
    assert!(a.voxel(key).unwrap().weight > 0.0);
    // A real sweep: fewer updates, same accuracy bound, deterministic.
    let s = sweep(&world, &bridge_poses()[0], true, 21);
    let mut simple = TsdfMap::new(TsdfConfig::default()).unwrap();
    let mut m1 = TsdfMap::new(merged).unwrap();
    let us = simple.integrate_sweep(&s);
    let um = m1.integrate_sweep(&s);
    assert_eq!(us.points, um.points);
    assert!(um.voxel_updates < us.voxel_updates, "{um:?} vs {us:?}");
    let mesh = m1.extract_mesh();
    assert_clean(&mesh);
    let (mean, _) = distances(scene, &mesh, 3);
    assert!(mean <= 0.005, "{mean}");
    let mut m2 = TsdfMap::new(merged).unwrap();
    m2.integrate_sweep(&s);
    assert_eq!(m2.extract_mesh(), mesh);
}

/// Every voxel of the map, with its value: blocks of any size hold the same
/// voxels with the same values to the bit (each voxel's updates are applied
/// in ray order, whichever block it falls in); with blocks of 2 voxels most
/// bands cross several blocks, with 64 most lie in one.
#[test]
fn the_block_size_does_not_change_any_voxel() {
    let world = scene::builtin::scene("bridge1")
        .unwrap()
        .build(Path::new("."))
        .unwrap();
    let s = sweep(&world, &bridge_poses()[2], true, 7);
    let voxels = |block_size: usize| {
        let mut tsdf = TsdfMap::new(TsdfConfig {
            block_size,
            dropoff: true,
            ..TsdfConfig::default()
        })
        .unwrap();
        tsdf.integrate_sweep(&s);
        let bs = block_size as i32;
        let mut out = std::collections::BTreeMap::new();
        for b in tsdf.block_keys() {
            let f = b.first_voxel(bs).coords();
            for (x, y, z) in
                (0..bs).flat_map(|x| (0..bs).flat_map(move |y| (0..bs).map(move |z| (x, y, z))))
            {
                let key = map::VoxelKey::new(f[0] + x, f[1] + y, f[2] + z);
                let v = tsdf.voxel(key).unwrap();
                if v.weight > 0.0 {
                    out.insert(key, (v.distance_m.to_bits(), v.weight.to_bits()));
                }
            }
        }
        out
    };
    let small = voxels(2);
    assert!(small.len() > 10_000, "{}", small.len());
    assert_eq!(small, voxels(8));
    assert_eq!(small, voxels(64));
}
