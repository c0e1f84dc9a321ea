//! Ordering one segment's blast targets (Paul App. A.2): nearest neighbour,
//! 2-opt and the GA on 500 targets (issue 11 asks for a 500-disc segment
//! planned in ≤ 2 s, poses included).
#![allow(clippy::unwrap_used)] // benchmark setup may panic

use blast::sequence::{GaConfig, Targets, Weights, genetic, nearest_neighbour, two_opt};
use criterion::{Criterion, criterion_group, criterion_main};
use geom::{Point3, Real};
use rand::{RngExt, SeedableRng};
use std::hint::black_box;

/// 500 targets on a 1 m × 1 m roof patch, each reached by a pose that
/// varies smoothly with its position.
fn targets() -> Targets {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let c: Vec<Point3> = (0..500)
        .map(|_| Point3::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0), 1.5))
        .collect();
    let q: Vec<Vec<Real>> = c
        .iter()
        .map(|p| (0..6).map(|l| 0.8 * p.x - 0.5 * p.y * l as Real).collect())
        .collect();
    Targets::new(&c, &q).unwrap()
}

fn bench(c: &mut Criterion) {
    let t = targets();
    let w0 = Weights::normalising(1.0, 1.0);
    let nn = nearest_neighbour(&t, 0, w0);
    let w = Weights::of_population(&t, std::slice::from_ref(&nn));
    let nn = nearest_neighbour(&t, 0, w);
    let opt = two_opt(&t, &nn, w);
    let ga = genetic(&t, &opt, w, &GaConfig::default());
    eprintln!(
        "500 targets: nearest neighbour {:.3}, 2-opt {:.3}, GA {:.3}",
        t.cost(&nn, w),
        t.cost(&opt, w),
        ga.cost
    );
    let mut g = c.benchmark_group("sequence_500");
    g.sample_size(10);
    g.bench_function("nearest_neighbour", |b| {
        b.iter(|| nearest_neighbour(black_box(&t), 0, w));
    });
    g.bench_function("two_opt", |b| b.iter(|| two_opt(black_box(&t), &nn, w)));
    g.bench_function("ga_default", |b| {
        b.iter(|| genetic(black_box(&t), &opt, w, &GaConfig::default()));
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
