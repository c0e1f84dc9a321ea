//! The library side of `surveyor map`: scan files in, `mesh.ply` and
//! `occupancy.json` out; configs from TOML; bad files named in errors.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code may panic

use geom::{Isometry3, Point3, Real, Translation3, UnitQuaternion};
use map::{MapConfig, Mapper, OccupancyReport, build_from_scans};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sensor::Sweep;
use sensor::{Scanner, ScannerConfig, SweepConfig};
use std::path::Path;

/// A bridge1 sweep from the start pose, looking up.
fn bridge_sweep() -> Sweep {
    let world = scene::builtin::scene("bridge1")
        .unwrap()
        .build(Path::new("."))
        .unwrap();
    let scanner = Scanner::new(ScannerConfig::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let start = Isometry3::from_parts(
        Translation3::new(0.317, 0.0, 0.7716),
        UnitQuaternion::identity(),
    );
    scanner
        .nodding_sweep(&world, &start, &SweepConfig::default(), &mut rng)
        .unwrap()
}

/// Write points as `surveyor scan` does: float x y z intensity ox oy oz.
fn write_scan(path: &Path, origins: &[Point3], points: &[Point3]) {
    let mut cols: Vec<Vec<f32>> = vec![Vec::new(); 7];
    for (o, p) in origins.iter().zip(points) {
        for (c, v) in cols.iter_mut().zip([p.x, p.y, p.z, 100.0, o.x, o.y, o.z]) {
            c.push(v as f32);
        }
    }
    let refs: Vec<&[f32]> = cols.iter().map(Vec::as_slice).collect();
    scene::io::write_ply_vertices_file(
        path,
        &["x", "y", "z", "intensity", "ox", "oy", "oz"],
        &refs,
    )
    .unwrap();
}

#[test]
fn scan_files_to_mesh_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = bridge_sweep();
    let (origins, points) = (sweep.origins(), sweep.positions());
    let half = points.len() / 2;
    let (a, b) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
    write_scan(&a, &origins[..half], &points[..half]);
    write_scan(&b, &origins[half..], &points[half..]);
    let sweeps = [Sweep::read_ply(&a).unwrap(), Sweep::read_ply(&b).unwrap()];
    assert_eq!(sweeps[0].len() + sweeps[1].len(), points.len());

    let config = MapConfig::default().with_voxel_m(0.02);
    let out = build_from_scans(&sweeps, &config).unwrap();
    let out_dir = dir.path().join("out");
    out.write(&out_dir).unwrap();

    let mesh = scene::io::load_mesh(&out_dir.join("mesh.ply"), 1.0).unwrap();
    assert_eq!(mesh.triangles, out.mesh.triangles);
    assert_eq!(mesh.vertices.len(), out.mesh.vertices.len());
    let json = std::fs::read_to_string(out_dir.join("occupancy.json")).unwrap();
    let report: OccupancyReport = serde_json::from_str(&json).unwrap();
    // JSON keeps integers exactly and floats to within an ulp.
    assert_eq!(report.regions, out.report.regions);
    assert!((report.h1_weighted - out.report.h1_weighted).abs() < 1e-9 * report.h1_weighted);
    assert_eq!(report.h2, 0.0);
    let a3 = &report.regions[2];
    assert_eq!(a3.free + a3.unknown + a3.occupied, a3.total);
    assert!(a3.occupied > 1000 && a3.free > 20_000, "{a3:?}");
    assert!(report.h1_weighted < report.h1_unweighted);
    assert_eq!(
        report.h1_unweighted,
        a3.unknown as Real * std::f64::consts::LN_2
    );

    // Per-sweep calls give the same maps as the one-shot call.
    let mut mapper = Mapper::new(&config).unwrap();
    for s in &sweeps {
        let summary = mapper.integrate_sweep(s);
        assert_eq!(summary.occupancy.rays, s.len());
    }
    assert_eq!(mapper.outputs(), out);
}

#[test]
fn bad_scan_files_are_named_in_errors() {
    let dir = tempfile::tempdir().unwrap();
    let o = [Point3::new(0.0, 0.0, 0.5)];
    let p = [Point3::new(0.0, 0.0, 1.5)];

    // No origins.
    let no_origin = dir.path().join("no_origin.ply");
    scene::io::write_ply_vertices_file(&no_origin, &["x", "y", "z"], &[&[0.0], &[0.0], &[1.0]])
        .unwrap();
    let e = Sweep::read_ply(&no_origin).unwrap_err().to_string();
    assert!(e.contains("no_origin.ply") && e.contains("`ox`"), "{e}");

    // A NaN coordinate.
    let nan = dir.path().join("nan.ply");
    write_scan(
        &nan,
        &[o[0], o[0]],
        &[p[0], Point3::new(0.0, Real::NAN, 1.0)],
    );
    let e = Sweep::read_ply(&nan).unwrap_err().to_string();
    assert!(
        e.contains("nan.ply") && e.contains("vertex 1") && e.contains("`y`"),
        "{e}"
    );

    // No points.
    let empty = dir.path().join("empty.ply");
    write_scan(&empty, &[], &[]);
    // No points: an empty sweep (a scan that hit nothing), not an error.
    assert!(Sweep::read_ply(&empty).unwrap().is_empty());

    // Missing file.
    let e = Sweep::read_ply(&dir.path().join("missing.ply"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.ply"), "{e}");
}

#[test]
fn configs_load_from_toml_with_defaults_and_reject_unknown_fields() {
    let cfg: MapConfig = toml::from_str(
        r#"
        [occupancy]
        voxel_m = 0.02
        weights = [0.5, 0.3, 0.2]
        [occupancy.occlusion]
        importance = 3.0
        [occupancy.regions]
        a1 = { min = [-1.0, -1.0, -0.5], max = [1.0, 1.0, 1.5] }
        a2 = { min = [-1.5, -1.5, -1.0], max = [1.5, 1.5, 2.0] }
        a3 = { min = [-2.0, -2.0, -1.5], max = [2.0, 2.0, 2.5] }
        [tsdf]
        truncation_m = 0.05
        weighting = "inverse_square"
        "#,
    )
    .unwrap();
    assert_eq!(cfg.occupancy.voxel_m, 0.02);
    assert_eq!(cfg.occupancy.occlusion.importance, 3.0);
    assert_eq!(cfg.occupancy.occlusion.range_jump_m, 0.1);
    assert_eq!(cfg.tsdf.voxel_m, 0.01);
    assert_eq!(cfg.tsdf.weighting, map::TsdfWeighting::InverseSquare);
    cfg.validate().unwrap();
    let round: MapConfig = toml::from_str(&toml::to_string(&cfg).unwrap()).unwrap();
    assert_eq!(round, cfg);
    assert!(toml::from_str::<MapConfig>("[tsdf]\nvoxel = 0.01\n").is_err());
    // A weight outside [0, ∞) is a config error naming the field.
    let bad = MapConfig {
        occupancy: map::OccupancyConfig {
            weights: [0.6, -0.1, 0.5],
            ..cfg.occupancy
        },
        ..cfg
    };
    let e = Mapper::new(&bad).unwrap_err().to_string();
    assert!(e.contains("occupancy.weights"), "{e}");
}
