//! The ray–triangle convention of `geom::triangle` (closed interval `[0, t_max]`,
//! edges and vertices included, rays in the plane miss) holds in the scene's BVH
//! paths too: single rays (`first_hit_f32`, `cast_ray`) and batches
//! (`cast_rays_f32`) agree with `Triangle::ray_hit` by brute force on rays through
//! vertices, edges, the mesh's outer boundary, at `t = 0` and at `t = t_max`.
//!
//! The mesh is an 8 × 8 grid of unit-square cells of 1/8 m split into triangles,
//! at z = 0, and the rays run along the z axis from dyadic points: every
//! coordinate and product is exact in `f32` and `f64` alike, so the two
//! precisions must agree to the bit, not within a tolerance.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Point3, Ray, Real, UnitVector3, Vector3};
use scene::bvh::RayF32;
use scene::{MaterialId, RayCast, Scene, TriMesh, default_materials};

const N: usize = 8;
const CELL: Real = 0.125;

fn grid() -> TriMesh {
    let mut vertices = Vec::new();
    for j in 0..=N {
        for i in 0..=N {
            vertices.push(Point3::new(i as Real * CELL, j as Real * CELL, 0.0));
        }
    }
    let id = |i: usize, j: usize| (j * (N + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..N {
        for i in 0..N {
            // Alternate the diagonal so both diagonals occur.
            if (i + j) % 2 == 0 {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                triangles.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    TriMesh::new(vertices, triangles, "grid").unwrap()
}

/// Closest hit by brute force with `geom`'s test: the oracle.
fn brute(mesh: &TriMesh, ray: &Ray, t_max: Real) -> Option<Real> {
    (0..mesh.len())
        .filter_map(|i| mesh.triangle(i).ray_hit(ray, t_max))
        .reduce(Real::min)
}

/// Sample points at every multiple of 1/16 m from −1/16 to 1 + 1/16: vertices,
/// edge midpoints, cell centres and diagonal points, the outer boundary, and
/// points just outside it.
fn samples() -> Vec<(Real, Real)> {
    let k = (2 * N + 2) as i32;
    let mut out = Vec::new();
    for j in -1..=k {
        for i in -1..=k {
            out.push((Real::from(i) / 16.0, Real::from(j) / 16.0));
        }
    }
    out
}

#[test]
fn bvh_paths_follow_the_geom_convention() {
    let mesh = grid();
    let scene = Scene::from_mesh("grid", mesh.clone(), default_materials(), MaterialId(0)).unwrap();
    scene.check_invariants().unwrap();
    let down = UnitVector3::new_normalize(Vector3::new(0.0, 0.0, -1.0));
    let up = UnitVector3::new_normalize(Vector3::new(0.0, 0.0, 1.0));
    // (origin height, direction, t_max): surface at t = 2 within, at, just short
    // of t_max; from below; from the surface itself (t = 0).
    let cases = [
        (2.0, down, 10.0),
        (2.0, down, 2.0),
        (2.0, down, 1.999_999),
        (-0.5, up, 0.5),
        (-0.5, up, Real::INFINITY),
        (0.0, down, 1.0),
        (0.0, up, 1.0),
    ];
    let (mut hits, mut misses, mut compared) = (0, 0, 0);
    for (z, dir, t_max) in cases {
        let rays: Vec<Ray> = samples()
            .into_iter()
            .map(|(x, y)| Ray::new(Point3::new(x, y, z), dir))
            .collect();
        let raw: Vec<[f32; 6]> = rays
            .iter()
            .map(|r| {
                [
                    r.origin.x as f32,
                    r.origin.y as f32,
                    r.origin.z as f32,
                    r.dir.x as f32,
                    r.dir.y as f32,
                    r.dir.z as f32,
                ]
            })
            .collect();
        let mut batch = vec![0.0f32; raw.len()];
        scene.cast_rays_f32(&raw, t_max as f32, &mut batch);
        let mut with_faces = vec![None; raw.len()];
        let prepared: Vec<RayF32> = raw
            .iter()
            .map(|r| RayF32::new([r[0], r[1], r[2]], [r[3], r[4], r[5]]))
            .collect();
        scene.first_hits(&prepared, t_max as f32, &mut with_faces);
        for (((ray, r), b), wf) in rays.iter().zip(&raw).zip(&batch).zip(&with_faces) {
            let want = brute(&mesh, ray, t_max);
            let (x, y) = (ray.origin.x, ray.origin.y);
            let inside = (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y);
            // The oracle itself follows the convention: closed grid, closed interval.
            let surface_t = (z as Real).abs();
            assert_eq!(
                want,
                (inside && surface_t <= t_max).then_some(surface_t),
                "geom at ({x}, {y}, {z}), t_max {t_max}"
            );
            let single_hit =
                scene.first_hit_f32([r[0], r[1], r[2]], [r[3], r[4], r[5]], t_max as f32);
            // The batch with faces: the single walk's hit, face and all.
            assert_eq!(
                wf.map(|(face, t)| (t, face)),
                single_hit,
                "first_hits at ({x}, {y}, {z}), t_max {t_max}"
            );
            let single = single_hit.map(|(t, face)| {
                // The reported face is hit by geom's test at that distance.
                assert_eq!(
                    mesh.triangle(face as usize).ray_hit(ray, t_max),
                    Some(Real::from(t)),
                    "face {face} at ({x}, {y}, {z})"
                );
                Real::from(t)
            });
            assert_eq!(
                single, want,
                "first_hit_f32 at ({x}, {y}, {z}), t_max {t_max}"
            );
            let batched = b.is_finite().then_some(Real::from(*b));
            assert_eq!(
                batched, want,
                "cast_rays_f32 at ({x}, {y}, {z}), t_max {t_max}"
            );
            let cast = scene.cast_ray(ray, t_max).map(|h| h.distance);
            assert_eq!(cast, want, "cast_ray at ({x}, {y}, {z}), t_max {t_max}");
            compared += 1;
            if want.is_some() {
                hits += 1;
            } else {
                misses += 1;
            }
        }
    }
    // Every sample inside the closed grid is a hit in the cases that reach it.
    let inside = (2 * N + 1) * (2 * N + 1);
    assert_eq!(hits, 6 * inside, "{compared} rays compared");
    assert_eq!(misses, compared - hits);
}

#[test]
fn rays_in_the_plane_miss_in_both() {
    let mesh = grid();
    let scene = Scene::from_mesh("grid", mesh.clone(), default_materials(), MaterialId(0)).unwrap();
    for (x, y) in samples() {
        for dir in [Vector3::x_axis(), Vector3::y_axis()] {
            let ray = Ray::new(Point3::new(x - 2.0, y, 0.0), dir);
            assert_eq!(brute(&mesh, &ray, 10.0), None);
            let o = [(x - 2.0) as f32, y as f32, 0.0];
            let d = [dir.x as f32, dir.y as f32, dir.z as f32];
            assert_eq!(
                scene.first_hit_f32(o, d, 10.0),
                None,
                "({x}, {y}) along {d:?}"
            );
        }
    }
}
