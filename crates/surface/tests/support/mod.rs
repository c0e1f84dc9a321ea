//! Test support: scripted raster sweeps of point3's 26 range finders over the
//! built-in scenes, chunking of real scans into sensor sets, and a checked feed.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, missing_docs)]

use geom::{Isometry3, Point3, Real, Translation3, UnitQuaternion, UnitVector3, Vector3, unit};
use rand::SeedableRng;
use scene::World;
use sensor::RangeFinder;
use surface::{ChangeLog, SensorSet, SurfaceModel};

/// A rectangular face patch: `origin + a·û + b·v̂`, `a ∈ [0, |u|]`, `b ∈ [0, |v|]`,
/// outward normal `û × v̂`.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    pub origin: Point3,
    pub u: Vector3,
    pub v: Vector3,
}

impl Face {
    pub const fn new(origin: [Real; 3], u: [Real; 3], v: [Real; 3]) -> Self {
        Self {
            origin: Point3::new(origin[0], origin[1], origin[2]),
            u: Vector3::new(u[0], u[1], u[2]),
            v: Vector3::new(v[0], v[1], v[2]),
        }
    }

    pub fn normal(&self) -> UnitVector3 {
        unit(self.u.cross(&self.v)).unwrap()
    }

    pub fn area(&self) -> Real {
        self.u.cross(&self.v).norm()
    }

    pub fn center(&self) -> Point3 {
        self.origin + 0.5 * (self.u + self.v)
    }
}

/// The reachable faces of a built-in scene (SPEC §4), as rectangles (the
/// hexagonal sides of block2 and the L-shaped sides of block1 as covering
/// rectangles or unions of rectangles).
pub fn faces(scene: &str) -> Vec<Face> {
    match scene {
        "cube" => vec![
            Face::new([-0.5, -0.5, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            Face::new([0.5, -0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            Face::new([0.5, 0.5, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            Face::new([-0.5, 0.5, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
            Face::new([-0.5, -0.5, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ],
        "block1" => vec![
            Face::new([-0.6, -0.35, 0.8], [0.6, 0.0, 0.0], [0.0, 0.7, 0.0]),
            Face::new([0.0, -0.35, 0.4], [0.6, 0.0, 0.0], [0.0, 0.7, 0.0]),
            Face::new([0.0, -0.35, 0.4], [0.0, 0.7, 0.0], [0.0, 0.0, 0.4]),
            Face::new([0.6, -0.35, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 0.4]),
            Face::new([0.6, 0.35, 0.0], [-1.2, 0.0, 0.0], [0.0, 0.0, 0.4]),
            Face::new([0.0, 0.35, 0.4], [-0.6, 0.0, 0.0], [0.0, 0.0, 0.4]),
            Face::new([-0.6, 0.35, 0.0], [0.0, -0.7, 0.0], [0.0, 0.0, 0.8]),
            Face::new([-0.6, -0.35, 0.0], [1.2, 0.0, 0.0], [0.0, 0.0, 0.4]),
            Face::new([-0.6, -0.35, 0.4], [0.6, 0.0, 0.0], [0.0, 0.0, 0.4]),
        ],
        "block2" => vec![
            Face::new([-0.15, -0.4, 0.6], [0.35, 0.0, 0.0], [0.0, 0.8, 0.0]),
            Face::new([0.5, -0.4, 0.3], [0.0, 0.8, 0.0], [-0.3, 0.0, 0.3]),
            Face::new([0.5, -0.4, 0.0], [0.0, 0.8, 0.0], [0.0, 0.0, 0.3]),
            Face::new([0.5, 0.4, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.6]),
            Face::new([-0.15, -0.4, 0.6], [0.0, 0.8, 0.0], [-0.35, 0.0, -0.2]),
            Face::new([-0.5, 0.4, 0.0], [0.0, -0.8, 0.0], [0.0, 0.0, 0.4]),
            Face::new([-0.5, -0.4, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.6]),
        ],
        _ => Vec::new(),
    }
}

/// The ground-truth world of a built-in scene.
pub fn world(scene: &str) -> World {
    scene::builtin::scene(scene)
        .unwrap()
        .build(std::path::Path::new("."))
        .unwrap()
}

/// The table under every surface-following scene: a 4 m square at z = 0, normal +z.
pub fn table() -> Vec<Point3> {
    vec![
        Point3::new(-2.0, -2.0, 0.0),
        Point3::new(2.0, -2.0, 0.0),
        Point3::new(2.0, 2.0, 0.0),
        Point3::new(-2.0, 2.0, 0.0),
    ]
}

/// Closest approach of the control point to the scene during a sweep (m).
pub const CLEARANCE: Real = 0.045;

/// Parameters of a scripted sweep.
#[derive(Clone, Copy, Debug)]
pub struct Sweep {
    /// Raster step along and between passes (m).
    pub step: Real,
    /// Distance of the control point from the face (m).
    pub standoff: Real,
    /// How far beyond the face's edges passes run (m).
    pub margin: Real,
    /// Range noise σ (m).
    pub noise_sigma: Real,
    pub seed: u64,
}

impl Default for Sweep {
    fn default() -> Self {
        Self {
            step: 0.04,
            standoff: 0.1,
            margin: 0.0,
            noise_sigma: 0.0,
            seed: 1,
        }
    }
}

/// Control-point positions of raster passes over each face, at the standoff,
/// moving positions closer than [`CLEARANCE`] to the scene back to it and
/// skipping those inside it.
pub fn raster_positions(scene: &str, sweep: &Sweep) -> Vec<Point3> {
    let w = world(scene);
    let mesh = w.as_scene().unwrap();
    let mut out = Vec::new();
    let mut push = |p: Point3| {
        if mesh.is_inside_closed_object(&p, None) {
            return;
        }
        // Too close to a surface (near a concave edge): back off along the
        // surface's normal to the clearance, as a follower would.
        let mut p = p;
        if let Some((d, _, q)) = mesh.closest_point(&p, CLEARANCE) {
            if d < 1e-9 {
                return;
            }
            p = q + (p - q) * (CLEARANCE / d);
        }
        if p.z < CLEARANCE || mesh.closest_point(&p, CLEARANCE - 1e-6).is_some() {
            return;
        }
        out.push(p);
    };
    if scene == "cylinder" {
        // Top disc raster, then rings around the side, top to bottom.
        let top = Face::new([-0.4, -0.4, 0.8], [0.8, 0.0, 0.0], [0.0, 0.8, 0.0]);
        for p in face_raster(&top, sweep) {
            if (p.x * p.x + p.y * p.y).sqrt() < 0.4 + sweep.margin {
                push(p);
            }
        }
        let r = 0.4 + sweep.standoff;
        let n = ((2.0 * std::f64::consts::PI * 0.4) / sweep.step).ceil() as usize;
        let mut z = 0.8;
        let mut ring = 0;
        while z > 0.5 * sweep.standoff {
            for k in 0..n {
                let k = if ring % 2 == 0 { k } else { n - 1 - k };
                let a = 2.0 * std::f64::consts::PI * k as Real / n as Real;
                push(Point3::new(r * a.cos(), r * a.sin(), z));
            }
            z -= sweep.step;
            ring += 1;
        }
        return out;
    }
    for f in faces(scene) {
        for p in face_raster(&f, sweep) {
            push(p);
        }
    }
    out
}

fn face_raster(f: &Face, sweep: &Sweep) -> Vec<Point3> {
    let (lu, lv) = (f.u.norm(), f.v.norm());
    let (uh, vh) = (f.u / lu, f.v / lv);
    let n = f.normal().into_inner();
    let count = |len: Real| ((len + 2.0 * sweep.margin) / sweep.step).round().max(1.0) as usize;
    let (nu, nv) = (count(lu), count(lv));
    // The raster grid, visited in square rings from the face's centre outwards,
    // each ring anticlockwise: the model grows as a blob and edges are
    // approached from an already modelled face, as a surface follower approaches
    // them.
    let mut grid = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            let du = (i as Real - nu as Real / 2.0) / (nu as Real / 2.0).max(1.0);
            let dv = (j as Real - nv as Real / 2.0) / (nv as Real / 2.0).max(1.0);
            let ring = (du.abs().max(dv.abs()) * (nu.max(nv) as Real) / 2.0).round() as i64;
            grid.push((ring, dv.atan2(du), i, j));
        }
    }
    grid.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
    let mut out = Vec::with_capacity(grid.len());
    for (_, _, i, j) in grid {
        let a = -sweep.margin + (lu + 2.0 * sweep.margin) * i as Real / nu as Real;
        let b = -sweep.margin + (lv + 2.0 * sweep.margin) * j as Real / nv as Real;
        out.push(f.origin + uh * a + vh * b + n * sweep.standoff);
    }
    out
}

/// Sensor sets of point3's 26 range finders at each raster position.
pub fn sweep_sets(scene: &str, sweep: &Sweep) -> Vec<SensorSet> {
    let w = world(scene);
    let robot = robot::builtin("point3").unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(sweep.seed);
    let mut sets = Vec::new();
    for p in raster_positions(scene, sweep) {
        let frames = robot.forward_kinematics(&[p.x, p.y, p.z]).unwrap();
        let mut points = Vec::new();
        let mut axes = Vec::new();
        for mount in &robot.range_finders {
            let finder = RangeFinder {
                origin: mount.origin,
                axis: mount.axis,
                max_range_m: mount.max_range_m,
                noise_sigma_m: sweep.noise_sigma,
            };
            if let Some(sp) = finder.measure(&w, &frames[mount.link.0], &mut rng) {
                points.push(sp.point);
                axes.push(sp.axis);
            }
        }
        if !points.is_empty() {
            sets.push(SensorSet::new(points, axes).unwrap());
        }
    }
    sets
}

/// Feed sets, checking the invariants after every update (and the moment totals
/// against the points fed by the harness itself).
pub fn feed_checked(model: &mut SurfaceModel, sets: &[SensorSet]) -> Vec<ChangeLog> {
    let mut fed: u64 = model.points_fed();
    let mut logs = Vec::with_capacity(sets.len());
    for (k, set) in sets.iter().enumerate() {
        let log = model
            .update(set)
            .unwrap_or_else(|e| panic!("set {k}: update refused: {e}"));
        fed += set.len() as u64;
        if let Err(e) = model.check_invariants() {
            panic!("set {k}: {e}");
        }
        let represented: u64 = model.segments().map(surface::Segment::points).sum();
        assert_eq!(
            represented + model.points_deleted(),
            fed,
            "set {k}: moment totals"
        );
        assert!(
            model
                .segments()
                .filter(|s| s.is_initial())
                .all(|s| s.points() == 0)
        );
        logs.push(log);
    }
    logs
}

/// Identity isometry at `p` (point3's body frame).
pub fn at(p: Point3) -> Isometry3 {
    Isometry3::from_parts(Translation3::from(p.coords), UnitQuaternion::identity())
}

/// Chunk a scan into sets of `size` nearby points: points are ordered along a
/// Morton (Z-order) curve of a `cell`-sized grid, then cut into consecutive runs.
pub fn chunk_sets(
    points: &[Point3],
    axes: &[UnitVector3],
    size: usize,
    cell: Real,
) -> Vec<SensorSet> {
    let lo = points
        .iter()
        .fold(Point3::new(Real::MAX, Real::MAX, Real::MAX), |a, p| {
            a.inf(p)
        });
    let key = |p: &Point3| -> u64 {
        let q = |v: Real| ((v / cell).floor().max(0.0) as u64).min((1 << 21) - 1);
        let (x, y, z) = (q(p.x - lo.x), q(p.y - lo.y), q(p.z - lo.z));
        let spread = |mut v: u64| {
            v &= 0x1f_ffff;
            v = (v | v << 32) & 0x1f_0000_0000_ffff;
            v = (v | v << 16) & 0x1f_0000_ff00_00ff;
            v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
            v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
            v = (v | v << 2) & 0x1249_2492_4924_9249;
            v
        };
        spread(x) | spread(y) << 1 | spread(z) << 2
    };
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| (key(&points[i]), i));
    order
        .chunks(size)
        .map(|c| {
            SensorSet::new(
                c.iter().map(|&i| points[i]).collect(),
                c.iter().map(|&i| axes[i]).collect(),
            )
            .unwrap()
        })
        .collect()
}

/// Keep one point (the first) per `cell`-sized voxel.
pub fn voxel_subsample(
    points: &[Point3],
    axes: &[UnitVector3],
    cell: Real,
) -> (Vec<Point3>, Vec<UnitVector3>) {
    let mut seen = std::collections::BTreeSet::new();
    let mut out = (Vec::new(), Vec::new());
    for (p, a) in points.iter().zip(axes) {
        if cell <= 0.0 {
            out.0.push(*p);
            out.1.push(*a);
            continue;
        }
        let key = (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        );
        if seen.insert(key) {
            out.0.push(*p);
            out.1.push(*a);
        }
    }
    out
}
