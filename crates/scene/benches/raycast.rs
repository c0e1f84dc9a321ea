//! Ray-casting throughput on the benchmark structure (~66 k triangles):
//! one million incoherent rays, one at a time through `first_hit_f32` (the path of
//! `RayCast::cast_ray`), and in batches through `cast_rays_f32` (sixteen rays
//! interleaved per thread, the path of `surveyor raycast` and of
//! `../shared/bench/compare.sh`) on one and two threads.
//!
//! `cargo bench -p scene --bench raycast`
#![allow(clippy::expect_used)] // a benchmark without its fixture cannot run

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use scene::fixtures::{benchmark_structure, incoherent_rays};
use scene::{MaterialId, Scene, default_materials};
use std::hint::black_box;

fn raycast(c: &mut Criterion) {
    let scene = Scene::from_mesh(
        "structure",
        benchmark_structure(),
        default_materials(),
        MaterialId(0),
    )
    .expect("benchmark structure builds");
    let rays = incoherent_rays(1_000_000, 1);
    let mut out = vec![0.0f32; rays.len()];
    let mut group = c.benchmark_group("raycast_66k");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("incoherent_1M_single_rays_one_thread", |b| {
        b.iter(|| {
            for (o, r) in out.iter_mut().zip(&rays) {
                *o = scene
                    .first_hit_f32([r[0], r[1], r[2]], [r[3], r[4], r[5]], f32::INFINITY)
                    .map_or(f32::INFINITY, |(t, _)| t);
            }
            black_box(&out);
        });
    });
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        group.bench_function(format!("incoherent_1M_batch_{threads}_threads"), |b| {
            b.iter(|| pool.install(|| scene.cast_rays_f32(&rays, f32::INFINITY, &mut out)));
        });
    }
    group.finish();

    // The scanner's own rays: one URG-04LX sweep (151 scans × 342 rays at 0.36°,
    // nodded through 60° about the scanner's y axis) from bridge1's start pose,
    // against bridge1, and against the structure from beside the sphere (looking
    // up at the top beams) and from the sphere's centre (every ray hits the
    // sphere's 65 k triangles from inside: the hard case for any BVH).
    let sweep = |origin: [f32; 3]| -> Vec<[f32; 6]> {
        let mut rays = Vec::with_capacity(151 * 342);
        for j in 0..151 {
            let tilt = (-30.0f32 + 0.4 * j as f32).to_radians();
            for i in 0..342 {
                let theta = (-61.38f32 + 0.36 * i as f32).to_radians();
                let (d0, d1, d2) = (0.0, -theta.sin(), theta.cos());
                let (st, ct) = tilt.sin_cos();
                rays.push([
                    origin[0],
                    origin[1],
                    origin[2],
                    ct * d0 + st * d2,
                    d1,
                    -st * d0 + ct * d2,
                ]);
            }
        }
        rays
    };
    let bridge = scene::builtin::scene("bridge1")
        .expect("built-in")
        .build(std::path::Path::new("."))
        .expect("bridge1 builds");
    let bridge = bridge.as_scene().expect("a mesh scene");
    let mut group = c.benchmark_group("raycast_scanner_sweep");
    group.sample_size(20);
    for (name, target, origin) in [
        ("bridge1_start_pose", bridge, [0.317f32, 0.0, 0.7716]),
        ("structure_66k_beside_sphere", &scene, [0.3f32, -1.1, 1.2]),
        ("structure_66k_inside_sphere", &scene, [0.3f32, 0.2, 1.2]),
    ] {
        let rays = sweep(origin);
        let mut out = vec![0.0f32; rays.len()];
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(format!("{name}_one_thread"), |b| {
            b.iter(|| {
                for (o, r) in out.iter_mut().zip(&rays) {
                    *o = target
                        .first_hit_f32([r[0], r[1], r[2]], [r[3], r[4], r[5]], 4.0)
                        .map_or(f32::INFINITY, |(t, _)| t);
                }
                black_box(&out);
            });
        });
        group.bench_function(format!("{name}_two_threads"), |b| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .build()
                .expect("thread pool");
            b.iter(|| pool.install(|| target.cast_rays_f32(&rays, 4.0, &mut out)));
        });
    }
    group.finish();
}

criterion_group!(benches, raycast);
criterion_main!(benches);
