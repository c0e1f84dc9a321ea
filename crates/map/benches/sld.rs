//! Scale-Like Discs (Paul §5.2): the 55 000-point cloud of the speed target
//! (Paul Table 5.1: 54 916 points in 5.5 s) and the full fused section.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/sld_support/mod.rs"]
mod support;

use criterion::{Criterion, criterion_group, criterion_main};
use map::sld::{Orientation, SldConfig, generate_discs};
use std::hint::black_box;

fn sld(c: &mut Criterion) {
    let cfg = SldConfig::default();
    let mut group = c.benchmark_group("sld");
    let small = support::fused_bridge1_55k();
    group.bench_function(format!("bridge1 {} points", small.points.len()), |b| {
        b.iter(|| {
            generate_discs(
                black_box(&small.points),
                Orientation::SensorOrigins(&small.origins),
                &cfg,
                1,
            )
            .unwrap()
        });
    });
    let mut full = support::fused_bridge1(5, 0.4, 11);
    support::crop_x(&mut full, 1.0);
    group.bench_function(format!("bridge1 {} points", full.points.len()), |b| {
        b.iter(|| {
            generate_discs(
                black_box(&full.points),
                Orientation::SensorOrigins(&full.origins),
                &cfg,
                1,
            )
            .unwrap()
        });
    });
    group.finish();
}

criterion_group!(benches, sld);
criterion_main!(benches);
