//! Ray, nearest-point and contact queries against brute-force oracles.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Capsule, Point3, Ray, Real, Triangle, UnitVector3, Vector3, unit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene::bvh::RayF32;
use scene::{MaterialId, RayCast, Scene, TriMesh, default_materials};

/// A random soup of triangles of varied sizes in a 4 m box.
fn random_soup(rng: &mut ChaCha8Rng, n: usize) -> TriMesh {
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for i in 0..n {
        let c = Point3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        );
        let size = if i % 10 == 0 { 1.0 } else { 0.15 };
        for _ in 0..3 {
            vertices.push(
                c + Vector3::new(
                    rng.random_range(-size..size),
                    rng.random_range(-size..size),
                    rng.random_range(-size..size),
                ),
            );
        }
        let b = (3 * i) as u32;
        triangles.push([b, b + 1, b + 2]);
    }
    TriMesh::new(vertices, triangles, "soup").unwrap()
}

fn random_dir(rng: &mut ChaCha8Rng) -> UnitVector3 {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.norm() > 0.1 && v.norm() <= 1.0 {
            return unit(v).unwrap();
        }
    }
}

fn brute_first_hit(mesh: &TriMesh, ray: &Ray, max: Real) -> Option<(Real, usize)> {
    let mut best: Option<(Real, usize)> = None;
    for i in 0..mesh.len() {
        if let Some(t) = mesh.triangle(i).ray_hit(ray, max)
            && t > 0.0
            && best.is_none_or(|(b, _)| t < b)
        {
            best = Some((t, i));
        }
    }
    best
}

#[test]
fn rays_agree_with_brute_force_on_random_scenes() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for scene_no in 0..6 {
        let n = [1, 5, 50, 300, 1000, 3000][scene_no];
        let mesh = random_soup(&mut rng, n);
        let scene =
            Scene::from_mesh("soup", mesh.clone(), default_materials(), MaterialId(0)).unwrap();
        scene.check_invariants().unwrap();
        let mut hits = 0;
        for _ in 0..400 {
            let origin = Point3::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            );
            let ray = Ray::new(origin, random_dir(&mut rng));
            let max = rng.random_range(0.5..8.0);
            let got = scene.cast_ray(&ray, max);
            let want = brute_first_hit(&mesh, &ray, max);
            match (got, want) {
                (None, None) => {}
                (Some(h), Some((t, face))) => {
                    hits += 1;
                    assert!(
                        (h.distance - t).abs() < 1e-5,
                        "scene {scene_no}: {} vs {t}",
                        h.distance
                    );
                    // The same triangle, or another at the same distance.
                    if h.element as usize != face {
                        let t2 = mesh
                            .triangle(h.element as usize)
                            .ray_hit(&ray, max)
                            .unwrap();
                        assert!((t2 - t).abs() < 1e-5);
                    }
                    assert!((h.point - ray.point_at(t)).norm() < 1e-5);
                    assert!(h.normal.dot(&ray.dir) <= 0.0, "normal faces the sensor");
                }
                (g, w) => {
                    // Only grazing hits within single-precision tolerance may differ.
                    let t = g.map(|h| h.distance).or(w.map(|w| w.0)).unwrap();
                    assert!(
                        (t - max).abs() < 1e-5 || t < 1e-5,
                        "scene {scene_no}: got {g:?}, brute force {w:?}"
                    );
                }
            }
        }
        if n >= 300 {
            assert!(hits > 40, "too few hits ({hits}) to test anything");
        }
    }
}

#[test]
fn batched_rays_equal_single_rays() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mesh = random_soup(&mut rng, 500);
    let scene = Scene::from_mesh("soup", mesh, default_materials(), MaterialId(0)).unwrap();
    let rays: Vec<Ray> = (0..2000)
        .map(|_| {
            Ray::new(
                Point3::new(rng.random_range(-3.0..3.0), 0.0, 0.0),
                random_dir(&mut rng),
            )
        })
        .collect();
    let batch = scene.cast_rays(&rays, 10.0);
    for (r, b) in rays.iter().zip(&batch) {
        assert_eq!(scene.cast_ray(r, 10.0), *b);
    }
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
    let mut out = vec![0.0f32; raw.len()];
    scene.cast_rays_f32(&raw, f32::INFINITY, &mut out);
    for (o, b) in out.iter().zip(&batch) {
        match b {
            Some(h) => assert!((f64::from(*o) - h.distance).abs() < 1e-4),
            None => assert!(o.is_infinite()),
        }
    }
    // The batch with faces: each ray's hit, face included, is the single
    // walk's, and its distance the plain batch's.
    let mut with_faces = vec![None; raw.len()];
    let prepared: Vec<RayF32> = raw
        .iter()
        .map(|r| RayF32::new([r[0], r[1], r[2]], [r[3], r[4], r[5]]))
        .collect();
    scene.first_hits(&prepared, f32::INFINITY, &mut with_faces);
    for ((r, wf), o) in raw.iter().zip(&with_faces).zip(&out) {
        let single = scene.first_hit_f32([r[0], r[1], r[2]], [r[3], r[4], r[5]], f32::INFINITY);
        assert_eq!(wf.map(|(face, t)| (t, face)), single);
        assert_eq!(wf.map_or(f32::INFINITY, |(_, t)| t).to_bits(), o.to_bits());
    }
}

#[test]
fn closest_point_agrees_with_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mesh = random_soup(&mut rng, 800);
    let scene = Scene::from_mesh("soup", mesh.clone(), default_materials(), MaterialId(0)).unwrap();
    for _ in 0..300 {
        let p = Point3::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
        );
        let brute = mesh
            .iter_triangles()
            .map(|t| t.distance_to_point(&p))
            .fold(Real::INFINITY, Real::min);
        let (d, face, q) = scene.closest_point(&p, 100.0).unwrap();
        assert!((d - brute).abs() < 1e-12);
        assert!((mesh.triangle(face.0 as usize).distance_to_point(&p) - d).abs() < 1e-12);
        assert!(((q - p).norm() - d).abs() < 1e-12);
        // A radius below the true distance finds nothing.
        if brute > 1e-3 {
            assert!(scene.closest_point(&p, brute * 0.999).is_none());
        }
    }
}

#[test]
fn capsule_and_triangle_contacts_agree_with_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mesh = random_soup(&mut rng, 400);
    let scene = Scene::from_mesh("soup", mesh.clone(), default_materials(), MaterialId(0)).unwrap();
    let mut contacts = 0;
    for _ in 0..200 {
        let a = Point3::new(
            rng.random_range(-2.5..2.5),
            rng.random_range(-2.5..2.5),
            rng.random_range(-2.5..2.5),
        );
        let b = a + random_dir(&mut rng).into_inner() * rng.random_range(0.0..0.8);
        let cap = Capsule::new(a, b, rng.random_range(0.01..0.1));
        let brute = mesh
            .iter_triangles()
            .any(|t| cap.distance_to_triangle(&t) <= 0.0);
        assert_eq!(scene.capsule_contact(&cap, 0.0).is_some(), brute);
        contacts += usize::from(brute);
        let probe = Triangle::new(a, b, a + random_dir(&mut rng).into_inner() * 0.3);
        let brute_t = mesh.iter_triangles().any(|t| t.intersects_triangle(&probe));
        assert_eq!(scene.triangles_contact(&[probe]).is_some(), brute_t);
    }
    assert!(
        contacts > 10 && contacts < 190,
        "{contacts} contacts: test not discriminating"
    );
}
