//! Issue 8 §2: parameters that would allocate without bound are refused or
//! capped before allocating, and non-finite numbers are named.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::primitives::cuboid;
use geom::{Aabb, Point3};
use scene::{
    MaterialId, SamplingConfig, Scene, SceneSpec, SurfaceSampler, World, default_materials,
    sample_surfaces,
};
use std::path::Path;

fn spec(toml_text: &str) -> SceneSpec {
    toml::from_str(toml_text).unwrap()
}

fn build_err(toml_text: &str) -> String {
    spec(toml_text)
        .build(Path::new("."))
        .unwrap_err()
        .to_string()
}

const CYLINDER: &str = "[[objects]]\nname = \"c\"\nmaterial = \"timber\"\nshape = { kind = \"cylinder\", from = [0, 0, 0], to = [0, 0, 1], radius = 0.2, segments = SEGMENTS }\n";

#[test]
fn cylinder_segments_over_the_budget_are_refused_naming_the_limit() {
    // Issue 8: segments = 4e9 aborted with "memory allocation failed".
    let err = build_err(&CYLINDER.replace("SEGMENTS", "4000000000"));
    assert_eq!(
        err,
        "object `c` (cylinder segments): expected at most 4096 sides (MAX_PRIMITIVE_SEGMENTS: the caps' triangulation is quadratic in it), got 4000000000"
    );
    assert!(
        build_err(&CYLINDER.replace("SEGMENTS", "4097")).contains("got 4097"),
        "one past the limit"
    );
    // The limit itself builds: 4096 sides, 2·4096 side triangles + 2·4094 in the caps.
    let World::Mesh(s) = spec(&CYLINDER.replace("SEGMENTS", "4096"))
        .build(Path::new("."))
        .unwrap()
    else {
        panic!("a mesh scene");
    };
    assert_eq!(s.mesh().len(), 2 * 4096 + 2 * 4094);
}

#[test]
fn prism_profiles_over_the_budget_are_refused() {
    let profile: Vec<String> = (0..5000)
        .map(|i| {
            let a = std::f64::consts::TAU * f64::from(i) / 5000.0;
            format!("[{}, {}]", a.cos(), a.sin())
        })
        .collect();
    let text = format!(
        "[[objects]]\nname = \"p\"\nmaterial = \"timber\"\nshape = {{ kind = \"prism\", axis = \"z\", from = 0, to = 1, profile = [{}] }}\n",
        profile.join(", ")
    );
    let err = build_err(&text);
    assert!(
        err.starts_with("object `p` (prism profile): expected at most 4096 vertices"),
        "{err}"
    );
    assert!(err.ends_with("got 5000"), "{err}");
}

#[test]
fn non_finite_and_huge_poses_and_coordinates_are_named() {
    let object = |pose: &str| {
        format!(
            "[[objects]]\nname = \"b\"\nmaterial = \"timber\"\npose = {pose}\nshape = {{ kind = \"box\", min = [0, 0, 0], max = [1, 1, 1] }}\n"
        )
    };
    for (pose, field, got) in [
        ("{ translation = [nan, 0, 0] }", "translation[0]", "got NaN"),
        ("{ translation = [0, inf, 0] }", "translation[1]", "got inf"),
        (
            "{ translation = [0, 0, -1e308] }",
            "translation[2]",
            "got -1000",
        ),
        ("{ rpy_deg = [0, nan, 0] }", "rpy_deg[1]", "got NaN"),
        ("{ rpy_deg = [0, 0, 1e308] }", "rpy_deg[2]", "within ±360"),
    ] {
        let err = build_err(&object(pose));
        assert!(
            err.starts_with(&format!("object `b` pose: {field}: expected a")),
            "{pose}: {err}"
        );
        assert!(err.contains(got), "{pose}: {err}");
    }
    // Within the bound (UTM-sized offsets) builds.
    spec(&object("{ translation = [500000, 5000000, 10] }"))
        .build(Path::new("."))
        .unwrap();
    // Shape coordinates share the bound.
    let err = build_err(
        "[[objects]]\nname = \"b\"\nmaterial = \"timber\"\nshape = { kind = \"box\", min = [-1e308, 0, 0], max = [1e308, 1, 1] }\n",
    );
    assert!(
        err.starts_with("object `b` (box): expected finite min < max"),
        "{err}"
    );
    let err = build_err(&CYLINDER.replace("SEGMENTS", "8").replace("0.2", "1e300"));
    assert!(err.contains("radius must be finite and within"), "{err}");
}

fn unit_cube() -> Scene {
    let cube = cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0));
    Scene::from_mesh("cube", cube, default_materials(), MaterialId(0)).unwrap()
}

#[test]
fn an_over_budget_density_is_capped_and_reported() {
    // Issue 8: samples_per_m2 = 1e12 aborted. The cube has 6 m² on 12 faces;
    // each face gets its share rounded up or down, so 6 000 ± 12 samples.
    let scene = unit_cube();
    let cfg = SamplingConfig {
        samples_per_m2: 1e12,
        max_samples: 6_000,
        exposed_only: false,
        ..SamplingConfig::default()
    };
    let sampler = SurfaceSampler::new(&scene, &cfg).unwrap();
    assert!(sampler.is_capped());
    assert!((sampler.samples_per_m2() - 1_000.0).abs() < 1e-9);
    let n = sample_surfaces(&scene, &cfg).unwrap().len();
    assert!((6_000 - 12..=6_000 + 12).contains(&n), "{n}");
    // With a region, only faces meeting it count: the bottom face z = 0 (and the
    // four side faces touching it) meet a thin slab under the cube, so the
    // area is 5 m² and the density 6 000 / 5.
    let slab = SamplingConfig {
        region: Some(Aabb::new(
            Point3::new(-1.0, -1.0, -0.5),
            Point3::new(2.0, 2.0, 0.0),
        )),
        ..cfg
    };
    let sampler = SurfaceSampler::new(&scene, &slab).unwrap();
    assert!((sampler.samples_per_m2() - 1_200.0).abs() < 1e-9);
    // Under the budget, the density is as asked.
    let fine = SamplingConfig {
        samples_per_m2: 900.0,
        ..cfg
    };
    let sampler = SurfaceSampler::new(&scene, &fine).unwrap();
    assert!(!sampler.is_capped());
    assert_eq!(sampler.samples_per_m2(), 900.0);
}

#[test]
fn chunks_do_not_change_the_samples() {
    let scene = match builtin::scene_world("bridge1") {
        World::Mesh(s) => s,
        World::Cloud(_) => unreachable!(),
    };
    let cfg = SamplingConfig {
        samples_per_m2: 2_000.0,
        region: Some(Aabb::new(
            Point3::new(-0.5, -1.0, -0.2),
            Point3::new(0.5, 1.0, 1.7),
        )),
        seed: 4,
        ..SamplingConfig::default()
    };
    let whole = sample_surfaces(&scene, &cfg).unwrap();
    assert!(whole.len() > 5_000, "{}", whole.len());
    for chunk in [1, 7, 1000] {
        let mut chunks = 0;
        let mut joined = Vec::new();
        for c in SurfaceSampler::new(&scene, &cfg).unwrap().with_chunk(chunk) {
            assert!(c.len() <= chunk);
            chunks += 1;
            joined.extend(c);
        }
        assert_eq!(joined, whole, "chunk {chunk}");
        assert!(
            chunks >= whole.len() / chunk,
            "chunk {chunk}: {chunks} chunks"
        );
    }
}

mod builtin {
    pub fn scene_world(name: &str) -> scene::World {
        scene::builtin::scene(name)
            .unwrap()
            .build(std::path::Path::new("."))
            .unwrap()
    }
}

#[test]
fn bad_sampling_settings_are_named() {
    let scene = unit_cube();
    for (cfg, field) in [
        (
            SamplingConfig {
                samples_per_m2: f64::NAN,
                ..SamplingConfig::default()
            },
            "sampling.samples_per_m2",
        ),
        (
            SamplingConfig {
                samples_per_m2: 0.0,
                ..SamplingConfig::default()
            },
            "sampling.samples_per_m2",
        ),
        (
            SamplingConfig {
                samples_per_m2: -5.0,
                ..SamplingConfig::default()
            },
            "sampling.samples_per_m2",
        ),
        (
            SamplingConfig {
                region: Some(Aabb {
                    min: Point3::new(0.0, f64::NAN, 0.0),
                    max: Point3::new(1.0, 1.0, 1.0),
                }),
                ..SamplingConfig::default()
            },
            "sampling.region",
        ),
        (
            SamplingConfig {
                max_samples: 0,
                ..SamplingConfig::default()
            },
            "sampling.max_samples",
        ),
    ] {
        let err = match sample_surfaces(&scene, &cfg) {
            Ok(v) => panic!("{field}: accepted, {} samples", v.len()),
            Err(e) => e.to_string(),
        };
        assert!(err.starts_with(&format!("{field}: expected")), "{err}");
    }
}
