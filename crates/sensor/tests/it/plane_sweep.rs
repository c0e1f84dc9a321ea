//! A nodding sweep of a plane: point count and noise against analytic predictions.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Isometry3, Point3, Real, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scene::{MaterialId, RayCast, Scene, default_materials, primitives::cuboid};
use sensor::{Scanner, ScannerConfig, SweepConfig};

/// A 4 m × 4 m slab whose underside is the plane z = 1.
fn slab() -> Scene {
    let mesh = cuboid(Point3::new(-2.0, -2.0, 1.0), Point3::new(2.0, 2.0, 1.05));
    Scene::from_mesh("slab", mesh, default_materials(), MaterialId(0)).unwrap()
}

/// The scanner at the origin tilted by `t` about its y axis (the nodding axis).
fn pose(t: Real) -> Isometry3 {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), t),
    )
}

#[test]
fn sweep_of_a_plane_matches_the_prediction() {
    let world = slab();
    let config = ScannerConfig {
        material_range_bias: false,
        ..ScannerConfig::default()
    };
    let scanner = Scanner::new(config).unwrap();
    assert_eq!(scanner.ray_count(), 342);
    let sweep = SweepConfig::default();
    let tilts = sweep.tilt_values(0.0, None);
    assert_eq!(tilts.len(), 151);
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let swept = scanner
        .nodding_sweep(&world, &Isometry3::identity(), &sweep, &mut rng)
        .unwrap();
    let shape = swept.grid_shape().unwrap();
    assert_eq!(shape.scans as usize, tilts.len());
    assert_eq!(shape.rays_per_scan as usize, scanner.ray_count());
    assert_eq!(swept.scanner_poses().len(), tilts.len());
    for (&t, p) in tilts.iter().zip(swept.scanner_poses()) {
        assert!((p.rotation.angle_to(&pose(t).rotation)).abs() < 1e-12);
    }
    let mut predicted = 0usize;
    let mut deviations = Vec::new();
    for &t in &tilts {
        for theta in scanner.bearings_rad() {
            // Analytic: direction (cos θ sin t, −sin θ, cos θ cos t) meets z = 1 at
            // (tan t, −tan θ / cos t, 1), inside the slab when |y| ≤ 2.
            let y = -theta.tan() / t.cos();
            let lambda = 1.0 / (theta.cos() * t.cos());
            predicted += usize::from(y.abs() <= 2.0 && lambda <= 4.0);
        }
    }
    let measured = swept.len();
    for p in swept.points() {
        let c = p.cell.unwrap();
        let (t, theta) = (
            tilts[c.scan as usize],
            scanner.bearings_rad()[c.ray as usize],
        );
        let y = -theta.tan() / t.cos();
        let lambda = 1.0 / (theta.cos() * t.cos());
        assert!(
            y.abs() <= 2.0 && lambda <= 4.0,
            "return where none is predicted: t={t}, θ={theta}"
        );
        deviations.push(p.range_m() - lambda);
        // The point lies on the ray at the measured range.
        let dir = Vector3::new(theta.cos() * t.sin(), -theta.sin(), theta.cos() * t.cos());
        assert!((p.point - Point3::from(dir * p.range_m())).norm() < 1e-9);
        assert_eq!(p.origin, Point3::origin());
        assert_eq!(p.material, Some(MaterialId(0)));
        assert!(p.intensity > 0.0);
    }
    assert_eq!(measured, predicted);
    assert!(predicted > 45_000, "{predicted}");
    // Noise: σ = 10 mm below 1 m and 1 % beyond; normalised deviations ~ N(0, 1).
    let n = deviations.len() as Real;
    let mean = deviations.iter().sum::<Real>() / n;
    assert!(mean.abs() < 3.0 * 0.015 / n.sqrt(), "mean {mean}");
    let sd = (deviations.iter().map(|d| (d - mean).powi(2)).sum::<Real>() / n).sqrt();
    // Ranges here lie in [1, 2.41] m: σ between 10 and 24 mm.
    assert!(sd > 0.010 && sd < 0.020, "sd {sd}");
    assert!(deviations.iter().all(|d| d.abs() < 6.0 * 0.0241));
}

#[test]
fn same_seed_same_scan_and_noise_can_be_disabled() {
    let world = slab();
    let scanner = Scanner::new(ScannerConfig::default()).unwrap();
    let a = scanner.scan(&world, &pose(0.1), &mut ChaCha8Rng::seed_from_u64(3));
    let b = scanner.scan(&world, &pose(0.1), &mut ChaCha8Rng::seed_from_u64(3));
    assert_eq!(a, b);
    let exact = Scanner::new(ScannerConfig {
        noise: sensor::RangeNoise {
            enabled: false,
            ..Default::default()
        },
        material_range_bias: false,
        ..ScannerConfig::default()
    })
    .unwrap();
    let s = exact.scan(&world, &pose(0.0), &mut ChaCha8Rng::seed_from_u64(3));
    for r in s.returns.iter().flatten() {
        assert!((r.point.z - 1.0).abs() < 1e-9);
    }
}

#[test]
fn full_field_and_bad_configs() {
    let full = Scanner::new(ScannerConfig::full_field()).unwrap();
    assert_eq!(full.ray_count(), 667);
    let bad = ScannerConfig {
        half_fov_deg: 150.0,
        ..ScannerConfig::default()
    };
    let err = Scanner::new(bad).unwrap_err().to_string();
    assert!(err.contains("half_fov_deg") && err.contains("150"), "{err}");
    // Nothing within range: every slot empty.
    let world = slab();
    let far = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, -10.0),
        UnitQuaternion::identity(),
    );
    let s = full.scan(&world, &far, &mut ChaCha8Rng::seed_from_u64(1));
    assert!(s.returns.iter().all(Option::is_none));
    assert!(
        world
            .cast_ray(&geom::Ray::new(Point3::origin(), Vector3::z_axis()), 4.0)
            .is_some()
    );
}

#[test]
fn range_finder_reads_the_plane() {
    let world = slab();
    let rf = sensor::RangeFinder {
        origin: Point3::new(0.0, 0.0, 0.9),
        axis: Vector3::z_axis(),
        max_range_m: 0.2,
        noise_sigma_m: 0.0,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let p = rf
        .measure(&world, &Isometry3::identity(), &mut rng)
        .unwrap();
    assert!((p.distance_m - 0.1).abs() < 1e-12);
    assert!((p.point - Point3::new(0.0, 0.0, 1.0)).norm() < 1e-12);
    assert_eq!(p.axis, Vector3::z_axis());
    // Mounted lower, out of range.
    let low = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, -0.5),
        UnitQuaternion::identity(),
    );
    assert!(rf.measure(&world, &low, &mut rng).is_none());
}
