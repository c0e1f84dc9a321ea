//! The Laser Range Classifier (Paul App. B) on simulated observations: accuracy
//! inside its constraints, degradation outside them, the constraints.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Point3, Real, UnitVector3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene::default_materials;
use sensor::classifier::{
    ClassifyError, Lrc, LrcConfig, Observation, ObservationSetup, ObservedReturn, TrainingConfig,
    extract_features, simulate_observation,
};
use sensor::{Scanner, ScannerConfig};
use std::sync::OnceLock;

/// Sweeps at 0.8° steps keep the test quick; features do not depend on the
/// sampling density (the fits weigh incidence bins equally).
const STEP_DEG: Real = 0.8;

fn lrc() -> &'static Lrc {
    static LRC: OnceLock<Lrc> = OnceLock::new();
    LRC.get_or_init(|| {
        let training = TrainingConfig {
            observations_per_material: 100,
            sweep_step_deg: STEP_DEG,
            ..TrainingConfig::default()
        };
        Lrc::train(
            LrcConfig::default(),
            &training,
            &default_materials(),
            &ScannerConfig::default(),
            1,
        )
        .unwrap()
    })
}

/// Accuracy over `per_material` fresh observations of each material drawn by
/// `setup`, classified under `config`: `(accuracy, classified, refused)`.
fn accuracy(
    config: &LrcConfig,
    per_material: usize,
    seed: u64,
    setup: impl Fn(&mut ChaCha8Rng) -> ObservationSetup,
) -> (Real, usize, usize) {
    let materials = default_materials();
    let scanner = ScannerConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut right, mut total, mut refused) = (0, 0, 0);
    for _ in 0..per_material {
        for (m, material) in materials.iter().enumerate() {
            let s = setup(&mut rng);
            let obs = simulate_observation(&s, material, &scanner, &mut rng).unwrap();
            match lrc().classify_with(&obs, config) {
                Ok(c) => {
                    let sum: Real = c.posterior.iter().sum();
                    assert!((sum - 1.0).abs() < 1e-12 && c.posterior.iter().all(|p| *p >= 0.0));
                    total += 1;
                    right += usize::from(c.best() == m);
                }
                Err(_) => refused += 1,
            }
        }
    }
    (right as Real / total.max(1) as Real, total, refused)
}

fn inside(rng: &mut ChaCha8Rng) -> ObservationSetup {
    ObservationSetup {
        range_m: rng.random_range(0.25..0.8),
        incidence_rad: rng.random_range(0.0..42f64.to_radians()),
        tilt_direction_rad: rng.random_range(0.0..std::f64::consts::TAU),
        sweep_step_deg: STEP_DEG,
        ..ObservationSetup::default()
    }
}

#[test]
fn identifies_the_five_materials_inside_the_constraints() {
    let (acc, total, refused) = accuracy(&LrcConfig::default(), 40, 7, inside);
    eprintln!(
        "inside the constraints: accuracy {acc:.3} over {total} observations, {refused} refused"
    );
    // Refused: poses whose patch has too few returns in the ±20° window or
    // too narrow a span of incidence, and a few atypical ones (the χ² tail).
    assert!(total >= 140, "{total} classified, {refused} refused");
    assert!(acc >= 0.9, "accuracy {acc}");
}

#[test]
fn degrades_visibly_outside_the_constraints() {
    let (inside_acc, _, _) = accuracy(&LrcConfig::default(), 20, 8, inside);
    // At 1.5 m the 0.18 m patch shows only ±7° of the curves.
    let (far, n_far, _) = accuracy(&LrcConfig::permissive(), 20, 9, |rng| ObservationSetup {
        range_m: 1.5,
        ..inside(rng)
    });
    // At 60° incidence no return is within ±20°: fit whatever is seen.
    let wide = LrcConfig {
        fit_window_deg: 90.0,
        ..LrcConfig::permissive()
    };
    let (oblique, n_oblique, _) = accuracy(&wide, 20, 10, |rng| ObservationSetup {
        incidence_rad: 60f64.to_radians(),
        ..inside(rng)
    });
    eprintln!(
        "accuracy: inside {inside_acc:.3}, at 1.5 m {far:.3} ({n_far}), at 60° {oblique:.3} ({n_oblique})"
    );
    assert!(n_far >= 40 && n_oblique >= 40);
    assert!(far < inside_acc - 0.25, "at 1.5 m: {far} vs {inside_acc}");
    assert!(
        oblique < inside_acc - 0.25,
        "at 60°: {oblique} vs {inside_acc}"
    );
}

#[test]
fn constraints_are_enforced() {
    let materials = default_materials();
    let scanner = ScannerConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let cfg = LrcConfig::default();
    let mut observe = |setup: ObservationSetup| {
        simulate_observation(&setup, &materials[0], &scanner, &mut rng).unwrap()
    };
    let base = ObservationSetup {
        sweep_step_deg: STEP_DEG,
        ..ObservationSetup::default()
    };
    let ok = observe(base);
    let (_, g) = extract_features(&ok, &cfg).unwrap();
    assert!((g.range_m - 0.5).abs() < 0.01 && g.incidence_rad.to_degrees() < 2.0);
    assert!(g.normal.z > 0.999);
    let far = observe(ObservationSetup {
        range_m: 0.9,
        ..base
    });
    assert!(matches!(
        extract_features(&far, &cfg),
        Err(ClassifyError::OutOfRange { .. })
    ));
    let near = observe(ObservationSetup {
        range_m: 0.2,
        ..base
    });
    assert!(matches!(
        extract_features(&near, &cfg),
        Err(ClassifyError::OutOfRange { .. })
    ));
    let oblique = observe(ObservationSetup {
        incidence_rad: 45f64.to_radians(),
        ..base
    });
    match extract_features(&oblique, &cfg) {
        Err(ClassifyError::TooOblique { incidence_deg, .. }) => {
            assert!((incidence_deg - 45.0).abs() < 1.5, "{incidence_deg}");
        }
        other => panic!("{other:?}"),
    }
    // A single scan is one line on the patch: no plane, no incidence.
    let single = observe(ObservationSetup {
        sweep_step_deg: 0.0,
        ..base
    });
    assert_eq!(
        extract_features(&single, &cfg).unwrap_err(),
        ClassifyError::Degenerate
    );
    // A sweep whose scans all miss normal incidence by 25° or more (the
    // surface tilted 30° along the nodding direction, a ±5° sweep): no
    // return within ±20°.
    let tilted = observe(ObservationSetup {
        incidence_rad: 30f64.to_radians(),
        tilt_direction_rad: std::f64::consts::FRAC_PI_2,
        sweep_half_deg: 5.0,
        ..base
    });
    assert!(matches!(
        extract_features(&tilted, &cfg),
        Err(ClassifyError::TooFewPoints { found: 0, .. })
    ));
    // The full sweep reaches it.
    let swept = observe(ObservationSetup {
        incidence_rad: 30f64.to_radians(),
        tilt_direction_rad: std::f64::consts::FRAC_PI_2,
        ..base
    });
    assert!(extract_features(&swept, &cfg).is_ok());
    // Too few returns at all.
    let mut few = ok.clone();
    few.returns.truncate(10);
    assert!(matches!(
        extract_features(&few, &cfg),
        Err(ClassifyError::TooFewPoints { .. })
    ));
    // Bad returns are named.
    let mut bad = ok.clone();
    bad.returns[17].intensity = Real::NAN;
    assert_eq!(
        extract_features(&bad, &cfg),
        Err(ClassifyError::InvalidReturn {
            index: 17,
            field: "intensity"
        })
    );
    let mut bad = ok;
    bad.returns[3].range_m = -1.0;
    assert_eq!(
        extract_features(&bad, &cfg),
        Err(ClassifyError::InvalidReturn {
            index: 3,
            field: "range_m"
        })
    );
}

#[test]
fn features_follow_the_appendix_b_curves() {
    // Noise-free scanner, normal view, 0.5 m. Broad lobes (rough surfaces)
    // give smooth intensity curves that a parabola fits well; the sharper the
    // specular peak, the more negative its curvature, until the lobe is so
    // narrow (plastic, stainless steel) that the parabola fails and its MSE
    // — App. B's measure of that failure — carries the information.
    let scanner = ScannerConfig {
        noise: sensor::RangeNoise {
            enabled: false,
            ..sensor::RangeNoise::default()
        },
        reflection: sensor::ReflectionModel {
            intensity_noise_rel: 0.0,
            ..sensor::ReflectionModel::default()
        },
        ..ScannerConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let f: Vec<_> = default_materials()
        .iter()
        .map(|m| {
            let obs =
                simulate_observation(&ObservationSetup::default(), m, &scanner, &mut rng).unwrap();
            extract_features(&obs, &LrcConfig::default()).unwrap().0
        })
        .collect();
    let [painted, timber, concrete, plastic, steel] = [&f[0], &f[1], &f[2], &f[3], &f[4]];
    assert!(painted.intensity_quadratic < timber.intensity_quadratic);
    assert!(timber.intensity_quadratic < concrete.intensity_quadratic);
    assert!(concrete.intensity_quadratic < 0.0);
    let mse = [concrete, timber, painted, plastic, steel].map(|x| x.intensity_mse);
    assert!(mse.windows(2).all(|w| w[0] < w[1]), "{mse:?}");
    // Specular returns read short near 0°: stainless steel's range error
    // curve is the sharpest.
    assert!(steel.range_quadratic < 0.0 && steel.range_mse > concrete.range_mse);
}

#[test]
fn observations_from_scans_and_training_determinism() {
    // Observation::from_sweep keeps the returns on the target patch.
    let world = sensor_plane();
    let scanner = Scanner::new(ScannerConfig::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pose = geom::Isometry3::translation(0.0, 0.0, 0.5);
    let scan = scanner.scan(&world, &pose, &mut rng);
    let mut builder = sensor::SweepBuilder::new(scanner.bearings_rad()).unwrap();
    scan.push_to(&mut builder).unwrap();
    let sweep = builder.finish().unwrap();
    let target = Point3::new(0.0, 0.0, 1.0);
    let obs = Observation::from_sweep(&sweep, &target, 0.1);
    assert!(!obs.returns.is_empty());
    assert!(
        obs.returns
            .iter()
            .all(|r| (r.point() - target).norm() <= 0.1)
    );
    assert_eq!(obs.target, Some(target));

    // Training is deterministic for a seed.
    let small = TrainingConfig {
        observations_per_material: 12,
        sweep_step_deg: 2.0,
        ..TrainingConfig::default()
    };
    let mats = &default_materials()[..2];
    let a = Lrc::train(
        LrcConfig::default(),
        &small,
        mats,
        &ScannerConfig::default(),
        9,
    )
    .unwrap();
    let b = Lrc::train(
        LrcConfig::default(),
        &small,
        mats,
        &ScannerConfig::default(),
        9,
    )
    .unwrap();
    assert_eq!(a, b);
    assert_eq!(a.material_names(), vec!["painted_metal", "timber"]);
    // A config that no observation can satisfy fails with a message.
    let impossible = LrcConfig {
        min_points: 100_000,
        ..LrcConfig::default()
    };
    let e = Lrc::train(impossible, &small, mats, &ScannerConfig::default(), 9).unwrap_err();
    assert!(e.to_string().contains("painted_metal"), "{e}");
}

#[test]
fn hand_made_observation_is_checked() {
    let ret = ObservedReturn {
        origin: Point3::origin(),
        direction: UnitVector3::new_unchecked(Vector3::z()),
        range_m: 0.5,
        intensity: 100.0,
    };
    // Identical rays: all points coincide, no plane.
    let obs = Observation {
        returns: vec![ret; 100],
        target: None,
    };
    assert_eq!(
        extract_features(&obs, &LrcConfig::default()),
        Err(ClassifyError::Degenerate)
    );
}

/// The underside of a slab at z = 1 (painted metal).
fn sensor_plane() -> scene::Scene {
    let mesh = scene::primitives::cuboid(Point3::new(-2.0, -2.0, 1.0), Point3::new(2.0, 2.0, 1.05));
    scene::Scene::from_mesh("slab", mesh, default_materials(), scene::MaterialId(0)).unwrap()
}

#[test]
fn refuses_patches_that_are_not_flat_or_unlike_every_material() {
    let materials = default_materials();
    let scanner = ScannerConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let setup = ObservationSetup {
        incidence_rad: 0.17,
        sweep_step_deg: STEP_DEG,
        ..ObservationSetup::default()
    };
    let flat = simulate_observation(&setup, &materials[0], &scanner, &mut rng).unwrap();
    let c = lrc().classify(&flat).unwrap();
    // Range noise alone: σ = 0.01 m along each ray, σ cos φ across the plane.
    let rms = c.geometry.plane_rms_m;
    assert!((0.008..=0.0101).contains(&rms), "plane RMS {rms}");
    assert!(rms <= lrc().plane_rms_limit_m);
    assert_eq!(c.mahalanobis_sq.len(), materials.len());

    // Fold half of the patch (the side x > 0 of the plane z = 0 it lies in)
    // by 45°: a ridge, its points about 2 cm RMS off their best plane.
    let folded = Observation {
        returns: flat
            .returns
            .iter()
            .map(|r| {
                let p = r.point();
                let p = Point3::new(p.x, p.y, p.z + p.x.max(0.0));
                let (direction, range_m) = UnitVector3::new_and_get(p - r.origin);
                ObservedReturn {
                    direction,
                    range_m,
                    ..*r
                }
            })
            .collect(),
        target: flat.target,
    };
    match lrc().classify(&folded) {
        Err(ClassifyError::NotFlat { rms_m, limit_m }) => {
            assert!(rms_m > 1.5 * limit_m, "{rms_m} vs {limit_m}");
        }
        other => panic!("a folded patch gave {other:?}"),
    }
    assert!(
        lrc()
            .check_geometry(&folded, &LrcConfig::default())
            .is_err()
    );
    assert!(lrc().check_geometry(&flat, &LrcConfig::default()).is_ok());

    // Five times brighter than the material: no trained curve is like it.
    let bright = Observation {
        returns: flat
            .returns
            .iter()
            .map(|r| ObservedReturn {
                intensity: 5.0 * r.intensity,
                ..*r
            })
            .collect(),
        target: flat.target,
    };
    match lrc().classify(&bright) {
        Err(ClassifyError::Atypical { distance_sq, limit }) => assert!(distance_sq > limit),
        other => panic!("a patch brighter than any material gave {other:?}"),
    }
    // Its geometry is fine, and without the typicality limit it is
    // classified (confidently, and meaninglessly).
    assert!(lrc().check_geometry(&bright, &LrcConfig::default()).is_ok());
    let anything = LrcConfig {
        max_mahalanobis_sq: Real::INFINITY,
        ..LrcConfig::default()
    };
    assert!(lrc().classify_with(&bright, &anything).is_ok());
}

#[test]
fn mahalanobis_distances_of_fresh_observations_follow_chi_square() {
    // Observations like the training ones: the squared distance to their own
    // material's density is χ² with 4 degrees of freedom (median 3.36, 1 %
    // above 13.28) as far as the Gaussian model holds.
    let materials = default_materials();
    let scanner = ScannerConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    let mut own = Vec::new();
    let permissive_typicality = LrcConfig {
        max_mahalanobis_sq: Real::INFINITY,
        ..LrcConfig::default()
    };
    for _ in 0..30 {
        for (m, material) in materials.iter().enumerate() {
            let obs =
                simulate_observation(&inside(&mut rng), material, &scanner, &mut rng).unwrap();
            if let Ok(c) = lrc().classify_with(&obs, &permissive_typicality) {
                own.push(c.mahalanobis_sq[m]);
            }
        }
    }
    own.sort_by(Real::total_cmp);
    let median = own[own.len() / 2];
    let beyond = own
        .iter()
        .filter(|q| **q > sensor::classifier::CHI2_4_P99)
        .count() as Real
        / own.len() as Real;
    eprintln!(
        "{} observations: median {median:.2}, {:.1} % beyond the 99th percentile",
        own.len(),
        100.0 * beyond
    );
    assert!(own.len() >= 100);
    assert!((2.0..6.0).contains(&median), "median {median}");
    assert!(beyond <= 0.1, "{beyond}");
}

/// `Lrc::geometry_passes` (counting, stopping early) decides as
/// `Lrc::check_geometry` (the full features) does, on observations inside
/// and outside every constraint: ranges and incidences beyond the limits,
/// returns thinned to around the 50 the fit window needs, patches small
/// enough for a narrow incidence span, and patches folded off their plane.
#[test]
fn geometry_passes_decides_as_check_geometry() {
    let materials = default_materials();
    let scanner = ScannerConfig::default();
    let config = LrcConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(45);
    let mut outcomes = std::collections::BTreeMap::<String, usize>::new();
    for n in 0..400 {
        let small = n % 3 == 0;
        let setup = ObservationSetup {
            range_m: rng.random_range(0.15..0.95),
            incidence_rad: rng.random_range(0.0..55f64.to_radians()),
            tilt_direction_rad: rng.random_range(0.0..std::f64::consts::TAU),
            sweep_step_deg: if small { 0.2 } else { STEP_DEG },
            sweep_half_deg: rng.random_range(1.0..30.0),
            patch_radius_m: if small {
                rng.random_range(0.02..0.05)
            } else {
                0.18
            },
        };
        let material = &materials[n % materials.len()];
        let mut obs = simulate_observation(&setup, material, &scanner, &mut rng).unwrap();
        // Keep about `keep` returns (spread over the patch), to land around
        // the fit window's 50.
        let keep = rng.random_range(20..400usize);
        if !small && obs.returns.len() > keep {
            let every = obs.returns.len().div_ceil(keep);
            obs.returns = obs.returns.into_iter().step_by(every).collect();
        }
        if n % 7 == 0 {
            let fold = rng.random_range(0.0..1.0);
            for r in &mut obs.returns {
                let p = r.point();
                let p = Point3::new(p.x, p.y, p.z + fold * p.x.max(0.0));
                let (direction, range_m) = UnitVector3::new_and_get(p - r.origin);
                *r = ObservedReturn {
                    direction,
                    range_m,
                    ..*r
                };
            }
        }
        let full = lrc().check_geometry(&obs, &config);
        let fast = lrc().geometry_passes(&obs, &config);
        assert_eq!(
            full.is_ok(),
            fast.is_ok(),
            "{setup:?}: {full:?} against {fast:?}"
        );
        let kind = match &full {
            Ok(_) => "passes".to_string(),
            Err(e) => format!("{e:?}")
                .split([' ', '{'])
                .next()
                .unwrap()
                .to_string(),
        };
        *outcomes.entry(kind).or_default() += 1;
    }
    // Every outcome was exercised, each enough times to mean something.
    for kind in [
        "passes",
        "OutOfRange",
        "TooOblique",
        "TooFewPoints",
        "NarrowIncidence",
        "NotFlat",
    ] {
        let seen = outcomes.get(kind).copied().unwrap_or(0);
        assert!(seen >= 5, "{kind}: {seen} of 400 ({outcomes:?})");
    }
}
