//! The built-in scenes against SPEC §4's numbers.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Aabb, Point3, Ray, Vector3, unit};
use scene::{RayCast, SamplingConfig, SceneSpec, builtin, sample_surfaces};
use std::path::Path;

fn build(name: &str) -> scene::Scene {
    match builtin::scene(name).unwrap().build(Path::new(".")).unwrap() {
        scene::World::Mesh(s) => s,
        scene::World::Cloud(_) => panic!("built-ins are meshes"),
    }
}

#[test]
fn every_builtin_builds_closed_objects() {
    for name in builtin::NAMES {
        let s = build(name);
        s.check_invariants().unwrap();
        for o in s.objects() {
            assert!(o.closed, "{name}/{} is not closed", o.name);
        }
    }
    assert!(builtin::scene("nope").is_none());
}

#[test]
fn bridge1_geometry_by_rays() {
    let s = build("bridge1");
    let mat = |h: &scene::Hit| s.material(h.material.unwrap()).unwrap().name.clone();
    let cast = |o: [f64; 3], d: [f64; 3]| {
        let r = Ray::new(Point3::from(o), unit(Vector3::from(d)).unwrap());
        s.cast_ray(&r, 5.0).unwrap()
    };
    // Up to the roof underside.
    let h = cast([0.3, 0.0, 0.7], [0.0, 0.0, 1.0]);
    assert!((h.point.z - 1.52).abs() < 1e-9 && mat(&h) == "timber");
    // Left to the steel plate on the left web (y = 0.738), painted metal.
    let h = cast([0.0, 0.0, 1.1], [0.0, 1.0, 0.0]);
    assert!((h.point.y - 0.738).abs() < 1e-9 && mat(&h) == "painted_metal");
    // Left, beside the plate: the web face at 0.744.
    let h = cast([0.6, 0.0, 1.1], [0.0, 1.0, 0.0]);
    assert!((h.point.y - 0.744).abs() < 1e-9);
    // Right: the containment sheet at y = -0.740 (plastic).
    let h = cast([0.0, 0.0, 1.1], [0.0, -1.0, 0.0]);
    assert!((h.point.y + 0.740).abs() < 1e-9 && mat(&h) == "plastic");
    // Right beyond the sheet's x range: the web at -0.744.
    let h = cast([1.8, 0.0, 1.1], [0.0, -1.0, 0.0]);
    assert!((h.point.y + 0.744).abs() < 1e-9 && mat(&h) == "painted_metal");
    // Down onto the bottom flange top (z 0.82) from beside the web.
    let h = cast([0.0, 0.65, 1.2], [0.0, 0.0, -1.0]);
    assert!((h.point.z - 0.82).abs() < 1e-9);
    // Up under the bottom flange (z 0.80).
    let h = cast([-1.0, 0.65, 0.3], [0.0, 0.0, 1.0]);
    assert!((h.point.z - 0.80).abs() < 1e-9);
    // Down to the platform top (z 0) and past it to the floor (z -0.05).
    let h = cast([0.0, 0.0, 0.5], [0.0, 0.0, -1.0]);
    assert!(h.point.z.abs() < 1e-9);
    let h = cast([1.0, 0.0, 0.5], [0.0, 0.0, -1.0]);
    assert!((h.point.z + 0.05).abs() < 1e-9 && mat(&h) == "concrete");
    // The blast hose: top at z = 0.06 at y = 0.35.
    let h = cast([0.0, 0.35, 0.5], [0.0, 0.0, -1.0]);
    assert!((h.point.z - 0.06).abs() < 1e-6 && mat(&h) == "plastic");
    // A scaffold tube at (0.45, 0.55), radius 0.025.
    let h = cast([0.0, 0.55, 0.4], [1.0, 0.0, 0.0]);
    assert!((h.point.x - 0.425).abs() < 1e-3);
}

#[test]
fn bridge2_and_3_add_their_timber() {
    let s2 = build("bridge2");
    let r = Ray::new(Point3::new(0.0, 0.0, 1.3), -Vector3::x_axis());
    let h = s2.cast_ray(&r, 5.0).unwrap();
    assert!((h.point.x + 0.58).abs() < 1e-9);
    let s3 = build("bridge3");
    let h = s3
        .cast_ray(
            &Ray::new(Point3::new(0.0, 0.0, 1.3), Vector3::x_axis()),
            5.0,
        )
        .unwrap();
    assert!((h.point.x - 0.58).abs() < 1e-9);
    // A vertical lattice slat at y = 0.2 (0.18..0.22), face x = -0.58.
    let h = s3
        .cast_ray(
            &Ray::new(Point3::new(0.0, 0.2, 1.0), -Vector3::x_axis()),
            5.0,
        )
        .unwrap();
    assert!((h.point.x + 0.58).abs() < 1e-9);
    // Between slats (y = 0.1, z = 1.03) the ray leaves through the open channel end.
    let between = Ray::new(Point3::new(0.0, 0.1, 1.03), -Vector3::x_axis());
    assert!(s3.cast_ray(&between, 5.0).is_none());
}

#[test]
fn surface_following_solids_have_the_specified_volumes() {
    let vol = |n: &str| build(n).mesh().signed_volume();
    assert!((vol("cube") - 1.0).abs() < 1e-12);
    assert!((vol("block1") - (1.2 * 0.4 + 0.6 * 0.4) * 0.7).abs() < 1e-12);
    // block2: 1.0×0.6 minus chamfer triangles (0.3·0.3/2 and 0.35·0.2/2), depth 0.8.
    let area = 0.6 - 0.5 * 0.3 * 0.3 - 0.5 * 0.35 * 0.2;
    assert!((vol("block2") - area * 0.8).abs() < 1e-12);
    let cyl = vol("cylinder");
    let exact = std::f64::consts::PI * 0.16 * 0.8;
    assert!((cyl - exact).abs() / exact < 1e-3);
}

#[test]
fn scene_specs_round_trip_through_toml() {
    for name in builtin::NAMES {
        let spec = builtin::scene(name).unwrap();
        let text = toml::to_string(&spec).unwrap();
        let back: SceneSpec = toml::from_str(&text).unwrap();
        assert_eq!(back, spec, "{name}:\n{text}");
    }
}

#[test]
fn unknown_material_and_bad_shapes_are_named() {
    let mut spec = builtin::scene("cube").unwrap();
    spec.objects[0].material = "gold".into();
    let err = spec.build(Path::new(".")).unwrap_err().to_string();
    assert!(
        err.contains("cube") && err.contains("gold") && err.contains("painted_metal"),
        "{err}"
    );
    let bad: Result<SceneSpec, _> = toml::from_str(
        "[[objects]]\nname = \"a\"\nmaterial = \"timber\"\nshape = { kind = \"box\", min = [0, 0, 0], max = [1, 0, 1] }\n",
    );
    let err = bad.unwrap().build(Path::new(".")).unwrap_err().to_string();
    assert!(
        err.contains("object `a`") && err.contains("min < max"),
        "{err}"
    );
    let typo: Result<SceneSpec, _> = toml::from_str(
        "[[objects]]\nname = \"a\"\nmaterial = \"timber\"\nshape = { kind = \"sphere\", r = 1 }\n",
    );
    assert!(typo.unwrap_err().to_string().contains("sphere"));
}

#[test]
fn sampling_density_exposure_and_determinism() {
    let s = build("bridge1");
    let region = Aabb::new(Point3::new(-0.5, -1.0, -0.2), Point3::new(0.5, 1.0, 1.7));
    let cfg = SamplingConfig {
        samples_per_m2: 20_000.0,
        region: Some(region),
        exposed_only: true,
        seed: 1,
        ..SamplingConfig::default()
    };
    let a = sample_surfaces(&s, &cfg).unwrap();
    let b = sample_surfaces(&s, &cfg).unwrap();
    assert_eq!(a, b);
    assert!(a.iter().all(|p| region.contains_point(&p.point)));
    // Nothing on hidden faces: the web behind the plate, the plate's back, the
    // flange tops under the roof, the floor under the platform.
    for p in &a {
        let q = p.point;
        assert!(!((q.y - 0.744).abs() < 1e-9 && q.x.abs() < 0.4 && q.z > 0.95 && q.z < 1.35));
        assert!(!((q.z - 1.52).abs() < 1e-9 && p.normal.z > 0.5));
        assert!(
            !((q.z + 0.05).abs() < 1e-9 && q.x.abs() < 0.6 && q.y.abs() < 0.5 && p.normal.z > 0.5)
        );
    }
    // The exposed roof underside inside the region is 1.0 × 2.0 m².
    let roof: usize = a
        .iter()
        .filter(|p| (p.point.z - 1.52).abs() < 1e-9 && p.normal.z < -0.5)
        .count();
    let expected = 20_000.0 * (1.0 * 2.0 - 2.0 * 1.0 * 0.3); // minus the two top flanges' contact
    let rel = (roof as f64 - expected).abs() / expected;
    assert!(rel < 0.05, "roof samples {roof} vs {expected}");
    let mut all = cfg;
    all.exposed_only = false;
    assert!(sample_surfaces(&s, &all).unwrap().len() > a.len());
}
