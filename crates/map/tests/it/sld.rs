//! Scale-Like Discs (Paul §5.2) against ground truth: fused bridge1 sweeps,
//! exact surface samples (mesh vertices), the real pc2beam cloud.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::sld_support as support;

use geom::{Point3, Real, Vector3};
use map::MapError;
use map::sld::{Disc, Orientation, SldConfig, generate_discs, voxel_index};
use map::sld_io::{
    ExtraColumn, load_discs_csv, load_points, parse_discs_csv, save_discs_csv, write_discs_csv,
};
use std::collections::HashSet;
use std::path::Path;

/// The fused cloud of the acceptance tests: five sweeps of bridge1 (0.4°
/// tilt steps) kept to the robot's section of the channel, |x| ≤ 1 m (the
/// far ends, 1.5–2.5 m from every viewpoint, are sampled too sparsely for
/// n_min = 8 returns within μ = 40 mm; Paul likewise uses the points inside
/// the manipulator's work envelope, §5.3.3).
fn acceptance_cloud(noise: bool) -> support::Fused {
    let mut cfg = sensor::ScannerConfig::default();
    cfg.noise.enabled = noise;
    cfg.material_range_bias = noise;
    let mut f = support::fused_bridge1_with(cfg, 5, 0.4, 11);
    support::crop_x(&mut f, 1.0);
    f
}

fn home_voxels_are_unique(points: &[Point3], homes: &[u32], mu: Real) -> bool {
    let mut seen = HashSet::new();
    homes
        .iter()
        .all(|&h| seen.insert(voxel_index(&points[h as usize], mu).unwrap()))
}

#[test]
fn fused_bridge1_registration_voxels_and_normals() {
    let f = acceptance_cloud(true);
    assert!(f.points.len() > 150_000, "{} points", f.points.len());
    let cfg = SldConfig::default();
    let r = generate_discs(&f.points, Orientation::SensorOrigins(&f.origins), &cfg, 1).unwrap();
    // ≥ 99 % of the points registered (thesis: 99.87 %).
    let registered = r.registered_fraction();
    assert!(registered >= 0.99, "registered {registered}");
    assert_eq!(
        r.per_point_disc.iter().filter(|d| d.is_some()).count(),
        r.registered
    );
    // Paul §5.2: "each occupied geometric voxel is limited to containing only
    // one SLD" — the voxel of its home point.
    assert!(home_voxels_are_unique(&f.points, &r.homes, cfg.radius_m));
    assert!(r.discs.len() <= r.occupied_voxels);
    for (d, &h) in r.discs.iter().zip(&r.homes) {
        assert!(d.points >= cfg.min_points);
        assert_eq!(d.radius_m, cfg.radius_m);
        // The centre is the home point moved along the normal onto the plane.
        let off = d.centre - f.points[h as usize];
        assert!(off.cross(&d.normal).norm() < 1e-9 && off.norm() <= cfg.radius_m);
    }

    // Normals. A disc whose μ-ball holds points of one plane only ("pure")
    // must match its face; discs straddling an edge or a step represent
    // neither face and are excluded (counted). With σ = 10 mm range noise a
    // PCA normal over N points in a disc of radius μ has an error of about
    // σ / (√N · μ/2) radians (Rayleigh-distributed): the test checks the
    // discs reach that limit, and the 5° target where N allows it.
    let faces = support::point_faces(&f);
    let truth = support::disc_truths(f.scene(), &f.points, &faces, &r.discs, &r.homes);
    let pure: Vec<(&support::DiscTruth, &Disc)> =
        truth.iter().zip(&r.discs).filter(|(t, _)| t.pure).collect();
    assert!(
        pure.len() * 10 >= r.discs.len() * 7,
        "{} of {} pure",
        pure.len(),
        r.discs.len()
    );
    let normalised: Vec<Real> = pure
        .iter()
        .map(|(t, d)| {
            t.error_deg.to_radians() / (0.010 / (0.5 * cfg.radius_m * (d.points as Real).sqrt()))
        })
        .collect();
    let (p50, p90) = (
        support::quantile(&normalised, 0.5),
        support::quantile(&normalised, 0.9),
    );
    // Rayleigh(1): median 1.18, 90th percentile 2.15.
    assert!(
        p50 < 1.4 && p90 < 2.8,
        "normalised errors: p50 {p50}, p90 {p90}"
    );
    let dense: Vec<Real> = pure
        .iter()
        .filter(|(_, d)| d.points >= 200)
        .map(|(t, _)| t.error_deg)
        .collect();
    let within = dense.iter().filter(|e| **e <= 5.0).count() as Real / dense.len() as Real;
    eprintln!(
        "bridge1 fused: {} points, {} discs, registered {registered:.4}, {} pure, normalised error p50 {p50:.2} p90 {p90:.2}, {} discs ≥ 200 points: {within:.3} within 5°",
        f.points.len(),
        r.discs.len(),
        pure.len(),
        dense.len()
    );
    assert!(
        dense.len() > 300 && within >= 0.95,
        "{} dense discs, {within} within 5°",
        dense.len()
    );
    // Oriented toward the sensor: no pure disc faces into its surface.
    let flipped = pure.iter().filter(|(t, _)| t.error_deg > 90.0).count();
    assert!(flipped * 200 <= pure.len(), "{flipped} flipped");
}

#[test]
fn noise_free_sweeps_give_exact_normals() {
    let f = acceptance_cloud(false);
    let r = generate_discs(
        &f.points,
        Orientation::SensorOrigins(&f.origins),
        &SldConfig::default(),
        3,
    )
    .unwrap();
    let faces = support::point_faces(&f);
    let truth = support::disc_truths(f.scene(), &f.points, &faces, &r.discs, &r.homes);
    let pure: Vec<Real> = truth
        .iter()
        .filter(|t| t.pure)
        .map(|t| t.error_deg)
        .collect();
    assert!(
        pure.len() * 10 >= truth.len() * 7,
        "{} of {} pure",
        pure.len(),
        truth.len()
    );
    let worst = support::quantile(&pure, 1.0);
    eprintln!(
        "noise-free: {} of {} discs pure, worst {worst:.3}°",
        pure.len(),
        truth.len()
    );
    assert!(worst <= 5.0, "worst pure-disc normal error {worst}°");
    assert!(support::quantile(&pure, 0.99) < 0.5);
}

#[test]
fn discs_from_surface_samples_like_mesh_vertices() {
    // Exact points on bridge1's exposed faces around the robot, ~1 per
    // (5 mm)², oriented by their face normals (what a fused mesh's vertices
    // and vertex normals give).
    let world = support::bridge1();
    let scene = world.as_scene().unwrap();
    let region = geom::Aabb::new(Point3::new(-0.5, -0.75, -0.2), Point3::new(0.5, 0.75, 1.6));
    let samples = scene::sample_surfaces(
        scene,
        &scene::SamplingConfig {
            region: Some(region),
            ..scene::SamplingConfig::default()
        },
    )
    .unwrap();
    let points: Vec<Point3> = samples.iter().map(|s| s.point).collect();
    let normals: Vec<Vector3> = samples.iter().map(|s| s.normal.into_inner()).collect();
    let faces: Vec<u32> = samples.iter().map(|s| s.face.0).collect();
    let r = generate_discs(
        &points,
        Orientation::ReferenceNormals(&normals),
        &SldConfig::default(),
        5,
    )
    .unwrap();
    assert!(
        r.registered_fraction() >= 0.995,
        "{}",
        r.registered_fraction()
    );
    let truth = support::disc_truths(scene, &points, &faces, &r.discs, &r.homes);
    let pure: Vec<Real> = truth
        .iter()
        .filter(|t| t.pure)
        .map(|t| t.error_deg)
        .collect();
    assert!(
        pure.len() * 2 >= truth.len(),
        "{} of {} pure",
        pure.len(),
        truth.len()
    );
    eprintln!(
        "surface samples: {} points, {} discs, registered {:.4}, {} pure, worst {:.3}°",
        points.len(),
        r.discs.len(),
        r.registered_fraction(),
        pure.len(),
        support::quantile(&pure, 1.0)
    );
    assert!(support::quantile(&pure, 1.0) <= 5.0);
    assert!(home_voxels_are_unique(&points, &r.homes, 0.04));
}

#[test]
fn deterministic_for_a_seed() {
    let mut f = support::fused_bridge1(2, 0.8, 3);
    support::crop_x(&mut f, 1.0);
    let run = |seed| {
        generate_discs(
            &f.points,
            Orientation::SensorOrigins(&f.origins),
            &SldConfig::default(),
            seed,
        )
        .unwrap()
    };
    let a = run(7);
    let b = run(7);
    assert_eq!(a, b);
    let c = run(8);
    assert_ne!(a.discs, c.discs);
    // A different seed gives different but equally valid discs.
    for r in [&a, &c] {
        assert!(home_voxels_are_unique(&f.points, &r.homes, 0.04));
        assert!(r.registered_fraction() > 0.98);
    }
    let (na, nc) = (a.discs.len() as Real, c.discs.len() as Real);
    assert!((na - nc).abs() / na < 0.05, "{na} vs {nc} discs");
}

#[test]
fn pc2beam_real_cloud() {
    // 3 907 points of real steel beams with per-point normals (unoriented).
    let cloud = scene::io::load_cloud(Path::new(
        "../../data/pointclouds/pc2beam_steel_beams_test_points.txt",
    ))
    .unwrap();
    let normals = cloud.normals.clone().unwrap();
    let r = generate_discs(
        &cloud.points,
        Orientation::Canonical,
        &SldConfig::default(),
        1,
    )
    .unwrap();
    assert!(
        r.registered_fraction() >= 0.99,
        "{}",
        r.registered_fraction()
    );
    assert!(home_voxels_are_unique(&cloud.points, &r.homes, 0.04));
    // The file's normals up to sign, at each disc's home point. The cloud is
    // sparse (≈ 10 points per disc) and its normals come from another
    // estimator, so agreement is statistical: the median disc within 2°, and
    // 80 % within 10° (the rest straddle flange edges and corners).
    let err: Vec<Real> = r
        .discs
        .iter()
        .zip(&r.homes)
        .map(|(d, &h)| {
            let n = normals[h as usize];
            (d.normal.dot(&n).abs() / n.norm())
                .min(1.0)
                .acos()
                .to_degrees()
        })
        .collect();
    let within10 = err.iter().filter(|e| **e <= 10.0).count() as Real / err.len() as Real;
    assert!(
        support::quantile(&err, 0.5) < 2.0,
        "median {}",
        support::quantile(&err, 0.5)
    );
    eprintln!(
        "pc2beam: {} discs, registered {:.4}, median {:.2}°, {within10:.3} within 10°",
        r.discs.len(),
        r.registered_fraction(),
        support::quantile(&err, 0.5)
    );
    assert!(within10 >= 0.8, "{within10}");
    // Canonical orientation: largest component positive.
    for d in &r.discs {
        let n = d.normal;
        let big = [n.x, n.y, n.z]
            .into_iter()
            .max_by(|a, b| a.abs().total_cmp(&b.abs()))
            .unwrap();
        assert!(big > 0.0);
    }
}

#[test]
fn viewpoint_and_canonical_orientation() {
    let points: Vec<Point3> = (0..30)
        .flat_map(|i| {
            (0..30).map(move |j| Point3::new(f64::from(i) * 0.01, f64::from(j) * 0.01, 1.0))
        })
        .collect();
    let below = generate_discs(
        &points,
        Orientation::Viewpoint(Point3::origin()),
        &SldConfig::default(),
        0,
    )
    .unwrap();
    assert!(below.discs.iter().all(|d| d.normal.z < -0.999));
    let canon = generate_discs(&points, Orientation::Canonical, &SldConfig::default(), 0).unwrap();
    assert!(canon.discs.iter().all(|d| d.normal.z > 0.999));
    let origins = vec![Point3::new(0.1, 0.1, 2.0); points.len()];
    let above = generate_discs(
        &points,
        Orientation::SensorOrigins(&origins),
        &SldConfig::default(),
        0,
    )
    .unwrap();
    assert!(above.discs.iter().all(|d| d.normal.z > 0.999));
    assert_eq!(above.registered, points.len());
}

#[test]
fn sparse_and_degenerate_input() {
    let cfg = SldConfig::default();
    // Empty cloud.
    let r = generate_discs(&[], Orientation::Canonical, &cfg, 0).unwrap();
    assert!(r.discs.is_empty() && r.registered_fraction() == 1.0);
    // Collinear points have no normal: no disc, nothing registered.
    let line: Vec<Point3> = (0..50)
        .map(|i| Point3::new(f64::from(i) * 0.001, 0.0, 0.0))
        .collect();
    let r = generate_discs(&line, Orientation::Canonical, &cfg, 0).unwrap();
    assert!(r.discs.is_empty() && r.registered == 0);
    // Fewer than n_min points within μ.
    let few: Vec<Point3> = (0..7)
        .map(|i| Point3::new(f64::from(i) * 0.003, f64::from(i % 2) * 0.003, 0.0))
        .collect();
    assert!(
        generate_discs(&few, Orientation::Canonical, &cfg, 0)
            .unwrap()
            .discs
            .is_empty()
    );
}

#[test]
fn bad_input_is_an_error() {
    let cfg = SldConfig::default();
    let mut pts = vec![Point3::new(0.0, 0.0, 0.0); 10];
    pts[4].y = f64::NAN;
    assert!(matches!(
        generate_discs(&pts, Orientation::Canonical, &cfg, 0),
        Err(MapError::NonFinite {
            what: "point",
            index: 4
        })
    ));
    let pts = vec![Point3::origin(); 10];
    let origins = vec![Point3::origin(); 9];
    assert!(matches!(
        generate_discs(&pts, Orientation::SensorOrigins(&origins), &cfg, 0),
        Err(MapError::LengthMismatch {
            expected: 10,
            got: 9,
            ..
        })
    ));
    for bad in [
        (
            SldConfig {
                radius_m: 0.0,
                ..cfg
            },
            "radius_m",
            "0",
        ),
        (
            SldConfig {
                min_points: 2,
                ..cfg
            },
            "min_points",
            "2",
        ),
        (
            SldConfig {
                plane_tolerance_m: Some(-1.0),
                ..cfg
            },
            "plane_tolerance_m",
            "-1",
        ),
        (
            SldConfig {
                min_eigen_ratio: 0.5,
                ..cfg
            },
            "min_eigen_ratio",
            "0.5",
        ),
    ] {
        let e = generate_discs(&pts, Orientation::Canonical, &bad.0, 0).unwrap_err();
        assert!(
            matches!(e, MapError::Config { stage: "SLD", field, .. } if field == bad.1),
            "{e:?}"
        );
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("SLD config `{}`: expected ", bad.1))
                && msg.ends_with(&format!(", got {}", bad.2)),
            "{msg}"
        );
    }
    let far = vec![Point3::new(1e9, 0.0, 0.0)];
    assert!(matches!(
        generate_discs(&far, Orientation::Canonical, &cfg, 0),
        Err(MapError::OutOfRange { index: 0, .. })
    ));
}

#[test]
fn config_loads_from_json_with_defaults() {
    let cfg: SldConfig = serde_json::from_str(r#"{"radius_m": 0.025}"#).unwrap();
    assert_eq!(cfg.radius_m, 0.025);
    assert_eq!(cfg.min_points, 8);
    assert_eq!(cfg.plane_tolerance(), 0.025);
    assert!(serde_json::from_str::<SldConfig>(r#"{"radius": 1}"#).is_err());
}

#[test]
fn csv_round_trip_and_errors() {
    let mut f = support::fused_bridge1(1, 1.2, 1);
    support::crop_x(&mut f, 0.5);
    let r = generate_discs(
        &f.points,
        Orientation::SensorOrigins(&f.origins),
        &SldConfig::default(),
        1,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("discs.csv");
    let seg = ExtraColumn {
        name: "segment".into(),
        values: (0..r.discs.len()).map(|i| (i % 3) as Real).collect(),
    };
    save_discs_csv(&path, &r.discs, &[seg]).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("cx,cy,cz,nx,ny,nz,radius,points,segment\n"));
    let back = load_discs_csv(&path).unwrap();
    assert_eq!(back.len(), r.discs.len());
    for (a, b) in back.iter().zip(&r.discs) {
        assert_eq!(a.centre, b.centre);
        assert!((a.normal.into_inner() - b.normal.into_inner()).norm() < 1e-15);
        assert_eq!((a.radius_m, a.points), (b.radius_m, b.points));
    }
    // Columns in another order, blank lines.
    let d = parse_discs_csv(
        "points,radius,nz,ny,nx,cz,cy,cx\n\n5,0.04,2,0,0,3,2,1\n",
        "t",
    )
    .unwrap();
    assert_eq!(d[0].centre, Point3::new(1.0, 2.0, 3.0));
    assert_eq!(d[0].normal.z, 1.0);
    // Errors name the source, the line and the field.
    let e = parse_discs_csv("cx,cy,cz,nx,ny,nz,radius\n", "a.csv").unwrap_err();
    assert!(
        e.to_string().contains("a.csv:1") && e.to_string().contains("points"),
        "{e}"
    );
    let e = parse_discs_csv(
        "cx,cy,cz,nx,ny,nz,radius,points\n0,0,0,0,0,1,0.04,3\n0,x,0,0,0,1,0.04,3\n",
        "b.csv",
    )
    .unwrap_err();
    assert!(
        e.to_string().starts_with("b.csv:3") && e.to_string().contains("cy"),
        "{e}"
    );
    let e = parse_discs_csv(
        "cx,cy,cz,nx,ny,nz,radius,points\n0,0,0,0,0,0,0.04,3\n",
        "c.csv",
    )
    .unwrap_err();
    assert!(e.to_string().contains("normal"), "{e}");
    let e = parse_discs_csv(
        "cx,cy,cz,nx,ny,nz,radius,points\n0,0,0,0,0,1,0.04,3.5\n",
        "d.csv",
    )
    .unwrap_err();
    assert!(e.to_string().contains("points"), "{e}");
    // A centre beyond ±1e7 m (geom::MAX_COORDINATE_M) is refused.
    let e = parse_discs_csv(
        "cx,cy,cz,nx,ny,nz,radius,points\n1e30,0,0,0,0,1,0.04,3\n",
        "f.csv",
    )
    .unwrap_err();
    assert!(
        e.to_string().starts_with("f.csv:2") && e.to_string().contains("`cx`"),
        "{e}"
    );
    assert!(parse_discs_csv("", "e.csv").is_err());
    let missing = dir.path().join("missing.csv");
    let e = load_discs_csv(&missing).unwrap_err();
    assert!(
        matches!(&e, MapError::Io { path, op: map::IoOp::Read, .. } if *path == missing),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with(&format!("{}: cannot read: ", missing.display())),
        "{e}"
    );
    // Bad extra columns are refused before anything is written.
    let mut out = Vec::new();
    let bad = ExtraColumn {
        name: "a,b".into(),
        values: vec![0.0; r.discs.len()],
    };
    assert!(write_discs_csv(&mut out, &r.discs, &[bad]).is_err());
    let short = ExtraColumn {
        name: "s".into(),
        values: vec![],
    };
    assert!(write_discs_csv(&mut out, &r.discs, &[short]).is_err());
    assert!(out.is_empty());
}

#[test]
fn scan_ply_with_origins_loads_and_orients() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scan.ply");
    let pts: Vec<Point3> = (0..20)
        .flat_map(|i| {
            (0..20).map(move |j| Point3::new(f64::from(i) * 0.01, f64::from(j) * 0.01, 1.5))
        })
        .collect();
    let col = |k: usize| pts.iter().map(|p| p[k] as f32).collect::<Vec<f32>>();
    let zeros = vec![0.0f32; pts.len()];
    let ones = vec![1.0f32; pts.len()];
    let (x, y, z) = (col(0), col(1), col(2));
    scene::io::write_ply_vertices_file(
        &path,
        &["x", "y", "z", "intensity", "ox", "oy", "oz"],
        &[&x, &y, &z, &ones, &zeros, &zeros, &zeros],
    )
    .unwrap();
    let loaded = load_points(&path).unwrap();
    assert_eq!(loaded.points.len(), 400);
    assert_eq!(loaded.origins.as_ref().unwrap()[7], Point3::origin());
    let r = generate_discs(
        &loaded.points,
        loaded.orientation(),
        &SldConfig::default(),
        2,
    )
    .unwrap();
    assert!(!r.discs.is_empty() && r.discs.iter().all(|d| d.normal.z < -0.999));
    assert!(load_points(&dir.path().join("none.ply")).is_err());
}
