//! Shared fixtures of the map tests and benches: fused scanner sweeps of the
//! built-in bridge1 scene (the map crate itself depends on neither the robot
//! nor the simulator, so the sweeps are posed directly).

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use geom::{Isometry3, Point3, Real, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use scene::{Scene, World};
use sensor::{Scanner, ScannerConfig};
use std::path::Path;

/// A fused cloud with its per-point sensor origins.
pub struct Fused {
    /// The world the points came from.
    pub world: World,
    /// Measured points.
    pub points: Vec<Point3>,
    /// The scanner origin of each point.
    pub origins: Vec<Point3>,
}

impl Fused {
    /// The triangle scene.
    pub fn scene(&self) -> &Scene {
        self.world.as_scene().unwrap()
    }
}

/// The bridge1 world.
pub fn bridge1() -> World {
    scene::builtin::scene("bridge1")
        .unwrap()
        .build(Path::new("."))
        .unwrap()
}

/// Scanner positions (inside the channel) and the direction of the centre
/// ray at zero tilt: up, left, right, forward, back, and two diagonals.
pub fn viewpoints() -> Vec<(Point3, Vector3)> {
    vec![
        (Point3::new(0.0, 0.0, 0.6), Vector3::new(0.0, 0.0, 1.0)),
        (Point3::new(0.3, -0.3, 0.9), Vector3::new(0.0, 1.0, 0.0)),
        (Point3::new(-0.3, 0.3, 0.9), Vector3::new(0.0, -1.0, 0.0)),
        (Point3::new(-0.4, 0.1, 1.0), Vector3::new(1.0, 0.0, 0.2)),
        (Point3::new(0.4, -0.1, 1.0), Vector3::new(-1.0, 0.0, 0.2)),
        (Point3::new(0.0, 0.2, 0.4), Vector3::new(0.0, -1.0, 1.0)),
        (Point3::new(0.0, -0.2, 0.4), Vector3::new(0.0, 1.0, 1.0)),
    ]
}

/// `world_from_scanner = T(p) · R · R_y(tilt)` with `R` turning the scanner's
/// `z` (centre ray) onto `dir`, the scan plane containing world `x` × `dir`.
pub fn pose(p: Point3, dir: Vector3, tilt_rad: Real) -> Isometry3 {
    let r = UnitQuaternion::rotation_between(&Vector3::z(), &dir).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), tilt_rad);
    Isometry3::from_parts(Translation3::from(p.coords), r * tilt)
}

/// Sweeps of bridge1 from the first `views` viewpoints, tilting ±30° in
/// `tilt_step_deg` steps, fused into one cloud.
pub fn fused_bridge1(views: usize, tilt_step_deg: Real, seed: u64) -> Fused {
    fused_bridge1_with(ScannerConfig::default(), views, tilt_step_deg, seed)
}

/// [`fused_bridge1`] with a scanner configuration (e.g. without noise).
pub fn fused_bridge1_with(
    config: ScannerConfig,
    views: usize,
    tilt_step_deg: Real,
    seed: u64,
) -> Fused {
    let world = bridge1();
    let scanner = Scanner::new(config).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut points = Vec::new();
    let mut origins = Vec::new();
    let steps = (60.0 / tilt_step_deg).round() as usize;
    for (p, dir) in viewpoints().into_iter().take(views) {
        for k in 0..=steps {
            let tilt = (-30.0 + k as Real * tilt_step_deg).to_radians();
            let world_from_scanner = pose(p, dir, tilt);
            let scan = scanner.scan(&world, &world_from_scanner, &mut rng);
            for r in scan.returns.iter().flatten() {
                points.push(r.point);
                origins.push(p);
            }
        }
    }
    Fused {
        world,
        points,
        origins,
    }
}

/// The 55 000-point cloud of the speed target (Paul Table 5.1: 54 916
/// points): five sweeps at 0.4° tilt steps (≈ 215 000 points), thinned to
/// 55 000 by a seeded uniform random subset, as a fused map's vertices are
/// sparser than the raw returns.
pub fn fused_bridge1_55k() -> Fused {
    let mut f = fused_bridge1(5, 0.4, 11);
    thin(&mut f, 55_000, 5);
    f
}

/// Keep a seeded uniform random subset of `keep` points (in input order).
pub fn thin(f: &mut Fused, keep: usize, seed: u64) {
    use rand::RngExt;
    let n = f.points.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut idx: Vec<usize> = (0..n).collect();
    for i in 0..keep.min(n) {
        let j = rng.random_range(i..n);
        idx.swap(i, j);
    }
    idx.truncate(keep.min(n));
    idx.sort_unstable();
    f.points = idx.iter().map(|&i| f.points[i]).collect();
    f.origins = idx.iter().map(|&i| f.origins[i]).collect();
}

/// The face of the scene each point lies on: the first hit of the ray from
/// its sensor origin through it (range noise moves a point along its ray, so
/// this is exactly the face the sensor measured).
pub fn point_faces(f: &Fused) -> Vec<u32> {
    use scene::RayCast;
    let scene = f.scene();
    f.points
        .iter()
        .zip(&f.origins)
        .map(|(p, o)| {
            let dir = geom::unit(p - o).unwrap();
            scene
                .cast_ray(&geom::Ray::new(*o, dir), 10.0)
                .unwrap()
                .element
        })
        .collect()
}

/// Outward unit normal of a scene triangle.
pub fn face_normal(scene: &Scene, face: u32) -> Vector3 {
    scene
        .mesh()
        .triangle(face as usize)
        .normal()
        .unwrap()
        .into_inner()
}

/// Indices of the points within `r` of `c` (brute force over a grid built by
/// the caller is not worth it for tests: the clouds are small enough).
pub fn points_within(points: &[Point3], grid: &Grid, c: &Point3, r: Real) -> Vec<usize> {
    grid.within(points, c, r)
}

/// A uniform grid over points for radius queries in tests.
pub struct Grid {
    cell: Real,
    map: std::collections::HashMap<[i64; 3], Vec<usize>>,
}

impl Grid {
    /// Index `points` with cells of `cell` metres.
    pub fn new(points: &[Point3], cell: Real) -> Self {
        let mut map = std::collections::HashMap::<[i64; 3], Vec<usize>>::new();
        for (i, p) in points.iter().enumerate() {
            map.entry(Self::key(p, cell)).or_default().push(i);
        }
        Self { cell, map }
    }

    fn key(p: &Point3, cell: Real) -> [i64; 3] {
        [
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        ]
    }

    /// Indices of points within `r` of `c` (r ≤ cell), ascending.
    pub fn within(&self, points: &[Point3], c: &Point3, r: Real) -> Vec<usize> {
        let k = Self::key(c, self.cell);
        let mut out = Vec::new();
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(v) = self.map.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        out.extend(v.iter().copied().filter(|&i| (points[i] - c).norm() <= r));
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }
}

/// Ground truth of one disc.
pub struct DiscTruth {
    /// The μ-ball of the home point holds points of one plane only (same
    /// face normal, same offset within 1 mm): the disc straddles no edge or
    /// step.
    pub pure: bool,
    /// Angle between the disc normal and its home face's outward normal, degrees.
    pub error_deg: Real,
    /// Object name and outward axis of the home face (`roof-z`, `left_beam-y`, …).
    pub group: String,
}

/// The plane offset `n·v` of a face.
fn face_offset(scene: &Scene, face: u32) -> Real {
    let t = scene.mesh().triangle(face as usize);
    face_normal(scene, face).dot(&t.a.coords)
}

/// Group name of a face: object and outward axis.
pub fn face_group(scene: &Scene, face: u32) -> String {
    let n = face_normal(scene, face);
    let obj = &scene.objects()[scene.triangle_object(scene::FaceId(face)).index()].name;
    let ax = if n.x.abs() > 0.9 {
        if n.x > 0.0 { "+x" } else { "-x" }
    } else if n.y.abs() > 0.9 {
        if n.y > 0.0 { "+y" } else { "-y" }
    } else if n.z.abs() > 0.9 {
        if n.z > 0.0 { "+z" } else { "-z" }
    } else {
        "~"
    };
    format!("{obj}{ax}")
}

/// Truth of every disc: `faces[i]` is the face of point `i`, `homes[k]` the
/// home point of disc `k`.
pub fn disc_truths(
    scene: &Scene,
    points: &[Point3],
    faces: &[u32],
    discs: &[map::sld::Disc],
    homes: &[u32],
) -> Vec<DiscTruth> {
    let grid = Grid::new(points, 0.04);
    discs
        .iter()
        .zip(homes)
        .map(|(d, &h)| {
            let face = faces[h as usize];
            let n = face_normal(scene, face);
            let off = face_offset(scene, face);
            let pure = grid
                .within(points, &points[h as usize], d.radius_m)
                .iter()
                .all(|&i| {
                    let f = faces[i];
                    f == face
                        || (face_normal(scene, f).dot(&n) > 0.99996
                            && (face_offset(scene, f) - off).abs() < 1e-3)
                });
            DiscTruth {
                pure,
                error_deg: d.normal.dot(&n).clamp(-1.0, 1.0).acos().to_degrees(),
                group: face_group(scene, face),
            }
        })
        .collect()
}

/// The `q`-quantile of `v` (sorted copy, nearest rank).
pub fn quantile(v: &[Real], q: Real) -> Real {
    let mut s = v.to_vec();
    s.sort_by(Real::total_cmp);
    s[((s.len() as Real - 1.0) * q).round() as usize]
}

/// Keep the points (and origins) with `|x| ≤ half_length`: the section of
/// the channel around the robot.
pub fn crop_x(f: &mut Fused, half_length: Real) {
    let (p, o): (Vec<Point3>, Vec<Point3>) = f
        .points
        .iter()
        .zip(&f.origins)
        .filter(|(p, _)| p.x.abs() <= half_length)
        .map(|(p, o)| (*p, *o))
        .unzip();
    f.points = p;
    f.origins = o;
}

/// Paul's map pipeline up to the mesh (A§5.1.1): nodding sweeps (60° at 0.4°)
/// of bridge1 from the first `views` viewpoints fused in a TSDF of `voxel_m`,
/// and the extracted mesh, whose triangles face the sensors.
pub fn tsdf_mesh_bridge1(
    config: ScannerConfig,
    views: usize,
    voxel_m: Real,
    seed: u64,
) -> (World, scene::TriMesh) {
    let world = bridge1();
    let scanner = Scanner::new(config).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut tsdf = map::TsdfMap::new(map::TsdfConfig::with_voxel_m(voxel_m)).unwrap();
    for (p, dir) in viewpoints().into_iter().take(views) {
        let grid = scanner
            .nodding_sweep(
                &world,
                &pose(p, dir, 0.0),
                &sensor::SweepConfig::default(),
                &mut rng,
            )
            .unwrap();
        tsdf.integrate_sweep(&grid);
    }
    let mesh = tsdf.extract_mesh();
    (world, mesh)
}

/// The scene face closest to each point (within `max_m`; `u32::MAX` if none).
pub fn closest_faces(scene: &Scene, points: &[Point3], max_m: Real) -> Vec<u32> {
    points
        .iter()
        .map(|p| {
            scene
                .closest_point(p, max_m)
                .map_or(u32::MAX, |(_, f, _)| f.0)
        })
        .collect()
}
