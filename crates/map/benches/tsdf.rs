//! TSDF integration per sweep and per depth frame, and mesh extraction, on
//! bridge1 at 10 mm voxels.
//!
//! Open3D's `ScalableTSDFVolume` integrates a 640 × 480 depth frame at 10 mm
//! in about 15 ms on this machine; the `depth_frame_640x480` cases feed the
//! same number of rays (307 200, a 58° × 45° pinhole looking up at the roof)
//! through the simple integrator (one band per return) and the merged one
//! (returns bundled per voxel first, as voxblox does for dense frames).
//!
//! `cargo bench -p map --bench tsdf -- --warm-up-time 1 --measurement-time 3`
#![allow(clippy::expect_used)] // a benchmark without its fixture cannot run

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use geom::{Isometry3, Point3, Ray, Real, Translation3, UnitQuaternion, Vector3, unit};
use map::{TsdfConfig, TsdfIntegrator, TsdfMap};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scene::{RayCast, World};
use sensor::Sweep;
use sensor::{Scanner, ScannerConfig, SweepConfig};
use std::hint::black_box;
use std::path::Path;

fn sweep(world: &World, world_from_target: &Isometry3, seed: u64) -> Sweep {
    let scanner = Scanner::new(ScannerConfig::default()).expect("scanner");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    scanner
        .nodding_sweep(world, world_from_target, &SweepConfig::default(), &mut rng)
        .expect("sweep")
}

fn poses() -> Vec<Isometry3> {
    let at = |x, y, z, r| Isometry3::from_parts(Translation3::new(x, y, z), r);
    let rx = |deg: Real| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), deg.to_radians());
    let ry = |deg: Real| UnitQuaternion::from_axis_angle(&Vector3::y_axis(), deg.to_radians());
    vec![
        at(0.317, 0.0, 0.7716, UnitQuaternion::identity()),
        at(0.0, 0.2, 0.8, rx(-90.0)),
        at(0.0, -0.2, 0.8, rx(90.0)),
        at(0.2, 0.0, 0.9, ry(90.0)),
        at(-0.2, 0.0, 0.9, ry(-90.0)),
        at(0.0, 0.0, 0.6, rx(180.0)),
    ]
}

/// A 640 × 480 pinhole frame (58° × 45°) from the start pose looking up, as
/// (origin, point) pairs of the rays that hit.
fn depth_frame(world: &World) -> (Vec<Point3>, Vec<Point3>) {
    let origin = Point3::new(0.317, 0.0, 0.7716);
    let (w, h) = (640usize, 480usize);
    let fx = (w as Real / 2.0) / (29.0f64.to_radians()).tan();
    let fy = (h as Real / 2.0) / (22.5f64.to_radians()).tan();
    let rays: Vec<Ray> = (0..w * h)
        .filter_map(|k| {
            let (u, v) = ((k % w) as Real + 0.5, (k / w) as Real + 0.5);
            let d = Vector3::new((u - w as Real / 2.0) / fx, (v - h as Real / 2.0) / fy, 1.0);
            unit(d).map(|d| Ray::new(origin, d))
        })
        .collect();
    let hits = world.cast_rays(&rays, 4.0);
    rays.iter()
        .zip(hits)
        .filter_map(|(r, hit)| hit.map(|h| (origin, r.point_at(h.distance))))
        .unzip()
}

fn tsdf(c: &mut Criterion) {
    let world = scene::builtin::scene("bridge1")
        .expect("bridge1")
        .build(Path::new("."))
        .expect("bridge1 builds");
    let sweeps: Vec<Sweep> = poses()
        .iter()
        .enumerate()
        .map(|(k, p)| sweep(&world, p, 10 + k as u64))
        .collect();
    let config = TsdfConfig::default();
    let mut five = TsdfMap::new(config).expect("tsdf");
    for s in &sweeps[1..] {
        five.integrate_sweep(s);
    }

    let mut group = c.benchmark_group("tsdf_bridge1_10mm");
    group.sample_size(10);
    group.throughput(Throughput::Elements(sweeps[0].len() as u64));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        group.bench_function(format!("sweep_into_empty_map_{threads}_threads"), |b| {
            b.iter_batched(
                || TsdfMap::new(config).expect("tsdf"),
                |mut map| {
                    pool.install(|| black_box(map.integrate_sweep(&sweeps[0])));
                    map
                },
                BatchSize::PerIteration,
            );
        });
        group.bench_function(
            format!("sweep_into_five_sweep_map_{threads}_threads"),
            |b| {
                b.iter_batched(
                    || five.clone(),
                    |mut map| {
                        pool.install(|| black_box(map.integrate_sweep(&sweeps[0])));
                        map
                    },
                    BatchSize::PerIteration,
                );
            },
        );
    }
    group.finish();

    let (origins, points) = depth_frame(&world);
    let mut group = c.benchmark_group("tsdf_depth_frame_640x480_10mm");
    group.sample_size(10);
    group.throughput(Throughput::Elements(points.len() as u64));
    for (name, integrator) in [
        ("simple", TsdfIntegrator::Simple),
        ("merged", TsdfIntegrator::Merged),
    ] {
        let config = TsdfConfig {
            integrator,
            ..config
        };
        group.bench_function(format!("integrate_{name}"), |b| {
            b.iter_batched(
                || TsdfMap::new(config).expect("tsdf"),
                |mut map| {
                    black_box(map.integrate_points(&origins, &points).expect("frame"));
                    map
                },
                BatchSize::PerIteration,
            );
        });
    }
    group.finish();

    let mut six = five.clone();
    six.integrate_sweep(&sweeps[0]);
    let mut group = c.benchmark_group("tsdf_mesh_bridge1_six_sweeps");
    group.sample_size(10);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        group.bench_function(format!("extract_mesh_{threads}_threads"), |b| {
            b.iter(|| pool.install(|| black_box(six.extract_mesh())));
        });
    }
    group.finish();
}

criterion_group!(benches, tsdf);
criterion_main!(benches);
