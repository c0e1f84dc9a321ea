//! Issue 8 §2: scenario numbers that are non-finite, ignored or over budget
//! are refused naming the field; scoring runs in bounded memory; no points is
//! no accuracy.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::primitives::cuboid;
use geom::{Point3, Real};
use scenario::Scenario;
use scenario::{MetricsConfig, builtin_scenario};
use scene::{MaterialId, SamplingConfig, Scene, default_materials, sample_surfaces};
use sim::metrics::{accuracy, coverage, coverage_in_chunks};

/// bridge1 as TOML with `edit` applied to the text.
fn bridge1_with(edit: impl Fn(String) -> String) -> Result<Scenario, String> {
    let text = builtin_scenario("bridge1").unwrap().to_toml().unwrap();
    Scenario::from_toml(&edit(text), "b.toml").map_err(|e| e.to_string())
}

/// Replace the first `key = ...` line under `[table]` by `key = value`.
fn set(text: &str, table: &str, key: &str, value: &str) -> String {
    let mut out = Vec::new();
    let mut in_table = false;
    let mut done = false;
    for line in text.lines() {
        if line.starts_with('[') {
            in_table = line == format!("[{table}]");
        }
        if in_table && !done && line.starts_with(&format!("{key} =")) {
            out.push(format!("{key} = {value}"));
            done = true;
        } else {
            out.push(line.to_owned());
        }
    }
    if !done {
        // The key was absent (a default): add it under the table, or add the table.
        match out.iter().position(|l| *l == format!("[{table}]")) {
            Some(at) => out.insert(at + 1, format!("{key} = {value}")),
            None => out.push(format!("[{table}]\n{key} = {value}")),
        }
    }
    out.join("\n")
}

#[test]
fn the_builtin_scenarios_validate() {
    for name in scenario::BUILTIN_NAMES {
        builtin_scenario(name).unwrap().validate().unwrap();
    }
    bridge1_with(|t| t).unwrap();
}

#[test]
fn non_finite_or_huge_translations_are_named() {
    for (value, got) in [
        ("[nan, 0.0, 0.0]", "got NaN"),
        ("[0.0, inf, 0.0]", "got inf"),
        ("[0.0, 0.0, 1e308]", "got 1000"),
    ] {
        let err = bridge1_with(|t| set(&t, "robot.base_pose", "translation", value)).unwrap_err();
        assert!(
            err.starts_with("scenario b.toml: robot.base_pose: translation["),
            "{value}: {err}"
        );
        assert!(err.contains(got), "{value}: {err}");
    }
    let err = bridge1_with(|t| set(&t, "scanner.mount", "rpy_deg", "[0.0, nan, 0.0]")).unwrap_err();
    assert!(
        err.starts_with("scenario b.toml: scanner.mount: rpy_deg[1]"),
        "{err}"
    );
    // An object's pose in the scene, by name.
    let mut s = builtin_scenario("cube").unwrap();
    s.scene.objects[0].pose = Some(scene::PoseSpec {
        translation: [0.0, Real::NAN, 0.0],
        rpy_deg: [0.0; 3],
    });
    let err = s.validate().unwrap_err().to_string();
    assert!(err.contains("pose: translation[1]"), "{err}");
    assert!(
        err.contains(&format!("`{}`", s.scene.objects[0].name)),
        "{err}"
    );
}

#[test]
fn bad_scoring_and_noise_settings_are_named() {
    for (table, key, value, field) in [
        (
            "metrics",
            "covered_within_m",
            "nan",
            "metrics.covered_within_m",
        ),
        (
            "metrics",
            "covered_within_m",
            "0.0",
            "metrics.covered_within_m",
        ),
        (
            "metrics",
            "covered_within_m",
            "-0.01",
            "metrics.covered_within_m",
        ),
        (
            "metrics.sampling",
            "samples_per_m2",
            "nan",
            "metrics.sampling.samples_per_m2",
        ),
        (
            "metrics.sampling",
            "samples_per_m2",
            "0.0",
            "metrics.sampling.samples_per_m2",
        ),
        (
            "metrics.sampling",
            "samples_per_m2",
            "-1.0",
            "metrics.sampling.samples_per_m2",
        ),
        (
            "scanner.config.noise",
            "sigma_near_m",
            "nan",
            "`noise.sigma_near_m`",
        ),
        (
            "scanner.config.noise",
            "sigma_near_m",
            "-0.01",
            "`noise.sigma_near_m`",
        ),
        (
            "scanner.config",
            "angular_step_deg",
            "1e-7",
            "`angular_step_deg`",
        ),
        ("scanner.sweep", "step_deg", "1e-7", "`step_deg`"),
    ] {
        let err = bridge1_with(|t| set(&t, table, key, value)).unwrap_err();
        assert!(
            err.starts_with("scenario b.toml: ") && err.contains(field),
            "{table}.{key} = {value}: {err}"
        );
    }
    // The library call refuses them too, whoever built the config.
    let scene = unit_cube();
    let bad = MetricsConfig {
        covered_within_m: Real::NAN,
        ..MetricsConfig::default()
    };
    let err = coverage(&scene, &[], &bad).unwrap_err().to_string();
    assert!(err.contains("metrics.covered_within_m"), "{err}");
}

fn unit_cube() -> Scene {
    let cube = cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0));
    Scene::from_mesh("cube", cube, default_materials(), MaterialId(0)).unwrap()
}

/// Points on the cube's top face and on half of its x = 1 face.
fn some_points() -> Vec<Point3> {
    let mut pts = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let (u, v) = (f64::from(i) / 39.0, f64::from(j) / 39.0);
            pts.push(Point3::new(u, v, 1.0));
            pts.push(Point3::new(1.0, v, 0.5 * u));
        }
    }
    pts
}

#[test]
fn chunked_coverage_equals_a_brute_force_count() {
    let scene = unit_cube();
    let cfg = MetricsConfig {
        covered_within_m: 0.02,
        sampling: SamplingConfig {
            samples_per_m2: 2_000.0,
            seed: 9,
            ..SamplingConfig::default()
        },
    };
    let points = some_points();
    // Oracle: every sample against every point.
    let samples = sample_surfaces(&scene, &cfg.sampling).unwrap();
    let covered = samples
        .iter()
        .filter(|s| points.iter().any(|p| (p - s.point).norm() <= 0.02))
        .count();
    for chunk in [7, 1000, scene::DEFAULT_SAMPLE_CHUNK] {
        let r = coverage_in_chunks(&scene, &points, &cfg, chunk).unwrap();
        assert_eq!(
            (r.samples, r.covered),
            (samples.len(), covered),
            "chunk {chunk}"
        );
        assert_eq!(r.per_material.len(), 1);
        assert_eq!(r.per_material[0].samples, samples.len());
        assert!(!r.density_capped);
        assert_eq!(r.samples_per_m2, 2_000.0);
    }
    // A top face and half a side, plus 2 cm strips along their edges on the
    // neighbouring faces (4 + 1.5 + 0.5 m of edge): (1 + 0.5 + 0.12) / 6 = 0.27.
    let f = coverage(&scene, &points, &cfg).unwrap().fraction();
    assert!((f - 0.27).abs() < 0.01, "{f}");
}

#[test]
fn an_over_budget_density_scores_within_the_budget() {
    // Issue 8: samples_per_m2 = 1e12 aborted. 6 m² capped at 6 000 samples:
    // 1 000 per m², 6 000 ± 12 samples (one rounding per face), and the
    // covered fraction stays the 0.27 of the uncapped scoring.
    let scene = unit_cube();
    let cfg = MetricsConfig {
        covered_within_m: 0.02,
        sampling: SamplingConfig {
            samples_per_m2: 1e12,
            max_samples: 6_000,
            ..SamplingConfig::default()
        },
    };
    let r = coverage(&scene, &some_points(), &cfg).unwrap();
    assert!(r.density_capped);
    assert!((r.samples_per_m2 - 1_000.0).abs() < 1e-9);
    assert!(
        (6_000 - 12..=6_000 + 12).contains(&r.samples),
        "{}",
        r.samples
    );
    assert!((r.fraction() - 0.27).abs() < 0.015, "{}", r.fraction());
}

#[test]
fn no_points_is_no_accuracy_not_a_perfect_one() {
    let scene = unit_cube();
    let r = accuracy(&scene, &[], 0.5);
    assert_eq!(r.points, 0);
    assert_eq!(r.distances, None);
    assert_eq!(r.to_string(), "no points");
    // With points: a hand-computed case, 1 cm and 3 cm above the top face.
    let r = accuracy(
        &scene,
        &[Point3::new(0.5, 0.5, 1.01), Point3::new(0.5, 0.5, 1.03)],
        0.5,
    );
    let d = r.distances.unwrap();
    assert!((d.mean_m - 0.02).abs() < 1e-12 && (d.max_m - 0.03).abs() < 1e-12);
    assert_eq!(
        r.to_string(),
        "mean 20.0 mm, 95th percentile 30.0 mm, max 30.0 mm over 2 points"
    );
}
