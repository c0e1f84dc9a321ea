//! Occupancy integration of one scanner sweep, and prediction rays.
//!
//! The sweep is the URG-04LX's: 151 scans × 342 rays (51 642 returns) nodded
//! through 60°, from the centre of the bridge regions, every return about
//! 2 m away (a sphere of radius 2 m with a ±5 cm ripple), at 10 mm voxels over
//! A3 (420 × 420 × 421 voxels). OctoMap's `insertPointCloud` takes about 1 s
//! for such a sweep on this machine.
//!
//! `cargo bench -p map --bench occupancy -- --warm-up-time 1 --measurement-time 3`
#![allow(clippy::expect_used)] // a benchmark without its fixture cannot run

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use geom::{Isometry3, Real, Translation3, UnitQuaternion, Vector3, unit};
use map::{OccupancyConfig, OccupancyGrid};
use sensor::Sweep;
use sensor::{ScannerConfig, SweepConfig};
use std::hint::black_box;

fn sphere_sweep() -> Sweep {
    let bearings = ScannerConfig::default().bearings_rad();
    let centre = Translation3::new(0.0, 0.0, 0.475);
    let tilts = SweepConfig::default().tilt_values(0.0, None);
    let poses: Vec<Isometry3> = tilts
        .iter()
        .map(|&t| {
            Isometry3::from_parts(
                centre,
                UnitQuaternion::from_axis_angle(&Vector3::y_axis(), t),
            )
        })
        .collect();
    let mut ranges = Vec::with_capacity(poses.len() * bearings.len());
    for (j, _) in poses.iter().enumerate() {
        for (i, _) in bearings.iter().enumerate() {
            let ripple = 0.05 * ((i as Real) * 0.05).sin() * ((j as Real) * 0.07).cos();
            ranges.push(Some(2.0 + ripple));
        }
    }
    Sweep::from_range_grid(&bearings, &poses, &ranges).expect("sweep")
}

fn occupancy(c: &mut Criterion) {
    let sweep = sphere_sweep();
    let config = OccupancyConfig::default();
    let mut group = c.benchmark_group("occupancy_sweep_51642_rays_2m_10mm");
    group.sample_size(10);
    group.throughput(Throughput::Elements(sweep.len() as u64));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        group.bench_function(format!("fresh_grid_{threads}_threads"), |b| {
            b.iter_batched(
                || OccupancyGrid::new(config).expect("grid"),
                |mut grid| {
                    pool.install(|| black_box(grid.integrate_sweep(&sweep)));
                    grid
                },
                BatchSize::PerIteration,
            );
        });
        let mut seen = OccupancyGrid::new(config).expect("grid");
        seen.integrate_sweep(&sweep);
        group.bench_function(format!("same_sweep_again_{threads}_threads"), |b| {
            b.iter(|| pool.install(|| black_box(seen.integrate_sweep(&sweep))));
        });
    }
    group.finish();

    // Prediction: rays of a candidate viewpoint through a partly known grid,
    // counting the unknown voxels each would reveal (up to 4 m).
    let mut grid = OccupancyGrid::new(config).expect("grid");
    grid.integrate_sweep(&sweep);
    let origin = geom::Point3::new(0.3, 0.1, 0.6);
    let dirs: Vec<_> = (0..4096)
        .filter_map(|k| {
            let a = Real::from(k) * 0.618_033_988_75 * std::f64::consts::TAU;
            let z = 1.0 - 2.0 * (Real::from(k) + 0.5) / 4096.0;
            let r = (1.0 - z * z).sqrt();
            unit(Vector3::new(r * a.cos(), r * a.sin(), z))
        })
        .collect();
    let mut group = c.benchmark_group("occupancy_prediction");
    group.sample_size(10);
    group.throughput(Throughput::Elements(dirs.len() as u64));
    group.bench_function("cast_4096_rays_4m", |b| {
        b.iter(|| {
            let mut total = 0u64;
            for d in &dirs {
                total += u64::from(grid.cast_through_unknown(&origin, d, 4.0, |_| {}).unknown);
            }
            black_box(total)
        });
    });
    group.finish();
}

criterion_group!(benches, occupancy);
criterion_main!(benches);
